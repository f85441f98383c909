//! Escaping and stuffing for generated protocols whose spec declares `framing.escaping`: the
//! frame as the spec lays it out (unescaped) and the bytes as they travel, each turned into the
//! other in a caller's buffer, without allocating. The rules are the interpreter's
//! (`busspec_model::escape`), written separately: tests hold the two to each other.
//!
//! A generated decoder unescapes into a buffer of the spec's longest unescaped frame and decodes
//! that; an encoder encodes into one and escapes into the caller's buffer (of
//! [`crate::Protocol::MAX_FRAME_LEN`], the worst case escaped). A stream decoder frames
//! escaped bytes by [`frame_lens`].

use crate::stream::{VarLen, VarLens};
use crate::{DecodeError, EncodeError, EscapeFault};

/// How a protocol's frames are escaped on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EscapeKind {
    /// Each `(byte, replacement)` of the map travels as `escape`, `replacement`.
    Bytes {
        escape: u8,
        map: &'static [(u8, u8)],
    },
    /// `byte` follows every occurrence of `after`.
    Insert { after: &'static [u8], byte: u8 },
    /// Consistent overhead byte stuffing.
    Cobs,
}

/// A protocol's escaping, resolved by the generator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Escaping {
    pub kind: EscapeKind,
    /// The escaped bytes start here and end this many bytes before the frame's end.
    pub from: usize,
    pub tail: usize,
    /// Where the start bytes sit, and them (empty: none).
    pub sync_at: usize,
    pub sync: &'static [u8],
    /// The end byte a frame ends in (byte escaping and COBS); where the escape byte travels
    /// doubled (a map entry `(escape, escape)`: Garmin's and TSIP's DLE stuffing), the byte
    /// after the escape byte that ends it (DLE ETX's `03`), found by pairing.
    pub end: u8,
    /// The length field (offset, width, least significant byte first), if any.
    pub length: Option<(usize, usize, bool)>,
    /// Per direction (requests, responses): the length field's constant `k` (the frame's
    /// length is the field's value less `k`) and the shortest frame, where stuffed frames are
    /// framed by their length field.
    pub rules: [Option<(i64, usize)>; 2],
    /// Per direction (requests, responses): the shortest and longest frame unescaped
    /// (`(usize::MAX, 0)` for a direction without messages); an escaped stream decodes a
    /// frame as a direction only where its unescaped length lies between them.
    pub lens: [(usize, usize); 2],
    /// Whether the length field and checksum are computed on the escaped bytes.
    pub computed_escaped: bool,
    /// The checksum: where its coverage starts, its length, high byte first, and its
    /// distance from the frame's end to its first byte.
    pub covers_from: usize,
    pub checksum_len: usize,
    pub checksum_be: bool,
    pub checksum_from_end: usize,
}

/// An unescaped frame's length (it may exceed the buffer it was unescaped into, which then
/// holds its first bytes), and what [`Unescaped::locate`] needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unescaped {
    pub len: usize,
    added: usize,
    length: Option<i64>,
    checksum: Option<(usize, u32, u32)>,
}

impl Unescaped {
    /// An error of the unescaped frame's decode, located in the escaped bytes where the spec
    /// computes it there (its length field and checksum).
    pub fn locate(&self, e: DecodeError) -> DecodeError {
        let Some(sum) = self.checksum else {
            return e;
        };
        match e {
            DecodeError::LengthMismatch {
                offset, expected, ..
            } => DecodeError::LengthMismatch {
                offset,
                expected: expected + self.added as i64,
                found: self.length.unwrap_or(-1),
            },
            DecodeError::ChecksumMismatch { width, .. } => DecodeError::ChecksumMismatch {
                offset: sum.0,
                expected: sum.1,
                found: sum.2,
                width,
            },
            e => e,
        }
    }
}

fn read(bytes: &[u8], be: bool) -> u32 {
    let mut v = 0u32;
    for i in 0..bytes.len() {
        let b = if be {
            bytes[i]
        } else {
            bytes[bytes.len() - 1 - i]
        };
        v = v.wrapping_shl(8) | u32::from(b);
    }
    v
}

fn write(v: u32, out: &mut [u8], be: bool) {
    let n = out.len();
    for i in 0..n {
        let b = (v >> (8 * i)) as u8;
        if be {
            out[n - 1 - i] = b;
        } else {
            out[i] = b;
        }
    }
}

/// Writes bytes into a buffer, counting those past its end.
struct Out<'b> {
    buf: &'b mut [u8],
    len: usize,
}

