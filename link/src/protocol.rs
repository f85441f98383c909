//! What the transaction layer needs to know about each protocol, on top of the generated codec.

use std::fmt::Debug;
use std::ops::RangeInclusive;
use std::time::Duration;

use busspec_protocols::{sd, ub2, DecodeError, EncodeError};

/// A command's kind, as the spec declares it (the generated `Request::kind`).
pub use busspec_protocols::CommandKind as Kind;

/// How a command may be sent, from the spec.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Policy {
    pub kind: Kind,
    pub broadcast_accepted: bool,
    pub broadcast_answered: bool,
}

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

/// One protocol as the link sees it: the generated codec plus the rules of its bus.
pub trait Protocol: 'static {
    type Request: Copy + Debug + PartialEq;
    type Response: Copy + Debug + PartialEq;
    /// The spec's name: `ub2`, `sd`.
    const NAME: &'static str;
    const MAX_FRAME_LEN: usize;
    const DEVICE_ADDRESSES: RangeInclusive<u8>;
    const BROADCAST_ADDRESS: Option<u8>;
    /// Default baud rate (the document's).
    const BAUD: u32;
    /// The quiet time between two requests: UB2 §2.1 demands 10 ms; SD §1 allows at most 100
    /// frames per second, i.e. one every 10 ms.
    const INTER_REQUEST_GAP: Duration;

    fn request_name(r: &Self::Request) -> &'static str;
    fn response_name(r: &Self::Response) -> &'static str;
    fn encode_request(r: &Self::Request, address: u8, buf: &mut [u8])
        -> Result<usize, EncodeError>;
    fn decode_request(frame: &[u8]) -> Result<(u8, Self::Request), DecodeError>;
    fn encode_response(
        r: &Self::Response,
        address: u8,
        buf: &mut [u8],
    ) -> Result<usize, EncodeError>;
    fn decode_reply(
        frame: &[u8],
        request: &Self::Request,
    ) -> Result<(u8, Self::Response), DecodeError>;
    /// Whether the frame's checksum is right, and nothing else (the weakest acceptance test).
    fn checksum_ok(frame: &[u8]) -> bool;

    /// The command's kind and broadcast rules, from the spec.
    fn policy(r: &Self::Request) -> Policy;

    /// Whether sending `r` twice does no more than sending it once, so a lost or garbled reply
    /// may be answered by sending it again. Never for movements (a second trigger restarts or
    /// extends the move) or resets (the second reply reports the reset state, not the value
    /// before it); not for commands that change how the device is reached; not for reads that
    /// clear what they report.
    fn retry_safe(r: &Self::Request) -> bool;

    /// The address the reply to `r`, sent to `address`, comes from.
    fn reply_address(_r: &Self::Request, address: u8) -> u8 {
        address
    }

    /// A reply that says the device saw a corrupted request (UB2 NAK 0x92): worth a retry.
    fn is_checksum_nak(_r: &Self::Response) -> bool {
        false
    }
    /// A refusal (NAK) rather than an answer.
    fn is_nak(_r: &Self::Response) -> bool {
        false
    }

    /// The freshness counter a request carries, if it carries one (SD set point, §3.1).
    fn freshness_mut(_r: &mut Self::Request) -> Option<&mut u8> {
        None
    }
    /// The request that reads the device's view of the host's freshness counter, and how to
    /// read it out of the reply (SD §3.12).
    fn freshness_readout() -> Option<Self::Request> {
        None
    }
    fn freshness_from_reply(_r: &Self::Response) -> Option<u8> {
        None
    }
}

fn retry_by_kind(policy: Policy) -> bool {
    matches!(
        policy.kind,
        Kind::Getter | Kind::CompletionCheck | Kind::Setter
    )
}

