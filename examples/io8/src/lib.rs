//! # IO8: the smallest complete device on the `ecat-slave` core
//!
//! An 8-channel digital I/O module: eight inputs (0x6000, TxPDO 0x1A00)
//! with a debounce filter, eight outputs (0x7000, RxPDO 0x1600) that are
//! off unless the device is in OP, one stored parameter (0x8000:01 "Input
//! filter", saved by 0x1010:01 = "save"), SDO Information, complete access
//! and FoE firmware update in BOOT. It uses only the public API of
//! `ecat-slave` and is written as a template for your own device; the
//! [`guide`] walks through it step by step.
//!
//! * [`description`]: what the device is ([`DEVICE`], [`OBJECTS`]).
//! * [`board`]: its hardware ([`Board`], [`SimBoard`]).
//! * [`app`]: what it does ([`Io8`], the [`Application`](ecat_slave::device::Application)).
//!
//! Layers: `app` → `board`, `description`
//!
//! ```
//! use ecat_slave::al::AlState;
//!
//! // On the software ESC of ecat-sim (on a board: `Slave::new(esc, Io8::default())`).
//! let slave = ecat_sim::SoftSlave::new(io8_example::Io8::default());
//! assert_eq!(slave.slave().al_status().state, AlState::Init);
//! assert_eq!(slave.slave().od().get(0x8000, 1), Some(10), "filter 10 ms");
//! ```
#![cfg_attr(not(any(test, feature = "std")), no_std)]
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

pub mod app;
pub mod board;
pub mod description;

pub use app::{Debounce, Io8};
pub use board::{Board, SimBoard};
pub use description::{DEVICE, DICT, ENTRIES, OBJECTS};

#[doc = include_str!("../WRITE-YOUR-OWN-DEVICE.md")]
pub mod guide {}

#[cfg(test)]
mod tests;
