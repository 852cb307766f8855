//! A device's object dictionary as one static description.
//!
//! A [`Dictionary`] is a device's objects (strictly ascending by index,
//! entries strictly ascending by subindex), its enumeration data types and
//! the prefix sums that give every entry a *flat position*: the slot of its
//! live value in an `ObjectStore` (`super::store`). It is built
//! in `const` context, without heap, with the [`dictionary!`](crate::dictionary)
//! macro:
//!
//! ```
//! use ecat_slave::od::build::{sub0, var, constant};
//! use ecat_slave::od::{DataType, Object, ObjectCode, PdoMapping};
//!
//! const OBJECTS: &[Object] = &[
//!     Object { index: 0x1000, name: "Device type", code: ObjectCode::Var, entries: &[
//!         var("Device type", DataType::UInt32, PdoMapping::None, 0x0000_1389),
//!     ] },
//!     Object { index: 0x1018, name: "Identity", code: ObjectCode::Record, entries: &[
//!         sub0(1),
//!         constant(1, "Vendor ID", DataType::UInt32, 0x0000_0ABC),
//!     ] },
//! ];
//! ecat_slave::dictionary!(pub DICT, pub ENTRIES = OBJECTS, &[]);
//! assert_eq!(ENTRIES, 3);
//! assert_eq!(DICT.find_entry(0x1018, 1).map(|(flat, _)| flat), Some(2));
//! ```
//!
//! Everything the ESI, the SII, SDO Information, the PDO engine and the
//! application know about objects comes from here; [`Dictionary::validate`]
//! (a `const fn`, so a device can run it at compile time) refuses a
//! description that contradicts itself.

use super::types::{
    Access, DataType, DefaultValue, Entry, EnumDesc, EnumType, Object, ObjectCode, PdoMapping,
};

/// One device's objects, enumerations and flat positions.
#[derive(Debug, Clone, Copy)]
pub struct Dictionary {
    objects: &'static [Object],
    enums: &'static [&'static EnumDesc],
    /// Flat position of the first entry of each object.
    entry_base: &'static [u16],
    entry_count: usize,
    /// Entries plus the `i64` slots of the byte area.
    value_slots: usize,
    /// An entry of a PDO mapping object is writable ([`writable_mapping`]).
    writable_mapping: bool,
}

/// Total number of entries of `objects` (gaps and subindex 0 included): the
/// length of the device's value storage.
pub const fn entry_count(objects: &[Object]) -> usize {
    let mut acc = 0usize;
    let mut rest = objects;
    while let Some((obj, tail)) = rest.split_first() {
        acc += obj.entries.len();
        rest = tail;
    }
    acc
}

/// Length of the value storage `objects` need: one `i64` slot per entry
/// (gaps and subindex 0 included), then the byte area, 8 bytes a slot,
/// where octet strings, `GUID`s and arrays held as one value keep their
/// bytes ([`Entry::area_len`], in dictionary order).
pub const fn value_slots(objects: &[Object]) -> usize {
    let mut acc = 0usize;
    let mut rest = objects;
    while let Some((obj, tail)) = rest.split_first() {
        acc += obj.entries.len();
        let mut es = obj.entries;
        while let Some((e, t)) = es.split_first() {
            acc += e.area_len().div_ceil(8);
            es = t;
        }
        rest = tail;
    }
    acc
}

/// Whether an entry of a PDO mapping object (0x1600..=0x17FF,
/// 0x1A00..=0x1BFF) is writable in some state: a master may change a
/// mapping. Without one, a download to a mapping object can only write the
/// values its entries hold (a complete access; any other write is refused
/// as read-only), so the core's mapping rules have nothing to check.
pub const fn writable_mapping(objects: &[Object]) -> bool {
    let mut rest = objects;
    while let Some((obj, tail)) = rest.split_first() {
        if matches!(obj.index, 0x1600..=0x17FF | 0x1A00..=0x1BFF) {
            let mut es = obj.entries;
            while let Some((e, t)) = es.split_first() {
                if e.access().writable() {
                    return true;
                }
                es = t;
            }
        }
        rest = tail;
    }
    false
}

/// Flat position of the first entry of each of the `N` objects (the prefix
/// sums of their entry counts). `N` must be `objects.len()`.
#[allow(
    clippy::indexing_slicing,
    reason = "const fn: the index is checked against N first"
)]
pub const fn entry_bases<const N: usize>(objects: &[Object]) -> [u16; N] {
    let mut out = [0u16; N];
    let mut acc = 0usize;
    let mut i = 0;
    let mut rest = objects;
    while let Some((obj, tail)) = rest.split_first() {
        if i < N {
            out[i] = acc as u16;
        }
        acc += obj.entries.len();
        i += 1;
        rest = tail;
    }
    out
}

