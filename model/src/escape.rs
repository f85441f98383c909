//! Escaping and stuffing (`framing.escaping`): the frame as the IR lays it out (unescaped) and
//! the bytes as they travel (escaped), each turned into the other.
//!
//! Every decode of the interpreter unescapes first ([`unescape`]) and decodes the unescaped
//! frame; encode escapes what it laid out ([`escape`]). Errors found in the unescaped frame are
//! located in it, except the two that the spec computes on the escaped bytes
//! (`computed: escaped`): a length field and a checksum that disagree are reported with the
//! escaped frame's offsets and values ([`Unescaped::locate`]).
//!
//! The three kinds (the generated code's `rt::escape` does the same, written separately):
//! - **Bytes** (SLIP, KISS, HDLC): between the leading start bytes and the end byte (or the
//!   frame's end, where a length field frames it: XBee API mode 2), each byte of the map
//!   travels as the escape byte and its replacement. An escape byte followed by anything else,
//!   or a byte of the map found as it is, is refused. Where the map has the escape byte stand
//!   for itself (DLE stuffing: Garmin's serial link, TSIP), it travels doubled and frames end
//!   in it and a byte no escape stands for (`10 03`), found in a stream by pairing
//!   ([`frame_end`]).
//! - **Insert** (Dynamixel 2.0): from the declared part through the payload, the byte is
//!   inserted after every occurrence of the pattern, matched left to right on the unstuffed
//!   bytes and afresh after each one. A pattern not followed by the byte is refused.
//! - **COBS**: the bytes between the leading start bytes and the end byte 0x00 are COBS
//!   blocks; a 0x00 among them, a block running past them, no block at all, or the one
//!   non-canonical ending (a 0x01 block after a full 0xFF block) is refused, so decoding
//!   accepts exactly what encoding writes.

use std::borrow::Cow;

use crate::interp::{read_uint, write_uint, DecodeError, EscapeFault};
use crate::ir::{Computed, Direction, EscapeKind, Framing, Protocol};

/// A frame unescaped, with what [`Unescaped::locate`] needs to report the checks the spec
/// computes on the escaped bytes.
#[derive(Debug, Clone)]
pub struct Unescaped<'w> {
    /// The frame as the IR lays it out.
    pub frame: Cow<'w, [u8]>,
    /// Set where the length field and checksum are computed on the escaped bytes and the frame
    /// was stuffed: how many bytes stuffing added, the escaped length field's value and the
    /// escaped checksum's check (offset, expected, found).
    escaped: Option<EscapedChecks>,
}

#[derive(Debug, Clone, Copy)]
struct EscapedChecks {
    added: usize,
    length: Option<i64>,
    checksum: (usize, u64, u64),
}

impl Unescaped<'_> {
    /// An error the unescaped frame's decode gave, located in the escaped frame where the
    /// spec computes it there (`computed: escaped`): its length field and checksum.
    pub fn locate(&self, e: DecodeError) -> DecodeError {
        let Some(x) = self.escaped else {
            return e;
        };
        match e {
            DecodeError::LengthMismatch {
                offset, expected, ..
            } => DecodeError::LengthMismatch {
                offset,
                expected: expected + x.added as i64,
                found: x.length.unwrap_or(-1),
            },
            DecodeError::ChecksumMismatch { width, .. } => DecodeError::ChecksumMismatch {
                offset: x.checksum.0,
                expected: x.checksum.1,
                found: x.checksum.2,
                width,
            },
            e => e,
        }
    }
}

/// The unescaped frame of `wire`; the wire itself where the protocol has no escaping or the
/// frame is too short to hold the bytes around its escaped ones (decoding then says what is
/// wrong with it).
pub fn unescape<'w>(p: &Protocol, wire: &'w [u8]) -> Result<Unescaped<'w>, DecodeError> {
    unescape_as(p, Direction::Request, wire)
}

/// [`unescape`] of a frame of direction `d`: the bytes between its own start and end bytes
/// ([`Framing::escaped_region_of`]). Where the escaped region differs by direction, a frame
/// decoded without a known direction is unescaped once per direction tried.
pub fn unescape_as<'w>(
    p: &Protocol,
    d: Direction,
    wire: &'w [u8],
) -> Result<Unescaped<'w>, DecodeError> {
    let f = &p.framing;
    let (Some(e), Some((from, to))) = (&f.escaping, f.escaped_region_of(d, wire.len())) else {
        return Ok(Unescaped {
            frame: Cow::Borrowed(wire),
            escaped: None,
        });
    };
    let mut out = Vec::with_capacity(wire.len());
    out.extend_from_slice(&wire[..from]);
    unescape_region(&e.kind, wire, from, to, &mut out)?;
    out.extend_from_slice(&wire[to..]);
    let added = wire.len() - out.len();
    let escaped = if e.computed == Computed::Escaped && added > 0 {
        Some(normalize(p, wire, &mut out, added))
    } else {
        None
    };
    Ok(Unescaped {
        frame: Cow::Owned(out),
        escaped,
    })
}

