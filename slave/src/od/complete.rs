//! Complete access (ETG.1000.6 5.6.2.1.2, 5.6.2.4.2): a whole record or
//! array in one SDO transfer.
//!
//! Layout, the same the ESI's record DataTypes declare: with subindex 0
//! included it takes 16 bits (the UINT8 value and 8 padding bits), then
//! every following subindex packed at its bit size in subindex order, gaps
//! as zero bits, the total rounded up to whole bytes. Without subindex 0
//! (request subindex 1) packing starts with subindex 1 at bit 0. Arrays
//! carry as many elements as subindex 0 says (upload), or as the data holds
//! (download, which then sets subindex 0).

use super::model;
use super::store::{ObjectStore, byte_len};
use super::types::{Access, DataType, Object, ObjectCode};
use crate::al::AlState;
use crate::pdo::{read_bits, write_bits};
use crate::wire::coe::SdoAbortCode;

/// Largest complete-access image handled.
pub const MAX_COMPLETE: usize = 256;

/// Most entries one complete download can change.
pub const MAX_ENTRIES: usize = 64;

fn object(index: u16) -> Result<(usize, &'static Object), SdoAbortCode> {
    let (pos, obj) = model::find(index).ok_or(SdoAbortCode::ObjectNotFound)?;
    if obj.code == ObjectCode::Var {
        return Err(SdoAbortCode::CompleteAccessNotSupported);
    }
    Ok((pos, obj))
}

/// Which entries take part: `(flat, entry)` from the first subindex on.
fn members(
    index: u16,
    obj: &'static Object,
    with_sub0: bool,
    elements: Option<u8>,
) -> impl Iterator<Item = (usize, &'static super::types::Entry)> {
    let start = if with_sub0 { 0 } else { 1 };
    obj.entries
        .iter()
        .filter(move |e| e.sub >= start && elements.is_none_or(|n| e.sub <= n))
        .filter_map(move |e| model::find_entry(index, e.sub).map(|(f, _)| (f, e)))
}

fn bit_size(e: &super::types::Entry) -> u16 {
    if e.sub == 0 { 16 } else { e.bit_len }
}

/// Complete upload of `index` (request subindex `sub`: 0 includes
/// subindex 0, 1 starts after it) into `out`; returns the byte count.
pub fn upload(
    store: &ObjectStore,
    index: u16,
    sub: u8,
    out: &mut [u8],
) -> Result<usize, SdoAbortCode> {
    let (_, obj) = object(index)?;
    if sub > 1 {
        return Err(SdoAbortCode::CompleteAccessNotSupported);
    }
    let elements = (obj.code == ObjectCode::Array)
        .then(|| store.get(index, 0).unwrap_or(0).clamp(0, 255) as u8);
    let mut bit = 0u16;
    let mut buf = [0u8; MAX_COMPLETE];
    for (flat, e) in members(index, obj, sub == 0, elements) {
        if !e.gap {
            if !e.access.readable() {
                return Err(SdoAbortCode::WriteOnly);
            }
            if e.data_type == DataType::VisibleString {
                return Err(SdoAbortCode::CompleteAccessNotSupported);
            }
            let bits = e.bit_len.min(64) as u8;
            write_bits(&mut buf, bit, bits, store.value(flat) as u64);
        }
        bit = bit
            .checked_add(bit_size(e))
            .ok_or(SdoAbortCode::ObjectTooLong)?;
    }
    let n = usize::from(bit).div_ceil(8);
    let (Some(dst), Some(src)) = (out.get_mut(..n), buf.get(..n)) else {
        return Err(SdoAbortCode::ObjectTooLong);
    };
    dst.copy_from_slice(src);
    Ok(n)
}

/// Values a complete download would store: `(flat, value)` pairs, checked
/// but not yet applied (all or nothing).
pub type Changes = heapless::Vec<(usize, i64), MAX_ENTRIES>;

