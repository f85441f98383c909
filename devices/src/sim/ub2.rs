//! A simulated UB2 motorized capacitor (SB-70).
//!
//! Behaviour follows the document; where it is silent the choice is stated here:
//! - a movement trigger while a movement runs is refused with 0x91 (incompatible status);
//! - a completion check for another movement than the last one triggered answers 0x53;
//! - the reference run (→ preset → lower factory limit → preset) reports no step loss
//!   (the document lists no 0x5400 for it, ub2-e31);
//! - a current above its firmware maximum is refused with 0x94 (ub2-e08);
//! - a lower customer limit above the upper one (or the reverse) is refused with 0x93, like one
//!   outside the factory limits;
//! - the baud rate is stored and reported nowhere else: a simulated line has no baud rate to
//!   change;
//! - a frame with a bad checksum addressed to this device gets 0x92; a frame that does not
//!   start with 0xAA, or is for another address, is ignored (§2.1); one too short to hold a
//!   code is ignored too.
//!
//! [`Ub2Sim::msb_first`] makes it a device built to the document's examples rather than its
//! text (erratum ub2-e01): it reads and writes every multi-byte number most significant byte
//! first, so a request it gets means to it what the bytes mean big-endian, and its replies
//! carry its values big-endian. The 8-bit sum is the same either way.

use std::time::Duration;

use busspec_protocols::ub2::{
    self, response, BaudRateIndex, Capacitance, ModeOfOperation, Request, Response, Ub2,
};
use busspec_protocols::{DecodeError, Framing, Protocol};

use busspec_link::sim::{reply, swap_numbers, Device};

/// Micro-steps per full step (§3.3).
pub const MICRO_STEPS: u32 = 256;

/// The fixed (factory, firmware) parameters of a simulated capacitor.
#[derive(Debug, Clone, PartialEq)]
pub struct Ub2Config {
    /// The C-curve: (full-step position, capacitance), positions rising, at most 500 entries.
    pub c_curve: Vec<(u16, Capacitance)>,
    /// Upper factory limit as a full-step position (the lower one is position 0, §3.2).
    pub upper_factory_full_steps: u16,
    pub preset_full_steps: u16,
    pub cmin_nom: Capacitance,
    pub cmax_nom: Capacitance,
    pub i_idle_max: u8,
    pub i_drive_max: u8,
    /// Drive speed at index 18, full steps per second; index 0 is 10 % of it (§5.1).
    pub max_speed: f64,
    /// Acceleration at index 18, full steps per second squared; index 0 is 10 % of it.
    pub max_acceleration: f64,
    pub firmware_version: [u8; 11],
    pub serial_number: [u8; 8],
    pub temperature: u8,
}

impl Default for Ub2Config {
    /// A 50-500 pF capacitor over 10,000 full steps, 200 C-curve entries.
    fn default() -> Self {
        let entries = 200u16;
        let span = 9950.0;
        let c_curve = (0..entries)
            .map(|i| {
                let steps = i * 50;
                let x = f64::from(steps) / span;
                // Vacuum capacitors are close to linear, a little steeper towards Cmax.
                let pf = 50.0 + 450.0 * (0.7 * x + 0.3 * x * x);
                (steps, Capacitance((pf * 100.0).round() as u32))
            })
            .collect();
        Ub2Config {
            c_curve,
            upper_factory_full_steps: 9950,
            preset_full_steps: 638,
            cmin_nom: Capacitance(5000),
            cmax_nom: Capacitance(50000),
            i_idle_max: 100,
            i_drive_max: 200,
            max_speed: 1000.0,
            max_acceleration: 4000.0,
            firmware_version: *b"20100433.00",
            serial_number: *b"##654321",
            temperature: 33,
        }
    }
}

/// One leg of a movement: from, to (micro-steps), and the speed profile.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Leg {
    from: u32,
    to: u32,
    speed: f64,
    acceleration: f64,
}

impl Leg {
    fn distance(&self) -> f64 {
        f64::from(self.from.abs_diff(self.to))
    }

