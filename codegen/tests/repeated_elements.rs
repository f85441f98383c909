//! The runtime's repeated-field helpers (`rt::read_elements`, `rt::read_bits` and their
//! writers), which generated code will call for repeated fields, read every repeated field of
//! every example of the variable-length specs as the interpreter reads it, and write back the
//! same bytes.

use busspec_model::interp::{self, Raw};
use busspec_model::ir::{self, ByteOrder, FieldType};
use busspec_runtime::codec as rt;

fn load(name: &str) -> ir::Protocol {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(name);
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

/// Checks each example with a repeated field; returns how many it checked.
fn check(file: &str) -> usize {
    let p = load(file);
    let mut checked = 0;
    for e in &p.examples {
        let m = p.message(e.message);
        let Some((f, _)) = m.repeat() else { continue };
        let frame = interp::decode(&p, Some(e.message.direction), e.reply_to, &e.wire)
            .unwrap_or_else(|err| panic!("{file}: {}: {err}", m.name));
        let Some(Raw::List(list)) = frame.get(&f.name) else {
            panic!("{file}: {}.{} decodes to no list", m.name, f.name)
        };
        let at = m.layout.payload + f.offset;
        let bytes = &e.wire[at..at + f.elements_len(list.len())];
        let mut out = [0xEEu8; 512];
        let n = if f.ty == FieldType::Bit {
            let got = rt::read_bits::<256>(bytes).unwrap();
            let want: Vec<bool> = list.iter().map(|&v| v == 1).collect();
            assert_eq!(got.iter().collect::<Vec<_>>(), want, "{file}: {}", m.name);
            assert_eq!(got.elements().iter().collect::<Vec<_>>(), *list);
            rt::write_bits(&got, &mut out)
        } else {
            let ra = repeat_at(&p, m);
            let got = ra.elements::<i64, 256>(bytes).unwrap();
            assert_eq!(got.as_slice(), &list[..], "{file}: {}", m.name);
            ra.write(&got, &mut out)
        };
        assert_eq!(&out[..n], bytes, "{file}: {} written back", m.name);
        checked += 1;
    }
    checked
}

#[test]
fn repeated_fields_read_and_write_as_the_interpreter_does() {
    assert_eq!(check("model/tests/fixtures/valid/minimal_variable.yaml"), 2);
    let modbus = check("spec/modbus.yaml");
    let dynamixel = check("spec/dynamixel.yaml");
    // Every example with a repeated field the specs hold today: one dropped would show here.
    assert_eq!(modbus, 6, "modbus: examples with a repeated field");
    assert_eq!(dynamixel, 4, "dynamixel: examples with a repeated field");
    // A coil example is among them: bits are read, not skipped.
    let p = load("spec/modbus.yaml");
    assert!(p.examples.iter().any(|e| p
        .message(e.message)
        .repeat()
        .is_some_and(|(f, _)| f.ty == FieldType::Bit)));
}

/// `m`'s repeated field as generated code will describe it to the runtime.
fn repeat_at(p: &ir::Protocol, m: &ir::Message) -> rt::RepeatAt {
    let (f, r) = m.repeat().expect("a repeated field");
    let leak = |s: &str| -> &'static str { Box::leak(s.to_owned().into_boxed_str()) };
    let field = |i: usize| {
        let c = &m.fields[i];
        rt::CountField {
            name: leak(&c.name),
            at: m.layout.payload + c.offset,
            width: c.width,
            le: c.byte_order == ByteOrder::Little,
        }
    };
    let _ = p;
    rt::RepeatAt {
        field: Box::leak(Box::new(busspec_runtime::FieldDesc::new(
            leak(&m.name),
            leak(&f.name),
        ))),
        base: m.layout.len,
        at: m.layout.payload + f.offset,
        width: if f.ty == FieldType::Bit { 0 } else { f.width },
        le: f.byte_order == ByteOrder::Little,
        signed: f.signed,
        count: match r.count {
            ir::Count::ToEnd => rt::CountBy::End,
            ir::Count::Elements(i) => rt::CountBy::Elements(field(i)),
            ir::Count::Bytes(i) => rt::CountBy::Bytes(field(i)),
            ir::Count::Until(t) => rt::CountBy::Until(t),
            ir::Count::Fixed(n) => rt::CountBy::Fixed(n),
        },
        min: r.min,
        max: r.max,
    }
}

/// `RepeatAt::count` agrees with the interpreter's `element_count` (the same count, or both
/// refuse) on every example with a repeated field and on frames made from each by cutting or
/// adding up to three bytes and by changing each byte up to the elements; `frame_len` gives
/// the example's own length from its head.
fn check_counts(file: &str) -> (usize, usize) {
    let p = load(file);
    let (mut accepted, mut refused) = (0, 0);
    for e in &p.examples {
        let m = p.message(e.message);
        if !m.is_variable() {
            continue;
        }
        let ra = repeat_at(&p, m);
        let mut frames = vec![e.wire.clone()];
        for k in 1..=3 {
            if e.wire.len() >= k {
                frames.push(e.wire[..e.wire.len() - k].to_vec());
            }
            let mut longer = e.wire.clone();
            longer.extend(std::iter::repeat(0x01).take(k));
            frames.push(longer);
        }
        for i in 0..ra.at.min(e.wire.len()) {
            for d in [1u8, 2, 0x80] {
                let mut w = e.wire.clone();
                w[i] = w[i].wrapping_add(d);
                frames.push(w);
            }
        }
        for w in &frames {
            let want = interp::element_count(&p, m, w).ok();
            let got = ra.count(w).ok();
            assert_eq!(got, want, "{file}: {} on {w:02X?}", m.name);
            match ra.count(w) {
                Ok(_) => accepted += 1,
                Err(err) => {
                    assert!(!err.to_string().is_empty());
                    refused += 1;
                }
            }
        }
        match ra.count {
            rt::CountBy::End => assert_eq!(ra.frame_len(&e.wire), None),
            _ => assert_eq!(
                ra.frame_len(&e.wire),
                Some(e.wire.len()),
                "{file}: {}",
                m.name
            ),
        }
    }
    (accepted, refused)
}

#[test]
fn element_counts_agree_with_the_interpreter() {
    for file in [
        "model/tests/fixtures/valid/minimal_variable.yaml",
        "spec/modbus.yaml",
        "spec/dynamixel.yaml",
    ] {
        // Both outcomes occur: the comparison is not between two engines that refuse all.
        let (accepted, refused) = check_counts(file);
        assert!(
            accepted > 0 && refused > 0,
            "{file}: {accepted} accepted, {refused} refused"
        );
    }
}

#[test]
fn a_count_that_lies_gives_no_frame_length() {
    // Modbus read holding registers reply: address, code 0x03, byte count, registers.
    static VALUES: busspec_runtime::FieldDesc =
        busspec_runtime::FieldDesc::new("read_holding_registers_reply", "values");
    let ra = rt::RepeatAt {
        field: &VALUES,
        base: 5,
        at: 3,
        width: 2,
        le: false,
        signed: false,
        count: rt::CountBy::Bytes(rt::CountField {
            name: "byte_count",
            at: 2,
            width: 1,
            le: false,
        }),
        min: 1,
        max: 125,
    };
    assert_eq!(ra.frame_len(&[0x01, 0x03]), None, "count not arrived yet");
    assert_eq!(ra.frame_len(&[0x01, 0x03, 0x04]), Some(9));
    assert_eq!(
        ra.frame_len(&[0x01, 0x03, 0x03]),
        Some(0),
        "odd bytes for 2-byte elements"
    );
    assert_eq!(
        ra.frame_len(&[0x01, 0x03, 0xFC]),
        Some(0),
        "more than 125 registers"
    );
    assert_eq!(ra.frame_len(&[0x01, 0x03, 0x00]), Some(0), "fewer than 1");
    assert_eq!(ra.count(&[0x01, 0x03, 0x04, 0, 1, 0, 2, 0xAA, 0xBB]), Ok(2));
    assert_eq!(
        ra.count(&[0x01, 0x03, 0x06, 0, 1, 0, 2, 0xAA, 0xBB]),
        Err(busspec_runtime::DecodeError::ByteCount {
            list: &VALUES,
            field: "byte_count",
            offset: 2,
            expected: 4,
            found: 6
        })
    );
}
