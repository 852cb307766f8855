//! The harness: a software PAM on the software ESC, a master that reaches
//! it only through EtherCAT frames (register writes, mailbox, process
//! data), the world around it (time, power, PDI, EEPROM, flash), and the
//! invariant checks after every firmware pass.
//!
//! Where a real master would first read something from the slave (the SII
//! mailbox geometry, the mapping of the assigned PDOs), the harness takes
//! it from the device description or the dictionary; everything the slave
//! does in answer goes through frames.

use std::boxed::Box;
use std::format;
use std::string::{String, ToString};
use std::vec;
use std::vec::Vec;

use ecat_sim::SoftSlave;
use ecat_sim::esc::PdiFault;
use ecat_slave::al::AlState;
use ecat_slave::device::{Application, FULL_PASS_NS, SM_CONTROL};
use ecat_slave::esc::registers as reg;
use ecat_slave::firmware::{
    self, BootDecision, BootState, EFW_HEADER_LEN, EfwHeaderRepr, FirmwareVersion, ImageStore,
    MemStore, Slot, StoreError,
};
use ecat_slave::od::types::{DataType, DefaultValue, PdoMapping};
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::coe::{CoeHeader, CoeService, DownloadKind, SdoRequest, SdoResponse};
use ecat_slave::wire::ecat::Command;
use ecat_slave::wire::foe::FoeRepr;
use ecat_slave::wire::mailbox::{HEADER_LEN as MBX_HEADER, Mailbox, MailboxRepr, MailboxType};

use super::action::{
    Action, Coil, Image, Outputs, PDOS, PdiRegion, Request, SmSetting, StageEvent, Target, Value,
};
use super::model::{
    Invariant, Observation, PassContext, Shadow, Unlock, Violation, mapping, pdo_bits,
};
use crate::app::power_stage::{Fault, Solenoid};
use crate::od::DICT;
use crate::{DEVICE, PRODUCT_CODE, Pam, REVISION, VENDOR_ID, VENDOR_PASSWORD};

/// Bytes of the simulated firmware flash (two slots of half of it).
pub const FLASH_BYTES: usize = 16 * 1024;

/// Version of the factory image the flash starts with.
pub const FACTORY_VERSION: &str = "10";

/// The factory image's payload.
pub const FACTORY_PAYLOAD: &[u8] = b"invariant harness factory firmware 10";

/// Time a mailbox frame takes, ns.
const FRAME_NS: u64 = 100_000;
/// A millisecond, ns.
const MS: u64 = 1_000_000;
/// Frames a mailbox client waits for an answer.
const ANSWER_FRAMES: usize = 24;
/// Source MAC of the master's frames.
const MASTER_MAC: [u8; 6] = [0x02, 0x10, 0x10, 0x10, 0x10, 0x10];
/// Address field of an auto-increment datagram to the first slave.
const fn ap(ado: u16) -> u32 {
    (ado as u32) << 16
}

/// A PAM (or a wrapper around one, to plant violations) the harness runs.
pub trait Device: Application + Send + 'static {
    /// The PAM inside.
    fn pam(&self) -> &Pam;
    /// The PAM inside, mutably.
    fn pam_mut(&mut self) -> &mut Pam;
}

impl Device for Pam {
    fn pam(&self) -> &Pam {
        self
    }
    fn pam_mut(&mut self) -> &mut Pam {
        self
    }
}

/// The bootloader the harness runs at power-on (the core's
/// [`firmware::power_on`], or a planted one that skips a check).
pub type Bootloader = fn(&mut dyn ImageStore) -> BootDecision;

/// The firmware flash: a [`MemStore`] whose boot records can be made
/// unreadable, counting what the firmware writes into the slots.
#[derive(Debug, Clone)]
pub struct Flash {
    mem: MemStore<FLASH_BYTES>,
    unreadable: bool,
    slot_writes: u64,
}