impl Out<'_> {
    #[inline]
    fn push(&mut self, b: u8) {
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = b;
        }
        self.len += 1;
    }
}

/// Unescapes `wire` into `out`; `sum` is the frame checksum over the bytes before it (as the
/// generated code's frame checks take it). Where the spec computes the length field and
/// checksum on the escaped bytes, rewrites them in `out` so that they are right for it exactly
/// where the escaped ones are right for `wire`.
pub fn unescape(
    e: &Escaping,
    wire: &[u8],
    out: &mut [u8],
    sum: impl Fn(&[u8]) -> u32,
) -> Result<Unescaped, DecodeError> {
    let mut o = Out { buf: out, len: 0 };
    let to = wire.len().checked_sub(e.tail).filter(|&to| to >= e.from);
    let Some(to) = to else {
        for &b in wire {
            o.push(b);
        }
        return Ok(Unescaped {
            len: o.len,
            added: 0,
            length: None,
            checksum: None,
        });
    };
    for &b in &wire[..e.from] {
        o.push(b);
    }
    let bad = |offset: usize, fault: EscapeFault| DecodeError::BadEscape { offset, fault };
    match e.kind {
        EscapeKind::Bytes { escape, map } => {
            // The escapes lie inside the region: one cut by its end is refused with the byte
            // after it.
            let region = &wire[..to];
            let mut i = e.from;
            while i < to {
                match unescape_byte(escape, map, region, i) {
                    Some(Ok((b, next))) => {
                        o.push(b);
                        i = next;
                    }
                    Some(Err(fault)) => return Err(bad(i, fault)),
                    None => {
                        let found = wire.get(i + 1).copied().unwrap_or(0);
                        return Err(bad(i, EscapeFault::Escape { escape, found }));
                    }
                }
            }
        }
        EscapeKind::Insert { after, byte } => {
            let mut i = e.from;
            // The last bytes pushed since the last pattern (at most four), newest last.
            let (mut recent, mut since) = ([0u8; 4], 0usize);
            while i < to {
                o.push(wire[i]);
                recent.copy_within(1.., 0);
                recent[3] = wire[i];
                since += 1;
                i += 1;
                let n = after.len().min(4);
                if since >= after.len() && recent[4 - n..] == *after {
                    match wire.get(i) {
                        Some(&b) if b == byte && i < to => {}
                        found => {
                            return Err(bad(
                                i,
                                EscapeFault::Stuffing {
                                    expected: byte,
                                    found: found.copied(),
                                },
                            ))
                        }
                    }
                    i += 1;
                    since = 0;
                }
            }
        }
        EscapeKind::Cobs => {
            if e.from == to {
                return Err(bad(e.from, EscapeFault::CobsEmpty));
            }
            let mut i = e.from;
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
                    o.push(b);
                }
                i += 1 + n;
                full = code == 0xFF;
                if i < to && !full {
                    o.push(0);
                }
            }
        }
    }
    for &b in &wire[to..] {
        o.push(b);
    }
    let len = o.len;
    let added = wire.len().saturating_sub(len);
    if !e.computed_escaped || added == 0 || len > o.buf.len() {
        return Ok(Unescaped {
            len,
            added: 0,
            length: None,
            checksum: None,
        });
    }
    let out = &mut o.buf[..len];
    let length = e.length.map(|(at, width, le)| {
        let v = read(&wire[at..at + width], !le);
        write(v.wrapping_sub(added as u32), &mut out[at..at + width], !le);
        i64::from(v)
    });
    let at = wire.len() - e.checksum_from_end;
    let expected = mask(sum(&wire[..at]), e.checksum_len);
    let found = read(&wire[at..at + e.checksum_len], e.checksum_be);
    let own_at = len - e.checksum_from_end;
    let own = mask(sum(&out[..own_at]), e.checksum_len);
    let written = if expected == found { own } else { own ^ 1 };
    write(
        written,
        &mut out[own_at..own_at + e.checksum_len],
        e.checksum_be,
    );
    Ok(Unescaped {
        len,
        added,
        length,
        checksum: Some((at, expected, found)),
    })
}

fn mask(v: u32, len: usize) -> u32 {
    if len >= 4 {
        v
    } else {
        v & ((1u32 << (8 * len)) - 1)
    }
}

