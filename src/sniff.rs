//! `busspec sniff`: a bus heard live from a serial port or pseudo-terminal, its frames printed
//! as `decode --stream` prints them, timed, and closed by the line's silence where the spec
//! declares an inter-frame gap ([`crate::timing`]); optionally written to pcapng as it goes.

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use busspec_model::ir::Parity;
use clap::Args;

use crate::timing::{self, Timed};
use crate::{pcapng, usage_error, Out};

pub const SNIFF_HELP: &str = "\
Listen to a bus on a serial port (or a pseudo-terminal) and print every frame as one JSON line,
as `busspec decode --stream` does, until Ctrl-C, --seconds or the port goes away.

The port opens at the spec's serial settings (baud rate, data bits, parity, stop bits; --baud
for another rate) and only reads: sniff never writes to the line. Each line carries, after
\"offset\" (the byte's offset since sniffing began):

  \"time\"        when the event's first byte started on the line, in seconds since the epoch
                (six decimals): the time the bytes were read, less one character time for
                each byte of the chunk read after it;
  \"decided_by\"  what settled the event, where gap framing is on (below):
                \"bytes\"   the byte rule (as `decode --stream`: start, code, length, checksum;
                          longest first) settled it, and bytes followed with no gap;
                \"timing\"  the byte rule still waited (a longer frame could start there, or its
                          length had not come) when the line fell silent for a gap;
                \"both\"    the byte rule settled it and a gap followed.

Gap framing: where the spec declares an inter-frame gap (`transactions.inter_frame_gap` in
character times at the line's baud rate, e.g. Modbus RTU's t3.5; else `serial.inter_frame_gap_ms`)
a silence at least that long closes whatever frame is open, as the end of a capture would.
--gap-ms sets another gap, --gap-ms 0 frames by bytes alone. A frame prints once the line has
been quiet for a gap, or when the bytes after it settle it.

Timestamps are when the operating system handed the bytes over. USB serial adapters batch
them (many every 16 ms by default), which hides gaps shorter than that; lower the adapter's
latency (`setserial PORT low_latency`, or its latency_timer in sysfs) to frame by short gaps.

