//! FoE download throughput on the virtual link: a 1 MiB `.efw` image
//! written in BOOT through the 1024-byte bootstrap mailbox (1012 data bytes
//! per FoE packet), each packet acknowledged, as TwinCAT does it.
//!
//! Run: `cargo bench -p master-test --bench foe`.

// criterion's group macro generates an undocumented function.
#![allow(missing_docs)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use master_test::VirtualBus;
use master_test::foe::{self, enter_boot};
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use std::time::{Duration, Instant};

const LEN: usize = 1024 * 1024;

fn bench(c: &mut Criterion) {
    let img = foe::pam_image("11", LEN);
    let bus = VirtualBus::new(1).expect("bus");
    let md = &*bus.maindevice;
    let station = smol::block_on(async {
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        enter_boot(md, station).await.expect("BOOT");
        station
    });
    let mut g = c.benchmark_group("foe");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    g.throughput(Throughput::Bytes(img.len() as u64));
    g.bench_function("download_1MiB_boot_mailbox_1024", |b| {
        b.iter_custom(|iters| {
            smol::block_on(async {
                let mut client = MailboxClient::new(md, station, MailboxGeometry::bootstrap());
                let start = Instant::now();
                for _ in 0..iters {
                    foe::write(&mut client, "pam-199-p-etc.efw", 0, &img, |_, _| {})
                        .await
                        .expect("download");
                }
                start.elapsed()
            })
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
