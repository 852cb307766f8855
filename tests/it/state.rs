//! AL state machine, watchdogs, PDO modes and LEDs, driven by ethercrab and
//! by raw register writes (AL control 0x0120, SM registers) on the virtual
//! link. The public TF-1200 conformance cases are named `tf1200_*`.

use ecat_slave::led::LedPattern;
use ecat_slave::wire::mailbox::MailboxType;
use master_test::link::{Clock, lock};
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use master_test::{Group, VirtualBus};
use std::time::Duration;

type Md = ethercrab::MainDevice<'static>;

/// Writes AL control and returns (AL status, AL status code) once the
/// firmware has run.
async fn request(bus: &VirtualBus, station: u16, control: u16) -> (u16, u16) {
    crate::common::request(&bus.maindevice, station, control).await
}

async fn status(bus: &VirtualBus, station: u16) -> (u16, u16) {
    crate::common::status(&bus.maindevice, station).await
}

/// ethercrab's `init` of the bus (PRE-OP); the first slave's station
/// address.
async fn first_station(bus: &VirtualBus) -> u16 {
    let md = &*bus.maindevice;
    let group = bus.init().await.expect("init");
    group.subdevice(md, 0).expect("slave").configured_address()
}

/// Lets the link thread poll the firmware a few times.
async fn settle(bus: &VirtualBus) {
    crate::common::settle(&bus.maindevice).await;
    // The simulated clock stands still: run the firmware's loop once.
    let _ = bus.run_firmware();
}

async fn write_sm(bus: &VirtualBus, station: u16, sm: u16, start: u16, len: u16, control: u8) {
    let md: &Md = &bus.maindevice;
    let mut b = [0u8; 8];
    b[0..2].copy_from_slice(&start.to_le_bytes());
    b[2..4].copy_from_slice(&len.to_le_bytes());
    b[4] = control;
    b[6] = 1;
    ethercrab::Command::fpwr(station, 0x0800 + 8 * sm)
        .send(md, b)
        .await
        .expect("SM");
    settle(bus).await;
}

/// One slave brought to SAFE-OP by ethercrab (mailbox and process data SMs
/// configured), returned with its station address.
async fn safe_op(bus: &VirtualBus) -> (Group<ethercrab::subdevice_group::SafeOp>, u16) {
    let md: &Md = &bus.maindevice;
    let group = bus.init().await.expect("init");
    let station = group.subdevice(md, 0).expect("slave").configured_address();
    (group.into_safe_op(md).await.expect("safe-op"), station)
}

const ERR: u16 = 0x10;

#[test]
fn every_transition_of_the_manual_table_and_every_invalid_request() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_group, s) = safe_op(&bus).await;
        // Manual 5.9 rows (from SAFE-OP, with all SMs configured).
        for (control, want) in [
            (0x08, 0x08), // SO
            (0x04, 0x04), // OS
            (0x08, 0x08),
            (0x02, 0x02), // OP
            (0x04, 0x04), // PS
            (0x02, 0x02), // SP
            (0x04, 0x04),
            (0x08, 0x08),
            (0x01, 0x01), // OI
            (0x02, 0x02), // IP
            (0x01, 0x01), // PI
            (0x02, 0x02),
            (0x04, 0x04),
            (0x01, 0x01), // SI
        ] {
            assert_eq!(
                request(&bus, s, control).await,
                (want, 0),
                "request {control:#x}"
            );
        }
        // Invalid requests from INIT, PRE-OP, SAFE-OP: error flag + 0x0011,
        // state kept; unknown states 0x0012.
        for (setup, bad) in [
            (&[][..], 0x04u16),
            (&[][..], 0x08),
            (&[0x02][..], 0x08),
            (&[0x02][..], 0x03),
            (&[0x02, 0x04][..], 0x03),
        ] {
            request(&bus, s, 0x11).await;
            for c in setup {
                request(&bus, s, *c).await;
            }
            let before = status(&bus, s).await.0;
            let (st, code) = request(&bus, s, bad).await;
            assert_eq!(
                (st, code),
                (before | ERR, 0x0011),
                "{setup:?} then {bad:#x}"
            );
            // Without acknowledge further requests are ignored.
            assert_eq!(request(&bus, s, 0x01).await, (before | ERR, 0x0011));
        }
        for unknown in [0x00u16, 0x05, 0x06, 0x07, 0x09, 0x0F] {
            request(&bus, s, 0x11).await;
            request(&bus, s, 0x02).await;
            assert_eq!(
                request(&bus, s, unknown).await,
                (0x02 | ERR, 0x0012),
                "{unknown:#x}"
            );
        }
        assert_eq!(
            request(&bus, s, 0x11).await,
            (0x01, 0),
            "acknowledge to INIT"
        );
    });
}

