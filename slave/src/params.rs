//! Power-loss-safe parameter storage (manual 6.1.6, 6.2.2-6.2.4: SAVE,
//! LOADBACK, DEFAULT).
//!
//! Every entry the model marks `backup` is stored, in model order, each in
//! its byte size. The storage holds two copies ("slots"); a SAVE always
//! writes the slot that does not hold the newest valid set, with a sequence
//! number one higher. Loading takes the valid slot with the highest
//! sequence number. A power cut at any byte of a SAVE therefore leaves
//! either the old or the new set valid, never a mix.
//!
//! Slot layout (little-endian):
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 4 | magic `PAMP` (0x504D4150) |
//! | 4 | 4 | sequence number |
//! | 8 | 2 | payload length |
//! | 10 | 2 | layout version (1) |
//! | 12 | 4 | CRC-32 over bytes 4..12 and the payload |
//! | 16 | n | payload |

use crate::firmware::Crc32;
use crate::hal::{NvError, NvStorage};
use crate::od::model;
use crate::od::store::{ObjectStore, byte_len};
use crate::od::types::{DataType, Entry};

/// Size of one slot.
pub const SLOT_SIZE: usize = 512;
/// Storage needed for both slots.
pub const STORAGE_SIZE: usize = 2 * SLOT_SIZE;
const HEADER: usize = 16;
const MAGIC: u32 = 0x504D_4150;
const LAYOUT_VERSION: u16 = 1;

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

fn stored_entries() -> impl Iterator<Item = (usize, &'static Entry)> {
    let mut flat = 0usize;
    model::OBJECTS
        .iter()
        .flat_map(|o| o.entries.iter())
        .filter_map(move |e| {
            let here = flat;
            flat += 1;
            (e.backup && !e.gap && e.data_type != DataType::VisibleString).then_some((here, e))
        })
}

/// Bytes of the stored parameter set.
pub fn payload_len() -> usize {
    stored_entries().map(|(_, e)| byte_len(e)).sum()
}

fn crc(header: &[u8], payload: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(header.get(4..12).unwrap_or(&[]));
    c.update(payload);
    c.finish()
}

fn read_slot<N: NvStorage>(nv: &N, slot: usize, buf: &mut [u8; SLOT_SIZE]) -> Option<(u32, usize)> {
    nv.read(slot * SLOT_SIZE, buf).ok()?;
    let word =
        |o: usize| -> Option<u32> { Some(u32::from_le_bytes(buf.get(o..o + 4)?.try_into().ok()?)) };
    if word(0)? != MAGIC {
        return None;
    }
    let seq = word(4)?;
    let len = usize::from(u16::from_le_bytes(buf.get(8..10)?.try_into().ok()?));
    let version = u16::from_le_bytes(buf.get(10..12)?.try_into().ok()?);
    if version != LAYOUT_VERSION || len != payload_len() || HEADER + len > SLOT_SIZE {
        return None;
    }
    let payload = buf.get(HEADER..HEADER + len)?;
    (crc(buf, payload) == word(12)?).then_some((seq, len))
}

/// The newest valid slot: (slot, sequence).
fn newest<N: NvStorage>(nv: &N) -> Option<(usize, u32)> {
    let mut buf = [0u8; SLOT_SIZE];
    let a = read_slot(nv, 0, &mut buf).map(|(s, _)| (0, s));
    let b = read_slot(nv, 1, &mut buf).map(|(s, _)| (1, s));
    match (a, b) {
        (Some(x), Some(y)) => Some(if y.1.wrapping_sub(x.1) as i32 > 0 {
            y
        } else {
            x
        }),
        (x, y) => x.or(y),
    }
}

/// What `nv` holds.
pub fn stored<N: NvStorage>(nv: &N) -> Stored {
    if let Some((_, seq)) = newest(nv) {
        return Stored::Valid(seq);
    }
    let mut buf = [0u8; SLOT_SIZE];
    let blank =
        (0..2).all(|s| nv.read(s * SLOT_SIZE, &mut buf).is_ok() && buf.iter().all(|b| *b == 0xFF));
    if blank {
        Stored::Blank
    } else {
        Stored::Corrupt
    }
}

/// SAVE: writes the backup entries of `store` into the older slot.
/// Returns the new sequence number.
pub fn save<N: NvStorage>(store: &ObjectStore, nv: &mut N) -> Result<u32, ParamError> {
    if nv.capacity() < STORAGE_SIZE {
        return Err(ParamError::TooSmall(nv.capacity()));
    }
    let len = payload_len();
    if HEADER + len > SLOT_SIZE {
        return Err(ParamError::TooLarge(len));
    }
    let (slot, seq) = match newest(nv) {
        Some((s, seq)) => (1 - s, seq.wrapping_add(1)),
        None => (0, 1),
    };
    let mut buf = [0xFFu8; SLOT_SIZE];
    let mut at = HEADER;
    for (flat, e) in stored_entries() {
        let n = byte_len(e);
        let v = store.value(flat).to_le_bytes();
        if let (Some(dst), Some(src)) = (buf.get_mut(at..at + n), v.get(..n)) {
            dst.copy_from_slice(src);
        }
        at += n;
    }
    let mut head = [0u8; HEADER];
    head[0..4].copy_from_slice(&MAGIC.to_le_bytes());
    head[4..8].copy_from_slice(&seq.to_le_bytes());
    head[8..10].copy_from_slice(&(len as u16).to_le_bytes());
    head[10..12].copy_from_slice(&LAYOUT_VERSION.to_le_bytes());
    let c = crc(&head, buf.get(HEADER..HEADER + len).unwrap_or(&[]));
    head[12..16].copy_from_slice(&c.to_le_bytes());
    if let Some(dst) = buf.get_mut(..HEADER) {
        dst.copy_from_slice(&head);
    }
    nv.write(slot * SLOT_SIZE, buf.get(..HEADER + len).unwrap_or(&[]))?;
    Ok(seq)
}

