//! Microchip LAN9252 SPI interface (PDI type 0x80, "LAN9252 compatible
//! SPI").
//!
//! The host side of the LAN9252 is a set of 32-bit system registers
//! reached with SPI instructions (fast read `0B`, serial write `02`, the
//! address MSB first, data little endian). The ESC memory is reached
//! indirectly:
//!
//! - below 0x1000 (ESC registers) through ECAT_CSR_CMD/ECAT_CSR_DATA, in
//!   naturally aligned chunks of 1, 2 or 4 bytes;
//! - from 0x1000 on (process RAM, SyncManager buffers) through the process
//!   RAM read and write FIFOs.
//!
//! An access that crosses 0x1000 is split there: the part below goes
//! through CSR, the rest through the FIFO.
//!
//! SPI cost (SEL cycles; each poll counts once, the counts below assume
//! the chip is ready on the first poll):
//!
//! | access | SEL cycles |
//! |---|---|
//! | system register read/write | 1 |
//! | CSR read of one chunk (1/2/4 bytes) | 3: CMD write, CMD poll, DATA read |
//! | CSR write of one chunk | 3: DATA write, CMD write, CMD poll |
//! | [`Esc::al_event`] | 3 (a 4-byte CSR read of 0x0220; this chip has no address-phase echo) |
//! | FIFO read or write of n bytes at a | 4 + 2 per burst: abort, abort poll, ADDR_LEN, start, then per burst a count poll and one burst of at most 16 DWORDs; ⌈((a & 3) + n) / 4⌉ DWORDs in all |
//!
//! The protocol facts and their sources are listed in `docs/SPI-NOTES.md`
//! (part B); the bracketed keys in the comments refer to that file. Most
//! LAN9252 facts there rest on vendor and SOES code, not on the datasheet.

use crate::check_range;
use ecat_pdi::{Esc, EscError};
use embedded_hal::spi::{Operation, SpiDevice};

/// Instruction 0x0B: fast read, one dummy byte in SPI mode [MCHP lan9252
/// ecat_util.h.ftl:180-205; MCHP-9252HW SPIDriver.h].
const INSTR_FAST_READ: u8 = 0x0B;
/// Instruction 0x02: serial write, no dummy byte [MCHP lan9252
/// ecat_util.h.ftl:180-205].
const INSTR_WRITE: u8 = 0x02;
/// Value clocked out on MOSI for the dummy byte and the data bytes of a
/// read. SOES's Linux driver sends 0x01 as the dummy [SOES
/// drivers/linux/lan9252/lan9252.c:93-121]; the value is a don't-care.
const MOSI_IDLE: u8 = 0x00;

/// ID_REV: chip ID (upper 16 bits) and revision (lower 16 bits) [SOES
/// raspberrypi-lan9252 esc_hw.c:29, 539-540].
pub const ID_REV: u16 = 0x0050;
/// IRQ_CFG: IRQ pin configuration [MCHP drv_lan9252.c:56-59].
pub const IRQ_CFG: u16 = 0x0054;
/// INT_STS: interrupt status [MCHP drv_lan9252.c:56-59].
pub const INT_STS: u16 = 0x0058;
/// INT_EN: interrupt enable [MCHP drv_lan9252.c:56-59].
pub const INT_EN: u16 = 0x005C;
/// BYTE_TEST: reads [`BYTE_TEST_VALUE`] once the chip answers [SOES
/// drivers/linux/lan9252/lan9252.c:68-84].
pub const BYTE_TEST: u16 = 0x0064;
/// HW_CFG: bit 27 = READY [SOES raspberrypi-lan9252 esc_hw.c:27, 36].
pub const HW_CFG: u16 = 0x0074;
/// RESET_CTL: bit 0 = DIGITAL_RST, bit 6 = ETHERCAT_RST [SOES
/// raspberrypi-lan9252 esc_hw.c:26, 33-34].
pub const RESET_CTL: u16 = 0x01F8;
/// ECAT_CSR_DATA: data of an ESC register access [SOES rt-kernel-lan9252
/// esc_hw.c:43-49].
pub const ECAT_CSR_DATA: u16 = 0x0300;
/// ECAT_CSR_CMD: command of an ESC register access [SOES
/// rt-kernel-lan9252 esc_hw.c:43-49].
pub const ECAT_CSR_CMD: u16 = 0x0304;
/// ECAT_PRAM_RD_ADDR_LEN: process RAM read address and length [SOES
/// rt-kernel-lan9252 esc_hw.c:29-41].
pub const ECAT_PRAM_RD_ADDR_LEN: u16 = 0x0308;
/// ECAT_PRAM_RD_CMD: process RAM read command/status [SOES
/// rt-kernel-lan9252 esc_hw.c:29-41].
pub const ECAT_PRAM_RD_CMD: u16 = 0x030C;
/// ECAT_PRAM_WR_ADDR_LEN: process RAM write address and length [SOES
/// rt-kernel-lan9252 esc_hw.c:29-41].
pub const ECAT_PRAM_WR_ADDR_LEN: u16 = 0x0310;
/// ECAT_PRAM_WR_CMD: process RAM write command/status [SOES
/// rt-kernel-lan9252 esc_hw.c:29-41].
pub const ECAT_PRAM_WR_CMD: u16 = 0x0314;
/// Process RAM read data FIFO [SOES rt-kernel-lan9252 esc_hw.c:27-28]
/// (Microchip reads the aliased 0x0004, SPI-NOTES B.3).
pub const ECAT_PRAM_RD_DATA: u16 = 0x0000;
/// Process RAM write data FIFO [SOES rt-kernel-lan9252 esc_hw.c:27-28].
pub const ECAT_PRAM_WR_DATA: u16 = 0x0020;

