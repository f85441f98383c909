//! The commands that talk to devices: `sim`, `talk`, `demo`, `soak`.

use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

use busspec_devices::master::{CCurvePoint, SdMaster, SdString, Ub2Master};
use busspec_devices::sim::sd::SdSim;
use busspec_devices::sim::ub2::Ub2Sim;
use busspec_devices::soak;
use busspec_devices::{Sd, Ub2};
use busspec_link::clock::Clock;
use busspec_link::fault::{Fate, FaultConfig, FaultyReplies};
use busspec_link::master::{LinkError, Progress};
use busspec_link::protocol::{byte_order_source, declared_byte_order};
use busspec_link::sim::{serve, Device};
use busspec_link::soak::SoakConfig;
use busspec_link::{Link, Master, Message, Protocol, SerialTransport, SystemClock, Transport};
use busspec_model::ir::Direction;
use busspec_model::Protocol as Spec;
use busspec_protocols::{sd, ub2, CommandKind, FrameBuffer, RequestMessage};

use crate::{frames, spec_sim, svg};

/// An address as `33`, `0x21` or `0X21`.
pub fn parse_address(text: &str) -> Result<u8, String> {
    let t = text.trim();
    let parsed = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => t.parse::<u8>(),
    };
    parsed.map_err(|_| format!("address `{text}` is not a byte (decimal, or hex with 0x)"))
}

/// A byte-error rate for `sim --fault-rate`: a number from 0 to 1.
pub fn parse_rate(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(r) if (0.0..=1.0).contains(&r) => Ok(r),
        Ok(_) => Err(format!(
            "`{text}` is not a probability: a byte-error rate lies from 0 to 1 (0.01 = 1 %)"
        )),
        Err(_) => Err(format!(
            "`{text}` is not a number: a byte-error rate lies from 0 to 1 (0.01 = 1 %)"
        )),
    }
}

/// Where and how `busspec sim` serves.
pub struct SimLine<'a> {
    /// A new pseudo-terminal (its path printed).
    pub pty: bool,
    /// Or this serial port.
    pub port: Option<&'a str>,
    /// Log every frame on stderr.
    pub verbose: bool,
    /// Damage the replies: a byte-error rate as `soak --rate`'s, and the generator's seed.
    pub faults: Option<(f64, u64)>,
}

/// The request frame for `command` with `name=value` arguments, through the same JSON contract
/// as `busspec encode`: values in the spec's units, enum and special values by name.
#[cfg(test)]
fn request_frame(
    spec: &Spec,
    command: &str,
    address: u8,
    args: &[String],
) -> Result<Vec<u8>, String> {
    let line = request_line(spec, command, address, args)?;
    frames::encode_built_in(spec, &line).map_err(|e| format!("{command}: {e}"))
}

/// The `encode` JSON line for `command` with `name=value` arguments.
fn request_line(
    spec: &Spec,
    command: &str,
    address: u8,
    args: &[String],
) -> Result<String, String> {
    let Some(c) = spec.commands.iter().find(|c| c.name == command) else {
        return Err(format!(
            "unknown command `{command}` in {}; its commands: {}",
            spec.name,
            spec.commands
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    };
    let mut fields = serde_json::Map::new();
    for arg in args {
        let Some((name, value)) = arg.split_once('=') else {
            return Err(format!(
                "argument `{arg}` is not name=value (the fields of {command}: {})",
                field_list(c)
            ));
        };
        // JSON where it parses (numbers, quoted text, lists), else a name (enum or special value).
        let v = serde_json::from_str::<serde_json::Value>(value)
            .unwrap_or_else(|_| serde_json::Value::String(value.to_owned()));
        fields.insert(name.to_owned(), v);
    }
    // The freshness counter is the master's to keep (SD §3.1): it replaces whatever is given.
    if c.leaves().any(|l| l.name() == "freshness") && !fields.contains_key("freshness") {
        fields.insert("freshness".to_owned(), serde_json::Value::from(0));
    }
    // What encode fills in itself (constants, repeats, values following another field, a
    // list's count: Modbus's `byte_count`) need not be given.
    let missing: Vec<String> = c
        .leaves()
        .filter(|l| match l {
            busspec_model::ir::Leaf::Field(i, _) => !c.is_derived(*i),
            busspec_model::ir::Leaf::Bits(_, _, b) => b.constant.is_none(),
        })
        .map(|l| l.name().to_owned())
        .filter(|n| !fields.contains_key(n))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "{command} needs {}: give them as name=value",
            missing.join(", ")
        ));
    }
    let line = serde_json::json!({
        "message": command,
        "direction": "request",
        "address": address,
        "fields": fields,
    });
    Ok(line.to_string())
}

fn field_list(c: &busspec_model::ir::Message) -> String {
    let names: Vec<String> = c.leaves().map(|l| l.name().to_owned()).collect();
    if names.is_empty() {
        "none".to_owned()
    } else {
        names.join(", ")
    }
}

/// The JSON line `busspec decode` prints for this reply, from the typed reply itself.
fn reply_line<P: Protocol>(spec: &Spec, response: &P::Response, address: u8) -> String {
    busspec_json::message_line(spec, Direction::Response, address, response, None)
        .unwrap_or_else(|e| format!("{{\"error\":{:?}}}", e))
}

