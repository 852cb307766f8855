//! Loading one device of an ESI file (ETG.2000) for a software twin.
//!
//! [`EsiFile::parse`] reads the vendor and every `Descriptions/Devices/Device`
//! of a file; [`EsiFile::device`] picks one by type name and revision. What a
//! twin needs is read into [`EsiDevice`]: identity, names, group, physics,
//! FMMUs, SyncManagers, PDOs (with `Sm`, `Fixed`, `Mandatory`, `Exclude`),
//! mailbox protocols, `<Eeprom>` (`<Data>` or `<ByteSize>`/`<ConfigData>`),
//! E-Bus current, DC op modes and, when the device has one, the object
//! dictionary's objects and data types (to check the PDO entries).
//!
//! Every error names the element and the line it starts on
//! ([`EsiError`]) and refuses only its device ([`EsiFile::refused`]); what
//! the loader cannot model is a [`Warning`] with element and line, and the
//! twin still starts.

use std::collections::BTreeMap;
use std::fmt;

use ecat_slave::sii::{FmmuUsage, SmType};

use crate::xml::{self, Element};

mod read;
mod types;

pub(crate) use read::EEPROM_SIZE;
pub use types::{array_bounds, array_element, base_type_code};

/// Where in the file something is: the element name and its line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct At {
    /// Element name (`RxPdo`, `Entry`, `Sm`).
    pub element: String,
    /// Line of its start tag (1-based).
    pub line: u32,
}

impl At {
    /// Where `e` is.
    pub fn of(e: &Element) -> Self {
        At {
            element: e.name.clone(),
            line: e.line,
        }
    }
}

impl fmt::Display for At {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "<{}> at line {}", self.element, self.line)
    }
}

/// Something of a device's ESI the loader cannot model and leaves out (or
/// reads the way a configurator would): the twin still starts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    /// Where it is.
    pub at: At,
    /// What is skipped or assumed.
    pub message: String,
}

impl Warning {
    /// A warning about `e`.
    pub fn new(e: &Element, message: impl Into<String>) -> Self {
        Warning {
            at: At::of(e),
            message: message.into(),
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.at, self.message)
    }
}

/// Why an ESI file cannot describe a twin.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EsiError {
    /// The file is not well-formed XML.
    #[error("not well-formed XML: {0}")]
    Xml(#[from] xml::XmlError),
    /// The root element is not `EtherCATInfo`.
    #[error("root element is <{0}>, not <EtherCATInfo>")]
    NotEsi(String),
    /// A required element or attribute is missing.
    #[error("{at}: missing {what}")]
    Missing {
        /// The element that lacks it.
        at: At,
        /// What is missing.
        what: &'static str,
    },
    /// A value cannot be read.
    #[error("{at}: bad {what} '{value}'")]
    BadValue {
        /// The element holding it.
        at: At,
        /// What the value is.
        what: &'static str,
        /// The text found.
        value: String,
    },
    /// A PDO entry or object uses a data type the twin does not know.
    #[error("{at}: unknown data type '{name}'")]
    UnknownDataType {
        /// The element.
        at: At,
        /// The type name.
        name: String,
    },
    /// A PDO entry maps an object the device's dictionary does not have.
    #[error("{at}: PDO entry {index:#06x}:{sub:02x} is not an object of the dictionary")]
    EntryNotInDictionary {
        /// The `Entry` element.
        at: At,
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
    },
    /// A SyncManager is smaller than what is assigned to it.
    #[error("{at}: SM{sm} DefaultSize {size} bytes is too small for {needed} bytes ({what})")]
    SmTooSmall {
        /// The `Sm` element.
        at: At,
        /// SyncManager number.
        sm: u8,
        /// Its size.
        size: u16,
        /// Bytes needed.
        needed: u16,
        /// What needs them.
        what: &'static str,
    },
    /// A SyncManager runs past the ESC's 64 KiB address space.
    #[error(
        "{at}: SM{sm} at {start:#06x} with {size} bytes runs past the end of the ESC address space (0xffff)"
    )]
    SmBeyondMemory {
        /// The `Sm` element.
        at: At,
        /// SyncManager number.
        sm: u8,
        /// Its start address.
        start: u16,
        /// Its size.
        size: u16,
    },
    /// A PDO names a SyncManager the device does not have, or one of the
    /// wrong direction.
    #[error("{at}: PDO {index:#06x} is assigned to SM{sm}, which is {problem}")]
    BadPdoSm {
        /// The PDO element.
        at: At,
        /// PDO index.
        index: u16,
        /// The SyncManager.
        sm: u8,
        /// What is wrong with it.
        problem: &'static str,
    },
    /// No device of the file matches the type and revision asked for.
    #[error("no device {wanted} in the file (it has: {known})")]
    NoSuchDevice {
        /// What was asked for.
        wanted: String,
        /// `type rev` of every device of the file.
        known: String,
    },
    /// Several devices match and none was chosen.
    #[error("the file has {count} devices; choose one with --type (it has: {known})")]
    Ambiguous {
        /// How many.
        count: usize,
        /// `type rev` of every device.
        known: String,
    },
}

