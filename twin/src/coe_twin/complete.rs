//! What a twin's dictionary lacks, filled in from the ESI's PDOs (mapping
//! objects, mapped entries, 0x1000, 0x1018, 0x1C00, 0x1C12/0x1C13), and
//! what a device could not have, normalised (default assignments, ranges
//! that hold no default): each with a warning naming element and line.

use super::*;

/// The default assignment `index` (0x1C12/0x1C13) as the core reads it:
/// subindex 0 the number of PDOs, then the PDOs, without empty (0) places
/// and without PDOs the twin leaves out; a warning when that changes it.
pub(super) fn normalize_assignment(
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
            0 => *e = crate::with_default(e, DefaultValue::int(want.len() as i64)),
            s => {
                *e = crate::with_default(
                    e,
                    DefaultValue::int(want.get(usize::from(s) - 1).copied().unwrap_or(0)),
                )
            }
        }
    }
    o.entries = Box::leak(entries.into_boxed_slice());
}

/// Ranges a device could not have (minimum above maximum, a default
/// outside them or outside its type) are dropped with a warning: the
/// entry is served without one, as a configurator would read it.
pub(super) fn drop_impossible_ranges(
    dev: &EsiDevice,
    objects: &mut [Object],
    warnings: &mut Vec<Warning>,
) {
    use ecat_slave::od::dictionary::{natural_range, value_le};
    for o in objects.iter_mut() {
        let bad: Vec<usize> = o
            .entries
            .iter()
            .enumerate()
            .filter(|(_, e)| {
                let Some(v) = e.default_value().as_int() else {
                    return false;
                };
                if e.data_type.is_bytes() || matches!(e.data_type, DataType::Enum(_)) {
                    return false;
                }
                let t = &e.data_type;
                let (lo, hi) = (e.min().unwrap_or(v), e.max().unwrap_or(v));
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
                        o.index, e.sub, e.min(), e.max(), e.default_value()
                    ),
                });
                let default = e.default_value();
                e.limits = crate::leak_limits(None, None, e.unit());
                *e = crate::with_default(e, default);
                // A default outside its type: its bits in the type's size.
                if let Some(v) = e.default_value().as_int() {
                    let (lo, hi) =
                        ecat_slave::od::dictionary::natural_range(&e.data_type, e.bit_len);
                    if !e.data_type.is_real() && (v < lo || v > hi) {
                        let cut = ecat_slave::od::store::from_raw(
                            e,
                            v as u64
                                & u64::MAX
                                    .checked_shr(64 - u32::from(e.bit_len.clamp(1, 64)))
                                    .unwrap_or(u64::MAX),
                        );
                        *e = crate::with_default(e, DefaultValue::int(cut));
                    }
                }
            }
        }
        o.entries = Box::leak(entries.into_boxed_slice());
    }
}

/// The type a PDO entry of CoE code `code` and `bits` bits has (a code
/// that is no base type, or none: by its size).
pub(super) fn pdo_entry_type(code: u8, bits: u8) -> DataType {
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
pub(super) fn mapped_entry(sub: u8, name: &str, ty: DataType, bits: u8, out: bool) -> Entry {
    let base = if out {
        output(sub, leak(name), ty)
    } else {
        input(sub, leak(name), ty)
    };
    let entry = Entry {
        bit_len: u16::from(bits),
        ..base
    };
    if ty.is_bytes() {
        crate::with_default(&entry, DefaultValue::Bytes(&[]))
    } else {
        entry
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
pub(super) fn complete(
    dev: &EsiDevice,
    objects: &mut Vec<Object>,
    warnings: &mut Vec<Warning>,
) -> Vec<u16> {
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
            // The file's number, whatever its size: the entry keeps it
            // (in its limits when 32 bits cannot hold it).
            entries: Box::leak(Box::new([crate::with_default(
                &var("Device type", DataType::UInt32, PdoMapping::None, 0),
                DefaultValue::int(profile),
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
                    Some(e) => *e = crate::with_default(e, DefaultValue::int(*v)),
                    None => entries.push(map(sub, ecat_slave::od::build::sub_name(sub), *v as u32)),
                }
            }
            entries.sort_by_key(|e| e.sub);
            if entries.first().is_some_and(|z| !z.access().writable()) {
                entries.retain(|e| e.sub <= n);
            }
            let highest = entries.iter().map(|e| e.sub).max().unwrap_or(0);
            if let Some(z) = entries.first_mut().filter(|z| z.sub == 0) {
                *z = crate::with_default(
                    z,
                    DefaultValue::int(i64::from(if z.access().writable() { n } else { highest })),
                );
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
        let n = o
            .entries
            .first()
            .and_then(|e| e.default_value().as_int())
            .unwrap_or(0);
        for e in o
            .entries
            .iter()
            .filter(|e| e.sub >= 1 && i64::from(e.sub) <= n)
        {
            let Some(v) = e.default_value().as_int() else {
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
                        if o.entries[k].bit_len != u16::from(e.bit_len) && !o.entries[k].gap() =>
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
                        if !x.pdo().allows(dir) && !x.gap() {
                            let pdo = if x.pdo() == PdoMapping::None {
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
                                y.flags = y.flags.with_pdo(pdo);
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
                            *z = crate::with_default(z, DefaultValue::int(i64::from(highest)));
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
        let mut entries = vec![Entry {
            // `assign_count` spells out capacities up to 32 only.
            limits: crate::leak_limits(Some(0), Some(i64::from(cap)), ""),
            ..assign_count(u8::try_from(def.len()).unwrap_or(u8::MAX), cap)
        }];
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
                e.with_access(ecat_slave::od::Access::Rw)
                    .with_pdo(PdoMapping::RxTx)
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
        if o.code == ObjectCode::Var || !o.entries.iter().any(|e| e.access().writable()) {
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
            .map(|e| copy(e).with_access(ecat_slave::od::Access::Ro))
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
