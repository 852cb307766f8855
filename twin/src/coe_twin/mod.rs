//! A twin of a device with a mailbox: the core's firmware ([`Slave`] on
//! the software ESC, with its CoE server, SDO Information, PDO engine and
//! AL state machine) running a [`DeviceDescription`] built at run time
//! from the ESI.
//!
//! The description takes: identity and names; the dictionary
//! ([`crate::dictionary`]; 0x1018:01..03 always carry the ESI identity),
//! or, for an ESI without one, a dictionary made from the PDOs
//! (`synthesize`);
//! the mailbox from the `MBoxOut`/`MBoxIn` SyncManagers, the bootstrap
//! mailbox from `Eeprom/BootStrap`, CoE services from `Mailbox/CoE`, FoE
//! from `Mailbox/FoE`; PDO sets from
//! `VendorSpecific/TwinCAT/AlternativeSmMapping`, else the default
//! assignment (0x1C12/0x1C13) plus sets that honour `Exclude`
//! ([`alternative_sets`]); ESC settings from `Eeprom` and `Electrical`. The memory layout
//! follows the ESI's SyncManager addresses.
//!
//! Behaviour is generic ([`EsiApp`]): outputs are stored, inputs follow
//! the [`InputRule`].
//!
//! [`Slave`]: ecat_slave::device::Slave

//!
//! Files: `complete.rs` fills in what the ESI's dictionary lacks and
//! normalises it, `pdo_sets.rs` the PDO sets, `modular.rs` slots and
//! modules, `app.rs` the behaviour; this file builds the description from
//! them.

mod app;
mod complete;
mod modular;
mod pdo_sets;

pub use app::{EsiApp, slave};
pub use modular::default_modules;
pub use pdo_sets::alternative_sets;

use complete::{complete, drop_impossible_ranges, normalize_assignment};
use modular::modular;
use pdo_sets::{assigned, pdo_sets};

use ecat_sim::SoftSlave;
use ecat_slave::device::{
    Application, CoeServices, DeviceDescription, EscConfig, MailboxConfig, MemoryLayout, PdoSet,
    ProcessData, Tick,
};
use ecat_slave::od::build::{assign, assign_count, constant, input, map, output, sub0, var};
use ecat_slave::od::{DataType, DefaultValue, Entry, Object, ObjectCode, PdoMapping};
use ecat_slave::sii::{SmType, protocols};

use crate::esc_twin::InputRule;
use crate::esi::{At, EsiDevice, EsiError, Warning};
use crate::xml::hex_binary;
use crate::{dictionary, leak};

/// Most dictionary entries a twin can hold (its value storage).
pub const TWIN_ENTRIES: usize = 4096;

/// Why the description of a device with a mailbox cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DescriptionBuildError {
    /// The ESI is wrong (element and line inside).
    #[error(transparent)]
    Esi(#[from] EsiError),
    /// A PDO entry of a device without a dictionary has a type the core
    /// does not serve (the dictionary is made from the PDOs).
    #[error(
        "{at}: PDO entry {index:#06x}:{sub:02x} has data type code {code:#04x}, which twins do not serve yet"
    )]
    UnsupportedEntryType {
        /// The PDO element.
        at: At,
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// CoE data type code.
        code: u8,
    },
    /// More entries than a twin holds.
    #[error("{device}: {entries} dictionary entries, a twin holds at most {TWIN_ENTRIES}")]
    TooManyEntries {
        /// The device.
        device: String,
        /// Entries.
        entries: usize,
    },
    /// The description contradicts itself (the core's check).
    #[error("{device}: {source}")]
    Contradiction {
        /// The device.
        device: String,
        /// What the core's check found.
        source: ecat_slave::od::DescriptionError,
    },
    /// A process-data area the ESI gives no SyncManager for would be placed
    /// (after the SyncManager named) beyond the ESC's address space.
    #[error(
        "{at}: the {what} placed after this SyncManager would start at {start:#x}, beyond the ESC address space (0xffff)"
    )]
    NoRoomFor {
        /// The `Sm` element it would follow.
        at: At,
        /// `outputs` or `inputs`.
        what: &'static str,
        /// Where it would start.
        start: u32,
    },
    /// A mailbox SyncManager is missing.
    #[error("{0}: the ESI has a mailbox protocol but no MBoxOut/MBoxIn SyncManager")]
    NoMailboxSm(String),
    /// A mailbox is longer than a twin's firmware buffers hold (the core's
    /// [`MAX_MAILBOX`](ecat_slave::device::MAX_MAILBOX)).
    #[error(
        "{device}: the {which} mailbox is {len} bytes long; a twin serves mailboxes of at most {max} bytes"
    )]
    MailboxTooLong {
        /// The device.
        device: String,
        /// `MBoxOut`, `MBoxIn`, or the bootstrap `out` / `in` mailbox.
        which: &'static str,
        /// Its length in the ESI.
        len: u16,
        /// The longest a twin serves.
        max: usize,
    },
    /// A modular device's slots or modules cannot be used.
    #[error("{at}: {problem}")]
    Modular {
        /// The element.
        at: At,
        /// What is wrong.
        problem: String,
    },
}

