//! The raw-socket runner: a line of software slaves (any devices) answering
//! EtherCAT frames (EtherType 0x88A4) on a real network interface, so any
//! master (TwinCAT, SOEM/pysoem, IgH, ethercrab's raw-socket task) can drive
//! them. Frames come back out of the same interface, as from the last slave
//! of a line. Everything that is not EtherCAT, and frames a slave already
//! processed (source MAC with the locally administered bit set: our own
//! replies seen again), is ignored.

mod ahead;
pub mod cycle;
mod pin;
mod socket;
mod turns;

use crate::chain::{
    Chain, IMAGE_SLOT_CAPACITY, LineSlave, factory_image_store_of, provision_factory,
};
use crate::faults::{Fate, FaultConfig, FaultInjector};
use crate::file_store::FileStore;
use crate::pcap::PcapWriter;
use crate::state_dir::{Loaded, SlaveState};
use ahead::AheadAnswers;
use cycle::CycleWatch;
use ecat_slave::firmware::ImageStore;
pub use pin::{allowed_cpus, pin_to_cpu};
use pnet_datalink::NetworkInterface;
use socket::{PacketSocket, is_queue_full};
use std::fs::File;
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use turns::{FirmwareTurns, YieldAfterReply};

/// What to run (the slaves themselves are handed to [`run`]).
#[derive(Debug, Clone)]
pub struct RunnerConfig {
    /// Network interface name.
    pub iface: String,
    /// Capture every frame (both directions) to this pcap file.
    pub pcap: Option<PathBuf>,
    /// Directory for the slaves' persistent state.
    pub state_dir: Option<PathBuf>,
    /// A faulty wire in front of the line ([`crate::faults`]).
    pub faults: Option<FaultConfig>,
    /// Port 1 of the last slave: frames leave through this interface to
    /// the next runner after this line processed them, and what comes
    /// back goes out of `iface` to the master ([`run`]).
    pub forward: Option<String>,
    /// Slot capacity of each slave's firmware store, the largest image it
    /// accepts ([`IMAGE_SLOT_CAPACITY`] by default); a slave's store takes
    /// up to two slots of it, in memory (or on disk with `state_dir`).
    pub image_slot_capacity: usize,
    /// Poll the socket without sleeping in a short window around the
    /// time a cyclic master's next frame is due ([`cycle`]), so its
    /// arrival costs no thread wake-up; at most a fifth of a core. Off by
    /// default: on this project's 2-vCPU VM it made the round trip slower
    /// (a 4 kHz master: p50 21 / 32 µs with 8 / 64 slaves against 13 / 11
    /// µs sleeping; no better at 1 kHz), presumably because the polling
    /// vCPU takes time from the one the master and the kernel's veth path
    /// run on. Worth trying where the runner has a core of its own.
    pub busy_poll: bool,
    /// Answer a cyclic master's process-data frames ahead
    /// ([`Chain::ahead`]): the reply is worked out while the runner
    /// waits, sent as the frame arrives, and the ESCs then run on the
    /// frame as always (their reply must be the same; a difference is
    /// counted in [`RunStats::ahead_differed`] and switches this off). On
    /// by default.
    pub answer_ahead: bool,
}

impl RunnerConfig {
    /// Serves `iface` with the defaults: no capture, no state directory,
    /// no faults, no forwarding, [`IMAGE_SLOT_CAPACITY`], no busy polling,
    /// answers ahead.
    pub fn new(iface: impl Into<String>) -> Self {
        Self {
            iface: iface.into(),
            pcap: None,
            state_dir: None,
            faults: None,
            forward: None,
            image_slot_capacity: IMAGE_SLOT_CAPACITY,
            busy_poll: false,
            answer_ahead: true,
        }
    }
}

