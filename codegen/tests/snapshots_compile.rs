//! The generator's snapshots (`codegen/tests/snapshots/`, the code emitted for the small fixture
//! specs) compile against the runtime, and replay their specs' examples through the
//! [`Protocol`] trait: decode, then encode back to the same bytes.

include!("snapshots/mini.rs");
include!("snapshots/mini_crc.rs");
include!("snapshots/core_names.rs");
include!("snapshots/syncy.rs");
include!("snapshots/codeless.rs");
include!("snapshots/variable.rs");
include!("snapshots/ending.rs");
include!("snapshots/pelco_d.rs");
include!("snapshots/unaddressed.rs");
include!("snapshots/ft12_fixed.rs");
include!("snapshots/ubx_like.rs");
include!("snapshots/sbf_blocks.rs");
include!("snapshots/herkulex.rs");
include!("snapshots/maestro_compact.rs");
include!("snapshots/pelco_p.rs");
include!("snapshots/msp_v1.rs");
include!("snapshots/msp_by_direction.rs");
include!("snapshots/bcd_meter.rs");
include!("snapshots/crc_extra.rs");
include!("snapshots/mavlink_v1.rs");
include!("snapshots/mavlink_v2.rs");
include!("snapshots/msp_v2.rs");
include!("snapshots/ft12_variable.rs");
include!("snapshots/sync_after_code.rs");
include!("snapshots/meter_floats.rs");
include!("snapshots/telemetry_le.rs");
include!("snapshots/slip_sensor.rs");
include!("snapshots/hdlc_like.rs");
include!("snapshots/cobs_link.rs");
include!("snapshots/dynamixel2_stuffed.rs");
include!("snapshots/xbee_api2.rs");
include!("snapshots/kiss.rs");
include!("snapshots/garmin_link.rs");
include!("snapshots/tsip.rs");
include!("snapshots/fport.rs");
include!("snapshots/fport_uplink.rs");
include!("snapshots/fport_both.rs");
include!("snapshots/unasked.rs");
include!("snapshots/unasked_to_end.rs");
include!("snapshots/lists_after.rs");
include!("snapshots/lists_length.rs");
include!("snapshots/packed_channels.rs");
include!("snapshots/records.rs");
include!("snapshots/records_sized.rs");
include!("snapshots/mbus_short.rs");
include!("snapshots/dlt645.rs");
include!("snapshots/optional_sensor.rs");
include!("snapshots/text_counted.rs");
include!("snapshots/text_terminated.rs");
include!("snapshots/vesc.rs");
include!("snapshots/mbus.rs");
include!("snapshots/jbd_bms.rs");
include!("snapshots/shdlc.rs");
include!("snapshots/nextion.rs");
include!("snapshots/rtcm3_frame.rs");
include!("snapshots/ubx_fixed_blocks.rs");
include!("snapshots/float_lists.rs");
include!("snapshots/pelco_d_replies.rs");
include!("snapshots/roboclaw.rs");
include!("snapshots/header_constant.rs");
include!("snapshots/novatel_oem.rs");

mod agree;

crate::views!(vario::Vario, vario, request, response);
crate::views!(ending::Ending, ending, request, response);
crate::views!(lists_after::ListsAfter, lists_after, request, response);
crate::views!(lists_length::ListsLength, lists_length, request, -);
crate::views!(msp_by_direction::MspByDirection, msp_by_direction, -, response);
crate::views!(text_counted::TextCounted, text_counted, request, response);
crate::views!(nextion::Nextion, nextion, request, response);
crate::views!(float_lists::FloatLists, float_lists, -, response);
crate::views!(unasked_to_end::UnaskedToEnd, unasked_to_end, -, response);
crate::views!(
    ubx_fixed_blocks::UbxFixedBlocks,
    ubx_fixed_blocks,
    request,
    -
);
crate::views!(
    text_terminated::TextTerminated,
    text_terminated,
    request,
    response
);

/// Every fixture with a borrowed view: made of exactly the frames the owned decode accepts,
/// refused with its error elsewhere, its values the owned message's (`agree::views_agree`).
#[test]
fn fixture_views_agree_with_the_owned_decode() {
    fn one<P: agree::Views>(file: &str) {
        let p = fixture(file);
        let (made, refused) = agree::views_agree::<P>(&p, 200);
        eprintln!("{file}: {made} made, {refused} refused");
        assert!(
            made >= p.examples.len() && refused > 100,
            "{file}: {made} {refused}"
        );
    }
    one::<vario::Vario>("model/tests/fixtures/valid/minimal_variable.yaml");
    one::<ending::Ending>("model/tests/fixtures/valid/minimal_end.yaml");
    one::<lists_after::ListsAfter>("model/tests/fixtures/valid/lists_after.yaml");
    one::<lists_length::ListsLength>("model/tests/fixtures/valid/lists_length.yaml");
    one::<msp_by_direction::MspByDirection>("model/tests/fixtures/valid/msp_by_direction.yaml");
    one::<text_counted::TextCounted>("model/tests/fixtures/valid/text_counted.yaml");
    one::<text_terminated::TextTerminated>("model/tests/fixtures/valid/text_terminated.yaml");
    one::<nextion::Nextion>("model/tests/fixtures/valid/nextion.yaml");
    one::<float_lists::FloatLists>("model/tests/fixtures/valid/float_lists.yaml");
    one::<ubx_fixed_blocks::UbxFixedBlocks>("model/tests/fixtures/valid/ubx_fixed_blocks.yaml");
    one::<unasked_to_end::UnaskedToEnd>("model/tests/fixtures/valid/unasked_to_end.yaml");
}

use busspec_model::ir::{self, Direction};
use busspec_runtime::{Framing, Message, Protocol, ResponseMessage};

/// `name`, a path from the repository's root.
fn fixture(name: &str) -> ir::Protocol {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(name);
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

/// Both engines refused a frame, and in the same words.
fn same_text(
    generated: Result<(), busspec_runtime::DecodeError>,
    interpreted: Result<(), busspec_model::interp::DecodeError>,
) {
    match (generated, interpreted) {
        (Err(g), Err(i)) => assert_eq!(g.to_string(), i.to_string()),
        (g, i) => panic!("both engines must refuse: {g:?} / {i:?}"),
    }
}

fn replay<P: Protocol>(file: &str) {
    let p = fixture(file);
    assert_eq!(P::NAME, p.name);
    assert!(!p.examples.is_empty());
    for e in &p.examples {
        let mut buf = vec![0xA5u8; P::MAX_FRAME_LEN];
        let n = match e.message.direction {
            Direction::Request => {
                let d = P::decode_request(&e.wire).unwrap();
                assert_eq!(d.message.name(), p.message(e.message).name);
                d.message.encode(d.address, &mut buf).unwrap()
            }
            // A reply whose checksum takes in its request's bytes, with the request's frame.
            Direction::Response if e.request.is_some() => {
                let w = e.request.as_deref().unwrap_or_default();
                let d = P::decode_reply_to(&e.wire, w).unwrap();
                assert_eq!(d.message.name(), p.message(e.message).name);
                P::encode_reply(&d.message, d.address, w, &mut buf).unwrap()
            }
            Direction::Response => {
                let request = e.reply_to.map(|c| {
                    let w = &p
                        .examples
                        .iter()
                        .find(|x| x.message.direction == Direction::Request && x.message.index == c)
                        .unwrap()
                        .wire;
                    P::decode_request(w).unwrap().message
                });
                let d = P::Response::decode_as_reply(&e.wire, request.as_ref()).unwrap();
                assert_eq!(d.message.name(), p.message(e.message).name);
                d.message.encode(d.address, &mut buf).unwrap()
            }
        };
        assert_eq!(&buf[..n], &e.wire[..]);
    }
}

#[test]
fn mini_snapshot_replays_its_examples() {
    replay::<mini::Mini>("model/tests/fixtures/valid/minimal.yaml");
}

#[test]
fn mini_crc_snapshot_replays_its_examples() {
    replay::<mini_crc::MiniCrc>("model/tests/fixtures/valid/minimal_crc.yaml");
}

/// Every frame of a direction with one frame length is taken from the buffer once, before the
/// message's own checks: a short buffer is refused first, then a value out of its range.
#[test]
fn a_single_length_encoder_refuses_a_short_buffer_before_the_message() {
    use busspec_runtime::EncodeError;
    use mini_crc::Response;
    let bad = Response::RuntimeMinSec(mini_crc::response::RuntimeMinSec {
        minutes: 60,
        seconds: 0,
    });
    let short = EncodeError::BufferTooSmall {
        needed: 6,
        available: 5,
    };
    assert_eq!(bad.encode(0x01, &mut [0; 5]), Err(short));
    assert!(matches!(
        bad.encode(0x01, &mut [0; 6]),
        Err(EncodeError::NotInRange {
            field: "minutes",
            ..
        })
    ));
    let good = Response::RuntimeMinSec(mini_crc::response::RuntimeMinSec {
        minutes: 59,
        seconds: 0,
    });
    assert_eq!(good.encode(0x01, &mut [0; 5]), Err(short));
    assert_eq!(good.encode(0x01, &mut [0; 6]), Ok(6));
}

/// Names that clash with core's (`Option`, `Some`, `Ok`, ...), with primitives and with the
/// generated code's own locals compile (this file would not otherwise) and round-trip; the
/// types keep their spec names.
#[test]
fn core_names_snapshot_replays_its_examples() {
    replay::<clash::Clash>("codegen/tests/fixtures/core_names.yaml");
    let m = clash::Request::Option(clash::request::Option {
        some: clash::Result::Err,
        core: clash::Option(5),
    });
    let mut buf = [0u8; clash::MAX_FRAME_LEN];
    let n = m.encode(0x21, &mut buf).unwrap();
    assert_eq!(clash::Request::decode(&buf[..n]).unwrap().message, m);
    let flags = clash::Ok::SOME;
    assert!(flags.contains(clash::Ok::SOME) && !flags.contains(clash::Ok::NONE));
    assert_eq!(clash::Some(3).value(), 5.0);
    let rt = clash::Request::Rt(clash::request::Rt { f: 7 });
    let n = rt.encode(0x21, &mut buf).unwrap();
    assert_eq!(&buf[3..5], &[7, 7]);
    assert_eq!(clash::Request::decode(&buf[..n]).unwrap().message, rt);
}

/// A syncy frame: `body` (sync, address, length, code, payload) and its checksum, the inverted
/// sum of every byte after the sync bytes.
fn syncy_frame(body: &[u8]) -> Vec<u8> {
    let sum = body[2..].iter().fold(0u8, |s, b| s.wrapping_add(*b));
    let mut f = body.to_vec();
    f.push(!sum);
    f
}

/// A sync sequence, a length field, an inverted sum-8 over all but the sync bytes, and 24-bit
/// integers: the examples replay, and generated code agrees with the interpreter on every
/// frame; a wrong second sync byte, a lying length field, a wrong checksum and a 24-bit value
/// out of range are refused.
#[test]
fn sync_snapshot_replays_and_agrees_with_the_interpreter() {
    use busspec_runtime::DecodeError;
    replay::<syncy::Syncy>("model/tests/fixtures/valid/minimal_sync.yaml");
    let p = fixture("model/tests/fixtures/valid/minimal_sync.yaml");
    let m = syncy::Response::Counter(syncy::response::Counter {
        total: 0xFF_FFFF,
        tag: 15,
        offset: -0x8_0000,
    });
    let mut buf = [0u8; syncy::MAX_FRAME_LEN];
    let n = m.encode(3, &mut buf).unwrap();
    let want = syncy_frame(&[0xFF, 0xFF, 3, 8, 1, 0xFF, 0xFF, 0xFF, 0xF8, 0, 0]);
    assert_eq!(&buf[..n], &want[..]);
    let d = syncy::Response::decode(&buf[..n]).unwrap();
    assert_eq!(d.message, m);
    let interp =
        busspec_model::interp::decode(&p, Some(Direction::Response), None, &buf[..n]).unwrap();
    assert_eq!(p.message(interp.message).name, "counter");
    assert_eq!(interp.address, 3);
    let move_to = syncy_frame(&[0xFF, 0xFF, 1, 5, 3, 0xFF, 0xFF, 0x9C]);
    let mut bad_sync = move_to.clone();
    bad_sync[1] = 0xFE;
    let mut bad_sum = move_to.clone();
    bad_sum[8] ^= 1;
    let lying = syncy_frame(&[0xFF, 0xFF, 1, 6, 3, 0xFF, 0xFF, 0x9C]);
    let broadcast = syncy_frame(&[0xFF, 0xFF, 0xFE, 2, 4]);
    // Each frame: both engines decode it, or both refuse it.
    for (frame, ok) in [
        (&move_to, true),
        (&bad_sync, false),
        (&bad_sum, false),
        (&lying, false),
        (&broadcast, false),
    ] {
        let g = syncy::Request::decode(frame);
        let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, frame);
        assert_eq!(g.is_ok(), ok, "{frame:02X?}: {g:?}");
        assert_eq!(i.is_ok(), ok, "{frame:02X?}: {i:?}");
    }
    assert_eq!(
        syncy::Request::decode(&bad_sync),
        Err(DecodeError::BadStart {
            offset: 1,
            expected: 0xFF,
            found: 0xFE
        })
    );
    assert_eq!(
        syncy::Request::decode(&lying),
        Err(DecodeError::LengthMismatch {
            offset: 3,
            expected: 5,
            found: 6
        })
    );
    same_text(
        syncy::Request::decode(&lying).map(|_| ()),
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &lying).map(|_| ()),
    );
    let far = syncy::Request::MoveTo(syncy::request::MoveTo {
        target: syncy::Millimetre::from_raw(0x80_0000),
    });
    assert!(far.encode(1, &mut buf).is_err());
    // In a stream: noise, a lone sync byte, then the frame.
    let mut s = syncy::StreamDecoder::new(None);
    let mut bytes = vec![0x00, 0xFF];
    bytes.extend_from_slice(&move_to);
    let mut events: Vec<_> = s.feed(&bytes).collect();
    events.extend(core::iter::from_fn(|| s.finish()));
    assert!(
        events.iter().any(|e| matches!(
            e,
            syncy::Event::Request {
                offset: 2,
                len: 9,
                ..
            }
        )),
        "{events:?}"
    );
}

/// A field following another of its frame is computed by encode and checked by decode; reply
/// fields following the request are checked by `decode_reply` and `answers`, as the
/// interpreter checks them; the error reply's code is the request's with 0x80 set.
#[test]
fn following_fields_are_computed_and_checked_as_the_interpreter_does() {
    use busspec_runtime::DecodeError;
    let p = fixture("model/tests/fixtures/valid/minimal_sync.yaml");
    let req = syncy::Request::SetPair(syncy::request::SetPair {
        quantity: 10,
        level: 0x0102,
    });
    let mut buf = [0u8; syncy::MAX_FRAME_LEN];
    let n = req.encode(1, &mut buf).unwrap();
    let wire = syncy_frame(&[0xFF, 0xFF, 1, 6, 5, 10, 20, 1, 2]);
    assert_eq!(&buf[..n], &wire[..]);
    // `doubled` is not 2 × quantity: both engines refuse it.
    let bad = syncy_frame(&[0xFF, 0xFF, 1, 6, 5, 10, 21, 1, 2]);
    assert!(matches!(
        syncy::Request::decode(&bad),
        Err(DecodeError::NotFollowing {
            field: busspec_runtime::FieldDesc {
                message: "set_pair",
                name: "doubled",
            },
            offset: 6,
            expected: 20,
            found: 21,
            ..
        })
    ));
    same_text(
        syncy::Request::decode(&bad).map(|_| ()),
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &bad).map(|_| ()),
    );
    // 200 × 2 does not fit the byte `doubled` is: encode refuses.
    let far = syncy::Request::SetPair(syncy::request::SetPair {
        quantity: 200,
        level: 0,
    });
    assert!(far.encode(1, &mut buf).is_err());
    let ireq = busspec_model::interp::decode(&p, Some(Direction::Request), None, &wire).unwrap();
    let wrong_quantity = syncy_frame(&[0xFF, 0xFF, 1, 4, 5, 9, 2]);
    for (reply, ok) in [
        (syncy_frame(&[0xFF, 0xFF, 1, 4, 5, 10, 2]), true),
        (wrong_quantity.clone(), false),
        (syncy_frame(&[0xFF, 0xFF, 1, 4, 5, 10, 1]), false),
        (syncy_frame(&[0xFF, 0xFF, 1, 3, 0x85, 3]), true),
    ] {
        let g = syncy::Response::decode_reply(&reply, &req);
        let i = busspec_model::interp::decode_reply(&p, &ireq, &reply);
        assert_eq!(g.is_ok(), ok, "{reply:02X?}: {g:?}");
        assert_eq!(i.is_ok(), ok, "{reply:02X?}: {i:?}");
        let plain = syncy::Response::decode(&reply).unwrap().message;
        assert_eq!(plain.answers(&req), ok);
    }
    assert!(matches!(
        syncy::Response::decode_reply(&wrong_quantity, &req),
        Err(DecodeError::NotFollowing {
            field: busspec_runtime::FieldDesc {
                name: "quantity",
                ..
            },
            offset: 5,
            expected: 10,
            found: 9,
            ..
        })
    ));
    same_text(
        syncy::Response::decode_reply(&wrong_quantity, &req).map(|_| ()),
        busspec_model::interp::decode_reply(&p, &ireq, &wrong_quantity).map(|_| ()),
    );
    assert_eq!(
        syncy::Response::SetPairError(syncy::response::SetPairError { reason: 3 }).code(),
        &[0x85]
    );
}

/// Replies without a code are told apart by their length, and by the request where they share
/// it; the stream decoder frames them; generated code and the interpreter agree.
#[test]
fn codeless_snapshot_replays_and_agrees_with_the_interpreter() {
    use busspec_runtime::DecodeError;
    replay::<codeless::Codeless>("model/tests/fixtures/valid/minimal_codeless.yaml");
    let p = fixture("model/tests/fixtures/valid/minimal_codeless.yaml");
    let status = syncy_frame(&[0xFF, 0xFF, 1, 2, 0x02]);
    let read_status = syncy_frame(&[0xFF, 0xFF, 1, 4, 0x00, 0x34, 0x12]);
    let long = syncy_frame(&[0xFF, 0xFF, 1, 3, 0x00, 0x34]);
    let d = codeless::Response::decode(&status).unwrap();
    assert_eq!(
        d.message,
        codeless::Response::Status(codeless::response::Status {
            error: codeless::Errors::ANGLE
        })
    );
    let d = codeless::Response::decode(&read_status).unwrap();
    assert_eq!(
        d.message,
        codeless::Response::ReadStatus(codeless::response::ReadStatus {
            error: codeless::Errors::from_raw(0),
            value: 0x1234
        })
    );
    // A ping gets a status, not a status with a value.
    assert!(matches!(
        codeless::Response::decode_reply(
            &read_status,
            &codeless::Request::Ping(codeless::request::Ping)
        ),
        Err(DecodeError::NotAReply { .. } | DecodeError::WrongLength { .. })
    ));
    for frame in [&status, &read_status, &long] {
        let g = codeless::Response::decode(frame);
        let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, frame);
        assert_eq!(g.is_ok(), i.is_ok(), "{frame:02X?}: {g:?} / {i:?}");
    }
    assert!(codeless::Response::decode(&long).is_err());
    let mut s = codeless::StreamDecoder::new(Some(busspec_runtime::stream::Direction::Response));
    let mut bytes = vec![0x55];
    bytes.extend_from_slice(&status);
    bytes.extend_from_slice(&read_status);
    let mut events: Vec<_> = s.feed(&bytes).collect();
    events.extend(core::iter::from_fn(|| s.finish()));
    let frames: Vec<(u64, usize)> = events
        .iter()
        .filter_map(|e| match e {
            codeless::Event::Response { offset, len, .. } => Some((*offset, *len)),
            _ => None,
        })
        .collect();
    assert_eq!(frames, [(1, 6), (7, 8)], "{events:?}");
}

/// Repeated fields in generated code: the examples replay; every example, and frames made from
/// them with counts and length fields that lie, decode as the interpreter decodes them, and
/// lists of every length encode alike (too many or too few elements, and a count that does not
/// count them, refused by both).
#[test]
fn variable_snapshot_replays_and_agrees_with_the_interpreter() {
    use busspec_runtime::{DecodeError, EncodeError};
    replay::<vario::Vario>("model/tests/fixtures/valid/minimal_variable.yaml");
    let p = fixture("model/tests/fixtures/valid/minimal_variable.yaml");
    let t = agree::agree::<vario::Vario>(&p);
    assert!(t.accepted > 4 && t.refused > 100, "{t:?}");
    assert!(t.encoded > 4 && t.encode_refused > 4, "{t:?}");
    // A write of two registers, by hand.
    let values = busspec_runtime::Repeated::from_slice(&[0x1234u16, 0xABCD]).unwrap();
    let w = vario::Request::Write(vario::request::Write {
        quantity: 2,
        values,
    });
    assert_eq!(w.frame_len(), 12);
    let mut buf = [0u8; vario::MAX_FRAME_LEN];
    let n = w.encode(3, &mut buf).unwrap();
    let mut want = vec![0xA5, 0x5A, 3, 8, 2, 2, 4, 0x12, 0x34, 0xAB, 0xCD, 0];
    agree::reseal(&p, &mut want);
    assert_eq!(&buf[..n], &want[..]);
    assert_eq!(vario::Request::decode(&want).unwrap().message, w);
    // A quantity the list does not have: refused, naming the list and the count that fits.
    let short = vario::Request::Write(vario::request::Write {
        quantity: 3,
        values,
    });
    assert_eq!(
        short.encode(3, &mut buf),
        Err(EncodeError::WrongCount {
            field: "values",
            min: 3,
            max: 3,
            found: 2,
        })
    );
    let empty = vario::Request::Write(vario::request::Write {
        quantity: 1,
        values: busspec_runtime::Repeated::new(),
    });
    assert_eq!(
        empty.encode(3, &mut buf),
        Err(EncodeError::WrongCount {
            field: "values",
            min: 1,
            max: 16,
            found: 0,
        })
    );
    // A byte count that lies about the frame's length.
    let mut lying = want.clone();
    lying[6] = 6;
    agree::reseal(&p, &mut lying);
    assert!(matches!(
        vario::Request::decode(&lying),
        Err(DecodeError::ByteCount {
            field: "byte_count",
            offset: 6,
            found: 6,
            ..
        })
    ));
    same_text(
        vario::Request::decode(&lying).map(|_| ()),
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &lying).map(|_| ()),
    );
    // The reply's count follows the request: two registers asked, three sent.
    let read = vario::Request::Read(vario::request::Read {
        first: 16,
        quantity: 2,
    });
    let mut three = vec![0xA5, 0x5A, 1, 8, 1, 0, 7, 1, 0, 0, 9, 0];
    agree::reseal(&p, &mut three);
    assert!(vario::Response::decode(&three).is_ok());
    assert!(matches!(
        vario::Response::decode_reply(&three, &read),
        Err(DecodeError::BadCount {
            field: busspec_runtime::FieldDesc { name: "values", .. },
            found: 3,
            ..
        })
    ));
    let reply = vario::Response::decode(&three).unwrap().message;
    assert!(!reply.answers(&read));
}

