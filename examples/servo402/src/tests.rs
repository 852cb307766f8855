//! The servo402 on the software ESC, driven by a minimal master that
//! speaks raw EtherCAT frames (auto-increment physical reads and writes
//! to the slave at position 0): the drive seen from the wire.

use ecat_cia402::PowerState;
use ecat_cia402::objects::{RX_PDO_BYTES, TX_PDO_BYTES, index};
use ecat_cia402::state::control;
use ecat_sim::SoftSlave;
use ecat_slave::al::{AlState, AlStatus};
use ecat_slave::device::{Application, Changes, Download, SM_CONTROL, Write};
use ecat_slave::esc::registers as reg;
use ecat_slave::pdo::Direction;
use ecat_slave::sii::SiiReader;
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::coe::SdoAbortCode;
use ecat_slave::wire::ecat::Command;

use crate::*;

mod invariants;

pub(crate) const MS: u64 = 1_000_000;

/// The cyclic outputs of 0x1600.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Out {
    pub controlword: u16,
    pub target_position: i32,
    pub target_velocity: i32,
    pub target_torque: i16,
    pub mode: i8,
}

impl Out {
    fn bytes(&self) -> [u8; RX_PDO_BYTES] {
        let mut b = [0u8; RX_PDO_BYTES];
        b[0..2].copy_from_slice(&self.controlword.to_le_bytes());
        b[2..6].copy_from_slice(&self.target_position.to_le_bytes());
        b[6..10].copy_from_slice(&self.target_velocity.to_le_bytes());
        b[10..12].copy_from_slice(&self.target_torque.to_le_bytes());
        b[12] = self.mode as u8;
        b
    }
}

/// The cyclic inputs of 0x1A00.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct In {
    pub statusword: u16,
    pub position: i32,
    pub velocity: i32,
    pub torque: i16,
    pub mode_display: i8,
    pub following_error: i32,
    pub error_code: u16,
}

impl In {
    fn parse(b: &[u8]) -> Self {
        let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
        let i32_at = |i: usize| i32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        In {
            statusword: u16_at(0),
            position: i32_at(2),
            velocity: i32_at(6),
            torque: u16_at(10) as i16,
            mode_display: b[12] as i8,
            following_error: i32_at(13),
            error_code: u16_at(17),
        }
    }

    pub fn state(&self) -> Option<PowerState> {
        PowerState::from_statusword(self.statusword)
    }
}

/// A master for one servo402, one datagram per frame, with a simulated clock.
pub(crate) struct Master<A: Application = Servo402> {
    pub slave: SoftSlave<A>,
    pub now_ns: u64,
}

impl Master<Servo402> {
    pub fn new() -> Self {
        Master::with(Servo402::default())
    }
}

impl<A: Application> Master<A> {
    pub fn with(app: A) -> Self {
        Master {
            slave: SoftSlave::new(app),
            now_ns: 0,
        }
    }

    /// Sends one APxx datagram to `ado`; returns the working counter.
    fn transfer(&mut self, command: Command, ado: u16, data: &mut [u8]) -> u16 {
        let mut buf = vec![0u8; 1514];
        let mut b = FrameBuilder::new(&mut buf, [0x02, 0, 0, 0, 0, 1]).unwrap();
        let r = b.push(command, u32::from(ado) << 16, data).unwrap();
        let len = b.finish();
        self.slave.process_frame(&mut buf[..len]);
        data.copy_from_slice(&buf[r.clone()]);
        u16::from_le_bytes([buf[r.end], buf[r.end + 1]])
    }

    pub fn write(&mut self, ado: u16, data: &[u8]) {
        let mut d = data.to_vec();
        assert_eq!(
            self.transfer(Command::Apwr, ado, &mut d),
            1,
            "APWR {ado:#06x}"
        );
    }

    pub fn read(&mut self, ado: u16, len: usize) -> Vec<u8> {
        let mut d = vec![0u8; len];
        assert_eq!(
            self.transfer(Command::Aprd, ado, &mut d),
            1,
            "APRD {ado:#06x}"
        );
        d
    }

    /// Lets `ns` pass, then runs the firmware once.
    pub fn poll_ns(&mut self, ns: u64) {
        self.now_ns += ns;
        self.slave.poll(self.now_ns).unwrap();
    }

