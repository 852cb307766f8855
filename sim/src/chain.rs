//! A line of software slaves that frames pass through in order, whatever
//! devices they are.
//!
//! [`Chain::process`] gives the same result as passing the frame through
//! every slave's ESC one after the other ([`Chain::process_serial`]), but
//! parses the frame once and hands each datagram only to the slaves it
//! addresses: a configured-address datagram to the slave with that station
//! address or alias, an auto-increment datagram to the slave at that
//! position, broadcast and logical datagrams to every slave in line order.
//! Only addressed slaves change a datagram, so the outcome is identical;
//! the test `dispatch_equals_serial_processing` checks it on random traffic.
//!
//! Slaves of different devices share a line through [`LineSlave`], the
//! object-safe face of a [`SoftSlave`]; [`Chain::slave`] gives a test the
//! typed slave back.

use std::any::Any;

use crate::esc::{FrameOutcome, SoftEsc};
use crate::image_store::VecStore;
use crate::slave::{SoftPdi, SoftSlave, SpiStats};
use ecat_slave::al::AlStatus;
use ecat_slave::device::{Application, DeviceDescription};
use ecat_slave::esc::EscError;
use ecat_slave::firmware::{self, FirmwareVersion, ImageStore, StoreError};
use ecat_slave::hal::NvStorage;
use ecat_slave::led::LedPattern;
use ecat_slave::od::Od;
use ecat_slave::wire::ecat::{
    Addressing, Command, DatagramHead, DatagramParts, EcatFrame, FrameType, MAX_DATAGRAMS,
};
use ecat_slave::wire::ethernet::{ETHERTYPE_ETHERCAT, EthernetFrame};

mod ahead;
pub use ahead::Ahead;

/// Slot capacity of a software slave's firmware store (2 MiB).
pub const IMAGE_SLOT_CAPACITY: usize = 2 * 1024 * 1024;

/// Version of the factory firmware a software slave starts with.
pub const FACTORY_VERSION: &str = "10";

/// Gives a blank image store the factory firmware (slot A, version
/// [`FACTORY_VERSION`]); a store that already holds a boot state is kept.
pub fn provision_factory(store: &mut dyn ImageStore) -> Result<(), StoreError> {
    match store.read_state() {
        Ok(_) => Ok(()),
        Err(_) => {
            let payload = b"simulated factory firmware 10";
            let v = FirmwareVersion::new(FACTORY_VERSION).ok_or(StoreError::OutOfBounds)?;
            firmware::provision(store, v, payload)
        }
    }
}

fn factory_image_store() -> Box<dyn ImageStore + Send> {
    factory_image_store_of(IMAGE_SLOT_CAPACITY)
}

/// A heap image store with slots of `capacity` bytes holding the factory
/// firmware ([`provision_factory`]); memory follows what is written, up to
/// two slots of `capacity` bytes.
pub fn factory_image_store_of(capacity: usize) -> Box<dyn ImageStore + Send> {
    let mut store = VecStore::new(capacity);
    let _ = provision_factory(&mut store);
    Box::new(store)
}

/// A software slave of any device, as a line holds it.
pub trait LineSlave: Send {
    /// The device's description.
    fn description(&self) -> &'static DeviceDescription;
    /// Passes an Ethernet frame through the ESC (in place).
    fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome;
    /// The software ESC.
    fn esc(&self) -> &SoftEsc;
    /// The software ESC, mutably.
    fn esc_mut(&mut self) -> &mut SoftEsc;
    /// Runs the firmware once ([`SoftSlave::poll_with`]).
    fn poll_with(
        &mut self,
        now_ns: u64,
        images: Option<&mut dyn ImageStore>,
    ) -> Result<(), EscError>;
    /// A power cycle ([`SoftSlave::power_cycle`]).
    fn power_cycle(&mut self);
    /// Sets whether port 1 has a link.
    fn set_port1_link(&mut self, link: bool);
    /// Sets 0x100A to the version that runs.
    fn set_firmware_version(&mut self, version: &str);
    /// The bootloader started no image: only INIT and BOOT are accepted
    /// ([`Slave::set_no_valid_firmware`](ecat_slave::device::Slave::set_no_valid_firmware)).
    fn set_no_valid_firmware(&mut self, none: bool);
    /// The version in 0x100A.
    fn firmware_version(&self) -> String;
    /// RUN and ERR LED patterns.
    fn led_patterns(&self) -> (LedPattern, LedPattern);
    /// Whether RUN and ERR are lit now.
    fn leds(&self) -> (bool, bool);
    /// Simulates the firmware stalling.
    fn set_stalled(&mut self, stalled: bool);
    /// The SPI wire's counters when the firmware reaches its ESC through
    /// an SPI driver and an emulated chip ([`SoftPdi::spi_stats`]).
    fn spi_stats(&self) -> Option<SpiStats> {
        None
    }
    /// Switches emergencies on or off.
    fn set_emergencies(&mut self, enabled: bool);
    /// Emergencies waiting for the master.
    fn emergencies_waiting(&self) -> usize;
    /// The AL status the firmware holds.
    fn al_status(&self) -> AlStatus;
    /// The live object dictionary.
    fn od(&self) -> &Od;
    /// The live object dictionary, mutably.
    fn od_mut(&mut self) -> &mut Od;
    /// The application's non-volatile storage, if it has one.
    fn nv(&self) -> Option<&dyn NvStorage>;
    /// The application's non-volatile storage, mutably.
    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage>;
    /// For [`Chain::slave`].
    fn as_any(&self) -> &dyn Any;
    /// For [`Chain::slave_mut`].
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<A: Application + Send + 'static, P: SoftPdi + Send + 'static> LineSlave for SoftSlave<A, P> {
    fn description(&self) -> &'static DeviceDescription {
        self.slave().description()
    }
    fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome {
        SoftSlave::process_frame(self, frame)
    }
    fn esc(&self) -> &SoftEsc {
        self.slave().esc().soft_esc()
    }
    fn spi_stats(&self) -> Option<SpiStats> {
        self.slave().esc().spi_stats()
    }
    fn esc_mut(&mut self) -> &mut SoftEsc {
        self.slave_mut().esc_mut().soft_esc_mut()
    }
    fn poll_with(
        &mut self,
        now_ns: u64,
        images: Option<&mut dyn ImageStore>,
    ) -> Result<(), EscError> {
        SoftSlave::poll_with(self, now_ns, images)
    }
    fn power_cycle(&mut self) {
        SoftSlave::power_cycle(self);
    }
    fn set_port1_link(&mut self, link: bool) {
        SoftSlave::set_port1_link(self, link);
    }
    fn set_firmware_version(&mut self, version: &str) {
        self.slave_mut().set_firmware_version(version);
    }
    fn set_no_valid_firmware(&mut self, none: bool) {
        self.slave_mut().set_no_valid_firmware(none);
    }
    fn firmware_version(&self) -> String {
        self.slave().firmware_version().as_str().to_string()
    }
    fn led_patterns(&self) -> (LedPattern, LedPattern) {
        SoftSlave::led_patterns(self)
    }
    fn leds(&self) -> (bool, bool) {
        SoftSlave::leds(self)
    }
    fn set_stalled(&mut self, stalled: bool) {
        SoftSlave::set_stalled(self, stalled);
    }
    fn set_emergencies(&mut self, enabled: bool) {
        SoftSlave::set_emergencies(self, enabled);
    }
    fn emergencies_waiting(&self) -> usize {
        self.slave().emergencies_waiting()
    }
    fn al_status(&self) -> AlStatus {
        self.slave().al_status()
    }
    fn od(&self) -> &Od {
        self.slave().od()
    }
    fn od_mut(&mut self) -> &mut Od {
        self.slave_mut().od_mut()
    }
    fn nv(&self) -> Option<&dyn NvStorage> {
        self.slave().app().nv()
    }
    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        self.slave_mut().app_mut().nv_mut()
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// A line of software slaves, first to last.
pub struct Chain {
    slaves: Vec<Box<dyn LineSlave>>,
    /// Each slave's firmware image store (A/B slots).
    images: Vec<Box<dyn ImageStore + Send>>,
    frames: u64,
    pdi_failures: u64,
    /// (station address or alias, slave position), sorted.
    addresses: Vec<(u16, usize)>,
    /// For every 16-bit address, the position in `addresses` of its first
    /// entry (`u32::MAX`: nobody answers to it): one lookup per datagram
    /// instead of a binary search.
    first_of: Vec<u32>,
    /// Each slave's address generation when `addresses` was built.
    addr_gens: Vec<u32>,
    /// Slaves a datagram reached whose firmware has not been looked at
    /// since (each once, oldest first: a [`Chain::service_until`] stopped
    /// by a frame leaves the rest here, served first next time).
    touched: Vec<usize>,
    /// Whether a broadcast or logical datagram reached every slave.
    touched_all: bool,
    /// Per slave: whether it is in `touched`.
    queued: Vec<bool>,
    /// The next slave of the round-robin sweep.
    sweep_next: usize,
    /// Whether [`Chain::idle`] runs firmware beyond what is due.
    idle_passes: bool,
    /// Time up to which the sweep has run.
    swept_until: u64,
    /// Firmware runs so far.
    runs: u64,
    /// Enabled FMMU windows of every slave: (logical start, end, slave),
    /// sorted by start.
    windows: Vec<(u64, u64, usize)>,
    /// Longest window in `windows`.
    widest: u64,
    /// Each slave's FMMU generation when `windows` was built.
    fmmu_gens: Vec<u32>,
    /// Whether `windows` must be rebuilt before the next logical datagram.
    windows_stale: bool,
    /// Whether `windows`, sorted by logical start, is in line order too
    /// (each slave's windows together, slaves first to last: the image as
    /// ethercrab lays it out), so a logical datagram reaches the slaves in
    /// the order its windows come.
    windows_in_order: bool,
    /// Scratch list of the slaves one logical datagram reaches.
    hits: Vec<usize>,
    /// Per slave: the number of the last frame whose port times its DC
    /// unit got ([`pass`]).
    stamps: Vec<u64>,
    /// Injected time of the frame being processed (it enters slave 0).
    frame_ns: u64,
    /// How long a frame takes from one slave's port 0 to the next one's
    /// (and back), for the DC receive times.
    hop_ns: u64,
}

/// Default [`Chain::set_hop_delay_ns`]: a frame's delay through one slave
/// and its cable, of the order of an ESC with MII ports (a few hundred ns;
/// EBUS ESCs forward faster).
pub const DEFAULT_HOP_NS: u64 = 500;

/// When a frame entering the line at `t` passes slave `i` of `n`: port 0
/// at `t + i·hop`, port 1 at `t + (2(n−1) − i)·hop` (none for the last).
fn port_times(i: usize, n: usize, (t, hop): (u64, u64)) -> (u64, Option<u64>) {
    let k = i as u64;
    let p0 = t.saturating_add(k.saturating_mul(hop));
    let p1 = (i + 1 < n).then(|| {
        let hops = (2 * (n as u64).saturating_sub(1)).saturating_sub(k);
        t.saturating_add(hops.saturating_mul(hop))
    });
    (p0, p1)
}

/// The frame going through the line: when it enters, how long each hop
/// takes, how many slaves it passes, and its number (see [`pass`]).
#[derive(Debug, Clone, Copy)]
struct FrameClock {
    t: u64,
    hop: u64,
    n: usize,
    frame: u64,
}

/// Hands a datagram (`head`, its data in place) to slave `i`, telling its
/// DC unit when the frame passes its ports ([`port_times`]) once per
/// frame: `stamps[i]` holds the number of the frame whose times slave `i`
/// last got (a second datagram of the same frame passes it at the same
/// times). Returns the working counter increment and the ESC's FMMU and
/// address generations after the datagram (a write may have changed
/// either).
fn pass(
    s: &mut dyn LineSlave,
    i: usize,
    clock: &FrameClock,
    stamps: &mut [u64],
    head: DatagramHead,
    data: &mut [u8],
) -> (u16, (u32, u32)) {
    let esc = s.esc_mut();
    if let Some(stamp) = stamps.get_mut(i)
        && *stamp != clock.frame
    {
        *stamp = clock.frame;
        let (p0, p1) = port_times(i, clock.n, (clock.t, clock.hop));
        esc.set_frame_times(p0, p1);
    }
    let wkc = esc.process_data(head.command, head.adp, head.ado, data);
    (wkc, (esc.fmmu_generation(), esc.address_generation()))
}

/// Queues slave `i`'s firmware for the next service, once.
fn touch(queued: &mut [bool], touched: &mut Vec<usize>, i: usize) {
    if let Some(q) = queued.get_mut(i)
        && !*q
    {
        *q = true;
        touched.push(i);
    }
}

/// Shortest time in which the sweep of [`Chain::service`] reaches every
/// slave of a line: each firmware runs at least this often even when the
/// master does not address it (watchdog supervision, the application's
/// own timing).
pub const SWEEP_MIN_NS: u64 = 1_000_000;

/// Slaves run by one [`Chain::idle`] pass besides those that are due.
pub const IDLE_BATCH: usize = 64;

/// Sweep time added per slave of the line: a line of `n` slaves is swept
/// every `max(SWEEP_MIN_NS, n × SWEEP_PER_SLAVE_NS)`, so the sweep costs
/// a bounded share of a core at any length (1024 slaves: every 10.2 ms).
pub const SWEEP_PER_SLAVE_NS: u64 = 10_000;

impl core::fmt::Debug for Chain {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Chain")
            .field("slaves", &self.slaves.len())
            .field("frames", &self.frames)
            .finish()
    }
}