#[test]
fn tf1200_init_to_preop_with_matching_sm0_sm1() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_g, s) = safe_op(&bus).await;
        request(&bus, s, 0x01).await;
        assert_eq!(request(&bus, s, 0x02).await, (0x02, 0));
    });
}

#[test]
fn tf1200_stay_init_with_error_when_sm0_sm1_do_not_match() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_g, s) = safe_op(&bus).await;
        request(&bus, s, 0x01).await;
        write_sm(&bus, s, 0, 0x1000, 64, 0x26).await;
        assert_eq!(request(&bus, s, 0x02).await, (0x01 | ERR, 0x0016));
        write_sm(&bus, s, 0, 0x1000, 128, 0x26).await;
        assert_eq!(
            request(&bus, s, 0x12).await,
            (0x02, 0),
            "fixed and acknowledged"
        );
    });
}

#[test]
fn tf1200_boot_handling() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_g, s) = safe_op(&bus).await;
        request(&bus, s, 0x01).await;
        // Standard mailbox SMs do not match the bootstrap mailbox.
        assert_eq!(request(&bus, s, 0x03).await, (0x01 | ERR, 0x0015));
        request(&bus, s, 0x11).await;
        write_sm(&bus, s, 0, 0x1000, 1024, 0x26).await;
        write_sm(&bus, s, 1, 0x1400, 1024, 0x22).await;
        assert_eq!(request(&bus, s, 0x03).await, (0x03, 0), "INIT -> BOOT");
        assert_eq!(
            request(&bus, s, 0x02).await,
            (0x03 | ERR, 0x0011),
            "BOOT -> PRE-OP refused"
        );
        for bad in [0x04u16, 0x08] {
            request(&bus, s, 0x13).await;
            assert_eq!(
                request(&bus, s, bad).await,
                (0x03 | ERR, 0x0011),
                "BOOT -> {bad:#x}"
            );
        }
        assert_eq!(request(&bus, s, 0x11).await, (0x01, 0), "BOOT -> INIT");
    });
}

#[test]
fn tf1200_unknown_requested_state() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_g, s) = safe_op(&bus).await;
        assert_eq!(request(&bus, s, 0x0E).await, (0x04 | ERR, 0x0012));
    });
}

#[test]
fn tf1200_safeop_to_preop_when_sm2_or_sm3_change() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_g, s) = safe_op(&bus).await;
        write_sm(&bus, s, 2, 0x1100, 6, 0x64).await;
        assert_eq!(status(&bus, s).await, (0x02 | ERR, 0x001D));
        request(&bus, s, 0x12).await;
        write_sm(&bus, s, 2, 0x1100, 5, 0x64).await;
        assert_eq!(request(&bus, s, 0x04).await, (0x04, 0));
        write_sm(&bus, s, 3, 0x1180, 9, 0x20).await;
        assert_eq!(status(&bus, s).await, (0x02 | ERR, 0x001E));
    });
}

#[test]
fn tf1200_op_to_init_preop_and_safeop() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_g, s) = safe_op(&bus).await;
        for target in [0x01u16, 0x02, 0x04] {
            request(&bus, s, 0x11).await;
            request(&bus, s, 0x02).await;
            request(&bus, s, 0x04).await;
            assert_eq!(request(&bus, s, 0x08).await, (0x08, 0));
            assert_eq!(
                request(&bus, s, target).await,
                (target, 0),
                "OP -> {target:#x}"
            );
        }
    });
}

#[test]
fn tf1200_op_to_safeop_on_unknown_state() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_g, s) = safe_op(&bus).await;
        request(&bus, s, 0x08).await;
        assert_eq!(request(&bus, s, 0x0D).await, (0x04 | ERR, 0x0012));
        // OP -> BOOT is not a transition: SAFE-OP with 0x0011.
        request(&bus, s, 0x14).await;
        assert_eq!(request(&bus, s, 0x08).await, (0x08, 0));
        assert_eq!(request(&bus, s, 0x03).await, (0x04 | ERR, 0x0011));
    });
}

#[test]
fn tf1200_op_to_preop_on_sm_change() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let (_g, s) = safe_op(&bus).await;
        assert_eq!(request(&bus, s, 0x08).await, (0x08, 0));
        write_sm(&bus, s, 2, 0x1100, 7, 0x64).await;
        assert_eq!(status(&bus, s).await, (0x02 | ERR, 0x001D));
        // A mailbox SM change above INIT drops to INIT.
        write_sm(&bus, s, 1, 0x1080, 64, 0x22).await;
        assert_eq!(status(&bus, s).await, (0x01 | ERR, 0x0016));
    });
}