/// What a stream decoder reported, in terms both engines share: a frame by its message's name
/// (`?` for an ambiguous one, `!` for one out of spec), or skipped bytes (`-`, runs merged);
/// offset and length.
type Seen = (String, u64, u64);

/// Appends `e`, merging skipped bytes with skipped bytes just before.
fn note(out: &mut Vec<Seen>, e: Seen) {
    if let Some(last) = out.last_mut() {
        if last.0 == "-" && e.0 == "-" && last.1 + last.2 == e.1 {
            last.2 += e.2;
            return;
        }
    }
    out.push(e);
}

/// `cap` through the generated stream decoder of `P`, pushed in pieces of the sizes in `cuts`
/// (repeated), both directions.
fn generated_seen<P: Protocol>(cap: &[u8], cuts: &[usize]) -> Vec<Seen> {
    generated_seen_as::<P>(cap, cuts, None)
}

/// [`generated_seen`] of the frames of one direction (`None`: both).
fn generated_seen_as<P: Protocol>(
    cap: &[u8],
    cuts: &[usize],
    direction: Option<Direction>,
) -> Vec<Seen> {
    use busspec_runtime::stream::{Direction as D, Event, StreamDecoder};
    let mut d = StreamDecoder::<P>::new(direction.map(|d| match d {
        Direction::Request => D::Request,
        Direction::Response => D::Response,
    }));
    let mut out = Vec::new();
    let take = |e: Event<P::Request, P::Response>, out: &mut Vec<Seen>| {
        let s = match e {
            Event::Request { offset, len, frame } => {
                (frame.message.name().to_owned(), offset, len as u64)
            }
            Event::Response { offset, len, frame } => {
                (frame.message.name().to_owned(), offset, len as u64)
            }
            Event::Ambiguous { offset, len, .. } => ("?".to_owned(), offset, len as u64),
            Event::OutOfSpec { offset, len, .. } => ("!".to_owned(), offset, len as u64),
            Event::Skipped { offset, len } => ("-".to_owned(), offset, len),
        };
        note(out, s);
    };
    let mut rest = cap;
    for &n in cuts.iter().cycle() {
        if rest.is_empty() {
            break;
        }
        let (chunk, r) = rest.split_at(n.min(rest.len()));
        rest = r;
        let mut chunk = chunk;
        while !chunk.is_empty() {
            let k = d.push(chunk);
            chunk = &chunk[k..];
            while let Some(e) = d.poll() {
                take(e, &mut out);
            }
        }
    }
    while let Some(e) = d.finish() {
        take(e, &mut out);
    }
    out
}

/// `cap` through the interpreter's stream decoder, pushed the same way.
fn interp_seen(p: &ir::Protocol, cap: &[u8], cuts: &[usize]) -> Vec<Seen> {
    interp_seen_as(p, cap, cuts, None)
}

/// [`interp_seen`] of the frames of one direction (`None`: both).
fn interp_seen_as(
    p: &ir::Protocol,
    cap: &[u8],
    cuts: &[usize],
    direction: Option<Direction>,
) -> Vec<Seen> {
    use busspec_model::stream::{Event, StreamDecoder};
    let mut d = StreamDecoder::new(p, direction);
    let mut events = Vec::new();
    let mut rest = cap;
    for &n in cuts.iter().cycle() {
        if rest.is_empty() {
            break;
        }
        let (chunk, r) = rest.split_at(n.min(rest.len()));
        rest = r;
        events.extend(d.push(chunk));
    }
    events.extend(d.flush());
    let mut out = Vec::new();
    for e in events {
        let s = match e {
            Event::Frame {
                offset,
                bytes,
                frame,
            } => (
                p.message(frame.message).name.clone(),
                offset,
                bytes.len() as u64,
            ),
            Event::Ambiguous { offset, bytes, .. } => ("?".to_owned(), offset, bytes.len() as u64),
            Event::OutOfSpec { offset, bytes, .. } => ("!".to_owned(), offset, bytes.len() as u64),
            Event::Skipped { offset, bytes } => ("-".to_owned(), offset, bytes.len() as u64),
        };
        note(&mut out, s);
    }
    out
}

/// A reply's list runs to the end of the frame and no length field says where that is: the
/// generated stream decoder frames it by the lengths `FRAME_LENGTHS` lists, as the interpreter's
/// does, on captures of the examples with noise, cut frames and lists of every length, however
/// they are cut; the examples replay and both engines agree frame by frame.
#[test]
fn repeat_to_the_end_snapshot_streams_as_the_interpreter_does() {
    use busspec_runtime::Repeated;
    replay::<ending::Ending>("model/tests/fixtures/valid/minimal_end.yaml");
    let p = fixture("model/tests/fixtures/valid/minimal_end.yaml");
    let t = agree::agree::<ending::Ending>(&p);
    assert!(t.accepted > 5 && t.refused > 100, "{t:?}");
    // Every length the reply can have, 1 to 16 registers, is one of the listed lengths.
    let mut frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    let mut buf = [0u8; ending::MAX_FRAME_LEN];
    for n in 1..=16u16 {
        let values: Vec<u16> = (0..n).map(|k| k.wrapping_mul(0x1F3D)).collect();
        let reply = ending::Response::ReadReply(ending::response::ReadReply {
            values: Repeated::from_slice(&values).unwrap(),
        });
        let len = reply.encode(2, &mut buf).unwrap();
        assert!(ending::Ending::FRAME_LENGTHS.contains(&len), "{len}");
        frames.push(buf[..len].to_vec());
    }
    let mut rng = agree::Rng(0x5EED);
    let mut found = 0;
    for _ in 0..200 {
        let cap = random_capture(&frames, &mut rng, 30, 12);
        let cuts: Vec<usize> = (0..8).map(|_| 1 + rng.below(40) as usize).collect();
        let want = interp_seen(&p, &cap, &cuts);
        let got = generated_seen::<ending::Ending>(&cap, &cuts);
        assert_eq!(got, want, "capture {cap:02X?}");
        assert_eq!(generated_seen::<ending::Ending>(&cap, &[cap.len()]), got);
        found += got
            .iter()
            .filter(|s| !matches!(&*s.0, "-" | "?" | "!"))
            .count();
    }
    assert!(found > 200 * 15, "only {found} frames found");
}

/// A code-less message beside 2-byte coded ones, told apart by a constant sub-field (Pelco-D,
/// as a user wrote it): the coded frames are not refused with the code-less message's error,
/// the examples replay, and both engines agree on every example, the frames mutated from it
/// and captures of them, however they are cut.
#[test]
fn codeless_beside_coded_snapshot_agrees_with_the_interpreter() {
    use pelco_d2::{PelcoD2, Request};
    let file = "model/tests/fixtures/valid/pelco_d_codeless.yaml";
    let go_to = [0xFF, 0x01, 0x00, 0x07, 0x00, 0x01, 0x09];
    assert_eq!(
        Request::decode(&go_to).map(|d| d.message),
        Ok(Request::GoToPreset(pelco_d2::request::GoToPreset {
            preset: 1
        }))
    );
    replay::<PelcoD2>(file);
    let p = fixture(file);
    let t = agree::agree::<PelcoD2>(&p);
    assert!(t.accepted >= 3 && t.refused > 100, "{t:?}");
    // A coded frame whose own field is out of range is refused for it, as by the interpreter.
    let mut zero = go_to;
    zero[5] = 0;
    agree::reseal(&p, &mut zero);
    assert!(matches!(
        Request::decode(&zero),
        Err(busspec_runtime::DecodeError::OutOfRange {
            field: busspec_runtime::FieldDesc { name: "preset", .. },
            ..
        })
    ));
    for lookup in [false, true] {
        let i = if lookup {
            busspec_model::interp::Lookup::new(&p, Some(Direction::Request)).decode(&p, None, &zero)
        } else {
            busspec_model::interp::decode(&p, Some(Direction::Request), None, &zero)
        };
        assert!(
            matches!(&i, Err(busspec_model::interp::DecodeError::OutOfRange { field, .. }) if field == "preset"),
            "{i:?}"
        );
    }
    let found = examples_stream_alike::<PelcoD2>(&p, 0x9E1C0, "go_to_preset");
    assert!(found > 100, "only {found} go_to_preset frames found");
}

/// Frames that end in a stop byte after the checksum: the examples replay, a wrong end byte is
/// refused in the same words by both engines before the checksum is looked at, and both agree
/// on every frame mutated from the examples and on captures of them, however they are cut.
#[test]
fn end_byte_snapshot_agrees_with_the_interpreter() {
    use ft12_fixed::{Ft12Fixed, Request};
    let file = "model/tests/fixtures/valid/ft12_fixed.yaml";
    replay::<Ft12Fixed>(file);
    let p = fixture(file);
    let reset = [0x10, 0x40, 0x01, 0x41, 0x16];
    let d = Request::decode(&reset).unwrap();
    assert_eq!(
        (d.address, d.message),
        (
            1,
            Request::ResetRemoteLink(ft12_fixed::request::ResetRemoteLink)
        )
    );
    let mut buf = [0u8; 8];
    assert_eq!(
        Request::ResetRemoteLink(ft12_fixed::request::ResetRemoteLink).encode(0xFF, &mut buf),
        Ok(5)
    );
    assert_eq!(buf[..5], [0x10, 0x40, 0xFF, 0x3F, 0x16]);
    // A wrong end byte and a wrong checksum: the end byte is named first.
    let bad = [0x10, 0x40, 0x01, 0x42, 0x17];
    let g = Request::decode(&bad).map(|_| ());
    let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, &bad).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "bad end byte at offset 4: expected 0x16, found 0x17"
    );
    same_text(g, i);
    let t = agree::agree::<Ft12Fixed>(&p);
    assert!(t.accepted >= 6 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<Ft12Fixed>(&p, 0xF712, "reset_remote_link");
    assert!(found > 100, "only {found} reset_remote_link frames found");
}

/// A constant whole frame beside framed ones (M-Bus's `E5`): the examples replay; `E5` decodes
/// as `ack` with address 0 and encodes back whatever address it is given; it is the reply only
/// of the commands that list it, refused in both engines' words otherwise; a frame that merely
/// begins with it is no constant; both engines agree on every frame mutated from the examples
/// and on captures of them.
#[test]
fn constant_frame_snapshot_agrees_with_the_interpreter() {
    use mbus_short::{MbusShort, Request, Response};
    let file = "model/tests/fixtures/valid/mbus_short.yaml";
    replay::<MbusShort>(file);
    let p = fixture(file);
    let d = Response::decode(&[0xE5]).unwrap();
    assert_eq!(
        (d.address, d.message),
        (0, Response::Ack(mbus_short::response::Ack))
    );
    assert_eq!(
        Response::Ack(mbus_short::response::Ack).constant_frame(),
        Some(&[0xE5][..])
    );
    assert_eq!(
        Response::StatusOfLink(mbus_short::response::StatusOfLink).constant_frame(),
        None
    );
    let mut buf = [0u8; 8];
    assert_eq!(
        Response::Ack(mbus_short::response::Ack).encode(0xFE, &mut buf),
        Ok(1)
    );
    assert_eq!(buf[0], 0xE5);
    assert_eq!(
        Response::Ack(mbus_short::response::Ack)
            .encode(0, &mut [])
            .unwrap_err()
            .to_string(),
        busspec_runtime::EncodeError::BufferTooSmall {
            needed: 1,
            available: 0
        }
        .to_string()
    );
    // The reply of `snd_nke` and `req_ske`; and `E5` to a request is no frame at all.
    assert!(Response::decode_reply(&[0xE5], &Request::SndNke(mbus_short::request::SndNke)).is_ok());
    assert!(Response::decode_reply(&[0xE5], &Request::ReqSke(mbus_short::request::ReqSke)).is_ok());
    assert!(Request::decode(&[0xE5]).is_err());
    same_text(
        Request::decode(&[0xE5]).map(|_| ()),
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &[0xE5]).map(|_| ()),
    );
    // Bytes that begin with E5 are refused, in the same words.
    for bad in [&[0xE5, 0xE5][..], &[0xE5, 0x10, 0x0B, 0x05, 0x10], &[]] {
        same_text(
            Response::decode(bad).map(|_| ()),
            busspec_model::interp::decode(&p, Some(Direction::Response), None, bad).map(|_| ()),
        );
    }
    let t = agree::agree::<MbusShort>(&p);
    assert!(t.accepted >= 5 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<MbusShort>(&p, 0xE5E5, "ack");
    assert!(found > 100, "only {found} ack frames found");
}

/// The runtime stream decoder's fast path is its full rule at every head of captures of the
/// constant-frame fixture (examples, `E5`s, noise, cut frames), from a fresh decoder, one
/// after a request and one of responses only: where the fast path decides, the same event and
/// state; and `E5` heads are decided as frames.
#[test]
fn constant_frame_fast_path_is_the_rule() {
    use busspec_runtime::stream::{Direction as Dir, Event, StreamDecoder};
    use mbus_short::{MbusShort, Request};
    let p = fixture("model/tests/fixtures/valid/mbus_short.yaml");
    let frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    let mut after = StreamDecoder::<MbusShort>::new(None);
    assert!(after.feed(&frames[0]).count() > 0);
    let states = [
        StreamDecoder::<MbusShort>::new(None),
        after,
        StreamDecoder::<MbusShort>::new(Some(Dir::Response))
            .with_default_request(Some(Request::ReqSke(mbus_short::request::ReqSke))),
        StreamDecoder::<MbusShort>::new(Some(Dir::Request)),
    ];
    let cap = <MbusShort as Protocol>::MAX_FRAME_LEN;
    let mut rng = agree::Rng(0xE5);
    let (mut decided, mut acks) = (0, 0);
    for _ in 0..200 {
        let mut bytes = Vec::new();
        for _ in 0..12 {
            let f = &frames[rng.below(frames.len() as u64) as usize];
            match rng.below(6) {
                0 => bytes.extend((0..1 + rng.below(3)).map(|_| rng.below(256) as u8)),
                1 => bytes.extend_from_slice(&f[..f.len() - 1]),
                _ => bytes.extend_from_slice(f),
            }
        }
        for at in 0..bytes.len() {
            let mut w: Vec<u8> = bytes[at..].iter().copied().take(cap).collect();
            w.resize(cap, 0);
            for (i, d) in states.iter().enumerate() {
                let Some([fast, full]) = d.fast_and_full(&w, (i % 2) as u64) else {
                    continue;
                };
                assert_eq!(fast, full, "{w:02X?} from state {i}");
                decided += 1;
                if w[0] == 0xE5 && i < 3 {
                    assert!(
                        [&fast.event, &fast.pending]
                            .iter()
                            .any(|e| matches!(e, Some(Event::Response { len: 1, .. }))),
                        "{w:02X?} from state {i}: {fast:?}"
                    );
                    acks += 1;
                }
            }
        }
    }
    assert!(
        decided > 5000 && acks > 300,
        "{decided} decided, {acks} acks"
    );
}

/// The 8-bit Fletcher checksum (UBX): the examples replay, a frame with its two checksum bytes
/// swapped is refused in both engines' words, and both agree on every frame mutated from the
/// examples and on captures of them.
#[test]
fn fletcher_snapshot_agrees_with_the_interpreter() {
    use ubx_like::{Request, UbxLike};
    let file = "model/tests/fixtures/valid/ubx_like.yaml";
    replay::<UbxLike>(file);
    let p = fixture(file);
    assert_eq!(ubx_like::checksum(&[0x06, 0x08, 0x00, 0x00]), 0x300E);
    let swapped = [0xB5, 0x62, 0x06, 0x08, 0x00, 0x00, 0x30, 0x0E];
    let g = Request::decode(&swapped).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "checksum mismatch at offset 6: expected 0x300E, found 0x0E30"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, &swapped);
    same_text(g, i.map(|_| ()));
    // A payload over 255 bytes (NAV-SAT with 22 satellites), which the two-byte length carries.
    let big = p.examples.iter().find(|e| e.wire.len() > 255).unwrap();
    match ubx_like::Response::decode(&big.wire).map(|d| d.message) {
        Ok(ubx_like::Response::Satellites(s)) => assert_eq!(s.svs.len(), 22),
        other => panic!("NAV-SAT decoded as {other:?}"),
    }
    let t = agree::agree::<UbxLike>(&p);
    assert!(t.accepted >= 6 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<UbxLike>(&p, 0xF1E7, "ack");
    assert!(found > 50, "only {found} ack frames found");
}

/// A checksum before the bytes it covers (Septentrio SBF's CRC-16/XMODEM at offset 2, over
/// the ID, the length and the body after it): the examples replay (their CRCs computed apart
/// from busspec), a byte changed anywhere the CRC covers is a mismatch at offset 2 in both
/// engines' words, the sync bytes are not covered, and both agree on every frame mutated from
/// the examples and on captures of them with noise between.
#[test]
fn checksum_before_the_payload_snapshot_agrees_with_the_interpreter() {
    use busspec_runtime::DecodeError;
    use sbf_blocks::{Response, SbfBlocks};
    let file = "model/tests/fixtures/valid/sbf_blocks.yaml";
    replay::<SbfBlocks>(file);
    let p = fixture(file);
    assert_eq!(p.framing.checksum.lead, Some(2));
    assert_eq!(sbf_blocks::checksum(b"123456789"), 0x31C3);
    let good = p.examples[2].wire.clone();
    assert!(Response::decode(&good).is_ok());
    for i in [4, 6, 9, good.len() - 1] {
        let mut bad = good.clone();
        bad[i] ^= 0x10;
        let g = Response::decode(&bad).map(|_| ());
        assert!(
            matches!(g, Err(DecodeError::ChecksumMismatch { offset: 2, .. })),
            "byte {i}: {g:?}"
        );
        let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &bad);
        same_text(g, i.map(|_| ()));
    }
    // The CRC itself changed: found where it sits.
    let mut bad = good.clone();
    bad[3] ^= 0x01;
    let g = Response::decode(&bad).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "checksum mismatch at offset 2: expected 0x5010, found 0x5110"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &bad);
    same_text(g, i.map(|_| ()));
    let t = agree::agree::<SbfBlocks>(&p);
    assert!(t.accepted >= 4 && t.refused > 50, "{t:?}");
    let found = examples_stream_alike::<SbfBlocks>(&p, 0x5BF0, "end_of_pvt");
    assert!(found > 50, "only {found} EndOfPVT blocks found");
}

/// HerkuleX's checksum: before the data it covers, over the size, ID and command before it
/// and the data after it (skipping its own two bytes), its XOR kept to 0xFE and followed by
/// that value's complement kept to 0xFE. The examples replay (their checksums computed apart
/// from busspec); a byte changed on either side of it is a mismatch at offset 5 in both
/// engines' words, a wrong complement byte too; the sync bytes are not covered, and a change
/// of bit 0 (which the mask drops) passes both; both agree on every frame mutated from the
/// examples and on captures of them with noise between.
#[test]
fn herkulex_snapshot_agrees_with_the_interpreter() {
    use busspec_runtime::DecodeError;
    use herkulex::{Herkulex, Request, Response};
    let file = "model/tests/fixtures/valid/herkulex.yaml";
    replay::<Herkulex>(file);
    let p = fixture(file);
    assert_eq!(p.framing.checksum.lead, Some(5));
    assert_eq!(p.framing.checksum.covers_from, 2);
    assert!(p.framing.covers_around());
    // 0x31 ^ 0x32 ^ .. ^ 0x39 = 0x31, kept to 0xFE: 0x30, then !0x30 & 0xFE = 0xCE.
    assert_eq!(herkulex::checksum(b"123456789"), 0x30CE);
    // The broadcast STAT request, FF FF 07 FE 07 FE 00.
    assert_eq!(
        p.examples[0].wire,
        [0xFF, 0xFF, 0x07, 0xFE, 0x07, 0xFE, 0x00]
    );
    assert!(Request::decode(&p.examples[0].wire).is_ok());
    // STAT ACK of servo 1: FF FF 09 01 47 0C F2 00 42.
    let good = p.examples[2].wire.clone();
    assert_eq!(good, [0xFF, 0xFF, 0x09, 0x01, 0x47, 0x0C, 0xF2, 0x00, 0x42]);
    assert!(Response::decode(&good).is_ok());
    // Bytes before it (ID, command) and after it (both status bytes).
    for i in [3, 4, 7, 8] {
        let mut bad = good.clone();
        bad[i] ^= 0x10;
        let g = Response::decode(&bad).map(|_| ());
        assert!(
            matches!(g, Err(DecodeError::ChecksumMismatch { offset: 5, .. })),
            "byte {i}: {g:?}"
        );
        let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &bad);
        same_text(g, i.map(|_| ()));
    }
    // The complement byte wrong.
    let mut bad = good.clone();
    bad[6] ^= 0x02;
    let g = Response::decode(&bad).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "checksum mismatch at offset 5: expected 0x0CF2, found 0x0CF0"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &bad);
    same_text(g, i.map(|_| ()));
    // The first byte wrong: the expected value is over the frame, not from the first byte.
    let mut bad = good.clone();
    bad[5] = 0x0E;
    let g = Response::decode(&bad).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "checksum mismatch at offset 5: expected 0x0CF2, found 0x0EF2"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &bad);
    same_text(g, i.map(|_| ()));
    // Bit 0 of a status byte, which the mask drops: both engines take the frame.
    let mut odd = good.clone();
    odd[8] ^= 0x01;
    assert!(Response::decode(&odd).is_ok());
    assert!(busspec_model::interp::decode(&p, Some(Direction::Response), None, &odd).is_ok());
    let t = agree::agree::<Herkulex>(&p);
    assert!(t.accepted >= 6 && t.refused > 50, "{t:?}");
    let found = examples_stream_alike::<Herkulex>(&p, 0x4E5C, "stat_ack");
    assert!(found > 50, "only {found} STAT ACKs found");
}

