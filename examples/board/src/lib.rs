//! # Board support example: the IO8 on an STM32 Nucleo with a LAN9252 shield
//!
//! What an embedded team writes to put a device of the `ecat-slave` core
//! on a board: the board's pins as the device's [`Board`], the ESC chip
//! behind the SPI PDI driver of `ecat-esc-spi`, and a main loop that runs
//! the firmware when the ESC's IRQ line says an AL event is waiting (and
//! at a slow idle period otherwise, for the timers and the backstop pass).
//! Everything here is `no_std` and generic over the `embedded-hal` 1.0
//! traits, so the same code builds for the microcontroller and, in CI, for
//! the host, where the tests put a byte-level emulation of the LAN9252
//! (`ecat-esc-spi-emu`) behind the SPI bus and drive the ESC with EtherCAT
//! frames.
//!
//! ## The target
//!
//! An STM32 Nucleo-64 board (e.g. NUCLEO-F401RE, Cortex-M4F) with a
//! LAN9252 EtherCAT shield on its Arduino header (for instance the EasyCAT
//! shield): SPI1 on D13/D12/D11 (PA5 SCK, PA6 MISO, PA7 MOSI), chip select
//! on D9 (PC7), the LAN9252 IRQ on D2 (PA10, active low as
//! [`Node::start`] programs it), eight inputs and eight outputs on free
//! GPIOs. The LAN9252 takes SPI mode 0 up to several MHz.
//!
//! ## The firmware binaries
//!
//! This crate is the board-independent part, host-tested. Two
//! `cortex-m-rt` binaries for `thumbv7em-none-eabihf` use it; they are
//! not workspace members (their target and linker scripts are their own):
//!
//! * `examples/board/nucleo-f446re/`: the NUCLEO-F446RE with a LAN9252
//!   shield on `stm32f4xx-hal`, the IRQ on an EXTI line, parameters and
//!   FoE images in the internal flash ([`store`]); flashed with probe-rs.
//! * `examples/board/qemu/`: the same application and main loop on QEMU's
//!   `mps2-an386` (Cortex-M4), with the SPI bus and the flash carried over
//!   the emulated UART to a host bridge ([`link`]); CI brings it to OP
//!   with SOEM.
//!
//! Both do, in their `main`:
//!
//! ```text
//! let (mut node, _chip) = Node::start(spi, irq, board, nv)?;   // byte test, IRQ set up
//! node.boot(&mut images, FIRMWARE_VERSION);                    // bootloader decision, 0x100A
//! loop {
//!     node.step_with(now_ns(), Some(&mut images));             // a pass if IRQ or 1 ms
//!     wfi();                                                   // sleep until IRQ or tick
//! }
//! ```
//!
//! Parameters (0x1010 "save") go to whatever [`NvStorage`] the board
//! gives: a flash sector on the STM32; [`MemNv`] loses them at power-off.
//!
//! For an ET1100-family chip (ET1100, ET1200, AX58100, LAN9253 in
//! "Beckhoff SPI" mode) replace [`Lan9252Spi`] by
//! `ecat_esc_spi::et1100::Et1100Spi` and drop the start-up checks; the
//! IRQ and the loop stay the same, and an idle pass costs one short SPI
//! transaction instead of three.
#![no_std]
#![forbid(unsafe_code)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod link;
pub mod store;

use ecat_esc_spi::lan9252::{ChipId, Lan9252Error, Lan9252Spi};
use ecat_slave::device::{PollSchedule, Slave};
use ecat_slave::esc::EscError;
use ecat_slave::firmware::{self, BootDecision, FirmwareVersion, ImageStore};
use ecat_slave::hal::{MemNv, NvStorage};
use ecat_slave::params::STORAGE_SIZE;
use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::spi::SpiDevice;
use io8_example::{Board, Io8};

/// Longest time between two passes of the firmware when the IRQ line stays
/// quiet: the application's timers (the IO8's input filter) and the
/// firmware's watchdog checks run at least this often.
pub const IDLE_POLL_NS: u64 = 1_000_000;

/// Payload of the factory image [`Node::boot`] records in a blank store.
pub const FACTORY_MARKER: &[u8] = b"factory firmware (runs from the MCU's own flash)";

/// Eight input pins and eight output pins as the IO8's [`Board`]. A pin
/// that cannot be read reads low; an output that cannot be set is skipped
/// (GPIO errors are `Infallible` on most MCUs).
#[derive(Debug)]
pub struct PinBoard<I: InputPin, O: OutputPin> {
    inputs: [I; 8],
    outputs: [O; 8],
}

impl<I: InputPin, O: OutputPin> PinBoard<I, O> {
    /// Inputs 1..=8 and outputs 1..=8, in channel order.
    pub fn new(inputs: [I; 8], outputs: [O; 8]) -> Self {
        PinBoard { inputs, outputs }
    }

    /// The output pins (a test reads what the firmware drove).
    pub fn outputs(&self) -> &[O; 8] {
        &self.outputs
    }
}

