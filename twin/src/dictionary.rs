//! The object dictionary of an ESI device (`Profile/Dictionary`, ETG.2000)
//! as the core's [`Dictionary`], built at run time.
//!
//! Data types: every base type of ETG.1000.6 Table 64 by its ETG.2000 name
//! (`BOOL`, `SINT`..`LINT`, `INT24`..`INT56`, `USINT`..`ULINT`,
//! `UINT24`..`UINT56`, `REAL`, `LREAL`, `BYTE`/`WORD`/`DWORD`, `BIT1`..`BIT8`,
//! `BITARR8`..`BITARR32`, `STRING(n)`, `OCTET_STRING`, `UNICODE_STRING`,
//! `TIME_OF_DAY`, `TIME_DIFFERENCE`, `GUID`), `ARRAY [lo..hi] OF T` held as
//! one value (an array of `BYTE` is an `OCTET_STRING`), derived types (a
//! `DataType` with only a `BaseType`), enumerations (`EnumInfo`; one
//! without an `Index` is served as its base type), records (`SubItem`s
//! with `SubIdx`) and arrays (a `SubItem` of an `ArrayInfo` type).
//! What cannot be modelled (an object of an unknown type, more bits than
//! CoE's UNSIGNED16 bit length) is left out with a [`Warning`]. Objects: `Var` of a base
//! type or enumeration, records and arrays; `Info` gives defaults
//! (`DefaultData` little-endian hex, `DefaultValue`, `DefaultString`),
//! ranges (`MinData`/`MaxData`, `MinValue`/`MaxValue`) and units
//! (ETG.1004 codes the core knows); `Flags` give access (`ro`, `rw`, `wo`,
//! `WriteRestrictions="PreOP"`), PDO mapping, backup and setting. A
//! record's `SubItem` without `Flags` of a `BITn` type is a padding gap.
//!
//! Everything is leaked into `'static` data: a twin lives as long as its
//! line; [`crate::coe_twin::describe`] builds a dictionary once per
//! distinct device. Errors name the element and its line.

use std::collections::BTreeMap;

use ecat_slave::coe::sdo_info::unit_text;
use ecat_slave::od::build::sub_name;
use ecat_slave::od::dictionary::natural_bits;
use ecat_slave::od::{
    Access, DataType, DefaultValue, Dictionary, Entry, EntryFlags, EnumDesc, Object, ObjectCode,
    PdoMapping,
};

use crate::esi::{At, EsiError, Warning, array_bounds, array_element, base_type_code};
use crate::leak;
use crate::xml::{Element, hex_binary};

fn bad(e: &Element, what: &'static str, value: &str) -> EsiError {
    EsiError::BadValue {
        at: At::of(e),
        what,
        value: value.trim().chars().take(40).collect(),
    }
}

fn number(e: &Element, what: &'static str) -> Result<i64, EsiError> {
    crate::xml::number(&e.text).ok_or_else(|| bad(e, what, &e.text))
}

fn child_u(e: &Element, name: &str, what: &'static str) -> Result<Option<i64>, EsiError> {
    e.child(name).map(|c| number(c, what)).transpose()
}

/// The core's data type of a CoE base type code (`None` for a code that
/// is no base type).
pub(crate) fn data_type_of_code(code: u8) -> Option<DataType> {
    DataType::from_code(u16::from(code))
}

/// A scalar type the core can serve.
#[derive(Debug, Clone, Copy)]
struct Scalar {
    ty: DataType,
    bits: u16,
}

/// The scalar type named `name`, if it is a base type, `STRING(n)` or an
/// `ARRAY [lo..hi] OF` a base type (bit size 0: the entry's `BitSize`
/// says, as for `OCTET_STRING`).
fn base_scalar(name: &str) -> Option<Scalar> {
    let n = name.trim();
    if let Some(len) = n.strip_prefix("STRING(").and_then(|r| r.strip_suffix(')')) {
        let len: u16 = len.trim().parse().ok()?;
        return Some(Scalar {
            ty: DataType::VisibleString,
            bits: len.checked_mul(8)?,
        });
    }
    if let Some(element) = array_element(n) {
        let e = base_scalar(element)?;
        let bits = array_bounds(n)
            .and_then(|(lo, hi)| u16::try_from((hi - lo + 1).max(0)).ok())
            .and_then(|k| k.checked_mul(e.bits))
            .unwrap_or(0);
        return Some(array_scalar(e, bits));
    }
    let ty = data_type_of_code(base_type_code(n)?)?;
    Some(Scalar {
        ty,
        bits: natural_bits(&ty),
    })
}

/// An array of `element`s held as one value of `bits` bits.
fn array_scalar(element: Scalar, bits: u16) -> Scalar {
    let ty = if element.ty == DataType::Byte {
        DataType::OctetString
    } else {
        DataType::Array(element.ty.code())
    };
    Scalar { ty, bits }
}

/// `s` with the entry's `BitSize` `bits` where its type leaves the length
/// open (strings, octet strings, arrays).
fn sized(s: Scalar, bits: u16) -> Scalar {
    if s.ty.is_bytes() && bits != 0 {
        Scalar { bits, ..s }
    } else {
        s
    }
}

/// One item of a record or array data type.
#[derive(Debug, Clone)]
struct SubDef<'a> {
    sub: Option<u8>,
    name: String,
    type_name: String,
    bits: u16,
    flags: Option<&'a Element>,
    el: &'a Element,
}

#[derive(Debug, Clone)]
enum TypeDef<'a> {
    Scalar(Scalar),
    Record(Vec<SubDef<'a>>),
    ArrayOf { base: String, elements: u16 },
}

/// The data types of a dictionary by name.
struct Types<'a> {
    defs: BTreeMap<String, (TypeDef<'a>, &'a Element)>,
    enums: Vec<&'static EnumDesc>,
}