impl Flash {
    fn provisioned() -> Self {
        let mut mem = MemStore::new();
        if let Some(v) = FirmwareVersion::new(FACTORY_VERSION) {
            let _ = firmware::provision(&mut mem, v, FACTORY_PAYLOAD);
        }
        Flash {
            mem,
            unreadable: false,
            slot_writes: 0,
        }
    }

    /// The raw contents of a slot.
    pub fn slot(&self, slot: Slot) -> &[u8] {
        self.mem.slot_bytes(slot)
    }
}

impl ImageStore for Flash {
    fn slot_capacity(&self) -> usize {
        self.mem.slot_capacity()
    }
    fn erase(&mut self, slot: Slot) -> Result<(), StoreError> {
        self.slot_writes = self.slot_writes.saturating_add(1);
        self.mem.erase(slot)
    }
    fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError> {
        self.slot_writes = self.slot_writes.saturating_add(data.len() as u64);
        self.mem.write(slot, offset, data)
    }
    fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError> {
        self.mem.read(slot, offset, buf)
    }
    fn read_state(&self) -> Result<BootState, StoreError> {
        if self.unreadable {
            return Err(StoreError::Io);
        }
        self.mem.read_state()
    }
    fn write_state(&mut self, state: &BootState) -> Result<(), StoreError> {
        self.mem.write_state(state)
    }
}

/// Where the output entries sit in SM2: (index, sub, bit offset, bits).
type Layout = Vec<(u16, u8, usize, usize)>;

/// What an SDO exchange ended with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Answer {
    Ack,
    Abort,
    None,
}

/// The master's own configuration of the slave (what it wrote).
#[derive(Debug, Clone, Copy, Default)]
struct MasterConfig {
    /// SM0/SM1 as written: (out start, out len), (in start, in len).
    mailbox: Option<((u16, u16), (u16, u16))>,
    /// SM2/SM3 as written: (start, len) when enabled with a length.
    sm2: Option<(u16, u16)>,
    sm3: Option<(u16, u16)>,
    counter: u8,
    outputs: Option<Outputs>,
}

/// A software PAM, a frame-level master and the invariant checks.
pub struct Harness<D: Device = Pam> {
    slave: Box<SoftSlave<D>>,
    flash: Box<Flash>,
    boot: Bootloader,
    now_ns: u64,
    master: MasterConfig,
    shadow: Shadow,
    last: Observation,
    stalled: bool,
    pdi_fault: bool,
    step: usize,
    violation: Option<Violation>,
    next_version: u32,
    /// Images the bootloader may start: (version, payload).
    good: Vec<(String, Vec<u8>)>,
    /// Firmware passes run so far.
    passes: u64,
    /// The output image layout (index, sub, bit offset, bits) of the
    /// 0x1C12 values it was made for.
    layout: Option<(Vec<i64>, Layout)>,
}

impl Harness<Pam> {
    /// A PAM with blank parameter storage and the factory firmware.
    pub fn new() -> Self {
        Harness::with_device(Pam::default())
    }
}

impl Default for Harness<Pam> {
    fn default() -> Self {
        Self::new()
    }
}

impl<D: Device> Harness<D> {
    /// `device` with the factory firmware and the core's bootloader.
    pub fn with_device(device: D) -> Self {
        Self::with_bootloader(device, firmware_power_on)
    }

    /// `device` booted by `boot`.
    pub fn with_bootloader(device: D, boot: Bootloader) -> Self {
        let mut h = Harness {
            slave: Box::new(SoftSlave::new(device)),
            flash: Box::new(Flash::provisioned()),
            boot,
            now_ns: 0,
            master: MasterConfig::default(),
            shadow: Shadow::default(),
            last: placeholder(),
            stalled: false,
            pdi_fault: false,
            step: 0,
            violation: None,
            next_version: 11,
            good: vec![(FACTORY_VERSION.to_string(), FACTORY_PAYLOAD.to_vec())],
            passes: 0,
            layout: None,
        };
        h.power_on(true);
        h
    }

