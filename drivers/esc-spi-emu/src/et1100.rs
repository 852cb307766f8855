//! Byte-level emulation of the Beckhoff ET1100/ET1200 SPI slave interface
//! (also what an AX58100 or a LAN9253 in "Beckhoff SPI" mode speak).
//!
//! Every SPI access is one SEL (chip select) cycle: an address/command
//! phase of 2 or 3 bytes, then a data phase of 0..N bytes. While the
//! master clocks the address phase, the ESC returns the AL event request
//! register on MISO. Reads auto-increment the address and are terminated
//! by a 0xFF byte on MOSI; writes end when SEL is released. Facts and their
//! sources are in `docs/SPI-NOTES.md`, section A; each rule below cites
//! them in brackets.
//!
//! ```text
//! read AL status 0x0130, 2 bytes:   MOSI 09 82 00 FF    MISO I0 I1 D0 D1
//! same, with a wait-state byte:     MOSI 09 83 FF 00 FF MISO I0 I1 FF D0 D1
//! write 0x0130 = 0x0002:            MOSI 09 84 02 00    MISO I0 I1 00 00
//! ```
//!
//! The emulation decodes the bytes as a shift register would: MISO byte
//! `k` depends only on MOSI bytes `0..k` and the chip state. Each access
//! reaches the [`SoftEsc`] as exactly one [`Esc::read`] or [`Esc::write`],
//! so SyncManager side effects (a mailbox emptied by reading its last
//! byte, the AL control event acknowledged by reading 0x0120) happen once
//! per access, as on silicon.

use crate::Counters;
use ecat_sim::esc::{MEM_SIZE, SoftEsc};
use ecat_slave::esc::Esc;
use embedded_hal::spi::{self, ErrorKind, Operation, SpiDevice};

/// The AL event request register the address phase echoes
/// [IPX-III §10.2.6, Table 46; ET1200-III §6.3.6, Table 41].
const AL_EVENT_REQUEST: usize = 0x0220;
/// The AL event mask register that gates the IRQ output [SEC-I §12.1].
const AL_EVENT_MASK: usize = 0x0204;

/// Command code NOP [ET1200-III Table 39; IPX-III Table 45].
pub const CMD_NOP: u8 = 0b000;
/// Command code read [ET1200-III Table 39; IPX-III Table 45].
pub const CMD_READ: u8 = 0b010;
/// Command code read with a following wait-state byte [IPX-III Table 45;
/// SOES twrk60 esc_hw.c:21-24; MCHP lan9253 ecat_util.h.ftl:360-362].
pub const CMD_READ_WAIT: u8 = 0b011;
/// Command code write [ET1200-III Table 39; IPX-III Table 45].
pub const CMD_WRITE: u8 = 0b100;
/// Command code address extension: a third address/command byte follows
/// [ET1200-III Table 40].
pub const CMD_ADDR_EXT: u8 = 0b110;

/// Errors of the emulated SPI devices.
///
/// It has no values: a real chip has no way to signal an error on SPI, so
/// the emulations never fail a transaction. Malformed accesses are counted
/// instead (`counters().protocol_errors()` of each emulation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EmuError {}

