//! # The IO8 firmware on QEMU's mps2-an386
//!
//! The board's firmware (`board-example`: [`Node`], the IO8, the unchanged
//! LAN9252 driver, the core) on an emulated Cortex-M4. Only the transport
//! differs from the NUCLEO-F446RE binary: the SPI bus of the LAN9252 and
//! the flash holding the FoE images and the parameters are carried over
//! UART0 to `board-bridge` on the host ([`board_example::link`]), which
//! answers them with the LAN9252 emulation in front of a software ESC
//! that a master drives over a network interface. The chip's IRQ line
//! comes back as notices on the same UART.
//!
//! Main loop: a firmware pass when the IRQ line is asserted or 1 ms has
//! passed, then sleep (`wfi`) until an interrupt: a byte from the bridge
//! (an IRQ notice) or the 1 ms SysTick.
//!
//! The IO8's eight outputs are looped back to its eight inputs (a test
//! jig): a master sees what it wrote come back through the input filter.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod hw;

use core::cell::RefCell;

use board_example::Node;
use board_example::link::{FLASH_SECTOR, Link, LinkFlash, LinkIrq, LinkSpi};
use board_example::store::{FlashLayout, NorImageStore, NorNv};
use cortex_m_rt::{entry, exception};
use hw::Uart;

/// The version this firmware reports in 0x100A when its image store is
/// blank (the IO8's factory version).
const FIRMWARE_VERSION: &str = "10";

/// The bridge's flash: two image slots of 128 KiB, two boot-record
/// copies and two parameter slots in sectors of their own.
const LAYOUT: FlashLayout = FlashLayout {
    erase_unit: FLASH_SECTOR,
    slots: [0, 0x2_0000],
    slot_len: 0x2_0000,
    state: [0x4_0000, 0x4_0000 + FLASH_SECTOR],
    state_len: FLASH_SECTOR,
    params: [0x4_0000 + 2 * FLASH_SECTOR, 0x4_0000 + 3 * FLASH_SECTOR],
    params_len: FLASH_SECTOR,
};
/// Flash the firmware uses.
const FLASH_SIZE: u32 = 0x4_0000 + 4 * FLASH_SECTOR;
const _: () = assert!(LAYOUT.is_valid(FLASH_SIZE));

/// The IO8's outputs looped back to its inputs.
#[derive(Debug, Default)]
struct LoopbackBoard {
    levels: u8,
}

impl io8_example::Board for LoopbackBoard {
    fn inputs(&mut self) -> u8 {
        self.levels
    }

    fn set_outputs(&mut self, bits: u8) {
        self.levels = bits;
    }
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        halt("peripherals taken twice")
    };
    hw::start_clock(cp.SYST);
    let mut console = Uart::new(hw::UART1);
    let link = RefCell::new(Link::new(Uart::new(hw::UART0), hw::now_ns));
    enable_uart0_rx_interrupt();

    let nv = NorNv::new(LinkFlash::new(&link, FLASH_SIZE), &LAYOUT);
    let Some(mut images) = NorImageStore::new(LinkFlash::new(&link, FLASH_SIZE), LAYOUT) else {
        halt("flash layout")
    };
    let board = LoopbackBoard::default();
    let (mut node, chip) = match Node::start(LinkSpi::new(&link), LinkIrq::new(&link), board, nv) {
        Ok(x) => x,
        Err(_) => halt("no LAN9252 on the link"),
    };
    let decision = node.boot(&mut images, FIRMWARE_VERSION);
    console.write_str("board-qemu: IO8 on LAN9252 rev ");
    console.write_u32(u32::from(chip.revision));
    console.write_str(", firmware ");
    console.write_str(node.slave().firmware_version().as_str());
    console.write_str(match decision.slot {
        Some(ecat_slave::firmware::Slot::A) => " from slot A\n",
        Some(ecat_slave::firmware::Slot::B) => " from slot B\n",
        None => ", no valid image\n",
    });

    loop {
        #[cfg(feature = "measure")]
        measure::before(&link);
        let _ran = node.step_with(hw::now_ns(), Some(&mut images));
        #[cfg(feature = "measure")]
        measure::after(
            &link,
            _ran.unwrap_or(false),
            node.slave().al_status().state == ecat_slave::al::AlState::Op,
        );
        // Sleep until the next interrupt unless a notice already waits.
        let waiting = link.try_borrow_mut().map_or(true, |mut l| {
            l.serial_mut().arm_rx_interrupt();
            l.serial_mut().rx_waiting()
        });
        if !waiting {
            cortex_m::asm::wfi();
        }
    }
}

