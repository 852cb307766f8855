//! Software twins from ESI files and a line from an ENI (`ecat-twin`):
//! the twins' SII agrees with the real devices' SII dumps, ethercrab brings
//! the ENI line EK1100, EL2004, EL2828, EL1008, PAM-199-P-ETC to OP with
//! the identities and process-image sizes of the real devices and
//! exchanges process data with every slave, and a broken ESI names the
//! element and line and starts nothing.

use std::path::{Path, PathBuf};
use std::time::Duration;

use device_catalog::twins;
use ecat_esi::inspect::{Inspection, inspect};
use ecat_sim::chain::Chain;
use ecat_slave::sii::PdoDirection;
use ecat_twin::{EscTwin, EsiFile, InputRule};
use master_test::VirtualBus;
use master_test::link::{Clock, lock};

fn testdata(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../twin/testdata")
        .join(p)
}

/// A real device's SII dump from `tests/data/sii-dumps` (provenance in
/// `tests/data/README.md`).
fn dump(name: &str) -> Vec<u8> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/sii-dumps")
        .join(name);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Output and input bytes a master gives the device of this SII: its
/// PDOs' bits per SyncManager, rounded up to bytes.
fn image_bytes(i: &Inspection) -> (usize, usize) {
    let mut out = std::collections::BTreeMap::<(bool, u8), u32>::new();
    for p in i.pdos.iter().filter(|p| p.sm_raw != 0xFF) {
        let bits: u32 = p.entries.iter().map(|e| u32::from(e.bit_len)).sum();
        *out.entry((p.direction == PdoDirection::Rx, p.sm_raw))
            .or_default() += bits;
    }
    let sum = |rx: bool| {
        out.iter()
            .filter(|((r, _), _)| *r == rx)
            .map(|(_, b)| b.div_ceil(8) as usize)
            .sum()
    };
    (sum(true), sum(false))
}

/// What a master reads from an SII and the twin must show as the real
/// device does.
fn visible(i: &Inspection) -> String {
    let g = i.general.as_ref().map(|(raw, s)| {
        format!(
            "group {:?} order {:?} name {:?} coe {:#x} ebus {} ports {:#06x}",
            s[0], s[2], s[3], raw.coe_details, raw.current_on_ebus, raw.physical_port
        )
    });
    let pdos: Vec<String> = i
        .pdos
        .iter()
        .map(|p| {
            let e: Vec<String> = p
                .entries
                .iter()
                .map(|e| {
                    format!(
                        "{:#06x}:{} {:?} t{} b{}",
                        e.index, e.sub, e.name, e.data_type, e.bit_len
                    )
                })
                .collect();
            format!(
                "{:?} {:#06x} {:?} sm{} f{:#x} [{}]",
                p.direction,
                p.index,
                p.name,
                p.sm_raw,
                p.flags,
                e.join(", ")
            )
        })
        .collect();
    let fmmus: Vec<u8> = i
        .fmmus
        .iter()
        .copied()
        .filter(|u| *u != 0xFF && *u != 0)
        .collect();
    format!(
        "pdi {:04x?}\nidentity {:x?}\nmailbox {:#x} {:?}\ngeneral {g:?}\nfmmus {fmmus:?}\nsms {:?}\npdos {pdos:#?}\neeprom {}",
        i.pdi, i.identity, i.mailbox_protocols, i.standard_mailbox, i.sync_managers, i.eeprom_bytes
    )
}

