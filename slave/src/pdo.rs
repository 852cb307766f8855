//! PDO assignment, mapping and the process image (layer 4).
//!
//! A [`ProcessImage`] is computed from the assignment object (0x1C12 for
//! outputs, 0x1C13 for inputs) and the mapping objects it names, as the live
//! object dictionary holds them. It packs entry values into the SyncManager
//! buffer bit by bit (inputs) and unpacks the buffer into entries (outputs).

use crate::od::model;
use crate::od::store::ObjectStore;
use crate::od::types::PdoMapping;

/// Most mapped entries (padding included) of one direction.
pub const MAX_MAPPED: usize = 48;
/// Largest process image of one direction in bytes.
pub const MAX_IMAGE: usize = 128;

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
    /// The assignment mixes PDOs of the directional and independent modes.
    #[error("PDOs {0:#06x} and {1:#06x} belong to different modes")]
    MixedModes(u16, u16),
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

/// The PDO mode a PDO belongs to (manual 7.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PdoMode {
    /// Directional: 0x1600, 0x1A00, 0x1A02 (FUNCTION = DIR).
    Directional,
    /// Independent: 0x1601, 0x1A01, 0x1A03 (FUNCTION = IND).
    Independent,
}

/// The SII PDO flags (ETG.2010 Table 14) of the PDO whose mapping object is
/// `pdo`, as the ESI states them with its attributes: fixed content
/// (`Fixed="1"`, [`crate::sii::pdo_flags::FIXED_CONTENT`]) when no entry of
/// the mapping object can be written, i.e. the master cannot change what
/// the PDO carries. The SII encoder and the ESI generator both call this,
/// so the two files cannot disagree on a flag.
pub fn sii_flags(pdo: u16) -> u16 {
    let Some((_, o)) = crate::od::model::find(pdo) else {
        return 0;
    };
    if o.entries.iter().any(|e| e.access.writable()) {
        0
    } else {
        crate::sii::pdo_flags::FIXED_CONTENT
    }
}

/// The mode of a PDO index, if it is one of the device's PDOs.
pub const fn pdo_mode(pdo: u16) -> Option<PdoMode> {
    match pdo {
        0x1600 | 0x1A00 | 0x1A02 => Some(PdoMode::Directional),
        0x1601 | 0x1A01 | 0x1A03 => Some(PdoMode::Independent),
        _ => None,
    }
}

/// The process image of one direction.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ProcessImage {
    entries: heapless::Vec<MappedEntry, MAX_MAPPED>,
    bits: u16,
    mode: Option<PdoMode>,
}

impl ProcessImage {
    /// Builds the image from the assignment and mapping objects in `store`.
    pub fn build(store: &ObjectStore, dir: Direction) -> Result<Self, PdoError> {
        let assign = dir.assign_index();
        let count = store.get(assign, 0).unwrap_or(0);
        let mut image = ProcessImage::default();
        let (lo, hi) = dir.pdo_range();
        for i in 1..=count.clamp(0, 254) as u8 {
            let pdo = store.get(assign, i).unwrap_or(0) as u16;
            if pdo < lo || pdo > hi || model::find(pdo).is_none() {
                return Err(PdoError::UnknownPdo(pdo));
            }
            if let Some(m) = pdo_mode(pdo) {
                match image.mode {
                    Some(prev) if prev != m => {
                        let first = store.get(assign, 1).unwrap_or(0) as u16;
                        return Err(PdoError::MixedModes(first, pdo));
                    }
                    _ => image.mode = Some(m),
                }
            }
            let n = store.get(pdo, 0).unwrap_or(0);
            for s in 1..=n.clamp(0, 254) as u8 {
                let mapping = store.get(pdo, s).unwrap_or(0) as u32;
                image.push_mapping(pdo, mapping, dir)?;
            }
        }
        Ok(image)
    }

