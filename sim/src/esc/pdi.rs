//! The PDI side: [`Esc`] for the software ESC (what firmware sees, with the
//! SyncManager rules of the PDI), and injected PDI failures ([`PdiFault`]).

use super::*;

// The last byte of the PDI-writable multi-byte registers (range patterns
// take named constants only).
const STATION_ALIAS_LAST: u16 = reg::STATION_ALIAS + 1;
const AL_STATUS_LAST: u16 = reg::AL_STATUS + 1;
const AL_STATUS_CODE_LAST: u16 = reg::AL_STATUS_CODE + 1;
const AL_EVENT_MASK_LAST: u16 = reg::AL_EVENT_MASK + 3;

/// A PDI failure injected into the software ESC: PDI accesses that touch
/// `start..end` fail with [`EscError::Interface`], as an SPI error on a
/// hardware ESC would. The frame side is not affected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdiFault {
    /// First address that fails.
    pub start: u16,
    /// One past the last address that fails.
    pub end: u16,
    /// PDI reads fail.
    pub reads: bool,
    /// PDI writes fail.
    pub writes: bool,
}

impl PdiFault {
    /// Every PDI access (read and write) fails.
    pub const ALL: PdiFault = PdiFault {
        start: 0,
        end: u16::MAX,
        reads: true,
        writes: true,
    };

    /// Reads of `start..end` fail.
    pub const fn reads(start: u16, end: u16) -> Self {
        PdiFault {
            start,
            end,
            reads: true,
            writes: false,
        }
    }

    pub(super) fn hits(&self, a: u32, b: u32, write: bool) -> bool {
        let dir = if write { self.writes } else { self.reads };
        dir && a < u32::from(self.end) && u32::from(self.start) < b
    }
}

impl SoftEsc {
    /// Makes PDI accesses fail as `fault` says (`None`: the PDI works).
    pub fn set_pdi_fault(&mut self, fault: Option<PdiFault>) {
        self.pdi_fault = fault;
    }

    /// PDI accesses (reads and writes, of any length) since the ESC was
    /// created: each one is a transaction on an SPI PDI.
    pub fn pdi_accesses(&self) -> u64 {
        self.pdi_accesses
    }

    /// Which SyncManager (if any, enabled) holds `[a, b)` partly.
    pub(super) fn pdi_sm_checks(&self, a: u32, b: u32, write: bool) -> Result<(u8, u8), EscError> {
        // Returns (bitmask of SMs whose last byte is covered, bitmask of
        // SMs touched).
        let mut complete = 0u8;
        let mut touched = 0u8;
        for (n, sm) in self.sms.iter().enumerate() {
            if !sm.overlaps(a, b) {
                continue;
            }
            touched |= 1 << n;
            let full = self.sm_status_bit(n, smr::STATUS_MAILBOX_FULL);
            if sm.is_mailbox() {
                // The PDI reads what the master wrote, writes what it reads.
                let ok = if write {
                    !sm.ecat_writes() && !full
                } else {
                    sm.ecat_writes() && full
                };
                if !ok {
                    return Err(EscError::SmBusy { sm: n as u8 });
                }
            }
            if sm.covers_last(a, b) {
                complete |= 1 << n;
            }
        }
        Ok((complete, touched))
    }
}

