//! File access over EtherCAT (FoE, ETG.1000.6 §5.8 "File Access over
//! EtherCAT"; Table "FoE elements"): the data of a mailbox of type
//! [`MailboxType::FoE`](super::mailbox::MailboxType::FoE), i.e. everything
//! after the 6-byte mailbox header.
//!
//! ```text
//!  0        1          2                                6
//! +--------+----------+--------------------------------+----------------------
//! | opcode | reserved | u32 password / packet / error  | name / data / text
//! +--------+----------+--------------------------------+----------------------
//!  BUSY only: bytes 2..4 u16 done, bytes 4..6 u16 entire
//! ```
//!
//! | opcode | service       | bytes 2..6         | tail                 |
//! |--------|---------------|--------------------|----------------------|
//! | 1      | read request  | password           | file name            |
//! | 2      | write request | password           | file name            |
//! | 3      | data          | packet number      | file data            |
//! | 4      | ack           | packet number      | —                    |
//! | 5      | error         | error code         | error text           |
//! | 6      | busy          | u16 done, u16 entire | —                  |
//!
//! The file name, data and error text have no terminator: they run to the
//! end of the mailbox data (the mailbox header's length field).

use super::{Field, Rest, WireError};
use crate::codes::protocol_codes;

/// Length of the FoE header (opcode, reserved byte, 32-bit word).
pub const HEADER_LEN: usize = field::TAIL.start;

mod field {
    use super::{Field, Rest};

    /// Operation code ([`super::FoeOpcode`]).
    pub const OPCODE: usize = 0;
    /// Reserved, 0.
    pub const RESERVED: usize = 1;
    /// Password (RRQ/WRQ), packet number (DATA/ACK) or error code (ERR).
    pub const WORD: Field = 2..6;
    /// BUSY: progress, "done" part.
    pub const BUSY_DONE: Field = 2..4;
    /// BUSY: progress, "entire" part.
    pub const BUSY_ENTIRE: Field = 4..6;
    /// File name (RRQ/WRQ), data (DATA) or error text (ERR).
    pub const TAIL: Rest = 6..;
}

protocol_codes! {
    /// FoE operation code (ETG.1000.6 §5.8, Table "FoE elements", `OpCode`).
    ///
    /// Each variant's discriminant is its code (`repr(u8)`): the conversion
    /// to `u8` compiles to the tag. `Unknown`'s tag is not a code.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum FoeOpcode(u8) {
        /// `1`: read request (upload, slave → master).
        ReadRequest = 1,
        /// `2`: write request (download, master → slave).
        WriteRequest = 2,
        /// `3`: one packet of file data.
        Data = 3,
        /// `4`: acknowledges a write request (packet 0) or a data packet.
        Ack = 4,
        /// `5`: aborts the transfer with an error code and text.
        Error = 5,
        /// `6`: the receiver cannot take the packet yet; it is to be repeated.
        Busy = 6,
    } else {
        /// Any other value.
        Unknown = 0xFF,
    }
}

protocol_codes! {
    /// FoE error code (ETG.1000.6 §5.8, Table "FoE error codes", `0x8000` to
    /// `0x800B`).
    ///
    /// `0x800C` to `0x8011` are not in that table; they are defined by ETG's
    /// EtherCAT Slave Stack Code (`foeappl.h`, SSC 5.12) and are decoded by
    /// common masters (TwinCAT, EC-Master), so this stack uses them for
    /// firmware-image errors, where they say more than "program error".
    ///
    /// Each variant's discriminant is its code (`repr(u32)`), so the
    /// conversion to `u32`, a `match` returning them, compiles to the tag
    /// itself. `Unknown`'s tag is 0xFFFFFFFF, not a code: its field holds it.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum FoeErrorCode(u32) {
        /// `0x8000` Not defined (see the error text).
        NotDefined = 0x8000,
        /// `0x8001` The file requested by a read request does not exist.
        NotFound = 0x8001,
        /// `0x8002` Access to the file is not allowed.
        AccessDenied = 0x8002,
        /// `0x8003` Disk full: the file does not fit the storage.
        DiskFull = 0x8003,
        /// `0x8004` Illegal FoE operation (e.g. unexpected or unknown opcode).
        Illegal = 0x8004,
        /// `0x8005` Packet number wrong.
        PacketNumberWrong = 0x8005,
        /// `0x8006` The file already exists.
        AlreadyExists = 0x8006,
        /// `0x8007` No user.
        NoUser = 0x8007,
        /// `0x8008` Bootstrap only: the service is available in BOOT only.
        BootstrapOnly = 0x8008,
        /// `0x8009` Not bootstrap: this file (name) is not valid in BOOT.
        NotBootstrap = 0x8009,
        /// `0x800A` No rights: password invalid.
        NoRights = 0x800A,
        /// `0x800B` Program error (generic, when no other code applies).
        ProgramError = 0x800B,
        /// `0x800C` (SSC) Checksum included in the file is invalid.
        InvalidChecksum = 0x800C,
        /// `0x800D` (SSC) The hardware does not support this firmware.
        InvalidFirmware = 0x800D,
        /// `0x800F` (SSC) No file to read (deprecated, same as `NotFound`).
        NoFile = 0x800F,
        /// `0x8010` (SSC) File header missing or wrong.
        NoFileHeader = 0x8010,
        /// `0x8011` (SSC) Flash cannot be accessed.
        FlashError = 0x8011,
    } else {
        /// Any other value.
        Unknown = 0xFFFF_FFFF,
    }
}