    fn push_mapping(&mut self, pdo: u16, mapping: u32, dir: Direction) -> Result<(), PdoError> {
        let index = (mapping >> 16) as u16;
        let sub = ((mapping >> 8) & 0xFF) as u8;
        let bits = (mapping & 0xFF) as u8;
        let invalid = PdoError::InvalidMapping { pdo, mapping };
        let flat = if index == 0 {
            None
        } else {
            let (flat, e) = model::find_entry(index, sub).ok_or(invalid)?;
            if e.pdo != dir.mapping() || e.bit_len != u16::from(bits) || e.gap {
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

    /// The mode the assigned PDOs belong to (`None` when nothing is assigned).
    pub fn mode(&self) -> Option<PdoMode> {
        self.mode
    }

    /// The mapped entries in image order.
    pub fn entries(&self) -> &[MappedEntry] {
        &self.entries
    }

    /// Packs the mapped entries' values into `out` (inputs).
    pub fn pack(&self, store: &ObjectStore, out: &mut [u8]) {
        for e in &self.entries {
            let v = e.flat.map_or(0, |f| store.value(usize::from(f))) as u64;
            write_bits(out, e.bit_offset, e.bit_len, v);
        }
    }

    /// Unpacks `data` into the mapped entries (outputs), sign-extending
    /// signed types.
    pub fn unpack(&self, store: &mut ObjectStore, data: &[u8]) {
        for e in &self.entries {
            let Some(f) = e.flat else { continue };
            let raw = read_bits(data, e.bit_offset, e.bit_len);
            let signed = model::entry_at(usize::from(f)).is_some_and(|en| en.data_type.is_signed());
            let v = if signed && e.bit_len < 64 && e.bit_len > 0 {
                let shift = 64 - u32::from(e.bit_len);
                ((raw << shift) as i64) >> shift
            } else {
                raw as i64
            };
            store.set_value(usize::from(f), v);
        }
    }
}

/// Writes the low `len` bits of `v` at bit `offset` of `buf` (LSB first).
pub fn write_bits(buf: &mut [u8], offset: u16, len: u8, v: u64) {
    if offset % 8 == 0 && len % 8 == 0 {
        let start = usize::from(offset / 8);
        let n = usize::from(len / 8);
        let bytes = v.to_le_bytes();
        if let (Some(dst), Some(src)) = (buf.get_mut(start..start + n), bytes.get(..n)) {
            dst.copy_from_slice(src);
        }
        return;
    }
    for i in 0..u16::from(len) {
        let bit = offset + i;
        let Some(b) = buf.get_mut(usize::from(bit / 8)) else {
            return;
        };
        let m = 1u8 << (bit % 8);
        if (v >> i) & 1 != 0 {
            *b |= m;
        } else {
            *b &= !m;
        }
    }
}

/// Reads `len` bits at bit `offset` of `buf` (LSB first).
pub fn read_bits(buf: &[u8], offset: u16, len: u8) -> u64 {
    let mut v = 0u64;
    for i in 0..u16::from(len.min(64)) {
        let bit = offset + i;
        let set = buf
            .get(usize::from(bit / 8))
            .is_some_and(|b| b & (1 << (bit % 8)) != 0);
        if set {
            v |= 1 << i;
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::al::AlState;

    #[test]
    fn default_directional_images_are_5_and_14_bytes() {
        let s = ObjectStore::new();
        let out = ProcessImage::build(&s, Direction::Outputs).unwrap();
        let inp = ProcessImage::build(&s, Direction::Inputs).unwrap();
        assert_eq!(out.byte_len(), 5);
        assert_eq!(inp.byte_len(), 14);
        assert_eq!(out.mode(), Some(PdoMode::Directional));
    }

    #[test]
    fn outputs_unpack_into_enable_and_command_value() {
        let mut s = ObjectStore::new();
        let out = ProcessImage::build(&s, Direction::Outputs).unwrap();
        let cmd: i32 = -5000;
        let mut data = [0u8; 5];
        data[0] = 1;
        data[1..5].copy_from_slice(&cmd.to_le_bytes());
        out.unpack(&mut s, &data);
        assert_eq!(s.get(0x7000, 1), Some(1));
        assert_eq!(s.get(0x7000, 3), Some(-5000));
    }

    #[test]
    fn inputs_pack_ia_at_byte_10() {
        let mut s = ObjectStore::new();
        s.set(0x6000, 6, 750);
        s.set(0x6000, 1, 1);
        let inp = ProcessImage::build(&s, Direction::Inputs).unwrap();
        let mut buf = [0u8; 14];
        inp.pack(&s, &mut buf);
        assert_eq!(buf[0], 1);
        // 0x1A00 is 4 bytes; 0x1A02 W, C, U, IA -> IA at 4 + 6.
        assert_eq!(u16::from_le_bytes([buf[10], buf[11]]), 750);
    }

    #[test]
    fn mixed_mode_assignment_is_refused() {
        let mut s = ObjectStore::new();
        s.download(0x1C13, 2, &0x1A03u16.to_le_bytes(), AlState::PreOp)
            .unwrap();
        assert_eq!(
            ProcessImage::build(&s, Direction::Inputs),
            Err(PdoError::MixedModes(0x1A00, 0x1A03))
        );
    }

    #[test]
    fn unknown_pdo_in_assignment_is_refused() {
        let mut s = ObjectStore::new();
        s.set(0x1C12, 1, 0x1234);
        assert_eq!(
            ProcessImage::build(&s, Direction::Outputs),
            Err(PdoError::UnknownPdo(0x1234))
        );
    }

    #[test]
    fn bit_helpers_round_trip_unaligned_values() {
        let mut buf = [0u8; 4];
        write_bits(&mut buf, 3, 5, 0b10110);
        assert_eq!(read_bits(&buf, 3, 5), 0b10110);
        write_bits(&mut buf, 8, 16, 0xBEEF);
        assert_eq!(read_bits(&buf, 8, 16), 0xBEEF);
        // Out of range is ignored, not a panic.
        write_bits(&mut buf, 30, 8, 0xFF);
        assert_eq!(read_bits(&buf, 40, 8), 0);
    }
}
