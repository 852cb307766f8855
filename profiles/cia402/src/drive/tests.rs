use super::*;
use crate::state::status;

const MS: u64 = 1_000_000;
const CONNECTED: Link = Link {
    outputs_valid: true,
    watchdog_armed: true,
    dc_cycle_ns: None,
};
const LOST: Link = Link {
    outputs_valid: false,
    watchdog_armed: true,
    dc_cycle_ns: None,
};

/// A drive, its parameters, its set points and the time.
struct Bench {
    drive: Drive,
    p: Parameters,
    sp: Setpoints,
    now: u64,
    link: Link,
    fault: Option<u16>,
    emergencies: Vec<u16>,
    last: Report,
}

impl Bench {
    fn new() -> Self {
        Bench {
            drive: Drive::default(),
            p: Parameters::DEFAULT,
            sp: Setpoints::default(),
            now: 0,
            link: CONNECTED,
            fault: None,
            emergencies: Vec::new(),
            last: Report::default(),
        }
    }

    /// `n` steps of `dt` ns.
    fn run(&mut self, n: usize, dt: u64) -> Report {
        for _ in 0..n {
            self.now += dt;
            self.last = self
                .drive
                .step(&self.sp, self.link, self.fault, &self.p, self.now);
            if let Some(e) = self.last.emergency {
                self.emergencies.push(e);
            }
        }
        self.last
    }

    fn cw(&mut self, cw: u16) -> Report {
        self.sp.controlword = cw;
        self.run(1, MS)
    }

    fn enable(&mut self, mode: Mode) {
        self.sp.mode = mode.code();
        self.sp.target_position = self.drive.axis().motion().position() as i32;
        self.cw(0);
        self.cw(control::SHUTDOWN);
        self.cw(control::SWITCH_ON);
        self.cw(control::ENABLE_OPERATION);
        assert_eq!(self.drive.state(), PowerState::OperationEnabled);
    }

    fn state(&self) -> PowerState {
        self.drive.state()
    }

    fn sw(&self) -> u16 {
        self.last.inputs.statusword
    }
}

#[test]
fn the_enable_sequence_reaches_operation_enabled_and_the_statusword_shows_each_state() {
    let mut b = Bench::new();
    assert_eq!(b.state(), PowerState::NotReadyToSwitchOn);
    assert_eq!(
        b.cw(0).inputs.statusword,
        0x0240,
        "Switch on disabled, remote"
    );
    assert_eq!(b.cw(control::SHUTDOWN).inputs.statusword, 0x0231);
    assert_eq!(b.cw(control::SWITCH_ON).inputs.statusword, 0x0233);
    let r = b.cw(control::ENABLE_OPERATION);
    // Operation enabled, remote, CSP "target position used".
    assert_eq!(r.inputs.statusword, 0x1237);
    assert!(r.power_stage.enabled);
    assert_eq!(r.inputs.mode_display, 8);
}

#[test]
fn without_valid_outputs_or_without_an_armed_watchdog_the_controlword_is_ignored() {
    for link in [
        LOST,
        Link {
            outputs_valid: true,
            watchdog_armed: false,
            dc_cycle_ns: None,
        },
    ] {
        let mut b = Bench::new();
        b.link = link;
        for cw in [
            control::SHUTDOWN,
            control::SWITCH_ON,
            control::ENABLE_OPERATION,
        ] {
            let r = b.cw(cw);
            assert_eq!(b.state(), PowerState::SwitchOnDisabled);
            assert!(!r.power_stage.enabled);
            assert_eq!(r.inputs.statusword & status::REMOTE, 0, "not remote");
        }
    }
}

