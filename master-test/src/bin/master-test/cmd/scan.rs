//! `scan`: the slaves of the segment, one row each (or JSON).

use super::state::{al_status, state_name};
use crate::failure::Failure;
use crate::output::outln;
use crate::target::{Session, Where};
use ecat_slave::al::AlStatusCode;
use master_test::eeprom;
use serde::Serialize;

/// Options of `scan`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// JSON (schema in docs/book/src/commissioning.md) instead of a table.
    #[arg(long)]
    json: bool,
}

/// Mailbox protocol names of SII word 0x1C.
fn protocols(bits: u16) -> Vec<&'static str> {
    [
        (0x01, "AoE"),
        (0x02, "EoE"),
        (0x04, "CoE"),
        (0x08, "FoE"),
        (0x10, "SoE"),
        (0x20, "VoE"),
    ]
    .iter()
    .filter(|(b, _)| bits & b != 0)
    .map(|(_, n)| *n)
    .collect()
}

/// One row of `scan` (and its JSON schema).
#[derive(Serialize)]
struct ScanRow {
    position: usize,
    station: u16,
    alias: u16,
    name: String,
    vendor_id: u32,
    product_code: u32,
    revision: u32,
    serial: u32,
    state: &'static str,
    error: bool,
    al_status_code: u16,
    al_status_text: &'static str,
    mailbox: Vec<&'static str>,
}

/// Runs `scan`.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    let json = args.json;
    let s = Session::open(w).await?;
    let md = s.md();
    let mut rows = Vec::new();
    for (position, sd) in s.group.iter(md).enumerate() {
        let station = sd.configured_address();
        let (st, code) = al_status(md, station).await?;
        let header = eeprom::read_header(md, station).await?;
        let bits = ecat_slave::sii::SiiReader::new(&header)
            .map(|r| r.mailbox_protocols())
            .unwrap_or(0);
        let id = sd.identity();
        rows.push(ScanRow {
            position,
            station,
            alias: sd.alias_address(),
            name: sd.name().to_string(),
            vendor_id: id.vendor_id,
            product_code: id.product_id,
            revision: id.revision,
            serial: id.serial,
            state: state_name(st),
            error: st & 0x10 != 0,
            al_status_code: code,
            al_status_text: AlStatusCode::from_code(code).text(),
            mailbox: protocols(bits),
        });
    }
    if json {
        let text = serde_json::to_string_pretty(&rows)
            .map_err(|e| Failure::Comm(format!("cannot encode JSON: {e}")))?;
        outln!("{text}");
        return Ok(());
    }
    outln!("{} slave(s) on {}", rows.len(), s.bus.describe());
    outln!(
        "{:<3} {:<7} {:<6} {:<16} {:<10} {:<10} {:<10} {:<10} {:<8} Mailbox",
        "Pos",
        "Station",
        "Alias",
        "Name",
        "Vendor",
        "Product",
        "Revision",
        "Serial",
        "State"
    );
    for r in &rows {
        let state = if r.error {
            format!("{}+ERR", r.state)
        } else {
            r.state.to_string()
        };
        outln!(
            "{:<3} {:<#7x} {:<6} {:<16} {:<#10x} {:<#10x} {:<#10x} {:<#10x} {:<8} {}",
            r.position,
            r.station,
            r.alias,
            r.name,
            r.vendor_id,
            r.product_code,
            r.revision,
            r.serial,
            state,
            r.mailbox.join(",")
        );
        if r.al_status_code != 0 {
            outln!(
                "    AL status code {:#06x}: {}",
                r.al_status_code,
                r.al_status_text
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mailbox_protocols_are_named_from_sii_word_0x1c() {
        assert_eq!(protocols(0x0C), vec!["CoE", "FoE"]);
        assert_eq!(protocols(0x3F).len(), 6);
        assert!(protocols(0).is_empty());
    }
}
