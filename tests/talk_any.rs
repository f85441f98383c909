//! `busspec talk` for protocols without rules of their own (Modbus, Dynamixel), end to end
//! through a real pseudo-terminal pair: a small device answers in a thread of the test, the
//! CLI talks to it as a process. The master runs by the spec alone: refusals (Modbus
//! exceptions, `kind: nak`) are answers, a read whose replies are lost is sent again, a write
//! is not; bad arguments and a missing port are clear errors.

#![cfg(unix)]

use std::process::{Command, Output};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use busspec_link::sim::{serve, Device};
use busspec_link::{Protocol, SerialTransport, SystemClock};
use busspec_protocols::modbus::{self, ExceptionCode, Request as Q, Response as R};

const BIN: &str = env!("CARGO_BIN_EXE_busspec");

/// What the device saw and what it is told to do.
#[derive(Default)]
struct State {
    /// Frames it took.
    frames: u32,
    /// Replies to drop, from the next one on.
    mute: u32,
    registers: [u16; 10],
}

/// A Modbus server at address 7 (ten holding registers; reads beyond them are refused with
/// exception 2), and a Dynamixel device at ID 1 that answers PING.
struct Devices(Arc<Mutex<State>>);

impl Device for Devices {
    fn on_frame(&mut self, frame: &[u8], _now: Duration) -> Option<Vec<u8>> {
        let mut s = self.0.lock().unwrap();
        // Dynamixel PING to ID 1, and its status packet (no error).
        if frame == [0xFF, 0xFF, 0x01, 0x02, 0x01, 0xFB] {
            s.frames += 1;
            return Some(vec![0xFF, 0xFF, 0x01, 0x02, 0x00, 0xFC]);
        }
        let d = modbus::Modbus::decode_request(frame).ok()?;
        if d.address != 7 {
            return None;
        }
        s.frames += 1;
        let response = match d.message {
            Q::ReadHoldingRegisters(modbus::request::ReadHoldingRegisters {
                starting_address,
                quantity,
            }) => {
                let (a, n) = (usize::from(starting_address), usize::from(quantity));
                match s.registers.get(a..a + n) {
                    Some(regs) => {
                        R::ReadHoldingRegistersReply(modbus::response::ReadHoldingRegistersReply {
                            registers: busspec_protocols::Repeated::from_slice(regs).ok()?,
                        })
                    }
                    None => R::ReadHoldingRegistersException(
                        modbus::response::ReadHoldingRegistersException {
                            exception_code: ExceptionCode::IllegalDataAddress,
                        },
                    ),
                }
            }
            Q::WriteSingleRegister(modbus::request::WriteSingleRegister {
                register_address,
                register_value,
            }) => {
                *s.registers.get_mut(usize::from(register_address))? = register_value;
                R::WriteSingleRegisterReply(modbus::response::WriteSingleRegisterReply {
                    register_address,
                    register_value,
                })
            }
            _ => return None,
        };
        if s.mute > 0 {
            s.mute -= 1;
            return None;
        }
        busspec_link::sim::reply::<modbus::Modbus>(&response, 7)
    }
    fn address(&self) -> u8 {
        7
    }
}

/// The devices served on one end of a pseudo-terminal pair; the other end's path.
struct Bus {
    path: String,
    state: Arc<Mutex<State>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    _theirs: serialport::TTYPort,
}

