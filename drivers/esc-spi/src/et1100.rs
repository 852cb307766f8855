//! Beckhoff ET1100/ET1200 SPI slave interface (PDI type 0x05).
//!
//! Also fits chips with the same SPI slave protocol: the ASIX AX58100 and
//! the Microchip LAN9253 in "Beckhoff SPI" mode.
//!
//! Every access is one SPI_SEL cycle (one
//! [`SpiDevice::transaction`]): an address phase of 2 or 3 bytes, then a
//! data phase of 0..N bytes. While the master shifts out the address
//! phase, the ESC shifts out the AL event request register (0x0220,
//! 0x0221 and, in 3-byte mode, 0x0222); the driver keeps those bytes
//! ([`Et1100Spi::latched_al_event`]) and answers [`Esc::al_event`] with a
//! bare address phase and no data phase.
//!
//! SPI cost (SEL cycles): one per read, one per write, one per
//! [`Esc::al_event`]. Zero-length accesses make no SPI traffic.
//!
//! The protocol facts and their sources are listed in `docs/SPI-NOTES.md`
//! (part A); the bracketed keys in the comments refer to that file.

use crate::check_range;
use ecat_pdi::{Esc, EscError};
use embedded_hal::spi::{Operation, SpiDevice};

/// CMD 000b: no operation [ET1200-III Table 39; IPX-III Table 45].
const CMD_NOP: u8 = 0b000;
/// CMD 010b: read [ET1200-III Table 39; IPX-III Table 45].
const CMD_READ: u8 = 0b010;
/// CMD 011b: read with following wait-state bytes [IPX-III Table 45;
/// SOES twrk60 esc_hw.c:21-24; MCHP lan9253 ecat_util.h.ftl:360-362].
/// ET1200-III Table 39 lists 011b as reserved; see SPI-NOTES A.1.
const CMD_READ_WAIT: u8 = 0b011;
/// CMD 100b: write [ET1200-III Table 39; IPX-III Table 45].
const CMD_WRITE: u8 = 0b100;
/// CMD0 110b: address extension, a third address/command byte follows
/// [ET1200-III Table 39, Table 40].
const CMD_ADDR_EXT: u8 = 0b110;
/// MOSI value of the wait-state byte [MCHP lan9253 ecat_util.h.ftl:350;
/// ASIX AX58100_SPI.c:162-163].
const WAIT_STATE_BYTE: u8 = 0xFF;
/// MOSI value of the last data byte of a read; every earlier data byte is
/// 0x00 [ET1200-III §6.3.8.2 (cut off); SOES twrk60 esc_hw.c:69-74, 127;
/// SSC el9800hw.c:488, 530-533].
const READ_TERMINATOR: u8 = 0xFF;
/// The 2-byte address phase carries A[12:0] only (A[15:13] = 000b), so it
/// reaches the first 8 KB [ET1200-III §6.3.5, Table 40].
const TWO_BYTE_LIMIT: usize = 0x2000;

/// Which address phase the driver sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Addressing {
    /// 2-byte address phase when every byte of the access lies below
    /// 0x2000, 3-byte address phase when any byte lies at or above 0x2000.
    /// [`Esc::al_event`] then returns 16 bits of events.
    #[default]
    Auto,
    /// Always the 3-byte address phase (the whole 64 KB; the AL event
    /// bytes 0x0220..0x0222 come back in every address phase).
    ThreeByte,
}

/// How the driver covers the ESC's internal read time before the first
/// data byte of a read [ET1200-III §6.3.8.1].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReadMode {
    /// Command 011b followed by one wait-state byte 0xFF on MOSI
    /// [IPX-III Table 45; MCHP lan9253 ecat_util.c.ftl:2051-2056].
    #[default]
    WaitState,
    /// Command 010b with the data phase right after the address phase;
    /// the board must guarantee the internal read time t_read, e.g. by a
    /// slow SPI clock or a SEL/clock timing of the SPI device.
    Plain,
}