/// Escapes `frame` (as the spec lays it out) into `buf` and returns the escaped length;
/// where the spec computes the length field and checksum on the escaped bytes, rewrites them.
pub fn escape(
    e: &Escaping,
    frame: &[u8],
    buf: &mut [u8],
    sum: impl Fn(&[u8]) -> u32,
) -> Result<usize, EncodeError> {
    let available = buf.len();
    let mut o = Out { buf, len: 0 };
    let to = frame.len().checked_sub(e.tail).filter(|&to| to >= e.from);
    let Some(to) = to else {
        for &b in frame {
            o.push(b);
        }
        return finish(o.len, available);
    };
    for &b in &frame[..e.from] {
        o.push(b);
    }
    let region = &frame[e.from..to];
    match e.kind {
        EscapeKind::Bytes { escape, map } => {
            for &b in region {
                match map.iter().find(|(raw, _)| *raw == b) {
                    Some((_, r)) => {
                        o.push(escape);
                        o.push(*r);
                    }
                    None => o.push(b),
                }
            }
        }
        EscapeKind::Insert { after, byte } => {
            let mut since = 0;
            for (i, &b) in region.iter().enumerate() {
                o.push(b);
                let done = &region[since..=i];
                if done.len() >= after.len() && done.ends_with(after) {
                    o.push(byte);
                    since = i + 1;
                }
            }
        }
        EscapeKind::Cobs => {
            let mut code_at = o.len;
            o.push(0);
            let mut code = 1u8;
            for (i, &b) in region.iter().enumerate() {
                if b == 0 {
                    set(o.buf, code_at, code);
                    code_at = o.len;
                    o.push(0);
                    code = 1;
                    continue;
                }
                o.push(b);
                code += 1;
                if code == 0xFF && i + 1 < region.len() {
                    set(o.buf, code_at, code);
                    code_at = o.len;
                    o.push(0);
                    code = 1;
                }
            }
            set(o.buf, code_at, code);
        }
    }
    for &b in &frame[to..] {
        o.push(b);
    }
    let len = finish(o.len, available)?;
    let added = len - frame.len();
    if e.computed_escaped && added > 0 {
        let wire = &mut o.buf[..len];
        if let Some((at, width, le)) = e.length {
            let v = read(&frame[at..at + width], !le);
            write(v.wrapping_add(added as u32), &mut wire[at..at + width], !le);
        }
        let at = len - e.checksum_from_end;
        let s = mask(sum(&wire[..at]), e.checksum_len);
        write(s, &mut wire[at..at + e.checksum_len], e.checksum_be);
    }
    Ok(len)
}

fn set(buf: &mut [u8], at: usize, v: u8) {
    if let Some(slot) = buf.get_mut(at) {
        *slot = v;
    }
}

fn finish(len: usize, available: usize) -> Result<usize, EncodeError> {
    if len > available {
        return Err(EncodeError::BufferTooSmall {
            needed: len,
            available,
        });
    }
    Ok(len)
}

/// The frame lengths escaped bytes at the head of a stream can have, per direction: up to the
/// first end byte after the start bytes (byte escaping, COBS), or as the length field of
/// stuffed frames says; the stream decoders' rule for escaped frames. `max`: the longest
/// frame on the wire.
pub fn frame_lens(e: &Escaping, head: &[u8], max: usize) -> VarLens {
    for (i, &b) in e.sync.iter().enumerate() {
        if head.get(e.sync_at + i).is_some_and(|&x| x != b) {
            return VarLens::NONE;
        }
    }
    if let (EscapeKind::Bytes { escape, map }, 0) = (e.kind, e.tail) {
        return lens_by_length(e, head, escape, map);
    }
    if let EscapeKind::Bytes { .. } | EscapeKind::Cobs = e.kind {
        let lead = e.sync.len();
        let len = match frame_end(e, head, lead) {
            Some(Some(len)) => len,
            Some(None) => return VarLens::NONE,
            None => {
                return VarLens {
                    requests: VarLen::NEED_MORE,
                    responses: VarLen::NEED_MORE,
                }
            }
        };
        // Unescaped without a buffer: its length, or none where the escapes are bad.
        let plain = unescape(e, &head[..len], &mut [], |_| 0)
            .ok()
            .map(|u| u.len);
        let of = |(lo, hi): (usize, usize)| match plain {
            Some(n) if lo <= n && n <= hi => VarLen::len(len),
            _ => VarLen::NONE,
        };
        return VarLens {
            requests: of(e.lens[0]),
            responses: of(e.lens[1]),
        };
    }
    let Some((at, width, le)) = e.length else {
        return VarLens::NONE;
    };
    let Some(bytes) = head.get(at..at + width) else {
        return VarLens {
            requests: VarLen::NEED_MORE,
            responses: VarLen::NEED_MORE,
        };
    };
    let v = i64::from(read(bytes, !le));
    let of = |rule: Option<(i64, usize)>| match rule {
        Some((k, head_len)) => match usize::try_from(v - k) {
            Ok(n) if n >= head_len && n <= max => VarLen::len(n),
            _ => VarLen::NONE,
        },
        None => VarLen::NONE,
    };
    VarLens {
        requests: of(e.rules[0]),
        responses: of(e.rules[1]),
    }
}

