//! Decoding of any SII image into a readable listing or JSON (host tool).
//!
//! Built on [`SiiReader`]; nothing here panics on a broken image: a bad
//! checksum, a category running past the end, an unknown category type, a
//! cut string or PDO are collected in [`Inspection::problems`] and the rest
//! of the image is still decoded.
//!
//! # JSON schema of `esi inspect --json`
//!
//! [`Inspection::to_json`] serialises an [`InspectionReport`] with
//! serde_json, pretty-printed (two-space indent), keys in the order below.
//! Every number is a plain JSON integer in decimal (no hex strings);
//! strings are UTF-8 (bytes that are not are replaced by U+FFFD). The
//! schema is stable: fields may be added at the end of an object in a
//! later version, none is renamed, removed or retyped. Parsing the output
//! back into [`InspectionReport`] (it implements `Deserialize`) is the
//! check the tests run.
//!
//! | path | type | meaning |
//! |---|---|---|
//! | `size` | integer | image length in bytes |
//! | `eeprom_bytes` | integer | EEPROM size the image declares (word 0x3E) |
//! | `version` | integer | SII version (word 0x3F) |
//! | `header.pdi_control`, `.pdi_config`, `.sync_impulse`, `.pdi_config2`, `.station_alias` | integer (u16) | words 0x00..0x04 |
//! | `header.stored_crc`, `.computed_crc` | integer (u8) | checksum in word 0x07 and over bytes 0..14 |
//! | `header.crc_ok` | bool | the two agree |
//! | `identity.vendor_id`, `.product_code`, `.revision`, `.serial` | integer (u32) | words 0x08..0x0F |
//! | `mailbox.standard`, `mailbox.bootstrap` | object | `out_offset`, `out_size` (master to slave), `in_offset`, `in_size` (integers, u16) |
//! | `mailbox.protocols` | integer (u16) | protocol bits of word 0x1C |
//! | `mailbox.protocol_names` | array of string | `"AoE"`, `"EoE"`, `"CoE"`, `"FoE"`, `"SoE"`, `"VoE"` for the bits set |
//! | `categories[]` | array of object | the category chain: `word_offset` (u16), `type` (u16, raw), `kind` (string, e.g. `"Strings"`, `"unknown (0x1234)"`), `len` (data bytes) |
//! | `strings[]` | array of object | `index` (1-based, u8), `text` (string) |
//! | `general` | object or null | `group`, `image`, `order`, `name` (strings resolved), `coe_details`, `foe_details`, `eoe_details`, `flags` (u8), `current_on_ebus` (i16, mA), `physical_port` (u16) |
//! | `fmmus[]` | array of object | `usage` (u8), `name` (`"Outputs"`, `"Inputs"`, `"SyncM status"`, `"unused"`, `"not used"`, `"unknown"`) |
//! | `sync_managers[]` | array of object | `start`, `length` (u16), `control`, `enable`, `type` (u8), `type_name` (`"MBoxOut"`, `"MBoxIn"`, `"Outputs"`, `"Inputs"`, `"unused"`, `"unknown (n)"`) |
//! | `pdos[]` | array of object | RxPDOs then TxPDOs: `direction` (`"RxPDO"`/`"TxPDO"`), `index` (u16), `sm` (u8, or null when not assigned), `dc_sync` (u8), `name`, `flags` (u16), `entries` |
//! | `pdos[].entries[]` | array of object | `index` (u16, 0 for padding), `sub` (u8), `name`, `data_type` (u8, CoE code), `data_type_name` (e.g. `"UINT"`, `"BIT3"`), `bit_len` (u8), `flags` (u16) |
//! | `dc[]` | array of object | `name`, `assign_activate` (u16), `cycle_time_sync0`, `shift_time_sync0`, `shift_time_sync1` (u32, ns), `sync0_cycle_factor`, `sync1_cycle_factor` (i16) |
//! | `problems` | array of string | everything wrong with the image, empty for a clean one |

use std::fmt::Write as _;

use ecat_slave::sii::{
    CategoryType, DcEntry, PdoDirection, SiiError, SiiGeneralRaw, SiiIdentity, SiiMailbox,
    SiiReader, SiiStrings, SiiSyncManager, SmType, protocols,
};

use serde::{Deserialize, Serialize};

/// One category of the chain.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CategoryInfo {
    /// Word address of the header.
    pub word_offset: u16,
    /// Raw type word.
    pub raw_type: u16,
    /// Readable type.
    pub kind: String,
    /// Data length in bytes.
    pub len: usize,
}

