//! The IO8 on the software ESC, driven by a minimal master that speaks
//! raw EtherCAT frames (auto-increment physical reads and writes to the
//! slave at position 0): the device's behaviour seen from the wire.

use ecat_sim::SoftSlave;
use ecat_slave::al::{AlState, AlStatus, AlStatusCode};
use ecat_slave::device::{Application, Changes, Download, SM_CONTROL, Write};
use ecat_slave::esc::registers as reg;
use ecat_slave::od::ObjectStore;
use ecat_slave::pdo::Direction;
use ecat_slave::sii::SiiReader;
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::coe::SdoAbortCode;
use ecat_slave::wire::ecat::Command;

use crate::description::{INPUTS, OUTPUTS, SAVE_SIGNATURE, SETTINGS, STORE_PARAMETERS};
use crate::*;

const MS: u64 = 1_000_000;

/// A master for one slave, one datagram per frame, with a simulated clock.
struct Master {
    slave: SoftSlave<Io8>,
    now_ns: u64,
}

impl Master {
    fn new() -> Self {
        Master {
            slave: SoftSlave::new(Io8::default()),
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

    fn write(&mut self, ado: u16, data: &[u8]) {
        let mut d = data.to_vec();
        assert_eq!(
            self.transfer(Command::Apwr, ado, &mut d),
            1,
            "APWR {ado:#06x}"
        );
    }

    fn read(&mut self, ado: u16, len: usize) -> Vec<u8> {
        let mut d = vec![0u8; len];
        assert_eq!(
            self.transfer(Command::Aprd, ado, &mut d),
            1,
            "APRD {ado:#06x}"
        );
        d
    }

    /// Lets `ms` pass, then runs the firmware once.
    fn poll(&mut self, ms: u64) {
        self.now_ns += ms * MS;
        self.slave.poll(self.now_ns).unwrap();
    }

    fn status(&self) -> AlStatus {
        self.slave.slave().al_status()
    }

    fn request(&mut self, state: AlState) -> AlStatus {
        self.write(reg::AL_CONTROL, &[state.bits(), 0]);
        self.poll(1);
        self.status()
    }

    fn sync_manager(&mut self, n: u8, start: u16, len: u16) {
        let [s0, s1] = start.to_le_bytes();
        let [l0, l1] = len.to_le_bytes();
        let control = SM_CONTROL[usize::from(n)];
        self.write(reg::sm(n).unwrap(), &[s0, s1, l0, l1, control, 0, 1, 0]);
    }

    /// One cycle: outputs written, the firmware run after `ms`, inputs read.
    fn cycle(&mut self, outputs: u8, ms: u64) -> u8 {
        let layout = DEVICE.layout();
        self.write(layout.pd_out, &[outputs]);
        self.poll(ms);
        self.read(layout.pd_in, 1)[0]
    }

    /// INIT -> PRE-OP -> SAFE-OP -> OP as a master configures the device
    /// from its SII: mailboxes, then one byte of process data each way.
    fn bring_to_op(&mut self) {
        let layout = DEVICE.layout();
        self.sync_manager(0, layout.mbx_out.0, layout.mbx_out.1);
        self.sync_manager(1, layout.mbx_in.0, layout.mbx_in.1);
        assert_eq!(self.request(AlState::PreOp).state, AlState::PreOp);
        self.sync_manager(2, layout.pd_out, 1);
        self.sync_manager(3, layout.pd_in, 1);
        assert_eq!(self.request(AlState::SafeOp).state, AlState::SafeOp);
        self.cycle(0, 1);
        assert_eq!(
            self.request(AlState::Op),
            AlStatus {
                state: AlState::Op,
                error: false,
                code: AlStatusCode::NoError,
            }
        );
    }

    fn app(&mut self) -> &mut Io8 {
        self.slave.slave_mut().app_mut()
    }
}

#[test]
fn the_description_is_valid() {
    assert_eq!(DEVICE.validate(), Ok(()));
    assert_eq!(DICT.entry_count(), ENTRIES);
}

#[test]
fn the_process_image_is_one_byte_each_way() {
    assert_eq!(DEVICE.default_image_len(Direction::Outputs), 1);
    assert_eq!(DEVICE.default_image_len(Direction::Inputs), 1);
}

#[test]
fn the_sii_image_carries_identity_names_and_mailboxes() {
    let image = DEVICE.sii_image();
    let sii = SiiReader::new(&image).unwrap();
    assert!(sii.crc_ok());
    let id = sii.identity();
    assert_eq!((id.vendor_id, id.product_code, id.revision), (0xABE, 8, 1));
    let strings = sii.strings().unwrap();
    assert_eq!(strings.get(1), Some("IO8"), "string 1: the device type");
    let general = sii.general().unwrap().unwrap().resolve(&strings);
    assert_eq!(general.name, "IO8 8-channel digital I/O");
    assert_eq!(general.order, "IO8");
    assert_eq!(general.group, "DigIO");
    assert_eq!(sii.standard_mailbox().rx_size, 128);
    assert_eq!(sii.bootstrap_mailbox().rx_size, 128);
    let foe = ecat_slave::sii::protocols::FOE;
    assert_eq!(sii.mailbox_protocols() & foe, foe);
}

#[test]
fn the_debounce_takes_a_change_once_it_was_stable_for_the_filter_time() {
    let mut f = Debounce::new();
    assert_eq!(f.update(0b0000_0001, 0, 10 * MS), 0);
    assert_eq!(f.update(0b0000_0001, 9 * MS, 10 * MS), 0);
    assert_eq!(f.update(0b0000_0001, 10 * MS, 10 * MS), 1);
    // Falling edges are filtered the same way, per input.
    assert_eq!(f.update(0b1000_0000, 11 * MS, 10 * MS), 1);
    assert_eq!(f.update(0b1000_0000, 21 * MS, 10 * MS), 0b1000_0000);
}

#[test]
fn the_debounce_ignores_glitches_shorter_than_the_filter_time() {
    let mut f = Debounce::new();
    let mut t = 0;
    // Bouncing every 3 ms never settles for 10 ms.
    for level in [1, 0, 1, 0, 1, 0] {
        assert_eq!(f.update(level, t, 10 * MS), 0, "at {t}");
        t += 3 * MS;
    }
    assert_eq!(f.update(1, t, 10 * MS), 0);
    assert_eq!(f.update(1, t + 10 * MS, 10 * MS), 1);
}

#[test]
fn a_zero_filter_passes_inputs_at_once() {
    let mut f = Debounce::new();
    assert_eq!(f.update(0xA5, 5, 0), 0xA5);
    assert_eq!(f.levels(), 0xA5);
}

#[test]
fn the_soft_slave_reaches_op_with_the_standard_pdo_set() {
    let mut m = Master::new();
    assert_eq!(m.status().state, AlState::Init);
    m.bring_to_op();
    assert_eq!(m.read(reg::AL_STATUS, 2), [0x08, 0x00]);
}

#[test]
fn inputs_reach_0x6000_and_the_master_only_after_the_filter_time() {
    let mut m = Master::new();
    m.bring_to_op();
    m.app().board_mut().set_input(1, true);
    m.app().board_mut().set_input(8, true);
    // Seen at the first poll; 10 ms (the default filter) later it counts.
    for _ in 0..10 {
        assert_eq!(m.cycle(0, 1), 0);
        assert_eq!(m.slave.slave().od().get(INPUTS, 1), Some(0));
    }
    assert_eq!(m.cycle(0, 1), 0b1000_0001);
    assert_eq!(m.slave.slave().od().get(INPUTS, 1), Some(1));
    assert_eq!(m.slave.slave().od().get(INPUTS, 8), Some(1));
    assert_eq!(m.slave.slave().od().get(INPUTS, 2), Some(0));
}

#[test]
fn the_input_filter_parameter_sets_the_debounce_time() {
    let mut m = Master::new();
    m.slave.slave_mut().od_mut().set(SETTINGS, 1, 0);
    m.bring_to_op();
    m.app().board_mut().input_levels = 0x3C;
    assert_eq!(m.cycle(0, 1), 0x3C, "no filter");
    m.slave.slave_mut().od_mut().set(SETTINGS, 1, 50);
    m.app().board_mut().input_levels = 0;
    // Seen at the first poll, taken 50 ms later.
    for _ in 0..50 {
        assert_eq!(m.cycle(0, 1), 0x3C);
    }
    assert_eq!(m.cycle(0, 1), 0);
}

#[test]
fn outputs_reach_the_board_only_while_the_device_is_in_op() {
    let mut m = Master::new();
    let layout = DEVICE.layout();
    m.sync_manager(0, layout.mbx_out.0, layout.mbx_out.1);
    m.sync_manager(1, layout.mbx_in.0, layout.mbx_in.1);
    m.request(AlState::PreOp);
    m.sync_manager(2, layout.pd_out, 1);
    m.sync_manager(3, layout.pd_in, 1);
    m.request(AlState::SafeOp);
    // SAFE-OP: outputs in the dictionary are not valid, the board stays off.
    m.slave.slave_mut().od_mut().set(OUTPUTS, 1, 1);
    m.cycle(0xFF, 1);
    assert_eq!(m.app().board().output_levels, 0);
    assert_eq!(m.request(AlState::Op).state, AlState::Op);
    m.cycle(0xA5, 1);
    assert_eq!(m.app().board().output_levels, 0xA5);
    assert!(m.app().board().output(1) && !m.app().board().output(2));
    assert_eq!(m.slave.slave().od().get(OUTPUTS, 6), Some(1));
    // Leaving OP switches them off at once and clears 0x7000.
    assert_eq!(m.request(AlState::SafeOp).state, AlState::SafeOp);
    assert_eq!(m.app().board().output_levels, 0);
    assert_eq!(m.slave.slave().od().get(OUTPUTS, 1), Some(0));
}

#[test]
fn an_sdo_read_of_outputs_in_the_same_firmware_pass_sees_the_new_outputs() {
    // A master writes outputs and then reads one back by SDO; both reach
    // the firmware in one pass (the SDO request frame came before the
    // firmware ran after the process-data frame). The pass takes the
    // outputs first, as the SSC's SM2 interrupt does, so the SDO answer
    // has the value just written.
    let mut m = Master::new();
    m.bring_to_op();
    m.cycle(0x00, 1);
    assert_eq!(m.slave.slave().od().get(OUTPUTS, 1), Some(0));
    let layout = DEVICE.layout();
    m.write(layout.pd_out, &[0xA5]);
    // ETG.1000.6 5.6.2.4, SDO upload request of 0x7000:01: mailbox header
    // (length 10, CoE, counter 1), CoE header (SDO request), initiate
    // upload.
    let mut request = vec![
        10, 0, 0, 0, 0, 0x13, 0x00, 0x20, 0x40, 0x00, 0x70, 0x01, 0, 0, 0, 0,
    ];
    request.resize(usize::from(layout.mbx_out.1), 0);
    m.write(layout.mbx_out.0, &request);
    m.poll(1);
    let response = m.read(layout.mbx_in.0, usize::from(layout.mbx_in.1));
    // CoE SDO response, expedited upload of one byte: output 1 of 0xA5.
    assert_eq!(&response[6..12], &[0x00, 0x30, 0x4F, 0x00, 0x70, 0x01]);
    assert_eq!(response[12], 1, "0x7000:01 after outputs 0xA5");
}

#[test]
fn an_expired_sm_watchdog_switches_the_outputs_off() {
    let mut m = Master::new();
    m.bring_to_op();
    m.cycle(0xFF, 1);
    assert_eq!(m.app().board().output_levels, 0xFF);
    // No outputs from the master for 150 ms (the watchdog is 100 ms).
    m.poll(150);
    m.poll(1);
    assert_eq!(m.status().state, AlState::SafeOp);
    assert_eq!(m.status().code, AlStatusCode::SmWatchdog);
    assert_eq!(m.app().board().output_levels, 0);
}

#[test]
fn a_stalled_firmware_has_its_outputs_switched_off_by_the_pdi_watchdog() {
    let mut m = Master::new();
    m.bring_to_op();
    m.cycle(0x0F, 1);
    assert_eq!(m.app().board().output_levels, 0x0F);
    m.slave.set_stalled(true);
    m.poll(150);
    assert_eq!(m.app().board().output_levels, 0);
}

#[test]
fn writing_save_to_0x1010_stores_the_parameters_for_the_next_power_on() {
    let mut m = Master::new();
    let save = |m: &mut Master, value: i64| {
        let (app, od) = m.slave.slave_mut().app_and_od();
        let pairs = [(1, value)];
        let download = Download {
            index: STORE_PARAMETERS,
            sub: 1,
            complete_access: false,
            state: AlState::PreOp,
            now_ns: 0,
            changes: Changes::list(&pairs),
        };
        app.sdo_download(od, &download)
    };
    m.slave.slave_mut().od_mut().set(SETTINGS, 1, 250);
    assert_eq!(save(&mut m, 1), Err(SdoAbortCode::TransferFailed));
    assert_eq!(save(&mut m, SAVE_SIGNATURE), Ok(Write::Done));
    assert_eq!(m.slave.slave().od().get(STORE_PARAMETERS, 1), Some(1));
    m.slave.power_cycle();
    assert_eq!(m.slave.slave().od().get(SETTINGS, 1), Some(250));
    // A fresh device with the same storage powers on with it too.
    let nv = m.app().storage().clone();
    let other = SoftSlave::new(Io8::new(SimBoard::new(), nv));
    assert_eq!(other.slave().od().get(SETTINGS, 1), Some(250));
}

#[test]
fn other_writes_are_stored_as_the_core_checked_them() {
    let mut app = Io8::default();
    let mut store = ObjectStore::<[i64; ENTRIES]>::new(&DICT);
    let download = Download {
        index: SETTINGS,
        sub: 1,
        complete_access: false,
        state: AlState::Op,
        now_ns: 0,
        changes: Changes::list(&[(1, 20)]),
    };
    assert_eq!(app.sdo_download(&mut store, &download), Ok(Write::Store));
}

/// PDI transfers (each one an SPI transaction on a real ESC) of one pass
/// of the firmware loop: the loop reads the AL event request first and
/// touches only what it flags.
#[test]
fn an_idle_pass_is_one_pdi_transfer_and_a_cycle_in_op_three() {
    let mut m = Master::new();
    let pdi = |m: &Master| m.slave.slave().esc().pdi_accesses();
    let layout = DEVICE.layout();
    m.sync_manager(0, layout.mbx_out.0, layout.mbx_out.1);
    m.sync_manager(1, layout.mbx_in.0, layout.mbx_in.1);
    assert_eq!(m.request(AlState::PreOp).state, AlState::PreOp);
    m.poll(1);
    let before = pdi(&m);
    m.poll(1);
    assert_eq!(pdi(&m) - before, 1, "PRE-OP, nothing flagged: 0x0220 only");
    m.sync_manager(2, layout.pd_out, 1);
    m.sync_manager(3, layout.pd_in, 1);
    assert_eq!(m.request(AlState::SafeOp).state, AlState::SafeOp);
    m.cycle(0, 1);
    assert_eq!(m.request(AlState::Op).state, AlState::Op);
    m.poll(1);
    let before = pdi(&m);
    m.poll(1);
    assert_eq!(pdi(&m) - before, 2, "OP, nothing flagged: 0x0220 + inputs");
    // A cycle: the master writes the outputs and reads the inputs.
    let before = pdi(&m);
    m.cycle(0x5A, 1);
    assert_eq!(pdi(&m) - before, 3, "OP cycle: 0x0220 + outputs + inputs");
    assert!(
        m.slave.slave().app().board().output(2),
        "0x5A bit 1 reached"
    );
    // The backstop: a full pass at least every FULL_PASS_NS.
    let before = pdi(&m);
    m.poll(ecat_slave::device::FULL_PASS_NS / MS);
    assert!(pdi(&m) - before > 3, "full pass after 100 ms");
}
