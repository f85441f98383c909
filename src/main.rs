//! `busspec`: check protocol specs, render their reference documentation, and decode and
//! encode frames.

mod demo;
mod dissector_cli;
mod frames;
mod interpreted;
mod link_cli;
mod pcapng;
mod sniff;
mod spec_sim;
mod svg;
mod timing;

use std::io::{BufRead, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use busspec_model::diff::{self, Category};
use busspec_model::ir::Direction;
use busspec_model::{docs, load_file, Protocol};
use busspec_protocols::{sd, ub2};
use clap::{Args, CommandFactory, Parser, Subcommand, ValueEnum};

use frames::Engine;

const DECODE_HELP: &str = "\
Decode frames to JSON, one line per frame.

Each HEX argument is one frame: hex digits in wire order (the order the bytes travel), with
spaces and 0x prefixes allowed, so a frame pastes in as printed: \"0xAA21 4101 3E1F 0000 6A\".
Each decoded frame prints as one JSON object, keys in this order:

  {\"protocol\":\"ub2\",\"direction\":\"response\",\"address\":33,\"code\":\"0x4101\",
   \"message\":\"actual_capacitance\",\"fields\":{\"capacitance\":79.98}}

Field values: numbers with a unit are physical values (raw * scale + offset) in the unit the
spec declares (pF, °, °/s, A, V, °C, ...), exact; `special` raw values by name; enums by value
name (a value the enum does not list as its raw number); flags as the list of set flag names
(a set bit the spec does not name as its numeric mask); constants, repeated fields and other
unit-less numbers as raw numbers; text as a string, one character per byte.

Without --direction the direction follows from code and length. Responses that only their
request can tell apart (SD 0x22..0x28, 0x38) need --reply-to <command>.

Decoding is strict: a frame whose values lie outside the ranges the spec gives, whose address
is outside the device range (and is neither the broadcast nor the host address), or that sends
a command to the broadcast address when the command does not accept it, is refused with the
reason, as any bad frame. With --lenient such a frame prints instead, its values decoded with
those rules lifted (by the interpreter, for built-in protocols too), followed by
\"violations\": every rule it breaks, as strict decoding words it:

  {\"protocol\":\"sd\",\"direction\":\"request\",\"address\":32,...,\"violations\":[\"address 0x20 at
   offset 1 is outside the device range 0x01..=0x1E and is not the broadcast or host address\"]}

Exit status: 0 when every frame decoded. Otherwise the frames that decoded still print, each
failure prints one line on stderr, `frame N (TEXT): reason`, and the exit status is 1. TEXT is
the argument, or for a frame longer than 32 bytes its first 32 bytes and the total length
(`AA...AA… (50000 bytes)`). Wrong arguments: 2.

A single HEX argument `-` reads hex frames one per line from stdin instead, as
loggers and terminals print them: each line is read as a HEX argument is (spaces and 0x
prefixes allowed), `#` starts a comment that runs to the end of the line, and lines that are
empty or only a comment are skipped. Each frame prints as above; a line that fails prints
`line N (TEXT): reason` on stderr and the next line is read (exit status 1 at the end, as for
arguments). Each line is decoded on its own: a response only its request tells apart needs
--reply-to. Output is written in large chunks, so `decode P - < log` runs at disk speed.

--stream FILE (- for stdin) reads raw bytes of a bus capture instead, both directions mixed,
and prints one line per frame with \"offset\" (the byte offset of its first byte) as the first
key; bytes that start no frame print as {\"offset\":N,\"skipped\":K,\"bytes\":\"A5FF\"}, and a frame
only its request could identify, with no request before it, as
{\"offset\":N,\"ambiguous\":[names],\"bytes\":\"...\"}. A frame that checksums but breaks a rule of the
spec (range, address, broadcast) prints as {\"offset\":N,\"out_of_spec\":\"reason\", then the keys of
a frame with its values decoded with the rules lifted (when they decode so), \"bytes\":\"...\"};
its bytes are consumed, never skipped. After noise the decoder drops one byte and
tries again; where messages share a code the longest complete frame that checksums wins; a
response is paired with the request just before it (--reply-to gives the request to assume when
there is none). Exit status 0 unless the capture cannot be read (the lines of what was read
before the error print, then `error: cannot read FILE (after N bytes): reason`).

A pcapng file (told by its Section Header Block: 0A0D0D0A, then the byte-order magic) is read
as the capture its packets make, concatenated in file order; offsets count in that
concatenation. Only user link types (147-162) are read. A truncated or damaged file ends the
run with `error: pcapng FILE: block N at byte B: reason`, after the lines of what came before.
Its packets' timestamps (each packet's first byte) time the events: every line gains \"time\"
after \"offset\" (when the event's first byte started, in seconds since the epoch), and where
the spec declares an inter-frame gap (`transactions.inter_frame_gap` at its baud rate, else
`serial.inter_frame_gap_ms`) a silence that long between packets closes a frame, as `busspec
sniff` does live, and \"decided_by\" says what settled the event: \"bytes\", \"timing\" or
\"both\" (see `busspec sniff --help`).

--pcapng OUT also writes the stream to OUT as pcapng: one Enhanced Packet Block per line
printed (frames, and skipped, ambiguous and out-of-spec bytes, so the packets concatenated are
the capture, but that a flag two frames share, as HDLC's may be, is in both), link type LINKTYPE_USER0 (147), the frame's wire bytes as the packet, the
direction in epb_flags (request outbound, response inbound, none for noise), a comment with the
message or the reason, and as timestamp the time the event's first byte starts on the line at
the spec's serial settings (start, data, parity and stop bits at its baud rate), counted from
the epoch in nanoseconds; the interface names the protocol (`busspec NAME`) and the capture.

Output closed early (`| head`) ends the run quietly.";

const ENCODE_HELP: &str = "\
Encode JSON lines from stdin to frames, one hex line per frame.

Each input line is the object `busspec decode` prints (\"offset\" from --stream is ignored):
\"message\" and \"address\" are required; \"direction\" only when a request and a response share
the message name; \"code\" and \"protocol\", when present, must match. \"fields\" holds every field
the message has, in the same form decode prints; constants and repeated fields may be left out.
Physical values convert back exactly: a value that is not a whole number of the unit's steps
is an error naming the field, the value and the step. A value must fit its field's width and
lie in the `range` the spec gives it (or be one of its special values); the address must be a
device address, the broadcast address or the host address, and the broadcast address only for
a command that accepts it. A line that breaks one of these prints the reason, naming the
field and the allowed range, and no frame.

Output: each frame as uppercase hex digits in wire order, no spaces and no 0x prefix
(AA2141013E1F00006A), so `busspec decode P X | busspec encode P` prints X back for any frame X
written that way (from a device address).

Empty lines are skipped. A line that cannot be encoded (bad JSON, unknown message or field,
missing field, value out of range, address or broadcast refused) prints `line N: reason` on
stderr, nothing on stdout, and the next line is read; the exit status is then 1.";

#[derive(Parser)]
#[command(
    name = "busspec",
    version,
    about = "Vendor serial protocols as declarative specs: check them, document them, decode and encode their frames."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Validate spec files and print a summary per protocol; on failure print every error.
    Check {
        /// Spec files (default: every *.yaml in spec/).
        files: Vec<PathBuf>,
    },
    /// Render the Markdown reference of each spec into a directory.
    Docs {
        /// Spec files (default: every *.yaml in spec/).
        files: Vec<PathBuf>,
        /// Where the references go.
        #[arg(long, default_value = "docs")]
        out: PathBuf,
        /// Write nothing; fail if any reference is missing or differs from what the spec gives.
        #[arg(long)]
        check: bool,
    },
    /// Decode frames (hex arguments, hex lines from stdin with `-`, or a raw capture with
    /// --stream) to JSON lines.
    #[command(long_about = DECODE_HELP)]
    Decode(DecodeArgs),
    /// Encode JSON lines read from stdin to frames, one uppercase hex line each.
    #[command(long_about = ENCODE_HELP)]
    Encode(EncodeArgs),
    /// Every change between two revisions of a spec, classified by what it breaks.
    #[command(long_about = DIFF_HELP)]
    Diff(DiffArgs),
    /// Run simulated devices on a pseudo-terminal (printing its path) or a serial port.
    #[command(long_about = SIM_HELP)]
    Sim(SimArgs),
    /// Run one transaction with a device on a serial port and print the reply as JSON.
    #[command(long_about = TALK_HELP)]
    Talk(TalkArgs),
    /// Listen to a bus on a serial port or pseudo-terminal: every frame as a JSON line, timed,
    /// closed by the line's silence as the spec says; optionally written to pcapng.
    #[command(long_about = sniff::SNIFF_HELP)]
    Sniff(sniff::SniffArgs),
    /// Write a Wireshark Lua dissector for built-in protocols and spec files.
    #[command(long_about = dissector_cli::DISSECTOR_HELP)]
    Dissector(dissector_cli::DissectorArgs),
    /// A scripted session against simulated devices: no hardware needed.
    Demo {
        /// Also draw the simulated capacitor's C-curve into this SVG file.
        #[arg(long, value_name = "FILE")]
        svg: Option<PathBuf>,
    },
    /// Many transactions through a faulty simulated line; counts what got through.
    Soak {
        /// Transactions per protocol.
        #[arg(long, default_value_t = 100_000)]
        transactions: u64,
        /// Byte-error rate (0.01 = 1 %), split over corrupted, dropped and duplicated bytes,
        /// with truncated, silenced and late frames at a fifth of it each.
        #[arg(long, default_value_t = 0.01)]
        rate: f64,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Only this protocol (default: every built-in one).
        protocol: Option<String>,
        /// Soak the protocol of this spec file against devices of its `device:` section.
        #[arg(long, value_name = "FILE", requires = "protocol")]
        spec: Option<PathBuf>,
    },
}

const SIM_HELP: &str = "\
Run simulated devices on a line until Ctrl-C.

With --pty, opens a pseudo-terminal pair and prints the path of the end to talk to (one line on
stdout), e.g. /dev/pts/5; `busspec talk --port /dev/pts/5 ...` then talks to the simulators.
With --port PATH, serves on that serial port instead. Several --address options put several
devices on the one line (default: ub2 0x21, sd 0x01, otherwise the spec's default address or
its first from 1). --verbose logs every frame on stderr (`REQUEST -> REPLY`; with --fault-rate,
`(sent as BYTES[, N ms late])` or `(lost on the line)` after a reply the line changed).

UB2 and SD devices are behavioural models of the documents (movements, C-curve, strings).
Every other protocol, built in (modbus, dynamixel, pelco_d, pelco_p, crsf, dynamixel2) or a spec file given with --spec, is
simulated from its spec's `device:` section (spec/SCHEMA.md): the spaces it declares (Modbus's
coils, discrete inputs, holding and input registers; Dynamixel's control table) start at their
initial values, writes change what later reads return, values a reply takes from its request
come from it, and requests past the end of a space or breaking the spec's rules get the
refusal it names (Modbus exceptions 2 and 3, Dynamixel's range error, Dynamixel 2.0's Access Error). Broadcasts are carried
out and answered only where the spec says so; frames that do not decode, or are for another
address, get no reply. A spec without the section answers each command with its reply and
stores nothing.

--fault-rate RATE makes the devices a faulty line's far end, to test a master against: their
replies (never the requests they read) are damaged at that byte-error rate (0.01 = 1 %), split
as `busspec soak --rate` splits it: 60/20/20 over corrupted, dropped and duplicated bytes, and
a fifth of it per reply for each of truncated, silenced and late (1 to 1.8 times the protocol's
reply timeout). --fault-seed N (default 1) seeds it: the same requests in the same order get
the same damage. Ctrl-C (or SIGTERM) ends the simulator; with --fault-rate it then prints
`faults injected: ...` on stderr, as the soak reports it.";

const TALK_HELP: &str = "\
Run one transaction with a device and print its reply as one JSON line, in the shape `busspec
decode` prints.

The command is a command name from the spec (`busspec decode --help` lists the value forms;
docs/<protocol>.md lists the commands) and its fields follow as name=value, in the spec's
units: `go_to_capacitance target=150` (pF), `set_point position=45` (degrees),
`set_mode_of_operation mode=close_loop_control`. Constant and repeated fields are filled in;
the SD freshness counter is the master's and is filled in too.

Movements wait for completion, showing progress on stderr, and print the trigger's reply and
the final completion reply (--no-wait: only the trigger's). `c-curve` (ub2) reads the whole
C-curve table, one line per entry, and with --svg FILE draws it. An SD string readout without
byte_number reads the whole string and prints {\"protocol\",\"address\",\"message\",\"text\"}.

Reads and setters are retried on a garbled reply or a timeout; movements and resets never.

--spec FILE talks the protocol of a spec file read at run time (frames of up to 1,024 bytes):
the same master, its timing, retries, broadcasts and refusals from the spec, with the
interpreter encoding the request and decoding the reply.
Exit status 1 with `error: ...` on stderr when no valid reply comes.";

#[derive(Args)]
struct SimArgs {
    /// The protocol: ub2, sd, modbus, dynamixel, pelco_d, pelco_p, crsf, dynamixel2, or the `protocol:` of the spec given with
    /// --spec.
    protocol: String,
    /// Simulate devices of this spec file (by its `device:` section).
    #[arg(long, value_name = "FILE")]
    spec: Option<PathBuf>,
    /// A device address (decimal or 0x..); repeat for several devices.
    #[arg(long = "address", value_name = "A", value_parser = link_cli::parse_address)]
    addresses: Vec<u8>,
    /// Serve on a new pseudo-terminal and print its path.
    #[arg(long, conflicts_with = "port")]
    pty: bool,
    /// Serve on this serial port.
    #[arg(long, value_name = "PATH")]
    port: Option<String>,
    /// Log every frame on stderr (replies as the devices made them, before --fault-rate).
    #[arg(long)]
    verbose: bool,
    /// Damage the replies at this byte-error rate (0.01 = 1 %), as `soak --rate` damages a
    /// line: corrupted, dropped and duplicated bytes, truncated, silenced and late replies.
    #[arg(long, value_name = "RATE", value_parser = link_cli::parse_rate, allow_negative_numbers = true)]
    fault_rate: Option<f64>,
    /// The seed of --fault-rate's damage: the same seed, the same damage (default 1).
    #[arg(long, value_name = "N", requires = "fault_rate")]
    fault_seed: Option<u64>,
    /// ub2: a device built to the document's examples, not its text: multi-byte numbers travel
    /// most significant byte first (erratum ub2-e01). `talk` refuses to move it.
    #[arg(long)]
    msb_first: bool,
}

#[derive(Args)]
struct TalkArgs {
    /// The serial port (or pseudo-terminal) the device is on.
    #[arg(long, value_name = "PATH")]
    port: String,
    /// Talk the protocol of this spec file (read at run time, by the interpreter).
    #[arg(long, value_name = "FILE")]
    spec: Option<PathBuf>,
    /// Baud rate (default: the document's: ub2 19200, sd 115200).
    #[arg(long)]
    baud: Option<u32>,
    /// Reply timeout in milliseconds (default: the spec's `transactions.response_timeout_ms`,
    /// else 200 below 100,000 baud and 50 from it: ub2 200, sd 50, modbus 1000, dynamixel 50,
    /// pelco_d 200, pelco_p 200, crsf 50, dynamixel2 200).
    #[arg(long, value_name = "MS")]
    timeout: Option<u64>,
    /// A built-in protocol: ub2, sd, modbus, dynamixel, pelco_d, pelco_p, crsf or dynamixel2; or the `protocol:` of --spec.
    protocol: String,
    /// The device address (decimal or 0x..); the SD broadcast ID 0x1F where the command takes it.
    #[arg(long, value_parser = link_cli::parse_address)]
    address: u8,
    /// A command name (snake_case, as in the spec), or `c-curve` (ub2).
    command: String,
    /// The command's fields as name=value.
    args: Vec<String>,
    /// Do not wait for a movement to complete.
    #[arg(long)]
    no_wait: bool,
    /// With c-curve: draw the table into this SVG file.
    #[arg(long, value_name = "FILE")]
    svg: Option<PathBuf>,
    /// Also write every frame sent and received to this pcapng file (link type USER0, 147):
    /// requests outbound, replies inbound, at the time the master saw them.
    #[arg(long, value_name = "FILE")]
    pcapng: Option<PathBuf>,
}

const DIFF_HELP: &str = "\
Every change between two revisions of a spec, classified by what it breaks.

  wire-breaking  a peer built from the old spec reads or writes some frame differently: a code
                 removed, changed or reused; a field's offset, width, signedness, byte order,
                 scale, packing or constant changed; an enum, flag or special value removed or
                 renumbered; a reply a command may get removed; checksum, framing, address range
                 or serial settings changed; a frame's length changed.
  api-breaking   the bytes mean the same, but code using the generated crate or the JSON of
                 `busspec decode` must change: a message, field, unit, enum or value renamed; a
                 field's type changed without a wire change; a range narrowed.
  compatible     a command, response, reply, enum value or flag added; a range widened;
                 documentation, examples, errata or provenance changed.

Both files must load and validate; otherwise every error prints as `file: path: message`.

Output: a summary and one line per change (`path: text`), grouped by category; --json prints
one JSON document instead, --changelog a Markdown changelog entry for release notes.

Exit status: 0 when no change falls in a denied category; 1 when one does (wire-breaking is
denied by default; --allow wire accepts it, --deny api denies API-breaking changes too); 2 for
wrong arguments or a spec that does not load.";

#[derive(Args)]
struct DiffArgs {
    /// The old revision of the spec.
    old: PathBuf,
    /// The new revision of the spec.
    new: PathBuf,
    /// Print one JSON document (for CI) instead of text.
    #[arg(long, conflicts_with = "changelog")]
    json: bool,
    /// Print a Markdown changelog entry instead of text.
    #[arg(long)]
    changelog: bool,
    /// Accept changes of this category (exit 0 despite them).
    #[arg(long, value_enum, value_name = "CATEGORY")]
    allow: Vec<Gate>,
    /// Fail (exit 1) on changes of this category.
    #[arg(long, value_enum, value_name = "CATEGORY")]
    deny: Vec<Gate>,
}

/// A breaking category that can be allowed or denied.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Gate {
    Wire,
    Api,
}

impl Gate {
    fn category(self) -> Category {
        match self {
            Gate::Wire => Category::WireBreaking,
            Gate::Api => Category::ApiBreaking,
        }
    }
}

#[derive(Args)]
struct DecodeArgs {
    /// The protocol: ub2, sd, modbus, dynamixel, pelco_d, pelco_p, crsf, dynamixel2 (built in: generated code), or the `protocol:` of the spec given with --spec.
    protocol: String,
    /// Frames in hex, one per argument, bytes in wire order; spaces and 0x allowed. `-` alone:
    /// hex frames from stdin, one per line (`#` starts a comment).
    #[arg(
        value_name = "HEX",
        required_unless_present = "stream",
        conflicts_with = "stream"
    )]
    frames: Vec<String>,
    /// Decode only as this direction (default: inferred from code and length).
    #[arg(long, value_enum)]
    direction: Option<DirectionArg>,
    /// Load the spec from this file instead of the built-in one.
    #[arg(long, value_name = "FILE")]
    spec: Option<PathBuf>,
    /// The request (a command name) the frames answer: settles responses only it can tell apart.
    #[arg(long, value_name = "COMMAND")]
    reply_to: Option<String>,
    /// The request frame (hex) the frames answer: each frame must be a reply it gets, and every
    /// value that follows from the request must (Modbus: byte count = 2 × quantity).
    #[arg(long, value_name = "HEX", conflicts_with_all = ["stream", "reply_to", "direction"])]
    request: Option<String>,
    /// Read a bus capture from FILE, `-` for stdin, instead of hex arguments: raw bytes, or a
    /// pcapng file (told by its first bytes) whose packets' bytes, in order, are the capture.
    #[arg(long, value_name = "FILE")]
    stream: Option<PathBuf>,
    /// With --stream: also write every event (frames, and the bytes that start none) to FILE as
    /// pcapng, one packet each, link type USER0 (147), direction in epb_flags, timestamps at
    /// the spec's baud rate from the capture's first byte.
    #[arg(long, value_name = "FILE", requires = "stream")]
    pcapng: Option<PathBuf>,
    /// Print a frame that breaks only the spec's ranges, address or broadcast rules, with its
    /// "violations", instead of refusing it (a stream always reports such frames).
    #[arg(long)]
    lenient: bool,
}

#[derive(Args)]
struct EncodeArgs {
    /// The protocol: ub2, sd, modbus, dynamixel, pelco_d, pelco_p, crsf, dynamixel2 (built in: generated code), or the `protocol:` of the spec given with --spec.
    protocol: String,
    /// Load the spec from this file instead of the built-in one.
    #[arg(long, value_name = "FILE")]
    spec: Option<PathBuf>,
    /// The request frame (hex) the replies answer: a reply whose checksum takes in its
    /// request's bytes (`checksum_over_request`) is encoded over them.
    #[arg(long, value_name = "HEX")]
    request: Option<String>,
}

#[derive(Clone, Copy, ValueEnum)]
enum DirectionArg {
    Request,
    Response,
}

impl From<DirectionArg> for Direction {
    fn from(d: DirectionArg) -> Direction {
        match d {
            DirectionArg::Request => Direction::Request,
            DirectionArg::Response => Direction::Response,
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check { files } => check(files),
        Command::Docs { files, out, check } => render_docs(files, &out, check),
        Command::Decode(args) => decode(args),
        Command::Encode(args) => encode(args),
        Command::Diff(args) => return diff(args),
        Command::Sim(a) => link_cli::sim(
            &a.protocol,
            a.spec.as_deref(),
            &a.addresses,
            &link_cli::SimLine {
                pty: a.pty,
                port: a.port.as_deref(),
                verbose: a.verbose,
                faults: a.fault_rate.map(|r| (r, a.fault_seed.unwrap_or(1))),
            },
            a.msb_first,
        ),
        Command::Talk(a) => talk(a),
        Command::Sniff(a) => sniff::sniff(a),
        Command::Dissector(a) => dissector_cli::run(a),
        Command::Demo { svg } => demo(svg.as_deref()),
        Command::Soak {
            transactions,
            rate,
            seed,
            protocol,
            spec: Some(file),
        } => {
            let name = protocol.unwrap_or_default();
            protocol_spec("soak", &name, &file)
                .and_then(|p| link_cli::soak_spec(p, transactions, rate, seed))
        }
        Command::Soak {
            transactions,
            rate,
            seed,
            protocol,
            spec: None,
        } => {
            let chosen: Vec<&str> = match protocol.as_deref() {
                Some(p) => vec![p],
                None => link_cli::soak_targets(),
            };
            link_cli::soak(&chosen, transactions, rate, seed)
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            if !msg.is_empty() {
                eprintln!("{msg}");
            }
            ExitCode::FAILURE
        }
    }
}

/// The spec files to work on: those given, or every `*.yaml` in `spec/`, sorted.
fn spec_files(files: Vec<PathBuf>) -> Result<Vec<PathBuf>, String> {
    if !files.is_empty() {
        return Ok(files);
    }
    let dir = Path::new("spec");
    let entries = std::fs::read_dir(dir).map_err(|e| {
        format!(
            "error: no spec files given and cannot read {}: {e}",
            dir.display()
        )
    })?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    found.sort();
    if found.is_empty() {
        return Err(format!(
            "error: no spec files given and no *.yaml in {}",
            dir.display()
        ));
    }
    Ok(found)
}

/// Every diagnostic of a spec that failed to load, then a count line.
fn load_errors(d: &busspec_model::Diagnostics) -> String {
    let n = d.items.len();
    format!(
        "{d}\n{}: {n} error{}",
        d.file,
        if n == 1 { "" } else { "s" }
    )
}

/// Loads every file, printing all diagnostics of every file that fails.
fn load_all(files: Vec<PathBuf>) -> Result<Vec<(PathBuf, Protocol)>, String> {
    let mut loaded = Vec::new();
    let mut errors = Vec::new();
    for f in spec_files(files)? {
        match load_file(&f) {
            Ok(p) => loaded.push((f, p)),
            Err(d) => errors.push(load_errors(&d)),
        }
    }
    if errors.is_empty() {
        Ok(loaded)
    } else {
        Err(errors.join("\n"))
    }
}

fn check(files: Vec<PathBuf>) -> Result<(), String> {
    for (f, p) in load_all(files)? {
        let printed = p.examples.iter().filter(|e| e.printed.is_some()).count();
        let corrected = p.examples.iter().filter(|e| e.corrected.is_some()).count();
        println!(
            "{}: {} ({} rev {}): {} commands, {} responses, {} examples ({} printed, {} derived, {} corrected), {} errata: ok",
            f.display(),
            p.name,
            p.document.title,
            p.document.revision,
            p.commands.len(),
            p.responses.len(),
            p.examples.len(),
            printed,
            p.examples.len() - printed,
            corrected,
            p.errata.len()
        );
    }
    Ok(())
}

fn render_docs(files: Vec<PathBuf>, out: &Path, check: bool) -> Result<(), String> {
    let loaded = load_all(files)?;
    if !check {
        std::fs::create_dir_all(out)
            .map_err(|e| format!("error: cannot create {}: {e}", out.display()))?;
    }
    let mut stale = Vec::new();
    for (f, p) in loaded {
        let source = f.to_string_lossy().replace('\\', "/");
        let text = docs::render(&p, &source);
        let target = out.join(format!("{}.md", p.name));
        let current = std::fs::read_to_string(&target).ok();
        if current.as_deref() == Some(text.as_str()) {
            continue;
        }
        if check {
            stale.push(target.display().to_string());
        } else {
            std::fs::write(&target, text)
                .map_err(|e| format!("error: cannot write {}: {e}", target.display()))?;
            println!("wrote {}", target.display());
        }
    }
    if stale.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "stale documentation (run `busspec docs` and commit): {}",
            stale.join(", ")
        ))
    }
}

/// Exits with clap's usage error (status 2) for a subcommand's arguments.
fn usage_error(subcommand: &str, msg: String) -> ! {
    let mut cmd = Cli::command();
    let sub = cmd.find_subcommand_mut(subcommand).cloned();
    match sub {
        Some(sub) => {
            let mut sub = sub.bin_name(format!("busspec {subcommand}"));
            sub.error(clap::error::ErrorKind::InvalidValue, msg).exit()
        }
        None => cmd.error(clap::error::ErrorKind::InvalidValue, msg).exit(),
    }
}

/// The protocol to work with: a built-in one (its generated code, embedded so the binary works
/// from any directory), or the spec in `--spec FILE` (the interpreter), whose name must match.
/// The spec file `file`, which must define protocol `name`.
fn protocol_spec(subcommand: &str, name: &str, file: &Path) -> Result<Protocol, String> {
    protocol(subcommand, name, Some(file)).map(|e| e.spec)
}

fn protocol(subcommand: &str, name: &str, spec: Option<&Path>) -> Result<Engine, String> {
    let loaded = match spec {
        Some(file) => Engine::interpreted(load_file(file).map_err(|d| load_errors(&d))?),
        None => match Engine::built_in(name) {
            Some(engine) => engine?,
            None => usage_error(
                subcommand,
                format!(
                    "unknown protocol `{name}`: the built-in ones are {} (or give --spec FILE)",
                    busspec_protocols::PROTOCOLS.join(", ")
                ),
            ),
        },
    };
    if loaded.spec.name != name {
        let file = spec.map(|f| f.display().to_string()).unwrap_or_default();
        usage_error(
            subcommand,
            format!(
                "{file} defines protocol `{}`, not `{name}`: name the protocol the spec defines",
                loaded.spec.name
            ),
        );
    }
    Ok(loaded)
}

/// Output gathered in a buffer and written in large chunks, not a system call per line: when
/// it holds [`Out::CHUNK`] bytes, before a line goes to stderr (so the two interleave as they
/// were printed), and at the end ([`Out::finish`]). A closed pipe (`| head`) ends the run
/// quietly; any other write error is reported.
struct Out<W: Write> {
    w: W,
    buf: Vec<u8>,
}

impl<W: Write> Out<W> {
    /// Bytes gathered before they are written.
    const CHUNK: usize = 64 * 1024;

    fn new(w: W) -> Self {
        Out {
            w,
            buf: Vec::with_capacity(Self::CHUNK + 4096),
        }
    }

    /// Writes one line.
    fn line(&mut self, line: &str) -> Result<(), String> {
        self.buf.extend_from_slice(line.as_bytes());
        self.buf.push(b'\n');
        self.written()
    }

    /// Writes what is gathered once it is a chunk's worth (after lines went to `self.buf`).
    fn written(&mut self) -> Result<(), String> {
        if self.buf.len() >= Self::CHUNK {
            self.flush()?;
        }
        Ok(())
    }

    /// Writes everything gathered.
    fn flush(&mut self) -> Result<(), String> {
        let result = self.w.write_all(&self.buf).and_then(|()| self.w.flush());
        self.buf.clear();
        result.map_err(|e| {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                String::new()
            } else {
                format!("error: cannot write output: {e}")
            }
        })
    }

    /// Writes everything gathered, then `message` to stderr.
    fn error(&mut self, message: std::fmt::Arguments) -> Result<(), String> {
        self.flush()?;
        eprintln!("{message}");
        Ok(())
    }

    fn finish(mut self) -> Result<(), String> {
        self.flush()
    }
}