/// One PDO entry with its resolved name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PdoEntryInfo {
    /// Object index (0: padding).
    pub index: u16,
    /// Subindex.
    pub sub: u8,
    /// Name from the Strings category ("" for none).
    pub name: String,
    /// CoE data type code.
    pub data_type: u8,
    /// Bit length.
    pub bit_len: u8,
    /// Entry flags.
    pub flags: u16,
}

/// One PDO with its entries.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PdoInfo {
    /// Tx (inputs) or Rx (outputs).
    pub direction: PdoDirection,
    /// PDO index.
    pub index: u16,
    /// SyncManager byte (0xFF: not assigned by default).
    pub sm_raw: u8,
    /// DC sync byte.
    pub dc_sync: u8,
    /// Name from the Strings category.
    pub name: String,
    /// PDO flags.
    pub flags: u16,
    /// Entries in order.
    pub entries: Vec<PdoEntryInfo>,
}

/// One DC operation mode with its resolved name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DcInfo {
    /// The raw element.
    pub entry: DcEntry,
    /// Name from the Strings category.
    pub name: String,
}

/// Everything decoded from an SII image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Inspection {
    /// Image length in bytes.
    pub size: usize,
    /// Words 0x00..0x06: PDI control, PDI config, sync impulse, PDI config 2, alias.
    pub pdi: [u16; 5],
    /// Checksum stored in word 7.
    pub stored_crc: u8,
    /// Checksum computed over bytes 0..14.
    pub computed_crc: u8,
    /// Identity words 0x08..0x0F.
    pub identity: SiiIdentity,
    /// Bootstrap mailbox words 0x14..0x17.
    pub bootstrap_mailbox: SiiMailbox,
    /// Standard mailbox words 0x18..0x1B.
    pub standard_mailbox: SiiMailbox,
    /// Mailbox protocol bits, word 0x1C.
    pub mailbox_protocols: u16,
    /// Declared EEPROM size in bytes.
    pub eeprom_bytes: u32,
    /// Version word 0x3F.
    pub version: u16,
    /// The category chain as far as it could be followed.
    pub categories: Vec<CategoryInfo>,
    /// Strings by 1-based index (non-UTF-8 bytes replaced).
    pub strings: Vec<(u8, String)>,
    /// The General category and its resolved strings (group, image, order, name).
    pub general: Option<(SiiGeneralRaw, [String; 4])>,
    /// FMMU usage bytes.
    pub fmmus: Vec<u8>,
    /// SyncManager elements.
    pub sync_managers: Vec<SiiSyncManager>,
    /// RxPDOs then TxPDOs.
    pub pdos: Vec<PdoInfo>,
    /// DC operation modes.
    pub dc: Vec<DcInfo>,
    /// Everything wrong with the image.
    pub problems: Vec<String>,
}

impl Inspection {
    /// Whether the header checksum is right.
    pub fn crc_ok(&self) -> bool {
        self.stored_crc == self.computed_crc
    }
}

/// Readable name of a CoE base data type code.
pub fn data_type_name(code: u8) -> String {
    match ecat_slave::od::types::base_type(u16::from(code)) {
        _ if code == 0 => "-".into(),
        Some(t) => t.name.into(),
        None => format!("{code:#04x}"),
    }
}

fn category_name(kind: CategoryType) -> String {
    match kind {
        CategoryType::Nop => "NOP".into(),
        CategoryType::DeviceSpecific(r) => format!("device specific ({r})"),
        CategoryType::Strings => "Strings".into(),
        CategoryType::DataTypes => "DataTypes".into(),
        CategoryType::General => "General".into(),
        CategoryType::Fmmu => "FMMU".into(),
        CategoryType::SyncM => "SyncM".into(),
        CategoryType::FmmuX => "FMMUX".into(),
        CategoryType::SyncUnit => "SyncUnit".into(),
        CategoryType::TxPdo => "TxPDO".into(),
        CategoryType::RxPdo => "RxPDO".into(),
        CategoryType::Dc => "DC".into(),
        CategoryType::Timeouts => "Timeouts".into(),
        CategoryType::Dictionary => "Dictionary".into(),
        CategoryType::Hardware => "Hardware".into(),
        CategoryType::Vendor(r) => format!("vendor specific ({r:#06x})"),
        CategoryType::End => "End".into(),
        CategoryType::Unknown(r) => format!("unknown ({r:#06x})"),
    }
}

fn string_at(strings: &SiiStrings<'_>, idx: u8) -> String {
    strings
        .get_bytes(idx)
        .map(|b| String::from_utf8_lossy(b).into_owned())
        .unwrap_or_default()
}