/// What SOEM must see on the ENI line (`name|vendor|product|rev|out|in`
/// per slave): the EK1100, EL2004 and EL2828 from their real SII dumps
/// (SOEM names a slave by the SII General order string), the EL1008 from
/// its ESI, the PAM from its description.
pub(crate) fn soem_expectations() -> String {
    let mut out = Vec::new();
    for n in [
        "ek1100-eeprom-dump.bin",
        "el2004-eeprom-dump.bin",
        "el2828.bin",
    ] {
        let i = inspect(&dump(n)).expect("dump");
        let (o, inp) = image_bytes(&i);
        let order = i
            .general
            .as_ref()
            .map(|(_, s)| s[2].clone())
            .unwrap_or_default();
        out.push(format!(
            "{order}|{:#x}|{:#x}|{:#x}|{o}|{inp}",
            i.identity.vendor_id, i.identity.product_code, i.identity.revision
        ));
    }
    out.push("EL1008|0x2|0x3f03052|0x100000|0|1".into());
    let pam = &pam_199_p_etc::DEVICE;
    out.push(format!(
        "{}|{:#x}|{:#x}|{:#x}|5|14",
        pam.names.type_name,
        pam.identity.vendor_id,
        pam.identity.product_code,
        pam.identity.revision
    ));
    let io8 = &io8_example::DEVICE;
    out.push(format!(
        "{}|{:#x}|{:#x}|{:#x}|1|1",
        io8.names.type_name, io8.identity.vendor_id, IO8_TWIN_PRODUCT, io8.identity.revision
    ));
    out.join(";")
}

/// Product code of the IO8 twin in the SOEM ENI line (not the catalog's,
/// so the twin is built from its ESI).
const IO8_TWIN_PRODUCT: u32 = 0x108;

/// The IO8's ESI under product code [`IO8_TWIN_PRODUCT`], and `eni` with
/// a sixth slave of it whose CoE init commands set its PDO assignment and
/// its input filter (0x8000:01 = 250 ms).
pub(crate) fn coe_twin_line(eni: &str) -> (String, String) {
    let io8 = &io8_example::DEVICE;
    let esi = String::from_utf8(ecat_esi::generate(io8).expect("ESI"))
        .expect("utf-8")
        .replace(
            &format!("ProductCode=\"#x{:08X}\"", io8.identity.product_code),
            &format!("ProductCode=\"#x{IO8_TWIN_PRODUCT:08X}\""),
        );
    assert!(
        esi.contains(&format!("#x{IO8_TWIN_PRODUCT:08X}")),
        "product code replaced"
    );
    let slave = format!(
        r##"<Slave>
      <Info><Name>Term 6 (IO8 twin)</Name><PhysAddr>1006</PhysAddr><AutoIncAddr>65531</AutoIncAddr>
        <VendorId>{}</VendorId><ProductCode>{IO8_TWIN_PRODUCT}</ProductCode><RevisionNo>{}</RevisionNo></Info>
      <ProcessData><Send><BitStart>56</BitStart><BitLength>8</BitLength></Send><Recv><BitStart>120</BitStart><BitLength>8</BitLength></Recv></ProcessData>
      <Mailbox><Protocol>CoE</Protocol><CoE><InitCmds>
        <InitCmd><Transition>PS</Transition><Comment>clear RxPDO assignment</Comment><Ccs>1</Ccs><Index>#x1c12</Index><SubIndex>0</SubIndex><Data>00</Data></InitCmd>
        <InitCmd><Transition>PS</Transition><Comment>RxPDO 0x1600</Comment><Ccs>1</Ccs><Index>#x1c12</Index><SubIndex>1</SubIndex><Data>0016</Data></InitCmd>
        <InitCmd><Transition>PS</Transition><Comment>1 RxPDO</Comment><Ccs>1</Ccs><Index>#x1c12</Index><SubIndex>0</SubIndex><Data>01</Data></InitCmd>
        <InitCmd><Transition>PS</Transition><Comment>input filter 250 ms</Comment><Ccs>1</Ccs><Index>#x8000</Index><SubIndex>1</SubIndex><Data>fa00</Data></InitCmd>
      </InitCmds></CoE></Mailbox>
    </Slave>
  </Config>"##,
        io8.identity.vendor_id, io8.identity.revision
    );
    (esi, eni.replacen("</Config>", &slave, 1))
}

