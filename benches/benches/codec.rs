//! Frame throughput of the generated codecs, each group with its baselines measured in the same
//! run (see BENCHMARKS.md): per protocol
//!
//! - `<p>/decode`, `<p>/encode`: the mixed stream of 128 frames, per frame (`frames`) and per
//!   byte (`bytes`): generated, hand-written, deku, interpreter;
//! - `<p>/stream`: a 1 MiB synthetic capture with 1 % noise: the generated stream decoder, the
//!   plain byte pass (the memory floor), the interpreter's stream decoder (on the first 64 KiB);
//! - `<p>/checksum`: the checksum alone over the bytes it covers in each frame of the mixed
//!   stream;
//!
//! and for Modbus and Dynamixel (no hand-written or deku contender) `<p>/decode` and
//! `<p>/encode` with the generated code, the interpreter and for Modbus its peer modbus-core,
//! and `<p>/stream` as above.
//!
//! `cargo bench -p busspec-benches -- ub2/decode` runs one group; `-- --test` runs each once.

use std::hint::black_box;
use std::time::Duration;

use busspec_benches::mixed::{capture, Mixed, Proto, CAPTURE_BYTES};
use busspec_benches::peer::modbus_core;
use busspec_benches::{
    decode_all, encode_all, jobs, messages, plain_sum, stream_generated, stream_interp, Contender,
    Deku, Generated, Hand, Interp,
};
use busspec_model::ir::{Direction, Protocol};
use busspec_protocols::dynamixel::Dynamixel;
use busspec_protocols::modbus::Modbus;
use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use criterion::measurement::WallTime;
use criterion::{
    criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, Throughput,
};

/// The interpreter's stream decoder runs on this much of the capture (it is slow, and its
/// figure is per byte anyway).
const INTERP_CAPTURE_BYTES: usize = 64 << 10;