impl<'a> Types<'a> {
    fn parse(dts: Option<&'a Element>) -> Result<Self, EsiError> {
        let mut defs = BTreeMap::new();
        let mut enums = Vec::new();
        let Some(dts) = dts else {
            return Ok(Types { defs, enums });
        };
        for dt in dts.children_named("DataType") {
            let name_el = dt.child("Name").ok_or_else(|| EsiError::Missing {
                at: At::of(dt),
                what: "<Name>",
            })?;
            let name = name_el.text.trim().to_string();
            let bits = child_u(dt, "BitSize", "BitSize")?.unwrap_or(0);
            let named_index = enum_index_of_name(&name);
            let def = if dt.child("EnumInfo").is_some()
                && dt.child("Index").is_none()
                && named_index.is_none()
            {
                // An enumeration without a data type index: its values are
                // served as its base type of its size (what the ESI lets a
                // master know).
                let size = u16::try_from(bits).unwrap_or(0);
                let base = dt
                    .text_at("BaseType")
                    .and_then(|b| self_or_base(&defs, b))
                    .filter(|b| b.bits == size)
                    .unwrap_or_else(|| unsigned_of(size));
                TypeDef::Scalar(base)
            } else if dt.child("EnumInfo").is_some() {
                let mut values = Vec::new();
                for ei in dt.children_named("EnumInfo") {
                    let v = ei
                        .child("Enum")
                        .map(|e| number(e, "Enum"))
                        .transpose()?
                        .unwrap_or(0);
                    values.push((v, leak(ei.text_at("Text").unwrap_or(""))));
                }
                let index = child_u(dt, "Index", "Index")?
                    .or(named_index.map(i64::from))
                    .unwrap_or(0);
                let desc: &'static EnumDesc = Box::leak(Box::new(EnumDesc {
                    index: u16::try_from(index)
                        .map_err(|_| bad(dt, "Index", &index.to_string()))?,
                    name: leak(&name),
                    bit_len: u8::try_from(bits)
                        .map_err(|_| bad(dt, "BitSize", &bits.to_string()))?,
                    values: Box::leak(values.into_boxed_slice()),
                }));
                enums.push(desc);
                TypeDef::Scalar(Scalar {
                    ty: desc.data_type(),
                    bits: u16::from(desc.bit_len),
                })
            } else if let Some(ai) = dt.child("ArrayInfo") {
                let base = dt
                    .text_at("BaseType")
                    .ok_or_else(|| EsiError::Missing {
                        at: At::of(dt),
                        what: "<BaseType>",
                    })?
                    .to_string();
                let elements = child_u(ai, "Elements", "Elements")?.unwrap_or(0);
                TypeDef::ArrayOf {
                    base,
                    elements: u16::try_from(elements)
                        .map_err(|_| bad(ai, "Elements", &elements.to_string()))?,
                }
            } else if dt.child("SubItem").is_some() {
                let mut subs = Vec::new();
                for si in dt.children_named("SubItem") {
                    let sub = si
                        .child("SubIdx")
                        .map(|c| number(c, "SubIdx"))
                        .transpose()?
                        .map(|v| u8::try_from(v).map_err(|_| bad(si, "SubIdx", &v.to_string())))
                        .transpose()?;
                    let b = child_u(si, "BitSize", "BitSize")?.unwrap_or(0);
                    subs.push(SubDef {
                        sub,
                        name: si.text_at("Name").unwrap_or("").to_string(),
                        type_name: si.text_at("Type").unwrap_or("").to_string(),
                        bits: u16::try_from(b).map_err(|_| bad(si, "BitSize", &b.to_string()))?,
                        flags: si.child("Flags"),
                        el: si,
                    });
                }
                TypeDef::Record(subs)
            } else if let Some(s) = base_scalar(&name) {
                TypeDef::Scalar(sized(s, u16::try_from(bits).unwrap_or(0)))
            } else if let Some(base) = dt.text_at("BaseType").and_then(|b| self_or_base(&defs, b)) {
                // A derived type (`DT_Temperature` of `INT`).
                TypeDef::Scalar(sized(base, u16::try_from(bits).unwrap_or(0)))
            } else {
                // Unknown: only a warning when an object uses it.
                continue;
            };
            defs.insert(name, (def, dt));
        }
        Ok(Types { defs, enums })
    }

    fn scalar(&self, name: &str, el: &Element) -> Result<Scalar, EsiError> {
        match self.defs.get(name.trim()) {
            Some((TypeDef::Scalar(s), _)) => return Ok(*s),
            Some((TypeDef::ArrayOf { base, elements }, _)) => {
                // An array type as an item's type: the array as one value.
                let e = self.scalar(base, el)?;
                return Ok(array_scalar(e, elements.saturating_mul(e.bits)));
            }
            _ => {}
        }
        base_scalar(name).ok_or_else(|| EsiError::UnknownDataType {
            at: At::of(el),
            name: name.trim().to_string(),
        })
    }
}

