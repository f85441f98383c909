//! UB2 frames decoded and encoded by hand: `0xAA`, address, 2-byte request code or 1/2-byte
//! response code, little-endian payload, 8-bit sum. Only the messages of the bench subset.
//! Strict as the spec: the address is a device's (0x21..=0x40) or the host's (0x20), the
//! C-curve index lies in 0..=499, and a frame longer than the longest is refused first.

use busspec_protocols::ub2::{request, response, Capacitance, ModeOfOperation, Request, Response};
use busspec_protocols::{DecodeError, Decoded, EncodeError, FieldDesc, MessageDesc};

const START: u8 = 0xAA;
/// The host's address; the devices' follow it (§2.2, §2.3; erratum ub2-e02).
const HOST: u8 = 0x20;
const FIRST_DEVICE: u8 = 0x21;
const LAST_DEVICE: u8 = 0x40;
/// The C-curve table's last index (§6.7).
const LAST_INDEX: u16 = 499;

fn sum8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |s, b| s.wrapping_add(*b))
}

/// Length bounds (too long first), start byte, checksum and address; returns the address and
/// the bytes between it and the checksum (code and payload).
#[inline]
fn envelope(frame: &[u8], min: usize, max: usize) -> Result<(u8, &[u8]), DecodeError> {
    if frame.len() > max {
        return Err(DecodeError::TooLong {
            max,
            found: frame.len(),
        });
    }
    if let Some(&found) = frame.first() {
        if found != START {
            return Err(DecodeError::BadStart {
                offset: 0,
                expected: START,
                found,
            });
        }
    }
    if frame.len() < min {
        return Err(DecodeError::Truncated {
            needed: min,
            found: frame.len(),
        });
    }
    let (body, sum) = frame.split_at(frame.len() - 1);
    let expected = sum8(body);
    if sum[0] != expected {
        return Err(DecodeError::ChecksumMismatch {
            offset: body.len(),
            expected: expected.into(),
            found: sum[0].into(),
            width: 1,
        });
    }
    let address = body[1];
    if !(HOST..=LAST_DEVICE).contains(&address) {
        return Err(DecodeError::BadAddress {
            offset: 1,
            found: address,
            min: FIRST_DEVICE,
            max: LAST_DEVICE,
        });
    }
    Ok((address, &body[2..]))
}

/// A C-curve index, refused beyond the table's last (the field starts at offset 4).
#[inline]
fn index(field: &'static FieldDesc, a: u8, b: u8) -> Result<u16, DecodeError> {
    let index = u16le(a, b);
    if index > LAST_INDEX {
        return Err(DecodeError::OutOfRange {
            field,
            offset: 4,
            found: index.into(),
            min: 0,
            max: LAST_INDEX.into(),
            kind: busspec_runtime::NumKind::Int,
        });
    }
    Ok(index)
}

fn u16le(a: u8, b: u8) -> u16 {
    u16::from_le_bytes([a, b])
}

fn u32le(a: u8, b: u8, c: u8, d: u8) -> u32 {
    u32::from_le_bytes([a, b, c, d])
}

/// A frame of a known code and another length. One arm stands for several codes here, so the
/// error names the protocol, not each message, and the length of the arm's frames.
fn wrong_length(message: &'static MessageDesc, frame: &[u8]) -> DecodeError {
    DecodeError::WrongLength {
        message,
        found: frame.len(),
        less: 0,
    }
}

/// What [`wrong_length`] names for frames of `lengths`.
const fn ub2(lengths: &'static [usize]) -> MessageDesc {
    MessageDesc::new("ub2", 0, 0, lengths)
}
static LEN_4: MessageDesc = ub2(&[4]);
static LEN_5: MessageDesc = ub2(&[5]);
static LEN_6: MessageDesc = ub2(&[6]);
static LEN_7: MessageDesc = ub2(&[7]);
static LEN_9: MessageDesc = ub2(&[9]);
static LEN_10: MessageDesc = ub2(&[10]);
static LEN_13: MessageDesc = ub2(&[13]);
static LEN_16: MessageDesc = ub2(&[16]);

