//! # board-bridge: the host side of the emulated board
//!
//! QEMU runs the board's firmware (`examples/board/qemu`) on an emulated
//! Cortex-M4 whose UART0 is a socket. Everything the firmware would do on
//! its SPI bus and its flash arrives there as framed requests
//! ([`board_example::link`]); this crate answers them:
//!
//! * an SPI transaction goes, byte for byte, through the LAN9252 emulation
//!   of `ecat-esc-spi-emu` in front of a software ESC ([`Chip`]), the
//!   chip a master drives over a network interface;
//! * a flash read, program or erase goes to a NOR flash image in a file
//!   ([`FlashImage`]), which outlives QEMU (and the bridge): the FoE image
//!   store and the parameters of the firmware survive a restart of QEMU,
//!   as a board's flash survives a reset.
//!
//! When an EtherCAT frame makes the chip assert its IRQ output, the bridge
//! tells the firmware with an IRQ notice ([`Chip::irq_notice`]).
//!
//! The binary (`src/main.rs`) adds the sockets: the raw socket on the
//! interface, the Unix socket QEMU connects to.

use std::fs::File;
use std::io;
use std::os::unix::fs::FileExt;
use std::path::Path;

use board_example::link::{FLASH_SECTOR, IRQ_NOTICE, Request, SPI};
use ecat_esc_spi_emu::lan9252::Lan9252Emu;
use ecat_sim::esc::SoftEsc;
use embedded_hal::spi::{Operation, SpiDevice};

/// Status byte: done.
pub const OK: u8 = 0;
/// Status byte: the address range is outside the flash.
pub const OUT_OF_RANGE: u8 = 1;
/// Status byte: a program would set a bit from 0 to 1 (not erased).
pub const NOT_ERASED: u8 = 2;
/// Status byte: an erase address not on a sector boundary.
pub const UNALIGNED: u8 = 3;
/// Status byte: the SPI emulation failed the transaction.
pub const SPI_FAILED: u8 = 4;

/// Largest flash image the bridge keeps (1 MiB).
pub const MAX_FLASH: usize = 1 << 20;

/// The ESC chip at the end of the SPI bus: the LAN9252 emulation around
/// a software ESC serving the IO8's SII, and the IRQ level the firmware
/// was last told.
pub struct Chip {
    emu: Lan9252Emu,
    told: bool,
}

impl Chip {
    /// A LAN9252 in front of a software ESC with `sii` in its EEPROM.
    pub fn new(sii: &[u8]) -> Self {
        Chip {
            emu: Lan9252Emu::new(SoftEsc::new(sii)),
            told: false,
        }
    }

    /// The emulated chip.
    pub fn emu(&self) -> &Lan9252Emu {
        &self.emu
    }

    /// The software ESC, for the frames of the master.
    pub fn esc_mut(&mut self) -> &mut SoftEsc {
        self.emu.esc_mut()
    }

    /// The board was reset (QEMU started): the chip powers on again, the
    /// EEPROM keeps its contents.
    pub fn reset(&mut self) {
        self.emu.reset();
        self.told = false;
    }

    /// The notice to send when the IRQ output became asserted since the
    /// firmware last heard of it (after a frame or a watchdog event).
    pub fn irq_notice(&mut self) -> Option<[u8; 2]> {
        let now = self.emu.irq();
        (now && !self.told).then(|| {
            self.told = true;
            [IRQ_NOTICE, 1]
        })
    }

    /// One SPI transaction at time `now_ns`: clocks `mosi` through the
    /// emulation and appends the answer (`'S'`, status, IRQ level, MISO
    /// bytes `skip..skip + keep`) to `out`.
    pub fn spi(&mut self, now_ns: u64, mosi: &[u8], skip: usize, keep: usize, out: &mut Vec<u8>) {
        let esc = self.emu.esc_mut();
        esc.update_watchdogs(now_ns);
        let mut buf = mosi.to_vec();
        let ok = self
            .emu
            .transaction(&mut [Operation::TransferInPlace(&mut buf)])
            .is_ok();
        // Stamp the access with its time (the PDI watchdog).
        self.emu.esc_mut().update_watchdogs(now_ns);
        let irq = self.emu.irq();
        self.told = irq;
        match buf.get(skip..skip + keep) {
            Some(miso) if ok => {
                out.extend_from_slice(&[SPI, OK, u8::from(irq)]);
                out.extend_from_slice(miso);
            }
            _ => out.extend_from_slice(&[SPI, SPI_FAILED, u8::from(irq)]),
        }
    }
}

/// A NOR flash image: erased bytes read 0xFF, a program clears bits only,
/// an erase sets a 4 KiB sector back to 0xFF. Optionally written through
/// to a file, so that it survives the bridge.
pub struct FlashImage {
    bytes: Vec<u8>,
    file: Option<File>,
}

impl FlashImage {
    /// An erased flash in memory only.
    pub fn in_memory() -> Self {
        FlashImage {
            bytes: Vec::new(),
            file: None,
        }
    }

