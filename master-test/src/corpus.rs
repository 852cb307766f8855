//! The ESI corpus runner (`master-test esi corpus DIR`): every device of
//! every ESI file of a folder as a twin on the virtual bus, brought to OP
//! by ethercrab, its SII (read over the EEPROM interface) checked against
//! its ESI device (`ecat_esi::check`), its SDO Information against the
//! ESI's dictionary and its behaviour with the conformance checker (ESC,
//! SII, state machine, mailbox and CoE groups; an ESC in device emulation
//! judged as such); a table (file, type, revision, result, reason) and a
//! JUnit report.
//!
//! What is compared over SDO Information, per object of the ESI's
//! dictionary (as the twin loader reads it, [`ecat_twin::dictionary`]):
//! the object is listed and has the ESI's name and highest subindex; each
//! entry has the ESI's data type, bit length and read/write access, and is
//! mappable at least where the ESI lets it map. Objects the loader left out
//! with a warning are not compared (the warning is the row's note); objects
//! the twin added from the PDOs are allowed; objects a warning names (the
//! twin completed or changed them) are compared for their presence only.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use ecat_sim::chain::Chain;
use ecat_twin::{EsiDevice, InputRule};

use crate::VirtualBus;
use crate::link::Clock;
use crate::mailbox::{MailboxClient, MailboxGeometry};
use crate::sdo_info::{entry_description, object_description, od_list};

/// The longest one device may take (a hung exchange ends the device, not
/// the run).
pub const DEVICE_TIME_LIMIT: std::time::Duration = std::time::Duration::from_secs(120);

/// How far a device got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Loaded, in OP, SII = ESI and (with CoE) SDO Information = ESI.
    Pass,
    /// The file or the device does not load.
    Load,
    /// The twin cannot be built from what loaded.
    Build,
    /// ethercrab did not bring it to OP.
    Op,
    /// Its SII differs from the ESI.
    Sii,
    /// Its SDO Information differs from the ESI's dictionary.
    SdoInfo,
    /// A check of `master-test conformance` failed on it.
    Conformance,
    /// Not an EtherCAT device: `Invisible` and without a product code
    /// (Beckhoff's end caps, shield and power terminals have no ESC), so
    /// there is nothing on the wire to simulate. Not counted in the rate.
    Passive,
}

impl Outcome {
    /// The word the table shows.
    pub fn word(self) -> &'static str {
        match self {
            Outcome::Pass => "pass",
            Outcome::Load => "load",
            Outcome::Build => "build",
            Outcome::Op => "op",
            Outcome::Sii => "sii",
            Outcome::SdoInfo => "sdo-info",
            Outcome::Conformance => "conformance",
            Outcome::Passive => "passive",
        }
    }
}

/// One device (or one file that has none that loads).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Row {
    /// File name.
    pub file: String,
    /// Device type (order code); empty for a file that does not load.
    pub type_name: String,
    /// Revision.
    pub revision: u32,
    /// How far it got.
    pub outcome: Outcome,
    /// Why it failed (file, element and line where the loader knows
    /// them), or the first warning of a device that passed.
    pub reason: String,
    /// How many warnings the loader gave.
    pub warnings: usize,
}

/// The rows of every device of every `*.xml` file of `dir`, in file order.
/// A file of module types only (`EtherCATModule`) gives no row.
pub fn run_dir(dir: &Path) -> std::io::Result<Vec<Row>> {
    run_dir_with(dir, |_| {})
}

/// [`run_dir`], calling `done` with each row as it is decided (a
/// progress report).
pub fn run_dir_with(dir: &Path, mut done: impl FnMut(&Row)) -> std::io::Result<Vec<Row>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml")))
        .collect();
    files.sort();
    let mut rows = Vec::new();
    for path in files {
        for r in run_file(&path) {
            done(&r);
            rows.push(r);
        }
    }
    Ok(rows)
}

