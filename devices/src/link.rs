//! The master's rules for UB2 and SD: [`Link`] for [`crate::Ub2`] and [`crate::Sd`].
//!
//! Everything the spec says comes from the codec's [`busspec_runtime::Protocol`], the commands
//! unsafe to retry included (each spec's `transactions.retry`: UB2's new address or baud rate and the status
//! read that clears its RESET flag; SD's new ID and new zero); these impls hold only what a
//! master decides on top (see [`Link`]): UB2's checksum NAK 0x92, its 0x93 to a movement read
//! as the answer, and its byte-order probe (the factory limits, erratum ub2-e01); SD's reply
//! from the new ID, and its 4-bit freshness counter.

#[cfg(any(feature = "ub2", feature = "sd"))]
use busspec_link_core::link::Link;
#[cfg(feature = "ub2")]
use busspec_link_core::link::{text, ByteOrderCheck};
#[cfg(feature = "ub2")]
use busspec_runtime::CommandKind;

#[cfg(feature = "ub2")]
use busspec_protocols::ub2;

#[cfg(feature = "ub2")]
/// What the master takes as a plausible UB2 capacitance, in 0.01 pF: 0.01 pF to 10,000.00 pF.
/// The spec gives a capacitance no range of its own (a `u32` of 0.01 pF, §3.1); the document's
/// examples run from 30.00 pF to 800 pF. A value in this range read one way
/// reads, byte-swapped, as more than 10,000.00 pF unless its lowest byte is 0 and its second
/// below 0x10, so a pair of limits rarely fits both ways.
pub const UB2_PLAUSIBLE_CAPACITANCE: core::ops::RangeInclusive<u32> = 1..=1_000_000;

#[cfg(feature = "ub2")]
fn ub2_limits_fit(lower: u32, upper: u32) -> bool {
    UB2_PLAUSIBLE_CAPACITANCE.contains(&lower)
        && UB2_PLAUSIBLE_CAPACITANCE.contains(&upper)
        && lower < upper
}

#[cfg(feature = "ub2")]
/// A capacitance in 0.01 pF, as `123.45`.
struct Pf(u32);

#[cfg(feature = "ub2")]
impl core::fmt::Display for Pf {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}.{:02}", self.0 / 100, self.0 % 100)
    }
}

#[cfg(feature = "ub2")]
impl Link for crate::Ub2 {
    fn is_checksum_nak(r: &ub2::Response) -> bool {
        matches!(
            r,
            ub2::Response::NakChecksumError(ub2::response::NakChecksumError)
        )
    }

    /// §7.2, 0x93 "Limit reached": the spec marks it `kind: nak`, as the document files it, and
    /// to the limit setters (§5.5, §5.6) it is one: the command is ignored (ub2-e23). But to a
    /// movement trigger (§4.2.1, §4.3.1, §4.4.1, §4.7.1, §4.8.1, §4.9.1 and the go-to-limit
    /// commands) the document says "Command approved, Movement started but target position
    /// outside of customer limits, Cap will run till customer limit" (each command's
    /// `response_meanings`): the device moves, so the master takes it as the answer, a movement
    /// clipped to the limit, not as a refusal.
    fn nak_approves(request: &ub2::Request, response: &ub2::Response) -> bool {
        matches!(
            response,
            ub2::Response::NakLimitReached(ub2::response::NakLimitReached)
        ) && request.command().kind == CommandKind::Movement
    }

    /// The factory limits (§6.16, §6.17): every capacitor has them, they travel as `u32` of
    /// 0.01 pF, each must be a plausible capacitance ([`UB2_PLAUSIBLE_CAPACITANCE`]) and the
    /// lower must lie below the upper. The 8-bit sum cannot tell the byte orders apart
    /// (ub2-e01); these readings can.
    fn byte_order_probe() -> &'static [ub2::Request] {
        &[
            ub2::Request::GetLowerFactoryLimit(ub2::request::GetLowerFactoryLimit),
            ub2::Request::GetUpperFactoryLimit(ub2::request::GetUpperFactoryLimit),
        ]
    }

    fn byte_order_check(replies: &[ub2::Response]) -> Option<ByteOrderCheck> {
        let [ub2::Response::LowerFactoryLimit(ub2::response::LowerFactoryLimit {
            capacitance: lower,
            ..
        }), ub2::Response::UpperFactoryLimit(ub2::response::UpperFactoryLimit {
            capacitance: upper,
            ..
        })] = replies
        else {
            return None;
        };
        let (lo, hi) = (lower.raw(), upper.raw());
        let (slo, shi) = (lo.swap_bytes(), hi.swap_bytes());
        Some(ByteOrderCheck {
            read: text(format_args!("factory limits {}..={} pF", Pf(lo), Pf(hi))),
            swapped: text(format_args!("factory limits {}..={} pF", Pf(slo), Pf(shi))),
            rule: text(format_args!(
                "each inside {}..={} pF, lower below upper",
                Pf(*UB2_PLAUSIBLE_CAPACITANCE.start()),
                Pf(*UB2_PLAUSIBLE_CAPACITANCE.end())
            )),
            declared_fits: ub2_limits_fit(lo, hi),
            swapped_fits: ub2_limits_fit(slo, shi),
            erratum: "ub2-e01",
        })
    }

    /// A reset, and a new slave address (§5.3): the device answers elsewhere from then on.
    fn forgets_byte_order_checks(r: &ub2::Request) -> bool {
        matches!(r, ub2::Request::SetSlaveAddress(_)) || r.command().kind == CommandKind::Reset
    }
}