/// The 16-bit sum negated (JBD's battery management protocol), a layout, header fields and a
/// checksum's first covered part per direction: the examples replay (the protocol document's
/// request and reply among them), a request's state leads its register and a reply's status
/// follows its register, both checksums cover from offset 2 (a request's register, a reply's
/// status); each message's header value is checked (a read's state, a reply's status); a
/// frame whose checksum is the sum itself rather than its negation, or a reply's
/// checksum over its register too, is refused in both engines' words, and both agree on every
/// frame mutated from the examples and on captures of them.
#[test]
fn sum16_complement_snapshot_agrees_with_the_interpreter() {
    use jbd_bms::{JbdBms, Request, Response};
    let file = "model/tests/fixtures/valid/jbd_bms.yaml";
    replay::<JbdBms>(file);
    let p = fixture(file);
    assert_eq!(jbd_bms::checksum(&[0x03, 0x00]), 0xFFFD);
    let c = &p.framing.checksum;
    assert_eq!((c.covers_from, c.response_covers_from), (2, 2));
    // DD A5 03 00 with the plain sum 00 03 where the negated one FF FD belongs.
    let plain = [0xDD, 0xA5, 0x03, 0x00, 0x00, 0x03, 0x77];
    let g = Request::decode(&plain).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "checksum mismatch at offset 4: expected 0xFFFD, found 0x0003"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, &plain);
    same_text(g, i.map(|_| ()));
    // The error reply to register 03: its status 80 after the register.
    let error = [0xDD, 0x03, 0x80, 0x00, 0xFF, 0x80, 0x77];
    match Response::decode(&error).map(|d| d.message) {
        Ok(Response::BasicInfoError(_)) => {}
        other => panic!("decoded as {other:?}"),
    }
    match Request::decode(&[0xDD, 0xA5, 0x04, 0x00, 0xFF, 0xFC, 0x77]).map(|d| d.message) {
        Ok(Request::ReadCellVoltages(_)) => {}
        other => panic!("decoded as {other:?}"),
    }
    // Each message's header value (`header:`): a write's state 5A where every request here
    // is a read (A5; the checksum does not cover it), an error reply's status 00 where it
    // is 80, refused alike.
    let write = [0xDD, 0x5A, 0x04, 0x00, 0xFF, 0xFC, 0x77];
    let g = Request::decode(&write).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "invalid value for read_cell_voltages.state at offset 1: expected 0xA5, found 0x5A"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, &write);
    same_text(g, i.map(|_| ()));
    let ok_but_empty = [0xDD, 0x03, 0x00, 0x00, 0x00, 0x00, 0x77];
    let g = Response::decode(&ok_but_empty).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "invalid value for basic_info_error.status at offset 2: expected 0x80, found 0x00"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &ok_but_empty);
    same_text(g, i.map(|_| ()));
    // Its checksum over the register too (!(03 + 80 + 00) + 1): refused alike.
    let over_register = [0xDD, 0x03, 0x80, 0x00, 0xFF, 0x7D, 0x77];
    let g = Response::decode(&over_register).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "checksum mismatch at offset 4: expected 0xFF80, found 0xFF7D"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &over_register);
    same_text(g, i.map(|_| ()));
    let t = agree::agree::<JbdBms>(&p);
    assert!(t.accepted >= 7 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<JbdBms>(&p, 0x1BD5, "read_version");
    assert!(found > 20, "only {found} read_version frames found");
}

/// A layout per direction (Sensirion SHDLC, the SPS30): the examples replay (the datasheet's
/// requests among them), a request's length field sits at offset 3 and a reply's at 4 after
/// its state byte, the state is a field of every reply and of no request, a frame laid out as
/// the other direction's is refused in both engines' words, and both agree on every frame
/// mutated from the examples and on captures of them through both stream decoders.
#[test]
fn layout_by_direction_snapshot_agrees_with_the_interpreter() {
    use shdlc::{Request, Response, Shdlc};
    let file = "model/tests/fixtures/valid/shdlc.yaml";
    replay::<Shdlc>(file);
    let p = fixture(file);
    assert_eq!(shdlc::checksum(&[0x00, 0x00, 0x02, 0x01, 0x03]), 0xF9);
    // Read measured values as the datasheet prints it, and its empty reply.
    let read = [0x7E, 0x00, 0x03, 0x00, 0xFC, 0x7E];
    assert_eq!(
        Request::decode(&read).map(|d| d.message),
        Ok(Request::ReadMeasuredValues(
            shdlc::request::ReadMeasuredValues {}
        ))
    );
    let empty = [0x7E, 0x00, 0x03, 0x43, 0x00, 0xB9, 0x7E];
    match Response::decode(&empty).map(|d| d.message) {
        Ok(Response::NoNewValues(r)) => assert_eq!(r.state, shdlc::State::NotAllowedInState),
        other => panic!("decoded as {other:?}"),
    }
    // A request is no reply: its length byte where a reply's state is, and one byte short.
    let g = Response::decode(&read).map(|_| ());
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &read);
    same_text(g, i.map(|_| ()));
    let g = Request::decode(&empty).map(|_| ());
    let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, &empty);
    same_text(g, i.map(|_| ()));
    let t = agree::agree::<Shdlc>(&p);
    assert!(t.accepted >= 15 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<Shdlc>(&p, 0x5D1C, "read_measured_values");
    assert!(found > 20, "only {found} read_measured_values frames found");
}

/// End bytes alone delimit Nextion's frames (no start byte, length field or checksum): the
/// examples replay; a list that holds the end bytes before the frame's own is refused by both
/// decoders and both encoders in the same words; a fixed-length reply holding them takes its
/// whole length; both stream decoders end a frame at its first end bytes, on the capture the
/// longest-first rule once read as one 16-byte instruction and on random captures of the
/// replies.
#[test]
fn end_delimited_snapshot_agrees_with_the_interpreter() {
    use busspec_model::interp::{self, Raw, Value};
    use nextion::{Nextion, Request, Response};
    let file = "model/tests/fixtures/valid/nextion.yaml";
    replay::<Nextion>(file);
    let p = fixture(file);
    // `a`, FF FF FF, `b`, then the frame's own end bytes.
    let inside = [0x61, 0xFF, 0xFF, 0xFF, 0x62, 0xFF, 0xFF, 0xFF];
    let g = Request::decode(&inside).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "instruction.text at offset 1: holds the end bytes FF FF FF, which end the frame there"
    );
    same_text(
        g,
        interp::decode(&p, Some(Direction::Request), None, &inside).map(|_| ()),
    );
    // The text ends in FF: with the end bytes, they first appear one byte early.
    let late = [0x61, 0xFF, 0xFF, 0xFF, 0xFF];
    same_text(
        Request::decode(&late).map(|_| ()),
        interp::decode(&p, Some(Direction::Request), None, &late).map(|_| ()),
    );
    assert!(Request::decode(&late).is_err());
    for text in [&b"a\xFF\xFF\xFFb"[..], b"ab\xFF", b"\xFF\xFF"] {
        let message = Request::Instruction(nextion::request::Instruction {
            text: busspec_runtime::codec::Repeated::from_slice(text).unwrap(),
        });
        let g = message.encode(0, &mut [0u8; 256]);
        let values = [Value {
            name: "text".into(),
            raw: Raw::Text(text.to_vec()),
        }];
        let i = interp::encode(&p, p.find("instruction").unwrap(), 0, &values);
        let (g, i) = (g.unwrap_err().to_string(), i.unwrap_err().to_string());
        assert_eq!(g, i);
        assert!(g.contains("would put the end bytes FF FF FF"), "{g}");
    }
    // Numeric data -1: a fixed-length reply takes its whole length.
    let minus_one = [0x71, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF];
    assert_eq!(
        Response::decode(&minus_one).map(|d| d.message),
        Ok(Response::Number(nextion::response::Number { value: -1 }))
    );
    let t = agree::agree::<Nextion>(&p);
    assert!(t.accepted >= 10 && t.refused > 100, "{t:?}");
    // The capture the longest-first rule read as one instruction: three replies.
    let cap = [
        0x01, 0xFF, 0xFF, 0xFF, 0x71, 0x01, 0x02, 0x00, 0x00, 0xFF, 0xFF, 0xFF, 0x01, 0xFF, 0xFF,
        0xFF,
    ];
    let seen = |cuts: &[usize]| {
        let want = interp_seen_as(&p, &cap, cuts, Some(Direction::Response));
        let got = generated_seen_as::<Nextion>(&cap, cuts, Some(Direction::Response));
        assert_eq!(got, want);
        got
    };
    let whole = seen(&[cap.len()]);
    let names: Vec<&str> = whole.iter().map(|s| s.0.as_str()).collect();
    assert_eq!(names, ["success", "number", "success"]);
    assert_eq!(seen(&[1]), whole);
    assert_eq!(seen(&[3, 5]), whole);
    // Both directions: every reply is an instruction's text too, so each frame is
    // ambiguous, but the frames split alike at the same places.
    let both = interp_seen(&p, &cap, &[cap.len()]);
    assert_eq!(generated_seen::<Nextion>(&cap, &[cap.len()]), both);
    let at: Vec<(u64, u64)> = both.iter().map(|s| (s.1, s.2)).collect();
    assert_eq!(at, [(0, 4), (4, 8), (12, 4)]);
    // Random captures of the replies, with noise and cut anywhere.
    let replies: Vec<Vec<u8>> = p
        .examples
        .iter()
        .filter(|e| p.message(e.message).direction == Direction::Response)
        .map(|e| e.wire.clone())
        .collect();
    let mut rng = agree::Rng(0x4E58);
    let mut numbers = 0;
    for _ in 0..200 {
        let mut cap = Vec::new();
        for _ in 0..12 {
            if rng.below(6) == 0 {
                cap.extend((0..1 + rng.below(4)).map(|_| rng.below(256) as u8));
            }
            cap.extend_from_slice(&replies[rng.below(replies.len() as u64) as usize]);
        }
        let cuts: Vec<usize> = (0..5).map(|_| 1 + rng.below(12) as usize).collect();
        let want = interp_seen_as(&p, &cap, &cuts, Some(Direction::Response));
        let got = generated_seen_as::<Nextion>(&cap, &cuts, Some(Direction::Response));
        assert_eq!(got, want, "capture {cap:02X?}");
        numbers += got.iter().filter(|s| s.0 == "number").count();
    }
    assert!(numbers > 100, "only {numbers} number frames found");
}

/// A 24-bit CRC (RTCM 3's CRC-24Q): the examples replay, the catalogue's check value holds in
/// generated code, a frame with a byte of its CRC changed is refused in both engines' words
/// (six hex digits), and both engines agree on every frame mutated from the examples and on
/// captures of them.
#[test]
fn crc24_snapshot_agrees_with_the_interpreter() {
    use rtcm3_frame::{Request, Rtcm3Frame};
    let file = "model/tests/fixtures/valid/rtcm3_frame.yaml";
    replay::<Rtcm3Frame>(file);
    let p = fixture(file);
    assert_eq!(rtcm3_frame::checksum(b"123456789"), 0xCD_E703);
    let mut bad = p.examples[1].wire.clone();
    let last = bad.len() - 1;
    bad[last] ^= 0x01;
    let g = Request::decode(&bad).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "checksum mismatch at offset 9: expected 0x09263C, found 0x09263D"
    );
    same_text(
        g,
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &bad).map(|_| ()),
    );
    let t = agree::agree::<Rtcm3Frame>(&p);
    assert!(t.accepted >= 2 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<Rtcm3Frame>(&p, 0xD300, "antenna");
    assert!(found > 50, "only {found} antenna frames found");
}

/// A reply whose checksum takes in its request's bytes (Pelco D's general response): the
/// examples replay with their requests' frames, both engines refuse such a reply without them
/// in the same words, check it over them alike (every frame mutated from the examples, alone
/// and as the reply to its example request), encode it only over them, and a stream keeps the
/// bytes of the request before a reply.
#[test]
fn over_request_snapshot_agrees_with_the_interpreter() {
    use busspec_runtime::EncodeError;
    use pelco_d_replies::{PelcoDReplies, Response, StreamDecoder};
    let file = "model/tests/fixtures/valid/pelco_d_replies.yaml";
    replay::<PelcoDReplies>(file);
    let p = fixture(file);
    let (zoom, reply) = (
        [0xFF, 0x01, 0x00, 0x20, 0x00, 0x00, 0x21],
        [0xFF, 0x01, 0x00, 0x21],
    );
    let g = Response::decode(&reply).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "general_response's checksum at offset 3 takes in its request's bytes: decode it as the reply to its request"
    );
    same_text(
        g,
        busspec_model::interp::decode(&p, Some(Direction::Response), None, &reply).map(|_| ()),
    );
    let d = PelcoDReplies::decode_reply_to(&reply, &zoom).unwrap();
    assert_eq!(d.message.name(), "general_response");
    let mut buf = [0u8; 16];
    assert_eq!(
        d.message.encode(1, &mut buf),
        Err(EncodeError::NeedsRequest {
            message: "general_response"
        })
    );
    let aux = [0xFF, 0x01, 0x00, 0x09, 0x00, 0x01, 0x0B];
    let n = PelcoDReplies::encode_reply(&d.message, 1, &aux, &mut buf).unwrap();
    assert_eq!(&buf[..n], [0xFF, 0x01, 0x00, 0x0B]);
    assert!(PelcoDReplies::decode_reply_to(&reply, &aux).is_err());
    let t = agree::agree::<PelcoDReplies>(&p);
    assert!(t.accepted >= 8 && t.refused > 20, "{t:?}");
    // A stream: each reply checked over the request before it, and a reply after the wrong
    // request, or none, is no frame.
    let capture = [
        &zoom[..],
        &reply,
        &aux,
        &[0xFF, 0x01, 0x00, 0x0B],
        &aux,
        &reply,
    ]
    .concat();
    let mut s = StreamDecoder::new(None);
    let mut events: Vec<pelco_d_replies::Event> = s.feed(&capture).collect();
    events.extend(core::iter::from_fn(|| s.finish()));
    let names: Vec<&str> = events
        .iter()
        .filter_map(|e| match e {
            pelco_d_replies::Event::Request { frame, .. } => Some(frame.message.name()),
            pelco_d_replies::Event::Response { frame, .. } => Some(frame.message.name()),
            _ => None,
        })
        .collect();
    assert_eq!(
        names,
        [
            "ptz",
            "general_response",
            "set_auxiliary",
            "general_response",
            "set_auxiliary"
        ]
    );
    let found = examples_stream_alike::<PelcoDReplies>(&p, 0x0D00, "general_response");
    assert!(found > 10, "only {found} general responses found");
}

/// Messages without a checksum (RoboClaw: reads travel as address and command alone, a
/// write's acknowledgement is the single byte FF) beside replies whose CRC takes in the
/// read's bytes: the examples replay, a read and the acknowledgement decode and encode
/// without a checksum, a read with bytes after it is refused in both engines' words, a reply
/// is checked over the read before it, and both engines agree on every frame mutated from the
/// examples (alone and as the reply to their request) and on captures of them.
#[test]
fn unchecked_snapshot_agrees_with_the_interpreter() {
    use roboclaw::{Request, Response, Roboclaw, StreamDecoder};
    let file = "model/tests/fixtures/valid/roboclaw.yaml";
    replay::<Roboclaw>(file);
    let p = fixture(file);
    let read = [0x80, 0x18];
    let d = Request::decode(&read).unwrap();
    assert_eq!(d.address, 0x80);
    assert_eq!(
        d.message,
        Request::ReadMainBattery(roboclaw::request::ReadMainBattery)
    );
    let mut buf = [0u8; 16];
    assert_eq!(d.message.encode(0x80, &mut buf), Ok(2));
    assert_eq!(buf[..2], read);
    let ack = Response::decode(&[0xFF]).unwrap();
    assert_eq!(ack.message.encode(0, &mut buf), Ok(1));
    assert_eq!(buf[0], 0xFF);
    // A read followed by a CRC of its own is no read: refused alike.
    for bad in [&[0x80, 0x18, 0x1D, 0x2B][..], &[0x80, 0x18, 0x00], &[0x80]] {
        let g = Request::decode(bad).map(|_| ());
        assert!(g.is_err(), "{bad:02X?}");
        same_text(
            g,
            busspec_model::interp::decode(&p, Some(Direction::Request), None, bad).map(|_| ()),
        );
    }
    let reply = [0x00, 0xF1, 0xC8, 0xC4];
    let d = Roboclaw::decode_reply_to(&reply, &read).unwrap();
    assert_eq!(d.message.name(), "main_battery");
    assert!(Roboclaw::decode_reply_to(&reply, &[0x80, 0x19]).is_err());
    let n = Roboclaw::encode_reply(&d.message, 0, &read, &mut buf).unwrap();
    assert_eq!(buf[..n], reply);
    let t = agree::agree::<Roboclaw>(&p);
    assert!(t.accepted >= 10 && t.refused > 50, "{t:?}");
    // A master's stream: each reply checked over the read before it.
    let forward = [0x80, 0x00, 0x40, 0x73, 0x9E];
    let capture = [&read[..], &reply, &forward, &[0xFF], &read, &reply].concat();
    let mut s = StreamDecoder::new(None);
    let mut events: Vec<roboclaw::Event> = s.feed(&capture).collect();
    events.extend(core::iter::from_fn(|| s.finish()));
    let names: Vec<&str> = events
        .iter()
        .filter_map(|e| match e {
            roboclaw::Event::Request { frame, .. } => Some(frame.message.name()),
            roboclaw::Event::Response { frame, .. } => Some(frame.message.name()),
            _ => None,
        })
        .collect();
    assert_eq!(
        names,
        [
            "read_main_battery",
            "main_battery",
            "drive_forward_m1",
            "ack",
            "read_main_battery",
            "main_battery"
        ],
        "{events:?}"
    );
}

/// No start byte, no address, no checksum (Maestro's compact protocol): the examples replay,
/// both engines agree on every frame mutated from them and on captures, where only the codes
/// and lengths frame the stream.
#[test]
fn no_checksum_snapshot_agrees_with_the_interpreter() {
    use maestro_compact::{MaestroCompact, Request};
    let file = "model/tests/fixtures/valid/maestro_compact.yaml";
    replay::<MaestroCompact>(file);
    let p = fixture(file);
    assert_eq!(
        Request::decode(&[0x90, 0x05]).map(|d| d.message),
        Ok(Request::GetPosition(
            maestro_compact::request::GetPosition { channel: 5 }
        ))
    );
    let t = agree::agree::<MaestroCompact>(&p);
    assert!(t.accepted >= 3 && t.refused > 10, "{t:?}");
    // Any two bytes are also a position reply: Get Position is ambiguous in a stream of both
    // directions, Set Target's four bytes are not.
    let found = examples_stream_alike::<MaestroCompact>(&p, 0x3A35, "set_target");
    assert!(found > 50, "only {found} set_target frames found");
}

/// Pelco-P: the ETX end byte before the checksum, which covers it; commands with no reply and
/// so no response at all. The examples replay, a wrong ETX is named before the checksum in
/// both engines' words, every frame is refused as a response, and both engines agree on every
/// frame mutated from the examples and on captures of them.
#[test]
fn pelco_p_snapshot_agrees_with_the_interpreter() {
    use pelco_p::{PelcoP, Request};
    let file = "model/tests/fixtures/valid/pelco_p.yaml";
    replay::<PelcoP>(file);
    let p = fixture(file);
    let go_to = [0xA0, 0x00, 0x00, 0x07, 0x00, 0x01, 0xAF, 0x09];
    let d = Request::decode(&go_to).unwrap();
    assert_eq!(
        d.message,
        Request::GoToPreset(pelco_p::request::GoToPreset { preset: 1 })
    );
    assert_eq!(d.message.command().reply, busspec_runtime::Reply::None);
    assert_eq!(d.message.command().reply, busspec_runtime::Reply::None);
    let mut etx = go_to;
    etx[6] = 0xAE;
    let g = Request::decode(&etx).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "bad end byte at offset 6: expected 0xAF, found 0xAE"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, &etx);
    same_text(g, i.map(|_| ()));
    // The checksum covers the ETX: another ETX with its checksum resealed is still refused
    // for the ETX, and the resealed frame's checksum differs from the original's.
    let mut resealed = etx;
    agree::reseal(&p, &mut resealed);
    assert_eq!(
        resealed, go_to,
        "reseal writes the ETX back and the checksum over it"
    );
    assert!(pelco_p::Response::decode(&go_to).is_err());
    let t = agree::agree::<PelcoP>(&p);
    assert!(t.accepted >= 2 && t.refused > 50, "{t:?}");
    let found = examples_stream_alike::<PelcoP>(&p, 0x9E1C0, "go_to_preset");
    assert!(found > 100, "only {found} go_to_preset frames found");
}

