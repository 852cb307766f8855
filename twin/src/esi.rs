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

use ecat_slave::sii::{FmmuUsage, SmType, pdo_flags, protocols};

use crate::xml::{self, Element, hex_binary};

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

fn number(e: &Element, text: &str, what: &'static str) -> Result<i64, EsiError> {
    let t = text.trim();
    xml::number(t).ok_or_else(|| EsiError::BadValue {
        at: At::of(e),
        what,
        value: t.to_string(),
    })
}

fn ranged<T: TryFrom<i64>>(e: &Element, text: &str, what: &'static str) -> Result<T, EsiError> {
    let v = number(e, text, what)?;
    T::try_from(v).map_err(|_| EsiError::BadValue {
        at: At::of(e),
        what,
        value: text.trim().to_string(),
    })
}

fn attr_num<T: TryFrom<i64>>(
    e: &Element,
    name: &str,
    what: &'static str,
) -> Result<Option<T>, EsiError> {
    e.attr(name).map(|v| ranged(e, v, what)).transpose()
}

fn child_num<T: TryFrom<i64>>(
    e: &Element,
    name: &str,
    what: &'static str,
) -> Result<Option<T>, EsiError> {
    e.child(name).map(|c| ranged(c, &c.text, what)).transpose()
}

fn required<T>(v: Option<T>, e: &Element, what: &'static str) -> Result<T, EsiError> {
    v.ok_or_else(|| EsiError::Missing {
        at: At::of(e),
        what,
    })
}

fn flag(e: &Element, name: &str) -> bool {
    matches!(e.attr(name), Some("1" | "true"))
}

/// The CoE code of a base data type name of ETG.2000 (`BOOL`, `UINT`,
/// `BIT3`, `STRING(8)`, `BITARR16`, `ARRAY [0..3] OF BYTE`...), `None` for a
/// name it does not know. An array held as one value reports its element's
/// code, an array of `BYTE` `OCTET_STRING` (what the SSC's ESI writes for an
/// octet string, docs/MANUAL-NOTES.md).
pub fn base_type_code(name: &str) -> Option<u8> {
    if let Some(element) = array_element(name) {
        return match element {
            "BYTE" => Some(0x0A),
            e => base_type_code(e),
        };
    }
    let t = ecat_slave::od::types::base_type_named(name)?;
    u8::try_from(t.code).ok()
}

/// The element type of an ETG.2000 array type name `ARRAY [lo..hi] OF T`
/// (blanks as written), `None` for any other name.
pub fn array_element(name: &str) -> Option<&str> {
    let rest = name.trim().strip_prefix("ARRAY")?.trim_start();
    let rest = rest.strip_prefix('[')?;
    let (_, element) = rest.split_once(']')?;
    Some(element.trim_start().strip_prefix("OF")?.trim())
}

/// The bounds of an ETG.2000 array type name `ARRAY [lo..hi] OF T`.
pub fn array_bounds(name: &str) -> Option<(i64, i64)> {
    let rest = name.trim().strip_prefix("ARRAY")?.trim_start();
    let (bounds, _) = rest.strip_prefix('[')?.split_once(']')?;
    let (lo, hi) = bounds.split_once("..")?;
    Some((lo.trim().parse().ok()?, hi.trim().parse().ok()?))
}

/// Device-specific data types of a dictionary: name → base type code.
fn dictionary_types(dict: &Element) -> BTreeMap<String, u8> {
    let mut types = BTreeMap::new();
    let Some(dts) = dict.child("DataTypes") else {
        return types;
    };
    // A named type resolves to its BaseType, or to itself when it is an
    // array/record/enum (the code of the PDO entry is then the base of
    // its elements, which the SII does not need exactly).
    for dt in dts.children_named("DataType") {
        let Some(name) = dt.text_at("Name") else {
            continue;
        };
        let base = dt
            .text_at("BaseType")
            .and_then(base_type_code)
            .map(|c| {
                if dt.child("ArrayInfo").is_some() && c == 0x1E {
                    0x0A
                } else {
                    c
                }
            })
            .or_else(|| base_type_code(name));
        match base {
            Some(code) => {
                types.insert(name.to_string(), code);
            }
            None if dt.child("EnumInfo").is_some() || dt.child("SubItem").is_some() => {
                // Enumerations and records: known, an unsigned of their size.
                types.insert(name.to_string(), 0x07);
            }
            None => {}
        }
    }
    types
}

