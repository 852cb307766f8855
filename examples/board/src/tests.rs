//! The board code on the host: the "mock HAL" is a byte-level emulation
//! of the LAN9252's SPI interface (`ecat-esc-spi-emu`) in front of the
//! software ESC, whose IRQ output drives the IRQ pin, plus GPIO pins in
//! cells. A minimal master writes EtherCAT frames into the ESC.

extern crate std;

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::vec;
use std::vec::Vec;

use ecat_esc_spi_emu::lan9252::Lan9252Emu;
use ecat_sim::esc::SoftEsc;
use ecat_slave::al::AlState;
use ecat_slave::device::SM_CONTROL;
use ecat_slave::esc::registers as reg;
use ecat_slave::hal::MemNv;
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::ecat::Command;
use embedded_hal::digital::{self, InputPin, OutputPin};
use embedded_hal::spi::{self, Operation, SpiDevice};
use io8_example::DEVICE;

use super::*;

type Chip = Rc<RefCell<Lan9252Emu>>;

/// The SPI bus with the chip select: the emulated chip.
struct Spi(Chip);

impl spi::ErrorType for Spi {
    type Error = <Lan9252Emu as spi::ErrorType>::Error;
}

impl SpiDevice for Spi {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        self.0.borrow_mut().transaction(ops)
    }
}

/// The IRQ pin: low while the chip asserts its IRQ (active low).
struct IrqPin(Chip);

impl digital::ErrorType for IrqPin {
    type Error = core::convert::Infallible;
}

impl InputPin for IrqPin {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        Ok(!self.0.borrow().irq())
    }
    fn is_low(&mut self) -> Result<bool, Self::Error> {
        Ok(self.0.borrow().irq())
    }
}

/// A GPIO pin as a shared level.
#[derive(Clone, Default)]
struct Pin(Rc<Cell<bool>>);

impl digital::ErrorType for Pin {
    type Error = core::convert::Infallible;
}

impl InputPin for Pin {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        Ok(self.0.get())
    }
    fn is_low(&mut self) -> Result<bool, Self::Error> {
        Ok(!self.0.get())
    }
}

impl OutputPin for Pin {
    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.0.set(true);
        Ok(())
    }
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.0.set(false);
        Ok(())
    }
}

struct Rig {
    chip: Chip,
    node: Node<Spi, IrqPin, PinBoard<Pin, Pin>, MemNv<STORAGE_SIZE>>,
    inputs: [Pin; 8],
    outputs: [Pin; 8],
    now_ns: u64,
}

impl Rig {
    fn new() -> Self {
        let sii = DEVICE.sii_image();
        let chip = Rc::new(RefCell::new(Lan9252Emu::new(SoftEsc::new(&sii))));
        let inputs: [Pin; 8] = Default::default();
        let outputs: [Pin; 8] = Default::default();
        let board = PinBoard::new(inputs.clone(), outputs.clone());
        let (node, id) = Node::start(Spi(chip.clone()), IrqPin(chip.clone()), board, MemNv::new())
            .expect("the chip answers the byte test and is ready");
        assert_eq!(id.id, 0x9252, "chip id from ID_REV");
        Rig {
            chip,
            node,
            inputs,
            outputs,
            now_ns: 0,
        }
    }

