//! A twin of a device with a mailbox: the core's firmware ([`Slave`] on
//! the software ESC, with its CoE server, SDO Information, PDO engine and
//! AL state machine) running a [`DeviceDescription`] built at run time
//! from the ESI.
//!
//! The description takes: identity and names; the dictionary
//! ([`crate::dictionary`]; 0x1018:01..03 always carry the ESI identity),
//! or, for an ESI without one, a dictionary made from the PDOs
//! (`synthesize`);
//! the mailbox from the `MBoxOut`/`MBoxIn` SyncManagers, the bootstrap
//! mailbox from `Eeprom/BootStrap`, CoE services from `Mailbox/CoE`, FoE
//! from `Mailbox/FoE`; PDO sets from
//! `VendorSpecific/TwinCAT/AlternativeSmMapping`, else the default
//! assignment (0x1C12/0x1C13) plus, when more PDOs exist, one set of all
//! of them; ESC settings from `Eeprom` and `Electrical`. The memory layout
//! follows the ESI's SyncManager addresses.
//!
//! Behaviour is generic ([`EsiApp`]): outputs are stored, inputs follow
//! the [`InputRule`].
//!
//! [`Slave`]: ecat_slave::device::Slave

use ecat_slave::device::{
    Application, CoeServices, DeviceDescription, DeviceNames, EscConfig, Identity, MailboxConfig,
    MemoryLayout, PdoSet, ProcessData, SoftSlave, Tick,
};
use ecat_slave::od::build::{assign, assign_count, constant, input, map, output, sub0, var};
use ecat_slave::od::{DataType, DefaultValue, Entry, Object, ObjectCode, PdoMapping};
use ecat_slave::sii::{SmType, protocols};

use crate::dictionary;
use crate::esc_twin::InputRule;
use crate::esi::{At, EsiDevice, EsiError};
use crate::xml::hex_binary;

/// Most dictionary entries a twin can hold (its value storage).
pub const TWIN_ENTRIES: usize = 4096;

/// Why the description of a device with a mailbox cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DescriptionBuildError {
    /// The ESI is wrong (element and line inside).
    #[error(transparent)]
    Esi(#[from] EsiError),
    /// A PDO entry of a device without a dictionary has a type the core
    /// does not serve (the dictionary is made from the PDOs).
    #[error(
        "{at}: PDO entry {index:#06x}:{sub:02x} has data type code {code:#04x}, which twins do not serve yet"
    )]
    UnsupportedEntryType {
        /// The PDO element.
        at: At,
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// CoE data type code.
        code: u8,
    },
    /// More entries than a twin holds.
    #[error("{device}: {entries} dictionary entries, a twin holds at most {TWIN_ENTRIES}")]
    TooManyEntries {
        /// The device.
        device: String,
        /// Entries.
        entries: usize,
    },
    /// The description contradicts itself (the core's check).
    #[error("{device}: {source}")]
    Contradiction {
        /// The device.
        device: String,
        /// What the core's check found.
        source: ecat_slave::od::DescriptionError,
    },
    /// A mailbox SyncManager is missing.
    #[error("{0}: the ESI has a mailbox protocol but no MBoxOut/MBoxIn SyncManager")]
    NoMailboxSm(String),
    /// Modular devices are not twinned yet.
    #[error("{0}: modular devices (<Slots>) cannot be twinned from their ESI yet")]
    Modular(String),
}

fn leak(s: &str) -> &'static str {
    Box::leak(s.to_string().into_boxed_str())
}

fn leak_list(v: Vec<u16>) -> &'static [u16] {
    Box::leak(v.into_boxed_slice())
}

/// A copy of `e` (every field of an entry is `Copy`).
fn copy(e: &Entry) -> Entry {
    Entry {
        default: e.default,
        ..*e
    }
}

/// The PDOs an assignment object (0x1C12/0x1C13) lists by default.
fn assigned(objects: &[Object], index: u16) -> Vec<u16> {
    let Some(o) = objects.iter().find(|o| o.index == index) else {
        return Vec::new();
    };
    let n = match o.entries.first().map(|e| e.default) {
        Some(DefaultValue::Int(n)) => n,
        _ => 0,
    };
    o.entries
        .iter()
        .filter(|e| e.sub >= 1 && i64::from(e.sub) <= n)
        .filter_map(|e| match e.default {
            DefaultValue::Int(v) => u16::try_from(v).ok(),
            DefaultValue::Str(_) => None,
        })
        .collect()
}

