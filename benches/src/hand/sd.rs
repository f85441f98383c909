//! SD frames decoded and encoded by hand: code, ID, two argument bytes, CRC-16/CMS high byte
//! first (the catalogue CRC from the `crc` crate, as an engineer would take it). Only the
//! messages of the bench subset.

use busspec_protocols::sd::{ActuatorStatusBits, Angle, Request, Response, Temperature, Velocity};
use busspec_protocols::{DecodeError, Decoded, EncodeError};

const LEN: usize = 6;
const CRC: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_CMS);

/// Length and CRC; returns code, address and the two argument bytes.
#[inline]
fn envelope(frame: &[u8]) -> Result<(u8, u8, u8, u8), DecodeError> {
    let f: &[u8; LEN] = frame.try_into().map_err(|_| {
        if frame.len() < LEN {
            DecodeError::Truncated {
                needed: LEN,
                found: frame.len(),
            }
        } else {
            DecodeError::WrongLength {
                expected: LEN,
                found: frame.len(),
            }
        }
    })?;
    let expected = CRC.checksum(&f[..4]);
    let found = u16::from_be_bytes([f[4], f[5]]);
    if found != expected {
        return Err(DecodeError::ChecksumMismatch {
            offset: 4,
            expected: expected.into(),
            found: found.into(),
        });
    }
    Ok((f[0], f[1], f[2], f[3]))
}

fn invalid(field: &'static str, offset: usize, found: u8) -> DecodeError {
    DecodeError::InvalidValue {
        field,
        offset,
        found: found.into(),
    }
}

/// Both argument bytes must be these constants.
#[inline]
fn constants(a1: u8, a2: u8, want1: u8, want2: u8) -> Result<(), DecodeError> {
    if a1 != want1 {
        return Err(invalid("arg1", 2, a1));
    }
    if a2 != want2 {
        return Err(invalid("arg2", 3, a2));
    }
    Ok(())
}

/// Bits 15..12 and the 12-bit two's-complement position in bits 11..0 of a big-endian word.
#[inline]
fn position_word(a1: u8, a2: u8) -> (u8, Angle) {
    let w = u16::from_be_bytes([a1, a2]);
    ((w >> 12) as u8, Angle(((w << 4) as i16) >> 4))
}

pub fn decode_request(frame: &[u8]) -> Result<Decoded<Request>, DecodeError> {
    let (code, address, a1, a2) = envelope(frame)?;
    let message = match code {
        0x76 => {
            let (freshness, position) = position_word(a1, a2);
            Request::SetPoint {
                freshness,
                position,
            }
        }
        0x69 => constants(a1, a2, 0, 0).map(|()| Request::ReadActualPosition)?,
        0x77 => Request::SetVelocity {
            set_velocity: Velocity(i16::from_be_bytes([a1, a2])),
        },
        0x68 => constants(a1, a2, 0, 0).map(|()| Request::ReadActualVelocity)?,
        0xAA => {
            if a2 != a1 {
                return Err(invalid("new_id_repeat", 3, a2));
            }
            Request::SetServoId { new_id: a1 }
        }
        0xA0 => constants(a1, a2, 0, 0).map(|()| Request::ReadTemperatures)?,
        0xA1 => constants(a1, a2, 0, 0).map(|()| Request::ReadHumidity)?,
        0x40 => match (a1, a2) {
            (0xAA, 0x02) => Request::ReadActuatorStatusWord,
            (0xAA, 0x52) => Request::ResetActuatorStatusWord,
            (0xAA, _) => return Err(invalid("arg2", 3, a2)),
            _ => return Err(invalid("arg1", 2, a1)),
        },
        0xA2 => match (a1, a2) {
            (0x00, 0x00) => Request::ReadTotalRuntimeHours,
            (0x00, 0x01) => Request::ReadTotalRuntimeMinSec,
            (0x00, _) => return Err(invalid("arg2", 3, a2)),
            _ => return Err(invalid("arg1", 2, a1)),
        },
        _ => {
            return Err(DecodeError::UnknownCommand {
                offset: 0,
                code: code.into(),
            })
        }
    };
    Ok(Decoded { address, message })
}

