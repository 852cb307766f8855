//! The PAM-199-P-ETC's safety rules (docs/SAFETY.md) as a master would try
//! to break them with ethercrab: no solenoid current without cyclic
//! outputs under an armed SM watchdog, FUNCTION and the PDO assignment in
//! step through DEFAULT, LOADBACK and a power cycle, the vendor unlock
//! ended by INIT. Each test was written against a finding of the issue 29
//! review and failed before its fix.

use crate::common::{abort_code, request};
use master_test::VirtualBus;
use master_test::link::lock;
use pam_199_p_etc::Pam;
use pam_199_p_etc::board::Solenoid;
use std::time::Duration;

type Md = ethercrab::MainDevice<'static>;

/// Solenoid A and B set points of the PAM at `i`, mA.
fn setpoints(bus: &VirtualBus, i: usize) -> (u32, u32) {
    let chain = lock(&bus.chain);
    let stage = chain.slave::<Pam>(i).expect("a PAM").slave().app().stage();
    (
        u32::from(stage.setpoint_ma(Solenoid::A)),
        u32::from(stage.setpoint_ma(Solenoid::B)),
    )
}

/// Finding 1 (issue 29): with no RxPDO assigned there are no cyclic
/// outputs and no SM watchdog; ENABLE and a command value written over SDO
/// in OP must not drive the valve (before the fix: IA 477 mA after 3 s).
#[test]
fn sdo_written_outputs_without_cyclic_data_never_drive_the_solenoids() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("slave");
        sd.sdo_write(0x1C12, 0, 0u8).await.expect("no RxPDO");
        let group = group.into_safe_op(md).await.expect("SAFE-OP");
        let group = group.into_op(md).await.expect("OP without outputs");
        let sd = group.subdevice(md, 0).expect("slave");
        assert_eq!(sd.outputs_raw().len(), 0, "no output image");
        sd.sdo_write(0x7000, 1, 1u8).await.expect("ENABLE over SDO");
        sd.sdo_write(0x7000, 3, 5000i32)
            .await
            .expect("COMMAND over SDO");
        for _ in 0..3000 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("inputs");
        }
        let st = request(md, sd.configured_address(), 0x08).await;
        assert_eq!(st, (0x08, 0), "still OP: nothing was wrong");
        assert_eq!(setpoints(&bus, 0), (0, 0), "solenoids off");
        let ia: u16 = sd.sdo_read(0x6000, 6).await.expect("IA");
        assert_eq!(ia, 0, "IA");
    });
}

/// The same outputs over PDO (the master's cyclic data, SM watchdog
/// armed) do drive the valve: the rule does not switch off a healthy line.
#[test]
fn cyclic_outputs_under_the_sm_watchdog_drive_the_solenoids() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let group = group.into_op(md).await.expect("OP");
        let sd = group.subdevice(md, 0).expect("slave");
        {
            let mut out = sd.outputs_raw_mut();
            out[0] = 1;
            out[1..5].copy_from_slice(&5000i32.to_le_bytes());
        }
        for _ in 0..500 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("cycle");
        }
        assert!(setpoints(&bus, 0).0 > 0, "solenoid A driven");
        // The master disables the SM watchdog (0x0420 = 0): the PAM stops
        // driving, since nothing would switch it off if the master died.
        ethercrab::Command::fpwr(sd.configured_address(), 0x0420)
            .send(md, 0u16)
            .await
            .expect("0x0420");
        for _ in 0..200 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("cycle");
        }
        assert_eq!(setpoints(&bus, 0), (0, 0), "no watchdog, no current");
    });
}

