//! The profile's objects, described once with the core's `od::build`
//! constructors, and the `const` concatenation a device composes its
//! dictionary with.
//!
//! A drive's dictionary is its own communication objects (0x1000-0x1C33),
//! the profile's fixed PDO mappings ([`RX_PDO`] 0x1600, [`TX_PDO`]
//! 0x1A00), its manufacturer objects (0x2000-0x5FFF), the profile area
//! ([`OBJECTS`], 0x6007-0x6502) and its device objects (0xF000-). The
//! parts interleave by index, so a device writes its table as parts in
//! index order and [`join`]s them into one array:
//!
//! ```
//! use ecat_cia402::objects::{self, join, object_count};
//! use ecat_slave::od::build::{constant, sub0, var};
//! use ecat_slave::od::{DataType, Object, ObjectCode, PdoMapping};
//!
//! const HEAD: &[Object] = &[
//!     Object { index: 0x1000, name: "Device type", code: ObjectCode::Var, entries: &[
//!         var("Device type", DataType::UInt32, PdoMapping::None, objects::DEVICE_TYPE_SERVO),
//!     ] },
//!     Object { index: 0x1018, name: "Identity", code: ObjectCode::Record, entries: &[
//!         sub0(1),
//!         constant(1, "Vendor ID", DataType::UInt32, 0x0ABE),
//!     ] },
//! ];
//! const PARTS: &[&[Object]] = &[HEAD, objects::PDO_MAPPINGS, objects::OBJECTS];
//! const ALL: [Object; object_count(PARTS)] = join(PARTS);
//! ecat_slave::dictionary!(DICT, ENTRIES = &ALL, &[]);
//! assert_eq!(DICT.validate(), Ok(()));
//! assert!(DICT.find(0x6040).is_some() && DICT.find(0x1A00).is_some());
//! ```
//!
//! Why a `const fn` and not a macro: the parts stay ordinary `const`
//! items a reader can look up, the array length is computed from them
//! (no count written by hand), and the order is checked where every
//! device's is, by `Dictionary::validate` (objects out of order or twice
//! fail the build through `DeviceDescription::assert_valid`). A macro
//! would have to re-parse object literals to learn what `object_count`
//! knows already. The DMA-22 device concatenates its per-slot copies the
//! same way.
//!
//! The mapping objects are writable in PRE-OP (flexible mapping, ETG.1020
//! "PDO configuration"): a master sets subindex 0 to 0, writes the
//! entries, then the count; the core checks each step (0x06010003,
//! 0x06040041-43) and PRE-OP→SAFE-OP the SM lengths against the new
//! images. Every drive built on the profile gets it. The mappable objects
//! are the ones [`RX_PDO`]/[`TX_PDO`] map by default; the parameters are
//! not mappable, since
//! the core sets every RxPDO-mappable entry to 0 when OP is left
//! (docs/SAFETY.md C2), which a parameter must survive.

use ecat_slave::od::build::{input, map_rw, mapping_count, output, ranged, sub_name, var};
use ecat_slave::od::{DataType, Entry, Limits, Object, ObjectCode, PdoMapping};

use crate::drive::Parameters;
use crate::mode::{Mode, SUPPORTED_DRIVE_MODES};

