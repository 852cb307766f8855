//! Power-loss-safe parameter storage: the mechanism behind a device's
//! SAVE / LOADBACK / DEFAULT commands (which object triggers them is the
//! device's business).
//!
//! Every entry the dictionary marks `backup` is stored, in dictionary
//! order, each in its byte size. The storage holds two copies ("slots"); a SAVE always
//! writes the slot that does not hold the newest valid set, with a sequence
//! number one higher. Loading takes the valid slot with the highest
//! sequence number. A power cut at any byte of a SAVE therefore leaves
//! either the old or the new set valid, never a mix.
//!
//! Slot layout (little-endian):
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 4 | magic `PRM1` (0x314D5250) |
//! | 4 | 4 | sequence number |
//! | 8 | 2 | payload length |
//! | 10 | 2 | layout version (2) |
//! | 12 | 4 | CRC-32 over bytes 4..12 and the payload |
//! | 16 | n | payload |

use crate::firmware::Crc32;
use crate::hal::{NvError, NvStorage};
use crate::od::Dictionary;
use crate::od::store::{Od, byte_len, from_raw};
use crate::od::types::{DefaultValue, Entry};

/// Size of one slot.
pub const SLOT_SIZE: usize = 512;
/// Storage needed for both slots.
pub const STORAGE_SIZE: usize = 2 * SLOT_SIZE;
/// Bytes of a slot header.
pub const HEADER: usize = 16;
const MAGIC: u32 = u32::from_le_bytes(*b"PRM1");
const LAYOUT_VERSION: u16 = 2;

/// Errors of the parameter store.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ParamError {
    /// The storage failed (or power was cut).
    #[error("parameter storage: {0}")]
    Storage(#[from] NvError),
    /// The storage is smaller than two slots.
    #[error("parameter storage too small: {0} bytes, need {STORAGE_SIZE}")]
    TooSmall(usize),
    /// The parameter set does not fit a slot.
    #[error("parameter set of {0} bytes does not fit a slot")]
    TooLarge(usize),
    /// No valid parameter set is stored.
    #[error("no valid parameter set stored")]
    NoValidSet,
}

/// What the storage holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stored {
    /// Both slots erased: a new device, the defaults apply.
    Blank,
    /// A valid set with this sequence number.
    Valid(u32),
    /// Something was written but no slot is valid: an EEPROM data error.
    Corrupt,
}

fn stored_entries(dict: &Dictionary) -> impl Iterator<Item = (usize, &'static Entry)> {
    dict.entries()
        .filter(|(_, _, e)| e.backup() && !e.gap() && !e.data_type.is_bytes())
        .map(|(flat, _, e)| (flat, e))
}

/// Bytes of the stored parameter set of `dict`.
pub fn payload_len(dict: &Dictionary) -> usize {
    stored_entries(dict).map(|(_, e)| byte_len(e)).sum()
}

/// Bytes read or written at once: slots are checked and written in
/// pieces, so no slot-sized buffer is ever on the stack.
const CHUNK: usize = 32;

fn header_word(head: &[u8; HEADER], at: usize) -> u32 {
    let mut w = [0u8; 4];
    if let Some(src) = head.get(at..at + 4) {
        w.copy_from_slice(src);
    }
    u32::from_le_bytes(w)
}

/// Sequence number and payload length of `slot` when it holds a valid set
/// for `dict` (magic, layout version, length and CRC checked).
fn read_slot<N: NvStorage>(nv: &N, dict: &Dictionary, slot: usize) -> Option<(u32, usize)> {
    let base = slot * SLOT_SIZE;
    let mut head = [0u8; HEADER];
    nv.read(base, &mut head).ok()?;
    if header_word(&head, 0) != MAGIC {
        return None;
    }
    let seq = header_word(&head, 4);
    let len = usize::from(u16::from_le_bytes([head[8], head[9]]));
    let version = u16::from_le_bytes([head[10], head[11]]);
    if version != LAYOUT_VERSION || len != payload_len(dict) || HEADER + len > SLOT_SIZE {
        return None;
    }
    let mut c = Crc32::new();
    c.update(head.get(4..12).unwrap_or(&[]));
    let mut chunk = [0u8; CHUNK];
    let mut at = 0;
    while at < len {
        let n = (len - at).min(CHUNK);
        let piece = chunk.get_mut(..n)?;
        nv.read(base + HEADER + at, piece).ok()?;
        c.update(piece);
        at += n;
    }
    (c.finish() == header_word(&head, 12)).then_some((seq, len))
}

