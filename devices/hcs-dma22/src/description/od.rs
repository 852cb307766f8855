//! The object dictionary of the DMA-22(A) node as an ETG.5001 modular
//! device: the node's own objects, and per slot n (0..=4, module address
//! E22 = n + 1, index distance 0x10):
//!
//! | object | what |
//! |---|---|
//! | 0x1600 + n | RxPDO of module n: its CMD 15 block (control byte, process values 1 and 2) |
//! | 0x1A00 + n | TxPDO of module n: its CMD 15 answer (status word, values 1 and 2) |
//! | 0x6000 + 0x10·n | inputs: status word, value 1, value 2 |
//! | 0x7000 + 0x10·n | outputs: control byte, process value 1, process value 2 |
//! | 0x8000 + 0x10·n | parameters ID 0x00..=0xFE (subindex = ID + 1) |
//! | 0x8001 + 0x10·n | parameters ID 0xFF..=0x109 (subindex = ID − 0xFE) |
//! | 0xA000 + 0x10·n | diagnosis: error number, error count |
//!
//! The PDO entries are the 5 + 6 bytes a module has in CMD 15 (000 5.1,
//! 5.2); what the process values and values mean depends on the module's
//! operation mode E00 (5.5.2-5.5.6, see [`crate::app::model`]).

use ecat_slave::od::build::{
    SYNC_PARAMETER_ENTRIES, assign, assign_count, base, constant, input, map_to, output, string,
    sub_name, sub0, var,
};
use ecat_slave::od::modules::{ModularLayout, ModuleType, SlotRange};
use ecat_slave::od::{Access, DataType, Entry, Limits, Object, ObjectCode, PdoMapping};

use super::map::{DEVICE_NAME, MODULE_IDENT, PRODUCT_CODE, REVISION, SLOTS, VENDOR_ID};
pub use super::map::{
    DIAGNOSIS, INPUTS, OUTPUTS, PARAMS_HIGH, PARAMS_LOW, REQUEST, RESPONSE, parameter, ro, rw,
    slot_index,
};
use super::params::{PARAMETERS_HIGH, PARAMETERS_LOW};

/// Most bytes of a telegram in the channel (a CMD 15 for 5 modules has 28).
pub const MAX_TELEGRAM: usize = 32;

/// 0..=MAX_TELEGRAM bytes of a telegram (a constant: a `const fn` can
/// refer to it, not build it, as a `'static` reference).
const TELEGRAM_LENGTH: Limits = Limits::range(0, MAX_TELEGRAM as i64, "");

/// 0..=SLOTS modules.
const SLOT_COUNT: Limits = Limits::range(0, SLOTS as i64, "");

#[allow(
    clippy::indexing_slicing,
    reason = "evaluated only in const items: an index out of range fails the build"
)]
const fn telegram_entries(access: Access) -> [Entry; MAX_TELEGRAM + 2] {
    let mut l = [const { sub0(0) }; MAX_TELEGRAM + 2];
    l[0] = sub0(MAX_TELEGRAM as u8 + 1);
    let mut len = base(1, "Length", DataType::UInt8, access, PdoMapping::None, 0);
    len.limits = &TELEGRAM_LENGTH;
    l[1] = len;
    let mut k = 2;
    while k < l.len() {
        l[k] = base(
            k as u8,
            sub_name(k as u8),
            DataType::UInt8,
            access,
            PdoMapping::None,
            0,
        );
        k += 1;
    }
    l
}

/// Entries of 0x2000.
pub const REQUEST_ENTRIES: [Entry; MAX_TELEGRAM + 2] = telegram_entries(Access::Rw);
/// Entries of 0x2001.
pub const RESPONSE_ENTRIES: [Entry; MAX_TELEGRAM + 2] = telegram_entries(Access::Ro);

const INPUT_ENTRIES: &[Entry] = &[
    sub0(3),
    input(1, "Status word", DataType::UInt16),
    input(2, "Value 1", DataType::Int16),
    input(3, "Value 2", DataType::Int16),
];

const OUTPUT_ENTRIES: &[Entry] = &[
    sub0(3),
    output(1, "Control byte", DataType::UInt8),
    output(2, "Process value 1", DataType::Int16),
    output(3, "Process value 2", DataType::Int16),
];

const DIAGNOSIS_ENTRIES: &[Entry] = &[
    sub0(2),
    base(
        1,
        "Error number",
        DataType::UInt8,
        Access::Ro,
        PdoMapping::None,
        0,
    ),
    base(
        2,
        "Errors since power-on",
        DataType::UInt16,
        Access::Ro,
        PdoMapping::None,
        0,
    ),
];

const fn rx_map(n: u8) -> [Entry; 4] {
    let o = slot_index(OUTPUTS, n);
    [
        sub0(3),
        map_to(1, "Control byte", o, 1, 8),
        map_to(2, "Process value 1", o, 2, 16),
        map_to(3, "Process value 2", o, 3, 16),
    ]
}

const fn tx_map(n: u8) -> [Entry; 4] {
    let i = slot_index(INPUTS, n);
    [
        sub0(3),
        map_to(1, "Status word", i, 1, 16),
        map_to(2, "Value 1", i, 2, 16),
        map_to(3, "Value 2", i, 3, 16),
    ]
}