/// The methods that only forward to a generated module's codec.
macro_rules! codec {
    ($m:ident) => {
        type Request = $m::Request;
        type Response = $m::Response;
        const NAME: &'static str = $m::PROTOCOL;
        const MAX_FRAME_LEN: usize = $m::MAX_FRAME_LEN;
        const DEVICE_ADDRESSES: RangeInclusive<u8> = $m::DEVICE_ADDRESSES;
        const BROADCAST_ADDRESS: Option<u8> = $m::BROADCAST_ADDRESS;
        const BAUD: u32 = $m::BAUD;
        const INTER_REQUEST_GAP: Duration =
            inter_request_gap($m::INTER_FRAME_GAP_MS, $m::MAX_FRAMES_PER_S);

        fn request_name(r: &$m::Request) -> &'static str {
            r.name()
        }
        fn response_name(r: &$m::Response) -> &'static str {
            r.name()
        }
        fn encode_request(
            r: &$m::Request,
            address: u8,
            buf: &mut [u8],
        ) -> Result<usize, EncodeError> {
            r.encode(address, buf)
        }
        fn decode_request(frame: &[u8]) -> Result<(u8, $m::Request), DecodeError> {
            $m::Request::decode(frame).map(|d| (d.address, d.message))
        }
        fn encode_response(
            r: &$m::Response,
            address: u8,
            buf: &mut [u8],
        ) -> Result<usize, EncodeError> {
            r.encode(address, buf)
        }
        fn decode_reply(
            frame: &[u8],
            request: &$m::Request,
        ) -> Result<(u8, $m::Response), DecodeError> {
            $m::Response::decode_reply(frame, request).map(|d| (d.address, d.message))
        }
        fn policy(r: &$m::Request) -> Policy {
            let b = r.broadcast();
            Policy {
                kind: r.kind(),
                broadcast_accepted: b.accepted,
                broadcast_answered: b.answered,
            }
        }
    };
}

/// The UB2 capacitor protocol.
#[derive(Debug, Clone, Copy)]
pub struct Ub2;

impl Protocol for Ub2 {
    codec!(ub2);

    fn checksum_ok(frame: &[u8]) -> bool {
        match frame.split_last() {
            Some((last, body)) if !body.is_empty() => ub2::checksum(body) == *last,
            _ => false,
        }
    }
    fn retry_safe(r: &ub2::Request) -> bool {
        match r {
            // The device answers from the old address or at the old rate, then moves on.
            ub2::Request::SetSlaveAddress { .. } | ub2::Request::SetBaudRate { .. } => false,
            // §6.6.1: the RESET flag "will be reset after reading".
            ub2::Request::GetStatus => false,
            _ => retry_by_kind(Self::policy(r)),
        }
    }
    fn is_checksum_nak(r: &ub2::Response) -> bool {
        matches!(r, ub2::Response::NakChecksumError)
    }
    fn is_nak(r: &ub2::Response) -> bool {
        matches!(
            r,
            ub2::Response::NakUnknownCommand
                | ub2::Response::NakIncompatibleStatus
                | ub2::Response::NakChecksumError
                | ub2::Response::NakIndexOutOfRange
        )
    }
}

/// The SD actuator protocol.
#[derive(Debug, Clone, Copy)]
pub struct Sd;

impl Protocol for Sd {
    codec!(sd);

    fn checksum_ok(frame: &[u8]) -> bool {
        if frame.len() < 3 {
            return false;
        }
        let (body, crc) = frame.split_at(frame.len() - 2);
        sd::checksum(body).to_be_bytes() == crc
    }
    fn retry_safe(r: &sd::Request) -> bool {
        match r {
            // After the first one lands the actuator answers to the new ID only.
            sd::Request::SetServoId { .. } => false,
            // Takes the position at the moment it lands: a second one, later, sets another zero.
            sd::Request::SetCurrentPositionAsZero => false,
            _ => retry_by_kind(Self::policy(r)),
        }
    }
    fn reply_address(r: &sd::Request, address: u8) -> u8 {
        match r {
            // The actuator answers with its new ID (sd-e04).
            sd::Request::SetServoId { new_id } => *new_id,
            _ => address,
        }
    }
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
            } => Some(*host_freshness_counter & 0x0F),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn policies_come_from_the_specs() {
        let go = ub2::Request::GoToCapacitance {
            target: ub2::Capacitance(15000),
        };
        assert_eq!(Ub2::policy(&go).kind, Kind::Movement);
        assert!(!Ub2::retry_safe(&go));
        assert_eq!(
            Ub2::policy(&ub2::Request::GetActualCapacitance).kind,
            Kind::Getter
        );
        assert!(Ub2::retry_safe(&ub2::Request::GetActualCapacitance));
        assert!(!Ub2::retry_safe(&ub2::Request::GetStatus));
        let sp = sd::Request::SetPoint {
            freshness: 0,
            position: sd::Angle(0),
        };
        assert_eq!(
            Sd::policy(&sp),
            Policy {
                kind: Kind::Movement,
                broadcast_accepted: true,
                broadcast_answered: false
            }
        );
        assert!(Sd::policy(&sd::Request::ReadActualPosition).broadcast_answered);
        assert!(!Sd::retry_safe(&sd::Request::ResetStallEventCounter));
        assert_eq!(Ub2::INTER_REQUEST_GAP, Duration::from_millis(10));
        assert_eq!(Sd::INTER_REQUEST_GAP, Duration::from_millis(10));
    }
}