    /// Duration of a trapezoidal (or, if short, triangular) speed profile.
    fn duration(&self) -> f64 {
        let (d, v, a) = (self.distance(), self.speed, self.acceleration);
        if d == 0.0 {
            return 0.0;
        }
        if v * v / a >= d {
            2.0 * (d / a).sqrt()
        } else {
            v / a + d / v
        }
    }

    /// Distance covered after `t` seconds.
    fn covered(&self, t: f64) -> f64 {
        let (d, a) = (self.distance(), self.acceleration);
        let total = self.duration();
        if t >= total {
            return d;
        }
        let v = self.speed.min((d * a).sqrt());
        let ta = v / a;
        if t < ta {
            0.5 * a * t * t
        } else if t < total - ta {
            0.5 * a * ta * ta + v * (t - ta)
        } else {
            d - 0.5 * a * (total - t) * (total - t)
        }
    }

    fn position(&self, t: f64) -> u32 {
        let c = self.covered(t).round() as u32;
        if self.to >= self.from {
            self.from.saturating_add(c).min(self.to)
        } else {
            self.from.saturating_sub(c).max(self.to)
        }
    }
}

/// A movement under way or finished.
#[derive(Debug, Clone, PartialEq)]
pub struct Movement {
    /// First code byte of the trigger (0x10 reference run, 0x20 go-to-capacitance, ...).
    pub trigger: u8,
    pub started: Duration,
    legs: Vec<Leg>,
    /// Micro-steps lost: the capacitor stops this short of the target.
    pub lost_micro_steps: u32,
}

impl Movement {
    fn duration(&self) -> Duration {
        Duration::from_secs_f64(self.legs.iter().map(Leg::duration).sum())
    }

    fn finished(&self, now: Duration) -> bool {
        now >= self.started + self.duration()
    }

    fn end(&self) -> u32 {
        let last = self.legs.last().map_or(0, |l| l.to);
        let first = self.legs.first().map_or(last, |l| l.from);
        if last >= first {
            last.saturating_sub(self.lost_micro_steps)
        } else {
            last.saturating_add(self.lost_micro_steps)
        }
    }

    fn position(&self, now: Duration) -> u32 {
        if self.finished(now) {
            return self.end();
        }
        let mut t = now.saturating_sub(self.started).as_secs_f64();
        for leg in &self.legs {
            let d = leg.duration();
            if t < d {
                return leg.position(t);
            }
            t -= d;
        }
        self.end()
    }
}

/// A simulated UB2 capacitor.
#[derive(Debug, Clone, PartialEq)]
pub struct Ub2Sim {
    pub config: Ub2Config,
    pub address: u8,
    pub baud_rate: BaudRateIndex,
    pub mode: ModeOfOperation,
    pub acceleration_index: u8,
    pub speed_index: u8,
    pub idle_current: u8,
    pub drive_current: u8,
    pub lower_customer_limit: Capacitance,
    pub upper_customer_limit: Capacitance,
    pub stored_positions: [u16; 10],
    /// Status error byte (§6.6.1); the RESET bit is set at power-up and cleared when read.
    pub error_bits: ub2::StatusErrorBits,
    /// Position in micro-steps when no movement is recorded.
    pub position: u32,
    pub movement: Option<Movement>,
    /// Micro-steps the next movement will lose (a fault to provoke 0x5400).
    pub lose_steps_next_move: u32,
    /// Multi-byte numbers travel most significant byte first, as the document's examples print
    /// them, not little-endian as its text and the spec say (ub2-e01).
    pub msb_first: bool,
}

impl Ub2Sim {
    pub fn new(address: u8) -> Self {
        Self::with_config(address, Ub2Config::default())
    }

    pub fn with_config(address: u8, config: Ub2Config) -> Self {
        let lower = config.c_curve.first().map_or(Capacitance(0), |e| e.1);
        let mut sim = Ub2Sim {
            address,
            baud_rate: BaudRateIndex::Baud19200,
            mode: ModeOfOperation::OpenLoopControl,
            acceleration_index: 5,
            speed_index: 7,
            idle_current: 40,
            drive_current: 110,
            lower_customer_limit: lower,
            upper_customer_limit: lower,
            stored_positions: [0; 10],
            error_bits: ub2::StatusErrorBits::RESET,
            position: u32::from(config.preset_full_steps) * MICRO_STEPS,
            movement: None,
            lose_steps_next_move: 0,
            msb_first: false,
            config,
        };
        sim.upper_customer_limit = sim.upper_factory_limit();
        sim
    }