/// `(index, sub)` → bit length of every object of a dictionary (what it
/// cannot read it leaves out: the dictionary itself is read, with its
/// errors and warnings, when a twin is built).
fn dictionary_objects(dict: &Element) -> BTreeMap<(u16, u8), u16> {
    let mut out = BTreeMap::new();
    let Some(objs) = dict.child("Objects") else {
        return out;
    };
    let n = |e: &Element, name: &str| -> Option<i64> { e.text_at(name).and_then(xml::number) };
    // Bit sizes of the named record/array types, per subindex.
    let mut type_subs: BTreeMap<&str, Vec<(u8, u16)>> = BTreeMap::new();
    if let Some(dts) = dict.child("DataTypes") {
        for dt in dts.children_named("DataType") {
            let Some(name) = dt.text_at("Name") else {
                continue;
            };
            let subs = dt
                .children_named("SubItem")
                .map(|si| {
                    let sub = n(si, "SubIdx")
                        .and_then(|v| u8::try_from(v).ok())
                        .unwrap_or(0);
                    let bits = n(si, "BitSize")
                        .and_then(|v| u16::try_from(v).ok())
                        .unwrap_or(0);
                    (sub, bits)
                })
                .collect();
            type_subs.insert(name.trim(), subs);
        }
    }
    for o in objs.children_named("Object") {
        let Some(index) = n(o, "Index").and_then(|v| u16::try_from(v).ok()) else {
            continue;
        };
        let bits = n(o, "BitSize")
            .and_then(|v| u16::try_from(v).ok())
            .unwrap_or(0);
        let ty = o.text_at("Type").unwrap_or("").trim();
        match type_subs.get(ty).filter(|s| !s.is_empty()) {
            Some(subs) => {
                for (sub, b) in subs {
                    out.insert((index, *sub), *b);
                }
                // Array types list one element; the object's Info says
                // how many subindices exist.
                if let Some(info) = o.child("Info") {
                    for si in info.children_named("SubItem") {
                        if let Some(name) = si.text_at("Name")
                            && let Some(s) = name
                                .strip_prefix("SubIndex ")
                                .and_then(|s| s.trim().parse::<u8>().ok())
                        {
                            let b = subs.last().map_or(0, |l| l.1);
                            out.entry((index, s)).or_insert(b);
                        }
                    }
                }
            }
            None => {
                out.insert((index, 0), bits);
            }
        }
    }
    out
}

fn sm_kind(e: &Element) -> Result<SmType, EsiError> {
    Ok(match e.text.trim() {
        "MBoxOut" => SmType::MailboxOut,
        "MBoxIn" => SmType::MailboxIn,
        "Outputs" => SmType::ProcessOut,
        "Inputs" => SmType::ProcessIn,
        "" => SmType::Unused,
        other => {
            return Err(EsiError::BadValue {
                at: At::of(e),
                what: "SyncManager type",
                value: other.to_string(),
            });
        }
    })
}

fn parse_pdo(
    p: &Element,
    types: &BTreeMap<String, u8>,
    warnings: &mut Vec<Warning>,
) -> Result<EsiPdo, EsiError> {
    let index: u16 = required(child_num(p, "Index", "PDO Index")?, p, "<Index>")?;
    let sm: Option<u8> = attr_num(p, "Sm", "Sm")?;
    let mut flags = 0u16;
    if flag(p, "Mandatory") {
        flags |= pdo_flags::MANDATORY;
    }
    if flag(p, "Fixed") {
        flags |= pdo_flags::FIXED_CONTENT;
    }
    if flag(p, "Virtual") {
        flags |= pdo_flags::VIRTUAL_CONTENT;
    }
    let mut excludes = Vec::new();
    for x in p.children_named("Exclude") {
        excludes.push(ranged(x, &x.text, "Exclude")?);
    }
    let mut entries = Vec::new();
    for en in p.children_named("Entry") {
        let eindex: u16 = required(child_num(en, "Index", "entry Index")?, en, "<Index>")?;
        let bit_len: u8 = required(child_num(en, "BitLen", "BitLen")?, en, "<BitLen>")?;
        let sub: u8 = child_num(en, "SubIndex", "SubIndex")?.unwrap_or(0);
        let name = en.text_at("Name").unwrap_or("").to_string();
        if eindex == 0 && bit_len == 0 {
            // Padding of no bits: nothing to map.
            continue;
        }
        let data_type = if eindex == 0 {
            0
        } else {
            match en.child("DataType") {
                None => {
                    warnings.push(Warning::new(
                        en,
                        format!("PDO entry {eindex:#06x}:{sub:02x} has no <DataType>: typed by its {bit_len} bits"),
                    ));
                    0
                }
                Some(dt) => {
                    match base_type_code(&dt.text).or_else(|| types.get(dt.text.trim()).copied()) {
                        Some(c) => c,
                        None => {
                            warnings.push(Warning::new(
                            dt,
                            format!(
                                "PDO entry {eindex:#06x}:{sub:02x}: unknown data type '{}': typed by its {bit_len} bits",
                                dt.text.trim()
                            ),
                        ));
                            0
                        }
                    }
                }
            }
        };
        entries.push(EsiPdoEntry {
            index: eindex,
            sub,
            bit_len,
            name,
            data_type,
        });
    }
    Ok(EsiPdo {
        index,
        name: p.text_at("Name").unwrap_or("").to_string(),
        sm,
        flags,
        excludes,
        entries,
        at: At::of(p),
    })
}