impl spi::Error for EmuError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// Number of bytes a transaction clocks: the length of each operation
/// (for `Transfer`, the longer of its two buffers; embedded-hal 1.0).
pub(crate) fn clocked_len(ops: &[Operation<'_, u8>]) -> usize {
    ops.iter()
        .map(|op| match op {
            Operation::Read(r) => r.len(),
            Operation::Write(w) => w.len(),
            Operation::Transfer(r, w) => r.len().max(w.len()),
            Operation::TransferInPlace(b) => b.len(),
            Operation::DelayNs(_) => 0,
        })
        .sum()
}

/// Clocks the bytes of all operations in order through `f(k, mosi) ->
/// miso`, `k` counting bytes from the start of the SEL cycle, as
/// embedded-hal 1.0 defines the operations: `Write` discards MISO; `Read`
/// sends 0x00 (what most HALs clock out) and keeps MISO; `Transfer(r, w)`
/// sends `w` then 0x00 while `r` is longer, and drops MISO beyond `r`;
/// `TransferInPlace` sends the buffer and overwrites it; `DelayNs` clocks
/// nothing.
pub(crate) fn clock_ops(ops: &mut [Operation<'_, u8>], mut f: impl FnMut(usize, u8) -> u8) {
    let mut k = 0usize;
    for op in ops.iter_mut() {
        match op {
            Operation::Write(w) => {
                for &b in w.iter() {
                    f(k, b);
                    k += 1;
                }
            }
            Operation::Read(r) => {
                for x in r.iter_mut() {
                    *x = f(k, 0x00);
                    k += 1;
                }
            }
            Operation::Transfer(r, w) => {
                let n = r.len().max(w.len());
                for i in 0..n {
                    let mosi = w.get(i).copied().unwrap_or(0x00);
                    let miso = f(k, mosi);
                    if let Some(x) = r.get_mut(i) {
                        *x = miso;
                    }
                    k += 1;
                }
            }
            Operation::TransferInPlace(b) => {
                for x in b.iter_mut() {
                    *x = f(k, *x);
                    k += 1;
                }
            }
            Operation::DelayNs(_) => {}
        }
    }
}

/// Reads a little-endian u32 out of a memory image (0 where it is short).
pub(crate) fn mem_u32(mem: &[u8], at: usize) -> u32 {
    let mut b = [0u8; 4];
    if let Some(src) = mem.get(at..at + 4) {
        b.copy_from_slice(src);
    }
    u32::from_le_bytes(b)
}

/// Whether the ESC asserts its IRQ output: the AL event request
/// (0x0220:0x0223) ANDed with the AL event mask (0x0204:0x0207), all
/// resulting bits ORed [SEC-I §12.1, Fig. 41]. Read from the raw memory,
/// without side effects.
pub(crate) fn esc_irq(esc: &SoftEsc) -> bool {
    let mem = esc.raw_memory();
    mem_u32(mem, AL_EVENT_REQUEST) & mem_u32(mem, AL_EVENT_MASK) != 0
}

/// What the data phase of the current cycle does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Still clocking the address/command phase.
    Address,
    /// NOP: data bytes access nothing.
    Nop,
    /// Read, optionally with the wait-state byte first.
    Read {
        /// CMD 011b: the first byte after the address phase is a wait state.
        wait: bool,
    },
    /// Write: the data bytes are collected and written at SEL release.
    Write,
    /// A reserved command: the rest of the cycle is ignored.
    Reserved,
}

/// Decoding state of one SEL cycle.
#[derive(Debug)]
struct Cycle {
    /// Bytes clocked in the whole cycle (known from the operations).
    total: usize,
    /// Address/command bytes seen so far.
    hdr: [u8; 3],
    /// Length of the address phase: 2, or 3 with the address extension.
    hdr_len: usize,
    /// Decoded command (CMD1 in 3-byte mode).
    cmd: u8,
    /// Decoded address.
    addr: u16,
    /// What the data bytes do.
    phase: Phase,
    /// Bytes clocked so far.
    clocked: usize,
    /// Data bytes read from the ESC (set at the first data byte).
    read_len: usize,
    /// Data bytes collected for a write.
    write_len: usize,
    /// The cycle broke a protocol rule (counted once per cycle).
    error: bool,
}

/// Emulated ET1100-family ESC behind its SPI slave interface.
///
/// An [`embedded_hal::spi::SpiDevice`]: one
/// [`transaction`](SpiDevice::transaction) is one SEL cycle.
pub struct Et1100Emu {
    esc: SoftEsc,
    /// Data of the current access (the single ESC read or write).
    buf: [u8; MEM_SIZE],
    counters: Counters,
    last_command: Option<(u8, u16, u16)>,
}

impl core::fmt::Debug for Et1100Emu {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Et1100Emu")
            .field("esc", &self.esc)
            .field("counters", &self.counters)
            .field("last_command", &self.last_command)
            .finish_non_exhaustive()
    }
}

impl Et1100Emu {
    /// Puts the SPI slave interface in front of `esc`.
    pub fn new(esc: SoftEsc) -> Self {
        Et1100Emu {
            esc,
            buf: [0; MEM_SIZE],
            counters: Counters::default(),
            last_command: None,
        }
    }

    /// The software ESC behind the interface.
    pub fn esc(&self) -> &SoftEsc {
        &self.esc
    }

    /// The software ESC behind the interface, mutable (to process frames
    /// as a master, or to set up memory for a test).
    pub fn esc_mut(&mut self) -> &mut SoftEsc {
        &mut self.esc
    }

