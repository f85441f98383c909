//! The movements of UB2 and SD, as sequences of transactions any driver of the master runs
//! ([`Movement`]): [`Ub2Movement`] triggers a UB2 movement and polls its completion check
//! (§4.x.2), reading the position in between; [`SdMove`] sends an SD set point and reads the
//! actual position until it equals the target.

#[cfg(any(feature = "ub2", feature = "sd"))]
use core::time::Duration;

#[cfg(any(feature = "ub2", feature = "sd"))]
use busspec_link_core::movement::{MoveError, MoveReport, Movement, Moving, Step};
#[cfg(feature = "ub2")]
use busspec_link_core::Link;
#[cfg(feature = "ub2")]
use busspec_runtime::{CommandKind, Protocol};

#[cfg(feature = "sd")]
use crate::Sd;
#[cfg(feature = "ub2")]
use crate::Ub2;
#[cfg(feature = "sd")]
use busspec_protocols::sd;
#[cfg(feature = "ub2")]
use busspec_protocols::ub2;

#[cfg(feature = "ub2")]
/// The completion check that goes with a UB2 movement trigger: same first code byte, second
/// byte 0x01 (§4.x.2). Built as a frame and decoded, so it is whatever the spec says it is.
pub fn ub2_completion_check(trigger: &ub2::Request) -> Option<ub2::Request> {
    let code = trigger.code();
    if code.len() != 2 || code[1] != 0x00 {
        return None;
    }
    let address = *Ub2::BUS.device_addresses.start();
    let mut frame = [0xAA, address, code[0], 0x01, 0];
    frame[4] = ub2::checksum(&frame[..4]);
    match Ub2::decode_request(&frame) {
        Ok(d) if d.message.command().kind == CommandKind::CompletionCheck => Some(d.message),
        _ => None,
    }
}

#[cfg(feature = "ub2")]
#[derive(Debug, Clone, Copy, PartialEq)]
enum Ub2Phase {
    Trigger,
    Check,
    Position { elapsed: Duration },
}

#[cfg(feature = "ub2")]
/// A UB2 movement: the trigger, then the completion check every `poll_every`, reading the
/// full-step position while it is not done, until done or `limit` has passed.
#[derive(Debug, Clone)]
pub struct Ub2Movement {
    trigger: ub2::Request,
    check: Option<ub2::Request>,
    poll_every: Duration,
    limit: Duration,
    start: Duration,
    started: Option<ub2::Response>,
    clipped: bool,
    polls: u32,
    phase: Ub2Phase,
}

#[cfg(feature = "ub2")]
impl Ub2Movement {
    pub fn new(trigger: ub2::Request, poll_every: Duration, limit: Duration) -> Self {
        Ub2Movement {
            trigger,
            check: ub2_completion_check(&trigger),
            poll_every,
            limit,
            start: Duration::ZERO,
            started: None,
            clipped: false,
            polls: 0,
            phase: Ub2Phase::Trigger,
        }
    }

    fn refused(request: ub2::Request, response: ub2::Response, detail: &'static str) -> Step<Ub2> {
        Step::Failed(MoveError::Refused {
            request,
            response,
            detail,
        })
    }

    fn ask(request: ub2::Request) -> Step<Ub2> {
        Step::Ask {
            request,
            optional: false,
        }
    }
}

#[cfg(feature = "ub2")]
impl Movement<Ub2> for Ub2Movement {
    fn trigger(&self) -> Result<ub2::Request, MoveError<Ub2>> {
        match self.check {
            Some(_) => Ok(self.trigger),
            None => Err(MoveError::NotATrigger {
                request: self.trigger,
            }),
        }
    }

    fn next(&mut self, now: Duration) -> Step<Ub2> {
        let Some(check) = self.check else {
            return Step::Failed(MoveError::NotATrigger {
                request: self.trigger,
            });
        };
        match self.phase {
            Ub2Phase::Trigger => {
                self.start = now;
                Step::Ask {
                    request: self.trigger,
                    optional: false,
                }
            }
            _ => {
                self.phase = Ub2Phase::Check;
                Self::ask(check)
            }
        }
    }