    /// The same device, sending and reading its multi-byte numbers most significant byte first
    /// (`true`) or little-endian as the spec says (`false`, the default).
    pub fn msb_first(mut self, msb_first: bool) -> Self {
        self.msb_first = msb_first;
        self
    }

    /// Capacitance at a micro-step position, interpolated linearly along the C-curve.
    pub fn capacitance_at(&self, micro_steps: u32) -> Capacitance {
        let x = f64::from(micro_steps) / f64::from(MICRO_STEPS);
        let curve = &self.config.c_curve;
        let (Some(first), Some(last)) = (curve.first(), curve.last()) else {
            return Capacitance(0);
        };
        if x <= f64::from(first.0) {
            return first.1;
        }
        for w in curve.windows(2) {
            let ((x0, c0), (x1, c1)) = (w[0], w[1]);
            if x <= f64::from(x1) && x1 > x0 {
                let f = (x - f64::from(x0)) / f64::from(x1 - x0);
                let c = f64::from(c0.0) + f * (f64::from(c1.0) - f64::from(c0.0));
                return Capacitance(c.round() as u32);
            }
        }
        last.1
    }

    /// The micro-step position of a capacitance (the C-curve inverted), clamped to the curve.
    pub fn position_of(&self, c: Capacitance) -> u32 {
        let curve = &self.config.c_curve;
        let (Some(first), Some(last)) = (curve.first(), curve.last()) else {
            return 0;
        };
        let ms = |steps: f64| (steps * f64::from(MICRO_STEPS)).round() as u32;
        if c <= first.1 {
            return ms(f64::from(first.0));
        }
        for w in curve.windows(2) {
            let ((x0, c0), (x1, c1)) = (w[0], w[1]);
            if c <= c1 && c1 > c0 {
                let f = (f64::from(c.0) - f64::from(c0.0)) / (f64::from(c1.0) - f64::from(c0.0));
                return ms(f64::from(x0) + f * (f64::from(x1) - f64::from(x0)));
            }
        }
        ms(f64::from(last.0))
    }

    pub fn lower_factory_limit(&self) -> Capacitance {
        self.capacitance_at(0)
    }

    pub fn upper_factory_limit(&self) -> Capacitance {
        self.capacitance_at(u32::from(self.config.upper_factory_full_steps) * MICRO_STEPS)
    }

    /// Position in micro-steps at `now`.
    pub fn position_at(&self, now: Duration) -> u32 {
        match &self.movement {
            Some(m) => m.position(now),
            None => self.position,
        }
    }

    pub fn moving(&self, now: Duration) -> bool {
        self.movement.as_ref().is_some_and(|m| !m.finished(now))
    }

    fn index_value(max: f64, index: u8) -> f64 {
        max * (0.1 + 0.9 * f64::from(index.min(18)) / 18.0)
    }

    /// Drive speed, micro-steps per second.
    pub fn speed(&self) -> f64 {
        Self::index_value(self.config.max_speed, self.speed_index) * f64::from(MICRO_STEPS)
    }

    /// Acceleration, micro-steps per second squared.
    pub fn acceleration(&self) -> f64 {
        Self::index_value(self.config.max_acceleration, self.acceleration_index)
            * f64::from(MICRO_STEPS)
    }

    fn leg(&self, from: u32, to: u32) -> Leg {
        Leg {
            from,
            to,
            speed: self.speed(),
            acceleration: self.acceleration(),
        }
    }

