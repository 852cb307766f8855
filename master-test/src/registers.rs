//! ESC registers the test master reads and writes, by name.
//!
//! Addresses come from ethercrab's own register list
//! ([`ethercrab::RegisterAddress`], ETG.1000.4 Table 31) wherever it names
//! one; the few it does not name are local constants here, each with its
//! ETG.1000.4 reference. Never from the slave's register map
//! (`ecat_pdi` / `ecat_slave::esc::registers`): the test master must not
//! share encoding knowledge with the slave it tests, or a wrong address
//! would be wrong at both ends and pass.
//!
//! Layer: a leaf of `master-test` (constants only, no I/O).

use ethercrab::RegisterAddress as R;

/// ESC type, `u8` (0x0000; revision and build follow).
pub const TYPE: u16 = R::Type as u16;
/// Configured station address, `u16` (0x0010).
pub const STATION_ADDRESS: u16 = R::ConfiguredStationAddress as u16;
/// Configured station alias, `u16` (0x0012; loaded from SII word 4).
pub const STATION_ALIAS: u16 = R::ConfiguredStationAlias as u16;
/// Port 0's invalid frame counter, `u8` (0x0300, the first of the RX
/// error counters of ports 0-3; a write clears them). ethercrab does not
/// name it.
pub const RX_ERROR_COUNTER: u16 = 0x0300;
/// ESC configuration, `u8` (0x0141, loaded from SII word 0's high
/// byte): bit 0 "device emulation", the AL status follows AL control
/// without a firmware (ESC-only devices such as digital I/O terminals).
/// ethercrab does not name it.
pub const ESC_CONFIGURATION: u16 = 0x0141;
/// DL status, `u16` (0x0110, ETG.1000.4 Table 34).
pub const DL_STATUS: u16 = R::DlStatus as u16;
/// AL control, `u16` (0x0120, ETG.1000.4 Table 35): requested state,
/// bit 4 acknowledges an error.
pub const AL_CONTROL: u16 = R::AlControl as u16;
/// AL status, `u16` (0x0130, ETG.1000.4 Table 35): state, bit 4 the
/// error flag.
pub const AL_STATUS: u16 = R::AlStatus as u16;
/// AL status code, `u16` (0x0134).
pub const AL_STATUS_CODE: u16 = R::AlStatusCode as u16;
/// Watchdog divider, `u16` (0x0400).
pub const WATCHDOG_DIVIDER: u16 = R::WatchdogDivider as u16;
/// SyncManager watchdog time, `u16` (0x0420).
pub const SM_WATCHDOG: u16 = R::SyncManagerWatchdog as u16;
/// SII EEPROM control/status, `u16` (0x0502).
pub const SII_CONTROL: u16 = R::SiiControl as u16;
/// SII EEPROM word address, `u32` (0x0504).
pub const SII_ADDRESS: u16 = R::SiiAddress as u16;
/// SII EEPROM data, 4 or 8 bytes read, 2 bytes written (0x0508).
pub const SII_DATA: u16 = R::SiiData as u16;
/// DC receive time of port 0, `u32` (0x0900; a write latches every
/// port's receive time).
pub const DC_TIME_PORT0: u16 = R::DcTimePort0 as u16;
/// DC system time (64 bit): the reference clock's time, which a master
/// distributes with FRMW or ARMW.
pub const DC_SYSTEM_TIME: u16 = R::DcSystemTime as u16;

/// Bytes of one FMMU's register block (ETG.1000.4 Table 57).
pub const FMMU_LEN: u16 = 16;
/// Bytes of one SyncManager's register block (ETG.1000.4 Table 59).
pub const SM_LEN: u16 = 8;
/// Most FMMUs and most SyncManagers an ESC has.
pub const MAX_UNITS: u8 = 16;

/// Offset of a SyncManager's status byte in its block (mailbox full,
/// buffer state).
pub const SM_STATUS: u16 = 5;
/// Offset of a SyncManager's activate byte (enable, repeat request).
pub const SM_ACTIVATE: u16 = 6;
/// Offset of a SyncManager's PDI control byte (deactivate, repeat ack).
pub const SM_PDI_CONTROL: u16 = 7;

/// The register block of FMMU `n` (0x0600 + 16·n); `None` past the 16 an
/// ESC can have.
pub const fn fmmu(n: u8) -> Option<u16> {
    if n < MAX_UNITS {
        Some(R::Fmmu0 as u16 + FMMU_LEN * n as u16)
    } else {
        None
    }
}

/// The register block of SyncManager `n` (0x0800 + 8·n); `None` past
/// the 16 an ESC can have.
pub const fn sm(n: u8) -> Option<u16> {
    if n < MAX_UNITS {
        Some(R::Sm0 as u16 + SM_LEN * n as u16)
    } else {
        None
    }
}

/// FMMU 0 (the first FMMU's block).
pub const FMMU0: u16 = R::Fmmu0 as u16;
/// FMMU 1.
pub const FMMU1: u16 = R::Fmmu1 as u16;
/// SyncManager 0 (mailbox out, master to slave).
pub const SM0: u16 = R::Sm0 as u16;
/// SyncManager 1 (mailbox in, slave to master).
pub const SM1: u16 = R::Sm1 as u16;
/// SyncManager 2 (outputs).
pub const SM2: u16 = R::Sm2 as u16;
/// SyncManager 3 (inputs).
pub const SM3: u16 = R::Sm3 as u16;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_names_are_the_etg_addresses() {
        // ETG.1000.4 Table 31, as a reader of the standard writes them.
        assert_eq!(
            [AL_CONTROL, AL_STATUS, AL_STATUS_CODE, DL_STATUS],
            [0x0120, 0x0130, 0x0134, 0x0110]
        );
        assert_eq!([STATION_ADDRESS, STATION_ALIAS, TYPE], [0x0010, 0x0012, 0]);
        assert_eq!(
            [SII_CONTROL, SII_ADDRESS, SII_DATA],
            [0x0502, 0x0504, 0x0508]
        );
        assert_eq!([WATCHDOG_DIVIDER, SM_WATCHDOG], [0x0400, 0x0420]);
        assert_eq!([SM0, SM1, SM2, SM3], [0x0800, 0x0808, 0x0810, 0x0818]);
        assert_eq!(DC_TIME_PORT0, 0x0900);
    }

    #[test]
    fn unit_blocks_exist_for_16_units_and_no_more() {
        assert_eq!(sm(1), Some(0x0808));
        assert_eq!(sm(15), Some(0x0878));
        assert_eq!(sm(16), None);
        assert_eq!(sm(u8::MAX), None);
        assert_eq!(fmmu(1), Some(0x0610));
        assert_eq!(fmmu(15), Some(0x06F0));
        assert_eq!(fmmu(16), None);
        // ethercrab's own per-unit names agree.
        for n in 0..MAX_UNITS {
            assert_eq!(sm(n), Some(u16::from(R::sync_manager(n))));
            assert_eq!(fmmu(n), Some(u16::from(R::fmmu(n))));
        }
        assert_eq!(
            SM1 + SM_STATUS,
            R::sync_manager_status(1),
            "ethercrab's SM status offset"
        );
    }
}
