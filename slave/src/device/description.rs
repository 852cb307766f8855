//! The static description of a device: everything the ESI, the SII, SDO
//! Information, the PDO engine and the state machine need to know, in one
//! `const` value without heap.
//!
//! ```
//! # use ecat_slave::device::*;
//! # use ecat_slave::od::build::*;
//! # use ecat_slave::od::{DataType, Object, ObjectCode, PdoMapping};
//! # const OBJECTS: &[Object] = &[
//! #   Object { index: 0x1000, name: "Device type", code: ObjectCode::Var,
//! #     entries: &[var("Device type", DataType::UInt32, PdoMapping::None, 0)] },
//! #   Object { index: 0x1018, name: "Identity", code: ObjectCode::Record, entries: &[
//! #     sub0(4), constant(1, "Vendor ID", DataType::UInt32, 0xABC),
//! #     constant(2, "Product code", DataType::UInt32, 1),
//! #     constant(3, "Revision", DataType::UInt32, 1),
//! #     constant(4, "Serial number", DataType::UInt32, 0)] },
//! # ];
//! # ecat_slave::dictionary!(DICT, ENTRIES = OBJECTS, &[]);
//! const DEVICE: DeviceDescription = DeviceDescription {
//!     identity: Identity { vendor_id: 0xABC, product_code: 1, revision: 1, serial: 0 },
//!     names: DeviceNames {
//!         vendor: "ACME", type_name: "X1", name: "X1 demo",
//!         group_type: "Demo", group_name: "Demo devices",
//!     },
//!     dictionary: &DICT,
//!     process_data: ProcessData { sets: &[] },
//!     mailbox: MailboxConfig::STANDARD,
//!     esc: EscConfig::DEFAULT,
//!     modules: None,
//! };
//! const _: () = DEVICE.assert_valid(); // contradictions fail the build
//! ```

pub use crate::foe::FoeSecurity;
use crate::od::dictionary::{DescriptionError, Dictionary};
use crate::od::modules::{
    CONFIGURED_MODULES, DETECTED_MODULES, MODULAR_DEVICE_PROFILE, ModularLayout,
};
use crate::od::{DefaultValue, Object, PdoMapping};
use crate::pdo::{Direction, MAX_IMAGE, MAX_MAPPED};
pub use crate::pdo::{PdoSet, ProcessData};

/// Identity (object 0x1018 and SII words 0x08..0x0F).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Identity {
    /// Vendor ID (ETG-assigned).
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision number.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
}

/// Names as the ESI and the SII carry them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceNames {
    /// Vendor name (ESI `Vendor/Name`).
    pub vendor: &'static str,
    /// Order code / device type (ESI `Type`, SII string 1, General order).
    pub type_name: &'static str,
    /// Device name (ESI `Name`, General name).
    pub name: &'static str,
    /// Group type (ESI `GroupType`, General group).
    pub group_type: &'static str,
    /// Group display name (ESI `Groups/Group/Name`).
    pub group_name: &'static str,
}

/// CoE services the device offers (SII General "CoE details", ESI
/// `Mailbox/CoE` attributes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoeServices {
    /// SDO Information.
    pub sdo_info: bool,
    /// PDO assignment through 0x1C12/0x1C13.
    pub pdo_assign: bool,
    /// PDO mapping configuration through 0x16xx/0x1Axx (the core does not
    /// offer writable mappings yet; keep `false`).
    pub pdo_config: bool,
    /// SDO complete access.
    pub complete_access: bool,
}

impl CoeServices {
    /// The SII General "CoE details" byte (bit 0 SDO always set).
    pub const fn details(&self) -> u8 {
        0x01 | (self.sdo_info as u8) << 1
            | (self.pdo_assign as u8) << 2
            | (self.pdo_config as u8) << 3
            | (self.complete_access as u8) << 5
    }
}

/// Mailbox sizes and protocols.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MailboxConfig {
    /// Standard mailbox size in bytes (SM0 and SM1 each), 16..=1024.
    pub size: u16,
    /// Bootstrap mailbox size for BOOT (SM0/SM1 in BOOT), `None` when the
    /// device has no BOOT state (INIT→BOOT is refused with 0x0013).
    pub boot_size: Option<u16>,
    /// CoE services.
    pub coe: CoeServices,
    /// FoE firmware update in BOOT (needs `boot_size`).
    pub foe: bool,
    /// Who may update the firmware over FoE: the factory password and the
    /// key images must be signed with ([`FoeSecurity::OPEN`] for none).
    pub foe_security: FoeSecurity,
}

