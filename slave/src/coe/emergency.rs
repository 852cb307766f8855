//! CoE Emergency (ETG.1000.6 5.6.4) and the error register 0x1001.
//!
//! The application raises its own emergencies (a fault appearing) and
//! states its error-register bits; the core adds what it sees itself and
//! keeps 0x1001 consistent:
//!
//! | condition | error code | register bit | data byte 0 |
//! |---|---|---|---|
//! | the application's faults | its codes | its bits | its data |
//! | SyncManager watchdog (OP left) | 0x8100 | communication (4) | AL code low byte |
//! | PRE-OP→SAFE-OP refused | 0xA000 | communication (4) | AL code (2 bytes) |
//! | PDI failure (firmware cannot reach its ESC) | 0x5000 (device hardware) | generic (0) | 1 out of range, 2 SM busy, 3 interface |
//! | every fault gone (register back to 0) | 0x0000 | 0 | |
//!
//! Bit 0 (generic error) of 0x1001 is set whenever any other bit is. The
//! queue holds [`QUEUE_LEN`] messages; when it is full the **oldest** is
//! dropped, so the master always sees the most recent condition. INIT
//! empties it ([`Emergencies::clear`]).

use crate::esc::EscError;
use crate::wire::coe::{CoeHeader, CoeService, Emergency, EmergencyRepr};

/// Messages held while the master has not read the mailbox.
pub const QUEUE_LEN: usize = 8;

/// Error register bits (0x1001, CiA 301).
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
    /// Device profile specific.
    pub const PROFILE: u8 = 0x20;
    /// Manufacturer specific.
    pub const MANUFACTURER: u8 = 0x80;
}

/// The emergency queue and the error register.
#[derive(Debug, Default)]
pub struct Emergencies {
    queue: heapless::Deque<EmergencyRepr, QUEUE_LEN>,
    dropped: u32,
    /// The application's register bits.
    app_bits: u8,
    /// The communication error the core saw at the last update.
    comm: bool,
    /// The register at the last update.
    last_register: u8,
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

    /// The error register as it stands (application bits, communication,
    /// generic).
    pub fn register(&self) -> u8 {
        let r = self.app_bits
            | if self.comm {
                register::COMMUNICATION
            } else {
                0
            };
        if r != 0 { r | register::GENERIC } else { 0 }
    }

    /// Sets the application's error-register bits (current, voltage,
    /// temperature, manufacturer, ...). Call before [`Self::raise`] so the
    /// message carries the new register.
    pub fn set_app_bits(&mut self, bits: u8) {
        self.app_bits = bits & !register::GENERIC;
    }

    /// Queues an application emergency with `code` and `data`, carrying
    /// the current register.
    pub fn raise(&mut self, code: u16, data: [u8; 5]) {
        let error_register = self.register();
        self.push(EmergencyRepr {
            error_code: code,
            error_register,
            data,
        });
    }

    /// The core's part of a poll: `comm` is the communication error (the SM
    /// watchdog took the device out of OP; `al_code` its AL status code).
    /// Queues 0x8100 when it appears and 0x0000 when the register falls
    /// back to 0. Returns the register for 0x1001.
    pub fn update(&mut self, comm: bool, al_code: u16) -> u8 {
        let rising = comm && !self.comm;
        self.comm = comm;
        if rising {
            self.raise(0x8100, [al_code as u8, 0, 0, 0, 0]);
        }
        let r = self.register();
        if r == 0 && self.last_register != 0 {
            self.raise(0x0000, [0; 5]);
        }
        self.last_register = r;
        r
    }

    /// Queues the refusal of a state transition (0xA000, AL code in data).
    pub fn transition_refused(&mut self, al_code: u16) {
        let mut e = EmergencyRepr {
            error_code: 0xA000,
            error_register: self.register() | register::GENERIC | register::COMMUNICATION,
            data: [0; 5],
        };
        let [lo, hi] = al_code.to_le_bytes();
        e.data[0] = lo;
        e.data[1] = hi;
        self.push(e);
    }