pub(super) fn leak_list(v: Vec<u16>) -> &'static [u16] {
    Box::leak(v.into_boxed_slice())
}

/// The defaults of a list object (a PDO assignment or mapping): the
/// values of subindices 1 to subindex 0's default (-1 for one that is no
/// number).
pub(super) fn list_defaults(o: &Object) -> Vec<i64> {
    let count = o
        .entries
        .first()
        .and_then(|e| e.default_value().as_int())
        .unwrap_or(0);
    o.entries
        .iter()
        .filter(|e| e.sub >= 1 && i64::from(e.sub) <= count)
        .map(|e| e.default_value().as_int().unwrap_or(-1))
        .collect()
}

/// A copy of `e` (every field of an entry is `Copy`).
pub(super) fn copy(e: &Entry) -> Entry {
    Entry { ..*e }
}

pub(super) fn sm(dev: &EsiDevice, kind: SmType) -> Option<(u16, u16)> {
    dev.sms
        .iter()
        .find(|s| s.kind == kind)
        .map(|s| (s.start, s.default_size))
}

pub(super) fn record(index: u16, name: &str, entries: Vec<Entry>) -> Object {
    Object {
        index,
        name: leak(name),
        code: ObjectCode::Record,
        entries: Box::leak(entries.into_boxed_slice()),
    }
}

pub(super) fn array(index: u16, name: &str, entries: Vec<Entry>) -> Object {
    Object {
        code: ObjectCode::Array,
        ..record(index, name, entries)
    }
}

/// A description, its memory layout and what the loader left out or
/// assumed building it.
pub type Described = (&'static DeviceDescription, MemoryLayout, &'static [Warning]);

/// Descriptions built so far, one per distinct device.
static DESCRIPTIONS: crate::Cache<Described> = crate::Cache::new();

/// The twin's description and memory layout for `dev`. Built and leaked
/// once per distinct device: describing an equal device again returns the
/// same description.
pub fn describe(
    dev: &EsiDevice,
) -> Result<(&'static DeviceDescription, MemoryLayout), DescriptionBuildError> {
    describe_with_warnings(dev).map(|(d, l, _)| (d, l))
}

/// [`describe`] with the warnings: what of the ESI the twin leaves out or
/// assumes (the load's [`EsiDevice::warnings`] included), each naming the
/// element and line.
pub fn describe_with_warnings(dev: &EsiDevice) -> Result<Described, DescriptionBuildError> {
    DESCRIPTIONS.get_or_build(dev, build_description)
}

