//! ESC register map (ETG.1000.4 clause 6, ET1100 datasheet section II).
//!
//! Every register the stack touches is a constant here with its width and
//! meaning. Per-instance blocks (SyncManager n, FMMU n) come from functions
//! returning `Option`, never panicking on an index from outside.

/// Type of the ESC (1 byte). Reported as 0x11 like an ET1100-class device.
pub const TYPE: u16 = 0x0000;
/// Revision (1 byte).
pub const REVISION: u16 = 0x0001;
/// Build (2 bytes).
pub const BUILD: u16 = 0x0002;
/// Number of FMMUs supported (1 byte).
pub const FMMU_COUNT: u16 = 0x0004;
/// Number of SyncManagers supported (1 byte).
pub const SM_COUNT: u16 = 0x0005;
/// Process RAM size in KiB (1 byte).
pub const RAM_SIZE: u16 = 0x0006;
/// Port descriptor (1 byte, 2 bits per port: 0 not implemented, 3 MII).
pub const PORT_DESCRIPTOR: u16 = 0x0007;
/// ESC features supported (2 bytes). Bit 2 = distributed clocks (the
/// software ESC sets it: its DC unit is emulated, see `esc::dc`).
pub const FEATURES: u16 = 0x0008;
/// Configured station address (2 bytes, written by the master).
pub const STATION_ADDRESS: u16 = 0x0010;
/// Configured station alias (2 bytes, loaded from SII word 4).
pub const STATION_ALIAS: u16 = 0x0012;
/// Write register enable (1 byte).
pub const WRITE_ENABLE: u16 = 0x0020;
/// Write register protection (1 byte).
pub const WRITE_PROTECTION: u16 = 0x0021;
/// ESC write enable (1 byte).
pub const ESC_WRITE_ENABLE: u16 = 0x0030;
/// ESC write protection (1 byte).
pub const ESC_WRITE_PROTECTION: u16 = 0x0031;
/// ESC reset ECAT (1 byte).
pub const ESC_RESET_ECAT: u16 = 0x0040;
/// ESC DL control (4 bytes).
pub const DL_CONTROL: u16 = 0x0100;
/// Physical read/write offset (2 bytes).
pub const PHYSICAL_RW_OFFSET: u16 = 0x0108;
/// ESC DL status (2 bytes): bit 0 PDI operational, bit 1 PDI watchdog
/// status (1 = reloaded / not expired), bit 2 enhanced link detection,
/// bit 4 + n physical link on port n, bit 8 + 2n loop port n, bit 9 + 2n
/// communication on port n.
pub const DL_STATUS: u16 = 0x0110;

