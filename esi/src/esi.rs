//! ESI (ETG.2000 v1.17) XML generation from a device description (host
//! tool).
//!
//! Everything comes from the [`DeviceDescription`] the slave runs: the
//! dictionary, identity, names and PDO sets, and the communication layout
//! (SyncManagers, FMMUs, mailbox, PDO assignment, ConfigData, BootStrap) by
//! decoding the device's own SII image, so the ESI and the EEPROM cannot
//! disagree. The XML is written with quick-xml's
//! [`Writer`], never by string concatenation, and is byte-for-byte
//! deterministic.

use std::collections::BTreeMap;
use std::io;

use ecat_sim::esc::SoftEsc;
use ecat_slave::device::DeviceDescription;
use ecat_slave::esc::Esc;
use ecat_slave::esc::registers as reg;
use ecat_slave::od::Dictionary;
use ecat_slave::od::modules::ModularLayout;
use ecat_slave::od::types::{
    Access, DataType, DefaultValue, Entry, Object, ObjectCode, PdoMapping,
};
use ecat_slave::sii::{self, FmmuUsage, PdoDirection, SiiError, SiiReader, SmType};
use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, BytesText, Event};

/// ETG.2000 schema version the file follows.
pub const ESI_VERSION: &str = "1.17";
/// AL state machine timeouts in ms (ESI `Info/StateMachine/Timeout`):
/// PRE-OP, SAFE-OP/OP, back to INIT, back to SAFE-OP.
pub const STATE_MACHINE_TIMEOUTS_MS: [u32; 4] = [2000, 9000, 5000, 200];
/// `<Dc>`: the two operation modes every device on the core runs, as
/// configurators offer them (ETG.2000 `Dc/OpMode`): free run / SM-synchron
/// (AssignActivate 0: no SYNC signal) and DC-synchron on SYNC0
/// (AssignActivate 0x0300: 0x0981 = cyclic operation + SYNC0, written by
/// the master as the 16-bit 0x0980; SYNC0 cycle = the bus cycle, factor 1;
/// 0x1C32:01/0x1C33:01 = 2 through the `Sm` elements). The core checks
/// what the master activates at PRE-OP→SAFE-OP (`device::DC_MIN_CYCLE_NS`).
fn write_dc(w: &mut W) -> io::Result<()> {
    start(w, "Dc", &[])?;
    start(w, "OpMode", &[])?;
    text(w, "Name", "FreeRun")?;
    text(w, "Desc", "FreeRun/SM-Synchron")?;
    text(w, "AssignActivate", "#x0000")?;
    end(w, "OpMode")?;
    start(w, "OpMode", &[])?;
    text(w, "Name", "DcSync")?;
    text(w, "Desc", "DC-Synchron (SYNC0)")?;
    text(w, "AssignActivate", "#x0300")?;
    text_attrs(w, "CycleTimeSync0", &[("Factor", "1")], "0")?;
    text_attrs(w, "ShiftTimeSync0", &[("Factor", "0")], "0")?;
    for sm in ["2", "3"] {
        start(w, "Sm", &[("No", sm)])?;
        text(w, "SyncType", "2")?;
        end(w, "Sm")?;
    }
    end(w, "OpMode")?;
    end(w, "Dc")
}

/// Mailbox request and response timeouts in ms (ESI `Info/Mailbox/Timeout`).
pub const MAILBOX_TIMEOUTS_MS: [u32; 2] = [100, 2000];

