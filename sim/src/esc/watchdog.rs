//! The SyncManager (process data) and PDI watchdogs (0x0400-0x0443), run on
//! injected time.

use super::*;

impl SoftEsc {
    /// Sets or clears DL status bit 1, "PDI watchdog not expired". An ESC
    /// without a PDI (PDI control 0: a coupler) has none that could be
    /// reloaded: the bit stays clear.
    pub fn set_pdi_watchdog_ok(&mut self, ok: bool) {
        let ok = ok && self.mem_u8(reg::PDI_CONTROL) != 0;
        let dl = self.mem_u16(reg::DL_STATUS);
        let bit = reg::dl_status::PDI_WATCHDOG_OK;
        self.set_u16(reg::DL_STATUS, if ok { dl | bit } else { dl & !bit });
    }

    /// Watchdog base tick in ns: (0x0400 + 2) x 40 ns (ET1100 datasheet,
    /// ETG.1000.4 6.7).
    pub fn watchdog_base_ns(&self) -> u64 {
        (u64::from(self.mem_u16(reg::WATCHDOG_DIVIDER)) + 2) * 40
    }

    /// Runs the ESC's watchdogs at time `now_ns`, as silicon does on its
    /// own clock. The SyncManager (process data) watchdog is re-armed by
    /// every completed write of an output SM with the watchdog trigger bit
    /// and expires after 0x0420 base ticks: 0x0440 bit 0 clears and
    /// 0x0442 counts. The PDI watchdog is re-armed by every PDI access and
    /// expires after 0x0410 base ticks: DL status bit 1 clears and 0x0443
    /// counts. A time of 0 disables a watchdog.
    pub fn update_watchdogs(&mut self, now_ns: u64) {
        // Frames processed after this without their own times (a single
        // ESC, not on a line) pass the DC unit at this time.
        self.dc_port0_ns = self.dc_port0_ns.max(now_ns);
        self.update_dc(now_ns);
        let base = self.watchdog_base_ns();
        if core::mem::take(&mut self.wd_restart) {
            if self.wd_sm_armed_at.is_some() {
                self.wd_sm_armed_at = Some(now_ns);
            }
            self.wd_pdi_at = Some(now_ns);
        }
        if core::mem::take(&mut self.wd_sm_trigger) {
            self.wd_sm_armed_at = Some(now_ns);
            let st = self.mem_u16(reg::WATCHDOG_STATUS_PD) | 0x0001;
            self.set_u16(reg::WATCHDOG_STATUS_PD, st);
        }
        let pd_ticks = u64::from(self.mem_u16(reg::WATCHDOG_TIME_PD));
        if let Some(armed) = self.wd_sm_armed_at {
            let expired = pd_ticks != 0 && now_ns.saturating_sub(armed) >= pd_ticks * base;
            let status = self.mem_u16(reg::WATCHDOG_STATUS_PD);
            if expired && status & 1 != 0 {
                self.set_u16(reg::WATCHDOG_STATUS_PD, status & !1);
                self.raise_al_event(reg::AL_EVENT_WATCHDOG_PD);
                let c = self.mem_u8(reg::WATCHDOG_COUNTER_PD).saturating_add(1);
                self.set_u8(reg::WATCHDOG_COUNTER_PD, c);
            }
        }
        if core::mem::take(&mut self.pdi_touched) || self.wd_pdi_at.is_none() {
            self.wd_pdi_at = Some(now_ns);
            self.set_pdi_watchdog_ok(true);
        }
        let pdi_ticks = u64::from(self.mem_u16(reg::WATCHDOG_TIME_PDI));
        let last = self.wd_pdi_at.unwrap_or(now_ns);
        let dl = self.mem_u16(reg::DL_STATUS);
        if pdi_ticks != 0
            && now_ns.saturating_sub(last) >= pdi_ticks * base
            && dl & reg::dl_status::PDI_WATCHDOG_OK != 0
        {
            self.set_pdi_watchdog_ok(false);
            let c = self.mem_u8(reg::WATCHDOG_COUNTER_PDI).saturating_add(1);
            self.set_u8(reg::WATCHDOG_COUNTER_PDI, c);
        }
    }

    /// Whether the PDI watchdog has expired (DL status bit 1 clear).
    pub fn pdi_watchdog_expired(&self) -> bool {
        self.mem_u16(reg::DL_STATUS) & reg::dl_status::PDI_WATCHDOG_OK == 0
    }
}
