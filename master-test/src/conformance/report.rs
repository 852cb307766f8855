//! The report of a conformance run and its renderers: text table,
//! JUnit XML, JSON.

use super::*;

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
pub(super) fn xml_escape(s: &str) -> String {
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