/// Where a frame with byte escaping or COBS that starts `head` ends: just after the first end
/// byte after its `lead` start bytes, or, where the escape byte travels doubled (DLE
/// stuffing), after the first escape byte followed by [`Escaping::end`] (`10 10` is a data
/// byte, `10 03` ends the frame, the escape byte and a replacement another byte). `None`: the
/// bytes end first; `Some(None)`: an escape byte followed by another byte, a bad escape.
fn frame_end(e: &Escaping, head: &[u8], lead: usize) -> Option<Option<usize>> {
    if let EscapeKind::Bytes { escape, map } = e.kind {
        if map.contains(&(escape, escape)) {
            let mut i = lead;
            while i < head.len() {
                if head[i] != escape {
                    i += 1;
                    continue;
                }
                let next = *head.get(i + 1)?;
                if next == e.end {
                    return Some(Some(i + 2));
                }
                if !map.iter().any(|(_, r)| *r == next) {
                    return Some(None);
                }
                i += 2;
            }
            return None;
        }
    }
    let i = head.iter().skip(lead).position(|&b| b == e.end)?;
    Some(Some(lead + i + 1))
}

/// [`frame_lens`] where requests and responses are escaped and framed apart (F.Port: requests
/// between 7E flags, responses without start or end bytes, stuffed from their first byte and
/// framed by their length field): each direction's lengths by its own escaping, `requests`'
/// for requests, `responses`' for responses (each constant gives no rule or lengths for the
/// other direction).
pub fn frame_lens_by_direction(
    requests: &Escaping,
    responses: &Escaping,
    head: &[u8],
    max: usize,
) -> VarLens {
    VarLens {
        requests: frame_lens(requests, head, max).requests,
        responses: frame_lens(responses, head, max).responses,
    }
}

/// Byte escaping without an end byte (XBee API mode 2): the length field read as the bytes
/// after the start bytes unescape, and each direction's frame as far as that many bytes
/// unescape (its frame length from the field, [`Escaping::rules`], within [`Escaping::lens`]).
fn lens_by_length(e: &Escaping, head: &[u8], escape: u8, map: &[(u8, u8)]) -> VarLens {
    const NEED_MORE: VarLens = VarLens {
        requests: VarLen::NEED_MORE,
        responses: VarLen::NEED_MORE,
    };
    let Some((at, width, le)) = e.length else {
        return VarLens::NONE;
    };
    // The byte at `i` unescaped and where the next starts; `None` past `head`, `Err` at a
    // bad escape.
    let one = |i: usize| unescape_byte(escape, map, head, i);
    // Unescaped bytes up to `n` (counted from the frame's first byte): where the `n`th ends on
    // the wire, continuing from (`count`, `i`).
    let advance = |count: &mut usize, i: &mut usize, n: usize, mut seen: Option<&mut [u8; 4]>| {
        while *count < n {
            match one(*i) {
                Some(Ok((b, next))) => {
                    if let Some(bytes) = seen.as_deref_mut() {
                        if let Some(slot) = (*count).checked_sub(at).and_then(|k| bytes.get_mut(k))
                        {
                            *slot = b;
                        }
                    }
                    *count += 1;
                    *i = next;
                }
                Some(Err(_)) => return Some(false),
                None => return None,
            }
        }
        Some(true)
    };
    let lead = e.sync.len();
    let (mut count, mut i) = (lead, lead);
    let mut field = [0u8; 4];
    match advance(&mut count, &mut i, at + width, Some(&mut field)) {
        Some(true) => {}
        Some(false) => return VarLens::NONE,
        None => return NEED_MORE,
    }
    let v = i64::from(read(&field[..width.min(4)], !le));
    // Each direction's frame length, shortest first, as far as the bytes go.
    let mut wanted: [(usize, usize); 2] = [(usize::MAX, 0), (usize::MAX, 1)];
    for (want, (rule, (lo, hi))) in wanted.iter_mut().zip(e.rules.iter().zip(e.lens)) {
        if let Some((k, _)) = rule {
            if let Ok(n) = usize::try_from(v - k) {
                if lo <= n && n <= hi {
                    want.0 = n;
                }
            }
        }
    }
    if wanted[1].0 < wanted[0].0 {
        wanted.swap(0, 1);
    }
    let mut out = [VarLen::NONE; 2];
    for (n, d) in wanted {
        // No frame ends before its length field.
        if n == usize::MAX || n < at + width {
            continue;
        }
        out[d] = match advance(&mut count, &mut i, n, None) {
            Some(true) => VarLen::len(i),
            Some(false) => break,
            None => {
                // This frame and every one as long or longer wait for more bytes.
                for (n2, d2) in wanted {
                    if n2 != usize::MAX && n2 >= n {
                        out[d2] = VarLen::NEED_MORE;
                    }
                }
                break;
            }
        };
    }
    VarLens {
        requests: out[0],
        responses: out[1],
    }
}

