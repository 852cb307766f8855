//! # The UART link: SPI and flash of a board carried over a serial line
//!
//! An emulated board (QEMU's `mps2-an386`) has no ESC chip on an SPI bus,
//! but it has a UART. This module turns the UART into the board's SPI bus
//! and its flash: every SPI transaction (one chip-select cycle) and every
//! flash access becomes one framed request on the line, and a host
//! program at the other end (`board-bridge`) answers it, with the LAN9252
//! byte-level emulation of `ecat-esc-spi-emu` in front of a software ESC
//! for the SPI requests and a flash image kept in a file for the flash
//! requests. The firmware above the link is the board's: the LAN9252
//! driver of `ecat-esc-spi` runs unchanged on [`LinkSpi`], the IRQ input
//! is [`LinkIrq`], and the FoE image store is
//! [`NorImageStore`](crate::store::NorImageStore) on [`LinkFlash`].
//!
//! ## Framing
//!
//! The firmware is the only one that starts an exchange; every request
//! gets exactly one answer, whose first byte repeats the request's. All
//! integers are little-endian.
//!
//! | request (firmware → bridge) | answer (bridge → firmware) |
//! |---|---|
//! | `'S'` len:u16 skip:u16 keep:u16 mosi\[len\] | `'S'` status:u8 irq:u8 miso\[keep\] (bytes skip..skip+keep of the cycle) |
//! | `'R'` addr:u32 len:u16 | `'R'` status:u8 data\[len\] (no data if status ≠ 0) |
//! | `'W'` addr:u32 len:u16 data\[len\] | `'W'` status:u8 |
//! | `'E'` addr:u32 count:u16 | `'E'` status:u8 (count sectors of [`FLASH_SECTOR`] bytes erased to 0xFF) |
//!
//! `'S'` is one chip-select cycle: the frame boundary is the chip select.
//! `len` bytes are clocked out; the answer carries only the MISO bytes the
//! transaction reads (`skip` leading bytes and everything after
//! `skip + keep` are clocked but not sent back), so a write costs no bytes
//! back. `irq` is the chip's IRQ output after the cycle (1 = asserted).
//!
//! Between two exchanges the bridge may send `'I'` irq:u8 on its own when
//! the IRQ output of the chip becomes asserted (an EtherCAT frame raised
//! an AL event): the board's IRQ line. The firmware takes such notices
//! whenever it reads the line, also while it waits for an answer.
//!
//! Status 0 is success; anything else is an error ([`LinkError::Refused`]):
//! an address outside the flash, a length over [`MAX_TRANSFER`], a
//! program of bits from 0 to 1. A byte that starts no known answer is a
//! [`LinkError::Framing`] error; no answer within [`ANSWER_TIMEOUT_NS`]
//! is [`LinkError::Timeout`]. The LAN9252 driver then reports an SPI bus
//! error and the core's firmware loop goes to its fail-safe state, as
//! with a broken wire.
//!
//! The answerer side of the framing (for the bridge, and for tests) is
//! [`Request::parse`] and the `encode_*` functions.

use core::cell::RefCell;

use embedded_hal::digital;
use embedded_hal::spi::{self, Operation, SpiDevice};
use embedded_storage::nor_flash::{
    ErrorType as FlashErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// Request/answer code of an SPI transaction.
pub const SPI: u8 = b'S';
/// Request/answer code of a flash read.
pub const FLASH_READ: u8 = b'R';
/// Request/answer code of a flash program.
pub const FLASH_WRITE: u8 = b'W';
/// Request/answer code of a flash sector erase.
pub const FLASH_ERASE: u8 = b'E';
/// Code of the bridge's unsolicited IRQ notice.
pub const IRQ_NOTICE: u8 = b'I';

/// Erase unit of the link flash (the bridge's flash image), bytes.
pub const FLASH_SECTOR: u32 = 4096;
/// Longest SPI cycle or flash transfer of one request, bytes.
pub const MAX_TRANSFER: usize = 1024;
/// How long the firmware waits for an answer before it calls the line
/// broken (1 s: the bridge answers in microseconds, but an emulator on a
/// busy machine may not be scheduled for a while).
pub const ANSWER_TIMEOUT_NS: u64 = 1_000_000_000;

/// What the firmware's UART offers the link.
pub trait Serial {
    /// Sends one byte (waits while the transmitter is full).
    fn write(&mut self, byte: u8);
    /// The next received byte, if one is waiting (does not wait).
    fn read(&mut self) -> Option<u8>;
    /// Called while an answer is awaited and no byte is waiting: the
    /// firmware may sleep until the next interrupt (a received byte or
    /// its tick); a host test may do nothing.
    fn wait(&mut self) {}
}

/// Why an exchange over the link failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkError {
    /// No answer in time.
    Timeout,
    /// The answer did not fit the request (wrong code).
    Framing,
    /// The bridge refused the request (status byte).
    Refused(u8),
    /// The request is longer than [`MAX_TRANSFER`] or its fields overflow.
    TooLong,
    /// The link was in use (a nested access through another handle).
    Busy,
}

