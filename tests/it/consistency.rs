//! One source of truth: the generated ESI, the model and what the live
//! slave reports over SDO Information and SDO must agree.

use ecat_esi::xml::{Element, hex_binary, hex_dec};
use master_test::VirtualBus;
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use master_test::sdo_info::{entry_description, object_description, od_list};
use pam_199_p_etc::od as model;
use std::collections::BTreeMap;

/// CoE data type code of an ESI type name.
fn type_code(name: &str) -> Option<u16> {
    if let Some(t) = ecat_slave::od::types::base_type_named(name) {
        return Some(t.code);
    }
    (name.starts_with("DT08") && name.contains("EN"))
        .then(|| u16::from_str_radix(name.get(2..6)?, 16).ok())
        .flatten()
}

/// One entry as the ESI describes it.
#[derive(Debug)]
struct EsiEntry {
    name: String,
    type_name: String,
    bit_size: u16,
    access: String,
    default: Option<Vec<u8>>,
}

type EsiDictionary = BTreeMap<u16, (String, BTreeMap<u8, EsiEntry>)>;

/// The device's objects as its ESI describes them; for a modular device
/// (ETG.2000 `Slots`) also the objects of the module in each slot of
/// `modules` (its `ModuleIdent`, in slot order), at the slot-0 index plus
/// slot × `SlotIndexIncrement`.
fn esi_dictionary(doc: &Element, modules: &[u32]) -> EsiDictionary {
    let dev = doc.path("Descriptions/Devices/Device").expect("device");
    let mut out = profile_dictionary(dev.path("Profile/Dictionary").expect("dictionary"), 0, 0);
    if let Some(slots) = dev.path("Slots") {
        let step = hex_dec(
            slots
                .attr("SlotIndexIncrement")
                .expect("SlotIndexIncrement"),
        )
        .unwrap();
        let pdo_step = hex_dec(slots.attr("SlotPdoIncrement").expect("SlotPdoIncrement")).unwrap();
        let types: Vec<&Element> = doc
            .path("Descriptions/Modules")
            .expect("Modules")
            .children_named("Module")
            .collect();
        for (slot, ident) in modules.iter().enumerate() {
            let module = types
                .iter()
                .find(|m| {
                    m.path("Type")
                        .and_then(|t| t.attr("ModuleIdent"))
                        .and_then(hex_dec)
                        == Some(i64::from(*ident))
                })
                .unwrap_or_else(|| panic!("no ESI module with ident {ident:#x}"));
            let dict = module
                .path("Profile/Dictionary")
                .expect("module dictionary");
            out.extend(profile_dictionary(
                dict,
                (step as usize * slot) as u16,
                (pdo_step as usize * slot) as u16,
            ));
        }
    }
    out
}

