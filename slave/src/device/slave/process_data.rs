//! Process data: outputs from SM2 into the dictionary, inputs from the
//! dictionary into SM3, and the safe state of the outputs.

use super::*;

impl<E: Esc, A: Application, const MBX: usize, const SDO: usize, const PDO: usize, const IMG: usize>
    Slave<E, A, MBX, SDO, PDO, IMG>
{
    /// Outputs to their safe state: every RxPDO-mappable entry back to
    /// zero, then the application switches its hardware outputs off.
    pub(super) fn safe_outputs(&mut self) {
        // Outputs held for the next SYNC0 are as stale as the rest.
        self.dc_outputs = None;
        self.outputs_applied = false;
        let od = A::Values::view_mut(&mut self.store);
        let dict = od.dictionary();
        for (flat, _, e) in dict.entries() {
            if e.pdo() == PdoMapping::Rx {
                od.set_value(flat, 0);
            }
        }
        self.app.outputs_safe(od);
    }

    pub(super) fn read_outputs(&mut self, events: u32) -> Result<(), EscError> {
        if events & reg::al_event_sm(2) != 0 {
            self.outputs_since_sync0 = true;
        }
        let mut buf = [0u8; IMG];
        if events & reg::al_event_sm(2) != 0 && self.outputs.byte_len() > 0 {
            let n = self.outputs.byte_len();
            if let Some(b) = buf.get_mut(..n) {
                match self.esc.read(self.layout.pd_out, b) {
                    // SM2 turned into a mailbox by the master: nothing to
                    // take; the supervision answers it with 0x001D.
                    Err(EscError::SmBusy { .. }) => return Ok(()),
                    r => r?,
                }
            }
            if self.sync_mode == SyncMode::DcSync0 {
                // Held until the next SYNC0.
                self.dc_outputs = Some((n, buf));
            } else if self.al.state == AlState::Op
                && let Some(b) = buf.get(..n)
            {
                let od = A::Values::view_mut(&mut self.store);
                self.outputs.unpack(od, b);
                self.outputs_applied = true;
            }
        }
        Ok(())
    }

    pub(super) fn write_inputs(&mut self) -> Result<(), EscError> {
        let n = self.inputs.byte_len();
        if n > 0 {
            let mut inb = [0u8; IMG];
            if let Some(b) = inb.get_mut(..n) {
                self.inputs.pack(A::Values::view(&self.store), b);
                match self.esc.write(self.layout.pd_in, b) {
                    // The master made SM3 a mailbox it has not emptied:
                    // its configuration, not the PDI, is at fault; the
                    // supervision answers it with 0x001E.
                    Err(EscError::SmBusy { .. }) => {}
                    r => r?,
                }
            }
        }
        Ok(())
    }
}
