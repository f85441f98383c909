//! What the benches feed every contender: a sequential stream of mixed frames built from the
//! spec's own example frames, and a synthetic bus capture with noise.

use std::ops::Range;

use busspec_model::ir::{Direction, Protocol};
use busspec_protocols::dynamixel::Dynamixel;
use busspec_protocols::modbus::Modbus;
use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol as _;

/// The validated spec of generated protocol `P`: the text it was generated from
/// ([`Source::spec_yaml`](busspec_runtime::Source::spec_yaml)), loaded by the interpreter's loader.
pub fn spec<P: busspec_protocols::Protocol>() -> Protocol {
    busspec_model::load_str(P::NAME, P::SOURCE.spec_yaml).unwrap_or_else(|d| panic!("{d}"))
}

/// A protocol the benches cover: UB2 and SD with hand-written and deku baselines
/// ([`crate::Hand`], [`crate::Deku`]) of their [`Proto::subset`]; Modbus and Dynamixel with
/// the generated code and the interpreter only, and for Modbus the modbus-core peer
/// ([`crate::peer::modbus_core`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Proto {
    Ub2,
    Sd,
    Modbus,
    Dynamixel,
}

impl Proto {
    /// The protocols with hand-written and deku baselines.
    pub const ALL: [Proto; 2] = [Proto::Ub2, Proto::Sd];
    /// The protocols with variable-length frames, without those baselines.
    pub const VARIABLE: [Proto; 2] = [Proto::Modbus, Proto::Dynamixel];

    /// The protocol's name in its spec ([`busspec_protocols::Protocol::NAME`]).
    pub fn name(self) -> &'static str {
        match self {
            Proto::Ub2 => Ub2::NAME,
            Proto::Sd => Sd::NAME,
            Proto::Modbus => Modbus::NAME,
            Proto::Dynamixel => Dynamixel::NAME,
        }
    }

    /// The benched protocol called `name` (its spec's name).
    pub fn from_name(name: &str) -> Option<Proto> {
        Proto::ALL
            .into_iter()
            .chain(Proto::VARIABLE)
            .find(|p| p.name() == name)
    }

    /// The benched protocol generated as `P`.
    ///
    /// # Panics
    /// If `P` is not one the benches cover.
    pub fn of<P: busspec_protocols::Protocol>() -> Proto {
        Proto::from_name(P::NAME).unwrap_or_else(|| panic!("the benches do not cover {}", P::NAME))
    }

    /// The validated spec, as the generated code was built from it (the interpreter's input).
    pub fn spec(self) -> Protocol {
        match self {
            Proto::Ub2 => spec::<Ub2>(),
            Proto::Sd => spec::<Sd>(),
            Proto::Modbus => spec::<Modbus>(),
            Proto::Dynamixel => spec::<Dynamixel>(),
        }
    }

    /// The messages every contender implements, by spec name. The mixed stream holds the
    /// spec's examples of exactly these (see BENCHMARKS.md for why a subset).
    pub fn subset(self) -> &'static [&'static str] {
        match self {
            Proto::Ub2 => UB2_SUBSET,
            Proto::Sd => SD_SUBSET,
            Proto::Modbus => MODBUS_SUBSET,
            Proto::Dynamixel => DYNAMIXEL_SUBSET,
        }
    }
}

include!("subset.rs");

/// Every Modbus message the spec has an example of, less the three modbus-core gets wrong
/// ([`crate::peer::modbus_core::NOT_HANDLED`]), left out for every contender.
pub const MODBUS_SUBSET: &[&str] = &[
    "read_coils",
    "read_coils_reply",
    "read_discrete_inputs",
    "read_discrete_inputs_reply",
    "read_holding_registers",
    "read_holding_registers_reply",
    "read_input_registers",
    "read_input_registers_reply",
    "write_single_coil",
    "write_single_register",
    "write_single_register_reply",
    "write_multiple_coils_reply",
    "write_multiple_registers_reply",
    "read_coils_exception",
];

