//! A device simulator for any spec, by its `device:` section ([`crate::device`]): the
//! interpreter decodes each request, the device's spaces answer it or change, and the
//! interpreter encodes the reply. Sans-IO and clock-free: [`Sim::answer`] takes one request
//! frame and returns the reply to send, if any (`busspec sim` puts it on a line, the soak on a
//! simulated bus).
//!
//! What the device does is the section's rules, stated there; this module decides only what
//! the section leaves open:
//! - a frame that does not decode strictly is answered only when it fails a rule of the spec
//!   alone (a value out of its range, the broadcast rule) and comes to this device's address:
//!   with the command's `invalid` refusal, if it has one; anything else (noise, a checksum
//!   error, a frame for another address) gets silence, as on a real bus;
//! - a broadcast is carried out by every device and answered by none unless the command's
//!   `broadcast.answered` says so, refusals included;
//! - a write whose values do not fit the space's elements is refused as `outside`, and a
//!   staged write is checked when it is staged, so a commit never fails half-way;
//! - a reply the spec's rules cannot carry is not sent: Dynamixel's status packet to a READ
//!   must hold as many bytes as the READ asked for, so a READ of 0 bytes (out of the spec's
//!   range) gets silence, not a range error.

use std::sync::Arc;

use crate::device::{element_bits, Action, Refusal, Rule, Source, Space};
use crate::interp::{self, Raw, Value};
use crate::ir::{Direction, FieldType, Follows, Leaf, MessageRef, Protocol};

/// Elements per page: a write copies one page where a clone of the device shares it.
const PAGE: usize = 256;

/// A space's elements, in pages shared between clones until written.
#[derive(Debug, Clone)]
struct Store {
    pages: Vec<Arc<[i64; PAGE]>>,
    size: u32,
}

impl PartialEq for Store {
    fn eq(&self, other: &Store) -> bool {
        self.size == other.size
            && self
                .pages
                .iter()
                .zip(&other.pages)
                .all(|(a, b)| Arc::ptr_eq(a, b) || a == b)
    }
}

impl Store {
    fn new(s: &Space) -> Store {
        let zero = Arc::new([0i64; PAGE]);
        let n = (s.size as usize).div_ceil(PAGE);
        let mut store = Store {
            pages: vec![zero; n],
            size: s.size,
        };
        for &(at, v) in &s.initial {
            store.set(at, v);
        }
        store
    }

    fn get(&self, i: u32) -> i64 {
        let i = i as usize;
        self.pages.get(i / PAGE).map_or(0, |p| p[i % PAGE])
    }

    fn set(&mut self, i: u32, v: i64) {
        let i = i as usize;
        if let Some(p) = self.pages.get_mut(i / PAGE) {
            Arc::make_mut(p)[i % PAGE] = v;
        }
    }
}

/// A write that waits for a commit: space, first element, values.
type Staged = (usize, u32, Vec<i64>);

/// One simulated device of a protocol.
#[derive(Debug, Clone)]
pub struct Sim {
    p: Arc<Protocol>,
    address: u8,
    spaces: Vec<Store>,
    staged: Vec<Staged>,
}

impl PartialEq for Sim {
    /// Two devices are alike when their address, data and staged writes are (of one protocol).
    fn eq(&self, other: &Sim) -> bool {
        self.address == other.address && self.spaces == other.spaces && self.staged == other.staged
    }
}

/// Why a request is refused.
enum Refused {
    Outside,
}

impl Sim {
    /// A device of `p` at `address` (0 for a protocol without addresses), its spaces at their
    /// initial values.
    pub fn new(p: Arc<Protocol>, address: u8) -> Sim {
        let spaces = p.device.spaces.iter().map(Store::new).collect();
        Sim {
            p,
            address,
            spaces,
            staged: Vec::new(),
        }
    }

    pub fn address(&self) -> u8 {
        self.address
    }

    pub fn protocol(&self) -> &Protocol {
        &self.p
    }

    /// Element `at` of the space called `space`, if there is one.
    pub fn element(&self, space: &str, at: u32) -> Option<i64> {
        let i = self.p.device.space(space)?;
        (at < self.spaces[i].size).then(|| self.spaces[i].get(at))
    }

    /// Sets element `at` of `space` (for tests and set-up); false where there is none or the
    /// value does not fit.
    pub fn set_element(&mut self, space: &str, at: u32, value: i64) -> bool {
        let Some(i) = self.p.device.space(space) else {
            return false;
        };
        let s = &self.p.device.spaces[i];
        if at >= s.size || !(s.min..=s.max).contains(&value) {
            return false;
        }
        self.spaces[i].set(at, value);
        true
    }

