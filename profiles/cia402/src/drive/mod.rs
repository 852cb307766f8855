//! The drive: the CiA 402 profile's behaviour on injected time.
//!
//! [`Drive::step`] is one tick: the master's set points ([`Setpoints`],
//! the RxPDO objects), whether they are valid ([`Link`]: OP, cyclic
//! outputs, the SM watchdog armed; the DC cycle), a hardware fault, the
//! parameters and the time go in; the statusword and the actual values
//! ([`Inputs`], the TxPDO objects), what the power stage does
//! ([`PowerStage`]) and an Emergency come out. It knows nothing of the
//! object dictionary ([`crate::Cia402Axis`] binds it to one) and never
//! reads a clock.
//!
//! What it implements, with the clauses of IEC 61800-7-201 / CiA 402-2
//! (and ETG.6010, which applies them to EtherCAT) each decision follows:
//!
//! * the PDS FSA ([`crate::state`]), commands only from a valid
//!   connection; the fault reset on the rising edge of controlword bit 7
//!   and only once the fault is gone (transition 15);
//! * quick stop (transition 11) per 6005Ah "Quick stop option code": 0
//!   coasts to Switch on disabled, 1/5 ramp on 6084h "Profile
//!   deceleration", 2/6 on 6085h "Quick stop deceleration", 3/4/7/8
//!   (current/voltage limit) on 6085h as well; 1-4 then transit to Switch
//!   on disabled (transition 12), 5-8 stay in Quick stop active holding
//!   the position until "enable operation" (16) or "disable voltage" (12);
//! * faults (13, 14) per 605Eh "Fault reaction option code": 0 coasts, 1
//!   ramps on 6084h, 2-4 on 6085h, then Fault with the power stage off;
//!   6003Fh "Error code" holds the fault's code, an Emergency carries it
//!   (CiA 301 / ETG.1000.6 Emergency: 0x8611 "following error", 0x8100
//!   communication, the board's own codes);
//! * the lost connection per 6007h "Abort connection option code" (1
//!   fault 0x8100, 2 disable voltage, 3 quick stop; 0 "no action" is not
//!   offered: a drive must not keep its torque without a master, see
//!   docs/SAFETY.md S2): ETG.6010 couples the PDS FSA to the EtherCAT
//!   state machine this way, the outputs being valid in OP only
//!   (ETG.1000.6);
//! * leaving Operation enabled by "disable operation" (5), "shutdown" (8)
//!   or "disable voltage" (9) switches the power stage off at once (605Ch,
//!   605Bh option code 0 "disable drive function"; the option objects are
//!   not offered);
//! * the modes ([`crate::mode`]) with their statusword bits 10, 12, 13
//!   (CiA 402-2 "operation mode specific" bits per mode), bit 11 when a
//!   limit cut a set point, bit 7 "warning" while the following error is
//!   outside its window, bit 9 "remote" while the controlword is
//!   processed;
//! * CSP set points interpolated linearly over the DC cycle (0x1C32:02)
//!   from the SYNC0 at which the core delivered them (ETG.6010: the
//!   interpolation time period is the cycle in DC mode), stepped in free
//!   run;
//! * following error monitoring in the position modes: 6065h window
//!   (0xFFFFFFFF switches it off), 6066h time out (ms; 0 = at once), 60F4h
//!   the value, fault 0x8611.

use crate::axis::{Axis, AxisModel, Demand, Limits, MAX_STEP_NS, MILLI, Motion};
use crate::mode::{HOMING_METHODS, Mode};
use crate::state::{Command, PowerState, control, status, transition};
use ecat_slave::coe::emergency::register;

