//! Runs one contender over the benches' inputs a given number of times, for counting
//! instructions under callgrind (`benches/icount.sh`): the difference between two pass counts,
//! divided by the difference in frames (or bytes), is the cost of one frame (or byte) with the
//! set-up subtracted out.
//!
//! ```text
//! icount <ub2|sd> <generated|hand-written|deku|interpreter> <decode|encode> <passes>
//! icount <modbus|dynamixel> <generated|interpreter|modbus-core> <decode|encode> <passes>
//! icount <modbus|dynamixel> view decode <passes>
//! icount <ub2|sd|modbus|dynamixel> stream <generated|generated-clean|plain-sum|decode> <passes>
//! ```
//!
//! A decode or encode pass is the 128-frame mixed stream; a stream pass is the 1 MiB capture
//! (1 % noise; `generated-clean`: none; `decode`: the frames of the clean capture decoded one
//! by one, their boundaries known, the stream rows' yardstick). Modbus and Dynamixel have no
//! hand-written or deku contender; `modbus-core` is Modbus's peer; `view` decodes through the
//! generated borrowed views (`RequestView`/`ResponseView`).
//! Prints the units one pass stands for (frames or bytes) and a value computed from the work,
//! so none of it can be optimised away.

use std::process::ExitCode;

use busspec_benches::mixed::{capture_with_noise, Mixed, Proto, CAPTURE_BYTES, NOISE_PER_MILLE};
use busspec_benches::peer::modbus_core;
use busspec_benches::{
    decode_all, decode_all_dynamixel_views, decode_all_modbus_views, encode_all, jobs, messages,
    plain_sum, stream_generated, Contender, Deku, Generated, Hand, Interp,
};
use busspec_model::ir::Direction;
use busspec_protocols::dynamixel::Dynamixel;
use busspec_protocols::modbus::Modbus;
use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol;

const USAGE: &str = "usage: icount <ub2|sd> <generated|hand-written|deku|interpreter> <decode|encode> <passes>\n       icount <modbus|dynamixel> <generated|interpreter|modbus-core> <decode|encode> <passes>\n       icount <modbus|dynamixel> view decode <passes>\n       icount <ub2|sd|modbus|dynamixel> stream <generated|generated-clean|plain-sum|decode> <passes>";

fn run<C: Contender>(c: &C, mixed: &Mixed, op: &str, passes: u64) -> Result<u64, String> {
    match op {
        "decode" => {
            let jobs = jobs(c, mixed);
            Ok((0..passes)
                .map(|_| decode_all(c, &mixed.bytes, &jobs) as u64)
                .sum())
        }
        "encode" => {
            let msgs = messages(c, mixed);
            let mut out = vec![0u8; mixed.bytes.len()];
            (0..passes)
                .map(|_| encode_all(c, &msgs, &mut out).map(|n| n as u64))
                .sum::<Option<u64>>()
                .ok_or_else(|| "a message did not encode".to_owned())
        }
        _ => Err(format!("unknown operation `{op}`\n{USAGE}")),
    }
}

/// The stream contenders of protocol `P` (`op`: which one); prints the units of one pass and
/// returns the value the work computed.
fn stream<P: Protocol>(op: &str, passes: u64) -> Result<u64, String> {
    let proto = Proto::of::<P>();
    let spec = proto.spec();
    if op == "decode" {
        // The yardstick of the stream rows: the clean capture's frames decoded one by one.
        let mixed = Mixed::capture(proto, &spec, CAPTURE_BYTES);
        let c = Generated::<P>::default();
        let jobs = jobs(&c, &mixed);
        println!("units per pass: {} bytes", mixed.bytes.len());
        println!("frames per pass: {}", mixed.entries.len());
        return Ok((0..passes)
            .map(|_| decode_all(&c, &mixed.bytes, &jobs) as u64)
            .sum());
    }
    // `generated-clean`: the generated stream decoder over the capture without noise.
    let noise = if op == "generated-clean" {
        0
    } else {
        NOISE_PER_MILLE
    };
    let cap = capture_with_noise(&spec, CAPTURE_BYTES, noise);
    let f = match op {
        "generated" | "generated-clean" => |c: &[u8]| stream_generated::<P>(c).frames,
        "plain-sum" => |c: &[u8]| u64::from(plain_sum(c)),
        other => return Err(format!("unknown stream contender `{other}`\n{USAGE}")),
    };
    println!("units per pass: {} bytes", cap.len());
    println!("frames per pass: {}", stream_generated::<P>(&cap).frames);
    Ok((0..passes).map(|_| f(&cap)).sum())
}

/// Prints the units of one pass of the mixed stream.
fn mixed_units(mixed: &Mixed) {
    println!(
        "units per pass: {} frames ({} bytes)",
        mixed.entries.len(),
        mixed.bytes.len()
    );
}