    /// One APxx datagram from the master to the slave at position 0.
    fn transfer(&mut self, command: Command, ado: u16, data: &mut [u8]) -> u16 {
        let mut buf = vec![0u8; 1514];
        let mut b = FrameBuilder::new(&mut buf, [0x02, 0, 0, 0, 0, 1]).expect("frame");
        let r = b
            .push(command, u32::from(ado) << 16, data)
            .expect("datagram");
        let len = b.finish();
        self.chip
            .borrow_mut()
            .esc_mut()
            .process_frame(&mut buf[..len]);
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

    /// The main loop turning for `us` microseconds in 100 us steps;
    /// returns how many firmware passes it made.
    fn run_for(&mut self, us: u64) -> u32 {
        let before = self.node.passes();
        for _ in 0..us / 100 {
            self.now_ns += 100_000;
            self.node.step(self.now_ns).expect("PDI works");
        }
        self.node.passes() - before
    }

    fn al_state(&mut self) -> u8 {
        self.read(reg::AL_STATUS, 2)[0]
    }

    fn sync_manager(&mut self, n: u8, start: u16, len: u16) {
        let [s0, s1] = start.to_le_bytes();
        let [l0, l1] = len.to_le_bytes();
        let control = SM_CONTROL[usize::from(n)];
        self.write(reg::sm(n).expect("SM"), &[s0, s1, l0, l1, control, 0, 1, 0]);
    }
}

#[test]
fn a_quiet_irq_line_means_a_pass_per_idle_period_and_no_spi_traffic_between() {
    let mut rig = Rig::new();
    rig.run_for(2_000);
    let sel = rig.chip.borrow().counters().transactions();
    let passes = rig.run_for(10_000);
    assert_eq!(passes, 10, "one pass per IDLE_POLL_NS (1 ms) over 10 ms");
    let per_pass = (rig.chip.borrow().counters().transactions() - sel) / u64::from(passes);
    assert_eq!(
        per_pass, 3,
        "an idle pass on the LAN9252: the AL event through CSR"
    );
}

#[test]
fn an_al_control_write_asserts_irq_and_the_firmware_answers_within_one_step() {
    let mut rig = Rig::new();
    rig.run_for(2_000);
    let layout = DEVICE.layout();
    rig.sync_manager(0, layout.mbx_out.0, layout.mbx_out.1);
    rig.sync_manager(1, layout.mbx_in.0, layout.mbx_in.1);
    rig.run_for(1_000);
    rig.write(reg::AL_CONTROL, &[AlState::PreOp.bits(), 0]);
    assert!(rig.chip.borrow().irq(), "AL control event on the IRQ line");
    // 100 us later, not at the next idle period.
    assert_eq!(rig.run_for(100), 1);
    assert_eq!(rig.al_state(), AlState::PreOp.bits());
    assert!(
        !rig.chip.borrow().irq(),
        "the firmware's read of 0x0120 released it"
    );
}

#[test]
fn in_op_the_pins_follow_the_process_data_both_ways() {
    let mut rig = Rig::new();
    let layout = DEVICE.layout();
    rig.sync_manager(0, layout.mbx_out.0, layout.mbx_out.1);
    rig.sync_manager(1, layout.mbx_in.0, layout.mbx_in.1);
    rig.write(reg::AL_CONTROL, &[AlState::PreOp.bits(), 0]);
    rig.run_for(200);
    rig.sync_manager(2, layout.pd_out, 1);
    rig.sync_manager(3, layout.pd_in, 1);
    rig.write(reg::AL_CONTROL, &[AlState::SafeOp.bits(), 0]);
    rig.run_for(200);
    assert_eq!(rig.al_state(), AlState::SafeOp.bits());
    rig.write(layout.pd_out, &[0]);
    rig.write(reg::AL_CONTROL, &[AlState::Op.bits(), 0]);
    rig.run_for(200);
    assert_eq!(rig.al_state(), AlState::Op.bits());
    rig.inputs[2].0.set(true);
    rig.inputs[7].0.set(true);
    let mut got = 0;
    // Cycles of 1 ms beyond the IO8's 10 ms input filter.
    for _ in 0..15 {
        rig.write(layout.pd_out, &[0b1000_0001]);
        rig.run_for(1_000);
        got = rig.read(layout.pd_in, 1)[0];
    }
    assert_eq!(got, 0b1000_0100, "inputs 3 and 8");
    let driven: Vec<bool> = rig.outputs.iter().map(|p| p.0.get()).collect();
    assert_eq!(
        driven,
        [true, false, false, false, false, false, false, true],
        "outputs 1 and 8 on"
    );
    assert_eq!(rig.chip.borrow().counters().protocol_errors(), 0);
}