/// Defines a [`Dictionary`] constant and the constant holding its entry
/// count (the length of the value storage, `[i64; COUNT]`).
///
/// `dictionary!(pub NAME, pub COUNT = OBJECTS, ENUMS);` where `OBJECTS` is a
/// `&'static [Object]` and `ENUMS` a `&'static [&'static EnumDesc]`.
#[macro_export]
macro_rules! dictionary {
    ($vis:vis $name:ident, $cvis:vis $count:ident = $objects:expr, $enums:expr $(,)?) => {
        /// Length of the dictionary's value storage (its entries and its
        /// byte area).
        $cvis const $count: usize = $crate::od::dictionary::value_slots($objects);
        /// The object dictionary.
        $vis const $name: $crate::od::Dictionary = {
            const __DICTIONARY_OBJECTS: &[$crate::od::Object] = $objects;
            const __DICTIONARY_N: usize = __DICTIONARY_OBJECTS.len();
            const __DICTIONARY_BASE: [u16; __DICTIONARY_N] =
                $crate::od::dictionary::entry_bases::<__DICTIONARY_N>(__DICTIONARY_OBJECTS);
            $crate::od::Dictionary::new(__DICTIONARY_OBJECTS, $enums, &__DICTIONARY_BASE)
        };
    };
}

/// A contradiction in a device description, found by
/// [`Dictionary::validate`] or
/// [`DeviceDescription::validate`](crate::device::DeviceDescription::validate).
///
/// Each variant names the object (and subindex) at fault; [`Self::message`]
/// is a fixed text usable in a `const` panic.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DescriptionError {
    /// Objects are not strictly ascending by index.
    #[error("object {index:#06x} is out of order (objects must ascend)")]
    ObjectOrder {
        /// The object.
        index: u16,
    },
    /// An object has no entry.
    #[error("object {index:#06x} has no entry")]
    EmptyObject {
        /// The object.
        index: u16,
    },
    /// Entries of an object are not strictly ascending by subindex.
    #[error("object {index:#06x} subindex {sub} is out of order")]
    EntryOrder {
        /// The object.
        index: u16,
        /// The entry.
        sub: u8,
    },
    /// A VAR object has other than exactly subindex 0.
    #[error("VAR object {index:#06x} must have exactly subindex 0")]
    VarShape {
        /// The object.
        index: u16,
    },
    /// Subindex 0 of a record or array is not a read-only UINT8 holding the
    /// highest subindex (writable only for PDO assignments).
    #[error("object {index:#06x}: subindex 0 must be UINT8 holding the highest subindex")]
    SubIndexZero {
        /// The object.
        index: u16,
    },
    /// The bit length does not match the data type (or string default).
    #[error("{index:#06x}:{sub}: bit length does not match the data type")]
    BitLength {
        /// The object.
        index: u16,
        /// The entry.
        sub: u8,
    },
    /// The default lies outside the entry's range or enumeration.
    #[error("{index:#06x}:{sub}: default outside the range or enumeration")]
    DefaultOutOfRange {
        /// The object.
        index: u16,
        /// The entry.
        sub: u8,
    },
    /// `min` is above `max`.
    #[error("{index:#06x}:{sub}: minimum above maximum")]
    EmptyRange {
        /// The object.
        index: u16,
        /// The entry.
        sub: u8,
    },
    /// A padding gap is accessible or mappable.
    #[error("{index:#06x}:{sub}: a padding gap must be read-only, unmapped BITn")]
    GapShape {
        /// The object.
        index: u16,
        /// The entry.
        sub: u8,
    },
    /// An entry's type is an enumeration the dictionary does not list.
    #[error("{index:#06x}:{sub}: enumeration type not listed in the dictionary")]
    UnknownEnum {
        /// The object.
        index: u16,
        /// The entry.
        sub: u8,
    },
    /// A writable string does not fit the store's string slots.
    #[error("{index:#06x}:{sub}: a writable string must be one of the first 4 of at most 32 bytes")]
    StringEntry {
        /// The object.
        index: u16,
        /// The entry.
        sub: u8,
    },
    /// More entries than flat positions can address.
    #[error("more than 65535 entries and value slots")]
    TooManyEntries,
    /// A PDO mapping entry maps an entry that does not exist, is not
    /// mappable in the PDO's direction, or has another bit length.
    #[error(
        "PDO {pdo:#06x}:{sub} maps an entry that is missing, not mappable this way or of another size"
    )]
    BadMapping {
        /// The PDO mapping object.
        pdo: u16,
        /// The mapping entry.
        sub: u8,
    },
    /// A PDO (or the PDOs of one set) is larger than the process image.
    #[error("PDO set {set}: the process image exceeds its maximum size")]
    ImageTooLarge {
        /// The PDO set.
        set: usize,
    },
    /// A PDO set names an object that is not a PDO mapping object of the
    /// right direction (0x1600-0x17FF receive, 0x1A00-0x1BFF transmit).
    #[error("PDO set {set} names {pdo:#06x}, which is not a mapping object of its direction")]
    UnknownPdo {
        /// The PDO set.
        set: usize,
        /// The PDO index.
        pdo: u16,
    },
    /// The defaults of 0x1C12/0x1C13 differ from the first (default) PDO set.
    #[error("the defaults of 0x1C12/0x1C13 must be the first PDO set")]
    DefaultAssignment,
    /// 0x1018 disagrees with the description's identity.
    #[error("0x1018 disagrees with the identity")]
    Identity,
    /// A mandatory object (0x1000, 0x1018) is missing.
    #[error("mandatory object {index:#06x} is missing")]
    MissingObject {
        /// The object.
        index: u16,
    },
    /// The mailbox sizes are outside 16..=1024 bytes, or the bootstrap
    /// mailbox is smaller than the standard one.
    #[error("mailbox sizes must be 16..=1024 bytes")]
    MailboxSize,
    /// A device name (type, name, group) is empty or longer than 64 bytes.
    #[error("device names must be 1..=64 bytes")]
    Name,
}

