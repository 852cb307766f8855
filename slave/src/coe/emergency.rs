//! CoE Emergency (ETG.1000.6 5.6.4): what the device reports on its own,
//! and the error register 0x1001 kept consistent with it.
//!
//! The device compares its fault state each poll with the previous one and
//! queues an emergency for every fault that appears (and the "error reset"
//! code 0x0000 when the last one clears). The queue holds
//! [`QUEUE_LEN`] messages; when it is full the **oldest** message is
//! dropped, so the master always sees the most recent condition.
//!
//! | condition | error code | register bit | data byte 0 |
//! |---|---|---|---|
//! | short circuit at solenoid A/B | 0x2320 | current (1) | 1 = A, 2 = B |
//! | open circuit at solenoid A/B | 0xFF01 (manufacturer) | current (1) | 1 = A, 2 = B |
//! | supply overvoltage | 0x3210 | voltage (2) | |
//! | supply undervoltage | 0x3220 | voltage (2) | |
//! | over temperature | 0x4210 | temperature (3) | |
//! | EEPROM data error | 0x5530 | manufacturer (7) | |
//! | SyncManager watchdog (OP left) | 0x8100 | communication (4) | AL code low byte |
//! | PRE-OP→SAFE-OP refused | 0xA000 | communication (4) | AL code low byte |
//! | PDI failure (firmware cannot reach its ESC) | 0x5000 (device hardware) | generic (0) | 1 out of range, 2 SM busy, 3 interface |
//! | all faults gone | 0x0000 | 0 | |
//!
//! Bit 0 (generic error) of 0x1001 is set whenever any other bit is.

use crate::wire::coe::{CoeHeader, CoeService, Emergency, EmergencyRepr};

/// Messages held while the master has not read the mailbox.
pub const QUEUE_LEN: usize = 8;

/// Error register bits (0x1001).
pub mod register {
    /// Generic error.
    pub const GENERIC: u8 = 0x01;
    /// Current.
    pub const CURRENT: u8 = 0x02;
    /// Voltage.
    pub const VOLTAGE: u8 = 0x04;
    /// Temperature.
    pub const TEMPERATURE: u8 = 0x08;
    /// Communication.
    pub const COMMUNICATION: u8 = 0x10;
    /// Manufacturer specific.
    pub const MANUFACTURER: u8 = 0x80;
}

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
    /// SyncManager watchdog expired (communication).
    pub watchdog: bool,
}

impl FaultState {
    /// The error register 0x1001 for this state.
    pub fn error_register(&self) -> u8 {
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
        if self.watchdog {
            r |= register::COMMUNICATION;
        }
        if self.eeprom {
            r |= register::MANUFACTURER;
        }
        if r != 0 {
            r |= register::GENERIC;
        }
        r
    }
}

/// The emergency queue.
#[derive(Debug, Default)]
pub struct Emergencies {
    queue: heapless::Deque<EmergencyRepr, QUEUE_LEN>,
    last: FaultState,
    dropped: u32,
}

impl Emergencies {
    /// Queues `e`, dropping the oldest message when full.
    pub fn push(&mut self, e: EmergencyRepr) {
        if self.queue.is_full() {
            let _ = self.queue.pop_front();
            self.dropped = self.dropped.saturating_add(1);
        }
        let _ = self.queue.push_back(e);
    }

    /// Queues one message with `code`, the register of `state` and `data0`.
    fn push_code(&mut self, code: u16, state: &FaultState, data0: u8) {
        self.push(EmergencyRepr {
            error_code: code,
            error_register: state.error_register(),
            data: [data0, 0, 0, 0, 0],
        });
    }

    /// Compares `now` with the previous state and queues a message for
    /// every new fault (and 0x0000 when the last fault clears). Returns the
    /// error register for 0x1001.
    pub fn update(&mut self, now: FaultState, al_code: u16) -> u8 {
        let old = self.last;
        for (i, (n, o)) in now.short.iter().zip(old.short.iter()).enumerate() {
            if *n && !*o {
                self.push_code(0x2320, &now, i as u8 + 1);
            }
        }
        for (i, (n, o)) in now.open.iter().zip(old.open.iter()).enumerate() {
            if *n && !*o {
                self.push_code(0xFF01, &now, i as u8 + 1);
            }
        }
        let rising = [
            (now.overvoltage && !old.overvoltage, 0x3210),
            (now.undervoltage && !old.undervoltage, 0x3220),
            (now.overtemperature && !old.overtemperature, 0x4210),
            (now.eeprom && !old.eeprom, 0x5530),
        ];
        for (rose, code) in rising {
            if rose {
                self.push_code(code, &now, 0);
            }
        }
        if now.watchdog && !old.watchdog {
            self.push_code(0x8100, &now, al_code as u8);
        }
        if now.error_register() == 0 && old.error_register() != 0 {
            self.push_code(0x0000, &now, 0);
        }
        self.last = now;
        now.error_register()
    }