    /// Starts a movement to `target` (micro-steps), clipped to the customer limits.
    fn start_movement(&mut self, trigger: u8, target: i64, now: Duration) -> Response {
        if self.moving(now) {
            return Response::NakIncompatibleStatus(response::NakIncompatibleStatus);
        }
        let here = self.position_at(now);
        let lo = i64::from(self.position_of(self.lower_customer_limit));
        let hi = i64::from(self.position_of(self.upper_customer_limit));
        let clipped = target < lo || target > hi;
        let to = target.clamp(lo, hi) as u32;
        let lost = std::mem::take(&mut self.lose_steps_next_move).min(here.abs_diff(to));
        // Without the encoder the controller cannot notice lost steps (§5.8).
        let lost = if self.mode == ModeOfOperation::EncoderDisabled {
            0
        } else {
            lost
        };
        self.position = here;
        self.movement = Some(Movement {
            trigger,
            started: now,
            legs: vec![self.leg(here, to)],
            lost_micro_steps: lost,
        });
        if clipped {
            Response::NakLimitReached(response::NakLimitReached)
        } else {
            Response::MovementStarted(response::MovementStarted)
        }
    }

    fn reference_run(&mut self, now: Duration) -> Response {
        if self.moving(now) {
            return Response::NakIncompatibleStatus(response::NakIncompatibleStatus);
        }
        let here = self.position_at(now);
        let preset = u32::from(self.config.preset_full_steps) * MICRO_STEPS;
        self.position = here;
        self.movement = Some(Movement {
            trigger: 0x10,
            started: now,
            legs: vec![
                self.leg(here, preset),
                self.leg(preset, 0),
                self.leg(0, preset),
            ],
            lost_micro_steps: 0,
        });
        Response::MovementStarted(response::MovementStarted)
    }

    fn completion(&self, trigger: u8, now: Duration) -> Response {
        match &self.movement {
            Some(m) if m.trigger == trigger => {
                if !m.finished(now) {
                    Response::MovementNotCompleted(response::MovementNotCompleted)
                } else if m.lost_micro_steps > 0 && trigger != 0x10 {
                    Response::MovementCompletedWithStepLoss(
                        response::MovementCompletedWithStepLoss {
                            lost_micro_steps: m.lost_micro_steps,
                        },
                    )
                } else {
                    Response::MovementCompleted(response::MovementCompleted)
                }
            }
            _ => Response::MovementNotTriggered(response::MovementNotTriggered),
        }
    }

    fn set_limit(&mut self, lower: bool, c: Capacitance) -> Response {
        let inside = c >= self.lower_factory_limit() && c <= self.upper_factory_limit();
        let ordered = if lower {
            c <= self.upper_customer_limit
        } else {
            c >= self.lower_customer_limit
        };
        if !(inside && ordered) {
            return Response::NakLimitReached(response::NakLimitReached);
        }
        if lower {
            self.lower_customer_limit = c;
            Response::SetLowerCustomerLimitAck(response::SetLowerCustomerLimitAck)
        } else {
            self.upper_customer_limit = c;
            Response::SetUpperCustomerLimitAck(response::SetUpperCustomerLimitAck)
        }
    }

