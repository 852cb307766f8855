//! # ecat-esc-spi-emu: byte-level SPI emulations of EtherCAT slave controllers
//!
//! Each emulation is an `embedded-hal` 1.0
//! [`SpiDevice`](embedded_hal::spi::SpiDevice) that decodes the bytes a
//! microcontroller clocks out as the chip's datasheet describes and turns
//! them into PDI accesses of the `ecat-slave` software ESC
//! ([`ecat_sim::esc::SoftEsc`]) behind it. A PDI driver under test
//! then talks to it exactly as to a chip, while a master drives the
//! software ESC's other side with real EtherCAT frames:
//!
//! - [`et1100`]: the Beckhoff ET1100/ET1200 SPI slave interface.
//! - [`lan9252`]: the Microchip LAN9252 SPI interface.
//!
//! Written from the datasheets' protocol tables (each rule cites its
//! section; see `docs/SPI-NOTES.md`), independently of the drivers in
//! `ecat-esc-spi`: this crate does not depend on them.
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

/// What an emulated chip counted on its SPI side, as a logic analyser on
/// the bus would (both emulations keep one).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    transactions: u64,
    bytes_clocked: u64,
    protocol_errors: u64,
    refused: u64,
}

impl Counters {
    /// SEL cycles (transactions) seen.
    pub fn transactions(&self) -> u64 {
        self.transactions
    }

    /// Bytes clocked over all SEL cycles.
    pub fn bytes_clocked(&self) -> u64 {
        self.bytes_clocked
    }

    /// SEL cycles that broke a protocol rule of the chip (see each
    /// emulation for its rules); at most one per cycle.
    pub fn protocol_errors(&self) -> u64 {
        self.protocol_errors
    }

    /// Accesses the software ESC refused (a mailbox not full on a read or
    /// full on a write, an address beyond its memory): the read delivered
    /// 0x00 bytes, the write was dropped, as a real chip carries on.
    pub fn refused_accesses(&self) -> u64 {
        self.refused
    }

    /// One SEL cycle of `bytes` bytes ended, malformed or not.
    pub(crate) fn cycle(&mut self, bytes: usize, malformed: bool) {
        self.transactions = self.transactions.saturating_add(1);
        self.bytes_clocked = self.bytes_clocked.saturating_add(bytes as u64);
        if malformed {
            self.protocol_errors = self.protocol_errors.saturating_add(1);
        }
    }

    /// The software ESC refused an access.
    pub(crate) fn refuse(&mut self) {
        self.refused = self.refused.saturating_add(1);
    }
}
