//! The HCS DMA-22(A) telegram codec (`hcs_dma22::telegram`): the zero-copy
//! views `Request` and `Response` (`new_checked`, `check_len`,
//! `telegram_len`, every getter and setter), `RequestRepr` and
//! `ResponseRepr` (`parse`, `parse_padded`, `buffer_len`, `emit`), the
//! `Repr` constructors (`MultiWriteRequest::new`, `ReadResponse::new`) and
//! the node rules on parsed requests (`ResponseGate`, `Multiplexer`).
//!
//! Input: the bytes of a process-data buffer holding one telegram (the
//! seeds are the byte examples of the manuals), read both as a request
//! (master -> slave) and as a response (slave -> master). The same bytes,
//! through `arbitrary`, also give `Repr`s built field by field, valid or
//! not, that are emitted.
//!
//! Invariants: no panic; every error is one the function documents for
//! its direction, and `parse` fails exactly like `parse_padded` when that
//! fails. When `parse_padded` succeeds: the view agrees (`new_checked`
//! and `check_len` succeed, `telegram_len()` is `buffer_len()`, the
//! getters give the `Repr`'s fields); `parse` accepts the telegram prefix
//! `bytes[..buffer_len()]` (and the whole input only if it is that prefix,
//! else `BadLength`); `emit` into `buffer_len()` bytes of garbage gives
//! back exactly that prefix, which parses to an equal `Repr`; `emit` into
//! a longer buffer leaves the tail alone; `emit` into any shorter buffer
//! is `BufferTooSmall` and leaves the buffer untouched. A built `Repr`
//! emits exactly when it is valid (word count 1..=8, CMD 15 SADR 1..=5)
//! and then round-trips the same way.
#![no_main]

use std::fmt::Debug;

use arbitrary::{Result as ArbResult, Unstructured};
use hcs_dma22::telegram::semantics::{Multiplexer, ResponseGate};
use hcs_dma22::telegram::{
    Command, ErrorReply, Exception, ModuleOutput, MultiWriteRequest, MultiWriteResponse,
    ReadRequest, ReadResponse, Request, RequestRepr, Response, ResponseRepr, TelegramError,
    WriteParameter,
};
use libfuzzer_sys::fuzz_target;

const COMMANDS: [Command; 3] = [Command::Read, Command::Write, Command::MultiWrite];

/// What both directions have in common.
trait Codec: Copy + PartialEq + Debug {
    const WHAT: &'static str;
    fn parse(bytes: &[u8]) -> Result<Self, TelegramError>;
    fn parse_padded(bytes: &[u8]) -> Result<Self, TelegramError>;
    fn buffer_len(&self) -> usize;
    fn emit(&self, buf: &mut [u8]) -> Result<usize, TelegramError>;
    /// `telegram_len`, `check_len` and whether `new_checked` succeeds, on
    /// the view of this direction.
    fn view_len(
        bytes: &[u8],
    ) -> (
        Result<usize, TelegramError>,
        Result<(), TelegramError>,
        bool,
    );
    /// Whether `parse` / `parse_padded` of this direction may fail so.
    fn documented(e: &TelegramError) -> bool;
    /// The view's getters give the fields of `self`.
    fn agrees_with_view(&self, telegram: &[u8]);
}

impl Codec for RequestRepr {
    const WHAT: &'static str = "request";
    fn parse(bytes: &[u8]) -> Result<Self, TelegramError> {
        Self::parse(bytes)
    }
    fn parse_padded(bytes: &[u8]) -> Result<Self, TelegramError> {
        Self::parse_padded(bytes)
    }
    fn buffer_len(&self) -> usize {
        self.buffer_len()
    }
    fn emit(&self, buf: &mut [u8]) -> Result<usize, TelegramError> {
        self.emit(buf)
    }
    fn view_len(
        bytes: &[u8],
    ) -> (
        Result<usize, TelegramError>,
        Result<(), TelegramError>,
        bool,
    ) {
        let view = Request::new_unchecked(bytes);
        (
            view.telegram_len(),
            view.check_len(),
            Request::new_checked(bytes).is_ok(),
        )
    }
    fn documented(e: &TelegramError) -> bool {
        matches!(
            e,
            TelegramError::Truncated { .. }
                | TelegramError::BadLength { .. }
                | TelegramError::UnknownCommand(_)
                | TelegramError::SnumOutOfRange(_)
                | TelegramError::WordCountOutOfRange { .. }
        )
    }
    fn agrees_with_view(&self, telegram: &[u8]) {
        let v = Request::new_unchecked(telegram);
        assert_eq!(v.tadr(), self.tadr(), "request TADR");
        assert_eq!(v.command(), Some(self.command()), "request CMD");
        assert_eq!(v.command_byte(), self.command().code(), "request CMD byte");
        match self {
            RequestRepr::Read(r) => {
                assert_eq!((v.sadr(), v.id(), v.word_count()), (r.sadr, r.id, r.words));
            }
            RequestRepr::Write(w) => {
                assert_eq!((v.sadr(), v.id(), v.value()), (w.sadr, w.id, w.value));
            }
            RequestRepr::MultiWrite(m) => {
                assert_eq!(v.snum(), m.snum(), "SNUM");
                assert_eq!(m.modules().len(), usize::from(m.snum()), "modules in use");
                for x in 1..=m.snum() {
                    assert_eq!(Some(&v.module(x)), m.module(x), "module {x}");
                }
                assert_eq!(m.module(0), None);
                assert_eq!(m.module(m.snum() + 1), None);
            }
        }
    }
}

