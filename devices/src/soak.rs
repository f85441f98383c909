//! The soak mixes of UB2 and SD ([`SoakTarget`] for [`crate::Ub2`] and [`crate::Sd`]: the
//! simulator each soaks and the requests it sends, some of them deliberately out of range),
//! and the soak by protocol name, as `busspec soak` runs it. The soak itself is
//! `busspec-link`'s, generic ([`busspec_link::soak::run`]).

#[cfg(any(feature = "ub2", feature = "sd"))]
use busspec_link::soak::{run, SoakTarget};
use busspec_link::soak::{SoakConfig, SoakReport};
#[cfg(any(feature = "ub2", feature = "sd"))]
use busspec_runtime::Protocol;

#[cfg(feature = "sd")]
use crate::sim::sd::SdSim;
#[cfg(feature = "ub2")]
use crate::sim::ub2::Ub2Sim;
#[cfg(feature = "sd")]
use crate::Sd;
#[cfg(feature = "ub2")]
use crate::Ub2;
#[cfg(feature = "sd")]
use busspec_protocols::sd;
#[cfg(feature = "ub2")]
use busspec_protocols::ub2;

#[cfg(feature = "ub2")]
impl SoakTarget for Ub2 {
    type Device = Ub2Sim;

    fn device(index: u8) -> Ub2Sim {
        Ub2Sim::new(0x21 + index)
    }

    fn request(rng: &mut fastrand::Rng, d: &Ub2Sim) -> ub2::Request {
        use ub2::Request as Q;
        let cap = |rng: &mut fastrand::Rng| {
            let lo = d.lower_factory_limit().0;
            let hi = d.upper_factory_limit().0;
            ub2::Capacitance(rng.u32(lo.saturating_sub(500)..=hi + 500))
        };
        match rng.u32(0..100) {
            0..=4 => Q::GetActualCapacitance,
            5..=8 => Q::GetActualFullStepPosition,
            9..=10 => Q::GetMinimumCapacitance,
            11..=12 => Q::GetMaximumCapacitance,
            13..=15 => Q::GetAccelerationSpeed,
            16..=27 => Q::GetCCurveIndexedFullStepCapacitance {
                index: rng.u16(0..210),
            },
            28..=29 => Q::GetControllerTemperature,
            30..=33 => Q::GetMicroStepPosition,
            34..=36 => Q::GetFirmwareVersion,
            37..=39 => Q::GetSerialNumber,
            40 => Q::GetCminNom,
            41 => Q::GetCmaxNom,
            42..=43 => Q::GetLowerCustomerLimit,
            44..=45 => Q::GetUpperCustomerLimit,
            46 => Q::GetLowerFactoryLimit,
            47 => Q::GetUpperFactoryLimit,
            48 => Q::GetPresetCapacitance,
            49 => Q::GetPresetFullStepPosition,
            50..=53 => Q::GetStoredFullStepPosition {
                index: rng.u8(0..=10),
            },
            54..=55 => Q::GetModeOfOperation,
            56..=57 => Q::GetStatus,
            58..=61 => Q::GoToFullStepPositionStatus,
            62..=63 => Q::MoveFullStepsStatus,
            64..=65 => Q::GoToCapacitanceStatus,
            66..=69 => Q::SetAccelerationSpeedIndex {
                acceleration_index: rng.u8(0..=19),
                speed_index: rng.u8(0..=19),
            },
            70..=72 => Q::SetCurrent {
                idle_current: rng.u8(0..=110),
                drive_current: rng.u8(0..=210),
            },
            73..=77 => Q::StoreIndexedPosition {
                index: rng.u8(0..=10),
                position: rng.u16(0..10_000),
            },
            78..=79 => Q::SetModeOfOperation {
                mode: ub2::ModeOfOperation::from_raw(rng.u8(0..=3)),
            },
            80..=83 => Q::SetLowerCustomerLimit { limit: cap(rng) },
            84..=87 => Q::SetUpperCustomerLimit { limit: cap(rng) },
            88..=91 => Q::GoToFullStepPosition {
                target: rng.u16(0..10_000),
            },
            92..=95 => Q::MoveFullSteps {
                steps: rng.i16(-2000..=2000),
            },
            _ => Q::GoToCapacitance { target: cap(rng) },
        }
    }
}