    /// Queues a PDI failure (0x5000 device hardware; data byte 0 says
    /// which: 1 access out of range, 2 SyncManager busy, 3 interface; for
    /// a bus error byte 1 gives its kind, [`BusErrorKind::code`]).
    ///
    /// [`BusErrorKind::code`]: crate::esc::BusErrorKind::code
    pub fn pdi_failure(&mut self, e: EscError) {
        let (kind, detail) = match e {
            EscError::OutOfRange { .. } => (1, 0),
            EscError::SmBusy { .. } => (2, 0),
            EscError::Interface => (3, 0),
            EscError::Bus(b) => (3, b.code()),
        };
        self.push(EmergencyRepr {
            error_code: 0x5000,
            error_register: self.register() | register::GENERIC,
            data: [kind, detail, 0, 0, 0],
        });
    }

    /// Drops every queued message (the mailbox stopped: INIT). The register
    /// state is kept, so a fault that persists is not reported again and
    /// 0x1001 stays as it is.
    pub fn clear(&mut self) {
        self.queue.clear();
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
#[allow(clippy::unwrap_used, clippy::indexing_slicing)]
mod tests {
    use super::*;

    fn code_of(out: &[u8]) -> u16 {
        u16::from_le_bytes([out[2], out[3]])
    }

    #[test]
    fn an_application_fault_and_its_clearing_give_one_message_and_a_reset() {
        let mut q = Emergencies::default();
        assert_eq!(q.update(false, 0), 0);
        q.set_app_bits(register::CURRENT);
        q.raise(0xFF01, [1, 0, 0, 0, 0]);
        assert_eq!(q.update(false, 0), register::GENERIC | register::CURRENT);
        assert_eq!(q.update(false, 0), 0x03, "no repeat while it persists");
        assert_eq!(q.len(), 1);
        q.set_app_bits(0);
        assert_eq!(q.update(false, 0), 0);
        assert_eq!(q.len(), 2);
        let mut out = [0u8; 16];
        assert_eq!(q.pop_into(&mut out), Some(10));
        assert_eq!(out[..2], [0x00, 0x10], "CoE service 1");
        assert_eq!(code_of(&out), 0xFF01);
        assert_eq!((out[4], out[5]), (0x03, 1));
        q.pop_into(&mut out).unwrap();
        assert_eq!(code_of(&out), 0x0000);
        assert!(q.is_empty());
    }

    #[test]
    fn the_sm_watchdog_raises_0x8100_with_the_communication_bit() {
        let mut q = Emergencies::default();
        assert_eq!(q.update(true, 0x1B), 0x11);
        assert_eq!(q.update(true, 0x1B), 0x11);
        let mut out = [0u8; 16];
        q.pop_into(&mut out).unwrap();
        assert_eq!((code_of(&out), out[4], out[5]), (0x8100, 0x11, 0x1B));
        assert!(q.is_empty(), "raised once");
        assert_eq!(q.update(false, 0), 0);
        q.pop_into(&mut out).unwrap();
        assert_eq!(code_of(&out), 0x0000, "reset when it clears");
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
        assert_eq!(code_of(&out), 3, "oldest kept is #3");
    }

    #[test]
    fn clear_empties_the_queue_but_keeps_the_register() {
        let mut q = Emergencies::default();
        q.set_app_bits(register::VOLTAGE);
        q.raise(0x3210, [0; 5]);
        q.update(false, 0);
        q.clear();
        assert!(q.is_empty());
        assert_eq!(
            q.update(false, 0),
            0x05,
            "register unchanged, no re-announce"
        );
        assert!(q.is_empty());
    }

    #[test]
    fn refusals_and_pdi_failures_carry_their_codes() {
        let mut q = Emergencies::default();
        q.transition_refused(0x001D);
        q.pdi_failure(EscError::Interface);
        let mut out = [0u8; 16];
        q.pop_into(&mut out).unwrap();
        assert_eq!((code_of(&out), out[5], out[6]), (0xA000, 0x1D, 0x00));
        assert_eq!(out[4] & 0x11, 0x11);
        q.pop_into(&mut out).unwrap();
        assert_eq!((code_of(&out), out[5]), (0x5000, 3));
    }

    #[test]
    fn a_bus_error_names_its_kind_in_the_second_data_byte() {
        let mut q = Emergencies::default();
        q.pdi_failure(EscError::Bus(crate::esc::BusErrorKind::ChipSelectFault));
        let mut out = [0u8; 16];
        q.pop_into(&mut out).unwrap();
        assert_eq!((code_of(&out), out[5], out[6]), (0x5000, 3, 4));
    }
}
