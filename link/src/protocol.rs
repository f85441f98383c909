//! What a bus master adds to a protocol beyond its spec: the [`Link`] extension trait.
//!
//! Everything the spec says — names, codes, encoding, decoding, which responses a request may
//! get, each command's kind and broadcast rules, which responses are NAKs, the checksum, the
//! line constants — comes from [`busspec_runtime::Protocol`] and [`busspec_runtime::Message`],
//! which the generated protocol types (`busspec_protocols::ub2::Ub2`, `busspec_protocols::sd::Sd`)
//! implement. [`Link`] holds only what a master decides on top: which commands are safe to send
//! twice, where a reply comes from, which NAK means "try again", the SD freshness counter, the
//! quiet time between requests, and the one place the master reads a NAK differently from the
//! spec ([`Link::nak_approves`]).

use std::time::Duration;

use busspec_protocols::{sd, ub2, CommandKind, Protocol};

/// The quiet time between two requests: the document's gap between frames, or the period of its
/// highest frame rate, whichever is longer.
const fn inter_request_gap(gap_ms: Option<u32>, max_frames_per_s: Option<u32>) -> Duration {
    let gap = match gap_ms {
        Some(g) => g as u64,
        None => 0,
    };
    let period = match max_frames_per_s {
        Some(r) if r > 0 => 1000u64.div_ceil(r as u64),
        _ => 0,
    };
    Duration::from_millis(if gap > period { gap } else { period })
}

/// Whether a command of this kind may be sent again when its reply is lost or garbled, with
/// nothing else known about it: reads, completion checks and setters (sending the same value
/// twice sets it once); never movements (a second trigger restarts or extends the move) or
/// resets (the second reply reports the reset state, not the value before it).
pub fn retry_safe_by_kind(kind: CommandKind) -> bool {
    matches!(
        kind,
        CommandKind::Getter | CommandKind::CompletionCheck | CommandKind::Setter
    )
}

/// One protocol as a bus master sees it: the generated [`Protocol`] plus the master's own rules.
pub trait Link: Protocol {
    /// The quiet time between two requests, from the spec's [`Protocol::INTER_FRAME_GAP_MS`]
    /// and [`Protocol::MAX_FRAMES_PER_S`]: the gap, or the period of the highest frame rate,
    /// whichever is longer (UB2 §2.1 demands 10 ms; SD §1 allows at most 100 frames per second,
    /// i.e. one every 10 ms).
    const INTER_REQUEST_GAP: Duration =
        inter_request_gap(Self::INTER_FRAME_GAP_MS, Self::MAX_FRAMES_PER_S);

    /// Whether sending `r` twice does no more than sending it once, so a lost or garbled reply
    /// may be answered by sending it again. By default what [`retry_safe_by_kind`] says of the
    /// spec's [`Protocol::kind`]; a protocol adds the commands its kind does not tell about:
    /// commands that change how the device is reached, reads that clear what they report,
    /// setters whose effect depends on when they land.
    fn retry_safe(r: &Self::Request) -> bool {
        retry_safe_by_kind(Self::kind(r))
    }

    /// The address the reply to `r`, sent to `address`, comes from.
    fn reply_address(_r: &Self::Request, address: u8) -> u8 {
        address
    }

    /// A reply that says the device saw a corrupted request (UB2 NAK 0x92): a line failure
    /// worth a retry, not the device's answer.
    fn is_checksum_nak(_r: &Self::Response) -> bool {
        false
    }

    /// Whether `response`, which the spec marks `kind: nak` ([`Protocol::is_nak`]), means to
    /// `request` that the command was carried out after all. The one place the master reads a
    /// NAK differently from the spec; `false` unless a protocol says otherwise.
    fn nak_approves(_request: &Self::Request, _response: &Self::Response) -> bool {
        false
    }

    /// Whether `response` refuses `request`: a NAK the spec declares ([`Protocol::is_nak`])
    /// that does not, to this request, approve it ([`Link::nak_approves`]).
    fn is_refusal(request: &Self::Request, response: &Self::Response) -> bool {
        Self::is_nak(response) && !Self::nak_approves(request, response)
    }

    /// How many values the freshness counter takes: the master counts modulo this, from 0
    /// (1 to 256; a whole byte by default).
    const FRESHNESS_MODULUS: u16 = 256;
    /// The freshness counter a request carries, if it carries one (SD set point, §3.1).
    fn freshness_mut(_r: &mut Self::Request) -> Option<&mut u8> {
        None
    }
    /// The request that reads the device's view of the host's freshness counter (SD §3.12).
    fn freshness_readout() -> Option<Self::Request> {
        None
    }
    /// The host's freshness counter as the reply to [`Link::freshness_readout`] carries it (the
    /// master takes it modulo [`Link::FRESHNESS_MODULUS`]).
    fn freshness_from_reply(_r: &Self::Response) -> Option<u8> {
        None
    }
}

impl Link for ub2::Ub2 {
    fn retry_safe(r: &ub2::Request) -> bool {
        match r {
            // The device answers from the old address or at the old rate, then moves on.
            ub2::Request::SetSlaveAddress { .. } | ub2::Request::SetBaudRate { .. } => false,
            // §6.6.1: the RESET flag "will be reset after reading".
            ub2::Request::GetStatus => false,
            _ => retry_safe_by_kind(Self::kind(r)),
        }
    }

    fn is_checksum_nak(r: &ub2::Response) -> bool {
        matches!(r, ub2::Response::NakChecksumError)
    }

