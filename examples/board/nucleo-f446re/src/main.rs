//! # The IO8 firmware on a NUCLEO-F446RE with a LAN9252 shield
//!
//! `board-example`'s application and main loop on real hardware: an STM32
//! NUCLEO-F446RE (Cortex-M4F, 512 KiB flash) with a LAN9252 EtherCAT
//! shield on its Arduino header (AB&T EasyCAT, or Microchip's EVB-LAN9252
//! wired to the same pins), on `stm32f4xx-hal`.
//!
//! | signal | Arduino pin | STM32 |
//! |---|---|---|
//! | SPI1 SCK / MISO / MOSI | D13 / D12 / D11 | PA5 / PA6 / PA7 |
//! | LAN9252 chip select (SCS) | D9 | PC7 |
//! | LAN9252 IRQ (active low, push-pull) | D2 | PA10 (EXTI10) |
//! | IO8 outputs 1-8 | D3 D4 D5 D6 D7 D8 D10, CN10-1 | PB3 PB5 PB4 PB10 PA8 PA9 PB6 PC9 |
//! | IO8 inputs 1-8 (pull-down) | A0 A1 A2 A3 A4 A5, CN10-2, CN10-4 | PA0 PA1 PA4 PB0 PC1 PC0 PC8 PC6 |
//!
//! Main loop: a firmware pass when the LAN9252 asserts its IRQ (EXTI10
//! wakes the core) or 1 ms has passed (SysTick), then `wfi`. Parameters
//! (0x1010 "save") and FoE images live in the internal flash, each region
//! in sectors of its own (`memory.x`, [`LAYOUT`]).
#![no_std]
#![no_main]
#![deny(unsafe_code)]

use core::cell::RefCell;
use core::sync::atomic::{AtomicU32, Ordering};

use board_example::store::{FlashLayout, NorImageStore, NorNv};
use board_example::{Node, PinBoard};
use cortex_m::peripheral::SYST;
use cortex_m_rt::{entry, exception};
use critical_section::Mutex;
use embedded_hal::digital::{ErrorType, InputPin};
use embedded_hal_bus::spi::ExclusiveDevice;
use embedded_storage::nor_flash::{self, NorFlash, ReadNorFlash};
use stm32f4xx_hal::flash::{Error as FlashError, FlashExt};
use stm32f4xx_hal::gpio::{Edge, ErasedPin, Input, Output, PA10};
use stm32f4xx_hal::pac::{self, interrupt};
use stm32f4xx_hal::prelude::*;

/// The version this firmware reports in 0x100A when its image store is
/// blank (the IO8's factory version).
const FIRMWARE_VERSION: &str = "10";

/// Where parameters and FoE images go (offsets from 0x08000000; the
/// sector map is in `memory.x`).
const LAYOUT: FlashLayout = FlashLayout {
    erase_unit: 16 * 1024,
    params: [0x0_4000, 0x0_8000],
    params_len: 16 * 1024,
    state: [0x0_C000, 0x1_0000],
    state_len: 16 * 1024,
    slots: [0x4_0000, 0x6_0000],
    slot_len: 128 * 1024,
};
const _: () = assert!(LAYOUT.is_valid(512 * 1024));

/// The core clock.
const SYSCLK_HZ: u32 = 84_000_000;

/// The internal flash, shared by the image store and the parameters:
/// each operation unlocks it for its duration (the HAL locks it again
/// when its guard drops).
struct Flash<'a>(&'a RefCell<pac::FLASH>);

impl nor_flash::ErrorType for Flash<'_> {
    type Error = FlashError;
}

impl ReadNorFlash for Flash<'_> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        let flash = self.0.try_borrow().map_err(|_| FlashError::Operation)?;
        let start = offset as usize;
        let src = flash
            .read()
            .get(start..start + bytes.len())
            .ok_or(FlashError::ProgrammingSequence)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.0.try_borrow().map_or(0, |f| f.len())
    }
}

impl NorFlash for Flash<'_> {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = 128 * 1024;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        let mut flash = self.0.try_borrow_mut().map_err(|_| FlashError::Operation)?;
        NorFlash::erase(&mut flash.unlocked(), from, to)
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        let mut flash = self.0.try_borrow_mut().map_err(|_| FlashError::Operation)?;
        NorFlash::write(&mut flash.unlocked(), offset, bytes)
    }
}

/// The LAN9252's IRQ pin, shared with the EXTI handler that acknowledges
/// its edge.
static IRQ_PIN: Mutex<RefCell<Option<PA10<Input>>>> = Mutex::new(RefCell::new(None));

/// The IRQ line as the main loop reads it.
struct Irq;

impl ErrorType for Irq {
    type Error = core::convert::Infallible;
}

impl InputPin for Irq {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        self.is_low().map(|low| !low)
    }

    fn is_low(&mut self) -> Result<bool, Self::Error> {
        Ok(critical_section::with(|cs| {
            IRQ_PIN
                .borrow_ref_mut(cs)
                .as_mut()
                .is_none_or(|p| p.is_low().unwrap_or(true))
        }))
    }
}

