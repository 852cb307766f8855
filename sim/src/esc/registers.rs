//! ECAT writes into the register area: write masks and side effects (AL
//! control, SII commands, SM/FMMU reconfiguration, watchdog restart, DC
//! latching and activation).

use super::*;

// The last byte of each multi-byte register (range patterns take named
// constants only, no arithmetic).
const STATION_ADDRESS_LAST: u16 = reg::STATION_ADDRESS + 1;
const DL_CONTROL_LAST: u16 = reg::DL_CONTROL + 3;
const PHYSICAL_RW_OFFSET_LAST: u16 = reg::PHYSICAL_RW_OFFSET + 1;
const ECAT_EVENT_MASK_LAST: u16 = reg::ECAT_EVENT_MASK + 1;
const AL_CONTROL_LAST: u16 = reg::AL_CONTROL + 1;
const LOST_LINK_COUNTER_LAST: u16 = reg::LOST_LINK_COUNTER + 3;
const WATCHDOG_DIVIDER_LAST: u16 = reg::WATCHDOG_DIVIDER + 1;
const WATCHDOG_TIME_PDI_LAST: u16 = reg::WATCHDOG_TIME_PDI + 1;
const WATCHDOG_TIME_PD_LAST: u16 = reg::WATCHDOG_TIME_PD + 1;
/// SII control's high byte: the command bits 8-10.
const SII_CONTROL_COMMAND: u16 = reg::SII_CONTROL + 1;
/// The SII address and data registers and the MII management interface.
const MII_LAST: u16 = reg::MII_CONTROL + 7;
const FMMU_LAST: u16 = reg::FMMU_BASE + 16 * reg::FMMU_LEN - 1;
const SM_LAST: u16 = reg::SM_BASE + 16 * reg::SM_LEN - 1;
const DC_RECEIVE_TIME_PORT0_LAST: u16 = reg::DC_RECEIVE_TIME_PORT0 + 3;
const DC_RECEIVE_TIME_PORT1: u16 = reg::DC_RECEIVE_TIME_PORT0 + 4;
const DC_RECEIVE_TIME_PORT3_LAST: u16 = reg::DC_RECEIVE_TIME_PORT0 + 15;
const DC_SYSTEM_TIME_LAST: u16 = reg::DC_SYSTEM_TIME + 7;
const DC_RECEIVE_TIME_PU_LAST: u16 = reg::DC_RECEIVE_TIME_PU + 7;
const DC_SYSTEM_TIME_DELAY_LAST: u16 = reg::DC_SYSTEM_TIME_DELAY + 3;
const DC_SYSTEM_TIME_DIFF_LAST: u16 = reg::DC_SYSTEM_TIME_DIFF + 3;
const DC_SPEED_COUNTER_START_LAST: u16 = reg::DC_SPEED_COUNTER_START + 1;
const DC_SPEED_COUNTER_DIFF: u16 = reg::DC_SPEED_COUNTER_START + 2;
const DC_SPEED_COUNTER_DIFF_LAST: u16 = reg::DC_SPEED_COUNTER_START + 3;
const DC_SYNC1_STATUS: u16 = reg::DC_SYNC0_STATUS + 1;
/// The last register of the DC unit.
const DC_LAST: u16 = 0x09FF;
const DIGITAL_OUTPUT_LAST: u16 = reg::DIGITAL_OUTPUT + 3;

