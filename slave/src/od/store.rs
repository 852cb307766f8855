//! Live values of the object dictionary.
//!
//! One `i64` slot per entry of the device's [`Dictionary`], indexed by the
//! entry's flat position; after them the *byte area*: the bytes of octet
//! strings, `UNICODE_STRING`s, `GUID`s and arrays held as one value, 8 a
//! slot, in dictionary order ([`Dictionary::value_slots`]); and a few
//! string slots for visible strings (further or longer strings are served
//! from their defaults and are read-only). `REAL`/`LREAL` values are their
//! IEEE 754 bit patterns in the entry's slot. SDO access goes through
//! [`ObjectStore::upload`] and [`ObjectStore::download`], which apply the
//! description's rules (existence, access in the current state, length,
//! range, enumeration members) and answer with the CoE abort code a master
//! expects.
//!
//! The store is sized by its device without heap and without making every
//! user generic: [`ObjectStore<V>`] owns its values `V` (`[i64; N]`, N the
//! dictionary's entry count) as its last field, and [`Od`] is the same
//! store with the values unsized (`[i64]`). Core and application code take
//! `&Od` / `&mut Od`; [`ObjectStore::od`] / [`ObjectStore::od_mut`] turn a
//! sized store into one (the way `heapless`'s `VecView` works).

use super::dictionary::{Dictionary, value_le};
use super::types::{Access, DataType, DefaultValue, Entry};
use crate::al::AlState;
use crate::wire::coe::SdoAbortCode;

pub use super::types::{STRING_CAPACITY, STRING_SLOTS};

type Strings = heapless::Vec<(u16, heapless::String<STRING_CAPACITY>), STRING_SLOTS>;

/// The live values of every entry of one device's dictionary; `V` is the
/// value storage (`[i64; N]`), or `[i64]` in the unsized view [`Od`].
#[derive(Debug, Clone)]
pub struct ObjectStore<V: ?Sized = [i64]> {
    dict: &'static Dictionary,
    strings: Strings,
    values: V,
}

/// An object store whatever its size: what core and application code take.
pub type Od = ObjectStore<[i64]>;

/// Storage for a dictionary's values: `[i64; N]` for any `N`.
pub trait ValueStorage: Sized + Send + 'static {
    /// Number of values held.
    const LEN: usize;
    /// All zeros.
    fn zeroed() -> Self;
    /// The store as the unsized view.
    fn view(store: &ObjectStore<Self>) -> &Od;
    /// The store as the unsized view, mutably.
    fn view_mut(store: &mut ObjectStore<Self>) -> &mut Od;
}

impl<const N: usize> ValueStorage for [i64; N] {
    const LEN: usize = N;
    fn zeroed() -> Self {
        [0; N]
    }
    fn view(store: &ObjectStore<Self>) -> &Od {
        store
    }
    fn view_mut(store: &mut ObjectStore<Self>) -> &mut Od {
        store
    }
}

impl<V: ValueStorage> ObjectStore<V> {
    /// A store of `dict` holding every entry's default value. `V` must hold
    /// `dict.entry_count()` values: entries beyond it read as 0 and ignore
    /// writes ([`DeviceDescription::validate`](crate::device::DeviceDescription)
    /// and the device's `Values` type keep them equal).
    pub fn new(dict: &'static Dictionary) -> Self {
        let mut s = Self::zeroed(dict);
        s.od_mut().load_defaults();
        s
    }

    /// A store of `dict` with every value 0, not its defaults (fill them
    /// in with [`ObjectStore::load_defaults`] where the store lives: no
    /// store-sized copy on the stack).
    pub fn zeroed(dict: &'static Dictionary) -> Self {
        ObjectStore {
            dict,
            strings: heapless::Vec::new(),
            values: V::zeroed(),
        }
    }

    /// The store as [`Od`].
    pub fn od(&self) -> &Od {
        V::view(self)
    }

    /// The store as [`Od`], mutably.
    pub fn od_mut(&mut self) -> &mut Od {
        V::view_mut(self)
    }
}

impl<V: ValueStorage> core::ops::Deref for ObjectStore<V> {
    type Target = Od;
    fn deref(&self) -> &Od {
        self.od()
    }
}

impl<V: ValueStorage> core::ops::DerefMut for ObjectStore<V> {
    fn deref_mut(&mut self) -> &mut Od {
        self.od_mut()
    }
}

/// Size in bytes of an entry's value on the wire (bit sizes round up).
pub fn byte_len(entry: &Entry) -> usize {
    usize::from(entry.bit_len).div_ceil(8)
}

