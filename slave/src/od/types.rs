//! Types of the static object-dictionary description.
//!
//! These types describe objects; they hold no live values and know nothing
//! of EtherCAT frames. A device builds its one description from them
//! (see [`super::dictionary`] and [`super::build`]).

/// Longest visible string a string slot of the value store holds.
pub const STRING_CAPACITY: usize = 32;
/// Number of string slots a value store has (longer or further strings are
/// served from their defaults and are read-only).
pub const STRING_SLOTS: usize = 4;

/// CoE base data types used by the dictionary (ETG.1000.6 Table 64 codes).
///
/// Values up to 64 bits live in the store's `i64` slot of their entry
/// (signed types sign-extended; `REAL` and `LREAL` as their IEEE 754 bit
/// patterns, zero-extended). Strings, octet strings, `GUID` and arrays held
/// as one value are *byte entries* ([`Entry::area_len`]); see
/// `super::store` for where their bytes live.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DataType {
    /// BOOL, 1 bit (0x0001).
    Bool,
    /// SINT / INTEGER8 (0x0002).
    Int8,
    /// INT / INTEGER16 (0x0003).
    Int16,
    /// DINT / INTEGER32 (0x0004).
    Int32,
    /// USINT / UNSIGNED8 (0x0005).
    UInt8,
    /// UINT / UNSIGNED16 (0x0006).
    UInt16,
    /// UDINT / UNSIGNED32 (0x0007).
    UInt32,
    /// REAL / REAL32 (0x0008): the IEEE 754 single's bits.
    Real32,
    /// VISIBLE_STRING (0x0009).
    VisibleString,
    /// OCTET_STRING (0x000A): bytes of the entry's length.
    OctetString,
    /// UNICODE_STRING (0x000B): UTF-16LE code units of the entry's length.
    UnicodeString,
    /// TIME_OF_DAY (0x000C): 48 bits (ms since midnight, days since 1984).
    TimeOfDay,
    /// TIME_DIFFERENCE (0x000D): 48 bits.
    TimeDifference,
    /// INT24 / INTEGER24 (0x0010).
    Int24,
    /// LREAL / REAL64 (0x0011): the IEEE 754 double's bits.
    Real64,
    /// INT40 / INTEGER40 (0x0012).
    Int40,
    /// INT48 / INTEGER48 (0x0013).
    Int48,
    /// INT56 / INTEGER56 (0x0014).
    Int56,
    /// LINT / INTEGER64 (0x0015).
    Int64,
    /// UINT24 / UNSIGNED24 (0x0016).
    UInt24,
    /// UINT40 / UNSIGNED40 (0x0018).
    UInt40,
    /// UINT48 / UNSIGNED48 (0x0019).
    UInt48,
    /// UINT56 / UNSIGNED56 (0x001A).
    UInt56,
    /// ULINT / UNSIGNED64 (0x001B).
    UInt64,
    /// GUID (0x001D): 128 bits, a byte entry.
    Guid,
    /// BYTE (0x001E): 8 bits without arithmetic meaning.
    Byte,
    /// WORD (0x001F): 16 bits.
    Word,
    /// DWORD (0x0020): 32 bits.
    Dword,
    /// BITARR8 (0x002D): 8 bits addressed one by one.
    BitArr8,
    /// BITARR16 (0x002E).
    BitArr16,
    /// BITARR32 (0x002F).
    BitArr32,
    /// BITn padding / bit field of n bits (0x0030 + n - 1, n in 1..=8).
    Bits(u8),
    /// An array of the base type with this code held as one value (an
    /// ETG.2000 `ARRAY [0..n] OF T` that is the type of a variable or of a
    /// record item, not an array object with subindices): a byte entry of
    /// the entry's length. Reported with the element's code.
    Array(u16),
    /// A device-specific enumeration (data type index 0x0800.., see [`EnumDesc`]).
    Enum(EnumType),
}

impl DataType {
    /// The CoE data type code as reported by SDO Information and the ESI.
    pub const fn code(&self) -> u16 {
        match self {
            DataType::Bool => 0x0001,
            DataType::Int8 => 0x0002,
            DataType::Int16 => 0x0003,
            DataType::Int32 => 0x0004,
            DataType::UInt8 => 0x0005,
            DataType::UInt16 => 0x0006,
            DataType::UInt32 => 0x0007,
            DataType::Real32 => 0x0008,
            DataType::VisibleString => 0x0009,
            DataType::OctetString => 0x000A,
            DataType::UnicodeString => 0x000B,
            DataType::TimeOfDay => 0x000C,
            DataType::TimeDifference => 0x000D,
            DataType::Int24 => 0x0010,
            DataType::Real64 => 0x0011,
            DataType::Int40 => 0x0012,
            DataType::Int48 => 0x0013,
            DataType::Int56 => 0x0014,
            DataType::Int64 => 0x0015,
            DataType::UInt24 => 0x0016,
            DataType::UInt40 => 0x0018,
            DataType::UInt48 => 0x0019,
            DataType::UInt56 => 0x001A,
            DataType::UInt64 => 0x001B,
            DataType::Guid => 0x001D,
            DataType::Byte => 0x001E,
            DataType::Word => 0x001F,
            DataType::Dword => 0x0020,
            DataType::BitArr8 => 0x002D,
            DataType::BitArr16 => 0x002E,
            DataType::BitArr32 => 0x002F,
            DataType::Bits(n) => 0x002F + *n as u16,
            DataType::Array(code) => *code,
            DataType::Enum(e) => e.index(),
        }
    }

