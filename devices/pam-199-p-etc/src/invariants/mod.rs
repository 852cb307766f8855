//! # Invariants: the safety rules checked on random master sessions
//!
//! The rules of `docs/SAFETY.md` as invariants, not examples: a
//! [`Harness`] runs a software PAM (the [`Pam`](crate::Pam) application on
//! the core's firmware loop, against the software ESC) and plays a master
//! that reaches it only through EtherCAT frames, plus the world around it
//! (injected time, power cycles that keep the parameter EEPROM and the
//! firmware flash, cut saves and downloads, PDI faults, a stalled
//! firmware, power-stage faults). After every firmware pass it checks
//! every [`Invariant`] and reports the first [`Violation`].
//!
//! One action model ([`Action`]) serves both random drivers:
//!
//! - the property test `src/tests/invariants.rs` generates action
//!   sequences with proptest strategies (`PROPTEST_CASES` sets how many);
//! - the cargo-fuzz target `fuzz/fuzz_targets/pam_invariants.rs` decodes
//!   them from bytes with [`decode`]; [`encode`] writes seeds and replays
//!   shrunk property-test cases.
//!
//! Host-only test tooling: behind the `invariants` feature (which needs
//! `std`) and in the crate's own tests. It uses the software ESC only
//! through a few `use` lines of `harness.rs`.

mod action;
mod harness;
mod model;
mod seeds;

pub use action::{
    Action, Coil, INTERESTING, Image, JUMPS_MS, MAX_ACTIONS, Outputs, PDOS, PdiRegion, Request,
    SmSetting, StageEvent, Target, Value, decode, encode,
};
pub use harness::{
    Bootloader, Device, FACTORY_PAYLOAD, FACTORY_VERSION, FLASH_BYTES, Flash, Harness,
};
pub use model::{
    Invariant, Observation, PassContext, Shadow, Unlock, Violation, assigned, function_pdos,
    image_bytes, mapping,
};
pub use seeds::seeds;
