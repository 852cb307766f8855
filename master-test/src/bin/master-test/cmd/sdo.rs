//! `sdo read/write`: one object entry over CoE SDO, typed by the slave's
//! own SDO Information (or `--type`).

use crate::failure::{Failure, input};
use crate::output::outln;
use crate::target::{Session, Where};
use master_test::cli::{self, Value};
use master_test::mailbox::{ClientError, MailboxClient};
use master_test::sdo_info::{self, EntryInfo, value_info};

/// Options of `sdo`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(subcommand)]
    op: Op,
}

/// `sdo` subcommands.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Op {
    /// Upload INDEX:SUB and print its value with name, unit and type.
    ///
    /// Integers print in decimal (signed where the type is), enumerations
    /// as `TEXT (value)`, BOOL as true/false, strings as text.
    Read {
        /// Object address INDEX:SUB, both hexadecimal with or without 0x,
        /// as the tools print them: 0x800D:02, 800d:2, 0x8006:2A.
        address: String,
        /// Print the uploaded bytes in hex instead of the typed value.
        #[arg(long, conflicts_with = "json")]
        raw: bool,
        /// JSON: {"address", "name", "type", "bit_len", "access", "unit",
        /// "value", "value_text"}.
        #[arg(long)]
        json: bool,
        /// The data type, for slaves without SDO Information (UINT, DINT,
        /// BOOL, STRING, ...).
        #[arg(long = "type", value_name = "TYPE")]
        data_type: Option<String>,
    },
    /// Parse VALUE for the entry's type, check it against the range SDO
    /// Information gives, download it, read it back.
    ///
    /// Integers in decimal or 0x-hex (negative for signed types),
    /// enumerations by text or number, BOOL as true/false/1/0, strings as
    /// text. The value is encoded in the entry's byte size and downloaded
    /// expedited (up to 4 bytes) or normal. A value outside the entry's
    /// minimum..maximum is refused before anything is sent (exit 2).
    Write {
        /// Object address, as for `sdo read`.
        address: String,
        /// The value to write.
        #[arg(allow_hyphen_values = true)]
        value: String,
        /// Send the value even if it is outside the range SDO Information
        /// gives (let the device judge it).
        #[arg(long)]
        no_check: bool,
        /// The data type, for slaves without SDO Information (as for `sdo
        /// read`).
        #[arg(long = "type", value_name = "TYPE")]
        data_type: Option<String>,
    },
}

/// Data types `--type` takes: the integer and boolean base types (code,
/// bits) of the one table, `ecat_slave::od::types::BASE_TYPES`.
fn integer_types() -> impl Iterator<Item = &'static ecat_slave::od::types::BaseType> {
    use ecat_slave::od::types::{BASE_TYPES, BaseKind};
    BASE_TYPES.iter().filter(|t| {
        matches!(
            t.kind,
            BaseKind::Bool | BaseKind::Signed | BaseKind::Unsigned
        ) && t.bits <= 64
    })
}

/// An entry description made from `--type` (`STRING` takes the length
/// the slave gives).
fn typed_entry(index: u16, sub: u8, t: &str, string_len: usize) -> Result<EntryInfo, Failure> {
    let upper = t.to_ascii_uppercase();
    let (code, bits) = if upper == "STRING" {
        (0x0009, u16::try_from(string_len * 8).unwrap_or(u16::MAX))
    } else {
        let ty = integer_types().find(|ty| ty.name == upper).ok_or_else(|| {
            let names: Vec<&str> = integer_types().map(|ty| ty.name).collect();
            input(format!(
                "--type {t}: unknown data type (one of {}, STRING)",
                names.join(", ")
            ))
        })?;
        (ty.code, ty.bits)
    };
    Ok(EntryInfo {
        index,
        sub,
        data_type: code,
        bit_len: bits,
        access: 0x3F,
        unit: None,
        default: None,
        min: None,
        max: None,
        name: "(no SDO Information)".into(),
    })
}

