//! Byte-level emulation of the Microchip LAN9252 SPI interface.
//!
//! The LAN9252's SPI address space is the chip's system CSR space, not
//! ESC memory: ESC registers below 0x1000 are reached one at a time through
//! ECAT_CSR_DATA/ECAT_CSR_CMD, process RAM through the PRAM read and write
//! FIFOs. Every SEL cycle is an instruction byte, a 16-bit address MSB
//! first, dummy bytes for the fast read, then data; register data is
//! little endian. Facts and their sources are in `docs/SPI-NOTES.md`,
//! section B; each rule below cites them in brackets.
//!
//! ```text
//! fast read BYTE_TEST:   MOSI 0B 00 64 00 00 00 00 00   MISO .. .. .. .. 21 43 65 87
//! CSR read of 0x0130:    MOSI 02 03 04 30 01 02 C0       (ECAT_CSR_CMD: read, 2 bytes)
//!                        MOSI 0B 03 04 00 + 4 bytes      MISO .. 30 01 02 40 (busy clear)
//!                        MOSI 0B 03 00 00 + 4 bytes      MISO .. D0 D1 00 00
//! ```
//!
//! Each CSR command and each whole FIFO transfer reaches the [`SoftEsc`]
//! as exactly one [`Esc::read`] or [`Esc::write`]. The chip's internal
//! delays are not modelled: a command completes as soon as it is written
//! (its busy bit reads 0 at the next poll), a reset is over at once.

use crate::Counters;
use crate::et1100::{clock_ops, clocked_len, esc_irq, mem_u32};
use ecat_sim::esc::{MEM_SIZE, SoftEsc};
use ecat_slave::esc::Esc;
use embedded_hal::spi::{self, Operation, SpiDevice};

pub use crate::et1100::EmuError;

/// Instruction serial read: address, then data [MCHP lan9252
/// ecat_util.h.ftl:180-205; MCHP-9252HW SPIDriver.h].
pub const INSTR_READ: u8 = 0x03;
/// Instruction fast read: address, one dummy byte, then data [MCHP lan9252
/// ecat_util.h.ftl:180-205; SOES drivers/linux/lan9252/lan9252.c:93-121].
pub const INSTR_FAST_READ: u8 = 0x0B;
/// Instruction serial write: address, then data [MCHP lan9252
/// ecat_util.h.ftl:180-205].
pub const INSTR_WRITE: u8 = 0x02;
/// Instruction "reset SQI mode to SPI" [SOES rt-kernel-lan9252
/// esc_hw.c:22; MBED SQI_RESET]; a no-op here (only SPI is emulated).
pub const INSTR_SQI_RESET: u8 = 0xFF;

/// ID_REV: chip ID (upper 16 bits), revision (lower 16) [SOES
/// raspberrypi-lan9252 esc_hw.c:29, 539-540].
pub const ID_REV: u16 = 0x0050;
/// IRQ_CFG [MCHP drv_lan9252.c:56-59].
pub const IRQ_CFG: u16 = 0x0054;
/// INT_STS [MCHP drv_lan9252.c:56-59].
pub const INT_STS: u16 = 0x0058;
/// INT_EN [MCHP drv_lan9252.c:56-59].
pub const INT_EN: u16 = 0x005C;
/// BYTE_TEST, reads 0x87654321 [SOES drivers/linux/lan9252/lan9252.c:68-84].
pub const BYTE_TEST: u16 = 0x0064;
/// HW_CFG, bit 27 READY [SOES raspberrypi-lan9252 esc_hw.c:27, 36].
pub const HW_CFG: u16 = 0x0074;
/// RESET_CTL, bit 0 DIGITAL_RST, bit 6 ETHERCAT_RST [SOES
/// raspberrypi-lan9252 esc_hw.c:26, 33-34].
pub const RESET_CTL: u16 = 0x01F8;
/// ECAT_CSR_DATA [SOES rt-kernel-lan9252 esc_hw.c:43-49].
pub const ECAT_CSR_DATA: u16 = 0x0300;
/// ECAT_CSR_CMD [SOES rt-kernel-lan9252 esc_hw.c:43-49].
pub const ECAT_CSR_CMD: u16 = 0x0304;
/// ECAT_PRAM_RD_ADDR_LEN [SOES rt-kernel-lan9252 esc_hw.c:29-41].
pub const ECAT_PRAM_RD_ADDR_LEN: u16 = 0x0308;
/// ECAT_PRAM_RD_CMD [SOES rt-kernel-lan9252 esc_hw.c:29-41].
pub const ECAT_PRAM_RD_CMD: u16 = 0x030C;
/// ECAT_PRAM_WR_ADDR_LEN [SOES rt-kernel-lan9252 esc_hw.c:29-41].
pub const ECAT_PRAM_WR_ADDR_LEN: u16 = 0x0310;
/// ECAT_PRAM_WR_CMD [SOES rt-kernel-lan9252 esc_hw.c:29-41].
pub const ECAT_PRAM_WR_CMD: u16 = 0x0314;
/// The read FIFO [SOES rt-kernel-lan9252 esc_hw.c:27-28]. (gap: Microchip
/// reads at 0x0004 and calls the FIFO registers aliased [MCHP lan9252
/// ecat_util.c.ftl:374-376], the alias range is not found; chosen: any
/// address 0x0000-0x001F is the read FIFO.)
pub const PRAM_RD_FIFO: u16 = 0x0000;
/// The write FIFO [SOES rt-kernel-lan9252 esc_hw.c:27-28]. (gap: as for
/// the read FIFO; chosen: any address 0x0020-0x003F.)
pub const PRAM_WR_FIFO: u16 = 0x0020;

