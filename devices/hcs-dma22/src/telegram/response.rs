//! Responses, slave → master: CMD 3 (4.1.2), CMD 6 (4.3.2), CMD 15 (5.2)
//! and the error replies (4.1.3, 4.3.3, 5.3).
//!
//! ```text
//!  0      1      2     3       4       5       6       7       8
//! +------+------+-----+-------+-------+-------+- .. -+-------+
//! | TADR | SADR | 3   | CNT   | DAT1H | DAT1L |  ..  | DATnL |   CMD 3, 4 + CNT
//! +------+------+-----+-------+-------+-------+------+-------+
//! | TADR | SADR | 6   | IDH   | IDL   | DATH  | DATL |            CMD 6, 7
//! +------+------+-----+-------+-------+-------+------+-------+-------+
//! | TADR | SADR | 15  | DAT.1H| DAT.1L| DAT.2H|DAT.2L| DAT.3H| DAT.3L|  CMD 15, 9
//! +------+------+-----+-------+-------+-------+------+-------+-------+
//!                       status word     VALUE1         VALUE2
//! +------+------+-----+-------+
//! | TADR | SADR | ERR | EXCE  |                                  error, 4
//! +------+------+-----+-------+
//! ```
//!
//! TADR echoes the request's. For CMD 15, SADR names the module whose data
//! the response carries; the node answers with modules 1, 2, … SNUM, 1, …
//! in turn (5.2, see [`super::semantics::Multiplexer`]).

use super::exception::Exception;
use super::limits::{MAX_READ_CNT, MAX_READ_WORDS, MODULE_ADDRESSES};
use super::{
    Command, ERROR_FLAG, ERROR_LEN, HEADER_LEN, MULTI_WRITE_RESPONSE_LEN, SIMPLE_LEN,
    TelegramError, WriteParameter, check_exact, check_room, field, get_u8, get_u16_be, set_u8,
    set_u16_be,
};

/// Length of the CMD 3 response header (TADR, SADR, CMD, CNT).
const READ_HEADER_LEN: usize = field::READ_DATA;

/// Largest number of words in a CMD 3 response, as an array length.
const READ_WORDS_CAP: usize = MAX_READ_WORDS as usize;

