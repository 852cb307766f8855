//! # The FoE image store and the parameters on a NOR flash
//!
//! The core's [`ImageStore`] (two image slots and two copies of the boot
//! record) and [`NvStorage`] (the parameter store's two slots) on any
//! `embedded-storage` [`NorFlash`] that programs bytewise: the STM32F4's
//! internal flash, or the bridge's flash image over the UART link
//! ([`crate::link::LinkFlash`]) on the emulated board. Every region that
//! is written as a whole (an image slot, a boot-record copy, a parameter
//! slot) has erase units of its own, so a power cut while one is erased
//! and written leaves the other copy intact, as the core's power-cut
//! rules expect.

use core::cell::RefCell;

use ecat_slave::firmware::{BootState, ImageStore, STATE_RECORD_LEN, Slot, StoreError};
use ecat_slave::hal::{NvError, NvStorage};
use ecat_slave::params::{SLOT_SIZE, STORAGE_SIZE};
use embedded_storage::nor_flash::NorFlash;

/// Where the store's regions are in the flash (byte offsets as the
/// [`NorFlash`] counts them). Each start is the start of an erase unit and
/// each region ends on one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlashLayout {
    /// The erase unit the regions are aligned to: the flash's
    /// `ERASE_SIZE` when its sectors are uniform; on a flash with sectors
    /// of several sizes (the STM32F4's 16, 64 and 128 KiB, whose driver
    /// erases every sector a range touches) the smallest sector, with each
    /// region placed on whole sectors of its own.
    pub erase_unit: u32,
    /// Image slots A and B.
    pub slots: [u32; 2],
    /// Length of an image slot: the largest image the device accepts.
    pub slot_len: u32,
    /// The two copies of the boot record.
    pub state: [u32; 2],
    /// Length of a boot-record region (its erase unit(s)).
    pub state_len: u32,
    /// The two parameter slots.
    pub params: [u32; 2],
    /// Length of a parameter region (its erase unit(s)).
    pub params_len: u32,
}

impl FlashLayout {
    /// Whether the regions fit a flash of `capacity` bytes, are aligned to
    /// the erase unit, do not overlap, and hold what goes into them.
    // A const fn cannot call `get`; `i` and `j` stay below the length of
    // the fixed array they index.
    #[allow(clippy::indexing_slicing)]
    pub const fn is_valid(&self, capacity: u32) -> bool {
        let erase = self.erase_unit;
        let regions = [
            (self.slots[0], self.slot_len),
            (self.slots[1], self.slot_len),
            (self.state[0], self.state_len),
            (self.state[1], self.state_len),
            (self.params[0], self.params_len),
            (self.params[1], self.params_len),
        ];
        if erase == 0
            || (self.state_len as usize) < STATE_RECORD_LEN
            || (self.params_len as usize) < SLOT_SIZE
        {
            return false;
        }
        let mut i = 0;
        while i < regions.len() {
            let (start, len) = regions[i];
            let Some(end) = start.checked_add(len) else {
                return false;
            };
            if len == 0 || start % erase != 0 || len % erase != 0 || end > capacity {
                return false;
            }
            let mut j = i + 1;
            while j < regions.len() {
                let (s2, l2) = regions[j];
                if start < s2.saturating_add(l2) && s2 < end {
                    return false;
                }
                j += 1;
            }
            i += 1;
        }
        true
    }
}

/// The start of image slot `slot` in `layout`.
fn slot_start(layout: &FlashLayout, slot: Slot) -> u32 {
    match slot {
        Slot::A => layout.slots[0],
        Slot::B => layout.slots[1],
    }
}

/// The FoE image store on a NOR flash: image slots and boot records where
/// the [`FlashLayout`] says. The flash is in a `RefCell` because the
/// core's store reads through `&self`; a nested access is an I/O error,
/// never a panic.
pub struct NorImageStore<F: NorFlash> {
    flash: RefCell<F>,
    layout: FlashLayout,
}

impl<F: NorFlash> NorImageStore<F> {
    const BYTEWISE: () = assert!(
        F::WRITE_SIZE == 1 && F::READ_SIZE == 1,
        "NorImageStore needs a flash that reads and programs bytewise"
    );

