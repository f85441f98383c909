//! Generated code held to the interpreter (`busspec_model::interp`, the oracle) on frames of
//! variable length: every example, frames mutated from them (bytes changed, counts and length
//! fields that lie, frames cut and lengthened, with and without a good checksum), and messages
//! encoded from the examples' values with lists of other lengths and values.
//!
//! Shared by the test files that include generated code with repeated fields.

#![allow(dead_code, unused_imports)]

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{self, Direction, MessageRef};
use busspec_runtime::{Elements, FieldValue, Message, Protocol, RequestMessage, ResponseMessage};

/// `name`, a path from the repository's root.
pub fn fixture(name: &str) -> ir::Protocol {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(name);
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

/// What the two engines made of the frames checked.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Tally {
    pub accepted: usize,
    pub refused: usize,
    /// Messages encoded from values (both engines wrote the same bytes, or both refused).
    pub encoded: usize,
    pub encode_refused: usize,
}

/// A visited value as the interpreter holds it.
fn raw(v: FieldValue<'_>) -> Raw {
    match v {
        FieldValue::Int(i) => Raw::Int(i),
        FieldValue::Text(t) => Raw::Text(t.to_vec()),
        FieldValue::List(items) => Raw::List(items.iter().collect()),
        FieldValue::Records(list) => Raw::Records(
            (0..list.len())
                .map(|k| {
                    (0..list.fields())
                        .map(|j| list.get(k, j).unwrap_or(0))
                        .collect()
                })
                .collect(),
        ),
    }
}

/// The values a generated message visits, by name.
pub fn visited<M: Message>(m: &M) -> Vec<(&'static str, Raw)> {
    let mut out = Vec::new();
    m.visit(|n, v| out.push((n, raw(v))));
    out
}

/// The generated message has the interpreter's name and every value it visits is the
/// interpreter's.
fn same<M: Message>(p: &ir::Protocol, g: &M, i: &interp::Frame, wire: &[u8]) {
    assert_eq!(g.name(), p.message(i.message).name, "{wire:02X?}");
    for (n, v) in visited(g) {
        assert_eq!(i.get(n), Some(&v), "{wire:02X?}: {n}");
    }
}

/// Decodes `wire` with both engines (as the reply to `request` where given: the generated
/// request, the interpreter's frame of it and its bytes, which a reply's checksum may take
/// in), asserts they agree on acceptance and values, and that the generated encoder writes an
/// accepted frame back byte for byte; returns whether it was accepted.
pub fn check<P: Protocol>(
    p: &ir::Protocol,
    d: Direction,
    request: Option<(&P::Request, &interp::Frame, &[u8])>,
    wire: &[u8],
) -> bool {
    let mut buf = vec![0xA5u8; P::MAX_FRAME_LEN];
    match d {
        Direction::Request => {
            let g = P::decode_request(wire);
            let i = interp::decode(p, Some(d), None, wire);
            assert_eq!(g.is_ok(), i.is_ok(), "{wire:02X?}: {g:?} / {i:?}");
            let (g, i) = match (g, i) {
                (Ok(g), Ok(i)) => (g, i),
                (g, i) => return same_words(g.err(), i.err(), wire),
            };
            assert_eq!(g.address, i.address);
            same(p, &g.message, &i, wire);
            assert_eq!(g.message.frame_len(), unescaped_len(p, d, wire));
            let n = g.message.encode(g.address, &mut buf).unwrap();
            written_back(p, &buf[..n], wire);
        }
        Direction::Response => {
            let g = match request {
                Some((r, _, w)) => {
                    P::Response::decode_as_reply_over(wire, Some(r), Some(P::Request::covered(w)))
                }
                None => P::Response::decode_as_reply(wire, None),
            };
            let i = match request {
                Some((_, f, w)) => interp::decode_reply_with(p, f, Some(w), wire),
                None => interp::decode(p, Some(d), None, wire),
            };
            assert_eq!(g.is_ok(), i.is_ok(), "{wire:02X?}: {g:?} / {i:?}");
            let (g, i) = match (g, i) {
                (Ok(g), Ok(i)) => (g, i),
                (g, i) => return same_words(g.err(), i.err(), wire),
            };
            assert_eq!(g.address, i.address);
            same(p, &g.message, &i, wire);
            assert_eq!(g.message.frame_len(), unescaped_len(p, d, wire));
            if let Some((r, _, _)) = request {
                assert!(g.message.answers(r), "{wire:02X?}");
            }
            let n = match request {
                Some((_, _, w)) => P::encode_reply(&g.message, g.address, w, &mut buf).unwrap(),
                None => g.message.encode(g.address, &mut buf).unwrap(),
            };
            written_back(p, &buf[..n], wire);
        }
    }
    true
}

