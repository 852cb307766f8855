//! SDO access through ethercrab's own CoE client.

use crate::common::abort_code;
use master_test::VirtualBus;

#[test]
fn sdo_reads_identity_and_writes_current_with_range_checks() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");

        let product: u32 = sd.sdo_read(0x1018, 2).await.expect("0x1018:02");
        assert_eq!(product, 0x00C7_03F3);

        sd.sdo_write(0x800D, 2, 2000u16)
            .await
            .expect("CURRENT = 2000");
        let current: u16 = sd.sdo_read(0x800D, 2).await.expect("read CURRENT");
        assert_eq!(current, 2000);

        let e = sd
            .sdo_write(0x800D, 2, 5000u16)
            .await
            .expect_err("5000 mA is above 3000");
        assert_eq!(abort_code(&e), Some(0x0609_0031));
        let current: u16 = sd.sdo_read(0x800D, 2).await.expect("read CURRENT");
        assert_eq!(current, 2000, "a refused write leaves the value");

        let e = sd
            .sdo_write(0x1018, 1, 1u32)
            .await
            .expect_err("identity is read-only");
        assert_eq!(abort_code(&e), Some(0x0601_0002));

        let e = sd
            .sdo_read::<u32>(0x1234, 0)
            .await
            .expect_err("no such object");
        assert_eq!(abort_code(&e), Some(0x0602_0000));
    });
}

#[test]
fn sdo_length_and_access_errors_carry_their_abort_codes() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");

        let e = sd
            .sdo_write(0x800D, 2, 1000u32)
            .await
            .expect_err("4 bytes into a UINT");
        assert_eq!(abort_code(&e), Some(0x0607_0012));
        let e = sd
            .sdo_write(0x8002, 2, 100u16)
            .await
            .expect_err("2 bytes into a UDINT");
        assert_eq!(abort_code(&e), Some(0x0607_0013));
        let e = sd
            .sdo_write(0x800D, 2, 100u16)
            .await
            .expect_err("below 500 mA");
        assert_eq!(abort_code(&e), Some(0x0609_0032));
        let e = sd
            .sdo_write(0xF800, 2, 9u8)
            .await
            .expect_err("not a FUNCTION value");
        assert_eq!(abort_code(&e), Some(0x0609_0030));
        let e = sd
            .sdo_read::<u32>(0xF801, 1)
            .await
            .expect_err("PASSWORD is write-only");
        assert_eq!(abort_code(&e), Some(0x0601_0001));
        let e = sd
            .sdo_read::<u16>(0x1018, 7)
            .await
            .expect_err("no subindex 7");
        assert_eq!(abort_code(&e), Some(0x0609_0011));
        let name: heapless::String<32> = sd.sdo_read(0x1008, 0).await.expect("device name");
        assert_eq!(name.as_str(), "PAM-199-P-ETC");
        // 0x10F8 timestamp counts while the slave runs (manual 7.2).
        let t1: u64 = sd.sdo_read(0x10F8, 0).await.expect("timestamp");
        smol::Timer::after(std::time::Duration::from_millis(5)).await;
        let t2: u64 = sd.sdo_read(0x10F8, 0).await.expect("timestamp");
        assert!(t2 > t1, "0x10F8 advances: {t1} then {t2}");
    });
}
