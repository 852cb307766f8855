//! Property tests: no parse, view accessor or emit panics on any input;
//! every accepted byte string re-encodes to itself; every valid `Repr`
//! round-trips through `emit` and `parse`.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use proptest::prelude::*;

use super::*;

const COMMANDS: [Command; 3] = [Command::Read, Command::Write, Command::MultiWrite];

fn module() -> impl Strategy<Value = ModuleOutput> {
    (any::<u8>(), any::<i16>(), any::<i16>()).prop_map(|(control, value1, value2)| ModuleOutput {
        control,
        value1,
        value2,
    })
}

fn request() -> impl Strategy<Value = RequestRepr> {
    prop_oneof![
        (any::<u8>(), any::<u8>(), any::<u16>(), 1u16..=8).prop_map(|(tadr, sadr, id, words)| {
            RequestRepr::Read(ReadRequest {
                tadr,
                sadr,
                id,
                words,
            })
        }),
        (any::<u8>(), any::<u8>(), any::<u16>(), any::<u16>()).prop_map(
            |(tadr, sadr, id, value)| {
                RequestRepr::Write(WriteParameter {
                    tadr,
                    sadr,
                    id,
                    value,
                })
            }
        ),
        (any::<u8>(), prop::collection::vec(module(), 1..=5)).prop_map(|(tadr, modules)| {
            RequestRepr::MultiWrite(MultiWriteRequest::new(tadr, &modules).unwrap())
        }),
    ]
}

fn response() -> impl Strategy<Value = ResponseRepr> {
    prop_oneof![
        (
            any::<u8>(),
            any::<u8>(),
            prop::collection::vec(any::<u16>(), 1..=8)
        )
            .prop_map(|(tadr, sadr, words)| {
                ResponseRepr::Read(ReadResponse::new(tadr, sadr, &words).unwrap())
            }),
        (any::<u8>(), any::<u8>(), any::<u16>(), any::<u16>()).prop_map(
            |(tadr, sadr, id, value)| {
                ResponseRepr::Write(WriteParameter {
                    tadr,
                    sadr,
                    id,
                    value,
                })
            }
        ),
        (
            any::<u8>(),
            1u8..=5,
            any::<u16>(),
            any::<i16>(),
            any::<i16>()
        )
            .prop_map(|(tadr, sadr, status, value1, value2)| {
                ResponseRepr::MultiWrite(MultiWriteResponse {
                    tadr,
                    sadr,
                    status,
                    value1,
                    value2,
                })
            }),
        (any::<u8>(), any::<u8>(), 0usize..3, any::<u8>()).prop_map(|(tadr, sadr, cmd, code)| {
            ResponseRepr::Error(ErrorReply {
                tadr,
                sadr,
                exception: Exception::new(COMMANDS[cmd], code),
            })
        }),
    ]
}

/// Byte strings that look like telegrams often enough to reach every
/// branch: a CMD byte from the known set (or any), byte 1 / byte 3 small
/// (SNUM, CNT), and any length up to 40.
fn telegram_like() -> impl Strategy<Value = Vec<u8>> {
    (
        prop::collection::vec(any::<u8>(), 0..40),
        prop_oneof![
            Just(3u8),
            Just(6),
            Just(15),
            Just(0x83),
            Just(0x86),
            Just(0x8F),
            any::<u8>()
        ],
        0u8..8,
        0u8..20,
    )
        .prop_map(|(mut bytes, cmd, snum, cnt)| {
            if let Some(b) = bytes.get_mut(1) {
                *b = snum;
            }
            if let Some(b) = bytes.get_mut(2) {
                *b = cmd;
            }
            if let Some(b) = bytes.get_mut(3) {
                *b = cnt;
            }
            bytes
        })
}

fn bytes() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![prop::collection::vec(any::<u8>(), 0..64), telegram_like()]
}

/// Calls every getter of both views.
fn touch_views(bytes: &[u8]) {
    let request = Request::new_unchecked(bytes);
    let _ = (
        request.check_len(),
        request.telegram_len(),
        request.tadr(),
        request.sadr(),
        request.snum(),
        request.command(),
        request.id(),
        request.word_count(),
        request.value(),
    );
    for x in 0..=u8::MAX {
        let _ = request.module(x);
    }
    let response = Response::new_unchecked(bytes);
    let _ = (
        response.check_len(),
        response.telegram_len(),
        response.tadr(),
        response.sadr(),
        response.is_error(),
        response.command(),
        response.exception(),
        response.cnt(),
        response.read_data(),
        response.id(),
        response.value(),
        response.status(),
        response.value1(),
        response.value2(),
    );
    for i in [0, 1, 7, 8, 200, usize::MAX] {
        let _ = response.read_word(i);
    }
}