    /// The answer to one decoded request at `now`; also applies its effect.
    pub fn respond(&mut self, request: &Request, now: Duration) -> Response {
        use Request as Q;
        use Response as R;
        let here = self.position_at(now);
        let full = |ms: u32| u16::try_from(ms / MICRO_STEPS).unwrap_or(u16::MAX);
        let steps = |s: i64| s * i64::from(MICRO_STEPS);
        match *request {
            Q::ReferenceRun(ub2::request::ReferenceRun) => self.reference_run(now),
            Q::GoToCapacitance(ub2::request::GoToCapacitance { target }) => {
                let lo = self.lower_customer_limit;
                let hi = self.upper_customer_limit;
                let pos = i64::from(self.position_of(target.clamp(lo, hi)));
                let r = self.start_movement(0x20, pos, now);
                if r == R::MovementStarted(ub2::response::MovementStarted)
                    && (target < lo || target > hi)
                {
                    R::NakLimitReached(ub2::response::NakLimitReached)
                } else {
                    r
                }
            }
            Q::GoToFullStepPosition(ub2::request::GoToFullStepPosition { target }) => {
                self.start_movement(0x21, steps(i64::from(target)), now)
            }
            Q::MoveFullSteps(ub2::request::MoveFullSteps { steps: s }) => {
                self.start_movement(0x22, i64::from(here) + steps(i64::from(s)), now)
            }
            Q::GoToCmin(ub2::request::GoToCmin) => {
                let to = i64::from(self.position_of(self.lower_customer_limit));
                self.start_movement(0x23, to, now)
            }
            Q::GoToCmax(ub2::request::GoToCmax) => {
                let to = i64::from(self.position_of(self.upper_customer_limit));
                self.start_movement(0x24, to, now)
            }
            Q::GoToMicroStepPosition(ub2::request::GoToMicroStepPosition { target }) => {
                self.start_movement(0x25, i64::from(target), now)
            }
            Q::MoveMicroSteps(ub2::request::MoveMicroSteps { steps: s }) => {
                self.start_movement(0x26, i64::from(here) + i64::from(s), now)
            }
            Q::GoToStoredPosition(ub2::request::GoToStoredPosition { index }) => {
                match self.stored_positions.get(usize::from(index)) {
                    Some(&p) => self.start_movement(0x27, steps(i64::from(p)), now),
                    None => R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange),
                }
            }
            Q::ReferenceRunStatus(ub2::request::ReferenceRunStatus) => self.completion(0x10, now),
            Q::GoToCapacitanceStatus(ub2::request::GoToCapacitanceStatus) => {
                self.completion(0x20, now)
            }
            Q::GoToFullStepPositionStatus(ub2::request::GoToFullStepPositionStatus) => {
                self.completion(0x21, now)
            }
            Q::MoveFullStepsStatus(ub2::request::MoveFullStepsStatus) => self.completion(0x22, now),
            Q::GoToCminStatus(ub2::request::GoToCminStatus) => self.completion(0x23, now),
            Q::GoToCmaxStatus(ub2::request::GoToCmaxStatus) => self.completion(0x24, now),
            Q::GoToMicroStepPositionStatus(ub2::request::GoToMicroStepPositionStatus) => {
                self.completion(0x25, now)
            }
            Q::MoveMicroStepsStatus(ub2::request::MoveMicroStepsStatus) => {
                self.completion(0x26, now)
            }
            Q::GoToStoredPositionStatus(ub2::request::GoToStoredPositionStatus) => {
                self.completion(0x27, now)
            }
            Q::SetAccelerationSpeedIndex(ub2::request::SetAccelerationSpeedIndex {
                acceleration_index,
                speed_index,
            }) => {
                if acceleration_index > 18 || speed_index > 18 {
                    return R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange);
                }
                self.acceleration_index = acceleration_index;
                self.speed_index = speed_index;
                R::SetAccelerationSpeedIndexAck(ub2::response::SetAccelerationSpeedIndexAck)
            }
            Q::SetCurrent(ub2::request::SetCurrent {
                idle_current,
                drive_current,
            }) => {
                if idle_current > self.config.i_idle_max || drive_current > self.config.i_drive_max
                {
                    return R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange);
                }
                self.idle_current = idle_current;
                self.drive_current = drive_current;
                R::SetCurrentAck(ub2::response::SetCurrentAck)
            }
            Q::SetSlaveAddress(ub2::request::SetSlaveAddress { address }) => {
                if !ub2::DEVICE_ADDRESSES.contains(&address) {
                    return R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange);
                }
                // The ACK still goes out from the old address (§5.3 example); see on_frame.
                self.address = address;
                R::SetSlaveAddressAck(ub2::response::SetSlaveAddressAck)
            }
            Q::SetBaudRate(ub2::request::SetBaudRate { baud_rate }) => {
                if baud_rate.name().is_none() {
                    return R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange);
                }
                self.baud_rate = baud_rate;
                R::SetBaudRateAck(ub2::response::SetBaudRateAck)
            }
            Q::SetLowerCustomerLimit(ub2::request::SetLowerCustomerLimit { limit }) => {
                self.set_limit(true, limit)
            }
            Q::SetUpperCustomerLimit(ub2::request::SetUpperCustomerLimit { limit }) => {
                self.set_limit(false, limit)
            }
            Q::StoreIndexedPosition(ub2::request::StoreIndexedPosition { index, position }) => {
                match self.stored_positions.get_mut(usize::from(index)) {
                    Some(slot) => {
                        *slot = position;
                        R::StoreIndexedPositionAck(ub2::response::StoreIndexedPositionAck)
                    }
                    None => R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange),
                }
            }
            Q::SetModeOfOperation(ub2::request::SetModeOfOperation { mode }) => {
                if self.moving(now) {
                    return R::NakIncompatibleStatus(ub2::response::NakIncompatibleStatus);
                }
                if mode.name().is_none() {
                    return R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange);
                }
                self.mode = mode;
                R::SetModeOfOperationAck(ub2::response::SetModeOfOperationAck)
            }
            Q::GetActualCapacitance(ub2::request::GetActualCapacitance) => {
                R::ActualCapacitance(ub2::response::ActualCapacitance {
                    capacitance: self.capacitance_at(here),
                })
            }
            Q::GetActualFullStepPosition(ub2::request::GetActualFullStepPosition) => {
                R::ActualFullStepPosition(ub2::response::ActualFullStepPosition {
                    full_steps: full(here),
                })
            }
            Q::GetMinimumCapacitance(ub2::request::GetMinimumCapacitance) => {
                R::MinimumCapacitance(ub2::response::MinimumCapacitance {
                    capacitance: self
                        .config
                        .c_curve
                        .iter()
                        .map(|e| e.1)
                        .min()
                        .unwrap_or_default(),
                })
            }
            Q::GetMaximumCapacitance(ub2::request::GetMaximumCapacitance) => {
                R::MaximumCapacitance(ub2::response::MaximumCapacitance {
                    capacitance: self
                        .config
                        .c_curve
                        .iter()
                        .map(|e| e.1)
                        .max()
                        .unwrap_or_default(),
                })
            }
            Q::GetAccelerationSpeed(ub2::request::GetAccelerationSpeed) => {
                R::AccelerationSpeed(ub2::response::AccelerationSpeed {
                    acceleration_index: self.acceleration_index,
                    speed_index: self.speed_index,
                })
            }
            Q::GetStatus(ub2::request::GetStatus) => {
                let error_bits = self.error_bits;
                // §6.6.1: "Reset indicator flag will be reset after reading".
                self.error_bits =
                    ub2::StatusErrorBits(error_bits.0 & !ub2::StatusErrorBits::RESET.0);
                R::Status(ub2::response::Status {
                    error_bits,
                    reserved: 0,
                })
            }
            Q::GetCCurveIndexedFullStepCapacitance(
                ub2::request::GetCCurveIndexedFullStepCapacitance { index },
            ) => match self.config.c_curve.get(usize::from(index)) {
                Some(&(full_steps, capacitance)) => R::CCurveEntry(ub2::response::CCurveEntry {
                    index,
                    full_steps,
                    capacitance,
                }),
                None => R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange),
            },
            Q::GetControllerTemperature(ub2::request::GetControllerTemperature) => {
                R::ControllerTemperature(ub2::response::ControllerTemperature {
                    temperature: self.config.temperature,
                })
            }
            Q::GetMicroStepPosition(ub2::request::GetMicroStepPosition) => {
                R::MicroStepPosition(ub2::response::MicroStepPosition { micro_steps: here })
            }
            Q::GetFirmwareVersion(ub2::request::GetFirmwareVersion) => {
                R::FirmwareVersion(ub2::response::FirmwareVersion {
                    firmware_version: self.config.firmware_version.into(),
                })
            }
            Q::GetSerialNumber(ub2::request::GetSerialNumber) => {
                R::SerialNumber(ub2::response::SerialNumber {
                    serial_number: self.config.serial_number.into(),
                })
            }
            Q::GetCminNom(ub2::request::GetCminNom) => R::CminNom(ub2::response::CminNom {
                capacitance: self.config.cmin_nom,
            }),
            Q::GetCmaxNom(ub2::request::GetCmaxNom) => R::CmaxNom(ub2::response::CmaxNom {
                capacitance: self.config.cmax_nom,
            }),
            Q::GetLowerCustomerLimit(ub2::request::GetLowerCustomerLimit) => {
                R::LowerCustomerLimit(ub2::response::LowerCustomerLimit {
                    capacitance: self.lower_customer_limit,
                })
            }
            Q::GetUpperCustomerLimit(ub2::request::GetUpperCustomerLimit) => {
                R::UpperCustomerLimit(ub2::response::UpperCustomerLimit {
                    capacitance: self.upper_customer_limit,
                })
            }
            Q::GetLowerFactoryLimit(ub2::request::GetLowerFactoryLimit) => {
                R::LowerFactoryLimit(ub2::response::LowerFactoryLimit {
                    capacitance: self.lower_factory_limit(),
                })
            }
            Q::GetUpperFactoryLimit(ub2::request::GetUpperFactoryLimit) => {
                R::UpperFactoryLimit(ub2::response::UpperFactoryLimit {
                    capacitance: self.upper_factory_limit(),
                })
            }
            Q::GetPresetCapacitance(ub2::request::GetPresetCapacitance) => {
                R::PresetCapacitance(ub2::response::PresetCapacitance {
                    capacitance: self
                        .capacitance_at(u32::from(self.config.preset_full_steps) * MICRO_STEPS),
                })
            }
            Q::GetPresetFullStepPosition(ub2::request::GetPresetFullStepPosition) => {
                R::PresetFullStepPosition(ub2::response::PresetFullStepPosition {
                    full_steps: u32::from(self.config.preset_full_steps),
                })
            }
            Q::GetStoredFullStepPosition(ub2::request::GetStoredFullStepPosition { index }) => {
                match self.stored_positions.get(usize::from(index)) {
                    Some(&full_steps) => {
                        R::StoredFullStepPosition(ub2::response::StoredFullStepPosition {
                            index,
                            full_steps,
                        })
                    }
                    None => R::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange),
                }
            }
            Q::GetModeOfOperation(ub2::request::GetModeOfOperation) => {
                R::ActualModeOfOperation(ub2::response::ActualModeOfOperation { mode: self.mode })
            }
        }
    }
}