pub fn decode_request(frame: &[u8]) -> Result<Decoded<Request>, DecodeError> {
    let (address, rest) = envelope(frame, 5, 9)?;
    let message = match *rest {
        [0x10, 0x00] => Request::ReferenceRun(request::ReferenceRun),
        [0x20, 0x00, a, b, c, d] => Request::GoToCapacitance(request::GoToCapacitance {
            target: Capacitance(u32le(a, b, c, d)),
        }),
        [0x20, 0x01] => Request::GoToCapacitanceStatus(request::GoToCapacitanceStatus),
        [0x21, 0x00, a, b] => Request::GoToFullStepPosition(request::GoToFullStepPosition {
            target: u16le(a, b),
        }),
        [0x22, 0x00, a, b] => Request::MoveFullSteps(request::MoveFullSteps {
            steps: i16::from_le_bytes([a, b]),
        }),
        [0x80, 0x00, m] => Request::SetModeOfOperation(request::SetModeOfOperation {
            mode: ModeOfOperation::from_raw(m),
        }),
        [0x40, 0x01] => Request::GetActualCapacitance(request::GetActualCapacitance),
        [0x40, 0x80] => Request::GetModeOfOperation(request::GetModeOfOperation),
        [0x40, 0x30, a, b] => Request::GetCCurveIndexedFullStepCapacitance(
            request::GetCCurveIndexedFullStepCapacitance {
                index: index(
                    field!("get_c_curve_indexed_full_step_capacitance", "index"),
                    a,
                    b,
                )?,
            },
        ),
        [0x40, 0x32] => Request::GetControllerTemperature(request::GetControllerTemperature),
        [0x40, 0x61] => Request::GetFirmwareVersion(request::GetFirmwareVersion),
        [0x40, 0x72, index] => match index {
            0x01 => Request::GetLowerCustomerLimit(request::GetLowerCustomerLimit),
            0x02 => Request::GetUpperCustomerLimit(request::GetUpperCustomerLimit),
            found => {
                return Err(DecodeError::InvalidValue {
                    field: field!("get_lower_customer_limit", "index"),
                    offset: 4,
                    expected: 1,
                    found: found.into(),
                })
            }
        },
        [0x20, 0x00, ..] => return Err(wrong_length(&LEN_9, frame)),
        [0x21 | 0x22, 0x00, ..] | [0x40, 0x30, ..] => return Err(wrong_length(&LEN_7, frame)),
        [0x80, 0x00, ..] | [0x40, 0x72, ..] => return Err(wrong_length(&LEN_6, frame)),
        [0x10, 0x00, ..] | [0x20, 0x01, ..] | [0x40, 0x01 | 0x32 | 0x61 | 0x80, ..] => {
            return Err(wrong_length(&LEN_5, frame))
        }
        [hi, lo, ..] => {
            return Err(DecodeError::UnknownCommand {
                offset: 2,
                code: u32::from(u16::from_be_bytes([hi, lo])),
                len: 2,
            })
        }
        _ => return Err(wrong_length(&LEN_5, frame)),
    };
    Ok(Decoded { address, message })
}