/// How [`Esc::al_event`] fetches the AL event request (both ways take it
/// from the address phase; they differ in what the ESC counts as a PDI
/// access).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EventPoll {
    /// A one-byte read of address 0x0000 (the ESC type register), as the
    /// SSC's main loop does [SSC el9800hw.c:166-221]: a real read access,
    /// so it re-arms the ESC's PDI watchdog ("triggered by a correct PDI
    /// read or write access"), and address 0 acknowledges no event
    /// [SSC el9800hw.c:36-37, 45]. One SEL cycle of 3 bytes (4 with the
    /// wait-state byte).
    #[default]
    ReadType,
    /// A bare address phase with the NOP command and no data phase, as
    /// the SSC's interrupt routine does [SSC el9800hw.c:231-270]: 2 bytes,
    /// but no data access, so it does not keep the PDI watchdog alive; an
    /// idle firmware using it must access the ESC otherwise within the
    /// PDI watchdog time (0x0410).
    Nop,
}

/// Configuration of an [`Et1100Spi`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Et1100Config {
    /// Address phase length (default [`Addressing::Auto`]).
    pub addressing: Addressing,
    /// Read command (default [`ReadMode::WaitState`]).
    pub read: ReadMode,
    /// How the AL event request is polled (default [`EventPoll::ReadType`]).
    pub event_poll: EventPoll,
}

/// An ET1100-family ESC on an `embedded-hal` 1.0 [`SpiDevice`].
///
/// The SPI device must be set up for the ESC's SPI mode and SEL polarity
/// (register 0x0150, loaded from the SII EEPROM). Each access is one
/// transaction, i.e. one SEL cycle.
#[derive(Debug)]
pub struct Et1100Spi<D> {
    spi: D,
    config: Et1100Config,
    al_event: u32,
    transactions: u32,
}

/// The address/command phase of one access, plus an optional wait-state
/// byte, as sent on MOSI; after the transfer it holds what came back on
/// MISO.
struct Header {
    bytes: [u8; 4],
    /// Number of address/command bytes (2 or 3).
    address_len: usize,
    /// Number of bytes to send (address bytes plus a wait-state byte).
    len: usize,
}

impl Header {
    /// Builds the address phase for `addr` and `cmd` [ET1200-III Table 40].
    fn new(addr: u16, cmd: u8, three_byte: bool, wait_state: bool) -> Self {
        // Byte 0 = A[12:5] in both modes [ET1200-III Table 40].
        let a12_5 = ((addr >> 5) & 0xFF) as u8;
        // A[4:0] in bits 7:3 of byte 1 [ET1200-III Table 40].
        let a4_0 = ((addr & 0x1F) as u8) << 3;
        let mut bytes = if three_byte {
            // 3-byte mode: byte 1 carries CMD0 = 110b (address extension);
            // byte 2 = A[15:13] in bits 7:5, CMD1 in bits 4:2, res[1:0] = 00b
            // [ET1200-III Table 40; MCHP lan9253 ecat_util.c.ftl:1965-1967].
            let a15_13 = ((addr >> 13) as u8) << 5;
            [a12_5, a4_0 | CMD_ADDR_EXT, a15_13 | (cmd << 2), 0]
        } else {
            // 2-byte mode: CMD0 in bits 2:0 of byte 1 [ET1200-III Table 40].
            [a12_5, a4_0 | cmd, 0, 0]
        };
        let address_len = if three_byte { 3 } else { 2 };
        let mut len = address_len;
        if wait_state {
            // One wait-state byte 0xFF right after the address phase
            // [IPX-III Table 45; ASIX AX58100_SPI.c:162-163].
            if let Some(b) = bytes.get_mut(address_len) {
                *b = WAIT_STATE_BYTE;
            }
            len += 1;
        }
        Self {
            bytes,
            address_len,
            len,
        }
    }

    fn as_mut_slice(&mut self) -> &mut [u8] {
        self.bytes.get_mut(..self.len).unwrap_or(&mut [])
    }