fn decode(args: DecodeArgs) -> Result<(), String> {
    let mut engine = protocol("decode", &args.protocol, args.spec.as_deref())?;
    let p = &engine.spec;
    let reply_to = args.reply_to.as_deref().map(|name| {
        p.commands
            .iter()
            .position(|c| c.name == name)
            .unwrap_or_else(|| {
                usage_error(
                    "decode",
                    format!("--reply-to `{name}` is not a command of {}", p.name),
                )
            })
    });
    let mut direction = args.direction.map(Direction::from);
    let mut reply_to = reply_to;
    let request = match &args.request {
        None => None,
        Some(text) => {
            let frame = busspec_json::parse_hex(text)
                .and_then(|wire| {
                    busspec_model::interp::decode(p, Some(Direction::Request), None, &wire)
                        .map_err(|e| e.to_string())
                })
                .unwrap_or_else(|e| usage_error("decode", format!("--request {text}: {e}")));
            direction = Some(Direction::Response);
            reply_to = Some(frame.message.index);
            // Owned: `engine` is borrowed mutably below, while the request is still needed.
            Some((
                frame.into_owned(),
                busspec_json::parse_hex(text).unwrap_or_default(),
            ))
        }
    };
    if let Some((_, wire)) = &request {
        engine.set_request(wire);
    }
    let mut out = Out::new(std::io::stdout().lock());
    if let Some(file) = &args.stream {
        if args.pcapng.as_deref() == Some(Path::new("-")) {
            usage_error(
                "decode",
                "--pcapng needs a file: stdout carries the JSON lines".into(),
            );
        }
        let pcapng = args.pcapng.as_deref();
        decode_stream(&engine, direction, reply_to, file, pcapng, &mut out)?;
        return out.finish();
    }
    if args.frames.iter().any(|f| f == "-") {
        if args.frames.len() > 1 {
            usage_error(
                "decode",
                "`-` (hex frames from stdin, one per line) must be the only HEX argument".into(),
            );
        }
        let failed = decode_lines(&mut engine, direction, reply_to, args.lenient, &mut out)?;
        out.finish()?;
        return if failed == 0 {
            Ok(())
        } else {
            Err(String::new())
        };
    }
    let mut failed = 0;
    for (i, text) in args.frames.iter().enumerate() {
        let wire = busspec_json::parse_hex(text);
        let result = wire.as_ref().map_err(String::clone).and_then(|wire| {
            if let Some((req, req_wire)) = &request {
                busspec_model::interp::decode_reply_with(&engine.spec, req, Some(req_wire), wire)
                    .map_err(|e| e.to_string())?;
            }
            if args.lenient {
                engine.decode_lenient_into(direction, reply_to, wire, &mut out.buf)
            } else {
                engine.decode_into(direction, reply_to, wire, &mut out.buf)
            }
        });
        match result {
            Ok(()) => out.written()?,
            Err(reason) => {
                failed += 1;
                let shown = quoted(text, wire.as_deref().ok());
                out.error(format_args!("frame {} ({shown}): {reason}", i + 1))?;
            }
        }
    }
    out.finish()?;
    if failed == 0 {
        Ok(())
    } else {
        Err(String::new())
    }
}

