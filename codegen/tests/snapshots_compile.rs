//! The generator's snapshots (`codegen/tests/snapshots/`, the code emitted for the small fixture
//! specs) compile against the runtime, and replay their specs' examples through the
//! [`Protocol`] trait: decode, then encode back to the same bytes.

include!("snapshots/mini.rs");
include!("snapshots/mini_crc.rs");
include!("snapshots/core_names.rs");

use busspec_model::ir::{self, Direction};
use busspec_runtime::{Message, Protocol};

/// `name`, a path from the repository's root.
fn fixture(name: &str) -> ir::Protocol {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(name);
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
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
                let d = P::decode_response_for(&e.wire, request.as_ref()).unwrap();
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

/// Names that clash with core's (`Option`, `Some`, `Ok`, ...), with primitives and with the
/// generated code's own locals compile (this file would not otherwise) and round-trip; the
/// types keep their spec names.
#[test]
fn core_names_snapshot_replays_its_examples() {
    replay::<clash::Clash>("codegen/tests/fixtures/core_names.yaml");
    let m = clash::Request::Option {
        some: clash::Result::Err,
        core: clash::Option(5),
    };
    let mut buf = [0u8; clash::MAX_FRAME_LEN];
    let n = m.encode(0x21, &mut buf).unwrap();
    assert_eq!(clash::Request::decode(&buf[..n]).unwrap().message, m);
    let flags = clash::Ok::SOME;
    assert!(flags.contains(clash::Ok::SOME) && !flags.contains(clash::Ok::NONE));
    assert_eq!(clash::Some(3).value(), 5.0);
    let rt = clash::Request::Rt { f: 7 };
    let n = rt.encode(0x21, &mut buf).unwrap();
    assert_eq!(&buf[3..5], &[7, 7]);
    assert_eq!(clash::Request::decode(&buf[..n]).unwrap().message, rt);
}
