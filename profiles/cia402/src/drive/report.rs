//! What one step reports: the following error monitor, the TxPDO values
//! ([`Inputs`]) and the statusword's mode-specific bits.

use super::*;

impl<A: Axis> Drive<A> {
    /// The following error (inc) and whether it just timed out.
    pub(super) fn monitor(&mut self, motion: &Motion, p: &Parameters, now_ns: u64) -> (i64, bool) {
        if self.state != PowerState::OperationEnabled || !self.mode.controls_position() {
            self.following_since = None;
            self.warning = false;
            return (0, false);
        }
        // In whole increments, so 0x60F4 = 0x6062 − 0x6064 as the master reads them.
        let error = self
            .demand_m
            .div_euclid(MILLI)
            .saturating_sub(motion.position());
        if p.following_error_window == u32::MAX
            || error.unsigned_abs() <= u64::from(p.following_error_window)
        {
            self.following_since = None;
            self.warning = false;
            return (error, false);
        }
        self.warning = true;
        let since = *self.following_since.get_or_insert(now_ns);
        let timeout = u64::from(p.following_error_timeout_ms).saturating_mul(NS_PER_MS);
        (error, now_ns.saturating_sub(since) >= timeout)
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn inputs(
        &self,
        motion: &Motion,
        following_error: i64,
        cut: bool,
        connected: bool,
        sp: &Setpoints,
        cw: u16,
        p: &Parameters,
    ) -> Inputs {
        let mut sw = self.state.statusword_bits();
        if connected {
            sw |= status::REMOTE;
        }
        if self.warning {
            sw |= status::WARNING;
        }
        if self.state.may_drive() && (cut || motion.limited) {
            sw |= status::INTERNAL_LIMIT;
        }
        if self.state == PowerState::OperationEnabled {
            sw |= self.mode_bits(motion, sp, cw, p);
        }
        if self.following_fault {
            sw |= status::MODE_SPECIFIC_13;
        }
        Inputs {
            statusword: sw,
            mode_display: self.mode.code(),
            position: motion.position() as i32,
            velocity: sat_i32(motion.velocity),
            torque: if self.state.may_drive() {
                sat_i16(motion.torque)
            } else {
                0
            },
            following_error: sat_i32(following_error),
            position_demand: self.demand_m.div_euclid(MILLI) as i32,
            error_code: self.error_code,
        }
    }

    /// Statusword bits 10, 12, 13 of the mode in Operation enabled.
    pub(super) fn mode_bits(
        &self,
        motion: &Motion,
        sp: &Setpoints,
        cw: u16,
        p: &Parameters,
    ) -> u16 {
        let halt = cw & control::HALT != 0;
        let v = motion.velocity;
        let still = v.unsigned_abs() <= u64::from(p.velocity_threshold);
        let bit = |on: bool, b: u16| if on { b } else { 0 };
        match self.mode {
            // "Target value ignored": 1 = the target is used.
            Mode::CyclicPosition | Mode::CyclicVelocity | Mode::CyclicTorque => {
                status::MODE_SPECIFIC_12
            }
            Mode::ProfileVelocity => {
                let target = i64::from(sp.target_velocity)
                    .clamp(-i64::from(p.max_motor_speed), i64::from(p.max_motor_speed));
                let reached = if halt {
                    still
                } else {
                    v.saturating_sub(target).unsigned_abs() <= u64::from(p.velocity_window)
                };
                bit(reached, status::TARGET_REACHED) | bit(still, status::MODE_SPECIFIC_12)
            }
            Mode::ProfilePosition => {
                let at_target = self.velocity_demand == 0
                    && self.demand_m == self.pp_target_m
                    && (i128::from(motion.position_m) - i128::from(self.pp_target_m)).abs()
                        <= i128::from(p.position_window) * i128::from(MILLI);
                let reached = if halt {
                    self.velocity_demand == 0 && still
                } else {
                    at_target
                };
                bit(reached, status::TARGET_REACHED) | bit(self.pp_ack, status::MODE_SPECIFIC_12)
            }
            Mode::Homing => {
                bit(
                    self.homing_attained,
                    status::TARGET_REACHED | status::MODE_SPECIFIC_12,
                ) | bit(self.homing_error, status::MODE_SPECIFIC_13)
            }
        }
    }
}