/// The frame on one line of `decode P -` input: the text before any `#` (a comment), trimmed;
/// `None` for a line with no frame (empty, blank or only a comment).
fn frame_text(line: &str) -> Option<&str> {
    let text = line.split_once('#').map_or(line, |(frame, _)| frame).trim();
    (!text.is_empty()).then_some(text)
}

/// Reads stdin line by line for `decode P -` and `encode`: `each` gets the line's number and
/// text and writes its output to `out`, or says why the line failed (`Err`: the whole error
/// line, printed on stderr after everything before it); a line that is not UTF-8 fails as
/// `line N: not UTF-8 text: …`. Returns how many lines failed; a read error ends the run with
/// its reason, after the output of the lines before it.
fn stdin_lines<W: Write>(
    out: &mut Out<W>,
    mut each: impl FnMut(usize, &str, &mut Out<W>) -> Result<(), String>,
) -> Result<usize, String> {
    let stdin = std::io::stdin();
    let mut input = std::io::BufReader::with_capacity(Out::<W>::CHUNK, stdin.lock());
    let mut failed = 0;
    let mut line = Vec::new();
    for number in 1.. {
        line.clear();
        match input.read_until(b'\n', &mut line) {
            Ok(0) => break,
            Ok(_) => {}
            Err(e) => {
                out.flush()?;
                return Err(format!("error: cannot read stdin (line {number}): {e}"));
            }
        }
        let result = match std::str::from_utf8(&line) {
            Ok(text) => each(number, text, out),
            Err(e) => Err(format!(
                "line {number}: not UTF-8 text: invalid byte at offset {}",
                e.valid_up_to()
            )),
        };
        match result {
            Ok(()) => out.written()?,
            Err(reason) => {
                failed += 1;
                out.error(format_args!("{reason}"))?;
            }
        }
    }
    Ok(failed)
}

