//! The harness's master on the wire: frames, registers, SyncManagers, AL
//! requests and the process data cycle.

use super::*;

impl<D: Device> Harness<D> {
    /// One frame of datagrams through the ESC; the data and working
    /// counter of each. No firmware pass.
    pub(super) fn frame(&mut self, dgs: &[(Command, u16, &[u8])]) -> Vec<(Vec<u8>, u16)> {
        let need = 16 + dgs.iter().map(|(_, _, d)| 12 + d.len()).sum::<usize>();
        let mut buf = vec![0u8; need.clamp(64, 16 + 0x7FF)];
        let Ok(mut b) = FrameBuilder::new(&mut buf, MASTER_MAC) else {
            return Vec::new();
        };
        let mut ranges = Vec::with_capacity(dgs.len());
        for (cmd, ado, data) in dgs {
            match b.push(*cmd, ap(*ado), data) {
                Ok(r) => ranges.push(r),
                Err(_) => return Vec::new(),
            }
        }
        let len = b.finish();
        let Some(frame) = buf.get_mut(..len) else {
            return Vec::new();
        };
        let _ = self.slave.process_frame(frame);
        ranges
            .into_iter()
            .map(|r| {
                let data = frame.get(r.clone()).map(<[u8]>::to_vec).unwrap_or_default();
                let wkc = match frame.get(r.end..r.end + 2) {
                    Some(&[l, h]) => u16::from_le_bytes([l, h]),
                    _ => 0,
                };
                (data, wkc)
            })
            .collect()
    }

    /// A register write in its own frame, then a firmware pass.
    pub(super) fn write_reg(&mut self, ado: u16, data: &[u8]) -> bool {
        self.now_ns += FRAME_NS;
        let r = self.frame(&[(Command::Apwr, ado, data)]);
        if matches!(ado, reg::WATCHDOG_DIVIDER..=0x0421) {
            self.shadow.wd_written_at = Some(self.now_ns);
        }
        self.pass();
        r.first().is_some_and(|(_, w)| *w == 1)
    }

    /// A register read in its own frame, then a firmware pass.
    pub(super) fn read_reg(&mut self, ado: u16, len: usize) -> Option<Vec<u8>> {
        self.now_ns += FRAME_NS;
        let zeros = vec![0u8; len];
        let r = self.frame(&[(Command::Aprd, ado, &zeros)]);
        self.pass();
        r.into_iter()
            .next()
            .filter(|(_, w)| *w == 1)
            .map(|(d, _)| d)
    }

    pub(super) fn sm_bytes(n: usize, start: u16, len: u16) -> [u8; 8] {
        let s = start.to_le_bytes();
        let l = len.to_le_bytes();
        let control = SM_CONTROL.get(n).copied().unwrap_or(0);
        [s[0], s[1], l[0], l[1], control, 0, 1, 0]
    }

    pub(super) fn write_sm(&mut self, n: u16, bytes: &[u8; 8]) {
        let _ = self.write_reg(reg::SM_BASE + 8 * n, bytes);
    }

    // --- AL control ---------------------------------------------------------

    pub(super) fn request(&mut self, state: Request, ack: bool) {
        let from = self.last.state;
        let pending_error = self.last.error && !ack;
        let control = state.code() | if ack { 0x10 } else { 0 };
        // The firmware writes its AL status again when it takes this.
        self.shadow.status_stale = false;
        self.write_reg(reg::AL_CONTROL, &control.to_le_bytes());
        self.wait(5);
        // C6: with no image started, INIT → PRE-OP is refused with 0x0014.
        if self.shadow.no_image
            && from == AlState::Init
            && state == Request::PreOp
            && !pending_error
            && !self.pdi_fault
            && self.last.code != 0x0014
        {
            let code = self.last.code;
            self.violate(
                Invariant::I4,
                format!("no image started: INIT → PRE-OP answered with code {code:#06x}"),
            );
        }
    }

    pub(super) fn mailbox_sms(&mut self, boot: bool) {
        let layout = DEVICE.layout();
        let (out, inp) = if boot {
            (layout.boot_out, layout.boot_in)
        } else {
            (layout.mbx_out, layout.mbx_in)
        };
        self.write_sm(0, &Self::sm_bytes(0, out.0, out.1));
        self.write_sm(1, &Self::sm_bytes(1, inp.0, inp.1));
        self.master.mailbox = Some((out, inp));
    }

    /// Bytes of the image an assignment in the dictionary makes now.
    pub(super) fn assigned_len(&self, assign: u16) -> u16 {
        let od = self.slave.slave().od();
        let n = od.get(assign, 0).unwrap_or(0).clamp(0, 254) as u8;
        let bits: u32 = (1..=n)
            .map(|s| pdo_bits(od.get(assign, s).unwrap_or(0) as u16))
            .sum();
        bits.div_ceil(8) as u16
    }

