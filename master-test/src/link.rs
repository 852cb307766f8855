//! The virtual EtherCAT link: every frame ethercrab sends passes through a
//! chain of software slaves, in order, and comes back to ethercrab.
//!
//! No sockets and no root: a thread takes frames from ethercrab's
//! [`PduTx`], runs them through [`Chain::process`] and hands the result to
//! [`PduRx`]. The slaves' firmware is polled after every frame and at least
//! every millisecond, with time from a [`Clock`] the test controls.
//!
//! With a [`FaultInjector`] the link is a bad wire: frames are dropped
//! (before or after the slaves), corrupted (the first slave counts an
//! invalid frame, nobody acts on it), duplicated, delayed, reordered, or
//! lost while the link is down (see [`ecat_sim::faults`]).

pub use ecat_sim::chain::Chain;
pub use ecat_sim::faults::{Fate, FaultConfig, FaultInjector, FaultStats};
use ecat_sim::pcap::PcapWriter;
use ethercrab::{PduRx, PduTx};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::task::{Wake, Waker};
use std::thread::{self, JoinHandle, Thread};
use std::time::{Duration, Instant};

/// Where the slaves' time comes from.
#[derive(Debug, Clone)]
pub enum Clock {
    /// Real time since the link started.
    Real(Instant),
    /// Simulated time in nanoseconds, advanced only by the test.
    Simulated(Arc<AtomicU64>),
    /// Simulated time in nanoseconds that the test advances and that every
    /// frame on the wire advances by `step_ns`: the slaves' time follows
    /// the traffic, not the machine, so a test runs the same on an idle
    /// and on a loaded machine ([`Clock::frames`]).
    Frames {
        /// The time now.
        now: Arc<AtomicU64>,
        /// What one frame costs, ns.
        step_ns: u64,
        /// Whether [`Clock::sleep`] also waits the time in real time (for
        /// people watching), or only moves the slaves' time on (tests).
        paced: bool,
    },
}

/// Simulated time one frame takes on a [`Clock::frames`] clock: 20 µs,
/// a short frame's trip through a line and back plus a master's
/// turn-around. A master that configures 64 slaves' DC start times one
/// after the other (4 frames each) then spends 5 ms, as on a real line;
/// the slaves' timers (SM watchdog 100 ms = 5000 frames without process
/// data) never see more time than the traffic says, whatever the machine.
pub const FRAME_STEP_NS: u64 = 20_000;

impl Clock {
    /// Real time starting now.
    pub fn real() -> Self {
        Clock::Real(Instant::now())
    }

    /// Simulated time starting at 0; advance it with [`Clock::advance`].
    pub fn simulated() -> Self {
        Clock::Simulated(Arc::new(AtomicU64::new(0)))
    }

    /// Simulated time starting at 0 that every frame advances by
    /// [`FRAME_STEP_NS`] (and [`Clock::advance`] as the test says).
    pub fn frames() -> Self {
        Clock::Frames {
            now: Arc::new(AtomicU64::new(0)),
            step_ns: FRAME_STEP_NS,
            paced: false,
        }
    }

    /// [`Clock::frames`] whose [`Clock::sleep`] also waits in real time:
    /// the slaves' time is as reproducible as in a test, and a person
    /// watching the demo sees it at the speed it claims.
    pub fn frames_paced() -> Self {
        Clock::Frames {
            now: Arc::new(AtomicU64::new(0)),
            step_ns: FRAME_STEP_NS,
            paced: true,
        }
    }

    /// Current time in nanoseconds.
    pub fn now_ns(&self) -> u64 {
        match self {
            Clock::Real(start) => u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX),
            Clock::Simulated(t) | Clock::Frames { now: t, .. } => t.load(Ordering::Acquire),
        }
    }

    /// Advances simulated time (no effect on real time).
    pub fn advance(&self, d: Duration) {
        if let Clock::Simulated(t) | Clock::Frames { now: t, .. } = self {
            let ns = u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
            t.fetch_add(ns, Ordering::AcqRel);
        }
    }

    /// A frame passed the wire: a [`Clock::frames`] clock advances by its
    /// step; the others do not change.
    pub fn frame_passed(&self) {
        if let Clock::Frames { now, step_ns, .. } = self {
            now.fetch_add(*step_ns, Ordering::AcqRel);
        }
    }

    /// Whether the time is simulated (does not follow the machine's clock).
    pub fn is_simulated(&self) -> bool {
        !matches!(self, Clock::Real(_))
    }

    /// [`Clock::now_ns`] as a duration since the clock started.
    pub fn elapsed(&self) -> Duration {
        Duration::from_nanos(self.now_ns())
    }

    /// A master's wait of `d` in this clock's time: real time sleeps; a
    /// simulated clock moves on by `d` at once and the task yields, so the
    /// slaves see the time pass however long the machine takes.
    pub async fn sleep(&self, d: Duration) {
        match self {
            Clock::Real(_) => {
                smol::Timer::after(d).await;
            }
            Clock::Frames { paced: true, .. } => {
                self.advance(d);
                smol::Timer::after(d).await;
            }
            Clock::Simulated(_) | Clock::Frames { .. } => {
                self.advance(d);
                smol::future::yield_now().await;
            }
        }
    }
}