/// `name` as a base type or one of the types `defs` already has.
fn self_or_base(defs: &BTreeMap<String, (TypeDef<'_>, &Element)>, name: &str) -> Option<Scalar> {
    match defs.get(name.trim()) {
        Some((TypeDef::Scalar(s), _)) => Some(*s),
        _ => base_scalar(name),
    }
}

/// The data type index a Beckhoff-style enumeration name carries
/// (`DT0800EN03`: index 0x0800, 3 bits), as its devices report it.
fn enum_index_of_name(name: &str) -> Option<u16> {
    let rest = name.trim().strip_prefix("DT")?;
    let (hex, bits) = rest.split_once("EN")?;
    if hex.len() != 4 || bits.is_empty() || !bits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    u16::from_str_radix(hex, 16)
        .ok()
        .filter(|i| (0x0800..=0x0FFF).contains(i))
}

/// The unsigned type of `bits` bits (an enumeration without an index).
fn unsigned_of(bits: u16) -> Scalar {
    let ty = match bits {
        1..=8 if bits < 8 => DataType::Bits(bits as u8),
        8 => DataType::UInt8,
        16 => DataType::UInt16,
        24 => DataType::UInt24,
        32 => DataType::UInt32,
        64 => DataType::UInt64,
        _ => DataType::UInt32,
    };
    Scalar {
        ty,
        bits: natural_bits(&ty),
    }
}

/// Access, PDO mapping, backup, setting from a `Flags` element.
fn flags(
    f: Option<&Element>,
    inherit: Access,
) -> Result<(Access, PdoMapping, bool, bool), EsiError> {
    let Some(f) = f else {
        return Ok((inherit, PdoMapping::None, false, false));
    };
    // ETG.2000 AccessType: ro, rw, wo (any case), WriteRestrictions
    // PreOP, SafeOP, OP and their pairs; the core knows "writable in
    // PRE-OP only" and "writable", so PreOP is the one kept.
    let access = match f.child("Access") {
        Some(a) => match (
            a.text.trim().to_ascii_lowercase().as_str(),
            a.attr("WriteRestrictions"),
        ) {
            ("ro", _) => Access::Ro,
            ("wo", _) => Access::Wo,
            ("rw", Some(r)) if r.trim().eq_ignore_ascii_case("PreOP") => Access::RwPreOp,
            ("rw", _) => Access::Rw,
            (other, _) => return Err(bad(a, "Access", other)),
        },
        None => inherit,
    };
    // ETG.2000 PdoMappingType: R, T, RT, TR, in either case.
    let pdo = match f.text_at("PdoMapping").map(str::trim) {
        None | Some("") => PdoMapping::None,
        Some(p) => {
            let rx = p.contains(['R', 'r']);
            let tx = p.contains(['T', 't']);
            if p.chars().any(|c| !matches!(c, 'R' | 'r' | 'T' | 't')) {
                return Err(bad(f.child("PdoMapping").unwrap_or(f), "PdoMapping", p));
            }
            match (rx, tx) {
                (true, true) => PdoMapping::RxTx,
                (true, false) => PdoMapping::Rx,
                _ => PdoMapping::Tx,
            }
        }
    };
    let on = |n: &str| matches!(f.text_at(n).map(str::trim), Some("1" | "true"));
    Ok((access, pdo, on("Backup"), on("Setting")))
}

/// Sign-extends the `bits`-bit little-endian `bytes`.
fn from_le(bytes: &[u8], ty: &DataType, bits: u16) -> i64 {
    let mut raw = [0u8; 8];
    for (d, s) in raw.iter_mut().zip(bytes) {
        *d = *s;
    }
    let u = u64::from_le_bytes(raw);
    let b = u32::from(bits).clamp(1, 64);
    if ty.is_signed() && b < 64 {
        let shift = 64 - b;
        ((u << shift) as i64) >> shift
    } else {
        u as i64
    }
}

/// Default, minimum, maximum and unit of an entry.
struct ValueInfo {
    default: DefaultValue,
    min: Option<i64>,
    max: Option<i64>,
    unit: &'static str,
}

const NO_VALUE_INFO: ValueInfo = ValueInfo {
    default: DefaultValue::int(0),
    min: None,
    max: None,
    unit: "",
};

/// Default, minimum, maximum and unit of an entry from an `Info`.
fn value_info(info: Option<&Element>, s: &Scalar) -> Result<ValueInfo, EsiError> {
    let Some(info) = info else {
        return Ok(NO_VALUE_INFO);
    };
    let data = |name: &str| -> Result<Option<i64>, EsiError> {
        match info.child(name) {
            Some(d) => {
                let b = hex_binary(&d.text).ok_or_else(|| bad(d, "hexBinary", &d.text))?;
                Ok(Some(from_le(&b, &s.ty, s.bits)))
            }
            None => Ok(None),
        }
    };
    let val = |name: &str| -> Result<Option<i64>, EsiError> {
        let Some(c) = info.child(name) else {
            return Ok(None);
        };
        if s.ty.is_real() {
            // A float as text ("1.5", "-3e2"): its bit pattern.
            let f: f64 = c
                .text
                .trim()
                .parse()
                .map_err(|_| bad(c, "value", &c.text))?;
            return Ok(Some(match s.ty {
                DataType::Real32 => i64::from((f as f32).to_bits()),
                _ => f.to_bits() as i64,
            }));
        }
        let v = number(c, "value")?;
        // A hex value of a signed type is its bit pattern in the type's
        // size (Teknic writes INT's -2 as #xFFFE): sign-extended, as
        // TwinCAT reads it. Decimal values are taken as written.
        // An enumeration with negative values has a signed base type
        // (Teknic's DT0802EN16 on INT).
        let signed = s.ty.is_signed();
        let hex = c
            .text
            .trim()
            .get(..2)
            .is_some_and(|p| p.eq_ignore_ascii_case("#x"));
        let bits = u32::from(s.bits).clamp(1, 64);
        if hex && signed && bits < 64 && (v as u64) >> bits == 0 {
            let shift = 64 - bits;
            return Ok(Some((v << shift) >> shift));
        }
        Ok(Some(v))
    };
    if s.ty.is_bytes() {
        let default = match s.ty {
            DataType::VisibleString => {
                // `DefaultString`, or the string's bytes as `DefaultData`
                // (Beckhoff's 0x1008 of STRING(n)).
                let from_data = match info.child("DefaultData") {
                    Some(d) => {
                        let b = hex_binary(&d.text).ok_or_else(|| bad(d, "hexBinary", &d.text))?;
                        let end = b.iter().position(|c| *c == 0).unwrap_or(b.len());
                        Some(String::from_utf8_lossy(b.get(..end).unwrap_or(&[])).into_owned())
                    }
                    None => None,
                };
                let text = info
                    .text_at("DefaultString")
                    .or(from_data.as_deref())
                    .unwrap_or("");
                // Cut to the string's length (at a character boundary).
                let max = usize::from(s.bits / 8);
                let mut end = text.len().min(max);
                while !text.is_char_boundary(end) {
                    end -= 1;
                }
                DefaultValue::Str(leak(text.get(..end).unwrap_or("")))
            }
            _ => match info.child("DefaultData") {
                Some(d) => {
                    let mut b = hex_binary(&d.text).ok_or_else(|| bad(d, "hexBinary", &d.text))?;
                    b.truncate(usize::from(s.bits).div_ceil(8));
                    DefaultValue::Bytes(Box::leak(b.into_boxed_slice()))
                }
                None => DefaultValue::Bytes(&[]),
            },
        };
        return Ok(ValueInfo {
            default,
            min: None,
            max: None,
            unit: "",
        });
    }
    let default = DefaultValue::int(data("DefaultData")?.or(val("DefaultValue")?).unwrap_or(0));
    let min = data("MinData")?.or(val("MinValue")?);
    let max = data("MaxData")?.or(val("MaxValue")?);
    let unit = match info.child("Unit") {
        Some(u) => {
            let code = number(u, "Unit")?;
            unit_text(u32::try_from(code).unwrap_or(0))
        }
        None => "",
    };
    Ok(ValueInfo {
        default,
        min,
        max,
        unit,
    })
}

struct EntrySpec {
    scalar: Scalar,
    sub: u8,
    name: String,
    access: Access,
    pdo: PdoMapping,
    backup: bool,
    setting: bool,
    gap: bool,
}

fn entry(spec: &EntrySpec, info: Option<&Element>) -> Result<Entry, EsiError> {
    let ValueInfo {
        default,
        min,
        max,
        unit,
    } = if spec.gap {
        NO_VALUE_INFO
    } else {
        value_info(info, &spec.scalar)?
    };
    // No Info: a string is empty, other bytes zeros.
    let default = match (default, spec.scalar.ty) {
        (DefaultValue::Int(_), DataType::VisibleString) => DefaultValue::Str(""),
        (DefaultValue::Int(_), t) if t.is_bytes() => DefaultValue::Bytes(&[]),
        (d, _) => d,
    };
    let entry = Entry {
        sub: spec.sub,
        name: leak(&spec.name),
        data_type: spec.scalar.ty,
        bit_len: spec.scalar.bits,
        default_bits: 0,
        limits: crate::leak_limits(min, max, unit),
        flags: EntryFlags::new(spec.access, spec.pdo)
            .with_backup(spec.backup)
            .with_setting(spec.setting)
            .with_gap(spec.gap),
    };
    Ok(crate::with_default(&entry, default))
}

/// The `Info` of every sub entry: matched by `Name` (the first unused of
/// that name), else by position among the named ones.
fn sub_infos<'a>(obj_info: Option<&'a Element>, names: &[String]) -> Vec<Option<&'a Element>> {
    let items: Vec<&Element> = obj_info
        .map(|i| i.children_named("SubItem").collect())
        .unwrap_or_default();
    let mut used = vec![false; items.len()];
    let mut out = Vec::with_capacity(names.len());
    for (k, n) in names.iter().enumerate() {
        let by_name = items.iter().enumerate().find(|(i, it)| {
            !used.get(*i).copied().unwrap_or(true) && it.text_at("Name") == Some(n)
        });
        // By position only where the Info names no entry there (an Info
        // that leaves entries out must not shift its defaults onto
        // others).
        let pick = match by_name {
            Some((i, it)) => Some((i, *it)),
            None => items
                .get(k)
                .filter(|it| !used.get(k).copied().unwrap_or(true) && it.child("Name").is_none())
                .map(|it| (k, *it)),
        };
        match pick {
            Some((i, it)) => {
                if let Some(u) = used.get_mut(i) {
                    *u = true;
                }
                out.push(it.child("Info"));
            }
            None => out.push(None),
        }
    }
    out
}