/// What BYTE_TEST reads (`21 43 65 87` on the wire) [SOES
/// drivers/linux/lan9252/lan9252.c:68-84, 120-121].
pub const BYTE_TEST_VALUE: u32 = 0x8765_4321;
/// The chip ID of the LAN9252 in ID_REV [SOES raspberrypi-lan9252
/// esc_hw.c:539-540].
pub const LAN9252_ID: u16 = 0x9252;

/// HW_CFG bit 27: device ready [SOES raspberrypi-lan9252 esc_hw.c:27, 36].
const HW_CFG_READY: u32 = 1 << 27;
/// RESET_CTL bit 6: EtherCAT reset, self-clearing [SOES
/// raspberrypi-lan9252 esc_hw.c:26, 33-34, 509-517].
const RESET_CTL_ETHERCAT_RST: u32 = 1 << 6;
/// ECAT_CSR_CMD bit 31: busy (write 1 to start, reads 1 while busy)
/// [SOES rt-kernel-lan9252 esc_hw.c:43-49].
const CSR_BUSY: u32 = 1 << 31;
/// ECAT_CSR_CMD bit 30: 1 = read, 0 = write [SOES rt-kernel-lan9252
/// esc_hw.c:43-49; MCHP lan9252 ecat_util.h.ftl:207-211].
const CSR_READ: u32 = 1 << 30;
/// ECAT_PRAM_*_CMD bit 31: busy (write 1 to start) [SOES
/// rt-kernel-lan9252 esc_hw.c:30-38].
const PRAM_BUSY: u32 = 1 << 31;
/// ECAT_PRAM_*_CMD bit 30: abort [SOES rt-kernel-lan9252 esc_hw.c:30-38].
const PRAM_ABORT: u32 = 1 << 30;
/// ECAT_PRAM_*_CMD bits 12:8: DWORDs available in the read FIFO / free in
/// the write FIFO [SOES rt-kernel-lan9252 esc_hw.c:30-38; MCHP-9252HW
/// 9252_HW.h].
const PRAM_COUNT_SHIFT: u32 = 8;
const PRAM_COUNT_MASK: u32 = 0x1F;
/// At most 16 DWORDs per FIFO batch [SOES raspberrypi-lan9252
/// esc_hw.c:172-176]; also the size of the driver's burst buffer.
const MAX_BURST_DWORDS: usize = 16;
/// First process RAM address; below it the ESC is reached through CSR
/// [SOES rt-kernel-lan9252 esc_hw.c:283; MCHP drv_lan9252.c:311].
const PRAM_START: u16 = 0x1000;

/// Reads of BYTE_TEST (in [`Lan9252Spi::init`]) and of HW_CFG (waiting
/// for READY, in `init` and [`Lan9252Spi::reset`]) before giving up.
pub const INIT_POLLS: u32 = 1000;
/// Reads of RESET_CTL waiting for ETHERCAT_RST to clear.
pub const RESET_POLLS: u32 = 1000;
/// Reads of ECAT_CSR_CMD waiting for CSR_BUSY to clear.
pub const CSR_POLLS: u32 = 100;
/// Reads of an ECAT_PRAM_*_CMD register waiting for BUSY to clear after
/// an abort, or for FIFO data/space.
pub const FIFO_POLLS: u32 = 1000;

/// Errors of the LAN9252 driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Lan9252Error {
    /// The SPI device reported an error of this kind.
    #[error("SPI bus error: {0}")]
    Spi(ecat_pdi::BusErrorKind),
    /// BYTE_TEST never read 0x87654321.
    #[error("LAN9252 not responding: BYTE_TEST reads {last:#010x}")]
    NotResponding {
        /// The last value read from BYTE_TEST.
        last: u32,
    },
    /// HW_CFG READY never became set.
    #[error("LAN9252 not ready (HW_CFG READY clear)")]
    NotReady,
    /// RESET_CTL ETHERCAT_RST never cleared.
    #[error("LAN9252 EtherCAT reset did not complete")]
    ResetTimeout,
    /// ECAT_CSR_CMD stayed busy.
    #[error("ECAT_CSR_CMD stayed busy, ESC address {addr:#06x}")]
    CsrTimeout {
        /// ESC address of the register access.
        addr: u16,
    },
    /// A process RAM FIFO stayed busy after abort, or gave no data/space.
    #[error("process RAM FIFO timed out, ESC address {addr:#06x}")]
    FifoTimeout {
        /// ESC start address of the process RAM access.
        addr: u16,
    },
}

impl From<Lan9252Error> for EscError {
    /// An SPI error keeps its kind ([`EscError::Bus`]); the chip's own
    /// failures (timeouts, a chip that does not answer) are interface
    /// failures.
    fn from(e: Lan9252Error) -> Self {
        match e {
            Lan9252Error::Spi(kind) => EscError::Bus(kind),
            _ => EscError::Interface,
        }
    }
}

/// Contents of ID_REV.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChipId {
    /// Chip ID (upper 16 bits of ID_REV), 0x9252 on a LAN9252.
    pub id: u16,
    /// Chip revision (lower 16 bits of ID_REV).
    pub revision: u16,
}

impl ChipId {
    /// Whether the ID is the LAN9252's.
    pub fn is_lan9252(&self) -> bool {
        self.id == LAN9252_ID
    }
}

/// A LAN9252 on an `embedded-hal` 1.0 [`SpiDevice`] (SPI mode, not SQI).
#[derive(Debug)]
pub struct Lan9252Spi<D> {
    spi: D,
    transactions: u32,
}

