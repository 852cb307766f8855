//! SII: the EtherCAT Slave Information Interface EEPROM image (ETG.2010).
//!
//! Two halves, both heap-free and panic-free on any input:
//!
//! - [`encode`] turns a [`SiiConfig`] into an EEPROM image: the fixed header
//!   of ETG.2010 Table 2 (words 0x00..0x3F, with the CRC-8 of word 7, see
//!   [`crc8`]) followed by the categories of ETG.2010 Table 3 in the order
//!   Strings, General, FMMU, SyncM, TxPDO, RxPDO, End.
//! - [`SiiReader`] is a zero-copy view over any image (ours or another
//!   vendor's dump) with accessors for the header, an iterator over the
//!   category chain and decoders for the common categories.
//!
//! The encoder only produces images that ethercrab 0.7.1 accepts: it refuses
//! General flags outside 0x1F, CoE details outside 0x3F, SM enable bytes
//! outside 0x0F, unknown FMMU usages, device names over 64 characters, and it
//! writes the General category with exactly 32 bytes and all PDOs of one
//! direction into one category placed after the SyncM category.
//!
//! Table numbers: Table 2 (SII area, the header) and Tables 14/15 (PDO and
//! PDO entry structure) are the numbers other implementations (ethercrab,
//! SOEM notes) cite; the numbers given for the category list (3), Strings
//! (6), General (7), FMMU (8), SyncM (9) and FMMUX (10) follow the order of
//! the ETG.2010 clauses and may be off by a few between editions, so every
//! citation also names the category.
//!
//! Layout reference (byte offsets into the image, all little-endian):
//!
//! | Word  | Content (ETG.2010 Table 2)                                   |
//! |-------|--------------------------------------------------------------|
//! | 0x00  | PDI control                                                   |
//! | 0x01  | PDI configuration                                             |
//! | 0x02  | SYNC impulse length                                           |
//! | 0x03  | PDI configuration 2                                           |
//! | 0x04  | configured station alias                                      |
//! | 0x07  | checksum: CRC-8 of bytes 0..14 in the low byte                |
//! | 0x08  | vendor id, product code, revision, serial (u32 each)          |
//! | 0x14  | bootstrap mailbox: receive offset/size, send offset/size      |
//! | 0x18  | standard mailbox: receive offset/size, send offset/size       |
//! | 0x1C  | mailbox protocols (AoE 1, EoE 2, CoE 4, FoE 8, SoE 0x10, VoE 0x20) |
//! | 0x3E  | EEPROM size in KiBit minus one                                |
//! | 0x3F  | version (1)                                                   |
//! | 0x40  | first category header (type, length in words), data follows  |

mod crc;
mod encode;
mod read;

pub use crc::crc8;
pub use encode::encode;
pub use read::{
    Categories, Category, DcEntry, DcIter, FmmuIter, PdoDirection, PdoEntryIter, PdoEntryView,
    PdoIter, PdoView, SiiGeneralRaw, SiiReader, SiiStrings, StringIter, SyncManagerIter,
};

/// Byte offset of the first category header (word 0x40, ETG.2010 Table 2).
pub const FIRST_CATEGORY_BYTE: usize = 0x80;

/// Size of the SII EEPROM images this crate builds and the software ESC
/// emulates, in bytes (64 Kbit: room for the images of vendors' devices
/// with many PDOs; an image declares its own EEPROM size in word 0x3E).
pub const SII_SIZE: usize = 8192;

/// Word address of the first category header (ETG.2010 Table 2).
pub const FIRST_CATEGORY_WORD: u16 = 0x40;

/// Length in bytes of the General category data (ETG.2010 Table 7).
pub const GENERAL_LEN: usize = 32;

/// Length in bytes of one SyncM category element (ETG.2010 Table 9).
pub const SYNC_MANAGER_LEN: usize = 8;

/// Length in bytes of a TxPDO/RxPDO header and of one PDO entry
/// (ETG.2010 Tables 14 and 15).
pub const PDO_RECORD_LEN: usize = 8;

/// Length in bytes of one DC category element (ETG.2010, category DC = 60).
pub const DC_ENTRY_LEN: usize = 24;

/// Longest device name (order/name/group/image string of the General
/// category) the encoder accepts: ethercrab 0.7.1 reads these into a
/// 64-byte string and rejects longer ones.
pub const MAX_NAME_LEN: usize = 64;