    /// Queues a PDI failure (0x5000 device hardware; data byte 0 says
    /// which: 1 access out of range, 2 SyncManager busy, 3 interface).
    pub fn pdi_failure(&mut self, e: crate::esc::EscError) {
        let kind = match e {
            crate::esc::EscError::OutOfRange { .. } => 1,
            crate::esc::EscError::SmBusy { .. } => 2,
            crate::esc::EscError::Interface => 3,
        };
        let state = self.last;
        self.push(EmergencyRepr {
            error_code: 0x5000,
            error_register: state.error_register() | register::GENERIC,
            data: [kind, 0, 0, 0, 0],
        });
    }

    /// Drops every queued message (the mailbox stopped: INIT). The fault
    /// state is kept, so a fault that persists is not reported again and
    /// 0x1001 stays as it is.
    pub fn clear(&mut self) {
        self.queue.clear();
    }

    /// Queues the refusal of a state transition (0xA000, AL code in data).
    pub fn transition_refused(&mut self, al_code: u16) {
        let state = self.last;
        let mut e = EmergencyRepr {
            error_code: 0xA000,
            error_register: state.error_register() | register::GENERIC | register::COMMUNICATION,
            data: [0; 5],
        };
        e.data[..2].copy_from_slice(&al_code.to_le_bytes());
        self.push(e);
    }

    /// Writes the oldest queued message as CoE payload (CoE header with
    /// service Emergency + 8 bytes) into `out`; returns its length.
    pub fn pop_into(&mut self, out: &mut [u8]) -> Option<usize> {
        let (head, rest) = out.split_at_mut_checked(CoeHeader::<&[u8]>::HEADER_LEN)?;
        let e = self.queue.front()?;
        e.emit(&mut Emergency::new_unchecked(&mut *rest)).ok()?;
        CoeHeader::emit_into(head, 0, CoeService::Emergency);
        let _ = self.queue.pop_front();
        Some(CoeHeader::<&[u8]>::HEADER_LEN + 8)
    }

    /// Messages waiting.
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// Whether no message waits.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// Messages dropped because the queue was full.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_fault_queues_one_message_and_its_clearing_a_reset() {
        let mut q = Emergencies::default();
        let mut s = FaultState::default();
        assert_eq!(q.update(s, 0), 0);
        s.open[0] = true;
        assert_eq!(q.update(s, 0), register::GENERIC | register::CURRENT);
        assert_eq!(q.update(s, 0), 0x03, "no repeat while it persists");
        assert_eq!(q.len(), 1);
        s.open[0] = false;
        assert_eq!(q.update(s, 0), 0);
        assert_eq!(q.len(), 2);
        let mut out = [0u8; 16];
        assert_eq!(q.pop_into(&mut out), Some(10));
        assert_eq!(out[..2], [0x00, 0x10], "CoE service 1");
        assert_eq!(u16::from_le_bytes([out[2], out[3]]), 0xFF01);
        assert_eq!((out[4], out[5]), (0x03, 1));
        q.pop_into(&mut out).unwrap();
        assert_eq!(u16::from_le_bytes([out[2], out[3]]), 0x0000);
        assert!(q.is_empty());
    }

    #[test]
    fn a_full_queue_drops_the_oldest() {
        let mut q = Emergencies::default();
        for i in 0..(QUEUE_LEN as u16 + 3) {
            q.push(EmergencyRepr {
                error_code: i,
                error_register: 0,
                data: [0; 5],
            });
        }
        assert_eq!(q.len(), QUEUE_LEN);
        assert_eq!(q.dropped(), 3);
        let mut out = [0u8; 16];
        q.pop_into(&mut out).unwrap();
        assert_eq!(u16::from_le_bytes([out[2], out[3]]), 3, "oldest kept is #3");
    }

    #[test]
    fn error_register_bits_follow_the_faults() {
        let s = FaultState {
            undervoltage: true,
            overtemperature: true,
            ..Default::default()
        };
        assert_eq!(s.error_register(), 0x01 | 0x04 | 0x08);
        let s = FaultState {
            eeprom: true,
            watchdog: true,
            ..Default::default()
        };
        assert_eq!(s.error_register(), 0x01 | 0x10 | 0x80);
    }

    #[test]
    fn too_small_output_keeps_the_message() {
        let mut q = Emergencies::default();
        q.push(EmergencyRepr {
            error_code: 1,
            error_register: 0,
            data: [0; 5],
        });
        assert_eq!(q.pop_into(&mut [0u8; 4]), None);
        assert_eq!(q.len(), 1);
    }
}