/// Largest CSR chunk at `addr` for `remaining` bytes: 1, 2 or 4, never
/// crossing the natural alignment, never 3 [SOES rt-kernel-lan9252
/// esc_hw.c:292-321]. 3 bytes at an aligned address go as 2 + 1, as
/// Microchip does [MCHP drv_lan9252.c:223-236].
fn csr_chunk(addr: u16, remaining: usize) -> usize {
    let size = if addr & 1 != 0 {
        1
    } else if addr & 2 != 0 || remaining < 4 {
        if remaining >= 2 { 2 } else { 1 }
    } else {
        4
    };
    size.min(remaining)
}

fn pram_count(cmd: u32) -> usize {
    ((cmd >> PRAM_COUNT_SHIFT) & PRAM_COUNT_MASK) as usize
}

impl<D: SpiDevice> Lan9252Spi<D> {
    /// Wraps an SPI device. Call [`Lan9252Spi::init`] before use.
    pub fn new(spi: D) -> Self {
        Self {
            spi,
            transactions: 0,
        }
    }

    /// The SPI device.
    pub fn spi(&self) -> &D {
        &self.spi
    }

    /// The SPI device, mutably (e.g. to change its clock).
    pub fn spi_mut(&mut self) -> &mut D {
        &mut self.spi
    }

    /// Gives the SPI device back.
    pub fn release(self) -> D {
        self.spi
    }

    /// Number of SEL cycles (SPI transactions) this driver has started,
    /// wrapping; failed transactions count too.
    pub fn transactions(&self) -> u32 {
        self.transactions
    }

    /// Brings the chip up: reads BYTE_TEST until it is 0x87654321 (at most
    /// [`INIT_POLLS`] reads, else [`Lan9252Error::NotResponding`]), waits
    /// for HW_CFG READY (at most [`INIT_POLLS`] reads, else
    /// [`Lan9252Error::NotReady`]) [MCHP drv_lan9252.c:75-79; SOES
    /// raspberrypi-lan9252 esc_hw.c:520-533], then reads ID_REV.
    ///
    /// Lenient: any chip ID is accepted and returned; check
    /// [`ChipId::is_lan9252`] to insist on a LAN9252 (other LAN925x/LAN9253
    /// parts in this mode answer the same way).
    pub fn init(&mut self) -> Result<ChipId, Lan9252Error> {
        let mut last = 0;
        let mut answered = false;
        for _ in 0..INIT_POLLS {
            last = self.read_register(BYTE_TEST)?;
            if last == BYTE_TEST_VALUE {
                answered = true;
                break;
            }
        }
        if !answered {
            return Err(Lan9252Error::NotResponding { last });
        }
        self.wait_ready()?;
        let id_rev = self.read_register(ID_REV)?;
        // Chip ID in the upper 16 bits, revision in the lower [SOES
        // raspberrypi-lan9252 esc_hw.c:539-540].
        Ok(ChipId {
            id: (id_rev >> 16) as u16,
            revision: (id_rev & 0xFFFF) as u16,
        })
    }

    /// Resets the EtherCAT core: writes RESET_CTL with only ETHERCAT_RST
    /// (bit 6) set, reads RESET_CTL until the bit clears (at most
    /// [`RESET_POLLS`] reads, else [`Lan9252Error::ResetTimeout`]), then
    /// waits for HW_CFG READY [SOES raspberrypi-lan9252 esc_hw.c:509-533].
    /// (SOES ANDs the reset bits together and so writes 0, and its
    /// rt-kernel HAL polls the wrong register [SPI-NOTES B.4]; this driver
    /// sets and polls bit 6 of RESET_CTL.)
    pub fn reset(&mut self) -> Result<(), Lan9252Error> {
        self.write_register(RESET_CTL, RESET_CTL_ETHERCAT_RST)?;
        let mut cleared = false;
        for _ in 0..RESET_POLLS {
            if self.read_register(RESET_CTL)? & RESET_CTL_ETHERCAT_RST == 0 {
                cleared = true;
                break;
            }
        }
        if !cleared {
            return Err(Lan9252Error::ResetTimeout);
        }
        self.wait_ready()
    }

    /// Enables the IRQ pin for the EtherCAT (AL event) interrupt: writes
    /// IRQ_CFG with bit 8 (IRQ enable), bit 4 (polarity, 1 = active high)
    /// and bit 0 (buffer type, 1 = push-pull, 0 = open drain), then INT_EN
    /// bit 0. Two SEL cycles. The bit meanings are **inferred** from
    /// Microchip's (0x101) and SOES's (0x111, "push-pull active high")
    /// values, not taken from the datasheet [MCHP drv_lan9252.c:97-109;
    /// SOES raspberrypi-lan9252 esc_hw.c:579-583; SPI-NOTES B.4]. Which AL
    /// events raise the IRQ is set by the AL event mask 0x0204.
    pub fn enable_irq(&mut self, active_high: bool, push_pull: bool) -> Result<(), Lan9252Error> {
        let cfg = (1 << 8) | (u32::from(active_high) << 4) | u32::from(push_pull);
        self.write_register(IRQ_CFG, cfg)?;
        self.write_register(INT_EN, 1)
    }

    /// Reads a 32-bit LAN9252 system register (not ESC memory), one SEL
    /// cycle: `0B AH AL <dummy>` then 4 data bytes, little endian [SOES
    /// rt-kernel-lan9252 esc_hw.c:78-100; SPI-NOTES B.1].
    pub fn read_register(&mut self, addr: u16) -> Result<u32, Lan9252Error> {
        // Address MSB first, one dummy byte for the fast read [SPI-NOTES B.1].
        let [ah, al] = addr.to_be_bytes();
        let header = [INSTR_FAST_READ, ah, al, MOSI_IDLE];
        let mut data = [MOSI_IDLE; 4];
        self.run(&mut [
            Operation::Write(&header),
            Operation::TransferInPlace(&mut data),
        ])?;
        Ok(u32::from_le_bytes(data))
    }

