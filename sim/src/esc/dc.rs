//! The Distributed Clocks unit's time base (ETG.1000.4 §6.8 "Distributed
//! clock"; ET1100 Section I ch. 9 "Distributed Clocks").
//!
//! Every ESC has a free-running **local time** (ns, 64 bit, 0 at power-on)
//! driven by its own oscillator, which runs fast or slow by a few ppm.
//! The master turns it into the common **system time** with three
//! registers: the system time offset (0x0920, local → system), the
//! transmission delay (0x0928, how long a frame takes from the reference
//! clock to this ESC) and the drift control: each time the master
//! distributes the reference clock's system time (an ARMW/FRMW to 0x0910
//! that the reference answers with its time and the others receive as a
//! write), the ESC compares it (plus its delay) with its own system time,
//! shows the difference in 0x092C, and speeds its clock up or slows it
//! down until the difference goes to zero. Nothing steps the clock: the
//! control loop only changes its rate, as the ET1100's speed counter
//! does, within a bounded range.
//!
//! Here the oscillator is a rate relative to the injected (simulation)
//! time, with a configurable error in parts per billion, so every soft
//! slave's clock really drifts and the drift control really has to steer
//! it; convergence is a measurable property, not an assumption.

/// Largest rate correction the drift control applies, in parts per
/// billion (±0.5 ‰). An oscillator error beyond it cannot be compensated,
/// as on silicon (ESC oscillators are specified to ±25 ppm and better).
pub const MAX_CORRECTION_PPB: i64 = 500_000;

/// Largest oscillator error a soft ESC takes, ppb (±10 %; a crystal is
/// off by tens of ppm).
pub const MAX_ERROR_PPB: i64 = 100_000_000;

/// Largest difference the drift control takes in, ns (larger ones are
/// clamped: it only ever slews, and its arithmetic stays in range).
const MAX_DIFFERENCE_NS: i64 = 1 << 40;

/// Proportional gain of the drift control: ppb of rate correction per ns
/// of filtered difference. With it a difference of 1 µs corrects at
/// 100 ppm, i.e. by 1 µs in about 10 ms.
const KP_PPB_PER_NS: i64 = 100;

/// Integral gain: ppb added to the standing correction per ns of
/// difference and per received time (it absorbs the oscillator's error,
/// so the difference settles at zero instead of at drift / Kp).
const KI_PPB_PER_NS: i64 = 2;

/// A soft ESC's oscillator and its drift control state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DcClock {
    /// Oscillator error: the local clock runs `1 + error` times as fast as
    /// the injected time.
    error_ppb: i64,
    /// The drift control's standing correction (its integral part).
    integral_ppb: i64,
    /// The drift control's current total correction.
    correction_ppb: i64,
    /// Injected time and local time at the last change of rate.
    base_t: u64,
    base_local: u64,
    /// Filtered system time difference, ns (signed: own - received).
    filtered: i64,
    /// Received times so far (for the filter's start).
    received: u32,
}

impl Default for DcClock {
    fn default() -> Self {
        DcClock::new(0)
    }
}

impl DcClock {
    /// A clock whose oscillator runs `error_ppb` parts per billion fast
    /// (negative: slow), local time 0 at injected time 0.
    pub const fn new(error_ppb: i64) -> Self {
        let error_ppb = if error_ppb > MAX_ERROR_PPB {
            MAX_ERROR_PPB
        } else if error_ppb < -MAX_ERROR_PPB {
            -MAX_ERROR_PPB
        } else {
            error_ppb
        };
        DcClock {
            error_ppb,
            integral_ppb: 0,
            correction_ppb: 0,
            base_t: 0,
            base_local: 0,
            filtered: 0,
            received: 0,
        }
    }

    /// The oscillator error in ppb.
    pub fn error_ppb(&self) -> i64 {
        self.error_ppb
    }

    /// The drift control's current rate correction in ppb.
    pub fn correction_ppb(&self) -> i64 {
        self.correction_ppb
    }

