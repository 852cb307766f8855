//! # ecat-esc-spi-emu: byte-level SPI emulations of EtherCAT slave controllers
//!
//! Each emulation is an `embedded-hal` 1.0
//! [`SpiDevice`](embedded_hal::spi::SpiDevice) that decodes the bytes a
//! microcontroller clocks out as the chip's datasheet describes and turns
//! them into PDI accesses of the `ecat-slave` software ESC
//! ([`ecat_slave::esc::soft::SoftEsc`]) behind it. A PDI driver under test
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
