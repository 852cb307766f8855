//! The HCS DMA-22(A) node, a modular device (ETG.5001), driven by
//! ethercrab: configured module list, module PDOs, the manual's CMD 15
//! example as process data, and the refusals a master expects.

use crate::common::{Md, abort_code, request, status};
use hcs_dma22::telegram::semantics::status as hcs_status;
use hcs_dma22::telegram::{ModuleOutput, MultiWriteResponse, RequestRepr, ResponseRepr};
use hcs_dma22::{MODULE_IDENT, description::od as dma_od};
use master_test::VirtualBus;
use master_test::link::Clock;

/// 000 5.4.2: the master writes 1.000 V, 2.000 V and -3.000 V to modules
/// 1, 2 and 3 (mode 3) ...
const REQUEST_5_4_2: [u8; 18] = [
    0x23, 0x03, 0x0F, // TADR, SNUM, CMD
    0x00, 0x03, 0xE8, 0x00, 0x00, // module 1
    0x00, 0x07, 0xD0, 0x00, 0x00, // module 2
    0x00, 0xF4, 0x48, 0x00, 0x00, // module 3
];
/// ... and the node answers module by module (TADR 0x23, 0x24, 0x25).
const RESPONSES_5_4_2: [[u8; 9]; 3] = [
    [0x23, 0x01, 0x0F, 0x40, 0x00, 0x00, 0x00, 0x03, 0xE8],
    [0x24, 0x02, 0x0F, 0x40, 0x00, 0x00, 0x00, 0x07, 0xD0],
    [0x25, 0x03, 0x0F, 0x40, 0x00, 0x00, 0x00, 0xF4, 0x48],
];

/// Writes the configured module list 0xF030 the way TwinCAT's init
/// commands do: the entries, then the count.
macro_rules! configure {
    ($sd:expr, $idents:expr) => {{
        let idents: &[u32] = $idents;
        for (k, id) in idents.iter().enumerate() {
            $sd.sdo_write(0xF030, k as u8 + 1, *id)
                .await
                .expect("0xF030 entry");
        }
        $sd.sdo_write(0xF030, 0, idents.len() as u8)
            .await
            .expect("0xF030 count");
    }};
}