impl Codec for ResponseRepr {
    const WHAT: &'static str = "response";
    fn parse(bytes: &[u8]) -> Result<Self, TelegramError> {
        Self::parse(bytes)
    }
    fn parse_padded(bytes: &[u8]) -> Result<Self, TelegramError> {
        Self::parse_padded(bytes)
    }
    fn buffer_len(&self) -> usize {
        self.buffer_len()
    }
    fn emit(&self, buf: &mut [u8]) -> Result<usize, TelegramError> {
        self.emit(buf)
    }
    fn view_len(
        bytes: &[u8],
    ) -> (
        Result<usize, TelegramError>,
        Result<(), TelegramError>,
        bool,
    ) {
        let view = Response::new_unchecked(bytes);
        (
            view.telegram_len(),
            view.check_len(),
            Response::new_checked(bytes).is_ok(),
        )
    }
    fn documented(e: &TelegramError) -> bool {
        matches!(
            e,
            TelegramError::Truncated { .. }
                | TelegramError::BadLength { .. }
                | TelegramError::UnknownCommand(_)
                | TelegramError::CntOutOfRange(_)
                | TelegramError::SadrOutOfRange(_)
        )
    }
    fn agrees_with_view(&self, telegram: &[u8]) {
        let v = Response::new_unchecked(telegram);
        assert_eq!(
            (v.tadr(), v.sadr()),
            (self.tadr(), self.sadr()),
            "TADR, SADR"
        );
        match self {
            ResponseRepr::Read(r) => {
                assert_eq!(v.command(), Some(Command::Read));
                assert_eq!(v.cnt(), r.cnt(), "CNT");
                assert_eq!(v.read_data().len(), usize::from(r.cnt()), "read data");
                assert_eq!(r.words().len() * 2, usize::from(r.cnt()));
                for (i, w) in r.words().iter().enumerate() {
                    assert_eq!(v.read_word(i), *w, "word {i}");
                }
                assert_eq!(v.read_word(r.words().len()), 0, "word past CNT");
            }
            ResponseRepr::Write(w) => {
                assert_eq!(v.command(), Some(Command::Write));
                assert_eq!((v.id(), v.value()), (w.id, w.value));
            }
            ResponseRepr::MultiWrite(m) => {
                assert_eq!(v.command(), Some(Command::MultiWrite));
                assert_eq!(
                    (v.status(), v.value1(), v.value2()),
                    (m.status, m.value1, m.value2)
                );
            }
            ResponseRepr::Error(e) => {
                assert!(v.is_error());
                assert_eq!(v.command(), None);
                assert_eq!(v.error_command(), Some(e.exception.command()));
                assert_eq!(v.exception(), Some(e.exception));
                assert_eq!(v.exception_code(), e.exception.code());
                assert_eq!(v.command_byte(), e.exception.error_code());
            }
        }
        if !matches!(self, ResponseRepr::Error(_)) {
            assert!(!v.is_error());
            assert_eq!(v.exception(), None);
        }
    }
}

/// Garbage of `len` bytes that differs from `like` in every byte, so that
/// an `emit` that skips a byte shows.
fn garbage(like: &[u8], len: usize) -> Vec<u8> {
    (0..len)
        .map(|i| !like.get(i).copied().unwrap_or(0x5A))
        .collect()
}