    /// The AL event request bytes the ESC returned during the address
    /// phase: byte 0 = 0x0220, byte 1 = 0x0221, byte 2 = 0x0222 in 3-byte
    /// mode [IPX-III §10.2.6, Table 46; ET1200-III §6.3.6, Table 41].
    /// What comes back during the wait-state byte is not known and is
    /// discarded [SPI-NOTES A.3].
    fn al_event(&self) -> u32 {
        self.bytes
            .iter()
            .take(self.address_len)
            .enumerate()
            .fold(0, |acc, (i, &b)| acc | (u32::from(b) << (8 * i)))
    }
}

impl<D: SpiDevice> Et1100Spi<D> {
    /// Wraps an SPI device.
    pub fn new(spi: D, config: Et1100Config) -> Self {
        Self {
            spi,
            config,
            al_event: 0,
            transactions: 0,
        }
    }

    /// The configuration the driver was built with.
    pub fn config(&self) -> &Et1100Config {
        &self.config
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

    /// The AL event request bytes returned on MISO during the address
    /// phase of the last successful access, little endian: bits 0..7 =
    /// 0x0220, bits 8..15 = 0x0221 and, after a 3-byte address phase, bits
    /// 16..23 = 0x0222 (0 after a 2-byte address phase). 0 before the
    /// first access.
    pub fn latched_al_event(&self) -> u32 {
        self.al_event
    }

    /// Number of SEL cycles (SPI transactions) this driver has started,
    /// wrapping; failed transactions count too.
    pub fn transactions(&self) -> u32 {
        self.transactions
    }

    /// Whether an access of `len` bytes at `addr` uses the 3-byte address
    /// phase. The ESC increments the address itself during the data phase
    /// [ET1100-III §6.3.3]; Auto picks 3 bytes as soon as any byte of the
    /// access lies at or above 0x2000, the 2-byte limit [ET1200-III §6.3.5].
    fn three_byte(&self, addr: u16, len: usize) -> bool {
        match self.config.addressing {
            Addressing::ThreeByte => true,
            Addressing::Auto => usize::from(addr) + len.saturating_sub(1) >= TWO_BYTE_LIMIT,
        }
    }

    /// Runs one SEL cycle.
    fn run(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), EscError> {
        self.transactions = self.transactions.wrapping_add(1);
        self.spi
            .transaction(ops)
            .map_err(|e| EscError::Bus(crate::bus_kind(&e)))
    }
}

impl<D: SpiDevice> Esc for Et1100Spi<D> {
    /// One SEL cycle: address phase (read or read-with-wait-state command,
    /// the AL event bytes are latched), an optional wait-state byte, then
    /// the data phase with MOSI 0x00 on every byte but the last, which is
    /// 0xFF. No maximum length is known [ET1100-III §6.3.3; SPI-NOTES
    /// A.3], so the whole access is one data phase.
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
        check_range(addr, buf.len())?;
        if buf.is_empty() {
            return Ok(());
        }
        let wait_state = self.config.read == ReadMode::WaitState;
        let cmd = if wait_state { CMD_READ_WAIT } else { CMD_READ };
        let mut header = Header::new(addr, cmd, self.three_byte(addr, buf.len()), wait_state);
        // Read termination: 0x00 on MOSI for every data byte but the last,
        // 0xFF for the last [ET1200-III §6.3.8.2; SOES twrk60
        // esc_hw.c:69-74, 127; SSC el9800hw.c:530-533]. The buffer itself
        // carries the MOSI pattern (TransferInPlace), so no extra buffer.
        buf.fill(0x00);
        if let Some(last) = buf.last_mut() {
            *last = READ_TERMINATOR;
        }
        self.run(&mut [
            Operation::TransferInPlace(header.as_mut_slice()),
            Operation::TransferInPlace(buf),
        ])?;
        self.al_event = header.al_event();
        Ok(())
    }