/// Unescapes `wire[from..to]` onto `out`.
fn unescape_region(
    kind: &EscapeKind,
    wire: &[u8],
    from: usize,
    to: usize,
    out: &mut Vec<u8>,
) -> Result<(), DecodeError> {
    let bad = |offset: usize, fault: EscapeFault| DecodeError::BadEscape { offset, fault };
    match kind {
        EscapeKind::Bytes { escape, map, .. } => {
            // The escapes lie inside the region: one cut by its end (before the end byte at
            // worst) is refused with the byte after it.
            let region = &wire[..to];
            let mut i = from;
            while i < to {
                match unescape_byte(*escape, map, region, i) {
                    Some(Ok((b, next))) => {
                        out.push(b);
                        i = next;
                    }
                    Some(Err(fault)) => return Err(bad(i, fault)),
                    None => {
                        let found = wire.get(i + 1).copied().unwrap_or(0);
                        return Err(bad(
                            i,
                            EscapeFault::Escape {
                                escape: *escape,
                                found,
                            },
                        ));
                    }
                }
            }
        }
        EscapeKind::Insert { after, byte, .. } => {
            let mut i = from;
            let mut since = out.len();
            while i < to {
                out.push(wire[i]);
                i += 1;
                if out.len() - since >= after.len() && out.ends_with(after) {
                    match wire.get(i) {
                        Some(b) if *b == *byte && i < to => {}
                        found => {
                            return Err(bad(
                                i,
                                EscapeFault::Stuffing {
                                    expected: *byte,
                                    found: found.copied(),
                                },
                            ))
                        }
                    }
                    i += 1;
                    since = out.len();
                }
            }
        }
        EscapeKind::Cobs => {
            if from == to {
                return Err(bad(from, EscapeFault::CobsEmpty));
            }
            let mut i = from;
            let mut full = false;
            while i < to {
                let code = wire[i];
                if code == 0 {
                    return Err(bad(i, EscapeFault::CobsZero));
                }
                let n = usize::from(code) - 1;
                if i + 1 + n > to {
                    return Err(bad(i, EscapeFault::CobsOverrun { code }));
                }
                if full && code == 1 && i + 1 == to {
                    return Err(bad(i, EscapeFault::CobsTrailing));
                }
                for (k, &b) in wire[i + 1..i + 1 + n].iter().enumerate() {
                    if b == 0 {
                        return Err(bad(i + 1 + k, EscapeFault::CobsZero));
                    }
                    out.push(b);
                }
                i += 1 + n;
                full = code == 0xFF;
                if i < to && !full {
                    out.push(0);
                }
            }
        }
    }
    Ok(())
}

/// Byte escaping: the byte that `wire[i]` unescapes to and where the next one starts; `None`
/// where `wire` ends first, `Err` at a bad escape (or without byte escaping). How a stream
/// reads the length field of frames with no end byte (XBee API mode 2).
pub fn unescape_one(f: &Framing, wire: &[u8], i: usize) -> Option<Result<(u8, usize), ()>> {
    let Some(EscapeKind::Bytes { escape, map, .. }) = f.escaping.as_ref().map(|e| &e.kind) else {
        return Some(Err(()));
    };
    unescape_byte(*escape, map, wire, i).map(|r| r.map_err(|_| ()))
}

/// Byte escaping: what `wire[i]` unescapes to and where the next byte starts; `None` where
/// `wire` ends inside the escape, the fault at a bad one. What [`unescape_region`] and
/// [`unescape_one`] both read by.
fn unescape_byte(
    escape: u8,
    map: &[(u8, u8)],
    wire: &[u8],
    i: usize,
) -> Option<Result<(u8, usize), EscapeFault>> {
    let b = *wire.get(i)?;
    if b == escape {
        let next = *wire.get(i + 1)?;
        return Some(match map.iter().find(|(_, r)| *r == next) {
            Some((raw, _)) => Ok((*raw, i + 2)),
            None => Err(EscapeFault::Escape {
                escape,
                found: next,
            }),
        });
    }
    if map.iter().any(|(raw, _)| *raw == b) {
        return Some(Err(EscapeFault::Unescaped { found: b }));
    }
    Some(Ok((b, i + 1)))
}