    /// Handles the bytes a device received between two silences on the line: one request
    /// frame, or, where the master sent frames back to back (commands that get no reply, at a
    /// rate the protocol allows with no gap between frames: CRSF, Pelco P), several, which the
    /// device tells apart by the protocol's framing as a real one does (its start bytes,
    /// length and checksum) and answers each. Returns the reply to send (each frame's, one
    /// after the other), if any.
    pub fn answer(&mut self, bytes: &[u8]) -> Option<Vec<u8>> {
        if let Some(reply) = self.answer_frame(bytes) {
            return Some(reply);
        }
        // Only bytes that are no frame on their own may hold several.
        let p = Arc::clone(&self.p);
        if interp::decode(&p, Some(Direction::Request), None, bytes).is_ok() {
            return None;
        }
        let mut stream = crate::stream::StreamDecoder::new(&p, Some(Direction::Request));
        let mut events = stream.push(bytes);
        events.extend(stream.flush());
        let frames: Vec<&[u8]> = events
            .iter()
            .filter(|e| {
                matches!(
                    e,
                    crate::stream::Event::Frame { .. } | crate::stream::Event::OutOfSpec { .. }
                )
            })
            .map(crate::stream::Event::bytes)
            .collect();
        if frames.len() < 2 {
            return None;
        }
        let mut reply = Vec::new();
        for frame in frames {
            reply.extend(self.answer_frame(frame).unwrap_or_default());
        }
        (!reply.is_empty()).then_some(reply)
    }

    /// Handles one request frame; returns the reply to send, if any.
    fn answer_frame(&mut self, frame: &[u8]) -> Option<Vec<u8>> {
        let p = Arc::clone(&self.p);
        let p = &*p;
        let addressed = p.framing.has_address();
        let request = match interp::decode(p, Some(Direction::Request), None, frame) {
            Ok(f) => f,
            Err(e) if crate::stream::breaks_spec(&e) => {
                let relaxed = crate::stream::relaxed(p);
                let (f, _) = crate::stream::decode_lenient(
                    p,
                    &relaxed,
                    Some(Direction::Request),
                    None,
                    frame,
                )
                .ok()?;
                if f.message.direction != Direction::Request
                    || (addressed && f.address != self.address)
                {
                    return None;
                }
                let f = f.into_owned();
                let r = p.device.rules[f.message.index].invalid.clone()?;
                return self.refuse(p, &f, frame, &r);
            }
            Err(_) => return None,
        };
        let broadcast = addressed && p.framing.address.broadcast == Some(request.address);
        if addressed && request.address != self.address && !broadcast {
            return None;
        }
        let command = p.message(request.message);
        let answered = !broadcast || command.broadcast.as_ref().is_some_and(|b| b.answered);
        let rule = p.device.rules[request.message.index].clone();
        // A command for the devices it lists (Dynamixel's SYNC READ): the others ignore it.
        if let Some(list) = &rule.listed {
            let listed = match request.get(list) {
                Some(Raw::List(ids)) => ids.contains(&i64::from(self.address)),
                _ => false,
            };
            if !listed {
                return None;
            }
        }
        match self.act(p, &rule, &request) {
            Err(Refused::Outside) => {
                let r = rule.outside.as_ref()?;
                if !answered {
                    return None;
                }
                self.refuse(p, &request, frame, r)
            }
            Ok(into) => {
                if !answered {
                    return None;
                }
                let reply = rule.reply?;
                let given = into
                    .into_iter()
                    .map(|(name, raw)| Value {
                        name: name.into(),
                        raw,
                    })
                    .collect();
                self.reply(p, &request, frame, reply, given)
            }
        }
    }

