//! The SII (EEPROM) image parsers: `ecat_slave::sii::SiiReader` (header,
//! category chain, Strings, General, FMMU, SyncM, TxPDO/RxPDO, DC), the
//! `esi` crate's `inspect` (listing and JSON report), `check` (against the
//! PAM's ESI, for images with the PAM's vendor id) and `ihex` (Intel HEX
//! images), and the software ESC serving the image (alias and PDI
//! configuration at power-on).
//!
//! Input: an image, or Intel HEX text of one (an input starting with `:`).
//!
//! Invariants: no panic; the JSON report is valid JSON; a decoded Intel
//! HEX image encodes and decodes back to itself; and the SII round trip:
//! what the reader decodes (the `SiiConfig` the encoder takes), when the
//! encoder accepts it, encodes to an image that decodes to the same
//! configuration and encodes again to the same bytes.
#![no_main]

use std::sync::OnceLock;

use ecat_esi::{check, ihex, inspect};
use ecat_sim::esc::SoftEsc;
use ecat_slave::sii::{
    self, FmmuUsage, PdoDirection, SiiConfig, SiiGeneral, SiiPdo, SiiPdoEntry, SiiReader,
    SiiSyncManager,
};
use libfuzzer_sys::fuzz_target;

/// The PAM's ESI (generated once) without its `Profile` (the object
/// dictionary, 94 % of the text), which `check` does not compare: parsing
/// the whole 166 KB on every run would cost more than the rest together.
fn pam_esi() -> &'static str {
    static ESI: OnceLock<String> = OnceLock::new();
    ESI.get_or_init(|| {
        let xml = ecat_esi::generate(&pam_199_p_etc::DEVICE).expect("PAM ESI");
        let xml = String::from_utf8(xml).expect("UTF-8 ESI");
        let (a, b) = (
            xml.find("<Profile").expect("Profile"),
            xml.find("</Profile>").expect("/Profile"),
        );
        let short = format!("{}{}", &xml[..a], &xml[b + "</Profile>".len()..]);
        let sii = ecat_esi::sii_image(&pam_199_p_etc::DEVICE);
        let m = check::check(&short, &sii).expect("the short ESI reads");
        assert!(
            m.is_empty(),
            "the short ESI still matches the PAM's SII: {m:?}"
        );
        short
    })
}

/// Everything the reader gives for an image (errors included).
fn read_everything(img: &[u8]) {
    let Ok(r) = SiiReader::new(img) else {
        return;
    };
    let _ = (
        r.pdi_control(),
        r.pdi_config(),
        r.sync_impulse(),
        r.pdi_config2(),
    );
    let _ = (r.station_alias(), r.config_data(), r.crc_ok(), r.identity());
    let _ = (
        r.bootstrap_mailbox(),
        r.standard_mailbox(),
        r.mailbox_protocols(),
    );
    let _ = (r.eeprom_size_bytes(), r.version(), r.word(u16::MAX));
    for c in r.categories().take(4096) {
        let Ok(c) = c else { break };
        let _ = (c.kind, c.word_offset, c.data.len());
    }
    if let Ok(strings) = r.strings() {
        let mut buf = [0u8; 80];
        for (i, s) in strings.iter() {
            let _ = (s, strings.get_bytes(i), strings.get(i));
            let _ = strings.get_ascii_lossy(i, &mut buf);
        }
        let _ = strings.get(0);
        let _ = strings.get(255);
        if let Ok(Some(g)) = r.general() {
            let _ = g.resolve(&strings);
        }
    }
    if let Ok(f) = r.fmmus() {
        let _ = f.count();
    }
    if let Ok(s) = r.sync_managers() {
        let _ = s.count();
    }
    for dir in [PdoDirection::Tx, PdoDirection::Rx] {
        if let Ok(pdos) = r.pdos(dir) {
            for p in pdos.take(4096) {
                let Ok(p) = p else { continue };
                let _ = (p.sm(), p.bit_len(), p.entries().count());
            }
        }
    }
    if let Ok(dc) = r.dc() {
        let _ = dc.count();
    }
    let _ = ecat_esi::esi::sii_pdos(&r);
}

/// A PDO entry: index, sub, name, data type, bits.
type Entry = (u16, u8, String, u8, u8);
/// A PDO: index, SyncManager, name, flags, entries.
type Pdo = (u16, Option<u8>, String, u16, Vec<Entry>);

/// The configuration the reader decodes, owned, with string indices
/// resolved: what `SiiConfig` holds.
#[derive(Debug, PartialEq, Eq)]
struct Decoded {
    header: [u16; 5],
    identity: sii::SiiIdentity,
    bootstrap: sii::SiiMailbox,
    standard: sii::SiiMailbox,
    protocols: u16,
    eeprom_kbit: u32,
    general: (String, String, String, String, [u8; 4], i16, u16),
    fmmus: Vec<FmmuUsage>,
    sync_managers: Vec<SiiSyncManager>,
    /// TxPDOs, RxPDOs.
    pdos: [Vec<Pdo>; 2],
}