#[test]
fn in_csp_the_position_follows_a_ramp_with_a_lag_of_velocity_times_the_loop_time_constant() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicPosition);
    let mut worst = 0i64;
    // 100 inc per 1 ms cycle: 100 000 inc/s.
    for k in 1..=500 {
        b.sp.target_position = k * 100;
        let r = b.run(1, MS);
        worst = worst.max(i64::from(r.inputs.following_error).abs());
        assert_eq!(b.state(), PowerState::OperationEnabled);
    }
    let r = b.last;
    assert_eq!(r.inputs.position_demand, 50_000);
    // v × τ = 100 000 inc/s × 1 ms.
    assert!(
        (99..=101).contains(&r.inputs.following_error),
        "{:?}",
        r.inputs
    );
    assert!(worst <= 101, "worst following error {worst}");
    assert_eq!(r.inputs.position + r.inputs.following_error, 50_000);
    assert!((99_000..=101_000).contains(&r.inputs.velocity));
}

#[test]
fn in_dc_mode_csp_set_points_are_interpolated_over_the_cycle() {
    let mut b = Bench::new();
    b.link.dc_cycle_ns = Some(MS as u32);
    b.enable(Mode::CyclicPosition);
    b.sp.target_position = 1000;
    // Ticks every 100 us between two SYNC0: the demand moves on linearly.
    let mut demands = Vec::new();
    for _ in 0..10 {
        demands.push(b.run(1, MS / 10).inputs.position_demand);
    }
    // From the SYNC0 that delivered it to the next one.
    assert_eq!(demands, [0, 100, 200, 300, 400, 500, 600, 700, 800, 900]);
    assert_eq!(b.run(1, MS / 10).inputs.position_demand, 1000);
    // Free run: the set point is taken at once.
    let mut b = Bench::new();
    b.enable(Mode::CyclicPosition);
    b.sp.target_position = 1000;
    assert_eq!(b.run(1, MS / 10).inputs.position_demand, 1000);
}

#[test]
fn in_dc_mode_a_set_point_every_cycle_is_reached_at_the_next_sync0() {
    let mut b = Bench::new();
    b.link.dc_cycle_ns = Some(MS as u32);
    b.enable(Mode::CyclicPosition);
    // One tick per cycle, at the SYNC0 that delivers the next set point:
    // the demand is the previous set point.
    for k in 1..=50 {
        b.sp.target_position = k * 100;
        let r = b.run(1, MS);
        assert_eq!(r.inputs.position_demand, (k - 1) * 100, "cycle {k}");
    }
    assert!((99..=101).contains(&b.last.inputs.following_error));
}

#[test]
fn a_following_error_beyond_the_window_for_the_timeout_faults_with_0x8611_once() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicPosition);
    // 1 000 000 inc away: the axis runs at its 1e6 inc/s limit.
    b.sp.target_position = 1_000_000;
    let r = b.run(5, MS);
    assert_eq!(
        b.state(),
        PowerState::OperationEnabled,
        "within the 10 ms time out"
    );
    assert_ne!(
        r.inputs.statusword & status::WARNING,
        0,
        "outside the window: warning"
    );
    assert_ne!(
        r.inputs.statusword & status::INTERNAL_LIMIT,
        0,
        "at the velocity limit"
    );
    b.run(6, MS);
    assert_eq!(b.emergencies, [FOLLOWING_ERROR]);
    assert_eq!(b.last.inputs.error_code, 0x8611);
    assert_eq!(b.last.error_register, register::PROFILE);
    assert_ne!(b.sw() & status::MODE_SPECIFIC_13, 0, "following error bit");
    // The fault reaction brakes on 0x6085, then Fault with the power stage off.
    assert_eq!(b.state(), PowerState::FaultReactionActive);
    b.run(1000, MS);
    assert_eq!(b.state(), PowerState::Fault);
    assert_eq!(b.sw() & 0x4F, 0x08);
    assert!(!b.last.power_stage.enabled);
    assert_eq!(b.emergencies.len(), 1, "one Emergency per fault");
}

#[test]
fn a_fault_reset_needs_the_rising_edge_of_bit_7_and_clears_the_error_code() {
    let mut b = Bench::new();
    b.sp.controlword = control::FAULT_RESET;
    b.run(1, MS);
    b.fault = Some(0x2310);
    b.run(1, MS);
    assert_eq!(b.state(), PowerState::Fault, "unpowered: no reaction ramp");
    b.fault = None;
    // Bit 7 held from before the fault: no edge, no reset.
    b.run(3, MS);
    assert_eq!(b.state(), PowerState::Fault);
    b.cw(0);
    let r = b.cw(control::FAULT_RESET);
    assert_eq!(b.state(), PowerState::SwitchOnDisabled);
    assert_eq!(r.inputs.error_code, 0);
    assert_eq!(r.error_register, 0);
}

