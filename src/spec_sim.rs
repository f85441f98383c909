//! Simulated devices of any spec, by its `device:` section (`busspec_model::sim`): on a line
//! (`busspec sim`) and on the soak's simulated bus, with a random request mix drawn from the
//! spec itself.

use std::sync::Arc;
use std::time::Duration;

use busspec_link::sim::Device;
use busspec_link::soak::{SoakConfig, SoakReport};
use busspec_link::Link;
use busspec_model::device::{Action, Source};
use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{Direction, FieldType, Leaf, MessageRef};
use busspec_model::sim::Sim;
use busspec_model::Protocol;

/// A device of any spec on a simulated or real line.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecDevice(pub Sim);

impl Device for SpecDevice {
    fn on_frame(&mut self, frame: &[u8], _now: Duration) -> Option<Vec<u8>> {
        self.0.answer(frame)
    }
    fn address(&self) -> u8 {
        self.0.address()
    }
}

/// The address a protocol's first simulated device takes: the spec's default address, else
/// the first device address from 1 (0 where that is the only one, or the protocol has none).
pub fn first_address(p: &Protocol) -> u8 {
    let a = &p.framing.address;
    if !p.framing.has_address() {
        return 0;
    }
    a.default.unwrap_or(if (a.min..=a.max).contains(&1) {
        1
    } else {
        a.min
    })
}

/// The `i`-th device's address on a soak bus: consecutive from [`first_address`].
pub fn nth_address(p: &Protocol, i: u8) -> u8 {
    if !p.framing.has_address() {
        return 0;
    }
    first_address(p)
        .saturating_add(i)
        .min(p.framing.address.max)
}

/// The most elements a random list gets, so frames stay short and the soak quick.
const MAX_ELEMENTS: i64 = 16;

