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
//! assignment (0x1C12/0x1C13) plus sets that honour `Exclude`
//! ([`alternative_sets`]); ESC settings from `Eeprom` and `Electrical`. The memory layout
//! follows the ESI's SyncManager addresses.
//!
//! Behaviour is generic ([`EsiApp`]): outputs are stored, inputs follow
//! the [`InputRule`].
//!
//! [`Slave`]: ecat_slave::device::Slave

use ecat_sim::SoftSlave;
use ecat_slave::device::{
    Application, CoeServices, DeviceDescription, EscConfig, MailboxConfig, MemoryLayout, PdoSet,
    ProcessData, Tick,
};
use ecat_slave::od::build::{assign, assign_count, constant, input, map, output, sub0, var};
use ecat_slave::od::{DataType, DefaultValue, Entry, Object, ObjectCode, PdoMapping};
use ecat_slave::sii::{SmType, protocols};

use crate::esc_twin::InputRule;
use crate::esi::{At, EsiDevice, EsiError, Warning};
use crate::xml::hex_binary;
use crate::{dictionary, leak};

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
    /// A process-data area the ESI gives no SyncManager for would be placed
    /// (after the SyncManager named) beyond the ESC's address space.
    #[error(
        "{at}: the {what} placed after this SyncManager would start at {start:#x}, beyond the ESC address space (0xffff)"
    )]
    NoRoomFor {
        /// The `Sm` element it would follow.
        at: At,
        /// `outputs` or `inputs`.
        what: &'static str,
        /// Where it would start.
        start: u32,
    },
    /// A mailbox SyncManager is missing.
    #[error("{0}: the ESI has a mailbox protocol but no MBoxOut/MBoxIn SyncManager")]
    NoMailboxSm(String),
    /// A modular device's slots or modules cannot be used.
    #[error("{at}: {problem}")]
    Modular {
        /// The element.
        at: At,
        /// What is wrong.
        problem: String,
    },
}

fn leak_list(v: Vec<u16>) -> &'static [u16] {
    Box::leak(v.into_boxed_slice())
}

/// The defaults of a list object (a PDO assignment or mapping): the
/// values of subindices 1 to subindex 0's default (-1 for one that is no
/// number).
fn list_defaults(o: &Object) -> Vec<i64> {
    let count = match o.entries.first().map(|e| e.default) {
        Some(DefaultValue::Int(n)) => n,
        _ => 0,
    };
    o.entries
        .iter()
        .filter(|e| e.sub >= 1 && i64::from(e.sub) <= count)
        .map(|e| match e.default {
            DefaultValue::Int(v) => v,
            _ => -1,
        })
        .collect()
}

/// The default assignment `index` (0x1C12/0x1C13) as the core reads it:
/// subindex 0 the number of PDOs, then the PDOs, without empty (0) places
/// and without PDOs the twin leaves out; a warning when that changes it.
fn normalize_assignment(
    dev: &EsiDevice,
    objects: &mut [Object],
    index: u16,
    left_out: &[u16],
    warnings: &mut Vec<Warning>,
) {
    let mapping: Vec<u16> = objects
        .iter()
        .map(|o| o.index)
        .filter(|i| (0x1600..=0x1BFF).contains(i))
        .collect();
    let Some(o) = objects.iter_mut().find(|o| o.index == index) else {
        return;
    };
    if o.code == ObjectCode::Var {
        return;
    }
    let mut list = assigned(std::slice::from_ref(o), index);
    list.retain(|p| !left_out.contains(p));
    // A PDO the device does not have (Beckhoff's EL3632 defaults 0x1C13 to
    // 0x1A73, an oversampling PDO its ESI does not list): the PDOs the
    // ESI assigns to the SM instead, as a configurator starts from them.
    // (A modular device's slot PDOs are made later, from its modules.)
    let modular = dev.source.child("Slots").is_some();
    if !modular && list.iter().any(|p| !mapping.contains(p)) {
        let sm = if index == 0x1C12 { 2 } else { 3 };
        list = dev
            .rx_pdos
            .iter()
            .chain(&dev.tx_pdos)
            .filter(|p| p.sm == Some(sm) && !left_out.contains(&p.index))
            .map(|p| p.index)
            .filter(|p| mapping.contains(p))
            .collect();
    }
    let now = list_defaults(o);
    let want: Vec<i64> = list.iter().map(|p| i64::from(*p)).collect();
    if now == want {
        return;
    }
    warnings.push(Warning {
        at: dev.at.clone(),
        message: format!(
            "{index:#06x} defaults to {now:x?}: {want:x?} assumed (no empty places, no PDO the twin leaves out or the device does not have)"
        ),
    });
    let mut entries: Vec<Entry> = o.entries.iter().map(copy).collect();
    for e in entries.iter_mut() {
        match e.sub {
            0 => e.default = DefaultValue::Int(want.len() as i64),
            s => e.default = DefaultValue::Int(want.get(usize::from(s) - 1).copied().unwrap_or(0)),
        }
    }
    o.entries = Box::leak(entries.into_boxed_slice());
}

/// Ranges a device could not have (minimum above maximum, a default
/// outside them or outside its type) are dropped with a warning: the
/// entry is served without one, as a configurator would read it.
fn drop_impossible_ranges(dev: &EsiDevice, objects: &mut [Object], warnings: &mut Vec<Warning>) {
    use ecat_slave::od::dictionary::{natural_range, value_le};
    for o in objects.iter_mut() {
        let bad: Vec<usize> = o
            .entries
            .iter()
            .enumerate()
            .filter(|(_, e)| {
                let DefaultValue::Int(v) = e.default else {
                    return false;
                };
                if e.data_type.is_bytes() || matches!(e.data_type, DataType::Enum(_)) {
                    return false;
                }
                let t = &e.data_type;
                let (lo, hi) = (e.min.unwrap_or(v), e.max.unwrap_or(v));
                let (nlo, nhi) = natural_range(t, e.bit_len);
                let natural = t.is_real() || (lo >= nlo && hi <= nhi);
                !(value_le(t, lo, hi) && value_le(t, lo, v) && value_le(t, v, hi) && natural)
            })
            .map(|(k, _)| k)
            .collect();
        if bad.is_empty() {
            continue;
        }
        let mut entries: Vec<Entry> = o.entries.iter().map(copy).collect();
        for k in bad {
            if let Some(e) = entries.get_mut(k) {
                warnings.push(Warning {
                    at: dev.at.clone(),
                    message: format!(
                        "{:#06x}:{:02x}: the range {:?}..{:?} of its type does not hold the default {:?} or is empty: served without a range, the default cut to its type",
                        o.index, e.sub, e.min, e.max, e.default
                    ),
                });
                e.min = None;
                e.max = None;
                // A default outside its type: its bits in the type's size.
                if let DefaultValue::Int(v) = e.default {
                    let (lo, hi) =
                        ecat_slave::od::dictionary::natural_range(&e.data_type, e.bit_len);
                    if !e.data_type.is_real() && (v < lo || v > hi) {
                        e.default = DefaultValue::Int(ecat_slave::od::store::from_raw(
                            e,
                            v as u64
                                & u64::MAX
                                    .checked_shr(64 - u32::from(e.bit_len.clamp(1, 64)))
                                    .unwrap_or(u64::MAX),
                        ));
                    }
                }
            }
        }
        o.entries = Box::leak(entries.into_boxed_slice());
    }
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
            DefaultValue::Int(v) => u16::try_from(v).ok().filter(|v| *v != 0),
            DefaultValue::Str(_) | DefaultValue::Bytes(_) => None,
        })
        .collect()
}