/// Whether `r` is a reply `q` may get (within the subset).
fn answers(q: &Request, r: &Response) -> bool {
    use Request as Q;
    use Response as R;
    matches!(
        (q, r),
        (Q::SetPoint { .. }, R::SetPointReply { .. })
            | (Q::ReadActualPosition, R::ActualPosition { .. })
            | (Q::SetVelocity { .. }, R::SetVelocityReply { .. })
            | (Q::ReadActualVelocity, R::ActualVelocity { .. })
            | (Q::SetServoId { .. }, R::SetServoIdReply { .. })
            | (Q::ReadTemperatures, R::Temperatures { .. })
            | (Q::ReadHumidity, R::Humidity { .. })
            | (
                Q::ReadActuatorStatusWord | Q::ResetActuatorStatusWord,
                R::ActuatorStatusWord { .. }
            )
            | (Q::ReadTotalRuntimeHours, R::TotalRuntimeHours { .. })
            | (Q::ReadTotalRuntimeMinSec, R::TotalRuntimeMinSec { .. })
    )
}

/// With `request`, only replies it may get decode ([`DecodeError::NotAReply`] otherwise), which
/// settles the replies only it identifies (0x22 here); without it those are
/// [`DecodeError::Ambiguous`].
pub fn decode_response(
    frame: &[u8],
    request: Option<&Request>,
) -> Result<Decoded<Response>, DecodeError> {
    let (code, address, a1, a2) = envelope(frame)?;
    let message = match code {
        0x56 => {
            let (freshness, position) = position_word(a1, a2);
            Response::SetPointReply {
                freshness,
                position,
            }
        }
        0x49 => {
            let (zero, position) = position_word(a1, a2);
            if zero != 0 {
                return Err(invalid("zero", 2, zero));
            }
            Response::ActualPosition { position }
        }
        0x57 => Response::SetVelocityReply {
            actual_velocity: Velocity(i16::from_be_bytes([a1, a2])),
        },
        0x48 => Response::ActualVelocity {
            actual_velocity: Velocity(i16::from_be_bytes([a1, a2])),
        },
        0x55 => {
            if a2 != a1 {
                return Err(invalid("new_id_repeat", 3, a2));
            }
            Response::SetServoIdReply { new_id: a1 }
        }
        0x20 => Response::Temperatures {
            motor_temperature: Temperature(a1),
            pcb_temperature: Temperature(a2),
        },
        0x21 => {
            if a2 != a1 {
                return Err(invalid("humidity_repeat", 3, a2));
            }
            Response::Humidity { humidity: a1 }
        }
        0x41 => Response::ActuatorStatusWord {
            status_bits: ActuatorStatusBits(a1),
            status_arg2: a2,
        },
        0x22 => match request {
            Some(Request::ReadTotalRuntimeHours) => Response::TotalRuntimeHours {
                runtime_hours: u16::from_be_bytes([a1, a2]),
            },
            Some(Request::ReadTotalRuntimeMinSec) => Response::TotalRuntimeMinSec {
                runtime_minutes: a1,
                runtime_seconds: a2,
            },
            Some(_) => return Err(DecodeError::NotAReply { code: 0x22 }),
            None => return Err(DecodeError::Ambiguous { code: 0x22 }),
        },
        _ => {
            return Err(DecodeError::UnknownCommand {
                offset: 0,
                code: code.into(),
            })
        }
    };
    if let Some(q) = request {
        if !answers(q, &message) {
            return Err(DecodeError::NotAReply { code: code.into() });
        }
    }
    Ok(Decoded { address, message })
}

fn put(code: u8, address: u8, a1: u8, a2: u8, buf: &mut [u8]) -> Result<usize, EncodeError> {
    let available = buf.len();
    let out: &mut [u8; LEN] =
        buf.get_mut(..LEN)
            .and_then(|s| s.try_into().ok())
            .ok_or(EncodeError::BufferTooSmall {
                needed: LEN,
                available,
            })?;
    *out = [code, address, a1, a2, 0, 0];
    let crc = CRC.checksum(&out[..4]);
    out[4..].copy_from_slice(&crc.to_be_bytes());
    Ok(LEN)
}