    /// The store on `flash` with `layout`; `None` if the layout does not
    /// fit the flash ([`FlashLayout::is_valid`]).
    pub fn new(flash: F, layout: FlashLayout) -> Option<Self> {
        let () = Self::BYTEWISE;
        let capacity = u32::try_from(flash.capacity()).ok()?;
        layout.is_valid(capacity).then(|| NorImageStore {
            flash: RefCell::new(flash),
            layout,
        })
    }

    /// The flash back (e.g. to share it with the parameter store).
    pub fn into_flash(self) -> F {
        self.flash.into_inner()
    }

    fn region(&self, slot: Slot, offset: usize, len: usize) -> Result<u32, StoreError> {
        let end = offset.checked_add(len).ok_or(StoreError::OutOfBounds)?;
        if end > self.layout.slot_len as usize {
            return Err(StoreError::OutOfBounds);
        }
        let offset = u32::try_from(offset).map_err(|_| StoreError::OutOfBounds)?;
        slot_start(&self.layout, slot)
            .checked_add(offset)
            .ok_or(StoreError::OutOfBounds)
    }

    fn copies(&self) -> Result<[[u8; STATE_RECORD_LEN]; 2], StoreError> {
        let mut flash = self.flash.try_borrow_mut().map_err(|_| StoreError::Io)?;
        let mut copies = [[0u8; STATE_RECORD_LEN]; 2];
        for (copy, &at) in copies.iter_mut().zip(self.layout.state.iter()) {
            flash.read(at, copy).map_err(|_| StoreError::Io)?;
        }
        Ok(copies)
    }
}

impl<F: NorFlash> ImageStore for NorImageStore<F> {
    fn slot_capacity(&self) -> usize {
        self.layout.slot_len as usize
    }

    fn erase(&mut self, slot: Slot) -> Result<(), StoreError> {
        let start = slot_start(&self.layout, slot);
        let end = start
            .checked_add(self.layout.slot_len)
            .ok_or(StoreError::OutOfBounds)?;
        self.flash
            .get_mut()
            .erase(start, end)
            .map_err(|_| StoreError::Io)
    }

    fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError> {
        let at = self.region(slot, offset, data.len())?;
        self.flash
            .get_mut()
            .write(at, data)
            .map_err(|_| StoreError::Io)
    }

    fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError> {
        let cap = self.layout.slot_len as usize;
        if offset > cap {
            return Err(StoreError::OutOfBounds);
        }
        let n = buf.len().min(cap - offset);
        let at = self.region(slot, offset, n)?;
        let dst = buf.get_mut(..n).ok_or(StoreError::OutOfBounds)?;
        self.flash
            .try_borrow_mut()
            .map_err(|_| StoreError::Io)?
            .read(at, dst)
            .map_err(|_| StoreError::Io)?;
        Ok(n)
    }

    fn read_state(&self) -> Result<BootState, StoreError> {
        let [a, b] = self.copies()?;
        BootState::read_bank([&a, &b])
            .map(|(_, s)| s)
            .ok_or(StoreError::NoState)
    }

    fn write_state(&mut self, state: &BootState) -> Result<(), StoreError> {
        let [a, b] = self.copies()?;
        let (index, record) = BootState::bank_write([&a, &b], state);
        let start = *self.layout.state.get(index).ok_or(StoreError::Io)?;
        let end = start
            .checked_add(self.layout.state_len)
            .ok_or(StoreError::OutOfBounds)?;
        let flash = self.flash.get_mut();
        flash.erase(start, end).map_err(|_| StoreError::Io)?;
        flash.write(start, &record).map_err(|_| StoreError::Io)
    }
}

/// The parameter storage ([`STORAGE_SIZE`] bytes: the parameter store's
/// two slots of [`SLOT_SIZE`]) on a NOR flash, each slot in a region of
/// its own. A RAM copy serves reads; a write updates it and rewrites the
/// slot(s) it touched (erase, program), so a SAVE, which writes one slot,
/// never erases the other.
pub struct NorNv<F: NorFlash> {
    flash: F,
    regions: [u32; 2],
    region_len: u32,
    ram: [u8; STORAGE_SIZE],
    writes: u32,
}