/// Prints progress on stderr, at most every `every`.
struct ProgressLine {
    last: Option<Instant>,
    every: Duration,
}

impl ProgressLine {
    fn new() -> Self {
        ProgressLine {
            last: None,
            every: Duration::from_millis(250),
        }
    }

    fn show(&mut self, unit: &str, p: Progress) {
        if self.last.is_some_and(|t| t.elapsed() < self.every) {
            return;
        }
        self.last = Some(Instant::now());
        match p {
            Progress::Moving { elapsed, position } => eprintln!(
                "moving: {position:.2} {unit} after {:.1} s",
                elapsed.as_secs_f64()
            ),
            Progress::Read { done } => eprintln!("read {done} {unit}"),
        }
    }
}

/// What `talk` does besides one transaction.
pub struct TalkOptions<'a> {
    pub port: &'a str,
    pub baud: Option<u32>,
    pub address: u8,
    pub command: &'a str,
    pub args: &'a [String],
    /// Wait for a movement to complete (default).
    pub wait: bool,
    pub svg: Option<&'a Path>,
    pub timeout: Option<Duration>,
    /// Every frame sent and received also goes to this pcapng file.
    pub pcapng: Option<&'a Path>,
}

fn link_error(e: LinkError) -> String {
    format!("error: {e}")
}

fn open<P: Link>(
    spec: &Spec,
    o: &TalkOptions,
) -> Result<Master<P, SerialTransport, SystemClock>, String> {
    let baud = o.baud.unwrap_or(P::baud());
    if baud == 0 {
        return Err("error: --baud 0: a baud rate is positive".to_owned());
    }
    let t = SerialTransport::open(o.port, baud).map_err(|e| format!("error: {e}"))?;
    let mut m = Master::new(t, SystemClock::new());
    if let Some(path) = o.pcapng {
        record(&mut m, spec, o.port, baud, path)?;
    }
    if baud != P::baud() {
        // The gap in character times, and the driver-enable timing, follow the line's rate.
        let line = busspec_link::Line {
            baud,
            ..busspec_link::Line::for_link::<P>()
        };
        let timing = busspec_link::Timing {
            inter_request_gap: busspec_link::Timing::for_line::<P>(&line).inter_request_gap,
            ..m.timing()
        };
        m = m.with_line(line).with_timing(timing);
    }
    if let Some(timeout) = o.timeout {
        let mut timing = m.timing();
        timing.reply_timeout = timeout;
        timing.settle = timeout;
        m = m.with_timing(timing);
    }
    Ok(m)
}

/// Writes every frame `m` sends or receives to the pcapng file at `path`, as it goes: a request
/// outbound, what comes back inbound (with why the master rejected it, if it did), each at the
/// wall-clock time the master saw it. A write that fails is said on stderr once; the
/// transactions go on.
fn record<P: Link>(
    m: &mut Master<P, SerialTransport, SystemClock>,
    spec: &Spec,
    port: &str,
    baud: u32,
    path: &Path,
) -> Result<(), String> {
    use busspec_link::master::TraceEvent;
    let name = path.display().to_string();
    let file =
        std::fs::File::create(path).map_err(|e| format!("error: cannot create {name}: {e}"))?;
    let mut out = crate::pcapng::Writer::new(file, &name, spec, port, baud)?;
    let mut failed = false;
    m.observe(move |e| {
        let (bytes, flags, comment) = match e {
            TraceEvent::Sent { attempt, bytes } => (
                *bytes,
                crate::pcapng::OUTBOUND,
                format!("request, attempt {attempt}"),
            ),
            TraceEvent::Received {
                attempt,
                bytes,
                rejected,
            } => (
                *bytes,
                crate::pcapng::INBOUND,
                match rejected {
                    None => format!("reply, attempt {attempt}"),
                    Some(why) => format!("rejected, attempt {attempt}: {why}"),
                },
            ),
            _ => return,
        };
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        if let Err(e) = out.packet(now, bytes, flags, comment) {
            if !std::mem::replace(&mut failed, true) {
                eprintln!("{e}");
            }
        }
    });
    Ok(())
}

/// `busspec talk`: one transaction (or one long operation) on a real port.
pub fn talk(spec: &Spec, o: &TalkOptions) -> Result<(), String> {
    // UB2 and SD each have long operations of their own (movements, the C-curve, strings).
    match spec.name.as_str() {
        n if n == Ub2::NAME => talk_ub2(spec, o),
        n if n == Sd::NAME => talk_sd(spec, o),
        // Every other protocol by its spec alone: timing, retries, broadcasts and refusals
        // from its `transactions:` section, its commands' `broadcast` and its `kind: nak`.
        name => {
            busspec_protocols::with_protocol(name, TalkPlain { spec, o }).unwrap_or_else(|| {
                Err(format!(
                    "error: busspec cannot talk {name}: it is not a built-in protocol"
                ))
            })
        }
    }
}

