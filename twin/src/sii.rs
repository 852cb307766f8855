//! The SII EEPROM image of a twin, from its ESI device.
//!
//! When the ESI carries the image (`<Eeprom><Data>`), that is served
//! verbatim (only the station alias, word 4, is replaced when the line
//! gives one, and the checksum recomputed). Otherwise the image is encoded
//! with the core's SII encoder (ETG.2010) from the ESI: the header from
//! `<ConfigData>` (PDI control, PDI configuration, SYNC impulse, PDI
//! configuration 2, alias), the EEPROM size from `<ByteSize>`, identity,
//! mailbox offsets from the mailbox SyncManagers, the General category
//! (group, type, name, CoE details, E-Bus current, physical ports from
//! `Physics`), FMMU, SyncM, TxPDO and RxPDO categories.

use ecat_slave::sii::{
    self, FmmuUsage, SiiConfig, SiiGeneral, SiiIdentity, SiiMailbox, SiiPdo, SiiPdoEntry,
    SiiSyncManager, SmType,
};

use crate::esi::{EsiDevice, EsiPdo};

/// Bytes of EEPROM the software ESC emulates.
pub const EEPROM_BYTES: usize = ecat_slave::sii::SII_SIZE;
/// The largest EEPROM a twin gets when its image needs more than
/// [`EEPROM_BYTES`] (the software ESC emulates up to this).
pub const MAX_EEPROM_BYTES: usize = ecat_sim::esc::MAX_SII_SIZE;

/// Why the SII image cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SiiBuildError {
    /// The core's encoder refused the content.
    #[error("{device}: the SII image cannot be encoded: {source}")]
    Encode {
        /// The device.
        device: String,
        /// The encoder's reason.
        source: sii::SiiError,
    },
    /// `<Eeprom><Data>` is shorter than the SII header.
    #[error("{device}: <Eeprom><Data> holds {len} bytes, less than the 128-byte SII header")]
    DataTooShort {
        /// The device.
        device: String,
        /// Its length.
        len: usize,
    },
}

/// SII "physical port" word from the ESI `Physics` string: one nibble per
/// port, `Y` (100BASE-TX) 1, `K` (E-Bus, LVDS) 3, `H` (fast hot connect)
/// 4, anything else 0.
pub fn physical_port(physics: &str) -> u16 {
    physics
        .chars()
        .take(4)
        .enumerate()
        .map(|(i, c)| {
            let nibble: u16 = match c {
                'Y' => 1,
                'K' => 3,
                'H' => 4,
                _ => 0,
            };
            nibble << (4 * i)
        })
        .sum()
}

/// `s` cut to the core's longest device name ([`sii::MAX_NAME_LEN`]
/// bytes, at a character boundary): ethercrab refuses longer SII names, so
/// a twin shows a vendor's longer name cut.
pub fn fit_name(s: &str) -> &str {
    let mut end = s.len().min(sii::MAX_NAME_LEN);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    s.get(..end).unwrap_or("")
}

fn word(data: &[u8], w: usize) -> u16 {
    let lo = data.get(2 * w).copied().unwrap_or(0);
    let hi = data.get(2 * w + 1).copied().unwrap_or(0);
    u16::from_le_bytes([lo, hi])
}

/// A PDO's fields with its entries borrowed for the encoder.
type PdoParts<'a> = (u16, Option<u8>, &'a str, u16, Vec<SiiPdoEntry<'a>>);

