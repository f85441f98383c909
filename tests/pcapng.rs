//! `decode --stream --pcapng`: a capture of example frames with noise, written to pcapng by the
//! generated code (built-in protocols) and by the interpreter (`--spec`), read back by
//! `decode --stream` to the same events; the file's blocks as documented (link type, one
//! packet per event, direction, timestamps); a truncated or corrupt file refused with the
//! block and byte, never a panic; tshark reads it where tshark is installed.

use std::borrow::Cow;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use busspec_model::{load_file, Protocol};
use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption;
use pcap_file::pcapng::blocks::interface_description::InterfaceDescriptionOption;
use pcap_file::pcapng::{Block, PcapNgParser};

#[path = "common/cli.rs"]
mod cli;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str], stdin: &[u8]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_busspec"))
        .args(args)
        .current_dir(root())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run busspec");
    {
        let mut input = child.stdin.take().expect("stdin");
        // The process may end before reading everything (an error): not a failure here.
        let _ = input.write_all(stdin);
    }
    child.wait_with_output().expect("wait for busspec")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A directory of this test's own: the tests run at once and write files of the same names.
/// A scratch directory for `test`, removed when dropped.
fn temp_dir(test: &str) -> tempfile::TempDir {
    cli::scratch(&format!("pcapng-{test}"))
}

/// Every example frame of `p`, in spec order, with noise before every third.
fn capture(p: &Protocol) -> Vec<u8> {
    let noise: [&[u8]; 3] = [&[0x00, 0x13], &[0xFF], &[0x01, 0x02, 0x03]];
    let mut bytes = Vec::new();
    for (n, e) in p.examples.iter().enumerate() {
        if n % 3 == 1 {
            bytes.extend_from_slice(noise[(n / 3) % noise.len()]);
        }
        bytes.extend_from_slice(&e.wire);
    }
    bytes.extend_from_slice(&[0xEE]);
    bytes
}

/// What a pcapng file busspec wrote holds.
struct File {
    linktype: u32,
    description: String,
    resolution: Option<u8>,
    /// Each packet: timestamp (ns), epb_flags, data.
    packets: Vec<(u128, u32, Vec<u8>)>,
}

fn parse(bytes: &[u8]) -> File {
    let (mut rest, mut parser) = PcapNgParser::new(bytes).expect("section header");
    let mut file = File {
        linktype: 0,
        description: String::new(),
        resolution: None,
        packets: Vec::new(),
    };
    while !rest.is_empty() {
        let (r, block) = parser.next_block(rest).expect("block");
        rest = r;
        match block {
            Block::InterfaceDescription(i) => {
                file.linktype = u32::from(i.linktype);
                for o in &i.options {
                    match o {
                        InterfaceDescriptionOption::IfDescription(d) => {
                            file.description = d.to_string()
                        }
                        InterfaceDescriptionOption::IfTsResol(r) => file.resolution = Some(*r),
                        _ => {}
                    }
                }
            }
            Block::EnhancedPacket(e) => {
                let flags = e
                    .options
                    .iter()
                    .find_map(|o| match o {
                        EnhancedPacketOption::Flags(f) => Some(*f),
                        _ => None,
                    })
                    .unwrap_or(0);
                let data: Cow<[u8]> = e.data;
                file.packets
                    .push((e.timestamp.as_nanos(), flags, data.into_owned()));
            }
            other => panic!("unexpected block {other:?}"),
        }
    }
    file
}

/// The cases: a built-in protocol (generated code) and specs given with --spec (interpreter).
fn cases() -> Vec<(Protocol, Vec<String>)> {
    let load = |f: &str| load_file(&root().join("spec").join(f)).unwrap_or_else(|d| panic!("{d}"));
    vec![
        (load("ub2.yaml"), vec!["ub2".into()]),
        (load("modbus.yaml"), vec!["modbus".into()]),
        (
            load("sd.yaml"),
            vec!["sd".into(), "--spec".into(), "spec/sd.yaml".into()],
        ),
        (
            load("dynamixel.yaml"),
            vec![
                "dynamixel".into(),
                "--spec".into(),
                "spec/dynamixel.yaml".into(),
            ],
        ),
    ]
}

/// Writes `p`'s capture to pcapng; returns the raw capture, the JSON lines and the file.
fn written(p: &Protocol, protocol: &[String], dir: &Path) -> (Vec<u8>, String, PathBuf) {
    let bytes = capture(p);
    let raw = dir.join(format!("{}.bin", p.name));
    let file = dir.join(format!("{}.pcapng", p.name));
    std::fs::write(&raw, &bytes).unwrap();
    let mut args = vec!["decode"];
    args.extend(protocol.iter().map(String::as_str));
    args.extend([
        "--stream",
        raw.to_str().unwrap(),
        "--pcapng",
        file.to_str().unwrap(),
    ]);
    let out = run(&args, b"");
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    (bytes, text(&out.stdout), file)
}

