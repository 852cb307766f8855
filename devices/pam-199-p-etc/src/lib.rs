//! # pam-199-p-etc: the W.E.St. PAM-199-P-ETC valve amplifier on the core
//!
//! One device on [`ecat_slave`], in the IO8 example's layout:
//!
//! * [`description`]: what it is, described once ([`DEVICE`], the object
//!   dictionary [`od`] of manual chapter 6);
//! * [`board`]: its hardware, the solenoid [`PowerStage`] (and
//!   [`SimPowerStage`], the simulated one with fault injection);
//! * [`app`]: what it does ([`Pam`]: the amplifier task, the 0xF801
//!   commands, the vendor password, FUNCTION selecting the PDO set,
//!   parameter storage, diagnosis emergencies);
//! * `invariants` (feature `invariants`): the safety rules of
//!   docs/SAFETY.md checked after every step of random master sessions.
//!
//! `#![no_std]` without its `std` feature.
//!
//! Layers: `invariants` → `app` → `board` → `description`
//!
//! ```
//! use ecat_sim::SoftSlave;
//! use pam_199_p_etc::Pam;
//! let mut slave = SoftSlave::new(Pam::default());
//! slave.poll(0).unwrap();
//! assert_eq!(slave.slave().od().get(0x1018, 2), Some(0x00C7_03F3));
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
#[cfg(any(test, feature = "invariants"))]
pub mod invariants;
#[cfg(test)]
mod tests;

pub use app::{COMMAND_ACK, COMMAND_ACK_NS, Pam, SAVE_MIN_INTERVAL_NS, VENDOR_PASSWORD};
pub use board::{PowerStage, SimPowerStage};
pub use description::{
    DEVICE, DEVICE_NAME, DIRECTIONAL_MAPPING, INDEPENDENT_MAPPING, PRODUCT_CODE, REVISION,
    VENDOR_ID, function_set, od,
};

/// The PAM's live object dictionary (sized for [`od::DICT`]).
pub type Store = ecat_slave::od::ObjectStore<[i64; od::ENTRY_COUNT]>;

/// A store of the PAM's dictionary at its defaults.
pub fn store() -> Store {
    Store::new(&od::DICT)
}