/// The PDO sets of the device.
fn pdo_sets(
    dev: &EsiDevice,
    objects: &[Object],
    left_out: &[u16],
) -> Result<&'static [PdoSet], EsiError> {
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
                    let v = crate::xml::number(&p.text)
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
        let mut rx = assigned(objects, 0x1C12);
        let mut tx = assigned(objects, 0x1C13);
        rx.retain(|p| !left_out.contains(p));
        tx.retain(|p| !left_out.contains(p));
        let mut dev = dev.clone();
        dev.rx_pdos.retain(|p| !left_out.contains(&p.index));
        dev.tx_pdos.retain(|p| !left_out.contains(&p.index));
        let dev = &dev;
        if !rx.is_empty() || !tx.is_empty() {
            sets.push(PdoSet {
                name: "Default",
                rx: leak_list(rx.clone()),
                tx: leak_list(tx.clone()),
            });
        }
        for (n, (srx, stx)) in alternative_sets(dev, &rx, &tx).into_iter().enumerate() {
            sets.push(PdoSet {
                name: leak(&format!("Alternative {}", n + 1)),
                rx: leak_list(srx),
                tx: leak_list(stx),
            });
        }
    }
    // The first set is what 0x1C12/0x1C13 hold at power-on (ETG.1000.6:
    // the device's default assignment); an AlternativeSmMapping marked
    // default that says otherwise comes after it.
    let (rx, tx) = (assigned(objects, 0x1C12), assigned(objects, 0x1C13));
    let first_ok = sets
        .first()
        .is_none_or(|s| s.rx == rx.as_slice() && s.tx == tx.as_slice());
    let lists = objects.iter().any(|o| matches!(o.index, 0x1C12 | 0x1C13));
    if !first_ok && lists {
        sets.insert(
            0,
            PdoSet {
                name: "Default",
                rx: leak_list(rx),
                tx: leak_list(tx),
            },
        );
    }
    Ok(Box::leak(sets.into_boxed_slice()))
}

/// PDO sets beyond the default assignment for a device without
/// `AlternativeSmMapping`: every PDO of the device lands in a set, and no
/// set holds two PDOs that exclude each other (`Exclude`, either way) or
/// more than the core's process image per direction. Built greedily: a set
/// starts with the first PDO no set holds yet and takes, in ESI order,
/// every PDO that fits.
pub fn alternative_sets(dev: &EsiDevice, rx: &[u16], tx: &[u16]) -> Vec<(Vec<u16>, Vec<u16>)> {
    let pdos: Vec<&crate::esi::EsiPdo> = dev.rx_pdos.iter().chain(&dev.tx_pdos).collect();
    let is_rx = |i: u16| dev.rx_pdos.iter().any(|p| p.index == i);
    let excludes = |a: &crate::esi::EsiPdo, b: &crate::esi::EsiPdo| {
        a.excludes.contains(&b.index) || b.excludes.contains(&a.index)
    };
    let limit = u32::try_from(ecat_slave::pdo::MAX_IMAGE * 8).unwrap_or(u32::MAX);
    let mut covered: Vec<u16> = rx.iter().chain(tx).copied().collect();
    let mut out = Vec::new();
    while let Some(seed) = pdos.iter().find(|p| !covered.contains(&p.index)) {
        let mut set: Vec<&crate::esi::EsiPdo> = vec![*seed];
        for p in &pdos {
            if set.iter().any(|q| q.index == p.index || excludes(q, p)) {
                continue;
            }
            let same: Vec<&&crate::esi::EsiPdo> = set
                .iter()
                .filter(|q| is_rx(q.index) == is_rx(p.index))
                .collect();
            let bits: u32 = same.iter().map(|q| q.bits()).fold(0, u32::saturating_add);
            let entries: usize = same.iter().map(|q| q.entries.len()).sum();
            if bits.saturating_add(p.bits()) <= limit
                && entries + p.entries.len() <= ecat_slave::pdo::MAX_MAPPED
            {
                set.push(p);
            }
        }
        covered.extend(set.iter().map(|p| p.index));
        let (mut srx, mut stx) = (Vec::new(), Vec::new());
        for p in pdos
            .iter()
            .filter(|p| set.iter().any(|q| q.index == p.index))
        {
            if is_rx(p.index) {
                srx.push(p.index);
            } else {
                stx.push(p.index);
            }
        }
        out.push((srx, stx));
    }
    out
}

fn sm(dev: &EsiDevice, kind: SmType) -> Option<(u16, u16)> {
    dev.sms
        .iter()
        .find(|s| s.kind == kind)
        .map(|s| (s.start, s.default_size))
}

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

/// The type a PDO entry of CoE code `code` and `bits` bits has (a code
/// that is no base type, or none: by its size).
fn pdo_entry_type(code: u8, bits: u8) -> DataType {
    match dictionary::data_type_of_code(code) {
        Some(t)
            if t.is_bytes() || ecat_slave::od::dictionary::natural_bits(&t) == u16::from(bits) =>
        {
            t
        }
        _ => match bits {
            1 => DataType::Bool,
            2..=7 => DataType::Bits(bits),
            8 => DataType::UInt8,
            16 => DataType::UInt16,
            24 => DataType::UInt24,
            32 => DataType::UInt32,
            40 => DataType::UInt40,
            48 => DataType::UInt48,
            56 => DataType::UInt56,
            64 => DataType::UInt64,
            _ => DataType::OctetString,
        },
    }
}

/// An entry a PDO maps (`out`: an RxPDO's) as the device would describe
/// it: read-only inputs, writable outputs, of the PDO entry's type and
/// length.
fn mapped_entry(sub: u8, name: &str, ty: DataType, bits: u8, out: bool) -> Entry {
    let base = if out {
        output(sub, leak(name), ty)
    } else {
        input(sub, leak(name), ty)
    };
    Entry {
        bit_len: u16::from(bits),
        default: if ty.is_bytes() {
            DefaultValue::Bytes(&[])
        } else {
            DefaultValue::Int(0)
        },
        ..base
    }
}

