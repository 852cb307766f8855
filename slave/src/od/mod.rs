//! Object dictionary: the engine, not the objects.
//!
//! A device describes its objects once, as a [`Dictionary`] of [`Object`]s
//! built with the `const` constructors of [`build`] and checked by
//! [`Dictionary::validate`]. [`store::ObjectStore`] holds the live values;
//! [`complete`] does complete access. The ESI, the SII, SDO Information,
//! the PDO engine and the application all read the one description.
//!
//! Layers: `complete`, `modules` → `build` → `store` → `dictionary` →
//! `sub_names`, `bits`, `types`

pub mod bits;
pub mod build;
pub mod complete;
pub mod dictionary;
pub mod modules;
pub mod store;
mod sub_names;
pub mod types;

pub use dictionary::{DescriptionError, Dictionary};
pub use store::{ObjectStore, Od, ValueStorage};
pub use types::*;
