//! Long lines on the virtual link: ethercrab brings 256 and 1024 slaves
//! to OP, every slave has its identity and auto-assigned station address,
//! the working counter counts every slave, and each slave's outputs and
//! inputs travel in its own bytes of a process image that spans several
//! frames.

use io8_example::Io8;
use master_test::link::{Chain, Clock, lock};
use master_test::{LongGroup, VirtualBus};
use std::time::Duration;

/// An output byte for slave `i` that differs from its neighbours'.
fn out_pattern(i: usize) -> u8 {
    (i.wrapping_mul(37) + 11) as u8
}

/// An input byte for slave `i`, different from its output pattern.
fn in_pattern(i: usize) -> u8 {
    (i.wrapping_mul(53) + 7) as u8 ^ 0x5A
}

/// Runs `f` on a thread with a stack big enough for a 1024-slave group.
fn on_big_stack(f: impl FnOnce() + Send + 'static) {
    std::thread::Builder::new()
        .name("long-line".into())
        .stack_size(64 << 20)
        .spawn(f)
        .expect("thread")
        .join()
        .expect("long-line test thread");
}

/// Brings the line `spec` of `n` slaves (IO8s, and PAMs where `pam(i)`)
/// to OP, writes a different output to every slave, sets a different
/// input on every IO8 and checks both ends of every slave.
fn long_line(spec: &'static str, n: usize, pam: fn(usize) -> bool) {
    on_big_stack(move || {
        smol::block_on(async move {
            let entries = device_catalog::parse_line(spec).expect("line");
            assert_eq!(entries.len(), n);
            let chain = Chain::with_slaves(device_catalog::slaves(&entries));
            // Simulated time: the IO8 input filter and the SM watchdog run
            // on the test's clock, never on the machine's speed.
            let bus = VirtualBus::with_chain(chain, Clock::simulated(), None).expect("bus");
            let md = &*bus.maindevice;
            let group = bus.init_long().await.expect("init to PRE-OP");
            assert_eq!(group.len(), n, "every slave found");
            for (i, sd) in group.iter(md).enumerate() {
                let (name, product) = if pam(i) {
                    ("PAM-199-P-ETC", 0x00C7_03F3)
                } else {
                    ("IO8", 0x0000_0008)
                };
                assert_eq!(sd.name(), name, "slave {i}");
                assert_eq!(sd.identity().product_id, product, "slave {i}");
                assert_eq!(sd.configured_address(), 0x1000 + i as u16, "slave {i}");
            }
            let group: LongGroup<_> = group.into_op(md).await.expect("into OP");
            for (i, sd) in group.iter(md).enumerate() {
                let mut out = sd.outputs_raw_mut();
                if pam(i) {
                    out[0] = 1;
                    out[1..5].copy_from_slice(&(i as i32 * 7).to_le_bytes());
                } else {
                    out[0] = out_pattern(i);
                }
            }
            {
                let mut chain = lock(&bus.chain);
                for i in (0..n).filter(|&i| !pam(i)) {
                    let io8 = chain.slave_mut::<Io8>(i).expect("an IO8");
                    let board = io8.slave_mut().app_mut().board_mut();
                    for c in 1..=8u8 {
                        board.set_input(c, in_pattern(i) & (1 << (c - 1)) != 0);
                    }
                }
            }
            // Beyond the IO8's 10 ms input filter, a cycle per simulated ms.
            // Every cycle's LRWs reach every slave: 3 each (read + write),
            // exactly when no slave's image straddles two frames (1-byte
            // IO8 images), else a straddling slave counts in both frames.
            let mut wkc = None;
            for cycle in 0..30 {
                bus.clock.advance(Duration::from_millis(1));
                let r = group.tx_rx(md).await.expect("tx_rx");
                let w = usize::from(r.working_counter);
                assert!(w >= 3 * n, "cycle {cycle}: WKC {w} for {n} slaves");
                if !(0..n).any(pam) {
                    assert_eq!(w, 3 * n, "cycle {cycle}");
                }
                assert_eq!(*wkc.get_or_insert(w), w, "cycle {cycle}: WKC changed");
                assert!(r.all_op(), "cycle {cycle}: every slave in OP");
            }
            {
                let chain = lock(&bus.chain);
                for i in 0..n {
                    if pam(i) {
                        let od = chain.slaves()[i].od();
                        assert_eq!(od.get(0x7000, 3), Some(i as i64 * 7), "PAM {i} command");
                    } else {
                        let io8 = chain.slave::<Io8>(i).expect("an IO8");
                        let board = io8.slave().app().board();
                        let driven = (1..=8u8)
                            .filter(|&c| board.output(c))
                            .fold(0u8, |acc, c| acc | 1 << (c - 1));
                        assert_eq!(driven, out_pattern(i), "IO8 {i} outputs");
                    }
                }
            }
            for (i, sd) in group.iter(md).enumerate() {
                if pam(i) {
                    assert_eq!(sd.inputs_raw()[0] & 1, 1, "PAM {i} READY");
                } else {
                    assert_eq!(sd.inputs_raw()[0], in_pattern(i), "IO8 {i} inputs");
                }
            }
        });
    });
}

#[test]
fn ethercrab_brings_256_mixed_slaves_to_op_with_every_slaves_data() {
    let spec = "pam,io8,io8,io8,pam,io8,io8,io8,pam,io8,io8,io8,pam,io8,io8,io8";
    // 16 copies of a 16-slave pattern (4 PAMs, 12 IO8s).
    let line: &'static str = Box::leak(vec![spec; 16].join(",").into_boxed_str());
    long_line(line, 256, |i| i % 4 == 0);
}

#[test]
fn ethercrab_brings_1024_slaves_to_op_with_every_slaves_data() {
    long_line("io8*1024", 1024, |_| false);
}
