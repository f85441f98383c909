//! `busspec sniff` on a pseudo-terminal: Modbus RTU traffic written at real timing, with
//! frames that the byte rule alone splits wrongly, settled by silence; the same framing
//! offline from the pcapng file sniff wrote; a port that goes away; wrong arguments.

#![cfg(unix)]

use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

use busspec_model::{interp, load_file, Protocol};
use serialport::{SerialPort, TTYPort};

#[path = "common/cli.rs"]
mod cli;

const BIN: &str = env!("CARGO_BIN_EXE_busspec");

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn modbus() -> Protocol {
    load_file(&root().join("spec/modbus.yaml")).expect("modbus spec loads")
}

/// A scratch directory for `test`, removed when dropped.
fn temp_dir(test: &str) -> tempfile::TempDir {
    cli::scratch(&format!("sniff-{test}"))
}

/// `body` with its Modbus CRC appended.
fn sealed(p: &Protocol, body: &[u8]) -> Vec<u8> {
    let mut f = body.to_vec();
    f.extend([0, 0]);
    interp::reseal(p, &mut f);
    f
}

/// A frame as the test sent it.
#[derive(Debug, Clone)]
struct Sent {
    offset: u64,
    message: &'static str,
    direction: &'static str,
    /// The byte rule alone cannot split it from the frame after it.
    trap: bool,
}

/// A read of `quantity` holding registers from `start`, and its reply with `registers`.
fn read_pair(p: &Protocol, address: u8, start: u16, registers: &[u16]) -> [Vec<u8>; 2] {
    let n = registers.len() as u16;
    let [sh, sl] = start.to_be_bytes();
    let [nh, nl] = n.to_be_bytes();
    let request = sealed(p, &[address, 0x03, sh, sl, nh, nl]);
    let mut reply = vec![address, 0x03, 2 * n as u8];
    for r in registers {
        reply.extend(r.to_be_bytes());
    }
    [request, sealed(p, &reply)]
}

/// A read whose request the byte rule alone takes for the head of a longer reply: the start
/// address's high byte `bc` reads as a reply's byte count, so a reply of `5 + bc` bytes could
/// start at the request, running into the real reply; two of the real reply's register bytes
/// are chosen so that this longer frame checksums. The byte rule tries the longest frame
/// first, and takes it.
fn trap_pair(p: &Protocol, address: u8, bc: u8, registers: &mut [u16]) -> [Vec<u8>; 2] {
    let [request, mut reply] = read_pair(p, address, u16::from(bc) << 8, registers);
    let fake_len = 5 + usize::from(bc);
    // The fake frame's CRC falls on reply bytes `fake_len - 10 ..= fake_len - 9`, in the
    // registers (which start at reply byte 3) and before the reply's own CRC.
    assert!(fake_len - 10 >= 3 && fake_len - 8 <= reply.len() - 2);
    let mut fake = request.clone();
    fake.extend_from_slice(&reply[..fake_len - 10]);
    fake.extend([0, 0]);
    interp::reseal(p, &mut fake);
    reply[fake_len - 10..fake_len - 8].copy_from_slice(&fake[fake_len - 2..]);
    let body = reply.len() - 2;
    [request, sealed(p, &reply[..body])]
}

/// The conversation: plain reads, writes whose reply waits for its gap, and traps.
fn traffic(p: &Protocol) -> Vec<(Vec<u8>, Sent)> {
    let mut rng = fastrand::Rng::with_seed(25);
    let mut frames = Vec::new();
    let mut offset = 0u64;
    let mut push = |frames: &mut Vec<(Vec<u8>, Sent)>, f: Vec<u8>, message, direction, trap| {
        let sent = Sent {
            offset,
            message,
            direction,
            trap,
        };
        offset += f.len() as u64;
        frames.push((f, sent));
    };
    for i in 0..24u16 {
        let address = rng.u8(1..=247);
        match i % 3 {
            0 => {
                let regs: Vec<u16> = (0..rng.u16(1..=6)).map(|_| rng.u16(..)).collect();
                let [q, r] = read_pair(p, address, rng.u16(0..0x0100), &regs);
                push(&mut frames, q, "read_holding_registers", "request", false);
                push(
                    &mut frames,
                    r,
                    "read_holding_registers_reply",
                    "response",
                    false,
                );
            }
            1 => {
                let n = rng.u16(1..=4);
                let start = rng.u16(..);
                let mut q = vec![address, 0x10];
                q.extend(start.to_be_bytes());
                q.extend(n.to_be_bytes());
                q.push(2 * n as u8);
                for _ in 0..n {
                    q.extend(rng.u16(..).to_be_bytes());
                }
                let mut r = vec![address, 0x10];
                r.extend(start.to_be_bytes());
                r.extend(n.to_be_bytes());
                let (q, r) = (sealed(p, &q), sealed(p, &r));
                push(&mut frames, q, "write_multiple_registers", "request", false);
                push(
                    &mut frames,
                    r,
                    "write_multiple_registers_reply",
                    "response",
                    false,
                );
            }
            _ => {
                let bc = [8u8, 10, 12][usize::from(i / 3) % 3];
                let mut regs: Vec<u16> = (0..8).map(|_| rng.u16(..)).collect();
                let [q, r] = trap_pair(p, address, bc, &mut regs);
                push(&mut frames, q, "read_holding_registers", "request", true);
                push(
                    &mut frames,
                    r,
                    "read_holding_registers_reply",
                    "response",
                    true,
                );
            }
        }
    }
    frames
}

