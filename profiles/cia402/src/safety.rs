//! The safety rules of a CiA 402 drive on the core (docs/SAFETY.md,
//! "servo402 and CiA 402 twins": S1, S2, S3 and S5; S4, what the master
//! may write when, is checked by the SDO tests) as a checker that watches
//! a drive from outside, one observation per step.
//!
//! A property test feeds it what a master and a scope would see after
//! every step of a random sequence (the AL state, whether the cyclic
//! outputs are valid and the SM watchdog armed, the statusword, the power
//! stage, the velocity, the time) and fails at the first observation that
//! breaks a rule. It keeps no history beyond what the rules need, so it
//! runs in firmware-sized memory too.

use crate::drive::PowerStage;
use crate::state::PowerState;

/// What is observed after one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Observation {
    /// Time, ns.
    pub now_ns: u64,
    /// The AL state is OP.
    pub op: bool,
    /// The core's `outputs_valid` for this step.
    pub outputs_valid: bool,
    /// The SM watchdog is armed.
    pub watchdog_armed: bool,
    /// 0x6041.
    pub statusword: u16,
    /// 0x603F.
    pub error_code: u16,
    /// 0x606C, inc/s.
    pub velocity: i64,
    /// What the power stage was told.
    pub power_stage: PowerStage,
}

/// A broken rule, with what was seen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Violation {
    /// S5: the statusword codes no state of the PDS FSA.
    #[error("S5: statusword {statusword:#06x} codes no PDS state")]
    Statusword {
        /// 0x6041.
        statusword: u16,
    },
    /// S1: the power stage carries current outside Operation enabled and
    /// the braking states.
    #[error("S1: power stage on in {state:?}")]
    PowerWithoutOperation {
        /// The PDS state shown.
        state: PowerState,
    },
    /// S1: torque reported or produced with the power stage off.
    #[error("S1: torque {torque} with the power stage off")]
    TorqueWithoutPower {
        /// The torque, ‰.
        torque: i16,
    },
    /// S1: Operation enabled without valid cyclic outputs under an armed
    /// SM watchdog in OP.
    #[error(
        "S1: Operation enabled with op={op}, outputs valid={outputs_valid}, watchdog armed={watchdog_armed}"
    )]
    OperationWithoutMaster {
        /// AL state OP.
        op: bool,
        /// Outputs valid.
        outputs_valid: bool,
        /// SM watchdog armed.
        watchdog_armed: bool,
    },
    /// S2: Switched on or Ready to switch on kept without a master.
    #[error("S2: {state:?} kept without a master")]
    ReadyWithoutMaster {
        /// The PDS state shown.
        state: PowerState,
    },
    /// S2: a braking state without a master lasted longer than its bound.
    #[error("S2: {state:?} for {elapsed_ns} ns without a master (bound {bound_ns} ns)")]
    StopTooLong {
        /// The PDS state shown.
        state: PowerState,
        /// How long, ns.
        elapsed_ns: u64,
        /// The bound, ns.
        bound_ns: u64,
    },
    /// S3: the velocity grew in Quick stop active or Fault reaction active.
    #[error("S3: |velocity| {velocity} above {entry} at the start of the {state:?} ramp")]
    Accelerating {
        /// The PDS state shown.
        state: PowerState,
        /// |velocity| now.
        velocity: u64,
        /// |velocity| when the ramp began.
        entry: u64,
    },
    /// S5: Fault without an error code, or with the power stage on.
    #[error("S5: Fault with error code {error_code:#06x}, power stage on {enabled}")]
    FaultNotSafe {
        /// 0x603F.
        error_code: u16,
        /// The power stage.
        enabled: bool,
    },
}

/// Checks observations against S1, S2, S3 and S5. `min_deceleration` (inc/s², the
/// smallest ramp the parameters allow) and `settle_ns` bound how long a
/// stop without a master may take: |v| / deceleration + settle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Checker {
    /// The smallest deceleration of a ramp, inc/s².
    pub min_deceleration: u64,
    /// Time the loops need to come to rest after the ramp, ns.
    pub settle_ns: u64,
    /// Slack on S3 for the loops' rounding, inc/s.
    pub velocity_slack: u64,
    last: Option<PowerState>,
    ramp_entry: u64,
    /// Since when there is no master, and the velocity then.
    lost: Option<(u64, u64)>,
}

impl Checker {
    /// A checker for ramps of at least `min_deceleration` inc/s².
    pub const fn new(min_deceleration: u64) -> Self {
        Checker {
            min_deceleration,
            settle_ns: 100_000_000,
            velocity_slack: 10,
            last: None,
            ramp_entry: 0,
            lost: None,
        }
    }

