//! Raw bus captures: each event of a stream decoder as a JSON line.

use busspec_model::ir::Direction;
use busspec_model::stream::{decode_lenient, relaxed, Event as InterpEvent};
use busspec_runtime::stream::{Direction as StreamDirection, Event, StreamDecoder};
use busspec_runtime::{Decoded, Message, Protocol};

use crate::decode::{ambiguous_candidates, request_for, request_for_reply};
use crate::print::{ambiguous_line, frame_line, out_of_spec_line, skipped_line};
use crate::{Printer, Spec, Typed};

/// The JSON line of an event of the interpreter's stream decoder (`busspec_model::stream`).
pub fn event_line(p: &Spec, e: &InterpEvent) -> String {
    match e {
        InterpEvent::Frame { offset, frame, .. } => frame_line(p, frame, Some(*offset)),
        InterpEvent::Skipped { offset, bytes } => skipped_line(*offset, bytes),
        InterpEvent::Ambiguous {
            offset,
            bytes,
            candidates,
        } => ambiguous_line(*offset, candidates, bytes),
        InterpEvent::OutOfSpec {
            offset,
            bytes,
            reason,
            frame,
        } => out_of_spec_line(p, *offset, &reason.to_string(), frame.as_ref(), bytes),
    }
}

/// The lines of the interpreter's stream events written to `out` (each ended by `\n`), as
/// [`event_line`] prints them; `printer` is [`Printer::new`]`(p)`.
pub fn write_events(p: &Spec, printer: &Printer, events: &[InterpEvent], out: &mut Vec<u8>) {
    for e in events {
        match e {
            InterpEvent::Frame { offset, frame, .. } => printer.frame(out, p, frame, Some(*offset)),
            InterpEvent::Skipped { offset, bytes } => Printer::skipped(out, *offset, bytes),
            InterpEvent::Ambiguous {
                offset,
                bytes,
                candidates,
            } => Printer::ambiguous(out, *offset, candidates, bytes),
            InterpEvent::OutOfSpec { .. } => {
                out.extend_from_slice(event_line(p, e).as_bytes());
                out.push(b'\n');
            }
        }
    }
}

/// The generated [`StreamDecoder`] of protocol `P`, printing JSON lines: each frame's line
/// with `"offset"` first, noise and ambiguous frames with their bytes. It keeps the bytes not
/// yet accounted for (at most a frame's worth and the noise of one run) to print them.
///
/// [`TypedStream::push`] gives each line as a `String` (printed by `print.rs`, the
/// reference); [`TypedStream::push_into`] writes the same lines to a buffer ([`Printer`]),
/// the way for captures of any size.
pub struct TypedStream<'s, P: Protocol> {
    spec: &'s Spec,
    decoder: StreamDecoder<P>,
    printer: Printer,
    /// The events of one [`Self::push_into`], kept for their memory.
    events: Vec<Event<P::Request, P::Response>>,
    /// Bytes pushed; `pending[done..]` not yet reported, `pending[0]` at stream offset `base`.
    pending: Vec<u8>,
    done: usize,
    base: u64,
    direction: Option<Direction>,
    /// The command a response with no request before it answers (`--reply-to`).
    reply_to: Option<usize>,
    /// Whether the last frame reported was a request: the decoder then paired the next
    /// response with it, not with the default request.
    after_request: bool,
    /// `spec` with its rules lifted, made at the first out-of-spec frame.
    relaxed: Option<Spec>,
}

impl<'s, P: Protocol> TypedStream<'s, P> {
    /// A stream of frames of `direction` (`None`: both); a response only its request tells
    /// apart, with no request before it, as the reply to command `reply_to` (an index into the
    /// spec's commands). `spec` is the spec `P` was generated from ([`crate::load_spec`]).
    pub fn new(spec: &'s Spec, direction: Option<Direction>, reply_to: Option<usize>) -> Self {
        let along = direction;
        let direction = direction.map(|d| match d {
            Direction::Request => StreamDirection::Request,
            Direction::Response => StreamDirection::Response,
        });
        let default = reply_to.and_then(|cmd| request_for::<P>(spec, cmd));
        TypedStream {
            spec,
            decoder: StreamDecoder::new(direction).with_default_request(default),
            printer: Printer::new(spec),
            events: Vec::new(),
            pending: Vec::new(),
            done: 0,
            base: 0,
            direction: along,
            reply_to,
            after_request: false,
            relaxed: None,
        }
    }