/// Finding 2: DEFAULT (and LOADBACK) in OP must not change FUNCTION behind
/// the master (before the fix FUNCTION became 1 while 0x1C12:01 stayed
/// 0x1601 and the slave stayed in OP). In PRE-OP they may, and the
/// assignment follows.
#[test]
fn default_and_loadback_keep_function_and_assignment_in_step() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("slave");
        sd.sdo_write(0xF800, 2, 2u8).await.expect("FUNCTION = IND");
        // A LOADBACK source with FUNCTION = DIR (the default).
        sd.sdo_write(0xF800, 2, 1u8).await.expect("FUNCTION = DIR");
        sd.sdo_write(0xF801, 2, 1u32).await.expect("SAVE");
        sd.sdo_write(0xF800, 2, 2u8).await.expect("FUNCTION = IND");
        let a: u16 = sd.sdo_read(0x1C12, 1).await.expect("0x1C12:01");
        assert_eq!(a, 0x1601, "the independent set");
        let group = group.into_safe_op(md).await.expect("SAFE-OP");
        let group = group.into_op(md).await.expect("OP");
        let sd = group.subdevice(md, 0).expect("slave");
        for sub in [3u8, 4] {
            let e = sd
                .sdo_write(0xF801, sub, 1u32)
                .await
                .expect_err("would change FUNCTION in OP");
            assert_eq!(abort_code(&e), Some(0x0800_0022), "0xF801:{sub:02}");
            let f: u8 = sd.sdo_read(0xF800, 2).await.expect("FUNCTION");
            assert_eq!(f, 2, "FUNCTION unchanged after 0xF801:{sub:02}");
            let a: u16 = sd.sdo_read(0x1C12, 1).await.expect("0x1C12:01");
            assert_eq!(a, 0x1601);
        }
        group.tx_rx(md).await.expect("cycle");
        let st = request(md, sd.configured_address(), 0x08).await;
        assert_eq!(st, (0x08, 0), "OP, no error");
        let group = group.into_safe_op(md).await.expect("SAFE-OP");
        let group = group.into_pre_op(md).await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("slave");
        sd.sdo_write(0xF801, 3, 1u32)
            .await
            .expect("DEFAULT in PRE-OP");
        let f: u8 = sd.sdo_read(0xF800, 2).await.expect("FUNCTION");
        let a: u16 = sd.sdo_read(0x1C12, 1).await.expect("0x1C12:01");
        let t: u16 = sd.sdo_read(0x1C13, 1).await.expect("0x1C13:01");
        assert_eq!((f, a, t), (1, 0x1600, 0x1A00), "DIR with its set");
    });
}

/// Finding 2, second part: DEFAULT and LOADBACK leave the password-locked
/// manufacturer settings 0xF80F alone unless the password was given.
#[test]
fn default_and_loadback_do_not_touch_the_locked_manufacturer_settings() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("slave");
        let password = pam_199_p_etc::VENDOR_PASSWORD;
        sd.sdo_write(0xF801, 1, password).await.expect("unlock");
        sd.sdo_write(0xF80F, 1, 1234u16)
            .await
            .expect("manufacturer");
        sd.sdo_write(0xF801, 2, 1u32).await.expect("SAVE with 1234");
        sd.sdo_write(0xF80F, 1, 4321u16)
            .await
            .expect("manufacturer");
        sd.sdo_write(0xF801, 1, 0u32).await.expect("lock");
        bus.clock.advance(Duration::from_secs(2));
        for sub in [3u8, 4] {
            sd.sdo_write(0xF801, sub, 1u32).await.expect("command");
            let v: u16 = sd.sdo_read(0xF80F, 1).await.expect("0xF80F:01");
            assert_eq!(v, 4321, "0xF801:{sub:02} left 0xF80F:01 alone");
        }
        sd.sdo_write(0xF801, 1, password).await.expect("unlock");
        sd.sdo_write(0xF801, 4, 1u32).await.expect("LOADBACK");
        let v: u16 = sd.sdo_read(0xF80F, 1).await.expect("0xF80F:01");
        assert_eq!(v, 1234, "unlocked, LOADBACK restores it");
    });
}

