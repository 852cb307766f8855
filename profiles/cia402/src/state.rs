//! The power drive system finite state automaton (PDS FSA) of IEC
//! 61800-7-201 / CiA 402-2 ("PDS FSA": the state diagram with
//! transitions 0-16, the controlword's command coding table and the
//! statusword's state coding table), as ETG.6010 takes it over for
//! EtherCAT unchanged.
//!
//! This module is pure: states, the commands a controlword encodes, and
//! one transition function for the transitions a command causes. What
//! happens *inside* a state (ramps, faults, the lost connection) is the
//! [`Drive`](crate::Drive)'s.

/// Bits of the controlword 0x6040 (CiA 402-2, object 6040h: "so", "ev",
/// "qs", "eo", the operation-mode-specific bits 4-6, "fr", "h").
pub mod control {
    /// Bit 0 "switch on".
    pub const SWITCH_ON_BIT: u16 = 1 << 0;
    /// Bit 1 "enable voltage".
    pub const ENABLE_VOLTAGE_BIT: u16 = 1 << 1;
    /// Bit 2 "quick stop" (0 = quick stop requested).
    pub const QUICK_STOP_BIT: u16 = 1 << 2;
    /// Bit 3 "enable operation".
    pub const ENABLE_OPERATION_BIT: u16 = 1 << 3;
    /// Bit 4, operation mode specific: PP "new set-point", HM "homing
    /// operation start".
    pub const NEW_SET_POINT: u16 = 1 << 4;
    /// Bit 5, PP: "change set immediately".
    pub const CHANGE_SET_IMMEDIATELY: u16 = 1 << 5;
    /// Bit 6, PP: "abs/rel" (1 = the target is relative to the preceding one).
    pub const RELATIVE: u16 = 1 << 6;
    /// Bit 7 "fault reset" (acts on its rising edge).
    pub const FAULT_RESET_BIT: u16 = 1 << 7;
    /// Bit 8 "halt".
    pub const HALT: u16 = 1 << 8;

    /// Command "shutdown" (0xxx x110): transitions 2, 6, 8.
    pub const SHUTDOWN: u16 = 0x0006;
    /// Command "switch on" (0xxx 0111): transition 3; from Operation
    /// enabled the same code is "disable operation", transition 5.
    pub const SWITCH_ON: u16 = 0x0007;
    /// Command "disable operation" (0xxx 0111): transition 5.
    pub const DISABLE_OPERATION: u16 = 0x0007;
    /// Command "enable operation" / "switch on + enable operation" (0xxx
    /// 1111): transitions 4, 16 and 3 + 4.
    pub const ENABLE_OPERATION: u16 = 0x000F;
    /// Command "disable voltage" (0xxx xx0x): transitions 7, 9, 10, 12.
    pub const DISABLE_VOLTAGE: u16 = 0x0000;
    /// Command "quick stop" (0xxx x01x): transitions 7, 10, 11.
    pub const QUICK_STOP: u16 = 0x0002;
    /// Command "fault reset" (0 → 1 on bit 7): transition 15.
    pub const FAULT_RESET: u16 = 0x0080;
}

/// Bits of the statusword 0x6041 (CiA 402-2, object 6041h).
pub mod status {
    /// Bit 0 "ready to switch on".
    pub const READY_TO_SWITCH_ON: u16 = 1 << 0;
    /// Bit 1 "switched on".
    pub const SWITCHED_ON: u16 = 1 << 1;
    /// Bit 2 "operation enabled".
    pub const OPERATION_ENABLED: u16 = 1 << 2;
    /// Bit 3 "fault".
    pub const FAULT: u16 = 1 << 3;
    /// Bit 4 "voltage enabled": high voltage is applied to the PDS.
    pub const VOLTAGE_ENABLED: u16 = 1 << 4;
    /// Bit 5 "quick stop" (0 = the PDS is reacting on a quick stop request).
    pub const QUICK_STOP: u16 = 1 << 5;
    /// Bit 6 "switch on disabled".
    pub const SWITCH_ON_DISABLED: u16 = 1 << 6;
    /// Bit 7 "warning".
    pub const WARNING: u16 = 1 << 7;
    /// Bit 9 "remote": the controlword is processed.
    pub const REMOTE: u16 = 1 << 9;
    /// Bit 10 "target reached" (mode specific meaning).
    pub const TARGET_REACHED: u16 = 1 << 10;
    /// Bit 11 "internal limit active".
    pub const INTERNAL_LIMIT: u16 = 1 << 11;
    /// Bit 12, operation mode specific: CSP/CSV/CST "target value
    /// ignored" (1 = the target is used), PP "set-point acknowledge", PV
    /// "speed" (1 = speed 0), HM "homing attained".
    pub const MODE_SPECIFIC_12: u16 = 1 << 12;
    /// Bit 13, operation mode specific: CSP/PP "following error", HM
    /// "homing error".
    pub const MODE_SPECIFIC_13: u16 = 1 << 13;
    /// The bits that code the state (0-3, 5, 6; CiA 402-2 state coding
    /// table masks bit 5 out for some states, see [`super::PowerState::from_statusword`]).
    pub const STATE_MASK: u16 = 0x006F;
}