/// Error code of a following error (CiA 402-2 / CiA 301 Emergency error
/// code 8611h "Following error").
pub const FOLLOWING_ERROR: u16 = 0x8611;
/// Error code of a lost connection: the master's cyclic outputs stopped
/// being valid while the power stage drove the motor (CiA 301 8100h
/// "Communication"; the data bytes say which reaction ran).
pub const CONNECTION_LOST: u16 = 0x8100;
/// Error code of a stalled firmware: the ESC's PDI watchdog expired and
/// cut the power stage (CiA 301 6010h "Software reset (watchdog)").
pub const FIRMWARE_STALLED: u16 = 0x6010;

const NS_PER_S: i128 = 1_000_000_000;
const NS_PER_MS: u64 = 1_000_000;

/// The parameters the drive reads every step (the RW objects of the
/// profile, defaults as in [`crate::objects`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Parameters {
    /// 6007h "Abort connection option code" (1 fault, 2 disable voltage,
    /// 3 quick stop; anything else is taken as 1).
    pub abort_connection_option: i16,
    /// 605Ah "Quick stop option code" (0..=8).
    pub quick_stop_option: i16,
    /// 605Eh "Fault reaction option code" (0..=4).
    pub fault_reaction_option: i16,
    /// 6065h "Following error window", inc (0xFFFFFFFF: no monitoring).
    pub following_error_window: u32,
    /// 6066h "Following error time out", ms.
    pub following_error_timeout_ms: u16,
    /// 6067h "Position window", inc (PP target reached).
    pub position_window: u32,
    /// 606Dh "Velocity window", inc/s (PV target reached).
    pub velocity_window: u16,
    /// 606Fh "Velocity threshold", inc/s (PV "speed 0", the end of a stop).
    pub velocity_threshold: u16,
    /// 6072h "Max torque", ‰ of the rated torque.
    pub max_torque: u16,
    /// 607Ch "Home offset", inc.
    pub home_offset: i32,
    /// 6080h "Max motor speed", inc/s (this drive's velocity unit).
    pub max_motor_speed: u32,
    /// 6081h "Profile velocity", inc/s (PP).
    pub profile_velocity: u32,
    /// 6083h "Profile acceleration", inc/s² (PP, PV).
    pub profile_acceleration: u32,
    /// 6084h "Profile deceleration", inc/s² (PP, PV, halt, quick stop 1/5).
    pub profile_deceleration: u32,
    /// 6085h "Quick stop deceleration", inc/s².
    pub quick_stop_deceleration: u32,
    /// 6098h "Homing method".
    pub homing_method: i8,
}

impl Parameters {
    /// The defaults of the profile's objects.
    pub const DEFAULT: Parameters = Parameters {
        abort_connection_option: 1,
        quick_stop_option: 2,
        fault_reaction_option: 2,
        following_error_window: 5_000,
        following_error_timeout_ms: 10,
        position_window: 10,
        velocity_window: 100,
        velocity_threshold: 100,
        max_torque: 3_000,
        home_offset: 0,
        max_motor_speed: 1_000_000,
        profile_velocity: 100_000,
        profile_acceleration: 1_000_000,
        profile_deceleration: 1_000_000,
        quick_stop_deceleration: 5_000_000,
        homing_method: 37,
    };
}

impl Default for Parameters {
    fn default() -> Self {
        Parameters::DEFAULT
    }
}

/// The master's set points (the profile's RxPDO objects).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Setpoints {
    /// 6040h "Controlword".
    pub controlword: u16,
    /// 6060h "Modes of operation" (0: no change).
    pub mode: i8,
    /// 607Ah "Target position", inc.
    pub target_position: i32,
    /// 60FFh "Target velocity", inc/s.
    pub target_velocity: i32,
    /// 6071h "Target torque", ‰.
    pub target_torque: i16,
}

/// Whether the set points come from a master that is there.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Link {
    /// The core's `Tick::outputs_valid`: OP, and the master's cyclic
    /// outputs applied since OP was entered.
    pub outputs_valid: bool,
    /// The core's `Tick::sm_watchdog_armed`: the outputs stop on their own
    /// when the master does.
    pub watchdog_armed: bool,
    /// The DC cycle (0x1C32:02) when the device runs DC-synchronous on
    /// SYNC0: cyclic set points are interpolated over it.
    pub dc_cycle_ns: Option<u32>,
}