    /// The type of a base data type code the core serves (not an
    /// enumeration, not an array), the inverse of [`DataType::code`].
    pub const fn from_code(code: u16) -> Option<DataType> {
        Some(match code {
            0x0001 => DataType::Bool,
            0x0002 => DataType::Int8,
            0x0003 => DataType::Int16,
            0x0004 => DataType::Int32,
            0x0005 => DataType::UInt8,
            0x0006 => DataType::UInt16,
            0x0007 => DataType::UInt32,
            0x0008 => DataType::Real32,
            0x0009 => DataType::VisibleString,
            0x000A => DataType::OctetString,
            0x000B => DataType::UnicodeString,
            0x000C => DataType::TimeOfDay,
            0x000D => DataType::TimeDifference,
            0x0010 => DataType::Int24,
            0x0011 => DataType::Real64,
            0x0012 => DataType::Int40,
            0x0013 => DataType::Int48,
            0x0014 => DataType::Int56,
            0x0015 => DataType::Int64,
            0x0016 => DataType::UInt24,
            0x0018 => DataType::UInt40,
            0x0019 => DataType::UInt48,
            0x001A => DataType::UInt56,
            0x001B => DataType::UInt64,
            0x001D => DataType::Guid,
            0x001E => DataType::Byte,
            0x001F => DataType::Word,
            0x0020 => DataType::Dword,
            0x002D => DataType::BitArr8,
            0x002E => DataType::BitArr16,
            0x002F => DataType::BitArr32,
            0x0030..=0x0037 => DataType::Bits((code - 0x002F) as u8),
            _ => return None,
        })
    }

    /// Whether values of this type are signed integers. An enumeration is
    /// signed when one of its values is negative (its base type is: CiA
    /// 402's quick stop option code 0x605A is an INTEGER16 with -1 and -2
    /// among its values), so its bits are sign-extended on the wire.
    pub const fn is_signed(&self) -> bool {
        if let DataType::Enum(e) = self {
            return e.is_signed();
        }
        matches!(
            self,
            DataType::Int8
                | DataType::Int16
                | DataType::Int24
                | DataType::Int32
                | DataType::Int40
                | DataType::Int48
                | DataType::Int56
                | DataType::Int64
        )
    }

    /// Whether values are IEEE 754 floats (`REAL`, `LREAL`), held as their
    /// bit patterns.
    pub const fn is_real(&self) -> bool {
        matches!(self, DataType::Real32 | DataType::Real64)
    }

    /// Whether values of this type are bytes rather than a number:
    /// strings, octet strings, `GUID`, arrays held as one value.
    pub const fn is_bytes(&self) -> bool {
        matches!(
            self,
            DataType::VisibleString
                | DataType::OctetString
                | DataType::UnicodeString
                | DataType::Guid
                | DataType::Array(_)
        )
    }

    /// The ETG/IEC 61131 type name used in the ESI (`BOOL`, `UINT`, `BIT7`, ...).
    /// Enumerations return "": their name (`DT0800EN03`) is their
    /// [`EnumDesc`]'s, in the dictionary ([`crate::od::Dictionary::find_enum`]); strings return
    /// `STRING` (the ESI appends the length: `STRING(13)`); an array its
    /// element's name (the ESI writes `ARRAY [0..n] OF T`).
    pub const fn etg_name(&self) -> &'static str {
        match self {
            DataType::Bool => "BOOL",
            DataType::Int8 => "SINT",
            DataType::Int16 => "INT",
            DataType::Int32 => "DINT",
            DataType::UInt8 => "USINT",
            DataType::UInt16 => "UINT",
            DataType::UInt32 => "UDINT",
            DataType::Real32 => "REAL",
            DataType::VisibleString => "STRING",
            DataType::OctetString => "OCTET_STRING",
            DataType::UnicodeString => "UNICODE_STRING",
            DataType::TimeOfDay => "TIME_OF_DAY",
            DataType::TimeDifference => "TIME_DIFFERENCE",
            DataType::Int24 => "INT24",
            DataType::Real64 => "LREAL",
            DataType::Int40 => "INT40",
            DataType::Int48 => "INT48",
            DataType::Int56 => "INT56",
            DataType::Int64 => "LINT",
            DataType::UInt24 => "UINT24",
            DataType::UInt40 => "UINT40",
            DataType::UInt48 => "UINT48",
            DataType::UInt56 => "UINT56",
            DataType::UInt64 => "ULINT",
            DataType::Guid => "GUID",
            DataType::Byte => "BYTE",
            DataType::Word => "WORD",
            DataType::Dword => "DWORD",
            DataType::BitArr8 => "BITARR8",
            DataType::BitArr16 => "BITARR16",
            DataType::BitArr32 => "BITARR32",
            DataType::Bits(1) => "BIT1",
            DataType::Bits(2) => "BIT2",
            DataType::Bits(3) => "BIT3",
            DataType::Bits(4) => "BIT4",
            DataType::Bits(5) => "BIT5",
            DataType::Bits(6) => "BIT6",
            DataType::Bits(7) => "BIT7",
            DataType::Bits(_) => "BIT8",
            DataType::Array(code) => match base_type_const(*code) {
                Some(b) => b.name,
                None => "BYTE",
            },
            DataType::Enum(_) => "",
        }
    }
}

/// [`base_type`] in `const` context.
const fn base_type_const(code: u16) -> Option<&'static BaseType> {
    let mut rest = BASE_TYPES;
    while let Some((t, tail)) = rest.split_first() {
        if t.code == code {
            return Some(t);
        }
        rest = tail;
    }
    None
}

