//! The run harness: results collected per check, AL requests and
//! acknowledges, the slave returned to PRE-OP.

use super::*;
use crate::registers;

/// Collects results while the checks run.
pub(super) struct Run<'a> {
    pub(super) md: &'a MainDevice<'a>,
    pub(super) station: u16,
    pub(super) sii: Vec<u8>,
    pub(super) mailbox: Option<MailboxGeometry>,
    pub(super) bootstrap: Option<MailboxGeometry>,
    /// ESC configuration 0x0141 bit 0: the ESC runs the AL state machine
    /// itself, copying AL control into AL status (Beckhoff ESC datasheet,
    /// section II, register 0x0141; an ESC-only device without a
    /// microcontroller). It refuses nothing, so the state group checks
    /// that promise instead of refusals.
    pub(super) device_emulation: bool,
    pub(super) checks: Vec<CheckResult>,
    pub(super) group: Group,
    pub(super) emergencies: Vec<Vec<u8>>,
    pub(super) clock: Clock,
}

/// A check's outcome before it is recorded.
pub(super) enum Outcome {
    Pass(String),
    Fail(String),
    NotApplicable(String),
}

impl<'a> Run<'a> {
    pub(super) fn record(
        &mut self,
        id: &'static str,
        reference: &'static str,
        expected: &str,
        o: Outcome,
    ) {
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

    pub(super) fn client(&self) -> Option<MailboxClient<'a>> {
        self.mailbox.map(|g| {
            let mut c = MailboxClient::new(self.md, self.station, g);
            c.lenient_abort_service = true;
            c.timeout = Duration::from_secs(1);
            c
        })
    }

    pub(super) async fn read<T: ethercrab::EtherCrabWireReadSized>(
        &self,
        reg: u16,
    ) -> Result<T, String> {
        Command::fprd(self.station, reg)
            .with_wkc(1)
            .receive::<T>(self.md)
            .await
            .map_err(|e| format!("FPRD {reg:#06x}: {e}"))
    }

    pub(super) async fn write(&self, reg: u16, data: &[u8]) -> Result<(), String> {
        Command::fpwr(self.station, reg)
            .with_wkc(1)
            .send(self.md, data)
            .await
            .map_err(|e| format!("FPWR {reg:#06x}: {e}"))
    }

    /// AL status (0x0130) and AL status code (0x0134).
    pub(super) async fn al(&self) -> Result<(u16, u16), String> {
        Ok((
            self.read::<u16>(registers::AL_STATUS).await?,
            self.read::<u16>(registers::AL_STATUS_CODE).await?,
        ))
    }

    /// Writes AL control `control` and waits until the state it names is
    /// reached or the error flag is set (3 s); returns the final status and
    /// code.
    pub(super) async fn request(&self, control: u16) -> Result<(u16, u16), String> {
        self.write(registers::AL_CONTROL, &control.to_le_bytes())
            .await?;
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
    pub(super) async fn acknowledge(&self, state: u16) -> Result<(u16, u16), String> {
        self.write(registers::AL_CONTROL, &(state | 0x10).to_le_bytes())
            .await?;
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
    pub(super) async fn back_to_preop(&self) {
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

pub(super) fn state_name(st: u16) -> String {
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

pub(super) fn al_text(st: u16, code: u16) -> String {
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
    let emulation = ethercrab::Command::fprd(station, registers::ESC_CONFIGURATION)
        .receive::<u8>(md)
        .await
        .is_ok_and(|c| c & 0x01 != 0);
    let mut r = Run {
        md,
        station,
        sii,
        mailbox,
        bootstrap,
        device_emulation: emulation,
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