/// The ID_REV value. (gap: the revision is not in the notes; chosen:
/// 0x0001.)
const ID_REV_VALUE: u32 = 0x9252_0001;
/// BYTE_TEST value [SOES drivers/linux/lan9252/lan9252.c:68-84].
const BYTE_TEST_VALUE: u32 = 0x8765_4321;
/// HW_CFG READY [SOES raspberrypi-lan9252 esc_hw.c:27, 36, 528-533].
const HW_CFG_READY: u32 = 1 << 27;
/// RESET_CTL DIGITAL_RST and ETHERCAT_RST [SOES raspberrypi-lan9252
/// esc_hw.c:26, 33-34].
const RESET_BITS: u32 = (1 << 0) | (1 << 6);
/// IRQ_CFG IRQ enable (inferred from Microchip's 0x101 and SOES's 0x111
/// [MCHP drv_lan9252.c:97-109; SOES raspberrypi-lan9252 esc_hw.c:579-583];
/// not from the datasheet).
const IRQ_CFG_IRQ_EN: u32 = 1 << 8;
/// INT_EN / INT_STS bit 0: EtherCAT (AL event) interrupt (inferred, as
/// IRQ_CFG).
const INT_ECAT: u32 = 1 << 0;
/// CSR and PRAM command bit 31: busy / start [SOES rt-kernel-lan9252
/// esc_hw.c:30-49].
const BUSY: u32 = 1 << 31;
/// ECAT_CSR_CMD bit 30: read (1) / write (0) [SOES rt-kernel-lan9252
/// esc_hw.c:43-49].
const CSR_READ: u32 = 1 << 30;
/// PRAM command bit 30: abort [SOES rt-kernel-lan9252 esc_hw.c:30-38].
const PRAM_ABORT: u32 = 1 << 30;
/// PRAM command bit 0: data / space available [SOES rt-kernel-lan9252
/// esc_hw.c:30-38; MCHP-9252HW 9252_HW.h].
const PRAM_AVAIL: u32 = 1 << 0;
/// Depth of the FIFOs in DWORDs [SOES raspberrypi-lan9252
/// esc_hw.c:172-176].
const FIFO_DWORDS: usize = 16;
/// First process RAM address: below it, the CSR path [SOES
/// rt-kernel-lan9252 esc_hw.c:283; MCHP drv_lan9252.c:311].
const PRAM_START: u16 = 0x1000;
/// Staging space of one FIFO transfer: all of process RAM plus lane
/// padding.
const STAGE: usize = MEM_SIZE - PRAM_START as usize + 4;

/// Which registers a data phase reaches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    /// CSRs; the address auto-increments per byte.
    Reg,
    /// The read FIFO: no auto-increment, each 4 bytes pop a DWORD.
    RdFifo,
    /// The write FIFO: no auto-increment, each 4 bytes push a DWORD.
    WrFifo,
}

/// What the cycle's instruction does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Instr {
    /// Read (serial or fast).
    Read,
    /// Write.
    Write,
    /// SQI reset or an unknown instruction: the rest is ignored.
    Ignore,
}

/// Decoding state of one SEL cycle.
#[derive(Debug)]
struct Cycle {
    instr: Instr,
    /// Instruction + address (+ dummy) bytes.
    hdr_len: usize,
    addr: u16,
    target: Target,
    clocked: usize,
    /// The DWORD being shifted out (latched at its first byte).
    latch: u32,
    /// The FIFO DWORD being shifted in.
    word: [u8; 4],
    /// A register DWORD being written: (DWORD address, value, byte mask).
    pend: Option<(u16, u32, u32)>,
    error: bool,
}

/// The PRAM read FIFO: one ESC read staged as DWORDs.
struct RdFifo {
    buf: [u8; STAGE],
    /// DWORDs of the current transfer.
    dwords: usize,
    /// DWORDs already popped.
    next: usize,
}

/// The PRAM write FIFO: DWORDs collected until the length is complete.
struct WrFifo {
    buf: [u8; STAGE],
    addr: u16,
    len: usize,
    /// DWORDs the transfer needs (0: not busy).
    dwords: usize,
    /// DWORDs received.
    got: usize,
}

/// Emulated LAN9252 (EtherCAT ESC with SPI host interface).
///
/// An [`embedded_hal::spi::SpiDevice`]: one
/// [`transaction`](SpiDevice::transaction) is one SEL (CS) cycle.
pub struct Lan9252Emu {
    esc: SoftEsc,
    irq_cfg: u32,
    int_en: u32,
    csr_data: u32,
    csr_cmd: u32,
    rd_addr_len: u32,
    wr_addr_len: u32,
    rd: RdFifo,
    wr: WrFifo,
    counters: Counters,
}