/// The objects' indices (axis 0; axis n adds n × [`AXIS_OFFSET`]).
pub mod index {
    /// 6007h "Abort connection option code".
    pub const ABORT_CONNECTION_OPTION: u16 = 0x6007;
    /// 603Fh "Error code".
    pub const ERROR_CODE: u16 = 0x603F;
    /// 6040h "Controlword".
    pub const CONTROLWORD: u16 = 0x6040;
    /// 6041h "Statusword".
    pub const STATUSWORD: u16 = 0x6041;
    /// 605Ah "Quick stop option code".
    pub const QUICK_STOP_OPTION: u16 = 0x605A;
    /// 605Eh "Fault reaction option code".
    pub const FAULT_REACTION_OPTION: u16 = 0x605E;
    /// 6060h "Modes of operation".
    pub const MODES_OF_OPERATION: u16 = 0x6060;
    /// 6061h "Modes of operation display".
    pub const MODES_DISPLAY: u16 = 0x6061;
    /// 6062h "Position demand value".
    pub const POSITION_DEMAND: u16 = 0x6062;
    /// 6064h "Position actual value".
    pub const POSITION_ACTUAL: u16 = 0x6064;
    /// 6065h "Following error window".
    pub const FOLLOWING_ERROR_WINDOW: u16 = 0x6065;
    /// 6066h "Following error time out".
    pub const FOLLOWING_ERROR_TIMEOUT: u16 = 0x6066;
    /// 6067h "Position window".
    pub const POSITION_WINDOW: u16 = 0x6067;
    /// 606Ch "Velocity actual value".
    pub const VELOCITY_ACTUAL: u16 = 0x606C;
    /// 606Dh "Velocity window".
    pub const VELOCITY_WINDOW: u16 = 0x606D;
    /// 606Fh "Velocity threshold".
    pub const VELOCITY_THRESHOLD: u16 = 0x606F;
    /// 6071h "Target torque".
    pub const TARGET_TORQUE: u16 = 0x6071;
    /// 6072h "Max torque".
    pub const MAX_TORQUE: u16 = 0x6072;
    /// 6077h "Torque actual value".
    pub const TORQUE_ACTUAL: u16 = 0x6077;
    /// 607Ah "Target position".
    pub const TARGET_POSITION: u16 = 0x607A;
    /// 607Ch "Home offset".
    pub const HOME_OFFSET: u16 = 0x607C;
    /// 6080h "Max motor speed".
    pub const MAX_MOTOR_SPEED: u16 = 0x6080;
    /// 6081h "Profile velocity".
    pub const PROFILE_VELOCITY: u16 = 0x6081;
    /// 6083h "Profile acceleration".
    pub const PROFILE_ACCELERATION: u16 = 0x6083;
    /// 6084h "Profile deceleration".
    pub const PROFILE_DECELERATION: u16 = 0x6084;
    /// 6085h "Quick stop deceleration".
    pub const QUICK_STOP_DECELERATION: u16 = 0x6085;
    /// 6098h "Homing method".
    pub const HOMING_METHOD: u16 = 0x6098;
    /// 60F4h "Following error actual value".
    pub const FOLLOWING_ERROR_ACTUAL: u16 = 0x60F4;
    /// 60FFh "Target velocity".
    pub const TARGET_VELOCITY: u16 = 0x60FF;
    /// 6502h "Supported drive modes".
    pub const SUPPORTED_DRIVE_MODES: u16 = 0x6502;
}

/// Index distance of the objects of axis n (CiA 402-2: logical device n
/// of a multi-axis drive at 6000h + n × 800h).
pub const AXIS_OFFSET: u16 = 0x0800;

/// 0x1000 "Device type" of a CiA 402 servo drive: profile 402 (0x0192)
/// in bits 0-15, "servo drive" (0x02) in the additional information
/// (CiA 402-2 / CiA 301 object 1000h; ETG.6010 uses the same value).
pub const DEVICE_TYPE_SERVO: i64 = 0x0002_0192;

/// The parameters that change how the drive stops or how far it may go:
/// written only while the power stage is off (docs/SAFETY.md S4).
pub const SAFETY_PARAMETERS: [u16; 9] = [
    index::ABORT_CONNECTION_OPTION,
    index::QUICK_STOP_OPTION,
    index::FAULT_REACTION_OPTION,
    index::FOLLOWING_ERROR_WINDOW,
    index::FOLLOWING_ERROR_TIMEOUT,
    index::MAX_TORQUE,
    index::MAX_MOTOR_SPEED,
    index::PROFILE_DECELERATION,
    index::QUICK_STOP_DECELERATION,
];

use ObjectCode::{Record, Var};

const D: Parameters = Parameters::DEFAULT;

const fn obj(index: u16, name: &'static str, entries: &'static [Entry]) -> Object {
    Object {
        index,
        name,
        code: Var,
        entries,
    }
}

/// 6060h: an output (RxPDO-mappable, RW) defaulting to CSP.
const MODES_OF_OPERATION: Entry = output(0, "Modes of operation", DataType::Int8)
    .with_default(Mode::CyclicPosition.code() as i64);