    /// Runs `actions` in order, checking every invariant after every
    /// firmware pass; stops at the first violation.
    pub fn run(&mut self, actions: &[Action]) -> Result<(), Violation> {
        for (i, a) in actions.iter().enumerate() {
            self.step = i;
            self.act(a);
            if let Some(v) = self.violation.take() {
                return Err(v);
            }
        }
        Ok(())
    }

    /// The slave.
    pub fn slave(&self) -> &SoftSlave<D> {
        &self.slave
    }

    /// The slave, mutably.
    pub fn slave_mut(&mut self) -> &mut SoftSlave<D> {
        &mut self.slave
    }

    /// The firmware flash.
    pub fn flash(&self) -> &Flash {
        &self.flash
    }

    /// Time now, ns.
    pub fn now_ns(&self) -> u64 {
        self.now_ns
    }

    /// Firmware passes run so far.
    pub fn passes(&self) -> u64 {
        self.passes
    }

    /// The shadow model.
    pub fn shadow(&self) -> &Shadow {
        &self.shadow
    }

    fn violate(&mut self, invariant: Invariant, detail: String) {
        if self.violation.is_none() {
            self.violation = Some(Violation {
                invariant,
                step: self.step,
                detail,
            });
        }
    }

    // --- observation and the firmware pass --------------------------------

    fn observe(&self) -> Observation {
        let fw = self.slave.slave();
        let od = fw.od();
        let al = fw.al_status();
        let pam = fw.app().pam();
        let stage = pam.stage();
        let f = flats();
        let esc = fw.esc();
        let mem = esc.raw_memory();
        let u16_at = |a: u16| -> u16 {
            let a = usize::from(a);
            match mem.get(a..a + 2) {
                Some(&[l, h]) => u16::from_le_bytes([l, h]),
                _ => 0,
            }
        };
        let sm = |n: u16| -> (bool, u16) {
            let base = reg::SM_BASE + 8 * n;
            let act = mem.get(usize::from(base + 6)).copied().unwrap_or(0);
            (act & 1 != 0, u16_at(base + 2))
        };
        let values = |flats: &[usize]| -> Vec<i64> { flats.iter().map(|x| od.value(*x)).collect() };
        let mut diag = [false; 8];
        for (d, x) in diag.iter_mut().zip(f.diag) {
            *d = od.value(x) != 0;
        }
        Observation {
            state: al.state,
            error: al.error,
            code: al.code.code(),
            setpoints: [
                stage.setpoint_ma(Solenoid::A),
                stage.setpoint_ma(Solenoid::B),
            ],
            function: od.value(f.function),
            sens: od.value(f.sens),
            rx_assign: values(&f.rx_assign),
            tx_assign: values(&f.tx_assign),
            f80f: [od.value(f.f80f[0]), od.value(f.f80f[1])],
            rx_entries: f
                .rx
                .iter()
                .map(|x| od.value(*x))
                .filter(|v| *v != 0)
                .collect(),
            eeprom_error: pam.amplifier().eeprom_error,
            diag,
            wd_time: u16_at(reg::WATCHDOG_TIME_PD),
            wd_status: u16_at(reg::WATCHDOG_STATUS_PD),
            al_status_reg: u16_at(reg::AL_STATUS),
            al_code_reg: u16_at(reg::AL_STATUS_CODE),
            sm: [sm(2), sm(3)],
            pdi_wd_expired: esc.pdi_watchdog_expired(),
            slot_writes: self.flash.slot_writes,
        }
    }

