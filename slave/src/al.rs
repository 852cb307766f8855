//! Application-layer state machine (ETG.1000.6 6.4.1).
//!
//! [`transition`] is a pure function of the current AL status, the value the
//! master wrote into AL control (0x0120) and the checks the device performs
//! on its SyncManagers; it returns the new AL status (0x0130/0x0134). It
//! knows nothing of the ESC or the object dictionary.

use crate::codes::protocol_codes;

/// EtherCAT device states (AL status bits 0-3). Each discriminant is the
/// state's bits (`repr(u8)`), so [`AlState::bits`] is the tag itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum AlState {
    /// INIT (1).
    Init = 1,
    /// PRE-OPERATIONAL (2): mailbox running.
    PreOp = 2,
    /// BOOTSTRAP (3): firmware update over FoE only.
    Boot = 3,
    /// SAFE-OPERATIONAL (4): inputs valid, outputs in safe state.
    SafeOp = 4,
    /// OPERATIONAL (8).
    Op = 8,
}

impl AlState {
    /// Decodes the state nibble; `None` for anything else.
    pub const fn from_bits(bits: u8) -> Option<Self> {
        match bits & 0x0F {
            1 => Some(AlState::Init),
            2 => Some(AlState::PreOp),
            3 => Some(AlState::Boot),
            4 => Some(AlState::SafeOp),
            8 => Some(AlState::Op),
            _ => None,
        }
    }

    /// The state nibble.
    pub const fn bits(self) -> u8 {
        match self {
            AlState::Init => 1,
            AlState::PreOp => 2,
            AlState::Boot => 3,
            AlState::SafeOp => 4,
            AlState::Op => 8,
        }
    }

    /// Short name as masters print it.
    pub const fn name(self) -> &'static str {
        match self {
            AlState::Init => "INIT",
            AlState::PreOp => "PRE-OP",
            AlState::Boot => "BOOT",
            AlState::SafeOp => "SAFE-OP",
            AlState::Op => "OP",
        }
    }
}

impl core::fmt::Display for AlState {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

protocol_codes! {
    /// AL status codes (register 0x0134, ETG.1000.6 table 11).
    ///
    /// Each variant's discriminant is its code (`repr(u16)`), so
    /// [`AlStatusCode::code`], a `match` returning them, compiles to the tag
    /// itself instead of a table of 22 arms. `Other`'s tag is 0xFFFF, not a
    /// code: its own field holds the code.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum AlStatusCode(u16) {
        /// 0x0000 no error.
        NoError = 0x0000,
        /// 0x0001 unspecified error.
        Unspecified = 0x0001,
        /// 0x0007 firmware update not successful, old firmware still running.
        FirmwareUpdateFailed = 0x0007,
        /// 0x0011 invalid requested state change.
        InvalidStateChange = 0x0011,
        /// 0x0012 unknown requested state.
        UnknownState = 0x0012,
        /// 0x0013 bootstrap not supported.
        BootNotSupported = 0x0013,
        /// 0x0014 no valid firmware.
        NoValidFirmware = 0x0014,
        /// 0x0015 invalid mailbox configuration (BOOT).
        InvalidMailboxBoot = 0x0015,
        /// 0x0016 invalid mailbox configuration (PRE-OP).
        InvalidMailboxPreOp = 0x0016,
        /// 0x0017 invalid SyncManager configuration.
        InvalidSmConfig = 0x0017,
        /// 0x001A synchronisation error.
        SyncError = 0x001A,
        /// 0x001B SyncManager watchdog.
        SmWatchdog = 0x001B,
        /// 0x001D invalid output configuration.
        InvalidOutputConfig = 0x001D,
        /// 0x001E invalid input configuration.
        InvalidInputConfig = 0x001E,
        /// 0x0021 waiting for INIT.
        WaitingForInit = 0x0021,
        /// 0x0024 invalid input mapping.
        InvalidInputMapping = 0x0024,
        /// 0x0025 invalid output mapping.
        InvalidOutputMapping = 0x0025,
        /// 0x002C fatal sync error.
        FatalSyncError = 0x002C,
        /// 0x0030 invalid DC SYNC configuration.
        InvalidDcSyncConfig = 0x0030,
        /// 0x0035 invalid DC sync cycle time.
        InvalidDcCycleTime = 0x0035,
        /// 0x0070 the configured module ident list (0xF030) does not match the
        /// detected one (0xF050) (ETG.1000.6; ETG.5001 modular devices).
        ModuleIdentMismatch = 0x0070,
    } else {
        /// Any other code.
        Other = 0xFFFF,
    }
}

