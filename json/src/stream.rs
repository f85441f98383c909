//! Raw bus captures: each event of a stream decoder as a JSON line.

use busspec_model::ir::Direction;
use busspec_model::stream::{decode_lenient, relaxed, Event as InterpEvent};
use busspec_runtime::stream::{Direction as StreamDirection, Event, StreamDecoder};
use busspec_runtime::Protocol;

use crate::decode::{candidates, request_for};
use crate::print::{ambiguous_line, frame_line, out_of_spec_line, skipped_line};
use crate::{Spec, Typed};

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

/// The generated [`StreamDecoder`] of protocol `P`, printing JSON lines: each frame's line
/// with `"offset"` first, noise and ambiguous frames with their bytes. It keeps the bytes not
/// yet accounted for (at most a frame's worth and the noise of one run) to print them.
pub struct TypedStream<'s, P: Protocol> {
    spec: &'s Spec,
    decoder: StreamDecoder<P>,
    /// Bytes pushed and not yet reported; `pending[0]` is at stream offset `base`.
    pending: Vec<u8>,
    base: u64,
    direction: Option<Direction>,
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
            pending: Vec::new(),
            base: 0,
            direction: along,
            relaxed: None,
        }
    }

    /// Feeds bytes; returns the lines of what they settled.
    pub fn push(&mut self, data: &[u8]) -> Vec<String> {
        self.pending.extend_from_slice(data);
        let events: Vec<_> = self.decoder.feed(data).collect();
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

    /// The bytes of `len` at stream offset `offset`, dropping every byte before their end.
    fn take(&mut self, offset: u64, len: u64) -> Vec<u8> {
        let from = usize::try_from(offset.saturating_sub(self.base)).unwrap_or(usize::MAX);
        let to = usize::try_from((offset + len).saturating_sub(self.base)).unwrap_or(usize::MAX);
        let to = to.min(self.pending.len());
        let bytes = self.pending.get(from.min(to)..to).unwrap_or(&[]).to_vec();
        self.pending.drain(..to);
        self.base += to as u64;
        bytes
    }

    fn line(&mut self, e: &Event<P::Request, P::Response>) -> String {
        let bytes = self.take(e.offset(), e.len());
        let printed = match *e {
            Event::Request { offset, frame, .. } => {
                Typed::<P>::Request(frame).line(self.spec, Some(offset))
            }
            Event::Response { offset, frame, .. } => {
                Typed::<P>::Response(frame).line(self.spec, Some(offset))
            }
            Event::Ambiguous { offset, .. } => Ok(ambiguous_line(
                offset,
                &candidates::<P>(self.spec, &bytes),
                &bytes,
            )),
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
        printed.unwrap_or_else(|why| {
            format!(
                "{{\"offset\":{},\"error\":{}}}",
                e.offset(),
                serde_json::to_string(&why).unwrap_or_default()
            )
        })
    }
}