#[test]
fn ethercrab_runs_the_manual_5_4_2_example_on_three_modules_after_writing_0xf030() {
    smol::block_on(async {
        let bus = VirtualBus::line("dma22", Clock::frames()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("node");
        assert_eq!(sd.name(), "DMA-22(A)-ECAT");
        let detected: u8 = sd.sdo_read(0xF050, 0).await.expect("0xF050:00");
        assert_eq!(detected, 3);
        configure!(sd, &[MODULE_IDENT; 3]);
        let group = master_test::into_op_cyclic(group, md, std::time::Duration::from_millis(2))
            .await
            .expect("OP");
        let sd = group.subdevice(md, 0).expect("node");
        // Three module PDOs each way: 5 bytes out (control, PV1, PV2) and
        // 6 bytes in (status, value 1, value 2) per module.
        assert_eq!((sd.outputs_raw().len(), sd.inputs_raw().len()), (15, 18));
        let RequestRepr::MultiWrite(req) = RequestRepr::parse(&REQUEST_5_4_2).expect("5.4.2")
        else {
            panic!("a CMD 15");
        };
        // The CMD 15 module blocks become the module PDOs (CoE: LE).
        {
            let mut out = sd.outputs_raw_mut();
            for (k, m) in req.modules().iter().enumerate() {
                let b = &mut out[5 * k..5 * k + 5];
                b[0] = m.control;
                b[1..3].copy_from_slice(&m.value1.to_le_bytes());
                b[3..5].copy_from_slice(&m.value2.to_le_bytes());
            }
        }
        for _ in 0..10 {
            group.tx_rx(md).await.expect("cycle");
            smol::Timer::after(std::time::Duration::from_millis(2)).await;
        }
        // (ethercrab's PDI guards are spin locks: copy, do not hold.)
        let inp = sd.inputs_raw().to_vec();
        for (k, want) in RESPONSES_5_4_2.iter().enumerate() {
            let b = &inp[6 * k..6 * k + 6];
            let answer = MultiWriteResponse {
                tadr: want[0],
                sadr: k as u8 + 1,
                status: u16::from_le_bytes([b[0], b[1]]),
                value1: i16::from_le_bytes([b[2], b[3]]),
                value2: i16::from_le_bytes([b[4], b[5]]),
            };
            let mut bytes = [0u8; 9];
            ResponseRepr::MultiWrite(answer)
                .emit(&mut bytes)
                .expect("emit");
            // The example prints HW enable as 0x40 in DAT.1H, the mode
            // tables as 0x04 (NOTES.md 21): the node follows the tables.
            assert_eq!(answer.status, hcs_status::HW_ENABLE, "module {}", k + 1);
            let mut expected = *want;
            expected[3] = 0x04;
            assert_eq!(bytes, expected, "module {} answers as in 5.4.2", k + 1);
        }
        // The same values as parameters: A1.01 and d1.10 of each module.
        for (k, sv) in [1000i16, 2000, -3000].into_iter().enumerate() {
            let (i, s) = dma_od::parameter(k as u8, 0x0A).unwrap();
            let d110: i16 = sd.sdo_read(i, s).await.expect("d1.10");
            assert_eq!(d110, sv, "module {} d1.10", k + 1);
        }
        // BUS_DISABLE on module 2: its output drops, the others run on.
        sd.outputs_raw_mut()[5] = 0x80;
        for _ in 0..5 {
            group.tx_rx(md).await.expect("cycle");
        }
        let inp = sd.inputs_raw().to_vec();
        let st2 = u16::from_le_bytes([inp[6], inp[7]]);
        assert_eq!(st2, hcs_status::HW_ENABLE | hcs_status::BUS_DISABLE);
        assert_eq!(i16::from_le_bytes([inp[10], inp[11]]), 0, "module 2 off");
        assert_eq!(i16::from_le_bytes([inp[4], inp[5]]), 1000, "module 1 on");
        let _ = ModuleOutput::default();
    });
}

#[test]
fn a_configured_module_list_that_differs_is_refused_with_al_status_0x0070() {
    smol::block_on(async {
        let bus = VirtualBus::line("dma22", Clock::frames()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("node");
        let station = sd.configured_address();
        // An ident the node does not know is refused at the write.
        let e = sd
            .sdo_write(0xF030, 1, 0x1234_5678u32)
            .await
            .expect_err("unknown module");
        assert_eq!(abort_code(&e), Some(0x0609_0030));
        // Two modules configured, three detected.
        configure!(sd, &[MODULE_IDENT; 2]);
        let group = group.into_pre_op_pdi(md).await.expect("SMs and FMMUs");
        assert_eq!(
            request(md, station, 0x04).await,
            (0x12, 0x0070),
            "PRE-OP + error, configured and detected lists differ"
        );
        let (_, code) = status(md, station).await;
        assert_eq!(code, 0x0070);
        drop(group);
    });
}

#[test]
fn objects_and_pdos_of_empty_slots_do_not_exist() {
    smol::block_on(async {
        let bus = VirtualBus::line("dma22", Clock::frames()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("node");
        // Slot 3 (module 3) exists, slot 4 does not.
        let _: u16 = sd.sdo_read(0x6020, 1).await.expect("module 3 status");
        for index in [0x6030u16, 0x7040, 0x8031, 0xA030, 0x1603] {
            let e = sd.sdo_read::<u8>(index, 0).await.expect_err("empty slot");
            assert_eq!(abort_code(&e), Some(0x0602_0000), "{index:#06x}");
        }
        // Assigning the PDO of an empty slot is refused at the write.
        let e = sd
            .sdo_write(0x1C12, 3, 0x1603u16)
            .await
            .expect_err("empty slot's PDO");
        assert_eq!(abort_code(&e), Some(0x0609_0030));
        drop(group);
    });
}

#[test]
fn the_dma22_esi_describes_slots_and_modules() {
    let xml = ecat_esi::generate(&hcs_dma22::DEVICE).expect("ESI");
    let text = std::str::from_utf8(&xml).unwrap();
    let doc = ecat_esi::xml::parse(text).expect("parse");
    let slots = doc
        .path("Descriptions/Devices/Device/Slots")
        .expect("Slots");
    assert_eq!(slots.children_named("Slot").count(), 5);
    assert_eq!(slots.attr("SlotIndexIncrement"), Some("#x10"));
    let module = doc.path("Descriptions/Modules/Module").expect("Module");
    assert_eq!(
        module.path("Type").and_then(|t| t.attr("ModuleIdent")),
        Some("#x00220001")
    );
    let objects = module
        .path("Profile/Dictionary/Objects")
        .expect("module objects");
    let names: Vec<&str> = objects
        .children_named("Object")
        .filter_map(|o| o.text_at("Index"))
        .collect();
    assert_eq!(
        names,
        [
            "#x1600", "#x1A00", "#x6000", "#x7000", "#x8000", "#x8001", "#xA000"
        ]
    );
    // The device's own dictionary holds no module object.
    let own = doc
        .path("Descriptions/Devices/Device/Profile/Dictionary/Objects")
        .unwrap();
    assert!(
        own.children_named("Object")
            .filter_map(|o| o.text_at("Index"))
            .all(|i| !i.starts_with("#x6") && !i.starts_with("#x7") && !i.starts_with("#x8"))
    );
    // Its schema validation: `shared::every_catalog_devices_generated_esi_validates_against_the_etg_schema`.
}

/// Writes `telegram` into the node's request object (complete access from
/// subindex 1: length, bytes) and reads its answer.
async fn exchange(c: &mut master_test::mailbox::MailboxClient<'_>, telegram: &[u8]) -> Vec<u8> {
    let mut data = vec![telegram.len() as u8];
    data.extend_from_slice(telegram);
    data.resize(33, 0);
    c.sdo_download(0x2000, 1, true, &data)
        .await
        .expect("request");
    let a = c.sdo_upload(0x2001, 1, true).await.expect("response");
    a[1..1 + usize::from(a[0])].to_vec()
}

#[test]
fn hcs_telegrams_through_the_coe_channel_reach_the_module_parameters() {
    use master_test::mailbox::{MailboxClient, MailboxGeometry};
    smol::block_on(async {
        let bus = VirtualBus::line("dma22", Clock::frames()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let station = group.subdevice(md, 0).expect("node").configured_address();
        let layout = hcs_dma22::DEVICE.layout();
        let mut c = MailboxClient::new(md, station, MailboxGeometry::of(&layout));
        // Manual 6.3: read the software version of module 1.
        assert_eq!(
            exchange(&mut c, &[0x01, 0x01, 0x03, 0x00, 0x00, 0x00, 0x01]).await,
            [0x01, 0x01, 0x03, 0x02, 0x03, 0xE9]
        );
        // CMD 6: A1.01 of module 2 = 1.500 V, then the same parameter
        // over CoE (0x8010:20 = ID 0x1F of slot 1).
        let write = [0x02, 0x02, 0x06, 0x00, 0x1F, 0x05, 0xDC];
        assert_eq!(exchange(&mut c, &write).await, write);
        let v = c.sdo_upload(0x8010, 0x20, false).await.expect("A1.01");
        assert_eq!(i16::from_le_bytes([v[0], v[1]]), 1500);
        // The same request again is not answered (3.3).
        assert_eq!(exchange(&mut c, &write).await, [] as [u8; 0]);
        drop(group);
    });
}

#[test]
fn a_mixed_line_pam_dma22_io8_reaches_op_and_the_hw_enable_input_acts() {
    use hcs_dma22::Dma22Node;
    use master_test::link::lock;
    use std::time::Duration;
    smol::block_on(async {
        let bus = VirtualBus::line("pam,dma22x1,io8", Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let names: Vec<String> = group.iter(md).map(|s| s.name().to_string()).collect();
        assert_eq!(names, ["PAM-199-P-ETC", "DMA-22(A)-ECAT", "IO8"]);
        let sd = group.subdevice(md, 1).expect("node");
        configure!(sd, &[MODULE_IDENT]);
        let group = group.into_op(md).await.expect("OP");
        let sizes: Vec<(usize, usize)> = group
            .iter(md)
            .map(|s| (s.outputs_raw().len(), s.inputs_raw().len()))
            .collect();
        assert_eq!(sizes, [(5, 14), (5, 6), (1, 1)], "one module: 5 out, 6 in");
        let sd = group.subdevice(md, 1).expect("node");
        sd.outputs_raw_mut()[1..3].copy_from_slice(&2500i16.to_le_bytes());
        let cycle = async |n: usize| {
            for _ in 0..n {
                bus.clock.advance(Duration::from_millis(1));
                group.tx_rx(md).await.expect("cycle");
            }
        };
        cycle(5).await;
        let inp = sd.inputs_raw().to_vec();
        assert_eq!(
            (
                u16::from_le_bytes([inp[0], inp[1]]),
                i16::from_le_bytes([inp[4], inp[5]])
            ),
            (hcs_status::HW_ENABLE, 2500)
        );
        // The module's hardware enable input (X3/1) goes low: no enable,
        // no output, the control byte reset (5.5.1.2).
        lock(&bus.chain)
            .slave_mut::<Dma22Node<1>>(1)
            .expect("slave 1 is the node")
            .slave_mut()
            .app_mut()
            .module_mut(0)
            .expect("module 1")
            .hw_enable = false;
        cycle(5).await;
        let inp = sd.inputs_raw().to_vec();
        assert_eq!(
            (
                u16::from_le_bytes([inp[0], inp[1]]),
                i16::from_le_bytes([inp[4], inp[5]])
            ),
            (0, 0)
        );
    });
}
