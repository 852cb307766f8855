//! The object dictionary of the PAM-199-P-ETC: the one static description.
//! Built with the core's entry constructors ([`ecat_slave::od::build`])
//! and its [`ecat_slave::dictionary!`] macro; the device's
//! [`crate::DEVICE`] description refers to [`DICT`].
//!
//! Every object and subindex of the manual's tables 6.1.1-6.1.7, with the
//! ranges of chapters 6.2-6.4, plus the ETG objects the manual does not list
//! (0x10F8, 0x1C00, 0x1C12, 0x1C13, 0xF000). The ESI, the SII, SDO
//! Information, the PDO mapping and the application all read [`OBJECTS`] and
//! [`ENUMS`] (through [`DICT`]); every choice made where the manual is damaged or contradicts
//! itself is recorded in `docs/MANUAL-NOTES.md` (cited as "note n" below).
//!
//! Layout rule for blank subindices (note 20): in a parameter or process-data
//! record, a blank subindex after a bit-sized entry is a padding [`Entry`]
//! (`gap: true`, `BITn`) that fills up to the next byte boundary of the
//! record's packed layout (subindex 1 upwards); a blank subindex at a byte
//! boundary is absent. In PDO mapping objects a blank row is a padding
//! mapping `0x000000nn`.
//!
//! The enumeration types 0x0800-0x0805 are data types, not objects: they are
//! in [`ENUMS`], not in [`OBJECTS`] (note 19).

use DataType::{Bool, Int16, Int32, UInt8, UInt16, UInt32};
use ObjectCode::{Array, Record, Var};
use PdoMapping::None as NoPdo;
use ecat_slave::od::build::{
    SYNC_PARAMETER_ENTRIES, assign, assign_count, base, constant, gap, input, map, output, pad,
    ranged, setting, string, sub_name, sub0, var,
};
use ecat_slave::od::{Access, DataType, Entry, EnumDesc, Limits, Object, ObjectCode, PdoMapping};

// ---------------------------------------------------------------------------
// Enumeration data types (manual 6.1.7)
// ---------------------------------------------------------------------------

/// DT0800EN03, module function (F800:02 FUNCTION).
pub const DT0800EN03: EnumDesc = EnumDesc {
    index: 0x0800,
    name: "DT0800EN03",
    bit_len: 3,
    values: &[(1, "DIRECTIONAL"), (2, "INDEPENDENT")],
};

/// DT0801EN03, failure monitoring (F800:03 SENS).
pub const DT0801EN03: EnumDesc = EnumDesc {
    index: 0x0801,
    name: "DT0801EN03",
    bit_len: 3,
    values: &[(1, "OFF"), (2, "ON"), (3, "AUTO")],
};

/// DT0802EN03, binary parameters (CCMODE, ACC).
pub const DT0802EN03: EnumDesc = EnumDesc {
    index: 0x0802,
    name: "DT0802EN03",
    bit_len: 3,
    values: &[(0, "OFF"), (1, "ON")],
};

/// DT0803EN05, PWM frequency table (PWM); texts are the frequency in Hz
/// as the manual names them, values the device's codes (note 13).
pub const DT0803EN05: EnumDesc = EnumDesc {
    index: 0x0803,
    name: "DT0803EN05",
    bit_len: 5,
    values: &[
        (0x11, "60"),
        (0x0E, "70"),
        (0x0B, "80"),
        (0x08, "100"),
        (0x05, "120"),
        (0x02, "150"),
        (0x13, "200"),
        (0x10, "250"),
        (0x0D, "400"),
        (0x0A, "500"),
        (0x07, "600"),
        (0x04, "800"),
        (0x01, "1000"),
        (0x12, "1200"),
        (0x0F, "1500"),
        (0x0C, "2000"),
        (0x09, "2500"),
        (0x06, "3000"),
        (0x03, "6000"),
        (0x14, "10000"),
    ],
};

/// DT0804EN03, LIN/SIN (defined by the manual, used by no object).
pub const DT0804EN03: EnumDesc = EnumDesc {
    index: 0x0804,
    name: "DT0804EN03",
    bit_len: 3,
    values: &[(0, "LIN"), (1, "SIN")],
};

/// DT0805EN03, overlap compensation type (MMTYPE).
pub const DT0805EN03: EnumDesc = EnumDesc {
    index: 0x0805,
    name: "DT0805EN03",
    bit_len: 3,
    values: &[(0, "JMP"), (1, "LIN")],
};

/// Every enumeration data type, ascending by index.
pub const ENUMS: &[&EnumDesc] = &[
    &DT0800EN03,
    &DT0801EN03,
    &DT0802EN03,
    &DT0803EN05,
    &DT0804EN03,
    &DT0805EN03,
];

/// DT0803EN05 code of 2500 Hz, the PWM default (note 12).
const PWM_2500_HZ: i64 = 0x09;

// ---------------------------------------------------------------------------
// Entry constructors
// ---------------------------------------------------------------------------

/// A TxPDO-mappable solenoid current in mA.
const fn current(sub: u8, name: &'static str) -> Entry {
    Entry {
        limits: &Limits {
            min: None,
            max: None,
            unit: "mA",
            default: None,
        },
        ..input(sub, name, DataType::UInt16)
    }
}

/// An enumerated setting: the enumeration's values are its range.
const fn choice(sub: u8, name: &'static str, e: &'static EnumDesc, default: i64) -> Entry {
    setting(sub, name, e.data_type(), default, &Limits::NONE)
}

/// The PWM frequency setting (DT0803EN05, unit Hz, default 2500 Hz).
const fn pwm(sub: u8, name: &'static str) -> Entry {
    Entry {
        limits: &Limits {
            min: None,
            max: None,
            unit: "Hz",
            default: None,
        },
        ..choice(sub, name, &DT0803EN05, PWM_2500_HZ)
    }
}

/// Type, range and unit of a kind of parameter (manual 6.2-6.4).
#[derive(Clone, Copy)]
struct Kind {
    data_type: DataType,
    limits: &'static Limits,
}

const fn kind(data_type: DataType, limits: &'static Limits) -> Kind {
    Kind { data_type, limits }
}

