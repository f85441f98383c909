//! Both engines print every example frame of every built-in spec as the same JSON line, and
//! read it back to the example's bytes: the generated codec (typed messages through
//! `Message::visit`) and the interpreter (frames decoded from the IR at run time).

use busspec_json::{
    decode_frame, decode_frame_with, decode_typed, decode_typed_with, event_line, frame_line,
    load_spec, parse_line, Spec, TypedStream,
};
use busspec_model::stream::StreamDecoder;
use busspec_protocols::{Protocol, ProtocolVisitor, PROTOCOLS};

/// Checks every example of `P`'s spec; returns how many there are, and how many of them read
/// both as a request and as a response.
struct Examples;

impl ProtocolVisitor for Examples {
    type Output = (usize, usize);
    fn visit<P: Protocol>(self) -> (usize, usize) {
        let spec = load_spec::<P>().unwrap_or_else(|e| panic!("{e}"));
        let mut echoes = 0;
        assert!(!spec.examples.is_empty(), "{} has no examples", spec.name);
        for (i, e) in spec.examples.iter().enumerate() {
            let m = spec.message(e.message);
            let at = format!("{} example {i} (§{} {})", spec.name, e.section, m.name);
            // Decoded as `busspec decode` decodes it: no direction, the request only where the
            // response needs it.
            let reply_to = m.needs_request.then_some(e.reply_to).flatten();
            // A frame that reads both ways (a Modbus echo) is the same error in both engines,
            // and then decodes with its direction given.
            let direction = match decode_frame(&spec, None, reply_to, &e.wire) {
                Err(err) if err.contains("a request and a response look alike") => {
                    let typed = decode_typed::<P>(&spec, None, reply_to, &e.wire);
                    assert_eq!(typed.err(), Some(err), "{at}");
                    echoes += 1;
                    Some(e.message.direction)
                }
                _ => None,
            };
            // A reply whose checksum takes in its request's bytes, with them.
            let covered = e.request.as_deref().and_then(|w| spec.checksum_span(w));
            let frame = decode_frame_with(&spec, direction, reply_to, covered, &e.wire)
                .unwrap_or_else(|err| panic!("{at}: interpreter: {err}"));
            let typed = decode_typed_with::<P>(&spec, direction, reply_to, covered, &e.wire)
                .unwrap_or_else(|err| panic!("{at}: generated: {err}"));
            assert_eq!(
                frame.message, e.message,
                "{at}: interpreter decodes another message"
            );
            assert_eq!(
                typed.name(),
                m.name,
                "{at}: generated code decodes another message"
            );
            assert_eq!(typed.direction(), e.message.direction, "{at}");
            let interpreted = frame_line(&spec, &frame, None);
            let generated = typed
                .line(&spec, None)
                .unwrap_or_else(|err| panic!("{at}: {err}"));
            assert_eq!(
                generated, interpreted,
                "{at}: the engines print differently"
            );
            // Valid JSON, naming the message and direction.
            let v: serde_json::Value = serde_json::from_str(&generated).expect("JSON");
            assert_eq!(v["message"], m.name.as_str(), "{at}");
            assert_eq!(v["direction"], e.message.direction.as_str(), "{at}");
            assert_eq!(v["protocol"], spec.name.as_str(), "{at}");

            // And back, through both engines, to the example's bytes.
            let parsed = parse_line(&spec, &generated).unwrap_or_else(|err| panic!("{at}: {err}"));
            assert_eq!(parsed.message, e.message, "{at}");
            let again = parsed
                .encode_reply(&spec, e.request.as_deref())
                .unwrap_or_else(|err| panic!("{at}: interpreter encode: {err}"));
            assert_eq!(
                again, e.wire,
                "{at}: the interpreter re-encodes differently"
            );
            let back = parsed
                .to_typed::<P>(&spec)
                .unwrap_or_else(|err| panic!("{at}: typed: {err}"));
            assert_eq!(
                back, typed,
                "{at}: the line reads back as another typed message"
            );
            let again = back
                .encode_reply(e.request.as_deref())
                .unwrap_or_else(|err| panic!("{at}: generated encode: {err}"));
            assert_eq!(
                again, e.wire,
                "{at}: the generated code re-encodes differently"
            );
        }
        (spec.examples.len(), echoes)
    }
}

#[test]
fn both_engines_print_every_example_alike_and_read_it_back() {
    let mut counts = Vec::new();
    for name in PROTOCOLS {
        let n = busspec_protocols::with_protocol(name, Examples).expect("a built-in protocol");
        counts.push((*name, n));
    }
    // Modbus's write_single_coil and write_single_register replies echo their request.
    let at_least = [
        ("ub2", 80, 0),
        ("sd", 50, 0),
        ("modbus", 15, 4),
        ("dynamixel", 10, 0),
    ];
    for (name, examples, echoes) in at_least {
        assert!(
            counts
                .iter()
                .any(|&(n, (c, e))| n == name && c >= examples && e >= echoes),
            "{name}: {counts:?}"
        );
    }
}

/// Every example in a row, with noise between some and the ambiguous responses alone: both
/// stream decoders print the same lines, however the capture is cut.
struct Capture;

impl ProtocolVisitor for Capture {
    type Output = usize;
    fn visit<P: Protocol>(self) -> usize {
        let spec: Spec = load_spec::<P>().unwrap_or_else(|e| panic!("{e}"));
        let noise: [&[u8]; 3] = [&[0x00, 0x13], &[0xFF], &[0x55, 0x01, 0x02]];
        let mut bytes = Vec::new();
        for (i, e) in spec.examples.iter().enumerate() {
            if i % 5 == 2 {
                bytes.extend_from_slice(noise[i % 3]);
            }
            bytes.extend_from_slice(&e.wire);
        }
        for chunk in [1, 7, 4096] {
            let mut interp = StreamDecoder::new(&spec, None);
            let mut typed = TypedStream::<P>::new(&spec, None, None);
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for piece in bytes.chunks(chunk) {
                a.extend(interp.push(piece).iter().map(|e| event_line(&spec, e)));
                b.extend(typed.push(piece));
            }
            a.extend(interp.flush().iter().map(|e| event_line(&spec, e)));
            b.extend(typed.finish());
            assert_eq!(a.len(), b.len(), "{} in chunks of {chunk}", spec.name);
            for (x, y) in a.iter().zip(&b) {
                assert_eq!(x, y, "{} in chunks of {chunk}", spec.name);
            }
            assert!(a.iter().any(|l| l.contains("\"skipped\"")));
        }
        bytes.len()
    }
}

#[test]
fn both_stream_decoders_print_a_capture_alike() {
    for name in PROTOCOLS {
        let len = busspec_protocols::with_protocol(name, Capture).expect("built in");
        assert!(len > 80, "{name}: {len} bytes");
    }
}
