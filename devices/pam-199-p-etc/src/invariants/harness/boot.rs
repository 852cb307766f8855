//! The world of the firmware: power-on and the bootloader's decision,
//! FoE downloads cut anywhere, the flash.

use super::*;

impl<D: Device> Harness<D> {
    /// Power off and on; `confirm`: the started image confirms itself.
    pub(super) fn power_on(&mut self, confirm: bool) {
        self.slave.pam_restore_power();
        self.flash.mem.restore_power();
        self.slave.power_cycle();
        self.slave.slave_mut().esc_mut().set_pdi_fault(None);
        self.stalled = false;
        self.pdi_fault = false;
        let decision = (self.boot)(&mut *self.flash);
        self.check_boot(&decision);
        if confirm && decision.slot.is_some() {
            let _ = firmware::confirm_boot(&mut *self.flash);
            self.shadow.trials = None;
        }
        let fw = self.slave.slave_mut();
        fw.set_firmware_version(decision.version.as_str());
        fw.set_no_valid_firmware(decision.slot.is_none());
        self.shadow.no_image = decision.slot.is_none();
        self.master = MasterConfig::default();
        self.shadow.unlock = Unlock::No;
        self.shadow.last_save_sent = None;
        self.shadow.sm2_pending = None;
        self.shadow.enable = [false; 3];
        self.shadow.cyclic_since_op = false;
        self.shadow.wd_written_at = None;
        self.shadow.wd_zero_since = None;
        self.shadow.foe_authorised = false;
        self.shadow.status_stale = false;
        self.shadow.password_outstanding = false;
        self.shadow.save_outstanding = false;
        let o = self.observe();
        // I3 after power-on: the default or a value SAVE may have stored.
        if o.f80f != [0, 0] && !self.shadow.saved_f80f.contains(&o.f80f) {
            self.violate(
                Invariant::I3,
                format!("0xF80F is {:?} after power-on: never saved", o.f80f),
            );
        }
        // I2 after power-on (P5): the assignment is FUNCTION's set.
        let (rx, tx) = crate::invariants::model::function_pdos(o.function);
        let ok = crate::invariants::model::assigned(&o.rx_assign).all(|p| rx.contains(&p))
            && crate::invariants::model::assigned(&o.tx_assign).all(|p| tx.contains(&p));
        if !ok {
            self.violate(
                Invariant::I2,
                format!(
                    "after power-on FUNCTION {} with assignment {:?}/{:?}",
                    o.function, o.rx_assign, o.tx_assign
                ),
            );
        }
        self.last = o;
        self.now_ns += MS;
        self.pass();
    }

    /// I4: what the bootloader started.
    pub(super) fn check_boot(&mut self, d: &BootDecision) {
        if self.flash.unreadable && d.slot.is_some() {
            self.violate(
                Invariant::I4,
                format!("boot records unreadable, yet {:?} started", d.slot),
            );
            return;
        }
        let Some(slot) = d.slot else {
            return;
        };
        let version = d.version.as_str().to_string();
        let Some((_, payload)) = self.good.iter().find(|(v, _)| *v == version) else {
            self.violate(
                Invariant::I4,
                format!("started {slot:?} with version {version:?}: not an image that passed"),
            );
            return;
        };
        let bytes = self.flash.slot(slot);
        if bytes.get(..payload.len()) != Some(&payload[..]) {
            self.violate(
                Invariant::I4,
                format!("started {slot:?} (version {version}) whose bytes are not the image's"),
            );
            return;
        }
        if let ecat_slave::firmware::BootOutcome::Trial { .. } = d.outcome {
            let n = match &self.shadow.trials {
                Some((v, n)) if *v == version => n + 1,
                _ => 1,
            };
            if n > firmware::MAX_BOOT_ATTEMPTS {
                self.violate(
                    Invariant::I4,
                    format!("version {version} started on trial {n} times without confirming"),
                );
            }
            self.shadow.trials = Some((version, n));
        } else {
            self.shadow.trials = None;
        }
    }

    // --- FoE ----------------------------------------------------------------

