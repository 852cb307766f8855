//! Deadband (overlap) compensation and output scaling (manual 6.3.4–6.3.7,
//! figures 1–2): MMTYPE, TRIGGER, MIN, MAX.
//!
//! Inputs and outputs are in 0.01 % (|x| ≤ 10000). Parameter ranges (values
//! outside are clamped when applied): TRIGGER 0..3000, MIN 0..6000,
//! MAX 5000..10000. With `m = |x|` and `T, MIN, MAX` of the active side, our
//! reading of the manual and its figures 1–2 is:
//!
//! * **JMP** (default): `m < T` → 0 (the non-sensitive range around zero);
//!   `m ≥ T` → `MIN + (m − T) * (MAX − MIN) / (10000 − T)`. The output jumps
//!   from 0 to MIN at the trigger and rises linearly to MAX at 100 %.
//! * **LIN**: `m < T` → `m * MIN / T` (rises linearly from 0 to MIN at the
//!   trigger, continuous, recommended inside control loops); `m ≥ T` as JMP.
//! * **TRIGGER = 0**: no deadband: `m == 0` → 0, otherwise
//!   `MIN + m * (MAX − MIN) / 10000` (both types).
//!
//! The sign of `x` is preserved. Divisions round to the nearest integer
//! (halves away from zero). Full scale always gives exactly MAX.
//! MIN > MAX (possible: MIN up to 6000, MAX down to 5000) is not rejected:
//! the line then falls from MIN to MAX; nothing panics.
//!
//! Directional mode ([`DirectionalDeadband`]) uses one TRIGGER and MMTYPE for
//! both sides and MIN:A/MAX:A for positive, MIN:B/MAX:B for negative inputs.
//! Independent mode ([`Deadband::apply_unipolar`]) uses one set per channel
//! and inputs 0..10000 only (negative inputs are treated as 0).

use super::{FULL_SCALE, div_round, sat_i32};

/// Largest TRIGGER value.
pub const TRIGGER_MAX: u16 = 3_000;
/// Largest MIN value.
pub const MIN_MAX: u16 = 6_000;
/// Smallest MAX value.
pub const MAX_MIN: u16 = 5_000;
/// Largest MAX value.
pub const MAX_MAX: u16 = 10_000;

/// Compensation type MMTYPE (enum DT0805EN03: JMP = 0, LIN = 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MmType {
    /// Jump to MIN at the trigger (default).
    #[default]
    Jmp = 0,
    /// Linear rise from 0 to MIN below the trigger.
    Lin = 1,
}

impl MmType {
    /// The type for an OD value (0 = JMP, 1 = LIN); `None` otherwise.
    pub fn from_od(v: u16) -> Option<Self> {
        match v {
            0 => Some(Self::Jmp),
            1 => Some(Self::Lin),
            _ => None,
        }
    }
}

/// One side's compensation parameters (independent channel, or one
/// solenoid of the directional mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Deadband {
    /// MMTYPE.
    pub mmtype: MmType,
    /// TRIGGER in 0.01 % (0..3000).
    pub trigger: u16,
    /// MIN in 0.01 % (0..6000).
    pub min: u16,
    /// MAX in 0.01 % (5000..10000).
    pub max: u16,
}

impl Default for Deadband {
    /// OD defaults: JMP, TRIGGER 200, MIN 0, MAX 10000.
    fn default() -> Self {
        Self {
            mmtype: MmType::Jmp,
            trigger: 200,
            min: 0,
            max: 10_000,
        }
    }
}

impl Deadband {
    /// Applies the compensation to a magnitude (0..10000, clamped).
    fn magnitude(&self, m: i32) -> i32 {
        let m = i64::from(m.clamp(0, FULL_SCALE));
        let t = i64::from(self.trigger.min(TRIGGER_MAX));
        let min = i64::from(self.min.min(MIN_MAX));
        let max = i64::from(self.max.clamp(MAX_MIN, MAX_MAX));
        let fs = i64::from(FULL_SCALE);
        let out = if m == 0 {
            0
        } else if m < t {
            match self.mmtype {
                MmType::Jmp => 0,
                // t > m > 0 here, so the divisor is positive.
                MmType::Lin => div_round(m * min, t),
            }
        } else {
            // t <= 3000, so fs - t >= 7000.
            min + div_round((m - t) * (max - min), fs - t)
        };
        sat_i32(out)
    }

    /// Independent mode: `x` in 0..10000 (negative → 0, above → 10000).
    pub fn apply_unipolar(&self, x: i32) -> i32 {
        self.magnitude(x.max(0))
    }

    /// Applies the compensation to a signed value with these parameters on
    /// both sides (sign preserved).
    pub fn apply_signed(&self, x: i32) -> i32 {
        let m = self.magnitude(sat_i32(i64::from(x).abs()));
        if x < 0 { -m } else { m }
    }
}

/// Directional-mode compensation: common MMTYPE and TRIGGER, MIN:A/MAX:A for
/// positive inputs (solenoid A), MIN:B/MAX:B for negative inputs (B).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DirectionalDeadband {
    /// MMTYPE.
    pub mmtype: MmType,
    /// TRIGGER in 0.01 % (0..3000).
    pub trigger: u16,
    /// MIN:A in 0.01 % (0..6000).
    pub min_a: u16,
    /// MAX:A in 0.01 % (5000..10000).
    pub max_a: u16,
    /// MIN:B in 0.01 % (0..6000).
    pub min_b: u16,
    /// MAX:B in 0.01 % (5000..10000).
    pub max_b: u16,
}