/// What values of a base data type are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BaseKind {
    /// `BOOL`.
    Bool,
    /// A signed integer.
    Signed,
    /// An unsigned integer (`BYTE`, `WORD`, `DWORD` too).
    Unsigned,
    /// An IEEE 754 float (`REAL`, `LREAL`).
    Real,
    /// `BITn`: n bits of a packed field.
    Bits,
    /// An array of bits (`BITARRn`).
    BitArray,
    /// A character or octet string (`STRING(n)`, `OCTET_STRING`,
    /// `UNICODE_STRING`): its length is the entry's.
    String,
    /// A time (`TIME_OF_DAY`, `TIME_DIFFERENCE`) or a `GUID`.
    Other,
}

/// One CoE base data type: its code (ETG.1000.6 Table 64, as SDO
/// Information and the SII report it), its ETG.2000 / IEC 61131 name (as
/// the ESI writes it), its size and kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BaseType {
    /// Data type code.
    pub code: u16,
    /// ESI name (`UDINT`, `BIT3`, `STRING`: the ESI appends the length).
    pub name: &'static str,
    /// Bits of one value; 0 for strings, whose length is the entry's.
    pub bits: u16,
    /// What the values are.
    pub kind: BaseKind,
}

const fn base(code: u16, name: &'static str, bits: u16, kind: BaseKind) -> BaseType {
    BaseType {
        code,
        name,
        bits,
        kind,
    }
}

/// The base data types of ETG.1000.6 (Table 64) with their ETG.2000 names:
/// the one table every reader and writer of type codes and names uses
/// (SDO Information, the ESI writer and readers, `esi inspect`, the
/// commissioning tool).
pub const BASE_TYPES: &[BaseType] = &[
    base(0x0001, "BOOL", 1, BaseKind::Bool),
    base(0x0002, "SINT", 8, BaseKind::Signed),
    base(0x0003, "INT", 16, BaseKind::Signed),
    base(0x0004, "DINT", 32, BaseKind::Signed),
    base(0x0005, "USINT", 8, BaseKind::Unsigned),
    base(0x0006, "UINT", 16, BaseKind::Unsigned),
    base(0x0007, "UDINT", 32, BaseKind::Unsigned),
    base(0x0008, "REAL", 32, BaseKind::Real),
    base(0x0009, "STRING", 0, BaseKind::String),
    base(0x000A, "OCTET_STRING", 0, BaseKind::String),
    base(0x000B, "UNICODE_STRING", 0, BaseKind::String),
    base(0x000C, "TIME_OF_DAY", 48, BaseKind::Other),
    base(0x000D, "TIME_DIFFERENCE", 48, BaseKind::Other),
    base(0x0010, "INT24", 24, BaseKind::Signed),
    base(0x0011, "LREAL", 64, BaseKind::Real),
    base(0x0012, "INT40", 40, BaseKind::Signed),
    base(0x0013, "INT48", 48, BaseKind::Signed),
    base(0x0014, "INT56", 56, BaseKind::Signed),
    base(0x0015, "LINT", 64, BaseKind::Signed),
    base(0x0016, "UINT24", 24, BaseKind::Unsigned),
    base(0x0018, "UINT40", 40, BaseKind::Unsigned),
    base(0x0019, "UINT48", 48, BaseKind::Unsigned),
    base(0x001A, "UINT56", 56, BaseKind::Unsigned),
    base(0x001B, "ULINT", 64, BaseKind::Unsigned),
    base(0x001D, "GUID", 128, BaseKind::Other),
    base(0x001E, "BYTE", 8, BaseKind::Unsigned),
    base(0x001F, "WORD", 16, BaseKind::Unsigned),
    base(0x0020, "DWORD", 32, BaseKind::Unsigned),
    base(0x002D, "BITARR8", 8, BaseKind::BitArray),
    base(0x002E, "BITARR16", 16, BaseKind::BitArray),
    base(0x002F, "BITARR32", 32, BaseKind::BitArray),
    base(0x0030, "BIT1", 1, BaseKind::Bits),
    base(0x0031, "BIT2", 2, BaseKind::Bits),
    base(0x0032, "BIT3", 3, BaseKind::Bits),
    base(0x0033, "BIT4", 4, BaseKind::Bits),
    base(0x0034, "BIT5", 5, BaseKind::Bits),
    base(0x0035, "BIT6", 6, BaseKind::Bits),
    base(0x0036, "BIT7", 7, BaseKind::Bits),
    base(0x0037, "BIT8", 8, BaseKind::Bits),
];

/// The base data type of `code`, if it is one.
pub fn base_type(code: u16) -> Option<&'static BaseType> {
    BASE_TYPES.iter().find(|t| t.code == code)
}

/// The base data type an ESI names (`UDINT`, `BIT3`, `STRING(12)`:
/// surrounding blanks ignored), if it is one.
pub fn base_type_named(name: &str) -> Option<&'static BaseType> {
    let n = name.trim();
    let n = match n.strip_prefix("STRING(") {
        Some(rest) if rest.ends_with(')') => "STRING",
        _ => n,
    };
    BASE_TYPES.iter().find(|t| t.name == n)
}

/// An enumeration as an entry's [`DataType`] names it: its data type
/// index, the bit size of its values and whether one of them is negative.
/// Its values and texts are its [`EnumDesc`]'s, which the dictionary
/// lists ([`crate::od::Dictionary::find_enum`]). Three bytes instead of a
/// pointer: a `DataType` takes 4 bytes on a 32-bit microcontroller instead
/// of 8, and an [`Entry`] 36 instead of 40.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct EnumType {
    /// The index, little-endian, then the bit size (bits 0..=6) and
    /// whether signed (bit 7). Bytes, not a `u16`: aligned to 1, the three
    /// fit behind a `DataType`'s tag.
    bytes: [u8; 3],
}

