//! The derive-based peer: the bench subset of each protocol with deku's `DekuRead`/`DekuWrite`,
//! the checksum (which deku cannot express over the bytes before it) checked and written around
//! the derived code.

pub mod sd;
pub mod ub2;

/// Why the peer did not decode or encode a frame.
#[derive(Debug)]
pub enum Error {
    Truncated {
        found: usize,
    },
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