    /// One firmware pass at the current time, then every check.
    fn pass(&mut self) {
        let result = self
            .slave
            .poll_with(self.now_ns, Some(&mut *self.flash as &mut dyn ImageStore));
        self.passes += 1;
        let after = self.observe();
        let before = core::mem::replace(&mut self.last, after.clone());
        let ctx = PassContext {
            now_ns: self.now_ns,
            stalled: self.stalled,
            failed: result.is_err() && !self.stalled,
            pdi_fault: self.pdi_fault,
            full_pass_ns: FULL_PASS_NS + MS,
        };
        self.shadow.consume(&before, &after, self.stalled);
        // A pass that reached the ESC wrote the AL status again first.
        if !ctx.failed && !self.stalled {
            self.shadow.status_stale = false;
        }
        if let Some((inv, detail)) = self.shadow.check_pass(&before, &after, &ctx) {
            let detail = format!("{detail} (t = {} ms)", self.now_ns / MS);
            self.violate(inv, detail);
        }
        self.shadow.mailbox_written = false;
        if ctx.failed {
            self.shadow.status_stale = true;
        }
        // The unlock ends at INIT (P6), unless a password write is still
        // waiting in the mailbox.
        if !self.stalled && after.state == AlState::Init {
            self.shadow.unlock = if self.shadow.password_outstanding {
                Unlock::Maybe
            } else {
                Unlock::No
            };
        }
        // A SAVE still waiting may store what 0xF80F holds now.
        if self.shadow.save_outstanding {
            self.note_save_candidate();
        }
    }

    fn wait(&mut self, ms: u64) {
        for _ in 0..ms {
            self.now_ns += MS;
            self.pass();
        }
    }

    // --- frames -----------------------------------------------------------