    fn answered(&mut self, now: Duration, response: Option<ub2::Response>) -> Step<Ub2> {
        let Some(check) = self.check else {
            return self.next(now);
        };
        match (self.phase, response) {
            (Ub2Phase::Trigger, Some(r)) => {
                self.clipped = match r {
                    ub2::Response::MovementStarted(ub2::response::MovementStarted) => false,
                    // 0x93: approved, the cap runs to the customer limit (§7.2).
                    r if Ub2::nak_approves(&self.trigger, &r) => true,
                    other => {
                        return Self::refused(self.trigger, other, "the movement did not start")
                    }
                };
                self.started = Some(r);
                self.phase = Ub2Phase::Check;
                Self::ask(check)
            }
            (Ub2Phase::Check, Some(reply)) => {
                self.polls += 1;
                let elapsed = now.saturating_sub(self.start);
                let lost = match reply {
                    ub2::Response::MovementCompleted(ub2::response::MovementCompleted) => None,
                    ub2::Response::MovementCompletedWithStepLoss(
                        ub2::response::MovementCompletedWithStepLoss { lost_micro_steps },
                    ) => Some(lost_micro_steps),
                    ub2::Response::MovementNotCompleted(ub2::response::MovementNotCompleted) => {
                        if elapsed >= self.limit {
                            return Step::Failed(MoveError::Timeout {
                                request: self.trigger,
                                waited: elapsed,
                            });
                        }
                        self.phase = Ub2Phase::Position { elapsed };
                        return Step::Ask {
                            request: ub2::Request::GetActualFullStepPosition(
                                ub2::request::GetActualFullStepPosition,
                            ),
                            optional: true,
                        };
                    }
                    other => {
                        return Self::refused(
                            check,
                            other,
                            "while waiting for the movement to complete",
                        )
                    }
                };
                Step::Done(MoveReport {
                    started: self.started.unwrap_or(ub2::Response::MovementStarted(
                        ub2::response::MovementStarted,
                    )),
                    finished: Some(reply),
                    clipped: self.clipped,
                    lost_micro_steps: lost,
                    polls: self.polls,
                    elapsed,
                })
            }
            (Ub2Phase::Position { elapsed }, r) => {
                let progress = match r {
                    Some(ub2::Response::ActualFullStepPosition(
                        ub2::response::ActualFullStepPosition { full_steps },
                    )) => Some(Moving {
                        elapsed,
                        position: f64::from(full_steps),
                    }),
                    _ => None,
                };
                Step::Sleep {
                    until: now + self.poll_every,
                    progress,
                }
            }
            // Only the position read is optional: a driver hands back `None` for nothing else.
            (_, None) => self.next(now),
        }
    }
}

#[cfg(feature = "sd")]
/// An SD move: a set point to `target`, then the actual position every `poll_every` until it
/// equals the target or `limit` has passed.
#[derive(Debug, Clone)]
pub struct SdMove {
    target: sd::Angle,
    poll_every: Duration,
    limit: Duration,
    start: Duration,
    started: Option<sd::Response>,
    polls: u32,
}

#[cfg(feature = "sd")]
impl SdMove {
    pub fn new(target: sd::Angle, poll_every: Duration, limit: Duration) -> Self {
        SdMove {
            target,
            poll_every,
            limit,
            start: Duration::ZERO,
            started: None,
            polls: 0,
        }
    }

    fn set_point(&self) -> sd::Request {
        sd::Request::SetPoint(sd::request::SetPoint {
            freshness: 0,
            position: self.target,
        })
    }
}

#[cfg(feature = "sd")]
impl Movement<Sd> for SdMove {
    fn trigger(&self) -> Result<sd::Request, MoveError<Sd>> {
        Ok(self.set_point())
    }

    fn next(&mut self, now: Duration) -> Step<Sd> {
        if self.started.is_none() {
            self.start = now;
            return Step::Ask {
                request: self.set_point(),
                optional: false,
            };
        }
        Step::Ask {
            request: sd::Request::ReadActualPosition(sd::request::ReadActualPosition),
            optional: false,
        }
    }

    fn answered(&mut self, now: Duration, response: Option<sd::Response>) -> Step<Sd> {
        let Some(reply) = response else {
            return self.next(now);
        };
        let Some(started) = self.started else {
            self.started = Some(reply);
            return self.next(now);
        };
        self.polls += 1;
        let elapsed = now.saturating_sub(self.start);
        let sd::Response::ActualPosition(sd::response::ActualPosition { position }) = reply else {
            return Step::Failed(MoveError::Refused {
                request: sd::Request::ReadActualPosition(sd::request::ReadActualPosition),
                response: reply,
                detail: "expected the actual position",
            });
        };
        if position == self.target {
            return Step::Done(MoveReport {
                started,
                finished: Some(reply),
                clipped: false,
                lost_micro_steps: None,
                polls: self.polls,
                elapsed,
            });
        }
        if elapsed >= self.limit {
            return Step::Failed(MoveError::Timeout {
                request: self.set_point(),
                waited: elapsed,
            });
        }
        Step::Sleep {
            until: now + self.poll_every,
            progress: Some(Moving {
                elapsed,
                position: position.value(),
            }),
        }
    }
}
