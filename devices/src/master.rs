//! The long operations of UB2 and SD on `busspec-link`'s blocking [`Master`], as extension
//! traits (bring [`Ub2Master`] or [`SdMaster`] into scope): UB2 movements and the C-curve table
//! (§6.7), SD moves and the four string readouts (§3.20-§3.23). Each is a sequence of
//! [`Master::ask`] transactions or a [`Movement`](busspec_link_core::movement::Movement) run
//! by [`Master::run_to_end`]: the master's rules stay the generic master's.

use std::time::Duration;

use busspec_link::clock::Clock;
use busspec_link::master::{LinkError, Master, MoveReport, Progress};
use busspec_link::transport::Transport;
#[cfg(feature = "ub2")]
use busspec_runtime::Protocol;

#[cfg(feature = "sd")]
use crate::movement::SdMove;
#[cfg(feature = "ub2")]
use crate::movement::Ub2Movement;
#[cfg(feature = "sd")]
use crate::Sd;
#[cfg(feature = "ub2")]
use crate::Ub2;
#[cfg(feature = "sd")]
use busspec_protocols::sd;
#[cfg(feature = "ub2")]
use busspec_protocols::ub2;

#[cfg(feature = "ub2")]
/// One row of the UB2 C-curve table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CCurvePoint {
    pub index: u16,
    pub full_steps: u16,
    pub capacitance: ub2::Capacitance,
}

