//! Requests, master → slave: CMD 3 (4.1.1), CMD 6 (4.3.1) and CMD 15
//! (5.1).
//!
//! ```text
//!  0      1          2     3     4     5        6
//! +------+----------+-----+-----+-----+--------+--------+
//! | TADR | SADR     | 3   | IDH | IDL | N-high | N-low  |  CMD 3, 7 bytes
//! +------+----------+-----+-----+-----+--------+--------+
//! | TADR | SADR     | 6   | IDH | IDL | DATH   | DATL   |  CMD 6, 7 bytes
//! +------+----------+-----+-----+-----+--------+--------+
//!
//!  0      1      2    3 + 5·(x-1)                                 3 + 5·SNUM
//! +------+------+----+--------+---------+---------+---------+---------+ ...
//! | TADR | SNUM | 15 | DATx.1 | DATx.2H | DATx.2L | DATx.3H | DATx.3L | ...
//! +------+------+----+--------+---------+---------+---------+---------+ ...
//!                     control   process value 1     process value 2
//!                     one block per module x = 1..=SNUM (E22 order)
//! ```

use super::limits::{MAX_READ_WORDS, MODULE_ADDRESSES};
use super::{
    Command, HEADER_LEN, MAX_MODULES, MODULE_BLOCK_LEN, SIMPLE_LEN, TelegramError, check_exact,
    check_room, field, get_u8, get_u16_be, set_u8, set_u16_be, shifted,
};