/// Checks a complete download of `data` into `index` in AL state `state`
/// and returns the changes to apply. Read-only entries must be written with
/// their current value (0x06010002 otherwise); arrays take their element
/// count from the data.
pub fn check_download(
    store: &ObjectStore,
    index: u16,
    sub: u8,
    data: &[u8],
    state: AlState,
) -> Result<Changes, SdoAbortCode> {
    let (_, obj) = object(index)?;
    if sub > 1 {
        return Err(SdoAbortCode::CompleteAccessNotSupported);
    }
    let with_sub0 = sub == 0;
    let elements = if obj.code == ObjectCode::Array {
        let count = if with_sub0 {
            i64::from(*data.first().ok_or(SdoAbortCode::LengthTooLow)?)
        } else {
            store.get(index, 0).unwrap_or(0)
        };
        if count > i64::from(obj.max_sub()) {
            return Err(SdoAbortCode::ValueTooHigh);
        }
        Some(count.clamp(0, 255) as u8)
    } else {
        None
    };
    let total: usize = members(index, obj, with_sub0, elements)
        .map(|(_, e)| usize::from(bit_size(e)))
        .sum();
    match total.div_ceil(8).cmp(&data.len()) {
        core::cmp::Ordering::Greater => return Err(SdoAbortCode::LengthTooLow),
        core::cmp::Ordering::Less => return Err(SdoAbortCode::LengthTooHigh),
        core::cmp::Ordering::Equal => {}
    }
    let mut bit = 0u16;
    let mut changes = Changes::new();
    for (flat, e) in members(index, obj, with_sub0, elements) {
        let size = bit_size(e);
        let value_bits = if e.sub == 0 {
            8
        } else {
            e.bit_len.min(64) as u8
        };
        if usize::from(bit) + usize::from(size) > data.len() * 8 {
            return Err(SdoAbortCode::LengthTooLow);
        }
        let raw = read_bits(data, bit, value_bits);
        bit += size;
        if e.gap {
            continue;
        }
        let current = store.value(flat);
        if e.access == Access::Ro {
            if raw as i64 != current {
                return Err(SdoAbortCode::ReadOnly);
            }
            continue;
        }
        let n = byte_len(e);
        let bytes = raw.to_le_bytes();
        let value = ObjectStore::check(e, bytes.get(..n).unwrap_or(&[]), state)?;
        changes
            .push((flat, value))
            .map_err(|_| SdoAbortCode::ObjectTooLong)?;
    }
    Ok(changes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_object_uploads_42_points_after_a_padded_subindex_0() {
        let s = ObjectStore::new();
        let mut out = [0u8; 128];
        let n = upload(&s, 0x8006, 0, &mut out).unwrap();
        assert_eq!(n, 2 + 42 * 2);
        assert_eq!(out[0], 42);
        assert_eq!(out[1], 0, "padding byte");
        assert_eq!(i16::from_le_bytes([out[2], out[3]]), -10000);
        assert_eq!(i16::from_le_bytes([out[84], out[85]]), 10000);
        let n = upload(&s, 0x8006, 1, &mut out).unwrap();
        assert_eq!(n, 84);
    }

    #[test]
    fn record_with_bit_fields_packs_gaps_as_zero_bits() {
        let mut s = ObjectStore::new();
        s.set(0x800A, 1, 1); // CCMODE ON (3 bits) + 5-bit gap
        s.set(0x800A, 3, 1); // MMTYPE LIN
        let mut out = [0u8; 64];
        let n = upload(&s, 0x800A, 1, &mut out).unwrap();
        // 3+5, 3+5, then TRIGGER, MIN:A, MAX:A, MIN:B, MAX:B (5 x 16 bits).
        assert_eq!(n, 2 + 10);
        assert_eq!(out[0], 0x01);
        assert_eq!(out[1], 0x01);
        assert_eq!(u16::from_le_bytes([out[2], out[3]]), 200);
    }

    #[test]
    fn complete_download_of_the_curve_round_trips_and_is_all_or_nothing() {
        let mut s = ObjectStore::new();
        let mut img = [0u8; 86];
        img[0] = 42;
        for i in 0..42 {
            let v = (i as i16 - 21) * 100;
            img[2 + 2 * i..4 + 2 * i].copy_from_slice(&v.to_le_bytes());
        }
        let changes = check_download(&s, 0x8006, 0, &img, AlState::Op).unwrap();
        assert_eq!(changes.len(), 42);
        for (f, v) in &changes {
            s.set_value(*f, *v);
        }
        assert_eq!(s.get(0x8006, 1), Some(-2100));
        // One point out of range: nothing is applied.
        img[2..4].copy_from_slice(&(-20000i16).to_le_bytes());
        assert_eq!(
            check_download(&s, 0x8006, 0, &img, AlState::Op),
            Err(SdoAbortCode::ValueTooLow)
        );
        // Wrong length.
        assert_eq!(
            check_download(&s, 0x8006, 0, &img[..85], AlState::Op),
            Err(SdoAbortCode::LengthTooLow)
        );
        let mut long = [0u8; 90];
        long[..86].copy_from_slice(&img);
        long[2..4].copy_from_slice(&0i16.to_le_bytes());
        assert_eq!(
            check_download(&s, 0x8006, 0, &long, AlState::Op),
            Err(SdoAbortCode::LengthTooHigh)
        );
    }

    #[test]
    fn pdo_assignment_array_is_written_whole_only_in_preop() {
        let s = ObjectStore::new();
        let img = [2u8, 0, 0x00, 0x1A, 0x02, 0x1A];
        let c = check_download(&s, 0x1C13, 0, &img, AlState::PreOp).unwrap();
        assert_eq!(c.len(), 3);
        assert_eq!(
            check_download(&s, 0x1C13, 0, &img, AlState::SafeOp),
            Err(SdoAbortCode::InvalidState)
        );
        let too_many = [3u8, 0, 0, 0x1A, 2, 0x1A, 3, 0x1A];
        assert_eq!(
            check_download(&s, 0x1C13, 0, &too_many, AlState::PreOp),
            Err(SdoAbortCode::ValueTooHigh)
        );
    }

    #[test]
    fn read_only_members_must_keep_their_value() {
        let s = ObjectStore::new();
        let mut out = [0u8; 32];
        let n = upload(&s, 0x1018, 0, &mut out).unwrap();
        assert_eq!(n, 2 + 16);
        assert_eq!(
            check_download(&s, 0x1018, 0, &out[..n], AlState::PreOp).map(|c| c.len()),
            Ok(0)
        );
        out[2] ^= 1;
        assert_eq!(
            check_download(&s, 0x1018, 0, &out[..n], AlState::PreOp),
            Err(SdoAbortCode::ReadOnly)
        );
    }

    #[test]
    fn variables_and_write_only_members_refuse_complete_access() {
        let s = ObjectStore::new();
        let mut out = [0u8; 32];
        assert_eq!(
            upload(&s, 0x1000, 0, &mut out),
            Err(SdoAbortCode::CompleteAccessNotSupported)
        );
        assert_eq!(
            upload(&s, 0xF801, 0, &mut out),
            Err(SdoAbortCode::WriteOnly)
        );
        assert_eq!(
            upload(&s, 0x1234, 0, &mut out),
            Err(SdoAbortCode::ObjectNotFound)
        );
        assert_eq!(
            upload(&s, 0x8006, 5, &mut out),
            Err(SdoAbortCode::CompleteAccessNotSupported)
        );
    }
}
