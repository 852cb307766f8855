//! One 1 ms application tick of the amplifier (signal chain, failure
//! monitoring, simulated power stage with its 50 µs sub-steps, process data
//! written back into the object dictionary), in both modes.
//!
//! Run: `cargo bench -p pam-199-p-etc --bench app`.

// criterion's group macro generates an undocumented function.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use pam_199_p_etc::app::amplifier::Amplifier;
use pam_199_p_etc::board::SimPowerStage;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("app_tick");
    for (name, function) in [("directional", 1i64), ("independent", 2)] {
        let mut store = pam_199_p_etc::store();
        store.set(0xF800, 2, function);
        store.set(0x800A, 1, 1); // curve on: the longer path
        store.set(0x7000, 1, 1);
        store.set(0x7000, 3, 5000);
        store.set(0x7010, 1, 1);
        store.set(0x7010, 3, 5000);
        store.set(0x7020, 1, 1);
        store.set(0x7020, 3, 2500);
        let mut amp = Amplifier::new();
        let mut stage = SimPowerStage::new();
        let mut t = 0u64;
        g.bench_function(name, |b| {
            b.iter(|| {
                t += 1_000_000;
                amp.tick(black_box(&mut store), &mut stage, t, true);
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