impl core::fmt::Debug for EnumType {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("EnumType")
            .field("index", &format_args!("{:#06x}", self.index()))
            .field("bit_len", &self.bit_len())
            .field("signed", &self.is_signed())
            .finish()
    }
}

impl EnumType {
    /// The type of `e`'s values.
    pub const fn of(e: &EnumDesc) -> Self {
        let mut signed = false;
        let mut rest = e.values;
        while let [(v, _), tail @ ..] = rest {
            if *v < 0 {
                signed = true;
            }
            rest = tail;
        }
        let [lo, hi] = e.index.to_le_bytes();
        EnumType {
            bytes: [lo, hi, (e.bit_len & 0x7F) | if signed { 0x80 } else { 0 }],
        }
    }

    /// The data type index (0x0800..0x0FFF).
    pub const fn index(self) -> u16 {
        u16::from_le_bytes([self.bytes[0], self.bytes[1]])
    }

    /// The bit size of a value.
    pub const fn bit_len(self) -> u8 {
        self.bytes[2] & 0x7F
    }

    /// Whether a value of the enumeration is negative (its values are then
    /// sign-extended on the wire).
    pub const fn is_signed(self) -> bool {
        self.bytes[2] & 0x80 != 0
    }
}

/// An enumeration data type (manual 6.1.7, objects 0x0800..0x0805).
#[derive(Debug, PartialEq, Eq)]
pub struct EnumDesc {
    /// Data type index, 0x0800..0x0FFF (ETG.1000.6 enumeration range).
    pub index: u16,
    /// Name as in the manual and the ESI, e.g. `DT0800EN03` (`ENnn` = bit size).
    pub name: &'static str,
    /// Bit size of a value of this type.
    pub bit_len: u8,
    /// `(value, text)` pairs in the manual's order.
    pub values: &'static [(i64, &'static str)],
}

impl EnumDesc {
    /// The data type of entries holding values of this enumeration.
    pub const fn data_type(&self) -> DataType {
        DataType::Enum(EnumType::of(self))
    }

    /// Whether `value` is one of the enumeration's values.
    pub fn contains(&self, value: i64) -> bool {
        self.values.iter().any(|(v, _)| *v == value)
    }

    /// The text of `value`, if it is defined.
    pub fn text(&self, value: i64) -> Option<&'static str> {
        self.values
            .iter()
            .find(|(v, _)| *v == value)
            .map(|(_, t)| *t)
    }
}

/// Who may read or write an entry, and in which AL states (ETG.1000.6 5.6.3.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Read-only in every state.
    Ro,
    /// Read/write in PRE-OP, SAFE-OP and OP.
    Rw,
    /// Readable always, writable only in PRE-OP (PDO assignment 0x1C12/0x1C13).
    RwPreOp,
    /// Write-only (reads abort 0x06010001).
    Wo,
}

impl Access {
    /// Whether an SDO upload of the entry is allowed at all.
    pub const fn readable(&self) -> bool {
        !matches!(self, Access::Wo)
    }

    /// Whether an SDO download of the entry is allowed in some state.
    pub const fn writable(&self) -> bool {
        !matches!(self, Access::Ro)
    }

    /// The ETG.1000.6 object access bits (bits 0-5: read PRE-OP/SAFE-OP/OP,
    /// write PRE-OP/SAFE-OP/OP) as used by SDO Information.
    pub const fn bits(&self) -> u16 {
        match self {
            Access::Ro => 0x0007,
            Access::Rw => 0x003F,
            Access::RwPreOp => 0x000F,
            Access::Wo => 0x0038,
        }
    }
}

/// Whether an entry may be mapped into a PDO and in which direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PdoMapping {
    /// Not mappable.
    None,
    /// Mappable into an RxPDO (master outputs, 0x7000 range).
    Rx,
    /// Mappable into a TxPDO (master inputs, 0x6000/0xA000 range).
    Tx,
    /// Mappable into both (ETG.2000 `PdoMapping` `RT`/`TR`).
    RxTx,
}

impl PdoMapping {
    /// Whether an entry of this mappability may be mapped the way `dir`
    /// (`Rx` or `Tx`) says.
    pub const fn allows(self, dir: PdoMapping) -> bool {
        matches!(
            (self, dir),
            (PdoMapping::Rx | PdoMapping::RxTx, PdoMapping::Rx)
                | (PdoMapping::Tx | PdoMapping::RxTx, PdoMapping::Tx)
        )
    }
}

/// CoE object code (ETG.1000.6 table 62).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectCode {
    /// A single variable (0x07).
    Var,
    /// An array: all subindices >= 1 share one type (0x08).
    Array,
    /// A record of differently typed entries (0x09).
    Record,
}

impl ObjectCode {
    /// The numeric object code.
    pub const fn code(&self) -> u8 {
        match self {
            ObjectCode::Var => 0x07,
            ObjectCode::Array => 0x08,
            ObjectCode::Record => 0x09,
        }
    }
}

/// An `i64` kept as two 32-bit halves, so that it is aligned to 4 bytes:
/// with it a [`DefaultValue`] takes 12 bytes on a 32-bit microcontroller
/// instead of 16 (a `i64` is aligned to 8 there).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Int64(pub(crate) [u32; 2]);

impl Int64 {
    /// `v`, stored in halves.
    pub const fn new(v: i64) -> Self {
        Int64([v as u32, (v >> 32) as u32])
    }

    /// The value.
    pub const fn get(self) -> i64 {
        ((self.0[1] as u64) << 32 | self.0[0] as u64) as i64
    }
}

impl core::fmt::Debug for Int64 {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.get().fmt(f)
    }
}

impl From<i64> for Int64 {
    fn from(v: i64) -> Self {
        Int64::new(v)
    }
}

