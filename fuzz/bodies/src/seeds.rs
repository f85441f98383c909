//! The seed corpus and the dictionaries, derived from the specs: every example frame of the
//! document, in the input layout of each target (see the crate docs), and every message's frame
//! prefix (start byte, a device address, code). `make-corpus` writes them under `fuzz/`; a test
//! checks the committed files are up to date.
//!
//! The spec loader's seeds are the real specs and the codegen's fixture specs, read where they
//! are (see [`LOADER_SEED_DIRS`]), not copied.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use busspec_model::ir::{Direction, Protocol};

use crate::spec_named;

/// The spec of each generated protocol, by name.
fn specs() -> impl Iterator<Item = (&'static str, &'static Protocol)> {
    busspec_protocols::PROTOCOLS.iter().map(|&name| {
        let p = spec_named(name).expect("every name in PROTOCOLS is a protocol");
        (name, p)
    })
}

/// Generated seed files are named `seed-…`; libFuzzer names what it adds by content hash, so
/// the two never clash and only the generated ones are committed.
pub const SEED_PREFIX: &str = "seed-";

/// Example frames per stream seed.
const CAPTURE_FRAMES: usize = 12;

/// Directories (relative to the repository root) whose files seed `spec_loader`.
pub const LOADER_SEED_DIRS: &[&str] = &[
    "spec",
    "model/tests/fixtures/valid",
    "model/tests/fixtures/broken",
];

/// The repository root (this crate lives in `fuzz/bodies`).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every generated seed: target name → file name → bytes.
pub fn corpus() -> BTreeMap<&'static str, BTreeMap<String, Vec<u8>>> {
    let mut out = BTreeMap::new();
    for (proto, p) in specs() {
        // A protocol with interpreter bodies of its own (Modbus, Dynamixel), or with generated
        // targets alone (Pelco D and P), has its generated ones as `<proto>_generated_<kind>`,
        // and not every kind.
        let generated = format!("{proto}_generated_");
        let interpreted = crate::interpreted::specs().iter().any(|(n, _)| *n == proto)
            || crate::TARGETS
                .iter()
                .any(|t| t.name.starts_with(&generated));
        let mut put = |kind: &str, name: String, bytes: Vec<u8>| {
            let target = match interpreted {
                true => format!("{proto}_generated_{kind}"),
                false => format!("{proto}_{kind}"),
            };
            let Some(t) = crate::TARGETS.iter().find(|t| t.name == target) else {
                assert!(interpreted, "no target {target}");
                return;
            };
            out.entry(t.name)
                .or_insert_with(BTreeMap::new)
                .insert(format!("{SEED_PREFIX}{name}"), bytes);
        };
        for (i, e) in p.examples.iter().enumerate() {
            let name = format!("example-{i:03}");
            put("decode", name.clone(), e.wire.clone());
            put("roundtrip", name.clone(), e.wire.clone());
            let pick = e.reply_to.unwrap_or(0);
            let pick = u8::try_from(pick).expect("fewer than 256 commands");
            put("differential", name, [&[pick], &e.wire[..]].concat());
        }
        // Captures of a few examples each (short inputs fuzz faster): as a sniffer sees them,
        // each direction alone, and with noise and cut-short frames between the frames.
        for (n, group) in p.examples.chunks(CAPTURE_FRAMES).enumerate() {
            let b = u8::try_from(n % 256).expect("below 256");
            let all: Vec<u8> = group.iter().flat_map(|e| e.wire.clone()).collect();
            put(
                "stream",
                format!("capture-{n:02}-both"),
                [&[0, b, b], &all[..]].concat(),
            );
            for (mode, d, name) in [
                (1, Direction::Request, "requests"),
                (2, Direction::Response, "responses"),
            ] {
                let part: Vec<u8> = group
                    .iter()
                    .filter(|e| e.message.direction == d)
                    .flat_map(|e| e.wire.clone())
                    .collect();
                if !part.is_empty() {
                    let seed = [&[mode, b, b.wrapping_add(1)], &part[..]].concat();
                    put("stream", format!("capture-{n:02}-{name}"), seed);
                }
            }
            let mut noisy = vec![0, b, b.wrapping_add(2)];
            for (i, e) in group.iter().enumerate() {
                noisy.extend_from_slice(&[0x00, 0xFF, 0x55][..i % 4]);
                if i % 5 == 0 {
                    noisy.extend_from_slice(&e.wire[..e.wire.len() / 2]);
                }
                noisy.extend_from_slice(&e.wire);
            }
            put("stream", format!("capture-{n:02}-noisy"), noisy);
        }
    }
    for (proto, p) in crate::interpreted::specs() {
        let mut put = |kind: &str, name: String, bytes: Vec<u8>| {
            let target: &'static str = crate::TARGETS
                .iter()
                .find(|t| t.name == format!("{proto}_{kind}"))
                .expect("a target for every kind")
                .name;
            out.entry(target)
                .or_insert_with(BTreeMap::new)
                .insert(format!("{SEED_PREFIX}{name}"), bytes);
        };
        let requests: Vec<usize> = p
            .examples
            .iter()
            .enumerate()
            .filter(|(_, e)| e.message.direction == Direction::Request)
            .map(|(i, _)| i)
            .collect();
        for (i, e) in p.examples.iter().enumerate() {
            // The request a reply answers is the example just before it, where there is one.
            let pick = requests.iter().rposition(|&r| r < i).unwrap_or(0);
            let pick = u8::try_from(pick).expect("fewer than 256 requests");
            put(
                "decode",
                format!("example-{i:03}"),
                [&[pick], &e.wire[..]].concat(),
            );
        }
        let all: Vec<u8> = p.examples.iter().flat_map(|e| e.wire.clone()).collect();
        put(
            "stream",
            "capture-both".to_owned(),
            [&[0, 7], &all[..]].concat(),
        );
        for (mode, d, name) in [
            (1, Direction::Request, "requests"),
            (2, Direction::Response, "responses"),
        ] {
            let part: Vec<u8> = p
                .examples
                .iter()
                .filter(|e| e.message.direction == d)
                .flat_map(|e| e.wire.clone())
                .collect();
            put(
                "stream",
                format!("capture-{name}"),
                [&[mode, 3], &part[..]].concat(),
            );
            let mut noisy = vec![mode, 11];
            for (i, e) in p
                .examples
                .iter()
                .filter(|e| e.message.direction == d)
                .enumerate()
            {
                noisy.extend_from_slice(&[0x00, 0xFF, 0x55][..i % 4]);
                if i % 3 == 0 {
                    noisy.extend_from_slice(&e.wire[..e.wire.len() / 2]);
                }
                noisy.extend_from_slice(&e.wire);
            }
            put("stream", format!("capture-{name}-noisy"), noisy);
        }
    }
    out
}