/// `emit` of a `Repr` that must be valid: `buffer_len()` bytes, the same
/// bytes in a longer buffer with the tail untouched, refusal of every
/// shorter buffer, and a parse of the bytes back to `repr`. The bytes.
fn emit_valid<C: Codec>(repr: &C) -> Vec<u8> {
    let n = repr.buffer_len();
    let mut out = vec![0xA5u8; n];
    assert_eq!(repr.emit(&mut out), Ok(n), "{}: emit of {repr:?}", C::WHAT);
    let mut inverted = garbage(&out, n);
    assert_eq!(repr.emit(&mut inverted), Ok(n));
    assert_eq!(inverted, out, "{}: emit depends on the buffer", C::WHAT);
    assert_eq!(
        C::parse(&out),
        Ok(*repr),
        "{}: emitted {out:02x?} does not parse back",
        C::WHAT
    );
    assert_eq!(C::view_len(&out).0, Ok(n), "{}: view length", C::WHAT);
    repr.agrees_with_view(&out);

    let tail = [0x11u8, 0x22, 0x33];
    let mut long = garbage(&out, n);
    long.extend_from_slice(&tail);
    assert_eq!(repr.emit(&mut long), Ok(n));
    assert_eq!(
        &long[..n],
        &out[..],
        "{}: emit into a longer buffer",
        C::WHAT
    );
    assert_eq!(&long[n..], &tail, "{}: emit wrote past buffer_len", C::WHAT);
    assert_eq!(C::parse_padded(&long), Ok(*repr), "{}: padded", C::WHAT);

    for got in 0..n {
        let mut short = garbage(&out, got);
        let before = short.clone();
        assert_eq!(
            repr.emit(&mut short),
            Err(TelegramError::BufferTooSmall { needed: n, got }),
            "{}: emit of {repr:?} into {got} bytes",
            C::WHAT
        );
        assert_eq!(short, before, "{}: failed emit touched the buffer", C::WHAT);
    }
    out
}

/// `emit` of a `Repr` that must be refused: with `err` into a buffer with
/// room for it (into a shorter one `BufferTooSmall` will do), leaving the
/// buffer untouched.
fn emit_invalid<C: Codec>(repr: &C, err: TelegramError) {
    let n = repr.buffer_len();
    for len in [0, n - 1, n, 32] {
        let mut buf = vec![0xC3u8; len];
        let result = repr.emit(&mut buf);
        let too_small = TelegramError::BufferTooSmall {
            needed: n,
            got: len,
        };
        assert!(
            result == Err(err) || (len < n && result == Err(too_small)),
            "{}: emit of {repr:?} into {len} bytes: {result:?}",
            C::WHAT
        );
        assert!(
            buf.iter().all(|&b| b == 0xC3),
            "{}: failed emit wrote",
            C::WHAT
        );
    }
}

/// Parses `data` in one direction with every entry point and checks them
/// against each other; the parsed `Repr`.
fn parse_direction<C: Codec>(data: &[u8]) -> Option<C> {
    let exact = C::parse(data);
    let padded = C::parse_padded(data);
    let (view_len, view_check, view_checked) = C::view_len(data);
    assert_eq!(
        view_check.is_ok(),
        view_checked,
        "{}: check_len and new_checked disagree",
        C::WHAT
    );
    if let Ok(len) = view_len {
        assert_eq!(
            view_check.is_ok(),
            len <= data.len(),
            "{}: check_len and telegram_len disagree",
            C::WHAT
        );
    }
    for e in [&exact, &padded]
        .into_iter()
        .filter_map(|r| r.as_ref().err())
    {
        assert!(C::documented(e), "{}: undocumented error {e:?}", C::WHAT);
        let _ = (e.to_string(), e.exception());
        match *e {
            TelegramError::Truncated { needed, got } => {
                assert!(got == data.len() && needed > got, "{}: {e:?}", C::WHAT);
            }
            TelegramError::BadLength { expected, got } => {
                assert!(got == data.len() && expected < got, "{}: {e:?}", C::WHAT);
            }
            _ => {}
        }
    }

    let repr = match padded {
        Ok(repr) => repr,
        Err(e) => {
            assert_eq!(
                exact,
                Err(e),
                "{}: parse accepts more than parse_padded",
                C::WHAT
            );
            return None;
        }
    };
    let n = repr.buffer_len();
    assert!(
        n <= data.len(),
        "{}: {repr:?} longer than its input",
        C::WHAT
    );
    assert_eq!(view_len, Ok(n), "{}: view and Repr lengths differ", C::WHAT);
    assert!(view_checked, "{}: parsed but new_checked fails", C::WHAT);
    if n == data.len() {
        assert_eq!(
            exact,
            Ok(repr),
            "{}: parse and parse_padded differ",
            C::WHAT
        );
    } else {
        assert_eq!(
            exact,
            Err(TelegramError::BadLength {
                expected: n,
                got: data.len()
            }),
            "{}: parse of a padded telegram",
            C::WHAT
        );
    }
    let telegram = &data[..n];
    assert_eq!(
        C::parse(telegram),
        Ok(repr),
        "{}: parse of the prefix",
        C::WHAT
    );
    repr.agrees_with_view(telegram);
    let out = emit_valid(&repr);
    assert!(
        out == telegram,
        "{}: {repr:?} re-encodes differently\n parsed  {telegram:02x?}\n emitted {out:02x?}",
        C::WHAT
    );
    Some(repr)
}

