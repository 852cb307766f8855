//! # ecat-esc-spi: SPI PDI drivers for real EtherCAT slave controllers
//!
//! Drivers that implement the `ecat-slave` core's PDI trait
//! ([`ecat_pdi::Esc`]) on an `embedded-hal` 1.0
//! [`SpiDevice`](embedded_hal::spi::SpiDevice), so a firmware built on the
//! core runs on a microcontroller next to a real ESC chip:
//!
//! - [`et1100`]: the Beckhoff ET1100/ET1200 SPI slave interface (also the
//!   ASIX AX58100 and the LAN9253 in "Beckhoff SPI" mode): 2- and 3-byte
//!   addressing, read with a wait-state byte, the AL event request
//!   returned in every address phase.
//! - [`lan9252`]: the Microchip LAN9252 SPI interface: instructions, ESC
//!   registers through ECAT_CSR_CMD/ECAT_CSR_DATA, process RAM through the
//!   read/write FIFOs, byte test, reset and ready checks.
//!
//! `#![no_std]`, no allocation. Protocol facts and their sources are in
//! `docs/SPI-NOTES.md` of the repository.
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

pub mod et1100;
pub mod lan9252;

use ecat_pdi::{BusErrorKind, EscError};

/// The kind of an SPI error, kept in [`EscError::Bus`] so the firmware
/// (and its diagnosis) knows what failed on the bus.
fn bus_kind(e: &impl embedded_hal::spi::Error) -> BusErrorKind {
    use embedded_hal::spi::ErrorKind;
    match e.kind() {
        ErrorKind::Overrun => BusErrorKind::Overrun,
        ErrorKind::ModeFault => BusErrorKind::ModeFault,
        ErrorKind::FrameFormat => BusErrorKind::FrameFormat,
        ErrorKind::ChipSelectFault => BusErrorKind::ChipSelectFault,
        _ => BusErrorKind::Other,
    }
}

/// Size of the ESC address space (16-bit addresses).
const MEMORY_SIZE: usize = 0x1_0000;

/// Rejects accesses past the 64 KB ESC address space (before any SPI
/// traffic).
fn check_range(addr: u16, len: usize) -> Result<(), EscError> {
    if usize::from(addr).saturating_add(len) > MEMORY_SIZE {
        Err(EscError::OutOfRange { addr, len })
    } else {
        Ok(())
    }
}
