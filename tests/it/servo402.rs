//! The servo402, a CiA 402 servo drive on the core, driven by ethercrab
//! on the virtual bus: a line brought to OP DC-synchronous on SYNC0 (as
//! ethercrab's `dc` example does it), the power drive system state
//! machine walked to Operation enabled in CSP, the position following a
//! target ramp with a bounded following error; the quick stop ramp; the
//! following-error fault with its Emergency and error code, and the fault
//! reset; leaving OP in Operation enabled. Time is the simulated clock's.

use ecat_cia402::PowerState;
use ecat_cia402::objects::{RX_PDO_BYTES, TX_PDO_BYTES};
use ecat_cia402::state::control;
use ecat_slave::al::AlState;
use ecat_slave::wire::mailbox::MailboxType;
use ethercrab::subdevice_group::{CycleInfo, DcConfiguration, TxRxResponse};
use master_test::VirtualBus;
use master_test::link::{Chain, Clock, lock};
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use std::time::Duration;

const CYCLE: Duration = Duration::from_millis(1);

/// The cyclic outputs of 0x1600.
#[derive(Debug, Clone, Copy, Default)]
struct Out {
    controlword: u16,
    target_position: i32,
    target_velocity: i32,
    mode: i8,
}

impl Out {
    fn write(&self, b: &mut [u8]) {
        assert_eq!(b.len(), RX_PDO_BYTES);
        b[0..2].copy_from_slice(&self.controlword.to_le_bytes());
        b[2..6].copy_from_slice(&self.target_position.to_le_bytes());
        b[6..10].copy_from_slice(&self.target_velocity.to_le_bytes());
        b[10..12].copy_from_slice(&0i16.to_le_bytes());
        b[12] = self.mode as u8;
    }
}

/// The cyclic inputs of 0x1A00.
#[derive(Debug, Clone, Copy, Default)]
struct In {
    statusword: u16,
    position: i32,
    velocity: i32,
    mode_display: i8,
    following_error: i32,
    error_code: u16,
}

impl In {
    fn parse(b: &[u8]) -> Self {
        assert_eq!(b.len(), TX_PDO_BYTES);
        let i32_at = |i: usize| i32::from_le_bytes(b[i..i + 4].try_into().unwrap());
        In {
            statusword: u16::from_le_bytes([b[0], b[1]]),
            position: i32_at(2),
            velocity: i32_at(6),
            mode_display: b[12] as i8,
            following_error: i32_at(13),
            error_code: u16::from_le_bytes([b[17], b[18]]),
        }
    }

    fn state(&self) -> Option<PowerState> {
        PowerState::from_statusword(self.statusword)
    }
}

type OpGroup = ethercrab::SubDeviceGroup<
    { master_test::MAX_SUBDEVICES },
    { master_test::PDI_LEN },
    ethercrab::DefaultLock,
    ethercrab::subdevice_group::Op,
    ethercrab::subdevice_group::HasDc,
>;

/// One DC cycle: outputs, `tx_rx_dc`, the wait to the next cycle in the
/// slaves' time; the inputs.
async fn dc_cycle(bus: &VirtualBus, group: &OpGroup, out: Out) -> In {
    let md = &*bus.maindevice;
    let sd = group.subdevice(md, 0).expect("servo402");
    out.write(&mut sd.outputs_raw_mut());
    let TxRxResponse {
        extra: CycleInfo {
            next_cycle_wait, ..
        },
        ..
    } = group.tx_rx_dc(md).await.expect("tx_rx_dc");
    bus.clock.advance(next_cycle_wait);
    In::parse(&sd.inputs_raw())
}

/// Controlword `cw` until the statusword shows `state` (at most 20 cycles).
async fn dc_command(bus: &VirtualBus, group: &OpGroup, out: &mut Out, cw: u16, state: PowerState) {
    out.controlword = cw;
    for _ in 0..20 {
        if dc_cycle(bus, group, *out).await.state() == Some(state) {
            return;
        }
    }
    panic!("controlword {cw:#06x}: no {state:?}");
}