/// A read/write view of a request (master → slave) in any buffer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Request<T> {
    /// Wraps a buffer without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`Request::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, TelegramError> {
        let request = Self::new_unchecked(buffer);
        request.check_len()?;
        Ok(request)
    }

    /// Checks that the buffer holds the whole telegram its header
    /// announces ([`Request::telegram_len`]); trailing bytes are allowed.
    pub fn check_len(&self) -> Result<(), TelegramError> {
        let needed = self.telegram_len()?;
        let got = self.buffer.as_ref().len();
        if got < needed {
            Err(TelegramError::Truncated { needed, got })
        } else {
            Ok(())
        }
    }

    /// Length of the telegram according to its header: 7 for CMD 3 and
    /// CMD 6, 3 + 5·SNUM for CMD 15.
    ///
    /// Fails with [`TelegramError::Truncated`] without the 3 header bytes,
    /// [`TelegramError::UnknownCommand`] for a CMD other than 3, 6, 15 and
    /// [`TelegramError::SnumOutOfRange`] for a CMD 15 with SNUM outside
    /// 1..=5.
    pub fn telegram_len(&self) -> Result<usize, TelegramError> {
        let got = self.buffer.as_ref().len();
        if got < HEADER_LEN {
            return Err(TelegramError::Truncated {
                needed: HEADER_LEN,
                got,
            });
        }
        match self.command() {
            Some(Command::Read | Command::Write) => Ok(SIMPLE_LEN),
            Some(Command::MultiWrite) => {
                let snum = self.snum();
                if MODULE_ADDRESSES.contains(&snum) {
                    Ok(multi_write_len(snum))
                } else {
                    Err(TelegramError::SnumOutOfRange(snum))
                }
            }
            None => Err(TelegramError::UnknownCommand(self.command_byte())),
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// TADR, the telegram address chosen by the master (3.3).
    pub fn tadr(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::TADR)
    }

    /// SADR, the addressed module (its E22), CMD 3 and CMD 6.
    pub fn sadr(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::SADR)
    }

    /// SNUM, the number of modules, CMD 15 (same byte as SADR).
    pub fn snum(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::SNUM)
    }

    /// The raw CMD byte.
    pub fn command_byte(&self) -> u8 {
        get_u8(self.buffer.as_ref(), field::CMD)
    }

    /// The command, if the CMD byte is 3, 6 or 15.
    pub fn command(&self) -> Option<Command> {
        Command::from_code(self.command_byte())
    }

    /// IDH, IDL: the (first) parameter ID, CMD 3 and CMD 6.
    pub fn id(&self) -> u16 {
        get_u16_be(self.buffer.as_ref(), field::ID)
    }

    /// N-high, N-low: the number of parameter words to read, CMD 3.
    pub fn word_count(&self) -> u16 {
        get_u16_be(self.buffer.as_ref(), field::N)
    }

    /// DATH, DATL: the value to write, CMD 6.
    pub fn value(&self) -> u16 {
        get_u16_be(self.buffer.as_ref(), field::DAT)
    }

    /// The block of module `x` (its E22, 1..=5) of a CMD 15: DATx.1,
    /// DATx.2, DATx.3. All zero if `x` is 0 or the block is out of the
    /// buffer.
    pub fn module(&self, x: u8) -> ModuleOutput {
        let buf = self.buffer.as_ref();
        let Some(at) = block_offset(x) else {
            return ModuleOutput::default();
        };
        ModuleOutput {
            control: get_u8(buf, at.saturating_add(field::BLOCK_CONTROL)),
            value1: get_u16_be(buf, shifted(field::BLOCK_VALUE1, at)).cast_signed(),
            value2: get_u16_be(buf, shifted(field::BLOCK_VALUE2, at)).cast_signed(),
        }
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Request<T> {
    /// Sets TADR.
    pub fn set_tadr(&mut self, tadr: u8) {
        set_u8(self.buffer.as_mut(), field::TADR, tadr);
    }

    /// Sets SADR (CMD 3, CMD 6).
    pub fn set_sadr(&mut self, sadr: u8) {
        set_u8(self.buffer.as_mut(), field::SADR, sadr);
    }

    /// Sets SNUM (CMD 15).
    pub fn set_snum(&mut self, snum: u8) {
        set_u8(self.buffer.as_mut(), field::SNUM, snum);
    }

    /// Sets the CMD byte.
    pub fn set_command(&mut self, command: Command) {
        set_u8(self.buffer.as_mut(), field::CMD, command.code());
    }

    /// Sets IDH, IDL.
    pub fn set_id(&mut self, id: u16) {
        set_u16_be(self.buffer.as_mut(), field::ID, id);
    }

    /// Sets N-high, N-low.
    pub fn set_word_count(&mut self, words: u16) {
        set_u16_be(self.buffer.as_mut(), field::N, words);
    }

    /// Sets DATH, DATL.
    pub fn set_value(&mut self, value: u16) {
        set_u16_be(self.buffer.as_mut(), field::DAT, value);
    }

    /// Writes the block of module `x` (1..=5); dropped if `x` is 0 or the
    /// block is out of the buffer.
    pub fn set_module(&mut self, x: u8, module: ModuleOutput) {
        let Some(at) = block_offset(x) else {
            return;
        };
        let buf = self.buffer.as_mut();
        if buf.len() < at.saturating_add(MODULE_BLOCK_LEN) {
            return;
        }
        set_u8(buf, at.saturating_add(field::BLOCK_CONTROL), module.control);
        set_u16_be(
            buf,
            shifted(field::BLOCK_VALUE1, at),
            module.value1.cast_unsigned(),
        );
        set_u16_be(
            buf,
            shifted(field::BLOCK_VALUE2, at),
            module.value2.cast_unsigned(),
        );
    }
}

impl<T: AsRef<[u8]>> AsRef<[u8]> for Request<T> {
    fn as_ref(&self) -> &[u8] {
        self.buffer.as_ref()
    }
}

/// Offset of module `x`'s block (x = 1..=5 → 3, 8, 13, 18, 23).
fn block_offset(x: u8) -> Option<usize> {
    usize::from(x)
        .checked_sub(1)
        .map(|i| field::MODULES.saturating_add(i.saturating_mul(MODULE_BLOCK_LEN)))
}

/// 3 + 5·SNUM (5.1).
const fn multi_write_len(snum: u8) -> usize {
    HEADER_LEN + MODULE_BLOCK_LEN * snum as usize
}

/// CMD 3, "Master Read parameters" (4.1.1): read `words` consecutive
/// parameters starting at `id` from module `sadr`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ReadRequest {
    /// Telegram address.
    pub tadr: u8,
    /// Module address (E22), 1..=32 (see [`super::limits::SADR_RANGE`];
    /// not checked here, the node answers an unknown one with exception
    /// 5).
    pub sadr: u8,
    /// First parameter ID.
    pub id: u16,
    /// Number of parameter words N, 1..=8 (checked by `parse` and `emit`).
    pub words: u16,
}