fn note(problems: &mut Vec<String>, e: &SiiError) {
    let msg = e.to_string();
    if !problems.contains(&msg) {
        problems.push(msg);
    }
}

/// Decodes `image`. Only an image shorter than the 128-byte header is an
/// error; everything else wrong is listed in [`Inspection::problems`].
pub fn inspect(image: &[u8]) -> Result<Inspection, SiiError> {
    let r = SiiReader::new(image)?;
    let mut problems = Vec::new();
    if !r.crc_ok() {
        problems.push(format!(
            "header checksum mismatch: stored {:#04x}, computed {:#04x}",
            r.stored_crc(),
            r.computed_crc()
        ));
    }
    let declared = r.eeprom_size_bytes() as usize;
    if declared < image.len() && image[declared..].iter().any(|b| *b != 0xFF) {
        problems.push(format!(
            "data beyond the declared EEPROM size of {declared} bytes"
        ));
    }

    let mut categories = Vec::new();
    let mut ended = false;
    for c in r.categories() {
        match c {
            Ok(c) => {
                if let CategoryType::Unknown(raw) = c.kind {
                    problems.push(format!(
                        "unknown category type {raw:#06x} at word {:#06x}",
                        c.word_offset
                    ));
                }
                ended = c.kind == CategoryType::End;
                categories.push(CategoryInfo {
                    word_offset: c.word_offset,
                    raw_type: c.kind.raw(),
                    kind: category_name(c.kind),
                    len: c.data.len(),
                });
            }
            Err(e) => note(&mut problems, &e),
        }
    }
    if !ended {
        problems.push("category chain has no End marker".into());
    }

    let strings = r.strings().unwrap_or_else(|e| {
        note(&mut problems, &e);
        SiiStrings::default()
    });
    let mut string_list = Vec::new();
    for (idx, s) in strings.iter() {
        match s {
            Ok(s) => string_list.push((idx, s.to_string())),
            Err(SiiError::InvalidUtf8 { .. }) => string_list.push((idx, string_at(&strings, idx))),
            Err(e) => note(&mut problems, &e),
        }
    }

    let general = match r.general() {
        Ok(g) => g.map(|g| {
            let names =
                [g.group_idx, g.image_idx, g.order_idx, g.name_idx].map(|i| string_at(&strings, i));
            (g, names)
        }),
        Err(e) => {
            note(&mut problems, &e);
            None
        }
    };

    let fmmus = match r.fmmus() {
        Ok(it) => it.map(|u| u.raw()).collect(),
        Err(e) => {
            note(&mut problems, &e);
            Vec::new()
        }
    };
    let sync_managers = match r.sync_managers() {
        Ok(it) => it.collect(),
        Err(e) => {
            note(&mut problems, &e);
            Vec::new()
        }
    };

    let mut pdos = Vec::new();
    for direction in [PdoDirection::Rx, PdoDirection::Tx] {
        let iter = match r.pdos(direction) {
            Ok(it) => it,
            Err(e) => {
                note(&mut problems, &e);
                continue;
            }
        };
        for p in iter {
            match p {
                Ok(p) => pdos.push(PdoInfo {
                    direction,
                    index: p.index,
                    sm_raw: p.sm_raw,
                    dc_sync: p.dc_sync,
                    name: string_at(&strings, p.name_idx),
                    flags: p.flags,
                    entries: p
                        .entries()
                        .map(|e| PdoEntryInfo {
                            index: e.index,
                            sub: e.sub,
                            name: string_at(&strings, e.name_idx),
                            data_type: e.data_type,
                            bit_len: e.bit_len,
                            flags: e.flags,
                        })
                        .collect(),
                }),
                Err(e) => note(&mut problems, &e),
            }
        }
    }

    let dc = match r.dc() {
        Ok(it) => it
            .map(|entry| DcInfo {
                name: string_at(&strings, entry.name_idx),
                entry,
            })
            .collect(),
        Err(e) => {
            note(&mut problems, &e);
            Vec::new()
        }
    };

    Ok(Inspection {
        size: image.len(),
        pdi: [
            r.pdi_control(),
            r.pdi_config(),
            r.sync_impulse(),
            r.pdi_config2(),
            r.station_alias(),
        ],
        stored_crc: r.stored_crc(),
        computed_crc: r.computed_crc(),
        identity: r.identity(),
        bootstrap_mailbox: r.bootstrap_mailbox(),
        standard_mailbox: r.standard_mailbox(),
        mailbox_protocols: r.mailbox_protocols(),
        eeprom_bytes: r.eeprom_size_bytes(),
        version: r.version(),
        categories,
        strings: string_list,
        general,
        fmmus,
        sync_managers,
        pdos,
        dc,
        problems,
    })
}

