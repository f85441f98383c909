//! The SD bench subset as a deku user would write it: a derived frame (code, ID, message chosen
//! by the code) with the CRC-16/CMS checked and written around it. Replies only their request
//! identifies (0x22) are read raw and interpreted by the request, as deku cannot choose a
//! variant from something outside the frame. The ID (a device's, 0x01..=0x1E, or the
//! broadcast ID 0x1F) and the ranged fields are asserted; which commands accept the broadcast ID
//! is checked around the derived code.

use deku::prelude::*;

use super::Error;

const CRC: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_CMS);

/// deku reads a 12-bit two's-complement field into an `i16` sign-extended, but writes only
/// values that fit 12 bits unsigned: write the low 12 bits of a value in range.
fn write_i12<W: deku::no_std_io::Write + deku::no_std_io::Seek>(
    writer: &mut deku::writer::Writer<W>,
    v: i16,
) -> Result<(), DekuError> {
    if !(-2048..=2047).contains(&v) {
        return Err(DekuError::InvalidParam(
            "12-bit position out of range".into(),
        ));
    }
    ((v as u16) & 0xFFF).to_writer(writer, (deku::ctx::Endian::Big, deku::ctx::BitSize(12)))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
pub struct RequestFrame {
    pub code: u8,
    #[deku(assert = "(0x01..=0x1F).contains(address)")]
    pub address: u8,
    #[deku(ctx = "*code")]
    pub message: Request,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(ctx = "code: u8", id = "code", endian = "big")]
pub enum Request {
    #[deku(id = 0x76)]
    SetPoint {
        #[deku(bits = 4)]
        freshness: u8,
        #[deku(bits = 12, writer = "write_i12(deku::writer, *position)")]
        position: i16,
    },
    #[deku(id = 0x69)]
    ReadActualPosition {
        #[deku(assert_eq = "0")]
        arg1: u8,
        #[deku(assert_eq = "0")]
        arg2: u8,
    },
    #[deku(id = 0x77)]
    SetVelocity { set_velocity: i16 },
    #[deku(id = 0x68)]
    ReadActualVelocity {
        #[deku(assert_eq = "0")]
        arg1: u8,
        #[deku(assert_eq = "0")]
        arg2: u8,
    },
    #[deku(id = 0xAA)]
    SetServoId {
        #[deku(assert = "(0x01..=0x1E).contains(new_id)")]
        new_id: u8,
        #[deku(assert = "*new_id_repeat == *new_id")]
        new_id_repeat: u8,
    },
    #[deku(id = 0xA0)]
    ReadTemperatures {
        #[deku(assert_eq = "0")]
        arg1: u8,
        #[deku(assert_eq = "0")]
        arg2: u8,
    },
    #[deku(id = 0xA1)]
    ReadHumidity {
        #[deku(assert_eq = "0")]
        arg1: u8,
        #[deku(assert_eq = "0")]
        arg2: u8,
    },
    #[deku(id = 0x40)]
    ActuatorStatusWord {
        #[deku(assert_eq = "0xAA")]
        arg1: u8,
        op: StatusOp,
    },
    #[deku(id = 0xA2)]
    ReadTotalRuntime {
        #[deku(assert_eq = "0")]
        arg1: u8,
        part: RuntimePart,
    },
}

/// Argument 2 of 0x40.
#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(id_type = "u8", ctx = "endian: deku::ctx::Endian", endian = "endian")]
pub enum StatusOp {
    #[deku(id = 0x02)]
    Read,
    #[deku(id = 0x52)]
    Reset,
}

/// Argument 2 of 0xA2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(id_type = "u8", ctx = "endian: deku::ctx::Endian", endian = "endian")]
pub enum RuntimePart {
    #[deku(id = 0x00)]
    Hours,
    #[deku(id = 0x01)]
    MinSec,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
pub struct ResponseFrame {
    pub code: u8,
    #[deku(assert = "(0x01..=0x1F).contains(address)")]
    pub address: u8,
    #[deku(ctx = "*code")]
    pub message: Response,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, DekuRead, DekuWrite)]
#[deku(ctx = "code: u8", id = "code", endian = "big")]
pub enum Response {
    #[deku(id = 0x56)]
    SetPointReply {
        #[deku(bits = 4)]
        freshness: u8,
        #[deku(bits = 12, writer = "write_i12(deku::writer, *position)")]
        position: i16,
    },
    #[deku(id = 0x49)]
    ActualPosition {
        #[deku(bits = 4, assert_eq = "0")]
        zero: u8,
        #[deku(bits = 12, writer = "write_i12(deku::writer, *position)")]
        position: i16,
    },
    #[deku(id = 0x57)]
    SetVelocityReply { actual_velocity: i16 },
    #[deku(id = 0x48)]
    ActualVelocity { actual_velocity: i16 },
    #[deku(id = 0x55)]
    SetServoIdReply {
        #[deku(assert = "(0x01..=0x1E).contains(new_id)")]
        new_id: u8,
        #[deku(assert = "*new_id_repeat == *new_id")]
        new_id_repeat: u8,
    },
    #[deku(id = 0x20)]
    Temperatures {
        motor_temperature: u8,
        pcb_temperature: u8,
    },
    #[deku(id = 0x21)]
    Humidity {
        #[deku(assert = "*humidity <= 100")]
        humidity: u8,
        #[deku(assert = "*humidity_repeat == *humidity")]
        humidity_repeat: u8,
    },
    #[deku(id = 0x41)]
    ActuatorStatusWord { status_bits: u8, status_arg2: u8 },
    /// Total run-time in hours or in minutes and seconds: which, only the request says.
    #[deku(id = 0x22)]
    TotalRuntime { args: [u8; 2] },
}

impl Request {
    /// Whether the command may be sent to the broadcast ID.
    pub fn accepts_broadcast(&self) -> bool {
        matches!(
            self,
            Request::SetPoint { .. }
                | Request::ReadActualPosition { .. }
                | Request::SetVelocity { .. }
                | Request::ReadActualVelocity { .. }
                | Request::SetServoId { .. }
        )
    }
}

const BROADCAST: u8 = 0x1F;

/// Refuses the broadcast ID for a command that does not accept it.
fn unicast(f: &RequestFrame) -> Result<(), Error> {
    if f.address == BROADCAST && !f.message.accepts_broadcast() {
        return Err(Error::BroadcastNotAccepted);
    }
    Ok(())
}

/// Run-time minutes and seconds are 0..=59.
fn min_sec(minutes: u8, seconds: u8) -> Result<(), Error> {
    if minutes > 59 {
        return Err(Error::OutOfRange {
            field: "runtime_minutes",
        });
    }
    if seconds > 59 {
        return Err(Error::OutOfRange {
            field: "runtime_seconds",
        });
    }
    Ok(())
}

/// A response with the replies only their request identifies interpreted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reply {
    Frame(ResponseFrame),
    TotalRuntimeHours {
        address: u8,
        hours: u16,
    },
    TotalRuntimeMinSec {
        address: u8,
        minutes: u8,
        seconds: u8,
    },
}