#[test]
fn a_capture_written_to_pcapng_reads_back_to_the_same_events() {
    let scratch = temp_dir("a_capture_written_to_pcapng_reads_back_to_the_same_events");
    let dir = scratch.path();
    for (p, protocol) in cases() {
        let (bytes, lines, file) = written(&p, &protocol, dir);
        let events: Vec<serde_json::Value> = lines
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert!(events.iter().any(|e| e.get("skipped").is_some()), "{lines}");
        assert!(
            events.iter().any(|e| e.get("direction").is_some()),
            "{lines}"
        );

        // One packet per event, the capture byte for byte, as documented.
        let pcap = parse(&std::fs::read(&file).unwrap());
        assert_eq!(pcap.linktype, 147, "{}", p.name);
        assert_eq!(pcap.description, format!("busspec {}", p.name));
        assert_eq!(pcap.resolution, Some(9));
        assert_eq!(pcap.packets.len(), events.len(), "{}: {lines}", p.name);
        assert_eq!(pcap.packets.concat_data(), bytes);
        let parity = u128::from(!matches!(p.serial.parity, busspec_model::ir::Parity::None));
        let bits = 1 + u128::from(p.serial.data_bits) + parity + u128::from(p.serial.stop_bits);
        for (event, (nanos, flags, _)) in events.iter().zip(&pcap.packets) {
            let offset = u128::from(event["offset"].as_u64().unwrap());
            assert_eq!(
                *nanos,
                offset * bits * 1_000_000_000 / u128::from(p.serial.baud)
            );
            let want = match event.get("direction").and_then(|d| d.as_str()) {
                Some("request") => 2,
                Some("response") => 1,
                _ => 0,
            };
            assert_eq!(*flags, want, "{event}");
        }

        // Read back, from the file and from stdin: the same lines.
        let mut args = vec!["decode"];
        args.extend(protocol.iter().map(String::as_str));
        args.extend(["--stream", file.to_str().unwrap()]);
        let back = run(&args, b"");
        assert_eq!(back.status.code(), Some(0), "{}", text(&back.stderr));
        let char_ns = char_ns(&p);
        assert_eq!(untimed(&text(&back.stdout), char_ns), lines, "{}", p.name);
        let n = args.len();
        args[n - 1] = "-";
        let back = run(&args, &std::fs::read(&file).unwrap());
        assert_eq!(back.status.code(), Some(0), "{}", text(&back.stderr));
        let back = untimed(&text(&back.stdout), char_ns);
        assert_eq!(back, lines, "{} from stdin", p.name);
    }
}

/// Nanoseconds a character of `p` takes on the line.
fn char_ns(p: &Protocol) -> u128 {
    let parity = u128::from(!matches!(p.serial.parity, busspec_model::ir::Parity::None));
    let bits = 1 + u128::from(p.serial.data_bits) + parity + u128::from(p.serial.stop_bits);
    bits * 1_000_000_000 / u128::from(p.serial.baud)
}

/// The lines of a pcapng read back, without the keys its timestamps add: each line's
/// `"time"` must be its offset's time at `char_ns` a character (within a character: the file
/// holds whole nanoseconds), and where there is `"decided_by"` it must be `"bytes"` (the
/// packets follow one another with no silence between).
fn untimed(lines: &str, char_ns: u128) -> String {
    let mut out = String::new();
    for line in lines.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let offset = u128::from(v["offset"].as_u64().unwrap());
        let time = v["time"]
            .as_f64()
            .unwrap_or_else(|| panic!("no time: {line}"));
        let want = (offset * char_ns) as f64 / 1e9;
        assert!(
            (time - want).abs() * 1e9 <= char_ns as f64 + 1000.0,
            "{line}: time {time}, want {want}"
        );
        let mut line = line.to_owned();
        for key in [",\"time\":", ",\"decided_by\":"] {
            if let Some(at) = line.find(key) {
                let rest = &line[at + key.len()..];
                let end = rest.find(',').unwrap();
                if key.contains("decided") {
                    assert_eq!(&rest[..end], "\"bytes\"", "{line}");
                }
                line = format!("{}{}", &line[..at], &rest[end..]);
            }
        }
        out.push_str(&line);
        out.push('\n');
    }
    out
}

trait ConcatData {
    fn concat_data(&self) -> Vec<u8>;
}

impl ConcatData for Vec<(u128, u32, Vec<u8>)> {
    fn concat_data(&self) -> Vec<u8> {
        self.iter()
            .flat_map(|(_, _, d)| d.iter().copied())
            .collect()
    }
}