/// Completes the dictionary of a device with CoE from its PDOs, as the
/// device must have it to run them (an ESI without a dictionary, only
/// `<ChannelInfo>` or no profile, gets all of it): 0x1000 (the profile
/// number), 0x1018, the PDO mapping objects, 0x1C00, 0x1C12/0x1C13
/// assigning the PDOs with a default SyncManager, and the entries the PDOs
/// map (a VAR for subindex 0 alone, else a record; read-only inputs and
/// writable outputs). An entry the dictionary has but does not let map the
/// way a PDO maps it is made mappable. What is added is named in
/// `warnings` when the ESI has a dictionary.
fn complete(dev: &EsiDevice, objects: &mut Vec<Object>, warnings: &mut Vec<Warning>) -> Vec<u16> {
    let mut conflicting: Vec<u16> = Vec::new();
    let mut outside: Vec<Warning> = Vec::new();
    let mut both: Vec<(u16, u8)> = Vec::new();
    let has_dictionary = !objects.is_empty();
    let mut note = |at: &At, message: String| {
        if has_dictionary {
            warnings.push(Warning {
                at: at.clone(),
                message,
            });
        }
    };
    let has = |objects: &[Object], i: u16| objects.iter().any(|o| o.index == i);
    if !has(objects, 0x1000) {
        let profile = dev
            .source
            .path("Profile/ChannelInfo/ProfileNo")
            .or_else(|| dev.source.path("Profile/ProfileNo"))
            .and_then(|p| crate::xml::number(&p.text))
            .unwrap_or(0);
        note(
            &dev.at,
            "no object 0x1000: made from the profile number".into(),
        );
        objects.push(Object {
            index: 0x1000,
            name: "Device type",
            code: ObjectCode::Var,
            entries: Box::leak(Box::new([var(
                "Device type",
                DataType::UInt32,
                PdoMapping::None,
                profile,
            )])),
        });
    }
    if !has(objects, 0x1018) {
        note(&dev.at, "no object 0x1018: made from the identity".into());
        objects.push(record(
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
        ));
    }
    // Mapped objects missing: index -> (name, [(sub, name, type, bits, out)]).
    type Missing = Vec<(u8, String, DataType, u8, bool)>;
    let mut missing: std::collections::BTreeMap<u16, (String, Missing)> =
        std::collections::BTreeMap::new();
    for (pdos, range) in [
        (&dev.rx_pdos, 0x1600..=0x17FFu16),
        (&dev.tx_pdos, 0x1A00..=0x1BFF),
    ] {
        for p in pdos.iter() {
            if !range.contains(&p.index) {
                // An RxPdo 0x1A00 (the EL9800's first revisions): no
                // mapping object of its direction can hold it.
                outside.push(Warning {
                    at: p.at.clone(),
                    message: format!(
                        "PDO {:#06x} is outside its direction's mapping objects ({:#06x}..{:#06x}): left out of the PDO sets",
                        p.index,
                        range.start(),
                        range.end()
                    ),
                });
                conflicting.push(p.index);
                continue;
            }
            if !has(objects, p.index) {
                let mut entries = vec![sub0(u8::try_from(p.entries.len()).unwrap_or(u8::MAX))];
                for (k, e) in p.entries.iter().enumerate() {
                    let sub = u8::try_from(k + 1).unwrap_or(u8::MAX);
                    let value =
                        u32::from(e.index) << 16 | u32::from(e.sub) << 8 | u32::from(e.bit_len);
                    entries.push(map(sub, ecat_slave::od::build::sub_name(sub), value));
                }
                note(
                    &p.at,
                    format!(
                        "PDO {:#06x} has no mapping object: made from the PDO",
                        p.index
                    ),
                );
                objects.push(record(p.index, &p.name, entries));
                continue;
            }
            // The mapping object's defaults must be the PDO's entries
            // (what the SII and the master see): where the dictionary says
            // otherwise, the PDO wins.
            let want: Vec<i64> = p
                .entries
                .iter()
                .map(|e| {
                    i64::from(
                        u32::from(e.index) << 16 | u32::from(e.sub) << 8 | u32::from(e.bit_len),
                    )
                })
                .collect();
            let Some(pos) = objects.iter().position(|o| o.index == p.index) else {
                continue;
            };
            let o = &objects[pos];
            let have = list_defaults(o);
            if have == want || o.code == ObjectCode::Var {
                continue;
            }
            note(
                &p.at,
                format!(
                    "PDO {:#06x}: the mapping object's defaults differ from the PDO's entries: the PDO's taken",
                    p.index
                ),
            );
            let n = u8::try_from(want.len()).unwrap_or(u8::MAX);
            let mut entries: Vec<Entry> = o.entries.iter().map(copy).collect();
            for (k, v) in want.iter().enumerate() {
                let sub = u8::try_from(k + 1).unwrap_or(u8::MAX);
                match entries.iter_mut().find(|e| e.sub == sub) {
                    Some(e) => e.default = DefaultValue::Int(*v),
                    None => entries.push(map(sub, ecat_slave::od::build::sub_name(sub), *v as u32)),
                }
            }
            entries.sort_by_key(|e| e.sub);
            if entries.first().is_some_and(|z| !z.access.writable()) {
                entries.retain(|e| e.sub <= n);
            }
            let highest = entries.iter().map(|e| e.sub).max().unwrap_or(0);
            if let Some(z) = entries.first_mut().filter(|z| z.sub == 0) {
                z.default =
                    DefaultValue::Int(i64::from(if z.access.writable() { n } else { highest }));
            }
            objects[pos] = Object {
                entries: Box::leak(entries.into_boxed_slice()),
                ..objects[pos]
            };
        }
    }
    // What the PDOs map: the ESI's PDOs, and the defaults of the
    // dictionary's own mapping objects (which may map more).
    let mut wanted: Vec<(At, u16, bool, crate::esi::EsiPdoEntry)> = Vec::new();
    for (pdos, out) in [(&dev.rx_pdos, true), (&dev.tx_pdos, false)] {
        // The default PDOs (with an Sm) first: they win a conflict.
        let ordered = pdos
            .iter()
            .filter(|p| p.sm.is_some())
            .chain(pdos.iter().filter(|p| p.sm.is_none()));
        for p in ordered {
            for e in p.entries.iter().filter(|e| e.index != 0) {
                wanted.push((p.at.clone(), p.index, out, e.clone()));
            }
        }
    }
    for o in objects.iter() {
        let out = (0x1600..=0x17FF).contains(&o.index);
        if !out && !(0x1A00..=0x1BFF).contains(&o.index) {
            continue;
        }
        let n = match o.entries.first().map(|e| e.default) {
            Some(DefaultValue::Int(n)) => n,
            _ => 0,
        };
        for e in o
            .entries
            .iter()
            .filter(|e| e.sub >= 1 && i64::from(e.sub) <= n)
        {
            let DefaultValue::Int(v) = e.default else {
                continue;
            };
            let (index, sub, bits) = ((v >> 16) as u16, (v >> 8) as u8, v as u8);
            if index == 0
                || wanted
                    .iter()
                    .any(|(_, p, _, x)| *p == o.index && x.index == index && x.sub == sub)
            {
                continue;
            }
            let name = format!("SubIndex {sub:03}");
            let entry = crate::esi::EsiPdoEntry {
                index,
                sub,
                bit_len: bits,
                name,
                data_type: 0,
            };
            wanted.push((dev.at.clone(), o.index, out, entry));
        }
    }
    {
        {
            let at = &dev.at;
            for (p_at, p_index, out, e) in &wanted {
                let (out, e) = (*out, e);
                let p_name = String::new();
                let p = (p_at, *p_index, &p_name);
                let _ = at;
                let dir = if out { PdoMapping::Rx } else { PdoMapping::Tx };
                let ty = pdo_entry_type(e.data_type, e.bit_len);
                let Some(pos) = objects.iter().position(|o| o.index == e.index) else {
                    let slot = missing
                        .entry(e.index)
                        .or_insert_with(|| (format!("{:#06x}", e.index), Vec::new()));
                    match slot.1.iter_mut().find(|(s, ..)| *s == e.sub) {
                        // Mapped both ways (an RxPDO and a TxPDO of it).
                        Some(x) if x.4 != out => both.push((e.index, e.sub)),
                        Some(_) => {}
                        None => slot.1.push((e.sub, e.name.clone(), ty, e.bit_len, out)),
                    }
                    continue;
                };
                let o = &objects[pos];
                match o.entries.iter().position(|x| x.sub == e.sub) {
                    Some(k)
                        if o.entries[k].bit_len != u16::from(e.bit_len) && !o.entries[k].gap =>
                    {
                        // One object, one size: a PDO that maps it with
                        // another length (Beckhoff's alternative PDOs of a
                        // wider time stamp) cannot be assigned.
                        note(
                            p.0,
                            format!(
                                "PDO {:#06x} maps {:#06x}:{:02x} with {} bits, the dictionary has {}: the PDO is left out of the PDO sets",
                                p.1, e.index, e.sub, e.bit_len, o.entries[k].bit_len
                            ),
                        );
                        if !conflicting.contains(&p.1) {
                            conflicting.push(p.1);
                        }
                    }
                    Some(k) => {
                        let x = &o.entries[k];
                        if !x.pdo.allows(dir) && !x.gap {
                            let pdo = if x.pdo == PdoMapping::None {
                                dir
                            } else {
                                PdoMapping::RxTx
                            };
                            note(
                                p.0,
                                format!(
                                    "PDO {:#06x} maps {:#06x}:{:02x}, which the dictionary does not let map this way: made mappable",
                                    p.1, e.index, e.sub
                                ),
                            );
                            let mut entries: Vec<Entry> = o.entries.iter().map(copy).collect();
                            if let Some(y) = entries.get_mut(k) {
                                y.pdo = pdo;
                            }
                            objects[pos] = Object {
                                entries: Box::leak(entries.into_boxed_slice()),
                                ..objects[pos]
                            };
                        }
                    }
                    None if o.code != ObjectCode::Var => {
                        note(
                            p.0,
                            format!(
                                "PDO {:#06x} maps {:#06x}:{:02x}, which object {:#06x} does not have: added",
                                p.1, e.index, e.sub, e.index
                            ),
                        );
                        let mut entries: Vec<Entry> = o.entries.iter().map(copy).collect();
                        entries.push(mapped_entry(e.sub, &e.name, ty, e.bit_len, out));
                        entries.sort_by_key(|x| x.sub);
                        let highest = entries.iter().map(|x| x.sub).max().unwrap_or(0);
                        if let Some(z) = entries.first_mut().filter(|z| z.sub == 0) {
                            z.default = DefaultValue::Int(i64::from(highest));
                        }
                        objects[pos] = Object {
                            entries: Box::leak(entries.into_boxed_slice()),
                            ..objects[pos]
                        };
                    }
                    None => note(
                        p.0,
                        format!(
                            "PDO {:#06x} maps {:#06x}:{:02x} of the variable {:#06x}",
                            p.1, e.index, e.sub, e.index
                        ),
                    ),
                }
            }
        }
    }
    if !has(objects, 0x1C00) {
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
        note(
            &dev.at,
            "no object 0x1C00: made from the SyncManagers".into(),
        );
        objects.push(array(0x1C00, "Sync manager type", sm_types));
    }
    for (index, name, pdos) in [
        (0x1C12u16, "RxPDO assign", &dev.rx_pdos),
        (0x1C13u16, "TxPDO assign", &dev.tx_pdos),
    ] {
        if has(objects, index) {
            continue;
        }
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
        note(
            &dev.at,
            format!("no object {index:#06x}: made from the PDOs' Sm"),
        );
        objects.push(array(index, name, entries));
    }
    for (index, (pdo_name, mut subs)) in missing {
        subs.sort_by_key(|s| s.0);
        note(
            &dev.at,
            format!(
                "PDO entries map {index:#06x}, which the dictionary does not have: made from the PDO entries"
            ),
        );
        let make = |(sub, name, ty, bits, out): &(u8, String, DataType, u8, bool)| {
            let e = mapped_entry(*sub, name, *ty, *bits, *out);
            if both.contains(&(index, *sub)) {
                Entry {
                    pdo: PdoMapping::RxTx,
                    access: ecat_slave::od::Access::Rw,
                    ..e
                }
            } else {
                e
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
    // A PDO left out of the sets keeps its mapping as the vendor wrote it
    // (Beckhoff's 32-bit views of 64-bit time stamps), which the core's
    // mapping rules would refuse as written back: such a mapping is fixed.
    for index in &conflicting {
        let Some(pos) = objects.iter().position(|o| o.index == *index) else {
            continue;
        };
        let o = &objects[pos];
        if o.code == ObjectCode::Var || !o.entries.iter().any(|e| e.access.writable()) {
            continue;
        }
        note(
            &dev.at,
            format!(
                "PDO {index:#06x} is left out of the PDO sets: its mapping object is read-only"
            ),
        );
        let entries: Vec<Entry> = o
            .entries
            .iter()
            .map(|e| Entry {
                access: ecat_slave::od::Access::Ro,
                ..copy(e)
            })
            .collect();
        objects[pos] = Object {
            entries: Box::leak(entries.into_boxed_slice()),
            ..objects[pos]
        };
    }
    objects.sort_by_key(|o| o.index);
    warnings.append(&mut outside);
    conflicting
}

fn modular_error(e: &crate::xml::Element, problem: impl Into<String>) -> DescriptionBuildError {
    DescriptionBuildError::Modular {
        at: At::of(e),
        problem: problem.into(),
    }
}

/// Object `index` of slot 0 in slot `slot`: PDO mapping objects step by
/// the PDO increment, the rest by the index distance.
fn shifted(index: u16, slot: u16, distance: u16, pdo_increment: u16) -> Option<u16> {
    let step = if (0x1600..=0x1BFF).contains(&index) {
        pdo_increment
    } else {
        distance
    };
    index.checked_add(step.checked_mul(slot)?)
}

/// A modular device (ETG.2000 `Slots` and `Modules`, ETG.5001): the module
/// types, every slot's copy of their objects appended to `objects` (PDO
/// mapping entries pointing at the slot's objects), and the layout.
fn modular(
    dev: &EsiDevice,
    slots_el: &crate::xml::Element,
    objects: &mut Vec<Object>,
    warnings: &mut Vec<Warning>,
) -> Result<Option<ecat_slave::od::modules::ModularLayout>, DescriptionBuildError> {
    use ecat_slave::od::modules::{ModularLayout, ModuleType, SlotRange};
    let num = |e: &crate::xml::Element, name: &str| -> Result<u16, DescriptionBuildError> {
        let v = e
            .attr(name)
            .ok_or_else(|| modular_error(e, format!("missing attribute {name}")))?;
        crate::xml::number(v)
            .and_then(|v| u16::try_from(v).ok())
            .ok_or_else(|| modular_error(e, format!("bad {name} '{v}'")))
    };
    let distance = num(slots_el, "SlotIndexIncrement")?;
    let pdo_increment = num(slots_el, "SlotPdoIncrement")?;
    let slots = u8::try_from(slots_el.children_named("Slot").count())
        .map_err(|_| modular_error(slots_el, "more than 255 slots"))?;
    if slots == 0 {
        return Err(modular_error(slots_el, "no <Slot>"));
    }
    let Some(modules_el) = dev.modules.as_ref() else {
        // Modules described in another file (a module library) that was
        // not given: the device runs with its slots empty.
        warnings.push(Warning::new(
            slots_el,
            "the file has no <Modules> (a module library in another file?): the slots stay empty",
        ));
        return Ok(None);
    };
    let mut types = Vec::new();
    let mut module_objects: Vec<Object> = Vec::new();
    for m in modules_el.children_named("Module") {
        let ty = m
            .child("Type")
            .ok_or_else(|| modular_error(m, "missing <Type>"))?;
        let ident = ty
            .attr("ModuleIdent")
            .and_then(crate::xml::number)
            .and_then(|v| u32::try_from(v).ok())
            .ok_or_else(|| modular_error(ty, "missing or bad ModuleIdent"))?;
        let pdo_list = |tag: &str| -> Result<Vec<u16>, DescriptionBuildError> {
            m.children_named(tag)
                .map(|p| {
                    p.text_at("Index")
                        .and_then(crate::xml::number)
                        .and_then(|v| u16::try_from(v).ok())
                        .ok_or_else(|| modular_error(p, "missing or bad <Index>"))
                })
                .collect()
        };
        types.push(ModuleType {
            ident,
            type_name: leak(ty.text.trim()),
            name: leak(m.text_at("Name").unwrap_or(ty.text.trim())),
            rx: leak_list(pdo_list("RxPdo")?),
            tx: leak_list(pdo_list("TxPdo")?),
        });
        if let Some(d) = m.path("Profile/Dictionary") {
            let (parsed, _, mut w) = dictionary::parse(d)?;
            warnings.append(&mut w);
            for p in parsed {
                if !module_objects.iter().any(|o| o.index == p.object.index) {
                    module_objects.push(p.object);
                }
            }
        }
    }
    if types.is_empty() {
        return Err(modular_error(modules_el, "no <Module>"));
    }
    let ranges: Vec<SlotRange> = module_objects
        .iter()
        .map(|o| SlotRange {
            base: o.index,
            distance: if (0x1600..=0x1BFF).contains(&o.index) {
                pdo_increment
            } else {
                distance
            },
            width: 1,
        })
        .collect();
    let slot_of_object = |index: u16| -> Option<u16> {
        ranges.iter().find_map(|r| {
            let off = index.checked_sub(r.base)?;
            (r.distance != 0 && off % r.distance == 0 && off / r.distance < u16::from(slots))
                .then_some(off / r.distance)
        })
    };
    for slot in 0..u16::from(slots) {
        for o in &module_objects {
            let index = shifted(o.index, slot, distance, pdo_increment).ok_or_else(|| {
                modular_error(
                    slots_el,
                    format!("object {:#06x} of slot {slot} beyond 0xFFFF", o.index),
                )
            })?;
            let entries: Vec<Entry> = o
                .entries
                .iter()
                .map(|e| {
                    // A mapping entry of slot 0 points at slot 0's object.
                    let default = match e.default {
                        DefaultValue::Int(v)
                            if (0x1600..=0x1BFF).contains(&o.index) && e.sub != 0 =>
                        {
                            let target = ((v >> 16) & 0xFFFF) as u16;
                            match slot_of_object(target).filter(|s| *s == 0) {
                                Some(_) => {
                                    let moved = shifted(target, slot, distance, pdo_increment)
                                        .unwrap_or(target);
                                    DefaultValue::Int((v & 0xFFFF) | i64::from(moved) << 16)
                                }
                                None => DefaultValue::Int(v),
                            }
                        }
                        d => d,
                    };
                    Entry { default, ..copy(e) }
                })
                .collect();
            if objects.iter().any(|x| x.index == index) {
                return Err(modular_error(
                    slots_el,
                    format!("object {index:#06x} of slot {slot} is also an object of the device"),
                ));
            }
            objects.push(Object {
                index,
                entries: Box::leak(entries.into_boxed_slice()),
                ..*o
            });
        }
    }
    modular_objects(slots_el, slots, distance, objects, warnings);
    objects.sort_by_key(|o| o.index);
    Ok(Some(ModularLayout {
        slots,
        index_distance: distance,
        pdo_increment,
        ranges: Box::leak(ranges.into_boxed_slice()),
        modules: Box::leak(types.into_boxed_slice()),
    }))
}

/// The objects of ETG.5001 a modular device must have (0xF000 modular
/// device profile, 0xF030 configured and 0xF050 detected module ident
/// list), made for a file that has Slots but leaves them out (the ETG's
/// own CiA 402 Modules/Slots example does): as the HCS DMA-22 node
/// describes them, each with a warning naming the Slots element.
fn modular_objects(
    slots_el: &crate::xml::Element,
    slots: u8,
    distance: u16,
    objects: &mut Vec<Object>,
    warnings: &mut Vec<Warning>,
) {
    use ecat_slave::od::Access;
    use ecat_slave::od::modules::{CONFIGURED_MODULES, DETECTED_MODULES, MODULAR_DEVICE_PROFILE};
    let ident_list = |access: Access| -> &'static [Entry] {
        let mut l = vec![Entry {
            access,
            min: Some(0),
            max: Some(i64::from(slots)),
            ..sub0(slots)
        }];
        if access == Access::RwPreOp {
            l[0].default = DefaultValue::Int(0);
        }
        for k in 1..=slots {
            l.push(Entry {
                access,
                ..constant(k, leak(&format!("SubIndex {k:03}")), DataType::UInt32, 0)
            });
        }
        Box::leak(l.into_boxed_slice())
    };
    let made: [(u16, &'static str, ObjectCode, &'static [Entry]); 3] = [
        (
            MODULAR_DEVICE_PROFILE,
            "Modular device profile",
            ObjectCode::Record,
            Box::leak(Box::new([
                sub0(2),
                constant(
                    1,
                    "Module index distance",
                    DataType::UInt16,
                    i64::from(distance),
                ),
                constant(
                    2,
                    "Maximum number of modules",
                    DataType::UInt16,
                    i64::from(slots),
                ),
            ])),
        ),
        (
            CONFIGURED_MODULES,
            "Configured module ident list",
            ObjectCode::Array,
            ident_list(Access::RwPreOp),
        ),
        (
            DETECTED_MODULES,
            "Detected module ident list",
            ObjectCode::Array,
            ident_list(Access::Ro),
        ),
    ];
    for (index, name, code, entries) in made {
        if objects.iter().any(|o| o.index == index) {
            continue;
        }
        warnings.push(Warning::new(
            slots_el,
            format!("object {index:#06x} '{name}' of a modular device (ETG.5001) is missing: made with {slots} slots"),
        ));
        objects.push(Object {
            index,
            name,
            code,
            entries,
        });
    }
}

/// The module idents of a modular device's slots: each `Slot`'s default
/// `ModuleIdent` (`Default="1"`, else its first), in slot order.
pub fn default_modules(dev: &EsiDevice) -> Vec<u32> {
    let Some(slots) = dev.source.child("Slots") else {
        return Vec::new();
    };
    slots
        .children_named("Slot")
        .filter_map(|s| {
            let ids: Vec<&crate::xml::Element> = s.children_named("ModuleIdent").collect();
            ids.iter()
                .find(|i| i.attr("Default") == Some("1"))
                .or(ids.first())
                .and_then(|i| crate::xml::number(&i.text))
                .and_then(|v| u32::try_from(v).ok())
        })
        .collect()
}

/// A description, its memory layout and what the loader left out or
/// assumed building it.
pub type Described = (&'static DeviceDescription, MemoryLayout, &'static [Warning]);

/// Descriptions built so far, one per distinct device.
static DESCRIPTIONS: crate::Cache<Described> = crate::Cache::new();

/// The twin's description and memory layout for `dev`. Built and leaked
/// once per distinct device: describing an equal device again returns the
/// same description.
pub fn describe(
    dev: &EsiDevice,
) -> Result<(&'static DeviceDescription, MemoryLayout), DescriptionBuildError> {
    describe_with_warnings(dev).map(|(d, l, _)| (d, l))
}

/// [`describe`] with the warnings: what of the ESI the twin leaves out or
/// assumes (the load's [`EsiDevice::warnings`] included), each naming the
/// element and line.
pub fn describe_with_warnings(dev: &EsiDevice) -> Result<Described, DescriptionBuildError> {
    DESCRIPTIONS.get_or_build(dev, build_description)
}

/// [`describe`] without the cache.
fn build_description(dev: &EsiDevice) -> Result<Described, DescriptionBuildError> {
    let label = dev.label();
    // ETG.2000 requires it; the SII General category of a CoE device
    // carries it.
    if dev.group_type.is_empty() {
        return Err(EsiError::Missing {
            at: dev.at.clone(),
            what: "<GroupType>",
        }
        .into());
    }
    let mut warnings = dev.warnings.clone();
    let (mut parsed, enums): (Vec<Object>, _) = match dev.source.path("Profile/Dictionary") {
        Some(dict_el) => {
            let (parsed, enums, mut w) = dictionary::parse(dict_el)?;
            warnings.append(&mut w);
            (parsed.into_iter().map(|p| p.object).collect(), enums)
        }
        None => (Vec::new(), Vec::new()),
    };
    let left_out = complete(dev, &mut parsed, &mut warnings);
    for index in [0x1C12u16, 0x1C13] {
        normalize_assignment(dev, &mut parsed, index, &left_out, &mut warnings);
    }
    drop_impossible_ranges(dev, &mut parsed, &mut warnings);
    // Writable strings beyond the store's string slots are served
    // read-only (the core keeps STRING_SLOTS of them).
    let mut strings = 0usize;
    for o in parsed.iter_mut() {
        let mut changed = None;
        for (k, e) in o.entries.iter().enumerate() {
            if let DefaultValue::Str(t) = e.default {
                let slot = t.len() <= ecat_slave::od::STRING_CAPACITY;
                if e.access.writable() && (!slot || strings >= ecat_slave::od::STRING_SLOTS) {
                    changed.get_or_insert_with(Vec::new).push(k);
                }
                if slot {
                    strings += 1;
                }
            }
        }
        if let Some(ks) = changed {
            warnings.push(Warning {
                at: dev.at.clone(),
                message: format!(
                    "object {:#06x}: a writable string beyond the twin's {} string slots of {} bytes is served read-only",
                    o.index,
                    ecat_slave::od::STRING_SLOTS,
                    ecat_slave::od::STRING_CAPACITY
                ),
            });
            let mut entries: Vec<Entry> = o.entries.iter().map(copy).collect();
            for k in ks {
                if let Some(e) = entries.get_mut(k) {
                    e.access = ecat_slave::od::Access::Ro;
                }
            }
            o.entries = Box::leak(entries.into_boxed_slice());
        }
    }
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
    let modular = match dev.source.child("Slots") {
        Some(slots) => modular(dev, slots, &mut objects, &mut warnings)?,
        None => None,
    };
    let entries = ecat_slave::od::dictionary::value_slots(&objects);
    if entries > TWIN_ENTRIES {
        return Err(DescriptionBuildError::TooManyEntries {
            device: label,
            entries,
        });
    }
    let sets = pdo_sets(dev, &objects, &left_out)?;
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
    // Process data without an <Sm> of its own: outputs right after the
    // input mailbox, inputs 0x100 bytes after the outputs; within 0xFFFF.
    let after = |base: u16, gap: u16, kind: SmType, what: &'static str| {
        let start = u32::from(base) + u32::from(gap);
        u16::try_from(start).map_err(|_| DescriptionBuildError::NoRoomFor {
            at: dev
                .sms
                .iter()
                .find(|s| s.kind == kind)
                .map_or_else(|| dev.at.clone(), |s| s.at.clone()),
            what,
            start,
        })
    };
    let pd_out = match sm(dev, SmType::ProcessOut) {
        Some(s) => s.0,
        None => after(mbx_in.0, mbx_in.1, SmType::MailboxIn, "outputs")?,
    };
    let pd_in = match (sm(dev, SmType::ProcessIn), sm(dev, SmType::ProcessOut)) {
        (Some(s), _) => s.0,
        (None, Some(_)) => after(pd_out, 0x100, SmType::ProcessOut, "inputs")?,
        (None, None) => after(pd_out, 0x100, SmType::MailboxIn, "inputs")?,
    };
    let eeprom_kbit = dev.eeprom_kbit().ok_or_else(|| EsiError::BadValue {
        at: dev.at.clone(),
        what: crate::esi::EEPROM_SIZE,
        value: dev.eeprom_bytes.unwrap_or(0).to_string(),
    })?;
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
    let (identity, names) = crate::identity_and_names(dev);
    let desc: &'static DeviceDescription = Box::leak(Box::new(DeviceDescription {
        identity,
        names,
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
            foe_security: ecat_slave::device::FoeSecurity::OPEN,
        },
        esc: EscConfig {
            pdi_control: u16::from_le_bytes([
                cd.first().copied().unwrap_or(0x05),
                cd.get(1).copied().unwrap_or(0),
            ]),
            eeprom_kbit,
            ebus_current_ma: dev.ebus_current_ma,
            physical_ports: crate::sii::physical_port(&dev.physics),
        },
        modules: modular.map(|m| &*Box::leak(Box::new(m))),
    }));
    desc.validate()
        .map_err(|source| DescriptionBuildError::Contradiction {
            device: dev.label(),
            source,
        })?;
    Ok((desc, layout, Box::leak(warnings.into_boxed_slice())))
}