/// A state of the PDS FSA.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum PowerState {
    /// Not ready to switch on: the drive initialises (left at once,
    /// transition 1).
    #[default]
    NotReadyToSwitchOn,
    /// Switch on disabled: no high voltage requested, no torque.
    SwitchOnDisabled,
    /// Ready to switch on: high voltage may be applied, no torque.
    ReadyToSwitchOn,
    /// Switched on: high voltage applied, power stage ready, no torque.
    SwitchedOn,
    /// Operation enabled: the power stage drives the motor.
    OperationEnabled,
    /// Quick stop active: the quick stop function is being executed.
    QuickStopActive,
    /// Fault reaction active: the fault reaction is being executed.
    FaultReactionActive,
    /// Fault: the power stage is off until a fault reset.
    Fault,
}

impl PowerState {
    /// The statusword bits 0-6 of the state (CiA 402-2 state coding: bit 4
    /// "voltage enabled" is set wherever high voltage is applied, bit 5
    /// "quick stop" is 1 where the coding requires it and 0 elsewhere).
    pub const fn statusword_bits(self) -> u16 {
        use status::*;
        match self {
            // xxxx xxxx x0xx 0000
            PowerState::NotReadyToSwitchOn => 0,
            // xxxx xxxx x1xx 0000
            PowerState::SwitchOnDisabled => SWITCH_ON_DISABLED,
            // xxxx xxxx x01x 0001
            PowerState::ReadyToSwitchOn => QUICK_STOP | VOLTAGE_ENABLED | READY_TO_SWITCH_ON,
            // xxxx xxxx x01x 0011
            PowerState::SwitchedOn => {
                QUICK_STOP | VOLTAGE_ENABLED | SWITCHED_ON | READY_TO_SWITCH_ON
            }
            // xxxx xxxx x01x 0111
            PowerState::OperationEnabled => {
                QUICK_STOP | VOLTAGE_ENABLED | OPERATION_ENABLED | SWITCHED_ON | READY_TO_SWITCH_ON
            }
            // xxxx xxxx x00x 0111
            PowerState::QuickStopActive => {
                VOLTAGE_ENABLED | OPERATION_ENABLED | SWITCHED_ON | READY_TO_SWITCH_ON
            }
            // xxxx xxxx x0xx 1111
            PowerState::FaultReactionActive => {
                VOLTAGE_ENABLED | FAULT | OPERATION_ENABLED | SWITCHED_ON | READY_TO_SWITCH_ON
            }
            // xxxx xxxx x0xx 1000
            PowerState::Fault => FAULT,
        }
    }

    /// The state a statusword codes (what a master decodes), `None` for a
    /// combination the coding table does not list.
    pub const fn from_statusword(sw: u16) -> Option<PowerState> {
        // Masks 0x4F (bit 5 "don't care") and 0x6F, as the table reads.
        Some(match (sw & 0x4F, sw & 0x6F) {
            (0x00, _) => PowerState::NotReadyToSwitchOn,
            (0x40, _) => PowerState::SwitchOnDisabled,
            (_, 0x21) => PowerState::ReadyToSwitchOn,
            (_, 0x23) => PowerState::SwitchedOn,
            (_, 0x27) => PowerState::OperationEnabled,
            (_, 0x07) => PowerState::QuickStopActive,
            (0x0F, _) => PowerState::FaultReactionActive,
            (0x08, _) => PowerState::Fault,
            _ => return None,
        })
    }

    /// Whether the power stage may carry current in this state: Operation
    /// enabled, and the braking ramps of Quick stop active and Fault
    /// reaction active (CiA 402-2: "torque" for these three states only).
    pub const fn may_drive(self) -> bool {
        matches!(
            self,
            PowerState::OperationEnabled
                | PowerState::QuickStopActive
                | PowerState::FaultReactionActive
        )
    }

    /// A short name for logs and test messages.
    pub const fn name(self) -> &'static str {
        match self {
            PowerState::NotReadyToSwitchOn => "Not ready to switch on",
            PowerState::SwitchOnDisabled => "Switch on disabled",
            PowerState::ReadyToSwitchOn => "Ready to switch on",
            PowerState::SwitchedOn => "Switched on",
            PowerState::OperationEnabled => "Operation enabled",
            PowerState::QuickStopActive => "Quick stop active",
            PowerState::FaultReactionActive => "Fault reaction active",
            PowerState::Fault => "Fault",
        }
    }
}