    /// Feeds bytes; returns the lines of what they settled.
    pub fn push(&mut self, data: &[u8]) -> Vec<String> {
        self.keep(data);
        let mut events = Vec::new();
        self.decoder.feed(data).for_each(|e| events.push(e));
        events.iter().map(|e| self.line(e)).collect()
    }

    /// Settles everything buffered, as at the end of a capture; returns the lines.
    pub fn finish(&mut self) -> Vec<String> {
        let mut lines = Vec::new();
        while let Some(e) = self.decoder.finish() {
            lines.push(self.line(&e));
        }
        lines
    }

    /// Feeds bytes; writes the lines of what they settled to `out`, each ended by `\n`: the
    /// lines [`Self::push`] returns.
    pub fn push_into(&mut self, data: &[u8], out: &mut Vec<u8>) {
        self.keep(data);
        let mut events = std::mem::take(&mut self.events);
        events.clear();
        // `for_each` rather than `extend`: the decoder's own loop (`Feed::fold`).
        self.decoder.feed(data).for_each(|e| events.push(e));
        for e in &events {
            self.write(e, out);
        }
        self.events = events;
    }

    /// Settles everything buffered, as at the end of a capture; writes the lines to `out`.
    pub fn finish_into(&mut self, out: &mut Vec<u8>) {
        while let Some(e) = self.decoder.finish() {
            self.write(&e, out);
        }
    }

    /// Writes the line of `e` as [`Self::line`] gives it.
    fn write(&mut self, e: &Event<P::Request, P::Response>, out: &mut Vec<u8>) {
        let after_request = self.after_request;
        self.pair(e);
        let printed = match *e {
            Event::Request { offset, frame, .. } => {
                self.decoded(Direction::Request, offset, e.len(), &frame, out)
            }
            Event::Response { offset, frame, .. } => {
                self.decoded(Direction::Response, offset, e.len(), &frame, out)
            }
            Event::Skipped { offset, len } => {
                let r = self.take_range(offset, len);
                Printer::skipped(out, offset, self.pending.get(r).unwrap_or_default());
                Ok(())
            }
            Event::Ambiguous { offset, .. } => {
                let r = self.take_range(offset, e.len());
                let bytes = self.pending.get(r).unwrap_or_default();
                match Self::settled_by(
                    self.spec,
                    self.direction,
                    self.reply_to,
                    after_request,
                    bytes,
                ) {
                    Some(d) => {
                        let (printer, spec) = (&mut self.printer, self.spec);
                        let (address, message) = (d.address, &d.message);
                        printer.message(
                            out,
                            spec,
                            Direction::Response,
                            address,
                            message,
                            Some(offset),
                        )
                    }
                    None => {
                        let candidates =
                            ambiguous_candidates::<P>(self.spec, self.direction, bytes);
                        Printer::ambiguous(out, offset, &candidates, bytes);
                        Ok(())
                    }
                }
            }
            Event::OutOfSpec { .. } => {
                out.extend_from_slice(self.line(e).as_bytes());
                out.push(b'\n');
                Ok(())
            }
        };
        if let Err(why) = printed {
            out.extend_from_slice(error_line(e.offset(), &why).as_bytes());
            out.push(b'\n');
        }
    }

    /// Writes the line of a frame of `direction` of `len` bytes at `offset`.
    fn decoded<M: Message>(
        &mut self,
        direction: Direction,
        offset: u64,
        len: u64,
        d: &Decoded<M>,
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        self.take_range(offset, len);
        let (printer, spec) = (&mut self.printer, self.spec);
        printer.message(out, spec, direction, d.address, &d.message, Some(offset))
    }

    /// Follows the decoder's pairing: a response is paired with the request reported just
    /// before it (noise between them aside), else with the default request.
    fn pair(&mut self, e: &Event<P::Request, P::Response>) {
        match e {
            Event::Request { .. } => self.after_request = true,
            Event::Skipped { .. } => {}
            _ => self.after_request = false,
        }
    }