/// Why the runner could not run.
#[derive(Debug, thiserror::Error)]
pub enum RunnerError {
    /// No interface of that name.
    #[error("network interface '{name}' does not exist (available: {available})")]
    NoSuchInterface {
        /// The name asked for.
        name: String,
        /// Interfaces that exist.
        available: String,
    },
    /// The process may not open a raw socket.
    #[error(
        "no permission to open a raw socket on '{0}': run as root or grant CAP_NET_RAW (sudo setcap cap_net_raw+ep <binary>)"
    )]
    Permission(String),
    /// The slave count is out of range.
    #[error("a line needs 1 to {MAX_LINE} slaves, got {0}")]
    Count(usize),
    /// The firmware store was written once but its boot records are gone:
    /// the runner will not fall back to the factory firmware silently.
    #[error(
        "the firmware boot records in {} are unreadable although the store was written: \
         refusing to fall back to the factory firmware silently (remove the directory to \
         start from the factory firmware)",
        .0.display()
    )]
    LostBootState(PathBuf),
    /// The thread relaying frames that come back on the forwarding
    /// interface stopped while the runner ran: the line behind this runner
    /// is cut off, so the runner stops too instead of serving half a line.
    #[error("the relay of frames coming back on {iface} failed ({reason}); stopping")]
    RelayFailed {
        /// The forwarding interface.
        iface: String,
        /// What ended the relay.
        reason: String,
    },
    /// The runner could not be pinned to the CPU asked for
    /// ([`pin_to_cpu`]).
    #[error("cannot pin the runner to CPU {cpu}: {reason}")]
    Cpu {
        /// The CPU asked for.
        cpu: usize,
        /// Why not, with the CPUs the process may use.
        reason: String,
    },
    /// Any other I/O failure.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The error.
        source: io::Error,
    },
}

/// Counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RunStats {
    /// EtherCAT frames answered.
    pub answered: u64,
    /// Frames ignored (other EtherTypes, our own replies).
    pub ignored: u64,
    /// The SPI wires' counters summed over the slaves whose firmware runs
    /// through an SPI driver and an emulated chip (`None`: no such slave).
    pub spi: Option<crate::slave::SpiStats>,
    /// Of the frames answered, those answered ahead
    /// ([`RunnerConfig::answer_ahead`]).
    pub answered_ahead: u64,
    /// Frames answered ahead whose reply from the ESCs then differed from
    /// the one sent (0 unless there is a bug; the first switches answering
    /// ahead off for the run).
    pub ahead_differed: u64,
    /// How often the yield after a reply answered ahead was paused for a
    /// second because yields took long (a busy machine).
    pub yield_pauses: u64,
}

/// Most slaves one runner serves.
pub const MAX_LINE: usize = 4096;

/// How long a reordered reply is held (it then follows later replies).
const REORDER_HOLD: Duration = Duration::from_millis(2);

/// Longest sleep of the threads that only wait for frames (the relay of
/// returning frames, [`reflect`]) before they look at their stop flags.
const STOP_CHECK: Duration = Duration::from_millis(100);

/// How often a firmware run looks whether a frame waits: a frame waits at
/// most this long plus one slave's firmware step.
const CHECK_EVERY: Duration = Duration::from_micros(5);

/// Receive buffer: a jumbo frame fits.
const RECV_BUFFER: usize = 16 * 1024;

/// Waits up to `d` for a frame on `sock`.
fn sock_wait(sock: &PacketSocket, d: Duration) -> Result<(), RunnerError> {
    sock.wait(d).map(|_| ()).map_err(|source| RunnerError::Io {
        context: "waiting for a frame".into(),
        source,
    })
}

