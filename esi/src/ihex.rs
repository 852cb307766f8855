//! Intel HEX encoding and decoding of EEPROM images (host tool).
//!
//! Records: type 00 (data, 16 bytes per line), type 04 (extended linear
//! address, only written above 64 KiB), type 01 (end of file). The checksum
//! is the two's complement of the sum of all record bytes.

/// Data bytes per type-00 record.
pub const RECORD_LEN: usize = 16;

/// One record `:LLAAAATT<data>CC` with its checksum.
fn record(address: u16, kind: u8, data: &[u8]) -> String {
    let len = u8::try_from(data.len()).unwrap_or(u8::MAX);
    let [hi, lo] = address.to_be_bytes();
    let mut bytes = vec![len, hi, lo, kind];
    bytes.extend_from_slice(&data[..usize::from(len)]);
    let sum = bytes.iter().fold(0u8, |s, b| s.wrapping_add(*b));
    bytes.push(sum.wrapping_neg());
    let mut line = String::with_capacity(1 + bytes.len() * 2);
    line.push(':');
    for b in bytes {
        line.push_str(&format!("{b:02X}"));
    }
    line
}

/// Encodes `data` (loaded at address 0) as Intel HEX, one record per line,
/// each line ending in `\n`.
pub fn encode(data: &[u8]) -> String {
    let mut out = String::new();
    let mut upper: u32 = 0;
    for (n, chunk) in data.chunks(RECORD_LEN).enumerate() {
        let address = u32::try_from(n * RECORD_LEN).unwrap_or(u32::MAX);
        if address >> 16 != upper {
            upper = address >> 16;
            let ext = u16::try_from(upper).unwrap_or(u16::MAX).to_be_bytes();
            out.push_str(&record(0, 0x04, &ext));
            out.push('\n');
        }
        out.push_str(&record((address & 0xFFFF) as u16, 0x00, chunk));
        out.push('\n');
    }
    out.push_str(&record(0, 0x01, &[]));
    out.push('\n');
    out
}

/// Why an Intel HEX text could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IhexError {
    /// A line is not a well-formed record.
    #[error("line {line}: malformed record")]
    Malformed {
        /// 1-based line number.
        line: usize,
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
/// are filled with 0xFF (erased EEPROM).
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
        let hex = raw.strip_prefix(':').ok_or(IhexError::Malformed { line })?;
        let bytes = crate::xml::hex_binary(hex).ok_or(IhexError::Malformed { line })?;
        let (&len, rest) = bytes.split_first().ok_or(IhexError::Malformed { line })?;
        if bytes.len() != usize::from(len) + 5 || rest.len() < 4 {
            return Err(IhexError::Malformed { line });
        }
        if bytes.iter().fold(0u8, |s, b| s.wrapping_add(*b)) != 0 {
            return Err(IhexError::Checksum { line });
        }
        let address = usize::from(u16::from_be_bytes([rest[0], rest[1]]));
        let kind = rest[2];
        let data = &rest[3..3 + usize::from(len)];
        match kind {
            0x00 => {
                let at = base + address;
                let end = at + data.len();
                if end > LIMIT {
                    return Err(IhexError::TooLarge { line });
                }
                if out.len() < end {
                    out.resize(end, 0xFF);
                }
                out[at..end].copy_from_slice(data);
            }
            0x01 => return Ok(out),
            0x02 | 0x04 if data.len() == 2 => {
                let v = usize::from(u16::from_be_bytes([data[0], data[1]]));
                base = if kind == 0x02 { v << 4 } else { v << 16 };
            }
            0x02 | 0x04 => return Err(IhexError::Malformed { line }),
            other => return Err(IhexError::UnsupportedType { line, kind: other }),
        }
    }
    Err(IhexError::NoEof)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_checksum_matches_the_textbook_example() {
        let data = [
            0x21, 0x46, 0x01, 0x36, 0x01, 0x21, 0x47, 0x01, 0x36, 0x00, 0x7E, 0xFE, 0x09, 0xD2,
            0x19, 0x01,
        ];
        assert_eq!(
            record(0x0100, 0x00, &data),
            ":10010000214601360121470136007EFE09D2190140"
        );
        assert_eq!(record(0, 0x01, &[]), ":00000001FF");
    }

    #[test]
    fn encodes_sixteen_byte_records_and_a_short_last_one() {
        let data: Vec<u8> = (0..20).collect();
        let text = encode(&data);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[0].starts_with(":10000000000102"));
        assert!(lines[1].starts_with(":04001000101112"));
        assert_eq!(lines[2], ":00000001FF");
        assert!(text.ends_with('\n'));
    }

    #[test]
    fn empty_image_is_only_the_eof_record() {
        assert_eq!(encode(&[]), ":00000001FF\n");
    }

    #[test]
    fn images_above_64_kib_get_an_extended_linear_address_record() {
        let data = vec![0xA5u8; 0x10010];
        let text = encode(&data);
        assert!(text.contains("\n:020000040001F9\n"));
        assert_eq!(decode(&text).unwrap(), data);
    }

    #[test]
    fn decode_round_trips_the_sii_image() {
        let sii = crate::sii_image(&pam_199_p_etc::DEVICE);
        assert_eq!(decode(&encode(&sii)).unwrap(), sii);
    }

    #[test]
    fn decode_reports_bad_checksums_types_and_missing_eof() {
        assert_eq!(
            decode(":0100000000FE\n:00000001FF"),
            Err(IhexError::Checksum { line: 1 })
        );
        assert_eq!(decode(":0100000000FF\n"), Err(IhexError::NoEof));
        assert_eq!(
            decode(":00000003FD\n"),
            Err(IhexError::UnsupportedType { line: 1, kind: 3 })
        );
        assert_eq!(decode("garbage"), Err(IhexError::Malformed { line: 1 }));
        assert_eq!(decode(":05000000"), Err(IhexError::Malformed { line: 1 }));
    }
}