/// `talk --spec FILE`: one transaction in the protocol of a spec read at run time, through the
/// same master ([`crate::interpreted::Interpreted`]).
pub fn talk_spec(spec: Spec, o: &TalkOptions) -> Result<(), String> {
    use crate::interpreted::Interpreted;
    let spec = crate::interpreted::install(spec)?;
    // The request as `encode` builds it from the arguments, by the interpreter.
    let line = request_line(spec, o.command, o.address, o.args)?;
    let wire = frames::Engine::interpreted(spec.clone())
        .encode(&line)
        .map_err(|e| format!("{}: {e}", o.command))?;
    let request = Interpreted::decode_request(&wire)
        .map_err(|e| format!("{}: {e}", o.command))?
        .message;
    if request.name() != o.command {
        return Err(format!("{} is not a command", o.command));
    }
    let mut m = open::<Interpreted>(spec, o)?;
    one(spec, &mut m, o.address, request)
}

/// `soak --spec FILE`: the master in the protocol of a spec read at run time against devices
/// of its `device:` section, through a faulty line.
pub fn soak_spec(spec: Spec, transactions: u64, rate: f64, seed: u64) -> Result<(), String> {
    use crate::interpreted::Interpreted;
    if !(0.0..=1.0).contains(&rate) {
        return Err(format!("error: --rate {rate} is not a probability (0..=1)"));
    }
    let spec = crate::interpreted::install(spec)?;
    if spec.commands.is_empty() {
        return Err(format!("error: {} has no command to soak", spec.name));
    }
    let config = SoakConfig {
        transactions,
        byte_error_rate: rate,
        seed,
        devices: 2,
    };
    let started = Instant::now();
    let report = spec_sim::soak::<Interpreted>(std::sync::Arc::new(spec.clone()), config)?;
    print(&format!("{report}"))?;
    for e in &report.examples {
        print(&format!("  e.g. {e}"))?;
    }
    eprintln!(
        "({} took {:.1} s)",
        spec.name,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `talk` for a built-in protocol without rules of its own: one transaction, through
/// [`busspec_link::Plain`].
struct TalkPlain<'a> {
    spec: &'a Spec,
    o: &'a TalkOptions<'a>,
}

impl busspec_protocols::ProtocolVisitor for TalkPlain<'_> {
    type Output = Result<(), String>;
    fn visit<P: Protocol>(self) -> Self::Output {
        let (spec, o) = (self.spec, self.o);
        let request = checked::<busspec_link::Plain<P>>(spec, o)?;
        let mut m = open::<busspec_link::Plain<P>>(spec, o)?;
        one(spec, &mut m, o.address, request)
    }
}

/// The typed request `talk` sends, built from its arguments through the `encode` JSON contract.
fn typed<P: Protocol>(spec: &Spec, o: &TalkOptions) -> Result<P::Request, String> {
    let line = request_line(spec, o.command, o.address, o.args)?;
    let typed = busspec_json::parse_line(spec, &line)
        .and_then(|parsed| parsed.to_typed::<P>(spec))
        .map_err(|e| format!("{}: {e}", o.command))?;
    match typed {
        busspec_json::Typed::Request(d) => Ok(d.message),
        busspec_json::Typed::Response(_) => Err(format!("{} is not a command", o.command)),
    }
}

/// [`typed`], encoded once to `talk`'s address before any port is opened: a value outside its
/// range, an address no frame may carry or a broadcast the command does not accept is the
/// encoder's error (`EncodeError`, naming the field and the allowed range), and nothing is
/// written.
fn checked<P: Protocol>(spec: &Spec, o: &TalkOptions) -> Result<P::Request, String> {
    let request = typed::<P>(spec, o)?;
    let mut buf = P::Buffer::ZERO;
    request
        .encode(o.address, buf.as_mut())
        .map_err(|e| format!("{}: {e}", o.command))?;
    Ok(request)
}

fn print(line: &str) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{line}").map_err(|e| format!("error: cannot write output: {e}"))
}

fn one<P: Link, T: Transport, C: Clock>(
    spec: &Spec,
    m: &mut Master<P, T, C>,
    address: u8,
    request: P::Request,
) -> Result<(), String> {
    let ex = m.transact(address, request).map_err(link_error)?;
    match ex.response {
        Some(r) => {
            print(&reply_line::<P>(spec, &r, ex.address))?;
            // A refusal is the device's answer, printed like any other; say what it is.
            if P::is_refusal(&request, &r) {
                std::io::stdout()
                    .flush()
                    .map_err(|e| format!("error: cannot write output: {e}"))?;
                eprintln!("{} refused {} ({})", P::name(), request.name(), r.name());
            }
            Ok(())
        }
        None => {
            // Not answered: a broadcast, or a command that gets no reply (Pelco P's).
            if spec.framing.address.broadcast == Some(address) {
                eprintln!(
                    "sent {} to broadcast address 0x{address:02X}; it is not answered",
                    request.name()
                );
            } else {
                eprintln!(
                    "sent {} to 0x{address:02X}; it gets no reply",
                    request.name()
                );
            }
            Ok(())
        }
    }
}