impl<F: NorFlash> NorNv<F> {
    /// The parameters in the `params` regions of `layout` on `flash`,
    /// read into RAM (a failed read leaves blank storage: the defaults).
    pub fn new(mut flash: F, layout: &FlashLayout) -> Self {
        let mut ram = [0xFFu8; STORAGE_SIZE];
        for (chunk, &at) in ram.chunks_mut(SLOT_SIZE).zip(layout.params.iter()) {
            if flash.read(at, chunk).is_err() {
                chunk.fill(0xFF);
            }
        }
        NorNv {
            flash,
            regions: layout.params,
            region_len: layout.params_len,
            ram,
            writes: 0,
        }
    }

    /// The flash.
    pub fn flash_mut(&mut self) -> &mut F {
        &mut self.flash
    }

    fn range(offset: usize, len: usize) -> Result<core::ops::Range<usize>, NvError> {
        match offset.checked_add(len) {
            Some(end) if end <= STORAGE_SIZE => Ok(offset..end),
            _ => Err(NvError::OutOfRange {
                offset,
                len,
                capacity: STORAGE_SIZE,
            }),
        }
    }
}

impl<F: NorFlash> NvStorage for NorNv<F> {
    fn capacity(&self) -> usize {
        STORAGE_SIZE
    }

    fn read(&self, offset: usize, buf: &mut [u8]) -> Result<(), NvError> {
        let r = Self::range(offset, buf.len())?;
        buf.copy_from_slice(self.ram.get(r).ok_or(NvError::Interrupted)?);
        Ok(())
    }

    fn write(&mut self, offset: usize, data: &[u8]) -> Result<(), NvError> {
        let r = Self::range(offset, data.len())?;
        if data.is_empty() {
            return Ok(());
        }
        self.ram
            .get_mut(r.clone())
            .ok_or(NvError::Interrupted)?
            .copy_from_slice(data);
        let first = r.start / SLOT_SIZE;
        let last = (r.end - 1) / SLOT_SIZE;
        for k in first..=last {
            let at = *self.regions.get(k).ok_or(NvError::Interrupted)?;
            let end = at
                .checked_add(self.region_len)
                .ok_or(NvError::Interrupted)?;
            let slot = self
                .ram
                .get(k * SLOT_SIZE..(k + 1) * SLOT_SIZE)
                .ok_or(NvError::Interrupted)?;
            self.flash
                .erase(at, end)
                .map_err(|_| NvError::Interrupted)?;
            self.flash
                .write(at, slot)
                .map_err(|_| NvError::Interrupted)?;
        }
        self.writes = self.writes.wrapping_add(1);
        Ok(())
    }

    fn write_count(&self) -> u32 {
        self.writes
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use ecat_slave::firmware::{self, FirmwareVersion};
    use embedded_storage::nor_flash::{ErrorType, NorFlashErrorKind, ReadNorFlash};
    use std::vec;
    use std::vec::Vec;

    /// A NOR flash in RAM: erase to 0xFF in 4 KiB units, programming only
    /// clears bits (a program that would set one is an error, as the
    /// bridge's flash refuses it), erases counted per unit.
    struct RamNor {
        bytes: Vec<u8>,
        erases: Vec<u32>,
    }

    impl RamNor {
        fn new(len: usize) -> Self {
            RamNor {
                bytes: vec![0xFF; len],
                erases: vec![0; len / 4096],
            }
        }
    }

    impl ErrorType for RamNor {
        type Error = NorFlashErrorKind;
    }

    impl ReadNorFlash for RamNor {
        const READ_SIZE: usize = 1;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            let o = offset as usize;
            let src = self
                .bytes
                .get(o..o + bytes.len())
                .ok_or(NorFlashErrorKind::OutOfBounds)?;
            bytes.copy_from_slice(src);
            Ok(())
        }
        fn capacity(&self) -> usize {
            self.bytes.len()
        }
    }