/// A read/write view of a response (slave → master) in any buffer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Response<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Response<T> {
    /// Wraps a buffer without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`Response::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, TelegramError> {
        let response = Self::new_unchecked(buffer);
        response.check_len()?;
        Ok(response)
    }

    /// Checks that the buffer holds the whole telegram its header
    /// announces ([`Response::telegram_len`]); trailing bytes are allowed.
    pub fn check_len(&self) -> Result<(), TelegramError> {
        let needed = self.telegram_len()?;
        let got = self.buffer.as_ref().len();
        if got < needed {
            Err(TelegramError::Truncated { needed, got })
        } else {
            Ok(())
        }
    }

    /// Length of the telegram according to its header: 4 + CNT for CMD 3,
    /// 7 for CMD 6, 9 for CMD 15, 4 for an error reply.
    ///
    /// Fails with [`TelegramError::Truncated`] without the header (3 bytes,
    /// 4 for CMD 3), [`TelegramError::UnknownCommand`] for a CMD byte other
    /// than 3, 6, 15, 0x83, 0x86, 0x8F and [`TelegramError::CntOutOfRange`]
    /// for a CMD 3 whose CNT is not an even number in 2..=16.
    pub fn telegram_len(&self) -> Result<usize, TelegramError> {
        let got = self.buffer.as_ref().len();
        if got < HEADER_LEN {
            return Err(TelegramError::Truncated {
                needed: HEADER_LEN,
                got,
            });
        }
        let cmd = self.command_byte();
        if cmd & ERROR_FLAG != 0 {
            return match Command::from_error_code(cmd) {
                Some(_) => Ok(ERROR_LEN),
                None => Err(TelegramError::UnknownCommand(cmd)),
            };
        }
        match Command::from_code(cmd) {
            Some(Command::Read) => {
                if got < READ_HEADER_LEN {
                    return Err(TelegramError::Truncated {
                        needed: READ_HEADER_LEN,
                        got,
                    });
                }
                let cnt = self.cnt();
                if cnt == 0 || cnt > MAX_READ_CNT || !cnt.is_multiple_of(2) {
                    return Err(TelegramError::CntOutOfRange(cnt));
                }
                Ok(READ_HEADER_LEN + usize::from(cnt))
            }
            Some(Command::Write) => Ok(SIMPLE_LEN),
            Some(Command::MultiWrite) => Ok(MULTI_WRITE_RESPONSE_LEN),
            None => Err(TelegramError::UnknownCommand(cmd)),
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// TADR, echoed from the request.
    pub fn tadr(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::TADR)
    }

    /// SADR, the module that answers (0 = the node itself, exception 9 of
    /// 5.3).
    pub fn sadr(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::SADR)
    }

    /// The raw CMD (or ERR) byte.
    pub fn command_byte(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::CMD)
    }

    /// Whether bit 7 of the CMD byte is set (an error reply).
    pub fn is_error(&self) -> bool {
        self.command_byte() & ERROR_FLAG != 0
    }

    /// The command of a positive response (CMD byte 3, 6 or 15).
    pub fn command(&self) -> Option<Command> {
        Command::from_code(self.command_byte())
    }

    /// The failed command of an error reply (ERR byte 0x83, 0x86, 0x8F).
    pub fn error_command(&self) -> Option<Command> {
        Command::from_error_code(get_u8(self.buffer.as_ref(), field::ERR))
    }

    /// The raw EXCE byte of an error reply.
    pub fn exception_code(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::EXCE)
    }

    /// The exception of an error reply, decoded in its command's table.
    pub fn exception(&self) -> Option<Exception> {
        self.error_command()
            .map(|cmd| Exception::new(cmd, self.exception_code()))
    }

    /// CNT, the number of data bytes of a CMD 3 response.
    pub fn cnt(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::CNT)
    }

    /// The CNT data bytes of a CMD 3 response (clamped to the buffer).
    pub fn read_data(&self) -> &[u8] {
        let buf = self.buffer.as_ref();
        let end = READ_HEADER_LEN
            .saturating_add(usize::from(self.cnt()))
            .min(buf.len());
        buf.get(READ_HEADER_LEN..end).unwrap_or(&[])
    }

    /// Word `i` (0-based: DAT(i+1)H, DAT(i+1)L) of a CMD 3 response, or 0
    /// out of range.
    pub fn read_word(&self, i: usize) -> u16 {
        let at = i.saturating_mul(2);
        get_u16_be(self.read_data(), at..at.saturating_add(2))
    }

    /// IDH, IDL of a CMD 6 response.
    pub fn id(&self) -> u16 {
        get_u16_be(self.buffer.as_ref(), field::ID)
    }

    /// DATH, DATL of a CMD 6 response.
    pub fn value(&self) -> u16 {
        get_u16_be(self.buffer.as_ref(), field::DAT)
    }

    /// DAT.1H, DAT.1L, the status word of a CMD 15 response.
    pub fn status(&self) -> u16 {
        get_u16_be(self.buffer.as_ref(), field::STATUS)
    }

    /// DAT.2H, DAT.2L, VALUE1 of a CMD 15 response (signed).
    pub fn value1(&self) -> i16 {
        get_u16_be(self.buffer.as_ref(), field::VALUE1).cast_signed()
    }

    /// DAT.3H, DAT.3L, VALUE2 of a CMD 15 response (signed).
    pub fn value2(&self) -> i16 {
        get_u16_be(self.buffer.as_ref(), field::VALUE2).cast_signed()
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Response<T> {
    /// Sets TADR.
    pub fn set_tadr(&mut self, tadr: u8) {
        set_u8(self.buffer.as_mut(), field::TADR, tadr);
    }

    /// Sets SADR.
    pub fn set_sadr(&mut self, sadr: u8) {
        set_u8(self.buffer.as_mut(), field::SADR, sadr);
    }

    /// Sets the CMD byte of a positive response.
    pub fn set_command(&mut self, command: Command) {
        set_u8(self.buffer.as_mut(), field::CMD, command.code());
    }

    /// Makes the telegram an error reply: ERR and EXCE.
    pub fn set_exception(&mut self, exception: Exception) {
        let buf = self.buffer.as_mut();
        set_u8(buf, field::ERR, exception.error_code());
        set_u8(buf, field::EXCE, exception.code());
    }

    /// Sets CNT.
    pub fn set_cnt(&mut self, cnt: u8) {
        set_u8(self.buffer.as_mut(), field::CNT, cnt);
    }

    /// Sets word `i` (0-based) of a CMD 3 response; dropped if it is out
    /// of the buffer.
    pub fn set_read_word(&mut self, i: usize, word: u16) {
        let at = i.saturating_mul(2).saturating_add(READ_HEADER_LEN);
        set_u16_be(self.buffer.as_mut(), at..at.saturating_add(2), word);
    }

    /// Sets IDH, IDL (CMD 6).
    pub fn set_id(&mut self, id: u16) {
        set_u16_be(self.buffer.as_mut(), field::ID, id);
    }

    /// Sets DATH, DATL (CMD 6).
    pub fn set_value(&mut self, value: u16) {
        set_u16_be(self.buffer.as_mut(), field::DAT, value);
    }

    /// Sets the status word (CMD 15).
    pub fn set_status(&mut self, status: u16) {
        set_u16_be(self.buffer.as_mut(), field::STATUS, status);
    }

    /// Sets VALUE1 (CMD 15).
    pub fn set_value1(&mut self, value: i16) {
        set_u16_be(self.buffer.as_mut(), field::VALUE1, value.cast_unsigned());
    }

    /// Sets VALUE2 (CMD 15).
    pub fn set_value2(&mut self, value: i16) {
        set_u16_be(self.buffer.as_mut(), field::VALUE2, value.cast_unsigned());
    }
}

impl<T: AsRef<[u8]>> AsRef<[u8]> for Response<T> {
    fn as_ref(&self) -> &[u8] {
        self.buffer.as_ref()
    }
}

/// CMD 3 response (4.1.2): CNT = 2·N data bytes, the values of the N
/// parameters from the requested ID on.
///
/// Built with [`ReadResponse::new`]; holds 1..=8 words.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ReadResponse {
    /// Telegram address (echoed).
    pub tadr: u8,
    /// Module address.
    pub sadr: u8,
    len: u8,
    /// Words 0..len; the rest stays 0 so that the derived equality and
    /// hash only see the words in use.
    words: [u16; READ_WORDS_CAP],
}

