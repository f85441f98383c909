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
            0..=4 => Q::GetActualCapacitance(ub2::request::GetActualCapacitance),
            5..=8 => Q::GetActualFullStepPosition(ub2::request::GetActualFullStepPosition),
            9..=10 => Q::GetMinimumCapacitance(ub2::request::GetMinimumCapacitance),
            11..=12 => Q::GetMaximumCapacitance(ub2::request::GetMaximumCapacitance),
            13..=15 => Q::GetAccelerationSpeed(ub2::request::GetAccelerationSpeed),
            16..=27 => Q::GetCCurveIndexedFullStepCapacitance(
                ub2::request::GetCCurveIndexedFullStepCapacitance {
                    index: rng.u16(0..210),
                },
            ),
            28..=29 => Q::GetControllerTemperature(ub2::request::GetControllerTemperature),
            30..=33 => Q::GetMicroStepPosition(ub2::request::GetMicroStepPosition),
            34..=36 => Q::GetFirmwareVersion(ub2::request::GetFirmwareVersion),
            37..=39 => Q::GetSerialNumber(ub2::request::GetSerialNumber),
            40 => Q::GetCminNom(ub2::request::GetCminNom),
            41 => Q::GetCmaxNom(ub2::request::GetCmaxNom),
            42..=43 => Q::GetLowerCustomerLimit(ub2::request::GetLowerCustomerLimit),
            44..=45 => Q::GetUpperCustomerLimit(ub2::request::GetUpperCustomerLimit),
            46 => Q::GetLowerFactoryLimit(ub2::request::GetLowerFactoryLimit),
            47 => Q::GetUpperFactoryLimit(ub2::request::GetUpperFactoryLimit),
            48 => Q::GetPresetCapacitance(ub2::request::GetPresetCapacitance),
            49 => Q::GetPresetFullStepPosition(ub2::request::GetPresetFullStepPosition),
            50..=53 => Q::GetStoredFullStepPosition(ub2::request::GetStoredFullStepPosition {
                index: rng.u8(0..=10),
            }),
            54..=55 => Q::GetModeOfOperation(ub2::request::GetModeOfOperation),
            56..=57 => Q::GetStatus(ub2::request::GetStatus),
            58..=61 => Q::GoToFullStepPositionStatus(ub2::request::GoToFullStepPositionStatus),
            62..=63 => Q::MoveFullStepsStatus(ub2::request::MoveFullStepsStatus),
            64..=65 => Q::GoToCapacitanceStatus(ub2::request::GoToCapacitanceStatus),
            66..=69 => Q::SetAccelerationSpeedIndex(ub2::request::SetAccelerationSpeedIndex {
                acceleration_index: rng.u8(0..=19),
                speed_index: rng.u8(0..=19),
            }),
            70..=72 => Q::SetCurrent(ub2::request::SetCurrent {
                idle_current: rng.u8(0..=110),
                drive_current: rng.u8(0..=210),
            }),
            73..=77 => Q::StoreIndexedPosition(ub2::request::StoreIndexedPosition {
                index: rng.u8(0..=10),
                position: rng.u16(0..10_000),
            }),
            78..=79 => Q::SetModeOfOperation(ub2::request::SetModeOfOperation {
                mode: ub2::ModeOfOperation::from_raw(rng.u8(0..=3)),
            }),
            80..=83 => {
                Q::SetLowerCustomerLimit(ub2::request::SetLowerCustomerLimit { limit: cap(rng) })
            }
            84..=87 => {
                Q::SetUpperCustomerLimit(ub2::request::SetUpperCustomerLimit { limit: cap(rng) })
            }
            88..=91 => Q::GoToFullStepPosition(ub2::request::GoToFullStepPosition {
                target: rng.u16(0..10_000),
            }),
            92..=95 => Q::MoveFullSteps(ub2::request::MoveFullSteps {
                steps: rng.i16(-2000..=2000),
            }),
            _ => Q::GoToCapacitance(ub2::request::GoToCapacitance { target: cap(rng) }),
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
            0..=14 => Q::SetPoint(sd::request::SetPoint {
                freshness: 0,
                position: sd::Angle(rng.i16(-2048..=2047)),
            }),
            15..=24 => Q::ReadActualPosition(sd::request::ReadActualPosition),
            25..=29 => Q::SetVelocity(sd::request::SetVelocity {
                set_velocity: sd::Velocity(rng.i16(-3600..=3600)),
            }),
            30..=33 => Q::ReadActualVelocity(sd::request::ReadActualVelocity),
            34..=35 => Q::ReadServoId(sd::request::ReadServoId),
            36..=38 => Q::ReadCurrentConsumption(sd::request::ReadCurrentConsumption),
            39..=40 => Q::ReadBusVoltages(sd::request::ReadBusVoltages),
            41..=42 => {
                Q::ReadExtendedCurrentConsumption(sd::request::ReadExtendedCurrentConsumption)
            }
            43..=45 => Q::ReadTemperatures(sd::request::ReadTemperatures),
            46..=47 => Q::ReadHumidity(sd::request::ReadHumidity),
            48..=50 => Q::ReadSkippedFramesCounter(sd::request::ReadSkippedFramesCounter),
            51 => Q::ResetDroppedFramesCounter(sd::request::ResetDroppedFramesCounter),
            52..=54 => Q::ReadActuatorStatusWord(sd::request::ReadActuatorStatusWord),
            55 => Q::ResetActuatorStatusWord(sd::request::ResetActuatorStatusWord),
            56 => Q::ResetDefaultRoleAndErrorFlags(sd::request::ResetDefaultRoleAndErrorFlags),
            57 => Q::SetCurrentPositionAsZero(sd::request::SetCurrentPositionAsZero),
            58..=59 => Q::ReadCurrentZeroOffset(sd::request::ReadCurrentZeroOffset),
            60 => Q::ResetZeroOffset(sd::request::ResetZeroOffset),
            61..=64 => Q::ReadElectronicSerialNumber(sd::request::ReadElectronicSerialNumber {
                byte_number: rng.u8(0..=31),
            }),
            65..=68 => Q::ReadProductDescription(sd::request::ReadProductDescription {
                byte_number: rng.u8(0..=31),
            }),
            69..=70 => Q::ReadSoftwareRevision(sd::request::ReadSoftwareRevision {
                byte_number: rng.u8(0..=31),
            }),
            71..=72 => Q::ReadHardwareRevision(sd::request::ReadHardwareRevision {
                byte_number: rng.u8(0..=31),
            }),
            73..=74 => Q::ReadTotalRuntimeHours(sd::request::ReadTotalRuntimeHours),
            75..=76 => Q::ReadTotalRuntimeMinSec(sd::request::ReadTotalRuntimeMinSec),
            77 => Q::ReadLoadRuntime024Hours(sd::request::ReadLoadRuntime024Hours),
            78 => Q::ReadLoadRuntime024MinSec(sd::request::ReadLoadRuntime024MinSec),
            79 => Q::ResetLoadRuntime024(sd::request::ResetLoadRuntime024),
            80 => Q::ReadLoadRuntime2549Hours(sd::request::ReadLoadRuntime2549Hours),
            81 => Q::ReadLoadRuntime2549MinSec(sd::request::ReadLoadRuntime2549MinSec),
            82 => Q::ResetLoadRuntime2549(sd::request::ResetLoadRuntime2549),
            83 => Q::ReadLoadRuntime5074Hours(sd::request::ReadLoadRuntime5074Hours),
            84 => Q::ReadLoadRuntime5074MinSec(sd::request::ReadLoadRuntime5074MinSec),
            85 => Q::ResetLoadRuntime5074(sd::request::ResetLoadRuntime5074),
            86 => Q::ReadLoadRuntime7599Hours(sd::request::ReadLoadRuntime7599Hours),
            87 => Q::ReadLoadRuntime7599MinSec(sd::request::ReadLoadRuntime7599MinSec),
            88 => Q::ResetLoadRuntime7599(sd::request::ResetLoadRuntime7599),
            89 => Q::ReadLoadRuntime100Hours(sd::request::ReadLoadRuntime100Hours),
            90 => Q::ReadLoadRuntime100MinSec(sd::request::ReadLoadRuntime100MinSec),
            91 => Q::ResetLoadRuntime100(sd::request::ResetLoadRuntime100),
            92..=94 => Q::ReadStallEventCounter(sd::request::ReadStallEventCounter),
            95 => Q::ResetStallEventCounter(sd::request::ResetStallEventCounter),
            _ => Q::ReadPowerUpCycles(sd::request::ReadPowerUpCycles),
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
