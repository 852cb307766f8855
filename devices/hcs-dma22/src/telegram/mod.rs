//! The HCS telegram: CMD 3, CMD 6, CMD 15 and their error replies
//! (DMA-22(A) EtherNet/IP manual chapters 3.4, 4 and 5; the same telegram
//! over Profibus-DP in the DMA Profibus manual chapters 3 and 4, and over
//! Profinet in the DAC-42(A) manual chapter 9).
//!
//! Every telegram starts with the same three bytes; all 16-bit fields are
//! big-endian ("H" byte first, "write first" = byte 0). There is no
//! checksum.
//!
//! ```text
//! master → slave (requests)                         bytes
//!  CMD 3   TADR SADR 0x03 IDH IDL N-high N-low          7
//!  CMD 6   TADR SADR 0x06 IDH IDL DATH DATL             7
//!  CMD 15  TADR SNUM 0x0F { DATx.1 DATx.2H DATx.2L DATx.3H DATx.3L } × SNUM
//!                                                   3 + 5·SNUM (8..=28)
//!
//! slave → master (responses)
//!  CMD 3   TADR SADR 0x03 CNT DAT1H DAT1L .. DATnH DATnL   4 + CNT
//!  CMD 6   TADR SADR 0x06 IDH IDL DATH DATL                7
//!  CMD 15  TADR SADR 0x0F DAT.1H DAT.1L DAT.2H DAT.2L DAT.3H DAT.3L  9
//!  error   TADR SADR ERR EXCE                              4
//!          ERR = 0x80 | CMD: 0x83 read failed, 0x86 / 0x8F write failed
//! ```
//!
//! The same CMD has a different layout in each direction, so requests
//! ([`request`]: [`Request`] view, [`RequestRepr`]) and responses
//! ([`response`]: [`Response`] view, [`ResponseRepr`]) are parsed
//! separately. Exception codes are in [`exception`]; the rules the manual
//! states about the telegrams (word limits, ID range, SNUM, the TADR rule
//! and the CMD 15 answer multiplexing) are in [`semantics`].
//!
//! # Fixed-size buffers
//!
//! Fieldbus process data has a fixed size (EtherNet/IP assembly sizes E29
//! / E30, Profibus GSD modules such as "CMD15 5fold 9B-I 28B-O"), so a
//! telegram usually sits at the start of a longer buffer whose tail is
//! filler ("Dummy only for filling up the buffer", manual 6.3). The
//! `parse` functions want the telegram exactly; the `parse_padded`
//! functions accept and ignore trailing bytes. `emit` writes
//! `buffer_len()` bytes at the start of the buffer and leaves the rest
//! untouched.
//!
//! # Panics
//!
//! Nothing here panics. Views read out-of-range fields as zero and drop
//! out-of-range writes, so even a view made with `new_unchecked` over a
//! short buffer is safe; once `check_len` has succeeded every field is in
//! range.
//!
//! Layers: `semantics` → `request`, `response` → `exception`, `limits`

use core::ops::Range;

pub mod exception;
pub mod limits;
pub mod request;
pub mod response;
pub mod semantics;

#[cfg(test)]
mod props;
#[cfg(test)]
mod seed_vectors;

pub use exception::{Exception, MultiWriteException, ReadException, WriteException};
pub use request::{
    ModuleOutput, MultiWriteRequest, ReadRequest, Request, RequestRepr, WriteParameter,
};
pub use response::{ErrorReply, MultiWriteResponse, ReadResponse, Response, ResponseRepr};

/// Length of the header every telegram starts with: TADR, SADR (or SNUM)
/// and CMD (or ERR).
pub const HEADER_LEN: usize = 3;

/// Length of a CMD 3 request and of a CMD 6 request or response (4.1.1,
/// 4.3.1, 4.3.2: "7 bytes").
pub const SIMPLE_LEN: usize = 7;

/// Length of an error reply (4.1.3, 4.3.3, 5.3: "4 bytes").
pub const ERROR_LEN: usize = 4;

/// Length of a CMD 15 response (5.2: "9 bytes").
pub const MULTI_WRITE_RESPONSE_LEN: usize = 9;

