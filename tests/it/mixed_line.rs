//! A mixed line: ethercrab brings PAM-199-P-ETC, IO8, PAM-199-P-ETC to OP
//! over the virtual link; each slave reports its own identity and name,
//! and the process data of each reaches the right bytes of the image.

use io8_example::Io8;
use master_test::VirtualBus;
use master_test::link::{Clock, lock};
use std::time::Duration;

#[test]
fn ethercrab_brings_pam_io8_pam_to_op_with_each_devices_identity_and_data() {
    smol::block_on(async {
        // Simulated time: no SM watchdog trips on a slow machine; the IO8
        // input filter runs on the same clock.
        let bus = VirtualBus::line("pam,io8,pam", Clock::simulated()).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init to PRE-OP");
        assert_eq!(group.len(), 3);
        let want = [
            (0x0000_05AE, 0x00C7_03F3, "PAM-199-P-ETC", 5, 14),
            (0x0000_0ABE, 0x0000_0008, "IO8", 1, 1),
            (0x0000_05AE, 0x00C7_03F3, "PAM-199-P-ETC", 5, 14),
        ];
        for (sd, (vendor, product, name, _, _)) in group.iter(md).zip(want) {
            let id = sd.identity();
            assert_eq!((id.vendor_id, id.product_id), (vendor, product), "{name}");
            assert_eq!(sd.name(), name);
        }
        let group = group.into_op(md).await.expect("into OP");
        for (sd, (_, _, name, outs, ins)) in group.iter(md).zip(want) {
            assert_eq!(
                (sd.outputs_raw().len(), sd.inputs_raw().len()),
                (outs, ins),
                "{name}: image sizes"
            );
        }
        // Outputs: a command to each PAM, a bit pattern to the IO8.
        for (i, sd) in group.iter(md).enumerate() {
            let mut out = sd.outputs_raw_mut();
            if i == 1 {
                out[0] = 0b1010_0101;
            } else {
                out[0] = 1;
                out[1..5].copy_from_slice(&(1000 * (i as i32 + 1)).to_le_bytes());
            }
        }
        // Inputs: channels 2 and 8 of the IO8 go high.
        {
            let mut chain = lock(&bus.chain);
            let io8 = chain.slave_mut::<Io8>(1).expect("slave 1 is the IO8");
            let board = io8.slave_mut().app_mut().board_mut();
            board.set_input(2, true);
            board.set_input(8, true);
        }
        // Beyond the IO8's 10 ms input filter, a cycle per simulated ms.
        for _ in 0..30 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("tx_rx");
        }
        {
            let chain = lock(&bus.chain);
            let od = |i: usize| chain.slaves()[i].od();
            assert_eq!(
                (od(0).get(0x7000, 1), od(0).get(0x7000, 3)),
                (Some(1), Some(1000)),
                "PAM 1"
            );
            assert_eq!(
                (od(2).get(0x7000, 1), od(2).get(0x7000, 3)),
                (Some(1), Some(3000)),
                "PAM 2"
            );
            let io8 = chain.slave::<Io8>(1).expect("IO8");
            let board = io8.slave().app().board();
            let driven: Vec<bool> = (1..=8).map(|c| board.output(c)).collect();
            assert_eq!(
                driven,
                [true, false, true, false, false, true, false, true],
                "0b1010_0101 on the IO8's outputs"
            );
            // The PAMs' outputs did not leak into the IO8 and back.
            assert_eq!(od(1).get(0x7000, 1), Some(1));
        }
        let inputs = group.subdevice(md, 1).expect("IO8").inputs_raw()[0];
        assert_eq!(inputs, 0b1000_0010, "IO8 inputs 2 and 8 in its own byte");
        let pam_ready = group.subdevice(md, 0).expect("PAM").inputs_raw()[0] & 1;
        assert_eq!(pam_ready, 1, "PAM 1 READY in its own image");
    });
}