/// The UB2 operations of a [`Master`]: a movement polled to completion, the C-curve table.
#[cfg(feature = "ub2")]
pub trait Ub2Master {
    /// Triggers a movement and polls its completion check every `poll_every` until it is done,
    /// reporting the full-step position in between. Fails if the device refuses the trigger,
    /// says the movement was not triggered, or is not done within `limit`.
    fn run_movement(
        &mut self,
        address: u8,
        trigger: ub2::Request,
        poll_every: Duration,
        limit: Duration,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<MoveReport<ub2::Response>, LinkError>;

    /// Reads the whole C-curve table (§6.7): entries from index 0 until the device answers
    /// "index out of range" (0x94), at most 500.
    fn read_c_curve(
        &mut self,
        address: u8,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Vec<CCurvePoint>, LinkError>;
}

#[cfg(feature = "ub2")]
impl<T: Transport, C: Clock> Ub2Master for Master<Ub2, T, C> {
    fn run_movement(
        &mut self,
        address: u8,
        trigger: ub2::Request,
        poll_every: Duration,
        limit: Duration,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<MoveReport<ub2::Response>, LinkError> {
        self.run_to_end(
            address,
            Ub2Movement::new(trigger, poll_every, limit),
            progress,
        )
    }

    fn read_c_curve(
        &mut self,
        address: u8,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Vec<CCurvePoint>, LinkError> {
        const MAX_ENTRIES: u16 = 500;
        let mut table = Vec::new();
        for index in 0..MAX_ENTRIES {
            let request = ub2::Request::GetCCurveIndexedFullStepCapacitance(
                ub2::request::GetCCurveIndexedFullStepCapacitance { index },
            );
            match self.ask(address, request)? {
                ub2::Response::CCurveEntry(ub2::response::CCurveEntry {
                    index: got,
                    full_steps,
                    capacitance,
                }) if got == index => table.push(CCurvePoint {
                    index,
                    full_steps,
                    capacitance,
                }),
                ub2::Response::CCurveEntry(ub2::response::CCurveEntry { index: got, .. }) => {
                    return Err(LinkError::BadReply {
                        protocol: Ub2::NAME,
                        request: request.name(),
                        address,
                        attempts: 1,
                        reason: format!("entry {got} came back for index {index}"),
                        bytes: Vec::new(),
                    })
                }
                ub2::Response::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange) => break,
                other => {
                    return Err(LinkError::refused::<Ub2>(
                        &request,
                        address,
                        &other,
                        "reading the C-curve table",
                    ))
                }
            }
            progress(Progress::Read { done: table.len() });
        }
        Ok(table)
    }
}

#[cfg(feature = "sd")]
/// The four SD string readouts (§3.20-§3.23).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdString {
    SerialNumber,
    ProductDescription,
    SoftwareRevision,
    HardwareRevision,
}

#[cfg(feature = "sd")]
impl SdString {
    pub const ALL: [SdString; 4] = [
        SdString::SerialNumber,
        SdString::ProductDescription,
        SdString::SoftwareRevision,
        SdString::HardwareRevision,
    ];

    /// The request for byte `byte_number` of this string.
    pub fn request(self, byte_number: u8) -> sd::Request {
        match self {
            SdString::SerialNumber => {
                sd::Request::ReadElectronicSerialNumber(sd::request::ReadElectronicSerialNumber {
                    byte_number,
                })
            }
            SdString::ProductDescription => {
                sd::Request::ReadProductDescription(sd::request::ReadProductDescription {
                    byte_number,
                })
            }
            SdString::SoftwareRevision => {
                sd::Request::ReadSoftwareRevision(sd::request::ReadSoftwareRevision { byte_number })
            }
            SdString::HardwareRevision => {
                sd::Request::ReadHardwareRevision(sd::request::ReadHardwareRevision { byte_number })
            }
        }
    }

    /// The character and the string length a reply carries.
    pub fn character(response: &sd::Response) -> Option<(u8, u8)> {
        match *response {
            sd::Response::ElectronicSerialNumberCharacter(
                sd::response::ElectronicSerialNumberCharacter {
                    character,
                    string_length,
                },
            )
            | sd::Response::ProductDescriptionCharacter(
                sd::response::ProductDescriptionCharacter {
                    character,
                    string_length,
                },
            )
            | sd::Response::SoftwareRevisionCharacter(sd::response::SoftwareRevisionCharacter {
                character,
                string_length,
            })
            | sd::Response::HardwareRevisionCharacter(sd::response::HardwareRevisionCharacter {
                character,
                string_length,
            }) => Some((character, string_length)),
            _ => None,
        }
    }

    /// The readout this request belongs to.
    pub fn of(request: &sd::Request) -> Option<SdString> {
        SdString::ALL
            .into_iter()
            .find(|s| s.request(0).name() == request.name())
    }
}

/// The SD operations of a [`Master`]: the string readouts, a move polled to its target.
#[cfg(feature = "sd")]
pub trait SdMaster {
    /// Reads a whole string, one character per transaction: byte 0 gives the length, then the
    /// rest. Every reply must agree on the length.
    fn read_string(
        &mut self,
        address: u8,
        which: SdString,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Vec<u8>, LinkError>;

    /// Sends a set point and polls the actual position every `poll_every` until it equals the
    /// target, or `limit` passes.
    fn move_to(
        &mut self,
        address: u8,
        target: sd::Angle,
        poll_every: Duration,
        limit: Duration,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<MoveReport<sd::Response>, LinkError>;
}

#[cfg(feature = "sd")]
impl<T: Transport, C: Clock> SdMaster for Master<Sd, T, C> {
    fn read_string(
        &mut self,
        address: u8,
        which: SdString,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Vec<u8>, LinkError> {
        let mut text = Vec::new();
        let mut length = None;
        let mut byte = 0u8;
        while length.map_or(true, |n| usize::from(byte) < usize::from(n)) && byte < 0x20 {
            let request = which.request(byte);
            let response = self.ask(address, request)?;
            let Some((c, n)) = SdString::character(&response) else {
                return Err(LinkError::refused::<Sd>(
                    &request,
                    address,
                    &response,
                    "expected a string character",
                ));
            };
            if n > 0x20 {
                return Err(LinkError::refused::<Sd>(
                    &request,
                    address,
                    &response,
                    &format!("string length {n} exceeds 32"),
                ));
            }
            match length {
                None => length = Some(n),
                Some(l) if l != n => {
                    return Err(LinkError::refused::<Sd>(
                        &request,
                        address,
                        &response,
                        &format!("string length changed from {l} to {n} while reading"),
                    ))
                }
                Some(_) => {}
            }
            if n == 0 {
                break;
            }
            text.push(c);
            byte += 1;
            progress(Progress::Read { done: text.len() });
        }
        Ok(text)
    }

    fn move_to(
        &mut self,
        address: u8,
        target: sd::Angle,
        poll_every: Duration,
        limit: Duration,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<MoveReport<sd::Response>, LinkError> {
        self.run_to_end(address, SdMove::new(target, poll_every, limit), progress)
    }
}