/// [`describe`] without the cache.
pub(super) fn build_description(dev: &EsiDevice) -> Result<Described, DescriptionBuildError> {
    let label = dev.label();
    // ETG.2000 requires it; the SII General category of a CoE device
    // carries it.
    if dev.group_type.is_empty() {
        return Err(EsiError::Missing {
            at: dev.at.clone(),
            what: "<GroupType>",
        }
        .into());
    }
    let mut warnings = dev.warnings.clone();
    let (mut parsed, enums): (Vec<Object>, _) = match dev.source.path("Profile/Dictionary") {
        Some(dict_el) => {
            let (parsed, enums, mut w) = dictionary::parse(dict_el)?;
            warnings.append(&mut w);
            (parsed.into_iter().map(|p| p.object).collect(), enums)
        }
        None => (Vec::new(), Vec::new()),
    };
    let left_out = complete(dev, &mut parsed, &mut warnings);
    for index in [0x1C12u16, 0x1C13] {
        normalize_assignment(dev, &mut parsed, index, &left_out, &mut warnings);
    }
    drop_impossible_ranges(dev, &mut parsed, &mut warnings);
    // Writable strings beyond the store's string slots are served
    // read-only (the core keeps STRING_SLOTS of them).
    let mut strings = 0usize;
    for o in parsed.iter_mut() {
        let mut changed = None;
        for (k, e) in o.entries.iter().enumerate() {
            if let DefaultValue::Str(t) = e.default_value() {
                let slot = t.len() <= ecat_slave::od::STRING_CAPACITY;
                if e.access().writable() && (!slot || strings >= ecat_slave::od::STRING_SLOTS) {
                    changed.get_or_insert_with(Vec::new).push(k);
                }
                if slot {
                    strings += 1;
                }
            }
        }
        if let Some(ks) = changed {
            warnings.push(Warning {
                at: dev.at.clone(),
                message: format!(
                    "object {:#06x}: a writable string beyond the twin's {} string slots of {} bytes is served read-only",
                    o.index,
                    ecat_slave::od::STRING_SLOTS,
                    ecat_slave::od::STRING_CAPACITY
                ),
            });
            let mut entries: Vec<Entry> = o.entries.iter().map(copy).collect();
            for k in ks {
                if let Some(e) = entries.get_mut(k) {
                    e.flags = e.flags.with_access(ecat_slave::od::Access::Ro);
                }
            }
            o.entries = Box::leak(entries.into_boxed_slice());
        }
    }
    let mut objects: Vec<Object> = Vec::with_capacity(parsed.len());
    for o in parsed {
        if o.index == 0x1018 {
            // The identity the device answers with is the ESI's.
            let id = [dev.vendor_id, dev.product_code, dev.revision];
            let entries: Vec<Entry> = o
                .entries
                .iter()
                .map(|e| match e.sub {
                    s @ 1..=3 => crate::with_default(
                        e,
                        DefaultValue::int(i64::from(
                            id.get(usize::from(s) - 1).copied().unwrap_or(0),
                        )),
                    ),
                    _ => copy(e),
                })
                .collect();
            objects.push(Object {
                entries: Box::leak(entries.into_boxed_slice()),
                ..o
            });
        } else {
            objects.push(o);
        }
    }
    let modular = match dev.source.child("Slots") {
        Some(slots) => modular(dev, slots, &mut objects, &mut warnings)?,
        None => None,
    };
    let entries = ecat_slave::od::dictionary::value_slots(&objects);
    if entries > TWIN_ENTRIES {
        return Err(DescriptionBuildError::TooManyEntries {
            device: label,
            entries,
        });
    }
    let sets = pdo_sets(dev, &objects, &left_out)?;
    let (mbx_out, mbx_in) = match (sm(dev, SmType::MailboxOut), sm(dev, SmType::MailboxIn)) {
        (Some(o), Some(i)) => (o, i),
        _ => return Err(DescriptionBuildError::NoMailboxSm(label)),
    };
    let boot = match dev.source.path("Eeprom/BootStrap") {
        Some(b) => {
            let bytes = hex_binary(&b.text).ok_or_else(|| EsiError::BadValue {
                at: At {
                    element: b.name.clone(),
                    line: b.line,
                },
                what: "hexBinary",
                value: b.text.clone(),
            })?;
            let w = |k: usize| {
                u16::from_le_bytes([
                    bytes.get(2 * k).copied().unwrap_or(0),
                    bytes.get(2 * k + 1).copied().unwrap_or(0),
                ])
            };
            Some(((w(0), w(1)), (w(2), w(3))))
        }
        None => None,
    }
    .filter(|((_, out_len), _)| *out_len != 0);
    // Process data without an <Sm> of its own: outputs right after the
    // input mailbox, inputs 0x100 bytes after the outputs; within 0xFFFF.
    let after = |base: u16, gap: u16, kind: SmType, what: &'static str| {
        let start = u32::from(base) + u32::from(gap);
        u16::try_from(start).map_err(|_| DescriptionBuildError::NoRoomFor {
            at: dev
                .sms
                .iter()
                .find(|s| s.kind == kind)
                .map_or_else(|| dev.at.clone(), |s| s.at.clone()),
            what,
            start,
        })
    };
    let pd_out = match sm(dev, SmType::ProcessOut) {
        Some(s) => s.0,
        None => after(mbx_in.0, mbx_in.1, SmType::MailboxIn, "outputs")?,
    };
    let pd_in = match (sm(dev, SmType::ProcessIn), sm(dev, SmType::ProcessOut)) {
        (Some(s), _) => s.0,
        (None, Some(_)) => after(pd_out, 0x100, SmType::ProcessOut, "inputs")?,
        (None, None) => after(pd_out, 0x100, SmType::MailboxIn, "inputs")?,
    };
    let eeprom_kbit = dev.eeprom_kbit().ok_or_else(|| EsiError::BadValue {
        at: dev.at.clone(),
        what: crate::esi::EEPROM_SIZE,
        value: dev.eeprom_bytes.unwrap_or(0).to_string(),
    })?;
    let layout = MemoryLayout {
        mbx_out,
        mbx_in,
        boot_out: boot.map_or((mbx_out.0, 0), |b| b.0),
        boot_in: boot.map_or((mbx_in.0, 0), |b| b.1),
        pd_out,
        pd_in,
    };
    // The firmware's buffers hold MAX_MAILBOX bytes; the description's
    // check sees the output mailboxes only, so the input ones are checked
    // here too (a longer one would not fit the firmware's buffers).
    let max = ecat_slave::device::MAX_MAILBOX;
    for (which, len) in [
        ("MBoxOut", layout.mbx_out.1),
        ("MBoxIn", layout.mbx_in.1),
        ("bootstrap out", layout.boot_out.1),
        ("bootstrap in", layout.boot_in.1),
    ] {
        if usize::from(len) > max {
            return Err(DescriptionBuildError::MailboxTooLong {
                device: dev.label(),
                which,
                len,
                max,
            });
        }
    }
    let coe = dev.coe_details;
    let cd = &dev.config_data;
    let (identity, names) = crate::identity_and_names(dev);
    let desc: &'static DeviceDescription = Box::leak(Box::new(DeviceDescription {
        identity,
        names,
        dictionary: dictionary::build(objects, enums),
        process_data: ProcessData { sets },
        mailbox: MailboxConfig {
            size: mbx_out.1,
            boot_size: boot.map(|b| b.0.1),
            coe: CoeServices {
                sdo_info: coe & 0x02 != 0,
                pdo_assign: coe & 0x04 != 0,
                pdo_config: coe & 0x08 != 0,
                complete_access: coe & 0x20 != 0,
            },
            foe: dev.mailbox_protocols & protocols::FOE != 0 && boot.is_some(),
            foe_security: ecat_slave::device::FoeSecurity::OPEN,
        },
        esc: EscConfig {
            pdi_control: u16::from_le_bytes([
                cd.first().copied().unwrap_or(0x05),
                cd.get(1).copied().unwrap_or(0),
            ]),
            eeprom_kbit,
            ebus_current_ma: dev.ebus_current_ma,
            physical_ports: crate::sii::physical_port(&dev.physics),
        },
        modules: modular.map(|m| &*Box::leak(Box::new(m))),
    }));
    desc.validate()
        .map_err(|source| DescriptionBuildError::Contradiction {
            device: dev.label(),
            source,
        })?;
    Ok((desc, layout, Box::leak(warnings.into_boxed_slice())))
}

