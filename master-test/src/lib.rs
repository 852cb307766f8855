//! # master-test: an ethercrab master for software slaves and real segments
//!
//! [`VirtualBus`] puts an ethercrab [`MainDevice`] on a virtual link
//! ([`link`]) to a line of software slaves of any devices of the catalog
//! (PAM-199-P-ETC by default): real EtherCAT frames, no sockets, no root.
//! [`bus::Bus`] is either that or ethercrab's raw socket on a network
//! interface. On top: what ethercrab lacks for commissioning, a raw
//! [`mailbox`] client (segmented SDO, [`sdo_info`], [`foe`], BOOT), the
//! SII [`eeprom`] interface, and the live dictionary ([`od`]).
//!
//! The `master-test` binary is the commissioning tool built from these
//! (see its `--help` and docs/book/src/commissioning.md); the integration tests use the same
//! pieces.

pub mod bus;
pub mod cli;
pub mod conformance;
pub mod corpus;
pub mod eeprom;
pub mod foe;
pub mod link;
pub mod mailbox;
pub mod od;
pub mod registers;
pub mod replay;
pub mod sdo_info;

use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, RetryBehaviour, Timeouts};
use link::{Chain, Clock, FaultConfig, FaultInjector, Link, SharedChain, SharedFaults};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Most slaves one group can hold.
pub const MAX_SUBDEVICES: usize = 64;
/// Most EtherCAT frames in flight.
pub const MAX_FRAMES: usize = 16;
/// Payload bytes of one frame.
pub const MAX_PDU_DATA: usize = PduStorage::element_size(1100);
/// Process data image of a group in bytes (64 slaves x 21 bytes fit).
pub const PDI_LEN: usize = 2048;

/// The group type used throughout the tests.
pub type Group<S> = ethercrab::SubDeviceGroup<MAX_SUBDEVICES, PDI_LEN, ethercrab::DefaultLock, S>;

/// Most slaves of a long-line group ([`LongGroup`]).
pub const LONG_LINE: usize = 1024;
/// Process data image of a long-line group in bytes (1024 slaves x 32).
pub const LONG_PDI_LEN: usize = 32768;

/// A group for long lines (up to [`LONG_LINE`] slaves): about 290 KB, so
/// keep it off small thread stacks (see [`VirtualBus::init_long`]).
pub type LongGroup<S> =
    ethercrab::SubDeviceGroup<LONG_LINE, LONG_PDI_LEN, ethercrab::DefaultLock, S>;

/// Errors of setting up a virtual bus.
#[derive(Debug, thiserror::Error)]
pub enum BusError {
    /// ethercrab reported an error.
    #[error("ethercrab: {0}")]
    Ethercrab(#[from] ethercrab::error::Error),
    /// The link thread could not be started.
    #[error("cannot start the virtual link thread: {0}")]
    Thread(#[from] std::io::Error),
    /// The PDU storage was already split.
    #[error("PDU storage already in use")]
    Storage,
    /// Not every slave reached OP within 10 s of cyclic exchange.
    #[error("not every slave reached OP within 10 s")]
    NotOp,
    /// The line named an unknown device.
    #[error("{0}")]
    Line(device_catalog::CatalogError),
    /// A line longer than the group of the command (`.1`: its most
    /// slaves; [`MAX_SUBDEVICES`] for the commissioning commands,
    /// [`LONG_LINE`] for the demo).
    #[error(
        "a line of {0} slaves: this command drives at most {1} (the demo up to {LONG_LINE}; \
         longer lines run on pam-slave)"
    )]
    LineTooLong(usize, usize),
    /// The ENI or an ESI file of a twin line is wrong (file, element and
    /// line in the text).
    #[error("{0}")]
    Twins(String),
}

/// A line of `n` PAM-199-P-ETC slaves in their power-on state.
pub fn pam_line(n: usize) -> Chain {
    Chain::of(n, pam_199_p_etc::Pam::default)
}

/// Timeouts suited to the in-process link on a busy CI machine.
///
/// ethercrab measures them in real time while the slaves run on the
/// simulated clock, so they only bound how long the machine may stall a
/// frame: a PDU or an EEPROM read that takes seconds means a hung link,
/// not a slow slave. With 100 ms for an EEPROM operation a bring-up failed
/// now and then with two busy loops on a 2-core machine already loaded to
/// 9 (`timeout: EEPROM`).
pub fn timeouts() -> Timeouts {
    Timeouts {
        state_transition: Duration::from_secs(10),
        pdu: Duration::from_secs(3),
        eeprom: Duration::from_secs(3),
        wait_loop_delay: Duration::from_micros(100),
        mailbox_echo: Duration::from_millis(500),
        mailbox_response: Duration::from_secs(2),
    }
}

/// An ethercrab master connected to a chain of software slaves.
pub struct VirtualBus {
    /// The ethercrab master.
    pub maindevice: Arc<MainDevice<'static>>,
    /// The slaves on the line (lock with [`link::lock`]).
    pub chain: SharedChain,
    /// The slaves' clock.
    pub clock: Clock,
    /// The faulty wire, if the bus has one ([`VirtualBus::with_faults`]).
    pub faults: Option<SharedFaults>,
    _link: Link,
}

