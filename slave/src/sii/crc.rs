//! CRC-8 of the SII header (ETG.2010 Table 2, word 0x07 "Checksum").

/// The SII checksum as a `crc` algorithm. The crate's catalogue has no
/// entry with these parameters (CRC-8/ROHC has the polynomial and initial
/// value but reflects; CRC-8/SMBUS starts at 0), so ethercrab and we
/// define it.
const CRC_8_SII: crc::Algorithm<u8> = crc::Algorithm {
    width: 8,
    poly: 0x07,
    init: 0xFF,
    refin: false,
    refout: false,
    xorout: 0x00,
    check: 0xFB,
    residue: 0x00,
};

/// The `crc` crate's engine for [`CRC_8_SII`], bit by bit (`NoTable`: 14
/// bytes per image do not pay for a 256-byte table in flash).
static SII_CRC: crc::Crc<u8, crc::NoTable> = crc::Crc::<u8, crc::NoTable>::new(&CRC_8_SII);

/// CRC-8 as used for the SII checksum (ETG.2010 Table 2, word 0x07):
/// polynomial x^8 + x^2 + x + 1 (0x07), initial value 0xFF, no reflection, no
/// final XOR (the check
/// value of `"123456789"` is 0xFB). The checksum covers bytes 0..14 of the
/// image (words 0x00..0x06) and is stored in the low byte of word 0x07.
/// Computed by the `crc` crate.
pub fn crc8(bytes: &[u8]) -> u8 {
    SII_CRC.checksum(bytes)
}

#[cfg(test)]
mod tests {
    use super::crc8;
    use proptest::prelude::*;

    /// The algorithm as ETG.2010 states it, bit by bit (the hand-written
    /// implementation the crate replaced).
    fn crc8_bitwise(bytes: &[u8]) -> u8 {
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

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// The crate's table-driven CRC equals the bitwise definition.
        #[test]
        fn crate_crc8_equals_the_bitwise_definition(
            bytes in prop::collection::vec(any::<u8>(), 0..64)
        ) {
            prop_assert_eq!(crc8(&bytes), crc8_bitwise(&bytes));
        }
    }

    /// The check value of the algorithm: CRC of ASCII "123456789". (The
    /// `check: 0x80` in ethercrab's `crc::Algorithm` is unchecked metadata;
    /// the real dumps below confirm these parameters.)
    #[test]
    fn check_value_of_123456789_is_0xfb() {
        assert_eq!(crc8(b"123456789"), 0xFB);
        assert_eq!(super::CRC_8_SII.check, 0xFB);
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
        let dir = super::super::read::tests::dump_dir();
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