/// The length of `wire` after its preamble and unescaped (`framing.preamble`,
/// `framing.escaping`), or laid out in a long length form's width (`framing.length.long`): a
/// message's `frame_len`.
fn unescaped_len(p: &ir::Protocol, d: Direction, wire: &[u8]) -> usize {
    if p.framing.long.is_some() || p.framing.form.is_some() || p.framing.truncation.is_some() {
        return busspec_model::long::canonical(p, wire).map_or(wire.len(), |c| c.frame.len());
    }
    let frame = p.framing.after_preamble(wire);
    busspec_model::escape::unescape_bytes_of(&p.framing, d, frame).map_or(frame.len(), |f| f.len())
}

/// What an encoder wrote back is the frame decoded: byte for byte, but that it sends its
/// preamble whatever number of preamble bytes came before the frame.
fn written_back(p: &ir::Protocol, written: &[u8], wire: &[u8]) {
    // Payload truncation (`framing.truncation`): a frame that came with trailing zeros in its
    // payload is written back stripped of them.
    if p.framing.truncation.is_some() {
        let laid =
            busspec_model::long::canonical(p, wire).map_or(wire.to_vec(), |c| c.frame.to_vec());
        let sent = busspec_model::truncate::travel(p, laid);
        assert_eq!(written, sent, "written back stripped");
        return;
    }
    match &p.framing.preamble {
        Some(pre) => {
            let frame = p.framing.after_preamble(wire);
            let sent = [vec![pre.byte; usize::from(pre.send)], frame.to_vec()].concat();
            assert_eq!(written, sent, "written back");
        }
        None => assert_eq!(written, wire, "written back"),
    }
}

/// How many preamble bytes `wire` begins with (`framing.preamble`).
/// Both engines refused a frame: they say so in the same words. Returns false (refused).
fn same_words(
    g: Option<busspec_runtime::DecodeError>,
    i: Option<interp::DecodeError>,
    wire: &[u8],
) -> bool {
    if let (Some(g), Some(i)) = (g, i) {
        assert_eq!(g.to_string(), i.to_string(), "{wire:02X?}");
    }
    false
}

pub use busspec_model::mutate::{fix_length, mutations, reseal, reseal_as};

/// A small deterministic generator (xorshift), so failures replay.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
}

/// The message `name` of `P` from `values` through `from_fields`.
fn build_generated<M: Message>(name: &str, values: &[Value]) -> Option<M> {
    // Records lent flat, record after record.
    let flats: Vec<(Vec<i64>, usize)> = values
        .iter()
        .map(|v| match &v.raw {
            Raw::Records(r) => (r.concat(), r.first().map_or(0, Vec::len)),
            _ => (Vec::new(), 0),
        })
        .collect();
    M::from_fields(name, |n| {
        values
            .iter()
            .zip(&flats)
            .find(|(v, _)| v.name == n)
            .map(|(v, (flat, fields))| match &v.raw {
                Raw::Int(i) => FieldValue::Int(*i),
                Raw::Text(t) => FieldValue::Text(t),
                Raw::List(l) => FieldValue::List(Elements::I64(l)),
                Raw::Records(_) => FieldValue::Records(busspec_runtime::RecordList::Flat {
                    values: flat,
                    fields: *fields,
                }),
            })
    })
    .ok()
}

/// Both engines encode `values` as message `r` alike: the same bytes, or both refuse.
/// Returns whether they encoded.
pub fn encode_alike<P: Protocol>(
    p: &ir::Protocol,
    r: MessageRef,
    address: u8,
    values: &[Value],
) -> bool {
    encode_alike_over::<P>(p, r, address, values, None)
}