/// Opens the interface and serves frames for the line `slaves` (first to
/// last) until `stop` is set.
pub fn run(
    config: &RunnerConfig,
    slaves: Vec<Box<dyn LineSlave>>,
    stop: &AtomicBool,
) -> Result<RunStats, RunnerError> {
    if slaves.is_empty() || slaves.len() > MAX_LINE {
        return Err(RunnerError::Count(slaves.len()));
    }
    let iface = find_interface(&config.iface)?;
    let out_iface = config.forward.as_deref().map(find_interface).transpose()?;
    if out_iface.as_ref().is_some_and(|o| o.name == iface.name) {
        return Err(RunnerError::Io {
            context: format!("forwarding from {} to itself", iface.name),
            source: io::Error::new(
                io::ErrorKind::InvalidInput,
                "--forward needs a second interface",
            ),
        });
    }
    if let Some(dir) = &config.state_dir {
        std::fs::create_dir_all(dir).map_err(|source| RunnerError::Io {
            context: format!("creating state directory {}", dir.display()),
            source,
        })?;
    }
    let mut pcap: Option<PcapWriter<BufWriter<File>>> = match &config.pcap {
        Some(p) => Some(PcapWriter::create(p).map_err(|source| RunnerError::Io {
            context: format!("creating pcap file {}", p.display()),
            source,
        })?),
        None => None,
    };
    let sock = Arc::new(PacketSocket::open(&iface)?);
    let (mut chain, mut states) = match &config.state_dir {
        Some(dir) => persistent_chain_with(dir, slaves, config.image_slot_capacity)?,
        None => {
            let stores = slaves
                .iter()
                .map(|_| factory_image_store_of(config.image_slot_capacity))
                .collect();
            (Chain::with_stores(slaves, stores), Vec::new())
        }
    };
    // On a wire the slaves' clock is real time: the sweep runs every
    // firmware in its turn, and the extra passes of an idle link (meant
    // for a simulated clock that stands still) would only run into the
    // next frame of a cyclic master.
    chain.set_idle_passes(false);
    let out = out_iface
        .as_ref()
        .map(PacketSocket::open)
        .transpose()?
        .map(Arc::new);
    // The master-side socket, shared with the thread that relays frames
    // coming back from the next runner (replaced when it is reopened).
    let shared = Mutex::new(Arc::clone(&sock));
    let mut sock = sock;
    let mut port1 = PortWatch::new(out_iface.as_ref().map(|i| i.name.clone()));
    if let Some(up) = port1.poll() {
        set_last_port1(&mut chain, up);
    }
    let start = Instant::now();
    let clock = || u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
    let mut stats = RunStats::default();
    let mut rbuf = vec![0u8; RECV_BUFFER];
    let mut faults = config.faults.clone().map(FaultInjector::new);
    // Replies held back by the faulty wire: (release time, frame).
    let mut held: Vec<(Instant, Vec<u8>)> = Vec::new();
    let mut was_down = false;
    let send = |sock: &PacketSocket, frame: &[u8]| -> Result<(), RunnerError> {
        match sock.send(frame) {
            // A full transmit queue loses the frame, as a wire would; the
            // master's retry decides.
            Err(e) if is_queue_full(&e) => Ok(()),
            Err(source) => Err(RunnerError::Io {
                context: format!("sending on {}", iface.name),
                source,
            }),
            Ok(()) => Ok(()),
        }
    };
    // A processed frame goes on down the line when port 1 has a link
    // (without the "processed" mark, so the next runner takes it as a
    // request; it marks it again), else it turns around to the master.
    let out_name = out_iface
        .as_ref()
        .map(|i| i.name.clone())
        .unwrap_or_default();
    //
    // A frame port 1 cannot take is never fatal: the kernel refuses a
    // send while the next runner's cable is being pulled (ENOBUFS from the
    // veth's queue, ENETDOWN, ENXIO for a vanished interface) before the
    // link watch has seen it go. With the link gone the ESC closes the
    // loop and the frame turns around to the master; with the link still
    // up the frame is lost as on a wire, and the master's retry decides.
    let reply =
        |sock: &PacketSocket, port1: &mut PortWatch, frame: &mut [u8]| -> Result<(), RunnerError> {
            match out.as_ref().filter(|_| port1.up) {
                Some(o) => {
                    if let Some(b) = frame.get_mut(6) {
                        *b &= !0x02;
                    }
                    let r = o.send(frame);
                    if let Some(b) = frame.get_mut(6) {
                        *b |= 0x02;
                    }
                    match r {
                        Err(_) if link_is_down(&out_name) => {
                            port1.lost();
                            send(sock, frame)
                        }
                        _ => Ok(()),
                    }
                }
                None => send(sock, frame),
            }
        };
    let done = AtomicBool::new(false);
    let mut reopened: Option<Instant> = None;
    // The master's cycle: the window of its next frame.
    let mut cycle = CycleWatch::new();
    // When the firmware runs between frames.
    let mut turns = FirmwareTurns::new(Instant::now());
    // Whether the master gets the CPU right after a reply answered ahead.
    let mut yielding = YieldAfterReply::default();
    // Replies worked out ahead; forgotten whenever anything runs on the
    // line.
    // (Not on a faulty wire: its frames take their fate first.)
    let mut answers = AheadAnswers::new(config.answer_ahead && config.faults.is_none());
    std::thread::scope(|scope| {
        let relay = out.as_ref().zip(out_iface.as_ref()).map(|(o, out_nic)| {
            let (o, shared, done) = (Arc::clone(o), &shared, &done);
            scope.spawn(move || relay_back(o, out_nic, shared, stop, done))
        });
        let result = (|| -> Result<RunStats, RunnerError> {
            while !stop.load(Ordering::Acquire) {
                // A relay that ended on its own (an error, or a panic) is
                // noticed at once: joined below, it says why.
                if relay.as_ref().is_some_and(|h| h.is_finished()) {
                    return Err(RunnerError::RelayFailed {
                        iface: out_name.clone(),
                        reason: String::new(),
                    });
                }
                if let Some(up) = port1.poll() {
                    set_last_port1(&mut chain, up);
                    answers.forget();
                }
                if port1.take_lost() {
                    set_last_port1(&mut chain, false);
                    answers.forget();
                }
                if !held.is_empty() {
                    let t = Instant::now();
                    let mut due = Vec::new();
                    held.retain(|(at, f)| {
                        let ready = *at <= t;
                        if ready {
                            due.push(f.clone());
                        }
                        !ready
                    });
                    for mut f in due {
                        reply(&sock, &mut port1, &mut f)?;
                    }
                }
                let mut run_firmware = false;
                match sock.try_recv(&mut rbuf) {
                    Ok(Some(len)) => {
                        let buf = &mut rbuf[..len];
                        if !is_request(buf) {
                            stats.ignored += 1;
                            continue;
                        }
                        let arrived = clock();
                        // A process-data frame of the shape worked out
                        // ahead is answered before anything else is looked
                        // at (after a cycle's sleep each cache line and
                        // page on the way to the reply costs); the ESCs
                        // then run on it as on any other, and must reply
                        // the same.
                        let ahead = if let Some(r) = answers.answer(buf, arrived) {
                            reply(&sock, &mut port1, r)?;
                            let now = Instant::now();
                            if yielding.due(now) {
                                std::thread::yield_now();
                                yielding.yielded(now, Instant::now());
                            }
                            true
                        } else {
                            false
                        };
                        cycle.arrival(arrived);
                        if let Some(p) = pcap.as_mut() {
                            let _ = p.write_frame(buf);
                        }
                        let fate = faults
                            .as_mut()
                            .map_or(Fate::Deliver, |f| f.fate(start.elapsed()));
                        let down = fate == Fate::LinkDown;
                        if down && !was_down {
                            chain.link_lost();
                        }
                        was_down = down;
                        turns.frame_arrived(Instant::now());
                        if matches!(fate, Fate::DropBefore | Fate::LinkDown | Fate::Corrupt) {
                            answers.forget();
                            if fate == Fate::Corrupt {
                                chain.corrupted_frame();
                            }
                            continue;
                        }
                        let request = (fate == Fate::Duplicate).then(|| buf.to_vec());
                        if !ahead {
                            answers.forget();
                            answers.learn(buf);
                        }
                        // As on silicon, the ESCs answer the frame at once;
                        // the firmware runs afterwards, once no frame
                        // waits. A slow firmware step (a flash write with
                        // fsync in FoE) delays the mailbox answer, never
                        // the frame: masters with short frame timeouts
                        // (SOEM: 2 ms) keep working.
                        chain.process_frame_at(buf, arrived);
                        if let Some(p) = pcap.as_mut() {
                            let _ = p.write_frame(buf);
                        }
                        if ahead && !answers.check(buf) {
                            eprintln!(
                                "error: a frame answered ahead differed from the ESCs' own reply \
                                 (a bug: please report it with a capture, --pcap); \
                                 no longer answering ahead"
                            );
                        }
                        match fate {
                            _ if ahead => {}
                            Fate::DropAfter => {}
                            Fate::Delay(d) => held.push((Instant::now() + d, buf.to_vec())),
                            Fate::Reorder => {
                                held.push((Instant::now() + REORDER_HOLD, buf.to_vec()))
                            }
                            _ => {
                                reply(&sock, &mut port1, buf)?;
                                if let Some(mut again) = request {
                                    chain.process_frame_at(&mut again, arrived);
                                    reply(&sock, &mut port1, &mut again)?;
                                }
                            }
                        }
                        stats.answered += 1;
                        // Frames that never let the queue empty (a flood)
                        // still leave the firmware its turn.
                        run_firmware = turns.starved(Instant::now());
                    }
                    Ok(None) if turns.due(Instant::now()) => run_firmware = true,
                    Ok(None) => {
                        // The line waits: what the next cyclic frame will
                        // read is in the caches now.
                        answers.prepare(&chain);
                        let now = Instant::now();
                        let now_ns = clock();
                        let at = |ns: u64| now + Duration::from_nanos(ns.saturating_sub(now_ns));
                        let window = cycle.window().filter(|w| w.until > now_ns);
                        if let Some(w) = window {
                            // The idle run keeps out of the window of a
                            // cyclic master's next frame (the frame's own
                            // firmware run comes right after it), and no
                            // timer wakes the runner there or while the
                            // frame is answered (`Window::clear`).
                            let next_idle = turns.next_idle();
                            let keep_out = at(w.from).checked_sub(turns.idle_took() + CHECK_EVERY);
                            if keep_out.is_none_or(|k| next_idle >= k) && next_idle < at(w.clear) {
                                turns.postpone_idle(at(w.clear));
                            }
                        }
                        let mut until = turns.next_idle();
                        if let Some((at, _)) = held.iter().min_by_key(|(at, _)| *at) {
                            until = until.min(*at);
                        }
                        match window.filter(|_| config.busy_poll) {
                            // Before the window: sleep until it opens.
                            Some(w) if now_ns < w.from => sock_wait(
                                &sock,
                                until.min(at(w.from)).saturating_duration_since(now),
                            )?,
                            // In the window: poll without sleeping.
                            Some(_) => {}
                            None => sock_wait(&sock, until.saturating_duration_since(now))?,
                        }
                    }
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    Err(_) if link_is_down(&iface.name) => {
                        // A pulled cable on port 0: the slaves keep running
                        // on their own until it is back.
                        if !was_down {
                            chain.link_lost();
                        }
                        was_down = true;
                        answers.forget();
                        let _ = chain.idle(clock());
                        persist_parameters(&chain, &mut states)?;
                        std::thread::sleep(Duration::from_millis(5));
                    }
                    // The link is back but the socket keeps the error of
                    // its going down: a fresh socket (once; an error right
                    // after that is real).
                    Err(_) if reopened.is_none_or(|t| t.elapsed() > Duration::from_millis(50)) => {
                        sock = Arc::new(PacketSocket::open(&iface)?);
                        *shared.lock().unwrap_or_else(|e| e.into_inner()) = Arc::clone(&sock);
                        reopened = Some(Instant::now());
                        was_down = false;
                    }
                    Err(source) => {
                        return Err(RunnerError::Io {
                            context: format!("receiving on {}", iface.name),
                            source,
                        });
                    }
                }
                if run_firmware {
                    // The firmware runs (what the frames raised, the
                    // sweep's turns), stopping for the next frame.
                    // Whatever a firmware step acknowledged (SAVE) is on
                    // stable storage before the master can read the
                    // acknowledgement.
                    answers.forget();
                    let t = Instant::now();
                    let mut checked = t;
                    let mut frame_waiting = || {
                        let now = Instant::now();
                        if now.duration_since(checked) < CHECK_EVERY {
                            return false;
                        }
                        checked = now;
                        sock.wait(Duration::ZERO).unwrap_or(true)
                    };
                    // A PDI failure is counted and handled by the
                    // slave (fail-safe).
                    let stopped = chain.service_until(clock(), &mut frame_waiting) == Ok(false);
                    persist_parameters(&chain, &mut states)?;
                    turns.ran(t, Instant::now(), stopped);
                }
            }
            stats.answered_ahead = answers.answered;
            stats.ahead_differed = answers.differed;
            stats.yield_pauses = yielding.pauses();
            stats.spi = chain
                .slaves()
                .iter()
                .filter_map(|s| s.spi_stats())
                .reduce(crate::slave::SpiStats::sum);
            Ok(stats)
        })();
        done.store(true, Ordering::Release);
        let relayed = relay.map(|h| h.join());
        if let Some(p) = pcap.as_mut() {
            let _ = p.flush();
        }
        let relay_failed = |reason: String| RunnerError::RelayFailed {
            iface: out_name.clone(),
            reason,
        };
        match (result, relayed) {
            (Err(RunnerError::RelayFailed { .. }) | Ok(_), Some(Ok(Err(e)))) => {
                Err(relay_failed(e.to_string()))
            }
            (Err(RunnerError::RelayFailed { .. }) | Ok(_), Some(Err(_))) => {
                Err(relay_failed("the relay thread panicked".into()))
            }
            (Err(RunnerError::RelayFailed { .. }), _) => {
                Err(relay_failed("the relay thread ended".into()))
            }
            (Err(e), _) => Err(e),
            (Ok(stats), _) => Ok(stats),
        }
    })
}