#[test]
fn twins_from_the_synthetic_esi_files_show_what_the_real_devices_sii_dumps_show() {
    let dir = testdata("esi");
    for (file, ty, dump_name) in [
        ("EK1100.xml", "EK1100", "ek1100-eeprom-dump.bin"),
        ("EL2xxx.xml", "EL2004", "el2004-eeprom-dump.bin"),
        ("EL2xxx.xml", "EL2828", "el2828.bin"),
    ] {
        let esi = ecat_twin::load_esi(&dir.join(file)).expect("ESI loads");
        let dev = esi.device(Some(ty), None).expect("device");
        let twin = ecat_twin::twin(dev, None, InputRule::Hold).expect("twin");
        let ours = inspect(twin.esc().sii()).expect("twin SII decodes");
        let real = inspect(&dump(dump_name)).expect("dump decodes");
        assert!(ours.problems.is_empty(), "{ty}: {:?}", ours.problems);
        assert!(ours.crc_ok(), "{ty}: checksum");
        assert_eq!(
            visible(&ours),
            visible(&real),
            "{ty}: twin SII vs the real device's dump"
        );
        assert_eq!(
            image_bytes(&ours),
            image_bytes(&real),
            "{ty}: process image"
        );
    }
}

#[test]
fn an_esi_carrying_the_eeprom_data_is_served_byte_for_byte() {
    // The real EL2889's EEPROM as `<Eeprom><Data>` of an ESI made here:
    // the twin serves exactly the real device's image.
    let real = dump("el2889.bin");
    let hex: String = real.iter().map(|b| format!("{b:02X}")).collect();
    let esi = format!(
        r##"<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>#x2</Id><Name>V</Name></Vendor><Descriptions><Devices>
<Device Physics="KK"><Type ProductCode="#x0b493052" RevisionNo="#x00110000">EL2889</Type><Name>EL2889</Name>
<Sm StartAddress="#x0f00" ControlByte="#x44" Enable="1">Outputs</Sm>
<Sm StartAddress="#x0f01" ControlByte="#x44" Enable="1">Outputs</Sm>
<Eeprom><Data>{hex}</Data></Eeprom></Device></Devices></Descriptions></EtherCATInfo>"##
    );
    let file = EsiFile::parse(&esi).expect("parses");
    let dev = &file.devices[0];
    let twin = ecat_twin::twin(dev, None, InputRule::Hold).expect("twin");
    assert_eq!(&twin.esc().sii()[..real.len()], &real[..]);
    // With an alias from a line, only word 4 and the checksum change.
    let aliased = ecat_twin::sii::image(dev, Some(0x1234)).expect("image");
    assert_eq!(&aliased[8..10], &[0x34, 0x12]);
    let i = inspect(&aliased).expect("decodes");
    assert!(i.crc_ok());
    assert_eq!(&aliased[16..real.len()], &real[16..]);
}