    /// Writes a 32-bit LAN9252 system register (not ESC memory), one SEL
    /// cycle: `02 AH AL d0 d1 d2 d3` [SOES rt-kernel-lan9252
    /// esc_hw.c:57-75; SPI-NOTES B.1].
    pub fn write_register(&mut self, addr: u16, value: u32) -> Result<(), Lan9252Error> {
        let [ah, al] = addr.to_be_bytes();
        let [d0, d1, d2, d3] = value.to_le_bytes();
        self.run(&mut [Operation::Write(&[INSTR_WRITE, ah, al, d0, d1, d2, d3])])
    }

    /// Runs one SEL cycle.
    fn run(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Lan9252Error> {
        self.transactions = self.transactions.wrapping_add(1);
        self.spi
            .transaction(ops)
            .map_err(|e| Lan9252Error::Spi(crate::bus_kind(&e)))
    }

    /// Reads HW_CFG until READY is set [SOES raspberrypi-lan9252
    /// esc_hw.c:528-533].
    fn wait_ready(&mut self) -> Result<(), Lan9252Error> {
        for _ in 0..INIT_POLLS {
            if self.read_register(HW_CFG)? & HW_CFG_READY != 0 {
                return Ok(());
            }
        }
        Err(Lan9252Error::NotReady)
    }

    /// Writes ECAT_CSR_CMD and reads it until CSR_BUSY clears [SOES
    /// rt-kernel-lan9252 esc_hw.c:103-133]. (Microchip's Harmony driver
    /// skips this poll; this driver polls, SPI-NOTES B.2.)
    fn csr_command(&mut self, cmd: u32, addr: u16) -> Result<(), Lan9252Error> {
        self.write_register(ECAT_CSR_CMD, cmd)?;
        for _ in 0..CSR_POLLS {
            if self.read_register(ECAT_CSR_CMD)? & CSR_BUSY == 0 {
                return Ok(());
            }
        }
        Err(Lan9252Error::CsrTimeout { addr })
    }

    /// CSR command word: busy, read/write, size in bits 23:16, ESC address
    /// in bits 15:0 [SOES rt-kernel-lan9252 esc_hw.c:43-49; MCHP
    /// drv_lan9252.c:238-241, 362-365].
    fn csr_word(read: bool, addr: u16, size: usize) -> u32 {
        let rw = if read { CSR_READ } else { 0 };
        CSR_BUSY | rw | ((size as u32) << 16) | u32::from(addr)
    }

    /// Reads ESC registers below 0x1000 through CSR, chunk by chunk.
    fn csr_read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), Lan9252Error> {
        let mut addr = addr;
        let mut rest = buf;
        while !rest.is_empty() {
            let size = csr_chunk(addr, rest.len());
            let (chunk, tail) = core::mem::take(&mut rest).split_at_mut(size);
            // Read: CMD (busy | read | size | addr), poll, then DATA; byte i
            // of DATA is the byte at addr + i [SOES rt-kernel-lan9252
            // esc_hw.c:103-117].
            self.csr_command(Self::csr_word(true, addr, size), addr)?;
            let value = self.read_register(ECAT_CSR_DATA)?.to_le_bytes();
            for (dst, src) in chunk.iter_mut().zip(value) {
                *dst = src;
            }
            addr = addr.wrapping_add(size as u16);
            rest = tail;
        }
        Ok(())
    }

    /// Writes ESC registers below 0x1000 through CSR, chunk by chunk.
    fn csr_write(&mut self, addr: u16, data: &[u8]) -> Result<(), Lan9252Error> {
        let mut addr = addr;
        let mut rest = data;
        while !rest.is_empty() {
            let size = csr_chunk(addr, rest.len());
            let (chunk, tail) = rest.split_at(size);
            // Write: DATA first (the byte at addr in byte 0), then CMD (busy
            // | write | size | addr), then poll [SOES rt-kernel-lan9252
            // esc_hw.c:120-133].
            let mut value = [0u8; 4];
            for (dst, src) in value.iter_mut().zip(chunk) {
                *dst = *src;
            }
            self.write_register(ECAT_CSR_DATA, u32::from_le_bytes(value))?;
            self.csr_command(Self::csr_word(false, addr, size), addr)?;
            addr = addr.wrapping_add(size as u16);
            rest = tail;
        }
        Ok(())
    }

    /// Starts a process RAM FIFO access: ABORT, poll until BUSY clears,
    /// ADDR_LEN (length in bits 31:16, address in 15:0), then BUSY [SOES
    /// rt-kernel-lan9252 esc_hw.c:136-271, 151; SPI-NOTES B.3].
    fn pram_start(
        &mut self,
        cmd_reg: u16,
        addr_len_reg: u16,
        addr: u16,
        len: usize,
    ) -> Result<(), Lan9252Error> {
        self.write_register(cmd_reg, PRAM_ABORT)?;
        let mut idle = false;
        for _ in 0..FIFO_POLLS {
            if self.read_register(cmd_reg)? & PRAM_BUSY == 0 {
                idle = true;
                break;
            }
        }
        if !idle {
            return Err(Lan9252Error::FifoTimeout { addr });
        }
        // len <= 0xF000 here (addr >= 0x1000 and addr + len <= 0x10000).
        let addr_len = ((len as u32) << 16) | u32::from(addr);
        self.write_register(addr_len_reg, addr_len)?;
        self.write_register(cmd_reg, PRAM_BUSY)
    }