    /// Carries out `rule` for `request`: the reply fields a read fills, or none.
    fn act(
        &mut self,
        p: &Protocol,
        rule: &Rule,
        request: &interp::Frame,
    ) -> Result<Vec<(String, Raw)>, Refused> {
        let int = |name: &str| match request.get(name) {
            Some(Raw::Int(i)) => *i,
            _ => 0,
        };
        let list = |name: &str| match request.get(name) {
            Some(Raw::List(l)) => l.clone(),
            _ => Vec::new(),
        };
        match &rule.action {
            Action::Nothing => Ok(Vec::new()),
            Action::Read {
                space,
                start,
                count,
                into,
                at,
            } => {
                let store = &self.spaces[*space];
                let mut given = Vec::new();
                if let (Some(start), Some(into)) = (start, into) {
                    let n = count.as_deref().map_or(1, int);
                    let from = self.span(*space, int(start), n)?;
                    let values = (from..from + n as u32).map(|i| store.get(i)).collect();
                    given.push((into.clone(), Raw::List(values)));
                }
                for a in at {
                    let elements: Vec<i64> = (a.element..a.element + a.elements)
                        .map(|i| store.get(i))
                        .collect();
                    given.push((a.field.clone(), Raw::Int(a.value(&elements))));
                }
                Ok(given)
            }
            Action::Write {
                space,
                start,
                count,
                source,
                staged,
            } => {
                let values = match source {
                    Source::Value(f) => vec![int(f)],
                    Source::List(f) => {
                        let mut l = list(f);
                        if let Some(c) = count {
                            let n = usize::try_from(int(c)).map_err(|_| Refused::Outside)?;
                            if n > l.len() {
                                return Err(Refused::Outside);
                            }
                            l.truncate(n);
                        }
                        l
                    }
                    Source::Records {
                        list: l,
                        length,
                        big: None,
                    } => {
                        let len = usize::try_from(int(length)).map_err(|_| Refused::Outside)?;
                        let records = list(l);
                        let mine = records
                            .chunks(len + 1)
                            .find(|r| r.len() == len + 1 && r[0] == i64::from(self.address));
                        match mine {
                            Some(r) => r[1..].to_vec(),
                            // No record for this device: nothing to do.
                            None => return Ok(Vec::new()),
                        }
                    }
                    Source::Records {
                        list: l,
                        length,
                        big: Some(big),
                    } => {
                        let len = u32::try_from(int(length)).map_err(|_| Refused::Outside)?;
                        let mine = match request.get(l) {
                            Some(Raw::Records(rs)) => rs
                                .iter()
                                .find(|r| r.first() == Some(&i64::from(self.address)))
                                .and_then(|r| r.get(1).copied()),
                            _ => None,
                        };
                        // No record for this device: nothing to do.
                        let Some(data) = mine else {
                            return Ok(Vec::new());
                        };
                        let bits = element_bits(p.device.spaces[*space].ty);
                        if u64::from(len) * u64::from(bits) > 64 {
                            return Err(Refused::Outside);
                        }
                        let mask = (1i64 << bits) - 1;
                        (0..len)
                            .map(|k| {
                                let k = if *big { len - 1 - k } else { k };
                                data >> (bits * k) & mask
                            })
                            .collect()
                    }
                };
                let s = &p.device.spaces[*space];
                let values: Vec<i64> = if s.ty == FieldType::Bit {
                    values.into_iter().map(|v| i64::from(v != 0)).collect()
                } else {
                    values
                };
                if values.iter().any(|v| !(s.min..=s.max).contains(v)) {
                    return Err(Refused::Outside);
                }
                let at = self.span(*space, int(start), values.len() as i64)?;
                if *staged {
                    // One staged write at a time: a second replaces the first (Dynamixel's
                    // REG_WRITE), so a request sent again stages the same write once.
                    self.staged = vec![(*space, at, values)];
                } else {
                    self.write(*space, at, &values);
                }
                Ok(Vec::new())
            }
            Action::Commit => {
                for (space, at, values) in std::mem::take(&mut self.staged) {
                    self.write(space, at, &values);
                }
                Ok(Vec::new())
            }
            Action::Reset => {
                self.spaces = p.device.spaces.iter().map(Store::new).collect();
                self.staged.clear();
                Ok(Vec::new())
            }
        }
    }

    /// The first element of `n` from `start` in `space`, if they all lie in it.
    fn span(&self, space: usize, start: i64, n: i64) -> Result<u32, Refused> {
        let size = i64::from(self.spaces[space].size);
        if start < 0 || n < 0 || start.saturating_add(n) > size {
            return Err(Refused::Outside);
        }
        Ok(start as u32)
    }

    fn write(&mut self, space: usize, at: u32, values: &[i64]) {
        for (k, &v) in values.iter().enumerate() {
            self.spaces[space].set(at + k as u32, v);
        }
    }

    fn refuse(
        &self,
        p: &Protocol,
        request: &interp::Frame,
        request_wire: &[u8],
        r: &Refusal,
    ) -> Option<Vec<u8>> {
        let given = r
            .values
            .iter()
            .map(|(n, v)| Value {
                name: n.clone().into(),
                raw: Raw::Int(*v),
            })
            .collect();
        self.reply(p, request, request_wire, r.reply, given)
    }

