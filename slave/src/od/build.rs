//! `const` constructors for dictionary entries, so a device's object table
//! reads like the manual's: one line per subindex.
//!
//! Every constructor fills the bit length from the data type (strings from
//! their default), so the table cannot contradict itself there; ranges,
//! units (a `&Limits`) and flags are set with struct update syntax:
//!
//! ```
//! use ecat_slave::od::build::{ranged, sub0};
//! use ecat_slave::od::{DataType, Entry, Limits};
//! const CURRENT: Entry =
//!     ranged(2, "CURRENT", DataType::UInt16, 1000, &Limits::range(500, 3000, "mA"));
//! const ZERO: Entry = sub0(2);
//! assert_eq!(CURRENT.bit_len, 16);
//! assert_eq!((CURRENT.min(), CURRENT.max(), CURRENT.unit()), (Some(500), Some(3000), "mA"));
//! assert_eq!(ZERO.name, "SubIndex 000");
//! ```

use super::dictionary::natural_bits;
use super::sub_names::SUB_NAMES;
use super::types::{Access, DataType, DefaultValue, Entry, EntryFlags, Int64, Limits, PdoMapping};

/// `"SubIndex nnn"`, the ETG name of an unnamed subindex.
#[allow(
    clippy::indexing_slicing,
    reason = "a u8 index into a table of 256 names cannot be out of range"
)]
pub const fn sub_name(sub: u8) -> &'static str {
    SUB_NAMES[sub as usize]
}

/// An entry with no range, no unit, not stored, not a gap.
///
/// # Panics
///
/// When `default` is a 64-bit number beyond the 32-bit range (see
/// [`Entry::with_default`]), as every constructor here that takes a
/// default: in a `const` item, a build error.
pub const fn base(
    sub: u8,
    name: &'static str,
    data_type: DataType,
    access: Access,
    pdo: PdoMapping,
    default: i64,
) -> Entry {
    Entry {
        sub,
        name,
        data_type,
        bit_len: natural_bits(&data_type),
        default_bits: 0,
        limits: &Limits::NONE,
        flags: EntryFlags::new(access, pdo),
    }
    .with_default(default)
}

/// Subindex 0 of an array or record: the highest subindex, UINT8, RO.
pub const fn sub0(highest: u8) -> Entry {
    base(
        0,
        "SubIndex 000",
        DataType::UInt8,
        Access::Ro,
        PdoMapping::None,
        highest as i64,
    )
}

/// Subindex 0 of a PDO assignment (0x1C12/0x1C13): `count` PDOs assigned,
/// writable in PRE-OP, at most `capacity`.
pub const fn assign_count(count: u8, capacity: u8) -> Entry {
    Entry {
        limits: capacity_limits(capacity),
        ..sub0(count).with_access(Access::RwPreOp)
    }
}

/// `0..=capacity` for 0x1C12:00 / 0x1C13:00. A `'static` reference built in
/// a `const fn` must come from constants, so the capacities a device can
/// have (0..=32 PDOs per assignment) are spelled out. A larger capacity
/// gets `0..=255`, the entry type's range (what SDO Information shows; a
/// count beyond the array's entries is still refused with 0x06090031 when
/// written); a builder that needs the exact bound sets its own `Limits`,
/// as the twins do. Not a `static` table filled by a loop: a firmware
/// would then link all 34 (1.5 KB on a Cortex-M4), where each spelled-out
/// `Limits` is linked only when a device uses it.
#[rustfmt::skip]
const fn capacity_limits(capacity: u8) -> &'static Limits {
    match capacity {
            0 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([0, 0])), unit: "", default: None },
            1 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([1, 0])), unit: "", default: None },
            2 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([2, 0])), unit: "", default: None },
            3 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([3, 0])), unit: "", default: None },
            4 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([4, 0])), unit: "", default: None },
            5 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([5, 0])), unit: "", default: None },
            6 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([6, 0])), unit: "", default: None },
            7 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([7, 0])), unit: "", default: None },
            8 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([8, 0])), unit: "", default: None },
            9 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([9, 0])), unit: "", default: None },
            10 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([10, 0])), unit: "", default: None },
            11 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([11, 0])), unit: "", default: None },
            12 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([12, 0])), unit: "", default: None },
            13 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([13, 0])), unit: "", default: None },
            14 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([14, 0])), unit: "", default: None },
            15 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([15, 0])), unit: "", default: None },
            16 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([16, 0])), unit: "", default: None },
            17 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([17, 0])), unit: "", default: None },
            18 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([18, 0])), unit: "", default: None },
            19 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([19, 0])), unit: "", default: None },
            20 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([20, 0])), unit: "", default: None },
            21 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([21, 0])), unit: "", default: None },
            22 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([22, 0])), unit: "", default: None },
            23 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([23, 0])), unit: "", default: None },
            24 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([24, 0])), unit: "", default: None },
            25 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([25, 0])), unit: "", default: None },
            26 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([26, 0])), unit: "", default: None },
            27 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([27, 0])), unit: "", default: None },
            28 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([28, 0])), unit: "", default: None },
            29 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([29, 0])), unit: "", default: None },
            30 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([30, 0])), unit: "", default: None },
            31 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([31, 0])), unit: "", default: None },
            32 => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([32, 0])), unit: "", default: None },
            _ => &Limits { min: Some(Int64([0, 0])), max: Some(Int64([255, 0])), unit: "", default: None },
    }
}