impl ReadRequest {
    /// Checks the word count (1..=[`MAX_READ_WORDS`]).
    pub const fn check(&self) -> Result<(), TelegramError> {
        if self.words == 0 || self.words > MAX_READ_WORDS {
            Err(TelegramError::WordCountOutOfRange { words: self.words })
        } else {
            Ok(())
        }
    }
}

/// CMD 6, "Master Write single parameter" (4.3.1), and its positive
/// response, which has the same layout and echoes the request (4.3.2,
/// example 4.4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct WriteParameter {
    /// Telegram address.
    pub tadr: u8,
    /// Module address (E22).
    pub sadr: u8,
    /// Parameter ID.
    pub id: u16,
    /// The parameter value, DATH/DATL as a raw word (the parameter decides
    /// whether it is signed: "0x7FFF == +32767, 0x8000 == -32768").
    pub value: u16,
}

/// One module's block of a CMD 15 request (5.1: DATx.1, DATx.2, DATx.3).
///
/// What the process values mean depends on the module's operation mode
/// (5.5.2 to 5.5.6; e.g. A1.01 set value and A1.02 feedback value in mode
/// 3); so does the control byte (see [`super::semantics::control`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ModuleOutput {
    /// DATx.1, the control byte ("Byte for special functions").
    pub control: u8,
    /// DATx.2H, DATx.2L, process value 1 (signed, 0x8000 == -32768).
    pub value1: i16,
    /// DATx.3H, DATx.3L, process value 2 (signed).
    pub value2: i16,
}

/// CMD 15, "Master writes multiple parameters" (5.1): the process data of
/// modules 1..=SNUM, in E22 order.
///
/// Built with [`MultiWriteRequest::new`]; holds 1..=5 modules.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MultiWriteRequest {
    tadr: u8,
    snum: u8,
    /// Modules 1..=snum; the rest stays default so that the derived
    /// equality and hash only see the modules in use.
    modules: [ModuleOutput; MAX_MODULES],
}

impl MultiWriteRequest {
    /// A request for `modules.len()` modules, `modules[0]` being the module
    /// with E22 = 1. Fails with [`TelegramError::SnumOutOfRange`] unless
    /// there are 1..=5 modules.
    pub fn new(tadr: u8, modules: &[ModuleOutput]) -> Result<Self, TelegramError> {
        let snum = u8::try_from(modules.len()).unwrap_or(u8::MAX);
        if !MODULE_ADDRESSES.contains(&snum) {
            return Err(TelegramError::SnumOutOfRange(snum));
        }
        let mut all = [ModuleOutput::default(); MAX_MODULES];
        for (slot, module) in all.iter_mut().zip(modules) {
            *slot = *module;
        }
        Ok(Self {
            tadr,
            snum,
            modules: all,
        })
    }

    /// Telegram address.
    pub const fn tadr(&self) -> u8 {
        self.tadr
    }

    /// Sets the telegram address (a new TADR forces an answer, 3.3).
    pub const fn set_tadr(&mut self, tadr: u8) {
        self.tadr = tadr;
    }

    /// SNUM, the number of modules, 1..=5.
    pub const fn snum(&self) -> u8 {
        self.snum
    }

    /// The modules' blocks, index 0 = module with E22 = 1.
    pub fn modules(&self) -> &[ModuleOutput] {
        self.modules
            .get(..usize::from(self.snum))
            .unwrap_or(&self.modules)
    }

