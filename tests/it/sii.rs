//! The SII image: CRC, identity and name through our reader and ethercrab.

use ecat_slave::sii::SiiReader;
use master_test::VirtualBus;

#[test]
fn sii_image_passes_crc_and_agrees_with_ethercrab() {
    let image = pam_199_p_etc::DEVICE.sii_image();
    let r = SiiReader::new(&image).expect("image parses");
    assert!(r.crc_ok(), "header CRC-8 over bytes 0..14");
    let id = r.identity();
    assert_eq!(id.vendor_id, 0x0000_05AE);
    assert_eq!(id.product_code, 0x00C7_03F3);
    assert_eq!(id.revision, 7);
    let general = r.general().expect("general ok").expect("general present");
    let strings = r.strings().expect("strings ok");
    let name = strings.get(general.name_idx).expect("name string");
    assert_eq!(name, "PAM-199-P-ETC");

    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let eid = sd.identity();
        assert_eq!(
            (eid.vendor_id, eid.product_id, eid.revision, eid.serial),
            (id.vendor_id, id.product_code, id.revision, id.serial)
        );
        assert_eq!(sd.name(), name);
    });
}

#[test]
fn ethercrab_configures_the_mailbox_sms_exactly_as_our_reader_decodes_the_sii() {
    use ecat_slave::sii::SmType;
    let image = pam_199_p_etc::DEVICE.sii_image();
    let r = SiiReader::new(&image).expect("image parses");
    let sms: Vec<_> = r.sync_managers().expect("SyncM").collect();
    let mbx = r.standard_mailbox();
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        for (n, sm) in sms.iter().enumerate().take(2) {
            let regs: [u8; 8] = ethercrab::Command::fprd(station, 0x0800 + 8 * n as u16)
                .receive(md)
                .await
                .expect("SM registers");
            let start = u16::from_le_bytes([regs[0], regs[1]]);
            let len = u16::from_le_bytes([regs[2], regs[3]]);
            assert_eq!(start, sm.start, "SM{n} start");
            assert_eq!(regs[4], sm.control, "SM{n} control");
            assert_eq!(regs[6] & 1, 1, "SM{n} enabled");
            let (want_len, kind) = if n == 0 {
                (mbx.rx_size, SmType::MailboxOut)
            } else {
                (mbx.tx_size, SmType::MailboxIn)
            };
            assert_eq!(sm.sm_type, kind);
            assert_eq!(
                len, want_len,
                "SM{n} length = mailbox size from words 0x18-0x1B"
            );
        }
        assert_eq!((mbx.rx_offset, mbx.tx_offset), (sms[0].start, sms[1].start));
    });
}