/// Bits of [`DL_STATUS`] (ET1100 Section II, register 0x0110).
pub mod dl_status {
    /// PDI operational (the EEPROM was loaded).
    pub const PDI_OPERATIONAL: u16 = 0x0001;
    /// PDI watchdog status: 1 = reloaded / not expired.
    pub const PDI_WATCHDOG_OK: u16 = 0x0002;
    /// Physical link on port `n` (0..=3).
    pub const fn link(n: u8) -> u16 {
        0x0010 << (n & 3)
    }
    /// Loop of port `n` closed (0..=3).
    pub const fn loop_closed(n: u8) -> u16 {
        0x0100 << (2 * (n & 3))
    }
    /// Communication established on port `n` (0..=3).
    pub const fn communication(n: u8) -> u16 {
        0x0200 << (2 * (n & 3))
    }
}
/// AL control (2 bytes, written by the master): bits 0-3 requested state,
/// bit 4 error acknowledge, bit 5 device identification.
pub const AL_CONTROL: u16 = 0x0120;
/// AL status (2 bytes, written by the PDI): bits 0-3 state, bit 4 error,
/// bit 5 device identification loaded.
pub const AL_STATUS: u16 = 0x0130;
/// AL status code (2 bytes, written by the PDI).
pub const AL_STATUS_CODE: u16 = 0x0134;
/// RUN LED override (1 byte).
pub const RUN_LED_OVERRIDE: u16 = 0x0138;
/// ERR LED override (1 byte).
pub const ERR_LED_OVERRIDE: u16 = 0x0139;
/// PDI control (1 byte): 0x05 = SPI, 0x80 = on-chip bus.
pub const PDI_CONTROL: u16 = 0x0140;
/// ESC configuration (1 byte).
pub const ESC_CONFIG: u16 = 0x0141;
/// PDI configuration (2 bytes).
pub const PDI_CONFIG: u16 = 0x0150;
/// ECAT event mask (2 bytes).
pub const ECAT_EVENT_MASK: u16 = 0x0200;
/// AL event mask (4 bytes, PDI side).
pub const AL_EVENT_MASK: u16 = 0x0204;
/// ECAT event request (2 bytes, read-only to the master).
pub const ECAT_EVENT_REQUEST: u16 = 0x0210;
/// AL event request (4 bytes, PDI side): bit 0 AL control written,
/// bit 8 + n SyncManager n event.
pub const AL_EVENT_REQUEST: u16 = 0x0220;
/// RX error counters, ports 0-3 (8 bytes; a write clears them).
pub const RX_ERROR_COUNTER: u16 = 0x0300;
/// Forwarded RX error counters, ports 0-3 (4 bytes; a write clears them).
pub const FORWARDED_RX_ERROR_COUNTER: u16 = 0x0308;
/// ECAT processing unit error counter (1 byte) and PDI error counter (1 byte).
pub const PROCESSING_ERROR_COUNTER: u16 = 0x030C;
/// Lost link counters, ports 0-3 (4 bytes; a write clears them).
pub const LOST_LINK_COUNTER: u16 = 0x0310;
/// Watchdog divider (2 bytes): base tick = (value + 2) x 40 ns.
pub const WATCHDOG_DIVIDER: u16 = 0x0400;
/// PDI watchdog time in base ticks (2 bytes, 0 disables).
pub const WATCHDOG_TIME_PDI: u16 = 0x0410;
/// SyncManager (process data) watchdog time in base ticks (2 bytes, 0 disables).
pub const WATCHDOG_TIME_PD: u16 = 0x0420;
/// Watchdog status process data (2 bytes): bit 0 = 1 while not expired.
pub const WATCHDOG_STATUS_PD: u16 = 0x0440;
/// Watchdog counter process data (1 byte).
pub const WATCHDOG_COUNTER_PD: u16 = 0x0442;
/// Watchdog counter PDI (1 byte).
pub const WATCHDOG_COUNTER_PDI: u16 = 0x0443;
/// EEPROM configuration (1 byte): bit 0 = PDI owns the EEPROM.
pub const SII_CONFIG: u16 = 0x0500;
/// EEPROM PDI access state (1 byte).
pub const SII_PDI_ACCESS: u16 = 0x0501;
/// EEPROM control/status (2 bytes): bit 0 write enable, bit 5 emulation,
/// bit 6 read size (1 = 8 bytes, read-only), bit 7 address algorithm,
/// bits 8-10 command (read 1, write 2, reload 4), bits 11-14 errors,
/// bit 15 busy.
pub const SII_CONTROL: u16 = 0x0502;
/// EEPROM address in words (4 bytes).
pub const SII_ADDRESS: u16 = 0x0504;
/// EEPROM data (8 bytes: 4 or 8 valid after a read).
pub const SII_DATA: u16 = 0x0508;
/// MII management control/status (2 bytes).
pub const MII_CONTROL: u16 = 0x0510;
/// First FMMU register block; 16 bytes each.
pub const FMMU_BASE: u16 = 0x0600;
/// Size of one FMMU register block.
pub const FMMU_LEN: u16 = 16;
/// First SyncManager register block; 8 bytes each.
pub const SM_BASE: u16 = 0x0800;
/// Size of one SyncManager register block.
pub const SM_LEN: u16 = 8;
/// Receive time port 0 (4 bytes), first DC register.
pub const DC_RECEIVE_TIME_PORT0: u16 = 0x0900;
/// Last DC register (SYNC1 cycle time, 4 bytes at 0x09A4).
pub const DC_SYNC1_CYCLE_TIME: u16 = 0x09A4;
/// DC system time (u64; ECAT read: local time + offset; ECAT write: a
/// distributed reference time for the drift control).
pub const DC_SYSTEM_TIME: u16 = 0x0910;
/// DC receive time of the ECAT processing unit (u64, local time).
pub const DC_RECEIVE_TIME_PU: u16 = 0x0918;
/// DC system time offset (u64, local time → system time).
pub const DC_SYSTEM_TIME_OFFSET: u16 = 0x0920;
/// DC system time (transmission) delay (u32, ns).
pub const DC_SYSTEM_TIME_DELAY: u16 = 0x0928;
/// DC system time difference (u32: bit 31 sign, 30..0 magnitude).
pub const DC_SYSTEM_TIME_DIFF: u16 = 0x092C;
/// DC speed counter start (u16).
pub const DC_SPEED_COUNTER_START: u16 = 0x0930;
/// DC system time difference filter depth (low nibble).
pub const DC_TIME_FILTER_DEPTH: u16 = 0x0934;
/// DC speed counter filter depth (low nibble).
pub const DC_SPEED_FILTER_DEPTH: u16 = 0x0935;
/// DC cyclic unit control (u8: bit 0 SYNC out unit controlled by PDI).
pub const DC_CYCLIC_UNIT_CONTROL: u16 = 0x0980;
/// DC activation (u8): bit 0 cyclic operation, bit 1 SYNC0, bit 2 SYNC1.
pub const DC_ACTIVATION: u16 = 0x0981;
/// DC SYNC signal pulse length (u16, units of 10 ns; 0: acknowledge mode).
pub const DC_PULSE_LENGTH: u16 = 0x0982;
/// DC SYNC0 status (u8, bit 0: a SYNC0 pulse occurred; a read clears it).
pub const DC_SYNC0_STATUS: u16 = 0x098E;
/// DC start time of cyclic operation (u64, system time; read: the next
/// SYNC0 pulse).
pub const DC_START_TIME: u16 = 0x0990;
/// DC SYNC0 cycle time (u32, ns; 0: a single pulse).
pub const DC_SYNC0_CYCLE_TIME: u16 = 0x09A0;
/// Digital I/O output data (4 bytes).
pub const DIGITAL_OUTPUT: u16 = 0x0F00;
/// Start of process RAM.
pub const PROCESS_RAM: u16 = 0x1000;