    /// Takes the software ESC back out.
    pub fn into_esc(self) -> SoftEsc {
        self.esc
    }

    /// What the chip counted on its SPI side.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// The last decoded access as `(command, address, data length)`: the
    /// command is CMD1 in 3-byte mode; the length counts data bytes (not
    /// the wait-state byte). `None` before the first complete address
    /// phase and after [`Et1100Emu::reset`].
    pub fn last_command(&self) -> Option<(u8, u16, u16)> {
        self.last_command
    }

    /// Whether the SPI_IRQ output is asserted: (AL event request
    /// 0x0220:0x0223 AND AL event mask 0x0204:0x0207) != 0 [SEC-I §12.1,
    /// Fig. 41]. The pin polarity configured in 0x0150/0x0151 is not
    /// modelled (gap: the notes disagree where it is configured, A.5).
    pub fn irq(&self) -> bool {
        esc_irq(&self.esc)
    }

    /// Power-on of the chip: the ESC's registers return to their power-on
    /// values ([`SoftEsc::power_on`]) and the last command is forgotten.
    /// The statistics counters keep counting (as
    /// [`SoftEsc::pdi_accesses`] does).
    pub fn reset(&mut self) {
        self.esc.power_on();
        self.buf = [0; MEM_SIZE];
        self.last_command = None;
    }

    /// The AL event request byte `i` (0x0220 + i) as the ESC holds it
    /// now, read without side effects.
    fn event_byte(&self, i: usize) -> u8 {
        self.esc
            .raw_memory()
            .get(AL_EVENT_REQUEST + i)
            .copied()
            .unwrap_or(0)
    }

    /// Decodes the command of the address phase once it is complete.
    fn decode(&self, c: &mut Cycle) {
        c.phase = match c.cmd {
            CMD_NOP => Phase::Nop,
            CMD_READ => Phase::Read { wait: false },
            CMD_READ_WAIT => Phase::Read { wait: true },
            CMD_WRITE => Phase::Write,
            // 001b, 101b, 111b, and 110b in byte 2, are reserved
            // [ET1200-III Table 39; IPX-III Table 45]. (gap: what the ESC
            // does with a reserved command is not in the retrieved pages
            // (SPI error handling, ET1200 §6.3.9, title only); chosen: a
            // protocol error, the rest of the cycle is ignored and MISO
            // is 0x00.)
            _ => {
                c.error = true;
                Phase::Reserved
            }
        };
    }

    /// Performs the single ESC read of this access at its first data
    /// byte; its length is what the master will clock before releasing
    /// SEL (the ESC prefetches byte by byte; the emulation reads the
    /// whole access at once, so side effects happen once).
    fn do_read(&mut self, c: &mut Cycle, data_len: usize) {
        c.read_len = data_len;
        match self.buf.get_mut(..data_len) {
            Some(buf) => {
                if self.esc.read(c.addr, buf).is_err() {
                    buf.fill(0x00);
                    self.counters.refuse();
                }
            }
            // Longer than the whole ESC memory: the SoftEsc would refuse
            // it as out of range; it is refused without reaching it.
            None => self.counters.refuse(),
        }
    }

