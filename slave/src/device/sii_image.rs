//! The SII EEPROM image of a device, encoded from its description.
//!
//! A hardware build writes this image into the ESC's EEPROM (with a
//! master's EEPROM tool or at production); the software ESC serves it. It
//! runs on the host or at start-up of a simulated slave: the encoder keeps
//! the PDO tables of one image on the stack (about 20 KiB), which a
//! microcontroller firmware never needs to do.

use crate::od::{DefaultValue, Dictionary};
use crate::pdo::Direction;
use crate::sii;
use crate::sii::SII_SIZE;

use super::description::{DeviceDescription, MemoryLayout};
use super::slave::SM_CONTROL;

/// Most entries of one PDO in the SII.
const SII_MAX_ENTRIES: usize = 24;
/// Most PDOs of one direction.
const SII_MAX_PDOS: usize = 16;

type PdoEntries = heapless::Vec<sii::SiiPdoEntry<'static>, SII_MAX_ENTRIES>;

/// The mapping entries of PDO `pdo` as its defaults state them:
/// `(index, sub, bits)`, padding as index 0.
pub fn mapping_entries(dict: &Dictionary, pdo: u16) -> impl Iterator<Item = (u16, u8, u8)> {
    let entries = dict.find(pdo).map_or(&[][..], |(_, o)| o.entries);
    let count = entries.first().map_or(0, |e| match e.default_value() {
        DefaultValue::Int(v) => v.get(),
        DefaultValue::Str(_) | DefaultValue::Bytes(_) => 0,
    });
    entries
        .iter()
        .filter(move |e| e.sub != 0 && i64::from(e.sub) <= count)
        .filter_map(|e| match e.default_value() {
            DefaultValue::Int(m) => {
                let m = m.get() as u32;
                Some(((m >> 16) as u16, (m >> 8) as u8, m as u8))
            }
            DefaultValue::Str(_) | DefaultValue::Bytes(_) => None,
        })
}

fn pdo_entries(dict: &'static Dictionary, pdo: u16) -> PdoEntries {
    let mut v = PdoEntries::new();
    for (index, sub, bits) in mapping_entries(dict, pdo) {
        let (name, dtype) = match dict.find_entry(index, sub) {
            Some((_, m)) if index != 0 => (m.name, (m.data_type.code() & 0xFF) as u8),
            _ => ("", 0),
        };
        let _ = v.push(sii::SiiPdoEntry {
            index,
            sub,
            name,
            data_type: dtype,
            bit_len: bits,
        });
    }
    v
}

impl DeviceDescription {
    /// Every PDO of the direction that some set names, ascending, with the
    /// SyncManager it is assigned to by default (`None`: an alternative).
    pub fn pdos(&self, dir: Direction) -> heapless::Vec<(u16, Option<u8>), SII_MAX_PDOS> {
        let mut all: heapless::Vec<(u16, Option<u8>), SII_MAX_PDOS> = heapless::Vec::new();
        let sm = match dir {
            Direction::Outputs => 2,
            Direction::Inputs => 3,
        };
        for (n, set) in self.process_data.sets.iter().enumerate() {
            let list = match dir {
                Direction::Outputs => set.rx,
                Direction::Inputs => set.tx,
            };
            for &pdo in list {
                // A modular device's EEPROM cannot know which modules are
                // plugged: their PDOs are found over CoE (ETG.5001).
                if self.modules.is_some_and(|m| m.slot_of(pdo).is_some()) {
                    continue;
                }
                if !all.iter().any(|(p, _)| *p == pdo) {
                    let _ = all.push((pdo, (n == 0).then_some(sm)));
                }
            }
        }
        all.sort_unstable_by_key(|(p, _)| *p);
        all
    }

    /// Bytes of the default (first) set's process image of a direction.
    pub fn default_image_len(&self, dir: Direction) -> u16 {
        let Some(set) = self.process_data.sets.first() else {
            return 0;
        };
        let list = match dir {
            Direction::Outputs => set.rx,
            Direction::Inputs => set.tx,
        };
        let bits: usize = list
            .iter()
            .filter(|&&pdo| self.modules.is_none_or(|m| m.slot_of(pdo).is_none()))
            .flat_map(|&pdo| mapping_entries(self.dictionary, pdo))
            .map(|(_, _, b)| usize::from(b))
            .sum();
        u16::try_from(bits.div_ceil(8)).unwrap_or(u16::MAX)
    }

    /// The SII image for the description's own layout.
    pub fn sii_image(&self) -> [u8; SII_SIZE] {
        self.sii_image_for(&self.layout())
    }

    /// The SII image for a memory layout (another standard mailbox size).
    /// An unencodable description (one `validate` refuses, or an image over
    /// the EEPROM size) gives a blank (all 0xFF) EEPROM that no master
    /// accepts; [`Self::encode_sii`] says why.
    pub fn sii_image_for(&self, layout: &MemoryLayout) -> [u8; SII_SIZE] {
        let mut out = [0xFFu8; SII_SIZE];
        if self.encode_sii(layout, &mut out).is_err() {
            out = [0xFF; SII_SIZE];
        }
        out
    }

