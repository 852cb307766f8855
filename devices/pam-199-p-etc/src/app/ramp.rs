//! Ramp generators (manual 6.3.1, parameters RA).
//!
//! Values are in 0.01 % (full scale [`FULL_SCALE`] = 10000). A ramp time
//! `T` ms (1..=120000) is the time for a full-scale change of 10000, so the
//! slope is `10000 / T` per ms. "UP" is used while the *magnitude* of the
//! output grows (moving away from zero), "DOWN" while it shrinks (moving
//! towards zero).
//!
//! ## Exact integer arithmetic
//!
//! Elapsed time is accumulated as `10000 * t_us` ("scaled time"). Moving one
//! unit at ramp time `T` ms costs `T * 1000` scaled time units, so a step of
//! `dt_us` advances `(rem + 10000 * dt_us) / (T * 1000)` units and keeps the
//! remainder `rem` for the next call. Nothing is rounded, so there is no drift:
//! a 100 ms ramp stepped at 1 ms gives exactly 100 units per tick and reaches
//! 10000 at tick 100; a 120000 ms ramp reaches 10000 after exactly 120 s.
//! The remainder is leftover *time*, so it stays valid when the slope changes
//! (e.g. at the zero crossing); it is dropped when the target is reached
//! (time is not banked while idle).
//!
//! ## Crossing zero (four-quadrant ramp)
//!
//! If the target has the other sign than the output, the output first runs to
//! zero with the DOWN time of the old side, then away from zero with the UP
//! time of the new side, both within the same call if the time suffices
//! (manual 6.3.1: "first the deceleration ramp of the old direction is
//! completed (RA:DOWN:A/B) before the acceleration in the new direction
//! starts (RA:UP:A/B)"). A change from +10000 to -10000 therefore takes
//! `RA:DOWN:A + RA:UP:B`.
//!
//! Positive values belong to solenoid A, negative values to solenoid B.

use super::FULL_SCALE;

/// Shortest ramp time in ms (RA range 1..120000 ms).
pub const RAMP_MIN_MS: u32 = 1;
/// Longest ramp time in ms (RA range 1..120000 ms).
pub const RAMP_MAX_MS: u32 = 120_000;
/// Default ramp time in ms (OD default of every RA entry).
pub const RAMP_DEFAULT_MS: u32 = 100;

/// Four ramp times in ms: UP/DOWN for the positive side (solenoid A) and
/// UP/DOWN for the negative side (solenoid B).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Times {
    up_a: u32,
    down_a: u32,
    up_b: u32,
    down_b: u32,
}

/// Clamps a ramp time into 1..=120000 ms.
fn clamp_ms(ms: u32) -> u32 {
    ms.clamp(RAMP_MIN_MS, RAMP_MAX_MS)
}

/// Shared ramp state: the output and the leftover scaled time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
struct Core {
    output: i32,
    rem: u64,
}

impl Core {
    /// Advances the output toward `target` (already clamped to ±10000) by
    /// `dt_us` with the given ramp times.
    fn step(&mut self, target: i32, dt_us: u32, t: Times) -> i32 {
        let mut acc = self
            .rem
            .saturating_add(u64::from(dt_us).saturating_mul(10_000));
        // At most two segments: towards zero, then away from zero.
        for _ in 0..2 {
            if self.output == target {
                self.rem = 0;
                return self.output;
            }
            let crossing = (self.output > 0 && target < 0) || (self.output < 0 && target > 0);
            let seg_target = if crossing { 0 } else { target };
            let towards_zero = seg_target.unsigned_abs() < self.output.unsigned_abs();
            // Side: the output's sign, or the target's when the output is 0.
            let side_a = self.output > 0 || (self.output == 0 && seg_target > 0);
            let ms = match (side_a, towards_zero) {
                (true, false) => t.up_a,
                (true, true) => t.down_a,
                (false, false) => t.up_b,
                (false, true) => t.down_b,
            };
            let den = u64::from(clamp_ms(ms)).saturating_mul(1000);
            let dist = u64::from(seg_target.abs_diff(self.output));
            let need = dist.saturating_mul(den);
            if acc >= need {
                self.output = seg_target;
                acc -= need;
                // Reaching the final target is handled at the loop head.
            } else {
                // den >= 1000, and units < dist <= 20000: fits in i32.
                let (units, rem) = super::div_rem_u64(acc, den);
                let units = i32::try_from(units).unwrap_or(0);
                self.rem = rem;
                self.output = if seg_target > self.output {
                    self.output.saturating_add(units)
                } else {
                    self.output.saturating_sub(units)
                };
                return self.output;
            }
        }
        if self.output == target {
            self.rem = 0;
        }
        self.output
    }
}