/// Per frame and per byte: the same measurement under both throughputs.
fn throughputs(mixed: &Mixed) -> [(&'static str, Throughput); 2] {
    [
        ("frames", Throughput::Elements(mixed.entries.len() as u64)),
        ("bytes", Throughput::Bytes(mixed.bytes.len() as u64)),
    ]
}

fn decode_one<C: Contender>(
    g: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    unit: &str,
    c: &C,
    mixed: &Mixed,
) {
    let jobs = jobs(c, mixed);
    assert_eq!(
        decode_all(c, &mixed.bytes, &jobs),
        mixed.entries.len(),
        "{name}"
    );
    g.bench_function(BenchmarkId::new(name, unit), |b| {
        b.iter(|| decode_all(c, black_box(&mixed.bytes), black_box(&jobs)))
    });
}

fn encode_one<C: Contender>(
    g: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    unit: &str,
    c: &C,
    mixed: &Mixed,
) {
    let msgs = messages(c, mixed);
    let mut out = vec![0u8; mixed.bytes.len()];
    assert_eq!(
        encode_all(c, &msgs, &mut out),
        Some(mixed.bytes.len()),
        "{name}"
    );
    g.bench_function(BenchmarkId::new(name, unit), |b| {
        b.iter(|| encode_all(c, black_box(&msgs), black_box(&mut out)))
    });
}

/// The decode and encode groups of protocol `P`: its four contenders on its mixed stream.
fn frames<P: busspec_protocols::Protocol>(c: &mut Criterion, spec: &Protocol)
where
    Hand<P>: Contender,
    Deku<P>: Contender,
{
    let proto = Proto::of::<P>();
    let generated = Generated::<P>::default();
    let hand = Hand::<P>::default();
    let deku = Deku::<P>::default();
    let interp = Interp(spec);
    let mixed = Mixed::from_spec(proto, spec);
    let mut g = c.benchmark_group(format!("{}/decode", proto.name()));
    for (unit, t) in throughputs(&mixed) {
        g.throughput(t);
        decode_one(&mut g, "generated", unit, &generated, &mixed);
        decode_one(&mut g, "hand-written", unit, &hand, &mixed);
        decode_one(&mut g, "deku", unit, &deku, &mixed);
        decode_one(&mut g, "interpreter", unit, &interp, &mixed);
    }
    g.finish();
    let mut g = c.benchmark_group(format!("{}/encode", proto.name()));
    for (unit, t) in throughputs(&mixed) {
        g.throughput(t);
        encode_one(&mut g, "generated", unit, &generated, &mixed);
        encode_one(&mut g, "hand-written", unit, &hand, &mixed);
        encode_one(&mut g, "deku", unit, &deku, &mixed);
        encode_one(&mut g, "interpreter", unit, &interp, &mixed);
    }
    g.finish();
}

/// The decode and encode groups of Modbus or Dynamixel (`P`): the generated code and the
/// interpreter, and for Modbus modbus-core, on the mixed stream.
fn variable<P: busspec_protocols::Protocol>(c: &mut Criterion, spec: &Protocol) {
    let proto = Proto::of::<P>();
    let generated = Generated::<P>::default();
    let interp = Interp(spec);
    let mixed = Mixed::from_spec(proto, spec);
    let peer = (proto == Proto::Modbus).then(|| {
        let frames: Vec<(Direction, std::ops::Range<usize>)> = mixed
            .entries
            .iter()
            .map(|e| (e.direction, e.range.clone()))
            .collect();
        assert_eq!(
            modbus_core::decode_all(&mixed.bytes, &frames),
            frames.len(),
            "modbus-core"
        );
        frames
    });
    let mut g = c.benchmark_group(format!("{}/decode", proto.name()));
    for (unit, t) in throughputs(&mixed) {
        g.throughput(t);
        decode_one(&mut g, "generated", unit, &generated, &mixed);
        if let Some(frames) = &peer {
            g.bench_function(BenchmarkId::new("modbus-core", unit), |b| {
                b.iter(|| modbus_core::decode_all(black_box(&mixed.bytes), black_box(frames)))
            });
        }
        decode_one(&mut g, "interpreter", unit, &interp, &mixed);
    }
    g.finish();
    let mut g = c.benchmark_group(format!("{}/encode", proto.name()));
    for (unit, t) in throughputs(&mixed) {
        g.throughput(t);
        encode_one(&mut g, "generated", unit, &generated, &mixed);
        if let Some(frames) = &peer {
            let adus: Vec<_> = frames
                .iter()
                .map(|(d, r)| modbus_core::decode(*d, &mixed.bytes[r.clone()]).expect("decodes"))
                .collect();
            let mut out = vec![0u8; mixed.bytes.len()];
            assert_eq!(
                modbus_core::encode_all(&adus, &mut out),
                Some(mixed.bytes.len())
            );
            g.bench_function(BenchmarkId::new("modbus-core", unit), |b| {
                b.iter(|| modbus_core::encode_all(black_box(&adus), black_box(&mut out)))
            });
        }
        encode_one(&mut g, "interpreter", unit, &interp, &mixed);
    }
    g.finish();
}

/// The stream group of protocol `P`: its generated stream decoder on the synthetic capture,
/// with the plain byte pass and the interpreter's stream decoder.
fn stream<P: busspec_protocols::Protocol>(c: &mut Criterion, spec: &Protocol) {
    let proto = Proto::of::<P>();
    let cap = capture(spec, CAPTURE_BYTES);
    let found = stream_generated::<P>(&cap);
    assert_eq!(found.bytes, cap.len() as u64);
    let mut g = c.benchmark_group(format!("{}/stream", proto.name()));
    g.throughput(Throughput::Bytes(cap.len() as u64));
    g.bench_function("generated", |b| {
        b.iter(|| stream_generated::<P>(black_box(&cap)))
    });
    g.bench_function("plain-sum", |b| b.iter(|| plain_sum(black_box(&cap))));
    let head = &cap[..INTERP_CAPTURE_BYTES];
    g.throughput(Throughput::Bytes(head.len() as u64));
    g.bench_function("interpreter-64KiB", |b| {
        b.iter(|| stream_interp(spec, black_box(head)))
    });
    g.finish();
}

/// The bytes each frame's checksum covers, frame by frame.
fn covered(mixed: &Mixed, spec: &Protocol) -> Vec<Vec<u8>> {
    let n = spec.framing.checksum.len();
    mixed
        .entries
        .iter()
        .map(|e| {
            let f = mixed.frame(e);
            f[..f.len() - n].to_vec()
        })
        .collect()
}

fn checksum_one<T>(
    g: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    frames: &[Vec<u8>],
    f: impl Fn(&[u8]) -> T,
) {
    g.bench_function(name, |b| {
        b.iter(|| {
            for frame in black_box(frames) {
                black_box(f(frame));
            }
        })
    });
}

fn checksum_group<'c>(
    c: &'c mut Criterion,
    proto: Proto,
    spec: &Protocol,
) -> (BenchmarkGroup<'c, WallTime>, Vec<Vec<u8>>) {
    let frames = covered(&Mixed::from_spec(proto, spec), spec);
    let mut g = c.benchmark_group(format!("{}/checksum", proto.name()));
    g.throughput(Throughput::Bytes(
        frames.iter().map(Vec::len).sum::<usize>() as u64,
    ));
    (g, frames)
}

