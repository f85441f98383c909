//! A protocol whose commands get no reply has no responses, and its generated `Response` is an
//! enum without variants. Under the `arbitrary` feature (the fuzz bodies turn it on, so `cargo
//! test --workspace` builds this crate with it) that module must still compile: `arbitrary`'s
//! derive refuses an empty enum, so the generator writes an impl that makes no value. The module
//! is the code generated for the Pelco P fixture (`codegen/tests/snapshots/pelco_p.rs`, which
//! `busspec-codegen`'s snapshot test keeps current).

#![cfg(feature = "arbitrary")]

include!("../../codegen/tests/snapshots/pelco_p.rs");

use arbitrary::{Arbitrary, Unstructured};

#[test]
fn a_protocol_without_responses_takes_arbitrary_requests_and_makes_no_response() {
    let bytes: Vec<u8> = (0..=255u8).cycle().take(4096).collect();
    let mut u = Unstructured::new(&bytes);
    let mut encoded = 0;
    for _ in 0..64 {
        let request = pelco_p::Request::arbitrary(&mut u).unwrap();
        let mut buf = [0u8; pelco_p::MAX_FRAME_LEN];
        if let Ok(n) = request.encode(0x00, &mut buf) {
            let back = pelco_p::Request::decode(&buf[..n]).unwrap();
            assert_eq!(back.message, request);
            encoded += 1;
        }
    }
    assert!(encoded > 0, "no arbitrary request encoded");
    let mut u = Unstructured::new(&bytes);
    assert!(pelco_p::Response::arbitrary(&mut u).is_err());
}
