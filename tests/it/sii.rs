//! The SII image: CRC, identity and name through our reader and ethercrab.

use master_test::VirtualBus;
use pam_slave::sii::SiiReader;

#[test]
fn sii_image_passes_crc_and_agrees_with_ethercrab() {
    let image = pam_slave::device::sii_image();
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