/// A one-channel ramp generator with separate UP and DOWN times (RA:UP,
/// RA:DOWN), used in independent mode.
///
/// Values are in 0.01 %; targets are clamped to ±10000. The same UP/DOWN
/// times apply on both sides of zero (for the directional four-quadrant ramp
/// see [`FourQuadrantRamp`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ramp {
    up_ms: u32,
    down_ms: u32,
    core: Core,
}

impl Default for Ramp {
    /// Both times at the manual's default of 100 ms, output 0.
    fn default() -> Self {
        Self::new(RAMP_DEFAULT_MS, RAMP_DEFAULT_MS)
    }
}

impl Ramp {
    /// A ramp at output 0 with the UP and DOWN times in ms (each clamped to
    /// 1..=120000).
    pub fn new(up_ms: u32, down_ms: u32) -> Self {
        Self {
            up_ms: clamp_ms(up_ms),
            down_ms: clamp_ms(down_ms),
            core: Core::default(),
        }
    }

    /// Changes the ramp times (clamped to 1..=120000 ms) without touching the
    /// output.
    pub fn set_times(&mut self, up_ms: u32, down_ms: u32) {
        self.up_ms = clamp_ms(up_ms);
        self.down_ms = clamp_ms(down_ms);
    }

    /// The (clamped) UP and DOWN times in ms.
    pub fn times(&self) -> (u32, u32) {
        (self.up_ms, self.down_ms)
    }

    /// The current output in 0.01 %.
    pub fn output(&self) -> i32 {
        self.core.output
    }

    /// Forces the output to `value` (clamped to ±10000), e.g. 0 when the
    /// channel is disabled, and drops any partial progress.
    pub fn reset_to(&mut self, value: i32) {
        self.core = Core {
            output: value.clamp(-FULL_SCALE, FULL_SCALE),
            rem: 0,
        };
    }

    /// Advances the output by `dt_us` toward `target` (clamped to ±10000) and
    /// returns it. The slope is `10000 / up_ms` per ms while |output| grows
    /// and `10000 / down_ms` per ms while it shrinks; the target is reached
    /// exactly, never overshot.
    pub fn step(&mut self, target: i32, dt_us: u32) -> i32 {
        let t = Times {
            up_a: self.up_ms,
            down_a: self.down_ms,
            up_b: self.up_ms,
            down_b: self.down_ms,
        };
        self.core
            .step(target.clamp(-FULL_SCALE, FULL_SCALE), dt_us, t)
    }
}

/// The four-quadrant ramp of the directional mode (manual 6.3.1): RA:UP:A,
/// RA:DOWN:A for positive values (solenoid A), RA:UP:B, RA:DOWN:B for
/// negative values (solenoid B). On a change of sign the old side's DOWN ramp
/// runs to zero first, then the new side's UP ramp starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FourQuadrantRamp {
    times: Times,
    core: Core,
}

impl Default for FourQuadrantRamp {
    /// All four times at the manual's default of 100 ms, output 0.
    fn default() -> Self {
        Self::new(
            RAMP_DEFAULT_MS,
            RAMP_DEFAULT_MS,
            RAMP_DEFAULT_MS,
            RAMP_DEFAULT_MS,
        )
    }
}

