//! The amplifier through ethercrab: set-point to solenoid current, failure
//! monitoring, parameter commands. Slave time is simulated: every process
//! data cycle advances it by 1 ms.

use crate::common::abort_code;
use master_test::link::{Clock, lock};
use master_test::{Group, VirtualBus};
use pam_199_p_etc::Pam;
use pam_199_p_etc::board::{Fault, Solenoid};
use std::time::Duration;

type OpGroup = Group<ethercrab::subdevice_group::Op>;

/// Runs `ms` cycles of 1 ms simulated time with ENABLE and COMMAND VALUE.
async fn cycles(bus: &VirtualBus, group: &OpGroup, ms: u32, enable: bool, command: i32) -> Vec<u8> {
    let md = &*bus.maindevice;
    let mut last = Vec::new();
    for _ in 0..ms {
        {
            let sd = group.subdevice(md, 0).expect("slave");
            let mut out = sd.outputs_raw_mut();
            out[0] = u8::from(enable);
            out[1..5].copy_from_slice(&command.to_le_bytes());
        }
        bus.clock.advance(Duration::from_millis(1));
        group.tx_rx(md).await.expect("tx_rx");
        last = group.subdevice(md, 0).expect("slave").inputs_raw().to_vec();
    }
    last
}

fn ia(inputs: &[u8]) -> u16 {
    u16::from_le_bytes([inputs[10], inputs[11]])
}

/// One slave in OP with CURRENT 1500 mA, TRIGGER 0 and no dither, so the
/// solenoid current is exactly U x CURRENT.
async fn setup(sens: u8) -> (VirtualBus, OpGroup) {
    let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
    let md = &*bus.maindevice;
    let group = bus.init().await.expect("init");
    {
        let sd = group.subdevice(md, 0).expect("slave");
        sd.sdo_write(0x800D, 2, 1500u16).await.expect("CURRENT");
        sd.sdo_write(0x800A, 5, 0u16).await.expect("TRIGGER");
        sd.sdo_write(0x800D, 3, 0u16).await.expect("DAMPL");
        sd.sdo_write(0xF800, 3, sens).await.expect("SENS");
    }
    let group = group.into_op(md).await.expect("op");
    (bus, group)
}

#[test]
fn half_command_settles_solenoid_a_at_750_ma_and_ready() {
    smol::block_on(async {
        let (bus, group) = setup(2).await;
        // 100 ms ramp to 50 % takes 50 ms; allow the current to settle.
        let inp = cycles(&bus, &group, 200, true, 5000).await;
        assert_eq!(inp[0] & 1, 1, "READY");
        let w = i16::from_le_bytes([inp[4], inp[5]]);
        let c = i16::from_le_bytes([inp[6], inp[7]]);
        assert_eq!((w, c), (5000, 5000));
        // Tolerance: 2 % of the setpoint (controller settling, no dither).
        assert!((735..=765).contains(&ia(&inp)), "IA {} mA", ia(&inp));
        assert_eq!(u16::from_le_bytes([inp[12], inp[13]]), 0, "IB off");
    });
}

#[test]
fn open_wire_drops_ready_and_sens_on_recovers_only_after_enable_off_on() {
    smol::block_on(async {
        let (bus, group) = setup(2).await;
        let md = &*bus.maindevice;
        cycles(&bus, &group, 200, true, 5000).await;
        lock(&bus.chain)
            .slave_mut::<Pam>(0)
            .expect("a PAM")
            .slave_mut()
            .app_mut()
            .stage_mut()
            .inject(Fault::OpenWire(Solenoid::A));
        let inp = cycles(&bus, &group, 20, true, 5000).await;
        assert_eq!(inp[0] & 1, 0, "READY dropped");
        assert_ne!(
            inp[2] & 0x02,
            0,
            "OPEN SOLENOID A bit (0xA010:02) in the TxPDO"
        );
        assert_eq!(ia(&inp), 0, "current zero");
        let sd = group.subdevice(md, 0).expect("slave");
        let open: u8 = sd.sdo_read(0xA010, 2).await.expect("diag");
        assert_eq!(open, 1);
        lock(&bus.chain)
            .slave_mut::<Pam>(0)
            .expect("a PAM")
            .slave_mut()
            .app_mut()
            .stage_mut()
            .clear_faults();
        let inp = cycles(&bus, &group, 2000, true, 5000).await;
        assert_eq!(
            inp[0] & 1,
            0,
            "SENS = ON: still off after the fault has gone"
        );
        cycles(&bus, &group, 10, false, 5000).await;
        let inp = cycles(&bus, &group, 200, true, 5000).await;
        assert_eq!(inp[0] & 1, 1, "ENABLE off/on reset the failure");
        assert!((735..=765).contains(&ia(&inp)), "IA {}", ia(&inp));
    });
}

#[test]
fn sens_auto_resumes_by_itself_once_the_fault_has_gone() {
    smol::block_on(async {
        let (bus, group) = setup(3).await;
        cycles(&bus, &group, 200, true, 5000).await;
        lock(&bus.chain)
            .slave_mut::<Pam>(0)
            .expect("a PAM")
            .slave_mut()
            .app_mut()
            .stage_mut()
            .inject(Fault::OpenWire(Solenoid::A));
        let inp = cycles(&bus, &group, 20, true, 5000).await;
        assert_eq!(inp[0] & 1, 0);
        lock(&bus.chain)
            .slave_mut::<Pam>(0)
            .expect("a PAM")
            .slave_mut()
            .app_mut()
            .stage_mut()
            .clear_faults();
        // Checked each second: within 1.2 s it runs again.
        let inp = cycles(&bus, &group, 1200, true, 5000).await;
        assert_eq!(inp[0] & 1, 1, "READY back without touching ENABLE");
        assert!((735..=765).contains(&ia(&inp)));
    });
}