#[cfg(test)]
mod tests {
    use super::modular::modular_objects;
    use super::*;
    use crate::esi::EsiFile;

    fn dev_with(pdos: &str) -> EsiDevice {
        let text = format!(
            r##"<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>
<Type ProductCode="#x1" RevisionNo="#x1">D</Type><Name>D</Name><GroupType>G</GroupType>
<Sm StartAddress="#x1000" DefaultSize="128" ControlByte="#x26" Enable="1">MBoxOut</Sm>
<Sm StartAddress="#x1080" DefaultSize="128" ControlByte="#x22" Enable="1">MBoxIn</Sm>
<Sm StartAddress="#x1100" ControlByte="#x64" Enable="1">Outputs</Sm>
<Sm StartAddress="#x1180" ControlByte="#x20" Enable="1">Inputs</Sm>
{pdos}
<Mailbox><CoE SdoInfo="1" PdoAssign="1"/></Mailbox>
</Device></Devices></Descriptions></EtherCATInfo>"##
        );
        EsiFile::parse(&text).unwrap().devices.remove(0)
    }

    fn pdo(tag: &str, index: u16, sm: Option<u8>, excludes: &[u16], entry: u16) -> String {
        let sm = sm.map_or(String::new(), |s| format!(" Sm=\"{s}\""));
        let ex: String = excludes
            .iter()
            .map(|e| format!("<Exclude>#x{e:04x}</Exclude>"))
            .collect();
        format!(
            "<{tag}{sm}><Index>#x{index:04x}</Index><Name>P</Name>{ex}<Entry><Index>#x{entry:04x}</Index><SubIndex>1</SubIndex><BitLen>16</BitLen><Name>v</Name><DataType>UINT</DataType></Entry></{tag}>"
        )
    }