#[interrupt]
fn EXTI15_10() {
    critical_section::with(|cs| {
        if let Some(p) = IRQ_PIN.borrow_ref_mut(cs).as_mut() {
            p.clear_interrupt_pending_bit();
        }
    });
}

/// Milliseconds since start (SysTick), low and high words.
static MS_LO: AtomicU32 = AtomicU32::new(0);
static MS_HI: AtomicU32 = AtomicU32::new(0);
const RELOAD: u32 = SYSCLK_HZ / 1000 - 1;

#[exception]
fn SysTick() {
    if MS_LO.fetch_add(1, Ordering::Relaxed) == u32::MAX {
        MS_HI.fetch_add(1, Ordering::Relaxed);
    }
}

/// Monotonic time in ns (SysTick milliseconds plus the counter's progress).
fn now_ns() -> u64 {
    loop {
        let (hi, lo) = (MS_HI.load(Ordering::Relaxed), MS_LO.load(Ordering::Relaxed));
        let current = SYST::get_current();
        if MS_LO.load(Ordering::Relaxed) == lo && MS_HI.load(Ordering::Relaxed) == hi {
            let ms = u64::from(hi) << 32 | u64::from(lo);
            let into = u64::from(RELOAD.saturating_sub(current));
            return ms * 1_000_000 + into * 1_000_000_000 / u64::from(SYSCLK_HZ);
        }
    }
}

#[entry]
fn main() -> ! {
    let (Some(dp), Some(mut cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        halt()
    };
    let rcc = dp.RCC.constrain();
    let clocks = rcc.cfgr.sysclk(SYSCLK_HZ.Hz()).freeze();
    cp.SYST
        .set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
    cp.SYST.set_reload(RELOAD);
    cp.SYST.clear_current();
    cp.SYST.enable_interrupt();
    cp.SYST.enable_counter();

    let (gpioa, gpiob, gpioc) = (dp.GPIOA.split(), dp.GPIOB.split(), dp.GPIOC.split());
    let bus = dp.SPI1.spi(
        (gpioa.pa5, gpioa.pa6, gpioa.pa7),
        embedded_hal::spi::MODE_0,
        8.MHz(),
        &clocks,
    );
    let Ok(spi) = ExclusiveDevice::new_no_delay(bus, gpioc.pc7.into_push_pull_output());

    // IRQ: falling edge of D2 wakes the core.
    let mut syscfg = dp.SYSCFG.constrain();
    let mut exti = dp.EXTI;
    let mut irq = gpioa.pa10.into_pull_up_input();
    irq.make_interrupt_source(&mut syscfg);
    irq.trigger_on_edge(&mut exti, Edge::Falling);
    irq.enable_interrupt(&mut exti);
    critical_section::with(|cs| IRQ_PIN.borrow_ref_mut(cs).replace(irq));
    enable_exti_interrupt();

    let inputs: [ErasedPin<Input>; 8] = [
        gpioa.pa0.into_pull_down_input().erase(),
        gpioa.pa1.into_pull_down_input().erase(),
        gpioa.pa4.into_pull_down_input().erase(),
        gpiob.pb0.into_pull_down_input().erase(),
        gpioc.pc1.into_pull_down_input().erase(),
        gpioc.pc0.into_pull_down_input().erase(),
        gpioc.pc8.into_pull_down_input().erase(),
        gpioc.pc6.into_pull_down_input().erase(),
    ];
    let outputs: [ErasedPin<Output>; 8] = [
        gpiob.pb3.into_push_pull_output().erase(),
        gpiob.pb5.into_push_pull_output().erase(),
        gpiob.pb4.into_push_pull_output().erase(),
        gpiob.pb10.into_push_pull_output().erase(),
        gpioa.pa8.into_push_pull_output().erase(),
        gpioa.pa9.into_push_pull_output().erase(),
        gpiob.pb6.into_push_pull_output().erase(),
        gpioc.pc9.into_push_pull_output().erase(),
    ];
    let board = PinBoard::new(inputs, outputs);

    let flash = RefCell::new(dp.FLASH);
    let nv = NorNv::new(Flash(&flash), &LAYOUT);
    let Some(mut images) = NorImageStore::new(Flash(&flash), LAYOUT) else {
        halt()
    };
    let Ok((mut node, _chip)) = Node::start(spi, Irq, board, nv) else {
        halt()
    };
    node.boot(&mut images, FIRMWARE_VERSION);

    loop {
        // A PDI failure has already put the firmware in its safe state.
        let _ = node.step_with(now_ns(), Some(&mut images));
        // Sleep until the IRQ edge or the next millisecond; an edge that
        // came during the pass has left its interrupt pending, so wfi
        // returns at once.
        cortex_m::asm::wfi();
    }
}

#[allow(unsafe_code)]
fn enable_exti_interrupt() {
    // SAFETY: unmasking can break a critical section that relies on the
    // line being masked; the only data the handler touches is IRQ_PIN,
    // always reached inside `critical_section::with`.
    unsafe { cortex_m::peripheral::NVIC::unmask(pac::Interrupt::EXTI15_10) };
}

/// Stops: outputs stay as the last pass left them off (a halt before the
/// firmware runs leaves every output at its reset state, low).
fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo<'_>) -> ! {
    halt()
}