/// One PDO assigned by 0x1C12/0x1C13 (UINT16, RW in PRE-OP).
pub const fn assign(sub: u8, pdo: u16) -> Entry {
    base(
        sub,
        sub_name(sub),
        DataType::UInt16,
        Access::RwPreOp,
        PdoMapping::None,
        pdo as i64,
    )
}

/// The entry of a read-only VAR object (subindex 0).
pub const fn var(name: &'static str, t: DataType, pdo: PdoMapping, default: i64) -> Entry {
    base(0, name, t, Access::Ro, pdo, default)
}

/// A read-only VISIBLE_STRING VAR sized by its default (0x1008-0x100A):
/// `string("Device name", &Limits::text("IO8"))`. The text comes as a
/// `&'static Limits` because an entry keeps it there (its own 32 default
/// bits cannot hold it), and a `const fn` cannot make a `'static`
/// reference of an argument.
pub const fn string(name: &'static str, text: &'static Limits) -> Entry {
    let len = match text.default {
        Some(DefaultValue::Str(t)) => t.len(),
        _ => 0,
    };
    Entry {
        bit_len: 8 * len as u16,
        limits: text,
        ..var(name, DataType::VisibleString, PdoMapping::None, 0)
    }
}

/// A read-only constant of a record or array (identity, 0x1C00, 0xF000).
pub const fn constant(sub: u8, name: &'static str, t: DataType, value: i64) -> Entry {
    base(sub, name, t, Access::Ro, PdoMapping::None, value)
}

/// A PDO mapping entry `index << 16 | sub << 8 | bits` (UINT32, RO).
pub const fn map(sub: u8, name: &'static str, mapping: u32) -> Entry {
    base(
        sub,
        name,
        DataType::UInt32,
        Access::Ro,
        PdoMapping::None,
        mapping as i64,
    )
}

/// Subindex 0 of a writable PDO mapping object (flexible mapping,
/// ETG.1000.6 / ETG.1020): `count` entries mapped by default, writable in
/// PRE-OP, at most `capacity` (the object's highest subindex). The
/// core checks what a master writes (`0x06010003`, `0x06040041`..`43`).
pub const fn mapping_count(count: u8, capacity: u8) -> Entry {
    assign_count(count, capacity)
}

/// A writable PDO mapping entry (UINT32, RW in PRE-OP) holding `mapping`
/// (`index << 16 | sub << 8 | bits`; 0 for a free place of the object).
pub const fn map_rw(sub: u8, name: &'static str, mapping: u32) -> Entry {
    map(sub, name, mapping).with_access(Access::RwPreOp)
}

/// A PDO mapping entry that maps `index:subindex` of `bits` bits (the
/// mapping value packed for you).
pub const fn map_to(sub: u8, name: &'static str, index: u16, subindex: u8, bits: u8) -> Entry {
    map(
        sub,
        name,
        (index as u32) << 16 | (subindex as u32) << 8 | bits as u32,
    )
}