/// Length of one module's block in a CMD 15 request (5.1: control byte and
/// two process values).
pub const MODULE_BLOCK_LEN: usize = 5;

/// Largest number of modules a CMD 15 request carries (5.1: "SNUM Number of
/// connected slaves (Maximum 5)").
pub const MAX_MODULES: usize = 5;

/// Longest telegram: a CMD 15 request for five modules, 3 + 5·5 = 28 bytes
/// (5.1, "Overall telegram length in bytes" 8 13 18 23 28).
pub const MAX_TELEGRAM_LEN: usize = HEADER_LEN + MODULE_BLOCK_LEN * MAX_MODULES;

/// Bit 7 of the CMD byte marks an error reply (5.3: "Error, Bit „7“ with
/// command 0x0F in decimal 15 is set").
pub const ERROR_FLAG: u8 = 0x80;

/// Byte offsets of the fields (manual tables "Write first … Write last").
mod field {
    use super::Field;

    /// Telegram address, chosen by the master and echoed by the slave.
    pub const TADR: usize = 0;
    /// Slave (module) address: request and response of CMD 3 / 6, response
    /// of CMD 15, error reply.
    pub const SADR: usize = 1;
    /// Number of modules, CMD 15 request only (same byte as SADR).
    pub const SNUM: usize = 1;
    /// Command (3, 6, 15).
    pub const CMD: usize = 2;
    /// Error code of an error reply (same byte as CMD).
    pub const ERR: usize = 2;
    /// Exception code of an error reply.
    pub const EXCE: usize = 3;
    /// Parameter ID (IDH, IDL), CMD 3 request and CMD 6.
    pub const ID: Field = 3..5;
    /// Number of parameter words (N-high, N-low), CMD 3 request.
    pub const N: Field = 5..7;
    /// Parameter value (DATH, DATL), CMD 6.
    pub const DAT: Field = 5..7;
    /// Number of data bytes, CMD 3 response.
    pub const CNT: usize = 3;
    /// First data byte, CMD 3 response.
    pub const READ_DATA: usize = 4;
    /// First module block, CMD 15 request.
    pub const MODULES: usize = 3;
    /// Control byte (DATx.1), offset inside a module block.
    pub const BLOCK_CONTROL: usize = 0;
    /// Process value 1 (DATx.2H, DATx.2L), offset inside a module block.
    pub const BLOCK_VALUE1: Field = 1..3;
    /// Process value 2 (DATx.3H, DATx.3L), offset inside a module block.
    pub const BLOCK_VALUE2: Field = 3..5;
    /// Status word (DAT.1H, DAT.1L), CMD 15 response.
    pub const STATUS: Field = 3..5;
    /// VALUE1 (DAT.2H, DAT.2L), CMD 15 response.
    pub const VALUE1: Field = 5..7;
    /// VALUE2 (DAT.3H, DAT.3L), CMD 15 response.
    pub const VALUE2: Field = 7..9;
}

/// Byte range of a fixed-size field.
type Field = Range<usize>;

/// The three commands of the HCS telegram (3.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Command {
    /// CMD 3: read one or more parameters, IDs in rising order (4.1).
    Read,
    /// CMD 6: write a single parameter (4.3).
    Write,
    /// CMD 15: write the process data of all modules (1..=5) of a node and
    /// get the process data of one of them back (5).
    MultiWrite,
}

impl Command {
    /// The CMD byte: 3, 6 or 15.
    pub const fn code(self) -> u8 {
        match self {
            Self::Read => 3,
            Self::Write => 6,
            Self::MultiWrite => 15,
        }
    }

    /// The command for a CMD byte, if it is one of 3, 6, 15.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            3 => Some(Self::Read),
            6 => Some(Self::Write),
            15 => Some(Self::MultiWrite),
            _ => None,
        }
    }

    /// The ERR byte of this command's error reply: CMD with bit 7 set,
    /// 0x83, 0x86 or 0x8F (4.1.3, 4.3.3, 5.3).
    pub const fn error_code(self) -> u8 {
        self.code() | ERROR_FLAG
    }

    /// The command whose error reply carries this ERR byte.
    pub const fn from_error_code(err: u8) -> Option<Self> {
        if err & ERROR_FLAG == 0 {
            None
        } else {
            Self::from_code(err & !ERROR_FLAG)
        }
    }
}