    impl NorFlash for RamNor {
        const WRITE_SIZE: usize = 1;
        const ERASE_SIZE: usize = 4096;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            for u in from / 4096..to / 4096 {
                self.erases[u as usize] += 1;
            }
            self.bytes
                .get_mut(from as usize..to as usize)
                .ok_or(NorFlashErrorKind::OutOfBounds)?
                .fill(0xFF);
            Ok(())
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            let o = offset as usize;
            let dst = self
                .bytes
                .get_mut(o..o + bytes.len())
                .ok_or(NorFlashErrorKind::OutOfBounds)?;
            for (d, s) in dst.iter_mut().zip(bytes) {
                if *s & !*d != 0 {
                    return Err(NorFlashErrorKind::Other);
                }
                *d &= *s;
            }
            Ok(())
        }
    }

    const LAYOUT: FlashLayout = FlashLayout {
        erase_unit: 4096,
        slots: [0, 0x4000],
        slot_len: 0x4000,
        state: [0x8000, 0x9000],
        state_len: 0x1000,
        params: [0xA000, 0xB000],
        params_len: 0x1000,
    };

    #[test]
    fn overlapping_or_misaligned_layouts_are_refused() {
        assert!(LAYOUT.is_valid(0xC000));
        assert!(!LAYOUT.is_valid(0xB000), "params beyond the flash");
        let overlap = FlashLayout {
            state: [0x3000, 0x9000],
            ..LAYOUT
        };
        assert!(!overlap.is_valid(0xC000));
        let odd = FlashLayout {
            slot_len: 0x3F00,
            ..LAYOUT
        };
        assert!(!odd.is_valid(0xC000));
        assert!(NorImageStore::new(RamNor::new(0x8000), LAYOUT).is_none());
    }

    #[test]
    fn a_downloaded_image_boots_after_a_power_cycle_from_the_same_flash() {
        let mut store = NorImageStore::new(RamNor::new(0xC000), LAYOUT).expect("layout");
        assert_eq!(store.read_state(), Err(StoreError::NoState), "blank flash");
        let v10 = FirmwareVersion::new("10").expect("version");
        firmware::provision(&mut store, v10, b"factory").expect("provision");
        let image = master_image("11", &[0x5A; 3000]);
        let mut v = firmware::EfwValidator::new(identity(), 0x4000);
        let slot = firmware::begin_download(&mut store).expect("begin");
        assert_eq!(slot, Slot::B);
        let mut off = 0;
        for chunk in image.chunks(500) {
            let payload = v.feed(chunk).expect("valid");
            firmware::write_chunk(&mut store, slot, off, payload).expect("write");
            off += payload.len();
        }
        let validated = v.finish().expect("complete");
        firmware::finish_download(&mut store, slot, &validated).expect("finish");
        firmware::commit_pending(&mut store).expect("commit");
        // Power cycle: a new store on the same flash.
        let mut store = NorImageStore::new(store.into_flash(), LAYOUT).expect("layout");
        let decision = firmware::power_on(&mut store);
        assert_eq!(decision.slot, Some(Slot::B));
        assert_eq!(decision.version.as_str(), "11");
        firmware::confirm_boot(&mut store).expect("confirm");
        let flash = store.into_flash();
        assert!(
            flash.erases[8] >= 1 && flash.erases[9] >= 1,
            "each boot-record copy erased in its own unit: {:?}",
            flash.erases
        );
    }

    fn identity() -> firmware::DeviceIdentity {
        firmware::DeviceIdentity {
            vendor_id: 1,
            product_code: 2,
            revision: 1,
        }
    }

    fn master_image(version: &str, payload: &[u8]) -> Vec<u8> {
        let header = firmware::EfwHeaderRepr {
            header_len: firmware::EFW_HEADER_LEN as u16,
            flags: 0,
            vendor_id: 1,
            product_code: 2,
            revision_min: 0,
            revision_max: u32::MAX,
            version: FirmwareVersion::new(version).expect("version"),
            payload_len: 0,
            payload_crc: 0,
        };
        let mut out = vec![0u8; firmware::EFW_HEADER_LEN + payload.len()];
        let n = firmware::pack(&header, payload, &mut out).expect("pack");
        out.truncate(n);
        out
    }

    #[test]
    fn a_parameter_save_rewrites_only_the_slot_it_writes() {
        let mut nv = NorNv::new(RamNor::new(0xC000), &LAYOUT);
        let mut b = [0u8; 4];
        nv.read(0, &mut b).expect("read");
        assert_eq!(b, [0xFF; 4], "blank");
        nv.write(SLOT_SIZE + 8, &[1, 2, 3]).expect("write slot 1");
        assert_eq!(nv.flash.erases[0xA], 0, "slot 0's region untouched");
        assert_eq!(nv.flash.erases[0xB], 1);
        let nv = NorNv::new(nv.flash, &LAYOUT);
        nv.read(SLOT_SIZE + 8, &mut b[..3]).expect("read");
        assert_eq!(&b[..3], &[1, 2, 3], "back from the flash");
        assert!(nv.read(STORAGE_SIZE - 1, &mut b).is_err());
    }
}