impl SoftEsc {
    /// Writes into the register area with the ECAT write masks and side
    /// effects (AL control event, SII commands, SM/FMMU reconfiguration).
    pub(super) fn register_write(&mut self, addr: u16, data: &[u8]) {
        let mut touched_sm = 0u16;
        let mut touched_fmmu = 0u16;
        let mut sii_command = false;
        let mut al_control = false;
        let mut dc_latch = false;
        let mut dc_reset = false;
        let mut dc_activation = false;
        // System time received (0x0910..0x0917): value and which bytes.
        let mut dc_received: Option<(u64, u8)> = None;
        for (i, &v) in data.iter().enumerate() {
            let Some(a) = addr.checked_add(i as u16) else {
                break;
            };
            match a {
                reg::STATION_ADDRESS..=STATION_ADDRESS_LAST
                | reg::WRITE_ENABLE..=reg::WRITE_PROTECTION
                | reg::ESC_WRITE_ENABLE..=reg::ESC_WRITE_PROTECTION
                | reg::ESC_RESET_ECAT
                | reg::DL_CONTROL..=DL_CONTROL_LAST
                | reg::PHYSICAL_RW_OFFSET..=PHYSICAL_RW_OFFSET_LAST
                | reg::ECAT_EVENT_MASK..=ECAT_EVENT_MASK_LAST => self.set_u8(a, v),
                reg::AL_CONTROL..=AL_CONTROL_LAST => {
                    self.set_u8(a, v);
                    al_control = true;
                }
                // Error counters: any write clears.
                reg::RX_ERROR_COUNTER..=LOST_LINK_COUNTER_LAST
                | reg::WATCHDOG_COUNTER_PD..=reg::WATCHDOG_COUNTER_PDI => self.set_u8(a, 0),
                reg::WATCHDOG_DIVIDER..=WATCHDOG_DIVIDER_LAST
                | reg::WATCHDOG_TIME_PDI..=WATCHDOG_TIME_PDI_LAST
                | reg::WATCHDOG_TIME_PD..=WATCHDOG_TIME_PD_LAST => {
                    self.set_u8(a, v);
                    self.wd_restart = true;
                }
                reg::SII_CONFIG..=reg::SII_PDI_ACCESS => self.set_u8(a, v),
                reg::SII_CONTROL => {
                    // Bits 1-6 (the silicon's status: read size, ...) are
                    // read-only; bits 0 and 7 writable.
                    let keep = self.mem_u8(a) & 0x7E;
                    self.set_u8(a, (v & 0x81) | keep);
                }
                SII_CONTROL_COMMAND => {
                    // Command bits 8-10; error and busy bits are status.
                    self.set_u8(a, v & 0x07);
                    sii_command = true;
                }
                reg::SII_ADDRESS..=MII_LAST => self.set_u8(a, v),
                reg::FMMU_BASE..=FMMU_LAST => {
                    self.set_u8(a, v);
                    touched_fmmu |= 1 << ((a - reg::FMMU_BASE) / reg::FMMU_LEN);
                }
                reg::SM_BASE..=SM_LAST => {
                    let off = (a - reg::SM_BASE) % reg::SM_LEN;
                    if off != smr::STATUS && off != smr::PDI_CONTROL {
                        self.set_u8(a, v);
                        touched_sm |= 1 << ((a - reg::SM_BASE) / reg::SM_LEN);
                    }
                }
                // Receive times: a write to port 0's latches them all.
                reg::DC_RECEIVE_TIME_PORT0..=DC_RECEIVE_TIME_PORT0_LAST => dc_latch = true,
                // Receive times of ports 1-3 and of the processing unit,
                // the system time difference: read-only.
                DC_RECEIVE_TIME_PORT1..=DC_RECEIVE_TIME_PORT3_LAST
                | reg::DC_RECEIVE_TIME_PU..=DC_RECEIVE_TIME_PU_LAST
                | reg::DC_SYSTEM_TIME_DIFF..=DC_SYSTEM_TIME_DIFF_LAST => {}
                reg::DC_SYSTEM_TIME..=DC_SYSTEM_TIME_LAST => {
                    let (value, mask) = dc_received.unwrap_or((0, 0));
                    let byte = u32::from(a - reg::DC_SYSTEM_TIME);
                    dc_received = Some((value | u64::from(v) << (8 * byte), mask | 1 << byte));
                }
                // Speed counter start: a write resets the drift control
                // (ETG.1020 §22.2.4: masters write 0x0934 then 0x0930 to
                // reset the loop after blanking the DC registers).
                reg::DC_SPEED_COUNTER_START..=DC_SPEED_COUNTER_START_LAST => {
                    self.set_u8(a, v);
                    dc_reset = true;
                }
                // Speed counter difference and SYNC0/1 status: read-only.
                DC_SPEED_COUNTER_DIFF..=DC_SPEED_COUNTER_DIFF_LAST
                | reg::DC_SYNC0_STATUS..=DC_SYNC1_STATUS => {}
                reg::DC_ACTIVATION => {
                    self.set_u8(a, v);
                    dc_activation = true;
                }
                reg::DC_SYSTEM_TIME_OFFSET..=DC_SYSTEM_TIME_DELAY_LAST
                | reg::DC_TIME_FILTER_DEPTH..=DC_LAST
                | reg::DIGITAL_OUTPUT..=DIGITAL_OUTPUT_LAST => self.set_u8(a, v),
                _ => {}
            }
        }
        if al_control {
            if self.mem_u8(reg::ESC_CONFIG) & ESC_CONFIG_DEVICE_EMULATION != 0 {
                // Device emulation (ET1100 Section II, 0x0141 bit 0): an
                // ESC without a firmware (digital I/O terminals, couplers)
                // takes the value written to AL control as its AL status,
                // the acknowledge bit 4 included: real EK1100, EL2828 and
                // EL2889 answer 0x0011 after a master wrote 0x0011
                // (tests/data/captures, the replay oracle).
                let requested = self.mem_u16(reg::AL_CONTROL) & 0x001F;
                self.set_u16(reg::AL_STATUS, requested);
            }
            self.raise_al_event(reg::AL_EVENT_AL_CONTROL);
        }
        if dc_latch {
            self.dc_latch();
        }
        // A time is the low 32 bits at least; all 8 bytes make it 64-bit.
        match dc_received {
            Some((value, 0xFF)) => self.dc_receive(value, 8),
            Some((value, mask)) if mask & 0x0F == 0x0F => self.dc_receive(value, 4),
            _ => {}
        }
        if dc_reset {
            self.dc.reset_control(self.dc_port0_ns);
            self.set_u32(reg::DC_SYSTEM_TIME_DIFF, 0);
            self.set_u16(reg::DC_SPEED_COUNTER_START + 2, 0);
        }
        if dc_activation {
            self.dc_activate();
        }
        if touched_fmmu != 0 {
            self.reload_fmmus();
        }
        if touched_sm != 0 {
            for n in 0..SM_COUNT {
                if touched_sm & (1 << n) != 0 {
                    self.reload_sm(n);
                }
            }
        }
        if sii_command {
            self.sii_execute();
        }
        // After the SII command: an EEPROM reload changes the alias, and
        // addressing must follow it at once.
        self.refresh_address();
    }
}
