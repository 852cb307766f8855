//! Prints the sizes behind the firmware footprint: `core::mem::size_of` of
//! the firmware object and its parts (static RAM), and what the object
//! dictionary tables of each device are made of (read-only data, mostly
//! relocated pointers: `.data.rel.ro`).
//!
//! The board types mirror the firmware's (zero-sized), so the sizes are the
//! ones linked there.

use std::collections::BTreeSet;
use std::mem::size_of;

use ecat_slave::coe::CoeServer;
use ecat_slave::coe::emergency::Emergencies;
use ecat_slave::coe::sdo::SdoServer;
use ecat_slave::coe::sdo_info::SdoInfoServer;
use ecat_slave::device::{DeviceDescription, Slave};
use ecat_slave::esc::{Esc, EscError};
use ecat_slave::firmware::EfwValidator;
use ecat_slave::foe::{FoeServer, FoeState};
use ecat_slave::hal::{NvError, NvStorage};
use ecat_slave::mailbox::MailboxServer;
use ecat_slave::od::{
    DataType, DefaultValue, Dictionary, Entry, EnumDesc, Limits, Object, ObjectStore,
};
use ecat_slave::pdo::ProcessImage;

struct NoEsc;
impl Esc for NoEsc {
    fn read(&mut self, _: u16, _: &mut [u8]) -> Result<(), EscError> {
        Ok(())
    }
    fn write(&mut self, _: u16, _: &[u8]) -> Result<(), EscError> {
        Ok(())
    }
}

struct NoNv;
impl NvStorage for NoNv {
    fn capacity(&self) -> usize {
        0
    }
    fn read(&self, _: usize, _: &mut [u8]) -> Result<(), NvError> {
        Ok(())
    }
    fn write(&mut self, _: usize, _: &[u8]) -> Result<(), NvError> {
        Ok(())
    }
}

struct NoBoard;
impl io8_example::Board for NoBoard {
    fn inputs(&mut self) -> u8 {
        0
    }
    fn set_outputs(&mut self, _: u8) {}
}

struct NoStage;
impl pam_199_p_etc::board::PowerStage for NoStage {
    fn set_current(
        &mut self,
        _: pam_199_p_etc::board::Solenoid,
        _: u16,
        _: pam_199_p_etc::board::Dither,
        _: u16,
        _: pam_199_p_etc::board::PiGains,
    ) {
    }
    fn disable(&mut self) {}
    fn measured_ma(&self, _: pam_199_p_etc::board::Solenoid) -> u16 {
        0
    }
    fn faults(&self) -> pam_199_p_etc::board::Faults {
        Default::default()
    }
    fn step(&mut self, _: u32) {}
}

type Io8App = io8_example::Io8<NoBoard, NoNv>;
type PamApp = pam_199_p_etc::Pam<NoStage, NoNv>;

fn row(name: &str, bytes: usize) {
    println!("    {bytes:>7}  {name}");
}

/// What a dictionary's tables hold.
fn od_tables(device: &str, desc: &DeviceDescription) {
    let dict: &Dictionary = desc.dictionary;
    let objects = dict.objects();
    let entries: usize = objects.iter().map(|o| o.entries.len()).sum();
    let enums = dict.enums();
    let enum_values: usize = enums.iter().map(|e| e.values.len()).sum();
    let mut strings: Vec<&'static str> = Vec::new();
    let mut ranged = 0usize;
    let mut limits: Vec<*const Limits> = Vec::new();
    for o in objects {
        strings.push(o.name);
        for e in o.entries {
            strings.push(e.name);
            strings.push(e.unit());
            if let DefaultValue::Str(s) = e.default_value() {
                strings.push(s);
            }
            ranged += usize::from(e.min().is_some() || e.max().is_some());
            if *e.limits != Limits::NONE {
                limits.push(e.limits);
            }
        }
    }
    limits.sort();
    limits.dedup();
    for e in enums {
        strings.push(e.name);
        strings.extend(e.values.iter().map(|(_, t)| *t));
    }
    let total: usize = strings.iter().map(|s| s.len()).sum();
    let distinct: BTreeSet<&str> = strings.iter().copied().collect();
    let distinct_bytes: usize = distinct.iter().map(|s| s.len()).sum();
    let object_bytes = std::mem::size_of_val(objects);
    let entry_bytes = entries * size_of::<Entry>();
    let limits_bytes = (limits.len() + 1) * size_of::<Limits>();
    let enum_bytes = enums.len() * (size_of::<EnumDesc>() + size_of::<&EnumDesc>())
        + enum_values * size_of::<(i64, &str)>();
    let base_bytes = objects.len() * size_of::<u16>();
    let pointer_tables = object_bytes + entry_bytes + limits_bytes + enum_bytes;
    println!(
        "  {device}: {} objects, {entries} entries ({ranged} with a range), {} enumerations ({enum_values} values), {} value slots",
        objects.len(),
        enums.len(),
        dict.entry_count()
    );
    row(
        &format!(
            "Object table ({} x {} B: &str name, &[Entry], code)",
            objects.len(),
            size_of::<Object>()
        ),
        object_bytes,
    );
    row(
        &format!(
            "Entry table ({entries} x {} B: &str name, DataType {} B, 32 default bits, &Limits, flags)",
            size_of::<Entry>(),
            size_of::<DataType>(),
        ),
        entry_bytes,
    );
    row(
        &format!(
            "range, unit and wide-default tables (at most {} distinct Limits + the shared NONE, {} B each)",
            limits.len(),
            size_of::<Limits>()
        ),
        limits_bytes,
    );
    row(
        "enumeration tables (EnumDesc, (i64, &str) values)",
        enum_bytes,
    );
    row("  = pointer-bearing tables (.data.rel.ro)", pointer_tables);
    row("entry base table (u16 per object, .rodata)", base_bytes);
    row(
        &format!(
            "strings referenced ({} refs; {} distinct, .rodata)",
            strings.len(),
            distinct.len()
        ),
        total,
    );
    row(
        "  of which distinct (what the linker keeps when it merges literals)",
        distinct_bytes,
    );
    // A packed layout: names/units as u16 offsets into one string pool,
    // ranges and string defaults in side tables indexed by u8, the rest as
    // small integers, no padding; entries addressed by index, no pointers.
    let packed_entry = 2 + 1 + 2 + 1 + 1 + 1 + 8;
    let packed = objects.len() * 8
        + entries * packed_entry
        + ranged * 16
        + enum_values * 10
        + distinct_bytes;
    row(
        &format!(
            "rough estimate, packed tables: {} B/entry (u16 name offset, u8 type, u16 bits, u8 access/flags, u8 unit, u8 range index, i64 default), 8 B/object, 16 B/range, 10 B/enum value, one string pool",
            packed_entry
        ),
        packed,
    );
}