fn talk_ub2(spec: &Spec, o: &TalkOptions) -> Result<(), String> {
    if o.command == "c-curve" {
        let mut m = open::<Ub2>(spec, o)?;
        let mut line = ProgressLine::new();
        let table = m
            .read_c_curve(o.address, &mut |p| line.show("entries", p))
            .map_err(link_error)?;
        for p in &table {
            let r = ub2::Response::CCurveEntry(ub2::response::CCurveEntry {
                index: p.index,
                full_steps: p.full_steps,
                capacitance: p.capacitance,
            });
            print(&reply_line::<Ub2>(spec, &r, o.address))?;
        }
        eprintln!("read {} C-curve entries", table.len());
        if let Some(path) = o.svg {
            write_svg(path, &table, o.address)?;
        }
        return Ok(());
    }
    let request = checked::<Ub2>(spec, o)?;
    let mut m = open::<Ub2>(spec, o)?;
    check_byte_order(&mut m, o.address, &request)?;
    if o.wait && busspec_devices::movement::ub2_completion_check(&request).is_some() {
        let mut line = ProgressLine::new();
        let report = m
            .run_movement(
                o.address,
                request,
                Duration::from_millis(50),
                Duration::from_secs(600),
                &mut |p| line.show("full-steps", p),
            )
            .map_err(link_error)?;
        print_move::<Ub2>(spec, &report, o.address)?;
        if report.clipped {
            eprintln!("the target lay outside the customer limits: the capacitor ran to the limit");
        }
        if let Some(lost) = report.lost_micro_steps {
            eprintln!("movement completed with step loss: {lost} micro-steps lost");
        }
        return Ok(());
    }
    one(spec, &mut m, o.address, request)
}

/// Before a movement: the byte-order check the master makes before the first movement to an
/// address ([`Link::byte_order_probe`]), made here so `talk` can say what it read; the master
/// then does not check again. A refusal is the command's error: nothing that moves is sent.
fn check_byte_order<P: Link, T: Transport, C: Clock>(
    m: &mut Master<P, T, C>,
    address: u8,
    request: &P::Request,
) -> Result<(), String> {
    if request.command().kind != CommandKind::Movement {
        return Ok(());
    }
    if let Some(check) = m.check_byte_order(address, request).map_err(link_error)? {
        eprintln!(
            "byte order checked: {} plausible {} ({})",
            check.read,
            declared_byte_order::<P>(),
            byte_order_source::<P>()
        );
    }
    Ok(())
}

/// Prints a movement's trigger reply and its final reply (to the completion check).
fn print_move<P: Protocol>(
    spec: &Spec,
    report: &busspec_link::master::MoveReport<P::Response>,
    address: u8,
) -> Result<(), String> {
    print(&reply_line::<P>(spec, &report.started, address))?;
    match &report.finished {
        Some(done) => print(&reply_line::<P>(spec, done, address)),
        None => Ok(()),
    }
}

