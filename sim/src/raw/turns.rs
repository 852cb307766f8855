//! When the runner gives the slaves' firmware its turn between frames.
//!
//! The ESCs answer every frame at once; the firmware runs afterwards, once
//! no frame waits, and stops for the next frame
//! ([`Chain::service_until`](crate::chain::Chain::service_until)). Two
//! rules keep it from being left out: without frames it runs every
//! [`IDLE_TICK`] (the sweep's turns, SM watchdog supervision), and work
//! that has waited [`STARVE_AFTER`] while frames kept coming without a gap
//! (a flood) runs after the frame just answered, one step per frame until
//! it is done (a run looks for a waiting frame only `CHECK_EVERY` after it
//! started, so it takes at least one step).

use std::time::{Duration, Instant};

/// Longest time the runner waits for a frame before the firmware runs on
/// its own (the sweep's turns, SM watchdog supervision).
pub(super) const IDLE_TICK: Duration = Duration::from_millis(1);

/// Longest time firmware work waits while frames keep coming without a
/// gap: then it runs after the frame just answered.
pub(super) const STARVE_AFTER: Duration = Duration::from_millis(1);

/// The firmware's schedule (all times on the runner's monotonic clock).
#[derive(Debug, Clone)]
pub(super) struct FirmwareTurns {
    /// Since when firmware work has been left to do (a frame raised it,
    /// or a run stopped for a frame before it was done).
    work_since: Option<Instant>,
    /// When the firmware runs next without a frame.
    next_idle: Instant,
    /// How long the last idle run took.
    idle_took: Duration,
}

impl FirmwareTurns {
    /// Nothing to do yet; the first idle run one [`IDLE_TICK`] after `now`.
    pub(super) fn new(now: Instant) -> Self {
        Self {
            work_since: None,
            next_idle: now + IDLE_TICK,
            idle_took: Duration::ZERO,
        }
    }

    /// A frame arrived at `now`: the ESCs may have raised work.
    pub(super) fn frame_arrived(&mut self, now: Instant) {
        self.work_since.get_or_insert(now);
    }

    /// Right after a frame was answered: whether the firmware runs now,
    /// although more frames may wait (its work has waited
    /// [`STARVE_AFTER`]).
    pub(super) fn starved(&self, now: Instant) -> bool {
        self.work_since
            .is_some_and(|t| now.saturating_duration_since(t) >= STARVE_AFTER)
    }

    /// No frame waits: whether the firmware runs now (work is left, or
    /// the idle run is due).
    pub(super) fn due(&self, now: Instant) -> bool {
        self.work_since.is_some() || now >= self.next_idle
    }

    /// When the firmware runs next without a frame.
    pub(super) fn next_idle(&self) -> Instant {
        self.next_idle
    }

    /// How long the last idle run took (an idle run starts at least that
    /// long before a window it must keep out of).
    pub(super) fn idle_took(&self) -> Duration {
        self.idle_took
    }

    /// Moves the next idle run to `at` (out of a cyclic master's window).
    pub(super) fn postpone_idle(&mut self, at: Instant) {
        self.next_idle = at;
    }

    /// A firmware run that started at `started` ended at `now`; `stopped`:
    /// it stopped for a waiting frame and left work (which keeps the time
    /// it has waited since).
    pub(super) fn ran(&mut self, started: Instant, now: Instant, stopped: bool) {
        if stopped {
            self.work_since.get_or_insert(started);
            return;
        }
        self.work_since = None;
        if started >= self.next_idle {
            self.idle_took = now.saturating_duration_since(started);
        }
        self.next_idle = now + IDLE_TICK;
    }
}

/// A yield after a reply that took longer than this let other work run,
/// not only the master taking the reply: the machine is busy.
pub(super) const YIELD_TOO_LONG: Duration = Duration::from_micros(200);

/// How long the runner stops yielding after a yield took too long.
pub(super) const YIELD_PAUSE: Duration = Duration::from_secs(1);

/// Whether the runner yields the CPU right after a reply it answered
/// ahead, before its own work on the frame ([`super::run`]).
///
/// The reply wakes the master on the runner's CPU, most often, and the
/// master usually preempts the runner within the send, but not always:
/// measured over veth at 1 kHz (the latency bench with timestamps on both
/// sides, 5 000 frames per case), 1.4-5 % of the replies reached the
/// master only after the runner's send returned, and then only once the
/// runner's work on the frame had ended, 35-145 µs later (the longer, the
/// more slaves): most of the runner's p99 over the floor's. With a yield
/// none of 5 000 did at 1 and 8 slaves, 3 at 64. On a busy machine a
/// yield hands the CPU to whatever else runs there for a whole time
/// slice, and the runner's work, and the next frame, wait: two yields in
/// a row that took longer than [`YIELD_TOO_LONG`] stop the yielding for
/// [`YIELD_PAUSE`]. (One alone does not: on an idle VM about one round
/// trip in a thousand takes that long for reasons of the host's, and a
/// pause after each took the yield away for much of a run.)
#[derive(Debug, Clone, Default)]
pub(super) struct YieldAfterReply {
    paused_until: Option<Instant>,
    /// Yields in a row that took too long.
    too_long: u8,
    /// Pauses so far.
    pauses: u64,
}