impl DescriptionError {
    /// A fixed text for `const` panics (the `Display` text has the details).
    pub const fn message(&self) -> &'static str {
        match self {
            Self::ObjectOrder { .. } => "objects must be strictly ascending by index",
            Self::EmptyObject { .. } => "every object needs an entry",
            Self::EntryOrder { .. } => "entries must be strictly ascending by subindex",
            Self::VarShape { .. } => "a VAR object has exactly subindex 0",
            Self::SubIndexZero { .. } => "subindex 0 must be UINT8 holding the highest subindex",
            Self::BitLength { .. } => "an entry's bit length does not match its type",
            Self::DefaultOutOfRange { .. } => "a default lies outside its range or enumeration",
            Self::EmptyRange { .. } => "an entry's minimum is above its maximum",
            Self::GapShape { .. } => "a padding gap must be a read-only, unmapped BITn",
            Self::UnknownEnum { .. } => "an enumeration type is not listed in the dictionary",
            Self::StringEntry { .. } => "a writable string must fit a string slot",
            Self::TooManyEntries => "more than 65535 entries",
            Self::BadMapping { .. } => {
                "a PDO maps an entry that is missing, not mappable that way or of another size"
            }
            Self::ImageTooLarge { .. } => "a PDO set exceeds the process image",
            Self::UnknownPdo { .. } => {
                "a PDO set names an object that is not a PDO of its direction"
            }
            Self::DefaultAssignment => "0x1C12/0x1C13 defaults must be the first PDO set",
            Self::Identity => "0x1018 disagrees with the identity",
            Self::MissingObject { .. } => "a mandatory object (0x1000, 0x1018) is missing",
            Self::MailboxSize => "mailbox sizes must be 16..=1024 bytes",
            Self::Name => "device names must be 1..=64 bytes",
        }
    }
}

/// Natural bit size of a type (strings, octet strings and arrays: 0,
/// sized by their entry).
pub const fn natural_bits(t: &DataType) -> u16 {
    match t {
        DataType::Bool => 1,
        DataType::Int8 | DataType::UInt8 | DataType::Byte | DataType::BitArr8 => 8,
        DataType::Int16 | DataType::UInt16 | DataType::Word | DataType::BitArr16 => 16,
        DataType::Int24 | DataType::UInt24 => 24,
        DataType::Int32
        | DataType::UInt32
        | DataType::Dword
        | DataType::BitArr32
        | DataType::Real32 => 32,
        DataType::Int40 | DataType::UInt40 => 40,
        DataType::Int48 | DataType::UInt48 | DataType::TimeOfDay | DataType::TimeDifference => 48,
        DataType::Int56 | DataType::UInt56 => 56,
        DataType::Int64 | DataType::UInt64 | DataType::Real64 => 64,
        DataType::Guid => 128,
        DataType::Bits(n) => *n as u16,
        DataType::Enum(e) => e.bit_len() as u16,
        DataType::VisibleString
        | DataType::OctetString
        | DataType::UnicodeString
        | DataType::Array(_) => 0,
    }
}

/// A `REAL`/`LREAL` value from the bits the store holds.
pub const fn real_value(t: &DataType, raw: i64) -> f64 {
    match t {
        DataType::Real32 => f32::from_bits(raw as u32) as f64,
        _ => f64::from_bits(raw as u64),
    }
}

/// `a <= b` for values of `t` as the store holds them (floats compared as
/// floats; a NaN bound constrains nothing).
pub const fn value_le(t: &DataType, a: i64, b: i64) -> bool {
    if t.is_real() {
        match (real_order(t, a), real_order(t, b)) {
            (Some(x), Some(y)) => x <= y,
            _ => true,
        }
    } else {
        a <= b
    }
}

