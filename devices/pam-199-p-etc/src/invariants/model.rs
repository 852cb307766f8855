//! The rules of docs/SAFETY.md as invariants over what can be observed of
//! the slave after every firmware pass, and the shadow model of the
//! history some of them need (what the master sent and the slave
//! acknowledged). Nothing here drives the slave; [`super::Harness`] does
//! and calls these checks.
//!
//! The shadow is built from the master's side (what it wrote, what the
//! slave answered) and from the observable outputs (set points, ESC
//! registers, dictionary values), never from the core's private flags:
//! a check that read `outputs_applied` to decide whether current may flow
//! would only compare the code with itself.

use std::fmt;
use std::string::String;
use std::vec::Vec;

use ecat_slave::al::AlState;

/// The invariants (docs/SAFETY.md, "Invariants").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Invariant {
    /// I1 (P1, P2, C1, C4): a solenoid set point above 0 mA only in OP,
    /// with cyclic outputs consumed since OP was entered whose ENABLE of
    /// that channel is 1, the SM watchdog armed, no EEPROM data error, no
    /// failure shown by SENS for that channel; while the firmware is
    /// stalled, none once the PDI watchdog has expired.
    I1,
    /// I2 (P3, P4, P5, C5): in SAFE-OP and OP every assigned PDO belongs to
    /// FUNCTION's PDO set and SM2/SM3 match the assigned image; 0x1C12,
    /// 0x1C13 and F800:02 change only in PRE-OP; after power-on the
    /// assignment is FUNCTION's set.
    I2,
    /// I3 (P6): 0xF80F changes only while the vendor password is given
    /// (written since the last INIT or power-on); after power-on it holds
    /// its default or a value it had when SAVE ran.
    I3,
    /// I4 (P7, C6): the bootloader starts only an image that is byte for
    /// byte one the master downloaded completely (or the factory image),
    /// never one whose check failed or a trial image past its attempts;
    /// with unreadable boot records it starts none and the slave stays in
    /// INIT/BOOT (INIT → PRE-OP refused with 0x0014); image slots are
    /// written only in BOOT after a write request with the right password.
    I4,
    /// I5 (C2, C3): leaving OP clears every RxPDO-mappable entry and the
    /// set points; an expired SM watchdog ends OP in the same pass; a
    /// failed PDI access leaves no current and no OP; after a successful
    /// pass the AL status registers show the firmware's state.
    I5,
    /// I6 (P5): SAVE is acknowledged at most once per second.
    I6,
}

impl Invariant {
    /// Every invariant, in order.
    pub const ALL: [Invariant; 6] = [
        Invariant::I1,
        Invariant::I2,
        Invariant::I3,
        Invariant::I4,
        Invariant::I5,
        Invariant::I6,
    ];
}

/// A broken invariant: which, at which step, and what was seen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// The invariant.
    pub invariant: Invariant,
    /// Index of the action during which it broke.
    pub step: usize,
    /// What was observed.
    pub detail: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:?} broken at step {}: {}",
            self.invariant, self.step, self.detail
        )
    }
}

/// Whether the vendor unlock may be in force (the shadow of P6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unlock {
    /// Locked: no password since INIT / power-on, or locked again.
    No,
    /// The password was acknowledged.
    Yes,
    /// A password write got no answer: it may have been taken.
    Maybe,
}

impl Unlock {
    /// The more permissive of two unlock states.
    pub fn or(self, other: Unlock) -> Unlock {
        match (self, other) {
            (Unlock::Yes, _) | (_, Unlock::Yes) => Unlock::Yes,
            (Unlock::Maybe, _) | (_, Unlock::Maybe) => Unlock::Maybe,
            _ => Unlock::No,
        }
    }
}