/// Names of the mailbox protocol bits set in `bits`.
pub fn protocol_names(bits: u16) -> Vec<&'static str> {
    [
        (protocols::AOE, "AoE"),
        (protocols::EOE, "EoE"),
        (protocols::COE, "CoE"),
        (protocols::FOE, "FoE"),
        (protocols::SOE, "SoE"),
        (protocols::VOE, "VoE"),
    ]
    .into_iter()
    .filter(|(b, _)| bits & b != 0)
    .map(|(_, n)| n)
    .collect()
}

fn fmmu_name(raw: u8) -> &'static str {
    match raw {
        0x00 => "unused",
        0x01 => "Outputs",
        0x02 => "Inputs",
        0x03 => "SyncM status",
        0xFF => "not used",
        _ => "unknown",
    }
}

fn sm_type_name(t: SmType) -> String {
    match t {
        SmType::Unused => "unused".into(),
        SmType::MailboxOut => "MBoxOut".into(),
        SmType::MailboxIn => "MBoxIn".into(),
        SmType::ProcessOut => "Outputs".into(),
        SmType::ProcessIn => "Inputs".into(),
        SmType::Unknown(r) => format!("unknown ({r})"),
    }
}

fn direction_name(d: PdoDirection) -> &'static str {
    match d {
        PdoDirection::Rx => "RxPDO",
        PdoDirection::Tx => "TxPDO",
    }
}

impl From<&SiiMailbox> for MailboxAreaReport {
    fn from(m: &SiiMailbox) -> Self {
        Self {
            out_offset: m.rx_offset,
            out_size: m.rx_size,
            in_offset: m.tx_offset,
            in_size: m.tx_size,
        }
    }
}

