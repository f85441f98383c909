//! The CLI's two engines behind the JSON contract of `busspec-json`: the generated codec of a
//! built-in protocol (found by name in `busspec_protocols`), or the interpreter for a spec given
//! at run time with `--spec FILE`. Both print and read the same lines.

use busspec_json::{Printer, Spec, TypedStream};
use busspec_model::ir::Direction;
use busspec_model::stream::StreamDecoder;
use busspec_protocols::{with_protocol, Protocol, ProtocolVisitor};

pub use busspec_json::hex;

/// A protocol to decode and encode: its spec, and which engine serves it.
pub struct Engine {
    pub spec: Spec,
    /// Served by the generated code of the built-in protocol `spec.name`, else the interpreter.
    generated: bool,
    /// Prints decoded frames ([`Self::decode_into`]).
    printer: Printer,
    /// The bytes the request's checksum covers, where the frames decoded are replies to a
    /// request given whole (`--request`): a reply's checksum may take them in
    /// (`checksum_over_request`).
    covered: Option<Vec<u8>>,
}

/// Loads the spec a built-in protocol was generated from.
struct Load;

impl ProtocolVisitor for Load {
    type Output = Result<Spec, String>;
    fn visit<P: Protocol>(self) -> Self::Output {
        busspec_json::load_spec::<P>()
    }
}

struct Decode<'a> {
    spec: &'a Spec,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    covered: Option<&'a [u8]>,
    wire: &'a [u8],
}

/// Decodes a frame with the generated code; its line written to `out` by `printer`.
struct DecodeInto<'a> {
    decode: Decode<'a>,
    printer: &'a mut Printer,
    out: &'a mut Vec<u8>,
}

impl ProtocolVisitor for DecodeInto<'_> {
    type Output = Result<(), String>;
    fn visit<P: Protocol>(self) -> Self::Output {
        let Decode {
            spec,
            direction,
            reply_to,
            covered,
            wire,
        } = self.decode;
        let (out, printer) = (self.out, self.printer);
        match busspec_json::decode_typed_with::<P>(spec, direction, reply_to, covered, wire)? {
            busspec_json::Typed::Request(d) => {
                printer.message(out, spec, Direction::Request, d.address, &d.message, None)
            }
            busspec_json::Typed::Response(d) => {
                printer.message(out, spec, Direction::Response, d.address, &d.message, None)
            }
        }
    }
}

struct Encode<'a> {
    spec: &'a Spec,
    line: &'a str,
    request: Option<&'a [u8]>,
}

impl ProtocolVisitor for Encode<'_> {
    type Output = Result<Vec<u8>, String>;
    fn visit<P: Protocol>(self) -> Self::Output {
        busspec_json::parse_line(self.spec, self.line)?
            .to_typed::<P>(self.spec)?
            .encode_reply(self.request)
            .map_err(|e| e.to_string())
    }
}

/// A capture decoder that prints JSON lines.
pub trait LineStream {
    /// Feeds bytes; writes the lines of what they settled to `out`, each ended by `\n`.
    fn push(&mut self, data: &[u8], out: &mut Vec<u8>);
    /// Settles what is left, at the end of the capture; writes the lines to `out`.
    fn finish(&mut self, out: &mut Vec<u8>);
}

impl<P: Protocol> LineStream for TypedStream<'_, P> {
    fn push(&mut self, data: &[u8], out: &mut Vec<u8>) {
        self.push_into(data, out)
    }
    fn finish(&mut self, out: &mut Vec<u8>) {
        self.finish_into(out)
    }
}

struct Interpreted<'a> {
    spec: &'a Spec,
    printer: &'a Printer,
    decoder: StreamDecoder<'a>,
    /// The events of one piece, kept for their memory.
    events: Vec<busspec_model::stream::Event<'a>>,
}

impl LineStream for Interpreted<'_> {
    fn push(&mut self, data: &[u8], out: &mut Vec<u8>) {
        self.decoder.recycle(&mut self.events);
        self.decoder.push_into(data, &mut self.events);
        busspec_json::write_events(self.spec, self.printer, &self.events, out);
    }
    fn finish(&mut self, out: &mut Vec<u8>) {
        let events = self.decoder.flush();
        busspec_json::write_events(self.spec, self.printer, &events, out);
    }
}

struct Stream<'a> {
    spec: &'a Spec,
    direction: Option<Direction>,
    reply_to: Option<usize>,
}

impl<'a> ProtocolVisitor for Stream<'a> {
    type Output = Box<dyn LineStream + 'a>;
    fn visit<P: Protocol>(self) -> Self::Output {
        Box::new(TypedStream::<P>::new(
            self.spec,
            self.direction,
            self.reply_to,
        ))
    }
}

fn not_built_in(name: &str) -> String {
    format!("`{name}` is not a built-in protocol")
}

impl Engine {
    /// The built-in protocol called `name` (its generated code), or `None` when there is none.
    pub fn built_in(name: &str) -> Option<Result<Engine, String>> {
        with_protocol(name, Load).map(|r| {
            r.map(|spec| Engine {
                printer: Printer::new(&spec),
                spec,
                generated: true,
                covered: None,
            })
        })
    }

    /// A spec loaded at run time, served by the interpreter.
    pub fn interpreted(spec: Spec) -> Engine {
        Engine {
            printer: Printer::new(&spec),
            spec,
            generated: false,
            covered: None,
        }
    }

