//! CRC-8 of the SII header (ETG.2010 Table 2, word 0x07 "Checksum").

/// CRC-8 as used for the SII checksum (ETG.2010 Table 2, word 0x07):
/// polynomial x^8 + x^2 + x + 1 (0x07), initial value 0xFF, no reflection, no
/// final XOR (the check
/// value of `"123456789"` is 0xFB). The checksum covers bytes 0..14 of the
/// image (words 0x00..0x06) and is stored in the low byte of word 0x07.
pub fn crc8(bytes: &[u8]) -> u8 {
    let mut crc: u8 = 0xFF;
    for &byte in bytes {
        crc ^= byte;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
    }
    crc
}

#[cfg(test)]
mod tests {
    use super::crc8;

    /// The check value of the algorithm: CRC of ASCII "123456789". (The
    /// `check: 0x80` in ethercrab's `crc::Algorithm` is unchecked metadata;
    /// the real dumps below confirm these parameters.)
    #[test]
    fn check_value_of_123456789_is_0xfb() {
        assert_eq!(crc8(b"123456789"), 0xFB);
    }

    #[test]
    fn empty_input_gives_the_initial_value() {
        assert_eq!(crc8(&[]), 0xFF);
    }

    /// Headers of EL2828 and EK1100 dumps (bytes 0..14 with their stored
    /// checksum byte), the ET1100 defaults as written by TwinCAT.
    #[test]
    fn beckhoff_header_vectors() {
        let el2828 = [
            0x04, 0x01, 0x00, 0x00, 0x00, 0x00, 0xFF, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        ];
        assert_eq!(crc8(&el2828), 0xE2);
        let ek1100 = [
            0x00, 0x0D, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        ];
        assert_eq!(crc8(&ek1100), 0x46);
        let el2004 = [
            0x04, 0x01, 0x00, 0x00, 0x00, 0x00, 0x0F, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        ];
        assert_eq!(crc8(&el2004), 0xD8);
    }

    /// The checksum of every real dump in `reference/sii-dumps` matches.
    #[test]
    fn real_dumps_carry_a_matching_header_crc() {
        let Some(dir) = super::super::read::tests::dump_dir() else {
            std::println!("sii-dumps folder absent, skipping");
            return;
        };
        let mut seen = 0;
        for (name, image) in super::super::read::tests::dumps(&dir) {
            assert!(image.len() >= 16, "{name}");
            let crc = crc8(&image[..14]);
            std::println!("{name}: stored {:#04x} computed {crc:#04x}", image[14]);
            assert_eq!(crc, image[14], "{name}");
            assert_eq!(image[15], 0, "{name}");
            seen += 1;
        }
        assert!(seen > 0);
    }
}