    /// Clocks one byte: `mosi` in, the returned MISO byte out.
    fn clock(&mut self, c: &mut Cycle, k: usize, mosi: u8) -> u8 {
        c.clocked = k + 1;
        if c.phase == Phase::Address {
            if let Some(h) = c.hdr.get_mut(k) {
                *h = mosi;
            }
            // MISO of the address phase: 0x0220, 0x0221, and 0x0222 in
            // 3-byte mode, as the ESC holds them while the byte is clocked
            // [IPX-III §10.2.6, Table 46; ET1200-III §6.3.6, Table 41].
            let miso = self.event_byte(k);
            match k {
                1 => {
                    // Byte 0 = A[12:5]; byte 1 = A[4:0] in bits 7:3 and
                    // CMD0 in bits 2:0; A[15:13] = 000b in 2-byte mode
                    // [ET1200-III §6.3.5, Table 40].
                    let [b0, b1, _] = c.hdr;
                    c.addr = (u16::from(b0) << 5) | u16::from(b1 >> 3);
                    c.cmd = b1 & 0x07;
                    if c.cmd == CMD_ADDR_EXT {
                        c.hdr_len = 3;
                    } else {
                        self.decode(c);
                    }
                }
                2 => {
                    // Byte 2 = A[15:13] in bits 7:5, CMD1 in bits 4:2,
                    // res[1:0] = 00b [ET1200-III Table 40].
                    c.addr |= u16::from(mosi >> 5) << 13;
                    c.cmd = (mosi >> 2) & 0x07;
                    if mosi & 0x03 != 0 {
                        // (gap: what the ESC does with res[1:0] != 00b is
                        // not stated; chosen: a protocol error, the
                        // command is decoded anyway.)
                        c.error = true;
                    }
                    self.decode(c);
                }
                _ => {}
            }
            return miso;
        }
        let j = k.saturating_sub(c.hdr_len);
        match c.phase {
            Phase::Address | Phase::Nop | Phase::Reserved => 0x00,
            Phase::Read { wait } => {
                let first = usize::from(wait);
                if wait && j == 0 {
                    // The wait-state byte: 0xFF on MOSI [MCHP lan9253
                    // ecat_util.h.ftl:350; ASIX AX58100_SPI.c:162-163].
                    // (gap: MISO during this byte is not documented, all
                    // code discards it; chosen: 0xFF, as a busy ESC
                    // drives MISO high in BUSY signalling, ET1200-III
                    // §6.3.8.1.)
                    if mosi != 0xFF {
                        c.error = true;
                    }
                    return 0xFF;
                }
                let d = j - first;
                if d == 0 {
                    let data_len = c.total.saturating_sub(c.hdr_len + first);
                    self.do_read(c, data_len);
                }
                // Read termination: 0x00 on MOSI for every data byte but
                // the last, 0xFF for the last [ET1200-III §6.3.8.2 (text
                // cut off); SOES twrk60 esc_hw.c:69-74, 127; SSC
                // el9800hw.c:488, 530-533; MCHP lan9253 ecat_util.c.ftl:
                // 2058-2067]. (gap: the error handling of a read without
                // the final 0xFF is not retrieved; SSC el9800hw.c:466-500
                // calls it an SPI error; chosen: a protocol error is
                // counted but the read, and its side effects, still
                // happened. A non-0x00 byte before the last counts too,
                // since the ESC may take it as the end of the read.)
                let last = k + 1 == c.total;
                if (last && mosi != 0xFF) || (!last && mosi != 0x00) {
                    c.error = true;
                }
                self.buf.get(d).copied().unwrap_or(0x00)
            }
            Phase::Write => {
                // Data bytes go to auto-incremented addresses [ET1100-III
                // §6.3.3]; the write ends with SEL release, there is no
                // termination byte [ET1200-III §6.3.7]. MISO is
                // undetermined during the data phase [ET1200-III §6.3.7;
                // IPX-III §10.2.7] (chosen: 0x00).
                if let Some(x) = self.buf.get_mut(j) {
                    *x = mosi;
                }
                c.write_len = j + 1;
                0x00
            }
        }
    }

    /// SEL release: ends the access.
    fn finish(&mut self, c: &mut Cycle) {
        if c.clocked == 0 {
            // SEL asserted and released without a clock: nothing happens.
            return;
        }
        if c.clocked < c.hdr_len {
            // (gap: an address phase cut short is not described; chosen:
            // a protocol error, nothing is accessed.)
            c.error = true;
            return;
        }
        let data = c.clocked - c.hdr_len;
        let len = match c.phase {
            Phase::Read { wait } => c.read_len.max(data.saturating_sub(usize::from(wait))),
            Phase::Write => {
                if c.write_len > 0 {
                    // One PDI write of all data bytes at SEL release.
                    match self.buf.get(..c.write_len) {
                        Some(d) => {
                            if self.esc.write(c.addr, d).is_err() {
                                self.counters.refuse();
                            }
                        }
                        None => self.counters.refuse(),
                    }
                }
                c.write_len
            }
            _ => data,
        };
        let len = u16::try_from(len).unwrap_or(u16::MAX);
        self.last_command = Some((c.cmd, c.addr, len));
    }
}

impl spi::ErrorType for Et1100Emu {
    type Error = EmuError;
}