/// The objects of one ESI `Dictionary`, their indices moved by `shift`
/// (PDO mapping objects by `pdo_shift`, the objects they map by `shift`,
/// as a configurator places a module into a slot, ETG.2000 `Slots`).
fn profile_dictionary(dict: &Element, shift: u16, pdo_shift: u16) -> EsiDictionary {
    let types: BTreeMap<String, &Element> = dict
        .path("DataTypes")
        .expect("data types")
        .children_named("DataType")
        .map(|t| (t.text_at("Name").unwrap_or("").to_string(), t))
        .collect();
    let mut out = BTreeMap::new();
    for obj in dict
        .path("Objects")
        .expect("objects")
        .children_named("Object")
    {
        let index = hex_dec(obj.text_at("Index").unwrap()).unwrap() as u16;
        let mapping = (0x1600..=0x1BFF).contains(&index);
        let index = index + if mapping { pdo_shift } else { shift };
        let name = obj.text_at("Name").unwrap().to_string();
        let type_name = obj.text_at("Type").unwrap().to_string();
        let mut entries = BTreeMap::new();
        let access = obj.text_at("Flags/Access").unwrap_or("").to_string();
        match types
            .get(&type_name)
            .filter(|t| t.child("SubItem").is_some())
        {
            None => {
                let default = obj
                    .text_at("Info/DefaultData")
                    .and_then(hex_binary)
                    .or_else(|| {
                        obj.text_at("Info/DefaultString")
                            .map(|s| s.as_bytes().to_vec())
                    });
                entries.insert(
                    0,
                    EsiEntry {
                        name: name.clone(),
                        type_name: type_name.clone(),
                        bit_size: obj.text_at("BitSize").unwrap().parse().unwrap(),
                        access,
                        default,
                    },
                );
            }
            Some(t) => {
                // Arrays: the element type holds "Elements"; sub-items list
                // SubIndex 000 and the elements.
                // Defaults by sub-item name (padding gaps have none); array
                // elements by position among the unnamed rest.
                let info_items: Vec<(String, Option<Vec<u8>>)> = obj
                    .path("Info")
                    .map(|i| {
                        i.children_named("SubItem")
                            .map(|s| {
                                (
                                    s.text_at("Name").unwrap_or("").to_string(),
                                    s.text_at("Info/DefaultData").and_then(hex_binary),
                                )
                            })
                            .collect()
                    })
                    .unwrap_or_default();
                let defaults: Vec<Option<Vec<u8>>> =
                    info_items.iter().map(|(_, d)| d.clone()).collect();
                let by_name = |n: &str| {
                    info_items
                        .iter()
                        .find(|(name, _)| name == n)
                        .and_then(|(_, d)| d.clone())
                };
                let mut pos = 0;
                for si in t.children_named("SubItem") {
                    let sub_name = si.text_at("Name").unwrap().to_string();
                    let ty = si.text_at("Type").unwrap().to_string();
                    let bits: u16 = si.text_at("BitSize").unwrap().parse().unwrap();
                    let acc = si.text_at("Flags/Access").unwrap_or("").to_string();
                    match si.text_at("SubIdx") {
                        Some(idx) => {
                            let default = by_name(&sub_name);
                            entries.insert(
                                idx.parse::<u8>().unwrap(),
                                EsiEntry {
                                    name: sub_name,
                                    type_name: ty,
                                    bit_size: bits,
                                    access: acc,
                                    default,
                                },
                            );
                            pos += 1;
                        }
                        None => {
                            // Array elements: type DTxxxxARR with ArrayInfo.
                            let arr = types.get(&ty).expect("array type");
                            let elem = arr.text_at("BaseType").unwrap().to_string();
                            let ebits: u16 = types
                                .get(&elem)
                                .and_then(|e| e.text_at("BitSize"))
                                .unwrap_or("0")
                                .parse()
                                .unwrap();
                            let lbound: u8 =
                                arr.text_at("ArrayInfo/LBound").unwrap().parse().unwrap();
                            let n: u8 = arr.text_at("ArrayInfo/Elements").unwrap().parse().unwrap();
                            for k in 0..n {
                                entries.insert(
                                    lbound + k,
                                    EsiEntry {
                                        name: String::new(),
                                        type_name: elem.clone(),
                                        bit_size: ebits,
                                        access: acc.clone(),
                                        default: defaults.get(pos).cloned().flatten(),
                                    },
                                );
                                pos += 1;
                            }
                        }
                    }
                }
            }
        }
        if mapping && shift != 0 {
            // A mapping entry is index << 16 | sub << 8 | bits, LE.
            for e in entries.values_mut().filter(|e| e.bit_size == 32) {
                if let Some(d) = e.default.as_mut().filter(|d| d.len() == 4) {
                    let v = u32::from_le_bytes([d[0], d[1], d[2], d[3]]);
                    let moved = v.wrapping_add(u32::from(shift) << 16);
                    d.copy_from_slice(&moved.to_le_bytes());
                }
            }
        }
        out.insert(index, (name, entries));
    }
    out
}

fn access_bits(esi: &str) -> Option<u16> {
    match esi {
        "ro" => Some(0x07),
        "rw" => Some(0x3F),
        "wo" => Some(0x38),
        _ => None,
    }
}

/// What the comparison of one device's ESI with its live slave covered.
struct Compared {
    /// Modules detected (0xF050) of a modular device.
    modules: u8,
    entries: usize,
    gaps: usize,
    ranges: usize,
}

