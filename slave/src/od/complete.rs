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

use super::bits::{read_bits, write_bits};
use super::store::{Od, byte_len, from_raw};
use super::types::{Access, DataType, Entry, Object, ObjectCode};
use crate::al::AlState;
use crate::wire::coe::SdoAbortCode;

/// Largest complete-access image handled.
pub const MAX_COMPLETE: usize = 256;

fn object(od: &Od, index: u16) -> Result<(usize, &'static Object), SdoAbortCode> {
    let (pos, obj) = od
        .dictionary()
        .find(index)
        .ok_or(SdoAbortCode::ObjectNotFound)?;
    if obj.code == ObjectCode::Var {
        return Err(SdoAbortCode::CompleteAccessNotSupported);
    }
    Ok((pos, obj))
}

/// Which entries take part: `(flat, entry)` from the first subindex on.
fn members(
    od: &Od,
    pos: usize,
    obj: &'static Object,
    with_sub0: bool,
    elements: Option<u8>,
) -> impl Iterator<Item = (usize, &'static Entry)> {
    let start = if with_sub0 { 0 } else { 1 };
    let base = od.dictionary().base(pos).unwrap_or(0);
    obj.entries
        .iter()
        .enumerate()
        .filter(move |(_, e)| e.sub >= start && elements.is_none_or(|n| e.sub <= n))
        .map(move |(i, e)| (base + i, e))
}

fn bit_size(e: &Entry) -> u16 {
    if e.sub == 0 { 16 } else { e.bit_len }
}

/// Complete upload of `index` (request subindex `sub`: 0 includes
/// subindex 0, 1 starts after it) into `out`; returns the byte count.
pub fn upload(store: &Od, index: u16, sub: u8, out: &mut [u8]) -> Result<usize, SdoAbortCode> {
    let (pos, obj) = object(store, index)?;
    if sub > 1 {
        return Err(SdoAbortCode::CompleteAccessNotSupported);
    }
    let elements = (obj.code == ObjectCode::Array)
        .then(|| store.get(index, 0).unwrap_or(0).clamp(0, 255) as u8);
    let mut bit = 0u16;
    let mut buf = [0u8; MAX_COMPLETE];
    for (flat, e) in members(store, pos, obj, sub == 0, elements) {
        if !e.gap() {
            if !e.access().readable() {
                return Err(SdoAbortCode::WriteOnly);
            }
            if e.data_type == DataType::VisibleString {
                return Err(SdoAbortCode::CompleteAccessNotSupported);
            }
            if e.data_type.is_bytes() {
                // An octet string or array: its bytes in order.
                let mut bytes = [0u8; MAX_COMPLETE];
                let n = store
                    .area_bytes(flat, &mut bytes)
                    .ok_or(SdoAbortCode::ObjectTooLong)?;
                for (i, b) in bytes.iter().take(n).enumerate() {
                    let at = u16::try_from(i * 8)
                        .ok()
                        .and_then(|o| bit.checked_add(o))
                        .ok_or(SdoAbortCode::ObjectTooLong)?;
                    write_bits(&mut buf, at, 8, u64::from(*b));
                }
            } else {
                let bits = e.bit_len.min(64) as u8;
                write_bits(&mut buf, bit, bits, store.value(flat) as u64);
            }
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

/// The values a checked complete download stores: `(subindex, value)`
/// of every writable entry, in subindex order, decoded from the download's
/// image on each walk. No list is kept: on a microcontroller a list of
/// (u8, i64) pairs was the deepest stack frame of a poll (1 KiB), and the
/// decoding is a few shifts per entry. Read-only entries (checked equal
/// to what they hold) and gaps are left out.
#[derive(Debug, Clone, Copy)]
pub struct CompleteChanges<'a> {
    obj: &'static Object,
    with_sub0: bool,
    elements: Option<u8>,
    data: &'a [u8],
}

impl<'a> CompleteChanges<'a> {
    /// The `(subindex, value)` pairs, in subindex order.
    pub fn iter(&self) -> CompleteIter<'a> {
        CompleteIter {
            entries: self.obj.entries.iter(),
            with_sub0: self.with_sub0,
            elements: self.elements,
            data: self.data,
            bit: 0,
        }
    }
}

/// The walk of [`CompleteChanges::iter`].
#[derive(Debug, Clone)]
pub struct CompleteIter<'a> {
    entries: core::slice::Iter<'static, Entry>,
    with_sub0: bool,
    elements: Option<u8>,
    data: &'a [u8],
    bit: u16,
}