impl SpiDevice<u8> for Et1100Emu {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), EmuError> {
        // One transaction = one SEL cycle: SEL asserted starts an access,
        // SEL released ends it [IPA-III §10.2.3].
        let total = clocked_len(operations);
        let mut c = Cycle {
            total,
            hdr: [0; 3],
            hdr_len: 2,
            cmd: 0,
            addr: 0,
            phase: Phase::Address,
            clocked: 0,
            read_len: 0,
            write_len: 0,
            error: false,
        };
        clock_ops(operations, |k, mosi| self.clock(&mut c, k, mosi));
        self.finish(&mut c);
        self.counters.cycle(total, c.error);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ecat_slave::wire::builder::FrameBuilder;
    use ecat_slave::wire::ecat::Command;

    fn emu() -> Et1100Emu {
        let mut sii = [0xFFu8; 128];
        sii[..16].fill(0);
        Et1100Emu::new(SoftEsc::new(&sii))
    }

    /// One SEL cycle clocking `mosi`; returns MISO.
    fn xfer<const N: usize>(e: &mut Et1100Emu, mosi: [u8; N]) -> [u8; N] {
        let mut buf = mosi;
        e.transaction(&mut [Operation::TransferInPlace(&mut buf)])
            .unwrap();
        buf
    }

    /// Sends one frame of `(command, ado, data)` APxx datagrams to
    /// station position 0.
    fn frame(e: &mut Et1100Emu, dgs: &[(Command, u16, &[u8])]) {
        let mut buf = [0u8; 256];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
        for (c, ado, d) in dgs {
            b.push(*c, u32::from(*ado) << 16, d).unwrap();
        }
        let len = b.finish();
        e.esc_mut().process_frame(&mut buf[..len]);
    }

    fn set_event(e: &mut Et1100Emu, ev: u32) {
        e.esc_mut().raw_memory_mut()[0x0220..0x0224].copy_from_slice(&ev.to_le_bytes());
    }

    #[test]
    fn read_al_status_two_byte_mode() {
        let mut e = emu();
        set_event(&mut e, 0x00A5_3C11);
        e.esc_mut().raw_memory_mut()[0x0130..0x0132].copy_from_slice(&[0x08, 0x00]);
        let pdi = e.esc().pdi_accesses();
        assert_eq!(
            xfer(&mut e, [0x09, 0x82, 0x00, 0xFF]),
            [0x11, 0x3C, 0x08, 0x00]
        );
        assert_eq!(e.esc().pdi_accesses(), pdi + 1, "one PDI access");
        assert_eq!(e.last_command(), Some((CMD_READ, 0x0130, 2)));
        assert_eq!(e.counters().protocol_errors(), 0);
        assert_eq!(e.counters().transactions(), 1);
        assert_eq!(e.counters().bytes_clocked(), 4);
    }

    #[test]
    fn read_with_wait_state_byte() {
        let mut e = emu();
        set_event(&mut e, 0x0000_0201);
        e.esc_mut().raw_memory_mut()[0x0130..0x0132].copy_from_slice(&[0x02, 0x00]);
        assert_eq!(
            xfer(&mut e, [0x09, 0x83, 0xFF, 0x00, 0xFF]),
            [0x01, 0x02, 0xFF, 0x02, 0x00]
        );
        assert_eq!(e.last_command(), Some((CMD_READ_WAIT, 0x0130, 2)));
        assert_eq!(e.counters().protocol_errors(), 0);
        // A wait-state byte that is not 0xFF is a protocol error.
        xfer(&mut e, [0x09, 0x83, 0x00, 0x00, 0xFF]);
        assert_eq!(e.counters().protocol_errors(), 1);
    }

    #[test]
    fn write_al_control_and_al_status() {
        let mut e = emu();
        set_event(&mut e, 0x0000_0004);
        let pdi = e.esc().pdi_accesses();
        // The vector of SPI-NOTES A.6: the bytes decode as a 2-byte write
        // of 0x0120 and reach the ESC as one PDI write; the SoftEsc keeps
        // AL control master-writable only, so its memory stays 0.
        assert_eq!(
            xfer(&mut e, [0x09, 0x04, 0x02, 0x00]),
            [0x04, 0x00, 0x00, 0x00]
        );
        assert_eq!(e.last_command(), Some((CMD_WRITE, 0x0120, 2)));
        assert_eq!(e.esc().pdi_accesses(), pdi + 1);
        assert_eq!(e.esc().raw_memory()[0x0120..0x0122], [0, 0]);
        // AL status is PDI-writable: the bytes land at 0x0130/0x0131.
        xfer(&mut e, [0x09, 0x84, 0x02, 0x00]);
        assert_eq!(e.esc().raw_memory()[0x0130..0x0132], [0x02, 0x00]);
        assert_eq!(e.esc().pdi_accesses(), pdi + 2);
        assert_eq!(e.counters().protocol_errors(), 0);
    }

