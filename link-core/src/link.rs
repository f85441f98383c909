//! What a bus master adds to a protocol beyond its spec: the [`Link`] extension trait.
//!
//! Everything the spec says — names, codes, encoding, decoding, which responses a request may
//! get, each command's kind and broadcast rules, which responses are NAKs, the checksum, the
//! line constants — comes from [`busspec_runtime::Protocol`] and [`busspec_runtime::Message`],
//! which the generated protocol types (`busspec_protocols::ub2::Ub2`, `busspec_protocols::sd::Sd`)
//! implement. [`Link`] holds only what a master decides on top: which commands are safe to send
//! twice, where a reply comes from, which NAK means "try again", the SD freshness counter, the
//! quiet time between requests, and the one place the master reads a NAK differently from the
//! spec ([`Link::nak_approves`]), and the readings that tell whether a device sends its numbers
//! in the byte order the spec declares ([`Link::byte_order_probe`]).

use core::fmt::Write;
use core::time::Duration;

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

/// What a byte-order probe read ([`Link::byte_order_probe`]), judged both ways: as the spec
/// declares the numbers travel, and byte-swapped.
///
/// The texts are fixed-capacity strings ([`Text`]), so the check allocates nothing and fits a
/// `no_std` master.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ByteOrderCheck {
    /// What was read, in the declared byte order (`factory limits 50.00..=500.00 pF`).
    pub read: Text,
    /// The same bytes read the other way round.
    pub swapped: Text,
    /// What a plausible reading is (`inside 0.01..=10000.00 pF, lower below upper`).
    pub rule: Text,
    /// The reading is plausible in the declared byte order.
    pub declared_fits: bool,
    /// The reading is plausible byte-swapped.
    pub swapped_fits: bool,
    /// The erratum of the spec that records the doubt about the byte order (`ub2-e01`).
    pub erratum: &'static str,
}

/// A short text of at most 96 bytes (longer text is cut at the last character that fits).
pub type Text = heapless::String<96>;

/// Formats `args` into a [`Text`], cut where it is full.
pub fn text(args: core::fmt::Arguments<'_>) -> Text {
    struct Cut(Text);
    impl Write for Cut {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            for c in s.chars() {
                if self.0.push(c).is_err() {
                    break;
                }
            }
            Ok(())
        }
    }
    let mut t = Cut(Text::new());
    let _ = t.write_fmt(args);
    t.0
}

/// The spec's `byte_order:` line: its line number (from 1) and its text without the comment
/// (`byte_order: little`), if the spec has one at the top level.
pub fn spec_byte_order_line<P: Protocol>() -> Option<(usize, &'static str)> {
    P::SPEC_YAML.lines().enumerate().find_map(|(i, line)| {
        line.starts_with("byte_order:")
            .then(|| (i + 1, line.split('#').next().unwrap_or(line).trim_end()))
    })
}

/// The byte order the spec declares, as a word (`little-endian`), from its `byte_order:` line.
pub fn declared_byte_order<P: Protocol>() -> &'static str {
    match spec_byte_order_line::<P>().map(|(_, l)| l.trim_start_matches("byte_order:").trim()) {
        Some("big") => "big-endian",
        Some("little") => "little-endian",
        _ => "in the declared byte order",
    }
}

/// The other byte order than the declared one, as a word.
pub fn swapped_byte_order<P: Protocol>() -> &'static str {
    match declared_byte_order::<P>() {
        "big-endian" => "little-endian",
        "little-endian" => "big-endian (most significant byte first)",
        _ => "byte-swapped",
    }
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

    /// Requests whose replies carry multi-byte numbers with a range the master knows, read
    /// before the first movement to an address to make sure the device sends its numbers in
    /// the byte order the spec declares: a device that reads the target the other way round
    /// runs somewhere else entirely. None by default: no check.
    fn byte_order_probe() -> &'static [Self::Request] {
        &[]
    }

    /// The replies to [`Link::byte_order_probe`], in its order, judged both ways; `None` if
    /// they are not the replies the probe expects (a NAK, another reply).
    fn byte_order_check(_replies: &[Self::Response]) -> Option<ByteOrderCheck> {
        None
    }

    /// Whether sending `r` makes the master forget which addresses passed the byte-order check:
    /// a reset, or a command that moves a device to another address (another device may then
    /// answer where a checked one did). A reset by default.
    fn forgets_byte_order_checks(r: &Self::Request) -> bool {
        Self::kind(r) == CommandKind::Reset
    }
}

/// What the master takes as a plausible UB2 capacitance, in 0.01 pF: 0.01 pF to 10,000.00 pF.
/// The spec gives a capacitance no range of its own (a `u32` of 0.01 pF, §3.1); the document's
/// examples run from 30.00 pF to 800 pF. A value in this range read one way
/// reads, byte-swapped, as more than 10,000.00 pF unless its lowest byte is 0 and its second
/// below 0x10, so a pair of limits rarely fits both ways.
pub const UB2_PLAUSIBLE_CAPACITANCE: core::ops::RangeInclusive<u32> = 1..=1_000_000;

fn ub2_limits_fit(lower: u32, upper: u32) -> bool {
    UB2_PLAUSIBLE_CAPACITANCE.contains(&lower)
        && UB2_PLAUSIBLE_CAPACITANCE.contains(&upper)
        && lower < upper
}

/// A capacitance in 0.01 pF, as `123.45`.
struct Pf(u32);

impl core::fmt::Display for Pf {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}.{:02}", self.0 / 100, self.0 % 100)
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

    /// The factory limits (§6.16, §6.17): every capacitor has them, they travel as `u32` of
    /// 0.01 pF, each must be a plausible capacitance ([`UB2_PLAUSIBLE_CAPACITANCE`]) and the
    /// lower must lie below the upper. The 8-bit sum cannot tell the byte orders apart
    /// (ub2-e01); these readings can.
    fn byte_order_probe() -> &'static [ub2::Request] {
        &[
            ub2::Request::GetLowerFactoryLimit,
            ub2::Request::GetUpperFactoryLimit,
        ]
    }

    fn byte_order_check(replies: &[ub2::Response]) -> Option<ByteOrderCheck> {
        let [ub2::Response::LowerFactoryLimit {
            capacitance: lower, ..
        }, ub2::Response::UpperFactoryLimit {
            capacitance: upper, ..
        }] = replies
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
        matches!(r, ub2::Request::SetSlaveAddress { .. }) || Self::kind(r) == CommandKind::Reset
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
