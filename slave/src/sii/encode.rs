//! SII image encoder (ETG.2010 Tables 2 and 3).

use super::{
    CategoryType, FIRST_CATEGORY_BYTE, GENERAL_LEN, MAX_NAME_LEN, PDO_RECORD_LEN, SYNC_MANAGER_LEN,
    SiiConfig, SiiError, SiiMailbox, SiiPdo, crc8,
};

/// Longest string the Strings category can hold (length byte, ETG.2010
/// Table 6).
const MAX_STRING_LEN: usize = 255;

/// Encodes `cfg` as an SII EEPROM image into `out` (ETG.2010 Tables 2..15).
///
/// `out` is meant to be the whole EEPROM (`eeprom_kbit * 128` bytes); the
/// header (words 0x00..0x3F, reserved words zero, checksum per [`crc8`]) is
/// followed by the categories Strings, General (exactly 32 bytes), FMMU
/// (always present, padded with 0xFF to a whole word), SyncM, TxPDO and RxPDO
/// (each omitted when empty; all PDOs of a direction in one category) and the
/// End marker (type word 0xFFFF plus a length word 0xFFFF, as erased EEPROM
/// reads). Every byte of `out` after the End marker is set to 0xFF.
///
/// Strings are deduplicated (equal text gets one 1-based index); an empty
/// string is written as index 0 (none). Strings are stored as given (UTF-8).
///
/// Returns the number of bytes used, up to and including the End marker.
///
/// # Errors
///
/// - [`SiiError::BufferTooSmall`] when `out` cannot hold the image,
/// - [`SiiError::ImageTooLarge`] when the image exceeds `eeprom_kbit`,
/// - [`SiiError::TooManyStrings`] for more than 255 distinct strings,
/// - [`SiiError::StringTooLong`] for a string over 255 bytes, or a General
///   group/image/order/name over [`MAX_NAME_LEN`] bytes (ethercrab rejects
///   longer device names),
/// - [`SiiError::TooManyEntries`] for a PDO with more than 255 entries,
/// - [`SiiError::CategoryTooLong`] for a category over 65535 words,
/// - [`SiiError::InvalidField`] for values ethercrab 0.7.1 or ETG.2010
///   forbid: `eeprom_kbit` 0, mailbox protocol bits above 0x20, CoE details
///   above 0x3F, FoE/EoE details above 1, General flags above 0x1F, an SM
///   enable byte above 0x0F, an SM type above 4, an FMMU usage outside
///   {0, 1, 2, 3, 0xFF}, a PDO assigned to SM 0xFF (`Some(0xFF)`; use `None`).
///
/// On error the content of `out` is unspecified.
pub fn encode(cfg: &SiiConfig<'_>, out: &mut [u8]) -> Result<usize, SiiError> {
    validate(cfg)?;
    let mut w = Writer { out, pos: 0 };

    write_header(cfg, &mut w)?;

    // Strings category: intern every string once, in a fixed order.
    let strings_header = w.pos;
    w.put(&[0; 4])?;
    let mut table = StringTable {
        count_at: w.pos,
        end: w.pos,
        count: 0,
    };
    w.put_u8(0)?;
    table.end = w.pos;
    let g = &cfg.general;
    // String 1 is what SOEM (ecx_config_init) shows as the slave's name,
    // while ethercrab follows the General category's name index. Vendors'
    // EEPROMs put the device type (order code) first, then group and name
    // (see the Beckhoff dumps in tests/data/sii-dumps): order code
    // first, then the name, so string 1 is the device type, or the name
    // when there is no order code.
    for name in [g.order, g.name, g.group, g.image] {
        if name.len() > MAX_NAME_LEN {
            return Err(SiiError::StringTooLong {
                len: name.len(),
                max: MAX_NAME_LEN,
            });
        }
        table.intern(&mut w, name)?;
    }
    for pdo in cfg.tx_pdos.iter().chain(cfg.rx_pdos) {
        table.intern(&mut w, pdo.name)?;
        for entry in pdo.entries {
            table.intern(&mut w, entry.name)?;
        }
    }
    w.set_u8(table.count_at, table.count)?;
    w.pad_to_word(0)?;
    w.close_category(strings_header, CategoryType::Strings)?;

    // General category (ETG.2010 Table 7), exactly 32 bytes.
    let header = w.open_category()?;
    let group = table.find(&w, g.group);
    let mut general = [0u8; GENERAL_LEN];
    general[0] = group;
    general[1] = table.find(&w, g.image);
    general[2] = table.find(&w, g.order);
    general[3] = table.find(&w, g.name);
    general[5] = g.coe_details;
    general[6] = g.foe_details;
    general[7] = g.eoe_details;
    general[11] = g.flags;
    let [lo, hi] = g.current_on_ebus.to_le_bytes();
    general[12] = lo;
    general[13] = hi;
    general[14] = group;
    let [lo, hi] = g.physical_port.to_le_bytes();
    general[16] = lo;
    general[17] = hi;
    w.put(&general)?;
    w.close_category(header, CategoryType::General)?;

    // FMMU category (ETG.2010 Table 8).
    let header = w.open_category()?;
    for fmmu in cfg.fmmus {
        w.put_u8(fmmu.raw())?;
    }
    w.pad_to_word(0xFF)?;
    w.close_category(header, CategoryType::Fmmu)?;

    // SyncM category (ETG.2010 Table 9).
    let header = w.open_category()?;
    for sm in cfg.sync_managers {
        let mut rec = [0u8; SYNC_MANAGER_LEN];
        let [a, b] = sm.start.to_le_bytes();
        let [c, d] = sm.length.to_le_bytes();
        rec[0] = a;
        rec[1] = b;
        rec[2] = c;
        rec[3] = d;
        rec[4] = sm.control;
        rec[6] = sm.enable;
        rec[7] = sm.sm_type.raw();
        w.put(&rec)?;
    }
    w.close_category(header, CategoryType::SyncM)?;

    // TxPDO then RxPDO (ETG.2010 Tables 14, 15).
    write_pdos(&mut w, &table, cfg.tx_pdos, CategoryType::TxPdo)?;
    write_pdos(&mut w, &table, cfg.rx_pdos, CategoryType::RxPdo)?;

    // End marker.
    w.put_u16(CategoryType::End.raw())?;
    w.put_u16(0xFFFF)?;
    let used = w.pos;
    if let Some(rest) = w.out.get_mut(used..) {
        rest.fill(0xFF);
    }

    let eeprom_bytes = usize::from(cfg.eeprom_kbit).saturating_mul(128);
    if used > eeprom_bytes {
        return Err(SiiError::ImageTooLarge { used, eeprom_bytes });
    }
    Ok(used)
}