    /// A device with mailbox SyncManagers `sms` (and no process-data
    /// ones unless `sms` has them).
    fn dev_with_sms(sms: &str) -> EsiDevice {
        let text = format!(
            r##"<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>
<Type ProductCode="#x1" RevisionNo="#x1">D</Type><Name>D</Name><GroupType>G</GroupType>
{sms}
<Mailbox><CoE SdoInfo="1"/></Mailbox>
</Device></Devices></Descriptions></EtherCATInfo>"##
        );
        EsiFile::parse(&text).unwrap().devices.remove(0)
    }

    #[test]
    fn a_mailbox_longer_than_a_twin_serves_is_a_load_error_not_a_panic() {
        let sms = |out: u16, inp: u16| {
            format!(
                "<Sm StartAddress=\"#x1000\" DefaultSize=\"{out}\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>\n\
                 <Sm StartAddress=\"#x1800\" DefaultSize=\"{inp}\" ControlByte=\"#x22\" Enable=\"1\">MBoxIn</Sm>"
            )
        };
        let e = describe(&dev_with_sms(&sms(128, 2048))).unwrap_err();
        assert_eq!(
            e.to_string(),
            "D rev 0x00000001: the MBoxIn mailbox is 2048 bytes long; a twin serves mailboxes of at most 1024 bytes"
        );
        // The longest there is loads, and its twin runs.
        let dev = dev_with_sms(&sms(1024, 1024));
        assert!(describe(&dev).is_ok());
        let mut t = crate::twin(&dev, Some(7), crate::InputRule::ALL[0].1).unwrap();
        let _ = t.poll_with(1_000_000, None);
        // A bootstrap mailbox too.
        let boot = format!(
            "{}\n<Eeprom><ByteSize>2048</ByteSize><BootStrap>0010008000180080</BootStrap></Eeprom>",
            sms(128, 128)
        );
        let e = describe(&dev_with_sms(&boot)).unwrap_err();
        assert!(
            e.to_string()
                .contains("the bootstrap out mailbox is 32768 bytes long"),
            "{e}"
        );
    }