/// MSP v1: the checksum covers from the length field, which sits after a 1-byte code (it once
/// covered from where the length field sits after no code, so every example failed); the
/// examples replay and both engines agree on every frame mutated from them and on captures.
#[test]
fn msp_snapshot_agrees_with_the_interpreter() {
    use msp_v1::{MspV1, Request, Response};
    let file = "model/tests/fixtures/valid/msp_v1.yaml";
    replay::<MspV1>(file);
    let p = fixture(file);
    assert_eq!(msp_v1::checksum(&[0x00, 0x01]), 0x01);
    assert_eq!(
        Request::decode(&[0x24, 0x4D, 0x3C, 0x00, 0x01, 0x01]).map(|d| d.message),
        Ok(Request::ApiVersion(msp_v1::request::ApiVersion))
    );
    let error = [0x24, 0x4D, 0x21, 0x00, 0x6C, 0x6C];
    assert_eq!(
        Response::decode_reply(&error, &Request::Attitude(msp_v1::request::Attitude))
            .map(|d| d.message),
        Ok(Response::Error(msp_v1::response::Error { cmd: 108 }))
    );
    let t = agree::agree::<MspV1>(&p);
    assert!(t.accepted >= 4 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<MspV1>(&p, 0x3517, "attitude_reply");
    assert!(found > 50, "only {found} attitude_reply frames found");
}

/// Start bytes that differ by direction: a request and its reply share a code, and the start
/// bytes tell them apart in both engines, in `decode` and in a stream of both; a frame with the
/// other direction's start bytes is refused at the byte that differs.
#[test]
fn start_by_direction_snapshot_agrees_with_the_interpreter() {
    use busspec_runtime::DecodeError;
    use msp_by_direction::{MspByDirection, Request, Response};
    let file = "model/tests/fixtures/valid/msp_by_direction.yaml";
    replay::<MspByDirection>(file);
    let p = fixture(file);
    let request = [0x24, 0x4D, 0x3C, 0x00, 0x01, 0x01];
    let reply = [0x24, 0x4D, 0x3E, 0x03, 0x01, 0x00, 0x01, 0x2C, 0x2F];
    assert_eq!(
        Request::decode(&request).map(|d| d.message),
        Ok(Request::ApiVersion(msp_by_direction::request::ApiVersion))
    );
    let wrong = DecodeError::BadStart {
        offset: 2,
        expected: 0x3E,
        found: 0x3C,
    };
    assert_eq!(Response::decode(&request), Err(wrong));
    assert_eq!(
        Response::decode(&reply).map(|d| d.message),
        Ok(Response::ApiVersionReply(
            msp_by_direction::response::ApiVersionReply {
                protocol_version: 0,
                api_major: 1,
                api_minor: 44
            }
        ))
    );
    let mut buf = [0u8; 16];
    let n = Request::ApiVersion(msp_by_direction::request::ApiVersion)
        .encode(0, &mut buf)
        .unwrap();
    assert_eq!(&buf[..n], &request);
    let t = agree::agree::<MspByDirection>(&p);
    assert!(t.accepted >= 6 && t.refused > 100, "{t:?}");
    for (seed, message) in [(0x24D3, "api_version_reply"), (0x24D4, "api_version")] {
        let found = examples_stream_alike::<MspByDirection>(&p, seed, message);
        assert!(found > 30, "only {found} {message} frames found");
    }
}

/// The start byte and the length field sent twice: a second copy that differs is refused
/// where it lies, as the interpreter refuses it, and both engines agree on every frame
/// mutated from the examples and on captures of them.
#[test]
fn repeated_start_and_length_snapshot_agrees_with_the_interpreter() {
    use busspec_runtime::DecodeError;
    use ft12_variable::{Ft12Variable, Request};
    let file = "model/tests/fixtures/valid/ft12_variable.yaml";
    replay::<Ft12Variable>(file);
    let p = fixture(file);
    let reset = [0x68, 0x03, 0x03, 0x68, 0x53, 0xFE, 0x50, 0xA1, 0x16];
    assert_eq!(
        Request::decode(&reset).map(|d| (d.address, d.message)),
        Ok((0xFE, Request::Reset(ft12_variable::request::Reset)))
    );
    let mut buf = [0u8; 32];
    let n = Request::Reset(ft12_variable::request::Reset)
        .encode(0xFE, &mut buf)
        .unwrap();
    assert_eq!(&buf[..n], &reset);
    for (at, b, want) in [
        (
            2,
            0x04,
            DecodeError::LengthMismatch {
                offset: 2,
                expected: 3,
                found: 4,
            },
        ),
        (
            3,
            0x69,
            DecodeError::BadStart {
                offset: 3,
                expected: 0x68,
                found: 0x69,
            },
        ),
    ] {
        let mut bad = reset;
        bad[at] = b;
        let got = Request::decode(&bad).unwrap_err();
        assert_eq!(got, want);
        let interp = busspec_model::interp::decode(&p, None, None, &bad).unwrap_err();
        assert_eq!(got.to_string(), interp.to_string());
    }
    let t = agree::agree::<Ft12Variable>(&p);
    assert!(t.accepted >= 3 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<Ft12Variable>(&p, 0x6868, "rsp_ud");
    assert!(found > 30, "only {found} rsp_ud frames found");
}

/// The start bytes again after a two-byte code: the generated decode reads the second copy
/// where a two-byte code puts it (it read it at a one-byte code's offset, and refused every
/// frame: random specs, seed 34), and agrees with the interpreter on every mutation.
#[test]
fn start_after_a_two_byte_code_is_read_where_it_sits() {
    use busspec_runtime::DecodeError;
    use sync_after_code::{Request, SyncAfterCode};
    let file = "model/tests/fixtures/valid/sync_after_code.yaml";
    replay::<SyncAfterCode>(file);
    let p = fixture(file);
    let read = [0x7E, 0x01, 0x02, 0x7E, 0x05, 0x06];
    assert_eq!(
        Request::decode(&read).map(|d| d.message),
        Ok(Request::Read(sync_after_code::request::Read {
            register: 5
        }))
    );
    let mut bad = read;
    bad[3] = 0x7F;
    bad[5] ^= 0x01;
    assert_eq!(
        Request::decode(&bad),
        Err(DecodeError::BadStart {
            offset: 3,
            expected: 0x7E,
            found: 0x7F
        })
    );
    let t = agree::agree::<SyncAfterCode>(&p);
    assert!(t.accepted >= 2 && t.refused > 50, "{t:?}");
}

/// BCD fields: the examples replay, a digit above 9 is refused as the interpreter refuses it,
/// a value past the digits is refused by encode, and both engines agree on every frame
/// mutated from the examples and on captures of them.
/// A CRC that takes each message's extra byte (MAVLink's CRC_EXTRA): the generated checksum
/// finds it by the code, as the interpreter does; a frame checked without it, or with another
/// message's, is refused alike.
#[test]
fn crc_extra_snapshot_agrees_with_the_interpreter() {
    use crc_extra::{CrcExtra, Response};
    let file = "model/tests/fixtures/valid/crc_extra.yaml";
    replay::<CrcExtra>(file);
    let p = fixture(file);
    let t = agree::agree::<CrcExtra>(&p);
    assert!(t.accepted >= p.examples.len() && t.refused > 100, "{t:?}");
    let heartbeat = [
        0xFE, 0x09, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x03, 0x51, 0x04, 0x03, 0x37, 0x97,
    ];
    assert!(Response::decode(&heartbeat).is_ok());
    assert_eq!(crc_extra::checksum_extra(&heartbeat[1..12]), Some(50));
    // The CRC without the extra byte, as a reader that knows no CRC_EXTRA computes it.
    let plain = busspec_runtime::crc::Crc::<u16>::new(&crc_extra::CRC_ALGORITHM)
        .checksum(&heartbeat[1..12])
        .to_le_bytes();
    let mut bare = heartbeat;
    bare[12..].copy_from_slice(&plain);
    let refused = Response::decode(&bare).unwrap_err();
    let interp = busspec_model::interp::decode(&p, None, None, &bare).unwrap_err();
    assert_eq!(refused.to_string(), interp.to_string());
    assert!(
        refused.to_string().contains("checksum mismatch"),
        "{refused}"
    );
}

/// Header fields every message carries (MAVLink v1's sequence, system and component IDs
/// between the length and the message id): pymavlink's frames replay, each variant carries the
/// header as fields decoded from where the header sits, and both engines agree on every frame
/// mutated from the examples.
#[test]
fn mavlink_v1_snapshot_agrees_with_the_interpreter() {
    use mavlink_v1::{MavlinkV1, Request, Response};
    let file = "model/tests/fixtures/valid/mavlink_v1.yaml";
    replay::<MavlinkV1>(file);
    let p = fixture(file);
    let t = agree::agree::<MavlinkV1>(&p);
    assert!(t.accepted >= p.examples.len() && t.refused > 100, "{t:?}");
    // pymavlink 2.4.50: HEARTBEAT from system 255, component 190, sequence 17.
    let heartbeat = [
        0xFE, 0x09, 0x11, 0xFF, 0xBE, 0x00, 0x00, 0x00, 0x00, 0x00, 0x06, 0x08, 0x00, 0x00, 0x03,
        0x15, 0xEA,
    ];
    let d = Response::decode(&heartbeat).unwrap();
    let Response::Heartbeat(mavlink_v1::response::Heartbeat {
        sequence,
        sysid,
        compid,
        vehicle_type,
        ..
    }) = d.message
    else {
        panic!("{d:?}");
    };
    assert_eq!((sequence, sysid, compid, vehicle_type), (17, 255, 190, 6));
    // The next heartbeat: one more in the sequence, the CRC over it.
    let mut next = d.message;
    if let Response::Heartbeat(mavlink_v1::response::Heartbeat { sequence, .. }) = &mut next {
        *sequence = 18;
    }
    let mut buf = [0u8; MavlinkV1::MAX_FRAME_LEN];
    let n = next.encode(0, &mut buf).unwrap();
    assert_eq!(buf[2], 18);
    assert_eq!(&buf[3..15], &heartbeat[3..15]);
    let interp = busspec_model::interp::decode(&p, None, None, &buf[..n]).unwrap();
    assert_eq!(p.message(interp.message).name, "heartbeat");
    let ping = [
        0xFE, 0x0E, 0x05, 0xFF, 0xBE, 0x04, 0x40, 0x42, 0x0F, 0x00, 0x00, 0x00, 0x00, 0x00, 0x07,
        0x00, 0x00, 0x00, 0x01, 0x01, 0xBE, 0xAC,
    ];
    let Request::Ping(mavlink_v1::request::Ping { sequence, seq, .. }) =
        Request::decode(&ping).unwrap().message
    else {
        panic!()
    };
    assert_eq!((sequence, seq), (5, 7));
}

/// Payload truncation (MAVLink v2, `framing.truncation: trailing_zeros`): pymavlink's frames
/// replay (most of them truncated); a SYS_STATUS of 43 payload bytes cut to every length from
/// none to one more than the whole decodes alike in both engines, in the same values or the
/// same words, and encodes back stripped alike; a truncated frame's bad checksum is refused at
/// its offset as it travelled by both; the 3-byte code of RAW_RPM (339) is `53 01 00`; both
/// engines agree on every frame mutated from the examples and on captures of them however cut.
#[test]
fn truncation_snapshot_agrees_with_the_interpreter() {
    use busspec_model::interp;
    use mavlink_v2::{MavlinkV2, Response};
    let file = "model/tests/fixtures/valid/mavlink_v2.yaml";
    replay::<MavlinkV2>(file);
    let p = fixture(file);
    // SYS_STATUS with every payload byte 1..=43, then cut to n bytes.
    let mut whole = vec![0xFD, 43, 0, 0, 7, 1, 1, 0x01, 0x00, 0x00];
    whole.extend(1..=43u8);
    whole.extend([0, 0]);
    interp::reseal(&p, &mut whole);
    let mut accepted = 0;
    for n in 0..=44usize {
        let mut wire = whole[..10 + n.min(43)].to_vec();
        if n == 44 {
            wire.push(0x2C);
        }
        wire[1] = n as u8;
        wire.extend([0, 0]);
        interp::reseal(&p, &mut wire);
        if agree::check::<MavlinkV2>(&p, Direction::Response, None, &wire) {
            accepted += 1;
            // Its values: the payload padded with zeros.
            let g = Response::decode(&wire).unwrap();
            let Response::SysStatus(mavlink_v2::response::SysStatus {
                battery_remaining,
                onboard_control_sensors_health_extended,
                ..
            }) = g.message
            else {
                panic!("{g:?}");
            };
            let want = |at: usize, v: i64| if n > at { v } else { 0 };
            assert_eq!(i64::from(battery_remaining), want(30, 31), "{n}");
            // The last field, at 39..43: as many of its bytes as came, the rest zeros.
            let health: Vec<u8> = (39..43)
                .map(|i| if i < n { i as u8 + 1 } else { 0 })
                .collect();
            assert_eq!(
                onboard_control_sensors_health_extended,
                u32::from_le_bytes([health[0], health[1], health[2], health[3]]),
                "{n}"
            );
            // Nothing to strip: written back as it came.
            let mut buf = [0u8; MavlinkV2::MAX_FRAME_LEN];
            let k = g.message.encode(0, &mut buf).unwrap();
            assert_eq!(&buf[..k], &wire[..], "{n}");
        }
        // The same frame with a bad checksum: refused alike, at its offset as it travelled.
        let mut bad = wire.clone();
        let at = bad.len() - 2;
        bad[at] ^= 1;
        let g = Response::decode(&bad).unwrap_err();
        let i = interp::decode(&p, Some(Direction::Response), None, &bad).unwrap_err();
        assert_eq!(g.to_string(), i.to_string(), "{n}");
        if (1..=43).contains(&n) {
            assert!(
                g.to_string()
                    .contains(&format!("checksum mismatch at offset {at}")),
                "{n}: {g}"
            );
        }
    }
    assert_eq!(accepted, 43);
    // Every request payload truncated (a PING of zeros travels as one byte).
    let mut buf = [0u8; MavlinkV2::MAX_FRAME_LEN];
    let ping = mavlink_v2::Request::Ping(mavlink_v2::request::Ping {
        incompat_flags: 0,
        compat_flags: 0,
        sequence: 9,
        sysid: 255,
        compid: 190,
        time_usec: 0,
        seq: 0,
        target_system: 0,
        target_component: 0,
    });
    let k = ping.encode(0, &mut buf).unwrap();
    assert_eq!(
        &buf[..k],
        &interp::parse_hex("FD 01 00 00 09 FF BE 04 00 00 00 37 6D").unwrap()[..]
    );
    let rpm = interp::parse_hex("FD 04 00 00 4E 01 01 53 01 00 00 90 BB 44 3C B5").unwrap();
    assert!(matches!(
        Response::decode(&rpm).unwrap().message,
        Response::RawRpm(mavlink_v2::response::RawRpm { index: 0, .. })
    ));
    assert_eq!(mavlink_v2::response::RawRpm::DESC.code, 0x530100);
    let t = agree::agree::<MavlinkV2>(&p);
    assert!(t.accepted >= p.examples.len() && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<MavlinkV2>(&p, 0x2323, "attitude");
    assert!(found > 30, "only {found} attitude frames found");
}

/// A header field before the code (MSP v2's flag byte, between `$X<` and the function),
/// which the checksum covers from: the examples replay, and a changed flag byte is refused by
/// both engines in the same words unless the checksum is made again.
#[test]
fn msp_v2_snapshot_agrees_with_the_interpreter() {
    use msp_v2::{MspV2, Request};
    let file = "model/tests/fixtures/valid/msp_v2.yaml";
    replay::<MspV2>(file);
    let p = fixture(file);
    let t = agree::agree::<MspV2>(&p);
    assert!(t.accepted >= p.examples.len() && t.refused > 20, "{t:?}");
    let flagged = [0x24, 0x58, 0x3C, 0x01, 0x02, 0x00, 0x00, 0x00, 0x3C];
    let Request::FcVariant(msp_v2::request::FcVariant { dont_reply }) =
        Request::decode(&flagged).unwrap().message
    else {
        panic!()
    };
    assert!(dont_reply);
    let mut bad = flagged;
    bad[3] = 0x00;
    same_text(
        Request::decode(&bad).map(|_| ()),
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &bad).map(|_| ()),
    );
}

#[test]
fn bcd_snapshot_agrees_with_the_interpreter() {
    use bcd_meter::{BcdMeter, Request, Response};
    use busspec_runtime::DecodeError;
    let file = "model/tests/fixtures/valid/bcd_meter.yaml";
    replay::<BcdMeter>(file);
    let p = fixture(file);
    let energy = [0x68, 0x01, 0x91, 0x56, 0x34, 0x12, 0x00, 0x02, 0x98, 0x16];
    let d = Response::decode(&energy).unwrap();
    let Response::Energy(bcd_meter::response::Energy { energy: e, tariff }) = d.message else {
        panic!("{d:?}");
    };
    assert_eq!((e.raw(), tariff), (123_456, 2));
    let mut bad = energy;
    bad[3] = 0x5A;
    bad[8] = 0x9C;
    let refused = Response::decode(&bad).unwrap_err();
    assert_eq!(
        refused,
        DecodeError::NotBcd {
            field: &bcd_meter::response::Energy::ENERGY_DESC,
            offset: 3,
            found: 0x0012_345A
        }
    );
    let interp = busspec_model::interp::decode(&p, None, None, &bad).unwrap_err();
    assert_eq!(refused.to_string(), interp.to_string());
    let mut buf = [0u8; 16];
    let clock = Request::SetClock(bcd_meter::request::SetClock {
        hour: 7,
        minute: 5,
        year: 1999,
    });
    let n = clock.encode(1, &mut buf).unwrap();
    assert_eq!(
        &buf[..n],
        &[0x68, 0x01, 0x08, 0x07, 0x05, 0x99, 0x19, 0x2F, 0x16]
    );
    let too_big = Request::SetClock(bcd_meter::request::SetClock {
        hour: 7,
        minute: 5,
        year: 10_000,
    });
    assert!(too_big.encode(1, &mut buf).is_err());
    let t = agree::agree::<BcdMeter>(&p);
    assert!(t.accepted >= 4 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<BcdMeter>(&p, 0xBCD, "energy");
    assert!(found > 30, "only {found} energy frames found");
}

/// Both stream decoders on 100 captures of `p`'s examples with noise between them (and, where
/// the framing's flag may be shared, frames sharing it), each cut into chunks several ways,
/// see the same events; how many `message` frames they found.
fn examples_stream_alike<P: Protocol>(p: &ir::Protocol, seed: u64, message: &str) -> usize {
    let frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    let mut rng = agree::Rng(seed);
    let mut found = 0;
    for _ in 0..100 {
        let mut cap = Vec::new();
        for _ in 0..20 {
            let f = &frames[rng.below(frames.len() as u64) as usize];
            if rng.below(8) == 0 {
                cap.extend((0..1 + rng.below(4)).map(|_| rng.below(256) as u8));
            }
            // A flag shared by two frames (HDLC): this frame's opening flag left out.
            let shared = p.framing.shared_flag().is_some_and(|flag| {
                cap.last() == Some(&flag) && f.first() == Some(&flag) && rng.below(2) == 0
            });
            // Wake-up bytes (DL/T 645): as many as the frame may have, or a few more (the
            // first of which are noise), or none.
            if let Some(pre) = p.framing.preamble.as_ref().filter(|_| rng.below(2) == 0) {
                let frame = p.framing.after_preamble(f);
                let k = rng.below(u64::from(pre.max) + 3) as usize;
                cap.extend(std::iter::repeat(pre.byte).take(k));
                cap.extend_from_slice(frame);
                continue;
            }
            cap.extend_from_slice(&f[usize::from(shared)..]);
        }
        let cuts: Vec<usize> = (0..6).map(|_| 1 + rng.below(20) as usize).collect();
        let want = interp_seen(p, &cap, &cuts);
        let got = generated_seen::<P>(&cap, &cuts);
        assert_eq!(got, want, "capture {cap:02X?}");
        found += got.iter().filter(|s| s.0 == message).count();
    }
    found
}

/// Frames without an address: the examples replay, decode reports address 0 and encode
/// refuses any other as the interpreter does, and both engines agree on every frame mutated
/// from the examples and on captures of them, however they are cut.
#[test]
fn unaddressed_snapshot_agrees_with_the_interpreter() {
    use unaddressed::{Request, Unaddressed};
    let file = "model/tests/fixtures/valid/unaddressed.yaml";
    replay::<Unaddressed>(file);
    let p = fixture(file);
    let set_rate = [0xA5, 0x5A, 0x03, 0x20, 0x64, 0x00, 0x47];
    let d = Request::decode(&set_rate).unwrap();
    assert_eq!(
        (d.address, d.message),
        (
            0,
            Request::SetRate(unaddressed::request::SetRate { rate: 100 })
        )
    );
    let mut buf = [0u8; 16];
    let g = d.message.encode(3, &mut buf).map(|_| ());
    let values = [busspec_model::interp::Value {
        name: "rate".into(),
        raw: busspec_model::interp::Raw::Int(100),
    }];
    let r = p.find("set_rate").unwrap();
    let i = busspec_model::interp::encode(&p, r, 3, &values).map(|_| ());
    match (g, i) {
        (Err(g), Err(i)) => {
            assert_eq!(g.to_string(), i.to_string());
            assert!(g.to_string().contains("carry no address"), "{g}");
        }
        other => panic!("both encoders must refuse address 3: {other:?}"),
    }
    let t = agree::agree::<Unaddressed>(&p);
    assert!(t.accepted >= 5 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<Unaddressed>(&p, 0xADD0, "set_rate");
    assert!(found > 100, "only {found} set_rate frames found");
}

/// Every fixture whose snapshot compiles here, held to the interpreter on its examples and the
/// frames mutated from them: the same acceptance, values and re-encoding, and every refusal in
/// the same words (`agree::check`).
#[test]
fn every_snapshot_refuses_as_the_interpreter_words_it() {
    let t = [
        agree::agree::<mini::Mini>(&fixture("model/tests/fixtures/valid/minimal.yaml")),
        agree::agree::<mini_crc::MiniCrc>(&fixture("model/tests/fixtures/valid/minimal_crc.yaml")),
        agree::agree::<clash::Clash>(&fixture("codegen/tests/fixtures/core_names.yaml")),
        agree::agree::<syncy::Syncy>(&fixture("model/tests/fixtures/valid/minimal_sync.yaml")),
        agree::agree::<codeless::Codeless>(&fixture(
            "model/tests/fixtures/valid/minimal_codeless.yaml",
        )),
    ];
    for t in t {
        assert!(t.accepted > 0 && t.refused > 50, "{t:?}");
    }
}

/// Floats and 64-bit integers: the examples replay (a word-swapped f32 as a Modbus meter sends
/// it, a u64 above `i64::MAX`, a negative i64), the typed values are the numbers the spec
/// states, NaN and out-of-range floats are refused alike by both engines in the same words,
/// and both engines agree on every frame mutated from the examples and on captures of them.
#[test]
fn float_and_64_bit_snapshots_agree_with_the_interpreter() {
    use meter_floats::{MeterFloats, Response};
    let file = "model/tests/fixtures/valid/meter_floats.yaml";
    replay::<MeterFloats>(file);
    let p = fixture(file);
    let readings = busspec_model::interp::parse_hex(
        "01 04 19 9A 43 66 42 48 00 00 40 C8 1C D6 C8 B4 39 58 99 9A 99 99 99 99 3F B9 FF FF FF FF FF FF FD 98 FF FF FE E0 8E 04 FB 35 56 78 12 34 FF FB FF FF 58 77",
    )
    .unwrap();
    let d = Response::decode(&readings).unwrap();
    let Response::Readings(meter_floats::response::Readings {
        voltage,
        frequency,
        energy,
        energy_swapped,
        pulses,
        drift,
        counter,
        temperature,
    }) = d.message
    else {
        panic!("{d:?}")
    };
    assert_eq!(voltage, 230.1f32);
    assert_eq!(frequency, 50.0f32);
    assert_eq!(energy, 12345.678f64);
    assert_eq!(energy_swapped, 0.1f64);
    assert_eq!(pulses, 18446744073709551000u64);
    assert_eq!(drift, -1234567890123i64);
    assert_eq!(counter, 305419896u32);
    assert_eq!(temperature, -5i32);
    let mut buf = [0u8; 64];
    let n = d.message.encode(1, &mut buf).unwrap();
    assert_eq!(&buf[..n], &readings[..]);
    // A NaN, an infinity and a value just past the range: refused by both, in the same words.
    let r = p.find("readings").unwrap();
    for bits in [
        0x7FC0_0001u32,
        0x7F80_0000,
        65.01f32.to_bits(),
        44.99f32.to_bits(),
    ] {
        let mut frame = readings.clone();
        frame[6..10].copy_from_slice(&bits.to_be_bytes());
        agree::reseal(&p, &mut frame);
        let g = Response::decode(&frame).map(|_| ());
        let i = busspec_model::interp::decode_as(&p, r, &frame).map(|_| ());
        same_text(g, i);
    }
    let t = agree::agree::<MeterFloats>(&p);
    assert!(t.accepted >= 4 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<MeterFloats>(&p, 0xF10A7, "readings");
    assert!(found > 100, "only {found} readings frames found");

    use telemetry_le::{Request, TelemetryLe};
    let file = "model/tests/fixtures/valid/telemetry_le.yaml";
    replay::<TelemetryLe>(file);
    let p = fixture(file);
    let t = agree::agree::<TelemetryLe>(&p);
    assert!(t.accepted >= 4 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<TelemetryLe>(&p, 0x7E1E, "state");
    assert!(found > 100, "only {found} state frames found");
    // Encode refuses a NaN where the field has a range, as the interpreter does.
    let m = Request::SetHome(telemetry_le::request::SetHome {
        lat: f64::NAN,
        lon: 0.0,
    });
    let g = m.encode(0, &mut buf).map(|_| ());
    let values = [
        busspec_model::interp::Value {
            name: "lat".into(),
            raw: busspec_model::interp::Raw::Int(f64::NAN.to_bits() as i64),
        },
        busspec_model::interp::Value {
            name: "lon".into(),
            raw: busspec_model::interp::Raw::Int(0),
        },
    ];
    let i = busspec_model::interp::encode(&p, p.find("set_home").unwrap(), 0, &values).map(|_| ());
    match (g, i) {
        (Err(g), Err(i)) => {
            assert_eq!(g.to_string(), i.to_string());
            assert_eq!(g.to_string(), "lat = NaN is outside its range -90.0..=90.0");
        }
        other => panic!("both encoders must refuse a NaN latitude: {other:?}"),
    }
}

/// Frames mutated before escaping: each example unescaped, a byte changed or the frame cut or
/// grown, resealed (and its length field made to agree), escaped again; so that most reach the
/// checks after the escapes, where the wire's own mutations mostly break an escape.
fn escaped_mutations(p: &ir::Protocol, d: Direction, wire: &[u8]) -> Vec<Vec<u8>> {
    let plain = busspec_model::escape::unescape_bytes_of(&p.framing, d, wire).unwrap();
    let mut out = Vec::new();
    for m in agree::mutations(p, d, &plain) {
        out.push(busspec_model::escape::escape_as(p, d, &m));
        out.push(busspec_model::escape::escape_bytes_of(&p.framing, d, &m));
    }
    out
}

/// Both engines on one escaped protocol: the examples replay, every frame mutated from them
/// (escaped or not) and random bytes decode alike, refusals in the same words, and captures of
/// the examples with noise frame alike however they are cut. Returns the frames each engine
/// accepted and refused.
fn escaped_agree<P: Protocol>(file: &str, seed: u64, message: &str) -> (usize, usize, usize) {
    replay::<P>(file);
    let p = fixture(file);
    let t = agree::agree::<P>(&p);
    assert!(t.accepted >= p.examples.len(), "{t:?}");
    let (mut accepted, mut refused) = (0, 0);
    for e in &p.examples {
        let d = e.message.direction;
        for f in escaped_mutations(&p, d, &e.wire) {
            if agree::check::<P>(&p, d, None, &f) {
                accepted += 1;
            } else {
                refused += 1;
            }
        }
    }
    let mut rng = agree::Rng(seed);
    for _ in 0..3000 {
        let n = rng.below(40) as usize;
        let f: Vec<u8> = (0..n).map(|_| rng.below(256) as u8).collect();
        for d in [Direction::Request, Direction::Response] {
            agree::check::<P>(&p, d, None, &f);
        }
    }
    let found = examples_stream_alike::<P>(&p, seed, message);
    (accepted, refused, found)
}

/// Escaping and stuffing: SLIP (a map), HDLC (XOR), COBS (a block of 254 bytes in an example)
/// and Dynamixel 2.0's stuffing (the length and CRC over the stuffed bytes), each held to the
/// interpreter by [`escaped_agree`]; a bad escape is refused by both in the same words.
#[test]
fn escaped_snapshots_agree_with_the_interpreter() {
    let slip = escaped_agree::<slip_sensor::SlipSensor>(
        "model/tests/fixtures/valid/slip_sensor.yaml",
        0x511F,
        "temperature",
    );
    let hdlc = escaped_agree::<hdlc_like::HdlcLike>(
        "model/tests/fixtures/valid/hdlc_like.yaml",
        0x7E7D,
        "write_register",
    );
    let cobs = escaped_agree::<cobs_link::CobsLink>(
        "model/tests/fixtures/valid/cobs_link.yaml",
        0xC0B5,
        "log",
    );
    let dxl = escaped_agree::<dynamixel2_stuffed::Dynamixel2Stuffed>(
        "model/tests/fixtures/valid/dynamixel2_stuffed.yaml",
        0xFFFD,
        "write4",
    );
    let xbee = escaped_agree::<xbee_api2::XbeeApi2>(
        "model/tests/fixtures/valid/xbee_api2.yaml",
        0x7D33,
        "transmit_request",
    );
    let kiss = escaped_agree::<kiss::Kiss>(
        "model/tests/fixtures/valid/kiss.yaml",
        0xC0DB,
        // A data frame reads alike both ways (a stream reports it ambiguous): count TXDELAY.
        "tx_delay",
    );
    let fport = escaped_agree::<fport::Fport>(
        "model/tests/fixtures/valid/fport.yaml",
        0x7E5D,
        "downlink_data",
    );
    let uplink = escaped_agree::<fport_uplink::FportUplink>(
        "model/tests/fixtures/valid/fport_uplink.yaml",
        0x0881,
        "uplink_data",
    );
    let both = escaped_agree::<fport_both::FportBoth>(
        "model/tests/fixtures/valid/fport_both.yaml",
        0x7E81,
        "uplink_data",
    );
    for (name, (accepted, refused, found)) in [
        ("fport", fport),
        ("fport_uplink", uplink),
        ("fport_both", both),
        ("slip", slip),
        ("kiss", kiss),
        ("hdlc", hdlc),
        ("cobs", cobs),
        ("dxl", dxl),
        ("xbee", xbee),
    ] {
        assert!(
            accepted > 5 && refused > 100 && found > 50,
            "{name}: {accepted} {refused} {found}"
        );
    }
    let p = fixture("model/tests/fixtures/valid/slip_sensor.yaml");
    let bad = busspec_model::interp::parse_hex("81 DB 41 DB DD 60 28 C0").unwrap();
    let g = slip_sensor::Response::decode(&bad).unwrap_err();
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &bad).unwrap_err();
    assert_eq!(
        g.to_string(),
        "bad escape at offset 1: 0xDB followed by 0x41"
    );
    assert_eq!(g.to_string(), i.to_string());
    // The stuffed write: the generated encoder stuffs FD after FF FF FD and counts it.
    let w = dynamixel2_stuffed::Request::Write4(dynamixel2_stuffed::request::Write4 {
        address: 0x74,
        value: 0x00FD_FFFF,
    });
    let mut buf = [0u8; dynamixel2_stuffed::MAX_FRAME_LEN];
    let n = w.encode(1, &mut buf).unwrap();
    assert_eq!(
        &buf[..n],
        &busspec_model::interp::parse_hex("FF FF FD 00 01 0A 00 03 74 00 FF FF FD FD 00 21 E7")
            .unwrap()[..]
    );
}

/// Garmin's serial link (fixture `garmin_link`): DLE stuffing, 10 doubled between the leading
/// DLE and the closing DLE ETX. Both engines agree on the examples, frames mutated from them and
/// random bytes ([`escaped_agree`]); a lone 10 is refused by both in the same words; the
/// generated encoder doubles a 10 in the data; both stream decoders find the end by pairing, so
/// a frame whose last data byte is 10 (`10 10 10 03`) and a size of 0x10 (`10 11 10 10 ...`)
/// are found whole.
#[test]
fn garmin_link_snapshot_agrees_with_the_interpreter() {
    use garmin_link::{GarminLink, Response};
    let file = "model/tests/fixtures/valid/garmin_link.yaml";
    let (accepted, refused, found) = escaped_agree::<GarminLink>(file, 0x1003, "date_time");
    assert!(
        accepted > 5 && refused > 100 && found > 50,
        "{accepted} {refused} {found}"
    );
    let p = fixture(file);
    let hex = |s: &str| busspec_model::interp::parse_hex(s).unwrap();
    for (bad, words) in [
        (
            "10 15 02 10 00 D9 10 03",
            "bad escape at offset 3: 0x10 followed by 0x00",
        ),
        (
            "10 FE 10 03 00 02 10 03",
            "bad escape at offset 2: 0x10 followed by 0x03",
        ),
    ] {
        let g = GarminLink::decode_response(&hex(bad)).map(|_| ());
        let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &hex(bad))
            .map(|_| ());
        assert_eq!(g.as_ref().unwrap_err().to_string(), words);
        same_text(g, i);
    }
    let nak = Response::Nak(garmin_link::response::Nak { packet_id: 0x10 });
    let mut buf = [0u8; garmin_link::MAX_FRAME_LEN];
    let n = nak.encode(0, &mut buf).unwrap();
    assert_eq!(&buf[..n], &hex("10 15 02 10 10 00 D9 10 03")[..]);
    // A capture of the date and time (its checksum's 10 doubled just before DLE ETX) and the
    // position (its size 0x10 doubled), a byte of noise between: each found whole.
    let cap = hex(
        "10 0E 08 0B 1D EA 07 0D 00 0A 10 10 AA 10 03 55 10 11 10 10 00 00 00 00 00 00 E0 3F 00 00 00 00 00 00 F4 BF 0D 10 03",
    );
    let want: Vec<Seen> = vec![
        ("date_time".into(), 0, 15),
        ("-".into(), 15, 1),
        ("position".into(), 16, 23),
    ];
    for cuts in [[1usize], [3], [64]] {
        assert_eq!(generated_seen::<GarminLink>(&cap, &cuts), want);
        assert_eq!(interp_seen(&p, &cap, &cuts), want);
    }
}

/// Trimble TSIP (fixture `tsip`): DLE stuffing without a size or checksum. Both engines agree
/// on the examples, mutated frames and random bytes; the generated encoder doubles the 10 of
/// a float; a lone 10 is refused by both in the same words.
#[test]
fn tsip_snapshot_agrees_with_the_interpreter() {
    use tsip::{Response, Tsip};
    let file = "model/tests/fixtures/valid/tsip.yaml";
    let (accepted, refused, found) = escaped_agree::<Tsip>(file, 0x7519, "gps_time");
    assert!(
        accepted > 5 && refused > 50 && found > 50,
        "{accepted} {refused} {found}"
    );
    let p = fixture(file);
    let hex = |s: &str| busspec_model::interp::parse_hex(s).unwrap();
    let bad = hex("10 41 41 10 00 00 09 60 41 90 00 00 10 03");
    let g = Tsip::decode_response(&bad).map(|_| ());
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &bad).map(|_| ());
    assert_eq!(
        g.as_ref().unwrap_err().to_string(),
        "bad escape at offset 3: 0x10 followed by 0x00"
    );
    same_text(g, i);
    let time = Response::GpsTime(tsip::response::GpsTime {
        time_of_week: 9.0,
        week: 2400,
        utc_offset: 18.0,
    });
    let mut buf = [0u8; tsip::MAX_FRAME_LEN];
    let n = time.encode(0, &mut buf).unwrap();
    assert_eq!(
        &buf[..n],
        &hex("10 41 41 10 10 00 00 09 60 41 90 00 00 10 03")[..]
    );
}

/// Fields after a list and several lists: the examples replay, and every frame mutated from
/// them decodes alike in both engines (the same values, the same refusals in the same words);
/// lists of other lengths encode alike.
#[test]
fn lists_snapshots_agree_with_the_interpreter() {
    replay::<lists_after::ListsAfter>("model/tests/fixtures/valid/lists_after.yaml");
    let p = fixture("model/tests/fixtures/valid/lists_after.yaml");
    let t = agree::agree::<lists_after::ListsAfter>(&p);
    assert!(t.accepted > 5 && t.refused > 100 && t.encoded > 10, "{t:?}");
    replay::<lists_length::ListsLength>("model/tests/fixtures/valid/lists_length.yaml");
    let p = fixture("model/tests/fixtures/valid/lists_length.yaml");
    let t = agree::agree::<lists_length::ListsLength>(&p);
    assert!(t.accepted > 3 && t.refused > 50 && t.encoded > 10, "{t:?}");
}

/// Captures of the lists fixtures' examples (and frames mutated from them) with noise and cut
/// frames between them, cut into chunks anywhere: the generated stream decoder finds what the
/// interpreter's finds, framing each message by its count fields (read after the lists
/// before them) or its length field.
#[test]
fn lists_snapshots_stream_as_the_interpreter_does() {
    fn run<P: Protocol>(file: &str) -> usize {
        let p = fixture(file);
        let mut frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
        for e in &p.examples {
            let d = e.message.direction;
            frames.extend(
                agree::mutations(&p, d, &e.wire)
                    .into_iter()
                    .filter(|w| busspec_model::interp::decode(&p, Some(d), None, w).is_ok()),
            );
        }
        let mut rng = agree::Rng(0x11575);
        let mut found = 0;
        for _ in 0..200 {
            let cap = random_capture(&frames, &mut rng, 20, 10);
            let cuts: Vec<usize> = (0..8).map(|_| 1 + rng.below(40) as usize).collect();
            let want = interp_seen(&p, &cap, &cuts);
            let got = generated_seen::<P>(&cap, &cuts);
            assert_eq!(got, want, "{file}: capture {cap:02X?}");
            found += got
                .iter()
                .filter(|s| !matches!(&*s.0, "-" | "?" | "!"))
                .count();
        }
        found
    }
    let found = run::<lists_after::ListsAfter>("model/tests/fixtures/valid/lists_after.yaml");
    assert!(found > 200 * 10, "only {found} frames found");
    let found = run::<lists_length::ListsLength>("model/tests/fixtures/valid/lists_length.yaml");
    assert!(found > 200 * 10, "only {found} frames found");
}

/// The packed fixture replays its examples; its examples and frames mutated from them (padding
/// bits set, elements out of range, other bytes) decode alike in both engines, and lists of
/// other lengths or wider elements are refused by both; its streams agree.
#[test]
fn packed_snapshot_agrees_with_the_interpreter() {
    let file = "model/tests/fixtures/valid/packed_channels.yaml";
    replay::<packed_channels::PackedChannels>(file);
    let p = fixture(file);
    let t = agree::agree::<packed_channels::PackedChannels>(&p);
    assert!(t.accepted > 3 && t.refused > 50, "{t:?}");
    // Each packed field of each example with lists of other lengths and elements at and past
    // the ends of their range and of their bits: encoded alike, or refused by both.
    let mut encoded = 0;
    for e in &p.examples {
        let decoded =
            busspec_model::interp::decode(&p, Some(e.message.direction), None, &e.wire).unwrap();
        let m = p.message(e.message);
        for f in m.fields.iter().filter(|f| f.packed.is_some()) {
            let pk = f.packed.unwrap();
            let mut lists: Vec<Vec<i64>> = vec![vec![0; pk.count - 1], vec![0; pk.count + 1]];
            // And for the elements of a fixed count (`trim`): past a signed type's ends, past
            // a range below 0, a float's bits past its range, 64 bits all set.
            let three = i64::from(3.0f32.to_bits());
            for v in [
                0,
                1,
                pk.max(),
                pk.max().saturating_add(1),
                -1,
                1999,
                2000,
                6,
                7,
                -901,
                0x800000,
                -0x800001,
                three,
                i64::MIN,
            ] {
                for k in [0, pk.count - 1] {
                    let mut l = vec![1; pk.count];
                    l[k] = v;
                    lists.push(l);
                }
            }
            for l in lists {
                let values: Vec<_> = decoded
                    .values
                    .iter()
                    .map(|v| {
                        let mut v = v.clone();
                        if v.name == f.name {
                            v.raw = busspec_model::interp::Raw::List(l.clone());
                        }
                        v
                    })
                    .collect();
                if agree::encode_alike::<packed_channels::PackedChannels>(&p, e.message, 0, &values)
                {
                    encoded += 1;
                }
            }
        }
    }
    assert!(encoded > 20, "{encoded}");
    // The padding bits of `levels` (bit 0 of its second byte) set: refused alike.
    let mut wire = p.examples[1].wire.clone();
    wire[5] |= 1;
    let n = wire.len();
    busspec_model::interp::reseal(&p, &mut wire[..n]);
    same_text(
        packed_channels::PackedChannels::decode_request(&wire).map(|_| ()),
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &wire).map(|_| ()),
    );
    let e = packed_channels::PackedChannels::decode_request(&wire).unwrap_err();
    assert_eq!(
        e.to_string(),
        "invalid value for levels.levels at offset 5: expected 0x00, found 0x01"
    );
    let mut rng = agree::Rng(0x9AC7);
    let frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    for _ in 0..100 {
        let cap = random_capture(&frames, &mut rng, 12, 5);
        let cuts: Vec<usize> = (0..6).map(|_| 1 + rng.below(20) as usize).collect();
        assert_eq!(
            generated_seen::<packed_channels::PackedChannels>(&cap, &cuts),
            interp_seen(&p, &cap, &cuts)
        );
    }
}

/// Records of a fixed count (UBX-shaped fixed blocks): the examples replay; frames mutated
/// from them decode alike in both engines; a frame one record short is refused by both in the
/// same words; lists of records of another count are refused by both encoders; streams agree.
#[test]
fn fixed_records_snapshot_agrees_with_the_interpreter() {
    use ubx_fixed_blocks::{Response, UbxFixedBlocks};
    let file = "model/tests/fixtures/valid/ubx_fixed_blocks.yaml";
    replay::<UbxFixedBlocks>(file);
    let p = fixture(file);
    let t = agree::agree::<UbxFixedBlocks>(&p);
    assert!(t.accepted >= 4 && t.refused > 50, "{t:?}");
    // The three satellites decoded, then the flags after them.
    match Response::decode(&p.examples[1].wire).map(|d| d.message) {
        Ok(Response::SatBlocks(s)) => {
            assert_eq!(s.blocks.len(), 3);
            assert_eq!(s.flags, 3);
            let _: &busspec_runtime::Repeated<ubx_fixed_blocks::SatBlocksBlocks, 3> = &s.blocks;
        }
        other => panic!("{other:?}"),
    }
    // One record short (its length field and checksum made to agree): refused alike.
    let mut short = p.examples[1].wire.clone();
    short.drain(10..16);
    short[4] -= 6;
    let n = short.len();
    busspec_model::interp::reseal(&p, &mut short[..n]);
    let g = Response::decode(&short).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "sat_blocks.blocks at offset 10: 3 elements, expected 2 by the frame's length"
    );
    same_text(
        g,
        busspec_model::interp::decode(&p, Some(Direction::Response), None, &short).map(|_| ()),
    );
    // Two, three and four records: only three encode, in both engines.
    let e = &p.examples[1];
    let decoded =
        busspec_model::interp::decode(&p, Some(Direction::Response), None, &e.wire).unwrap();
    let mut encoded = 0;
    for n in [0usize, 2, 3, 4] {
        let values: Vec<_> = decoded
            .values
            .iter()
            .map(|v| {
                let mut v = v.clone();
                if let busspec_model::interp::Raw::Records(r) = &mut v.raw {
                    let one = r[0].clone();
                    r.resize(n, one);
                }
                v
            })
            .collect();
        if agree::encode_alike::<UbxFixedBlocks>(&p, e.message, 0, &values) {
            encoded += 1;
        }
        let i = busspec_model::interp::encode(&p, e.message, 0, &values);
        match n {
            3 => assert!(i.is_ok()),
            _ => assert_eq!(
                i.unwrap_err().to_string(),
                format!("blocks takes 3..=3 elements, got {n}")
            ),
        }
    }
    assert_eq!(encoded, 1);
    let mut rng = agree::Rng(0xF1ED);
    let frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    for _ in 0..100 {
        let cap = random_capture(&frames, &mut rng, 12, 5);
        let cuts: Vec<usize> = (0..6).map(|_| 1 + rng.below(20) as usize).collect();
        assert_eq!(
            generated_seen::<UbxFixedBlocks>(&cap, &cuts),
            interp_seen(&p, &cap, &cuts)
        );
    }
}

/// Lists of floats and 64-bit integers counted by a field: the examples replay (floats with
/// their words swapped, u64 above `i64::MAX`); frames mutated from them decode alike; an
/// element outside its float range is refused by both in the same words; streams agree.
#[test]
fn float_lists_snapshot_agrees_with_the_interpreter() {
    use float_lists::{FloatLists, Response};
    let file = "model/tests/fixtures/valid/float_lists.yaml";
    replay::<FloatLists>(file);
    let p = fixture(file);
    let t = agree::agree::<FloatLists>(&p);
    assert!(t.accepted >= 6 && t.refused > 50, "{t:?}");
    match Response::decode(&p.examples[1].wire).map(|d| d.message) {
        Ok(Response::Floats(f)) => assert_eq!(f.values.as_slice(), &[230.1f32, -0.5, 49.98]),
        other => panic!("{other:?}"),
    }
    match Response::decode(&p.examples[3].wire).map(|d| d.message) {
        Ok(Response::Counters(c)) => {
            assert_eq!(
                c.totals.as_slice(),
                &[987_654_321_987_654_321u64, 1_234_567_890_123]
            );
            assert_eq!(c.drifts.as_slice(), &[-9_000_000_000i64, 42]);
        }
        other => panic!("{other:?}"),
    }
    // The second float made 2000.0 (its words swapped): outside its range, alike.
    let mut wire = p.examples[1].wire.clone();
    let b = 2000.0f32.to_be_bytes();
    wire[7..11].copy_from_slice(&[b[2], b[3], b[0], b[1]]);
    let n = wire.len();
    busspec_model::interp::reseal(&p, &mut wire[..n]);
    let g = Response::decode(&wire).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "floats.values at offset 7 is 2000.0, outside its range -1000.0..=1000.0"
    );
    same_text(
        g,
        busspec_model::interp::decode(&p, Some(Direction::Response), None, &wire).map(|_| ()),
    );
    let mut rng = agree::Rng(0x64F3);
    let frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    for _ in 0..100 {
        let cap = random_capture(&frames, &mut rng, 12, 5);
        let cuts: Vec<usize> = (0..6).map(|_| 1 + rng.below(20) as usize).collect();
        assert_eq!(
            generated_seen::<FloatLists>(&cap, &cuts),
            interp_seen(&p, &cap, &cuts)
        );
    }
}

