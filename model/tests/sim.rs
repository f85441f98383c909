//! The device simulator of any spec (`busspec_model::sim`) on Modbus and Dynamixel 1.0, by
//! their `device:` sections: writes change what reads return, values the reply takes from its
//! request come from it, requests outside a space or breaking the spec's rules get the
//! refusal the section names, broadcasts are carried out and not answered, staged writes wait
//! for their commit, records go to the device they name.

use std::path::Path;
use std::sync::Arc;

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{Direction, MessageRef};
use busspec_model::sim::Sim;
use busspec_model::{load_file, Protocol};

fn spec(name: &str) -> Arc<Protocol> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    Arc::new(load_file(&root.join(format!("spec/{name}.yaml"))).expect("spec loads"))
}

fn int(name: &str, v: i64) -> Value<'static> {
    Value {
        name: name.to_owned().into(),
        raw: Raw::Int(v),
    }
}

fn list(name: &str, v: &[i64]) -> Value<'static> {
    Value {
        name: name.to_owned().into(),
        raw: Raw::List(v.to_vec()),
    }
}

/// A request frame of command `name` to `address`.
fn request(p: &Protocol, name: &str, address: u8, values: &[Value]) -> Vec<u8> {
    let index = p.commands.iter().position(|c| c.name == name).unwrap();
    let r = MessageRef {
        direction: Direction::Request,
        index,
    };
    interp::encode(p, r, address, values).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The reply decoded as the answer to `req`: its message name and values.
fn reply(p: &Protocol, req: &[u8], wire: &[u8]) -> (String, Vec<(String, Raw)>) {
    let request = interp::decode(p, Some(Direction::Request), None, req).unwrap();
    let f = interp::decode_reply(p, &request, wire).unwrap_or_else(|e| panic!("{e}"));
    let values = f
        .values
        .iter()
        .map(|v| (v.name.to_string(), v.raw.clone()))
        .collect();
    (p.message(f.message).name.clone(), values)
}

fn get<'a>(values: &'a [(String, Raw)], name: &str) -> &'a Raw {
    &values.iter().find(|(n, _)| n == name).unwrap().1
}

#[test]
fn modbus_writes_change_what_reads_return() {
    let p = spec("modbus");
    let mut d = Sim::new(Arc::clone(&p), 0x11);
    let w = request(
        &p,
        "write_multiple_registers",
        0x11,
        &[
            int("starting_address", 100),
            int("quantity", 3),
            list("values", &[7, 8, 9]),
        ],
    );
    let (name, v) = reply(&p, &w, &d.answer(&w).expect("a reply"));
    assert_eq!(name, "write_multiple_registers_reply");
    assert_eq!(get(&v, "starting_address"), &Raw::Int(100));
    assert_eq!(get(&v, "quantity"), &Raw::Int(3));
    assert_eq!(d.element("holding_registers", 101), Some(8));

    let r = request(
        &p,
        "read_holding_registers",
        0x11,
        &[int("starting_address", 99), int("quantity", 5)],
    );
    let (name, v) = reply(&p, &r, &d.answer(&r).expect("a reply"));
    assert_eq!(name, "read_holding_registers_reply");
    assert_eq!(get(&v, "registers"), &Raw::List(vec![0, 7, 8, 9, 0]));

    // A single register's reply echoes the request; coils are bits, packed and padded.
    let w = request(
        &p,
        "write_single_register",
        0x11,
        &[int("register_address", 5), int("register_value", 0xBEEF)],
    );
    assert_eq!(
        d.answer(&w).as_deref(),
        Some(&w[..]),
        "the echo is the request"
    );
    let w = request(
        &p,
        "write_multiple_coils",
        0x11,
        &[
            int("starting_address", 3),
            int("quantity", 10),
            list("outputs", &[1, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 0, 0]),
        ],
    );
    assert!(d.answer(&w).is_some());
    let r = request(
        &p,
        "read_coils",
        0x11,
        &[int("starting_address", 2), int("quantity", 12)],
    );
    let (_, v) = reply(&p, &r, &d.answer(&r).unwrap());
    let Raw::List(bits) = get(&v, "coils") else {
        panic!()
    };
    assert_eq!(&bits[..12], &[0, 1, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0]);
    let w = request(
        &p,
        "write_single_coil",
        0x11,
        &[int("output_address", 0), int("output_value", 0xFF00)],
    );
    assert_eq!(d.answer(&w).as_deref(), Some(&w[..]));
    assert_eq!(d.element("coils", 0), Some(1));
}

#[test]
fn modbus_refusals_are_the_exceptions_the_spec_names() {
    let p = spec("modbus");
    let mut d = Sim::new(Arc::clone(&p), 0x11);
    // Past the end of the table: exception 2, nothing written.
    let w = request(
        &p,
        "write_multiple_registers",
        0x11,
        &[
            int("starting_address", 9999),
            int("quantity", 2),
            list("values", &[1, 2]),
        ],
    );
    let (name, v) = reply(&p, &w, &d.answer(&w).unwrap());
    assert_eq!(name, "write_multiple_registers_exception");
    assert_eq!(get(&v, "exception_code"), &Raw::Int(2));
    assert_eq!(d.element("holding_registers", 9999), Some(0));
    // A quantity the spec forbids (0): exception 3. The frame is built by hand, as encode
    // refuses it.
    let mut q = vec![0x11, 0x03, 0x00, 0x00, 0x00, 0x00, 0, 0];
    interp::reseal(&p, &mut q);
    let (name, v) = reply(
        &p,
        &request(
            &p,
            "read_holding_registers",
            0x11,
            &[int("starting_address", 0), int("quantity", 1)],
        ),
        &d.answer(&q).unwrap(),
    );
    assert_eq!(name, "read_holding_registers_exception");
    assert_eq!(get(&v, "exception_code"), &Raw::Int(3));
    // Another address, a bad checksum: silence.
    let r = request(
        &p,
        "read_coils",
        0x12,
        &[int("starting_address", 0), int("quantity", 1)],
    );
    assert_eq!(d.answer(&r), None);
    let mut bad = request(
        &p,
        "read_coils",
        0x11,
        &[int("starting_address", 0), int("quantity", 1)],
    );
    *bad.last_mut().unwrap() ^= 1;
    assert_eq!(d.answer(&bad), None);
}