/// `decode P -`: hex frames from stdin, one per line (see DECODE_HELP). Each frame's line goes
/// to `out`; each line that fails prints `line N (TEXT): reason` on stderr and the next line is
/// read. Returns how many lines failed; a read error ends the run with its reason.
fn decode_lines(
    engine: &mut Engine,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    lenient: bool,
    out: &mut Out<impl Write>,
) -> Result<usize, String> {
    stdin_lines(out, |number, line, out| {
        let Some(text) = frame_text(line) else {
            return Ok(());
        };
        let wire = busspec_json::parse_hex(text);
        wire.as_ref()
            .map_err(String::clone)
            .and_then(|wire| {
                if lenient {
                    engine.decode_lenient_into(direction, reply_to, wire, &mut out.buf)
                } else {
                    engine.decode_into(direction, reply_to, wire, &mut out.buf)
                }
            })
            .map_err(|reason| {
                let shown = quoted(text, wire.as_deref().ok());
                format!("line {number} ({shown}): {reason}")
            })
    })
}

/// The most bytes of a frame an error line quotes.
const QUOTED_BYTES: usize = 32;

/// A frame's argument as an error line quotes it: as given, or, for a frame longer than
/// [`QUOTED_BYTES`], its first bytes in hex and the total length; text that is not hex and
/// runs longer than twice that many characters, likewise by characters.
fn quoted(text: &str, wire: Option<&[u8]>) -> String {
    match wire {
        Some(wire) if wire.len() > QUOTED_BYTES => format!(
            "{}… ({} bytes)",
            frames::hex(&wire[..QUOTED_BYTES]),
            wire.len()
        ),
        Some(_) => text.to_owned(),
        None => {
            let n = text.chars().count();
            if n > 4 * QUOTED_BYTES {
                let head: String = text.chars().take(2 * QUOTED_BYTES).collect();
                format!("{head}… ({n} characters)")
            } else {
                text.to_owned()
            }
        }
    }
}

