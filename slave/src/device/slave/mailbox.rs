//! The mailbox side of the firmware loop: SM0 requests to the mailbox server
//! (CoE, FoE), responses into SM1 when it is free, the repeat service
//! (ETG.1000.4 mailbox repeat toggle).

use super::*;

impl<E: Esc, A: Application, const MBX: usize, const SDO: usize, const PDO: usize, const IMG: usize>
    Slave<E, A, MBX, SDO, PDO, IMG>
{
    pub(super) fn mailbox_layout(&self) -> ((u16, u16), (u16, u16)) {
        if self.al.state == AlState::Boot {
            (self.layout.boot_out, self.layout.boot_in)
        } else {
            (self.layout.mbx_out, self.layout.mbx_in)
        }
    }

    /// Writes the waiting response (in `sent`) into SM1 if SM1 is free;
    /// it then stays in `sent` for the repeat service. The whole buffer is
    /// written so that the ESC sees its last byte and marks the mailbox
    /// full.
    pub(super) fn deliver_pending(&mut self) -> Result<(), EscError> {
        if self.pending.is_none() || self.sm_full(1)? {
            return Ok(());
        }
        let (_, inp) = self.mailbox_layout();
        if let Some(len) = self.pending {
            let n = usize::from(inp.1).min(MBX);
            // The whole SM1 buffer goes out: zeros after the response.
            if let Some(tail) = self.sent.get_mut(len.min(n)..n) {
                tail.fill(0);
            }
            if let Some(f) = self.sent.get(..n) {
                self.esc.write(inp.0, f)?;
                self.sm1_writes = self.sm1_writes.wrapping_add(1);
            }
            self.pending = None;
            self.last_sent = Some(len);
        }
        Ok(())
    }

    /// Whether a new response may be built in `sent`: nothing waits to be
    /// delivered, and SM1 is empty, so the master has read the last
    /// response (it stays in `sent` for the repeat service until then).
    /// The response is then written at once, in the same pass.
    fn may_respond(&mut self) -> Result<bool, EscError> {
        Ok(self.pending.is_none() && !self.sm_full(1)?)
    }

    /// Mailbox repeat (ETG.1000.4 SyncManager repeat): when the master
    /// toggles the repeat request bit of SM1 (activate byte bit 1), the
    /// last response is put into SM1 again and the repeat acknowledge bit
    /// (PDI control bit 1) is toggled to match.
    pub(super) fn serve_repeat(&mut self) -> Result<(), EscError> {
        let base = reg::sm(1).ok_or(EscError::OutOfRange { addr: 0, len: 0 })?;
        let request = self.esc.read_u8(base + smr::ACTIVATE)? & smr::ACTIVATE_REPEAT;
        let pdi = self.esc.read_u8(base + smr::PDI_CONTROL)?;
        if request == pdi & smr::PDI_REPEAT_ACK {
            return Ok(());
        }
        if self.last_sent.is_some() && !self.sm_full(1)? {
            let (_, inp) = self.mailbox_layout();
            let n = usize::from(inp.1).min(MBX);
            if let Some(f) = self.sent.get(..n) {
                self.esc.write(inp.0, f)?;
                self.sm1_writes = self.sm1_writes.wrapping_add(1);
            }
        }
        self.esc.write(
            base + smr::PDI_CONTROL,
            &[(pdi & !smr::PDI_REPEAT_ACK) | request],
        )
    }

    pub(super) fn serve_mailbox<'s>(
        &mut self,
        images: Option<&mut (dyn ImageStore + 's)>,
    ) -> Result<(), EscError> {
        self.serve_repeat()?;
        self.deliver_pending()?;
        // One request at a time: a new request waits in SM0 until the
        // previous response has left and the master has read it.
        if self.pending.is_some() {
            return Ok(());
        }
        let view = object_view(self.app.description(), A::Values::view(&self.store));
        if !self.sm_full(0)? {
            // Nothing new: continue a response that spans several mailboxes.
            let (_, inp) = self.mailbox_layout();
            let emergency = self.emergencies_enabled && !self.emergencies.is_empty();
            // Only SDO Information spans several mailboxes; the flag is a
            // constant of a static description, so a firmware without SDO
            // Information does not link the fragment code.
            let fragments =
                self.app.description().mailbox.coe.sdo_info && self.mailbox.has_pending();
            if (!fragments && !emergency) || !self.may_respond()? {
                return Ok(());
            }
            let max = usize::from(inp.1).min(MBX);
            // The last response was read: `sent` takes the next one.
            self.last_sent = None;
            self.sent.fill(0);
            let mut produced = None;
            if fragments {
                produced = self
                    .sent
                    .get_mut(..max)
                    .and_then(|r| self.mailbox.next_pending(r, view));
            }
            if produced.is_none() && emergency {
                produced = self.sent.get_mut(..max).and_then(|r| {
                    let body = r.get_mut(crate::wire::mailbox::HEADER_LEN..)?;
                    let n = self.emergencies.pop_into(body)?;
                    self.mailbox.frame_coe(r, n)
                });
            }
            if let Some(len) = produced {
                self.pending = Some(len);
                self.deliver_pending()?;
            }
            return Ok(());
        }
        if !self.may_respond()? {
            // The request waits in SM0 until the master has read SM1.
            return Ok(());
        }
        let (out, inp) = self.mailbox_layout();
        let n = usize::from(out.1).min(MBX);
        let Some(req) = self.request.get_mut(..n) else {
            return Ok(());
        };
        self.esc.read(out.0, req)?;
        let max = usize::from(inp.1).min(MBX);
        let state = self.al.state;
        let version = self.firmware_version();
        let desc = self.app.description();
        let id = &desc.identity;
        let foe_offered = desc.mailbox.foe;
        let mut ctx = images.filter(|_| foe_offered).map(|store| FoeContext {
            store,
            identity: DeviceIdentity {
                vendor_id: id.vendor_id,
                product_code: id.product_code,
                revision: id.revision,
            },
            version: version.as_str(),
            security: desc.mailbox.foe_security,
            in_boot: state == AlState::Boot,
            busy: false,
        });
        let now_ns = self.now_ns;
        let (Some(req), Some(resp)) = (self.request.get(..n), self.sent.get_mut(..max)) else {
            return Ok(());
        };
        // Disjoint field borrows: no copy of the mailbox server, and the
        // response is built where it stays for the repeat service.
        let handled = self.mailbox.handle(
            req,
            resp,
            &mut OdAccess {
                app: &mut self.app,
                od: A::Values::view_mut(&mut self.store),
                state,
                now_ns,
            },
            ctx.as_mut(),
        );
        match handled {
            // The master sent the last request again: not executed, and
            // `sent` still holds the last response.
            Handled::Repeated => {}
            Handled::Done(produced) => {
                // `sent` was cleared for the new response.
                self.last_sent = None;
                if let Some(len) = produced {
                    self.pending = Some(len);
                    self.deliver_pending()?;
                }
            }
        }
        Ok(())
    }

    pub(super) fn sm_full(&mut self, n: u8) -> Result<bool, EscError> {
        let base = reg::sm(n).ok_or(EscError::OutOfRange { addr: 0, len: 0 })?;
        Ok(self.esc.read_u8(base + smr::STATUS)? & smr::STATUS_MAILBOX_FULL != 0)
    }
}