#[cfg(feature = "sd")]
impl SoakTarget for Sd {
    type Device = SdSim;

    fn device(index: u8) -> SdSim {
        SdSim::new(1 + index)
    }

    fn request(rng: &mut fastrand::Rng, _d: &SdSim) -> sd::Request {
        use sd::Request as Q;
        match rng.u32(0..100) {
            0..=14 => Q::SetPoint {
                freshness: 0,
                position: sd::Angle(rng.i16(-2048..=2047)),
            },
            15..=24 => Q::ReadActualPosition,
            25..=29 => Q::SetVelocity {
                set_velocity: sd::Velocity(rng.i16(-3600..=3600)),
            },
            30..=33 => Q::ReadActualVelocity,
            34..=35 => Q::ReadServoId,
            36..=38 => Q::ReadCurrentConsumption,
            39..=40 => Q::ReadBusVoltages,
            41..=42 => Q::ReadExtendedCurrentConsumption,
            43..=45 => Q::ReadTemperatures,
            46..=47 => Q::ReadHumidity,
            48..=50 => Q::ReadSkippedFramesCounter,
            51 => Q::ResetDroppedFramesCounter,
            52..=54 => Q::ReadActuatorStatusWord,
            55 => Q::ResetActuatorStatusWord,
            56 => Q::ResetDefaultRoleAndErrorFlags,
            57 => Q::SetCurrentPositionAsZero,
            58..=59 => Q::ReadCurrentZeroOffset,
            60 => Q::ResetZeroOffset,
            61..=64 => Q::ReadElectronicSerialNumber {
                byte_number: rng.u8(0..=31),
            },
            65..=68 => Q::ReadProductDescription {
                byte_number: rng.u8(0..=31),
            },
            69..=70 => Q::ReadSoftwareRevision {
                byte_number: rng.u8(0..=31),
            },
            71..=72 => Q::ReadHardwareRevision {
                byte_number: rng.u8(0..=31),
            },
            73..=74 => Q::ReadTotalRuntimeHours,
            75..=76 => Q::ReadTotalRuntimeMinSec,
            77 => Q::ReadLoadRuntime024Hours,
            78 => Q::ReadLoadRuntime024MinSec,
            79 => Q::ResetLoadRuntime024,
            80 => Q::ReadLoadRuntime2549Hours,
            81 => Q::ReadLoadRuntime2549MinSec,
            82 => Q::ResetLoadRuntime2549,
            83 => Q::ReadLoadRuntime5074Hours,
            84 => Q::ReadLoadRuntime5074MinSec,
            85 => Q::ResetLoadRuntime5074,
            86 => Q::ReadLoadRuntime7599Hours,
            87 => Q::ReadLoadRuntime7599MinSec,
            88 => Q::ResetLoadRuntime7599,
            89 => Q::ReadLoadRuntime100Hours,
            90 => Q::ReadLoadRuntime100MinSec,
            91 => Q::ResetLoadRuntime100,
            92..=94 => Q::ReadStallEventCounter,
            95 => Q::ResetStallEventCounter,
            _ => Q::ReadPowerUpCycles,
        }
    }
}

/// The protocols [`run_named`] can soak, by spec name, in the order `busspec soak` runs them.
pub const TARGETS: &[&str] = &[
    #[cfg(feature = "ub2")]
    Ub2::NAME,
    #[cfg(feature = "sd")]
    Sd::NAME,
];

/// [`run`] for the protocol a name from [`TARGETS`] stands for; `None` for any other name.
pub fn run_named(name: &str, config: SoakConfig) -> Option<SoakReport> {
    #[cfg(feature = "ub2")]
    if name == Ub2::NAME {
        return Some(run::<Ub2>(config));
    }
    #[cfg(feature = "sd")]
    if name == Sd::NAME {
        return Some(run::<Sd>(config));
    }
    let _ = (name, config);
    None
}