impl From<Int64> for i64 {
    fn from(v: Int64) -> Self {
        v.get()
    }
}

// What the halves are for: the dictionary table of a 32-bit firmware
// (checked whenever the core is built for one, as the footprint and board
// firmware builds of `.ci/run` do).
#[cfg(target_pointer_width = "32")]
const _: () = assert!(core::mem::size_of::<Entry>() == 24 && core::mem::align_of::<Entry>() == 4);
#[cfg(target_pointer_width = "32")]
const _: () = assert!(core::mem::size_of::<Limits>() == 44);

/// The default value of an entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DefaultValue {
    /// A number (integers, booleans as 0/1, enumerations by value); build
    /// it with [`DefaultValue::int`], read it with [`DefaultValue::as_int`].
    Int(Int64),
    /// A visible string (it may be shorter than the entry).
    Str(&'static str),
    /// The bytes of an octet string, `GUID` or array entry (zeros after
    /// them up to the entry's length).
    Bytes(&'static [u8]),
}

impl DefaultValue {
    /// A number.
    pub const fn int(v: i64) -> Self {
        DefaultValue::Int(Int64::new(v))
    }

    /// The number, for an [`Int`](DefaultValue::Int) default.
    pub const fn as_int(&self) -> Option<i64> {
        match self {
            DefaultValue::Int(v) => Some(v.get()),
            _ => None,
        }
    }
}

/// One subindex of an object.
#[derive(Debug, PartialEq, Eq)]
pub struct Entry {
    /// Subindex (0 = number of entries for arrays and records).
    pub sub: u8,
    /// Name as in the manual (`CURRENT`, `RA:UP:A`, ...); `SubIndex 002` for gaps.
    pub name: &'static str,
    /// Data type.
    pub data_type: DataType,
    /// Size in bits (strings: 8 x maximum length).
    pub bit_len: u16,
    /// Access rights, PDO mappability, backup, setting and gap, in one
    /// byte; read them with [`Entry::access`], [`Entry::pdo`],
    /// [`Entry::backup`], [`Entry::setting`], [`Entry::gap`].
    pub flags: EntryFlags,
    /// The default number's low 32 bits, sign- or zero-extended by the
    /// data type ([`DataType::is_signed`]); read the default with
    /// [`Entry::default_value`], set it with [`Entry::with_default`].
    /// A default these bits cannot hold (a string's text, an octet
    /// string's bytes, a 64-bit number beyond the 32-bit range) is the
    /// entry's [`Limits::default`], and these bits are then 0.
    pub default_bits: u32,
    /// Range, unit and a default too wide for [`Entry::default_bits`],
    /// where the device gives them ([`Limits::NONE`] for none); read them
    /// with [`Entry::min`], [`Entry::max`], [`Entry::unit`],
    /// [`Entry::default_value`].
    pub limits: &'static Limits,
}

/// The 32 default bits ([`Entry::default_bits`]) of the number `v` in an
/// entry of type `t`, or `None` when they cannot hold it (then `v` goes in
/// the entry's [`Limits::default`]). Numbers are held as the store holds
/// them (signed types sign-extended, others zero-extended), so the bits
/// are `v`'s low half and `v` must be their extension.
pub const fn default_bits(t: &DataType, v: i64) -> Option<u32> {
    let bits = v as u32;
    if extend_default(t, bits) == v {
        Some(bits)
    } else {
        None
    }
}

/// The number held by the 32 default bits `bits` of an entry of type `t`.
const fn extend_default(t: &DataType, bits: u32) -> i64 {
    if t.is_signed() {
        bits as i32 as i64
    } else {
        bits as i64
    }
}

/// An entry's access rights, PDO mappability and flags in one byte (five
/// separate fields took five bytes and made every [`Entry`] 4 bytes
/// longer on a 32-bit microcontroller). Build with [`EntryFlags::new`] and
/// the `with_*` methods, all `const`.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct EntryFlags(u8);

impl EntryFlags {
    const BACKUP: u8 = 0x10;
    const SETTING: u8 = 0x20;
    const GAP: u8 = 0x40;

    /// `access` and `pdo`; not backup, not a setting, not a gap.
    pub const fn new(access: Access, pdo: PdoMapping) -> Self {
        EntryFlags(0).with_access(access).with_pdo(pdo)
    }

    /// Access rights.
    pub const fn access(self) -> Access {
        match self.0 & 0x03 {
            0 => Access::Ro,
            1 => Access::Rw,
            2 => Access::RwPreOp,
            _ => Access::Wo,
        }
    }

    /// PDO mappability.
    pub const fn pdo(self) -> PdoMapping {
        match (self.0 >> 2) & 0x03 {
            0 => PdoMapping::None,
            1 => PdoMapping::Rx,
            2 => PdoMapping::Tx,
            _ => PdoMapping::RxTx,
        }
    }

    /// Stored by SAVE and part of the backup (ETG.1000.6 access bit 8).
    pub const fn backup(self) -> bool {
        self.0 & Self::BACKUP != 0
    }

    /// A device setting (ETG.1000.6 access bit 9).
    pub const fn setting(self) -> bool {
        self.0 & Self::SETTING != 0
    }

    /// A padding gap (blank subindex in the manual): not accessible by
    /// SDO, packed as zero bits in complete access and PDOs.
    pub const fn gap(self) -> bool {
        self.0 & Self::GAP != 0
    }

    /// With access rights `a`.
    pub const fn with_access(self, a: Access) -> Self {
        let bits = match a {
            Access::Ro => 0,
            Access::Rw => 1,
            Access::RwPreOp => 2,
            Access::Wo => 3,
        };
        EntryFlags(self.0 & !0x03 | bits)
    }

    /// With PDO mappability `p`.
    pub const fn with_pdo(self, p: PdoMapping) -> Self {
        let bits = match p {
            PdoMapping::None => 0,
            PdoMapping::Rx => 1,
            PdoMapping::Tx => 2,
            PdoMapping::RxTx => 3,
        };
        EntryFlags(self.0 & !0x0C | bits << 2)
    }

    const fn with(self, bit: u8, on: bool) -> Self {
        EntryFlags(if on { self.0 | bit } else { self.0 & !bit })
    }

    /// Stored by SAVE (or not).
    pub const fn with_backup(self, on: bool) -> Self {
        self.with(Self::BACKUP, on)
    }

    /// A device setting (or not).
    pub const fn with_setting(self, on: bool) -> Self {
        self.with(Self::SETTING, on)
    }

    /// A padding gap (or not).
    pub const fn with_gap(self, on: bool) -> Self {
        self.with(Self::GAP, on)
    }
}

impl core::fmt::Debug for EntryFlags {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("EntryFlags")
            .field("access", &self.access())
            .field("pdo", &self.pdo())
            .field("backup", &self.backup())
            .field("setting", &self.setting())
            .field("gap", &self.gap())
            .finish()
    }
}