impl ReadResponse {
    /// A response carrying `words` (1..=8 parameter values, raw words).
    /// Fails with [`TelegramError::WordCountOutOfRange`] otherwise.
    pub fn new(tadr: u8, sadr: u8, words: &[u16]) -> Result<Self, TelegramError> {
        let n = u16::try_from(words.len()).unwrap_or(u16::MAX);
        if n == 0 || n > MAX_READ_WORDS {
            return Err(TelegramError::WordCountOutOfRange { words: n });
        }
        let mut all = [0u16; READ_WORDS_CAP];
        for (slot, word) in all.iter_mut().zip(words) {
            *slot = *word;
        }
        Ok(Self {
            tadr,
            sadr,
            len: u8::try_from(n).unwrap_or(u8::MAX),
            words: all,
        })
    }

    /// The parameter values, DAT1 first.
    pub fn words(&self) -> &[u16] {
        self.words.get(..usize::from(self.len)).unwrap_or(&[])
    }

    /// CNT, the number of data bytes (2·N).
    pub const fn cnt(&self) -> u8 {
        self.len.saturating_mul(2)
    }

    /// Length of the telegram, 4 + CNT.
    pub const fn buffer_len(&self) -> usize {
        READ_HEADER_LEN + self.cnt() as usize
    }
}

/// CMD 15 response (5.2): the state of the module SADR.
///
/// What VALUE1 and VALUE2 are depends on the module's operation mode
/// (5.5.2 to 5.5.6; e.g. d1.11 actual value and d1.10 set value in mode 3,
/// d1.07 and d1.08 currents in modes 1 and 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MultiWriteResponse {
    /// Telegram address (echoed).
    pub tadr: u8,
    /// The module that answers, 1..=5 (checked by `parse` and `emit`).
    pub sadr: u8,
    /// DAT.1H, DAT.1L, the status word (see
    /// [`super::semantics::status`]).
    pub status: u16,
    /// DAT.2H, DAT.2L, VALUE1 (signed).
    pub value1: i16,
    /// DAT.3H, DAT.3L, VALUE2 (signed).
    pub value2: i16,
}

