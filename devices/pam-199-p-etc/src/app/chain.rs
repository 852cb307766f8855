//! The complete signal chain of one channel (manual 6.3–6.5).
//!
//! ```text
//! command --IO_BASE--> W --RA ramp--> C --CC (if CCMODE)--> TRIGGER/MIN/MAX --> U
//! current setpoint [mA] = U * CURRENT / 10000
//! ```
//!
//! Decisions (our reading of the manual):
//!
//! * **W** = `command * 10000 / IO_BASE` in 0.01 % (IO_BASE = 100 %, rounded
//!   to nearest), clamped to ±10000 (DIR) or 0..10000 (IND).
//! * **C** = the output of the ramp. The manual lists C as "command value
//!   after ramp function" (6.5) but as "control signal after CC" in the PDO
//!   tables (6.1); we take C = after the ramp, *before* CC, so C shows the
//!   ramp and U shows the effect of CC and the compensation together.
//! * **U** = C through the CC curve (only if CCMODE = ON; with the default
//!   points the curve is the identity anyway), then through the deadband
//!   compensation / MIN / MAX scaling: "command value to current
//!   controller".
//! * W, C and U are reported in IO_BASE units (`value * IO_BASE / 10000`,
//!   rounded), since IO_BASE is the "reference value for 100 % command and
//!   feedback values" (6.2.1). The 0.01 % values are returned as well.
//! * **Current setpoint** = `U * CURRENT / 10000` mA (rounded). In DIR mode it
//!   is signed: positive drives solenoid A, negative solenoid B.
//! * **Disabled** (ENABLE false, or the device not ready because of a fault):
//!   the ramp output *jumps* to 0 (it does not ramp down, the power stage is
//!   off), so C, U and the current setpoint are 0; W still shows the scaled
//!   command. After re-enabling, the ramp starts again from 0.
//! * IO_BASE is clamped to 100..32767, CURRENT to 500..3000 mA.

use super::curve::{DirectionalCurve, IndependentCurve};
use super::deadband::{Deadband, DirectionalDeadband, MmType};
use super::ramp::{FourQuadrantRamp, RAMP_DEFAULT_MS, Ramp};
use super::{FULL_SCALE, div_round, sat_i32};

/// Smallest IO_BASE.
pub const IO_BASE_MIN: u16 = 100;
/// Largest IO_BASE.
pub const IO_BASE_MAX: u16 = 32_767;
/// Default IO_BASE (0.01 % units).
pub const IO_BASE_DEFAULT: u16 = 10_000;
/// Smallest nominal CURRENT in mA.
pub const CURRENT_MIN_MA: u16 = 500;
/// Largest nominal CURRENT in mA.
pub const CURRENT_MAX_MA: u16 = 3_000;
/// Default nominal CURRENT in mA.
pub const CURRENT_DEFAULT_MA: u16 = 1_000;

/// The results of one chain step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ChannelOutput {
    /// W: command after input scaling, in IO_BASE units.
    pub w: i32,
    /// C: command after the ramp, in IO_BASE units.
    pub c: i32,
    /// U: command to the current controller, in IO_BASE units.
    pub u: i32,
    /// W in 0.01 %.
    pub w_pct: i32,
    /// C in 0.01 %.
    pub c_pct: i32,
    /// U in 0.01 %.
    pub u_pct: i32,
    /// Current setpoint in mA (DIR: positive = solenoid A, negative = B;
    /// IND: never negative).
    pub current_setpoint_ma: i32,
}

/// Scales a raw command to 0.01 % (IO_BASE = 10000), clamped to `lo..=hi`.
fn scale_in(command: i32, io_base: u16, lo: i32, hi: i32) -> i32 {
    let base = i64::from(io_base.clamp(IO_BASE_MIN, IO_BASE_MAX));
    sat_i32(div_round(i64::from(command) * i64::from(FULL_SCALE), base)).clamp(lo, hi)
}

/// Scales a 0.01 % value back to IO_BASE units.
fn scale_out(v: i32, io_base: u16) -> i32 {
    let base = i64::from(io_base.clamp(IO_BASE_MIN, IO_BASE_MAX));
    sat_i32(div_round(i64::from(v) * base, i64::from(FULL_SCALE)))
}

/// The current setpoint in mA for `u` in 0.01 %.
fn current_ma(u: i32, current: u16) -> i32 {
    let i = i64::from(current.clamp(CURRENT_MIN_MA, CURRENT_MAX_MA));
    sat_i32(div_round(i64::from(u) * i, i64::from(FULL_SCALE)))
}