impl spi::Error for LinkError {
    fn kind(&self) -> spi::ErrorKind {
        spi::ErrorKind::Other
    }
}

impl NorFlashError for LinkError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            LinkError::TooLong => NorFlashErrorKind::OutOfBounds,
            _ => NorFlashErrorKind::Other,
        }
    }
}

/// Counters of the link, as the firmware saw it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// SPI transactions completed.
    pub spi: u32,
    /// Flash requests completed.
    pub flash: u32,
    /// IRQ notices received.
    pub notices: u32,
    /// Exchanges that failed.
    pub errors: u32,
}

/// The firmware end of the link: a [`Serial`] port, the IRQ level last
/// reported and a clock for the answer timeout.
pub struct Link<S: Serial> {
    serial: S,
    now_ns: fn() -> u64,
    irq: bool,
    stats: LinkStats,
}

impl<S: Serial> Link<S> {
    /// The link on `serial`, with the board's monotonic clock `now_ns`
    /// for the answer timeout. The IRQ line starts asserted, so the first
    /// pass of the firmware runs at once.
    pub fn new(serial: S, now_ns: fn() -> u64) -> Self {
        Link {
            serial,
            now_ns,
            irq: true,
            stats: LinkStats::default(),
        }
    }

    /// The serial port.
    pub fn serial_mut(&mut self) -> &mut S {
        &mut self.serial
    }

    /// What the link counted.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// Whether the chip's IRQ output is asserted, after taking every
    /// notice already received.
    pub fn irq(&mut self) -> bool {
        while let Some(b) = self.serial.read() {
            if b == IRQ_NOTICE {
                // A notice is two bytes; the second follows at once.
                if let Ok(level) = self.next_byte() {
                    self.irq = level != 0;
                    self.stats.notices = self.stats.notices.wrapping_add(1);
                }
            }
            // Any other byte between exchanges is a stray answer of an
            // exchange that timed out: dropped.
        }
        self.irq
    }