/// The rows of every device of one ESI file.
pub fn run_file(path: &Path) -> Vec<Row> {
    let file = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let row = |type_name: &str, revision: u32, outcome, reason: String| Row {
        file: file.clone(),
        type_name: type_name.to_string(),
        revision,
        outcome,
        reason,
        warnings: 0,
    };
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) => return vec![row("", 0, Outcome::Load, format!("{file}: {e}"))],
    };
    let esi = match ecat_twin::EsiFile::parse_bytes(&bytes) {
        Ok(f) => f,
        Err(e) => return vec![row("", 0, Outcome::Load, format!("{file}: {e}"))],
    };
    let text = ecat_twin::xml::decode(&bytes).unwrap_or_default();
    let mut rows: Vec<Row> = esi
        .refused
        .iter()
        .map(|(label, e)| row(label, 0, Outcome::Load, format!("{file}: {e}")))
        .collect();
    for dev in &esi.devices {
        let (outcome, reason, warnings) = run_device(&file, &text, dev);
        rows.push(Row {
            warnings,
            ..row(&dev.type_name, dev.revision, outcome, reason)
        });
    }
    rows
}

/// One device: twin, OP, SII, SDO Information.
fn run_device(file: &str, text: &str, dev: &EsiDevice) -> (Outcome, String, usize) {
    if dev.product_code == 0
        && dev
            .source
            .attr("Invisible")
            .is_some_and(|v| v == "1" || v == "true")
    {
        return (
            Outcome::Passive,
            format!(
                "{file}: line {}: Invisible, no product code: a terminal without an ESC",
                dev.at.line
            ),
            0,
        );
    }
    let warnings = match ecat_twin::warnings(dev) {
        Ok(w) => w,
        Err(e) => return (Outcome::Build, format!("{file}: {e}"), 0),
    };
    let first = warnings
        .first()
        .map_or_else(String::new, |w| format!("{file}: {w}"));
    let n = warnings.len();
    let twin = match ecat_twin::twin(dev, None, InputRule::Hold) {
        Ok(t) => t,
        Err(e) => return (Outcome::Build, format!("{file}: {e}"), n),
    };
    let layout = if dev.has_mailbox() {
        match ecat_twin::coe_twin::describe(dev) {
            Ok((_, l)) => Some(l),
            Err(e) => return (Outcome::Build, format!("{file}: {e}"), n),
        }
    } else {
        None
    };
    let expected = if dev.has_mailbox() && dev.coe_details & 0x02 != 0 {
        match dev.source.path("Profile/Dictionary") {
            Some(d) => match ecat_twin::dictionary::parse(d) {
                Ok((objects, _, _)) => Some(objects),
                Err(e) => return (Outcome::Build, format!("{file}: {e}"), n),
            },
            None => None,
        }
    } else {
        None
    };
    let work = async {
        let bus = VirtualBus::with_chain(Chain::with_slaves(vec![twin]), Clock::simulated(), None)
            .map_err(|e| (Outcome::Op, e.to_string()))?;
        let md = &*bus.maindevice;
        let group = bus
            .init()
            .await
            .map_err(|e| (Outcome::Op, format!("init: {e}")))?;
        let station = group
            .subdevice(md, 0)
            .map_err(|e| (Outcome::Op, e.to_string()))?
            .configured_address();
        let sii = crate::eeprom::read_all(md, station)
            .await
            .map_err(|e| (Outcome::Sii, format!("SII read: {e}")))?;
        let mismatches = ecat_esi::check::check_device(text, dev.product_code, dev.revision, &sii)
            .map_err(|e| (Outcome::Sii, e.to_string()))?;
        if let Some(m) = mismatches.first() {
            return Err((
                Outcome::Sii,
                format!("{} SII mismatch(es), first: {m}", mismatches.len()),
            ));
        }
        if let (Some(objects), Some(layout)) = (&expected, &layout) {
            let mut c = MailboxClient::new(md, station, MailboxGeometry::of(layout));
            compare_sdo_info(&mut c, objects, &warnings)
                .await
                .map_err(|e| (Outcome::SdoInfo, e))?;
        }
        // The conformance checker's behaviour checks (ESC, SII, state
        // machine, mailbox, CoE; an ESC in device emulation judged as
        // such). Its ESI checks are the ones above, so it runs without it.
        let opts = crate::conformance::Options {
            only: Vec::new(),
            esi: None,
            foe: None,
            clock: bus.clock.clone(),
        };
        let report = crate::conformance::run(md, station, &dev.type_name, &opts).await;
        let failed: Vec<&str> = report.failed().map(|c| c.id).collect();
        if !failed.is_empty() {
            let first = report
                .failed()
                .next()
                .map_or(String::new(), |c| c.observed.clone());
            return Err((
                Outcome::Conformance,
                format!("conformance: {} failed (first: {first})", failed.join(", ")),
            ));
        }
        // Where a transition stops: the AL status code the slave set.
        let al_code = || async {
            let code: Result<u16, _> = ethercrab::Command::fprd(station, 0x0134).receive(md).await;
            code.map_or_else(|_| "?".to_string(), |c| format!("{c:#06x}"))
        };
        let group = match group.into_safe_op(md).await {
            Ok(g) => g,
            Err(e) => {
                let code = al_code().await;
                return Err((
                    Outcome::Op,
                    format!("into SAFE-OP: {e} (AL status code {code})"),
                ));
            }
        };
        let group = match group.into_op(md).await {
            Ok(g) => g,
            Err(e) => {
                let code = al_code().await;
                return Err((Outcome::Op, format!("into OP: {e} (AL status code {code})")));
            }
        };
        for _ in 0..4 {
            bus.clock.advance(std::time::Duration::from_millis(1));
            group
                .tx_rx(md)
                .await
                .map_err(|e| (Outcome::Op, format!("process data: {e}")))?;
        }
        let state = group
            .subdevice(md, 0)
            .map_err(|e| (Outcome::Op, e.to_string()))?
            .status()
            .await
            .map_err(|e| (Outcome::Op, e.to_string()))?;
        if state.0 != ethercrab::SubDeviceState::Op {
            return Err((Outcome::Op, format!("AL state {:?} after OP", state)));
        }
        Ok(())
    };
    // A device that stops answering must not stop the run (wall-clock
    // time only bounds the runner, it decides no result of a device that
    // answers).
    let limit = async {
        smol::Timer::after(DEVICE_TIME_LIMIT).await;
        Err((
            Outcome::Op,
            format!("no result within {} s", DEVICE_TIME_LIMIT.as_secs()),
        ))
    };
    let result = smol::block_on(smol::future::or(work, limit));
    match result {
        Ok(()) => (Outcome::Pass, first, n),
        Err((o, why)) => (
            o,
            format!(
                "{file}: {} rev {:#010x}: {why}",
                dev.type_name, dev.revision
            ),
            n,
        ),
    }
}

