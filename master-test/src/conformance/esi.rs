//! What the checker reads of a device's ESI: modules of a modular
//! device, their PDOs, the dictionary's object list.

use super::*;

/// The module idents of a modular device's detected module list (0xF050),
/// or `None` for a device without one.
pub(super) async fn detected_modules(c: &mut MailboxClient<'_>) -> Option<Vec<u32>> {
    let n = c.sdo_upload(0xF050, 0, false).await.ok()?;
    let mut idents = Vec::new();
    for s in 1..=n.first().copied().unwrap_or(0) {
        let v = c.sdo_upload(0xF050, s, false).await.ok()?;
        idents.push(u32::from_le_bytes(v.get(..4)?.try_into().ok()?));
    }
    Some(idents)
}

/// An ESI's `Slots` increments and its module types.
pub(super) struct EsiModules<'a> {
    /// `SlotIndexIncrement`.
    index_step: u16,
    /// `SlotPdoIncrement`.
    pdo_step: u16,
    /// `(ModuleIdent, Module)`.
    modules: Vec<(u32, &'a ecat_esi::xml::Element)>,
}

/// The ESI's `Slots` increments (index, PDO) and its modules by ident.
pub(super) fn esi_modules(root: &ecat_esi::xml::Element) -> Result<EsiModules<'_>, String> {
    let slots = root
        .path("Descriptions/Devices/Device/Slots")
        .ok_or("no Device/Slots")?;
    let inc = |name: &str| {
        slots
            .attr(name)
            .and_then(ecat_esi::xml::hex_dec)
            .and_then(|v| u16::try_from(v).ok())
            .ok_or(format!("Slots without a valid {name}"))
    };
    let (index_step, pdo_step) = (inc("SlotIndexIncrement")?, inc("SlotPdoIncrement")?);
    let modules = root
        .path("Descriptions/Modules")
        .ok_or("no Descriptions/Modules")?
        .children_named("Module")
        .map(|m| {
            m.path("Type")
                .and_then(|t| t.attr("ModuleIdent"))
                .and_then(ecat_esi::xml::hex_dec)
                .and_then(|v| u32::try_from(v).ok())
                .map(|id| (id, m))
                .ok_or_else(|| "a Module without a valid ModuleIdent".to_string())
        })
        .collect::<Result<_, _>>()?;
    Ok(EsiModules {
        index_step,
        pdo_step,
        modules,
    })
}

/// The ESI module with `ident`.
pub(super) fn esi_module<'a>(
    modules: &[(u32, &'a ecat_esi::xml::Element)],
    ident: u32,
) -> Result<&'a ecat_esi::xml::Element, String> {
    modules
        .iter()
        .find(|(id, _)| *id == ident)
        .map(|(_, m)| *m)
        .ok_or(format!("no Module with ident {ident:#010x}"))
}

/// The PDOs the ESI's modules give a modular device with `idents` in its
/// slots (in order): `(PDO index, mapping entries index << 16 | sub << 8 |
/// bits)`, moved into each slot by `SlotPdoIncrement` and
/// `SlotIndexIncrement` (ETG.2000 `Slots`, ETG.5001).
pub(super) fn esi_module_pdos(xml: &str, idents: &[u32]) -> Result<Vec<(u16, Vec<u32>)>, String> {
    let root = ecat_esi::xml::parse(xml).map_err(|e| e.to_string())?;
    let EsiModules {
        index_step,
        pdo_step,
        modules,
    } = esi_modules(&root)?;
    let mut out = Vec::new();
    for (slot, ident) in idents.iter().enumerate() {
        let slot = u16::try_from(slot).map_err(|_| "too many slots")?;
        let m = esi_module(&modules, *ident)?;
        for pdo in m.children_named("RxPdo").chain(m.children_named("TxPdo")) {
            let hex = |e: &ecat_esi::xml::Element, p: &str| {
                e.text_at(p)
                    .and_then(ecat_esi::xml::hex_dec)
                    .and_then(|v| u32::try_from(v).ok())
            };
            let index = hex(pdo, "Index").ok_or("a module PDO without an Index")?;
            let mut entries = Vec::new();
            for e in pdo.children_named("Entry") {
                let i = hex(e, "Index").ok_or("a PDO entry without an Index")?;
                let sub = hex(e, "SubIndex").unwrap_or(0);
                let bits = hex(e, "BitLen").ok_or("a PDO entry without a BitLen")?;
                let i = if i == 0 {
                    0
                } else {
                    i + u32::from(index_step) * u32::from(slot)
                };
                entries.push((i << 16) | (sub << 8) | bits);
            }
            let moved = index as u16 + pdo_step * slot;
            out.push((moved, entries));
        }
    }
    Ok(out)
}

/// The object indices of an ESI's dictionary (first device); of a modular
/// device also its modules' objects for the modules `idents` in its slots.
pub(super) fn esi_objects(xml: &str, idents: &[u32]) -> Result<Vec<u16>, String> {
    let root = ecat_esi::xml::parse(xml).map_err(|e| e.to_string())?;
    let device = root
        .path("Descriptions/Devices/Device")
        .ok_or("no Descriptions/Devices/Device")?;
    let objects = device
        .path("Profile/Dictionary/Objects")
        .ok_or("no Profile/Dictionary/Objects")?;
    let index_of = |o: &ecat_esi::xml::Element| {
        o.text_at("Index")
            .and_then(ecat_esi::xml::hex_dec)
            .and_then(|v| u16::try_from(v).ok())
            .ok_or_else(|| "an Object without a valid Index".to_string())
    };
    let mut out: Vec<u16> = objects
        .children_named("Object")
        .map(index_of)
        .collect::<Result<_, _>>()?;
    if !idents.is_empty() {
        let EsiModules {
            index_step,
            pdo_step,
            modules,
        } = esi_modules(&root)?;
        for (slot, ident) in idents.iter().enumerate() {
            let slot = u16::try_from(slot).map_err(|_| "too many slots")?;
            let m = esi_module(&modules, *ident)?;
            let objs = m
                .path("Profile/Dictionary/Objects")
                .ok_or("a Module without Profile/Dictionary/Objects")?;
            for o in objs.children_named("Object") {
                let i = index_of(o)?;
                let step = if (0x1600..=0x1BFF).contains(&i) {
                    pdo_step
                } else {
                    index_step
                };
                out.push(i + step * slot);
            }
        }
        out.sort_unstable();
    }
    Ok(out)
}
