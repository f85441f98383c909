//! The derive-based peer: the bench subset of each protocol with deku's `DekuRead`/`DekuWrite`,
//! the checksum (which deku cannot express over the bytes before it) checked and written around
//! the derived code. Strict as the spec, as the generated code is: address ranges and field
//! ranges are deku assertions (checked on read and on write); what deku cannot see from inside
//! a field (a frame's length, the broadcast rule of a command) is checked around it.

pub mod modbus_core;
pub mod sd;
pub mod ub2;

/// Why the peer did not decode or encode a frame.
#[derive(Debug)]
pub enum Error {
    Truncated {
        found: usize,
    },
    /// Longer than the longest frame: refused before anything else.
    TooLong {
        found: usize,
    },
    /// A value outside its field's range, outside a derived field.
    OutOfRange {
        field: &'static str,
    },
    /// The broadcast address, for a command that does not accept it.
    BroadcastNotAccepted,
    Checksum {
        expected: u32,
        found: u32,
    },
    /// Bytes left over after the derived reader finished.
    Trailing {
        bytes: usize,
    },
    /// A reply only its request identifies, and no request.
    Ambiguous,
    /// A reply the given request does not get.
    NotAReply,
    BufferTooSmall,
    Deku(deku::DekuError),
}

impl From<deku::DekuError> for Error {
    fn from(e: deku::DekuError) -> Self {
        Error::Deku(e)
    }
}
