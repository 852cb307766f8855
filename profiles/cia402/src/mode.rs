//! Modes of operation (CiA 402-2 objects 6060h "Modes of operation",
//! 6061h "Modes of operation display", 6502h "Supported drive modes";
//! ETG.6010 names CSP, CSV and CST the modes an EtherCAT drive runs
//! DC-synchronously).

/// A mode of operation this profile runs (0x6060/0x6061 values, INTEGER8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Profile position mode (1): point-to-point moves with the set-point
    /// handshake (controlword bit 4 / statusword bit 12).
    ProfilePosition,
    /// Profile velocity mode (3): ramps to the target velocity.
    ProfileVelocity,
    /// Homing mode (6): methods 35 and 37, "homing on the current position".
    Homing,
    /// Cyclic synchronous position mode (8): the master sends a position
    /// every cycle.
    CyclicPosition,
    /// Cyclic synchronous velocity mode (9).
    CyclicVelocity,
    /// Cyclic synchronous torque mode (10).
    CyclicTorque,
}

/// Every mode, in the order of their codes.
pub const ALL: [Mode; 6] = [
    Mode::ProfilePosition,
    Mode::ProfileVelocity,
    Mode::Homing,
    Mode::CyclicPosition,
    Mode::CyclicVelocity,
    Mode::CyclicTorque,
];

/// 0x6502 "Supported drive modes" of this profile: bit 0 pp, bit 2 pv,
/// bit 5 hm, bit 7 csp, bit 8 csv, bit 9 cst (CiA 402-2 object 6502h
/// value definition; bits 1 vl, 3 tq, 6 ip, 10 cstca not supported).
pub const SUPPORTED_DRIVE_MODES: u32 = {
    let mut bits = 0;
    let mut rest: &[Mode] = &ALL;
    while let Some((m, tail)) = rest.split_first() {
        bits |= m.supported_bit();
        rest = tail;
    }
    bits
};

/// The homing methods this profile runs (CiA 402-2 object 6098h: 35 in
/// the first edition and 37 in the current one both mean "homing on the
/// current position": the position actual value becomes the home offset).
pub const HOMING_METHODS: [i8; 2] = [35, 37];

impl Mode {
    /// The mode with 0x6060 code `code`; `None` for 0 ("no mode change /
    /// no mode assigned") and every mode this profile does not run.
    pub const fn from_code(code: i64) -> Option<Mode> {
        Some(match code {
            1 => Mode::ProfilePosition,
            3 => Mode::ProfileVelocity,
            6 => Mode::Homing,
            8 => Mode::CyclicPosition,
            9 => Mode::CyclicVelocity,
            10 => Mode::CyclicTorque,
            _ => return None,
        })
    }

    /// The 0x6060/0x6061 code.
    pub const fn code(self) -> i8 {
        match self {
            Mode::ProfilePosition => 1,
            Mode::ProfileVelocity => 3,
            Mode::Homing => 6,
            Mode::CyclicPosition => 8,
            Mode::CyclicVelocity => 9,
            Mode::CyclicTorque => 10,
        }
    }

    /// The mode's bit in 0x6502.
    pub const fn supported_bit(self) -> u32 {
        match self {
            Mode::ProfilePosition => 1 << 0,
            Mode::ProfileVelocity => 1 << 2,
            Mode::Homing => 1 << 5,
            Mode::CyclicPosition => 1 << 7,
            Mode::CyclicVelocity => 1 << 8,
            Mode::CyclicTorque => 1 << 9,
        }
    }

    /// Whether the drive's position loop is closed in this mode (the
    /// following error 0x60F4 is monitored).
    pub const fn controls_position(self) -> bool {
        matches!(
            self,
            Mode::ProfilePosition | Mode::Homing | Mode::CyclicPosition
        )
    }

    /// Whether the mode takes a cyclic set point every cycle (ETG.6010's
    /// cyclic synchronous modes).
    pub const fn is_cyclic(self) -> bool {
        matches!(
            self,
            Mode::CyclicPosition | Mode::CyclicVelocity | Mode::CyclicTorque
        )
    }

    /// The usual abbreviation (CSP, PV, ...).
    pub const fn name(self) -> &'static str {
        match self {
            Mode::ProfilePosition => "PP",
            Mode::ProfileVelocity => "PV",
            Mode::Homing => "HM",
            Mode::CyclicPosition => "CSP",
            Mode::CyclicVelocity => "CSV",
            Mode::CyclicTorque => "CST",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip_and_zero_or_unknown_codes_are_no_mode() {
        for m in ALL {
            assert_eq!(Mode::from_code(i64::from(m.code())), Some(m));
        }
        for code in [0, 2, 4, 5, 7, 11, -1, -128, 127, i64::MAX, i64::MIN] {
            assert_eq!(Mode::from_code(code), None, "{code}");
        }
    }

    #[test]
    fn supported_drive_modes_has_the_bits_of_pp_pv_hm_csp_csv_cst() {
        assert_eq!(SUPPORTED_DRIVE_MODES, 0x0000_03A5);
    }

    #[test]
    fn the_position_loop_runs_in_csp_pp_and_homing_only() {
        let position: Vec<_> = ALL.iter().filter(|m| m.controls_position()).collect();
        assert_eq!(
            position,
            [&Mode::ProfilePosition, &Mode::Homing, &Mode::CyclicPosition]
        );
        assert!(ALL.iter().filter(|m| m.is_cyclic()).all(|m| m.code() >= 8));
    }
}
