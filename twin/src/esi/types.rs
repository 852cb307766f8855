//! ETG.2000 type names (`UINT`, `STRING(8)`, `ARRAY [0..3] OF BYTE`) and
//! what a device's `Profile/Dictionary` declares: its data types and the
//! bit size of its objects' entries.

use std::collections::BTreeMap;

use crate::xml::{self, Element};

/// The CoE code of a base data type name of ETG.2000 (`BOOL`, `UINT`,
/// `BIT3`, `STRING(8)`, `BITARR16`, `ARRAY [0..3] OF BYTE`...), `None` for a
/// name it does not know. An array held as one value reports its element's
/// code, an array of `BYTE` `OCTET_STRING` (what the SSC's ESI writes for an
/// octet string, docs/MANUAL-NOTES.md).
pub fn base_type_code(name: &str) -> Option<u8> {
    if let Some(element) = array_element(name) {
        return match element {
            "BYTE" => Some(0x0A),
            e => base_type_code(e),
        };
    }
    let t = ecat_slave::od::types::base_type_named(name)?;
    u8::try_from(t.code).ok()
}

/// The element type of an ETG.2000 array type name `ARRAY [lo..hi] OF T`
/// (blanks as written), `None` for any other name.
pub fn array_element(name: &str) -> Option<&str> {
    let rest = name.trim().strip_prefix("ARRAY")?.trim_start();
    let rest = rest.strip_prefix('[')?;
    let (_, element) = rest.split_once(']')?;
    Some(element.trim_start().strip_prefix("OF")?.trim())
}

/// The bounds of an ETG.2000 array type name `ARRAY [lo..hi] OF T`.
pub fn array_bounds(name: &str) -> Option<(i64, i64)> {
    let rest = name.trim().strip_prefix("ARRAY")?.trim_start();
    let (bounds, _) = rest.strip_prefix('[')?.split_once(']')?;
    let (lo, hi) = bounds.split_once("..")?;
    Some((lo.trim().parse().ok()?, hi.trim().parse().ok()?))
}

/// Device-specific data types of a dictionary: name → base type code.
pub(super) fn dictionary_types(dict: &Element) -> BTreeMap<String, u8> {
    let mut types = BTreeMap::new();
    let Some(dts) = dict.child("DataTypes") else {
        return types;
    };
    // A named type resolves to its BaseType, or to itself when it is an
    // array/record/enum (the code of the PDO entry is then the base of
    // its elements, which the SII does not need exactly).
    for dt in dts.children_named("DataType") {
        let Some(name) = dt.text_at("Name") else {
            continue;
        };
        let base = dt
            .text_at("BaseType")
            .and_then(base_type_code)
            .map(|c| {
                if dt.child("ArrayInfo").is_some() && c == 0x1E {
                    0x0A
                } else {
                    c
                }
            })
            .or_else(|| base_type_code(name));
        match base {
            Some(code) => {
                types.insert(name.to_string(), code);
            }
            None if dt.child("EnumInfo").is_some() || dt.child("SubItem").is_some() => {
                // Enumerations and records: known, an unsigned of their size.
                types.insert(name.to_string(), 0x07);
            }
            None => {}
        }
    }
    types
}

/// `(index, sub)` → bit length of every object of a dictionary (what it
/// cannot read it leaves out: the dictionary itself is read, with its
/// errors and warnings, when a twin is built).
pub(super) fn dictionary_objects(dict: &Element) -> BTreeMap<(u16, u8), u16> {
    let mut out = BTreeMap::new();
    let Some(objs) = dict.child("Objects") else {
        return out;
    };
    let n = |e: &Element, name: &str| -> Option<i64> { e.text_at(name).and_then(xml::number) };
    // Bit sizes of the named record/array types, per subindex.
    let mut type_subs: BTreeMap<&str, Vec<(u8, u16)>> = BTreeMap::new();
    if let Some(dts) = dict.child("DataTypes") {
        for dt in dts.children_named("DataType") {
            let Some(name) = dt.text_at("Name") else {
                continue;
            };
            let subs = dt
                .children_named("SubItem")
                .map(|si| {
                    let sub = n(si, "SubIdx")
                        .and_then(|v| u8::try_from(v).ok())
                        .unwrap_or(0);
                    let bits = n(si, "BitSize")
                        .and_then(|v| u16::try_from(v).ok())
                        .unwrap_or(0);
                    (sub, bits)
                })
                .collect();
            type_subs.insert(name.trim(), subs);
        }
    }
    for o in objs.children_named("Object") {
        let Some(index) = n(o, "Index").and_then(|v| u16::try_from(v).ok()) else {
            continue;
        };
        let bits = n(o, "BitSize")
            .and_then(|v| u16::try_from(v).ok())
            .unwrap_or(0);
        let ty = o.text_at("Type").unwrap_or("").trim();
        match type_subs.get(ty).filter(|s| !s.is_empty()) {
            Some(subs) => {
                for (sub, b) in subs {
                    out.insert((index, *sub), *b);
                }
                // Array types list one element; the object's Info says
                // how many subindices exist.
                if let Some(info) = o.child("Info") {
                    for si in info.children_named("SubItem") {
                        if let Some(name) = si.text_at("Name")
                            && let Some(s) = name
                                .strip_prefix("SubIndex ")
                                .and_then(|s| s.trim().parse::<u8>().ok())
                        {
                            let b = subs.last().map_or(0, |l| l.1);
                            out.entry((index, s)).or_insert(b);
                        }
                    }
                }
            }
            None => {
                out.insert((index, 0), bits);
            }
        }
    }
    out
}