/// What the checks see of the slave at one moment.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Observation {
    /// The firmware's AL state.
    pub state: AlState,
    /// The firmware's error indication.
    pub error: bool,
    /// The firmware's AL status code.
    pub code: u16,
    /// Set points of solenoids A and B, mA.
    pub setpoints: [u16; 2],
    /// F800:02 FUNCTION.
    pub function: i64,
    /// F800:03 SENS.
    pub sens: i64,
    /// 0x1C12 subindices 0.. (count, then PDOs).
    pub rx_assign: Vec<i64>,
    /// 0x1C13 subindices 0...
    pub tx_assign: Vec<i64>,
    /// 0xF80F:01, 0xF80F:02.
    pub f80f: [i64; 2],
    /// The values of RxPDO-mappable entries that are not 0.
    pub rx_entries: Vec<i64>,
    /// The amplifier's EEPROM data error.
    pub eeprom_error: bool,
    /// Diagnosis: 0xA000:01..04 (memory, under/over voltage,
    /// temperature), 0xA010:01..02 (A), 0xA020:01..02 (B).
    pub diag: [bool; 8],
    /// ESC 0x0420 (SM watchdog time).
    pub wd_time: u16,
    /// ESC 0x0440 (SM watchdog status).
    pub wd_status: u16,
    /// ESC 0x0130 (AL status).
    pub al_status_reg: u16,
    /// ESC 0x0134 (AL status code).
    pub al_code_reg: u16,
    /// ESC SM2 and SM3: (enabled, length).
    pub sm: [(bool, u16); 2],
    /// The ESC's PDI watchdog expired.
    pub pdi_wd_expired: bool,
    /// Bytes the firmware erased or wrote in the image slots so far.
    pub slot_writes: u64,
}

/// The PDO sets of FUNCTION (written here once more, from the manual's
/// chapter 7.1, instead of read from the description the code uses).
pub fn function_pdos(function: i64) -> (&'static [u16], &'static [u16]) {
    if function == 2 {
        (&[0x1601], &[0x1A01, 0x1A03])
    } else {
        (&[0x1600], &[0x1A00, 0x1A02])
    }
}

/// The PDOs of an assignment (subindex 0 is the count).
pub fn assigned(assign: &[i64]) -> impl Iterator<Item = u16> + '_ {
    let n = assign.first().copied().unwrap_or(0).clamp(0, 254) as usize;
    assign.iter().skip(1).take(n).map(|v| *v as u16)
}

/// The shadow of the history the invariants need.
#[derive(Debug, Clone)]
pub struct Shadow {
    /// Bytes and ENABLE bits of the newest SM2 write the firmware has not
    /// run since.
    pub sm2_pending: Option<[bool; 3]>,
    /// ENABLE (0x7000:01, 0x7010:01, 0x7020:01) in the newest SM2 write
    /// the firmware has run after.
    pub enable: [bool; 3],
    /// An SM2 write was consumed in OP since OP was entered.
    pub cyclic_since_op: bool,
    /// When the master last wrote a watchdog register (divider, times).
    pub wd_written_at: Option<u64>,
    /// Since when 0x0420 is 0 (the master disabled the SM watchdog).
    pub wd_zero_since: Option<u64>,
    /// The vendor unlock.
    pub unlock: Unlock,
    /// Values 0xF80F had when SAVE was sent (what the EEPROM may hold).
    pub saved_f80f: Vec<[i64; 2]>,
    /// The master wrote the mailbox since the last pass.
    pub mailbox_written: bool,
    /// The last write request carried the right FoE password.
    pub foe_authorised: bool,
    /// The bootloader started no image at the last power-on.
    pub no_image: bool,
    /// Send time of the last acknowledged SAVE, ns.
    pub last_save_sent: Option<u64>,
    /// (version text, unconfirmed trial boots in a row).
    pub trials: Option<(String, u8)>,
    /// The last pass failed (its AL status write may have failed with the
    /// PDI): the registers may still show the state before the failure
    /// until a pass reaches the ESC again, which writes them first.
    pub status_stale: bool,
    /// A write of 0xF801:01 got no answer: it may be served later.
    pub password_outstanding: bool,
    /// A SAVE got no answer: it may be served later.
    pub save_outstanding: bool,
}

impl Default for Shadow {
    fn default() -> Self {
        Shadow {
            sm2_pending: None,
            enable: [false; 3],
            cyclic_since_op: false,
            wd_written_at: None,
            wd_zero_since: None,
            unlock: Unlock::No,
            saved_f80f: Vec::new(),
            mailbox_written: false,
            foe_authorised: false,
            no_image: false,
            last_save_sent: None,
            trials: None,
            status_stale: false,
            password_outstanding: false,
            save_outstanding: false,
        }
    }
}

