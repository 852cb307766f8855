//! An open conformance checker: groups of checks run against one slave,
//! real or simulated, over any [`MainDevice`], each with the ETG section it
//! follows, what it expects, what it observed and a verdict.
//!
//! The checker needs the slave in PRE-OP with the mailbox configured (as
//! ethercrab's `init_single_group` leaves it) and returns it to PRE-OP.
//! Groups:
//!
//! | group | what |
//! |---|---|
//! | `esc` | register reads, station address and alias, DL status, EEPROM interface |
//! | `sii` | header checksum, categories, identity = 0x1018, mailbox = SyncM, device name, PDOs = live mapping, ESI |
//! | `state` | allowed and refused AL transitions with their codes, error acknowledge, SM checks at PRE-OP and SAFE-OP, SM watchdog and recovery |
//! | `mailbox` | unsupported protocol, inconsistent and short lengths, repeated counter, SM1 repeat, nothing stale after INIT |
//! | `coe` | every announced entry read (and rewritten with its own value), abort service and codes, complete access, SDO Information = ESI, Emergency framing |
//! | `foe` | (opt-in) BOOT, file download, wrong password refused |
//!
//! Not a replacement for the ETG Conformance Test Tool: it checks what the
//! sections cited say, as this project reads them (see docs/book/src/conformance.md).

use crate::eeprom;
use crate::foe;
use crate::link::Clock;
use crate::mailbox::{ClientError, MailboxClient, MailboxGeometry, sm_register};
use crate::sdo_info::{self, EntryInfo};
use ecat_slave::wire::coe::{CoeHeader, CoeService, SdoRequest};
use ecat_slave::wire::mailbox::{MailboxError as WireMailboxError, MailboxType};
use ethercrab::{Command, MainDevice};
use std::fmt::Write as _;
use std::time::Duration;

/// A group of checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Group {
    /// ESC registers and the EEPROM interface.
    Esc,
    /// SII contents and their consistency with the live slave and the ESI.
    Sii,
    /// The AL state machine.
    State,
    /// The mailbox layer.
    Mailbox,
    /// CoE: SDO, SDO Information, Emergency.
    Coe,
    /// FoE in BOOT (opt-in).
    Foe,
}

impl Group {
    /// Every group, in the order they run.
    pub const ALL: [Group; 6] = [
        Group::Esc,
        Group::Sii,
        Group::State,
        Group::Mailbox,
        Group::Coe,
        Group::Foe,
    ];

    /// The group's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Group::Esc => "esc",
            Group::Sii => "sii",
            Group::State => "state",
            Group::Mailbox => "mailbox",
            Group::Coe => "coe",
            Group::Foe => "foe",
        }
    }

    /// The group named `s`.
    pub fn parse(s: &str) -> Result<Group, String> {
        Group::ALL
            .into_iter()
            .find(|g| g.name() == s.trim().to_ascii_lowercase())
            .ok_or_else(|| {
                format!(
                    "unknown check group '{s}': choose from {}",
                    Group::ALL.map(Group::name).join(", ")
                )
            })
    }
}

/// The outcome of one check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// The slave did what the reference says.
    Pass,
    /// It did not.
    Fail,
    /// The check does not apply to this slave (the feature is not
    /// announced) or was not asked for.
    NotApplicable,
}

impl Verdict {
    /// `pass`, `FAIL`, `n/a`.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "FAIL",
            Verdict::NotApplicable => "n/a",
        }
    }
}

/// One check's result.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckResult {
    /// Stable identifier (`coe.abort-service`).
    pub id: &'static str,
    /// Its group.
    pub group: Group,
    /// The section it follows (`ETG.1000.6 5.6.2.7`).
    pub reference: &'static str,
    /// What the reference requires.
    pub expected: String,
    /// What the slave did.
    pub observed: String,
    /// Pass, fail or not applicable.
    pub verdict: Verdict,
}

/// What to run.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Only these groups (empty: all but FoE unless `foe` is given).
    pub only: Vec<Group>,
    /// The device's ESI (XML text) for the consistency checks.
    pub esi: Option<String>,
    /// FoE checks: the file to download in BOOT.
    pub foe: Option<FoeOptions>,
    /// The time the checker waits and measures in: real time on a wire;
    /// on a virtual bus the slaves' clock, so a check that waits for a
    /// watchdog sees the same on an idle and on a busy machine.
    pub clock: Clock,
}

/// The FoE group's input.
#[derive(Debug, Clone)]
pub struct FoeOptions {
    /// The file sent with a write request in BOOT.
    pub file: Vec<u8>,
    /// Its name in the request.
    pub name: String,
    /// The right password.
    pub password: u32,
}

/// All results for one slave.
#[derive(Debug, Clone)]
pub struct Report {
    /// `slave 0 (0x1000 PAM-199-P-ETC)`.
    pub slave: String,
    /// In the order they ran.
    pub checks: Vec<CheckResult>,
}

impl Report {
    /// The checks that failed.
    pub fn failed(&self) -> impl Iterator<Item = &CheckResult> {
        self.checks.iter().filter(|c| c.verdict == Verdict::Fail)
    }

    /// Counts of (pass, fail, not applicable).
    pub fn counts(&self) -> (usize, usize, usize) {
        let n = |v| self.checks.iter().filter(|c| c.verdict == v).count();
        (
            n(Verdict::Pass),
            n(Verdict::Fail),
            n(Verdict::NotApplicable),
        )
    }

    /// A table: verdict, check, expectation with its reference, observed.
    pub fn to_text(&self) -> String {
        let mut out = format!("conformance of {}\n", self.slave);
        let w = self.checks.iter().map(|c| c.id.len()).max().unwrap_or(5);
        for c in &self.checks {
            let _ = writeln!(
                out,
                "{:<4}  {:<w$}  {} [{}]\n      {:<w$}  observed: {}",
                c.verdict.name(),
                c.id,
                c.expected,
                c.reference,
                "",
                c.observed
            );
        }
        let (p, f, n) = self.counts();
        let _ = writeln!(out, "{p} passed, {f} failed, {n} not applicable");
        out
    }

    /// JSON: `{"slave": ..., "passed": n, "failed": n, "not_applicable": n,
    /// "checks": [{"id", "group", "reference", "expected", "observed",
    /// "verdict"}]}`.
    pub fn to_json(&self) -> String {
        let (p, f, n) = self.counts();
        let checks: Vec<serde_json::Value> = self
            .checks
            .iter()
            .map(|c| {
                serde_json::json!({
                    "id": c.id,
                    "group": c.group.name(),
                    "reference": c.reference,
                    "expected": c.expected,
                    "observed": c.observed,
                    "verdict": match c.verdict {
                        Verdict::Pass => "pass",
                        Verdict::Fail => "fail",
                        Verdict::NotApplicable => "not_applicable",
                    },
                })
            })
            .collect();
        let v = serde_json::json!({
            "slave": self.slave,
            "passed": p,
            "failed": f,
            "not_applicable": n,
            "checks": checks,
        });
        serde_json::to_string_pretty(&v).unwrap_or_default()
    }

    /// JUnit XML (one test suite, one test case per check; failures carry
    /// the observation, checks that do not apply are skipped), as CI
    /// systems read it.
    pub fn to_junit(&self) -> String {
        let (_, f, n) = self.counts();
        let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        let _ = writeln!(
            out,
            "<testsuites>\n  <testsuite name=\"conformance {}\" tests=\"{}\" failures=\"{f}\" skipped=\"{n}\">",
            xml_escape(&self.slave),
            self.checks.len()
        );
        for c in &self.checks {
            let _ = write!(
                out,
                "    <testcase classname=\"conformance.{}\" name=\"{}\"",
                c.group.name(),
                xml_escape(c.id)
            );
            match c.verdict {
                Verdict::Pass => out.push_str("/>\n"),
                Verdict::Fail => {
                    let _ = writeln!(
                        out,
                        ">\n      <failure message=\"{}\">expected: {} [{}]\nobserved: {}</failure>\n    </testcase>",
                        xml_escape(&c.observed),
                        xml_escape(&c.expected),
                        xml_escape(c.reference),
                        xml_escape(&c.observed)
                    );
                }
                Verdict::NotApplicable => {
                    let _ = writeln!(
                        out,
                        ">\n      <skipped message=\"{}\"/>\n    </testcase>",
                        xml_escape(&c.observed)
                    );
                }
            }
        }
        out.push_str("  </testsuite>\n</testsuites>\n");
        out
    }
}

/// Escapes text for XML attributes and content (control characters other
/// than tab and newline become spaces: XML 1.0 cannot carry them).
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' | '\n' => out.push(ch),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// Collects results while the checks run.
struct Run<'a> {
    md: &'a MainDevice<'a>,
    station: u16,
    sii: Vec<u8>,
    mailbox: Option<MailboxGeometry>,
    bootstrap: Option<MailboxGeometry>,
    checks: Vec<CheckResult>,
    group: Group,
    emergencies: Vec<Vec<u8>>,
    clock: Clock,
}

/// A check's outcome before it is recorded.
enum Outcome {
    Pass(String),
    Fail(String),
    NotApplicable(String),
}

impl<'a> Run<'a> {
    fn record(&mut self, id: &'static str, reference: &'static str, expected: &str, o: Outcome) {
        let (verdict, observed) = match o {
            Outcome::Pass(s) => (Verdict::Pass, s),
            Outcome::Fail(s) => (Verdict::Fail, s),
            Outcome::NotApplicable(s) => (Verdict::NotApplicable, s),
        };
        self.checks.push(CheckResult {
            id,
            group: self.group,
            reference,
            expected: expected.to_string(),
            observed,
            verdict,
        });
    }

