//! The software EtherCAT Slave Controller.
//!
//! [`SoftEsc`] holds the ESC memory (registers 0x0000-0x0FFF and process RAM
//! from 0x1000), processes every datagram of an EtherCAT frame in place the
//! way silicon does (addressing, working counter, SyncManager and FMMU rules,
//! the SII EEPROM interface) and offers the PDI side through [`Esc`].
//!
//! Nothing here panics on input: every address computation is checked, an
//! access that wraps past 0xFFFF or is refused by a SyncManager leaves memory
//! untouched and does not count in the working counter.

pub mod dc;

use dc::DcClock;
use ecat_slave::esc::registers::{self as reg, sm as smr};
use ecat_slave::esc::{Esc, EscError};
use ecat_slave::wire::ecat::{Command, Datagram, DatagramCursor, EcatFrame, FrameType};
use ecat_slave::wire::ethernet::{ETHERTYPE_ETHERCAT, EthernetFrame};

/// Size of the ESC address space modelled: 4 KiB registers + 8 KiB process RAM.
pub const MEM_SIZE: usize = 0x3000;
/// Number of SyncManagers implemented.
pub const SM_COUNT: usize = 8;
/// Number of FMMUs implemented.
pub const FMMU_COUNT: usize = 8;
/// ESC configuration register 0x0141 bit 0, "device emulation": the AL
/// status follows the AL control register (ESCs without a firmware).
pub const ESC_CONFIG_DEVICE_EMULATION: u8 = 0x01;

pub use ecat_slave::sii::SII_SIZE;
/// Longest datagram payload the ESC processes (an Ethernet frame's worth).
pub const MAX_DATAGRAM: usize = 1500;

/// What [`SoftEsc::process_frame`] did with a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameOutcome {
    /// The frame was an EtherCAT frame and was processed (possibly partly,
    /// when a later datagram was malformed).
    Processed {
        /// Number of datagrams handled.
        datagrams: usize,
    },
    /// Not an EtherCAT frame (other EtherType): forwarded untouched.
    NotEthercat,
    /// The frame is too short or its EtherCAT header is inconsistent:
    /// forwarded untouched.
    Malformed,
}

/// Cached configuration of one SyncManager.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct SmConfig {
    start: u16,
    len: u16,
    control: u8,
    enabled: bool,
    /// The activation register as written (enable, repeat request, ...).
    activate: u8,
}

impl SmConfig {
    fn is_mailbox(&self) -> bool {
        self.control & 0x03 == smr::MODE_MAILBOX
    }
    fn ecat_writes(&self) -> bool {
        self.control & 0x0C == smr::DIR_ECAT_WRITE
    }
    /// End address (exclusive) of the buffer.
    fn end(&self) -> u32 {
        u32::from(self.start) + u32::from(self.len)
    }
    /// Whether `[a, b)` overlaps the buffer.
    fn overlaps(&self, a: u32, b: u32) -> bool {
        self.enabled && self.len > 0 && a < self.end() && u32::from(self.start) < b
    }
    /// Whether `[a, b)` covers the last byte of the buffer.
    fn covers_last(&self, a: u32, b: u32) -> bool {
        let last = self.end() - 1;
        a <= last && last < b
    }
}

/// Cached configuration of one FMMU.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct FmmuConfig {
    logical: u32,
    len: u16,
    start_bit: u8,
    stop_bit: u8,
    physical: u16,
    physical_bit: u8,
    read: bool,
    write: bool,
    enabled: bool,
}

impl FmmuConfig {
    /// Logical range in bytes [start, end).
    fn logical_end(&self) -> u64 {
        u64::from(self.logical) + u64::from(self.len)
    }
    fn byte_aligned(&self) -> bool {
        self.start_bit == 0 && self.stop_bit == 7 && self.physical_bit == 0
    }
}

/// Direction of one ECAT-side physical access.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ReadMode {
    /// Replace the frame data with memory contents.
    Copy,
    /// OR memory contents into the frame data (broadcast reads).
    Or,
}

/// The software ESC.
pub struct SoftEsc {
    mem: [u8; MEM_SIZE],
    sii: [u8; SII_SIZE],
    sms: [SmConfig; SM_COUNT],
    fmmus: [FmmuConfig; FMMU_COUNT],
    /// Bit n set: FMMU n enabled (fast skip in logical addressing).
    fmmu_active: u8,
    /// Bumped whenever the FMMU configuration may have changed.
    fmmu_gen: u32,
    /// PDI reads and writes since power-on (what an SPI bus would carry).
    pdi_accesses: u64,
    /// Bit n set: SM n enabled with a non-zero length.
    sm_active: u8,
    /// Bit n set: an ECAT write completed the buffer of output SM n since the
    /// last [`SoftEsc::take_sm_writes`].
    sm_written: u16,
    /// Cached 0x0010 / 0x0012 for configured addressing (hot path).
    station: u16,
    alias: u16,
    /// An output SM with watchdog trigger was completed since the last
    /// watchdog update.
    wd_sm_trigger: bool,
    /// Time the SM watchdog was last re-armed (None: not armed yet).
    wd_sm_armed_at: Option<u64>,
    /// The PDI accessed the ESC since the last watchdog update.
    pdi_touched: bool,
    /// Time of the last PDI access seen by the watchdog.
    wd_pdi_at: Option<u64>,
    /// The master wrote a watchdog divider or time: both watchdogs restart
    /// their count at the next update.
    wd_restart: bool,
    /// Injected PDI failure (tests of the firmware's fail-safe paths).
    pdi_fault: Option<PdiFault>,
    /// Counts changes of the station address or alias (lets a line keep
    /// its address index current).
    addr_gen: u32,
    /// The Distributed Clocks unit's oscillator and drift control.
    dc: DcClock,
    /// Injected time at which the current frame passes port 0 (and comes
    /// back through port 1, when port 1 is open), for the DC unit.
    dc_port0_ns: u64,
    dc_port1_ns: Option<u64>,
    /// System time of the next SYNC0 pulse while SYNC0 is active.
    sync0_next: Option<u64>,
    /// SYNC0 pulses since power-on, and the system time of the last.
    sync0_pulses: u64,
    sync0_last: Option<u64>,
}

/// A PDI failure injected into the software ESC: PDI accesses that touch
/// `start..end` fail with [`EscError::Interface`], as an SPI error on a
/// hardware ESC would. The frame side is not affected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdiFault {
    /// First address that fails.
    pub start: u16,
    /// One past the last address that fails.
    pub end: u16,
    /// PDI reads fail.
    pub reads: bool,
    /// PDI writes fail.
    pub writes: bool,
}

impl PdiFault {
    /// Every PDI access (read and write) fails.
    pub const ALL: PdiFault = PdiFault {
        start: 0,
        end: u16::MAX,
        reads: true,
        writes: true,
    };

    /// Reads of `start..end` fail.
    pub const fn reads(start: u16, end: u16) -> Self {
        PdiFault {
            start,
            end,
            reads: true,
            writes: false,
        }
    }

    fn hits(&self, a: u32, b: u32, write: bool) -> bool {
        let dir = if write { self.writes } else { self.reads };
        dir && a < u32::from(self.end) && u32::from(self.start) < b
    }
}

impl core::fmt::Debug for SoftEsc {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SoftEsc")
            .field("station_address", &self.mem_u16(reg::STATION_ADDRESS))
            .field("al_status", &self.mem_u16(reg::AL_STATUS))
            .finish_non_exhaustive()
    }
}

impl SoftEsc {
    /// Creates an ESC in its power-on state, loading the SII image `sii`
    /// (truncated to [`SII_SIZE`], the rest reads 0xFF) and taking the
    /// station alias and PDI configuration from it.
    pub fn new(sii: &[u8]) -> Self {
        let mut esc = SoftEsc {
            mem: [0; MEM_SIZE],
            sii: [0xFF; SII_SIZE],
            sms: [SmConfig::default(); SM_COUNT],
            fmmus: [FmmuConfig::default(); FMMU_COUNT],
            fmmu_active: 0,
            fmmu_gen: 0,
            pdi_accesses: 0,
            sm_active: 0,
            sm_written: 0,
            station: 0,
            alias: 0,
            wd_sm_trigger: false,
            wd_sm_armed_at: None,
            pdi_touched: false,
            wd_pdi_at: None,
            wd_restart: false,
            pdi_fault: None,
            addr_gen: 0,
            dc: DcClock::default(),
            dc_port0_ns: 0,
            dc_port1_ns: None,
            sync0_next: None,
            sync0_pulses: 0,
            sync0_last: None,
        };
        let n = sii.len().min(SII_SIZE);
        if let (Some(dst), Some(src)) = (esc.sii.get_mut(..n), sii.get(..n)) {
            dst.copy_from_slice(src);
        }
        esc.power_on();
        esc
    }

    /// Programs a whole SII image into the EEPROM (truncated to
    /// [`SII_SIZE`], the rest erased to 0xFF), as a configurator writes a
    /// device's EEPROM; the ESC loads it at its next power-on.
    pub fn program_sii(&mut self, image: &[u8]) {
        self.sii = [0xFF; SII_SIZE];
        let n = image.len().min(SII_SIZE);
        if let (Some(dst), Some(src)) = (self.sii.get_mut(..n), image.get(..n)) {
            dst.copy_from_slice(src);
        }
    }

    /// Programs the station alias into the SII image (word 4, checksum of
    /// words 0..6 recomputed), as a configurator writes it to a device's
    /// EEPROM. The ESC loads it into 0x0012 at its next power-on (the
    /// alias register is loaded from the EEPROM only then).
    pub fn program_sii_alias(&mut self, alias: u16) {
        if let Some(w) = self.sii.get_mut(8..10) {
            w.copy_from_slice(&alias.to_le_bytes());
        }
        let crc = self.sii.get(..14).map_or(0, ecat_slave::sii::crc8);
        if let Some(c) = self.sii.get_mut(14) {
            *c = crc;
        }
    }

    /// Makes PDI accesses fail as `fault` says (`None`: the PDI works).
    pub fn set_pdi_fault(&mut self, fault: Option<PdiFault>) {
        self.pdi_fault = fault;
    }

    /// Resets every register to its power-on value (as a power cycle does);
    /// process RAM is cleared, the SII image is kept.
    pub fn power_on(&mut self) {
        self.mem = [0; MEM_SIZE];
        self.sms = [SmConfig::default(); SM_COUNT];
        self.fmmus = [FmmuConfig::default(); FMMU_COUNT];
        self.fmmu_active = 0;
        self.fmmu_gen = self.fmmu_gen.wrapping_add(1);
        self.sm_active = 0;
        self.sm_written = 0;
        self.wd_sm_trigger = false;
        self.wd_sm_armed_at = None;
        self.pdi_touched = false;
        self.wd_pdi_at = None;
        self.set_u8(reg::TYPE, 0x11);
        self.set_u8(reg::REVISION, 0x02);
        self.set_u8(reg::FMMU_COUNT, FMMU_COUNT as u8);
        self.set_u8(reg::SM_COUNT, SM_COUNT as u8);
        self.set_u8(reg::RAM_SIZE, ((MEM_SIZE - 0x1000) / 1024) as u8);
        // Ports 0 and 1 MII, ports 2 and 3 not implemented.
        self.set_u8(reg::PORT_DESCRIPTOR, 0x0F);
        // Bit-oriented FMMUs, LRW and read/write commands supported; DC
        // receive times and a 64-bit system time (bits 2 and 3) and the
        // SYNC0 unit with the activation registers 0x0981-0x0984 (bit 8,
        // "enhanced DC sync activation"); ETG.1000.4 Table 31. No LATCH
        // inputs and no SYNC1 pulses yet.
        self.set_u16(reg::FEATURES, 0x010C);
        self.dc.power_on(self.dc_port0_ns);
        self.sync0_next = None;
        self.sync0_last = None;
        // DC control loop defaults (ET1100 Section II, 0x0930-0x0935).
        self.set_u16(reg::DC_SPEED_COUNTER_START, 0x1000);
        self.set_u8(reg::DC_TIME_FILTER_DEPTH, 4);
        self.set_u8(reg::DC_SPEED_FILTER_DEPTH, 12);
        let alias = self.sii_word(4);
        self.set_u16(reg::STATION_ALIAS, alias);
        self.refresh_address();
        let pdi = self.sii_word(0);
        self.set_u8(reg::PDI_CONTROL, (pdi & 0xFF) as u8);
        self.set_u8(reg::ESC_CONFIG, (pdi >> 8) as u8);
        let pdi_cfg = self.sii_word(1);
        self.set_u16(reg::PDI_CONFIG, pdi_cfg);
        self.set_u16(reg::AL_STATUS, 0x0001);
        self.set_u16(reg::WATCHDOG_DIVIDER, 2498);
        self.set_u16(reg::WATCHDOG_TIME_PDI, 1000);
        self.set_u16(reg::WATCHDOG_TIME_PD, 1000);
        self.set_u16(reg::WATCHDOG_STATUS_PD, 0x0001);
        // Every AL event reaches the IRQ line but the SM8-15 ones and the
        // reserved bits 4..7 of the first byte: the ET1100's reset value of
        // the AL event mask (ET1100 Section II, register 0x0204: 0x00FFFF0F).
        // Only the IRQ output uses it; 0x0220 shows every event regardless.
        self.set_u32(reg::AL_EVENT_MASK, 0x00FF_FF0F);
        // 8-byte EEPROM reads.
        self.set_u16(reg::SII_CONTROL, 0x0040);
        self.set_port1_link(false);
    }