    /// Encodes response `reply` to `request`: the values given, then those of the request's
    /// fields of the same names, then those that follow from the request, then each field's
    /// first valid value. `request_wire`: the request's frame, whose bytes a reply's checksum
    /// may take in (`checksum_over_request`).
    fn reply(
        &self,
        p: &Protocol,
        request: &interp::Frame,
        request_wire: &[u8],
        reply: usize,
        mut values: Vec<Value>,
    ) -> Option<Vec<u8>> {
        let m = &p.responses[reply];
        // Fields encode computes: a list's count, and values that follow another field.
        let request_int = |name: &str| match request.get(name) {
            Some(Raw::Int(i)) => Some(*i),
            _ => None,
        };
        for leaf in m.leaves() {
            let name = leaf.name().to_owned();
            if values.iter().any(|v| v.name == name) {
                continue;
            }
            let raw = match leaf {
                Leaf::Bits(_, _, b) => {
                    if b.constant.is_some() {
                        continue;
                    }
                    match request.get(&name) {
                        Some(r @ Raw::Int(_)) => r.clone(),
                        _ => Raw::Int(first_valid(b.range, None)),
                    }
                }
                Leaf::Field(i, f) => {
                    // Encoding computes it (a constant, a count, a value that follows another).
                    if m.is_derived(i) {
                        continue;
                    }
                    if let Some(r) = request.get(&name) {
                        let fits = match r {
                            Raw::List(_) => f.is_list() && !f.is_record(),
                            Raw::Records(_) => f.is_record(),
                            Raw::Text(_) => f.is_ascii(),
                            Raw::Int(_) => !f.is_list() && !f.is_ascii(),
                        };
                        if fits {
                            values.push(Value {
                                name: name.into(),
                                raw: r.clone(),
                            });
                            continue;
                        }
                    }
                    if let Some(Follows::Request(rel)) = &f.follows {
                        if let Some(v) = request_int(&rel.field) {
                            values.push(Value {
                                name: name.into(),
                                raw: Raw::Int(rel.apply(v)),
                            });
                            continue;
                        }
                    }
                    if let Some(pk) = &f.packed {
                        Raw::List(vec![first_valid(f.range, None); pk.count])
                    } else if let Some(r) = &f.repeat {
                        let n = r
                            .request
                            .as_ref()
                            .and_then(|rel| request_int(&rel.field).map(|v| rel.apply(v)))
                            .and_then(|n| usize::try_from(n).ok())
                            .unwrap_or(r.min);
                        if f.is_ascii() {
                            // Text (counted, or up to a terminator): as many spaces as it
                            // takes at least, none of them its terminator.
                            let c = if f.terminator() == Some(b' ') {
                                b'_'
                            } else {
                                b' '
                            };
                            Raw::Text(vec![c; n])
                        } else if f.is_record() {
                            let rec = f
                                .record
                                .iter()
                                .map(|g| {
                                    let first_enum = g.enumeration.and_then(|e| {
                                        p.enums[e].values.first().map(|v| v.value as i64)
                                    });
                                    first_valid(g.range, first_enum)
                                })
                                .collect();
                            Raw::Records(vec![rec; n])
                        } else {
                            Raw::List(vec![first_valid(f.range, None); n])
                        }
                    } else if f.is_ascii() {
                        Raw::Text(vec![b' '; f.width])
                    } else {
                        let first_enum = f
                            .enumeration
                            .and_then(|e| p.enums[e].values.first().map(|v| v.value as i64));
                        Raw::Int(first_valid(f.range, first_enum))
                    }
                }
            };
            values.push(Value {
                name: name.into(),
                raw,
            });
        }
        // A reply carries the device's address where replies carry one (with a layout per
        // direction, requests alone may: RoboClaw's replies have none).
        let address = if p.framing.has_address_in(Direction::Response) {
            self.address
        } else {
            0
        };
        let r = MessageRef {
            direction: Direction::Response,
            index: reply,
        };
        let covered = p.checksum_span(request_wire);
        interp::encode_with(p, r, address, &values, covered).ok()
    }
}

/// 0 where the range (and enum) allow it, else the range's minimum or the enum's first value.
fn first_valid(range: Option<(i64, i64)>, first_enum: Option<i64>) -> i64 {
    if let Some(e) = first_enum {
        return e;
    }
    match range {
        Some((lo, hi)) if !(lo..=hi).contains(&0) => lo,
        _ => 0,
    }
}