/// Every Dynamixel message the spec has an example of.
pub const DYNAMIXEL_SUBSET: &[&str] = &[
    "read",
    "read_status",
    "ping",
    "status",
    "write",
    "reg_write",
    "action",
    "reset",
    "sync_write",
];

/// Frames per iteration of the decode and encode benches: enough that the figure is the cost
/// of a frame in a stream, not of one frame overlapped with itself in the pipeline.
pub const FRAMES: usize = 128;

/// At most this many examples of one message go into the mix, so the short ACKs the UB2 spec
/// shows for every movement do not crowd out the rest.
const PER_MESSAGE: usize = 2;

/// One frame of the mixed stream.
#[derive(Debug, Clone)]
pub struct Entry {
    pub message: String,
    pub direction: Direction,
    /// Where the frame lies in [`Mixed::bytes`].
    pub range: Range<usize>,
    /// For a response only its request identifies: that request's frame.
    pub reply_to: Option<Vec<u8>>,
}

/// An example chosen for the mix.
struct Picked {
    name: String,
    direction: Direction,
    wire: Vec<u8>,
    reply_to: Option<Vec<u8>>,
}

/// [`FRAMES`] frames back to back, both directions, cycling through the selected examples.
#[derive(Debug, Clone)]
pub struct Mixed {
    pub proto: Proto,
    pub bytes: Vec<u8>,
    pub entries: Vec<Entry>,
}

impl Mixed {
    pub fn new(proto: Proto) -> Mixed {
        Self::from_spec(proto, &proto.spec())
    }

    pub fn from_spec(proto: Proto, p: &Protocol) -> Mixed {
        let subset = proto.subset();
        let mut picked: Vec<Picked> = Vec::new();
        for e in &p.examples {
            let m = p.message(e.message);
            if !subset.contains(&m.name.as_str()) {
                continue;
            }
            if picked.iter().filter(|x| x.name == m.name).count() >= PER_MESSAGE {
                continue;
            }
            let reply_to = reply_to(p, e);
            picked.push(Picked {
                name: m.name.clone(),
                direction: e.message.direction,
                wire: e.wire.clone(),
                reply_to,
            });
        }
        for name in subset {
            assert!(
                picked.iter().any(|x| x.name == *name),
                "{}: no example of {name} in the spec",
                proto.name()
            );
        }
        let mut bytes = Vec::new();
        let mut entries = Vec::with_capacity(FRAMES);
        for x in picked.iter().cycle().take(FRAMES) {
            let start = bytes.len();
            bytes.extend_from_slice(&x.wire);
            entries.push(Entry {
                message: x.name.clone(),
                direction: x.direction,
                range: start..bytes.len(),
                reply_to: x.reply_to.clone(),
            });
        }
        Mixed {
            proto,
            bytes,
            entries,
        }
    }

    /// The frames of the capture without noise ([`capture_with_noise`] with `per_mille` 0),
    /// each whole one an entry (the cut last one left out): the frames the stream decoder
    /// finds, with their boundaries known, to decode them one by one (its yardstick).
    pub fn capture(proto: Proto, p: &Protocol, len: usize) -> Mixed {
        let bytes = capture_with_noise(p, len, 0);
        let mut entries = Vec::new();
        let mut start = 0;
        for e in p.examples.iter().cycle() {
            let end = start + e.wire.len();
            if end > bytes.len() {
                break;
            }
            entries.push(Entry {
                message: p.message(e.message).name.clone(),
                direction: e.message.direction,
                range: start..end,
                reply_to: reply_to(p, e),
            });
            start = end;
        }
        Mixed {
            proto,
            bytes,
            entries,
        }
    }

    pub fn frame(&self, e: &Entry) -> &[u8] {
        &self.bytes[e.range.clone()]
    }
}