/// The floor of [`run`] for latency measurements: answers every EtherCAT
/// request on `iface` at once, unchanged but marked as processed (source
/// MAC bit 1), through the same socket path and loop as the runner but
/// without any slave. What a benchmark measures against it is what the
/// kernel and the socket cost without EtherCAT work. Runs until `stop`.
pub fn reflect(iface: &str, stop: &AtomicBool) -> Result<RunStats, RunnerError> {
    let nic = find_interface(iface)?;
    let sock = PacketSocket::open(&nic)?;
    let mut stats = RunStats::default();
    let mut buf = vec![0u8; RECV_BUFFER];
    let io = |context: &str, source| RunnerError::Io {
        context: format!("{context} on {iface}"),
        source,
    };
    while !stop.load(Ordering::Acquire) {
        match sock.try_recv(&mut buf) {
            Ok(Some(len)) => {
                let frame = &mut buf[..len];
                if !is_request(frame) {
                    stats.ignored += 1;
                    continue;
                }
                if let Some(b) = frame.get_mut(6) {
                    *b |= 0x02;
                }
                match sock.send(frame) {
                    Err(e) if !is_queue_full(&e) => return Err(io("sending", e)),
                    _ => stats.answered += 1,
                }
            }
            // Sleeps until a frame comes, like the kernel floor's
            // reflector (`../shared/bench/veth-floor`): no polling window,
            // and no timer near the frames (`stop` is seen within
            // STOP_CHECK).
            Ok(None) => {
                sock.wait(STOP_CHECK).map_err(|e| io("waiting", e))?;
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(io("receiving", e)),
        }
    }
    Ok(stats)
}

/// Frames coming back from the next runner on port 1 (processed there,
/// marked) go out of port 0 to the master unchanged, as the return path
/// of an ESC passes them through. Runs until `stop` or `done`.
fn relay_back(
    mut rx: Arc<PacketSocket>,
    out: &NetworkInterface,
    to_master: &Mutex<Arc<PacketSocket>>,
    stop: &AtomicBool,
    done: &AtomicBool,
) -> Result<(), RunnerError> {
    let out_name = out.name.as_str();
    let mut reopened: Option<Instant> = None;
    let mut buf = vec![0u8; RECV_BUFFER];
    while !stop.load(Ordering::Acquire) && !done.load(Ordering::Acquire) {
        match rx.try_recv(&mut buf) {
            Ok(Some(len)) => {
                let frame = &buf[..len];
                if is_processed(frame) {
                    let tx = Arc::clone(&to_master.lock().unwrap_or_else(|e| e.into_inner()));
                    if let Err(source) = tx.send(frame)
                        && !is_queue_full(&source)
                    {
                        return Err(RunnerError::Io {
                            context: "relaying a returning frame to the master".into(),
                            source,
                        });
                    }
                }
            }
            Ok(None) => {
                rx.wait(STOP_CHECK).map_err(|source| RunnerError::Io {
                    context: format!("waiting for frames back on {out_name}"),
                    source,
                })?;
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            // The next runner's cable pulled: wait for it.
            Err(_) if link_is_down(out_name) => std::thread::sleep(Duration::from_millis(5)),
            // Back: a fresh socket (see `run`).
            Err(_) if reopened.is_none_or(|t| t.elapsed() > Duration::from_millis(50)) => {
                rx = Arc::new(PacketSocket::open(out)?);
                reopened = Some(Instant::now());
            }
            Err(source) => {
                return Err(RunnerError::Io {
                    context: format!("receiving frames back on {out_name}"),
                    source,
                });
            }
        }
    }
    Ok(())
}

/// Whether port 1 (the forwarding interface) has a link, checked every
/// 100 ms (carrier: the interface is up and its peer too), or at once
/// when a frame could not go out on it.
struct PortWatch {
    name: Option<String>,
    up: bool,
    checked: Option<Instant>,
    /// Set by [`PortWatch::lost`] until the line's DL status shows it.
    lost: bool,
}

impl PortWatch {
    fn new(name: Option<String>) -> Self {
        PortWatch {
            name,
            up: false,
            checked: None,
            lost: false,
        }
    }

    /// A send on port 1 failed and its link is gone: the loop closes now,
    /// not at the next periodic check.
    fn lost(&mut self) {
        self.up = false;
        self.lost = true;
        self.checked = Some(Instant::now());
    }

    /// Whether [`PortWatch::lost`] closed the port since the last call.
    fn take_lost(&mut self) -> bool {
        std::mem::take(&mut self.lost)
    }

    /// Checks the link when due; returns the new state when it changed
    /// (or on the first check).
    fn poll(&mut self) -> Option<bool> {
        let name = self.name.as_ref()?;
        if self
            .checked
            .is_some_and(|t| t.elapsed() < Duration::from_millis(100))
        {
            return None;
        }
        let first = self.checked.is_none();
        self.checked = Some(Instant::now());
        let up = pnet_datalink::interfaces()
            .iter()
            .find(|i| &i.name == name)
            .is_some_and(|i| i.is_up() && i.is_running());
        let changed = up != self.up || first;
        self.up = up;
        changed.then_some(up)
    }
}

/// Whether interface `name` is down or has no carrier (or is gone).
fn link_is_down(name: &str) -> bool {
    !pnet_datalink::interfaces()
        .iter()
        .any(|i| i.name == name && i.is_up() && i.is_running())
}

/// Port 1 of the line's last slave has a link when frames go on to a next
/// runner (DL status shows it; the loop is closed there otherwise).
fn set_last_port1(chain: &mut Chain, up: bool) {
    if let Some(last) = chain.slaves_mut().last_mut() {
        last.set_port1_link(up);
    }
}

fn find_interface(name: &str) -> Result<NetworkInterface, RunnerError> {
    let all = pnet_datalink::interfaces();
    all.iter()
        .find(|i| i.name == name)
        .cloned()
        .ok_or_else(|| RunnerError::NoSuchInterface {
            name: name.to_string(),
            available: all
                .iter()
                .map(|i| i.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })
}

fn io_err(context: String) -> impl FnOnce(io::Error) -> RunnerError {
    move |source| RunnerError::Io { context, source }
}

fn slave_dir(dir: &Path, i: usize) -> PathBuf {
    dir.join(format!("slave-{i}"))
}

/// Slaves whose parameter storage (`slave-N/params-*.bin`, see
/// [`crate::state_dir`]) and firmware store (`slave-N/firmware/`) live
/// under `dir`. A blank firmware store gets the factory firmware; a store
/// whose boot records were lost is an error, not a silent downgrade to the
/// factory version. Damaged parameter storage is loaded as such: the device
/// reports its EEPROM data error.
pub fn persistent_chain(
    dir: &Path,
    slaves: Vec<Box<dyn LineSlave>>,
) -> Result<(Chain, Vec<SlaveState>), RunnerError> {
    persistent_chain_with(dir, slaves, IMAGE_SLOT_CAPACITY)
}

/// [`persistent_chain`] with firmware slots of `image_slot_capacity`
/// bytes.
pub fn persistent_chain_with(
    dir: &Path,
    mut slaves: Vec<Box<dyn LineSlave>>,
    image_slot_capacity: usize,
) -> Result<(Chain, Vec<SlaveState>), RunnerError> {
    let mut stores: Vec<Box<dyn ImageStore + Send>> = Vec::with_capacity(slaves.len());
    let mut states = Vec::with_capacity(slaves.len());
    for (i, slave) in slaves.iter_mut().enumerate() {
        let sd = slave_dir(dir, i);
        let fw_dir = sd.join("firmware");
        std::fs::create_dir_all(&fw_dir)
            .map_err(io_err(format!("creating {}", fw_dir.display())))?;
        let mut store = FileStore::open(&fw_dir, image_slot_capacity).map_err(io_err(format!(
            "opening firmware store {}",
            fw_dir.display()
        )))?;
        if store.read_state().is_err() && store.has_been_written() {
            return Err(RunnerError::LostBootState(fw_dir));
        }
        let _ = provision_factory(&mut store);
        stores.push(Box::new(store));
        let mut state =
            SlaveState::open(&sd).map_err(io_err(format!("opening {}", sd.display())))?;
        if let Some(nv) = slave.nv_mut() {
            let loaded = state.load(nv).map_err(io_err(format!(
                "reading the parameters in {}",
                sd.display()
            )))?;
            if let Loaded::Damaged(regions) = &loaded {
                eprintln!(
                    "warning: slave {i}: parameter storage in {} damaged (regions {regions:?}); \
                     the device reports an EEPROM data error unless its other copy is valid",
                    sd.display()
                );
            }
            if loaded != Loaded::Blank {
                // Restart with the loaded EEPROM so the parameters apply.
                slave.power_cycle();
            }
        }
        states.push(state);
    }
    Ok((Chain::with_stores(slaves, stores), states))
}

/// Writes the parameter storage of every slave whose EEPROM changed,
/// durably ([`SlaveState::persist`]).
fn persist_parameters(chain: &Chain, states: &mut [SlaveState]) -> Result<(), RunnerError> {
    for (s, state) in chain.slaves().iter().zip(states.iter_mut()) {
        if let Some(nv) = s.nv() {
            state.persist(nv).map_err(io_err(format!(
                "writing the parameters in {}",
                state.dir().display()
            )))?;
        }
    }
    Ok(())
}

/// Whether `frame` is an EtherCAT frame from a master (not yet processed
/// by any slave).
pub fn is_request(frame: &[u8]) -> bool {
    is_ethercat(frame) && frame.get(6).is_some_and(|b| b & 0x02 == 0)
}

/// Whether `frame` is an EtherCAT frame a slave has processed (source MAC
/// with the locally administered bit set): a reply on its way back.
pub fn is_processed(frame: &[u8]) -> bool {
    is_ethercat(frame) && frame.get(6).is_some_and(|b| b & 0x02 != 0)
}

fn is_ethercat(frame: &[u8]) -> bool {
    frame.len() >= 16 && frame.get(12..14) == Some(&[0x88, 0xA4][..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_unprocessed_ethercat_frames_are_requests() {
        let mut f = vec![0u8; 60];
        f[6] = 0x10;
        f[12] = 0x88;
        f[13] = 0xA4;
        assert!(is_request(&f));
        f[6] = 0x12;
        assert!(!is_request(&f), "our own reply");
        f[6] = 0x10;
        f[12] = 0x08;
        f[13] = 0x00;
        assert!(!is_request(&f), "IPv4");
        assert!(!is_request(&f[..10]));
    }

    #[test]
    fn state_dir_keeps_saved_parameters_and_the_firmware_store_across_restarts() {
        use crate::testing::{TestApp, line};
        let dir = std::env::temp_dir().join(format!("ecat-state-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let slaves = || -> Vec<Box<dyn LineSlave>> {
            (0..2)
                .map(|_| Box::new(crate::testing::slave()) as Box<dyn LineSlave>)
                .collect()
        };
        {
            let (mut chain, mut states) = persistent_chain(&dir, slaves()).unwrap();
            assert_eq!(chain.slaves()[1].firmware_version(), "10");
            let s = chain.slave_mut::<TestApp>(1).unwrap().slave_mut();
            s.od_mut().set(0x8000, 1, 777);
            let (app, od) = s.app_and_od();
            ecat_slave::params::save(od, &mut app.nv).unwrap();
            persist_parameters(&chain, &mut states).unwrap();
        }
        assert!(dir.join("slave-1/params-0.bin").exists());
        assert!(dir.join("slave-1/params-1.bin").exists());
        assert!(!dir.join("slave-0/params-0.bin").exists(), "never saved");
        assert!(dir.join("slave-1/firmware").is_dir());
        let (chain, _) = persistent_chain(&dir, slaves()).unwrap();
        assert_eq!(chain.slaves()[1].od().get(0x8000, 1), Some(777), "restored");
        assert_eq!(
            chain.slaves()[0].od().get(0x8000, 1),
            Some(100),
            "untouched"
        );
        assert_eq!(chain.slaves()[0].firmware_version(), "10");
        let _ = line(1);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn lost_firmware_boot_records_are_an_error_not_a_silent_factory_reflash() {
        let dir = std::env::temp_dir().join(format!("ecat-lost-boot-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let one = || -> Vec<Box<dyn LineSlave>> { vec![Box::new(crate::testing::slave())] };
        drop(persistent_chain(&dir, one()).unwrap());
        let fw = dir.join("slave-0/firmware");
        std::fs::remove_file(fw.join("state_0.bin")).unwrap();
        let _ = std::fs::remove_file(fw.join("state_1.bin"));
        let err = persistent_chain(&dir, one()).map(|_| ()).unwrap_err();
        assert!(matches!(err, RunnerError::LostBootState(_)), "{err}");
        assert!(err.to_string().contains("refusing to fall back"), "{err}");
        // Removing the store is the explicit way back to the factory image.
        std::fs::remove_dir_all(&fw).unwrap();
        let (chain, _) = persistent_chain(&dir, one()).unwrap();
        assert_eq!(chain.slaves()[0].firmware_version(), "10");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_firmware_store_has_the_configured_slot_capacity() {
        let dir = std::env::temp_dir().join(format!("ecat-capacity-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let one = || -> Vec<Box<dyn LineSlave>> { vec![Box::new(crate::testing::slave())] };
        let (chain, _) = persistent_chain_with(&dir, one(), 64 * 1024).unwrap();
        assert_eq!(chain.image_store(0).unwrap().slot_capacity(), 64 * 1024);
        assert_eq!(chain.slaves()[0].firmware_version(), "10");
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(
            RunnerConfig::new("x").image_slot_capacity,
            IMAGE_SLOT_CAPACITY
        );
    }

    #[test]
    fn unknown_interface_is_named_in_the_error() {
        let cfg = RunnerConfig::new("no-such-if0");
        let one: Vec<Box<dyn LineSlave>> = vec![Box::new(crate::testing::slave())];
        let err = run(&cfg, one, &AtomicBool::new(false)).unwrap_err();
        assert!(err.to_string().contains("no-such-if0"), "{err}");
        let err = run(&cfg, Vec::new(), &AtomicBool::new(false)).unwrap_err();
        assert!(err.to_string().contains("1 to 4096"), "{err}");
    }
}