/// The profile area of axis 0, ascending: 0x6007-0x6502.
#[rustfmt::skip]
pub const OBJECTS: &[Object] = &[
    obj(index::ABORT_CONNECTION_OPTION, "Abort connection option code", &[
        ranged(0, "Abort connection option code", DataType::Int16, D.abort_connection_option as i64, &Limits::range(1, 3, "")),
    ]),
    obj(index::ERROR_CODE, "Error code", &[input(0, "Error code", DataType::UInt16)]),
    obj(index::CONTROLWORD, "Controlword", &[output(0, "Controlword", DataType::UInt16)]),
    obj(index::STATUSWORD, "Statusword", &[input(0, "Statusword", DataType::UInt16)]),
    obj(index::QUICK_STOP_OPTION, "Quick stop option code", &[
        ranged(0, "Quick stop option code", DataType::Int16, D.quick_stop_option as i64, &Limits::range(0, 8, "")),
    ]),
    obj(index::FAULT_REACTION_OPTION, "Fault reaction option code", &[
        ranged(0, "Fault reaction option code", DataType::Int16, D.fault_reaction_option as i64, &Limits::range(0, 4, "")),
    ]),
    obj(index::MODES_OF_OPERATION, "Modes of operation", &[MODES_OF_OPERATION]),
    obj(index::MODES_DISPLAY, "Modes of operation display", &[
        input(0, "Modes of operation display", DataType::Int8).with_default(Mode::CyclicPosition.code() as i64),
    ]),
    obj(index::POSITION_DEMAND, "Position demand value", &[input(0, "Position demand value", DataType::Int32)]),
    obj(index::POSITION_ACTUAL, "Position actual value", &[input(0, "Position actual value", DataType::Int32)]),
    obj(index::FOLLOWING_ERROR_WINDOW, "Following error window", &[
        ranged(0, "Following error window", DataType::UInt32, D.following_error_window as i64, &Limits::range(0, u32::MAX as i64, "inc")),
    ]),
    obj(index::FOLLOWING_ERROR_TIMEOUT, "Following error time out", &[
        ranged(0, "Following error time out", DataType::UInt16, D.following_error_timeout_ms as i64, &Limits::range(0, u16::MAX as i64, "ms")),
    ]),
    obj(index::POSITION_WINDOW, "Position window", &[
        ranged(0, "Position window", DataType::UInt32, D.position_window as i64, &Limits::range(0, u32::MAX as i64, "inc")),
    ]),
    obj(index::VELOCITY_ACTUAL, "Velocity actual value", &[input(0, "Velocity actual value", DataType::Int32)]),
    obj(index::VELOCITY_WINDOW, "Velocity window", &[
        ranged(0, "Velocity window", DataType::UInt16, D.velocity_window as i64, &Limits::range(0, u16::MAX as i64, "inc/s")),
    ]),
    obj(index::VELOCITY_THRESHOLD, "Velocity threshold", &[
        ranged(0, "Velocity threshold", DataType::UInt16, D.velocity_threshold as i64, &Limits::range(0, u16::MAX as i64, "inc/s")),
    ]),
    obj(index::TARGET_TORQUE, "Target torque", &[output(0, "Target torque", DataType::Int16)]),
    obj(index::MAX_TORQUE, "Max torque", &[
        ranged(0, "Max torque", DataType::UInt16, D.max_torque as i64, &Limits::range(0, u16::MAX as i64, "permille")),
    ]),
    obj(index::TORQUE_ACTUAL, "Torque actual value", &[input(0, "Torque actual value", DataType::Int16)]),
    obj(index::TARGET_POSITION, "Target position", &[output(0, "Target position", DataType::Int32)]),
    obj(index::HOME_OFFSET, "Home offset", &[
        ranged(0, "Home offset", DataType::Int32, D.home_offset as i64, &Limits::range(i32::MIN as i64, i32::MAX as i64, "inc")),
    ]),
    obj(index::MAX_MOTOR_SPEED, "Max motor speed", &[
        ranged(0, "Max motor speed", DataType::UInt32, D.max_motor_speed as i64, &Limits::range(0, i32::MAX as i64, "inc/s")),
    ]),
    obj(index::PROFILE_VELOCITY, "Profile velocity", &[
        ranged(0, "Profile velocity", DataType::UInt32, D.profile_velocity as i64, &Limits::range(0, i32::MAX as i64, "inc/s")),
    ]),
    obj(index::PROFILE_ACCELERATION, "Profile acceleration", &[
        ranged(0, "Profile acceleration", DataType::UInt32, D.profile_acceleration as i64, &Limits::range(1, u32::MAX as i64, "inc/s^2")),
    ]),
    obj(index::PROFILE_DECELERATION, "Profile deceleration", &[
        ranged(0, "Profile deceleration", DataType::UInt32, D.profile_deceleration as i64, &Limits::range(1, u32::MAX as i64, "inc/s^2")),
    ]),
    obj(index::QUICK_STOP_DECELERATION, "Quick stop deceleration", &[
        ranged(0, "Quick stop deceleration", DataType::UInt32, D.quick_stop_deceleration as i64, &Limits::range(1, u32::MAX as i64, "inc/s^2")),
    ]),
    obj(index::HOMING_METHOD, "Homing method", &[
        ranged(0, "Homing method", DataType::Int8, D.homing_method as i64, &Limits::range(35, 37, "")),
    ]),
    obj(index::FOLLOWING_ERROR_ACTUAL, "Following error actual value", &[input(0, "Following error actual value", DataType::Int32)]),
    obj(index::TARGET_VELOCITY, "Target velocity", &[output(0, "Target velocity", DataType::Int32)]),
    obj(index::SUPPORTED_DRIVE_MODES, "Supported drive modes", &[
        var("Supported drive modes", DataType::UInt32, PdoMapping::None, SUPPORTED_DRIVE_MODES as i64),
    ]),
];

