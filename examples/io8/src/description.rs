//! What the IO8 is: identity, names, object dictionary, PDO sets, mailbox.
//! One `const` value; the ESI, the SII, SDO Information and the PDO engine
//! all read it.

use ecat_slave::device::{
    CoeServices, DeviceDescription, DeviceNames, EscConfig, FoeSecurity, Identity, MailboxConfig,
    PdoSet, ProcessData,
};
use ecat_slave::od::build::{
    SYNC_PARAMETER_ENTRIES, assign, assign_count, constant, input, map, output, ranged, string,
    sub_name, sub0, var,
};
use ecat_slave::od::{Access, DataType, Limits, Object, ObjectCode, PdoMapping};

/// Vendor ID of the IO8.
///
/// Example vendor ID: replace with your ETG-assigned vendor ID.
pub const VENDOR_ID: u32 = 0x0000_0ABE;
/// Product code of the IO8.
pub const PRODUCT_CODE: u32 = 0x0000_0008;
/// Revision number of the IO8.
pub const REVISION: u32 = 1;

/// CiA 401 (generic I/O modules) device type with the "digital inputs"
/// (bit 16) and "digital outputs" (bit 17) flags.
pub const DEVICE_TYPE: i64 = 0x0003_0191;

/// 0x1010 "Store parameters" (CiA 301): writing [`SAVE_SIGNATURE`] into
/// subindex 1 saves the parameters.
pub const STORE_PARAMETERS: u16 = 0x1010;
/// `"save"` in ASCII, little-endian: the value that triggers a save.
pub const SAVE_SIGNATURE: i64 = 0x6576_6173;
/// The input object (TxPDO-mappable BOOLs, subindex n = input n).
pub const INPUTS: u16 = 0x6000;
/// The output object (RxPDO-mappable BOOLs, subindex n = output n).
pub const OUTPUTS: u16 = 0x7000;
/// The settings object; subindex 1 is the input filter time.
pub const SETTINGS: u16 = 0x8000;
/// Subindex of "Input filter" (UINT16, ms) in [`SETTINGS`].
pub const INPUT_FILTER: u8 = 1;

/// The IO8's objects, strictly ascending by index.
#[rustfmt::skip]
pub const OBJECTS: &[Object] = &[
    Object { index: 0x1000, name: "Device type", code: ObjectCode::Var, entries: &[
        var("Device type", DataType::UInt32, PdoMapping::None, DEVICE_TYPE),
    ] },
    Object { index: 0x1001, name: "Error register", code: ObjectCode::Var, entries: &[
        var("Error register", DataType::UInt8, PdoMapping::None, 0),
    ] },
    Object { index: 0x1008, name: "Device name", code: ObjectCode::Var, entries: &[
        string("Device name", &Limits::text("IO8")),
    ] },
    // The core's firmware update writes the running version here.
    Object { index: 0x100A, name: "Software version", code: ObjectCode::Var, entries: &[
        string("Software version", &Limits::text("10")),
    ] },
    // Reads 1: "the device saves parameters on command".
    Object { index: STORE_PARAMETERS, name: "Store parameters", code: ObjectCode::Record, entries: &[
        sub0(1),
        constant(1, "Save all parameters", DataType::UInt32, 1).with_access(Access::Rw),
    ] },
    Object { index: 0x1018, name: "Identity", code: ObjectCode::Record, entries: &[
        sub0(4),
        constant(1, "Vendor ID", DataType::UInt32, VENDOR_ID as i64),
        constant(2, "Product code", DataType::UInt32, PRODUCT_CODE as i64),
        constant(3, "Revision", DataType::UInt32, REVISION as i64),
        constant(4, "Serial number", DataType::UInt32, 0),
    ] },
    Object { index: 0x1600, name: "Outputs", code: ObjectCode::Record, entries: &[
        sub0(8),
        map(1, sub_name(1), 0x7000_0101),
        map(2, sub_name(2), 0x7000_0201),
        map(3, sub_name(3), 0x7000_0301),
        map(4, sub_name(4), 0x7000_0401),
        map(5, sub_name(5), 0x7000_0501),
        map(6, sub_name(6), 0x7000_0601),
        map(7, sub_name(7), 0x7000_0701),
        map(8, sub_name(8), 0x7000_0801),
    ] },
    Object { index: 0x1A00, name: "Inputs", code: ObjectCode::Record, entries: &[
        sub0(8),
        map(1, sub_name(1), 0x6000_0101),
        map(2, sub_name(2), 0x6000_0201),
        map(3, sub_name(3), 0x6000_0301),
        map(4, sub_name(4), 0x6000_0401),
        map(5, sub_name(5), 0x6000_0501),
        map(6, sub_name(6), 0x6000_0601),
        map(7, sub_name(7), 0x6000_0701),
        map(8, sub_name(8), 0x6000_0801),
    ] },
    Object { index: 0x1C00, name: "SM types", code: ObjectCode::Array, entries: &[
        sub0(4),
        constant(1, sub_name(1), DataType::UInt8, 1),
        constant(2, sub_name(2), DataType::UInt8, 2),
        constant(3, sub_name(3), DataType::UInt8, 3),
        constant(4, sub_name(4), DataType::UInt8, 4),
    ] },
    Object { index: 0x1C12, name: "RxPDO assign", code: ObjectCode::Array, entries: &[
        assign_count(1, 1),
        assign(1, 0x1600),
    ] },
    Object { index: 0x1C13, name: "TxPDO assign", code: ObjectCode::Array, entries: &[
        assign_count(1, 1),
        assign(1, 0x1A00),
    ] },
    // ETG.1020 synchronisation parameters, kept current by the core.
    Object { index: 0x1C32, name: "SM output parameter", code: ObjectCode::Record, entries: SYNC_PARAMETER_ENTRIES },
    Object { index: 0x1C33, name: "SM input parameter", code: ObjectCode::Record, entries: SYNC_PARAMETER_ENTRIES },
    Object { index: INPUTS, name: "Inputs", code: ObjectCode::Record, entries: &[
        sub0(8),
        input(1, "Input 1", DataType::Bool),
        input(2, "Input 2", DataType::Bool),
        input(3, "Input 3", DataType::Bool),
        input(4, "Input 4", DataType::Bool),
        input(5, "Input 5", DataType::Bool),
        input(6, "Input 6", DataType::Bool),
        input(7, "Input 7", DataType::Bool),
        input(8, "Input 8", DataType::Bool),
    ] },
    Object { index: OUTPUTS, name: "Outputs", code: ObjectCode::Record, entries: &[
        sub0(8),
        output(1, "Output 1", DataType::Bool),
        output(2, "Output 2", DataType::Bool),
        output(3, "Output 3", DataType::Bool),
        output(4, "Output 4", DataType::Bool),
        output(5, "Output 5", DataType::Bool),
        output(6, "Output 6", DataType::Bool),
        output(7, "Output 7", DataType::Bool),
        output(8, "Output 8", DataType::Bool),
    ] },
    Object { index: SETTINGS, name: "Settings", code: ObjectCode::Record, entries: &[
        sub0(1),
        ranged(INPUT_FILTER, "Input filter", DataType::UInt16, 10, &Limits::range(0, 1000, "ms")),
    ] },
];