/// A command of the controlword (CiA 402-2 command coding, bits 7, 3, 2,
/// 1, 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Command {
    /// 0 x 1 1 0.
    Shutdown,
    /// 0 0 1 1 1: "switch on", or "disable operation" from Operation enabled.
    SwitchOn,
    /// 0 1 1 1 1: "enable operation", or "switch on + enable operation".
    EnableOperation,
    /// 0 x x 0 x.
    DisableVoltage,
    /// 0 x 0 1 x.
    QuickStop,
    /// Bit 7 set: "fault reset" (the drive acts on its rising edge); no
    /// other command is decoded while it is set.
    FaultReset,
}

impl Command {
    /// The command `controlword` codes. Every controlword codes one: the
    /// table's "x" bits are ignored, and the order of the checks is the
    /// table's priority (fault reset, disable voltage, quick stop, ...).
    pub const fn decode(controlword: u16) -> Command {
        use control::*;
        if controlword & FAULT_RESET_BIT != 0 {
            Command::FaultReset
        } else if controlword & ENABLE_VOLTAGE_BIT == 0 {
            Command::DisableVoltage
        } else if controlword & QUICK_STOP_BIT == 0 {
            Command::QuickStop
        } else if controlword & SWITCH_ON_BIT == 0 {
            Command::Shutdown
        } else if controlword & ENABLE_OPERATION_BIT == 0 {
            Command::SwitchOn
        } else {
            Command::EnableOperation
        }
    }
}