/// Why the ESI could not be generated.
#[derive(Debug, thiserror::Error)]
pub enum EsiError {
    /// The device's own SII image does not decode.
    #[error("the device SII image does not decode: {0}")]
    Sii(#[from] SiiError),
    /// Writing the XML failed.
    #[error("writing XML failed: {0}")]
    Io(#[from] io::Error),
    /// The model and the SII disagree in a way the ESI cannot express.
    #[error("inconsistent device model: {0}")]
    Model(String),
}

type W = Writer<Vec<u8>>;

fn start(w: &mut W, name: &str, attrs: &[(&str, &str)]) -> io::Result<()> {
    let mut s = BytesStart::new(name);
    for a in attrs {
        s.push_attribute(*a);
    }
    w.write_event(Event::Start(s))
}

fn end(w: &mut W, name: &str) -> io::Result<()> {
    w.write_event(Event::End(BytesEnd::new(name)))
}

fn text_attrs(w: &mut W, name: &str, attrs: &[(&str, &str)], value: &str) -> io::Result<()> {
    let mut e = w.create_element(name);
    for a in attrs {
        e = e.with_attribute(*a);
    }
    e.write_text_content(BytesText::new(value))?;
    Ok(())
}

fn text(w: &mut W, name: &str, value: &str) -> io::Result<()> {
    text_attrs(w, name, &[], value)
}

fn empty(w: &mut W, name: &str, attrs: &[(&str, &str)]) -> io::Result<()> {
    let mut e = w.create_element(name);
    for a in attrs {
        e = e.with_attribute(*a);
    }
    e.write_empty()?;
    Ok(())
}

/// `#x` and `width` upper-case hex digits.
pub fn hex(value: u32, width: usize) -> String {
    format!("#x{value:0width$X}")
}

/// Upper-case `xs:hexBinary` of `bytes`.
pub fn hex_binary(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

fn flag(b: bool) -> &'static str {
    if b { "1" } else { "0" }
}

/// The ESI type name of an entry: `UINT`, `BIT7`, `DT0800EN03`, `STRING(13)`.
pub fn type_name(e: &Entry, dict: &Dictionary) -> String {
    match e.data_type {
        // An enumeration's name is its EnumDesc's (`DT0800EN03`, or what a
        // vendor's ESI calls it).
        DataType::Enum(t) => dict.find_enum(t.index()).map_or_else(
            || format!("DT{:04X}EN{:02}", t.index(), t.bit_len()),
            |d| d.name.to_string(),
        ),
        DataType::VisibleString => format!("STRING({})", e.bit_len / 8),
        DataType::OctetString => format!("ARRAY [0..{}] OF BYTE", i32::from(e.bit_len / 8) - 1),
        t @ DataType::Array(_) => {
            let n = ecat_slave::od::dictionary::natural_bits(
                &DataType::from_code(t.code()).unwrap_or(DataType::UInt8),
            )
            .max(1);
            format!(
                "ARRAY [0..{}] OF {}",
                i32::from(e.bit_len / n) - 1,
                t.etg_name()
            )
        }
        t => t.etg_name().to_string(),
    }
}

/// Little-endian bytes of `value` in the entry's size (whole bytes,
/// two's complement for negative values).
pub fn value_bytes(value: i64, bit_len: u16) -> Vec<u8> {
    let n = usize::from(bit_len.div_ceil(8)).clamp(1, 8);
    value.to_le_bytes()[..n].to_vec()
}

/// `DefaultData`-style hex of an integer value in an entry's size.
pub fn default_data(value: i64, bit_len: u16) -> String {
    hex_binary(&value_bytes(value, bit_len))
}

/// The ETG.1004 unit code of an entry's unit text, with the unit's name
/// and symbol for the ESI's `UnitTypes`: the same codes SDO Information
/// reports (`ecat_slave::coe::sdo_info::unit_code`), so both agree.
fn unit_code(unit: &str) -> Option<(u32, &'static str, &'static str)> {
    let code = ecat_slave::coe::sdo_info::unit_code(unit);
    let (name, symbol) = match code {
        0x0003_0000 => ("second", "s"),
        0xFD03_0000 => ("millisecond", "ms"),
        0xFA03_0000 => ("microsecond", "µs"),
        0x0004_0000 => ("ampere", "A"),
        0xFD04_0000 => ("milliampere", "mA"),
        0x0026_0000 => ("volt", "V"),
        0xFD26_0000 => ("millivolt", "mV"),
        0x0020_0000 => ("hertz", "Hz"),
        0x002D_0000 => ("degree Celsius", "°C"),
        0x0001_0000 => ("metre", "m"),
        0xFD01_0000 => ("millimetre", "mm"),
        0x0024_0000 => ("watt", "W"),
        _ => return None,
    };
    Some((code, name, symbol))
}

fn access_attrs(a: Access) -> (&'static str, Option<(&'static str, &'static str)>) {
    match a {
        Access::Ro => ("ro", None),
        Access::Rw => ("rw", None),
        Access::RwPreOp => ("rw", Some(("WriteRestrictions", "PreOP"))),
        Access::Wo => ("wo", None),
    }
}

fn write_access(w: &mut W, a: Access) -> io::Result<()> {
    let (text_value, restriction) = access_attrs(a);
    match restriction {
        Some(r) => text_attrs(w, "Access", &[r], text_value),
        None => text(w, "Access", text_value),
    }
}

fn pdo_flag(p: PdoMapping) -> Option<&'static str> {
    match p {
        PdoMapping::None => None,
        PdoMapping::Rx => Some("R"),
        PdoMapping::Tx => Some("T"),
        PdoMapping::RxTx => Some("RT"),
    }
}

/// Flags of one entry (object or sub item): Access, Category, PdoMapping,
/// Backup, Setting, in schema order.
fn write_entry_flags(w: &mut W, e: &Entry, category: Option<&str>) -> io::Result<()> {
    start(w, "Flags", &[])?;
    write_access(w, e.access())?;
    if let Some(c) = category {
        text(w, "Category", c)?;
    }
    if let Some(p) = pdo_flag(e.pdo()) {
        text(w, "PdoMapping", p)?;
    }
    if e.backup() {
        text(w, "Backup", "1")?;
    }
    if e.setting() {
        text(w, "Setting", "1")?;
    }
    end(w, "Flags")
}

/// ETG.1000.6 mandatory objects (`Category` m); every other object is o.
fn category(index: u16) -> &'static str {
    match index {
        0x1000 | 0x1018 | 0x1C00 => "m",
        _ => "o",
    }
}