/// A padding mapping `0x000000nn` (index 0) in a PDO mapping object.
pub const fn pad(sub: u8, bits: u8) -> Entry {
    map(sub, sub_name(sub), bits as u32)
}

/// A padding gap of a record: `bits` zero bits up to a byte boundary, no
/// access (SDO Information: NULL, access 0; upload 0x06010000).
pub const fn gap(sub: u8, bits: u8) -> Entry {
    base(
        sub,
        sub_name(sub),
        DataType::Bits(bits),
        Access::Ro,
        PdoMapping::None,
        0,
    )
    .with_gap(true)
}

/// A TxPDO-mappable input (read-only).
pub const fn input(sub: u8, name: &'static str, t: DataType) -> Entry {
    base(sub, name, t, Access::Ro, PdoMapping::Tx, 0)
}

/// An RxPDO-mappable output (read/write).
pub const fn output(sub: u8, name: &'static str, t: DataType) -> Entry {
    base(sub, name, t, Access::Rw, PdoMapping::Rx, 0)
}

/// A stored device setting (RW, backup, setting), with its unit and range
/// (`&Limits::unit("ms")`, `&Limits::NONE`).
pub const fn setting(
    sub: u8,
    name: &'static str,
    t: DataType,
    default: i64,
    limits: &'static Limits,
) -> Entry {
    Entry {
        limits,
        ..base(sub, name, t, Access::Rw, PdoMapping::None, default)
            .with_backup(true)
            .with_setting(true)
    }
}

/// A stored setting with a range (`&Limits::range(min, max, unit)`): the
/// same as [`setting`], named for what the table says.
pub const fn ranged(
    sub: u8,
    name: &'static str,
    t: DataType,
    default: i64,
    limits: &'static Limits,
) -> Entry {
    setting(sub, name, t, default, limits)
}

/// ETG.1020 sync modes of 0x1C32:01 / 0x1C33:01.
pub mod sync_mode {
    /// Free run: the application runs on its own timing.
    pub const FREE_RUN: i64 = 0;
    /// Synchronous with the SM2 (outputs) / SM3 (inputs) event.
    pub const SM_SYNCHRON: i64 = 1;
    /// DC-synchronous on SYNC0.
    pub const DC_SYNC0: i64 = 2;
}

/// 0x1C32:04 / 0x1C33:04 "Sync modes supported": free run (bit 0),
/// SM-synchronous (bit 1), DC SYNC0 (bits 4:2 = 001).
pub const SYNC_MODES_SUPPORTED: i64 = 0x0007;

/// The entries of 0x1C32 "SM output parameter" and 0x1C33 "SM input
/// parameter" (ETG.1020, synchronisation; the subindices ETG.1020 gives
/// them, 7 and 8 left out). A device puts both objects in its dictionary
/// with these entries; the core keeps them current: the sync mode and
/// cycle times chosen at PRE-OP→SAFE-OP from the DC registers, the SM
/// event missed counter in DC mode. The master may write the sync mode
/// in PRE-OP (checked against the DC registers at SAFE-OP).
pub const SYNC_PARAMETER_ENTRIES: &[Entry] = &[
    sub0(12),
    Entry {
        limits: &Limits::range(sync_mode::FREE_RUN, sync_mode::DC_SYNC0, ""),
        ..base(
            1,
            "Sync mode",
            DataType::UInt16,
            Access::RwPreOp,
            PdoMapping::None,
            sync_mode::FREE_RUN,
        )
    },
    constant(2, "Cycle time", DataType::UInt32, 0),
    constant(3, "Shift time", DataType::UInt32, 0),
    constant(
        4,
        "Sync modes supported",
        DataType::UInt16,
        SYNC_MODES_SUPPORTED,
    ),
    constant(
        5,
        "Minimum cycle time",
        DataType::UInt32,
        crate::limits::DC_MIN_CYCLE_NS as i64,
    ),
    constant(6, "Calc and copy time", DataType::UInt32, 0),
    constant(9, "Delay time", DataType::UInt32, 0),
    constant(10, "Sync0 cycle time", DataType::UInt32, 0),
    constant(11, "SM event missed counter", DataType::UInt16, 0),
    constant(12, "Cycle time too small counter", DataType::UInt16, 0),
];