    pub fn status(&self) -> AlStatus {
        self.slave.slave().al_status()
    }

    pub fn request(&mut self, state: AlState) -> AlStatus {
        self.write(reg::AL_CONTROL, &[state.bits() | 0x10, 0]);
        self.poll_ns(MS);
        self.status()
    }

    fn sync_manager(&mut self, n: u8, start: u16, len: u16) {
        let [s0, s1] = start.to_le_bytes();
        let [l0, l1] = len.to_le_bytes();
        let control = SM_CONTROL[usize::from(n)];
        self.write(reg::sm(n).unwrap(), &[s0, s1, l0, l1, control, 0, 1, 0]);
    }

    /// The SyncManagers as a master configures them from the SII.
    pub fn configure(&mut self) {
        let layout = DEVICE.layout();
        self.sync_manager(0, layout.mbx_out.0, layout.mbx_out.1);
        self.sync_manager(1, layout.mbx_in.0, layout.mbx_in.1);
        self.sync_manager(2, layout.pd_out, RX_PDO_BYTES as u16);
        self.sync_manager(3, layout.pd_in, TX_PDO_BYTES as u16);
    }

    /// One cycle: outputs written, the firmware run after `ns`, inputs read.
    pub fn cycle_ns(&mut self, out: Out, ns: u64) -> In {
        let layout = DEVICE.layout();
        self.write(layout.pd_out, &out.bytes());
        self.poll_ns(ns);
        In::parse(&self.read(layout.pd_in, TX_PDO_BYTES))
    }

    pub fn cycle(&mut self, out: Out) -> In {
        self.cycle_ns(out, MS)
    }

    /// The inputs without writing outputs, after `ns`.
    pub fn idle_ns(&mut self, ns: u64) -> In {
        self.poll_ns(ns);
        In::parse(&self.read(DEVICE.layout().pd_in, TX_PDO_BYTES))
    }

    /// INIT -> PRE-OP -> SAFE-OP -> OP with outputs `out` flowing.
    pub fn bring_to_op(&mut self, out: Out) {
        self.configure();
        assert_eq!(self.request(AlState::PreOp).state, AlState::PreOp);
        assert_eq!(self.request(AlState::SafeOp).state, AlState::SafeOp);
        self.cycle(out);
        assert_eq!(self.request(AlState::Op).state, AlState::Op);
        self.cycle(out);
    }

    /// An SDO download as the core hands it to the application after its
    /// own checks, stored when accepted.
    pub fn sdo(&mut self, index: u16, sub: u8, value: i64) -> Result<Write, SdoAbortCode> {
        let state = self.status().state;
        let (app, od) = self.slave.slave_mut().app_and_od();
        let changes = [(sub, value)];
        let d = Download {
            index,
            sub,
            complete_access: false,
            state,
            now_ns: 0,
            changes: Changes::list(&changes),
        };
        let r = app.sdo_download(od, &d);
        if r == Ok(Write::Store) {
            d.apply(od);
        }
        r
    }
}

impl Master<Servo402> {
    pub fn board(&self) -> &SimBoard {
        self.slave.slave().app().board()
    }

    pub fn drive_state(&self) -> PowerState {
        self.slave.slave().app().axis().drive().state()
    }
}

/// Shutdown, switch on, enable operation in `mode`, the target at the
/// actual position; the inputs in Operation enabled.
pub(crate) fn enable<A: Application>(m: &mut Master<A>, mode: i8) -> In {
    let pos = m.cycle(Out::default()).position;
    let mut out = Out {
        mode,
        target_position: pos,
        ..Out::default()
    };
    for cw in [
        control::SHUTDOWN,
        control::SWITCH_ON,
        control::ENABLE_OPERATION,
    ] {
        out.controlword = cw;
        m.cycle(out);
    }
    let i = m.cycle(out);
    assert_eq!(i.state(), Some(PowerState::OperationEnabled), "{i:?}");
    i
}

#[test]
fn the_description_is_valid() {
    assert_eq!(DEVICE.validate(), Ok(()));
    assert_eq!(DICT.entry_count(), ENTRIES);
}

