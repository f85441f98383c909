//! The UB2 bench subset as a deku user would write it: derived readers and writers for the
//! frame and its messages, the 8-bit sum checked and written around them. The address (a
//! device's, 0x21..=0x40, or the host's, 0x20) and the C-curve index (0..=499) are asserted.

use deku::prelude::*;

use super::Error;

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(magic = b"\xAA")]
pub struct RequestFrame {
    #[deku(assert = "(0x20..=0x40).contains(address)")]
    pub address: u8,
    pub message: Request,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(id_type = "u16", id_endian = "big", endian = "little")]
pub enum Request {
    #[deku(id = 0x1000)]
    ReferenceRun,
    #[deku(id = 0x2000)]
    GoToCapacitance { target: u32 },
    #[deku(id = 0x2001)]
    GoToCapacitanceStatus,
    #[deku(id = 0x2100)]
    GoToFullStepPosition { target: u16 },
    #[deku(id = 0x2200)]
    MoveFullSteps { steps: i16 },
    #[deku(id = 0x8000)]
    SetModeOfOperation { mode: Mode },
    #[deku(id = 0x4001)]
    GetActualCapacitance,
    #[deku(id = 0x4080)]
    GetModeOfOperation,
    #[deku(id = 0x4030)]
    GetCCurveIndexedFullStepCapacitance {
        #[deku(assert = "*index <= 499")]
        index: u16,
    },
    #[deku(id = 0x4032)]
    GetControllerTemperature,
    #[deku(id = 0x4061)]
    GetFirmwareVersion,
    #[deku(id = 0x4072)]
    GetLimit { limit: Limit },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(id_type = "u8", ctx = "endian: deku::ctx::Endian", endian = "endian")]
pub enum Mode {
    #[deku(id = 0x00)]
    EncoderDisabled,
    #[deku(id = 0x01)]
    CloseLoopControl,
    #[deku(id = 0x02)]
    OpenLoopControl,
    #[deku(id_pat = "_")]
    Unknown(u8),
}

/// The index byte of 0x4072 (and of its reply) selecting the limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(id_type = "u8", ctx = "endian: deku::ctx::Endian", endian = "endian")]
pub enum Limit {
    #[deku(id = 0x01)]
    LowerCustomer,
    #[deku(id = 0x02)]
    UpperCustomer,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(magic = b"\xAA")]
pub struct ResponseFrame {
    #[deku(assert = "(0x20..=0x40).contains(address)")]
    pub address: u8,
    pub message: Response,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(id_type = "u8")]
pub enum Response {
    #[deku(id = 0x50)]
    MovementStarted,
    #[deku(id = 0x51)]
    MovementCompleted,
    #[deku(id = 0x52)]
    MovementNotCompleted,
    #[deku(id = 0x93)]
    NakLimitReached,
    #[deku(id = 0x94)]
    NakIndexOutOfRange,
    /// Setter echoes, 0x80 0x00.
    #[deku(id = 0x80)]
    Echo(Echo),
    /// Getter replies, 0x41 and the getter's second code byte.
    #[deku(id = 0x41)]
    Data(Data),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(id_type = "u8")]
pub enum Echo {
    #[deku(id = 0x00)]
    SetModeOfOperationAck,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(id_type = "u8", endian = "little")]
pub enum Data {
    #[deku(id = 0x01)]
    ActualCapacitance { capacitance: u32 },
    #[deku(id = 0x80)]
    ActualModeOfOperation { mode: Mode },
    #[deku(id = 0x30)]
    CCurveEntry {
        #[deku(assert = "*index <= 499")]
        index: u16,
        full_steps: u16,
        capacitance: u32,
    },
    #[deku(id = 0x32)]
    ControllerTemperature { temperature: u8 },
    #[deku(id = 0x61)]
    FirmwareVersion { firmware_version: [u8; 11] },
    #[deku(id = 0x72)]
    Limit { limit: Limit, capacitance: u32 },
}