    /// One SEL cycle: address phase with the write command (the AL event
    /// bytes are latched), then the data bytes; releasing SEL ends the
    /// write, there is no termination byte [ET1200-III §6.3.7; IPX-III
    /// §10.2.7].
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
        check_range(addr, data.len())?;
        if data.is_empty() {
            return Ok(());
        }
        let mut header = Header::new(addr, CMD_WRITE, self.three_byte(addr, data.len()), false);
        self.run(&mut [
            Operation::TransferInPlace(header.as_mut_slice()),
            Operation::Write(data),
        ])?;
        self.al_event = header.al_event();
        Ok(())
    }

    /// One SEL cycle at address 0 ([`EventPoll`]): a one-byte read of the
    /// type register (`00 03 FF FF` with the wait-state byte, `00 02 FF`
    /// without), or a bare NOP address phase (`00 00`, as the SSC's
    /// interrupt routine does [SSC el9800hw.c:231-270]); address 0
    /// acknowledges no event [SSC el9800hw.c:36-37, 45]. Returns the AL
    /// event bytes of the address phase [IPX-III §10.2.6, Table 46]: with
    /// [`Addressing::Auto`] only 0x0220:0x0221 (bits 16..31 are 0), with
    /// [`Addressing::ThreeByte`] 0x0220..0x0222 (bits 24..31 are 0).
    fn al_event(&mut self) -> Result<u32, EscError> {
        if self.config.event_poll == EventPoll::ReadType {
            let mut type_register = [0u8; 1];
            self.read(0x0000, &mut type_register)?;
            return Ok(self.al_event);
        }
        let three_byte = self.config.addressing == Addressing::ThreeByte;
        let mut header = Header::new(0x0000, CMD_NOP, three_byte, false);
        self.run(&mut [Operation::TransferInPlace(header.as_mut_slice())])?;
        self.al_event = header.al_event();
        Ok(self.al_event)
    }
}

/// A scripted [`SpiDevice`] for the unit tests of both drivers.
#[cfg(test)]
pub(crate) mod mock {
    extern crate std;

    use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
    use std::collections::VecDeque;
    use std::format;
    use std::string::String;
    use std::vec::Vec;

    /// One expected SEL cycle.
    #[derive(Debug)]
    pub(crate) struct Expect {
        /// MOSI bytes of the whole SEL cycle.
        pub mosi: Vec<u8>,
        /// MISO bytes handed back (missing ones are 0x00).
        pub miso: Vec<u8>,
        /// Fail the transaction with a bus error instead.
        pub fail: bool,
    }

    /// An expected SEL cycle with MOSI and the MISO answer.
    pub(crate) fn t(mosi: &[u8], miso: &[u8]) -> Expect {
        assert!(miso.len() <= mosi.len(), "MISO longer than MOSI");
        Expect {
            mosi: mosi.to_vec(),
            miso: miso.to_vec(),
            fail: false,
        }
    }

    /// A SEL cycle that fails with a bus error.
    pub(crate) fn bus_error() -> Expect {
        Expect {
            mosi: Vec::new(),
            miso: Vec::new(),
            fail: true,
        }
    }