/// Mailbox protocol bits of word 0x1C (ETG.2010 Table 2).
pub mod protocols {
    /// ADS over EtherCAT.
    pub const AOE: u16 = 0x0001;
    /// Ethernet over EtherCAT.
    pub const EOE: u16 = 0x0002;
    /// CANopen over EtherCAT.
    pub const COE: u16 = 0x0004;
    /// File access over EtherCAT.
    pub const FOE: u16 = 0x0008;
    /// Servo drive profile over EtherCAT.
    pub const SOE: u16 = 0x0010;
    /// Vendor specific protocol over EtherCAT.
    pub const VOE: u16 = 0x0020;
}

/// PDO flag bits of a TxPDO/RxPDO category header (ETG.2010 Table 14,
/// offset 6), with the ESI (ETG.2000 `PdoType`) attribute each mirrors.
/// The values agree with SOES's `siitool` and IgH's SII reader.
pub mod pdo_flags {
    /// `Mandatory="1"`: the PDO must be assigned.
    pub const MANDATORY: u16 = 0x0001;
    /// PDO assigned by default (`Sm` present in the ESI).
    pub const DEFAULT: u16 = 0x0002;
    /// Oversampling PDO (`OSFac`).
    pub const OVERSAMPLE: u16 = 0x0004;
    /// `Fixed="1"`: the PDO's entries cannot be changed.
    pub const FIXED_CONTENT: u16 = 0x0010;
    /// `Virtual="1"`: the PDO's content is virtual.
    pub const VIRTUAL_CONTENT: u16 = 0x0020;
    /// The master downloads the PDO even when it is the default.
    pub const DOWNLOAD_ANYWAY: u16 = 0x0040;
    /// The PDO belongs to a module.
    pub const FROM_MODULE: u16 = 0x0080;
    /// Module aligned.
    pub const MODULE_ALIGN: u16 = 0x0100;
    /// Depends on the slot.
    pub const DEPEND_ON_SLOT: u16 = 0x0200;
    /// Depends on the slot group.
    pub const DEPEND_ON_SLOT_GROUP: u16 = 0x0400;
    /// `OverwrittenByModule="1"`.
    pub const OVERWRITTEN_BY_MODULE: u16 = 0x0800;
    /// The PDO is configurable.
    pub const CONFIGURABLE: u16 = 0x1000;
    /// Automatic PDO name.
    pub const AUTO_PDO_NAME: u16 = 0x2000;
    /// Automatic exclusion disabled.
    pub const DIS_AUTO_EXCLUDE: u16 = 0x4000;
    /// The PDO is writable.
    pub const WRITABLE: u16 = 0x8000;
}

/// Everything that can go wrong while encoding or reading an SII image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SiiError {
    /// The image is shorter than the fixed header (ETG.2010 Table 2 needs
    /// words 0x00..0x3F, 128 bytes).
    #[error("SII image too short: {len} bytes, the header alone needs 128")]
    ImageTooShort {
        /// Length of the image given.
        len: usize,
    },
    /// The output buffer cannot hold the encoded image.
    #[error("SII output buffer too small: {needed} bytes needed, {available} available")]
    BufferTooSmall {
        /// Bytes needed at least (may grow once more is encoded).
        needed: usize,
        /// Length of the buffer given.
        available: usize,
    },
    /// The encoded image does not fit the EEPROM size declared in word 0x3E.
    #[error("SII image of {used} bytes exceeds the declared EEPROM size of {eeprom_bytes} bytes")]
    ImageTooLarge {
        /// Bytes used up to and including the End marker.
        used: usize,
        /// Declared EEPROM size in bytes.
        eeprom_bytes: usize,
    },
    /// A category's length runs past the end of the image (ETG.2010 Table 3).
    #[error(
        "SII category at word {word_offset:#06x} with {len_words} words runs past the image end"
    )]
    CategoryOverrun {
        /// Word address of the category header.
        word_offset: u16,
        /// Length field of the category, in words.
        len_words: u16,
    },
    /// A category is shorter than its fixed structure.
    #[error("SII category type {category} has {len} bytes, fewer than its structure needs")]
    CategoryTooShort {
        /// Raw category type.
        category: u16,
        /// Data length in bytes.
        len: usize,
    },
    /// A category would need more than 0xFFFF words.
    #[error("SII category type {category} would exceed 65535 words")]
    CategoryTooLong {
        /// Raw category type.
        category: u16,
    },
    /// A string of the Strings category runs past the category end
    /// (ETG.2010 Table 6).
    #[error("SII string {index} runs past the end of the Strings category")]
    StringOverrun {
        /// 1-based string index.
        index: u8,
    },
    /// A string is not valid UTF-8.
    #[error("SII string {index} is not valid UTF-8")]
    InvalidUtf8 {
        /// 1-based string index.
        index: u8,
    },
    /// More than 255 distinct strings (the Strings count is a u8).
    #[error("SII image needs more than 255 distinct strings")]
    TooManyStrings,
    /// A string is longer than allowed (255 for any string, 64 for names).
    #[error("SII string of {len} bytes exceeds the limit of {max}")]
    StringTooLong {
        /// Length of the string in bytes.
        len: usize,
        /// Limit that applies to it.
        max: usize,
    },
    /// A PDO header or its entries run past the end of the PDO category
    /// (ETG.2010 Tables 14, 15).
    #[error("SII PDO {index:#06x} runs past the end of its category")]
    PdoOverrun {
        /// PDO index from the header (0 if the header itself is cut).
        index: u16,
    },
    /// A PDO has more than 255 entries.
    #[error("SII PDO {pdo:#06x} has more than 255 entries")]
    TooManyEntries {
        /// PDO index.
        pdo: u16,
    },
    /// A configuration field holds a value the encoder refuses (ETG.2010
    /// reserved bits, or values ethercrab 0.7.1 rejects).
    #[error("SII field {field} has invalid value {value:#x}")]
    InvalidField {
        /// Name of the field.
        field: &'static str,
        /// Offending value.
        value: u32,
    },
}