impl Device for Ub2Sim {
    fn address(&self) -> u8 {
        self.address
    }

    fn on_frame(&mut self, frame: &[u8], now: Duration) -> Option<Vec<u8>> {
        // §2.1: a frame not starting with 0xAA is ignored; a frame for another slave too.
        if frame.first() != Some(&0xAA) || frame.get(1) != Some(&self.address) || frame.len() < 5 {
            return None;
        }
        let me = self.address;
        // An MSB-first device reads each number the other way round: what it understands is
        // what the frame with those bytes reversed says little-endian.
        let mut seen = frame.to_vec();
        if self.msb_first {
            if let Ok(d) = Ub2::decode_request(frame) {
                swap_numbers(&d.message, me, &mut seen);
            }
        }
        let response = match Ub2::decode_request(&seen) {
            Ok(d) => self.respond(&d.message, now),
            Err(DecodeError::ChecksumMismatch { .. }) => {
                Response::NakChecksumError(response::NakChecksumError)
            }
            // A value the spec's ranges forbid (an index, an address past 0x40, or a number an
            // MSB-first device reads the other way round): §7.1's 0x94, "given index is outside
            // of defined / allowed range".
            Err(DecodeError::InvalidValue { .. } | DecodeError::OutOfRange { .. }) => {
                Response::NakIndexOutOfRange(response::NakIndexOutOfRange)
            }
            Err(_) if !Ub2::checksum_ok(&seen) => {
                Response::NakChecksumError(response::NakChecksumError)
            }
            Err(_) => Response::NakUnknownCommand(response::NakUnknownCommand),
        };
        let mut out = reply::<Ub2>(&response, me)?;
        if self.msb_first {
            swap_numbers(&response, me, &mut out);
        }
        Some(out)
    }
}