fn events(stdout: &[u8]) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

/// How many sent frames `events` give exactly: an event at the frame's offset naming its
/// message and direction (and nothing else: no noise, no other frame).
fn right(sent: &[Sent], events: &[serde_json::Value]) -> usize {
    sent.iter()
        .filter(|s| {
            events.iter().any(|e| {
                e["offset"] == s.offset
                    && e["message"] == s.message
                    && e["direction"] == s.direction
            })
        })
        .count()
}

/// A sniffer on one end of a pseudo-terminal pair; the test writes to the other.
struct Sniffer {
    child: Child,
    master: Option<TTYPort>,
    /// The sniffer's stderr after its first line, read to the end by a thread.
    stderr: std::thread::JoinHandle<String>,
}

impl Sniffer {
    fn start(args: &[&str]) -> Sniffer {
        let (master, slave) = TTYPort::pair().expect("a pseudo-terminal pair");
        let path = slave.name().expect("the slave's path");
        // The pair's descriptors would be inherited by the sniffer, which would then hold the
        // line's other end open itself: keep a copy closed on exec, and close the originals.
        let copy = master.try_clone_native().expect("a copy of the master");
        drop(master);
        drop(slave);
        let master = copy;
        let mut child = Command::new(BIN)
            .args(["sniff", "--port", &path])
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("busspec runs");
        // Sniff says it listens once the port is open.
        let mut err = BufReader::new(child.stderr.take().unwrap());
        let mut first = String::new();
        err.read_line(&mut first).unwrap();
        assert!(first.starts_with("sniff: "), "sniff said {first:?}");
        let stderr = std::thread::spawn(move || {
            let mut rest = first;
            let _ = err.read_to_string(&mut rest);
            rest
        });
        Sniffer {
            child,
            master: Some(master),
            stderr,
        }
    }

    fn write(&mut self, bytes: &[u8]) {
        let m = self.master.as_mut().unwrap();
        m.write_all(bytes).unwrap();
        m.flush().unwrap();
    }

    /// Ends the sniffer: with Ctrl-C (SIGINT), or by closing the line's other end.
    fn stop(mut self, interrupt: bool) -> (Output, String) {
        if interrupt {
            let pid = self.child.id().to_string();
            let killed = Command::new("kill").args(["-INT", &pid]).status().unwrap();
            assert!(killed.success());
        } else {
            self.master = None;
        }
        let mut stdout = Vec::new();
        self.child
            .stdout
            .take()
            .unwrap()
            .read_to_end(&mut stdout)
            .unwrap();
        let status = self.child.wait().unwrap();
        let stderr = self.stderr.join().unwrap();
        (
            Output {
                status,
                stdout,
                stderr: Vec::new(),
            },
            stderr,
        )
    }
}

