//! The node's address map and identity: where a module's objects and
//! parameters live, the entry builders of its parameter tables, and the
//! identity constants. A leaf: the dictionary (`od`), the parameter table
//! (`params`), the model and the telegram channel all use it; it uses none
//! of them.

use ecat_slave::od::build::ranged;
use ecat_slave::od::{Access, DataType, Entry, Limits};

/// Vendor ID used for the DMA-22(A) twin. HCS has no EtherCAT vendor ID
/// we know of: this is a placeholder from the range our examples use, not
/// an ETG assignment (README, NOTES.md).
pub const VENDOR_ID: u32 = 0x0000_0AC5;
/// Product code: the DMA-22 node.
pub const PRODUCT_CODE: u32 = 0x0000_0022;
/// Revision number.
pub const REVISION: u32 = 1;
/// Module ident of the DMA-22(A) module (0xF030/0xF050 entries).
pub const MODULE_IDENT: u32 = 0x0022_0001;
/// Slots of the node (CMD 15 addresses at most 5 modules, 000 5.1).
pub const SLOTS: u8 = 5;
/// Device name (0x1008; the SII's device type, string 1, which SOEM shows).
pub const DEVICE_NAME: &str = "DMA-22(A)-ECAT";

/// A read-only parameter (a `d` value, `Vers`, `E00`, `E04`-`E07`, `E28`)
/// with the range the manual prints.
pub const fn ro(
    sub: u8,
    name: &'static str,
    t: DataType,
    default: i64,
    limits: &'static Limits,
) -> Entry {
    rw(sub, name, t, default, limits)
        .with_access(Access::Ro)
        .with_backup(false)
        .with_setting(false)
}

/// A read/write parameter, writable in every state as over the HCS
/// fieldbuses, with its range and default.
pub const fn rw(
    sub: u8,
    name: &'static str,
    t: DataType,
    default: i64,
    limits: &'static Limits,
) -> Entry {
    ranged(sub, name, t, default, limits)
}

/// Index of slot `n`'s copy of `base`.
pub const fn slot_index(base: u16, n: u8) -> u16 {
    base + 0x10 * n as u16
}

/// Inputs of a module (0x60n0).
pub const INPUTS: u16 = 0x6000;
/// Outputs of a module (0x70n0).
pub const OUTPUTS: u16 = 0x7000;
/// Parameters ID 0x00..=0xFE of a module (0x80n0).
pub const PARAMS_LOW: u16 = 0x8000;
/// Parameters ID 0xFF..=0x109 of a module (0x80n1).
pub const PARAMS_HIGH: u16 = 0x8001;
/// Diagnosis of a module (0xA0n0).
pub const DIAGNOSIS: u16 = 0xA000;
/// 0x2000 HCS telegram request (the telegram channel, [`crate::app::channel`]).
pub const REQUEST: u16 = 0x2000;
/// 0x2001 HCS telegram response.
pub const RESPONSE: u16 = 0x2001;

/// The `(index, subindex)` of HCS parameter `id` of the module in slot
/// `n`, if the ID is in the parameter range.
pub const fn parameter(n: u8, id: u16) -> Option<(u16, u8)> {
    if id < 0xFF {
        Some((slot_index(PARAMS_LOW, n), (id + 1) as u8))
    } else if id <= 0x109 {
        Some((slot_index(PARAMS_HIGH, n), (id - 0xFE) as u8))
    } else {
        None
    }
}
