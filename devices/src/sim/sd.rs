//! A simulated SD-01/02 servo actuator.
//!
//! Behaviour follows the ICD; where it is silent the choice is stated here:
//! - positions slew linearly at the set velocity (no acceleration phase); the 12-bit position
//!   range (-2048..=2047 digits, ±180°) is not crossed, so a set point beyond it stops there;
//! - the freshness check (§3.1) counts the set point counter values skipped since the last set
//!   point (the first after power-up is taken as it is); more than `freshness_threshold` skipped
//!   (a repeated value counts as 15) loads the fail-safe position and sets the FRC status bit;
//!   skipped values within the threshold add to the dropped frames counter;
//! - positions are reported relative to the zero offset (§3.17); set points are taken in the
//!   same frame of reference;
//! - the status word is reported as it was before a reset (§3.15 does not say);
//! - a string byte beyond the string's length reads as character 0 (sd-e21 leaves it open);
//! - the total run-time counter advances with time since power-up; the load counters hold their
//!   configured values until reset;
//! - a frame that does not decode, or is for another ID, gets no reply (the ICD has no NAK,
//!   sd-e06); a broadcast gets one only where the spec says it is answered.

use std::time::Duration;

use busspec_protocols::sd::{self, ActuatorStatusBits, Angle, Request, Response, Sd, Velocity};
use busspec_protocols::Protocol;

use busspec_link::sim::{reply, Device};

/// Fixed parameters of a simulated actuator.
#[derive(Debug, Clone, PartialEq)]
pub struct SdConfig {
    /// Set point counter values that may be skipped (§3.1); 15 or more disables the check.
    pub freshness_threshold: u8,
    /// Where the actuator goes when the freshness check fails, in digits of 360/4096°.
    pub fail_safe_position: i16,
    pub serial_number: Vec<u8>,
    pub product_description: Vec<u8>,
    pub software_revision: Vec<u8>,
    pub hardware_revision: Vec<u8>,
    /// Total run-time at power-up, seconds.
    pub total_runtime_s: u64,
    /// Run-time per load band (0-24 %, 25-49 %, 50-74 %, 75-99 %, 100 %), seconds.
    pub load_runtime_s: [u64; 5],
    pub power_up_cycles: u16,
    pub bus_voltages: (sd::Voltage, sd::Voltage),
    pub temperatures: (sd::Temperature, sd::Temperature),
    pub humidity: u8,
}

impl Default for SdConfig {
    fn default() -> Self {
        SdConfig {
            freshness_threshold: 3,
            fail_safe_position: 0,
            serial_number: b"SD02-0001234".to_vec(),
            product_description: b"SD-02 servo actuator (busspec sim)"
                .iter()
                .take(32)
                .copied()
                .collect(),
            software_revision: b"2.4.1".to_vec(),
            hardware_revision: b"C".to_vec(),
            total_runtime_s: 1234 * 3600 + 56 * 60 + 7,
            load_runtime_s: [
                900 * 3600,
                250 * 3600 + 60,
                70 * 3600,
                14 * 3600 + 5,
                3600 + 1,
            ],
            power_up_cycles: 321,
            bus_voltages: (sd::Voltage(140), sd::Voltage(139)),
            temperatures: (sd::Temperature(85), sd::Temperature(90)),
            humidity: 45,
        }
    }
}

/// A simulated SD actuator.
#[derive(Debug, Clone, PartialEq)]
pub struct SdSim {
    pub config: SdConfig,
    pub id: u8,
    /// Encoder position (digits) at `since`, and the target it slews to.
    pub position: i16,
    pub target: i16,
    pub since: Duration,
    /// Set velocity, 0.1 °/s.
    pub velocity: i16,
    /// Encoder position taken as zero (§3.17).
    pub zero_offset: i16,
    /// Last host freshness counter received (§3.1).
    pub host_freshness: Option<u8>,
    /// Actuator freshness counter, decremented for each set point reply.
    pub actuator_freshness: u8,
    pub dropped_frames: u8,
    pub status_bits: ActuatorStatusBits,
    pub stall_events: u16,
    pub load_runtime_s: [u64; 5],
}

const MIN_POS: i16 = -2048;
const MAX_POS: i16 = 2047;

/// Wraps a value into the 12-bit two's-complement range.
fn wrap12(v: i32) -> i16 {
    (((v + 2048).rem_euclid(4096)) - 2048) as i16
}