/// The value of `raw` (the entry's bits, zero-extended to 64) in the
/// entry's signedness: signed types are sign-extended from their bit size,
/// as the store holds them.
pub fn from_raw(entry: &Entry, raw: u64) -> i64 {
    let bits = u32::from(entry.bit_len).min(64);
    if entry.data_type.is_signed() && bits > 0 && bits < 64 {
        let shift = 64 - bits;
        ((raw << shift) as i64) >> shift
    } else {
        raw as i64
    }
}

impl Od {
    /// The dictionary this store holds the values of.
    pub fn dictionary(&self) -> &'static Dictionary {
        self.dict
    }

    /// Restores every entry to its default value.
    pub fn load_defaults(&mut self) {
        self.strings.clear();
        let dict = self.dict;
        let mut area = dict.entry_count();
        for (flat, _, e) in dict.entries() {
            let slots = e.area_len().div_ceil(8);
            match e.default_value() {
                DefaultValue::Int(v) if slots == 0 => self.set_value(flat, v.get()),
                DefaultValue::Int(_) => self.fill_area(area, slots, &[]),
                DefaultValue::Bytes(b) => self.fill_area(area, slots, b),
                DefaultValue::Str(s) if s.len() <= STRING_CAPACITY => {
                    let mut text = heapless::String::new();
                    // Fits: checked above.
                    let _ = text.push_str(s);
                    // Strings beyond the slots read as their default
                    // (see `encode`) and cannot be written.
                    let _ = self.strings.push((flat as u16, text));
                }
                DefaultValue::Str(_) => {}
            }
            area += slots;
        }
    }

    /// Writes `bytes` (zeros after them) into `slots` slots of the byte
    /// area from slot `first`.
    fn fill_area(&mut self, first: usize, slots: usize, bytes: &[u8]) {
        for k in 0..slots {
            let mut chunk = [0u8; 8];
            for (i, c) in chunk.iter_mut().enumerate() {
                *c = bytes.get(k * 8 + i).copied().unwrap_or(0);
            }
            self.set_value(first + k, i64::from_le_bytes(chunk));
        }
    }

    /// Copies the bytes of the byte-area entry at flat position `flat`
    /// into `out`; returns how many (its length), `None` when the entry
    /// keeps no bytes there or `out` is too short.
    pub fn area_bytes(&self, flat: usize, out: &mut [u8]) -> Option<usize> {
        let (first, len) = self.dict.area_of(flat)?;
        let dst = out.get_mut(..len)?;
        for (i, d) in dst.iter_mut().enumerate() {
            let word = self.value(first + i / 8).to_le_bytes();
            *d = word.get(i % 8).copied().unwrap_or(0);
        }
        Some(len)
    }

    /// Replaces the bytes of the byte-area entry at flat position `flat`
    /// with `data` (its length exactly); returns whether it was stored.
    pub fn set_area_bytes(&mut self, flat: usize, data: &[u8]) -> bool {
        match self.dict.area_of(flat) {
            Some((first, len)) if len == data.len() => {
                self.fill_area(first, len.div_ceil(8), data);
                true
            }
            _ => false,
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
        self.dict
            .find_entry(index, sub)
            .map(|(flat, _)| self.value(flat))
    }

    /// Sets `index:sub` without checks; returns whether the entry exists.
    pub fn set(&mut self, index: u16, sub: u8, v: i64) -> bool {
        match self.dict.find_entry(index, sub) {
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
        let Some((flat, _)) = self.dict.find_entry(index, sub) else {
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
        if entry.data_type.is_bytes() && entry.data_type != DataType::VisibleString {
            return self
                .area_bytes(flat, out)
                .ok_or(SdoAbortCode::ObjectTooLong);
        }
        if entry.data_type == DataType::VisibleString {
            // A string beyond the store's slots is served from its default
            // (read-only strings of a large dictionary need no slot).
            let fallback = match entry.default_value() {
                DefaultValue::Str(d) => d,
                DefaultValue::Int(_) | DefaultValue::Bytes(_) => "",
            };
            let s = self.string(flat).unwrap_or(fallback);
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
        let (flat, entry) = self.lookup(index, sub)?;
        if !entry.access().readable() {
            return Err(SdoAbortCode::WriteOnly);
        }
        self.encode(flat, entry, out)
    }

    /// Decodes and checks a value for `entry` from `data` as an SDO download
    /// would, without storing it. Returns the value.
    pub fn check(&self, entry: &Entry, data: &[u8], state: AlState) -> Result<i64, SdoAbortCode> {
        match entry.access() {
            Access::Ro => return Err(SdoAbortCode::ReadOnly),
            Access::RwPreOp if state != AlState::PreOp => return Err(SdoAbortCode::InvalidState),
            _ => {}
        }
        if entry.data_type.is_bytes() {
            // Bytes are stored by `download`, not as a number.
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
        let value = from_raw(entry, unsigned);
        // Enumerations and booleans accept their members only (0x06090030),
        // whatever the bit pattern; other unsigned types must have no bits
        // set above their bit size.
        match entry.data_type {
            DataType::Bool if unsigned > 1 => return Err(SdoAbortCode::ValueRange),
            // A 64-bit enumeration has no bits above its size (a shift by
            // 64 would overflow).
            DataType::Enum(e)
                if !self
                    .dict
                    .find_enum(e.index())
                    .is_some_and(|d| d.contains(value))
                    || unsigned.checked_shr(bits).unwrap_or(0) != 0 =>
            {
                return Err(SdoAbortCode::ValueRange);
            }
            _ => {}
        }
        if !entry.data_type.is_signed() && bits < 64 && unsigned >> bits != 0 {
            return Err(SdoAbortCode::ValueTooHigh);
        }
        let t = &entry.data_type;
        if let Some(max) = entry.max()
            && !value_le(t, value, max)
        {
            return Err(SdoAbortCode::ValueTooHigh);
        }
        if let Some(min) = entry.min()
            && !value_le(t, min, value)
        {
            return Err(SdoAbortCode::ValueTooLow);
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
        let (flat, entry) = self.lookup(index, sub)?;
        if self.dict.area_of(flat).is_some() {
            match entry.access() {
                Access::Ro => return Err(SdoAbortCode::ReadOnly),
                Access::RwPreOp if state != AlState::PreOp => {
                    return Err(SdoAbortCode::InvalidState);
                }
                _ => {}
            }
            let len = entry.area_len();
            if data.len() > len {
                return Err(SdoAbortCode::LengthTooHigh);
            }
            if data.len() < len {
                return Err(SdoAbortCode::LengthTooLow);
            }
            self.set_area_bytes(flat, data);
            return Ok(0);
        }
        let value = self.check(entry, data, state)?;
        self.set_value(flat, value);
        Ok(value)
    }

    /// Finds an SDO-accessible entry: unknown index aborts 0x06020000,
    /// unknown subindex 0x06090011, a padding gap 0x06010000 (unsupported
    /// access: SDO Information describes a gap as NULL with no access
    /// rights, as the SSC does, so reading it is refused the way the SSC
    /// refuses it).
    pub fn lookup(&self, index: u16, sub: u8) -> Result<(usize, &'static Entry), SdoAbortCode> {
        let Some((_, obj)) = self.dict.find(index) else {
            return Err(SdoAbortCode::ObjectNotFound);
        };
        match self.dict.find_entry(obj.index, sub) {
            Some((_, e)) if e.gap() => Err(SdoAbortCode::UnsupportedAccess),
            Some((flat, e)) => Ok((flat, e)),
            None => Err(SdoAbortCode::SubindexNotFound),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::od::types::Limits;
    use crate::testing::store;

    fn up(s: &Od, index: u16, sub: u8) -> Result<u64, SdoAbortCode> {
        let mut buf = [0u8; 8];
        let n = s.upload(index, sub, &mut buf)?;
        let mut raw = [0u8; 8];
        raw[..n].copy_from_slice(&buf[..n]);
        Ok(u64::from_le_bytes(raw))
    }

    #[test]
    fn defaults_read_back_and_strings_upload_as_text() {
        let s = store();
        assert_eq!(up(&s, 0x1018, 1), Ok(0xABC));
        assert_eq!(up(&s, 0x8000, 1), Ok(100));
        let mut buf = [0u8; 16];
        assert_eq!(s.upload(0x1008, 0, &mut buf), Ok(4));
        assert_eq!(&buf[..4], b"TD-1");
    }

    #[test]
    fn unknown_object_subindex_and_padding_abort_with_their_codes() {
        let s = store();
        assert_eq!(up(&s, 0x2000, 0), Err(SdoAbortCode::ObjectNotFound));
        assert_eq!(up(&s, 0x1018, 9), Err(SdoAbortCode::SubindexNotFound));
        assert_eq!(up(&s, 0x6000, 2), Err(SdoAbortCode::UnsupportedAccess));
    }

    #[test]
    fn sdo_write_read_only_object_aborts_0601_0002() {
        let mut s = store();
        assert_eq!(
            s.download(0x1018, 1, &[1, 0, 0, 0], AlState::PreOp),
            Err(SdoAbortCode::ReadOnly)
        );
    }

    #[test]
    fn ranges_types_lengths_and_enumerations_are_checked() {
        let mut s = store();
        let w = |s: &mut Od, sub: u8, d: &[u8]| s.download(0x8000, sub, d, AlState::Op);
        assert_eq!(
            w(&mut s, 1, &1001u16.to_le_bytes()),
            Err(SdoAbortCode::ValueTooHigh)
        );
        assert_eq!(w(&mut s, 1, &[1]), Err(SdoAbortCode::LengthTooLow));
        assert_eq!(w(&mut s, 1, &[1, 0, 0]), Err(SdoAbortCode::LengthTooHigh));
        assert_eq!(
            w(&mut s, 2, &[3]),
            Err(SdoAbortCode::ValueRange),
            "not a member"
        );
        assert_eq!(w(&mut s, 2, &[2]), Ok(2));
        assert_eq!(
            w(&mut s, 3, &(-101i16).to_le_bytes()),
            Err(SdoAbortCode::ValueTooLow)
        );
        assert_eq!(w(&mut s, 3, &(-100i16).to_le_bytes()), Ok(-100));
        assert_eq!(s.get(0x8000, 3), Some(-100), "sign extended");
    }

    /// A 64-bit enumeration (`DT0801EN64`), with a member above 32 bits.
    const WIDE: crate::od::EnumDesc = crate::od::EnumDesc {
        index: 0x0801,
        name: "DT0801EN64",
        bit_len: 64,
        values: &[(1, "ONE"), (0x1_0000_0000, "HIGH")],
    };

    /// A store whose dictionary lists `enums`: one VAR 0x2000 of `entry`.
    fn store_of(
        entry: &'static Entry,
        enums: &'static [&'static crate::od::EnumDesc],
    ) -> ObjectStore<[i64; 2]> {
        let objects: &'static [crate::od::Object] = Box::leak(Box::new([crate::od::Object {
            index: 0x2000,
            name: "Test",
            code: crate::od::ObjectCode::Var,
            entries: core::slice::from_ref(entry),
        }]));
        let dict = Box::leak(Box::new(crate::od::Dictionary::new(objects, enums, &[0])));
        ObjectStore::new(dict)
    }

    #[test]
    fn a_64_bit_enumeration_accepts_its_members_and_refuses_others_with_0609_0030() {
        static E: Entry = crate::od::build::setting(1, "Wide", WIDE.data_type(), 1, &Limits::NONE);
        let e = &E;
        assert_eq!(e.bit_len, 64);
        let s = store_of(e, &[&WIDE]);
        let w = |v: u64| s.check(e, &v.to_le_bytes(), AlState::PreOp);
        assert_eq!(w(1), Ok(1));
        assert_eq!(w(0x1_0000_0000), Ok(0x1_0000_0000));
        assert_eq!(w(2), Err(SdoAbortCode::ValueRange));
        assert_eq!(w(u64::MAX), Err(SdoAbortCode::ValueRange));
    }

    /// CiA 402's quick stop option code (0x605A, INTEGER16) as Teknic's
    /// ESI describes it: an enumeration with negative members.
    const SIGNED: crate::od::EnumDesc = crate::od::EnumDesc {
        index: 0x0802,
        name: "DT0802EN16",
        bit_len: 16,
        values: &[
            (-2, "Position hold"),
            (-1, "Dynamic brake"),
            (0, "Coast"),
            (2, "Decelerate"),
        ],
    };

    #[test]
    fn an_enumeration_with_negative_members_takes_their_bit_patterns() {
        static E: Entry =
            crate::od::build::setting(1, "Quick stop", SIGNED.data_type(), -1, &Limits::NONE);
        let e = &E;
        assert_eq!(e.bit_len, 16);
        assert!(e.data_type.is_signed());
        let s = store_of(e, &[&SIGNED]);
        let w = |v: i16| s.check(e, &v.to_le_bytes(), AlState::PreOp);
        assert_eq!(w(-1), Ok(-1), "0xFFFF is -1");
        assert_eq!(w(-2), Ok(-2));
        assert_eq!(w(2), Ok(2));
        assert_eq!(w(-3), Err(SdoAbortCode::ValueRange));
        assert_eq!(w(1), Err(SdoAbortCode::ValueRange));
        assert!(!WIDE.data_type().is_signed());
    }

    #[test]
    fn pdo_assignment_is_writable_only_in_preop() {
        let mut s = store();
        let d = 0x1601u16.to_le_bytes();
        assert_eq!(
            s.download(0x1C12, 1, &d, AlState::SafeOp),
            Err(SdoAbortCode::InvalidState)
        );
        assert_eq!(s.download(0x1C12, 1, &d, AlState::PreOp), Ok(0x1601));
    }

    #[test]
    fn a_sized_store_and_its_view_are_the_same_values() {
        let mut s = store();
        s.set(0x7000, 3, -7);
        let od: &Od = s.od();
        assert_eq!(od.get(0x7000, 3), Some(-7));
        assert_eq!(od.dictionary().entry_count(), crate::testing::ENTRIES);
        assert!(s.set_string(0x100A, 0, "11"));
        assert!(!s.set_string(0x1018, 1, "x"), "not a string entry");
    }
}