impl FoeErrorCode {
    /// Short description, usable as the error text of an ERR packet.
    pub const fn text(self) -> &'static str {
        match self {
            Self::NotDefined => "not defined",
            Self::NotFound => "file not found",
            Self::AccessDenied => "access denied",
            Self::DiskFull => "disk full",
            Self::Illegal => "illegal FoE operation",
            Self::PacketNumberWrong => "packet number wrong",
            Self::AlreadyExists => "file already exists",
            Self::NoUser => "no user",
            Self::BootstrapOnly => "bootstrap only",
            Self::NotBootstrap => "file not valid in bootstrap",
            Self::NoRights => "no rights (password invalid)",
            Self::ProgramError => "program error",
            Self::InvalidChecksum => "invalid checksum",
            Self::InvalidFirmware => "firmware not supported by this hardware",
            Self::NoFile => "no file",
            Self::NoFileHeader => "file header missing or wrong",
            Self::FlashError => "flash cannot be accessed",
            Self::Unknown(_) => "unknown FoE error",
        }
    }
}

impl core::fmt::Display for FoeErrorCode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:#06x}: {}", u32::from(*self), self.text())
    }
}

/// A read/write view of an FoE packet, the data of an FoE mailbox
/// (ETG.1000.6 §5.8). The view spans exactly the mailbox data: the tail
/// (name, data, text) runs to the end of the buffer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Foe<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Foe<T> {
    /// Wraps a buffer without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`Foe::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let foe = Self::new_unchecked(buffer);
        foe.check_len()?;
        Ok(foe)
    }

    /// Checks that the 6-byte FoE header is present
    /// ([`WireError::Truncated`] otherwise).
    pub fn check_len(&self) -> Result<(), WireError> {
        if self.buffer.as_ref().len() < HEADER_LEN {
            Err(WireError::Truncated)
        } else {
            Ok(())
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Operation code.
    pub fn opcode(&self) -> FoeOpcode {
        FoeOpcode::from(super::get_u8(self.buffer.as_ref(), field::OPCODE))
    }

    /// The reserved byte (0 when sent by this stack).
    pub fn reserved(&self) -> u8 {
        super::get_u8(self.buffer.as_ref(), field::RESERVED)
    }

    /// Bytes 2..6 as one little-endian `u32` (password, packet number or
    /// error code, depending on the opcode).
    pub fn word(&self) -> u32 {
        super::get_u32_le(self.buffer.as_ref(), field::WORD)
    }

    /// Password of a read or write request.
    pub fn password(&self) -> u32 {
        self.word()
    }

    /// Packet number of a data packet or acknowledge.
    pub fn packet_number(&self) -> u32 {
        self.word()
    }

    /// Error code of an error packet.
    pub fn error_code(&self) -> FoeErrorCode {
        FoeErrorCode::from(self.word())
    }

    /// BUSY progress: the "done" part.
    pub fn busy_done(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::BUSY_DONE)
    }

    /// BUSY progress: the "entire" part.
    pub fn busy_entire(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::BUSY_ENTIRE)
    }

    /// Everything after the header: file name, data or error text.
    pub fn tail(&self) -> &[u8] {
        super::tail(self.buffer.as_ref(), field::TAIL)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Foe<T> {
    /// Sets the operation code.
    pub fn set_opcode(&mut self, op: FoeOpcode) {
        super::set_u8(self.buffer.as_mut(), field::OPCODE, op.into());
    }

    /// Sets the reserved byte.
    pub fn set_reserved(&mut self, value: u8) {
        super::set_u8(self.buffer.as_mut(), field::RESERVED, value);
    }

    /// Sets bytes 2..6 (password, packet number or error code).
    pub fn set_word(&mut self, value: u32) {
        super::set_u32_le(self.buffer.as_mut(), field::WORD, value);
    }

    /// Sets the BUSY progress fields.
    pub fn set_busy(&mut self, done: u16, entire: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::BUSY_DONE, done);
        super::set_u16_le(self.buffer.as_mut(), field::BUSY_ENTIRE, entire);
    }

    /// Mutable tail (name, data or text); empty if the header is missing.
    pub fn tail_mut(&mut self) -> &mut [u8] {
        super::tail_mut(self.buffer.as_mut(), field::TAIL)
    }
}

