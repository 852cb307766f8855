//! `od dump`: the live object dictionary through SDO Information, like
//! TwinCAT's CoE-Online tab (or JSON).

use crate::failure::Failure;
use crate::output::{outln, stop_requested};
use crate::target::{Session, Where};
use master_test::cli::{self, Value};
use master_test::od::EntryValue;
use master_test::sdo_info;
use serde::Serialize;

/// Options of `od`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(subcommand)]
    op: Op,
}

/// `od` subcommands.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Op {
    /// Every object of the OD list (all objects) with every subindex:
    /// name, type, access, unit and the current value.
    Dump {
        /// A JSON array of objects with their entries, including default,
        /// minimum and maximum (schema in docs/book/src/commissioning.md).
        #[arg(long)]
        json: bool,
    },
}

/// One entry of `od dump --json` (the schema docs/book/src/commissioning.md documents).
#[derive(Serialize)]
struct JsonEntry {
    sub: u8,
    address: String,
    name: String,
    #[serde(rename = "type")]
    type_name: String,
    type_code: u16,
    bit_len: u16,
    access: &'static str,
    unit: &'static str,
    default: Option<serde_json::Value>,
    min: Option<serde_json::Value>,
    max: Option<serde_json::Value>,
    value: Option<serde_json::Value>,
    #[serde(skip_serializing_if = "Option::is_none")]
    value_text: Option<&'static str>,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    padding: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
}

/// One object of `od dump --json`.
#[derive(Serialize)]
struct JsonObject {
    index: u16,
    name: String,
    object_code: u8,
    entries: Vec<JsonEntry>,
}

fn json_entry(d: &master_test::od::DumpEntry) -> JsonEntry {
    let e = &d.info;
    let opt = |v: &Option<Vec<u8>>| {
        v.as_deref()
            .map(|b| cli::decode(e.data_type, e.bit_len, b).to_json())
    };
    let mut j = JsonEntry {
        sub: e.sub,
        address: format!("0x{:04X}:{:02X}", e.index, e.sub),
        name: e.name.clone(),
        type_name: cli::type_name(e.data_type),
        type_code: e.data_type,
        bit_len: e.bit_len,
        access: cli::access_text(e.access),
        unit: cli::unit_text(e.unit),
        default: opt(&e.default),
        min: opt(&e.min),
        max: opt(&e.max),
        value: None,
        value_text: None,
        padding: false,
        error: None,
    };
    match &d.value {
        EntryValue::Value(v) => {
            j.value = Some(v.to_json());
            if let Value::Enum { text, .. } = v {
                j.value_text = *text;
            }
        }
        EntryValue::WriteOnly => {}
        EntryValue::Padding => j.padding = true,
        EntryValue::Error(s) => j.error = Some(s.clone()),
    }
    j
}

/// Runs an `od` command.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    let Op::Dump { json } = args.op;
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let mut c = s.client(&sel)?;
    let objects = sdo_info::od_list(&mut c, sdo_info::list_type::ALL).await?;
    let mut all = Vec::new();
    if !json {
        outln!(
            "{:<9}  {:<28} {:<11} {:<3} {:<4} Value",
            "Index",
            "Name",
            "Type",
            "Acc",
            "Unit"
        );
    }
    for index in objects {
        if stop_requested() {
            return Err(Failure::Interrupted("the dump is incomplete".into()));
        }
        let o = master_test::od::read_object(&mut c, index).await?;
        if json {
            all.push(JsonObject {
                index: o.info.index,
                name: o.info.name.clone(),
                object_code: o.info.object_code,
                entries: o.entries.iter().map(json_entry).collect(),
            });
            continue;
        }
        outln!(
            "{:04X}       {:<28} [{}]",
            o.info.index,
            o.info.name,
            cli::object_code_text(o.info.object_code)
        );
        for d in &o.entries {
            let e = &d.info;
            outln!(
                "  {:04X}:{:02X}  {:<28} {:<11} {:<3} {:<4} {}",
                e.index,
                e.sub,
                e.name,
                cli::type_name(e.data_type),
                cli::access_text(e.access),
                cli::unit_text(e.unit),
                d.value.text(e.bit_len)
            );
        }
    }
    if json {
        let text = serde_json::to_string_pretty(&all)
            .map_err(|e| Failure::Comm(format!("cannot encode JSON: {e}")))?;
        outln!("{text}");
    }
    Ok(())
}