    /// One frame of datagrams through the ESC; the data and working
    /// counter of each. No firmware pass.
    fn frame(&mut self, dgs: &[(Command, u16, &[u8])]) -> Vec<(Vec<u8>, u16)> {
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
    fn write_reg(&mut self, ado: u16, data: &[u8]) -> bool {
        self.now_ns += FRAME_NS;
        let r = self.frame(&[(Command::Apwr, ado, data)]);
        if matches!(ado, reg::WATCHDOG_DIVIDER..=0x0421) {
            self.shadow.wd_written_at = Some(self.now_ns);
        }
        self.pass();
        r.first().is_some_and(|(_, w)| *w == 1)
    }

    /// A register read in its own frame, then a firmware pass.
    fn read_reg(&mut self, ado: u16, len: usize) -> Option<Vec<u8>> {
        self.now_ns += FRAME_NS;
        let zeros = vec![0u8; len];
        let r = self.frame(&[(Command::Aprd, ado, &zeros)]);
        self.pass();
        r.into_iter()
            .next()
            .filter(|(_, w)| *w == 1)
            .map(|(d, _)| d)
    }

    fn sm_bytes(n: usize, start: u16, len: u16) -> [u8; 8] {
        let s = start.to_le_bytes();
        let l = len.to_le_bytes();
        let control = SM_CONTROL.get(n).copied().unwrap_or(0);
        [s[0], s[1], l[0], l[1], control, 0, 1, 0]
    }

    fn write_sm(&mut self, n: u16, bytes: &[u8; 8]) {
        let _ = self.write_reg(reg::SM_BASE + 8 * n, bytes);
    }

    // --- AL control ---------------------------------------------------------

    fn request(&mut self, state: Request, ack: bool) {
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

    fn mailbox_sms(&mut self, boot: bool) {
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
    fn assigned_len(&self, assign: u16) -> u16 {
        let od = self.slave.slave().od();
        let n = od.get(assign, 0).unwrap_or(0).clamp(0, 254) as u8;
        let bits: u32 = (1..=n)
            .map(|s| pdo_bits(od.get(assign, s).unwrap_or(0) as u16))
            .sum();
        bits.div_ceil(8) as u16
    }

    fn process_data_sms(&mut self, sm2: SmSetting, sm3: SmSetting) {
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
    fn output_image(&mut self, outputs: Outputs, len: usize) -> (Vec<u8>, [bool; 3]) {
        let mut bytes = vec![0u8; len];
        let assign = &self.last.rx_assign;
        if self.layout.as_ref().is_none_or(|(a, _)| a != assign) {
            let mut layout = Vec::new();
            let mut offset = 0usize;
            for pdo in super::model::assigned(assign) {
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
    fn cycle_frame(&mut self, outputs: Outputs) {
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

    fn observe_sm2(&self) -> (bool, u16) {
        let mem = self.slave.slave().esc().raw_memory();
        let base = usize::from(reg::SM_BASE + 16);
        let act = mem.get(base + 6).copied().unwrap_or(0);
        let len = match mem.get(base + 2..base + 4) {
            Some(&[l, h]) => u16::from_le_bytes([l, h]),
            _ => 0,
        };
        (act & 1 != 0, len)
    }

    fn cycles(&mut self, count: u8, outputs: Outputs) {
        self.master.outputs = Some(outputs);
        for _ in 0..count.max(1) {
            self.now_ns += MS;
            self.cycle_frame(outputs);
            self.pass();
        }
    }

    /// `ms` milliseconds in which the master keeps cycling with its last
    /// outputs (if it has sent any) while something else happens.
    fn keep_cycling(&mut self, ms: u64) {
        for _ in 0..ms {
            self.now_ns += MS;
            if let Some(o) = self.master.outputs {
                self.cycle_frame(o);
            }
            self.pass();
        }
    }

    // --- mailbox ----------------------------------------------------------

    /// Reads away what earlier requests left (answers that came too late
    /// for their request, emergencies) until SM0 and SM1 are both empty
    /// after a pass: then no earlier request waits or is being answered,
    /// and the next answer belongs to the next request (two requests for
    /// the same object cannot be told apart by their answers).
    fn mbx_drain(&mut self) {
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

    fn mbx_send(&mut self, ty: MailboxType, payload: &[u8]) -> bool {
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
    fn mbx_read(&mut self) -> Option<(MailboxType, Vec<u8>)> {
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
    fn mbx_exchange(
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
    fn sdo(&mut self, req: &SdoRequest<'_>, expect: Option<(u16, u8)>) -> Option<Vec<u8>> {
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
    fn sdo_room(&self) -> usize {
        self.master
            .mailbox
            .map_or(0, |((_, l), _)| usize::from(l))
            .saturating_sub(MBX_HEADER + 2 + 8)
    }

    fn download(&mut self, index: u16, sub: u8, complete: bool, data: &[u8]) -> Answer {
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

    fn upload(&mut self, index: u16, sub: u8, complete: bool) -> Option<Vec<u8>> {
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

    fn sdo_download(&mut self, index: u16, sub: u8, value: Value, complete: Option<u8>) {
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

    fn note_save_candidate(&mut self) {
        let f = self.last.f80f;
        if !self.shadow.saved_f80f.contains(&f) {
            self.shadow.saved_f80f.push(f);
        }
    }

    // --- power and the bootloader -------------------------------------------

    /// Power off and on; `confirm`: the started image confirms itself.
    fn power_on(&mut self, confirm: bool) {
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
        let (rx, tx) = super::model::function_pdos(o.function);
        let ok = super::model::assigned(&o.rx_assign).all(|p| rx.contains(&p))
            && super::model::assigned(&o.tx_assign).all(|p| tx.contains(&p));
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
    fn check_boot(&mut self, d: &BootDecision) {
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

    fn efw(&mut self, image: Image) -> Vec<u8> {
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

    fn foe(&mut self, request: &FoeRepr<'_>) -> Option<Vec<u8>> {
        let mut b = vec![0u8; request.buffer_len()];
        let n = request.emit(&mut b).ok()?;
        b.truncate(n);
        let (_, p) = self.mbx_exchange(MailboxType::FoE, &b, |t, _| t == MailboxType::FoE)?;
        Some(p)
    }

    /// Whether the flash lost power; if so the slave is power cycled.
    fn flash_cut(&mut self) -> bool {
        if self.flash.mem.is_powered() {
            return false;
        }
        self.power_on(true);
        true
    }

    fn foe_download(
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

    fn bring_up(&mut self, target: Target) {
        self.request(Request::Init, true);
        if target == Target::Boot {
            self.mailbox_sms(true);
            self.request(Request::Boot, true);
            return;
        }
        self.mailbox_sms(false);
        self.request(Request::PreOp, true);
        if target == Target::PreOp {
            return;
        }
        self.process_data_sms(SmSetting::Image, SmSetting::Image);
        self.request(Request::SafeOp, true);
        if target == Target::SafeOp {
            return;
        }
        let outputs = Outputs::Values {
            enable: 0x07,
            command: 4000,
        };
        self.cycles(5, outputs);
        self.request(Request::Op, true);
        self.cycles(20, outputs);
    }

    /// Runs one action (then the checks already ran after each pass).
    pub fn act(&mut self, a: &Action) {
        match *a {
            Action::BringUp { target } => self.bring_up(target),
            Action::Mailbox { boot } => self.mailbox_sms(boot),
            Action::ProcessData { sm2, sm3 } => self.process_data_sms(sm2, sm3),
            Action::Request { state, ack } => self.request(state, ack),
            Action::Cycles { count, outputs } => self.cycles(count, outputs),
            Action::Silence { ms } => self.wait(u64::from(ms.min(500))),
            Action::TimeJump { ms } => {
                self.now_ns = self.now_ns.saturating_add(u64::from(ms) * MS);
                self.pass();
            }
            Action::Watchdog { time } => {
                if time == 0 && self.last.wd_time != 0 {
                    self.shadow.wd_zero_since = Some(self.now_ns + FRAME_NS);
                } else if time != 0 {
                    self.shadow.wd_zero_since = None;
                }
                self.write_reg(reg::WATCHDOG_TIME_PD, &time.to_le_bytes());
            }
            Action::Download {
                index,
                sub,
                value,
                complete,
            } => self.sdo_download(index, sub, value, complete),
            Action::Upload {
                index,
                sub,
                complete,
            } => {
                let _ = self.upload(index, sub, complete);
            }
            Action::PowerCycle { confirm } => self.power_on(confirm),
            Action::CutSave { after } => {
                self.slave
                    .slave_mut()
                    .app_mut()
                    .pam_mut()
                    .nv_mut()
                    .cut_power_after(usize::from(after));
                self.sdo_download(0xF801, 2, Value::One, None);
                self.power_on(true);
            }
            Action::PdiFault {
                region,
                reads,
                writes,
                ms,
            } => {
                let (start, end) = region_range(region);
                self.slave
                    .slave_mut()
                    .esc_mut()
                    .set_pdi_fault(Some(PdiFault {
                        start,
                        end,
                        reads,
                        writes,
                    }));
                self.pdi_fault = true;
                self.keep_cycling(u64::from(ms) + 1);
                self.slave.slave_mut().esc_mut().set_pdi_fault(None);
                self.pdi_fault = false;
                self.keep_cycling(1);
            }
            Action::Stall { ms } => {
                self.slave.set_stalled(true);
                self.stalled = true;
                self.keep_cycling(u64::from(ms.min(500)));
                self.slave.set_stalled(false);
                self.stalled = false;
                self.keep_cycling(1);
            }
            Action::Foe {
                image,
                password,
                stop_after,
                cut_after,
            } => self.foe_download(image, password, stop_after, cut_after),
            Action::BootRecords { readable } => self.flash.unreadable = !readable,
            Action::Stage(e) => {
                let stage = self.slave.slave_mut().app_mut().pam_mut().stage_mut();
                let s = |c: Coil| match c {
                    Coil::A => Solenoid::A,
                    Coil::B => Solenoid::B,
                };
                match e {
                    StageEvent::OpenWire(c) => stage.inject(Fault::OpenWire(s(c))),
                    StageEvent::Short(c) => stage.inject(Fault::ShortCircuit(s(c))),
                    StageEvent::Supply(v) => stage.inject(Fault::SupplyVoltage(f32::from(v))),
                    StageEvent::Temperature(t) => {
                        stage.inject(Fault::Temperature(f32::from(t)));
                    }
                    StageEvent::Clear => stage.clear_faults(),
                }
                self.keep_cycling(1);
            }
            Action::CorruptNv { at, xor } => {
                let nv = self.slave.slave_mut().app_mut().pam_mut().nv_mut();
                let bytes = nv.bytes_mut();
                let n = bytes.len();
                if let Some(b) = bytes.get_mut(usize::from(at) % n.max(1)) {
                    *b ^= xor.max(1);
                }
            }
            Action::CorruptSlot { at, mask } => {
                let slot = self
                    .flash
                    .mem
                    .read_state()
                    .map_or(Slot::B, |s| s.active.other());
                let used = self
                    .flash
                    .slot(slot)
                    .iter()
                    .rposition(|b| *b != 0xFF)
                    .map_or(1, |p| p + 1);
                let _ = self.flash.mem.write(slot, usize::from(at) % used, &[mask]);
            }
        }
    }
}

/// Flat positions of the entries every observation reads (looked up
/// once).
struct Flats {
    function: usize,
    sens: usize,
    f80f: [usize; 2],
    diag: [usize; 8],
    rx_assign: Vec<usize>,
    tx_assign: Vec<usize>,
    rx: Vec<usize>,
}

fn flats() -> &'static Flats {
    static FLATS: std::sync::OnceLock<Flats> = std::sync::OnceLock::new();
    FLATS.get_or_init(|| {
        let at = |i: u16, s: u8| DICT.find_entry(i, s).map_or(0, |(flat, _)| flat);
        let list = |i: u16| -> Vec<usize> {
            let n = DICT.find(i).map_or(0, |(_, o)| o.max_sub());
            (0..=n).map(|s| at(i, s)).collect()
        };
        let d = [
            (0xA000, 1),
            (0xA000, 2),
            (0xA000, 3),
            (0xA000, 4),
            (0xA010, 1),
            (0xA010, 2),
            (0xA020, 1),
            (0xA020, 2),
        ];
        Flats {
            function: at(0xF800, 2),
            sens: at(0xF800, 3),
            f80f: [at(0xF80F, 1), at(0xF80F, 2)],
            diag: d.map(|(i, s)| at(i, s)),
            rx_assign: list(0x1C12),
            tx_assign: list(0x1C13),
            rx: DICT
                .entries()
                .filter(|(_, _, e)| e.pdo == PdoMapping::Rx)
                .map(|(flat, _, _)| flat)
                .collect(),
        }
    })
}

/// The core's bootloader, as a [`Bootloader`].
fn firmware_power_on(store: &mut dyn ImageStore) -> BootDecision {
    firmware::power_on(store)
}

trait RestorePower {
    fn pam_restore_power(&mut self);
}

impl<D: Device> RestorePower for SoftSlave<D> {
    fn pam_restore_power(&mut self) {
        self.slave_mut()
            .app_mut()
            .pam_mut()
            .nv_mut()
            .restore_power();
    }
}

fn region_range(r: PdiRegion) -> (u16, u16) {
    let layout = DEVICE.layout();
    match r {
        PdiRegion::All => (0, u16::MAX),
        PdiRegion::Al => (reg::AL_CONTROL, reg::AL_STATUS_CODE + 2),
        PdiRegion::Events => (reg::AL_EVENT_REQUEST, reg::AL_EVENT_REQUEST + 4),
        PdiRegion::Watchdog => (reg::WATCHDOG_DIVIDER, 0x0450),
        PdiRegion::SyncManagers => (reg::SM_BASE, reg::SM_BASE + 32),
        PdiRegion::Mailbox => (
            layout.mbx_out.0.min(layout.boot_out.0),
            layout.mbx_in.0 + layout.mbx_in.1.max(layout.boot_in.1),
        ),
        PdiRegion::ProcessData => (layout.pd_out, layout.pd_in + 128),
    }
}

/// The default image length of an assignment object (the SII's SM length).
fn default_len(assign: u16) -> u16 {
    let Some((_, obj)) = DICT.find(assign) else {
        return 0;
    };
    let count = obj.entry(0).map_or(0, |e| match e.default {
        DefaultValue::Int(v) => v,
        DefaultValue::Str(_) | DefaultValue::Bytes(_) => 0,
    });
    let bits: u32 = obj
        .entries
        .iter()
        .filter(|e| e.sub != 0 && i64::from(e.sub) <= count)
        .filter_map(|e| match e.default {
            DefaultValue::Int(v) => Some(v as u16),
            DefaultValue::Str(_) | DefaultValue::Bytes(_) => None,
        })
        .map(pdo_bits)
        .sum();
    bits.div_ceil(8) as u16
}

fn put_bits(buf: &mut [u8], at: usize, bits: usize, v: u64) {
    for i in 0..bits.min(64) {
        let bit = (v >> i) & 1;
        let pos = at + i;
        if let Some(b) = buf.get_mut(pos / 8) {
            *b |= (bit as u8) << (pos % 8);
        }
    }
}

fn get_bits(buf: &[u8], at: usize, bits: usize) -> u64 {
    let mut v = 0u64;
    for i in 0..bits.min(64) {
        let pos = at + i;
        let bit = buf.get(pos / 8).map_or(0, |b| (b >> (pos % 8)) & 1);
        v |= u64::from(bit) << i;
    }
    v
}

/// The bytes of `value` for `entry` (4 bytes when the entry is unknown).
fn encode_value(value: Value, entry: Option<&ecat_slave::od::Entry>) -> Vec<u8> {
    let bytes = entry.map_or(4, |e| match e.data_type {
        DataType::Bool => 1,
        _ => usize::from(e.bit_len).div_ceil(8).max(1),
    });
    let default = entry.and_then(|e| match e.default {
        DefaultValue::Int(v) => Some(v),
        DefaultValue::Str(_) | DefaultValue::Bytes(_) => None,
    });
    let v: i64 = match value {
        Value::Zero => 0,
        Value::One => 1,
        Value::Two => 2,
        Value::Default => default.unwrap_or(0),
        Value::Min => entry.and_then(|e| e.min).unwrap_or(0),
        Value::Max => entry.and_then(|e| e.max).unwrap_or(-1),
        Value::Password => i64::from(VENDOR_PASSWORD),
        Value::Pdo(p) => i64::from(PDOS.get(usize::from(p)).copied().unwrap_or(0)),
        Value::Raw(x) => i64::from(x),
    };
    let le = v.to_le_bytes();
    let mut out: Vec<u8> = le.iter().take(bytes.min(8)).copied().collect();
    out.resize(bytes, 0);
    if let Some(e) = entry
        && matches!(e.data_type, DataType::VisibleString)
    {
        out = b"inv".to_vec();
    }
    out
}

fn decode_i64(bytes: &[u8]) -> i64 {
    let mut raw = [0u8; 8];
    for (d, s) in raw.iter_mut().zip(bytes) {
        *d = *s;
    }
    i64::from_le_bytes(raw)
}

/// An observation before the first pass.
fn placeholder() -> Observation {
    Observation {
        state: AlState::Init,
        error: false,
        code: 0,
        setpoints: [0, 0],
        function: 1,
        sens: 2,
        rx_assign: Vec::new(),
        tx_assign: Vec::new(),
        f80f: [0, 0],
        rx_entries: Vec::new(),
        eeprom_error: false,
        diag: [false; 8],
        wd_time: 1000,
        wd_status: 1,
        al_status_reg: 1,
        al_code_reg: 0,
        sm: [(false, 0); 2],
        pdi_wd_expired: false,
        slot_writes: 0,
    }
}