/// The PDO sets of the device.
fn pdo_sets(dev: &EsiDevice, objects: &[Object]) -> Result<&'static [PdoSet], EsiError> {
    let alt = dev
        .source
        .path("VendorSpecific/TwinCAT")
        .map(|t| t.children_named("AlternativeSmMapping").collect::<Vec<_>>())
        .unwrap_or_default();
    let mut sets = Vec::new();
    if !alt.is_empty() {
        // The default mapping first (0x1C12/0x1C13 default to it).
        let mut ordered = alt.clone();
        ordered.sort_by_key(|a| a.attr("Default") != Some("1"));
        for a in ordered {
            let mut rx = Vec::new();
            let mut tx = Vec::new();
            for sm in a.children_named("Sm") {
                let list: &mut Vec<u16> = match sm.attr("No") {
                    Some("2") => &mut rx,
                    Some("3") => &mut tx,
                    _ => continue,
                };
                for p in sm.children_named("Pdo") {
                    let v = crate::eni::number(&p.text)
                        .and_then(|v| u16::try_from(v).ok())
                        .ok_or_else(|| EsiError::BadValue {
                            at: At {
                                element: p.name.clone(),
                                line: p.line,
                            },
                            what: "Pdo",
                            value: p.text.clone(),
                        })?;
                    list.push(v);
                }
            }
            sets.push(PdoSet {
                name: leak(a.text_at("Name").unwrap_or("")),
                rx: leak_list(rx),
                tx: leak_list(tx),
            });
        }
    } else {
        let rx = assigned(objects, 0x1C12);
        let tx = assigned(objects, 0x1C13);
        let all_rx: Vec<u16> = dev.rx_pdos.iter().map(|p| p.index).collect();
        let all_tx: Vec<u16> = dev.tx_pdos.iter().map(|p| p.index).collect();
        let more = all_rx.iter().any(|p| !rx.contains(p)) || all_tx.iter().any(|p| !tx.contains(p));
        if !rx.is_empty() || !tx.is_empty() {
            sets.push(PdoSet {
                name: "Default",
                rx: leak_list(rx),
                tx: leak_list(tx),
            });
        }
        if more {
            sets.push(PdoSet {
                name: "All PDOs",
                rx: leak_list(all_rx),
                tx: leak_list(all_tx),
            });
        }
    }
    Ok(Box::leak(sets.into_boxed_slice()))
}

fn sm(dev: &EsiDevice, kind: SmType) -> Option<(u16, u16)> {
    dev.sms
        .iter()
        .find(|s| s.kind == kind)
        .map(|s| (s.start, s.default_size))
}

/// The CoE data type of a PDO entry's type code.
fn entry_type(code: u8) -> Option<DataType> {
    Some(match code {
        0x01 => DataType::Bool,
        0x02 => DataType::Int8,
        0x03 => DataType::Int16,
        0x04 => DataType::Int32,
        0x05 => DataType::UInt8,
        0x06 => DataType::UInt16,
        0x07 => DataType::UInt32,
        0x15 => DataType::Int64,
        0x1B => DataType::UInt64,
        c @ 0x30..=0x37 => DataType::Bits(c - 0x2F),
        _ => return None,
    })
}

/// An entry a PDO maps: subindex, name, type, output (else input).
type MappedEntry = (u8, String, DataType, bool);

fn record(index: u16, name: &str, entries: Vec<Entry>) -> Object {
    Object {
        index,
        name: leak(name),
        code: ObjectCode::Record,
        entries: Box::leak(entries.into_boxed_slice()),
    }
}

fn array(index: u16, name: &str, entries: Vec<Entry>) -> Object {
    Object {
        code: ObjectCode::Array,
        ..record(index, name, entries)
    }
}

