//! When a cyclic master's next frame is due: the runner measures the
//! period of the master's cycles from the frames' arrival times and waits
//! for the next cycle's first frame by polling the socket (no thread
//! wake-up on its arrival) in a short window around the time it is due,
//! and keeps the firmware's idle work out of that window.
//!
//! A cycle starts with a frame that follows a quiet gap of at least
//! [`CYCLE_GAP_NS`]; the frames a master sends within one cycle (SOEM's
//! and ethercrab's process data and mailbox frames, each sent when the
//! previous came back) belong to it. The period is a moving average of
//! the cycle starts' intervals, its jitter a moving average of the
//! deviations (as TCP estimates a round trip time, RFC 6298). A master
//! whose jitter exceeds an eighth of its period, or whose period is
//! outside [`MIN_PERIOD_NS`]..=[`MAX_PERIOD_NS`], is not treated as cyclic:
//! no window, the runner just blocks.

/// Shortest quiet time before a frame that starts a new cycle.
pub const CYCLE_GAP_NS: u64 = 50_000;

/// Shortest cycle period given a window (10 kHz: 100 µs).
pub const MIN_PERIOD_NS: u64 = 100_000;

/// Longest cycle period given a window (10 Hz).
pub const MAX_PERIOD_NS: u64 = 100_000_000;

/// Cycle intervals measured before a window is given.
const WARM_UP: u32 = 4;

/// Widest window on each side of the expected time, as a share of the
/// period: the polling costs at most a fifth of a core.
const WINDOW_SHARE: u64 = 10;

/// Margin added on each side of the window beyond twice the jitter.
const WINDOW_MARGIN_NS: u64 = 10_000;

/// Longest time after the expected frame that a timer keeps clear of it
/// ([`Window::clear`]).
pub const CLEAR_AFTER_NS: u64 = 500_000;

/// The measured cycle of a master (all times in ns on one clock).
#[derive(Debug, Clone, Default)]
pub struct CycleWatch {
    last_arrival: Option<u64>,
    last_start: Option<u64>,
    /// Average period; 0 before the first interval.
    period: u64,
    /// Average deviation of an interval from `period`.
    jitter: u64,
    intervals: u32,
}

/// Where to look for the next cycle's first frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    /// Start polling from here.
    pub from: u64,
    /// The frame is expected here.
    pub expected: u64,
    /// Stop polling here (the frame is late or the master stopped).
    pub until: u64,
    /// The earliest time after the window at which a timer of the runner
    /// (its idle firmware run) does not meet the frame's round trip or
    /// the work right after it: half a period after the expected time, at
    /// most [`CLEAR_AFTER_NS`], never before `until`. A timer at `until`
    /// fires just after a frame that came in time, often while it is
    /// being answered or the master takes the answer.
    pub clear: u64,
}

impl CycleWatch {
    /// A watch that has seen no frame.
    pub fn new() -> Self {
        Self::default()
    }

    /// A master's frame arrived at `t`.
    pub fn arrival(&mut self, t: u64) {
        let starts_cycle = self
            .last_arrival
            .is_none_or(|a| t.saturating_sub(a) >= CYCLE_GAP_NS);
        self.last_arrival = Some(t);
        if !starts_cycle {
            return;
        }
        if let Some(s) = self.last_start {
            let sample = t.saturating_sub(s);
            if self.intervals == 0 {
                self.period = sample;
                self.jitter = sample / 2;
            } else {
                let dev = sample.abs_diff(self.period);
                // period += (sample - period) / 8; jitter += (dev - jitter) / 4
                self.period = self.period - self.period / 8 + sample / 8;
                self.jitter = self.jitter - self.jitter / 4 + dev / 4;
            }
            self.intervals = self.intervals.saturating_add(1);
        }
        self.last_start = Some(t);
    }

    /// The measured period, once the master looks cyclic.
    pub fn period(&self) -> Option<u64> {
        let cyclic = self.intervals >= WARM_UP
            && (MIN_PERIOD_NS..=MAX_PERIOD_NS).contains(&self.period)
            && self.jitter <= self.period / 8;
        cyclic.then_some(self.period)
    }

