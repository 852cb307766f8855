//! Reading the devices of an ESI file into [`EsiDevice`]s: numbers and
//! flags with the element's line in every error, SyncManagers, PDOs, one
//! device, the checks a device could not fail, and [`EsiFile`].

use std::collections::BTreeMap;

use ecat_slave::sii::{FmmuUsage, SmType, pdo_flags, protocols};

use super::types::{dictionary_objects, dictionary_types};
use super::*;
use crate::xml::{self, Element, hex_binary};

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
