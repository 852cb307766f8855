//! PDO assignment, mapping and the process image.
//!
//! A [`ProcessImage`] is computed from the assignment object (0x1C12 for
//! outputs, 0x1C13 for inputs) and the mapping objects it names, as the live
//! object dictionary holds them. It packs entry values into the SyncManager
//! buffer at bit granularity (inputs) and unpacks the buffer into entries
//! (outputs) with [`write_bits`] and [`read_bits`].

use crate::od::Dictionary;
use crate::od::store::Od;
use crate::od::types::PdoMapping;

pub use crate::od::bits::{read_bits, write_bits};

/// One PDO assignment the device offers: the RxPDOs for SM2 and the TxPDOs
/// for SM3 that belong together (the ESI's `AlternativeSmMapping`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoSet {
    /// Name of the assignment (shown by configurators).
    pub name: &'static str,
    /// RxPDO mapping objects (0x1600..0x17FF), in assignment order.
    pub rx: &'static [u16],
    /// TxPDO mapping objects (0x1A00..0x1BFF), in assignment order.
    pub tx: &'static [u16],
}

/// The device's process data: its PDO sets, the first being the default
/// assignment (the defaults of 0x1C12/0x1C13). An assignment written by a
/// master must be made of PDOs of one set; PDOs that share no set exclude
/// each other in the ESI.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProcessData {
    /// The PDO sets; empty for a device without process data.
    pub sets: &'static [PdoSet],
}

/// Most mapped entries (padding included) of one direction: 48 in a
/// firmware build; a host build (feature `std`), which simulates devices
/// described by any vendor's ESI (twins of 8-channel time-stamp terminals
/// map 280), allows 320.
#[cfg(not(feature = "std"))]
pub const MAX_MAPPED: usize = 48;
/// Most mapped entries (padding included) of one direction (see the
/// firmware build's value).
#[cfg(feature = "std")]
pub const MAX_MAPPED: usize = 320;
/// Largest process image of one direction in bytes: 128 in a firmware
/// build, 512 in a host build (feature `std`, twins of large devices).
#[cfg(not(feature = "std"))]
pub const MAX_IMAGE: usize = 128;
/// Largest process image of one direction in bytes (see the firmware
/// build's value).
#[cfg(feature = "std")]
pub const MAX_IMAGE: usize = 512;
/// Bytes the default memory layout leaves for the outputs before the
/// inputs (`MemoryLayout::new`), the same in every build.
pub const DEFAULT_OUTPUT_AREA: usize = 128;

/// Which process image: outputs (RxPDOs, 0x1C12) or inputs (TxPDOs, 0x1C13).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Master to slave: RxPDOs, assigned in 0x1C12, SM2.
    Outputs,
    /// Slave to master: TxPDOs, assigned in 0x1C13, SM3.
    Inputs,
}

impl Direction {
    /// The assignment object.
    pub const fn assign_index(self) -> u16 {
        match self {
            Direction::Outputs => 0x1C12,
            Direction::Inputs => 0x1C13,
        }
    }
    /// The PDO mapping objects' index range.
    pub const fn pdo_range(self) -> (u16, u16) {
        match self {
            Direction::Outputs => (0x1600, 0x17FF),
            Direction::Inputs => (0x1A00, 0x1BFF),
        }
    }
    const fn mapping(self) -> PdoMapping {
        match self {
            Direction::Outputs => PdoMapping::Rx,
            Direction::Inputs => PdoMapping::Tx,
        }
    }
}

/// Why an assignment or mapping cannot form a process image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PdoError {
    /// The assignment names an object that is not a PDO of this direction.
    #[error("assigned PDO {0:#06x} does not exist")]
    UnknownPdo(u16),
    /// A mapping entry names an entry that does not exist or may not be
    /// mapped in this direction.
    #[error("PDO {pdo:#06x} maps {mapping:#010x}, which is not mappable")]
    InvalidMapping {
        /// The PDO.
        pdo: u16,
        /// The mapping value.
        mapping: u32,
    },
    /// The assignment mixes PDOs that belong to no common PDO set.
    #[error("PDOs {0:#06x} and {1:#06x} belong to no common PDO set")]
    MixedSets(u16, u16),
    /// More entries or bytes than the image can hold.
    #[error("process image too large")]
    TooLarge,
}