    fn send(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.serial.write(b);
        }
    }

    fn next_byte(&mut self) -> Result<u8, LinkError> {
        let start = (self.now_ns)();
        loop {
            if let Some(b) = self.serial.read() {
                return Ok(b);
            }
            if (self.now_ns)().saturating_sub(start) > ANSWER_TIMEOUT_NS {
                return Err(LinkError::Timeout);
            }
            self.serial.wait();
        }
    }

    /// Reads up to the answer to `code` (taking IRQ notices on the way)
    /// and its status byte.
    fn answer(&mut self, code: u8) -> Result<(), LinkError> {
        loop {
            let b = self.next_byte()?;
            if b == IRQ_NOTICE {
                self.irq = self.next_byte()? != 0;
                self.stats.notices = self.stats.notices.wrapping_add(1);
                continue;
            }
            if b != code {
                return Err(LinkError::Framing);
            }
            return match self.next_byte()? {
                0 => Ok(()),
                s => Err(LinkError::Refused(s)),
            };
        }
    }

    fn counted<T>(&mut self, r: Result<T, LinkError>, spi: bool) -> Result<T, LinkError> {
        match (&r, spi) {
            (Ok(_), true) => self.stats.spi = self.stats.spi.wrapping_add(1),
            (Ok(_), false) => self.stats.flash = self.stats.flash.wrapping_add(1),
            (Err(_), _) => self.stats.errors = self.stats.errors.wrapping_add(1),
        }
        r
    }

    /// One SPI transaction (chip-select cycle) over the link.
    pub fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), LinkError> {
        let r = self.transaction_inner(ops);
        self.counted(r, true)
    }

    fn transaction_inner(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), LinkError> {
        let (len, skip, keep) = cycle_shape(ops).ok_or(LinkError::TooLong)?;
        let [l0, l1] = len.to_le_bytes();
        let [s0, s1] = skip.to_le_bytes();
        let [k0, k1] = keep.to_le_bytes();
        self.send(&[SPI, l0, l1, s0, s1, k0, k1]);
        for op in ops.iter() {
            match op {
                Operation::Write(w) => self.send(w),
                Operation::Transfer(r, w) => {
                    let n = r.len().max(w.len());
                    for k in 0..n {
                        self.serial.write(w.get(k).copied().unwrap_or(0));
                    }
                }
                Operation::TransferInPlace(b) => self.send(b),
                Operation::Read(r) => {
                    for _ in 0..r.len() {
                        self.serial.write(0);
                    }
                }
                Operation::DelayNs(_) => {}
            }
        }
        self.answer(SPI)?;
        self.irq = self.next_byte()? != 0;
        // MISO bytes skip..skip+keep, into the operations that read.
        let window = usize::from(skip)..usize::from(skip) + usize::from(keep);
        let mut pos = 0usize;
        for op in ops.iter_mut() {
            let (clocked, reads): (usize, &mut [u8]) = match op {
                Operation::Write(w) => (w.len(), &mut []),
                Operation::Transfer(r, w) => (r.len().max(w.len()), r),
                Operation::TransferInPlace(b) => (b.len(), b),
                Operation::Read(r) => (r.len(), r),
                Operation::DelayNs(_) => (0, &mut []),
            };
            for k in 0..clocked {
                if window.contains(&(pos + k)) {
                    let b = self.next_byte()?;
                    if let Some(slot) = reads.get_mut(k) {
                        *slot = b;
                    }
                }
            }
            pos += clocked;
        }
        Ok(())
    }

    fn flash_header(&mut self, code: u8, addr: u32, len: u16) {
        let [a0, a1, a2, a3] = addr.to_le_bytes();
        let [l0, l1] = len.to_le_bytes();
        self.send(&[code, a0, a1, a2, a3, l0, l1]);
    }

    /// Reads `buf.len()` bytes of the link flash at `addr`.
    pub fn flash_read(&mut self, addr: u32, buf: &mut [u8]) -> Result<(), LinkError> {
        let mut r = Ok(());
        for (k, chunk) in buf.chunks_mut(MAX_TRANSFER).enumerate() {
            let at = offset_of(addr, k);
            r = at.and_then(|at| {
                let len = u16::try_from(chunk.len()).map_err(|_| LinkError::TooLong)?;
                self.flash_header(FLASH_READ, at, len);
                self.answer(FLASH_READ)?;
                for b in chunk.iter_mut() {
                    *b = self.next_byte()?;
                }
                Ok(())
            });
            if r.is_err() {
                break;
            }
        }
        self.counted(r, false)
    }

    /// Programs `data` into the link flash at `addr` (NOR rules: bits go
    /// from 1 to 0 only; the bridge refuses anything else).
    pub fn flash_write(&mut self, addr: u32, data: &[u8]) -> Result<(), LinkError> {
        let mut r = Ok(());
        for (k, chunk) in data.chunks(MAX_TRANSFER).enumerate() {
            r = offset_of(addr, k).and_then(|at| {
                let len = u16::try_from(chunk.len()).map_err(|_| LinkError::TooLong)?;
                self.flash_header(FLASH_WRITE, at, len);
                self.send(chunk);
                self.answer(FLASH_WRITE)
            });
            if r.is_err() {
                break;
            }
        }
        self.counted(r, false)
    }

    /// Erases `count` sectors of [`FLASH_SECTOR`] bytes from `addr` (a
    /// sector boundary).
    pub fn flash_erase(&mut self, addr: u32, count: u16) -> Result<(), LinkError> {
        self.flash_header(FLASH_ERASE, addr, count);
        let r = self.answer(FLASH_ERASE);
        self.counted(r, false)
    }
}