fn first_name(e: &Element) -> String {
    // Several `Name`s with LcId: prefer English (1033), else the first.
    e.children_named("Name")
        .find(|n| n.attr("LcId") == Some("1033"))
        .or_else(|| e.child("Name"))
        .map(|n| n.text.clone())
        .unwrap_or_default()
}

fn parse_device(
    d: &Element,
    vendor_id: u32,
    vendor_name: &str,
    groups: &BTreeMap<String, String>,
) -> Result<EsiDevice, EsiError> {
    let ty = required(d.child("Type"), d, "<Type>")?;
    let product_code: u32 = attr_num(ty, "ProductCode", "ProductCode")?.unwrap_or(0);
    let revision: u32 = attr_num(ty, "RevisionNo", "RevisionNo")?.unwrap_or(0);
    let group_type = d.text_at("GroupType").unwrap_or("").to_string();
    let dict = d.path("Profile/Dictionary");
    let types = dict.map(dictionary_types).unwrap_or_default();
    let objects = dict.map(dictionary_objects).unwrap_or_default();
    let mut fmmus = Vec::new();
    for f in d.children_named("Fmmu") {
        fmmus.push(match f.text.trim() {
            "Outputs" => FmmuUsage::Outputs,
            "Inputs" => FmmuUsage::Inputs,
            "MBoxState" => FmmuUsage::SyncMStatus,
            "" => FmmuUsage::NotUsed,
            other => {
                return Err(EsiError::BadValue {
                    at: At::of(f),
                    what: "FMMU usage",
                    value: other.to_string(),
                });
            }
        });
    }
    let mut sms = Vec::new();
    for s in d.children_named("Sm") {
        let start: u16 = required(
            attr_num(s, "StartAddress", "StartAddress")?,
            s,
            "StartAddress attribute",
        )?;
        let mut enable: u8 = attr_num::<u8>(s, "Enable", "Enable")?.unwrap_or(0) & 0x01;
        if flag(s, "Virtual") {
            enable |= 0x04;
        }
        if flag(s, "OpOnly") {
            enable |= 0x08;
        }
        sms.push(EsiSm {
            start,
            default_size: attr_num(s, "DefaultSize", "DefaultSize")?.unwrap_or(0),
            control: attr_num(s, "ControlByte", "ControlByte")?.unwrap_or(0),
            enable,
            kind: sm_kind(s)?,
            at: At::of(s),
        });
    }
    let mut warnings = Vec::new();
    let mut rx_pdos = Vec::new();
    for p in d.children_named("RxPdo") {
        rx_pdos.push(parse_pdo(p, &types, &mut warnings)?);
    }
    let mut tx_pdos = Vec::new();
    for p in d.children_named("TxPdo") {
        tx_pdos.push(parse_pdo(p, &types, &mut warnings)?);
    }
    let mut mailbox_protocols = 0u16;
    let mut coe_details = 0u8;
    if let Some(m) = d.child("Mailbox") {
        for (name, bit) in [
            ("AoE", protocols::AOE),
            ("EoE", protocols::EOE),
            ("CoE", protocols::COE),
            ("FoE", protocols::FOE),
            ("SoE", protocols::SOE),
            ("VoE", protocols::VOE),
        ] {
            if m.child(name).is_some() {
                mailbox_protocols |= bit;
            }
        }
        if let Some(c) = m.child("CoE") {
            coe_details = 0x01
                | u8::from(flag(c, "SdoInfo")) << 1
                | u8::from(flag(c, "PdoAssign")) << 2
                | u8::from(flag(c, "PdoConfig")) << 3
                | u8::from(flag(c, "PdoUpload")) << 4
                | u8::from(flag(c, "CompleteAccess")) << 5;
        }
    }
    let ee = d.child("Eeprom");
    let eeprom_data = match ee.and_then(|e| e.child("Data")) {
        Some(data) => Some(hex_binary(&data.text).ok_or_else(|| EsiError::BadValue {
            at: At::of(data),
            what: "hexBinary",
            value: data.text.chars().take(16).collect(),
        })?),
        None => None,
    };
    let config_data = match ee.and_then(|e| e.child("ConfigData")) {
        Some(cd) => hex_binary(&cd.text).ok_or_else(|| EsiError::BadValue {
            at: At::of(cd),
            what: "hexBinary",
            value: cd.text.clone(),
        })?,
        None => Vec::new(),
    };
    let eeprom_bytes: Option<u32> = match ee {
        Some(e) => child_num(e, "ByteSize", "ByteSize")?,
        None => None,
    };
    if let (Some(b), Some(el)) = (eeprom_bytes, ee.and_then(|e| e.child("ByteSize")))
        && b / 128 > u32::from(u16::MAX)
    {
        return Err(EsiError::BadValue {
            at: At::of(el),
            what: EEPROM_SIZE,
            value: el.text.clone(),
        });
    }
    // ETG.2000: `Device/Info/Electrical/EBusCurrent`.
    let ebus_current_ma = match d.child("Info").and_then(|i| i.child("Electrical")) {
        Some(el) => child_num(el, "EBusCurrent", "EBusCurrent")?.unwrap_or(0),
        None => 0,
    };
    let mut dc_modes = Vec::new();
    if let Some(dc) = d.child("Dc") {
        for m in dc.children_named("OpMode") {
            let aa = m
                .child("AssignActivate")
                .map(|a| ranged::<u16>(a, &a.text, "AssignActivate"))
                .transpose()?
                .unwrap_or(0);
            dc_modes.push(EsiDcMode {
                name: m.text_at("Name").unwrap_or("").to_string(),
                assign_activate: aa,
            });
        }
    }
    let dev = EsiDevice {
        vendor_id,
        vendor_name: vendor_name.to_string(),
        type_name: ty.text.clone(),
        product_code,
        revision,
        name: first_name(d),
        group_name: groups.get(&group_type).cloned().unwrap_or_default(),
        group_type,
        physics: d.attr("Physics").unwrap_or("").to_string(),
        fmmus,
        sms,
        rx_pdos,
        tx_pdos,
        mailbox_protocols,
        coe_details,
        eeprom_data,
        eeprom_bytes,
        config_data,
        ebus_current_ma,
        dc_modes,
        objects,
        at: At::of(d),
        source: d.clone(),
        modules: None,
        warnings,
    };
    let mut dev = dev;
    check_sms(&mut dev)?;
    Ok(dev)
}