/// The generic behaviour of a twin with a mailbox: outputs are stored by
/// the core; inputs (entries mappable into TxPDOs) follow the rule.
#[derive(Debug)]
pub struct EsiApp {
    desc: &'static DeviceDescription,
    rule: InputRule,
    /// Module idents a modular device detects at power-on, slot order.
    modules: Vec<u32>,
    /// (input flat position, bit length, output flat position of the same
    /// type for the loopback).
    inputs: Vec<(usize, u16, Option<usize>)>,
    ticks: u64,
    /// A drive's axes (CiA 402: profile 402 in 0x1000, or 0x6040/0x6041,
    /// one per axis at n × 0x800): the profile's state machine and axis
    /// model answer its controlword and set points, so a master enables
    /// the twin as it enables the drive.
    axes: Vec<ecat_cia402::Cia402Axis>,
}

impl EsiApp {
    /// The behaviour of `desc` with input rule `rule`.
    pub fn new(desc: &'static DeviceDescription, rule: InputRule) -> Self {
        let mut flat = 0usize;
        let mut ins: Vec<(usize, DataType, u16)> = Vec::new();
        let mut outs: Vec<(usize, DataType)> = Vec::new();
        for o in desc.dictionary.objects() {
            for e in o.entries {
                let numeric = !e.data_type.is_bytes() && !e.gap;
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
        let dict = desc.dictionary;
        let axes = if ecat_cia402::Cia402Axis::is_cia402(dict) {
            ecat_cia402::Cia402Axis::axes_of(dict)
                .filter_map(|n| {
                    ecat_cia402::Cia402Axis::with_axis(dict, n, ecat_cia402::AxisModel::default())
                        .ok()
                })
                .collect()
        } else {
            Vec::new()
        };
        EsiApp {
            desc,
            rule,
            modules: Vec::new(),
            inputs,
            ticks: 0,
            axes,
        }
    }

    /// How many CiA 402 axes the twin runs (0: not a drive).
    pub fn axes(&self) -> usize {
        self.axes.len()
    }

    /// The same with these modules plugged (a modular device; see
    /// [`default_modules`]).
    pub fn with_modules(mut self, idents: Vec<u32>) -> Self {
        self.modules = idents;
        self
    }
}

impl Application for EsiApp {
    fn description(&self) -> &'static DeviceDescription {
        self.desc
    }

    type Values = [i64; TWIN_ENTRIES];

    fn power_on(&mut self, od: &mut ecat_slave::od::store::Od) {
        if let Some(m) = self.desc.modules {
            m.set_detected(od, &self.modules);
        }
    }

    fn sdo_download(
        &mut self,
        _od: &mut ecat_slave::od::store::Od,
        d: &ecat_slave::device::Download<'_>,
    ) -> Result<ecat_slave::device::Write, ecat_slave::SdoAbortCode> {
        for axis in &self.axes {
            axis.check_download(d)?;
        }
        Ok(ecat_slave::device::Write::Store)
    }

    fn power_cycle(&mut self) {
        for axis in &mut self.axes {
            axis.reset();
        }
    }

    fn tick(&mut self, tick: &mut Tick<'_>) {
        self.tick_inputs(tick);
        // After the input rule: a drive's actual values are the axis's.
        for axis in &mut self.axes {
            axis.tick(tick, None);
        }
    }
}

impl EsiApp {
    fn tick_inputs(&mut self, tick: &mut Tick<'_>) {
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

/// A software slave of `desc` laid out as `layout`, with `modules`
/// plugged when it is a modular device.
pub fn slave(
    desc: &'static DeviceDescription,
    layout: MemoryLayout,
    rule: InputRule,
    modules: Vec<u32>,
) -> SoftSlave<EsiApp> {
    SoftSlave::with_layout(EsiApp::new(desc, rule).with_modules(modules), layout)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::esi::EsiFile;

    fn dev_with(pdos: &str) -> EsiDevice {
        let text = format!(
            r##"<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>
<Type ProductCode="#x1" RevisionNo="#x1">D</Type><Name>D</Name><GroupType>G</GroupType>
<Sm StartAddress="#x1000" DefaultSize="128" ControlByte="#x26" Enable="1">MBoxOut</Sm>
<Sm StartAddress="#x1080" DefaultSize="128" ControlByte="#x22" Enable="1">MBoxIn</Sm>
<Sm StartAddress="#x1100" ControlByte="#x64" Enable="1">Outputs</Sm>
<Sm StartAddress="#x1180" ControlByte="#x20" Enable="1">Inputs</Sm>
{pdos}
<Mailbox><CoE SdoInfo="1" PdoAssign="1"/></Mailbox>
</Device></Devices></Descriptions></EtherCATInfo>"##
        );
        EsiFile::parse(&text).unwrap().devices.remove(0)
    }

    fn pdo(tag: &str, index: u16, sm: Option<u8>, excludes: &[u16], entry: u16) -> String {
        let sm = sm.map_or(String::new(), |s| format!(" Sm=\"{s}\""));
        let ex: String = excludes
            .iter()
            .map(|e| format!("<Exclude>#x{e:04x}</Exclude>"))
            .collect();
        format!(
            "<{tag}{sm}><Index>#x{index:04x}</Index><Name>P</Name>{ex}<Entry><Index>#x{entry:04x}</Index><SubIndex>1</SubIndex><BitLen>16</BitLen><Name>v</Name><DataType>UINT</DataType></Entry></{tag}>"
        )
    }

    /// A device with mailbox SyncManagers `sms` (and no process-data
    /// ones unless `sms` has them).
    fn dev_with_sms(sms: &str) -> EsiDevice {
        let text = format!(
            r##"<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>
<Type ProductCode="#x1" RevisionNo="#x1">D</Type><Name>D</Name><GroupType>G</GroupType>
{sms}
<Mailbox><CoE SdoInfo="1"/></Mailbox>
</Device></Devices></Descriptions></EtherCATInfo>"##
        );
        EsiFile::parse(&text).unwrap().devices.remove(0)
    }

    #[test]
    fn process_data_placed_beyond_0xffff_is_a_load_error_naming_the_sm() {
        let mbx = |out: u16, inp: u16| {
            format!(
                "<Sm StartAddress=\"#x{out:04x}\" DefaultSize=\"128\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>\n\
                 <Sm StartAddress=\"#x{inp:04x}\" DefaultSize=\"128\" ControlByte=\"#x22\" Enable=\"1\">MBoxIn</Sm>"
            )
        };
        // MBoxIn ends at the top: the outputs would start at 0x10000.
        let e = describe(&dev_with_sms(&mbx(0xFF00, 0xFF80))).unwrap_err();
        assert_eq!(
            e.to_string(),
            "<Sm> at line 4: the outputs placed after this SyncManager would start at 0x10000, beyond the ESC address space (0xffff)"
        );
        // Outputs fit, the inputs 0x100 bytes later would not.
        let e = describe(&dev_with_sms(&mbx(0xFE00, 0xFE80))).unwrap_err();
        assert!(
            e.to_string()
                .contains("the inputs placed after this SyncManager would start at 0x10000"),
            "{e}"
        );
        // An output SM near the top and no input SM.
        let sms = format!(
            "{}\n<Sm StartAddress=\"#xfff0\" ControlByte=\"#x64\" Enable=\"1\">Outputs</Sm>",
            mbx(0x1000, 0x1080)
        );
        let e = describe(&dev_with_sms(&sms)).unwrap_err();
        assert!(
            e.to_string().starts_with("<Sm> at line 5: the inputs"),
            "{e}"
        );
        // Normal places still work.
        let (_, layout) = describe(&dev_with_sms(&mbx(0x1000, 0x1080))).unwrap();
        assert_eq!((layout.pd_out, layout.pd_in), (0x1100, 0x1200));
    }

    #[test]
    fn an_absurd_eeprom_size_set_by_code_is_an_error_not_a_wrap() {
        let mut d = dev_with_sms(
            "<Sm StartAddress=\"#x1000\" DefaultSize=\"128\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>\n\
             <Sm StartAddress=\"#x1080\" DefaultSize=\"128\" ControlByte=\"#x22\" Enable=\"1\">MBoxIn</Sm>",
        );
        d.eeprom_bytes = Some(u32::MAX);
        let e = describe(&d).unwrap_err();
        assert!(
            e.to_string()
                .contains("bad EEPROM ByteSize (at most 65535 kbit) '4294967295'"),
            "{e}"
        );
        d.eeprom_bytes = Some(4096);
        assert_eq!(describe(&d).unwrap().0.esc.eeprom_kbit, 32);
    }

    #[test]
    fn alternative_sets_honour_excludes_and_cover_every_pdo() {
        let d = dev_with(
            &[
                pdo("RxPdo", 0x1600, Some(2), &[0x1601], 0x7000),
                pdo("RxPdo", 0x1601, None, &[0x1600], 0x7010),
                pdo("RxPdo", 0x1602, None, &[], 0x7020),
                pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000),
            ]
            .concat(),
        );
        let sets = alternative_sets(&d, &[0x1600], &[0x1A00]);
        // 0x1601 excludes 0x1600: its set holds 0x1601, 0x1602, 0x1A00.
        assert_eq!(sets, [(vec![0x1601, 0x1602], vec![0x1A00])]);
        let d = dev_with(
            &[
                pdo("RxPdo", 0x1600, Some(2), &[], 0x7000),
                pdo("RxPdo", 0x1601, None, &[], 0x7010),
                pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000),
            ]
            .concat(),
        );
        let sets = alternative_sets(&d, &[0x1600], &[0x1A00]);
        assert_eq!(
            sets,
            [(vec![0x1600, 0x1601], vec![0x1A00])],
            "optional PDO with the default ones"
        );
        assert!(alternative_sets(&d, &[0x1600, 0x1601], &[0x1A00]).is_empty());
    }