/// Bit offsets of a record's entries: subindex 0 at 0 (8 bits), the rest
/// packed from bit 16 in subindex order; and the total size rounded up to
/// whole bytes.
pub fn record_layout(o: &Object) -> (Vec<(&'static Entry, u32)>, u32) {
    let mut out = Vec::new();
    let mut off = 16u32;
    for e in o.entries {
        if e.sub == 0 {
            out.push((e, 0));
        } else {
            out.push((e, off));
            off += u32::from(e.bit_len);
        }
    }
    (out, off.div_ceil(8) * 8)
}

/// Number of elements and element entry of an ARRAY object.
fn array_shape(o: &Object) -> Option<(u32, &'static Entry)> {
    let first = o.entries.iter().find(|e| e.sub >= 1)?;
    Some((u32::from(o.max_sub()), first))
}

/// The ESI data type name of an object.
pub fn object_type_name(o: &Object, dict: &Dictionary) -> String {
    match (o.code, o.entries.first()) {
        (ObjectCode::Var, Some(e)) => type_name(e, dict),
        _ => format!("DT{:04X}", o.index),
    }
}

/// Bit size of an object as the ESI states it.
pub fn object_bit_size(o: &Object) -> u32 {
    match o.code {
        ObjectCode::Var => o.entries.first().map_or(0, |e| u32::from(e.bit_len)),
        ObjectCode::Record => record_layout(o).1,
        ObjectCode::Array => array_shape(o).map_or(16, |(n, e)| 16 + n * u32::from(e.bit_len)),
    }
}

/// The objects of a dictionary an ESI `Dictionary` element describes: of
/// a modular device the device's own objects, or one module's objects in
/// slot 0 (ETG.2000 `Modules/Module/Profile`).
type Objects<'a> = &'a [&'static Object];

fn write_base_types(w: &mut W, dict: &Dictionary, objects: Objects<'_>) -> io::Result<()> {
    // Name -> (sort key, bit size); sorted by CoE code then name.
    let mut base: BTreeMap<(u16, String), u32> = BTreeMap::new();
    for o in objects {
        for e in o.entries {
            if matches!(e.data_type, DataType::Enum(_)) {
                continue;
            }
            base.insert(
                (e.data_type.code(), type_name(e, dict)),
                u32::from(e.bit_len),
            );
        }
    }
    for ((_, name), bits) in &base {
        start(w, "DataType", &[])?;
        text(w, "Name", name)?;
        text(w, "BitSize", &bits.to_string())?;
        end(w, "DataType")?;
    }
    for en in dict.enums() {
        start(w, "DataType", &[])?;
        text(w, "Index", &hex(u32::from(en.index), 4))?;
        text(w, "Name", en.name)?;
        text(w, "BitSize", &en.bit_len.to_string())?;
        for (value, label) in en.values {
            start(w, "EnumInfo", &[])?;
            text(w, "Text", label)?;
            text(w, "Enum", &value.to_string())?;
            end(w, "EnumInfo")?;
        }
        end(w, "DataType")?;
    }
    Ok(())
}

fn write_sub_item(
    w: &mut W,
    sub: Option<u8>,
    name: &str,
    type_name: &str,
    bits: u32,
    offset: u32,
    e: &Entry,
) -> io::Result<()> {
    start(w, "SubItem", &[])?;
    if let Some(s) = sub {
        text(w, "SubIdx", &s.to_string())?;
    }
    text(w, "Name", name)?;
    text(w, "Type", type_name)?;
    if !e.unit().is_empty() {
        text(w, "Comment", &format!("Unit: {}", e.unit()))?;
    }
    text(w, "BitSize", &bits.to_string())?;
    text(w, "BitOffs", &offset.to_string())?;
    // A padding gap keeps its place in the layout but states no access
    // rights: the slave describes it as NULL with access 0 (MANUAL-NOTES
    // note 20), which the ESI's ro/rw/wo cannot express.
    if !e.gap() {
        write_entry_flags(w, e, None)?;
    }
    end(w, "SubItem")
}

fn write_complex_types(w: &mut W, dict: &Dictionary, objects: Objects<'_>) -> io::Result<()> {
    for o in objects.iter().copied() {
        match o.code {
            ObjectCode::Var => {}
            ObjectCode::Record => {
                let (layout, size) = record_layout(o);
                start(w, "DataType", &[])?;
                text(w, "Name", &format!("DT{:04X}", o.index))?;
                text(w, "BitSize", &size.to_string())?;
                for (e, off) in layout {
                    let t = type_name(e, dict);
                    write_sub_item(w, Some(e.sub), e.name, &t, u32::from(e.bit_len), off, e)?;
                }
                end(w, "DataType")?;
            }
            ObjectCode::Array => {
                let Some((n, elem)) = array_shape(o) else {
                    continue;
                };
                let arr = format!("DT{:04X}ARR", o.index);
                let bits = n * u32::from(elem.bit_len);
                start(w, "DataType", &[])?;
                text(w, "Name", &arr)?;
                text(w, "BaseType", &type_name(elem, dict))?;
                text(w, "BitSize", &bits.to_string())?;
                start(w, "ArrayInfo", &[])?;
                text(w, "LBound", "1")?;
                text(w, "Elements", &n.to_string())?;
                end(w, "ArrayInfo")?;
                end(w, "DataType")?;
                start(w, "DataType", &[])?;
                text(w, "Name", &format!("DT{:04X}", o.index))?;
                text(w, "BitSize", &(16 + bits).to_string())?;
                if let Some(sub0) = o.entry(0) {
                    write_sub_item(w, Some(0), sub0.name, &type_name(sub0, dict), 8, 0, sub0)?;
                }
                write_sub_item(w, None, "Elements", &arr, bits, 16, elem)?;
                end(w, "DataType")?;
            }
        }
    }
    Ok(())
}

/// `Info` content of one entry: Min/Max/Default data (or DefaultString),
/// then the unit code where ETG.1004 has one.
fn write_value_info(w: &mut W, e: &Entry) -> io::Result<()> {
    match e.default_value() {
        DefaultValue::Str(s) => text(w, "DefaultString", s)?,
        DefaultValue::Bytes(b) => {
            let mut bytes = b.to_vec();
            bytes.resize(usize::from(e.bit_len).div_ceil(8), 0);
            text(w, "DefaultData", &hex_binary(&bytes))?;
        }
        DefaultValue::Int(v) => {
            let v = v.get();
            if let Some(min) = e.min() {
                text(w, "MinData", &default_data(min, e.bit_len))?;
            }
            if let Some(max) = e.max() {
                text(w, "MaxData", &default_data(max, e.bit_len))?;
            }
            text(w, "DefaultData", &default_data(v, e.bit_len))?;
        }
    }
    if let Some((code, _, _)) = unit_code(e.unit()) {
        text(w, "Unit", &hex(code, 8))?;
    }
    Ok(())
}

/// Object-level access of a record or array: the common access of its
/// entries, else rw if any entry is writable.
fn object_access(o: &Object) -> Access {
    let mut it = o.entries.iter().filter(|e| !e.gap()).map(|e| e.access());
    let Some(first) = it.next() else {
        return Access::Ro;
    };
    if it.clone().all(|a| a == first) {
        return first;
    }
    if o.entries.iter().any(|e| e.access().writable()) {
        Access::Rw
    } else {
        Access::Ro
    }
}

fn write_objects(w: &mut W, dict: &Dictionary, objects: Objects<'_>) -> io::Result<()> {
    for o in objects.iter().copied() {
        start(w, "Object", &[])?;
        text(w, "Index", &hex(u32::from(o.index), 4))?;
        text(w, "Name", o.name)?;
        text(w, "Type", &object_type_name(o, dict))?;
        text(w, "BitSize", &object_bit_size(o).to_string())?;
        start(w, "Info", &[])?;
        match (o.code, o.entries.first()) {
            (ObjectCode::Var, Some(e)) => write_value_info(w, e)?,
            _ => {
                // Gaps have no value, hence no default to state.
                for e in o.entries.iter().filter(|e| !e.gap()) {
                    start(w, "SubItem", &[])?;
                    text(w, "Name", e.name)?;
                    start(w, "Info", &[])?;
                    write_value_info(w, e)?;
                    end(w, "Info")?;
                    end(w, "SubItem")?;
                }
            }
        }
        end(w, "Info")?;
        match (o.code, o.entries.first()) {
            (ObjectCode::Var, Some(e)) => write_entry_flags(w, e, Some(category(o.index)))?,
            _ => {
                start(w, "Flags", &[])?;
                write_access(w, object_access(o))?;
                text(w, "Category", category(o.index))?;
                end(w, "Flags")?;
            }
        }
        end(w, "Object")?;
    }
    Ok(())
}

fn write_unit_types(w: &mut W, objects: Objects<'_>) -> io::Result<()> {
    let mut units: BTreeMap<u32, (&str, &str)> = BTreeMap::new();
    for e in objects.iter().flat_map(|o| o.entries) {
        if let Some((code, name, symbol)) = unit_code(e.unit()) {
            units.insert(code, (name, symbol));
        }
    }
    if units.is_empty() {
        return Ok(());
    }
    start(w, "UnitTypes", &[])?;
    for (code, (name, symbol)) in units {
        start(w, "UnitType", &[])?;
        text(w, "NotationIndex", &hex(code >> 24, 2))?;
        text(w, "Index", &hex(code, 8))?;
        text(w, "Name", name)?;
        text(w, "Symbol", symbol)?;
        end(w, "UnitType")?;
    }
    end(w, "UnitTypes")
}

fn write_dictionary(w: &mut W, dict: &Dictionary, objects: Objects<'_>) -> io::Result<()> {
    start(w, "Dictionary", &[])?;
    write_unit_types(w, objects)?;
    start(w, "DataTypes", &[])?;
    write_base_types(w, dict, objects)?;
    write_complex_types(w, dict, objects)?;
    end(w, "DataTypes")?;
    start(w, "Objects", &[])?;
    write_objects(w, dict, objects)?;
    end(w, "Objects")?;
    end(w, "Dictionary")
}

/// One PDO of the SII with its direction and default SyncManager.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoSlot {
    /// PDO index.
    pub index: u16,
    /// RxPDO (outputs) or TxPDO (inputs).
    pub direction: PdoDirection,
    /// Default SyncManager; `None` for an alternative PDO (SII 0xFF).
    pub sm: Option<u8>,
}

/// The PDOs of an SII image, RxPDOs first, in category order.
pub fn sii_pdos(r: &SiiReader<'_>) -> Result<Vec<PdoSlot>, SiiError> {
    let mut out = Vec::new();
    for direction in [PdoDirection::Rx, PdoDirection::Tx] {
        for p in r.pdos(direction)? {
            let p = p?;
            out.push(PdoSlot {
                index: p.index,
                direction,
                sm: p.sm(),
            });
        }
    }
    Ok(out)
}

/// Entries of a PDO as the mapping object's defaults list them:
/// `(index, sub, bits)`, padding as index 0.
pub fn mapping_entries(dict: &Dictionary, pdo: u16) -> Vec<(u16, u8, u8)> {
    ecat_slave::device::mapping_entries(dict, pdo).collect()
}

fn write_pdo(
    w: &mut W,
    dev: &DeviceDescription,
    slot: &PdoSlot,
    all: &[PdoSlot],
) -> Result<(), EsiError> {
    let dict = dev.dictionary;
    let tag = match slot.direction {
        PdoDirection::Rx => "RxPdo",
        PdoDirection::Tx => "TxPdo",
    };
    let sm = slot.sm.map(|s| s.to_string());
    let mut attrs: Vec<(&str, &str)> = Vec::new();
    // The same flags the SII carries (ecat_slave::pdo::sii_flags).
    let flags = ecat_slave::pdo::sii_flags(dict, slot.index);
    if flags & ecat_slave::sii::pdo_flags::FIXED_CONTENT != 0 {
        attrs.push(("Fixed", "1"));
    }
    if flags & ecat_slave::sii::pdo_flags::MANDATORY != 0 {
        attrs.push(("Mandatory", "1"));
    }
    if let Some(sm) = &sm {
        attrs.push(("Sm", sm));
    }
    let name = dict
        .find(slot.index)
        .map(|(_, o)| o.name)
        .ok_or_else(|| EsiError::Model(format!("PDO {:#06x} has no mapping object", slot.index)))?;
    start(w, tag, &attrs)?;
    text(w, "Index", &hex(u32::from(slot.index), 4))?;
    text(w, "Name", name)?;
    // PDOs of one direction that share no PDO set exclude each other.
    let mine = dev.pdo_sets_of(slot.index);
    for other in all
        .iter()
        .filter(|o| o.direction == slot.direction && o.index != slot.index)
        .filter(|o| dev.pdo_sets_of(o.index) & mine == 0)
    {
        text(w, "Exclude", &hex(u32::from(other.index), 4))?;
    }
    for (index, sub, bits) in mapping_entries(dict, slot.index) {
        start(w, "Entry", &[])?;
        if index == 0 {
            text(w, "Index", "#x0")?;
            text(w, "BitLen", &bits.to_string())?;
        } else {
            let (_, e) = dict.find_entry(index, sub).ok_or_else(|| {
                EsiError::Model(format!(
                    "{:#06x} maps missing {index:#06x}:{sub}",
                    slot.index
                ))
            })?;
            text(w, "Index", &hex(u32::from(index), 4))?;
            text(w, "SubIndex", &sub.to_string())?;
            text(w, "BitLen", &bits.to_string())?;
            text(w, "Name", e.name)?;
            text(w, "DataType", &type_name(e, dict))?;
        }
        end(w, "Entry")?;
    }
    end(w, tag)?;
    Ok(())
}

fn write_alternative_mappings(w: &mut W, dev: &DeviceDescription) -> io::Result<()> {
    let sets = dev.process_data.sets;
    if sets.len() < 2 {
        return Ok(());
    }
    start(w, "VendorSpecific", &[])?;
    start(w, "TwinCAT", &[])?;
    for (n, set) in sets.iter().enumerate() {
        let attrs: &[(&str, &str)] = if n == 0 { &[("Default", "1")] } else { &[] };
        start(w, "AlternativeSmMapping", attrs)?;
        text(w, "Name", set.name)?;
        for (sm, list) in [("2", set.rx), ("3", set.tx)] {
            start(w, "Sm", &[("No", sm)])?;
            for pdo in list {
                text(w, "Pdo", &hex(u32::from(*pdo), 4))?;
            }
            end(w, "Sm")?;
        }
        end(w, "AlternativeSmMapping")?;
    }
    end(w, "TwinCAT")?;
    end(w, "VendorSpecific")
}

fn sm_name(t: SmType) -> &'static str {
    match t {
        SmType::MailboxOut => "MBoxOut",
        SmType::MailboxIn => "MBoxIn",
        SmType::ProcessOut => "Outputs",
        SmType::ProcessIn => "Inputs",
        SmType::Unused | SmType::Unknown(_) => "",
    }
}

