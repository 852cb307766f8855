//! Value parsers clap calls for arguments of several commands: numbers in
//! decimal or 0x-hex with their range, FoE passwords. A bad value is a
//! usage error naming the argument (exit 2), never a panic.

/// `0x1001` or `4097`.
pub fn parse_u16(s: &str) -> Result<u16, String> {
    let v = master_test::cli::parse_int(s)
        .ok_or_else(|| format!("'{s}' is not a number (decimal, or hex with 0x)"))?;
    u16::try_from(v).map_err(|_| format!("{v} is outside 0..=65535 (0x0000..=0xFFFF)"))
}

/// `0xFFFFFFFF` or `4294967295`.
pub fn parse_u32(s: &str) -> Result<u32, String> {
    let v = master_test::cli::parse_int(s)
        .ok_or_else(|| format!("'{s}' is not a number (decimal, or hex with 0x)"))?;
    u32::try_from(v).map_err(|_| format!("{v} is outside 0..=4294967295"))
}

/// A FoE password: 1 to 8 hex digits, `0x` optional.
pub fn parse_password(s: &str) -> Result<u32, String> {
    let digits = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    if digits.is_empty() || digits.len() > 8 || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(format!(
            "'{s}' is not a FoE password: 1 to 8 hex digits, 0x optional (e.g. 00000000)"
        ));
    }
    u32::from_str_radix(digits, 16).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn station_addresses_parse_in_hex_and_decimal() {
        assert_eq!(parse_u16("0x1001"), Ok(0x1001));
        assert_eq!(parse_u16("4097"), Ok(0x1001));
        assert!(
            parse_u16("0x10000")
                .unwrap_err()
                .contains("outside 0..=65535")
        );
        assert!(parse_u16("abc").unwrap_err().contains("not a number"));
    }

    #[test]
    fn revisions_parse_up_to_u32_max() {
        assert_eq!(parse_u32("0xFFFFFFFF"), Ok(u32::MAX));
        assert_eq!(parse_u32("7"), Ok(7));
        assert!(
            parse_u32("0x100000000")
                .unwrap_err()
                .contains("outside 0..=4294967295")
        );
        assert!(parse_u32("-1").unwrap_err().contains("outside"));
    }

    #[test]
    fn passwords_are_1_to_8_hex_digits() {
        assert_eq!(parse_password("00000000"), Ok(0));
        assert_eq!(parse_password("0x1234ABCD"), Ok(0x1234_ABCD));
        assert_eq!(parse_password("f"), Ok(15));
        for bad in ["", "0x", "123456789", "12G4", "-1"] {
            let e = parse_password(bad).unwrap_err();
            assert!(e.contains("1 to 8 hex digits"), "{bad}: {e}");
        }
    }
}