#[test]
fn the_process_image_is_the_13_and_19_bytes_of_the_fixed_mappings() {
    assert_eq!(
        usize::from(DEVICE.default_image_len(Direction::Outputs)),
        RX_PDO_BYTES
    );
    assert_eq!(
        usize::from(DEVICE.default_image_len(Direction::Inputs)),
        TX_PDO_BYTES
    );
}

#[test]
fn the_sii_image_carries_identity_names_and_mailboxes() {
    let image = DEVICE.sii_image();
    let sii = SiiReader::new(&image).unwrap();
    assert!(sii.crc_ok());
    let id = sii.identity();
    assert_eq!(
        (id.vendor_id, id.product_code, id.revision),
        (0xABE, 0x402, 1)
    );
    assert_eq!(sii.strings().unwrap().get(1), Some("SERVO402"));
}

#[test]
fn a_master_enables_csp_in_op_and_the_position_follows_a_ramp() {
    let mut m = Master::new();
    m.bring_to_op(Out::default());
    let start = enable(&mut m, 8);
    assert_eq!(start.mode_display, 8);
    assert!(m.board().stage.enabled);
    let mut out = Out {
        controlword: control::ENABLE_OPERATION,
        mode: 8,
        target_position: start.position,
        ..Out::default()
    };
    let mut worst = 0;
    let mut last = start;
    for _ in 0..300 {
        out.target_position += 50; // 50 000 inc/s at 1 ms
        last = m.cycle(out);
        worst = worst.max(last.following_error.abs());
    }
    assert_eq!(last.state(), Some(PowerState::OperationEnabled));
    // The lag of the position loop: v x tau = 50 inc.
    assert!(worst <= 51, "following error up to {worst}");
    assert!(
        (out.target_position - last.position - 50).abs() <= 1,
        "{last:?}"
    );
    assert_eq!(last.error_code, 0);
}

#[test]
fn an_sdo_written_controlword_never_enables_the_power_stage() {
    let mut m = Master::new();
    m.configure();
    for state in [AlState::PreOp, AlState::SafeOp] {
        m.request(state);
        for cw in [
            control::SHUTDOWN,
            control::SWITCH_ON,
            control::ENABLE_OPERATION,
        ] {
            assert_eq!(
                m.sdo(index::CONTROLWORD, 0, i64::from(cw)),
                Ok(Write::Store)
            );
            m.poll_ns(MS);
        }
        assert_eq!(m.drive_state(), PowerState::SwitchOnDisabled, "{state:?}");
        assert!(!m.board().stage.enabled);
    }
}

#[test]
fn leaving_op_in_operation_enabled_brakes_and_faults_with_0x8100() {
    let mut m = Master::new();
    m.bring_to_op(Out::default());
    enable(&mut m, 9);
    let out = Out {
        controlword: control::ENABLE_OPERATION,
        mode: 9,
        target_velocity: 100_000,
        ..Out::default()
    };
    for _ in 0..50 {
        m.cycle(out);
    }
    assert_eq!(m.request(AlState::SafeOp).state, AlState::SafeOp);
    assert_eq!(m.drive_state(), PowerState::FaultReactionActive);
    assert!(m.board().stage.enabled, "braking on 0x6085");
    // 100 000 inc/s at 5e6 inc/s²: 20 ms, then the loops settle.
    let mut i = m.idle_ns(MS);
    for _ in 0..50 {
        i = m.idle_ns(MS);
    }
    assert_eq!(i.state(), Some(PowerState::Fault));
    assert_eq!(i.error_code, 0x8100);
    assert!(!m.board().stage.enabled);
    assert_eq!(i.torque, 0);
}

#[test]
fn frames_that_stop_in_op_end_in_fault_through_the_sm_watchdog() {
    let mut m = Master::new();
    m.bring_to_op(Out::default());
    enable(&mut m, 8);
    // No more frames: the SM watchdog (100 ms) ends OP.
    for _ in 0..20 {
        m.poll_ns(10 * MS);
    }
    let s = m.status();
    assert_eq!((s.state, s.error), (AlState::SafeOp, true));
    assert_eq!(m.drive_state(), PowerState::Fault);
    assert!(!m.board().stage.enabled);
}