/// Everything a pass's checks need besides the two observations.
#[derive(Debug, Clone, Copy)]
pub struct PassContext {
    /// Time of the pass, ns.
    pub now_ns: u64,
    /// The firmware was stalled (only the ESC ran).
    pub stalled: bool,
    /// The pass ended in a PDI failure.
    pub failed: bool,
    /// A PDI fault is injected now.
    pub pdi_fault: bool,
    /// Tolerance for what the firmware only sees at its full passes (a
    /// register write raises no AL event), ns.
    pub full_pass_ns: u64,
}

fn fail(out: &mut Option<(Invariant, String)>, inv: Invariant, detail: String) {
    if out.is_none() {
        *out = Some((inv, detail));
    }
}

impl Shadow {
    /// A request got its answer: the slave serves requests in order, so
    /// every earlier one is done (an unanswered password write may have
    /// unlocked: from now on only INIT or a newer write decide).
    pub fn answered(&mut self) {
        if self.password_outstanding {
            self.password_outstanding = false;
            self.unlock = Unlock::Maybe.or(self.unlock);
        }
        self.save_outstanding = false;
    }

    /// The firmware ran (not stalled): the pending SM2 write is consumed.
    /// Call after the pass with the state after it.
    pub fn consume(&mut self, before: &Observation, after: &Observation, stalled: bool) {
        if stalled {
            return;
        }
        let pending = self.sm2_pending.take();
        if let Some(enable) = pending {
            self.enable = enable;
        }
        if after.state == AlState::Op {
            if before.state != AlState::Op {
                self.cyclic_since_op = pending.is_some();
            } else {
                self.cyclic_since_op |= pending.is_some();
            }
        } else {
            self.cyclic_since_op = false;
        }
    }

    /// The watchdog was written within the tolerance window.
    fn wd_recent(&self, ctx: &PassContext) -> bool {
        self.wd_written_at
            .is_some_and(|t| ctx.now_ns.saturating_sub(t) <= ctx.full_pass_ns)
    }

    /// Checks one firmware pass (`before`: after the previous pass or the
    /// power-on; `after`: now). Returns the first broken invariant.
    pub fn check_pass(
        &self,
        before: &Observation,
        after: &Observation,
        ctx: &PassContext,
    ) -> Option<(Invariant, String)> {
        let mut out = None;
        self.check_current(after, ctx, &mut out);
        self.check_function(before, after, ctx, &mut out);
        self.check_manufacturer(before, after, &mut out);
        self.check_boot(before, after, &mut out);
        self.check_leaving_op(before, after, ctx, &mut out);
        out
    }

    /// I1.
    fn check_current(
        &self,
        o: &Observation,
        ctx: &PassContext,
        out: &mut Option<(Invariant, String)>,
    ) {
        for (i, sp) in o.setpoints.iter().enumerate() {
            if *sp == 0 {
                continue;
            }
            let coil = if i == 0 { 'A' } else { 'B' };
            if ctx.stalled {
                if o.pdi_wd_expired {
                    fail(
                        out,
                        Invariant::I1,
                        format!("{sp} mA on {coil} with the PDI watchdog expired (stalled)"),
                    );
                }
                continue;
            }
            let why = |w: &str| format!("{sp} mA on solenoid {coil}: {w}");
            if o.state != AlState::Op {
                fail(out, Invariant::I1, why(&format!("state {:?}", o.state)));
            }
            if ctx.failed {
                fail(out, Invariant::I1, why("after a PDI failure"));
            }
            if !self.cyclic_since_op {
                fail(out, Invariant::I1, why("no cyclic outputs since OP"));
            }
            let channel = if o.function == 2 { 1 + i } else { 0 };
            if !self.enable.get(channel).copied().unwrap_or(false) {
                fail(
                    out,
                    Invariant::I1,
                    why(&format!(
                        "ENABLE of channel {channel} is 0 in the cyclic outputs ({:?})",
                        self.enable
                    )),
                );
            }
            let disabled_long = self
                .wd_zero_since
                .is_some_and(|t| ctx.now_ns.saturating_sub(t) > ctx.full_pass_ns);
            if o.wd_time == 0 && (disabled_long || self.wd_zero_since.is_none()) {
                fail(out, Invariant::I1, why("SM watchdog disabled (0x0420 = 0)"));
            }
            if o.eeprom_error {
                fail(out, Invariant::I1, why("EEPROM data error"));
            }
            if o.sens != 1 {
                let [mem, under, over, temp, short_a, open_a, short_b, open_b] = o.diag;
                let common = mem || under || over || temp;
                let own = match (o.function == 2, i) {
                    (false, _) => short_a || open_a || short_b || open_b,
                    (true, 0) => short_a || open_a,
                    (true, _) => short_b || open_b,
                };
                if common || own {
                    fail(
                        out,
                        Invariant::I1,
                        why(&format!("failure shown by SENS {}: {:?}", o.sens, o.diag)),
                    );
                }
            }
        }
    }

