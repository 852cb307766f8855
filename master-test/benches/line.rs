//! Start to OP of long lines on the virtual link: from building the line
//! of software slaves (power-on) until ethercrab's `into_op` returns with
//! every slave in OP, for 1, 64, 256 and 1024 IO8 slaves and 64 PAMs
//! (real-time clock, the link thread running). ethercrab discovers the
//! slaves one after the other (EEPROM, mailbox, PDO assignment: about
//! 300 frames per slave), so the time should grow linearly with the line.
//!
//! Run: `cargo bench -p master-test --bench line`. Criterion reports the
//! time per bring-up and, as throughput, slaves per second; the time per
//! slave is the time divided by the slave count.

// criterion's group macro generates an undocumented function.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use master_test::VirtualBus;
use master_test::link::{Chain, Clock};
use std::time::{Duration, Instant};

/// One bring-up of the line `spec`: returns its duration.
fn start_to_op(spec: &str, n: usize) -> Duration {
    let entries = device_catalog::parse_line(spec).expect("line");
    let t0 = Instant::now();
    let chain = Chain::with_slaves(device_catalog::slaves(&entries));
    let bus = VirtualBus::with_chain(chain, Clock::real(), None).expect("bus");
    smol::block_on(async {
        let md = &*bus.maindevice;
        let group = bus.init_long().await.expect("PRE-OP");
        assert_eq!(group.len(), n);
        let group = group.into_op(md).await.expect("OP");
        assert!(group.tx_rx(md).await.expect("cycle").all_op());
    });
    t0.elapsed()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("start_to_op");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    for (device, n) in [
        ("io8", 1usize),
        ("io8", 64),
        ("pam", 64),
        ("io8", 256),
        ("io8", 1024),
    ] {
        let spec = format!("{device}*{n}");
        g.throughput(Throughput::Elements(n as u64));
        g.bench_with_input(BenchmarkId::new(device, n), &spec, |b, spec| {
            b.iter_custom(|iters| (0..iters).map(|_| start_to_op(spec, n)).sum())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