/// The firmware's buffer sizes (as `examples/firmware`): mailboxes and
/// process images from the description, SDO transfers 128 / 256 bytes.
const IO8_MBX: usize = io8_example::DEVICE.largest_mailbox();
const IO8_IMAGE: (usize, usize) = io8_example::DEVICE.largest_image();
const PAM_MBX: usize = pam_199_p_etc::DEVICE.largest_mailbox();
const PAM_IMAGE: (usize, usize) = pam_199_p_etc::DEVICE.largest_image();
type Io8Firmware = Slave<NoEsc, Io8App, IO8_MBX, 128, { IO8_IMAGE.0 }, { IO8_IMAGE.1 }>;
type PamFirmware = Slave<NoEsc, PamApp, PAM_MBX, 256, { PAM_IMAGE.0 }, { PAM_IMAGE.1 }>;

fn main() {
    println!(
        "Static RAM parts (core::mem::size_of on x86-64, board types zero-sized as in the firmware):"
    );
    row(
        "Slave<SpiEsc, Io8<..>, ..>  (the whole IO8 firmware object, buffers from its description)",
        size_of::<Io8Firmware>(),
    );
    row(
        "Slave<SpiEsc, Pam<..>, ..>  (the whole PAM firmware object, buffers from its description)",
        size_of::<PamFirmware>(),
    );
    row("  Io8<..> application", size_of::<Io8App>());
    row("  Pam<..> application", size_of::<PamApp>());
    row(
        &format!(
            "  ObjectStore, IO8 ({} values x 8 B + strings)",
            io8_example::ENTRIES
        ),
        size_of::<ObjectStore<[i64; io8_example::ENTRIES]>>(),
    );
    row(
        &format!(
            "  ObjectStore, PAM ({} values x 8 B + strings)",
            pam_199_p_etc::od::ENTRY_COUNT
        ),
        size_of::<ObjectStore<[i64; pam_199_p_etc::od::ENTRY_COUNT]>>(),
    );
    row(
        "    of which the string slots (heapless 4 x 32 B)",
        size_of::<ObjectStore<[i64; 0]>>(),
    );
    row(
        "  MailboxServer (IO8: 128-byte SDO transfers)",
        size_of::<MailboxServer<128>>(),
    );
    row("    CoeServer", size_of::<CoeServer<128>>());
    row(
        "      SdoServer (segmented transfer buffer)",
        size_of::<SdoServer<128>>(),
    );
    row(
        "      SdoInfoServer (fragment buffer)",
        size_of::<SdoInfoServer>(),
    );
    row("    FoeServer", size_of::<FoeServer>());
    row(
        "      FoeState (largest: Sending with the info file)",
        size_of::<FoeState>(),
    );
    row(
        "      EfwValidator (inside FoeState::Receiving)",
        size_of::<EfwValidator>(),
    );
    row(
        &format!(
            "  request and response buffers (IO8: 2 x {IO8_MBX} B, PAM: 2 x {PAM_MBX} B; IO8)"
        ),
        2 * size_of::<[u8; IO8_MBX]>(),
    );
    row(
        &format!(
            "  ProcessImage (x 2: outputs, inputs; IO8: {} entries)",
            IO8_IMAGE.0
        ),
        size_of::<ProcessImage<{ IO8_IMAGE.0 }>>(),
    );
    row("  Emergencies (queue)", size_of::<Emergencies>());
    println!(
        "Object dictionary tables (x86-64: pointers and usize 8 B; a 32-bit MCU roughly halves the pointer parts):"
    );
    od_tables("IO8", &io8_example::DEVICE);
    od_tables("PAM", &pam_199_p_etc::DEVICE);
}