/// Where each block of a little-endian pcapng file starts, and the file's end.
fn block_starts(bytes: &[u8]) -> Vec<usize> {
    let mut starts = vec![0];
    let mut at = 0;
    while at + 8 <= bytes.len() {
        let len = u32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap()) as usize;
        at += len;
        starts.push(at);
    }
    starts
}

#[test]
fn a_truncated_or_corrupt_pcapng_is_refused_naming_block_and_byte() {
    let scratch = temp_dir("a_truncated_or_corrupt_pcapng_is_refused_naming_block_and_byte");
    let dir = scratch.path();
    let (p, protocol) = cases().swap_remove(0);
    let (_, lines, file) = written(&p, &protocol, dir);
    let bytes = std::fs::read(&file).unwrap();
    let starts = block_starts(&bytes);
    assert_eq!(*starts.last().unwrap(), bytes.len());
    let decode = |data: &[u8]| run(&["decode", "ub2", "--stream", "-"], data);

    // Cut inside a block: the events before it print, then the error names the block.
    for (block, w) in starts.windows(2).enumerate().skip(1).take(6) {
        for cut in [w[0] + 1, w[0] + 9, w[1] - 1] {
            let out = decode(&bytes[..cut]);
            assert_eq!(out.status.code(), Some(1), "cut at {cut}");
            assert_eq!(
                text(&out.stderr),
                format!(
                    "error: pcapng -: block {block} at byte {}: truncated: the file ends {} bytes into it\n",
                    w[0],
                    cut - w[0]
                )
            );
            assert!(lines.starts_with(&untimed(&text(&out.stdout), char_ns(&p))));
        }
        // Cut between blocks: a shorter capture, no error.
        let out = decode(&bytes[..w[1]]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    }

    // A link type that does not carry bus bytes (Ethernet) is refused where it is declared.
    let mut ethernet = bytes.clone();
    ethernet[starts[1] + 8..starts[1] + 10].copy_from_slice(&1u16.to_le_bytes());
    let out = decode(&ethernet);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr),
        format!(
            "error: pcapng -: block 1 at byte {}: interface 0 has link type 1 (ETHERNET), not a user link type (147..=162) that carries bus bytes\n",
            starts[1]
        )
    );

    // A packet of an interface never described.
    let mut orphan = bytes.clone();
    orphan[starts[2] + 8] = 7;
    let out = decode(&orphan);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr),
        format!(
            "error: pcapng -: block 2 at byte {}: packet of interface 7, which no interface block before it describes\n",
            starts[2]
        )
    );

    // Damage anywhere: an error that says where, or events; never a panic.
    let mut rng = fastrand::Rng::with_seed(25);
    for _ in 0..150 {
        let mut damaged = bytes.clone();
        for _ in 0..rng.usize(1..4) {
            let at = rng.usize(..damaged.len());
            damaged[at] = rng.u8(..);
        }
        let out = decode(&damaged);
        let stderr = text(&out.stderr);
        assert!(
            matches!(out.status.code(), Some(0 | 1)),
            "{:?}: {stderr}",
            out.status
        );
        assert!(
            stderr.is_empty() || (stderr.starts_with("error: ") && stderr.contains(" at byte ")),
            "{stderr}"
        );
    }
}

#[test]
fn tshark_reads_every_packet() {
    if !cli::tshark_present("the check that it reads busspec's pcapng") {
        return;
    }
    let scratch = temp_dir("tshark_reads_every_packet");
    let dir = scratch.path();
    for (p, protocol) in cases() {
        let (_, lines, file) = written(&p, &protocol, dir);
        let out = Command::new("tshark")
            .args([
                "-r",
                file.to_str().unwrap(),
                "-T",
                "fields",
                "-e",
                "frame.number",
                "-e",
                "frame.comment",
                "-e",
                "frame.packet_flags_direction",
            ])
            .output()
            .expect("run tshark");
        assert!(out.status.success(), "{}", text(&out.stderr));
        let seen = text(&out.stdout);
        assert_eq!(seen.lines().count(), lines.lines().count(), "{}", p.name);
        // Each packet as tshark shows it: the event's direction and message, and the direction
        // bits of `epb_flags` (outbound 2 for a request, inbound 1 for a response).
        for (packet, line) in seen.lines().zip(lines.lines()) {
            let event: serde_json::Value = serde_json::from_str(line).unwrap();
            let cols: Vec<&str> = packet.split('\t').collect();
            let (comment, flags) = (cols.get(1).copied(), cols.get(2).copied());
            match (event["direction"].as_str(), event["message"].as_str()) {
                (Some(d), Some(m)) => {
                    assert_eq!(comment, Some(format!("{d} {m}").as_str()), "{packet}");
                    let bits = if d == "request" {
                        "0x00000002"
                    } else {
                        "0x00000001"
                    };
                    assert_eq!(flags, Some(bits), "{packet}");
                }
                _ => assert_ne!(comment, Some(""), "{packet}"),
            }
        }
    }
}