/// 0x1600, the RxPDO of the cyclic synchronous modes (what a typical
/// ETG.6010 drive maps for CSP/CSV/CST): controlword, target position,
/// target velocity, target torque, modes of operation; 13 bytes. Writable
/// in PRE-OP (flexible mapping, ETG.1020): up to 8 entries of the
/// profile's RxPDO-mappable objects; subindices 6-8 are free places.
#[rustfmt::skip]
pub const RX_PDO: Object = Object { index: 0x1600, name: "Drive outputs", code: Record, entries: &[
    mapping_count(5, 8),
    map_rw(1, sub_name(1), mapping(index::CONTROLWORD, 16)),
    map_rw(2, sub_name(2), mapping(index::TARGET_POSITION, 32)),
    map_rw(3, sub_name(3), mapping(index::TARGET_VELOCITY, 32)),
    map_rw(4, sub_name(4), mapping(index::TARGET_TORQUE, 16)),
    map_rw(5, sub_name(5), mapping(index::MODES_OF_OPERATION, 8)),
    map_rw(6, sub_name(6), 0),
    map_rw(7, sub_name(7), 0),
    map_rw(8, sub_name(8), 0),
] };

/// 0x1A00, the TxPDO: statusword, position, velocity, torque, modes of
/// operation display, following error, error code; 19 bytes. Writable in
/// PRE-OP like [`RX_PDO`]: up to 10 entries; subindices 8-10 are free.
#[rustfmt::skip]
pub const TX_PDO: Object = Object { index: 0x1A00, name: "Drive inputs", code: Record, entries: &[
    mapping_count(7, 10),
    map_rw(1, sub_name(1), mapping(index::STATUSWORD, 16)),
    map_rw(2, sub_name(2), mapping(index::POSITION_ACTUAL, 32)),
    map_rw(3, sub_name(3), mapping(index::VELOCITY_ACTUAL, 32)),
    map_rw(4, sub_name(4), mapping(index::TORQUE_ACTUAL, 16)),
    map_rw(5, sub_name(5), mapping(index::MODES_DISPLAY, 8)),
    map_rw(6, sub_name(6), mapping(index::FOLLOWING_ERROR_ACTUAL, 32)),
    map_rw(7, sub_name(7), mapping(index::ERROR_CODE, 16)),
    map_rw(8, sub_name(8), 0),
    map_rw(9, sub_name(9), 0),
    map_rw(10, sub_name(10), 0),
] };

/// The mapping value of subindex 0 of `index` with `bits` bits.
const fn mapping(index: u16, bits: u8) -> u32 {
    (index as u32) << 16 | bits as u32
}

/// [`RX_PDO`] and [`TX_PDO`] as one part for [`join`].
pub const PDO_MAPPINGS: &[Object] = &[RX_PDO, TX_PDO];

/// Bytes of the outputs [`RX_PDO`] maps.
pub const RX_PDO_BYTES: usize = 13;
/// Bytes of the inputs [`TX_PDO`] maps.
pub const TX_PDO_BYTES: usize = 19;

const fn copy(o: &Object) -> Object {
    Object {
        index: o.index,
        name: o.name,
        code: o.code,
        entries: o.entries,
    }
}

/// How many objects `parts` hold together: the length for [`join`].
pub const fn object_count(parts: &[&[Object]]) -> usize {
    let mut n = 0;
    let mut rest = parts;
    while let Some((part, tail)) = rest.split_first() {
        n += part.len();
        rest = tail;
    }
    n
}