/// The entry's description from SDO Information, or from `--type`.
async fn describe_entry(
    c: &mut MailboxClient<'_>,
    index: u16,
    sub: u8,
    data_type: Option<&str>,
    string_len: usize,
) -> Result<EntryInfo, Failure> {
    if let Some(t) = data_type {
        return typed_entry(index, sub, t, string_len);
    }
    match sdo_info::entry_description(c, index, sub, value_info::ALL).await {
        Ok(e) => Ok(e),
        Err(e @ ClientError::Abort { .. }) => Err(e.into()),
        Err(e) => Err(Failure::from(e).context(format!(
            "no SDO Information for 0x{index:04X}:{sub:02X} (give the data type with --type)"
        ))),
    }
}

/// `0x800D:02 CURRENT = 1000 mA  (UINT, RW)`.
/// Without `unit` (raw bytes) the unit is left out.
fn describe(e: &EntryInfo, value: &str, unit: bool) -> String {
    let unit = if unit { cli::unit_text(e.unit) } else { "" };
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    format!(
        "0x{:04X}:{:02X} {} = {value}{unit}  ({}, {})",
        e.index,
        e.sub,
        e.name,
        cli::type_name(e.data_type),
        cli::access_text(e.access)
    )
}

/// Runs an `sdo` command.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    let op = args.op;
    let address = match &op {
        Op::Read { address, .. } | Op::Write { address, .. } => address.clone(),
    };
    let (index, sub) = cli::parse_address(&address).map_err(input)?;
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let mut c = s.client(&sel)?;
    match op {
        Op::Read {
            raw,
            json,
            data_type,
            ..
        } => {
            let bytes = c.sdo_upload(index, sub, false).await?;
            let e = describe_entry(&mut c, index, sub, data_type.as_deref(), bytes.len()).await?;
            let value = cli::decode(e.data_type, e.bit_len, &bytes);
            if json {
                let text = match &value {
                    Value::Enum { text, .. } => text.map(str::to_string),
                    _ => None,
                };
                let j = serde_json::json!({
                    "address": format!("0x{index:04X}:{sub:02X}"),
                    "name": e.name,
                    "type": cli::type_name(e.data_type),
                    "bit_len": e.bit_len,
                    "access": cli::access_text(e.access),
                    "unit": cli::unit_text(e.unit),
                    "value": value.to_json(),
                    "value_text": text,
                });
                outln!("{j}");
            } else {
                let shown = if raw {
                    cli::hex(&bytes)
                } else {
                    cli::show(&value, e.bit_len)
                };
                outln!("{}", describe(&e, &shown, !raw));
            }
            Ok(())
        }
        Op::Write {
            value,
            no_check,
            data_type,
            ..
        } => {
            let e = describe_entry(&mut c, index, sub, data_type.as_deref(), value.len()).await?;
            let bytes = cli::parse_value(e.data_type, e.bit_len, &value).map_err(|m| {
                input(format!(
                    "bad value for 0x{index:04X}:{sub:02X} {} ({}): {m}",
                    e.name,
                    cli::type_name(e.data_type)
                ))
            })?;
            if !no_check {
                check_range(&e, &bytes)?;
            }
            let how = if bytes.len() <= 4 {
                "expedited"
            } else {
                "normal"
            };
            outln!(
                "0x{index:04X}:{sub:02X} {} := {} ({}, {how} download)",
                e.name,
                cli::format_value(e.data_type, e.bit_len, &bytes),
                cli::hex(&bytes)
            );
            c.sdo_download(index, sub, false, &bytes).await?;
            match c.sdo_upload(index, sub, false).await {
                Ok(back) => {
                    let shown = cli::show(&cli::decode(e.data_type, e.bit_len, &back), e.bit_len);
                    outln!("{}", describe(&e, &shown, true));
                }
                // Write-only entries (commands) cannot be read back.
                Err(ClientError::Abort { code, .. }) if u32::from(code) == 0x0601_0001 => {
                    outln!("0x{index:04X}:{sub:02X} {} written (write-only)", e.name);
                }
                Err(err) => return Err(err.into()),
            }
            Ok(())
        }
    }
}