#[test]
fn ethercrab_enables_servo402_in_csp_on_sync0_and_the_position_follows_a_target_ramp() {
    use ethercrab::DcSync;
    smol::block_on(async {
        let entries = device_catalog::parse_line("servo402").expect("line");
        let chain = Chain::with_slaves(device_catalog::slaves(&entries));
        let bus = VirtualBus::with_dc(chain, Clock::frames(), 10_000).expect("bus");
        let md = &*bus.maindevice;
        let mut group = bus.init().await.expect("init with DC");
        for mut sd in group.iter_mut(md) {
            sd.set_dc_sync(DcSync::Sync0);
        }
        let group = group.into_pre_op_pdi(md).await.expect("PRE-OP with PDI");
        {
            let sd = group.subdevice(md, 0).expect("servo402");
            assert_eq!(sd.name(), "SERVO402");
            let modes: u32 = sd.sdo_read(0x6502, 0).await.expect("0x6502");
            assert_eq!(modes & 0x380, 0x380, "CSP, CSV, CST supported");
            sd.sdo_write(0x6060, 0, 8i8).await.expect("0x6060 = CSP");
        }
        for _ in 0..50 {
            group.tx_rx_sync_system_time(md).await.expect("sync");
        }
        let group = group
            .configure_dc_sync(
                md,
                DcConfiguration {
                    start_delay: Duration::from_millis(20),
                    sync0_period: CYCLE,
                    sync0_shift: CYCLE / 2,
                },
            )
            .await
            .expect("configure DC sync");
        let group = group.into_safe_op(md).await.expect("SAFE-OP in DC mode");
        let group = group.request_into_op(md).await.expect("OP requested");
        let mut out = Out {
            mode: 8,
            ..Out::default()
        };
        let mut op = false;
        for _ in 0..2_000 {
            let sd = group.subdevice(md, 0).expect("servo402");
            out.write(&mut sd.outputs_raw_mut());
            let response @ TxRxResponse {
                extra: CycleInfo {
                    next_cycle_wait, ..
                },
                ..
            } = group.tx_rx_dc(md).await.expect("tx_rx_dc");
            bus.clock.advance(next_cycle_wait);
            if response.all_op() {
                op = true;
                break;
            }
        }
        assert!(op, "OP in DC mode");
        {
            let chain = lock(&bus.chain);
            let od = chain.slaves()[0].od();
            assert_eq!(od.get(0x1C32, 1), Some(2), "DC SYNC0");
            assert_eq!(od.get(0x1C32, 2), Some(1_000_000));
        }
        // The state machine to Operation enabled, the target at the
        // actual position first.
        let start = dc_cycle(&bus, &group, out).await;
        assert_eq!(
            start.state(),
            Some(PowerState::SwitchOnDisabled),
            "{start:?}"
        );
        assert_eq!(start.mode_display, 8);
        out.target_position = start.position;
        dc_command(
            &bus,
            &group,
            &mut out,
            control::SHUTDOWN,
            PowerState::ReadyToSwitchOn,
        )
        .await;
        dc_command(
            &bus,
            &group,
            &mut out,
            control::SWITCH_ON,
            PowerState::SwitchedOn,
        )
        .await;
        dc_command(
            &bus,
            &group,
            &mut out,
            control::ENABLE_OPERATION,
            PowerState::OperationEnabled,
        )
        .await;
        // A ramp of 100 inc per 1 ms cycle: 100 000 inc/s.
        let speed = 100;
        let mut worst = 0;
        let mut last = In::default();
        for k in 1..=1000 {
            out.target_position = start.position + k * speed;
            last = dc_cycle(&bus, &group, out).await;
            assert_eq!(
                last.state(),
                Some(PowerState::OperationEnabled),
                "cycle {k}: {last:?}"
            );
            assert_ne!(last.statusword & 0x1000, 0, "CSP: target position used");
            worst = worst.max(last.following_error.abs());
        }
        let lag = out.target_position - last.position;
        eprintln!(
            "servo402 CSP on SYNC0: following error up to {worst} inc, the position {lag} inc \
             behind the last target, velocity {} inc/s",
            last.velocity
        );
        // Three cycles' travel behind, one each for: the position loop's
        // lag (v x tau, tau = 1 ms: the following error), the set point
        // reached at the SYNC0 after the one that delivered it (the drive
        // interpolates over the cycle), and the frame's inputs being the
        // previous pass's.
        assert!(
            worst <= speed + speed / 10,
            "following error up to {worst} inc"
        );
        assert!(
            lag > 0 && lag <= 3 * speed + speed / 10,
            "{lag} inc behind the target"
        );
        assert!(
            (last.velocity - speed * 1000).abs() <= speed * 10,
            "{last:?}"
        );
        assert_eq!(last.error_code, 0);
        let board = {
            let chain = lock(&bus.chain);
            chain
                .slave::<servo402_example::Servo402>(0)
                .expect("a servo402")
                .slave()
                .app()
                .board()
                .stage
        };
        assert!(board.enabled, "the power stage drives");
    });
}