fn invalid(field: &'static str, value: impl Into<u32>) -> SiiError {
    SiiError::InvalidField {
        field,
        value: value.into(),
    }
}

fn validate(cfg: &SiiConfig<'_>) -> Result<(), SiiError> {
    if cfg.eeprom_kbit == 0 {
        return Err(invalid("eeprom_kbit", cfg.eeprom_kbit));
    }
    if cfg.mailbox_protocols & !0x3F != 0 {
        return Err(invalid("mailbox_protocols", cfg.mailbox_protocols));
    }
    let g = &cfg.general;
    if g.coe_details & !0x3F != 0 {
        return Err(invalid("coe_details", g.coe_details));
    }
    if g.foe_details > 1 {
        return Err(invalid("foe_details", g.foe_details));
    }
    if g.eoe_details > 1 {
        return Err(invalid("eoe_details", g.eoe_details));
    }
    if g.flags & !0x1F != 0 {
        return Err(invalid("general flags", g.flags));
    }
    for fmmu in cfg.fmmus {
        if !matches!(fmmu.raw(), 0..=3 | 0xFF) {
            return Err(invalid("fmmu usage", fmmu.raw()));
        }
    }
    for sm in cfg.sync_managers {
        if sm.enable & !0x0F != 0 {
            return Err(invalid("sm enable", sm.enable));
        }
        if sm.sm_type.raw() > 4 {
            return Err(invalid("sm type", sm.sm_type.raw()));
        }
    }
    for pdo in cfg.tx_pdos.iter().chain(cfg.rx_pdos) {
        if pdo.sm == Some(0xFF) {
            return Err(invalid("pdo sm", 0xFFu8));
        }
        if pdo.entries.len() > usize::from(u8::MAX) {
            return Err(SiiError::TooManyEntries { pdo: pdo.index });
        }
    }
    Ok(())
}