    pub(super) fn process_data_sms(&mut self, sm2: SmSetting, sm3: SmSetting) {
        let layout = DEVICE.layout();
        let defaults = (default_len(0x1C12), default_len(0x1C13));
        for (n, setting, start, image, default) in [
            (
                2u16,
                sm2,
                layout.pd_out,
                self.assigned_len(0x1C12),
                defaults.0,
            ),
            (
                3u16,
                sm3,
                layout.pd_in,
                self.assigned_len(0x1C13),
                defaults.1,
            ),
        ] {
            let len = match setting {
                SmSetting::Off => None,
                SmSetting::Image => Some(image),
                SmSetting::Default => Some(default),
                SmSetting::Len(l) => Some(u16::from(l)),
            };
            let bytes = match len {
                None => [0u8; 8],
                Some(l) => Self::sm_bytes(usize::from(n), start, l),
            };
            self.write_sm(n, &bytes);
            let cfg = len.filter(|l| *l > 0).map(|l| (start, l));
            if n == 2 {
                self.master.sm2 = cfg;
            } else {
                self.master.sm3 = cfg;
            }
        }
    }

    // --- process data -------------------------------------------------------

    /// The SM2 bytes for `outputs` under the assignment in the dictionary,
    /// and the ENABLE bits they carry.
    pub(super) fn output_image(&mut self, outputs: Outputs, len: usize) -> (Vec<u8>, [bool; 3]) {
        let mut bytes = vec![0u8; len];
        let assign = &self.last.rx_assign;
        if self.layout.as_ref().is_none_or(|(a, _)| a != assign) {
            let mut layout = Vec::new();
            let mut offset = 0usize;
            for pdo in crate::invariants::model::assigned(assign) {
                for m in mapping(pdo) {
                    let bits = usize::from(m as u8);
                    layout.push(((m >> 16) as u16, (m >> 8) as u8, offset, bits));
                    offset += bits;
                }
            }
            self.layout = Some((assign.clone(), layout));
        }
        let layout: &[(u16, u8, usize, usize)] = self.layout.as_ref().map_or(&[], |(_, l)| l);
        match outputs {
            Outputs::Raw(raw) => {
                for (i, b) in bytes.iter_mut().enumerate() {
                    *b = raw.get(i % 4).copied().unwrap_or(0);
                }
            }
            Outputs::Values { enable, command } => {
                for (index, sub, at, bits) in layout {
                    let v: u64 = match (index, sub) {
                        (0x7000, 1) => u64::from(enable & 1),
                        (0x7010, 1) => u64::from((enable >> 1) & 1),
                        (0x7020, 1) => u64::from((enable >> 2) & 1),
                        (0x7000 | 0x7010 | 0x7020, 3) => command as u32 as u64,
                        _ => 0,
                    };
                    put_bits(&mut bytes, *at, *bits, v);
                }
            }
        }
        let mut enable = [false; 3];
        for (index, sub, at, bits) in layout {
            let ch = match (index, sub) {
                (0x7000, 1) => 0,
                (0x7010, 1) => 1,
                (0x7020, 1) => 2,
                _ => continue,
            };
            if let Some(e) = enable.get_mut(ch) {
                *e = get_bits(&bytes, *at, *bits) != 0;
            }
        }
        (bytes, enable)
    }

    /// One process-data frame (SM2 written if configured, SM3 read), no
    /// pass.
    pub(super) fn cycle_frame(&mut self, outputs: Outputs) {
        let sm2 = self.master.sm2;
        let sm3 = self.master.sm3;
        let mut out = None;
        if let Some((start, len)) = sm2 {
            out = Some((start, self.output_image(outputs, usize::from(len))));
        }
        let zeros = vec![0u8; sm3.map_or(0, |(_, l)| usize::from(l))];
        let mut dgs: Vec<(Command, u16, &[u8])> = Vec::new();
        if let Some((start, (bytes, _))) = &out {
            dgs.push((Command::Apwr, *start, bytes));
        }
        if let Some((start, _)) = sm3 {
            dgs.push((Command::Aprd, start, &zeros));
        }
        if dgs.is_empty() {
            return;
        }
        let r = self.frame(&dgs);
        if let Some((_, (_, enable))) = out {
            let written = r.first().is_some_and(|(_, w)| *w == 1);
            let (enabled, len) = self.observe_sm2();
            if written && enabled && len > 0 {
                self.shadow.sm2_pending = Some(enable);
            }
        }
    }

    pub(super) fn observe_sm2(&self) -> (bool, u16) {
        let mem = self.slave.slave().esc().raw_memory();
        let base = usize::from(reg::SM_BASE + 16);
        let act = mem.get(base + 6).copied().unwrap_or(0);
        let len = match mem.get(base + 2..base + 4) {
            Some(&[l, h]) => u16::from_le_bytes([l, h]),
            _ => 0,
        };
        (act & 1 != 0, len)
    }

    pub(super) fn cycles(&mut self, count: u8, outputs: Outputs) {
        self.master.outputs = Some(outputs);
        for _ in 0..count.max(1) {
            self.now_ns += MS;
            self.cycle_frame(outputs);
            self.pass();
        }
    }

    /// `ms` milliseconds in which the master keeps cycling with its last
    /// outputs (if it has sent any) while something else happens.
    pub(super) fn keep_cycling(&mut self, ms: u64) {
        for _ in 0..ms {
            self.now_ns += MS;
            if let Some(o) = self.master.outputs {
                self.cycle_frame(o);
            }
            self.pass();
        }
    }

    // --- mailbox ----------------------------------------------------------
}