impl AlStatusCode {
    /// The ETG.1000.6 description of the code.
    pub const fn text(self) -> &'static str {
        match self {
            AlStatusCode::NoError => "no error",
            AlStatusCode::Unspecified => "unspecified error",
            AlStatusCode::FirmwareUpdateFailed => {
                "firmware update not successful, old firmware still running"
            }
            AlStatusCode::InvalidStateChange => "invalid requested state change",
            AlStatusCode::UnknownState => "unknown requested state",
            AlStatusCode::BootNotSupported => "bootstrap not supported",
            AlStatusCode::NoValidFirmware => "no valid firmware",
            AlStatusCode::InvalidMailboxBoot => "invalid mailbox configuration (BOOT)",
            AlStatusCode::InvalidMailboxPreOp => "invalid mailbox configuration (PRE-OP)",
            AlStatusCode::InvalidSmConfig => "invalid SyncManager configuration",
            AlStatusCode::SyncError => "synchronization error",
            AlStatusCode::SmWatchdog => "SyncManager watchdog",
            AlStatusCode::InvalidOutputConfig => "invalid output configuration",
            AlStatusCode::InvalidInputConfig => "invalid input configuration",
            AlStatusCode::WaitingForInit => "waiting for INIT",
            AlStatusCode::InvalidInputMapping => "invalid input mapping",
            AlStatusCode::InvalidOutputMapping => "invalid output mapping",
            AlStatusCode::FatalSyncError => "fatal sync error",
            AlStatusCode::InvalidDcSyncConfig => "invalid DC SYNC configuration",
            AlStatusCode::InvalidDcCycleTime => "invalid DC sync cycle time",
            AlStatusCode::ModuleIdentMismatch => {
                "detected module ident list (0xF050) and configured module ident list (0xF030) do not match"
            }
            AlStatusCode::Other(_) => "other AL status code",
        }
    }
}

/// The AL status as registers 0x0130 and 0x0134 show it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AlStatus {
    /// Current state.
    pub state: AlState,
    /// Error indication (0x0130 bit 4).
    pub error: bool,
    /// Status code (0x0134).
    pub code: AlStatusCode,
}

impl AlStatus {
    /// Power-on status: INIT, no error.
    pub const INIT: AlStatus = AlStatus {
        state: AlState::Init,
        error: false,
        code: AlStatusCode::NoError,
    };

    /// Value of register 0x0130.
    pub const fn register(&self) -> u16 {
        self.state.bits() as u16 | if self.error { 0x10 } else { 0 }
    }
}

/// The device's checks run on the way up (ETG.1000.6 table 8).
pub trait TransitionChecks {
    /// INIT→PRE-OP: SM0/SM1 match the standard mailbox of the SII
    /// (`Err` typically [`AlStatusCode::InvalidMailboxPreOp`]).
    fn check_mailbox(&mut self) -> Result<(), AlStatusCode>;
    /// INIT→BOOT: SM0/SM1 match the bootstrap mailbox
    /// ([`AlStatusCode::InvalidMailboxBoot`], or
    /// [`AlStatusCode::BootNotSupported`]).
    fn check_boot_mailbox(&mut self) -> Result<(), AlStatusCode>;
    /// PRE-OP→SAFE-OP: the PDO assignment is valid and SM2/SM3 match it
    /// (0x001D / 0x001E / 0x0024 / 0x0025).
    fn check_process_data(&mut self) -> Result<(), AlStatusCode>;
    /// SAFE-OP→OP: outputs can be taken over.
    fn check_outputs(&mut self) -> Result<(), AlStatusCode>;
    /// An upward transition (INIT→PRE-OP, INIT→BOOT, PRE-OP→SAFE-OP,
    /// SAFE-OP→OP) passed its check: the application may still refuse it.
    /// Downward transitions cannot be refused (ETG.1000.6).
    fn accept(&mut self, from: AlState, to: AlState) -> Result<(), AlStatusCode> {
        let _ = (from, to);
        Ok(())
    }
}