impl FourQuadrantRamp {
    /// A ramp at output 0 with RA:UP:A, RA:DOWN:A, RA:UP:B, RA:DOWN:B in ms
    /// (each clamped to 1..=120000).
    pub fn new(up_a_ms: u32, down_a_ms: u32, up_b_ms: u32, down_b_ms: u32) -> Self {
        let mut r = Self {
            times: Times {
                up_a: 0,
                down_a: 0,
                up_b: 0,
                down_b: 0,
            },
            core: Core::default(),
        };
        r.set_times(up_a_ms, down_a_ms, up_b_ms, down_b_ms);
        r
    }

    /// Changes the four ramp times (clamped to 1..=120000 ms) without touching
    /// the output.
    pub fn set_times(&mut self, up_a_ms: u32, down_a_ms: u32, up_b_ms: u32, down_b_ms: u32) {
        self.times = Times {
            up_a: clamp_ms(up_a_ms),
            down_a: clamp_ms(down_a_ms),
            up_b: clamp_ms(up_b_ms),
            down_b: clamp_ms(down_b_ms),
        };
    }

    /// The (clamped) times `(up_a, down_a, up_b, down_b)` in ms.
    pub fn times(&self) -> (u32, u32, u32, u32) {
        let t = self.times;
        (t.up_a, t.down_a, t.up_b, t.down_b)
    }

    /// The current output in 0.01 % (positive: solenoid A, negative: B).
    pub fn output(&self) -> i32 {
        self.core.output
    }

    /// Forces the output to `value` (clamped to ±10000) and drops any partial
    /// progress.
    pub fn reset_to(&mut self, value: i32) {
        self.core = Core {
            output: value.clamp(-FULL_SCALE, FULL_SCALE),
            rem: 0,
        };
    }

