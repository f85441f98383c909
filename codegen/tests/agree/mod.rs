//! Generated code held to the interpreter (`busspec_model::interp`, the oracle) on frames of
//! variable length: every example, frames mutated from them (bytes changed, counts and length
//! fields that lie, frames cut and lengthened, with and without a good checksum), and messages
//! encoded from the examples' values with lists of other lengths and values.
//!
//! Shared by the test files that include generated code with repeated fields.

#![allow(dead_code, unused_imports)]

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{self, Direction, MessageRef};
use busspec_runtime::{Elements, FieldValue, Message, Protocol};

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
/// request and the interpreter's frame of it), asserts they agree on acceptance and values, and
/// that the generated encoder writes an accepted frame back byte for byte; returns whether it
/// was accepted.
pub fn check<P: Protocol>(
    p: &ir::Protocol,
    d: Direction,
    request: Option<(&P::Request, &interp::Frame)>,
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
            assert_eq!(g.message.frame_len(), unescaped_len(p, wire));
            let n = g.message.encode(g.address, &mut buf).unwrap();
            written_back(p, &buf[..n], wire);
        }
        Direction::Response => {
            let g = P::decode_response_for(wire, request.map(|r| r.0));
            let i = match request {
                Some((_, f)) => interp::decode_reply(p, f, wire),
                None => interp::decode(p, Some(d), None, wire),
            };
            assert_eq!(g.is_ok(), i.is_ok(), "{wire:02X?}: {g:?} / {i:?}");
            let (g, i) = match (g, i) {
                (Ok(g), Ok(i)) => (g, i),
                (g, i) => return same_words(g.err(), i.err(), wire),
            };
            assert_eq!(g.address, i.address);
            same(p, &g.message, &i, wire);
            assert_eq!(g.message.frame_len(), unescaped_len(p, wire));
            if let Some((r, _)) = request {
                assert!(P::answers(r, &g.message), "{wire:02X?}");
            }
            let n = g.message.encode(g.address, &mut buf).unwrap();
            written_back(p, &buf[..n], wire);
        }
    }
    true
}

/// The length of `wire` after its preamble and unescaped (`framing.preamble`,
/// `framing.escaping`), or laid out in a long length form's width (`framing.length.long`): a
/// message's `frame_len`.
fn unescaped_len(p: &ir::Protocol, wire: &[u8]) -> usize {
    if p.framing.long.is_some() || p.framing.form.is_some() {
        return busspec_model::long::canonical(p, wire).map_or(wire.len(), |c| c.frame.len());
    }
    let frame = p.framing.after_preamble(wire);
    busspec_model::escape::unescape_bytes(&p.framing, frame).map_or(frame.len(), |f| f.len())
}

/// What an encoder wrote back is the frame decoded: byte for byte, but that it sends its
/// preamble whatever number of preamble bytes came before the frame.
fn written_back(p: &ir::Protocol, written: &[u8], wire: &[u8]) {
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

pub use busspec_model::mutate::{fix_length, mutations, reseal};

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

/// The message `name` of `P` from `values` through `from_fields`, encoded for `address`.
fn encode_generated<M: Message>(
    name: &str,
    address: u8,
    values: &[Value],
    buf: &mut [u8],
) -> Option<Vec<u8>> {
    // Records lent flat, record after record.
    let flats: Vec<(Vec<i64>, usize)> = values
        .iter()
        .map(|v| match &v.raw {
            Raw::Records(r) => (r.concat(), r.first().map_or(0, Vec::len)),
            _ => (Vec::new(), 0),
        })
        .collect();
    let m = M::from_fields(name, |n| {
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
    .ok()?;
    let n = m.encode(address, buf).ok()?;
    Some(buf[..n].to_vec())
}

/// Both engines encode `values` as message `r` alike: the same bytes, or both refuse.
/// Returns whether they encoded.
pub fn encode_alike<P: Protocol>(
    p: &ir::Protocol,
    r: MessageRef,
    address: u8,
    values: &[Value],
) -> bool {
    let name = &p.message(r).name;
    let mut buf = vec![0u8; P::MAX_FRAME_LEN];
    let g = match r.direction {
        Direction::Request => encode_generated::<P::Request>(name, address, values, &mut buf),
        Direction::Response => encode_generated::<P::Response>(name, address, values, &mut buf),
    };
    let i = interp::encode(p, r, address, values);
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
            let w = &p
                .examples
                .iter()
                .find(|x| x.message.direction == Direction::Request && x.message.index == c)?
                .wire;
            let g = P::decode_request(w).ok()?.message;
            let i = interp::decode(p, Some(Direction::Request), None, w).ok()?;
            Some((g, i))
        });
        let mut frames = vec![e.wire.clone()];
        frames.extend(mutations(p, d, &e.wire));
        for (k, f) in frames.iter().enumerate() {
            let mut ok = check::<P>(p, d, None, f);
            if let Some((g, i)) = &request {
                ok |= check::<P>(p, d, Some((g, i)), f);
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
        let decoded = interp::decode(p, Some(d), e.reply_to, &e.wire).unwrap();
        let names: Vec<&str> = match d {
            Direction::Request => visited(&P::decode_request(&e.wire).unwrap().message),
            Direction::Response => visited(
                &P::decode_response_for(&e.wire, request.as_ref().map(|r| &r.0))
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
        assert!(encode_alike::<P>(p, e.message, decoded.address, &given));
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
                        _ => lo + rng.below((hi - lo) as u64 + 1) as i64,
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
                    if encode_alike::<P>(p, e.message, decoded.address, &values) {
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