    #[test]
    fn three_byte_mode_reaches_above_8k() {
        let mut e = emu();
        set_event(&mut e, 0x0055_4433);
        e.esc_mut().raw_memory_mut()[0x2FFC..0x3000].copy_from_slice(&[1, 2, 3, 4]);
        e.esc_mut().raw_memory_mut()[0x0FFC..0x1000].copy_from_slice(&[9, 8, 7, 6]);
        // 0x2FFC: A[12:5] = 0x7F; A[4:0] = 0x1C -> 0xE0 | 110b; byte 2 =
        // A[15:13] = 001b -> 0x20 | 010b << 2.
        assert_eq!(
            xfer(&mut e, [0x7F, 0xE6, 0x28, 0x00, 0x00, 0x00, 0xFF]),
            [0x33, 0x44, 0x55, 1, 2, 3, 4]
        );
        assert_eq!(e.last_command(), Some((CMD_READ, 0x2FFC, 4)));
        // The same two bytes in 2-byte mode reach 0x0FFC (A[15:13] = 0).
        assert_eq!(
            xfer(&mut e, [0x7F, 0xE2, 0x00, 0x00, 0x00, 0xFF]),
            [0x33, 0x44, 9, 8, 7, 6]
        );
        assert_eq!(e.counters().protocol_errors(), 0);
        // 0x3000 is beyond the SoftEsc memory: 0x00 bytes, refused.
        assert_eq!(
            xfer(&mut e, [0x80, 0x06, 0x28, 0x00, 0x00, 0x00, 0xFF]),
            [0x33, 0x44, 0x55, 0, 0, 0, 0]
        );
        assert_eq!(e.last_command(), Some((CMD_READ, 0x3000, 4)));
        assert_eq!(e.counters().refused_accesses(), 1);
        // A write there is dropped and counted too.
        xfer(&mut e, [0xFF, 0xFE, 0xE0 | (CMD_WRITE << 2), 1, 2]);
        assert_eq!(e.counters().refused_accesses(), 2);
        // res[1:0] != 00b is a protocol error.
        xfer(&mut e, [0x7F, 0xE6, 0x29, 0x00, 0xFF]);
        assert_eq!(e.counters().protocol_errors(), 1);
    }

    #[test]
    fn nop_returns_the_event_and_accesses_nothing() {
        let mut e = emu();
        set_event(&mut e, 0x0000_0102);
        let pdi = e.esc().pdi_accesses();
        assert_eq!(xfer(&mut e, [0x00, 0x00]), [0x02, 0x01]);
        assert_eq!(xfer(&mut e, [0x00, 0x00, 0x12, 0x34]), [0x02, 0x01, 0, 0]);
        // 3-byte NOP.
        assert_eq!(xfer(&mut e, [0x00, 0x06, 0x00]), [0x02, 0x01, 0x00]);
        assert_eq!(e.esc().pdi_accesses(), pdi);
        assert_eq!(e.counters().protocol_errors(), 0);
        assert_eq!(e.last_command(), Some((CMD_NOP, 0, 0)));
    }

    #[test]
    fn reading_al_control_acknowledges_its_event() {
        let mut e = emu();
        // The master writes AL control: the SoftEsc raises event bit 0.
        frame(&mut e, &[(Command::Apwr, 0x0120, &[0x02, 0x00])]);
        assert_eq!(e.esc().raw_memory()[0x0220] & 1, 1);
        // The echo of this read still shows the event (clocked before the
        // access); the next address phase no longer does.
        let miso = xfer(&mut e, [0x09, 0x02, 0x00, 0xFF]);
        assert_eq!(miso[0] & 1, 1);
        assert_eq!(miso[2..], [0x02, 0x00]);
        assert_eq!(e.esc().raw_memory()[0x0220] & 1, 0);
        assert_eq!(xfer(&mut e, [0x00, 0x00])[0] & 1, 0);
    }