/// Whether `r` is a reply `q` may get (within the subset): the replies the command lists, and
/// 0x94, which every command may get (§7.1; the other common NAKs lie outside the subset).
fn answers(q: &Request, r: &Response) -> bool {
    use Request as Q;
    use Response as R;
    matches!(
        (q, r),
        (_, R::NakIndexOutOfRange(response::NakIndexOutOfRange))
            | (
                Q::ReferenceRun(request::ReferenceRun)
                    | Q::GoToCapacitance(_)
                    | Q::GoToFullStepPosition(_)
                    | Q::MoveFullSteps(_),
                R::MovementStarted(response::MovementStarted)
            )
            | (
                Q::GoToCapacitance(_) | Q::GoToFullStepPosition(_) | Q::MoveFullSteps(_),
                R::NakLimitReached(response::NakLimitReached)
            )
            | (
                Q::GoToCapacitanceStatus(request::GoToCapacitanceStatus),
                R::MovementCompleted(response::MovementCompleted)
                    | R::MovementNotCompleted(response::MovementNotCompleted)
            )
            | (
                Q::SetModeOfOperation(_),
                R::SetModeOfOperationAck(response::SetModeOfOperationAck)
            )
            | (
                Q::GetActualCapacitance(request::GetActualCapacitance),
                R::ActualCapacitance(_)
            )
            | (
                Q::GetModeOfOperation(request::GetModeOfOperation),
                R::ActualModeOfOperation(_)
            )
            | (Q::GetCCurveIndexedFullStepCapacitance(_), R::CCurveEntry(_))
            | (
                Q::GetControllerTemperature(request::GetControllerTemperature),
                R::ControllerTemperature(_)
            )
            | (
                Q::GetFirmwareVersion(request::GetFirmwareVersion),
                R::FirmwareVersion(_)
            )
            | (
                Q::GetLowerCustomerLimit(request::GetLowerCustomerLimit),
                R::LowerCustomerLimit(_)
            )
            | (
                Q::GetUpperCustomerLimit(request::GetUpperCustomerLimit),
                R::UpperCustomerLimit(_)
            )
    )
}