/// Where a frame with byte escaping or COBS that starts `buf` ends: just after the first end
/// byte after its `lead` start bytes, or, where the escape byte travels doubled (Garmin's and
/// TSIP's DLE stuffing, [`EscapeKind::doubled`]), after the first escape byte that pairs with
/// the frame's last end byte (`10 10` is a data byte, `10 03` ends the frame, the escape byte
/// and a replacement another byte). `None`: the bytes end first; `Some(None)`: an escape byte
/// followed by another byte (a bad escape: the stream drops a byte). How the stream decoder
/// frames escaped bytes (the generated one's `rt::escaped_lens` reads the same way).
pub fn frame_end(f: &Framing, d: Direction, buf: &[u8], lead: usize) -> Option<Option<usize>> {
    let kind = f.escaping.as_ref().map(|e| &e.kind);
    let end = f.end_of(d);
    if let (Some(escape), Some(EscapeKind::Bytes { map, .. }), [_, after]) =
        (kind.and_then(EscapeKind::doubled), kind, end)
    {
        let mut i = lead;
        while i < buf.len() {
            if buf[i] != escape {
                i += 1;
                continue;
            }
            let next = *buf.get(i + 1)?;
            if next == *after {
                return Some(Some(i + 2));
            }
            if !map.iter().any(|(_, r)| *r == next) {
                return Some(None);
            }
            i += 2;
        }
        return None;
    }
    let end = end.first().copied().unwrap_or(0);
    let i = buf.iter().skip(lead).position(|&b| b == end)?;
    Some(Some(lead + i + 1))
}

/// Escapes `frame[from..to]` onto `out`.
fn escape_region(kind: &EscapeKind, frame: &[u8], out: &mut Vec<u8>) {
    match kind {
        EscapeKind::Bytes { escape, map, .. } => {
            for &b in frame {
                match map.iter().find(|(raw, _)| *raw == b) {
                    Some((_, r)) => out.extend_from_slice(&[*escape, *r]),
                    None => out.push(b),
                }
            }
        }
        EscapeKind::Insert { after, byte, .. } => {
            let mut since = 0;
            for (i, &b) in frame.iter().enumerate() {
                out.push(b);
                let done = &frame[since..=i];
                if done.len() >= after.len() && done.ends_with(after) {
                    out.push(*byte);
                    since = i + 1;
                }
            }
        }
        EscapeKind::Cobs => {
            let mut code_at = out.len();
            out.push(0);
            let mut code = 1u8;
            for (i, &b) in frame.iter().enumerate() {
                if b == 0 {
                    out[code_at] = code;
                    code_at = out.len();
                    out.push(0);
                    code = 1;
                    continue;
                }
                out.push(b);
                code += 1;
                if code == 0xFF && i + 1 < frame.len() {
                    out[code_at] = code;
                    code_at = out.len();
                    out.push(0);
                    code = 1;
                }
            }
            out[code_at] = code;
        }
    }
}

/// The bytes as they travel for `frame` (as the IR lays it out, length field and checksum
/// those of the unescaped frame): escaped, and where the spec computes the length field and
/// checksum on the escaped bytes, those rewritten for them.
pub fn escape(p: &Protocol, frame: &[u8]) -> Vec<u8> {
    escape_as(p, Direction::Request, frame)
}

/// [`escape`] of a frame of direction `d` ([`Framing::escaped_region_of`]).
pub fn escape_as(p: &Protocol, d: Direction, frame: &[u8]) -> Vec<u8> {
    let f = &p.framing;
    let wire = escape_bytes_of(f, d, frame);
    match &f.escaping {
        Some(e) if e.computed == Computed::Escaped && wire.len() > frame.len() => {
            let mut wire = wire;
            let added = wire.len() - frame.len();
            if let Some((at, width)) = length_field(p) {
                let v = read_uint(&frame[at..at + width], p.byte_order);
                write_uint(
                    v.wrapping_add(added as u64),
                    &mut wire[at..at + width],
                    p.byte_order,
                );
            }
            let c = &f.checksum;
            let at = f.checksum_at_of(d, wire.len());
            let sum = c.compute(wire.get(c.covers_from..at).unwrap_or(&[]));
            write_uint(sum, &mut wire[at..at + c.len()], c.byte_order);
            wire
        }
        _ => wire,
    }
}

/// `frame` escaped byte for byte, nothing rewritten (examples go through it to put printed
/// text in the wire's byte order).
pub fn escape_bytes(f: &Framing, frame: &[u8]) -> Vec<u8> {
    escape_bytes_of(f, Direction::Request, frame)
}