fn decode_stream(
    engine: &Engine,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    file: &Path,
    pcapng: Option<&Path>,
    out: &mut Out<impl Write>,
) -> Result<(), String> {
    let name = file.display().to_string();
    let mut input: Box<dyn Read> = if name == "-" {
        Box::new(std::io::stdin().lock())
    } else {
        Box::new(std::fs::File::open(file).map_err(|e| format!("error: cannot read {name}: {e}"))?)
    };
    let mut writer = match pcapng {
        None => None,
        Some(path) => Some(pcapng::create(
            path,
            &engine.spec,
            &name,
            engine.spec.serial.baud,
        )?),
    };
    let mut stream = Feed {
        lines: Lines::Plain(engine.stream(direction, reply_to)),
        writer: writer.as_mut(),
    };
    let mut chunk = vec![0u8; Out::<std::io::Sink>::CHUNK];
    let mut read = 0u64;
    // The first bytes tell a pcapng file from a raw capture.
    let mut head = Vec::new();
    loop {
        let n = match read_some(&mut input, &mut chunk) {
            Ok(n) => n,
            Err(e) => {
                // What was decoded before the error is printed, then the error.
                out.flush()?;
                return Err(format!(
                    "error: cannot read {name} (after {read} bytes): {e}"
                ));
            }
        };
        read += n as u64;
        if n == 0 {
            break;
        }
        if head.len() < 12 {
            head.extend_from_slice(&chunk[..n]);
            if head.len() < 12 {
                continue;
            }
            if pcapng::is_pcapng(&head) {
                // A capture with timestamps: framed by silence too, where the spec has a gap.
                let baud = engine.spec.serial.baud;
                let char_ns = timing::char_ns(engine.spec.transactions.character_bits, baud);
                stream.timed(char_ns, timing::spec_gap_ns(&engine.spec, baud));
                let mut end_ns = 0u64;
                let head = std::mem::take(&mut head);
                let captured = pcapng::read(&name, head, &mut input, |p, time| {
                    // A packet's time is its first byte's; without one it follows the last.
                    let start = time.unwrap_or(end_ns);
                    end_ns = start.saturating_add((p.len() as u64).saturating_mul(char_ns));
                    stream.push_timed(p, start, char_ns, out)
                });
                if let Err(e) = captured {
                    out.flush()?;
                    return Err(e);
                }
                break;
            }
            stream.push(&std::mem::take(&mut head), out)?;
            continue;
        }
        stream.push(&chunk[..n], out)?;
    }
    // A capture shorter than a pcapng header is raw bytes.
    stream.push(&head, out)?;
    let before = out.buf.len();
    stream.lines.finish(&mut out.buf);
    if let Some(w) = stream.writer {
        w.lines(&out.buf[before..])?;
    }
    if let Some(w) = writer {
        w.finish()?;
    }
    Ok(())
}