/// `parts` one after the other, as one array of `N` =
/// [`object_count`]`(parts)` objects. Evaluated in a `const` item: a
/// smaller `N` fails the build here; a larger one leaves empty objects at
/// the end, which `Dictionary::validate` refuses, as it refuses parts out
/// of index order.
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated in const items only; the index is checked against N first"
)]
pub const fn join<const N: usize>(parts: &[&[Object]]) -> [Object; N] {
    let mut out = [const {
        Object {
            index: 0,
            name: "",
            code: Var,
            entries: &[],
        }
    }; N];
    let mut k = 0;
    let mut rest = parts;
    while let Some((part, tail)) = rest.split_first() {
        let mut objects = *part;
        while let Some((o, more)) = objects.split_first() {
            if k < N {
                out[k] = copy(o);
            }
            k += 1;
            objects = more;
        }
        rest = tail;
    }
    // More objects than N: a build error where the array is made.
    assert!(k <= N, "join: N is smaller than the objects of the parts");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use ecat_slave::od::{DefaultValue, Dictionary};

    ecat_slave::dictionary!(PROFILE, PROFILE_ENTRIES = OBJECTS, &[]);

    #[test]
    fn the_profile_objects_are_a_valid_ascending_table_of_vars() {
        assert_eq!(PROFILE.validate(), Ok(()));
        assert_eq!(PROFILE_ENTRIES, OBJECTS.len());
        assert!(
            OBJECTS
                .iter()
                .all(|o| o.code == Var && o.entries.len() == 1)
        );
    }

    #[test]
    fn the_parameter_defaults_are_the_drives_defaults() {
        let d: &Dictionary = &PROFILE;
        let get = |i| match d
            .find_entry(i, 0)
            .and_then(|(_, e)| e.default_value().as_int())
        {
            Some(v) => v,
            None => panic!("{i:#06x}"),
        };
        let p = Parameters::DEFAULT;
        assert_eq!(
            get(index::QUICK_STOP_OPTION),
            i64::from(p.quick_stop_option)
        );
        assert_eq!(
            get(index::QUICK_STOP_DECELERATION),
            i64::from(p.quick_stop_deceleration)
        );
        assert_eq!(get(index::MAX_MOTOR_SPEED), i64::from(p.max_motor_speed));
        assert_eq!(get(index::HOMING_METHOD), i64::from(p.homing_method));
        assert_eq!(get(index::MODES_OF_OPERATION), 8);
        assert_eq!(get(index::SUPPORTED_DRIVE_MODES), 0x3A5);
    }

    #[test]
    fn only_set_points_are_rxpdo_mappable_and_the_mappings_have_the_sizes_they_say() {
        let bits = |o: &Object| -> u32 {
            o.entries
                .iter()
                .skip(1)
                .map(|e| match e.default_value() {
                    DefaultValue::Int(v) => (v.get() & 0xFF) as u32,
                    _ => 0,
                })
                .sum()
        };
        assert_eq!(bits(&RX_PDO) as usize, 8 * RX_PDO_BYTES);
        assert_eq!(bits(&TX_PDO) as usize, 8 * TX_PDO_BYTES);
        let mapped = |pdo: &Object, index: u16| {
            pdo.entries.iter().skip(1).any(|e| match e.default_value() {
                DefaultValue::Int(v) => (v.get() >> 16) as u16 == index,
                _ => false,
            })
        };
        for o in OBJECTS {
            let e = &o.entries[0];
            match e.pdo() {
                // C2 zeroes every RxPDO-mappable entry when OP is left:
                // only set points may be RxPDO-mappable.
                PdoMapping::Rx => assert!(mapped(&RX_PDO, o.index), "{:#06x}", o.index),
                PdoMapping::Tx => assert_eq!(e.access(), ecat_slave::od::Access::Ro),
                // Every other writable entry is a stored parameter.
                _ => assert!(
                    e.access() == ecat_slave::od::Access::Ro || (e.setting() && e.backup()),
                    "{:#06x}",
                    o.index
                ),
            }
        }
    }

    #[test]
    fn safety_parameters_are_stored_settings() {
        for i in SAFETY_PARAMETERS {
            let (_, e) = PROFILE.find_entry(i, 0).expect("object");
            assert!(
                e.setting() && e.backup() && e.pdo() == PdoMapping::None,
                "{i:#06x}"
            );
        }
    }

    #[test]
    fn join_concatenates_the_parts_in_order() {
        const A: &[Object] = &[obj(0x1000, "a", &[])];
        const PARTS: &[&[Object]] = &[A, OBJECTS, &[]];
        const ALL: [Object; object_count(PARTS)] = join(PARTS);
        assert_eq!(ALL.len(), 1 + OBJECTS.len());
        assert_eq!(ALL[0].index, 0x1000);
        assert_eq!(ALL[1].index, 0x6007);
        assert_eq!(ALL.last().map(|o| o.index), Some(0x6502));
    }
}
