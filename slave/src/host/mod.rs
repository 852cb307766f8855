//! Host-side conveniences (feature `std`): pcap capture and the raw-socket
//! runner that puts software slaves on a real network interface.
//!
//! Nothing here is part of the `no_std` core; it drives [`crate::device`]
//! from a host operating system.

pub mod chain;
pub mod faults;
pub mod image_store;
pub mod pcap;
pub mod raw;
pub mod state_dir;
