//! Live values of the object dictionary (layer 2).
//!
//! One slot per entry of [`super::model::OBJECTS`], indexed by the entry's
//! flat position. SDO access goes through [`ObjectStore::upload`] and
//! [`ObjectStore::download`], which apply the model's rules (existence,
//! access in the current state, length, range, enumeration members) and
//! answer with the CoE abort code a master expects.

use super::model::{self, ENTRY_COUNT};
use super::types::{Access, DataType, DefaultValue, Entry};
use crate::al::AlState;
use crate::wire::coe::SdoAbortCode;

/// Longest string value an entry can hold.
pub const STRING_CAPACITY: usize = 32;
/// Number of string entries the store can hold.
pub const STRING_SLOTS: usize = 4;

/// The live values of every entry.
#[derive(Debug, Clone)]
pub struct ObjectStore {
    values: [i64; ENTRY_COUNT],
    strings: heapless::Vec<(u16, heapless::String<STRING_CAPACITY>), STRING_SLOTS>,
}

impl Default for ObjectStore {
    fn default() -> Self {
        Self::new()
    }
}

/// Size in bytes of an entry's value on the wire (bit sizes round up).
pub fn byte_len(entry: &Entry) -> usize {
    usize::from(entry.bit_len).div_ceil(8)
}

impl ObjectStore {
    /// A store holding every entry's default value.
    pub fn new() -> Self {
        let mut s = ObjectStore {
            values: [0; ENTRY_COUNT],
            strings: heapless::Vec::new(),
        };
        s.load_defaults();
        s
    }

    /// Restores every entry to its default value.
    pub fn load_defaults(&mut self) {
        self.strings.clear();
        let mut flat = 0usize;
        for obj in model::OBJECTS {
            for e in obj.entries {
                match e.default {
                    DefaultValue::Int(v) => {
                        if let Some(slot) = self.values.get_mut(flat) {
                            *slot = v;
                        }
                    }
                    DefaultValue::Str(s) => {
                        let mut text = heapless::String::new();
                        for c in s.chars() {
                            if text.push(c).is_err() {
                                break;
                            }
                        }
                        // More string entries than slots is a model error the
                        // model's tests exclude; extra strings read as "".
                        let _ = self.strings.push((flat as u16, text));
                    }
                }
                flat += 1;
            }
        }
    }

    /// The numeric value at flat position `flat` (0 when out of range).
    pub fn value(&self, flat: usize) -> i64 {
        self.values.get(flat).copied().unwrap_or(0)
    }

    /// Sets the numeric value at flat position `flat` without any check
    /// (for the device's own process data and diagnostics).
    pub fn set_value(&mut self, flat: usize, v: i64) {
        if let Some(slot) = self.values.get_mut(flat) {
            *slot = v;
        }
    }

    /// The value of `index:sub`, if the entry exists.
    pub fn get(&self, index: u16, sub: u8) -> Option<i64> {
        model::find_entry(index, sub).map(|(flat, _)| self.value(flat))
    }

    /// Sets `index:sub` without checks; returns whether the entry exists.
    pub fn set(&mut self, index: u16, sub: u8, v: i64) -> bool {
        match model::find_entry(index, sub) {
            Some((flat, _)) => {
                self.set_value(flat, v);
                true
            }
            None => false,
        }
    }

    /// The string value at flat position `flat`, if it is a string entry.
    pub fn string(&self, flat: usize) -> Option<&str> {
        self.strings
            .iter()
            .find(|(f, _)| usize::from(*f) == flat)
            .map(|(_, s)| s.as_str())
    }

    /// Replaces the string at `index:sub` (e.g. 0x100A after a firmware
    /// update); returns false if it is not a string entry or too long.
    pub fn set_string(&mut self, index: u16, sub: u8, text: &str) -> bool {
        let Some((flat, _)) = model::find_entry(index, sub) else {
            return false;
        };
        let Some((_, s)) = self
            .strings
            .iter_mut()
            .find(|(f, _)| usize::from(*f) == flat)
        else {
            return false;
        };
        let mut new = heapless::String::new();
        if new.push_str(text).is_err() {
            return false;
        }
        *s = new;
        true
    }