/// One mapped entry: where its bits go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MappedEntry {
    /// Flat entry position in the store, `None` for padding.
    pub flat: Option<u16>,
    /// Bit offset in the image.
    pub bit_offset: u16,
    /// Bit length.
    pub bit_len: u8,
}

/// The SII PDO flags (ETG.2010 Table 14) of the PDO whose mapping object is
/// `pdo`, as the ESI states them with its attributes: fixed content
/// (`Fixed="1"`, [`crate::sii::pdo_flags::FIXED_CONTENT`]) when no entry of
/// the mapping object can be written, i.e. the master cannot change what
/// the PDO carries. The SII encoder and the ESI generator both call this,
/// so the two files cannot disagree on a flag.
pub fn sii_flags(dict: &Dictionary, pdo: u16) -> u16 {
    let Some((_, o)) = dict.find(pdo) else {
        return 0;
    };
    if o.entries.iter().any(|e| e.access().writable()) {
        0
    } else {
        crate::sii::pdo_flags::FIXED_CONTENT
    }
}

/// Whether `mapping` (`index << 16 | sub << 8 | bits`) may stand in a PDO
/// of direction `dir` of `dict`: padding (index 0, 1 to 64 bits), or an
/// entry that exists, is no gap, may be mapped in that direction and has
/// exactly `bits` bits; else 0x06040041 (the object cannot be mapped).
pub fn check_mapping_value(
    dict: &Dictionary,
    dir: Direction,
    mapping: u32,
) -> Result<(), crate::wire::coe::SdoAbortCode> {
    let index = (mapping >> 16) as u16;
    let sub = ((mapping >> 8) & 0xFF) as u8;
    let bits = (mapping & 0xFF) as u8;
    let ok = if index == 0 {
        (1..=64).contains(&bits)
    } else {
        dict.find_entry(index, sub).is_some_and(|(_, e)| {
            e.pdo().allows(dir.mapping()) && !e.gap() && e.bit_len == u16::from(bits) && bits != 0
        })
    };
    if ok {
        Ok(())
    } else {
        Err(crate::wire::coe::SdoAbortCode::CannotMap)
    }
}

/// Bit mask of the PDO sets (of `pd`) that contain `pdo`.
pub fn sets_of(pd: &ProcessData, pdo: u16) -> u32 {
    let mut mask = 0u32;
    for (n, set) in pd.sets.iter().enumerate().take(32) {
        if set.rx.contains(&pdo) || set.tx.contains(&pdo) {
            mask |= 1 << n;
        }
    }
    mask
}

/// Writes PDO set `set` of `pd` into the assignment objects 0x1C12 and
/// 0x1C13 (count and PDOs), as a device does when its configuration selects
/// another set. Returns `false` for a set that does not exist.
pub fn assign_set(od: &mut Od, pd: &ProcessData, set: usize) -> bool {
    let Some(s) = pd.sets.get(set) else {
        return false;
    };
    for (index, list) in [(0x1C12u16, s.rx), (0x1C13, s.tx)] {
        od.set(index, 0, list.len() as i64);
        for (i, pdo) in list.iter().enumerate() {
            od.set(index, (i + 1) as u8, i64::from(*pdo));
        }
    }
    true
}

/// The process image of one direction: at most `N` mapped entries
/// (padding included; a firmware sizes it for its device).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProcessImage<const N: usize = MAX_MAPPED> {
    entries: heapless::Vec<MappedEntry, N>,
    bits: u16,
    /// The PDO sets every assigned PDO belongs to (bit n: set n).
    sets: u32,
}

impl<const N: usize> Default for ProcessImage<N> {
    fn default() -> Self {
        ProcessImage {
            entries: heapless::Vec::new(),
            bits: 0,
            sets: u32::MAX,
        }
    }
}