/// `addr` plus `k` chunks of [`MAX_TRANSFER`] bytes.
fn offset_of(addr: u32, k: usize) -> Result<u32, LinkError> {
    k.checked_mul(MAX_TRANSFER)
        .and_then(|o| u32::try_from(o).ok())
        .and_then(|o| addr.checked_add(o))
        .ok_or(LinkError::TooLong)
}

/// Total clocked bytes of a transaction, and the range of them that
/// reads (skip, keep): from the first reading operation to the end of the
/// last one. `None` if longer than [`MAX_TRANSFER`].
fn cycle_shape(ops: &[Operation<'_, u8>]) -> Option<(u16, u16, u16)> {
    let mut pos = 0usize;
    let mut first: Option<usize> = None;
    let mut last = 0usize;
    for op in ops {
        let (n, reads) = match op {
            Operation::Write(w) => (w.len(), 0),
            Operation::Transfer(r, w) => (r.len().max(w.len()), r.len()),
            Operation::TransferInPlace(b) => (b.len(), b.len()),
            Operation::Read(r) => (r.len(), r.len()),
            Operation::DelayNs(_) => (0, 0),
        };
        if reads > 0 {
            first.get_or_insert(pos);
            last = pos + reads;
        }
        pos += n;
    }
    if pos > MAX_TRANSFER {
        return None;
    }
    let skip = first.unwrap_or(pos);
    let keep = last.saturating_sub(skip);
    Some((
        u16::try_from(pos).ok()?,
        u16::try_from(skip).ok()?,
        u16::try_from(keep).ok()?,
    ))
}

/// The ESC's SPI bus with its chip select, over the link: an
/// `embedded-hal` [`SpiDevice`] for the unchanged PDI driver.
pub struct LinkSpi<'a, S: Serial> {
    link: &'a RefCell<Link<S>>,
}

impl<'a, S: Serial> LinkSpi<'a, S> {
    /// The SPI device on `link`.
    pub fn new(link: &'a RefCell<Link<S>>) -> Self {
        LinkSpi { link }
    }
}

impl<S: Serial> spi::ErrorType for LinkSpi<'_, S> {
    type Error = LinkError;
}

impl<S: Serial> SpiDevice for LinkSpi<'_, S> {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), LinkError> {
        self.link
            .try_borrow_mut()
            .map_err(|_| LinkError::Busy)?
            .transaction(ops)
    }
}

/// The chip's IRQ output as an input pin, low while asserted (the driver
/// programs the LAN9252's IRQ active low), from the link's notices and
/// answers.
pub struct LinkIrq<'a, S: Serial> {
    link: &'a RefCell<Link<S>>,
}

impl<'a, S: Serial> LinkIrq<'a, S> {
    /// The IRQ pin on `link`.
    pub fn new(link: &'a RefCell<Link<S>>) -> Self {
        LinkIrq { link }
    }
}

impl<S: Serial> digital::ErrorType for LinkIrq<'_, S> {
    type Error = core::convert::Infallible;
}

impl<S: Serial> digital::InputPin for LinkIrq<'_, S> {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        self.is_low().map(|low| !low)
    }

    fn is_low(&mut self) -> Result<bool, Self::Error> {
        // Link in use: count the line as asserted (poll rather than miss).
        Ok(self.link.try_borrow_mut().map_or(true, |mut l| l.irq()))
    }
}

/// The bridge's flash image over the link, as a NOR flash of `capacity`
/// bytes in sectors of [`FLASH_SECTOR`] bytes, programmable bytewise.
pub struct LinkFlash<'a, S: Serial> {
    link: &'a RefCell<Link<S>>,
    capacity: u32,
}

impl<'a, S: Serial> LinkFlash<'a, S> {
    /// The first `capacity` bytes of the bridge's flash (a multiple of
    /// [`FLASH_SECTOR`]).
    pub fn new(link: &'a RefCell<Link<S>>, capacity: u32) -> Self {
        LinkFlash { link, capacity }
    }