const RX0: [Entry; 4] = rx_map(0);
const RX1: [Entry; 4] = rx_map(1);
const RX2: [Entry; 4] = rx_map(2);
const RX3: [Entry; 4] = rx_map(3);
const RX4: [Entry; 4] = rx_map(4);
const TX0: [Entry; 4] = tx_map(0);
const TX1: [Entry; 4] = tx_map(1);
const TX2: [Entry; 4] = tx_map(2);
const TX3: [Entry; 4] = tx_map(3);
const TX4: [Entry; 4] = tx_map(4);

/// 0xF030 / 0xF050 entries: count and one ident per slot.
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated only in const items: an index out of range fails the build"
)]
const fn ident_list(access: Access) -> [Entry; 6] {
    let mut l = [
        sub0(SLOTS),
        constant(1, sub_name(1), DataType::UInt32, 0),
        constant(2, sub_name(2), DataType::UInt32, 0),
        constant(3, sub_name(3), DataType::UInt32, 0),
        constant(4, sub_name(4), DataType::UInt32, 0),
        constant(5, sub_name(5), DataType::UInt32, 0),
    ];
    let mut k = 0;
    while k < l.len() {
        l[k].flags = l[k].flags.with_access(access);
        k += 1;
    }
    l[0].limits = &SLOT_COUNT;
    l
}

const CONFIGURED: [Entry; 6] = {
    let mut l = ident_list(Access::RwPreOp);
    l[0].default_bits = 0;
    l
};
const DETECTED: [Entry; 6] = ident_list(Access::Ro);

/// Slot n's copies of one module object: the same name and entries in
/// every slot (the ESI describes a module object once, ETG.2000 `Module`).
macro_rules! per_slot {
    ($base:expr, $name:literal, $entries:expr) => {
        per_slot!(@ $base, $name, $entries, 0, 1, 2, 3, 4)
    };
    (@ $base:expr, $name:literal, $entries:expr, $($n:literal),*) => {
        [$(Object {
            index: slot_index($base, $n),
            name: $name,
            code: ObjectCode::Record,
            entries: $entries,
        }),*]
    };
}

use ObjectCode::{Array, Record, Var};
use PdoMapping::None as NoPdo;

#[rustfmt::skip]
const HEAD: &[Object] = &[
    // ETG.5001: device type = profile 5001 (0x1389).
    Object { index: 0x1000, name: "Device type", code: Var, entries: &[var("Device type", DataType::UInt32, NoPdo, 0x0000_1389)] },
    Object { index: 0x1001, name: "Error register", code: Var, entries: &[var("Error register", DataType::UInt8, NoPdo, 0)] },
    Object { index: 0x1008, name: "Device name", code: Var, entries: &[string("Device name", &Limits::text(DEVICE_NAME))] },
    Object { index: 0x1009, name: "Hardware version", code: Var, entries: &[string("Hardware version", &Limits::text("1"))] },
    Object { index: 0x100A, name: "Software version", code: Var, entries: &[string("Software version", &Limits::text("10.01"))] },
    Object { index: 0x1018, name: "Identity", code: Record, entries: &[
        sub0(4),
        constant(1, "Vendor ID", DataType::UInt32, VENDOR_ID as i64),
        constant(2, "Product code", DataType::UInt32, PRODUCT_CODE as i64),
        constant(3, "Revision", DataType::UInt32, REVISION as i64),
        constant(4, "Serial number", DataType::UInt32, 0),
    ] },
    Object { index: 0x1600, name: "DMA-22 RxPDO", code: Record, entries: &RX0 },
    Object { index: 0x1601, name: "DMA-22 RxPDO", code: Record, entries: &RX1 },
    Object { index: 0x1602, name: "DMA-22 RxPDO", code: Record, entries: &RX2 },
    Object { index: 0x1603, name: "DMA-22 RxPDO", code: Record, entries: &RX3 },
    Object { index: 0x1604, name: "DMA-22 RxPDO", code: Record, entries: &RX4 },
    Object { index: 0x1A00, name: "DMA-22 TxPDO", code: Record, entries: &TX0 },
    Object { index: 0x1A01, name: "DMA-22 TxPDO", code: Record, entries: &TX1 },
    Object { index: 0x1A02, name: "DMA-22 TxPDO", code: Record, entries: &TX2 },
    Object { index: 0x1A03, name: "DMA-22 TxPDO", code: Record, entries: &TX3 },
    Object { index: 0x1A04, name: "DMA-22 TxPDO", code: Record, entries: &TX4 },
    Object { index: 0x1C00, name: "Sync manager type", code: Array, entries: &[
        sub0(4),
        constant(1, sub_name(1), DataType::UInt8, 1),
        constant(2, sub_name(2), DataType::UInt8, 2),
        constant(3, sub_name(3), DataType::UInt8, 3),
        constant(4, sub_name(4), DataType::UInt8, 4),
    ] },
    Object { index: 0x1C12, name: "RxPDO assign", code: Array, entries: &[
        assign_count(5, 5),
        assign(1, 0x1600), assign(2, 0x1601), assign(3, 0x1602), assign(4, 0x1603), assign(5, 0x1604),
    ] },
    Object { index: 0x1C13, name: "TxPDO assign", code: Array, entries: &[
        assign_count(5, 5),
        assign(1, 0x1A00), assign(2, 0x1A01), assign(3, 0x1A02), assign(4, 0x1A03), assign(5, 0x1A04),
    ] },
    Object { index: 0x1C32, name: "SM output parameter", code: Record, entries: SYNC_PARAMETER_ENTRIES },
    Object { index: 0x1C33, name: "SM input parameter", code: Record, entries: SYNC_PARAMETER_ENTRIES },
    Object { index: REQUEST, name: "HCS telegram request", code: Record, entries: &REQUEST_ENTRIES },
    Object { index: RESPONSE, name: "HCS telegram response", code: Record, entries: &RESPONSE_ENTRIES },
];