/// Why a byte string is not a telegram, or why a `Repr` cannot be encoded.
///
/// Field-level rules that the slave answers with an exception instead
/// (e.g. an unknown parameter ID, "2 = Wrong ID") are not errors here; see
/// [`semantics`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum TelegramError {
    /// Fewer bytes than the header, or than the length the header
    /// announces.
    #[error("telegram truncated: {needed} bytes needed, {got} present")]
    Truncated {
        /// Bytes needed to go on.
        needed: usize,
        /// Bytes present.
        got: usize,
    },
    /// More bytes than the telegram announced by its header (only from the
    /// exact `parse`; `parse_padded` ignores trailing bytes).
    #[error("telegram of {expected} bytes given in a buffer of {got} bytes")]
    BadLength {
        /// Length announced by the header.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// The CMD byte is not a command of this direction: requests carry 3, 6
    /// or 15; responses 3, 6, 15, 0x83, 0x86 or 0x8F.
    #[error("unknown command byte {0:#04x}")]
    UnknownCommand(u8),
    /// CMD 3 reads 1..=8 parameter words (Profibus manual 3.1: "N-low …
    /// 1 to 8 (0x08) (maximal 8 parameters readable at once)").
    #[error("{words} parameter words: CMD 3 reads 1 to 8")]
    WordCountOutOfRange {
        /// The word count N (or CNT / 2).
        words: u16,
    },
    /// CNT of a CMD 3 response is not an even number of bytes in 2..=16
    /// (4.1.2: CNT = N·2; 4.1.3 exception 3: "CNT == 0 or CNT > 16").
    #[error("CNT = {0}: a CMD 3 response carries 2 to 16 data bytes, an even number")]
    CntOutOfRange(u8),
    /// SNUM of a CMD 15 request is not 1..=5 (5.1).
    #[error("SNUM = {0}: CMD 15 addresses 1 to 5 modules")]
    SnumOutOfRange(u8),
    /// SADR of a CMD 15 response is not 1..=5 (5.2: "1 to max 5 depending
    /// on number of slaves").
    #[error("SADR = {0}: a CMD 15 response comes from module 1 to 5")]
    SadrOutOfRange(u8),
    /// The buffer given to `emit` is shorter than `buffer_len()`.
    #[error("output buffer of {got} bytes, the telegram needs {needed}")]
    BufferTooSmall {
        /// Bytes the telegram needs.
        needed: usize,
        /// Bytes in the buffer.
        got: usize,
    },
}

impl TelegramError {
    /// The exception a slave answers a request with that failed to parse
    /// this way, where the manual names one: a word count outside 1..=8 is
    /// read exception 3 ("CNT == 0 or CNT > 16", 4.1.3); an SNUM outside
    /// 1..=5 is CMD 15 exception 7 ("Invalid number of connected slaves",
    /// 5.3). `None` for the other errors.
    pub const fn exception(&self) -> Option<Exception> {
        match self {
            Self::WordCountOutOfRange { .. } => Some(Exception::Read(ReadException::CntOutOfRange)),
            Self::SnumOutOfRange(_) => Some(Exception::MultiWrite(
                MultiWriteException::InvalidSlaveCount,
            )),
            _ => None,
        }
    }
}

/// Reads one byte, or 0 if `at` is out of range.
fn get_u8(buf: &[u8], at: usize) -> u8 {
    buf.get(at).copied().unwrap_or(0)
}

/// Writes one byte; out-of-range writes are dropped.
fn set_u8(buf: &mut [u8], at: usize, value: u8) {
    if let Some(b) = buf.get_mut(at) {
        *b = value;
    }
}

/// Reads a big-endian `u16`, or 0 if `field` is out of range.
fn get_u16_be(buf: &[u8], field: Field) -> u16 {
    buf.get(field)
        .and_then(|b| <[u8; 2]>::try_from(b).ok())
        .map_or(0, u16::from_be_bytes)
}