#[test]
fn tf1200_mailbox_repeat_returns_the_identical_previous_response() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let s = first_station(&bus).await;
        let mut c = MailboxClient::new(md, s, MailboxGeometry::standard());
        c.send(
            ecat_slave::wire::mailbox::MailboxType::CoE,
            &[0x00, 0x20, 0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0],
        )
        .await
        .expect("upload request");
        let first = c.receive().await.expect("response");
        // The master "lost" it: repeat.
        let again = c.repeat().await.expect("repeated");
        assert_eq!(first, again, "identical response");
        assert_eq!(
            u32::from_le_bytes(first.payload[6..10].try_into().unwrap()),
            0x00C7_03F3
        );
    });
}

#[test]
fn a_request_waits_in_sm0_until_the_master_has_read_sm1_and_a_repeat_still_returns_the_last_response()
 {
    // The firmware builds a response where it keeps it for the repeat
    // service, so it takes the next request only once the master has read
    // the previous response; a request sent again (same counter and
    // content) is not executed and leaves that response in place.
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let s = first_station(&bus).await;
        let mut c = MailboxClient::new(md, s, MailboxGeometry::standard());
        let vendor = [0x00, 0x20, 0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0];
        let product = [0x00, 0x20, 0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0];
        let sm_status = |sm: u16| async move {
            let v: u8 = ethercrab::Command::fprd(s, 0x0805 + 8 * sm)
                .receive(md)
                .await
                .expect("SM status");
            v & 0x08 != 0
        };
        c.send_raw(MailboxType::CoE, 1, &vendor)
            .await
            .expect("first request");
        settle(&bus).await;
        assert!(sm_status(1).await, "the first response waits in SM1");
        c.send_raw(MailboxType::CoE, 2, &product)
            .await
            .expect("second request");
        for _ in 0..3 {
            settle(&bus).await;
        }
        assert!(sm_status(0).await, "the second request waits in SM0");
        let first = c.receive().await.expect("first response");
        let second = c
            .receive()
            .await
            .expect("second response, after the first was read");
        assert!(!sm_status(0).await, "the second request was taken");
        let value = |m: &master_test::mailbox::Message| {
            u32::from_le_bytes(m.payload[6..10].try_into().unwrap())
        };
        assert_eq!(value(&first), 0x0000_05AE, "0x1018:01 answered first");
        assert_eq!(value(&second), 0x00C7_03F3, "then 0x1018:02");
        // The same request again: not executed, nothing new in SM1, and the
        // repeat service still has the last response.
        c.send_raw(MailboxType::CoE, 2, &product)
            .await
            .expect("sent again");
        for _ in 0..3 {
            settle(&bus).await;
        }
        assert!(!sm_status(1).await, "no response to a request sent again");
        let again = c.repeat().await.expect("repeated");
        assert_eq!(again, second, "the repeat gives the last response");
    });
}

#[test]
fn sm_watchdog_with_defaults_trips_at_100_ms_of_simulated_time() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let s = group.subdevice(md, 0).expect("slave").configured_address();
        let group = group.into_op(md).await.expect("op");
        {
            let sd = group.subdevice(md, 0).expect("slave");
            let mut out = sd.outputs_raw_mut();
            out[0] = 1;
            out[1..5].copy_from_slice(&5000i32.to_le_bytes());
        }
        group.tx_rx(md).await.expect("last output write");
        bus.clock.advance(Duration::from_millis(99));
        settle(&bus).await;
        assert_eq!(status(&bus, s).await, (0x08, 0), "still OP at 99 ms");
        assert_eq!(lock(&bus.chain).slaves()[0].od().get(0x7000, 1), Some(1));
        bus.clock.advance(Duration::from_micros(1_100));
        settle(&bus).await;
        assert_eq!(
            status(&bus, s).await,
            (0x04 | ERR, 0x001B),
            "SAFE-OP + 0x1B by 100 ms + 1 tick"
        );
        {
            let chain = lock(&bus.chain);
            let st = &chain.slaves()[0].od();
            assert_eq!(st.get(0x7000, 1), Some(0), "outputs in the safe state");
            assert_eq!(st.get(0x7000, 3), Some(0));
            assert_eq!(chain.slaves()[0].led_patterns().1, LedPattern::DoubleFlash);
        }
        let wd: u16 = ethercrab::Command::fprd(s, 0x0440)
            .receive(md)
            .await
            .unwrap();
        let count: u8 = ethercrab::Command::fprd(s, 0x0442)
            .receive(md)
            .await
            .unwrap();
        assert_eq!((wd & 1, count), (0, 1));
        // Acknowledge, fresh outputs, OP again.
        assert_eq!(request(&bus, s, 0x14).await, (0x04, 0));
        assert_eq!(
            request(&bus, s, 0x08).await,
            (0x04 | ERR, 0x001B),
            "no fresh outputs yet"
        );
        request(&bus, s, 0x14).await;
        group.tx_rx(md).await.expect("fresh outputs");
        assert_eq!(request(&bus, s, 0x08).await, (0x08, 0));
    });
}

