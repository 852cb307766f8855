//! When a board's main loop runs the firmware: the IRQ entry point.
//!
//! An ESC drives its IRQ output while an AL event it is told to signal
//! (0x0220 AND the AL event mask 0x0204) is pending: AL control written, a
//! mailbox or process-data SyncManager buffer written or read, the
//! process-data watchdog expired (ET1100 Section I, "Interrupts"). A board
//! that wires the IRQ line runs a firmware pass ([`Slave::poll`]) as soon
//! as the line is asserted, and otherwise only at a slow idle period for
//! the application's own timing and the firmware's backstop checks; the
//! SPI bus stays quiet in between. A board without the line polls at the
//! idle period alone (or faster, at the cost of SPI traffic).
//!
//! [`Slave::poll`]: super::Slave::poll

/// Decides, turn by turn of a main loop, whether a firmware pass is due.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PollSchedule {
    idle_ns: u64,
    last_ns: Option<u64>,
}

impl PollSchedule {
    /// A schedule running the firmware on every asserted IRQ and at least
    /// every `idle_ns` (the first turn always runs it).
    pub const fn new(idle_ns: u64) -> Self {
        PollSchedule {
            idle_ns,
            last_ns: None,
        }
    }

    /// Whether the firmware runs at `now_ns` with the IRQ line asserted or
    /// not; a `true` answer counts as the pass having run then. An IRQ
    /// line the board cannot read should be passed as asserted (poll
    /// rather than miss an event).
    pub fn due(&mut self, irq_asserted: bool, now_ns: u64) -> bool {
        let idle = self
            .last_ns
            .is_none_or(|t| now_ns.saturating_sub(t) >= self.idle_ns);
        if irq_asserted || idle {
            self.last_ns = Some(now_ns);
            true
        } else {
            false
        }
    }

    /// The idle period in ns.
    pub fn idle_ns(&self) -> u64 {
        self.idle_ns
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quiet_irq_line_runs_the_firmware_once_per_idle_period() {
        let mut s = PollSchedule::new(1_000);
        let runs = (0..10_000u64)
            .step_by(100)
            .filter(|&t| s.due(false, t))
            .count();
        assert_eq!(runs, 10, "t = 0, 1000, ..., 9000");
    }

    #[test]
    fn an_asserted_irq_runs_the_firmware_at_once_and_restarts_the_idle_period() {
        let mut s = PollSchedule::new(1_000);
        assert!(s.due(false, 0), "the first turn runs");
        assert!(!s.due(false, 500));
        assert!(s.due(true, 600), "IRQ: at once");
        assert!(!s.due(false, 1_500), "idle period counts from the IRQ pass");
        assert!(s.due(false, 1_600));
    }

    #[test]
    fn time_going_backwards_does_not_stop_the_schedule() {
        let mut s = PollSchedule::new(1_000);
        assert!(s.due(false, 5_000));
        assert!(
            !s.due(false, 10),
            "a clock that jumped back waits, saturating"
        );
        assert!(s.due(true, 10), "but an IRQ still runs it");
    }
}