/// Timeouts of a master on a faulty wire: a lost frame must cost about
/// a cycle, not half a second, or the slaves' SM watchdog (100 ms) fires
/// before the master notices; a lost frame is sent again up to 3 times.
pub fn fault_timeouts() -> (Timeouts, RetryBehaviour) {
    (
        Timeouts {
            pdu: Duration::from_millis(10),
            ..timeouts()
        },
        RetryBehaviour::Count(3),
    )
}

impl VirtualBus {
    /// `n` PAM-199-P-ETC slaves on a frame clock ([`Clock::frames`]): their
    /// time follows the traffic, so what they do does not depend on how
    /// busy the machine is.
    pub fn new(n: usize) -> Result<Self, BusError> {
        Self::with_clock(n, Clock::frames())
    }

    /// `n` PAM-199-P-ETC slaves whose firmware sees `clock`.
    pub fn with_clock(n: usize, clock: Clock) -> Result<Self, BusError> {
        Self::with_options(n, clock, None)
    }

    /// `n` PAM-199-P-ETC slaves on `clock`, capturing every frame to the
    /// pcap file `pcap`.
    pub fn with_options(
        n: usize,
        clock: Clock,
        pcap: Option<&std::path::Path>,
    ) -> Result<Self, BusError> {
        Self::with_chain(pam_line(n), clock, pcap)
    }

    /// The line `spec` of catalog devices (`pam,io8,pam`, `io8*4`) on
    /// `clock`.
    pub fn line(spec: &str, clock: Clock) -> Result<Self, BusError> {
        Self::line_with(spec, clock, None)
    }

    /// [`VirtualBus::line`] capturing every frame to the pcap file `pcap`.
    pub fn line_with(
        spec: &str,
        clock: Clock,
        pcap: Option<&std::path::Path>,
    ) -> Result<Self, BusError> {
        let entries = device_catalog::parse_line(spec).map_err(BusError::Line)?;
        Self::with_chain(
            Chain::with_slaves(device_catalog::slaves(&entries)),
            clock,
            pcap,
        )
    }

    /// A bus over a prepared line of slaves.
    pub fn with_chain(
        chain: Chain,
        clock: Clock,
        pcap: Option<&std::path::Path>,
    ) -> Result<Self, BusError> {
        let pcap = pcap.map(ecat_sim::pcap::PcapWriter::create).transpose()?;
        Self::on_shared(Arc::new(Mutex::new(chain)), clock, pcap, None, 0)
    }

    /// A bus over `chain` whose master sets up Distributed Clocks at init
    /// as ethercrab does on real lines: receive times latched (BWR 0x0900)
    /// and read, system time offsets and transmission delays written, then
    /// `iterations` FRMWs of the reference clock's system time (static
    /// drift compensation; ethercrab's default is 10 000). The other
    /// constructors set 0 iterations.
    pub fn with_dc(chain: Chain, clock: Clock, iterations: u32) -> Result<Self, BusError> {
        Self::on_shared(Arc::new(Mutex::new(chain)), clock, None, None, iterations)
    }

    /// A bus over `chain` whose wire injects `faults` (see
    /// [`link::FaultConfig`]); the master uses [`fault_timeouts`].
    pub fn with_faults(chain: Chain, clock: Clock, faults: FaultConfig) -> Result<Self, BusError> {
        let f = Arc::new(Mutex::new(FaultInjector::new(faults)));
        Self::on_shared(Arc::new(Mutex::new(chain)), clock, None, Some(f), 0)
    }

    /// What the faulty wire injected so far (zeros without faults).
    pub fn fault_stats(&self) -> link::FaultStats {
        self.faults
            .as_ref()
            .map(|f| link::lock_faults(f).stats())
            .unwrap_or_default()
    }

    /// Another master session on the same line: a new ethercrab
    /// [`MainDevice`] with its own link to the slaves of this bus (as when
    /// one master program stops and the next one starts). The slaves keep
    /// their state; both links may run.
    pub fn next_session(&self) -> Result<Self, BusError> {
        Self::on_shared(self.chain.clone(), self.clock.clone(), None, None, 0)
    }

    fn on_shared(
        chain: SharedChain,
        clock: Clock,
        pcap: Option<ecat_sim::pcap::PcapWriter<std::io::BufWriter<std::fs::File>>>,
        faults: Option<SharedFaults>,
        dc_static_sync_iterations: u32,
    ) -> Result<Self, BusError> {
        // Each bus owns its storage for the life of the process; tests
        // create a handful, so leaking is the simple, safe choice.
        let storage: &'static PduStorage<MAX_FRAMES, MAX_PDU_DATA> =
            Box::leak(Box::new(PduStorage::new()));
        let (tx, rx, pdu_loop) = storage.try_split().map_err(|()| BusError::Storage)?;
        let (t, retry_behaviour) = match faults {
            Some(_) => fault_timeouts(),
            None => (timeouts(), RetryBehaviour::None),
        };
        let maindevice = Arc::new(MainDevice::new(
            pdu_loop,
            t,
            MainDeviceConfig {
                dc_static_sync_iterations,
                retry_behaviour,
            },
        ));
        let link =
            Link::spawn_with_faults(tx, rx, chain.clone(), clock.clone(), pcap, faults.clone())?;
        Ok(VirtualBus {
            maindevice,
            chain,
            clock,
            faults,
            _link: link,
        })
    }