fn fmmu_name(u: FmmuUsage) -> Option<&'static str> {
    match u {
        FmmuUsage::Outputs => Some("Outputs"),
        FmmuUsage::Inputs => Some("Inputs"),
        FmmuUsage::SyncMStatus => Some("MBoxState"),
        FmmuUsage::Unused | FmmuUsage::NotUsed | FmmuUsage::Unknown(_) => None,
    }
}

/// The 8 bytes of ESI `Eeprom/BootStrap`: bootstrap mailbox out offset,
/// out size, in offset, in size (u16 little-endian each).
pub fn bootstrap_bytes(m: &sii::SiiMailbox) -> [u8; 8] {
    let mut b = [0u8; 8];
    for (i, v) in [m.rx_offset, m.rx_size, m.tx_offset, m.tx_size]
        .into_iter()
        .enumerate()
    {
        b[2 * i..2 * i + 2].copy_from_slice(&v.to_le_bytes());
    }
    b
}

/// The ESC watchdog registers 0x0400/0x0410/0x0420 as the software ESC
/// resets them (divider, PDI time, SM time).
fn watchdog_registers(image: &[u8]) -> [u16; 3] {
    let mut esc = SoftEsc::new(image);
    [
        reg::WATCHDOG_DIVIDER,
        reg::WATCHDOG_TIME_PDI,
        reg::WATCHDOG_TIME_PD,
    ]
    .map(|a| esc.read_u16(a).unwrap_or(0))
}