    fn client(&self) -> Option<MailboxClient<'a>> {
        self.mailbox.map(|g| {
            let mut c = MailboxClient::new(self.md, self.station, g);
            c.lenient_abort_service = true;
            c.timeout = Duration::from_secs(1);
            c
        })
    }

    async fn read<T: ethercrab::EtherCrabWireReadSized>(&self, reg: u16) -> Result<T, String> {
        Command::fprd(self.station, reg)
            .with_wkc(1)
            .receive::<T>(self.md)
            .await
            .map_err(|e| format!("FPRD {reg:#06x}: {e}"))
    }

    async fn write(&self, reg: u16, data: &[u8]) -> Result<(), String> {
        Command::fpwr(self.station, reg)
            .with_wkc(1)
            .send(self.md, data)
            .await
            .map_err(|e| format!("FPWR {reg:#06x}: {e}"))
    }

    /// AL status (0x0130) and AL status code (0x0134).
    async fn al(&self) -> Result<(u16, u16), String> {
        Ok((
            self.read::<u16>(0x0130).await?,
            self.read::<u16>(0x0134).await?,
        ))
    }

    /// Writes AL control `control` and waits until the state it names is
    /// reached or the error flag is set (3 s); returns the final status and
    /// code.
    async fn request(&self, control: u16) -> Result<(u16, u16), String> {
        self.write(0x0120, &control.to_le_bytes()).await?;
        let start = self.clock.elapsed();
        loop {
            let (st, code) = self.al().await?;
            if st & 0x10 != 0 || (st & 0x0F == control & 0x0F) {
                return Ok((st, code));
            }
            if (self.clock.elapsed() - start) > Duration::from_secs(3) {
                return Ok((st, code));
            }
            self.clock.sleep(Duration::from_micros(500)).await;
        }
    }

    /// Acknowledges an error in `state` (control = state | 0x10) and
    /// returns the status afterwards.
    async fn acknowledge(&self, state: u16) -> Result<(u16, u16), String> {
        self.write(0x0120, &(state | 0x10).to_le_bytes()).await?;
        let start = self.clock.elapsed();
        loop {
            let (st, code) = self.al().await?;
            if st & 0x10 == 0 || (self.clock.elapsed() - start) > Duration::from_secs(3) {
                return Ok((st, code));
            }
            self.clock.sleep(Duration::from_micros(500)).await;
        }
    }

    /// Back to PRE-OP whatever happened (acknowledging errors on the way).
    async fn back_to_preop(&self) {
        for _ in 0..3 {
            if let Ok((st, _)) = self.al().await {
                if st & 0x1F == 0x02 {
                    return;
                }
                if st & 0x10 != 0 {
                    let _ = self.acknowledge(st & 0x0F).await;
                }
            }
            if let Ok((st, _)) = self.request(0x02).await
                && st & 0x1F == 0x02
            {
                return;
            }
            let _ = self.request(0x01).await;
            let _ = self.acknowledge(0x01).await;
        }
    }
}

fn state_name(st: u16) -> String {
    let s = match st & 0x0F {
        0x01 => "INIT",
        0x02 => "PRE-OP",
        0x03 => "BOOT",
        0x04 => "SAFE-OP",
        0x08 => "OP",
        _ => "?",
    };
    if st & 0x10 != 0 {
        format!("{s} + error")
    } else {
        s.to_string()
    }
}

fn al_text(st: u16, code: u16) -> String {
    if st & 0x10 != 0 {
        format!(
            "{}, AL status code {code:#06x} ({})",
            state_name(st),
            ecat_slave::al::AlStatusCode::from_code(code).text()
        )
    } else {
        state_name(st)
    }
}

/// Runs the checks of `opts` against the slave at `station` (in PRE-OP).
/// `label` names it in the report.
pub async fn run(md: &MainDevice<'_>, station: u16, label: &str, opts: &Options) -> Report {
    let wanted = |g: Group| {
        if opts.only.is_empty() {
            g != Group::Foe || opts.foe.is_some()
        } else {
            opts.only.contains(&g)
        }
    };
    let sii = eeprom::read_all(md, station).await.unwrap_or_default();
    let (mailbox, bootstrap) = eeprom::mailboxes(&sii);
    let mut r = Run {
        md,
        station,
        sii,
        mailbox,
        bootstrap,
        checks: Vec::new(),
        group: Group::Esc,
        emergencies: Vec::new(),
        clock: opts.clock.clone(),
    };
    for g in Group::ALL {
        if !wanted(g) {
            continue;
        }
        r.group = g;
        match g {
            Group::Esc => esc_checks(&mut r).await,
            Group::Sii => sii_checks(&mut r, opts.esi.as_deref()).await,
            Group::State => state_checks(&mut r).await,
            Group::Mailbox => mailbox_checks(&mut r).await,
            Group::Coe => coe_checks(&mut r, opts.esi.as_deref()).await,
            Group::Foe => foe_checks(&mut r, opts.foe.as_ref()).await,
        }
        r.back_to_preop().await;
    }
    Report {
        slave: label.to_string(),
        checks: r.checks,
    }
}

// ---------------------------------------------------------------- ESC --