/// What an EEPROM `ByteSize` beyond the SII's 65535 kbit is called in
/// [`EsiError::BadValue`].
pub(crate) const EEPROM_SIZE: &str = "EEPROM ByteSize (at most 65535 kbit)";

/// The smallest mailbox: a 6-byte header and a 10-byte CoE SDO.
const MIN_MAILBOX: u16 = 16;

fn check_sms(dev: &mut EsiDevice) -> Result<(), EsiError> {
    let mut warnings = Vec::new();
    for (i, s) in dev.sms.iter().enumerate() {
        let sm = u8::try_from(i).unwrap_or(u8::MAX);
        if u32::from(s.start) + u32::from(s.default_size) > 0x1_0000 {
            return Err(EsiError::SmBeyondMemory {
                at: s.at.clone(),
                sm,
                start: s.start,
                size: s.default_size,
            });
        }
        match s.kind {
            SmType::MailboxOut | SmType::MailboxIn if s.default_size < MIN_MAILBOX => {
                return Err(EsiError::SmTooSmall {
                    at: s.at.clone(),
                    sm,
                    size: s.default_size,
                    needed: MIN_MAILBOX,
                    what: "a mailbox header and one CoE SDO",
                });
            }
            SmType::ProcessOut | SmType::ProcessIn => {
                // A master sizes a process-data SyncManager by the PDOs it
                // assigns (ETG.2000 `Sm/DefaultSize` is a default only).
                let needed = dev.sm_bytes(sm);
                if s.default_size != 0 && s.default_size < needed {
                    warnings.push(Warning {
                        at: s.at.clone(),
                        message: format!(
                            "SM{sm} DefaultSize {} bytes is smaller than the {needed} bytes of the PDOs assigned to it: {needed} assumed",
                            s.default_size
                        ),
                    });
                }
            }
            _ => {}
        }
    }
    for (pdos, kind, dir) in [
        (
            &dev.rx_pdos,
            SmType::ProcessOut,
            "not an output SyncManager",
        ),
        (&dev.tx_pdos, SmType::ProcessIn, "not an input SyncManager"),
    ] {
        for p in pdos {
            let Some(sm) = p.sm else { continue };
            match dev.sms.get(usize::from(sm)) {
                None => {
                    return Err(EsiError::BadPdoSm {
                        at: p.at.clone(),
                        index: p.index,
                        sm,
                        problem: "not described by an <Sm>",
                    });
                }
                Some(s) if s.kind != kind => {
                    return Err(EsiError::BadPdoSm {
                        at: p.at.clone(),
                        index: p.index,
                        sm,
                        problem: dir,
                    });
                }
                Some(_) => {}
            }
        }
    }
    dev.warnings.append(&mut warnings);
    Ok(())
}