impl Link {
    /// The controlword counts: valid cyclic outputs under an armed SM
    /// watchdog (docs/SAFETY.md S1).
    pub const fn connected(&self) -> bool {
        self.outputs_valid && self.watchdog_armed
    }
}

/// What the drive reports (the profile's TxPDO objects).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Inputs {
    /// 6041h "Statusword".
    pub statusword: u16,
    /// 6061h "Modes of operation display".
    pub mode_display: i8,
    /// 6064h "Position actual value", inc (modulo 2³²).
    pub position: i32,
    /// 606Ch "Velocity actual value", inc/s.
    pub velocity: i32,
    /// 6077h "Torque actual value", ‰.
    pub torque: i16,
    /// 60F4h "Following error actual value", inc (position modes).
    pub following_error: i32,
    /// 6062h "Position demand value", inc (modulo 2³²).
    pub position_demand: i32,
    /// 603Fh "Error code" (0: none).
    pub error_code: u16,
}

/// What the power stage does until the next step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PowerStage {
    /// The power stage carries current.
    pub enabled: bool,
    /// The torque it produces, ‰ (0 when not enabled).
    pub torque: i16,
}

/// The outcome of one [`Drive::step`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Report {
    /// The values for the master.
    pub inputs: Inputs,
    /// The power stage.
    pub power_stage: PowerStage,
    /// A fault happened in this step: its error code, for an Emergency.
    pub emergency: Option<u16>,
    /// The error register bits (0x1001) of the latched fault.
    pub error_register: u8,
}

/// A braking ramp of Quick stop active or Fault reaction active.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Ramp {
    /// inc/s²; the ramp's velocity falls by it.
    deceleration: i64,
    /// The ramp's velocity, inc/s.
    velocity: i64,
    /// The state at standstill (Switch on disabled, Fault, or Quick stop
    /// active itself: hold the position).
    then: PowerState,
    /// Standstill reached (holding).
    done: bool,
}

/// A cyclic position set point being interpolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Segment {
    from_m: i64,
    to_m: i64,
    t0_ns: u64,
    len_ns: u64,
}

impl Segment {
    fn at(&self, now_ns: u64) -> i64 {
        let elapsed = now_ns.saturating_sub(self.t0_ns);
        if self.len_ns == 0 || elapsed >= self.len_ns {
            return self.to_m;
        }
        let span = i128::from(self.to_m) - i128::from(self.from_m);
        let part = span * i128::from(elapsed) / i128::from(self.len_ns);
        sat(i128::from(self.from_m) + part)
    }
}

fn sat(v: i128) -> i64 {
    i64::try_from(v).unwrap_or(if v < 0 { i64::MIN } else { i64::MAX })
}

fn sat_i32(v: i64) -> i32 {
    i32::try_from(v).unwrap_or(if v < 0 { i32::MIN } else { i32::MAX })
}

fn sat_i16(v: i64) -> i16 {
    i16::try_from(v).unwrap_or(if v < 0 { i16::MIN } else { i16::MAX })
}

/// `v` moved towards `to` by at most `by` (≥ 0).
fn towards(v: i128, to: i128, by: i128) -> i128 {
    if v < to {
        v.saturating_add(by).min(to)
    } else {
        v.saturating_sub(by).max(to)
    }
}

/// The velocity change a rate (inc/s²) gives over `dt_ns`.
fn delta_v(rate: i64, dt_ns: u64) -> i128 {
    i128::from(rate.max(0)).saturating_mul(i128::from(dt_ns)) / NS_PER_S
}

/// Milli-increments covered at `v` inc/s over `dt_ns`.
fn distance(v: i128, dt_ns: u64) -> i128 {
    v.saturating_mul(i128::from(dt_ns))
        .saturating_mul(i128::from(MILLI))
        / NS_PER_S
}