async fn esc_checks(r: &mut Run<'_>) {
    let o = match r.read::<[u8; 4]>(0x0000).await {
        Ok(b) => Outcome::Pass(format!(
            "type {:#04x}, revision {}, build {}",
            b[0],
            b[1],
            u16::from_le_bytes([b[2], b[3]])
        )),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "esc.information",
        "ETG.1000.4 6.1.1",
        "ESC type, revision and build (0x0000-0x0003) readable by configured address",
        o,
    );

    let o = match r.read::<u16>(0x0010).await {
        Ok(a) if a == r.station => Outcome::Pass(format!("{a:#06x}")),
        Ok(a) => Outcome::Fail(format!("{a:#06x}, configured {:#06x}", r.station)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "esc.station-address",
        "ETG.1000.4 6.2.1",
        "0x0010 holds the configured station address",
        o,
    );

    let word4 = r.sii.get(8..10).map(|b| u16::from_le_bytes([b[0], b[1]]));
    let o = match (r.read::<u16>(0x0012).await, word4) {
        (Ok(a), Some(w)) if a == w => Outcome::Pass(format!("{a:#06x} = SII word 4")),
        (Ok(a), Some(w)) => Outcome::Fail(format!("{a:#06x}, SII word 4 is {w:#06x}")),
        (Ok(_), None) => Outcome::Fail("SII unreadable".into()),
        (Err(e), _) => Outcome::Fail(e),
    };
    r.record(
        "esc.station-alias",
        "ETG.1000.4 6.2.2, ETG.2010 2.2",
        "0x0012 = configured station alias of SII word 4 (loaded at power-on)",
        o,
    );

    let o = match r.read::<u16>(0x0110).await {
        Ok(s) if s & 0x0010 != 0 && s & 0x0200 != 0 => {
            Outcome::Pass(format!("{s:#06x}: port 0 link and communication"))
        }
        Ok(s) => Outcome::Fail(format!(
            "{s:#06x}: port 0 physical link {} communication {}",
            s & 0x0010 != 0,
            s & 0x0200 != 0
        )),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "esc.dl-status",
        "ETG.1000.4 6.4.3",
        "DL status 0x0110: port 0 physical link (bit 4) and communication established (bit 9)",
        o,
    );

    let a = eeprom::read(r.md, r.station, 8).await;
    let b = eeprom::read(r.md, r.station, 8).await;
    let ctl = r.read::<u16>(0x0502).await;
    let o = match (a, b, ctl) {
        (Ok(a), Ok(b), Ok(c)) if a == b && c & 0x8000 == 0 && c & 0x7800 == 0 => {
            Outcome::Pass(format!(
                "words 0-7 read twice alike; {}-byte reads; status {c:#06x} not busy, no error",
                if c & 0x0040 != 0 { 8 } else { 4 }
            ))
        }
        (Ok(a), Ok(b), Ok(c)) => Outcome::Fail(format!(
            "reads {} alike; status {c:#06x}{}{}",
            if a == b { "" } else { "not" },
            if c & 0x8000 != 0 { ", busy" } else { "" },
            if c & 0x7800 != 0 {
                ", error bits set"
            } else {
                ""
            }
        )),
        (Err(e), _, _) | (_, Err(e), _) => Outcome::Fail(format!("EEPROM read: {e}")),
        (_, _, Err(e)) => Outcome::Fail(e),
    };
    r.record(
        "esc.eeprom-interface",
        "ETG.1000.4 6.4.6",
        "SII reads through 0x0500-0x050F are repeatable; afterwards not busy, no error bits",
        o,
    );
}

// ---------------------------------------------------------------- SII --

async fn sii_checks(r: &mut Run<'_>, esi: Option<&str>) {
    let ins = match ecat_esi::inspect::inspect(&r.sii) {
        Ok(i) => i,
        Err(e) => {
            r.record(
                "sii.checksum",
                "ETG.2010 2.2",
                "an SII of at least the 64-word header",
                Outcome::Fail(format!("{e}")),
            );
            return;
        }
    };
    let o = if ins.stored_crc == ins.computed_crc {
        Outcome::Pass(format!("{:#04x}", ins.stored_crc))
    } else {
        Outcome::Fail(format!(
            "stored {:#04x}, computed {:#04x}",
            ins.stored_crc, ins.computed_crc
        ))
    };
    r.record(
        "sii.checksum",
        "ETG.2010 2.2",
        "word 7 = CRC-8 (x^8+x^2+x+1, start 0xFF) of words 0-6",
        o,
    );

    let other: Vec<&String> = ins
        .problems
        .iter()
        .filter(|p| !p.contains("checksum"))
        .collect();
    let o = if other.is_empty() {
        Outcome::Pass(format!("{} categories decode", ins.categories.len()))
    } else {
        Outcome::Fail(
            other
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join("; "),
        )
    };
    r.record(
        "sii.categories",
        "ETG.2010 2.3-2.9",
        "every category decodes (strings, general, FMMU, SyncM, PDOs), ends with 0xFFFF",
        o,
    );

    let o = if ins.standard_mailbox.rx_size == 0 {
        Outcome::NotApplicable("no standard mailbox in the SII".into())
    } else {
        let sm = &ins.sync_managers;
        let want = [
            (ins.standard_mailbox.rx_offset, ins.standard_mailbox.rx_size),
            (ins.standard_mailbox.tx_offset, ins.standard_mailbox.tx_size),
        ];
        let got: Vec<(u16, u16)> = sm.iter().take(2).map(|s| (s.start, s.length)).collect();
        if got == want {
            Outcome::Pass(format!(
                "out {:#06x}/{} in {:#06x}/{}",
                want[0].0, want[0].1, want[1].0, want[1].1
            ))
        } else {
            Outcome::Fail(format!("header {want:04x?}, SyncM category {got:04x?}"))
        }
    };
    r.record(
        "sii.mailbox-sync-managers",
        "ETG.2010 2.2, 2.7",
        "words 0x18-0x1B (standard mailbox) = SM0/SM1 of the SyncM category",
        o,
    );

    let mut client = r.client();
    let Some(c) = client.as_mut() else {
        for (id, reference, exp) in [
            (
                "sii.identity",
                "ETG.2010 2.2, ETG.1000.6 5.6.7.4.9",
                "SII identity = 0x1018",
            ),
            (
                "sii.device-name",
                "ETG.2010 2.3, 2.4",
                "device name = 0x1008",
            ),
            (
                "sii.pdo-mapping",
                "ETG.2010 2.8",
                "PDO categories = live mapping",
            ),
        ] {
            r.record(
                id,
                reference,
                exp,
                Outcome::NotApplicable("no mailbox".into()),
            );
        }
        return;
    };
    let coe = ins.mailbox_protocols & 0x0004 != 0;
    let o = if !coe {
        Outcome::NotApplicable("no CoE announced".into())
    } else {
        let mut live = Vec::new();
        let mut err = None;
        for sub in 1..=3u8 {
            match c.sdo_upload(0x1018, sub, false).await {
                Ok(v) if v.len() == 4 => live.push(u32::from_le_bytes([v[0], v[1], v[2], v[3]])),
                Ok(v) => err = Some(format!("0x1018:{sub:02x} has {} bytes", v.len())),
                Err(e) => err = Some(format!("0x1018:{sub:02x}: {e}")),
            }
        }
        let id = &ins.identity;
        let sii = [id.vendor_id, id.product_code, id.revision];
        match err {
            Some(e) => Outcome::Fail(e),
            None if live == sii => Outcome::Pass(format!(
                "vendor {:#x}, product {:#x}, revision {:#x}",
                sii[0], sii[1], sii[2]
            )),
            None => Outcome::Fail(format!("SII {sii:#x?}, 0x1018 {live:#x?}")),
        }
    };
    r.record(
        "sii.identity",
        "ETG.2010 2.2, ETG.1000.6 5.6.7.4.9",
        "vendor, product code and revision of SII words 8-13 = 0x1018:01-03",
        o,
    );

    let name_1008 = if coe {
        c.sdo_upload(0x1008, 0, false).await.ok().map(|v| {
            String::from_utf8_lossy(&v)
                .trim_end_matches('\0')
                .to_string()
        })
    } else {
        None
    };
    let general_name = ins.general.as_ref().map(|(_, s)| s[3].clone());
    let string_1 = ins
        .strings
        .iter()
        .find(|(i, _)| *i == 1)
        .map(|(_, s)| s.clone());
    let o = match (&name_1008, &general_name) {
        (None, _) => Outcome::NotApplicable("0x1008 not readable (no CoE)".into()),
        (Some(_), None) => Outcome::Fail("no General category".into()),
        (Some(n), Some(g)) if !g.is_empty() && string_1.as_deref() == Some(n.as_str()) => {
            Outcome::Pass(format!("string 1 \"{n}\" = 0x1008; General name \"{g}\""))
        }
        (Some(n), Some(g)) => Outcome::Fail(format!(
            "0x1008 \"{n}\", General name \"{g}\", string 1 \"{}\"",
            string_1.unwrap_or_default()
        )),
    };
    r.record(
        "sii.device-name",
        "ETG.2010 2.3, 2.4; vendor SII images; SOEM reads string 1",
        "SII string 1 (the device type, what SOEM shows as the name) = 0x1008; the General category names a non-empty string",
        o,
    );

    let o = if !coe {
        Outcome::NotApplicable("no CoE announced".into())
    } else {
        let mut diffs = Vec::new();
        let mut compared = 0;
        // A modular device (ETG.5001, 0xF050 readable): its modules' PDOs
        // are not in the SII but in the ESI's `Modules`, moved into their
        // slots.
        let modules = detected_modules(c).await;
        let module_pdos = match (&modules, esi) {
            (Some(idents), Some(xml)) => match esi_module_pdos(xml, idents) {
                Ok(p) => p,
                Err(e) => {
                    diffs.push(format!("the ESI's modules cannot be read: {e}"));
                    Vec::new()
                }
            },
            _ => Vec::new(),
        };
        let mut unchecked = 0;
        for (assign, dir) in [
            (0x1C12u16, ecat_slave::sii::PdoDirection::Rx),
            (0x1C13, ecat_slave::sii::PdoDirection::Tx),
        ] {
            let Ok(n) = c.sdo_upload(assign, 0, false).await else {
                continue;
            };
            for k in 1..=n.first().copied().unwrap_or(0) {
                let Ok(v) = c.sdo_upload(assign, k, false).await else {
                    diffs.push(format!("{assign:#06x}:{k:02x} unreadable"));
                    continue;
                };
                let pdo = u16::from_le_bytes([
                    v.first().copied().unwrap_or(0),
                    v.get(1).copied().unwrap_or(0),
                ]);
                let described: Option<Vec<u32>> = ins
                    .pdos
                    .iter()
                    .find(|p| p.index == pdo && p.direction == dir)
                    .map(|info| {
                        info.entries
                            .iter()
                            .map(|e| {
                                (u32::from(e.index) << 16)
                                    | (u32::from(e.sub) << 8)
                                    | u32::from(e.bit_len)
                            })
                            .collect()
                    })
                    .or_else(|| {
                        module_pdos
                            .iter()
                            .find(|(p, _)| *p == pdo)
                            .map(|(_, e)| e.clone())
                    });
                let Some(sii) = described else {
                    if modules.is_some() && esi.is_none() {
                        unchecked += 1;
                    } else {
                        diffs.push(format!(
                            "PDO {pdo:#06x} assigned but not in the SII{}",
                            if modules.is_some() {
                                " nor in the ESI's modules"
                            } else {
                                ""
                            }
                        ));
                    }
                    continue;
                };
                let mut live = Vec::new();
                let count = c
                    .sdo_upload(pdo, 0, false)
                    .await
                    .ok()
                    .and_then(|v| v.first().copied())
                    .unwrap_or(0);
                for e in 1..=count {
                    if let Ok(v) = c.sdo_upload(pdo, e, false).await
                        && v.len() == 4
                    {
                        live.push(u32::from_le_bytes([v[0], v[1], v[2], v[3]]));
                    }
                }
                compared += 1;
                if live != sii {
                    diffs.push(format!(
                        "PDO {pdo:#06x}: described {sii:08x?}, live {live:08x?}"
                    ));
                }
            }
        }
        if diffs.is_empty() {
            let modular = match (&modules, unchecked) {
                (Some(m), 0) => format!(" ({} module(s): their PDOs from the ESI)", m.len()),
                (Some(m), n) => format!(
                    " ({} module(s): {n} module PDO(s) unchecked without an ESI)",
                    m.len()
                ),
                (None, _) => String::new(),
            };
            Outcome::Pass(format!("{compared} assigned PDO(s) agree{modular}"))
        } else {
            Outcome::Fail(diffs.join("; "))
        }
    };
    r.record(
        "sii.pdo-mapping",
        "ETG.2010 2.8, ETG.1000.6 5.6.7.4",
        "every PDO assigned in 0x1C12/0x1C13 is in the SII PDO categories with the entries its live mapping object holds",
        o,
    );
    if let Some(c) = client.take() {
        r.emergencies.extend(c.emergencies);
    }

    let o = match esi {
        None => Outcome::NotApplicable("no ESI given (--esi FILE)".into()),
        Some(xml) => match ecat_esi::check::check(xml, &r.sii) {
            Ok(m) if m.is_empty() => Outcome::Pass("no difference".into()),
            Ok(m) => Outcome::Fail(
                m.iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join("; "),
            ),
            Err(e) => Outcome::Fail(format!("the ESI cannot be read: {e}")),
        },
    };
    r.record(
        "sii.esi",
        "ETG.2000, ETG.2010",
        "the SII is what the ESI describes (identity, mailboxes, SMs, PDOs, strings)",
        o,
    );
}

// -------------------------------------------------------------- state --

async fn state_checks(r: &mut Run<'_>) {
    const INVALID: u16 = 0x0011;
    // Refused transitions from PRE-OP, then INIT.
    let refused = async |r: &mut Run<'_>, id, from: u16, to: u16, what: &str| {
        let o = match r.request(to).await {
            Ok((st, code)) if st == (from | 0x10) && code == INVALID => {
                Outcome::Pass(al_text(st, code))
            }
            Ok((st, code)) => Outcome::Fail(al_text(st, code)),
            Err(e) => Outcome::Fail(e),
        };
        r.record(id, "ETG.1000.6 6.4.1, Table 9", what, o);
        let _ = r.acknowledge(from).await;
    };
    refused(
        r,
        "state.preop-to-op-refused",
        0x02,
        0x08,
        "PRE-OP -> OP refused: PRE-OP + error, 0x0011 invalid requested state change",
    )
    .await;

    let o = match r.al().await {
        Ok((0x02, _)) => Outcome::Pass("PRE-OP, error flag cleared".into()),
        Ok((st, code)) => Outcome::Fail(al_text(st, code)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "state.error-acknowledge",
        "ETG.1000.6 6.4.1.3",
        "writing the current state with the acknowledge bit (0x0010) clears the error flag",
        o,
    );

    if r.bootstrap.is_some() {
        refused(
            r,
            "state.preop-to-boot-refused",
            0x02,
            0x03,
            "PRE-OP -> BOOT refused (BOOT only from INIT): 0x0011",
        )
        .await;
    } else {
        r.record(
            "state.preop-to-boot-refused",
            "ETG.1000.6 6.4.1, Table 9",
            "PRE-OP -> BOOT refused (BOOT only from INIT): 0x0011",
            Outcome::NotApplicable("no bootstrap mailbox in the SII".into()),
        );
    }

    let o = match r.request(0x01).await {
        Ok((0x01, _)) => Outcome::Pass("INIT".into()),
        Ok((st, code)) => Outcome::Fail(al_text(st, code)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "state.preop-to-init",
        "ETG.1000.6 6.4.1",
        "PRE-OP -> INIT",
        o,
    );
    refused(
        r,
        "state.init-to-safeop-refused",
        0x01,
        0x04,
        "INIT -> SAFE-OP refused: INIT + error, 0x0011",
    )
    .await;
    refused(
        r,
        "state.init-to-op-refused",
        0x01,
        0x08,
        "INIT -> OP refused: INIT + error, 0x0011",
    )
    .await;

    // Mailbox SM checks at INIT -> PRE-OP.
    if let Some(g) = r.mailbox {
        let good0 = r.read::<[u8; 8]>(0x0800).await.unwrap_or_default();
        let good1 = r.read::<[u8; 8]>(0x0808).await.unwrap_or_default();
        let cases: [(&'static str, u16, [u8; 8], &str); 3] = [
            (
                "state.sm-mailbox-start",
                0x0800,
                {
                    let mut b = good0;
                    b[0..2].copy_from_slice(&g.out.0.wrapping_add(0x40).to_le_bytes());
                    b
                },
                "SM0 start not the SII's: INIT -> PRE-OP refused, 0x0016 invalid mailbox configuration",
            ),
            (
                "state.sm-mailbox-length",
                0x0808,
                {
                    let mut b = good1;
                    b[2..4].copy_from_slice(&g.inp.1.saturating_sub(2).to_le_bytes());
                    b
                },
                "SM1 length not the SII's: INIT -> PRE-OP refused, 0x0016",
            ),
            (
                "state.sm-mailbox-control",
                0x0800,
                {
                    let mut b = good0;
                    b[4] = 0x24; // 3-buffer mode instead of mailbox
                    b
                },
                "SM0 in buffered instead of mailbox mode: INIT -> PRE-OP refused, 0x0016",
            ),
        ];
        for (id, reg, bad, what) in cases {
            let o = match r.write(reg, &bad).await {
                Err(e) => Outcome::Fail(e),
                Ok(()) => match r.request(0x02).await {
                    Ok((st, code)) if st == 0x11 && code == 0x0016 => {
                        Outcome::Pass(al_text(st, code))
                    }
                    Ok((st, code)) => Outcome::Fail(al_text(st, code)),
                    Err(e) => Outcome::Fail(e),
                },
            };
            r.record(id, "ETG.1000.6 6.4.1.1, Table 10", what, o);
            let _ = r.request(0x01).await;
            let _ = r.acknowledge(0x01).await;
            let _ = r.write(0x0800, &good0).await;
            let _ = r.write(0x0808, &good1).await;
        }
    } else {
        for id in [
            "state.sm-mailbox-start",
            "state.sm-mailbox-length",
            "state.sm-mailbox-control",
        ] {
            r.record(
                id,
                "ETG.1000.6 6.4.1.1",
                "mailbox SM checked at INIT -> PRE-OP",
                Outcome::NotApplicable("no mailbox".into()),
            );
        }
    }

    let o = match r.request(0x02).await {
        Ok((0x02, _)) => Outcome::Pass("PRE-OP".into()),
        Ok((st, code)) => Outcome::Fail(al_text(st, code)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "state.init-to-preop",
        "ETG.1000.6 6.4.1",
        "INIT -> PRE-OP with the SII's mailbox configuration",
        o,
    );

    // Process data SMs (SM2 outputs, SM3 inputs) as a master configures
    // them: start, control and enable of the SII's SyncM category, length
    // of the PDOs assigned now.
    let found = (
        r.read::<[u8; 8]>(0x0810).await.unwrap_or_default(),
        r.read::<[u8; 8]>(0x0818).await.unwrap_or_default(),
    );
    let (sm2, sm3) = process_data_sms(r).await;
    let _ = r.write(0x0810, &sm2).await;
    let _ = r.write(0x0818, &sm3).await;
    let len = |b: &[u8; 8]| u16::from_le_bytes([b[2], b[3]]);
    let enabled = |b: &[u8; 8]| b[6] & 1 != 0 && len(b) > 0;

    let o = match r.request(0x04).await {
        Ok((0x04, _)) => Outcome::Pass("SAFE-OP".into()),
        Ok((st, code)) => Outcome::Fail(al_text(st, code)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "state.preop-to-safeop",
        "ETG.1000.6 6.4.1",
        "PRE-OP -> SAFE-OP with the process data SMs the master configured",
        o,
    );
    let _ = r.request(0x02).await;

    for (id, reg, sm, code, what) in [
        (
            "state.sm-output-length",
            0x0810u16,
            sm2,
            0x001Du16,
            "SM2 (outputs) one byte longer than the mapping: PRE-OP -> SAFE-OP refused, 0x001D invalid output configuration",
        ),
        (
            "state.sm-input-length",
            0x0818,
            sm3,
            0x001E,
            "SM3 (inputs) one byte longer than the mapping: PRE-OP -> SAFE-OP refused, 0x001E invalid input configuration",
        ),
    ] {
        if !enabled(&sm) {
            r.record(
                id,
                "ETG.1000.6 6.4.1.2, Table 10",
                what,
                Outcome::NotApplicable("the SM carries no process data".into()),
            );
            continue;
        }
        let mut bad = sm;
        bad[2..4].copy_from_slice(&(len(&sm) + 1).to_le_bytes());
        let o = match r.write(reg, &bad).await {
            Err(e) => Outcome::Fail(e),
            Ok(()) => match r.request(0x04).await {
                Ok((st, c)) if st == 0x12 && c == code => Outcome::Pass(al_text(st, c)),
                Ok((st, c)) => Outcome::Fail(al_text(st, c)),
                Err(e) => Outcome::Fail(e),
            },
        };
        r.record(id, "ETG.1000.6 6.4.1.2, Table 10", what, o);
        let _ = r.acknowledge(0x02).await;
        let _ = r.request(0x02).await;
        let _ = r.write(reg, &sm).await;
    }

    watchdog_checks(r, sm2).await;
    let _ = r.request(0x02).await;
    let _ = r.write(0x0810, &found.0).await;
    let _ = r.write(0x0818, &found.1).await;
}

/// SM2 and SM3 register images (0x0810, 0x0818) for the process data the
/// slave has assigned now: start, control byte and enable from the SII's
/// SyncM category; the length from the assigned PDOs' mapping (over CoE),
/// or the SII's default length without CoE.
async fn process_data_sms(r: &Run<'_>) -> ([u8; 8], [u8; 8]) {
    let sms = ecat_esi::inspect::inspect(&r.sii)
        .map(|i| i.sync_managers)
        .unwrap_or_default();
    let mut client = r.client();
    let mut out = [[0u8; 8]; 2];
    for (k, (n, assign)) in [(2usize, 0x1C12u16), (3, 0x1C13)].into_iter().enumerate() {
        let Some(sm) = sms.get(n) else { continue };
        let mut len = sm.length;
        if let Some(c) = client.as_mut()
            && let Ok(count) = c.sdo_upload(assign, 0, false).await
        {
            let mut bits = 0u32;
            for i in 1..=count.first().copied().unwrap_or(0) {
                let Ok(p) = c.sdo_upload(assign, i, false).await else {
                    continue;
                };
                let pdo = u16::from_le_bytes([
                    p.first().copied().unwrap_or(0),
                    p.get(1).copied().unwrap_or(0),
                ]);
                let entries = c
                    .sdo_upload(pdo, 0, false)
                    .await
                    .ok()
                    .and_then(|v| v.first().copied())
                    .unwrap_or(0);
                for e in 1..=entries {
                    if let Ok(v) = c.sdo_upload(pdo, e, false).await {
                        bits += u32::from(v.first().copied().unwrap_or(0));
                    }
                }
            }
            len = u16::try_from(bits.div_ceil(8)).unwrap_or(u16::MAX);
        }
        if let Some(b) = out.get_mut(k) {
            *b = sm_register(sm.start, len, sm.control, len > 0 && sm.enable & 1 != 0);
        }
    }
    (out[0], out[1])
}

/// SAFE-OP -> OP with outputs, the SM watchdog when they stop, and the
/// recovery.
async fn watchdog_checks(r: &mut Run<'_>, sm2: [u8; 8]) {
    let start = u16::from_le_bytes([sm2[0], sm2[1]]);
    let len = usize::from(u16::from_le_bytes([sm2[2], sm2[3]]));
    let watchdog_on = sm2[4] & 0x40 != 0;
    let divider = r.read::<u16>(0x0400).await.unwrap_or(0);
    let wd = r.read::<u16>(0x0420).await.unwrap_or(0);
    let wd_time = Duration::from_nanos(40 * (u64::from(divider) + 2) * u64::from(wd));
    let ids = [
        ("state.safeop-to-op", "SAFE-OP -> OP while outputs arrive"),
        (
            "state.sm-watchdog",
            "outputs stop: OP -> SAFE-OP + error, 0x001B sync manager watchdog, after the watchdog time",
        ),
        (
            "state.watchdog-recovery",
            "acknowledge and fresh outputs: back to OP",
        ),
    ];
    if len == 0 || sm2[6] & 1 == 0 {
        for (id, what) in ids {
            r.record(
                id,
                "ETG.1000.6 6.4.1, ETG.1000.4 6.7",
                what,
                Outcome::NotApplicable("no output SM (SM2)".into()),
            );
        }
        return;
    }
    let outputs = vec![0u8; len];
    let send = async |r: &Run<'_>| {
        let _ = Command::fpwr(r.station, start)
            .send(r.md, &outputs[..])
            .await;
    };
    // SAFE-OP, outputs flowing, then OP.
    let _ = r.request(0x04).await;
    let mut reached = None;
    let _ = r.write(0x0120, &0x08u16.to_le_bytes()).await;
    let t0 = r.clock.elapsed();
    while (r.clock.elapsed() - t0) < Duration::from_secs(3) {
        send(r).await;
        if let Ok((st, code)) = r.al().await
            && (st == 0x08 || st & 0x10 != 0)
        {
            reached = Some((st, code));
            break;
        }
        r.clock.sleep(Duration::from_millis(1)).await;
    }
    let o = match reached {
        Some((0x08, _)) => Outcome::Pass("OP".into()),
        Some((st, code)) => Outcome::Fail(al_text(st, code)),
        None => Outcome::Fail("no OP within 3 s".into()),
    };
    let in_op = matches!(reached, Some((0x08, _)));
    r.record(ids[0].0, "ETG.1000.6 6.4.1", ids[0].1, o);

    if !watchdog_on || wd == 0 {
        r.record(
            ids[1].0,
            "ETG.1000.4 6.7, ETG.1000.6 Table 10",
            ids[1].1,
            Outcome::NotApplicable(format!(
                "SM2 watchdog {} (control {:#04x}), 0x0420 = {wd}",
                if watchdog_on { "on" } else { "off" },
                sm2[4]
            )),
        );
        r.record(
            ids[2].0,
            "ETG.1000.6 6.4.1.3",
            ids[2].1,
            Outcome::NotApplicable("no SM watchdog".into()),
        );
        return;
    }
    let o = if !in_op {
        Outcome::NotApplicable("OP was not reached".into())
    } else {
        let stop = r.clock.elapsed();
        let mut seen = None;
        while (r.clock.elapsed() - stop) < wd_time * 5 + Duration::from_secs(2) {
            if let Ok((st, code)) = r.al().await
                && st != 0x08
            {
                seen = Some((st, code, r.clock.elapsed() - stop));
                break;
            }
            r.clock.sleep(Duration::from_millis(1)).await;
        }
        match seen {
            Some((0x14, 0x001B, t)) => Outcome::Pass(format!(
                "SAFE-OP + error, 0x001B after {} ms (watchdog {} ms)",
                t.as_millis(),
                wd_time.as_millis()
            )),
            Some((st, code, _)) => Outcome::Fail(al_text(st, code)),
            None => Outcome::Fail(format!(
                "still OP {} ms after the outputs stopped (watchdog {} ms)",
                (r.clock.elapsed() - stop).as_millis(),
                wd_time.as_millis()
            )),
        }
    };
    r.record(ids[1].0, "ETG.1000.4 6.7, ETG.1000.6 Table 10", ids[1].1, o);

    let o = if !in_op {
        Outcome::NotApplicable("OP was not reached".into())
    } else {
        // Fresh outputs first (the watchdog is re-armed by them), then the
        // acknowledge, then OP, outputs flowing all along.
        for _ in 0..5 {
            send(r).await;
            r.clock.sleep(Duration::from_millis(1)).await;
        }
        let _ = r.write(0x0120, &0x14u16.to_le_bytes()).await;
        for _ in 0..5 {
            send(r).await;
            r.clock.sleep(Duration::from_millis(1)).await;
        }
        let _ = r.write(0x0120, &0x08u16.to_le_bytes()).await;
        let t0 = r.clock.elapsed();
        let mut last = (0, 0);
        loop {
            send(r).await;
            if let Ok(s) = r.al().await {
                last = s;
                if s.0 == 0x08 {
                    break Outcome::Pass("OP".into());
                }
            }
            if (r.clock.elapsed() - t0) > Duration::from_secs(3) {
                break Outcome::Fail(al_text(last.0, last.1));
            }
            r.clock.sleep(Duration::from_millis(1)).await;
        }
    };
    r.record(ids[2].0, "ETG.1000.6 6.4.1.3", ids[2].1, o);
    let _ = r.request(0x04).await;
    let _ = r.request(0x02).await;
}

// ------------------------------------------------------------ mailbox --

/// Sends a raw mailbox and waits for one answer; `None` when nothing came
/// within `wait`.
async fn exchange_raw(
    c: &mut MailboxClient<'_>,
    kind: MailboxType,
    counter: u8,
    header_len: u16,
    payload: &[u8],
    wait: Duration,
) -> Result<Option<crate::mailbox::Message>, String> {
    let size = c.max_payload() + ecat_slave::wire::mailbox::HEADER_LEN;
    let mut buf = vec![0u8; size];
    buf[0..2].copy_from_slice(&header_len.to_le_bytes());
    buf[5] = u8::from(kind) | (counter << 4);
    let n = payload.len().min(size - 6);
    buf[6..6 + n].copy_from_slice(&payload[..n]);
    let saved = c.timeout;
    // Whatever already waits (an Emergency after a refused state change)
    // is not the answer: keep Emergencies, drop the rest.
    c.timeout = Duration::ZERO;
    for _ in 0..8 {
        match c.receive().await {
            Ok(m) => keep_emergency(c, m),
            Err(_) => break,
        }
    }
    c.timeout = saved;
    c.write_buffer(&buf).await.map_err(|e| e.to_string())?;
    c.timeout = wait;
    let mut answer = None;
    for _ in 0..8 {
        match c.receive().await {
            Ok(m) if is_emergency(&m) => keep_emergency(c, m),
            Ok(m) => {
                answer = Some(Ok(m));
                break;
            }
            Err(e) => {
                answer = Some(Err(e));
                break;
            }
        }
    }
    c.timeout = saved;
    match answer {
        Some(Ok(m)) => Ok(Some(m)),
        None | Some(Err(ClientError::Timeout(_))) => Ok(None),
        Some(Err(e)) => Err(e.to_string()),
    }
}

fn is_emergency(m: &crate::mailbox::Message) -> bool {
    m.kind == MailboxType::CoE && m.payload.get(1).is_some_and(|b| b >> 4 == 1)
}

fn keep_emergency(c: &mut MailboxClient<'_>, m: crate::mailbox::Message) {
    if is_emergency(&m) {
        c.emergencies.push(m.payload);
    }
}

fn mailbox_error(m: &crate::mailbox::Message) -> Option<u16> {
    if m.kind != MailboxType::Error {
        return None;
    }
    WireMailboxError::new_checked(&m.payload[..])
        .ok()
        .map(|e| u16::from(e.detail()))
}

/// An SDO upload request of `index:sub` with its CoE header.
fn upload_request(index: u16, sub: u8) -> Vec<u8> {
    let req = SdoRequest::InitiateUpload {
        index,
        sub,
        complete_access: false,
    };
    let mut p = vec![0u8; 2 + req.buffer_len()];
    CoeHeader::emit_into(&mut p[..2], 0, CoeService::SdoRequest);
    let _ = req.emit(&mut p[2..]);
    p
}

async fn mailbox_checks(r: &mut Run<'_>) {
    let ids = [
        "mailbox.unsupported-protocol",
        "mailbox.invalid-size",
        "mailbox.size-too-short",
        "mailbox.repeated-counter",
        "mailbox.repeat-request",
        "mailbox.empty-after-init",
    ];
    let Some(mut c) = r.client() else {
        for id in ids {
            r.record(
                id,
                "ETG.1000.6 5.3",
                "mailbox behaviour",
                Outcome::NotApplicable("no mailbox in the SII".into()),
            );
        }
        return;
    };
    let wait = Duration::from_millis(300);
    let protocols = ecat_esi::inspect::inspect(&r.sii)
        .map(|i| i.mailbox_protocols)
        .unwrap_or(0);
    // A protocol the SII does not announce: SoE (bit 4), else VoE, AoE.
    let (kind, _) = [
        (MailboxType::SoE, 0x0010u16),
        (MailboxType::VoE, 0x0020),
        (MailboxType::AoE, 0x0001),
    ]
    .into_iter()
    .find(|(_, b)| protocols & b == 0)
    .unwrap_or((MailboxType::VoE, 0x0020));
    let o = match exchange_raw(&mut c, kind, 1, 4, &[0, 0, 0, 0], wait).await {
        Ok(Some(m)) if mailbox_error(&m) == Some(0x0002) => {
            Outcome::Pass(format!("{kind:?}: mailbox error 0x0002"))
        }
        Ok(Some(m)) => Outcome::Fail(format!("{kind:?}: {:?} {:02x?}", m.kind, m.payload)),
        Ok(None) => Outcome::Fail(format!("{kind:?}: no answer")),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        ids[0],
        "ETG.1000.6 5.3.3, Table 29",
        "a protocol the SII does not announce gets a mailbox error reply 0x0002 (unsupported protocol)",
        o,
    );

    let too_long = c.max_payload() as u16 + 1;
    let o = match exchange_raw(
        &mut c,
        MailboxType::CoE,
        2,
        too_long,
        &upload_request(0x1000, 0),
        wait,
    )
    .await
    {
        Ok(Some(m)) if mailbox_error(&m) == Some(0x0008) => {
            Outcome::Pass("mailbox error 0x0008".into())
        }
        Ok(Some(m)) => Outcome::Fail(format!("{:?} {:02x?}", m.kind, m.payload)),
        Ok(None) => Outcome::Fail("no answer".into()),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        ids[1],
        "ETG.1000.6 5.3.3, Table 29",
        "header length beyond the mailbox: mailbox error reply 0x0008 (invalid size)",
        o,
    );

    let o = match exchange_raw(&mut c, MailboxType::CoE, 3, 1, &[0], wait).await {
        Ok(Some(m)) if mailbox_error(&m) == Some(0x0006) => {
            Outcome::Pass("mailbox error 0x0006".into())
        }
        Ok(Some(m)) => Outcome::Fail(format!("{:?} {:02x?}", m.kind, m.payload)),
        Ok(None) => Outcome::Fail("no answer".into()),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        ids[2],
        "ETG.1000.6 5.3.3, Table 29",
        "a CoE message of 1 byte (shorter than its header): mailbox error reply 0x0006 (size too short)",
        o,
    );

    let coe = protocols & 0x0004 != 0;
    let req = upload_request(0x1000, 0);
    let o = if !coe {
        Outcome::NotApplicable("no CoE announced".into())
    } else {
        let first = exchange_raw(&mut c, MailboxType::CoE, 4, req.len() as u16, &req, wait).await;
        let second = exchange_raw(&mut c, MailboxType::CoE, 4, req.len() as u16, &req, wait).await;
        match (first, second) {
            (Ok(Some(_)), Ok(None)) => Outcome::Pass("answered once".into()),
            (Ok(Some(_)), Ok(Some(m))) => {
                Outcome::Fail(format!("executed twice: {:?} {:02x?}", m.kind, m.payload))
            }
            (Ok(None), _) => Outcome::Fail("the first request got no answer".into()),
            (Err(e), _) | (_, Err(e)) => Outcome::Fail(e),
        }
    };
    r.record(
        ids[3],
        "ETG.1000.6 5.3.2",
        "a mailbox repeated with the same counter (1-7) is not executed again",
        o,
    );

    let o = if !coe {
        Outcome::NotApplicable("no CoE announced".into())
    } else {
        match exchange_raw(&mut c, MailboxType::CoE, 5, req.len() as u16, &req, wait).await {
            Ok(Some(m)) => match c.repeat().await {
                Ok(again) if again == m => Outcome::Pass("the last answer again".into()),
                Ok(again) => Outcome::Fail(format!("{again:?}, first {m:?}")),
                Err(e) => Outcome::Fail(e.to_string()),
            },
            Ok(None) => Outcome::Fail("no answer to repeat".into()),
            Err(e) => Outcome::Fail(e),
        }
    };
    r.record(
        ids[4],
        "ETG.1000.4 8.2.2.3 (SM repeat), ETG.1000.6 5.3.2",
        "toggling the SM1 repeat request gives the last mailbox answer again, acknowledged in 0x080F",
        o,
    );

    // After INIT -> PRE-OP nothing from before may wait in SM1.
    let _ = r.request(0x01).await;
    let _ = r.request(0x02).await;
    r.clock.sleep(Duration::from_millis(20)).await;
    let o = match r.read::<u8>(0x080D).await {
        Ok(st) if st & 0x08 == 0 => Outcome::Pass("SM1 empty".into()),
        Ok(st) => {
            let m = c.receive().await;
            Outcome::Fail(format!(
                "SM1 status {st:#04x}: a message waits: {}",
                match m {
                    Ok(m) => format!("{:?} {:02x?}", m.kind, m.payload),
                    Err(e) => e.to_string(),
                }
            ))
        }
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        ids[5],
        "ETG.1000.6 5.3, 6.4.1 (INIT: mailbox off)",
        "after INIT -> PRE-OP the slave's mailbox holds nothing from before (no stale answer or Emergency)",
        o,
    );
    r.emergencies.extend(c.emergencies);
}

// ---------------------------------------------------------------- CoE --

/// Whether `access` (SDO Information entry access bits) allows reading /
/// writing in PRE-OP.
fn readable(access: u16) -> bool {
    access & 0x0001 != 0
}
fn writable(access: u16) -> bool {
    access & 0x0008 != 0
}

async fn coe_checks(r: &mut Run<'_>, esi: Option<&str>) {
    let protocols = ecat_esi::inspect::inspect(&r.sii)
        .map(|i| i.mailbox_protocols)
        .unwrap_or(0);
    let coe_details = ecat_esi::inspect::inspect(&r.sii)
        .ok()
        .and_then(|i| i.general.map(|(g, _)| g.coe_details))
        .unwrap_or(0);
    let ids: [(&'static str, &'static str, &'static str); 10] = [
        (
            "coe.sdo-info",
            "ETG.1000.6 5.6.3",
            "SDO Information: OD list, every object and entry described",
        ),
        (
            "coe.upload-readable",
            "ETG.1000.6 5.6.2.4, 5.6.3.6",
            "every entry described as readable uploads",
        ),
        (
            "coe.rewrite-writable",
            "ETG.1000.6 5.6.2.1",
            "every entry writable in PRE-OP accepts its own value",
        ),
        (
            "coe.abort-service",
            "ETG.1000.6 5.6.2.7",
            "Abort SDO Transfer travels as CoE service 2 (SDO request), command 0x80",
        ),
        (
            "coe.abort-unknown-object",
            "ETG.1000.6 Table 40",
            "upload of an absent object aborts 0x06020000",
        ),
        (
            "coe.abort-unknown-subindex",
            "ETG.1000.6 Table 40",
            "upload of an absent subindex aborts 0x06090011",
        ),
        (
            "coe.abort-read-only",
            "ETG.1000.6 Table 40",
            "download to a read-only entry aborts 0x06010002",
        ),
        (
            "coe.abort-length",
            "ETG.1000.6 Table 40",
            "download of one byte too many aborts 0x06070010 or 0x06070012",
        ),
        (
            "coe.complete-access",
            "ETG.1000.6 5.6.2.1.2, 5.6.2.4.2",
            "complete access (SII CoE details bit 5): 0x1018 whole = its entries one by one",
        ),
        (
            "coe.sdo-info-esi",
            "ETG.2000 (Dictionary), ETG.1000.6 5.6.3.3",
            "the OD list holds the objects of the ESI's dictionary, no more, no fewer",
        ),
    ];
    let emergency_id = (
        "coe.emergency-framing",
        "ETG.1000.6 5.6.4",
        "every Emergency received is CoE service 1 with 8 data bytes (error code, error register, 5 bytes)",
    );
    let client = if protocols & 0x0004 != 0 {
        r.client()
    } else {
        None
    };
    let Some(mut c) = client else {
        for (id, reference, what) in ids.into_iter().chain([emergency_id]) {
            r.record(
                id,
                reference,
                what,
                Outcome::NotApplicable("no CoE announced".into()),
            );
        }
        return;
    };

    // SDO Information.
    let mut entries: Vec<EntryInfo> = Vec::new();
    let mut list = Vec::new();
    let o = if coe_details & 0x02 == 0 {
        Outcome::NotApplicable("SDO Information not announced (SII CoE details bit 1)".into())
    } else {
        match sdo_info::od_list(&mut c, sdo_info::list_type::ALL).await {
            Err(e) => Outcome::Fail(format!("OD list: {e}")),
            Ok(l) => {
                list = l;
                let mut problems = Vec::new();
                for &index in &list {
                    match sdo_info::object_description(&mut c, index).await {
                        Err(e) => problems.push(format!("{index:#06x}: {e}")),
                        Ok(obj) => {
                            for sub in 0..=obj.max_sub {
                                match sdo_info::entry_description(&mut c, index, sub, 0).await {
                                    Ok(e) => entries.push(e),
                                    // Arrays and records may have gaps.
                                    Err(e) if e.abort_code() == Some(0x0609_0011) => {}
                                    Err(e) => problems.push(format!("{index:#06x}:{sub:02x}: {e}")),
                                }
                            }
                        }
                    }
                }
                if problems.is_empty() {
                    Outcome::Pass(format!(
                        "{} objects, {} entries described",
                        list.len(),
                        entries.len()
                    ))
                } else {
                    Outcome::Fail(problems.join("; "))
                }
            }
        }
    };
    r.record(ids[0].0, ids[0].1, ids[0].2, o);

    // Every readable entry uploads.
    let mut values: Vec<(u16, u8, Vec<u8>, u16)> = Vec::new();
    let o = if entries.is_empty() {
        Outcome::NotApplicable("no entry descriptions".into())
    } else {
        let mut failed = Vec::new();
        for e in entries.iter().filter(|e| readable(e.access)) {
            match c.sdo_upload(e.index, e.sub, false).await {
                Ok(v) => values.push((e.index, e.sub, v, e.access)),
                Err(err) => failed.push(format!("{:#06x}:{:02x}: {err}", e.index, e.sub)),
            }
        }
        if failed.is_empty() {
            Outcome::Pass(format!("{} entries read", values.len()))
        } else {
            Outcome::Fail(format!(
                "{} of {} failed: {}",
                failed.len(),
                failed.len() + values.len(),
                failed.join("; ")
            ))
        }
    };
    r.record(ids[1].0, ids[1].1, ids[1].2, o);

    // Every entry writable in PRE-OP takes its own value (0x1010/0x1011
    // need their signatures instead).
    let o = if values.is_empty() {
        Outcome::NotApplicable("no entries read".into())
    } else {
        let (mut failed, mut refused) = (Vec::new(), Vec::new());
        let mut n = 0;
        for (index, sub, v, access) in &values {
            if !writable(*access)
                || matches!(index, 0x1010 | 0x1011)
                || *sub == 0 && *index >= 0x1600 && *index < 0x1C00
            {
                continue;
            }
            n += 1;
            match c.sdo_download(*index, *sub, false, v).await {
                Ok(()) => {}
                // Refusals the device may give for reasons of its own: a
                // lock (0x06010000), a value its rules exclude now
                // (0x0609003x), local control or device state (0x0800002x).
                Err(err)
                    if err.abort_code().is_some_and(|a| {
                        a == 0x0601_0000
                            || (0x0609_0030..=0x0609_0036).contains(&a)
                            || (0x0800_0020..=0x0800_0022).contains(&a)
                    }) =>
                {
                    refused.push(format!(
                        "{index:#06x}:{sub:02x} {:#010x}",
                        err.abort_code().unwrap_or(0)
                    ));
                }
                Err(err) => failed.push(format!("{index:#06x}:{sub:02x} = {v:02x?}: {err}")),
            }
        }
        let note = if refused.is_empty() {
            String::new()
        } else {
            format!(
                "; refused by the device's own rules (allowed): {}",
                refused.join(", ")
            )
        };
        if failed.is_empty() {
            Outcome::Pass(format!("{} entries rewritten{note}", n - refused.len()))
        } else {
            Outcome::Fail(format!("{}{note}", failed.join("; ")))
        }
    };
    r.record(ids[2].0, ids[2].1, ids[2].2, o);

    // An index not in the list (or 0x5FFF without a list).
    let absent = (0x2000u16..0x6000)
        .rev()
        .find(|i| !list.contains(i))
        .unwrap_or(0x5FFF);
    let req = upload_request(absent, 0);
    let o = match exchange_raw(
        &mut c,
        MailboxType::CoE,
        0,
        req.len() as u16,
        &req,
        Duration::from_millis(500),
    )
    .await
    {
        Ok(Some(m)) if m.kind == MailboxType::CoE && m.payload.len() >= 3 => {
            let service = m.payload[1] >> 4;
            let cmd = m.payload[2];
            if service == 2 && cmd == 0x80 {
                Outcome::Pass("service 2, command 0x80".into())
            } else {
                Outcome::Fail(format!("service {service}, command {cmd:#04x}"))
            }
        }
        Ok(Some(m)) => Outcome::Fail(format!("{:?} {:02x?}", m.kind, m.payload)),
        Ok(None) => Outcome::Fail("no answer".into()),
        Err(e) => Outcome::Fail(e),
    };
    r.record(ids[3].0, ids[3].1, ids[3].2, o);

    let abort = |res: Result<Vec<u8>, ClientError>, want: &[u32]| match res {
        Err(e) if e.abort_code().is_some_and(|c| want.contains(&c)) => {
            Outcome::Pass(format!("{:#010x}", e.abort_code().unwrap_or(0)))
        }
        Err(e) => Outcome::Fail(e.to_string()),
        Ok(v) => Outcome::Fail(format!("no abort: {v:02x?}")),
    };
    let o = abort(c.sdo_upload(absent, 0, false).await, &[0x0602_0000]);
    r.record(
        ids[4].0,
        ids[4].1,
        &format!("{} ({absent:#06x})", ids[4].2),
        o,
    );

    let max_1018 = c
        .sdo_upload(0x1018, 0, false)
        .await
        .ok()
        .and_then(|v| v.first().copied())
        .unwrap_or(4);
    let o = abort(
        c.sdo_upload(0x1018, max_1018.saturating_add(1), false)
            .await,
        &[0x0609_0011],
    );
    r.record(
        ids[5].0,
        ids[5].1,
        &format!("{} (0x1018:{:02x})", ids[5].2, max_1018.saturating_add(1)),
        o,
    );

    let o = abort(
        c.sdo_download(0x1018, 1, false, &[0, 0, 0, 0])
            .await
            .map(|()| Vec::new()),
        &[0x0601_0002],
    );
    r.record(ids[6].0, ids[6].1, &format!("{} (0x1018:01)", ids[6].2), o);

    let target = values.iter().find(|(i, s, v, a)| {
        writable(*a) && (1..=3).contains(&v.len()) && *s != 0 && !matches!(i, 0x1010 | 0x1011)
    });
    let o = match target {
        None => Outcome::NotApplicable("no writable entry of 1-3 bytes".into()),
        Some((index, sub, v, _)) => {
            let mut long = v.clone();
            long.push(0);
            let res = c
                .sdo_download(*index, *sub, false, &long)
                .await
                .map(|()| Vec::new());
            match abort(res, &[0x0607_0010, 0x0607_0012]) {
                Outcome::Pass(s) => Outcome::Pass(format!("{index:#06x}:{sub:02x}: {s}")),
                Outcome::Fail(s) => Outcome::Fail(format!("{index:#06x}:{sub:02x}: {s}")),
                other => other,
            }
        }
    };
    r.record(ids[7].0, ids[7].1, ids[7].2, o);

    let o = if coe_details & 0x20 == 0 {
        Outcome::NotApplicable("complete access not announced (SII CoE details bit 5)".into())
    } else {
        let whole = c.sdo_upload(0x1018, 0, true).await;
        let mut single = vec![max_1018, 0];
        for sub in 1..=max_1018 {
            if let Ok(v) = c.sdo_upload(0x1018, sub, false).await {
                single.extend(v);
            }
        }
        match whole {
            Ok(w) if w == single => Outcome::Pass(format!("{} bytes", w.len())),
            Ok(w) => Outcome::Fail(format!("complete {w:02x?}, entries {single:02x?}")),
            Err(e) => Outcome::Fail(e.to_string()),
        }
    };
    r.record(ids[8].0, ids[8].1, ids[8].2, o);

    let o = match (esi, list.is_empty()) {
        (None, _) => Outcome::NotApplicable("no ESI given (--esi FILE)".into()),
        (Some(_), true) => Outcome::NotApplicable("no OD list".into()),
        (Some(xml), false) => {
            match esi_objects(xml, &detected_modules(&mut c).await.unwrap_or_default()) {
                Err(e) => Outcome::Fail(format!("the ESI cannot be read: {e}")),
                Ok(esi) => {
                    let missing: Vec<String> = esi
                        .iter()
                        .filter(|i| !list.contains(i))
                        .map(|i| format!("{i:#06x}"))
                        .collect();
                    let extra: Vec<String> = list
                        .iter()
                        .filter(|i| !esi.contains(i))
                        .map(|i| format!("{i:#06x}"))
                        .collect();
                    if missing.is_empty() && extra.is_empty() {
                        Outcome::Pass(format!("{} objects", list.len()))
                    } else {
                        Outcome::Fail(format!(
                            "in the ESI only: [{}]; in the OD list only: [{}]",
                            missing.join(", "),
                            extra.join(", ")
                        ))
                    }
                }
            }
        }
    };
    r.record(ids[9].0, ids[9].1, ids[9].2, o);

    r.emergencies.extend(std::mem::take(&mut c.emergencies));
    let all = std::mem::take(&mut r.emergencies);
    let o = if all.is_empty() {
        Outcome::NotApplicable("no Emergency arrived during the checks".into())
    } else {
        let bad: Vec<String> = all
            .iter()
            .filter(|p| p.len() != 10 || p[1] >> 4 != 1)
            .map(|p| format!("{p:02x?}"))
            .collect();
        if bad.is_empty() {
            Outcome::Pass(format!("{} Emergency message(s) well formed", all.len()))
        } else {
            Outcome::Fail(bad.join("; "))
        }
    };
    r.record(emergency_id.0, emergency_id.1, emergency_id.2, o);
}

/// The module idents of a modular device's detected module list (0xF050),
/// or `None` for a device without one.
async fn detected_modules(c: &mut MailboxClient<'_>) -> Option<Vec<u32>> {
    let n = c.sdo_upload(0xF050, 0, false).await.ok()?;
    let mut idents = Vec::new();
    for s in 1..=n.first().copied().unwrap_or(0) {
        let v = c.sdo_upload(0xF050, s, false).await.ok()?;
        idents.push(u32::from_le_bytes(v.get(..4)?.try_into().ok()?));
    }
    Some(idents)
}

/// An ESI's `Slots` increments and its module types.
struct EsiModules<'a> {
    /// `SlotIndexIncrement`.
    index_step: u16,
    /// `SlotPdoIncrement`.
    pdo_step: u16,
    /// `(ModuleIdent, Module)`.
    modules: Vec<(u32, &'a ecat_esi::xml::Element)>,
}

/// The ESI's `Slots` increments (index, PDO) and its modules by ident.
fn esi_modules(root: &ecat_esi::xml::Element) -> Result<EsiModules<'_>, String> {
    let slots = root
        .path("Descriptions/Devices/Device/Slots")
        .ok_or("no Device/Slots")?;
    let inc = |name: &str| {
        slots
            .attr(name)
            .and_then(ecat_esi::xml::hex_dec)
            .and_then(|v| u16::try_from(v).ok())
            .ok_or(format!("Slots without a valid {name}"))
    };
    let (index_step, pdo_step) = (inc("SlotIndexIncrement")?, inc("SlotPdoIncrement")?);
    let modules = root
        .path("Descriptions/Modules")
        .ok_or("no Descriptions/Modules")?
        .children_named("Module")
        .map(|m| {
            m.path("Type")
                .and_then(|t| t.attr("ModuleIdent"))
                .and_then(ecat_esi::xml::hex_dec)
                .and_then(|v| u32::try_from(v).ok())
                .map(|id| (id, m))
                .ok_or_else(|| "a Module without a valid ModuleIdent".to_string())
        })
        .collect::<Result<_, _>>()?;
    Ok(EsiModules {
        index_step,
        pdo_step,
        modules,
    })
}

/// The ESI module with `ident`.
fn esi_module<'a>(
    modules: &[(u32, &'a ecat_esi::xml::Element)],
    ident: u32,
) -> Result<&'a ecat_esi::xml::Element, String> {
    modules
        .iter()
        .find(|(id, _)| *id == ident)
        .map(|(_, m)| *m)
        .ok_or(format!("no Module with ident {ident:#010x}"))
}

/// The PDOs the ESI's modules give a modular device with `idents` in its
/// slots (in order): `(PDO index, mapping entries index << 16 | sub << 8 |
/// bits)`, moved into each slot by `SlotPdoIncrement` and
/// `SlotIndexIncrement` (ETG.2000 `Slots`, ETG.5001).
fn esi_module_pdos(xml: &str, idents: &[u32]) -> Result<Vec<(u16, Vec<u32>)>, String> {
    let root = ecat_esi::xml::parse(xml).map_err(|e| e.to_string())?;
    let EsiModules {
        index_step,
        pdo_step,
        modules,
    } = esi_modules(&root)?;
    let mut out = Vec::new();
    for (slot, ident) in idents.iter().enumerate() {
        let slot = u16::try_from(slot).map_err(|_| "too many slots")?;
        let m = esi_module(&modules, *ident)?;
        for pdo in m.children_named("RxPdo").chain(m.children_named("TxPdo")) {
            let hex = |e: &ecat_esi::xml::Element, p: &str| {
                e.text_at(p)
                    .and_then(ecat_esi::xml::hex_dec)
                    .and_then(|v| u32::try_from(v).ok())
            };
            let index = hex(pdo, "Index").ok_or("a module PDO without an Index")?;
            let mut entries = Vec::new();
            for e in pdo.children_named("Entry") {
                let i = hex(e, "Index").ok_or("a PDO entry without an Index")?;
                let sub = hex(e, "SubIndex").unwrap_or(0);
                let bits = hex(e, "BitLen").ok_or("a PDO entry without a BitLen")?;
                let i = if i == 0 {
                    0
                } else {
                    i + u32::from(index_step) * u32::from(slot)
                };
                entries.push((i << 16) | (sub << 8) | bits);
            }
            let moved = index as u16 + pdo_step * slot;
            out.push((moved, entries));
        }
    }
    Ok(out)
}

/// The object indices of an ESI's dictionary (first device); of a modular
/// device also its modules' objects for the modules `idents` in its slots.
fn esi_objects(xml: &str, idents: &[u32]) -> Result<Vec<u16>, String> {
    let root = ecat_esi::xml::parse(xml).map_err(|e| e.to_string())?;
    let device = root
        .path("Descriptions/Devices/Device")
        .ok_or("no Descriptions/Devices/Device")?;
    let objects = device
        .path("Profile/Dictionary/Objects")
        .ok_or("no Profile/Dictionary/Objects")?;
    let index_of = |o: &ecat_esi::xml::Element| {
        o.text_at("Index")
            .and_then(ecat_esi::xml::hex_dec)
            .and_then(|v| u16::try_from(v).ok())
            .ok_or_else(|| "an Object without a valid Index".to_string())
    };
    let mut out: Vec<u16> = objects
        .children_named("Object")
        .map(index_of)
        .collect::<Result<_, _>>()?;
    if !idents.is_empty() {
        let EsiModules {
            index_step,
            pdo_step,
            modules,
        } = esi_modules(&root)?;
        for (slot, ident) in idents.iter().enumerate() {
            let slot = u16::try_from(slot).map_err(|_| "too many slots")?;
            let m = esi_module(&modules, *ident)?;
            let objs = m
                .path("Profile/Dictionary/Objects")
                .ok_or("a Module without Profile/Dictionary/Objects")?;
            for o in objs.children_named("Object") {
                let i = index_of(o)?;
                let step = if (0x1600..=0x1BFF).contains(&i) {
                    pdo_step
                } else {
                    index_step
                };
                out.push(i + step * slot);
            }
        }
        out.sort_unstable();
    }
    Ok(out)
}

// ---------------------------------------------------------------- FoE --

async fn foe_checks(r: &mut Run<'_>, foe_opts: Option<&FoeOptions>) {
    let ids = [
        (
            "foe.boot",
            "ETG.1000.6 6.4.1, ETG.2010 2.2",
            "INIT -> BOOT with the SII's bootstrap mailbox",
        ),
        (
            "foe.write",
            "ETG.1000.6 5.8",
            "a file written in BOOT is acknowledged packet by packet",
        ),
        (
            "foe.wrong-password",
            "ETG.1000.6 5.8",
            "a write request with a wrong password is refused with an FoE error",
        ),
    ];
    let (Some(opts), Some(boot)) = (foe_opts, r.bootstrap) else {
        let why = if foe_opts.is_none() {
            "no --foe-file given"
        } else {
            "no bootstrap mailbox in the SII"
        };
        for (id, reference, what) in ids {
            r.record(id, reference, what, Outcome::NotApplicable(why.into()));
        }
        return;
    };
    let o = match foe::enter_boot_geometry(r.md, r.station, boot).await {
        Ok(()) => Outcome::Pass("BOOT".into()),
        Err(e) => Outcome::Fail(e.to_string()),
    };
    let in_boot = matches!(o, Outcome::Pass(_));
    r.record(ids[0].0, ids[0].1, ids[0].2, o);
    let mut c = MailboxClient::new(r.md, r.station, boot);
    c.timeout = Duration::from_secs(2);
    let o = if in_boot {
        match foe::write(
            &mut c,
            "conformance.bad",
            opts.password ^ 0xFFFF_FFFF,
            &opts.file,
            |_, _| {},
        )
        .await
        {
            Err(e) if e.foe_code().is_some() => Outcome::Pass(e.to_string()),
            Err(e) => Outcome::Fail(e.to_string()),
            Ok(()) => Outcome::Fail("accepted".into()),
        }
    } else {
        Outcome::NotApplicable("not in BOOT".into())
    };
    r.record(ids[2].0, ids[2].1, ids[2].2, o);
    let o = if in_boot {
        match foe::write(&mut c, &opts.name, opts.password, &opts.file, |_, _| {}).await {
            Ok(()) => Outcome::Pass(format!("{} bytes", opts.file.len())),
            Err(e) => Outcome::Fail(e.to_string()),
        }
    } else {
        Outcome::NotApplicable("not in BOOT".into())
    };
    // Report in the documented order.
    let wrong = r.checks.pop();
    r.record(ids[1].0, ids[1].1, ids[1].2, o);
    if let Some(w) = wrong {
        r.checks.push(w);
    }
    let _ = foe::request_state(r.md, r.station, 0x11).await;
    // Back to the standard mailbox.
    if let Some(g) = r.mailbox {
        for (reg, b) in g.sm_registers() {
            let _ = r.write(reg, &b).await;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report() -> Report {
        Report {
            slave: "slave 0 (0x1000 A<B>)".into(),
            checks: vec![
                CheckResult {
                    id: "coe.abort-service",
                    group: Group::Coe,
                    reference: "ETG.1000.6 5.6.2.7",
                    expected: "service 2".into(),
                    observed: "service 3 & \"x\"".into(),
                    verdict: Verdict::Fail,
                },
                CheckResult {
                    id: "esc.information",
                    group: Group::Esc,
                    reference: "ETG.1000.4 6.1.1",
                    expected: "readable".into(),
                    observed: "type 0x11".into(),
                    verdict: Verdict::Pass,
                },
                CheckResult {
                    id: "foe.boot",
                    group: Group::Foe,
                    reference: "ETG.1000.6",
                    expected: "BOOT".into(),
                    observed: "no --foe-file given".into(),
                    verdict: Verdict::NotApplicable,
                },
            ],
        }
    }

    #[test]
    fn groups_parse_by_name_and_unknown_ones_are_named() {
        assert_eq!(Group::parse("CoE"), Ok(Group::Coe));
        assert_eq!(Group::parse(" state "), Ok(Group::State));
        let e = Group::parse("dc").unwrap_err();
        assert!(
            e.contains("'dc'") && e.contains("esc, sii, state, mailbox, coe, foe"),
            "{e}"
        );
    }

    #[test]
    fn junit_counts_failures_and_skips_and_escapes_text() {
        let x = report().to_junit();
        assert!(
            x.contains("tests=\"3\" failures=\"1\" skipped=\"1\""),
            "{x}"
        );
        assert!(
            x.contains("name=\"conformance slave 0 (0x1000 A&lt;B&gt;)\""),
            "{x}"
        );
        assert!(
            x.contains("<failure message=\"service 3 &amp; &quot;x&quot;\">"),
            "{x}"
        );
        assert!(
            x.contains("<testcase classname=\"conformance.esc\" name=\"esc.information\"/>"),
            "{x}"
        );
        assert!(
            x.contains("<skipped message=\"no --foe-file given\"/>"),
            "{x}"
        );
        assert_eq!(xml_escape("a\u{1}b\tc"), "a b\tc");
    }

    #[test]
    fn json_has_counts_and_every_check() {
        let v: serde_json::Value = serde_json::from_str(&report().to_json()).unwrap();
        assert_eq!(v["failed"], 1);
        assert_eq!(v["passed"], 1);
        assert_eq!(v["not_applicable"], 1);
        assert_eq!(v["checks"][0]["verdict"], "fail");
        assert_eq!(v["checks"][2]["group"], "foe");
    }

    #[test]
    fn text_table_names_verdicts_and_totals() {
        let t = report().to_text();
        assert!(t.starts_with("conformance of slave 0"), "{t}");
        assert!(t.contains("FAIL  coe.abort-service"), "{t}");
        assert!(t.contains("1 passed, 1 failed, 1 not applicable"), "{t}");
    }

    #[test]
    fn esi_objects_come_from_the_dictionary_of_the_first_device() {
        let xml = ecat_esi::esi::generate(&pam_199_p_etc::DEVICE).unwrap();
        let objects = esi_objects(std::str::from_utf8(&xml).unwrap(), &[]).unwrap();
        assert!(objects.contains(&0x1018) && objects.contains(&0x800D));
        assert!(esi_objects("<EtherCATInfo/>", &[]).is_err());
    }
}