/// A `REAL`/`LREAL` value's place in the order of floats as an integer
/// (its sign and magnitude bits as a signed number, -0 and +0 equal);
/// `None` for a NaN. Integer compares instead of float ones: a Cortex-M4F
/// has no double-precision unit, and the soft-float conversion and compare
/// cost 258 bytes of flash in every firmware.
const fn real_order(t: &DataType, raw: i64) -> Option<i64> {
    let (sign, magnitude, infinity) = match t {
        DataType::Real32 => {
            let bits = raw as u32;
            (bits >> 31 != 0, (bits & 0x7FFF_FFFF) as i64, 0x7F80_0000)
        }
        _ => {
            let bits = raw as u64;
            (
                bits >> 63 != 0,
                (bits & 0x7FFF_FFFF_FFFF_FFFF) as i64,
                0x7FF0_0000_0000_0000,
            )
        }
    };
    if magnitude > infinity {
        None
    } else if sign {
        Some(-magnitude)
    } else {
        Some(magnitude)
    }
}

/// The range a value of `t` can take in `bits` bits.
pub const fn natural_range(t: &DataType, bits: u16) -> (i64, i64) {
    let bits = if bits > 64 { 64 } else { bits as u32 };
    if t.is_signed() {
        if bits == 0 {
            return (0, 0);
        }
        let max = if bits >= 64 {
            i64::MAX
        } else {
            (1i64 << (bits - 1)) - 1
        };
        (-max - 1, max)
    } else if bits >= 63 {
        (0, i64::MAX)
    } else {
        (0, (1i64 << bits) - 1)
    }
}

/// Most string entries a store holds (see
/// [`STRING_SLOTS`](super::types::STRING_SLOTS)).
const MAX_STRINGS: usize = super::types::STRING_SLOTS;
/// Longest string value (see [`STRING_CAPACITY`](super::types::STRING_CAPACITY)).
const MAX_STRING: usize = super::types::STRING_CAPACITY;