    /// Reads `cmd_reg` until its DWORD count (bits 12:8) is non-zero and
    /// returns the count [SOES rt-kernel-lan9252 esc_hw.c:136-271;
    /// raspberrypi-lan9252 esc_hw.c:79-94].
    fn pram_wait_count(&mut self, cmd_reg: u16, addr: u16) -> Result<usize, Lan9252Error> {
        for _ in 0..FIFO_POLLS {
            let count = pram_count(self.read_register(cmd_reg)?);
            if count > 0 {
                return Ok(count);
            }
        }
        Err(Lan9252Error::FifoTimeout { addr })
    }

    /// Reads process RAM through the read FIFO. The FIFO stream starts
    /// with (addr & 3) padding bytes, then the data, then padding to a
    /// whole DWORD [SOES rt-kernel-lan9252 esc_hw.c:169-177; MCHP lan9252
    /// ecat_util.c.ftl:365-370, 417]. Each batch (at most the available
    /// count, the remaining DWORDs and 16) is one SEL cycle of fast read
    /// at the FIFO address [SOES rt-kernel-lan9252 esc_hw.c:179-200].
    fn pram_read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), Lan9252Error> {
        let lead = usize::from(addr & 3);
        self.pram_start(ECAT_PRAM_RD_CMD, ECAT_PRAM_RD_ADDR_LEN, addr, buf.len())?;
        let mut dwords_left = (lead + buf.len()).div_ceil(4);
        // Stream index of the first byte of the next batch.
        let mut stream = 0usize;
        let [ah, al] = ECAT_PRAM_RD_DATA.to_be_bytes();
        let header = [INSTR_FAST_READ, ah, al, MOSI_IDLE];
        while dwords_left > 0 {
            let count = self.pram_wait_count(ECAT_PRAM_RD_CMD, addr)?;
            let n = count.min(dwords_left).min(MAX_BURST_DWORDS);
            let mut burst_buf = [MOSI_IDLE; 4 * MAX_BURST_DWORDS];
            let (burst, _) = burst_buf.split_at_mut(4 * n);
            self.run(&mut [Operation::Write(&header), Operation::TransferInPlace(burst)])?;
            for (i, &byte) in burst.iter().enumerate() {
                // Stream byte s holds the data byte s - lead; padding has none.
                if let Some(dst) = (stream + i).checked_sub(lead).and_then(|j| buf.get_mut(j)) {
                    *dst = byte;
                }
            }
            stream += 4 * n;
            dwords_left -= n;
        }
        Ok(())
    }

    /// Writes process RAM through the write FIFO: the first DWORD carries
    /// the data from byte lane (addr & 3), padding bytes are 0x00, the
    /// last DWORD is padded [SOES rt-kernel-lan9252 esc_hw.c:233-242].
    /// Each batch (at most the free count, the remaining DWORDs and 16) is
    /// one SEL cycle `02 00 20 <data>` [SOES rt-kernel-lan9252
    /// esc_hw.c:249-270].
    fn pram_write(&mut self, addr: u16, data: &[u8]) -> Result<(), Lan9252Error> {
        let lead = usize::from(addr & 3);
        self.pram_start(ECAT_PRAM_WR_CMD, ECAT_PRAM_WR_ADDR_LEN, addr, data.len())?;
        let mut dwords_left = (lead + data.len()).div_ceil(4);
        let mut stream = 0usize;
        let [ah, al] = ECAT_PRAM_WR_DATA.to_be_bytes();
        let header = [INSTR_WRITE, ah, al];
        while dwords_left > 0 {
            let count = self.pram_wait_count(ECAT_PRAM_WR_CMD, addr)?;
            let n = count.min(dwords_left).min(MAX_BURST_DWORDS);
            let mut burst_buf = [0u8; 4 * MAX_BURST_DWORDS];
            let (burst, _) = burst_buf.split_at_mut(4 * n);
            for (i, slot) in burst.iter_mut().enumerate() {
                *slot = (stream + i)
                    .checked_sub(lead)
                    .and_then(|j| data.get(j))
                    .copied()
                    .unwrap_or(0);
            }
            self.run(&mut [Operation::Write(&header), Operation::Write(burst)])?;
            stream += 4 * n;
            dwords_left -= n;
        }
        Ok(())
    }

    /// ESC memory read, split at 0x1000 into a CSR part and a FIFO part.
    fn esc_read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), Lan9252Error> {
        let csr_len = usize::from(PRAM_START.saturating_sub(addr)).min(buf.len());
        let (csr, pram) = buf.split_at_mut(csr_len);
        if !csr.is_empty() {
            self.csr_read(addr, csr)?;
        }
        if !pram.is_empty() {
            self.pram_read(addr.max(PRAM_START), pram)?;
        }
        Ok(())
    }

    /// ESC memory write, split at 0x1000 into a CSR part and a FIFO part.
    fn esc_write(&mut self, addr: u16, data: &[u8]) -> Result<(), Lan9252Error> {
        let csr_len = usize::from(PRAM_START.saturating_sub(addr)).min(data.len());
        let (csr, pram) = data.split_at(csr_len);
        if !csr.is_empty() {
            self.csr_write(addr, csr)?;
        }
        if !pram.is_empty() {
            self.pram_write(addr.max(PRAM_START), pram)?;
        }
        Ok(())
    }
}