/// Reads what `input` has, retrying where a signal interrupted it.
fn read_some(input: &mut dyn Read, chunk: &mut [u8]) -> std::io::Result<usize> {
    loop {
        match input.read(chunk) {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            other => return other,
        }
    }
}

/// A capture's bytes on their way to the stream decoder and, with --pcapng, the file.
struct Feed<'a, 'w> {
    lines: Lines<'a>,
    writer: Option<&'w mut pcapng::Writer<std::io::BufWriter<std::fs::File>>>,
}

/// A stream decoder's lines, as they are (a raw capture) or timed ([`timing::Timed`]).
enum Lines<'a> {
    Plain(Box<dyn frames::LineStream + 'a>),
    Timed(timing::Timed<'a>),
    /// Only while one becomes the other.
    Moving,
}

impl Lines<'_> {
    fn finish(&mut self, out: &mut Vec<u8>) {
        match self {
            Lines::Plain(s) => s.finish(out),
            Lines::Timed(t) => t.finish(out),
            Lines::Moving => {}
        }
    }
}

impl Feed<'_, '_> {
    /// From now on the bytes come with times: lines are timed, and closed by gaps of `gap_ns`.
    fn timed(&mut self, char_ns: u64, gap_ns: Option<u64>) {
        if let Lines::Plain(s) = std::mem::replace(&mut self.lines, Lines::Moving) {
            self.lines = Lines::Timed(timing::Timed::new(s, char_ns, gap_ns));
        }
    }

