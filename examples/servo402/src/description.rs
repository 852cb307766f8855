//! What the servo402 is: identity, names, object dictionary, PDO set,
//! mailbox. One `const` value; the ESI, the SII, SDO Information and the
//! PDO engine all read it.
//!
//! The dictionary is the drive's own communication objects, the CiA 402
//! profile's fixed PDO mappings, two manufacturer objects and the
//! profile's objects, joined in index order with
//! [`ecat_cia402::objects::join`] (see its documentation for why a
//! `const fn`).

use ecat_cia402::ModelParams;
use ecat_cia402::objects::{self, DEVICE_TYPE_SERVO, join, object_count};
use ecat_slave::device::{
    CoeServices, DeviceDescription, DeviceNames, EscConfig, FoeSecurity, Identity, MailboxConfig,
    PdoSet, ProcessData,
};
use ecat_slave::od::build::{
    SYNC_PARAMETER_ENTRIES, assign, assign_count, constant, string, sub_name, sub0, var,
};
use ecat_slave::od::{Access, DataType, Limits, Object, ObjectCode, PdoMapping};

/// Vendor ID of the servo402.
///
/// Example vendor ID: replace with your ETG-assigned vendor ID.
pub const VENDOR_ID: u32 = 0x0000_0ABE;
/// Product code of the servo402.
pub const PRODUCT_CODE: u32 = 0x0000_0402;
/// Revision number of the servo402.
pub const REVISION: u32 = 1;

/// 0x1010 "Store parameters" (CiA 301): writing [`SAVE_SIGNATURE`] into
/// subindex 1 saves the parameters (the profile's settings).
pub const STORE_PARAMETERS: u16 = 0x1010;
/// `"save"` in ASCII, little-endian: the value that triggers a save.
pub const SAVE_SIGNATURE: i64 = 0x6576_6173;
/// 0x2000 "Axis model": the simulated axis's constants (read-only).
pub const AXIS_MODEL: u16 = 0x2000;
/// 0x2001 "Power stage fault": the error code the board reports now (0:
/// none), what a fault reset waits for.
pub const POWER_STAGE_FAULT: u16 = 0x2001;

const MODEL: ModelParams = ModelParams::DEFAULT;

#[rustfmt::skip]
const HEAD: &[Object] = &[
    Object { index: 0x1000, name: "Device type", code: ObjectCode::Var, entries: &[
        var("Device type", DataType::UInt32, PdoMapping::None, DEVICE_TYPE_SERVO),
    ] },
    Object { index: 0x1001, name: "Error register", code: ObjectCode::Var, entries: &[
        var("Error register", DataType::UInt8, PdoMapping::None, 0),
    ] },
    Object { index: 0x1008, name: "Device name", code: ObjectCode::Var, entries: &[
        string("Device name", &Limits::text("SERVO402")),
    ] },
    // The core's firmware update writes the running version here.
    Object { index: 0x100A, name: "Software version", code: ObjectCode::Var, entries: &[
        string("Software version", &Limits::text("10")),
    ] },
    Object { index: STORE_PARAMETERS, name: "Store parameters", code: ObjectCode::Record, entries: &[
        sub0(1),
        // Reads 1: "the device saves parameters on command".
        constant(1, "Save all parameters", DataType::UInt32, 1).with_access(Access::Rw),
    ] },
    Object { index: 0x1018, name: "Identity", code: ObjectCode::Record, entries: &[
        sub0(4),
        constant(1, "Vendor ID", DataType::UInt32, VENDOR_ID as i64),
        constant(2, "Product code", DataType::UInt32, PRODUCT_CODE as i64),
        constant(3, "Revision", DataType::UInt32, REVISION as i64),
        constant(4, "Serial number", DataType::UInt32, 0),
    ] },
];

#[rustfmt::skip]
const SYNC_MANAGERS: &[Object] = &[
    Object { index: 0x1C00, name: "SM types", code: ObjectCode::Array, entries: &[
        sub0(4),
        constant(1, sub_name(1), DataType::UInt8, 1),
        constant(2, sub_name(2), DataType::UInt8, 2),
        constant(3, sub_name(3), DataType::UInt8, 3),
        constant(4, sub_name(4), DataType::UInt8, 4),
    ] },
    Object { index: 0x1C12, name: "RxPDO assign", code: ObjectCode::Array, entries: &[
        assign_count(1, 1), assign(1, 0x1600),
    ] },
    Object { index: 0x1C13, name: "TxPDO assign", code: ObjectCode::Array, entries: &[
        assign_count(1, 1), assign(1, 0x1A00),
    ] },
    // ETG.1020 synchronisation: free run or DC SYNC0, kept by the core.
    Object { index: 0x1C32, name: "SM output parameter", code: ObjectCode::Record, entries: SYNC_PARAMETER_ENTRIES },
    Object { index: 0x1C33, name: "SM input parameter", code: ObjectCode::Record, entries: SYNC_PARAMETER_ENTRIES },
];

#[rustfmt::skip]
const MANUFACTURER: &[Object] = &[
    Object { index: AXIS_MODEL, name: "Axis model", code: ObjectCode::Record, entries: &[
        sub0(3),
        constant(1, "Position loop time constant", DataType::UInt32, (MODEL.position_lag_ns / 1000) as i64),
        constant(2, "Rated acceleration", DataType::UInt32, MODEL.rated_acceleration),
        constant(3, "Coast deceleration", DataType::UInt32, MODEL.coast_deceleration),
    ] },
    Object { index: POWER_STAGE_FAULT, name: "Power stage fault", code: ObjectCode::Var, entries: &[
        var("Power stage fault", DataType::UInt16, PdoMapping::None, 0),
    ] },
];

const PARTS: &[&[Object]] = &[
    HEAD,
    objects::PDO_MAPPINGS,
    SYNC_MANAGERS,
    MANUFACTURER,
    objects::OBJECTS,
];

const ALL: [Object; object_count(PARTS)] = join(PARTS);

/// The servo402's objects, strictly ascending by index.
pub const OBJECTS: &[Object] = &ALL;

ecat_slave::dictionary!(pub DICT, pub ENTRIES = OBJECTS, &[]);

/// The servo402, described once.
pub const DEVICE: DeviceDescription = DeviceDescription {
    identity: Identity {
        vendor_id: VENDOR_ID,
        product_code: PRODUCT_CODE,
        revision: REVISION,
        serial: 0,
    },
    names: DeviceNames {
        vendor: "Example Devices",
        type_name: "SERVO402",
        name: "SERVO402 CiA 402 servo drive",
        group_type: "Drive",
        group_name: "Drives",
    },
    dictionary: &DICT,
    process_data: ProcessData {
        sets: &[PdoSet {
            name: "Cyclic synchronous",
            rx: &[0x1600],
            tx: &[0x1A00],
        }],
    },
    mailbox: MailboxConfig {
        size: 128,
        boot_size: Some(512),
        coe: CoeServices {
            sdo_info: true,
            pdo_assign: true,
            // The profile's mappings are writable in PRE-OP.
            pdo_config: true,
            complete_access: true,
        },
        foe: true,
        foe_security: FoeSecurity::OPEN,
    },
    esc: EscConfig::DEFAULT,
    modules: None,
};

// Every contradiction in the description is a build error.
const _: () = DEVICE.assert_valid();
