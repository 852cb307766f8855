//! Timing limits of this firmware that several layers publish or enforce.
//!
//! A leaf: it depends on nothing in the crate, so any layer may use it.

/// Shortest SYNC0 cycle the firmware accepts in DC mode (0x09A0 below it
/// is refused at PRE-OP→SAFE-OP with 0x0035, and 0x1C32:05 "minimum cycle
/// time" publishes it): one pass of the firmware loop with process data
/// must fit in a cycle.
pub const DC_MIN_CYCLE_NS: u32 = 100_000;
