//! Firmware update over FoE in BOOT (manual 5.10) through ethercrab's
//! register access and the test master's FoE client.

use master_test::VirtualBus;
use master_test::foe::{self, enter_boot, request_state};
use master_test::link::lock;
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use pam_199_p_etc::{PRODUCT_CODE, VENDOR_ID};

/// A `.efw` image of `len` payload bytes with `version` for `product`.
fn image(len: usize, version: &str, product: u32) -> Vec<u8> {
    let payload: Vec<u8> = (0..len).map(|i| (i * 7 + i / 251) as u8).collect();
    foe::efw_image(VENDOR_ID, product, version, &payload)
}

/// Software version after a power cycle, read over SDO by a fresh master.
async fn version_after_power_cycle(bus: &VirtualBus) -> String {
    let booted = lock(&bus.chain).power_cycle(0).expect("slave 0");
    let md = &*bus.maindevice;
    let group = bus.init().await.expect("init after power cycle");
    let sd = group.subdevice(md, 0).expect("slave");
    let v: heapless::String<32> = sd.sdo_read(0x100A, 0).await.expect("0x100A");
    assert_eq!(v.as_str(), booted);
    booted
}

async fn boot_client(bus: &VirtualBus) -> (MailboxClient<'_>, u16) {
    let md = &*bus.maindevice;
    let group = bus.init().await.expect("init");
    let station = group.subdevice(md, 0).expect("slave").configured_address();
    enter_boot(md, station).await.expect("BOOT");
    (
        MailboxClient::new(md, station, MailboxGeometry::bootstrap()),
        station,
    )
}

#[test]
fn a_1_mib_image_downloaded_in_boot_runs_after_init_and_a_power_cycle() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (mut c, station) = boot_client(&bus).await;
        let img = image(1024 * 1024, "11", PRODUCT_CODE);
        let mut last = 0;
        foe::write(&mut c, "pam-199-p-etc.efw", 0, &img, |done, total| {
            assert!(done >= last && done <= total);
            last = done;
        })
        .await
        .expect("download");
        assert_eq!(last, img.len());
        let info = foe::read(&mut c, "info.txt", 0).await.expect("info file");
        assert!(
            String::from_utf8_lossy(&info).contains("version=10"),
            "still running 10 until INIT + power cycle"
        );
        request_state(&bus.maindevice, station, 0x01)
            .await
            .expect("BOOT -> INIT");
        assert_eq!(version_after_power_cycle(&bus).await, "11");
    });
}

async fn refused(img: &[u8], password: u32, want: u32) {
    let bus = VirtualBus::new(1).expect("bus");
    let (mut c, station) = boot_client(&bus).await;
    let e = foe::write(&mut c, "pam-199-p-etc.efw", password, img, |_, _| {})
        .await
        .expect_err("refused");
    assert_eq!(e.foe_code(), Some(want), "{e}");
    request_state(&bus.maindevice, station, 0x01)
        .await
        .expect("INIT");
    assert_eq!(
        version_after_power_cycle(&bus).await,
        "10",
        "old firmware still runs"
    );
}

#[test]
fn wrong_password_is_refused_with_0x800a() {
    smol::block_on(refused(&image(4000, "11", PRODUCT_CODE), 0x1234, 0x800A));
}

#[test]
fn wrong_product_code_is_refused_and_the_old_firmware_stays() {
    smol::block_on(refused(&image(4000, "11", 0x0BAD_0001), 0, 0x800D));
}

#[test]
fn bad_crc_is_refused_and_the_old_firmware_stays() {
    let mut img = image(5000, "11", PRODUCT_CODE);
    let last = img.len() - 1;
    img[last] ^= 0xFF;
    smol::block_on(refused(&img, 0, 0x800C));
}