/// The unwrapped position (milli-inc) of a 32-bit position `target` that
/// lies nearest to `reference_m` (CiA 402 positions wrap modulo 2³²).
pub fn unwrap_near(target: i32, reference_m: i64) -> i64 {
    let reference = reference_m.div_euclid(MILLI);
    let delta = i64::from(target.wrapping_sub(reference as i32));
    reference.saturating_add(delta).saturating_mul(MILLI)
}

/// The error register bits (CiA 301 1001h) of an error code's class.
pub const fn error_register_bits(code: u16) -> u8 {
    match code >> 12 {
        0 => 0,
        2 => register::CURRENT,
        3 => register::VOLTAGE,
        4 => register::TEMPERATURE,
        8 if code >> 8 == 0x81 => register::COMMUNICATION,
        _ => register::PROFILE,
    }
}

/// The CiA 402 drive on axis `A`. See the module documentation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Drive<A: Axis = AxisModel> {
    axis: A,
    state: PowerState,
    mode: Mode,
    last_controlword: u16,
    last_ns: Option<u64>,
    error_code: u16,
    ramp: Option<Ramp>,
    /// Position demand, milli-inc.
    demand_m: i64,
    /// Velocity demand of the profile generators (PP, PV), inc/s.
    velocity_demand: i64,
    segment: Option<Segment>,
    pp_target_m: i64,
    pp_ack: bool,
    homing_attained: bool,
    homing_error: bool,
    /// Since when the following error is outside its window.
    following_since: Option<u64>,
    /// The following error timed out (statusword bit 13 until reset).
    following_fault: bool,
    warning: bool,
}

impl<A: Axis + Default> Default for Drive<A> {
    fn default() -> Self {
        Drive::new(A::default())
    }
}

impl<A: Axis> Drive<A> {
    /// A drive on `axis`, Not ready to switch on, in CSP.
    pub fn new(axis: A) -> Self {
        let mut drive = Drive {
            axis,
            state: PowerState::NotReadyToSwitchOn,
            mode: Mode::CyclicPosition,
            last_controlword: 0,
            last_ns: None,
            error_code: 0,
            ramp: None,
            demand_m: 0,
            velocity_demand: 0,
            segment: None,
            pp_target_m: 0,
            pp_ack: false,
            homing_attained: false,
            homing_error: false,
            following_since: None,
            following_fault: false,
            warning: false,
        };
        drive.reset();
        drive
    }

    /// Back to the power-on state (a power cycle of the drive's logic),
    /// keeping the axis: Not ready to switch on, no fault, CSP.
    pub fn reset(&mut self) {
        let demand_m = self.axis.motion().position_m;
        self.state = PowerState::NotReadyToSwitchOn;
        self.mode = Mode::CyclicPosition;
        self.last_controlword = 0;
        self.last_ns = None;
        self.error_code = 0;
        self.ramp = None;
        self.demand_m = demand_m;
        self.velocity_demand = 0;
        self.segment = None;
        self.pp_target_m = demand_m;
        self.pp_ack = false;
        self.homing_attained = false;
        self.homing_error = false;
        self.following_since = None;
        self.following_fault = false;
        self.warning = false;
    }

    /// The PDS state.
    pub fn state(&self) -> PowerState {
        self.state
    }

    /// The mode of operation (0x6061).
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The latched error code (0x603F; 0 without fault).
    pub fn error_code(&self) -> u16 {
        self.error_code
    }

    /// The axis.
    pub fn axis(&self) -> &A {
        &self.axis
    }

    /// The axis, mutably (a test moves the simulated load).
    pub fn axis_mut(&mut self) -> &mut A {
        &mut self.axis
    }

    /// Whether the power stage carries current (until the next step).
    pub fn power_stage_enabled(&self) -> bool {
        self.state.may_drive()
    }

