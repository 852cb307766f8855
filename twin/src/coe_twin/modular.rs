//! Modular devices (ETG.2000 `Slots` and `Modules`, ETG.5001): module
//! types, every slot's copy of their objects, the objects of ETG.5001 a
//! file leaves out.

use super::*;

pub(super) fn modular_error(
    e: &crate::xml::Element,
    problem: impl Into<String>,
) -> DescriptionBuildError {
    DescriptionBuildError::Modular {
        at: At::of(e),
        problem: problem.into(),
    }
}

/// Object `index` of slot 0 in slot `slot`: PDO mapping objects step by
/// the PDO increment, the rest by the index distance.
pub(super) fn shifted(index: u16, slot: u16, distance: u16, pdo_increment: u16) -> Option<u16> {
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
pub(super) fn modular(
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
                    let default = match e.default_value() {
                        DefaultValue::Int(v)
                            if (0x1600..=0x1BFF).contains(&o.index) && e.sub != 0 =>
                        {
                            let v = v.get();
                            let target = ((v >> 16) & 0xFFFF) as u16;
                            match slot_of_object(target).filter(|s| *s == 0) {
                                Some(_) => {
                                    let moved = shifted(target, slot, distance, pdo_increment)
                                        .unwrap_or(target);
                                    DefaultValue::int((v & 0xFFFF) | i64::from(moved) << 16)
                                }
                                None => DefaultValue::int(v),
                            }
                        }
                        d => d,
                    };
                    crate::with_default(e, default)
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
pub(super) fn modular_objects(
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
            limits: crate::leak_limits(Some(0), Some(i64::from(slots)), ""),
            ..sub0(slots).with_access(access)
        }];
        if access == Access::RwPreOp {
            l[0] = crate::with_default(&l[0], DefaultValue::int(0));
        }
        for k in 1..=slots {
            l.push(
                constant(k, leak(&format!("SubIndex {k:03}")), DataType::UInt32, 0)
                    .with_access(access),
            );
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