#[cfg(feature = "sd")]
use busspec_protocols::sd;

#[cfg(feature = "sd")]
impl Link for crate::Sd {
    fn reply_address(r: &sd::Request, address: u8) -> u8 {
        match r {
            // The actuator answers with its new ID (sd-e04).
            sd::Request::SetServoId(sd::request::SetServoId { new_id }) => *new_id,
            _ => address,
        }
    }

    /// §3.1: "the 4-bit host data freshness counter" (bits 15..12 of the set point).
    const FRESHNESS_MODULUS: u16 = 16;

    fn freshness_mut(r: &mut sd::Request) -> Option<&mut u8> {
        match r {
            sd::Request::SetPoint(sd::request::SetPoint { freshness, .. }) => Some(freshness),
            _ => None,
        }
    }

    fn freshness_readout() -> Option<sd::Request> {
        Some(sd::Request::ReadSkippedFramesCounter(
            sd::request::ReadSkippedFramesCounter,
        ))
    }

    fn freshness_from_reply(r: &sd::Response) -> Option<u8> {
        match r {
            sd::Response::SkippedFramesCounter(sd::response::SkippedFramesCounter {
                host_freshness_counter,
                ..
            }) => Some(*host_freshness_counter),
            _ => None,
        }
    }
}

#[cfg(all(test, feature = "ub2", feature = "sd"))]
mod tests {
    use super::*;
    use crate::{Sd, Ub2};
    use busspec_runtime::{Broadcast, ResponseMessage};
    use core::time::Duration;

    #[test]
    fn policies_come_from_the_specs() {
        let go = ub2::Request::GoToCapacitance(ub2::request::GoToCapacitance {
            target: ub2::Capacitance(15000),
        });
        assert_eq!(go.command().kind, CommandKind::Movement);
        assert!(!Ub2::retry_safe(&go));
        assert_eq!(
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
                .command()
                .kind,
            CommandKind::Getter
        );
        assert!(Ub2::retry_safe(&ub2::Request::GetActualCapacitance(
            ub2::request::GetActualCapacitance
        )));
        assert!(!Ub2::retry_safe(&ub2::Request::GetStatus(
            ub2::request::GetStatus
        )));
        let sp = sd::Request::SetPoint(sd::request::SetPoint {
            freshness: 0,
            position: sd::Angle(0),
        });
        assert_eq!(sp.command().kind, CommandKind::Movement);
        assert_eq!(
            sp.command().broadcast,
            Broadcast {
                accepted: true,
                answered: false
            }
        );
        assert!(
            sd::Request::ReadActualPosition(sd::request::ReadActualPosition)
                .command()
                .broadcast
                .answered
        );
        assert!(!Sd::retry_safe(&sd::Request::ResetStallEventCounter(
            sd::request::ResetStallEventCounter
        )));
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
            R::NakUnknownCommand(ub2::response::NakUnknownCommand),
            R::NakIncompatibleStatus(ub2::response::NakIncompatibleStatus),
            R::NakChecksumError(ub2::response::NakChecksumError),
            R::NakLimitReached(ub2::response::NakLimitReached),
            R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange),
        ];
        assert!(naks.iter().all(|r| r.is_nak()));
        assert_eq!(naks[3].code(), &[0x93]);
        let movement = Q::GoToCapacitance(ub2::request::GoToCapacitance {
            target: ub2::Capacitance(15000),
        });
        let limit = Q::SetLowerCustomerLimit(ub2::request::SetLowerCustomerLimit {
            limit: ub2::Capacitance(1),
        });
        assert_eq!(limit.command().kind, CommandKind::Setter);
        // The spec lets both get 0x93.
        assert!(R::NakLimitReached(ub2::response::NakLimitReached).answers(&movement));
        assert!(R::NakLimitReached(ub2::response::NakLimitReached).answers(&limit));
        // To the movement it is the answer (the cap runs to the limit), to the setter a refusal.
        assert!(Ub2::nak_approves(
            &movement,
            &R::NakLimitReached(ub2::response::NakLimitReached)
        ));
        assert!(!Ub2::is_refusal(
            &movement,
            &R::NakLimitReached(ub2::response::NakLimitReached)
        ));
        assert!(!Ub2::nak_approves(
            &limit,
            &R::NakLimitReached(ub2::response::NakLimitReached)
        ));
        assert!(Ub2::is_refusal(
            &limit,
            &R::NakLimitReached(ub2::response::NakLimitReached)
        ));
        // Every other NAK refuses a movement too; an answer refuses nothing.
        for nak in naks
            .iter()
            .filter(|r| **r != R::NakLimitReached(ub2::response::NakLimitReached))
        {
            assert!(Ub2::is_refusal(&movement, nak), "{nak:?}");
            assert!(Ub2::is_refusal(&limit, nak), "{nak:?}");
        }
        assert!(!Ub2::is_refusal(
            &movement,
            &R::MovementStarted(ub2::response::MovementStarted)
        ));
        assert!(!R::MovementStarted(ub2::response::MovementStarted).is_nak());
        // The only checksum NAK is 0x92.
        assert!(naks.iter().all(|r| Ub2::is_checksum_nak(r)
            == (*r == R::NakChecksumError(ub2::response::NakChecksumError))));
    }
}