#[test]
fn a_fault_reset_is_refused_while_the_hardware_still_reports_the_fault() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicVelocity);
    b.fault = Some(0x4310);
    b.run(200, MS);
    assert_eq!(b.state(), PowerState::Fault);
    assert_eq!(b.last.error_register, register::TEMPERATURE);
    b.cw(0);
    b.cw(control::FAULT_RESET);
    assert_eq!(b.state(), PowerState::Fault);
    b.fault = None;
    b.cw(0);
    b.cw(control::FAULT_RESET);
    assert_eq!(b.state(), PowerState::SwitchOnDisabled);
    assert_eq!(b.emergencies, [0x4310]);
}

/// Runs at 100 000 inc/s in CSV, then quick stop; the steps until
/// Switch on disabled.
fn quick_stop_from_speed(b: &mut Bench) -> usize {
    b.enable(Mode::CyclicVelocity);
    b.sp.target_velocity = 100_000;
    b.run(100, MS);
    assert!(b.last.inputs.velocity > 99_000);
    b.sp.controlword = control::QUICK_STOP;
    let mut last_v = i64::from(b.last.inputs.velocity);
    let mut steps = 0;
    while b.state() != PowerState::SwitchOnDisabled && steps < 10_000 {
        let r = b.run(1, MS / 10);
        steps += 1;
        let v = i64::from(r.inputs.velocity);
        assert!(v <= last_v + 10, "only braking: {v} after {last_v}");
        last_v = v;
        if b.state() == PowerState::QuickStopActive {
            assert_eq!(r.inputs.statusword & 0x6F, 0x07, "bit 5 quick stop = 0");
            assert!(r.power_stage.enabled);
        }
    }
    steps
}

#[test]
fn quick_stop_ramps_on_the_quick_stop_deceleration_and_then_disables() {
    let mut b = Bench::new();
    let steps = quick_stop_from_speed(&mut b);
    // 100 000 inc/s at 5e6 inc/s²: 20 ms, then the loops settle.
    assert!((200..=300).contains(&steps), "{steps} x 100 us");
    assert!(!b.last.power_stage.enabled);
    // Option 1: the profile deceleration (1e6 inc/s²): 100 ms.
    let mut b = Bench::new();
    b.p.quick_stop_option = 1;
    let steps = quick_stop_from_speed(&mut b);
    assert!((1000..=1100).contains(&steps), "{steps} x 100 us");
}

#[test]
fn quick_stop_option_0_coasts_to_switch_on_disabled_at_once() {
    let mut b = Bench::new();
    b.p.quick_stop_option = 0;
    b.enable(Mode::CyclicVelocity);
    b.sp.target_velocity = 10_000;
    b.run(50, MS);
    let r = b.cw(control::QUICK_STOP);
    assert_eq!(b.state(), PowerState::SwitchOnDisabled);
    assert!(!r.power_stage.enabled);
    assert_eq!(r.power_stage.torque, 0);
}

#[test]
fn quick_stop_options_5_to_8_hold_in_quick_stop_active_until_enable_operation() {
    let mut b = Bench::new();
    b.p.quick_stop_option = 6;
    b.enable(Mode::CyclicVelocity);
    b.sp.target_velocity = 50_000;
    b.run(50, MS);
    b.sp.controlword = control::QUICK_STOP;
    b.run(200, MS);
    assert_eq!(b.state(), PowerState::QuickStopActive);
    assert_eq!(b.last.inputs.velocity, 0);
    assert!(b.last.power_stage.enabled, "holding the position");
    b.sp.target_velocity = 0;
    b.cw(control::ENABLE_OPERATION);
    assert_eq!(b.state(), PowerState::OperationEnabled, "transition 16");
    b.cw(control::QUICK_STOP);
    b.cw(control::DISABLE_VOLTAGE);
    assert_eq!(b.state(), PowerState::SwitchOnDisabled, "transition 12");
}