    /// Encodes the SII image (ETG.2010) for `layout` into `out`; returns
    /// the bytes used.
    pub fn encode_sii(
        &self,
        layout: &MemoryLayout,
        out: &mut [u8],
    ) -> Result<usize, sii::SiiError> {
        let dict = self.dictionary;
        let rx_list = self.pdos(Direction::Outputs);
        let tx_list = self.pdos(Direction::Inputs);
        let mut rx_entries: heapless::Vec<PdoEntries, SII_MAX_PDOS> = heapless::Vec::new();
        for (pdo, _) in &rx_list {
            let _ = rx_entries.push(pdo_entries(dict, *pdo));
        }
        let mut tx_entries: heapless::Vec<PdoEntries, SII_MAX_PDOS> = heapless::Vec::new();
        for (pdo, _) in &tx_list {
            let _ = tx_entries.push(pdo_entries(dict, *pdo));
        }
        let mut rx: heapless::Vec<sii::SiiPdo<'_>, SII_MAX_PDOS> = heapless::Vec::new();
        for ((index, sm), entries) in rx_list.iter().zip(rx_entries.iter()) {
            let _ = rx.push(sii::SiiPdo {
                index: *index,
                sm: *sm,
                name: dict.find(*index).map_or("", |(_, o)| o.name),
                flags: crate::pdo::sii_flags(dict, *index),
                entries,
            });
        }
        let mut tx: heapless::Vec<sii::SiiPdo<'_>, SII_MAX_PDOS> = heapless::Vec::new();
        for ((index, sm), entries) in tx_list.iter().zip(tx_entries.iter()) {
            let _ = tx.push(sii::SiiPdo {
                index: *index,
                sm: *sm,
                name: dict.find(*index).map_or("", |(_, o)| o.name),
                flags: crate::pdo::sii_flags(dict, *index),
                entries,
            });
        }
        let out_len = self.default_image_len(Direction::Outputs);
        let in_len = self.default_image_len(Direction::Inputs);
        let mut sms: heapless::Vec<sii::SiiSyncManager, 4> = heapless::Vec::new();
        let _ = sms.push(sii::SiiSyncManager {
            start: layout.mbx_out.0,
            length: layout.mbx_out.1,
            control: SM_CONTROL[0],
            enable: 0x01,
            sm_type: sii::SmType::MailboxOut,
        });
        let _ = sms.push(sii::SiiSyncManager {
            start: layout.mbx_in.0,
            length: layout.mbx_in.1,
            control: SM_CONTROL[1],
            enable: 0x01,
            sm_type: sii::SmType::MailboxIn,
        });
        let _ = sms.push(sii::SiiSyncManager {
            start: layout.pd_out,
            length: out_len,
            control: SM_CONTROL[2],
            // A modular device's process data depend on its modules: the
            // SyncManagers are enabled and sized by the master.
            enable: u8::from(out_len > 0 || self.modules.is_some()),
            sm_type: sii::SmType::ProcessOut,
        });
        let _ = sms.push(sii::SiiSyncManager {
            start: layout.pd_in,
            length: in_len,
            control: SM_CONTROL[3],
            enable: u8::from(in_len > 0 || self.modules.is_some()),
            sm_type: sii::SmType::ProcessIn,
        });
        let fmmus = [
            sii::FmmuUsage::Outputs,
            sii::FmmuUsage::Inputs,
            sii::FmmuUsage::SyncMStatus,
        ];
        let boot = if layout.has_boot() {
            sii::SiiMailbox {
                rx_offset: layout.boot_out.0,
                rx_size: layout.boot_out.1,
                tx_offset: layout.boot_in.0,
                tx_size: layout.boot_in.1,
            }
        } else {
            sii::SiiMailbox::default()
        };
        let mbx = &self.mailbox;
        let protocols = sii::protocols::COE | if mbx.foe { sii::protocols::FOE } else { 0 };
        let id = &self.identity;
        let cfg = sii::SiiConfig {
            pdi_control: self.esc.pdi_control,
            // 0x0151 (high byte): SYNC0 is an output (bit 2) mapped to AL
            // event request bit 2 (bit 3), which the core's DC-synchronous
            // firmware waits on; 0x0150 (SPI mode etc.) 0. Sync impulse
            // length 0 (SII word 2 -> 0x0982): acknowledge mode, SYNC0
            // stays active until the firmware reads 0x098E (ET1100
            // Section II, 0x0151 and 0x0982).
            pdi_config: 0x0C00,
            sync_impulse: 0x0000,
            pdi_config2: 0x0000,
            station_alias: 0,
            identity: sii::SiiIdentity {
                vendor_id: id.vendor_id,
                product_code: id.product_code,
                revision: id.revision,
                serial: id.serial,
            },
            bootstrap_mailbox: boot,
            standard_mailbox: sii::SiiMailbox {
                rx_offset: layout.mbx_out.0,
                rx_size: layout.mbx_out.1,
                tx_offset: layout.mbx_in.0,
                tx_size: layout.mbx_in.1,
            },
            mailbox_protocols: protocols,
            eeprom_kbit: self.esc.eeprom_kbit,
            general: sii::SiiGeneral {
                group: self.names.group_type,
                image: "",
                order: self.names.type_name,
                name: self.names.name,
                coe_details: mbx.coe.details(),
                foe_details: u8::from(mbx.foe),
                eoe_details: 0x00,
                // Safe-op enabled; identity in AL status code: no.
                flags: 0x01,
                current_on_ebus: self.esc.ebus_current_ma,
                physical_port: self.esc.physical_ports,
            },
            fmmus: &fmmus,
            sync_managers: &sms,
            tx_pdos: &tx,
            rx_pdos: &rx,
        };
        sii::encode(&cfg, out)
    }
}