    /// The firmware stalled and the ESC's PDI watchdog cut the power
    /// stage (hardware did it; the drive learns it now): Fault 0x6010
    /// without a ramp, so nothing drives when the firmware runs again.
    /// Returns the error code for an Emergency if it is new.
    pub fn power_cut(&mut self) -> Option<u16> {
        self.ramp = None;
        let new = self.state != PowerState::Fault;
        if new {
            self.error_code = FIRMWARE_STALLED;
        }
        self.state = PowerState::Fault;
        new.then_some(FIRMWARE_STALLED)
    }

    /// One tick at `now_ns`. See the module documentation.
    pub fn step(
        &mut self,
        sp: &Setpoints,
        link: Link,
        hardware_fault: Option<u16>,
        p: &Parameters,
        now_ns: u64,
    ) -> Report {
        let dt = self
            .last_ns
            .map_or(0, |t| now_ns.saturating_sub(t))
            .min(MAX_STEP_NS);
        self.last_ns = Some(now_ns);
        let connected = link.connected();
        let mut emergency = None;
        // Transition 1: the drive is initialised at once.
        if self.state == PowerState::NotReadyToSwitchOn {
            self.state = PowerState::SwitchOnDisabled;
        }
        // 0x6060: a supported mode replaces the display; 0 and unknown
        // codes leave it.
        if let Some(m) = Mode::from_code(i64::from(sp.mode))
            && m != self.mode
        {
            self.mode = m;
            self.restart_generators();
        }
        // Transition 13: a fault from the hardware.
        if let Some(code) = hardware_fault {
            emergency = emergency.or(self.fault(code, p));
        }
        let cw = if connected { sp.controlword } else { 0 };
        let rising = cw & !self.last_controlword;
        if connected {
            self.command(cw, rising, hardware_fault.is_some(), p);
        } else {
            emergency = emergency.or(self.connection_lost(p));
        }
        self.last_controlword = cw;

        let limits = Limits {
            max_velocity: i64::from(p.max_motor_speed),
            max_torque: i64::from(p.max_torque),
        };
        let (demand, cut) = self.demand(sp, cw, rising, link, p, now_ns, dt);
        let motion = self.axis.step(demand, limits, dt);
        self.end_ramp(&motion, p);
        let following_error = self.monitor(&motion, p, now_ns);
        if following_error.1 {
            emergency = emergency.or(self.fault(FOLLOWING_ERROR, p));
            self.following_fault = true;
        }
        let inputs = self.inputs(&motion, following_error.0, cut, connected, sp, cw, p);
        let enabled = self.state.may_drive();
        Report {
            inputs,
            power_stage: PowerStage {
                enabled,
                torque: if enabled { sat_i16(motion.torque) } else { 0 },
            },
            emergency,
            error_register: error_register_bits(self.error_code),
        }
    }

    /// Generators start from where the axis is (a new mode, a new enable).
    fn restart_generators(&mut self) {
        let m = self.axis.motion();
        self.demand_m = m.position_m;
        self.velocity_demand = m.velocity;
        self.segment = None;
        self.pp_target_m = m.position_m;
        self.pp_ack = false;
        self.homing_attained = false;
        self.homing_error = false;
        self.following_since = None;
        self.warning = false;
    }

    /// Transition 13 (and 14 at once when nothing moves): a fault with
    /// `code`; the Emergency's code if the fault is new.
    fn fault(&mut self, code: u16, p: &Parameters) -> Option<u16> {
        if matches!(
            self.state,
            PowerState::FaultReactionActive | PowerState::Fault
        ) {
            return None;
        }
        self.error_code = code;
        let deceleration = match p.fault_reaction_option {
            0 => 0,
            1 => i64::from(p.profile_deceleration),
            _ => i64::from(p.quick_stop_deceleration),
        };
        if self.state.may_drive() && deceleration > 0 {
            self.start_ramp(deceleration, PowerState::Fault);
            self.state = PowerState::FaultReactionActive;
        } else {
            // Nothing was driven, or the reaction is to coast: the power
            // stage goes off now.
            self.ramp = None;
            self.state = PowerState::Fault;
        }
        Some(code)
    }