#[test]
fn a_transfer_the_master_abandons_or_a_power_cut_leaves_the_old_firmware() {
    smol::block_on(async {
        // Master stops halfway, then INIT and a power cycle.
        let bus = VirtualBus::new(1).expect("bus");
        let (mut c, station) = boot_client(&bus).await;
        let img = image(200_000, "11", PRODUCT_CODE);
        foe::write_partial(
            &mut c,
            "pam-199-p-etc.efw",
            0,
            &img,
            100_000,
            &mut |_, _| {},
        )
        .await
        .expect("first half");
        request_state(&bus.maindevice, station, 0x01)
            .await
            .expect("INIT");
        assert_eq!(version_after_power_cycle(&bus).await, "10");

        // Power cut in the middle of the transfer.
        let bus = VirtualBus::new(1).expect("bus");
        let (mut c, _) = boot_client(&bus).await;
        foe::write_partial(&mut c, "pam-199-p-etc.efw", 0, &img, 60_000, &mut |_, _| {})
            .await
            .expect("part");
        assert_eq!(version_after_power_cycle(&bus).await, "10");
    });
}

#[test]
fn foe_write_in_preop_is_refused_with_bootstrap_only() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        let mut c = MailboxClient::new(md, station, MailboxGeometry::standard());
        let e = foe::write(
            &mut c,
            "pam-199-p-etc.efw",
            0,
            &image(1000, "11", PRODUCT_CODE),
            |_, _| {},
        )
        .await
        .expect_err("not in BOOT");
        assert_eq!(e.foe_code(), Some(0x8008));
        let info = foe::read(&mut c, "info.txt", 0)
            .await
            .expect("reading the info file works in PRE-OP");
        assert!(
            String::from_utf8_lossy(&info).contains("product_code=0x00c703f3")
                || String::from_utf8_lossy(&info).contains("0x00C703F3")
        );
    });
}

#[test]
fn the_owner_sets_a_foe_password_that_survives_a_power_cycle() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (mut c, station) = boot_client(&bus).await;
        let e = foe::set_password(&mut c, 0x1234, 0xBEEF)
            .await
            .expect_err("only with the current password");
        assert_eq!(e.foe_code(), Some(0x800A), "{e}");
        foe::set_password(&mut c, 0, 0xBEEF)
            .await
            .expect("set with the factory password");
        request_state(&bus.maindevice, station, 0x01)
            .await
            .expect("INIT");
        assert_eq!(version_after_power_cycle(&bus).await, "10");
        let (mut c, station) = boot_client(&bus).await;
        let img = image(3000, "11", PRODUCT_CODE);
        let e = foe::write(&mut c, "pam-199-p-etc.efw", 0, &img, |_, _| {})
            .await
            .expect_err("the factory password no longer works");
        assert_eq!(e.foe_code(), Some(0x800A), "{e}");
        foe::write(&mut c, "pam-199-p-etc.efw", 0xBEEF, &img, |_, _| {})
            .await
            .expect("the owner's password works");
        request_state(&bus.maindevice, station, 0x01)
            .await
            .expect("INIT");
        assert_eq!(version_after_power_cycle(&bus).await, "11");
    });
}

#[test]
fn a_downgrade_is_refused_by_the_slave_with_0x8002_unless_the_owner_allows_it() {
    smol::block_on(async {
        // The slave runs 10 (factory); 9 is older.
        refused(&image(4000, "9", PRODUCT_CODE), 0, 0x8002).await;
        let bus = VirtualBus::new(1).expect("bus");
        let (mut c, station) = boot_client(&bus).await;
        let img = image(4000, "9", PRODUCT_CODE);
        foe::write(&mut c, "pam-199-p-etc.downgrade.efw", 0, &img, |_, _| {})
            .await
            .expect("the owner's explicit downgrade");
        request_state(&bus.maindevice, station, 0x01)
            .await
            .expect("INIT");
        assert_eq!(version_after_power_cycle(&bus).await, "9");
        // 9 is now the floor: 9.1 is an upgrade without any consent.
        let (mut c, station) = boot_client(&bus).await;
        foe::write(
            &mut c,
            "pam-199-p-etc.efw",
            0,
            &image(4000, "9.1", PRODUCT_CODE),
            |_, _| {},
        )
        .await
        .expect("upgrade from the downgraded version");
        request_state(&bus.maindevice, station, 0x01)
            .await
            .expect("INIT");
        assert_eq!(version_after_power_cycle(&bus).await, "9.1");
    });
}
