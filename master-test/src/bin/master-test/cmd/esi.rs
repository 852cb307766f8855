//! `esi check`: the live slave's SII against its ESI; `esi corpus`: every
//! device of a folder of ESI files as a twin on the virtual bus.

use crate::failure::{Failure, input};
use crate::output::outln;
use crate::target::{Session, Where};
use master_test::eeprom;
use std::path::{Path, PathBuf};

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
    /// Every device of every ESI file of a folder as a twin on the virtual
    /// bus: loads, builds SII and dictionary, brings it to OP with
    /// ethercrab, compares its SII and its SDO Information with the ESI.
    /// Prints a table (file, type, revision, result, reason) and the pass
    /// rate; exit 1 when a device fails (or, with --min-pass, when fewer
    /// pass).
    Corpus {
        /// The folder of ESI files.
        dir: PathBuf,
        /// Also write a JUnit XML report here.
        #[arg(long, value_name = "FILE")]
        junit: Option<PathBuf>,
        /// Exit 0 when at least this percentage of the devices pass.
        #[arg(long, value_name = "PERCENT")]
        min_pass: Option<f64>,
    },
}

/// Runs an `esi` command.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    let esi = match args.op {
        Op::Check { esi } => esi,
        Op::Corpus {
            dir,
            junit,
            min_pass,
        } => return corpus(&dir, junit.as_deref(), min_pass),
    };
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

/// `esi corpus DIR`: the table, the JUnit report, exit 1 on a failure.
fn corpus(dir: &Path, junit: Option<&Path>, min_pass: Option<f64>) -> Result<(), Failure> {
    let mut n = 0usize;
    let rows = master_test::corpus::run_dir_with(dir, |r| {
        n += 1;
        eprintln!(
            "[{n}] {} {} {:#010x}: {}",
            r.file,
            r.type_name,
            r.revision,
            r.outcome.word()
        );
    })
    .map_err(|e| input(format!("cannot read {}: {e}", dir.display())))?;
    if let Some(j) = junit {
        std::fs::write(j, master_test::corpus::junit(&rows))
            .map_err(|e| input(format!("cannot write {}: {e}", j.display())))?;
    }
    outln!("{}", master_test::corpus::table(&rows).trim_end());
    use master_test::corpus::Outcome;
    let pass = rows.iter().filter(|r| r.outcome == Outcome::Pass).count();
    let counted = rows
        .iter()
        .filter(|r| r.outcome != Outcome::Passive)
        .count();
    let rate = 100.0 * pass as f64 / counted.max(1) as f64;
    if pass == counted || min_pass.is_some_and(|m| rate >= m) {
        return Ok(());
    }
    Err(Failure::Mismatch(master_test::corpus::summary(&rows)))
}
