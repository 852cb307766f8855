//! A small test device for the unit tests of the core and of the
//! simulator (feature `testing`): every dictionary shape the core handles
//! (VAR, RECORD with a padding gap, ARRAY, strings, an enumeration, ranges,
//! two PDO sets, the assignment objects) and an application with parameter
//! storage. It names no real device.

#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use crate::device::{
    Application, CoeServices, DeviceDescription, DeviceNames, EscConfig, FoeSecurity, Identity,
    MailboxConfig, PdoSet, ProcessData,
};
use crate::hal::{MemNv, NvStorage};
use crate::od::build::{
    assign, assign_count, constant, gap, input, map, output, pad, ranged, setting, string, sub0,
    var,
};
use crate::od::{DataType, EnumDesc, Limits, Object, ObjectCode, Od, PdoMapping};
use crate::params::{self, STORAGE_SIZE};

/// An enumeration of the test device.
pub const MODE: EnumDesc = EnumDesc {
    index: 0x0800,
    name: "DT0800EN08",
    bit_len: 8,
    values: &[(1, "ONE"), (2, "TWO")],
};

/// The test device's objects.
#[rustfmt::skip]
pub const OBJECTS: &[Object] = &[
    Object { index: 0x1000, name: "Device type", code: ObjectCode::Var, entries: &[
        var("Device type", DataType::UInt32, PdoMapping::None, 5001),
    ] },
    Object { index: 0x1001, name: "Error register", code: ObjectCode::Var, entries: &[
        var("Error register", DataType::UInt8, PdoMapping::None, 0),
    ] },
    Object { index: 0x1008, name: "Device name", code: ObjectCode::Var, entries: &[
        string("Device name", &Limits::text("TD-1")),
    ] },
    Object { index: 0x100A, name: "Software version", code: ObjectCode::Var, entries: &[
        string("Software version", &Limits::text("10")),
    ] },
    Object { index: 0x1018, name: "Identity", code: ObjectCode::Record, entries: &[
        sub0(4),
        constant(1, "Vendor ID", DataType::UInt32, 0x0000_0ABC),
        constant(2, "Product code", DataType::UInt32, 0x0000_0001),
        constant(3, "Revision", DataType::UInt32, 1),
        constant(4, "Serial number", DataType::UInt32, 0),
    ] },
    Object { index: 0x1600, name: "Outputs A", code: ObjectCode::Record, entries: &[
        sub0(3),
        map(1, "Enable", 0x7000_0101),
        pad(2, 7),
        map(3, "Value", 0x7000_0310),
    ] },
    Object { index: 0x1601, name: "Outputs B", code: ObjectCode::Record, entries: &[
        sub0(1),
        map(1, "Word", 0x7010_0020),
    ] },
    Object { index: 0x1A00, name: "Inputs A", code: ObjectCode::Record, entries: &[
        sub0(3),
        map(1, "Ready", 0x6000_0101),
        pad(2, 7),
        map(3, "Value", 0x6000_0310),
    ] },
    Object { index: 0x1A01, name: "Inputs B", code: ObjectCode::Record, entries: &[
        sub0(1),
        map(1, "Word", 0x6010_0020),
    ] },
    Object { index: 0x1C00, name: "SM types", code: ObjectCode::Array, entries: &[
        sub0(4),
        constant(1, "SubIndex 001", DataType::UInt8, 1),
        constant(2, "SubIndex 002", DataType::UInt8, 2),
        constant(3, "SubIndex 003", DataType::UInt8, 3),
        constant(4, "SubIndex 004", DataType::UInt8, 4),
    ] },
    Object { index: 0x1C12, name: "RxPDO assign", code: ObjectCode::Array, entries: &[
        assign_count(1, 1),
        assign(1, 0x1600),
    ] },
    Object { index: 0x1C13, name: "TxPDO assign", code: ObjectCode::Array, entries: &[
        assign_count(1, 2),
        assign(1, 0x1A00),
        assign(2, 0),
    ] },
    Object { index: 0x6000, name: "Inputs", code: ObjectCode::Record, entries: &[
        sub0(3),
        input(1, "Ready", DataType::Bool),
        gap(2, 7),
        input(3, "Value", DataType::Int16),
    ] },
    Object { index: 0x6010, name: "Input word", code: ObjectCode::Var, entries: &[
        var("Input word", DataType::UInt32, PdoMapping::Tx, 0),
    ] },
    Object { index: 0x7000, name: "Outputs", code: ObjectCode::Record, entries: &[
        sub0(3),
        output(1, "Enable", DataType::Bool),
        gap(2, 7),
        output(3, "Value", DataType::Int16),
    ] },
    Object { index: 0x7010, name: "Output word", code: ObjectCode::Var, entries: &[
        var("Output word", DataType::UInt32, PdoMapping::Rx, 0).with_access(crate::od::Access::Rw),
    ] },
    Object { index: 0x8000, name: "Settings", code: ObjectCode::Record, entries: &[
        sub0(3),
        ranged(1, "Gain", DataType::UInt16, 100, &Limits::range(0, 1000, "mA")),
        setting(2, "Mode", MODE.data_type(), 1, &Limits::NONE),
        ranged(3, "Offset", DataType::Int16, -5, &Limits::range(-100, 100, "")),
    ] },
    Object { index: 0x8001, name: "Curve", code: ObjectCode::Array, entries: &[
        sub0(4),
        ranged(1, "SubIndex 001", DataType::Int16, -10, &Limits::range(-1000, 1000, "")),
        ranged(2, "SubIndex 002", DataType::Int16, 0, &Limits::range(-1000, 1000, "")),
        ranged(3, "SubIndex 003", DataType::Int16, 10, &Limits::range(-1000, 1000, "")),
        ranged(4, "SubIndex 004", DataType::Int16, 20, &Limits::range(-1000, 1000, "")),
    ] },
];