fn sum8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |s, b| s.wrapping_add(*b))
}

/// Checks the length (too long first) and the trailing sum; returns the bytes before it.
fn checked(frame: &[u8], min: usize, max: usize) -> Result<&[u8], Error> {
    if frame.len() > max {
        return Err(Error::TooLong { found: frame.len() });
    }
    if frame.len() < min {
        return Err(Error::Truncated { found: frame.len() });
    }
    let (body, sum) = frame.split_at(frame.len() - 1);
    let expected = sum8(body);
    if sum[0] != expected {
        return Err(Error::Checksum {
            expected: expected.into(),
            found: sum[0].into(),
        });
    }
    Ok(body)
}

pub fn decode_request(frame: &[u8]) -> Result<RequestFrame, Error> {
    let body = checked(frame, 5, 9)?;
    let ((rest, _), f) = RequestFrame::from_bytes((body, 0))?;
    if !rest.is_empty() {
        return Err(Error::Trailing { bytes: rest.len() });
    }
    Ok(f)
}

/// Whether `r` is a reply `q` may get: the replies the command lists, and 0x94, which every
/// command may get.
fn answers(q: &Request, r: &Response) -> bool {
    use Request as Q;
    use Response as R;
    matches!(
        (q, r),
        (_, R::NakIndexOutOfRange)
            | (
                Q::ReferenceRun
                    | Q::GoToCapacitance { .. }
                    | Q::GoToFullStepPosition { .. }
                    | Q::MoveFullSteps { .. },
                R::MovementStarted
            )
            | (
                Q::GoToCapacitance { .. }
                    | Q::GoToFullStepPosition { .. }
                    | Q::MoveFullSteps { .. },
                R::NakLimitReached
            )
            | (
                Q::GoToCapacitanceStatus,
                R::MovementCompleted | R::MovementNotCompleted
            )
            | (
                Q::SetModeOfOperation { .. },
                R::Echo(Echo::SetModeOfOperationAck)
            )
            | (
                Q::GetActualCapacitance,
                R::Data(Data::ActualCapacitance { .. })
            )
            | (
                Q::GetModeOfOperation,
                R::Data(Data::ActualModeOfOperation { .. })
            )
            | (
                Q::GetCCurveIndexedFullStepCapacitance { .. },
                R::Data(Data::CCurveEntry { .. })
            )
            | (
                Q::GetControllerTemperature,
                R::Data(Data::ControllerTemperature { .. })
            )
            | (Q::GetFirmwareVersion, R::Data(Data::FirmwareVersion { .. }))
    ) || matches!((q, r), (Q::GetLimit { limit }, R::Data(Data::Limit { limit: l, .. })) if l == limit)
}

/// UB2 responses need no request to be told apart; with `request`, only replies it may get
/// decode, as the SD peer's.
pub fn decode_response(
    frame: &[u8],
    request: Option<&RequestFrame>,
) -> Result<ResponseFrame, Error> {
    let body = checked(frame, 4, 16)?;
    let ((rest, _), f) = ResponseFrame::from_bytes((body, 0))?;
    if !rest.is_empty() {
        return Err(Error::Trailing { bytes: rest.len() });
    }
    match request {
        Some(q) if !answers(&q.message, &f.message) => Err(Error::NotAReply),
        _ => Ok(f),
    }
}

/// Writes the derived body, then its sum.
fn seal(n: usize, buf: &mut [u8]) -> Result<usize, Error> {
    let sum = sum8(&buf[..n]);
    *buf.get_mut(n).ok_or(Error::BufferTooSmall)? = sum;
    Ok(n + 1)
}

pub fn encode_request(f: &RequestFrame, buf: &mut [u8]) -> Result<usize, Error> {
    let n = f.to_slice(buf)?;
    seal(n, buf)
}

pub fn encode_response(f: &ResponseFrame, buf: &mut [u8]) -> Result<usize, Error> {
    let n = f.to_slice(buf)?;
    seal(n, buf)
}