    /// Checks one observation.
    pub fn check(&mut self, o: &Observation) -> Result<(), Violation> {
        let state = PowerState::from_statusword(o.statusword).ok_or(Violation::Statusword {
            statusword: o.statusword,
        })?;
        let connected = o.op && o.outputs_valid && o.watchdog_armed;
        if o.power_stage.enabled && !state.may_drive() {
            return Err(Violation::PowerWithoutOperation { state });
        }
        if !o.power_stage.enabled && o.power_stage.torque != 0 {
            return Err(Violation::TorqueWithoutPower {
                torque: o.power_stage.torque,
            });
        }
        if state == PowerState::OperationEnabled && !connected {
            return Err(Violation::OperationWithoutMaster {
                op: o.op,
                outputs_valid: o.outputs_valid,
                watchdog_armed: o.watchdog_armed,
            });
        }
        if state == PowerState::Fault && (o.error_code == 0 || o.power_stage.enabled) {
            return Err(Violation::FaultNotSafe {
                error_code: o.error_code,
                enabled: o.power_stage.enabled,
            });
        }
        let speed = o.velocity.unsigned_abs();
        let braking = matches!(
            state,
            PowerState::QuickStopActive | PowerState::FaultReactionActive
        );
        if braking {
            if self.last != Some(state) {
                self.ramp_entry = speed;
            }
            if speed > self.ramp_entry.saturating_add(self.velocity_slack) {
                return Err(Violation::Accelerating {
                    state,
                    velocity: speed,
                    entry: self.ramp_entry,
                });
            }
        }
        if connected {
            self.lost = None;
        } else {
            if matches!(state, PowerState::SwitchedOn | PowerState::ReadyToSwitchOn) {
                return Err(Violation::ReadyWithoutMaster { state });
            }
            let (since, v0) = *self.lost.get_or_insert((o.now_ns, speed));
            if braking {
                let ramp = v0
                    .saturating_mul(1_000_000_000)
                    .checked_div(self.min_deceleration)
                    .unwrap_or(u64::MAX);
                let bound = ramp.saturating_add(self.settle_ns);
                let elapsed = o.now_ns.saturating_sub(since);
                if elapsed > bound {
                    return Err(Violation::StopTooLong {
                        state,
                        elapsed_ns: elapsed,
                        bound_ns: bound,
                    });
                }
            }
        }
        self.last = Some(state);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seen(statusword: u16, enabled: bool) -> Observation {
        Observation {
            now_ns: 0,
            op: true,
            outputs_valid: true,
            watchdog_armed: true,
            statusword,
            error_code: 0,
            velocity: 0,
            power_stage: PowerStage { enabled, torque: 0 },
        }
    }

    #[test]
    fn operation_enabled_with_a_master_and_its_power_stage_passes() {
        let mut c = Checker::new(1_000_000);
        assert_eq!(c.check(&seen(0x1237, true)), Ok(()));
        assert_eq!(c.check(&seen(0x0250, false)), Ok(()));
    }

    #[test]
    fn each_rule_fails_on_the_observation_that_breaks_it() {
        let mut c = Checker::new(1_000_000);
        assert!(matches!(
            c.check(&seen(0x0250, true)),
            Err(Violation::PowerWithoutOperation { .. })
        ));
        assert!(matches!(
            c.check(&seen(0x00FF, false)),
            Err(Violation::Statusword { .. })
        ));
        let mut o = seen(0x0237, true);
        o.watchdog_armed = false;
        assert!(matches!(
            c.check(&o),
            Err(Violation::OperationWithoutMaster { .. })
        ));
        let mut o = seen(0x0233, false);
        o.op = false;
        assert!(matches!(
            c.check(&o),
            Err(Violation::ReadyWithoutMaster { .. })
        ));
        assert!(matches!(
            c.check(&seen(0x0208, false)),
            Err(Violation::FaultNotSafe { .. })
        ));
        let mut o = seen(0x0250, false);
        o.power_stage.torque = 5;
        assert!(matches!(
            c.check(&o),
            Err(Violation::TorqueWithoutPower { .. })
        ));
    }

    #[test]
    fn a_ramp_that_speeds_up_or_lasts_too_long_without_a_master_fails() {
        let mut c = Checker::new(1_000_000);
        let mut o = seen(0x0207, true); // Quick stop active
        o.velocity = 1000;
        assert_eq!(c.check(&o), Ok(()));
        o.velocity = 2000;
        assert!(matches!(c.check(&o), Err(Violation::Accelerating { .. })));
        let mut c = Checker::new(1_000_000);
        let mut o = seen(0x000F, true); // Fault reaction active
        o.op = false;
        o.velocity = 1_000_000; // 1 s at 1e6 inc/s², + 100 ms
        assert_eq!(c.check(&o), Ok(()));
        o.now_ns = 1_100_000_000;
        assert_eq!(c.check(&o), Ok(()));
        o.now_ns = 1_100_000_001;
        assert!(matches!(c.check(&o), Err(Violation::StopTooLong { .. })));
    }

    /// The rules against the drive itself (the device-level property test is
    /// servo402's `tests/invariants.rs`, with AL states and frames).
    mod properties {
        use super::*;
        use crate::drive::{Drive, Link, Parameters, Report, Setpoints};
        use crate::state::control;
        use proptest::prelude::*;

        const MS: u64 = 1_000_000;

        struct Bench {
            drive: Drive,
            p: Parameters,
            sp: Setpoints,
            now: u64,
            link: Link,
            fault: Option<u16>,
            last: Report,
        }

        impl Bench {
            fn run(&mut self, n: usize, dt: u64) {
                for _ in 0..n {
                    self.now += dt;
                    self.last = self
                        .drive
                        .step(&self.sp, self.link, self.fault, &self.p, self.now);
                }
            }
        }

        #[derive(Debug, Clone)]
        enum Step {
            Cycle {
                cw: u16,
                mode: i8,
                position: i32,
                velocity: i32,
                torque: i16,
                dt: u64,
            },
            Link(bool, bool),
            Fault(Option<u16>),
            Options(i16, i16, i16),
            Cut,
        }

        fn step() -> impl Strategy<Value = Step> {
            let cw = prop_oneof![
                Just(0u16),
                Just(control::SHUTDOWN),
                Just(control::SWITCH_ON),
                Just(control::ENABLE_OPERATION),
                Just(control::QUICK_STOP),
                Just(control::FAULT_RESET),
                Just(control::ENABLE_OPERATION | control::NEW_SET_POINT),
                Just(control::ENABLE_OPERATION | control::HALT),
                any::<u16>(),
            ];
            let mode = prop_oneof![
                Just(1i8),
                Just(3),
                Just(6),
                Just(8),
                Just(9),
                Just(10),
                any::<i8>()
            ];
            prop_oneof![
                8 => (cw, mode, any::<i32>(), any::<i32>(), any::<i16>(), 0u64..20_000_000)
                    .prop_map(|(cw, mode, position, velocity, torque, dt)| Step::Cycle {
                        cw, mode, position: position >> (position as u32 % 24), velocity: velocity >> 8,
                        torque, dt
                    }),
                1 => (any::<bool>(), any::<bool>()).prop_map(|(a, b)| Step::Link(a, b)),
                1 => prop::option::of(any::<u16>()).prop_map(Step::Fault),
                1 => (0i16..=3, -1i16..=9, -1i16..=5).prop_map(|(a, q, f)| Step::Options(a, q, f)),
                1 => Just(Step::Cut),
            ]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(64))]
            /// Any controlword, mode, set point, time step, link and fault
            /// sequence: the drive never panics and keeps S1-S3 and S5 at every step.
            #[test]
            fn random_sequences_keep_the_safety_rules(steps in prop::collection::vec(step(), 1..200)) {
                let mut b = Bench {
                    drive: Drive::default(),
                    p: Parameters::DEFAULT,
                    sp: Setpoints::default(),
                    now: 0,
                    link: Link { outputs_valid: true, watchdog_armed: true, dc_cycle_ns: None },
                    fault: None,
                    last: Report::default(),
                };
                let mut checker = Checker::new(1_000_000);
                for s in steps {
                    match s {
                        Step::Cycle { cw, mode, position, velocity, torque, dt } => {
                            b.sp = Setpoints {
                                controlword: cw,
                                mode,
                                target_position: position,
                                target_velocity: velocity,
                                target_torque: torque,
                            };
                            b.run(1, dt);
                        }
                        Step::Link(v, w) => {
                            b.link = Link { outputs_valid: v, watchdog_armed: w, dc_cycle_ns: None };
                            b.run(1, MS);
                        }
                        Step::Fault(f) => {
                            b.fault = f.filter(|&c| c != 0);
                            b.run(1, MS);
                        }
                        Step::Options(a, q, f) => {
                            // Only while the power stage is off (S4).
                            if !b.drive.power_stage_enabled() {
                                b.p.abort_connection_option = a.max(1);
                                b.p.quick_stop_option = q;
                                b.p.fault_reaction_option = f;
                            }
                            b.run(1, MS);
                        }
                        Step::Cut => {
                            b.drive.power_cut();
                            b.run(1, MS);
                        }
                    }
                    let r = b.last;
                    let o = Observation {
                        now_ns: b.now,
                        op: true,
                        outputs_valid: b.link.outputs_valid,
                        watchdog_armed: b.link.watchdog_armed,
                        statusword: r.inputs.statusword,
                        error_code: r.inputs.error_code,
                        velocity: i64::from(r.inputs.velocity),
                        power_stage: r.power_stage,
                    };
                    prop_assert_eq!(checker.check(&o), Ok(()), "{:?} after {:?}", b.drive.state(), s);
                }
            }
        }
    }
}