fn write_svg(path: &Path, table: &[CCurvePoint], address: u8) -> Result<(), String> {
    let points: Vec<(f64, f64)> = table
        .iter()
        .map(|p| (f64::from(p.full_steps), p.capacitance.value()))
        .collect();
    let title = format!(
        "UB2 capacitor at 0x{address:02X}: C-curve ({} entries)",
        table.len()
    );
    std::fs::write(path, svg::c_curve(&points, &title))
        .map_err(|e| format!("error: cannot write {}: {e}", path.display()))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

fn talk_sd(spec: &Spec, o: &TalkOptions) -> Result<(), String> {
    // A string readout without a byte number reads the whole string.
    let readout = SdString::ALL
        .into_iter()
        .find(|s| s.request(0).name() == o.command);
    if let (Some(which), true) = (readout, o.args.is_empty()) {
        let mut m = open::<Sd>(spec, o)?;
        let mut line = ProgressLine::new();
        let text = m
            .read_string(o.address, which, &mut |p| line.show("characters", p))
            .map_err(link_error)?;
        let line = serde_json::json!({
            "protocol": Sd::NAME,
            "address": o.address,
            "message": o.command,
            "text": text.iter().map(|&b| char::from(b)).collect::<String>(),
        });
        return print(&line.to_string());
    }
    let request = checked::<Sd>(spec, o)?;
    let mut m = open::<Sd>(spec, o)?;
    check_byte_order(&mut m, o.address, &request)?;
    if let (true, sd::Request::SetPoint(sd::request::SetPoint { position, .. })) =
        (o.wait && Some(o.address) != sd::BROADCAST_ADDRESS, request)
    {
        let mut line = ProgressLine::new();
        let report = m
            .move_to(
                o.address,
                position,
                Duration::from_millis(20),
                Duration::from_secs(600),
                &mut |p| line.show("°", p),
            )
            .map_err(link_error)?;
        print_move::<Sd>(spec, &report, o.address)?;
        return Ok(());
    }
    one(spec, &mut m, o.address, request)
}

/// `busspec sim`: serves simulated devices on a pseudo-terminal (printing its path) or a port.
pub fn sim(
    protocol: &str,
    spec_file: Option<&Path>,
    addresses: &[u8],
    line: &SimLine,
    msb_first: bool,
) -> Result<(), String> {
    if msb_first && (protocol != Ub2::NAME || spec_file.is_some()) {
        return Err(format!(
            "error: --msb-first is for the {} simulator (erratum ub2-e01)",
            Ub2::NAME
        ));
    }
    match protocol {
        p if p == Ub2::NAME && spec_file.is_none() => {
            let addresses = if addresses.is_empty() {
                vec![0x21]
            } else {
                addresses.to_vec()
            };
            check_addresses::<Ub2>(&addresses)?;
            let devices: Vec<Ub2Sim> = addresses
                .iter()
                .map(|&a| Ub2Sim::new(a).msb_first(msb_first))
                .collect();
            let timeout = busspec_link::Timing::for_protocol::<Ub2>().reply_timeout;
            run_sim(Ub2::NAME, Ub2::BUS.baud, timeout, devices, line)
        }
        p if p == Sd::NAME && spec_file.is_none() => {
            let addresses = if addresses.is_empty() {
                vec![0x01]
            } else {
                addresses.to_vec()
            };
            check_addresses::<Sd>(&addresses)?;
            let devices: Vec<SdSim> = addresses.iter().map(|&a| SdSim::new(a)).collect();
            let timeout = busspec_link::Timing::for_protocol::<Sd>().reply_timeout;
            run_sim(Sd::NAME, Sd::BUS.baud, timeout, devices, line)
        }
        // Every other protocol, built in or a spec file: its `device:` section.
        name => {
            let spec = crate::protocol("sim", name, spec_file)?.spec;
            let spec = std::sync::Arc::new(spec);
            let addresses = if addresses.is_empty() {
                vec![spec_sim::first_address(&spec)]
            } else {
                addresses.to_vec()
            };
            check_spec_addresses(&spec, &addresses)?;
            if !spec.device.declared {
                eprintln!(
                    "{}: the spec has no `device:` section: each command is answered with its reply, and nothing is stored",
                    spec.name
                );
            }
            let devices = spec_sim::devices(&spec, &addresses);
            let timeout = busspec_link::busspec_link_core::master::default_reply_timeout(
                spec.transactions.response_timeout_us,
                spec.serial.baud,
            );
            run_sim(&spec.name, spec.serial.baud, timeout, devices, line)
        }
    }
}

/// Addresses for simulated devices of a spec: device addresses, each once (0 alone for a
/// protocol without addresses).
fn check_spec_addresses(spec: &Spec, addresses: &[u8]) -> Result<(), String> {
    let a = &spec.framing.address;
    for (i, &x) in addresses.iter().enumerate() {
        if !spec.framing.has_address() {
            if x != 0 || addresses.len() > 1 {
                return Err(format!(
                    "error: {} frames carry no address: one simulated device, address 0",
                    spec.name
                ));
            }
            continue;
        }
        if !(a.min..=a.max).contains(&x) {
            return Err(format!(
                "error: address 0x{x:02X} is not a {} device address (0x{:02X}..=0x{:02X})",
                spec.name, a.min, a.max
            ));
        }
        if addresses[..i].contains(&x) {
            return Err(format!(
                "error: address 0x{x:02X} given twice: devices on one bus need distinct addresses"
            ));
        }
    }
    Ok(())
}

fn check_addresses<P: Protocol>(addresses: &[u8]) -> Result<(), String> {
    for (i, a) in addresses.iter().enumerate() {
        if !P::BUS.device_addresses.contains(a) {
            return Err(format!(
                "error: address 0x{a:02X} is not a {} device address (0x{:02X}..=0x{:02X})",
                P::NAME,
                P::BUS.device_addresses.start(),
                P::BUS.device_addresses.end()
            ));
        }
        if addresses[..i].contains(a) {
            return Err(format!(
                "error: address 0x{a:02X} given twice: devices on one bus need distinct addresses"
            ));
        }
    }
    Ok(())
}

/// Serves `devices` on the line until Ctrl-C (or SIGTERM), or until the line fails; with
/// faults, their replies are damaged on the way out (late ones by 1 to 1.8 times `timeout`, the
/// protocol's reply timeout) and what was injected is said on stderr at the end.
fn run_sim<D: Device>(
    name: &str,
    baud: u32,
    timeout: Duration,
    mut devices: Vec<D>,
    line: &SimLine,
) -> Result<(), String> {
    // Before the path is printed: whoever reads it may stop the simulator at once.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let stop = std::sync::Arc::clone(&stop);
        ctrlc::set_handler(move || stop.store(true, std::sync::atomic::Ordering::SeqCst))
            .map_err(|e| format!("error: sim: cannot handle Ctrl-C: {e}"))?;
    }
    // Keep the pty's other end open for as long as we serve, so the line never hangs up.
    let mut _slave = None;
    let transport = match (line.pty, line.port) {
        (true, _) => {
            let (ours, theirs) = serialport::TTYPort::pair()
                .map_err(|e| format!("error: cannot open a pseudo-terminal: {e}"))?;
            let name = serialport::SerialPort::name(&theirs).unwrap_or_default();
            print(&name)?;
            _slave = Some(theirs);
            SerialTransport::from_port(Box::new(ours))
        }
        (false, Some(path)) => {
            SerialTransport::open(path, baud).map_err(|e| format!("error: {e}"))?
        }
        (false, None) => return Err("error: give --pty or --port PATH".to_owned()),
    };
    let _ = std::io::stdout().flush();
    let addresses: Vec<String> = devices
        .iter()
        .map(|d| format!("0x{:02X}", d.address()))
        .collect();
    let clock = SystemClock::new();
    let (rate, seed) = line.faults.unwrap_or((0.0, 1));
    let config = FaultConfig::byte_error_rate(rate, timeout);
    let mut transport = FaultyReplies::new(transport, clock, config, seed);
    eprintln!(
        "{} simulator serving address{} {}{}",
        name,
        if addresses.len() == 1 { "" } else { "es" },
        addresses.join(", "),
        match line.faults {
            Some(_) =>
                format!(", its replies damaged at a byte-error rate of {rate} (seed {seed})"),
            None => String::new(),
        }
    );
    let verbose = line.verbose;
    let damaged = line.faults.is_some();
    let fates = transport.last_fate();
    let served = serve(
        &mut transport,
        &clock,
        &mut devices,
        Duration::from_millis(3),
        || !stop.load(std::sync::atomic::Ordering::SeqCst),
        |req, reply| {
            if verbose {
                // With faults, what went out on the line beside the reply the device made.
                let fate = match (reply, fates.take()) {
                    (Some(reply), Some(fate)) if damaged => {
                        let same = matches!(&fate, Fate::Sent { bytes, late } if bytes[..] == reply[..] && late.is_zero());
                        match fate {
                            _ if same => String::new(),
                            Fate::Lost => " (lost on the line)".to_owned(),
                            fate => format!(" (sent as {fate})"),
                        }
                    }
                    _ => String::new(),
                };
                eprintln!(
                    "{} -> {}{}",
                    frames::hex(req),
                    reply
                        .map(frames::hex)
                        .unwrap_or_else(|| "(no reply)".to_owned()),
                    fate
                );
            }
        },
    );
    if line.faults.is_some() {
        eprintln!("{}", transport.counts());
    }
    served.map_err(|e| format!("error: serving the simulator: {e}"))
}

