//! The PDO sets of a twin: `AlternativeSmMapping`, else the default
//! assignment and sets that honour `Exclude`.

use super::*;

/// The PDOs an assignment object (0x1C12/0x1C13) lists by default.
pub(super) fn assigned(objects: &[Object], index: u16) -> Vec<u16> {
    let Some(o) = objects.iter().find(|o| o.index == index) else {
        return Vec::new();
    };
    let n = o
        .entries
        .first()
        .and_then(|e| e.default_value().as_int())
        .unwrap_or(0);
    o.entries
        .iter()
        .filter(|e| e.sub >= 1 && i64::from(e.sub) <= n)
        .filter_map(|e| match e.default_value() {
            DefaultValue::Int(v) => u16::try_from(v.get()).ok().filter(|v| *v != 0),
            DefaultValue::Str(_) | DefaultValue::Bytes(_) => None,
        })
        .collect()
}

/// The PDO sets of the device.
pub(super) fn pdo_sets(
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