impl MailboxConfig {
    /// 128-byte mailbox, CoE with SDO Information, PDO assignment and
    /// complete access, no BOOT, no FoE.
    pub const STANDARD: MailboxConfig = MailboxConfig {
        size: 128,
        boot_size: None,
        coe: CoeServices {
            sdo_info: true,
            pdo_assign: true,
            pdo_config: false,
            complete_access: true,
        },
        foe: false,
        foe_security: FoeSecurity::OPEN,
    };
}

/// What the SII says about the ESC and the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EscConfig {
    /// PDI control (SII word 0, ESC 0x0140): 0x05 SPI.
    pub pdi_control: u16,
    /// EEPROM size in KiBit (the image must fit).
    pub eeprom_kbit: u16,
    /// Current taken from (positive) or fed into (negative) the E-Bus, mA.
    pub ebus_current_ma: i16,
    /// Physical ports, one nibble per port (0x0011: two MII ports).
    pub physical_ports: u16,
}

impl EscConfig {
    /// SPI PDI, 16 KiBit EEPROM, no E-Bus current, two MII ports.
    pub const DEFAULT: EscConfig = EscConfig {
        pdi_control: 0x0005,
        eeprom_kbit: 16,
        ebus_current_ma: 0,
        physical_ports: 0x0011,
    };
}

/// A device, described once.
#[derive(Debug, Clone, Copy)]
pub struct DeviceDescription {
    /// Identity (must equal 0x1018).
    pub identity: Identity,
    /// Names.
    pub names: DeviceNames,
    /// The object dictionary.
    pub dictionary: &'static Dictionary,
    /// PDO sets.
    pub process_data: ProcessData,
    /// Mailbox.
    pub mailbox: MailboxConfig,
    /// ESC and board data for the SII.
    pub esc: EscConfig,
    /// Slots and modules of a modular device (ETG.5001); `None` for a
    /// compact device.
    pub modules: Option<&'static ModularLayout>,
}

/// Physical layout of the mailboxes and process data buffers in ESC memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryLayout {
    /// Standard mailbox out (SM0, master to slave): start, length.
    pub mbx_out: (u16, u16),
    /// Standard mailbox in (SM1, slave to master): start, length.
    pub mbx_in: (u16, u16),
    /// Bootstrap mailbox out (SM0 in BOOT): start, length (0: no BOOT).
    pub boot_out: (u16, u16),
    /// Bootstrap mailbox in (SM1 in BOOT): start, length (0: no BOOT).
    pub boot_in: (u16, u16),
    /// Output process data buffer (SM2) start.
    pub pd_out: u16,
    /// Input process data buffer (SM3) start.
    pub pd_in: u16,
}

/// Largest mailbox the core handles.
pub const MAX_MAILBOX: usize = 1024;

impl MemoryLayout {
    /// Standard mailboxes of `size` bytes at 0x1000 and right after, the
    /// bootstrap mailboxes (if any) of `boot` bytes at 0x1000 and right
    /// after, process data after the standard mailboxes: outputs, then
    /// inputs [`DEFAULT_OUTPUT_AREA`](crate::pdo::DEFAULT_OUTPUT_AREA)
    /// bytes later. `None` for a size outside
    /// 16..=[`MAX_MAILBOX`].
    pub const fn new(size: u16, boot: Option<u16>) -> Option<Self> {
        if size < 16 || size as usize > MAX_MAILBOX {
            return None;
        }
        let boot = match boot {
            Some(b) if b < 16 || b as usize > MAX_MAILBOX => return None,
            Some(b) => b,
            None => 0,
        };
        let out = 0x1000;
        let pd_out = out + 2 * size;
        Some(MemoryLayout {
            mbx_out: (out, size),
            mbx_in: (out + size, size),
            boot_out: (out, boot),
            boot_in: (out + boot, boot),
            pd_out,
            pd_in: pd_out + crate::pdo::DEFAULT_OUTPUT_AREA as u16,
        })
    }