/// [`encode_alike`] of a reply whose checksum takes in its request's bytes
/// (`checksum_over_request`), over the request's frame `request`.
pub fn encode_alike_over<P: Protocol>(
    p: &ir::Protocol,
    r: MessageRef,
    address: u8,
    values: &[Value],
    request: Option<&[u8]>,
) -> bool {
    let name = &p.message(r).name;
    let mut buf = vec![0u8; P::MAX_FRAME_LEN];
    let n = match (r.direction, request) {
        (Direction::Request, _) => build_generated::<P::Request>(name, values)
            .and_then(|m| m.encode(address, &mut buf).ok()),
        (Direction::Response, None) => build_generated::<P::Response>(name, values)
            .and_then(|m| m.encode(address, &mut buf).ok()),
        (Direction::Response, Some(w)) => {
            build_generated::<P::Response>(name, values).and_then(|m| {
                m.encode_reply_over(address, P::Request::covered(w), &mut buf)
                    .ok()
            })
        }
    };
    let g = n.map(|n| buf[..n].to_vec());
    let i = interp::encode_with(
        p,
        r,
        address,
        values,
        request.and_then(|w| p.checksum_span(w)),
    );
    assert_eq!(
        g.is_some(),
        i.is_ok(),
        "{name} {values:?}: generated {g:02X?}, interpreter {i:?}"
    );
    if let (Some(g), Ok(i)) = (g, i) {
        assert_eq!(g, i, "{name} {values:?}");
        return true;
    }
    false
}

/// Every example of `p` and the frames mutated from it decode alike in both engines (replies
/// both alone and as the reply to their example request), and every example with a repeated
/// field encodes alike with its list made shorter, longer, emptied, filled to its bound and
/// past it, with values at the ends of the element type, its count left as the example's or
/// made to agree.
pub fn agree<P: Protocol>(p: &ir::Protocol) -> Tally {
    let mut t = Tally::default();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for e in &p.examples {
        let d = e.message.direction;
        let request = e.reply_to.and_then(|c| {
            let w = match &e.request {
                Some(w) => w,
                None => {
                    &p.examples
                        .iter()
                        .find(|x| {
                            x.message.direction == Direction::Request && x.message.index == c
                        })?
                        .wire
                }
            };
            let g = P::decode_request(w).ok()?.message;
            let i = interp::decode(p, Some(Direction::Request), None, w).ok()?;
            Some((g, i, w.clone()))
        });
        let mut frames = vec![e.wire.clone()];
        frames.extend(mutations(p, d, &e.wire));
        for (k, f) in frames.iter().enumerate() {
            let mut ok = check::<P>(p, d, None, f);
            if let Some((g, i, w)) = &request {
                ok |= check::<P>(p, d, Some((g, i, w)), f);
            }
            if k == 0 {
                assert!(ok, "{}: example {:02X?} refused", p.name, e.wire);
            }
            if ok {
                t.accepted += 1;
            } else {
                t.refused += 1;
            }
        }
        // Encode from the example's values, as the generated message visits them (count fields
        // and values following another are computed, not given).
        let m = p.message(e.message);
        if !m.is_variable() {
            continue;
        }
        let covered = request.as_ref().and_then(|r| p.checksum_span(&r.2));
        let decoded = interp::decode_with(p, Some(d), e.reply_to, covered, &e.wire).unwrap();
        let names: Vec<&str> = match d {
            Direction::Request => visited(&P::decode_request(&e.wire).unwrap().message),
            Direction::Response => visited(
                &match &request {
                    Some((r, _, w)) => P::Response::decode_as_reply_over(
                        &e.wire,
                        Some(r),
                        Some(P::Request::covered(w)),
                    ),
                    None => P::Response::decode_as_reply(&e.wire, None),
                }
                .unwrap()
                .message,
            ),
        }
        .into_iter()
        .map(|(n, _)| n)
        .collect();
        let given: Vec<Value> = decoded
            .values
            .iter()
            .filter(|v| names.contains(&&*v.name))
            .cloned()
            .collect();
        // A reply whose checksum takes in its request's bytes is encoded over them.
        let over = request
            .as_ref()
            .filter(|_| m.over_request.is_some())
            .map(|r| r.2.as_slice());
        assert!(encode_alike_over::<P>(
            p,
            e.message,
            decoded.address,
            &given,
            over
        ));
        // Each list in turn (a message may have several), the others as the example has them.
        for (_, rf, r) in m.repeats() {
            let (lo, hi) = if rf.ty == ir::FieldType::Bit {
                (0, 1)
            } else {
                busspec_model::interp::raw_limits(8 * rf.width as u32, rf.signed)
            };
            let bound = if rf.ty == ir::FieldType::Bit {
                r.max.div_ceil(8) * 8
            } else {
                r.max
            };
            let mut lens = vec![
                0,
                1,
                r.min,
                r.max,
                bound,
                bound + 1,
                r.min.saturating_sub(1),
            ];
            lens.extend((0..6).map(|_| rng.below(bound as u64 + 2) as usize));
            for n in lens {
                let list: Vec<i64> = (0..n)
                    .map(|k| match k % 4 {
                        0 => lo,
                        1 => hi,
                        // Anywhere between (a 64-bit or float element's: any bits).
                        _ => lo.wrapping_add(
                            rng.below((hi.wrapping_sub(lo) as u64).wrapping_add(1)) as i64,
                        ),
                    })
                    .collect();
                // Records: each field at the ends of its type or anywhere between.
                let records: Vec<Vec<i64>> = (0..n)
                    .map(|k| {
                        rf.record
                            .iter()
                            .map(|g| {
                                let (lo, hi) = g.raw_span();
                                match (k + rng.below(3) as usize) % 4 {
                                    0 => lo,
                                    1 => hi,
                                    _ => lo + rng.below((hi - lo) as u64 + 1) as i64,
                                }
                            })
                            .collect()
                    })
                    .collect();
                let mut values = given.clone();
                for v in &mut values {
                    if v.name == rf.name {
                        v.raw = if rf.is_record() {
                            Raw::Records(records.clone())
                        } else {
                            Raw::List(list.clone())
                        };
                    }
                }
                // As given (a count following another field may now disagree), then with every
                // integer the count could follow from set to agree.
                let mut tries = vec![values.clone()];
                for v in &values {
                    if let Raw::Int(_) = v.raw {
                        let mut w = values.clone();
                        for x in &mut w {
                            if x.name == v.name {
                                x.raw = Raw::Int(n as i64);
                            }
                        }
                        tries.push(w);
                    }
                }
                for values in tries {
                    if encode_alike_over::<P>(p, e.message, decoded.address, &values, over) {
                        t.encoded += 1;
                    } else {
                        t.encode_refused += 1;
                    }
                }
            }
        }
    }
    t
}