/// UB2 responses need no request to be told apart; with `request`, only replies it may get
/// decode ([`DecodeError::NotAReply`] otherwise), as the SD decoder's.
pub fn decode_response(
    frame: &[u8],
    request: Option<&Request>,
) -> Result<Decoded<Response>, DecodeError> {
    let (address, rest) = envelope(frame, 4, 16)?;
    let message = match *rest {
        [0x50] => Response::MovementStarted(response::MovementStarted),
        [0x51] => Response::MovementCompleted(response::MovementCompleted),
        [0x52] => Response::MovementNotCompleted(response::MovementNotCompleted),
        [0x93] => Response::NakLimitReached(response::NakLimitReached),
        [0x94] => Response::NakIndexOutOfRange(response::NakIndexOutOfRange),
        [0x80, 0x00] => Response::SetModeOfOperationAck(response::SetModeOfOperationAck),
        [0x41, 0x01, a, b, c, d] => Response::ActualCapacitance(response::ActualCapacitance {
            capacitance: Capacitance(u32le(a, b, c, d)),
        }),
        [0x41, 0x80, m] => Response::ActualModeOfOperation(response::ActualModeOfOperation {
            mode: ModeOfOperation::from_raw(m),
        }),
        [0x41, 0x30, i0, i1, f0, f1, c0, c1, c2, c3] => {
            Response::CCurveEntry(response::CCurveEntry {
                index: index(field!("c_curve_entry", "index"), i0, i1)?,
                full_steps: u16le(f0, f1),
                capacitance: Capacitance(u32le(c0, c1, c2, c3)),
            })
        }
        [0x41, 0x32, t] => {
            Response::ControllerTemperature(response::ControllerTemperature { temperature: t })
        }
        [0x41, 0x61, ref text @ ..] if text.len() == 11 => {
            let mut firmware_version = [0u8; 11];
            firmware_version.copy_from_slice(text);
            Response::FirmwareVersion(response::FirmwareVersion {
                firmware_version: firmware_version.into(),
            })
        }
        [0x41, 0x72, index, a, b, c, d] => {
            let capacitance = Capacitance(u32le(a, b, c, d));
            match index {
                0x01 => Response::LowerCustomerLimit(response::LowerCustomerLimit { capacitance }),
                0x02 => Response::UpperCustomerLimit(response::UpperCustomerLimit { capacitance }),
                found => {
                    return Err(DecodeError::InvalidValue {
                        field: field!("lower_customer_limit", "index"),
                        offset: 4,
                        expected: 1,
                        found: found.into(),
                    })
                }
            }
        }
        [0x50..=0x52 | 0x93 | 0x94, ..] => return Err(wrong_length(&LEN_4, frame)),
        [0x80, 0x00, ..] => return Err(wrong_length(&LEN_5, frame)),
        [0x41, 0x01, ..] => return Err(wrong_length(&LEN_9, frame)),
        [0x41, 0x80, ..] => return Err(wrong_length(&LEN_6, frame)),
        [0x41, 0x30, ..] => return Err(wrong_length(&LEN_13, frame)),
        [0x41, 0x32, ..] => return Err(wrong_length(&LEN_6, frame)),
        [0x41, 0x61, ..] => return Err(wrong_length(&LEN_16, frame)),
        [0x41, 0x72, ..] => return Err(wrong_length(&LEN_10, frame)),
        [code, ..] => {
            return Err(DecodeError::UnknownResponse {
                offset: 2,
                code: code.into(),
                len: 1,
            })
        }
        [] => return Err(wrong_length(&LEN_4, frame)),
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

/// Refuses an address that is neither a device's nor the host's (once, before the match).
#[inline]
fn check_address(address: u8) -> Result<(), EncodeError> {
    if !(HOST..=LAST_DEVICE).contains(&address) {
        return Err(EncodeError::BadAddress {
            address,
            min: FIRST_DEVICE,
            max: LAST_DEVICE,
        });
    }
    Ok(())
}

/// Writes start, address, code and payload, then the checksum; returns the frame length.
fn put(address: u8, code: &[u8], payload: &[u8], buf: &mut [u8]) -> Result<usize, EncodeError> {
    let len = 3 + code.len() + payload.len();
    let available = buf.len();
    let out = buf.get_mut(..len).ok_or(EncodeError::BufferTooSmall {
        needed: len,
        available,
    })?;
    out[0] = START;
    out[1] = address;
    out[2..2 + code.len()].copy_from_slice(code);
    out[2 + code.len()..len - 1].copy_from_slice(payload);
    out[len - 1] = sum8(&out[..len - 1]);
    Ok(len)
}

/// Refuses a C-curve index beyond the table's last.
#[inline]
fn put_index(index: u16) -> Result<(), EncodeError> {
    if index > LAST_INDEX {
        return Err(EncodeError::NotInRange {
            field: "index",
            value: index.into(),
            min: 0,
            max: LAST_INDEX.into(),
            kind: busspec_runtime::NumKind::Int,
        });
    }
    Ok(())
}

/// Encodes a request of the subset; `None` for any other message.
pub fn encode_request(
    m: &Request,
    address: u8,
    buf: &mut [u8],
) -> Option<Result<usize, EncodeError>> {
    if let Err(e) = check_address(address) {
        return Some(Err(e));
    }
    Some(match *m {
        Request::ReferenceRun(request::ReferenceRun) => put(address, &[0x10, 0x00], &[], buf),
        Request::GoToCapacitance(request::GoToCapacitance { target }) => {
            put(address, &[0x20, 0x00], &target.0.to_le_bytes(), buf)
        }
        Request::GoToCapacitanceStatus(request::GoToCapacitanceStatus) => {
            put(address, &[0x20, 0x01], &[], buf)
        }
        Request::GoToFullStepPosition(request::GoToFullStepPosition { target }) => {
            put(address, &[0x21, 0x00], &target.to_le_bytes(), buf)
        }
        Request::MoveFullSteps(request::MoveFullSteps { steps }) => {
            put(address, &[0x22, 0x00], &steps.to_le_bytes(), buf)
        }
        Request::SetModeOfOperation(request::SetModeOfOperation { mode }) => {
            put(address, &[0x80, 0x00], &[mode.raw()], buf)
        }
        Request::GetActualCapacitance(request::GetActualCapacitance) => {
            put(address, &[0x40, 0x01], &[], buf)
        }
        Request::GetModeOfOperation(request::GetModeOfOperation) => {
            put(address, &[0x40, 0x80], &[], buf)
        }
        Request::GetCCurveIndexedFullStepCapacitance(
            request::GetCCurveIndexedFullStepCapacitance { index },
        ) => put_index(index).and_then(|()| put(address, &[0x40, 0x30], &index.to_le_bytes(), buf)),
        Request::GetControllerTemperature(request::GetControllerTemperature) => {
            put(address, &[0x40, 0x32], &[], buf)
        }
        Request::GetFirmwareVersion(request::GetFirmwareVersion) => {
            put(address, &[0x40, 0x61], &[], buf)
        }
        Request::GetLowerCustomerLimit(request::GetLowerCustomerLimit) => {
            put(address, &[0x40, 0x72], &[0x01], buf)
        }
        Request::GetUpperCustomerLimit(request::GetUpperCustomerLimit) => {
            put(address, &[0x40, 0x72], &[0x02], buf)
        }
        _ => return None,
    })
}

/// Encodes a response of the subset; `None` for any other message.
pub fn encode_response(
    m: &Response,
    address: u8,
    buf: &mut [u8],
) -> Option<Result<usize, EncodeError>> {
    if let Err(e) = check_address(address) {
        return Some(Err(e));
    }
    Some(match *m {
        Response::MovementStarted(response::MovementStarted) => put(address, &[0x50], &[], buf),
        Response::MovementCompleted(response::MovementCompleted) => put(address, &[0x51], &[], buf),
        Response::MovementNotCompleted(response::MovementNotCompleted) => {
            put(address, &[0x52], &[], buf)
        }
        Response::NakLimitReached(response::NakLimitReached) => put(address, &[0x93], &[], buf),
        Response::NakIndexOutOfRange(response::NakIndexOutOfRange) => {
            put(address, &[0x94], &[], buf)
        }
        Response::SetModeOfOperationAck(response::SetModeOfOperationAck) => {
            put(address, &[0x80, 0x00], &[], buf)
        }
        Response::ActualCapacitance(response::ActualCapacitance { capacitance }) => {
            put(address, &[0x41, 0x01], &capacitance.0.to_le_bytes(), buf)
        }
        Response::ActualModeOfOperation(response::ActualModeOfOperation { mode }) => {
            put(address, &[0x41, 0x80], &[mode.raw()], buf)
        }
        Response::CCurveEntry(response::CCurveEntry {
            index,
            full_steps,
            capacitance,
        }) => {
            if let Err(e) = put_index(index) {
                return Some(Err(e));
            }
            let mut p = [0u8; 8];
            p[..2].copy_from_slice(&index.to_le_bytes());
            p[2..4].copy_from_slice(&full_steps.to_le_bytes());
            p[4..].copy_from_slice(&capacitance.0.to_le_bytes());
            put(address, &[0x41, 0x30], &p, buf)
        }
        Response::ControllerTemperature(response::ControllerTemperature { temperature }) => {
            put(address, &[0x41, 0x32], &[temperature], buf)
        }
        Response::FirmwareVersion(response::FirmwareVersion { firmware_version }) => {
            put(address, &[0x41, 0x61], &firmware_version.0, buf)
        }
        Response::LowerCustomerLimit(response::LowerCustomerLimit { capacitance }) => {
            let c = capacitance.0.to_le_bytes();
            put(address, &[0x41, 0x72], &[0x01, c[0], c[1], c[2], c[3]], buf)
        }
        Response::UpperCustomerLimit(response::UpperCustomerLimit { capacitance }) => {
            let c = capacitance.0.to_le_bytes();
            put(address, &[0x41, 0x72], &[0x02, c[0], c[1], c[2], c[3]], buf)
        }
        _ => return None,
    })
}