    /// The same layout with standard mailboxes of `size` bytes (16..=1024):
    /// SM0 at 0x1000, SM1 right after, process data after both; the
    /// bootstrap mailboxes stay.
    pub const fn with_mailbox_size(&self, size: u16) -> Option<Self> {
        let boot = if self.boot_out.1 == 0 {
            None
        } else {
            Some(self.boot_out.1)
        };
        Self::new(size, boot)
    }

    /// Whether the layout has a bootstrap mailbox (the device has BOOT).
    pub const fn has_boot(&self) -> bool {
        self.boot_out.1 != 0
    }
}

/// The largest process image of a description's PDO sets.
struct ImageBounds {
    /// Most entries one direction maps.
    entries: usize,
    /// Most bits one direction maps.
    bits: usize,
    /// A mapping entry of a set is writable (the master may change it).
    writable: bool,
}

/// The number of entries a PDO mapping object maps by default (its
/// subindex 0; 0 without one).
const fn mapped_count(o: &Object) -> i64 {
    match int_default(o, 0) {
        Some(c) => c,
        None => 0,
    }
}

/// Whether entry `e` of a mapping object is one of the `count` it maps.
const fn is_mapped(e: &crate::od::Entry, count: i64) -> bool {
    e.sub != 0 && e.sub as i64 <= count
}

const fn name_ok(s: &str) -> bool {
    !s.is_empty() && s.len() <= crate::sii::MAX_NAME_LEN
}

const fn int_default(o: &Object, sub: u8) -> Option<i64> {
    let mut es = o.entries;
    while let Some((e, tail)) = es.split_first() {
        if e.sub == sub {
            return match e.default_value() {
                DefaultValue::Int(v) => Some(v.get()),
                DefaultValue::Str(_) | DefaultValue::Bytes(_) => None,
            };
        }
        es = tail;
    }
    None
}

/// Subindex `sub` of `o` holds `v` (or is absent or a string).
const fn same(o: &Object, sub: u8, v: u32) -> bool {
    match int_default(o, sub) {
        Some(x) => x == v as i64,
        None => true,
    }
}