impl core::fmt::Debug for Lan9252Emu {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Lan9252Emu")
            .field("esc", &self.esc)
            .field("irq_cfg", &self.irq_cfg)
            .field("int_en", &self.int_en)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl Lan9252Emu {
    /// Puts the LAN9252 host interface in front of `esc`.
    pub fn new(esc: SoftEsc) -> Self {
        Lan9252Emu {
            esc,
            irq_cfg: 0,
            int_en: 0,
            csr_data: 0,
            csr_cmd: 0,
            rd_addr_len: 0,
            wr_addr_len: 0,
            rd: RdFifo {
                buf: [0; STAGE],
                dwords: 0,
                next: 0,
            },
            wr: WrFifo {
                buf: [0; STAGE],
                addr: 0,
                len: 0,
                dwords: 0,
                got: 0,
            },
            counters: Counters::default(),
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

    /// Whether the IRQ output is asserted: (AL event request AND AL event
    /// mask) != 0 [SEC-I §12.1], gated by INT_EN bit 0 and IRQ_CFG bit 8
    /// (inferred [MCHP drv_lan9252.c:97-109; SOES raspberrypi-lan9252
    /// esc_hw.c:579-583]). "Asserted" regardless of the polarity in
    /// IRQ_CFG bit 4.
    pub fn irq(&self) -> bool {
        self.int_sts() & self.int_en & INT_ECAT != 0 && self.irq_cfg & IRQ_CFG_IRQ_EN != 0
    }

    /// Power-on of the chip: the ESC's registers return to their power-on
    /// values ([`SoftEsc::power_on`]), the host interface registers to 0,
    /// the FIFOs are emptied; READY (HW_CFG bit 27) is set at once. The
    /// statistics counters keep counting.
    pub fn reset(&mut self) {
        self.esc.power_on();
        self.irq_cfg = 0;
        self.int_en = 0;
        self.csr_data = 0;
        self.csr_cmd = 0;
        self.rd_addr_len = 0;
        self.wr_addr_len = 0;
        self.rd.dwords = 0;
        self.rd.next = 0;
        self.wr.dwords = 0;
        self.wr.got = 0;
    }

    /// INT_STS: bit 0 = an EtherCAT event is pending, (AL event request
    /// AND AL event mask) != 0 [SEC-I §12.1; SOES raspberrypi-lan9252
    /// esc_hw.c:543-547] (the bit is inferred, see [`Lan9252Emu::irq`]).
    fn int_sts(&self) -> u32 {
        if esc_irq(&self.esc) { INT_ECAT } else { 0 }
    }

    /// ECAT_PRAM_RD_CMD as read: busy while DWORDs remain, bits 12:8 the
    /// available DWORDs (at most a FIFO's worth), bit 0 available [SOES
    /// rt-kernel-lan9252 esc_hw.c:30-38; MCHP-9252HW 9252_HW.h].
    fn rd_status(&self) -> u32 {
        fifo_status(self.rd.dwords.saturating_sub(self.rd.next))
    }

    /// ECAT_PRAM_WR_CMD as read: busy until the length is complete, bits
    /// 12:8 the free DWORD space, bit 0 space available.
    fn wr_status(&self) -> u32 {
        fifo_status(self.wr.dwords.saturating_sub(self.wr.got))
    }

    /// Reads the register DWORD at `a` (DWORD aligned), without side
    /// effects. Unknown addresses read 0.
    fn reg_read(&self, a: u16) -> u32 {
        match a {
            ID_REV => ID_REV_VALUE,
            IRQ_CFG => self.irq_cfg,
            INT_STS => self.int_sts(),
            INT_EN => self.int_en,
            BYTE_TEST => BYTE_TEST_VALUE,
            // (gap: the other HW_CFG bits are not in the notes; chosen: 0.)
            HW_CFG => HW_CFG_READY,
            ECAT_CSR_DATA => self.csr_data,
            ECAT_CSR_CMD => self.csr_cmd,
            ECAT_PRAM_RD_ADDR_LEN => self.rd_addr_len,
            ECAT_PRAM_RD_CMD => self.rd_status(),
            ECAT_PRAM_WR_ADDR_LEN => self.wr_addr_len,
            ECAT_PRAM_WR_CMD => self.wr_status(),
            // RESET_CTL reads 0: its bits clear themselves at once (the
            // real chip takes time; drivers poll until clear [SOES
            // raspberrypi-lan9252 esc_hw.c:509-517]).
            _ => 0,
        }
    }

    /// Writes the register DWORD at `a`: the bytes in `mask` take
    /// `value`. Read-only and unknown registers ignore writes.
    fn reg_write(&mut self, c: &mut Cycle, a: u16, value: u32, mask: u32) {
        let merge = |old: u32| (old & !mask) | (value & mask);
        let written = value & mask;
        match a {
            IRQ_CFG => self.irq_cfg = merge(self.irq_cfg),
            INT_EN => self.int_en = merge(self.int_en),
            // DIGITAL_RST or ETHERCAT_RST resets the ESC [SOES
            // raspberrypi-lan9252 esc_hw.c:26, 33-34, 509-517]. (gap: what
            // ETHERCAT_RST leaves of the host interface is not in the
            // notes; chosen: both reset the whole chip.)
            RESET_CTL if written & RESET_BITS != 0 => self.reset(),
            ECAT_CSR_DATA => self.csr_data = merge(self.csr_data),
            ECAT_CSR_CMD => {
                let v = merge(self.csr_cmd);
                self.csr_command(c, v);
            }
            ECAT_PRAM_RD_ADDR_LEN => self.rd_addr_len = merge(self.rd_addr_len),
            ECAT_PRAM_WR_ADDR_LEN => self.wr_addr_len = merge(self.wr_addr_len),
            ECAT_PRAM_RD_CMD => {
                // Bit 30 aborts, bit 31 starts [SOES rt-kernel-lan9252
                // esc_hw.c:30-38, 136-200]. (gap: both at once, or a start
                // while busy, is not described; chosen: abort wins, a new
                // start replaces the transfer under way.)
                if written & PRAM_ABORT != 0 {
                    self.rd.dwords = 0;
                    self.rd.next = 0;
                } else if written & BUSY != 0 {
                    self.pram_read_start(c);
                }
            }
            ECAT_PRAM_WR_CMD => {
                if written & PRAM_ABORT != 0 {
                    self.wr.dwords = 0;
                    self.wr.got = 0;
                } else if written & BUSY != 0 {
                    self.pram_write_start(c);
                }
            }
            _ => {}
        }
    }

    /// Executes an ECAT_CSR_CMD write: bit 31 starts, bit 30 reads, bits
    /// 23:16 size, bits 15:0 ESC address; a read leaves the data right
    /// aligned in ECAT_CSR_DATA (byte 0 = the byte at the address), a
    /// write takes ECAT_CSR_DATA's low `size` bytes [SOES
    /// rt-kernel-lan9252 esc_hw.c:43-49, 103-133; MCHP lan9252
    /// ecat_util.h.ftl:207-211].
    fn csr_command(&mut self, c: &mut Cycle, v: u32) {
        // Done at once: busy reads back 0 at the next poll.
        self.csr_cmd = v & !BUSY;
        if v & BUSY == 0 {
            return;
        }
        let size = ((v >> 16) & 0xFF) as usize;
        let addr = (v & 0xFFFF) as u16;
        // Size 1, 2 or 4, not crossing its natural alignment [SOES
        // rt-kernel-lan9252 esc_hw.c:292-321]; process RAM goes through
        // the FIFOs [SOES …:283; MCHP drv_lan9252.c:311]. (gap: what the
        // chip does otherwise is not in the notes (LAN9252 Table 12-14 not
        // retrieved); chosen: a protocol error, nothing is accessed.)
        let legal =
            matches!(size, 1 | 2 | 4) && usize::from(addr) % size.max(1) == 0 && addr < PRAM_START;
        let mut b = [0u8; 4];
        let (true, Some(part)) = (legal, b.get_mut(..size)) else {
            c.error = true;
            return;
        };
        if v & CSR_READ != 0 {
            if self.esc.read(addr, part).is_err() {
                part.fill(0);
                self.counters.refuse();
            }
            self.csr_data = u32::from_le_bytes(b);
        } else {
            let d = self.csr_data.to_le_bytes();
            let data = d.get(..size).unwrap_or(&[]);
            if self.esc.write(addr, data).is_err() {
                self.counters.refuse();
            }
        }
    }

    /// The address and length of a PRAM transfer (bits 15:0 address,
    /// 31:16 length [SOES rt-kernel-lan9252 esc_hw.c:29-41, 151]), or
    /// `None` (a protocol error) for a transfer the FIFOs do not make.
    /// (gap: a length of 0 or an address below 0x1000 is not described;
    /// chosen: a protocol error, nothing is accessed.)
    fn pram_window(c: &mut Cycle, addr_len: u32) -> Option<(u16, usize)> {
        let addr = (addr_len & 0xFFFF) as u16;
        let len = (addr_len >> 16) as usize;
        if len == 0 || addr < PRAM_START {
            c.error = true;
            return None;
        }
        Some((addr, len))
    }

    /// Starts a PRAM read: ONE ESC read of the whole length, staged as
    /// DWORDs with the first byte at lane `addr & 3` and padding (0x00)
    /// elsewhere [SOES rt-kernel-lan9252 esc_hw.c:169-177; MCHP lan9252
    /// ecat_util.c.ftl:365-370, 417].
    fn pram_read_start(&mut self, c: &mut Cycle) {
        self.rd.dwords = 0;
        self.rd.next = 0;
        let Some((addr, len)) = Self::pram_window(c, self.rd_addr_len) else {
            return;
        };
        let lane = usize::from(addr & 3);
        self.rd.buf.fill(0);
        match self.rd.buf.get_mut(lane..lane + len) {
            Some(dst) => {
                if self.esc.read(addr, dst).is_err() {
                    dst.fill(0);
                    self.counters.refuse();
                }
            }
            // Longer than process RAM: out of range for the SoftEsc;
            // refused without reaching it, the FIFO delivers zeros.
            None => self.counters.refuse(),
        }
        self.rd.dwords = (lane + len).div_ceil(4);
    }

    /// Starts a PRAM write: the FIFO takes DWORDs until `len` bytes from
    /// lane `addr & 3` of the first DWORD on have arrived [SOES
    /// rt-kernel-lan9252 esc_hw.c:233-242].
    fn pram_write_start(&mut self, c: &mut Cycle) {
        self.wr.dwords = 0;
        self.wr.got = 0;
        let Some((addr, len)) = Self::pram_window(c, self.wr_addr_len) else {
            return;
        };
        self.wr.buf.fill(0);
        self.wr.addr = addr;
        self.wr.len = len;
        self.wr.dwords = (usize::from(addr & 3) + len).div_ceil(4);
    }

    /// Pops a DWORD of the read FIFO; an empty FIFO gives 0 and a protocol
    /// error. (gap: what the chip returns is not in the notes.)
    fn pop(&mut self, c: &mut Cycle) -> u32 {
        if self.rd.next >= self.rd.dwords {
            c.error = true;
            return 0;
        }
        let v = mem_u32(&self.rd.buf, 4 * self.rd.next);
        self.rd.next += 1;
        v
    }

    /// Pushes a DWORD into the write FIFO; when the length is complete,
    /// ONE ESC write of it. A push with no transfer under way is dropped
    /// with a protocol error.
    fn push(&mut self, c: &mut Cycle, word: [u8; 4]) {
        if self.wr.got >= self.wr.dwords {
            c.error = true;
            return;
        }
        let at = 4 * self.wr.got;
        if let Some(dst) = self.wr.buf.get_mut(at..at + 4) {
            dst.copy_from_slice(&word);
        }
        self.wr.got += 1;
        if self.wr.got == self.wr.dwords {
            let lane = usize::from(self.wr.addr & 3);
            match self.wr.buf.get(lane..lane + self.wr.len) {
                Some(data) => {
                    if self.esc.write(self.wr.addr, data).is_err() {
                        self.counters.refuse();
                    }
                }
                None => self.counters.refuse(),
            }
            self.wr.dwords = 0;
            self.wr.got = 0;
        }
    }

    /// Clocks one byte: `mosi` in, the returned MISO byte out. MISO is
    /// 0x00 outside read data (gap: the chip leaves it undriven; chosen:
    /// 0x00).
    fn clock(&mut self, c: &mut Cycle, k: usize, mosi: u8) -> u8 {
        c.clocked = k + 1;
        if k == 0 {
            // The instruction byte [MCHP lan9252 ecat_util.h.ftl:180-205].
            (c.instr, c.hdr_len) = match mosi {
                INSTR_READ => (Instr::Read, 3),
                INSTR_FAST_READ => (Instr::Read, 4),
                INSTR_WRITE => (Instr::Write, 3),
                INSTR_SQI_RESET => (Instr::Ignore, 1),
                // Dual/quad instructions and anything else: not SPI.
                // (gap: the chip's reaction is not in the notes; chosen:
                // a protocol error, the rest of the cycle is ignored.)
                _ => {
                    c.error = true;
                    (Instr::Ignore, 1)
                }
            };
            return 0x00;
        }
        if c.instr == Instr::Ignore {
            return 0x00;
        }
        if k < c.hdr_len {
            // 16-bit address MSB first, then the dummy byte of the fast
            // read [SOES rt-kernel-lan9252 esc_hw.c:57-100].
            match k {
                1 => c.addr = u16::from(mosi) << 8,
                2 => {
                    c.addr |= u16::from(mosi);
                    c.target = match c.addr {
                        0x0000..=0x001F => Target::RdFifo,
                        0x0020..=0x003F => Target::WrFifo,
                        _ => Target::Reg,
                    };
                    if c.target != Target::Reg && c.addr & 3 != 0 {
                        // (gap: a FIFO access not starting at a DWORD is
                        // not described; chosen: a protocol error, the
                        // bytes still move whole DWORDs.)
                        c.error = true;
                    }
                }
                _ => {}
            }
            return 0x00;
        }
        let j = k - c.hdr_len;
        let lane = j % 4;
        match (c.instr, c.target) {
            (Instr::Read, Target::Reg) => {
                // Registers are little-endian DWORDs, byte 0 first; the
                // address advances per byte [SOES rt-kernel-lan9252
                // esc_hw.c:78-100]. (gap: auto-increment is not documented
                // in the notes; chosen: per byte, as the brief.) A DWORD
                // is latched at its first byte.
                let a = c.addr.wrapping_add(j as u16);
                if j == 0 || a & 3 == 0 {
                    c.latch = self.reg_read(a & !3);
                }
                c.latch
                    .to_le_bytes()
                    .get(usize::from(a & 3))
                    .copied()
                    .unwrap_or(0)
            }
            (Instr::Read, Target::RdFifo) => {
                // The FIFO address does not advance: each 4 bytes pop one
                // DWORD (SOES bursts the FIFO in one CS cycle [SOES
                // rt-kernel-lan9252 esc_hw.c:179-200]).
                if lane == 0 {
                    c.latch = self.pop(c);
                }
                c.latch.to_le_bytes().get(lane).copied().unwrap_or(0)
            }
            (Instr::Write, Target::Reg) => {
                let a = c.addr.wrapping_add(j as u16);
                let dword = a & !3;
                if let Some((pa, v, m)) = c.pend.take_if(|p| p.0 != dword) {
                    self.reg_write(c, pa, v, m);
                }
                let shift = 8 * u32::from(a & 3);
                let (v, m) = c.pend.map_or((0, 0), |p| (p.1, p.2));
                c.pend = Some((dword, v | (u32::from(mosi) << shift), m | (0xFF << shift)));
                0x00
            }
            (Instr::Write, Target::WrFifo) => {
                if let Some(x) = c.word.get_mut(lane) {
                    *x = mosi;
                }
                if lane == 3 {
                    self.push(c, c.word);
                }
                0x00
            }
            // Reading the write FIFO or writing the read FIFO. (gap: not
            // described; chosen: a protocol error, reads give 0x00.)
            _ => {
                c.error = true;
                0x00
            }
        }
    }

    /// SEL release: ends the access.
    fn finish(&mut self, c: &mut Cycle) {
        if c.clocked == 0 || c.instr == Instr::Ignore {
            return;
        }
        if c.clocked < c.hdr_len {
            // (gap: an address cut short is not described; chosen: a
            // protocol error, nothing is accessed.)
            c.error = true;
            return;
        }
        // A register DWORD written in part takes effect at SEL release.
        if let Some((a, v, m)) = c.pend.take() {
            self.reg_write(c, a, v, m);
        }
        let data = c.clocked - c.hdr_len;
        if c.target != Target::Reg && !data.is_multiple_of(4) {
            // FIFO transfers move whole DWORDs [SOES rt-kernel-lan9252
            // esc_hw.c:169-177, 233-242]. (gap: the chip's handling of a
            // partial DWORD is not described; chosen: a protocol error,
            // the partial DWORD is dropped (a read one was already
            // popped).)
            c.error = true;
        }
    }
}

/// A PRAM command register's status: bit 31 busy while DWORDs remain,
/// bits 12:8 = min(remaining, 16) DWORDs, bit 0 = some available.
fn fifo_status(remaining: usize) -> u32 {
    if remaining == 0 {
        return 0;
    }
    let n = remaining.min(FIFO_DWORDS) as u32;
    BUSY | (n << 8) | PRAM_AVAIL
}

impl spi::ErrorType for Lan9252Emu {
    type Error = EmuError;
}

impl SpiDevice<u8> for Lan9252Emu {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), EmuError> {
        // One transaction = one CS cycle; keeping CS low continues the
        // transfer [SOES rt-kernel-lan9252 esc_hw.c:179-200, 249-270].
        let total = clocked_len(operations);
        let mut c = Cycle {
            instr: Instr::Ignore,
            hdr_len: 1,
            addr: 0,
            target: Target::Reg,
            clocked: 0,
            latch: 0,
            word: [0; 4],
            pend: None,
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

    fn emu() -> Lan9252Emu {
        let mut sii = [0xFFu8; 128];
        sii[..16].fill(0);
        Lan9252Emu::new(SoftEsc::new(&sii))
    }

    fn xfer<const N: usize>(e: &mut Lan9252Emu, mosi: [u8; N]) -> [u8; N] {
        let mut buf = mosi;
        e.transaction(&mut [Operation::TransferInPlace(&mut buf)])
            .unwrap();
        buf
    }

    /// Fast read of a register DWORD, as SOES does.
    fn rd32(e: &mut Lan9252Emu, a: u16) -> u32 {
        let [h, l] = a.to_be_bytes();
        let m = xfer(e, [0x0B, h, l, 0x00, 0, 0, 0, 0]);
        u32::from_le_bytes([m[4], m[5], m[6], m[7]])
    }

    fn wr32(e: &mut Lan9252Emu, a: u16, v: u32) {
        let [h, l] = a.to_be_bytes();
        let [d0, d1, d2, d3] = v.to_le_bytes();
        xfer(e, [0x02, h, l, d0, d1, d2, d3]);
    }

    fn frame(e: &mut Lan9252Emu, dgs: &[(Command, u16, &[u8])]) {
        let mut buf = [0u8; 256];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
        for (c, ado, d) in dgs {
            b.push(*c, u32::from(*ado) << 16, d).unwrap();
        }
        let len = b.finish();
        e.esc_mut().process_frame(&mut buf[..len]);
    }

    #[test]
    fn byte_test_and_id_rev() {
        let mut e = emu();
        // The SOES vector (dummy byte 0x01 or 0x00).
        assert_eq!(
            xfer(&mut e, [0x0B, 0x00, 0x64, 0x01, 0, 0, 0, 0]),
            [0, 0, 0, 0, 0x21, 0x43, 0x65, 0x87]
        );
        assert_eq!(
            xfer(&mut e, [0x0B, 0x00, 0x64, 0x00, 0, 0, 0, 0])[4..],
            [0x21, 0x43, 0x65, 0x87]
        );
        assert_eq!(
            xfer(&mut e, [0x03, 0x00, 0x50, 0, 0, 0, 0]),
            [0, 0, 0, 0x01, 0x00, 0x52, 0x92]
        );
        // Byte access inside a DWORD, and a burst over two registers.
        assert_eq!(xfer(&mut e, [0x03, 0x00, 0x52, 0, 0])[3..], [0x52, 0x92]);
        let mut d = [0u8; 8];
        e.transaction(&mut [
            Operation::Write(&[0x03, 0x00, 0x50]),
            Operation::Read(&mut d),
        ])
        .unwrap();
        assert_eq!(d, [0x01, 0x00, 0x52, 0x92, 0, 0, 0, 0]);
        assert_eq!(rd32(&mut e, HW_CFG) & (1 << 27), 1 << 27, "READY");
        // BYTE_TEST is read-only; unknown registers read 0.
        wr32(&mut e, BYTE_TEST, 0);
        assert_eq!(rd32(&mut e, BYTE_TEST), 0x8765_4321);
        wr32(&mut e, 0x0100, 0x1234_5678);
        assert_eq!(rd32(&mut e, 0x0100), 0);
        // 0xFF (SQI reset) is a no-op.
        xfer(&mut e, [0xFF]);
        assert_eq!(e.counters().protocol_errors(), 0);
        assert_eq!(e.esc().pdi_accesses(), 0);
        assert_eq!(e.counters().transactions(), 11);
    }

    #[test]
    fn csr_read_of_al_status_in_three_cycles() {
        let mut e = emu();
        e.esc_mut().raw_memory_mut()[0x0130..0x0132].copy_from_slice(&[0x12, 0x00]);
        let pdi = e.esc().pdi_accesses();
        // ECAT_CSR_CMD = 0xC002_0130: busy, read, 2 bytes, 0x0130.
        xfer(&mut e, [0x02, 0x03, 0x04, 0x30, 0x01, 0x02, 0xC0]);
        assert_eq!(e.esc().pdi_accesses(), pdi + 1);
        assert_eq!(
            xfer(&mut e, [0x0B, 0x03, 0x04, 0x00, 0, 0, 0, 0])[4..],
            [0x30, 0x01, 0x02, 0x40],
            "busy clear"
        );
        assert_eq!(
            xfer(&mut e, [0x0B, 0x03, 0x00, 0x00, 0, 0, 0, 0])[4..],
            [0x12, 0x00, 0x00, 0x00]
        );
        assert_eq!(e.esc().pdi_accesses(), pdi + 1, "polls reach no ESC");
        // A 4-byte read of the AL event request (what SOES does after
        // every access) and a 1-byte read at an odd address.
        e.esc_mut().raw_memory_mut()[0x0220..0x0224].copy_from_slice(&[1, 2, 3, 4]);
        wr32(&mut e, ECAT_CSR_CMD, 0xC004_0220);
        assert_eq!(rd32(&mut e, ECAT_CSR_DATA), 0x0403_0201);
        wr32(&mut e, ECAT_CSR_CMD, 0xC001_0223);
        assert_eq!(rd32(&mut e, ECAT_CSR_DATA), 0x04);
        assert_eq!(e.counters().protocol_errors(), 0);
    }

    #[test]
    fn csr_write_of_al_status_code() {
        let mut e = emu();
        let pdi = e.esc().pdi_accesses();
        // DATA = 0x0011, then CMD = 0x8002_0134 (busy, write, 2 bytes).
        xfer(&mut e, [0x02, 0x03, 0x00, 0x11, 0x00, 0x00, 0x00]);
        xfer(&mut e, [0x02, 0x03, 0x04, 0x34, 0x01, 0x02, 0x80]);
        assert_eq!(e.esc().raw_memory()[0x0134..0x0136], [0x11, 0x00]);
        assert_eq!(rd32(&mut e, ECAT_CSR_CMD), 0x0002_0134);
        // Both in one CS cycle: DATA is written before CMD starts.
        xfer(
            &mut e,
            [
                0x02, 0x03, 0x00, 0x1D, 0x00, 0x00, 0x00, 0x34, 0x01, 0x02, 0x80,
            ],
        );
        assert_eq!(e.esc().raw_memory()[0x0134..0x0136], [0x1D, 0x00]);
        assert_eq!(e.esc().pdi_accesses(), pdi + 2);
        assert_eq!(e.counters().protocol_errors(), 0);
    }

    #[test]
    fn fifo_read_of_five_bytes_at_lane_one() {
        let mut e = emu();
        e.esc_mut().raw_memory_mut()[0x1000..0x1008].copy_from_slice(&[9, 1, 2, 3, 4, 5, 6, 7]);
        let pdi = e.esc().pdi_accesses();
        // Abort, address 0x1001 length 5, start.
        xfer(&mut e, [0x02, 0x03, 0x0C, 0x00, 0x00, 0x00, 0x40]);
        xfer(&mut e, [0x02, 0x03, 0x08, 0x01, 0x10, 0x05, 0x00]);
        xfer(&mut e, [0x02, 0x03, 0x0C, 0x00, 0x00, 0x00, 0x80]);
        assert_eq!(e.esc().pdi_accesses(), pdi + 1, "one ESC read");
        // Busy, 2 DWORDs available, available.
        assert_eq!(
            xfer(&mut e, [0x0B, 0x03, 0x0C, 0x00, 0, 0, 0, 0])[4..],
            [0x01, 0x02, 0x00, 0x80]
        );
        assert_eq!(rd32(&mut e, ECAT_PRAM_RD_ADDR_LEN), 0x0005_1001);
        // Both DWORDs in one burst at 0x0000: lane 0 is padding.
        assert_eq!(
            xfer(&mut e, [0x03, 0x00, 0x00, 0, 0, 0, 0, 0, 0, 0, 0])[3..],
            [0x00, 1, 2, 3, 4, 5, 0x00, 0x00]
        );
        assert_eq!(rd32(&mut e, ECAT_PRAM_RD_CMD), 0, "done");
        assert_eq!(e.esc().pdi_accesses(), pdi + 1);
        assert_eq!(e.counters().protocol_errors(), 0);
    }

    #[test]
    fn fifo_write_of_six_bytes_at_lane_two() {
        let mut e = emu();
        let pdi = e.esc().pdi_accesses();
        wr32(&mut e, ECAT_PRAM_WR_ADDR_LEN, 0x0006_1082);
        wr32(&mut e, ECAT_PRAM_WR_CMD, 0x8000_0000);
        assert_eq!(rd32(&mut e, ECAT_PRAM_WR_CMD), 0x8000_0201, "2 DWORDs free");
        // First DWORD: lanes 0-1 padding, then the data; one at 0x0020,
        // the next at an alias.
        xfer(&mut e, [0x02, 0x00, 0x20, 0xEE, 0xEE, 0xA0, 0xA1]);
        assert_eq!(rd32(&mut e, ECAT_PRAM_WR_CMD), 0x8000_0101);
        assert_eq!(e.esc().pdi_accesses(), pdi);
        xfer(&mut e, [0x02, 0x00, 0x24, 0xA2, 0xA3, 0xA4, 0xA5]);
        assert_eq!(e.esc().pdi_accesses(), pdi + 1, "one ESC write");
        assert_eq!(
            e.esc().raw_memory()[0x1080..0x108A],
            [0, 0, 0xA0, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0, 0]
        );
        assert_eq!(rd32(&mut e, ECAT_PRAM_WR_CMD), 0);
        assert_eq!(e.counters().protocol_errors(), 0);
        // A push with no transfer under way is a protocol error.
        xfer(&mut e, [0x02, 0x00, 0x20, 1, 2, 3, 4]);
        assert_eq!(e.counters().protocol_errors(), 1);
        assert_eq!(e.esc().pdi_accesses(), pdi + 1);
    }

    #[test]
    fn fifo_bursts_of_sixteen_dwords() {
        let mut e = emu();
        for (i, x) in e.esc_mut().raw_memory_mut()[0x1000..0x1046]
            .iter_mut()
            .enumerate()
        {
            *x = i as u8;
        }
        wr32(&mut e, ECAT_PRAM_RD_ADDR_LEN, (70 << 16) | 0x1000);
        wr32(&mut e, ECAT_PRAM_RD_CMD, BUSY);
        assert_eq!(rd32(&mut e, ECAT_PRAM_RD_CMD), 0x8000_1001, "16 available");
        let mut d = [0u8; 64];
        e.transaction(&mut [
            Operation::Write(&[0x03, 0x00, 0x00]),
            Operation::Read(&mut d),
        ])
        .unwrap();
        assert!(d.iter().enumerate().all(|(i, &x)| x == i as u8));
        assert_eq!(rd32(&mut e, ECAT_PRAM_RD_CMD), 0x8000_0201);
        // Microchip reads at 0x0004.
        let m = xfer(&mut e, [0x0B, 0x00, 0x04, 0x00, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(m[4..], [64, 65, 66, 67, 68, 69, 0, 0]);
        assert_eq!(rd32(&mut e, ECAT_PRAM_RD_CMD), 0);
        // Write: 70 bytes at 0x1100 in one burst of 18 DWORDs.
        wr32(&mut e, ECAT_PRAM_WR_ADDR_LEN, (70 << 16) | 0x1100);
        wr32(&mut e, ECAT_PRAM_WR_CMD, BUSY);
        assert_eq!(rd32(&mut e, ECAT_PRAM_WR_CMD), 0x8000_1001, "16 free");
        let mut w = [0u8; 72];
        for (i, x) in w.iter_mut().enumerate() {
            *x = 0x80 | i as u8;
        }
        e.transaction(&mut [Operation::Write(&[0x02, 0x00, 0x20]), Operation::Write(&w)])
            .unwrap();
        assert_eq!(e.esc().raw_memory()[0x1100..0x1146], w[..70]);
        assert_eq!(e.esc().raw_memory()[0x1146], 0);
        assert_eq!(e.counters().protocol_errors(), 0);
    }

    #[test]
    fn mailbox_through_the_fifo() {
        let mut e = emu();
        let sm0 = [0x00, 0x10, 0x08, 0x00, 0x26, 0x00, 0x01, 0x00];
        frame(&mut e, &[(Command::Apwr, 0x0800, &sm0)]);
        frame(
            &mut e,
            &[(Command::Apwr, 0x1000, &[1, 2, 3, 4, 5, 6, 7, 8])],
        );
        assert_ne!(e.esc().raw_memory()[0x0805] & 0x08, 0, "full");
        for round in 0..2 {
            wr32(&mut e, ECAT_PRAM_RD_ADDR_LEN, (8 << 16) | 0x1000);
            wr32(&mut e, ECAT_PRAM_RD_CMD, BUSY);
            let m = xfer(&mut e, [0x03, 0x00, 0x00, 0, 0, 0, 0, 0, 0, 0, 0]);
            let want = if round == 0 {
                [1, 2, 3, 4, 5, 6, 7, 8]
            } else {
                [0; 8]
            };
            assert_eq!(m[3..], want);
        }
        assert_eq!(e.esc().raw_memory()[0x0805] & 0x08, 0, "emptied");
        assert_eq!(
            e.counters().refused_accesses(),
            1,
            "second read: mailbox empty"
        );
    }

    #[test]
    fn int_sts_and_irq_follow_event_mask_and_enables() {
        let mut e = emu();
        e.esc_mut().raw_memory_mut()[0x0204..0x0208].fill(0);
        e.esc_mut().raw_memory_mut()[0x0220] = 0x01;
        assert_eq!(rd32(&mut e, INT_STS), 0, "masked");
        // AL event mask 0x0204 = 1 through a CSR write.
        wr32(&mut e, ECAT_CSR_DATA, 1);
        wr32(&mut e, ECAT_CSR_CMD, 0x8004_0204);
        assert_eq!(rd32(&mut e, INT_STS), 1);
        assert!(!e.irq(), "INT_EN and IRQ_CFG not set");
        wr32(&mut e, IRQ_CFG, 0x0000_0111);
        assert!(!e.irq());
        wr32(&mut e, INT_EN, 1);
        assert!(e.irq());
        assert_eq!(rd32(&mut e, IRQ_CFG), 0x111);
        assert_eq!(rd32(&mut e, INT_EN), 1);
        // INT_STS is read-only.
        wr32(&mut e, INT_STS, 0);
        assert_eq!(rd32(&mut e, INT_STS), 1);
        e.esc_mut().raw_memory_mut()[0x0220] = 0x02;
        assert!(!e.irq());
        assert_eq!(rd32(&mut e, INT_STS), 0);
    }

    #[test]
    fn reset_ctl_resets_chip_and_esc() {
        for bit in [0x01u8, 0x40] {
            let mut e = emu();
            e.esc_mut().raw_memory_mut()[0x1000] = 0x55;
            wr32(&mut e, IRQ_CFG, 0x101);
            wr32(&mut e, INT_EN, 1);
            wr32(&mut e, ECAT_PRAM_RD_ADDR_LEN, (4 << 16) | 0x1000);
            wr32(&mut e, ECAT_PRAM_RD_CMD, BUSY);
            xfer(&mut e, [0x02, 0x01, 0xF8, bit, 0x00, 0x00, 0x00]);
            assert_eq!(rd32(&mut e, RESET_CTL), 0, "self-clearing");
            assert_eq!(rd32(&mut e, HW_CFG), 1 << 27, "ready at once");
            assert_eq!(rd32(&mut e, IRQ_CFG), 0);
            assert_eq!(rd32(&mut e, INT_EN), 0);
            assert_eq!(rd32(&mut e, ECAT_PRAM_RD_CMD), 0);
            assert_eq!(e.esc().raw_memory()[0x1000], 0, "process RAM cleared");
            assert_eq!(rd32(&mut e, BYTE_TEST), 0x8765_4321);
            assert_eq!(e.counters().protocol_errors(), 0);
        }
        // Other bits reset nothing.
        let mut e = emu();
        wr32(&mut e, IRQ_CFG, 0x101);
        wr32(&mut e, RESET_CTL, 0x0000_0002);
        assert_eq!(rd32(&mut e, IRQ_CFG), 0x101);
        e.reset();
        assert_eq!(rd32(&mut e, IRQ_CFG), 0);
    }

    #[test]
    fn malformed_accesses_are_counted() {
        let mut e = emu();
        let pdi = e.esc().pdi_accesses();
        // Unknown instruction (quad read), rest ignored.
        assert_eq!(xfer(&mut e, [0xEB, 0x00, 0x64, 0, 0, 0, 0]), [0; 7]);
        assert_eq!(e.counters().protocol_errors(), 1);
        // CSR size 3, size 0, size 2 at an odd address, process RAM.
        for cmd in [
            0xC003_0130u32,
            0xC000_0130,
            0xC002_0131,
            0xC004_0222,
            0xC001_1000,
        ] {
            wr32(&mut e, ECAT_CSR_CMD, cmd);
        }
        assert_eq!(e.counters().protocol_errors(), 6);
        assert_eq!(rd32(&mut e, ECAT_CSR_CMD) & BUSY, 0);
        assert_eq!(e.esc().pdi_accesses(), pdi, "nothing accessed");
        // FIFO read when empty.
        assert_eq!(xfer(&mut e, [0x03, 0x00, 0x00, 0, 0, 0, 0])[3..], [0; 4]);
        assert_eq!(e.counters().protocol_errors(), 7);
        // Partial DWORD: 6 bytes from a 2-DWORD FIFO.
        e.esc_mut().raw_memory_mut()[0x1000..0x1008].copy_from_slice(&[1, 2, 3, 4, 5, 6, 7, 8]);
        wr32(&mut e, ECAT_PRAM_RD_ADDR_LEN, (8 << 16) | 0x1000);
        wr32(&mut e, ECAT_PRAM_RD_CMD, BUSY);
        assert_eq!(
            xfer(&mut e, [0x03, 0x00, 0x00, 0, 0, 0, 0, 0, 0])[3..],
            [1, 2, 3, 4, 5, 6]
        );
        assert_eq!(e.counters().protocol_errors(), 8);
        assert_eq!(rd32(&mut e, ECAT_PRAM_RD_CMD), 0, "dropped");
        // Partial write DWORD.
        wr32(&mut e, ECAT_PRAM_WR_ADDR_LEN, (4 << 16) | 0x1000);
        wr32(&mut e, ECAT_PRAM_WR_CMD, BUSY);
        xfer(&mut e, [0x02, 0x00, 0x20, 1, 2]);
        assert_eq!(e.counters().protocol_errors(), 9);
        // PRAM start below 0x1000 or with length 0.
        wr32(&mut e, ECAT_PRAM_RD_ADDR_LEN, (4 << 16) | 0x0130);
        wr32(&mut e, ECAT_PRAM_RD_CMD, BUSY);
        wr32(&mut e, ECAT_PRAM_WR_ADDR_LEN, 0x1000);
        wr32(&mut e, ECAT_PRAM_WR_CMD, BUSY);
        assert_eq!(e.counters().protocol_errors(), 11);
        // Address cut short; an empty cycle is no error.
        xfer(&mut e, [0x0B, 0x00, 0x64]);
        xfer(&mut e, [0x02, 0x00]);
        e.transaction(&mut []).unwrap();
        assert_eq!(e.counters().protocol_errors(), 13);
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
        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
    }

    #[test]
    fn random_byte_sequences_never_panic() {
        let mut e = emu();
        let sm0 = [0x00, 0x10, 0x08, 0x00, 0x26, 0x00, 0x01, 0x00];
        frame(&mut e, &[(Command::Apwr, 0x0800, &sm0)]);
        let regs = [
            0x0000u16, 0x0004, 0x0020, 0x0050, 0x0054, 0x0058, 0x005C, 0x0064, 0x0074, 0x01F8,
            0x0300, 0x0304, 0x0308, 0x030C, 0x0310, 0x0314,
        ];
        let mut rng = Rng(0x0123_4567_89AB_CDEF);
        let mut a = [0u8; 8];
        let mut b = [0u8; 80];
        let mut c = [0u8; 80];
        for i in 0..4000 {
            for x in a.iter_mut().chain(b.iter_mut()).chain(c.iter_mut()) {
                *x = rng.next() as u8;
            }
            if rng.below(4) != 0 {
                a[0] = [0x02, 0x03, 0x0B, 0xFF][rng.below(4)];
                let r = regs[rng.below(regs.len())] + (rng.below(8) as u16 & 3);
                a[1..3].copy_from_slice(&r.to_be_bytes());
                if rng.below(2) == 0 {
                    // Plausible command words: size 0..7, address in RAM.
                    c[2] = rng.below(8) as u8;
                    c[1] &= 0x3F;
                }
            }
            let la = rng.below(9);
            let (lb, lc) = (rng.below(80), rng.below(80));
            let (b1, b2) = b.split_at_mut(lb);
            let mut ops = [
                Operation::Write(&a[..la]),
                match rng.below(4) {
                    0 => Operation::Write(&c[..lc]),
                    1 => Operation::Read(&mut b1[..]),
                    2 => Operation::Transfer(&mut b1[..], &c[..lc]),
                    _ => Operation::TransferInPlace(&mut b1[..]),
                },
                Operation::Read(&mut b2[..rng.below(6).min(80 - lb)]),
            ];
            e.transaction(&mut ops).unwrap();
            if i % 50 == 0 {
                frame(&mut e, &[(Command::Apwr, 0x1000, &[i as u8; 8])]);
            }
        }
        assert_eq!(e.counters().transactions(), 4000);
        assert!(e.counters().protocol_errors() > 0);
        assert!(e.esc().pdi_accesses() > 0);
    }
}