    fn check(&self, offset: u32, len: usize) -> Result<(), LinkError> {
        let len = u32::try_from(len).map_err(|_| LinkError::TooLong)?;
        match offset.checked_add(len) {
            Some(end) if end <= self.capacity => Ok(()),
            _ => Err(LinkError::TooLong),
        }
    }
}

impl<S: Serial> FlashErrorType for LinkFlash<'_, S> {
    type Error = LinkError;
}

impl<S: Serial> ReadNorFlash for LinkFlash<'_, S> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), LinkError> {
        self.check(offset, bytes.len())?;
        self.link
            .try_borrow_mut()
            .map_err(|_| LinkError::Busy)?
            .flash_read(offset, bytes)
    }

    fn capacity(&self) -> usize {
        self.capacity as usize
    }
}

impl<S: Serial> NorFlash for LinkFlash<'_, S> {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = FLASH_SECTOR as usize;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), LinkError> {
        if !from.is_multiple_of(FLASH_SECTOR)
            || !to.is_multiple_of(FLASH_SECTOR)
            || to < from
            || to > self.capacity
        {
            return Err(LinkError::TooLong);
        }
        let count = u16::try_from((to - from) / FLASH_SECTOR).map_err(|_| LinkError::TooLong)?;
        if count == 0 {
            return Ok(());
        }
        self.link
            .try_borrow_mut()
            .map_err(|_| LinkError::Busy)?
            .flash_erase(from, count)
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), LinkError> {
        self.check(offset, bytes.len())?;
        self.link
            .try_borrow_mut()
            .map_err(|_| LinkError::Busy)?
            .flash_write(offset, bytes)
    }
}

/// A request as the bridge receives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Request<'a> {
    /// One chip-select cycle: clock out `mosi`, send back MISO bytes
    /// `skip..skip + keep`.
    Spi {
        /// The bytes clocked out.
        mosi: &'a [u8],
        /// Leading MISO bytes not sent back.
        skip: usize,
        /// MISO bytes sent back.
        keep: usize,
    },
    /// Read `len` bytes of flash at `addr`.
    FlashRead {
        /// Flash address.
        addr: u32,
        /// Byte count.
        len: usize,
    },
    /// Program `data` at `addr`.
    FlashWrite {
        /// Flash address.
        addr: u32,
        /// The bytes.
        data: &'a [u8],
    },
    /// Erase `count` sectors from `addr`.
    FlashErase {
        /// Flash address (a sector boundary).
        addr: u32,
        /// Sector count.
        count: u16,
    },
}

/// Why [`Request::parse`] took no request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParseError {
    /// More bytes are needed (at least this many in all).
    Incomplete(usize),
    /// The first byte is no request code.
    UnknownCode(u8),
    /// A length over [`MAX_TRANSFER`], or skip + keep beyond the cycle.
    BadLength,
}

fn u16_at(buf: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes([*buf.get(at)?, *buf.get(at + 1)?]))
}

fn u32_at(buf: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes([
        *buf.get(at)?,
        *buf.get(at + 1)?,
        *buf.get(at + 2)?,
        *buf.get(at + 3)?,
    ]))
}

/// Bytes of a request header (code and fields).
pub const HEADER_LEN: usize = 7;

