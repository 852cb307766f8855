//! Texts for the wire without `core::fmt`: a fixed-capacity ASCII buffer
//! with decimal and hexadecimal numbers (a leaf: it uses nothing of the
//! crate).
//!
//! A firmware path never formats with `core::fmt`: its machinery costs a
//! few kilobytes of flash (the formatter, padding, every `Display` of an
//! integer), more than the texts it produces. The FoE error texts and the
//! FoE info file are built here instead, and the `Display` impls that host
//! tools use print the same bytes (one text, two users).

/// An ASCII text of at most `N` bytes; what does not fit is cut off (a
/// text on the wire is informative, so a short one beats an error).
#[derive(Clone, PartialEq, Eq)]
pub struct Text<const N: usize> {
    buf: [u8; N],
    len: usize,
}

impl<const N: usize> Default for Text<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> core::fmt::Debug for Text<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        core::fmt::Debug::fmt(self.as_str(), f)
    }
}

impl<const N: usize> Text<N> {
    /// An empty text.
    pub const fn new() -> Self {
        Text {
            buf: [0; N],
            len: 0,
        }
    }

    /// The bytes written so far.
    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    /// The text (only ASCII and whole UTF-8 sequences of `push_str` are
    /// ever written; a sequence cut at the capacity is dropped whole).
    pub fn as_str(&self) -> &str {
        match core::str::from_utf8(self.as_bytes()) {
            Ok(s) => s,
            Err(e) => {
                let good = self.buf.get(..e.valid_up_to()).unwrap_or(&[]);
                core::str::from_utf8(good).unwrap_or("")
            }
        }
    }

    /// Appends `s` (cut at the capacity).
    pub fn push_str(&mut self, s: &str) -> &mut Self {
        for &b in s.as_bytes() {
            self.push_byte(b);
        }
        self
    }

    /// Appends `bytes` as printable ASCII, `?` for any other byte (no
    /// UTF-8 check linked: a version read from an image may hold any byte).
    pub fn push_ascii(&mut self, bytes: &[u8]) -> &mut Self {
        for &b in bytes {
            self.push_byte(if (0x20..0x7F).contains(&b) { b } else { b'?' });
        }
        self
    }

    /// Appends `v` in decimal.
    pub fn push_dec(&mut self, v: u64) -> &mut Self {
        let mut digits = [0u8; 20];
        let mut n = v;
        let mut i = digits.len();
        loop {
            i -= 1;
            let (q, r) = div_rem_10(n);
            if let Some(d) = digits.get_mut(i) {
                *d = b'0' + r;
            }
            n = q;
            if n == 0 || i == 0 {
                break;
            }
        }
        for &d in digits.get(i..).unwrap_or(&[]) {
            self.push_byte(d);
        }
        self
    }

    /// Appends `0x` and `v` in hexadecimal, at least `width` digits
    /// (zero-padded; 0 = as few as needed), lower or upper case: what
    /// `{:#x}`, `{:#010x}` and `0x{:08X}` print.
    pub fn push_hex(&mut self, v: u64, width: usize, upper: bool) -> &mut Self {
        self.push_str("0x");
        self.push_hex_digits(v, width, upper)
    }

    /// `v` in hexadecimal without the `0x` prefix (see [`Text::push_hex`]).
    pub fn push_hex_digits(&mut self, v: u64, width: usize, upper: bool) -> &mut Self {
        let alphabet: &[u8; 16] = if upper {
            b"0123456789ABCDEF"
        } else {
            b"0123456789abcdef"
        };
        let used = (16 - (v.leading_zeros() as usize) / 4).max(1);
        for k in (0..used.max(width).min(16)).rev() {
            let nibble = ((v >> (4 * k)) & 0xF) as usize;
            self.push_byte(alphabet.get(nibble).copied().unwrap_or(b'?'));
        }
        self
    }

    fn push_byte(&mut self, b: u8) {
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = b;
            self.len += 1;
        }
    }
}

/// `(n / 10, n % 10)` from 32-bit divisions only, 16 bits at a time: a
/// Cortex-M has no 64-bit divide, and one `u64 / 10` links the compiler's
/// 64-bit division routine (about 1 KB of flash) into a firmware.
fn div_rem_10(n: u64) -> (u64, u8) {
    let mut q = 0u64;
    let mut rem = 0u32;
    for shift in [48u32, 32, 16, 0] {
        // rem < 10, so `cur` < 10 * 2^16 fits a u32.
        let cur = (rem << 16) | ((n >> shift) & 0xFFFF) as u32;
        q |= u64::from(cur / 10) << shift;
        rem = cur % 10;
    }
    (q, rem as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_pushed_as_ascii_keep_printable_ones_and_mark_the_rest() {
        let mut t: Text<16> = Text::new();
        t.push_ascii(b"2.1\xFF\x00-rc\n");
        assert_eq!(t.as_str(), "2.1??-rc?");
    }

    #[test]
    fn decimal_digits_come_from_32_bit_divisions_for_every_magnitude() {
        for n in [
            0u64,
            9,
            10,
            65_535,
            65_536,
            4_294_967_295,
            4_294_967_296,
            10u64.pow(19),
            u64::MAX,
        ] {
            assert_eq!(div_rem_10(n), (n / 10, (n % 10) as u8), "{n}");
            let mut t: Text<24> = Text::new();
            t.push_dec(n);
            assert_eq!(t.as_str(), n.to_string(), "{n}");
        }
    }
    extern crate std;
    use std::format;

    #[test]
    fn numbers_print_as_core_fmt_prints_them() {
        for v in [0u64, 1, 9, 10, 255, 0x1234_5678, u32::MAX as u64, u64::MAX] {
            let mut t: Text<64> = Text::new();
            t.push_dec(v);
            assert_eq!(t.as_str(), format!("{v}"));
            let mut t: Text<64> = Text::new();
            t.push_hex(v, 0, false);
            assert_eq!(t.as_str(), format!("{v:#x}"));
            let mut t: Text<64> = Text::new();
            t.push_hex(v, 8, false);
            assert_eq!(t.as_str(), format!("{v:#010x}"));
            let mut t: Text<64> = Text::new();
            t.push_str("0x").push_hex_digits(v, 8, true);
            assert_eq!(t.as_str(), format!("0x{v:08X}"));
        }
    }

    #[test]
    fn a_text_longer_than_the_capacity_is_cut_not_refused() {
        let mut t: Text<5> = Text::new();
        t.push_str("abc").push_dec(12345);
        assert_eq!(t.as_str(), "abc12");
    }

    #[test]
    fn a_multibyte_character_cut_at_the_capacity_is_dropped_whole() {
        let mut t: Text<4> = Text::new();
        t.push_str("ab°");
        assert_eq!(t.as_str(), "ab\u{b0}");
        let mut t: Text<3> = Text::new();
        t.push_str("ab°");
        assert_eq!(t.as_str(), "ab");
    }
}