/// Identity object in words 0x08..0x0F (ETG.2010 Table 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SiiIdentity {
    /// Vendor id (word 0x08).
    pub vendor_id: u32,
    /// Product code (word 0x0A).
    pub product_code: u32,
    /// Revision number (word 0x0C).
    pub revision: u32,
    /// Serial number (word 0x0E).
    pub serial: u32,
}

/// A mailbox configuration, words 0x14..0x17 (bootstrap) or 0x18..0x1B
/// (standard) of ETG.2010 Table 2.
///
/// `rx` is the slave's receive mailbox, written by the master (SM0); `tx` is
/// the slave's send mailbox, read by the master (SM1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SiiMailbox {
    /// Receive (master-to-slave) mailbox start address.
    pub rx_offset: u16,
    /// Receive mailbox size in bytes.
    pub rx_size: u16,
    /// Send (slave-to-master) mailbox start address.
    pub tx_offset: u16,
    /// Send mailbox size in bytes.
    pub tx_size: u16,
}

/// Sync manager type byte (offset 7) of a SyncM element (ETG.2010 Table 9).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SmType {
    /// 0: not used or unknown.
    Unused,
    /// 1: mailbox out (master to slave).
    MailboxOut,
    /// 2: mailbox in (slave to master).
    MailboxIn,
    /// 3: process data out (outputs).
    ProcessOut,
    /// 4: process data in (inputs).
    ProcessIn,
    /// Any other value.
    Unknown(u8),
}

impl SmType {
    /// Decodes the type byte (ETG.2010 Table 9).
    pub const fn from_raw(raw: u8) -> Self {
        match raw {
            0 => Self::Unused,
            1 => Self::MailboxOut,
            2 => Self::MailboxIn,
            3 => Self::ProcessOut,
            4 => Self::ProcessIn,
            other => Self::Unknown(other),
        }
    }

    /// The type byte (ETG.2010 Table 9).
    pub const fn raw(self) -> u8 {
        match self {
            Self::Unused => 0,
            Self::MailboxOut => 1,
            Self::MailboxIn => 2,
            Self::ProcessOut => 3,
            Self::ProcessIn => 4,
            Self::Unknown(other) => other,
        }
    }
}

/// One element of the SyncM category (ETG.2010 Table 9). The status byte
/// (offset 5) is written as 0 and not decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SiiSyncManager {
    /// Physical start address.
    pub start: u16,
    /// Length in bytes.
    pub length: u16,
    /// Control register value (ESC register 0x0804).
    pub control: u8,
    /// Enable byte: bit 0 enable, bit 1 fixed content, bit 2 virtual,
    /// bit 3 opOnly. The encoder refuses other bits (ethercrab rejects them).
    pub enable: u8,
    /// Usage type.
    pub sm_type: SmType,
}

/// One byte of the FMMU category (ETG.2010 Table 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FmmuUsage {
    /// 0x00: unused.
    Unused,
    /// 0x01: used for outputs.
    Outputs,
    /// 0x02: used for inputs.
    Inputs,
    /// 0x03: used for the SyncM (mailbox) status.
    SyncMStatus,
    /// 0xFF: not used (also the padding byte of an odd count).
    NotUsed,
    /// Any other value (refused by the encoder).
    Unknown(u8),
}