    #[test]
    fn a_device_with_coe_is_described_and_its_errors_are_named() {
        // No dictionary: made from the PDOs; both PDO sets valid.
        let d = dev_with(
            &[
                pdo("RxPdo", 0x1600, Some(2), &[], 0x7000),
                pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000),
            ]
            .concat(),
        );
        let (desc, layout) = describe(&d).unwrap();
        assert_eq!(layout.mbx_out, (0x1000, 128));
        assert_eq!((layout.pd_out, layout.pd_in), (0x1100, 0x1180));
        assert!(desc.dictionary.find(0x7000).is_some());
        assert!(desc.mailbox.coe.sdo_info && desc.mailbox.coe.pdo_assign);
        // A REAL PDO entry: its object is a REAL output.
        let real = dev_with(
            &pdo("RxPdo", 0x1600, Some(2), &[], 0x7000)
                .replace("UINT", "REAL")
                .replace("<BitLen>16", "<BitLen>32"),
        );
        let (desc, _) = describe(&real).unwrap();
        let (_, e) = desc.dictionary.find_entry(0x7000, 1).unwrap();
        assert_eq!(
            (e.data_type, e.bit_len, e.pdo),
            (DataType::Real32, 32, PdoMapping::Rx)
        );
        // No GroupType (ETG.2000 requires one).
        let mut g = d.clone();
        g.group_type.clear();
        assert!(
            describe(&g)
                .unwrap_err()
                .to_string()
                .contains("<Device> at line 1: missing <GroupType>")
        );
        // Slots without the file's Modules, and without any Slot.
        let mut m = d.clone();
        // (Full literals: `Element` has a Drop impl, so no `..Default`.)
        m.source.children.push(crate::xml::Element {
            name: "Slots".into(),
            attrs: vec![
                ("SlotIndexIncrement".into(), "#x10".into()),
                ("SlotPdoIncrement".into(), "1".into()),
            ],
            text: String::new(),
            children: vec![crate::xml::Element {
                name: "Slot".into(),
                attrs: Vec::new(),
                text: String::new(),
                children: Vec::new(),
                line: 0,
            }],
            line: 0,
        });
        // Modules in a library not given: the slots stay empty, a warning.
        let (_, _, w) = describe_with_warnings(&m).unwrap();
        assert!(
            w.iter().any(|w| w
                .to_string()
                .starts_with("<Slots> at line 0: the file has no <Modules>")),
            "{w:?}"
        );
        if let Some(slots) = m.source.children.last_mut() {
            slots.children.clear();
        }
        let e = describe(&m).unwrap_err().to_string();
        assert!(e.contains("no <Slot>"), "{e}");
        // CoE without mailbox SyncManagers.
        let mut n = d.clone();
        n.sms
            .retain(|s| !matches!(s.kind, SmType::MailboxOut | SmType::MailboxIn));
        assert!(matches!(
            describe(&n),
            Err(DescriptionBuildError::NoMailboxSm(_))
        ));
    }