/// For an example of a response only its request identifies: an example of that request.
fn reply_to(p: &Protocol, e: &busspec_model::ir::Example) -> Option<Vec<u8>> {
    let m = p.message(e.message);
    if !m.needs_request {
        return None;
    }
    let cmd = e
        .reply_to
        .unwrap_or_else(|| panic!("example of {} names no request", m.name));
    let req = p
        .examples
        .iter()
        .find(|x| x.message.direction == Direction::Request && x.message.index == cmd)
        .unwrap_or_else(|| panic!("no example of request {}", p.commands[cmd].name));
    Some(req.wire.clone())
}

/// Size of the synthetic capture the stream benches decode.
pub const CAPTURE_BYTES: usize = 1 << 20;

/// One byte in a hundred of the capture is noise.
pub const NOISE_PER_MILLE: u32 = 10;

/// A synthetic bus capture of `len` bytes: every example frame of the protocol (both
/// directions, so requests and replies alternate as the spec lists them) over and over, with
/// [`NOISE_PER_MILLE`] of the bytes random noise inserted between frames. The last frame is
/// cut at `len`. Seeded, so every run decodes the same capture.
pub fn capture(p: &Protocol, len: usize) -> Vec<u8> {
    capture_with_noise(p, len, NOISE_PER_MILLE)
}

/// [`capture`] with `per_mille` of the bytes noise (0: the frames alone, back to back).
pub fn capture_with_noise(p: &Protocol, len: usize, per_mille: u32) -> Vec<u8> {
    let mut rng = fastrand::Rng::with_seed(0x0062_7573_7370_6563);
    let frames: Vec<&[u8]> = p.examples.iter().map(|e| e.wire.as_slice()).collect();
    let mean = frames.iter().map(|f| f.len()).sum::<usize>() as f64 / frames.len() as f64;
    // Noise bytes between two frames: Bernoulli per frame with the probability that makes
    // noise / total = NOISE_PER_MILLE / 1000 on average.
    let share = f64::from(per_mille) / 1000.0;
    let per_frame = share * mean / (1.0 - share);
    let mut out = Vec::with_capacity(len + 32);
    let mut i = 0;
    while out.len() < len {
        out.extend_from_slice(frames[i % frames.len()]);
        i += 1;
        if rng.f64() < per_frame {
            out.push(rng.u8(..));
        }
    }
    out.truncate(len);
    out
}

/// Hex lines of at least `len` bytes of text, as a logger or terminal prints frames: every
/// example frame of the protocol over and over (as [`capture`] has them, without the noise,
/// and without the responses only their request identifies, which a line decoded on its own
/// cannot settle), one per line, in turn as plain uppercase digits (`AA2141013E1F00006A`), as bytes separated
/// by spaces (`AA 21 41 01 ...`), and as `0x`-prefixed bytes (`0xAA 0x21 ...`), with a
/// `#` comment line every 64 frames. The input `busspec decode PROTO -` reads.
pub fn hex_lines(p: &Protocol, len: usize) -> String {
    use std::fmt::Write as _;
    let frames: Vec<&[u8]> = p
        .examples
        .iter()
        .filter(|e| !p.message(e.message).needs_request)
        .map(|e| e.wire.as_slice())
        .collect();
    let mut out = String::with_capacity(len + 64);
    let mut i = 0usize;
    while out.len() < len {
        let wire = frames[i % frames.len()];
        if i % 64 == 0 {
            let _ = writeln!(out, "# frame {i}");
        }
        for (k, b) in wire.iter().enumerate() {
            let _ = match i % 3 {
                0 => write!(out, "{b:02X}"),
                1 if k > 0 => write!(out, " {b:02X}"),
                1 => write!(out, "{b:02X}"),
                _ if k > 0 => write!(out, " 0x{b:02X}"),
                _ => write!(out, "0x{b:02X}"),
            };
        }
        out.push('\n');
        i += 1;
    }
    out
}