type FreeGroup = ethercrab::SubDeviceGroup<
    { master_test::MAX_SUBDEVICES },
    { master_test::PDI_LEN },
    ethercrab::DefaultLock,
    ethercrab::subdevice_group::Op,
>;

/// One free-run cycle of 1 ms.
async fn cycle(bus: &VirtualBus, group: &FreeGroup, out: Out) -> In {
    let md = &*bus.maindevice;
    let sd = group.subdevice(md, 0).expect("servo402");
    out.write(&mut sd.outputs_raw_mut());
    group.tx_rx(md).await.expect("cycle");
    bus.clock.advance(CYCLE);
    In::parse(&sd.inputs_raw())
}

async fn command(bus: &VirtualBus, group: &FreeGroup, out: &mut Out, cw: u16, state: PowerState) {
    out.controlword = cw;
    for _ in 0..20 {
        if cycle(bus, group, *out).await.state() == Some(state) {
            return;
        }
    }
    panic!("controlword {cw:#06x}: no {state:?}");
}

/// A servo402 in OP (free run), enabled in `mode`, the target at the
/// actual position.
async fn enabled(bus: &VirtualBus, mode: i8) -> (FreeGroup, Out) {
    let md = &*bus.maindevice;
    let group = bus.init().await.expect("PRE-OP");
    let group = master_test::into_op_cyclic(group, md, CYCLE)
        .await
        .expect("OP");
    let mut out = Out {
        mode,
        ..Out::default()
    };
    out.target_position = cycle(bus, &group, out).await.position;
    for (cw, s) in [
        (control::SHUTDOWN, PowerState::ReadyToSwitchOn),
        (control::SWITCH_ON, PowerState::SwitchedOn),
        (control::ENABLE_OPERATION, PowerState::OperationEnabled),
    ] {
        command(bus, &group, &mut out, cw, s).await;
    }
    (group, out)
}

#[test]
fn a_quick_stop_brakes_on_the_quick_stop_ramp_and_then_disables() {
    smol::block_on(async {
        let bus = VirtualBus::line("servo402", Clock::frames()).expect("bus");
        let (group, mut out) = enabled(&bus, 9).await;
        out.target_velocity = 100_000;
        let mut i = In::default();
        for _ in 0..100 {
            i = cycle(&bus, &group, out).await;
        }
        assert!(i.velocity > 99_000, "{i:?}");
        out.controlword = control::QUICK_STOP;
        let mut last_v = i.velocity;
        let mut braking = 0;
        for _ in 0..100 {
            i = cycle(&bus, &group, out).await;
            assert!(
                i.velocity <= last_v + 10,
                "braking only: {} after {last_v}",
                i.velocity
            );
            last_v = i.velocity;
            match i.state() {
                // The inputs of a frame are the previous pass's.
                Some(PowerState::OperationEnabled) if braking == 0 => {}
                Some(PowerState::QuickStopActive) => braking += 1,
                Some(PowerState::SwitchOnDisabled) => break,
                s => panic!("{s:?} during the quick stop"),
            }
        }
        // 100 000 inc/s at 0x6085 = 5e6 inc/s²: 20 ms, then the loops settle.
        assert_eq!(i.state(), Some(PowerState::SwitchOnDisabled), "{i:?}");
        assert!(
            (15..=40).contains(&braking),
            "{braking} cycles in Quick stop active"
        );
        assert_eq!(i.error_code, 0, "a quick stop is no fault");
    });
}

