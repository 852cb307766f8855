//! The axis a drive moves: its power stage, its inner control loops and
//! the mechanics, behind one trait ([`Axis`]), and [`AxisModel`], a simple
//! deterministic model of one that runs on injected time.
//!
//! The split is the one of real drives: the profile ([`crate::Drive`])
//! generates set points (ramps, profiles, the quick stop) and decides
//! whether the power stage may carry current; the axis (the current,
//! velocity and position loops of the power electronics and the motor
//! with its load) follows them. A firmware on a real board implements
//! [`Axis`] on its power stage and encoder; the simulator, the `servo402`
//! device and twins use [`AxisModel`].
//!
//! Units (no factor group, CiA 402-2 6091h-6097h are 1): positions in
//! increments (inc), in the trait as **milli-increments** (`_m`, 1/1000
//! inc) so slow ramps keep their fractions; velocities in inc/s;
//! accelerations in inc/s²; torques in per mille of the rated torque
//! (CiA 402-2 objects 6071h/6072h/6077h).

/// Nanoseconds per second.
const NS_PER_S: i128 = 1_000_000_000;
/// Milli-increments per increment.
pub const MILLI: i64 = 1_000;
/// The longest step the model integrates at once: a longer gap between
/// two ticks (a firmware that was not polled) is taken as this long, so
/// no product can overflow and a stalled loop does not teleport the axis.
pub const MAX_STEP_NS: u64 = 1_000_000_000;

/// What the drive asks of the axis for the next step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Demand {
    /// Power stage off: no torque, the axis coasts to a stop on its own
    /// friction.
    Off,
    /// Follow a position (milli-inc, not wrapped) with a velocity
    /// feed-forward (inc/s).
    Position {
        /// Demand position, milli-inc.
        position_m: i64,
        /// Velocity feed-forward, inc/s.
        feedforward: i64,
    },
    /// Follow a velocity (inc/s).
    Velocity {
        /// Demand velocity, inc/s.
        velocity: i64,
    },
    /// Produce a torque (per mille of the rated torque).
    Torque {
        /// Demand torque, ‰.
        torque: i64,
    },
}

/// Limits of one step (CiA 402-2 6080h "Max motor speed", 6072h "Max
/// torque").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest velocity in either direction, inc/s.
    pub max_velocity: i64,
    /// Largest torque in either direction, ‰.
    pub max_torque: i64,
}

/// What the axis measured at the end of a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Motion {
    /// Position, milli-inc (not wrapped; 0x6064 is its increments modulo 2³²).
    pub position_m: i64,
    /// Velocity, inc/s.
    pub velocity: i64,
    /// Torque, ‰.
    pub torque: i64,
    /// A limit (velocity or torque) cut the demand in this step.
    pub limited: bool,
}

impl Motion {
    /// The position in whole increments (rounded towards −∞).
    pub const fn position(&self) -> i64 {
        self.position_m.div_euclid(MILLI)
    }
}

/// The axis a [`Drive`](crate::Drive) moves.
pub trait Axis {
    /// Runs the axis for `dt_ns` under `demand` within `limits`; returns
    /// what it measured at the end. `dt_ns` may be 0 (two ticks at the
    /// same instant) and may be long (a firmware that was not polled).
    fn step(&mut self, demand: Demand, limits: Limits, dt_ns: u64) -> Motion;

    /// The last measurement, without moving.
    fn motion(&self) -> Motion;

    /// Redefines the current position as `position_m` (homing on the
    /// current position: the axis does not move, its position value does).
    fn set_position(&mut self, position_m: i64);
}

/// Parameters of [`AxisModel`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModelParams {
    /// Time constant of the position loop, ns: on a ramp of velocity v the
    /// position lags the demand by v × this (no feed-forward in CSP).
    pub position_lag_ns: u64,
    /// Time constant of the velocity loop, ns.
    pub velocity_lag_ns: u64,
    /// Acceleration at the rated torque (1000 ‰), inc/s²: the load's
    /// inertia.
    pub rated_acceleration: i64,
    /// Deceleration of the coasting axis (power stage off), inc/s²: its
    /// friction.
    pub coast_deceleration: i64,
}

impl ModelParams {
    /// A stiff servo: 1 ms loops, 10⁷ inc/s² at rated torque, coasting
    /// stops at 2·10⁵ inc/s².
    pub const DEFAULT: ModelParams = ModelParams {
        position_lag_ns: 1_000_000,
        velocity_lag_ns: 1_000_000,
        rated_acceleration: 10_000_000,
        coast_deceleration: 200_000,
    };
}

impl Default for ModelParams {
    fn default() -> Self {
        ModelParams::DEFAULT
    }
}

/// A simple deterministic axis: a first-order position loop with velocity
/// feed-forward, a first-order velocity loop, a torque mode that
/// accelerates an inertia, friction when the power stage is off. Each
/// loop is integrated with the implicit (backward) Euler rule, which is
/// stable for any step, so the same demands at the same times always give
/// the same motion and a long gap between ticks cannot make it diverge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AxisModel {
    params: ModelParams,
    motion: Motion,
}