/// Every getter of both views over any bytes.
fn touch_views(data: &[u8]) {
    let q = Request::new_unchecked(data);
    let _ = (q.tadr(), q.sadr(), q.snum(), q.command_byte(), q.command());
    let _ = (q.id(), q.word_count(), q.value(), q.as_ref().len());
    for x in 0..=u8::MAX {
        let _ = q.module(x);
    }
    let r = Response::new_unchecked(data);
    let _ = (
        r.tadr(),
        r.sadr(),
        r.command_byte(),
        r.is_error(),
        r.command(),
    );
    let _ = (
        r.error_command(),
        r.exception_code(),
        r.exception(),
        r.cnt(),
    );
    let _ = (r.id(), r.value(), r.status(), r.value1(), r.value2());
    assert!(r.read_data().len() <= data.len().saturating_sub(4));
    for i in [0, 1, 7, 8, 9, 255, usize::MAX / 2, usize::MAX] {
        let _ = r.read_word(i);
    }
    assert_eq!(r.into_inner().len(), data.len());
}

/// Every setter of both views on a copy of the bytes, with values taken
/// from them; the length never changes and what fits reads back.
fn poke_views(data: &[u8], u: &mut Unstructured<'_>) -> ArbResult<()> {
    let mut copy = data.to_vec();
    let mut q = Request::new_unchecked(&mut copy[..]);
    let (tadr, sadr, id, value): (u8, u8, u16, u16) = u.arbitrary()?;
    q.set_tadr(tadr);
    q.set_sadr(sadr);
    q.set_command(COMMANDS[usize::from(u.arbitrary::<u8>()? % 3)]);
    q.set_id(id);
    q.set_word_count(value);
    q.set_value(value);
    if data.len() >= 7 {
        assert_eq!(
            (q.tadr(), q.sadr(), q.id(), q.value()),
            (tadr, sadr, id, value)
        );
    }
    q.set_snum(sadr);
    for x in [0, 1, 2, 3, 4, 5, 6, u8::MAX] {
        let m = module(u)?;
        q.set_module(x, m);
        if x >= 1 && data.len() >= 3 + 5 * usize::from(x) {
            assert_eq!(q.module(x), m, "module {x} set and read back");
        }
    }
    let mut r = Response::new_unchecked(&mut copy[..]);
    r.set_tadr(tadr);
    r.set_sadr(sadr);
    r.set_command(COMMANDS[usize::from(u.arbitrary::<u8>()? % 3)]);
    r.set_cnt(u.arbitrary()?);
    for i in [0, 1, 7, 8, 200, usize::MAX] {
        r.set_read_word(i, value);
    }
    r.set_id(id);
    r.set_value(value);
    r.set_status(value);
    r.set_value1(value.cast_signed());
    r.set_value2(value.cast_signed());
    r.set_exception(exception(u)?);
    assert_eq!(copy.len(), data.len(), "a setter changed the length");
    Ok(())
}

fn module(u: &mut Unstructured<'_>) -> ArbResult<ModuleOutput> {
    Ok(ModuleOutput {
        control: u.arbitrary()?,
        value1: u.arbitrary()?,
        value2: u.arbitrary()?,
    })
}

fn exception(u: &mut Unstructured<'_>) -> ArbResult<Exception> {
    let cmd = COMMANDS[usize::from(u.arbitrary::<u8>()? % 3)];
    Ok(Exception::new(cmd, u.arbitrary()?))
}

