//! # ecat-sim: the EtherCAT simulator around the ecat-slave core
//!
//! What a firmware does not link, and what makes the core's devices run
//! without hardware: a software EtherCAT Slave Controller ([`esc::SoftEsc`])
//! that processes real EtherCAT frames (all 14 datagram commands, FMMUs,
//! SyncManagers, the SII EEPROM interface, SM and PDI watchdogs) with a
//! Distributed Clocks unit ([`esc::dc`]), software slaves ([`SoftSlave`]: a
//! device's firmware loop on that ESC, directly or through an emulated
//! chip interface, [`SoftPdi`]), lines of them ([`chain`]), the raw-socket
//! runner that serves a line on a network interface ([`raw`]), a
//! fault-injecting wire ([`faults`]), pcap capture ([`pcap`]), durable
//! per-slave state ([`state_dir`], [`file_store`]) and an in-memory image
//! store ([`image_store`]).
//!
//! The firmware core, [`ecat_slave`], knows none of this: it reaches any
//! ESC through its PDI trait ([`ecat_slave::esc::Esc`]), which the
//! software ESC implements like a chip driver does.
//!
//! Layers: `raw` → `chain`, `faults`, `pcap`, `state_dir`, `file_store` →
//! `slave`, `image_store` → `esc`
#![forbid(unsafe_code)]

pub mod chain;
pub mod esc;
pub mod faults;
pub mod file_store;
pub mod image_store;
pub mod pcap;
pub mod raw;
pub mod slave;
pub mod state_dir;
#[cfg(test)]
mod testing;

pub use esc::{FrameOutcome, SoftEsc};
pub use slave::{SoftPdi, SoftSlave, SpiStats};
