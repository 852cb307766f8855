//! How fast the soft slaves' Distributed Clocks converge under a master's
//! drift compensation: 8 IO8s whose oscillators run −25..+35 ppm off and
//! which powered on up to 9 ms apart; ethercrab's DC set-up (receive
//! times, offsets, delays) without static compensation, then the
//! reference time distributed by FRMW every 1 ms as a cyclic master does.
//! Prints the largest |system time − reference| over the line after k
//! distributions (read from the slaves at one instant).
//!
//! ```text
//! cargo run --release -p master-test --example dc_convergence
//! ```

use ecat_slave::esc::registers as reg;
use master_test::VirtualBus;
use master_test::link::{Chain, Clock, lock};
use std::time::Duration;

const ERRORS_PPB: [i64; 8] = [0, 20_000, -15_000, 35_000, -25_000, 10_000, -5_000, 30_000];

fn spread(chain: &Chain, t: u64) -> i64 {
    let r = chain.slaves()[0].esc().dc_system_time(t);
    chain
        .slaves()
        .iter()
        .map(|s| (s.esc().dc_system_time(t).wrapping_sub(r) as i64).abs())
        .max()
        .unwrap_or(0)
}

fn main() {
    let entries = device_catalog::parse_line("io8*8").expect("line");
    let mut chain = Chain::with_slaves(device_catalog::slaves(&entries));
    for (i, (s, e)) in chain.slaves_mut().iter_mut().zip(ERRORS_PPB).enumerate() {
        s.esc_mut().set_dc_oscillator(e);
        s.esc_mut().set_dc_local_time(i as u64 * 1_234_567);
    }
    let bus = VirtualBus::with_dc(chain, Clock::real(), 0).expect("bus");
    smol::block_on(async {
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init with DC");
        let reference = group
            .subdevice(md, 0)
            .expect("slave 0")
            .configured_address();
        println!("distributions (1 ms apart)  largest |system time - reference| (ns)");
        let marks = [0usize, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000];
        let mut k = 0;
        for &m in &marks {
            while k < m {
                ethercrab::Command::frmw(reference, reg::DC_SYSTEM_TIME)
                    .with_wkc(8)
                    .receive::<u64>(md)
                    .await
                    .expect("FRMW");
                smol::Timer::after(Duration::from_millis(1)).await;
                k += 1;
            }
            let t = bus.clock.now_ns();
            println!("{m:>26}  {:>10}", spread(&lock(&bus.chain), t));
        }
    });
}
