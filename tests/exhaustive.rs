//! Exhaustive round trips over the small domains, through the generated code and the
//! interpreter: every SD set point (all 4096 angles × 16 freshness values), every SD command
//! with every argument, every enum value (and an unlisted one), every NAK at every address, and
//! the whole request × response pairing matrix of both protocols against the spec.

mod common;

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{Direction, MessageKind, MessageRef, Protocol, ResponseKind};
use busspec_protocols::sd::{self, Sd};
use busspec_protocols::ub2::{self, Ub2};
use busspec_protocols::{
    FrameBuffer, Message, Protocol as Generated, RequestMessage, ResponseMessage,
};
use common::{all_messages, fix_checksum, random_frame, spec};

/// A frame that decodes as message `r`: its first example, else a random frame of its shape
/// that happens to satisfy its constants.
fn frame_of(p: &Protocol, r: MessageRef) -> Vec<u8> {
    if let Some(e) = p.examples.iter().find(|e| e.message == r) {
        return e.wire.clone();
    }
    let mut rng = fastrand::Rng::with_seed(r.index as u64);
    let m = p.message(r);
    (0..100_000)
        .map(|_| random_frame(p, m, &mut rng))
        .find(|f| interp::decode_as(p, r, f).is_ok())
        .unwrap_or_else(|| panic!("no frame of {} found", m.name))
}

#[test]
fn sd_set_point_every_angle_and_freshness() {
    let p = spec::<Sd>();
    let mut buf = [0xA5u8; sd::MAX_FRAME_LEN];
    let mut seen = std::collections::BTreeSet::new();
    for freshness in 0..16u8 {
        for raw in -2048..2048i16 {
            let position = sd::Angle::from_raw(raw);
            let msg = sd::Request::SetPoint(sd::request::SetPoint {
                freshness,
                position,
            });
            let n = msg.encode(0x05, &mut buf).unwrap();
            let frame = &buf[..n];
            assert!(
                seen.insert(frame.to_vec()),
                "two set points encode alike: {freshness} {raw}"
            );
            assert_eq!(sd::Request::decode(frame).unwrap().message, msg);
            let f = interp::decode(&p, Some(Direction::Request), None, frame).unwrap();
            assert_eq!(f.get("freshness"), Some(&Raw::Int(freshness.into())));
            assert_eq!(f.get("position"), Some(&Raw::Int(raw.into())));
            // 360/4096 ° per count, both ways.
            assert_eq!(position.value(), f64::from(raw) * 360.0 / 4096.0);
            assert_eq!(sd::Angle::from_value(position.value()), Some(position));
        }
    }
    assert_eq!(seen.len(), 4096 * 16);
    // Outside 12 bits the encoder refuses rather than wrapping.
    let wide = sd::Request::SetPoint(sd::request::SetPoint {
        freshness: 0,
        position: sd::Angle::from_raw(2048),
    });
    assert!(matches!(
        wide.encode(5, &mut buf),
        Err(busspec_protocols::EncodeError::OutOfRange { field: "position" })
    ));
    let wide = sd::Request::SetPoint(sd::request::SetPoint {
        freshness: 16,
        position: sd::Angle::from_raw(0),
    });
    assert!(wide.encode(5, &mut buf).is_err());
}

#[test]
fn sd_every_command_with_every_argument() {
    let p = spec::<Sd>();
    let mut codes: Vec<u8> = p.commands.iter().map(|c| c.code[0]).collect();
    codes.sort_unstable();
    codes.dedup();
    let (mut accepted, mut total) = (0u64, 0u64);
    for &code in &codes {
        let mut per_code = 0;
        for args in 0..=u16::MAX {
            let [a1, a2] = args.to_be_bytes();
            let address = 1 + (a1 ^ a2) % 30;
            let mut frame = [code, address, a1, a2, 0, 0];
            fix_checksum(&p, &mut frame);
            let oracle = interp::decode(&p, Some(Direction::Request), None, &frame);
            let generated = sd::Request::decode(&frame);
            match (oracle, generated) {
                (Ok(f), Ok(g)) => {
                    assert_eq!(g.message.name(), p.commands[f.message.index].name);
                    assert_eq!(g.address, address);
                    let mut buf = [0u8; sd::MAX_FRAME_LEN];
                    let n = g.message.encode(g.address, &mut buf).unwrap();
                    assert_eq!(&buf[..n], &frame);
                    per_code += 1;
                }
                (Err(_), Err(_)) => {}
                (o, g) => panic!("{frame:02X?}: interpreter {o:?}, generated {g:?}"),
            }
            total += 1;
        }
        assert!(per_code > 0, "no argument of code 0x{code:02X} decodes");
        accepted += per_code;
    }
    assert_eq!(total, codes.len() as u64 * 65536);
    assert!(accepted >= codes.len() as u64);
}