    /// I2.
    fn check_function(
        &self,
        before: &Observation,
        after: &Observation,
        ctx: &PassContext,
        out: &mut Option<(Invariant, String)>,
    ) {
        if matches!(after.state, AlState::SafeOp | AlState::Op) {
            let (rx, tx) = function_pdos(after.function);
            for (name, assign, set) in [
                ("0x1C12", &after.rx_assign, rx),
                ("0x1C13", &after.tx_assign, tx),
            ] {
                if let Some(p) = assigned(assign).find(|p| !set.contains(p)) {
                    fail(
                        out,
                        Invariant::I2,
                        format!(
                            "{:?}: {name} assigns {p:#06x}, FUNCTION {} selects {set:04x?}",
                            after.state, after.function
                        ),
                    );
                }
            }
            // The SMs against the image: the firmware's supervision
            // handles one finding per pass (an SM watchdog that ends OP
            // is reported before a changed SM, which ends SAFE-OP in the
            // next pass), so a pass that changed the state is not judged.
            if !ctx.stalled && !ctx.failed && !ctx.pdi_fault && before.state == after.state {
                for (k, assign) in [&after.rx_assign, &after.tx_assign].into_iter().enumerate() {
                    let bytes = image_bytes(assign);
                    let (enabled, len) = after.sm.get(k).copied().unwrap_or((false, 0));
                    // An SM of an empty image is checked at PRE-OP →
                    // SAFE-OP only (C5): the core's supervision in
                    // SAFE-OP/OP watches the SMs of non-empty images
                    // (see the ignored test
                    // `invariant_i2_an_unused_sm2_enabled_in_op_ends_op`).
                    let ok = bytes == 0 || (enabled && usize::from(len) == bytes);
                    if !ok {
                        fail(
                            out,
                            Invariant::I2,
                            format!(
                                "{:?}: SM{} (enabled {enabled}, {len} bytes) for an image of \
                                 {bytes} bytes",
                                after.state,
                                k + 2
                            ),
                        );
                    }
                }
            }
        }
        let outside = |s: AlState| s != AlState::PreOp;
        if outside(before.state) && outside(after.state) {
            if before.rx_assign != after.rx_assign || before.tx_assign != after.tx_assign {
                fail(
                    out,
                    Invariant::I2,
                    format!(
                        "assignment changed outside PRE-OP ({:?} → {:?}): {:?}/{:?} → {:?}/{:?}",
                        before.state,
                        after.state,
                        before.rx_assign,
                        before.tx_assign,
                        after.rx_assign,
                        after.tx_assign
                    ),
                );
            }
            if before.function != after.function {
                fail(
                    out,
                    Invariant::I2,
                    format!(
                        "FUNCTION changed outside PRE-OP ({:?} → {:?}): {} → {}",
                        before.state, after.state, before.function, after.function
                    ),
                );
            }
        }
    }

    /// I3 during a session.
    fn check_manufacturer(
        &self,
        before: &Observation,
        after: &Observation,
        out: &mut Option<(Invariant, String)>,
    ) {
        if before.f80f != after.f80f && self.unlock == Unlock::No {
            fail(
                out,
                Invariant::I3,
                format!(
                    "0xF80F changed without the vendor password: {:?} → {:?}",
                    before.f80f, after.f80f
                ),
            );
        }
    }