fn to_pdos<'a>(v: &'a [PdoParts<'a>]) -> Vec<SiiPdo<'a>> {
    v.iter()
        .map(|(index, sm, name, flags, entries)| SiiPdo {
            index: *index,
            sm: *sm,
            name,
            flags: *flags,
            entries,
        })
        .collect()
}

fn sii_pdos(pdos: &[EsiPdo], entry_names: bool, pdo_names: bool) -> Vec<PdoParts<'_>> {
    pdos.iter()
        .map(|p| {
            let entries = p
                .entries
                .iter()
                .map(|e| SiiPdoEntry {
                    index: e.index,
                    sub: e.sub,
                    name: if entry_names { &e.name } else { "" },
                    data_type: e.data_type,
                    bit_len: e.bit_len,
                })
                .collect();
            let name = if pdo_names { p.name.as_str() } else { "" };
            (p.index, p.sm, name, p.flags, entries)
        })
        .collect()
}

/// The SII image of `dev` with station alias `alias` (`None`: as the ESI
/// says), [`EEPROM_BYTES`] long.
pub fn image(dev: &EsiDevice, alias: Option<u16>) -> Result<Vec<u8>, SiiBuildError> {
    let mut out = match &dev.eeprom_data {
        Some(data) => {
            if data.len() < 128 {
                return Err(SiiBuildError::DataTooShort {
                    device: dev.label(),
                    len: data.len(),
                });
            }
            let mut img = data.clone();
            img.resize(EEPROM_BYTES.max(img.len()), 0xFF);
            img
        }
        None => encode(dev)?,
    };
    if let Some(a) = alias {
        if let Some(w) = out.get_mut(8..10) {
            w.copy_from_slice(&a.to_le_bytes());
        }
        let crc = out.get(..14).map(sii::crc8).unwrap_or(0);
        if let Some(c) = out.get_mut(14) {
            *c = crc;
        }
    }
    Ok(out)
}

/// Bytes an SII image uses: up to the end of its last category (ETG.2010:
/// categories from word 0x40, each a type word and a length in words, the
/// last of type 0xFFFF).
fn image_end(img: &[u8]) -> usize {
    let mut w = 0x40usize;
    while w * 2 + 4 <= img.len() {
        let ty = word(img, w);
        if ty == 0xFFFF {
            return (w + 1) * 2;
        }
        w += 2 + usize::from(word(img, w + 1));
    }
    img.len()
}

/// The bootstrap mailbox of `Eeprom/BootStrap` (out offset, out size, in
/// offset, in size, little-endian words); none without one.
fn bootstrap(dev: &EsiDevice) -> SiiMailbox {
    let Some(b) = dev
        .source
        .path("Eeprom/BootStrap")
        .and_then(|b| crate::xml::hex_binary(&b.text))
    else {
        return SiiMailbox::default();
    };
    SiiMailbox {
        rx_offset: word(&b, 0),
        rx_size: word(&b, 1),
        tx_offset: word(&b, 2),
        tx_size: word(&b, 3),
    }
}

fn mailbox_area(dev: &EsiDevice, kind: SmType) -> (u16, u16) {
    dev.sms
        .iter()
        .find(|s| s.kind == kind)
        .map_or((0, 0), |s| (s.start, s.default_size))
}

fn encode(dev: &EsiDevice) -> Result<Vec<u8>, SiiBuildError> {
    // An image that does not fit the emulated EEPROM with the names of
    // the PDO entries fits without them (what an EEPROM of a vendor's
    // device often leaves out too): the master names entries from the ESI.
    // An image that needs more than that even without them gets a larger
    // EEPROM, with its names (Beckhoff's EL1259, 8196 bytes without them).
    encode_with(dev, true, true, EEPROM_BYTES)
        .or_else(|_| encode_with(dev, false, true, EEPROM_BYTES))
        .or_else(|_| encode_with(dev, false, false, EEPROM_BYTES))
        .or_else(|_| encode_with(dev, true, true, MAX_EEPROM_BYTES))
}