/// The range and unit of an entry, and a default too wide for its 32
/// default bits. Most entries have none of them and share
/// [`Limits::NONE`]; an entry holds one reference (4 bytes on a 32-bit
/// microcontroller) instead of its two ends, a unit and a default (44
/// bytes), which is most of what a dictionary table costs in flash.
///
/// In a `const` item a reference to a `Limits` built by a `const fn` is
/// `'static`: `ranged(1, "Filter", DataType::UInt16, 10, &Limits::range(0, 100, "ms"))`,
/// `string("Device name", &Limits::text("IO8"))`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Smallest allowed value, where the manual gives a range (read it
    /// with [`Entry::min`]; an [`Int64`] of two halves: 12 bytes on a
    /// 32-bit microcontroller, where an `Option<i64>` is 16).
    pub min: Option<Int64>,
    /// Largest allowed value, where the manual gives a range
    /// ([`Entry::max`]).
    pub max: Option<Int64>,
    /// Unit text as the manual gives it (`ms`, `mA`, `Hz`, `0.01 %`), or "".
    pub unit: &'static str,
    /// The entry's default where its [`Entry::default_bits`] cannot hold
    /// it: a visible string's text, the bytes of an octet string, `GUID`
    /// or array entry, a 64-bit number beyond the 32-bit range. `None`
    /// for every other entry: it is read from the default bits.
    pub default: Option<DefaultValue>,
}

impl Limits {
    /// No range, no unit.
    pub const NONE: Limits = Limits {
        min: None,
        max: None,
        unit: "",
        default: None,
    };

    /// The range `min..=max` in `unit` ("" for none).
    pub const fn range(min: i64, max: i64, unit: &'static str) -> Limits {
        Limits {
            min: Some(Int64::new(min)),
            max: Some(Int64::new(max)),
            unit,
            default: None,
        }
    }

    /// The optional ends `min` and `max` in `unit` ("" for none): a
    /// range open at one end, as an ESI may give it.
    pub const fn bounds(min: Option<i64>, max: Option<i64>, unit: &'static str) -> Limits {
        Limits {
            min: match min {
                Some(v) => Some(Int64::new(v)),
                None => None,
            },
            max: match max {
                Some(v) => Some(Int64::new(v)),
                None => None,
            },
            unit,
            default: None,
        }
    }

    /// A unit without a range.
    pub const fn unit(unit: &'static str) -> Limits {
        Limits {
            min: None,
            max: None,
            unit,
            default: None,
        }
    }

    /// No range, no unit; `text` as the default of a visible string.
    pub const fn text(text: &'static str) -> Limits {
        Limits {
            default: Some(DefaultValue::Str(text)),
            ..Limits::NONE
        }
    }

    /// No range, no unit; `bytes` as the default of an octet string,
    /// `GUID` or array entry (zeros after them).
    pub const fn bytes(bytes: &'static [u8]) -> Limits {
        Limits {
            default: Some(DefaultValue::Bytes(bytes)),
            ..Limits::NONE
        }
    }

    /// These limits with `default` as the entry's default (a default the
    /// entry's 32 default bits cannot hold).
    pub const fn with_default(self, default: DefaultValue) -> Limits {
        Limits {
            default: Some(default),
            ..self
        }
    }
}

/// One object of the dictionary.
#[derive(Debug, PartialEq, Eq)]
pub struct Object {
    /// Object index.
    pub index: u16,
    /// Name as in the manual's "Group" column (`POWER STAGE`, `DIR_IN`).
    pub name: &'static str,
    /// Object code.
    pub code: ObjectCode,
    /// Entries in ascending subindex order; for arrays/records entry 0 is subindex 0.
    pub entries: &'static [Entry],
}

impl Entry {
    /// The entry with access rights `a` (`constant(..).with_access(Access::Rw)`).
    pub const fn with_access(self, a: Access) -> Self {
        Entry {
            flags: self.flags.with_access(a),
            ..self
        }
    }

    /// The entry with PDO mappability `p`.
    pub const fn with_pdo(self, p: PdoMapping) -> Self {
        Entry {
            flags: self.flags.with_pdo(p),
            ..self
        }
    }

    /// The entry stored by SAVE (or not).
    pub const fn with_backup(self, on: bool) -> Self {
        Entry {
            flags: self.flags.with_backup(on),
            ..self
        }
    }

    /// The entry as a device setting (or not).
    pub const fn with_setting(self, on: bool) -> Self {
        Entry {
            flags: self.flags.with_setting(on),
            ..self
        }
    }

