//! A heap-backed firmware image store for software slaves: the same rules
//! as [`ecat_slave::firmware::MemStore`] (erase to 0xFF, writes clear bits, two
//! boot-state copies) with slots of any size on the heap. Slots grow as
//! they are written, so memory follows use, not capacity.

use ecat_slave::firmware::{BootState, ImageStore, STATE_RECORD_LEN, Slot, StoreError};

/// Two image slots of `capacity` bytes each, on the heap.
#[derive(Debug, Clone)]
pub struct VecStore {
    capacity: usize,
    slots: [Vec<u8>; 2],
    state: [[u8; STATE_RECORD_LEN]; 2],
}

impl VecStore {
    /// Blank slots of `capacity` bytes each, no boot state.
    pub fn new(capacity: usize) -> Self {
        VecStore {
            capacity,
            slots: [Vec::new(), Vec::new()],
            state: [[0; STATE_RECORD_LEN]; 2],
        }
    }

    fn slot(&self, slot: Slot) -> &Vec<u8> {
        match slot {
            Slot::A => &self.slots[0],
            Slot::B => &self.slots[1],
        }
    }

    fn slot_mut(&mut self, slot: Slot) -> &mut Vec<u8> {
        match slot {
            Slot::A => &mut self.slots[0],
            Slot::B => &mut self.slots[1],
        }
    }
}

impl ImageStore for VecStore {
    fn slot_capacity(&self) -> usize {
        self.capacity
    }

    fn erase(&mut self, slot: Slot) -> Result<(), StoreError> {
        // Erased bytes read 0xFF; beyond the stored length everything does.
        self.slot_mut(slot).clear();
        Ok(())
    }

    fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError> {
        let cap = self.capacity;
        let end = offset
            .checked_add(data.len())
            .ok_or(StoreError::OutOfBounds)?;
        if end > cap {
            return Err(StoreError::OutOfBounds);
        }
        let s = self.slot_mut(slot);
        if s.len() < end {
            s.resize(end, 0xFF);
        }
        let dst = s.get_mut(offset..end).ok_or(StoreError::OutOfBounds)?;
        for (d, v) in dst.iter_mut().zip(data) {
            *d &= *v;
        }
        Ok(())
    }

    fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError> {
        if offset > self.capacity {
            return Err(StoreError::OutOfBounds);
        }
        let n = buf.len().min(self.capacity - offset);
        let s = self.slot(slot);
        for (i, b) in buf.iter_mut().take(n).enumerate() {
            *b = s.get(offset + i).copied().unwrap_or(0xFF);
        }
        Ok(n)
    }

    fn read_state(&self) -> Result<BootState, StoreError> {
        let [a, b] = &self.state;
        BootState::read_bank([a, b])
            .map(|(_, s)| s)
            .ok_or(StoreError::NoState)
    }

    fn write_state(&mut self, state: &BootState) -> Result<(), StoreError> {
        let [a, b] = &self.state;
        let (index, record) = BootState::bank_write([a, b], state);
        if let Some(slot) = self.state.get_mut(index) {
            *slot = record;
        }
        Ok(())
    }
}