/// `busspec soak`.
pub fn soak(protocols: &[&str], transactions: u64, rate: f64, seed: u64) -> Result<(), String> {
    if !(0.0..=1.0).contains(&rate) {
        return Err(format!("error: --rate {rate} is not a probability (0..=1)"));
    }
    let config = SoakConfig {
        transactions,
        byte_error_rate: rate,
        seed,
        devices: 2,
    };
    for p in protocols {
        let started = Instant::now();
        let report = match soak::run_named(p, config) {
            Some(r) => r,
            None => {
                busspec_protocols::with_protocol(p, SoakSpec { config }).ok_or_else(|| {
                    format!(
                        "error: no soak for `{p}`: there are {}",
                        soak_targets().join(", ")
                    )
                })??
            }
        };
        print(&format!("{report}"))?;
        for e in &report.examples {
            print(&format!("  e.g. {e}"))?;
        }
        eprintln!("({} took {:.1} s)", p, started.elapsed().as_secs_f64());
    }
    Ok(())
}

/// Every protocol `soak` runs: UB2 and SD with their devices' own simulators and request
/// mixes, every other built-in one by its spec's `device:` section.
pub fn soak_targets() -> Vec<&'static str> {
    let mut all: Vec<&'static str> = soak::TARGETS.to_vec();
    for &name in busspec_protocols::PROTOCOLS {
        if !all.contains(&name) {
            all.push(name);
        }
    }
    all
}

/// The soak of a built-in protocol through [`busspec_link::Plain`], against devices of its
/// spec's `device:` section, with a request mix drawn from the spec.
struct SoakSpec {
    config: SoakConfig,
}

impl busspec_protocols::ProtocolVisitor for SoakSpec {
    type Output = Result<busspec_link::soak::SoakReport, String>;
    fn visit<P: Protocol>(self) -> Self::Output {
        let spec = std::sync::Arc::new(busspec_json::load_spec::<P>()?);
        let mut report = spec_sim::soak::<busspec_link::Plain<P>>(spec, self.config)?;
        report.protocol = P::NAME;
        Ok(report)
    }
}

pub use crate::demo::demo;

/// Used by the demo to show a reply like `decode` would.
pub(crate) fn reply_json<P: Protocol>(spec: &Spec, response: &P::Response, address: u8) -> String {
    reply_line::<P>(spec, response, address)
}

pub(crate) fn svg_file(path: &Path, table: &[CCurvePoint], address: u8) -> Result<(), String> {
    write_svg(path, table, address)
}

#[cfg(test)]
mod tests {
    //! Every command of both specs, sent the way `talk` sends it (name=value arguments through
    //! the JSON contract, then the typed codec), to a fresh simulator: each must get a reply the
    //! spec lists for it, and not a refusal. The commands come from the spec, not from a list.

    use super::*;
    use busspec_link::sim::{BusConfig, SimBus};
    use busspec_link::SimClock;
    use busspec_model::ir::{Leaf, MessageKind, MessageRef, ResponseKind, StatedValue};