/// `Slots` of a modular device (ETG.2000, ETG.5001): one slot per module
/// position, the first one mandatory, each taking the device's module
/// types; the configurator downloads the configured module ident list
/// (0xF030) at PRE-OP→SAFE-OP.
fn write_slots(w: &mut W, m: &ModularLayout) -> io::Result<()> {
    let pdo = m.pdo_increment.to_string();
    let index = hex(u32::from(m.index_distance), 2);
    let count = m.slots.to_string();
    start(
        w,
        "Slots",
        &[
            ("DownloadModuleIdentList", "1"),
            ("MaxSlotCount", &count),
            ("SlotPdoIncrement", &pdo),
            ("SlotIndexIncrement", &index),
        ],
    )?;
    for slot in 0..m.slots {
        let min = if slot == 0 { "1" } else { "0" };
        start(w, "Slot", &[("MinInstances", min), ("MaxInstances", "1")])?;
        text_attrs(
            w,
            "Name",
            &[("LcId", "1033")],
            &format!("Slot {}", slot + 1),
        )?;
        for (k, t) in m.modules.iter().enumerate() {
            let attrs: &[(&str, &str)] = if k == 0 { &[("Default", "1")] } else { &[] };
            text_attrs(w, "ModuleIdent", attrs, &hex(t.ident, 8))?;
        }
        end(w, "Slot")?;
    }
    end(w, "Slots")
}

/// `Modules`: each module type with its PDOs and objects as in slot 0.
fn write_modules(w: &mut W, dev: &DeviceDescription, m: &ModularLayout) -> Result<(), EsiError> {
    start(w, "Modules", &[])?;
    for t in m.modules {
        start(w, "Module", &[])?;
        text_attrs(w, "Type", &[("ModuleIdent", &hex(t.ident, 8))], t.type_name)?;
        text_attrs(w, "Name", &[("LcId", "1033")], t.name)?;
        let pdos: Vec<PdoSlot> =
            t.rx.iter()
                .map(|&index| PdoSlot {
                    index,
                    direction: PdoDirection::Rx,
                    sm: Some(2),
                })
                .chain(t.tx.iter().map(|&index| PdoSlot {
                    index,
                    direction: PdoDirection::Tx,
                    sm: Some(3),
                }))
                .collect();
        for slot in &pdos {
            write_pdo(w, dev, slot, &pdos)?;
        }
        let objects: Vec<&'static Object> = dev
            .dictionary
            .objects()
            .iter()
            .filter(|o| m.slot_of(o.index) == Some(0))
            .collect();
        start(w, "Profile", &[])?;
        write_dictionary(w, dev.dictionary, &objects)?;
        end(w, "Profile")?;
        end(w, "Module")?;
    }
    end(w, "Modules")?;
    Ok(())
}