/// The enumeration of `enums` with the data type index of `e`, whose
/// bit size and signedness agree with it (`None`: not listed).
const fn enum_listed(enums: &[&'static EnumDesc], e: EnumType) -> Option<&'static EnumDesc> {
    let mut rest = enums;
    while let Some((x, tail)) = rest.split_first() {
        if x.index == e.index() {
            let t = EnumType::of(x);
            return if t.bit_len() == e.bit_len() && t.is_signed() == e.is_signed() {
                Some(*x)
            } else {
                None
            };
        }
        rest = tail;
    }
    None
}

const fn enum_contains(e: &EnumDesc, v: i64) -> bool {
    let mut rest = e.values;
    while let Some(((x, _), tail)) = rest.split_first() {
        if *x == v {
            return true;
        }
        rest = tail;
    }
    false
}

const fn check_entry(
    index: u16,
    code: ObjectCode,
    highest: u8,
    e: &Entry,
    enums: &[&'static EnumDesc],
) -> Result<(), DescriptionError> {
    let sub = e.sub;
    let desc = match e.data_type {
        DataType::Enum(en) => match enum_listed(enums, en) {
            Some(d) => Some(d),
            None => return Err(DescriptionError::UnknownEnum { index, sub }),
        },
        _ => None,
    };
    if e.gap() {
        let ok = matches!(e.data_type, DataType::Bits(_))
            && matches!(e.access(), Access::Ro)
            && matches!(e.pdo(), PdoMapping::None);
        if !ok {
            return Err(DescriptionError::GapShape { index, sub });
        }
    }
    match e.default_value() {
        DefaultValue::Str(s) => {
            let ok =
                matches!(e.data_type, DataType::VisibleString) && 8 * s.len() <= e.bit_len as usize;
            if !ok {
                return Err(DescriptionError::BitLength { index, sub });
            }
        }
        DefaultValue::Bytes(b) => {
            let area = e.data_type.is_bytes() && !matches!(e.data_type, DataType::VisibleString);
            if !area || b.len() > e.area_len() {
                return Err(DescriptionError::BitLength { index, sub });
            }
        }
        DefaultValue::Int(v) if e.data_type.is_bytes() => {
            // A byte entry whose default is all zeros.
            if v.get() != 0 || matches!(e.data_type, DataType::VisibleString) {
                return Err(DescriptionError::BitLength { index, sub });
            }
        }
        DefaultValue::Int(v) => {
            let v = v.get();
            // A BOOLEAN is one bit, or a whole byte (ATI's F/T sensor and
            // other SSC-based devices describe it so; TwinCAT accepts it).
            let byte_bool = matches!(e.data_type, DataType::Bool) && e.bit_len == 8;
            if e.bit_len != natural_bits(&e.data_type) && !byte_bool {
                return Err(DescriptionError::BitLength { index, sub });
            }
            if let (Some(lo), Some(hi)) = (e.min(), e.max())
                && !value_le(&e.data_type, lo, hi)
            {
                return Err(DescriptionError::EmptyRange { index, sub });
            }
            if e.data_type.is_real() {
                let below = match e.min() {
                    Some(m) => !value_le(&e.data_type, m, v),
                    None => false,
                };
                let above = match e.max() {
                    Some(m) => !value_le(&e.data_type, v, m),
                    None => false,
                };
                if below || above {
                    return Err(DescriptionError::DefaultOutOfRange { index, sub });
                }
                return Ok(());
            }
            let (lo, hi) = natural_range(&e.data_type, e.bit_len);
            let lo = match e.min() {
                Some(m) if m > lo => m,
                _ => lo,
            };
            let hi = match e.max() {
                Some(m) if m < hi => m,
                _ => hi,
            };
            let in_enum = match desc {
                Some(en) => enum_contains(en, v),
                None => true,
            };
            if v < lo || v > hi || !in_enum {
                return Err(DescriptionError::DefaultOutOfRange { index, sub });
            }
            if sub == 0 && !matches!(code, ObjectCode::Var) {
                // Lists the master writes in PRE-OP: the PDO assignments
                // and the configured module ident list (ETG.5001).
                let list = matches!(index, 0x1C12 | 0x1C13 | 0xF030);
                // A writable subindex 0 (a PDO assignment, a module list
                // such as 0xF010 or 0xF030) is the number of entries in
                // use, not the capacity.
                let ok = matches!(e.data_type, DataType::UInt8)
                    && (v == highest as i64
                        || ((list || e.access().writable()) && v >= 0 && v <= highest as i64));
                if !ok {
                    return Err(DescriptionError::SubIndexZero { index });
                }
            }
        }
    }
    Ok(())
}

impl Dictionary {
    /// A dictionary over `objects` and `enums`; `entry_base` must be
    /// [`entry_bases`] of `objects` (the [`dictionary!`](crate::dictionary)
    /// macro computes it).
    pub const fn new(
        objects: &'static [Object],
        enums: &'static [&'static EnumDesc],
        entry_base: &'static [u16],
    ) -> Self {
        Dictionary {
            objects,
            enums,
            entry_base,
            entry_count: entry_count(objects),
            value_slots: value_slots(objects),
            writable_mapping: writable_mapping(objects),
        }
    }

    /// Whether a master may change a PDO mapping ([`writable_mapping`]).
    /// For a `static` description the answer is a constant: a firmware
    /// whose mappings are fixed does not link the mapping rules.
    pub const fn has_writable_mapping(&self) -> bool {
        self.writable_mapping
    }

    /// Every object, ascending by index.
    pub const fn objects(&self) -> &'static [Object] {
        self.objects
    }

    /// The enumeration data types.
    pub const fn enums(&self) -> &'static [&'static EnumDesc] {
        self.enums
    }

    /// Number of entries (flat positions).
    pub const fn entry_count(&self) -> usize {
        self.entry_count
    }

    /// Length of the value storage: the entries, then the byte area
    /// ([`value_slots`]).
    pub const fn value_slots(&self) -> usize {
        self.value_slots
    }

    /// Where the byte-area entry at flat position `flat` keeps its bytes:
    /// `(first slot, length in bytes)`; `None` for an entry without bytes
    /// there.
    pub fn area_of(&self, flat: usize) -> Option<(usize, usize)> {
        let mut slot = self.entry_count;
        for (f, _, e) in self.entries() {
            if f == flat {
                let area = !e.gap()
                    && e.data_type.is_bytes()
                    && !matches!(e.data_type, DataType::VisibleString);
                return area.then_some((slot, e.area_len()));
            }
            slot += e.area_len().div_ceil(8);
        }
        None
    }

    /// Checks the description for contradictions: order and shape of
    /// objects and entries, bit lengths, defaults within ranges and
    /// enumerations, padding gaps, strings, flat positions. PDO mappings
    /// and sets are checked with the whole device
    /// ([`DeviceDescription::validate`](crate::device::DeviceDescription::validate)).
    pub const fn validate(&self) -> Result<(), DescriptionError> {
        if self.entry_count > u16::MAX as usize {
            return Err(DescriptionError::TooManyEntries);
        }
        let mut strings = 0usize;
        let mut prev: Option<u16> = None;
        let mut objs = self.objects;
        let mut i = 0usize;
        while let Some((o, tail)) = objs.split_first() {
            let index = o.index;
            if let Some(p) = prev
                && p >= index
            {
                return Err(DescriptionError::ObjectOrder { index });
            }
            prev = Some(index);
            // The flat positions handed in must be the prefix sums.
            if i >= self.entry_base.len() || self.entry_base.len() != self.objects.len() {
                return Err(DescriptionError::TooManyEntries);
            }
            let Some((first, _)) = o.entries.split_first() else {
                return Err(DescriptionError::EmptyObject { index });
            };
            let mut highest = 0u8;
            let mut es = o.entries;
            while let Some((e, t)) = es.split_first() {
                if e.sub > highest {
                    highest = e.sub;
                }
                es = t;
            }
            if matches!(o.code, ObjectCode::Var) && (o.entries.len() != 1 || first.sub != 0) {
                return Err(DescriptionError::VarShape { index });
            }
            if !matches!(o.code, ObjectCode::Var) && first.sub != 0 {
                return Err(DescriptionError::SubIndexZero { index });
            }
            let mut last: Option<u8> = None;
            let mut es = o.entries;
            while let Some((e, t)) = es.split_first() {
                if let Some(l) = last
                    && l >= e.sub
                {
                    return Err(DescriptionError::EntryOrder { index, sub: e.sub });
                }
                last = Some(e.sub);
                if let Err(err) = check_entry(index, o.code, highest, e, self.enums) {
                    return Err(err);
                }
                if let DefaultValue::Str(text) = e.default_value()
                    && text.len() <= MAX_STRING
                {
                    // Strings take the store's slots in order; a writable
                    // one needs a slot.
                    if e.access().writable() && strings >= MAX_STRINGS {
                        return Err(DescriptionError::StringEntry { index, sub: e.sub });
                    }
                    strings += 1;
                } else if let DefaultValue::Str(_) = e.default_value()
                    && e.access().writable()
                {
                    return Err(DescriptionError::StringEntry { index, sub: e.sub });
                }
                es = t;
            }
            i += 1;
            objs = tail;
        }
        if self.value_slots() > u16::MAX as usize {
            return Err(DescriptionError::TooManyEntries);
        }
        // The bases must be the prefix sums.
        let mut acc = 0usize;
        let mut objs = self.objects;
        let mut bases = self.entry_base;
        while let Some((o, tail)) = objs.split_first() {
            match bases.split_first() {
                Some((b, rest)) if *b as usize == acc => bases = rest,
                _ => return Err(DescriptionError::TooManyEntries),
            }
            acc += o.entries.len();
            objs = tail;
        }
        Ok(())
    }

    /// The object with index `index` and its position.
    pub fn find(&self, index: u16) -> Option<(usize, &'static Object)> {
        let pos = self
            .objects
            .binary_search_by_key(&index, |o| o.index)
            .ok()?;
        self.objects.get(pos).map(|o| (pos, o))
    }

    /// The entry `index:sub` (gaps included) and its flat position.
    pub fn find_entry(&self, index: u16, sub: u8) -> Option<(usize, &'static Entry)> {
        let (pos, obj) = self.find(index)?;
        let at = obj.entries.binary_search_by_key(&sub, |e| e.sub).ok()?;
        let base = usize::from(*self.entry_base.get(pos)?);
        obj.entries.get(at).map(|e| (base + at, e))
    }

    /// Flat position of the first entry of the object at position `pos`.
    pub fn base(&self, pos: usize) -> Option<usize> {
        self.entry_base.get(pos).map(|b| usize::from(*b))
    }

    /// The object position and entry at flat position `flat`.
    pub fn locate(&self, flat: usize) -> Option<(usize, &'static Entry)> {
        let pos = self
            .entry_base
            .partition_point(|&b| usize::from(b) <= flat)
            .checked_sub(1)?;
        let base = usize::from(*self.entry_base.get(pos)?);
        let entry = self.objects.get(pos)?.entries.get(flat - base)?;
        Some((pos, entry))
    }

    /// The entry at flat position `flat`.
    pub fn entry_at(&self, flat: usize) -> Option<&'static Entry> {
        self.locate(flat).map(|(_, e)| e)
    }

    /// Every entry with its flat position and object, in dictionary order.
    pub fn entries(&self) -> impl Iterator<Item = (usize, &'static Object, &'static Entry)> {
        self.objects
            .iter()
            .flat_map(|o| o.entries.iter().map(move |e| (o, e)))
            .enumerate()
            .map(|(flat, (o, e))| (flat, o, e))
    }

    /// The enumeration with data type index `index`.
    pub fn find_enum(&self, index: u16) -> Option<&'static EnumDesc> {
        self.enums.iter().find(|e| e.index == index).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The integer compare of floats agrees with the float compare
        /// (NaN on either side: no constraint), for REAL and LREAL.
        #[test]
        fn real_value_le_agrees_with_float_compare(a: u64, b: u64, pick: u8) {
            // Mix plain bits with the edge values (-0, +inf, -inf).
            let edge = |x: u64, t: &DataType| match (pick, t) {
                (0, DataType::Real32) => u64::from(0x8000_0000u32),
                (1, DataType::Real32) => u64::from(0x7F80_0000u32),
                (2, DataType::Real32) => u64::from(0xFF80_0000u32),
                (0, _) => 0x8000_0000_0000_0000,
                (1, _) => 0x7FF0_0000_0000_0000,
                (2, _) => 0xFFF0_0000_0000_0000,
                _ => x,
            };
            let float_le = |t: &DataType, a: i64, b: i64| {
                let (x, y) = (real_value(t, a), real_value(t, b));
                x.is_nan() || y.is_nan() || x <= y
            };
            for t in [DataType::Real32, DataType::Real64] {
                let (a, b) = (edge(a, &t) as i64, b as i64);
                proptest::prop_assert_eq!(value_le(&t, a, b), float_le(&t, a, b), "{:?} {:#x} {:#x}", t, a, b);
                proptest::prop_assert_eq!(value_le(&t, b, a), float_le(&t, b, a), "{:?} {:#x} {:#x}", t, b, a);
            }
        }
    }

    #[test]
    fn a_mapping_is_writable_when_any_entry_of_a_mapping_object_is() {
        use crate::od::build::{map, map_rw, mapping_count, setting};
        use crate::od::{Object, ObjectCode};
        const FIXED: &[Entry] = &[map(1, "a", 0x7000_0108)];
        const FLEXIBLE: &[Entry] = &[mapping_count(1, 2), map_rw(1, "a", 0x7000_0108)];
        const COUNT_ONLY: &[Entry] = &[mapping_count(1, 1), map(1, "a", 0x6000_0108)];
        const SETTING: &[Entry] = &[setting(0, "p", DataType::UInt8, 0, &Limits::NONE)];
        let obj = |index, entries| Object {
            index,
            name: "o",
            code: ObjectCode::Record,
            entries,
        };
        let cases = [
            (vec![obj(0x1600, FIXED), obj(0x1A00, FIXED)], false),
            (vec![obj(0x1600, FIXED), obj(0x1601, FLEXIBLE)], true),
            (vec![obj(0x1BFF, COUNT_ONLY)], true),
            (vec![obj(0x17FF, FLEXIBLE)], true),
            // Writable objects just outside both ranges are not mappings.
            (
                vec![
                    obj(0x15FF, FLEXIBLE),
                    obj(0x1800, FLEXIBLE),
                    obj(0x1C00, FLEXIBLE),
                ],
                false,
            ),
            (vec![obj(0x1600, FIXED), obj(0x8000, SETTING)], false),
            (vec![], false),
        ];
        for (objects, expected) in cases {
            let indexes: Vec<u16> = objects.iter().map(|o| o.index).collect();
            assert_eq!(writable_mapping(&objects), expected, "{indexes:04x?}");
            let objects: &'static [Object] = Vec::leak(objects);
            let d = Dictionary::new(objects, &[], &[]);
            assert_eq!(d.has_writable_mapping(), expected, "{indexes:04x?}");
        }
    }

    #[test]
    fn real_limits_compare_as_floats() {
        let f = |x: f32| i64::from(x.to_bits());
        let t = DataType::Real32;
        assert!(value_le(&t, f(-1.5), f(0.25)));
        assert!(!value_le(&t, f(0.25), f(-1.5)));
        assert!(value_le(&t, f(-0.0), f(0.0)) && value_le(&t, f(0.0), f(-0.0)));
        assert!(value_le(&t, f(-2.0), f(-1.0)) && !value_le(&t, f(-1.0), f(-2.0)));
        assert!(value_le(&t, f(f32::NAN), f(-1.0)) && value_le(&t, f(1.0), f(f32::NAN)));
        assert!(value_le(&t, f(f32::NEG_INFINITY), f(f32::MIN)));
        let d = |x: f64| x.to_bits() as i64;
        let t = DataType::Real64;
        assert!(value_le(&t, d(-1e300), d(1e-300)) && !value_le(&t, d(1e-300), d(-1e300)));
        assert!(value_le(&t, d(f64::NAN), d(0.0)));
    }
    use crate::od::build::{constant, gap, sub0, var};
    use crate::od::types::{Limits, PdoMapping};

    const GOOD: &[Object] = &[
        Object {
            index: 0x1000,
            name: "Device type",
            code: ObjectCode::Var,
            entries: &[var("Device type", DataType::UInt32, PdoMapping::None, 5001)],
        },
        Object {
            index: 0x6000,
            name: "Inputs",
            code: ObjectCode::Record,
            entries: &[sub0(2), constant(1, "Bit", DataType::Bool, 0), gap(2, 7)],
        },
    ];
    crate::dictionary!(DICT, COUNT = GOOD, &[]);

    #[test]
    fn flat_positions_are_prefix_sums() {
        assert_eq!(COUNT, 4);
        assert_eq!(DICT.find_entry(0x1000, 0).map(|x| x.0), Some(0));
        assert_eq!(DICT.find_entry(0x6000, 2).map(|x| x.0), Some(3));
        assert_eq!(DICT.locate(2).map(|(p, e)| (p, e.sub)), Some((1, 1)));
        assert!(DICT.find_entry(0x6000, 3).is_none());
        assert!(DICT.find(0x2000).is_none());
        assert_eq!(DICT.validate(), Ok(()));
    }

    const OUT_OF_ORDER: &[Object] = &[
        Object {
            index: 0x6000,
            name: "Inputs",
            code: ObjectCode::Var,
            entries: &[var("Inputs", DataType::UInt8, PdoMapping::None, 0)],
        },
        Object {
            index: 0x1000,
            name: "Device type",
            code: ObjectCode::Var,
            entries: &[var("Device type", DataType::UInt32, PdoMapping::None, 5001)],
        },
    ];
    crate::dictionary!(BAD_ORDER, BAD_ORDER_N = OUT_OF_ORDER, &[]);

    #[test]
    fn objects_out_of_order_are_refused() {
        assert_eq!(
            BAD_ORDER.validate(),
            Err(DescriptionError::ObjectOrder { index: 0x1000 })
        );
        let _ = BAD_ORDER_N;
    }

    const BAD_DEFAULT: &[Object] = &[Object {
        index: 0x8000,
        name: "Setting",
        code: ObjectCode::Var,
        entries: &[Entry {
            limits: &Limits::range(10, 20, ""),
            ..var("Setting", DataType::UInt16, PdoMapping::None, 30)
        }],
    }];
    crate::dictionary!(BAD_DEF, BAD_DEF_N = BAD_DEFAULT, &[]);

    #[test]
    fn a_default_outside_its_range_is_refused() {
        assert_eq!(
            BAD_DEF.validate(),
            Err(DescriptionError::DefaultOutOfRange {
                index: 0x8000,
                sub: 0
            })
        );
        let _ = BAD_DEF_N;
    }

    const BAD_SUB0: &[Object] = &[Object {
        index: 0x6000,
        name: "Inputs",
        code: ObjectCode::Record,
        entries: &[sub0(3), constant(1, "Bit", DataType::Bool, 0)],
    }];
    crate::dictionary!(BAD_S0, BAD_S0_N = BAD_SUB0, &[]);

    #[test]
    fn subindex_zero_must_hold_the_highest_subindex() {
        assert_eq!(
            BAD_S0.validate(),
            Err(DescriptionError::SubIndexZero { index: 0x6000 })
        );
        let _ = BAD_S0_N;
    }

    const BAD_BITS: &[Object] = &[Object {
        index: 0x2000,
        name: "x",
        code: ObjectCode::Var,
        entries: &[Entry {
            bit_len: 8,
            ..var("x", DataType::UInt16, PdoMapping::None, 0)
        }],
    }];
    crate::dictionary!(BAD_B, BAD_B_N = BAD_BITS, &[]);

    #[test]
    fn a_bit_length_that_is_not_the_types_is_refused() {
        assert_eq!(
            BAD_B.validate(),
            Err(DescriptionError::BitLength {
                index: 0x2000,
                sub: 0
            })
        );
        assert!(!BAD_B.validate().unwrap_err().message().is_empty());
        let _ = BAD_B_N;
    }

    const BYTE_BOOL: &[Object] = &[Object {
        index: 0x2000,
        name: "x",
        code: ObjectCode::Var,
        entries: &[Entry {
            bit_len: 8,
            ..var("x", DataType::Bool, PdoMapping::None, 1)
        }],
    }];
    crate::dictionary!(BYTE_B, BYTE_B_N = BYTE_BOOL, &[]);
    const WIDE_BOOL: &[Object] = &[Object {
        index: 0x2000,
        name: "x",
        code: ObjectCode::Var,
        entries: &[Entry {
            bit_len: 16,
            ..var("x", DataType::Bool, PdoMapping::None, 1)
        }],
    }];
    crate::dictionary!(WIDE_B, WIDE_B_N = WIDE_BOOL, &[]);

    #[test]
    fn a_bool_of_one_byte_is_valid_but_not_of_two() {
        assert_eq!(BYTE_B.validate(), Ok(()));
        assert_eq!(
            WIDE_B.validate(),
            Err(DescriptionError::BitLength {
                index: 0x2000,
                sub: 0
            })
        );
        let _ = (BYTE_B_N, WIDE_B_N);
    }

    #[test]
    fn natural_ranges() {
        assert_eq!(natural_range(&DataType::Int16, 16), (-32768, 32767));
        assert_eq!(natural_range(&DataType::UInt16, 16), (0, 65535));
        assert_eq!(natural_range(&DataType::Bits(7), 7), (0, 127));
        assert_eq!(natural_range(&DataType::UInt64, 64), (0, i64::MAX));
        assert_eq!(natural_range(&DataType::Int64, 64), (i64::MIN, i64::MAX));
    }
}