crate::dictionary!(pub DICT, pub ENTRIES = OBJECTS, &[&MODE]);

/// The test device.
pub const DEVICE: DeviceDescription = DeviceDescription {
    identity: Identity {
        vendor_id: 0x0000_0ABC,
        product_code: 0x0000_0001,
        revision: 1,
        serial: 0,
    },
    names: DeviceNames {
        vendor: "Test vendor",
        type_name: "TD-1",
        name: "TD-1 test device",
        group_type: "Test",
        group_name: "Test devices",
    },
    dictionary: &DICT,
    process_data: ProcessData {
        sets: &[
            PdoSet {
                name: "A",
                rx: &[0x1600],
                tx: &[0x1A00],
            },
            PdoSet {
                name: "B",
                rx: &[0x1601],
                tx: &[0x1A01],
            },
        ],
    },
    mailbox: MailboxConfig {
        size: 128,
        boot_size: Some(1024),
        coe: CoeServices {
            sdo_info: true,
            pdo_assign: true,
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

/// The test application: echoes outputs into inputs, stores parameters.
#[derive(Debug, Default)]
pub struct TestApp {
    /// Parameter storage.
    pub nv: MemNv<STORAGE_SIZE>,
    /// Ticks seen.
    pub ticks: u64,
}

impl Application for TestApp {
    fn description(&self) -> &'static DeviceDescription {
        &DEVICE
    }
    type Values = [i64; ENTRIES];

    fn power_on(&mut self, od: &mut Od) {
        let _ = params::load(od, &self.nv);
    }

    fn tick(&mut self, tick: &mut crate::device::Tick<'_>) {
        self.ticks += 1;
        let v = tick.od.get(0x7000, 3).unwrap_or(0);
        tick.od.set(0x6000, 3, v);
        tick.od.set(0x6000, 1, i64::from(tick.outputs_valid));
    }

    fn nv(&self) -> Option<&dyn NvStorage> {
        Some(&self.nv)
    }

    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        Some(&mut self.nv)
    }
}

/// A store of the test device at its defaults.
pub fn store() -> crate::od::ObjectStore<[i64; ENTRIES]> {
    crate::od::ObjectStore::new(&DICT)
}