impl Default for DirectionalDeadband {
    /// OD defaults: JMP, TRIGGER 200, MIN 0, MAX 10000 on both sides.
    fn default() -> Self {
        Self {
            mmtype: MmType::Jmp,
            trigger: 200,
            min_a: 0,
            max_a: 10_000,
            min_b: 0,
            max_b: 10_000,
        }
    }
}

impl DirectionalDeadband {
    /// The parameter set of solenoid A.
    pub fn side_a(&self) -> Deadband {
        Deadband {
            mmtype: self.mmtype,
            trigger: self.trigger,
            min: self.min_a,
            max: self.max_a,
        }
    }

    /// The parameter set of solenoid B.
    pub fn side_b(&self) -> Deadband {
        Deadband {
            mmtype: self.mmtype,
            trigger: self.trigger,
            min: self.min_b,
            max: self.max_b,
        }
    }

    /// Applies the compensation to `x` (−10000..10000, clamped): positive
    /// values with the A set, negative with the B set, sign preserved.
    pub fn apply(&self, x: i32) -> i32 {
        if x >= 0 {
            self.side_a().magnitude(x)
        } else {
            -self.side_b().magnitude(sat_i32(-i64::from(x)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn jmp(trigger: u16, min: u16, max: u16) -> Deadband {
        Deadband {
            mmtype: MmType::Jmp,
            trigger,
            min,
            max,
        }
    }

    #[test]
    fn jmp_is_zero_below_the_trigger_and_jumps_to_min_at_it() {
        let d = jmp(500, 2_000, 9_000);
        assert_eq!(d.apply_unipolar(499), 0);
        assert_eq!(d.apply_unipolar(500), 2_000);
        // 2000 + (600 - 500) * 7000 / 9500 = 2073.68 -> 2074.
        assert_eq!(d.apply_unipolar(600), 2_074);
        // 2000 + 4500 * 7000 / 9500 = 5315.79 -> 5316.
        assert_eq!(d.apply_unipolar(5_000), 5_316);
    }

    #[test]
    fn lin_rises_linearly_to_min_below_the_trigger() {
        let d = Deadband {
            mmtype: MmType::Lin,
            ..jmp(500, 2_000, 9_000)
        };
        assert_eq!(d.apply_unipolar(0), 0);
        // 250 * 2000 / 500 = 1000.
        assert_eq!(d.apply_unipolar(250), 1_000);
        assert_eq!(d.apply_unipolar(499), 1_996);
        assert_eq!(d.apply_unipolar(500), 2_000);
        assert_eq!(d.apply_unipolar(600), 2_074);
    }

    #[test]
    fn full_scale_gives_max() {
        for mm in [MmType::Jmp, MmType::Lin] {
            for t in [0, 1, 200, 3_000] {
                let d = Deadband {
                    mmtype: mm,
                    ..jmp(t, 1_234, 8_765)
                };
                assert_eq!(d.apply_unipolar(10_000), 8_765);
                assert_eq!(d.apply_signed(-10_000), -8_765);
            }
        }
    }

    #[test]
    fn defaults_scale_trigger_200_to_full_range() {
        let d = Deadband::default();
        assert_eq!(d.apply_unipolar(199), 0);
        assert_eq!(d.apply_unipolar(200), 0);
        // (5000 - 200) * 10000 / 9800 = 4897.96 -> 4898.
        assert_eq!(d.apply_unipolar(5_000), 4_898);
    }

    #[test]
    fn negative_side_uses_the_b_parameters() {
        let d = DirectionalDeadband {
            mmtype: MmType::Jmp,
            trigger: 1_000,
            min_a: 1_000,
            max_a: 10_000,
            min_b: 3_000,
            max_b: 6_000,
        };
        // A: 1000 + 4000 * 9000 / 9000 = 5000.
        assert_eq!(d.apply(5_000), 5_000);
        // B: -(3000 + 4000 * 3000 / 9000) = -4333.33 -> -4333.
        assert_eq!(d.apply(-5_000), -4_333);
        assert_eq!(d.apply(-999), 0);
        assert_eq!(d.apply(-1_000), -3_000);
        assert_eq!(d.apply(-10_000), -6_000);
        assert_eq!(d.apply(10_000), 10_000);
    }

    #[test]
    fn trigger_zero_means_no_deadband() {
        let d = jmp(0, 1_000, 10_000);
        assert_eq!(d.apply_unipolar(0), 0);
        // 1000 + 1 * 9000 / 10000 = 1000.9 -> 1001.
        assert_eq!(d.apply_unipolar(1), 1_001);
        assert_eq!(d.apply_unipolar(5_000), 5_500);
        let lin = Deadband {
            mmtype: MmType::Lin,
            ..d
        };
        assert_eq!(lin.apply_unipolar(5_000), 5_500);
        let identity = jmp(0, 0, 10_000);
        for x in (-10_000..=10_000).step_by(77) {
            assert_eq!(identity.apply_signed(x), x);
        }
    }

    #[test]
    fn independent_mode_clamps_negative_inputs_and_out_of_range_parameters() {
        let d = jmp(9_999, 9_999, 1);
        // Clamped to TRIGGER 3000, MIN 6000, MAX 5000: falling line.
        assert_eq!(d.apply_unipolar(-5_000), 0);
        assert_eq!(d.apply_unipolar(3_000), 6_000);
        assert_eq!(d.apply_unipolar(10_000), 5_000);
        assert_eq!(d.apply_unipolar(i32::MAX), 5_000);
        assert_eq!(d.apply_signed(i32::MIN), -5_000);
        assert_eq!(MmType::from_od(1), Some(MmType::Lin));
        assert_eq!(MmType::from_od(2), None);
    }
}