/// One parsed object: its index, name, code and entries.
#[derive(Debug)]
pub struct ParsedObject {
    /// The object.
    pub object: Object,
    /// Where it is.
    pub at: At,
}

/// Most bits an entry can have: SDO Information's bit length is
/// UNSIGNED16 (ETG.1000.6, Get Entry Description).
const MAX_ENTRY_BITS: i64 = u16::MAX as i64;

fn parse_object(
    o: &Element,
    types: &Types<'_>,
    warnings: &mut Vec<Warning>,
) -> Result<Option<ParsedObject>, EsiError> {
    let index_el = o.child("Index").ok_or_else(|| EsiError::Missing {
        at: At::of(o),
        what: "<Index>",
    })?;
    let index = u16::try_from(number(index_el, "Index")?)
        .map_err(|_| bad(index_el, "Index", &index_el.text))?;
    let name = o.text_at("Name").unwrap_or("").to_string();
    let type_el = o.child("Type").ok_or_else(|| EsiError::Missing {
        at: At::of(o),
        what: "<Type>",
    })?;
    let ty = type_el.text.trim();
    let (obj_access, obj_pdo, obj_backup, obj_setting) = flags(o.child("Flags"), Access::Ro)?;
    let info = o.child("Info");
    let obj_bits = o
        .text_at("BitSize")
        .and_then(crate::xml::number)
        .unwrap_or(0);
    if obj_bits > MAX_ENTRY_BITS
        && !types
            .defs
            .get(ty)
            .is_some_and(|(d, _)| matches!(d, TypeDef::Record(_)))
    {
        warnings.push(Warning::new(
            o,
            format!(
                "object {index:#06x} '{name}' of {obj_bits} bits is longer than a CoE entry can be described (UNSIGNED16 bit length): left out"
            ),
        ));
        return Ok(None);
    }
    let obj_bits = u16::try_from(obj_bits.max(0)).unwrap_or(0);
    let def = match types.defs.get(ty) {
        Some((d, _)) => Some(d.clone()),
        None => base_scalar(ty).map(TypeDef::Scalar),
    };
    let Some(def) = def else {
        warnings.push(Warning::new(
            type_el,
            format!("object {index:#06x} '{name}' has the unknown data type '{ty}': left out"),
        ));
        return Ok(None);
    };
    // A variable of an array type: the array as one value.
    let def = match def {
        TypeDef::ArrayOf { .. } => TypeDef::Scalar(sized(types.scalar(ty, type_el)?, obj_bits)),
        TypeDef::Scalar(s) => TypeDef::Scalar(sized(s, obj_bits)),
        d => d,
    };
    let (code, entries) = match def {
        TypeDef::Scalar(s) => {
            let spec = EntrySpec {
                scalar: s,
                sub: 0,
                name: name.clone(),
                access: obj_access,
                pdo: obj_pdo,
                backup: obj_backup,
                setting: obj_setting,
                gap: false,
            };
            (ObjectCode::Var, vec![entry(&spec, info)?])
        }
        TypeDef::ArrayOf { .. } => {
            return Err(bad(type_el, "object type (a bare array type)", ty));
        }
        TypeDef::Record(subs) => {
            // An array object: sub 0 and one item of an ArrayInfo type.
            let elements = subs
                .iter()
                .find_map(|s| match types.defs.get(s.type_name.trim()) {
                    Some((TypeDef::ArrayOf { base, elements }, _)) if s.sub.is_none() => {
                        Some((s, base.clone(), *elements))
                    }
                    _ => None,
                });
            let mut specs = Vec::new();
            let code = match elements {
                Some((item, base, n)) => {
                    if let Some(s0) = subs.iter().find(|s| s.sub == Some(0)) {
                        let sc = types.scalar(&s0.type_name, s0.el)?;
                        let (a, p, b, st) = flags(s0.flags, obj_access)?;
                        specs.push(EntrySpec {
                            scalar: sc,
                            sub: 0,
                            name: s0.name.clone(),
                            access: a,
                            pdo: p,
                            backup: b,
                            setting: st,
                            gap: false,
                        });
                    }
                    let sc = types.scalar(&base, item.el)?;
                    let (a, p, b, st) = flags(item.flags, obj_access)?;
                    for k in 1..=n {
                        let sub = u8::try_from(k)
                            .map_err(|_| bad(item.el, "Elements", &n.to_string()))?;
                        specs.push(EntrySpec {
                            scalar: sc,
                            sub,
                            name: String::new(),
                            access: a,
                            pdo: p,
                            backup: b,
                            setting: st,
                            gap: false,
                        });
                    }
                    ObjectCode::Array
                }
                None => {
                    for s in &subs {
                        let sub = s.sub.ok_or_else(|| EsiError::Missing {
                            at: At::of(s.el),
                            what: "<SubIdx>",
                        })?;
                        let mut sc = sized(types.scalar(&s.type_name, s.el)?, s.bits);
                        // A BOOL of a whole byte (ATI's F/T sensor): the
                        // core serves it so.
                        if matches!(sc.ty, DataType::Bool) && s.bits == 8 {
                            sc.bits = 8;
                        }
                        if s.bits != 0 && s.bits != sc.bits {
                            // A size its type cannot have (ATI's F/T
                            // sensor gives a DINT 1 bit, the next item's
                            // BitOffs 32 bits later): the type's size, as
                            // the offsets show it.
                            warnings.push(Warning::new(
                                s.el,
                                format!(
                                    "object {index:#06x}:{sub:02x}: BitSize {} is not the size of its type {} ({} bits): the type's size is used",
                                    s.bits, s.type_name, sc.bits
                                ),
                            ));
                        }
                        let gap =
                            s.flags.is_none() && matches!(sc.ty, DataType::Bits(_)) && sub != 0;
                        let (a, p, b, st) = flags(s.flags, obj_access)?;
                        specs.push(EntrySpec {
                            scalar: sc,
                            sub,
                            name: s.name.clone(),
                            access: if gap { Access::Ro } else { a },
                            pdo: if gap { PdoMapping::None } else { p },
                            backup: b,
                            setting: st,
                            gap,
                        });
                    }
                    ObjectCode::Record
                }
            };
            // Names of array elements come from the object's Info.
            let info_items: Vec<&Element> = info
                .map(|i| i.children_named("SubItem").collect())
                .unwrap_or_default();
            if code == ObjectCode::Array {
                for (k, spec) in specs.iter_mut().enumerate() {
                    if spec.name.is_empty() {
                        spec.name = info_items
                            .get(k)
                            .and_then(|i| i.text_at("Name"))
                            .map_or_else(|| sub_name(spec.sub).to_string(), str::to_string);
                    }
                }
            }
            let named: Vec<String> = specs
                .iter()
                .filter(|s| !s.gap)
                .map(|s| s.name.clone())
                .collect();
            let mut infos = sub_infos(info, &named).into_iter();
            let mut entries = Vec::with_capacity(specs.len());
            let highest = specs.iter().map(|s| s.sub).max().unwrap_or(0);
            for spec in &specs {
                let i = if spec.gap {
                    None
                } else {
                    infos.next().flatten()
                };
                let mut e = entry(spec, i)?;
                if e.sub == 0 {
                    // Subindex 0 holds the highest subindex (a PDO
                    // assignment or module list: at most that).
                    // (A writable subindex 0: the number of entries in
                    // use, as the core reads it.)
                    let list = matches!(index, 0x1C12 | 0x1C13 | 0xF030) || e.access().writable();
                    let want = i64::from(highest);
                    let ok = matches!(e.default_value().as_int(), Some(v) if v == want || (list && (0..=want).contains(&v)));
                    if !ok {
                        warnings.push(Warning::new(
                            o,
                            format!("object {index:#06x}: subindex 0 defaults to {:?}, its highest subindex is {highest}: {highest} assumed", e.default_value()),
                        ));
                        e = crate::with_default(&e, DefaultValue::int(want));
                    }
                }
                entries.push(e);
            }
            (code, entries)
        }
    };
    Ok(Some(ParsedObject {
        object: Object {
            index,
            name: leak(&name),
            code,
            entries: Box::leak(entries.into_boxed_slice()),
        },
        at: At::of(o),
    }))
}

