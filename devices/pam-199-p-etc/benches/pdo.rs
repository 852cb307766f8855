//! Bit-granular PDO packing: the PAM's process images (1-bit flags,
//! padding and 16/32-bit values, so both the bit path and the byte path of
//! `ecat_slave::pdo`) packed from and unpacked into the object dictionary,
//! as the firmware does every cycle, in both PDO sets.
//!
//! Run: `cargo bench -p pam-199-p-etc --bench pdo`.

// criterion's group macro generates an undocumented function.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use ecat_slave::pdo::{Direction, ProcessImage, assign_set};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("pdo_image");
    let pd = &pam_199_p_etc::DEVICE.process_data;
    for (name, set) in [("directional", 0usize), ("independent", 1)] {
        let mut store = pam_199_p_etc::store();
        assert!(assign_set(&mut store, pd, set));
        let out = <ProcessImage>::build(&store, Direction::Outputs, pd).expect("outputs");
        let inp = <ProcessImage>::build(&store, Direction::Inputs, pd).expect("inputs");
        // Every mapped input flag set, values non-zero.
        for e in inp.entries() {
            if let Some(f) = e.flat {
                store.set_value(usize::from(f), 1);
            }
        }
        let mut in_buf = vec![0u8; inp.byte_len()];
        g.bench_function(format!("pack/{name}"), |b| {
            b.iter(|| inp.pack(black_box(&store), black_box(&mut in_buf)))
        });
        let out_buf: Vec<u8> = (0..out.byte_len()).map(|i| 0x5A ^ i as u8).collect();
        g.bench_function(format!("unpack/{name}"), |b| {
            b.iter(|| out.unpack(black_box(&mut store), black_box(&out_buf)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
