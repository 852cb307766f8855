//! What the manuals say about the telegrams beyond their layout: limits,
//! address ranges, when the node answers and which module answers a CMD 15.
//!
//! The codec itself enforces only what decides a telegram's length or
//! cannot be encoded (word count, CNT, SNUM, the CMD 15 SADR); the rest is
//! left to the device, which answers with an exception (e.g. an unknown
//! parameter ID with exception 2, "Wrong ID").

use super::request::RequestRepr;

pub use super::limits::{MAX_READ_CNT, MAX_READ_WORDS, MODULE_ADDRESSES, SADR_RANGE};

/// Highest parameter ID in the DMA-22(A) parameter list (chapter 7, table
/// 5: 0x109 = L2.y8). The list has gaps (reserved IDs), and the Profibus
/// manual of the older DMA states smaller ranges (0x00A2, 0x00B0; see
/// `NOTES.md`), so this is an upper bound, not a membership test: the
/// module answers IDs it does not have with exception 2, "Wrong ID".
pub const PARAMETER_ID_MAX: u16 = 0x109;

/// Whether `id` is within the DMA-22(A) parameter list (0..=0x109, see
/// [`PARAMETER_ID_MAX`]).
pub const fn is_parameter_id(id: u16) -> bool {
    id <= PARAMETER_ID_MAX
}

/// Whether a CMD 3 of `words` words from `id` is a valid read of the
/// DMA-22(A) list: 1..=8 words ([`MAX_READ_WORDS`]) and the last ID,
/// `id + words - 1`, within [`PARAMETER_ID_MAX`] (3.4: "parameter-ID in
/// rising order").
pub const fn is_valid_read(id: u16, words: u16) -> bool {
    if words == 0 || words > MAX_READ_WORDS {
        return false;
    }
    match id.checked_add(words - 1) {
        Some(last) => last <= PARAMETER_ID_MAX,
        None => false,
    }
}

/// The TADR rule (3.3; 5.4.2): the node answers only a request that
/// differs from the previous one, so the master changes TADR to force an
/// answer ("TADR can be used to force a response from a slave … even if
/// the other data in the message remain unchanged").
///
/// The gate compares decoded requests, so filler bytes after the telegram
/// do not count as a change (see `NOTES.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ResponseGate {
    last: Option<RequestRepr>,
}

impl ResponseGate {
    /// A gate that has seen no request: the first one is answered.
    pub const fn new() -> Self {
        Self { last: None }
    }

    /// Records `request` and returns whether the node answers it: the
    /// first request and every request that differs from the previous one
    /// in any field (TADR included).
    pub fn admit(&mut self, request: &RequestRepr) -> bool {
        let due = self.last.as_ref() != Some(request);
        self.last = Some(*request);
        due
    }

    /// The last request seen.
    pub const fn last(&self) -> Option<&RequestRepr> {
        self.last.as_ref()
    }

    /// Forgets the last request (e.g. after a communication restart).
    pub const fn reset(&mut self) {
        self.last = None;
    }
}

/// The CMD 15 answer multiplexer of the node (5.2; 5.4.2): each answered
/// CMD 15 carries the data of the next module in E22 order, 1, 2, …,
/// SNUM, then 1 again ("When using 3 slaves than the slave with the module
/// address „1“ (E22 = 1) will respond first. After the next „Master-Write“
/// the slave with module address „2“ … Then it starts again with slave
/// „1“").
///
/// Advance it only for requests the [`ResponseGate`] lets through. If SNUM
/// shrinks below the next module, the sequence restarts at module 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Multiplexer {
    next: u8,
}

impl Default for Multiplexer {
    fn default() -> Self {
        Self::new()
    }
}

impl Multiplexer {
    /// A multiplexer that answers with module 1 first.
    pub const fn new() -> Self {
        Self { next: 1 }
    }

    /// The module (SADR) whose data the next response carries for a
    /// request with `snum` modules, without advancing; `None` unless
    /// `snum` is 1..=5.
    pub const fn peek(&self, snum: u8) -> Option<u8> {
        if snum == 0 || snum > *MODULE_ADDRESSES.end() {
            None
        } else if self.next >= 1 && self.next <= snum {
            Some(self.next)
        } else {
            Some(1)
        }
    }

    /// Like [`Multiplexer::peek`], and moves on to the following module.
    pub const fn next_sadr(&mut self, snum: u8) -> Option<u8> {
        let sadr = self.peek(snum);
        if let Some(sadr) = sadr {
            self.next = sadr.saturating_add(1);
        }
        sadr
    }

    /// Starts again with module 1.
    pub const fn reset(&mut self) {
        self.next = 1;
    }
}