/// A number of an integer-like value, for range checks.
fn number(v: &Value) -> Option<i128> {
    match v {
        Value::Int(i) => Some(i128::from(*i)),
        Value::UInt(u) => Some(i128::from(*u)),
        Value::Enum { value, .. } => Some(i128::from(*value)),
        Value::Bool(b) => Some(i128::from(*b)),
        _ => None,
    }
}

/// Refuses `bytes` outside the minimum..maximum SDO Information gives.
fn check_range(e: &EntryInfo, bytes: &[u8]) -> Result<(), Failure> {
    let decode = |b: &Option<Vec<u8>>| {
        b.as_deref()
            .and_then(|b| number(&cli::decode(e.data_type, e.bit_len, b)))
    };
    let (Some(v), min, max) = (
        number(&cli::decode(e.data_type, e.bit_len, bytes)),
        decode(&e.min),
        decode(&e.max),
    ) else {
        return Ok(());
    };
    let below = min.is_some_and(|m| v < m);
    let above = max.is_some_and(|m| v > m);
    if below || above {
        let unit = match cli::unit_text(e.unit) {
            "" => String::new(),
            u => format!(" {u}"),
        };
        let bound = |b: Option<i128>| b.map_or_else(String::new, |b| b.to_string());
        return Err(input(format!(
            "{v}{unit} is outside the range of 0x{:04X}:{:02X} {}: {}..={}{unit} \
             (SDO Information); nothing was sent (--no-check sends it anyway)",
            e.index,
            e.sub,
            e.name,
            bound(min),
            bound(max)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn current() -> EntryInfo {
        EntryInfo {
            index: 0x800D,
            sub: 2,
            data_type: 6,
            bit_len: 16,
            access: 0x3F,
            unit: Some(0xFD04_0000),
            default: Some(1000u16.to_le_bytes().to_vec()),
            min: Some(500u16.to_le_bytes().to_vec()),
            max: Some(3000u16.to_le_bytes().to_vec()),
            name: "CURRENT".into(),
        }
    }

    #[test]
    fn values_outside_the_sdo_information_range_are_refused_with_it() {
        let e = current();
        assert!(check_range(&e, &1000u16.to_le_bytes()).is_ok());
        assert!(check_range(&e, &500u16.to_le_bytes()).is_ok());
        assert!(check_range(&e, &3000u16.to_le_bytes()).is_ok());
        let Err(Failure::Input(m)) = check_range(&e, &5000u16.to_le_bytes()) else {
            panic!("5000 accepted");
        };
        assert!(m.contains("5000 mA is outside"), "{m}");
        assert!(m.contains("500..=3000 mA"), "{m}");
        assert!(check_range(&e, &499u16.to_le_bytes()).is_err());
        // No range given: anything goes.
        let free = EntryInfo {
            min: None,
            max: None,
            ..current()
        };
        assert!(check_range(&free, &5000u16.to_le_bytes()).is_ok());
    }

    #[test]
    fn types_by_name_for_slaves_without_sdo_information() {
        let e = typed_entry(0x6000, 1, "dint", 4).unwrap();
        assert_eq!((e.data_type, e.bit_len), (4, 32));
        let s = typed_entry(0x1008, 0, "STRING", 13).unwrap();
        assert_eq!((s.data_type, s.bit_len), (9, 104));
        let Err(Failure::Input(m)) = typed_entry(0x1000, 0, "FLOAT", 4) else {
            panic!("FLOAT accepted");
        };
        assert!(m.contains("unknown data type"), "{m}");
    }
}
