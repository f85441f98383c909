//! The TH-10 thermostat's protocol, generated at build time from `spec/thermo.yaml`.
//!
//! The included file declares the module [`thermo`] (`Request`, `Response`, unit types such as
//! `thermo::DeciCelsius`, the enums and flags, `StreamDecoder`, and the unit type
//! `thermo::Thermo` implementing [`busspec_runtime::Protocol`]), [`PROTOCOLS`] and
//! [`with_protocol`].

#![no_std]
#![forbid(unsafe_code)]

include!(concat!(env!("OUT_DIR"), "/protocols.rs"));