impl FmmuUsage {
    /// Decodes a usage byte (ETG.2010 Table 8).
    pub const fn from_raw(raw: u8) -> Self {
        match raw {
            0x00 => Self::Unused,
            0x01 => Self::Outputs,
            0x02 => Self::Inputs,
            0x03 => Self::SyncMStatus,
            0xFF => Self::NotUsed,
            other => Self::Unknown(other),
        }
    }

    /// The usage byte (ETG.2010 Table 8).
    pub const fn raw(self) -> u8 {
        match self {
            Self::Unused => 0x00,
            Self::Outputs => 0x01,
            Self::Inputs => 0x02,
            Self::SyncMStatus => 0x03,
            Self::NotUsed => 0xFF,
            Self::Unknown(other) => other,
        }
    }
}

/// One PDO entry to encode (ETG.2010 Table 15). The entry flags are written
/// as 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SiiPdoEntry<'a> {
    /// Object index (0 for a padding entry).
    pub index: u16,
    /// Subindex (0 for a padding entry).
    pub sub: u8,
    /// Entry name; empty for none (string index 0).
    pub name: &'a str,
    /// CoE base data type code (ETG.1000.6 Table 64: BOOL 1, UINT 6, ...),
    /// 0 for padding.
    pub data_type: u8,
    /// Length in bits.
    pub bit_len: u8,
}

/// One PDO to encode (ETG.2010 Table 14).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SiiPdo<'a> {
    /// PDO index (0x1600.. receive, 0x1A00.. transmit).
    pub index: u16,
    /// Sync manager it is assigned to by default; `None` is written as 0xFF
    /// (not assigned, an alternative PDO).
    pub sm: Option<u8>,
    /// PDO name; empty for none.
    pub name: &'a str,
    /// PDO flags (ETG.2010 Table 14 offset 6: bit 0 mandatory, bit 1
    /// default, bit 4 fixed content, ...).
    pub flags: u16,
    /// Mapped entries in order.
    pub entries: &'a [SiiPdoEntry<'a>],
}

/// General category content to encode (ETG.2010 Table 7), strings given as
/// text. Empty strings are written as index 0 (none).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SiiGeneral<'a> {
    /// Group type (ESI `GroupType`), byte 0 and its duplicate at byte 14.
    pub group: &'a str,
    /// Image name, byte 1.
    pub image: &'a str,
    /// Order code (ESI `Type`), byte 2; ethercrab shows it as the device name.
    pub order: &'a str,
    /// Device name (ESI `Name`), byte 3.
    pub name: &'a str,
    /// CoE details, byte 5: bit 0 SDO, bit 1 SDO info, bit 2 PDO assign,
    /// bit 3 PDO configuration, bit 4 upload at startup, bit 5 SDO complete
    /// access.
    pub coe_details: u8,
    /// FoE details, byte 6: bit 0 FoE enabled.
    pub foe_details: u8,
    /// EoE details, byte 7: bit 0 EoE enabled.
    pub eoe_details: u8,
    /// Flags, byte 11: bit 0 enable SAFEOP, bit 1 enable notLRW, bit 2
    /// mailbox data link layer, bit 3 identity via AL status code, bit 4
    /// identity via physical memory.
    pub flags: u8,
    /// Current consumption on E-Bus in mA, bytes 12..13 (negative: feeds).
    pub current_on_ebus: i16,
    /// Physical ports, bytes 16..17: one nibble per port (0 unused, 1 MII,
    /// 2 reserved, 3 EBUS, 4 fast hot connect); two MII ports: 0x0011.
    pub physical_port: u16,
}

/// What [`encode`] writes (ETG.2010 Table 2 header plus categories).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SiiConfig<'a> {
    /// PDI control, word 0x00 (ESC register 0x0140).
    pub pdi_control: u16,
    /// PDI configuration, word 0x01 (ESC register 0x0150).
    pub pdi_config: u16,
    /// SYNC impulse length in 10 ns units, word 0x02 (ESC register 0x0982).
    pub sync_impulse: u16,
    /// PDI configuration 2, word 0x03 (ESC register 0x0152).
    pub pdi_config2: u16,
    /// Configured station alias, word 0x04 (ESC register 0x0012).
    pub station_alias: u16,
    /// Identity, words 0x08..0x0F.
    pub identity: SiiIdentity,
    /// Bootstrap mailbox, words 0x14..0x17.
    pub bootstrap_mailbox: SiiMailbox,
    /// Standard mailbox, words 0x18..0x1B.
    pub standard_mailbox: SiiMailbox,
    /// Supported mailbox protocols, word 0x1C (see [`protocols`]); only bits
    /// 0..5 are accepted.
    pub mailbox_protocols: u16,
    /// EEPROM size in KiBit (word 0x3E holds this minus one); at least 1.
    pub eeprom_kbit: u16,
    /// General category.
    pub general: SiiGeneral<'a>,
    /// FMMU category, one usage per FMMU (written even when empty, since
    /// ethercrab expects the category).
    pub fmmus: &'a [FmmuUsage],
    /// SyncM category, one element per sync manager.
    pub sync_managers: &'a [SiiSyncManager],
    /// TxPDO category (slave to master); omitted when empty.
    pub tx_pdos: &'a [SiiPdo<'a>],
    /// RxPDO category (master to slave); omitted when empty.
    pub rx_pdos: &'a [SiiPdo<'a>],
}