impl<D: SpiDevice> Esc for Lan9252Spi<D> {
    /// Below 0x1000 through CSR (3 SEL cycles per 1/2/4-byte chunk), from
    /// 0x1000 on through the read FIFO. Every driver error maps to
    /// [`EscError::Interface`].
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
        check_range(addr, buf.len())?;
        Ok(self.esc_read(addr, buf)?)
    }

    /// Below 0x1000 through CSR (3 SEL cycles per 1/2/4-byte chunk), from
    /// 0x1000 on through the write FIFO. Every driver error maps to
    /// [`EscError::Interface`].
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
        check_range(addr, data.len())?;
        Ok(self.esc_write(addr, data)?)
    }

    /// A 4-byte CSR read of 0x0220..0x0223: three SEL cycles (CMD write,
    /// CMD poll, DATA read). The LAN9252 has no address-phase echo of the
    /// AL event [SPI-NOTES A.2]; this returns all 32 bits.
    fn al_event(&mut self) -> Result<u32, EscError> {
        let mut b = [0u8; 4];
        self.esc_read(0x0220, &mut b)?;
        Ok(u32::from_le_bytes(b))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::et1100::mock::{Expect, Mock, bus_error, t};
    use std::vec;
    use std::vec::Vec;

    /// Expected fast read of a system register returning `value`.
    fn rd(addr: u16, value: u32) -> Expect {
        let [ah, al] = addr.to_be_bytes();
        let mut miso = vec![0; 4];
        miso.extend(value.to_le_bytes());
        t(&[0x0B, ah, al, 0, 0, 0, 0, 0], &miso)
    }

    /// Expected write of a system register.
    fn wr(addr: u16, value: u32) -> Expect {
        let [ah, al] = addr.to_be_bytes();
        let mut mosi = vec![0x02, ah, al];
        mosi.extend(value.to_le_bytes());
        t(&mosi, &[])
    }

    /// A CSR read chunk: CMD write, one poll (idle), DATA read.
    fn csr_rd(addr: u16, size: u32, data: u32) -> Vec<Expect> {
        vec![
            wr(0x0304, 0xC000_0000 | (size << 16) | u32::from(addr)),
            rd(0x0304, 0x4000_0000 | (size << 16) | u32::from(addr)),
            rd(0x0300, data),
        ]
    }

    fn drv(script: Vec<Expect>) -> Lan9252Spi<Mock> {
        Lan9252Spi::new(Mock::new(script))
    }

    #[test]
    fn init_reads_byte_test_as_0b_00_64_then_ready_then_id() {
        let mut d = drv(vec![
            // Not yet answering, then `21 43 65 87` on the wire.
            rd(0x0064, 0xFFFF_FFFF),
            t(
                &[0x0B, 0x00, 0x64, 0x00, 0x00, 0x00, 0x00, 0x00],
                &[0xFF, 0xFF, 0xFF, 0xFF, 0x21, 0x43, 0x65, 0x87],
            ),
            rd(0x0074, 0),
            rd(0x0074, 0x0800_0000),
            rd(0x0050, 0x9252_0003),
        ]);
        let id = d.init().unwrap();
        assert_eq!(
            id,
            ChipId {
                id: 0x9252,
                revision: 3
            }
        );
        assert!(id.is_lan9252());
        assert_eq!(d.transactions(), 5);
    }

    #[test]
    fn init_accepts_another_chip_id_and_returns_it() {
        let mut d = drv(vec![
            rd(0x0064, 0x8765_4321),
            rd(0x0074, 0x0800_0000),
            rd(0x0050, 0x9253_0001),
        ]);
        let id = d.init().unwrap();
        assert_eq!(id.id, 0x9253);
        assert!(!id.is_lan9252());
    }

    #[test]
    fn init_gives_up_with_not_responding_and_last_value() {
        let script = (0..INIT_POLLS).map(|_| rd(0x0064, 0x1234_5678)).collect();
        let mut d = drv(script);
        assert_eq!(
            d.init(),
            Err(Lan9252Error::NotResponding { last: 0x1234_5678 })
        );
    }

    #[test]
    fn init_gives_up_with_not_ready() {
        let mut script = vec![rd(0x0064, 0x8765_4321)];
        script.extend((0..INIT_POLLS).map(|_| rd(0x0074, 0x0000_0000)));
        let mut d = drv(script);
        assert_eq!(d.init(), Err(Lan9252Error::NotReady));
    }

    #[test]
    fn reset_sets_ethercat_rst_polls_until_clear_then_waits_ready() {
        let mut d = drv(vec![
            t(&[0x02, 0x01, 0xF8, 0x40, 0x00, 0x00, 0x00], &[]),
            rd(0x01F8, 0x40),
            rd(0x01F8, 0x40),
            rd(0x01F8, 0x00),
            rd(0x0074, 0x0800_0000),
        ]);
        assert_eq!(d.reset(), Ok(()));
    }

    #[test]
    fn reset_that_never_clears_is_reset_timeout() {
        let mut script = vec![wr(0x01F8, 0x40)];
        script.extend((0..RESET_POLLS).map(|_| rd(0x01F8, 0x40)));
        let mut d = drv(script);
        assert_eq!(d.reset(), Err(Lan9252Error::ResetTimeout));
    }

    #[test]
    fn enable_irq_writes_irq_cfg_bits_8_4_0_and_int_en_bit_0() {
        let mut d = drv(vec![
            wr(0x0054, 0x0000_0111),
            wr(0x005C, 1),
            wr(0x0054, 0x0000_0100),
            wr(0x005C, 1),
        ]);
        d.enable_irq(true, true).unwrap();
        d.enable_irq(false, false).unwrap();
    }

    #[test]
    fn csr_read_of_al_status_is_three_sel_cycles() {
        let mut d = drv(vec![
            // CMD = 0xC0020130: busy | read | size 2 | 0x0130.
            t(&[0x02, 0x03, 0x04, 0x30, 0x01, 0x02, 0xC0], &[]),
            t(
                &[0x0B, 0x03, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00],
                &[0, 0, 0, 0, 0x30, 0x01, 0x02, 0x40],
            ),
            t(
                &[0x0B, 0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00],
                &[0, 0, 0, 0, 0x08, 0x00, 0x00, 0x00],
            ),
        ]);
        assert_eq!(d.read_u16(0x0130), Ok(0x0008));
        assert_eq!(d.transactions(), 3);
    }

    #[test]
    fn csr_poll_repeats_while_busy() {
        let mut d = drv(vec![
            wr(0x0304, 0xC002_0130),
            rd(0x0304, 0xC002_0130),
            rd(0x0304, 0xC002_0130),
            rd(0x0304, 0x4002_0130),
            rd(0x0300, 0x0000_0002),
        ]);
        assert_eq!(d.read_u16(0x0130), Ok(0x0002));
    }

    #[test]
    fn one_byte_csr_write_writes_data_then_command_then_polls() {
        let mut d = drv(vec![
            t(&[0x02, 0x03, 0x00, 0x02, 0x00, 0x00, 0x00], &[]),
            // CMD = 0x80010120: busy | write | size 1 | 0x0120.
            t(&[0x02, 0x03, 0x04, 0x20, 0x01, 0x01, 0x80], &[]),
            rd(0x0304, 0x0001_0120),
        ]);
        assert_eq!(d.write(0x0120, &[0x02]), Ok(()));
    }

    #[test]
    fn three_byte_read_at_aligned_address_splits_2_then_1() {
        let mut script = csr_rd(0x0130, 2, 0x0000_2211);
        script.extend(csr_rd(0x0132, 1, 0x0000_0033));
        let mut d = drv(script);
        let mut buf = [0u8; 3];
        d.read(0x0130, &mut buf).unwrap();
        assert_eq!(buf, [0x11, 0x22, 0x33]);
    }

    #[test]
    fn read_at_odd_address_splits_1_2_1() {
        let mut script = csr_rd(0x0131, 1, 0x0000_00AA);
        script.extend(csr_rd(0x0132, 2, 0x0000_CCBB));
        script.extend(csr_rd(0x0134, 1, 0x0000_00DD));
        let mut d = drv(script);
        let mut buf = [0u8; 4];
        d.read(0x0131, &mut buf).unwrap();
        assert_eq!(buf, [0xAA, 0xBB, 0xCC, 0xDD]);
    }

    #[test]
    fn aligned_u32_read_is_one_chunk_and_write_of_6_bytes_is_4_then_2() {
        let mut script = csr_rd(0x0800, 4, 0x4433_2211);
        script.extend([
            wr(0x0300, 0x0403_0201),
            wr(0x0304, 0x8004_0800),
            rd(0x0304, 0),
            wr(0x0300, 0x0000_0605),
            wr(0x0304, 0x8002_0804),
            rd(0x0304, 0),
        ]);
        let mut d = drv(script);
        assert_eq!(d.read_u32(0x0800), Ok(0x4433_2211));
        assert_eq!(d.write(0x0800, &[1, 2, 3, 4, 5, 6]), Ok(()));
    }

    #[test]
    fn al_event_is_a_four_byte_csr_read_of_0x0220() {
        let mut d = drv(csr_rd(0x0220, 4, 0x0001_0401));
        assert_eq!(d.al_event(), Ok(0x0001_0401));
        assert_eq!(d.transactions(), 3);
    }

    #[test]
    fn csr_busy_forever_is_csr_timeout_and_interface_error() {
        let script = || {
            let mut s = vec![wr(0x0304, 0xC002_0130)];
            s.extend((0..CSR_POLLS).map(|_| rd(0x0304, 0xC002_0130)));
            s
        };
        let mut d = drv(script());
        let mut buf = [0u8; 2];
        assert_eq!(
            d.esc_read(0x0130, &mut buf),
            Err(Lan9252Error::CsrTimeout { addr: 0x0130 })
        );
        let mut d = drv(script());
        assert_eq!(d.read_u16(0x0130), Err(EscError::Interface));
    }

    #[test]
    fn fifo_read_of_5_bytes_at_0x1001_takes_two_dwords_from_lane_1() {
        let mut d = drv(vec![
            wr(0x030C, 0x4000_0000),
            rd(0x030C, 0),
            wr(0x0308, 0x0005_1001),
            wr(0x030C, 0x8000_0000),
            // No data yet, then 2 DWORDs available.
            rd(0x030C, 0x8000_0000),
            rd(0x030C, 0x8000_0201),
            t(
                &[0x0B, 0x00, 0x00, 0x00, 0, 0, 0, 0, 0, 0, 0, 0],
                &[0, 0, 0, 0, 0xEE, 0x01, 0x02, 0x03, 0x04, 0x05, 0xEE, 0xEE],
            ),
        ]);
        let mut buf = [0u8; 5];
        d.read(0x1001, &mut buf).unwrap();
        assert_eq!(buf, [1, 2, 3, 4, 5]);
        assert_eq!(d.transactions(), 7);
    }

    #[test]
    fn fifo_read_follows_available_count_in_several_bursts() {
        // 12 bytes at 0x1000 = 3 DWORDs; the FIFO offers 1, then 2.
        let mut d = drv(vec![
            wr(0x030C, 0x4000_0000),
            rd(0x030C, 0),
            wr(0x0308, 0x000C_1000),
            wr(0x030C, 0x8000_0000),
            rd(0x030C, 0x8000_0101),
            t(&[0x0B, 0, 0, 0, 0, 0, 0, 0], &[0, 0, 0, 0, 1, 2, 3, 4]),
            rd(0x030C, 0x8000_0201),
            t(
                &[0x0B, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
                &[0, 0, 0, 0, 5, 6, 7, 8, 9, 10, 11, 12],
            ),
        ]);
        let mut buf = [0u8; 12];
        d.read(0x1000, &mut buf).unwrap();
        assert_eq!(buf, [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
    }

    #[test]
    fn fifo_read_of_128_byte_mailbox_is_two_bursts_of_16_dwords() {
        let mut script = vec![
            wr(0x030C, 0x4000_0000),
            rd(0x030C, 0),
            wr(0x0308, 0x0080_1000),
            wr(0x030C, 0x8000_0000),
        ];
        for half in 0..2u8 {
            // The count field could say more than 16; bursts stay at 16.
            script.push(rd(0x030C, 0x8000_1F01));
            let mut mosi = vec![0x0B, 0, 0, 0];
            mosi.extend([0u8; 64]);
            let mut miso = vec![0u8; 4];
            miso.extend((0..64u8).map(|i| half * 64 + i));
            script.push(t(&mosi, &miso));
        }
        let mut d = drv(script);
        let mut buf = [0u8; 128];
        d.read(0x1000, &mut buf).unwrap();
        assert!(buf.iter().zip(0..128u8).all(|(&b, v)| b == v));
        assert_eq!(d.transactions(), 8);
    }

    #[test]
    fn fifo_write_of_6_bytes_at_0x1082_pads_lanes_0_1() {
        let mut d = drv(vec![
            wr(0x0314, 0x4000_0000),
            rd(0x0314, 0),
            wr(0x0310, 0x0006_1082),
            wr(0x0314, 0x8000_0000),
            rd(0x0314, 0x8000_1001),
            t(&[0x02, 0x00, 0x20, 0x00, 0x00, 1, 2, 3, 4, 5, 6], &[]),
        ]);
        assert_eq!(d.write(0x1082, &[1, 2, 3, 4, 5, 6]), Ok(()));
        assert_eq!(d.transactions(), 6);
    }

    #[test]
    fn fifo_write_pads_the_last_dword() {
        let mut d = drv(vec![
            wr(0x0314, 0x4000_0000),
            rd(0x0314, 0x8000_0000),
            rd(0x0314, 0),
            wr(0x0310, 0x0003_1003),
            wr(0x0314, 0x8000_0000),
            rd(0x0314, 0x8000_0000),
            rd(0x0314, 0x8000_0201),
            t(&[0x02, 0x00, 0x20, 0, 0, 0, 9, 8, 7, 0, 0], &[]),
        ]);
        assert_eq!(d.write(0x1003, &[9, 8, 7]), Ok(()));
    }

    #[test]
    fn fifo_without_data_is_fifo_timeout() {
        let mut script = vec![
            wr(0x030C, 0x4000_0000),
            rd(0x030C, 0),
            wr(0x0308, 0x0004_1000),
            wr(0x030C, 0x8000_0000),
        ];
        script.extend((0..FIFO_POLLS).map(|_| rd(0x030C, 0x8000_0000)));
        let mut d = drv(script);
        let mut buf = [0u8; 4];
        assert_eq!(
            d.esc_read(0x1000, &mut buf),
            Err(Lan9252Error::FifoTimeout { addr: 0x1000 })
        );
    }

    #[test]
    fn access_crossing_0x1000_uses_csr_below_and_fifo_above() {
        let mut script = csr_rd(0x0FFF, 1, 0x0000_0077);
        script.extend([
            wr(0x030C, 0x4000_0000),
            rd(0x030C, 0),
            wr(0x0308, 0x0001_1000),
            wr(0x030C, 0x8000_0000),
            rd(0x030C, 0x8000_0101),
            t(&[0x0B, 0, 0, 0, 0, 0, 0, 0], &[0, 0, 0, 0, 0x88, 0, 0, 0]),
        ]);
        let mut d = drv(script);
        assert_eq!(d.read_u16(0x0FFF), Ok(0x8877));
    }

    #[test]
    fn out_of_range_and_zero_length_make_no_spi_traffic() {
        let mut d = drv(vec![]);
        let mut buf = [0u8; 4];
        assert_eq!(
            d.read(0xFFFE, &mut buf),
            Err(EscError::OutOfRange {
                addr: 0xFFFE,
                len: 4
            })
        );
        assert_eq!(
            d.write(0xFFFF, &[1, 2]),
            Err(EscError::OutOfRange {
                addr: 0xFFFF,
                len: 2
            })
        );
        assert_eq!(d.read(0x0130, &mut []), Ok(()));
        assert_eq!(d.write(0x1000, &[]), Ok(()));
        assert_eq!(d.transactions(), 0);
    }

    #[test]
    fn a_bus_error_keeps_its_kind_up_to_the_esc_error() {
        let mut d = drv(vec![bus_error(), bus_error()]);
        let other = ecat_pdi::BusErrorKind::Other;
        assert_eq!(d.read_register(0x0064), Err(Lan9252Error::Spi(other)));
        assert_eq!(d.al_event(), Err(EscError::Bus(other)));
        assert_eq!(d.transactions(), 2);
    }

    #[test]
    fn csr_chunks_never_cross_alignment_and_never_are_3() {
        for addr in 0u16..16 {
            for len in 1usize..9 {
                let size = csr_chunk(addr, len);
                assert!(matches!(size, 1 | 2 | 4), "{addr} {len} -> {size}");
                assert!(size <= len);
                assert_eq!(usize::from(addr) % size, 0);
            }
        }
        assert_eq!(csr_chunk(0x0130, 3), 2);
    }
}
