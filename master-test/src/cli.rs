//! Helpers of the `sdo` and `od` subcommands: the `INDEX:SUB` parser, CoE
//! value parsing and formatting typed by a data-type code and bit length
//! (as SDO Information reports them), type, access and unit names, and
//! values as JSON (serde_json).
//!
//! Everything here is pure (no bus); the subcommands of the `master-test`
//! binary and [`crate::od`] do the talking.

use ecat_slave::od::types::EnumDesc;
use std::fmt;
use std::sync::RwLock;

/// The enumeration data types of the device the tool talks to (SDO
/// Information reports an enumeration only by its type index).
static ENUMS: RwLock<&'static [&'static EnumDesc]> = RwLock::new(pam_199_p_etc::od::ENUMS);

/// Uses the enumeration types of another device (from its dictionary) to
/// name enumeration values.
pub fn use_enums(enums: &'static [&'static EnumDesc]) {
    if let Ok(mut e) = ENUMS.write() {
        *e = enums;
    }
}

fn enums() -> &'static [&'static EnumDesc] {
    ENUMS.read().map_or(&[][..], |e| *e)
}

/// Parses an object address `INDEX:SUB`.
///
/// Index and subindex are both hexadecimal, with or without `0x`
/// (`0x800D:02`, `800d:2`, `0x8006:2A`, `8006:0x2a`): exactly what the
/// tools print (`0x8006:2A`), so a printed address pastes back. `8006:10`
/// is subindex 0x10 = 16.
pub fn parse_address(s: &str) -> Result<(u16, u8), String> {
    let s = s.trim();
    let Some((index, sub)) = s.split_once(':') else {
        return Err(format!(
            "bad address '{s}': expected INDEX:SUB, e.g. 0x800D:02"
        ));
    };
    let (index, sub) = (index.trim(), sub.trim());
    let digits = strip_hex_prefix(index).unwrap_or(index);
    if digits.is_empty() || digits.len() > 4 || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(format!(
            "bad address '{s}': index '{index}' is not a 16-bit hex number"
        ));
    }
    let index = u16::from_str_radix(digits, 16)
        .map_err(|e| format!("bad address '{s}': index '{index}': {e}"))?;
    let sub_digits = strip_hex_prefix(sub).unwrap_or(sub);
    let parsed = if !sub_digits.is_empty()
        && sub_digits.len() <= 2
        && sub_digits.chars().all(|c| c.is_ascii_hexdigit())
    {
        u8::from_str_radix(sub_digits, 16).ok()
    } else {
        None
    };
    let sub = parsed.ok_or_else(|| {
        format!("bad address '{s}': subindex '{sub}' is not a hex number 00..=FF (0x optional)")
    })?;
    Ok((index, sub))
}

fn strip_hex_prefix(s: &str) -> Option<&str> {
    s.strip_prefix("0x").or_else(|| s.strip_prefix("0X"))
}

/// Parses an integer: decimal or `0x` hex, with an optional sign.
pub fn parse_int(s: &str) -> Option<i128> {
    let s = s.trim();
    let (neg, body) = match s.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, s.strip_prefix('+').unwrap_or(s)),
    };
    let magnitude = match strip_hex_prefix(body) {
        Some(hex) if !hex.is_empty() && hex.chars().all(|c| c.is_ascii_hexdigit()) => {
            i128::from_str_radix(hex, 16).ok()?
        }
        Some(_) => return None,
        None if !body.is_empty() && body.chars().all(|c| c.is_ascii_digit()) => {
            body.parse::<i128>().ok()?
        }
        None => return None,
    };
    Some(if neg { -magnitude } else { magnitude })
}

/// How values of a data type are read and written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// BOOL.
    Bool,
    /// SINT, INT, DINT, LINT.
    Signed,
    /// USINT, UINT, UDINT, ULINT, BITn.
    Unsigned,
    /// A device enumeration (0x0800..).
    Enum(&'static EnumDesc),
    /// VISIBLE_STRING.
    Text,
    /// Anything else: shown as bytes, not writable as a value.
    Other,
}

