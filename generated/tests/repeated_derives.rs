//! Generated messages with repeated fields under the crate's `serde` and `arbitrary` features:
//! this crate's Modbus and Dynamixel modules derive both, so `rt::Repeated` and `rt::Bits`
//! implement them; arbitrary messages that encode decode to messages that encode to the same
//! bytes.
//!
//! `cargo test --workspace` builds this crate with both features (the root crate's tests ask
//! for `serde`, the fuzz bodies for `arbitrary`).

#![cfg(all(
    feature = "serde",
    feature = "arbitrary",
    feature = "modbus",
    feature = "dynamixel"
))]

use busspec_protocols::{dynamixel, modbus};

use arbitrary::{Arbitrary, Unstructured};
use busspec_runtime::{Message, Protocol};

fn serde_both_ways<T: serde::Serialize + serde::de::DeserializeOwned>() {}

/// Arbitrary messages of `M` whose encode succeeds decode, and the decoded message encodes to
/// the same bytes (bits by a byte count come back padded to whole bytes, as both engines read
/// them); returns how many encoded.
fn arbitrary_round_trips<M: Message + for<'a> Arbitrary<'a>>(
    decode: impl Fn(&[u8]) -> Option<M>,
    max: usize,
) -> usize {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut encoded = 0;
    for _ in 0..3000 {
        let bytes: Vec<u8> = (0..600)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 24) as u8
            })
            .collect();
        let Ok(m) = M::arbitrary(&mut Unstructured::new(&bytes)) else {
            continue;
        };
        let mut buf = vec![0u8; max];
        let Ok(n) = m.encode(bytes[0] % 8 + 1, &mut buf) else {
            continue;
        };
        assert_eq!(n, m.frame_len(), "{m:?}");
        let back = decode(&buf[..n]).unwrap_or_else(|| panic!("{m:?}: {:02X?}", &buf[..n]));
        let mut again = vec![0u8; max];
        let k = back.encode(bytes[0] % 8 + 1, &mut again).unwrap();
        assert_eq!(&again[..k], &buf[..n], "{m:?}");
        encoded += 1;
    }
    encoded
}

#[test]
fn repeated_fields_derive_serde_and_arbitrary() {
    serde_both_ways::<modbus::Request>();
    serde_both_ways::<modbus::Response>();
    serde_both_ways::<dynamixel::Request>();
    serde_both_ways::<dynamixel::Response>();
    let max = <modbus::Modbus as Protocol>::MAX_FRAME_LEN;
    let q = arbitrary_round_trips::<modbus::Request>(
        |f| modbus::Request::decode(f).ok().map(|d| d.message),
        max,
    );
    let r = arbitrary_round_trips::<modbus::Response>(
        |f| modbus::Response::decode(f).ok().map(|d| d.message),
        max,
    );
    let max = <dynamixel::Dynamixel as Protocol>::MAX_FRAME_LEN;
    let d = arbitrary_round_trips::<dynamixel::Request>(
        |f| dynamixel::Request::decode(f).ok().map(|d| d.message),
        max,
    );
    assert!(q > 100 && r > 100 && d > 100, "{q} {r} {d}");
}