/// Offsets inside an FMMU block (ETG.1000.4 table 57).
pub mod fmmu {
    /// Logical start address (4 bytes).
    pub const LOGICAL_START: u16 = 0;
    /// Length in bytes (2 bytes).
    pub const LENGTH: u16 = 4;
    /// Logical start bit (1 byte, 0-7).
    pub const LOGICAL_START_BIT: u16 = 6;
    /// Logical stop bit (1 byte, 0-7).
    pub const LOGICAL_STOP_BIT: u16 = 7;
    /// Physical start address (2 bytes).
    pub const PHYSICAL_START: u16 = 8;
    /// Physical start bit (1 byte).
    pub const PHYSICAL_START_BIT: u16 = 10;
    /// Type (1 byte): bit 0 read, bit 1 write.
    pub const TYPE: u16 = 11;
    /// Activate (1 byte): bit 0 enable.
    pub const ACTIVATE: u16 = 12;
}

/// Offsets inside a SyncManager block (ETG.1000.4 table 58).
pub mod sm {
    /// Physical start address (2 bytes).
    pub const START: u16 = 0;
    /// Length in bytes (2 bytes).
    pub const LENGTH: u16 = 2;
    /// Control (1 byte): bits 0-1 mode (0 buffered, 2 mailbox), bits 2-3
    /// direction (0 ECAT reads, 1 ECAT writes), bit 4 ECAT event, bit 5 AL
    /// event, bit 6 watchdog trigger.
    pub const CONTROL: u16 = 4;
    /// Status (1 byte, read-only to the master): bit 0 write event, bit 1
    /// read event, bit 3 mailbox full, bits 4-5 last buffer written.
    pub const STATUS: u16 = 5;
    /// Activate (1 byte): bit 0 enable, bit 1 repeat request.
    pub const ACTIVATE: u16 = 6;
    /// PDI control (1 byte, read-only to the master): bit 0 deactivate,
    /// bit 1 repeat acknowledge.
    pub const PDI_CONTROL: u16 = 7;