impl Chain {
    /// `n` slaves of one device, each made by `make`, in their power-on
    /// state; every slave but the last reports a link on port 1.
    pub fn of<A: Application + Send + 'static>(n: usize, make: impl Fn() -> A) -> Self {
        Self::with_slaves(
            (0..n)
                .map(|_| Box::new(SoftSlave::new(make())) as Box<dyn LineSlave>)
                .collect(),
        )
    }

    /// A line of the given slaves (any devices, e.g. built with
    /// [`SoftSlave::with_layout`]), first to last, each with a factory
    /// firmware store.
    pub fn with_slaves(slaves: Vec<Box<dyn LineSlave>>) -> Self {
        let images = slaves.iter().map(|_| factory_image_store()).collect();
        Self::with_stores(slaves, images)
    }

    /// A line of slaves with their firmware image stores (e.g. file-backed
    /// ones that survive restarts). Each slave boots what its store holds.
    pub fn with_stores(
        mut slaves: Vec<Box<dyn LineSlave>>,
        mut images: Vec<Box<dyn ImageStore + Send>>,
    ) -> Self {
        images.truncate(slaves.len());
        while images.len() < slaves.len() {
            images.push(factory_image_store());
        }
        for (s, img) in slaves.iter_mut().zip(images.iter_mut()) {
            let decision = firmware::power_on(img.as_mut());
            let _ = firmware::confirm_boot(img.as_mut());
            s.set_firmware_version(decision.version.as_str());
            s.set_no_valid_firmware(decision.slot.is_none());
        }
        let last = slaves.len().saturating_sub(1);
        for (i, s) in slaves.iter_mut().enumerate() {
            s.set_port1_link(i != last);
        }
        let mut chain = Chain {
            slaves,
            images,
            frames: 0,
            pdi_failures: 0,
            addresses: Vec::new(),
            first_of: vec![u32::MAX; 1 << 16],
            addr_gens: Vec::new(),
            touched: Vec::new(),
            touched_all: false,
            queued: Vec::new(),
            sweep_next: 0,
            idle_passes: true,
            swept_until: 0,
            runs: 0,
            windows: Vec::new(),
            widest: 0,
            fmmu_gens: Vec::new(),
            windows_stale: true,
            windows_in_order: false,
            hits: Vec::new(),
            frame_ns: 0,
            hop_ns: DEFAULT_HOP_NS,
            stamps: Vec::new(),
        };
        chain.queued = vec![false; chain.slaves.len()];
        chain.stamps = vec![0; chain.slaves.len()];
        chain.reindex();
        chain
    }

    fn reindex(&mut self) {
        for &(a, _) in &self.addresses {
            if let Some(f) = self.first_of.get_mut(usize::from(a)) {
                *f = u32::MAX;
            }
        }
        self.addresses.clear();
        self.addr_gens.clear();
        for (i, s) in self.slaves.iter().enumerate() {
            let esc = s.esc();
            self.addr_gens.push(esc.address_generation());
            self.addresses.push((esc.station_address(), i));
            let alias = esc.station_alias();
            if alias != 0 && alias != esc.station_address() {
                self.addresses.push((alias, i));
            }
        }
        self.addresses.sort_unstable();
        for (k, &(a, _)) in self.addresses.iter().enumerate().rev() {
            if let Some(f) = self.first_of.get_mut(usize::from(a)) {
                *f = k as u32;
            }
        }
    }

    fn reindex_windows(&mut self) {
        self.windows.clear();
        self.fmmu_gens.clear();
        self.widest = 0;
        for (i, s) in self.slaves.iter().enumerate() {
            let esc = s.esc();
            self.fmmu_gens.push(esc.fmmu_generation());
            for (a, b) in esc.logical_windows() {
                self.widest = self.widest.max(b - a);
                self.windows.push((a, b, i));
            }
        }
        self.windows.sort_unstable();
        self.windows_in_order = self.windows.windows(2).all(|w| w[0].2 <= w[1].2);
        self.windows_stale = false;
    }

    /// What a datagram changed in slave `i`, from the FMMU and address
    /// generations its ESC reported after it ([`pass`]): (its FMMUs, so
    /// the window index is stale; its address or alias, so the address
    /// index is).
    fn changes(&self, i: usize, (fmmu_gen, addr_gen): (u32, u32)) -> (bool, bool) {
        (
            self.fmmu_gens.get(i).is_some_and(|g| *g != fmmu_gen),
            self.addr_gens.get(i).is_some_and(|g| *g != addr_gen),
        )
    }

    /// Brings the indexes up to date after a write that `remapped` some
    /// slave's FMMUs (the window index is rebuilt before the next logical
    /// datagram) or `moved` its address (the address index at once).
    fn after_write(&mut self, remapped: bool, moved: bool) {
        if remapped {
            self.windows_stale = true;
        }
        if moved {
            self.reindex();
        }
    }

    /// Passes one Ethernet frame through the line (as the frame travels
    /// down the line and back), then runs the firmware that has something
    /// to do at `now_ns` ([`Chain::service`]).
    pub fn process(&mut self, frame: &mut [u8], now_ns: u64) -> FrameOutcome {
        let outcome = self.process_frame_at(frame, now_ns);
        // A PDI failure is counted and handled by the slave (fail-safe);
        // the frame has already been answered by the ESCs.
        let _ = self.service(now_ns);
        outcome
    }

    /// Runs the firmware of the slaves that need it at `now_ns`, as an
    /// event-driven firmware on silicon does: every slave the last frame
    /// reached whose ESC raised an AL event (AL control written, a
    /// SyncManager buffer written or read) runs now, and a round-robin
    /// sweep runs every slave at least every `max(SWEEP_MIN_NS,
    /// n × SWEEP_PER_SLAVE_NS)` for what has no event (SM watchdog
    /// supervision, the application's own timing). The cost is
    /// proportional to what the frames addressed, not to the line length
    /// times the frame count. Returns the first PDI failure like
    /// [`Chain::poll`].
    pub fn service(&mut self, now_ns: u64) -> Result<(), (usize, EscError)> {
        self.service_until(now_ns, &mut || false).map(|_| ())
    }

    /// [`Chain::service`] that stops between two firmware runs as soon as
    /// `frame_waiting` says a frame waits, so a frame is never held up by
    /// more than one firmware step: the runner answers it and calls again,
    /// and the rest of the work (the touched slaves not run yet, the
    /// sweep's remaining turns) is done then. Returns whether all the work
    /// was done (`false`: stopped for a frame), or the first PDI failure
    /// like [`Chain::poll`].
    pub fn service_until(
        &mut self,
        now_ns: u64,
        frame_waiting: &mut dyn FnMut() -> bool,
    ) -> Result<bool, (usize, EscError)> {
        let mut first = None;
        let mut moved = false;
        let mut stopped = false;
        if core::mem::take(&mut self.touched_all) {
            // A broadcast or logical datagram reached every slave: all of
            // them after those still waiting from before.
            for i in 0..self.slaves.len() {
                self.touch(i);
            }
        }
        let mut touched = core::mem::take(&mut self.touched);
        let mut done = touched.len();
        for (k, &i) in touched.iter().enumerate() {
            if frame_waiting() {
                done = k;
                stopped = true;
                break;
            }
            if let Some(q) = self.queued.get_mut(i) {
                *q = false;
            }
            if self.has_event(i, now_ns) {
                moved |= self.poll_one(i, now_ns, &mut first);
            }
        }
        touched.drain(..done);
        // Touches during the runs (none today) come after the rest.
        touched.append(&mut self.touched);
        self.touched = touched;
        if !stopped {
            moved |= self.sweep(now_ns, &mut first, frame_waiting, &mut stopped);
        }
        if moved {
            self.reindex();
        }
        first.map_or(Ok(!stopped), Err)
    }

    /// [`Chain::service`] when the link is idle (no frame waiting): also
    /// runs the next [`IDLE_BATCH`] slaves of the sweep whatever the time,
    /// as a firmware's main loop keeps turning while nothing happens (with
    /// a simulated clock that stands still, this is what lets a stalled or
    /// repaired firmware be noticed). Lines of up to [`IDLE_BATCH`] slaves
    /// run completely on every idle pass.
    pub fn idle(&mut self, now_ns: u64) -> Result<(), (usize, EscError)> {
        let serviced = self.service(now_ns);
        if !self.idle_passes {
            return serviced;
        }
        let n = self.slaves.len();
        let mut first = None;
        let mut moved = false;
        for _ in 0..IDLE_BATCH.min(n) {
            let i = self.sweep_next % n;
            self.sweep_next = (i + 1) % n;
            moved |= self.poll_one(i, now_ns, &mut first);
        }
        if moved {
            self.reindex();
        }
        serviced.and(first.map_or(Ok(()), Err))
    }

    /// Turns the extra passes of [`Chain::idle`] on (the default) or off.
    /// Off, a firmware runs only when its ESC flags an event or its sweep
    /// turn comes in the slaves' time: with a simulated clock that stands
    /// still, each frame then costs exactly the passes it caused, which is
    /// what a measurement of the per-pass PDI cost needs.
    pub fn set_idle_passes(&mut self, on: bool) {
        self.idle_passes = on;
    }

    /// The sweep period of this line.
    pub fn sweep_period_ns(&self) -> u64 {
        (self.slaves.len() as u64)
            .saturating_mul(SWEEP_PER_SLAVE_NS)
            .max(SWEEP_MIN_NS)
    }

    /// Runs the firmware of the slaves whose turn in the sweep has come
    /// by `now_ns`; returns whether the firmware of one of them changed
    /// its station alias.
    fn sweep(
        &mut self,
        now_ns: u64,
        first: &mut Option<(usize, EscError)>,
        frame_waiting: &mut dyn FnMut() -> bool,
        stopped: &mut bool,
    ) -> bool {
        let n = self.slaves.len();
        if n == 0 {
            return false;
        }
        let period = self.sweep_period_ns();
        let elapsed = now_ns.saturating_sub(self.swept_until);
        let due = u128::from(elapsed) * n as u128 / u128::from(period);
        let due = usize::try_from(due).unwrap_or(usize::MAX).min(n);
        let mut moved = false;
        let mut ran = 0;
        while ran < due {
            if frame_waiting() {
                *stopped = true;
                break;
            }
            let i = self.sweep_next % n;
            self.sweep_next = (i + 1) % n;
            moved |= self.poll_one(i, now_ns, first);
            ran += 1;
        }
        // The turns not run (a frame came first) stay due.
        if ran == n {
            self.swept_until = now_ns;
        } else if ran > 0 {
            let step = u128::from(period) * ran as u128 / n as u128;
            self.swept_until += u64::try_from(step).unwrap_or(elapsed);
        }
        moved
    }

    /// Whether slave `i`'s ESC holds an AL event for the firmware at
    /// `now_ns` (its SYNC0 unit runs up to then first).
    fn has_event(&mut self, i: usize, now_ns: u64) -> bool {
        self.slaves.get_mut(i).is_some_and(|s| {
            let esc = s.esc_mut();
            esc.update_dc(now_ns);
            esc.al_event_pending()
        })
    }

    /// Runs slave `i`'s firmware; records a PDI failure in `first` and
    /// returns whether the firmware changed the slave's station alias.
    fn poll_one(&mut self, i: usize, now_ns: u64, first: &mut Option<(usize, EscError)>) -> bool {
        let (Some(s), Some(img)) = (self.slaves.get_mut(i), self.images.get_mut(i)) else {
            return false;
        };
        self.runs += 1;
        if let Err(e) = s.poll_with(now_ns, Some(img.as_mut())) {
            self.pdi_failures += 1;
            first.get_or_insert((i, e));
        }
        self.moved(i)
    }

    /// Records that a datagram reached slave `i`.
    fn touch(&mut self, i: usize) {
        touch(&mut self.queued, &mut self.touched, i);
    }

    /// The reference path: the frame through every ESC in turn.
    pub fn process_serial(&mut self, frame: &mut [u8]) -> FrameOutcome {
        let mut outcome = FrameOutcome::Malformed;
        let n = self.slaves.len();
        for (i, s) in self.slaves.iter_mut().enumerate() {
            let (p0, p1) = port_times(i, n, (self.frame_ns, self.hop_ns));
            s.esc_mut().set_frame_times(p0, p1);
            outcome = s.process_frame(frame);
        }
        self.reindex();
        outcome
    }

    /// [`Chain::process_serial`] for a frame arriving at `now_ns` (the DC
    /// units see the same port times as on the dispatching path).
    pub fn process_serial_at(&mut self, frame: &mut [u8], now_ns: u64) -> FrameOutcome {
        self.frame_ns = now_ns;
        self.process_serial(frame)
    }

    /// [`Chain::process_frame`] for a frame arriving at `now_ns`: the DC
    /// units see it pass their ports from that time on.
    pub fn process_frame_at(&mut self, frame: &mut [u8], now_ns: u64) -> FrameOutcome {
        self.frame_ns = now_ns;
        self.process_frame(frame)
    }

    /// The ESC part of [`Chain::process`], without running the firmware
    /// (the DC units take the frame time of the last frame; see
    /// [`Chain::process_frame_at`]).
    pub fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome {
        let n = self.slaves.len();
        if n == 0 {
            return FrameOutcome::Malformed;
        }
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
        self.frames += 1;
        // Each datagram's header read once (`DatagramHead::split`); the
        // walk ends where `DatagramCursor`'s does: a truncated datagram,
        // the last one, or the MAX_DATAGRAMS-th. (The serial reference
        // path keeps the cursor: the tests compare two walks written
        // apart.)
        let mut rest = ecat.payload_mut();
        let mut count = 0;
        while count < MAX_DATAGRAMS {
            let Some((head, dg, tail)) = DatagramHead::split(rest) else {
                break;
            };
            if n == 1 {
                self.dispatch_one(head, dg);
            } else {
                self.dispatch(head, dg, n);
            }
            count += 1;
            if !head.more_follows {
                break;
            }
            rest = tail;
        }
        FrameOutcome::Processed { datagrams: count }
    }

    /// Whether slave `i`'s station address or alias changed since the
    /// index was built.
    fn moved(&self, i: usize) -> bool {
        match (self.slaves.get(i), self.addr_gens.get(i)) {
            (Some(s), Some(g)) => s.esc().address_generation() != *g,
            _ => false,
        }
    }

    /// Sets the delay a frame takes from one slave to the next (and back),
    /// which the DC units see in their receive times (default
    /// [`DEFAULT_HOP_NS`]).
    pub fn set_hop_delay_ns(&mut self, hop_ns: u64) {
        self.hop_ns = hop_ns;
    }

    /// [`Chain::dispatch`] for a line of one slave: its ESC takes every
    /// datagram and decides itself whether it is addressed (station
    /// address, position, FMMU windows), as it does on the serial path;
    /// the line's indexes have nothing to choose between (they are still
    /// kept up to date: answering ahead reads them). The
    /// slave's firmware is queued after any datagram but a NOP, addressed
    /// or not; on longer lines only the slaves addressed are. With the
    /// index walks gone a cycle of one slave takes 733 instructions
    /// instead of 882 (`cycle_count 1`).
    fn dispatch_one(&mut self, dh: DatagramHead, dg: &mut [u8]) {
        let Some(mut parts) = DatagramParts::of(&dh, dg) else {
            return;
        };
        let addressing = dh.command.addressing();
        if addressing == Addressing::None {
            return;
        }
        // The window index chooses nothing here, but answering ahead
        // reads it (`Chain::ahead`): rebuilt as on longer lines.
        if self.windows_stale && addressing == Addressing::Logical {
            self.reindex_windows();
        }
        let clock = FrameClock {
            t: self.frame_ns,
            hop: self.hop_ns,
            n: 1,
            frame: self.frames,
        };
        let Some(s) = self.slaves.first_mut() else {
            return;
        };
        let (w, gens) = pass(s.as_mut(), 0, &clock, &mut self.stamps, dh, parts.data);
        if matches!(addressing, Addressing::Position | Addressing::Broadcast) {
            parts.set_adp(dh.adp.wrapping_add(1));
        }
        self.touch(0);
        if dh.command.is_write() {
            let (remapped, moved) = self.changes(0, gens);
            self.after_write(remapped, moved);
        }
        if w != 0 {
            parts.set_wkc(parts.wkc().wrapping_add(w));
        }
    }

    /// Hands one datagram (`dg`: its header, data and working counter,
    /// split off by [`DatagramHead::split`]) to the slaves it reaches.
    fn dispatch(&mut self, head: DatagramHead, dg: &mut [u8], n: usize) {
        let Some(mut parts) = DatagramParts::of(&head, dg) else {
            return;
        };
        let wkc0 = parts.wkc();
        let data = &mut *parts.data;
        let cmd = head.command;
        let clock = FrameClock {
            t: self.frame_ns,
            hop: self.hop_ns,
            n,
            frame: self.frames,
        };
        let mut wkc_add = 0u16;
        match cmd.addressing() {
            Addressing::Configured if cmd != Command::Frmw => {
                // Every slave answering to this address, in line order.
                let first = self
                    .first_of
                    .get(usize::from(head.adp))
                    .map_or(usize::MAX, |&k| k as usize);
                let mut k = first;
                let (mut remapped, mut moved) = (false, false);
                while let Some(&(a, i)) = self.addresses.get(k) {
                    if a != head.adp {
                        break;
                    }
                    if let Some(s) = self.slaves.get_mut(i) {
                        let (w, gens) = pass(s.as_mut(), i, &clock, &mut self.stamps, head, data);
                        wkc_add = wkc_add.wrapping_add(w);
                        if cmd.is_write() {
                            let (r, m) = self.changes(i, gens);
                            (remapped, moved) = (remapped | r, moved | m);
                        }
                    }
                    self.touch(i);
                    k += 1;
                }
                self.after_write(remapped, moved);
            }
            Addressing::Position if cmd != Command::Armw => {
                // Slave i sees ADP0 + i; the one seeing 0 is addressed.
                let pos = usize::from(0u16.wrapping_sub(head.adp));
                if let Some(s) = self.slaves.get_mut(pos) {
                    let at_zero = DatagramHead { adp: 0, ..head };
                    let (w, gens) = pass(s.as_mut(), pos, &clock, &mut self.stamps, at_zero, data);
                    wkc_add = w;
                    self.touch(pos);
                    if cmd.is_write() {
                        let (remapped, moved) = self.changes(pos, gens);
                        self.after_write(remapped, moved);
                    }
                }
                parts.set_adp(head.adp.wrapping_add(n as u16));
            }
            Addressing::Logical => {
                // Only the slaves with an FMMU window overlapping the
                // datagram act on it, in line order.
                if self.windows_stale {
                    self.reindex_windows();
                }
                let start = u64::from(head.adp) | (u64::from(head.ado) << 16);
                let end = start + data.len() as u64;
                // Windows starting before `lo` end before `start`. (A
                // master's image usually starts at 0: nothing to search.)
                let lo = start.saturating_sub(self.widest);
                let first = if lo == 0 {
                    0
                } else {
                    self.windows.partition_point(|w| w.0 < lo)
                };
                if self.windows_in_order {
                    // Each slave once, as its first window comes.
                    let (mut last, mut moved, mut remapped) = (usize::MAX, false, false);
                    for &(a, b, i) in self.windows.get(first..).unwrap_or_default() {
                        if a >= end {
                            break;
                        }
                        if b <= start || i == last {
                            continue;
                        }
                        last = i;
                        let Some(s) = self.slaves.get_mut(i) else {
                            continue;
                        };
                        let (w, gens) = pass(s.as_mut(), i, &clock, &mut self.stamps, head, data);
                        wkc_add = wkc_add.wrapping_add(w);
                        touch(&mut self.queued, &mut self.touched, i);
                        // An FMMU may map registers, even the FMMUs' own.
                        if cmd.is_write() {
                            let (r, m) = self.changes(i, gens);
                            (remapped, moved) = (remapped | r, moved | m);
                        }
                    }
                    self.after_write(remapped, moved);
                } else {
                    let mut hits = core::mem::take(&mut self.hits);
                    hits.clear();
                    for &(a, b, i) in self.windows.get(first..).unwrap_or_default() {
                        if a >= end {
                            break;
                        }
                        if b > start {
                            hits.push(i);
                        }
                    }
                    hits.sort_unstable();
                    hits.dedup();
                    let (mut remapped, mut moved) = (false, false);
                    for &i in &hits {
                        if let Some(s) = self.slaves.get_mut(i) {
                            let (w, gens) =
                                pass(s.as_mut(), i, &clock, &mut self.stamps, head, data);
                            wkc_add = wkc_add.wrapping_add(w);
                            // An FMMU may map registers, even the FMMUs' own.
                            if cmd.is_write() {
                                let (r, m) = self.changes(i, gens);
                                (remapped, moved) = (remapped | r, moved | m);
                            }
                        }
                        self.touch(i);
                    }
                    self.after_write(remapped, moved);
                    self.hits = hits;
                }
            }
            Addressing::None => {}
            // Broadcast, ARMW, FRMW: every slave in line order (position
            // and broadcast commands: slave i sees ADP0 + i).
            _ => {
                let advances = cmd.addressing() != Addressing::Configured;
                let (mut remapped, mut moved) = (false, false);
                for i in 0..n {
                    let adp = if advances {
                        head.adp.wrapping_add(i as u16)
                    } else {
                        head.adp
                    };
                    let Some(s) = self.slaves.get_mut(i) else {
                        continue;
                    };
                    let (w, gens) = pass(
                        s.as_mut(),
                        i,
                        &clock,
                        &mut self.stamps,
                        DatagramHead { adp, ..head },
                        data,
                    );
                    wkc_add = wkc_add.wrapping_add(w);
                    if cmd.is_write() {
                        let (r, m) = self.changes(i, gens);
                        (remapped, moved) = (remapped | r, moved | m);
                    }
                }
                if advances {
                    parts.set_adp(head.adp.wrapping_add(n as u16));
                }
                self.touched_all = true;
                self.after_write(remapped, moved);
            }
        }
        if wkc_add != 0 {
            parts.set_wkc(wkc0.wrapping_add(wkc_add));
        }
    }

    /// Runs every slave's firmware once (what [`Chain::service`] does for
    /// the slaves that need it). Every slave runs even when one
    /// fails; the first PDI failure (slave position, error) is returned
    /// and every failure is counted ([`Chain::pdi_failures`]).
    pub fn poll(&mut self, now_ns: u64) -> Result<(), (usize, EscError)> {
        let mut first = None;
        let mut moved = false;
        for i in 0..self.slaves.len() {
            moved |= self.poll_one(i, now_ns, &mut first);
        }
        // The firmware may have changed an alias through its PDI.
        if moved {
            self.reindex();
        }
        first.map_or(Ok(()), Err)
    }

    /// How many times a slave's firmware ran since the chain was built
    /// ([`Chain::poll`] counts one per slave).
    pub fn firmware_runs(&self) -> u64 {
        self.runs
    }

    /// A frame with a bad checksum reached the line (bit flip, runt): the
    /// first slave counts it on port 0 and nobody acts on it (what an ESC
    /// does with an FCS error).
    pub fn corrupted_frame(&mut self) {
        if let Some(first) = self.slaves.first_mut() {
            first.esc_mut().count_invalid_frame(0);
        }
    }

    /// The link into the line (port 0 of the first slave) went down.
    pub fn link_lost(&mut self) {
        if let Some(first) = self.slaves.first_mut() {
            first.esc_mut().count_lost_link(0);
        }
    }

    /// PDI failures seen by [`Chain::poll`] since the chain was built.
    pub fn pdi_failures(&self) -> u64 {
        self.pdi_failures
    }

    /// A simulated power cycle of slave `i`: ESC and firmware restart, the
    /// bootloader starts the pending image if one was downloaded and
    /// committed (its CRC verified, else the old one), and 0x100A reports
    /// the version that runs. Parameters (EEPROM) are kept. Returns the
    /// version, or `None` for a bad index.
    pub fn power_cycle(&mut self, i: usize) -> Option<String> {
        let slave = self.slaves.get_mut(i)?;
        let store = self.images.get_mut(i)?;
        slave.power_cycle();
        let decision = firmware::power_on(store.as_mut());
        // The start check of the simulated firmware is its CRC, already
        // verified by the bootloader: confirm the trial image.
        let _ = firmware::confirm_boot(store.as_mut());
        let version = decision.version.as_str().to_string();
        slave.set_firmware_version(&version);
        slave.set_no_valid_firmware(decision.slot.is_none());
        self.reindex();
        self.windows_stale = true;
        Some(version)
    }

    /// The firmware image store of slave `i`.
    pub fn image_store(&self, i: usize) -> Option<&(dyn ImageStore + Send)> {
        self.images.get(i).map(|b| b.as_ref())
    }

    /// The slaves.
    pub fn slaves(&self) -> &[Box<dyn LineSlave>] {
        &self.slaves
    }

    /// The slaves, mutably (to set inputs, inject faults).
    pub fn slaves_mut(&mut self) -> &mut [Box<dyn LineSlave>] {
        &mut self.slaves
    }

    /// Slave `i` as the device `A` it is (`None` for another device or a
    /// bad index).
    pub fn slave<A: Application + Send + 'static>(&self, i: usize) -> Option<&SoftSlave<A>> {
        self.slaves.get(i)?.as_any().downcast_ref()
    }

    /// Slave `i` as the device `A` it is, mutably.
    pub fn slave_mut<A: Application + Send + 'static>(
        &mut self,
        i: usize,
    ) -> Option<&mut SoftSlave<A>> {
        self.slaves.get_mut(i)?.as_any_mut().downcast_mut()
    }

    /// Number of frames processed so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::one_datagram;
    use ecat_slave::wire::builder::FrameBuilder;
    use ecat_slave::wire::ecat::Datagram;
    use proptest::prelude::*;

    /// An EEPROM alias program + reload for one slave: the alias is
    /// written to SII word 4 and the EEPROM reloaded, addressed by position,
    /// station or broadcast; alias addressing must follow.
    #[derive(Debug, Clone)]
    struct AliasReload {
        cmd: Command,
        adp: u16,
        alias: u16,
    }

    /// A random frame of plausible datagrams aimed at a 6-slave line.
    #[derive(Debug, Clone)]
    struct RandomFrame {
        /// Now and then (1 in 4) an alias reload first.
        reload: Option<AliasReload>,
        /// 1 to 8 datagrams: command, address, data.
        datagrams: Vec<(Command, u32, Vec<u8>)>,
    }

    fn alias_reload() -> impl Strategy<Value = AliasReload> {
        let target = prop_oneof![
            (0u16..6).prop_map(|p| (Command::Apwr, 0u16.wrapping_sub(p))),
            (0x1000u16..0x1006).prop_map(|s| (Command::Fpwr, s)),
            Just((Command::Bwr, 0)),
        ];
        (target, 0x2000u16..0x2008).prop_map(|((cmd, adp), alias)| AliasReload { cmd, adp, alias })
    }

    fn datagram() -> impl Strategy<Value = (Command, u32, Vec<u8>)> {
        let ado = prop_oneof![
            Just(0x0010u16),
            Just(0x0120),
            Just(0x0130),
            0x0600u16..0x0620,
            // SyncManagers, reconfigured anywhere (also over the
            // registers, where they must not hide them).
            0x0800u16..0x0820,
            0x1000u16..0x1300,
        ];
        let adp = prop_oneof![
            (0u16..8).prop_map(|p| 0u16.wrapping_sub(p)),
            0x1000u16..0x1008,
            0x2000u16..0x2008,
            any::<u16>(),
        ];
        (
            0u8..16,
            ado,
            adp,
            0u32..0x80,
            prop::collection::vec(any::<u8>(), 1..=20),
        )
            .prop_map(|(cmd, ado, adp, logical, data)| {
                let cmd = Command::from(cmd);
                let address = if matches!(cmd.addressing(), Addressing::Logical) {
                    logical
                } else {
                    u32::from(adp) | (u32::from(ado) << 16)
                };
                (cmd, address, data)
            })
    }

    fn random_frame() -> impl Strategy<Value = RandomFrame> {
        (
            proptest::option::weighted(0.25, alias_reload()),
            prop::collection::vec(datagram(), 1..=8),
        )
            .prop_map(|(reload, datagrams)| RandomFrame { reload, datagrams })
    }

    impl RandomFrame {
        fn bytes(&self) -> Vec<u8> {
            let mut buf = vec![0u8; 1600];
            let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
            if let Some(r) = &self.reload {
                let at = |ado: u16| u32::from(r.adp) | (u32::from(ado) << 16);
                for (ado, data) in [
                    (0x0502u16, &[0x01u8, 0x00][..]),
                    (0x0508, &r.alias.to_le_bytes()[..]),
                    (0x0502, &[0x01, 0x02, 0x04, 0x00, 0x00, 0x00][..]),
                    (0x0502, &[0x00, 0x04, 0x00, 0x00, 0x00, 0x00][..]),
                ] {
                    b.push(r.cmd, at(ado), data).unwrap();
                }
            }
            for (cmd, address, data) in &self.datagrams {
                if b.push(*cmd, *address, data).is_err() {
                    break;
                }
            }
            let len = b.finish();
            buf.truncate(len);
            buf
        }
    }

    /// Sets station addresses 0x1000.. and a process-data configuration so
    /// that logical and configured traffic finds targets: slave `i`'s
    /// 8 logical bytes at `8·i` (the image in line order, as ethercrab lays
    /// it out) or, `reversed`, at `8·(5 − i)` (last slave first).
    fn configured_pair(n: u16, reversed: bool) -> (Chain, Chain) {
        let mut a = crate::testing::line(usize::from(n));
        let mut b = crate::testing::line(usize::from(n));
        for i in 0..n {
            let mut buf = vec![0u8; 200];
            let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
            let adp = u32::from(0u16.wrapping_sub(i));
            fb.push(
                Command::Apwr,
                adp | (0x0010 << 16),
                &(0x1000 + i).to_le_bytes(),
            )
            .unwrap();
            let mut f0 = [0u8; 16];
            f0[0] = if reversed { (n - 1 - i) * 8 } else { i * 8 } as u8;
            f0[4] = 8;
            f0[7] = 7;
            f0[8..10].copy_from_slice(&0x1100u16.to_le_bytes());
            f0[11] = 3;
            f0[12] = 1;
            fb.push(Command::Apwr, adp | (0x0600 << 16), &f0).unwrap();
            let len = fb.finish();
            let mut f2 = buf[..len].to_vec();
            a.process_serial(&mut buf[..len]);
            b.process_frame(&mut f2);
        }
        (a, b)
    }

    /// Two lines of 6 slaves, each slave with an output window (4 bytes
    /// to 0x1100) and an input window (4 bytes from 0x1180) side by side
    /// at logical `8·i`, or `8·(5 − i)` when `reversed`.
    fn two_window_pair(reversed: bool) -> (Chain, Chain) {
        let mut a = crate::testing::line(6);
        let mut b = crate::testing::line(6);
        for i in 0..6u16 {
            let base = if reversed { (5 - i) * 8 } else { i * 8 };
            let fmmu = |logical: u16, physical: u16, kind: u8| {
                let mut f = [0u8; 16];
                f[0..2].copy_from_slice(&logical.to_le_bytes());
                f[4] = 4;
                f[7] = 7;
                f[8..10].copy_from_slice(&physical.to_le_bytes());
                f[11] = kind;
                f[12] = 1;
                f
            };
            let mut buf = vec![0u8; 200];
            let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
            let adp = u32::from(0u16.wrapping_sub(i));
            fb.push(Command::Apwr, adp | (0x0600 << 16), &fmmu(base, 0x1100, 2))
                .unwrap();
            fb.push(
                Command::Apwr,
                adp | (0x0610 << 16),
                &fmmu(base + 4, 0x1180, 1),
            )
            .unwrap();
            let len = fb.finish();
            let mut f2 = buf[..len].to_vec();
            a.process_serial(&mut buf[..len]);
            b.process_frame(&mut f2);
        }
        (a, b)
    }

    #[test]
    fn an_lrw_reaches_each_slave_once_whether_the_image_is_in_line_order_or_not() {
        for reversed in [false, true] {
            let (mut serial, mut fast) = two_window_pair(reversed);
            let data: Vec<u8> = (0..48).collect();
            let mut f1 = one_datagram(Command::Lrw, 0, &data);
            let mut f2 = f1.clone();
            serial.process_serial(&mut f1);
            fast.process_frame(&mut f2);
            assert_eq!(
                fast.windows_in_order, !reversed,
                "the layout was recognised"
            );
            assert_eq!(f1, f2, "the same answer as every ESC walking the frame");
            let wkc = u16::from_le_bytes([f2[f2.len() - 2], f2[f2.len() - 1]]);
            assert_eq!(
                wkc,
                6 * 3,
                "each slave's write (2) and read (1) counted once"
            );
        }
    }

    #[test]
    fn an_alias_from_an_eeprom_reload_is_addressable_on_the_line() {
        let mut line = crate::testing::line(3);
        let mut buf = vec![0u8; 200];
        let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
        // Slave 1 (position -1): alias 0x2001 into SII word 4, reload.
        let at = |ado: u16| u32::from(0u16.wrapping_sub(1)) | (u32::from(ado) << 16);
        fb.push(Command::Apwr, at(0x0502), &[0x01, 0x00]).unwrap();
        fb.push(Command::Apwr, at(0x0508), &[0x01, 0x20]).unwrap();
        fb.push(Command::Apwr, at(0x0502), &[0x01, 0x02, 4, 0, 0, 0])
            .unwrap();
        fb.push(Command::Apwr, at(0x0502), &[0x00, 0x04, 0, 0, 0, 0])
            .unwrap();
        let read = fb
            .push(Command::Fprd, 0x2001 | (0x0130 << 16), &[0, 0])
            .unwrap();
        let len = fb.finish();
        let f = &mut buf[..len];
        line.process_frame(f);
        let wkc = u16::from_le_bytes([f[read.end], f[read.end + 1]]);
        assert_eq!(wkc, 1, "FPRD by the reloaded alias answered on the line");
    }

    fn al_status(line: &Chain, i: usize) -> u16 {
        let m = line.slaves()[i].esc().raw_memory();
        u16::from_le_bytes([m[0x0130], m[0x0131]])
    }

    #[test]
    fn idle_passes_switched_off_run_only_what_is_due() {
        let mut line = crate::testing::line(4);
        line.idle(0).unwrap();
        assert_eq!(line.firmware_runs(), 4, "idle runs the whole short line");
        line.set_idle_passes(false);
        line.idle(0).unwrap();
        assert_eq!(line.firmware_runs(), 4, "nothing flagged, nothing due");
        line.set_idle_passes(true);
        line.idle(0).unwrap();
        assert_eq!(line.firmware_runs(), 8);
    }

    /// For `service_until`: a frame waits from the look after `runs`
    /// firmware runs on (the chain looks once before each run).
    fn waits_after(runs: usize) -> impl FnMut() -> bool {
        let mut looks = 0;
        move || {
            looks += 1;
            looks > runs
        }
    }

    #[test]
    fn service_stopped_by_a_waiting_frame_finishes_the_events_on_the_next_call() {
        let mut line = crate::testing::line(8);
        // A broadcast PRE-OP request without mailbox SMs: every slave's
        // firmware has an AL control event to answer (INIT + error).
        let mut f = one_datagram(Command::Bwr, 0x0120 << 16, &[0x02, 0]);
        line.process_frame_at(&mut f, 0);
        // A frame waits after three firmware runs.
        assert_eq!(line.service_until(0, &mut waits_after(3)), Ok(false));
        assert_eq!(line.firmware_runs(), 3);
        assert!(
            (0..3).all(|i| al_status(&line, i) == 0x0011),
            "PRE-OP refused: INIT + error"
        );
        assert!((3..8).all(|i| al_status(&line, i) == 0x0001), "not run yet");
        // Next call (no frame waits): the other five, once each.
        assert_eq!(line.service_until(0, &mut || false), Ok(true));
        assert_eq!(line.firmware_runs(), 8);
        assert!((0..8).all(|i| al_status(&line, i) == 0x0011));
        assert_eq!(line.service_until(0, &mut || false), Ok(true));
        assert_eq!(line.firmware_runs(), 8, "nothing left to do");
    }

    #[test]
    fn frames_back_to_back_starve_no_slave_of_its_events() {
        // Every frame is a broadcast PRE-OP request and the next frame
        // always waits after two firmware runs: the slaves left over are
        // served first next time, so all eight answer within four frames
        // (not only the first two, again and again).
        let mut line = crate::testing::line(8);
        for _ in 0..4 {
            let mut f = one_datagram(Command::Bwr, 0x0120 << 16, &[0x02, 0]);
            line.process_frame_at(&mut f, 0);
            assert_eq!(line.service_until(0, &mut waits_after(2)), Ok(false));
        }
        assert!(
            (0..8).all(|i| al_status(&line, i) == 0x0011),
            "{:?}",
            (0..8).map(|i| al_status(&line, i)).collect::<Vec<_>>()
        );
    }

    #[test]
    fn service_stopped_in_the_sweep_keeps_the_remaining_turns_due() {
        let mut line = crate::testing::line(4);
        let period = line.sweep_period_ns();
        // A whole sweep period later every slave is due; a frame waits
        // after the first run.
        assert_eq!(line.service_until(period, &mut waits_after(1)), Ok(false));
        assert_eq!(line.firmware_runs(), 1);
        // The three not run stay due at the same time, and no more.
        assert_eq!(line.service_until(period, &mut || false), Ok(true));
        assert_eq!(line.firmware_runs(), 4);
        assert_eq!(line.service_until(period, &mut || false), Ok(true));
        assert_eq!(line.firmware_runs(), 4);
    }

    #[test]
    fn service_without_a_waiting_frame_is_what_service_does() {
        let mut a = crate::testing::line(8);
        let mut b = crate::testing::line(8);
        let mut f = one_datagram(Command::Bwr, 0x0120 << 16, &[0x02, 0]);
        let mut g = f.clone();
        a.process_frame_at(&mut f, 0);
        b.process_frame_at(&mut g, 0);
        for t in [0, 300_000, 1_000_000, 2_500_000] {
            a.service(t).unwrap();
            assert_eq!(b.service_until(t, &mut || false), Ok(true));
            assert_eq!(a.firmware_runs(), b.firmware_runs(), "at {t}");
        }
        assert!((0..8).all(|i| al_status(&a, i) == al_status(&b, i)));
    }

    #[test]
    fn a_frame_runs_only_the_firmware_whose_esc_raised_an_event() {
        let mut line = crate::testing::line(8);
        line.service(0).unwrap();
        assert_eq!(line.firmware_runs(), 0, "nothing due at time 0");
        // A read of slave 2's AL status: no event, no firmware run.
        let at = |pos: u16, ado: u16| u32::from(0u16.wrapping_sub(pos)) | (u32::from(ado) << 16);
        let mut f = one_datagram(Command::Aprd, at(2, 0x0130), &[0, 0]);
        line.process(&mut f, 0);
        assert_eq!(line.firmware_runs(), 0);
        // PRE-OP requested on slave 3 without mailbox SMs (AL control
        // event): only it runs, and refuses with the error flag.
        let mut f = one_datagram(Command::Apwr, at(3, 0x0120), &[0x02, 0]);
        line.process(&mut f, 0);
        assert_eq!(line.firmware_runs(), 1);
        assert_eq!(al_status(&line, 3), 0x0011, "INIT + error");
        assert!(
            (0..8)
                .filter(|&i| i != 3)
                .all(|i| al_status(&line, i) == 0x0001)
        );
        // A broadcast INIT + acknowledge: every slave runs once.
        let mut f = one_datagram(Command::Bwr, 0x0120 << 16, &[0x11, 0]);
        line.process(&mut f, 0);
        assert_eq!(line.firmware_runs(), 9);
        assert!((0..8).all(|i| al_status(&line, i) == 0x0001));
    }

    /// A flash whose boot records (and everything else) cannot be read.
    struct BrokenFlash;

    impl ImageStore for BrokenFlash {
        fn slot_capacity(&self) -> usize {
            IMAGE_SLOT_CAPACITY
        }
        fn erase(&mut self, _: ecat_slave::firmware::Slot) -> Result<(), StoreError> {
            Err(StoreError::Io)
        }
        fn write(
            &mut self,
            _: ecat_slave::firmware::Slot,
            _: usize,
            _: &[u8],
        ) -> Result<(), StoreError> {
            Err(StoreError::Io)
        }
        fn read(
            &self,
            _: ecat_slave::firmware::Slot,
            _: usize,
            _: &mut [u8],
        ) -> Result<usize, StoreError> {
            Err(StoreError::Io)
        }
        fn read_state(&self) -> Result<ecat_slave::firmware::BootState, StoreError> {
            Err(StoreError::Io)
        }
        fn write_state(&mut self, _: &ecat_slave::firmware::BootState) -> Result<(), StoreError> {
            Err(StoreError::Io)
        }
    }

    #[test]
    fn a_slave_whose_boot_records_cannot_be_read_refuses_preop_with_0x0014() {
        let slaves: Vec<Box<dyn LineSlave>> = vec![
            Box::new(crate::testing::slave()),
            Box::new(crate::testing::slave()),
        ];
        let mut line = Chain::with_stores(slaves, vec![Box::new(BrokenFlash)]);
        let at = |pos: u16| u32::from(0u16.wrapping_sub(pos)) | (0x0120 << 16);
        for pos in 0..2 {
            let mut f = one_datagram(Command::Apwr, at(pos), &[0x02, 0]);
            line.process(&mut f, 0);
        }
        let code = |line: &Chain, i: usize| line.slaves()[i].al_status().code;
        assert_eq!(al_status(&line, 0), 0x0011, "INIT + error");
        assert_eq!(
            code(&line, 0),
            ecat_slave::al::AlStatusCode::NoValidFirmware
        );
        assert_eq!(
            code(&line, 1),
            ecat_slave::al::AlStatusCode::InvalidMailboxPreOp,
            "a slave with readable records runs its firmware"
        );
        // Still so after a power cycle.
        line.power_cycle(0);
        let mut f = one_datagram(Command::Apwr, at(0), &[0x02, 0]);
        line.process(&mut f, 0);
        assert_eq!(
            code(&line, 0),
            ecat_slave::al::AlStatusCode::NoValidFirmware
        );
    }

    #[test]
    fn a_logical_write_that_reprograms_an_fmmu_moves_logical_addressing_at_once() {
        let mut line = crate::testing::line(2);
        // Slave 1's FMMU0: logical 0x100.. written into its own FMMU1
        // registers (0x0610, 16 bytes).
        let mut f0 = [0u8; 16];
        f0[0..4].copy_from_slice(&0x100u32.to_le_bytes());
        f0[4..6].copy_from_slice(&16u16.to_le_bytes());
        f0[7] = 7;
        f0[8..10].copy_from_slice(&0x0610u16.to_le_bytes());
        f0[11] = 2;
        f0[12] = 1;
        let at1 = u32::from(0u16.wrapping_sub(1)) | (0x0600 << 16);
        let mut f = one_datagram(Command::Apwr, at1, &f0);
        line.process_frame(&mut f);
        // Through it, FMMU1 := logical 0x200.. -> physical 0x1100, write.
        let mut f1 = [0u8; 16];
        f1[0..4].copy_from_slice(&0x200u32.to_le_bytes());
        f1[4..6].copy_from_slice(&4u16.to_le_bytes());
        f1[7] = 7;
        f1[8..10].copy_from_slice(&0x1100u16.to_le_bytes());
        f1[11] = 2;
        f1[12] = 1;
        let mut f = one_datagram(Command::Lwr, 0x100, &f1);
        line.process_frame(&mut f);
        // The new window answers in the very next frame.
        let mut f = one_datagram(Command::Lwr, 0x200, &[1, 2, 3, 4]);
        line.process_frame(&mut f);
        let wkc = u16::from_le_bytes([f[f.len() - 2], f[f.len() - 1]]);
        assert_eq!(wkc, 1, "slave 1 took the write through its new FMMU1");
        assert_eq!(
            &line.slaves()[1].esc().raw_memory()[0x1100..0x1104],
            &[1, 2, 3, 4]
        );
        assert_eq!(
            &line.slaves()[0].esc().raw_memory()[0x1100..0x1104],
            &[0; 4]
        );
    }

    #[test]
    fn the_sweep_runs_every_firmware_once_per_period_spread_over_it() {
        let n = 200;
        let mut line = crate::testing::line(n);
        assert_eq!(line.sweep_period_ns(), 2_000_000, "200 x 10 us");
        line.service(0).unwrap();
        line.service(1_000_000).unwrap();
        assert_eq!(
            line.firmware_runs(),
            100,
            "half the line after half the period"
        );
        line.service(1_500_000).unwrap();
        assert_eq!(line.firmware_runs(), 150);
        line.service(2_000_000).unwrap();
        assert_eq!(line.firmware_runs(), 200, "each slave once");
        // A long pause runs each slave once, not once per missed period.
        line.service(60_000_000).unwrap();
        assert_eq!(line.firmware_runs(), 400);
        // An idle pass runs the next 64 whatever the time.
        line.idle(60_000_000).unwrap();
        assert_eq!(line.firmware_runs(), 464);
        // Short lines keep the 1 ms minimum.
        assert_eq!(crate::testing::line(3).sweep_period_ns(), SWEEP_MIN_NS);
    }

    /// A frame of 130 datagrams (BRD of the AL status, each with "more
    /// follows"): both paths stop after MAX_DATAGRAMS (128), the last two
    /// left unanswered.
    #[test]
    fn line_stops_after_128_datagrams_like_the_esc() {
        // 130 × 14 bytes: longer than an Ethernet frame, within the
        // EtherCAT header's 2047.
        let mut buf = vec![0u8; 2048];
        let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
        let ends: Vec<usize> = (0..130)
            .map(|_| fb.push(Command::Brd, 0x0130 << 16, &[0, 0]).unwrap().end)
            .collect();
        let len = fb.finish();
        let mut f1 = buf[..len].to_vec();
        let mut f2 = f1.clone();
        let (mut serial, mut fast) = (crate::testing::line(3), crate::testing::line(3));
        assert_eq!(
            serial.process_serial(&mut f1),
            FrameOutcome::Processed { datagrams: 128 }
        );
        assert_eq!(
            fast.process_frame(&mut f2),
            FrameOutcome::Processed { datagrams: 128 }
        );
        assert_eq!(f1, f2);
        let wkc = |f: &[u8], end: usize| u16::from_le_bytes([f[end], f[end + 1]]);
        assert_eq!(
            wkc(&f2, ends[127]),
            3,
            "the 128th datagram reached all three"
        );
        assert_eq!(wkc(&f2, ends[128]), 0, "the 129th is not processed");
    }

    proptest! {
        // 32 sequences of 128 frames: 4096 frames against fresh lines (the
        // xorshift loop this replaces ran one sequence of 3000).
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// Damaged frames (cut short anywhere, a byte anywhere in the
        /// EtherCAT part overwritten: length fields running past the
        /// frame, "more follows" bits set on the last datagram, wrong
        /// commands) end the walk where the ESC's own walk ends: the line
        /// path answers them byte for byte like the serial path.
        #[test]
        fn dispatch_equals_serial_on_damaged_frames(
            frames in prop::collection::vec((random_frame(), any::<prop::sample::Index>(),
                any::<prop::sample::Index>(), any::<u8>(), any::<bool>()), 64),
            one in any::<bool>(),
        ) {
            // A line of one slave takes its own path (`dispatch_one`).
            let (mut serial, mut fast) = configured_pair(if one { 1 } else { 6 }, false);
            for (round, (frame, cut, at, byte, cut_first)) in frames.iter().enumerate() {
                let mut f1 = frame.bytes();
                // Ethernet header (14) and EtherCAT header (2) kept: the
                // damage falls on the datagrams.
                let body = f1.len().saturating_sub(16).max(1);
                if *cut_first {
                    // Cut inside the datagrams, the EtherCAT header's
                    // length following (else the whole frame is refused
                    // before any datagram is looked at).
                    f1.truncate(16 + cut.index(body));
                    let len = u16::try_from(f1.len() - 16).unwrap();
                    let h = u16::from_le_bytes([f1[14], f1[15]]);
                    f1[14..16].copy_from_slice(&((h & !0x07FF) | len).to_le_bytes());
                }
                let k = 16 + at.index(f1.len().saturating_sub(16).max(1));
                if let Some(b) = f1.get_mut(k) {
                    *b = *byte;
                }
                let mut f2 = f1.clone();
                let o1 = serial.process_serial(&mut f1);
                let o2 = fast.process_frame(&mut f2);
                prop_assert_eq!(o1, o2, "round {}", round);
                prop_assert_eq!(&f1, &f2, "frame differs in round {}", round);
            }
        }

        /// The line's dispatch (each datagram to the slaves it addresses)
        /// and the reference (every ESC walks the whole frame) give the
        /// same frames, outcomes and slave memories on random traffic.
        #[test]
        fn dispatch_equals_serial_processing(
            frames in prop::collection::vec(random_frame(), 128),
            reversed in any::<bool>(),
            one in any::<bool>(),
        ) {
            // A line of one slave takes its own path (`dispatch_one`).
            let n: u16 = if one { 1 } else { 6 };
            let (mut serial, mut fast) = configured_pair(n, reversed);
            let mut counted = 0usize;
            for (round, frame) in frames.iter().enumerate() {
                let mut f1 = frame.bytes();
                let mut f2 = f1.clone();
                let o1 = serial.process_serial(&mut f1);
                let o2 = fast.process_frame(&mut f2);
                prop_assert_eq!(o1, o2, "round {}", round);
                prop_assert_eq!(&f1, &f2, "frame differs in round {}", round);
                let eth = EthernetFrame::new_checked(&f1[..]).unwrap();
                let ecat = EcatFrame::new_checked(eth.payload()).unwrap();
                for r in ecat.datagrams() {
                    let dg = Datagram::new_checked(&ecat.payload()[r.unwrap()]).unwrap();
                    counted += usize::from(dg.wkc() != 0);
                }
            }
            // The traffic really reached slaves (not a comparison of no-ops;
            // one slave answers fewer of the random datagrams).
            let enough = if one { frames.len() / 2 } else { frames.len() };
            prop_assert!(counted > enough, "only {} datagrams were answered", counted);
            // And the slaves' memories agree: read back every station's
            // FMMU registers and a span of process RAM through both paths.
            for i in 0..6u16 {
                let mut buf = vec![0u8; 200];
                let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
                fb.push(
                    Command::Fprd,
                    u32::from(0x1000 + i) | (0x0600 << 16),
                    &[0; 16],
                )
                .unwrap();
                fb.push(
                    Command::Fprd,
                    u32::from(0x1000 + i) | (0x1100 << 16),
                    &[0; 64],
                )
                .unwrap();
                let len = fb.finish();
                let mut f1 = buf[..len].to_vec();
                let mut f2 = f1.clone();
                serial.process_serial(&mut f1);
                fast.process_frame(&mut f2);
                prop_assert_eq!(f1, f2, "slave {} memory", i);
            }
            // Whatever the traffic did (station addresses, SMs over the
            // registers, EEPROM reloads), every slave still answers an AL
            // status read by position, on both paths, and a broadcast
            // read reaches all of them.
            for i in 0..n {
                let mut buf = vec![0u8; 200];
                let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
                let aprd = fb
                    .push(
                        Command::Aprd,
                        u32::from(0u16.wrapping_sub(i)) | (0x0130 << 16),
                        &[0, 0],
                    )
                    .unwrap();
                let brd = fb.push(Command::Brd, 0x0130 << 16, &[0, 0]).unwrap();
                let len = fb.finish();
                let mut f1 = buf[..len].to_vec();
                let mut f2 = f1.clone();
                serial.process_serial(&mut f1);
                fast.process_frame(&mut f2);
                for f in [&f1, &f2] {
                    let wkc = |end: usize| u16::from_le_bytes([f[end], f[end + 1]]);
                    prop_assert_eq!(wkc(aprd.end), 1, "AL status of slave {} unreadable", i);
                    prop_assert_eq!(wkc(brd.end), n, "a broadcast AL status read missed slaves");
                }
            }
        }
    }
}

#[cfg(test)]
mod garbage_tests {
    use proptest::prelude::*;

    /// A frame of random bytes with the EtherCAT EtherType and, when
    /// `plausible`, an EtherCAT header whose length fits, so datagrams are
    /// reached.
    fn garbage_frame() -> impl Strategy<Value = Vec<u8>> {
        (prop::collection::vec(any::<u8>(), 16..1416), any::<bool>()).prop_map(
            |(mut f, plausible)| {
                f[6] = 0x10;
                f[12] = 0x88;
                f[13] = 0xA4;
                if plausible {
                    let pl = (f.len() - 16).min(0x7FF) as u16;
                    f[14] = pl as u8;
                    f[15] = 0x10 | ((pl >> 8) as u8 & 0x07);
                }
                f
            },
        )
    }

    proptest! {
        // 200 sequences of 100 frames: the 20 000 of the loop this replaces.
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn random_ethercat_frames_never_panic_the_line_or_its_firmware(
            frames in prop::collection::vec(garbage_frame(), 100)
        ) {
            let mut chain = crate::testing::line(2);
            for (i, mut f) in frames.into_iter().enumerate() {
                chain.process(&mut f, i as u64 * 1_000_000);
            }
        }
    }
}
