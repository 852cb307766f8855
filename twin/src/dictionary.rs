//! The object dictionary of an ESI device (`Profile/Dictionary`, ETG.2000)
//! as the core's [`Dictionary`], built at run time.
//!
//! Data types: the base types the core serves (`BOOL`, `SINT`..`LINT`,
//! `USINT`..`ULINT`, `BYTE`/`WORD`/`DWORD`, `BIT1`..`BIT8`, `STRING(n)`),
//! enumerations (`EnumInfo`), records (`SubItem`s with `SubIdx`) and
//! arrays (a `SubItem` of an `ArrayInfo` type). Objects: `Var` of a base
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
    Access, DataType, DefaultValue, Dictionary, Entry, EnumDesc, Object, ObjectCode, PdoMapping,
};

use crate::esi::{At, EsiError, base_type_code};
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

/// The core's data type of a CoE base type code (`None` for types the
/// core does not serve: REAL, UINT24, ...).
pub(crate) fn data_type_of_code(code: u8) -> Option<DataType> {
    // Strings are served from their own entries, not as a scalar.
    DataType::from_code(u16::from(code)).filter(|t| *t != DataType::VisibleString)
}

/// A scalar type the core can serve.
#[derive(Debug, Clone, Copy)]
struct Scalar {
    ty: DataType,
    bits: u16,
}