impl Iterator for CompleteIter<'_> {
    type Item = (u8, i64);

    fn next(&mut self) -> Option<(u8, i64)> {
        let start = if self.with_sub0 { 0 } else { 1 };
        for e in self.entries.by_ref() {
            if e.sub < start || self.elements.is_some_and(|n| e.sub > n) {
                continue;
            }
            let at = self.bit;
            self.bit = self.bit.saturating_add(bit_size(e));
            if e.gap() || e.access() == Access::Ro || e.data_type.is_bytes() {
                continue;
            }
            let raw = read_bits(self.data, at, value_bits(e));
            return Some((e.sub, from_raw(e, raw)));
        }
        None
    }
}

/// Bits of an entry's value in the image (subindex 0 is a UINT8 in 16).
fn value_bits(e: &Entry) -> u8 {
    if e.sub == 0 {
        8
    } else {
        e.bit_len.min(64) as u8
    }
}

/// Checks a complete download of `data` into `index` in AL state `state`
/// and returns the changes it makes (all or nothing: nothing is applied
/// here). Read-only entries must be written with their current value
/// (0x06010002 otherwise); arrays take their element count from the data.
pub fn check_download<'a>(
    store: &Od,
    index: u16,
    sub: u8,
    data: &'a [u8],
    state: AlState,
) -> Result<CompleteChanges<'a>, SdoAbortCode> {
    let (pos, obj) = object(store, index)?;
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
    let total: usize = members(store, pos, obj, with_sub0, elements)
        .map(|(_, e)| usize::from(bit_size(e)))
        .sum();
    match total.div_ceil(8).cmp(&data.len()) {
        core::cmp::Ordering::Greater => return Err(SdoAbortCode::LengthTooLow),
        core::cmp::Ordering::Less => return Err(SdoAbortCode::LengthTooHigh),
        core::cmp::Ordering::Equal => {}
    }
    let mut bit = 0u16;
    for (flat, e) in members(store, pos, obj, with_sub0, elements) {
        let size = bit_size(e);
        if usize::from(bit) + usize::from(size) > data.len() * 8 {
            return Err(SdoAbortCode::LengthTooLow);
        }
        let raw = read_bits(data, bit, value_bits(e));
        bit += size;
        if e.gap() {
            continue;
        }
        if e.data_type.is_bytes() {
            return Err(SdoAbortCode::CompleteAccessNotSupported);
        }
        let current = store.value(flat);
        if e.access() == Access::Ro {
            // The store holds signed values sign-extended; the raw bits
            // are zero-extended.
            if from_raw(e, raw) != current {
                return Err(SdoAbortCode::ReadOnly);
            }
            continue;
        }
        let n = byte_len(e);
        let bytes = raw.to_le_bytes();
        // The value the walk of `CompleteChanges` decodes again (the same
        // `from_raw` of the same bits).
        store.check(e, bytes.get(..n).unwrap_or(&[]), state)?;
    }
    Ok(CompleteChanges {
        obj,
        with_sub0,
        elements,
        data,
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)]
mod tests {
    use super::*;

    /// [`check_download`] returning its changes as a list.
    fn check(
        store: &Od,
        index: u16,
        sub: u8,
        data: &[u8],
        state: AlState,
    ) -> Result<Vec<(u8, i64)>, SdoAbortCode> {
        check_download(store, index, sub, data, state).map(|c| c.iter().collect())
    }
    use crate::testing::store;

    #[test]
    fn a_record_with_a_gap_packs_it_as_zero_bits() {
        let mut s = store();
        s.set(0x7000, 1, 1);
        s.set(0x7000, 3, -2);
        let mut out = [0u8; 16];
        // SubIndex 0 (16 bits), Enable (1) + gap (7), Value (16).
        assert_eq!(upload(&s, 0x7000, 0, &mut out), Ok(5));
        assert_eq!(&out[..5], &[3, 0, 0x01, 0xFE, 0xFF]);
        assert_eq!(upload(&s, 0x7000, 1, &mut out), Ok(3));
    }

    #[test]
    fn an_array_downloads_whole_and_all_or_nothing() {
        let s = store();
        let img = [4u8, 0, 1, 0, 2, 0, 3, 0, 4, 0];
        let c = check(&s, 0x8001, 0, &img, AlState::Op).unwrap();
        assert_eq!(c.len(), 4);
        let mut bad = img;
        bad[2..4].copy_from_slice(&2000i16.to_le_bytes());
        assert_eq!(
            check(&s, 0x8001, 0, &bad, AlState::Op),
            Err(SdoAbortCode::ValueTooHigh)
        );
        assert_eq!(
            check(&s, 0x8001, 0, &img[..9], AlState::Op),
            Err(SdoAbortCode::LengthTooLow)
        );
    }