/// High-level representation of an FoE packet (ETG.1000.6 §5.8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FoeRepr<'a> {
    /// Read request: upload the file `name`.
    ReadRequest {
        /// Password (0 if none).
        password: u32,
        /// File name, without terminator.
        name: &'a [u8],
    },
    /// Write request: download the file `name`.
    WriteRequest {
        /// Password (0 if none).
        password: u32,
        /// File name, without terminator.
        name: &'a [u8],
    },
    /// One packet of file data; numbering starts at 1.
    Data {
        /// Packet number.
        packet: u32,
        /// File data.
        data: &'a [u8],
    },
    /// Acknowledge of a write request (packet 0) or of a data packet.
    Ack {
        /// Packet number acknowledged.
        packet: u32,
    },
    /// Transfer aborted.
    Error {
        /// Error code.
        code: FoeErrorCode,
        /// Error text (may be empty), without terminator.
        text: &'a [u8],
    },
    /// The receiver is busy; the last packet is to be repeated.
    Busy {
        /// Progress: done part.
        done: u16,
        /// Progress: entire.
        entire: u16,
    },
    /// A packet with an opcode this stack does not know, kept as is.
    Unknown {
        /// The raw opcode (never 1..=6).
        opcode: u8,
        /// Bytes 2..6.
        word: u32,
        /// Bytes after the header.
        tail: &'a [u8],
    },
}

impl<'a> FoeRepr<'a> {
    /// Parses an FoE packet (the mailbox data). Only a buffer shorter than
    /// the header is rejected ([`WireError::Truncated`]); unknown opcodes
    /// become [`FoeRepr::Unknown`], unknown error codes
    /// [`FoeErrorCode::Unknown`].
    pub fn parse(bytes: &'a [u8]) -> Result<Self, WireError> {
        let foe = Foe::new_checked(bytes)?;
        let tail = super::tail(bytes, field::TAIL);
        Ok(match foe.opcode() {
            FoeOpcode::ReadRequest => Self::ReadRequest {
                password: foe.password(),
                name: tail,
            },
            FoeOpcode::WriteRequest => Self::WriteRequest {
                password: foe.password(),
                name: tail,
            },
            FoeOpcode::Data => Self::Data {
                packet: foe.packet_number(),
                data: tail,
            },
            FoeOpcode::Ack => Self::Ack {
                packet: foe.packet_number(),
            },
            FoeOpcode::Error => Self::Error {
                code: foe.error_code(),
                text: tail,
            },
            FoeOpcode::Busy => Self::Busy {
                done: foe.busy_done(),
                entire: foe.busy_entire(),
            },
            FoeOpcode::Unknown(opcode) => Self::Unknown {
                opcode,
                word: foe.word(),
                tail,
            },
        })
    }

    /// The operation code of this packet.
    pub const fn opcode(&self) -> FoeOpcode {
        match self {
            Self::ReadRequest { .. } => FoeOpcode::ReadRequest,
            Self::WriteRequest { .. } => FoeOpcode::WriteRequest,
            Self::Data { .. } => FoeOpcode::Data,
            Self::Ack { .. } => FoeOpcode::Ack,
            Self::Error { .. } => FoeOpcode::Error,
            Self::Busy { .. } => FoeOpcode::Busy,
            Self::Unknown { opcode, .. } => FoeOpcode::Unknown(*opcode),
        }
    }