    fn push(&mut self, data: &[u8], out: &mut Out<impl Write>) -> Result<(), String> {
        self.push_at(data, None, out)
    }

    /// `data` whose first byte started at `start_ns`, one character every `char_ns`.
    fn push_timed(
        &mut self,
        data: &[u8],
        start_ns: u64,
        char_ns: u64,
        out: &mut Out<impl Write>,
    ) -> Result<(), String> {
        self.push_at(data, Some((start_ns, char_ns)), out)
    }

    fn push_at(
        &mut self,
        data: &[u8],
        time: Option<(u64, u64)>,
        out: &mut Out<impl Write>,
    ) -> Result<(), String> {
        // In pieces whose lines fit the output buffer's chunk.
        let mut done = 0u64;
        for piece in data.chunks(1024) {
            done += piece.len() as u64;
            let before = out.buf.len();
            match (&mut self.lines, time) {
                (Lines::Timed(t), Some((start, char_ns))) => {
                    t.push(piece, start.saturating_add(done * char_ns), &mut out.buf)
                }
                (Lines::Timed(t), None) => t.push_following(piece, &mut out.buf),
                (Lines::Plain(s), _) => s.push(piece, &mut out.buf),
                (Lines::Moving, _) => {}
            }
            if let Some(w) = self.writer.as_mut() {
                w.bytes(piece);
                w.lines(&out.buf[before..])?;
            }
            out.written()?;
        }
        Ok(())
    }
}

fn encode(args: EncodeArgs) -> Result<(), String> {
    let engine = protocol("encode", &args.protocol, args.spec.as_deref())?;
    let request = args.request.as_deref().map(|text| {
        busspec_json::parse_hex(text)
            .and_then(|wire| {
                busspec_model::interp::decode(&engine.spec, Some(Direction::Request), None, &wire)
                    .map_err(|e| e.to_string())?;
                Ok(wire)
            })
            .unwrap_or_else(|e| usage_error("encode", format!("--request {text}: {e}")))
    });
    let mut out = Out::new(std::io::stdout().lock());
    let failed = stdin_lines(&mut out, |number, text, out| {
        if text.trim().is_empty() {
            return Ok(());
        }
        let wire = engine
            .encode_reply(text.trim(), request.as_deref())
            .map_err(|reason| format!("line {number}: {reason}"))?;
        out.line(&frames::hex(&wire))
    })?;
    out.finish()?;
    if failed == 0 {
        Ok(())
    } else {
        Err(String::new())
    }
}