--pcapng FILE also writes every event as it is settled to FILE (as `decode --stream --pcapng`:
link type USER0, direction, comment), timestamped with its \"time\"; `busspec decode --stream
FILE` reads it back and frames it by the same gaps.

Ends on Ctrl-C (or SIGTERM) or after --seconds with status 0, everything settled and the
pcapng file complete. A port that cannot be opened is an error (status 1); one that goes away
while sniffing (unplugged, the other end of a pseudo-terminal closed) ends the run with what was
heard settled and printed, then `error: sniff PORT: the port went away after N bytes: reason`
(status 1).";

#[derive(Args)]
pub struct SniffArgs {
    /// The serial port (or pseudo-terminal) to listen on.
    #[arg(long, value_name = "PATH")]
    port: String,
    /// The protocol: ub2, sd, modbus, dynamixel, pelco_d, pelco_p, crsf, dynamixel2 (built in: generated code), or the
    /// `protocol:` of the spec given with --spec.
    protocol: String,
    /// A spec file to decode with (the interpreter), instead of a built-in protocol.
    #[arg(long, value_name = "FILE")]
    spec: Option<PathBuf>,
    /// Baud rate (default: the spec's).
    #[arg(long)]
    baud: Option<u32>,
    /// The silence, in milliseconds, that closes a frame (default: the spec's inter-frame gap
    /// at the baud rate; 0: frame by the bytes alone).
    #[arg(long, value_name = "MS")]
    gap_ms: Option<f64>,
    /// Also write every event to this pcapng file (link type USER0, 147).
    #[arg(long, value_name = "FILE")]
    pcapng: Option<PathBuf>,
    /// Stop after this many seconds (default: run until Ctrl-C or the port goes away).
    #[arg(long, value_name = "S")]
    seconds: Option<f64>,
}

/// Nanoseconds since the epoch, from a start read once and a monotonic clock after it, so a
/// wall-clock step while sniffing does not reorder events.
struct Clock {
    epoch_ns: u64,
    start: Instant,
}

impl Clock {
    fn new() -> Clock {
        let epoch = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default();
        Clock {
            epoch_ns: u64::try_from(epoch.as_nanos()).unwrap_or(u64::MAX),
            start: Instant::now(),
        }
    }
    fn now_ns(&self) -> u64 {
        let elapsed = u64::try_from(self.start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.epoch_ns.saturating_add(elapsed)
    }
}

/// A gap given in milliseconds, as nanoseconds (`None`: 0, frame by bytes alone).
fn gap_from_ms(ms: f64) -> Option<u64> {
    if !(0.0..=60_000.0).contains(&ms) {
        usage_error(
            "sniff",
            format!("--gap-ms {ms}: a gap is 0 (none) to 60000 ms"),
        );
    }
    let ns = (ms * 1e6).round() as u64;
    (ns > 0).then_some(ns)
}

fn serial_settings(
    spec: &busspec_json::Spec,
) -> Result<
    (
        serialport::DataBits,
        serialport::Parity,
        serialport::StopBits,
    ),
    String,
> {
    use serialport::{DataBits, StopBits};
    let data = match spec.serial.data_bits {
        5 => DataBits::Five,
        6 => DataBits::Six,
        7 => DataBits::Seven,
        8 => DataBits::Eight,
        n => {
            return Err(format!(
                "error: sniff: {n} data bits: a serial port has 5 to 8"
            ))
        }
    };
    let parity = match spec.serial.parity {
        Parity::None => serialport::Parity::None,
        Parity::Even => serialport::Parity::Even,
        Parity::Odd => serialport::Parity::Odd,
    };
    let stop = match spec.serial.stop_bits {
        1 => StopBits::One,
        2 => StopBits::Two,
        n => {
            return Err(format!(
                "error: sniff: {n} stop bits: a serial port has 1 or 2"
            ))
        }
    };
    Ok((data, parity, stop))
}

pub fn sniff(args: SniffArgs) -> Result<(), String> {
    let engine = crate::protocol("sniff", &args.protocol, args.spec.as_deref())?;
    let spec = &engine.spec;
    let baud = args.baud.unwrap_or(spec.serial.baud);
    if baud == 0 {
        usage_error("sniff", "--baud 0: a baud rate is positive".into());
    }
    let seconds = args.seconds.map(|s| {
        if !s.is_finite() || s <= 0.0 {
            usage_error(
                "sniff",
                format!("--seconds {s}: a positive number of seconds"),
            );
        }
        Duration::from_secs_f64(s.min(1e9))
    });
    let gap_ns = match args.gap_ms {
        Some(ms) => gap_from_ms(ms),
        None => timing::spec_gap_ns(spec, baud),
    };
    let char_ns = timing::char_ns(spec.transactions.character_bits, baud);
    let (data, parity, stop) = serial_settings(spec)?;
    // Reads wait at most this long, so a gap closes frames promptly and Ctrl-C is seen.
    let poll = Duration::from_nanos(gap_ns.unwrap_or(50_000_000).clamp(1_000_000, 50_000_000));
    let mut port = serialport::new(&args.port, baud)
        .data_bits(data)
        .parity(parity)
        .stop_bits(stop)
        .flow_control(serialport::FlowControl::None)
        .timeout(poll)
        .open()
        .map_err(|e| format!("error: sniff: cannot open serial port {}: {e}", args.port))?;

    let stop_flag = Arc::new(AtomicBool::new(false));
    {
        let flag = Arc::clone(&stop_flag);
        ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))
            .map_err(|e| format!("error: sniff: cannot handle Ctrl-C: {e}"))?;
    }

    let mut writer = match &args.pcapng {
        None => None,
        Some(path) => Some(pcapng::create(path, spec, &args.port, baud)?),
    };
    let gap_text = match gap_ns {
        Some(ns) => format!("frames closed by {} µs of silence", ns.div_ceil(1000)),
        None => "frames by bytes alone".to_owned(),
    };
    eprintln!(
        "sniff: {} at {baud} baud, {}{}{}, {gap_text}; Ctrl-C ends",
        args.port,
        spec.serial.data_bits,
        match spec.serial.parity {
            Parity::None => 'N',
            Parity::Even => 'E',
            Parity::Odd => 'O',
        },
        spec.serial.stop_bits
    );

    let clock = Clock::new();
    let mut timed = Timed::new(engine.stream(None, None), char_ns, gap_ns);
    let mut out = Out::new(std::io::stdout().lock());
    let mut buf = vec![0u8; 4096];
    let mut lost: Option<std::io::Error> = None;
    loop {
        if stop_flag.load(Ordering::SeqCst) || seconds.is_some_and(|s| clock.start.elapsed() >= s) {
            break;
        }
        let before = out.buf.len();
        match port.read(&mut buf) {
            Ok(0) => {
                lost = Some(std::io::Error::new(
                    std::io::ErrorKind::UnexpectedEof,
                    "end of file",
                ));
                break;
            }
            Ok(n) => {
                let now = clock.now_ns();
                if let Some(w) = writer.as_mut() {
                    w.bytes(&buf[..n]);
                }
                timed.push(&buf[..n], now, &mut out.buf);
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted
                ) =>
            {
                timed.idle(clock.now_ns(), &mut out.buf);
            }
            Err(e) => {
                lost = Some(e);
                break;
            }
        }
        written(&mut out, before, writer.as_mut())?;
    }
    let before = out.buf.len();
    timed.finish(&mut out.buf);
    written(&mut out, before, writer.as_mut())?;
    if let Some(w) = writer {
        w.finish()?;
    }
    out.finish()?;
    match lost {
        None => Ok(()),
        Some(e) => Err(format!(
            "error: sniff {}: the port went away after {} bytes: {e}",
            args.port,
            timed.pushed()
        )),
    }
}

/// The lines from `before` on are out: to the pcapng file, and to stdout at once (live).
fn written<W: Write>(
    out: &mut Out<W>,
    before: usize,
    writer: Option<&mut pcapng::Writer<std::io::BufWriter<std::fs::File>>>,
) -> Result<(), String> {
    if out.buf.len() == before {
        return Ok(());
    }
    if let Some(w) = writer {
        w.lines(&out.buf[before..])?;
    }
    out.flush()
}