/// `v` as an `i64`, saturated.
fn sat(v: i128) -> i64 {
    if v > i128::from(i64::MAX) {
        i64::MAX
    } else if v < i128::from(i64::MIN) {
        i64::MIN
    } else {
        v as i64
    }
}

/// `v` clamped to `-limit..=limit` (`limit` taken as ≥ 0); whether it was cut.
fn clamp_sym(v: i128, limit: i64) -> (i128, bool) {
    let l = i128::from(limit.max(0));
    if v > l {
        (l, true)
    } else if v < -l {
        (-l, true)
    } else {
        (v, false)
    }
}

/// `a × b`, saturated.
fn mul(a: i128, b: i128) -> i128 {
    a.saturating_mul(b)
}

/// `a / b` rounded to the nearest integer (halves away from 0), `b` > 0:
/// the loops reach their target exactly instead of stopping one unit short.
fn div_round(a: i128, b: i128) -> i128 {
    let half = b / 2;
    if a >= 0 {
        a.saturating_add(half) / b
    } else {
        a.saturating_sub(half) / b
    }
}

/// `v` moved towards 0 by `by` (≥ 0), never past it.
fn towards_zero(v: i128, by: i128) -> i128 {
    if v > 0 {
        v.saturating_sub(by).max(0)
    } else {
        v.saturating_add(by).min(0)
    }
}

impl AxisModel {
    /// A model at position 0, at rest.
    pub const fn new(params: ModelParams) -> Self {
        AxisModel {
            params,
            motion: Motion {
                position_m: 0,
                velocity: 0,
                torque: 0,
                limited: false,
            },
        }
    }

    /// Its parameters.
    pub const fn params(&self) -> &ModelParams {
        &self.params
    }
}

impl Axis for AxisModel {
    fn step(&mut self, demand: Demand, limits: Limits, dt_ns: u64) -> Motion {
        let dt = i128::from(dt_ns.min(MAX_STEP_NS));
        let p = self.params;
        let v0 = i128::from(self.motion.velocity);
        let x0 = i128::from(self.motion.position_m);
        if dt == 0 {
            // No time passes: nothing moves; the torque is what the
            // demand asks (or none without power).
            self.motion.torque = match demand {
                Demand::Off => 0,
                Demand::Torque { torque } => {
                    sat(clamp_sym(i128::from(torque), limits.max_torque).0)
                }
                _ => self.motion.torque,
            };
            return self.motion;
        }
        // Distance in milli-inc covered at `v` inc/s during the step.
        let distance = |v: i128| mul(mul(v, dt), i128::from(MILLI)) / NS_PER_S;
        let mut limited = false;
        // (velocity at the end, position change in milli-inc, torque if commanded)
        let (v1, dx, torque) = match demand {
            Demand::Off => {
                let dv = mul(i128::from(p.coast_deceleration.max(0)), dt) / NS_PER_S;
                let v1 = towards_zero(v0, dv);
                // The mean velocity over the step.
                (v1, distance(v0.saturating_add(v1)) / 2, Some(0))
            }
            Demand::Position {
                position_m,
                feedforward,
            } => {
                let ff = distance(i128::from(feedforward));
                let predicted = x0.saturating_add(ff);
                let tau = i128::from(p.position_lag_ns);
                let error = i128::from(position_m).saturating_sub(predicted);
                let dx = ff.saturating_add(div_round(mul(error, dt), tau + dt));
                let v = mul(dx, NS_PER_S) / mul(dt, i128::from(MILLI));
                let (v1, cut) = clamp_sym(v, limits.max_velocity);
                limited |= cut;
                (v1, if cut { distance(v1) } else { dx }, None)
            }
            Demand::Velocity { velocity } => {
                let (vd, cut) = clamp_sym(i128::from(velocity), limits.max_velocity);
                limited |= cut;
                let tau = i128::from(p.velocity_lag_ns);
                let v1 = v0.saturating_add(div_round(mul(vd.saturating_sub(v0), dt), tau + dt));
                (v1, distance(v1), None)
            }
            Demand::Torque { torque } => {
                let (t, cut) = clamp_sym(i128::from(torque), limits.max_torque);
                limited |= cut;
                let a = mul(t, i128::from(p.rated_acceleration)) / 1000;
                let (v1, cut) = clamp_sym(
                    v0.saturating_add(mul(a, dt) / NS_PER_S),
                    limits.max_velocity,
                );
                limited |= cut;
                (v1, distance(v1), Some(sat(t)))
            }
        };
        let torque = match torque {
            Some(t) => t,
            None => {
                // What the motion took: its acceleration over the rated one.
                let a = mul(v1.saturating_sub(v0), NS_PER_S) / dt;
                let rated = i128::from(p.rated_acceleration.max(1));
                let (t, cut) = clamp_sym(mul(a, 1000) / rated, limits.max_torque);
                limited |= cut;
                sat(t)
            }
        };
        self.motion = Motion {
            position_m: sat(x0.saturating_add(dx)),
            velocity: sat(v1),
            torque,
            limited,
        };
        self.motion
    }

    fn motion(&self) -> Motion {
        self.motion
    }