    #[test]
    fn mailbox_read_empties_sm0_and_an_empty_one_is_refused() {
        let mut e = emu();
        let sm0 = [0x00, 0x10, 0x08, 0x00, 0x26, 0x00, 0x01, 0x00];
        let sm1 = [0x80, 0x10, 0x08, 0x00, 0x22, 0x00, 0x01, 0x00];
        frame(
            &mut e,
            &[(Command::Apwr, 0x0800, &sm0), (Command::Apwr, 0x0808, &sm1)],
        );
        frame(
            &mut e,
            &[(Command::Apwr, 0x1000, &[1, 2, 3, 4, 5, 6, 7, 8])],
        );
        assert_ne!(e.esc().raw_memory()[0x0805] & 0x08, 0, "SM0 full");
        assert_ne!(e.esc().raw_memory()[0x0221] & 0x01, 0, "SM0 event");
        let pdi = e.esc().pdi_accesses();
        // 0x1000: A[12:5] = 0x80, A[4:0] = 0.
        let miso = xfer(&mut e, [0x80, 0x02, 0, 0, 0, 0, 0, 0, 0, 0xFF]);
        assert_eq!(miso[1] & 0x01, 0x01, "echo shows the SM0 event");
        assert_eq!(miso[2..], [1, 2, 3, 4, 5, 6, 7, 8]);
        assert_eq!(e.esc().pdi_accesses(), pdi + 1);
        assert_eq!(e.esc().raw_memory()[0x0805] & 0x08, 0, "emptied");
        assert_eq!(e.esc().raw_memory()[0x0221] & 0x01, 0, "event acknowledged");
        // Read again: the mailbox is empty; the chip returns 0x00 bytes.
        let miso = xfer(&mut e, [0x80, 0x02, 0, 0, 0, 0, 0, 0, 0, 0xFF]);
        assert_eq!(miso[2..], [0; 8]);
        assert_eq!(e.counters().refused_accesses(), 1);
        // SM1 (mailbox in) takes one PDI write of 8 bytes; a second is
        // refused because it is full.
        let w = [0x84, 0x04, 9, 9, 9, 9, 9, 9, 9, 9];
        xfer(&mut e, w);
        assert_ne!(e.esc().raw_memory()[0x080D] & 0x08, 0, "SM1 full");
        xfer(&mut e, w);
        assert_eq!(e.counters().refused_accesses(), 2);
        assert_eq!(e.counters().protocol_errors(), 0);
    }

    #[test]
    fn malformed_accesses_are_counted() {
        let mut e = emu();
        e.esc_mut().raw_memory_mut()[0x0130] = 0x04;
        // Unterminated read: the read still happened.
        assert_eq!(xfer(&mut e, [0x09, 0x82, 0x00, 0x00])[2], 0x04);
        assert_eq!(e.counters().protocol_errors(), 1);
        // 0xFF before the last byte.
        xfer(&mut e, [0x09, 0x82, 0xFF, 0xFF]);
        assert_eq!(e.counters().protocol_errors(), 2);
        // Reserved commands 001b, 101b, 111b, and 110b as CMD1.
        let pdi = e.esc().pdi_accesses();
        for cmd in [0x01u8, 0x05, 0x07] {
            assert_eq!(xfer(&mut e, [0x09, 0x80 | cmd, 0x00, 0xFF])[2..], [0, 0]);
        }
        xfer(&mut e, [0x09, 0x86, 0x18, 0x00, 0xFF]);
        assert_eq!(e.counters().protocol_errors(), 6);
        assert_eq!(e.esc().pdi_accesses(), pdi);
        // A 1-byte cycle, and a 3-byte address phase cut after 2 bytes.
        xfer(&mut e, [0x09]);
        xfer(&mut e, [0x09, 0x86]);
        assert_eq!(e.counters().protocol_errors(), 8);
        assert_eq!(e.esc().pdi_accesses(), pdi);
        // An empty transaction is no error.
        e.transaction(&mut []).unwrap();
        assert_eq!(e.counters().protocol_errors(), 8);
        assert_eq!(e.counters().transactions(), 9);
    }