impl YieldAfterReply {
    /// Whether to yield now.
    pub(super) fn due(&self, now: Instant) -> bool {
        self.paused_until.is_none_or(|t| now >= t)
    }

    /// A yield that started at `started` returned at `now`.
    pub(super) fn yielded(&mut self, started: Instant, now: Instant) {
        if now.saturating_duration_since(started) <= YIELD_TOO_LONG {
            self.too_long = 0;
            return;
        }
        self.too_long += 1;
        if self.too_long >= 2 {
            self.too_long = 0;
            self.paused_until = Some(now + YIELD_PAUSE);
            self.pauses += 1;
        }
    }

    /// How often the yielding was paused.
    pub(super) fn pauses(&self) -> u64 {
        self.pauses
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_yields_in_a_row_that_let_other_work_run_pause_the_yielding_for_a_second() {
        let t0 = Instant::now();
        let mut y = YieldAfterReply::default();
        assert!(y.due(t0));
        // The master took the reply: 15 µs.
        y.yielded(t0, t0 + 15 * US);
        assert!(y.due(t0 + 20 * US));
        // One slow round trip between fast ones: the host, not the load.
        let slow = 3 * YIELD_TOO_LONG;
        y.yielded(t0 + 20 * US, t0 + 20 * US + slow);
        y.yielded(t0 + 1000 * US, t0 + 1010 * US);
        y.yielded(t0 + 2000 * US, t0 + 2000 * US + slow);
        y.yielded(t0 + 3000 * US, t0 + 3010 * US);
        assert!(y.due(t0 + 3020 * US));
        assert_eq!(y.pauses(), 0);
        // A busy machine: every yield comes back after a time slice.
        y.yielded(t0 + 3500 * US, t0 + 3500 * US + slow);
        let back = t0 + 4000 * US + slow;
        y.yielded(t0 + 4000 * US, back);
        assert!(!y.due(back));
        assert_eq!(y.pauses(), 1);
        assert!(!y.due(back + YIELD_PAUSE - US));
        assert!(y.due(back + YIELD_PAUSE), "tried again after the pause");
    }

    const US: Duration = Duration::from_micros(1);

    #[test]
    fn a_flood_of_frames_leaves_the_firmware_a_step_after_each_frame_once_its_work_waited_1_ms() {
        let t0 = Instant::now();
        let mut turns = FirmwareTurns::new(t0);
        // Frames back to back every 20 us for 5 ms: the queue never
        // empties, so the firmware only runs when starved, one step each
        // time (a run always stops for the next frame); 40 steps of work.
        let mut left = 40;
        let mut first_turn = None;
        for k in 0..250u32 {
            let now = t0 + k * 20 * US;
            turns.frame_arrived(now);
            assert!(turns.due(now), "frames raised work");
            if turns.starved(now) && left > 0 {
                first_turn.get_or_insert(now);
                left -= 1;
                turns.ran(now, now + US, left > 0);
            }
        }
        let first = first_turn.expect("the firmware got a turn during the flood");
        assert!(
            first - t0 >= STARVE_AFTER,
            "not before its work waited 1 ms"
        );
        assert!(
            first - t0 <= STARVE_AFTER + 20 * US,
            "at the first frame after that"
        );
        assert_eq!(
            left, 0,
            "a step after every frame from then on: 40 steps in 0.8 ms"
        );
    }

    #[test]
    fn a_finished_run_clears_the_work_and_sets_the_next_idle_run_a_tick_later() {
        let t0 = Instant::now();
        let mut turns = FirmwareTurns::new(t0);
        assert!(!turns.due(t0), "nothing to do, idle run not yet due");
        assert!(turns.due(t0 + IDLE_TICK), "the idle run after a tick");
        turns.frame_arrived(t0 + 10 * US);
        assert!(turns.due(t0 + 11 * US));
        assert!(!turns.starved(t0 + 11 * US), "a frame's work is fresh");
        turns.ran(t0 + 12 * US, t0 + 30 * US, false);
        assert!(!turns.due(t0 + 31 * US), "done");
        assert_eq!(turns.next_idle(), t0 + 30 * US + IDLE_TICK);
        // An idle run (started at or after its time) measures itself.
        let idle_at = turns.next_idle();
        turns.ran(idle_at, idle_at + 7 * US, false);
        assert_eq!(turns.idle_took(), 7 * US);
    }

    #[test]
    fn a_run_stopped_by_a_frame_keeps_the_time_its_work_has_waited() {
        let t0 = Instant::now();
        let mut turns = FirmwareTurns::new(t0);
        turns.frame_arrived(t0);
        turns.ran(t0 + 600 * US, t0 + 605 * US, true);
        turns.frame_arrived(t0 + 700 * US);
        assert!(!turns.starved(t0 + 900 * US));
        assert!(
            turns.starved(t0 + STARVE_AFTER),
            "counted from the first frame, not the run"
        );
    }
}
