//! ECAT-side access to physical memory with the SyncManager rules: mailbox
//! full/empty, three-buffer output areas, read and write events.

use super::*;

/// Direction of one ECAT-side physical access.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ReadMode {
    /// Replace the frame data with memory contents.
    Copy,
    /// OR memory contents into the frame data (broadcast reads).
    Or,
}

/// `dst.copy_from_slice(src)` (equal lengths), with the register widths
/// (1, 2, 4 and 8 bytes: AL status, DL status, a system time) copied in
/// line rather than through a call to `memcpy`.
#[inline(always)]
fn copy_register(dst: &mut [u8], src: &[u8]) {
    match (dst.len(), src.len()) {
        (2, 2) => {
            if let (Ok(d), Ok(s)) = (<&mut [u8; 2]>::try_from(dst), <&[u8; 2]>::try_from(src)) {
                *d = *s;
            }
        }
        (4, 4) => {
            if let (Ok(d), Ok(s)) = (<&mut [u8; 4]>::try_from(dst), <&[u8; 4]>::try_from(src)) {
                *d = *s;
            }
        }
        (8, 8) => {
            if let (Ok(d), Ok(s)) = (<&mut [u8; 8]>::try_from(dst), <&[u8; 8]>::try_from(src)) {
                *d = *s;
            }
        }
        _ => dst.copy_from_slice(src),
    }
}

impl SoftEsc {
    /// ECAT-side read of physical memory with SyncManager rules. Returns
    /// whether the access happened (counts in the working counter).
    #[inline]
    pub(super) fn ecat_read(&mut self, addr: u16, out: &mut [u8], mode: ReadMode) -> bool {
        let a = usize::from(addr);
        let b = a + out.len();
        // The registers below the FMMUs (ESC information, addresses, DL
        // and AL status, event and error registers, watchdogs, the SII
        // interface) all exist, hold no DC time to refresh and lie outside
        // every SyncManager: a plain copy, the hot path of FPRD AL status.
        if b <= usize::from(reg::FMMU_BASE)
            && mode == ReadMode::Copy
            && let Some(src) = self.mem.get(a..b)
        {
            copy_register(out, src);
            return true;
        }
        self.ecat_read_checked(addr, out, mode)
    }

    /// [`SoftEsc::ecat_read`] beyond the plain registers.
    fn ecat_read_checked(&mut self, addr: u16, out: &mut [u8], mode: ReadMode) -> bool {
        let a = u32::from(addr);
        let b = a + out.len() as u32;
        if b > 0x1_0000 || !self.silicon.implements(a, b) {
            return false;
        }
        self.refresh_dc_registers(a, b);
        // SyncManager checks, on the part in process RAM only: as on
        // silicon, SyncManagers map process RAM, and one a master
        // configured over the registers must not hide them (the master
        // could no longer read AL status to repair it).
        let ram = a.max(u32::from(reg::PROCESS_RAM));
        let mut complete = 0u8;
        let checked = if ram < b { self.sm_active } else { 0 };
        for (n, sm) in self.sms_overlapping(checked, ram, b) {
            if sm.is_mailbox() {
                if sm.ecat_writes() || !self.sm_status_bit(n, smr::STATUS_MAILBOX_FULL) {
                    return false;
                }
            } else if sm.ecat_writes() {
                // Reading back a buffered output area is allowed (memory).
                continue;
            }
            if sm.covers_last(ram, b) {
                complete |= 1 << n;
            }
        }
        // Copy out: bytes beyond the modelled memory read as zero.
        let mem_end = (b as usize).min(self.mem.len());
        let from = (a as usize).min(mem_end);
        let src = self.mem.get(from..mem_end).unwrap_or(&[]);
        match mode {
            ReadMode::Copy => {
                let n = src.len().min(out.len());
                let (head, tail) = out.split_at_mut(n);
                head.copy_from_slice(src.get(..n).unwrap_or(&[]));
                // Bytes beyond the modelled memory: rare, and a memset
                // call costs more than the copy of a register.
                if !tail.is_empty() {
                    tail.fill(0);
                }
            }
            ReadMode::Or => {
                for (d, v) in out.iter_mut().zip(src) {
                    *d |= *v;
                }
            }
        }
        while complete != 0 {
            let n = complete.trailing_zeros() as usize;
            complete &= complete - 1;
            self.ecat_read_complete(n);
        }
        true
    }

    /// The master read the last byte of SM `n`'s buffer.
    pub(super) fn ecat_read_complete(&mut self, n: usize) {
        let Some(sm) = self.sms.get(n).copied() else {
            return;
        };
        let status = if sm.is_mailbox() {
            // Mailbox emptied by the master.
            (self.sm_status(n) & !smr::STATUS_MAILBOX_FULL) | smr::STATUS_READ_EVENT
        } else {
            self.sm_status(n) | smr::STATUS_READ_EVENT
        };
        self.set_sm_status(n, status);
        self.raise_al_event(reg::al_event_sm(n as u8));
    }

    /// ECAT-side write of physical memory with SyncManager rules and
    /// register write masks. Returns whether the access happened.
    pub(super) fn ecat_write(&mut self, addr: u16, data: &[u8]) -> bool {
        let a = u32::from(addr);
        let b = a + data.len() as u32;
        if b > 0x1_0000 || !self.silicon.implements(a, b) {
            return false;
        }
        // The DC system time difference 0x092C-0x092F is the ESC's to
        // write: a master's write changes nothing and is not counted (the
        // real ESCs of tests/data/captures answer it with 0).
        let diff = u32::from(reg::DC_SYSTEM_TIME_DIFF);
        if a >= diff && b <= diff + 4 {
            return false;
        }
        if a < u32::from(reg::PROCESS_RAM) {
            self.register_write(addr, data);
            return true;
        }
        let mut complete = 0u8;
        for (n, sm) in self.sms_overlapping(self.sm_active, a, b) {
            if !sm.ecat_writes() {
                return false;
            }
            if sm.is_mailbox() && self.sm_status_bit(n, smr::STATUS_MAILBOX_FULL) {
                return false;
            }
            if sm.covers_last(a, b) {
                complete |= 1 << n;
            }
        }
        let mem_end = (b as usize).min(self.mem.len());
        let from = (a as usize).min(mem_end);
        if let (Some(dst), Some(src)) = (
            self.mem.get_mut(from..mem_end),
            data.get(..mem_end.saturating_sub(from)),
        ) {
            dst.copy_from_slice(src);
        }
        while complete != 0 {
            let n = complete.trailing_zeros() as usize;
            complete &= complete - 1;
            self.ecat_write_complete(n);
        }
        true
    }

    /// The master wrote the last byte of SM `n`'s buffer.
    pub(super) fn ecat_write_complete(&mut self, n: usize) {
        let Some(sm) = self.sms.get(n).copied() else {
            return;
        };
        let status = if sm.is_mailbox() {
            self.sm_status(n) | smr::STATUS_MAILBOX_FULL | smr::STATUS_WRITE_EVENT
        } else {
            // Three-buffer mode: flip the "last buffer written" field.
            let s = self.sm_status(n);
            let next = ((s >> 4) & 0x03).wrapping_add(1) % 3;
            (s & !0x30) | (next << 4) | smr::STATUS_WRITE_EVENT
        };
        self.set_sm_status(n, status);
        if !sm.is_mailbox() {
            self.sm_written |= 1 << n;
            if sm.control & smr::WATCHDOG_TRIGGER != 0 {
                self.wd_sm_trigger = true;
            }
        }
        self.raise_al_event(reg::al_event_sm(n as u8));
    }
}