    mod signed {
        use crate::od::build::{constant, ranged, sub0};
        use crate::od::{DataType, Limits, Object, ObjectCode};

        /// A record with a read-only signed member holding a negative value.
        #[rustfmt::skip]
        pub const OBJECTS: &[Object] = &[
            Object { index: 0x8000, name: "Calibration", code: ObjectCode::Record, entries: &[
                sub0(2),
                constant(1, "Factory offset", DataType::Int16, -300),
                ranged(2, "Gain", DataType::Int32, -7, &Limits::range(-1000, 1000, "")),
            ] },
        ];

        crate::dictionary!(pub DICT, pub ENTRIES = OBJECTS, &[]);
    }

    #[test]
    fn a_record_with_a_negative_read_only_member_downloads_back_what_it_uploaded() {
        let s = crate::od::ObjectStore::<[i64; signed::ENTRIES]>::new(&signed::DICT);
        let mut out = [0u8; 16];
        let n = upload(&s, 0x8000, 0, &mut out).unwrap();
        assert_eq!(&out[..n], &[2, 0, 0xD4, 0xFE, 0xF9, 0xFF, 0xFF, 0xFF]);
        let c = check(&s, 0x8000, 0, &out[..n], AlState::PreOp).unwrap();
        assert_eq!(c.as_slice(), &[(2, -7)], "only the RW member is written");
        out[2] ^= 1;
        assert_eq!(
            check(&s, 0x8000, 0, &out[..n], AlState::PreOp),
            Err(SdoAbortCode::ReadOnly),
            "a changed RO member"
        );
    }

    mod wide {
        use crate::od::build::{setting, sub_name, sub0};
        use crate::od::{DataType, Entry, Limits, Object, ObjectCode};

        /// Subindex 0 (RW: an array's element count) and 100 UINT8
        /// elements.
        const fn elements() -> [Entry; 101] {
            const FIRST: Entry = sub0(100);
            let mut all = [FIRST; 101];
            all[0].flags = all[0].flags.with_access(crate::od::Access::Rw);
            let mut i = 1;
            while i < 101 {
                all[i] = setting(
                    i as u8,
                    sub_name(i as u8),
                    DataType::UInt8,
                    0,
                    &Limits::NONE,
                );
                i += 1;
            }
            all
        }

        const ENTRIES_100: [Entry; 101] = elements();

        pub const OBJECTS: &[Object] = &[Object {
            index: 0x8000,
            name: "Table",
            code: ObjectCode::Array,
            entries: &ENTRIES_100,
        }];

        crate::dictionary!(pub DICT, pub ENTRIES = OBJECTS, &[]);
    }

    #[test]
    fn a_complete_download_of_100_elements_changes_every_one_in_order() {
        // A list of changes held 64 pairs: this download was refused with
        // 0x06010005 before the changes were decoded from the image.
        let s = crate::od::ObjectStore::<[i64; wide::ENTRIES]>::new(&wide::DICT);
        let mut img = [0u8; 102];
        img[0] = 100;
        for (i, b) in img[2..].iter_mut().enumerate() {
            *b = i as u8 + 1;
        }
        let c = check(&s, 0x8000, 0, &img, AlState::PreOp).unwrap();
        assert_eq!(c.len(), 101);
        assert_eq!(c[0], (0, 100));
        assert!(
            c[1..]
                .iter()
                .enumerate()
                .all(|(i, &(sub, v))| { usize::from(sub) == i + 1 && v == i as i64 + 1 })
        );
    }

    #[test]
    fn read_only_members_must_keep_their_value_and_vars_refuse() {
        let s = store();
        let mut out = [0u8; 32];
        let n = upload(&s, 0x1018, 0, &mut out).unwrap();
        assert_eq!(
            check(&s, 0x1018, 0, &out[..n], AlState::PreOp).map(|c| c.len()),
            Ok(0)
        );
        out[2] ^= 1;
        assert_eq!(
            check(&s, 0x1018, 0, &out[..n], AlState::PreOp),
            Err(SdoAbortCode::ReadOnly)
        );
        assert_eq!(
            upload(&s, 0x1000, 0, &mut out),
            Err(SdoAbortCode::CompleteAccessNotSupported)
        );
        assert_eq!(
            upload(&s, 0x2000, 0, &mut out),
            Err(SdoAbortCode::ObjectNotFound)
        );
    }
}
