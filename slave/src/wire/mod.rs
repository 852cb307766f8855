//! Wire formats: views and `Repr`s only, no state, no object-dictionary
//! knowledge.
//!
//! Every on-the-wire structure the slave stack touches is described here in
//! the style of smoltcp's `wire` module:
//!
//! * a zero-copy *view* (`EthernetFrame`, `EcatFrame`, `Datagram`, `Mailbox`,
//!   `Coe`, `Sdo`, `SdoInfo`, `Emergency`, ...) wrapping any `T: AsRef<[u8]>`,
//!   with `new_unchecked`, `new_checked`/`check_len`, getters and, for
//!   `T: AsRef<[u8]> + AsMut<[u8]>`, setters;
//! * where useful a high-level `Repr` with `parse`, `emit` and `buffer_len`.
//!
//! Views never panic: field accessors read out-of-range fields as zero (and
//! silently drop out-of-range writes, returning empty slices for payloads),
//! so even a view made with `new_unchecked` over a short buffer is safe to
//! use. Once `check_len` has succeeded every field is in range and the
//! values are meaningful.
//!
//! Protocol enumerations keep unknown codes as `Unknown(raw)` variants; the
//! parsers here reject only byte strings that cannot be interpreted at all
//! (too short, or a length field pointing past the buffer). Deciding whether
//! a well-formed but unexpected value is acceptable is the job of the layers
//! above.
//!
//! All multi-byte fields are little-endian, except the Ethernet ethertype,
//! which is big-endian as in every Ethernet II frame.
//!
//! Modules: [`ethernet`] (Ethernet II framing), [`ecat`] (EtherCAT header,
//! datagrams, datagram iteration), [`mailbox`] (mailbox header, mailbox error
//! reply), [`coe`] (CoE header, SDO, SDO abort codes, SDO information header,
//! emergency) and [`builder`] (building request frames for tests and tools).
//!
//! References: ETG.1000.4 (data link layer: EtherCAT frame header, datagrams,
//! mailbox header) and ETG.1000.6 (application layer: mailbox, CoE, SDO, SDO
//! information, emergency).

pub mod builder;
pub mod coe;
pub mod ecat;
pub mod ethernet;
pub mod foe;
pub mod mailbox;

/// Errors reported by the wire-format views and `Repr`s.
///
/// The variants describe *why* a byte string could not be interpreted; they
/// never carry protocol semantics (those are kept as `Unknown(raw)` values in
/// the protocol enums instead).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum WireError {
    /// The buffer is shorter than the fixed-size header of the format.
    #[error("buffer too short for the fixed header")]
    Truncated,
    /// A length field points past the end of the buffer, or is impossible
    /// for the format (e.g. below the format's minimum size).
    #[error("length field inconsistent with the buffer")]
    BadLength,
    /// A frame chains more datagrams than [`ecat::MAX_DATAGRAMS`].
    #[error("too many datagrams in one frame")]
    TooManyDatagrams,
    /// The destination buffer given to an `emit` is too small.
    #[error("output buffer too small")]
    BufferTooSmall,
    /// A `Repr` cannot be encoded because one of its fields is out of the
    /// range the wire format can carry (e.g. more than 4 bytes of expedited
    /// data, or a payload longer than the 11-bit length field).
    #[error("value does not fit the wire format")]
    Unrepresentable,
}

/// Byte range of a fixed-size field inside a header.
type Field = core::ops::Range<usize>;
/// Byte range of a variable-length tail (payload) starting at an offset.
type Rest = core::ops::RangeFrom<usize>;

/// Reads one byte, or 0 if `at` is out of range.
// The field helpers below are small and run on every datagram: `#[inline]`
// lets the crates that parse frames (the software ESC) inline them.
#[inline]
fn get_u8(buf: &[u8], at: usize) -> u8 {
    buf.get(at).copied().unwrap_or(0)
}

/// Writes one byte; out-of-range writes are dropped.
#[inline]
fn set_u8(buf: &mut [u8], at: usize, value: u8) {
    if let Some(b) = buf.get_mut(at) {
        *b = value;
    }
}

/// Reads a fixed-size array, or all zeroes if `field` is out of range.
#[inline]
fn get_array<const N: usize>(buf: &[u8], field: Field) -> [u8; N] {
    buf.get(field)
        .and_then(|b| <[u8; N]>::try_from(b).ok())
        .unwrap_or([0; N])
}