/// Generates the ESI XML of the device `dev`.
pub fn generate(dev: &DeviceDescription) -> Result<Vec<u8>, EsiError> {
    let image = dev.sii_image();
    let r = SiiReader::new(&image)?;
    let strings = r.strings()?;
    let general = r
        .general()?
        .ok_or_else(|| EsiError::Model("SII has no General category".into()))?
        .resolve(&strings);
    let pdos = sii_pdos(&r)?;
    let profile = match dev.dictionary.find_entry(0x1000, 0) {
        Some((_, e)) => match e.default_value() {
            DefaultValue::Int(v) => v.get() & 0xFFFF,
            DefaultValue::Str(_) | DefaultValue::Bytes(_) => 0,
        },
        None => 0,
    };

    let mut w = Writer::new_with_indent(Vec::new(), b'\t', 1);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    start(
        &mut w,
        "EtherCATInfo",
        &[
            ("xmlns:xsi", "http://www.w3.org/2001/XMLSchema-instance"),
            ("xsi:noNamespaceSchemaLocation", "EtherCATInfo.xsd"),
            ("Version", ESI_VERSION),
        ],
    )?;
    start(&mut w, "Vendor", &[])?;
    text(&mut w, "Id", &hex(dev.identity.vendor_id, 8))?;
    text_attrs(&mut w, "Name", &[("LcId", "1033")], dev.names.vendor)?;
    end(&mut w, "Vendor")?;

    start(&mut w, "Descriptions", &[])?;
    start(&mut w, "Groups", &[])?;
    start(&mut w, "Group", &[])?;
    text(&mut w, "Type", general.group)?;
    text_attrs(&mut w, "Name", &[("LcId", "1033")], dev.names.group_name)?;
    end(&mut w, "Group")?;
    end(&mut w, "Groups")?;

    start(&mut w, "Devices", &[])?;
    start(&mut w, "Device", &[("Physics", "YY")])?;
    text_attrs(
        &mut w,
        "Type",
        &[
            ("ProductCode", &hex(dev.identity.product_code, 8)),
            ("RevisionNo", &hex(dev.identity.revision, 8)),
        ],
        general.order,
    )?;
    text_attrs(&mut w, "Name", &[("LcId", "1033")], general.name)?;

    start(&mut w, "Info", &[])?;
    start(&mut w, "StateMachine", &[])?;
    start(&mut w, "Timeout", &[])?;
    let [preop, safeop, init, back] = STATE_MACHINE_TIMEOUTS_MS;
    text(&mut w, "PreopTimeout", &preop.to_string())?;
    text(&mut w, "SafeopOpTimeout", &safeop.to_string())?;
    text(&mut w, "BackToInitTimeout", &init.to_string())?;
    text(&mut w, "BackToSafeopTimeout", &back.to_string())?;
    end(&mut w, "Timeout")?;
    end(&mut w, "StateMachine")?;
    start(&mut w, "Mailbox", &[])?;
    start(&mut w, "Timeout", &[])?;
    text(
        &mut w,
        "RequestTimeout",
        &MAILBOX_TIMEOUTS_MS[0].to_string(),
    )?;
    text(
        &mut w,
        "ResponseTimeout",
        &MAILBOX_TIMEOUTS_MS[1].to_string(),
    )?;
    end(&mut w, "Timeout")?;
    end(&mut w, "Mailbox")?;
    end(&mut w, "Info")?;

    text(&mut w, "GroupType", general.group)?;
    start(&mut w, "Profile", &[])?;
    text(&mut w, "ProfileNo", &profile.to_string())?;
    let own: Vec<&'static Object> = dev
        .dictionary
        .objects()
        .iter()
        .filter(|o| dev.modules.is_none_or(|m| m.slot_of(o.index).is_none()))
        .collect();
    write_dictionary(&mut w, dev.dictionary, &own)?;
    end(&mut w, "Profile")?;

    for u in r.fmmus()? {
        if let Some(name) = fmmu_name(u) {
            text(&mut w, "Fmmu", name)?;
        }
    }
    for sm in r.sync_managers()? {
        text_attrs(
            &mut w,
            "Sm",
            &[
                ("DefaultSize", &sm.length.to_string()),
                ("StartAddress", &hex(u32::from(sm.start), 4)),
                ("ControlByte", &hex(u32::from(sm.control), 2)),
                ("Enable", &sm.enable.to_string()),
            ],
            sm_name(sm.sm_type),
        )?;
    }
    for slot in &pdos {
        write_pdo(&mut w, dev, slot, &pdos)?;
    }

    let protocols = r.mailbox_protocols();
    let coe = dev.mailbox.coe;
    let mut mbx_attrs: Vec<(&str, &str)> = Vec::new();
    if general.flags & 0x04 != 0 {
        mbx_attrs.push(("DataLinkLayer", "1"));
    }
    start(&mut w, "Mailbox", &mbx_attrs)?;
    if protocols & sii::protocols::EOE != 0 {
        empty(&mut w, "EoE", &[])?;
    }
    if protocols & sii::protocols::COE != 0 {
        empty(
            &mut w,
            "CoE",
            &[
                ("SdoInfo", flag(coe.sdo_info)),
                ("PdoAssign", flag(coe.pdo_assign)),
                ("PdoConfig", flag(coe.pdo_config)),
                ("CompleteAccess", flag(coe.complete_access)),
                // The core's SDO server always does segmented transfers.
                ("SegmentedSdo", flag(true)),
            ],
        )?;
    }
    if protocols & sii::protocols::FOE != 0 {
        empty(&mut w, "FoE", &[])?;
    }
    end(&mut w, "Mailbox")?;

    write_dc(&mut w)?;
    if let Some(m) = dev.modules {
        write_slots(&mut w, m)?;
    }

    let [divider, pdi, sm_wd] = watchdog_registers(&image);
    start(&mut w, "ESC", &[])?;
    text(&mut w, "Reg0400", &hex(u32::from(divider), 4))?;
    text(&mut w, "Reg0410", &hex(u32::from(pdi), 4))?;
    text(&mut w, "Reg0420", &hex(u32::from(sm_wd), 4))?;
    end(&mut w, "ESC")?;

    start(&mut w, "Eeprom", &[])?;
    text(&mut w, "ByteSize", &r.eeprom_size_bytes().to_string())?;
    text(&mut w, "ConfigData", &hex_binary(&r.config_data()))?;
    text(
        &mut w,
        "BootStrap",
        &hex_binary(&bootstrap_bytes(&r.bootstrap_mailbox())),
    )?;
    end(&mut w, "Eeprom")?;

    write_alternative_mappings(&mut w, dev)?;
    end(&mut w, "Device")?;
    end(&mut w, "Devices")?;
    if let Some(m) = dev.modules {
        write_modules(&mut w, dev, m)?;
    }
    end(&mut w, "Descriptions")?;
    end(&mut w, "EtherCATInfo")?;
    let mut out = w.into_inner();
    out.push(b'\n');
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xml::{self, Element, hex_binary as unhex, hex_dec};
    use pam_199_p_etc::od as model;
    use pam_199_p_etc::{DEVICE, DIRECTIONAL_MAPPING, INDEPENDENT_MAPPING};
    use std::path::PathBuf;

    fn generated() -> Vec<u8> {
        generate(&DEVICE).unwrap()
    }

    fn device(doc: &Element) -> &Element {
        doc.path("Descriptions/Devices/Device").unwrap()
    }

    fn golden_dir() -> PathBuf {
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/golden"))
    }

    /// Compares `actual` with the golden file `name`, or rewrites it when
    /// `UPDATE_GOLDEN=1`.
    fn golden(name: &str, actual: &[u8]) {
        let path = golden_dir().join(name);
        if std::env::var("UPDATE_GOLDEN").is_ok_and(|v| v == "1") {
            std::fs::create_dir_all(golden_dir()).unwrap();
            std::fs::write(&path, actual).unwrap();
            return;
        }
        let want = std::fs::read(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e} (run with UPDATE_GOLDEN=1 to create it)",
                path.display()
            )
        });
        assert!(
            want == actual,
            "{} differs from the generated output; if the change is intended, \
             regenerate with UPDATE_GOLDEN=1",
            path.display()
        );
    }

    /// The schema validation of the same files needs the ETG.2000 schema,
    /// which is not committed: `tests/it/shared.rs`.
    #[test]
    fn every_catalog_devices_esi_agrees_with_its_sii() {
        for d in device_catalog::DEVICES {
            let xml = generate(d.description).unwrap();
            let sii = crate::sii_image(d.description);
            let text = std::str::from_utf8(&xml).unwrap();
            let m = crate::check::check(text, &sii).unwrap();
            assert!(m.is_empty(), "{}: {m:#?}", d.key);
            let r = SiiReader::new(&sii).unwrap();
            assert!(r.crc_ok(), "{}", d.key);
            assert_eq!(
                r.strings().unwrap().get(1),
                Some(d.description.names.type_name),
                "{}: SII string 1",
                d.key
            );
        }
        assert!(device_catalog::DEVICES.len() >= 2);
    }

    #[test]
    fn io8_esi_matches_its_golden_file() {
        golden("IO8.xml", &generate(&io8_example::DEVICE).unwrap());
    }

    #[test]
    fn generated_esi_matches_the_golden_file() {
        golden("PAM-199-P-ETC.xml", &generated());
    }

    #[test]
    fn sii_image_matches_the_golden_file() {
        golden("eeprom.bin", &crate::sii_image(&DEVICE));
    }

    #[test]
    fn generation_is_deterministic() {
        assert_eq!(generated(), generated());
    }

    /// Decodes little-endian `DefaultData` in the entry's signedness.
    fn decode(hex: &str, e: &Entry) -> i64 {
        let b = unhex(hex).unwrap();
        assert_eq!(b.len(), usize::from(e.bit_len.div_ceil(8)), "{}", e.name);
        let mut buf = [0u8; 8];
        buf[..b.len()].copy_from_slice(&b);
        let raw = i64::from_le_bytes(buf);
        let bits = 8 * b.len() as u32;
        if e.data_type.is_signed() && bits < 64 && raw >> (bits - 1) & 1 == 1 {
            raw - (1i64 << bits)
        } else {
            raw
        }
    }

    fn check_info(info: &Element, e: &Entry, what: &str) {
        match e.default_value() {
            DefaultValue::Str(s) => assert_eq!(info.text_at("DefaultString"), Some(s), "{what}"),
            DefaultValue::Bytes(b) => {
                let d = info
                    .text_at("DefaultData")
                    .and_then(unhex)
                    .unwrap_or_default();
                assert!(d.starts_with(b), "{what}");
            }
            DefaultValue::Int(v) => {
                let v = v.get();
                let d = info
                    .text_at("DefaultData")
                    .unwrap_or_else(|| panic!("{what}"));
                assert_eq!(decode(d, e), v, "{what} default");
                assert_eq!(
                    info.text_at("MinData").map(|m| decode(m, e)),
                    e.min(),
                    "{what}"
                );
                assert_eq!(
                    info.text_at("MaxData").map(|m| decode(m, e)),
                    e.max(),
                    "{what}"
                );
            }
        }
    }

    #[test]
    fn dictionary_holds_every_model_object_and_entry_with_its_defaults() {
        let doc = xml::parse(std::str::from_utf8(&generated()).unwrap()).unwrap();
        let dict = device(&doc).path("Profile/Dictionary").unwrap();
        let objects: Vec<&Element> = dict
            .path("Objects")
            .unwrap()
            .children_named("Object")
            .collect();
        assert_eq!(objects.len(), model::OBJECTS.len());
        let types: Vec<&Element> = dict
            .path("DataTypes")
            .unwrap()
            .children_named("DataType")
            .collect();
        let declared: Vec<&str> = types.iter().map(|t| t.text_at("Name").unwrap()).collect();
        for en in model::ENUMS {
            let t = types
                .iter()
                .find(|t| t.text_at("Name") == Some(en.name))
                .unwrap();
            let values: Vec<(i64, &str)> = t
                .children_named("EnumInfo")
                .map(|i| {
                    (
                        hex_dec(i.text_at("Enum").unwrap()).unwrap(),
                        i.text_at("Text").unwrap(),
                    )
                })
                .collect();
            assert_eq!(values, en.values.to_vec(), "{}", en.name);
        }
        for (o, x) in model::OBJECTS.iter().zip(&objects) {
            let what = format!("{:#06x}", o.index);
            assert_eq!(
                hex_dec(x.text_at("Index").unwrap()),
                Some(i64::from(o.index))
            );
            assert_eq!(x.text_at("Name"), Some(o.name), "{what}");
            let ty = x.text_at("Type").unwrap();
            assert!(declared.contains(&ty), "{what}: type {ty} not declared");
            let info = x.child("Info").unwrap();
            if o.code == ObjectCode::Var {
                check_info(info, &o.entries[0], &what);
                continue;
            }
            let subs: Vec<&Element> = info.children_named("SubItem").collect();
            let valued: Vec<&Entry> = o.entries.iter().filter(|e| !e.gap()).collect();
            assert_eq!(subs.len(), valued.len(), "{what}");
            for (e, s) in valued.into_iter().zip(subs) {
                assert_eq!(s.text_at("Name"), Some(e.name), "{what}");
                check_info(s.child("Info").unwrap(), e, &format!("{what}:{}", e.sub));
            }
            if o.code == ObjectCode::Record {
                let t = types
                    .iter()
                    .find(|t| t.text_at("Name") == Some(ty))
                    .unwrap();
                let items: Vec<(i64, &str, String)> = t
                    .children_named("SubItem")
                    .map(|i| {
                        (
                            hex_dec(i.text_at("SubIdx").unwrap()).unwrap(),
                            i.text_at("Name").unwrap(),
                            i.text_at("Type").unwrap().to_string(),
                        )
                    })
                    .collect();
                let want: Vec<(i64, &str, String)> = o
                    .entries
                    .iter()
                    .map(|e| (i64::from(e.sub), e.name, type_name(e, &model::DICT)))
                    .collect();
                assert_eq!(items, want, "{what}");
                for (_, _, t) in &items {
                    assert!(declared.contains(&t.as_str()), "{what}: {t}");
                }
            }
        }
    }

    #[test]
    fn dictionary_spot_checks_defaults_access_and_units() {
        let xml = String::from_utf8(generated()).unwrap();
        // CURRENT 1000 mA, range 500..3000.
        assert!(xml.contains("<MinData>F401</MinData>"));
        assert!(xml.contains("<DefaultData>E803</DefaultData>"));
        assert!(xml.contains("<Unit>#xFD040000</Unit>"));
        // 0x1C12/0x1C13 writable in PRE-OP only.
        assert!(xml.contains("<Access WriteRestrictions=\"PreOP\">rw</Access>"));
        // Gap padding types and strings are declared.
        for t in [
            "BIT3",
            "BIT5",
            "BIT7",
            "STRING(13)",
            "STRING(2)",
            "ULINT",
            "DT1C12ARR",
        ] {
            assert!(xml.contains(&format!("<Name>{t}</Name>")), "{t}");
        }
        assert_eq!(default_data(-10_000, 16), "F0D8");
        assert_eq!(default_data(1, 1), "01");
    }

    #[test]
    fn pdos_carry_sync_managers_excludes_and_padding_as_the_sii() {
        let doc = xml::parse(std::str::from_utf8(&generated()).unwrap()).unwrap();
        let dev = device(&doc);
        let pdo = |tag: &str, index: i64| {
            dev.children_named(tag)
                .find(|p| hex_dec(p.text_at("Index").unwrap()) == Some(index))
                .unwrap()
                .clone()
        };
        let excludes = |p: &Element| -> Vec<i64> {
            p.children_named("Exclude")
                .map(|e| hex_dec(&e.text).unwrap())
                .collect()
        };
        let p1600 = pdo("RxPdo", 0x1600);
        assert_eq!(
            (p1600.attr("Sm"), p1600.attr("Fixed")),
            (Some("2"), Some("1"))
        );
        assert_eq!(excludes(&p1600), [0x1601]);
        let p1601 = pdo("RxPdo", 0x1601);
        // The alternative set has fixed content too (no PDO configuration).
        assert_eq!((p1601.attr("Sm"), p1601.attr("Fixed")), (None, Some("1")));
        assert_eq!(excludes(&p1601), [0x1600]);
        for (i, sm) in [
            (0x1A00, Some("3")),
            (0x1A02, Some("3")),
            (0x1A01, None),
            (0x1A03, None),
        ] {
            let p = pdo("TxPdo", i);
            assert_eq!(p.attr("Sm"), sm, "{i:#x}");
            let want: &[i64] = if sm.is_some() {
                &[0x1A01, 0x1A03]
            } else {
                &[0x1A00, 0x1A02]
            };
            assert_eq!(excludes(&p), want, "{i:#x}");
        }
        let pad = p1600.children_named("Entry").nth(1).unwrap();
        assert_eq!(pad.text_at("Index"), Some("#x0"));
        assert_eq!(pad.text_at("BitLen"), Some("7"));
        assert!(pad.child("SubIndex").is_none());
        let alt: Vec<(&str, Option<&str>, Vec<&str>)> = dev
            .path("VendorSpecific/TwinCAT")
            .unwrap()
            .children_named("AlternativeSmMapping")
            .map(|m| {
                (
                    m.text_at("Name").unwrap(),
                    m.attr("Default"),
                    m.children_named("Sm")
                        .flat_map(|s| s.children_named("Pdo").map(|p| p.text.as_str()))
                        .collect(),
                )
            })
            .collect();
        assert_eq!(
            alt,
            [
                (
                    DIRECTIONAL_MAPPING,
                    Some("1"),
                    vec!["#x1600", "#x1A00", "#x1A02"]
                ),
                (
                    INDEPENDENT_MAPPING,
                    None,
                    vec!["#x1601", "#x1A01", "#x1A03"]
                ),
            ]
        );
    }

    #[test]
    fn mailbox_coe_attributes_follow_the_description() {
        let doc = xml::parse(std::str::from_utf8(&generated()).unwrap()).unwrap();
        let coe = device(&doc).path("Mailbox/CoE").unwrap();
        assert_eq!(coe.attr("SdoInfo"), Some("1"));
        assert_eq!(coe.attr("CompleteAccess"), Some("1"));
        assert_eq!(coe.attr("PdoAssign"), Some("1"));
        assert_eq!(coe.attr("PdoConfig"), Some("0"));
        assert_eq!(coe.attr("SegmentedSdo"), Some("1"));
        assert!(device(&doc).path("Mailbox/FoE").is_some());
        assert_eq!(DEVICE.mailbox.coe.details(), 0x27);
    }

    #[test]
    fn eeprom_section_mirrors_the_sii_header() {
        let doc = xml::parse(std::str::from_utf8(&generated()).unwrap()).unwrap();
        let ee = device(&doc).child("Eeprom").unwrap();
        let img = crate::sii_image(&DEVICE);
        assert_eq!(ee.text_at("ByteSize"), Some("2048"));
        assert_eq!(unhex(ee.text_at("ConfigData").unwrap()).unwrap(), img[..14]);
        // Bootstrap mailbox: out 0x1000+1024, in 0x1400+1024.
        assert_eq!(ee.text_at("BootStrap"), Some("0010000400140004"));
        assert_eq!(
            unhex(ee.text_at("BootStrap").unwrap()).unwrap(),
            img[0x28..0x30]
        );
    }
}
