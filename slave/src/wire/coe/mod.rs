//! CANopen over EtherCAT (ETG.1000.6 §5.6): CoE header, SDO requests and
//! responses, SDO abort codes, SDO information header and emergency
//! messages.
//!
//! Everything here sits in the data of a mailbox of type CoE:
//!
//! ```text
//! CoE header (2 bytes LE, ETG.1000.6 Table 29 "CoE elements")
//!  bits 0..=8 number, bits 9..=11 reserved, bits 12..=15 service
//!
//! SDO (ETG.1000.6 §5.6.2), at least 8 bytes after the CoE header:
//!  0        1       3     4              8
//! +--------+-------+-----+--------------+------------------------
//! | cmd    | index | sub | data / size  | data (normal transfer)
//! +--------+-------+-----+--------------+------------------------
//!  initiate cmd: bit 0 size indicator, bit 1 expedited, bits 2..=3 unused
//!                bytes of expedited data, bit 4 complete access, bits
//!                5..=7 command specifier
//!
//! SDO segment (ETG.1000.6 §5.6.2.3 / §5.6.2.6):
//!  0      1
//! +------+-------------------------------------------- (>= 7 bytes)
//! | cmd  | segment data (padded to 7 bytes)
//! +------+--------------------------------------------
//!  segment cmd: bit 0 last segment, bits 1..=3 unused bytes when the data
//!               is shorter than 7, bit 4 toggle, bits 5..=7 specifier
//! ```
//!
//! SDO frames are never shorter than 10 bytes after the mailbox header
//! ([`SDO_MAILBOX_MIN_LEN`]: CoE header + 8); shorter segment data is padded
//! with zeroes to 7 bytes and the number of padding bytes is given in the
//! command byte. In EtherCAT a segment may be longer than 7 bytes: its data
//! then runs to the end of the mailbox data (the mailbox length bounds it).
//!
//! [`SdoRequest`] and [`SdoResponse`] therefore parse *the bytes after the
//! CoE header, bounded by the mailbox length* (e.g. `coe.payload()` of a
//! [`CoeHeader`] built over `mailbox.payload()`).

use super::{Field, Rest, WireError};

/// Length of the CoE header.
pub const HEADER_LEN: usize = field::PAYLOAD.start;

/// Minimum length of an SDO request/response after the CoE header.
pub const SDO_LEN: usize = field::SDO_NORMAL_DATA.start;

/// Minimum mailbox data length of an SDO frame: CoE header + 8 bytes.
pub const SDO_MAILBOX_MIN_LEN: usize = HEADER_LEN + SDO_LEN;

/// Segment data shorter than this is padded to it (ETG.1000.6 §5.6.2.3).
pub const SEGMENT_MIN_DATA_LEN: usize = 7;

/// Length of the SDO information header after the CoE header.
pub const SDO_INFO_HEADER_LEN: usize = field::INFO_DATA.start;

/// Length of an emergency message after the CoE header.
pub const EMERGENCY_LEN: usize = field::EMCY_DATA.end;

mod field {
    use super::{Field, Rest};

    /// CoE header: number (bits 0..=8), reserved (9..=11), service
    /// (12..=15).
    pub const HEADER: Field = 0..2;
    /// Data following the CoE header.
    pub const PAYLOAD: Rest = 2..;

    /// SDO: command byte.
    pub const SDO_COMMAND: usize = 0;
    /// SDO: object index.
    pub const SDO_INDEX: Field = 1..3;
    /// SDO: subindex.
    pub const SDO_SUBINDEX: usize = 3;
    /// SDO: expedited data, complete size or abort code.
    pub const SDO_DATA: Field = 4..8;
    /// SDO: data of a normal (non-expedited) initiate.
    pub const SDO_NORMAL_DATA: Rest = 8..;
    /// SDO segment: segment data.
    pub const SEGMENT_DATA: Rest = 1..;

    /// SDO information: opcode (bits 0..=6) and incomplete flag (bit 7).
    pub const INFO_OPCODE: usize = 0;
    /// SDO information: reserved byte.
    pub const INFO_RESERVED: usize = 1;
    /// SDO information: fragments left.
    pub const INFO_FRAGMENTS_LEFT: Field = 2..4;
    /// SDO information: service data.
    pub const INFO_DATA: Rest = 4..;