    /// Encodes the value of an entry into `out` (little-endian, the entry's
    /// byte size; strings as their bytes). Returns the number of bytes.
    pub fn encode(
        &self,
        flat: usize,
        entry: &Entry,
        out: &mut [u8],
    ) -> Result<usize, SdoAbortCode> {
        if entry.data_type == DataType::VisibleString {
            let s = self.string(flat).unwrap_or("");
            let dst = out.get_mut(..s.len()).ok_or(SdoAbortCode::ObjectTooLong)?;
            dst.copy_from_slice(s.as_bytes());
            return Ok(s.len());
        }
        let n = byte_len(entry);
        let bytes = self.value(flat).to_le_bytes();
        let (Some(dst), Some(src)) = (out.get_mut(..n), bytes.get(..n)) else {
            return Err(SdoAbortCode::ObjectTooLong);
        };
        dst.copy_from_slice(src);
        Ok(n)
    }

    /// SDO upload of `index:sub` into `out`: checks existence and read
    /// access, returns the number of bytes written.
    pub fn upload(&self, index: u16, sub: u8, out: &mut [u8]) -> Result<usize, SdoAbortCode> {
        let (flat, entry) = lookup(index, sub)?;
        if !entry.access.readable() {
            return Err(SdoAbortCode::WriteOnly);
        }
        self.encode(flat, entry, out)
    }

    /// Decodes and checks a value for `entry` from `data` as an SDO download
    /// would, without storing it. Returns the value.
    pub fn check(entry: &Entry, data: &[u8], state: AlState) -> Result<i64, SdoAbortCode> {
        match entry.access {
            Access::Ro => return Err(SdoAbortCode::ReadOnly),
            Access::RwPreOp if state != AlState::PreOp => return Err(SdoAbortCode::InvalidState),
            _ => {}
        }
        if entry.data_type == DataType::VisibleString {
            return Err(SdoAbortCode::UnsupportedAccess);
        }
        let n = byte_len(entry);
        if data.len() > n {
            return Err(SdoAbortCode::LengthTooHigh);
        }
        if data.len() < n {
            return Err(SdoAbortCode::LengthTooLow);
        }
        let mut raw = [0u8; 8];
        if let Some(dst) = raw.get_mut(..n) {
            dst.copy_from_slice(data);
        }
        let unsigned = u64::from_le_bytes(raw);
        let bits = u32::from(entry.bit_len).min(64);
        let value = if entry.data_type.is_signed() && bits < 64 {
            let shift = 64 - bits;
            ((unsigned << shift) as i64) >> shift
        } else {
            unsigned as i64
        };
        // Enumerations and booleans accept their members only (0x06090030),
        // whatever the bit pattern; other unsigned types must have no bits
        // set above their bit size.
        match entry.data_type {
            DataType::Bool if unsigned > 1 => return Err(SdoAbortCode::ValueRange),
            DataType::Enum(e) if !e.contains(value) || unsigned >> bits != 0 => {
                return Err(SdoAbortCode::ValueRange);
            }
            _ => {}
        }
        if !entry.data_type.is_signed() && bits < 64 && unsigned >> bits != 0 {
            return Err(SdoAbortCode::ValueTooHigh);
        }
        if let Some(max) = entry.max {
            if value > max {
                return Err(SdoAbortCode::ValueTooHigh);
            }
        }
        if let Some(min) = entry.min {
            if value < min {
                return Err(SdoAbortCode::ValueTooLow);
            }
        }
        Ok(value)
    }

    /// SDO download of `data` into `index:sub` in AL state `state`, with
    /// every check of [`ObjectStore::check`]. Returns the stored value.
    pub fn download(
        &mut self,
        index: u16,
        sub: u8,
        data: &[u8],
        state: AlState,
    ) -> Result<i64, SdoAbortCode> {
        let (flat, entry) = lookup(index, sub)?;
        let value = Self::check(entry, data, state)?;
        self.set_value(flat, value);
        Ok(value)
    }
}