/// A freshness nibble and a 12-bit position as the big-endian word's two bytes.
fn put_position_word(freshness: u8, position: Angle) -> Result<[u8; 2], EncodeError> {
    if freshness > 0xF {
        return Err(EncodeError::OutOfRange { field: "freshness" });
    }
    if !(-2048..=2047).contains(&position.0) {
        return Err(EncodeError::OutOfRange { field: "position" });
    }
    Ok((u16::from(freshness) << 12 | (position.0 as u16 & 0xFFF)).to_be_bytes())
}

/// Encodes a request of the subset; `None` for any other message.
pub fn encode_request(
    m: &Request,
    address: u8,
    buf: &mut [u8],
) -> Option<Result<usize, EncodeError>> {
    Some(match *m {
        Request::SetPoint {
            freshness,
            position,
        } => put_position_word(freshness, position)
            .and_then(|[a1, a2]| put(0x76, address, a1, a2, buf)),
        Request::ReadActualPosition => put(0x69, address, 0, 0, buf),
        Request::SetVelocity { set_velocity } => {
            let [a1, a2] = set_velocity.0.to_be_bytes();
            put(0x77, address, a1, a2, buf)
        }
        Request::ReadActualVelocity => put(0x68, address, 0, 0, buf),
        Request::SetServoId { new_id } => put(0xAA, address, new_id, new_id, buf),
        Request::ReadTemperatures => put(0xA0, address, 0, 0, buf),
        Request::ReadHumidity => put(0xA1, address, 0, 0, buf),
        Request::ReadActuatorStatusWord => put(0x40, address, 0xAA, 0x02, buf),
        Request::ResetActuatorStatusWord => put(0x40, address, 0xAA, 0x52, buf),
        Request::ReadTotalRuntimeHours => put(0xA2, address, 0, 0, buf),
        Request::ReadTotalRuntimeMinSec => put(0xA2, address, 0, 1, buf),
        _ => return None,
    })
}

/// Encodes a response of the subset; `None` for any other message.
pub fn encode_response(
    m: &Response,
    address: u8,
    buf: &mut [u8],
) -> Option<Result<usize, EncodeError>> {
    Some(match *m {
        Response::SetPointReply {
            freshness,
            position,
        } => put_position_word(freshness, position)
            .and_then(|[a1, a2]| put(0x56, address, a1, a2, buf)),
        Response::ActualPosition { position } => {
            put_position_word(0, position).and_then(|[a1, a2]| put(0x49, address, a1, a2, buf))
        }
        Response::SetVelocityReply { actual_velocity } => {
            let [a1, a2] = actual_velocity.0.to_be_bytes();
            put(0x57, address, a1, a2, buf)
        }
        Response::ActualVelocity { actual_velocity } => {
            let [a1, a2] = actual_velocity.0.to_be_bytes();
            put(0x48, address, a1, a2, buf)
        }
        Response::SetServoIdReply { new_id } => put(0x55, address, new_id, new_id, buf),
        Response::Temperatures {
            motor_temperature,
            pcb_temperature,
        } => put(0x20, address, motor_temperature.0, pcb_temperature.0, buf),
        Response::Humidity { humidity } => put(0x21, address, humidity, humidity, buf),
        Response::ActuatorStatusWord {
            status_bits,
            status_arg2,
        } => put(0x41, address, status_bits.0, status_arg2, buf),
        Response::TotalRuntimeHours { runtime_hours } => {
            let [a1, a2] = runtime_hours.to_be_bytes();
            put(0x22, address, a1, a2, buf)
        }
        Response::TotalRuntimeMinSec {
            runtime_minutes,
            runtime_seconds,
        } => put(0x22, address, runtime_minutes, runtime_seconds, buf),
        _ => return None,
    })
}