impl Default for Clock {
    /// Real time starting now.
    fn default() -> Self {
        Clock::real()
    }
}

/// A chain shared between the link thread and the test.
pub type SharedChain = Arc<Mutex<Chain>>;

/// A fault injector shared between the link thread and the test.
pub type SharedFaults = Arc<Mutex<FaultInjector>>;

/// Locks the fault injector (recovering from a poisoned lock).
pub fn lock_faults(f: &SharedFaults) -> MutexGuard<'_, FaultInjector> {
    f.lock().unwrap_or_else(|e| e.into_inner())
}

/// Locks a shared chain, recovering it if a panicking test poisoned it.
pub fn lock(chain: &SharedChain) -> MutexGuard<'_, Chain> {
    chain.lock().unwrap_or_else(|e| e.into_inner())
}

struct ThreadWaker(Thread);

impl Wake for ThreadWaker {
    fn wake(self: Arc<Self>) {
        self.0.unpark();
    }
    fn wake_by_ref(self: &Arc<Self>) {
        self.0.unpark();
    }
}

/// The running link thread; stops when dropped.
pub struct Link {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Link {
    /// Starts the link thread between ethercrab's `tx`/`rx` and `chain`;
    /// with `pcap`, every frame is captured in both directions.
    pub fn spawn(
        tx: PduTx<'static>,
        rx: PduRx<'static>,
        chain: SharedChain,
        clock: Clock,
        pcap: Option<PcapWriter<std::io::BufWriter<std::fs::File>>>,
    ) -> std::io::Result<Self> {
        Self::spawn_with_faults(tx, rx, chain, clock, pcap, None)
    }

    /// [`Link::spawn`] through the faulty wire `faults`.
    pub fn spawn_with_faults(
        mut tx: PduTx<'static>,
        mut rx: PduRx<'static>,
        chain: SharedChain,
        clock: Clock,
        mut pcap: Option<PcapWriter<std::io::BufWriter<std::fs::File>>>,
        faults: Option<SharedFaults>,
    ) -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let stop2 = stop.clone();
        let thread = thread::Builder::new()
            .name("ecat-virtual-link".into())
            .spawn(move || {
                let waker = Waker::from(Arc::new(ThreadWaker(thread::current())));
                let mut buf: Vec<u8> = Vec::with_capacity(1536);
                let start_ns = clock.now_ns();
                // Replies held back: (release time, frame).
                let mut delayed: Vec<(Instant, Vec<u8>)> = Vec::new();
                let mut reordered: Option<(Instant, Vec<u8>)> = None;
                let mut was_down = false;
                let mut last_frame = Instant::now();
                // The slaves' time of the passes between frames. A
                // `Clock::frames` clock moves for the slaves with the
                // traffic: between frames they run at the last frame's
                // time, so whether such a pass sees an `advance` of the
                // test before the next frame does not depend on how the
                // machine schedules this thread (a drive ticking on that
                // early pass would take the next target a cycle late).
                let frames_clock = matches!(clock, Clock::Frames { .. });
                let mut frame_ns = clock.now_ns();
                let between_frames = |clock: &Clock, frame_ns: u64| {
                    if frames_clock {
                        frame_ns
                    } else {
                        clock.now_ns()
                    }
                };
                while !stop2.load(Ordering::Acquire) && !tx.should_exit() {
                    tx.replace_waker(&waker);
                    let mut sent = false;
                    while let Some(frame) = tx.next_sendable_frame() {
                        buf.clear();
                        let res = frame.send_blocking(|data| {
                            buf.extend_from_slice(data);
                            Ok(data.len())
                        });
                        if res.is_err() {
                            continue;
                        }
                        sent = true;
                        if let Some(p) = pcap.as_mut() {
                            let _ = p.write_frame(&buf);
                        }
                        clock.frame_passed();
                        let now = clock.now_ns();
                        frame_ns = now;
                        let fate = faults.as_ref().map_or(Fate::Deliver, |f| {
                            lock_faults(f).fate(Duration::from_nanos(now.saturating_sub(start_ns)))
                        });
                        let down = fate == Fate::LinkDown;
                        if down && !was_down {
                            lock(&chain).link_lost();
                        }
                        was_down = down;
                        match fate {
                            Fate::DropBefore | Fate::LinkDown => {
                                // The slaves keep running on their own.
                                let _ = lock(&chain).service(now);
                                continue;
                            }
                            Fate::Corrupt => {
                                let mut c = lock(&chain);
                                c.corrupted_frame();
                                let _ = c.service(now);
                                continue;
                            }
                            _ => {}
                        }
                        let request = (fate == Fate::Duplicate).then(|| buf.clone());
                        lock(&chain).process(&mut buf, now);
                        if let Some(p) = pcap.as_mut() {
                            let _ = p.write_frame(&buf);
                        }
                        match fate {
                            Fate::DropAfter => {}
                            Fate::Delay(d) => delayed.push((Instant::now() + d, buf.clone())),
                            Fate::Reorder => {
                                let held = (Instant::now() + REORDER_HOLD, buf.clone());
                                if let Some((_, older)) = reordered.replace(held) {
                                    let _ = rx.receive_frame(&older);
                                }
                            }
                            _ => {
                                // A frame ethercrab no longer waits for is
                                // dropped, as on a real wire.
                                let _ = rx.receive_frame(&buf);
                                if let Some(mut again) = request {
                                    lock(&chain).process(&mut again, clock.now_ns());
                                    let _ = rx.receive_frame(&again);
                                }
                                if let Some((_, r)) = reordered.take() {
                                    let _ = rx.receive_frame(&r);
                                }
                            }
                        }
                    }
                    let t = Instant::now();
                    delayed.retain(|(at, f)| {
                        let due = *at <= t;
                        if due {
                            let _ = rx.receive_frame(f);
                        }
                        !due
                    });
                    if reordered.as_ref().is_some_and(|(at, _)| *at <= t)
                        && let Some((_, r)) = reordered.take()
                    {
                        let _ = rx.receive_frame(&r);
                    }
                    if sent {
                        last_frame = Instant::now();
                    } else {
                        // PDI failures (injected faults) are handled by the
                        // slave and counted by the chain.
                        if last_frame.elapsed() < SPIN {
                            // A master that just sent a frame usually
                            // sends the next one within microseconds:
                            // waiting for it without sleeping saves the
                            // wake-up (tens of microseconds per frame).
                            let _ = lock(&chain).service(between_frames(&clock, frame_ns));
                            thread::yield_now();
                            continue;
                        }
                        let _ = lock(&chain).idle(between_frames(&clock, frame_ns));
                        let wait = if delayed.is_empty() && reordered.is_none() {
                            Duration::from_millis(1)
                        } else {
                            Duration::from_micros(100)
                        };
                        thread::park_timeout(wait);
                    }
                }
                if let Some(p) = pcap.as_mut() {
                    let _ = p.flush();
                }
            })?;
        Ok(Link {
            stop,
            thread: Some(thread),
        })
    }
}

