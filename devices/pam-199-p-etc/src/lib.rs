//! # pam-199-p-etc: the W.E.St. PAM-199-P-ETC valve amplifier on the core
//!
//! One device on [`ecat_slave`]: its object dictionary ([`od`], manual
//! chapter 6), its description ([`DEVICE`]) and its application ([`Pam`]:
//! the amplifier task of [`app`], the 0xF801 commands, the vendor password,
//! FUNCTION selecting the PDO set, parameter storage, diagnosis
//! emergencies). `#![no_std]` without its `std` feature.
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
mod device;
pub mod diagnosis;
#[cfg(any(test, feature = "invariants"))]
pub mod invariants;
pub mod od;
#[cfg(test)]
mod tests;

pub use device::{
    COMMAND_ACK, COMMAND_ACK_NS, DEVICE, DEVICE_NAME, DIRECTIONAL_MAPPING, INDEPENDENT_MAPPING,
    PRODUCT_CODE, Pam, REVISION, SAVE_MIN_INTERVAL_NS, VENDOR_ID, VENDOR_PASSWORD, function_set,
};

/// The PAM's live object dictionary (sized for [`od::DICT`]).
pub type Store = ecat_slave::od::ObjectStore<[i64; od::ENTRY_COUNT]>;

/// A store of the PAM's dictionary at its defaults.
pub fn store() -> Store {
    Store::new(&od::DICT)
}