    /// The modules' blocks, mutable.
    pub fn modules_mut(&mut self) -> &mut [ModuleOutput] {
        let snum = usize::from(self.snum);
        let (used, _) = self.modules.split_at_mut(snum.min(MAX_MODULES));
        used
    }

    /// The block of the module with E22 = `x` (1..=SNUM).
    pub fn module(&self, x: u8) -> Option<&ModuleOutput> {
        usize::from(x)
            .checked_sub(1)
            .and_then(|i| self.modules().get(i))
    }

    /// Length of the telegram, 3 + 5·SNUM.
    pub const fn buffer_len(&self) -> usize {
        multi_write_len(self.snum)
    }
}

/// A request, master → slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RequestRepr {
    /// CMD 3.
    Read(ReadRequest),
    /// CMD 6.
    Write(WriteParameter),
    /// CMD 15.
    MultiWrite(MultiWriteRequest),
}

impl RequestRepr {
    /// Parses a request that fills `bytes` exactly.
    ///
    /// Besides the errors of [`RequestRepr::parse_padded`], fails with
    /// [`TelegramError::BadLength`] if bytes follow the telegram.
    pub fn parse(bytes: &[u8]) -> Result<Self, TelegramError> {
        let repr = Self::parse_padded(bytes)?;
        check_exact(bytes, repr.buffer_len())?;
        Ok(repr)
    }

    /// Parses the request at the start of `bytes`, ignoring the bytes after
    /// it (the filler of a fixed-size process-data buffer, 6.3).
    ///
    /// Fails with [`TelegramError::Truncated`],
    /// [`TelegramError::UnknownCommand`] or
    /// [`TelegramError::SnumOutOfRange`] (see [`Request::telegram_len`]),
    /// and with [`TelegramError::WordCountOutOfRange`] for a CMD 3 whose N
    /// is not 1..=8.
    pub fn parse_padded(bytes: &[u8]) -> Result<Self, TelegramError> {
        let request = Request::new_checked(bytes)?;
        let tadr = request.tadr();
        match request.command() {
            Some(Command::Read) => {
                let read = ReadRequest {
                    tadr,
                    sadr: request.sadr(),
                    id: request.id(),
                    words: request.word_count(),
                };
                read.check()?;
                Ok(Self::Read(read))
            }
            Some(Command::Write) => Ok(Self::Write(WriteParameter {
                tadr,
                sadr: request.sadr(),
                id: request.id(),
                value: request.value(),
            })),
            Some(Command::MultiWrite) => {
                let snum = request.snum();
                let mut modules = [ModuleOutput::default(); MAX_MODULES];
                for (x, module) in (1..=snum).zip(modules.iter_mut()) {
                    *module = request.module(x);
                }
                Ok(Self::MultiWrite(MultiWriteRequest {
                    tadr,
                    snum,
                    modules,
                }))
            }
            None => Err(TelegramError::UnknownCommand(request.command_byte())),
        }
    }

    /// The command.
    pub const fn command(&self) -> Command {
        match self {
            Self::Read(_) => Command::Read,
            Self::Write(_) => Command::Write,
            Self::MultiWrite(_) => Command::MultiWrite,
        }
    }

    /// Telegram address; the response echoes it.
    pub const fn tadr(&self) -> u8 {
        match self {
            Self::Read(r) => r.tadr,
            Self::Write(w) => w.tadr,
            Self::MultiWrite(m) => m.tadr,
        }
    }

    /// Length of the telegram: 7, or 3 + 5·SNUM for CMD 15.
    pub const fn buffer_len(&self) -> usize {
        match self {
            Self::Read(_) | Self::Write(_) => SIMPLE_LEN,
            Self::MultiWrite(m) => m.buffer_len(),
        }
    }

