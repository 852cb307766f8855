//! Software ESC throughput: one cyclic frame (the group's LRW plus one FPRD
//! of AL status per slave, as ethercrab's `tx_rx` sends it) through a line
//! of 1 and of 64 configured ESCs.
//!
//! Run: `cargo bench -p pam-slave --bench esc`. Criterion reports the time
//! per frame; divide by the slave count for ns per slave per frame (the
//! benchmark names carry the count).

#![allow(missing_docs)] // criterion_group! generates an undocumented function.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use pam_slave::device::sii_image;
use pam_slave::esc::soft::SoftEsc;
use pam_slave::wire::builder::FrameBuilder;
use pam_slave::wire::ecat::Command;
use std::hint::black_box;

const OUT: u16 = 5;
const IN: u16 = 14;

/// Runs one frame through every ESC of the line.
fn pass(line: &mut [SoftEsc], frame: &mut [u8]) {
    for esc in line.iter_mut() {
        esc.process_frame(frame);
    }
}

/// Configures station address, SM2/SM3 and FMMU0/1 as ethercrab does.
fn configure(line: &mut [SoftEsc]) {
    let mut buf = vec![0u8; 2048];
    for i in 0..line.len() as u16 {
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).expect("buffer");
        let station = 0x1000 + i;
        let adp = 0u16.wrapping_sub(i) as u32;
        b.push(Command::Apwr, adp | (0x0010 << 16), &station.to_le_bytes())
            .expect("fits");
        let sm2 = [0x00, 0x11, OUT as u8, 0, 0x64, 0, 1, 0];
        let sm3 = [0x80, 0x11, IN as u8, 0, 0x20, 0, 1, 0];
        b.push(Command::Apwr, adp | (0x0810 << 16), &sm2)
            .expect("fits");
        b.push(Command::Apwr, adp | (0x0818 << 16), &sm3)
            .expect("fits");
        let log_out = u32::from(i) * u32::from(OUT);
        let log_in = 0x8000 + u32::from(i) * u32::from(IN);
        let mut f0 = [0u8; 16];
        f0[0..4].copy_from_slice(&log_out.to_le_bytes());
        f0[4..6].copy_from_slice(&OUT.to_le_bytes());
        f0[7] = 7;
        f0[8..10].copy_from_slice(&0x1100u16.to_le_bytes());
        f0[11] = 2;
        f0[12] = 1;
        let mut f1 = f0;
        f1[0..4].copy_from_slice(&log_in.to_le_bytes());
        f1[4..6].copy_from_slice(&IN.to_le_bytes());
        f1[8..10].copy_from_slice(&0x1180u16.to_le_bytes());
        f1[11] = 1;
        b.push(Command::Apwr, adp | (0x0600 << 16), &f0)
            .expect("fits");
        b.push(Command::Apwr, adp | (0x0610 << 16), &f1)
            .expect("fits");
        let len = b.finish();
        pass(line, &mut buf[..len]);
    }
}

/// The cyclic frame: LRW over outputs then inputs, FPRD 0x0130 per slave.
fn cyclic_frame(n: usize) -> Vec<u8> {
    let mut buf = vec![0u8; 16 + 12 + n * 19 * 2 + n * 14 + 64];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).expect("buffer");
    // Outputs at 0.., inputs at 0x8000..: two LRWs keep each contiguous.
    b.push(Command::Lrw, 0, &vec![0x5A; n * OUT as usize])
        .expect("fits");
    b.push(Command::Lrw, 0x8000, &vec![0; n * IN as usize])
        .expect("fits");
    for i in 0..n as u32 {
        b.push(Command::Fprd, (0x1000 + i) | (0x0130 << 16), &[0, 0])
            .expect("fits");
    }
    let len = b.finish();
    buf.truncate(len);
    buf
}

fn bench(c: &mut Criterion) {
    let sii = sii_image();
    let mut g = c.benchmark_group("soft_esc_cyclic_frame");
    for n in [1usize, 64] {
        let mut line: Vec<SoftEsc> = (0..n).map(|_| SoftEsc::new(&sii)).collect();
        configure(&mut line);
        let template = cyclic_frame(n);
        let mut frame = template.clone();
        // Sanity: the frame counts every slave (3 per LRW pair + 1 per FPRD).
        pass(&mut line, &mut frame);
        g.throughput(Throughput::Elements(n as u64));
        g.bench_with_input(BenchmarkId::new("slaves", n), &n, |bch, _| {
            bch.iter(|| {
                frame.copy_from_slice(&template);
                pass(black_box(&mut line), black_box(&mut frame));
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