    /// Emergency: error code.
    pub const EMCY_CODE: Field = 0..2;
    /// Emergency: error register (object 0x1001).
    pub const EMCY_REGISTER: usize = 2;
    /// Emergency: manufacturer-specific data.
    pub const EMCY_DATA: Field = 3..8;
}

mod abort;
mod emergency;
mod header;
mod sdo;
mod sdo_info;
mod sdo_repr;

pub use abort::*;
pub use emergency::*;
pub use header::*;
pub use sdo::*;
pub use sdo_info::*;
pub use sdo_repr::*;

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::*;

    /// Mailbox data of an SDO upload request for 0x1018:01 (CoE header
    /// 0x2000 = SDO request).
    static UPLOAD_REQUEST_BYTES: [u8; 10] =
        [0x00, 0x20, 0x40, 0x18, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00];

    /// Expedited upload response for 0x1018:01 = 0x0000_029A (4 bytes).
    static EXPEDITED_UPLOAD_RESPONSE_BYTES: [u8; 10] =
        [0x00, 0x30, 0x43, 0x18, 0x10, 0x01, 0x9A, 0x02, 0x00, 0x00];

    /// Expedited download request 0x6040:00 = 0x000F (2 bytes, n = 2).
    static EXPEDITED_DOWNLOAD_BYTES: [u8; 10] =
        [0x00, 0x20, 0x2B, 0x40, 0x60, 0x00, 0x0F, 0x00, 0x00, 0x00];

    /// Initiate download response for 0x6040:00.
    static DOWNLOAD_ACK_BYTES: [u8; 10] =
        [0x00, 0x30, 0x60, 0x40, 0x60, 0x00, 0x00, 0x00, 0x00, 0x00];

    /// Normal upload response for 0x1008:00 = "TD-1-NAME" (9 bytes).
    static NORMAL_UPLOAD_RESPONSE_BYTES: [u8; 19] = [
        0x00, 0x30, 0x41, 0x08, 0x10, 0x00, 0x09, 0x00, 0x00, 0x00, b'T', b'D', b'-', b'1', b'-',
        b'N', b'A', b'M', b'E',
    ];

    /// Normal download request with complete access for 0x1C12 (complete
    /// size 6, all 6 bytes in the request).
    static NORMAL_DOWNLOAD_BYTES: [u8; 16] = [
        0x00, 0x20, 0x31, 0x12, 0x1C, 0x00, 0x06, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x16, 0x01,
        0x16,
    ];

    /// Last download segment carrying 3 bytes, padded to 7 (unused = 4).
    static SHORT_SEGMENT_BYTES: [u8; 10] =
        [0x00, 0x20, 0x09, b'a', b'b', b'c', 0x00, 0x00, 0x00, 0x00];

    /// Upload segment response, toggle 1, last, 9 bytes (longer than 7).
    static LONG_SEGMENT_RESPONSE_BYTES: [u8; 12] = [
        0x00, 0x30, 0x11, b'1', b'2', b'3', b'4', b'5', b'6', b'7', b'8', b'9',
    ];

    /// Abort request for 0x7000:00, object does not exist.
    static ABORT_BYTES: [u8; 10] = [0x00, 0x20, 0x80, 0x00, 0x70, 0x00, 0x00, 0x00, 0x02, 0x06];

    /// Emergency 0x8130 (life guard/heartbeat error), register 0x11.
    static EMERGENCY_BYTES: [u8; 10] = [0x00, 0x10, 0x30, 0x81, 0x11, 1, 2, 3, 4, 5];

    /// SDO information: get OD list request for all objects (list type 1).
    static SDO_INFO_BYTES: [u8; 8] = [0x00, 0x80, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00];

    /// The SDO part of a CoE element (after the 2-byte CoE header).
    fn sdo_body(bytes: &[u8]) -> &[u8] {
        assert!(CoeHeader::new_checked(bytes).is_ok());
        &bytes[HEADER_LEN..]
    }

    #[test]
    fn deconstructs_coe_header() {
        let coe = CoeHeader::new_checked(&UPLOAD_REQUEST_BYTES[..]).unwrap();
        assert_eq!(coe.number(), 0);
        assert_eq!(coe.service(), CoeService::SdoRequest);
        assert_eq!(coe.payload(), &UPLOAD_REQUEST_BYTES[2..]);
        let coe = Coe::new_checked(&EMERGENCY_BYTES[..]).unwrap();
        assert_eq!(coe.service(), CoeService::Emergency);
    }

    #[test]
    fn constructs_coe_header() {
        let mut bytes = [0xFFu8; 2];
        CoeHeader::emit_into(&mut bytes, 0, CoeService::SdoResponse);
        assert_eq!(bytes, [0x00, 0x30]);
        let mut coe = CoeHeader::new_unchecked(&mut bytes[..]);
        coe.set_number(0x1FF);
        coe.set_service(CoeService::RxPdo);
        assert_eq!(coe.number(), 0x1FF);
        assert_eq!(coe.service(), CoeService::RxPdo);
        assert_eq!(bytes, [0xFF, 0x51]);
        // too short: nothing written, no panic
        let mut one = [0u8; 1];
        CoeHeader::emit_into(&mut one, 1, CoeService::SdoRequest);
        assert_eq!(one, [0]);
    }

    #[test]
    fn coe_repr_round_trip_and_limits() {
        let coe = CoeHeader::new_checked(&SDO_INFO_BYTES[..]).unwrap();
        let repr = CoeRepr::parse(&coe).unwrap();
        assert_eq!(
            repr,
            CoeRepr {
                number: 0,
                service: CoeService::SdoInformation
            }
        );
        let mut out = [0xAAu8; 2];
        repr.emit(&mut CoeHeader::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, [0x00, 0x80]);
        let bad = CoeRepr {
            number: 0x200,
            service: CoeService::TxPdo,
        };
        assert_eq!(
            bad.emit(&mut CoeHeader::new_unchecked(&mut out[..])),
            Err(WireError::Unrepresentable)
        );
        assert_eq!(
            repr.emit(&mut CoeHeader::new_unchecked(&mut out[..1])),
            Err(WireError::BufferTooSmall)
        );
        assert_eq!(
            CoeRepr::parse(&CoeHeader::new_unchecked(&[0u8][..])),
            Err(WireError::Truncated)
        );
    }

    #[test]
    fn unknown_coe_service_is_kept() {
        let coe = CoeHeader::new_checked(&[0x00u8, 0xF0][..]).unwrap();
        assert_eq!(coe.service(), CoeService::Unknown(15));
        for raw in 0..16u8 {
            assert_eq!(u8::from(CoeService::from(raw)), raw);
        }
    }

    #[test]
    fn parses_initiate_upload_request() {
        let req = SdoRequest::parse(sdo_body(&UPLOAD_REQUEST_BYTES)).unwrap();
        assert_eq!(
            req,
            SdoRequest::InitiateUpload {
                index: 0x1018,
                sub: 1,
                complete_access: false
            }
        );
        let mut out = [0xEEu8; 8];
        assert_eq!(req.emit(&mut out), Ok(8));
        assert_eq!(out, UPLOAD_REQUEST_BYTES[2..]);
    }

    #[test]
    fn sdo_view_deconstructs_expedited_download() {
        let sdo = Sdo::new_checked(sdo_body(&EXPEDITED_DOWNLOAD_BYTES)).unwrap();
        assert_eq!(sdo.command_specifier(), ccs::INITIATE_DOWNLOAD);
        assert!(sdo.expedited());
        assert!(sdo.size_indicator());
        assert_eq!(sdo.expedited_unused(), 2);
        assert_eq!(sdo.expedited_len(), 2);
        assert!(!sdo.complete_access());
        assert_eq!(sdo.index(), 0x6040);
        assert_eq!(sdo.sub_index(), 0);
        assert_eq!(sdo.data4(), [0x0F, 0, 0, 0]);
    }

    #[test]
    fn expedited_download_round_trip() {
        let req = SdoRequest::parse(sdo_body(&EXPEDITED_DOWNLOAD_BYTES)).unwrap();
        let expected = SdoRequest::InitiateDownload {
            index: 0x6040,
            sub: 0,
            complete_access: false,
            kind: DownloadKind::Expedited {
                data: [0x0F, 0, 0, 0],
                len: 2,
            },
        };
        assert_eq!(req, expected);
        if let SdoRequest::InitiateDownload { kind, .. } = req {
            assert_eq!(kind.data(), &[0x0F, 0x00]);
        }
        let mut out = [0u8; 8];
        assert_eq!(expected.emit(&mut out), Ok(8));
        assert_eq!(out, EXPEDITED_DOWNLOAD_BYTES[2..]);
    }

    #[test]
    fn expedited_size_bits_give_data_length() {
        for (cmd, len) in [(0x2F, 1), (0x2B, 2), (0x27, 3), (0x23, 4), (0x22, 4)] {
            let mut body = [0u8; 8];
            body[0] = cmd;
            match SdoRequest::parse(&body).unwrap() {
                SdoRequest::InitiateDownload {
                    kind: DownloadKind::Expedited { len: l, .. },
                    ..
                } => assert_eq!(l, len, "cmd {cmd:#x}"),
                other => panic!("unexpected {other:?}"),
            }
        }
    }

    #[test]
    fn expedited_with_impossible_length_is_unrepresentable() {
        let mut out = [0u8; 8];
        for len in [0u8, 5] {
            let req = SdoRequest::InitiateDownload {
                index: 1,
                sub: 0,
                complete_access: false,
                kind: DownloadKind::Expedited { data: [0; 4], len },
            };
            assert_eq!(req.emit(&mut out), Err(WireError::Unrepresentable));
            let resp = SdoResponse::UploadExpedited {
                index: 1,
                sub: 0,
                complete_access: false,
                data: [0; 4],
                len,
            };
            assert_eq!(resp.emit(&mut out), Err(WireError::Unrepresentable));
        }
    }

    #[test]
    fn download_ack_round_trip() {
        let resp = SdoResponse::parse(sdo_body(&DOWNLOAD_ACK_BYTES)).unwrap();
        assert_eq!(
            resp,
            SdoResponse::InitiateDownloadAck {
                index: 0x6040,
                sub: 0,
                complete_access: false
            }
        );
        let mut out = [0xFFu8; 8];
        assert_eq!(resp.emit(&mut out), Ok(8));
        assert_eq!(out, DOWNLOAD_ACK_BYTES[2..]);
    }

    #[test]
    fn expedited_upload_response_round_trip() {
        let resp = SdoResponse::parse(sdo_body(&EXPEDITED_UPLOAD_RESPONSE_BYTES)).unwrap();
        let expected = SdoResponse::UploadExpedited {
            index: 0x1018,
            sub: 1,
            complete_access: false,
            data: [0x9A, 0x02, 0, 0],
            len: 4,
        };
        assert_eq!(resp, expected);
        let mut out = [0u8; 8];
        assert_eq!(expected.emit(&mut out), Ok(8));
        assert_eq!(out, EXPEDITED_UPLOAD_RESPONSE_BYTES[2..]);
    }

    #[test]
    fn expedited_upload_emit_zeroes_unused_bytes() {
        let resp = SdoResponse::UploadExpedited {
            index: 0x6041,
            sub: 0,
            complete_access: false,
            data: [0x37, 0x02, 0xAA, 0xBB],
            len: 2,
        };
        let mut out = [0xFFu8; 8];
        assert_eq!(resp.emit(&mut out), Ok(8));
        assert_eq!(out, [0x4B, 0x41, 0x60, 0x00, 0x37, 0x02, 0x00, 0x00]);
    }

    #[test]
    fn normal_upload_response_round_trip() {
        let body = sdo_body(&NORMAL_UPLOAD_RESPONSE_BYTES);
        let resp = SdoResponse::parse(body).unwrap();
        let expected = SdoResponse::UploadNormal {
            index: 0x1008,
            sub: 0,
            complete_access: false,
            complete_size: 9,
            data: b"TD-1-NAME",
        };
        assert_eq!(resp, expected);
        assert_eq!(expected.buffer_len(), 17);
        let mut out = [0u8; 32];
        assert_eq!(expected.emit(&mut out), Ok(17));
        assert_eq!(&out[..17], body);
    }

    #[test]
    fn normal_download_with_complete_access_round_trip() {
        let body = sdo_body(&NORMAL_DOWNLOAD_BYTES);
        let req = SdoRequest::parse(body).unwrap();
        let expected = SdoRequest::InitiateDownload {
            index: 0x1C12,
            sub: 0,
            complete_access: true,
            kind: DownloadKind::Normal {
                complete_size: 6,
                data: &[0x02, 0x00, 0x00, 0x16, 0x01, 0x16],
            },
        };
        assert_eq!(req, expected);
        assert_eq!(expected.buffer_len(), 14);
        let mut out = [0u8; 14];
        assert_eq!(expected.emit(&mut out), Ok(14));
        assert_eq!(&out[..], body);
    }

    #[test]
    fn short_segment_honours_size_bits() {
        let body = sdo_body(&SHORT_SEGMENT_BYTES);
        let sdo = Sdo::new_checked(body).unwrap();
        assert_eq!(sdo.segment_unused(), 4);
        assert!(sdo.last_segment());
        assert!(!sdo.toggle());
        let req = SdoRequest::parse(body).unwrap();
        let expected = SdoRequest::DownloadSegment {
            toggle: false,
            last: true,
            data: b"abc",
        };
        assert_eq!(req, expected);
        assert_eq!(expected.buffer_len(), 8);
        let mut out = [0xFFu8; 8];
        assert_eq!(expected.emit(&mut out), Ok(8));
        assert_eq!(&out[..], body);
    }

    #[test]
    fn long_segment_runs_to_mailbox_length() {
        let body = sdo_body(&LONG_SEGMENT_RESPONSE_BYTES);
        let resp = SdoResponse::parse(body).unwrap();
        let expected = SdoResponse::UploadSegment {
            toggle: true,
            last: true,
            data: b"123456789",
        };
        assert_eq!(resp, expected);
        let mut out = [0u8; 10];
        assert_eq!(expected.emit(&mut out), Ok(10));
        assert_eq!(&out[..], body);
    }

    #[test]
    fn empty_segment_is_padded_to_seven_bytes() {
        let seg = SdoResponse::UploadSegment {
            toggle: false,
            last: true,
            data: &[],
        };
        let mut out = [0xFFu8; 8];
        assert_eq!(seg.emit(&mut out), Ok(8));
        assert_eq!(out, [0x0F, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(
            SdoResponse::parse(&out).unwrap(),
            SdoResponse::UploadSegment {
                toggle: false,
                last: true,
                data: &[]
            }
        );
    }

    #[test]
    fn segment_acks_and_segment_requests_round_trip() {
        let cases = [
            (
                SdoResponse::DownloadSegmentAck { toggle: true },
                [0x30u8, 0, 0, 0, 0, 0, 0, 0],
            ),
            (
                SdoResponse::DownloadSegmentAck { toggle: false },
                [0x20, 0, 0, 0, 0, 0, 0, 0],
            ),
        ];
        for (resp, bytes) in cases {
            let mut out = [0xFFu8; 8];
            assert_eq!(resp.emit(&mut out), Ok(8));
            assert_eq!(out, bytes);
            assert_eq!(SdoResponse::parse(&bytes).unwrap(), resp);
        }
        let req = SdoRequest::UploadSegment { toggle: true };
        let mut out = [0xFFu8; 8];
        assert_eq!(req.emit(&mut out), Ok(8));
        assert_eq!(out, [0x70, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(SdoRequest::parse(&out).unwrap(), req);
    }

    #[test]
    fn abort_request_and_response_round_trip() {
        let body = sdo_body(&ABORT_BYTES);
        let expected = SdoRequest::Abort {
            index: 0x7000,
            sub: 0,
            code: SdoAbortCode::ObjectNotFound,
        };
        assert_eq!(SdoRequest::parse(body).unwrap(), expected);
        let mut out = [0u8; 8];
        assert_eq!(expected.emit(&mut out), Ok(8));
        assert_eq!(&out[..], body);

        let resp = SdoResponse::Abort {
            index: 0x7000,
            sub: 0,
            code: SdoAbortCode::ObjectNotFound,
        };
        assert_eq!(SdoResponse::parse(body).unwrap(), resp);
        let mut out = [0u8; 8];
        assert_eq!(resp.emit(&mut out), Ok(8));
        assert_eq!(&out[..], body);
    }

    #[test]
    fn unknown_command_specifier_is_kept() {
        let body = [0xE0u8, 1, 2, 3, 4, 5, 6, 7];
        assert_eq!(
            SdoRequest::parse(&body).unwrap(),
            SdoRequest::Unknown { command: 0xE0 }
        );
        assert_eq!(
            SdoResponse::parse(&body).unwrap(),
            SdoResponse::Unknown { command: 0xE0 }
        );
        let mut out = [0xFFu8; 8];
        assert_eq!(SdoRequest::Unknown { command: 0xA0 }.emit(&mut out), Ok(8));
        assert_eq!(out, [0xA0, 0, 0, 0, 0, 0, 0, 0]);
    }

    #[test]
    fn sdo_shorter_than_eight_bytes_is_truncated() {
        for n in 0..SDO_LEN {
            let body = &UPLOAD_REQUEST_BYTES[2..2 + n];
            assert_eq!(SdoRequest::parse(body), Err(WireError::Truncated));
            assert_eq!(SdoResponse::parse(body), Err(WireError::Truncated));
        }
    }

    #[test]
    fn emit_into_short_buffer_fails_without_writing() {
        let resp = SdoResponse::UploadNormal {
            index: 0x1008,
            sub: 0,
            complete_access: false,
            complete_size: 9,
            data: b"TD-1-NAME",
        };
        let mut out = [0xEEu8; 16];
        assert_eq!(resp.emit(&mut out), Err(WireError::BufferTooSmall));
        assert_eq!(out, [0xEE; 16]);
        let seg = SdoRequest::DownloadSegment {
            toggle: false,
            last: false,
            data: b"x",
        };
        assert_eq!(seg.emit(&mut out[..7]), Err(WireError::BufferTooSmall));
    }

    #[test]
    fn unchecked_short_sdo_accessors_do_not_panic() {
        let sdo = Sdo::new_unchecked(&[0x09u8, b'a'][..]);
        assert_eq!(sdo.segment_data(), b"a");
        assert_eq!(sdo.index(), 0);
        assert_eq!(sdo.complete_size(), 0);
        assert!(sdo.normal_data().is_empty());
        let empty = Sdo::new_unchecked(&[][..]);
        assert!(empty.segment_data().is_empty());
        assert_eq!(empty.expedited_len(), 4);
    }

    #[test]
    fn abort_codes_round_trip_and_have_text() {
        use core::fmt::Write;
        assert_eq!(SdoAbortCode::ALL.len(), 31);
        for &code in SdoAbortCode::ALL {
            let raw = u32::from(code);
            assert_eq!(SdoAbortCode::from(raw), code);
            assert!(!code.description().is_empty());
        }
        assert_eq!(SdoAbortCode::from(0x0601_0001), SdoAbortCode::WriteOnly);
        assert_eq!(SdoAbortCode::from(0x0800_0022), SdoAbortCode::InvalidState);
        assert_eq!(
            SdoAbortCode::from(0x1234_5678),
            SdoAbortCode::Unknown(0x1234_5678)
        );
        assert_eq!(u32::from(SdoAbortCode::Unknown(7)), 7);
        // The first and the last of the table, by value.
        assert_eq!(u32::from(SdoAbortCode::ToggleBit), 0x0503_0000);
        assert_eq!(u32::from(*SdoAbortCode::ALL.last().unwrap()), 0x0800_0023);
        let mut s: heapless::String<96> = heapless::String::new();
        write!(s, "{}", SdoAbortCode::ObjectNotFound).unwrap();
        assert_eq!(
            s.as_str(),
            "0x06020000: the object does not exist in the object dictionary"
        );
    }

    #[test]
    fn sdo_info_header_deconstructs_and_round_trips() {
        let coe = CoeHeader::new_checked(&SDO_INFO_BYTES[..]).unwrap();
        assert_eq!(coe.service(), CoeService::SdoInformation);
        let info = SdoInfo::new_checked(coe.payload()).unwrap();
        assert_eq!(info.opcode(), SdoInfoOpcode::GetOdListReq);
        assert!(!info.incomplete());
        assert_eq!(info.reserved(), 0);
        assert_eq!(info.fragments_left(), 0);
        assert_eq!(info.payload(), &[0x01, 0x00]);
        let repr = SdoInfoRepr::parse(&info).unwrap();
        let mut out = [0xFFu8; 4];
        repr.emit(&mut SdoInfo::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, SDO_INFO_BYTES[2..6]);
    }

    #[test]
    fn sdo_info_incomplete_flag_is_separate_from_opcode() {
        let mut bytes = [0u8; 6];
        let mut info = SdoInfo::new_unchecked(&mut bytes[..]);
        info.set_opcode(SdoInfoOpcode::GetOdListResp);
        info.set_incomplete(true);
        info.set_fragments_left(3);
        info.payload_mut().copy_from_slice(&[0x00, 0x10]);
        assert_eq!(info.opcode(), SdoInfoOpcode::GetOdListResp);
        assert!(info.incomplete());
        info.set_opcode(SdoInfoOpcode::Unknown(0x7F));
        assert!(info.incomplete());
        assert_eq!(bytes, [0xFF, 0x00, 0x03, 0x00, 0x00, 0x10]);
        for raw in 0..0x80u8 {
            assert_eq!(u8::from(SdoInfoOpcode::from(raw)), raw);
        }
    }

    #[test]
    fn sdo_info_truncated_or_unrepresentable_is_rejected() {
        assert_eq!(
            SdoInfo::new_checked(&SDO_INFO_BYTES[2..5]).unwrap_err(),
            WireError::Truncated
        );
        let bad = SdoInfoRepr {
            opcode: SdoInfoOpcode::Unknown(0x80),
            incomplete: false,
            fragments_left: 0,
        };
        let mut out = [0u8; 4];
        assert_eq!(
            bad.emit(&mut SdoInfo::new_unchecked(&mut out[..])),
            Err(WireError::Unrepresentable)
        );
        let ok = SdoInfoRepr {
            opcode: SdoInfoOpcode::GetObjDescReq,
            ..bad
        };
        assert_eq!(ok.buffer_len(), 4);
        assert_eq!(
            ok.emit(&mut SdoInfo::new_unchecked(&mut out[..3])),
            Err(WireError::BufferTooSmall)
        );
    }

    #[test]
    fn emergency_round_trip() {
        let coe = CoeHeader::new_checked(&EMERGENCY_BYTES[..]).unwrap();
        let e = Emergency::new_checked(coe.payload()).unwrap();
        assert_eq!(e.error_code(), 0x8130);
        assert_eq!(e.error_register(), 0x11);
        assert_eq!(e.data(), [1, 2, 3, 4, 5]);
        let repr = EmergencyRepr::parse(&e).unwrap();
        assert_eq!(repr.buffer_len(), 8);
        let mut out = [0u8; 8];
        repr.emit(&mut Emergency::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, EMERGENCY_BYTES[2..]);
    }

    #[test]
    fn truncated_emergency_is_rejected() {
        assert_eq!(
            Emergency::new_checked(&EMERGENCY_BYTES[2..9]).unwrap_err(),
            WireError::Truncated
        );
        let e = Emergency::new_unchecked(&EMERGENCY_BYTES[2..4]);
        assert_eq!(e.error_code(), 0x8130);
        assert_eq!(e.data(), [0; 5]);
        let repr = EmergencyRepr {
            error_code: 0,
            error_register: 0,
            data: [0; 5],
        };
        let mut out = [0u8; 7];
        assert_eq!(
            repr.emit(&mut Emergency::new_unchecked(&mut out[..])),
            Err(WireError::BufferTooSmall)
        );
    }

    #[test]
    fn sdo_frames_meet_mailbox_minimum() {
        assert_eq!(SDO_MAILBOX_MIN_LEN, 10);
        let reqs = [
            SdoRequest::InitiateUpload {
                index: 0,
                sub: 0,
                complete_access: false,
            },
            SdoRequest::UploadSegment { toggle: false },
            SdoRequest::DownloadSegment {
                toggle: false,
                last: true,
                data: &[1],
            },
        ];
        for r in reqs {
            assert!(HEADER_LEN + r.buffer_len() >= SDO_MAILBOX_MIN_LEN);
        }
    }
}
