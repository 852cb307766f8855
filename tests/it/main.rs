//! Integration tests: the ethercrab master drives software PAM-199-P-ETC
//! slaves over the virtual link, with real EtherCAT frames. One test binary;
//! each area of the product is a module.

mod amplifier;
mod bring_up;
mod capture;
mod cli;
mod coe;
mod common;
mod conformance;
mod consistency;
mod dc;
mod dma22;
mod failsafe;
mod faults;
mod foe;
mod forward;
mod generic_core;
mod layers;
mod long_line;
mod mixed_line;
mod power_cut;
mod qemu;
mod replay;
mod safety;
mod sdo;
mod servo402;
mod shared;
mod sii;
mod soem;
mod spi_pdi;
mod state;
mod twins;
mod veth;