/// The newest valid slot: (slot, sequence).
fn newest<N: NvStorage>(nv: &N, dict: &Dictionary) -> Option<(usize, u32)> {
    let a = read_slot(nv, dict, 0).map(|(s, _)| (0, s));
    let b = read_slot(nv, dict, 1).map(|(s, _)| (1, s));
    match (a, b) {
        (Some(x), Some(y)) => Some(if y.1.wrapping_sub(x.1) as i32 > 0 {
            y
        } else {
            x
        }),
        (x, y) => x.or(y),
    }
}

/// What `nv` holds for a device with dictionary `dict`.
pub fn stored<N: NvStorage>(nv: &N, dict: &Dictionary) -> Stored {
    if let Some((_, seq)) = newest(nv, dict) {
        return Stored::Valid(seq);
    }
    let mut chunk = [0u8; CHUNK];
    let blank = (0..STORAGE_SIZE / CHUNK)
        .all(|k| nv.read(k * CHUNK, &mut chunk).is_ok() && chunk.iter().all(|b| *b == 0xFF));
    if blank {
        Stored::Blank
    } else {
        Stored::Corrupt
    }
}

/// SAVE: writes the backup entries of `store` into the older slot.
/// Returns the new sequence number.
///
/// The payload is written first, entry by entry, and the header with the
/// CRC over it last: a power cut at any byte leaves that slot invalid
/// (its old header no longer matches its payload, or the new one is not
/// there yet) and the other slot's set is the newest valid one.
pub fn save<N: NvStorage>(store: &Od, nv: &mut N) -> Result<u32, ParamError> {
    if nv.capacity() < STORAGE_SIZE {
        return Err(ParamError::TooSmall(nv.capacity()));
    }
    let dict = store.dictionary();
    let len = payload_len(dict);
    if HEADER + len > SLOT_SIZE {
        return Err(ParamError::TooLarge(len));
    }
    let (slot, seq) = match newest(nv, dict) {
        Some((s, seq)) => (1 - s, seq.wrapping_add(1)),
        None => (0, 1),
    };
    let base = slot * SLOT_SIZE;
    let mut head = [0u8; HEADER];
    head[0..4].copy_from_slice(&MAGIC.to_le_bytes());
    head[4..8].copy_from_slice(&seq.to_le_bytes());
    head[8..10].copy_from_slice(&(len as u16).to_le_bytes());
    head[10..12].copy_from_slice(&LAYOUT_VERSION.to_le_bytes());
    let mut c = Crc32::new();
    c.update(head.get(4..12).unwrap_or(&[]));
    // Entries are gathered into chunks so the storage sees few writes.
    let mut chunk = [0u8; CHUNK];
    let (mut filled, mut at) = (0usize, 0usize);
    for (flat, e) in stored_entries(dict) {
        let n = byte_len(e);
        let v = store.value(flat).to_le_bytes();
        for &b in v.get(..n).unwrap_or(&[]) {
            if let Some(slot_byte) = chunk.get_mut(filled) {
                *slot_byte = b;
            }
            filled += 1;
            if filled == CHUNK {
                c.update(&chunk);
                nv.write(base + HEADER + at, &chunk)?;
                at += CHUNK;
                filled = 0;
            }
        }
    }
    if filled > 0 {
        let piece = chunk.get(..filled).unwrap_or(&[]);
        c.update(piece);
        nv.write(base + HEADER + at, piece)?;
    }
    head[12..16].copy_from_slice(&c.finish().to_le_bytes());
    nv.write(base, &head)?;
    Ok(seq)
}