fn encode_with(
    dev: &EsiDevice,
    entry_names: bool,
    pdo_names: bool,
    eeprom_bytes: usize,
) -> Result<Vec<u8>, SiiBuildError> {
    let cd = &dev.config_data;
    // A loaded ESI's size fits (EsiFile::parse refuses larger ones).
    let kbit = dev.eeprom_kbit().unwrap_or(u16::MAX);
    let (rx_offset, rx_size) = mailbox_area(dev, SmType::MailboxOut);
    let (tx_offset, tx_size) = mailbox_area(dev, SmType::MailboxIn);
    let sms: Vec<SiiSyncManager> = dev
        .sms
        .iter()
        .map(|s| SiiSyncManager {
            start: s.start,
            length: s.default_size,
            control: s.control,
            enable: s.enable,
            sm_type: s.kind,
        })
        .collect();
    let rx = sii_pdos(&dev.rx_pdos, entry_names, pdo_names);
    let tx = sii_pdos(&dev.tx_pdos, entry_names, pdo_names);
    let rx_pdos = to_pdos(&rx);
    let tx_pdos = to_pdos(&tx);
    // An ESI without <Fmmu> (ETG.2000: optional; Beckhoff's CU2508 has
    // none) leaves the FMMUs to the configurator, which takes them in the
    // usual order: outputs, inputs, mailbox status. The EEPROM needs them
    // (ethercrab maps the process data only through a listed FMMU).
    let fmmus = if dev.fmmus.is_empty() && (!dev.rx_pdos.is_empty() || !dev.tx_pdos.is_empty()) {
        let mut f = vec![FmmuUsage::Outputs, FmmuUsage::Inputs];
        if rx_size != 0 {
            f.push(FmmuUsage::SyncMStatus);
        }
        f
    } else {
        dev.fmmus.clone()
    };
    let cfg = SiiConfig {
        pdi_control: word(cd, 0),
        pdi_config: word(cd, 1),
        sync_impulse: word(cd, 2),
        pdi_config2: word(cd, 3),
        station_alias: word(cd, 4),
        identity: SiiIdentity {
            vendor_id: dev.vendor_id,
            product_code: dev.product_code,
            revision: dev.revision,
            serial: 0,
        },
        bootstrap_mailbox: bootstrap(dev),
        standard_mailbox: SiiMailbox {
            rx_offset,
            rx_size,
            tx_offset,
            tx_size,
        },
        mailbox_protocols: dev.mailbox_protocols,
        // The image may need more than the EEPROM the ESI declares (a
        // 128-byte `ByteSize` with categories): the emulated EEPROM holds
        // it all, the header keeps the declared size (word 0x3E below).
        eeprom_kbit: kbit.max(u16::try_from(eeprom_bytes / 128).unwrap_or(u16::MAX)),
        general: SiiGeneral {
            group: fit_name(&dev.group_type),
            image: "",
            order: fit_name(&dev.type_name),
            name: fit_name(&dev.name),
            coe_details: dev.coe_details,
            foe_details: u8::from(dev.mailbox_protocols & sii::protocols::FOE != 0),
            eoe_details: u8::from(dev.mailbox_protocols & sii::protocols::EOE != 0),
            flags: 0,
            current_on_ebus: dev.ebus_current_ma,
            physical_port: physical_port(&dev.physics),
        },
        fmmus: &fmmus,
        sync_managers: &sms,
        tx_pdos: &tx_pdos,
        rx_pdos: &rx_pdos,
    };
    let mut out = vec![0xFFu8; usize::from(cfg.eeprom_kbit) * 128];
    sii::encode(&cfg, &mut out).map_err(|source| SiiBuildError::Encode {
        device: dev.label(),
        source,
    })?;
    // ConfigData covers the first 7 words (ETG.2000: bytes 0..13, the
    // checksum excluded): the reserved words 5 and 6 are the ESI's too
    // (Microchip's SAMD51 sample gives C040 in word 5), and the checksum
    // covers them.
    if cd.len() > 10 {
        for k in 10..14 {
            if let (Some(b), Some(v)) = (out.get_mut(k), cd.get(k)) {
                *b = *v;
            }
        }
        let crc = out.get(..14).map_or(0, sii::crc8);
        if let Some(c) = out.get_mut(14) {
            *c = crc;
        }
    }
    // SII word 0x3E: EEPROM size in kbit - 1 (ETG.2010): the declared
    // size, or the size the image needs when it is more (an EEPROM chip
    // larger than the ESI's ByteSize).
    let end = image_end(&out);
    let needed = u16::try_from(end.div_ceil(128)).unwrap_or(u16::MAX);
    if let Some(w) = out.get_mut(0x7C..0x7E) {
        w.copy_from_slice(&kbit.max(needed).saturating_sub(1).to_le_bytes());
    }
    out.truncate(end.next_multiple_of(128).max(EEPROM_BYTES));
    out.resize(EEPROM_BYTES.max(out.len()), 0xFF);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::esi::EsiFile;
    use ecat_slave::sii::SiiReader;

    const DEV: &str = r##"<EtherCATInfo><Vendor><Id>#x2</Id><Name>V</Name></Vendor><Descriptions><Devices>
<Device Physics="YKY"><Type ProductCode="#x044c2c52" RevisionNo="#x00120000">EK1100</Type><Name>Coupler</Name><Info><Electrical><EBusCurrent>-2000</EBusCurrent></Electrical></Info>
<GroupType>SystemBk</GroupType>
<Eeprom><ByteSize>2048</ByteSize><ConfigData>000D0000000000000000</ConfigData></Eeprom></Device>
</Devices></Descriptions></EtherCATInfo>"##;

    #[test]
    fn long_names_are_cut_at_a_character_boundary() {
        let long = "µ".repeat(40);
        let cut = fit_name(&long);
        assert_eq!(cut.len(), 64);
        assert_eq!(fit_name("EL2004"), "EL2004");
        let odd = format!("a{}", "µ".repeat(40));
        assert_eq!(fit_name(&odd).len(), 63, "no half character");
    }

    #[test]
    fn physics_letters_become_port_nibbles() {
        assert_eq!(physical_port("YKY"), 0x0131);
        assert_eq!(physical_port("KK"), 0x0033);
        assert_eq!(physical_port("YY"), 0x0011);
        assert_eq!(physical_port(""), 0);
        assert_eq!(physical_port("YYYYY"), 0x1111, "4 ports at most");
    }

    #[test]
    fn an_encoded_image_carries_header_identity_and_general_from_the_esi() {
        let f = EsiFile::parse(DEV).unwrap();
        let img = image(&f.devices[0], Some(0x0102)).unwrap();
        assert_eq!(img.len(), EEPROM_BYTES);
        assert_eq!(
            &img[0..2],
            &[0x00, 0x0D],
            "PDI control word from ConfigData"
        );
        assert_eq!(&img[8..10], &[0x02, 0x01], "alias");
        assert_eq!(img[14], sii::crc8(&img[..14]));
        let r = SiiReader::new(&img).unwrap();
        assert_eq!(r.identity().product_code, 0x044c_2c52);
        let g = r.general().unwrap().unwrap();
        assert_eq!(g.current_on_ebus, -2000);
        assert_eq!(g.physical_port, 0x0131);
    }

    #[test]
    fn config_data_of_seven_words_fills_the_reserved_words_and_the_checksum_covers_them() {
        let text = DEV.replace(
            "<ConfigData>000D0000000000000000</ConfigData>",
            "<ConfigData>050E00CC8813FF00000040C00000</ConfigData>",
        );
        let f = EsiFile::parse(&text).unwrap();
        let img = image(&f.devices[0], None).unwrap();
        assert_eq!(
            &img[..14],
            &[
                5, 0x0E, 0, 0xCC, 0x88, 0x13, 0xFF, 0, 0, 0, 0x40, 0xC0, 0, 0
            ]
        );
        assert_eq!(img[14], sii::crc8(&img[..14]));
        assert!(SiiReader::new(&img).is_ok());
    }

    /// `n` fixed TxPDOs of 8 BOOL entries each, with names, in SM0, and no
    /// `<Fmmu>`.
    fn with_tx_pdos(n: u16) -> String {
        let mut pdos = String::from(
            r##"<Sm StartAddress="#x1000" ControlByte="#x20" Enable="1">Inputs</Sm>"##,
        );
        for p in 0..n {
            pdos += &format!(
                r##"<TxPdo Fixed="1" Sm="0"><Index>#x{:x}</Index><Name>Channel {p} inputs</Name>"##,
                0x1A00 + p
            );
            for e in 1..=8 {
                pdos += &format!(
                    r##"<Entry><Index>#x{:x}</Index><SubIndex>{e}</SubIndex><BitLen>1</BitLen><Name>Input {e}</Name><DataType>BOOL</DataType></Entry>"##,
                    0x6000 + p
                );
            }
            pdos += "</TxPdo>";
        }
        DEV.replace("<Eeprom>", &format!("{pdos}<Eeprom>"))
    }

    #[test]
    fn an_esi_without_fmmus_gets_the_usual_ones_in_the_sii() {
        let f = EsiFile::parse(&with_tx_pdos(1)).unwrap();
        assert!(f.refused.is_empty(), "{:?}", f.refused);
        assert!(f.devices[0].fmmus.is_empty());
        let img = image(&f.devices[0], None).unwrap();
        let r = SiiReader::new(&img).unwrap();
        let usage: Vec<FmmuUsage> = r.fmmus().unwrap().collect();
        assert_eq!(usage, [FmmuUsage::Outputs, FmmuUsage::Inputs]);
        // Without process data, no FMMU is made up.
        let f = EsiFile::parse(DEV).unwrap();
        let img = image(&f.devices[0], None).unwrap();
        assert_eq!(SiiReader::new(&img).unwrap().fmmus().unwrap().count(), 0);
    }

    #[test]
    fn an_image_beyond_the_emulated_eeprom_gets_a_larger_one_with_its_names() {
        let f = EsiFile::parse(&with_tx_pdos(120)).unwrap();
        let img = image(&f.devices[0], None).unwrap();
        assert!(img.len() > EEPROM_BYTES && img.len() <= MAX_EEPROM_BYTES);
        assert_eq!(img.len() % 128, 0);
        let r = SiiReader::new(&img).unwrap();
        let pdos = r.pdos(sii::PdoDirection::Tx).unwrap();
        assert_eq!(pdos.count(), 120);
        let strings = r.strings().unwrap();
        let strings: Vec<&str> = strings.iter().filter_map(|(_, s)| s.ok()).collect();
        assert!(strings.contains(&"Input 8"), "names kept");
        let size_kbit = u16::from_le_bytes([img[0x7C], img[0x7D]]) + 1;
        assert!(usize::from(size_kbit) * 128 >= img.len(), "word 0x3E");
    }

    #[test]
    fn eeprom_data_is_served_verbatim_and_a_short_one_is_refused() {
        let data: String = (0..256).map(|i| format!("{:02X}", i % 251)).collect();
        let text = DEV.replace("<ByteSize>2048</ByteSize>", &format!("<Data>{data}</Data>"));
        let f = EsiFile::parse(&text).unwrap();
        let img = image(&f.devices[0], None).unwrap();
        assert_eq!(
            img[..256]
                .iter()
                .map(|b| usize::from(*b))
                .collect::<Vec<_>>(),
            (0..256).map(|i| i % 251).collect::<Vec<_>>()
        );
        assert!(img[256..].iter().all(|b| *b == 0xFF));
        let short = DEV.replace("<ByteSize>2048</ByteSize>", "<Data>0102</Data>");
        let f = EsiFile::parse(&short).unwrap();
        assert!(matches!(
            image(&f.devices[0], None),
            Err(SiiBuildError::DataTooShort { len: 2, .. })
        ));
    }
}
