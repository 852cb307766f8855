//! The safety rules of docs/SAFETY.md (servo402: S1-S3 and S5; the SDO
//! writes of S4 are among the steps, their refusals are checked by
//! `tests.rs`) as invariants:
//! random sequences of what a master and the world can do (controlwords,
//! modes and set points in cyclic frames, enable sequences and ramps,
//! frames that stop, AL state requests, the SM watchdog switched off and
//! on, SDO writes of the profile's objects with any value of their type,
//! faults of the power stage, stalls of the firmware, power cycles, time
//! steps from 0 to 150 ms) drive a servo402 on the software ESC, and
//! after every step [`ecat_cia402::safety::Checker`] judges what the wire
//! and the board show. A planted violation (an application that tells
//! the drive its outputs are always valid) shows that the checker fails
//! when a rule breaks.

use super::*;
use ecat_cia402::safety::{Checker, Observation, Violation};
use ecat_slave::device::{FULL_PASS_NS, StateChange, Tick};
use ecat_slave::hal::NvStorage;
use ecat_slave::od::Od;
use proptest::prelude::*;

/// An application whose board the harness can see.
trait WithBoard: Application {
    fn sim_board(&self) -> &SimBoard;
    fn sim_board_mut(&mut self) -> &mut SimBoard;
}

impl WithBoard for Servo402 {
    fn sim_board(&self) -> &SimBoard {
        self.board()
    }
    fn sim_board_mut(&mut self) -> &mut SimBoard {
        self.board_mut()
    }
}

/// The planted violation: the servo402 with an application that keeps
/// the last valid controlword when the outputs stop being valid and tells
/// the drive they still are (a firmware that latches its set points).
struct Lying(Servo402, i64);

impl Application for Lying {
    fn description(&self) -> &'static ecat_slave::device::DeviceDescription {
        self.0.description()
    }
    type Values = <Servo402 as Application>::Values;
    fn power_on(&mut self, od: &mut Od) {
        self.0.power_on(od);
    }
    fn state_change(
        &mut self,
        od: &mut Od,
        c: &StateChange,
    ) -> Result<(), ecat_slave::al::AlStatusCode> {
        self.0.state_change(od, c)
    }
    fn sdo_download(&mut self, od: &mut Od, d: &Download<'_>) -> Result<Write, SdoAbortCode> {
        self.0.sdo_download(od, d)
    }
    fn tick(&mut self, t: &mut Tick<'_>) {
        if t.outputs_valid {
            self.1 = t.od.get(index::CONTROLWORD, 0).unwrap_or(0);
        } else {
            t.od.set(index::CONTROLWORD, 0, self.1);
        }
        t.outputs_valid = true;
        t.sm_watchdog_armed = true;
        self.0.tick(t);
    }
    fn pdi_watchdog_expired(&mut self) {
        self.0.pdi_watchdog_expired();
    }
    fn power_cycle(&mut self) {
        self.0.power_cycle();
    }
    fn nv(&self) -> Option<&dyn NvStorage> {
        self.0.nv()
    }
    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        self.0.nv_mut()
    }
}

impl WithBoard for Lying {
    fn sim_board(&self) -> &SimBoard {
        self.0.board()
    }
    fn sim_board_mut(&mut self) -> &mut SimBoard {
        self.0.board_mut()
    }
}

/// One thing a master or the world does.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Step {
    /// Up to OP as a master brings a drive up: PRE-OP, SAFE-OP, a cycle, OP.
    ToOp,
    /// Fault reset, shutdown, switch on, enable operation in a mode
    /// (5 cycles of 1 ms).
    Enable(i8),
    /// A cyclic frame with these outputs, the firmware run after `ms`.
    Cycle(Out, u64),
    /// `n` cycles of 1 ms, the target position (CSP) or velocity moving on
    /// by `step` per cycle.
    Ramp(u16, i32),
    /// No frames for `ms`.
    Idle(u64),
    /// An AL state request.
    Request(AlState),
    /// The SM watchdog on (100 ms) or off.
    Watchdog(bool),
    /// An SDO write of a profile object.
    Sdo(u16, i64),
    /// The power stage reports a fault, or none.
    Fault(Option<u16>),
    /// The firmware stalls: the ESC's PDI watchdog cut the power.
    Stall,
    /// A power cycle.
    PowerCycle,
}

