//! The core's engine tested on the PAM's dictionary: these tests lived in
//! the core while the PAM was the core; they moved with the device and
//! check the same behaviour through the public core API.

#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod complete;
mod invariants;
mod params;
mod pdo;
mod sdo_info;
mod store;