/// Builds the output record.
fn output(w: i32, c: i32, u: i32, io_base: u16, current: u16) -> ChannelOutput {
    ChannelOutput {
        w: scale_out(w, io_base),
        c: scale_out(c, io_base),
        u: scale_out(u, io_base),
        w_pct: w,
        c_pct: c,
        u_pct: u,
        current_setpoint_ma: current_ma(u, current),
    }
}

/// Parameters of one independent channel (OD 0x801x / 0x802x plus IO_BASE).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IndependentParams {
    /// RA:UP:n in ms (1..120000).
    pub ramp_up_ms: u32,
    /// RA:DOWN:n in ms (1..120000).
    pub ramp_down_ms: u32,
    /// CCMODE:n (linearisation on).
    pub cc_enabled: bool,
    /// CCn curve points.
    pub curve: IndependentCurve,
    /// MMTYPE:n, TRIGGER:n, MIN:n, MAX:n.
    pub deadband: Deadband,
    /// IO_BASE (100..32767): raw command value for 100 %.
    pub io_base: u16,
    /// CURRENT:n nominal current in mA (500..3000).
    pub current_ma: u16,
}

impl Default for IndependentParams {
    /// The manual's defaults (IO_BASE 10000).
    fn default() -> Self {
        Self {
            ramp_up_ms: RAMP_DEFAULT_MS,
            ramp_down_ms: RAMP_DEFAULT_MS,
            cc_enabled: false,
            curve: IndependentCurve::default(),
            deadband: Deadband::default(),
            io_base: IO_BASE_DEFAULT,
            current_ma: CURRENT_DEFAULT_MA,
        }
    }
}

/// One independent (single-solenoid) channel, mode IND. The two channels of
/// the device are two separate instances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IndependentChain {
    params: IndependentParams,
    ramp: Ramp,
}

impl IndependentChain {
    /// A chain with the given parameters and the ramp at 0.
    pub fn new(params: IndependentParams) -> Self {
        Self {
            params,
            ramp: Ramp::new(params.ramp_up_ms, params.ramp_down_ms),
        }
    }

    /// The parameters.
    pub fn params(&self) -> &IndependentParams {
        &self.params
    }

    /// Replaces the parameters; the ramp keeps its output.
    pub fn set_params(&mut self, params: IndependentParams) {
        self.params = params;
        self.ramp.set_times(params.ramp_up_ms, params.ramp_down_ms);
    }

    /// Forces the ramp to 0.
    pub fn reset(&mut self) {
        self.ramp.reset_to(0);
    }

    /// One cycle: `command` is the raw command value (IO_BASE units, negative
    /// treated as 0), `enable` the ENABLE bit combined with readiness,
    /// `dt_us` the time since the previous call.
    pub fn step(&mut self, command: i32, enable: bool, dt_us: u32) -> ChannelOutput {
        let p = &self.params;
        let w = scale_in(command, p.io_base, 0, FULL_SCALE);
        let c = if enable {
            self.ramp.step(w, dt_us).clamp(0, FULL_SCALE)
        } else {
            self.ramp.reset_to(0);
            0
        };
        let cc = if p.cc_enabled { p.curve.apply(c) } else { c };
        let u = p.deadband.apply_unipolar(cc);
        output(w, c, u, p.io_base, p.current_ma)
    }
}

/// Parameters of the directional channel 0 (OD 0x8002, 0x8006, 0x800A,
/// 0x800D plus IO_BASE).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DirectionalParams {
    /// RA:UP:A in ms.
    pub ramp_up_a_ms: u32,
    /// RA:DOWN:A in ms.
    pub ramp_down_a_ms: u32,
    /// RA:UP:B in ms.
    pub ramp_up_b_ms: u32,
    /// RA:DOWN:B in ms.
    pub ramp_down_b_ms: u32,
    /// CCMODE (linearisation on).
    pub cc_enabled: bool,
    /// CC curve points (CCB:10 … CCA:10).
    pub curve: DirectionalCurve,
    /// MMTYPE, TRIGGER, MIN:A, MAX:A, MIN:B, MAX:B.
    pub deadband: DirectionalDeadband,
    /// IO_BASE (100..32767): raw command value for 100 %.
    pub io_base: u16,
    /// CURRENT nominal current in mA (500..3000), both solenoids.
    pub current_ma: u16,
}