    #[test]
    fn process_data_placed_beyond_0xffff_is_a_load_error_naming_the_sm() {
        let mbx = |out: u16, inp: u16| {
            format!(
                "<Sm StartAddress=\"#x{out:04x}\" DefaultSize=\"128\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>\n\
                 <Sm StartAddress=\"#x{inp:04x}\" DefaultSize=\"128\" ControlByte=\"#x22\" Enable=\"1\">MBoxIn</Sm>"
            )
        };
        // MBoxIn ends at the top: the outputs would start at 0x10000.
        let e = describe(&dev_with_sms(&mbx(0xFF00, 0xFF80))).unwrap_err();
        assert_eq!(
            e.to_string(),
            "<Sm> at line 4: the outputs placed after this SyncManager would start at 0x10000, beyond the ESC address space (0xffff)"
        );
        // Outputs fit, the inputs 0x100 bytes later would not.
        let e = describe(&dev_with_sms(&mbx(0xFE00, 0xFE80))).unwrap_err();
        assert!(
            e.to_string()
                .contains("the inputs placed after this SyncManager would start at 0x10000"),
            "{e}"
        );
        // An output SM near the top and no input SM.
        let sms = format!(
            "{}\n<Sm StartAddress=\"#xfff0\" ControlByte=\"#x64\" Enable=\"1\">Outputs</Sm>",
            mbx(0x1000, 0x1080)
        );
        let e = describe(&dev_with_sms(&sms)).unwrap_err();
        assert!(
            e.to_string().starts_with("<Sm> at line 5: the inputs"),
            "{e}"
        );
        // Normal places still work.
        let (_, layout) = describe(&dev_with_sms(&mbx(0x1000, 0x1080))).unwrap();
        assert_eq!((layout.pd_out, layout.pd_in), (0x1100, 0x1200));
    }

    #[test]
    fn an_absurd_eeprom_size_set_by_code_is_an_error_not_a_wrap() {
        let mut d = dev_with_sms(
            "<Sm StartAddress=\"#x1000\" DefaultSize=\"128\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>\n\
             <Sm StartAddress=\"#x1080\" DefaultSize=\"128\" ControlByte=\"#x22\" Enable=\"1\">MBoxIn</Sm>",
        );
        d.eeprom_bytes = Some(u32::MAX);
        let e = describe(&d).unwrap_err();
        assert!(
            e.to_string()
                .contains("bad EEPROM ByteSize (at most 65535 kbit) '4294967295'"),
            "{e}"
        );
        d.eeprom_bytes = Some(4096);
        assert_eq!(describe(&d).unwrap().0.esc.eeprom_kbit, 32);
    }