    fn hex(bytes: &[u8]) -> String {
        bytes
            .iter()
            .map(|b| format!("{b:02X}"))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Asserts MOSI per transaction, fails on extra transactions, and on
    /// drop on missing ones.
    #[derive(Debug)]
    pub(crate) struct Mock {
        script: VecDeque<Expect>,
        done: usize,
    }

    impl Mock {
        pub(crate) fn new(script: impl IntoIterator<Item = Expect>) -> Self {
            Self {
                script: script.into_iter().collect(),
                done: 0,
            }
        }

        /// Number of transactions run so far.
        pub(crate) fn done(&self) -> usize {
            self.done
        }
    }

    impl Drop for Mock {
        fn drop(&mut self) {
            if !std::thread::panicking() {
                assert!(
                    self.script.is_empty(),
                    "{} expected transaction(s) missing after {} done; next MOSI {}",
                    self.script.len(),
                    self.done,
                    self.script
                        .front()
                        .map(|e| hex(&e.mosi))
                        .unwrap_or_default()
                );
            }
        }
    }

    impl ErrorType for Mock {
        type Error = ErrorKind;
    }

    impl SpiDevice for Mock {
        fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
            let n = self.done;
            let exp = self
                .script
                .pop_front()
                .unwrap_or_else(|| panic!("unexpected extra transaction #{n}"));
            self.done += 1;
            if exp.fail {
                return Err(ErrorKind::Other);
            }
            let mut mosi = Vec::new();
            let mut miso = exp.miso.iter().copied();
            for op in ops.iter_mut() {
                match op {
                    Operation::Write(data) => {
                        mosi.extend_from_slice(data);
                        miso.by_ref().take(data.len()).for_each(drop);
                    }
                    Operation::TransferInPlace(buf) => {
                        for b in buf.iter_mut() {
                            mosi.push(*b);
                            *b = miso.next().unwrap_or(0);
                        }
                    }
                    Operation::Transfer(read, write) => {
                        assert_eq!(read.len(), write.len(), "unequal Transfer lengths");
                        for (r, w) in read.iter_mut().zip(write.iter()) {
                            mosi.push(*w);
                            *r = miso.next().unwrap_or(0);
                        }
                    }
                    Operation::Read(_) => panic!("Operation::Read leaves MOSI undefined"),
                    Operation::DelayNs(_) => {}
                }
            }
            assert_eq!(
                hex(&mosi),
                hex(&exp.mosi),
                "MOSI of transaction #{n} (left: sent, right: expected)"
            );
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::mock::{Mock, bus_error, t};
    use super::*;
    use std::vec;

    fn plain() -> Et1100Config {
        Et1100Config {
            addressing: Addressing::Auto,
            read: ReadMode::Plain,
            event_poll: EventPoll::Nop,
        }
    }

    fn drv(config: Et1100Config, script: std::vec::Vec<mock::Expect>) -> Et1100Spi<Mock> {
        Et1100Spi::new(Mock::new(script), config)
    }

    #[test]
    fn default_config_is_auto_addressing_with_wait_state() {
        let c = Et1100Config::default();
        assert_eq!(c.addressing, Addressing::Auto);
        assert_eq!(c.read, ReadMode::WaitState);
    }

    #[test]
    fn read_of_al_status_sends_09_82_then_terminates_with_ff() {
        let mut d = drv(
            plain(),
            vec![t(&[0x09, 0x82, 0x00, 0xFF], &[0x11, 0x22, 0x08, 0x00])],
        );
        assert_eq!(d.read_u16(0x0130), Ok(0x0008));
        assert_eq!(d.transactions(), 1);
    }

    #[test]
    fn wait_state_read_of_al_status_sends_09_83_ff_00_ff() {
        let mut d = drv(
            Et1100Config::default(),
            vec![t(
                &[0x09, 0x83, 0xFF, 0x00, 0xFF],
                &[0x01, 0x00, 0xA5, 0x04, 0x00],
            )],
        );
        assert_eq!(d.read_u16(0x0130), Ok(0x0004));
        assert_eq!(d.latched_al_event(), 0x0001);
    }

    #[test]
    fn write_of_al_control_sends_09_04_then_data_low_byte_first() {
        let mut d = drv(plain(), vec![t(&[0x09, 0x04, 0x02, 0x00], &[])]);
        assert_eq!(d.write_u16(0x0120, 0x0002), Ok(()));
        assert_eq!(d.transactions(), 1);
    }

    #[test]
    fn read_at_0x3000_uses_three_byte_phase_80_06_28() {
        let mut d = drv(
            plain(),
            vec![t(
                &[0x80, 0x06, 0x28, 0x00, 0x00, 0x00, 0xFF],
                &[0x01, 0x02, 0x03, 0xDD, 0xCC, 0xBB, 0xAA],
            )],
        );
        assert_eq!(d.read_u32(0x3000), Ok(0xAABB_CCDD));
        assert_eq!(d.latched_al_event(), 0x0003_0201);
    }

    #[test]
    fn wait_state_read_in_three_byte_mode_puts_ff_after_third_byte() {
        let cfg = Et1100Config {
            addressing: Addressing::ThreeByte,
            read: ReadMode::WaitState,
            event_poll: EventPoll::Nop,
        };
        // 0x0130: A[12:5] = 0x09, A[4:0] = 0x10 -> 0x80 | 110b; byte 2 = 011b << 2.
        let mut d = drv(
            cfg,
            vec![t(
                &[0x09, 0x86, 0x0C, 0xFF, 0x00, 0xFF],
                &[0, 0, 0, 0, 0x02, 0x00],
            )],
        );
        assert_eq!(d.read_u16(0x0130), Ok(0x0002));
    }

    #[test]
    fn write_in_three_byte_mode_puts_command_in_byte_2() {
        // 0x2F01: A[12:5] = 0x78, A[4:0] = 1 -> 0x08 | 110b, A[15:13] = 1 -> 0x20 | 100b << 2.
        let mut d = drv(plain(), vec![t(&[0x78, 0x0E, 0x30, 0xAB], &[])]);
        assert_eq!(d.write(0x2F01, &[0xAB]), Ok(()));
    }

    #[test]
    fn one_byte_read_sends_only_ff_in_data_phase() {
        // The SSC's read of one byte at 0x0000: `00 02 FF` [SSC el9800hw.c:180-208].
        let mut d = drv(plain(), vec![t(&[0x00, 0x02, 0xFF], &[0x04, 0x00, 0x5A])]);
        assert_eq!(d.read_u8(0x0000), Ok(0x5A));
        assert_eq!(d.latched_al_event(), 0x0004);
    }

    #[test]
    fn default_al_event_poll_reads_the_type_register_and_returns_the_address_phase() {
        let mut d = drv(
            Et1100Config::default(),
            vec![t(&[0x00, 0x03, 0xFF, 0xFF], &[0x01, 0x04, 0x00, 0x11])],
        );
        assert_eq!(d.al_event(), Ok(0x0401));
        assert_eq!(d.transactions(), 1);
    }

    #[test]
    fn al_event_poll_sends_00_00_and_returns_miso_bytes() {
        let mut d = drv(
            Et1100Config {
                event_poll: EventPoll::Nop,
                ..Et1100Config::default()
            },
            vec![t(&[0x00, 0x00], &[0x01, 0x04])],
        );
        assert_eq!(d.al_event(), Ok(0x0401));
        assert_eq!(d.latched_al_event(), 0x0401);
        assert_eq!(d.transactions(), 1);
    }

    #[test]
    fn al_event_poll_in_three_byte_mode_sends_00_06_00_and_returns_24_bits() {
        let cfg = Et1100Config {
            addressing: Addressing::ThreeByte,
            read: ReadMode::Plain,
            event_poll: EventPoll::Nop,
        };
        let mut d = drv(cfg, vec![t(&[0x00, 0x06, 0x00], &[0x01, 0x04, 0x02])]);
        assert_eq!(d.al_event(), Ok(0x0002_0401));
    }

    #[test]
    fn latched_al_event_follows_every_address_phase() {
        let mut d = drv(
            plain(),
            vec![
                t(&[0x09, 0x82, 0x00, 0xFF], &[0x10, 0x00, 0x01, 0x00]),
                t(&[0x09, 0x04, 0x08], &[0x00, 0x01]),
            ],
        );
        assert_eq!(d.latched_al_event(), 0);
        d.read_u16(0x0130).unwrap();
        assert_eq!(d.latched_al_event(), 0x0010);
        d.write(0x0120, &[0x08]).unwrap();
        assert_eq!(d.latched_al_event(), 0x0100);
    }

    #[test]
    fn auto_addressing_switches_to_three_bytes_at_0x2000() {
        let mut d = drv(
            plain(),
            vec![
                // 0x1FFF, 1 byte: 2-byte phase FF FA.
                t(&[0xFF, 0xFA, 0xFF], &[0, 0, 0x11]),
                // 0x2000, 1 byte: 3-byte phase 00 06 28.
                t(&[0x00, 0x06, 0x28, 0xFF], &[0, 0, 0, 0x22]),
                // 0x1FFF, 2 bytes, reaching 0x2000: 3-byte phase FF FE 08.
                t(&[0xFF, 0xFE, 0x08, 0x00, 0xFF], &[0, 0, 0, 0x11, 0x22]),
            ],
        );
        assert_eq!(d.read_u8(0x1FFF), Ok(0x11));
        assert_eq!(d.read_u8(0x2000), Ok(0x22));
        assert_eq!(d.read_u16(0x1FFF), Ok(0x2211));
    }

    #[test]
    fn long_read_is_one_sel_cycle_terminated_by_ff() {
        let mut mosi = vec![0x80, 0x06, 0x28];
        mosi.extend(core::iter::repeat_n(0x00, 127));
        mosi.push(0xFF);
        let mut miso = vec![0x01, 0x00, 0x00];
        miso.extend(1..=128u8);
        let mut d = drv(plain(), vec![t(&mosi, &miso)]);
        let mut buf = [0u8; 128];
        assert_eq!(d.read(0x3000, &mut buf), Ok(()));
        assert!(buf.iter().zip(1..=128u8).all(|(&b, v)| b == v));
        assert_eq!(d.transactions(), 1);
    }

    #[test]
    fn zero_length_accesses_make_no_spi_traffic() {
        let mut d = drv(plain(), vec![]);
        assert_eq!(d.read(0x1000, &mut []), Ok(()));
        assert_eq!(d.write(0xFFFF, &[]), Ok(()));
        assert_eq!(d.transactions(), 0);
    }

    #[test]
    fn access_past_0xffff_is_out_of_range_without_spi_traffic() {
        let mut d = drv(plain(), vec![]);
        let mut buf = [0u8; 2];
        assert_eq!(
            d.read(0xFFFF, &mut buf),
            Err(EscError::OutOfRange {
                addr: 0xFFFF,
                len: 2
            })
        );
        assert_eq!(
            d.write(0xFFFE, &[1, 2, 3]),
            Err(EscError::OutOfRange {
                addr: 0xFFFE,
                len: 3
            })
        );
        assert_eq!(d.transactions(), 0);
        assert_eq!(d.spi().done(), 0);
    }

    #[test]
    fn last_byte_of_memory_is_readable() {
        // 0xFFFF: A[12:5] = 0xFF, A[4:0] = 0x1F -> 0xF8 | 110b, A[15:13] = 7 -> 0xE0 | 0x08.
        let mut d = drv(
            plain(),
            vec![t(&[0xFF, 0xFE, 0xE8, 0xFF], &[0, 0, 0, 0x77])],
        );
        assert_eq!(d.read_u8(0xFFFF), Ok(0x77));
    }

    #[test]
    fn a_bus_error_keeps_its_kind_and_the_latched_event() {
        let mut d = drv(
            plain(),
            vec![
                t(&[0x00, 0x00], &[0x05, 0x00]),
                bus_error(),
                bus_error(),
                bus_error(),
            ],
        );
        assert_eq!(d.al_event(), Ok(0x0005));
        let bus = Err(EscError::Bus(ecat_pdi::BusErrorKind::Other));
        assert_eq!(d.read_u16(0x0130), bus);
        assert_eq!(d.write_u16(0x0120, 2).map(|_| 0), bus);
        assert_eq!(d.al_event().map(|_| 0), bus);
        assert_eq!(d.latched_al_event(), 0x0005);
        assert_eq!(d.transactions(), 4);
    }
}