#[test]
fn save_loadback_default_acknowledge_with_11111111_and_survive_a_power_cycle() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        sd.sdo_write(0x800D, 2, 2222u16).await.expect("CURRENT");
        sd.sdo_write(0xF801, 2, 1u32).await.expect("SAVE");
        let ack: u32 = sd.sdo_read(0xF801, 2).await.expect("read SAVE");
        assert_eq!(ack, 0x1111_1111, "SAVE acknowledged");
        let e = sd
            .sdo_write(0xF801, 2, 1u32)
            .await
            .expect_err("SAVE again at once");
        assert_eq!(abort_code(&e), Some(0x0800_0021), "SAVE is rate-limited");
        bus.clock.advance(Duration::from_secs(2));
        smol::Timer::after(Duration::from_millis(5)).await;
        let ack: u32 = sd.sdo_read(0xF801, 2).await.expect("read SAVE");
        assert_eq!(ack, 0, "the acknowledgement is momentary");

        sd.sdo_write(0x800D, 2, 1111u16).await.expect("CURRENT");
        sd.sdo_write(0xF801, 4, 1u32).await.expect("LOADBACK");
        let v: u16 = sd.sdo_read(0x800D, 2).await.expect("CURRENT");
        assert_eq!(v, 2222, "LOADBACK restored the saved value");
        let ack: u32 = sd.sdo_read(0xF801, 4).await.expect("read LOADBACK");
        assert_eq!(ack, 0x1111_1111);
        sd.sdo_write(0xF801, 3, 1u32).await.expect("DEFAULT");
        let v: u16 = sd.sdo_read(0x800D, 2).await.expect("CURRENT");
        assert_eq!(v, 1000, "DEFAULT restored the manual's default");
        let e = sd
            .sdo_write(0xF801, 3, 2u32)
            .await
            .expect_err("only 1 starts a command");
        assert_eq!(abort_code(&e), Some(0x0609_0030));

        // Power cycle: the saved 2222 comes back, DEFAULT was not saved.
        lock(&bus.chain).slaves_mut()[0].power_cycle();
        drop(group);
        let group = bus.init().await.expect("init after power cycle");
        let sd = group.subdevice(md, 0).expect("slave");
        let v: u16 = sd.sdo_read(0x800D, 2).await.expect("CURRENT");
        assert_eq!(v, 2222);
    });
}

#[test]
fn manufacturer_settings_need_the_vendor_password() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let e = sd.sdo_write(0xF80F, 1, 7u16).await.expect_err("locked");
        assert_eq!(abort_code(&e), Some(0x0601_0000));
        let e = sd
            .sdo_write(0xF801, 1, 0x1234_5678u32)
            .await
            .expect_err("wrong password");
        assert_eq!(abort_code(&e), Some(0x0609_0030));
        sd.sdo_write(0xF801, 1, pam_199_p_etc::VENDOR_PASSWORD)
            .await
            .expect("password");
        sd.sdo_write(0xF80F, 1, 7u16).await.expect("unlocked");
        let v: u16 = sd.sdo_read(0xF80F, 1).await.expect("read");
        assert_eq!(v, 7);
        sd.sdo_write(0xF801, 1, 0u32).await.expect("lock again");
        let e = sd
            .sdo_write(0xF80F, 1, 8u16)
            .await
            .expect_err("locked again");
        assert_eq!(abort_code(&e), Some(0x0601_0000));
    });
}

#[test]
fn acc_on_refuses_controller_gain_writes() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let e = sd
            .sdo_write(0x800D, 9, 20u16)
            .await
            .expect_err("ACC is ON by default");
        assert_eq!(abort_code(&e), Some(0x0800_0021));
        sd.sdo_write(0x800D, 7, 0u8).await.expect("ACC off");
        sd.sdo_write(0x800D, 9, 20u16)
            .await
            .expect("PPWM now writable");
    });
}

#[test]
fn eeprom_data_error_at_power_on_keeps_the_stage_off_until_save() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md = &*bus.maindevice;
        {
            let mut chain = lock(&bus.chain);
            let slave = chain.slave_mut::<Pam>(0).expect("a PAM");
            // A stored set with one flipped bit: CRC mismatch, no valid set.
            let (app, od) = slave.slave_mut().app_and_od();
            ecat_slave::params::save(od, app.nv_mut()).expect("save");
            app.nv_mut().bytes_mut()[40] ^= 0x01;
            slave.power_cycle();
        }
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let memory: u8 = sd.sdo_read(0xA000, 1).await.expect("A000:01");
        assert_eq!(memory, 1, "MEMORY diagnosis already visible in PRE-OP");
        let group = group.into_op(md).await.expect("op");
        let inp = cycles(&bus, &group, 50, true, 5000).await;
        assert_eq!(inp[0] & 1, 0, "no READY with an EEPROM data error");
        assert_eq!(inp[1] & 0x01, 0x01, "MEMORY bit (0xA000:01) in the TxPDO");
        let sd = group.subdevice(md, 0).expect("slave");
        sd.sdo_write(0xF801, 2, 1u32).await.expect("SAVE");
        let inp = cycles(&bus, &group, 200, true, 5000).await;
        assert_eq!(inp[0] & 1, 1, "SAVE cleared the error");
        assert_eq!(inp[1] & 0x01, 0);
    });
}
