//! What a microcontroller's flash holds of a busspec codec: built as a `staticlib` for
//! `thumbv7em-none-eabihf` at `opt-level = "s"` (see `BENCHMARKS.md`, "Flash"). Each
//! feature exports `busspec_ub2` and `busspec_sd`, which decode a request, or a response as the
//! reply to a request, and encode it back: with `generated`, every message of both protocols;
//! with `hand`, the benches' hand-written codec of the bench subset; with `subset`, the
//! generated code of the same subset.

#![no_std]
// `#[no_mangle]` (exporting the symbols to measure) counts as unsafe code; nothing else may.
#![deny(unsafe_code)]

#[cfg(not(test))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}

/// The codec under measurement, as `ub2` and `sd` modules with the generated API.
#[cfg(feature = "generated")]
use busspec_protocols::{sd, ub2};

#[cfg(feature = "subset")]
pub mod generated_subset {
    include!(concat!(env!("OUT_DIR"), "/subset.rs"));
}
#[cfg(feature = "subset")]
use generated_subset::{sd, ub2};

#[cfg(any(feature = "generated", feature = "subset"))]
macro_rules! roundtrip {
    ($name:ident, $p:ident) => {
        /// Decodes `frame` as a request, or else as the reply to `request` (itself decoded),
        /// and encodes it into `out`; returns the length written, 0 for a frame refused.
        #[allow(unsafe_code)]
        #[no_mangle]
        pub fn $name(frame: &[u8], request: &[u8], out: &mut [u8]) -> usize {
            if let Ok(d) = $p::Request::decode(frame) {
                return d.message.encode(d.address, out).unwrap_or(0);
            }
            let r = match $p::Request::decode(request) {
                Ok(q) => $p::Response::decode_reply(frame, &q.message),
                Err(_) => $p::Response::decode(frame),
            };
            match r {
                Ok(d) => d.message.encode(d.address, out).unwrap_or(0),
                Err(_) => 0,
            }
        }
    };
}
#[cfg(any(feature = "generated", feature = "subset"))]
roundtrip!(busspec_ub2, ub2);
#[cfg(any(feature = "generated", feature = "subset"))]
roundtrip!(busspec_sd, sd);

#[cfg(feature = "hand")]
#[path = "../../src/hand/mod.rs"]
pub mod hand;

#[cfg(feature = "hand")]
macro_rules! roundtrip_hand {
    ($name:ident, $p:ident) => {
        /// As the generated codec's: the hand-written decoders and encoders of the subset.
        #[allow(unsafe_code)]
        #[no_mangle]
        pub fn $name(frame: &[u8], request: &[u8], out: &mut [u8]) -> usize {
            if let Ok(d) = hand::$p::decode_request(frame) {
                return match hand::$p::encode_request(&d.message, d.address, out) {
                    Some(Ok(n)) => n,
                    _ => 0,
                };
            }
            let q = hand::$p::decode_request(request).ok();
            match hand::$p::decode_response(frame, q.as_ref().map(|q| &q.message)) {
                Ok(d) => match hand::$p::encode_response(&d.message, d.address, out) {
                    Some(Ok(n)) => n,
                    _ => 0,
                },
                Err(_) => 0,
            }
        }
    };
}
#[cfg(feature = "hand")]
roundtrip_hand!(busspec_ub2, ub2);
#[cfg(feature = "hand")]
roundtrip_hand!(busspec_sd, sd);