    fn set_position(&mut self, position_m: i64) {
        self.motion.position_m = position_m;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;
    const LIMITS: Limits = Limits {
        max_velocity: 1_000_000,
        max_torque: 3000,
    };

    #[test]
    fn a_position_ramp_is_followed_with_a_lag_of_velocity_times_the_time_constant() {
        let mut m = AxisModel::default();
        let v = 100_000; // inc/s: 100 inc per ms
        let mut last = Motion::default();
        for k in 1..=200 {
            last = m.step(
                Demand::Position {
                    position_m: k * 100 * MILLI,
                    feedforward: 0,
                },
                LIMITS,
                MS,
            );
        }
        let lag = 200 * 100 - last.position();
        // v × τ = 100 inc, within rounding.
        assert!((99..=101).contains(&lag), "lag {lag} inc");
        assert!((last.velocity - v).abs() <= 10, "{}", last.velocity);
        assert!(!last.limited);
    }

    #[test]
    fn the_same_ramp_sampled_finer_settles_to_the_same_lag() {
        let mut m = AxisModel::default();
        let mut last = Motion::default();
        // 20 us steps, the demand moving 2 inc per step (100 000 inc/s).
        for k in 1..=10_000 {
            last = m.step(
                Demand::Position {
                    position_m: k * 2 * MILLI,
                    feedforward: 0,
                },
                LIMITS,
                20_000,
            );
        }
        let lag = 20_000 - last.position();
        assert!((99..=101).contains(&lag), "lag {lag} inc");
    }

    #[test]
    fn feedforward_removes_the_lag_of_a_ramp() {
        let mut m = AxisModel::default();
        let mut last = Motion::default();
        for k in 1..=100 {
            last = m.step(
                Demand::Position {
                    position_m: k * 100 * MILLI,
                    feedforward: 100_000,
                },
                LIMITS,
                MS,
            );
        }
        assert!((100 * 100 - last.position()).abs() <= 1);
    }

    #[test]
    fn a_jump_beyond_the_velocity_limit_is_cut_and_reported() {
        let mut m = AxisModel::default();
        let out = m.step(
            Demand::Position {
                position_m: 1_000_000 * MILLI,
                feedforward: 0,
            },
            LIMITS,
            MS,
        );
        assert_eq!(out.velocity, LIMITS.max_velocity);
        assert_eq!(out.position(), 1_000, "1 ms at the limit");
        assert!(out.limited);
    }

    #[test]
    fn without_power_the_axis_coasts_to_rest_on_its_friction() {
        let mut m = AxisModel::default();
        m.step(Demand::Velocity { velocity: 10_000 }, LIMITS, 100 * MS);
        let v = m.motion().velocity;
        assert!(v > 9_000, "{v}");
        let mut t = 0;
        while m.motion().velocity != 0 {
            let out = m.step(Demand::Off, LIMITS, MS);
            assert_eq!(out.torque, 0);
            assert!(out.velocity <= v);
            t += 1;
        }
        // 2e5 inc/s² stops 10 000 inc/s in 50 ms.
        assert!((45..=55).contains(&t), "{t} ms");
    }

    #[test]
    fn torque_accelerates_the_inertia_up_to_the_velocity_limit() {
        let mut m = AxisModel::default();
        let out = m.step(Demand::Torque { torque: 100 }, LIMITS, MS);
        // 100 ‰ of 1e7 inc/s² for 1 ms.
        assert_eq!(out.velocity, 1_000);
        assert_eq!(out.torque, 100);
        let out = m.step(Demand::Torque { torque: 5000 }, LIMITS, 100 * MS);
        assert_eq!(out.torque, 3000, "cut to the maximum");
        assert_eq!(out.velocity, LIMITS.max_velocity);
        assert!(out.limited);
    }

    #[test]
    fn extreme_demands_and_gaps_saturate_instead_of_overflowing() {
        let mut m = AxisModel::default();
        let huge = Limits {
            max_velocity: i64::MAX,
            max_torque: i64::MAX,
        };
        for d in [
            Demand::Position {
                position_m: i64::MAX,
                feedforward: i64::MAX,
            },
            Demand::Position {
                position_m: i64::MIN,
                feedforward: i64::MIN,
            },
            Demand::Velocity { velocity: i64::MIN },
            Demand::Torque { torque: i64::MAX },
            Demand::Off,
        ] {
            for dt in [0, 1, MS, u64::MAX] {
                m.step(d, huge, dt);
                m.step(d, LIMITS, dt);
            }
        }
        m.set_position(i64::MAX);
        m.step(Demand::Velocity { velocity: i64::MAX }, huge, u64::MAX);
    }

    #[test]
    fn a_step_of_zero_time_moves_nothing() {
        let mut m = AxisModel::default();
        m.step(Demand::Velocity { velocity: 5_000 }, LIMITS, 10 * MS);
        let before = m.motion();
        let after = m.step(Demand::Velocity { velocity: 0 }, LIMITS, 0);
        assert_eq!(after.position_m, before.position_m);
        assert_eq!(after.velocity, before.velocity);
    }
}