impl SdSim {
    pub fn new(id: u8) -> Self {
        Self::with_config(id, SdConfig::default())
    }

    pub fn with_config(id: u8, config: SdConfig) -> Self {
        SdSim {
            load_runtime_s: config.load_runtime_s,
            config,
            id,
            position: 0,
            target: 0,
            since: Duration::ZERO,
            velocity: 900,
            zero_offset: 0,
            host_freshness: None,
            actuator_freshness: 0x0F,
            dropped_frames: 0,
            status_bits: ActuatorStatusBits(0),
            stall_events: 0,
        }
    }

    /// Slew rate in digits per second.
    fn rate(&self) -> f64 {
        f64::from(self.velocity.unsigned_abs()) * 0.1 * 4096.0 / 360.0
    }

    /// Encoder position at `now`.
    pub fn encoder_position(&self, now: Duration) -> i16 {
        let dt = now.saturating_sub(self.since).as_secs_f64();
        let moved = (self.rate() * dt).floor();
        let gap = f64::from(self.target) - f64::from(self.position);
        if gap.abs() <= moved {
            self.target
        } else {
            (f64::from(self.position) + moved.copysign(gap)) as i16
        }
    }

    /// Reported position at `now`: relative to the zero offset.
    pub fn position_at(&self, now: Duration) -> Angle {
        Angle(wrap12(
            i32::from(self.encoder_position(now)) - i32::from(self.zero_offset),
        ))
    }

    pub fn moving(&self, now: Duration) -> bool {
        self.encoder_position(now) != self.target && self.velocity != 0
    }

    fn retarget(&mut self, encoder_target: i16, now: Duration) {
        self.position = self.encoder_position(now);
        self.since = now;
        self.target = encoder_target.clamp(MIN_POS, MAX_POS);
    }

    fn set_point(&mut self, freshness: u8, position: Angle, now: Duration) {
        let f = freshness & 0x0F;
        let violated = match self.host_freshness {
            Some(last) if self.config.freshness_threshold < 15 => {
                let skipped = (f + 16 - last - 1) % 16;
                if skipped > self.config.freshness_threshold || f == last {
                    true
                } else {
                    self.dropped_frames = self.dropped_frames.saturating_add(skipped);
                    false
                }
            }
            _ => false,
        };
        self.host_freshness = Some(f);
        let target = if violated {
            self.status_bits = ActuatorStatusBits(self.status_bits.0 | ActuatorStatusBits::FRC.0);
            self.config.fail_safe_position
        } else {
            // Set points are relative to the zero offset, like reported positions.
            let raw = i32::from(wrap12(i32::from(position.0)));
            (raw + i32::from(self.zero_offset)).clamp(i32::from(MIN_POS), i32::from(MAX_POS)) as i16
        };
        self.retarget(target, now);
    }

    fn runtime(seconds: u64) -> (u16, u8, u8) {
        let hours = u16::try_from(seconds / 3600).unwrap_or(u16::MAX);
        ((hours), ((seconds / 60) % 60) as u8, (seconds % 60) as u8)
    }

    fn string(&self, which: u8) -> &[u8] {
        match which {
            0 => &self.config.serial_number,
            1 => &self.config.product_description,
            2 => &self.config.software_revision,
            _ => &self.config.hardware_revision,
        }
    }

    fn character(&self, which: u8, byte_number: u8) -> (u8, u8) {
        let s = self.string(which);
        let len = s.len().min(0x20);
        let c = if usize::from(byte_number) < len {
            s[usize::from(byte_number)]
        } else {
            0
        };
        (c, len as u8)
    }

    fn current(&self, now: Duration) -> sd::Current {
        if self.moving(now) {
            sd::Current(60)
        } else {
            sd::Current(15)
        }
    }

    fn reset_load(&mut self, band: usize) -> u16 {
        let before = Self::runtime(self.load_runtime_s[band]).0;
        self.load_runtime_s[band] = 0;
        before
    }

