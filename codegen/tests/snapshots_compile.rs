//! The generator's snapshots (`codegen/tests/snapshots/`, the code emitted for the small fixture
//! specs) compile against the runtime, and replay their specs' examples through the
//! [`Protocol`] trait: decode, then encode back to the same bytes.

include!("snapshots/mini.rs");
include!("snapshots/mini_crc.rs");

use busspec_model::ir::{self, Direction};
use busspec_runtime::{Message, Protocol};

fn fixture(name: &str) -> ir::Protocol {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../model/tests/fixtures/valid")
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
    replay::<mini::Mini>("minimal.yaml");
}

#[test]
fn mini_crc_snapshot_replays_its_examples() {
    replay::<mini_crc::MiniCrc>("minimal_crc.yaml");
}
