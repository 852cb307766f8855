//! # ecat-pdi: the contract between a slave core and ESC drivers
//!
//! [`Esc`] is the PDI (Process Data Interface) side of an EtherCAT Slave
//! Controller: what firmware sees of the chip (read and write ESC memory;
//! events appear in the AL event request register 0x0220). A chip driver
//! implements it (the `ecat-esc-spi` crate for the ET1100 family and the
//! LAN9252 over SPI); the slave core (`ecat-slave`) and its software ESC
//! use it. [`registers`] names the ESC registers (ETG.1000.4, the ET1100
//! and LAN9252 datasheets).
//!
//! `#![no_std]`, no dependencies: a driver links exactly this contract.
#![no_std]
#![forbid(unsafe_code)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod registers;

/// Errors of PDI access to ESC memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EscError {
    /// The access runs past the end of the ESC's memory.
    OutOfRange {
        /// First address of the access.
        addr: u16,
        /// Length of the access in bytes.
        len: usize,
    },
    /// The SyncManager buffer cannot be accessed now (mailbox empty on a
    /// read, full on a write, or the SM is in the other direction).
    SmBusy {
        /// SyncManager number.
        sm: u8,
    },
    /// The chip's interface protocol failed (a driver-level timeout, a
    /// status the chip never reached, an answer that cannot be right).
    Interface,
    /// The bus to the chip failed (an SPI transfer error): its kind.
    Bus(BusErrorKind),
}

impl core::fmt::Display for EscError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EscError::OutOfRange { addr, len } => {
                write!(f, "ESC access {addr:#06x}+{len} is outside the ESC memory")
            }
            EscError::SmBusy { sm } => write!(f, "SyncManager {sm} buffer is not accessible now"),
            EscError::Interface => f.write_str("PDI interface failure"),
            EscError::Bus(kind) => write!(f, "PDI bus failure: {kind}"),
        }
    }
}

impl core::error::Error for EscError {}

/// What went wrong on the bus to the chip, as a driver learns it from its
/// bus (the kinds of `embedded-hal` 1.0's `spi::ErrorKind`, so a driver
/// maps them one to one without this crate depending on it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BusErrorKind {
    /// Data arrived before the previous was read.
    Overrun,
    /// A multi-master conflict or a mode fault.
    ModeFault,
    /// The frame format was wrong.
    FrameFormat,
    /// Chip select could not be asserted or released.
    ChipSelectFault,
    /// Anything else the bus reports.
    Other,
}

impl BusErrorKind {
    /// A one-byte code (1..=5) for diagnosis data (an Emergency's byte).
    pub const fn code(self) -> u8 {
        match self {
            BusErrorKind::Overrun => 1,
            BusErrorKind::ModeFault => 2,
            BusErrorKind::FrameFormat => 3,
            BusErrorKind::ChipSelectFault => 4,
            BusErrorKind::Other => 5,
        }
    }
}

impl core::fmt::Display for BusErrorKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            BusErrorKind::Overrun => "overrun",
            BusErrorKind::ModeFault => "mode fault",
            BusErrorKind::FrameFormat => "frame format",
            BusErrorKind::ChipSelectFault => "chip select fault",
            BusErrorKind::Other => "other error",
        })
    }
}

/// The PDI side of an EtherCAT Slave Controller.
///
/// SyncManager rules apply as on silicon: reading the last byte of a
/// mailbox-out buffer empties it, writing the last byte of a mailbox-in
/// buffer marks it full, reading AL control clears the AL control event.
pub trait Esc {
    /// Reads `buf.len()` bytes of ESC memory starting at `addr`.
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError>;

    /// Writes `data` into ESC memory starting at `addr`.
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError>;

    /// Reads a little-endian `u8` register.
    fn read_u8(&mut self, addr: u16) -> Result<u8, EscError> {
        let mut b = [0u8; 1];
        self.read(addr, &mut b)?;
        Ok(b[0])
    }

    /// Reads a little-endian `u16` register.
    fn read_u16(&mut self, addr: u16) -> Result<u16, EscError> {
        let mut b = [0u8; 2];
        self.read(addr, &mut b)?;
        Ok(u16::from_le_bytes(b))
    }

    /// Reads a little-endian `u32` register.
    fn read_u32(&mut self, addr: u16) -> Result<u32, EscError> {
        let mut b = [0u8; 4];
        self.read(addr, &mut b)?;
        Ok(u32::from_le_bytes(b))
    }

    /// Writes a little-endian `u16` register.
    fn write_u16(&mut self, addr: u16, value: u16) -> Result<(), EscError> {
        self.write(addr, &value.to_le_bytes())
    }

    /// The AL event request register (0x0220..0x0223), the first thing
    /// the firmware loop reads on every pass. The default reads it as a
    /// register; a PDI that gets it more cheaply overrides this (an
    /// ET1100-family SPI slave returns 0x0220/0x0221 during the address
    /// phase of every access, so a bare address phase is enough; such a
    /// PDI may return only the low 16 bits, which hold AL control, the
    /// watchdog and the events of SyncManagers 0..7).
    fn al_event(&mut self) -> Result<u32, EscError> {
        self.read_u32(registers::AL_EVENT_REQUEST)
    }
}