impl MultiWriteResponse {
    /// Checks SADR (1..=5).
    pub fn check(&self) -> Result<(), TelegramError> {
        if MODULE_ADDRESSES.contains(&self.sadr) {
            Ok(())
        } else {
            Err(TelegramError::SadrOutOfRange(self.sadr))
        }
    }
}

/// An error reply (4.1.3, 4.3.3, 5.3): ERR = CMD | 0x80 and the exception.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ErrorReply {
    /// Telegram address (echoed).
    pub tadr: u8,
    /// The module that failed (0 = the node itself, 5.3 exception 9).
    pub sadr: u8,
    /// The failed command and why.
    pub exception: Exception,
}

/// A response, slave → master.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ResponseRepr {
    /// CMD 3.
    Read(ReadResponse),
    /// CMD 6 (echo of the request).
    Write(WriteParameter),
    /// CMD 15.
    MultiWrite(MultiWriteResponse),
    /// ERR 0x83, 0x86 or 0x8F.
    Error(ErrorReply),
}

impl ResponseRepr {
    /// Parses a response that fills `bytes` exactly.
    ///
    /// Besides the errors of [`ResponseRepr::parse_padded`], fails with
    /// [`TelegramError::BadLength`] if bytes follow the telegram.
    pub fn parse(bytes: &[u8]) -> Result<Self, TelegramError> {
        let repr = Self::parse_padded(bytes)?;
        check_exact(bytes, repr.buffer_len())?;
        Ok(repr)
    }

    /// Parses the response at the start of `bytes`, ignoring the bytes
    /// after it (the filler of a fixed-size process-data buffer, 6.3).
    ///
    /// Fails with [`TelegramError::Truncated`],
    /// [`TelegramError::UnknownCommand`] or
    /// [`TelegramError::CntOutOfRange`] (see [`Response::telegram_len`]),
    /// and with [`TelegramError::SadrOutOfRange`] for a CMD 15 response
    /// whose SADR is not 1..=5.
    pub fn parse_padded(bytes: &[u8]) -> Result<Self, TelegramError> {
        let response = Response::new_checked(bytes)?;
        let tadr = response.tadr();
        let sadr = response.sadr();
        if let Some(exception) = response.exception() {
            return Ok(Self::Error(ErrorReply {
                tadr,
                sadr,
                exception,
            }));
        }
        match response.command() {
            Some(Command::Read) => {
                let mut words = [0u16; READ_WORDS_CAP];
                for (i, word) in words.iter_mut().enumerate() {
                    *word = response.read_word(i);
                }
                let n = usize::from(response.cnt() / 2);
                Ok(Self::Read(ReadResponse::new(
                    tadr,
                    sadr,
                    words.get(..n).unwrap_or(&[]),
                )?))
            }
            Some(Command::Write) => Ok(Self::Write(WriteParameter {
                tadr,
                sadr,
                id: response.id(),
                value: response.value(),
            })),
            Some(Command::MultiWrite) => {
                let multi = MultiWriteResponse {
                    tadr,
                    sadr,
                    status: response.status(),
                    value1: response.value1(),
                    value2: response.value2(),
                };
                multi.check()?;
                Ok(Self::MultiWrite(multi))
            }
            None => Err(TelegramError::UnknownCommand(response.command_byte())),
        }
    }

    /// The command answered (for an error reply: the one that failed).
    pub const fn command(&self) -> Command {
        match self {
            Self::Read(_) => Command::Read,
            Self::Write(_) => Command::Write,
            Self::MultiWrite(_) => Command::MultiWrite,
            Self::Error(e) => e.exception.command(),
        }
    }

    /// Telegram address.
    pub const fn tadr(&self) -> u8 {
        match self {
            Self::Read(r) => r.tadr,
            Self::Write(w) => w.tadr,
            Self::MultiWrite(m) => m.tadr,
            Self::Error(e) => e.tadr,
        }
    }

