//! EtherCAT Slave Controller: the PDI contract.
//!
//! [`Esc`] is the PDI side of an ESC: what firmware sees (read and write
//! ESC memory; events appear in the AL event request register). A hardware
//! ESC (an ET1100 or a LAN9252 over SPI, `ecat-esc-spi`) implements it in
//! a driver; the software ESC of `ecat-sim` implements it too and also
//! processes EtherCAT frames itself. The trait, its error and the register
//! map live in the dependency-free `ecat-pdi` crate, re-exported here. This
//! layer knows nothing of CoE or the object dictionary.

pub use ecat_pdi::{BusErrorKind, Esc, EscError, registers};