    /// §7.2, 0x93 "Limit reached": the spec marks it `kind: nak`, as the document files it, and
    /// to the limit setters (§5.5, §5.6) it is one: the command is ignored (ub2-e23). But to a
    /// movement trigger (§4.2.1, §4.3.1, §4.4.1, §4.7.1, §4.8.1, §4.9.1 and the go-to-limit
    /// commands) the document says "Command approved, Movement started but target position
    /// outside of customer limits, Cap will run till customer limit" (each command's
    /// `response_meanings`): the device moves, so the master takes it as the answer, a movement
    /// clipped to the limit, not as a refusal.
    fn nak_approves(request: &ub2::Request, response: &ub2::Response) -> bool {
        matches!(response, ub2::Response::NakLimitReached)
            && Self::kind(request) == CommandKind::Movement
    }
}

impl Link for sd::Sd {
    fn retry_safe(r: &sd::Request) -> bool {
        match r {
            // After the first one lands the actuator answers to the new ID only.
            sd::Request::SetServoId { .. } => false,
            // Takes the position at the moment it lands: a second one, later, sets another zero.
            sd::Request::SetCurrentPositionAsZero => false,
            _ => retry_safe_by_kind(Self::kind(r)),
        }
    }

    fn reply_address(r: &sd::Request, address: u8) -> u8 {
        match r {
            // The actuator answers with its new ID (sd-e04).
            sd::Request::SetServoId { new_id } => *new_id,
            _ => address,
        }
    }

    /// §3.1: "the 4-bit host data freshness counter" (bits 15..12 of the set point).
    const FRESHNESS_MODULUS: u16 = 16;

    fn freshness_mut(r: &mut sd::Request) -> Option<&mut u8> {
        match r {
            sd::Request::SetPoint { freshness, .. } => Some(freshness),
            _ => None,
        }
    }

    fn freshness_readout() -> Option<sd::Request> {
        Some(sd::Request::ReadSkippedFramesCounter)
    }

    fn freshness_from_reply(r: &sd::Response) -> Option<u8> {
        match r {
            sd::Response::SkippedFramesCounter {
                host_freshness_counter,
                ..
            } => Some(*host_freshness_counter),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use busspec_protocols::sd::Sd;
    use busspec_protocols::ub2::Ub2;
    use busspec_protocols::Broadcast;

    #[test]
    fn policies_come_from_the_specs() {
        let go = ub2::Request::GoToCapacitance {
            target: ub2::Capacitance(15000),
        };
        assert_eq!(Ub2::kind(&go), CommandKind::Movement);
        assert!(!Ub2::retry_safe(&go));
        assert_eq!(
            Ub2::kind(&ub2::Request::GetActualCapacitance),
            CommandKind::Getter
        );
        assert!(Ub2::retry_safe(&ub2::Request::GetActualCapacitance));
        assert!(!Ub2::retry_safe(&ub2::Request::GetStatus));
        let sp = sd::Request::SetPoint {
            freshness: 0,
            position: sd::Angle(0),
        };
        assert_eq!(Sd::kind(&sp), CommandKind::Movement);
        assert_eq!(
            Sd::broadcast(&sp),
            Broadcast {
                accepted: true,
                answered: false
            }
        );
        assert!(Sd::broadcast(&sd::Request::ReadActualPosition).answered);
        assert!(!Sd::retry_safe(&sd::Request::ResetStallEventCounter));
        assert_eq!(Ub2::INTER_REQUEST_GAP, Duration::from_millis(10));
        assert_eq!(Sd::INTER_REQUEST_GAP, Duration::from_millis(10));
    }

    /// Every response the spec marks `kind: nak` is a refusal to every request that may get
    /// it, except UB2's 0x93 to a movement trigger, which approves it (§7.2, see
    /// `Link::nak_approves` for Ub2); SD has no NAK.
    #[test]
    fn naks_are_the_specs_but_limit_reached_approves_a_movement() {
        use ub2::{Request as Q, Response as R};
        let naks = [
            R::NakUnknownCommand,
            R::NakIncompatibleStatus,
            R::NakChecksumError,
            R::NakLimitReached,
            R::NakIndexOutOfRange,
        ];
        assert!(naks.iter().all(Ub2::is_nak));
        assert_eq!(naks[3].code(), &[0x93]);
        let movement = Q::GoToCapacitance {
            target: ub2::Capacitance(15000),
        };
        let limit = Q::SetLowerCustomerLimit {
            limit: ub2::Capacitance(1),
        };
        assert_eq!(Ub2::kind(&limit), CommandKind::Setter);
        // The spec lets both get 0x93.
        assert!(Ub2::answers(&movement, &R::NakLimitReached));
        assert!(Ub2::answers(&limit, &R::NakLimitReached));
        // To the movement it is the answer (the cap runs to the limit), to the setter a refusal.
        assert!(Ub2::nak_approves(&movement, &R::NakLimitReached));
        assert!(!Ub2::is_refusal(&movement, &R::NakLimitReached));
        assert!(!Ub2::nak_approves(&limit, &R::NakLimitReached));
        assert!(Ub2::is_refusal(&limit, &R::NakLimitReached));
        // Every other NAK refuses a movement too; an answer refuses nothing.
        for nak in naks.iter().filter(|r| **r != R::NakLimitReached) {
            assert!(Ub2::is_refusal(&movement, nak), "{nak:?}");
            assert!(Ub2::is_refusal(&limit, nak), "{nak:?}");
        }
        assert!(!Ub2::is_refusal(&movement, &R::MovementStarted));
        assert!(!Ub2::is_nak(&R::MovementStarted));
        // The only checksum NAK is 0x92.
        assert!(naks
            .iter()
            .all(|r| Ub2::is_checksum_nak(r) == (*r == R::NakChecksumError)));
    }
}
