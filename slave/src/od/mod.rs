//! Object dictionary (layer 2): the one static description of every object
//! ([`model`]), its types ([`types`]) and the live values ([`store`]).
//!
//! The ESI, the SII, SDO Information, the PDO mapping and the application all
//! read [`model::OBJECTS`]; nothing about an object is written twice.

pub mod complete;
pub mod model;
pub mod store;
pub mod types;

pub use types::*;