    /// The entry as a padding gap (or not).
    pub const fn with_gap(self, on: bool) -> Self {
        Entry {
            flags: self.flags.with_gap(on),
            ..self
        }
    }

    /// Access rights.
    pub const fn access(&self) -> Access {
        self.flags.access()
    }

    /// PDO mappability.
    pub const fn pdo(&self) -> PdoMapping {
        self.flags.pdo()
    }

    /// Stored by SAVE and part of the backup (ETG.1000.6 access bit 8).
    pub const fn backup(&self) -> bool {
        self.flags.backup()
    }

    /// A device setting (ETG.1000.6 access bit 9).
    pub const fn setting(&self) -> bool {
        self.flags.setting()
    }

    /// A padding gap (blank subindex in the manual): not accessible by
    /// SDO, packed as zero bits in complete access and PDOs.
    pub const fn gap(&self) -> bool {
        self.flags.gap()
    }

    /// The default value: [`Limits::default`] where the entry has one,
    /// else the number its [`Entry::default_bits`] hold.
    pub const fn default_value(&self) -> DefaultValue {
        match self.limits.default {
            Some(d) => d,
            None => DefaultValue::int(extend_default(&self.data_type, self.default_bits)),
        }
    }

    /// The entry with the number `v` as its default, held in its 32
    /// default bits.
    ///
    /// # Panics
    ///
    /// When they cannot hold `v` ([`default_bits`] is `None`: a 64-bit
    /// number beyond the 32-bit range); in a `const` item that is a
    /// compile error. Give such a default with [`Limits::with_default`];
    /// a builder of entries at run time checks [`default_bits`] first.
    #[allow(
        clippy::panic,
        reason = "meant for const items, where a default the entry cannot hold becomes a build error"
    )]
    pub const fn with_default(self, v: i64) -> Self {
        let Some(default_bits) = default_bits(&self.data_type, v) else {
            panic!("a default beyond 32 bits goes in the entry's Limits (Limits::with_default)");
        };
        Entry {
            default_bits,
            ..self
        }
    }

    /// Smallest allowed value, where the device gives a range.
    pub const fn min(&self) -> Option<i64> {
        match self.limits.min {
            Some(v) => Some(v.get()),
            None => None,
        }
    }

    /// Largest allowed value, where the device gives a range.
    pub const fn max(&self) -> Option<i64> {
        match self.limits.max {
            Some(v) => Some(v.get()),
            None => None,
        }
    }

    /// Unit text (`ms`, `mA`, `Hz`, `0.01 %`), or "".
    pub const fn unit(&self) -> &'static str {
        self.limits.unit
    }

    /// Bytes of the entry's value kept in the store's byte area: the
    /// length of an octet string, `UNICODE_STRING`, `GUID` or an array held
    /// as one value; 0 for numbers (their `i64` slot) and for visible
    /// strings (string slots, see `super::store`).
    pub const fn area_len(&self) -> usize {
        if self.gap()
            || !self.data_type.is_bytes()
            || matches!(self.data_type, DataType::VisibleString)
        {
            return 0;
        }
        (self.bit_len as usize).div_ceil(8)
    }
}