    #[test]
    fn operations_form_one_stream() {
        let mut e = emu();
        set_event(&mut e, 0x0000_0807);
        e.esc_mut().raw_memory_mut()[0x0130..0x0134].copy_from_slice(&[1, 2, 3, 4]);
        let mut ev = [0u8; 2];
        let mut data = [0u8; 3];
        let mut tail = [0xFFu8; 1];
        // Transfer with r longer than w: MOSI continues with 0x00.
        e.transaction(&mut [
            Operation::Transfer(&mut ev, &[0x09, 0x82]),
            Operation::DelayNs(100),
            Operation::Read(&mut data),
            Operation::TransferInPlace(&mut tail),
        ])
        .unwrap();
        assert_eq!(ev, [0x07, 0x08]);
        assert_eq!(data, [1, 2, 3]);
        assert_eq!(tail, [4]);
        assert_eq!(e.last_command(), Some((CMD_READ, 0x0130, 4)));
        assert_eq!(e.counters().protocol_errors(), 0);
        // Transfer with w longer than r: extra MISO discarded.
        let mut r = [0u8; 1];
        e.transaction(&mut [Operation::Transfer(&mut r, &[0x09, 0x82, 0x00, 0xFF])])
            .unwrap();
        assert_eq!(r, [0x07]);
        assert_eq!(e.counters().bytes_clocked(), 10);
        // Write then Read (what `write_read`-style drivers do).
        let mut d = [0u8; 1];
        e.transaction(&mut [Operation::Write(&[0x09, 0x82]), Operation::Read(&mut d)])
            .unwrap();
        assert_eq!(d, [1]);
        assert_eq!(
            e.counters().protocol_errors(),
            1,
            "a Read clocks 0x00: unterminated"
        );
    }

    #[test]
    fn irq_follows_event_and_mask_and_reset_clears() {
        let mut e = emu();
        let power_on_mask: [u8; 4] = e.esc().raw_memory()[0x0204..0x0208].try_into().unwrap();
        e.esc_mut().raw_memory_mut()[0x0204..0x0208].fill(0);
        set_event(&mut e, 0x0000_0100);
        assert!(!e.irq());
        // The mask is PDI-writable: write 0x0204 = 0x00000100.
        xfer(&mut e, [0x10, 0x24, 0x00, 0x01, 0x00, 0x00]);
        assert!(e.irq());
        set_event(&mut e, 0x0000_0001);
        assert!(!e.irq());
        e.reset();
        assert!(!e.irq());
        assert_eq!(e.last_command(), None);
        assert_eq!(e.esc().raw_memory()[0x0204..0x0208], power_on_mask);
        assert_eq!(e.into_esc().raw_memory()[0x0130], 0x01, "INIT");
    }

    /// xorshift64*.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        fn byte(&mut self) -> u8 {
            (self.next() >> 32) as u8
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
    }

    #[test]
    fn random_byte_sequences_never_panic() {
        let mut e = emu();
        let sm0 = [0x00, 0x10, 0x08, 0x00, 0x26, 0x00, 0x01, 0x00];
        let sm1 = [0x80, 0x10, 0x08, 0x00, 0x22, 0x00, 0x01, 0x00];
        frame(
            &mut e,
            &[(Command::Apwr, 0x0800, &sm0), (Command::Apwr, 0x0808, &sm1)],
        );
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let mut a = [0u8; 64];
        let mut b = [0u8; 64];
        let mut c = [0u8; 64];
        for i in 0..4000 {
            if i % 97 == 0 {
                frame(&mut e, &[(Command::Apwr, 0x1000, &[i as u8; 8])]);
            }
            for x in a.iter_mut().chain(b.iter_mut()).chain(c.iter_mut()) {
                *x = rng.byte();
            }
            // Bias the command bits towards valid ones.
            if rng.below(2) == 0 {
                a[1] = (a[1] & !7) | [0, 2, 3, 4, 6][rng.below(5)];
                a[0] &= 0x9F;
            }
            let (la, lb, lc) = (rng.below(8), rng.below(40), rng.below(40));
            let (b1, b2) = b.split_at_mut(lb.min(64));
            let mut ops = [
                Operation::TransferInPlace(&mut a[..la]),
                match rng.below(4) {
                    0 => Operation::Write(&c[..lc]),
                    1 => Operation::Read(&mut b1[..]),
                    2 => Operation::Transfer(&mut b1[..], &c[..lc]),
                    _ => Operation::DelayNs(5),
                },
                Operation::Read(&mut b2[..rng.below(8)]),
            ];
            e.transaction(&mut ops).unwrap();
            if i % 1000 == 999 {
                e.reset();
            }
        }
        assert_eq!(e.counters().transactions(), 4000);
        assert!(e.counters().protocol_errors() > 0);
    }
}
