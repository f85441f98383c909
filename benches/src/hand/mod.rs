//! Decoders and encoders for the bench subset of each protocol, written by hand the way a
//! careful engineer would: slice patterns on the code, every check the generated code makes
//! (over-long frames first, start byte, length, checksum, address and broadcast rule, code,
//! constants, repeated arguments, field ranges; the encoders refuse the same), typed results. They
//! produce the generated crate's types, so the tests can compare the two value for value.

/// A `&'static` descriptor of field `$field` of message `$message`, as the runtime's refusals
/// point at one.
macro_rules! field {
    ($message:literal, $field:literal) => {{
        static FIELD: busspec_protocols::FieldDesc =
            busspec_protocols::FieldDesc::new($message, $field);
        &FIELD
    }};
}

pub mod sd;
pub mod ub2;

/// Why a hand-written encoder did not encode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EncodeError {
    Frame(busspec_protocols::EncodeError),
    /// The hand-written encoders cover only the bench subset.
    NotInSubset(&'static str),
}

/// `None` from a subset encoder means the message is outside it.
#[inline]
pub fn subset(
    name: &'static str,
    r: Option<Result<usize, busspec_protocols::EncodeError>>,
) -> Result<usize, EncodeError> {
    match r {
        Some(r) => r.map_err(EncodeError::Frame),
        None => Err(EncodeError::NotInSubset(name)),
    }
}