/// Objects an SDO step writes, with the values it may write (the core
/// checks the type; the decelerations stay within what the checker's
/// stop bound assumes).
fn sdo() -> impl Strategy<Value = Step> {
    prop_oneof![
        any::<u16>().prop_map(|v| Step::Sdo(index::CONTROLWORD, i64::from(v))),
        any::<i8>().prop_map(|v| Step::Sdo(index::MODES_OF_OPERATION, i64::from(v))),
        (1i64..=3).prop_map(|v| Step::Sdo(index::ABORT_CONNECTION_OPTION, v)),
        (0i64..=8).prop_map(|v| Step::Sdo(index::QUICK_STOP_OPTION, v)),
        (0i64..=4).prop_map(|v| Step::Sdo(index::FAULT_REACTION_OPTION, v)),
        any::<u32>().prop_map(|v| Step::Sdo(index::FOLLOWING_ERROR_WINDOW, i64::from(v))),
        any::<u16>().prop_map(|v| Step::Sdo(index::FOLLOWING_ERROR_TIMEOUT, i64::from(v))),
        any::<u16>().prop_map(|v| Step::Sdo(index::MAX_TORQUE, i64::from(v))),
        (0i64..=2_000_000).prop_map(|v| Step::Sdo(index::MAX_MOTOR_SPEED, v)),
        any::<u32>().prop_map(|v| Step::Sdo(index::PROFILE_VELOCITY, i64::from(v))),
        (1i64..=u32::MAX as i64).prop_map(|v| Step::Sdo(index::PROFILE_ACCELERATION, v)),
        (1_000_000i64..=100_000_000).prop_map(|v| Step::Sdo(index::PROFILE_DECELERATION, v)),
        (1_000_000i64..=100_000_000).prop_map(|v| Step::Sdo(index::QUICK_STOP_DECELERATION, v)),
        any::<i32>().prop_map(|v| Step::Sdo(index::HOME_OFFSET, i64::from(v))),
        any::<i8>().prop_map(|v| Step::Sdo(index::HOMING_METHOD, i64::from(v))),
        any::<u16>().prop_map(|v| Step::Sdo(index::VELOCITY_THRESHOLD, i64::from(v))),
    ]
}

fn out() -> impl Strategy<Value = Out> {
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
        Just(0i8),
        Just(1),
        Just(3),
        Just(6),
        Just(8),
        Just(9),
        Just(10),
        any::<i8>()
    ];
    (cw, mode, any::<i32>(), any::<i32>(), any::<i16>(), 0u8..24).prop_map(
        |(controlword, mode, p, v, t, shift)| Out {
            controlword,
            mode,
            target_position: p >> shift,
            target_velocity: v >> (shift / 2 + 8),
            target_torque: t,
        },
    )
}

fn step() -> impl Strategy<Value = Step> {
    let mode = prop_oneof![Just(1i8), Just(3), Just(6), Just(8), Just(9), Just(10)];
    let state = prop_oneof![
        Just(AlState::Init),
        Just(AlState::PreOp),
        Just(AlState::SafeOp),
        Just(AlState::Op),
    ];
    prop_oneof![
        3 => Just(Step::ToOp),
        4 => mode.prop_map(Step::Enable),
        6 => (out(), 0u64..=20).prop_map(|(o, ms)| Step::Cycle(o, ms)),
        3 => (1u16..200, -2_000i32..2_000).prop_map(|(n, s)| Step::Ramp(n, s)),
        2 => (0u64..=150).prop_map(Step::Idle),
        2 => state.prop_map(Step::Request),
        1 => any::<bool>().prop_map(Step::Watchdog),
        2 => sdo(),
        1 => prop::option::weighted(0.3, 1u16..).prop_map(Step::Fault),
        1 => Just(Step::Stall),
        1 => Just(Step::PowerCycle),
    ]
}