/// A view made owned: its address, its name and the owned message, or the view's refusal;
/// `None` where the direction has no view.
pub type Viewed<M> = Option<Result<(u8, &'static str, M), busspec_runtime::DecodeError>>;

/// A generated module's borrowed views (`RequestView`/`ResponseView`), each made owned
/// (`to_owned`) with its name, so they can be held to the owned decoders: see [`views!`].
pub trait Views: Protocol {
    fn view_request(frame: &[u8]) -> Viewed<Self::Request>;
    fn view_response(frame: &[u8], request: Option<&Self::Request>) -> Viewed<Self::Response>;
}

/// `views!(Proto, module, request, response)`: [`Views`] for `Proto` of generated `module`,
/// each direction named having a view (`-` where the generator made none: `None`).
#[macro_export]
macro_rules! views {
    (@req $m:ident, request, $f:expr) => {
        Some($m::RequestView::decode($f).map(|d| (d.address, d.message.name(), d.message.to_owned())))
    };
    (@req $m:ident, -, $f:expr) => {{
        let _ = $f;
        None
    }};
    (@res $m:ident, response, $f:expr, $r:expr) => {
        Some(match $r {
            Some(r) => $m::ResponseView::decode_reply($f, r),
            None => $m::ResponseView::decode($f),
        }
        .map(|d| (d.address, d.message.name(), d.message.to_owned())))
    };
    (@res $m:ident, -, $f:expr, $r:expr) => {{
        let _ = ($f, $r);
        None
    }};
    ($p:ty, $m:ident, $q:tt, $s:tt) => {
        impl $crate::agree::Views for $p {
            fn view_request(frame: &[u8]) -> $crate::agree::Viewed<$m::Request> {
                $crate::views!(@req $m, $q, frame)
            }
            fn view_response(
                frame: &[u8],
                request: Option<&$m::Request>,
            ) -> $crate::agree::Viewed<$m::Response> {
                $crate::views!(@res $m, $s, frame, request)
            }
        }
    };
}

/// The view of `wire` (as the reply to `request` where given) is made exactly where the owned
/// decode accepts it, refused with the same error where it does not, and made owned is the
/// owned message, with the same address and name. Returns (made, refused), `None` where the
/// direction has no view.
pub fn view_agrees<P: Views>(
    d: Direction,
    request: Option<&P::Request>,
    wire: &[u8],
) -> Option<bool> {
    match d {
        Direction::Request => {
            let v = P::view_request(wire)?;
            let o = P::decode_request(wire);
            match (&v, &o) {
                (Ok((a, n, m)), Ok(g)) => {
                    // Raw values as `visit` gives them: a NaN is its bits.
                    assert_eq!(
                        (*a, *n, visited(m)),
                        (g.address, g.message.name(), visited(&g.message)),
                        "{wire:02X?}"
                    );
                }
                (Err(ve), Err(ge)) => assert_eq!(ve, ge, "{wire:02X?}"),
                _ => panic!("view {v:?} / owned {o:?}: {wire:02X?}"),
            }
            Some(o.is_ok())
        }
        Direction::Response => {
            let v = P::view_response(wire, request)?;
            let o = P::Response::decode_as_reply(wire, request);
            match (&v, &o) {
                (Ok((a, n, m)), Ok(g)) => {
                    // Raw values as `visit` gives them: a NaN is its bits.
                    assert_eq!(
                        (*a, *n, visited(m)),
                        (g.address, g.message.name(), visited(&g.message)),
                        "{wire:02X?}"
                    );
                }
                (Err(ve), Err(ge)) => assert_eq!(ve, ge, "{wire:02X?}"),
                _ => panic!("view {v:?} / owned {o:?}: {wire:02X?}"),
            }
            Some(o.is_ok())
        }
    }
}

/// Every example of `p`, the frames mutated from it (`busspec_model::mutate`) and `random`
/// frames more from each (bytes changed at random, cut or lengthened, the length field made to
/// agree and the checksum resealed, or not) through [`view_agrees`], replies alone and as the
/// reply to their example request. Returns (frames made into views, frames refused by both).
pub fn views_agree<P: Views>(p: &ir::Protocol, random: usize) -> (usize, usize) {
    let (mut made, mut refused) = (0, 0);
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    let mut tally = |r: Option<bool>| match r {
        Some(true) => made += 1,
        Some(false) => refused += 1,
        None => {}
    };
    for e in &p.examples {
        let d = e.message.direction;
        let request = e.reply_to.and_then(|c| {
            let w = &p
                .examples
                .iter()
                .find(|x| x.message.direction == Direction::Request && x.message.index == c)?
                .wire;
            Some(P::decode_request(w).ok()?.message)
        });
        let mut frames = vec![e.wire.clone()];
        frames.extend(mutations(p, d, &e.wire));
        for _ in 0..random {
            let mut f = e.wire.clone();
            for _ in 0..=rng.below(3) {
                match rng.below(4) {
                    0 if f.len() > 1 => {
                        let n = f.len() - 1 - rng.below(3.min(f.len() as u64 - 1)) as usize;
                        f.truncate(n);
                    }
                    1 => {
                        for _ in 0..=rng.below(4) {
                            f.push(rng.next() as u8);
                        }
                    }
                    _ if !f.is_empty() => {
                        let i = rng.below(f.len() as u64) as usize;
                        f[i] = rng.next() as u8;
                    }
                    _ => {}
                }
            }
            if rng.below(2) == 0 {
                fix_length(p, d, &mut f);
            }
            if rng.below(4) != 0 {
                reseal_as(p, d, &mut f);
            }
            frames.push(f);
        }
        for f in &frames {
            tally(view_agrees::<P>(d, None, f));
            if let Some(r) = &request {
                tally(view_agrees::<P>(d, Some(r), f));
            }
        }
    }
    (made, refused)
}
