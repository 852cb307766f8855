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
//!
//! One file per part of the chip, each an `impl SoftEsc` block: frame
//! processing and addressing (`frame.rs`), ECAT access to
//! physical memory with the SyncManager rules (`physical.rs`), the
//! SyncManagers (`sm.rs`) and FMMUs (`fmmu.rs`), register side effects
//! (`registers.rs`), the SII interface (`sii.rs`), the watchdogs
//! (`watchdog.rs`), the ports (`link.rs`), station addressing
//! (`addressing.rs`), the DC unit's registers (`dc_unit.rs`, its clock in
//! [`dc`]), the PDI side (`pdi.rs`) and raw memory access (`memory.rs`).

mod addressing;
mod ahead;
pub mod dc;
mod dc_unit;
mod fmmu;
mod frame;
mod link;
mod memory;
mod pdi;
mod physical;
mod registers;
mod sii;
mod silicon;
mod sm;
mod watchdog;

pub use ahead::SystemTimeAhead;
pub use pdi::PdiFault;
pub use silicon::Silicon;

use dc::DcClock;
use ecat_slave::esc::Esc;
use ecat_slave::esc::EscError;
use ecat_slave::esc::registers::{self as reg, sm as smr};
use ecat_slave::wire::ecat::{Addressing, Command, Datagram, DatagramCursor, EcatFrame, FrameType};
use ecat_slave::wire::ethernet::{ETHERTYPE_ETHERCAT, EthernetFrame};
use fmmu::{FmmuConfig, FmmuRoute};
use physical::ReadMode;
use sm::SmConfig;

/// Size of the ESC address space modelled by default: 4 KiB registers +
/// 8 KiB process RAM, as an ET1100.
pub const MEM_SIZE: usize = 0x3000;
/// The largest address space an ESC has: 4 KiB registers + 60 KiB process
/// RAM (ESCs on FPGAs, e.g. Beckhoff's EL6695 puts SM3 at 0x8E00).
pub const MAX_MEM_SIZE: usize = 0x1_0000;
/// Number of SyncManagers implemented.
pub const SM_COUNT: usize = 8;
/// Number of FMMUs implemented.
pub const FMMU_COUNT: usize = 8;
/// ESC configuration register 0x0141 bit 0, "device emulation": the AL
/// status follows the AL control register (ESCs without a firmware).
pub const ESC_CONFIG_DEVICE_EMULATION: u8 = 0x01;

pub use ecat_slave::sii::SII_SIZE;
/// The largest EEPROM the software ESC emulates (512 Kbit): an image
/// longer than [`SII_SIZE`] (a vendor's terminal with hundreds of PDO
/// entries) gets an EEPROM of its own length, up to this.
pub const MAX_SII_SIZE: usize = 0x1_0000;
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

/// The software ESC.
pub struct SoftEsc {
    /// Registers and process RAM ([`MEM_SIZE`] bytes unless the device
    /// needs more, [`SoftEsc::with_memory`]).
    mem: Vec<u8>,
    /// The EEPROM: [`SII_SIZE`] bytes, or an image's length up to
    /// [`MAX_SII_SIZE`].
    sii: Vec<u8>,
    /// The chip's profile: identity registers, units, EEPROM timing.
    silicon: Silicon,
    /// Injected time at which the running EEPROM command ends.
    sii_busy_until: Option<u64>,
    sms: [SmConfig; SM_COUNT],
    fmmus: [FmmuConfig; FMMU_COUNT],
    /// Bit n set: FMMU n enabled (fast skip in logical addressing).
    fmmu_active: u8,
    /// Bit n set: FMMU n enabled and reads (its type's bit 0).
    fmmu_reads: u8,
    /// Bit n set: FMMU n enabled and writes (its type's bit 1).
    fmmu_writes: u8,
    /// Each FMMU's whole-window transfer for the current configuration.
    routes: [FmmuRoute; FMMU_COUNT],
    /// Whether `routes` must be worked out again (an FMMU or SyncManager
    /// changed) before the next logical datagram.
    routes_stale: bool,
    /// Whether logical datagrams take the routes (off only in the tests
    /// that compare them with the general path).
    fast_routes: bool,
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
    /// (as [`SoftEsc::program_sii`] does; the rest reads 0xFF) and taking the
    /// station alias and PDI configuration from it.
    pub fn new(sii: &[u8]) -> Self {
        Self::with_memory(sii, MEM_SIZE)
    }