fn write_header(cfg: &SiiConfig<'_>, w: &mut Writer<'_>) -> Result<(), SiiError> {
    if w.out.len() < FIRST_CATEGORY_BYTE {
        return Err(SiiError::BufferTooSmall {
            needed: FIRST_CATEGORY_BYTE,
            available: w.out.len(),
        });
    }
    if let Some(header) = w.out.get_mut(..FIRST_CATEGORY_BYTE) {
        header.fill(0);
    }
    for word in [
        cfg.pdi_control,
        cfg.pdi_config,
        cfg.sync_impulse,
        cfg.pdi_config2,
        cfg.station_alias,
        0,
        0,
    ] {
        w.put_u16(word)?;
    }
    let crc = w.out.get(..14).map_or(0, crc8);
    w.put_u16(u16::from(crc))?;
    let id = &cfg.identity;
    for value in [id.vendor_id, id.product_code, id.revision, id.serial] {
        w.put(&value.to_le_bytes())?;
    }
    // Words 0x10..0x13: execution delay and port delays, left zero.
    w.pos = 0x14 * 2;
    for mbx in [cfg.bootstrap_mailbox, cfg.standard_mailbox] {
        let SiiMailbox {
            rx_offset,
            rx_size,
            tx_offset,
            tx_size,
        } = mbx;
        for word in [rx_offset, rx_size, tx_offset, tx_size] {
            w.put_u16(word)?;
        }
    }
    w.put_u16(cfg.mailbox_protocols)?;
    w.pos = 0x3E * 2;
    w.put_u16(cfg.eeprom_kbit.saturating_sub(1))?;
    w.put_u16(1)?;
    Ok(())
}

fn write_pdos(
    w: &mut Writer<'_>,
    table: &StringTable,
    pdos: &[SiiPdo<'_>],
    kind: CategoryType,
) -> Result<(), SiiError> {
    if pdos.is_empty() {
        return Ok(());
    }
    let header = w.open_category()?;
    for pdo in pdos {
        let count = u8::try_from(pdo.entries.len())
            .map_err(|_| SiiError::TooManyEntries { pdo: pdo.index })?;
        let mut rec = [0u8; PDO_RECORD_LEN];
        let [a, b] = pdo.index.to_le_bytes();
        rec[0] = a;
        rec[1] = b;
        rec[2] = count;
        rec[3] = pdo.sm.unwrap_or(0xFF);
        rec[4] = 0; // DC sync
        rec[5] = table.find(w, pdo.name);
        let [a, b] = pdo.flags.to_le_bytes();
        rec[6] = a;
        rec[7] = b;
        w.put(&rec)?;
        for entry in pdo.entries {
            let mut rec = [0u8; PDO_RECORD_LEN];
            let [a, b] = entry.index.to_le_bytes();
            rec[0] = a;
            rec[1] = b;
            rec[2] = entry.sub;
            rec[3] = table.find(w, entry.name);
            rec[4] = entry.data_type;
            rec[5] = entry.bit_len;
            w.put(&rec)?;
        }
    }
    w.close_category(header, kind)
}

/// Sequential writer over the output buffer; every access bounds-checked.
struct Writer<'b> {
    out: &'b mut [u8],
    pos: usize,
}