#[test]
fn a_following_error_faults_with_0x8611_and_its_emergency_and_a_fault_reset_recovers() {
    smol::block_on(async {
        let bus = VirtualBus::line("servo402", Clock::frames()).expect("bus");
        let md = &*bus.maindevice;
        let (group, mut out) = enabled(&bus, 8).await;
        // A target 1 000 000 inc away: the axis runs at its 1e6 inc/s
        // limit, beyond the 5 000 inc window for longer than 10 ms.
        out.target_position += 1_000_000;
        let mut i = In::default();
        for _ in 0..30 {
            i = cycle(&bus, &group, out).await;
            if i.error_code != 0 {
                break;
            }
        }
        assert_eq!(i.error_code, 0x8611, "{i:?}");
        assert_ne!(i.statusword & 0x2000, 0, "CSP following error bit");
        for _ in 0..300 {
            i = cycle(&bus, &group, out).await;
            if i.state() == Some(PowerState::Fault) {
                break;
            }
        }
        assert_eq!(i.state(), Some(PowerState::Fault), "{i:?}");
        // The Emergency: error code 0x8611, error register with the
        // generic and profile bits.
        let station = group
            .subdevice(md, 0)
            .expect("servo402")
            .configured_address();
        let layout = servo402_example::DEVICE.layout();
        let mut client = MailboxClient::new(md, station, MailboxGeometry::of(&layout));
        let msg = client.receive().await.expect("the Emergency");
        assert_eq!(msg.kind, MailboxType::CoE);
        let p = &msg.payload;
        assert_eq!(u16::from_le_bytes([p[0], p[1]]) >> 12, 1, "CoE Emergency");
        assert_eq!(u16::from_le_bytes([p[2], p[3]]), 0x8611);
        assert_eq!(p[4], 0x21, "error register: generic + device profile");
        // The fault reset: the rising edge of bit 7, then enable again.
        out.target_position = i.position;
        command(&bus, &group, &mut out, 0, PowerState::Fault).await;
        command(
            &bus,
            &group,
            &mut out,
            control::FAULT_RESET,
            PowerState::SwitchOnDisabled,
        )
        .await;
        let i = cycle(&bus, &group, out).await;
        assert_eq!(i.error_code, 0);
        command(
            &bus,
            &group,
            &mut out,
            control::SHUTDOWN,
            PowerState::ReadyToSwitchOn,
        )
        .await;
        command(
            &bus,
            &group,
            &mut out,
            control::ENABLE_OPERATION,
            PowerState::OperationEnabled,
        )
        .await;
    });
}

#[test]
fn leaving_op_in_operation_enabled_brakes_the_axis_and_ends_in_fault() {
    smol::block_on(async {
        let bus = VirtualBus::line("servo402", Clock::frames()).expect("bus");
        let md = &*bus.maindevice;
        let (group, mut out) = enabled(&bus, 9).await;
        out.target_velocity = 50_000;
        for _ in 0..100 {
            cycle(&bus, &group, out).await;
        }
        // The master leaves OP without disabling the drive.
        let group = group.into_safe_op(md).await.expect("SAFE-OP");
        for _ in 0..100 {
            group.tx_rx(md).await.expect("cycle");
            bus.clock.advance(CYCLE);
        }
        let chain = lock(&bus.chain);
        let s = &chain.slaves()[0];
        assert_eq!(s.al_status().state, AlState::SafeOp);
        let od = s.od();
        assert_eq!(
            od.get(0x6041, 0)
                .and_then(|w| PowerState::from_statusword(w as u16)),
            Some(PowerState::Fault)
        );
        assert_eq!(od.get(0x603F, 0), Some(0x8100));
        assert_eq!(od.get(0x606C, 0), Some(0), "braked to rest");
        let servo = chain
            .slave::<servo402_example::Servo402>(0)
            .expect("a servo402");
        assert!(!servo.slave().app().board().stage.enabled);
    });
}