/// The SDO Information of the slave behind `c` against the ESI's objects.
async fn compare_sdo_info(
    c: &mut MailboxClient<'_>,
    objects: &[ecat_twin::dictionary::ParsedObject],
    changed: &[ecat_twin::esi::Warning],
) -> Result<(), String> {
    let live = od_list(c, 1).await.map_err(|e| format!("OD list: {e}"))?;
    for p in objects {
        let o = &p.object;
        let at = format!("line {} object {:#06x}", p.at.line, o.index);
        if !live.contains(&o.index) {
            return Err(format!("{at}: not in the OD list"));
        }
        // An object the twin completed or changed, as a warning says
        // (from the PDOs, a range, a writable string served read-only):
        // compared for its presence only.
        let named = format!("{:#06x}", o.index);
        if changed.iter().any(|w| w.message.contains(&named)) {
            continue;
        }
        let info = object_description(c, o.index)
            .await
            .map_err(|e| format!("{at}: {e}"))?;
        if info.name != o.name {
            return Err(format!("{at}: name {:?}, ESI {:?}", info.name, o.name));
        }
        if info.max_sub != o.max_sub() {
            return Err(format!(
                "{at}: highest subindex {}, ESI {}",
                info.max_sub,
                o.max_sub()
            ));
        }
        for e in o.entries {
            let got = entry_description(c, o.index, e.sub, 0)
                .await
                .map_err(|x| format!("{at}:{:02x}: {x}", e.sub))?;
            let want_type = ecat_slave::coe::sdo_info::entry_data_type(e);
            let want_access = ecat_slave::coe::sdo_info::entry_access(e);
            let rw = 0x003F;
            let pdo = 0x00C0;
            let ok = got.data_type == want_type
                && got.bit_len == e.bit_len
                && got.access & rw == want_access & rw
                && got.access & want_access & pdo == want_access & pdo;
            if !ok {
                return Err(format!(
                    "{at}:{:02x}: type {:#06x} bits {} access {:#06x}, ESI type {want_type:#06x} bits {} access {want_access:#06x}",
                    e.sub, got.data_type, got.bit_len, got.access, e.bit_len
                ));
            }
        }
    }
    Ok(())
}