/// The dictionary of a device with CoE whose ESI has none (only
/// `<ChannelInfo>` or no profile): 0x1000 (the profile number), 0x1018,
/// the PDO mapping objects of its PDOs, 0x1C00, 0x1C12/0x1C13 assigning
/// the PDOs with a default SyncManager, and the objects the PDOs map (a
/// VAR for subindex 0 alone, else a record), read-only inputs and
/// writable outputs.
fn synthesize(dev: &EsiDevice) -> Result<Vec<Object>, DescriptionBuildError> {
    let profile = dev
        .source
        .path("Profile/ChannelInfo/ProfileNo")
        .or_else(|| dev.source.path("Profile/ProfileNo"))
        .and_then(|p| crate::eni::number(&p.text))
        .unwrap_or(0);
    let mut objects = vec![
        Object {
            index: 0x1000,
            name: "Device type",
            code: ObjectCode::Var,
            entries: Box::leak(Box::new([var(
                "Device type",
                DataType::UInt32,
                PdoMapping::None,
                profile,
            )])),
        },
        record(
            0x1018,
            "Identity",
            vec![
                sub0(4),
                constant(1, "Vendor ID", DataType::UInt32, i64::from(dev.vendor_id)),
                constant(
                    2,
                    "Product code",
                    DataType::UInt32,
                    i64::from(dev.product_code),
                ),
                constant(3, "Revision", DataType::UInt32, i64::from(dev.revision)),
                constant(4, "Serial number", DataType::UInt32, 0),
            ],
        ),
    ];
    // Mapped objects: (index) -> [(sub, name, type, output)].
    let mut mapped: std::collections::BTreeMap<u16, (String, Vec<MappedEntry>)> =
        std::collections::BTreeMap::new();
    for (pdos, out) in [(&dev.rx_pdos, true), (&dev.tx_pdos, false)] {
        for p in pdos.iter() {
            let mut entries = vec![sub0(u8::try_from(p.entries.len()).unwrap_or(u8::MAX))];
            for (k, e) in p.entries.iter().enumerate() {
                let sub = u8::try_from(k + 1).unwrap_or(u8::MAX);
                let value = u32::from(e.index) << 16 | u32::from(e.sub) << 8 | u32::from(e.bit_len);
                entries.push(map(sub, ecat_slave::od::build::sub_name(sub), value));
                if e.index == 0 {
                    continue;
                }
                let ty = entry_type(e.data_type).ok_or_else(|| {
                    DescriptionBuildError::UnsupportedEntryType {
                        at: p.at.clone(),
                        index: e.index,
                        sub: e.sub,
                        code: e.data_type,
                    }
                })?;
                let slot = mapped
                    .entry(e.index)
                    .or_insert_with(|| (p.name.clone(), Vec::new()));
                if !slot.1.iter().any(|(s, ..)| *s == e.sub) {
                    slot.1.push((e.sub, e.name.clone(), ty, out));
                }
            }
            objects.push(record(p.index, &p.name, entries));
        }
    }
    let sm_types: Vec<Entry> =
        std::iter::once(sub0(u8::try_from(dev.sms.len()).unwrap_or(u8::MAX)))
            .chain(dev.sms.iter().enumerate().map(|(i, s)| {
                let sub = u8::try_from(i + 1).unwrap_or(u8::MAX);
                let t = match s.kind {
                    SmType::MailboxOut => 1,
                    SmType::MailboxIn => 2,
                    SmType::ProcessOut => 3,
                    SmType::ProcessIn => 4,
                    _ => 0,
                };
                constant(
                    sub,
                    ecat_slave::od::build::sub_name(sub),
                    DataType::UInt8,
                    t,
                )
            }))
            .collect();
    objects.push(array(0x1C00, "Sync manager type", sm_types));
    for (index, name, pdos) in [
        (0x1C12u16, "RxPDO assign", &dev.rx_pdos),
        (0x1C13u16, "TxPDO assign", &dev.tx_pdos),
    ] {
        let def: Vec<u16> = pdos
            .iter()
            .filter(|p| p.sm.is_some())
            .map(|p| p.index)
            .collect();
        let cap = u8::try_from(pdos.len().max(1)).unwrap_or(u8::MAX);
        let mut entries = vec![assign_count(
            u8::try_from(def.len()).unwrap_or(u8::MAX),
            cap,
        )];
        for k in 1..=cap {
            let pdo = def.get(usize::from(k) - 1).copied().unwrap_or(0);
            entries.push(assign(k, pdo));
        }
        objects.push(array(index, name, entries));
    }
    for (index, (pdo_name, mut subs)) in mapped {
        subs.sort_by_key(|s| s.0);
        let make = |(sub, name, ty, out): &MappedEntry| {
            let n = leak(name);
            if *out {
                output(*sub, n, *ty)
            } else {
                input(*sub, n, *ty)
            }
        };
        match subs.as_slice() {
            [only] if only.0 == 0 => objects.push(Object {
                index,
                name: leak(&only.1),
                code: ObjectCode::Var,
                entries: Box::leak(Box::new([make(only)])),
            }),
            _ => {
                let highest = subs.iter().map(|s| s.0).max().unwrap_or(0);
                let entries: Vec<Entry> = std::iter::once(sub0(highest))
                    .chain(subs.iter().filter(|s| s.0 != 0).map(make))
                    .collect();
                objects.push(record(index, &pdo_name, entries));
            }
        }
    }
    objects.sort_by_key(|o| o.index);
    Ok(objects)
}