/// The generated ESI of catalog device `key` against what a live slave of
/// it reports over SDO Information: object list, names, max subindex, every
/// entry's name, bit size, type, access and default, and every range.
fn esi_equals_sdo_information(key: &str) -> Compared {
    let entry = device_catalog::find(key).expect("catalog device");
    let dev = entry.description;
    let xml = ecat_esi::generate(dev).expect("ESI");
    let doc = ecat_esi::xml::parse(std::str::from_utf8(&xml).unwrap()).expect("parse");
    smol::block_on(async {
        let bus = VirtualBus::line(key, master_test::link::Clock::frames()).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        let mut c = MailboxClient::new(md, station, MailboxGeometry::of(&dev.layout()));
        // A modular device: the modules it detected, as a master reads them.
        let mut modules = Vec::new();
        if dev.modules.is_some() {
            let n = c.sdo_upload(0xF050, 0, false).await.expect("0xF050:00")[0];
            for s in 1..=n {
                let v = c.sdo_upload(0xF050, s, false).await.expect("0xF050");
                modules.push(u32::from_le_bytes(v[..4].try_into().unwrap()));
            }
        }
        let esi = esi_dictionary(&doc, &modules);
        let slots = modules.len() as u8;
        let visible = |index: u16| {
            dev.modules
                .and_then(|m| m.slot_of(index))
                .is_none_or(|s| s < slots)
        };
        let live: Vec<u16> = od_list(&mut c, 1).await.expect("OD list");
        let esi_indices: Vec<u16> = esi.keys().copied().collect();
        assert_eq!(live, esi_indices, "{key}: object lists");
        let model_indices: Vec<u16> = dev
            .dictionary
            .objects()
            .iter()
            .map(|o| o.index)
            .filter(|i| visible(*i))
            .collect();
        assert_eq!(live, model_indices, "{key}");
        let mut checked = 0;
        let mut gaps = 0;
        for (index, (name, entries)) in &esi {
            let info = object_description(&mut c, *index)
                .await
                .expect("object description");
            assert_eq!(&info.name, name, "{index:#06x} name");
            assert_eq!(
                info.max_sub,
                *entries.keys().max().unwrap(),
                "{index:#06x} max subindex"
            );
            for (sub, e) in entries {
                let live = entry_description(&mut c, *index, *sub, 0x10)
                    .await
                    .expect("entry");
                if !e.name.is_empty() && entries.len() > 1 {
                    assert_eq!(live.name, e.name, "{index:#06x}:{sub} name");
                }
                assert_eq!(live.bit_len, e.bit_size, "{index:#06x}:{sub} bit size");
                if e.access.is_empty() && entries.len() > 1 && *sub > 0 {
                    // A padding gap: the ESI keeps its place in the layout
                    // without access rights; SDO Information says NULL
                    // with no access (as the SSC).
                    assert_eq!(
                        (live.data_type, live.access),
                        (0x0000, 0x0000),
                        "{index:#06x}:{sub} padding"
                    );
                    gaps += 1;
                    checked += 1;
                    continue;
                }
                if let Some(code) = type_code(&e.type_name) {
                    assert_eq!(
                        live.data_type, code,
                        "{index:#06x}:{sub} type {}",
                        e.type_name
                    );
                }
                if let Some(bits) = access_bits(&e.access) {
                    assert_eq!(
                        live.access & 0x38 != 0,
                        bits & 0x38 != 0,
                        "{index:#06x}:{sub} write"
                    );
                    assert_eq!(
                        live.access & 0x07 != 0,
                        bits & 0x07 != 0,
                        "{index:#06x}:{sub} read"
                    );
                }
                if let (Some(d), Some(ld)) = (&e.default, &live.default) {
                    assert_eq!(d, ld, "{index:#06x}:{sub} default");
                }
                checked += 1;
            }
        }
        // Ranges: every entry with a min/max in the model reports exactly
        // those through SDO Information (value info: minimum | maximum).
        let mut ranges = 0;
        for obj in dev.dictionary.objects().iter().filter(|o| visible(o.index)) {
            for e in obj.entries {
                let (Some(min), Some(max)) = (e.min(), e.max()) else {
                    continue;
                };
                let live = entry_description(&mut c, obj.index, e.sub, 0x60)
                    .await
                    .expect("entry");
                let n = usize::from(e.bit_len).div_ceil(8);
                assert_eq!(
                    live.min.as_deref(),
                    Some(&min.to_le_bytes()[..n]),
                    "{:#06x}:{} min",
                    obj.index,
                    e.sub
                );
                assert_eq!(
                    live.max.as_deref(),
                    Some(&max.to_le_bytes()[..n]),
                    "{:#06x}:{} max",
                    obj.index,
                    e.sub
                );
                ranges += 1;
            }
        }
        Compared {
            modules: slots,
            entries: checked,
            gaps,
            ranges,
        }
    })
}