    /// Module address.
    pub const fn sadr(&self) -> u8 {
        match self {
            Self::Read(r) => r.sadr,
            Self::Write(w) => w.sadr,
            Self::MultiWrite(m) => m.sadr,
            Self::Error(e) => e.sadr,
        }
    }

    /// Length of the telegram: 4 + CNT, 7, 9 or 4.
    pub const fn buffer_len(&self) -> usize {
        match self {
            Self::Read(r) => r.buffer_len(),
            Self::Write(_) => SIMPLE_LEN,
            Self::MultiWrite(_) => MULTI_WRITE_RESPONSE_LEN,
            Self::Error(_) => ERROR_LEN,
        }
    }

    /// Writes the telegram at the start of `buf` and returns its length,
    /// [`ResponseRepr::buffer_len`]; bytes after it are left alone.
    ///
    /// Fails with [`TelegramError::SadrOutOfRange`] for a CMD 15 response
    /// whose SADR is not 1..=5 and with [`TelegramError::BufferTooSmall`];
    /// `buf` is untouched on failure.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, TelegramError> {
        if let Self::MultiWrite(multi) = self {
            multi.check()?;
        }
        let len = self.buffer_len();
        check_room(buf, len)?;
        let mut response = Response::new_unchecked(buf);
        response.set_tadr(self.tadr());
        response.set_sadr(self.sadr());
        match self {
            Self::Read(read) => {
                response.set_command(Command::Read);
                response.set_cnt(read.cnt());
                for (i, word) in read.words().iter().enumerate() {
                    response.set_read_word(i, *word);
                }
            }
            Self::Write(write) => {
                response.set_command(Command::Write);
                response.set_id(write.id);
                response.set_value(write.value);
            }
            Self::MultiWrite(multi) => {
                response.set_command(Command::MultiWrite);
                response.set_status(multi.status);
                response.set_value1(multi.value1);
                response.set_value2(multi.value2);
            }
            Self::Error(error) => response.set_exception(error.exception),
        }
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
    use crate::telegram::{MultiWriteException, ReadException};

    #[test]
    fn read_response_view_and_repr() {
        let bytes = [0x24, 0x01, 0x03, 0x04, 0x01, 0x33, 0xFF, 0xFE];
        let response = Response::new_checked(&bytes[..]).unwrap();
        assert_eq!(response.telegram_len(), Ok(8));
        assert_eq!(response.cnt(), 4);
        assert_eq!(response.read_data(), &bytes[4..]);
        assert_eq!(response.read_word(1), 0xFFFE);
        assert_eq!(response.read_word(2), 0);
        assert_eq!(response.read_word(usize::MAX), 0);
        assert!(!response.is_error());
        assert_eq!(response.exception(), None);
        let ResponseRepr::Read(read) = ResponseRepr::parse(&bytes).unwrap() else {
            panic!("not a read")
        };
        assert_eq!(read.words(), &[0x0133, 0xFFFE]);
        assert_eq!(read.cnt(), 4);
        assert_eq!(read.buffer_len(), 8);
    }

    #[test]
    fn cnt_must_be_even_and_two_to_sixteen() {
        for cnt in [0u8, 1, 3, 15, 17, 18, 0xFF] {
            let mut bytes = [0u8; 40];
            bytes[..4].copy_from_slice(&[0x24, 0x01, 0x03, cnt]);
            assert_eq!(
                ResponseRepr::parse_padded(&bytes),
                Err(TelegramError::CntOutOfRange(cnt)),
                "CNT {cnt}"
            );
        }
        let mut sixteen = [0u8; 20];
        sixteen[..4].copy_from_slice(&[0x24, 0x01, 0x03, 16]);
        let ResponseRepr::Read(read) = ResponseRepr::parse(&sixteen).unwrap() else {
            panic!("not a read")
        };
        assert_eq!(read.words().len(), 8);
        assert_eq!(
            ResponseRepr::parse(&sixteen[..19]),
            Err(TelegramError::Truncated {
                needed: 20,
                got: 19
            })
        );
        assert_eq!(
            ResponseRepr::parse(&sixteen[..3]),
            Err(TelegramError::Truncated { needed: 4, got: 3 })
        );
    }