impl<const N: usize> ProcessImage<N> {
    /// Builds the image from the assignment and mapping objects in `store`;
    /// the assigned PDOs must share a PDO set of `pd` (when the device
    /// declares sets).
    pub fn build(store: &Od, dir: Direction, pd: &ProcessData) -> Result<Self, PdoError> {
        let mut image = ProcessImage::default();
        image.rebuild(store, dir, pd)?;
        Ok(image)
    }

    /// [`ProcessImage::build`] into this image, in place (a firmware keeps
    /// its images where they live: built by value, each was copied a few
    /// times on the stack). On an error the image is left empty.
    pub fn rebuild(
        &mut self,
        store: &Od,
        dir: Direction,
        pd: &ProcessData,
    ) -> Result<(), PdoError> {
        self.clear();
        let result = self.fill(store, dir, pd);
        if result.is_err() {
            self.clear();
        }
        result
    }

    /// Empty, as [`ProcessImage::default`], in place.
    pub fn clear(&mut self) {
        self.entries.clear();
        self.bits = 0;
        self.sets = u32::MAX;
    }

    fn fill(&mut self, store: &Od, dir: Direction, pd: &ProcessData) -> Result<(), PdoError> {
        let assign = dir.assign_index();
        let count = store.get(assign, 0).unwrap_or(0);
        let image = self;
        let (lo, hi) = dir.pdo_range();
        let dict = store.dictionary();
        for i in 1..=count.clamp(0, 254) as u8 {
            let pdo = store.get(assign, i).unwrap_or(0) as u16;
            if pdo < lo || pdo > hi || dict.find(pdo).is_none() {
                return Err(PdoError::UnknownPdo(pdo));
            }
            if !pd.sets.is_empty() {
                let mask = sets_of(pd, pdo);
                if image.sets & mask == 0 {
                    let first = store.get(assign, 1).unwrap_or(0) as u16;
                    return Err(PdoError::MixedSets(first, pdo));
                }
                image.sets &= mask;
            }
            let n = store.get(pdo, 0).unwrap_or(0);
            for s in 1..=n.clamp(0, 254) as u8 {
                let mapping = store.get(pdo, s).unwrap_or(0) as u32;
                image.push_mapping(dict, pdo, mapping, dir)?;
            }
        }
        Ok(())
    }

    fn push_mapping(
        &mut self,
        dict: &Dictionary,
        pdo: u16,
        mapping: u32,
        dir: Direction,
    ) -> Result<(), PdoError> {
        let index = (mapping >> 16) as u16;
        let sub = ((mapping >> 8) & 0xFF) as u8;
        let bits = (mapping & 0xFF) as u8;
        let invalid = PdoError::InvalidMapping { pdo, mapping };
        let flat = if index == 0 {
            None
        } else {
            let (flat, e) = dict.find_entry(index, sub).ok_or(invalid)?;
            if !e.pdo().allows(dir.mapping()) || e.bit_len != u16::from(bits) || e.gap() {
                return Err(invalid);
            }
            Some(u16::try_from(flat).map_err(|_| PdoError::TooLarge)?)
        };
        if bits == 0 {
            return Err(invalid);
        }
        let entry = MappedEntry {
            flat,
            bit_offset: self.bits,
            bit_len: bits,
        };
        self.entries.push(entry).map_err(|_| PdoError::TooLarge)?;
        self.bits = self
            .bits
            .checked_add(u16::from(bits))
            .filter(|b| usize::from(*b) <= MAX_IMAGE * 8)
            .ok_or(PdoError::TooLarge)?;
        Ok(())
    }

    /// Image size in bits.
    pub fn bit_len(&self) -> u16 {
        self.bits
    }

    /// Image size in bytes (what the SyncManager length must be).
    pub fn byte_len(&self) -> usize {
        usize::from(self.bits).div_ceil(8)
    }

    /// The PDO sets every assigned PDO belongs to (bit n: set n; all bits
    /// when nothing is assigned or the device declares no sets).
    pub fn sets(&self) -> u32 {
        self.sets
    }

