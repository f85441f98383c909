//! busspec-devices: the UB2 capacitor and the SD actuator as busspec's bus master sees them.
//!
//! The master crates are generic: `busspec-link-core` (the `no_std` sans-IO master and its
//! embedded drivers) and `busspec-link` (the `std` and tokio drivers, the simulated bus, the
//! soak) are written against [`busspec_runtime::Protocol`] and [`Link`], and name no
//! protocol. This crate holds what is particular to the two devices busspec drives:
//!
//! - [`Ub2`] and [`Sd`] (features `ub2`, `sd`): each the generated codec's [`Protocol`]
//!   (`busspec_protocols::ub2::Ub2`, `busspec_protocols::sd::Sd`: the same requests, responses
//!   and constants) plus the master's [`Link`] rules, in [`link`].
//! - [`movement`]: the UB2 movement and the SD move, for any driver of the core.
//! - With `std`: [`master`] (the UB2 C-curve table and movement, the SD string readouts and
//!   move, on `busspec_link::Master`), [`sim`] (behavioural simulators) and [`soak`] (their
//!   request mixes, and the soak by protocol name).
//!
//! Why a type of its own beside the codec's: [`Link`] is `busspec-link-core`'s trait and the
//! codec's unit type is `busspec-protocols`'; neither crate may know the other, and Rust lets
//! only the crate of the trait or of the type implement one for the other. So [`Ub2`] here is
//! a unit type whose [`Protocol`] is the codec's, item for item, and whose [`Link`] is the
//! master's rules for UB2.
//!
//! Each device is a feature, and each turns on only its own codec in `busspec-protocols`:
//! firmware that drives SD actuators builds with `default-features = false, features = ["sd"]`
//! and compiles neither UB2 nor Modbus nor Dynamixel.
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]

pub use busspec_link_core::Link;
/// The generated codecs this crate's features turned on (`protocols::ub2`, `protocols::sd`).
pub use busspec_protocols as protocols;
pub use busspec_runtime::{Message, Protocol};

/// A unit type that is the codec `$codec` item for item, so this crate may implement
/// [`Link`] for it.
#[allow(unused_macros)] // with neither `ub2` nor `sd`
macro_rules! protocol_as {
    ($(#[$attr:meta])* $name:ident = $codec:ty) => {
        $(#[$attr])*
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
        pub struct $name;

        impl busspec_runtime::Protocol for $name {
            type Request = <$codec as busspec_runtime::Protocol>::Request;
            type Response = <$codec as busspec_runtime::Protocol>::Response;
            type Buffer = <$codec as busspec_runtime::Protocol>::Buffer;

            const NAME: &'static str = <$codec as busspec_runtime::Protocol>::NAME;
            const SOURCE: busspec_runtime::Source = <$codec as busspec_runtime::Protocol>::SOURCE;
            const BUS: busspec_runtime::Bus = <$codec as busspec_runtime::Protocol>::BUS;
            const MAX_FRAME_LEN: usize = <$codec as busspec_runtime::Protocol>::MAX_FRAME_LEN;

            #[inline]
            fn decode_request(
                frame: &[u8],
            ) -> Result<busspec_runtime::Decoded<Self::Request>, busspec_runtime::DecodeError> {
                <$codec as busspec_runtime::Protocol>::decode_request(frame)
            }

            #[inline]
            fn decode_request_fixed(
                frame: &[u8],
            ) -> Result<busspec_runtime::Decoded<Self::Request>, busspec_runtime::DecodeError> {
                <$codec as busspec_runtime::Protocol>::decode_request_fixed(frame)
            }

            #[inline]
            fn decode_response_fixed(
                frame: &[u8],
            ) -> Result<busspec_runtime::Decoded<Self::Response>, busspec_runtime::DecodeError> {
                <$codec as busspec_runtime::Protocol>::decode_response_fixed(frame)
            }
        }

        impl busspec_runtime::Framing for $name {
            const MAX_REQUEST_LEN: usize = <$codec as busspec_runtime::Framing>::MAX_REQUEST_LEN;
            const MAX_RESPONSE_LEN: usize = <$codec as busspec_runtime::Framing>::MAX_RESPONSE_LEN;
            const FRAME_LENGTHS: &'static [usize] =
                <$codec as busspec_runtime::Framing>::FRAME_LENGTHS;
            const SHARED_FLAG: Option<u8> = <$codec as busspec_runtime::Framing>::SHARED_FLAG;
            const PREAMBLE: Option<busspec_runtime::Preamble> =
                <$codec as busspec_runtime::Framing>::PREAMBLE;
            const TRANSFORM: Option<busspec_runtime::Transform> =
                <$codec as busspec_runtime::Framing>::TRANSFORM;
            const LONG: Option<busspec_runtime::LongLength> =
                <$codec as busspec_runtime::Framing>::LONG;
            const OVER_REQUEST: bool = <$codec as busspec_runtime::Framing>::OVER_REQUEST;
            type Span = <$codec as busspec_runtime::Framing>::Span;
            const EMPTY_SPAN: Self::Span = <$codec as busspec_runtime::Framing>::EMPTY_SPAN;
            #[inline]
            fn candidates(head: &[u8]) -> busspec_runtime::stream::Candidates {
                <$codec as busspec_runtime::Framing>::candidates(head)
            }
            #[inline]
            fn candidate(head: &[u8]) -> busspec_runtime::stream::Candidate {
                <$codec as busspec_runtime::Framing>::candidate(head)
            }
            #[inline]
            fn variable_candidates(head: &[u8]) -> busspec_runtime::stream::VarLens {
                <$codec as busspec_runtime::Framing>::variable_candidates(head)
            }
            #[inline]
            fn checksum_ok(frame: &[u8]) -> bool {
                <$codec as busspec_runtime::Framing>::checksum_ok(frame)
            }
        }
    };
}

#[cfg(feature = "ub2")]
protocol_as! {
    /// The UB2 capacitor (Universal-ID UB2, SB-70) as the master sees it: the codec
    /// `busspec_protocols::ub2::Ub2` as its [`Protocol`], and the rules of [`link`] as its
    /// [`Link`].
    Ub2 = busspec_protocols::ub2::Ub2
}

#[cfg(feature = "sd")]
protocol_as! {
    /// The SD-01/02 actuator as the master sees it: the codec `busspec_protocols::sd::Sd` as
    /// its [`Protocol`], and the rules of [`link`] as its [`Link`].
    Sd = busspec_protocols::sd::Sd
}

pub mod link;
pub mod movement;

#[cfg(all(feature = "std", any(feature = "ub2", feature = "sd")))]
pub mod master;
#[cfg(all(feature = "std", any(feature = "ub2", feature = "sd")))]
pub mod sim;
#[cfg(feature = "std")]
pub mod soak;