    /// The tail bytes this packet carries (name, data, text; empty for
    /// ACK and BUSY).
    const fn tail(&self) -> &'a [u8] {
        match self {
            Self::ReadRequest { name, .. } | Self::WriteRequest { name, .. } => name,
            Self::Data { data, .. } => data,
            Self::Error { text, .. } => text,
            Self::Unknown { tail, .. } => tail,
            Self::Ack { .. } | Self::Busy { .. } => &[],
        }
    }

    /// Length of the packet: header plus tail.
    pub const fn buffer_len(&self) -> usize {
        HEADER_LEN + self.tail().len()
    }

    /// Writes the packet into the first [`FoeRepr::buffer_len`] bytes of
    /// `buf` (the mailbox data area; bytes beyond are untouched, the
    /// mailbox length field decides where the packet ends) and returns its
    /// length.
    ///
    /// Fails with [`WireError::BufferTooSmall`] if it does not fit and with
    /// [`WireError::Unrepresentable`] for an `Unknown` packet whose opcode
    /// is a known one; nothing is written then.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, WireError> {
        if matches!(self, Self::Unknown { opcode, .. }
            if !matches!(FoeOpcode::from(*opcode), FoeOpcode::Unknown(_)))
        {
            return Err(WireError::Unrepresentable);
        }
        let len = self.buffer_len();
        if buf.len() < len {
            return Err(WireError::BufferTooSmall);
        }
        let mut foe = Foe::new_unchecked(&mut *buf);
        foe.set_opcode(self.opcode());
        foe.set_reserved(0);
        match *self {
            Self::ReadRequest { password, .. } | Self::WriteRequest { password, .. } => {
                foe.set_word(password);
            }
            Self::Data { packet, .. } | Self::Ack { packet } => foe.set_word(packet),
            Self::Error { code, .. } => foe.set_word(code.into()),
            Self::Busy { done, entire } => foe.set_busy(done, entire),
            Self::Unknown { word, .. } => foe.set_word(word),
        }
        super::set_bytes(buf, HEADER_LEN, self.tail());
        Ok(len)
    }
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

    /// Write request, password 0, file "dev.efw".
    static WRQ_BYTES: [u8; 13] = [
        0x02, 0x00, // WRQ, reserved
        0x00, 0x00, 0x00, 0x00, // password 0
        b'd', b'e', b'v', b'.', b'e', b'f', b'w',
    ];

    /// Data packet 2 with 3 data bytes.
    static DATA_BYTES: [u8; 9] = [0x03, 0x00, 0x02, 0x00, 0x00, 0x00, 0xDE, 0xAD, 0x01];

    /// Error 0x8005 "packet number wrong" with text "bad".
    static ERR_BYTES: [u8; 9] = [0x05, 0x00, 0x05, 0x80, 0x00, 0x00, b'b', b'a', b'd'];

    /// Busy, done 3 of 10.
    static BUSY_BYTES: [u8; 6] = [0x06, 0x00, 0x03, 0x00, 0x0A, 0x00];

    #[test]
    fn deconstructs_write_request() {
        let foe = Foe::new_checked(&WRQ_BYTES[..]).unwrap();
        assert_eq!(foe.opcode(), FoeOpcode::WriteRequest);
        assert_eq!(foe.reserved(), 0);
        assert_eq!(foe.password(), 0);
        assert_eq!(foe.tail(), b"dev.efw");
    }

    #[test]
    fn parses_every_opcode() {
        assert_eq!(
            FoeRepr::parse(&WRQ_BYTES).unwrap(),
            FoeRepr::WriteRequest {
                password: 0,
                name: b"dev.efw"
            }
        );
        assert_eq!(
            FoeRepr::parse(&DATA_BYTES).unwrap(),
            FoeRepr::Data {
                packet: 2,
                data: &[0xDE, 0xAD, 0x01]
            }
        );
        assert_eq!(
            FoeRepr::parse(&ERR_BYTES).unwrap(),
            FoeRepr::Error {
                code: FoeErrorCode::PacketNumberWrong,
                text: b"bad"
            }
        );
        assert_eq!(
            FoeRepr::parse(&BUSY_BYTES).unwrap(),
            FoeRepr::Busy {
                done: 3,
                entire: 10
            }
        );
        let ack = [0x04, 0, 0x07, 0, 0, 0];
        assert_eq!(FoeRepr::parse(&ack).unwrap(), FoeRepr::Ack { packet: 7 });
        let rrq = [0x01, 0, 0x78, 0x56, 0x34, 0x12, b'a'];
        assert_eq!(
            FoeRepr::parse(&rrq).unwrap(),
            FoeRepr::ReadRequest {
                password: 0x1234_5678,
                name: b"a"
            }
        );
    }

    #[test]
    fn emits_byte_exact_packets() {
        for bytes in [&WRQ_BYTES[..], &DATA_BYTES, &ERR_BYTES, &BUSY_BYTES] {
            let repr = FoeRepr::parse(bytes).unwrap();
            assert_eq!(repr.buffer_len(), bytes.len());
            let mut out = [0xEEu8; 32];
            let n = repr.emit(&mut out).unwrap();
            assert_eq!(&out[..n], bytes);
            assert!(out[n..].iter().all(|&b| b == 0xEE));
        }
    }

    #[test]
    fn constructs_data_packet_with_setters() {
        let mut out = [0u8; 9];
        let mut foe = Foe::new_unchecked(&mut out[..]);
        foe.set_opcode(FoeOpcode::Data);
        foe.set_word(2);
        foe.tail_mut().copy_from_slice(&[0xDE, 0xAD, 0x01]);
        assert_eq!(out, DATA_BYTES);
    }

    #[test]
    fn truncated_header_is_rejected() {
        for len in 0..HEADER_LEN {
            assert_eq!(
                FoeRepr::parse(&DATA_BYTES[..len]),
                Err(WireError::Truncated)
            );
        }
        // a view over a short buffer reads zeroes and an empty tail
        let foe = Foe::new_unchecked(&DATA_BYTES[..3]);
        assert_eq!(foe.packet_number(), 0);
        assert!(foe.tail().is_empty());
    }

    #[test]
    fn header_only_packets_have_empty_tails() {
        let empty_data = [0x03, 0, 0x05, 0, 0, 0];
        assert_eq!(
            FoeRepr::parse(&empty_data).unwrap(),
            FoeRepr::Data {
                packet: 5,
                data: &[]
            }
        );
        let nameless = [0x02, 0, 0, 0, 0, 0];
        assert_eq!(
            FoeRepr::parse(&nameless).unwrap(),
            FoeRepr::WriteRequest {
                password: 0,
                name: &[]
            }
        );
    }

    #[test]
    fn unknown_opcode_is_kept_and_round_trips() {
        let bytes = [0x09, 0x00, 1, 2, 3, 4, 0xAA];
        let repr = FoeRepr::parse(&bytes).unwrap();
        assert_eq!(
            repr,
            FoeRepr::Unknown {
                opcode: 9,
                word: 0x0403_0201,
                tail: &[0xAA]
            }
        );
        assert_eq!(repr.opcode(), FoeOpcode::Unknown(9));
        let mut out = [0u8; 7];
        assert_eq!(repr.emit(&mut out), Ok(7));
        assert_eq!(out, bytes);
        let bad = FoeRepr::Unknown {
            opcode: 3,
            word: 0,
            tail: &[],
        };
        assert_eq!(bad.emit(&mut out), Err(WireError::Unrepresentable));
    }

    #[test]
    fn emit_into_short_buffer_fails_without_writing() {
        let repr = FoeRepr::parse(&ERR_BYTES).unwrap();
        let mut out = [0u8; 8];
        assert_eq!(repr.emit(&mut out), Err(WireError::BufferTooSmall));
        assert_eq!(out, [0; 8]);
        let ack = FoeRepr::Ack { packet: 1 };
        assert_eq!(ack.emit(&mut out[..5]), Err(WireError::BufferTooSmall));
    }

    #[test]
    fn reserved_byte_is_ignored_on_parse_and_cleared_on_emit() {
        let bytes = [0x04, 0xFF, 1, 0, 0, 0];
        let repr = FoeRepr::parse(&bytes).unwrap();
        let mut out = [0xFFu8; 6];
        repr.emit(&mut out).unwrap();
        assert_eq!(out, [0x04, 0x00, 1, 0, 0, 0]);
    }

    #[test]
    fn opcodes_and_error_codes_round_trip() {
        for raw in 0..=255u8 {
            assert_eq!(u8::from(FoeOpcode::from(raw)), raw);
        }
        for raw in 0x7FFF..=0x8012u32 {
            let code = FoeErrorCode::from(raw);
            assert_eq!(u32::from(code), raw);
            assert!(!code.text().is_empty());
        }
        assert_eq!(FoeErrorCode::from(0x800E), FoeErrorCode::Unknown(0x800E));
        assert_eq!(u32::from(FoeErrorCode::NoRights), 0x800A);
        assert_eq!(u32::from(FoeErrorCode::BootstrapOnly), 0x8008);
    }

    #[test]
    fn error_code_displays_hex_and_text() {
        use core::fmt::Write;
        let mut s: heapless::String<64> = heapless::String::new();
        write!(s, "{}", FoeErrorCode::DiskFull).unwrap();
        assert_eq!(s.as_str(), "0x8003: disk full");
    }
}