/// The twin's description and memory layout for `dev`.
pub fn describe(
    dev: &EsiDevice,
) -> Result<(&'static DeviceDescription, MemoryLayout), DescriptionBuildError> {
    let label = dev.label();
    if dev.source.child("Slots").is_some() {
        return Err(DescriptionBuildError::Modular(label));
    }
    let (parsed, enums) = match dev.source.path("Profile/Dictionary") {
        Some(dict_el) => {
            let (parsed, enums) = dictionary::parse(dict_el)?;
            (parsed.into_iter().map(|p| p.object).collect(), enums)
        }
        None => (synthesize(dev)?, Vec::new()),
    };
    let mut objects: Vec<Object> = Vec::with_capacity(parsed.len());
    for o in parsed {
        if o.index == 0x1018 {
            // The identity the device answers with is the ESI's.
            let id = [dev.vendor_id, dev.product_code, dev.revision];
            let entries: Vec<Entry> = o
                .entries
                .iter()
                .map(|e| match e.sub {
                    s @ 1..=3 => Entry {
                        default: DefaultValue::Int(i64::from(
                            id.get(usize::from(s) - 1).copied().unwrap_or(0),
                        )),
                        ..copy(e)
                    },
                    _ => copy(e),
                })
                .collect();
            objects.push(Object {
                entries: Box::leak(entries.into_boxed_slice()),
                ..o
            });
        } else {
            objects.push(o);
        }
    }
    let entries: usize = objects.iter().map(|o| o.entries.len()).sum();
    if entries > TWIN_ENTRIES {
        return Err(DescriptionBuildError::TooManyEntries {
            device: label,
            entries,
        });
    }
    let sets = pdo_sets(dev, &objects)?;
    let (mbx_out, mbx_in) = match (sm(dev, SmType::MailboxOut), sm(dev, SmType::MailboxIn)) {
        (Some(o), Some(i)) => (o, i),
        _ => return Err(DescriptionBuildError::NoMailboxSm(label)),
    };
    let boot = match dev.source.path("Eeprom/BootStrap") {
        Some(b) => {
            let bytes = hex_binary(&b.text).ok_or_else(|| EsiError::BadValue {
                at: At {
                    element: b.name.clone(),
                    line: b.line,
                },
                what: "hexBinary",
                value: b.text.clone(),
            })?;
            let w = |k: usize| {
                u16::from_le_bytes([
                    bytes.get(2 * k).copied().unwrap_or(0),
                    bytes.get(2 * k + 1).copied().unwrap_or(0),
                ])
            };
            Some(((w(0), w(1)), (w(2), w(3))))
        }
        None => None,
    }
    .filter(|((_, out_len), _)| *out_len != 0);
    let pd_out = sm(dev, SmType::ProcessOut).map_or(mbx_in.0 + mbx_in.1, |s| s.0);
    let pd_in = sm(dev, SmType::ProcessIn).map_or(pd_out + 0x100, |s| s.0);
    let layout = MemoryLayout {
        mbx_out,
        mbx_in,
        boot_out: boot.map_or((mbx_out.0, 0), |b| b.0),
        boot_in: boot.map_or((mbx_in.0, 0), |b| b.1),
        pd_out,
        pd_in,
    };
    let coe = dev.coe_details;
    let cd = &dev.config_data;
    let desc: &'static DeviceDescription = Box::leak(Box::new(DeviceDescription {
        identity: Identity {
            vendor_id: dev.vendor_id,
            product_code: dev.product_code,
            revision: dev.revision,
            serial: 0,
        },
        names: DeviceNames {
            vendor: leak(&dev.vendor_name),
            type_name: leak(&dev.type_name),
            name: leak(&dev.name),
            group_type: leak(&dev.group_type),
            group_name: leak(&dev.group_name),
        },
        dictionary: dictionary::build(objects, enums),
        process_data: ProcessData { sets },
        mailbox: MailboxConfig {
            size: mbx_out.1,
            boot_size: boot.map(|b| b.0.1),
            coe: CoeServices {
                sdo_info: coe & 0x02 != 0,
                pdo_assign: coe & 0x04 != 0,
                pdo_config: coe & 0x08 != 0,
                complete_access: coe & 0x20 != 0,
            },
            foe: dev.mailbox_protocols & protocols::FOE != 0 && boot.is_some(),
        },
        esc: EscConfig {
            pdi_control: u16::from_le_bytes([
                cd.first().copied().unwrap_or(0x05),
                cd.get(1).copied().unwrap_or(0),
            ]),
            eeprom_kbit: dev
                .eeprom_bytes
                .map_or(16, |b| u16::try_from(b * 8 / 1024).unwrap_or(16))
                .max(1),
            ebus_current_ma: dev.ebus_current_ma,
            physical_ports: crate::sii::physical_port(&dev.physics),
        },
        modules: None,
    }));
    desc.validate()
        .map_err(|source| DescriptionBuildError::Contradiction {
            device: dev.label(),
            source,
        })?;
    Ok((desc, layout))
}