/// Category type word (ETG.2010 Table 3). Bit 15 marks a vendor-specific
/// category; those and every unlisted value decode as [`Self::Unknown`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CategoryType {
    /// 0: no operation.
    Nop,
    /// 1..=9: device specific.
    DeviceSpecific(u16),
    /// 10: strings.
    Strings,
    /// 20: data types.
    DataTypes,
    /// 30: general.
    General,
    /// 40: FMMU usage.
    Fmmu,
    /// 41: sync managers.
    SyncM,
    /// 42: FMMU extended (ETG.2010 Table 10).
    FmmuX,
    /// 43: sync units.
    SyncUnit,
    /// 50: TxPDO (slave to master).
    TxPdo,
    /// 51: RxPDO (master to slave).
    RxPdo,
    /// 60: distributed clock.
    Dc,
    /// 70: timeouts.
    Timeouts,
    /// 80: dictionary.
    Dictionary,
    /// 90: hardware.
    Hardware,
    /// 0x0800..=0x0FFF: vendor specific.
    Vendor(u16),
    /// 0xFFFF: end of the category chain.
    End,
    /// Any other value, including those with bit 15 set.
    Unknown(u16),
}

impl CategoryType {
    /// Decodes a category type word (ETG.2010 Table 3).
    pub const fn from_raw(raw: u16) -> Self {
        match raw {
            0 => Self::Nop,
            1..=9 => Self::DeviceSpecific(raw),
            10 => Self::Strings,
            20 => Self::DataTypes,
            30 => Self::General,
            40 => Self::Fmmu,
            41 => Self::SyncM,
            42 => Self::FmmuX,
            43 => Self::SyncUnit,
            50 => Self::TxPdo,
            51 => Self::RxPdo,
            60 => Self::Dc,
            70 => Self::Timeouts,
            80 => Self::Dictionary,
            90 => Self::Hardware,
            0x0800..=0x0FFF => Self::Vendor(raw),
            0xFFFF => Self::End,
            other => Self::Unknown(other),
        }
    }

    /// The category type word (ETG.2010 Table 3).
    pub const fn raw(self) -> u16 {
        match self {
            Self::Nop => 0,
            Self::Strings => 10,
            Self::DataTypes => 20,
            Self::General => 30,
            Self::Fmmu => 40,
            Self::SyncM => 41,
            Self::FmmuX => 42,
            Self::SyncUnit => 43,
            Self::TxPdo => 50,
            Self::RxPdo => 51,
            Self::Dc => 60,
            Self::Timeouts => 70,
            Self::Dictionary => 80,
            Self::Hardware => 90,
            Self::End => 0xFFFF,
            Self::DeviceSpecific(raw) | Self::Vendor(raw) | Self::Unknown(raw) => raw,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn category_type_round_trips_every_word() {
        for raw in 0..=u16::MAX {
            assert_eq!(CategoryType::from_raw(raw).raw(), raw);
        }
        assert_eq!(CategoryType::from_raw(0x0800), CategoryType::Vendor(0x0800));
        assert_eq!(
            CategoryType::from_raw(0x800A),
            CategoryType::Unknown(0x800A)
        );
        assert_eq!(CategoryType::from_raw(3), CategoryType::DeviceSpecific(3));
    }

    #[test]
    fn fmmu_and_sm_type_bytes_round_trip() {
        for raw in 0..=u8::MAX {
            assert_eq!(FmmuUsage::from_raw(raw).raw(), raw);
            assert_eq!(SmType::from_raw(raw).raw(), raw);
        }
        assert_eq!(FmmuUsage::from_raw(0xFF), FmmuUsage::NotUsed);
        assert_eq!(SmType::from_raw(4), SmType::ProcessIn);
    }
}
