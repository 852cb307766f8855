//! A bad wire between ethercrab and the slaves (`VirtualBus::with_faults`):
//! random loss, corruption, duplicates, delay and reordering; a pulled
//! cable; and transfers interrupted at every single frame.

use crate::common::status;
use ecat_sim::SoftSlave;
use ecat_slave::al::{AlState, AlStatusCode};
use master_test::link::{Chain, Clock, Fate, FaultConfig, lock, lock_faults};
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use master_test::{VirtualBus, pam_line};
use std::time::Duration;

/// Every slave's AL state as the firmware holds it.
fn states(bus: &VirtualBus) -> Vec<(AlState, bool, AlStatusCode)> {
    lock(&bus.chain)
        .slaves()
        .iter()
        .map(|s| {
            let a = s.al_status();
            (a.state, a.error, a.code)
        })
        .collect()
}

#[test]
fn one_percent_loss_keeps_the_group_in_op_and_the_error_counter_matches_the_corruption() {
    let faults: FaultConfig = "drop=1%,corrupt=0.3%,dup=0.3%,reorder=0.3%,delay=1ms@0.3%,seed=11"
        .parse()
        .expect("faults");
    let bus =
        VirtualBus::with_faults(pam_line(8), Clock::frames(), FaultConfig::default()).expect("bus");
    let wire = bus.faults.clone().expect("faulty wire");
    smol::block_on(async {
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("bring-up");
        let group = master_test::into_op_cyclic(group, md, Duration::from_millis(1))
            .await
            .expect("OP");
        lock_faults(&wire).set_config(faults);
        // Any write clears the invalid frame counter; from here on every
        // corrupted frame must be counted by the first slave.
        ethercrab::Command::fpwr(0x1000, 0x0300)
            .send(md, 0u8)
            .await
            .expect("clear counter");
        let corrupted_before = bus.fault_stats().corrupted;
        let mut failed = 0u32;
        for _ in 0..3000 {
            if group.tx_rx(md).await.is_err() {
                failed += 1;
            }
            smol::Timer::after(Duration::from_millis(1)).await;
        }
        let counted: u8 = ethercrab::Command::fprd(0x1000, 0x0300)
            .receive(md)
            .await
            .expect("invalid frame counter");
        let stats = bus.fault_stats();
        let injected = stats.corrupted - corrupted_before;
        assert!(injected > 0, "the run injected no corruption: {stats:?}");
        assert_eq!(u64::from(counted), injected.min(255), "{stats:?}");
        assert!(stats.lost() > 20, "{stats:?}");
        // ethercrab's retries hide most losses; none reaches the SM watchdog.
        assert!(failed < 30, "{failed} failed cycles, {stats:?}");
        for (i, (state, error, code)) in states(&bus).into_iter().enumerate() {
            assert_eq!(
                (state, error, code),
                (AlState::Op, false, AlStatusCode::NoError),
                "slave {i} after 3000 cycles with {stats:?}"
            );
        }
    });
}

