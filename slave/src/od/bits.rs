//! Bit fields in byte buffers, LSB first and little-endian across bytes
//! as EtherCAT packs process data and complete-access records (ETG.1000.6
//! §5.6.2.5): what the PDO engine and complete access share.

/// Writes the low `len` bits of `v` at bit `offset` of `buf` (LSB first,
/// little-endian across bytes). Bits past the end of `buf` are dropped;
/// `len` is at most 64.
pub fn write_bits(buf: &mut [u8], offset: u16, len: u8, v: u64) {
    if len == 1 {
        // Flags, the most common bit field: one byte touched.
        if let Some(byte) = buf.get_mut(usize::from(offset / 8)) {
            let mask = 1u8 << (offset % 8);
            *byte = if v & 1 != 0 {
                *byte | mask
            } else {
                *byte & !mask
            };
        }
        return;
    }
    let len = u32::from(len.min(64));
    let mut pos = usize::from(offset);
    let mut done = 0;
    while done < len {
        let Some(byte) = buf.get_mut(pos / 8) else {
            return;
        };
        let shift = (pos % 8) as u32;
        let n = (8 - shift).min(len - done);
        let mask = (((1u16 << n) - 1) << shift) as u8;
        *byte = (*byte & !mask) | (((v >> done) as u8) << shift & mask);
        done += n;
        pos += n as usize;
    }
}

/// Reads `len` bits at bit `offset` of `buf` (LSB first, little-endian
/// across bytes); bits past the end of `buf` read as 0, `len` is at most
/// 64.
pub fn read_bits(buf: &[u8], offset: u16, len: u8) -> u64 {
    let len = u32::from(len.min(64));
    let mut pos = usize::from(offset);
    let mut done = 0;
    let mut v = 0u64;
    while done < len {
        let Some(&byte) = buf.get(pos / 8) else {
            break;
        };
        let shift = (pos % 8) as u32;
        let n = (8 - shift).min(len - done);
        let bits = (byte >> shift) & (((1u16 << n) - 1) as u8);
        v |= u64::from(bits) << done;
        done += n;
        pos += n as usize;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Bit `i` of `buf`, EtherCAT order (bit 0 the LSB of byte 0).
    fn bit(buf: &[u8], i: usize) -> bool {
        buf.get(i / 8).is_some_and(|b| b >> (i % 8) & 1 != 0)
    }

    #[test]
    fn write_bits_packs_lsb_first_across_bytes() {
        let mut buf = [0u8; 3];
        // 12 bits 0xABC at bit 4: low nibble C into byte 0's high nibble,
        // then 0xAB into byte 1.
        write_bits(&mut buf, 4, 12, 0xABC);
        assert_eq!(buf, [0xC0, 0xAB, 0x00]);
        assert_eq!(read_bits(&buf, 4, 12), 0xABC);
    }

    #[test]
    fn write_bits_keeps_the_neighbouring_bits() {
        let mut buf = [0xFFu8; 2];
        write_bits(&mut buf, 3, 6, 0);
        assert_eq!(buf, [0b0000_0111, 0b1111_1110]);
    }

    #[test]
    fn byte_aligned_fields_are_little_endian() {
        let mut buf = [0u8; 10];
        write_bits(&mut buf, 8, 32, 0x1122_3344);
        assert_eq!(&buf[..6], &[0, 0x44, 0x33, 0x22, 0x11, 0]);
        write_bits(&mut buf, 16, 64, u64::MAX);
        assert_eq!(read_bits(&buf, 16, 64), u64::MAX);
        assert_eq!(buf[1], 0x44);
    }

    #[test]
    fn bits_past_the_end_are_dropped_on_write_and_read_as_zero() {
        let mut buf = [0u8; 2];
        write_bits(&mut buf, 12, 8, 0xFF);
        assert_eq!(buf, [0x00, 0xF0]);
        assert_eq!(read_bits(&buf, 12, 8), 0x0F);
        assert_eq!(read_bits(&buf, 100, 8), 0);
        write_bits(&mut buf, u16::MAX, 64, u64::MAX);
        assert_eq!(buf, [0x00, 0xF0]);
        assert_eq!(read_bits(&[], 0, 64), 0);
    }

    #[test]
    fn a_length_over_64_is_cut_to_64() {
        let mut buf = [0u8; 10];
        write_bits(&mut buf, 0, 200, u64::MAX);
        assert_eq!(buf, [0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0, 0]);
        assert_eq!(read_bits(&buf, 0, 255), u64::MAX);
    }

    proptest! {
        /// Against a bit-by-bit model: exactly the field's bits change,
        /// and reading it back gives the value's low bits (those inside
        /// the buffer).
        #[test]
        fn write_then_read_matches_a_bit_by_bit_model(
            init in proptest::collection::vec(any::<u8>(), 0..12),
            offset in 0u16..100,
            len in 0u8..=64,
            v in any::<u64>(),
        ) {
            let mut buf = init.clone();
            write_bits(&mut buf, offset, len, v);
            let (start, end) = (usize::from(offset), usize::from(offset) + usize::from(len));
            let mut expect = 0u64;
            for i in 0..init.len() * 8 {
                let want = if (start..end).contains(&i) {
                    v >> (i - start) & 1 != 0
                } else {
                    bit(&init, i)
                };
                prop_assert_eq!(bit(&buf, i), want, "bit {}", i);
                if (start..end).contains(&i) && want {
                    expect |= 1 << (i - start);
                }
            }
            prop_assert_eq!(read_bits(&buf, offset, len), expect);
        }
    }
}