    /// The answer to one decoded request at `now`; also applies its effect.
    pub fn respond(&mut self, request: &Request, now: Duration) -> Response {
        use Request as Q;
        use Response as R;
        let hours = |s: u64| Self::runtime(s).0;
        let min_sec = |s: u64| {
            let (_, m, sec) = Self::runtime(s);
            (m, sec)
        };
        let total = self.config.total_runtime_s + now.as_secs();
        let load = self.load_runtime_s;
        match *request {
            Q::SetPoint(sd::request::SetPoint {
                freshness,
                position,
            }) => {
                self.set_point(freshness, position, now);
                self.actuator_freshness = self.actuator_freshness.wrapping_sub(1) & 0x0F;
                R::SetPointReply(sd::response::SetPointReply {
                    freshness: self.actuator_freshness,
                    position: self.position_at(now),
                })
            }
            Q::ReadActualPosition(sd::request::ReadActualPosition) => {
                R::ActualPosition(sd::response::ActualPosition {
                    position: self.position_at(now),
                })
            }
            Q::SetVelocity(sd::request::SetVelocity { set_velocity }) => {
                let here = self.encoder_position(now);
                self.position = here;
                self.since = now;
                self.velocity = set_velocity.0;
                R::SetVelocityReply(sd::response::SetVelocityReply {
                    actual_velocity: self.actual_velocity(now),
                })
            }
            Q::ReadActualVelocity(sd::request::ReadActualVelocity) => {
                R::ActualVelocity(sd::response::ActualVelocity {
                    actual_velocity: self.actual_velocity(now),
                })
            }
            Q::SetServoId(sd::request::SetServoId { new_id }) => {
                self.id = new_id;
                R::SetServoIdReply(sd::response::SetServoIdReply { new_id })
            }
            Q::ReadServoId(sd::request::ReadServoId) => {
                R::ServoId(sd::response::ServoId { id: self.id })
            }
            Q::ReadCurrentConsumption(sd::request::ReadCurrentConsumption) => {
                R::CurrentConsumption(sd::response::CurrentConsumption {
                    current: self.current(now),
                })
            }
            Q::ReadBusVoltages(sd::request::ReadBusVoltages) => {
                R::BusVoltages(sd::response::BusVoltages {
                    power_bus_1_voltage: self.config.bus_voltages.0,
                    power_bus_2_voltage: self.config.bus_voltages.1,
                })
            }
            Q::ReadExtendedCurrentConsumption(sd::request::ReadExtendedCurrentConsumption) => {
                R::ExtendedCurrentConsumption(sd::response::ExtendedCurrentConsumption {
                    current: self.current(now),
                })
            }
            Q::ReadTemperatures(sd::request::ReadTemperatures) => {
                R::Temperatures(sd::response::Temperatures {
                    motor_temperature: self.config.temperatures.0,
                    pcb_temperature: self.config.temperatures.1,
                })
            }
            Q::ReadHumidity(sd::request::ReadHumidity) => R::Humidity(sd::response::Humidity {
                humidity: self.config.humidity,
            }),
            Q::ReadSkippedFramesCounter(sd::request::ReadSkippedFramesCounter) => {
                R::SkippedFramesCounter(sd::response::SkippedFramesCounter {
                    host_freshness_counter: self.host_freshness.unwrap_or(0),
                    dropped_frames: self.dropped_frames,
                })
            }
            Q::ResetDroppedFramesCounter(sd::request::ResetDroppedFramesCounter) => {
                self.dropped_frames = 0;
                R::DroppedFramesCounterReset(sd::response::DroppedFramesCounterReset {
                    host_freshness_counter: self.host_freshness.unwrap_or(0),
                })
            }
            Q::ReadActuatorStatusWord(sd::request::ReadActuatorStatusWord) => {
                R::ActuatorStatusWord(sd::response::ActuatorStatusWord {
                    status_bits: self.status_bits,
                    status_arg2: 0,
                })
            }
            Q::ResetActuatorStatusWord(sd::request::ResetActuatorStatusWord) => {
                let before = self.status_bits;
                self.status_bits = ActuatorStatusBits(0);
                R::ActuatorStatusWord(sd::response::ActuatorStatusWord {
                    status_bits: before,
                    status_arg2: 0,
                })
            }
            Q::ResetDefaultRoleAndErrorFlags(sd::request::ResetDefaultRoleAndErrorFlags) => {
                self.status_bits = ActuatorStatusBits(0);
                R::ResetDefaultRoleAndErrorFlagsReply(
                    sd::response::ResetDefaultRoleAndErrorFlagsReply,
                )
            }
            Q::SetCurrentPositionAsZero(sd::request::SetCurrentPositionAsZero) => {
                let here = self.encoder_position(now);
                self.zero_offset = here;
                R::SetCurrentPositionAsZeroReply(sd::response::SetCurrentPositionAsZeroReply {
                    zero_offset: Angle(here),
                })
            }
            Q::ReadCurrentZeroOffset(sd::request::ReadCurrentZeroOffset) => {
                R::CurrentZeroOffset(sd::response::CurrentZeroOffset {
                    zero_offset: Angle(self.zero_offset),
                })
            }
            Q::ResetZeroOffset(sd::request::ResetZeroOffset) => {
                self.zero_offset = 0;
                R::ResetZeroOffsetReply(sd::response::ResetZeroOffsetReply)
            }
            Q::ReadElectronicSerialNumber(sd::request::ReadElectronicSerialNumber {
                byte_number,
            }) => {
                let (character, string_length) = self.character(0, byte_number);
                R::ElectronicSerialNumberCharacter(sd::response::ElectronicSerialNumberCharacter {
                    character,
                    string_length,
                })
            }
            Q::ReadProductDescription(sd::request::ReadProductDescription { byte_number }) => {
                let (character, string_length) = self.character(1, byte_number);
                R::ProductDescriptionCharacter(sd::response::ProductDescriptionCharacter {
                    character,
                    string_length,
                })
            }
            Q::ReadSoftwareRevision(sd::request::ReadSoftwareRevision { byte_number }) => {
                let (character, string_length) = self.character(2, byte_number);
                R::SoftwareRevisionCharacter(sd::response::SoftwareRevisionCharacter {
                    character,
                    string_length,
                })
            }
            Q::ReadHardwareRevision(sd::request::ReadHardwareRevision { byte_number }) => {
                let (character, string_length) = self.character(3, byte_number);
                R::HardwareRevisionCharacter(sd::response::HardwareRevisionCharacter {
                    character,
                    string_length,
                })
            }
            Q::ReadTotalRuntimeHours(sd::request::ReadTotalRuntimeHours) => {
                R::TotalRuntimeHours(sd::response::TotalRuntimeHours {
                    runtime_hours: hours(total),
                })
            }
            Q::ReadTotalRuntimeMinSec(sd::request::ReadTotalRuntimeMinSec) => {
                let (runtime_minutes, runtime_seconds) = min_sec(total);
                R::TotalRuntimeMinSec(sd::response::TotalRuntimeMinSec {
                    runtime_minutes,
                    runtime_seconds,
                })
            }
            Q::ReadLoadRuntime024Hours(sd::request::ReadLoadRuntime024Hours) => {
                R::LoadRuntime024Hours(sd::response::LoadRuntime024Hours {
                    runtime_hours: hours(load[0]),
                })
            }
            Q::ReadLoadRuntime024MinSec(sd::request::ReadLoadRuntime024MinSec) => {
                let (runtime_minutes, runtime_seconds) = min_sec(load[0]);
                R::LoadRuntime024MinSec(sd::response::LoadRuntime024MinSec {
                    runtime_minutes,
                    runtime_seconds,
                })
            }
            Q::ResetLoadRuntime024(sd::request::ResetLoadRuntime024) => {
                R::LoadRuntime024HoursBeforeReset(sd::response::LoadRuntime024HoursBeforeReset {
                    runtime_hours_before_reset: self.reset_load(0),
                })
            }
            Q::ReadLoadRuntime2549Hours(sd::request::ReadLoadRuntime2549Hours) => {
                R::LoadRuntime2549Hours(sd::response::LoadRuntime2549Hours {
                    runtime_hours: hours(load[1]),
                })
            }
            Q::ReadLoadRuntime2549MinSec(sd::request::ReadLoadRuntime2549MinSec) => {
                let (runtime_minutes, runtime_seconds) = min_sec(load[1]);
                R::LoadRuntime2549MinSec(sd::response::LoadRuntime2549MinSec {
                    runtime_minutes,
                    runtime_seconds,
                })
            }
            Q::ResetLoadRuntime2549(sd::request::ResetLoadRuntime2549) => {
                R::LoadRuntime2549HoursBeforeReset(sd::response::LoadRuntime2549HoursBeforeReset {
                    runtime_hours_before_reset: self.reset_load(1),
                })
            }
            Q::ReadLoadRuntime5074Hours(sd::request::ReadLoadRuntime5074Hours) => {
                R::LoadRuntime5074Hours(sd::response::LoadRuntime5074Hours {
                    runtime_hours: hours(load[2]),
                })
            }
            Q::ReadLoadRuntime5074MinSec(sd::request::ReadLoadRuntime5074MinSec) => {
                let (runtime_minutes, runtime_seconds) = min_sec(load[2]);
                R::LoadRuntime5074MinSec(sd::response::LoadRuntime5074MinSec {
                    runtime_minutes,
                    runtime_seconds,
                })
            }
            Q::ResetLoadRuntime5074(sd::request::ResetLoadRuntime5074) => {
                R::LoadRuntime5074HoursBeforeReset(sd::response::LoadRuntime5074HoursBeforeReset {
                    runtime_hours_before_reset: self.reset_load(2),
                })
            }
            Q::ReadLoadRuntime7599Hours(sd::request::ReadLoadRuntime7599Hours) => {
                R::LoadRuntime7599Hours(sd::response::LoadRuntime7599Hours {
                    runtime_hours: hours(load[3]),
                })
            }
            Q::ReadLoadRuntime7599MinSec(sd::request::ReadLoadRuntime7599MinSec) => {
                let (runtime_minutes, runtime_seconds) = min_sec(load[3]);
                R::LoadRuntime7599MinSec(sd::response::LoadRuntime7599MinSec {
                    runtime_minutes,
                    runtime_seconds,
                })
            }
            Q::ResetLoadRuntime7599(sd::request::ResetLoadRuntime7599) => {
                R::LoadRuntime7599HoursBeforeReset(sd::response::LoadRuntime7599HoursBeforeReset {
                    runtime_hours_before_reset: self.reset_load(3),
                })
            }
            Q::ReadLoadRuntime100Hours(sd::request::ReadLoadRuntime100Hours) => {
                R::LoadRuntime100Hours(sd::response::LoadRuntime100Hours {
                    runtime_hours: hours(load[4]),
                })
            }
            Q::ReadLoadRuntime100MinSec(sd::request::ReadLoadRuntime100MinSec) => {
                let (runtime_minutes, runtime_seconds) = min_sec(load[4]);
                R::LoadRuntime100MinSec(sd::response::LoadRuntime100MinSec {
                    runtime_minutes,
                    runtime_seconds,
                })
            }
            Q::ResetLoadRuntime100(sd::request::ResetLoadRuntime100) => {
                R::LoadRuntime100HoursBeforeReset(sd::response::LoadRuntime100HoursBeforeReset {
                    runtime_hours_before_reset: self.reset_load(4),
                })
            }
            Q::ReadStallEventCounter(sd::request::ReadStallEventCounter) => {
                R::StallEventCounter(sd::response::StallEventCounter {
                    stall_events: self.stall_events,
                })
            }
            Q::ResetStallEventCounter(sd::request::ResetStallEventCounter) => {
                let before = self.stall_events;
                self.stall_events = 0;
                R::StallEventCounterBeforeReset(sd::response::StallEventCounterBeforeReset {
                    stall_events_before_reset: before,
                })
            }
            Q::ReadPowerUpCycles(sd::request::ReadPowerUpCycles) => {
                R::PowerUpCycles(sd::response::PowerUpCycles {
                    power_up_cycles: self.config.power_up_cycles,
                })
            }
        }
    }

    fn actual_velocity(&self, now: Duration) -> Velocity {
        if !self.moving(now) {
            return Velocity(0);
        }
        let towards = self.target - self.encoder_position(now);
        Velocity((self.velocity.unsigned_abs() as i16).saturating_mul(towards.signum()))
    }
}

impl Device for SdSim {
    fn address(&self) -> u8 {
        self.id
    }

    fn on_frame(&mut self, frame: &[u8], now: Duration) -> Option<Vec<u8>> {
        let decoded = Sd::decode_request(frame).ok()?;
        let (to, request) = (decoded.address, decoded.message);
        let broadcast = Some(to) == Sd::BUS.broadcast_address;
        if !broadcast && to != self.id {
            return None;
        }
        let rules = request.command().broadcast;
        if broadcast && !rules.accepted {
            return None;
        }
        let response = self.respond(&request, now);
        if broadcast && !rules.answered {
            return None;
        }
        // Replies carry the actuator's own (after set_servo_id: new) ID (sd-e04).
        reply::<Sd>(&response, self.id)
    }
}
