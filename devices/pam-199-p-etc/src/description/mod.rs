//! What the PAM-199-P-ETC is, described once: its identity, names, PDO
//! sets and mailbox ([`DEVICE`]) and its object dictionary ([`od`], manual
//! chapter 6). The ESI, the SII, SDO Information, the PDO mapping and the
//! application ([`crate::app`]) all read it.

use ecat_slave::device::{
    CoeServices, DeviceDescription, DeviceNames, EscConfig, FoeSecurity, Identity, MailboxConfig,
    PdoSet, ProcessData,
};
use ecat_slave::od::Od;

pub mod od;

/// Full scale of the command and feedback values: 10000 = 100 % in units of
/// 0.01 % (manual 6.5, the signal chain's unit).
pub const FULL_SCALE: i32 = 10_000;

/// Vendor ID of W.E.St. Elektronik GmbH.
pub const VENDOR_ID: u32 = 0x0000_05AE;
/// Product code of the PAM-199-P-ETC.
pub const PRODUCT_CODE: u32 = 0x00C7_03F3;
/// Revision number.
pub const REVISION: u32 = 7;
/// Device name.
pub const DEVICE_NAME: &str = "PAM-199-P-ETC";

/// Name of the default PDO assignment (manual 7.1, "Case 1").
pub const DIRECTIONAL_MAPPING: &str = "Directional Mode (Extended)";
/// Name of the alternative PDO assignment (manual 7.1, "Case 2").
pub const INDEPENDENT_MAPPING: &str = "Independent Mode (Extended)";

/// The PAM-199-P-ETC, described once.
pub const DEVICE: DeviceDescription = DeviceDescription {
    identity: Identity {
        vendor_id: VENDOR_ID,
        product_code: PRODUCT_CODE,
        revision: REVISION,
        serial: 0,
    },
    names: DeviceNames {
        vendor: "W.E.St. Elektronik GmbH",
        type_name: DEVICE_NAME,
        name: DEVICE_NAME,
        group_type: "PAM",
        group_name: "PAM amplifiers",
    },
    dictionary: &od::DICT,
    process_data: ProcessData {
        sets: &[
            PdoSet {
                name: DIRECTIONAL_MAPPING,
                rx: &[0x1600],
                tx: &[0x1A00, 0x1A02],
            },
            PdoSet {
                name: INDEPENDENT_MAPPING,
                rx: &[0x1601],
                tx: &[0x1A01, 0x1A03],
            },
        ],
    },
    mailbox: MailboxConfig {
        size: 128,
        boot_size: Some(1024),
        coe: CoeServices {
            sdo_info: true,
            pdo_assign: true,
            // The mappings are fixed.
            pdo_config: false,
            complete_access: true,
        },
        foe: true,
        foe_security: FoeSecurity::OPEN,
    },
    esc: EscConfig::DEFAULT,
    modules: None,
};

const _: () = DEVICE.assert_valid();

/// The PDO set F800:02 FUNCTION selects: 0 directional, 1 independent.
pub fn function_set(od: &Od) -> usize {
    if od.get(0xF800, 2) == Some(2) { 1 } else { 0 }
}
