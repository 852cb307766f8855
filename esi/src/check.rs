//! Cross-check of an ESI file against an SII image (host tool).
//!
//! Reads the ESI back with quick-xml's reader and compares what both
//! describe: identity, device strings, mailbox layout and protocols, CoE
//! details, SyncManagers, FMMUs, PDOs (index, default SyncManager — SII
//! 0xFF is an ESI PDO without `Sm` — and entries), ConfigData, BootStrap and
//! the EEPROM size. Every difference is one [`Mismatch`].

use std::fmt;

use ecat_slave::sii::{
    FmmuUsage, PdoDirection, SiiError, SiiReader, SiiStrings, SmType, pdo_flags, protocols,
};

use crate::esi::bootstrap_bytes;
use crate::xml::{self, Element, hex_binary, hex_dec};

/// One difference between the ESI and the SII.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mismatch {
    /// What was compared (`identity product code`, `SM2 length`, ...).
    pub what: String,
    /// The ESI's value.
    pub esi: String,
    /// The SII's value.
    pub sii: String,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: ESI {}, SII {}", self.what, self.esi, self.sii)
    }
}

/// The inputs could not be compared at all.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// The ESI is not well-formed XML.
    #[error("ESI is not well-formed XML: {0}")]
    Xml(#[from] xml::XmlError),
    /// The ESI lacks a required element.
    #[error("ESI has no {0}")]
    Missing(&'static str),
    /// The SII image cannot be read.
    #[error("SII image cannot be read: {0}")]
    Sii(#[from] SiiError),
}

struct Diff(Vec<Mismatch>);

impl Diff {
    fn cmp<T: PartialEq + fmt::Debug>(&mut self, what: impl Into<String>, esi: T, sii: T) {
        if esi != sii {
            self.0.push(Mismatch {
                what: what.into(),
                esi: format!("{esi:?}"),
                sii: format!("{sii:?}"),
            });
        }
    }

    fn hex<T: Into<i64>>(&mut self, what: impl Into<String>, esi: Option<i64>, sii: T) {
        let sii = sii.into();
        if esi != Some(sii) {
            self.0.push(Mismatch {
                what: what.into(),
                esi: esi.map_or_else(|| "missing".into(), |v| format!("{v:#x}")),
                sii: format!("{sii:#x}"),
            });
        }
    }
}

/// `s` cut to what an SII name may hold for ethercrab.
fn fit(s: &str) -> String {
    let mut end = s.len().min(ecat_slave::sii::MAX_NAME_LEN);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    s.get(..end).unwrap_or("").to_string()
}

/// The device's `Name`: the English one (LcId 1033) if there is one.
fn english_name(dev: &Element) -> String {
    dev.children_named("Name")
        .find(|n| n.attr("LcId") == Some("1033"))
        .or_else(|| dev.child("Name"))
        .map(|n| n.text.trim().to_string())
        .unwrap_or_default()
}

fn num(e: Option<&Element>) -> Option<i64> {
    e.and_then(|e| hex_dec(&e.text))
}

/// An xs:boolean attribute value that means true.
fn xml_true(v: &str) -> bool {
    matches!(v.trim(), "1" | "true")
}

fn num_attr(e: &Element, a: &str) -> Option<i64> {
    e.attr(a).and_then(hex_dec)
}

fn string(strings: &SiiStrings<'_>, idx: u8) -> String {
    strings
        .get_bytes(idx)
        .map(|b| String::from_utf8_lossy(b).into_owned())
        .unwrap_or_default()
}

fn esi_sm_type(t: SmType) -> &'static str {
    match t {
        SmType::MailboxOut => "MBoxOut",
        SmType::MailboxIn => "MBoxIn",
        SmType::ProcessOut => "Outputs",
        SmType::ProcessIn => "Inputs",
        SmType::Unused | SmType::Unknown(_) => "",
    }
}

fn esi_fmmu(u: FmmuUsage) -> Option<&'static str> {
    match u {
        FmmuUsage::Outputs => Some("Outputs"),
        FmmuUsage::Inputs => Some("Inputs"),
        FmmuUsage::SyncMStatus => Some("MBoxState"),
        _ => None,
    }
}