/// One SyncManager of the ESI (`Device/Sm`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiSm {
    /// Physical start address.
    pub start: u16,
    /// `DefaultSize` (0 when absent: the master sizes it).
    pub default_size: u16,
    /// Control register byte.
    pub control: u8,
    /// SII enable byte: bit 0 enable, bit 1 fixed, bit 2 virtual, bit 3 OpOnly.
    pub enable: u8,
    /// Usage from the text (`MBoxOut`, `MBoxIn`, `Outputs`, `Inputs`).
    pub kind: SmType,
    /// Where it is.
    pub at: At,
}

/// One entry of a PDO.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiPdoEntry {
    /// Object index (0: padding).
    pub index: u16,
    /// Subindex.
    pub sub: u8,
    /// Bit length.
    pub bit_len: u8,
    /// Name.
    pub name: String,
    /// CoE data type code (0 for padding).
    pub data_type: u8,
}

/// One PDO (`Device/RxPdo` or `Device/TxPdo`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiPdo {
    /// PDO index.
    pub index: u16,
    /// Name.
    pub name: String,
    /// Default SyncManager (`Sm` attribute).
    pub sm: Option<u8>,
    /// SII PDO flags (mandatory, fixed, ...).
    pub flags: u16,
    /// PDOs this one excludes.
    pub excludes: Vec<u16>,
    /// Mapped entries.
    pub entries: Vec<EsiPdoEntry>,
    /// Where it is.
    pub at: At,
}

impl EsiPdo {
    /// Total bit length of the entries.
    pub fn bits(&self) -> u32 {
        self.entries
            .iter()
            .fold(0u32, |acc, e| acc.saturating_add(u32::from(e.bit_len)))
    }
}

/// One DC operation mode (`Device/Dc/OpMode`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiDcMode {
    /// Name.
    pub name: String,
    /// `AssignActivate` (register 0x0980 value).
    pub assign_activate: u16,
}

