//! Distributed Clocks: ethercrab's DC set-up (receive times latched and
//! read, offsets and transmission delays written, static drift
//! compensation by FRMW of the reference clock's system time) against
//! soft ESCs whose oscillators really run fast or slow. What is checked
//! is what a scope on the slaves' SYNC outputs would show: every slave's
//! system time at the same instant.

use ecat_slave::esc::registers as reg;
use ecat_slave::host::chain::DEFAULT_HOP_NS;
use master_test::VirtualBus;
use master_test::link::{Chain, Clock, lock};
use std::time::Duration;

/// Oscillator errors of the 8 slaves, ppb (slave 0 is the reference).
const ERRORS_PPB: [i64; 8] = [0, 20_000, -15_000, 35_000, -25_000, 10_000, -5_000, 30_000];

/// After convergence, the worst |system time of slave i − reference| at
/// one instant, ns. Measured: 0-1 ns after ethercrab's 10 000 static
/// FRMWs and after 200 cyclic ones (the drift control works on whole-ns
/// local times and corrects through its rate only, so it dithers by a few
/// ns: ≤ 10 ns in the `esc::dc` unit tests with a 1 ms period and the
/// filter off). The bound leaves room for a loaded machine's irregular
/// distribution period without hiding a loop that does not converge: the
/// differences before compensation are 100 ns to µs, and a 10 ppm
/// oscillator change drifts 2 µs in 200 ms.
const SYNC_BOUND_NS: i64 = 50;

fn line() -> Chain {
    let entries = device_catalog::parse_line("io8*8").expect("line");
    let mut chain = Chain::with_slaves(device_catalog::slaves(&entries));
    for (s, e) in chain.slaves_mut().iter_mut().zip(ERRORS_PPB) {
        s.esc_mut().set_dc_oscillator(e);
    }
    chain
}

/// Each slave's system time minus the reference's, at injected time `t`.
fn spread(chain: &Chain, t: u64) -> Vec<i64> {
    let r = chain.slaves()[0].esc().dc_system_time(t);
    chain
        .slaves()
        .iter()
        .map(|s| s.esc().dc_system_time(t).wrapping_sub(r) as i64)
        .collect()
}

/// `n` FRMWs of the reference clock's system time, as ethercrab's cyclic
/// DC distribution sends them, one every `period`.
async fn distribute(bus: &VirtualBus, reference: u16, n: usize, period: Duration) {
    for _ in 0..n {
        // The reference reads (+1), the 7 others take the write (+1 each).
        ethercrab::Command::frmw(reference, reg::DC_SYSTEM_TIME)
            .with_wkc(8)
            .receive::<u64>(&bus.maindevice)
            .await
            .expect("FRMW system time");
        if !period.is_zero() {
            smol::Timer::after(period).await;
        }
    }
}

#[test]
fn ethercrab_dc_setup_measures_the_line_and_static_drift_compensation_synchronises_8_drifting_clocks()
 {
    smol::block_on(async {
        let bus = VirtualBus::with_dc(line(), Clock::real(), 10_000).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init with DC");
        assert_eq!(group.len(), 8);
        let mut stations = Vec::new();
        for (i, sd) in group.iter(md).enumerate() {
            assert!(sd.dc_support().any(), "slave {i} reports DC");
            stations.push(sd.configured_address());
            // The transmission delay ethercrab computed from the latched
            // receive times: i hops of the line.
            let delay: u32 = ethercrab::Command::fprd(sd.configured_address(), 0x0928)
                .receive(md)
                .await
                .expect("0x0928");
            let want = i as i64 * DEFAULT_HOP_NS as i64;
            assert!(
                (i64::from(delay) - want).abs() <= 5,
                "slave {i}: delay {delay} ns, the line says {want} ns"
            );
        }
        let t = bus.clock.now_ns();
        let after_static = spread(&lock(&bus.chain), t);
        eprintln!("after static drift compensation: system time − reference, ns: {after_static:?}");
        // The cyclic distribution (1 ms) keeps them there.
        distribute(&bus, stations[0], 200, Duration::from_millis(1)).await;
        let t = bus.clock.now_ns();
        let chain = lock(&bus.chain);
        let cyclic = spread(&chain, t);
        eprintln!("after 200 cyclic distributions: {cyclic:?}");
        for (i, d) in cyclic.iter().enumerate() {
            assert!(
                d.abs() <= SYNC_BOUND_NS,
                "slave {i}: {d} ns off the reference"
            );
        }
        // Each drift control cancels its oscillator's error.
        for (i, s) in chain.slaves().iter().enumerate().skip(1) {
            let c = s.esc().dc_clock();
            let residual = c.error_ppb() + c.correction_ppb();
            assert!(
                residual.abs() <= 2_000,
                "slave {i}: {} ppb oscillator, {} ppb correction",
                c.error_ppb(),
                c.correction_ppb()
            );
            // 0x092C shows the (filtered) difference the loop works on.
            assert!(
                s.esc().dc_difference().abs() <= SYNC_BOUND_NS,
                "slave {i} 0x092C"
            );
        }
    });
}

#[test]
fn without_the_distribution_a_warming_oscillator_drifts_away_and_with_it_stays_in_step() {
    smol::block_on(async {
        let bus = VirtualBus::with_dc(line(), Clock::real(), 10_000).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init with DC");
        let reference = group
            .subdevice(md, 0)
            .expect("slave 0")
            .configured_address();
        distribute(&bus, reference, 100, Duration::from_millis(1)).await;
        // Slave 3's oscillator warms up: +10 ppm more.
        {
            let mut chain = lock(&bus.chain);
            let esc = chain.slaves_mut()[3].esc_mut();
            esc.set_dc_oscillator(ERRORS_PPB[3] + 10_000);
        }
        let t0 = bus.clock.now_ns();
        let before = spread(&lock(&bus.chain), t0)[3];
        // No distribution for 200 ms: 10 ppm over 200 ms = 2 us.
        smol::Timer::after(Duration::from_millis(200)).await;
        let t1 = bus.clock.now_ns();
        let drifted = spread(&lock(&bus.chain), t1)[3] - before;
        let expect = (t1 - t0) as i64 / 100_000; // 10 ppm of the elapsed time
        eprintln!(
            "200 ms without distribution: slave 3 drifted {drifted} ns (10 ppm: {expect} ns)"
        );
        assert!(
            (drifted - expect).abs() <= expect / 5 + 50,
            "drift as the oscillator says: {drifted} ns, expected about {expect} ns"
        );
        // The distribution resumes: the loop pulls it back and holds it.
        distribute(&bus, reference, 400, Duration::from_millis(1)).await;
        let t = bus.clock.now_ns();
        let back = spread(&lock(&bus.chain), t);
        eprintln!("after 400 distributions: {back:?}");
        assert!(
            back[3].abs() <= SYNC_BOUND_NS,
            "slave 3 back in step: {} ns",
            back[3]
        );
    });
}
