//! Building software twins from device descriptions files (host side, no
//! bus):
//!
//! * `esi_twin/io8`: parse the IO8's generated ESI (44 KB, 16 objects)
//!   and build its CoE twin (dictionary, description, SII, firmware);
//! * `esi_twin/dma22_5_slots`: the same for the DMA-22 node's ESI, a
//!   modular device whose twin holds 5 slots (about 1 140 entries);
//! * `eni_line/machine`: the ENI of `twin/testdata/machine.xml` (EK1100,
//!   EL2004, EL2828, EL1008 twins from the ESI directory and a built-in
//!   PAM), files read from disk each time.
//!
//! Run: `cargo bench -p master-test --bench twins`. A twin's description
//! is leaked on purpose (one line per process), so a long benchmark run
//! grows the heap; criterion's runs are short enough.

// criterion's group macro generates an undocumented function.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use ecat_twin::{EsiFile, InputRule, InputRules};
use std::hint::black_box;
use std::path::Path;

fn esi_twin(c: &mut Criterion) {
    let mut g = c.benchmark_group("esi_twin");
    let io8 = device_catalog::find("io8").expect("io8").description;
    for (name, dev) in [("io8", io8), ("dma22_5_slots", &hcs_dma22::DEVICE)] {
        let xml = String::from_utf8(ecat_esi::generate(dev).expect("ESI")).expect("utf-8");
        g.bench_function(name, |b| {
            b.iter(|| {
                let file = EsiFile::parse(black_box(&xml)).expect("ESI");
                let dev = file.device(None, None).expect("device");
                black_box(ecat_twin::twin(dev, None, InputRule::Hold).expect("twin"))
            })
        });
    }
    g.finish();
}

fn eni_line(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/testdata");
    let rules = InputRules::default();
    c.bench_function("eni_line/machine", |b| {
        b.iter(|| {
            let line = device_catalog::twins::from_eni(
                &root.join("machine.xml"),
                Some(&root.join("esi")),
                &rules,
            )
            .expect("line");
            black_box(line.slaves.len())
        })
    });
}

criterion_group!(benches, esi_twin, eni_line);
criterion_main!(benches);