/// The scalar type named `name`, if it is a base type the core serves.
fn base_scalar(name: &str) -> Option<Scalar> {
    let n = name.trim();
    if let Some(len) = n.strip_prefix("STRING(").and_then(|r| r.strip_suffix(')')) {
        let len: u16 = len.trim().parse().ok()?;
        return Some(Scalar {
            ty: DataType::VisibleString,
            bits: len.checked_mul(8)?,
        });
    }
    let ty = data_type_of_code(base_type_code(n)?)?;
    Some(Scalar {
        ty,
        bits: natural_bits(&ty),
    })
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
            let def = if dt.child("EnumInfo").is_some() {
                let mut values = Vec::new();
                for ei in dt.children_named("EnumInfo") {
                    let v = ei
                        .child("Enum")
                        .map(|e| number(e, "Enum"))
                        .transpose()?
                        .unwrap_or(0);
                    values.push((v, leak(ei.text_at("Text").unwrap_or(""))));
                }
                let index = child_u(dt, "Index", "Index")?.unwrap_or(0);
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
                    ty: DataType::Enum(desc),
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
            } else {
                match base_scalar(&name) {
                    Some(s) => TypeDef::Scalar(s),
                    // A base type the core does not serve: only an error
                    // when an object uses it.
                    None => continue,
                }
            };
            defs.insert(name, (def, dt));
        }
        Ok(Types { defs, enums })
    }

    fn scalar(&self, name: &str, el: &Element) -> Result<Scalar, EsiError> {
        if let Some(s) = base_scalar(name) {
            return Ok(s);
        }
        match self.defs.get(name.trim()) {
            Some((TypeDef::Scalar(s), _)) => Ok(*s),
            _ => Err(EsiError::UnknownDataType {
                at: At::of(el),
                name: name.trim().to_string(),
            }),
        }
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
    let access = match f.child("Access") {
        Some(a) => match (a.text.trim(), a.attr("WriteRestrictions")) {
            ("ro", _) => Access::Ro,
            ("wo", _) => Access::Wo,
            ("rw", Some(r)) if r.eq_ignore_ascii_case("PreOP") => Access::RwPreOp,
            ("rw", _) => Access::Rw,
            (other, _) => return Err(bad(a, "Access", other)),
        },
        None => inherit,
    };
    let pdo = match f.text_at("PdoMapping").map(str::trim) {
        None | Some("") => PdoMapping::None,
        Some(p) if p.contains('R') => PdoMapping::Rx,
        Some(p) if p.contains('T') => PdoMapping::Tx,
        Some(p) => {
            return Err(bad(f.child("PdoMapping").unwrap_or(f), "PdoMapping", p));
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
    default: DefaultValue::Int(0),
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
        info.child(name).map(|c| number(c, "value")).transpose()
    };
    let default = if s.ty == DataType::VisibleString {
        DefaultValue::Str(leak(info.text_at("DefaultString").unwrap_or("")))
    } else {
        DefaultValue::Int(data("DefaultData")?.or(val("DefaultValue")?).unwrap_or(0))
    };
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
    Ok(Entry {
        sub: spec.sub,
        name: leak(&spec.name),
        data_type: spec.scalar.ty,
        bit_len: spec.scalar.bits,
        access: spec.access,
        pdo: spec.pdo,
        default,
        min,
        max,
        unit,
        backup: spec.backup,
        setting: spec.setting,
        gap: spec.gap,
    })
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
        let pick = match by_name {
            Some((i, it)) => Some((i, *it)),
            None => items
                .get(k)
                .filter(|_| !used.get(k).copied().unwrap_or(true))
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

fn parse_object(o: &Element, types: &Types<'_>) -> Result<ParsedObject, EsiError> {
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
    let def = match base_scalar(ty) {
        Some(s) => Some(TypeDef::Scalar(s)),
        None => types.defs.get(ty).map(|(d, _)| d.clone()),
    };
    let Some(def) = def else {
        return Err(EsiError::UnknownDataType {
            at: At::of(type_el),
            name: ty.to_string(),
        });
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
                        let sc = types.scalar(&s.type_name, s.el)?;
                        if s.bits != 0 && s.bits != sc.bits {
                            return Err(bad(
                                s.el,
                                "BitSize (not the type's size)",
                                &s.bits.to_string(),
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
            for spec in &specs {
                let i = if spec.gap {
                    None
                } else {
                    infos.next().flatten()
                };
                entries.push(entry(spec, i)?);
            }
            (code, entries)
        }
    };
    Ok(ParsedObject {
        object: Object {
            index,
            name: leak(&name),
            code,
            entries: Box::leak(entries.into_boxed_slice()),
        },
        at: At::of(o),
    })
}

/// The objects and enumerations of a `Profile/Dictionary` element, objects
/// ascending by index.
pub fn parse(dict: &Element) -> Result<(Vec<ParsedObject>, Vec<&'static EnumDesc>), EsiError> {
    let types = Types::parse(dict.child("DataTypes"))?;
    let mut objects = Vec::new();
    if let Some(objs) = dict.child("Objects") {
        for o in objs.children_named("Object") {
            objects.push(parse_object(o, &types)?);
        }
    }
    objects.sort_by_key(|o| o.object.index);
    Ok((objects, types.enums))
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
        parse(&xml::parse(text).unwrap())
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
            (dt.code, dt.entries[0].default),
            (ObjectCode::Var, DefaultValue::Int(0x1389))
        );
        let off = &o(0x2000).entries[0];
        assert_eq!(off.data_type, DataType::Int16);
        assert_eq!(
            (off.default, off.min, off.max),
            (DefaultValue::Int(-10), Some(-1000), Some(1000))
        );
        assert_eq!(
            (off.unit, off.access, off.pdo, off.backup),
            ("ms", Access::Rw, PdoMapping::Tx, true)
        );
        let id = o(0x1018);
        assert_eq!(id.code, ObjectCode::Record);
        assert_eq!(id.entries.len(), 4);
        assert_eq!(id.entries[1].default, DefaultValue::Int(0xABC));
        assert!(id.entries[2].gap, "BIT7 without flags is a gap");
        let mode = &id.entries[3];
        assert_eq!(
            (mode.access, mode.pdo, mode.default),
            (Access::RwPreOp, PdoMapping::Rx, DefaultValue::Int(1))
        );
        assert!(matches!(mode.data_type, DataType::Enum(e) if e.text(1) == Some("on")));
        let a = o(0x1C12);
        assert_eq!(a.code, ObjectCode::Array);
        assert_eq!(a.entries.len(), 3, "sub 0 and two elements");
        assert_eq!(a.entries[1].default, DefaultValue::Int(0x1600));
        assert_eq!(a.entries[2].name, "SubIndex 002");
        assert_eq!(o(0x1008).entries[0].default, DefaultValue::Str("Twin 1"));
        let dict = build(objs.into_iter().map(|p| p.object).collect(), enums);
        assert_eq!(dict.entry_count(), 1 + 1 + 4 + 3 + 1);
        assert_eq!(dict.find_entry(0x2000, 0).map(|(f, _)| f), Some(9));
    }

    #[test]
    fn dictionary_errors_name_the_element_and_line() {
        let line =
            |needle: &str, text: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
        let t = DICT.replace("<Type>INT</Type>", "<Type>REAL</Type>");
        let e = parsed(&t).unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "<Type> at line {}: unknown data type 'REAL'",
                line("REAL", &t)
            )
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
        assert!(
            parsed(&t)
                .unwrap_err()
                .to_string()
                .contains("bad BitSize (not the type's size) '16'")
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

    #[test]
    fn little_endian_data_is_sign_extended_by_type() {
        assert_eq!(from_le(&[0xF6, 0xFF], &DataType::Int16, 16), -10);
        assert_eq!(from_le(&[0xF6, 0xFF], &DataType::UInt16, 16), 0xFFF6);
        assert_eq!(from_le(&[0xFF; 9], &DataType::Int64, 64), -1);
        assert_eq!(from_le(&[], &DataType::UInt8, 8), 0);
    }
}
