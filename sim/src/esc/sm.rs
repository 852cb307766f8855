//! SyncManagers: their cached configuration and status bits (0x0800-0x087F).

use super::*;

/// Cached configuration of one SyncManager.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct SmConfig {
    pub(super) start: u16,
    pub(super) len: u16,
    pub(super) control: u8,
    pub(super) enabled: bool,
    /// The activation register as written (enable, repeat request, ...).
    pub(super) activate: u8,
}

impl SmConfig {
    pub(super) fn is_mailbox(&self) -> bool {
        self.control & 0x03 == smr::MODE_MAILBOX
    }
    pub(super) fn ecat_writes(&self) -> bool {
        self.control & 0x0C == smr::DIR_ECAT_WRITE
    }
    /// End address (exclusive) of the buffer.
    pub(super) fn end(&self) -> u32 {
        u32::from(self.start) + u32::from(self.len)
    }
    /// Whether `[a, b)` overlaps the buffer.
    pub(super) fn overlaps(&self, a: u32, b: u32) -> bool {
        self.enabled && self.len > 0 && a < self.end() && u32::from(self.start) < b
    }
    /// Whether `[a, b)` covers the last byte of the buffer.
    pub(super) fn covers_last(&self, a: u32, b: u32) -> bool {
        let last = self.end() - 1;
        a <= last && last < b
    }
}

impl SoftEsc {
    pub(super) fn reload_sm(&mut self, n: usize) {
        let Some(base) = reg::sm(n as u8) else {
            return;
        };
        let new = SmConfig {
            start: self.mem_u16(base + smr::START),
            len: self.mem_u16(base + smr::LENGTH),
            control: self.mem_u8(base + smr::CONTROL),
            enabled: self.mem_u8(base + smr::ACTIVATE) & smr::ACTIVATE_ENABLE != 0,
            activate: self.mem_u8(base + smr::ACTIVATE),
        };
        let Some(slot) = self.sms.get_mut(n) else {
            return;
        };
        let old = *slot;
        *slot = new;
        self.routes_stale = true;
        if new.enabled && new.len > 0 {
            self.sm_active |= 1 << n;
        } else {
            self.sm_active &= !(1 << n);
        }
        // A changed activation register (enable, repeat request) is an
        // event for the firmware; so is any reconfiguration.
        if old != new {
            self.raise_al_event(reg::AL_EVENT_SM_CHANGED);
        }
        // (Re)configuring or enabling a SyncManager resets its buffer state.
        if old.start != new.start
            || old.len != new.len
            || old.control != new.control
            || old.enabled != new.enabled
        {
            self.set_sm_status(n, 0);
            // A (re)configured output SM with watchdog trigger restarts the
            // process-data watchdog: unarmed until the first output write.
            if new.enabled && new.control & smr::WATCHDOG_TRIGGER != 0 {
                self.wd_sm_armed_at = None;
                let st = self.mem_u16(reg::WATCHDOG_STATUS_PD) | 1;
                self.set_u16(reg::WATCHDOG_STATUS_PD, st);
            }
        }
    }

    /// The SyncManagers of `set` (bit n = SM n) that overlap `[a, b)`,
    /// lowest first, with their numbers.
    pub(super) fn sms_overlapping(
        &self,
        set: u8,
        a: u32,
        b: u32,
    ) -> impl Iterator<Item = (usize, SmConfig)> + '_ {
        let mut bits = set;
        core::iter::from_fn(move || {
            while bits != 0 {
                let n = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if let Some(sm) = self.sms.get(n)
                    && sm.overlaps(a, b)
                {
                    return Some((n, *sm));
                }
            }
            None
        })
    }

    pub(super) fn sm_status(&self, n: usize) -> u8 {
        reg::sm(n as u8).map_or(0, |b| self.mem_u8(b + smr::STATUS))
    }

    pub(super) fn sm_status_bit(&self, n: usize, bit: u8) -> bool {
        self.sm_status(n) & bit != 0
    }

    pub(super) fn set_sm_status(&mut self, n: usize, v: u8) {
        if let Some(b) = reg::sm(n as u8) {
            self.set_u8(b + smr::STATUS, v);
        }
    }
}