/// A random request frame of `p` for the device at `address`, from the soak's mix: any command,
/// every value within its range, and where the command reads or writes a space, mostly within
/// it and one time in eight past its end (for the refusal). `None` where the draw does not
/// encode (a spec whose rules the draw does not meet); the caller draws again.
pub fn random_request(p: &Protocol, rng: &mut fastrand::Rng, address: u8) -> Option<Vec<u8>> {
    if p.commands.is_empty() {
        return None;
    }
    let ci = rng.usize(0..p.commands.len());
    let m = &p.commands[ci];
    let rule = &p.device.rules[ci];
    // Fields a space rule sets: start, count, and the list's length.
    let mut fixed: Vec<(String, Raw)> = Vec::new();
    let space_of = |space: usize| &p.device.spaces[space];
    let limits = |name: &str| -> (i64, i64) {
        m.fields
            .iter()
            .find(|f| f.name == name)
            .map_or((0, 0), |f| {
                f.range
                    .unwrap_or_else(|| interp::raw_limits(8 * f.width as u32, f.signed))
            })
    };
    let span = |rng: &mut fastrand::Rng, size: u32, n: i64, start: &str| -> i64 {
        let (lo, hi) = limits(start);
        let size = i64::from(size);
        let s = if rng.u8(0..8) == 0 {
            (size - n + 1).max(0)
        } else {
            rng.i64(0..=(size - n).max(0))
        };
        s.clamp(lo, hi)
    };
    match &rule.action {
        Action::Read {
            space,
            start: Some(start),
            count,
            ..
        } => {
            let n = match count {
                Some(c) => {
                    let (lo, hi) = limits(c.as_str());
                    let n = rng.i64(lo.max(1)..=hi.min(MAX_ELEMENTS).max(lo.max(1)));
                    fixed.push((c.clone(), Raw::Int(n)));
                    n
                }
                None => 1,
            };
            let s = span(rng, space_of(*space).size, n, start);
            fixed.push((start.clone(), Raw::Int(s)));
        }
        Action::Write {
            space,
            start,
            count,
            source,
            ..
        } => {
            let sp = space_of(*space);
            let element = |rng: &mut fastrand::Rng| {
                if sp.ty == FieldType::Bit {
                    rng.i64(0..=1)
                } else {
                    rng.i64(sp.min.max(0)..=sp.max.min(0xFFFF))
                }
            };
            let n = match count {
                Some(c) => {
                    let (lo, hi) = limits(c.as_str());
                    let n = rng.i64(lo.max(1)..=hi.min(MAX_ELEMENTS).max(lo.max(1)));
                    fixed.push((c.clone(), Raw::Int(n)));
                    n
                }
                None => rng.i64(1..=4),
            };
            match source {
                Source::Value(v) => {
                    // A value field with an enum (a Modbus coil) keeps its enum values.
                    let n = 1;
                    let s = span(rng, sp.size, n, start);
                    fixed.push((start.clone(), Raw::Int(s)));
                    if m.fields
                        .iter()
                        .any(|f| f.name == *v && f.enumeration.is_none())
                    {
                        fixed.push((v.clone(), Raw::Int(element(rng))));
                    }
                }
                Source::List(l) => {
                    let s = span(rng, sp.size, n, start);
                    fixed.push((start.clone(), Raw::Int(s)));
                    let mut list: Vec<i64> = (0..n).map(|_| element(rng)).collect();
                    if sp.ty == FieldType::Bit {
                        list.resize(list.len().div_ceil(8) * 8, 0);
                    }
                    fixed.push((l.clone(), Raw::List(list)));
                }
                Source::Records { list, length, big } => {
                    let s = span(rng, sp.size, n, start);
                    fixed.push((start.clone(), Raw::Int(s)));
                    fixed.push((length.clone(), Raw::Int(n)));
                    let elements: Vec<i64> = (0..n).map(|_| element(rng)).collect();
                    match big {
                        None => {
                            let mut records = vec![i64::from(address)];
                            records.extend(elements);
                            fixed.push((list.clone(), Raw::List(records)));
                        }
                        // One record: the address and the elements as one number.
                        Some(big) => {
                            let bits = busspec_model::device::element_bits(sp.ty);
                            let mut data = 0i64;
                            for (k, e) in elements.iter().enumerate() {
                                let k = if *big {
                                    n as u32 - 1 - k as u32
                                } else {
                                    k as u32
                                };
                                data |= (e & ((1i64 << bits) - 1)) << (bits * k);
                            }
                            fixed.push((
                                list.clone(),
                                Raw::Records(vec![vec![i64::from(address), data]]),
                            ));
                        }
                    }
                }
            }
        }
        _ => {}
    }
    // A command only the devices it lists answer: this one alone (another listed device on
    // the soak's bus would answer too).
    if let Some(l) = &rule.listed {
        fixed.push((l.clone(), Raw::List(vec![i64::from(address)])));
    }
    let mut values: Vec<Value> = Vec::new();
    for leaf in m.leaves() {
        let name = leaf.name().to_owned();
        if let Some((_, raw)) = fixed.iter().find(|(n, _)| *n == name) {
            values.push(Value {
                name: name.into(),
                raw: raw.clone(),
            });
            continue;
        }
        let raw = match leaf {
            Leaf::Bits(_, _, b) => {
                if b.constant.is_some() {
                    continue;
                }
                let (lo, hi) = b
                    .range
                    .unwrap_or_else(|| interp::raw_limits(u32::from(b.width()), b.signed));
                Raw::Int(rng.i64(lo..=hi))
            }
            Leaf::Field(i, f) => {
                // Encoding computes it (a constant, a count, a value that follows another).
                if m.is_derived(i) {
                    continue;
                }
                let one = |rng: &mut fastrand::Rng| -> i64 {
                    if f.ty == FieldType::Bit {
                        return rng.i64(0..=1);
                    }
                    if let Some(e) = f.enumeration.map(|e| &p.enums[e]) {
                        if !e.values.is_empty() {
                            return e.values[rng.usize(0..e.values.len())].value as i64;
                        }
                    }
                    if let Some(fs) = f.flags.map(|x| &p.flags[x]) {
                        return fs
                            .bits
                            .iter()
                            .filter(|_| rng.bool())
                            .fold(0, |acc, b| acc | (1 << b.bit));
                    }
                    // Packed elements: each within its bits.
                    let bits = f.packed.map_or(8 * f.width as u32, |pk| pk.bits);
                    let (lo, hi) = f
                        .range
                        .unwrap_or_else(|| interp::raw_limits(bits, f.signed));
                    // A float's range is of raw bits, which do not order as its numbers (a
                    // range from -2.0 to 2.0 runs from 0xC0000000 down to 0x40000000), nor do a
                    // u64's past i64::MAX: one of its ends, each in it.
                    if lo > hi || (f.is_float() && f.range.is_some()) {
                        if rng.bool() {
                            lo
                        } else {
                            hi
                        }
                    } else {
                        rng.i64(lo..=hi)
                    }
                };
                if let Some(pk) = &f.packed {
                    Raw::List((0..pk.count).map(|_| one(rng)).collect())
                } else if let Some(r) = &f.repeat {
                    let hi = (r.max as i64).min(MAX_ELEMENTS).max(r.min as i64);
                    let n = rng.i64(r.min as i64..=hi);
                    let mut list: Vec<i64> = (0..n).map(|_| one(rng)).collect();
                    if f.ty == FieldType::Bit {
                        list.resize(list.len().div_ceil(8).max(1) * 8, 0);
                    }
                    Raw::List(list)
                } else if f.is_ascii() {
                    Raw::Text((0..f.width).map(|_| rng.u8(b'0'..=b'z')).collect())
                } else {
                    Raw::Int(one(rng))
                }
            }
        };
        values.push(Value {
            name: name.into(),
            raw,
        });
    }
    let r = MessageRef {
        direction: Direction::Request,
        index: ci,
    };
    interp::encode(p, r, address, &values).ok()
}