    /// Power-on at injected time `t`: local time restarts from 0, the drift
    /// control forgets what it learnt; the oscillator stays what it is.
    pub fn power_on(&mut self, t: u64) {
        *self = DcClock {
            base_t: t,
            ..DcClock::new(self.error_ppb)
        };
    }

    /// Resets the drift control (filter, correction) at injected time `t`,
    /// as a write of the speed counter start (0x0930) does on an ESC;
    /// local time runs on.
    pub fn reset_control(&mut self, t: u64) {
        self.rebase(t);
        self.integral_ppb = 0;
        self.correction_ppb = 0;
        self.filtered = 0;
        self.received = 0;
    }

    /// Sets the local time to `local` at injected time `t` (a slave that
    /// powered on at another moment than its neighbours).
    pub fn set_local(&mut self, t: u64, local: u64) {
        self.base_t = t;
        self.base_local = local;
    }

    /// Changes the oscillator's error from injected time `t` on (a
    /// temperature change, a test).
    /// (clamped to ±[`MAX_ERROR_PPB`]).
    pub fn set_error_ppb(&mut self, error_ppb: i64, t: u64) {
        self.rebase(t);
        self.error_ppb = error_ppb.clamp(-MAX_ERROR_PPB, MAX_ERROR_PPB);
    }

    /// Local time (ns) at injected time `t`. Times before the last rate
    /// change read as that change's local time (the clock never runs
    /// backwards).
    pub fn local(&self, t: u64) -> u64 {
        let dt = i128::from(t.saturating_sub(self.base_t));
        let rate = 1_000_000_000i128 + i128::from(self.error_ppb) + i128::from(self.correction_ppb);
        let advanced = dt * rate / 1_000_000_000;
        self.base_local
            .wrapping_add(u64::try_from(advanced.max(0)).unwrap_or(u64::MAX))
    }

    fn rebase(&mut self, t: u64) {
        if t > self.base_t {
            self.base_local = self.local(t);
            self.base_t = t;
        }
    }

    /// The drift control's reaction to a distributed system time, received
    /// at injected time `t`: `difference` = own system time − (received
    /// time + transmission delay), ns. `filter_depth` is 0x0934's low
    /// nibble (the difference is averaged over about 2^depth receptions).
    /// Returns the filtered difference.
    pub fn receive(&mut self, difference: i64, filter_depth: u8, t: u64) -> i64 {
        self.rebase(t);
        let difference = difference.clamp(-MAX_DIFFERENCE_NS, MAX_DIFFERENCE_NS);
        let depth = u32::from(filter_depth.min(15));
        if self.received == 0 {
            self.filtered = difference;
        } else {
            // Exponential average with weight 2^-depth.
            let step = (difference - self.filtered) >> depth.min(6);
            self.filtered += step;
        }
        self.received = self.received.saturating_add(1);
        // PI control on the (filtered) phase difference: a clock ahead
        // (difference > 0) slows down.
        let e = self.filtered.clamp(-1_000_000, 1_000_000);
        self.integral_ppb =
            (self.integral_ppb - KI_PPB_PER_NS * e).clamp(-MAX_CORRECTION_PPB, MAX_CORRECTION_PPB);
        self.correction_ppb =
            (self.integral_ppb - KP_PPB_PER_NS * e).clamp(-MAX_CORRECTION_PPB, MAX_CORRECTION_PPB);
        self.filtered
    }
}

/// The system time difference register (0x092C) for a difference `d`
/// (own − received, ns): bit 31 set when the local copy of the system
/// time is smaller than the received one, bits 30..0 the magnitude,
/// saturated (ET1100 Section II, 0x092C).
pub fn difference_register(d: i64) -> u32 {
    let magnitude = u32::try_from(d.unsigned_abs().min(0x7FFF_FFFF)).unwrap_or(0x7FFF_FFFF);
    if d < 0 {
        magnitude | 0x8000_0000
    } else {
        magnitude
    }
}