/// A twin of a CiA 402 drive's ESI (here servo402's own generated one)
/// runs the profile on its own: `EsiApp` finds the axis (ProfileNo 402,
/// 0x6040/0x6041), checks downloads with it and ticks it after the input
/// rule, so ethercrab enables it in CSP and the position follows.
#[test]
fn a_twin_of_a_cia402_esi_with_the_profile_hook_is_enabled_in_csp_and_follows_a_ramp() {
    let xml = ecat_esi::generate(&servo402_example::DEVICE).expect("ESI");
    let file = ecat_twin::EsiFile::parse(std::str::from_utf8(&xml).expect("utf-8")).expect("ESI");
    let esi_dev = file.device(None, None).expect("one device");
    let (desc, layout) = ecat_twin::coe_twin::describe(esi_dev).expect("description");
    assert!(
        ecat_cia402::Cia402Axis::is_cia402(desc.dictionary),
        "ProfileNo 402, 0x6040/0x6041"
    );
    // The twin runs the profile on its own: one axis, as the ESI says.
    let app = ecat_twin::coe_twin::EsiApp::new(desc, ecat_twin::InputRule::Hold);
    assert_eq!(app.axes(), 1, "a CiA 402 axis");
    let slave = ecat_sim::SoftSlave::with_layout(app, layout);
    let chain = Chain::with_slaves(vec![Box::new(slave)]);
    let bus = VirtualBus::with_chain(chain, Clock::frames(), None).expect("bus");
    smol::block_on(async {
        let (group, mut out) = enabled(&bus, 8).await;
        let start = out.target_position;
        let mut last = In::default();
        for k in 1..=200 {
            out.target_position = start + 50 * k;
            last = cycle(&bus, &group, out).await;
        }
        assert_eq!(last.state(), Some(PowerState::OperationEnabled), "{last:?}");
        assert!(last.following_error.abs() <= 60, "{last:?}");
        assert!(
            (out.target_position - last.position).abs() <= 150,
            "{last:?}"
        );
    });
}

