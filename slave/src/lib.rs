//! # pam-slave: an EtherCAT SubDevice stack realising the PAM-199-P-ETC
//!
//! A `#![no_std]`, heap-free EtherCAT slave core: the PAM-199-P-ETC object
//! dictionary ([`od`]), the CoE mailbox servers ([`coe`], [`mailbox`]), the AL
//! state machine ([`al`]), PDO mapping ([`pdo`]), the SII image ([`sii`]) and a
//! software EtherCAT Slave Controller ([`esc::soft`]) that processes real
//! EtherCAT frames. [`device::Slave`] ties them together into one device.
//!
//! Layers (top depends on bottom only): `device` → `od` → `coe`/`mailbox` →
//! `al`/`pdo` → `esc` → `hal`; byte formats live in [`wire`] and carry no
//! state.
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

pub mod al;
pub mod app;
pub mod coe;
pub mod device;
pub mod esc;
pub mod firmware;
pub mod foe;
pub mod hal;
#[cfg(feature = "std")]
pub mod host;
pub mod led;
pub mod mailbox;
pub mod od;
pub mod params;
pub mod pdo;
pub mod sii;
pub mod wire;