/// Byte escaping: what `wire[i]` unescapes to and where the next byte starts; `None` where
/// `wire` ends inside the escape, the fault at a bad one. What [`unescape`] and a stream's
/// [`frame_lens`] both read by.
#[inline]
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Garmin's serial link: `10 ID size data checksum 10 03`, every 10 inside doubled.
    const GARMIN: Escaping = Escaping {
        kind: EscapeKind::Bytes {
            escape: 0x10,
            map: &[(0x10, 0x10)],
        },
        from: 1,
        tail: 2,
        sync_at: 0,
        sync: &[0x10],
        end: 0x03,
        length: None,
        rules: [None, None],
        lens: [(5, 300), (5, 300)],
        computed_escaped: false,
        covers_from: 1,
        checksum_len: 1,
        checksum_be: false,
        checksum_from_end: 3,
    };

    fn end(head: &[u8]) -> Option<Option<usize>> {
        frame_end(&GARMIN, head, 1)
    }

    /// The end is found by pairing: a doubled 10 is data, however many there are before
    /// DLE ETX; a 10 followed by anything else is a bad escape; a frame cut after a 10 waits.
    #[test]
    fn doubled_escape_frames_end_where_the_pairs_say() {
        assert_eq!(end(&[0x10, 0xFE, 0x00, 0x02, 0x10, 0x03]), Some(Some(6)));
        // The checksum 10 doubled just before DLE ETX: 10 10 10 03.
        assert_eq!(
            end(&[0x10, 0x15, 0x02, 0x10, 0x10, 0x10, 0x10, 0x10, 0x03, 0x10]),
            Some(Some(9))
        );
        // 10 10 03: the 03 is data, the frame goes on.
        assert_eq!(end(&[0x10, 0x06, 0x10, 0x10, 0x03, 0x01]), None);
        assert_eq!(end(&[0x10, 0x06, 0x10]), None);
        assert_eq!(end(&[0x10, 0x06, 0x10, 0x41, 0x10, 0x03]), Some(None));
        let lens = frame_lens(&GARMIN, &[0x10, 0x06, 0x10, 0x41, 0x10, 0x03], 600);
        assert_eq!(lens.requests, VarLen::NONE);
        // A first end byte alone is no end: the frame waits for more bytes.
        let lens = frame_lens(&GARMIN, &[0x10, 0x06, 0x10, 0x10, 0x03, 0x01], 600);
        assert_eq!(lens.requests, VarLen::NEED_MORE);
        let lens = frame_lens(&GARMIN, &[0x10, 0xFE, 0x00, 0x02, 0x10, 0x03], 600);
        assert_eq!(lens.requests, VarLen::len(6));
        // Unescaped, the frame is 10 15 02 10 00 D9 10 03 less one byte of the wire.
        let wire = [0x10, 0x15, 0x02, 0x10, 0x10, 0x00, 0xD9, 0x10, 0x03];
        let mut out = [0u8; 16];
        let u = unescape(&GARMIN, &wire, &mut out, |_| 0).unwrap();
        assert_eq!(
            &out[..u.len],
            &[0x10, 0x15, 0x02, 0x10, 0x00, 0xD9, 0x10, 0x03]
        );
        let mut back = [0u8; 16];
        let n = escape(&GARMIN, &out[..u.len], &mut back, |_| 0).unwrap();
        assert_eq!(&back[..n], &wire);
    }
}