/// Devices of `p` at `addresses`.
pub fn devices(p: &Arc<Protocol>, addresses: &[u8]) -> Vec<SpecDevice> {
    addresses
        .iter()
        .map(|&a| SpecDevice(Sim::new(Arc::clone(p), a)))
        .collect()
}

/// Draws the soak's mix makes for one request before it takes the fallback (below).
const MAX_DRAWS: usize = 10_000;

/// A request of the mix for the device at `address`, through `P`'s codec: drawn again while
/// the codec refuses the draw, at most [`MAX_DRAWS`] times.
fn draw<P: Link>(p: &Protocol, rng: &mut fastrand::Rng, address: u8) -> Option<P::Request> {
    (0..MAX_DRAWS).find_map(|_| {
        let frame = random_request(p, rng, address)?;
        P::decode_request(&frame).ok().map(|d| d.message)
    })
}

/// The soak of `P` (a generated protocol, or one read at run time) against devices of `spec`'s
/// `device:` section, with the request mix drawn from the spec. Each device's first request is
/// drawn before the soak, with a generator of its own: a spec where no draw meets its rules is
/// refused, and a request the mix cannot draw in [`MAX_DRAWS`] tries is that one, so no spec
/// can hang the soak. A protocol without addresses gets one device.
pub fn soak<P: Link>(spec: Arc<Protocol>, mut config: SoakConfig) -> Result<SoakReport, String> {
    // Frames without an address reach every device and each answers: one device on such a bus.
    if !spec.framing.has_address() {
        config.devices = 1;
    }
    let mut first = fastrand::Rng::with_seed(config.seed);
    let fallback: Vec<(u8, P::Request)> = (0..config.devices.max(1))
        .map(|i| {
            let a = nth_address(&spec, i);
            draw::<P>(&spec, &mut first, a).map(|r| (a, r)).ok_or_else(|| {
                format!(
                    "error: {}: no request drawn from the spec encodes ({MAX_DRAWS} draws): nothing to soak",
                    spec.name
                )
            })
        })
        .collect::<Result<_, _>>()?;
    let for_devices = Arc::clone(&spec);
    Ok(busspec_link::soak::run_with::<P, _>(
        config,
        move |i| {
            SpecDevice(Sim::new(
                Arc::clone(&for_devices),
                nth_address(&for_devices, i),
            ))
        },
        move |rng, d| {
            draw::<P>(&spec, rng, d.address()).unwrap_or_else(|| {
                fallback
                    .iter()
                    .find(|(a, _)| *a == d.address())
                    .map_or(fallback[0].1, |(_, r)| *r)
            })
        },
    ))
}