    /// [`SoftEsc::new`] with an address space of `size` bytes (registers
    /// and process RAM; clamped to [`MEM_SIZE`]..=[`MAX_MEM_SIZE`] and
    /// rounded up to whole KiB), shown in the RAM size register 0x0006:
    /// for devices whose SyncManagers lie beyond an ET1100's 8 KiB.
    pub fn with_memory(sii: &[u8], size: usize) -> Self {
        let size = size.clamp(MEM_SIZE, MAX_MEM_SIZE).next_multiple_of(1024);
        let mut esc = SoftEsc {
            mem: vec![0; size],
            sii: Vec::new(),
            silicon: Silicon::SOFT,
            sii_busy_until: None,
            sms: [SmConfig::default(); SM_COUNT],
            fmmus: [FmmuConfig::default(); FMMU_COUNT],
            fmmu_active: 0,
            fmmu_reads: 0,
            fmmu_writes: 0,
            routes: [FmmuRoute::default(); FMMU_COUNT],
            routes_stale: true,
            fast_routes: true,
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
        esc.program_sii(sii);
        esc.power_on();
        esc
    }

    /// Programs a whole SII image into the EEPROM (of [`SII_SIZE`] bytes,
    /// or the image's length up to [`MAX_SII_SIZE`]; the rest erased to
    /// 0xFF), as a configurator writes a device's EEPROM; the ESC loads it
    /// at its next power-on.
    pub fn program_sii(&mut self, image: &[u8]) {
        let n = image.len().min(MAX_SII_SIZE);
        self.sii.clear();
        self.sii.resize(n.next_multiple_of(128).max(SII_SIZE), 0xFF);
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

    /// Resets every register to its power-on value (as a power cycle does);
    /// process RAM is cleared, the SII image is kept.
    pub fn power_on(&mut self) {
        self.mem.fill(0);
        self.sms = [SmConfig::default(); SM_COUNT];
        self.fmmus = [FmmuConfig::default(); FMMU_COUNT];
        self.fmmu_active = 0;
        self.fmmu_reads = 0;
        self.fmmu_writes = 0;
        self.routes_stale = true;
        self.fmmu_gen = self.fmmu_gen.wrapping_add(1);
        self.sm_active = 0;
        self.sm_written = 0;
        self.wd_sm_trigger = false;
        self.wd_sm_armed_at = None;
        self.pdi_touched = false;
        self.wd_pdi_at = None;
        self.sii_busy_until = None;
        let si = self.silicon;
        self.set_u8(reg::TYPE, si.esc_type);
        self.set_u8(reg::REVISION, si.revision);
        self.set_u16(reg::BUILD, si.build);
        self.set_u8(reg::FMMU_COUNT, si.fmmus);
        self.set_u8(reg::SM_COUNT, si.sms);
        let ram_kib = (self.mem.len() - 0x1000) / 1024;
        let ram_kib = si
            .ram_kib
            .unwrap_or(u8::try_from(ram_kib).unwrap_or(u8::MAX));
        self.set_u8(reg::RAM_SIZE, ram_kib);
        self.set_u8(reg::PORT_DESCRIPTOR, si.port_descriptor);
        self.set_u16(reg::FEATURES, si.features);
        if let Some((port1, port3)) = si.dc_marks {
            self.set_u32(reg::DC_RECEIVE_TIME_PORT0 + 4, u32::from_le_bytes(port1));
            self.set_u32(reg::DC_RECEIVE_TIME_PORT0 + 12, u32::from_le_bytes(port3));
        }
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
        // The EEPROM interface's status bits (8-byte reads).
        self.set_u16(reg::SII_CONTROL, si.sii_status);
        // The PDI watchdog starts reloaded (set_port1_link keeps it, and
        // clears it for an ESC without a PDI).
        self.set_u16(reg::DL_STATUS, reg::dl_status::PDI_WATCHDOG_OK);
        self.set_port1_link(false);
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

    /// Whether the AL event request register (0x0220) holds an event for
    /// the firmware: what makes an interrupt-driven firmware run.
    pub fn al_event_pending(&self) -> bool {
        self.mem_u32(reg::AL_EVENT_REQUEST) != 0
    }

    pub(super) fn raise_al_event(&mut self, bits: u32) {
        let v = self.mem_u32(reg::AL_EVENT_REQUEST) | bits;
        self.set_u32(reg::AL_EVENT_REQUEST, v);
    }

    pub(super) fn clear_al_event(&mut self, bits: u32) {
        let v = self.mem_u32(reg::AL_EVENT_REQUEST) & !bits;
        self.set_u32(reg::AL_EVENT_REQUEST, v);
    }
}

#[cfg(test)]
mod tests;