/// The harness: a master, what it knows of the link, the checker.
struct Harness<A: WithBoard> {
    m: Master<A>,
    checker: Checker,
    /// Cyclic outputs written since OP was entered.
    written_in_op: bool,
    was_op: bool,
    /// The SM watchdog as written, and when it was switched off (the core
    /// reads 0x0420 at its full passes, at most `FULL_PASS_NS` later).
    watchdog_on: bool,
    watchdog_off_at: Option<u64>,
    last_out: Out,
}

impl<A: WithBoard> Harness<A> {
    fn new(app: A) -> Self {
        let mut m = Master::with(app);
        m.configure();
        Harness {
            m,
            checker: Checker::new(1_000_000),
            written_in_op: false,
            was_op: false,
            watchdog_on: true,
            watchdog_off_at: None,
            last_out: Out::default(),
        }
    }

    fn op(&self) -> bool {
        self.m.status().state == AlState::Op
    }

    fn cycle(&mut self, out: Out, ns: u64) {
        self.last_out = out;
        self.m.cycle_ns(out, ns);
        if self.op() {
            self.written_in_op = true;
        }
    }

    /// Does `s`; the checks of the cycles inside it (enable, ramps).
    fn apply(&mut self, s: &Step) -> Result<(), Violation> {
        match *s {
            Step::ToOp => {
                for state in [AlState::PreOp, AlState::SafeOp] {
                    self.apply(&Step::Request(state))?;
                    self.after_step()?;
                }
                self.cycle(self.last_out, MS);
                self.after_step()?;
                self.apply(&Step::Request(AlState::Op))?;
                self.after_step()?;
                self.cycle(self.last_out, MS);
            }
            Step::Enable(mode) => {
                let mut out = Out {
                    mode,
                    target_position: self
                        .m
                        .slave
                        .slave()
                        .od()
                        .get(index::POSITION_ACTUAL, 0)
                        .unwrap_or(0) as i32,
                    ..Out::default()
                };
                for cw in [
                    0,
                    control::FAULT_RESET,
                    control::SHUTDOWN,
                    control::SWITCH_ON,
                    control::ENABLE_OPERATION,
                ] {
                    out.controlword = cw;
                    self.cycle(out, MS);
                    self.after_step()?;
                }
            }
            Step::Cycle(out, ms) => self.cycle(out, ms * MS),
            Step::Ramp(n, by) => {
                let mut out = self.last_out;
                for _ in 0..n {
                    out.target_position = out.target_position.wrapping_add(by);
                    out.target_velocity = out.target_velocity.saturating_add(by * 10);
                    self.cycle(out, MS);
                    self.after_step()?;
                }
            }
            Step::Idle(ms) => self.m.poll_ns(ms * MS),
            Step::Request(state) => {
                if self.m.status().state == AlState::Init && state != AlState::Init {
                    self.m.configure();
                }
                self.m.request(state);
            }
            Step::Watchdog(on) => {
                let t: u16 = if on { 1000 } else { 0 };
                self.m.write(reg::WATCHDOG_TIME_PD, &t.to_le_bytes());
                if self.watchdog_on && !on {
                    self.watchdog_off_at = Some(self.m.now_ns);
                }
                self.watchdog_on = on;
                self.m.poll_ns(MS);
            }
            Step::Sdo(index, value) => {
                let _ = self.m.sdo(index, 0, value);
                self.m.poll_ns(MS);
            }
            Step::Fault(f) => {
                self.m
                    .slave
                    .slave_mut()
                    .app_mut()
                    .sim_board_mut()
                    .fault_code = f;
                self.m.poll_ns(MS);
            }
            Step::Stall => {
                self.m.slave.slave_mut().app_mut().pdi_watchdog_expired();
            }
            Step::PowerCycle => {
                self.m.slave.power_cycle();
                self.watchdog_on = true;
                self.watchdog_off_at = None;
            }
        }
        Ok(())
    }

