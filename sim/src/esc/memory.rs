//! Little-endian access to the ESC memory without side effects, bounds-
//! checked (an address outside reads 0 and writes nothing).

use super::*;

impl SoftEsc {
    pub(super) fn mem_get(&self, addr: u16, out: &mut [u8]) -> bool {
        let a = usize::from(addr);
        match self.mem.get(a..a + out.len()) {
            Some(src) => {
                out.copy_from_slice(src);
                true
            }
            None => false,
        }
    }

    pub(super) fn mem_u8(&self, addr: u16) -> u8 {
        self.mem.get(usize::from(addr)).copied().unwrap_or(0)
    }

    pub(super) fn mem_u16(&self, addr: u16) -> u16 {
        let mut b = [0u8; 2];
        self.mem_get(addr, &mut b);
        u16::from_le_bytes(b)
    }

    pub(super) fn mem_u32(&self, addr: u16) -> u32 {
        let mut b = [0u8; 4];
        self.mem_get(addr, &mut b);
        u32::from_le_bytes(b)
    }

    pub(super) fn mem_u64(&self, addr: u16) -> u64 {
        let mut b = [0u8; 8];
        self.mem_get(addr, &mut b);
        u64::from_le_bytes(b)
    }

    pub(super) fn set_u64(&mut self, addr: u16, v: u64) {
        let a = usize::from(addr);
        if let Some(m) = self.mem.get_mut(a..a + 8) {
            m.copy_from_slice(&v.to_le_bytes());
        }
    }

    pub(super) fn set_u8(&mut self, addr: u16, v: u8) {
        if let Some(m) = self.mem.get_mut(usize::from(addr)) {
            *m = v;
        }
    }

    pub(super) fn set_u16(&mut self, addr: u16, v: u16) {
        let a = usize::from(addr);
        if let Some(m) = self.mem.get_mut(a..a + 2) {
            m.copy_from_slice(&v.to_le_bytes());
        }
    }

    pub(super) fn set_u32(&mut self, addr: u16, v: u32) {
        let a = usize::from(addr);
        if let Some(m) = self.mem.get_mut(a..a + 4) {
            m.copy_from_slice(&v.to_le_bytes());
        }
    }
}
