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
use crate::board::{Fault, Solenoid};
use crate::description::od::DICT;
use crate::{DEVICE, PRODUCT_CODE, Pam, REVISION, VENDOR_ID, VENDOR_PASSWORD};

mod boot;
mod mailbox;
mod wire;

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
                .filter(|(_, _, e)| e.pdo() == PdoMapping::Rx)
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
    let count = obj.entry(0).map_or(0, |e| match e.default_value() {
        DefaultValue::Int(v) => v.get(),
        DefaultValue::Str(_) | DefaultValue::Bytes(_) => 0,
    });
    let bits: u32 = obj
        .entries
        .iter()
        .filter(|e| e.sub != 0 && i64::from(e.sub) <= count)
        .filter_map(|e| match e.default_value() {
            DefaultValue::Int(v) => Some(v.get() as u16),
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
    let default = entry.and_then(|e| match e.default_value() {
        DefaultValue::Int(v) => Some(v.get()),
        DefaultValue::Str(_) | DefaultValue::Bytes(_) => None,
    });
    let v: i64 = match value {
        Value::Zero => 0,
        Value::One => 1,
        Value::Two => 2,
        Value::Default => default.unwrap_or(0),
        Value::Min => entry.and_then(|e| e.min()).unwrap_or(0),
        Value::Max => entry.and_then(|e| e.max()).unwrap_or(-1),
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