    /// Advances the output by `dt_us` toward `target` (clamped to ±10000) and
    /// returns it; see the module docs for the zero crossing.
    pub fn step(&mut self, target: i32, dt_us: u32) -> i32 {
        self.core
            .step(target.clamp(-FULL_SCALE, FULL_SCALE), dt_us, self.times)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn up_ramp_of_100_ms_is_linear_and_reaches_full_scale_at_tick_100() {
        let mut r = Ramp::new(100, 100);
        for k in 1..=100 {
            assert_eq!(r.step(10_000, 1000), 100 * k);
        }
        assert_eq!(r.step(10_000, 1000), 10_000);
    }

    #[test]
    fn down_ramp_uses_the_down_time() {
        let mut r = Ramp::new(1, 200);
        assert_eq!(r.step(10_000, 1000), 10_000);
        // 10000 / 200 ms = 50 per ms.
        for k in 1..=200 {
            assert_eq!(r.step(0, 1000), 10_000 - 50 * k);
        }
        assert_eq!(r.output(), 0);
    }

    #[test]
    fn ramp_time_1_ms_is_a_step() {
        let mut r = Ramp::new(1, 1);
        assert_eq!(r.step(7_300, 1000), 7_300);
        assert_eq!(r.step(0, 1000), 0);
        assert_eq!(r.step(-10_000, 1000), -10_000);
        // A swing across zero is two ramps (down, then up): -100 % -> +100 %
        // takes 2 ms with 1 ms ramps.
        assert_eq!(r.step(10_000, 1000), 0);
        assert_eq!(r.step(10_000, 1000), 10_000);
    }

    #[test]
    fn maximum_ramp_time_120000_ms_reaches_full_scale_after_exactly_120_s() {
        let mut r = Ramp::new(120_000, 120_000);
        for _ in 0..119_999 {
            r.step(10_000, 1000);
        }
        // 10000 * 119999 / 120000 = 9999.9166… -> 9999 after 119999 ms.
        assert_eq!(r.output(), 9_999);
        assert_eq!(r.step(10_000, 1000), 10_000);
        // After 60 s exactly half.
        let mut r = Ramp::new(120_000, 120_000);
        for _ in 0..60 {
            r.step(10_000, 1_000_000);
        }
        assert_eq!(r.output(), 5_000);
    }

    #[test]
    fn fractional_slopes_accumulate_without_drift() {
        // 10000 units in 300 ms = 33.33 per ms; after 3 ms exactly 100.
        let mut r = Ramp::new(300, 300);
        let outs: [i32; 3] = core::array::from_fn(|_| r.step(10_000, 1000));
        assert_eq!(outs, [33, 66, 100]);
        // Odd step sizes: 7 µs steps for 300 ms in total.
        let mut r = Ramp::new(300, 300);
        let mut t = 0u32;
        while t + 7 <= 300_000 {
            r.step(10_000, 7);
            t += 7;
        }
        r.step(10_000, 300_000 - t);
        assert_eq!(r.output(), 10_000);
    }

    #[test]
    fn target_change_mid_ramp_turns_around_with_the_down_slope() {
        let mut r = Ramp::new(100, 50);
        for _ in 0..50 {
            r.step(10_000, 1000);
        }
        assert_eq!(r.output(), 5_000);
        // New lower target: down slope 10000/50 = 200 per ms.
        assert_eq!(r.step(2_000, 1000), 4_800);
        for _ in 0..14 {
            r.step(2_000, 1000);
        }
        assert_eq!(r.output(), 2_000);
        // Target raised again mid-ramp: up slope 100 per ms.
        assert_eq!(r.step(3_000, 1000), 2_100);
        assert_eq!(r.step(2_150, 1000), 2_150); // never overshoots
    }

    #[test]
    fn zero_dt_does_not_move_and_targets_are_clamped() {
        let mut r = Ramp::new(1, 1);
        assert_eq!(r.step(5_000, 0), 0);
        assert_eq!(r.step(i32::MAX, 1000), 10_000);
        assert_eq!(r.step(i32::MIN, u32::MAX), -10_000);
    }

    #[test]
    fn four_quadrant_sign_change_runs_down_a_then_up_b() {
        // RA:UP:A 1, RA:DOWN:A 50, RA:UP:B 200, RA:DOWN:B 1.
        let mut r = FourQuadrantRamp::new(1, 50, 200, 1);
        assert_eq!(r.step(10_000, 1000), 10_000);
        // First RA:DOWN:A to zero: 200 per ms for 50 ms.
        for k in 1..=50 {
            assert_eq!(r.step(-10_000, 1000), 10_000 - 200 * k);
        }
        assert_eq!(r.output(), 0);
        // Then RA:UP:B to -10000: 50 per ms for 200 ms.
        for k in 1..=200 {
            assert_eq!(r.step(-10_000, 1000), -50 * k);
        }
        // Total time = down_a + up_b = 250 ms.
        assert_eq!(r.output(), -10_000);
        // And back: RA:DOWN:B (1 ms) to zero, then RA:UP:A (1 ms).
        assert_eq!(r.step(10_000, 1000), 0);
        assert_eq!(r.step(10_000, 1000), 10_000);
    }

    #[test]
    fn four_quadrant_crossing_within_one_call_carries_the_leftover_time() {
        let mut r = FourQuadrantRamp::new(100, 100, 100, 100);
        r.reset_to(1_000);
        // 10 ms down to 0, then 5 ms up B at 100 per ms -> -500.
        assert_eq!(r.step(-10_000, 15_000), -500);
        // +10000 to -10000 with all times 100 ms takes down_a + up_b = 200 ms.
        let mut r = FourQuadrantRamp::new(100, 100, 100, 100);
        r.reset_to(10_000);
        assert_eq!(r.step(-10_000, 199_999), -9_999);
        assert_eq!(r.step(-10_000, 1), -10_000);
    }
}