impl Inspection {
    /// The readable listing.
    pub fn to_text(&self) -> String {
        let mut o = String::new();
        let id = &self.identity;
        let _ = writeln!(
            o,
            "SII image: {} bytes, declared EEPROM size {} bytes, version {}",
            self.size, self.eeprom_bytes, self.version
        );
        let _ = writeln!(o, "Header:");
        let _ = writeln!(
            o,
            "  PDI control {:#06x}, PDI config {:#06x}, sync impulse {:#06x}, PDI config 2 {:#06x}, station alias {:#06x}",
            self.pdi[0], self.pdi[1], self.pdi[2], self.pdi[3], self.pdi[4]
        );
        let _ = writeln!(
            o,
            "  checksum {:#04x} ({})",
            self.stored_crc,
            if self.crc_ok() {
                "ok".to_string()
            } else {
                format!("BAD, computed {:#04x}", self.computed_crc)
            }
        );
        let _ = writeln!(o, "Identity:");
        let _ = writeln!(
            o,
            "  vendor {:#010x}, product {:#010x}, revision {:#010x}, serial {:#010x}",
            id.vendor_id, id.product_code, id.revision, id.serial
        );
        let _ = writeln!(o, "Mailbox:");
        for (name, m) in [
            ("standard", &self.standard_mailbox),
            ("bootstrap", &self.bootstrap_mailbox),
        ] {
            let _ = writeln!(
                o,
                "  {name:<9} out {:#06x}+{}, in {:#06x}+{}",
                m.rx_offset, m.rx_size, m.tx_offset, m.tx_size
            );
        }
        let names = protocol_names(self.mailbox_protocols);
        let _ = writeln!(
            o,
            "  protocols {:#06x}: {}",
            self.mailbox_protocols,
            if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            }
        );
        let _ = writeln!(o, "Categories:");
        for c in &self.categories {
            let _ = writeln!(
                o,
                "  word {:#06x}: {} (type {}), {} bytes",
                c.word_offset, c.kind, c.raw_type, c.len
            );
        }
        let _ = writeln!(o, "Strings:");
        for (i, s) in &self.strings {
            let _ = writeln!(o, "  {i:3}: {s:?}");
        }
        if let Some((g, [group, image, order, name])) = &self.general {
            let _ = writeln!(o, "General:");
            let _ = writeln!(
                o,
                "  group {group:?}, image {image:?}, order {order:?}, name {name:?}"
            );
            let _ = writeln!(
                o,
                "  CoE details {:#04x}, FoE details {:#04x}, EoE details {:#04x}, flags {:#04x}",
                g.coe_details, g.foe_details, g.eoe_details, g.flags
            );
            let _ = writeln!(
                o,
                "  E-Bus current {} mA, physical ports {:#06x}",
                g.current_on_ebus, g.physical_port
            );
        }
        let _ = writeln!(o, "FMMU:");
        for (i, u) in self.fmmus.iter().enumerate() {
            let _ = writeln!(o, "  FMMU{i}: {} ({u:#04x})", fmmu_name(*u));
        }
        let _ = writeln!(o, "SyncM:");
        for (i, sm) in self.sync_managers.iter().enumerate() {
            let _ = writeln!(
                o,
                "  SM{i}: start {:#06x}, length {}, control {:#04x}, enable {:#04x}, {}",
                sm.start,
                sm.length,
                sm.control,
                sm.enable,
                sm_type_name(sm.sm_type)
            );
        }
        let _ = writeln!(o, "PDOs:");
        for p in &self.pdos {
            let sm = if p.sm_raw == 0xFF {
                "not assigned".to_string()
            } else {
                format!("SM{}", p.sm_raw)
            };
            let bits: u32 = p.entries.iter().map(|e| u32::from(e.bit_len)).sum();
            let _ = writeln!(
                o,
                "  {} {:#06x} {:?}: {sm}, {} entries, {bits} bits, flags {:#06x}",
                direction_name(p.direction),
                p.index,
                p.name,
                p.entries.len(),
                p.flags
            );
            for e in &p.entries {
                if e.index == 0 {
                    let _ = writeln!(o, "    padding {} bits", e.bit_len);
                } else {
                    let _ = writeln!(
                        o,
                        "    {:#06x}:{:02x} {:?} {} {} bits",
                        e.index,
                        e.sub,
                        e.name,
                        data_type_name(e.data_type),
                        e.bit_len
                    );
                }
            }
        }
        let _ = writeln!(o, "DC:");
        if self.dc.is_empty() {
            let _ = writeln!(o, "  none");
        }
        for d in &self.dc {
            let e = &d.entry;
            let _ = writeln!(
                o,
                "  {:?}: AssignActivate {:#06x}, Sync0 cycle {} ns (factor {}), shift {} ns, Sync1 factor {}, shift {} ns",
                d.name,
                e.assign_activate,
                e.cycle_time_sync0,
                e.sync0_cycle_factor,
                e.shift_time_sync0,
                e.sync1_cycle_factor,
                e.shift_time_sync1
            );
        }
        if self.problems.is_empty() {
            let _ = writeln!(o, "Problems: none");
        } else {
            let _ = writeln!(o, "Problems:");
            for p in &self.problems {
                let _ = writeln!(o, "  {p}");
            }
        }
        o
    }

    /// The same content as the JSON report (see the module docs for the
    /// schema).
    pub fn to_report(&self) -> InspectionReport {
        let id = &self.identity;
        InspectionReport {
            size: self.size,
            eeprom_bytes: self.eeprom_bytes,
            version: self.version,
            header: HeaderReport {
                pdi_control: self.pdi[0],
                pdi_config: self.pdi[1],
                sync_impulse: self.pdi[2],
                pdi_config2: self.pdi[3],
                station_alias: self.pdi[4],
                stored_crc: self.stored_crc,
                computed_crc: self.computed_crc,
                crc_ok: self.crc_ok(),
            },
            identity: IdentityReport {
                vendor_id: id.vendor_id,
                product_code: id.product_code,
                revision: id.revision,
                serial: id.serial,
            },
            mailbox: MailboxReport {
                standard: (&self.standard_mailbox).into(),
                bootstrap: (&self.bootstrap_mailbox).into(),
                protocols: self.mailbox_protocols,
                protocol_names: protocol_names(self.mailbox_protocols)
                    .into_iter()
                    .map(String::from)
                    .collect(),
            },
            categories: self
                .categories
                .iter()
                .map(|c| CategoryReport {
                    word_offset: c.word_offset,
                    raw_type: c.raw_type,
                    kind: c.kind.clone(),
                    len: c.len,
                })
                .collect(),
            strings: self
                .strings
                .iter()
                .map(|(index, text)| StringReport {
                    index: *index,
                    text: text.clone(),
                })
                .collect(),
            general: self
                .general
                .as_ref()
                .map(|(g, [group, image, order, name])| GeneralReport {
                    group: group.clone(),
                    image: image.clone(),
                    order: order.clone(),
                    name: name.clone(),
                    coe_details: g.coe_details,
                    foe_details: g.foe_details,
                    eoe_details: g.eoe_details,
                    flags: g.flags,
                    current_on_ebus: g.current_on_ebus,
                    physical_port: g.physical_port,
                }),
            fmmus: self
                .fmmus
                .iter()
                .map(|u| FmmuReport {
                    usage: *u,
                    name: fmmu_name(*u).into(),
                })
                .collect(),
            sync_managers: self
                .sync_managers
                .iter()
                .map(|sm| SyncManagerReport {
                    start: sm.start,
                    length: sm.length,
                    control: sm.control,
                    enable: sm.enable,
                    raw_type: sm.sm_type.raw(),
                    type_name: sm_type_name(sm.sm_type),
                })
                .collect(),
            pdos: self
                .pdos
                .iter()
                .map(|p| PdoReport {
                    direction: direction_name(p.direction).into(),
                    index: p.index,
                    sm: (p.sm_raw != 0xFF).then_some(p.sm_raw),
                    dc_sync: p.dc_sync,
                    name: p.name.clone(),
                    flags: p.flags,
                    entries: p
                        .entries
                        .iter()
                        .map(|e| PdoEntryReport {
                            index: e.index,
                            sub: e.sub,
                            name: e.name.clone(),
                            data_type: e.data_type,
                            data_type_name: data_type_name(e.data_type),
                            bit_len: e.bit_len,
                            flags: e.flags,
                        })
                        .collect(),
                })
                .collect(),
            dc: self
                .dc
                .iter()
                .map(|d| {
                    let e = &d.entry;
                    DcReport {
                        name: d.name.clone(),
                        assign_activate: e.assign_activate,
                        cycle_time_sync0: e.cycle_time_sync0,
                        shift_time_sync0: e.shift_time_sync0,
                        shift_time_sync1: e.shift_time_sync1,
                        sync0_cycle_factor: e.sync0_cycle_factor,
                        sync1_cycle_factor: e.sync1_cycle_factor,
                    }
                })
                .collect(),
            problems: self.problems.clone(),
        }
    }

    /// The JSON report, pretty-printed (two-space indent, no trailing
    /// newline); the schema is in the module docs.
    pub fn to_json(&self) -> String {
        // Serialising plain structs of integers, strings and vectors into
        // a `Vec` cannot fail.
        serde_json::to_string_pretty(&self.to_report()).unwrap_or_default()
    }
}

