//! `esi check`: the live slave's SII against its ESI.

use crate::failure::{Failure, input};
use crate::output::outln;
use crate::target::{Session, Where};
use master_test::eeprom;
use std::path::PathBuf;

/// Options of `esi`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(subcommand)]
    op: Op,
}

/// `esi` subcommands.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Op {
    /// Compare the live slave's SII (read over the EEPROM interface) with
    /// an ESI: identity, name, mailbox, SyncManagers, FMMUs, PDOs, DC.
    /// Exit 1 on mismatches.
    Check {
        /// The ESI XML file; default: the ESI generated for the catalog
        /// device with the slave's identity.
        #[arg(long)]
        esi: Option<PathBuf>,
    },
}

/// Runs an `esi` command.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    let Op::Check { esi } = args.op;
    let given = match &esi {
        Some(p) => Some(
            String::from_utf8(
                std::fs::read(p).map_err(|e| input(format!("cannot read {}: {e}", p.display())))?,
            )
            .map_err(|_| input(format!("{}: not an ESI XML file (not UTF-8)", p.display())))?,
        ),
        None => None,
    };
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let (xml, source) = match (given, &esi, sel.device) {
        (Some(x), Some(p), _) => (x, p.display().to_string()),
        (None, _, Some(d)) => {
            let x = ecat_esi::esi::generate(d.description)
                .map_err(|e| input(format!("cannot generate the ESI: {e}")))?;
            let x = String::from_utf8(x).map_err(|_| input("generated ESI is not UTF-8"))?;
            (
                x,
                format!("the generated ESI of {}", d.description.names.type_name),
            )
        }
        _ => {
            return Err(input(format!(
                "{} is not a catalog device (vendor {:#x} product {:#x}): give its ESI \
                 with --esi FILE",
                sel.label(),
                sel.identity.vendor_id,
                sel.identity.product_id
            )));
        }
    };
    let image = eeprom::read_all(s.md(), sel.station).await?;
    let mismatches = ecat_esi::check::check(&xml, &image)
        .map_err(|e| input(format!("cannot check {source}: {e}")))?;
    if mismatches.is_empty() {
        outln!(
            "{} ({} bytes of SII) agrees with {source}",
            sel.label(),
            image.len()
        );
        return Ok(());
    }
    for m in &mismatches {
        outln!("{m}");
    }
    Err(Failure::Mismatch(format!(
        "{} mismatch(es) between {} and {source}",
        mismatches.len(),
        sel.label()
    )))
}