    fn spec(name: &str) -> Spec {
        frames::built_in_spec(name)
    }

    /// A list's count field (Modbus's `byte_count`) is computed as `encode` computes it: `talk`
    /// does not ask for it, and the frame is the one given the count by hand.
    #[test]
    fn talk_computes_a_list_count_as_encode_does() {
        let modbus = spec("modbus");
        let args = |extra: &[&str]| -> Vec<String> {
            ["starting_address=1", "quantity=2", "values=[7,9]"]
                .iter()
                .chain(extra)
                .map(|a| a.to_string())
                .collect()
        };
        let encode = |args: &[String]| {
            let line = request_line(&modbus, "write_multiple_registers", 1, args)?;
            busspec_json::parse_line(&modbus, &line)?.encode(&modbus)
        };
        let without = encode(&args(&[])).expect("no byte_count needed");
        assert_eq!(without, encode(&args(&["byte_count=4"])).unwrap());
        assert_eq!(without[..7], [0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04]);
        // A count that contradicts the list is still refused.
        assert!(encode(&args(&["byte_count=6"])).is_err());
    }

    /// name=value arguments for command `i`: the values of its first example the document does
    /// not get wrong, else the lowest valid value of each field.
    fn arguments(spec: &Spec, i: usize) -> Vec<String> {
        // The examples whose values the simulated capacitor (factory limits 50-500 pF) rightly
        // refuses: 25 pF (ub2-e11) and 800 pF (ub2-e12).
        match (spec.name.as_str(), spec.commands[i].name.as_str()) {
            ("ub2", "set_lower_customer_limit") => return vec!["limit=150".to_owned()],
            ("ub2", "set_upper_customer_limit") => return vec!["limit=400".to_owned()],
            _ => {}
        }
        let me = MessageRef {
            direction: Direction::Request,
            index: i,
        };
        if let Some(e) = spec
            .examples
            .iter()
            .find(|e| e.message == me && e.erratum.is_none() && !e.values.is_empty())
        {
            return e
                .values
                .iter()
                .map(|(name, v)| {
                    let text = match v {
                        StatedValue::Number(r) if r.to_string().contains('/') => {
                            format!("{}", r.to_f64())
                        }
                        StatedValue::Number(r) => r.to_string(),
                        StatedValue::Name(n) => n.clone(),
                        StatedValue::Exact { text, .. } => text.clone(),
                        StatedValue::Names(ns) => serde_json::to_string(ns).unwrap_or_default(),
                        StatedValue::Numbers(ns) => format!(
                            "[{}]",
                            ns.iter()
                                .map(|r| r.to_string())
                                .collect::<Vec<_>>()
                                .join(",")
                        ),
                        // Records as the JSON contract writes them: a list of objects.
                        StatedValue::Records(rs) => format!(
                            "[{}]",
                            rs.iter()
                                .map(|r| format!(
                                    "{{{}}}",
                                    r.iter()
                                        .map(|(k, v)| match v {
                                            StatedValue::Number(x) => format!("\"{k}\":{x}"),
                                            StatedValue::Name(x)
                                            | StatedValue::Exact { text: x, .. } => {
                                                format!(
                                                    "\"{k}\":{}",
                                                    serde_json::to_string(x).unwrap_or_default()
                                                )
                                            }
                                            _ => format!("\"{k}\":null"),
                                        })
                                        .collect::<Vec<_>>()
                                        .join(",")
                                ))
                                .collect::<Vec<_>>()
                                .join(",")
                        ),
                    };
                    format!("{name}={text}")
                })
                .collect();
        }
        let c = &spec.commands[i];
        c.leaves()
            .filter_map(|l| match l {
                Leaf::Field(_, f) if f.constant.is_some() || f.equals.is_some() => None,
                Leaf::Field(_, f) => {
                    let v = match (f.enumeration, f.range) {
                        (Some(e), _) => spec.enums[e].values[0].name.clone(),
                        (None, Some((lo, _))) => lo.to_string(),
                        (None, None) => "0".to_owned(),
                    };
                    Some(format!("{}={v}", f.name))
                }
                Leaf::Bits(_, _, b) if b.constant.is_some() => None,
                Leaf::Bits(_, _, b) => Some(format!("{}=0", b.name)),
            })
            .collect()
    }