/// [`escape_bytes`] of a frame of direction `d`.
pub fn escape_bytes_of(f: &Framing, d: Direction, frame: &[u8]) -> Vec<u8> {
    let (Some(e), Some((from, to))) = (&f.escaping, f.escaped_region_of(d, frame.len())) else {
        return frame.to_vec();
    };
    let mut out = Vec::with_capacity(f.wire_len(frame.len()));
    out.extend_from_slice(&frame[..from]);
    escape_region(&e.kind, &frame[from..to], &mut out);
    out.extend_from_slice(&frame[to..]);
    out
}

/// `wire` unescaped byte for byte, nothing rewritten or checked beyond the escapes.
pub fn unescape_bytes(f: &Framing, wire: &[u8]) -> Result<Vec<u8>, DecodeError> {
    unescape_bytes_of(f, Direction::Request, wire)
}

/// [`unescape_bytes`] of a frame of direction `d`.
pub fn unescape_bytes_of(f: &Framing, d: Direction, wire: &[u8]) -> Result<Vec<u8>, DecodeError> {
    let (Some(e), Some((from, to))) = (&f.escaping, f.escaped_region_of(d, wire.len())) else {
        return Ok(wire.to_vec());
    };
    let mut out = Vec::with_capacity(wire.len());
    out.extend_from_slice(&wire[..from]);
    unescape_region(&e.kind, wire, from, to, &mut out)?;
    out.extend_from_slice(&wire[to..]);
    Ok(out)
}

/// Where the length field sits (every frame has it at one offset before the stuffed bytes:
/// validated), and its width.
fn length_field(p: &Protocol) -> Option<(usize, usize)> {
    let l = p.framing.length.as_ref()?;
    Some((p.framing.head(Direction::Request, 0).length?, l.width))
}

/// Rewrites the unescaped frame `out` of stuffed `wire` (`added` bytes longer) so that its
/// length field and checksum are right for it exactly where the escaped ones are right for
/// `wire`: the length field less the added bytes, the checksum its own where the escaped one
/// checks, else anything but.
fn normalize(p: &Protocol, wire: &[u8], out: &mut [u8], added: usize) -> EscapedChecks {
    let length = length_field(p).map(|(at, width)| {
        let v = read_uint(&wire[at..at + width], p.byte_order);
        write_uint(
            v.wrapping_sub(added as u64),
            &mut out[at..at + width],
            p.byte_order,
        );
        v as i64
    });
    let (f, c) = (&p.framing, &p.framing.checksum);
    let at = f.checksum_at(wire.len());
    let expected = c.compute(wire.get(c.covers_from..at).unwrap_or(&[]));
    let found = read_uint(&wire[at..at + c.len()], c.byte_order);
    let own_at = f.checksum_at(out.len());
    let own = c.compute(out.get(c.covers_from..own_at).unwrap_or(&[]));
    let written = if expected == found { own } else { own ^ 1 };
    write_uint(written, &mut out[own_at..own_at + c.len()], c.byte_order);
    EscapedChecks {
        added,
        length,
        checksum: (at, expected, found),
    }
}

/// The escaping in a few words (`none` for none), as `busspec diff` and the docs say it.
pub fn describe(e: Option<&crate::ir::Escaping>) -> String {
    let Some(e) = e else {
        return "none".to_owned();
    };
    let computed = match e.computed {
        Computed::Unescaped => "checksum and length computed before escaping",
        Computed::Escaped => "checksum and length computed on the escaped bytes",
    };
    let what = match &e.kind {
        EscapeKind::Bytes { escape, map, .. } => {
            let pairs: Vec<String> = map
                .iter()
                .map(|(b, r)| match b == r {
                    true => format!("{b:02X} doubled"),
                    false => format!("{b:02X} as {escape:02X} {r:02X}"),
                })
                .collect();
            let ends = match e.kind.doubled() {
                Some(x) => format!("; a frame ends at the first {x:02X} not doubled"),
                None => String::new(),
            };
            format!("escape byte {escape:02X}: {}{ends}", pairs.join(", "))
        }
        EscapeKind::Insert { after, byte, from } => {
            let after: Vec<String> = after.iter().map(|b| format!("{b:02X}")).collect();
            format!(
                "{byte:02X} inserted after {} from the {:?} on",
                after.join(" "),
                from
            )
            .replace("Code", "code")
            .replace("Address", "address")
        }
        EscapeKind::Cobs => "COBS".to_owned(),
    };
    format!("{what} ({computed})")
}