/// Finding 3: a saved FUNCTION = IND comes back after a power cycle with
/// its PDO set (before the fix 0x1C12:01 was 0x1600 and SAFE-OP failed
/// with 0x001D until the master rewrote the assignment).
#[test]
fn a_saved_function_comes_back_with_its_pdo_set() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("slave");
        sd.sdo_write(0xF800, 2, 2u8).await.expect("FUNCTION = IND");
        sd.sdo_write(0xF801, 2, 1u32).await.expect("SAVE");
        drop(group);
        lock(&bus.chain).power_cycle(0);
        let group = bus.init().await.expect("PRE-OP after the power cycle");
        let sd = group.subdevice(md, 0).expect("slave");
        let f: u8 = sd.sdo_read(0xF800, 2).await.expect("FUNCTION");
        let a: u16 = sd.sdo_read(0x1C12, 1).await.expect("0x1C12:01");
        let t: u16 = sd.sdo_read(0x1C13, 1).await.expect("0x1C13:01");
        assert_eq!((f, a, t), (2, 0x1601, 0x1A01));
        group
            .into_safe_op(md)
            .await
            .expect("SAFE-OP with the saved set");
    });
}

/// Finding 8 (part): the vendor unlock ends at INIT, so the next master
/// session does not inherit it.
#[test]
fn the_vendor_unlock_ends_at_init() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("slave");
        let s = sd.configured_address();
        sd.sdo_write(0xF801, 1, pam_199_p_etc::VENDOR_PASSWORD)
            .await
            .expect("unlock");
        sd.sdo_write(0xF80F, 1, 7u16).await.expect("unlocked write");
        assert_eq!(request(md, s, 0x01).await.0, 0x01, "INIT");
        assert_eq!(request(md, s, 0x02).await.0, 0x02, "PRE-OP");
        let e = sd
            .sdo_write(0xF80F, 1, 8u16)
            .await
            .expect_err("locked again");
        assert_eq!(abort_code(&e), Some(0x0601_0000));
    });
}

/// With no RxPDO assigned SM2 is unused: disabled, or enabled with length
/// 0 as SOEM's config_map leaves an SM whose image is empty (an ESC does not
/// activate a SyncManager of length 0; SOES accepts it). Enabled with the
/// SII's length 5 it contradicts the empty image: 0x001D.
#[test]
fn an_unused_sm2_may_be_enabled_with_length_0_but_not_with_a_length() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let sd = group.subdevice(md, 0).expect("slave");
        let s = sd.configured_address();
        sd.sdo_write(0x1C12, 0, 0u8).await.expect("no RxPDO");
        // SM3 for the 14 input bytes, as any master sets it.
        ethercrab::Command::fpwr(s, 0x0818)
            .send(md, [0x80u8, 0x11, 14, 0, 0x20, 0x00, 0x01, 0x00])
            .await
            .expect("SM3");
        for (len, want) in [(0u16, (0x04, 0)), (5, (0x12, 0x001D))] {
            let l = len.to_le_bytes();
            let sm2 = [0x00, 0x11, l[0], l[1], 0x64, 0x00, 0x01, 0x00];
            ethercrab::Command::fpwr(s, 0x0810)
                .send(md, sm2)
                .await
                .expect("SM2");
            assert_eq!(request(md, s, 0x04).await, want, "SM2 length {len}");
            assert_eq!(request(md, s, 0x12).await.0, 0x02, "back to PRE-OP");
        }
    });
}

/// Found by invariant I1 (docs/SAFETY.md P2): in OP the cyclic outputs
/// own the entries the assigned RxPDO maps. An SDO write of ENABLE there
/// drove the valve until the next cycle overwrote it; it is refused with
/// 0x08000022 and the valve stays off. Unmapped outputs are still stored.
#[test]
fn an_sdo_write_of_a_mapped_output_in_op_is_refused() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        let group = group.into_op(md).await.expect("OP");
        let sd = group.subdevice(md, 0).expect("slave");
        {
            let mut out = sd.outputs_raw_mut();
            out[0] = 0; // ENABLE off
            out[1..5].copy_from_slice(&5000i32.to_le_bytes());
        }
        for _ in 0..50 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("cycle");
        }
        let e = sd
            .sdo_write(0x7000, 1, 1u8)
            .await
            .expect_err("ENABLE is mapped in OP");
        assert_eq!(abort_code(&e), Some(0x0800_0022));
        sd.sdo_write(0x7010, 1, 1u8)
            .await
            .expect("0x7010 is not mapped in directional mode");
        for _ in 0..20 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("cycle");
        }
        assert_eq!(setpoints(&bus, 0), (0, 0), "solenoids off");
    });
}