/// Compares the ESI text `esi` with the SII image `sii`; an empty list
/// means they agree. Only the first `Device` of the ESI is checked.
pub fn check(esi: &str, sii: &[u8]) -> Result<Vec<Mismatch>, CheckError> {
    check_selected(esi, sii, |_| true)
}

/// [`check`] for the device of the ESI with this product code and
/// revision (a file of several devices).
pub fn check_device(
    esi: &str,
    product_code: u32,
    revision: u32,
    sii: &[u8],
) -> Result<Vec<Mismatch>, CheckError> {
    check_selected(esi, sii, |d| {
        let ty = d.child("Type");
        let n = |a: &str| ty.and_then(|t| num_attr(t, a));
        n("ProductCode") == Some(i64::from(product_code))
            && n("RevisionNo") == Some(i64::from(revision))
    })
}

fn check_selected(
    esi: &str,
    sii: &[u8],
    pick: impl Fn(&Element) -> bool,
) -> Result<Vec<Mismatch>, CheckError> {
    let root = xml::parse(esi)?;
    if root.name != "EtherCATInfo" {
        return Err(CheckError::Missing("EtherCATInfo root element"));
    }
    let dev = root
        .path("Descriptions/Devices")
        .and_then(|d| d.children_named("Device").find(|d| pick(d)))
        .ok_or(CheckError::Missing("Descriptions/Devices/Device"))?;
    let r = SiiReader::new(sii)?;
    let strings = r.strings()?;
    let general = r.general()?;
    let mut d = Diff(Vec::new());

    // Identity.
    let id = r.identity();
    d.hex("vendor id", num(root.path("Vendor/Id")), id.vendor_id);
    let ty = dev
        .child("Type")
        .ok_or(CheckError::Missing("Device/Type"))?;
    d.hex("product code", num_attr(ty, "ProductCode"), id.product_code);
    d.hex("revision", num_attr(ty, "RevisionNo"), id.revision);

    // Device strings and CoE details from the General category.
    match general {
        Some(g) => {
            // Names as the SII can hold them for ethercrab (at most 64
            // bytes, ecat_slave::sii::MAX_NAME_LEN); the English `Name`
            // (LcId 1033) first, as configurators show it.
            d.cmp(
                "order code (Type)",
                fit(ty.text.trim()),
                string(&strings, g.order_idx),
            );
            d.cmp(
                "device name (Name)",
                fit(&english_name(dev)),
                string(&strings, g.name_idx),
            );
            d.cmp(
                "group (GroupType)",
                fit(dev.text_at("GroupType").unwrap_or("").trim()),
                string(&strings, g.group_idx),
            );
            // SOEM names a slave after SII string 1 (ethercrab follows the
            // name index): it must be the device type or its name.
            let first = string(&strings, 1);
            let name = english_name(dev);
            if first != fit(ty.text.trim()) && first != fit(&name) {
                d.0.push(Mismatch {
                    what: "SII string 1 (the device name SOEM shows)".into(),
                    esi: format!("{:?} (Type) or {name:?} (Name)", ty.text),
                    sii: format!("{first:?}"),
                });
            }
            let coe = dev.path("Mailbox/CoE");
            let attr = |a: &str| {
                coe.and_then(|c| c.attr(a))
                    .is_some_and(|v| v == "1" || v == "true")
            };
            for (name, bit) in [
                ("SdoInfo", 1),
                ("PdoAssign", 2),
                ("PdoConfig", 3),
                ("CompleteAccess", 5),
            ] {
                d.cmp(
                    format!("CoE {name} (General CoE details bit {bit})"),
                    attr(name),
                    g.coe_details & (1 << bit) != 0,
                );
            }
        }
        None => d.cmp("General category", "present", "missing"),
    }

    // Mailbox protocols.
    let mbx = dev.child("Mailbox");
    let mut esi_protocols = 0u16;
    for (tag, bit) in [
        ("AoE", protocols::AOE),
        ("EoE", protocols::EOE),
        ("CoE", protocols::COE),
        ("FoE", protocols::FOE),
        ("SoE", protocols::SOE),
        ("VoE", protocols::VOE),
    ] {
        if mbx.and_then(|m| m.child(tag)).is_some() {
            esi_protocols |= bit;
        }
    }
    d.hex(
        "mailbox protocols",
        Some(i64::from(esi_protocols)),
        r.mailbox_protocols(),
    );

    // SyncManagers, and the standard mailbox they carry.
    let esi_sms: Vec<&Element> = dev.children_named("Sm").collect();
    let sii_sms: Vec<_> = r.sync_managers()?.collect();
    d.cmp("SyncManager count", esi_sms.len(), sii_sms.len());
    for (i, (e, s)) in esi_sms.iter().zip(&sii_sms).enumerate() {
        d.hex(
            format!("SM{i} start address"),
            num_attr(e, "StartAddress"),
            s.start,
        );
        // No DefaultSize: the master sizes it (0 in the SII).
        d.hex(
            format!("SM{i} length"),
            Some(num_attr(e, "DefaultSize").unwrap_or(0)),
            s.length,
        );
        // A virtual SyncManager may leave ControlByte and Enable out.
        d.hex(
            format!("SM{i} control byte"),
            Some(num_attr(e, "ControlByte").unwrap_or(0)),
            s.control,
        );
        // ETG.2010 SyncM enable byte: bit 0 enable, 2 virtual, 3 OpOnly.
        let enable = Some(
            num_attr(e, "Enable").unwrap_or(0) & 1
                | i64::from(e.attr("Virtual").is_some_and(xml_true)) << 2
                | i64::from(e.attr("OpOnly").is_some_and(xml_true)) << 3,
        );
        d.hex(format!("SM{i} enable"), enable, s.enable);
        d.cmp(
            format!("SM{i} type"),
            e.text.as_str(),
            esi_sm_type(s.sm_type),
        );
    }
    let mb = r.standard_mailbox();
    let by_type = |t: &str| esi_sms.iter().find(|e| e.text == t);
    for (t, offset, size) in [
        ("MBoxOut", mb.rx_offset, mb.rx_size),
        ("MBoxIn", mb.tx_offset, mb.tx_size),
    ] {
        // No mailbox SyncManager: no mailbox (0 in the SII).
        let e = by_type(t);
        d.hex(
            format!("{t} offset (SII standard mailbox)"),
            Some(e.and_then(|e| num_attr(e, "StartAddress")).unwrap_or(0)),
            offset,
        );
        d.hex(
            format!("{t} size (SII standard mailbox)"),
            Some(e.and_then(|e| num_attr(e, "DefaultSize")).unwrap_or(0)),
            size,
        );
    }

    // FMMUs.
    let esi_fmmus: Vec<String> = dev.children_named("Fmmu").map(|e| e.text.clone()).collect();
    let sii_fmmus: Vec<String> = r
        .fmmus()?
        .filter_map(esi_fmmu)
        .map(str::to_string)
        .collect();
    // An ESI without <Fmmu> (optional in ETG.2000) says nothing about
    // the FMMUs: the configurator assigns them.
    if !esi_fmmus.is_empty() {
        d.cmp("FMMU usage", esi_fmmus, sii_fmmus);
    }

    // PDOs.
    for (direction, tag) in [(PdoDirection::Rx, "RxPdo"), (PdoDirection::Tx, "TxPdo")] {
        let esi_pdos: Vec<&Element> = dev.children_named(tag).collect();
        let mut seen = Vec::new();
        for p in r.pdos(direction)? {
            let p = p?;
            seen.push(i64::from(p.index));
            let what = format!("{tag} {:#06x}", p.index);
            let Some(e) = esi_pdos
                .iter()
                .find(|e| num(e.child("Index")) == Some(i64::from(p.index)))
            else {
                d.cmp(what, "missing", "present");
                continue;
            };
            d.cmp(
                format!("{what} SyncManager"),
                num_attr(e, "Sm"),
                p.sm().map(i64::from),
            );
            d.cmp(
                format!("{what} name"),
                e.text_at("Name").unwrap_or("").to_string(),
                string(&strings, p.name_idx),
            );
            // Flags the ESI states as attributes (ETG.2000 PdoType) and the
            // SII as bits (ETG.2010 Table 14).
            for (attr, bit) in [
                ("Fixed", pdo_flags::FIXED_CONTENT),
                ("Mandatory", pdo_flags::MANDATORY),
                ("Virtual", pdo_flags::VIRTUAL_CONTENT),
            ] {
                d.cmp(
                    format!("{what} {attr} (SII flag {bit:#06x})"),
                    e.attr(attr).is_some_and(xml_true),
                    p.flags & bit != 0,
                );
            }
            // A padding entry of no bits maps nothing (the SII has none).
            let esi_entries: Vec<(i64, i64, i64)> = e
                .children_named("Entry")
                .filter(|x| num(x.child("Index")) != Some(0) || num(x.child("BitLen")) != Some(0))
                .map(|x| {
                    (
                        num(x.child("Index")).unwrap_or(-1),
                        num(x.child("SubIndex")).unwrap_or(0),
                        num(x.child("BitLen")).unwrap_or(-1),
                    )
                })
                .collect();
            let sii_entries: Vec<(i64, i64, i64)> = p
                .entries()
                .map(|x| (i64::from(x.index), i64::from(x.sub), i64::from(x.bit_len)))
                .collect();
            if esi_entries.len() != sii_entries.len() {
                d.cmp(
                    format!("{what} entry count"),
                    esi_entries.len(),
                    sii_entries.len(),
                );
            }
            for (n, (a, b)) in esi_entries.iter().zip(&sii_entries).enumerate() {
                if a != b {
                    d.0.push(Mismatch {
                        what: format!("{what} entry {}", n + 1),
                        esi: format!("{:#06x}:{} {} bits", a.0, a.1, a.2),
                        sii: format!("{:#06x}:{} {} bits", b.0, b.1, b.2),
                    });
                }
            }
        }
        for e in &esi_pdos {
            let index = num(e.child("Index")).unwrap_or(-1);
            if !seen.contains(&index) {
                d.cmp(format!("{tag} {index:#06x}"), "present", "missing");
            }
        }
    }

    // EEPROM.
    let eeprom = dev.child("Eeprom");
    let text = |p: &str| eeprom.and_then(|e| e.text_at(p));
    let bytes_at = |p: &str| {
        text(p)
            .and_then(hex_binary)
            .map_or_else(|| "missing".to_string(), |b| crate::esi::hex_binary(&b))
    };
    // ConfigData gives the first words; the rest of 0..13 is zero.
    let config = text("ConfigData").and_then(hex_binary).map(|mut b| {
        b.resize(r.config_data().len(), 0);
        crate::esi::hex_binary(&b)
    });
    // The station alias (word 4, bytes 8-9) is the configurator's to
    // write into a device (ETG.2010 2.2, ETG.2100 `Identification`): an
    // ESI that leaves it 0 agrees with any alias.
    let mut sii_config = r.config_data();
    let esi_alias = text("ConfigData").and_then(hex_binary).map_or(0, |b| {
        b.get(8..10).map_or(0, |w| u16::from_le_bytes([w[0], w[1]]))
    });
    if esi_alias == 0
        && let Some(w) = sii_config.get_mut(8..10)
    {
        w.fill(0);
    }
    d.cmp(
        "Eeprom ConfigData (SII bytes 0..13)",
        config.unwrap_or_else(|| crate::esi::hex_binary(&sii_config)),
        crate::esi::hex_binary(&sii_config),
    );
    // No BootStrap: no bootstrap mailbox (zeros in the SII).
    let boot = match bytes_at("BootStrap") {
        b if b == "missing" => "0000000000000000".to_string(),
        b => b,
    };
    d.cmp(
        "Eeprom BootStrap (SII bootstrap mailbox)",
        boot,
        crate::esi::hex_binary(&bootstrap_bytes(&r.bootstrap_mailbox())),
    );
    // An EEPROM may be larger than the ESI's ByteSize (the image needs
    // more than a 128-byte ByteSize says, EL9800): smaller is a mismatch.
    let declared = text("ByteSize").and_then(hex_dec);
    let size = i64::from(r.eeprom_size_bytes());
    // (No ByteSize: the ESI does not say; the SII's size stands.)
    if declared.is_some_and(|b| size < b) {
        d.hex("Eeprom ByteSize", declared, r.eeprom_size_bytes());
    }
    Ok(d.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::esi::generate;
    use ecat_slave::sii::{CategoryType, crc8};

    fn ours() -> (String, Vec<u8>) {
        let esi = String::from_utf8(generate(&pam_199_p_etc::DEVICE).unwrap()).unwrap();
        (esi, crate::sii_image(&pam_199_p_etc::DEVICE))
    }

    /// Byte offset of the data of the first category of `kind`.
    fn category_data(img: &[u8], kind: CategoryType) -> usize {
        let r = SiiReader::new(img).unwrap();
        let c = r.find(kind).unwrap().unwrap();
        usize::from(c.word_offset) * 2 + 4
    }

    fn fix_crc(img: &mut [u8]) {
        img[14] = crc8(&img[..14]);
    }

    #[test]
    fn our_esi_and_our_sii_agree() {
        let (esi, sii) = ours();
        let m = check(&esi, &sii).unwrap();
        assert!(m.is_empty(), "{m:#?}");
    }

    #[test]
    fn changed_product_code_in_the_sii_is_reported() {
        let (esi, mut sii) = ours();
        sii[0x14] ^= 0x01;
        let m = check(&esi, &sii).unwrap();
        assert!(m.iter().any(|m| m.what == "product code"), "{m:#?}");
    }

    #[test]
    fn changed_sm_size_is_reported() {
        let (esi, mut sii) = ours();
        let at = category_data(&sii, CategoryType::SyncM) + 2 * 8 + 2; // SM2 length
        sii[at] = sii[at].wrapping_add(1);
        let m = check(&esi, &sii).unwrap();
        assert!(m.iter().any(|m| m.what == "SM2 length"), "{m:#?}");
    }

    #[test]
    fn an_esi_without_fmmus_agrees_with_the_fmmus_of_any_sii() {
        let (esi, sii) = ours();
        assert!(esi.contains("<Fmmu>"));
        let bare: String = esi
            .lines()
            .filter(|l| !l.trim_start().starts_with("<Fmmu>"))
            .collect::<Vec<_>>()
            .join("\n");
        assert!(!bare.contains("<Fmmu>"));
        let m = check(&bare, &sii).unwrap();
        assert!(m.is_empty(), "{m:#?}");
        // With its FMMUs, a changed usage is still reported.
        let mut changed = sii.clone();
        let at = category_data(&changed, CategoryType::Fmmu);
        changed[at] = 0x03;
        let m = check(&esi, &changed).unwrap();
        assert!(m.iter().any(|m| m.what == "FMMU usage"), "{m:#?}");
    }

    #[test]
    fn a_station_alias_the_configurator_wrote_agrees_with_an_esi_that_leaves_it_0() {
        let (esi, mut sii) = ours();
        sii[8..10].copy_from_slice(&42u16.to_le_bytes());
        fix_crc(&mut sii);
        let m = check(&esi, &sii).unwrap();
        assert!(m.is_empty(), "{m:#?}");
        // Another PDI control word is still a difference.
        sii[0] ^= 0x01;
        fix_crc(&mut sii);
        let m = check(&esi, &sii).unwrap();
        assert!(
            m.iter().any(|m| m.what.starts_with("Eeprom ConfigData")),
            "{m:#?}"
        );
    }

    #[test]
    fn pdo_moved_to_no_sync_manager_is_reported() {
        let (esi, mut sii) = ours();
        // First RxPDO (0x1600): SM byte at header offset 3.
        let at = category_data(&sii, CategoryType::RxPdo);
        assert_eq!(u16::from_le_bytes([sii[at], sii[at + 1]]), 0x1600);
        sii[at + 3] = 0xFF;
        let m = check(&esi, &sii).unwrap();
        assert!(
            m.iter().any(|m| m.what == "RxPdo 0x1600 SyncManager"),
            "{m:#?}"
        );
    }

    #[test]
    fn sii_string_1_that_is_not_the_device_is_reported() {
        let (esi, sii) = ours();
        let r = SiiReader::new(&sii).unwrap();
        assert_eq!(r.strings().unwrap().get(1), Some("PAM-199-P-ETC"));
        // Swap string 1 for another name of the same length.
        let at = category_data(&sii, CategoryType::Strings) + 2;
        let mut bad = sii.clone();
        bad[at..at + 13].copy_from_slice(b"PAM-199-P-XXX");
        let m = check(&esi, &bad).unwrap();
        assert!(
            m.iter()
                .any(|m| m.what == "SII string 1 (the device name SOEM shows)"),
            "{m:#?}"
        );
    }

    #[test]
    fn cleared_fixed_content_flag_is_reported() {
        let (esi, mut sii) = ours();
        // First RxPDO (0x1600): flags at header offset 6.
        let at = category_data(&sii, CategoryType::RxPdo);
        assert_eq!(sii[at + 6] & 0x10, 0x10, "0x1600 is fixed in the SII");
        sii[at + 6] &= !0x10;
        let m = check(&esi, &sii).unwrap();
        assert!(
            m.iter()
                .any(|m| m.what == "RxPdo 0x1600 Fixed (SII flag 0x0010)"),
            "{m:#?}"
        );
    }

    #[test]
    fn every_pdo_the_esi_marks_fixed_has_the_sii_flag() {
        let (esi, sii) = ours();
        let doc = crate::xml::parse(&esi).unwrap();
        let dev = doc.path("Descriptions/Devices/Device").unwrap();
        let fixed: Vec<i64> = dev
            .children
            .iter()
            .filter(|e| e.name == "RxPdo" || e.name == "TxPdo")
            .filter(|e| e.attr("Fixed") == Some("1"))
            .filter_map(|e| num(e.child("Index")))
            .collect();
        assert_eq!(fixed.len(), 6, "every PAM PDO has fixed content");
        let r = SiiReader::new(&sii).unwrap();
        for dir in [PdoDirection::Rx, PdoDirection::Tx] {
            for p in r.pdos(dir).unwrap() {
                let p = p.unwrap();
                assert_eq!(
                    p.flags & pdo_flags::FIXED_CONTENT != 0,
                    fixed.contains(&i64::from(p.index)),
                    "{:#06x}",
                    p.index
                );
            }
        }
    }

    #[test]
    fn changed_config_data_is_reported() {
        let (esi, mut sii) = ours();
        sii[2] ^= 0x01; // PDI configuration low byte
        fix_crc(&mut sii);
        let m = check(&esi, &sii).unwrap();
        assert!(
            m.iter().any(|m| m.what.starts_with("Eeprom ConfigData")),
            "{m:#?}"
        );
    }

    #[test]
    fn flipped_capability_is_reported_against_the_sii() {
        let (_, sii) = ours();
        let mut dev = pam_199_p_etc::DEVICE;
        dev.mailbox.coe.complete_access = false;
        let esi = String::from_utf8(generate(&dev).unwrap()).unwrap();
        let m = check(&esi, &sii).unwrap();
        assert_eq!(m.len(), 1, "{m:#?}");
        assert!(m[0].what.starts_with("CoE CompleteAccess"));
    }

    #[test]
    fn invalid_inputs_are_errors_not_panics() {
        let (esi, sii) = ours();
        assert!(matches!(check("<a>", &sii), Err(CheckError::Xml(_))));
        assert!(matches!(check("<a/>", &sii), Err(CheckError::Missing(_))));
        assert!(matches!(check(&esi, &sii[..16]), Err(CheckError::Sii(_))));
    }
}