/// Finds an SDO-accessible entry: unknown index aborts 0x06020000, unknown
/// subindex 0x06090011, a padding gap 0x06010000 (unsupported access: SDO
/// Information describes a gap as NULL with no access rights, as the SSC
/// does, so reading it is refused the way the SSC refuses it; MANUAL-NOTES
/// note 20).
pub fn lookup(index: u16, sub: u8) -> Result<(usize, &'static Entry), SdoAbortCode> {
    let Some((_, obj)) = model::find(index) else {
        return Err(SdoAbortCode::ObjectNotFound);
    };
    match model::find_entry(obj.index, sub) {
        Some((_, e)) if e.gap => Err(SdoAbortCode::UnsupportedAccess),
        Some((flat, e)) => Ok((flat, e)),
        None => Err(SdoAbortCode::SubindexNotFound),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn up(store: &ObjectStore, index: u16, sub: u8) -> Result<u64, SdoAbortCode> {
        let mut buf = [0u8; 8];
        let n = store.upload(index, sub, &mut buf)?;
        let mut raw = [0u8; 8];
        raw[..n].copy_from_slice(&buf[..n]);
        Ok(u64::from_le_bytes(raw))
    }

    #[test]
    fn identity_reads_product_code() {
        let s = ObjectStore::new();
        assert_eq!(up(&s, 0x1018, 2), Ok(0x00C7_03F3));
    }

    #[test]
    fn sdo_write_read_only_object_aborts_0601_0002() {
        let mut s = ObjectStore::new();
        assert_eq!(
            s.download(0x1018, 1, &[1, 0, 0, 0], AlState::PreOp),
            Err(SdoAbortCode::ReadOnly)
        );
    }

    #[test]
    fn current_above_range_aborts_0609_0031_and_below_0609_0032() {
        let mut s = ObjectStore::new();
        assert_eq!(
            s.download(0x800D, 2, &5000u16.to_le_bytes(), AlState::PreOp),
            Err(SdoAbortCode::ValueTooHigh)
        );
        assert_eq!(
            s.download(0x800D, 2, &100u16.to_le_bytes(), AlState::PreOp),
            Err(SdoAbortCode::ValueTooLow)
        );
        assert_eq!(
            s.download(0x800D, 2, &2000u16.to_le_bytes(), AlState::Op),
            Ok(2000)
        );
        assert_eq!(up(&s, 0x800D, 2), Ok(2000));
    }

    #[test]
    fn wrong_lengths_abort_0607_0012_and_0607_0013() {
        let mut s = ObjectStore::new();
        assert_eq!(
            s.download(0x800D, 2, &[0, 0, 0, 0], AlState::PreOp),
            Err(SdoAbortCode::LengthTooHigh)
        );
        assert_eq!(
            s.download(0x800D, 2, &[7], AlState::PreOp),
            Err(SdoAbortCode::LengthTooLow)
        );
    }

    #[test]
    fn unknown_object_and_subindex_abort() {
        let s = ObjectStore::new();
        assert_eq!(up(&s, 0x1234, 0), Err(SdoAbortCode::ObjectNotFound));
        assert_eq!(up(&s, 0x1018, 9), Err(SdoAbortCode::SubindexNotFound));
    }

    #[test]
    fn write_only_password_cannot_be_read() {
        let s = ObjectStore::new();
        assert_eq!(up(&s, 0xF801, 1), Err(SdoAbortCode::WriteOnly));
    }

    #[test]
    fn enum_value_outside_its_members_aborts_0609_0030() {
        let mut s = ObjectStore::new();
        assert_eq!(
            s.download(0xF800, 2, &[7], AlState::PreOp),
            Err(SdoAbortCode::ValueRange)
        );
        assert_eq!(
            s.download(0xF800, 2, &[9], AlState::PreOp),
            Err(SdoAbortCode::ValueRange),
            "high bits set in a 3-bit enum"
        );
        assert_eq!(s.download(0xF800, 2, &[2], AlState::PreOp), Ok(2));
    }

    #[test]
    fn pdo_assignment_is_writable_only_in_preop() {
        let mut s = ObjectStore::new();
        assert_eq!(
            s.download(0x1C12, 1, &0x1600u16.to_le_bytes(), AlState::SafeOp),
            Err(SdoAbortCode::InvalidState)
        );
        assert!(
            s.download(0x1C12, 1, &0x1600u16.to_le_bytes(), AlState::PreOp)
                .is_ok()
        );
    }

    #[test]
    fn device_name_uploads_as_string() {
        let s = ObjectStore::new();
        let mut buf = [0u8; 32];
        let n = s.upload(0x1008, 0, &mut buf).unwrap();
        assert_eq!(&buf[..n], b"PAM-199-P-ETC");
    }

    #[test]
    fn negative_curve_point_round_trips() {
        let mut s = ObjectStore::new();
        assert_eq!(
            s.download(0x8006, 1, &(-5000i16).to_le_bytes(), AlState::PreOp),
            Ok(-5000)
        );
        assert_eq!(up(&s, 0x8006, 1), Ok((-5000i16) as u16 as u64));
    }
}