/// LOADBACK: applies the newest valid set to `store`.
pub fn load<N: NvStorage>(store: &mut ObjectStore, nv: &N) -> Result<u32, ParamError> {
    let (slot, seq) = newest(nv).ok_or(ParamError::NoValidSet)?;
    let mut buf = [0u8; SLOT_SIZE];
    let (_, len) = read_slot(nv, slot, &mut buf).ok_or(ParamError::NoValidSet)?;
    let mut at = HEADER;
    for (flat, e) in stored_entries() {
        let n = byte_len(e);
        let mut raw = [0u8; 8];
        if let (Some(dst), Some(src)) = (raw.get_mut(..n), buf.get(at..at + n)) {
            dst.copy_from_slice(src);
        }
        let u = u64::from_le_bytes(raw);
        let bits = u32::from(e.bit_len).min(64);
        let v = if e.data_type.is_signed() && bits < 64 && bits > 0 {
            let shift = 64 - bits;
            ((u << shift) as i64) >> shift
        } else {
            u as i64
        };
        store.set_value(flat, v);
        at += n;
    }
    debug_assert_eq!(at, HEADER + len);
    Ok(seq)
}

/// DEFAULT: every backup entry back to its default value.
pub fn restore_defaults(store: &mut ObjectStore) {
    let defaults = ObjectStore::new();
    for (flat, _) in stored_entries() {
        store.set_value(flat, defaults.value(flat));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hal::MemNv;

    fn changed() -> ObjectStore {
        let mut s = ObjectStore::new();
        s.set(0x800D, 2, 2750);
        s.set(0x8006, 1, -7777);
        s.set(0x8002, 2, 120_000);
        s.set(0xF800, 1, 16383);
        s.set(0xF800, 2, 2);
        s
    }

    #[test]
    fn parameter_set_fits_a_slot() {
        assert!(HEADER + payload_len() <= SLOT_SIZE, "{}", payload_len());
        assert!(payload_len() > 200);
    }

    #[test]
    fn save_then_load_restores_every_stored_value() {
        let mut nv = MemNv::<STORAGE_SIZE>::new();
        assert_eq!(stored(&nv), Stored::Blank);
        let a = changed();
        assert_eq!(save(&a, &mut nv), Ok(1));
        let mut b = ObjectStore::new();
        assert_eq!(load(&mut b, &nv), Ok(1));
        for (flat, _) in stored_entries() {
            assert_eq!(a.value(flat), b.value(flat), "flat {flat}");
        }
        assert_eq!(b.get(0x8006, 1), Some(-7777));
    }

    #[test]
    fn saves_alternate_slots_and_the_newest_wins() {
        let mut nv = MemNv::<STORAGE_SIZE>::new();
        let mut s = ObjectStore::new();
        for i in 0..5 {
            s.set(0x800D, 2, 1000 + i);
            assert_eq!(save(&s, &mut nv), Ok(i as u32 + 1));
        }
        let mut t = ObjectStore::new();
        load(&mut t, &nv).unwrap();
        assert_eq!(t.get(0x800D, 2), Some(1004));
    }

    #[test]
    fn a_power_cut_at_every_byte_of_a_save_leaves_a_valid_set() {
        let old = ObjectStore::new();
        let new = changed();
        let mut base = MemNv::<STORAGE_SIZE>::new();
        save(&old, &mut base).unwrap();
        save(&old, &mut base).unwrap();
        let total = HEADER + payload_len();
        for cut in 0..=total {
            let mut nv = base.clone();
            nv.cut_power_after(cut);
            let res = save(&new, &mut nv);
            nv.restore_power();
            let mut s = ObjectStore::new();
            s.set(0x800D, 2, 9);
            let seq = load(&mut s, &nv).expect("a valid set after the cut");
            assert_eq!(res.is_ok(), cut == total, "cut {cut}");
            // Either the whole new set (the bytes not written already held
            // the new record's tail, or the write completed) or the whole
            // old one; never a mix.
            let expect = match seq {
                3 => &new,
                2 => &old,
                other => panic!("cut {cut}: sequence {other}"),
            };
            if cut < HEADER + 4 {
                assert_eq!(seq, 2, "cut {cut}: the new record cannot be valid yet");
            }
            for (flat, _) in stored_entries() {
                assert_eq!(s.value(flat), expect.value(flat), "cut {cut} flat {flat}");
            }
        }
    }

    #[test]
    fn corrupted_storage_is_reported_not_loaded() {
        let mut nv = MemNv::<STORAGE_SIZE>::new();
        save(&changed(), &mut nv).unwrap();
        nv.bytes_mut()[HEADER + 3] ^= 0x40;
        assert_eq!(stored(&nv), Stored::Corrupt);
        let mut s = ObjectStore::new();
        assert_eq!(load(&mut s, &nv), Err(ParamError::NoValidSet));
        assert_eq!(s.get(0x800D, 2), Some(1000), "nothing applied");
    }

    #[test]
    fn defaults_restore_only_parameters() {
        let mut s = changed();
        s.set(0x7000, 3, 5);
        restore_defaults(&mut s);
        assert_eq!(s.get(0x800D, 2), Some(1000));
        assert_eq!(s.get(0xF800, 2), Some(1));
        assert_eq!(s.get(0x7000, 3), Some(5), "process data untouched");
    }

    #[test]
    fn too_small_storage_is_an_error() {
        let mut nv = MemNv::<100>::new();
        assert_eq!(
            save(&ObjectStore::new(), &mut nv),
            Err(ParamError::TooSmall(100))
        );
    }
}