/// Writes a fixed-size array; out-of-range writes are dropped.
#[inline]
fn set_array<const N: usize>(buf: &mut [u8], field: Field, value: [u8; N]) {
    if let Some(b) = buf.get_mut(field).filter(|b| b.len() == N) {
        b.copy_from_slice(&value);
    }
}

/// Reads a little-endian `u16`, or 0 if `field` is out of range.
#[inline]
fn get_u16_le(buf: &[u8], field: Field) -> u16 {
    u16::from_le_bytes(get_array(buf, field))
}

/// Writes a little-endian `u16`; out-of-range writes are dropped.
#[inline]
fn set_u16_le(buf: &mut [u8], field: Field, value: u16) {
    set_array(buf, field, value.to_le_bytes());
}

/// Reads a little-endian `u32`, or 0 if `field` is out of range.
#[inline]
fn get_u32_le(buf: &[u8], field: Field) -> u32 {
    u32::from_le_bytes(get_array(buf, field))
}

/// Writes a little-endian `u32`; out-of-range writes are dropped.
#[inline]
fn set_u32_le(buf: &mut [u8], field: Field, value: u32) {
    set_array(buf, field, value.to_le_bytes());
}

/// Copies `data` into `buf` at `start`; dropped if it does not fit.
#[inline]
fn set_bytes(buf: &mut [u8], start: usize, data: &[u8]) {
    let end = start.saturating_add(data.len());
    if let Some(dst) = buf.get_mut(start..end) {
        dst.copy_from_slice(data);
    }
}

/// Sub-slice `range` of `buf`, or an empty slice if out of range.
fn slice(buf: &[u8], range: Field) -> &[u8] {
    buf.get(range).unwrap_or(&[])
}

/// Mutable sub-slice `range` of `buf`, or an empty slice if out of range.
fn slice_mut(buf: &mut [u8], range: Field) -> &mut [u8] {
    buf.get_mut(range).unwrap_or(&mut [])
}

/// Tail of `buf` from `rest`, or an empty slice if out of range.
fn tail(buf: &[u8], rest: Rest) -> &[u8] {
    buf.get(rest).unwrap_or(&[])
}

/// Mutable tail of `buf` from `rest`, or an empty slice if out of range.
fn tail_mut(buf: &mut [u8], rest: Rest) -> &mut [u8] {
    buf.get_mut(rest).unwrap_or(&mut [])
}

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_reads_are_zero_and_writes_are_dropped() {
        let mut buf = [0xAAu8; 3];
        assert_eq!(get_u16_le(&buf, 2..4), 0);
        assert_eq!(get_u32_le(&buf, 0..4), 0);
        assert_eq!(get_u8(&buf, 3), 0);
        set_u16_le(&mut buf, 2..4, 0x1234);
        set_u32_le(&mut buf, 0..4, 0x1234_5678);
        set_u8(&mut buf, 9, 1);
        assert_eq!(buf, [0xAA; 3]);
        assert!(slice(&buf, 2..5).is_empty());
        assert!(tail(&buf, 4..).is_empty());
        assert!(slice_mut(&mut buf, 1..9).is_empty());
        assert!(tail_mut(&mut buf, 7..).is_empty());
    }

    #[test]
    fn in_range_accesses_are_little_endian() {
        let mut buf = [0u8; 6];
        set_u16_le(&mut buf, 0..2, 0x1234);
        set_u32_le(&mut buf, 2..6, 0xDEAD_BEEF);
        assert_eq!(buf, [0x34, 0x12, 0xEF, 0xBE, 0xAD, 0xDE]);
        assert_eq!(get_u16_le(&buf, 0..2), 0x1234);
        assert_eq!(get_u32_le(&buf, 2..6), 0xDEAD_BEEF);
        assert_eq!(tail(&buf, 4..), &[0xAD, 0xDE]);
    }

    #[test]
    fn errors_have_messages() {
        use core::fmt::Write;
        let mut s: heapless::String<64> = heapless::String::new();
        write!(s, "{}", WireError::BadLength).unwrap();
        assert_eq!(s.as_str(), "length field inconsistent with the buffer");
    }
}