/// The generic behaviour of a twin with a mailbox: outputs are stored by
/// the core; inputs (entries mappable into TxPDOs) follow the rule.
#[derive(Debug)]
pub struct EsiApp {
    desc: &'static DeviceDescription,
    rule: InputRule,
    /// (input flat position, bit length, output flat position of the same
    /// type for the loopback).
    inputs: Vec<(usize, u16, Option<usize>)>,
    ticks: u64,
}

impl EsiApp {
    /// The behaviour of `desc` with input rule `rule`.
    pub fn new(desc: &'static DeviceDescription, rule: InputRule) -> Self {
        let mut flat = 0usize;
        let mut ins: Vec<(usize, DataType, u16)> = Vec::new();
        let mut outs: Vec<(usize, DataType)> = Vec::new();
        for o in desc.dictionary.objects() {
            for e in o.entries {
                let numeric = e.data_type != DataType::VisibleString && !e.gap;
                match e.pdo {
                    PdoMapping::Tx if numeric => ins.push((flat, e.data_type, e.bit_len)),
                    PdoMapping::Rx if numeric => outs.push((flat, e.data_type)),
                    _ => {}
                }
                flat += 1;
            }
        }
        // Loopback: the k-th input of a type takes the k-th output of it.
        let mut used = vec![false; outs.len()];
        let inputs = ins
            .into_iter()
            .map(|(f, t, bits)| {
                let pick = outs
                    .iter()
                    .enumerate()
                    .find(|(i, (_, ot))| *ot == t && !used.get(*i).copied().unwrap_or(true))
                    .map(|(i, (of, _))| (i, *of));
                if let Some((i, _)) = pick
                    && let Some(u) = used.get_mut(i)
                {
                    *u = true;
                }
                (f, bits, pick.map(|(_, of)| of))
            })
            .collect();
        EsiApp {
            desc,
            rule,
            inputs,
            ticks: 0,
        }
    }
}

impl Application for EsiApp {
    fn description(&self) -> &'static DeviceDescription {
        self.desc
    }

    type Values = [i64; TWIN_ENTRIES];

    fn tick(&mut self, tick: &mut Tick<'_>) {
        self.ticks = self.ticks.wrapping_add(1);
        match self.rule {
            InputRule::Hold => {}
            InputRule::Loopback => {
                for (f, _, src) in &self.inputs {
                    if let Some(s) = src {
                        let v = tick.od.value(*s);
                        tick.od.set_value(*f, v);
                    }
                }
            }
            InputRule::Counter => {
                for (f, bits, _) in &self.inputs {
                    let mask = if *bits >= 64 {
                        u64::MAX
                    } else {
                        (1u64 << bits) - 1
                    };
                    tick.od.set_value(*f, (self.ticks & mask) as i64);
                }
            }
        }
    }
}

/// A software slave of `desc` laid out as `layout`.
pub fn slave(
    desc: &'static DeviceDescription,
    layout: MemoryLayout,
    rule: InputRule,
) -> SoftSlave<EsiApp> {
    SoftSlave::with_layout(EsiApp::new(desc, rule), layout)
}