    /// Writes the telegram at the start of `buf` and returns its length,
    /// [`RequestRepr::buffer_len`]; bytes after it are left alone.
    ///
    /// Fails with [`TelegramError::WordCountOutOfRange`] for a CMD 3 whose
    /// word count is not 1..=8 and with [`TelegramError::BufferTooSmall`];
    /// `buf` is untouched on failure.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, TelegramError> {
        if let Self::Read(read) = self {
            read.check()?;
        }
        let len = self.buffer_len();
        check_room(buf, len)?;
        let mut request = Request::new_unchecked(buf);
        request.set_tadr(self.tadr());
        request.set_command(self.command());
        match self {
            Self::Read(read) => {
                request.set_sadr(read.sadr);
                request.set_id(read.id);
                request.set_word_count(read.words);
            }
            Self::Write(write) => {
                request.set_sadr(write.sadr);
                request.set_id(write.id);
                request.set_value(write.value);
            }
            Self::MultiWrite(multi) => {
                request.set_snum(multi.snum);
                for (x, module) in (1..=multi.snum).zip(multi.modules()) {
                    request.set_module(x, *module);
                }
            }
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

    const READ: [u8; 7] = [0x24, 0x01, 0x03, 0x00, 0x07, 0x00, 0x01];

    fn module(control: u8, value1: i16, value2: i16) -> ModuleOutput {
        ModuleOutput {
            control,
            value1,
            value2,
        }
    }

    #[test]
    fn view_reads_every_field() {
        let request = Request::new_checked(&READ[..]).unwrap();
        assert_eq!(request.telegram_len(), Ok(7));
        assert_eq!(request.tadr(), 0x24);
        assert_eq!(request.sadr(), 1);
        assert_eq!(request.command(), Some(Command::Read));
        assert_eq!(request.id(), 7);
        assert_eq!(request.word_count(), 1);
        assert_eq!(request.as_ref(), &READ);
        assert_eq!(request.into_inner(), &READ[..]);
    }

    #[test]
    fn view_builds_a_multi_write_request() {
        let mut buf = [0u8; 13];
        let mut request = Request::new_unchecked(&mut buf[..]);
        request.set_tadr(0x23);
        request.set_snum(2);
        request.set_command(Command::MultiWrite);
        request.set_module(1, module(0x80, 1000, 0));
        request.set_module(2, module(0x00, -3000, 7));
        request.set_module(3, module(0xFF, -1, -1)); // out of the buffer
        request.set_module(0, module(0xFF, -1, -1)); // no module 0
        assert_eq!(request.module(2), module(0x00, -3000, 7));
        assert_eq!(request.module(0), ModuleOutput::default());
        assert_eq!(request.module(9), ModuleOutput::default());
        assert_eq!(
            buf,
            [
                0x23, 0x02, 0x0F, 0x80, 0x03, 0xE8, 0x00, 0x00, 0x00, 0xF4, 0x48, 0x00, 0x07
            ]
        );
    }

    #[test]
    fn short_and_unknown_requests_are_rejected() {
        assert_eq!(
            RequestRepr::parse(&READ[..2]),
            Err(TelegramError::Truncated { needed: 3, got: 2 })
        );
        assert_eq!(
            RequestRepr::parse(&READ[..6]),
            Err(TelegramError::Truncated { needed: 7, got: 6 })
        );
        assert_eq!(
            RequestRepr::parse(&[0x24, 0x01, 0x04, 0, 7, 0, 1]),
            Err(TelegramError::UnknownCommand(0x04))
        );
        // An error code is a response, never a request.
        assert_eq!(
            RequestRepr::parse(&[0x24, 0x01, 0x83, 0x05]),
            Err(TelegramError::UnknownCommand(0x83))
        );
    }

    #[test]
    fn trailing_bytes_are_bad_length_unless_padded() {
        let mut padded = [0u8; 8];
        padded[..7].copy_from_slice(&READ);
        assert_eq!(
            RequestRepr::parse(&padded),
            Err(TelegramError::BadLength {
                expected: 7,
                got: 8
            })
        );
        assert_eq!(
            RequestRepr::parse_padded(&padded),
            RequestRepr::parse(&READ)
        );
    }

    #[test]
    fn read_word_count_must_be_one_to_eight() {
        for (n_high, n_low, words) in [(0, 0, 0), (0, 9, 9), (1, 0, 256), (0xFF, 0xFF, 0xFFFF)] {
            assert_eq!(
                RequestRepr::parse(&[0x24, 0x01, 0x03, 0x00, 0x07, n_high, n_low]),
                Err(TelegramError::WordCountOutOfRange { words })
            );
        }
        let eight = [0x24, 0x01, 0x03, 0x00, 0x07, 0x00, 0x08];
        let repr = RequestRepr::parse(&eight).unwrap();
        let RequestRepr::Read(mut read) = repr else {
            panic!("not a read: {repr:?}")
        };
        assert_eq!(read.words, 8);
        read.words = 9;
        let mut out = [0xAAu8; 7];
        assert_eq!(
            RequestRepr::Read(read).emit(&mut out),
            Err(TelegramError::WordCountOutOfRange { words: 9 })
        );
        assert_eq!(out, [0xAA; 7]);
    }

    #[test]
    fn snum_must_be_one_to_five() {
        for snum in [0u8, 6, 0xFF] {
            let mut bytes = [0u8; 40];
            bytes[..3].copy_from_slice(&[0x23, snum, 0x0F]);
            assert_eq!(
                RequestRepr::parse_padded(&bytes),
                Err(TelegramError::SnumOutOfRange(snum))
            );
            assert_eq!(
                Request::new_unchecked(&bytes[..]).check_len(),
                Err(TelegramError::SnumOutOfRange(snum))
            );
        }
        for snum in 1..=5u8 {
            let len = 3 + 5 * usize::from(snum);
            let mut bytes = [0u8; 28];
            bytes[..3].copy_from_slice(&[0x23, snum, 0x0F]);
            let repr = RequestRepr::parse(&bytes[..len]).unwrap();
            assert_eq!(repr.buffer_len(), len);
            assert_eq!(
                RequestRepr::parse(&bytes[..len - 1]),
                Err(TelegramError::Truncated {
                    needed: len,
                    got: len - 1
                })
            );
        }
    }

    #[test]
    fn multi_write_request_holds_one_to_five_modules() {
        assert_eq!(
            MultiWriteRequest::new(0, &[]),
            Err(TelegramError::SnumOutOfRange(0))
        );
        assert_eq!(
            MultiWriteRequest::new(0, &[ModuleOutput::default(); 6]),
            Err(TelegramError::SnumOutOfRange(6))
        );
        let mut m = MultiWriteRequest::new(7, &[module(1, 2, 3), module(4, 5, 6)]).unwrap();
        assert_eq!(m.snum(), 2);
        assert_eq!(m.buffer_len(), 13);
        assert_eq!(m.module(1), Some(&module(1, 2, 3)));
        assert_eq!(m.module(2), Some(&module(4, 5, 6)));
        assert_eq!(m.module(0), None);
        assert_eq!(m.module(3), None);
        m.modules_mut()[1].value2 = -6;
        assert_eq!(m.modules().len(), 2);
        assert_eq!(m.module(2), Some(&module(4, 5, -6)));
        m.set_tadr(8);
        assert_eq!(m.tadr(), 8);
    }

    #[test]
    fn emit_needs_room_and_leaves_the_tail_alone() {
        let repr = RequestRepr::parse(&READ).unwrap();
        let mut short = [0u8; 6];
        assert_eq!(
            repr.emit(&mut short),
            Err(TelegramError::BufferTooSmall { needed: 7, got: 6 })
        );
        assert_eq!(short, [0; 6]);
        let mut long = [0xEEu8; 10];
        assert_eq!(repr.emit(&mut long), Ok(7));
        assert_eq!(&long[..7], &READ);
        assert_eq!(&long[7..], &[0xEE; 3]);
    }
}