/// Flexible PDO mapping (ETG.1000.6, ETG.1020): in PRE-OP ethercrab writes
/// a mapping of its own (outputs: controlword, target position, modes of
/// operation; inputs: statusword, position), every refusal the core owes
/// on the way answered with its abort code; ethercrab then reads the new
/// mapping over CoE, sizes the images from it (7 and 6 bytes instead of
/// 13 and 19), reaches OP and enables CSP, and the position follows.
#[test]
fn ethercrab_writes_its_own_mapping_in_preop_and_runs_csp_on_it() {
    smol::block_on(async {
        let bus = VirtualBus::line("servo402", Clock::frames()).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("servo402");
        let code = |r: Result<(), ethercrab::error::Error>| {
            r.err().as_ref().and_then(crate::common::abort_code)
        };
        let map = |index: u16, bits: u32| u32::from(index) << 16 | bits;
        // An entry while subindex 0 is not 0.
        let r = sd.sdo_write(0x1600, 1, map(0x6040, 16)).await;
        assert_eq!(code(r), Some(0x0601_0003));
        sd.sdo_write(0x1600, 0, 0u8).await.expect("subindex 0 to 0");
        // The statusword is no output; a wrong length; a parameter.
        for bad in [map(0x6041, 16), map(0x6040, 32), map(0x6065, 32)] {
            let r = sd.sdo_write(0x1600, 1, bad).await;
            assert_eq!(code(r), Some(0x0604_0041), "{bad:#010x}");
        }
        for (sub, m) in [
            (1u8, map(0x6040, 16)),
            (2, map(0x607A, 32)),
            (3, map(0x6060, 8)),
            (4, 0),
        ] {
            sd.sdo_write(0x1600, sub, m).await.expect("mapping entry");
        }
        // A count over the cleared place, beyond the capacity.
        assert_eq!(code(sd.sdo_write(0x1600, 0, 4u8).await), Some(0x0604_0043));
        assert_eq!(code(sd.sdo_write(0x1600, 0, 9u8).await), Some(0x0609_0031));
        sd.sdo_write(0x1600, 0, 3u8).await.expect("three entries");
        sd.sdo_write(0x1A00, 0, 0u8).await.expect("subindex 0 to 0");
        sd.sdo_write(0x1A00, 1, map(0x6041, 16))
            .await
            .expect("statusword");
        sd.sdo_write(0x1A00, 2, map(0x6064, 32))
            .await
            .expect("position");
        sd.sdo_write(0x1A00, 0, 2u8).await.expect("two entries");
        let back: u32 = sd.sdo_read(0x1600, 2).await.expect("read back");
        assert_eq!(back, map(0x607A, 32));
        let group = master_test::into_op_cyclic(group, md, CYCLE)
            .await
            .expect("OP with the written mapping");
        let sd = group.subdevice(md, 0).expect("servo402");
        assert_eq!(
            (sd.outputs_raw().len(), sd.inputs_raw().len()),
            (7, 6),
            "the images of the written mapping"
        );
        // The mapping is fixed outside PRE-OP.
        let r = sd.sdo_write(0x1600, 0, 0u8).await;
        assert_eq!(code(r), Some(0x0800_0022));
        let (_, start) = custom_cycle(&bus, &group, 0, 0).await;
        for (cw, want) in [
            (control::SHUTDOWN, PowerState::ReadyToSwitchOn),
            (control::SWITCH_ON, PowerState::SwitchedOn),
            (control::ENABLE_OPERATION, PowerState::OperationEnabled),
        ] {
            let mut reached = false;
            for _ in 0..20 {
                let (sw, _) = custom_cycle(&bus, &group, cw, start).await;
                if PowerState::from_statusword(sw) == Some(want) {
                    reached = true;
                    break;
                }
            }
            assert!(reached, "controlword {cw:#06x}: no {want:?}");
        }
        // A ramp of 20 increments per cycle for 300 cycles: the position
        // follows it.
        let mut target = start;
        let mut position = start;
        for _ in 0..300 {
            target += 20;
            (_, position) = custom_cycle(&bus, &group, control::ENABLE_OPERATION, target).await;
        }
        assert!(
            (target - position).abs() < 200 && position > start + 5000,
            "target {target}, position {position}, start {start}"
        );
    });
}

/// One free-run cycle of the mapping written in
/// `ethercrab_writes_its_own_mapping_in_preop_and_runs_csp_on_it`:
/// controlword, target position and CSP out; statusword and position in.
async fn custom_cycle(bus: &VirtualBus, group: &FreeGroup, cw: u16, target: i32) -> (u16, i32) {
    let md = &*bus.maindevice;
    let sd = group.subdevice(md, 0).expect("servo402");
    {
        let mut o = sd.outputs_raw_mut();
        o[0..2].copy_from_slice(&cw.to_le_bytes());
        o[2..6].copy_from_slice(&target.to_le_bytes());
        o[6] = 8; // CSP
    }
    group.tx_rx(md).await.expect("cycle");
    bus.clock.advance(CYCLE);
    let i = sd.inputs_raw();
    (
        u16::from_le_bytes([i[0], i[1]]),
        i32::from_le_bytes([i[2], i[3], i[4], i[5]]),
    )
}