impl Default for DirectionalParams {
    /// The manual's defaults (IO_BASE 10000).
    fn default() -> Self {
        Self {
            ramp_up_a_ms: RAMP_DEFAULT_MS,
            ramp_down_a_ms: RAMP_DEFAULT_MS,
            ramp_up_b_ms: RAMP_DEFAULT_MS,
            ramp_down_b_ms: RAMP_DEFAULT_MS,
            cc_enabled: false,
            curve: DirectionalCurve::default(),
            deadband: DirectionalDeadband::default(),
            io_base: IO_BASE_DEFAULT,
            current_ma: CURRENT_DEFAULT_MA,
        }
    }
}

impl DirectionalParams {
    /// Compensation type shortcut.
    pub fn mmtype(&self) -> MmType {
        self.deadband.mmtype
    }
}

/// The directional channel (mode DIR): one signed command, solenoid A for
/// positive values, B for negative, with the four-quadrant ramp.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DirectionalChain {
    params: DirectionalParams,
    ramp: FourQuadrantRamp,
}

impl DirectionalChain {
    /// A chain with the given parameters and the ramp at 0.
    pub fn new(params: DirectionalParams) -> Self {
        let mut s = Self {
            params,
            ramp: FourQuadrantRamp::default(),
        };
        s.set_params(params);
        s
    }

    /// The parameters.
    pub fn params(&self) -> &DirectionalParams {
        &self.params
    }

    /// Replaces the parameters; the ramp keeps its output.
    pub fn set_params(&mut self, params: DirectionalParams) {
        self.params = params;
        self.ramp.set_times(
            params.ramp_up_a_ms,
            params.ramp_down_a_ms,
            params.ramp_up_b_ms,
            params.ramp_down_b_ms,
        );
    }

    /// Forces the ramp to 0.
    pub fn reset(&mut self) {
        self.ramp.reset_to(0);
    }