    #[test]
    fn read_response_holds_one_to_eight_words() {
        assert_eq!(
            ReadResponse::new(0, 1, &[]),
            Err(TelegramError::WordCountOutOfRange { words: 0 })
        );
        assert_eq!(
            ReadResponse::new(0, 1, &[0; 9]),
            Err(TelegramError::WordCountOutOfRange { words: 9 })
        );
        assert_eq!(ReadResponse::new(0, 1, &[7; 8]).unwrap().cnt(), 16);
    }

    #[test]
    fn multi_write_response_sadr_is_one_to_five() {
        for sadr in [0u8, 6, 32] {
            let bytes = [0x23, sadr, 0x0F, 0x40, 0x00, 0x00, 0x00, 0x03, 0xE8];
            assert_eq!(
                ResponseRepr::parse(&bytes),
                Err(TelegramError::SadrOutOfRange(sadr))
            );
            let repr = ResponseRepr::MultiWrite(MultiWriteResponse {
                tadr: 0x23,
                sadr,
                status: 0,
                value1: 0,
                value2: 0,
            });
            let mut out = [0u8; 9];
            assert_eq!(
                repr.emit(&mut out),
                Err(TelegramError::SadrOutOfRange(sadr))
            );
            assert_eq!(out, [0; 9]);
        }
    }

    #[test]
    fn error_replies_decode_in_their_commands_table() {
        let read = ResponseRepr::parse(&[0x23, 0x03, 0x83, 0x03]).unwrap();
        assert_eq!(
            read,
            ResponseRepr::Error(ErrorReply {
                tadr: 0x23,
                sadr: 3,
                exception: Exception::Read(ReadException::CntOutOfRange),
            })
        );
        assert_eq!(read.command(), Command::Read);
        let node = ResponseRepr::parse(&[0x01, 0x00, 0x8F, 0x09]).unwrap();
        assert_eq!(
            node,
            ResponseRepr::Error(ErrorReply {
                tadr: 1,
                sadr: 0,
                exception: Exception::MultiWrite(MultiWriteException::DataLengthTooSmall),
            })
        );
        let unknown = ResponseRepr::parse(&[0x01, 0x01, 0x86, 0x42]).unwrap();
        let mut out = [0u8; 4];
        assert_eq!(unknown.emit(&mut out), Ok(4));
        assert_eq!(out, [0x01, 0x01, 0x86, 0x42]);
    }

    #[test]
    fn unknown_response_commands_are_rejected() {
        for cmd in [0x00u8, 0x04, 0x10, 0x80, 0x85, 0x90, 0xFF] {
            assert_eq!(
                ResponseRepr::parse(&[0x01, 0x01, cmd, 0x00]),
                Err(TelegramError::UnknownCommand(cmd))
            );
        }
        assert_eq!(
            ResponseRepr::parse(&[0x01, 0x01]),
            Err(TelegramError::Truncated { needed: 3, got: 2 })
        );
    }

    #[test]
    fn response_trailing_bytes_are_bad_length_unless_padded() {
        let padded = [0x23, 0x03, 0x8F, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00];
        assert_eq!(
            ResponseRepr::parse(&padded),
            Err(TelegramError::BadLength {
                expected: 4,
                got: 9
            })
        );
        assert_eq!(
            ResponseRepr::parse_padded(&padded),
            ResponseRepr::parse(&padded[..4])
        );
    }

    #[test]
    fn view_setters_write_every_field() {
        let mut buf = [0u8; 9];
        let mut response = Response::new_unchecked(&mut buf[..]);
        response.set_tadr(0x25);
        response.set_sadr(3);
        response.set_command(Command::MultiWrite);
        response.set_status(0x0400);
        response.set_value1(810);
        response.set_value2(-3000);
        assert_eq!(response.value2(), -3000);
        assert_eq!(buf, [0x25, 0x03, 0x0F, 0x04, 0x00, 0x03, 0x2A, 0xF4, 0x48]);
        let mut small = [0u8; 5];
        let mut response = Response::new_unchecked(&mut small[..]);
        response.set_read_word(0, 0x0775);
        response.set_read_word(1, 0xFFFF); // out of the buffer
        response.set_id(1);
        response.set_value(2);
        assert_eq!(small, [0, 0, 0, 0x00, 0x01]);
        assert_eq!(Response::new_unchecked(&small[..]).into_inner(), &small);
    }
}