/// Unit of percentages ("0,01 %" in the manual).
const PCT: &str = "0.01 %";
/// RA (6.3.1): 1 ... 120000 ms.
const RA: Kind = kind(DataType::UInt32, &Limits::range(1, 120_000, "ms"));
/// TRIGGER (6.3.5): 0 ... 3000.
const TRIGGER: Kind = kind(DataType::UInt16, &Limits::range(0, 3000, PCT));
/// MIN (6.3.6): 0 ... 6000.
const MIN: Kind = kind(DataType::UInt16, &Limits::range(0, 6000, PCT));
/// MAX (6.3.7): 5000 ... 10000.
const MAX: Kind = kind(DataType::UInt16, &Limits::range(5000, 10_000, PCT));
/// CURRENT (6.4.1): 500 ... 3000 mA.
const CURRENT: Kind = kind(DataType::UInt16, &Limits::range(500, 3000, "mA"));
/// DAMPL (6.4.2): 0 ... 3000.
const DAMPL: Kind = kind(DataType::UInt16, &Limits::range(0, 3000, PCT));
/// DFREQ (6.4.3): 50 ... 400 Hz.
const DFREQ: Kind = kind(DataType::UInt16, &Limits::range(50, 400, "Hz"));
/// PPWM (6.4.6): 0 ... 300.
const PPWM: Kind = kind(DataType::UInt16, &Limits::range(0, 300, ""));
/// IPWM (6.4.7): 0 ... 100.
const IPWM: Kind = kind(DataType::UInt16, &Limits::range(0, 100, ""));
/// IO_BASE (6.2.1): 100 ... 32767.
const IO_BASE: Kind = kind(DataType::UInt16, &Limits::range(100, 32_767, ""));
/// CC curve points, directional (6.3.3): -10000 ... 10000.
const CC_DIR: Kind = kind(DataType::Int16, &Limits::range(-10_000, 10_000, PCT));
/// CC curve points, independent (6.3.3): 0 ... 10000.
const CC_IND: Kind = kind(DataType::Int16, &Limits::range(0, 10_000, PCT));

/// A stored device setting with the type, range and unit of `kind`.
const fn param(sub: u8, name: &'static str, default: i64, kind: Kind) -> Entry {
    ranged(sub, name, kind.data_type, default, kind.limits)
}

/// A command of 0xF801 (UDINT, not stored).
const fn command(sub: u8, name: &'static str, access: Access) -> Entry {
    base(sub, name, DataType::UInt32, access, PdoMapping::None, 0)
}

// ---------------------------------------------------------------------------
// The objects
// ---------------------------------------------------------------------------