/// The signed difference a 0x092C value stands for (see
/// [`difference_register`]).
pub fn difference_of_register(v: u32) -> i64 {
    let m = i64::from(v & 0x7FFF_FFFF);
    if v & 0x8000_0000 != 0 { -m } else { m }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fast_oscillator_gains_its_error_on_the_injected_time() {
        let c = DcClock::new(20_000); // +20 ppm
        assert_eq!(c.local(1_000_000_000), 1_000_020_000);
        let s = DcClock::new(-5_000);
        assert_eq!(s.local(2_000_000_000), 1_999_990_000);
        assert_eq!(DcClock::default().local(123), 123);
    }

    #[test]
    fn the_drift_control_removes_an_oscillator_error_without_stepping_the_clock() {
        // A slave 30 ppm fast, 2 us ahead, against a perfect reference;
        // the master distributes the time every 1 ms.
        let mut c = DcClock::new(30_000);
        let offset: i64 = 2_000;
        let mut last_local = 0;
        let mut diff = 0;
        for k in 1..=3_000u64 {
            let t = k * 1_000_000;
            let own = c.local(t) as i64 + offset;
            diff = own - t as i64;
            assert!(c.local(t) >= last_local, "never backwards");
            last_local = c.local(t);
            c.receive(diff, 0, t);
        }
        // Whole-ns local time makes the loop dither by a few ns.
        assert!(diff.abs() <= 10, "settled at {diff} ns");
        assert!(
            (c.correction_ppb() + 30_000).abs() < 1_500,
            "the correction cancels the +30 ppm: {}",
            c.correction_ppb()
        );
    }

    #[test]
    fn an_error_beyond_the_correction_range_is_not_compensated() {
        let mut c = DcClock::new(2_000_000); // 2000 ppm: broken crystal
        let mut diff = 0;
        for k in 1..=1_000u64 {
            let t = k * 1_000_000;
            diff = c.local(t) as i64 - t as i64;
            c.receive(diff, 0, t);
        }
        assert_eq!(c.correction_ppb(), -MAX_CORRECTION_PPB);
        assert!(diff > 1_000_000, "the difference keeps growing: {diff}");
    }

    #[test]
    fn difference_register_has_sign_bit_31_and_saturates() {
        assert_eq!(difference_register(5), 5);
        assert_eq!(difference_register(-5), 0x8000_0005);
        assert_eq!(difference_register(i64::MIN), 0xFFFF_FFFF);
        assert_eq!(difference_register(1 << 40), 0x7FFF_FFFF);
        for d in [0, 1, -1, 123_456, -987_654] {
            assert_eq!(difference_of_register(difference_register(d)), d);
        }
    }

    #[test]
    fn resetting_the_control_forgets_the_correction_but_not_the_time() {
        let mut c = DcClock::new(0);
        c.receive(1_000_000, 0, 1_000);
        assert_ne!(c.correction_ppb(), 0);
        let before = c.local(2_000);
        c.reset_control(2_000);
        assert_eq!(c.correction_ppb(), 0);
        assert_eq!(c.local(2_000), before);
        assert_eq!(c.local(1_002_000), before + 1_000_000, "nominal rate again");
    }

    #[test]
    fn extreme_inputs_neither_panic_nor_leave_the_bounds() {
        let mut c = DcClock::new(i64::MAX);
        assert_eq!(c.error_ppb(), MAX_ERROR_PPB);
        c.set_error_ppb(i64::MIN, 0);
        assert_eq!(c.error_ppb(), -MAX_ERROR_PPB);
        for d in [i64::MAX, i64::MIN, 0, i64::MAX, i64::MIN] {
            c.receive(d, 0, 10);
            assert!(c.correction_ppb().abs() <= MAX_CORRECTION_PPB);
        }
        let _ = c.local(u64::MAX);
    }

    #[test]
    fn power_on_restarts_local_time_and_keeps_the_oscillator() {
        let mut c = DcClock::new(10_000);
        c.receive(500, 0, 1_000);
        c.power_on(5_000_000);
        assert_eq!(c.local(5_000_000), 0);
        assert_eq!(c.correction_ppb(), 0);
        assert_eq!(c.error_ppb(), 10_000);
    }
}