/// One device of an ESI file, as far as a twin needs it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiDevice {
    /// Vendor ID.
    pub vendor_id: u32,
    /// Vendor name.
    pub vendor_name: String,
    /// Order code (`Type`).
    pub type_name: String,
    /// Product code.
    pub product_code: u32,
    /// Revision number.
    pub revision: u32,
    /// Device name (`Name`, the first one).
    pub name: String,
    /// Group type.
    pub group_type: String,
    /// Group name (from `Descriptions/Groups`).
    pub group_name: String,
    /// `Physics` attribute (`YY`, `KK`, `YKY`).
    pub physics: String,
    /// FMMU usages in order.
    pub fmmus: Vec<FmmuUsage>,
    /// SyncManagers in order.
    pub sms: Vec<EsiSm>,
    /// RxPDOs (master to slave).
    pub rx_pdos: Vec<EsiPdo>,
    /// TxPDOs (slave to master).
    pub tx_pdos: Vec<EsiPdo>,
    /// Mailbox protocols (SII word 0x1C bits); 0 without a mailbox.
    pub mailbox_protocols: u16,
    /// CoE details byte for the SII General category.
    pub coe_details: u8,
    /// `Eeprom/Data`: the whole SII image, served verbatim.
    pub eeprom_data: Option<Vec<u8>>,
    /// `Eeprom/ByteSize`.
    pub eeprom_bytes: Option<u32>,
    /// `Eeprom/ConfigData`: SII words 0x00.. (PDI control, config, ...).
    pub config_data: Vec<u8>,
    /// `Info/Electrical/EBusCurrent`, mA (negative: the device feeds the E-Bus).
    pub ebus_current_ma: i16,
    /// DC operation modes.
    pub dc_modes: Vec<EsiDcMode>,
    /// Objects of the dictionary: `(index, sub)` → bit length; empty when
    /// the ESI has no `Profile/Dictionary`.
    pub objects: BTreeMap<(u16, u8), u16>,
    /// Where the device is.
    pub at: At,
    /// The whole `Device` element (the dictionary and the vendor-specific
    /// parts are read from it when a twin with a mailbox is built).
    pub source: Element,
    /// The file's `Descriptions/Modules` (module types of modular
    /// devices), when the device has `Slots`.
    pub modules: Option<Element>,
    /// What the loader left out or assumed, with element and line.
    pub warnings: Vec<Warning>,
}

impl EsiDevice {
    /// `TYPE rev 0x...`, for messages.
    pub fn label(&self) -> String {
        format!("{} rev {:#010x}", self.type_name, self.revision)
    }

    /// Whether the device has a mailbox (and so a firmware behind its
    /// ESC): a mailbox SyncManager or a mailbox protocol.
    pub fn has_mailbox(&self) -> bool {
        self.mailbox_protocols != 0
            || self
                .sms
                .iter()
                .any(|s| matches!(s.kind, SmType::MailboxOut | SmType::MailboxIn))
    }

    /// Bytes of process data the default PDO assignment puts on `sm`.
    pub fn sm_bytes(&self, sm: u8) -> u16 {
        let bits: u32 = self
            .rx_pdos
            .iter()
            .chain(&self.tx_pdos)
            .filter(|p| p.sm == Some(sm))
            .map(EsiPdo::bits)
            .fold(0, u32::saturating_add);
        u16::try_from(bits.div_ceil(8)).unwrap_or(u16::MAX)
    }

    /// Output (RxPDO) bytes of the default assignment.
    pub fn output_bytes(&self) -> u16 {
        self.pd_bytes(&self.rx_pdos)
    }

    /// Input (TxPDO) bytes of the default assignment.
    pub fn input_bytes(&self) -> u16 {
        self.pd_bytes(&self.tx_pdos)
    }

    /// The EEPROM size in kbit the SII declares: `ByteSize / 128`, at
    /// least 1; 16 without a `<ByteSize>`. `None` beyond the SII's 65535
    /// kbit (a load error: [`EsiFile::parse`] refuses such a file).
    pub fn eeprom_kbit(&self) -> Option<u16> {
        match self.eeprom_bytes {
            None => Some(16),
            Some(b) => u16::try_from(b / 128).ok().map(|k| k.max(1)),
        }
    }

    fn pd_bytes(&self, pdos: &[EsiPdo]) -> u16 {
        // Per SyncManager, rounded up to whole bytes (as a master sizes
        // the SMs).
        let mut sms: Vec<u8> = pdos.iter().filter_map(|p| p.sm).collect();
        sms.sort_unstable();
        sms.dedup();
        sms.iter()
            .map(|sm| self.sm_bytes(*sm))
            .fold(0, u16::saturating_add)
    }
}

/// A parsed ESI file: its vendor and devices.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiFile {
    /// Every device of the file that loads, in file order.
    pub devices: Vec<EsiDevice>,
    /// The devices that do not load: `TYPE rev 0x...` (as far as it can be
    /// read) and why, with element and line.
    pub refused: Vec<(String, EsiError)>,
    /// The file's `Descriptions/Modules`, or the `Modules` of a module
    /// library (an `EtherCATModule` file, ETG.2000: module types that
    /// devices of other files plug into their slots).
    pub modules: Option<Element>,
}

#[cfg(test)]
mod tests;