/// Stops with a message on the console.
fn halt(why: &str) -> ! {
    let mut console = Uart::new(hw::UART1);
    console.write_str("board-qemu: halted: ");
    console.write_str(why);
    console.write_str("\n");
    loop {
        cortex_m::asm::wfi();
    }
}

/// UART0's receive interrupt as an NVIC line.
#[derive(Clone, Copy)]
struct Uart0Rx;

// SAFETY: `number` returns the AN386's interrupt number of UART0 RX, a
// valid NVIC line of the machine (what the trait requires).
#[allow(unsafe_code)]
unsafe impl cortex_m::interrupt::InterruptNumber for Uart0Rx {
    fn number(self) -> u16 {
        hw::UART0_RX_IRQ
    }
}

#[allow(unsafe_code)]
fn enable_uart0_rx_interrupt() {
    // SAFETY: unmasking can break a critical section that relies on the
    // line being masked; this firmware has none (its handler only turns
    // the UART's interrupt off and acknowledges it, sharing no data).
    unsafe { cortex_m::peripheral::NVIC::unmask(Uart0Rx) };
}

#[exception]
fn SysTick() {
    hw::tick();
}

// The table of device interrupts is cortex-m-rt's default (every line to
// DefaultHandler): the only one enabled is UART0 RX.
#[allow(unsafe_code)]
#[exception]
unsafe fn DefaultHandler(_irqn: i16) {
    Uart::rx_interrupt_taken(hw::UART0);
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo<'_>) -> ! {
    halt("panic")
}

/// Markers for the instruction counts (feature `measure`): empty
/// functions that are never inlined, so that a QEMU TCG plugin counting
/// executed instructions (`tools/insn-count.c`) sees where a firmware pass
/// starts and ends, and of which kind it was: a pass in OP with the
/// process data exchanged, a pass that served the mailbox, or an idle one
/// (judged by the SPI transactions it made and the AL state). Their
/// bodies differ (1 to 5 `nop`s) so that the linker does not fold them.
#[cfg(feature = "measure")]
#[allow(unsafe_code)] // `no_mangle`: the plugin finds the markers by name.
mod measure {
    use core::cell::RefCell;

    use board_example::link::{Link, Serial};

    use core::sync::atomic::{AtomicU32, Ordering};

    /// SPI transactions before the pass.
    static SPI_BEFORE: AtomicU32 = AtomicU32::new(0);

    #[inline(never)]
    #[unsafe(no_mangle)]
    pub extern "C" fn measure_begin() {
        for _ in 0..1 {
            cortex_m::asm::nop();
        }
    }
    #[inline(never)]
    #[unsafe(no_mangle)]
    pub extern "C" fn measure_end_idle() {
        for _ in 0..2 {
            cortex_m::asm::nop();
        }
    }
    #[inline(never)]
    #[unsafe(no_mangle)]
    pub extern "C" fn measure_end_op() {
        for _ in 0..3 {
            cortex_m::asm::nop();
        }
    }
    #[inline(never)]
    #[unsafe(no_mangle)]
    pub extern "C" fn measure_end_mailbox() {
        for _ in 0..4 {
            cortex_m::asm::nop();
        }
    }
    #[inline(never)]
    #[unsafe(no_mangle)]
    pub extern "C" fn measure_end_other() {
        for _ in 0..5 {
            cortex_m::asm::nop();
        }
    }

    fn spi<S: Serial>(link: &RefCell<Link<S>>) -> u32 {
        link.try_borrow().map_or(0, |l| l.stats().spi)
    }

    pub fn before<S: Serial>(link: &RefCell<Link<S>>) {
        SPI_BEFORE.store(spi(link), Ordering::Relaxed);
        measure_begin();
    }

    pub fn after<S: Serial>(link: &RefCell<Link<S>>, ran: bool, op: bool) {
        let n = spi(link).wrapping_sub(SPI_BEFORE.load(Ordering::Relaxed));
        match (ran, op, n) {
            (false, _, _) => {}
            (true, false, 0..=3) | (true, true, 0..=9) => measure_end_idle(),
            (true, true, 10..=15) => measure_end_op(),
            (true, _, 16..) => measure_end_mailbox(),
            _ => measure_end_other(),
        }
    }
}