/// A libFuzzer dictionary for `p`: each message's frame up to its code (with the first device
/// address), and the code alone.
pub fn dictionary(p: &Protocol) -> String {
    let mut text = format!(
        "# libFuzzer dictionary for {}: frame prefixes and command codes. Generated by\n\
         # `cargo run -p busspec-fuzz-bodies --bin make-corpus`; do not edit.\n",
        p.name
    );
    let mut seen = std::collections::BTreeSet::new();
    for d in [Direction::Request, Direction::Response] {
        for m in p.messages(d) {
            let o = m.layout;
            let len = (o.code + m.code.len()).max(o.address.map_or(0, |a| a + 1));
            let mut prefix = vec![0u8; len];
            if let Some(at) = o.start {
                for (i, s) in p.framing.sync_of(d).iter().enumerate() {
                    prefix[at + i] = *s;
                }
            }
            if let Some(at) = o.address {
                prefix[at] = p.framing.address.min;
            }
            prefix[o.code..o.code + m.code.len()].copy_from_slice(&m.code);
            for (kind, bytes) in [("frame", prefix), ("code", m.code.clone())] {
                // A message without a code (a Dynamixel status packet) has no code entry:
                // libFuzzer refuses an empty one.
                if !bytes.is_empty() && seen.insert(bytes.clone()) {
                    let escaped: String = bytes.iter().map(|b| format!("\\x{b:02X}")).collect();
                    let _ = writeln!(text, "{}_{}_{kind}=\"{escaped}\"", d.as_str(), m.name);
                }
            }
        }
    }
    text
}

/// Every generated file under `fuzz/`: path relative to `fuzz/` → contents.
pub fn files() -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    for (target, seeds) in corpus() {
        for (name, bytes) in seeds {
            out.insert(Path::new("corpus").join(target).join(name), bytes);
        }
    }
    for (_, p) in specs().chain(crate::interpreted::specs()) {
        out.insert(
            Path::new("dict").join(format!("{}.dict", p.name)),
            dictionary(p).into_bytes(),
        );
    }
    out
}

/// Generated files that are missing or differ under `fuzz_dir`, and seed files there that are
/// no longer generated.
pub fn stale(fuzz_dir: &Path) -> Vec<String> {
    let want = files();
    let mut out = Vec::new();
    for (path, bytes) in &want {
        match std::fs::read(fuzz_dir.join(path)) {
            Ok(b) if b == *bytes => {}
            Ok(_) => out.push(format!("{} differs", path.display())),
            Err(_) => out.push(format!("{} is missing", path.display())),
        }
    }
    for t in crate::TARGETS {
        let dir = Path::new("corpus").join(t.name);
        for name in list(&fuzz_dir.join(&dir)) {
            let rel = dir.join(&name);
            if name.starts_with(SEED_PREFIX) && !want.contains_key(&rel) {
                out.push(format!("{} is no longer generated", rel.display()));
            }
        }
    }
    out
}

/// Writes every generated file under `fuzz_dir` and removes seed files no longer generated.
pub fn write(fuzz_dir: &Path) -> std::io::Result<()> {
    let want = files();
    for t in crate::TARGETS {
        let dir = fuzz_dir.join("corpus").join(t.name);
        for name in list(&dir) {
            if name.starts_with(SEED_PREFIX)
                && !want.contains_key(&Path::new("corpus").join(t.name).join(&name))
            {
                std::fs::remove_file(dir.join(&name))?;
            }
        }
    }
    for (path, bytes) in want {
        let path = fuzz_dir.join(path);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)?;
        }
        std::fs::write(path, bytes)?;
    }
    Ok(())
}

/// File names in `dir`, sorted; none if it does not exist.
pub fn list(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok())
                .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
                .filter_map(|e| e.file_name().into_string().ok())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}
