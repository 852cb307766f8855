//! Discovery and bring-up to OP, process data in both directions.

use master_test::VirtualBus;
use master_test::link::lock;

async fn bring_up(n: usize) {
    // Simulated slave time: no SM watchdog can trip between the cycle and
    // the checks on a slow machine.
    let bus = VirtualBus::with_clock(n, master_test::link::Clock::simulated()).expect("bus");
    let md = &*bus.maindevice;
    let group = bus.init().await.expect("init to PRE-OP");
    assert_eq!(group.len(), n, "ethercrab finds every slave");
    for sd in group.iter(md) {
        let id = sd.identity();
        assert_eq!(id.vendor_id, 0x0000_05AE);
        assert_eq!(id.product_id, 0x00C7_03F3);
        assert_eq!(id.revision, 7);
        assert_eq!(sd.name(), "PAM-199-P-ETC");
    }
    let group = group.into_op(md).await.expect("into OP");
    for sd in group.iter(md) {
        let (state, _) = sd.status().await.expect("status");
        assert_eq!(state, ethercrab::SubDeviceState::Op);
    }
    for (i, sd) in group.iter(md).enumerate() {
        let mut out = sd.outputs_raw_mut();
        out[0] = 1;
        out[1..5].copy_from_slice(&(i as i32 * 10).to_le_bytes());
    }
    let resp = group.tx_rx(md).await.expect("tx_rx");
    // 5 output + 14 input bytes per slave. While the image fits one LRW
    // datagram every slave counts exactly 3 (read 1 + write 2). A larger
    // image is split over several frames and a slave whose image straddles
    // a frame boundary is counted in each frame, as on silicon.
    if n * 19 <= 1000 {
        assert_eq!(
            resp.working_counter as usize,
            3 * n,
            "LRW counts 3 per slave"
        );
    } else {
        assert!(
            resp.working_counter as usize >= 3 * n,
            "every slave counted"
        );
    }
    let chain = lock(&bus.chain);
    for (i, s) in chain.slaves().iter().enumerate() {
        assert_eq!(s.od().get(0x7000, 1), Some(1), "ENABLE reached slave {i}");
        assert_eq!(s.od().get(0x7000, 3), Some(i as i64 * 10), "slave {i}");
    }
}

#[test]
fn ethercrab_brings_one_slave_to_op_with_identity() {
    smol::block_on(bring_up(1));
}

#[test]
fn ethercrab_brings_eight_slaves_to_op_with_identity() {
    smol::block_on(bring_up(8));
}

#[test]
fn ethercrab_brings_sixty_four_slaves_to_op_with_identity() {
    smol::block_on(bring_up(64));
}

#[test]
fn outputs_reach_the_slave_and_inputs_reach_the_master_at_the_mapped_offset() {
    smol::block_on(async {
        // Simulated time stands still: neither the 1 ms application task
        // (which would overwrite the planted IA with the measured current)
        // nor the SM watchdog acts between the cycles, however slow the
        // machine is.
        let bus = VirtualBus::with_clock(2, master_test::link::Clock::simulated()).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let group = group.into_op(md).await.expect("op");
        // Directional outputs (0x1600): ENABLE bit 0 of byte 0, 7 bits
        // padding, COMMAND VALUE DINT at bytes 1..5.
        for (i, sd) in group.iter(md).enumerate() {
            let mut out = sd.outputs_raw_mut();
            assert_eq!(out.len(), 5);
            out[0] = 1;
            let cmd = -1234 - i as i32;
            out[1..5].copy_from_slice(&cmd.to_le_bytes());
        }
        // IA (0x6000:06) set inside the second slave.
        lock(&bus.chain).slaves_mut()[1]
            .od_mut()
            .set(0x6000, 6, 750);
        for _ in 0..3 {
            group.tx_rx(md).await.expect("tx_rx");
        }
        {
            let chain = lock(&bus.chain);
            for (i, s) in chain.slaves().iter().enumerate() {
                assert_eq!(s.od().get(0x7000, 1), Some(1), "ENABLE of slave {i}");
                assert_eq!(s.od().get(0x7000, 3), Some(-1234 - i as i64));
            }
        }
        let sd = group.subdevice(md, 1).expect("slave 1");
        let inp = sd.inputs_raw();
        // 0x1A00 takes 4 bytes, then 0x1A02: W, C, U, IA, IB (INT/UINT):
        // IA sits at byte 4 + 6 = 10.
        assert_eq!(inp.len(), 14);
        assert_eq!(u16::from_le_bytes([inp[10], inp[11]]), 750);
    });
}
