//! Firmware on a real PDI driver: each slave's firmware reaches its ESC
//! through an SPI driver (`ecat-esc-spi`: ET1100 family, LAN9252) talking
//! to a byte-level emulation of the chip's SPI interface
//! (`ecat-esc-spi-emu`), while ethercrab drives the ESC's other side with
//! real frames. Only the wire between the MCU and the chip is not real.
//! The same flows as on the direct PDI: bring-up to OP, SDO, process data
//! both ways, the SM watchdog, FoE in BOOT; plus the SPI cost of the
//! firmware loop's passes.

use crate::common::{abort_code, status};
use device_catalog::{Et1100Pdi, Lan9252Pdi};
use ecat_sim::SoftSlave;
use ecat_sim::chain::LineSlave;
use io8_example::Io8;
use master_test::VirtualBus;
use master_test::foe::{self, enter_boot, request_state};
use master_test::link::{Clock, lock};
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use std::time::Duration;

/// SPI statistics of slave `s`'s emulated chip: (SEL cycles, protocol
/// errors, refused accesses).
fn chip_stats(s: &dyn LineSlave) -> (u64, u64, u64) {
    let st = s.spi_stats().expect("a slave on an SPI PDI");
    (st.transactions, st.protocol_errors, st.refused_accesses)
}

#[test]
fn ethercrab_brings_a_line_whose_firmware_talks_spi_to_et1100_and_lan9252_chips_to_op() {
    smol::block_on(async {
        let bus = VirtualBus::line(
            "pam@et1100,io8@lan9252,pam@lan9252,io8@et1100",
            Clock::simulated(),
        )
        .expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init to PRE-OP");
        let names: Vec<String> = group.iter(md).map(|s| s.name().to_string()).collect();
        assert_eq!(names, ["PAM-199-P-ETC", "IO8", "PAM-199-P-ETC", "IO8"]);

        // SDO through both drivers: a download, its upload, a refusal.
        for i in [0, 2] {
            let sd = group.subdevice(md, i).expect("PAM");
            sd.sdo_write(0x800D, 2, 2000u16).await.expect("0x800D:02");
            let back: u16 = sd.sdo_read(0x800D, 2).await.expect("0x800D:02");
            assert_eq!(back, 2000, "slave {i}");
            let e = sd.sdo_write(0x800D, 2, 5000u16).await.unwrap_err();
            assert_eq!(abort_code(&e), Some(0x0609_0031), "slave {i}: {e}");
            let name: heapless::String<32> = sd.sdo_read(0x1008, 0).await.expect("0x1008");
            assert_eq!(
                name.as_str(),
                "PAM-199-P-ETC",
                "segmented upload, slave {i}"
            );
        }

        let group = group.into_op(md).await.expect("into OP");
        for (i, sd) in group.iter(md).enumerate() {
            let mut out = sd.outputs_raw_mut();
            if i % 2 == 1 {
                out[0] = 0b1010_0101 ^ i as u8;
            } else {
                out[0] = 1;
                out[1..5].copy_from_slice(&(1000 * (i as i32 + 1)).to_le_bytes());
            }
        }
        {
            let mut chain = lock(&bus.chain);
            let io8 = chain.slaves_mut()[1]
                .as_any_mut()
                .downcast_mut::<SoftSlave<Io8, Lan9252Pdi>>()
                .expect("slave 1: IO8 on the LAN9252");
            io8.slave_mut().app_mut().board_mut().set_input(2, true);
            let io8 = chain.slaves_mut()[3]
                .as_any_mut()
                .downcast_mut::<SoftSlave<Io8, Et1100Pdi>>()
                .expect("slave 3: IO8 on the ET1100");
            io8.slave_mut().app_mut().board_mut().set_input(7, true);
        }
        for _ in 0..30 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("tx_rx");
        }
        {
            let chain = lock(&bus.chain);
            let od = |i: usize| chain.slaves()[i].od();
            assert_eq!(od(0).get(0x7000, 3), Some(1000), "PAM on the ET1100");
            assert_eq!(od(2).get(0x7000, 3), Some(3000), "PAM on the LAN9252");
            let io8 = chain.slaves()[1]
                .as_any()
                .downcast_ref::<SoftSlave<Io8, Lan9252Pdi>>()
                .expect("IO8");
            let driven: Vec<bool> = (1..=8)
                .map(|c| io8.slave().app().board().output(c))
                .collect();
            assert_eq!(
                driven,
                [false, false, true, false, false, true, false, true]
            );
            let io8 = chain.slaves()[3]
                .as_any()
                .downcast_ref::<SoftSlave<Io8, Et1100Pdi>>()
                .expect("IO8");
            let driven: Vec<bool> = (1..=8)
                .map(|c| io8.slave().app().board().output(c))
                .collect();
            assert_eq!(driven, [false, true, true, false, false, true, false, true]);
        }
        assert_eq!(
            group.subdevice(md, 1).expect("IO8").inputs_raw()[0],
            0b0000_0010
        );
        assert_eq!(
            group.subdevice(md, 3).expect("IO8").inputs_raw()[0],
            0b0100_0000
        );
        assert_eq!(
            group.subdevice(md, 2).expect("PAM").inputs_raw()[0] & 1,
            1,
            "READY"
        );

        // The master stops: every SM watchdog expires, SAFE-OP + 0x001B.
        bus.clock.advance(Duration::from_millis(101));
        for _ in 0..4 {
            // A broadcast read answered by all four: the firmware runs.
            let _ = ethercrab::Command::brd(0x0130).receive::<u16>(md).await;
        }
        for sd in group.iter(md) {
            let st = status(md, sd.configured_address()).await;
            assert_eq!(st, (0x14, 0x001B), "{}", sd.name());
        }

        // Nothing on the SPI wire was malformed or refused by a chip.
        let chain = lock(&bus.chain);
        for (i, s) in chain.slaves().iter().enumerate() {
            let (sel, errors, refused) = chip_stats(s.as_ref());
            assert!(sel > 100, "slave {i}: {sel} SPI transactions");
            assert_eq!(
                (errors, refused),
                (0, 0),
                "slave {i}: SPI protocol errors, refused"
            );
        }
    });
}

