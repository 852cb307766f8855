//! EtherCAT Slave Controller.
//!
//! [`Esc`] is the PDI side of an ESC: what firmware sees (read and write
//! ESC memory; events appear in the AL event request register). The software
//! implementation [`soft::SoftEsc`] also processes EtherCAT frames itself; a
//! hardware ESC (e.g. a LAN9252 over SPI) implements the same trait in board
//! support code. This layer knows nothing of CoE, the object dictionary or
//! the amplifier.

pub mod dc;
pub mod registers;
pub mod soft;

/// Errors of PDI access to ESC memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EscError {
    /// The access runs past the end of the ESC's memory.
    #[error("ESC access {addr:#06x}+{len} is outside the ESC memory")]
    OutOfRange {
        /// First address of the access.
        addr: u16,
        /// Length of the access in bytes.
        len: usize,
    },
    /// The SyncManager buffer cannot be accessed now (mailbox empty on a
    /// read, full on a write, or the SM is in the other direction).
    #[error("SyncManager {sm} buffer is not accessible now")]
    SmBusy {
        /// SyncManager number.
        sm: u8,
    },
    /// The hardware interface failed (SPI error and the like).
    #[error("PDI interface failure")]
    Interface,
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
