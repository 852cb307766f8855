//! EtherCAT Slave Controller.
//!
//! [`Esc`] is the PDI side of an ESC: what firmware sees (read and write
//! ESC memory; events appear in the AL event request register). The software
//! implementation [`soft::SoftEsc`] also processes EtherCAT frames itself; a
//! hardware ESC (e.g. a LAN9252 over SPI) implements the same trait in board
//! support code. This layer knows nothing of CoE, the object dictionary or
//! the amplifier.

pub mod dc;
pub mod soft;

pub use ecat_pdi::{BusErrorKind, Esc, EscError, registers};