/// Every value of every enum field, plus one the spec does not list (`Unknown(raw)`), encoded
/// by the interpreter into a frame of the message and decoded by the generated code, which
/// must report the same raw value and write the frame back unchanged.
#[test]
fn ub2_every_enum_value_round_trips() {
    let p = spec::<Ub2>();
    let mut checked = 0;
    for r in all_messages(&p) {
        let m = p.message(r);
        for f in m.fields.iter().filter(|f| f.enumeration.is_some()) {
            let e = &p.enums[f.enumeration.unwrap()];
            let base = interp::decode_as(&p, r, &frame_of(&p, r)).unwrap();
            let unlisted = (0..=255i64)
                .find(|v| !e.values.iter().any(|x| x.value as i64 == *v))
                .unwrap();
            for raw in e.values.iter().map(|v| v.value as i64).chain([unlisted]) {
                let values: Vec<Value> = common::interp_values(&p, &base)
                    .into_iter()
                    .map(|(name, v)| Value {
                        raw: if name == f.name { Raw::Int(raw) } else { v },
                        name: name.into(),
                    })
                    .collect();
                let frame = interp::encode(&p, r, base.address, &values).unwrap();
                let (got, back) = match r.direction {
                    Direction::Request => {
                        let d = ub2::Request::decode(&frame).unwrap();
                        let mut buf = [0u8; ub2::MAX_FRAME_LEN];
                        let n = d.message.encode(d.address, &mut buf).unwrap();
                        (
                            common::visit_values(|v| d.message.visit(v)),
                            buf[..n].to_vec(),
                        )
                    }
                    Direction::Response => {
                        let d = ub2::Response::decode(&frame).unwrap();
                        let mut buf = [0u8; ub2::MAX_FRAME_LEN];
                        let n = d.message.encode(d.address, &mut buf).unwrap();
                        (
                            common::visit_values(|v| d.message.visit(v)),
                            buf[..n].to_vec(),
                        )
                    }
                };
                assert!(
                    got.contains(&(f.name.clone(), Raw::Int(raw))),
                    "{} {}={raw}: {got:?}",
                    m.name,
                    f.name
                );
                assert_eq!(back, frame, "{} {}={raw}", m.name, f.name);
                checked += 1;
            }
        }
    }
    assert!(
        checked >= 2 * (3 + 1) + (8 + 1),
        "only {checked} enum values checked"
    );
    // The typed view: listed values by name, others as Unknown, both lossless.
    for raw in 0..=255u8 {
        let mode = ub2::ModeOfOperation::from_raw(raw);
        assert_eq!(mode.raw(), raw);
        assert_eq!(mode.name().is_some(), raw <= 2, "{raw}");
    }
}

fn is_nak(p: &Protocol, r: MessageRef) -> bool {
    matches!(p.message(r).kind, MessageKind::Response(ResponseKind::Nak))
}

/// Every NAK of `P` at every device address decodes through both engines alike and
/// re-encodes; returns how many NAKs `P` has.
fn naks_at_every_address<P: Generated>() -> usize {
    let p = spec::<P>();
    let naks: Vec<MessageRef> = all_messages(&p)
        .into_iter()
        .filter(|r| is_nak(&p, *r))
        .collect();
    for &r in &naks {
        let base = interp::decode_as(&p, r, &frame_of(&p, r)).unwrap();
        for address in p.framing.address.min..=p.framing.address.max {
            let frame = interp::encode(&p, r, address, &base.values).unwrap();
            let d = P::decode_response(&frame).unwrap();
            assert!(d.message.is_nak(), "{}", d.message.name());
            let mut buf = P::Buffer::ZERO;
            let n = d.message.encode(address, buf.as_mut()).unwrap();
            assert_eq!(
                (d.message.name(), d.address),
                (p.message(r).name.as_str(), address)
            );
            assert_eq!(&buf.as_ref()[..n], &frame[..]);
        }
    }
    naks.len()
}

#[test]
fn every_nak_at_every_address() {
    assert_eq!(naks_at_every_address::<Ub2>(), 5, "UB2 NAKs 0x90..0x94");
    naks_at_every_address::<Sd>();
}