#[test]
fn ethercrab_brings_the_eni_line_to_op_with_the_real_devices_identities_and_images() {
    let ecat_twin::line::BuiltLine { slaves, placed } = twins::from_eni(
        &testdata("machine.xml"),
        Some(&testdata("esi")),
        &ecat_twin::InputRules::all(InputRule::Hold),
    )
    .expect("line from the ENI");
    assert_eq!(placed.len(), 5);
    // From the dumps: identity and process image of the real devices; the
    // EL1008 (no dump) and the PAM from their own descriptions.
    let real: Vec<(u32, u32, (usize, usize))> = [
        "ek1100-eeprom-dump.bin",
        "el2004-eeprom-dump.bin",
        "el2828.bin",
    ]
    .iter()
    .map(|n| {
        let i = inspect(&dump(n)).expect("dump");
        (
            i.identity.vendor_id,
            i.identity.product_code,
            image_bytes(&i),
        )
    })
    .collect();
    smol::block_on(async {
        let bus = VirtualBus::with_chain(Chain::with_slaves(slaves), Clock::simulated(), None)
            .expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init to PRE-OP");
        assert_eq!(group.len(), 5);
        let names: Vec<String> = group.iter(md).map(|sd| sd.name().to_string()).collect();
        eprintln!("ethercrab sees: {names:?}");
        for (k, (sd, (vendor, product, _))) in group.iter(md).zip(&real).enumerate() {
            let id = sd.identity();
            assert_eq!(
                (id.vendor_id, id.product_id),
                (*vendor, *product),
                "slave {k}"
            );
        }
        let pam = group.iter(md).nth(4).expect("PAM");
        assert_eq!(pam.name(), "PAM-199-P-ETC");
        assert_eq!(
            pam.alias_address(),
            42,
            "the ENI's alias is in the PAM's SII"
        );
        let group = group.into_op(md).await.expect("into OP");
        let sizes: Vec<(usize, usize)> = group
            .iter(md)
            .map(|sd| (sd.outputs_raw().len(), sd.inputs_raw().len()))
            .collect();
        assert_eq!(
            &sizes[..3],
            &real.iter().map(|r| r.2).collect::<Vec<_>>()[..],
            "EK1100, EL2004, EL2828 images as their dumps say"
        );
        assert_eq!(&sizes[3..], &[(0, 1), (5, 14)], "EL1008 and PAM");
        // Outputs to both output terminals, an input pattern on the EL1008.
        for (k, sd) in group.iter(md).enumerate() {
            let mut out = sd.outputs_raw_mut();
            match k {
                1 => out[0] = 0x0A,
                2 => out[0] = 0xA5,
                _ => {}
            }
        }
        {
            let mut chain = lock(&bus.chain);
            let el1008 = chain.slaves_mut()[3]
                .as_any_mut()
                .downcast_mut::<EscTwin>()
                .expect("slave 3 is an ESI twin");
            el1008.set_inputs(&[0x5C]);
        }
        for _ in 0..10 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("tx_rx");
        }
        let el1008_in = group.iter(md).nth(3).expect("EL1008").inputs_raw().to_vec();
        assert_eq!(
            el1008_in,
            [0x5C],
            "the EL1008 twin's inputs reach the master"
        );
        let chain = lock(&bus.chain);
        let outs = |k: usize| {
            chain.slaves()[k]
                .as_any()
                .downcast_ref::<EscTwin>()
                .expect("ESI twin")
                .outputs()
                .to_vec()
        };
        assert_eq!(outs(1), [0x0A], "EL2004 outputs");
        assert_eq!(outs(2), [0xA5], "EL2828 outputs");
        for k in 0..5 {
            assert_eq!(
                chain.slaves()[k].al_status().state,
                ecat_slave::al::AlState::Op,
                "slave {k} in OP"
            );
        }
    });
}

#[test]
fn a_counter_twin_changes_its_inputs_every_cycle() {
    let esi = ecat_twin::load_esi(&testdata("esi/EL1008.xml")).expect("ESI");
    let dev = esi.device(None, None).expect("one device");
    let twin = ecat_twin::twin(dev, None, InputRule::Counter).expect("twin");
    smol::block_on(async {
        let bus = VirtualBus::with_chain(Chain::with_slaves(vec![twin]), Clock::simulated(), None)
            .expect("bus");
        let md = &*bus.maindevice;
        let group = bus
            .init()
            .await
            .expect("init")
            .into_op(md)
            .await
            .expect("OP");
        let mut seen = std::collections::BTreeSet::new();
        for _ in 0..5 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("tx_rx");
            seen.insert(group.iter(md).next().expect("slave").inputs_raw()[0]);
        }
        assert!(seen.len() >= 3, "counter values seen: {seen:?}");
    });
}

/// A copy of the EL2xxx ESI with one text replaced.
fn broken(from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(testdata("esi/EL2xxx.xml")).expect("ESI");
    assert!(text.contains(from), "{from}");
    text.replacen(from, to, 1)
}

fn line_of(text: &str, needle: &str) -> u32 {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle") as u32
        + 1
}

#[test]
fn an_unknown_pdo_entry_type_is_a_warning_naming_the_element_and_line() {
    let text = broken(
        "<Name>Output</Name><DataType>BOOL</DataType></Entry>\n        </RxPdo>\n        <RxPdo Fixed=\"1\" Mandatory=\"1\" Sm=\"0\">\n          <Index>#x1601</Index>",
        "<Name>Output</Name><DataType>BOOLEAN9</DataType></Entry>\n        </RxPdo>\n        <RxPdo Fixed=\"1\" Mandatory=\"1\" Sm=\"0\">\n          <Index>#x1601</Index>",
    );
    let f = EsiFile::parse(&text).expect("the device still loads");
    let dev = f.device(Some("EL2004"), None).expect("EL2004");
    let line = line_of(&text, "BOOLEAN9");
    let w: Vec<String> = ecat_twin::warnings(dev)
        .expect("warnings")
        .iter()
        .map(ToString::to_string)
        .collect();
    assert_eq!(
        w,
        [format!(
            "<DataType> at line {line}: PDO entry 0x7000:01: unknown data type 'BOOLEAN9': typed by its 1 bits"
        )]
    );
    ecat_twin::twin(dev, None, InputRule::Hold).expect("the twin starts");
}