#[test]
fn sm_watchdog_time_zero_never_trips_and_the_multiplier_scales_it() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let s = group.subdevice(md, 0).expect("slave").configured_address();
        ethercrab::Command::fpwr(s, 0x0420)
            .send(md, 0u16)
            .await
            .unwrap();
        let t: u16 = ethercrab::Command::fprd(s, 0x0420)
            .receive(md)
            .await
            .unwrap();
        assert_eq!(t, 0);
        let group = group.into_op(md).await.expect("op");
        let t: u16 = ethercrab::Command::fprd(s, 0x0420)
            .receive(md)
            .await
            .unwrap();
        assert_eq!(t, 0, "still 0 in OP");
        group.tx_rx(md).await.unwrap();
        bus.clock.advance(Duration::from_secs(10));
        settle(&bus).await;
        assert_eq!(status(&bus, s).await, (0x08, 0), "0x0420 = 0 disables");
        // Multiplier 4998: 200 us ticks, 1000 ticks = 200 ms.
        ethercrab::Command::fpwr(s, 0x0400)
            .send(md, 4998u16)
            .await
            .unwrap();
        ethercrab::Command::fpwr(s, 0x0420)
            .send(md, 1000u16)
            .await
            .unwrap();
        group.tx_rx(md).await.unwrap();
        bus.clock.advance(Duration::from_millis(199));
        settle(&bus).await;
        assert_eq!(status(&bus, s).await, (0x08, 0));
        bus.clock.advance(Duration::from_micros(1_300));
        settle(&bus).await;
        assert_eq!(status(&bus, s).await, (0x04 | ERR, 0x001B));
    });
}

#[test]
fn pdi_watchdog_shows_in_dl_status_when_the_application_stalls() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let s = group.subdevice(md, 0).expect("slave").configured_address();
        lock(&bus.chain).slaves_mut()[0].set_stalled(true);
        bus.clock.advance(Duration::from_millis(101));
        settle(&bus).await;
        let dl: u16 = ethercrab::Command::fprd(s, 0x0110)
            .receive(md)
            .await
            .unwrap();
        let count: u8 = ethercrab::Command::fprd(s, 0x0443)
            .receive(md)
            .await
            .unwrap();
        assert_eq!(
            (dl & 0x0002, count),
            (0, 1),
            "PDI watchdog expired and counted"
        );
        assert_eq!(
            lock(&bus.chain).slaves()[0].led_patterns().1,
            LedPattern::On
        );
        lock(&bus.chain).slaves_mut()[0].set_stalled(false);
        settle(&bus).await;
        let dl: u16 = ethercrab::Command::fprd(s, 0x0110)
            .receive(md)
            .await
            .unwrap();
        assert_eq!(dl & 0x0002, 0x0002, "running again");
        drop(group);
    });
}

