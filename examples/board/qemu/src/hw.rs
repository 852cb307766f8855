//! The few peripherals of the mps2-an386 the firmware uses: two CMSDK APB
//! UARTs (ARM DDI 0479 "Cortex-M System Design Kit", APB UART: DATA 0x00,
//! STATE 0x04, CTRL 0x08, INTSTATUS/INTCLEAR 0x0C, BAUDDIV 0x10) and the
//! SysTick timer as the monotonic clock (the core clock is 25 MHz,
//! ARM AN386 §3).
//!
//! The machine has no peripheral access crate, so the UART registers are
//! reached with volatile accesses through raw addresses: the only
//! `unsafe` of the firmware, here and in `main.rs`'s interrupt setup.
#![allow(unsafe_code)]

use core::sync::atomic::{AtomicU32, Ordering};

use board_example::link::Serial;
use cortex_m::peripheral::SYST;

/// UART0: the link to the bridge (SPI bus and flash).
pub const UART0: usize = 0x4000_4000;
/// UART1: the console (boot message, measurement markers).
pub const UART1: usize = 0x4000_5000;
/// The NVIC line of UART0's receive interrupt (AN386 interrupt map).
pub const UART0_RX_IRQ: u16 = 0;

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTCLEAR: usize = 0x0C;
const BAUDDIV: usize = 0x10;

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_RX_INT_EN: u32 = 1 << 3;
const INT_RX: u32 = 1 << 1;

fn read(addr: usize) -> u32 {
    // SAFETY: `addr` is one of the CMSDK UART registers above, at a fixed,
    // always-mapped, 4-byte aligned device address of the AN386 memory
    // map; no Rust object lives there, a read has no side effect beyond
    // the device's own (DATA hands over the received byte).
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

fn write(addr: usize, value: u32) {
    // SAFETY: as in `read`; writing a UART register only affects the
    // device.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

/// A CMSDK APB UART, polled; its receive interrupt only wakes the core.
pub struct Uart {
    base: usize,
}

impl Uart {
    /// Enables transmitter and receiver of the UART at `base`. QEMU does
    /// not model the baud rate; BAUDDIV gets the smallest legal value.
    pub fn new(base: usize) -> Self {
        write(base + BAUDDIV, 16);
        write(base + CTRL, CTRL_TX_EN | CTRL_RX_EN);
        Uart { base }
    }

    /// Writes text (the console).
    pub fn write_str(&mut self, s: &str) {
        for b in s.bytes() {
            self.write(b);
        }
    }

    /// Writes `v` in decimal (the console; no `core::fmt`).
    pub fn write_u32(&mut self, mut v: u32) {
        let mut digits = [0u8; 10];
        let mut n = 0;
        loop {
            if let Some(d) = digits.get_mut(n) {
                *d = b'0' + (v % 10) as u8;
            }
            n += 1;
            v /= 10;
            if v == 0 || n == digits.len() {
                break;
            }
        }
        for d in digits.iter().take(n).rev() {
            self.write(*d);
        }
    }

    /// Whether a received byte waits.
    pub fn rx_waiting(&self) -> bool {
        read(self.base + STATE) & STATE_RX_FULL != 0
    }

    /// Asks for an interrupt at the next received byte (the handler
    /// [`Uart::rx_interrupt_taken`] turns it off again).
    pub fn arm_rx_interrupt(&mut self) {
        write(self.base + CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT_EN);
    }

    /// The receive interrupt's handler: off again and acknowledged; the
    /// byte stays in DATA for the main loop.
    pub fn rx_interrupt_taken(base: usize) {
        write(base + CTRL, CTRL_TX_EN | CTRL_RX_EN);
        write(base + INTCLEAR, INT_RX);
    }
}

impl Serial for Uart {
    fn write(&mut self, byte: u8) {
        while read(self.base + STATE) & STATE_TX_FULL != 0 {}
        write(self.base + DATA, u32::from(byte));
    }

    fn read(&mut self) -> Option<u8> {
        self.rx_waiting()
            .then(|| (read(self.base + DATA) & 0xFF) as u8)
    }

    fn wait(&mut self) {
        // Sleep until the byte arrives (or the next tick): polling the
        // UART in a tight loop would keep QEMU's device lock busy and
        // slow the byte down.
        self.arm_rx_interrupt();
        if !self.rx_waiting() {
            cortex_m::asm::wfi();
        }
    }
}

/// SysTick reload for 1 ms at 25 MHz.
const RELOAD: u32 = 25_000 - 1;
/// Nanoseconds per SysTick count at 25 MHz.
const NS_PER_COUNT: u64 = 40;

/// Milliseconds since start, low and high words (the SysTick handler
/// counts).
static MS_LO: AtomicU32 = AtomicU32::new(0);
static MS_HI: AtomicU32 = AtomicU32::new(0);

/// Starts SysTick: an interrupt every millisecond.
pub fn start_clock(mut syst: SYST) {
    syst.set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// The SysTick handler's work: one more millisecond.
pub fn tick() {
    if MS_LO.fetch_add(1, Ordering::Relaxed) == u32::MAX {
        MS_HI.fetch_add(1, Ordering::Relaxed);
    }
}

/// Monotonic time in ns: the milliseconds counted plus the SysTick
/// counter's progress in the current one (40 ns resolution).
pub fn now_ns() -> u64 {
    loop {
        let (hi, lo) = (MS_HI.load(Ordering::Relaxed), MS_LO.load(Ordering::Relaxed));
        let current = SYST::get_current();
        if MS_LO.load(Ordering::Relaxed) == lo && MS_HI.load(Ordering::Relaxed) == hi {
            let ms = u64::from(hi) << 32 | u64::from(lo);
            let into = u64::from(RELOAD.saturating_sub(current));
            return ms * 1_000_000 + into * NS_PER_COUNT;
        }
    }
}