    /// Runs every slave's firmware once now, as its main loop does
    /// between events. The link runs a firmware when its ESC raises an AL
    /// event, when its sweep turn comes in the slaves' time and when the
    /// link is idle ([`link::Chain::service`], [`link::Chain::idle`]); a
    /// test on a simulated clock that stands still while it keeps the
    /// link busy calls this to let the firmware notice what it injected
    /// (a PDI fault, a stall). Returns the first PDI failure (slave
    /// position, error), which the slave has already handled.
    pub fn run_firmware(&self) -> Result<(), (usize, ecat_slave::esc::EscError)> {
        link::lock(&self.chain).poll(self.clock.now_ns())
    }

    /// [`VirtualBus::init`] for lines longer than [`MAX_SUBDEVICES`] (up
    /// to [`LONG_LINE`] slaves). The group is large: run it on a thread
    /// with a big stack (the long-line tests use 64 MiB).
    pub async fn init_long(
        &self,
    ) -> Result<LongGroup<ethercrab::subdevice_group::PreOp>, BusError> {
        let md: &MainDevice<'static> = &self.maindevice;
        Ok(md
            .init_single_group::<LONG_LINE, LONG_PDI_LEN>(ethercrab::std::ethercat_now)
            .await?)
    }

    /// Discovers the slaves and brings them to PRE-OP (ethercrab's
    /// `init_single_group`; at most [`MAX_SUBDEVICES`] slaves, else
    /// ethercrab's capacity error; longer lines use
    /// [`VirtualBus::init_long`]).
    pub async fn init(&self) -> Result<Group<ethercrab::subdevice_group::PreOp>, BusError> {
        let md: &MainDevice<'static> = &self.maindevice;
        Ok(md
            .init_single_group::<MAX_SUBDEVICES, PDI_LEN>(ethercrab::std::ethercat_now)
            .await?)
    }
}

/// How far a master has brought a line of software slaves, read from
/// their registers: SII read (the EEPROM address,
/// [`registers::SII_ADDRESS`], moved), AL state
/// ([`registers::AL_STATUS`]) at least PRE-OP, at least SAFE-OP, OP.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LineProgress {
    /// Slaves on the line.
    pub slaves: usize,
    /// Slaves whose SII the master has read.
    pub sii_read: usize,
    /// Slaves in PRE-OP, SAFE-OP or OP.
    pub pre_op: usize,
    /// Slaves in SAFE-OP or OP.
    pub safe_op: usize,
    /// Slaves in OP.
    pub op: usize,
}

impl LineProgress {
    /// The progress of `chain` now.
    pub fn of(chain: &Chain) -> Self {
        let mut p = LineProgress {
            slaves: chain.slaves().len(),
            ..LineProgress::default()
        };
        for s in chain.slaves() {
            let mem = s.esc().raw_memory();
            let word = |a: usize| {
                mem.get(a..a + 2)
                    .map_or(0, |b| u16::from_le_bytes([b[0], b[1]]))
            };
            p.sii_read += usize::from(word(usize::from(registers::SII_ADDRESS)) != 0);
            let state = word(usize::from(registers::AL_STATUS)) & 0x0F;
            p.pre_op += usize::from(matches!(state, 2 | 4 | 8));
            p.safe_op += usize::from(matches!(state, 4 | 8));
            p.op += usize::from(state == 8);
        }
        p
    }

    /// Steps done of [`LineProgress::total`]: each slave's SII, PRE-OP,
    /// SAFE-OP and OP.
    pub fn done(&self) -> usize {
        self.sii_read + self.pre_op + self.safe_op + self.op
    }

    /// All steps of a bring-up to OP.
    pub fn total(&self) -> usize {
        self.slaves * 4
    }
}

/// Brings a PRE-OP group to OP the way a real master does for devices
/// with a SyncManager watchdog: request OP and keep exchanging process
/// data (fresh outputs every `cycle`) until every slave reports OP.
pub async fn into_op_cyclic<const N: usize, const P: usize>(
    group: ethercrab::SubDeviceGroup<
        N,
        P,
        ethercrab::DefaultLock,
        ethercrab::subdevice_group::PreOp,
    >,
    md: &MainDevice<'_>,
    cycle: Duration,
) -> Result<
    ethercrab::SubDeviceGroup<N, P, ethercrab::DefaultLock, ethercrab::subdevice_group::Op>,
    BusError,
> {
    let group = group.into_safe_op(md).await?.request_into_op(md).await?;
    let deadline = std::time::Instant::now() + Duration::from_secs(10);
    loop {
        let resp = group.tx_rx(md).await?;
        if resp.all_op() {
            return Ok(group);
        }
        if std::time::Instant::now() > deadline {
            return Err(BusError::NotOp);
        }
        smol::Timer::after(cycle).await;
    }
}
