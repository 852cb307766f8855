//! The harness's mailbox client: SDO uploads and downloads (complete
//! access too) through SM0/SM1.

use super::*;

impl<D: Device> Harness<D> {
    /// Reads away what earlier requests left (answers that came too late
    /// for their request, emergencies) until SM0 and SM1 are both empty
    /// after a pass: then no earlier request waits or is being answered,
    /// and the next answer belongs to the next request (two requests for
    /// the same object cannot be told apart by their answers).
    pub(super) fn mbx_drain(&mut self) {
        for _ in 0..8 {
            let sm0_full = self
                .read_reg(reg::SM_BASE + 5, 1)
                .is_some_and(|s| s.first().is_some_and(|b| b & 0x08 != 0));
            let stale = self.mbx_read().is_some();
            if !sm0_full && !stale {
                if !self.stalled && !self.pdi_fault {
                    self.shadow.answered();
                }
                return;
            }
        }
    }

    pub(super) fn mbx_send(&mut self, ty: MailboxType, payload: &[u8]) -> bool {
        let Some(((out, out_len), _)) = self.master.mailbox else {
            return false;
        };
        self.mbx_drain();
        let len = usize::from(out_len);
        if MBX_HEADER + payload.len() > len {
            return false;
        }
        self.master.counter = self.master.counter % 7 + 1;
        let mut msg = vec![0u8; len];
        if let Some(p) = msg.get_mut(MBX_HEADER..MBX_HEADER + payload.len()) {
            p.copy_from_slice(payload);
        }
        let repr = MailboxRepr {
            length: payload.len() as u16,
            address: 0,
            channel: 0,
            priority: 0,
            mailbox_type: ty,
            counter: self.master.counter,
        };
        if repr
            .emit(&mut Mailbox::new_unchecked(&mut msg[..]))
            .is_err()
        {
            return false;
        }
        for _ in 0..3 {
            self.now_ns += FRAME_NS;
            let r = self.frame(&[(Command::Apwr, out, &msg)]);
            let ok = r.first().is_some_and(|(_, w)| *w == 1);
            if ok {
                self.shadow.mailbox_written = true;
            }
            self.pass();
            if ok {
                return true;
            }
            // SM0 still full or SM1 holding an old answer: read it away.
            let _ = self.mbx_read();
        }
        false
    }

    /// Reads SM1 if it is full; the message's type and data.
    pub(super) fn mbx_read(&mut self) -> Option<(MailboxType, Vec<u8>)> {
        let (_, (inp, inp_len)) = self.master.mailbox?;
        let status = self.read_reg(reg::SM_BASE + 8 + 5, 1)?;
        if status.first().copied().unwrap_or(0) & 0x08 == 0 {
            return None;
        }
        let data = self.read_reg(inp, usize::from(inp_len))?;
        let m = Mailbox::new_checked(&data[..]).ok()?;
        Some((m.mailbox_type(), m.payload().to_vec()))
    }

    /// Sends a request and waits for its answer: the first message
    /// `accept` takes (emergencies and stale answers to earlier requests
    /// are read away and skipped).
    pub(super) fn mbx_exchange(
        &mut self,
        ty: MailboxType,
        payload: &[u8],
        accept: impl Fn(MailboxType, &[u8]) -> bool,
    ) -> Option<(MailboxType, Vec<u8>)> {
        if !self.mbx_send(ty, payload) {
            return None;
        }
        for _ in 0..ANSWER_FRAMES {
            if let Some((t, p)) = self.mbx_read()
                && accept(t, &p)
            {
                // Answers come in order: every earlier request is done.
                self.shadow.answered();
                return Some((t, p));
            }
        }
        None
    }

    /// An SDO request and its answer's SDO bytes. Answers to initiate
    /// requests must name `expect` (index, subindex).
    pub(super) fn sdo(
        &mut self,
        req: &SdoRequest<'_>,
        expect: Option<(u16, u8)>,
    ) -> Option<Vec<u8>> {
        let mut b = vec![0u8; 2 + req.buffer_len()];
        CoeHeader::emit_into(&mut b, 0, CoeService::SdoRequest);
        let n = req.emit(b.get_mut(2..)?).ok()?;
        b.truncate(2 + n);
        let accept = |t: MailboxType, p: &[u8]| -> bool {
            if t != MailboxType::CoE {
                return false;
            }
            let Ok(c) = CoeHeader::new_checked(p) else {
                return false;
            };
            if !matches!(
                c.service(),
                CoeService::SdoResponse | CoeService::SdoRequest
            ) {
                return false;
            }
            let named = match SdoResponse::parse(c.payload()) {
                Ok(
                    SdoResponse::InitiateDownloadAck { index, sub, .. }
                    | SdoResponse::UploadExpedited { index, sub, .. }
                    | SdoResponse::UploadNormal { index, sub, .. }
                    | SdoResponse::Abort { index, sub, .. },
                ) => Some((index, sub)),
                Ok(_) => None,
                Err(_) => return false,
            };
            match (expect, named) {
                (Some(e), Some(n)) => e == n,
                (Some(_), None) => false,
                (None, _) => true,
            }
        };
        let (_, p) = self.mbx_exchange(MailboxType::CoE, &b, accept)?;
        let c = CoeHeader::new_checked(&p[..]).ok()?;
        Some(c.payload().to_vec())
    }

    /// SDO data bytes a request can carry after the initiate header.
    pub(super) fn sdo_room(&self) -> usize {
        self.master
            .mailbox
            .map_or(0, |((_, l), _)| usize::from(l))
            .saturating_sub(MBX_HEADER + 2 + 8)
    }