#[test]
fn switching_to_independent_mode_in_preop_exchanges_both_channels() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        {
            let sd = group.subdevice(md, 0).expect("slave");
            sd.sdo_write(0xF800, 2, 2u8).await.expect("FUNCTION = IND");
            let rx: u16 = sd.sdo_read(0x1C12, 1).await.unwrap();
            let tx: u16 = sd.sdo_read(0x1C13, 1).await.unwrap();
            assert_eq!(
                (rx, tx),
                (0x1601, 0x1A01),
                "FUNCTION selected the IND assignment"
            );
            for base in [0x801Au16, 0x802A] {
                sd.sdo_write(base, 5, 0u16).await.unwrap(); // TRIGGER 0
            }
            for base in [0x801Du16, 0x802D] {
                sd.sdo_write(base, 3, 0u16).await.unwrap(); // no dither
            }
        }
        let group = group.into_op(md).await.expect("op in IND");
        for _ in 0..300 {
            {
                let sd = group.subdevice(md, 0).expect("slave");
                let mut out = sd.outputs_raw_mut();
                assert_eq!(out.len(), 6);
                out[0] = 1;
                out[1..3].copy_from_slice(&4000u16.to_le_bytes());
                out[3] = 1;
                out[4..6].copy_from_slice(&8000u16.to_le_bytes());
            }
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("tx_rx");
        }
        {
            let chain = lock(&bus.chain);
            let st = &chain.slaves()[0].od();
            assert_eq!(
                (st.get(0x7010, 1), st.get(0x7010, 3)),
                (Some(1), Some(4000))
            );
            assert_eq!(
                (st.get(0x7020, 1), st.get(0x7020, 3)),
                (Some(1), Some(8000))
            );
        }
        let sd = group.subdevice(md, 0).expect("slave");
        let inp = sd.inputs_raw();
        assert_eq!(inp.len(), 5 + 16);
        assert_eq!((inp[0] & 1, inp[1] & 1), (1, 1), "READY1 and READY2");
        let i1 = u16::from_le_bytes([inp[5 + 6], inp[5 + 7]]);
        let i2 = u16::from_le_bytes([inp[5 + 14], inp[5 + 15]]);
        assert!((392..=408).contains(&i1), "I1 {i1} mA = 40 % of 1000");
        assert!((784..=816).contains(&i2), "I2 {i2} mA = 80 % of 1000");
        // FUNCTION cannot change outside PRE-OP.
        let e = sd.sdo_write(0xF800, 2, 1u8).await.expect_err("in OP");
        assert_eq!(crate::common::abort_code(&e), Some(0x0800_0022));
    });
}

#[test]
fn an_assignment_that_disagrees_with_function_is_refused_at_safeop() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let s = sd.configured_address();
        sd.sdo_write(0x1C12, 1, 0x1601u16)
            .await
            .expect("IND outputs by hand");
        sd.sdo_write(0x1C13, 0, 1u8).await.unwrap();
        sd.sdo_write(0x1C13, 1, 0x1A01u16).await.unwrap();
        // ethercrab configures SM2/SM3 for the IND image; the request fails.
        let group = group.into_pre_op_pdi(md).await.expect("SMs and FMMUs");
        assert_eq!(
            request(&bus, s, 0x04).await,
            (0x02 | ERR, 0x001D),
            "FUNCTION is still DIR"
        );
        drop(group);
    });
}

#[test]
fn led_patterns_follow_the_state() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let led = |bus: &VirtualBus| lock(&bus.chain).slaves()[0].led_patterns();
        assert_eq!(led(&bus), (LedPattern::Off, LedPattern::Off), "INIT");
        let group = bus.init().await.expect("init");
        assert_eq!(led(&bus), (LedPattern::Blinking, LedPattern::Off), "PRE-OP");
        let group = group.into_safe_op(md).await.expect("safe-op");
        assert_eq!(
            led(&bus),
            (LedPattern::SingleFlash, LedPattern::Off),
            "SAFE-OP"
        );
        let s = group.subdevice(md, 0).unwrap().configured_address();
        let group = group.into_op(md).await.expect("op");
        assert_eq!(led(&bus), (LedPattern::On, LedPattern::Off), "OP");
        request(&bus, s, 0x03).await;
        assert_eq!(
            led(&bus),
            (LedPattern::SingleFlash, LedPattern::Blinking),
            "invalid request"
        );
        drop(group);
    });
}

#[test]
fn mixing_directional_and_independent_pdos_is_refused_at_the_write() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        // 0x1C13 = { 0x1A00, 0x1A02 }: replacing one with 0x1A03 mixes modes.
        let e = sd.sdo_write(0x1C13, 2, 0x1A03u16).await.expect_err("mixed");
        assert_eq!(crate::common::abort_code(&e), Some(0x0604_0043));
        let e = sd
            .sdo_write(0x1C13, 1, 0x1234u16)
            .await
            .expect_err("unknown PDO");
        assert_eq!(crate::common::abort_code(&e), Some(0x0609_0030));
        // The usual sequence (count 0, entries, count) switches modes fine.
        sd.sdo_write(0x1C13, 0, 0u8).await.unwrap();
        sd.sdo_write(0x1C13, 1, 0x1A01u16).await.unwrap();
        sd.sdo_write(0x1C13, 2, 0x1A03u16).await.unwrap();
        sd.sdo_write(0x1C13, 0, 2u8).await.unwrap();
        // Mapping objects are read-only (manual 6.1.1).
        let e = sd
            .sdo_write(0x1A00, 1, 0x6000_0101u32)
            .await
            .expect_err("RO");
        assert_eq!(crate::common::abort_code(&e), Some(0x0601_0002));
    });
}
