//! Stream events reduced to what both stream decoders (generated and interpreter) report, so
//! the two can be compared; and the checks every event list must pass.

use busspec_model::interp::{self, DecodeError as InterpError};
use busspec_model::ir::{Direction, Protocol};
use busspec_model::stream::{Event as InterpEvent, StreamDecoder as InterpDecoder};
use busspec_protocols::DecodeError;

use crate::oracle::{interp_values, Values};

/// An event reduced to what both decoders report: kind, offset, length, message, address, values.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Seen {
    Frame {
        offset: u64,
        len: u64,
        name: String,
        address: u8,
        values: Values,
    },
    Ambiguous {
        offset: u64,
        len: u64,
    },
    Skipped {
        offset: u64,
        len: u64,
    },
    OutOfSpec {
        offset: u64,
        len: u64,
        reason: Why,
    },
}

/// Why a frame is out of spec, reduced to what both decoders' errors say: which rule, where,
/// and the value that breaks it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Why {
    OutOfRange {
        field: String,
        offset: usize,
        found: i64,
        min: i64,
        max: i64,
    },
    BadAddress {
        offset: usize,
        found: u8,
        min: u8,
        max: u8,
    },
    BroadcastNotAccepted {
        address: u8,
    },
    /// Any other error: no stream decoder reports one as out of spec.
    Other(String),
}

impl Why {
    /// The generated decoder's reason.
    pub fn of(e: &DecodeError) -> Why {
        match *e {
            DecodeError::OutOfRange {
                field,
                offset,
                found,
                min,
                max,
                kind: _,
            } => Why::OutOfRange {
                field: field.name.to_owned(),
                offset,
                found,
                min,
                max,
            },
            DecodeError::BadAddress {
                offset,
                found,
                min,
                max,
            } => Why::BadAddress {
                offset,
                found,
                min,
                max,
            },
            DecodeError::BroadcastNotAccepted { address, .. } => {
                Why::BroadcastNotAccepted { address }
            }
            ref e => Why::Other(e.to_string()),
        }
    }

    /// The interpreter's reason.
    pub fn of_interp(e: &InterpError) -> Why {
        match e {
            InterpError::OutOfRange {
                field,
                offset,
                found,
                min,
                max,
                ..
            } => Why::OutOfRange {
                field: field.clone(),
                offset: *offset,
                found: *found,
                min: *min,
                max: *max,
            },
            InterpError::BadAddress {
                offset,
                found,
                min,
                max,
            } => Why::BadAddress {
                offset: *offset,
                found: *found,
                min: *min,
                max: *max,
            },
            InterpError::BroadcastNotAccepted { address, .. } => {
                Why::BroadcastNotAccepted { address: *address }
            }
            e => Why::Other(e.to_string()),
        }
    }
}

impl Seen {
    /// Offset and length of the bytes the event stands for.
    pub fn span(&self) -> (u64, u64) {
        match self {
            Seen::Frame { offset, len, .. }
            | Seen::Ambiguous { offset, len }
            | Seen::OutOfSpec { offset, len, .. }
            | Seen::Skipped { offset, len } => (*offset, *len),
        }
    }
}

/// Consecutive skipped runs are one run, however each decoder splits them.
pub fn merge(events: impl IntoIterator<Item = Seen>) -> Vec<Seen> {
    let mut out: Vec<Seen> = Vec::new();
    for e in events {
        if let (
            Some(Seen::Skipped { offset, len }),
            Seen::Skipped {
                offset: o2,
                len: l2,
            },
        ) = (out.last_mut(), &e)
        {
            if *offset + *len == *o2 {
                *len += l2;
                continue;
            }
        }
        out.push(e);
    }
    out
}

/// Every byte of a `total`-byte capture is in exactly one event, in order.
pub fn covers(events: &[Seen], total: u64) {
    let mut at = 0;
    for e in events {
        let (offset, len) = e.span();
        assert_eq!(offset, at, "gap or overlap before {e:?}");
        assert!(len > 0, "empty event {e:?}");
        at += len;
    }
    assert_eq!(at, total, "events end before the capture does");
}

/// The interpreter's events for `capture` pushed in `chunks` (the rest in one piece), then
/// flushed.
pub fn interp_events(
    p: &Protocol,
    direction: Option<Direction>,
    capture: &[u8],
    chunks: &[usize],
) -> Vec<Seen> {
    let mut d = InterpDecoder::new(p, direction);
    let mut events = Vec::new();
    let mut rest = capture;
    for &n in chunks {
        let (a, b) = rest.split_at(n.min(rest.len()));
        events.extend(d.push(a));
        rest = b;
    }
    events.extend(d.push(rest));
    events.extend(d.flush());
    merge(events.into_iter().map(|e| match e {
        InterpEvent::Frame {
            offset,
            bytes,
            frame,
        } => Seen::Frame {
            offset,
            len: bytes.len() as u64,
            name: p.message(frame.message).name.clone(),
            address: frame.address,
            values: interp_values(p, &frame),
        },
        InterpEvent::Ambiguous { offset, bytes, .. } => Seen::Ambiguous {
            offset,
            len: bytes.len() as u64,
        },
        InterpEvent::Skipped { offset, bytes } => Seen::Skipped {
            offset,
            len: bytes.len() as u64,
        },
        InterpEvent::OutOfSpec {
            offset,
            bytes,
            reason,
            ..
        } => Seen::OutOfSpec {
            offset,
            len: bytes.len() as u64,
            reason: Why::of_interp(&reason),
        },
    }))
}

/// Chunk sizes from 1 to `max` covering `total` bytes, drawn from `seed` (xorshift32), so one
/// input byte chooses how a capture is cut.
pub fn chunks(seed: u8, total: usize, max: usize) -> Vec<usize> {
    let mut x = u32::from(seed).wrapping_mul(0x9E37_79B9) | 1;
    let mut out = Vec::new();
    let mut n = 0;
    while n < total {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        let c = 1 + (x as usize) % max.max(1);
        out.push(c);
        n += c;
    }
    out
}

/// The interpreter's direction for the generated crate's.
pub fn direction(d: Option<busspec_protocols::stream::Direction>) -> Option<Direction> {
    d.map(|d| match d {
        busspec_protocols::stream::Direction::Request => Direction::Request,
        busspec_protocols::stream::Direction::Response => Direction::Response,
    })
}

/// Bytes `offset..offset+len` of `capture`; the event must lie inside it.
pub fn bytes_of(capture: &[u8], offset: u64, len: u64) -> &[u8] {
    let start = usize::try_from(offset).expect("offset fits usize");
    let end = start + usize::try_from(len).expect("length fits usize");
    capture.get(start..end).unwrap_or_else(|| {
        panic!(
            "event {offset}+{len} beyond a {}-byte capture",
            capture.len()
        )
    })
}

/// Renders `capture` for assertion messages.
pub fn hex(capture: &[u8]) -> String {
    interp::format_hex(capture)
}