impl<I: InputPin, O: OutputPin> Board for PinBoard<I, O> {
    fn inputs(&mut self) -> u8 {
        self.inputs
            .iter_mut()
            .enumerate()
            .fold(0, |bits, (n, pin)| {
                if pin.is_high().unwrap_or(false) {
                    bits | 1 << n
                } else {
                    bits
                }
            })
    }

    fn set_outputs(&mut self, bits: u8) {
        for (n, pin) in self.outputs.iter_mut().enumerate() {
            let _ = if bits & (1 << n) != 0 {
                pin.set_high()
            } else {
                pin.set_low()
            };
        }
    }
}

/// The IO8's largest mailbox and process image, from its description.
const MBX: usize = io8_example::DEVICE.largest_mailbox();
const IMAGE: (usize, usize) = io8_example::DEVICE.largest_image();
/// The largest object an SDO transfer of the IO8 carries (its device
/// name, 0x1008, is the longest).
const SDO: usize = 128;

/// The IO8's firmware, its buffers sized from its description.
pub type Io8Slave<S, B, N> = Slave<Lan9252Spi<S>, Io8<B, N>, MBX, SDO, { IMAGE.0 }, { IMAGE.1 }>;

/// The IO8 firmware on a LAN9252 over SPI, with the chip's IRQ line.
pub struct Node<S: SpiDevice, Q: InputPin, B: Board, N: NvStorage = MemNv<STORAGE_SIZE>> {
    slave: Io8Slave<S, B, N>,
    irq: Q,
    schedule: PollSchedule,
    passes: u32,
}

impl<S: SpiDevice, Q: InputPin, B: Board, N: NvStorage> Node<S, Q, B, N> {
    /// Checks the chip (byte test, ready), programs its IRQ output (push-
    /// pull, active low, EtherCAT events) and starts the firmware in INIT.
    pub fn start(spi: S, irq: Q, board: B, nv: N) -> Result<(Self, ChipId), Lan9252Error> {
        let mut esc = Lan9252Spi::new(spi);
        let id = esc.init()?;
        esc.enable_irq(false, true)?;
        let node = Node {
            slave: Slave::with_buffers(esc, Io8::new(board, nv)),
            irq,
            schedule: PollSchedule::new(IDLE_POLL_NS),
            passes: 0,
        };
        Ok((node, id))
    }

    /// One turn of the main loop at time `now_ns`: a firmware pass when the
    /// IRQ line is asserted (an AL event waits: AL control, a mailbox or
    /// process-data SyncManager, the watchdog) or [`IDLE_POLL_NS`] has
    /// passed since the last one; else nothing, not even an SPI access.
    /// Returns whether the firmware ran. A PDI failure has already put the
    /// firmware in its safe state when it is returned.
    pub fn step(&mut self, now_ns: u64) -> Result<bool, EscError> {
        // The IRQ pin: an unreadable pin counts as asserted (poll rather
        // than miss an event).
        self.step_with(now_ns, None)
    }

    /// The bootloader's part of a power-on: decides which image slot runs
    /// ([`firmware::power_on`]), confirms a trial image (this firmware's
    /// start check is that it got this far) and sets 0x100A to its
    /// version. A blank store is first given the running firmware as its
    /// factory image (`version`, with a marker payload: the image the
    /// microcontroller executes is its own flash, not the store's copy).
    /// Returns the decision; a store that cannot be read keeps the device
    /// in the bootloader (INIT and BOOT only).
    pub fn boot(&mut self, images: &mut dyn ImageStore, version: &str) -> BootDecision {
        if images
            .read_state()
            .is_err_and(|e| e == firmware::StoreError::NoState)
            && let Some(v) = FirmwareVersion::new(version)
        {
            let _ = firmware::provision(images, v, FACTORY_MARKER);
        }
        let decision = firmware::power_on(images);
        let _ = firmware::confirm_boot(images);
        let v = decision.version;
        self.slave
            .set_firmware_version(if v == FirmwareVersion::EMPTY {
                version
            } else {
                v.as_str()
            });
        self.slave.set_no_valid_firmware(decision.slot.is_none());
        decision
    }

    /// [`Node::step`] with the FoE image store: FoE downloads in BOOT go
    /// there, BOOT → INIT commits them for the next [`Node::boot`].
    pub fn step_with(
        &mut self,
        now_ns: u64,
        images: Option<&mut dyn ImageStore>,
    ) -> Result<bool, EscError> {
        let asserted = self.irq.is_low().unwrap_or(true);
        if !self.schedule.due(asserted, now_ns) {
            return Ok(false);
        }
        self.passes = self.passes.wrapping_add(1);
        self.slave.poll_with(now_ns, images).map(|()| true)
    }

    /// Firmware passes so far (wrapping).
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// The firmware.
    pub fn slave(&self) -> &Io8Slave<S, B, N> {
        &self.slave
    }

    /// The firmware, mutably.
    pub fn slave_mut(&mut self) -> &mut Io8Slave<S, B, N> {
        &mut self.slave
    }
}

#[cfg(test)]
mod tests;
