//! The Modbus peer agrees with the spec: modbus-core decodes every example frame of
//! `spec/modbus.yaml` it handles and encodes it back to the same bytes, so the benches compare
//! decoders doing the same work on frames both accept; and it still fails, as documented, on
//! the messages the benches leave out (when a new version fixes them, widen the subset).

use busspec_benches::peer::modbus_core::{decode, decode_all, encode_all, Adu, NOT_HANDLED};
use busspec_model::ir::{Direction, Protocol};

fn spec() -> Protocol {
    let yaml = include_str!("../../spec/modbus.yaml");
    busspec_model::load_str("modbus", yaml).unwrap_or_else(|d| panic!("{d}"))
}

/// The example decoded and encoded again by modbus-core, `None` if it rejects the frame.
fn round_trip(direction: Direction, wire: &[u8]) -> Option<Vec<u8>> {
    let adu = decode(direction, wire)?;
    match (adu, direction) {
        (Adu::Request(_), Direction::Request) | (Adu::Response(_), Direction::Response) => {}
        other => panic!("decoded as {other:?}"),
    }
    let mut out = [0u8; 256];
    let n = encode_all(&[adu], &mut out)?;
    Some(out[..n].to_vec())
}

#[test]
fn peer_decodes_and_reencodes_every_example_it_handles() {
    let p = spec();
    let mut checked = [0usize; 2];
    for e in &p.examples {
        let name = p.message(e.message).name.as_str();
        let again = round_trip(e.message.direction, &e.wire);
        if NOT_HANDLED.contains(&name) {
            assert_ne!(
                again.as_deref(),
                Some(&e.wire[..]),
                "{name}: modbus-core handles it now"
            );
            continue;
        }
        let again = again.unwrap_or_else(|| panic!("{name}: rejected {:02X?}", e.wire));
        assert_eq!(again, e.wire, "{name}: re-encoded differently");
        checked[usize::from(e.message.direction == Direction::Response)] += 1;
    }
    assert!(checked[0] >= 5 && checked[1] >= 5, "{checked:?}");
}

#[test]
fn decode_all_counts_only_frames_the_peer_accepts() {
    let p = spec();
    let mut bytes = Vec::new();
    let mut frames = Vec::new();
    for e in p
        .examples
        .iter()
        .filter(|e| !NOT_HANDLED.contains(&p.message(e.message).name.as_str()))
    {
        let start = bytes.len();
        bytes.extend_from_slice(&e.wire);
        frames.push((e.message.direction, start..bytes.len()));
    }
    assert_eq!(decode_all(&bytes, &frames), frames.len());
    // A corrupted CRC byte in the first frame: one fewer.
    let last = frames[0].1.end - 1;
    bytes[last] ^= 0xFF;
    assert_eq!(decode_all(&bytes, &frames), frames.len() - 1);
}