    pub(super) fn download(&mut self, index: u16, sub: u8, complete: bool, data: &[u8]) -> Answer {
        let room = self.sdo_room();
        if room == 0 {
            return Answer::None;
        }
        let kind = if data.len() <= 4 && !complete {
            let mut d = [0u8; 4];
            for (i, b) in data.iter().enumerate() {
                if let Some(x) = d.get_mut(i) {
                    *x = *b;
                }
            }
            DownloadKind::Expedited {
                data: d,
                len: data.len().max(1) as u8,
            }
        } else {
            DownloadKind::Normal {
                complete_size: data.len() as u32,
                data: data.get(..data.len().min(room)).unwrap_or(&[]),
            }
        };
        let req = SdoRequest::InitiateDownload {
            index,
            sub,
            complete_access: complete,
            kind,
        };
        let Some(r) = self.sdo(&req, Some((index, sub))) else {
            return Answer::None;
        };
        match SdoResponse::parse(&r) {
            Ok(SdoResponse::InitiateDownloadAck { .. }) => {}
            Ok(SdoResponse::Abort { .. }) => return Answer::Abort,
            _ => return Answer::None,
        }
        let mut at = data.len().min(room);
        let mut toggle = false;
        while at < data.len() {
            let seg = room + 7;
            let end = (at + seg).min(data.len());
            let last = end == data.len();
            let req = SdoRequest::DownloadSegment {
                toggle,
                last,
                data: data.get(at..end).unwrap_or(&[]),
            };
            let Some(r) = self.sdo(&req, None) else {
                return Answer::None;
            };
            match SdoResponse::parse(&r) {
                Ok(SdoResponse::DownloadSegmentAck { .. }) => {}
                Ok(SdoResponse::Abort { .. }) => return Answer::Abort,
                _ => return Answer::None,
            }
            toggle = !toggle;
            at = end;
        }
        Answer::Ack
    }

    pub(super) fn upload(&mut self, index: u16, sub: u8, complete: bool) -> Option<Vec<u8>> {
        let r = self.sdo(
            &SdoRequest::InitiateUpload {
                index,
                sub,
                complete_access: complete,
            },
            Some((index, sub)),
        )?;
        let (size, mut data) = match SdoResponse::parse(&r).ok()? {
            SdoResponse::UploadExpedited { data, len, .. } => {
                return Some(data.get(..usize::from(len)).unwrap_or(&data).to_vec());
            }
            SdoResponse::UploadNormal {
                complete_size,
                data,
                ..
            } => (complete_size as usize, data.to_vec()),
            _ => return None,
        };
        let mut toggle = false;
        for _ in 0..32 {
            if data.len() >= size {
                break;
            }
            let r = self.sdo(&SdoRequest::UploadSegment { toggle }, None)?;
            match SdoResponse::parse(&r).ok()? {
                SdoResponse::UploadSegment { data: d, last, .. } => {
                    data.extend_from_slice(d);
                    if last {
                        break;
                    }
                }
                _ => return None,
            }
            toggle = !toggle;
        }
        data.truncate(size);
        Some(data)
    }

    pub(super) fn sdo_download(&mut self, index: u16, sub: u8, value: Value, complete: Option<u8>) {
        let entry = DICT.find_entry(index, sub).map(|(_, e)| e);
        let bytes = encode_value(value, entry);
        let raw_value = decode_i64(&bytes);
        let single = complete.is_none();
        let sent_at = self.now_ns;
        if single && (index, sub) == (0xF801, 2) {
            // What SAVE may put into the EEPROM.
            self.note_save_candidate();
        }
        let answer = match complete {
            None => self.download(index, sub, false, &bytes),
            Some(at) => {
                let mut image = self
                    .upload(index, sub, true)
                    .unwrap_or_else(|| bytes.clone());
                if image.is_empty() {
                    image.clone_from(&bytes);
                }
                let start = usize::from(at) % image.len().max(1);
                for (i, b) in bytes.iter().enumerate() {
                    if let Some(x) = image.get_mut(start + i) {
                        *x = *b;
                    }
                }
                self.download(index, sub, true, &image)
            }
        };
        if single && (index, sub) == (0xF801, 1) {
            let password = raw_value as u32 == VENDOR_PASSWORD;
            self.shadow.unlock = match (password, answer) {
                (true, Answer::Ack) => Unlock::Yes,
                (false, Answer::Ack | Answer::Abort) => Unlock::No,
                (true, Answer::Abort) => self.shadow.unlock,
                (_, Answer::None) => Unlock::Maybe.or(self.shadow.unlock),
            };
            // Unanswered: it may still be served later, after an INIT.
            self.shadow.password_outstanding = answer == Answer::None;
        }
        if single && (index, sub) == (0xF801, 2) && answer == Answer::None {
            self.shadow.save_outstanding = true;
        }
        if single && (index, sub) == (0xF801, 2) && answer == Answer::Ack {
            // I6 (P5): at most one SAVE per second.
            if let Some(prev) = self.shadow.last_save_sent
                && self.now_ns < prev + crate::SAVE_MIN_INTERVAL_NS
            {
                self.violate(
                    Invariant::I6,
                    format!(
                        "SAVE acknowledged {} ms after the previous one was sent",
                        (self.now_ns - prev) / MS
                    ),
                );
            }
            self.shadow.last_save_sent = Some(sent_at);
        }
    }

    pub(super) fn note_save_candidate(&mut self) {
        let f = self.last.f80f;
        if !self.shadow.saved_f80f.contains(&f) {
            self.shadow.saved_f80f.push(f);
        }
    }

    // --- power and the bootloader -------------------------------------------
}