    #[test]
    fn the_counter_and_loopback_rules_drive_the_inputs() {
        let d = dev_with(
            &[
                pdo("RxPdo", 0x1600, Some(2), &[], 0x7000),
                pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000),
            ]
            .concat(),
        );
        let (desc, _) = describe(&d).unwrap();
        let mut store =
            ecat_slave::od::store::ObjectStore::<[i64; TWIN_ENTRIES]>::new(desc.dictionary);
        let od = <[i64; TWIN_ENTRIES] as ecat_slave::od::ValueStorage>::view_mut(&mut store);
        od.set(0x7000, 1, 1234);
        let mut em = ecat_slave::coe::emergency::Emergencies::default();
        let mut app = EsiApp::new(desc, InputRule::Loopback);
        app.tick(&mut Tick::new(
            od,
            0,
            true,
            ecat_slave::al::AlState::Op,
            &mut em,
        ));
        assert_eq!(od.get(0x6000, 1), Some(1234));
        let mut app = EsiApp::new(desc, InputRule::Counter);
        for _ in 0..3 {
            app.tick(&mut Tick::new(
                od,
                0,
                true,
                ecat_slave::al::AlState::Op,
                &mut em,
            ));
        }
        assert_eq!(od.get(0x6000, 1), Some(3));
    }

    #[test]
    fn a_modular_device_without_its_etg5001_objects_gets_them_with_a_warning() {
        let slots = crate::xml::parse("<Slots SlotIndexIncrement=\"#x800\"/>").unwrap();
        let mut objects = vec![record(0xF050, "Detected (the ESI's own)", vec![sub0(0)])];
        let mut warnings = Vec::new();
        modular_objects(&slots, 2, 0x800, &mut objects, &mut warnings);
        let idx: Vec<u16> = objects.iter().map(|o| o.index).collect();
        assert_eq!(idx, [0xF050, 0xF000, 0xF030], "the ESI's own 0xF050 kept");
        assert_eq!(objects[0].name, "Detected (the ESI's own)");
        let f000 = &objects[1];
        assert_eq!(f000.entries[1].default, DefaultValue::Int(0x800));
        assert_eq!(f000.entries[2].default, DefaultValue::Int(2));
        let f030 = &objects[2];
        assert_eq!(f030.entries.len(), 3, "subindex 0 and one per slot");
        assert_eq!(
            f030.entries[0].default,
            DefaultValue::Int(0),
            "nothing configured"
        );
        assert_eq!(f030.entries[1].access, ecat_slave::od::Access::RwPreOp);
        assert_eq!(warnings.len(), 2);
        assert!(
            warnings[1].to_string().contains("0xf030"),
            "{}",
            warnings[1]
        );
    }

    #[test]
    fn an_assignment_default_naming_a_pdo_the_device_lacks_becomes_the_esis_sm_pdos() {
        let dict = r##"<Profile><Dictionary><DataTypes>
<DataType><Name>DT1C13</Name><BitSize>48</BitSize>
<SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
<SubItem><SubIdx>1</SubIdx><Name>SubIndex 001</Name><Type>UINT</Type><BitSize>16</BitSize><BitOffs>16</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
<SubItem><SubIdx>2</SubIdx><Name>SubIndex 002</Name><Type>UINT</Type><BitSize>16</BitSize><BitOffs>32</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
</DataType></DataTypes><Objects>
<Object><Index>#x1c13</Index><Name>TxPDO assign</Name><Type>DT1C13</Type><BitSize>48</BitSize><Info>
<SubItem><Name>SubIndex 000</Name><Info><DefaultData>02</DefaultData></Info></SubItem>
<SubItem><Name>SubIndex 001</Name><Info><DefaultData>731a</DefaultData></Info></SubItem>
<SubItem><Name>SubIndex 002</Name><Info><DefaultData>001a</DefaultData></Info></SubItem>
</Info></Object></Objects></Dictionary></Profile>"##;
        let pdos = format!("{}{dict}", pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000));
        let (desc, _, warnings) = describe_with_warnings(&dev_with(&pdos)).unwrap();
        assert_eq!(desc.process_data.sets[0].tx, [0x1A00]);
        assert!(
            warnings
                .iter()
                .any(|w| w.message.starts_with("0x1c13 defaults to [1a73, 1a00]")),
            "{warnings:?}"
        );
    }
}