/// `esi inspect --json`: everything decoded from an SII image (schema in
/// the module docs).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InspectionReport {
    /// Image length in bytes.
    pub size: usize,
    /// Declared EEPROM size in bytes.
    pub eeprom_bytes: u32,
    /// SII version word 0x3F.
    pub version: u16,
    /// Words 0x00..0x07.
    pub header: HeaderReport,
    /// Words 0x08..0x0F.
    pub identity: IdentityReport,
    /// Mailbox areas and protocols.
    pub mailbox: MailboxReport,
    /// The category chain.
    pub categories: Vec<CategoryReport>,
    /// The Strings category.
    pub strings: Vec<StringReport>,
    /// The General category (`null` without one).
    pub general: Option<GeneralReport>,
    /// FMMU usage.
    pub fmmus: Vec<FmmuReport>,
    /// SyncManager elements.
    pub sync_managers: Vec<SyncManagerReport>,
    /// RxPDOs then TxPDOs.
    pub pdos: Vec<PdoReport>,
    /// DC operation modes.
    pub dc: Vec<DcReport>,
    /// Everything wrong with the image.
    pub problems: Vec<String>,
}

/// `header`: words 0x00..0x07.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeaderReport {
    /// Word 0x00.
    pub pdi_control: u16,
    /// Word 0x01.
    pub pdi_config: u16,
    /// Word 0x02.
    pub sync_impulse: u16,
    /// Word 0x03.
    pub pdi_config2: u16,
    /// Word 0x04.
    pub station_alias: u16,
    /// Checksum stored in word 0x07.
    pub stored_crc: u8,
    /// Checksum computed over bytes 0..14.
    pub computed_crc: u8,
    /// `stored_crc == computed_crc`.
    pub crc_ok: bool,
}

/// `identity`: words 0x08..0x0F.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IdentityReport {
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision number.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
}

/// `mailbox`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MailboxReport {
    /// Standard mailbox, words 0x18..0x1B.
    pub standard: MailboxAreaReport,
    /// Bootstrap mailbox, words 0x14..0x17.
    pub bootstrap: MailboxAreaReport,
    /// Protocol bits, word 0x1C.
    pub protocols: u16,
    /// Names of the protocol bits set.
    pub protocol_names: Vec<String>,
}

/// `mailbox.standard` / `mailbox.bootstrap`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MailboxAreaReport {
    /// Master-to-slave mailbox start.
    pub out_offset: u16,
    /// Master-to-slave mailbox size.
    pub out_size: u16,
    /// Slave-to-master mailbox start.
    pub in_offset: u16,
    /// Slave-to-master mailbox size.
    pub in_size: u16,
}

