//! SD frames decoded and encoded by hand: code, ID, two argument bytes, CRC-16/CMS high byte
//! first (the catalogue CRC from the `crc` crate, as an engineer would take it). Only the
//! messages of the bench subset. Strict as the spec: the ID is a device's (0x01..=0x1E) or the
//! broadcast ID 0x1F, which only the commands that accept broadcast may be sent to; new IDs,
//! humidity and run-time minutes and seconds lie in their ranges; a frame longer than 6 bytes
//! is refused first.

use busspec_protocols::sd::{
    request, response, ActuatorStatusBits, Angle, Request, Response, Temperature, Velocity,
};
use busspec_protocols::{DecodeError, Decoded, EncodeError, FieldDesc, MessageDesc, MessageNames};

const LEN: usize = 6;
const FIRST_ID: u8 = 0x01;
const LAST_ID: u8 = 0x1E;
/// The broadcast ID (BID), right after the last device ID.
const BROADCAST: u8 = 0x1F;
const CRC: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_CMS);

/// Length, CRC and ID; returns code, address and the two argument bytes.
#[inline]
fn envelope(frame: &[u8]) -> Result<(u8, u8, u8, u8), DecodeError> {
    let f: &[u8; LEN] = frame.try_into().map_err(|_| {
        if frame.len() > LEN {
            DecodeError::TooLong {
                max: LEN,
                found: frame.len(),
            }
        } else {
            DecodeError::Truncated {
                needed: LEN,
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
            width: 2,
        });
    }
    if !(FIRST_ID..=BROADCAST).contains(&f[1]) {
        return Err(DecodeError::BadAddress {
            offset: 1,
            found: f[1],
            min: FIRST_ID,
            max: LAST_ID,
        });
    }
    Ok((f[0], f[1], f[2], f[3]))
}

/// Refuses the broadcast ID for a command that does not accept it.
#[inline]
fn unicast(address: u8, message: &'static MessageDesc) -> Result<(), DecodeError> {
    if address == BROADCAST {
        return Err(DecodeError::BroadcastNotAccepted { message, address });
    }
    Ok(())
}

/// A byte repeated in argument 2, and in `min..=max`.
#[inline]
fn repeated(
    a1: u8,
    a2: u8,
    field: &'static FieldDesc,
    repeat: &'static FieldDesc,
    min: u8,
    max: u8,
) -> Result<u8, DecodeError> {
    if !(min..=max).contains(&a1) {
        return Err(out_of_range(field, 2, a1, min, max));
    }
    if a2 != a1 {
        return Err(DecodeError::NotEqual {
            field: repeat,
            offset: 3,
            other: field.name,
            expected: a1.into(),
            found: a2.into(),
        });
    }
    Ok(a1)
}

fn out_of_range(
    field: &'static FieldDesc,
    offset: usize,
    found: u8,
    min: u8,
    max: u8,
) -> DecodeError {
    DecodeError::OutOfRange {
        field,
        offset,
        found: found.into(),
        min: min.into(),
        max: max.into(),
        kind: busspec_runtime::NumKind::Int,
    }
}

/// A constant argument byte that holds another value. The commands sharing a code here are
/// told apart by their argument bytes, so the error names the code's first message.
fn invalid(field: &'static FieldDesc, offset: usize, found: u8) -> DecodeError {
    DecodeError::InvalidValue {
        field,
        offset,
        expected: 0,
        found: found.into(),
    }
}

/// Both argument bytes must be these constants.
#[inline]
fn constants(
    (arg1, arg2): (&'static FieldDesc, &'static FieldDesc),
    a1: u8,
    a2: u8,
) -> Result<(), DecodeError> {
    if a1 != 0 {
        return Err(invalid(arg1, 2, a1));
    }
    if a2 != 0 {
        return Err(invalid(arg2, 3, a2));
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
            Request::SetPoint(request::SetPoint {
                freshness,
                position,
            })
        }
        0x69 => constants(
            (
                field!("read_actual_position", "arg1"),
                field!("read_actual_position", "arg2"),
            ),
            a1,
            a2,
        )
        .map(|()| Request::ReadActualPosition(request::ReadActualPosition))?,
        0x77 => Request::SetVelocity(request::SetVelocity {
            set_velocity: Velocity(i16::from_be_bytes([a1, a2])),
        }),
        0x68 => constants(
            (
                field!("read_actual_velocity", "arg1"),
                field!("read_actual_velocity", "arg2"),
            ),
            a1,
            a2,
        )
        .map(|()| Request::ReadActualVelocity(request::ReadActualVelocity))?,
        0xAA => Request::SetServoId(request::SetServoId {
            new_id: repeated(
                a1,
                a2,
                field!("set_servo_id", "new_id"),
                field!("set_servo_id", "new_id_repeat"),
                FIRST_ID,
                LAST_ID,
            )?,
        }),
        0xA0 => {
            unicast(address, &request::ReadTemperatures::DESC)?;
            constants(
                (
                    field!("read_temperatures", "arg1"),
                    field!("read_temperatures", "arg2"),
                ),
                a1,
                a2,
            )
            .map(|()| Request::ReadTemperatures(request::ReadTemperatures))?
        }
        0xA1 => {
            unicast(address, &request::ReadHumidity::DESC)?;
            constants(
                (
                    field!("read_humidity", "arg1"),
                    field!("read_humidity", "arg2"),
                ),
                a1,
                a2,
            )
            .map(|()| Request::ReadHumidity(request::ReadHumidity))?
        }
        0x40 => match (a1, a2) {
            (0xAA, 0x02) => {
                unicast(address, &request::ReadActuatorStatusWord::DESC)?;
                Request::ReadActuatorStatusWord(request::ReadActuatorStatusWord)
            }
            (0xAA, 0x52) => {
                unicast(address, &request::ResetActuatorStatusWord::DESC)?;
                Request::ResetActuatorStatusWord(request::ResetActuatorStatusWord)
            }
            (0xAA, _) => return Err(invalid(field!("read_actuator_status_word", "arg2"), 3, a2)),
            _ => return Err(invalid(field!("read_actuator_status_word", "arg1"), 2, a1)),
        },
        0xA2 => match (a1, a2) {
            (0x00, 0x00) => {
                unicast(address, &request::ReadTotalRuntimeHours::DESC)?;
                Request::ReadTotalRuntimeHours(request::ReadTotalRuntimeHours)
            }
            (0x00, 0x01) => {
                unicast(address, &request::ReadTotalRuntimeMinSec::DESC)?;
                Request::ReadTotalRuntimeMinSec(request::ReadTotalRuntimeMinSec)
            }
            (0x00, _) => return Err(invalid(field!("read_total_runtime_hours", "arg2"), 3, a2)),
            _ => return Err(invalid(field!("read_total_runtime_hours", "arg1"), 2, a1)),
        },
        _ => {
            return Err(DecodeError::UnknownCommand {
                offset: 0,
                code: code.into(),
                len: 1,
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
        (Q::SetPoint(_), R::SetPointReply(_))
            | (
                Q::ReadActualPosition(request::ReadActualPosition),
                R::ActualPosition(_)
            )
            | (Q::SetVelocity(_), R::SetVelocityReply(_))
            | (
                Q::ReadActualVelocity(request::ReadActualVelocity),
                R::ActualVelocity(_)
            )
            | (Q::SetServoId(_), R::SetServoIdReply(_))
            | (
                Q::ReadTemperatures(request::ReadTemperatures),
                R::Temperatures(_)
            )
            | (Q::ReadHumidity(request::ReadHumidity), R::Humidity(_))
            | (
                Q::ReadActuatorStatusWord(request::ReadActuatorStatusWord)
                    | Q::ResetActuatorStatusWord(request::ResetActuatorStatusWord),
                R::ActuatorStatusWord(_)
            )
            | (
                Q::ReadTotalRuntimeHours(request::ReadTotalRuntimeHours),
                R::TotalRuntimeHours(_)
            )
            | (
                Q::ReadTotalRuntimeMinSec(request::ReadTotalRuntimeMinSec),
                R::TotalRuntimeMinSec(_)
            )
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
            Response::SetPointReply(response::SetPointReply {
                freshness,
                position,
            })
        }
        0x49 => {
            let (zero, position) = position_word(a1, a2);
            if zero != 0 {
                return Err(invalid(field!("actual_position", "zero"), 2, zero));
            }
            Response::ActualPosition(response::ActualPosition { position })
        }
        0x57 => Response::SetVelocityReply(response::SetVelocityReply {
            actual_velocity: Velocity(i16::from_be_bytes([a1, a2])),
        }),
        0x48 => Response::ActualVelocity(response::ActualVelocity {
            actual_velocity: Velocity(i16::from_be_bytes([a1, a2])),
        }),
        0x55 => Response::SetServoIdReply(response::SetServoIdReply {
            new_id: repeated(
                a1,
                a2,
                field!("set_servo_id_reply", "new_id"),
                field!("set_servo_id_reply", "new_id_repeat"),
                FIRST_ID,
                LAST_ID,
            )?,
        }),
        // 0x01..=0xFE, with 0x00 (no sensor) and 0xFF (defective) special: every byte.
        0x20 => Response::Temperatures(response::Temperatures {
            motor_temperature: Temperature(a1),
            pcb_temperature: Temperature(a2),
        }),
        // 1..=100 %, with 0 (no sensor) special.
        0x21 => Response::Humidity(response::Humidity {
            humidity: repeated(
                a1,
                a2,
                field!("humidity", "humidity"),
                field!("humidity", "humidity_repeat"),
                0,
                100,
            )?,
        }),
        0x41 => Response::ActuatorStatusWord(response::ActuatorStatusWord {
            status_bits: ActuatorStatusBits(a1),
            status_arg2: a2,
        }),
        0x22 => match request {
            Some(Request::ReadTotalRuntimeHours(request::ReadTotalRuntimeHours)) => {
                Response::TotalRuntimeHours(response::TotalRuntimeHours {
                    runtime_hours: u16::from_be_bytes([a1, a2]),
                })
            }
            Some(Request::ReadTotalRuntimeMinSec(request::ReadTotalRuntimeMinSec)) => {
                if a1 > 59 {
                    return Err(out_of_range(
                        field!("total_runtime_min_sec", "runtime_minutes"),
                        2,
                        a1,
                        0,
                        59,
                    ));
                }
                if a2 > 59 {
                    return Err(out_of_range(
                        field!("total_runtime_min_sec", "runtime_seconds"),
                        3,
                        a2,
                        0,
                        59,
                    ));
                }
                Response::TotalRuntimeMinSec(response::TotalRuntimeMinSec {
                    runtime_minutes: a1,
                    runtime_seconds: a2,
                })
            }
            Some(q) => {
                return Err(DecodeError::NotAReply {
                    message: "total_runtime_hours",
                    request: q.name(),
                    unasked: false,
                })
            }
            None => {
                return Err(DecodeError::Ambiguous {
                    code: 0x22,
                    candidates: MessageNames::from_slice(&[
                        &response::TotalRuntimeHours::DESC,
                        &response::TotalRuntimeMinSec::DESC,
                    ]),
                })
            }
        },
        _ => {
            return Err(DecodeError::UnknownResponse {
                offset: 0,
                code: code.into(),
                len: 1,
            })
        }
    };
    if let Some(q) = request {
        if !answers(q, &message) {
            return Err(DecodeError::NotAReply {
                message: message.name(),
                request: q.name(),
                unasked: false,
            });
        }
    }
    Ok(Decoded { address, message })
}

/// Refuses an ID that is neither a device's nor the broadcast ID (once, before the match).
#[inline]
fn check_address(address: u8) -> Result<(), EncodeError> {
    if !(FIRST_ID..=BROADCAST).contains(&address) {
        return Err(EncodeError::BadAddress {
            address,
            min: FIRST_ID,
            max: LAST_ID,
        });
    }
    Ok(())
}

/// Writes code, ID and arguments and the CRC; called once, after the encoders' match, so the
/// CRC is inlined once.
#[inline]
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

/// Refuses the broadcast ID for a command that does not accept it.
#[inline]
fn unicast_to(message: &'static MessageDesc, address: u8) -> Result<(), EncodeError> {
    if address == BROADCAST {
        return Err(EncodeError::BroadcastNotAccepted { message, address });
    }
    Ok(())
}

/// `?` for the subset encoders, which return `Option<Result<..>>`.
macro_rules! tri {
    ($e:expr) => {
        match $e {
            Ok(v) => v,
            Err(e) => return Some(Err(e)),
        }
    };
}

/// Refuses `value` outside `min..=max`.
#[inline]
fn in_range(field: &'static str, value: u8, min: u8, max: u8) -> Result<u8, EncodeError> {
    if !(min..=max).contains(&value) {
        return Err(EncodeError::NotInRange {
            field,
            value: value.into(),
            min: min.into(),
            max: max.into(),
            kind: busspec_runtime::NumKind::Int,
        });
    }
    Ok(value)
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
    tri!(check_address(address));
    let (code, a1, a2) = match *m {
        Request::SetPoint(request::SetPoint {
            freshness,
            position,
        }) => {
            let [a1, a2] = tri!(put_position_word(freshness, position));
            (0x76, a1, a2)
        }
        Request::ReadActualPosition(request::ReadActualPosition) => (0x69, 0, 0),
        Request::SetVelocity(request::SetVelocity { set_velocity }) => {
            let [a1, a2] = set_velocity.0.to_be_bytes();
            (0x77, a1, a2)
        }
        Request::ReadActualVelocity(request::ReadActualVelocity) => (0x68, 0, 0),
        Request::SetServoId(request::SetServoId { new_id }) => {
            let id = tri!(in_range("new_id", new_id, FIRST_ID, LAST_ID));
            (0xAA, id, id)
        }
        Request::ReadTemperatures(request::ReadTemperatures) => {
            tri!(unicast_to(&request::ReadTemperatures::DESC, address));
            (0xA0, 0, 0)
        }
        Request::ReadHumidity(request::ReadHumidity) => {
            tri!(unicast_to(&request::ReadHumidity::DESC, address));
            (0xA1, 0, 0)
        }
        Request::ReadActuatorStatusWord(request::ReadActuatorStatusWord) => {
            tri!(unicast_to(&request::ReadActuatorStatusWord::DESC, address));
            (0x40, 0xAA, 0x02)
        }
        Request::ResetActuatorStatusWord(request::ResetActuatorStatusWord) => {
            tri!(unicast_to(&request::ResetActuatorStatusWord::DESC, address));
            (0x40, 0xAA, 0x52)
        }
        Request::ReadTotalRuntimeHours(request::ReadTotalRuntimeHours) => {
            tri!(unicast_to(&request::ReadTotalRuntimeHours::DESC, address));
            (0xA2, 0, 0)
        }
        Request::ReadTotalRuntimeMinSec(request::ReadTotalRuntimeMinSec) => {
            tri!(unicast_to(&request::ReadTotalRuntimeMinSec::DESC, address));
            (0xA2, 0, 1)
        }
        _ => return None,
    };
    Some(put(code, address, a1, a2, buf))
}

/// Encodes a response of the subset; `None` for any other message.
pub fn encode_response(
    m: &Response,
    address: u8,
    buf: &mut [u8],
) -> Option<Result<usize, EncodeError>> {
    tri!(check_address(address));
    let (code, a1, a2) = match *m {
        Response::SetPointReply(response::SetPointReply {
            freshness,
            position,
        }) => {
            let [a1, a2] = tri!(put_position_word(freshness, position));
            (0x56, a1, a2)
        }
        Response::ActualPosition(response::ActualPosition { position }) => {
            let [a1, a2] = tri!(put_position_word(0, position));
            (0x49, a1, a2)
        }
        Response::SetVelocityReply(response::SetVelocityReply { actual_velocity }) => {
            let [a1, a2] = actual_velocity.0.to_be_bytes();
            (0x57, a1, a2)
        }
        Response::ActualVelocity(response::ActualVelocity { actual_velocity }) => {
            let [a1, a2] = actual_velocity.0.to_be_bytes();
            (0x48, a1, a2)
        }
        Response::SetServoIdReply(response::SetServoIdReply { new_id }) => {
            let id = tri!(in_range("new_id", new_id, FIRST_ID, LAST_ID));
            (0x55, id, id)
        }
        Response::Temperatures(response::Temperatures {
            motor_temperature,
            pcb_temperature,
        }) => (0x20, motor_temperature.0, pcb_temperature.0),
        Response::Humidity(response::Humidity { humidity }) => {
            let h = tri!(in_range("humidity", humidity, 0, 100));
            (0x21, h, h)
        }
        Response::ActuatorStatusWord(response::ActuatorStatusWord {
            status_bits,
            status_arg2,
        }) => (0x41, status_bits.0, status_arg2),
        Response::TotalRuntimeHours(response::TotalRuntimeHours { runtime_hours }) => {
            let [a1, a2] = runtime_hours.to_be_bytes();
            (0x22, a1, a2)
        }
        Response::TotalRuntimeMinSec(response::TotalRuntimeMinSec {
            runtime_minutes,
            runtime_seconds,
        }) => {
            let m = tri!(in_range("runtime_minutes", runtime_minutes, 0, 59));
            let s = tri!(in_range("runtime_seconds", runtime_seconds, 0, 59));
            (0x22, m, s)
        }
        _ => return None,
    };
    Some(put(code, address, a1, a2, buf))
}