#[test]
fn a_lost_connection_in_operation_enabled_brakes_then_faults_with_0x8100() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicVelocity);
    b.sp.target_velocity = 100_000;
    b.run(100, MS);
    b.link = LOST;
    let r = b.run(1, MS);
    assert_eq!(b.state(), PowerState::FaultReactionActive);
    assert!(r.power_stage.enabled, "braking");
    assert_eq!(r.inputs.statusword & status::REMOTE, 0);
    b.run(100, MS);
    assert_eq!(b.state(), PowerState::Fault);
    assert_eq!(b.emergencies, [CONNECTION_LOST]);
    assert_eq!(b.last.error_register, register::COMMUNICATION);
    // Back: only a fault reset from the master leaves Fault.
    b.link = CONNECTED;
    b.cw(control::ENABLE_OPERATION);
    assert_eq!(b.state(), PowerState::Fault);
    b.cw(control::FAULT_RESET);
    assert_eq!(b.state(), PowerState::SwitchOnDisabled);
}

#[test]
fn abort_connection_options_2_and_3_disable_at_once_or_after_a_quick_stop() {
    let mut b = Bench::new();
    b.p.abort_connection_option = 2;
    b.enable(Mode::CyclicVelocity);
    b.link = LOST;
    let r = b.run(1, MS);
    assert_eq!(b.state(), PowerState::SwitchOnDisabled);
    assert!(!r.power_stage.enabled);
    let mut b = Bench::new();
    b.p.abort_connection_option = 3;
    b.p.quick_stop_option = 6; // would stay in Quick stop active ...
    b.enable(Mode::CyclicVelocity);
    b.sp.target_velocity = 100_000;
    b.run(100, MS);
    b.link = LOST;
    b.run(1, MS);
    assert_eq!(b.state(), PowerState::QuickStopActive);
    b.run(100, MS);
    // ... but not without a master.
    assert_eq!(b.state(), PowerState::SwitchOnDisabled);
    assert!(b.emergencies.is_empty());
}

#[test]
fn without_a_master_switched_on_and_ready_to_switch_on_fall_to_switch_on_disabled() {
    for cw in [control::SHUTDOWN, control::SWITCH_ON] {
        let mut b = Bench::new();
        b.cw(0);
        b.cw(control::SHUTDOWN);
        b.cw(cw);
        b.link = LOST;
        b.run(1, MS);
        assert_eq!(b.state(), PowerState::SwitchOnDisabled);
    }
}

#[test]
fn disable_operation_switches_the_power_stage_off_at_once() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicVelocity);
    b.sp.target_velocity = 10_000;
    b.run(20, MS);
    let r = b.cw(control::DISABLE_OPERATION);
    assert_eq!(b.state(), PowerState::SwitchedOn);
    assert!(!r.power_stage.enabled);
    assert_eq!(r.inputs.torque, 0);
}

#[test]
fn csv_clamps_the_target_velocity_at_the_maximum_and_says_so() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicVelocity);
    b.sp.target_velocity = 2_000_000;
    let r = b.run(50, MS);
    assert_eq!(r.inputs.velocity, 1_000_000);
    assert_ne!(r.inputs.statusword & status::INTERNAL_LIMIT, 0);
    assert_ne!(r.inputs.statusword & status::MODE_SPECIFIC_12, 0);
    assert_eq!(r.inputs.following_error, 0, "no position loop in CSV");
}

#[test]
fn cst_accelerates_with_the_target_torque_cut_at_the_maximum() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicTorque);
    b.sp.target_torque = 100;
    let r = b.run(10, MS);
    // 100 ‰ of 1e7 inc/s² for 10 ms.
    assert_eq!(r.inputs.velocity, 10_000);
    assert_eq!(r.inputs.torque, 100);
    assert_eq!(r.power_stage.torque, 100);
    b.p.max_torque = 50;
    let r = b.run(1, MS);
    assert_eq!(r.inputs.torque, 50);
    assert_ne!(r.inputs.statusword & status::INTERNAL_LIMIT, 0);
}

