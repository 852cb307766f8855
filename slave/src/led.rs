//! EtherCAT RUN and ERR LEDs (manual 4.1, ETG.1300 indicator timing) as a
//! pure function of device state and time, driven through [`Leds`].
//!
//! | pattern | timing (ETG.1300) |
//! |---|---|
//! | blinking | 200 ms on, 200 ms off |
//! | single flash | 200 ms on, 1000 ms off |
//! | double flash | 200 on, 200 off, 200 on, 1000 off |
//! | flickering | 50 ms on, 50 ms off |
//!
//! RUN: INIT off, PRE-OP blinking, SAFE-OP single flash, OP on, BOOT
//! flickering (the manual calls it "flashing"; ETG.1300 names the bootstrap
//! pattern flickering). ERR (manual 4.1): off = no error, blinking =
//! invalid configuration, single flash = unsolicited state change, double
//! flash = application (SyncManager) watchdog timeout, flickering = booting
//! error, on = PDI watchdog timeout.

use crate::al::{AlState, AlStatus, AlStatusCode};

/// An indicator pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LedPattern {
    /// Constantly off.
    Off,
    /// Constantly on.
    On,
    /// 200 ms on, 200 ms off.
    Blinking,
    /// 200 ms on, 1000 ms off.
    SingleFlash,
    /// 200 on, 200 off, 200 on, 1000 off.
    DoubleFlash,
    /// 50 ms on, 50 ms off.
    Flickering,
}

impl LedPattern {
    /// Whether the LED is lit at `t_ms` into the pattern.
    pub const fn is_on(self, t_ms: u64) -> bool {
        match self {
            LedPattern::Off => false,
            LedPattern::On => true,
            LedPattern::Blinking => t_ms % 400 < 200,
            LedPattern::SingleFlash => t_ms % 1200 < 200,
            LedPattern::DoubleFlash => {
                let p = t_ms % 1600;
                p < 200 || (p >= 400 && p < 600)
            }
            LedPattern::Flickering => t_ms % 100 < 50,
        }
    }

    /// Lower-case name as the demo prints it.
    pub const fn name(self) -> &'static str {
        match self {
            LedPattern::Off => "off",
            LedPattern::On => "on",
            LedPattern::Blinking => "blinking",
            LedPattern::SingleFlash => "single flash",
            LedPattern::DoubleFlash => "double flash",
            LedPattern::Flickering => "flickering",
        }
    }
}

/// The LEDs of a board.
pub trait Leds {
    /// Sets the RUN (green) and ERR (red) LEDs.
    fn set(&mut self, run: bool, err: bool);
}

/// The RUN LED pattern for an AL state.
pub const fn run_pattern(state: AlState) -> LedPattern {
    match state {
        AlState::Init => LedPattern::Off,
        AlState::PreOp => LedPattern::Blinking,
        AlState::SafeOp => LedPattern::SingleFlash,
        AlState::Op => LedPattern::On,
        AlState::Boot => LedPattern::Flickering,
    }
}

/// The ERR LED pattern for the AL status and the PDI watchdog.
pub fn err_pattern(al: &AlStatus, pdi_watchdog_expired: bool) -> LedPattern {
    if pdi_watchdog_expired {
        return LedPattern::On;
    }
    if !al.error {
        return LedPattern::Off;
    }
    match al.code {
        AlStatusCode::SmWatchdog => LedPattern::DoubleFlash,
        AlStatusCode::NoValidFirmware | AlStatusCode::BootNotSupported => LedPattern::Flickering,
        AlStatusCode::SyncError => LedPattern::SingleFlash,
        // A refused request or a configuration the device cannot run.
        _ => LedPattern::Blinking,
    }
}

/// Both patterns.
pub fn patterns(al: &AlStatus, pdi_watchdog_expired: bool) -> (LedPattern, LedPattern) {
    (run_pattern(al.state), err_pattern(al, pdi_watchdog_expired))
}

/// Drives `leds` for time `t_ms`.
pub fn drive(leds: &mut impl Leds, al: &AlStatus, pdi_watchdog_expired: bool, t_ms: u64) {
    let (run, err) = patterns(al, pdi_watchdog_expired);
    leds.set(run.is_on(t_ms), err.is_on(t_ms));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trace(p: LedPattern, period: u64) -> Vec<bool> {
        (0..period).step_by(50).map(|t| p.is_on(t)).collect()
    }

    #[test]
    fn run_led_follows_the_state_table() {
        assert_eq!(run_pattern(AlState::Init), LedPattern::Off);
        assert_eq!(run_pattern(AlState::PreOp), LedPattern::Blinking);
        assert_eq!(run_pattern(AlState::SafeOp), LedPattern::SingleFlash);
        assert_eq!(run_pattern(AlState::Op), LedPattern::On);
        assert_eq!(run_pattern(AlState::Boot), LedPattern::Flickering);
    }

    #[test]
    fn patterns_have_the_etg_1300_timing() {
        // Blinking: 200 on / 200 off.
        assert_eq!(
            trace(LedPattern::Blinking, 400),
            [true, true, true, true, false, false, false, false]
        );
        // Single flash: 200 on, then 1000 off.
        let sf = trace(LedPattern::SingleFlash, 1200);
        assert_eq!(sf.iter().filter(|b| **b).count(), 4);
        assert!(sf[..4].iter().all(|b| *b));
        // Double flash: on 0-200, off 200-400, on 400-600, off 600-1600.
        assert!(LedPattern::DoubleFlash.is_on(100));
        assert!(!LedPattern::DoubleFlash.is_on(300));
        assert!(LedPattern::DoubleFlash.is_on(500));
        assert!(!LedPattern::DoubleFlash.is_on(700));
        assert!(!LedPattern::DoubleFlash.is_on(1599));
        assert!(LedPattern::DoubleFlash.is_on(1600));
        // Flickering: 50/50.
        assert!(LedPattern::Flickering.is_on(10));
        assert!(!LedPattern::Flickering.is_on(60));
    }

    #[test]
    fn err_led_shows_watchdog_configuration_and_pdi_errors() {
        let ok = AlStatus {
            state: AlState::Op,
            error: false,
            code: AlStatusCode::NoError,
        };
        assert_eq!(err_pattern(&ok, false), LedPattern::Off);
        let wd = AlStatus {
            state: AlState::SafeOp,
            error: true,
            code: AlStatusCode::SmWatchdog,
        };
        assert_eq!(err_pattern(&wd, false), LedPattern::DoubleFlash);
        let cfg = AlStatus {
            state: AlState::PreOp,
            error: true,
            code: AlStatusCode::InvalidOutputConfig,
        };
        assert_eq!(err_pattern(&cfg, false), LedPattern::Blinking);
        assert_eq!(err_pattern(&ok, true), LedPattern::On, "PDI watchdog");
    }

    #[test]
    fn drive_sets_both_leds() {
        struct Board(bool, bool);
        impl Leds for Board {
            fn set(&mut self, run: bool, err: bool) {
                self.0 = run;
                self.1 = err;
            }
        }
        let mut b = Board(false, false);
        let wd = AlStatus {
            state: AlState::SafeOp,
            error: true,
            code: AlStatusCode::SmWatchdog,
        };
        drive(&mut b, &wd, false, 0);
        assert_eq!((b.0, b.1), (true, true));
        drive(&mut b, &wd, false, 300);
        assert_eq!((b.0, b.1), (false, false));
    }
}