const fn find_object(objects: &'static [Object], index: u16) -> Option<&'static Object> {
    let mut rest = objects;
    while let Some((o, tail)) = rest.split_first() {
        if o.index == index {
            return Some(o);
        }
        rest = tail;
    }
    None
}

impl DeviceDescription {
    /// The largest mailbox of the device (standard or bootstrap), in
    /// bytes: the least `MBX` of a [`Slave`](super::Slave) for it. A
    /// `const fn`, so a firmware sizes its buffers from the description:
    /// `Slave<E, A, { DEVICE.largest_mailbox() }, ...>`.
    pub const fn largest_mailbox(&self) -> usize {
        let m = &self.mailbox;
        match m.boot_size {
            Some(b) if b > m.size => b as usize,
            _ => m.size as usize,
        }
    }

    /// The most entries and bytes one direction's process image takes in
    /// any PDO set of the description (`(entries, bytes)`): the least `PDO`
    /// and `IMG` of a [`Slave`](super::Slave) for it. A master assigns the
    /// PDOs of one set (the core refuses mixed sets) and, without
    /// `pdo_config`, cannot change a mapping, so no image is larger; with
    /// writable mappings (`pdo_config`, a twin's `rw` mapping entries) the
    /// bounds of the core ([`MAX_MAPPED`], [`MAX_IMAGE`]), as without PDO
    /// sets (any PDOs may then be assigned together). An assignment beyond
    /// these sizes (a PDO assigned twice) is refused at PRE-OP→SAFE-OP
    /// with 0x001D/0x001E, as any image the firmware cannot serve.
    pub const fn largest_image(&self) -> (usize, usize) {
        if self.mailbox.coe.pdo_config || self.process_data.sets.is_empty() {
            return (MAX_MAPPED, MAX_IMAGE);
        }
        match self.pdo_sets() {
            Ok(b) if !b.writable => (b.entries, b.bits.div_ceil(8)),
            // A mapping the master may rewrite (or a description
            // `validate` refuses).
            _ => (MAX_MAPPED, MAX_IMAGE),
        }
    }

    /// The memory layout the mailbox sizes imply.
    pub const fn layout(&self) -> MemoryLayout {
        match MemoryLayout::new(self.mailbox.size, self.mailbox.boot_size) {
            Some(l) => l,
            // `validate` refuses such sizes; fall back to 128 bytes.
            None => match MemoryLayout::new(128, None) {
                Some(l) => l,
                None => MemoryLayout {
                    mbx_out: (0x1000, 128),
                    mbx_in: (0x1080, 128),
                    boot_out: (0x1000, 0),
                    boot_in: (0x1000, 0),
                    pd_out: 0x1100,
                    pd_in: 0x1180,
                },
            },
        }
    }

    /// Bit mask of the PDO sets that contain `pdo` (bit n: set n).
    pub fn pdo_sets_of(&self, pdo: u16) -> u32 {
        let mut mask = 0u32;
        for (n, set) in self.process_data.sets.iter().enumerate().take(32) {
            if set.rx.contains(&pdo) || set.tx.contains(&pdo) {
                mask |= 1 << n;
            }
        }
        mask
    }

    /// Checks the description for contradictions: the dictionary
    /// ([`Dictionary::validate`]), names, mailbox sizes, 0x1000 and 0x1018
    /// present with 0x1018 equal to the identity, every PDO of every set a
    /// mapping object of its direction whose entries exist, are mappable in
    /// that direction and have their bit length, every set's image within
    /// [`MAX_IMAGE`] bytes and [`MAX_MAPPED`] entries, and 0x1C12/0x1C13
    /// (when present) defaulting to the first set.
    #[allow(
        clippy::indexing_slicing,
        reason = "const fn loops: every index is checked against the length first"
    )]
    pub const fn validate(&self) -> Result<(), DescriptionError> {
        if let Err(e) = self.dictionary.validate() {
            return Err(e);
        }
        let n = &self.names;
        if !name_ok(n.type_name) || !name_ok(n.name) || !name_ok(n.group_type) {
            return Err(DescriptionError::Name);
        }
        let m = &self.mailbox;
        if m.size < 16 || m.size as usize > MAX_MAILBOX {
            return Err(DescriptionError::MailboxSize);
        }
        if let Some(b) = m.boot_size
            && (b < 16 || b as usize > MAX_MAILBOX)
        {
            return Err(DescriptionError::MailboxSize);
        }
        let objects = self.dictionary.objects();
        if find_object(objects, 0x1000).is_none() {
            return Err(DescriptionError::MissingObject { index: 0x1000 });
        }
        let Some(id) = find_object(objects, 0x1018) else {
            return Err(DescriptionError::MissingObject { index: 0x1018 });
        };
        let i = &self.identity;
        if !same(id, 1, i.vendor_id) || !same(id, 2, i.product_code) || !same(id, 3, i.revision) {
            return Err(DescriptionError::Identity);
        }
        if self.modules.is_some() {
            let mut k = 0;
            let needed = [MODULAR_DEVICE_PROFILE, CONFIGURED_MODULES, DETECTED_MODULES];
            while k < needed.len() {
                if find_object(objects, needed[k]).is_none() {
                    return Err(DescriptionError::MissingObject { index: needed[k] });
                }
                k += 1;
            }
        }
        if let Err(e) = self.pdo_sets() {
            return Err(e);
        }
        Ok(())
    }

    /// The checks of the PDO sets (every PDO a mapping object whose
    /// entries exist and may be mapped in its direction, the image within
    /// the core's bounds, the first set the default assignment) and the
    /// largest image one direction takes in any set.
    #[allow(
        clippy::indexing_slicing,
        reason = "const fn loops: every index is checked against the length first"
    )]
    const fn pdo_sets(&self) -> Result<ImageBounds, DescriptionError> {
        let objects = self.dictionary.objects();
        let mut bounds = ImageBounds {
            entries: 0,
            bits: 0,
            writable: false,
        };
        let sets = self.process_data.sets;
        let mut s = 0usize;
        while s < sets.len() {
            let set = &sets[s];
            let mut d = 0;
            while d < 2 {
                let (list, dir) = if d == 0 {
                    (set.rx, Direction::Outputs)
                } else {
                    (set.tx, Direction::Inputs)
                };
                let (lo, hi) = dir.pdo_range();
                let want = match dir {
                    Direction::Outputs => PdoMapping::Rx,
                    Direction::Inputs => PdoMapping::Tx,
                };
                let mut bits = 0usize;
                let mut mapped = 0usize;
                let mut k = 0;
                while k < list.len() {
                    let pdo = list[k];
                    let Some(o) = find_object(objects, pdo) else {
                        return Err(DescriptionError::UnknownPdo { set: s, pdo });
                    };
                    if pdo < lo || pdo > hi {
                        return Err(DescriptionError::UnknownPdo { set: s, pdo });
                    }
                    let count = mapped_count(o);
                    let mut es = o.entries;
                    while let Some((e, tail)) = es.split_first() {
                        es = tail;
                        if !is_mapped(e, count) {
                            continue;
                        }
                        bounds.writable |= e.access().writable();
                        let DefaultValue::Int(mapping) = e.default_value() else {
                            return Err(DescriptionError::BadMapping { pdo, sub: e.sub });
                        };
                        let mapping = mapping.get() as u32;
                        let index = (mapping >> 16) as u16;
                        let msub = ((mapping >> 8) & 0xFF) as u8;
                        let mbits = (mapping & 0xFF) as u16;
                        if mbits == 0 {
                            return Err(DescriptionError::BadMapping { pdo, sub: e.sub });
                        }
                        if index != 0 {
                            let Some(target) = find_object(objects, index) else {
                                return Err(DescriptionError::BadMapping { pdo, sub: e.sub });
                            };
                            let mut found = false;
                            let mut ts = target.entries;
                            while let Some((t, tt)) = ts.split_first() {
                                if t.sub == msub {
                                    found = true;
                                    let ok = !t.gap() && t.bit_len == mbits && t.pdo().allows(want);
                                    if !ok {
                                        return Err(DescriptionError::BadMapping {
                                            pdo,
                                            sub: e.sub,
                                        });
                                    }
                                }
                                ts = tt;
                            }
                            if !found {
                                return Err(DescriptionError::BadMapping { pdo, sub: e.sub });
                            }
                        }
                        bits += mbits as usize;
                        mapped += 1;
                    }
                    k += 1;
                }
                if bits > MAX_IMAGE * 8 || mapped > MAX_MAPPED {
                    return Err(DescriptionError::ImageTooLarge { set: s });
                }
                if mapped > bounds.entries {
                    bounds.entries = mapped;
                }
                if bits > bounds.bits {
                    bounds.bits = bits;
                }
                // The default assignment is the first set.
                if s == 0
                    && let Some(a) = find_object(objects, dir.assign_index())
                {
                    let count = match int_default(a, 0) {
                        Some(c) => c,
                        None => -1,
                    };
                    if count != list.len() as i64 {
                        return Err(DescriptionError::DefaultAssignment);
                    }
                    let mut k = 0;
                    while k < list.len() {
                        match int_default(a, (k + 1) as u8) {
                            Some(v) if v == list[k] as i64 => {}
                            _ => return Err(DescriptionError::DefaultAssignment),
                        }
                        k += 1;
                    }
                }
                d += 1;
            }
            s += 1;
        }
        Ok(bounds)
    }

    /// [`Self::validate`] as a `const` assertion: `const _: () =
    /// DEVICE.assert_valid();` fails the build with the reason. Meant for
    /// `const` items only (at run time it would panic).
    #[allow(
        clippy::panic,
        reason = "evaluated in const items: a contradiction becomes a build error"
    )]
    pub const fn assert_valid(&self) {
        if let Err(e) = self.validate() {
            panic!("{}", e.message());
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::testing::DEVICE;

    #[test]
    fn buffer_sizes_come_from_the_largest_mailbox_and_pdo_set() {
        // 128-byte standard and 1024-byte bootstrap mailboxes.
        assert_eq!(DEVICE.largest_mailbox(), 1024);
        // Set A: 3 entries (BOOL, 7 padding bits, INT16) in 3 bytes per
        // direction; set B's inputs: one UDINT, 4 bytes.
        assert_eq!(DEVICE.largest_image(), (3, 4));
        // Constants: usable as `Slave`'s const generics.
        const SIZES: (usize, usize) = DEVICE.largest_image();
        assert_eq!(SIZES.0, 3);
    }
}