/// The [`Kind`] of CoE data type `code`.
pub fn kind(code: u16) -> Kind {
    match code {
        0x0001 => Kind::Bool,
        0x0002..=0x0004 | 0x0015 => Kind::Signed,
        0x0005..=0x0007 | 0x001B | 0x0030..=0x0037 => Kind::Unsigned,
        0x0009 => Kind::Text,
        c => enums()
            .iter()
            .find(|e| e.index == c)
            .map_or(Kind::Other, |e| Kind::Enum(e)),
    }
}

/// The ETG type name of `code` (`BOOL`, `UINT`, `BIT7`, `STRING`,
/// `DT0801EN03`, ...), or the code in hex for types this tool does not know.
pub fn type_name(code: u16) -> String {
    if let Some(t) = ecat_slave::od::types::base_type(code) {
        return t.name.to_string();
    }
    let name = match code {
        0x0021 => "PDO_MAPPING",
        0x0023 => "IDENTITY",
        0x002A => "RECORD",
        0x0000 => "NULL",
        c => match kind(c) {
            Kind::Enum(e) => e.name,
            _ => return format!("{c:#06x}"),
        },
    };
    name.to_string()
}

/// `RO`, `RW` or `WO` from the SDO Information access bits (read bits
/// 0x07, write bits 0x38); `--` for neither.
pub fn access_text(bits: u16) -> &'static str {
    match (bits & 0x07 != 0, bits & 0x38 != 0) {
        (true, true) => "RW",
        (true, false) => "RO",
        (false, true) => "WO",
        (false, false) => "--",
    }
}

/// Unit text of an ETG.1004 unit code (`ms`, `mA`, `Hz`), else "".
pub fn unit_text(code: Option<u32>) -> &'static str {
    match code {
        Some(0xFD03_0000) => "ms",
        Some(0xFD04_0000) => "mA",
        Some(0x0020_0000) => "Hz",
        _ => "",
    }
}

/// Object code name (VAR, ARRAY, RECORD).
pub fn object_code_text(code: u8) -> String {
    match code {
        7 => "VAR".into(),
        8 => "ARRAY".into(),
        9 => "RECORD".into(),
        c => format!("object code {c}"),
    }
}

/// A value decoded according to its data type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Value {
    /// BOOL.
    Bool(bool),
    /// A signed integer.
    Int(i64),
    /// An unsigned integer or bit field.
    UInt(u64),
    /// An enumeration value and its text, if defined.
    Enum {
        /// The value.
        value: i64,
        /// Its text.
        text: Option<&'static str>,
    },
    /// A visible string (trailing NULs removed).
    Text(String),
    /// Bytes that do not fit the type (or an unknown type).
    Bytes(Vec<u8>),
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Bool(b) => write!(f, "{b}"),
            Value::Int(v) => write!(f, "{v}"),
            Value::UInt(v) => write!(f, "{v}"),
            Value::Enum {
                value,
                text: Some(t),
            } => write!(f, "{t} ({value})"),
            Value::Enum { value, text: None } => write!(f, "{value} (undefined)"),
            Value::Text(s) => write!(f, "{s}"),
            Value::Bytes(b) => f.write_str(&hex(b)),
        }
    }
}

impl Value {
    /// The value as JSON: numbers, `true`/`false`, strings; an
    /// enumeration is its number, bytes a string of hex pairs.
    pub fn to_json(&self) -> serde_json::Value {
        match self {
            Value::Bool(b) => serde_json::Value::Bool(*b),
            Value::Int(v) => (*v).into(),
            Value::UInt(v) => (*v).into(),
            Value::Enum { value, .. } => (*value).into(),
            Value::Text(s) => s.as_str().into(),
            Value::Bytes(b) => hex(b).into(),
        }
    }
}