#[test]
fn pv_ramps_to_the_target_velocity_and_reports_target_reached_and_speed_zero() {
    let mut b = Bench::new();
    b.enable(Mode::ProfileVelocity);
    let r = b.run(1, MS);
    assert_ne!(r.inputs.statusword & status::MODE_SPECIFIC_12, 0, "speed 0");
    b.sp.target_velocity = 50_000;
    let r = b.run(10, MS);
    // 1e6 inc/s² for 10 ms: 10 000 inc/s of demand so far.
    assert!(
        (9_000..=10_000).contains(&r.inputs.velocity),
        "{}",
        r.inputs.velocity
    );
    assert_eq!(r.inputs.statusword & status::TARGET_REACHED, 0);
    let r = b.run(100, MS);
    assert_ne!(r.inputs.statusword & status::TARGET_REACHED, 0);
    assert_eq!(r.inputs.statusword & status::MODE_SPECIFIC_12, 0);
    // Halt: down to 0 on the profile deceleration; target reached at rest.
    b.sp.controlword = control::ENABLE_OPERATION | control::HALT;
    let r = b.run(100, MS);
    assert_eq!(r.inputs.velocity, 0);
    assert_ne!(r.inputs.statusword & status::TARGET_REACHED, 0);
}

#[test]
fn pp_takes_a_set_point_on_bit_4_acknowledges_it_and_reaches_the_target() {
    let mut b = Bench::new();
    b.enable(Mode::ProfilePosition);
    b.sp.target_position = 10_000;
    let r = b.cw(control::ENABLE_OPERATION | control::NEW_SET_POINT);
    assert_ne!(
        r.inputs.statusword & status::MODE_SPECIFIC_12,
        0,
        "acknowledged"
    );
    assert_eq!(r.inputs.statusword & status::TARGET_REACHED, 0);
    let r = b.cw(control::ENABLE_OPERATION);
    assert_eq!(
        r.inputs.statusword & status::MODE_SPECIFIC_12,
        0,
        "ready for the next"
    );
    // 10 000 inc at 100 000 inc/s with 1e6 inc/s² ramps: 0.2 s.
    let mut peak = 0;
    for _ in 0..300 {
        let r = b.run(1, MS);
        peak = peak.max(r.inputs.velocity);
    }
    let r = b.last;
    assert!((99_000..=100_000).contains(&peak), "{peak}");
    assert_eq!(r.inputs.position_demand, 10_000);
    assert!((r.inputs.position - 10_000).abs() <= 10);
    assert_ne!(r.inputs.statusword & status::TARGET_REACHED, 0);
    // Relative: 5 000 more.
    b.sp.target_position = 5_000;
    b.cw(control::ENABLE_OPERATION | control::NEW_SET_POINT | control::RELATIVE);
    b.cw(control::ENABLE_OPERATION);
    let r = b.run(300, MS);
    assert_eq!(r.inputs.position_demand, 15_000);
}

#[test]
fn pp_with_halt_stops_and_continues_to_the_target_when_released() {
    let mut b = Bench::new();
    b.enable(Mode::ProfilePosition);
    b.sp.target_position = 100_000;
    b.cw(control::ENABLE_OPERATION | control::NEW_SET_POINT);
    b.run(100, MS);
    b.sp.controlword = control::ENABLE_OPERATION | control::HALT;
    let r = b.run(200, MS);
    assert_eq!(r.inputs.velocity, 0);
    assert!(r.inputs.position < 100_000);
    assert_ne!(
        r.inputs.statusword & status::TARGET_REACHED,
        0,
        "halted at rest"
    );
    b.sp.controlword = control::ENABLE_OPERATION;
    let r = b.run(2000, MS);
    assert_eq!(r.inputs.position_demand, 100_000);
}