    /// Control: mailbox mode.
    pub const MODE_MAILBOX: u8 = 0x02;
    /// Control: ECAT writes (master to slave).
    pub const DIR_ECAT_WRITE: u8 = 0x04;
    /// Control: watchdog trigger enable.
    pub const WATCHDOG_TRIGGER: u8 = 0x40;
    /// Status: mailbox full.
    pub const STATUS_MAILBOX_FULL: u8 = 0x08;
    /// Status: write event (buffer written by ECAT).
    pub const STATUS_WRITE_EVENT: u8 = 0x01;
    /// Status: read event (buffer read by ECAT).
    pub const STATUS_READ_EVENT: u8 = 0x02;
    /// Activate: enable.
    pub const ACTIVATE_ENABLE: u8 = 0x01;
    /// Activate: repeat request.
    pub const ACTIVATE_REPEAT: u8 = 0x02;
    /// PDI control: deactivate.
    pub const PDI_DEACTIVATE: u8 = 0x01;
    /// PDI control: repeat acknowledge.
    pub const PDI_REPEAT_ACK: u8 = 0x02;
}

/// AL event request bit for "AL control written".
pub const AL_EVENT_AL_CONTROL: u32 = 0x0000_0001;

/// AL event request bit 4, "SyncManager activation register changed"
/// (ET1100 datasheet section II, register 0x0220; cleared when the PDI
/// reads a SyncManager's activation register, offset 6).
pub const AL_EVENT_SM_CHANGED: u32 = 0x0000_0010;

/// AL event request bit 2: DC SYNC0 status (cleared by reading 0x098E).
pub const AL_EVENT_SYNC0: u32 = 0x0000_0004;

/// AL event request bit 6, "watchdog process data expired" (cleared when
/// the PDI reads the watchdog status 0x0440).
pub const AL_EVENT_WATCHDOG_PD: u32 = 0x0000_0040;

/// Address of FMMU block `n`, if `n` is one of the 16 possible FMMUs.
pub const fn fmmu(n: u8) -> Option<u16> {
    if n < 16 {
        Some(FMMU_BASE + n as u16 * FMMU_LEN)
    } else {
        None
    }
}

/// Address of SyncManager block `n`, if `n` is one of the 16 possible SMs.
pub const fn sm(n: u8) -> Option<u16> {
    if n < 16 {
        Some(SM_BASE + n as u16 * SM_LEN)
    } else {
        None
    }
}

/// AL event request bit of SyncManager `n` (n < 16), else 0.
pub const fn al_event_sm(n: u8) -> u32 {
    if n < 16 { 1 << (8 + n as u32) } else { 0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sm_and_fmmu_blocks_are_addressed_without_panicking() {
        assert_eq!(sm(0), Some(0x0800));
        assert_eq!(sm(3), Some(0x0818));
        assert_eq!(sm(16), None);
        assert_eq!(fmmu(1), Some(0x0610));
        assert_eq!(fmmu(255), None);
        assert_eq!(al_event_sm(2), 0x400);
        assert_eq!(al_event_sm(40), 0);
    }
}