/// A list whose unit is scaled holds the unit's type (`rt::Repeated<Millivolts, 6>`), its
/// elements lent to `visit` by their raw values, as the interpreter holds them.
#[test]
fn a_scaled_list_holds_its_units_type() {
    let p = fixture("model/tests/fixtures/valid/lists_length.yaml");
    let mut seen = 0;
    for e in p
        .examples
        .iter()
        .filter(|e| e.message.direction == Direction::Request)
    {
        let d = lists_length::Request::decode(&e.wire).unwrap();
        if let lists_length::Request::Log(lists_length::request::Log { samples, .. }) = d.message {
            let typed: &busspec_runtime::Repeated<lists_length::Millivolts, 6> = &samples;
            let i = busspec_model::interp::decode_as(&p, e.message, &e.wire).unwrap();
            let raws: Vec<i64> = typed.iter().map(|m| i64::from(m.raw())).collect();
            assert_eq!(
                i.get("samples"),
                Some(&busspec_model::interp::Raw::List(raws))
            );
            seen += 1;
        }
    }
    assert!(seen > 0);
}

/// Repeated records: the examples replay; every frame mutated from them decodes alike in both
/// engines (records, refusals of a record's field out of range at its offset) and random
/// messages encode alike; captures stream alike.
#[test]
fn records_snapshot_agrees_with_the_interpreter() {
    let file = "model/tests/fixtures/valid/records.yaml";
    replay::<records::Records>(file);
    let p = fixture(file);
    let t = agree::agree::<records::Records>(&p);
    assert!(t.accepted > 5 && t.refused > 50 && t.encoded > 10, "{t:?}");
    // A record is a struct of typed fields inside `rt::Repeated`.
    let d = records::Request::decode(&p.examples[0].wire).unwrap();
    let records::Request::SyncWrite(records::request::SyncWrite { blocks, flags }) = d.message
    else {
        panic!("{d:?}");
    };
    assert_eq!(flags, 7);
    assert_eq!(blocks.len(), 2);
    assert_eq!(blocks[1].id, 5);
    assert_eq!(blocks[1].position, records::TenthDegree(0x3FF));
    assert_eq!(blocks[1].mode, records::DriveMode::Position);
    let mut buf = [0u8; records::MAX_FRAME_LEN];
    let n = d.message.encode(1, &mut buf).unwrap();
    assert_eq!(&buf[..n], &p.examples[0].wire[..]);
    // A record's field out of its range is refused by encode, named as the interpreter does.
    let mut items = blocks.to_vec();
    items[0].id = 0;
    let bad = busspec_runtime::Repeated::from_slice(&items).unwrap();
    let e = records::Request::SyncWrite(records::request::SyncWrite { blocks: bad, flags })
        .encode(1, &mut buf)
        .unwrap_err();
    assert!(e.to_string().contains("blocks.id"), "{e}");
}