    /// What is seen now, after a step.
    fn observe(&mut self) -> Observation {
        let op = self.op();
        if op && !self.was_op {
            // Entered OP in this step without cyclic outputs after it.
            self.written_in_op = false;
        }
        if !op {
            self.written_in_op = false;
        }
        self.was_op = op;
        let now = self.m.now_ns;
        // Still armed for the core until its next full pass.
        let armed = self.watchdog_on
            || self
                .watchdog_off_at
                .is_some_and(|t| now.saturating_sub(t) <= FULL_PASS_NS + MS);
        let od = self.m.slave.slave().od();
        let get = |i| od.get(i, 0).unwrap_or(0);
        Observation {
            now_ns: now,
            op,
            outputs_valid: op && self.written_in_op,
            watchdog_armed: armed,
            statusword: get(index::STATUSWORD) as u16,
            error_code: get(index::ERROR_CODE) as u16,
            velocity: get(index::VELOCITY_ACTUAL),
            power_stage: self.m.slave.slave().app().sim_board().stage,
        }
    }

    fn after_step(&mut self) -> Result<(), Violation> {
        let o = self.observe();
        self.checker.check(&o)
    }

    /// Runs `steps`; the first violation with its step number.
    fn run(&mut self, steps: &[Step]) -> Result<(), (usize, Step, Violation)> {
        for (k, s) in steps.iter().enumerate() {
            self.apply(s)
                .and_then(|()| self.after_step())
                .map_err(|v| (k, s.clone(), v))?;
        }
        Ok(())
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// S1-S3 and S5 hold after every step of any sequence.
    #[test]
    fn random_master_sequences_never_break_the_safety_rules(
        steps in prop::collection::vec(step(), 1..60)
    ) {
        let mut h = Harness::new(Servo402::default());
        prop_assert_eq!(h.run(&steps), Ok(()));
    }
}

#[test]
fn a_sequence_through_every_reaction_keeps_the_rules() {
    let mut h = Harness::new(Servo402::default());
    let run = [
        Step::Request(AlState::PreOp),
        Step::Request(AlState::SafeOp),
        Step::Cycle(Out::default(), 1),
        Step::Request(AlState::Op),
        Step::Cycle(Out::default(), 1),
        Step::Enable(8),
        Step::Ramp(100, 100),
        Step::Idle(150), // the SM watchdog ends OP: fault reaction
        Step::Request(AlState::Op),
        Step::Cycle(
            Out {
                controlword: control::FAULT_RESET,
                ..Out::default()
            },
            1,
        ),
        Step::Enable(9),
        Step::Ramp(50, 500),
        Step::Cycle(
            Out {
                controlword: control::QUICK_STOP,
                mode: 9,
                ..Out::default()
            },
            1,
        ),
        Step::Ramp(100, 0),
        Step::Enable(9),
        Step::Ramp(50, 500),
        Step::Watchdog(false),
        Step::Ramp(150, 500),
        Step::Watchdog(true),
        Step::Enable(10),
        Step::Fault(Some(0x2310)),
        Step::Ramp(100, 0),
        Step::Fault(None),
        Step::Enable(1),
        Step::Stall,
        Step::PowerCycle,
        Step::Request(AlState::PreOp),
    ];
    assert_eq!(h.run(&run), Ok(()));
}

#[test]
fn the_checker_catches_a_drive_that_ignores_the_lost_connection() {
    let mut h = Harness::new(Lying(Servo402::default(), 0));
    let run = [
        Step::Request(AlState::PreOp),
        Step::Request(AlState::SafeOp),
        Step::Cycle(Out::default(), 1),
        Step::Request(AlState::Op),
        Step::Cycle(Out::default(), 1),
        Step::Enable(8),
        Step::Request(AlState::SafeOp),
    ];
    let (k, _, v) = h.run(&run).expect_err("the planted violation is found");
    assert_eq!(k, 6, "at the request that left OP");
    assert_eq!(
        v,
        Violation::OperationWithoutMaster {
            op: false,
            outputs_valid: false,
            watchdog_armed: true
        }
    );
    // The same drive is caught by the random sequences too: the first
    // sequence that leaves OP in Operation enabled.
    let mut h = Harness::new(Lying(Servo402::default(), 0));
    let caught = h.run(&[
        Step::Request(AlState::PreOp),
        Step::Request(AlState::SafeOp),
        Step::Cycle(Out::default(), 1),
        Step::Request(AlState::Op),
        Step::Cycle(Out::default(), 1),
        Step::Enable(9),
        Step::Idle(150),
    ]);
    assert!(
        matches!(
            caught,
            Err((_, _, Violation::OperationWithoutMaster { .. }))
        ),
        "{caught:?}"
    );
}