    pub(super) fn efw(&mut self, image: Image) -> Vec<u8> {
        let (version, product) = match image {
            Image::Old => ("9".to_string(), PRODUCT_CODE),
            Image::OtherProduct => (self.next_version.to_string(), PRODUCT_CODE ^ 1),
            Image::Good | Image::Corrupt { .. } => {
                let v = self.next_version;
                self.next_version += 1;
                (v.to_string(), PRODUCT_CODE)
            }
        };
        let len = 1500 + (self.next_version as usize * 137) % 1500;
        let payload: Vec<u8> = (0..len)
            .map(|i| (i as u32).wrapping_mul(31).wrapping_add(self.next_version) as u8)
            .collect();
        let header = EfwHeaderRepr {
            header_len: EFW_HEADER_LEN as u16,
            flags: 0,
            vendor_id: VENDOR_ID,
            product_code: product,
            revision_min: REVISION,
            revision_max: REVISION,
            version: FirmwareVersion::new(&version).unwrap_or(FirmwareVersion::EMPTY),
            payload_len: 0,
            payload_crc: 0,
        };
        let mut out = vec![0u8; EFW_HEADER_LEN + payload.len()];
        let n = firmware::pack(&header, &payload, &mut out).unwrap_or(0);
        out.truncate(n);
        match image {
            Image::Good => self.good.push((version, payload)),
            Image::Corrupt { at } => {
                let i = EFW_HEADER_LEN + usize::from(at) % payload.len().max(1);
                if let Some(b) = out.get_mut(i) {
                    *b ^= 0x5A;
                }
            }
            Image::OtherProduct | Image::Old => {}
        }
        out
    }

    pub(super) fn foe(&mut self, request: &FoeRepr<'_>) -> Option<Vec<u8>> {
        let mut b = vec![0u8; request.buffer_len()];
        let n = request.emit(&mut b).ok()?;
        b.truncate(n);
        let (_, p) = self.mbx_exchange(MailboxType::FoE, &b, |t, _| t == MailboxType::FoE)?;
        Some(p)
    }

    /// Whether the flash lost power; if so the slave is power cycled.
    pub(super) fn flash_cut(&mut self) -> bool {
        if self.flash.mem.is_powered() {
            return false;
        }
        self.power_on(true);
        true
    }

    pub(super) fn foe_download(
        &mut self,
        image: Image,
        password: bool,
        stop_after: Option<u8>,
        cut_after: Option<u16>,
    ) {
        let file = self.efw(image);
        if let Some(units) = cut_after {
            self.flash.mem.cut_power_after(usize::from(units) * 64);
        }
        let pw = if password { 0 } else { 0x1234_5678 };
        // A write request with the right password may still be served
        // later (one waiting in SM0); only an answered wrong one ends the
        // authorisation.
        self.shadow.foe_authorised |= password;
        let ack = self.foe(&FoeRepr::WriteRequest {
            password: pw,
            name: b"pam-199-p-etc.efw",
        });
        if !password && ack.is_some() {
            self.shadow.foe_authorised = false;
        }
        if self.flash_cut() {
            return;
        }
        if !matches!(
            ack.as_deref().map(FoeRepr::parse),
            Some(Ok(FoeRepr::Ack { packet: 0 }))
        ) {
            self.flash.mem.restore_power();
            return;
        }
        let room = self
            .master
            .mailbox
            .map_or(0, |((_, l), _)| usize::from(l))
            .saturating_sub(MBX_HEADER + 6);
        if room == 0 {
            return;
        }
        let mut at = 0usize;
        let mut packet = 1u32;
        loop {
            if stop_after.is_some_and(|k| packet > u32::from(k)) {
                break;
            }
            let end = (at + room).min(file.len());
            let data = file.get(at..end).unwrap_or(&[]).to_vec();
            let last = data.len() < room;
            let mut answered = false;
            for _ in 0..8 {
                let r = self.foe(&FoeRepr::Data {
                    packet,
                    data: &data,
                });
                if self.flash_cut() {
                    return;
                }
                match r.as_deref().map(FoeRepr::parse) {
                    Some(Ok(FoeRepr::Ack { packet: p })) if p == packet => {
                        answered = true;
                        break;
                    }
                    Some(Ok(FoeRepr::Busy { .. })) => continue,
                    _ => break,
                }
            }
            if !answered || last {
                break;
            }
            at = end;
            packet += 1;
        }
        self.flash.mem.restore_power();
    }

    // --- the actions --------------------------------------------------------
}