/// Runs contender `who` of protocol `P` (`stream` and `op` for the stream contenders); prints
/// the units of one pass and returns the value the work computed.
fn measure<P: Protocol>(who: &str, op: &str, passes: u64) -> Result<u64, String>
where
    Hand<P>: Contender,
    Deku<P>: Contender,
{
    if who == "stream" {
        return stream::<P>(op, passes);
    }
    let spec = Proto::of::<P>().spec();
    let mixed = Mixed::from_spec(Proto::of::<P>(), &spec);
    mixed_units(&mixed);
    match who {
        "generated" => run(&Generated::<P>::default(), &mixed, op, passes),
        "hand-written" => run(&Hand::<P>::default(), &mixed, op, passes),
        "deku" => run(&Deku::<P>::default(), &mixed, op, passes),
        "interpreter" => run(&Interp(&spec), &mixed, op, passes),
        other => Err(format!("unknown contender `{other}`\n{USAGE}")),
    }
}

/// [`measure`] for Modbus and Dynamixel: the generated code, the interpreter, and for Modbus
/// modbus-core.
fn measure_variable<P: Protocol>(who: &str, op: &str, passes: u64) -> Result<u64, String> {
    if who == "stream" {
        return stream::<P>(op, passes);
    }
    let proto = Proto::of::<P>();
    let spec = proto.spec();
    let mixed = Mixed::from_spec(proto, &spec);
    mixed_units(&mixed);
    match who {
        "generated" => run(&Generated::<P>::default(), &mixed, op, passes),
        "interpreter" => run(&Interp(&spec), &mixed, op, passes),
        "modbus-core" if proto == Proto::Modbus => modbus_core_run(&mixed, op, passes),
        other => Err(format!("no contender `{other}` for {}\n{USAGE}", P::NAME)),
    }
}

/// Decode through the generated borrowed views (`RequestView`/`ResponseView`) of Modbus and
/// Dynamixel over the mixed stream, replies with their request as the owned decode takes them;
/// every frame must make a view.
fn view_run(proto: Proto, op: &str, passes: u64) -> Result<u64, String> {
    if op != "decode" {
        return Err(format!("a view only decodes, not `{op}`\n{USAGE}"));
    }
    let spec = proto.spec();
    let mixed = Mixed::from_spec(proto, &spec);
    mixed_units(&mixed);
    let n = mixed.entries.len();
    let all = |made: usize| {
        if made == n {
            Ok(made as u64)
        } else {
            Err(format!("{made} of {n} frames made a view"))
        }
    };
    match proto {
        Proto::Modbus => {
            let jobs = jobs(&Generated::<Modbus>::default(), &mixed);
            all(decode_all_modbus_views(&mixed.bytes, &jobs))?;
            Ok((0..passes)
                .map(|_| decode_all_modbus_views(&mixed.bytes, &jobs) as u64)
                .sum())
        }
        Proto::Dynamixel => {
            let jobs = jobs(&Generated::<Dynamixel>::default(), &mixed);
            all(decode_all_dynamixel_views(&mixed.bytes, &jobs))?;
            Ok((0..passes)
                .map(|_| decode_all_dynamixel_views(&mixed.bytes, &jobs) as u64)
                .sum())
        }
        _ => Err(format!("no view contender for {proto:?}\n{USAGE}")),
    }
}

/// modbus-core over the mixed stream: every frame must decode, and encode back to the stream.
fn modbus_core_run(mixed: &Mixed, op: &str, passes: u64) -> Result<u64, String> {
    let frames: Vec<(Direction, std::ops::Range<usize>)> = mixed
        .entries
        .iter()
        .map(|e| (e.direction, e.range.clone()))
        .collect();
    let adus = frames
        .iter()
        .map(|(d, r)| modbus_core::decode(*d, &mixed.bytes[r.clone()]))
        .collect::<Option<Vec<_>>>()
        .ok_or("modbus-core refuses a frame of the mixed stream")?;
    let mut out = vec![0u8; mixed.bytes.len()];
    if modbus_core::encode_all(&adus, &mut out) != Some(mixed.bytes.len()) || out != mixed.bytes {
        return Err("modbus-core encodes the mixed stream differently".to_owned());
    }
    match op {
        "decode" => Ok((0..passes)
            .map(|_| modbus_core::decode_all(&mixed.bytes, &frames) as u64)
            .sum()),
        "encode" => (0..passes)
            .map(|_| modbus_core::encode_all(&adus, &mut out).map(|n| n as u64))
            .sum::<Option<u64>>()
            .ok_or_else(|| "a message did not encode".to_owned()),
        _ => Err(format!("unknown operation `{op}`\n{USAGE}")),
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [proto, who, op, passes] = &args[..] else {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    };
    let Some(proto) = Proto::from_name(proto) else {
        eprintln!("unknown protocol `{proto}`\n{USAGE}");
        return ExitCode::from(2);
    };
    let Ok(passes) = passes.parse::<u64>() else {
        eprintln!("passes must be a whole number, not `{passes}`\n{USAGE}");
        return ExitCode::from(2);
    };
    let result = match proto {
        _ if who == "view" => view_run(proto, op, passes),
        Proto::Ub2 => measure::<Ub2>(who, op, passes),
        Proto::Sd => measure::<Sd>(who, op, passes),
        Proto::Modbus => measure_variable::<Modbus>(who, op, passes),
        Proto::Dynamixel => measure_variable::<Dynamixel>(who, op, passes),
    };
    match result {
        Ok(v) => {
            println!("result: {v}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::from(2)
        }
    }
}