impl Object {
    /// The entry with subindex `sub`, if present.
    pub fn entry(&self, sub: u8) -> Option<&'static Entry> {
        self.entries.iter().find(|e| e.sub == sub)
    }

    /// Highest subindex of the object (SDO Info "max subindex").
    pub fn max_sub(&self) -> u8 {
        self.entries.iter().map(|e| e.sub).max().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::od::build::{base, string, var};

    #[test]
    fn an_entry_keeps_a_32_bit_default_in_its_bits_sign_or_zero_extended() {
        let cases = [
            (DataType::Int8, -1),
            (DataType::Int16, -32768),
            (DataType::Int32, i64::from(i32::MIN)),
            (DataType::Int32, i64::from(i32::MAX)),
            (DataType::Int64, -5),
            (DataType::Int40, i64::from(i32::MIN)),
            (DataType::UInt32, i64::from(u32::MAX)),
            (DataType::UInt64, i64::from(u32::MAX)),
            (DataType::Real32, 0x3F80_0000),
            (DataType::Bool, 1),
            (DataType::Bits(3), 5),
        ];
        for (t, v) in cases {
            let e = base(1, "x", t, Access::Rw, PdoMapping::None, v);
            assert_eq!(e.default_value(), DefaultValue::int(v), "{t:?} {v}");
            assert_eq!(e.default_bits, v as u32, "{t:?} {v}");
            assert_eq!(e.limits.default, None, "{t:?} {v}");
        }
    }

    #[test]
    fn a_default_beyond_32_bits_does_not_fit_the_bits() {
        let cases = [
            (DataType::UInt64, 1 << 32),
            (DataType::Int64, i64::from(i32::MIN) - 1),
            (DataType::Int64, i64::MAX),
            (DataType::Real64, 1.0f64.to_bits() as i64),
            // Not the type's own bit pattern: a signed type's value is
            // sign-extended, an unsigned type's zero-extended.
            (DataType::UInt32, -1),
            (DataType::Int32, i64::from(u32::MAX)),
        ];
        for (t, v) in cases {
            assert_eq!(default_bits(&t, v), None, "{t:?} {v}");
        }
    }

    #[test]
    fn a_wide_default_or_a_text_is_read_from_the_limits() {
        const BIG: Entry = Entry {
            limits: &Limits::range(0, i64::MAX, "ns").with_default(DefaultValue::int(1 << 40)),
            ..var("Big", DataType::UInt64, PdoMapping::None, 0)
        };
        assert_eq!(BIG.default_value(), DefaultValue::int(1 << 40));
        assert_eq!(
            (BIG.min(), BIG.max(), BIG.unit()),
            (Some(0), Some(i64::MAX), "ns")
        );
        const NAME: Entry = string("Device name", &Limits::text("IO8"));
        assert_eq!(NAME.default_value(), DefaultValue::Str("IO8"));
        assert_eq!(NAME.bit_len, 24);
        const KEY: Limits = Limits::bytes(&[1, 2]);
        assert_eq!(KEY.default, Some(DefaultValue::Bytes(&[1, 2])));
    }

    #[test]
    fn a_range_keeps_its_64_bit_ends_and_may_be_open_at_either() {
        const E: Entry = var("x", DataType::Int64, PdoMapping::None, 0);
        let with = |l: &'static Limits| Entry { limits: l, ..E };
        const FULL: Limits = Limits::range(i64::MIN, i64::MAX, "ns");
        let full = with(&FULL);
        assert_eq!((full.min(), full.max()), (Some(i64::MIN), Some(i64::MAX)));
        let low = Box::leak(Box::new(Limits::bounds(Some(-(1 << 40)), None, "")));
        assert_eq!((with(low).min(), with(low).max()), (Some(-(1 << 40)), None));
        let high = Box::leak(Box::new(Limits::bounds(None, Some(7), "mA")));
        assert_eq!(
            (with(high).min(), with(high).max(), with(high).unit()),
            (None, Some(7), "mA")
        );
        assert_eq!(Limits::bounds(None, None, ""), Limits::NONE);
    }

    #[test]
    #[should_panic(expected = "Limits::with_default")]
    fn with_default_refuses_what_the_bits_cannot_hold() {
        let e = var("Big", DataType::UInt64, PdoMapping::None, 0);
        let _ = core::hint::black_box(e).with_default(1 << 33);
    }

    #[test]
    fn entry_flags_keep_every_combination() {
        for access in [Access::Ro, Access::Rw, Access::RwPreOp, Access::Wo] {
            for pdo in [
                PdoMapping::None,
                PdoMapping::Rx,
                PdoMapping::Tx,
                PdoMapping::RxTx,
            ] {
                for bits in 0..8u8 {
                    let (backup, setting, gap) = (bits & 1 != 0, bits & 2 != 0, bits & 4 != 0);
                    let f = EntryFlags::new(access, pdo)
                        .with_backup(backup)
                        .with_setting(setting)
                        .with_gap(gap);
                    assert_eq!((f.access(), f.pdo()), (access, pdo));
                    assert_eq!((f.backup(), f.setting(), f.gap()), (backup, setting, gap));
                    // Changing one part leaves the others.
                    let g = f
                        .with_access(Access::Wo)
                        .with_pdo(PdoMapping::Tx)
                        .with_gap(!gap);
                    assert_eq!(
                        (g.access(), g.pdo(), g.gap()),
                        (Access::Wo, PdoMapping::Tx, !gap)
                    );
                    assert_eq!((g.backup(), g.setting()), (backup, setting));
                }
            }
        }
    }

    #[test]
    fn int64_keeps_every_value() {
        for v in [
            0,
            1,
            -1,
            402,
            i64::from(u32::MAX),
            i64::from(i32::MIN) - 1,
            i64::MIN,
            i64::MAX,
        ] {
            assert_eq!(Int64::new(v).get(), v);
            assert_eq!(DefaultValue::int(v).as_int(), Some(v));
            assert_eq!(format!("{:?}", DefaultValue::int(v)), format!("Int({v})"));
        }
        assert_eq!(DefaultValue::Str("x").as_int(), None);
    }

    #[test]
    fn every_data_type_agrees_with_the_base_type_table() {
        use super::DataType::*;
        for t in [
            Bool,
            Int8,
            Int16,
            Int32,
            UInt8,
            UInt16,
            UInt32,
            Real32,
            VisibleString,
            OctetString,
            UnicodeString,
            TimeOfDay,
            TimeDifference,
            Int24,
            Real64,
            Int40,
            Int48,
            Int56,
            Int64,
            UInt24,
            UInt40,
            UInt48,
            UInt56,
            UInt64,
            Guid,
            Byte,
            Word,
            Dword,
            BitArr8,
            BitArr16,
            BitArr32,
        ]
        .into_iter()
        .chain((1..=8).map(Bits))
        {
            let b = base_type(t.code()).expect("in the table");
            assert_eq!(DataType::from_code(t.code()), Some(t));
            assert_eq!(b.name, t.etg_name(), "{t:?}");
            assert_eq!(base_type_named(t.etg_name()), Some(b));
        }
        assert_eq!(base_type_named(" STRING(13) ").map(|t| t.code), Some(9));
        assert_eq!(base_type_named("BIT9"), None);
        assert_eq!(base_type(0x0017), None);
        // Every code of the table is a type the core serves.
        for b in BASE_TYPES {
            assert_eq!(DataType::from_code(b.code).map(|t| t.code()), Some(b.code));
        }
        assert_eq!(Array(0x0006).code(), 0x0006);
        assert_eq!(Array(0x0006).etg_name(), "UINT");
        assert!(Array(0x001E).is_bytes() && OctetString.is_bytes() && !Real32.is_bytes());
    }

    #[test]
    fn rt_mappable_entries_map_both_ways() {
        assert!(PdoMapping::RxTx.allows(PdoMapping::Rx));
        assert!(PdoMapping::RxTx.allows(PdoMapping::Tx));
        assert!(!PdoMapping::Rx.allows(PdoMapping::Tx));
        assert!(!PdoMapping::None.allows(PdoMapping::Rx));
    }
}
