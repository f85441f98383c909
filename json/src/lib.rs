//! The JSON frame contract of busspec: frames ↔ JSON lines, whichever engine decoded them.
//!
//! One JSON object per frame, keys in this order:
//! `{"protocol":"ub2","direction":"response","address":33,"code":"0x4101","message":"actual_capacitance","fields":{"capacitance":79.98}}`
//! (a stream puts `"offset":N` first; a protocol whose frames carry no address has no
//! `"address"`, nor has a constant whole frame such as M-Bus's `E5`). Field values:
//!
//! - numbers with a unit: the physical value `raw * scale + offset`, exact, in the unit's symbol;
//! - `special` raw values: their name;
//! - enums: the value's name, or the raw number when the enum does not list it;
//! - flags: the names of the set bits, in bit order, then any set bit the spec does not name as
//!   its numeric value (`["oca", 64]`);
//! - constants, repeated (`equals`) fields and other unit-less numbers: the raw number;
//! - text (`ascii`): a string, one character per byte (bytes 0x80..0xFF as U+0080..U+00FF).
//!
//! The shape belongs to the contract, not to an engine. Each field is printed from its spec name
//! and raw value ([`FieldValue`]) with the spec's IR ([`Spec`]) for units and names, so a frame
//! prints the same from either engine:
//!
//! - a generated codec (any [`busspec_runtime::Protocol`]): [`message_line`] from a typed
//!   message's [`Message::visit`], [`decode_typed`] and [`Typed`], [`TypedStream`], with the IR
//!   loaded from the protocol's `SPEC_YAML` by [`load_spec`];
//! - the interpreter of `busspec-model` (a spec loaded at run time): [`frame_line`],
//!   [`decode_frame`], [`event_line`].
//!
//! The way back, [`parse_line`], checks a line against the spec and gives the frame's raw field
//! values ([`Parsed`]), which encode through the interpreter ([`Parsed::encode`]) or become a
//! typed message of a generated protocol ([`Parsed::to_typed`], with
//! [`Message::from_fields`]): a built-in protocol never goes through the interpreter's codec.
//!
//! Nothing here panics on any input: every failure is an error message saying what and where.

mod decode;
mod lines;
mod parse;
mod print;
mod stream;

use busspec_model::ir::Direction;
use busspec_runtime::{Decoded, EncodeError, FrameBuffer, Message, Protocol};

pub use busspec_model::ir::Protocol as Spec;
pub use busspec_runtime::FieldValue;
pub use decode::{decode_frame, decode_frame_with, decode_typed, decode_typed_with, request_for};
pub use lines::Printer;
pub use parse::{parse_line, Parsed};
pub use print::{
    ambiguous_line, frame_line, lenient_line, message_line, out_of_spec_line, skipped_line,
};
pub use stream::{event_line, write_events, TypedStream};

/// Uppercase hex, no separators: what `encode` prints and `decode` reads back.
pub fn hex(bytes: &[u8]) -> String {
    let mut out = Vec::with_capacity(2 * bytes.len());
    lines::push_hex(&mut out, bytes);
    // Hex digits are ASCII.
    String::from_utf8(out).unwrap_or_default()
}

/// Hex text to bytes: digits in wire order, spaces and `0x` prefixes allowed
/// (`"0xAA21 4101 3E1F 0000 6A"`); an error names the offending character and where it is.
pub fn parse_hex(text: &str) -> Result<Vec<u8>, String> {
    busspec_model::interp::parse_hex(text)
}

/// The IR of a generated protocol, loaded from the spec text it was generated from
/// ([`Source::spec_yaml`](busspec_runtime::Source::spec_yaml)): the units, enums and names [`message_line`] prints with.
pub fn load_spec<P: Protocol>() -> Result<Spec, String> {
    let file = format!("spec/{}.yaml", P::NAME);
    busspec_model::load_str(&file, P::SOURCE.spec_yaml)
        .map_err(|d| format!("built-in spec is invalid:\n{d}"))
}

/// A frame of a generated protocol, either way.
#[derive(Debug, Clone, Copy)]
pub enum Typed<P: Protocol> {
    Request(Decoded<P::Request>),
    Response(Decoded<P::Response>),
}

impl<P: Protocol> PartialEq for Typed<P> {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Typed::Request(a), Typed::Request(b)) => a == b,
            (Typed::Response(a), Typed::Response(b)) => a == b,
            _ => false,
        }
    }
}

impl<P: Protocol> Typed<P> {
    pub fn direction(&self) -> Direction {
        match self {
            Typed::Request(_) => Direction::Request,
            Typed::Response(_) => Direction::Response,
        }
    }

    pub fn address(&self) -> u8 {
        match self {
            Typed::Request(d) => d.address,
            Typed::Response(d) => d.address,
        }
    }

    /// The message's name in the spec.
    pub fn name(&self) -> &'static str {
        match self {
            Typed::Request(d) => d.message.name(),
            Typed::Response(d) => d.message.name(),
        }
    }

    /// The frame's bytes, from the generated encoder.
    pub fn encode(&self) -> Result<Vec<u8>, EncodeError> {
        self.encode_reply(None)
    }

    /// [`Self::encode`] of a reply to the request frame `request` (as it travelled), where
    /// given: the checksum of a reply that takes in its request's bytes
    /// (`checksum_over_request`) over them ([`Protocol::encode_reply`]).
    pub fn encode_reply(&self, request: Option<&[u8]>) -> Result<Vec<u8>, EncodeError> {
        let mut buf = P::Buffer::ZERO;
        let n = match (self, request) {
            (Typed::Request(d), _) => d.message.encode(d.address, buf.as_mut())?,
            (Typed::Response(d), None) => d.message.encode(d.address, buf.as_mut())?,
            (Typed::Response(d), Some(q)) => {
                P::encode_reply(&d.message, d.address, q, buf.as_mut())?
            }
        };
        Ok(buf.as_ref()[..n].to_vec())
    }

    /// The frame's JSON line; `offset` (stream mode) goes first.
    pub fn line(&self, spec: &Spec, offset: Option<u64>) -> Result<String, String> {
        match self {
            Typed::Request(d) => {
                message_line(spec, Direction::Request, d.address, &d.message, offset)
            }
            Typed::Response(d) => {
                message_line(spec, Direction::Response, d.address, &d.message, offset)
            }
        }
    }
}
