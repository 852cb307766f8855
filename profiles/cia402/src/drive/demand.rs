//! The demand of one step: what the mode asks of the axis (the profile
//! generators of PP and PV, the interpolated CSP set points, homing, the
//! ramps of quick stop and fault reactions), within the limits.

use super::*;

impl<A: Axis> Drive<A> {
    /// This step's demand to the axis; whether a limit cut a set point.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn demand(
        &mut self,
        sp: &Setpoints,
        cw: u16,
        rising: u16,
        link: Link,
        p: &Parameters,
        now_ns: u64,
        dt: u64,
    ) -> (Demand, bool) {
        let actual = self.axis.motion();
        match self.state {
            PowerState::OperationEnabled => self.mode_demand(sp, cw, rising, link, p, now_ns, dt),
            PowerState::QuickStopActive | PowerState::FaultReactionActive => {
                let Some(r) = &mut self.ramp else {
                    return (Demand::Off, false);
                };
                let v0 = i128::from(r.velocity);
                let dv = delta_v(r.deceleration, dt);
                let v = towards(v0, 0, dv);
                let dx = if v == 0 && dv > 0 {
                    // Stops within the step: v0² / (2 dec).
                    v0.saturating_mul(v0.abs())
                        .saturating_mul(i128::from(MILLI))
                        / (2 * i128::from(r.deceleration.max(1)))
                } else {
                    // Mean velocity over the step.
                    distance(v0.saturating_add(v), dt) / 2
                };
                r.velocity = sat(v);
                self.demand_m = sat(i128::from(self.demand_m).saturating_add(dx));
                (
                    Demand::Position {
                        position_m: self.demand_m,
                        feedforward: r.velocity,
                    },
                    false,
                )
            }
            _ => {
                // No torque: the demand follows the axis.
                self.demand_m = actual.position_m;
                self.velocity_demand = actual.velocity;
                self.segment = None;
                (Demand::Off, false)
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn mode_demand(
        &mut self,
        sp: &Setpoints,
        cw: u16,
        rising: u16,
        link: Link,
        p: &Parameters,
        now_ns: u64,
        dt: u64,
    ) -> (Demand, bool) {
        let actual = self.axis.motion();
        let vmax = i64::from(p.max_motor_speed);
        let halt = cw & control::HALT != 0;
        match self.mode {
            Mode::CyclicPosition => {
                let target_m = unwrap_near(sp.target_position, self.demand_m);
                let new = self.segment.is_none_or(|s| s.to_m != target_m);
                if new {
                    // A set point delivered at SYNC0: the previous one is
                    // reached by now (its segment has run its cycle), or
                    // the new one starts from where the demand is.
                    let from_m = match self.segment {
                        Some(s) if now_ns.saturating_sub(s.t0_ns) >= s.len_ns => s.to_m,
                        _ => self.demand_m,
                    };
                    self.segment = Some(Segment {
                        from_m,
                        to_m: target_m,
                        t0_ns: now_ns,
                        len_ns: link.dc_cycle_ns.map_or(0, u64::from),
                    });
                }
                if let Some(s) = &self.segment {
                    self.demand_m = s.at(now_ns);
                }
                (
                    Demand::Position {
                        position_m: self.demand_m,
                        feedforward: 0,
                    },
                    false,
                )
            }
            Mode::CyclicVelocity => {
                self.demand_m = actual.position_m;
                let target = i64::from(sp.target_velocity);
                (
                    Demand::Velocity {
                        velocity: target.clamp(-vmax, vmax),
                    },
                    target.abs() > vmax,
                )
            }
            Mode::CyclicTorque => {
                self.demand_m = actual.position_m;
                let target = i64::from(sp.target_torque);
                let tmax = i64::from(p.max_torque);
                (
                    Demand::Torque {
                        torque: target.clamp(-tmax, tmax),
                    },
                    target.abs() > tmax,
                )
            }
            Mode::ProfileVelocity => {
                self.demand_m = actual.position_m;
                let requested = i64::from(sp.target_velocity);
                let target = if halt {
                    0
                } else {
                    requested.clamp(-vmax, vmax)
                };
                let v = i128::from(self.velocity_demand);
                let speeding_up = (target > 0 && v >= 0 && i128::from(target) > v)
                    || (target < 0 && v <= 0 && i128::from(target) < v);
                let rate = if speeding_up {
                    p.profile_acceleration
                } else {
                    p.profile_deceleration
                };
                let v = towards(v, i128::from(target), delta_v(i64::from(rate), dt));
                self.velocity_demand = sat(v);
                (
                    Demand::Velocity {
                        velocity: self.velocity_demand,
                    },
                    !halt && requested.abs() > vmax,
                )
            }
            Mode::ProfilePosition => {
                if rising & control::NEW_SET_POINT != 0 {
                    self.pp_target_m = if cw & control::RELATIVE != 0 {
                        self.pp_target_m
                            .saturating_add(i64::from(sp.target_position).saturating_mul(MILLI))
                    } else {
                        unwrap_near(sp.target_position, self.demand_m)
                    };
                    self.pp_ack = true;
                }
                if cw & control::NEW_SET_POINT == 0 {
                    self.pp_ack = false;
                }
                let cut = self.profile_position(halt, p, dt);
                (
                    Demand::Position {
                        position_m: self.demand_m,
                        feedforward: self.velocity_demand,
                    },
                    cut,
                )
            }
            Mode::Homing => {
                if rising & control::NEW_SET_POINT != 0 {
                    if HOMING_METHODS.contains(&p.homing_method) {
                        // Homing on the current position: the position
                        // actual value becomes the home offset.
                        let home = i64::from(p.home_offset).saturating_mul(MILLI);
                        self.axis.set_position(home);
                        self.demand_m = home;
                        self.homing_attained = true;
                        self.homing_error = false;
                    } else {
                        self.homing_attained = false;
                        self.homing_error = true;
                    }
                }
                (
                    Demand::Position {
                        position_m: self.demand_m,
                        feedforward: 0,
                    },
                    false,
                )
            }
        }
    }

    /// One step of the trapezoidal profile to `pp_target_m`: accelerate at
    /// 0x6083 up to 0x6081 (at most 0x6080), brake at 0x6084 in time;
    /// `halt` brakes to a stop. Whether 0x6080 cut the profile velocity.
    pub(super) fn profile_position(&mut self, halt: bool, p: &Parameters, dt: u64) -> bool {
        let vmax = i128::from(p.profile_velocity.min(p.max_motor_speed));
        let cut = p.profile_velocity > p.max_motor_speed;
        let acc = delta_v(i64::from(p.profile_acceleration.max(1)), dt);
        let dec_rate = i128::from(p.profile_deceleration.max(1));
        let dec = delta_v(i64::from(p.profile_deceleration.max(1)), dt);
        let mut v = i128::from(self.velocity_demand);
        let x = i128::from(self.demand_m);
        let target = i128::from(self.pp_target_m);
        let remaining = target - x;
        if halt {
            v = towards(v, 0, dec);
        } else if remaining == 0 && v == 0 {
            return cut;
        } else {
            let dir = remaining.signum();
            // Braking distance at v, milli-inc: v² / (2 dec).
            let stop_m = v.saturating_mul(v).saturating_mul(i128::from(MILLI)) / (2 * dec_rate);
            if (v != 0 && v.signum() != dir) || stop_m >= remaining.abs() {
                v = towards(v, 0, dec);
            } else if v.abs() > vmax {
                v = towards(v, dir * vmax, dec);
            } else {
                v = towards(v, dir * vmax, acc);
            }
        }
        let approaching = !halt && v.signum() == remaining.signum();
        let mut next = x.saturating_add(distance(v, dt));
        if approaching && (target - next).signum() != remaining.signum() {
            // The last step reaches (or would pass) the target: stop on it.
            next = target;
            v = 0;
        }
        if !halt && v == 0 && (target - next).abs() <= i128::from(MILLI) / 2 {
            // Within half an increment at rest: on target.
            next = target;
        }
        self.demand_m = sat(next);
        self.velocity_demand = sat(v);
        cut
    }

    /// Standstill at the end of a ramp: its next state (12, 14), or holding.
    pub(super) fn end_ramp(&mut self, motion: &Motion, p: &Parameters) {
        let Some(r) = &mut self.ramp else {
            return;
        };
        let still = r.velocity == 0 && motion.velocity.abs() <= i64::from(p.velocity_threshold);
        if !still || r.done {
            return;
        }
        if r.then == PowerState::QuickStopActive {
            // Options 5-8: hold the position in Quick stop active.
            r.done = true;
        } else {
            self.state = r.then;
            self.ramp = None;
        }
    }
}