/// Computes the AL status after the master wrote `control` into 0x0120.
///
/// With the error flag set, a request without error acknowledge (bit 4) is
/// ignored. Unknown states answer 0x0012, forbidden transitions 0x0011; a
/// failed check keeps the lower state with the error flag and the check's
/// code. Any error while in OP drops to SAFE-OP.
pub fn transition(current: AlStatus, control: u16, checks: &mut impl TransitionChecks) -> AlStatus {
    let ack = control & 0x0010 != 0;
    if current.error && !ack {
        return current;
    }
    let base = if ack {
        AlStatus {
            error: false,
            code: AlStatusCode::NoError,
            ..current
        }
    } else {
        current
    };
    let fail = |code: AlStatusCode| AlStatus {
        state: if current.state == AlState::Op {
            AlState::SafeOp
        } else {
            current.state
        },
        error: true,
        code,
    };
    let Some(requested) = AlState::from_bits((control & 0x0F) as u8) else {
        return fail(AlStatusCode::UnknownState);
    };
    use AlState::*;
    let result = match (current.state, requested) {
        (a, b) if a == b => Ok(()),
        (_, Init) => Ok(()),
        (Init, PreOp) => checks
            .check_mailbox()
            .and_then(|()| checks.accept(Init, PreOp)),
        (Init, Boot) => checks
            .check_boot_mailbox()
            .and_then(|()| checks.accept(Init, Boot)),
        (PreOp, SafeOp) => checks
            .check_process_data()
            .and_then(|()| checks.accept(PreOp, SafeOp)),
        (SafeOp, Op) => checks
            .check_outputs()
            .and_then(|()| checks.accept(SafeOp, Op)),
        (SafeOp, PreOp) | (Op, PreOp) | (Op, SafeOp) => Ok(()),
        _ => Err(AlStatusCode::InvalidStateChange),
    };
    match result {
        Ok(()) => AlStatus {
            state: requested,
            ..base
        },
        Err(code) => fail(code),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Checks {
        mailbox: Result<(), AlStatusCode>,
        pd: Result<(), AlStatusCode>,
    }

    impl TransitionChecks for Checks {
        fn check_mailbox(&mut self) -> Result<(), AlStatusCode> {
            self.mailbox
        }
        fn check_boot_mailbox(&mut self) -> Result<(), AlStatusCode> {
            Ok(())
        }
        fn check_process_data(&mut self) -> Result<(), AlStatusCode> {
            self.pd
        }
        fn check_outputs(&mut self) -> Result<(), AlStatusCode> {
            Ok(())
        }
    }

    const OK: Checks = Checks {
        mailbox: Ok(()),
        pd: Ok(()),
    };

    fn at(state: AlState) -> AlStatus {
        AlStatus {
            state,
            ..AlStatus::INIT
        }
    }

    #[test]
    fn init_to_preop_with_matching_mailbox_succeeds() {
        let s = transition(AlStatus::INIT, 0x02, &mut { OK });
        assert_eq!(s, at(AlState::PreOp));
    }

    #[test]
    fn init_to_preop_with_bad_mailbox_stays_init_with_0016() {
        let mut c = Checks {
            mailbox: Err(AlStatusCode::InvalidMailboxPreOp),
            pd: Ok(()),
        };
        let s = transition(AlStatus::INIT, 0x02, &mut c);
        assert_eq!(s.state, AlState::Init);
        assert!(s.error);
        assert_eq!(s.code.code(), 0x0016);
        assert_eq!(s.register(), 0x11);
    }

    #[test]
    fn error_flag_ignores_requests_without_acknowledge() {
        let err = AlStatus {
            state: AlState::Init,
            error: true,
            code: AlStatusCode::InvalidMailboxPreOp,
        };
        assert_eq!(transition(err, 0x02, &mut { OK }), err);
        assert_eq!(transition(err, 0x12, &mut { OK }), at(AlState::PreOp));
        assert_eq!(transition(err, 0x11, &mut { OK }), at(AlState::Init));
    }

    #[test]
    fn unknown_requested_state_answers_0012() {
        let s = transition(at(AlState::PreOp), 0x05, &mut { OK });
        assert_eq!(
            (s.state, s.error, s.code.code()),
            (AlState::PreOp, true, 0x12)
        );
    }

    #[test]
    fn unknown_state_in_op_drops_to_safeop() {
        let s = transition(at(AlState::Op), 0x06, &mut { OK });
        assert_eq!(
            (s.state, s.error, s.code.code()),
            (AlState::SafeOp, true, 0x12)
        );
    }

    #[test]
    fn skipping_states_upwards_answers_0011() {
        let s = transition(AlStatus::INIT, 0x08, &mut { OK });
        assert_eq!(
            (s.state, s.error, s.code.code()),
            (AlState::Init, true, 0x11)
        );
        let s = transition(at(AlState::PreOp), 0x03, &mut { OK });
        assert_eq!(s.code, AlStatusCode::InvalidStateChange);
    }

    #[test]
    fn walking_up_and_down_reaches_each_state() {
        let mut s = AlStatus::INIT;
        for (req, want) in [
            (2, AlState::PreOp),
            (4, AlState::SafeOp),
            (8, AlState::Op),
            (4, AlState::SafeOp),
            (2, AlState::PreOp),
            (1, AlState::Init),
            (3, AlState::Boot),
            (1, AlState::Init),
        ] {
            s = transition(s, req, &mut { OK });
            assert_eq!(s, at(want), "request {req}");
        }
    }

    #[test]
    fn failed_process_data_check_stays_preop_with_code() {
        let mut c = Checks {
            mailbox: Ok(()),
            pd: Err(AlStatusCode::InvalidOutputConfig),
        };
        let s = transition(at(AlState::PreOp), 0x04, &mut c);
        assert_eq!(
            (s.state, s.error, s.code.code()),
            (AlState::PreOp, true, 0x1D)
        );
    }

    #[test]
    fn state_bits_round_trip_and_reject_unknown() {
        for s in [
            AlState::Init,
            AlState::PreOp,
            AlState::Boot,
            AlState::SafeOp,
            AlState::Op,
        ] {
            assert_eq!(AlState::from_bits(s.bits()), Some(s));
        }
        assert_eq!(AlState::from_bits(0), None);
        assert_eq!(AlState::from_bits(0x0F), None);
        assert_eq!(AlStatusCode::from_code(0x1B), AlStatusCode::SmWatchdog);
        assert_eq!(AlStatusCode::from_code(0x99).code(), 0x99);
    }
}