#[test]
fn with_the_sm_watchdog_disarmed_the_drive_cannot_be_enabled() {
    let mut m = Master::new();
    m.configure();
    m.write(reg::WATCHDOG_TIME_PD, &[0, 0]);
    m.request(AlState::PreOp);
    m.request(AlState::SafeOp);
    m.cycle(Out::default());
    m.request(AlState::Op);
    assert_eq!(m.status().state, AlState::Op);
    let mut out = Out::default();
    for cw in [
        control::SHUTDOWN,
        control::SWITCH_ON,
        control::ENABLE_OPERATION,
    ] {
        out.controlword = cw;
        let i = m.cycle(out);
        assert_eq!(i.state(), Some(PowerState::SwitchOnDisabled));
    }
    assert!(!m.board().stage.enabled);
}

#[test]
fn a_stalled_firmware_leaves_the_drive_in_fault_0x6010() {
    let mut m = Master::new();
    m.bring_to_op(Out::default());
    enable(&mut m, 8);
    m.slave.slave_mut().app_mut().pdi_watchdog_expired();
    assert!(!m.board().stage.enabled);
    assert_eq!(m.drive_state(), PowerState::Fault);
    let i = m.cycle(Out {
        controlword: control::ENABLE_OPERATION,
        mode: 8,
        ..Out::default()
    });
    assert_eq!(i.error_code, 0x6010);
}

#[test]
fn a_board_fault_faults_the_drive_and_holds_the_fault_reset_until_it_clears() {
    let mut m = Master::new();
    m.bring_to_op(Out::default());
    enable(&mut m, 8);
    m.slave.slave_mut().app_mut().board_mut().fault_code = Some(0x2310);
    let mut out = Out {
        controlword: control::ENABLE_OPERATION,
        mode: 8,
        ..Out::default()
    };
    let i = m.cycle(out);
    assert_eq!(i.error_code, 0x2310);
    assert_eq!(
        m.slave.slave().od().get(description::POWER_STAGE_FAULT, 0),
        Some(0x2310)
    );
    for _ in 0..50 {
        m.cycle(out);
    }
    out.controlword = control::FAULT_RESET;
    assert_eq!(m.cycle(out).state(), Some(PowerState::Fault));
    m.slave.slave_mut().app_mut().board_mut().fault_code = None;
    out.controlword = 0;
    m.cycle(out);
    out.controlword = control::FAULT_RESET;
    let i = m.cycle(out);
    assert_eq!(i.state(), Some(PowerState::SwitchOnDisabled));
    assert_eq!(i.error_code, 0);
}

#[test]
fn safety_parameters_are_refused_in_operation_enabled_and_accepted_when_disabled() {
    let mut m = Master::new();
    assert_eq!(
        m.sdo(index::QUICK_STOP_DECELERATION, 0, 1_000_000),
        Ok(Write::Store)
    );
    m.bring_to_op(Out::default());
    enable(&mut m, 8);
    assert_eq!(
        m.sdo(index::QUICK_STOP_DECELERATION, 0, 1),
        Err(SdoAbortCode::InvalidState)
    );
    assert_eq!(
        m.slave.slave().od().get(index::QUICK_STOP_DECELERATION, 0),
        Some(1_000_000)
    );
    assert_eq!(m.sdo(index::PROFILE_VELOCITY, 0, 5), Ok(Write::Store));
    assert_eq!(
        m.sdo(index::MODES_OF_OPERATION, 0, 2),
        Err(SdoAbortCode::ValueRange)
    );
}

#[test]
fn save_stores_the_profile_parameters_for_the_next_power_on() {
    let mut m = Master::new();
    assert_eq!(
        m.sdo(index::FOLLOWING_ERROR_WINDOW, 0, 1234),
        Ok(Write::Store)
    );
    assert_eq!(
        m.sdo(description::STORE_PARAMETERS, 1, 1),
        Err(SdoAbortCode::TransferFailed)
    );
    assert_eq!(
        m.sdo(
            description::STORE_PARAMETERS,
            1,
            description::SAVE_SIGNATURE
        ),
        Ok(Write::Done)
    );
    m.slave.power_cycle();
    assert_eq!(
        m.slave.slave().od().get(index::FOLLOWING_ERROR_WINDOW, 0),
        Some(1234)
    );
    assert_eq!(m.drive_state(), PowerState::NotReadyToSwitchOn);
    m.poll_ns(MS);
    assert_eq!(m.drive_state(), PowerState::SwitchOnDisabled);
}
