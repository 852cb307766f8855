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

mod coe;
mod esc;
mod esi;
mod foe_checks;
mod mailbox;
mod report;
mod run;
mod sii;
mod state;

use coe::*;
use esc::*;
use esi::*;
use foe_checks::*;
use mailbox::*;
use run::*;
use sii::*;
use state::*;

pub use report::Report;
#[cfg(test)]
use report::xml_escape;
pub use run::run;

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