/// How long the link thread keeps looking for the next frame without
/// sleeping after the last one.
const SPIN: Duration = Duration::from_micros(200);

/// Longest a reordered reply waits for the next frame.
const REORDER_HOLD: Duration = Duration::from_millis(5);

impl Drop for Link {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}

/// ethercrab on a network interface through a raw socket (pnet), with a
/// link thread like the virtual one: a reply nobody waits for any more
/// (late after a timeout, duplicated by the wire, another master's) is
/// dropped and the link goes on.
///
/// ethercrab's own `std::tx_rx_task` ends for good on such a frame (it
/// returns `Error::ReceiveFrame`), after which every request times out; on
/// a wire that may lose or delay a frame the master would be dead after
/// the first one. The tools and the tests use this link instead.
pub struct RawLink {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl RawLink {
    /// Opens a raw socket on `iface` and carries ethercrab's frames.
    pub fn spawn(
        iface: &str,
        mut tx: PduTx<'static>,
        mut rx: PduRx<'static>,
    ) -> std::io::Result<Self> {
        let nic = pnet_datalink::interfaces()
            .into_iter()
            .find(|i| i.name == iface)
            .ok_or_else(|| {
                std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    format!("no network interface '{iface}'"),
                )
            })?;
        let cfg = pnet_datalink::Config {
            read_timeout: Some(Duration::from_micros(200)),
            promiscuous: true,
            ..pnet_datalink::Config::default()
        };
        let (mut net_tx, mut net_rx) = match pnet_datalink::channel(&nic, cfg)? {
            pnet_datalink::Channel::Ethernet(t, r) => (t, r),
            _ => return Err(std::io::Error::other("not an Ethernet channel")),
        };
        let stop = Arc::new(AtomicBool::new(false));
        let stop2 = stop.clone();
        let thread = thread::Builder::new()
            .name(format!("ecat-raw-{iface}"))
            .spawn(move || {
                let waker = Waker::from(Arc::new(ThreadWaker(thread::current())));
                while !stop2.load(Ordering::Acquire) && !tx.should_exit() {
                    tx.replace_waker(&waker);
                    while let Some(frame) = tx.next_sendable_frame() {
                        let _ = frame.send_blocking(|data| match net_tx.send_to(data, None) {
                            Some(Err(_)) => Err(ethercrab::error::Error::SendFrame),
                            _ => Ok(data.len()),
                        });
                    }
                    if let Ok(frame) = net_rx.next() {
                        // EtherCAT frames a slave processed.
                        if ecat_sim::raw::is_processed(frame) {
                            let _ = rx.receive_frame(frame);
                        }
                    }
                }
            })?;
        Ok(RawLink {
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for RawLink {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