    /// I4 (slots, no image).
    fn check_boot(
        &self,
        before: &Observation,
        after: &Observation,
        out: &mut Option<(Invariant, String)>,
    ) {
        if after.slot_writes != before.slot_writes {
            let boot = before.state == AlState::Boot || after.state == AlState::Boot;
            if !boot || !self.foe_authorised {
                fail(
                    out,
                    Invariant::I4,
                    format!(
                        "image slot written in {:?} → {:?} (right FoE password: {})",
                        before.state, after.state, self.foe_authorised
                    ),
                );
            }
        }
        if self.no_image && !matches!(after.state, AlState::Init | AlState::Boot) {
            fail(
                out,
                Invariant::I4,
                format!("no image started, yet the slave is in {:?}", after.state),
            );
        }
    }

    /// I5.
    fn check_leaving_op(
        &self,
        before: &Observation,
        after: &Observation,
        ctx: &PassContext,
        out: &mut Option<(Invariant, String)>,
    ) {
        if ctx.stalled {
            return;
        }
        if before.state == AlState::Op && after.state != AlState::Op && !self.mailbox_written {
            if !after.rx_entries.is_empty() {
                fail(
                    out,
                    Invariant::I5,
                    format!(
                        "OP left for {:?}, RxPDO entries not cleared: {:?}",
                        after.state, after.rx_entries
                    ),
                );
            }
            if after.setpoints != [0, 0] {
                fail(
                    out,
                    Invariant::I5,
                    format!("OP left, set points {:?}", after.setpoints),
                );
            }
        }
        if ctx.failed && (after.state == AlState::Op || after.setpoints != [0, 0]) {
            fail(
                out,
                Invariant::I5,
                format!(
                    "PDI failure, yet {:?} with set points {:?}",
                    after.state, after.setpoints
                ),
            );
        }
        if ctx.failed || ctx.pdi_fault {
            return;
        }
        if after.state == AlState::Op
            && after.wd_time != 0
            && after.wd_status & 1 == 0
            && !self.wd_recent(ctx)
        {
            fail(
                out,
                Invariant::I5,
                "SM watchdog expired (0x0440 bit 0 clear) and the slave is still in OP".into(),
            );
        }
        let code = match after.state {
            AlState::Init => 1,
            AlState::PreOp => 2,
            AlState::Boot => 3,
            AlState::SafeOp => 4,
            AlState::Op => 8,
        } | if after.error { 0x10 } else { 0 };
        if !self.status_stale
            && (after.al_status_reg & 0x1F != code || after.al_code_reg != after.code)
        {
            fail(
                out,
                Invariant::I5,
                format!(
                    "AL status registers {:#06x}/{:#06x}, firmware {:?} error {} code {:#06x}",
                    after.al_status_reg, after.al_code_reg, after.state, after.error, after.code
                ),
            );
        }
    }
}

/// Bytes of the image an assignment makes, from the mapping objects' fixed
/// contents (manual 7.1; padding included).
pub fn image_bytes(assign: &[i64]) -> usize {
    let bits: u32 = assigned(assign).map(pdo_bits).sum();
    bits.div_ceil(8) as usize
}

/// Bits a PDO of the PAM maps: the lengths (`0xIIIISSLL` low byte) of its
/// mapping entries summed.
pub fn pdo_bits(pdo: u16) -> u32 {
    mapping(pdo).iter().map(|m| u32::from(*m as u8)).sum()
}

/// The mapping entries (`0xIIIISSLL`) of a PDO of the PAM, from its
/// dictionary (the mappings are fixed).
pub fn mapping(pdo: u16) -> Vec<u32> {
    let Some((_, obj)) = crate::description::od::DICT.find(pdo) else {
        return Vec::new();
    };
    obj.entries
        .iter()
        .filter(|e| e.sub != 0)
        .filter_map(|e| match e.default_value() {
            ecat_slave::od::types::DefaultValue::Int(v) => Some(v.get() as u32),
            ecat_slave::od::types::DefaultValue::Str(_)
            | ecat_slave::od::types::DefaultValue::Bytes(_) => None,
        })
        .collect()
}