/// Every object of the dictionary, strictly ascending by index.
#[rustfmt::skip]
pub const OBJECTS: &[Object] = &[
    // --- 6.1.1 communication parameters -----------------------------------
    Object { index: 0x1000, name: "DEVICE TYPE", code: Var, entries: &[
        var("DEVICE TYPE", UInt32, NoPdo, 0x0000_1389), // MDP 5001 (note 6)
    ] },
    Object { index: 0x1001, name: "ERROR REGISTER", code: Var, entries: &[
        var("ERROR REGISTER", UInt8, NoPdo, 0),
    ] },
    Object { index: 0x1008, name: "DEVICE NAME", code: Var, entries: &[
        string("DEVICE NAME", &Limits::text("PAM-199-P-ETC")),
    ] },
    Object { index: 0x1009, name: "HARDWARE VERSION", code: Var, entries: &[
        string("HARDWARE VERSION", &Limits::text("10")),
    ] },
    Object { index: 0x100A, name: "SOFTWARE VERSION", code: Var, entries: &[
        string("SOFTWARE VERSION", &Limits::text("10")),
    ] },
    Object { index: 0x1018, name: "IDENTITY", code: Record, entries: &[
        sub0(4),
        constant(0x01, "VENDOR ID", UInt32, 0x0000_05AE),
        constant(0x02, "PRODUCT CODE", UInt32, 0x00C7_03F3), // (note 2)
        constant(0x03, "REVISION", UInt32, 0x0000_0007),
        constant(0x04, "SERIAL NUMBER", UInt32, 0), // "Not used"
    ] },
    Object { index: 0x10F8, name: "Timestamp Object", code: Var, entries: &[
        var("Timestamp Object", DataType::UInt64, PdoMapping::Tx, 0), // (note 7)
    ] },
    // --- RxPDO mapping -----------------------------------------------------
    Object { index: 0x1600, name: "DIR", code: Record, entries: &[
        sub0(0x03),
        map(0x01, "ENABLE", 0x7000_0101),
        pad(0x02, 7),
        map(0x03, "COMMAND VALUE", 0x7000_0320),
    ] },
    Object { index: 0x1601, name: "IND", code: Record, entries: &[
        sub0(0x06),
        map(0x01, "ENABLE 1", 0x7010_0101), // (note 3)
        pad(0x02, 7),
        map(0x03, "COMMAND VALUE 1", 0x7010_0310),
        map(0x04, "ENABLE 2", 0x7020_0101),
        pad(0x05, 7),
        map(0x06, "COMMAND VALUE 2", 0x7020_0310),
    ] },
    // --- TxPDO mapping -----------------------------------------------------
    Object { index: 0x1A00, name: "DIR_IN", code: Record, entries: &[
        sub0(0x0D),
        map(0x01, "READY", 0x6000_0101),
        pad(0x02, 7),
        map(0x03, "MEMORY", 0xA000_0101),
        map(0x04, "UNDER-VOLTAGE", 0xA000_0201),
        map(0x05, "OVER VOLTAGE", 0xA000_0301),
        map(0x06, "OVER TEMPERATURE", 0xA000_0401),
        pad(0x07, 4),
        map(0x08, "SHORT SOLENOID A", 0xA010_0101),
        map(0x09, "OPEN SOLENOID A", 0xA010_0201),
        pad(0x0A, 6),
        map(0x0B, "SHORT SOLENOID B", 0xA020_0101),
        map(0x0C, "OPEN SOLENOID B", 0xA020_0201),
        pad(0x0D, 6),
    ] },
    Object { index: 0x1A01, name: "IND_IN", code: Record, entries: &[
        sub0(0x0F), // manual: 0x03 (note 8)
        map(0x01, "READY 1", 0x6010_0101),
        pad(0x02, 7),
        map(0x03, "READY 2", 0x6020_0101),
        pad(0x04, 7),
        map(0x05, "MEMORY", 0xA000_0101),
        map(0x06, "UNDER-VOLTAGE", 0xA000_0201),
        map(0x07, "OVER VOLTAGE", 0xA000_0301),
        map(0x08, "OVER TEMPERATURE", 0xA000_0401),
        pad(0x09, 4),
        map(0x0A, "SHORT SOLENOID A", 0xA010_0101),
        map(0x0B, "OPEN SOLENOID A", 0xA010_0201),
        pad(0x0C, 6),
        map(0x0D, "SHORT SOLENOID B", 0xA020_0101),
        map(0x0E, "OPEN SOLENOID B", 0xA020_0201),
        pad(0x0F, 6),
    ] },
    Object { index: 0x1A02, name: "DIR_SIG", code: Record, entries: &[
        sub0(0x05),
        map(0x01, "W", 0x6000_0310), // (note 1)
        map(0x02, "C", 0x6000_0410),
        map(0x03, "U", 0x6000_0510),
        map(0x04, "IA", 0x6000_0610),
        map(0x05, "IB", 0x6000_0710),
    ] },
    Object { index: 0x1A03, name: "IND_SIG", code: Record, entries: &[
        sub0(0x08), // manual: 0x06 (note 8)
        map(0x01, "W1", 0x6010_0310),
        map(0x02, "C1", 0x6010_0410),
        map(0x03, "U1", 0x6010_0510),
        map(0x04, "I1", 0x6010_0610),
        map(0x05, "W2", 0x6020_0310),
        map(0x06, "C2", 0x6020_0410),
        map(0x07, "U2", 0x6020_0510),
        map(0x08, "I2", 0x6020_0610),
    ] },
    // --- Sync manager objects (ETG.1000.6, not in the manual) (note 7) ---
    Object { index: 0x1C00, name: "Sync manager type", code: Array, entries: &[
        sub0(4),
        constant(0x01, sub_name(0x01), UInt8, 1), // mailbox out
        constant(0x02, sub_name(0x02), UInt8, 2), // mailbox in
        constant(0x03, sub_name(0x03), UInt8, 3), // outputs
        constant(0x04, sub_name(0x04), UInt8, 4), // inputs
    ] },
    Object { index: 0x1C12, name: "RxPDO assign", code: Array, entries: &[
        assign_count(1, 1),
        assign(0x01, 0x1600),
    ] },
    Object { index: 0x1C13, name: "TxPDO assign", code: Array, entries: &[
        assign_count(2, 2),
        assign(0x01, 0x1A00),
        assign(0x02, 0x1A02),
    ] },
    // ETG.1020 synchronisation parameters, kept current by the core.
    Object { index: 0x1C32, name: "SM output parameter", code: Record, entries: SYNC_PARAMETER_ENTRIES },
    Object { index: 0x1C33, name: "SM input parameter", code: Record, entries: SYNC_PARAMETER_ENTRIES },
    // --- 6.1.2 process data: inputs ----------------------------------------
    Object { index: 0x6000, name: "DIR", code: Record, entries: &[
        sub0(0x07),
        input(0x01, "READY", Bool),
        gap(0x02, 7),
        input(0x03, "W", Int16),
        input(0x04, "C", Int16),
        input(0x05, "U", Int16),
        current(0x06, "IA"),
        current(0x07, "IB"),
    ] },
    Object { index: 0x6010, name: "IND1", code: Record, entries: &[
        sub0(0x06),
        input(0x01, "READY1", Bool),
        gap(0x02, 7),
        input(0x03, "W1", UInt16),
        input(0x04, "C1", UInt16),
        input(0x05, "U1", UInt16),
        current(0x06, "I1"),
    ] },
    Object { index: 0x6020, name: "IND2", code: Record, entries: &[
        sub0(0x06),
        input(0x01, "READY2", Bool),
        gap(0x02, 7),
        input(0x03, "W2", UInt16),
        input(0x04, "C2", UInt16),
        input(0x05, "U2", UInt16),
        current(0x06, "I2"),
    ] },
    // --- 6.1.2 process data: outputs ---------------------------------------
    Object { index: 0x7000, name: "DIR", code: Record, entries: &[
        sub0(0x03),
        output(0x01, "ENABLE", Bool),
        gap(0x02, 7),
        output(0x03, "COMMAND VALUE", Int32), // (note 9)
    ] },
    Object { index: 0x7010, name: "IND1", code: Record, entries: &[
        sub0(0x03),
        output(0x01, "ENABLE1", Bool),
        gap(0x02, 7),
        output(0x03, "COMMAND VALUE 1", UInt16),
    ] },
    Object { index: 0x7020, name: "IND2", code: Record, entries: &[
        sub0(0x03),
        output(0x01, "ENABLE2", Bool),
        gap(0x02, 7),
        output(0x03, "COMMAND VALUE 2", UInt16),
    ] },
    // --- 6.1.3 parameters channel 0 (DIRECTIONAL) ---------------------------
    Object { index: 0x8002, name: "RAMP", code: Record, entries: &[
        sub0(0x05),
        param(0x02, "RA:UP:A", 100, RA),
        param(0x03, "RA:DOWN:A", 100, RA),
        param(0x04, "RA:UP:B", 100, RA),
        param(0x05, "RA:DOWN:B", 100, RA),
    ] },
    Object { index: 0x8006, name: "CC", code: Record, entries: &[
        sub0(0x2A),
        param(0x01, "CCB:10_X", -10_000, CC_DIR),
        param(0x02, "CCB:10_Y", -10_000, CC_DIR),
        param(0x03, "CCB:9_X", -9000, CC_DIR),
        param(0x04, "CCB:9_Y", -9000, CC_DIR),
        param(0x05, "CCB:8_X", -8000, CC_DIR),
        param(0x06, "CCB:8_Y", -8000, CC_DIR),
        param(0x07, "CCB:7_X", -7000, CC_DIR),
        param(0x08, "CCB:7_Y", -7000, CC_DIR),
        param(0x09, "CCB:6_X", -6000, CC_DIR),
        param(0x0A, "CCB:6_Y", -6000, CC_DIR),
        param(0x0B, "CCB:5_X", -5000, CC_DIR),
        param(0x0C, "CCB:5_Y", -5000, CC_DIR),
        param(0x0D, "CCB:4_X", -4000, CC_DIR),
        param(0x0E, "CCB:4_Y", -4000, CC_DIR),
        param(0x0F, "CCB:3_X", -3000, CC_DIR),
        param(0x10, "CCB:3_Y", -3000, CC_DIR),
        param(0x11, "CCB:2_X", -2000, CC_DIR),
        param(0x12, "CCB:2_Y", -2000, CC_DIR),
        param(0x13, "CCB:1_X", -1000, CC_DIR),
        param(0x14, "CCB:1_Y", -1000, CC_DIR),
        param(0x15, "CCA:0_X", 0, CC_DIR),
        param(0x16, "CCA:0_Y", 0, CC_DIR),
        param(0x17, "CCA:1_X", 1000, CC_DIR),
        param(0x18, "CCA:1_Y", 1000, CC_DIR),
        param(0x19, "CCA:2_X", 2000, CC_DIR),
        param(0x1A, "CCA:2_Y", 2000, CC_DIR),
        param(0x1B, "CCA:3_X", 3000, CC_DIR),
        param(0x1C, "CCA:3_Y", 3000, CC_DIR),
        param(0x1D, "CCA:4_X", 4000, CC_DIR),
        param(0x1E, "CCA:4_Y", 4000, CC_DIR),
        param(0x1F, "CCA:5_X", 5000, CC_DIR),
        param(0x20, "CCA:5_Y", 5000, CC_DIR),
        param(0x21, "CCA:6_X", 6000, CC_DIR),
        param(0x22, "CCA:6_Y", 6000, CC_DIR),
        param(0x23, "CCA:7_X", 7000, CC_DIR),
        param(0x24, "CCA:7_Y", 7000, CC_DIR),
        param(0x25, "CCA:8_X", 8000, CC_DIR),
        param(0x26, "CCA:8_Y", 8000, CC_DIR),
        param(0x27, "CCA:9_X", 9000, CC_DIR),
        param(0x28, "CCA:9_Y", 9000, CC_DIR),
        param(0x29, "CCA:10_X", 10_000, CC_DIR),
        param(0x2A, "CCA:10_Y", 10_000, CC_DIR), // comment says X (note 15)
    ] },
    Object { index: 0x800A, name: "MINMAX", code: Record, entries: &[
        sub0(0x09),
        choice(0x01, "CCMODE", &DT0802EN03, 0), // OFF
        gap(0x02, 5),
        choice(0x03, "MMTYPE", &DT0805EN03, 0), // JMP
        gap(0x04, 5),
        param(0x05, "TRIGGER", 200, TRIGGER),
        param(0x06, "MIN:A", 0, MIN),
        param(0x07, "MAX:A", 10_000, MAX),
        param(0x08, "MIN:B", 0, MIN),
        param(0x09, "MAX:B", 10_000, MAX),
    ] },
    Object { index: 0x800D, name: "POWER STAGE", code: Record, entries: &[
        sub0(0x0A),
        param(0x02, "CURRENT", 1000, CURRENT),
        param(0x03, "DAMPL", 500, DAMPL),
        param(0x04, "DFREQ", 120, DFREQ),
        pwm(0x05, "PWM"), // 2500 Hz, manual: 2604 (note 12)
        gap(0x06, 3),
        choice(0x07, "ACC", &DT0802EN03, 1), // ON
        gap(0x08, 5),
        param(0x09, "PPWM", 7, PPWM),
        param(0x0A, "IPWM", 40, IPWM),
    ] },
    // --- 6.1.4 parameters channel 1 / 2 (INDEPENDENT) -----------------------
    Object { index: 0x8012, name: "RAMP CHANNEL 1", code: Record, entries: &[
        sub0(0x03),
        param(0x02, "RA:UP:1", 100, RA),
        param(0x03, "RA:DOWN:1", 100, RA),
    ] },
    Object { index: 0x8016, name: "CC CHANNEL 1", code: Record, entries: &[
        sub0(0x16),
        param(0x01, "CC1:0_X", 0, CC_IND),
        param(0x02, "CC1:0_Y", 0, CC_IND),
        param(0x03, "CC1:1_X", 1000, CC_IND),
        param(0x04, "CC1:1_Y", 1000, CC_IND),
        param(0x05, "CC1:2_X", 2000, CC_IND),
        param(0x06, "CC1:2_Y", 2000, CC_IND),
        param(0x07, "CC1:3_X", 3000, CC_IND),
        param(0x08, "CC1:3_Y", 3000, CC_IND),
        param(0x09, "CC1:4_X", 4000, CC_IND),
        param(0x0A, "CC1:4_Y", 4000, CC_IND),
        param(0x0B, "CC1:5_X", 5000, CC_IND),
        param(0x0C, "CC1:5_Y", 5000, CC_IND),
        param(0x0D, "CC1:6_X", 6000, CC_IND),
        param(0x0E, "CC1:6_Y", 6000, CC_IND),
        param(0x0F, "CC1:7_X", 7000, CC_IND),
        param(0x10, "CC1:7_Y", 7000, CC_IND),
        param(0x11, "CC1:8_X", 8000, CC_IND),
        param(0x12, "CC1:8_Y", 8000, CC_IND),
        param(0x13, "CC1:9_X", 9000, CC_IND),
        param(0x14, "CC1:9_Y", 9000, CC_IND),
        param(0x15, "CC1:10_X", 10_000, CC_IND),
        param(0x16, "CC1:10_Y", 10_000, CC_IND),
    ] },
    Object { index: 0x801A, name: "MINMAX CHANNEL 1", code: Record, entries: &[
        sub0(0x07),
        choice(0x01, "CCMODE:1", &DT0802EN03, 0),
        gap(0x02, 5),
        choice(0x03, "MMTYPE:1", &DT0805EN03, 0), // manual: UINT (note 11)
        gap(0x04, 5),
        param(0x05, "TRIGGER:1", 200, TRIGGER),
        param(0x06, "MIN:1", 0, MIN),
        param(0x07, "MAX:1", 10_000, MAX),
    ] },
    Object { index: 0x801D, name: "POWER STAGE CHANNEL 1", code: Record, entries: &[
        sub0(0x0A), // manual: "80xD:00" (note 10)
        param(0x02, "CURRENT:1", 1000, CURRENT),
        param(0x03, "DAMPL:1", 500, DAMPL),
        param(0x04, "DFREQ:1", 120, DFREQ),
        pwm(0x05, "PWM:1"),
        gap(0x06, 3),
        choice(0x07, "ACC:1", &DT0802EN03, 1),
        gap(0x08, 5),
        param(0x09, "PPWM:1", 7, PPWM),
        param(0x0A, "IPWM:1", 40, IPWM),
    ] },
    Object { index: 0x8022, name: "RAMP CHANNEL 2", code: Record, entries: &[
        sub0(0x03),
        param(0x02, "RA:UP:2", 100, RA),
        param(0x03, "RA:DOWN:2", 100, RA),
    ] },
    Object { index: 0x8026, name: "CC CHANNEL 2", code: Record, entries: &[
        sub0(0x16),
        param(0x01, "CC2:0_X", 0, CC_IND),
        param(0x02, "CC2:0_Y", 0, CC_IND),
        param(0x03, "CC2:1_X", 1000, CC_IND),
        param(0x04, "CC2:1_Y", 1000, CC_IND),
        param(0x05, "CC2:2_X", 2000, CC_IND),
        param(0x06, "CC2:2_Y", 2000, CC_IND),
        param(0x07, "CC2:3_X", 3000, CC_IND),
        param(0x08, "CC2:3_Y", 3000, CC_IND),
        param(0x09, "CC2:4_X", 4000, CC_IND),
        param(0x0A, "CC2:4_Y", 4000, CC_IND),
        param(0x0B, "CC2:5_X", 5000, CC_IND),
        param(0x0C, "CC2:5_Y", 5000, CC_IND),
        param(0x0D, "CC2:6_X", 6000, CC_IND),
        param(0x0E, "CC2:6_Y", 6000, CC_IND),
        param(0x0F, "CC2:7_X", 7000, CC_IND),
        param(0x10, "CC2:7_Y", 7000, CC_IND),
        param(0x11, "CC2:8_X", 8000, CC_IND),
        param(0x12, "CC2:8_Y", 8000, CC_IND),
        param(0x13, "CC2:9_X", 9000, CC_IND),
        param(0x14, "CC2:9_Y", 9000, CC_IND),
        param(0x15, "CC2:10_X", 10_000, CC_IND),
        param(0x16, "CC2:10_Y", 10_000, CC_IND),
    ] },
    Object { index: 0x802A, name: "MINMAX CHANNEL 2", code: Record, entries: &[
        sub0(0x07),
        choice(0x01, "CCMODE:2", &DT0802EN03, 0),
        gap(0x02, 5),
        choice(0x03, "MMTYPE:2", &DT0805EN03, 0), // manual: UINT (note 11)
        gap(0x04, 5),
        param(0x05, "TRIGGER:2", 200, TRIGGER),
        param(0x06, "MIN:2", 0, MIN),
        param(0x07, "MAX:2", 10_000, MAX),
    ] },
    Object { index: 0x802D, name: "POWER STAGE CHANNEL 2", code: Record, entries: &[
        sub0(0x0A),
        param(0x02, "CURRENT:2", 1000, CURRENT),
        param(0x03, "DAMPL:2", 500, DAMPL),
        param(0x04, "DFREQ:2", 120, DFREQ),
        pwm(0x05, "PWM:2"),
        gap(0x06, 3),
        choice(0x07, "ACC:2", &DT0802EN03, 1),
        gap(0x08, 5),
        param(0x09, "PPWM:2", 7, PPWM),
        param(0x0A, "IPWM:2", 40, IPWM),
    ] },
    // --- 6.1.5 diagnosis messages ------------------------------------------
    Object { index: 0xA000, name: "DIAG", code: Record, entries: &[
        sub0(0x04),
        input(0x01, "MEMORY", Bool),
        input(0x02, "UNDERVOLTAGES", Bool),
        input(0x03, "OVERVOLTAGES", Bool),
        input(0x04, "TEMPERATURE", Bool),
    ] },
    Object { index: 0xA010, name: "DIAG 1", code: Record, entries: &[
        sub0(0x02),
        input(0x01, "SHORT CIRCUIT", Bool),
        input(0x02, "OPEN CIRCUIT", Bool), // flags blank in the manual (note 16)
    ] },
    Object { index: 0xA020, name: "DIAG 2", code: Record, entries: &[
        sub0(0x02),
        input(0x01, "SHORT CIRCUIT", Bool),
        input(0x02, "OPEN CIRCUIT", Bool), // flags blank in the manual (note 16)
    ] },
    // --- Modular device profile (ETG.5001, not in the manual) (note 7) ---
    Object { index: 0xF000, name: "Modular device profile", code: Record, entries: &[
        sub0(0x02),
        constant(0x01, "Module index distance", UInt16, 0x0010),
        constant(0x02, "Maximum number of modules", UInt16, 3),
    ] },
    // --- 6.1.6 system ------------------------------------------------------
    Object { index: 0xF800, name: "BASIS", code: Record, entries: &[
        sub0(0x03),
        param(0x01, "IO_BASE", 10_000, IO_BASE),
        choice(0x02, "FUNCTION", &DT0800EN03, 1), // DIRECTIONAL
        choice(0x03, "SENS", &DT0801EN03, 2),     // ON
    ] },
    Object { index: 0xF801, name: "FUNC", code: Record, entries: &[
        sub0(0x04),
        command(0x01, "PASSWORD", Access::Wo),
        command(0x02, "SAVE", Access::Rw), // manual: WO (note 4)
        command(0x03, "DEFAULT", Access::Rw),
        command(0x04, "LOADBACK", Access::Rw),
    ] },
    Object { index: 0xF80F, name: "MANU", code: Record, entries: &[
        sub0(0x02),
        setting(0x01, "RESERVED1", UInt16, 0, &Limits::NONE), // unnamed (note 17)
        setting(0x02, "RESERVED2", UInt16, 0, &Limits::NONE),
    ] },
];