/// `TYPE rev 0x...` of a `Device` element, as far as it can be read.
fn device_label(d: &Element) -> String {
    let ty = d.child("Type");
    let name = ty.map_or("(no Type)", |t| t.text.trim());
    let rev = ty
        .and_then(|t| t.attr("RevisionNo"))
        .and_then(xml::number)
        .map_or_else(String::new, |r| format!(" rev {r:#010x}"));
    format!("{name}{rev}")
}

impl EsiFile {
    /// Parses the bytes of an ESI file: decoded as its byte order mark or
    /// XML declaration says ([`xml::decode`]), then [`EsiFile::parse`].
    pub fn parse_bytes(bytes: &[u8]) -> Result<Self, EsiError> {
        Self::parse(&xml::decode(bytes)?)
    }

    /// Parses every device of an ESI document (or the modules of a module
    /// library). A device that cannot be read is listed in
    /// [`EsiFile::refused`]; only a file that is not an ESI at all, or
    /// whose vendor cannot be read, is an error.
    pub fn parse(text: &str) -> Result<Self, EsiError> {
        let root = xml::parse(text)?;
        if root.name == "EtherCATModule" {
            return Ok(EsiFile {
                devices: Vec::new(),
                refused: Vec::new(),
                modules: root.child("Modules").cloned(),
            });
        }
        if root.name != "EtherCATInfo" {
            return Err(EsiError::NotEsi(root.name.clone()));
        }
        let vendor = required(root.child("Vendor"), &root, "<Vendor>")?;
        let vendor_id: u32 = required(child_num(vendor, "Id", "vendor Id")?, vendor, "<Id>")?;
        let vendor_name = first_name(vendor);
        let desc = required(root.child("Descriptions"), &root, "<Descriptions>")?;
        let mut groups = BTreeMap::new();
        if let Some(gs) = desc.child("Groups") {
            for g in gs.children_named("Group") {
                if let Some(t) = g.text_at("Type") {
                    groups.insert(t.to_string(), first_name(g));
                }
            }
        }
        let devs = required(desc.child("Devices"), desc, "<Devices>")?;
        let modules = desc.child("Modules").cloned();
        let mut devices = Vec::new();
        let mut refused = Vec::new();
        for d in devs.children_named("Device") {
            match parse_device(d, vendor_id, &vendor_name, &groups) {
                Ok(mut dev) => {
                    if d.child("Slots").is_some() {
                        dev.modules = modules.clone();
                    }
                    devices.push(dev);
                }
                Err(e) => refused.push((device_label(d), e)),
            }
        }
        if devices.is_empty() && refused.is_empty() {
            return Err(EsiError::Missing {
                at: At::of(devs),
                what: "<Device>",
            });
        }
        Ok(EsiFile {
            devices,
            refused,
            modules,
        })
    }

    /// The first refused device's error, if every device of the file was
    /// refused (what a caller that wants one device reports).
    pub fn all_refused(&self) -> Option<&EsiError> {
        if self.devices.is_empty() {
            self.refused.first().map(|(_, e)| e)
        } else {
            None
        }
    }