fn ub2(c: &mut Criterion) {
    let spec = Proto::Ub2.spec();
    frames::<Ub2>(c, &spec);
    stream::<Ub2>(c, &spec);
    let (mut g, frames) = checksum_group(c, Proto::Ub2, &spec);
    let algorithm = &spec.framing.checksum.algorithm;
    checksum_one(
        &mut g,
        "generated",
        &frames,
        busspec_protocols::ub2::checksum,
    );
    checksum_one(&mut g, "interpreter", &frames, |f| {
        busspec_model::checksum::compute(algorithm, f)
    });
    g.finish();
}

fn sd(c: &mut Criterion) {
    let spec = Proto::Sd.spec();
    frames::<Sd>(c, &spec);
    stream::<Sd>(c, &spec);
    let (mut g, frames) = checksum_group(c, Proto::Sd, &spec);
    let algorithm = &spec.framing.checksum.algorithm;
    checksum_one(
        &mut g,
        "generated",
        &frames,
        busspec_protocols::sd::checksum,
    );
    // The other implementations the crc crate offers: bit by bit, and slice-by-16.
    static BITWISE: crc::Crc<u16, crc::NoTable> =
        crc::Crc::<u16, crc::NoTable>::new(&crc::CRC_16_CMS);
    static SLICE16: crc::Crc<u16, crc::Table<16>> =
        crc::Crc::<u16, crc::Table<16>>::new(&crc::CRC_16_CMS);
    checksum_one(&mut g, "crc-no-table", &frames, |f| BITWISE.checksum(f));
    checksum_one(&mut g, "crc-slice16", &frames, |f| SLICE16.checksum(f));
    checksum_one(&mut g, "interpreter", &frames, |f| {
        busspec_model::checksum::compute(algorithm, f)
    });
    g.finish();
}

fn modbus(c: &mut Criterion) {
    let spec = Proto::Modbus.spec();
    variable::<Modbus>(c, &spec);
    stream::<Modbus>(c, &spec);
}

fn dynamixel(c: &mut Criterion) {
    let spec = Proto::Dynamixel.spec();
    variable::<Dynamixel>(c, &spec);
    stream::<Dynamixel>(c, &spec);
}

fn config() -> Criterion {
    // Short runs: the machine is shared; ratios within one run are what BENCHMARKS.md reports.
    Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sample_size(50)
}

criterion_group! {
    name = benches;
    config = config();
    targets = ub2, sd, modbus, dynamixel
}
criterion_main!(benches);
