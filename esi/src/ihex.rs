//! Intel HEX encoding and decoding of EEPROM images (host tool), on the
//! `ihex` crate's records.
//!
//! Layout written: type 00 data records of [`RECORD_LEN`] bytes (the last
//! one shorter), a type 04 extended linear address record before the first
//! data record above each 64 KiB boundary (an SII image never needs one),
//! and the type 01 end-of-file record; one record per line, each ending in
//! `\n`. The checksum is the two's complement of the sum of all record
//! bytes. Read: types 00, 01, 02 (extended segment address) and 04; the
//! start-address records 03 and 05 have no meaning for an EEPROM image
//! and are refused.

use ::ihex::{ReaderError, Record};

/// Data bytes per type-00 record.
pub const RECORD_LEN: usize = 16;

/// Encodes `data` (loaded at address 0) as Intel HEX, one record per line,
/// each line ending in `\n`.
pub fn encode(data: &[u8]) -> String {
    let mut records = Vec::with_capacity(data.len() / RECORD_LEN + 2);
    let mut upper: u32 = 0;
    for (n, chunk) in data.chunks(RECORD_LEN).enumerate() {
        let address = u32::try_from(n * RECORD_LEN).unwrap_or(u32::MAX);
        let [hi, hi_lo, lo_hi, lo] = address.to_be_bytes();
        if address >> 16 != upper {
            upper = address >> 16;
            records.push(Record::ExtendedLinearAddress(u16::from_be_bytes([
                hi, hi_lo,
            ])));
        }
        records.push(Record::Data {
            offset: u16::from_be_bytes([lo_hi, lo]),
            value: chunk.to_vec(),
        });
    }
    records.push(Record::EndOfFile);
    // Cannot fail: every record holds at most 16 data bytes and the only
    // end-of-file record is the last.
    ::ihex::create_object_file_representation(&records).unwrap_or_default()
}

/// Why an Intel HEX text could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IhexError {
    /// A line is not a well-formed record.
    #[error("line {line}: malformed record ({reason})")]
    Malformed {
        /// 1-based line number.
        line: usize,
        /// What the `ihex` reader found.
        reason: ReaderError,
    },
    /// A record's checksum is wrong.
    #[error("line {line}: checksum mismatch")]
    Checksum {
        /// 1-based line number.
        line: usize,
    },
    /// A record type other than 00, 01, 02, 04.
    #[error("line {line}: unsupported record type {kind:#04x}")]
    UnsupportedType {
        /// 1-based line number.
        line: usize,
        /// Record type.
        kind: u8,
    },
    /// The data extends beyond 16 MiB (an EEPROM image never does).
    #[error("line {line}: address beyond 16 MiB")]
    TooLarge {
        /// 1-based line number.
        line: usize,
    },
    /// No end-of-file record.
    #[error("no end-of-file record")]
    NoEof,
}