impl Esc for SoftEsc {
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
        self.pdi_touched = true;
        self.pdi_accesses += 1;
        let a = u32::from(addr);
        let b = a + buf.len() as u32;
        if self.pdi_fault.is_some_and(|f| f.hits(a, b, false)) {
            return Err(EscError::Interface);
        }
        if b as usize > self.mem.len() {
            return Err(EscError::OutOfRange {
                addr,
                len: buf.len(),
            });
        }
        // SyncManager rules on the part in process RAM (an access may
        // start among the registers and run into it).
        let ram = a.max(u32::from(reg::PROCESS_RAM));
        let (complete, touched) = if ram < b {
            self.pdi_sm_checks(ram, b, false)?
        } else {
            (0, 0)
        };
        self.refresh_dc_registers(a, b);
        self.mem_get(addr, buf);
        let covers = |r: u16| a <= u32::from(r) && u32::from(r) < b;
        // Reading AL control acknowledges its event; reading the watchdog
        // status or an SM activation register acknowledges theirs.
        if covers(reg::AL_CONTROL) {
            self.clear_al_event(reg::AL_EVENT_AL_CONTROL);
        }
        if covers(reg::WATCHDOG_STATUS_PD) {
            self.clear_al_event(reg::AL_EVENT_WATCHDOG_PD);
        }
        if covers(reg::DC_SYNC0_STATUS) {
            // Acknowledge mode (pulse length 0): reading the status clears
            // it and the AL event bit mirroring it.
            let st = self.mem_u8(reg::DC_SYNC0_STATUS) & !0x01;
            self.set_u8(reg::DC_SYNC0_STATUS, st);
            self.clear_al_event(reg::AL_EVENT_SYNC0);
        }
        if (0..SM_COUNT as u8)
            .filter_map(reg::sm)
            .any(|base| covers(base + smr::ACTIVATE))
        {
            self.clear_al_event(reg::AL_EVENT_SM_CHANGED);
        }
        for n in 0..SM_COUNT {
            if touched & (1 << n) != 0 {
                self.clear_al_event(reg::al_event_sm(n as u8));
            }
            if complete & (1 << n) != 0 {
                let is_mbx = self.sms.get(n).is_some_and(SmConfig::is_mailbox);
                let s = self.sm_status(n) & !smr::STATUS_WRITE_EVENT;
                let s = if is_mbx {
                    s & !smr::STATUS_MAILBOX_FULL
                } else {
                    s
                };
                self.set_sm_status(n, s);
            }
        }
        Ok(())
    }

    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
        self.pdi_touched = true;
        self.pdi_accesses += 1;
        let a = u32::from(addr);
        let b = a + data.len() as u32;
        if self.pdi_fault.is_some_and(|f| f.hits(a, b, true)) {
            return Err(EscError::Interface);
        }
        if b as usize > self.mem.len() {
            return Err(EscError::OutOfRange {
                addr,
                len: data.len(),
            });
        }
        // The part among the registers, then the part in process RAM (an
        // access may run from one into the other).
        let ram = u32::from(reg::PROCESS_RAM);
        let split = usize::try_from(ram.saturating_sub(a))
            .unwrap_or(usize::MAX)
            .min(data.len());
        let (regs, data) = data.split_at(split);
        if !regs.is_empty() {
            // PDI-writable registers: AL status/code, alias, event mask,
            // SM PDI control, LED overrides, watchdog counters; DL status
            // and the rest stay as the ESC sets them.
            for (i, &v) in regs.iter().enumerate() {
                let r = addr.wrapping_add(i as u16);
                let writable = matches!(
                    r,
                    reg::STATION_ALIAS..=STATION_ALIAS_LAST
                        | reg::AL_STATUS..=AL_STATUS_LAST
                        | reg::AL_STATUS_CODE..=AL_STATUS_CODE_LAST
                        | reg::RUN_LED_OVERRIDE..=reg::ERR_LED_OVERRIDE
                        | reg::AL_EVENT_MASK..=AL_EVENT_MASK_LAST
                        | reg::WATCHDOG_STATUS_PD..=reg::WATCHDOG_COUNTER_PDI
                ) || (r >= reg::SM_BASE
                    && r < reg::SM_BASE + reg::SM_LEN * SM_COUNT as u16
                    && (r - reg::SM_BASE) % reg::SM_LEN == smr::PDI_CONTROL);
                if writable {
                    self.set_u8(r, v);
                }
            }
            self.refresh_address();
            if data.is_empty() {
                return Ok(());
            }
        }
        let a = a.max(ram);
        let (complete, touched) = self.pdi_sm_checks(a, b, true)?;
        if let Some(dst) = self.mem.get_mut(a as usize..b as usize) {
            dst.copy_from_slice(data);
        }
        for n in 0..SM_COUNT {
            // Writing a buffer the master reads acknowledges its read
            // event (ET1100 0x0805 bit 1, "cleared by writing from PDI").
            if touched & (1 << n) != 0 {
                self.clear_al_event(reg::al_event_sm(n as u8));
                let st = self.sm_status(n) & !smr::STATUS_READ_EVENT;
                self.set_sm_status(n, st);
            }
            if complete & (1 << n) != 0 {
                let is_mbx = self.sms.get(n).is_some_and(SmConfig::is_mailbox);
                if is_mbx {
                    let s = self.sm_status(n) | smr::STATUS_MAILBOX_FULL;
                    self.set_sm_status(n, s);
                }
            }
        }
        Ok(())
    }
}
