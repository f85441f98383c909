//! Typed `no_std` encoders and decoders for the RS485 protocols busspec transcribes,
//! generated at build time from the specs in `spec/` by `busspec-codegen`:
//!
//! - [`ub2`]: the Comet motorized vacuum capacitor, Universal-ID UB2 (SB-70);
//! - [`sd`]: the SD-01/02 servo actuator (RS485 ICD);
//! - [`modbus`]: Modbus RTU (function codes 0x01–0x06, 0x0F, 0x10 and their exceptions);
//! - [`dynamixel`]: ROBOTIS Dynamixel Protocol 1.0;
//! - [`pelco_d`]: Pelco D, PTZ camera receivers (pan, tilt, lens, presets, position queries);
//! - [`pelco_p`]: Pelco P, PTZ camera receivers (commands only: receivers do not answer);
//! - [`crsf`]: CRSF (Crossfire, ExpressLRS), RC links: packed RC channels, telemetry, extended frames;
//! - [`dynamixel2`]: ROBOTIS Dynamixel Protocol 2.0 (byte stuffing, CRC-16, sync and bulk instructions).
//!
//! Each module has `Request` and `Response` enums (one variant per command or response, named
//! fields, physical units as types), `encode` into a caller's buffer, `decode` from a byte
//! slice, `decode_reply` against the request, a `StreamDecoder` for raw captures, and a unit
//! type ([`ub2::Ub2`], [`sd::Sd`], [`modbus::Modbus`], [`dynamixel::Dynamixel`],
//! [`pelco_d::PelcoD`], [`pelco_p::PelcoP`], [`crsf::Crsf`], [`dynamixel2::Dynamixel2`]) implementing
//! [`Protocol`], so code generic over protocols works with all of them. [`PROTOCOLS`] and [`with_protocol`] find a protocol by name.
//!
//! Each module is behind the cargo feature of its name (`ub2`, `sd`, `modbus`, `dynamixel`,
//! `pelco_d`, `pelco_p`, `crsf`, `dynamixel2`; all eight by default): a firmware build turns the default off and names the protocols it speaks,
//! so it compiles only those; [`PROTOCOLS`] lists the ones built.
//!
//! Everything protocol-independent (errors, [`Decoded`], [`FieldValue`], the stream decoder) is
//! `busspec-runtime`'s, re-exported here.
//!
//! Invariants: `no_std`, no allocation, no `unsafe`, and no input makes encoding or decoding
//! panic — every frame is checked for length before any byte is read, and fixed-size arrays carry
//! the length to every field access.

#![no_std]
#![forbid(unsafe_code)]

// `arbitrary`'s derive counts recursion in a `std` thread-local, and `arbitrary` needs `std`
// anyway: the feature is for fuzzing and tests, never for a device build.
#[cfg(feature = "arbitrary")]
extern crate std;

#[doc(hidden)]
pub use busspec_runtime::Framing;
pub use busspec_runtime::{
    stream, Broadcast, Bus, Command, CommandKind, CountRule, DecodeError, Decoded, Elements,
    EncodeError, FieldDesc, FieldValue, FrameBuffer, Message, MessageDesc, MessageNames, NumKind,
    Protocol, ProtocolVisitor, Repeated, RequestMessage, ResponseMessage, Source,
};

include!(concat!(env!("OUT_DIR"), "/protocols.rs"));