impl<'a> Request<'a> {
    /// Parses the request at the start of `buf`: the request and its
    /// length in bytes.
    pub fn parse(buf: &'a [u8]) -> Result<(Request<'a>, usize), ParseError> {
        let code = *buf.first().ok_or(ParseError::Incomplete(1))?;
        if ![SPI, FLASH_READ, FLASH_WRITE, FLASH_ERASE].contains(&code) {
            return Err(ParseError::UnknownCode(code));
        }
        if buf.len() < HEADER_LEN {
            return Err(ParseError::Incomplete(HEADER_LEN));
        }
        let need = |n: usize| -> Result<&'a [u8], ParseError> {
            if n > MAX_TRANSFER {
                return Err(ParseError::BadLength);
            }
            buf.get(HEADER_LEN..HEADER_LEN + n)
                .ok_or(ParseError::Incomplete(HEADER_LEN + n))
        };
        let field16 = |at| u16_at(buf, at).map(usize::from).unwrap_or(0);
        let addr = u32_at(buf, 1).unwrap_or(0);
        match code {
            SPI => {
                let (len, skip, keep) = (field16(1), field16(3), field16(5));
                if skip.checked_add(keep).is_none_or(|e| e > len) {
                    return Err(ParseError::BadLength);
                }
                let mosi = need(len)?;
                Ok((Request::Spi { mosi, skip, keep }, HEADER_LEN + len))
            }
            FLASH_READ => {
                let len = field16(5);
                if len > MAX_TRANSFER {
                    return Err(ParseError::BadLength);
                }
                Ok((Request::FlashRead { addr, len }, HEADER_LEN))
            }
            FLASH_WRITE => {
                let data = need(field16(5))?;
                Ok((Request::FlashWrite { addr, data }, HEADER_LEN + data.len()))
            }
            _ => {
                let count = u16_at(buf, 5).unwrap_or(0);
                Ok((Request::FlashErase { addr, count }, HEADER_LEN))
            }
        }
    }

    /// The code its answer starts with.
    pub fn code(&self) -> u8 {
        match self {
            Request::Spi { .. } => SPI,
            Request::FlashRead { .. } => FLASH_READ,
            Request::FlashWrite { .. } => FLASH_WRITE,
            Request::FlashErase { .. } => FLASH_ERASE,
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::collections::VecDeque;
    use std::vec::Vec;

    /// A serial port whose far end answers every request with `answer`.
    struct Loop {
        sent: Vec<u8>,
        inbox: VecDeque<u8>,
        answer: fn(&Request<'_>) -> Vec<u8>,
    }

    impl Serial for Loop {
        fn write(&mut self, byte: u8) {
            self.sent.push(byte);
            if let Ok((req, n)) = Request::parse(&self.sent) {
                let a = (self.answer)(&req);
                self.inbox.extend(a);
                self.sent.drain(..n);
            }
        }
        fn read(&mut self) -> Option<u8> {
            self.inbox.pop_front()
        }
    }

    fn clock() -> u64 {
        0
    }

    /// MISO = MOSI + 1, so a test sees which bytes came back.
    fn echo_plus_one(req: &Request<'_>) -> Vec<u8> {
        match req {
            Request::Spi { mosi, skip, keep } => {
                let mut a = std::vec![SPI, 0, 1];
                a.extend(mosi[*skip..skip + keep].iter().map(|b| b.wrapping_add(1)));
                a
            }
            _ => std::vec![req.code(), 7],
        }
    }

    #[test]
    fn a_read_transaction_sends_every_mosi_byte_and_gets_back_only_the_read_part() {
        let link = RefCell::new(Link::new(
            Loop {
                sent: Vec::new(),
                inbox: VecDeque::new(),
                answer: echo_plus_one,
            },
            clock,
        ));
        let mut spi = LinkSpi::new(&link);
        let mut data = [0x10, 0x20, 0x30, 0x40];
        spi.transaction(&mut [
            Operation::Write(&[0x0B, 0x00, 0x64, 0x00]),
            Operation::TransferInPlace(&mut data),
        ])
        .expect("answered");
        assert_eq!(data, [0x11, 0x21, 0x31, 0x41]);
        let l = link.borrow();
        assert_eq!(l.stats().spi, 1);
        assert!(l.serial.sent.is_empty(), "the whole request was consumed");
    }

    #[test]
    fn the_cycle_shape_skips_leading_and_trailing_writes() {
        let mut r = [0u8; 4];
        let ops = [
            Operation::Write(&[1, 2, 3]),
            Operation::Read(&mut r),
            Operation::Write(&[9]),
        ];
        assert_eq!(cycle_shape(&ops), Some((8, 3, 4)));
        assert_eq!(
            cycle_shape(&[Operation::Write(&[1, 2])]),
            Some((2, 2, 0)),
            "a write reads nothing back"
        );
        let big = [0u8; MAX_TRANSFER + 1];
        assert_eq!(cycle_shape(&[Operation::Write(&big)]), None);
    }

    #[test]
    fn an_irq_notice_before_the_answer_sets_the_line() {
        fn notice_then_answer(req: &Request<'_>) -> Vec<u8> {
            let mut a = std::vec![IRQ_NOTICE, 1];
            if let Request::Spi { keep, .. } = req {
                a.extend([SPI, 0, 1]);
                a.extend(std::iter::repeat_n(0xEE, *keep));
            }
            a
        }
        let link = RefCell::new(Link::new(
            Loop {
                sent: Vec::new(),
                inbox: VecDeque::new(),
                answer: notice_then_answer,
            },
            clock,
        ));
        let mut b = [0u8; 2];
        LinkSpi::new(&link)
            .transaction(&mut [Operation::Read(&mut b)])
            .expect("answered");
        assert_eq!(b, [0xEE, 0xEE]);
        let mut irq = LinkIrq::new(&link);
        use embedded_hal::digital::InputPin;
        assert!(irq.is_low().expect("pin"), "asserted = low");
        link.borrow_mut().serial.inbox.extend([IRQ_NOTICE, 0]);
        assert!(irq.is_high().expect("pin"), "released by a notice");
    }

    #[test]
    fn a_refused_flash_request_and_a_wrong_answer_are_errors() {
        let link = RefCell::new(Link::new(
            Loop {
                sent: Vec::new(),
                inbox: VecDeque::new(),
                answer: echo_plus_one,
            },
            clock,
        ));
        let mut flash = LinkFlash::new(&link, 2 * FLASH_SECTOR);
        assert_eq!(flash.erase(0, FLASH_SECTOR), Err(LinkError::Refused(7)));
        assert_eq!(flash.erase(1, FLASH_SECTOR), Err(LinkError::TooLong));
        assert_eq!(
            flash.write(2 * FLASH_SECTOR - 1, &[0, 0]),
            Err(LinkError::TooLong),
            "beyond the capacity, not sent"
        );
        fn wrong(_: &Request<'_>) -> Vec<u8> {
            std::vec![b'X', 0]
        }
        link.borrow_mut().serial.answer = wrong;
        let mut b = [0u8; 1];
        assert_eq!(flash.read(0, &mut b), Err(LinkError::Framing));
        assert_eq!(
            link.borrow().stats().errors,
            2,
            "checked requests never reach the line"
        );
    }

    #[test]
    fn no_answer_is_a_timeout() {
        use core::sync::atomic::{AtomicU64, Ordering};
        static T: AtomicU64 = AtomicU64::new(0);
        fn ticking() -> u64 {
            T.fetch_add(100_000_000, Ordering::Relaxed)
        }
        fn silent(_: &Request<'_>) -> Vec<u8> {
            Vec::new()
        }
        let link = RefCell::new(Link::new(
            Loop {
                sent: Vec::new(),
                inbox: VecDeque::new(),
                answer: silent,
            },
            ticking,
        ));
        let mut b = [0u8; 1];
        assert_eq!(
            LinkSpi::new(&link).transaction(&mut [Operation::Read(&mut b)]),
            Err(LinkError::Timeout)
        );
    }

    #[test]
    fn requests_parse_from_their_bytes_and_bad_lengths_are_refused() {
        let spi = [SPI, 3, 0, 1, 0, 2, 0, 0xA, 0xB, 0xC];
        assert_eq!(
            Request::parse(&spi),
            Ok((
                Request::Spi {
                    mosi: &[0xA, 0xB, 0xC],
                    skip: 1,
                    keep: 2
                },
                10
            ))
        );
        assert_eq!(Request::parse(&spi[..8]), Err(ParseError::Incomplete(10)));
        assert_eq!(
            Request::parse(&[SPI, 3, 0, 2, 0, 2, 0]),
            Err(ParseError::BadLength),
            "skip + keep beyond the cycle"
        );
        assert_eq!(
            Request::parse(&[FLASH_ERASE, 0, 0x10, 0, 0, 2, 0]),
            Ok((
                Request::FlashErase {
                    addr: 0x1000,
                    count: 2
                },
                7
            ))
        );
        assert_eq!(
            Request::parse(&[FLASH_READ, 0, 0, 0, 0, 0xFF, 0xFF]),
            Err(ParseError::BadLength)
        );
        assert_eq!(Request::parse(&[0x42]), Err(ParseError::UnknownCode(0x42)));
        assert_eq!(Request::parse(&[]), Err(ParseError::Incomplete(1)));
    }
}
