//! # ecat-slave: an EtherCAT SubDevice (slave) stack core
//!
//! A `#![no_std]`, heap-free EtherCAT slave core that names no device:
//! what a firmware links. It reaches its EtherCAT Slave Controller through
//! the PDI trait [`Esc`] (a chip over SPI with `ecat-esc-spi`, or the
//! software ESC of `ecat-sim`, which also holds lines of software slaves
//! and the raw-socket runner). It holds the AL state machine ([`al`]) and
//! the handling of the SyncManager and PDI watchdogs, the mailbox
//! ([`mailbox`]) with CoE ([`coe`]: SDO, complete access, SDO Information,
//! Emergency) and FoE firmware update ([`foe`], [`firmware`]), the PDO
//! engine ([`pdo`]), the object dictionary engine ([`od`]), the SII encoder
//! and reader ([`sii`]), parameter storage ([`params`]), LEDs ([`led`]).
//!
//! A device is one static description plus one application trait
//! ([`device`]); see `examples/io8/WRITE-YOUR-OWN-DEVICE.md`.
//!
//! Byte formats live in [`wire`] and carry no state. The modules form
//! layers; a module uses only modules of layers below its own (the test
//! `tests/it/layers.rs` reads this list and every `crate::` path):
//!
//! Layers: `device` → `mailbox` → `foe`, `coe` → `params`, `pdo` →
//! `od` → `led`, `firmware` → `al` → `esc` → `sii` → `hal` → `wire`,
//! `limits`, `text` → `codes`
#![cfg_attr(not(any(test, feature = "std", feature = "testing")), no_std)]
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

pub mod al;
mod codes;
pub mod coe;
pub mod device;
pub mod esc;
pub mod firmware;
pub mod foe;
pub mod hal;
pub mod led;
mod limits;
pub mod mailbox;
pub mod od;
pub mod params;
pub mod pdo;
pub mod sii;
#[cfg(any(test, feature = "testing"))]
#[doc(hidden)]
pub mod testing;
pub mod text;
pub mod wire;

// What most users name, at the crate root (ethercrab-style): a device is
// a description and an application, run by `Slave` on an `Esc`.
pub use al::{AlState, AlStatusCode};
#[doc(alias = "SubDevice")]
#[doc(alias = "firmware loop")]
pub use device::Slave;
pub use device::{Application, DeviceDescription, Tick};
#[doc(alias = "ESC")]
#[doc(alias = "PDI")]
pub use esc::{Esc, EscError};
#[doc(alias = "object dictionary")]
pub use od::{Dictionary, Object, Od};
#[doc(alias = "abort code")]
pub use wire::coe::SdoAbortCode;