#[test]
fn a_pdo_entry_without_a_dictionary_object_loads_and_the_twin_starts() {
    let text = broken(
        "<GroupType>DigOut</GroupType>\n        <Fmmu>Outputs</Fmmu>\n        <Sm ControlByte=\"#x44\" StartAddress=\"#x0f00\" Enable=\"1\" OpOnly=\"1\">",
        "<GroupType>DigOut</GroupType>\n        <Profile><Dictionary><Objects><Object><Index>#x7000</Index><Name>Ch 1</Name><Type>BOOL</Type><BitSize>1</BitSize></Object></Objects></Dictionary></Profile>\n        <Fmmu>Outputs</Fmmu>\n        <Sm ControlByte=\"#x44\" StartAddress=\"#x0f00\" Enable=\"1\" OpOnly=\"1\">",
    );
    // The first entry maps 0x7000:01; the dictionary has only 0x7000:00.
    let f = EsiFile::parse(&text).expect("loads");
    let dev = f.device(Some("EL2004"), None).expect("EL2004");
    ecat_twin::twin(dev, None, InputRule::Hold).expect("the twin starts");
}

#[test]
fn an_sm_smaller_than_its_pdos_is_a_warning_and_the_pdos_size_it() {
    // Four 1-bit PDOs fit one byte; make the EL2828's 8 need 2 bytes.
    let text = broken(
        "<Entry><Index>#x7070</Index><SubIndex>1</SubIndex><BitLen>1</BitLen>",
        "<Entry><Index>#x7070</Index><SubIndex>1</SubIndex><BitLen>2</BitLen>",
    );
    let text = text.replacen(
        "<DataType>BOOL</DataType></Entry></RxPdo>\n      </Device>",
        "<DataType>BIT2</DataType></Entry></RxPdo>\n      </Device>",
        1,
    );
    let f = EsiFile::parse(&text).expect("loads");
    let dev = f.device(Some("EL2828"), None).expect("EL2828");
    let line = line_of(&text, "DefaultSize=\"1\"");
    assert_eq!(
        dev.warnings
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>(),
        [format!(
            "<Sm> at line {line}: SM0 DefaultSize 1 bytes is smaller than the 2 bytes of the PDOs assigned to it: 2 assumed"
        )]
    );
}