/// `None` when a category the configuration needs cannot be read.
fn decode(img: &[u8]) -> Option<Decoded> {
    let r = SiiReader::new(img).ok()?;
    let strings = r.strings().ok()?;
    let s = |i: u8| strings.get(i).unwrap_or("").to_string();
    let general = match r.general().ok()? {
        Some(g) => {
            let g = g.resolve(&strings);
            (
                g.group.to_string(),
                g.image.to_string(),
                g.order.to_string(),
                g.name.to_string(),
                [g.coe_details, g.foe_details, g.eoe_details, g.flags],
                g.current_on_ebus,
                g.physical_port,
            )
        }
        None => Default::default(),
    };
    let mut pdos: [Vec<_>; 2] = [vec![], vec![]];
    for (k, dir) in [PdoDirection::Tx, PdoDirection::Rx].into_iter().enumerate() {
        for p in r.pdos(dir).ok()?.take(4096) {
            let Ok(p) = p else { continue };
            let entries = p
                .entries()
                .map(|e| (e.index, e.sub, s(e.name_idx), e.data_type, e.bit_len))
                .collect();
            pdos[k].push((p.index, p.sm(), s(p.name_idx), p.flags, entries));
        }
    }
    Some(Decoded {
        header: [
            r.pdi_control(),
            r.pdi_config(),
            r.sync_impulse(),
            r.pdi_config2(),
            r.station_alias(),
        ],
        identity: r.identity(),
        bootstrap: r.bootstrap_mailbox(),
        standard: r.standard_mailbox(),
        protocols: r.mailbox_protocols(),
        eeprom_kbit: r.eeprom_size_bytes() / 128,
        general,
        fmmus: r.fmmus().ok()?.collect(),
        sync_managers: r.sync_managers().ok()?.collect(),
        pdos,
    })
}

/// Encodes `d` (`None` when the encoder refuses it or it is too large to try).
fn encode(d: &Decoded) -> Option<Vec<u8>> {
    let kbit = u16::try_from(d.eeprom_kbit).ok()?;
    let entries: Vec<Vec<Vec<SiiPdoEntry<'_>>>> = d
        .pdos
        .iter()
        .map(|dir| {
            dir.iter()
                .map(|(_, _, _, _, es)| {
                    es.iter()
                        .map(|(index, sub, name, data_type, bit_len)| SiiPdoEntry {
                            index: *index,
                            sub: *sub,
                            name,
                            data_type: *data_type,
                            bit_len: *bit_len,
                        })
                        .collect()
                })
                .collect()
        })
        .collect();
    let pdos: Vec<Vec<SiiPdo<'_>>> = d
        .pdos
        .iter()
        .zip(&entries)
        .map(|(dir, es)| {
            dir.iter()
                .zip(es)
                .map(|((index, sm, name, flags, _), entries)| SiiPdo {
                    index: *index,
                    sm: *sm,
                    name,
                    flags: *flags,
                    entries,
                })
                .collect()
        })
        .collect();
    let g = &d.general;
    let cfg = SiiConfig {
        pdi_control: d.header[0],
        pdi_config: d.header[1],
        sync_impulse: d.header[2],
        pdi_config2: d.header[3],
        station_alias: d.header[4],
        identity: d.identity,
        bootstrap_mailbox: d.bootstrap,
        standard_mailbox: d.standard,
        mailbox_protocols: d.protocols,
        eeprom_kbit: kbit,
        general: SiiGeneral {
            group: &g.0,
            image: &g.1,
            order: &g.2,
            name: &g.3,
            coe_details: g.4[0],
            foe_details: g.4[1],
            eoe_details: g.4[2],
            flags: g.4[3],
            current_on_ebus: g.5,
            physical_port: g.6,
        },
        fmmus: &d.fmmus,
        sync_managers: &d.sync_managers,
        tx_pdos: &pdos[0],
        rx_pdos: &pdos[1],
    };
    // The whole declared EEPROM, at most 64 KiB (larger images are not
    // tried: the buffer would be allocated on every run).
    let mut out = vec![0u8; (usize::from(kbit) * 128).min(64 * 1024)];
    let used = sii::encode(&cfg, &mut out).ok()?;
    assert!(used <= out.len());
    Some(out)
}

fn round_trip(img: &[u8]) {
    let Some(first) = decode(img) else {
        return;
    };
    let Some(bytes) = encode(&first) else {
        return;
    };
    let again = decode(&bytes).expect("an encoded image decodes");
    assert_eq!(
        first, again,
        "SII decode -> encode -> decode changed the configuration"
    );
    let bytes2 = encode(&again).expect("the encoder takes what it encoded");
    assert!(bytes == bytes2, "SII encode is not stable");
    assert!(
        SiiReader::new(&bytes).is_ok_and(|r| r.crc_ok()),
        "encoded header CRC"
    );
}

fn image(img: &[u8]) {
    read_everything(img);
    if let Ok(report) = inspect::inspect(img) {
        let _ = report.to_text();
        let _ = report.to_report();
        let json = report.to_json();
        if let Err(e) = serde_json::from_str::<serde_json::Value>(&json) {
            panic!("inspect JSON does not parse: {e}\n{json}");
        }
    }
    // The cross-check against the PAM's ESI for images that claim to be
    // a PAM (vendor id, word 0x08): parsing the ESI costs most of a run,
    // and other vendors' images would only differ everywhere.
    if img.get(0x10..0x14) == Some(&pam_199_p_etc::VENDOR_ID.to_le_bytes()[..]) {
        let _ = check::check(pam_esi(), img);
    }
    round_trip(img);
    // The software ESC serving the image: alias and PDI configuration.
    let esc = SoftEsc::new(img);
    let _ = (esc.station_alias(), esc.sii().len());
}

fuzz_target!(|data: &[u8]| {
    if data.first() == Some(&b':') {
        if let Ok(text) = std::str::from_utf8(data)
            && let Ok(img) = ihex::decode(text)
        {
            // Intel HEX decode -> encode -> decode gives the image back.
            let back = ihex::decode(&ihex::encode(&img)).expect("our Intel HEX decodes");
            assert!(back == img, "Intel HEX round trip changed the image");
            image(&img);
        }
        return;
    }
    image(data);
});