#[test]
fn esi_dictionary_equals_what_sdo_information_reports_live() {
    let c = esi_equals_sdo_information("pam");
    assert!(c.entries > 280, "only {} entries compared", c.entries);
    assert_eq!(c.gaps, 18, "the 18 padding gaps of MANUAL-NOTES note 20");
    assert!(c.ranges > 100, "{} ranges compared", c.ranges);
    let _ = model::OBJECTS;
}

#[test]
fn every_catalog_device_reports_over_sdo_information_what_its_esi_says() {
    for d in device_catalog::DEVICES {
        let c = esi_equals_sdo_information(d.key);
        let dict = d.description.dictionary;
        assert_eq!(
            c.modules > 0,
            d.description.modules.is_some(),
            "{}: a modular device's module objects were compared",
            d.key
        );
        // Of a modular device, the objects of the slots that hold a module.
        let shown = || {
            dict.entries().filter(|(_, o, _)| {
                d.description
                    .modules
                    .and_then(|m| m.slot_of(o.index))
                    .is_none_or(|s| s < c.modules)
            })
        };
        assert_eq!(
            c.entries,
            shown().count(),
            "{}: every entry compared",
            d.key
        );
        let want_gaps = shown().filter(|(_, _, e)| e.gap()).count();
        assert_eq!(c.gaps, want_gaps, "{}", d.key);
        let want_ranges = shown()
            .filter(|(_, _, e)| e.min().is_some() && e.max().is_some())
            .count();
        assert_eq!(c.ranges, want_ranges, "{}", d.key);
    }
}

#[test]
fn esi_pdo_sets_equal_the_live_mapping_and_assignment_objects() {
    let xml = ecat_esi::generate(&pam_199_p_etc::DEVICE).expect("ESI");
    let doc = ecat_esi::xml::parse(std::str::from_utf8(&xml).unwrap()).expect("parse");
    let dev = doc.path("Descriptions/Devices/Device").expect("device");
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let mut defaults = (Vec::new(), Vec::new());
        for (tag, list) in [("RxPdo", 0), ("TxPdo", 1)] {
            for pdo in dev.children_named(tag) {
                let index = hex_dec(pdo.text_at("Index").unwrap()).unwrap() as u16;
                let entries: Vec<u32> = pdo
                    .children_named("Entry")
                    .map(|e| {
                        let i = hex_dec(e.text_at("Index").unwrap()).unwrap() as u32;
                        let s = e.text_at("SubIndex").map_or(0, |s| hex_dec(s).unwrap()) as u32;
                        let b: u32 = e.text_at("BitLen").unwrap().parse().unwrap();
                        (i << 16) | (s << 8) | b
                    })
                    .collect();
                let n: u8 = sd.sdo_read(index, 0).await.expect("count");
                assert_eq!(usize::from(n), entries.len(), "{index:#06x} entry count");
                for (k, want) in entries.iter().enumerate() {
                    let got: u32 = sd.sdo_read(index, k as u8 + 1).await.expect("mapping");
                    assert_eq!(got, *want, "{index:#06x}:{}", k + 1);
                }
                if pdo.attr("Sm").is_some() {
                    if list == 0 {
                        defaults.0.push(index);
                    } else {
                        defaults.1.push(index);
                    }
                }
            }
        }
        // The default set (Sm attribute in the ESI) is the live assignment.
        for (assign, want) in [(0x1C12u16, &defaults.0), (0x1C13, &defaults.1)] {
            let n: u8 = sd.sdo_read(assign, 0).await.expect("count");
            let mut live = Vec::new();
            for k in 1..=n {
                live.push(sd.sdo_read::<u16>(assign, k).await.expect("pdo"));
            }
            assert_eq!(&live, want, "{assign:#06x}");
        }
        // The alternative set (independent mode) is assignable and maps the
        // same as its ESI description: write it and read it back.
        sd.sdo_write(0x1C12, 1, 0x1601u16)
            .await
            .expect("IND outputs");
        let v: u16 = sd.sdo_read(0x1C12, 1).await.expect("read");
        assert_eq!(v, 0x1601);
    });
}