/// Decodes Intel HEX text into a flat image starting at address 0; gaps
/// are filled with 0xFF (erased EEPROM). Blank lines and whitespace around
/// a record are ignored; nothing after the end-of-file record is read.
pub fn decode(text: &str) -> Result<Vec<u8>, IhexError> {
    const LIMIT: usize = 16 << 20;
    let mut out: Vec<u8> = Vec::new();
    let mut base: usize = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let raw = raw.trim();
        if raw.is_empty() {
            continue;
        }
        let record = Record::from_record_string(raw).map_err(|e| match e {
            ReaderError::ChecksumMismatch(..) => IhexError::Checksum { line },
            ReaderError::UnsupportedRecordType(kind) => IhexError::UnsupportedType { line, kind },
            reason => IhexError::Malformed { line, reason },
        })?;
        match record {
            Record::Data { offset, value } => {
                let at = base + usize::from(offset);
                let end = at + value.len();
                if end > LIMIT {
                    return Err(IhexError::TooLarge { line });
                }
                if out.len() < end {
                    out.resize(end, 0xFF);
                }
                if let Some(dst) = out.get_mut(at..end) {
                    dst.copy_from_slice(&value);
                }
            }
            Record::EndOfFile => return Ok(out),
            Record::ExtendedSegmentAddress(v) => base = usize::from(v) << 4,
            Record::ExtendedLinearAddress(v) => base = usize::from(v) << 16,
            other @ (Record::StartSegmentAddress { .. } | Record::StartLinearAddress(_)) => {
                return Err(IhexError::UnsupportedType {
                    line,
                    kind: other.record_type(),
                });
            }
        }
    }
    Err(IhexError::NoEof)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The record layout of the Wikipedia / Intel specification example.
    #[test]
    fn record_checksum_matches_the_textbook_example() {
        let data = [
            0x21, 0x46, 0x01, 0x36, 0x01, 0x21, 0x47, 0x01, 0x36, 0x00, 0x7E, 0xFE, 0x09, 0xD2,
            0x19, 0x01,
        ];
        let rec = Record::Data {
            offset: 0x0100,
            value: data.to_vec(),
        };
        assert_eq!(
            rec.to_record_string().unwrap(),
            ":10010000214601360121470136007EFE09D2190140"
        );
        assert_eq!(
            decode(":10010000214601360121470136007EFE09D2190140\n:00000001FF\n")
                .unwrap()
                .get(0x100..),
            Some(&data[..])
        );
    }

    #[test]
    fn encodes_sixteen_byte_records_and_a_short_last_one() {
        let data: Vec<u8> = (0..20).collect();
        assert_eq!(
            encode(&data),
            ":10000000000102030405060708090A0B0C0D0E0F78\n\
             :0400100010111213A6\n\
             :00000001FF\n"
        );
    }

    #[test]
    fn empty_image_is_only_the_eof_record() {
        assert_eq!(encode(&[]), ":00000001FF\n");
    }

    #[test]
    fn images_above_64_kib_get_an_extended_linear_address_record() {
        let data = vec![0xA5u8; 0x10010];
        let text = encode(&data);
        assert!(text.contains("\n:020000040001F9\n:10000000A5A5"));
        assert_eq!(text.matches(":02000004").count(), 1);
        assert_eq!(decode(&text).unwrap(), data);
    }

    #[test]
    fn decode_round_trips_the_sii_image() {
        let sii = crate::sii_image(&pam_199_p_etc::DEVICE);
        assert_eq!(decode(&encode(&sii)).unwrap(), sii);
    }

    /// The golden EEPROM image's Intel HEX: every line a 16-byte record at
    /// the next address, the same bytes, one EOF record.
    #[test]
    fn the_golden_image_encodes_line_by_line() {
        let sii = include_bytes!("../golden/eeprom.bin");
        let text = encode(sii);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), sii.len().div_ceil(RECORD_LEN) + 1);
        for (n, (line, chunk)) in lines.iter().zip(sii.chunks(RECORD_LEN)).enumerate() {
            let mut hex = format!(":{:02X}{:04X}00", chunk.len(), n * RECORD_LEN);
            for b in chunk {
                hex.push_str(&format!("{b:02X}"));
            }
            assert!(line.starts_with(&hex), "line {n}: {line}");
            let address = n * RECORD_LEN;
            let sum = chunk.len() + (address >> 8) + (address & 0xFF);
            let sum = chunk.iter().fold(sum, |s, b| s + usize::from(*b));
            assert_eq!(line.len(), hex.len() + 2);
            assert_eq!(
                u8::from_str_radix(&line[hex.len()..], 16).unwrap(),
                (sum as u8).wrapping_neg()
            );
        }
        assert_eq!(lines.last(), Some(&":00000001FF"));
    }

    #[test]
    fn decode_reports_bad_checksums_types_and_missing_eof() {
        assert_eq!(
            decode(":0100000000FE\n:00000001FF"),
            Err(IhexError::Checksum { line: 1 })
        );
        assert_eq!(decode(":0100000000FF\n"), Err(IhexError::NoEof));
        // A start segment address record: valid, meaningless for an EEPROM.
        assert_eq!(
            decode(":0400000300000000F9\n"),
            Err(IhexError::UnsupportedType { line: 1, kind: 3 })
        );
        assert_eq!(
            decode("\n:00000006FA\n"),
            Err(IhexError::UnsupportedType { line: 2, kind: 6 })
        );
        assert_eq!(
            decode("garbage"),
            Err(IhexError::Malformed {
                line: 1,
                reason: ReaderError::MissingStartCode
            })
        );
        assert!(matches!(
            decode(":05000000"),
            Err(IhexError::Malformed { line: 1, .. })
        ));
        // Gaps are erased EEPROM; an extended segment address moves the base.
        assert_eq!(
            decode(":020000020001FB\n:01000200AB52\n:00000001FF\n"),
            Ok([vec![0xFF; 0x12], vec![0xAB]].concat())
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Any image up to 70 KiB (across the 64 KiB boundary) survives the
        /// round trip.
        #[test]
        fn any_image_round_trips(data in prop::collection::vec(any::<u8>(), 0..70_000)) {
            prop_assert_eq!(decode(&encode(&data)).unwrap(), data);
        }

        /// Text that is not Intel HEX is an error, never a panic.
        #[test]
        fn garbage_text_is_an_error_not_a_panic(text in "[:0-9A-Fa-fx \n]{0,200}") {
            let _ = decode(&text);
        }
    }
}