// ---------------------------------------------------------------------------
// Positions: objects, flat entry positions, lookup
// ---------------------------------------------------------------------------

ecat_slave::dictionary!(pub DICT, pub ENTRY_COUNT = OBJECTS, ENUMS);

/// Number of objects in [`OBJECTS`].
pub const OBJECT_COUNT: usize = OBJECTS.len();

/// The object with index `index` and its position in [`OBJECTS`].
#[must_use]
pub fn find(index: u16) -> Option<(usize, &'static Object)> {
    DICT.find(index)
}

/// The entry `index:sub` (gaps included) and its flat position.
#[must_use]
pub fn find_entry(index: u16, sub: u8) -> Option<(usize, &'static Entry)> {
    DICT.find_entry(index, sub)
}

/// The entry at flat position `flat`.
#[must_use]
pub fn entry_at(flat: usize) -> Option<&'static Entry> {
    DICT.entry_at(flat)
}

/// The flat position of the entry `index:sub` (gaps included), found in
/// `const` context: what [`find_entry`] answers, for tables of positions
/// resolved at build time (see [`crate::app::entries`]).
#[must_use]
pub const fn position(index: u16, sub: u8) -> Option<usize> {
    let mut base = 0usize;
    let mut objects = OBJECTS;
    while let Some((o, rest)) = objects.split_first() {
        if o.index == index {
            let mut at = 0usize;
            let mut entries = o.entries;
            while let Some((e, tail)) = entries.split_first() {
                if e.sub == sub {
                    return Some(base + at);
                }
                at += 1;
                entries = tail;
            }
            return None;
        }
        base += o.entries.len();
        objects = rest;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use ecat_slave::od::DefaultValue;
    use ecat_slave::od::dictionary::natural_bits;

    #[test]
    fn the_dictionary_passes_the_cores_validation() {
        assert_eq!(DICT.validate(), Ok(()));
    }

    fn records() -> impl Iterator<Item = &'static Object> {
        OBJECTS.iter().filter(|o| o.code != ObjectCode::Var)
    }

    fn is_mapping(o: &Object) -> bool {
        (0x1600..=0x17FF).contains(&o.index) || (0x1A00..=0x1BFF).contains(&o.index)
    }

    fn int(e: &Entry) -> i64 {
        match e.default_value() {
            DefaultValue::Int(v) => v.get(),
            DefaultValue::Str(_) | DefaultValue::Bytes(_) => panic!("{} is not a number", e.name),
        }
    }

    /// Bit offset of every entry (subindex >= 1) in the packed layout of a
    /// record, and the total size.
    fn layout(o: &Object) -> (Vec<(&'static Entry, u32)>, u32) {
        let mut off = 0;
        let mut v = Vec::new();
        for e in o.entries.iter().filter(|e| e.sub >= 1) {
            v.push((e, off));
            off += u32::from(e.bit_len);
        }
        (v, off)
    }

    #[test]
    fn objects_are_strictly_ascending_by_index() {
        assert!(OBJECTS.windows(2).all(|w| w[0].index < w[1].index));
    }

    #[test]
    fn entries_are_strictly_ascending_by_subindex() {
        for o in OBJECTS {
            assert!(
                o.entries.windows(2).all(|w| w[0].sub < w[1].sub),
                "{:#06x}",
                o.index
            );
        }
    }

    #[test]
    fn var_objects_have_exactly_subindex_zero() {
        for o in OBJECTS.iter().filter(|o| o.code == ObjectCode::Var) {
            assert_eq!(o.entries.len(), 1);
            assert_eq!(o.entries[0].sub, 0);
            assert_eq!(o.entries[0].name, o.name);
        }
    }

    #[test]
    fn subindex_zero_holds_the_highest_subindex() {
        for o in records() {
            let s0 = &o.entries[0];
            assert_eq!(s0.sub, 0, "{:#06x}", o.index);
            assert_eq!(s0.data_type, DataType::UInt8);
            assert_eq!(s0.name, "SubIndex 000");
            assert_eq!(int(s0), i64::from(o.max_sub()), "{:#06x}", o.index);
            let want = if matches!(o.index, 0x1C12 | 0x1C13) {
                Access::RwPreOp
            } else {
                Access::Ro
            };
            assert_eq!(s0.access(), want, "{:#06x}", o.index);
        }
    }

    #[test]
    fn array_elements_share_one_type() {
        for o in OBJECTS.iter().filter(|o| o.code == ObjectCode::Array) {
            let t = o.entries[1].data_type;
            assert!(
                o.entries[1..].iter().all(|e| e.data_type == t),
                "{:#06x}",
                o.index
            );
        }
    }

    #[test]
    fn bit_lengths_match_data_types() {
        for o in OBJECTS {
            for e in o.entries {
                match e.default_value() {
                    DefaultValue::Str(s) => {
                        assert_eq!(e.data_type, DataType::VisibleString);
                        assert_eq!(usize::from(e.bit_len), 8 * s.len());
                    }
                    DefaultValue::Int(_) => {
                        assert_eq!(e.bit_len, natural_bits(&e.data_type), "{}", e.name)
                    }
                    DefaultValue::Bytes(_) => panic!("{}: the PAM has no octet strings", e.name),
                }
            }
        }
    }

    #[test]
    fn defaults_lie_within_ranges_and_enums() {
        for o in OBJECTS {
            for e in o.entries {
                let Some(v) = e.default_value().as_int() else {
                    continue;
                };
                if let Some(min) = e.min() {
                    assert!(v >= min, "{:#06x}:{} {}", o.index, e.sub, e.name);
                }
                if let Some(max) = e.max() {
                    assert!(v <= max, "{:#06x}:{} {}", o.index, e.sub, e.name);
                }
                if let DataType::Enum(t) = e.data_type {
                    let en = DICT.find_enum(t.index()).expect("listed");
                    assert!(en.contains(v), "{} default {v} not in {}", e.name, en.name);
                    assert_eq!(e.min(), None);
                    assert_eq!(e.max(), None);
                }
                if e.bit_len < 64 {
                    let bits = u32::from(e.bit_len);
                    if e.data_type.is_signed() {
                        assert!(
                            v >= -(1i64 << (bits - 1)) && v < (1i64 << (bits - 1)),
                            "{}",
                            e.name
                        );
                    } else {
                        assert!(v >= 0 && v < (1i64 << bits), "{}", e.name);
                    }
                }
            }
        }
    }

    #[test]
    fn enums_are_well_formed() {
        assert!(ENUMS.windows(2).all(|w| w[0].index < w[1].index));
        for e in ENUMS {
            assert_eq!(e.name, format!("DT{:04X}EN{:02}", e.index, e.bit_len));
            assert!(!e.values.is_empty());
            for (i, (v, t)) in e.values.iter().enumerate() {
                assert!(*v >= 0 && *v < (1 << e.bit_len), "{} {t}", e.name);
                assert!(
                    e.values[..i].iter().all(|(w, u)| w != v && u != t),
                    "{} {t}",
                    e.name
                );
            }
        }
    }

    #[test]
    fn pwm_codes_are_the_manuals_frequency_table() {
        let table = [
            (60, 0x11),
            (70, 0x0E),
            (80, 0x0B),
            (100, 0x08),
            (120, 0x05),
            (150, 0x02),
            (200, 0x13),
            (250, 0x10),
            (400, 0x0D),
            (500, 0x0A),
            (600, 0x07),
            (800, 0x04),
            (1000, 0x01),
            (1200, 0x12),
            (1500, 0x0F),
            (2000, 0x0C),
            (2500, 0x09),
            (3000, 0x06),
            (6000, 0x03),
            (10000, 0x14),
        ];
        assert_eq!(DT0803EN05.values.len(), table.len());
        for (hz, code) in table {
            assert_eq!(DT0803EN05.text(code), Some(hz.to_string().as_str()));
        }
        for idx in [0x800D, 0x801D, 0x802D] {
            let (_, e) = find_entry(idx, 0x05).unwrap();
            assert_eq!(e.default_value(), DefaultValue::int(0x09)); // 2500 Hz
            assert_eq!(e.bit_len, 5);
        }
    }

    #[test]
    fn every_mapping_entry_names_a_mappable_entry_or_padding() {
        for o in OBJECTS.iter().filter(|o| is_mapping(o)) {
            let dir = if o.index < 0x1A00 {
                PdoMapping::Rx
            } else {
                PdoMapping::Tx
            };
            for e in o.entries.iter().filter(|e| e.sub >= 1) {
                assert_eq!(e.data_type, DataType::UInt32);
                assert_eq!(e.access(), Access::Ro);
                let m = int(e) as u32;
                let (index, sub, bits) = ((m >> 16) as u16, (m >> 8) as u8, m as u8);
                if index == 0 {
                    assert_eq!(sub, 0);
                    assert!((1..8).contains(&bits), "{:#06x}:{}", o.index, e.sub);
                    assert_eq!(e.name, sub_name(e.sub));
                    continue;
                }
                let (_, target) = find_entry(index, sub).unwrap_or_else(|| panic!("{m:#010x}"));
                assert!(!target.gap(), "{m:#010x}");
                assert_eq!(u16::from(bits), target.bit_len, "{m:#010x}");
                assert_eq!(target.pdo(), dir, "{m:#010x}");
            }
        }
    }

    #[test]
    fn mapped_pdos_have_the_expected_byte_aligned_sizes() {
        let want = [
            (0x1600, 40),
            (0x1601, 48),
            (0x1A00, 32),
            (0x1A01, 40),
            (0x1A02, 80),
            (0x1A03, 128),
        ];
        assert_eq!(OBJECTS.iter().filter(|o| is_mapping(o)).count(), want.len());
        for (index, bits) in want {
            let (_, o) = find(index).unwrap();
            let mut off = 0u32;
            for e in o.entries.iter().filter(|e| e.sub >= 1) {
                let n = int(e) as u32 & 0xFF;
                if n >= 8 {
                    assert_eq!(off % 8, 0, "{index:#06x}:{} starts unaligned", e.sub);
                }
                off += n;
            }
            assert_eq!(off % 8, 0);
            assert_eq!(off, bits, "{index:#06x}");
        }
    }

    #[test]
    fn gaps_pad_exactly_to_the_next_byte_boundary() {
        for o in records().filter(|o| !is_mapping(o)) {
            for (e, off) in layout(o).0 {
                if e.gap() {
                    assert!(
                        off % 8 != 0,
                        "{:#06x}:{} at a byte boundary",
                        o.index,
                        e.sub
                    );
                    assert_eq!(
                        (off + u32::from(e.bit_len)) % 8,
                        0,
                        "{:#06x}:{}",
                        o.index,
                        e.sub
                    );
                    assert_eq!(e.data_type, DataType::Bits(e.bit_len as u8));
                    assert_eq!(
                        (e.access(), e.pdo(), e.default_value()),
                        (Access::Ro, PdoMapping::None, DefaultValue::int(0))
                    );
                    assert_eq!(e.name, sub_name(e.sub));
                    assert!(!e.backup() && !e.setting());
                } else if e.bit_len % 8 == 0 {
                    assert_eq!(off % 8, 0, "{:#06x}:{} starts unaligned", o.index, e.sub);
                }
            }
        }
    }

    #[test]
    fn only_f800_and_the_diagnosis_records_end_unaligned() {
        // Complete access pads these to the next byte with zero bits.
        let unaligned: Vec<(u16, u32)> = records()
            .map(|o| (o.index, layout(o).1 % 8))
            .filter(|(_, rest)| *rest != 0)
            .collect();
        assert_eq!(
            unaligned,
            [(0xA000, 4), (0xA010, 2), (0xA020, 2), (0xF800, 6)]
        );
    }

    #[test]
    fn manual_ranges_are_on_the_named_entries() {
        // (index, sub, name, min, max, unit) from manual 6.2-6.4.
        let mut rows: Vec<(u16, u8, &str, i64, i64, &str)> =
            vec![(0xF800, 0x01, "IO_BASE", 100, 32767, "")];
        for (idx, subs, names) in [
            (
                0x8002u16,
                2u8..=5u8,
                ["RA:UP:A", "RA:DOWN:A", "RA:UP:B", "RA:DOWN:B"].as_slice(),
            ),
            (0x8012, 2..=3, &["RA:UP:1", "RA:DOWN:1"]),
            (0x8022, 2..=3, &["RA:UP:2", "RA:DOWN:2"]),
        ] {
            for (s, n) in subs.zip(names) {
                rows.push((idx, s, n, 1, 120_000, "ms"));
            }
        }
        for (idx, sfx) in [(0x800Au16, ""), (0x801A, ":1"), (0x802A, ":2")] {
            let trigger = format!("TRIGGER{sfx}").leak();
            rows.push((idx, 0x05, trigger, 0, 3000, "0.01 %"));
        }
        rows.extend([
            (0x800A, 0x06, "MIN:A", 0, 6000, "0.01 %"),
            (0x800A, 0x07, "MAX:A", 5000, 10000, "0.01 %"),
            (0x800A, 0x08, "MIN:B", 0, 6000, "0.01 %"),
            (0x800A, 0x09, "MAX:B", 5000, 10000, "0.01 %"),
            (0x801A, 0x06, "MIN:1", 0, 6000, "0.01 %"),
            (0x801A, 0x07, "MAX:1", 5000, 10000, "0.01 %"),
            (0x802A, 0x06, "MIN:2", 0, 6000, "0.01 %"),
            (0x802A, 0x07, "MAX:2", 5000, 10000, "0.01 %"),
        ]);
        for (idx, sfx) in [(0x800Du16, ""), (0x801D, ":1"), (0x802D, ":2")] {
            for (s, n, min, max, unit) in [
                (0x02u8, "CURRENT", 500, 3000, "mA"),
                (0x03, "DAMPL", 0, 3000, "0.01 %"),
                (0x04, "DFREQ", 50, 400, "Hz"),
                (0x09, "PPWM", 0, 300, ""),
                (0x0A, "IPWM", 0, 100, ""),
            ] {
                rows.push((idx, s, format!("{n}{sfx}").leak(), min, max, unit));
            }
        }
        for (idx, lo, n) in [(0x8006u16, -10_000, 42u8), (0x8016, 0, 22), (0x8026, 0, 22)] {
            for s in 1..=n {
                let (_, e) = find_entry(idx, s).unwrap();
                rows.push((idx, s, e.name, lo, 10_000, "0.01 %"));
            }
        }
        assert_eq!(rows.len(), 1 + 8 + 3 + 8 + 15 + 86);
        for (idx, sub, name, min, max, unit) in rows {
            let (_, e) = find_entry(idx, sub).unwrap_or_else(|| panic!("{idx:#06x}:{sub}"));
            assert_eq!(e.name, name, "{idx:#06x}:{sub}");
            assert_eq!(
                (e.min(), e.max(), e.unit()),
                (Some(min), Some(max), unit),
                "{name}"
            );
        }
    }

    #[test]
    fn curve_points_are_named_and_preset_as_the_identity() {
        let (_, cc) = find(0x8006).unwrap();
        let mut names = Vec::new();
        for p in (1..=10).rev() {
            names.push(format!("CCB:{p}_X"));
            names.push(format!("CCB:{p}_Y"));
        }
        for p in 0..=10 {
            names.push(format!("CCA:{p}_X"));
            names.push(format!("CCA:{p}_Y"));
        }
        for (i, e) in cc.entries[1..].iter().enumerate() {
            assert_eq!(e.name, names[i]);
            assert_eq!(int(e), (i as i64 / 2) * 1000 - 10_000);
            assert_eq!(e.data_type, DataType::Int16);
        }
        for (idx, ch) in [(0x8016, 1), (0x8026, 2)] {
            let (_, cc) = find(idx).unwrap();
            for (i, e) in cc.entries[1..].iter().enumerate() {
                let axis = if i % 2 == 0 { "X" } else { "Y" };
                assert_eq!(e.name, format!("CC{ch}:{}_{axis}", i / 2));
                assert_eq!(int(e), (i as i64 / 2) * 1000);
            }
        }
    }

    #[test]
    fn identity_is_the_manuals() {
        let v = |s| int(find_entry(0x1018, s).unwrap().1);
        assert_eq!(
            [v(0), v(1), v(2), v(3), v(4)],
            [4, 0x0000_05AE, 0x00C7_03F3, 7, 0]
        );
        assert_eq!(find_entry(0x1018, 2).unwrap().1.name, "PRODUCT CODE");
        assert_eq!(int(find_entry(0x1000, 0).unwrap().1), 0x0000_1389);
        assert_eq!(
            find_entry(0x1008, 0).unwrap().1.default_value(),
            DefaultValue::Str("PAM-199-P-ETC")
        );
        assert_eq!(find_entry(0x1008, 0).unwrap().1.bit_len, 104);
    }

    #[test]
    fn default_pdo_assignment_is_the_directional_set() {
        let v = |i, s| int(find_entry(i, s).unwrap().1);
        assert_eq!([v(0x1C12, 0), v(0x1C12, 1)], [1, 0x1600]);
        assert_eq!(
            [v(0x1C13, 0), v(0x1C13, 1), v(0x1C13, 2)],
            [2, 0x1A00, 0x1A02]
        );
        assert_eq!(
            [v(0x1C00, 1), v(0x1C00, 2), v(0x1C00, 3), v(0x1C00, 4)],
            [1, 2, 3, 4]
        );
        for i in [0x1C12, 0x1C13] {
            let (_, o) = find(i).unwrap();
            assert!(o.entries.iter().all(|e| e.access() == Access::RwPreOp));
            assert_eq!(o.entries[0].max(), Some(i64::from(o.max_sub())));
        }
    }

    #[test]
    fn access_pdo_and_storage_flags_follow_the_index_ranges() {
        for o in OBJECTS {
            for e in o.entries.iter().filter(|e| e.sub >= 1 && !e.gap()) {
                let what = format!("{:#06x}:{} {}", o.index, e.sub, e.name);
                let stored =
                    (0x8000..=0x8FFF).contains(&o.index) || matches!(o.index, 0xF800 | 0xF80F);
                assert_eq!((e.backup(), e.setting()), (stored, stored), "{what}");
                match o.index {
                    0x6000..=0x6FFF | 0xA000..=0xAFFF => {
                        assert_eq!(
                            (e.access(), e.pdo()),
                            (Access::Ro, PdoMapping::Tx),
                            "{what}"
                        )
                    }
                    0x7000..=0x7FFF => {
                        assert_eq!(
                            (e.access(), e.pdo()),
                            (Access::Rw, PdoMapping::Rx),
                            "{what}"
                        )
                    }
                    0x8000..=0x8FFF | 0xF800 | 0xF80F => {
                        assert_eq!(
                            (e.access(), e.pdo()),
                            (Access::Rw, PdoMapping::None),
                            "{what}"
                        )
                    }
                    _ => assert_eq!(e.pdo(), PdoMapping::None, "{what}"),
                }
                if matches!(o.index, 0x6000..=0x7FFF | 0xA000..=0xAFFF) {
                    assert_eq!(int(e), 0, "{what}");
                }
            }
        }
        let (_, ts) = find_entry(0x10F8, 0).unwrap();
        assert_eq!((ts.data_type, ts.pdo()), (DataType::UInt64, PdoMapping::Tx));
        let acc = |s| find_entry(0xF801, s).unwrap().1.access();
        assert_eq!(
            [acc(1), acc(2), acc(3), acc(4)],
            [Access::Wo, Access::Rw, Access::Rw, Access::Rw]
        );
    }

    #[test]
    fn entry_base_prefix_sums_agree_with_find_entry() {
        assert_eq!(DICT.base(0), Some(0));
        assert_eq!(
            ENTRY_COUNT,
            OBJECTS.iter().map(|o| o.entries.len()).sum::<usize>()
        );
        assert_eq!(OBJECT_COUNT, OBJECTS.len());
        let mut flat = 0;
        for (pos, o) in OBJECTS.iter().enumerate() {
            assert_eq!(DICT.base(pos), Some(flat));
            assert_eq!(find(o.index).map(|(p, _)| p), Some(pos));
            for e in o.entries {
                let (f, found) = find_entry(o.index, e.sub).unwrap();
                assert_eq!(f, flat);
                // `OBJECTS` is a const: compare by value, not by address.
                assert_eq!(found, e);
                assert_eq!(entry_at(flat), Some(e));
                assert_eq!(DICT.locate(flat).map(|(p, _)| p), Some(pos));
                flat += 1;
            }
        }
        assert_eq!(flat, ENTRY_COUNT);
        assert!(entry_at(ENTRY_COUNT).is_none());
        assert!(find(0x1002).is_none());
        assert!(find_entry(0x8002, 0x01).is_none()); // blank at a byte boundary: absent
        assert!(find_entry(0x6000, 0x02).unwrap().1.gap());
    }

    #[test]
    fn names_are_short_nonempty_and_unique_per_object() {
        for o in OBJECTS {
            assert!(!o.name.is_empty() && o.name.len() <= 64);
            for (i, e) in o.entries.iter().enumerate() {
                assert!(
                    !e.name.is_empty() && e.name.len() <= 64,
                    "{:#06x}:{}",
                    o.index,
                    e.sub
                );
                assert!(e.name.is_ascii(), "{}", e.name);
                let dup = o.entries[..i].iter().any(|d| d.name == e.name);
                assert!(!dup || e.gap(), "{:#06x}: {} twice", o.index, e.name);
            }
        }
    }

    #[test]
    fn strings_fit_the_store() {
        // ObjectStore: STRING_SLOTS = 4 slots of STRING_CAPACITY = 32 bytes.
        let strings: Vec<&str> = OBJECTS
            .iter()
            .flat_map(|o| o.entries)
            .filter_map(|e| match e.default_value() {
                DefaultValue::Str(s) => Some(s),
                DefaultValue::Int(_) | DefaultValue::Bytes(_) => None,
            })
            .collect();
        assert_eq!(strings, ["PAM-199-P-ETC", "10", "10"]);
        assert!(strings.len() <= 4 && strings.iter().all(|s| s.len() <= 32));
    }
}