    /// The configured station address (0x0010).
    pub fn station_address(&self) -> u16 {
        self.station
    }

    /// A number that changes whenever the station address or alias does
    /// (a line rebuilds its address index when it sees a new one).
    pub fn address_generation(&self) -> u32 {
        self.addr_gen
    }

    /// Takes the station address and alias registers into the cache that
    /// configured addressing uses, counting a change.
    fn refresh_address(&mut self) {
        let station = self.mem_u16(reg::STATION_ADDRESS);
        let alias = self.mem_u16(reg::STATION_ALIAS);
        if (station, alias) != (self.station, self.alias) {
            self.station = station;
            self.alias = alias;
            self.addr_gen = self.addr_gen.wrapping_add(1);
        }
    }

    /// The configured station alias (0x0012).
    pub fn station_alias(&self) -> u16 {
        self.alias
    }

    /// Sets whether port 1 has a link (a slave that is not last in a chain
    /// has one). Updates DL status 0x0110 accordingly.
    pub fn set_port1_link(&mut self, link: bool) {
        // Bit 0 PDI operational, bit 1 PDI watchdog ok, bit 4 link port 0,
        // bit 9 communication port 0.
        let mut dl = 0x0203u16 | 0x0010;
        if link {
            dl |= 0x0020 | 0x0800;
        } else {
            // Loop port 1 closed.
            dl |= 0x0400;
        }
        let keep = self.mem_u16(reg::DL_STATUS) & 0x0002;
        self.set_u16(reg::DL_STATUS, (dl & !0x0002) | keep | 0x0002);
    }

    /// Counts a frame that arrived on `port` with a bad checksum (a bit
    /// flip, a runt): the invalid frame counter of the port (0x0300 +
    /// 2 x port, saturating at 255, cleared by any ECAT write) goes up; the
    /// ESC does not act on such a frame.
    pub fn count_invalid_frame(&mut self, port: u8) {
        let a = reg::RX_ERROR_COUNTER + 2 * u16::from(port.min(3));
        let v = self.mem_u8(a);
        self.set_u8(a, v.saturating_add(1));
    }

    /// Counts a loss of link on `port` (lost link counter 0x0310 + port,
    /// saturating at 255, cleared by any ECAT write).
    pub fn count_lost_link(&mut self, port: u8) {
        let a = 0x0310 + u16::from(port.min(3));
        let v = self.mem_u8(a);
        self.set_u8(a, v.saturating_add(1));
    }

    /// Sets or clears DL status bit 1, "PDI watchdog not expired".
    pub fn set_pdi_watchdog_ok(&mut self, ok: bool) {
        let dl = self.mem_u16(reg::DL_STATUS);
        self.set_u16(reg::DL_STATUS, if ok { dl | 0x0002 } else { dl & !0x0002 });
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
        if pdi_ticks != 0 && now_ns.saturating_sub(last) >= pdi_ticks * base && dl & 0x0002 != 0 {
            self.set_pdi_watchdog_ok(false);
            let c = self.mem_u8(reg::WATCHDOG_COUNTER_PDI).saturating_add(1);
            self.set_u8(reg::WATCHDOG_COUNTER_PDI, c);
        }
    }

    /// The injected times at which the next datagrams pass this ESC's
    /// port 0 (on the way down the line) and port 1 (on the way back;
    /// `None` when port 1 is closed): what the DC unit latches as receive
    /// times and reads its clock at. A line sets them per slave from its
    /// position and hop delay.
    pub fn set_frame_times(&mut self, port0_ns: u64, port1_ns: Option<u64>) {
        // Time only moves forward for a clock (a frame stamped earlier
        // than what the ESC has seen is taken as now).
        self.dc_port0_ns = port0_ns.max(self.dc_port0_ns);
        self.dc_port1_ns = port1_ns.map(|t| t.max(self.dc_port0_ns));
    }

    /// Makes this ESC's oscillator run `error_ppb` parts per billion fast
    /// (negative: slow) from the current frame time on.
    pub fn set_dc_oscillator(&mut self, error_ppb: i64) {
        self.dc.set_error_ppb(error_ppb, self.dc_port0_ns);
    }

    /// Sets the DC local time to `local_ns` at the current frame time (a
    /// slave powered on earlier or later than its neighbours).
    pub fn set_dc_local_time(&mut self, local_ns: u64) {
        self.dc.set_local(self.dc_port0_ns, local_ns);
    }

    /// The DC unit's clock (oscillator error, drift correction).
    pub fn dc_clock(&self) -> &DcClock {
        &self.dc
    }

    /// The DC local time at injected time `t_ns`.
    pub fn dc_local_time(&self, t_ns: u64) -> u64 {
        self.dc.local(t_ns)
    }

    /// The DC system time (local time + 0x0920 offset) at injected time
    /// `t_ns`, what a read of 0x0910 at that time returns.
    pub fn dc_system_time(&self, t_ns: u64) -> u64 {
        self.dc
            .local(t_ns)
            .wrapping_add(self.mem_u64(reg::DC_SYSTEM_TIME_OFFSET))
    }

    /// The last system time difference (0x092C) as a signed ns value
    /// (own − received).
    pub fn dc_difference(&self) -> i64 {
        dc::difference_of_register(self.mem_u32(reg::DC_SYSTEM_TIME_DIFF))
    }

    /// Runs the SYNC0 unit up to injected time `now_ns`: every pulse due
    /// by then (start time + k × cycle, in system time) sets 0x098E bit 0
    /// and AL event bit 2. Cheap when SYNC0 is off. A line calls this
    /// before it looks for AL events, so a firmware waits on SYNC0 as it
    /// would on its IRQ line.
    pub fn update_dc(&mut self, now_ns: u64) {
        let Some(next) = self.sync0_next else {
            return;
        };
        let now = self.dc_system_time(now_ns);
        if now < next {
            return;
        }
        let cycle = u64::from(self.mem_u32(reg::DC_SYNC0_CYCLE_TIME));
        let (count, last) = match (now - next).checked_div(cycle) {
            // Cycle time 0: a single pulse.
            None => {
                self.sync0_next = None;
                (1, next)
            }
            Some(k) => {
                let last = next + k * cycle;
                self.sync0_next = last.checked_add(cycle);
                (k.saturating_add(1), last)
            }
        };
        self.sync0_pulses = self.sync0_pulses.saturating_add(count);
        self.sync0_last = Some(last);
        let st = self.mem_u8(reg::DC_SYNC0_STATUS) | 0x01;
        self.set_u8(reg::DC_SYNC0_STATUS, st);
        // Only when the SII maps SYNC0 into the AL event request
        // (0x0151 bit 3); else a firmware polls 0x098E or wires SYNC0.
        if self.mem_u8(reg::PDI_CONFIG + 1) & 0x08 != 0 {
            self.raise_al_event(reg::AL_EVENT_SYNC0);
        }
    }

    /// Before a read of `[a, b)` (either side): the system time is the
    /// clock now, not a stored value; 0x0990 reads as the next SYNC0
    /// pulse while the unit runs.
    fn refresh_dc_registers(&mut self, a: u32, b: u32) {
        let st = u32::from(reg::DC_SYSTEM_TIME);
        if a < st + 8 && st < b {
            let now = self.dc_system_time(self.dc_port0_ns);
            self.set_u64(reg::DC_SYSTEM_TIME, now);
        }
        let nx = u32::from(reg::DC_START_TIME);
        if a < nx + 8 && nx < b {
            self.update_dc(self.dc_port0_ns);
            if let Some(next) = self.sync0_next {
                self.set_u64(reg::DC_START_TIME, next);
            }
        }
    }

    /// SYNC0 pulses since power-on.
    pub fn sync0_pulses(&self) -> u64 {
        self.sync0_pulses
    }

    /// System time of the last SYNC0 pulse.
    pub fn sync0_last(&self) -> Option<u64> {
        self.sync0_last
    }

    /// System time of the next SYNC0 pulse (`None`: SYNC0 is off).
    pub fn sync0_next(&self) -> Option<u64> {
        self.sync0_next
    }

    /// ECAT write of the activation register 0x0981: cyclic operation with
    /// SYNC0 (bits 0 and 1) arms the unit at the start time 0x0990; a
    /// start time already past is compared on its low 32 bits, as the
    /// ET1100 does, so the first pulse then comes after the 32-bit system
    /// time wraps around (about 4.3 s later; masters write a start time
    /// ahead of the reference clock's time). Anything else stops it.
    fn dc_activate(&mut self) {
        let act = self.mem_u8(reg::DC_ACTIVATION);
        if act & 0x03 != 0x03 {
            self.sync0_next = None;
            return;
        }
        let now = self.dc_system_time(self.dc_port0_ns);
        let mut start = self.mem_u64(reg::DC_START_TIME);
        if start < now {
            let wraps = (now - start).div_ceil(1 << 32);
            start = start.saturating_add(wraps.saturating_mul(1 << 32));
        }
        self.sync0_next = Some(start);
    }

    /// ECAT write to 0x0900: every port's receive time latched (local
    /// time of the frame at the port), and the processing unit's.
    fn dc_latch(&mut self) {
        let t0 = self.dc.local(self.dc_port0_ns);
        self.set_u32(reg::DC_RECEIVE_TIME_PORT0, t0 as u32);
        if let Some(t1) = self.dc_port1_ns {
            let t1 = self.dc.local(t1);
            self.set_u32(reg::DC_RECEIVE_TIME_PORT0 + 4, t1 as u32);
        }
        self.set_u64(reg::DC_RECEIVE_TIME_PU, t0);
    }

    /// ECAT write of a system time (`len` 4 or 8 bytes at 0x0910): the
    /// drift control compares it, plus the transmission delay, with this
    /// ESC's own system time (ET1100 Section I, "Propagation delay /
    /// drift compensation"; a 32-bit write compares the low 32 bits).
    fn dc_receive(&mut self, received: u64, len: usize) {
        let t = self.dc_port0_ns;
        let own = self.dc_system_time(t);
        let delay = u64::from(self.mem_u32(reg::DC_SYSTEM_TIME_DELAY));
        let reference = received.wrapping_add(delay);
        let diff = if len >= 8 {
            own.wrapping_sub(reference) as i64
        } else {
            i64::from((own as u32).wrapping_sub(reference as u32) as i32)
        };
        let depth = self.mem_u8(reg::DC_TIME_FILTER_DEPTH) & 0x0F;
        let filtered = self.dc.receive(diff, depth, t);
        self.set_u32(reg::DC_SYSTEM_TIME_DIFF, dc::difference_register(filtered));
        // 0x0932 "speed counter diff": here the drift control's rate
        // correction in ppm (an ESC shows it in its own clock units).
        let ppm = (self.dc.correction_ppb() / 1000).clamp(i64::from(i16::MIN), i64::from(i16::MAX));
        self.set_u16(reg::DC_SPEED_COUNTER_START + 2, ppm as i16 as u16);
    }