/// The whole request × response pairing matrix of `P`: `decode_reply` and `answers` are the
/// spec's lists of responses.
fn pairing_matrix<P: Generated>() {
    let p = spec::<P>();
    let requests: Vec<P::Request> = (0..p.commands.len())
        .map(|i| {
            let r = MessageRef {
                direction: Direction::Request,
                index: i,
            };
            P::decode_request(&frame_of(&p, r)).unwrap().message
        })
        .collect();
    let mut pairs = 0;
    for j in 0..p.responses.len() {
        let r = MessageRef {
            direction: Direction::Response,
            index: j,
        };
        let frame = frame_of(&p, r);
        for (i, request) in requests.iter().enumerate() {
            let listed = p.commands[i].gets(j);
            let reply = P::decode_reply(&frame, request);
            match reply {
                Ok(d) => {
                    // The same bytes may be a sibling response (same code and length) that this
                    // request gets instead; whatever it decodes as, it answers.
                    let k = p
                        .responses
                        .iter()
                        .position(|x| x.name == d.message.name())
                        .unwrap();
                    assert!(
                        p.commands[i].gets(k),
                        "{} decodes as a reply to {} but is not listed",
                        d.message.name(),
                        p.commands[i].name
                    );
                    assert!(d.message.answers(request));
                    assert_eq!(
                        k == j,
                        listed,
                        "{} for {}",
                        p.responses[j].name,
                        p.commands[i].name
                    );
                    pairs += usize::from(k == j);
                }
                Err(e) => {
                    assert!(
                        !listed,
                        "{} is listed for {} but decode_reply says {e}",
                        p.responses[j].name, p.commands[i].name
                    );
                }
            }
            if let Ok(d) = P::decode_response(&frame) {
                assert_eq!(
                    d.message.answers(request),
                    listed,
                    "answers({}, {})",
                    p.responses[j].name,
                    p.commands[i].name
                );
            }
        }
    }
    let listed: usize = p.commands.iter().map(|c| c.responses.len()).sum();
    assert_eq!(pairs, listed);
}

#[test]
fn ub2_pairing_matrix_is_the_spec() {
    pairing_matrix::<Ub2>();
}

#[test]
fn sd_pairing_matrix_is_the_spec() {
    pairing_matrix::<Sd>();
}

/// Each command's kind and broadcast rules, and the line constants, of generated protocol `P`
/// are its spec's.
fn command_info<P: Generated>() {
    use busspec_model::ir::CommandKind as K;
    use busspec_protocols::CommandKind;
    let p = spec::<P>();
    for (i, c) in p.commands.iter().enumerate() {
        let r = MessageRef {
            direction: Direction::Request,
            index: i,
        };
        let q = P::decode_request(&frame_of(&p, r)).unwrap().message;
        let MessageKind::Command(kind) = &c.kind else {
            panic!("{}: not a command", c.name)
        };
        let want = match kind {
            K::Movement => CommandKind::Movement,
            K::CompletionCheck => CommandKind::CompletionCheck,
            K::Setter => CommandKind::Setter,
            K::Getter => CommandKind::Getter,
            K::Reset => CommandKind::Reset,
        };
        assert_eq!(q.command().kind, want, "{}", c.name);
        let b = q.command().broadcast;
        let (accepted, answered) = c
            .broadcast
            .as_ref()
            .map_or((false, false), |b| (b.accepted, b.answered));
        assert_eq!((b.accepted, b.answered), (accepted, answered), "{}", c.name);
        assert_eq!(
            q.command().may_retry,
            p.transactions.retry_safe(c),
            "{}",
            c.name
        );
    }
    let t = &p.transactions;
    assert_eq!(
        P::BUS.transactions.response_timeout_us,
        t.response_timeout_us,
        "{}",
        p.name
    );
    assert_eq!(P::BUS.transactions.turnaround_us, t.turnaround_us);
    assert_eq!(
        P::BUS.transactions.gap_tenths_of_character,
        t.gap.map(|g| g.tenths)
    );
    if t.declared {
        assert_eq!(P::BUS.transactions.character_bits, t.character_bits);
        assert_eq!(
            P::BUS
                .transactions
                .gap_us_at(p.serial.baud, t.character_bits),
            t.gap_us_at(p.serial.baud)
        );
    }
    assert_eq!(P::BUS.baud, p.serial.baud);
    assert_eq!(P::BUS.inter_frame_gap_ms, p.serial.inter_frame_gap_ms);
    assert_eq!(
        P::BUS.max_frames_per_s,
        p.serial.frame_rate.as_ref().map(|r| r.max_per_s)
    );
}

/// Each generated command's `kind()` and `broadcast()`, and the line constants, are the spec's.
#[test]
fn generated_command_info_is_the_spec() {
    command_info::<Ub2>();
    command_info::<Sd>();
    command_info::<busspec_protocols::modbus::Modbus>();
    command_info::<busspec_protocols::dynamixel::Dynamixel>();
}