/// A 40 kB image through the mailbox in BOOT, through the driver: the new
/// version runs after BOOT -> INIT and a power cycle.
async fn foe_update_through(spec: &str) {
    let bus = VirtualBus::line(spec, Clock::frames()).expect("bus");
    let md = &*bus.maindevice;
    let group = bus.init().await.expect("init");
    let station = group.subdevice(md, 0).expect("slave").configured_address();
    enter_boot(md, station).await.expect("BOOT");
    let mut c = MailboxClient::new(md, station, MailboxGeometry::bootstrap());
    let img = foe::pam_image("11", 40_000);
    foe::write(&mut c, "pam-199-p-etc.efw", 0, &img, |_, _| {})
        .await
        .expect("download");
    request_state(md, station, 0x01)
        .await
        .expect("BOOT -> INIT");
    let booted = lock(&bus.chain).power_cycle(0).expect("slave 0");
    assert_eq!(booted, "11", "{spec}");
    let group = bus.init().await.expect("init after the power cycle");
    let sd = group.subdevice(md, 0).expect("slave");
    let v: heapless::String<32> = sd.sdo_read(0x100A, 0).await.expect("0x100A");
    assert_eq!(v.as_str(), "11", "{spec}");
    let (_, errors, refused) = chip_stats(lock(&bus.chain).slaves()[0].as_ref());
    assert_eq!((errors, refused), (0, 0), "{spec}");
}

#[test]
fn foe_in_boot_updates_the_firmware_through_the_et1100_driver() {
    smol::block_on(foe_update_through("pam@et1100"));
}

#[test]
fn foe_in_boot_updates_the_firmware_through_the_lan9252_driver() {
    smol::block_on(foe_update_through("pam@lan9252"));
}

/// SPI transactions (SEL cycles) of one firmware pass of slave `i`.
fn sel_cycles_of_a_pass(bus: &VirtualBus, i: usize, now_ns: u64) -> u64 {
    let mut chain = lock(&bus.chain);
    let before = chip_stats(chain.slaves()[i].as_ref()).0;
    chain.slaves_mut()[i].poll_with(now_ns, None).expect("pass");
    chip_stats(chain.slaves()[i].as_ref()).0 - before
}

#[test]
fn an_idle_pass_costs_one_spi_transaction_on_the_et1100() {
    smol::block_on(async {
        let bus = VirtualBus::line("io8@et1100,io8@lan9252", Clock::simulated()).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let t = bus.clock.now_ns();
        // PRE-OP, nothing flagged: the AL event alone.
        let et = sel_cycles_of_a_pass(&bus, 0, t);
        let lan = sel_cycles_of_a_pass(&bus, 1, t);
        assert_eq!(et, 1, "ET1100: the event comes with an address phase");
        assert_eq!(lan, 3, "LAN9252: CSR command, busy poll, data");
        let group = group.into_op(md).await.expect("OP");
        group.tx_rx(md).await.expect("cycle");
        let t = bus.clock.now_ns();
        // OP, nothing flagged: the event and the inputs.
        let et_idle = sel_cycles_of_a_pass(&bus, 0, t);
        assert_eq!(et_idle, 2, "ET1100 in OP: event + inputs");
        let lan_idle = sel_cycles_of_a_pass(&bus, 1, t);
        // A cycle: the outputs too. The link's extra idle passes are
        // switched off so that the counts are those of the frame's own
        // passes (the clock stands still: nothing else is due).
        let before: Vec<u64> = {
            let mut chain = lock(&bus.chain);
            chain.set_idle_passes(false);
            chain
                .slaves()
                .iter()
                .map(|s| chip_stats(s.as_ref()).0)
                .collect()
        };
        let runs = lock(&bus.chain).firmware_runs();
        group.tx_rx(md).await.expect("cycle");
        let chain = lock(&bus.chain);
        assert_eq!(chain.firmware_runs() - runs, 2, "one pass per slave");
        let after: Vec<u64> = chain
            .slaves()
            .iter()
            .map(|s| chip_stats(s.as_ref()).0)
            .collect();
        assert_eq!(
            after[0] - before[0],
            3,
            "ET1100 OP cycle: event + outputs + inputs"
        );
        eprintln!(
            "SPI transactions per pass: ET1100 idle 1, OP idle {et_idle}, OP cycle {}; \
             LAN9252 idle {lan}, OP idle {lan_idle}, OP cycle {}",
            after[0] - before[0],
            after[1] - before[1]
        );
        assert!(
            after[1] - before[1] > lan_idle,
            "LAN9252 cycle moves the outputs too"
        );
    });
}