/// Records whose width a field gives: the examples replay; frames mutated from them (the
/// width field among the bytes changed) decode alike in both engines, random messages encode
/// alike; a record's last field takes as many bytes as the frame says.
#[test]
fn records_sized_snapshot_agrees_with_the_interpreter() {
    let file = "model/tests/fixtures/valid/records_sized.yaml";
    replay::<records_sized::RecordsSized>(file);
    let p = fixture(file);
    let t = agree::agree::<records_sized::RecordsSized>(&p);
    // Random widths are mostly outside 1..=4: most random messages are refused by both.
    assert!(t.accepted > 50 && t.refused > 200 && t.encoded > 5, "{t:?}");
    let d = records_sized::Request::decode(&p.examples[1].wire).unwrap();
    let records_sized::Request::SyncWrite(records_sized::request::SyncWrite {
        blocks,
        data_length,
        ..
    }) = d.message
    else {
        panic!("{d:?}");
    };
    assert_eq!((data_length, blocks.len(), blocks[2].data), (1, 3, 255));
    let mut buf = [0u8; records_sized::MAX_FRAME_LEN];
    let n = d.message.encode(1, &mut buf).unwrap();
    assert_eq!(&buf[..n], &p.examples[1].wire[..]);
    // 256 does not fit the one byte data_length gives; a width of 5 is no u32's.
    let mut items = blocks.to_vec();
    items[0].data = 256;
    let bad = busspec_runtime::Repeated::from_slice(&items).unwrap();
    let m = records_sized::Request::SyncWrite(records_sized::request::SyncWrite {
        start_address: 64,
        data_length: 1,
        blocks: bad,
    });
    let e = m.encode(1, &mut buf).unwrap_err();
    assert!(e.to_string().contains("blocks.data"), "{e}");
    let m = records_sized::Request::SyncWrite(records_sized::request::SyncWrite {
        start_address: 64,
        data_length: 5,
        blocks,
    });
    let e = m.encode(1, &mut buf).unwrap_err();
    assert!(e.to_string().contains("data_length"), "{e}");
}

#[test]
fn records_snapshot_streams_as_the_interpreter_does() {
    let file = "model/tests/fixtures/valid/records.yaml";
    let p = fixture(file);
    let mut frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    for e in &p.examples {
        let d = e.message.direction;
        frames.extend(
            agree::mutations(&p, d, &e.wire)
                .into_iter()
                .filter(|w| busspec_model::interp::decode(&p, Some(d), None, w).is_ok()),
        );
    }
    let mut rng = agree::Rng(0x2EC0);
    let mut found = 0;
    for _ in 0..200 {
        let cap = random_capture(&frames, &mut rng, 20, 10);
        let cuts: Vec<usize> = (0..8).map(|_| 1 + rng.below(40) as usize).collect();
        let want = interp_seen(&p, &cap, &cuts);
        let got = generated_seen::<records::Records>(&cap, &cuts);
        assert_eq!(got, want, "{file}: capture {cap:02X?}");
        found += got
            .iter()
            .filter(|s| !matches!(&*s.0, "-" | "?" | "!"))
            .count();
    }
    assert!(found > 200 * 10, "only {found} frames found");
}

/// `parts` frames drawn from `frames`, one in `one_in` led by noise (one to five random bytes)
/// and one in `one_in` by a frame cut short.
fn random_capture(frames: &[Vec<u8>], rng: &mut agree::Rng, parts: usize, one_in: u64) -> Vec<u8> {
    let mut cap = Vec::new();
    for _ in 0..parts {
        let f = &frames[rng.below(frames.len() as u64) as usize];
        match rng.below(one_in) {
            0 => cap.extend((0..1 + rng.below(5)).map(|_| rng.below(256) as u8)),
            1 => cap.extend_from_slice(&f[..1 + rng.below(f.len() as u64 - 1) as usize]),
            _ => {}
        }
        cap.extend_from_slice(f);
    }
    cap
}

/// XBee frames (byte escaping without an end byte: the length field frames them) through a
/// decoder of one direction, pushed a byte at a time: the generated one waits for a response
/// whose length field says it is as long as a request would be, as the interpreter's does.
/// (It dropped such a response's start byte while the request's length waited.)
#[test]
fn xbee_responses_alone_stream_as_the_interpreter_does() {
    use busspec_runtime::stream::{Direction as D, Event, StreamDecoder};
    let p = fixture("model/tests/fixtures/valid/xbee_api2.yaml");
    let mut cap = vec![0x11];
    for e in &p.examples {
        cap.extend_from_slice(&e.wire);
    }
    for (d, md) in [
        (D::Response, Direction::Response),
        (D::Request, Direction::Request),
    ] {
        let mut g = StreamDecoder::<xbee_api2::XbeeApi2>::new(Some(d));
        let mut got = Vec::new();
        for b in &cap {
            g.push(std::slice::from_ref(b));
            while let Some(e) = g.poll() {
                got.push((e.offset(), matches!(e, Event::Skipped { .. })));
            }
        }
        while let Some(e) = g.finish() {
            got.push((e.offset(), matches!(e, Event::Skipped { .. })));
        }
        let mut i = busspec_model::stream::StreamDecoder::new(&p, Some(md));
        let mut want = Vec::new();
        let mut events = Vec::new();
        for b in &cap {
            events.extend(i.push(std::slice::from_ref(b)));
        }
        events.extend(i.flush());
        for e in events {
            let skipped = matches!(e, busspec_model::stream::Event::Skipped { .. });
            want.push((e.offset(), skipped));
        }
        // Noise runs may be reported in pieces by one and whole by the other: compare frames.
        got.retain(|e| !e.1);
        want.retain(|e| !e.1);
        let frames = p
            .examples
            .iter()
            .filter(|e| e.message.direction == md)
            .count();
        assert_eq!(got, want, "{md:?}");
        assert_eq!(got.len(), frames, "{md:?}: {got:?}");
    }
}

/// A per-byte transform of the payload (DL/T 645's +33H, `framing.transform`): the generated
/// code reads go645's frames to the real values (data identifier 00 01 00 00 as 0x00010000)
/// and writes them back byte for byte, the sum over the bytes as they travel; a frame whose
/// payload travelled untransformed decodes to other values in both engines alike, and one
/// with a payload byte changed and the sum left is refused as the interpreter refuses it.
#[test]
fn transform_snapshot_agrees_with_the_interpreter() {
    use dlt645::{Dlt645, Request, Response};
    let file = "model/tests/fixtures/valid/dlt645.yaml";
    let p = fixture(file);
    assert_eq!(
        <Dlt645 as Framing>::TRANSFORM,
        Some(busspec_runtime::Transform::Add(0x33))
    );
    let wire = busspec_model::interp::parse_hex(
        "68 01 00 00 00 00 00 68 91 08 33 33 34 33 59 B3 55 44 DC 16",
    )
    .unwrap();
    let d = Response::decode(&wire).unwrap();
    assert_eq!(
        d.message,
        Response::DataReply(dlt645::response::DataReply {
            address_low: 1,
            address_high: 0,
            data_id: 0x0001_0000,
            value: 11_228_026,
        })
    );
    let mut buf = [0u8; dlt645::MAX_FRAME_LEN];
    let n = d.message.encode(0, &mut buf).unwrap();
    assert_eq!(&buf[..n], [&[0xFE; 4][..], &wire].concat());
    let n = Request::ReadData(dlt645::request::ReadData {
        address_low: 1,
        address_high: 0,
        data_id: 0x0001_0000,
    })
    .encode(0, &mut buf)
    .unwrap();
    assert_eq!(
        &buf[4..n],
        busspec_model::interp::parse_hex("68 01 00 00 00 00 00 68 11 04 33 33 34 33 B3 16")
            .unwrap()
    );
    // A payload byte changed, the sum left: refused in the same words.
    let mut bad = wire.clone();
    bad[12] ^= 1;
    same_text(
        Response::decode(&bad).map(|_| ()),
        busspec_model::interp::decode(&p, Some(Direction::Response), None, &bad).map(|_| ()),
    );
    // The value's digits untransformed: 0x59 - 0x33 = 0x26; a byte that undoes to a digit
    // above 9 is refused at the field in both engines.
    let mut not_bcd = wire.clone();
    not_bcd[14] = 0x33 + 0x0A;
    busspec_model::interp::reseal(&p, &mut not_bcd);
    let g = Response::decode(&not_bcd).map(|_| ());
    assert!(g.is_err());
    same_text(
        g,
        busspec_model::interp::decode(&p, Some(Direction::Response), None, &not_bcd).map(|_| ()),
    );
}

/// A preamble of wake-up bytes (DL/T 645, `framing.preamble`): the examples replay (encode
/// sends four `FE`, decode takes the frames printed with four or none); a frame after 0 to 4
/// `FE` decodes in both engines, after 5 both refuse it in the same words; both agree on
/// frames mutated from the examples and on captures with runs of `FE` before frames, however
/// they are cut; the runtime's fast path is its full rule at every head of such captures.
#[test]
fn preamble_snapshot_agrees_with_the_interpreter() {
    use busspec_runtime::stream::StreamDecoder;
    use dlt645::{Dlt645, Request};
    let file = "model/tests/fixtures/valid/dlt645.yaml";
    replay::<Dlt645>(file);
    let p = fixture(file);
    let frame = [
        0x68, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0x68, 0x13, 0x00, 0xDF, 0x16,
    ];
    for k in 0..=6 {
        let mut w = vec![0xFE; k];
        w.extend_from_slice(&frame);
        let g = Request::decode(&w).map(|d| d.message.name());
        let i = busspec_model::interp::decode(&p, None, None, &w);
        if k <= 4 {
            assert_eq!(g, Ok("read_address"), "{k}");
            assert_eq!(p.message(i.unwrap().message).name, "read_address");
        } else {
            same_text(g.map(|_| ()), i.map(|_| ()));
        }
    }
    let mut buf = [0u8; dlt645::MAX_FRAME_LEN];
    assert_eq!(dlt645::MAX_FRAME_LEN, 4 + 22);
    let n = Request::ReadAddress(dlt645::request::ReadAddress {
        address_low: 0xAAAAAA,
        address_high: 0xAAAAAA,
    })
    .encode(0, &mut buf)
    .unwrap();
    assert_eq!(&buf[..n], [&[0xFE; 4][..], &frame].concat());
    assert!(Request::ReadAddress(dlt645::request::ReadAddress {
        address_low: 1,
        address_high: 0,
    })
    .encode(0, &mut buf[..3])
    .is_err());
    let t = agree::agree::<Dlt645>(&p);
    assert!(t.accepted >= 5 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<Dlt645>(&p, 0xFEFE, "read_data");
    assert!(found > 30, "only {found} read_data frames found");
    // The fast path, at every head of captures with preambles, noise and cut frames.
    let frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    let mut after = StreamDecoder::<Dlt645>::new(None);
    assert!(after.feed(&frames[0]).count() > 0);
    // Wake-up bytes held, for the frame that may follow.
    let mut woken = StreamDecoder::<Dlt645>::new(None);
    assert_eq!(woken.feed(&[0x00, 0xFE, 0xFE]).count(), 0);
    let states = [StreamDecoder::<Dlt645>::new(None), after, woken];
    let cap = <Dlt645 as Protocol>::MAX_FRAME_LEN;
    let mut rng = agree::Rng(0xFE);
    let mut decided = 0;
    for _ in 0..100 {
        let mut bytes = Vec::new();
        for _ in 0..12 {
            let f = &frames[rng.below(frames.len() as u64) as usize];
            match rng.below(6) {
                0 => bytes.extend((0..1 + rng.below(3)).map(|_| rng.below(256) as u8)),
                1 => bytes.extend_from_slice(&f[..f.len() - 1]),
                2 => bytes.extend(std::iter::repeat(0xFE).take(rng.below(7) as usize)),
                _ => bytes.extend_from_slice(f),
            }
        }
        for at in 0..bytes.len() {
            let mut w: Vec<u8> = bytes[at..].iter().copied().take(cap).collect();
            w.resize(cap, 0);
            for (i, d) in states.iter().enumerate() {
                if let Some([fast, full]) = d.fast_and_full(&w, (i % 2) as u64) {
                    assert_eq!(fast, full, "{w:02X?} from state {i}");
                    decided += 1;
                }
            }
        }
    }
    assert!(decided > 1000, "{decided} decided");
}

/// Optional fields (`present:`): the examples replay; frames of every presence (each status
/// byte's bits, each event kind) and of every length from too short to too long, with the
/// length field made to agree and the checksum resealed, decode alike in both engines (the
/// same values, a length the fields present do not make refused in the same words); every
/// presence given or left out encodes alike, a value given where its condition does not hold
/// or missing where it does refused by both in the same words; captures stream alike.
#[test]
fn optional_fields_snapshot_agrees_with_the_interpreter() {
    use busspec_model::interp::{Raw, Value};
    use optional_sensor::{OptionalSensor, Response};
    use std::borrow::Cow;
    let file = "model/tests/fixtures/valid/optional_sensor.yaml";
    replay::<OptionalSensor>(file);
    let p = fixture(file);
    let t = agree::agree::<OptionalSensor>(&p);
    assert!(t.accepted >= 6 && t.refused > 100, "{t:?}");
    // Every length of each code's frames, for each presence.
    let mut rng = agree::Rng(0x0971);
    let (mut accepted, mut wrong_length) = (0, 0);
    for (code, conditions) in [
        (0x81u8, [0u8, 1, 2, 3, 0xFC, 0xFF]),
        (0x82, [0, 1, 2, 3, 4, 0xFF]),
    ] {
        for c in conditions {
            for len in 5..=16usize {
                let mut w = vec![0xA5, 0x01, 0, code];
                if len > 5 {
                    w.push(c);
                }
                // Small bytes: a humidity within its range.
                while w.len() < len - 1 {
                    w.push(rng.below(4) as u8);
                }
                w.push(0);
                w.truncate(len);
                agree::fix_length(&p, Direction::Response, &mut w);
                agree::reseal(&p, &mut w);
                if agree::check::<OptionalSensor>(&p, Direction::Response, None, &w) {
                    accepted += 1;
                } else if Response::decode(&w)
                    .is_err_and(|e| e.to_string().starts_with("wrong length"))
                {
                    wrong_length += 1;
                }
            }
        }
    }
    assert!(
        accepted == 12 && wrong_length > 40,
        "{accepted} / {wrong_length}"
    );
    // Typed values: absent is `None`.
    let d = Response::decode(&p.examples[1].wire).unwrap().message;
    assert!(
        matches!(
            d,
            Response::Reading(optional_sensor::response::Reading {
                humidity: None,
                pressure: None,
                ..
            })
        ),
        "{d:?}"
    );
    let d = Response::decode(&p.examples[3].wire).unwrap().message;
    assert!(
        matches!(d, Response::Reading(optional_sensor::response::Reading { humidity: Some(h), pressure: Some(101000), .. }) if h.raw() == 450),
        "{d:?}"
    );
    // Every presence given or not, for each condition's value: both encode alike, and refuse
    // a presence their condition does not allow in the same words.
    let (mut encoded, mut refused) = (0, 0);
    let value = |name: &'static str, v: i64| Value {
        name: Cow::Borrowed(name),
        raw: Raw::Int(v),
    };
    let r = p.find("reading").unwrap();
    for status in [0i64, 1, 2, 3, 0x80, 0xFF] {
        for given in 0..4 {
            let mut values = vec![value("status", status), value("temperature", -100)];
            if given & 1 != 0 {
                values.push(value("humidity", 999));
            }
            if given & 2 != 0 {
                values.push(value("pressure", 0xFFFF_FFFF));
            }
            if agree::encode_alike::<OptionalSensor>(&p, r, 1, &values) {
                encoded += 1;
            } else {
                refused += 1;
                same_encode_words(&p, "reading", &values);
            }
        }
    }
    let e = p.find("event").unwrap();
    for kind in [0i64, 1, 2, 3, 255] {
        for given in [false, true] {
            let mut values = vec![value("kind", kind)];
            if given {
                values.push(value("detail", 7));
            }
            if agree::encode_alike::<OptionalSensor>(&p, e, 1, &values) {
                encoded += 1;
            } else {
                refused += 1;
                same_encode_words(&p, "event", &values);
            }
        }
    }
    assert_eq!(
        (encoded, refused),
        (6 + 5, 6 * 3 + 5),
        "every presence encodes once"
    );
    // A value out of its range is refused where it is given.
    let over = [
        value("status", 1),
        value("temperature", 0),
        value("humidity", 1001),
    ];
    assert!(!agree::encode_alike::<OptionalSensor>(&p, r, 1, &over));
    let found = examples_stream_alike::<OptionalSensor>(&p, 0x0971, "reading");
    assert!(found > 100, "only {found} reading frames found");
}

