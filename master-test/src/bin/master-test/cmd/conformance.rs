//! `conformance`: the open conformance checker against one slave (see
//! [`master_test::conformance`]).

use crate::failure::{Failure, input};
use crate::output::outln;
use crate::parse::parse_password;
use crate::target::{Session, Where};
use master_test::conformance::{self, FoeOptions, Group, Options};
use std::path::PathBuf;

/// Options of `conformance`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The device's ESI file, for the SII and dictionary consistency
    /// checks (default: the generated ESI when the slave is a device of
    /// the catalog; otherwise those checks do not apply).
    #[arg(long, value_name = "FILE")]
    esi: Option<PathBuf>,
    /// Only these groups, comma-separated: esc, sii, state, mailbox, coe,
    /// foe.
    #[arg(long, value_name = "GROUPS", value_delimiter = ',', value_parser = Group::parse)]
    only: Vec<Group>,
    /// Also write the results as JUnit XML to FILE (for CI systems).
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Also write the results as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Run the FoE checks: download FILE in BOOT (it really is written:
    /// on a device that takes firmware, use an image it accepts).
    #[arg(long, value_name = "FILE")]
    foe_file: Option<PathBuf>,
    /// The FoE password of the device: 1 to 8 hex digits.
    #[arg(long, default_value = "00000000", value_parser = parse_password)]
    foe_password: u32,
}

/// Runs the checks and prints the table; exit status 1 when a check
/// failed.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    let read = |p: &PathBuf| {
        std::fs::read(p).map_err(|e| input(format!("cannot read {}: {e}", p.display())))
    };
    let esi_given = match &args.esi {
        Some(p) => Some(
            String::from_utf8(read(p)?)
                .map_err(|_| input(format!("{}: not an ESI XML file (not UTF-8)", p.display())))?,
        ),
        None => None,
    };
    let foe = match &args.foe_file {
        Some(p) => Some(FoeOptions {
            file: read(p)?,
            name: p.file_name().map_or_else(
                || "firmware.efw".into(),
                |n| n.to_string_lossy().into_owned(),
            ),
            password: args.foe_password,
        }),
        None => None,
    };
    if args.only.contains(&Group::Foe) && foe.is_none() {
        return Err(input(
            "--only foe needs --foe-file FILE (the file to download in BOOT)",
        ));
    }
    for p in [&args.junit, &args.json].into_iter().flatten() {
        if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty())
            && !dir.is_dir()
        {
            return Err(input(format!(
                "cannot write {}: no directory {}",
                p.display(),
                dir.display()
            )));
        }
    }
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let esi = match (esi_given, sel.device) {
        (Some(x), _) => Some(x),
        (None, Some(d)) => ecat_esi::esi::generate(d.description)
            .ok()
            .and_then(|x| String::from_utf8(x).ok()),
        (None, None) => None,
    };
    let opts = Options {
        only: args.only.clone(),
        esi,
        foe,
        clock: s.bus.clock().clone(),
    };
    let report = conformance::run(s.md(), sel.station, &sel.label(), &opts).await;
    out_text(&report.to_text());
    let write = |p: &PathBuf, text: String| {
        std::fs::write(p, text).map_err(|e| input(format!("cannot write {}: {e}", p.display())))
    };
    if let Some(p) = &args.junit {
        write(p, report.to_junit())?;
    }
    if let Some(p) = &args.json {
        write(p, report.to_json())?;
    }
    let (_, failed, _) = report.counts();
    if failed > 0 {
        let ids: Vec<&str> = report.failed().map(|c| c.id).collect();
        return Err(Failure::Mismatch(format!(
            "{failed} conformance check(s) failed for {}: {}",
            sel.label(),
            ids.join(", ")
        )));
    }
    Ok(())
}

fn out_text(text: &str) {
    for l in text.lines() {
        outln!("{l}");
    }
}
