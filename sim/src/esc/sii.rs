//! The SII EEPROM interface (0x0500-0x050F): read, write and reload commands
//! on the image the ESC holds.

use super::*;

impl SoftEsc {
    /// Executes the command written into SII control 0x0503.
    pub(super) fn sii_execute(&mut self) {
        let ctrl = self.mem_u16(reg::SII_CONTROL);
        let cmd = (ctrl >> 8) & 0x07;
        // Error bits (11-14) and busy (15) are cleared by every command.
        let mut status = ctrl & 0x00FF;
        let word = self.mem_u32(reg::SII_ADDRESS);
        match cmd {
            0 => {}
            1 => {
                // Read: 8 bytes (bit 6) from the word address. A silicon
                // with an EEPROM read time stays busy (bit 15, the command
                // bits set) until the frames' time has passed it.
                if self.silicon.sii_read_ns > 0 {
                    status |= 0x8000 | 0x0100;
                    self.sii_busy_until =
                        Some(self.dc_port0_ns.saturating_add(self.silicon.sii_read_ns));
                }
                let mut data = [0xFFu8; 8];
                if let Ok(w) = usize::try_from(word) {
                    for (i, d) in data.iter_mut().enumerate() {
                        if let Some(v) = w.checked_mul(2).and_then(|b| self.sii.get(b + i)) {
                            *d = *v;
                        }
                    }
                }
                for (i, d) in data.iter().enumerate() {
                    self.set_u8(reg::SII_DATA + i as u16, *d);
                }
            }
            2 => {
                // Write one word, only with write access enabled (bit 0).
                let lo = self.mem_u8(reg::SII_DATA);
                let hi = self.mem_u8(reg::SII_DATA + 1);
                let slot = usize::try_from(word)
                    .ok()
                    .and_then(|w| w.checked_mul(2))
                    .filter(|b| b + 1 < self.sii.len());
                match (ctrl & 0x0001 != 0, slot) {
                    (true, Some(b)) => {
                        if let Some(s) = self.sii.get_mut(b..b + 2) {
                            s.copy_from_slice(&[lo, hi]);
                        }
                    }
                    // Command error (bit 13).
                    _ => status |= 0x2000,
                }
            }
            4 => {
                // Reload: refresh the alias from word 4.
                let alias = self.sii_word(4);
                self.set_u16(reg::STATION_ALIAS, alias);
            }
            _ => status |= 0x2000,
        }
        self.set_u16(reg::SII_CONTROL, status);
    }

    pub(super) fn sii_word(&self, word: usize) -> u16 {
        let lo = self.sii.get(word * 2).copied().unwrap_or(0xFF);
        let hi = self.sii.get(word * 2 + 1).copied().unwrap_or(0xFF);
        u16::from_le_bytes([lo, hi])
    }
}