/// Counted text (`type: ascii` with `repeat`) followed by fields: the examples replay; frames
/// of every count from 0 past `max`, their characters any bytes, with the checksum resealed,
/// decode alike in both engines (the same text, the same refusals); text of every length up
/// to past `max`, and a value that is not text, encode alike; captures stream alike.
#[test]
fn counted_text_snapshot_agrees_with_the_interpreter() {
    use busspec_model::interp::{Raw, Value};
    use std::borrow::Cow;
    use text_counted::{Response, TextCounted};
    let file = "model/tests/fixtures/valid/text_counted.yaml";
    replay::<TextCounted>(file);
    let p = fixture(file);
    let t = agree::agree::<TextCounted>(&p);
    assert!(t.accepted >= 4 && t.refused > 10, "{t:?}");
    let mut rng = agree::Rng(0x7e57);
    let mut accepted = 0;
    for count in 0..=20u8 {
        for _ in 0..8 {
            let mut w = vec![0x7E, 0x03, 0x21, count];
            for _ in 0..count {
                w.push(rng.below(256) as u8);
            }
            w.extend_from_slice(&[0, 0, 0x30, 0x39, 7, 0]);
            agree::reseal(&p, &mut w);
            if agree::check::<TextCounted>(&p, Direction::Response, None, &w) {
                accepted += 1;
            }
        }
    }
    // Counts 1..=16 of 21 fit (min 1, max 16, payload at most 24 bytes).
    assert_eq!(accepted, 16 * 8);
    let d = Response::decode(&p.examples[3].wire).unwrap().message;
    let Response::DeviceInfo(text_counted::response::DeviceInfo { name, serial, .. }) = d else {
        panic!("{d:?}")
    };
    assert_eq!((name.as_slice(), serial), (&b"ACME1"[..], 123_456));
    let r = p.find("set_name").unwrap();
    let (mut encoded, mut refused) = (0, 0);
    for len in 0..=18usize {
        let text: Vec<u8> = (0..len).map(|k| b'a' + k as u8).collect();
        let values = [
            Value {
                name: Cow::Borrowed("name"),
                raw: Raw::Text(text),
            },
            Value {
                name: Cow::Borrowed("channel"),
                raw: Raw::Int(3),
            },
        ];
        if agree::encode_alike::<TextCounted>(&p, r, 3, &values) {
            encoded += 1;
        } else {
            refused += 1;
        }
    }
    assert_eq!((encoded, refused), (17, 2));
    let not_text = [
        Value {
            name: Cow::Borrowed("name"),
            raw: Raw::List(vec![65, 66]),
        },
        Value {
            name: Cow::Borrowed("channel"),
            raw: Raw::Int(3),
        },
    ];
    assert!(!agree::encode_alike::<TextCounted>(&p, r, 3, &not_text));
    let found = examples_stream_alike::<TextCounted>(&p, 0x7e57, "device_info");
    assert!(found > 50, "only {found} device_info frames found");
}

/// Text up to a terminator (`repeat: {until: 0x00}`): the examples replay; device information
/// frames whose name is 0 to 30 random non-NUL bytes, with and without the NUL after them,
/// length and checksum resealed, decode alike in both engines, and exactly those with the NUL
/// and 1..=24 characters decode; text of every length to past `max` encodes alike, and text
/// holding its terminator is refused by both in the same words; captures stream alike.
#[test]
fn terminated_text_snapshot_agrees_with_the_interpreter() {
    use busspec_model::interp::{Raw, Value};
    use std::borrow::Cow;
    use text_terminated::{Response, TextTerminated};
    let file = "model/tests/fixtures/valid/text_terminated.yaml";
    replay::<TextTerminated>(file);
    let p = fixture(file);
    let t = agree::agree::<TextTerminated>(&p);
    assert!(t.accepted >= 5 && t.refused > 10, "{t:?}");
    let mut rng = agree::Rng(0x0029);
    let mut accepted = 0;
    for len in 0..=30usize {
        for nul in [true, false] {
            let mut w = vec![0xC8, 0, 0x29];
            for _ in 0..len {
                w.push(1 + rng.below(255) as u8);
            }
            if nul {
                w.push(0);
            }
            w.extend_from_slice(&[0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 3, 4, 5, 0]);
            w[1] = (w.len() - 2) as u8;
            agree::reseal(&p, &mut w);
            if agree::check::<TextTerminated>(&p, Direction::Response, None, &w) {
                accepted += 1;
            }
        }
    }
    // With the NUL, 1..=24 characters fit (min 1, max 24; the payload holds at most 40).
    assert_eq!(accepted, 24);
    let d = Response::decode(&p.examples[3].wire).unwrap().message;
    let Response::DeviceInfo(text_terminated::response::DeviceInfo { name, serial, .. }) = d else {
        panic!("{d:?}")
    };
    assert_eq!(
        (name.as_slice(), serial),
        (&b"TBS Tracer"[..], 1_414_745_936)
    );
    let r = p.find("set_name").unwrap();
    let text = |t: &[u8]| {
        [
            Value {
                name: Cow::Borrowed("name"),
                raw: Raw::Text(t.to_vec()),
            },
            Value {
                name: Cow::Borrowed("channel"),
                raw: Raw::Int(3),
            },
        ]
    };
    let (mut encoded, mut refused) = (0, 0);
    for len in 0..=18usize {
        let t: Vec<u8> = (0..len).map(|k| b'a' + k as u8).collect();
        if agree::encode_alike::<TextTerminated>(&p, r, 0, &text(&t)) {
            encoded += 1;
        } else {
            refused += 1;
        }
    }
    assert_eq!((encoded, refused), (17, 2));
    // A NUL among the characters would end the text early: both refuse, in the same words.
    let held = text(b"ab\0cd");
    assert!(!agree::encode_alike::<TextTerminated>(&p, r, 0, &held));
    let i = busspec_model::interp::encode(&p, r, 0, &held).unwrap_err();
    let mut chars = busspec_runtime::Repeated::<u8, 16>::new();
    for &b in b"ab\0cd" {
        chars.push(b).unwrap();
    }
    let m = text_terminated::Request::SetName(text_terminated::request::SetName {
        name: chars,
        channel: 3,
    });
    let mut buf = [0u8; text_terminated::MAX_FRAME_LEN];
    let g = m.encode(0, &mut buf).unwrap_err();
    assert_eq!(g.to_string(), i.to_string());
    assert_eq!(
        g.to_string(),
        "name holds its terminator 0x00 (character 2), which would end it there"
    );
    let found = examples_stream_alike::<TextTerminated>(&p, 0x0029, "parameter");
    assert!(found > 50, "only {found} parameter frames found");
}

/// Both engines refuse to encode `values` as response `name` of `p` in the same words.
fn same_encode_words(p: &ir::Protocol, name: &str, values: &[busspec_model::interp::Value]) {
    use busspec_model::interp::Raw;
    use busspec_runtime::FieldValue;
    let r = p.find(name).unwrap();
    let i = busspec_model::interp::encode(p, r, 1, values).unwrap_err();
    let m = <optional_sensor::Response as Message>::from_fields(name, |n| {
        values.iter().find(|v| v.name == n).map(|v| match v.raw {
            Raw::Int(x) => FieldValue::Int(x),
            _ => unreachable!(),
        })
    })
    .unwrap();
    let mut buf = [0u8; optional_sensor::MAX_FRAME_LEN];
    let g = m.encode(1, &mut buf).unwrap_err();
    assert_eq!(g.to_string(), i.to_string(), "{values:?}");
}

/// A length field whose width the start byte chooses (VESC, `framing.length.long`): the
/// examples replay (pyvesc's frames, short and long, decoded and encoded back byte for byte);
/// the encoder sends 255 payload bytes short and 256 long, as the interpreter does; a long
/// frame whose length fits the short field is refused by both in the same words, and errors
/// of a short frame are located on its bytes alike; both agree on frames mutated from the
/// examples and on captures of short and long frames however they are cut.
#[test]
fn long_length_snapshot_agrees_with_the_interpreter() {
    use busspec_model::interp::{self, Raw, Value};
    use vesc::{Request, Vesc};
    let file = "model/tests/fixtures/valid/vesc.yaml";
    replay::<Vesc>(file);
    let p = fixture(file);
    assert_eq!(
        <Vesc as Framing>::LONG.map(|l| (l.start, l.short_width, l.width)),
        Some((0x03, 1, 2))
    );
    let write = p.find("write_new_app_data").unwrap();
    let mut buf = [0u8; vesc::MAX_FRAME_LEN];
    for (n, start, len) in [
        (250usize, 0x02, 260usize),
        (251, 0x03, 262),
        (512, 0x03, 523),
    ] {
        let data: Vec<u8> = (0..n).map(|i| i as u8).collect();
        let g = Request::WriteNewAppData(vesc::request::WriteNewAppData {
            offset: 7,
            data: busspec_runtime::Repeated::from_slice(&data).unwrap(),
        })
        .encode(0, &mut buf)
        .unwrap();
        let values = [
            Value {
                name: "offset".into(),
                raw: Raw::Int(7),
            },
            Value {
                name: "data".into(),
                raw: Raw::List(data.iter().map(|&b| i64::from(b)).collect()),
            },
        ];
        let i = interp::encode(&p, write, 0, &values).unwrap();
        assert_eq!(&buf[..g], &i[..], "{n}");
        assert_eq!((i[0], i.len()), (start, len), "{n}");
        assert_eq!(
            Request::decode(&i).unwrap().message.name(),
            "write_new_app_data"
        );
    }
    // The set_rpm frame pyvesc sends, sent long: refused at the length field by both.
    let long = interp::parse_hex("03 00 05 08 FF FF EE 6C 18 7A 03").unwrap();
    let g = Request::decode(&long).map(|_| ());
    assert_eq!(
        g.map_err(|e| e.to_string()),
        Err("long length field at offset 1 says 5: lengths up to 255 take the short form".into())
    );
    same_text(g, interp::decode(&p, None, None, &long).map(|_| ()));
    // A short frame's errors on its own bytes: its checksum at offset 7, not 8.
    let mut bad = interp::parse_hex("02 05 08 FF FF EE 6C 18 7A 03").unwrap();
    bad[7] ^= 1;
    let g = Request::decode(&bad).map(|_| ());
    assert!(
        g.as_ref().unwrap_err().to_string().contains("offset 7"),
        "{g:?}"
    );
    same_text(g, interp::decode(&p, None, None, &bad).map(|_| ()));
    // A fixed message sent one byte long, the length field agreeing: the lengths as sent.
    let mut wrong = interp::parse_hex("02 06 08 FF FF EE 6C 00 18 7A 03").unwrap();
    interp::reseal(&p, &mut wrong);
    let g = Request::decode(&wrong).map(|_| ());
    assert!(
        g.as_ref()
            .unwrap_err()
            .to_string()
            .contains("expected 10 bytes, found 11"),
        "{g:?}"
    );
    same_text(
        g,
        interp::decode(&p, Some(Direction::Request), None, &wrong).map(|_| ()),
    );
    let t = agree::agree::<Vesc>(&p);
    assert!(t.accepted >= 14 && t.refused > 1000, "{t:?}");
    let found = examples_stream_alike::<Vesc>(&p, 0x5E5C, "write_new_app_data");
    assert!(found > 100, "{found}");
}