/// `Repr`s built field by field (valid or not) emit exactly when valid.
fn built_reprs(u: &mut Unstructured<'_>) -> ArbResult<()> {
    let (tadr, sadr, id, words): (u8, u8, u16, u16) = u.arbitrary()?;
    let read = RequestRepr::Read(ReadRequest {
        tadr,
        sadr,
        id,
        words,
    });
    if (1..=8).contains(&words) {
        emit_valid(&read);
    } else {
        emit_invalid(&read, TelegramError::WordCountOutOfRange { words });
    }

    let write = WriteParameter {
        tadr,
        sadr,
        id,
        value: words,
    };
    // CMD 6: the response echoes the request, byte for byte.
    let as_request = emit_valid(&RequestRepr::Write(write));
    assert_eq!(emit_valid(&ResponseRepr::Write(write)), as_request);

    let k = usize::from(u.arbitrary::<u8>()? % 8);
    let modules = (0..k).map(|_| module(u)).collect::<ArbResult<Vec<_>>>()?;
    match MultiWriteRequest::new(tadr, &modules) {
        Ok(mut m) => {
            assert!((1..=5).contains(&k), "CMD 15 of {k} modules");
            assert_eq!((m.snum(), m.modules()), (k as u8, &modules[..]));
            emit_valid(&RequestRepr::MultiWrite(m));
            m.set_tadr(sadr);
            if let Some(first) = m.modules_mut().first_mut() {
                *first = module(u)?;
            }
            assert_eq!(m.tadr(), sadr);
            emit_valid(&RequestRepr::MultiWrite(m));
        }
        Err(e) => {
            assert!(!(1..=5).contains(&k), "CMD 15 of {k} modules refused");
            assert_eq!(e, TelegramError::SnumOutOfRange(k as u8));
        }
    }

    let k = usize::from(u.arbitrary::<u8>()? % 10);
    let values = (0..k)
        .map(|_| u.arbitrary())
        .collect::<ArbResult<Vec<u16>>>()?;
    match ReadResponse::new(tadr, sadr, &values) {
        Ok(r) => {
            assert!((1..=8).contains(&k), "CMD 3 response of {k} words");
            assert_eq!(r.words(), &values[..]);
            assert_eq!(usize::from(r.cnt()), 2 * k);
            emit_valid(&ResponseRepr::Read(r));
        }
        Err(e) => {
            assert!(!(1..=8).contains(&k), "CMD 3 response of {k} words refused");
            assert_eq!(e, TelegramError::WordCountOutOfRange { words: k as u16 });
        }
    }

    let (status, value1, value2): (u16, i16, i16) = u.arbitrary()?;
    let multi = ResponseRepr::MultiWrite(MultiWriteResponse {
        tadr,
        sadr,
        status,
        value1,
        value2,
    });
    if (1..=5).contains(&sadr) {
        emit_valid(&multi);
    } else {
        emit_invalid(&multi, TelegramError::SadrOutOfRange(sadr));
    }

    emit_valid(&ResponseRepr::Error(ErrorReply {
        tadr,
        sadr,
        exception: exception(u)?,
    }));
    Ok(())
}

/// The node rules on a parsed request: the gate answers a request once,
/// the multiplexer answers a CMD 15 with modules 1..=SNUM in turn.
fn node_rules(request: &RequestRepr) {
    let mut gate = ResponseGate::new();
    assert!(gate.admit(request), "first request not answered");
    assert!(!gate.admit(request), "unchanged repetition answered");
    assert_eq!(gate.last(), Some(request));
    if let RequestRepr::MultiWrite(m) = request {
        let mut mux = Multiplexer::new();
        for turn in 0..2 * usize::from(m.snum()) {
            let expected = (turn % usize::from(m.snum()) + 1) as u8;
            assert_eq!(mux.peek(m.snum()), Some(expected));
            assert_eq!(mux.next_sadr(m.snum()), Some(expected));
        }
    }
}

fn run(data: &[u8]) {
    touch_views(data);
    if let Some(request) = parse_direction::<RequestRepr>(data) {
        node_rules(&request);
    }
    parse_direction::<ResponseRepr>(data);

    let mut u = Unstructured::new(data);
    let _ = poke_views(data, &mut u);
    let mut u = Unstructured::new(data);
    let _ = built_reprs(&mut u);
}

fuzz_target!(|data: &[u8]| run(data));