/// LOADBACK: applies the newest valid set to `store`.
pub fn load<N: NvStorage>(store: &mut Od, nv: &N) -> Result<u32, ParamError> {
    let dict = store.dictionary();
    let (slot, seq) = newest(nv, dict).ok_or(ParamError::NoValidSet)?;
    let mut at = slot * SLOT_SIZE + HEADER;
    for (flat, e) in stored_entries(dict) {
        let n = byte_len(e);
        let mut bytes = [0u8; 8];
        let piece = bytes.get_mut(..n.min(8)).unwrap_or(&mut []);
        nv.read(at, piece)?;
        store.set_value(flat, decode(e, piece));
        at += n;
    }
    Ok(seq)
}

/// The value of `index:sub` in the newest valid set of `nv` (what a
/// LOADBACK would restore), without loading the rest; `None` when the
/// entry is not stored (not `backup`) or nothing valid is stored.
pub fn stored_value<N: NvStorage>(nv: &N, dict: &Dictionary, index: u16, sub: u8) -> Option<i64> {
    let (flat, _) = dict.find_entry(index, sub)?;
    let (slot, _) = newest(nv, dict)?;
    let mut at = slot * SLOT_SIZE + HEADER;
    for (f, e) in stored_entries(dict) {
        let n = byte_len(e);
        if f == flat {
            let mut bytes = [0u8; 8];
            let piece = bytes.get_mut(..n.min(8))?;
            nv.read(at, piece).ok()?;
            return Some(decode(e, piece));
        }
        at += n;
    }
    None
}

/// A stored value of `e` from its little-endian bytes, sign-extended for a
/// signed type.
fn decode(e: &Entry, bytes: &[u8]) -> i64 {
    let mut raw = [0u8; 8];
    let n = bytes.len().min(8);
    if let (Some(dst), Some(src)) = (raw.get_mut(..n), bytes.get(..n)) {
        dst.copy_from_slice(src);
    }
    from_raw(e, u64::from_le_bytes(raw))
}

/// DEFAULT: every backup entry of `store` back to its default.
pub fn restore_defaults(store: &mut Od) {
    for (flat, e) in stored_entries(store.dictionary()) {
        if let DefaultValue::Int(v) = e.default_value() {
            store.set_value(flat, v.get());
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use crate::hal::MemNv;
    use crate::testing::{DICT, store};

    #[test]
    fn save_then_load_restores_and_a_power_cut_keeps_a_valid_set() {
        let mut nv = MemNv::<STORAGE_SIZE>::new();
        assert_eq!(stored(&nv, &DICT), Stored::Blank);
        let mut a = store();
        a.set(0x8000, 1, 555);
        a.set(0x8001, 2, -7);
        assert_eq!(save(&a, &mut nv), Ok(1));
        let mut b = store();
        assert_eq!(load(&mut b, &nv), Ok(1));
        assert_eq!((b.get(0x8000, 1), b.get(0x8001, 2)), (Some(555), Some(-7)));
        // A second save cut after every byte leaves set 1 or set 2.
        a.set(0x8000, 1, 666);
        for cut in 0..(HEADER + payload_len(&DICT)) {
            let mut n = nv.clone();
            n.cut_power_after(cut);
            let _ = save(&a, &mut n);
            let mut c = store();
            let seq = load(&mut c, &n).unwrap();
            let v = c.get(0x8000, 1).unwrap();
            assert!(
                (seq == 1 && v == 555) || (seq == 2 && v == 666),
                "cut {cut}: {seq} {v}"
            );
        }
    }

    #[test]
    fn corruption_is_reported_and_defaults_restore_only_parameters() {
        let mut nv = MemNv::<STORAGE_SIZE>::new();
        let a = store();
        save(&a, &mut nv).unwrap();
        nv.bytes_mut()[HEADER] ^= 0xFF;
        assert_eq!(stored(&nv, &DICT), Stored::Corrupt);
        let mut s = store();
        assert_eq!(load(&mut s, &nv), Err(ParamError::NoValidSet));
        s.set(0x8000, 1, 9);
        s.set(0x7000, 3, 9);
        restore_defaults(&mut s);
        assert_eq!((s.get(0x8000, 1), s.get(0x7000, 3)), (Some(100), Some(9)));
        let mut small = MemNv::<16>::new();
        assert_eq!(save(&a, &mut small), Err(ParamError::TooSmall(16)));
    }
}