/// A short form of the frame (M-Bus, `framing.forms`): the examples replay (short frames,
/// long frames and `E5`, decoded and encoded back byte for byte); a frame with an empty payload
/// is sent short and one with a payload long by both engines; a long frame with an empty
/// payload is refused by both in the same words, a short frame's errors are located on its own
/// bytes alike, and a short frame of another length is refused as it travelled; both agree on
/// frames mutated from the examples and on captures of every form however they are cut.
#[test]
fn short_form_snapshot_agrees_with_the_interpreter() {
    use busspec_model::interp;
    use mbus::{Mbus, Request, Response};
    let file = "model/tests/fixtures/valid/mbus.yaml";
    replay::<Mbus>(file);
    let p = fixture(file);
    assert_eq!(
        (mbus::FORM.start, mbus::FORM.fill, mbus::FORM.laid_len),
        (0x10, &[0x02u8, 0x02, 0x68][..], 8)
    );
    let mut buf = [0u8; mbus::MAX_FRAME_LEN];
    let n = Request::ReqUd2(mbus::request::ReqUd2)
        .encode(0x01, &mut buf)
        .unwrap();
    assert_eq!(&buf[..n], &[0x10, 0x5B, 0x01, 0x5C, 0x16]);
    let n = Request::SndUdReset(mbus::request::SndUdReset)
        .encode(0x01, &mut buf)
        .unwrap();
    assert_eq!(
        &buf[..n],
        &[0x68, 0x03, 0x03, 0x68, 0x53, 0x01, 0x50, 0xA4, 0x16]
    );
    // The single character whatever the address, as the interpreter writes it (0xFC is no
    // device's).
    for a in [0x01, 0xFC] {
        let n = Response::Ack(mbus::response::Ack)
            .encode(a, &mut buf)
            .unwrap();
        assert_eq!(&buf[..n], &[0xE5]);
        let i = busspec_model::interp::encode(&p, p.find("ack").unwrap(), a, &[]).unwrap();
        assert_eq!(i, [0xE5]);
    }
    for (hex, words) in [
        // SND_NKE sent long: refused at the length field by both.
        (
            "68 02 02 68 40 01 41 16",
            "long length field at offset 1 says 2: lengths up to 2 take the short form",
        ),
        // A short frame's checksum on its own bytes: offset 3, not 6.
        (
            "10 40 01 42 16",
            "checksum mismatch at offset 3: expected 0x41, found 0x42",
        ),
        // A short frame with a payload byte: as long as it travelled.
        (
            "10 40 01 00 41 16",
            "frame too long: 6 bytes, the longest frame has 5",
        ),
        ("10 40 01 41", "need at least 5 bytes, found 4"),
        // A short frame whose message has a payload: its length as it travelled.
        ("10 53 01 54 16", "found 5"),
    ] {
        let frame = interp::parse_hex(hex).unwrap();
        let g = Request::decode(&frame).map(|_| ());
        assert!(
            g.as_ref().unwrap_err().to_string().contains(words),
            "{hex}: {g:?}"
        );
        same_text(
            g,
            interp::decode(&p, Some(Direction::Request), None, &frame).map(|_| ()),
        );
    }
    let t = agree::agree::<Mbus>(&p);
    assert!(t.accepted >= 6 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<Mbus>(&p, 0x1068, "req_ud2");
    assert!(found > 30, "only {found} req_ud2 frames found");
}

/// CRC-16/XMODEM, RoboClaw's.
fn crc16_xmodem(data: &[u8]) -> u16 {
    let mut crc = 0u16;
    for &b in data {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                crc << 1 ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// RoboClaw's firmware version (command 21): text up to a NUL and a CRC, no length field, so
/// only the NUL tells where the reply ends. One frame: a reply whose text has no NUL, or whose
/// NUL is not where the frame's end says, is refused in both engines' words. A stream: both
/// decoders end the reply at its first NUL, wait for it while fewer than 48 bytes of text are
/// buffered, and take a run of 48 without one for no reply; they agree on captures of reads
/// and replies of every length, with noise, however they are cut.
#[test]
fn terminated_frame_snapshot_agrees_with_the_interpreter() {
    use busspec_model::interp;
    use roboclaw::{Response, Roboclaw};
    let file = "model/tests/fixtures/valid/roboclaw.yaml";
    let p = fixture(file);
    let read = [0x80, 0x15];
    let reply = |text: &[u8]| {
        let mut f = [text, &[0]].concat();
        let crc = crc16_xmodem(&[&read[..], &f].concat());
        f.extend_from_slice(&crc.to_be_bytes());
        f
    };
    let version = b"RoboClaw 10.2A v4.1.11\n";
    let d = Roboclaw::decode_reply_to(&reply(version), &read).unwrap();
    let Response::FirmwareVersion(roboclaw::response::FirmwareVersion { version: v }) = d.message
    else {
        panic!("{:?}", d.message)
    };
    assert_eq!(v.as_slice(), version);
    let mut buf = [0u8; 64];
    let n = Roboclaw::encode_reply(&d.message, 0, &read, &mut buf).unwrap();
    assert_eq!(buf[..n], reply(version));
    let request = interp::decode(&p, Some(Direction::Request), None, &read).unwrap();
    let both = |frame: &[u8]| {
        let g = Roboclaw::decode_reply_to(frame, &read).map(|_| ());
        let i = interp::decode_reply_with(&p, &request, Some(&read), frame).map(|_| ());
        match (&g, i) {
            (Ok(()), Ok(())) => {}
            (g, i) => same_text(*g, i),
        }
        g
    };
    // No NUL: the CRC right after the text, resealed.
    let mut none = version.to_vec();
    let crc = crc16_xmodem(&[&read[..], &none].concat());
    none.extend_from_slice(&crc.to_be_bytes());
    let e = both(&none).unwrap_err().to_string();
    assert!(e.contains("no terminator 0x00"), "{e}");
    // A NUL before the frame's end says: the text ends early.
    let early = reply(b"v4\x001.11");
    let e = both(&early).unwrap_err().to_string();
    assert!(e.contains("expected 7 by the frame's length"), "{e}");
    // 47 characters are the most; 48 are refused alike.
    assert!(both(&reply(&[b'x'; 47])).is_ok());
    assert!(both(&reply(&[b'x'; 48])).is_err());
    assert!(both(&reply(b"")).is_ok());
    // Encoding text that holds its terminator is refused.
    let held = Response::FirmwareVersion(roboclaw::response::FirmwareVersion {
        version: busspec_runtime::codec::Repeated::from_slice(b"v4\x00").unwrap(),
    });
    let e = Roboclaw::encode_reply(&held, 0, &read, &mut buf).unwrap_err();
    assert!(e.to_string().contains("holds its terminator 0x00"), "{e}");
    // A stream of replies alone, each after its read: one event each, whatever the cuts.
    let mut rng = agree::Rng(0x2115);
    let mut found = 0;
    for round in 0..200 {
        let mut cap = Vec::new();
        for _ in 0..8 {
            if rng.below(6) == 0 {
                cap.extend((0..1 + rng.below(4)).map(|_| rng.below(256) as u8));
            }
            cap.extend_from_slice(&read);
            let n = rng.below(48) as usize;
            let text: Vec<u8> = (0..n).map(|_| 1 + rng.below(255) as u8).collect();
            cap.extend_from_slice(&reply(&text));
            // Now and then a run of text without its NUL.
            if round % 7 == 0 && rng.below(4) == 0 {
                cap.extend(std::iter::repeat(b'z').take(40 + rng.below(20) as usize));
            }
        }
        let cuts: Vec<usize> = (0..6).map(|_| 1 + rng.below(30) as usize).collect();
        let want = interp_seen(&p, &cap, &cuts);
        let got = generated_seen::<Roboclaw>(&cap, &cuts);
        assert_eq!(got, want, "capture {cap:02X?}");
        assert_eq!(generated_seen::<Roboclaw>(&cap, &[cap.len()]), got);
        found += got.iter().filter(|s| s.0 == "firmware_version").count();
    }
    assert!(found > 200 * 5, "only {found} firmware versions found");
    // The examples in random order: a reply frames only right after its read.
    let found = examples_stream_alike::<Roboclaw>(&p, 0x15, "firmware_version");
    assert!(found > 2, "only {found} firmware versions found");
    let t = agree::agree::<Roboclaw>(&p);
    assert!(t.accepted >= 10 && t.refused > 50, "{t:?}");
}

/// The generated stream decoder's fast path against its full rule on every head of captures
/// of RoboClaw's reads and firmware versions (text up to a NUL, no length field: the
/// candidate's length known once the NUL is buffered), with noise, cut replies and runs of
/// text without a NUL: where the fast path decides, the same event and state.
#[test]
fn terminated_frame_fast_path_is_the_rule() {
    use busspec_runtime::stream::{Direction as Dir, StreamDecoder};
    use roboclaw::{Request, Roboclaw};
    let read = [0x80, 0x15];
    let reply = |text: &[u8]| {
        let mut f = [text, &[0]].concat();
        let crc = crc16_xmodem(&[&read[..], &f].concat());
        f.extend_from_slice(&crc.to_be_bytes());
        f
    };
    // After a read (settled: alone, it may be the start of a reply's text).
    let mut after = StreamDecoder::<Roboclaw>::new(None);
    let n = after.feed(&read).count();
    assert!(n + core::iter::from_fn(|| after.finish()).count() > 0);
    let states = [
        StreamDecoder::<Roboclaw>::new(None),
        after,
        StreamDecoder::<Roboclaw>::new(Some(Dir::Response)).with_default_request(Some(
            Request::ReadFirmwareVersion(roboclaw::request::ReadFirmwareVersion),
        )),
        StreamDecoder::<Roboclaw>::new(Some(Dir::Request)),
    ];
    let cap = <Roboclaw as Protocol>::MAX_FRAME_LEN;
    let mut rng = agree::Rng(0x21);
    let mut decided = 0;
    for _ in 0..60 {
        let mut bytes = Vec::new();
        for _ in 0..6 {
            bytes.extend_from_slice(&read);
            let n = rng.below(48) as usize;
            let text: Vec<u8> = (0..n).map(|_| 1 + rng.below(255) as u8).collect();
            let f = reply(&text);
            match rng.below(6) {
                0 => bytes.extend((0..1 + rng.below(3)).map(|_| rng.below(256) as u8)),
                1 => bytes.extend_from_slice(&f[..f.len() - 1]),
                2 => bytes.extend(std::iter::repeat(b'v').take(45 + rng.below(8) as usize)),
                _ => bytes.extend_from_slice(&f),
            }
        }
        for at in 0..bytes.len() {
            let mut w: Vec<u8> = bytes[at..].iter().copied().take(cap).collect();
            w.resize(cap, 0);
            for (i, d) in states.iter().enumerate() {
                let Some([fast, full]) = d.fast_and_full(&w, (i % 2) as u64) else {
                    continue;
                };
                assert_eq!(fast, full, "{w:02X?} from state {i}");
                decided += 1;
            }
        }
    }
    assert!(decided > 2000, "{decided} decided");
}

/// Responses a device sends unasked (`unasked: true`): the generated `is_unasked` says which,
/// a heartbeat heard right after a request is not its reply (`answers`, `decode_reply` refuse
/// it as the interpreter does, in the same words) and both stream decoders report it on its
/// own, then the request's reply after it; captures of the examples stream alike.
#[test]
fn unasked_snapshot_streams_as_the_interpreter_does() {
    use unasked::{Request, Response, Unasked};
    let file = "model/tests/fixtures/valid/unasked.yaml";
    replay::<Unasked>(file);
    let p = fixture(file);
    let get_status = busspec_model::interp::parse_hex("AA 21 40 01 0C").unwrap();
    let heartbeat = busspec_model::interp::parse_hex("AA 21 70 00 00 00 0A 45").unwrap();
    let status = busspec_model::interp::parse_hex("AA 21 40 01 00 05 11").unwrap();
    let go_to = busspec_model::interp::parse_hex("AA 21 20 00 05 F0").unwrap();
    let alarm = busspec_model::interp::parse_hex("AA 21 71 03 3F").unwrap();
    let q = Request::decode(&get_status).unwrap().message;
    let hb = Response::decode(&heartbeat).unwrap().message;
    assert!(hb.is_unasked() && rt_is_unasked(&hb));
    assert!(!hb.answers(&q));
    let st = Response::decode(&status).unwrap().message;
    assert!(!st.is_unasked() && !rt_is_unasked(&st) && st.answers(&q));
    let al = Response::decode(&alarm).unwrap().message;
    let g = Request::decode(&go_to).unwrap().message;
    assert!(al.is_unasked() && al.answers(&g) && !al.answers(&q));
    // As the reply to get_status, the heartbeat is refused alike by both engines.
    let gen = Unasked::decode_reply(&heartbeat, &q).unwrap_err();
    let iq =
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &get_status).unwrap();
    let int = busspec_model::interp::decode_reply(&p, &iq, &heartbeat).unwrap_err();
    assert_eq!(gen.to_string(), int.to_string());
    assert_eq!(
        gen.to_string(),
        "heartbeat is sent unasked, not a reply get_status gets"
    );
    assert!(matches!(
        gen,
        busspec_runtime::DecodeError::NotAReply { unasked: true, .. }
    ));
    // The alarm, also go_to's reply, is sent unasked all the same; `started`, go_to's reply
    // alone, is a wrong reply worded as before.
    let started = busspec_model::interp::parse_hex("AA 21 50 1B").unwrap();
    for (frame, words) in [
        (&alarm, "alarm is sent unasked, not a reply get_status gets"),
        (&started, "started is not a reply get_status gets"),
    ] {
        let gen = Unasked::decode_reply(frame, &q).unwrap_err();
        let int = busspec_model::interp::decode_reply(&p, &iq, frame).unwrap_err();
        assert_eq!(gen.to_string(), words);
        assert_eq!(int.to_string(), words);
    }
    // Request, heartbeat, its reply; go_to, the alarm as its reply, a heartbeat again; then
    // get_limit, a heartbeat, its reply, which only the request tells from a span: the
    // heartbeat leaves the request waiting in both stream decoders.
    let get_limit = busspec_model::interp::parse_hex("AA 21 41 0C").unwrap();
    let limit = busspec_model::interp::parse_hex("AA 21 42 02 00 10 1F").unwrap();
    let cap: Vec<u8> = [
        &get_status,
        &heartbeat,
        &status,
        &go_to,
        &alarm,
        &heartbeat,
        &get_limit,
        &heartbeat,
        &limit,
    ]
    .into_iter()
    .flatten()
    .copied()
    .collect();
    let names = [
        "get_status",
        "heartbeat",
        "status",
        "go_to",
        "alarm",
        "heartbeat",
        "get_limit",
        "heartbeat",
        "limit",
    ];
    for cuts in [&[1usize][..], &[3, 7], &[64]] {
        let want = interp_seen(&p, &cap, cuts);
        let got = generated_seen::<Unasked>(&cap, cuts);
        assert_eq!(got, want, "cuts {cuts:?}");
        let seen: Vec<&str> = got.iter().map(|s| s.0.as_str()).collect();
        assert_eq!(seen, names, "cuts {cuts:?}");
    }
    let t = agree::agree::<Unasked>(&p);
    assert!(t.accepted >= 5 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<Unasked>(&p, 0x0A5E, "heartbeat");
    assert!(found > 100, "only {found} heartbeat frames found");
}

/// A response sent unasked whose list runs to its end, which gives it a borrowed view: the
/// view refuses it as a reply in the words of the owned decode and the interpreter.
#[test]
fn unasked_to_end_snapshot_refuses_alike_through_its_view() {
    use unasked_to_end::{Request, Response, ResponseView, UnaskedToEnd};
    let file = "model/tests/fixtures/valid/unasked_to_end.yaml";
    replay::<UnaskedToEnd>(file);
    let p = fixture(file);
    let get_status = busspec_model::interp::parse_hex("AA 21 40 01 0C").unwrap();
    let log = busspec_model::interp::parse_hex("AA 21 72 3D 02 7C").unwrap();
    let q = Request::decode(&get_status).unwrap().message;
    let iq =
        busspec_model::interp::decode(&p, Some(Direction::Request), None, &get_status).unwrap();
    let words = "log is sent unasked, not a reply get_status gets";
    let owned = Response::decode_reply(&log, &q).unwrap_err();
    let view = ResponseView::decode_reply(&log, &q).unwrap_err();
    let int = busspec_model::interp::decode_reply(&p, &iq, &log).unwrap_err();
    assert_eq!(owned.to_string(), words);
    assert_eq!(view.to_string(), words);
    assert_eq!(int.to_string(), words);
    let t = agree::agree::<UnaskedToEnd>(&p);
    assert!(t.accepted >= 3 && t.refused > 100, "{t:?}");
}

/// The trait's `is_unasked`, as code generic over protocols sees it.
fn rt_is_unasked<R: busspec_runtime::ResponseMessage<unasked::Request>>(r: &R) -> bool {
    r.is_unasked()
}

/// FrSky F.Port v1 (`sum8_end_around`): the generated checksum is the end-around sum inverted
/// (ArduPilot's control frame's FA, where the plain sum inverted is 04, and 0x21 over
/// "123456789"); both engines decode ArduPilot's frame to the same channels and refuse it with
/// the plain sum's CRC in the same words; the encoder stuffs a CRC of 7D.
#[test]
fn end_around_sum_snapshot_agrees_with_the_interpreter() {
    use fport::{Fport, Request};
    let file = "model/tests/fixtures/valid/fport.yaml";
    replay::<Fport>(file);
    let p = fixture(file);
    let ardupilot = [
        0x7E, 0x19, 0x00, 0xE7, 0x3B, 0xDF, 0x5A, 0xCE, 0x07, 0x10, 0x75, 0x49, 0x9C, 0x15, 0xE0,
        0x03, 0x1F, 0xF8, 0xC0, 0x07, 0x3E, 0xF0, 0x81, 0x0F, 0x7C, 0x00, 0x38, 0xFA, 0x7E,
    ];
    assert_eq!(fport::checksum(&ardupilot[1..27]), 0xFA);
    assert_eq!(fport::checksum(b"123456789"), 0x21);
    match Request::decode(&ardupilot).map(|d| d.message) {
        Ok(Request::Control(c)) => {
            assert_eq!(c.channels[..8], [999, 999, 363, 999, 256, 746, 1810, 172]);
            assert_eq!(c.rssi, 56);
        }
        other => panic!("decoded as {other:?}"),
    }
    let mut plain = ardupilot;
    plain[27] = 0x04;
    let g = Request::decode(&plain).map(|_| ());
    let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, &plain);
    assert_eq!(
        g.unwrap_err().to_string(),
        "checksum mismatch at offset 27: expected 0xFA, found 0x04"
    );
    same_text(g, i.map(|_| ()));
    // The failsafe example's CRC is 7D: encoded, it travels as 7D 5D.
    let failsafe = &p.examples[2].wire;
    let decoded = Request::decode(failsafe).unwrap().message;
    let mut buf = [0u8; fport::MAX_FRAME_LEN];
    let n = decoded.encode(0, &mut buf).unwrap();
    assert_eq!(&buf[..n], &failsafe[..]);
    assert_eq!(buf[n - 3..n], [0x7D, 0x5D, 0x7E]);
}

/// F.Port both ways in one spec (`fport_both`): a capture of polls and control frames between
/// 7E flags, uplink frames (no flags, stuffed, found by their length) after the polls'
/// closing flags, a control frame sharing a poll's closing flag, ArduPilot's FF pad byte, noise,
/// an uplink frame with a bad CRC and one cut short. Both stream decoders report the same
/// events however the capture is cut, in both directions and each alone; the interpreter's are
/// pinned here.
#[test]
fn fport_both_streams_alike_interleaved_with_noise() {
    use busspec_model::interp::parse_hex;
    use fport_both::FportBoth;
    let file = "model/tests/fixtures/valid/fport_both.yaml";
    replay::<FportBoth>(file);
    let p = fixture(file);
    let hex = |s: &str| parse_hex(s).unwrap();
    let poll = hex("7E 08 01 10 00 00 00 00 00 00 E6 7E");
    let uplink = hex("08 81 10 10 01 7D 5E 00 00 00 D6");
    let null = hex("08 81 00 00 00 00 00 00 00 76");
    let control = p.examples[0].wire.clone();
    let mut cap = Vec::new();
    for part in [
        &poll[..],
        &uplink,
        &control,
        &[0xFF],
        &poll,
        &[0xFF],
        &null,
        &[0x12, 0x34],
        &poll,
        // The control frame's opening flag is the poll's closing one.
        &control[1..],
        &poll,
        // A bad CRC: no frame.
        &hex("08 81 00 00 00 00 00 00 00 77"),
        &poll,
        // Cut short: the next frame's flag ends it.
        &null[..6],
        &control,
        &hex("08 81 32 7D 5D 0D 78 56 34 12 A4"),
    ] {
        cap.extend_from_slice(part);
    }
    let names = |seen: &[Seen]| -> Vec<String> {
        seen.iter()
            .filter(|s| s.0 != "-")
            .map(|s| s.0.clone())
            .collect()
    };
    let want = interp_seen(&p, &cap, &[cap.len()]);
    assert_eq!(
        names(&want),
        [
            "downlink_data",
            "uplink_data",
            "control",
            "downlink_data",
            "uplink_data",
            "downlink_data",
            "control",
            "downlink_data",
            "downlink_data",
            "control",
            "uplink_data"
        ],
        "{want:?}"
    );
    let mut rng = agree::Rng(0xF0E7);
    for round in 0..200 {
        let cuts: Vec<usize> = if round == 0 {
            vec![1]
        } else {
            (0..6).map(|_| 1 + rng.below(24) as usize).collect()
        };
        assert_eq!(
            generated_seen::<FportBoth>(&cap, &cuts),
            interp_seen(&p, &cap, &cuts),
            "cuts {cuts:?}"
        );
        for d in [Direction::Request, Direction::Response] {
            assert_eq!(
                generated_seen_as::<FportBoth>(&cap, &cuts, Some(d)),
                interp_seen_as(&p, &cap, &cuts, Some(d)),
                "{d:?}, cuts {cuts:?}"
            );
        }
    }
    // Each frame alone, each direction, and the frames decoded without a direction.
    for e in &p.examples {
        let d = e.message.direction;
        assert!(agree::check::<FportBoth>(&p, d, None, &e.wire));
        let other = match d {
            Direction::Request => Direction::Response,
            Direction::Response => Direction::Request,
        };
        assert!(!agree::check::<FportBoth>(&p, other, None, &e.wire));
        let any = busspec_model::interp::decode(&p, None, None, &e.wire).unwrap();
        assert_eq!(any.message, e.message, "{:02X?}", e.wire);
    }
}

/// Every snapshot's `Framing::checksum_ok` (the weakest acceptance test, the checksum-only
/// soak master's rule) decides as the interpreter's `interp::checksum_ok`, on each example
/// frame (requests of replies too), each with one bit flipped at each offset, and each cut by
/// its last byte.
#[test]
fn every_snapshot_checks_checksums_as_the_interpreter_does() {
    fn one<P: Framing>(file: &str) -> (usize, usize) {
        let p = fixture(file);
        let mut frames: Vec<Vec<u8>> = Vec::new();
        for e in &p.examples {
            frames.push(e.wire.clone());
            frames.extend(e.request.clone());
        }
        let mut inputs = Vec::new();
        for w in &frames {
            inputs.push(w.clone());
            inputs.push(w[..w.len() - 1].to_vec());
            for at in 0..w.len() {
                for bit in [0x01, 0x80] {
                    let mut x = w.clone();
                    x[at] ^= bit;
                    inputs.push(x);
                }
            }
        }
        let (mut passed, mut failed) = (0, 0);
        let mut wrong = Vec::new();
        for x in &inputs {
            let (g, i) = (P::checksum_ok(x), busspec_model::interp::checksum_ok(&p, x));
            if g != i {
                wrong.push(format!("{} generated {g}, interpreter {i}", hex(x)));
            }
            if g {
                passed += 1
            } else {
                failed += 1
            }
        }
        assert!(wrong.is_empty(), "{file}: {}", wrong.join("\n"));
        (passed, failed)
    }
    fn hex(b: &[u8]) -> String {
        b.iter()
            .map(|x| format!("{x:02X}"))
            .collect::<Vec<_>>()
            .join(" ")
    }
    macro_rules! each {
        ($($module:ident :: $ty:ident, $file:literal;)*) => {{
            let mut totals = (0, 0);
            $(
                let (p, f) = one::<$module::$ty>($file);
                assert!(p > 0, "{}: no frame passes", $file);
                totals = (totals.0 + p, totals.1 + f);
            )*
            totals
        }};
    }
    let (passed, failed) = each! {
        mini::Mini, "model/tests/fixtures/valid/minimal.yaml";
        mini_crc::MiniCrc, "model/tests/fixtures/valid/minimal_crc.yaml";
        clash::Clash, "codegen/tests/fixtures/core_names.yaml";
        syncy::Syncy, "model/tests/fixtures/valid/minimal_sync.yaml";
        codeless::Codeless, "model/tests/fixtures/valid/minimal_codeless.yaml";
        vario::Vario, "model/tests/fixtures/valid/minimal_variable.yaml";
        ending::Ending, "model/tests/fixtures/valid/minimal_end.yaml";
        pelco_d2::PelcoD2, "model/tests/fixtures/valid/pelco_d_codeless.yaml";
        unaddressed::Unaddressed, "model/tests/fixtures/valid/unaddressed.yaml";
        ft12_fixed::Ft12Fixed, "model/tests/fixtures/valid/ft12_fixed.yaml";
        ubx_like::UbxLike, "model/tests/fixtures/valid/ubx_like.yaml";
        maestro_compact::MaestroCompact, "model/tests/fixtures/valid/maestro_compact.yaml";
        pelco_p::PelcoP, "model/tests/fixtures/valid/pelco_p.yaml";
        msp_v1::MspV1, "model/tests/fixtures/valid/msp_v1.yaml";
        msp_by_direction::MspByDirection, "model/tests/fixtures/valid/msp_by_direction.yaml";
        bcd_meter::BcdMeter, "model/tests/fixtures/valid/bcd_meter.yaml";
        crc_extra::CrcExtra, "model/tests/fixtures/valid/crc_extra.yaml";
        mavlink_v1::MavlinkV1, "model/tests/fixtures/valid/mavlink_v1.yaml";
        mavlink_v2::MavlinkV2, "model/tests/fixtures/valid/mavlink_v2.yaml";
        msp_v2::MspV2, "model/tests/fixtures/valid/msp_v2.yaml";
        ft12_variable::Ft12Variable, "model/tests/fixtures/valid/ft12_variable.yaml";
        sync_after_code::SyncAfterCode, "model/tests/fixtures/valid/sync_after_code.yaml";
        meter_floats::MeterFloats, "model/tests/fixtures/valid/meter_floats.yaml";
        telemetry_le::TelemetryLe, "model/tests/fixtures/valid/telemetry_le.yaml";
        slip_sensor::SlipSensor, "model/tests/fixtures/valid/slip_sensor.yaml";
        hdlc_like::HdlcLike, "model/tests/fixtures/valid/hdlc_like.yaml";
        cobs_link::CobsLink, "model/tests/fixtures/valid/cobs_link.yaml";
        dynamixel2_stuffed::Dynamixel2Stuffed, "model/tests/fixtures/valid/dynamixel2_stuffed.yaml";
        xbee_api2::XbeeApi2, "model/tests/fixtures/valid/xbee_api2.yaml";
        kiss::Kiss, "model/tests/fixtures/valid/kiss.yaml";
        garmin_link::GarminLink, "model/tests/fixtures/valid/garmin_link.yaml";
        tsip::Tsip, "model/tests/fixtures/valid/tsip.yaml";
        fport::Fport, "model/tests/fixtures/valid/fport.yaml";
        fport_uplink::FportUplink, "model/tests/fixtures/valid/fport_uplink.yaml";
        fport_both::FportBoth, "model/tests/fixtures/valid/fport_both.yaml";
        unasked::Unasked, "model/tests/fixtures/valid/unasked.yaml";
        unasked_to_end::UnaskedToEnd, "model/tests/fixtures/valid/unasked_to_end.yaml";
        lists_after::ListsAfter, "model/tests/fixtures/valid/lists_after.yaml";
        lists_length::ListsLength, "model/tests/fixtures/valid/lists_length.yaml";
        packed_channels::PackedChannels, "model/tests/fixtures/valid/packed_channels.yaml";
        records::Records, "model/tests/fixtures/valid/records.yaml";
        records_sized::RecordsSized, "model/tests/fixtures/valid/records_sized.yaml";
        mbus_short::MbusShort, "model/tests/fixtures/valid/mbus_short.yaml";
        dlt645::Dlt645, "model/tests/fixtures/valid/dlt645.yaml";
        optional_sensor::OptionalSensor, "model/tests/fixtures/valid/optional_sensor.yaml";
        text_counted::TextCounted, "model/tests/fixtures/valid/text_counted.yaml";
        text_terminated::TextTerminated, "model/tests/fixtures/valid/text_terminated.yaml";
        vesc::Vesc, "model/tests/fixtures/valid/vesc.yaml";
        mbus::Mbus, "model/tests/fixtures/valid/mbus.yaml";
        jbd_bms::JbdBms, "model/tests/fixtures/valid/jbd_bms.yaml";
        shdlc::Shdlc, "model/tests/fixtures/valid/shdlc.yaml";
        nextion::Nextion, "model/tests/fixtures/valid/nextion.yaml";
        rtcm3_frame::Rtcm3Frame, "model/tests/fixtures/valid/rtcm3_frame.yaml";
        ubx_fixed_blocks::UbxFixedBlocks, "model/tests/fixtures/valid/ubx_fixed_blocks.yaml";
        float_lists::FloatLists, "model/tests/fixtures/valid/float_lists.yaml";
        pelco_d_replies::PelcoDReplies, "model/tests/fixtures/valid/pelco_d_replies.yaml";
        roboclaw::Roboclaw, "model/tests/fixtures/valid/roboclaw.yaml";
        header_constant::HeaderConstant, "model/tests/fixtures/valid/header_constant.yaml";
        sbf_blocks::SbfBlocks, "model/tests/fixtures/valid/sbf_blocks.yaml";
        herkulex::Herkulex, "model/tests/fixtures/valid/herkulex.yaml";
        novatel_oem::NovatelOem, "model/tests/fixtures/valid/novatel_oem.yaml";
    };
    assert!(
        passed > 0 && failed > passed,
        "{passed} passed, {failed} failed"
    );
}

/// Header fields whose value every frame holds (`value` in `framing.header`, fixture
/// `header_constant`): the generated messages carry only the sequence number; a frame with
/// another header length or reserved byte is refused in both engines' words; both agree on
/// every frame mutated from the examples and find the position reports in a noisy capture.
#[test]
fn header_constant_snapshot_agrees_with_the_interpreter() {
    use header_constant::{HeaderConstant, Request, Response};
    let file = "model/tests/fixtures/valid/header_constant.yaml";
    replay::<HeaderConstant>(file);
    let p = fixture(file);
    assert!(p.framing.header.iter().any(|h| h.constant == Some(0x0B)));
    let log = Request::Log(header_constant::request::Log {
        sequence: 1,
        port: 7,
        trigger: 2,
    });
    let mut buf = [0u8; 64];
    let n = log.encode(0, &mut buf).unwrap();
    assert_eq!(&buf[..4], &[0xAA, 0x44, 0x12, 0x0B]);
    assert_eq!(buf[6], 0x00, "the reserved byte");
    // The header length one off, its CRC made right: no frame of this protocol.
    let mut other = buf[..n].to_vec();
    other[3] = 0x0C;
    busspec_model::interp::reseal(&p, &mut other);
    let g = Request::decode(&other).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "invalid value for log.header_length at offset 3: expected 0x0B, found 0x0C"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Request), None, &other);
    same_text(g, i.map(|_| ()));
    // The reserved byte set in a report.
    let mut report = p.examples[2].wire.clone();
    report[6] = 0x01;
    busspec_model::interp::reseal(&p, &mut report);
    let g = Response::decode(&report).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "invalid value for position.reserved at offset 6: expected 0x00, found 0x01"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &report);
    same_text(g, i.map(|_| ()));
    let t = agree::agree::<HeaderConstant>(&p);
    assert!(t.accepted >= 3 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<HeaderConstant>(&p, 0x4E0B, "position");
    assert!(found > 20, "only {found} position frames found");
}

/// Header fields in three places (`header` three times in the layout, fixture `novatel_oem`):
/// NovAtel's own BESTPOSB log decodes with its header's fields where the receiver puts them,
/// around the message id and the length; a log encoded again is the same bytes; a frame with
/// another header length is refused in both engines' words; both agree on every frame mutated
/// from the example and find the logs in a noisy capture.
#[test]
fn header_in_three_parts_snapshot_agrees_with_the_interpreter() {
    use novatel_oem::{NovatelOem, Response};
    let file = "model/tests/fixtures/valid/novatel_oem.yaml";
    replay::<NovatelOem>(file);
    let p = fixture(file);
    let parts: Vec<usize> = p.framing.header.iter().map(|h| h.part).collect();
    assert_eq!(parts, [0, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2]);
    let wire = p.examples[0].wire.clone();
    // The protocol's one response.
    let Response::Bestpos(log) = Response::decode(&wire).unwrap().message;
    // Part 2 between the message id and the length, part 3 after the length.
    assert_eq!((log.message_type, log.port_address), (0x00, 0x20));
    assert_eq!((log.week, log.milliseconds), (1803, 27_504_000));
    assert_eq!((log.reserved, log.software_version), (24901, 9603));
    let mut buf = [0u8; 128];
    let n = Response::Bestpos(log).encode(0, &mut buf).unwrap();
    assert_eq!(&buf[..n], &wire[..]);
    // The header length one off, its CRC made right: no frame of this protocol.
    let mut other = wire.clone();
    other[3] = 0x1D;
    busspec_model::interp::reseal(&p, &mut other);
    let g = Response::decode(&other).map(|_| ());
    assert_eq!(
        g.unwrap_err().to_string(),
        "invalid value for bestpos.header_length at offset 3: expected 0x1C, found 0x1D"
    );
    let i = busspec_model::interp::decode(&p, Some(Direction::Response), None, &other);
    same_text(g, i.map(|_| ()));
    let t = agree::agree::<NovatelOem>(&p);
    assert!(t.accepted >= 1 && t.refused > 100, "{t:?}");
    let found = examples_stream_alike::<NovatelOem>(&p, 0x1C2A, "bestpos");
    assert!(found > 20, "only {found} BESTPOS logs found");
}
