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

    /// Appends `v` in decimal. Numbers are 32-bit: a Cortex-M divides
    /// those in one instruction, where a 64-bit division links about 1 KB
    /// of the compiler's routines (the texts' numbers are lengths, CRCs and
    /// identity fields).
    pub fn push_dec(&mut self, v: u32) -> &mut Self {
        let mut digits = [0u8; 10];
        let mut n = v;
        let mut i = digits.len();
        while let Some(d) = i.checked_sub(1).and_then(|k| digits.get_mut(k)) {
            *d = b'0' + (n % 10) as u8;
            i -= 1;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        for &d in digits.get(i..).unwrap_or(&[]) {
            self.push_byte(d);
        }
        self
    }

    /// Appends `0x` and `v` in hexadecimal, at least `width` digits
    /// (zero-padded; 0 = as few as needed, at most 8), lower or upper
    /// case: what `{:#x}`, `{:#010x}` and `0x{:08X}` print.
    pub fn push_hex(&mut self, v: u32, width: usize, upper: bool) -> &mut Self {
        self.push_str("0x");
        self.push_hex_digits(v, width, upper)
    }

    /// `v` in hexadecimal without the `0x` prefix (see [`Text::push_hex`]).
    pub fn push_hex_digits(&mut self, v: u32, width: usize, upper: bool) -> &mut Self {
        let alphabet: &[u8; 16] = if upper {
            b"0123456789ABCDEF"
        } else {
            b"0123456789abcdef"
        };
        let used = (8 - (v.leading_zeros() as usize) / 4).max(1);
        for k in (0..used.max(width).min(8)).rev() {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_pushed_as_ascii_keep_printable_ones_and_mark_the_rest() {
        let mut t: Text<16> = Text::new();
        t.push_ascii(b"2.1\xFF\x00-rc\n");
        assert_eq!(t.as_str(), "2.1??-rc?");
    }

    extern crate std;
    use std::format;

    #[test]
    fn numbers_print_as_core_fmt_prints_them() {
        for v in [
            0u32,
            1,
            9,
            10,
            99,
            100,
            255,
            65_535,
            65_536,
            0x1234_5678,
            999_999_999,
            u32::MAX,
        ] {
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