    #[test]
    fn alternative_sets_honour_excludes_and_cover_every_pdo() {
        let d = dev_with(
            &[
                pdo("RxPdo", 0x1600, Some(2), &[0x1601], 0x7000),
                pdo("RxPdo", 0x1601, None, &[0x1600], 0x7010),
                pdo("RxPdo", 0x1602, None, &[], 0x7020),
                pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000),
            ]
            .concat(),
        );
        let sets = alternative_sets(&d, &[0x1600], &[0x1A00]);
        // 0x1601 excludes 0x1600: its set holds 0x1601, 0x1602, 0x1A00.
        assert_eq!(sets, [(vec![0x1601, 0x1602], vec![0x1A00])]);
        let d = dev_with(
            &[
                pdo("RxPdo", 0x1600, Some(2), &[], 0x7000),
                pdo("RxPdo", 0x1601, None, &[], 0x7010),
                pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000),
            ]
            .concat(),
        );
        let sets = alternative_sets(&d, &[0x1600], &[0x1A00]);
        assert_eq!(
            sets,
            [(vec![0x1600, 0x1601], vec![0x1A00])],
            "optional PDO with the default ones"
        );
        assert!(alternative_sets(&d, &[0x1600, 0x1601], &[0x1A00]).is_empty());
    }

    #[test]
    fn an_assignment_of_more_than_32_pdos_keeps_its_exact_capacity() {
        // 40 RxPDOs on SM2, no dictionary: 0x1C12 is made from them.
        let pdos: String = (0..40u16)
            .map(|k| pdo("RxPdo", 0x1600 + k, Some(2), &[], 0x7000 + 0x10 * k))
            .collect();
        let (desc, _) = describe(&dev_with(&pdos)).unwrap();
        let (_, e) = desc.dictionary.find_entry(0x1C12, 0).unwrap();
        assert_eq!((e.min(), e.max()), (Some(0), Some(40)));
    }

    #[test]
    fn a_device_with_coe_is_described_and_its_errors_are_named() {
        // No dictionary: made from the PDOs; both PDO sets valid.
        let d = dev_with(
            &[
                pdo("RxPdo", 0x1600, Some(2), &[], 0x7000),
                pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000),
            ]
            .concat(),
        );
        let (desc, layout) = describe(&d).unwrap();
        assert_eq!(layout.mbx_out, (0x1000, 128));
        assert_eq!((layout.pd_out, layout.pd_in), (0x1100, 0x1180));
        assert!(desc.dictionary.find(0x7000).is_some());
        assert!(desc.mailbox.coe.sdo_info && desc.mailbox.coe.pdo_assign);
        // A REAL PDO entry: its object is a REAL output.
        let real = dev_with(
            &pdo("RxPdo", 0x1600, Some(2), &[], 0x7000)
                .replace("UINT", "REAL")
                .replace("<BitLen>16", "<BitLen>32"),
        );
        let (desc, _) = describe(&real).unwrap();
        let (_, e) = desc.dictionary.find_entry(0x7000, 1).unwrap();
        assert_eq!(
            (e.data_type, e.bit_len, e.pdo()),
            (DataType::Real32, 32, PdoMapping::Rx)
        );
        // No GroupType (ETG.2000 requires one).
        let mut g = d.clone();
        g.group_type.clear();
        assert!(
            describe(&g)
                .unwrap_err()
                .to_string()
                .contains("<Device> at line 1: missing <GroupType>")
        );
        // Slots without the file's Modules, and without any Slot.
        let mut m = d.clone();
        // (Full literals: `Element` has a Drop impl, so no `..Default`.)
        m.source.children.push(crate::xml::Element {
            name: "Slots".into(),
            attrs: vec![
                ("SlotIndexIncrement".into(), "#x10".into()),
                ("SlotPdoIncrement".into(), "1".into()),
            ],
            text: String::new(),
            children: vec![crate::xml::Element {
                name: "Slot".into(),
                attrs: Vec::new(),
                text: String::new(),
                children: Vec::new(),
                line: 0,
            }],
            line: 0,
        });
        // Modules in a library not given: the slots stay empty, a warning.
        let (_, _, w) = describe_with_warnings(&m).unwrap();
        assert!(
            w.iter().any(|w| w
                .to_string()
                .starts_with("<Slots> at line 0: the file has no <Modules>")),
            "{w:?}"
        );
        if let Some(slots) = m.source.children.last_mut() {
            slots.children.clear();
        }
        let e = describe(&m).unwrap_err().to_string();
        assert!(e.contains("no <Slot>"), "{e}");
        // CoE without mailbox SyncManagers.
        let mut n = d.clone();
        n.sms
            .retain(|s| !matches!(s.kind, SmType::MailboxOut | SmType::MailboxIn));
        assert!(matches!(
            describe(&n),
            Err(DescriptionBuildError::NoMailboxSm(_))
        ));
    }

    #[test]
    fn the_counter_and_loopback_rules_drive_the_inputs() {
        let d = dev_with(
            &[
                pdo("RxPdo", 0x1600, Some(2), &[], 0x7000),
                pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000),
            ]
            .concat(),
        );
        let (desc, _) = describe(&d).unwrap();
        let mut store =
            ecat_slave::od::store::ObjectStore::<[i64; TWIN_ENTRIES]>::new(desc.dictionary);
        let od = <[i64; TWIN_ENTRIES] as ecat_slave::od::ValueStorage>::view_mut(&mut store);
        od.set(0x7000, 1, 1234);
        let mut em = ecat_slave::coe::emergency::Emergencies::default();
        let mut app = EsiApp::new(desc, InputRule::Loopback);
        app.tick(&mut Tick::new(
            od,
            0,
            true,
            ecat_slave::al::AlState::Op,
            &mut em,
        ));
        assert_eq!(od.get(0x6000, 1), Some(1234));
        let mut app = EsiApp::new(desc, InputRule::Counter);
        for _ in 0..3 {
            app.tick(&mut Tick::new(
                od,
                0,
                true,
                ecat_slave::al::AlState::Op,
                &mut em,
            ));
        }
        assert_eq!(od.get(0x6000, 1), Some(3));
    }

    #[test]
    fn a_modular_device_without_its_etg5001_objects_gets_them_with_a_warning() {
        let slots = crate::xml::parse("<Slots SlotIndexIncrement=\"#x800\"/>").unwrap();
        let mut objects = vec![record(0xF050, "Detected (the ESI's own)", vec![sub0(0)])];
        let mut warnings = Vec::new();
        modular_objects(&slots, 2, 0x800, &mut objects, &mut warnings);
        let idx: Vec<u16> = objects.iter().map(|o| o.index).collect();
        assert_eq!(idx, [0xF050, 0xF000, 0xF030], "the ESI's own 0xF050 kept");
        assert_eq!(objects[0].name, "Detected (the ESI's own)");
        let f000 = &objects[1];
        assert_eq!(f000.entries[1].default_value(), DefaultValue::int(0x800));
        assert_eq!(f000.entries[2].default_value(), DefaultValue::int(2));
        let f030 = &objects[2];
        assert_eq!(f030.entries.len(), 3, "subindex 0 and one per slot");
        assert_eq!(
            f030.entries[0].default_value(),
            DefaultValue::int(0),
            "nothing configured"
        );
        assert_eq!(f030.entries[1].access(), ecat_slave::od::Access::RwPreOp);
        assert_eq!(warnings.len(), 2);
        assert!(
            warnings[1].to_string().contains("0xf030"),
            "{}",
            warnings[1]
        );
    }

    #[test]
    fn an_assignment_default_naming_a_pdo_the_device_lacks_becomes_the_esis_sm_pdos() {
        let dict = r##"<Profile><Dictionary><DataTypes>
<DataType><Name>DT1C13</Name><BitSize>48</BitSize>
<SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
<SubItem><SubIdx>1</SubIdx><Name>SubIndex 001</Name><Type>UINT</Type><BitSize>16</BitSize><BitOffs>16</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
<SubItem><SubIdx>2</SubIdx><Name>SubIndex 002</Name><Type>UINT</Type><BitSize>16</BitSize><BitOffs>32</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
</DataType></DataTypes><Objects>
<Object><Index>#x1c13</Index><Name>TxPDO assign</Name><Type>DT1C13</Type><BitSize>48</BitSize><Info>
<SubItem><Name>SubIndex 000</Name><Info><DefaultData>02</DefaultData></Info></SubItem>
<SubItem><Name>SubIndex 001</Name><Info><DefaultData>731a</DefaultData></Info></SubItem>
<SubItem><Name>SubIndex 002</Name><Info><DefaultData>001a</DefaultData></Info></SubItem>
</Info></Object></Objects></Dictionary></Profile>"##;
        let pdos = format!("{}{dict}", pdo("TxPdo", 0x1A00, Some(3), &[], 0x6000));
        let (desc, _, warnings) = describe_with_warnings(&dev_with(&pdos)).unwrap();
        assert_eq!(desc.process_data.sets[0].tx, [0x1A00]);
        assert!(
            warnings
                .iter()
                .any(|w| w.message.starts_with("0x1c13 defaults to [1a73, 1a00]")),
            "{warnings:?}"
        );
    }
}
