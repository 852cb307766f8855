//! # servo402: a CiA 402 servo drive on the `ecat-slave` core
//!
//! The template for a drive: one axis in the CiA 402 drive profile
//! (`ecat-cia402`): the power drive system state machine on controlword
//! 0x6040 / statusword 0x6041 with quick stop and faults, the modes CSP,
//! CSV, CST (DC-synchronous on SYNC0 or free run), PP, PV and homing on
//! the current position, following-error monitoring, and the fixed PDOs a
//! typical drive maps (0x1600: controlword, target position, velocity,
//! torque, mode; 0x1A00: statusword, position, velocity, torque, mode
//! display, following error, error code). It uses only the public API of
//! `ecat-slave` and `ecat-cia402`; the [`guide`] walks through it.
//!
//! * [`description`]: what the device is ([`DEVICE`], [`OBJECTS`]).
//! * [`board`]: its hardware ([`Board`]: the axis with its power stage;
//!   [`SimBoard`]).
//! * [`app`]: what it does ([`Servo402`], the
//!   [`Application`](ecat_slave::device::Application)).
//!
//! ```
//! use ecat_slave::al::AlState;
//!
//! let slave = ecat_sim::SoftSlave::new(servo402_example::Servo402::default());
//! assert_eq!(slave.slave().al_status().state, AlState::Init);
//! assert_eq!(slave.slave().od().get(0x6502, 0), Some(0x3A5), "PP PV HM CSP CSV CST");
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

pub use app::Servo402;
pub use board::{Board, SimBoard};
pub use description::{DEVICE, DICT, ENTRIES, OBJECTS};

#[doc = include_str!("../WRITE-YOUR-OWN-DRIVE.md")]
pub mod guide {}

#[cfg(test)]
mod tests;