    fn known(&self) -> String {
        self.devices
            .iter()
            .map(EsiDevice::label)
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The device of type `type_name` (any case) and `revision`; either may
    /// be left out when the file leaves no doubt (the highest revision of
    /// a type is taken when no revision is given).
    pub fn device(
        &self,
        type_name: Option<&str>,
        revision: Option<u32>,
    ) -> Result<&EsiDevice, EsiError> {
        let matching: Vec<&EsiDevice> = self
            .devices
            .iter()
            .filter(|d| type_name.is_none_or(|t| d.type_name.eq_ignore_ascii_case(t.trim())))
            .filter(|d| revision.is_none_or(|r| d.revision == r))
            .collect();
        let types: std::collections::BTreeSet<&str> =
            matching.iter().map(|d| d.type_name.as_str()).collect();
        if matching.is_empty()
            && let Some((_, e)) = self.refused.iter().find(|(label, _)| {
                let ty = label.split(" rev ").next().unwrap_or("");
                type_name.is_none_or(|t| ty.eq_ignore_ascii_case(t.trim()))
            })
        {
            // The device asked for is in the file but does not load.
            return Err(e.clone());
        }
        match (matching.is_empty(), types.len()) {
            (true, _) => Err(EsiError::NoSuchDevice {
                wanted: format!(
                    "{}{}",
                    type_name.unwrap_or("(any type)"),
                    revision.map_or(String::new(), |r| format!(" rev {r:#010x}"))
                ),
                known: self.known(),
            }),
            (false, 1) => matching
                .iter()
                .max_by_key(|d| d.revision)
                .copied()
                .ok_or_else(|| EsiError::NoSuchDevice {
                    wanted: String::new(),
                    known: self.known(),
                }),
            _ => Err(EsiError::Ambiguous {
                count: matching.len(),
                known: self.known(),
            }),
        }
    }

    /// The device with this vendor, product code and revision (ENI
    /// matching); `revision` `None` takes the highest.
    pub fn find_identity(
        &self,
        vendor_id: u32,
        product_code: u32,
        revision: Option<u32>,
    ) -> Option<&EsiDevice> {
        self.devices
            .iter()
            .filter(|d| d.vendor_id == vendor_id && d.product_code == product_code)
            .filter(|d| revision.is_none_or(|r| d.revision == r))
            .max_by_key(|d| d.revision)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE: &str = r##"<?xml version="1.0"?>
<EtherCATInfo>
  <Vendor><Id>#x00000002</Id><Name>V</Name></Vendor>
  <Descriptions>
    <Groups><Group><Type>DigOut</Type><Name>Outputs</Name></Group></Groups>
    <Devices>
      <Device Physics="KK">
        <Type ProductCode="#x07d43052" RevisionNo="#x00100000">EL2004</Type>
        <Name LcId="1031">Deutsch</Name>
        <Name LcId="1033">English</Name>
        <GroupType>DigOut</GroupType>
        <Fmmu>Outputs</Fmmu>
        <Sm StartAddress="#x0f00" ControlByte="#x44" Enable="1" OpOnly="1">Outputs</Sm>
        <RxPdo Fixed="1" Mandatory="1" Sm="0">
          <Index>#x1600</Index><Name>Channel 1</Name>
          <Exclude>#x1601</Exclude>
          <Entry><Index>#x7000</Index><SubIndex>1</SubIndex><BitLen>1</BitLen><Name>Output</Name><DataType>BOOL</DataType></Entry>
          <Entry><Index>#x0</Index><BitLen>3</BitLen></Entry>
        </RxPdo>
        <Eeprom><ByteSize>2048</ByteSize><ConfigData>0401000000000F00</ConfigData></Eeprom>
      </Device>
    </Devices>
  </Descriptions>
</EtherCATInfo>"##;

    #[test]
    fn a_device_is_read_with_identity_names_sms_pdos_and_eeprom() {
        let f = EsiFile::parse(ONE).unwrap();
        let d = f.device(None, None).unwrap();
        assert_eq!(
            (d.vendor_id, d.product_code, d.revision),
            (2, 0x07d4_3052, 0x0010_0000)
        );
        assert_eq!(d.name, "English", "LcId 1033 preferred");
        assert_eq!(d.group_name, "Outputs");
        assert_eq!(d.sms[0].enable, 0x09, "enable + OpOnly");
        assert_eq!(d.sms[0].kind, SmType::ProcessOut);
        let p = &d.rx_pdos[0];
        assert_eq!(p.flags, pdo_flags::MANDATORY | pdo_flags::FIXED_CONTENT);
        assert_eq!(p.excludes, [0x1601]);
        assert_eq!(p.entries[1].data_type, 0, "padding");
        assert_eq!(p.bits(), 4);
        assert_eq!(d.output_bytes(), 1);
        assert_eq!(d.config_data, [4, 1, 0, 0, 0, 0, 0x0F, 0]);
        assert!(!d.has_mailbox());
    }

    #[test]
    fn device_choice_by_type_and_revision_and_its_errors() {
        let two = ONE.replace(
            "</Device>\n    </Devices>",
            "</Device>\n<Device><Type ProductCode=\"#x1\" RevisionNo=\"#x2\">EL9999</Type><Name>x</Name></Device>\n    </Devices>",
        );
        let f = EsiFile::parse(&two).unwrap();
        assert!(matches!(
            f.device(None, None),
            Err(EsiError::Ambiguous { count: 2, .. })
        ));
        assert_eq!(f.device(Some("el9999"), None).unwrap().revision, 2);
        let e = f.device(Some("EL2004"), Some(5)).unwrap_err();
        assert!(
            e.to_string().contains("no device EL2004 rev 0x00000005"),
            "{e}"
        );
        assert!(f.find_identity(2, 0x07d4_3052, None).is_some());
        assert!(f.find_identity(2, 0x07d4_3052, Some(1)).is_none());
    }

    /// Why the file's (first) device does not load, or the file's error.
    fn refusal(text: &str) -> String {
        match EsiFile::parse(text) {
            Ok(f) => f
                .refused
                .first()
                .map_or_else(|| "loads".to_string(), |(_, e)| e.to_string()),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn malformed_files_give_the_element_and_line() {
        let cases: [(&str, &str, &str); 6] = [
            (
                "ProductCode=\"#x07d43052\"",
                "ProductCode=\"#xZZ\"",
                "<Type> at line 8: bad ProductCode '#xZZ'",
            ),
            (
                "<BitLen>1</BitLen>",
                "<BitLen>300</BitLen>",
                "<BitLen> at line 17: bad BitLen '300'",
            ),
            (
                "Enable=\"1\" OpOnly=\"1\">Outputs",
                "Enable=\"1\">Sideways",
                "<Sm> at line 13: bad SyncManager type 'Sideways'",
            ),
            (
                "<Fmmu>Outputs</Fmmu>",
                "<Fmmu>Both</Fmmu>",
                "<Fmmu> at line 12: bad FMMU usage 'Both'",
            ),
            (
                "Sm=\"0\"",
                "Sm=\"3\"",
                "<RxPdo> at line 14: PDO 0x1600 is assigned to SM3, which is not described by an <Sm>",
            ),
            (
                "<ConfigData>0401000000000F00</ConfigData>",
                "<ConfigData>0401X</ConfigData>",
                "<ConfigData> at line 20: bad hexBinary '0401X'",
            ),
        ];
        for (from, to, want) in cases {
            let text = ONE.replace(from, to);
            assert_ne!(text, ONE, "{from}");
            assert_eq!(refusal(&text), want);
        }
        let tx = ONE.replace("<Sm StartAddress=\"#x0f00\"", "<Sm StartAddress=\"#x1000\" ControlByte=\"#x00\" Enable=\"1\">Inputs</Sm>\n<Sm StartAddress=\"#x0f00\"");
        // SM0 is now an input SM: an RxPDO on it is refused.
        let e = refusal(&tx);
        assert!(e.contains("not an output SyncManager"), "{e}");
        assert!(matches!(
            EsiFile::parse("<Other/>"),
            Err(EsiError::NotEsi(_))
        ));
        assert!(matches!(
            EsiFile::parse("<EtherCATInfo>"),
            Err(EsiError::Xml(_))
        ));
        let e = EsiFile::parse("<EtherCATInfo><Vendor><Id>2</Id></Vendor><Descriptions><Devices/></Descriptions></EtherCATInfo>").unwrap_err();
        assert!(e.to_string().contains("missing <Device>"), "{e}");
    }

    #[test]
    fn mailbox_sms_smaller_than_one_sdo_are_refused() {
        let text = ONE.replace(
            "<Fmmu>Outputs</Fmmu>",
            "<Sm StartAddress=\"#x1000\" DefaultSize=\"8\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>",
        );
        let e = refusal(&text);
        assert!(
            e.contains("SM0 DefaultSize 8 bytes is too small for 16 bytes"),
            "{e}"
        );
    }

    #[test]
    fn absurd_sm_addresses_and_eeprom_sizes_are_refused_at_load() {
        // A SyncManager running past the ESC's 64 KiB.
        let text = ONE.replace(
            "StartAddress=\"#x0f00\"",
            "StartAddress=\"#xfff0\" DefaultSize=\"256\"",
        );
        assert_eq!(
            refusal(&text),
            "<Sm> at line 13: SM0 at 0xfff0 with 256 bytes runs past the end of the ESC address space (0xffff)"
        );
        // Ending exactly at the top is fine.
        let top = ONE.replace(
            "StartAddress=\"#x0f00\"",
            "StartAddress=\"#xff00\" DefaultSize=\"256\"",
        );
        assert!(EsiFile::parse(&top).is_ok());
        // An EEPROM beyond the SII's 65535 kbit (ByteSize / 128).
        for (size, ok) in [("8388607", true), ("8388608", false), ("4294967295", false)] {
            let text = ONE.replace(
                "<ByteSize>2048</ByteSize>",
                &format!("<ByteSize>{size}</ByteSize>"),
            );
            match refusal(&text).as_str() {
                "loads" => assert!(ok, "{size}"),
                e => {
                    assert!(!ok, "{size}: {e}");
                    assert_eq!(
                        e,
                        format!(
                            "<ByteSize> at line 20: bad EEPROM ByteSize (at most 65535 kbit) '{size}'"
                        )
                    );
                }
            }
        }
        let f = EsiFile::parse(ONE).unwrap();
        assert_eq!(f.devices[0].eeprom_kbit(), Some(16));
    }

    #[test]
    fn base_type_names_map_to_coe_codes() {
        assert_eq!(base_type_code("BOOL"), Some(1));
        assert_eq!(base_type_code("BIT3"), Some(0x32));
        assert_eq!(base_type_code("BIT9"), None);
        assert_eq!(base_type_code("STRING(12)"), Some(9));
        assert_eq!(base_type_code("ULINT"), Some(0x1B));
        assert_eq!(base_type_code("FLOAT7"), None);
        assert_eq!(base_type_code("REAL"), Some(0x08));
        assert_eq!(base_type_code("BITARR16"), Some(0x2E));
        assert_eq!(base_type_code("ARRAY [0..27] OF BYTE"), Some(0x0A));
        assert_eq!(base_type_code("ARRAY [0..7] OF UINT"), Some(0x06));
        assert_eq!(array_bounds("ARRAY [0..-1] OF BYTE"), Some((0, -1)));
        assert_eq!(array_element("ARRAY[1..2]OF  INT"), Some("INT"));
        assert_eq!(array_element("ARRAY [0..1 OF BYTE"), None);
    }

    #[test]
    fn one_refused_device_leaves_the_others_of_its_file() {
        let two = ONE.replace(
            "</Device>\n    </Devices>",
            "</Device>\n<Device><Type ProductCode=\"#xZZ\" RevisionNo=\"#x2\">EL9999</Type><Name>x</Name></Device>\n    </Devices>",
        );
        let f = EsiFile::parse(&two).unwrap();
        assert_eq!(f.devices.len(), 1);
        assert_eq!(f.refused.len(), 1);
        assert_eq!(f.refused[0].0, "EL9999 rev 0x00000002");
        let e = f.device(Some("EL9999"), None).unwrap_err().to_string();
        assert!(e.contains("bad ProductCode '#xZZ'"), "{e}");
    }

    #[test]
    fn an_iso_8859_1_file_loads_with_lowercase_flags_and_its_names_decoded() {
        let latin1: Vec<u8> = ONE
            .replace(
                "<?xml version=\"1.0\"?>",
                "<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>",
            )
            .replace("Deutsch", "Ausg\u{e4}nge")
            .chars()
            .map(|c| c as u8)
            .collect();
        assert!(latin1.contains(&0xE4));
        let f = EsiFile::parse_bytes(&latin1).unwrap();
        let de = f.devices[0].source.children_named("Name").next().unwrap();
        assert_eq!(de.text, "Ausg\u{e4}nge");
        assert!(
            EsiFile::parse_bytes(&latin1[..40]).is_err(),
            "cut: an error, no panic"
        );
    }
}