impl Bus {
    fn start() -> Bus {
        let (ours, theirs) = serialport::TTYPort::pair().expect("a pseudo-terminal pair");
        let path = serialport::SerialPort::name(&theirs).expect("a named end");
        let state = Arc::new(Mutex::new(State {
            registers: core::array::from_fn(|i| 100 + i as u16),
            ..State::default()
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (keep, dev) = (Arc::clone(&stop), Devices(Arc::clone(&state)));
        let thread = std::thread::spawn(move || {
            let mut port = SerialTransport::from_port(Box::new(ours));
            let mut devices = vec![dev];
            let _ = serve(
                &mut port,
                &SystemClock::new(),
                &mut devices,
                Duration::from_millis(3),
                || !keep.load(Ordering::Relaxed),
                |_, _| {},
            );
        });
        Bus {
            path,
            state,
            stop,
            thread: Some(thread),
            _theirs: theirs,
        }
    }

    fn talk(&self, args: &[&str]) -> Output {
        Command::new(BIN)
            .args(["talk", "--port", &self.path])
            .args(args)
            .output()
            .expect("busspec runs")
    }

    fn frames(&self) -> u32 {
        self.state.lock().unwrap().frames
    }

    fn mute(&self, n: u32) {
        self.state.lock().unwrap().mute = n;
    }
}

impl Drop for Bus {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn line(o: &Output) -> serde_json::Value {
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_str(text.lines().next().expect("a line")).expect("JSON")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn talk_modbus_reads_refusals_retries_and_writes_through_a_pty() {
    let bus = Bus::start();
    let read = |start: &str, n: &str, timeout: &str| {
        bus.talk(&[
            "modbus",
            "--address",
            "7",
            "--timeout",
            timeout,
            "read_holding_registers",
            &format!("starting_address={start}"),
            &format!("quantity={n}"),
        ])
    };
    let r = line(&read("2", "3", "1000"));
    assert_eq!(r["message"], "read_holding_registers_reply");
    assert_eq!(r["fields"]["registers"], serde_json::json!([102, 103, 104]));
    assert_eq!(bus.frames(), 1);

    // An exception reply is a refusal: the device's answer, printed, said, not retried.
    let o = read("9", "2", "1000");
    let r = line(&o);
    assert_eq!(r["message"], "read_holding_registers_exception");
    assert_eq!(r["fields"]["exception_code"], "illegal_data_address");
    assert_eq!(
        stderr(&o),
        "modbus refused read_holding_registers (read_holding_registers_exception)\n"
    );
    assert_eq!(bus.frames(), 2);

    // Two replies lost: a read is sent again, and answered the third time.
    bus.mute(2);
    let r = line(&read("0", "1", "100"));
    assert_eq!(r["fields"]["registers"], serde_json::json!([100]));
    assert_eq!(bus.frames(), 5);

    // One reply lost: a write is not sent again (it landed), and the master says so.
    bus.mute(1);
    let o = bus.talk(&[
        "modbus",
        "--address",
        "7",
        "--timeout",
        "100",
        "write_single_register",
        "register_address=4",
        "register_value=48879",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        "error: modbus write_single_register to address 0x07: no reply within 100 ms (1 attempt)\n"
    );
    assert_eq!(bus.frames(), 6);
    let r = line(&read("4", "1", "1000"));
    assert_eq!(r["fields"]["registers"], serde_json::json!([48879]));
}

#[test]
fn talk_dynamixel_pings_through_a_pty() {
    let bus = Bus::start();
    let r = line(&bus.talk(&["dynamixel", "--address", "1", "ping"]));
    assert_eq!(r["message"], "status");
    assert_eq!(bus.frames(), 1);
}

#[test]
fn talk_errors_are_clear_and_nothing_is_sent() {
    let bus = Bus::start();
    let cases: &[(&[&str], &str)] = &[
        (
            &["modbus", "--address", "7", "read_everything"],
            "error: unknown command `read_everything` in modbus; its commands: read_coils,",
        ),
        (
            &[
                "modbus",
                "--address",
                "7",
                "read_holding_registers",
                "quantity",
            ],
            "error: argument `quantity` is not name=value",
        ),
        (
            &[
                "modbus",
                "--address",
                "7",
                "read_holding_registers",
                "quantity=1",
            ],
            "error: read_holding_registers needs starting_address",
        ),
        (
            &[
                "modbus",
                "--address",
                "7",
                "read_holding_registers",
                "starting_address=0",
                "quantity=126",
            ],
            "error: read_holding_registers: ",
        ),
        (
            // Reads do not accept the broadcast address.
            &[
                "modbus",
                "--address",
                "0",
                "read_holding_registers",
                "starting_address=0",
                "quantity=1",
            ],
            "error: read_holding_registers: ",
        ),
        (
            &[
                "modbus",
                "--address",
                "7",
                "--baud",
                "0",
                "read_coils",
                "starting_address=0",
                "quantity=1",
            ],
            "error: --baud 0: a baud rate is positive",
        ),
    ];
    for (args, start) in cases {
        let o = bus.talk(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).starts_with(start), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{args:?}");
    }
    assert_eq!(bus.frames(), 0);
    // A port that is not there.
    let o = Command::new(BIN)
        .args([
            "talk",
            "--port",
            "/dev/busspec-no-such-port",
            "modbus",
            "--address",
            "7",
        ])
        .args(["read_holding_registers", "starting_address=0", "quantity=1"])
        .output()
        .expect("busspec runs");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).starts_with("error: "), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("/dev/busspec-no-such-port"),
        "{}",
        stderr(&o)
    );
}

/// `talk --pcapng FILE` writes every frame sent and received: a read retried after a lost reply
/// is two requests (outbound) and one reply (inbound), in that order, with rising timestamps;
/// `decode --stream` reads the file back to those frames.
#[test]
fn talk_writes_the_frames_it_sends_and_receives_to_pcapng() {
    let bus = Bus::start();
    let dir = std::env::temp_dir().join(format!("busspec-talk-pcapng-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("talk.pcapng");
    bus.mute(1);
    let o = bus.talk(&[
        "modbus",
        "--address",
        "7",
        "--timeout",
        "100",
        "--pcapng",
        file.to_str().unwrap(),
        "read_holding_registers",
        "starting_address=1",
        "quantity=2",
    ]);
    let r = line(&o);
    assert_eq!(r["fields"]["registers"], serde_json::json!([101, 102]));
    let bytes = std::fs::read(&file).expect("the pcapng file");
    let mut reader = pcap_file::pcapng::PcapNgReader::new(&bytes[..]).expect("pcapng");
    let mut packets = Vec::new();
    while let Some(block) = reader.next_block() {
        if let pcap_file::pcapng::Block::EnhancedPacket(p) = block.expect("a block") {
            let flags = p.options.iter().find_map(|o| match o {
                pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption::Flags(f) => {
                    Some(*f)
                }
                _ => None,
            });
            packets.push((p.timestamp, flags, p.data.to_vec()));
        }
    }
    let flags: Vec<Option<u32>> = packets.iter().map(|p| p.1).collect();
    assert_eq!(
        flags,
        [Some(0b10), Some(0b10), Some(0b01)],
        "{packets:02X?}"
    );
    assert_eq!(packets[0].2, packets[1].2, "the same request sent again");
    assert!(packets[0].0 <= packets[1].0 && packets[1].0 <= packets[2].0);
    let out = Command::new(BIN)
        .args(["decode", "modbus", "--stream", file.to_str().unwrap()])
        .output()
        .expect("busspec runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", stderr(&out));
    assert_eq!(
        text.matches("\"message\":\"read_holding_registers\"")
            .count(),
        2,
        "{text}"
    );
    assert_eq!(
        text.matches("\"message\":\"read_holding_registers_reply\"")
            .count(),
        1,
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