/// Bits of the CMD 15 control byte DATx.1 that mean the same in every
/// operation mode (5.5.2 to 5.5.6, "Byte for special functions"; "Can be
/// set only if the hardware enable is active"). The other bits depend on
/// the mode (Din_1 0x01 and Din_2 0x10 in the closed-loop modes, CNTRL_1..4
/// reserved).
pub mod control {
    /// 0x04, TST_CMP: drive the Error/Comp output to 24 V.
    pub const TST_CMP: u8 = 0x04;
    /// 0x80, BUS_DISABLE: disable the module over the bus (setting and
    /// resetting it also acknowledges an error, 5.5.1.1).
    pub const BUS_DISABLE: u8 = 0x80;
}

/// Bits of the CMD 15 status word (DAT.1H in the high byte) as the mode
/// tables of 5.5.2 to 5.5.6 give them. The low byte holds the error
/// number when `ERROR` is set (5.5.1.1, table 3), mode-dependent flags
/// otherwise.
///
/// The byte examples of 5.4.1 and 5.4.2 show DAT.1H = 0x40 for "Hardware
/// Enable is active", which these tables call STAT_5 (reserved); see
/// `NOTES.md`.
pub mod status {
    /// 0x0100, digital input SP1 active.
    pub const SP1: u16 = 0x0100;
    /// 0x0200, digital input SP2 active.
    pub const SP2: u16 = 0x0200;
    /// 0x0400, HW_ENABLE: hardware enable active.
    pub const HW_ENABLE: u16 = 0x0400;
    /// 0x0800, ERROR: an error is pending; the low byte is its number.
    pub const ERROR: u16 = 0x0800;
    /// 0x1000, digital input SP3 active.
    pub const SP3: u16 = 0x1000;
    /// 0x2000, digital input SP4 active.
    pub const SP4: u16 = 0x2000;
    /// 0x4000, STAT_5 (reserved).
    pub const STAT_5: u16 = 0x4000;
    /// 0x8000, BUS_DISABLE is set.
    pub const BUS_DISABLE: u16 = 0x8000;
}

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::*;
    use crate::telegram::{ModuleOutput, MultiWriteRequest, ReadRequest, WriteParameter};

    #[test]
    fn read_limits() {
        assert!(is_valid_read(0, 1));
        assert!(is_valid_read(0x102, 8));
        assert!(!is_valid_read(0x103, 8));
        assert!(!is_valid_read(0, 0));
        assert!(!is_valid_read(0, 9));
        assert!(!is_valid_read(u16::MAX, 2));
        assert!(is_parameter_id(0x109));
        assert!(!is_parameter_id(0x10A));
        assert_eq!(u16::from(MAX_READ_CNT), MAX_READ_WORDS * 2);
    }

    #[test]
    fn gate_answers_the_first_request_and_every_change() {
        let read = RequestRepr::Read(ReadRequest {
            tadr: 1,
            sadr: 1,
            id: 0,
            words: 1,
        });
        let mut gate = ResponseGate::new();
        assert!(gate.admit(&read));
        assert!(!gate.admit(&read));
        assert!(!gate.admit(&read));
        assert_eq!(gate.last(), Some(&read));
        // Changing only TADR forces an answer.
        let RequestRepr::Read(mut next) = read else {
            unreachable!()
        };
        next.tadr = 2;
        assert!(gate.admit(&RequestRepr::Read(next)));
        // Changing data does too.
        let write = RequestRepr::Write(WriteParameter {
            tadr: 2,
            sadr: 1,
            id: 0x27,
            value: 0,
        });
        assert!(gate.admit(&write));
        gate.reset();
        assert!(gate.admit(&write));
    }

    #[test]
    fn multiplexer_cycles_in_e22_order() {
        let mut mux = Multiplexer::default();
        let order: [Option<u8>; 7] = core::array::from_fn(|_| mux.next_sadr(3));
        assert_eq!(order, [1, 2, 3, 1, 2, 3, 1].map(Some));
        assert_eq!(mux.peek(3), Some(2));
        // SNUM shrinks below the next module: back to 1.
        assert_eq!(mux.next_sadr(1), Some(1));
        assert_eq!(mux.next_sadr(1), Some(1));
        assert_eq!(mux.next_sadr(0), None);
        assert_eq!(mux.next_sadr(6), None);
        mux.next_sadr(5);
        mux.reset();
        assert_eq!(mux.peek(5), Some(1));
    }

    #[test]
    fn gate_and_multiplexer_together() {
        // Unchanged requests get no answer and do not advance the
        // multiplexer.
        let mut request = MultiWriteRequest::new(0x23, &[ModuleOutput::default(); 2]).unwrap();
        let mut gate = ResponseGate::new();
        let mut mux = Multiplexer::new();
        let mut answered = [0u8; 4];
        let mut n = 0;
        for tadr in [0x23, 0x23, 0x24, 0x24, 0x25, 0x26] {
            request.set_tadr(tadr);
            if gate.admit(&RequestRepr::MultiWrite(request)) {
                answered[n] = mux.next_sadr(request.snum()).unwrap();
                n += 1;
            }
        }
        assert_eq!(answered, [1, 2, 1, 2]);
    }
}