    /// The flash in `path`, created (empty = erased) if missing.
    pub fn open(path: &Path) -> io::Result<Self> {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)?;
        let mut bytes = std::fs::read(path)?;
        bytes.truncate(MAX_FLASH);
        Ok(FlashImage {
            bytes,
            file: Some(file),
        })
    }

    fn range(addr: u32, len: usize) -> Option<std::ops::Range<usize>> {
        let start = usize::try_from(addr).ok()?;
        let end = start.checked_add(len)?;
        (end <= MAX_FLASH).then_some(start..end)
    }

    /// Grows the image (with erased bytes) to hold `end`.
    fn cover(&mut self, end: usize) {
        if self.bytes.len() < end {
            self.bytes.resize(end, 0xFF);
        }
    }

    fn persist(&mut self, start: usize, end: usize) -> io::Result<()> {
        if let (Some(f), Some(bytes)) = (self.file.as_ref(), self.bytes.get(start..end)) {
            f.write_all_at(bytes, start as u64)?;
        }
        Ok(())
    }

    /// Reads `len` bytes at `addr` into `out` (0xFF beyond what was ever
    /// written); the status byte.
    pub fn read(&mut self, addr: u32, len: usize, out: &mut Vec<u8>) -> u8 {
        let Some(r) = Self::range(addr, len) else {
            return OUT_OF_RANGE;
        };
        self.cover(r.end);
        out.extend_from_slice(&self.bytes[r]);
        OK
    }

    /// Programs `data` at `addr`; the status byte.
    pub fn program(&mut self, addr: u32, data: &[u8]) -> u8 {
        let Some(r) = Self::range(addr, data.len()) else {
            return OUT_OF_RANGE;
        };
        self.cover(r.end);
        let target = &mut self.bytes[r.clone()];
        if target.iter().zip(data).any(|(t, d)| d & !t != 0) {
            return NOT_ERASED;
        }
        for (t, d) in target.iter_mut().zip(data) {
            *t &= d;
        }
        match self.persist(r.start, r.end) {
            Ok(()) => OK,
            Err(_) => OUT_OF_RANGE,
        }
    }

    /// Erases `count` sectors from `addr`; the status byte.
    pub fn erase(&mut self, addr: u32, count: u16) -> u8 {
        if !addr.is_multiple_of(FLASH_SECTOR) {
            return UNALIGNED;
        }
        let len = usize::from(count) * FLASH_SECTOR as usize;
        let Some(r) = Self::range(addr, len) else {
            return OUT_OF_RANGE;
        };
        self.cover(r.end);
        self.bytes[r.clone()].fill(0xFF);
        match self.persist(r.start, r.end) {
            Ok(()) => OK,
            Err(_) => OUT_OF_RANGE,
        }
    }
}

/// Answers one request at time `now_ns`, appending the answer to `out`.
pub fn answer(
    req: &Request<'_>,
    now_ns: u64,
    chip: &mut Chip,
    flash: &mut FlashImage,
    out: &mut Vec<u8>,
) {
    match *req {
        Request::Spi { mosi, skip, keep } => chip.spi(now_ns, mosi, skip, keep, out),
        Request::FlashRead { addr, len } => {
            let at = out.len();
            out.extend_from_slice(&[req.code(), OK]);
            let status = flash.read(addr, len, out);
            if let Some(s) = out.get_mut(at + 1) {
                *s = status;
            }
        }
        Request::FlashWrite { addr, data } => {
            out.extend_from_slice(&[req.code(), flash.program(addr, data)]);
        }
        Request::FlashErase { addr, count } => {
            out.extend_from_slice(&[req.code(), flash.erase(addr, count)]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use board_example::link::{FLASH_ERASE, FLASH_READ, FLASH_WRITE};

    fn chip() -> Chip {
        Chip::new(&io8_example::DEVICE.sii_image())
    }

    #[test]
    fn a_byte_test_read_through_the_bridge_answers_0x87654321() {
        let mut c = chip();
        let mut out = Vec::new();
        // Fast read of BYTE_TEST (0x0064): instruction, address, dummy, data.
        let mosi = [0x0B, 0x00, 0x64, 0x00, 0, 0, 0, 0];
        c.spi(0, &mosi, 4, 4, &mut out);
        assert_eq!(out, [SPI, OK, 0, 0x21, 0x43, 0x65, 0x87]);
    }

    #[test]
    fn flash_programs_clear_bits_only_and_erases_restore_0xff() {
        let mut f = FlashImage::in_memory();
        let (mut c, mut out) = (chip(), Vec::new());
        let w = Request::FlashWrite {
            addr: 10,
            data: &[0x0F],
        };
        answer(&w, 0, &mut c, &mut f, &mut out);
        assert_eq!(out, [FLASH_WRITE, OK]);
        out.clear();
        let w2 = Request::FlashWrite {
            addr: 10,
            data: &[0xF0],
        };
        answer(&w2, 0, &mut c, &mut f, &mut out);
        assert_eq!(out, [FLASH_WRITE, NOT_ERASED], "0x0F cannot become 0xF0");
        out.clear();
        answer(
            &Request::FlashRead { addr: 9, len: 3 },
            0,
            &mut c,
            &mut f,
            &mut out,
        );
        assert_eq!(out, [FLASH_READ, OK, 0xFF, 0x0F, 0xFF]);
        out.clear();
        answer(
            &Request::FlashErase { addr: 1, count: 1 },
            0,
            &mut c,
            &mut f,
            &mut out,
        );
        assert_eq!(out, [FLASH_ERASE, UNALIGNED]);
        assert_eq!(f.erase(0, 1), OK);
        assert_eq!(f.bytes[10], 0xFF);
        assert_eq!(f.read(MAX_FLASH as u32, 1, &mut out), OUT_OF_RANGE);
    }

    #[test]
    fn the_flash_file_keeps_what_was_programmed() {
        let path = std::env::temp_dir().join(format!("board-bridge-{}.bin", std::process::id()));
        let _ = std::fs::remove_file(&path);
        let mut f = FlashImage::open(&path).expect("create");
        assert_eq!(f.program(5000, b"abc"), OK);
        drop(f);
        let mut f = FlashImage::open(&path).expect("reopen");
        let mut out = Vec::new();
        assert_eq!(f.read(5000, 3, &mut out), OK);
        assert_eq!(out, b"abc");
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn an_al_event_from_a_frame_is_noticed_once() {
        let mut c = chip();
        assert_eq!(c.irq_notice(), None, "IRQ output not enabled yet");
    }
}