/// What [`parse`] reads of a `Profile/Dictionary`.
pub type ParsedDictionary = (Vec<ParsedObject>, Vec<&'static EnumDesc>, Vec<Warning>);

/// The objects and enumerations of a `Profile/Dictionary` element, objects
/// ascending by index, and what was left out.
pub fn parse(dict: &Element) -> Result<ParsedDictionary, EsiError> {
    let types = Types::parse(dict.child("DataTypes"))?;
    let mut objects: Vec<ParsedObject> = Vec::new();
    let mut warnings = Vec::new();
    if let Some(objs) = dict.child("Objects") {
        for o in objs.children_named("Object") {
            let Some(p) = parse_object(o, &types, &mut warnings)? else {
                continue;
            };
            if let Some(first) = objects.iter().find(|x| x.object.index == p.object.index) {
                warnings.push(Warning::new(
                    o,
                    format!(
                        "object {:#06x} is described again (first at line {}): the first kept",
                        p.object.index, first.at.line
                    ),
                ));
                continue;
            }
            objects.push(p);
        }
    }
    objects.sort_by_key(|o| o.object.index);
    Ok((objects, types.enums, warnings))
}

/// A [`Dictionary`] over `objects` (ascending) and `enums`, leaked.
pub fn build(objects: Vec<Object>, enums: Vec<&'static EnumDesc>) -> &'static Dictionary {
    let mut bases = Vec::with_capacity(objects.len());
    let mut acc = 0usize;
    for o in &objects {
        bases.push(u16::try_from(acc).unwrap_or(u16::MAX));
        acc += o.entries.len();
    }
    let objects: &'static [Object] = Box::leak(objects.into_boxed_slice());
    let enums: &'static [&'static EnumDesc] = Box::leak(enums.into_boxed_slice());
    let bases: &'static [u16] = Box::leak(bases.into_boxed_slice());
    Box::leak(Box::new(Dictionary::new(objects, enums, bases)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xml;

    const DICT: &str = r##"<Dictionary>
  <DataTypes>
    <DataType><Name>USINT</Name><BitSize>8</BitSize></DataType>
    <DataType><Index>#x0800</Index><Name>DT0800EN02</Name><BitSize>2</BitSize>
      <EnumInfo><Text>off</Text><Enum>0</Enum></EnumInfo>
      <EnumInfo><Text>on</Text><Enum>1</Enum></EnumInfo></DataType>
    <DataType><Name>DT1018</Name><BitSize>80</BitSize>
      <SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
      <SubItem><SubIdx>1</SubIdx><Name>Vendor ID</Name><Type>UDINT</Type><BitSize>32</BitSize><BitOffs>16</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
      <SubItem><SubIdx>2</SubIdx><Name>Gap</Name><Type>BIT7</Type><BitSize>7</BitSize><BitOffs>48</BitOffs></SubItem>
      <SubItem><SubIdx>3</SubIdx><Name>Mode</Name><Type>DT0800EN02</Type><BitSize>2</BitSize><BitOffs>55</BitOffs><Flags><Access WriteRestrictions="PreOP">rw</Access><PdoMapping>R</PdoMapping></Flags></SubItem>
    </DataType>
    <DataType><Name>DT1C12ARR</Name><BaseType>UINT</BaseType><BitSize>32</BitSize><ArrayInfo><LBound>1</LBound><Elements>2</Elements></ArrayInfo></DataType>
    <DataType><Name>DT1C12</Name><BitSize>48</BitSize>
      <SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs><Flags><Access>rw</Access></Flags></SubItem>
      <SubItem><Name>Elements</Name><Type>DT1C12ARR</Type><BitSize>32</BitSize><BitOffs>16</BitOffs><Flags><Access>rw</Access></Flags></SubItem>
    </DataType>
  </DataTypes>
  <Objects>
    <Object><Index>#x1C12</Index><Name>RxPDO assign</Name><Type>DT1C12</Type><BitSize>48</BitSize>
      <Info><SubItem><Name>SubIndex 000</Name><Info><DefaultData>01</DefaultData></Info></SubItem>
        <SubItem><Name>SubIndex 001</Name><Info><DefaultData>0016</DefaultData></Info></SubItem></Info></Object>
    <Object><Index>#x1000</Index><Name>Device type</Name><Type>UDINT</Type><BitSize>32</BitSize>
      <Info><DefaultData>89130000</DefaultData></Info><Flags><Access>ro</Access></Flags></Object>
    <Object><Index>#x2000</Index><Name>Offset</Name><Type>INT</Type><BitSize>16</BitSize>
      <Info><MinData>18FC</MinData><MaxData>E803</MaxData><DefaultData>F6FF</DefaultData><Unit>#xFD030000</Unit></Info>
      <Flags><Access>rw</Access><PdoMapping>T</PdoMapping><Backup>1</Backup></Flags></Object>
    <Object><Index>#x1018</Index><Name>Identity</Name><Type>DT1018</Type><BitSize>80</BitSize>
      <Info><SubItem><Name>SubIndex 000</Name><Info><DefaultValue>3</DefaultValue></Info></SubItem>
        <SubItem><Name>Vendor ID</Name><Info><DefaultValue>#x00000ABC</DefaultValue></Info></SubItem>
        <SubItem><Name>Mode</Name><Info><DefaultValue>1</DefaultValue></Info></SubItem></Info></Object>
    <Object><Index>#x1008</Index><Name>Device name</Name><Type>STRING(6)</Type><BitSize>48</BitSize>
      <Info><DefaultString>Twin 1</DefaultString></Info><Flags><Access>ro</Access></Flags></Object>
  </Objects>
</Dictionary>"##;

    fn parsed(text: &str) -> Result<(Vec<ParsedObject>, Vec<&'static EnumDesc>), EsiError> {
        parse(&xml::parse(text).unwrap()).map(|(o, e, _)| (o, e))
    }

    #[test]
    fn objects_of_every_shape_get_types_defaults_ranges_units_and_access() {
        let (objs, enums) = parsed(DICT).unwrap();
        let idx: Vec<u16> = objs.iter().map(|o| o.object.index).collect();
        assert_eq!(idx, [0x1000, 0x1008, 0x1018, 0x1C12, 0x2000], "sorted");
        assert_eq!(enums.len(), 1);
        let o = |i: u16| &objs.iter().find(|o| o.object.index == i).unwrap().object;
        let dt = o(0x1000);
        assert_eq!(
            (dt.code, dt.entries[0].default_value()),
            (ObjectCode::Var, DefaultValue::int(0x1389))
        );
        let off = &o(0x2000).entries[0];
        assert_eq!(off.data_type, DataType::Int16);
        assert_eq!(
            (off.default_value(), off.min(), off.max()),
            (DefaultValue::int(-10), Some(-1000), Some(1000))
        );
        assert_eq!(
            (off.unit(), off.access(), off.pdo(), off.backup()),
            ("ms", Access::Rw, PdoMapping::Tx, true)
        );
        let id = o(0x1018);
        assert_eq!(id.code, ObjectCode::Record);
        assert_eq!(id.entries.len(), 4);
        assert_eq!(id.entries[1].default_value(), DefaultValue::int(0xABC));
        assert!(id.entries[2].gap(), "BIT7 without flags is a gap");
        let mode = &id.entries[3];
        assert_eq!(
            (mode.access(), mode.pdo(), mode.default_value()),
            (Access::RwPreOp, PdoMapping::Rx, DefaultValue::int(1))
        );
        assert!(matches!(mode.data_type, DataType::Enum(e)
            if enums.iter().find(|d| d.index == e.index()).and_then(|d| d.text(1)) == Some("on")));
        let a = o(0x1C12);
        assert_eq!(a.code, ObjectCode::Array);
        assert_eq!(a.entries.len(), 3, "sub 0 and two elements");
        assert_eq!(a.entries[1].default_value(), DefaultValue::int(0x1600));
        assert_eq!(a.entries[2].name, "SubIndex 002");
        assert_eq!(
            o(0x1008).entries[0].default_value(),
            DefaultValue::Str("Twin 1")
        );
        let dict = build(objs.into_iter().map(|p| p.object).collect(), enums);
        assert_eq!(dict.entry_count(), 1 + 1 + 4 + 3 + 1);
        assert_eq!(dict.find_entry(0x2000, 0).map(|(f, _)| f), Some(9));
    }

    #[test]
    fn dictionary_errors_name_the_element_and_line() {
        let line =
            |needle: &str, text: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
        // An object of an unknown type is left out with a warning.
        let t = DICT.replace("<Type>INT</Type>", "<Type>FLOAT7</Type>");
        let (objs, _, w) = parse(&xml::parse(&t).unwrap()).unwrap();
        assert!(objs.iter().all(|o| o.object.index != 0x2000));
        assert_eq!(
            w.iter().map(ToString::to_string).collect::<Vec<_>>(),
            [format!(
                "<Type> at line {}: object 0x2000 'Offset' has the unknown data type 'FLOAT7': left out",
                line("FLOAT7", &t)
            )]
        );
        let t = DICT.replace(
            "<Access>rw</Access><PdoMapping>T",
            "<Access>rx</Access><PdoMapping>T",
        );
        let e = parsed(&t).unwrap_err().to_string();
        assert_eq!(
            e,
            format!("<Access> at line {}: bad Access 'rx'", line(">rx<", &t))
        );
        let t = DICT.replace(
            "<DefaultData>F6FF</DefaultData>",
            "<DefaultData>F6F</DefaultData>",
        );
        assert!(
            parsed(&t)
                .unwrap_err()
                .to_string()
                .contains("bad hexBinary 'F6F'")
        );
        let t = DICT.replace(
            "<SubIdx>1</SubIdx><Name>Vendor ID</Name><Type>UDINT</Type><BitSize>32",
            "<SubIdx>1</SubIdx><Name>Vendor ID</Name><Type>UDINT</Type><BitSize>16",
        );
        let (objs, _, w) = parse(&xml::parse(&t).unwrap()).unwrap();
        let id = &objs
            .iter()
            .find(|o| o.object.index == 0x1018)
            .unwrap()
            .object;
        assert_eq!(id.entries[1].bit_len, 32, "the type's size");
        assert!(
            w.iter().any(|w| w
                .to_string()
                .contains("BitSize 16 is not the size of its type UDINT")),
            "{w:?}"
        );
        let t = DICT.replace(
            "<Name>DT0800EN02</Name><BitSize>2</BitSize>",
            "<Name>DT0800EN02</Name><BitSize>999</BitSize>",
        );
        assert!(
            parsed(&t)
                .unwrap_err()
                .to_string()
                .contains("bad BitSize '999'")
        );
    }

    /// Types of ETG.1000.6 Table 64 the loader once refused, as a
    /// synthetic dictionary (written for this test).
    const TYPES: &str = r##"<Dictionary><DataTypes>
    <DataType><Name>ARRAY [0..3] OF BYTE</Name><BaseType>BYTE</BaseType><BitSize>32</BitSize><ArrayInfo><LBound>0</LBound><Elements>4</Elements></ArrayInfo></DataType>
    <DataType><Name>DT_Temperature</Name><BaseType>INT</BaseType><BitSize>16</BitSize></DataType>
    <DataType><Name>DT0801EN03</Name><BaseType>USINT</BaseType><BitSize>3</BitSize><EnumInfo><Text>a</Text><Enum>0</Enum></EnumInfo></DataType>
    <DataType><Name>DT_Mode</Name><BaseType>UINT</BaseType><BitSize>16</BitSize><EnumInfo><Text>a</Text><Enum>1</Enum></EnumInfo></DataType>
    <DataType><Name>DT2000</Name><BitSize>112</BitSize>
      <SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
      <SubItem><SubIdx>1</SubIdx><Name>Key</Name><Type>ARRAY [0..3] OF BYTE</Type><BitSize>32</BitSize><BitOffs>16</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
      <SubItem><SubIdx>2</SubIdx><Name>Mode</Name><Type>DT0801EN03</Type><BitSize>3</BitSize><BitOffs>48</BitOffs><Flags><Access>rw</Access><PdoMapping>tr</PdoMapping></Flags></SubItem>
      <SubItem><SubIdx>4</SubIdx><Name>Filter</Name><Type>ARRAY [0..3] OF UINT</Type><BitSize>64</BitSize><BitOffs>51</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
    </DataType></DataTypes><Objects>
    <Object><Index>#x2000</Index><Name>Rec</Name><Type>DT2000</Type><BitSize>112</BitSize><Info><SubItem><Name>SubIndex 000</Name><Info><DefaultData>01</DefaultData></Info></SubItem><SubItem><Name>Key</Name><Info><DefaultData>0A0B</DefaultData></Info></SubItem></Info></Object>
    <Object><Index>#x2001</Index><Name>Gain</Name><Type>REAL</Type><BitSize>32</BitSize><Info><DefaultValue>-2.5</DefaultValue><MinValue>-10</MinValue><MaxValue>10</MaxValue></Info><Flags><Access>rw</Access><PdoMapping>r</PdoMapping></Flags></Object>
    <Object><Index>#x2002</Index><Name>Temp</Name><Type>DT_Temperature</Type><BitSize>16</BitSize><Info><DefaultData>F6FF</DefaultData></Info><Flags><Access>ro</Access><PdoMapping>T</PdoMapping></Flags></Object>
    <Object><Index>#x2003</Index><Name>Mode</Name><Type>DT_Mode</Type><BitSize>16</BitSize><Flags><Access>ro</Access></Flags></Object>
    <Object><Index>#x2004</Index><Name>Buffer</Name><Type>ARRAY [0..16383] OF UINT</Type><BitSize>262144</BitSize><Flags><Access>rw</Access></Flags></Object>
    <Object><Index>#x2005</Index><Name>Counts</Name><Type>UINT24</Type><BitSize>24</BitSize><Flags><Access>ro</Access></Flags></Object>
    <Object><Index>#x1008</Index><Name>Name</Name><Type>STRING(20)</Type><BitSize>160</BitSize><Info><DefaultString>short</DefaultString></Info><Flags><Access>ro</Access></Flags></Object>
    </Objects></Dictionary>"##;

    #[test]
    fn real_arrays_derived_types_enumerations_and_24_bit_integers_are_read() {
        let (objs, enums, w) = parse(&xml::parse(TYPES).unwrap()).unwrap();
        let o = |i: u16| &objs.iter().find(|o| o.object.index == i).unwrap().object;
        let rec = o(0x2000);
        assert_eq!(
            rec.entries[0].default_value(),
            DefaultValue::int(4),
            "subindex 0 = highest"
        );
        let key = &rec.entries[1];
        assert_eq!((key.data_type, key.bit_len), (DataType::OctetString, 32));
        assert_eq!(key.default_value(), DefaultValue::Bytes(&[0x0A, 0x0B]));
        let mode = &rec.entries[2];
        assert_eq!(mode.pdo(), PdoMapping::RxTx);
        assert!(
            matches!(mode.data_type, DataType::Enum(e) if e.index() == 0x0801 && e.bit_len() == 3)
        );
        assert_eq!(enums.len(), 1, "only the enumeration with an index");
        assert_eq!(rec.entries[3].data_type, DataType::Array(0x0006));
        let gain = &o(0x2001).entries[0];
        assert_eq!(gain.data_type, DataType::Real32);
        assert_eq!(
            gain.default_value(),
            DefaultValue::int(i64::from((-2.5f32).to_bits()))
        );
        assert_eq!(gain.min(), Some(i64::from((-10f32).to_bits())));
        assert_eq!(o(0x2002).entries[0].data_type, DataType::Int16);
        assert_eq!(o(0x2002).entries[0].default_value(), DefaultValue::int(-10));
        assert_eq!(
            o(0x2003).entries[0].data_type,
            DataType::UInt16,
            "enum without index"
        );
        assert_eq!(o(0x2005).entries[0].data_type, DataType::UInt24);
        let name = &o(0x1008).entries[0];
        assert_eq!(
            (name.bit_len, name.default_value()),
            (160, DefaultValue::Str("short"))
        );
        assert!(objs.iter().all(|o| o.object.index != 0x2004), "left out");
        assert!(
            w.iter()
                .any(|w| w.message.contains("0x2004") && w.message.contains("262144 bits")),
            "{w:?}"
        );
        let dict = build(objs.into_iter().map(|p| p.object).collect(), enums);
        assert_eq!(dict.validate(), Ok(()));
        assert_eq!(
            dict.value_slots(),
            dict.entry_count() + 1 + 1,
            "two 4- and 8-byte areas"
        );
    }

    #[test]
    fn malformed_dictionaries_are_errors_or_warnings_never_panics() {
        for cut in (0..TYPES.len()).step_by(97) {
            let Some(text) = TYPES.get(..cut) else {
                continue;
            };
            if let Ok(e) = xml::parse(text) {
                let _ = parse(&e);
            }
        }
        for (from, to) in [
            (
                "ARRAY [0..3] OF BYTE</Type>",
                "ARRAY [0..-9] OF BYTE</Type>",
            ),
            ("<BitSize>262144</BitSize>", "<BitSize>-5</BitSize>"),
            (
                "<DefaultValue>-2.5</DefaultValue>",
                "<DefaultValue>pi</DefaultValue>",
            ),
            ("STRING(20)", "STRING(99999)"),
            ("<PdoMapping>tr</PdoMapping>", "<PdoMapping>x</PdoMapping>"),
        ] {
            let t = TYPES.replace(from, to);
            let _ = parse(&xml::parse(&t).unwrap());
        }
    }

    #[test]
    fn a_string_default_given_as_data_is_its_text() {
        let text = r##"<Dictionary><DataTypes/><Objects>
    <Object><Index>#x1008</Index><Name>Device name</Name><Type>STRING(6)</Type><BitSize>48</BitSize>
    <Info><DefaultData>454c32303134</DefaultData></Info><Flags><Access>ro</Access></Flags></Object>
    <Object><Index>#x1009</Index><Name>Hardware version</Name><Type>STRING(2)</Type><BitSize>16</BitSize>
    <Info><DefaultData>3030</DefaultData><DefaultString>01</DefaultString></Info><Flags><Access>ro</Access></Flags></Object>
</Objects></Dictionary>"##;
        let (objs, _, _) = parse(&xml::parse(text).unwrap()).unwrap();
        let e = |i: u16| first_entry(&objs, i);
        assert_eq!(e(0x1008).default_value(), DefaultValue::Str("EL2014"));
        assert_eq!(
            e(0x1009).default_value(),
            DefaultValue::Str("01"),
            "DefaultString first"
        );
    }

    #[test]
    fn hex_values_of_a_signed_type_are_its_bit_pattern() {
        let text = r##"<Dictionary><DataTypes/><Objects>
    <Object><Index>#x605A</Index><Name>Quick stop option code</Name><Type>INT</Type><BitSize>16</BitSize>
    <Info><MinValue>#xFFFE</MinValue><MaxValue>#x0006</MaxValue><DefaultValue>#xFFFF</DefaultValue></Info>
    <Flags><Access>rw</Access></Flags></Object>
    <Object><Index>#x2000</Index><Name>Decimal</Name><Type>INT</Type><BitSize>16</BitSize>
    <Info><MinValue>-5</MinValue><MaxValue>65535</MaxValue><DefaultValue>3</DefaultValue></Info>
    <Flags><Access>rw</Access></Flags></Object>
    <Object><Index>#x2001</Index><Name>Unsigned</Name><Type>UINT</Type><BitSize>16</BitSize>
    <Info><MaxValue>#xFFFE</MaxValue></Info><Flags><Access>rw</Access></Flags></Object>
</Objects></Dictionary>"##;
        let (objs, _, _) = parse(&xml::parse(text).unwrap()).unwrap();
        let e = |i: u16| first_entry(&objs, i);
        let qs = e(0x605A);
        assert_eq!((qs.min(), qs.max()), (Some(-2), Some(6)));
        assert_eq!(qs.default_value(), DefaultValue::int(-1));
        assert_eq!(e(0x2000).min(), Some(-5), "decimal as written");
        assert_eq!(e(0x2001).max(), Some(0xFFFE), "unsigned hex unchanged");
    }

    /// Entry 0 of object `index` of a parsed dictionary.
    fn first_entry(objs: &[ParsedObject], index: u16) -> &Entry {
        &objs
            .iter()
            .find(|o| o.object.index == index)
            .unwrap()
            .object
            .entries[0]
    }

    #[test]
    fn a_64_bit_default_beyond_32_bits_survives_in_the_entrys_limits() {
        // An entry keeps its default in 32 bits; a wider one (a ULINT, a
        // LINT below i32::MIN, an LREAL) is kept whole beside its range.
        let text = r##"<Dictionary><DataTypes/><Objects>
    <Object><Index>#x2000</Index><Name>Big</Name><Type>ULINT</Type><BitSize>64</BitSize>
    <Info><MinValue>1</MinValue><MaxValue>#x100000000000</MaxValue><DefaultValue>#x123456789A</DefaultValue></Info>
    <Flags><Access>rw</Access></Flags></Object>
    <Object><Index>#x2001</Index><Name>Low</Name><Type>LINT</Type><BitSize>64</BitSize>
    <Info><DefaultValue>-5000000000</DefaultValue></Info><Flags><Access>rw</Access></Flags></Object>
    <Object><Index>#x2002</Index><Name>Small</Name><Type>LINT</Type><BitSize>64</BitSize>
    <Info><DefaultValue>-7</DefaultValue></Info><Flags><Access>rw</Access></Flags></Object>
</Objects></Dictionary>"##;
        let (objs, _, _) = parse(&xml::parse(text).unwrap()).unwrap();
        let e = |i: u16| first_entry(&objs, i);
        let big = e(0x2000);
        assert_eq!(big.default_value(), DefaultValue::int(0x12_3456_789A));
        assert_eq!((big.min(), big.max()), (Some(1), Some(0x1000_0000_0000)));
        assert_eq!(e(0x2001).default_value(), DefaultValue::int(-5_000_000_000));
        // One that fits is in the entry's bits, its limits the shared none.
        let small = e(0x2002);
        assert_eq!(small.default_value(), DefaultValue::int(-7));
        assert_eq!(
            (small.default_bits, small.limits.default),
            (-7i32 as u32, None)
        );
    }

    #[test]
    fn little_endian_data_is_sign_extended_by_type() {
        assert_eq!(from_le(&[0xF6, 0xFF], &DataType::Int16, 16), -10);
        assert_eq!(from_le(&[0xF6, 0xFF], &DataType::UInt16, 16), 0xFFF6);
        assert_eq!(from_le(&[0xFF; 9], &DataType::Int64, 64), -1);
        assert_eq!(from_le(&[], &DataType::UInt8, 8), 0);
    }
}