#[test]
fn a_broadcast_is_carried_out_and_not_answered() {
    let p = spec("modbus");
    let mut a = Sim::new(Arc::clone(&p), 1);
    let mut b = Sim::new(Arc::clone(&p), 2);
    let w = request(
        &p,
        "write_single_register",
        0,
        &[int("register_address", 7), int("register_value", 42)],
    );
    assert_eq!(a.answer(&w), None);
    assert_eq!(b.answer(&w), None);
    assert_eq!(a.element("holding_registers", 7), Some(42));
    assert_eq!(b.element("holding_registers", 7), Some(42));
}

#[test]
fn dynamixel_control_table_staged_writes_records_and_reset() {
    let p = spec("dynamixel");
    let mut d = Sim::new(Arc::clone(&p), 1);
    let mut other = Sim::new(Arc::clone(&p), 2);
    let ping = request(&p, "ping", 1, &[]);
    let (name, v) = reply(&p, &ping, &d.answer(&ping).unwrap());
    assert_eq!((name.as_str(), get(&v, "error")), ("status", &Raw::Int(0)));
    // The initial table: model number 29.
    let r = request(&p, "read", 1, &[int("address", 0), int("length", 2)]);
    let (name, v) = reply(&p, &r, &d.answer(&r).unwrap());
    assert_eq!(name, "read_status");
    assert_eq!(get(&v, "data"), &Raw::List(vec![29, 0]));
    // Write then read back.
    let w = request(
        &p,
        "write",
        1,
        &[int("address", 30), list("data", &[0x00, 0x02])],
    );
    assert!(d.answer(&w).is_some());
    assert_eq!(d.element("control_table", 31), Some(2));
    // A staged write waits for ACTION (broadcast: no reply from anyone).
    let w = request(
        &p,
        "reg_write",
        1,
        &[int("address", 32), list("data", &[5])],
    );
    assert!(d.answer(&w).is_some());
    assert_eq!(d.element("control_table", 32), Some(0));
    // A second staged write replaces the first (as REG_WRITE does): only it is applied.
    let w2 = request(
        &p,
        "reg_write",
        1,
        &[int("address", 33), list("data", &[6])],
    );
    assert!(d.answer(&w2).is_some());
    assert!(d.answer(&w).is_some());
    let action = request(&p, "action", 254, &[]);
    assert_eq!(d.answer(&action), None);
    assert_eq!(d.element("control_table", 32), Some(5));
    assert_eq!(d.element("control_table", 33), Some(0));
    // SYNC_WRITE: each device its own record.
    let s = request(
        &p,
        "sync_write",
        254,
        &[
            int("address", 24),
            int("data_length", 2),
            list("blocks", &[1, 10, 11, 2, 20, 21]),
        ],
    );
    assert_eq!(d.answer(&s), None);
    assert_eq!(other.answer(&s), None);
    assert_eq!(d.element("control_table", 25), Some(11));
    assert_eq!(other.element("control_table", 24), Some(20));
    // Past the end of the table: the status packet with the range error.
    let r = request(&p, "read", 1, &[int("address", 70), int("length", 10)]);
    let (name, v) = reply(&p, &r, &d.answer(&r).unwrap());
    assert_eq!(name, "read_status");
    assert_eq!(get(&v, "error"), &Raw::Int(1 << 3));
    // Factory reset: the table as at start.
    let reset = request(&p, "reset", 1, &[]);
    assert!(d.answer(&reset).is_some());
    assert_eq!(d.element("control_table", 31), Some(0));
    assert_eq!(d.element("control_table", 0), Some(29));
}

#[test]
fn diff_says_what_a_command_does_now_and_breaks_no_peer() {
    use busspec_model::diff::{diff, Category};
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec/modbus.yaml");
    let text = std::fs::read_to_string(&root).unwrap();
    let old = busspec_model::load_str("modbus.yaml", &text).unwrap();
    assert!(diff(&old, &old).is_empty());
    let moved = text.replace(
        "{command: write_single_register, writes: holding_registers",
        "{command: write_single_register, writes: coils",
    );
    assert_ne!(moved, text);
    let new = busspec_model::load_str("modbus.yaml", &moved).unwrap();
    let got = diff(&old, &new);
    assert_eq!(got.len(), 1, "{got:?}");
    assert_eq!(got[0].path, "device.commands.write_single_register");
    assert_eq!(got[0].category, Category::Compatible);
    let at = text.find("\ndevice:\n").unwrap();
    let end = at + text[at..].find("\nframing:\n").unwrap();
    let gone = format!("{}{}", &text[..at], &text[end..]);
    let new = busspec_model::load_str("modbus.yaml", &gone).unwrap();
    let got = diff(&old, &new);
    assert_eq!(got.len(), 1, "{got:?}");
    assert_eq!(got[0].text, "device model removed");
}