    /// The mapped entries in image order.
    pub fn entries(&self) -> &[MappedEntry] {
        &self.entries
    }

    /// Packs the mapped entries' values into `out` (inputs).
    pub fn pack(&self, store: &Od, out: &mut [u8]) {
        for e in &self.entries {
            if e.bit_len > 64
                && let Some(f) = e.flat
            {
                // A byte-area entry (an array held as one value).
                let mut bytes = [0u8; 32];
                let n = store.area_bytes(usize::from(f), &mut bytes).unwrap_or(0);
                for (i, b) in bytes.iter().take(n).enumerate() {
                    let at = e.bit_offset.saturating_add(8 * i as u16);
                    write_bits(out, at, 8, u64::from(*b));
                }
                continue;
            }
            let v = e.flat.map_or(0, |f| store.value(usize::from(f))) as u64;
            write_bits(out, e.bit_offset, e.bit_len.min(64), v);
        }
    }

    /// Unpacks `data` into the mapped entries (outputs), sign-extending
    /// signed types.
    pub fn unpack(&self, store: &mut Od, data: &[u8]) {
        let dict = store.dictionary();
        for e in &self.entries {
            let Some(f) = e.flat else { continue };
            if e.bit_len > 64 {
                let mut bytes = [0u8; 32];
                let n = usize::from(e.bit_len).div_ceil(8).min(bytes.len());
                for (i, b) in bytes.iter_mut().take(n).enumerate() {
                    let at = e.bit_offset.saturating_add(8 * i as u16);
                    *b = read_bits(data, at, 8) as u8;
                }
                store.set_area_bytes(usize::from(f), bytes.get(..n).unwrap_or(&[]));
                continue;
            }
            let raw = read_bits(data, e.bit_offset, e.bit_len);
            let v = dict
                .entry_at(usize::from(f))
                .map_or(raw as i64, |en| crate::od::store::from_raw(en, raw));
            store.set_value(usize::from(f), v);
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::al::AlState;
    use crate::testing::{DEVICE, store};
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2048))]

        /// `write_bits` / `read_bits` agree with a per-bit model (LSB first,
        /// little-endian, cut at the buffer's end) for any field of up to
        /// 64 bits at any offset, and leave every other bit alone.
        #[test]
        fn bit_helpers_match_a_per_bit_model(
            mut buf in prop::collection::vec(any::<u8>(), 0..12),
            offset in 0u16..104,
            len in 0u8..=64,
            v in any::<u64>(),
        ) {
            let bits = buf.len() * 8;
            let get = |b: &[u8], i: usize| b[i / 8] >> (i % 8) & 1;
            let mut want = buf.clone();
            let mut want_read = 0u64;
            for i in 0..usize::from(len) {
                let at = usize::from(offset) + i;
                if at >= bits {
                    break;
                }
                want_read |= u64::from(get(&buf, at)) << i;
                let m = 1u8 << (at % 8);
                want[at / 8] = if (v >> i) & 1 != 0 { want[at / 8] | m } else { want[at / 8] & !m };
            }
            prop_assert_eq!(read_bits(&buf, offset, len), want_read);
            write_bits(&mut buf, offset, len, v);
            prop_assert_eq!(&buf, &want);
        }
    }

    #[test]
    fn the_default_set_gives_3_byte_images_and_unpacks_signed_values() {
        let mut s = store();
        let pd = &DEVICE.process_data;
        let out = <ProcessImage>::build(&s, Direction::Outputs, pd).unwrap();
        let inp = <ProcessImage>::build(&s, Direction::Inputs, pd).unwrap();
        assert_eq!((out.byte_len(), inp.byte_len()), (3, 3));
        assert_eq!(out.sets(), 0b01);
        out.unpack(&mut s, &[1, 0xFE, 0xFF]);
        assert_eq!((s.get(0x7000, 1), s.get(0x7000, 3)), (Some(1), Some(-2)));
        s.set(0x6000, 3, 0x1234);
        let mut buf = [0u8; 3];
        inp.pack(&s, &mut buf);
        assert_eq!(buf, [0, 0x34, 0x12]);
    }

    #[test]
    fn pdos_of_no_common_set_are_refused() {
        let mut s = store();
        s.download(0x1C13, 0, &[2], AlState::PreOp).unwrap();
        s.download(0x1C13, 2, &0x1A01u16.to_le_bytes(), AlState::PreOp)
            .unwrap();
        assert_eq!(
            <ProcessImage>::build(&s, Direction::Inputs, &DEVICE.process_data),
            Err(PdoError::MixedSets(0x1A00, 0x1A01))
        );
        s.set(0x1C12, 1, 0x1234);
        assert_eq!(
            <ProcessImage>::build(&s, Direction::Outputs, &DEVICE.process_data),
            Err(PdoError::UnknownPdo(0x1234))
        );
    }

    #[test]
    fn a_rebuild_in_place_that_fails_leaves_the_image_empty() {
        let mut s = store();
        let mut image = <ProcessImage>::build(&s, Direction::Inputs, &DEVICE.process_data).unwrap();
        assert!(image.byte_len() > 0);
        s.download(0x1C13, 0, &[2], AlState::PreOp).unwrap();
        s.download(0x1C13, 2, &0x1A01u16.to_le_bytes(), AlState::PreOp)
            .unwrap();
        assert_eq!(
            image.rebuild(&s, Direction::Inputs, &DEVICE.process_data),
            Err(PdoError::MixedSets(0x1A00, 0x1A01))
        );
        assert_eq!(
            image,
            ProcessImage::default(),
            "nothing of a half-built image"
        );
        s.download(0x1C13, 0, &[1], AlState::PreOp).unwrap();
        image
            .rebuild(&s, Direction::Inputs, &DEVICE.process_data)
            .unwrap();
        assert_eq!(
            image,
            <ProcessImage>::build(&s, Direction::Inputs, &DEVICE.process_data).unwrap(),
            "in place or by value: the same image"
        );
    }

    #[test]
    fn assign_set_writes_the_assignment_objects() {
        let mut s = store();
        assert!(assign_set(&mut s, &DEVICE.process_data, 1));
        assert_eq!(
            (s.get(0x1C12, 1), s.get(0x1C13, 1)),
            (Some(0x1601), Some(0x1A01))
        );
        let out = <ProcessImage>::build(&s, Direction::Outputs, &DEVICE.process_data).unwrap();
        assert_eq!((out.byte_len(), out.sets()), (4, 0b10));
        assert!(!assign_set(&mut s, &DEVICE.process_data, 2));
        assert_eq!(sets_of(&DEVICE.process_data, 0x1A00), 0b01);
        assert_eq!(
            sii_flags(&crate::testing::DICT, 0x1600),
            crate::sii::pdo_flags::FIXED_CONTENT
        );
    }

    #[test]
    fn bit_helpers_round_trip_unaligned_values() {
        let mut buf = [0u8; 4];
        write_bits(&mut buf, 3, 11, 0x5A5);
        assert_eq!(read_bits(&buf, 3, 11), 0x5A5);
        write_bits(&mut buf, 8, 16, 0xBEEF);
        assert_eq!(read_bits(&buf, 8, 16), 0xBEEF);
        // Past the end: no panic, the bits inside are written, the rest
        // dropped and read as 0.
        write_bits(&mut buf, 30, 8, 0xFF);
        assert_eq!(buf[3] >> 6, 0b11);
        assert_eq!(read_bits(&buf, 30, 8), 0b11);
        write_bits(&mut buf, 40, 8, 0xFF);
        assert_eq!(read_bits(&buf, 40, 8), 0);
        // Up to 64 bits at any offset, little-endian.
        let mut wide = [0u8; 10];
        write_bits(&mut wide, 5, 64, 0x8123_4567_89AB_CDEF);
        assert_eq!(read_bits(&wide, 5, 64), 0x8123_4567_89AB_CDEF);
        assert_eq!(wide[0], 0xEF << 5);
    }
}
