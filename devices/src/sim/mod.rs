//! Behavioural simulators of the UB2 capacitor ([`ub2::Ub2Sim`]) and the SD actuator
//! ([`sd::SdSim`]): `busspec-link`'s [`Device`](busspec_link::sim::Device)s, for its
//! [`SimBus`](busspec_link::sim::SimBus), its [`serve`](busspec_link::sim::serve) loop and the
//! soak. Each follows its document; where the document is silent, the module says what it
//! chose.

#[cfg(feature = "sd")]
pub mod sd;
#[cfg(feature = "ub2")]
pub mod ub2;