    fn start_ramp(&mut self, deceleration: i64, then: PowerState) {
        let m = self.axis.motion();
        self.demand_m = m.position_m;
        self.ramp = Some(Ramp {
            deceleration,
            velocity: m.velocity,
            then,
            done: false,
        });
    }

    /// A valid controlword: its command, with `rising` its bits that went
    /// from 0 to 1.
    fn command(&mut self, cw: u16, rising: u16, fault_active: bool, p: &Parameters) {
        match self.state {
            PowerState::Fault => {
                // Transition 15: the rising edge of bit 7, the fault gone.
                if rising & control::FAULT_RESET_BIT != 0 && !fault_active {
                    self.state = PowerState::SwitchOnDisabled;
                    self.error_code = 0;
                    self.following_fault = false;
                    self.following_since = None;
                    self.warning = false;
                }
            }
            PowerState::FaultReactionActive => {}
            from => {
                let stays = matches!(p.quick_stop_option, 5..=8);
                let to = transition(from, Command::decode(cw), stays);
                if to != from {
                    self.enter(from, to, p);
                }
            }
        }
    }

    fn enter(&mut self, from: PowerState, to: PowerState, p: &Parameters) {
        self.state = to;
        match to {
            PowerState::OperationEnabled => {
                self.ramp = None;
                self.restart_generators();
                if from == PowerState::QuickStopActive {
                    self.velocity_demand = 0;
                }
            }
            PowerState::QuickStopActive => self.quick_stop(p, false),
            _ => self.ramp = None,
        }
    }

    /// Quick stop active entered: the ramp of 0x605A (`forced_disable`: go
    /// to Switch on disabled at standstill whatever the option says).
    fn quick_stop(&mut self, p: &Parameters, forced_disable: bool) {
        let option = p.quick_stop_option;
        let deceleration = match option {
            1 | 5 => i64::from(p.profile_deceleration),
            2..=4 | 6..=8 => i64::from(p.quick_stop_deceleration),
            _ => 0,
        };
        let stays = matches!(option, 5..=8) && !forced_disable;
        if deceleration <= 0 {
            // Option 0: disable the drive function, the axis coasts.
            self.ramp = None;
            self.state = PowerState::SwitchOnDisabled;
            return;
        }
        self.state = PowerState::QuickStopActive;
        self.start_ramp(
            deceleration,
            if stays {
                PowerState::QuickStopActive
            } else {
                PowerState::SwitchOnDisabled
            },
        );
    }

    /// No valid controlword (OP left, watchdog, no cyclic outputs, the
    /// watchdog disarmed): nothing drives on without a master.
    fn connection_lost(&mut self, p: &Parameters) -> Option<u16> {
        match self.state {
            PowerState::OperationEnabled => match p.abort_connection_option {
                2 => {
                    self.ramp = None;
                    self.state = PowerState::SwitchOnDisabled;
                    None
                }
                3 => {
                    self.quick_stop(p, true);
                    None
                }
                _ => self.fault(CONNECTION_LOST, p),
            },
            PowerState::QuickStopActive => {
                match &mut self.ramp {
                    Some(r) if !r.done => r.then = PowerState::SwitchOnDisabled,
                    _ => {
                        self.ramp = None;
                        self.state = PowerState::SwitchOnDisabled;
                    }
                }
                None
            }
            PowerState::ReadyToSwitchOn | PowerState::SwitchedOn => {
                self.state = PowerState::SwitchOnDisabled;
                None
            }
            _ => None,
        }
    }
}

mod demand;
mod report;

#[cfg(test)]
mod tests;
