//! # Layer 1 `app`: the amplifier's behaviour (signal chain and power stage)
//!
//! This layer realises what the PAM-199-P-ETC *does* with a command value,
//! following the product manual (chapters 2, 4.5, 6.2–6.5 and 8.1). It knows
//! nothing of EtherCAT, the object dictionary or PDOs: the device layer reads
//! the parameters out of the OD, feeds the command value and the ENABLE bit in
//! and copies the results (W, C, U, IA/IB, diagnosis flags) back.
//!
//! Properties shared by every module here:
//!
//! * `no_std`, no heap, no `unsafe`, no panics on any input (all arithmetic is
//!   bounded, clamped, saturating or checked; no indexing).
//! * **Time is injected**: every time-dependent function takes `dt_us`
//!   (microseconds since the previous call); there are no clocks.
//! * The signal chain ([`ramp`], [`curve`], [`deadband`], [`chain`]) uses
//!   integer arithmetic only, in units of 0.01 % (full scale
//!   [`FULL_SCALE`] = 10000), so it is exact and deterministic. Only the
//!   solenoid *simulation* in [`power_stage`] uses `f32`.
//!
//! Pipeline per channel (manual 6.5, see [`chain`]):
//!
//! ```text
//! command --IO_BASE--> W --ramp (RA)--> C --CC (CCMODE)--> --TRIGGER/MIN/MAX--> U
//!         U * CURRENT / 10000 --> current setpoint [mA] --> PowerStage --> IA / IB
//! ```

pub mod amplifier;
pub mod chain;
pub mod curve;
pub mod deadband;
pub mod entries;
pub mod power_stage;
pub mod ramp;

pub use chain::{
    ChannelOutput, DirectionalChain, DirectionalParams, IndependentChain, IndependentParams,
};
pub use curve::{Coord, Curve, DirectionalCurve, IndependentCurve, Point};
pub use deadband::{Deadband, DirectionalDeadband, MmType};
pub use power_stage::{
    Dither, Fault, Faults, PiGains, PowerStage, SimPowerStage, Solenoid, StageParams, acc_gains,
    pwm_code, pwm_from_code,
};
pub use ramp::{FourQuadrantRamp, Ramp};

/// Full scale of the signal chain: 10000 = 100 % in units of 0.01 %.
pub const FULL_SCALE: i32 = 10_000;

/// Integer division `n / d` rounded to the nearest integer, halves away from
/// zero (so the result is symmetric for positive and negative `n`).
///
/// Returns 0 for `d <= 0` instead of panicking; callers only pass positive
/// divisors. Inputs are bounded by the callers so the intermediate
/// `n ± d / 2` cannot overflow; saturating arithmetic guards it anyway.
pub(crate) fn div_round(n: i64, d: i64) -> i64 {
    if d <= 0 {
        return 0;
    }
    let half = d / 2;
    if n >= 0 {
        n.saturating_add(half) / d
    } else {
        -(n.saturating_neg().saturating_add(half) / d)
    }
}

/// Clamps an `i64` into the `i32` range.
pub(crate) fn sat_i32(v: i64) -> i32 {
    // After the clamp the value fits, so the fallback is never taken.
    i32::try_from(v.clamp(i64::from(i32::MIN), i64::from(i32::MAX))).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn div_round_is_symmetric_and_rounds_halves_away_from_zero() {
        assert_eq!(div_round(5, 2), 3);
        assert_eq!(div_round(-5, 2), -3);
        assert_eq!(div_round(4, 3), 1);
        assert_eq!(div_round(-4, 3), -1);
        assert_eq!(div_round(7, 0), 0);
        assert_eq!(div_round(i64::MIN, 3), -(i64::MAX / 3));
    }

    #[test]
    fn sat_i32_clamps() {
        assert_eq!(sat_i32(i64::MAX), i32::MAX);
        assert_eq!(sat_i32(i64::MIN), i32::MIN);
        assert_eq!(sat_i32(-7), -7);
    }
}