impl Writer<'_> {
    fn too_small(&self, needed: usize) -> SiiError {
        SiiError::BufferTooSmall {
            needed,
            available: self.out.len(),
        }
    }

    fn put(&mut self, bytes: &[u8]) -> Result<(), SiiError> {
        let end = self
            .pos
            .checked_add(bytes.len())
            .ok_or(self.too_small(usize::MAX))?;
        let available = self.out.len();
        let dst = self
            .out
            .get_mut(self.pos..end)
            .ok_or(SiiError::BufferTooSmall {
                needed: end,
                available,
            })?;
        dst.copy_from_slice(bytes);
        self.pos = end;
        Ok(())
    }

    fn put_u8(&mut self, value: u8) -> Result<(), SiiError> {
        self.put(&[value])
    }

    fn put_u16(&mut self, value: u16) -> Result<(), SiiError> {
        self.put(&value.to_le_bytes())
    }

    fn set_u8(&mut self, at: usize, value: u8) -> Result<(), SiiError> {
        let needed = at.saturating_add(1);
        let err = self.too_small(needed);
        *self.out.get_mut(at).ok_or(err)? = value;
        Ok(())
    }

    fn pad_to_word(&mut self, fill: u8) -> Result<(), SiiError> {
        if self.pos % 2 == 1 {
            self.put_u8(fill)?;
        }
        Ok(())
    }

    /// Reserves a category header, returning its byte offset.
    fn open_category(&mut self) -> Result<usize, SiiError> {
        let at = self.pos;
        self.put(&[0; 4])?;
        Ok(at)
    }

    /// Fills in the header at `at` for the data written since.
    fn close_category(&mut self, at: usize, kind: CategoryType) -> Result<(), SiiError> {
        let data_start = at.saturating_add(4);
        let bytes = self.pos.saturating_sub(data_start);
        let words = u16::try_from(bytes.div_ceil(2)).map_err(|_| SiiError::CategoryTooLong {
            category: kind.raw(),
        })?;
        let [t0, t1] = kind.raw().to_le_bytes();
        let [l0, l1] = words.to_le_bytes();
        let err = self.too_small(data_start);
        let header = self.out.get_mut(at..data_start).ok_or(err)?;
        header.copy_from_slice(&[t0, t1, l0, l1]);
        Ok(())
    }
}

/// The Strings category being built inside the output buffer itself
/// (ETG.2010 Table 6): deduplication scans what was already written, so no
/// extra memory is needed.
struct StringTable {
    /// Byte offset of the count byte.
    count_at: usize,
    /// Byte offset just past the last string.
    end: usize,
    /// Strings written so far.
    count: u8,
}

impl StringTable {
    /// 1-based index of `s` if already written; 0 for the empty string or
    /// when absent.
    fn find(&self, w: &Writer<'_>, s: &str) -> u8 {
        if s.is_empty() {
            return 0;
        }
        let Some(data) = w.out.get(self.count_at.saturating_add(1)..self.end) else {
            return 0;
        };
        let mut rest = data;
        let mut index: u8 = 0;
        while let Some((&len, tail)) = rest.split_first() {
            index = index.saturating_add(1);
            let Some((text, next)) = tail.split_at_checked(usize::from(len)) else {
                return 0;
            };
            if text == s.as_bytes() {
                return index;
            }
            rest = next;
        }
        0
    }