    /// Decodes the frames that follow as replies to the request frame `request` (as it
    /// travelled): the checksum of a reply that takes in its request's bytes is checked over
    /// them.
    pub fn set_request(&mut self, request: &[u8]) {
        self.covered = self.spec.checksum_span(request).map(<[u8]>::to_vec);
    }

    /// Decodes one frame and writes its JSON line to `out`, ended by `\n`; `reply_to` is a
    /// command index.
    pub fn decode_into(
        &mut self,
        direction: Option<Direction>,
        reply_to: Option<usize>,
        wire: &[u8],
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        if !self.generated {
            let frame = busspec_json::decode_frame_with(
                &self.spec,
                direction,
                reply_to,
                self.covered.as_deref(),
                wire,
            )?;
            self.printer.frame(out, &self.spec, &frame, None);
            return Ok(());
        }
        let visitor = DecodeInto {
            decode: Decode {
                spec: &self.spec,
                direction,
                reply_to,
                covered: self.covered.as_deref(),
                wire,
            },
            printer: &mut self.printer,
            out,
        };
        with_protocol(&self.spec.name, visitor)
            .unwrap_or_else(|| Err(not_built_in(&self.spec.name)))
    }

    /// Decodes one frame as [`Self::decode_into`] does; a frame that strict decoding refuses
    /// only for rules of the spec (ranges, address, broadcast) decodes with those rules lifted
    /// and prints with its `"violations"` ([`busspec_json::lenient_line`]). Lifting the rules
    /// is the interpreter's (`busspec_model::stream::decode_lenient`), for built-in protocols
    /// too: the generated code has no lenient entry point, so that a device build cannot
    /// accept such a frame by mistake, and the interpreter decodes every spec the generated
    /// code does. Any other failure is strict decoding's error.
    pub fn decode_lenient_into(
        &mut self,
        direction: Option<Direction>,
        reply_to: Option<usize>,
        wire: &[u8],
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        let strict = match self.decode_into(direction, reply_to, wire, out) {
            Ok(()) => return Ok(()),
            Err(e) => e,
        };
        let line = self.lenient(direction, reply_to, wire, strict)?;
        out.extend_from_slice(line.as_bytes());
        out.push(b'\n');
        Ok(())
    }

    /// The lenient line of a frame strict decoding refused with `strict`, or that error.
    fn lenient(
        &self,
        direction: Option<Direction>,
        reply_to: Option<usize>,
        wire: &[u8],
        strict: String,
    ) -> Result<String, String> {
        let relaxed = busspec_model::stream::relaxed(&self.spec);
        let lenient = |reply_to| {
            busspec_model::stream::decode_lenient(&self.spec, &relaxed, direction, reply_to, wire)
        };
        // As `decode` settles a frame only its request tells apart: without the request first.
        let found = match lenient(None) {
            Err(busspec_model::interp::DecodeError::Ambiguous { .. }) if reply_to.is_some() => {
                lenient(reply_to)
            }
            other => other,
        };
        match found {
            Ok((frame, violations)) if !violations.is_empty() => {
                let reasons: Vec<String> = violations.iter().map(|v| v.to_string()).collect();
                Ok(busspec_json::lenient_line(&self.spec, &frame, &reasons))
            }
            _ => Err(strict),
        }
    }

    /// Encodes one JSON line to wire bytes.
    pub fn encode(&self, line: &str) -> Result<Vec<u8>, String> {
        self.encode_reply(line, None)
    }

    /// Encodes one JSON line to wire bytes as the reply to the request frame `request`,
    /// where given: the checksum of a reply that takes in its request's bytes
    /// (`checksum_over_request`) over them.
    pub fn encode_reply(&self, line: &str, request: Option<&[u8]>) -> Result<Vec<u8>, String> {
        if self.generated {
            encode_typed(&self.spec, line, request)
        } else {
            busspec_json::parse_line(&self.spec, line)?.encode_reply(&self.spec, request)
        }
    }

    /// A decoder for a raw capture; `reply_to` is a command index.
    pub fn stream(
        &self,
        direction: Option<Direction>,
        reply_to: Option<usize>,
    ) -> Box<dyn LineStream + '_> {
        let visitor = Stream {
            spec: &self.spec,
            direction,
            reply_to,
        };
        match self
            .generated
            .then(|| with_protocol(&self.spec.name, visitor))
        {
            Some(Some(s)) => s,
            _ => Box::new(Interpreted {
                spec: &self.spec,
                printer: &self.printer,
                events: Vec::new(),
                decoder: StreamDecoder::new(&self.spec, direction).with_default_request(reply_to),
            }),
        }
    }
}

/// Encodes one JSON line of a built-in protocol (`spec`, as [`Engine::built_in`] loads it)
/// with its generated codec.
#[cfg(test)]
pub fn encode_built_in(spec: &Spec, line: &str) -> Result<Vec<u8>, String> {
    encode_typed(spec, line, None)
}

/// One JSON line of a built-in protocol encoded with its generated codec, as the reply to the
/// request frame `request` where given.
fn encode_typed(spec: &Spec, line: &str, request: Option<&[u8]>) -> Result<Vec<u8>, String> {
    with_protocol(
        &spec.name,
        Encode {
            spec,
            line,
            request,
        },
    )
    .unwrap_or_else(|| Err(not_built_in(&spec.name)))
}

/// The spec of the built-in protocol called `name`.
#[cfg(test)]
pub fn built_in_spec(name: &str) -> Spec {
    match Engine::built_in(name) {
        Some(Ok(e)) => e.spec,
        Some(Err(e)) => panic!("{e}"),
        None => panic!("{}", not_built_in(name)),
    }
}