/// The rows as a table, then the pass rate.
pub fn table(rows: &[Row]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<44} {:<24} {:<10} {:<8} reason",
        "file", "type", "revision", "result"
    );
    for r in rows {
        let _ = writeln!(
            out,
            "{:<44} {:<24} {:#010x} {:<8} {}{}",
            r.file,
            r.type_name,
            r.revision,
            r.outcome.word(),
            r.reason,
            if r.warnings > 1 {
                format!(" (+{} more warnings)", r.warnings - 1)
            } else {
                String::new()
            }
        );
    }
    let _ = writeln!(out, "{}", summary(rows));
    out
}

/// `N of M devices pass (P %)`, with the count per outcome.
pub fn summary(rows: &[Row]) -> String {
    let pass = rows.iter().filter(|r| r.outcome == Outcome::Pass).count();
    let passive = rows
        .iter()
        .filter(|r| r.outcome == Outcome::Passive)
        .count();
    let total = rows.len() - passive;
    let pct = if total == 0 {
        0.0
    } else {
        100.0 * pass as f64 / total as f64
    };
    let mut per = String::new();
    for o in [
        Outcome::Load,
        Outcome::Build,
        Outcome::Op,
        Outcome::Sii,
        Outcome::SdoInfo,
        Outcome::Conformance,
    ] {
        let n = rows.iter().filter(|r| r.outcome == o).count();
        if n > 0 {
            let _ = write!(per, ", {n} {}", o.word());
        }
    }
    let warned = rows.iter().filter(|r| r.warnings > 0).count();
    let passive = if passive > 0 {
        format!(" ({passive} passive terminals without an ESC not counted)")
    } else {
        String::new()
    };
    format!(
        "{pass} of {total} devices pass ({pct:.1} %){per}; {warned} with loader warnings{passive}"
    )
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The rows as a JUnit XML report (one test case per device).
pub fn junit(rows: &[Row]) -> String {
    let failures = rows
        .iter()
        .filter(|r| !matches!(r.outcome, Outcome::Pass | Outcome::Passive))
        .count();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuite name=\"esi-corpus\" tests=\"{}\" failures=\"{failures}\">",
        rows.len()
    );
    for r in rows {
        let _ = write!(
            out,
            "  <testcase classname=\"{}\" name=\"{} rev {:#010x}\"",
            xml_escape(&r.file),
            xml_escape(&r.type_name),
            r.revision
        );
        if r.outcome == Outcome::Passive {
            let _ = writeln!(
                out,
                "><skipped message=\"{}\"/></testcase>",
                xml_escape(&r.reason)
            );
        } else if r.outcome == Outcome::Pass {
            out.push_str("/>\n");
        } else {
            let _ = writeln!(
                out,
                "><failure type=\"{}\" message=\"{}\"/></testcase>",
                r.outcome.word(),
                xml_escape(&r.reason)
            );
        }
    }
    out.push_str("</testsuite>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(outcome: Outcome) -> Row {
        Row {
            file: "a&b.xml".into(),
            type_name: "EL<1>".into(),
            revision: 0x10,
            outcome,
            reason: "why \"so\"".into(),
            warnings: 2,
        }
    }

    #[test]
    fn the_summary_counts_passes_and_failures_by_stage() {
        let rows = [row(Outcome::Pass), row(Outcome::Sii), row(Outcome::Pass)];
        assert_eq!(
            summary(&rows),
            "2 of 3 devices pass (66.7 %), 1 sii; 3 with loader warnings"
        );
        assert!(table(&rows).contains("(+1 more warnings)"));
    }

    #[test]
    fn the_junit_report_escapes_names_and_lists_failures() {
        let j = junit(&[row(Outcome::Pass), row(Outcome::Op)]);
        assert!(j.contains("tests=\"2\" failures=\"1\""), "{j}");
        assert!(j.contains("classname=\"a&amp;b.xml\" name=\"EL&lt;1&gt; rev 0x00000010\""));
        assert!(
            j.contains("<failure type=\"op\" message=\"why &quot;so&quot;\"/>"),
            "{j}"
        );
        ecat_twin::xml::parse(&j).expect("well-formed");
    }

    #[test]
    fn a_synthetic_coe_device_of_an_iso_8859_1_file_passes_every_stage() {
        let dir = std::env::temp_dir().join(format!("corpus-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("latin1.xml");
        std::fs::write(&path, SYNTHETIC_LATIN1).unwrap();
        let rows = run_dir(&dir).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(rows.len(), 1, "{rows:?}");
        assert_eq!(rows[0].outcome, Outcome::Pass, "{}", rows[0].reason);
        assert_eq!(rows[0].type_name, "Tw\u{e4}n");
    }

    /// A synthetic ESI written for this test (not a vendor's file): ISO-8859-1
    /// bytes (the `ä` is 0xE4), a REAL object, lowercase PdoMapping, an
    /// octet string, an entry mapped both ways and a PDO entry without an
    /// object of the dictionary.
    const SYNTHETIC_LATIN1: &[u8] = b"<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>
<EtherCATInfo><Vendor><Id>#x00000ABC</Id><Name>Synthetic</Name></Vendor><Descriptions>
<Groups><Group><Type>G</Type><Name>G</Name></Group></Groups><Devices>
<Device><Type ProductCode=\"#x1\" RevisionNo=\"#x2\">Tw\xe4n</Type><Name>Tw\xe4n</Name><GroupType>G</GroupType>
<Fmmu>Outputs</Fmmu><Fmmu>Inputs</Fmmu><Fmmu>MBoxState</Fmmu>
<Sm StartAddress=\"#x1000\" DefaultSize=\"128\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>
<Sm StartAddress=\"#x1080\" DefaultSize=\"128\" ControlByte=\"#x22\" Enable=\"1\">MBoxIn</Sm>
<Sm StartAddress=\"#x1100\" ControlByte=\"#x64\" Enable=\"1\">Outputs</Sm>
<Sm StartAddress=\"#x1180\" ControlByte=\"#x20\" Enable=\"1\">Inputs</Sm>
<RxPdo Fixed=\"1\" Sm=\"2\"><Index>#x1600</Index><Name>Out</Name>
<Entry><Index>#x7000</Index><SubIndex>0</SubIndex><BitLen>32</BitLen><Name>Set</Name><DataType>REAL</DataType></Entry></RxPdo>
<TxPdo Fixed=\"1\" Sm=\"3\"><Index>#x1A00</Index><Name>In</Name>
<Entry><Index>#x6000</Index><SubIndex>0</SubIndex><BitLen>16</BitLen><Name>Count</Name><DataType>UINT</DataType></Entry></TxPdo>
<Mailbox><CoE SdoInfo=\"1\" PdoAssign=\"0\"/></Mailbox>
<Profile><Dictionary><DataTypes>
<DataType><Name>REAL</Name><BitSize>32</BitSize></DataType>
<DataType><Name>UDINT</Name><BitSize>32</BitSize></DataType>
<DataType><Name>ARRAY [0..3] OF BYTE</Name><BaseType>BYTE</BaseType><BitSize>32</BitSize><ArrayInfo><LBound>0</LBound><Elements>4</Elements></ArrayInfo></DataType>
</DataTypes><Objects>
<Object><Index>#x1000</Index><Name>Device type</Name><Type>UDINT</Type><BitSize>32</BitSize><Info><DefaultData>00000000</DefaultData></Info><Flags><Access>ro</Access></Flags></Object>
<Object><Index>#x2000</Index><Name>Gain</Name><Type>REAL</Type><BitSize>32</BitSize><Info><DefaultValue>1.5</DefaultValue></Info><Flags><Access>rw</Access><PdoMapping>rt</PdoMapping></Flags></Object>
<Object><Index>#x2001</Index><Name>Key</Name><Type>ARRAY [0..3] OF BYTE</Type><BitSize>32</BitSize><Info><DefaultData>01020304</DefaultData></Info><Flags><Access>ro</Access></Flags></Object>
<Object><Index>#x7000</Index><Name>Set</Name><Type>REAL</Type><BitSize>32</BitSize><Flags><Access>rw</Access><PdoMapping>r</PdoMapping></Flags></Object>
</Objects></Dictionary></Profile>
</Device></Devices></Descriptions></EtherCATInfo>";
}