const INPUT_OBJECTS: [Object; 5] = per_slot!(INPUTS, "DMA-22 inputs", INPUT_ENTRIES);
const OUTPUT_OBJECTS: [Object; 5] = per_slot!(OUTPUTS, "DMA-22 outputs", OUTPUT_ENTRIES);
const DIAGNOSIS_OBJECTS: [Object; 5] = per_slot!(DIAGNOSIS, "DMA-22 diagnosis", DIAGNOSIS_ENTRIES);
#[rustfmt::skip]
const PARAMETER_OBJECTS: [Object; 10] = {
    let low: [Object; 5] = per_slot!(PARAMS_LOW, "DMA-22 parameters 0x00-0xFE", PARAMETERS_LOW);
    let high: [Object; 5] = per_slot!(PARAMS_HIGH, "DMA-22 parameters 0xFF-0x109", PARAMETERS_HIGH);
    let [l0, l1, l2, l3, l4] = low;
    let [h0, h1, h2, h3, h4] = high;
    [l0, h0, l1, h1, l2, h2, l3, h3, l4, h4]
};

#[rustfmt::skip]
const TAIL: &[Object] = &[
    Object { index: 0xF000, name: "Modular device profile", code: Record, entries: &[
        sub0(2),
        constant(1, "Module index distance", DataType::UInt16, 0x10),
        constant(2, "Maximum number of modules", DataType::UInt16, SLOTS as i64),
    ] },
    Object { index: 0xF030, name: "Configured module ident list", code: Array, entries: &CONFIGURED },
    Object { index: 0xF050, name: "Detected module ident list", code: Array, entries: &DETECTED },
];

const fn copy(o: &Object) -> Object {
    Object {
        index: o.index,
        name: o.name,
        code: o.code,
        entries: o.entries,
    }
}

#[allow(
    clippy::indexing_slicing,
    reason = "evaluated only in const items: an index out of range fails the build"
)]
const fn join<const N: usize>(parts: &[&[Object]]) -> [Object; N] {
    let mut out = [const {
        Object {
            index: 0,
            name: "",
            code: ObjectCode::Var,
            entries: &[],
        }
    }; N];
    let mut k = 0;
    let mut p = 0;
    while p < parts.len() {
        let mut i = 0;
        while i < parts[p].len() {
            out[k] = copy(&parts[p][i]);
            k += 1;
            i += 1;
        }
        p += 1;
    }
    out
}

const PARTS: &[&[Object]] = &[
    HEAD,
    &INPUT_OBJECTS,
    &OUTPUT_OBJECTS,
    &PARAMETER_OBJECTS,
    &DIAGNOSIS_OBJECTS,
    TAIL,
];
const COUNT: usize = HEAD.len() + 25 + TAIL.len();
const ALL: [Object; COUNT] = join(PARTS);

/// Every object, ascending.
pub const OBJECTS: &[Object] = &ALL;

ecat_slave::dictionary!(pub DICT, pub ENTRIES = OBJECTS, &[]);

/// The DMA-22(A) module type.
pub const DMA22_MODULE: ModuleType = ModuleType {
    ident: MODULE_IDENT,
    type_name: "DMA-22(A)",
    name: "DMA-22(A) amplifier module",
    rx: &[0x1600],
    tx: &[0x1A00],
};

/// Slots, their object ranges and the module type.
pub const LAYOUT: ModularLayout = ModularLayout {
    slots: SLOTS,
    index_distance: 0x10,
    pdo_increment: 1,
    ranges: &[
        SlotRange {
            base: 0x1600,
            distance: 1,
            width: 1,
        },
        SlotRange {
            base: 0x1A00,
            distance: 1,
            width: 1,
        },
        SlotRange {
            base: INPUTS,
            distance: 0x10,
            width: 1,
        },
        SlotRange {
            base: OUTPUTS,
            distance: 0x10,
            width: 1,
        },
        SlotRange {
            base: PARAMS_LOW,
            distance: 0x10,
            width: 2,
        },
        SlotRange {
            base: DIAGNOSIS,
            distance: 0x10,
            width: 1,
        },
    ],
    modules: &[DMA22_MODULE],
};