/// `categories[]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CategoryReport {
    /// Word address of the category header.
    pub word_offset: u16,
    /// Raw type word.
    #[serde(rename = "type")]
    pub raw_type: u16,
    /// Readable type.
    pub kind: String,
    /// Data length in bytes.
    pub len: usize,
}

/// `strings[]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StringReport {
    /// 1-based string index.
    pub index: u8,
    /// The string.
    pub text: String,
}

/// `general`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeneralReport {
    /// Group string.
    pub group: String,
    /// Image string.
    pub image: String,
    /// Order string.
    pub order: String,
    /// Name string.
    pub name: String,
    /// CoE details byte.
    pub coe_details: u8,
    /// FoE details byte.
    pub foe_details: u8,
    /// EoE details byte.
    pub eoe_details: u8,
    /// Flags byte.
    pub flags: u8,
    /// E-Bus current in mA.
    pub current_on_ebus: i16,
    /// Physical ports word.
    pub physical_port: u16,
}

/// `fmmus[]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmmuReport {
    /// Usage byte.
    pub usage: u8,
    /// Readable usage.
    pub name: String,
}

/// `sync_managers[]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SyncManagerReport {
    /// Start address.
    pub start: u16,
    /// Length in bytes.
    pub length: u16,
    /// Control register byte.
    pub control: u8,
    /// Enable byte.
    pub enable: u8,
    /// Raw type byte.
    #[serde(rename = "type")]
    pub raw_type: u8,
    /// Readable type.
    pub type_name: String,
}

/// `pdos[]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PdoReport {
    /// `"RxPDO"` or `"TxPDO"`.
    pub direction: String,
    /// PDO index.
    pub index: u16,
    /// SyncManager, `null` when not assigned by default.
    pub sm: Option<u8>,
    /// DC sync byte.
    pub dc_sync: u8,
    /// Name.
    pub name: String,
    /// PDO flags.
    pub flags: u16,
    /// Entries in order.
    pub entries: Vec<PdoEntryReport>,
}

/// `pdos[].entries[]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PdoEntryReport {
    /// Object index (0: padding).
    pub index: u16,
    /// Subindex.
    pub sub: u8,
    /// Name.
    pub name: String,
    /// CoE data type code.
    pub data_type: u8,
    /// Readable data type.
    pub data_type_name: String,
    /// Bit length.
    pub bit_len: u8,
    /// Entry flags.
    pub flags: u16,
}