#[test]
fn pam_slave_refuses_a_broken_esi_before_serving_with_exit_2() {
    let Some(bin) = crate::common::runner_binary() else {
        return crate::common::skip("pam-slave binary not built next to the test binary");
    };
    let dir = std::env::temp_dir().join(format!("twin-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let bad = dir.join("bad.xml");
    let text = broken("ProductCode=\"#x07d43052\"", "ProductCode=\"#xZZ\"");
    std::fs::write(&bad, &text).expect("write");
    // No --dry-run: it must stop before opening the (missing) interface.
    let out = std::process::Command::new(&bin)
        .args(["--iface", "no-such-if0", "--esi"])
        .arg(&bad)
        .args(["--type", "EL2004"])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    let line = line_of(&text, "#xZZ");
    assert!(
        err.contains(&format!("<Type> at line {line}: bad ProductCode '#xZZ'")),
        "{err}"
    );
    assert!(err.contains("bad.xml"), "names the file: {err}");
    // An ENI slave no device matches: listed, nothing starts.
    let eni = dir.join("eni.xml");
    std::fs::write(
        &eni,
        std::fs::read_to_string(testdata("machine.xml"))
            .expect("ENI")
            .replace(
                "<ProductCode>66072658</ProductCode>",
                "<ProductCode>99</ProductCode>",
            ),
    )
    .expect("write");
    let out = std::process::Command::new(&bin)
        .args(["--iface", "no-such-if0", "--eni"])
        .arg(&eni)
        .arg("--esi-dir")
        .arg(testdata("esi"))
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no device for slave 3 'Term 4 (EL1008)'"),
        "{err}"
    );
    assert!(err.contains("product 0x00000063"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Everything SDO Information reports of the first slave of `slaves`: the
/// object list, every object's description and every entry's with its
/// unit, default, minimum and maximum.
fn sdo_information(
    slaves: Vec<Box<dyn ecat_sim::chain::LineSlave>>,
    layout: ecat_slave::device::MemoryLayout,
) -> Vec<String> {
    use master_test::mailbox::{MailboxClient, MailboxGeometry};
    use master_test::sdo_info::{entry_description, object_description, od_list};
    smol::block_on(async {
        let bus = VirtualBus::with_chain(Chain::with_slaves(slaves), Clock::simulated(), None)
            .expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let mut out = vec![format!(
            "{} {:?} alias {}",
            sd.name(),
            sd.identity(),
            sd.alias_address()
        )];
        let mut c = MailboxClient::new(md, sd.configured_address(), MailboxGeometry::of(&layout));
        for index in od_list(&mut c, 1).await.expect("OD list") {
            let o = object_description(&mut c, index).await.expect("object");
            out.push(format!("{o:?}"));
            for sub in 0..=o.max_sub {
                match entry_description(&mut c, index, sub, 0x78).await {
                    Ok(e) => out.push(format!("{e:?}")),
                    Err(e) => out.push(format!("{index:#06x}:{sub} {e}")),
                }
            }
        }
        out
    })
}

#[test]
fn our_devices_generated_esi_loaded_as_twins_give_the_same_sii_and_sdo_information() {
    for key in ["pam", "io8"] {
        let entry = device_catalog::find(key).expect("catalog device");
        let dev = entry.description;
        let xml = ecat_esi::generate(dev).expect("ESI");
        let file =
            EsiFile::parse(std::str::from_utf8(&xml).expect("utf-8")).expect("our ESI loads");
        let esi_dev = file.device(None, None).expect("one device");
        let (desc, layout) = ecat_twin::coe_twin::describe(esi_dev).expect("description");
        assert_eq!(layout, dev.layout(), "{key}: memory layout");
        let twin = ecat_twin::twin(esi_dev, None, InputRule::Hold).expect("twin");
        let ours = inspect(twin.esc().sii()).expect("twin SII");
        let real = inspect(&dev.sii_image()).expect("device SII");
        assert_eq!(visible(&ours), visible(&real), "{key}: SII");
        assert_eq!(
            desc.dictionary.entry_count(),
            dev.dictionary.entry_count(),
            "{key}: dictionary size"
        );
        let want = sdo_information(
            vec![(entry.make)(device_catalog::Pdi::Direct)],
            dev.layout(),
        );
        let got = sdo_information(vec![twin], layout);
        assert!(want.len() > 20, "{key}: {} lines", want.len());
        for (k, (w, g)) in want.iter().zip(&got).enumerate() {
            assert_eq!(g, w, "{key}: SDO Information line {k}");
        }
        assert_eq!(got.len(), want.len(), "{key}: SDO Information length");
    }
}

#[test]
fn a_modular_devices_generated_esi_as_a_twin_reports_what_the_device_does() {
    // The DMA-22 node's ESI (<Slots> and <Modules>): the twin plugs each
    // slot's default module (5), like the catalog's dma22x5.
    let entry = device_catalog::find("dma22x5").expect("catalog device");
    let dev = entry.description;
    let xml = ecat_esi::generate(dev).expect("ESI");
    let file = EsiFile::parse(std::str::from_utf8(&xml).expect("utf-8")).expect("parses");
    let esi_dev = file.device(None, None).expect("device");
    assert_eq!(
        ecat_twin::coe_twin::default_modules(esi_dev),
        [0x0022_0001; 5]
    );
    let (desc, layout) = ecat_twin::coe_twin::describe(esi_dev).expect("description");
    let m = desc.modules.expect("modular");
    assert_eq!((m.slots, m.index_distance, m.pdo_increment), (5, 0x10, 1));
    assert_eq!(desc.dictionary.entry_count(), dev.dictionary.entry_count());
    let twin = ecat_twin::twin(esi_dev, None, InputRule::Hold).expect("twin");
    let want = sdo_information(
        vec![(entry.make)(device_catalog::Pdi::Direct)],
        dev.layout(),
    );
    let got = sdo_information(vec![twin], layout);
    assert!(want.len() > 1000, "{} lines", want.len());
    for (k, (w, g)) in want.iter().zip(&got).enumerate() {
        assert_eq!(g, w, "dma22x5: SDO Information line {k}");
    }
    assert_eq!(got.len(), want.len());
}

#[test]
fn a_twin_whose_esi_offers_no_sdo_information_nor_complete_access_refuses_both() {
    // The IO8's ESI with `SdoInfo` and `CompleteAccess` cleared: the twin's
    // SII says so, and the core refuses what the description does not
    // offer instead of serving it anyway.
    let edited = crate::common::io8_esi_without_sdo_info_nor_complete_access();
    let file = EsiFile::parse(&edited).expect("parses");
    let dev = file.device(None, None).expect("device");
    let twin = ecat_twin::twin(dev, None, InputRule::Hold).expect("twin");
    let general = inspect(twin.esc().sii())
        .expect("SII")
        .general
        .expect("General");
    assert_eq!(general.0.coe_details & 0x22, 0, "SII: no SDO Info, no CA");
    smol::block_on(async {
        use master_test::mailbox::{ClientError, MailboxClient, MailboxGeometry};
        use master_test::sdo_info::od_list;
        let bus = VirtualBus::with_chain(Chain::with_slaves(vec![twin]), Clock::simulated(), None)
            .expect("bus");
        let md = &*bus.maindevice;
        let station = {
            let group = bus.init().await.expect("init");
            group.subdevice(md, 0).expect("slave").configured_address()
        };
        let geometry = MailboxGeometry::of(&io8_example::DEVICE.layout());
        let mut c = MailboxClient::new(md, station, geometry);
        match od_list(&mut c, 1).await {
            Err(ClientError::Mailbox(code)) => assert_eq!(u16::from(code), 0x0004),
            other => panic!("SDO Information answered: {other:?}"),
        }
        match c.sdo_upload(0x1018, 1, true).await {
            Err(ClientError::Abort { code, .. }) => assert_eq!(u32::from(code), 0x0601_0000),
            other => panic!("complete access answered: {other:?}"),
        }
        let vendor = c.sdo_upload(0x1018, 1, false).await.expect("0x1018:01");
        assert_eq!(vendor, io8_example::DEVICE.identity.vendor_id.to_le_bytes());
    });
}

#[test]
fn a_coe_device_whose_esi_has_no_dictionary_gets_one_from_its_pdos_and_runs() {
    // The IO8's ESI with its <Dictionary> removed (a <ChannelInfo>-only
    // shape): the twin makes 0x1000, 0x1018, the PDO mapping and
    // assignment objects and the mapped objects from the PDOs.
    let xml =
        String::from_utf8(ecat_esi::generate(&io8_example::DEVICE).expect("ESI")).expect("utf-8");
    let (a, b) = (
        xml.find("<Dictionary>").expect("dict"),
        xml.find("</Dictionary>").expect("end"),
    );
    let stripped = format!(
        "{}<ChannelInfo><ProfileNo>5001</ProfileNo></ChannelInfo>{}",
        &xml[..a],
        &xml[b + "</Dictionary>".len()..]
    );
    let file = EsiFile::parse(&stripped).expect("parses");
    let dev = file.device(None, None).expect("device");
    let twin = ecat_twin::twin(dev, None, InputRule::Loopback).expect("twin");
    let od = twin.od();
    let indices: Vec<u16> = od.dictionary().objects().iter().map(|o| o.index).collect();
    assert_eq!(
        indices,
        [
            0x1000, 0x1018, 0x1600, 0x1A00, 0x1C00, 0x1C12, 0x1C13, 0x6000, 0x7000
        ]
    );
    assert_eq!(od.get(0x1000, 0), Some(5001));
    smol::block_on(async {
        use master_test::mailbox::{MailboxClient, MailboxGeometry};
        let bus = VirtualBus::with_chain(Chain::with_slaves(vec![twin]), Clock::simulated(), None)
            .expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        assert_eq!(sd.name(), "IO8");
        let mut c = MailboxClient::new(
            md,
            sd.configured_address(),
            MailboxGeometry::of(&io8_example::DEVICE.layout()),
        );
        let product = c.sdo_upload(0x1018, 2, false).await.expect("0x1018:02");
        assert_eq!(
            product,
            io8_example::DEVICE.identity.product_code.to_le_bytes()
        );
        let group = group.into_op(md).await.expect("OP");
        let sd = group.subdevice(md, 0).expect("slave");
        assert_eq!((sd.outputs_raw().len(), sd.inputs_raw().len()), (1, 1));
        sd.outputs_raw_mut()[0] = 0x3C;
        for _ in 0..5 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("tx_rx");
        }
        let inputs = group.subdevice(md, 0).expect("slave").inputs_raw().to_vec();
        assert_eq!(
            inputs,
            [0x3C],
            "loopback of the 8 BOOL outputs into the 8 BOOL inputs"
        );
    });
}

#[test]
fn an_eni_configuring_three_modules_gets_a_modular_twin_holding_three_and_ethercrab_runs_it() {
    // The DMA-22 node's ESI under another product code (so the catalog's
    // node does not claim the slave), in an ENI whose CoE init commands
    // write 0xF030 with three modules, as TwinCAT does for this machine.
    const PRODUCT: u32 = 0x0022_00FF;
    const IDENT: u32 = 0x0022_0001;
    let dev = &hcs_dma22::DEVICE;
    let esi = String::from_utf8(ecat_esi::generate(dev).expect("ESI"))
        .expect("utf-8")
        .replace(
            &format!("ProductCode=\"#x{:08X}\"", dev.identity.product_code),
            &format!("ProductCode=\"#x{PRODUCT:08X}\""),
        );
    let dir = std::env::temp_dir().join(format!("twin-modular-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("esi")).expect("dir");
    std::fs::write(dir.join("esi/DMA22.xml"), esi).expect("write");
    let cmd = |sub: u8, data: &str| {
        format!(
            "<InitCmd><Transition>PS</Transition><Ccs>1</Ccs><Index>#xf030</Index><SubIndex>{sub}</SubIndex><Data>{data}</Data></InitCmd>"
        )
    };
    let ident = hex_le(IDENT);
    let eni = format!(
        r##"<EtherCATConfig><Config><Slave><Info><Name>Node</Name><PhysAddr>1001</PhysAddr>
<VendorId>{}</VendorId><ProductCode>{PRODUCT}</ProductCode><RevisionNo>{}</RevisionNo></Info>
<Mailbox><CoE><InitCmds>{}{}{}{}</InitCmds></CoE></Mailbox></Slave></Config></EtherCATConfig>"##,
        dev.identity.vendor_id,
        dev.identity.revision,
        cmd(1, &ident),
        cmd(2, &ident),
        cmd(3, &ident),
        cmd(0, "03"),
    );
    std::fs::write(dir.join("eni.xml"), eni).expect("write");
    let line = twins::from_eni(
        &dir.join("eni.xml"),
        Some(&dir.join("esi")),
        &ecat_twin::InputRules::default(),
    )
    .expect("line");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(
        line.slaves[0].od().get(0xF050, 0),
        Some(3),
        "three modules detected"
    );
    smol::block_on(async {
        let bus = VirtualBus::with_chain(Chain::with_slaves(line.slaves), Clock::simulated(), None)
            .expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        for k in 1..=3u8 {
            sd.sdo_write(0xF030, k, IDENT).await.expect("0xF030 entry");
        }
        sd.sdo_write(0xF030, 0, 3u8).await.expect("0xF030 count");
        let group = group
            .into_op(md)
            .await
            .expect("OP with the ENI's module list");
        let sd = group.subdevice(md, 0).expect("slave");
        assert_eq!(
            (sd.outputs_raw().len(), sd.inputs_raw().len()),
            (15, 18),
            "3 modules' PDOs"
        );
    });
}

/// Little-endian hex of a u32, as ENI `Data` writes it.
fn hex_le(v: u32) -> String {
    v.to_le_bytes().iter().map(|b| format!("{b:02x}")).collect()
}