/// The `--json` document of `busspec diff`; README.md documents it.
#[derive(serde::Serialize)]
struct DiffJson<'a> {
    old: &'a diff::Side,
    new: &'a diff::Side,
    counts: std::collections::BTreeMap<&'static str, usize>,
    denied: Vec<&'static str>,
    failed: bool,
    changes: &'a [diff::Change],
}

fn diff(args: DiffArgs) -> ExitCode {
    if let Some(g) = args.allow.iter().find(|g| args.deny.contains(g)) {
        let name = g.to_possible_value().map(|v| v.get_name().to_owned());
        usage_error(
            "diff",
            format!("`{}` is both allowed and denied", name.unwrap_or_default()),
        );
    }
    let mut denied = vec![Category::WireBreaking];
    denied.retain(|c| !args.allow.iter().any(|g| g.category() == *c));
    for g in &args.deny {
        if !denied.contains(&g.category()) {
            denied.push(g.category());
        }
    }
    // Both sides load before either is reported, so every error of both files shows.
    let (old, new) = (load_file(&args.old), load_file(&args.new));
    let (old, new) = match (old, new) {
        (Ok(o), Ok(n)) => (o, n),
        (o, n) => {
            for d in [o.err(), n.err()].into_iter().flatten() {
                eprintln!("{}", load_errors(&d));
            }
            return ExitCode::from(2);
        }
    };
    let changes = diff::diff(&old, &new);
    let sides = (
        diff::Side::of(&args.old.display().to_string(), &old),
        diff::Side::of(&args.new.display().to_string(), &new),
    );
    let failing: Vec<Category> = denied
        .iter()
        .copied()
        .filter(|c| changes.iter().any(|ch| ch.category == *c))
        .collect();
    let text = if args.json {
        let doc = DiffJson {
            old: &sides.0,
            new: &sides.1,
            counts: diff::counts(&changes)
                .into_iter()
                .map(|(c, n)| (c.as_str(), n))
                .collect(),
            denied: denied.iter().map(|c| c.as_str()).collect(),
            failed: !failing.is_empty(),
            changes: &changes,
        };
        serde_json::to_string_pretty(&doc).unwrap_or_default() + "\n"
    } else if args.changelog {
        diff::render_markdown(&sides.0, &sides.1, &changes)
    } else {
        diff::render_text(&sides.0, &sides.1, &changes)
    };
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("error: cannot write output: {e}");
            return ExitCode::from(2);
        }
    }
    if failing.is_empty() {
        return ExitCode::SUCCESS;
    }
    for c in failing {
        let n = changes.iter().filter(|ch| ch.category == c).count();
        let why = if c == Category::WireBreaking {
            "pass --allow wire to accept them"
        } else {
            "denied by --deny api"
        };
        eprintln!(
            "error: {n} {} change{} ({why})",
            c.as_str(),
            if n == 1 { "" } else { "s" }
        );
    }
    ExitCode::FAILURE
}

fn talk(a: TalkArgs) -> Result<(), String> {
    let p = protocol("talk", &a.protocol, a.spec.as_deref())?.spec;
    let options = link_cli::TalkOptions {
        port: &a.port,
        baud: a.baud,
        address: a.address,
        command: &a.command,
        args: &a.args,
        wait: !a.no_wait,
        svg: a.svg.as_deref(),
        timeout: a.timeout.map(std::time::Duration::from_millis),
        pcapng: a.pcapng.as_deref(),
    };
    let talked = if a.spec.is_some() {
        link_cli::talk_spec(p, &options)
    } else {
        link_cli::talk(&p, &options)
    };
    talked.map_err(|e| {
        if e.starts_with("error: ") {
            e
        } else {
            format!("error: {e}")
        }
    })
}

fn demo(svg: Option<&Path>) -> Result<(), String> {
    let ub2 = busspec_json::load_spec::<ub2::Ub2>()?;
    let sd = busspec_json::load_spec::<sd::Sd>()?;
    link_cli::demo(&ub2, &sd, svg).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts the writes it gets; fails them with `error` once set.
    #[derive(Default)]
    struct Counting {
        writes: usize,
        bytes: Vec<u8>,
        error: Option<std::io::ErrorKind>,
    }

    impl Write for Counting {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if let Some(kind) = self.error {
                return Err(std::io::Error::new(kind, "refused"));
            }
            self.writes += 1;
            self.bytes.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn output_is_written_in_chunks_not_per_line() {
        let mut sink = Counting::default();
        let mut want = String::new();
        let mut out = Out::new(&mut sink);
        for i in 0..100_000 {
            let line = format!("{{\"offset\":{i}}}");
            out.line(&line).unwrap();
            want.push_str(&line);
            want.push('\n');
        }
        out.finish().unwrap();
        assert_eq!(sink.bytes, want.as_bytes());
        let chunks = want.len() / Out::<std::io::Sink>::CHUNK + 1;
        assert!(sink.writes <= chunks, "{} writes", sink.writes);
        // An error line goes out after everything printed before it.
        let mut sink = Counting::default();
        let mut out = Out::new(&mut sink);
        out.line("before").unwrap();
        out.error(format_args!("test: an error line")).unwrap();
        drop(out);
        assert_eq!(sink.bytes, b"before\n");
    }

    #[test]
    fn a_closed_pipe_ends_quietly_and_other_write_errors_are_reported() {
        for (kind, want) in [
            (std::io::ErrorKind::BrokenPipe, ""),
            (
                std::io::ErrorKind::PermissionDenied,
                "error: cannot write output: refused",
            ),
        ] {
            let mut sink = Counting {
                error: Some(kind),
                ..Counting::default()
            };
            let mut out = Out::new(&mut sink);
            out.line("a line").unwrap();
            assert_eq!(out.finish(), Err(want.to_owned()));
        }
    }
}