ecat_slave::dictionary!(pub DICT, pub ENTRIES = OBJECTS, &[]);

/// Who may update the IO8's firmware: anyone with the password 0, and
/// unsigned images (`FoeSecurity::OPEN`). With the feature
/// `footprint-signed`, images must be signed with a placeholder key (a
/// build measured for the size of the signature check only).
#[cfg(not(feature = "footprint-signed"))]
const FOE_SECURITY: FoeSecurity = FoeSecurity::OPEN;
#[cfg(feature = "footprint-signed")]
const FOE_SECURITY: FoeSecurity = FoeSecurity {
    factory_password: 0,
    public_key: Some([
        0xd8, 0x4e, 0x79, 0xd1, 0x51, 0x53, 0x29, 0x1e, 0x01, 0x8e, 0xd3, 0x1d, 0x9e, 0xbf, 0x05,
        0x61, 0xe7, 0xdf, 0xd9, 0x45, 0x62, 0x2e, 0x5c, 0xda, 0x66, 0xeb, 0x30, 0x53, 0xad, 0xc2,
        0x23, 0x9a,
    ]),
};

/// The IO8, described once.
pub const DEVICE: DeviceDescription = DeviceDescription {
    identity: Identity {
        vendor_id: VENDOR_ID,
        product_code: PRODUCT_CODE,
        revision: REVISION,
        serial: 0,
    },
    names: DeviceNames {
        vendor: "Example Devices",
        type_name: "IO8",
        name: "IO8 8-channel digital I/O",
        group_type: "DigIO",
        group_name: "Digital I/O",
    },
    dictionary: &DICT,
    process_data: ProcessData {
        sets: &[PdoSet {
            name: "Standard",
            rx: &[0x1600],
            tx: &[0x1A00],
        }],
    },
    mailbox: MailboxConfig {
        size: 128,
        // 128 bytes in BOOT too, as SOES's defaults (MBXSIZE and
        // MBXSIZEBOOT 128): a firmware holds two mailbox-sized buffers
        // (the request and the response kept for the repeat service), so
        // 512 bytes would cost 768 bytes of RAM for a faster FoE download
        // (116 instead of 500 image bytes per packet).
        boot_size: if cfg!(feature = "footprint-no-foe") {
            None
        } else {
            Some(128)
        },
        coe: CoeServices {
            sdo_info: !cfg!(feature = "coe-minimal"),
            pdo_assign: true,
            pdo_config: false,
            complete_access: !cfg!(feature = "coe-minimal"),
        },
        foe: !cfg!(feature = "footprint-no-foe"),
        foe_security: FOE_SECURITY,
    },
    esc: EscConfig::DEFAULT,
    modules: None,
};

// Every contradiction in the description is a build error.
const _: () = DEVICE.assert_valid();