/// Calls every setter of both views on a copy of `bytes`.
fn poke_views(bytes: &[u8]) {
    let mut copy = bytes.to_vec();
    let mut request = Request::new_unchecked(&mut copy[..]);
    request.set_tadr(1);
    request.set_sadr(2);
    request.set_snum(3);
    request.set_command(Command::MultiWrite);
    request.set_id(4);
    request.set_word_count(5);
    request.set_value(6);
    for x in 0..=6 {
        request.set_module(x, ModuleOutput::default());
    }
    let mut response = Response::new_unchecked(&mut copy[..]);
    response.set_cnt(16);
    for i in [0, 7, 8, usize::MAX] {
        response.set_read_word(i, 0xFFFF);
    }
    response.set_status(1);
    response.set_value1(-1);
    response.set_value2(-1);
    response.set_exception(Exception::new(Command::Read, 1));
    assert_eq!(copy.len(), bytes.len());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    /// No parse, accessor or setter panics, whatever the bytes.
    #[test]
    fn arbitrary_bytes_never_panic(bytes in bytes()) {
        let _ = RequestRepr::parse(&bytes);
        let _ = RequestRepr::parse_padded(&bytes);
        let _ = ResponseRepr::parse(&bytes);
        let _ = ResponseRepr::parse_padded(&bytes);
        touch_views(&bytes);
        poke_views(&bytes);
    }

    /// Whatever `parse` accepts re-encodes to the same bytes (the codec
    /// is a bijection on valid telegrams), and `parse_padded` agrees with
    /// `parse` on the telegram part.
    #[test]
    fn accepted_bytes_re_encode_identically(bytes in bytes()) {
        if let Ok(repr) = RequestRepr::parse(&bytes) {
            let mut out = vec![0u8; bytes.len()];
            prop_assert_eq!(repr.emit(&mut out), Ok(bytes.len()));
            prop_assert_eq!(&out, &bytes);
        }
        if let Ok(repr) = RequestRepr::parse_padded(&bytes) {
            let mut out = bytes.clone();
            let len = repr.emit(&mut out).unwrap();
            prop_assert_eq!(&out, &bytes);
            prop_assert_eq!(RequestRepr::parse(&bytes[..len]), Ok(repr));
        }
        if let Ok(repr) = ResponseRepr::parse(&bytes) {
            let mut out = vec![0u8; bytes.len()];
            prop_assert_eq!(repr.emit(&mut out), Ok(bytes.len()));
            prop_assert_eq!(&out, &bytes);
        }
        if let Ok(repr) = ResponseRepr::parse_padded(&bytes) {
            let mut out = bytes.clone();
            let len = repr.emit(&mut out).unwrap();
            prop_assert_eq!(&out, &bytes);
            prop_assert_eq!(ResponseRepr::parse(&bytes[..len]), Ok(repr));
        }
    }

    /// Every valid request round-trips, padded or not; a buffer one byte
    /// short is refused untouched.
    #[test]
    fn valid_requests_round_trip(repr in request(), filler in prop::collection::vec(any::<u8>(), 0..8)) {
        let len = repr.buffer_len();
        prop_assert!((SIMPLE_LEN..=MAX_TELEGRAM_LEN).contains(&len));
        let mut out = vec![0u8; len];
        prop_assert_eq!(repr.emit(&mut out), Ok(len));
        prop_assert_eq!(RequestRepr::parse(&out), Ok(repr));
        out.extend_from_slice(&filler);
        prop_assert_eq!(RequestRepr::parse_padded(&out), Ok(repr));
        let mut short = vec![0x5Au8; len - 1];
        prop_assert_eq!(
            repr.emit(&mut short),
            Err(TelegramError::BufferTooSmall { needed: len, got: len - 1 })
        );
        prop_assert!(short.iter().all(|&b| b == 0x5A));
    }

    /// Every valid response round-trips, padded or not; a buffer one byte
    /// short is refused untouched.
    #[test]
    fn valid_responses_round_trip(repr in response(), filler in prop::collection::vec(any::<u8>(), 0..8)) {
        let len = repr.buffer_len();
        prop_assert!((ERROR_LEN..=20).contains(&len));
        let mut out = vec![0u8; len];
        prop_assert_eq!(repr.emit(&mut out), Ok(len));
        prop_assert_eq!(ResponseRepr::parse(&out), Ok(repr));
        out.extend_from_slice(&filler);
        prop_assert_eq!(ResponseRepr::parse_padded(&out), Ok(repr));
        let mut short = vec![0x5Au8; len - 1];
        prop_assert_eq!(
            repr.emit(&mut short),
            Err(TelegramError::BufferTooSmall { needed: len, got: len - 1 })
        );
        prop_assert!(short.iter().all(|&b| b == 0x5A));
    }
}