    /// An ambiguous response `bytes` settled by `--reply-to` where no request came before
    /// it, as [`crate::decode_typed`] settles one frame: the default request the decoder was
    /// given holds neutral values, which a reply whose fields follow the request's (a READ's
    /// bytes, as many as it asked for) does not follow; here the request is the one the frame
    /// implies, so the generated stream answers as the interpreter's, which settles a reply
    /// by its command. A frame that also decodes as a request stays ambiguous.
    fn settled_by(
        spec: &Spec,
        direction: Option<Direction>,
        reply_to: Option<usize>,
        after_request: bool,
        bytes: &[u8],
    ) -> Option<Decoded<P::Response>> {
        let cmd = reply_to.filter(|_| !after_request)?;
        if direction.is_none() && P::decode_request(bytes).is_ok() {
            return None;
        }
        let request = request_for_reply::<P>(spec, cmd, bytes)?;
        P::decode_reply(bytes, &request).ok()
    }

    /// Keeps pushed bytes until their event reports them.
    fn keep(&mut self, data: &[u8]) {
        if self.done > 0 {
            self.pending.drain(..self.done);
            self.base += self.done as u64;
            self.done = 0;
        }
        self.pending.extend_from_slice(data);
    }

    /// Where the bytes of `len` at stream offset `offset` are in `pending`; every byte before
    /// their end counts as reported.
    fn take_range(&mut self, offset: u64, len: u64) -> std::ops::Range<usize> {
        let at = self.base + self.done as u64;
        let index = |o: u64| {
            usize::try_from(o.saturating_sub(at))
                .ok()
                .and_then(|i| i.checked_add(self.done))
                .unwrap_or(usize::MAX)
        };
        let to = index(offset + len).min(self.pending.len());
        let from = index(offset).min(to);
        self.done = to;
        from..to
    }

    /// The bytes of `len` at stream offset `offset`, dropping every byte before their end.
    fn take(&mut self, offset: u64, len: u64) -> Vec<u8> {
        let r = self.take_range(offset, len);
        self.pending.get(r).unwrap_or_default().to_vec()
    }

    fn line(&mut self, e: &Event<P::Request, P::Response>) -> String {
        let after_request = self.after_request;
        self.pair(e);
        let bytes = self.take(e.offset(), e.len());
        let printed = match *e {
            Event::Request { offset, frame, .. } => {
                Typed::<P>::Request(frame).line(self.spec, Some(offset))
            }
            Event::Response { offset, frame, .. } => {
                Typed::<P>::Response(frame).line(self.spec, Some(offset))
            }
            Event::Ambiguous { offset, .. } => match Self::settled_by(
                self.spec,
                self.direction,
                self.reply_to,
                after_request,
                &bytes,
            ) {
                Some(d) => Typed::<P>::Response(d).line(self.spec, Some(offset)),
                None => Ok(ambiguous_line(
                    offset,
                    &ambiguous_candidates::<P>(self.spec, self.direction, &bytes),
                    &bytes,
                )),
            },
            Event::Skipped { offset, .. } => Ok(skipped_line(offset, &bytes)),
            // The values of a frame the generated code refuses come from the interpreter,
            // with the spec's rules lifted; the reason, worded as the interpreter's stream
            // words it, from the same decoding where there is one.
            Event::OutOfSpec { offset, reason, .. } => {
                let spec = self.spec;
                let relaxed = self.relaxed.get_or_insert_with(|| relaxed(spec));
                let lenient = decode_lenient(spec, relaxed, self.direction, None, &bytes).ok();
                let why = lenient
                    .as_ref()
                    .and_then(|(_, v)| v.first())
                    .map_or_else(|| reason.to_string(), |v| v.to_string());
                let frame = lenient.as_ref().map(|(f, _)| f);
                Ok(out_of_spec_line(spec, offset, &why, frame, &bytes))
            }
        };
        // Only a protocol generated from another spec than `spec` gets here.
        printed.unwrap_or_else(|why| error_line(e.offset(), &why))
    }
}

/// The line of a frame `spec` cannot print (a protocol generated from another spec).
fn error_line(offset: u64, why: &str) -> String {
    format!(
        "{{\"offset\":{offset},\"error\":{}}}",
        serde_json::to_string(why).unwrap_or_default()
    )
}