/// `dc[]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DcReport {
    /// Name.
    pub name: String,
    /// AssignActivate word.
    pub assign_activate: u16,
    /// Sync0 cycle time in ns.
    pub cycle_time_sync0: u32,
    /// Sync0 shift time in ns.
    pub shift_time_sync0: u32,
    /// Sync1 shift time in ns.
    pub shift_time_sync1: u32,
    /// Sync0 cycle factor.
    pub sync0_cycle_factor: i16,
    /// Sync1 cycle factor.
    pub sync1_cycle_factor: i16,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// The real devices' SII dumps committed with the repository
    /// (`tests/data/sii-dumps`, provenance in `tests/data/README.md`).
    fn dumps() -> Vec<PathBuf> {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/sii-dumps");
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("{dir}: {e}"))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "bin"))
            .collect();
        files.sort();
        files
    }

    #[test]
    fn our_image_decodes_cleanly_with_identity_and_pdos() {
        let i = inspect(&crate::sii_image(&pam_199_p_etc::DEVICE)).unwrap();
        assert!(i.problems.is_empty(), "{:?}", i.problems);
        assert!(i.crc_ok());
        assert_eq!(i.identity.vendor_id, 0x05AE);
        assert_eq!(i.identity.product_code, 0x00C7_03F3);
        assert_eq!(i.sync_managers.len(), 4);
        assert_eq!(i.pdos.len(), 6);
        let p1a00 = i.pdos.iter().find(|p| p.index == 0x1A00).unwrap();
        assert_eq!(p1a00.sm_raw, 3);
        assert_eq!(p1a00.entries[0].name, "READY");
        let text = i.to_text();
        assert!(text.contains("checksum") && text.contains("(ok)"));
        assert!(text.contains("TxPDO 0x1a00 \"DIR_IN\": SM3"));
        assert!(text.contains("protocols 0x000c: CoE, FoE"));
    }

    #[test]
    fn every_real_dump_decodes_without_error() {
        let files = dumps();
        assert_eq!(files.len(), 7, "the seven committed dumps");
        for f in files {
            let bytes = std::fs::read(&f).unwrap();
            let i = inspect(&bytes).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
            assert!(
                i.categories.iter().any(|c| c.kind == "General"),
                "{}",
                f.display()
            );
            let text = i.to_text();
            assert!(text.contains("Identity:"));
            let json = i.to_json();
            assert!(json.starts_with('{') && json.ends_with('}'));
            let back: InspectionReport = serde_json::from_str(&json).unwrap();
            assert_eq!(back, i.to_report(), "{}", f.display());
        }
    }

    #[test]
    fn bad_checksum_is_reported_not_fatal() {
        let mut img = crate::sii_image(&pam_199_p_etc::DEVICE);
        img[0] ^= 0x01;
        let i = inspect(&img).unwrap();
        assert!(!i.crc_ok());
        assert!(i.problems.iter().any(|p| p.contains("checksum")));
        assert!(i.to_text().contains("BAD"));
    }

    #[test]
    fn category_past_the_end_is_reported() {
        let img = crate::sii_image(&pam_199_p_etc::DEVICE);
        // Cut the image inside the category chain.
        let i = inspect(&img[..200]).unwrap();
        assert!(
            i.problems.iter().any(|p| p.contains("runs past")),
            "{:?}",
            i.problems
        );
        // A length word that points far past the image.
        let mut img2 = img.clone();
        img2[0x82] = 0xFF;
        img2[0x83] = 0x7F;
        let i = inspect(&img2).unwrap();
        assert!(i.problems.iter().any(|p| p.contains("runs past")));
    }

    #[test]
    fn unknown_categories_are_listed_and_reported() {
        let mut img = crate::sii_image(&pam_199_p_etc::DEVICE);
        img[0x80] = 0x34; // first category type -> 0x1234
        img[0x81] = 0x12;
        let i = inspect(&img).unwrap();
        assert!(i.categories.iter().any(|c| c.raw_type == 0x1234));
        assert!(i.problems.iter().any(|p| p.contains("unknown category")));
    }

    #[test]
    fn too_short_images_and_constant_fills_do_not_panic() {
        assert!(inspect(&[0u8; 10]).is_err());
        for fill in [0x00u8, 0xFF, 0x55] {
            let _ = inspect(&vec![fill; 256]).unwrap().to_text();
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// Random images of 128 bytes to 4 KiB decode (with problems) and
        /// list as text and JSON without a panic; the JSON parses back into
        /// the schema.
        #[test]
        fn random_images_do_not_panic(
            img in proptest::collection::vec(proptest::prelude::any::<u8>(), 128..4096)
        ) {
            let i = inspect(&img).unwrap();
            let _ = i.to_text();
            let back: InspectionReport = serde_json::from_str(&i.to_json()).unwrap();
            proptest::prop_assert_eq!(back, i.to_report());
        }

        /// Our own image with random bytes overwritten in its category
        /// area: the chain is mostly intact, so the decoders of every
        /// category meet damaged data.
        #[test]
        fn damaged_categories_do_not_panic(
            damage in proptest::collection::vec((0x80usize..2048, proptest::prelude::any::<u8>()), 1..16)
        ) {
            let mut img = crate::sii_image(&pam_199_p_etc::DEVICE);
            for (at, b) in damage {
                if let Some(x) = img.get_mut(at) {
                    *x = b;
                }
            }
            let i = inspect(&img).unwrap();
            let _ = i.to_text();
            let _ = i.to_json();
        }
    }

    #[test]
    fn json_has_the_identity_and_pdo_entries() {
        let j = inspect(&crate::sii_image(&pam_199_p_etc::DEVICE))
            .unwrap()
            .to_json();
        assert!(j.contains("\"product_code\": 13042675"));
        assert!(j.contains("\"name\": \"COMMAND VALUE\""));
        assert!(j.contains("\"crc_ok\": true"));
        // Key order and shapes as documented.
        let keys: Vec<&str> = j
            .lines()
            .filter(|l| l.starts_with("  \"") && !l.starts_with("   "))
            .filter_map(|l| l.trim().split('"').nth(1))
            .collect();
        assert_eq!(
            keys,
            [
                "size",
                "eeprom_bytes",
                "version",
                "header",
                "identity",
                "mailbox",
                "categories",
                "strings",
                "general",
                "fmmus",
                "sync_managers",
                "pdos",
                "dc",
                "problems"
            ]
        );
        assert!(j.contains("\"sm\": 3,"), "assigned PDOs name their SM");
        assert!(j.contains("\"sm\": null,"), "alternative PDOs have none");
        assert!(j.contains("\"dc\": [],\n  \"problems\": []\n}"));
    }
}
