//! What the DMA-22(A) node is, described once: identity and names, the
//! PDO set of its five slots, its mailbox ([`DEVICE`]), the address map and
//! identities ([`map`]), the chapter 7 parameter list ([`params`]) and the
//! object dictionary of the modular device ([`od`], ETG.5001). The ESI, the
//! SII, SDO Information, the PDO mapping and the application
//! ([`crate::app`]) all read it.
//!
//! Layers: `od` → `params` → `map`

use ecat_slave::device::{
    DeviceDescription, DeviceNames, EscConfig, Identity, MailboxConfig, PdoSet, ProcessData,
};

pub mod map;
pub mod od;
pub mod params;

pub use map::{DEVICE_NAME, MODULE_IDENT, PRODUCT_CODE, REVISION, SLOTS, VENDOR_ID};

/// The node, described once.
pub const DEVICE: DeviceDescription = DeviceDescription {
    identity: Identity {
        vendor_id: VENDOR_ID,
        product_code: PRODUCT_CODE,
        revision: REVISION,
        serial: 0,
    },
    names: DeviceNames {
        vendor: "HCS Hydraulic Control Systems GmbH",
        type_name: DEVICE_NAME,
        name: "DMA-22(A) EtherCAT node",
        group_type: "DMA",
        group_name: "HCS digital amplifiers",
    },
    dictionary: &od::DICT,
    process_data: ProcessData {
        sets: &[PdoSet {
            name: "Modules",
            rx: &[0x1600, 0x1601, 0x1602, 0x1603, 0x1604],
            tx: &[0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x1A04],
        }],
    },
    // 128-byte mailbox, SDO Information, PDO assignment, complete
    // access; no BOOT, no FoE.
    mailbox: MailboxConfig::STANDARD,
    esc: EscConfig::DEFAULT,
    modules: Some(&od::LAYOUT),
};

const _: () = DEVICE.assert_valid();