#[test]
fn a_pulled_cable_puts_every_slave_in_safe_op_within_the_watchdog_and_ack_brings_op_back() {
    let clock = Clock::simulated();
    let bus =
        VirtualBus::with_faults(pam_line(4), clock.clone(), FaultConfig::default()).expect("bus");
    let faults = bus.faults.clone().expect("faulty wire");
    smol::block_on(async {
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let group = group
            .into_safe_op(md)
            .await
            .expect("SAFE-OP")
            .request_into_op(md)
            .await
            .expect("request OP");
        let drive = |on: bool| {
            for sd in group.iter(md) {
                let mut out = sd.outputs_raw_mut();
                out[0] = u8::from(on);
                out[1..5].copy_from_slice(&5000i32.to_le_bytes());
            }
        };
        for _ in 0..200 {
            drive(true);
            clock.advance(Duration::from_millis(1));
            let _ = group.tx_rx(md).await;
            if states(&bus).iter().all(|s| s.0 == AlState::Op) {
                break;
            }
        }
        assert!(
            states(&bus).iter().all(|s| s.0 == AlState::Op),
            "{:?}",
            states(&bus)
        );
        // Pull the cable now, for 2 s of slave time.
        let now = Duration::from_nanos(clock.now_ns());
        lock_faults(&faults).pull_cable(now, Duration::from_secs(2));
        // Watchdog 100 ms: still OP one cycle before it expires ...
        for _ in 0..99 {
            clock.advance(Duration::from_millis(1));
            let _ = group.tx_rx(md).await;
        }
        assert!(
            states(&bus).iter().all(|s| s.0 == AlState::Op),
            "{:?}",
            states(&bus)
        );
        // ... and SAFE-OP with 0x001B, outputs safe, one cycle after.
        for _ in 0..2 {
            clock.advance(Duration::from_millis(1));
            let _ = group.tx_rx(md).await;
        }
        for (i, s) in states(&bus).into_iter().enumerate() {
            assert_eq!(
                s,
                (AlState::SafeOp, true, AlStatusCode::SmWatchdog),
                "slave {i}"
            );
        }
        {
            let chain = lock(&bus.chain);
            for s in chain.slaves() {
                assert_eq!(s.od().get(0x7000, 1), Some(0), "ENABLE forced off");
                assert_eq!(s.od().get(0x6000, 1), Some(0), "not READY");
            }
        }
        // Cable back; the master acknowledges the error in SAFE-OP, sends
        // fresh outputs and requests OP again.
        lock_faults(&faults).heal();
        for sd in group.iter(md) {
            ethercrab::Command::fpwr(sd.configured_address(), 0x0120)
                .send(md, 0x0014u16)
                .await
                .expect("acknowledge");
        }
        for _ in 0..3 {
            drive(true);
            clock.advance(Duration::from_millis(1));
            let _ = group.tx_rx(md).await;
        }
        for sd in group.iter(md) {
            ethercrab::Command::fpwr(sd.configured_address(), 0x0120)
                .send(md, 0x0008u16)
                .await
                .expect("request OP");
        }
        for _ in 0..200 {
            drive(true);
            clock.advance(Duration::from_millis(1));
            let _ = group.tx_rx(md).await;
            if states(&bus).iter().all(|s| s.0 == AlState::Op && !s.1) {
                break;
            }
        }
        for sd in group.iter(md) {
            let (st, code) = status(md, sd.configured_address()).await;
            assert_eq!((st, code), (0x0008, 0), "back in OP without error");
        }
        assert!(bus.fault_stats().link_down > 90);
    });
}

/// The 86-byte interpolation curve 0x8006 with every point set to `v`.
fn curve(v: i16) -> Vec<u8> {
    let mut c = vec![0u8; 86];
    c[0] = 42;
    for i in 0..42 {
        c[2 + 2 * i..4 + 2 * i].copy_from_slice(&(v + i as i16).to_le_bytes());
    }
    c
}

/// A PAM with a 48-byte mailbox: the curve needs a segmented download
/// (several mailbox messages, each several frames).
fn small_mailbox_pam() -> (Chain, MailboxGeometry) {
    let layout = pam_199_p_etc::DEVICE
        .layout()
        .with_mailbox_size(48)
        .expect("layout");
    let chain = Chain::with_slaves(vec![Box::new(SoftSlave::with_layout(
        pam_199_p_etc::Pam::default(),
        layout,
    ))]);
    (chain, MailboxGeometry::of(&layout))
}