    /// The window of the next cycle's first frame, if the master is
    /// cyclic: twice the jitter plus a margin on each side of the expected
    /// time, at most a tenth of the period each.
    pub fn window(&self) -> Option<Window> {
        let period = self.period()?;
        let expected = self.last_start?.saturating_add(period);
        let half = (2 * self.jitter + WINDOW_MARGIN_NS).min(period / WINDOW_SHARE);
        let until = expected.saturating_add(half);
        Some(Window {
            from: expected.saturating_sub(half),
            expected,
            until,
            clear: expected
                .saturating_add((period / 2).min(CLEAR_AFTER_NS))
                .max(until),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;
    const US: u64 = 1_000;

    fn fed(arrivals: impl IntoIterator<Item = u64>) -> CycleWatch {
        let mut w = CycleWatch::new();
        for t in arrivals {
            w.arrival(t);
        }
        w
    }

    #[test]
    fn a_1_khz_master_gets_a_narrow_window_around_its_next_frame() {
        let w = fed((0..20).map(|k| k * MS));
        let win = w.window().expect("cyclic");
        assert_eq!(win.expected, 20 * MS);
        assert!(win.from < win.expected && win.until > win.expected);
        // Within a tenth of the period on each side.
        assert!(win.expected - win.from <= 100 * US, "{win:?}");
        assert!(win.until - win.expected <= 100 * US, "{win:?}");
    }

    #[test]
    fn timers_keep_clear_of_the_frame_for_half_a_period_at_most_500_us() {
        let at_1_khz = fed((0..20).map(|k| k * MS)).window().expect("cyclic");
        assert_eq!(at_1_khz.clear, 20 * MS + 500 * US);
        let at_4_khz = fed((0..20).map(|k| k * 250 * US)).window().expect("cyclic");
        assert_eq!(at_4_khz.clear, 20 * 250 * US + 125 * US);
        // A slow, jittery master's window reaches further than that.
        let at_20_hz = fed((0..20).map(|k| k * 50 * MS + (k % 2) * 2 * MS))
            .window()
            .expect("cyclic");
        assert!(
            at_20_hz.until > at_20_hz.expected + 500 * US,
            "{at_20_hz:?}"
        );
        assert_eq!(at_20_hz.clear, at_20_hz.until);
    }

    #[test]
    fn frames_within_a_cycle_do_not_shorten_the_period() {
        // Three frames per cycle, 20 µs apart, every 250 µs (4 kHz).
        let w =
            fed((0..40)
                .flat_map(|k| [k * 250 * US, k * 250 * US + 20 * US, k * 250 * US + 40 * US]));
        assert_eq!(w.period(), Some(250 * US));
        assert_eq!(w.window().expect("cyclic").expected, 40 * 250 * US);
    }

    #[test]
    fn back_to_back_traffic_is_not_cyclic() {
        // A frame every 30 µs: one endless cycle.
        let w = fed((0..1000).map(|k| k * 30 * US));
        assert_eq!(w.period(), None);
        assert_eq!(w.window(), None);
    }

    #[test]
    fn a_master_with_irregular_gaps_gets_no_window() {
        let gaps = [1, 7, 2, 9, 1, 5, 3, 8, 2, 6, 1, 9];
        let mut t = 0;
        let w = fed(gaps.iter().map(|g| {
            t += g * MS;
            t
        }));
        assert_eq!(w.window(), None);
    }

    #[test]
    fn too_few_cycles_or_too_slow_a_master_get_no_window() {
        assert_eq!(fed([0, MS, 2 * MS]).window(), None);
        assert_eq!(fed((0..10).map(|k| k * 200 * MS)).window(), None);
    }

    #[test]
    fn jitter_widens_the_window_up_to_a_tenth_of_the_period() {
        let steady = fed((0..30).map(|k| k * MS)).window().expect("cyclic");
        let jittery = fed((0..30).map(|k| k * MS + (k % 2) * 40 * US))
            .window()
            .expect("cyclic");
        let width = |w: Window| w.until - w.from;
        assert!(width(jittery) > width(steady), "{jittery:?} {steady:?}");
        assert!(width(jittery) <= 200 * US);
    }

    #[test]
    fn any_arrival_times_never_panic() {
        let mut w = CycleWatch::new();
        for t in [u64::MAX, 0, u64::MAX / 2, 1, u64::MAX, u64::MAX] {
            w.arrival(t);
            let _ = w.window();
        }
    }
}