    /// Index of `s`, appending it first when new.
    fn intern(&mut self, w: &mut Writer<'_>, s: &str) -> Result<u8, SiiError> {
        if s.is_empty() {
            return Ok(0);
        }
        let found = self.find(w, s);
        if found != 0 {
            return Ok(found);
        }
        let len = u8::try_from(s.len()).map_err(|_| SiiError::StringTooLong {
            len: s.len(),
            max: MAX_STRING_LEN,
        })?;
        let index = self.count.checked_add(1).ok_or(SiiError::TooManyStrings)?;
        w.pos = self.end;
        w.put_u8(len)?;
        w.put(s.as_bytes())?;
        self.end = w.pos;
        self.count = index;
        Ok(index)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{
        FmmuUsage, SiiGeneral, SiiIdentity, SiiPdoEntry, SiiSyncManager, SmType, protocols,
    };
    use super::*;

    fn minimal<'a>() -> SiiConfig<'a> {
        SiiConfig {
            pdi_control: 0x0005,
            pdi_config: 0,
            sync_impulse: 0,
            pdi_config2: 0,
            station_alias: 0,
            identity: SiiIdentity {
                vendor_id: 1,
                product_code: 2,
                revision: 3,
                serial: 4,
            },
            bootstrap_mailbox: SiiMailbox::default(),
            standard_mailbox: SiiMailbox::default(),
            mailbox_protocols: 0,
            eeprom_kbit: 2,
            general: SiiGeneral {
                group: "G",
                image: "",
                order: "O",
                name: "O",
                coe_details: 0,
                foe_details: 0,
                eoe_details: 0,
                flags: 0,
                current_on_ebus: 0,
                physical_port: 0x0011,
            },
            fmmus: &[FmmuUsage::Outputs],
            sync_managers: &[],
            tx_pdos: &[],
            rx_pdos: &[],
        }
    }

    #[test]
    fn minimal_image_has_exact_bytes() {
        let mut out = [0u8; 256];
        let used = encode(&minimal(), &mut out).unwrap();
        // Header words 0..7 and the checksum.
        assert_eq!(&out[..14], &[5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(out[14], crc8(&out[..14]));
        assert_eq!(out[15], 0);
        assert_eq!(
            &out[16..32],
            &[1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, 4, 0, 0, 0]
        );
        assert_eq!(&out[0x7C..0x80], &[1, 0, 1, 0]);
        // Strings: type 10, 3 words: count 2, "O" (order code first: string
        // 1 is what SOEM shows as the name), "G", pad.
        assert_eq!(&out[0x80..0x8A], &[10, 0, 3, 0, 2, 1, b'O', 1, b'G', 0]);
        // General: type 30, 16 words: group 2, image 0, order 1, name 1.
        assert_eq!(&out[0x8A..0x8E], &[30, 0, 16, 0]);
        assert_eq!(&out[0x8E..0x92], &[2, 0, 1, 1]);
        assert_eq!(out[0x8E + 14], 2);
        assert_eq!(&out[0x8E + 16..0x8E + 18], &[0x11, 0x00]);
        // FMMU: one usage plus 0xFF padding.
        let fmmu = 0x8E + 32;
        assert_eq!(&out[fmmu..fmmu + 6], &[40, 0, 1, 0, 1, 0xFF]);
        // Empty SyncM category then End.
        assert_eq!(&out[fmmu + 6..fmmu + 10], &[41, 0, 0, 0]);
        assert_eq!(&out[fmmu + 10..fmmu + 14], &[0xFF; 4]);
        assert_eq!(used, fmmu + 14);
        assert!(out[used..].iter().all(|&b| b == 0xFF));
    }

    #[test]
    fn buffer_smaller_than_header_is_refused() {
        let mut out = [0u8; 0x7F];
        assert_eq!(
            encode(&minimal(), &mut out),
            Err(SiiError::BufferTooSmall {
                needed: 0x80,
                available: 0x7F
            })
        );
    }

    #[test]
    fn buffer_too_small_for_categories_is_refused() {
        let mut out = [0u8; 0xA0];
        assert!(matches!(
            encode(&minimal(), &mut out),
            Err(SiiError::BufferTooSmall {
                available: 0xA0,
                ..
            })
        ));
    }

    #[test]
    fn image_larger_than_declared_eeprom_is_refused() {
        let mut cfg = minimal();
        cfg.eeprom_kbit = 1; // 128 bytes: the header alone
        let mut out = [0u8; 512];
        assert!(matches!(
            encode(&cfg, &mut out),
            Err(SiiError::ImageTooLarge {
                eeprom_bytes: 128,
                ..
            })
        ));
    }

    #[test]
    fn name_over_64_chars_is_refused() {
        let long = "N234567890123456789012345678901234567890123456789012345678901234X";
        assert_eq!(long.len(), 65);
        let mut cfg = minimal();
        cfg.general.name = long;
        let mut out = [0u8; 512];
        assert_eq!(
            encode(&cfg, &mut out),
            Err(SiiError::StringTooLong { len: 65, max: 64 })
        );
        cfg.general.name = &long[..64];
        assert!(encode(&cfg, &mut out).is_ok());
    }

    #[test]
    fn pdo_entry_name_over_255_bytes_is_refused() {
        let bytes = [b'x'; 256];
        let long = core::str::from_utf8(&bytes).unwrap();
        let entries = [SiiPdoEntry {
            index: 0x7000,
            sub: 1,
            name: long,
            data_type: 1,
            bit_len: 1,
        }];
        let pdos = [SiiPdo {
            index: 0x1600,
            sm: Some(2),
            name: "",
            flags: 0,
            entries: &entries,
        }];
        let mut cfg = minimal();
        cfg.rx_pdos = &pdos;
        let mut out = [0u8; 1024];
        assert_eq!(
            encode(&cfg, &mut out),
            Err(SiiError::StringTooLong { len: 256, max: 255 })
        );
    }

    #[test]
    fn more_than_255_strings_is_refused() {
        // 256 distinct one-entry names: "a".."z" style two-byte names.
        let mut names = [[0u8; 2]; 256];
        for (i, n) in names.iter_mut().enumerate() {
            *n = [b'A' + (i / 26) as u8, b'a' + (i % 26) as u8];
        }
        let entries: std::vec::Vec<SiiPdoEntry<'_>> = names
            .iter()
            .map(|n| SiiPdoEntry {
                index: 0x7000,
                sub: 1,
                name: core::str::from_utf8(n).unwrap(),
                data_type: 1,
                bit_len: 1,
            })
            .collect();
        let pdos = [
            SiiPdo {
                index: 0x1600,
                sm: Some(2),
                name: "",
                flags: 0,
                entries: &entries[..128],
            },
            SiiPdo {
                index: 0x1601,
                sm: Some(2),
                name: "",
                flags: 0,
                entries: &entries[128..],
            },
        ];
        let mut cfg = minimal();
        cfg.general.group = "";
        cfg.general.order = "";
        cfg.general.name = "";
        cfg.rx_pdos = &pdos;
        let mut out = [0u8; 8192];
        assert_eq!(encode(&cfg, &mut out), Err(SiiError::TooManyStrings));
    }

    #[test]
    fn fields_ethercrab_rejects_are_refused() {
        let mut out = [0u8; 512];
        let mut cfg = minimal();
        cfg.general.flags = 0x20;
        assert!(matches!(
            encode(&cfg, &mut out),
            Err(SiiError::InvalidField {
                field: "general flags",
                value: 0x20
            })
        ));
        let mut cfg = minimal();
        cfg.general.coe_details = 0x40;
        assert!(matches!(
            encode(&cfg, &mut out),
            Err(SiiError::InvalidField {
                field: "coe_details",
                ..
            })
        ));
        let mut cfg = minimal();
        cfg.mailbox_protocols = protocols::COE | 0x40;
        assert!(matches!(
            encode(&cfg, &mut out),
            Err(SiiError::InvalidField {
                field: "mailbox_protocols",
                ..
            })
        ));
        let mut cfg = minimal();
        cfg.fmmus = &[FmmuUsage::Unknown(4)];
        assert!(matches!(
            encode(&cfg, &mut out),
            Err(SiiError::InvalidField {
                field: "fmmu usage",
                value: 4
            })
        ));
        let sms = [SiiSyncManager {
            start: 0x1000,
            length: 128,
            control: 0x26,
            enable: 0x11,
            sm_type: SmType::MailboxOut,
        }];
        let mut cfg = minimal();
        cfg.sync_managers = &sms;
        assert!(matches!(
            encode(&cfg, &mut out),
            Err(SiiError::InvalidField {
                field: "sm enable",
                value: 0x11
            })
        ));
        let mut cfg = minimal();
        cfg.eeprom_kbit = 0;
        assert!(matches!(
            encode(&cfg, &mut out),
            Err(SiiError::InvalidField {
                field: "eeprom_kbit",
                ..
            })
        ));
        let pdos = [SiiPdo {
            index: 0x1A00,
            sm: Some(0xFF),
            name: "",
            flags: 0,
            entries: &[],
        }];
        let mut cfg = minimal();
        cfg.tx_pdos = &pdos;
        assert!(matches!(
            encode(&cfg, &mut out),
            Err(SiiError::InvalidField {
                field: "pdo sm",
                ..
            })
        ));
    }

    #[test]
    fn pdo_with_more_than_255_entries_is_refused() {
        let entry = SiiPdoEntry {
            index: 0x7000,
            sub: 1,
            name: "",
            data_type: 1,
            bit_len: 1,
        };
        let entries = [entry; 256];
        let pdos = [SiiPdo {
            index: 0x1600,
            sm: Some(2),
            name: "",
            flags: 0,
            entries: &entries,
        }];
        let mut cfg = minimal();
        cfg.rx_pdos = &pdos;
        let mut out = [0u8; 4096];
        assert_eq!(
            encode(&cfg, &mut out),
            Err(SiiError::TooManyEntries { pdo: 0x1600 })
        );
    }
}