#[test]
fn homing_on_the_current_position_sets_the_home_offset() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicVelocity);
    b.sp.target_velocity = 10_000;
    b.run(100, MS);
    b.sp.target_velocity = 0;
    b.run(100, MS);
    assert!(b.last.inputs.position > 500);
    b.p.home_offset = -42;
    b.sp.mode = Mode::Homing.code();
    b.cw(control::ENABLE_OPERATION);
    let r = b.cw(control::ENABLE_OPERATION | control::NEW_SET_POINT);
    assert_eq!(r.inputs.position, -42);
    assert_eq!(r.inputs.mode_display, 6);
    let bits = status::TARGET_REACHED | status::MODE_SPECIFIC_12;
    assert_eq!(r.inputs.statusword & bits, bits, "homing attained");
    // An unsupported method: homing error.
    b.p.homing_method = 1;
    b.cw(control::ENABLE_OPERATION);
    let r = b.cw(control::ENABLE_OPERATION | control::NEW_SET_POINT);
    assert_ne!(r.inputs.statusword & status::MODE_SPECIFIC_13, 0);
    assert_eq!(r.inputs.statusword & status::MODE_SPECIFIC_12, 0);
}

#[test]
fn the_mode_display_follows_supported_modes_only() {
    let mut b = Bench::new();
    for (code, display) in [(9, 9), (0, 9), (2, 9), (-5, 9), (1, 1), (10, 10), (6, 6)] {
        b.sp.mode = code;
        assert_eq!(b.run(1, MS).inputs.mode_display, display, "0x6060 = {code}");
    }
}

#[test]
fn a_stalled_firmware_faults_without_a_ramp() {
    let mut b = Bench::new();
    b.enable(Mode::CyclicVelocity);
    assert_eq!(b.drive.power_cut(), Some(FIRMWARE_STALLED));
    assert_eq!(b.drive.power_cut(), None);
    let r = b.run(1, MS);
    assert_eq!(b.state(), PowerState::Fault);
    assert!(!r.power_stage.enabled);
    assert_eq!(r.inputs.error_code, 0x6010);
}

#[test]
fn position_wraps_modulo_2_32_and_csp_follows_across_the_wrap() {
    let mut b = Bench::new();
    b.drive
        .axis_mut()
        .set_position((i64::from(i32::MAX) - 500) * MILLI);
    b.enable(Mode::CyclicPosition);
    let mut t = i32::MAX - 500;
    for _ in 0..20 {
        t = t.wrapping_add(100);
        b.sp.target_position = t;
        b.run(1, MS);
    }
    let r = b.last;
    assert!(r.inputs.position < 0, "wrapped: {}", r.inputs.position);
    assert!(r.inputs.following_error.abs() <= 101, "{:?}", r.inputs);
    assert_eq!(b.state(), PowerState::OperationEnabled);
}

/// An axis that reports the extremes of every value (a broken encoder).
#[derive(Debug, Default)]
struct Wild(u64);

impl Axis for Wild {
    fn step(&mut self, _: Demand, _: Limits, _: u64) -> Motion {
        self.0 += 1;
        self.motion()
    }
    fn motion(&self) -> Motion {
        let big = self.0.is_multiple_of(2);
        Motion {
            position_m: if big { i64::MAX } else { i64::MIN },
            velocity: if big { i64::MIN } else { i64::MAX },
            torque: if big { i64::MAX } else { i64::MIN },
            limited: big,
        }
    }
    fn set_position(&mut self, _: i64) {}
}

#[test]
fn an_axis_reporting_extreme_values_cannot_make_the_drive_panic() {
    let mut drive = Drive::new(Wild::default());
    let p = Parameters::DEFAULT;
    let mut now = 0;
    for mode in [1i8, 3, 6, 8, 9, 10] {
        for cw in [
            0,
            control::SHUTDOWN,
            control::ENABLE_OPERATION,
            0x1F,
            0x11F,
            0x5F,
            control::QUICK_STOP,
            0x80,
        ] {
            now += MS;
            let sp = Setpoints {
                controlword: cw,
                mode,
                target_position: i32::MIN,
                target_velocity: i32::MAX,
                target_torque: i16::MIN,
            };
            let r = drive.step(&sp, CONNECTED, None, &p, now);
            let _ = PowerState::from_statusword(r.inputs.statusword).expect("a state");
        }
    }
}
