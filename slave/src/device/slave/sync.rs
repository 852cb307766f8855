//! DC-synchronous operation: SYNC0 events, outputs applied at SYNC0, the SM-
//! event-missed counter and 0x1C32/0x1C33 (ETG.1020 sync types).

use super::*;

impl<E: Esc, A: Application, const MBX: usize, const SDO: usize, const PDO: usize, const IMG: usize>
    Slave<E, A, MBX, SDO, PDO, IMG>
{
    /// A SYNC0 event: acknowledged by reading 0x098E (one PDI read);
    /// counted, and in DC mode a cycle without new outputs since the last
    /// SYNC0 counts as an SM event missed.
    pub(super) fn sync0(&mut self, events: u32) -> Result<(), EscError> {
        if events & reg::AL_EVENT_SYNC0 == 0 {
            return Ok(());
        }
        self.esc.read_u8(reg::DC_SYNC0_STATUS)?;
        self.sync0_events = self.sync0_events.wrapping_add(1);
        // DC-synchronous outputs take effect at SYNC0, not when they
        // arrive (ETG.1020: outputs valid at the SYNC0 event).
        if let Some((n, buf)) = self.dc_outputs.take()
            && self.al.state == AlState::Op
            && let Some(b) = buf.get(..n)
        {
            let od = A::Values::view_mut(&mut self.store);
            self.outputs.unpack(od, b);
            self.outputs_applied = true;
        }
        if self.sync_mode == SyncMode::DcSync0 && self.al.state == AlState::Op {
            // `read_outputs` ran first in this pass: outputs that came
            // with this SYNC0 count for it.
            if !self.outputs_since_sync0 {
                self.sm_event_missed = self.sm_event_missed.wrapping_add(1);
                let n = i64::from(self.sm_event_missed as u16);
                let od = A::Values::view_mut(&mut self.store);
                od.set(0x1C32, 11, n);
                od.set(0x1C33, 11, n);
            }
            self.outputs_since_sync0 = false;
        }
        Ok(())
    }

    /// Back to free run (PRE-OP, INIT, BOOT): no held outputs, and
    /// 0x1C32/0x1C33 say so (a stale "DC" there would read as the next
    /// master's request).
    pub(super) fn reset_sync(&mut self) {
        self.sync_mode = SyncMode::FreeRun;
        self.dc_outputs = None;
        self.publish_sync(0);
    }

    /// 0x1C32/0x1C33 (if the device has them) show the sync mode and
    /// cycle time chosen and the SM event missed counter.
    pub(super) fn publish_sync(&mut self, cycle: i64) {
        use crate::od::build::sync_mode;
        let mode = match self.sync_mode {
            SyncMode::FreeRun => sync_mode::FREE_RUN,
            SyncMode::DcSync0 => sync_mode::DC_SYNC0,
        };
        let od = A::Values::view_mut(&mut self.store);
        for index in [0x1C32, 0x1C33] {
            od.set(index, 1, mode);
            od.set(index, 2, cycle);
            od.set(index, 10, cycle);
            od.set(index, 11, i64::from(self.sm_event_missed as u16));
        }
    }

    /// The synchronisation chosen at the last PRE-OP→SAFE-OP.
    pub fn sync_mode(&self) -> SyncMode {
        self.sync_mode
    }

    /// SYNC0 events the firmware has seen (wrapping).
    pub fn sync0_events(&self) -> u32 {
        self.sync0_events
    }

    /// DC mode: SYNC0 cycles in OP that came without new outputs since
    /// the previous one (ETG.1020 "SM event missed").
    pub fn sm_event_missed(&self) -> u32 {
        self.sm_event_missed
    }
}