    /// PDI accesses (reads and writes, of any length) since the ESC was
    /// created: each one is a transaction on an SPI PDI.
    pub fn pdi_accesses(&self) -> u64 {
        self.pdi_accesses
    }

    /// Changes whenever the FMMU configuration may have changed (a write
    /// to the FMMU registers, a power-on), so a line can cache which slave
    /// a logical address reaches ([`SoftEsc::logical_windows`]).
    pub fn fmmu_generation(&self) -> u32 {
        self.fmmu_gen
    }

    /// The logical byte windows `[start, end)` of the enabled FMMUs: a
    /// logical datagram outside all of them leaves this ESC untouched.
    pub fn logical_windows(&self) -> impl Iterator<Item = (u64, u64)> + '_ {
        self.fmmus
            .iter()
            .enumerate()
            .filter(|(n, _)| self.fmmu_active & (1 << n) != 0)
            .map(|(_, f)| (u64::from(f.logical), f.logical_end()))
    }

    /// Whether the AL event request register (0x0220) holds an event for
    /// the firmware: what makes an interrupt-driven firmware run.
    pub fn al_event_pending(&self) -> bool {
        self.mem_u32(reg::AL_EVENT_REQUEST) != 0
    }

    /// Whether the PDI watchdog has expired (DL status bit 1 clear).
    pub fn pdi_watchdog_expired(&self) -> bool {
        self.mem_u16(reg::DL_STATUS) & 0x0002 == 0
    }

    /// The ESC memory (registers and process RAM) as a debug probe sees
    /// it: no SyncManager rules, no side effects. For test tooling that
    /// plays a defective firmware or corrupts memory; firmware uses the
    /// [`Esc`] trait.
    pub fn raw_memory(&self) -> &[u8] {
        &self.mem
    }

    /// The ESC memory, writable without SyncManager rules or side effects
    /// (see [`SoftEsc::raw_memory`]).
    pub fn raw_memory_mut(&mut self) -> &mut [u8] {
        &mut self.mem
    }

    /// The SII image as the EEPROM holds it (including master writes).
    pub fn sii(&self) -> &[u8] {
        &self.sii
    }

    /// Returns and clears the set of output SyncManagers whose buffer the
    /// master completed since the last call (bit n = SM n). Used by the
    /// SyncManager watchdog.
    pub fn take_sm_writes(&mut self) -> u16 {
        core::mem::take(&mut self.sm_written)
    }

    // ----- frame processing (ECAT side) -------------------------------

    /// Processes one Ethernet frame in place, as the frame passes through
    /// this ESC. Non-EtherCAT and malformed frames are left untouched.
    pub fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome {
        let Ok(mut eth) = EthernetFrame::new_checked(&mut *frame) else {
            return FrameOutcome::Malformed;
        };
        if eth.ethertype() != ETHERTYPE_ETHERCAT {
            return FrameOutcome::NotEthercat;
        }
        eth.mark_forwarded();
        let Ok(mut ecat) = EcatFrame::new_checked(eth.payload_mut()) else {
            return FrameOutcome::Malformed;
        };
        if ecat.frame_type() != FrameType::Pdu {
            return FrameOutcome::Malformed;
        }
        let payload = ecat.payload_mut();
        let mut count = 0;
        let mut cursor = DatagramCursor::new();
        while let Some(item) = cursor.next_range(payload) {
            let Ok(range) = item else { break };
            let Some(bytes) = payload.get_mut(range) else {
                break;
            };
            let Ok(mut dg) = Datagram::new_checked(bytes) else {
                break;
            };
            self.process_datagram(&mut dg);
            count += 1;
        }
        FrameOutcome::Processed { datagrams: count }
    }

    /// Processes one datagram in place (addressing, data, working counter).
    pub fn process_datagram<T: AsRef<[u8]> + AsMut<[u8]>>(&mut self, dg: &mut Datagram<T>) {
        let cmd = dg.command();
        let adp = dg.adp();
        let ado = dg.ado();
        let logical = dg.logical_address();
        let mut wkc_add: u16 = 0;
        match cmd {
            Command::Aprd | Command::Apwr | Command::Aprw | Command::Armw => {
                dg.set_adp(adp.wrapping_add(1));
                let data = dg.data_mut();
                wkc_add = match cmd {
                    Command::Armw if adp == 0 => self.phys_read_count(ado, data, ReadMode::Copy),
                    Command::Armw => self.phys_write_count(ado, data),
                    _ if adp == 0 => self.phys_rw(cmd, ado, data, ReadMode::Copy),
                    _ => 0,
                };
            }
            Command::Fprd | Command::Fpwr | Command::Fprw | Command::Frmw => {
                let me = adp == self.station || (self.alias != 0 && adp == self.alias);
                if !me && cmd != Command::Frmw {
                    return;
                }
                let data = dg.data_mut();
                wkc_add = match cmd {
                    Command::Frmw if me => self.phys_read_count(ado, data, ReadMode::Copy),
                    Command::Frmw => self.phys_write_count(ado, data),
                    _ if me => self.phys_rw(cmd, ado, data, ReadMode::Copy),
                    _ => 0,
                };
            }
            Command::Brd | Command::Bwr | Command::Brw => {
                dg.set_adp(adp.wrapping_add(1));
                let data = dg.data_mut();
                wkc_add = self.phys_rw(cmd, ado, data, ReadMode::Or);
            }
            Command::Lrd | Command::Lwr | Command::Lrw => {
                let data = dg.data_mut();
                wkc_add = self.logical(cmd, logical, data);
            }
            Command::Nop | Command::Unknown(_) => {}
        }
        if wkc_add != 0 {
            dg.set_wkc(dg.wkc().wrapping_add(wkc_add));
        }
    }

    /// A read, write or read-write on physical memory; returns the working
    /// counter increment (read 1, write 1, read-write 3 / 1 / 2).
    fn phys_rw(&mut self, cmd: Command, addr: u16, data: &mut [u8], mode: ReadMode) -> u16 {
        match cmd {
            Command::Aprd | Command::Fprd | Command::Brd => self.phys_read_count(addr, data, mode),
            Command::Apwr | Command::Fpwr | Command::Bwr => self.phys_write_count(addr, data),
            Command::Aprw | Command::Fprw | Command::Brw => {
                let n = data.len().min(MAX_DATAGRAM);
                let mut scratch = [0u8; MAX_DATAGRAM];
                let (Some(tmp), Some(src)) = (scratch.get_mut(..n), data.get(..n)) else {
                    return 0;
                };
                tmp.copy_from_slice(src);
                let r = self.phys_read_count(addr, data, mode);
                let w = self.phys_write_count(addr, tmp);
                r + 2 * w
            }
            _ => 0,
        }
    }

    fn phys_read_count(&mut self, addr: u16, data: &mut [u8], mode: ReadMode) -> u16 {
        u16::from(self.ecat_read(addr, data, mode))
    }

    fn phys_write_count(&mut self, addr: u16, data: &[u8]) -> u16 {
        u16::from(self.ecat_write(addr, data))
    }

    /// Logical addressing through the FMMUs; returns the working counter
    /// increment (+1 for any read mapping hit, +2 for any write mapping hit
    /// on LRW; +1 for LRD/LWR).
    fn logical(&mut self, cmd: Command, addr: u32, data: &mut [u8]) -> u16 {
        if self.fmmu_active == 0 || data.is_empty() {
            return 0;
        }
        let start = u64::from(addr);
        let end = start + data.len() as u64;
        let want_read = matches!(cmd, Command::Lrd | Command::Lrw);
        let want_write = matches!(cmd, Command::Lwr | Command::Lrw);
        let mut read_hit = false;
        let mut write_hit = false;
        // Writes first, with the data as it arrived; then reads overwrite.
        for pass_write in [true, false] {
            let mut bits = self.fmmu_active;
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let Some(f) = self.fmmus.get(i).copied() else {
                    continue;
                };
                let hit_possible = if pass_write {
                    want_write && f.write
                } else {
                    want_read && f.read
                };
                if !hit_possible || f.logical_end() <= start || u64::from(f.logical) >= end {
                    continue;
                }
                let ok = if f.byte_aligned() {
                    self.fmmu_bytes(&f, start, data, pass_write)
                } else {
                    self.fmmu_bits(&f, start, data, pass_write)
                };
                if ok {
                    if pass_write {
                        write_hit = true;
                    } else {
                        read_hit = true;
                    }
                }
            }
        }
        match cmd {
            Command::Lrw => u16::from(read_hit) + 2 * u16::from(write_hit),
            _ => u16::from(read_hit || write_hit),
        }
    }

    /// Byte-aligned FMMU transfer of the overlap between the datagram
    /// `[start, start + data.len())` and the FMMU's logical window.
    fn fmmu_bytes(&mut self, f: &FmmuConfig, start: u64, data: &mut [u8], write: bool) -> bool {
        let lo = start.max(u64::from(f.logical));
        let hi = (start + data.len() as u64).min(f.logical_end());
        if lo >= hi {
            return false;
        }
        let (Ok(dg_off), Ok(n)) = (usize::try_from(lo - start), usize::try_from(hi - lo)) else {
            return false;
        };
        let Ok(phys_off) = u16::try_from(lo - u64::from(f.logical)) else {
            return false;
        };
        let Some(phys) = f.physical.checked_add(phys_off) else {
            return false;
        };
        let Some(window) = data.get_mut(dg_off..dg_off + n) else {
            return false;
        };
        if write {
            self.ecat_write(phys, window)
        } else {
            self.ecat_read(phys, window, ReadMode::Copy)
        }
    }

    /// Bit-granular FMMU transfer (start/stop bits other than 0/7).
    ///
    /// Hand-written on purpose: the same transfer with `bitvec` (both sides
    /// as `BitSlice<u8, Lsb0>`, `store_le(load_le::<u64>())` per 64 bits)
    /// was measurably slower for the small fields bit FMMUs carry. The
    /// `soft_esc_bit_fmmu` benchmark (one LRW, 4 output and 4 input bits
    /// per slave) took 1527 -> 1638 instructions per cycle with 1 slave
    /// (+7 %) and 87 953 -> 95 058 with 64 (+8 %, cachegrind; criterion
    /// timings on the 2-core CI machine scatter more than that between
    /// identical builds); `copy_from_bitslice` was slower still (+23 % /
    /// +25 %).
    fn fmmu_bits(&mut self, f: &FmmuConfig, start: u64, data: &mut [u8], write: bool) -> bool {
        // Logical bit range [lbit_start, lbit_end] inclusive.
        let lbit_start = u64::from(f.logical) * 8 + u64::from(f.start_bit & 7);
        let Some(last_byte) = f.logical_end().checked_sub(1) else {
            return false;
        };
        let lbit_end = last_byte * 8 + u64::from(f.stop_bit & 7);
        if lbit_end < lbit_start {
            return false;
        }
        let dg_bit_start = start * 8;
        let dg_bit_end = (start + data.len() as u64) * 8; // exclusive
        let lo = lbit_start.max(dg_bit_start);
        let hi = (lbit_end + 1).min(dg_bit_end);
        if lo >= hi {
            return false;
        }
        let phys_bit0 = u64::from(f.physical) * 8 + u64::from(f.physical_bit & 7);
        // Physical byte range touched, for SyncManager checks.
        let p_first = phys_bit0 + (lo - lbit_start);
        let p_last = phys_bit0 + (hi - 1 - lbit_start);
        let (Ok(pa), Ok(pb)) = (u16::try_from(p_first / 8), u16::try_from(p_last / 8)) else {
            return false;
        };
        let plen = usize::from(pb - pa) + 1;
        let mut buf = [0u8; MAX_DATAGRAM];
        let Some(pbuf) = buf.get_mut(..plen) else {
            return false;
        };
        // Read current physical bytes (directly: bit writes are read-modify-write).
        if !self.mem_get(pa, pbuf) {
            return false;
        }
        for bit in lo..hi {
            let pbit = phys_bit0 + (bit - lbit_start) - u64::from(pa) * 8;
            let dbit = bit - dg_bit_start;
            let (Ok(pi), Ok(di)) = (usize::try_from(pbit / 8), usize::try_from(dbit / 8)) else {
                return false;
            };
            let (pm, dm) = (1u8 << (pbit % 8), 1u8 << (dbit % 8));
            if write {
                let v = data.get(di).is_some_and(|b| b & dm != 0);
                if let Some(p) = pbuf.get_mut(pi) {
                    *p = if v { *p | pm } else { *p & !pm };
                }
            } else {
                let v = pbuf.get(pi).is_some_and(|b| b & pm != 0);
                if let Some(d) = data.get_mut(di) {
                    *d = if v { *d | dm } else { *d & !dm };
                }
            }
        }
        if write {
            let touched = buf.get(..plen).unwrap_or(&[]);
            self.ecat_write(pa, touched)
        } else {
            // Run the SyncManager read rules on the touched bytes.
            let mut sink = [0u8; MAX_DATAGRAM];
            let touched = sink.get_mut(..plen).unwrap_or(&mut []);
            self.ecat_read(pa, touched, ReadMode::Copy)
        }
    }

    /// ECAT-side read of physical memory with SyncManager rules. Returns
    /// whether the access happened (counts in the working counter).
    fn ecat_read(&mut self, addr: u16, out: &mut [u8], mode: ReadMode) -> bool {
        let a = u32::from(addr);
        let b = a + out.len() as u32;
        if b > 0x1_0000 {
            return false;
        }
        self.refresh_dc_registers(a, b);
        // SyncManager checks, on the part in process RAM only: as on
        // silicon, SyncManagers map process RAM, and one a master
        // configured over the registers must not hide them (the master
        // could no longer read AL status to repair it).
        let ram = a.max(u32::from(reg::PROCESS_RAM));
        let mut complete = 0u8;
        let mut bits = if ram < b { self.sm_active } else { 0 };
        while bits != 0 {
            let n = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let Some(sm) = self.sms.get(n) else { continue };
            if !sm.overlaps(ram, b) {
                continue;
            }
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
        let mem_end = (b as usize).min(MEM_SIZE);
        let from = (a as usize).min(mem_end);
        let src = self.mem.get(from..mem_end).unwrap_or(&[]);
        match mode {
            ReadMode::Copy => {
                for (d, v) in out.iter_mut().zip(src) {
                    *d = *v;
                }
                for d in out.iter_mut().skip(src.len()) {
                    *d = 0;
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
    fn ecat_read_complete(&mut self, n: usize) {
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
    fn ecat_write(&mut self, addr: u16, data: &[u8]) -> bool {
        let a = u32::from(addr);
        let b = a + data.len() as u32;
        if b > 0x1_0000 {
            return false;
        }
        if a < u32::from(reg::PROCESS_RAM) {
            self.register_write(addr, data);
            return true;
        }
        let mut complete = 0u8;
        let mut bits = self.sm_active;
        while bits != 0 {
            let n = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let Some(sm) = self.sms.get(n) else { continue };
            if !sm.overlaps(a, b) {
                continue;
            }
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
        let mem_end = (b as usize).min(MEM_SIZE);
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
    fn ecat_write_complete(&mut self, n: usize) {
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

    /// Writes into the register area with the ECAT write masks and side
    /// effects (AL control event, SII commands, SM/FMMU reconfiguration).
    fn register_write(&mut self, addr: u16, data: &[u8]) {
        let mut touched_sm = 0u16;
        let mut touched_fmmu = 0u16;
        let mut sii_command = false;
        let mut al_control = false;
        let mut dc_latch = false;
        let mut dc_reset = false;
        let mut dc_activation = false;
        // System time received (0x0910..0x0917): value and which bytes.
        let mut dc_received: Option<(u64, u8)> = None;
        for (i, &v) in data.iter().enumerate() {
            let Some(a) = addr.checked_add(i as u16) else {
                break;
            };
            match a {
                0x0010..=0x0011 | 0x0020..=0x0021 | 0x0030..=0x0031 | 0x0040 => self.set_u8(a, v),
                0x0100..=0x0103 | 0x0108..=0x0109 | 0x0200..=0x0201 => self.set_u8(a, v),
                0x0120..=0x0121 => {
                    self.set_u8(a, v);
                    al_control = true;
                }
                // Error counters: any write clears.
                0x0300..=0x0313 | 0x0442..=0x0443 => self.set_u8(a, 0),
                0x0400..=0x0401 | 0x0410..=0x0411 | 0x0420..=0x0421 => {
                    self.set_u8(a, v);
                    self.wd_restart = true;
                }
                0x0500..=0x0501 => self.set_u8(a, v),
                0x0502 => {
                    // Bit 6 (read size) is read-only; bits 0 and 7 writable.
                    let keep = self.mem_u8(a) & 0x40;
                    self.set_u8(a, (v & 0x81) | keep);
                }
                0x0503 => {
                    // Command bits 8-10; error and busy bits are status.
                    self.set_u8(a, v & 0x07);
                    sii_command = true;
                }
                0x0504..=0x0517 => self.set_u8(a, v),
                0x0600..=0x06FF => {
                    self.set_u8(a, v);
                    touched_fmmu |= 1 << ((a - reg::FMMU_BASE) / reg::FMMU_LEN);
                }
                0x0800..=0x087F => {
                    let off = (a - reg::SM_BASE) % reg::SM_LEN;
                    if off != smr::STATUS && off != smr::PDI_CONTROL {
                        self.set_u8(a, v);
                        touched_sm |= 1 << ((a - reg::SM_BASE) / reg::SM_LEN);
                    }
                }
                // Receive times: a write to port 0's latches them all.
                0x0900..=0x0903 => dc_latch = true,
                // Receive times of ports 1-3 and of the processing unit,
                // the system time difference: read-only.
                0x0904..=0x090F | 0x0918..=0x091F | 0x092C..=0x092F => {}
                0x0910..=0x0917 => {
                    let (value, mask) = dc_received.unwrap_or((0, 0));
                    let byte = u32::from(a - reg::DC_SYSTEM_TIME);
                    dc_received = Some((value | u64::from(v) << (8 * byte), mask | 1 << byte));
                }
                // Speed counter start: a write resets the drift control
                // (ETG.1020 §22.2.4: masters write 0x0934 then 0x0930 to
                // reset the loop after blanking the DC registers).
                0x0930..=0x0931 => {
                    self.set_u8(a, v);
                    dc_reset = true;
                }
                0x0932..=0x0933 | 0x098E..=0x098F => {}
                0x0981 => {
                    self.set_u8(a, v);
                    dc_activation = true;
                }
                0x0920..=0x092B | 0x0934..=0x09FF | 0x0F00..=0x0F03 => self.set_u8(a, v),
                _ => {}
            }
        }
        if al_control {
            if self.mem_u8(reg::ESC_CONFIG) & ESC_CONFIG_DEVICE_EMULATION != 0 {
                // Device emulation (ET1100 Section II, 0x0141 bit 0): an
                // ESC without a firmware (digital I/O terminals, couplers)
                // takes the requested state as its AL status. Only the
                // state bits are copied: such a device never indicates an
                // error, so an Error Ind Ack (bit 4) does not become an
                // error indication.
                let requested = self.mem_u16(reg::AL_CONTROL) & 0x000F;
                self.set_u16(reg::AL_STATUS, requested);
            }
            self.raise_al_event(reg::AL_EVENT_AL_CONTROL);
        }
        if dc_latch {
            self.dc_latch();
        }
        // A time is the low 32 bits at least; all 8 bytes make it 64-bit.
        match dc_received {
            Some((value, 0xFF)) => self.dc_receive(value, 8),
            Some((value, mask)) if mask & 0x0F == 0x0F => self.dc_receive(value, 4),
            _ => {}
        }
        if dc_reset {
            self.dc.reset_control(self.dc_port0_ns);
            self.set_u32(reg::DC_SYSTEM_TIME_DIFF, 0);
            self.set_u16(reg::DC_SPEED_COUNTER_START + 2, 0);
        }
        if dc_activation {
            self.dc_activate();
        }
        if touched_fmmu != 0 {
            self.reload_fmmus();
        }
        if touched_sm != 0 {
            for n in 0..SM_COUNT {
                if touched_sm & (1 << n) != 0 {
                    self.reload_sm(n);
                }
            }
        }
        if sii_command {
            self.sii_execute();
        }
        // After the SII command: an EEPROM reload changes the alias, and
        // addressing must follow it at once.
        self.refresh_address();
    }

    fn reload_fmmus(&mut self) {
        self.fmmu_active = 0;
        self.fmmu_gen = self.fmmu_gen.wrapping_add(1);
        for n in 0..FMMU_COUNT {
            let Some(base) = reg::fmmu(n as u8) else {
                continue;
            };
            let f = FmmuConfig {
                logical: self.mem_u32(base + reg::fmmu::LOGICAL_START),
                len: self.mem_u16(base + reg::fmmu::LENGTH),
                start_bit: self.mem_u8(base + reg::fmmu::LOGICAL_START_BIT),
                stop_bit: self.mem_u8(base + reg::fmmu::LOGICAL_STOP_BIT),
                physical: self.mem_u16(base + reg::fmmu::PHYSICAL_START),
                physical_bit: self.mem_u8(base + reg::fmmu::PHYSICAL_START_BIT),
                read: self.mem_u8(base + reg::fmmu::TYPE) & 0x01 != 0,
                write: self.mem_u8(base + reg::fmmu::TYPE) & 0x02 != 0,
                enabled: self.mem_u8(base + reg::fmmu::ACTIVATE) & 0x01 != 0,
            };
            if f.enabled && f.len > 0 {
                self.fmmu_active |= 1 << n;
            }
            if let Some(slot) = self.fmmus.get_mut(n) {
                *slot = f;
            }
        }
    }

    fn reload_sm(&mut self, n: usize) {
        let Some(base) = reg::sm(n as u8) else {
            return;
        };
        let new = SmConfig {
            start: self.mem_u16(base + smr::START),
            len: self.mem_u16(base + smr::LENGTH),
            control: self.mem_u8(base + smr::CONTROL),
            enabled: self.mem_u8(base + smr::ACTIVATE) & smr::ACTIVATE_ENABLE != 0,
            activate: self.mem_u8(base + smr::ACTIVATE),
        };
        let Some(slot) = self.sms.get_mut(n) else {
            return;
        };
        let old = *slot;
        *slot = new;
        if new.enabled && new.len > 0 {
            self.sm_active |= 1 << n;
        } else {
            self.sm_active &= !(1 << n);
        }
        // A changed activation register (enable, repeat request) is an
        // event for the firmware; so is any reconfiguration.
        if old != new {
            self.raise_al_event(reg::AL_EVENT_SM_CHANGED);
        }
        // (Re)configuring or enabling a SyncManager resets its buffer state.
        if old.start != new.start
            || old.len != new.len
            || old.control != new.control
            || old.enabled != new.enabled
        {
            self.set_sm_status(n, 0);
            // A (re)configured output SM with watchdog trigger restarts the
            // process-data watchdog: unarmed until the first output write.
            if new.enabled && new.control & smr::WATCHDOG_TRIGGER != 0 {
                self.wd_sm_armed_at = None;
                let st = self.mem_u16(reg::WATCHDOG_STATUS_PD) | 1;
                self.set_u16(reg::WATCHDOG_STATUS_PD, st);
            }
        }
    }

    /// Executes the command written into SII control 0x0503.
    fn sii_execute(&mut self) {
        let ctrl = self.mem_u16(reg::SII_CONTROL);
        let cmd = (ctrl >> 8) & 0x07;
        // Error bits (11-14) and busy (15) are cleared by every command.
        let mut status = ctrl & 0x00FF;
        let word = self.mem_u32(reg::SII_ADDRESS);
        match cmd {
            0 => {}
            1 => {
                // Read: 8 bytes (bit 6) from the word address.
                let mut data = [0xFFu8; 8];
                if let Ok(w) = usize::try_from(word) {
                    for (i, d) in data.iter_mut().enumerate() {
                        if let Some(v) = w.checked_mul(2).and_then(|b| self.sii.get(b + i)) {
                            *d = *v;
                        }
                    }
                }
                for (i, d) in data.iter().enumerate() {
                    self.set_u8(reg::SII_DATA + i as u16, *d);
                }
            }
            2 => {
                // Write one word, only with write access enabled (bit 0).
                let lo = self.mem_u8(reg::SII_DATA);
                let hi = self.mem_u8(reg::SII_DATA + 1);
                let slot = usize::try_from(word)
                    .ok()
                    .and_then(|w| w.checked_mul(2))
                    .filter(|b| b + 1 < SII_SIZE);
                match (ctrl & 0x0001 != 0, slot) {
                    (true, Some(b)) => {
                        if let Some(s) = self.sii.get_mut(b..b + 2) {
                            s.copy_from_slice(&[lo, hi]);
                        }
                    }
                    // Command error (bit 13).
                    _ => status |= 0x2000,
                }
            }
            4 => {
                // Reload: refresh the alias from word 4.
                let alias = self.sii_word(4);
                self.set_u16(reg::STATION_ALIAS, alias);
            }
            _ => status |= 0x2000,
        }
        self.set_u16(reg::SII_CONTROL, status);
    }

    fn sii_word(&self, word: usize) -> u16 {
        let lo = self.sii.get(word * 2).copied().unwrap_or(0xFF);
        let hi = self.sii.get(word * 2 + 1).copied().unwrap_or(0xFF);
        u16::from_le_bytes([lo, hi])
    }

    // ----- memory helpers ----------------------------------------------

    fn raise_al_event(&mut self, bits: u32) {
        let v = self.mem_u32(reg::AL_EVENT_REQUEST) | bits;
        self.set_u32(reg::AL_EVENT_REQUEST, v);
    }

    fn clear_al_event(&mut self, bits: u32) {
        let v = self.mem_u32(reg::AL_EVENT_REQUEST) & !bits;
        self.set_u32(reg::AL_EVENT_REQUEST, v);
    }

    fn sm_status(&self, n: usize) -> u8 {
        reg::sm(n as u8).map_or(0, |b| self.mem_u8(b + smr::STATUS))
    }

    fn sm_status_bit(&self, n: usize, bit: u8) -> bool {
        self.sm_status(n) & bit != 0
    }

    fn set_sm_status(&mut self, n: usize, v: u8) {
        if let Some(b) = reg::sm(n as u8) {
            self.set_u8(b + smr::STATUS, v);
        }
    }

    fn mem_get(&self, addr: u16, out: &mut [u8]) -> bool {
        let a = usize::from(addr);
        match self.mem.get(a..a + out.len()) {
            Some(src) => {
                out.copy_from_slice(src);
                true
            }
            None => false,
        }
    }

    fn mem_u8(&self, addr: u16) -> u8 {
        self.mem.get(usize::from(addr)).copied().unwrap_or(0)
    }

    fn mem_u16(&self, addr: u16) -> u16 {
        let mut b = [0u8; 2];
        self.mem_get(addr, &mut b);
        u16::from_le_bytes(b)
    }

    fn mem_u32(&self, addr: u16) -> u32 {
        let mut b = [0u8; 4];
        self.mem_get(addr, &mut b);
        u32::from_le_bytes(b)
    }

    fn mem_u64(&self, addr: u16) -> u64 {
        let mut b = [0u8; 8];
        self.mem_get(addr, &mut b);
        u64::from_le_bytes(b)
    }

    fn set_u64(&mut self, addr: u16, v: u64) {
        let a = usize::from(addr);
        if let Some(m) = self.mem.get_mut(a..a + 8) {
            m.copy_from_slice(&v.to_le_bytes());
        }
    }

    fn set_u8(&mut self, addr: u16, v: u8) {
        if let Some(m) = self.mem.get_mut(usize::from(addr)) {
            *m = v;
        }
    }

    fn set_u16(&mut self, addr: u16, v: u16) {
        let a = usize::from(addr);
        if let Some(m) = self.mem.get_mut(a..a + 2) {
            m.copy_from_slice(&v.to_le_bytes());
        }
    }

    fn set_u32(&mut self, addr: u16, v: u32) {
        let a = usize::from(addr);
        if let Some(m) = self.mem.get_mut(a..a + 4) {
            m.copy_from_slice(&v.to_le_bytes());
        }
    }

    /// Which SyncManager (if any, enabled) holds `[a, b)` partly.
    fn pdi_sm_checks(&self, a: u32, b: u32, write: bool) -> Result<(u8, u8), EscError> {
        // Returns (bitmask of SMs whose last byte is covered, bitmask of
        // SMs touched).
        let mut complete = 0u8;
        let mut touched = 0u8;
        for (n, sm) in self.sms.iter().enumerate() {
            if !sm.overlaps(a, b) {
                continue;
            }
            touched |= 1 << n;
            let full = self.sm_status_bit(n, smr::STATUS_MAILBOX_FULL);
            if sm.is_mailbox() {
                // The PDI reads what the master wrote, writes what it reads.
                let ok = if write {
                    !sm.ecat_writes() && !full
                } else {
                    sm.ecat_writes() && full
                };
                if !ok {
                    return Err(EscError::SmBusy { sm: n as u8 });
                }
            }
            if sm.covers_last(a, b) {
                complete |= 1 << n;
            }
        }
        Ok((complete, touched))
    }
}

impl Esc for SoftEsc {
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
        self.pdi_touched = true;
        self.pdi_accesses += 1;
        let a = u32::from(addr);
        let b = a + buf.len() as u32;
        if self.pdi_fault.is_some_and(|f| f.hits(a, b, false)) {
            return Err(EscError::Interface);
        }
        if b as usize > MEM_SIZE {
            return Err(EscError::OutOfRange {
                addr,
                len: buf.len(),
            });
        }
        // SyncManager rules on the part in process RAM (an access may
        // start among the registers and run into it).
        let ram = a.max(u32::from(reg::PROCESS_RAM));
        let (complete, touched) = if ram < b {
            self.pdi_sm_checks(ram, b, false)?
        } else {
            (0, 0)
        };
        self.refresh_dc_registers(a, b);
        self.mem_get(addr, buf);
        let covers = |r: u16| a <= u32::from(r) && u32::from(r) < b;
        // Reading AL control acknowledges its event; reading the watchdog
        // status or an SM activation register acknowledges theirs.
        if covers(reg::AL_CONTROL) {
            self.clear_al_event(reg::AL_EVENT_AL_CONTROL);
        }
        if covers(reg::WATCHDOG_STATUS_PD) {
            self.clear_al_event(reg::AL_EVENT_WATCHDOG_PD);
        }
        if covers(reg::DC_SYNC0_STATUS) {
            // Acknowledge mode (pulse length 0): reading the status clears
            // it and the AL event bit mirroring it.
            let st = self.mem_u8(reg::DC_SYNC0_STATUS) & !0x01;
            self.set_u8(reg::DC_SYNC0_STATUS, st);
            self.clear_al_event(reg::AL_EVENT_SYNC0);
        }
        if (0..SM_COUNT as u8)
            .filter_map(reg::sm)
            .any(|base| covers(base + smr::ACTIVATE))
        {
            self.clear_al_event(reg::AL_EVENT_SM_CHANGED);
        }
        for n in 0..SM_COUNT {
            if touched & (1 << n) != 0 {
                self.clear_al_event(reg::al_event_sm(n as u8));
            }
            if complete & (1 << n) != 0 {
                let is_mbx = self.sms.get(n).is_some_and(SmConfig::is_mailbox);
                let s = self.sm_status(n) & !smr::STATUS_WRITE_EVENT;
                let s = if is_mbx {
                    s & !smr::STATUS_MAILBOX_FULL
                } else {
                    s
                };
                self.set_sm_status(n, s);
            }
        }
        Ok(())
    }

    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
        self.pdi_touched = true;
        self.pdi_accesses += 1;
        let a = u32::from(addr);
        let b = a + data.len() as u32;
        if self.pdi_fault.is_some_and(|f| f.hits(a, b, true)) {
            return Err(EscError::Interface);
        }
        if b as usize > MEM_SIZE {
            return Err(EscError::OutOfRange {
                addr,
                len: data.len(),
            });
        }
        // The part among the registers, then the part in process RAM (an
        // access may run from one into the other).
        let ram = u32::from(reg::PROCESS_RAM);
        let split = usize::try_from(ram.saturating_sub(a))
            .unwrap_or(usize::MAX)
            .min(data.len());
        let (regs, data) = data.split_at(split);
        if !regs.is_empty() {
            // PDI-writable registers: AL status/code, alias, event mask,
            // SM PDI control, LED overrides, watchdog counters; DL status
            // and the rest stay as the ESC sets them.
            for (i, &v) in regs.iter().enumerate() {
                let r = addr.wrapping_add(i as u16);
                let writable = matches!(
                    r,
                    0x0012..=0x0013
                        | 0x0130..=0x0131
                        | 0x0134..=0x0135
                        | 0x0138..=0x0139
                        | 0x0204..=0x0207
                        | 0x0440..=0x0443
                ) || (r >= reg::SM_BASE
                    && r < reg::SM_BASE + reg::SM_LEN * SM_COUNT as u16
                    && (r - reg::SM_BASE) % reg::SM_LEN == smr::PDI_CONTROL);
                if writable {
                    self.set_u8(r, v);
                }
            }
            self.refresh_address();
            if data.is_empty() {
                return Ok(());
            }
        }
        let a = a.max(ram);
        let (complete, touched) = self.pdi_sm_checks(a, b, true)?;
        if let Some(dst) = self.mem.get_mut(a as usize..b as usize) {
            dst.copy_from_slice(data);
        }
        for n in 0..SM_COUNT {
            // Writing a buffer the master reads acknowledges its read
            // event (ET1100 0x0805 bit 1, "cleared by writing from PDI").
            if touched & (1 << n) != 0 {
                self.clear_al_event(reg::al_event_sm(n as u8));
                let st = self.sm_status(n) & !smr::STATUS_READ_EVENT;
                self.set_sm_status(n, st);
            }
            if complete & (1 << n) != 0 {
                let is_mbx = self.sms.get(n).is_some_and(SmConfig::is_mailbox);
                if is_mbx {
                    let s = self.sm_status(n) | smr::STATUS_MAILBOX_FULL;
                    self.set_sm_status(n, s);
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ecat_slave::wire::builder::FrameBuilder;
    use proptest::prelude::*;

    const SRC: [u8; 6] = [0x10, 0x10, 0x10, 0x10, 0x10, 0x10];

    fn esc() -> SoftEsc {
        // A minimal SII: alias 0x0000, the rest 0xFF.
        let mut sii = [0xFFu8; 128];
        sii[..16].fill(0);
        SoftEsc::new(&sii)
    }

    /// Builds a frame of `(command, address, data)` datagrams.
    fn frame(dgs: &[(Command, u32, &[u8])]) -> (Vec<u8>, Vec<core::ops::Range<usize>>) {
        let mut buf = vec![0u8; 1600];
        let mut b = FrameBuilder::new(&mut buf, SRC).unwrap();
        let ranges = dgs
            .iter()
            .map(|(c, a, d)| b.push(*c, *a, d).unwrap())
            .collect();
        let len = b.finish();
        buf.truncate(len);
        (buf, ranges)
    }

    fn wkc(frame: &[u8], data: &core::ops::Range<usize>) -> u16 {
        u16::from_le_bytes([frame[data.end], frame[data.end + 1]])
    }

    fn phys(adp: u16, ado: u16) -> u32 {
        u32::from(adp) | (u32::from(ado) << 16)
    }

    #[test]
    fn brd_counts_every_slave_and_ors_register_data() {
        let mut line = [esc(), esc()];
        let (mut f, r) = frame(&[(Command::Brd, 0, &[0])]);
        for e in &mut line {
            assert_eq!(
                e.process_frame(&mut f),
                FrameOutcome::Processed { datagrams: 1 }
            );
        }
        assert_eq!(wkc(&f, &r[0]), 2);
        assert_eq!(f[r[0].start], 0x11, "ESC type read");
        // ADP incremented by each slave.
        assert_eq!(
            u16::from_le_bytes([f[r[0].start - 8], f[r[0].start - 7]]),
            2
        );
    }

    #[test]
    fn reply_source_mac_has_the_locally_administered_bit() {
        let mut e = esc();
        let (mut f, _) = frame(&[(Command::Brd, 0, &[0])]);
        e.process_frame(&mut f);
        assert_eq!(f[6], 0x12);
    }

    #[test]
    fn auto_increment_write_addresses_position_zero_only() {
        let mut line = [esc(), esc(), esc()];
        // ADP 0xFFFF (-1) addresses the second slave.
        let (mut f, r) = frame(&[(Command::Apwr, phys(0xFFFF, 0x0010), &[0x34, 0x12])]);
        for e in &mut line {
            e.process_frame(&mut f);
        }
        assert_eq!(wkc(&f, &r[0]), 1);
        assert_eq!(line[0].mem_u16(reg::STATION_ADDRESS), 0);
        assert_eq!(line[1].mem_u16(reg::STATION_ADDRESS), 0x1234);
        // Then configured addressing reaches it.
        let (mut f, r) = frame(&[(Command::Fprd, phys(0x1234, 0x0130), &[0, 0])]);
        for e in &mut line {
            e.process_frame(&mut f);
        }
        assert_eq!(wkc(&f, &r[0]), 1);
        assert_eq!(&f[r[0].clone()], &[0x01, 0x00], "AL status INIT");
    }

    #[test]
    fn read_write_commands_count_three_and_return_old_data() {
        let mut e = esc();
        let (mut f, r) = frame(&[(Command::Aprw, phys(0, 0x0010), &[0x01, 0x10])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 3);
        assert_eq!(&f[r[0].clone()], &[0, 0], "old station address returned");
        assert_eq!(e.mem_u16(reg::STATION_ADDRESS), 0x1001);
    }

    #[test]
    fn access_wrapping_past_ffff_is_not_executed_or_counted() {
        let mut e = esc();
        let before = e.mem;
        let (mut f, r) = frame(&[(Command::Apwr, phys(0, 0xFFFE), &[1, 2, 3, 4])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 0);
        assert!(e.mem == before, "memory unchanged");
        let (mut f, r) = frame(&[(Command::Aprd, phys(0, 0xFFFF), &[9, 9])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 0);
        assert_eq!(&f[r[0].clone()], &[9, 9]);
    }

    #[test]
    fn read_only_registers_ignore_master_writes() {
        let mut e = esc();
        let (mut f, r) = frame(&[(Command::Apwr, phys(0, reg::AL_STATUS), &[0x08, 0x00])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 1, "the write is counted, as on silicon");
        assert_eq!(e.mem_u16(reg::AL_STATUS), 0x0001);
    }

    #[test]
    fn al_control_write_raises_an_event_that_a_pdi_read_clears() {
        let mut e = esc();
        let (mut f, _) = frame(&[(Command::Bwr, phys(0, reg::AL_CONTROL), &[0x02, 0x00])]);
        e.process_frame(&mut f);
        assert_eq!(e.read_u32(reg::AL_EVENT_REQUEST).unwrap() & 1, 1);
        assert_eq!(e.read_u16(reg::AL_CONTROL).unwrap(), 0x0002);
        assert_eq!(e.read_u32(reg::AL_EVENT_REQUEST).unwrap() & 1, 0);
    }

    #[test]
    fn device_emulation_makes_the_al_status_follow_al_control_without_error_bit() {
        // PDI control word 0x0104 of an EL2004 dump: digital I/O PDI, ESC
        // configuration 0x01 (device emulation).
        let mut sii = [0xFFu8; 128];
        sii[..16].fill(0);
        sii[0] = 0x04;
        sii[1] = 0x01;
        let mut e = SoftEsc::new(&sii);
        let (mut f, _) = frame(&[(Command::Bwr, phys(0, reg::AL_CONTROL), &[0x12, 0x00])]);
        e.process_frame(&mut f);
        assert_eq!(
            e.mem_u16(reg::AL_STATUS),
            0x0002,
            "PRE-OP, ack bit not copied"
        );
        let (mut f, _) = frame(&[(Command::Bwr, phys(0, reg::AL_CONTROL), &[0x08, 0x00])]);
        e.process_frame(&mut f);
        assert_eq!(e.mem_u16(reg::AL_STATUS), 0x0008);
    }

    #[test]
    fn without_device_emulation_al_control_leaves_the_status_to_the_firmware() {
        let mut e = esc();
        let (mut f, _) = frame(&[(Command::Bwr, phys(0, reg::AL_CONTROL), &[0x02, 0x00])]);
        e.process_frame(&mut f);
        assert_eq!(e.mem_u16(reg::AL_STATUS), 0x0001);
    }

    #[test]
    fn sii_read_command_loads_eight_bytes_and_is_never_busy() {
        let mut sii = [0u8; 256];
        for (i, b) in sii.iter_mut().enumerate() {
            *b = i as u8;
        }
        let mut e = SoftEsc::new(&sii);
        // Command read (0x0100) of word 8, as ethercrab writes it.
        let (mut f, _) = frame(&[(
            Command::Apwr,
            phys(0, reg::SII_CONTROL),
            &[0x00, 0x01, 0x08, 0x00, 0x00, 0x00],
        )]);
        e.process_frame(&mut f);
        let (mut f, r) = frame(&[
            (Command::Aprd, phys(0, reg::SII_CONTROL), &[0, 0]),
            (Command::Aprd, phys(0, reg::SII_DATA), &[0; 8]),
        ]);
        e.process_frame(&mut f);
        let ctrl = u16::from_le_bytes([f[r[0].start], f[r[0].start + 1]]);
        assert_eq!(ctrl & 0x8000, 0, "not busy");
        assert_eq!(ctrl & 0x0040, 0x0040, "8-byte reads");
        assert_eq!(ctrl & 0x7800, 0, "no error bits");
        assert_eq!(&f[r[1].clone()], &[16, 17, 18, 19, 20, 21, 22, 23]);
    }

    #[test]
    fn sii_write_without_write_enable_sets_command_error_once() {
        let mut e = esc();
        let (mut f, _) = frame(&[(Command::Apwr, phys(0, reg::SII_CONTROL), &[0x00, 0x02])]);
        e.process_frame(&mut f);
        assert_ne!(e.mem_u16(reg::SII_CONTROL) & 0x2000, 0);
        // The next command clears it: errors do not latch.
        let (mut f, _) = frame(&[(Command::Apwr, phys(0, reg::SII_CONTROL), &[0x00, 0x01])]);
        e.process_frame(&mut f);
        assert_eq!(e.mem_u16(reg::SII_CONTROL) & 0x7800, 0);
    }

    #[test]
    fn a_mailbox_sm_over_the_registers_does_not_hide_them() {
        let mut e = esc();
        // SM1 (mailbox in, ECAT reads) wrongly placed over 0x0000..0x0200.
        let sm1 = [0x00, 0x00, 0x00, 0x02, 0x22, 0x00, 0x01, 0x00];
        let (mut f, _) = frame(&[(Command::Apwr, phys(0, 0x0808), &sm1)]);
        e.process_frame(&mut f);
        let (mut f, r) = frame(&[
            (Command::Brd, phys(0, 0x0000), &[0]),
            (Command::Aprd, phys(0, reg::STATION_ADDRESS), &[0, 0]),
            (Command::Aprd, phys(0, reg::AL_STATUS), &[0, 0]),
        ]);
        e.process_frame(&mut f);
        assert_eq!(
            (wkc(&f, &r[0]), wkc(&f, &r[1]), wkc(&f, &r[2])),
            (1, 1, 1),
            "registers stay readable"
        );
        assert_eq!(&f[r[2].clone()], &[0x01, 0x00], "AL status INIT");
    }

    #[test]
    fn an_eeprom_reload_moves_alias_addressing_at_once() {
        let mut e = esc();
        // Write alias 0x1234 into SII word 4 (write access on), then reload.
        let (mut f, _) = frame(&[
            (Command::Apwr, phys(0, reg::SII_CONTROL), &[0x01, 0x00]),
            (Command::Apwr, phys(0, reg::SII_DATA), &[0x34, 0x12]),
            (
                Command::Apwr,
                phys(0, reg::SII_CONTROL),
                &[0x01, 0x02, 0x04, 0x00, 0x00, 0x00],
            ),
            (
                Command::Apwr,
                phys(0, reg::SII_CONTROL),
                &[0x00, 0x04, 0x00, 0x00, 0x00, 0x00],
            ),
            (Command::Fprd, phys(0x1234, reg::AL_STATUS), &[0, 0]),
        ]);
        let generation = e.address_generation();
        e.process_frame(&mut f);
        let r = frame(&[
            (Command::Apwr, phys(0, reg::SII_CONTROL), &[0x01, 0x00]),
            (Command::Apwr, phys(0, reg::SII_DATA), &[0x34, 0x12]),
            (
                Command::Apwr,
                phys(0, reg::SII_CONTROL),
                &[0x01, 0x02, 0x04, 0x00, 0x00, 0x00],
            ),
            (
                Command::Apwr,
                phys(0, reg::SII_CONTROL),
                &[0x00, 0x04, 0x00, 0x00, 0x00, 0x00],
            ),
            (Command::Fprd, phys(0x1234, reg::AL_STATUS), &[0, 0]),
        ])
        .1;
        assert_eq!(e.mem_u16(reg::STATION_ALIAS), 0x1234, "register reloaded");
        assert_eq!(e.station_alias(), 0x1234, "addressing follows");
        assert_ne!(e.address_generation(), generation);
        assert_eq!(wkc(&f, &r[4]), 1, "FPRD by the new alias in the same frame");
    }

    fn configure_mailbox(e: &mut SoftEsc) {
        let sm0 = [0x00, 0x10, 0x08, 0x00, 0x26, 0x00, 0x01, 0x00];
        let sm1 = [0x80, 0x10, 0x08, 0x00, 0x22, 0x00, 0x01, 0x00];
        let (mut f, _) = frame(&[
            (Command::Apwr, phys(0, 0x0800), &sm0),
            (Command::Apwr, phys(0, 0x0808), &sm1),
        ]);
        e.process_frame(&mut f);
    }

    #[test]
    fn mailbox_write_fills_sm0_and_a_second_write_is_refused() {
        let mut e = esc();
        configure_mailbox(&mut e);
        let (mut f, r) = frame(&[(Command::Apwr, phys(0, 0x1000), &[1; 8])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 1);
        assert_ne!(e.mem_u8(0x0805) & 0x08, 0, "SM0 full");
        assert_ne!(
            e.read_u32(reg::AL_EVENT_REQUEST).unwrap() & reg::al_event_sm(0),
            0
        );
        let (mut f, r) = frame(&[(Command::Apwr, phys(0, 0x1000), &[2; 8])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 0, "full mailbox refuses");
        let mut got = [0u8; 8];
        e.read(0x1000, &mut got).unwrap();
        assert_eq!(got, [1; 8]);
        assert_eq!(e.mem_u8(0x0805) & 0x08, 0, "PDI read empties it");
    }

    #[test]
    fn empty_read_mailbox_is_not_counted_and_full_one_empties_on_read() {
        let mut e = esc();
        configure_mailbox(&mut e);
        let (mut f, r) = frame(&[(Command::Aprd, phys(0, 0x1080), &[0; 8])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 0);
        e.write(0x1080, &[7; 8]).unwrap();
        assert_eq!(e.write(0x1080, &[8; 8]), Err(EscError::SmBusy { sm: 1 }));
        let (mut f, r) = frame(&[(Command::Aprd, phys(0, 0x1080), &[0; 8])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 1);
        assert_eq!(&f[r[0].clone()], &[7; 8]);
        assert_eq!(e.mem_u8(0x080D) & 0x08, 0, "emptied");
    }

    fn configure_process_data(e: &mut SoftEsc) {
        let sm2 = [0x00, 0x11, 0x02, 0x00, 0x64, 0x00, 0x01, 0x00];
        let sm3 = [0x80, 0x11, 0x02, 0x00, 0x20, 0x00, 0x01, 0x00];
        let mut f0 = [0u8; 16];
        f0[4] = 2;
        f0[7] = 7;
        f0[8..10].copy_from_slice(&0x1100u16.to_le_bytes());
        f0[11] = 2;
        f0[12] = 1;
        let mut f1 = f0;
        f1[0] = 2;
        f1[8..10].copy_from_slice(&0x1180u16.to_le_bytes());
        f1[11] = 1;
        let (mut f, _) = frame(&[
            (Command::Apwr, phys(0, 0x0810), &sm2),
            (Command::Apwr, phys(0, 0x0818), &sm3),
            (Command::Apwr, phys(0, 0x0600), &f0),
            (Command::Apwr, phys(0, 0x0610), &f1),
        ]);
        e.process_frame(&mut f);
    }

    #[test]
    fn lrw_through_two_fmmus_counts_three_and_moves_both_ways() {
        let mut e = esc();
        configure_process_data(&mut e);
        e.write(0x1180, &[0xAB, 0xCD]).unwrap();
        let (mut f, r) = frame(&[(Command::Lrw, 0, &[0x11, 0x22, 0, 0])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 3);
        assert_eq!(&f[r[0].clone()], &[0x11, 0x22, 0xAB, 0xCD]);
        let mut out = [0u8; 2];
        e.read(0x1100, &mut out).unwrap();
        assert_eq!(out, [0x11, 0x22]);
        assert_eq!(e.take_sm_writes(), 1 << 2, "SM2 buffer completed");
        assert_eq!(e.take_sm_writes(), 0);
    }

    #[test]
    fn logical_access_outside_every_fmmu_is_not_counted() {
        let mut e = esc();
        configure_process_data(&mut e);
        let (mut f, r) = frame(&[(Command::Lrd, 0x100, &[0; 4])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 0);
        let (mut f, r) = frame(&[(Command::Lwr, 0, &[5, 6])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 1);
    }

    #[test]
    fn bit_granular_fmmu_maps_single_bits() {
        let mut e = esc();
        // FMMU0: logical 0x10 bit 3..bit 4 (2 bits) -> physical 0x1200 bit 0.
        let mut f0 = [0u8; 16];
        f0[0] = 0x10;
        f0[4] = 1;
        f0[6] = 3;
        f0[7] = 4;
        f0[8..10].copy_from_slice(&0x1200u16.to_le_bytes());
        f0[11] = 2;
        f0[12] = 1;
        let (mut f, _) = frame(&[(Command::Apwr, phys(0, 0x0600), &f0)]);
        e.process_frame(&mut f);
        let (mut f, r) = frame(&[(Command::Lwr, 0x10, &[0b0001_1000])]);
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 1);
        assert_eq!(e.mem_u8(0x1200), 0b11);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Any FMMU (bit or byte granular, read or write) moves exactly the
        /// bits a per-bit model of ETG.1000.4 says, in both directions, and
        /// counts when its bit range meets the datagram's.
        #[test]
        fn fmmu_bit_mapping_matches_a_per_bit_model(
            logical in 0x10u32..0x18,
            len in 1u16..=3,
            start_bit in 0u8..8,
            stop_bit in 0u8..8,
            physical_bit in 0u8..8,
            write in any::<bool>(),
            memory in any::<[u8; 8]>(),
            at in 0x0Cu32..0x1C,
            data in prop::collection::vec(any::<u8>(), 1..8),
        ) {
            let mut e = esc();
            let mut f0 = [0u8; 16];
            f0[0..4].copy_from_slice(&logical.to_le_bytes());
            f0[4..6].copy_from_slice(&len.to_le_bytes());
            f0[6] = start_bit;
            f0[7] = stop_bit;
            f0[8..10].copy_from_slice(&0x1200u16.to_le_bytes());
            f0[10] = physical_bit;
            f0[11] = if write { 2 } else { 1 };
            f0[12] = 1;
            let (mut f, _) = frame(&[
                (Command::Apwr, phys(0, 0x0600), &f0),
                (Command::Apwr, phys(0, 0x1200), &memory),
            ]);
            e.process_frame(&mut f);

            // The model.
            let bit = |bytes: &[u8], i: u64| bytes[(i / 8) as usize] >> (i % 8) & 1;
            let set = |bytes: &mut [u8], i: u64, v: u8| {
                let m = 1u8 << (i % 8);
                let b = &mut bytes[(i / 8) as usize];
                *b = if v != 0 { *b | m } else { *b & !m };
            };
            let l_first = u64::from(logical) * 8 + u64::from(start_bit);
            let l_last = (u64::from(logical) + u64::from(len) - 1) * 8 + u64::from(stop_bit);
            let d_first = u64::from(at) * 8;
            let d_end = d_first + data.len() as u64 * 8;
            let mut want_memory = memory;
            let mut want_data = data.clone();
            let mut hit = false;
            for l in l_first.max(d_first)..(l_last + 1).min(d_end) {
                hit = true;
                let p = u64::from(physical_bit) + (l - l_first);
                if write {
                    set(&mut want_memory, p, bit(&data, l - d_first));
                } else {
                    set(&mut want_data, l - d_first, bit(&memory, p));
                }
            }

            let cmd = if write { Command::Lwr } else { Command::Lrd };
            let (mut f, r) = frame(&[(cmd, at, &data)]);
            e.process_frame(&mut f);
            prop_assert_eq!(wkc(&f, &r[0]), u16::from(hit));
            prop_assert_eq!(&f[r[0].clone()], &want_data[..]);
            let (mut f, r) = frame(&[(Command::Aprd, phys(0, 0x1200), &[0; 8])]);
            e.process_frame(&mut f);
            prop_assert_eq!(&f[r[0].clone()], &want_memory[..]);
        }
    }

    #[test]
    fn frames_that_are_not_ethercat_or_are_broken_are_left_untouched() {
        let mut e = esc();
        let mut ip = vec![0u8; 60];
        ip[12] = 0x08;
        assert_eq!(e.process_frame(&mut ip), FrameOutcome::NotEthercat);
        assert!(ip[6..12].iter().all(|b| *b == 0));
        let mut short = vec![0u8; 10];
        assert_eq!(e.process_frame(&mut short), FrameOutcome::Malformed);
        // EtherCAT header claiming more payload than the frame holds.
        let (mut f, _) = frame(&[(Command::Brd, 0, &[0])]);
        f[14] = 0xFF;
        f[15] = 0x17;
        assert_eq!(e.process_frame(&mut f), FrameOutcome::Malformed);
    }

    #[test]
    fn datagram_length_beyond_the_frame_stops_processing_without_damage() {
        let mut e = esc();
        let (mut f, r) = frame(&[(Command::Bwr, phys(0, 0x0010), &[1, 2])]);
        // Claim 0x200 data bytes in the datagram header.
        f[r[0].start - 4] = 0x00;
        f[r[0].start - 3] = 0x02;
        let outcome = e.process_frame(&mut f);
        assert_eq!(outcome, FrameOutcome::Processed { datagrams: 0 });
        assert_eq!(e.mem_u16(reg::STATION_ADDRESS), 0);
    }

    #[test]
    fn unknown_commands_are_passed_on_unchanged() {
        let mut e = esc();
        let (mut f, r) = frame(&[(Command::Unknown(0x33), 0, &[1, 2, 3])]);
        let before = f.clone();
        e.process_frame(&mut f);
        assert_eq!(wkc(&f, &r[0]), 0);
        assert_eq!(f[14..], before[14..]);
    }

    #[test]
    fn sm_watchdog_expires_after_1000_ticks_of_100_us_and_rearms_on_output_writes() {
        let mut e = esc();
        configure_process_data(&mut e);
        assert_eq!(e.watchdog_base_ns(), 100_000, "default 2498 gives 100 us");
        let (mut f, _) = frame(&[(Command::Lrw, 0, &[1, 2, 0, 0])]);
        e.process_frame(&mut f);
        e.update_watchdogs(0);
        e.update_watchdogs(99_999_999);
        assert_eq!(
            e.mem_u16(reg::WATCHDOG_STATUS_PD) & 1,
            1,
            "not yet at 99.99 ms"
        );
        e.update_watchdogs(100_000_000);
        assert_eq!(
            e.mem_u16(reg::WATCHDOG_STATUS_PD) & 1,
            0,
            "expired at 100 ms"
        );
        assert_eq!(e.mem_u8(reg::WATCHDOG_COUNTER_PD), 1);
        e.update_watchdogs(300_000_000);
        assert_eq!(e.mem_u8(reg::WATCHDOG_COUNTER_PD), 1, "counted once");
        let (mut f, _) = frame(&[(Command::Lrw, 0, &[1, 2, 0, 0])]);
        e.process_frame(&mut f);
        e.update_watchdogs(300_000_001);
        assert_eq!(
            e.mem_u16(reg::WATCHDOG_STATUS_PD) & 1,
            1,
            "fresh outputs re-arm"
        );
    }

    #[test]
    fn pd_watchdog_expiry_raises_al_event_6_until_the_pdi_reads_0x0440() {
        let mut e = esc();
        configure_process_data(&mut e);
        let _ = e.read_u32(reg::AL_EVENT_REQUEST);
        let (mut f, _) = frame(&[(Command::Lrw, 0, &[1, 2, 0, 0])]);
        e.process_frame(&mut f);
        e.update_watchdogs(0);
        let ev = |e: &mut SoftEsc| e.read_u32(reg::AL_EVENT_REQUEST).unwrap();
        assert_eq!(ev(&mut e) & reg::AL_EVENT_WATCHDOG_PD, 0);
        e.update_watchdogs(100_000_000);
        assert_ne!(ev(&mut e) & reg::AL_EVENT_WATCHDOG_PD, 0, "expired");
        assert!(e.al_event_pending());
        e.read_u16(reg::WATCHDOG_STATUS_PD).unwrap();
        assert_eq!(ev(&mut e) & reg::AL_EVENT_WATCHDOG_PD, 0, "acknowledged");
    }

    #[test]
    fn sm_reconfiguration_raises_al_event_4_until_the_pdi_reads_an_activation_register() {
        let mut e = esc();
        let ev = |e: &mut SoftEsc| e.read_u32(reg::AL_EVENT_REQUEST).unwrap();
        assert_eq!(ev(&mut e), 0, "a fresh ESC has no event");
        assert!(!e.al_event_pending());
        configure_mailbox(&mut e);
        assert_ne!(ev(&mut e) & reg::AL_EVENT_SM_CHANGED, 0);
        // Reading SM0's start address does not acknowledge it...
        e.read_u16(0x0800).unwrap();
        assert_ne!(ev(&mut e) & reg::AL_EVENT_SM_CHANGED, 0);
        // ...reading the whole SM block (activation at offset 6) does.
        let mut sm = [0u8; 8];
        e.read(0x0800, &mut sm).unwrap();
        assert_eq!(ev(&mut e) & reg::AL_EVENT_SM_CHANGED, 0);
        // Writing the same configuration again is no change.
        configure_mailbox(&mut e);
        assert_eq!(ev(&mut e) & reg::AL_EVENT_SM_CHANGED, 0);
    }

    #[test]
    fn pdi_writing_an_input_buffer_acknowledges_its_read_event() {
        let mut e = esc();
        configure_process_data(&mut e);
        let (mut f, _) = frame(&[(Command::Lrd, 2, &[0, 0])]);
        e.process_frame(&mut f);
        let sm3 = reg::al_event_sm(3);
        assert_ne!(e.read_u32(reg::AL_EVENT_REQUEST).unwrap() & sm3, 0);
        assert_ne!(e.mem_u8(0x081D) & smr::STATUS_READ_EVENT, 0);
        e.write(0x1180, &[5, 6]).unwrap();
        assert_eq!(e.read_u32(reg::AL_EVENT_REQUEST).unwrap() & sm3, 0);
        assert_eq!(e.mem_u8(0x081D) & smr::STATUS_READ_EVENT, 0);
    }

    #[test]
    fn watchdog_time_zero_disables_and_the_divider_scales_the_tick() {
        let mut e = esc();
        configure_process_data(&mut e);
        let (mut f, _) = frame(&[(Command::Bwr, phys(0, reg::WATCHDOG_TIME_PD), &[0, 0])]);
        e.process_frame(&mut f);
        let (mut f, _) = frame(&[(Command::Lrw, 0, &[1, 2, 0, 0])]);
        e.process_frame(&mut f);
        e.update_watchdogs(0);
        e.update_watchdogs(10_000_000_000);
        assert_eq!(e.mem_u16(reg::WATCHDOG_STATUS_PD) & 1, 1, "0 disables");
        // Divider 4998: 200 us ticks; 1000 ticks = 200 ms.
        let (mut f, _) = frame(&[
            (
                Command::Bwr,
                phys(0, reg::WATCHDOG_TIME_PD),
                &1000u16.to_le_bytes(),
            ),
            (
                Command::Bwr,
                phys(0, reg::WATCHDOG_DIVIDER),
                &4998u16.to_le_bytes(),
            ),
            (Command::Lrw, 0, &[1, 2, 0, 0]),
        ]);
        e.process_frame(&mut f);
        e.update_watchdogs(20_000_000_000);
        e.update_watchdogs(20_199_000_000);
        assert_eq!(e.mem_u16(reg::WATCHDOG_STATUS_PD) & 1, 1);
        e.update_watchdogs(20_200_000_000);
        assert_eq!(e.mem_u16(reg::WATCHDOG_STATUS_PD) & 1, 0);
    }

    #[test]
    fn pdi_watchdog_expires_when_the_firmware_stops_accessing_the_esc() {
        let mut e = esc();
        e.read_u16(reg::AL_CONTROL).unwrap();
        e.update_watchdogs(0);
        e.update_watchdogs(50_000_000);
        assert!(!e.pdi_watchdog_expired());
        e.update_watchdogs(100_000_000);
        assert!(e.pdi_watchdog_expired());
        assert_eq!(e.mem_u8(reg::WATCHDOG_COUNTER_PDI), 1);
        assert_eq!(
            e.mem_u16(reg::DL_STATUS) & 0x0002,
            0,
            "visible to the master"
        );
        e.read_u16(reg::AL_CONTROL).unwrap();
        e.update_watchdogs(100_000_001);
        assert!(!e.pdi_watchdog_expired());
    }

    /// A frame of EtherType 0x88A4 with random header and datagram bytes;
    /// half of them with an EtherCAT header whose length fits, so
    /// datagrams are reached.
    fn random_frame() -> impl Strategy<Value = Vec<u8>> {
        (prop::collection::vec(any::<u8>(), 14..214), any::<bool>()).prop_map(
            |(mut f, plausible)| {
                f[12] = 0x88;
                f[13] = 0xA4;
                if plausible && f.len() > 16 {
                    let pl = (f.len() - 16) as u16;
                    f[14] = pl as u8;
                    f[15] = 0x10 | ((pl >> 8) as u8 & 0x07);
                }
                f
            },
        )
    }

    proptest! {
        // 200 sequences of 100 frames: the 20 000 of the xorshift loop this
        // replaces.
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Random frames against one ESC with mailbox and process data
        /// configured never panic it.
        #[test]
        fn random_frames_never_panic(frames in prop::collection::vec(random_frame(), 100)) {
            let mut e = esc();
            configure_mailbox(&mut e);
            configure_process_data(&mut e);
            for mut f in frames {
                e.process_frame(&mut f);
            }
        }
    }
    /// An ECAT write of `data` at `addr` to a single ESC at frame time `t`.
    fn ecat_write_at(e: &mut SoftEsc, t: u64, addr: u16, data: &[u8]) {
        e.set_frame_times(t, None);
        let (mut f, _) = frame(&[(Command::Apwr, phys(0, addr), data)]);
        e.process_frame(&mut f);
    }

    /// An ECAT read of `len` bytes at `addr` at frame time `t`.
    fn ecat_read_at(e: &mut SoftEsc, t: u64, addr: u16, len: usize) -> Vec<u8> {
        e.set_frame_times(t, None);
        let zeros = vec![0u8; len];
        let (mut f, r) = frame(&[(Command::Aprd, phys(0, addr), &zeros)]);
        e.process_frame(&mut f);
        f[r[0].clone()].to_vec()
    }

    #[test]
    fn a_write_to_0x0900_latches_the_receive_times_of_both_ports_in_local_time() {
        let mut e = esc();
        e.set_dc_oscillator(1_000_000); // +1000 ppm, to see local != injected
        e.set_frame_times(2_000_000, Some(2_003_000));
        let (mut f, _) = frame(&[(Command::Bwr, phys(0, 0x0900), &[0, 0, 0, 0])]);
        e.process_frame(&mut f);
        let m = e.raw_memory();
        let p0 = u32::from_le_bytes(m[0x900..0x904].try_into().unwrap());
        let p1 = u32::from_le_bytes(m[0x904..0x908].try_into().unwrap());
        assert_eq!(p0, 2_002_000, "2 ms at +1000 ppm");
        assert_eq!(p1, 2_005_003);
        let pu = u64::from_le_bytes(m[0x918..0x920].try_into().unwrap());
        assert_eq!(pu, 2_002_000, "processing unit = port 0 time");
    }

    #[test]
    fn system_time_reads_local_time_plus_offset_at_the_frame_time() {
        let mut e = esc();
        ecat_write_at(&mut e, 0, 0x0920, &1_000_000_000u64.to_le_bytes());
        let v = ecat_read_at(&mut e, 5_000, 0x0910, 8);
        assert_eq!(u64::from_le_bytes(v.try_into().unwrap()), 1_000_005_000);
    }

    /// An ESC whose SII maps SYNC0 into the AL event request (0x0151 = 0x0C).
    fn esc_sync0_mapped() -> SoftEsc {
        let mut sii = [0xFFu8; 128];
        sii[..16].fill(0);
        sii[3] = 0x0C;
        SoftEsc::new(&sii)
    }

    #[test]
    fn sync0_raises_its_al_event_only_when_the_sii_maps_it() {
        for (mut e, mapped) in [(esc(), false), (esc_sync0_mapped(), true)] {
            ecat_write_at(&mut e, 0, 0x0990, &1_000u64.to_le_bytes());
            ecat_write_at(&mut e, 0, 0x09A0, &1_000u32.to_le_bytes());
            ecat_write_at(&mut e, 0, 0x0981, &[0x03]);
            e.update_dc(5_000);
            assert_eq!(e.mem_u8(reg::DC_SYNC0_STATUS) & 1, 1, "status either way");
            assert_eq!(
                e.mem_u32(reg::AL_EVENT_REQUEST) & reg::AL_EVENT_SYNC0 != 0,
                mapped
            );
        }
    }

    #[test]
    fn sync0_pulses_at_start_plus_whole_cycles_and_a_pdi_read_acknowledges_it() {
        let mut e = esc_sync0_mapped();
        ecat_write_at(&mut e, 0, 0x0990, &1_000_000u64.to_le_bytes());
        ecat_write_at(&mut e, 0, 0x09A0, &250_000u32.to_le_bytes());
        ecat_write_at(&mut e, 0, 0x0981, &[0x03]);
        assert_eq!(e.sync0_next(), Some(1_000_000));
        e.update_dc(999_999);
        assert_eq!(e.sync0_pulses(), 0, "not before the start time");
        e.update_dc(1_600_000);
        assert_eq!(e.sync0_pulses(), 3, "1.0, 1.25 and 1.5 ms");
        assert_eq!(e.sync0_last(), Some(1_500_000));
        assert_eq!(e.sync0_next(), Some(1_750_000));
        assert_ne!(e.mem_u32(reg::AL_EVENT_REQUEST) & reg::AL_EVENT_SYNC0, 0);
        assert_eq!(e.read_u8(reg::DC_SYNC0_STATUS).unwrap() & 1, 1);
        assert_eq!(
            e.mem_u32(reg::AL_EVENT_REQUEST) & reg::AL_EVENT_SYNC0,
            0,
            "acknowledged"
        );
        assert_eq!(e.mem_u8(reg::DC_SYNC0_STATUS) & 1, 0);
        // 0x0990 reads as the next pulse.
        let next = ecat_read_at(&mut e, 1_600_000, 0x0990, 8);
        assert_eq!(u64::from_le_bytes(next.try_into().unwrap()), 1_750_000);
        // Deactivated: no more pulses.
        ecat_write_at(&mut e, 1_600_000, 0x0981, &[0x00]);
        e.update_dc(10_000_000);
        assert_eq!(e.sync0_pulses(), 3);
    }

    #[test]
    fn a_start_time_in_the_past_waits_for_the_32_bit_wrap() {
        let mut e = esc();
        ecat_write_at(&mut e, 0, 0x0990, &500u64.to_le_bytes());
        ecat_write_at(&mut e, 0, 0x09A0, &1_000u32.to_le_bytes());
        ecat_write_at(&mut e, 1_000_000, 0x0981, &[0x03]);
        assert_eq!(e.sync0_next(), Some(500 + (1 << 32)));
        e.update_dc(2_000_000_000);
        assert_eq!(e.sync0_pulses(), 0);
    }

    #[test]
    fn writing_the_speed_counter_start_resets_the_drift_control() {
        let mut e = esc();
        // A received time 1 ms behind: the loop corrects.
        ecat_write_at(&mut e, 2_000_000, 0x0910, &1_000_000u64.to_le_bytes());
        assert_ne!(e.dc_clock().correction_ppb(), 0);
        assert_ne!(e.dc_difference(), 0);
        ecat_write_at(&mut e, 2_000_000, 0x0930, &0x1000u16.to_le_bytes());
        assert_eq!(e.dc_clock().correction_ppb(), 0);
        assert_eq!(e.dc_difference(), 0);
    }
    #[test]
    fn a_pdi_access_from_the_registers_into_process_ram_reaches_both() {
        let mut e = esc();
        // AL status code (writable by the PDI) up to 0x1001.
        let mut data = vec![0u8; 0x1002 - 0x0FFE];
        data[2] = 0xAB;
        data[3] = 0xCD;
        e.write(0x0FFE, &data).unwrap();
        assert_eq!(&e.raw_memory()[0x1000..0x1002], &[0xAB, 0xCD]);
        let mut back = [0u8; 4];
        e.read(0x0FFE, &mut back).unwrap();
        assert_eq!(&back[2..], &[0xAB, 0xCD]);
    }

    #[test]
    fn a_pdi_read_of_the_system_time_reads_the_clock_now() {
        let mut e = esc();
        e.set_frame_times(7_000, None);
        assert_eq!(e.read_u32(0x0910).unwrap(), 7_000);
        e.set_frame_times(9_000, None);
        assert_eq!(e.read_u32(0x0910).unwrap(), 9_000);
        e.set_frame_times(1_000, None);
        assert_eq!(
            e.read_u32(0x0910).unwrap(),
            9_000,
            "a clock never runs back"
        );
    }

    #[test]
    fn only_a_whole_low_word_of_0x0910_is_a_received_time() {
        let mut e = esc();
        ecat_write_at(&mut e, 2_000_000, 0x0912, &[1, 2]);
        assert_eq!(e.dc_clock().correction_ppb(), 0, "2 bytes: ignored");
        ecat_write_at(&mut e, 2_000_000, 0x0910, &1_000_000u32.to_le_bytes());
        assert_ne!(e.dc_clock().correction_ppb(), 0, "32-bit time compared");
    }

    #[test]
    fn a_start_time_far_in_the_past_arms_without_looping() {
        let mut e = esc();
        // System time near 2^60 (a master's epoch), start time 0.
        ecat_write_at(&mut e, 0, 0x0920, &(1u64 << 60).to_le_bytes());
        ecat_write_at(&mut e, 0, 0x09A0, &1_000u32.to_le_bytes());
        ecat_write_at(&mut e, 0, 0x0981, &[0x03]);
        let next = e.sync0_next().unwrap();
        assert!(next >= 1 << 60 && next - (1 << 60) <= 1 << 32);
        assert_eq!(next % (1 << 32), 0, "the low 32 bits of the start time");
        // A start time near the end of time does not overflow.
        ecat_write_at(&mut e, 0, 0x0981, &[0x00]);
        ecat_write_at(&mut e, 0, 0x0990, &(u64::MAX - 10).to_le_bytes());
        ecat_write_at(&mut e, 0, 0x0920, &(u64::MAX - 5).to_le_bytes());
        ecat_write_at(&mut e, 0, 0x0981, &[0x03]);
        e.update_dc(u64::MAX);
    }
}
