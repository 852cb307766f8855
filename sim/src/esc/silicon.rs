//! What the ESC chip itself contributes to its answers, as a profile: its
//! identity registers (0x0000-0x0009), how many FMMUs and SyncManagers it
//! has, whether it has a DC system time, its EEPROM interface's status bits
//! and how long an EEPROM read keeps it busy. None of this is in an ESI or
//! an SII (both describe the device, not the silicon under it), so a twin
//! gets the soft ESC's own profile unless it is given another.
//!
//! The presets come from the datasheets' register tables and, for the
//! figures a datasheet leaves to the EEPROM and the board, from captures of
//! real devices (`tests/data/captures`, ethercrab's repository): an
//! EK1100 (ET1100), an EL2889 and an EL2828 (ET1200 family).

use super::*;

/// An ESC's silicon as the master sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Silicon {
    /// ESC type, 0x0000 (0x11 ET1100, 0x12 ET1200).
    pub esc_type: u8,
    /// ESC revision, 0x0001.
    pub revision: u8,
    /// ESC build, 0x0002.
    pub build: u16,
    /// FMMUs, 0x0004 (writes and reads of the others are not counted).
    pub fmmus: u8,
    /// SyncManagers, 0x0005 (likewise).
    pub sms: u8,
    /// Process RAM in KiB, 0x0006 (`None`: the memory the ESC models).
    pub ram_kib: Option<u8>,
    /// Port descriptor, 0x0007.
    pub port_descriptor: u8,
    /// ESC features, 0x0008.
    pub features: u16,
    /// Whether the DC unit has its system time and the registers after
    /// it (0x0910-0x09FF); without, only the receive times 0x0900-0x090F
    /// answer (an ESC whose DC unit is left out).
    pub dc_system_time: bool,
    /// The EEPROM interface's status bits 0x0502 when idle (bit 6: 8-byte
    /// reads).
    pub sii_status: u16,
    /// How long an EEPROM read keeps the interface busy (bit 15, the read
    /// command bit set), ns; 0 answers at once.
    pub sii_read_ns: u64,
    /// What the receive time registers of port 1 and port 3 (0x0904,
    /// 0x090C) hold until a frame passes the port: Beckhoff's ESCs show
    /// ASCII "hoff" and "Verl" there (the last slave's closed port 1, the
    /// ports an ESC does not have); `None`: zeros.
    pub dc_marks: Option<([u8; 4], [u8; 4])>,
}

impl Silicon {
    /// The soft ESC's own profile: an ET1100's identity with every unit
    /// this simulator models (8 FMMUs, 8 SyncManagers, DC with SYNC0),
    /// EEPROM reads answered at once. The default of every slave.
    pub const SOFT: Silicon = Silicon {
        esc_type: 0x11,
        revision: 0x02,
        build: 0,
        fmmus: FMMU_COUNT as u8,
        sms: SM_COUNT as u8,
        ram_kib: None,
        // Ports 0 and 1 MII, ports 2 and 3 not implemented.
        port_descriptor: 0x0F,
        // Bit-oriented FMMUs, LRW and read/write commands supported; DC
        // receive times and a 64-bit system time (bits 2 and 3) and the
        // SYNC0 unit with the activation registers 0x0981-0x0984 (bit 8,
        // "enhanced DC sync activation"); ETG.1000.4 Table 31. No LATCH
        // inputs and no SYNC1 pulses yet.
        features: 0x010C,
        dc_system_time: true,
        sii_status: 0x0040,
        sii_read_ns: 0,
        dc_marks: None,
    };

    /// An ET1100 (Beckhoff's EK1100 coupler): 8 FMMUs, 8 SyncManagers,
    /// 8 KiB of RAM, ports MII, EBUS, MII, none (0x3B), features 0x00FC,
    /// an EEPROM read busy for 690 us (the EK1100s of the captures were
    /// busy after 675.6 us and idle at 711.4 us; 690 us fits every device
    /// of them).
    pub const ET1100: Silicon = Silicon {
        esc_type: 0x11,
        revision: 0x00,
        build: 0,
        fmmus: 8,
        sms: 8,
        ram_kib: Some(8),
        port_descriptor: 0x3B,
        features: 0x00FC,
        dc_system_time: true,
        sii_status: 0x0040,
        sii_read_ns: 690_000,
        dc_marks: Some((*b"hoff", *b"Verl")),
    };

    /// An ET1200 (Beckhoff's EL2889 terminal): revision 1, 3 FMMUs, 4
    /// SyncManagers, 1 KiB of RAM, ports EBUS, EBUS, none, not configured
    /// (0x4A), features 0x00FC, EEPROM reads as the ET1100's. (The EL2828
    /// and EL1004 of the captures have a variant: features 0x01FC, EEPROM
    /// status 0x0050, no DC system time; `tests/it/replay.rs`.)
    pub const ET1200: Silicon = Silicon {
        esc_type: 0x12,
        revision: 0x01,
        fmmus: 3,
        sms: 4,
        ram_kib: Some(1),
        port_descriptor: 0x4A,
        ..Silicon::ET1100
    };

    /// Whether an access to `a..b` reaches something this silicon has
    /// (the working counter counts it): an FMMU or SyncManager beyond its
    /// count, or the DC unit after the receive times without a system
    /// time, is not there.
    pub(super) fn implements(&self, a: u32, b: u32) -> bool {
        // Every hole lies below the DC registers' end: process data and
        // mailboxes (the hot path) skip the arithmetic.
        if a >= 0x0A00 {
            return true;
        }
        // The register map has room for 16 FMMUs and 16 SyncManagers.
        let holes = [
            (
                u32::from(reg::FMMU_BASE) + u32::from(self.fmmus) * u32::from(reg::FMMU_LEN),
                u32::from(reg::FMMU_BASE) + 16 * u32::from(reg::FMMU_LEN),
            ),
            (
                u32::from(reg::SM_BASE) + u32::from(self.sms) * u32::from(reg::SM_LEN),
                u32::from(reg::SM_BASE) + 16 * u32::from(reg::SM_LEN),
            ),
            if self.dc_system_time {
                (0, 0)
            } else {
                (0x0910, 0x0A00)
            },
        ];
        // Counted when any byte lands on something that exists (the holes
        // are disjoint: the bytes they cover add up).
        let covered: u32 = holes
            .iter()
            .map(|(lo, hi)| b.min(*hi).saturating_sub(a.max(*lo)))
            .sum();
        covered < b.saturating_sub(a)
    }
}

impl Default for Silicon {
    fn default() -> Self {
        Silicon::SOFT
    }
}

impl SoftEsc {
    /// Gives this ESC another silicon profile and powers it on again (its
    /// identity registers and units change; the EEPROM is kept).
    pub fn set_silicon(&mut self, silicon: Silicon) {
        self.silicon = silicon;
        self.power_on();
    }

    /// The ESC's silicon profile.
    pub fn silicon(&self) -> Silicon {
        self.silicon
    }

    /// Ends an EEPROM command whose busy time has passed by `now_ns`.
    pub(super) fn sii_tick(&mut self, now_ns: u64) {
        if let Some(t) = self.sii_busy_until
            && now_ns >= t
        {
            self.sii_busy_until = None;
            let ctrl = self.mem_u16(reg::SII_CONTROL);
            self.set_u16(reg::SII_CONTROL, ctrl & 0x7800 | ctrl & 0x00FF);
        }
    }
}
