//! The PAM-199-P-ETC's emergencies and error register (manual 8.1): what
//! its diagnosis objects say, turned into CoE Emergency messages when a
//! fault appears, and into the error-register bits of 0x1001. The core
//! adds the communication errors (SM watchdog 0x8100, refused transitions
//! 0xA000, PDI failures 0x5000) and the "error reset" 0x0000.
//!
//! | condition | error code | register bit | data byte 0 |
//! |---|---|---|---|
//! | short circuit at solenoid A/B | 0x2320 | current (1) | 1 = A, 2 = B |
//! | open circuit at solenoid A/B | 0xFF01 (manufacturer) | current (1) | 1 = A, 2 = B |
//! | supply overvoltage | 0x3210 | voltage (2) | |
//! | supply undervoltage | 0x3220 | voltage (2) | |
//! | over temperature | 0x4210 | temperature (3) | |
//! | EEPROM data error | 0x5530 | manufacturer (7) | |

use ecat_slave::coe::emergency::register;
use ecat_slave::device::Tick;
use ecat_slave::od::Od;

/// The fault conditions that produce emergencies.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FaultState {
    /// Short circuit at solenoid A / B.
    pub short: [bool; 2],
    /// Open circuit at solenoid A / B.
    pub open: [bool; 2],
    /// Supply overvoltage.
    pub overvoltage: bool,
    /// Supply undervoltage.
    pub undervoltage: bool,
    /// Over temperature.
    pub overtemperature: bool,
    /// EEPROM data error.
    pub eeprom: bool,
}

impl FaultState {
    /// The faults the diagnosis objects (0xA000/0xA010/0xA020, true = fault)
    /// show.
    pub fn from_od(od: &Od) -> Self {
        let e = &crate::app::entries::DIAGNOSIS;
        let d = |p: crate::app::entries::EntryPos| p.get(od) == 1;
        FaultState {
            short: e.short.map(d),
            open: e.open.map(d),
            overvoltage: d(e.overvoltage),
            undervoltage: d(e.undervoltage),
            overtemperature: d(e.temperature),
            eeprom: d(e.memory),
        }
    }

    /// The error-register bits (0x1001) of these faults, without the
    /// generic bit (the core adds it).
    pub fn error_bits(&self) -> u8 {
        let mut r = 0;
        if self.short.iter().chain(self.open.iter()).any(|b| *b) {
            r |= register::CURRENT;
        }
        if self.overvoltage || self.undervoltage {
            r |= register::VOLTAGE;
        }
        if self.overtemperature {
            r |= register::TEMPERATURE;
        }
        if self.eeprom {
            r |= register::MANUFACTURER;
        }
        r
    }

    /// Sets the register bits and raises an emergency for every fault of
    /// `self` that `old` did not have.
    pub fn report(&self, old: &FaultState, tick: &mut Tick<'_>) {
        tick.set_error_bits(self.error_bits());
        for (i, (n, o)) in self.short.iter().zip(old.short.iter()).enumerate() {
            if *n && !*o {
                tick.emergency(0x2320, [i as u8 + 1, 0, 0, 0, 0]);
            }
        }
        for (i, (n, o)) in self.open.iter().zip(old.open.iter()).enumerate() {
            if *n && !*o {
                tick.emergency(0xFF01, [i as u8 + 1, 0, 0, 0, 0]);
            }
        }
        let rising = [
            (self.overvoltage && !old.overvoltage, 0x3210),
            (self.undervoltage && !old.undervoltage, 0x3220),
            (self.overtemperature && !old.overtemperature, 0x4210),
            (self.eeprom && !old.eeprom, 0x5530),
        ];
        for (rose, code) in rising {
            if rose {
                tick.emergency(code, [0; 5]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_register_bits_follow_the_faults() {
        let s = FaultState {
            undervoltage: true,
            eeprom: true,
            ..FaultState::default()
        };
        assert_eq!(s.error_bits(), register::VOLTAGE | register::MANUFACTURER);
        let s = FaultState {
            short: [false, true],
            overtemperature: true,
            ..FaultState::default()
        };
        assert_eq!(s.error_bits(), register::CURRENT | register::TEMPERATURE);
        assert_eq!(FaultState::default().error_bits(), 0);
    }
}