/// Issue 25's timing proof. Modbus RTU at 19200 baud, 8E1: t3.5 is 2 ms. Each frame goes to
/// the pseudo-terminal in one write (its bytes back to back, as a UART sends them), and the
/// frames follow each other after 30 ms of silence, 200 ms after a trap's request (room for a
/// busy machine: a silence the sniffer misses would let the byte rule decide). Gap framing
/// must give every frame; the byte rule alone (`decode --stream` of the same bytes) must not.
#[test]
fn silence_settles_frames_the_bytes_alone_split_wrongly() {
    let p = modbus();
    let traffic = traffic(&p);
    let sent: Vec<Sent> = traffic.iter().map(|(_, s)| s.clone()).collect();
    let bytes: Vec<u8> = traffic.iter().flat_map(|(f, _)| f.clone()).collect();
    let traps = sent.iter().filter(|s| s.trap).count();

    // The byte rule alone, over the same bytes.
    let scratch = temp_dir("silence");
    let dir = scratch.path();
    let raw = dir.join("capture.bin");
    std::fs::write(&raw, &bytes).unwrap();
    let by_bytes = Command::new(BIN)
        .args(["decode", "modbus", "--stream", raw.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(by_bytes.status.success());
    let by_bytes = events(&by_bytes.stdout);
    let bytes_right = right(&sent, &by_bytes);
    let traps_right = right(
        &sent.iter().filter(|s| s.trap).cloned().collect::<Vec<_>>(),
        &by_bytes,
    );

    // Live, on a pseudo-terminal.
    let pcap = dir.join("sniffed.pcapng");
    let mut sniffer = Sniffer::start(&["modbus", "--pcapng", pcap.to_str().unwrap()]);
    for (n, (frame, s)) in traffic.iter().enumerate() {
        sniffer.write(frame);
        // The first read's request and reply go out back to back, with no gap between: the
        // byte rule settles that request ("bytes").
        let quiet = match (n, s.trap, s.direction) {
            (0, _, _) => 0,
            (_, true, "request") => 200,
            _ => 30,
        };
        std::thread::sleep(Duration::from_millis(quiet));
    }
    let (out, stderr) = sniffer.stop(true);
    assert!(out.status.success(), "{stderr}");
    let live = events(&out.stdout);
    let live_right = right(&sent, &live);
    let decided = |by: &str| live.iter().filter(|e| e["decided_by"] == by).count();
    eprintln!(
        "sniff timing: {} frames sent ({traps} of them in {} trap pairs); gap framing got {live_right} right \
         ({} decided by timing, {} by both, {} by bytes); the byte rule alone got {bytes_right} right, \
         {traps_right} of the {traps} trap frames",
        sent.len(),
        traps / 2,
        decided("timing"),
        decided("both"),
        decided("bytes"),
    );
    assert_eq!(live_right, sent.len(), "{live:#?}");
    assert_eq!(
        live.len(),
        sent.len(),
        "nothing but the frames sent: {live:#?}"
    );
    assert!(traps > 0 && traps_right < traps, "{by_bytes:#?}");
    assert!(bytes_right < sent.len());
    assert_eq!(live[0]["decided_by"], "bytes", "{}", live[0]);
    // Every trap's request was still open for the byte rule when the gap closed it.
    for s in sent.iter().filter(|s| s.trap && s.direction == "request") {
        let e = live.iter().find(|e| e["offset"] == s.offset).unwrap();
        assert_eq!(e["decided_by"], "timing", "{e}");
    }
    // Times are in order, and the silences show between frames.
    let times: Vec<f64> = live.iter().map(|e| e["time"].as_f64().unwrap()).collect();
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");

    // Offline: the pcapng sniff wrote frames the same way from its timestamps. The last event
    // differs only in what settled it: the capture's end, not a silence after it.
    let back = Command::new(BIN)
        .args(["decode", "modbus", "--stream", pcap.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        back.status.success(),
        "{}",
        String::from_utf8_lossy(&back.stderr)
    );
    let back = events(&back.stdout);
    assert_eq!(back.len(), live.len());
    let n = live.len();
    assert_eq!(back[..n - 1], live[..n - 1]);
    let mut last = live[n - 1].clone();
    last["decided_by"] = "bytes".into();
    assert_eq!(back[n - 1], last);
}

#[test]
fn a_port_that_goes_away_ends_the_run_with_what_was_heard() {
    let p = modbus();
    let [q, r] = read_pair(&p, 0x11, 0x006B, &[0x022B, 0x0000, 0x0064]);
    let mut sniffer = Sniffer::start(&["modbus"]);
    sniffer.write(&q);
    std::thread::sleep(Duration::from_millis(30));
    sniffer.write(&r);
    std::thread::sleep(Duration::from_millis(30));
    let (out, stderr) = sniffer.stop(false);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let got = events(&out.stdout);
    assert_eq!(got.len(), 2, "{got:?}");
    assert_eq!(got[0]["message"], "read_holding_registers");
    assert_eq!(got[1]["message"], "read_holding_registers_reply");
    let n = q.len() + r.len();
    assert!(
        stderr.contains(&format!("the port went away after {n} bytes")),
        "{stderr}"
    );
}

#[test]
fn wrong_arguments_are_refused_with_the_reason() {
    let run = |args: &[&str]| Command::new(BIN).arg("sniff").args(args).output().unwrap();
    let out = run(&["--port", "/nonexistent/tty", "modbus"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cannot open serial port /nonexistent/tty"),
        "{err}"
    );
    for (args, says) in [
        (
            &["--port", "/dev/null", "modbus", "--gap-ms=-1"][..],
            "--gap-ms -1",
        ),
        (
            &["--port", "/dev/null", "modbus", "--seconds", "0"][..],
            "--seconds 0",
        ),
        (
            &["--port", "/dev/null", "modbus", "--baud", "0"][..],
            "--baud 0",
        ),
        (&["--port", "/dev/null", "nosuch"][..], "nosuch"),
    ] {
        let out = run(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
    }
}
