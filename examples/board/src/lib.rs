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
//! ## Building for the board
//!
//! This crate is the board-independent part. A board binary adds the HAL
//! and the runtime (not built in CI, which has no ARM toolchain):
//!
//! ```text
//! rustup target add thumbv7em-none-eabihf
//! cargo new --bin nucleo-io8 && cd nucleo-io8
//! cargo add board-example --path ../examples/board
//! cargo add stm32f4xx-hal --features stm32f401 cortex-m-rt panic-halt
//! cargo add embedded-hal-bus                 # ExclusiveDevice: SpiBus + CS pin -> SpiDevice
//! # memory.x for the F401RE: FLASH 512K at 0x08000000, RAM 96K at 0x20000000
//! cargo build --release --target thumbv7em-none-eabihf
//! ```
//!
//! and its `main` (the shape of it; pin and clock names from
//! `stm32f4xx-hal` 0.2x):
//!
//! ```text
//! #[entry]
//! fn main() -> ! {
//!     let dp = pac::Peripherals::take().unwrap();
//!     let clocks = dp.RCC.constrain().cfgr.sysclk(84.MHz()).freeze();
//!     let (gpioa, gpioc) = (dp.GPIOA.split(), dp.GPIOC.split());
//!     let bus = dp.SPI1.spi((gpioa.pa5, gpioa.pa6, gpioa.pa7), spi::MODE_0, 8.MHz(), &clocks);
//!     let spi = ExclusiveDevice::new(bus, gpioc.pc7.into_push_pull_output(), delay).unwrap();
//!     let irq = gpioa.pa10.into_pull_up_input();
//!     let board = PinBoard::new(inputs, outputs);          // [ErasedPin<Input>; 8], [ErasedPin<Output>; 8]
//!     let mut node = Node::start(spi, irq, board, FlashNv::new(dp.FLASH)).unwrap();
//!     loop {
//!         let _ = node.step(monotonic_ns());              // a 64-bit timer in ns
//!     }
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

use ecat_esc_spi::lan9252::{ChipId, Lan9252Error, Lan9252Spi};
use ecat_slave::device::{PollSchedule, Slave};
use ecat_slave::esc::EscError;
use ecat_slave::hal::{MemNv, NvStorage};
use ecat_slave::params::STORAGE_SIZE;
use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::spi::SpiDevice;
use io8_example::{Board, Io8};

/// Longest time between two passes of the firmware when the IRQ line stays
/// quiet: the application's timers (the IO8's input filter) and the
/// firmware's watchdog checks run at least this often.
pub const IDLE_POLL_NS: u64 = 1_000_000;

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

/// The IO8 firmware on a LAN9252 over SPI, with the chip's IRQ line.
pub struct Node<S: SpiDevice, Q: InputPin, B: Board, N: NvStorage = MemNv<STORAGE_SIZE>> {
    slave: Slave<Lan9252Spi<S>, Io8<B, N>>,
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
            slave: Slave::new(esc, Io8::new(board, nv)),
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
        let asserted = self.irq.is_low().unwrap_or(true);
        if !self.schedule.due(asserted, now_ns) {
            return Ok(false);
        }
        self.passes = self.passes.wrapping_add(1);
        self.slave.poll(now_ns).map(|()| true)
    }

    /// Firmware passes so far (wrapping).
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// The firmware.
    pub fn slave(&self) -> &Slave<Lan9252Spi<S>, Io8<B, N>> {
        &self.slave
    }

    /// The firmware, mutably.
    pub fn slave_mut(&mut self) -> &mut Slave<Lan9252Spi<S>, Io8<B, N>> {
        &mut self.slave
    }
}

#[cfg(test)]
mod tests;