/// Writes a big-endian `u16`; out-of-range writes are dropped.
fn set_u16_be(buf: &mut [u8], field: Field, value: u16) {
    if let Some(b) = buf.get_mut(field).filter(|b| b.len() == 2) {
        b.copy_from_slice(&value.to_be_bytes());
    }
}

/// `field` moved by `offset` bytes (saturating, so never panics).
const fn shifted(field: Field, offset: usize) -> Field {
    field.start.saturating_add(offset)..field.end.saturating_add(offset)
}

/// Checks that `buf` can take `needed` bytes for an `emit`.
const fn check_room(buf: &[u8], needed: usize) -> Result<(), TelegramError> {
    if buf.len() < needed {
        Err(TelegramError::BufferTooSmall {
            needed,
            got: buf.len(),
        })
    } else {
        Ok(())
    }
}

/// Checks that `bytes` is exactly a telegram of `len` bytes.
const fn check_exact(bytes: &[u8], len: usize) -> Result<(), TelegramError> {
    if bytes.len() == len {
        Ok(())
    } else if bytes.len() < len {
        Err(TelegramError::Truncated {
            needed: len,
            got: bytes.len(),
        })
    } else {
        Err(TelegramError::BadLength {
            expected: len,
            got: bytes.len(),
        })
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

    #[test]
    fn out_of_range_reads_are_zero_and_writes_are_dropped() {
        let mut buf = [0xAAu8; 3];
        assert_eq!(get_u16_be(&buf, 2..4), 0);
        assert_eq!(get_u8(&buf, 3), 0);
        set_u16_be(&mut buf, 2..4, 0x1234);
        set_u8(&mut buf, 9, 1);
        assert_eq!(buf, [0xAA; 3]);
        assert_eq!(
            shifted(usize::MAX - 1..usize::MAX, 5),
            usize::MAX..usize::MAX
        );
    }

    #[test]
    fn words_are_big_endian() {
        let mut buf = [0u8; 2];
        set_u16_be(&mut buf, 0..2, 0x03E8);
        assert_eq!(buf, [0x03, 0xE8]);
        assert_eq!(get_u16_be(&buf, 0..2), 1000);
    }

    #[test]
    fn command_codes_and_error_codes() {
        for (cmd, code, err) in [
            (Command::Read, 3, 0x83),
            (Command::Write, 6, 0x86),
            (Command::MultiWrite, 15, 0x8F),
        ] {
            assert_eq!(cmd.code(), code);
            assert_eq!(cmd.error_code(), err);
            assert_eq!(Command::from_code(code), Some(cmd));
            assert_eq!(Command::from_error_code(err), Some(cmd));
            assert_eq!(Command::from_error_code(code), None);
        }
        for raw in 0..=u8::MAX {
            if ![3, 6, 15].contains(&raw) {
                assert_eq!(Command::from_code(raw), None);
            }
        }
        assert_eq!(Command::from_error_code(0x85), None);
        assert_eq!(MAX_TELEGRAM_LEN, 28);
    }

    #[test]
    fn errors_have_messages_with_their_numbers() {
        assert_eq!(
            TelegramError::WordCountOutOfRange { words: 9 }.to_string(),
            "9 parameter words: CMD 3 reads 1 to 8"
        );
        assert_eq!(
            TelegramError::UnknownCommand(0x85).to_string(),
            "unknown command byte 0x85"
        );
        assert_eq!(
            TelegramError::Truncated { needed: 7, got: 6 }.to_string(),
            "telegram truncated: 7 bytes needed, 6 present"
        );
        assert_eq!(
            TelegramError::SnumOutOfRange(6).to_string(),
            "SNUM = 6: CMD 15 addresses 1 to 5 modules"
        );
    }

    #[test]
    fn parse_errors_map_to_the_manual_exceptions() {
        assert_eq!(
            TelegramError::WordCountOutOfRange { words: 0 }.exception(),
            Some(Exception::Read(ReadException::CntOutOfRange))
        );
        assert_eq!(
            TelegramError::SnumOutOfRange(6).exception(),
            Some(Exception::MultiWrite(
                MultiWriteException::InvalidSlaveCount
            ))
        );
        assert_eq!(TelegramError::UnknownCommand(1).exception(), None);
    }
}