#[test]
fn an_sdo_download_interrupted_at_any_frame_is_all_or_nothing() {
    // How many frames a clean segmented download takes.
    let frames = {
        let (chain, geometry) = small_mailbox_pam();
        let bus = VirtualBus::with_faults(chain, Clock::frames(), FaultConfig::default()).unwrap();
        smol::block_on(async {
            let md = &*bus.maindevice;
            bus.init().await.expect("init");
            let f = bus.faults.clone().expect("faults");
            let start = lock_faults(&f).frames();
            let mut c = MailboxClient::new(md, 0x1000, geometry);
            c.sdo_download(0x8006, 0, true, &curve(-300))
                .await
                .expect("clean download");
            lock_faults(&f).frames() - start
        })
    };
    assert!(frames >= 6, "a segmented download takes several frames");
    let (mut applied, mut kept) = (0, 0);
    for k in 0..frames {
        for fate in [Fate::DropBefore, Fate::DropAfter, Fate::Corrupt] {
            let (chain, geometry) = small_mailbox_pam();
            let bus =
                VirtualBus::with_faults(chain, Clock::frames(), FaultConfig::default()).unwrap();
            let f = bus.faults.clone().expect("faults");
            smol::block_on(async {
                let md = &*bus.maindevice;
                bus.init().await.expect("init");
                let mut c = MailboxClient::new(md, 0x1000, geometry);
                let old = c.sdo_upload(0x8006, 0, true).await.expect("old curve");
                let new = curve(-300);
                let n = lock_faults(&f).frames();
                lock_faults(&f).force(n + k, fate);
                let result = c.sdo_download(0x8006, 0, true, &new).await;
                lock_faults(&f).heal();
                // The master learns what happened by reading back.
                let mut c = MailboxClient::new(md, 0x1000, geometry);
                let mut now = None;
                for _ in 0..3 {
                    if let Ok(v) = c.sdo_upload(0x8006, 0, true).await {
                        now = Some(v);
                        break;
                    }
                    smol::Timer::after(Duration::from_millis(50)).await;
                }
                let now = now.unwrap_or_else(|| panic!("frame {k} {fate:?}: no read-back"));
                if result.is_ok() {
                    assert_eq!(
                        now, new,
                        "frame {k} {fate:?}: reported done but not applied"
                    );
                }
                assert!(
                    now == new || now == old,
                    "frame {k} {fate:?}: half-written curve {now:?}"
                );
                if now == new {
                    applied += 1;
                } else {
                    kept += 1;
                }
            });
        }
    }
    eprintln!("interrupted SDO downloads: {applied} applied, {kept} not applied");
}

/// One FoE update of `img` on a fresh slave, with frame `k` of the
/// transfer given `fate`; after a failure, a second update on the same
/// slave. Returns (first succeeded, version after it and a power cycle,
/// version after the retry, frames of the first transfer).
fn foe_run(img: &[u8], k: Option<(u64, Fate)>) -> (bool, String, Option<String>, u64) {
    let bus =
        VirtualBus::with_faults(pam_line(1), Clock::frames(), FaultConfig::default()).expect("bus");
    let f = bus.faults.clone().expect("faults");
    smol::block_on(async {
        let md = &*bus.maindevice;
        let update = async |fault: Option<(u64, Fate)>| -> (bool, u64) {
            bus.init().await.expect("init");
            master_test::foe::enter_boot(md, 0x1000)
                .await
                .expect("BOOT");
            let mut c = MailboxClient::new(md, 0x1000, MailboxGeometry::bootstrap());
            let start = lock_faults(&f).frames();
            if let Some((k, fate)) = fault {
                lock_faults(&f).force(start + k, fate);
            }
            let ok = master_test::foe::write(&mut c, "fw.efw", 0, img, |_, _| {})
                .await
                .is_ok();
            lock_faults(&f).heal();
            let frames = lock_faults(&f).frames() - start;
            // Leave BOOT whatever happened (twice: the first request may
            // meet a slave still busy with the broken transfer).
            for _ in 0..2 {
                if master_test::foe::request_state(md, 0x1000, 0x11)
                    .await
                    .is_ok()
                {
                    break;
                }
            }
            (ok, frames)
        };
        let (ok, frames) = update(k).await;
        let version = lock(&bus.chain).power_cycle(0).expect("slave");
        let retry = if ok {
            None
        } else {
            let (again, _) = update(None).await;
            assert!(again, "the retry on the same slave succeeds");
            Some(lock(&bus.chain).power_cycle(0).expect("slave"))
        };
        (ok, version, retry, frames)
    })
}

#[test]
fn an_foe_update_interrupted_at_any_frame_keeps_the_old_firmware_and_a_retry_succeeds() {
    let img = master_test::foe::pam_image("11", 2500);
    let (ok, version, _, frames) = foe_run(&img, None);
    assert!(ok);
    assert_eq!(version, "11");
    assert!(frames >= 6, "{frames} frames");
    let mut failed = 0;
    for k in 0..frames {
        for fate in [Fate::DropBefore, Fate::DropAfter, Fate::Corrupt] {
            let (ok, version, retry, _) = foe_run(&img, Some((k, fate)));
            if ok {
                assert_eq!(version, "11", "frame {k} {fate:?}: reported done");
            } else {
                failed += 1;
                assert_eq!(
                    version, "10",
                    "frame {k} {fate:?}: a failed update keeps 10"
                );
                assert_eq!(retry.as_deref(), Some("11"), "frame {k} {fate:?}: retry");
            }
        }
    }
    eprintln!(
        "interrupted FoE downloads: {failed} of {} failed",
        frames * 3
    );
}