/// Bytes as space-separated hex pairs (`e8 03`); `(empty)` for none.
pub fn hex(bytes: &[u8]) -> String {
    if bytes.is_empty() {
        return "(empty)".into();
    }
    bytes
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Size in bytes of a value of `bit_len` bits.
pub fn byte_size(bit_len: u16) -> usize {
    usize::from(bit_len).div_ceil(8)
}

/// Decodes `bytes` (little-endian, as uploaded) as a value of type `code`
/// with `bit_len` bits. Integers must come in exactly the type's byte
/// size, else the bytes are returned as [`Value::Bytes`].
pub fn decode(code: u16, bit_len: u16, bytes: &[u8]) -> Value {
    let k = kind(code);
    if k == Kind::Text {
        let end = bytes.iter().rposition(|&b| b != 0).map_or(0, |p| p + 1);
        return Value::Text(String::from_utf8_lossy(&bytes[..end]).into_owned());
    }
    let size = byte_size(bit_len);
    if k == Kind::Other || bytes.len() != size || size == 0 || size > 8 {
        return Value::Bytes(bytes.to_vec());
    }
    let mut le = [0u8; 8];
    le[..size].copy_from_slice(bytes);
    let raw = u64::from_le_bytes(le);
    match k {
        Kind::Bool => Value::Bool(raw & 1 != 0),
        Kind::Signed => {
            let bits = u32::from(bit_len).clamp(1, 64);
            let shift = 64 - bits;
            Value::Int(((raw << shift) as i64) >> shift)
        }
        Kind::Unsigned => Value::UInt(raw),
        Kind::Enum(e) => {
            let value = raw as i64;
            Value::Enum {
                value,
                text: e.text(value),
            }
        }
        Kind::Text | Kind::Other => Value::Bytes(bytes.to_vec()),
    }
}

/// Decodes and formats in one go (see [`decode`]).
pub fn format_value(code: u16, bit_len: u16, bytes: &[u8]) -> String {
    decode(code, bit_len, bytes).to_string()
}

/// The value as the `sdo` and `od dump` tables show it: [`Value`]'s text,
/// with the hex form added for unsigned values of 32 bits and more (PDO
/// mappings, identity): `1879048449 (0x70000101)`.
pub fn show(value: &Value, bit_len: u16) -> String {
    match value {
        Value::UInt(v) if bit_len >= 32 => {
            format!("{v} (0x{v:0w$X})", w = usize::from(bit_len / 4))
        }
        v => v.to_string(),
    }
}

/// Parses `text` as a value of type `code` with `bit_len` bits and encodes
/// it little-endian in the entry's byte size.
///
/// Integers are decimal or `0x` hex, negative only for signed types, and
/// must fit `bit_len` bits; BOOL takes `true`/`false`/`1`/`0`;
/// enumerations take a value text (case-insensitive; texts win over
/// numbers, which matters for the PWM table whose texts are numbers) or a
/// number; strings are sent as their bytes, at most `bit_len / 8` long.
pub fn parse_value(code: u16, bit_len: u16, text: &str) -> Result<Vec<u8>, String> {
    let size = byte_size(bit_len);
    let tname = type_name(code);
    let t = text.trim();
    let bits = u32::from(bit_len).clamp(1, 64);
    let unsigned = |v: Option<i128>| -> Result<u64, String> {
        let v = v.ok_or_else(|| format!("'{t}' is not a number (decimal, or hex with 0x)"))?;
        let max = (1i128 << bits) - 1;
        if !(0..=max).contains(&v) {
            return Err(format!("{v} is out of range for {tname} (0..={max})"));
        }
        Ok(v as u64)
    };
    let encode = |raw: u64| raw.to_le_bytes()[..size.clamp(1, 8)].to_vec();
    match kind(code) {
        Kind::Bool => match t.to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(vec![1]),
            "false" | "0" => Ok(vec![0]),
            _ => Err(format!("'{t}' is not a BOOL (true, false, 1 or 0)")),
        },
        Kind::Signed => {
            let v = parse_int(t)
                .ok_or_else(|| format!("'{t}' is not a number (decimal, or hex with 0x)"))?;
            let (min, max) = (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1);
            if !(min..=max).contains(&v) {
                return Err(format!("{v} is out of range for {tname} ({min}..={max})"));
            }
            Ok(encode(v as i64 as u64))
        }
        Kind::Unsigned => Ok(encode(unsigned(parse_int(t))?)),
        Kind::Enum(e) => {
            if let Some((v, _)) = e.values.iter().find(|(_, s)| s.eq_ignore_ascii_case(t)) {
                return Ok(encode(*v as u64));
            }
            let choices = e
                .values
                .iter()
                .map(|(v, s)| format!("{s}={v}"))
                .collect::<Vec<_>>()
                .join(", ");
            match parse_int(t) {
                Some(v) => Ok(encode(unsigned(Some(v))?)),
                None => Err(format!(
                    "'{t}' is not a value of {tname} ({choices}, or a number)"
                )),
            }
        }
        Kind::Text => {
            if t.len() > size {
                Err(format!(
                    "'{t}' is longer than the {size} characters of this STRING"
                ))
            } else {
                Ok(t.as_bytes().to_vec())
            }
        }
        Kind::Other => Err(format!(
            "cannot write values of data type {tname} (use complete access tools)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_parse_with_and_without_prefixes() {
        assert_eq!(parse_address("0x800D:02"), Ok((0x800D, 2)));
        assert_eq!(parse_address("800D:2"), Ok((0x800D, 2)));
        assert_eq!(parse_address("800d:0x2A"), Ok((0x800D, 0x2A)));
        assert_eq!(parse_address("0X1018:0X04"), Ok((0x1018, 4)));
        assert_eq!(parse_address(" 1000:0 "), Ok((0x1000, 0)));
        assert_eq!(parse_address("0x8006:FF"), Ok((0x8006, 255)));
        // What the tools print pastes back: subindices are hex.
        assert_eq!(parse_address("0x8006:2A"), Ok((0x8006, 0x2A)));
        assert_eq!(parse_address("8006:10"), Ok((0x8006, 0x10)));
        assert_eq!(parse_address("0x800d:63"), Ok((0x800D, 0x63)));
    }

    #[test]
    fn malformed_addresses_name_the_problem() {
        for (input, needle) in [
            ("0x800D", "expected INDEX:SUB"),
            ("", "expected INDEX:SUB"),
            (":2", "index ''"),
            ("0x:2", "index '0x'"),
            ("800G:2", "index '800G'"),
            ("0x12345:1", "index '0x12345'"),
            ("-1:1", "index '-1'"),
            ("800D:", "subindex ''"),
            ("800D:256", "subindex '256'"),
            ("800D:0x100", "subindex '0x100'"),
            ("800D:2G", "subindex '2G'"),
            ("800D:-1", "subindex '-1'"),
            ("800D:0x", "subindex '0x'"),
            ("800D:1:2", "subindex '1:2'"),
        ] {
            let e = parse_address(input).expect_err(input);
            assert!(e.contains(needle), "{input}: {e}");
        }
    }

    #[test]
    fn integers_parse_in_decimal_and_hex() {
        assert_eq!(parse_int("42"), Some(42));
        assert_eq!(parse_int("-42"), Some(-42));
        assert_eq!(parse_int("+7"), Some(7));
        assert_eq!(parse_int("0x1F"), Some(31));
        assert_eq!(parse_int("-0x10"), Some(-16));
        for bad in ["", "-", "0x", "1.5", "12a", "0xZZ", "--1", " 1 2"] {
            assert_eq!(parse_int(bad), None, "{bad}");
        }
    }

    #[test]
    fn values_are_encoded_in_the_entry_size() {
        assert_eq!(parse_value(6, 16, "2000"), Ok(vec![0xD0, 0x07]));
        assert_eq!(parse_value(6, 16, "0xFFFF"), Ok(vec![0xFF, 0xFF]));
        assert_eq!(parse_value(3, 16, "-1"), Ok(vec![0xFF, 0xFF]));
        assert_eq!(parse_value(3, 16, "-32768"), Ok(vec![0x00, 0x80]));
        assert_eq!(
            parse_value(4, 32, "-10000"),
            Ok((-10000i32).to_le_bytes().to_vec())
        );
        assert_eq!(parse_value(2, 8, "-128"), Ok(vec![0x80]));
        assert_eq!(parse_value(5, 8, "255"), Ok(vec![0xFF]));
        assert_eq!(parse_value(7, 32, "0x70000320"), Ok(vec![0x20, 3, 0, 0x70]));
        assert_eq!(
            parse_value(0x1B, 64, "18446744073709551615"),
            Ok(vec![0xFF; 8])
        );
        assert_eq!(
            parse_value(0x15, 64, "-9223372036854775808"),
            Ok(i64::MIN.to_le_bytes().to_vec())
        );
        assert_eq!(parse_value(0x36, 7, "127"), Ok(vec![0x7F]));
        assert_eq!(parse_value(1, 1, "true"), Ok(vec![1]));
        assert_eq!(parse_value(1, 1, "FALSE"), Ok(vec![0]));
        assert_eq!(parse_value(1, 1, "1"), Ok(vec![1]));
        assert_eq!(parse_value(9, 8 * 13, "PAM"), Ok(b"PAM".to_vec()));
    }

    #[test]
    fn enumerations_parse_by_text_or_number() {
        // DT0801EN03: OFF=1, ON=2, AUTO=3.
        assert_eq!(parse_value(0x0801, 3, "ON"), Ok(vec![2]));
        assert_eq!(parse_value(0x0801, 3, "auto"), Ok(vec![3]));
        assert_eq!(parse_value(0x0801, 3, "1"), Ok(vec![1]));
        assert_eq!(parse_value(0x0801, 3, "0x3"), Ok(vec![3]));
        // DT0803EN05 texts are numbers: the text wins, else the number.
        assert_eq!(parse_value(0x0803, 5, "60"), Ok(vec![0x11]));
        assert_eq!(parse_value(0x0803, 5, "17"), Ok(vec![17]));
        let e = parse_value(0x0801, 3, "MAYBE").unwrap_err();
        assert!(e.contains("DT0801EN03") && e.contains("ON=2"), "{e}");
        let e = parse_value(0x0801, 3, "8").unwrap_err();
        assert!(e.contains("out of range for DT0801EN03 (0..=7)"), "{e}");
    }

    #[test]
    fn malformed_values_name_the_problem() {
        for (code, bits, input, needle) in [
            (6, 16, "abc", "'abc' is not a number"),
            (6, 16, "", "'' is not a number"),
            (6, 16, "1.5", "'1.5' is not a number"),
            (6, 16, "-1", "-1 is out of range for UINT (0..=65535)"),
            (6, 16, "65536", "65536 is out of range for UINT"),
            (
                3,
                16,
                "32768",
                "32768 is out of range for INT (-32768..=32767)",
            ),
            (3, 16, "-32769", "out of range for INT"),
            (2, 8, "0x80", "128 is out of range for SINT"),
            (0x36, 7, "128", "out of range for BIT7 (0..=127)"),
            (1, 1, "yes", "'yes' is not a BOOL"),
            (1, 1, "2", "'2' is not a BOOL"),
            (9, 16, "abc", "longer than the 2 characters"),
            (0x23, 32, "1", "cannot write values of data type IDENTITY"),
        ] {
            let e = parse_value(code, bits, input).expect_err(input);
            assert!(e.contains(needle), "{code:#x} {input}: {e}");
        }
    }

    #[test]
    fn values_are_formatted_by_type() {
        assert_eq!(format_value(6, 16, &[0xE8, 0x03]), "1000");
        assert_eq!(format_value(3, 16, &[0xF0, 0xD8]), "-10000");
        assert_eq!(format_value(4, 32, &[0xFF; 4]), "-1");
        assert_eq!(format_value(7, 32, &[0xFF; 4]), "4294967295");
        assert_eq!(format_value(2, 8, &[0x80]), "-128");
        assert_eq!(format_value(0x15, 64, &[0xFF; 8]), "-1");
        assert_eq!(format_value(0x1B, 64, &[0xFF; 8]), "18446744073709551615");
        assert_eq!(format_value(0x36, 7, &[0x7F]), "127");
        assert_eq!(format_value(1, 1, &[1]), "true");
        assert_eq!(format_value(1, 1, &[0]), "false");
        assert_eq!(format_value(0x0802, 3, &[1]), "ON (1)");
        assert_eq!(format_value(0x0801, 3, &[2]), "ON (2)");
        assert_eq!(format_value(0x0801, 3, &[6]), "6 (undefined)");
        assert_eq!(format_value(0x0803, 5, &[0x11]), "60 (17)");
        assert_eq!(format_value(9, 104, b"PAM-199-P-ETC"), "PAM-199-P-ETC");
        assert_eq!(format_value(9, 32, b"10\0\0"), "10");
        // Sizes that do not match the type, and unknown types: hex bytes.
        assert_eq!(format_value(6, 16, &[1, 2, 3]), "01 02 03");
        assert_eq!(format_value(6, 16, &[]), "(empty)");
        assert_eq!(format_value(0x2A, 16, &[0xAB, 0xCD]), "ab cd");
        // The table form adds hex to wide unsigned values only.
        let show_of = |code, bits, b: &[u8]| show(&decode(code, bits, b), bits);
        assert_eq!(
            show_of(7, 32, &0x7000_0101u32.to_le_bytes()),
            "1879048449 (0x70000101)"
        );
        assert_eq!(
            show_of(0x1B, 64, &[1, 0, 0, 0, 0, 0, 0, 0]),
            "1 (0x0000000000000001)"
        );
        assert_eq!(show_of(6, 16, &[0xE8, 0x03]), "1000");
        assert_eq!(show_of(4, 32, &[0xFF; 4]), "-1");
    }

    #[test]
    fn parse_and_format_round_trip() {
        for (code, bits, text) in [
            (6, 16, "2000"),
            (3, 16, "-5"),
            (4, 32, "-2147483648"),
            (7, 32, "4294967295"),
            (1, 1, "true"),
            (0x0801, 3, "AUTO (3)"),
        ] {
            let input = text.split(' ').next().unwrap_or(text);
            let bytes = parse_value(code, bits, input).unwrap();
            assert_eq!(format_value(code, bits, &bytes), text);
        }
    }

    #[test]
    fn names_and_json() {
        assert_eq!(type_name(7), "UDINT");
        assert_eq!(type_name(0x36), "BIT7");
        assert_eq!(type_name(0x30), "BIT1");
        assert_eq!(type_name(9), "STRING");
        assert_eq!(type_name(0x0801), "DT0801EN03");
        assert_eq!(type_name(0x1234), "0x1234");
        assert_eq!(access_text(0x0007), "RO");
        assert_eq!(access_text(0x033F), "RW");
        assert_eq!(access_text(0x000F), "RW");
        assert_eq!(access_text(0x0038), "WO");
        assert_eq!(unit_text(Some(0xFD04_0000)), "mA");
        assert_eq!(unit_text(Some(0)), "");
        assert_eq!(unit_text(None), "");
        assert_eq!(decode(0x0802, 3, &[1]).to_json().to_string(), "1");
        assert_eq!(decode(9, 16, b"ab").to_json().to_string(), "\"ab\"");
        assert_eq!(decode(1, 1, &[1]).to_json().to_string(), "true");
        assert_eq!(decode(6, 16, &[1]).to_json().to_string(), "\"01\"");
        assert_eq!(decode(3, 16, &[0xFF, 0xFF]).to_json().to_string(), "-1");
    }
}