    /// One cycle: `command` is the raw signed command value (IO_BASE units),
    /// `enable` the ENABLE bit combined with readiness, `dt_us` the time
    /// since the previous call.
    pub fn step(&mut self, command: i32, enable: bool, dt_us: u32) -> ChannelOutput {
        let p = &self.params;
        let w = scale_in(command, p.io_base, -FULL_SCALE, FULL_SCALE);
        let c = if enable {
            self.ramp.step(w, dt_us)
        } else {
            self.ramp.reset_to(0);
            0
        };
        let cc = if p.cc_enabled { p.curve.apply(c) } else { c };
        let u = p.deadband.apply(cc);
        output(w, c, u, p.io_base, p.current_ma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn no_deadband() -> Deadband {
        Deadband {
            mmtype: MmType::Jmp,
            trigger: 0,
            min: 0,
            max: 10_000,
        }
    }

    #[test]
    fn half_command_with_1500_ma_gives_750_ma_after_the_ramp() {
        let mut ch = IndependentChain::new(IndependentParams {
            deadband: no_deadband(),
            current_ma: 1_500,
            ..IndependentParams::default()
        });
        // Default ramp 100 ms: 50 % is reached after 50 ms.
        let mut out = ChannelOutput::default();
        for k in 1..=50 {
            out = ch.step(5_000, true, 1000);
            assert_eq!(out.c_pct, 100 * k);
        }
        assert_eq!(out.w, 5_000);
        assert_eq!(out.c, 5_000);
        assert_eq!(out.u, 5_000);
        assert_eq!(out.current_setpoint_ma, 750);
    }

    #[test]
    fn default_trigger_200_reduces_the_setpoint_by_the_compensation_formula() {
        let mut ch = IndependentChain::new(IndependentParams {
            current_ma: 1_500,
            ramp_up_ms: 1,
            ..IndependentParams::default()
        });
        let out = ch.step(5_000, true, 1000);
        // U = (5000 - 200) * 10000 / 9800 = 4898; I = 4898 * 1500 / 10000.
        assert_eq!(out.u_pct, 4_898);
        assert_eq!(out.current_setpoint_ma, 735);
    }

    #[test]
    fn io_base_16383_scales_commands_and_process_values() {
        let mut ch = IndependentChain::new(IndependentParams {
            deadband: no_deadband(),
            io_base: 16_383,
            ramp_up_ms: 1,
            ..IndependentParams::default()
        });
        let out = ch.step(16_383, true, 1000);
        assert_eq!((out.w_pct, out.w, out.u), (10_000, 16_383, 16_383));
        assert_eq!(out.current_setpoint_ma, 1_000);
        // 8192 * 10000 / 16383 = 5000.3 -> 5000; back: 5000 * 16383 / 10000
        // = 8191.5 -> 8192.
        let out = ch.step(8_192, true, 1000);
        assert_eq!((out.w_pct, out.w), (5_000, 8_192));
        // Beyond IO_BASE clamps to 100 %, negative clamps to 0 in IND.
        assert_eq!(ch.step(30_000, true, 1000).w_pct, 10_000);
        assert_eq!(ch.step(-5, true, 1000).w_pct, 0);
    }

    #[test]
    fn the_two_independent_channels_do_not_influence_each_other() {
        let mut ch1 = IndependentChain::new(IndependentParams {
            deadband: no_deadband(),
            ..IndependentParams::default()
        });
        let mut ch2 = IndependentChain::new(IndependentParams {
            deadband: no_deadband(),
            ramp_up_ms: 1,
            current_ma: 2_000,
            ..IndependentParams::default()
        });
        let a = ch1.step(10_000, true, 10_000);
        let b = ch2.step(2_500, true, 10_000);
        assert_eq!(a.c_pct, 1_000); // 10 ms of a 100 ms ramp
        assert_eq!(b.c_pct, 2_500); // 1 ms ramp: a step
        assert_eq!(b.current_setpoint_ma, 500);
        // Disabling channel 2 leaves channel 1 ramping.
        assert_eq!(ch2.step(2_500, false, 10_000).current_setpoint_ma, 0);
        assert_eq!(ch1.step(10_000, true, 10_000).c_pct, 2_000);
    }

    #[test]
    fn disable_jumps_the_ramp_to_zero_and_restarts_from_zero() {
        let mut ch = DirectionalChain::default();
        for _ in 0..100 {
            ch.step(10_000, true, 1000);
        }
        let out = ch.step(10_000, false, 1000);
        assert_eq!((out.w_pct, out.c_pct, out.u_pct), (10_000, 0, 0));
        assert_eq!(out.current_setpoint_ma, 0);
        assert_eq!(ch.step(10_000, true, 1000).c_pct, 100);
    }

    #[test]
    fn directional_negative_command_drives_solenoid_b_with_b_parameters() {
        let mut ch = DirectionalChain::new(DirectionalParams {
            ramp_up_a_ms: 1,
            ramp_down_a_ms: 1,
            ramp_up_b_ms: 1,
            ramp_down_b_ms: 1,
            deadband: DirectionalDeadband {
                trigger: 0,
                min_b: 2_000,
                max_b: 8_000,
                ..DirectionalDeadband::default()
            },
            current_ma: 2_000,
            ..DirectionalParams::default()
        });
        let out = ch.step(-5_000, true, 1000);
        // U = -(2000 + 5000 * 6000 / 10000) = -5000; I = -5000 * 2000 / 10000.
        assert_eq!(out.u_pct, -5_000);
        assert_eq!(out.current_setpoint_ma, -1_000);
        let out = ch.step(5_000, true, 1000);
        assert_eq!(out.current_setpoint_ma, 1_000);
        // Clamped to ±100 %.
        assert_eq!(ch.step(i32::MIN, true, 1000).w_pct, -10_000);
    }

    #[test]
    fn directional_sign_change_follows_the_four_quadrant_ramp() {
        let mut ch = DirectionalChain::new(DirectionalParams {
            ramp_up_a_ms: 1,
            ramp_down_a_ms: 50,
            ramp_up_b_ms: 200,
            ..DirectionalParams::default()
        });
        ch.step(10_000, true, 1000);
        for _ in 0..50 {
            ch.step(-10_000, true, 1000);
        }
        assert_eq!(ch.step(-10_000, true, 0).c_pct, 0);
        for _ in 0..200 {
            ch.step(-10_000, true, 1000);
        }
        assert_eq!(ch.step(-10_000, true, 0).c_pct, -10_000);
    }

    #[test]
    fn cc_is_applied_between_c_and_u_only_when_enabled() {
        let mut curve = DirectionalCurve::default();
        curve.set_point(15, 5_000, 2_000); // CCA:5
        let mut p = DirectionalParams {
            ramp_up_a_ms: 1,
            curve,
            deadband: DirectionalDeadband {
                trigger: 0,
                ..DirectionalDeadband::default()
            },
            ..DirectionalParams::default()
        };
        let mut ch = DirectionalChain::new(p);
        assert_eq!(ch.step(5_000, true, 1000).u_pct, 5_000);
        p.cc_enabled = true;
        ch.set_params(p);
        let out = ch.step(5_000, true, 1000);
        assert_eq!((out.c_pct, out.u_pct), (5_000, 2_000));
    }
}