    fn check_every_command<P: Link, D: Device>(name: &str, address: u8, device: impl Fn() -> D) {
        let spec = spec(name);
        assert!(!spec.commands.is_empty());
        for (i, c) in spec.commands.iter().enumerate() {
            let args = arguments(&spec, i);
            let frame = request_frame(&spec, &c.name, address, &args)
                .unwrap_or_else(|e| panic!("{name} {}: {e}", c.name));
            let request = P::decode_request(&frame)
                .unwrap_or_else(|e| panic!("{} {e}", c.name))
                .message;
            assert_eq!(request.name(), c.name);
            let clock = SimClock::new();
            let bus = SimBus::new(clock.clone(), BusConfig::new(P::BUS.baud), vec![device()]);
            let mut m: Master<P, _, _> = Master::new(bus, clock);
            let ex = m
                .transact(address, request)
                .unwrap_or_else(|e| panic!("{name} {} {args:?}: {e}", c.name));
            let response = ex.response.expect("a device address gets an answer");
            let rname = response.name();
            let listed = c
                .responses
                .iter()
                .any(|(r, _)| spec.responses[*r].name == rname);
            assert!(
                listed,
                "{name} {}: answered {rname}, which the spec does not list for it",
                c.name
            );
            let r = spec
                .responses
                .iter()
                .find(|r| r.name == rname)
                .expect("listed");
            assert!(
                !matches!(r.kind, MessageKind::Response(ResponseKind::Nak)),
                "{name} {} {args:?}: refused with {rname}",
                c.name
            );
            // The JSON line is the one `decode` prints for the reply.
            let line = reply_line::<P>(&spec, &response, ex.address);
            let json: serde_json::Value = serde_json::from_str(&line).expect("JSON");
            assert_eq!(json["message"], rname, "{line}");
            assert_eq!(json["address"], ex.address, "{line}");
            assert_eq!(json["direction"], "response", "{line}");
        }
    }

    #[test]
    fn every_ub2_command_is_sent_and_answered() {
        check_every_command::<Ub2, _>("ub2", 0x21, || Ub2Sim::new(0x21));
    }

    #[test]
    fn every_sd_command_is_sent_and_answered() {
        check_every_command::<Sd, _>("sd", 0x01, || SdSim::new(0x01));
    }

    #[test]
    fn arguments_are_checked_before_anything_is_sent() {
        let ub2 = spec("ub2");
        let err = request_frame(&ub2, "go_to_capacitanse", 0x21, &[]).unwrap_err();
        assert!(
            err.starts_with(
                "unknown command `go_to_capacitanse` in ub2; its commands: reference_run, "
            ),
            "{err}"
        );
        let err = request_frame(&ub2, "go_to_capacitance", 0x21, &[]).unwrap_err();
        assert_eq!(
            err,
            "go_to_capacitance needs target: give them as name=value"
        );
        let err =
            request_frame(&ub2, "go_to_capacitance", 0x21, &["target".to_owned()]).unwrap_err();
        assert_eq!(
            err,
            "argument `target` is not name=value (the fields of go_to_capacitance: target)"
        );
        let err = request_frame(
            &ub2,
            "go_to_capacitance",
            0x21,
            &["target=150.001".to_owned()],
        )
        .unwrap_err();
        assert!(
            err.contains("not a whole number of steps of 0.01 pF"),
            "{err}"
        );
        let ok = request_frame(
            &ub2,
            "set_mode_of_operation",
            0x21,
            &["mode=close_loop_control".to_owned()],
        )
        .unwrap();
        assert_eq!(frames::hex(&ok), "AA218000014C");
        assert_eq!(parse_address("0x21"), Ok(0x21));
        assert_eq!(parse_address("33"), Ok(33));
        assert!(parse_address("0x121").is_err());
    }

    /// What `busspec talk` does with a request the spec forbids: the encoder's error, before
    /// the port is opened (the port here does not exist, so any attempt to open it, let alone
    /// write, would say so instead).
    #[test]
    fn talk_refuses_what_the_spec_forbids_before_opening_the_port() {
        let port = "/nonexistent/busspec-talk-test";
        let cases: [(&str, u8, &str, &[&str], &str); 5] = [
            (
                "sd",
                0x01,
                "read_electronic_serial_number",
                &["byte_number=37"],
                "read_electronic_serial_number: byte_number = 37 is outside its range 0..=31",
            ),
            (
                "sd",
                0x1F,
                "read_temperatures",
                &[],
                "read_temperatures: read_temperatures does not accept the broadcast address 0x1F",
            ),
            (
                "sd",
                0x20,
                "set_point",
                &["position=45"],
                "set_point: address 0x20 is outside the device range 0x01..=0x1E and is not the broadcast or host address",
            ),
            (
                "ub2",
                0x41,
                "get_actual_capacitance",
                &[],
                "get_actual_capacitance: address 0x41 is outside the device range 0x21..=0x40 and is not the broadcast or host address",
            ),
            (
                "ub2",
                0x21,
                "go_to_stored_position",
                &["index=12"],
                "go_to_stored_position: index = 12 is outside its range 0..=9",
            ),
        ];
        for (protocol, address, command, args, want) in cases {
            let args: Vec<String> = args.iter().map(|a| (*a).to_owned()).collect();
            let o = TalkOptions {
                port,
                baud: None,
                address,
                command,
                args: &args,
                wait: true,
                svg: None,
                timeout: None,
                pcapng: None,
            };
            assert_eq!(
                talk(&spec(protocol), &o).unwrap_err(),
                want,
                "{protocol} {command}"
            );
        }
        // A request the spec allows gets as far as the port.
        let args = vec!["byte_number=3".to_owned()];
        let o = TalkOptions {
            port,
            baud: None,
            address: 0x01,
            command: "read_electronic_serial_number",
            args: &args,
            wait: true,
            svg: None,
            timeout: None,
            pcapng: None,
        };
        let err = talk(&spec("sd"), &o).unwrap_err();
        assert!(err.contains(port), "{err}");
    }
}