/// The state a controlword command leads to from `state` (transitions 2-12
/// and 16 of the PDS FSA; transition 16 only when the quick stop option
/// code keeps the drive in Quick stop active, `quick_stop_stays`). Fault
/// (13, 14) and fault reset (15) are the drive's: a fault reset needs a
/// rising edge and a cleared fault, which a command alone cannot know.
/// A command the state has no transition for leaves it unchanged.
pub const fn transition(state: PowerState, command: Command, quick_stop_stays: bool) -> PowerState {
    use Command as C;
    use PowerState as S;
    match (state, command) {
        // 2
        (S::SwitchOnDisabled, C::Shutdown) => S::ReadyToSwitchOn,
        // 3, 3 + 4
        (S::ReadyToSwitchOn, C::SwitchOn) => S::SwitchedOn,
        (S::ReadyToSwitchOn, C::EnableOperation) => S::OperationEnabled,
        // 7
        (S::ReadyToSwitchOn, C::DisableVoltage | C::QuickStop) => S::SwitchOnDisabled,
        // 4
        (S::SwitchedOn, C::EnableOperation) => S::OperationEnabled,
        // 6
        (S::SwitchedOn, C::Shutdown) => S::ReadyToSwitchOn,
        // 10
        (S::SwitchedOn, C::DisableVoltage | C::QuickStop) => S::SwitchOnDisabled,
        // 5
        (S::OperationEnabled, C::SwitchOn) => S::SwitchedOn,
        // 8
        (S::OperationEnabled, C::Shutdown) => S::ReadyToSwitchOn,
        // 9
        (S::OperationEnabled, C::DisableVoltage) => S::SwitchOnDisabled,
        // 11
        (S::OperationEnabled, C::QuickStop) => S::QuickStopActive,
        // 12
        (S::QuickStopActive, C::DisableVoltage) => S::SwitchOnDisabled,
        // 16
        (S::QuickStopActive, C::EnableOperation) if quick_stop_stays => S::OperationEnabled,
        (s, _) => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [PowerState; 8] = [
        PowerState::NotReadyToSwitchOn,
        PowerState::SwitchOnDisabled,
        PowerState::ReadyToSwitchOn,
        PowerState::SwitchedOn,
        PowerState::OperationEnabled,
        PowerState::QuickStopActive,
        PowerState::FaultReactionActive,
        PowerState::Fault,
    ];

    #[test]
    fn every_state_decodes_from_its_own_statusword_bits_with_any_other_bits() {
        for s in ALL {
            let sw = s.statusword_bits();
            assert_eq!(PowerState::from_statusword(sw), Some(s), "{s:?}");
            // Bits 7-15 do not code the state.
            assert_eq!(PowerState::from_statusword(sw | 0xFF80), Some(s), "{s:?}");
        }
    }

    #[test]
    fn the_statusword_codes_match_the_table_values_masters_test() {
        // What SOEM's and ethercrab's examples compare against (mask 0x6F).
        assert_eq!(PowerState::SwitchOnDisabled.statusword_bits() & 0x4F, 0x40);
        assert_eq!(PowerState::ReadyToSwitchOn.statusword_bits() & 0x6F, 0x21);
        assert_eq!(PowerState::SwitchedOn.statusword_bits() & 0x6F, 0x23);
        assert_eq!(PowerState::OperationEnabled.statusword_bits() & 0x6F, 0x27);
        assert_eq!(PowerState::QuickStopActive.statusword_bits() & 0x6F, 0x07);
        assert_eq!(
            PowerState::FaultReactionActive.statusword_bits() & 0x4F,
            0x0F
        );
        assert_eq!(PowerState::Fault.statusword_bits() & 0x4F, 0x08);
    }

    #[test]
    fn every_controlword_decodes_to_the_command_of_the_coding_table() {
        assert_eq!(Command::decode(control::SHUTDOWN), Command::Shutdown);
        assert_eq!(Command::decode(0x000E), Command::Shutdown, "bit 3 is x");
        assert_eq!(Command::decode(control::SWITCH_ON), Command::SwitchOn);
        assert_eq!(
            Command::decode(control::ENABLE_OPERATION),
            Command::EnableOperation
        );
        assert_eq!(Command::decode(0x0000), Command::DisableVoltage);
        assert_eq!(Command::decode(0x000D), Command::DisableVoltage);
        assert_eq!(Command::decode(0x0002), Command::QuickStop);
        assert_eq!(Command::decode(0x000B), Command::QuickStop);
        assert_eq!(Command::decode(0x0080), Command::FaultReset);
        assert_eq!(Command::decode(0x008F), Command::FaultReset);
        // The high byte (halt, mode specific, manufacturer) codes nothing.
        assert_eq!(Command::decode(0xFF0F & !0x0080), Command::EnableOperation);
        for cw in 0..=u16::MAX {
            let _ = Command::decode(cw);
        }
    }

    #[test]
    fn the_enable_sequence_and_its_shortcut_reach_operation_enabled() {
        let s = transition(PowerState::SwitchOnDisabled, Command::Shutdown, false);
        assert_eq!(s, PowerState::ReadyToSwitchOn);
        let s1 = transition(s, Command::SwitchOn, false);
        assert_eq!(s1, PowerState::SwitchedOn);
        assert_eq!(
            transition(s1, Command::EnableOperation, false),
            PowerState::OperationEnabled
        );
        // 3 + 4: "switch on + enable operation" from Ready to switch on.
        assert_eq!(
            transition(s, Command::EnableOperation, false),
            PowerState::OperationEnabled
        );
        // Switch on disabled needs "shutdown" first.
        for c in [Command::SwitchOn, Command::EnableOperation] {
            assert_eq!(
                transition(PowerState::SwitchOnDisabled, c, false),
                PowerState::SwitchOnDisabled
            );
        }
    }

    #[test]
    fn operation_enabled_leaves_by_transitions_5_8_9_and_11() {
        let oe = PowerState::OperationEnabled;
        assert_eq!(
            transition(oe, Command::SwitchOn, false),
            PowerState::SwitchedOn
        );
        assert_eq!(
            transition(oe, Command::Shutdown, false),
            PowerState::ReadyToSwitchOn
        );
        assert_eq!(
            transition(oe, Command::DisableVoltage, false),
            PowerState::SwitchOnDisabled
        );
        assert_eq!(
            transition(oe, Command::QuickStop, false),
            PowerState::QuickStopActive
        );
    }

    #[test]
    fn quick_stop_active_returns_to_operation_only_when_the_option_code_stays() {
        let qs = PowerState::QuickStopActive;
        assert_eq!(transition(qs, Command::EnableOperation, false), qs);
        assert_eq!(
            transition(qs, Command::EnableOperation, true),
            PowerState::OperationEnabled
        );
        assert_eq!(
            transition(qs, Command::DisableVoltage, true),
            PowerState::SwitchOnDisabled
        );
        assert_eq!(transition(qs, Command::Shutdown, true), qs);
    }

    #[test]
    fn no_command_leaves_fault_or_fault_reaction_and_only_three_states_may_drive() {
        for c in [
            Command::Shutdown,
            Command::SwitchOn,
            Command::EnableOperation,
            Command::DisableVoltage,
            Command::QuickStop,
            Command::FaultReset,
        ] {
            for s in [PowerState::Fault, PowerState::FaultReactionActive] {
                assert_eq!(transition(s, c, true), s);
            }
            // No command enables the power stage from a state without torque
            // except through Switched on / Ready to switch on (3 + 4, 4).
            for s in ALL {
                let to = transition(s, c, true);
                if to.may_drive() && !s.may_drive() {
                    assert!(
                        matches!(s, PowerState::SwitchedOn | PowerState::ReadyToSwitchOn),
                        "{s:?} --{c:?}--> {to:?}"
                    );
                }
            }
        }
        let driving: Vec<_> = ALL.iter().filter(|s| s.may_drive()).collect();
        assert_eq!(driving.len(), 3);
    }
}