/// Checks length (too long first) and CRC; returns the bytes before the CRC.
fn checked(frame: &[u8]) -> Result<&[u8], Error> {
    if frame.len() > 6 {
        return Err(Error::TooLong { found: frame.len() });
    }
    if frame.len() != 6 {
        return Err(Error::Truncated { found: frame.len() });
    }
    let (body, crc) = frame.split_at(4);
    let expected = CRC.checksum(body);
    let found = u16::from_be_bytes([crc[0], crc[1]]);
    if found != expected {
        return Err(Error::Checksum {
            expected: expected.into(),
            found: found.into(),
        });
    }
    Ok(body)
}

pub fn decode_request(frame: &[u8]) -> Result<RequestFrame, Error> {
    let body = checked(frame)?;
    let ((rest, _), f) = RequestFrame::from_bytes((body, 0))?;
    if !rest.is_empty() {
        return Err(Error::Trailing { bytes: rest.len() });
    }
    unicast(&f)?;
    Ok(f)
}

/// Whether `r` is a reply `q` may get (0x22 is settled by the request itself).
fn answers(q: &Request, r: &Response) -> bool {
    use Request as Q;
    use Response as R;
    matches!(
        (q, r),
        (Q::SetPoint { .. }, R::SetPointReply { .. })
            | (Q::ReadActualPosition { .. }, R::ActualPosition { .. })
            | (Q::SetVelocity { .. }, R::SetVelocityReply { .. })
            | (Q::ReadActualVelocity { .. }, R::ActualVelocity { .. })
            | (Q::SetServoId { .. }, R::SetServoIdReply { .. })
            | (Q::ReadTemperatures { .. }, R::Temperatures { .. })
            | (Q::ReadHumidity { .. }, R::Humidity { .. })
            | (Q::ActuatorStatusWord { .. }, R::ActuatorStatusWord { .. })
    )
}

pub fn decode_response(frame: &[u8], request: Option<&RequestFrame>) -> Result<Reply, Error> {
    let body = checked(frame)?;
    let ((rest, _), f) = ResponseFrame::from_bytes((body, 0))?;
    if !rest.is_empty() {
        return Err(Error::Trailing { bytes: rest.len() });
    }
    let Response::TotalRuntime { args } = f.message else {
        return match request {
            Some(q) if !answers(&q.message, &f.message) => Err(Error::NotAReply),
            _ => Ok(Reply::Frame(f)),
        };
    };
    let address = f.address;
    match request.map(|r| r.message) {
        Some(Request::ReadTotalRuntime {
            part: RuntimePart::Hours,
            ..
        }) => Ok(Reply::TotalRuntimeHours {
            address,
            hours: u16::from_be_bytes(args),
        }),
        Some(Request::ReadTotalRuntime {
            part: RuntimePart::MinSec,
            ..
        }) => min_sec(args[0], args[1]).map(|()| Reply::TotalRuntimeMinSec {
            address,
            minutes: args[0],
            seconds: args[1],
        }),
        Some(_) => Err(Error::NotAReply),
        None => Err(Error::Ambiguous),
    }
}

/// Writes the derived body, then its CRC.
fn seal(n: usize, buf: &mut [u8]) -> Result<usize, Error> {
    let crc = CRC.checksum(&buf[..n]).to_be_bytes();
    buf.get_mut(n..n + 2)
        .ok_or(Error::BufferTooSmall)?
        .copy_from_slice(&crc);
    Ok(n + 2)
}

pub fn encode_request(f: &RequestFrame, buf: &mut [u8]) -> Result<usize, Error> {
    unicast(f)?;
    let n = f.to_slice(buf)?;
    seal(n, buf)
}

pub fn encode_response(r: &Reply, buf: &mut [u8]) -> Result<usize, Error> {
    let f = match *r {
        Reply::Frame(f) => f,
        Reply::TotalRuntimeHours { address, hours } => ResponseFrame {
            code: 0x22,
            address,
            message: Response::TotalRuntime {
                args: hours.to_be_bytes(),
            },
        },
        Reply::TotalRuntimeMinSec {
            address,
            minutes,
            seconds,
        } => min_sec(minutes, seconds).map(|()| ResponseFrame {
            code: 0x22,
            address,
            message: Response::TotalRuntime {
                args: [minutes, seconds],
            },
        })?,
    };
    let n = f.to_slice(buf)?;
    seal(n, buf)
}
