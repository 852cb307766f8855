//! Software ESC throughput (lines of PAM-199-P-ETC slaves): one process-data cycle as ethercrab's `tx_rx`
//! sends it (one LRW over the group's image plus FPRD 0x0130 AL status per
//! slave, the image split over as many frames as it needs: 1 frame for 1
//! slave, 2 for 64, 6 for 256, 20 for 1024) through lines of 1, 8, 64, 256
//! and 1024 configured ESCs, two ways: `serial` (each ESC processes the whole frame
//! in turn) and `line` (the virtual link's `Chain`, which parses the frame
//! once and hands each datagram to the slaves it addresses).
//!
//! A second group, `soft_esc_bit_fmmu`, runs one LRW through a line whose
//! FMMUs are bit-granular (each slave 4 output bits and 4 input bits packed
//! into one logical byte, as TwinCAT packs bit terminals), the ESC's
//! bit-mapping path.
//!
//! Run: `cargo bench -p pam-199-p-etc --bench esc`. Criterion reports the time
//! per cycle and, as throughput, slaves per second; ns per slave per cycle
//! = time / slave count.

// criterion's group macro generates an undocumented function.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use ecat_sim::chain::Chain;
use ecat_sim::esc::SoftEsc;
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::ecat::Command;
use std::hint::black_box;

#[path = "esc_frames.rs"]
mod esc_frames;
use esc_frames::{
    Window, config_frames, configure_chain, cycle_frames, slave_config_frame, wkc_sum,
};

/// Runs one frame through every ESC of the line.
fn pass(line: &mut [SoftEsc], frame: &mut [u8]) {
    for esc in line.iter_mut() {
        esc.process_frame(frame);
    }
}

/// Configures a line of ESCs.
fn configure(line: &mut [SoftEsc]) {
    for mut f in config_frames(line.len()) {
        pass(line, &mut f);
    }
}

fn bench(c: &mut Criterion) {
    let sii = pam_199_p_etc::DEVICE.sii_image();
    let mut g = c.benchmark_group("soft_esc_cycle");
    for n in [1usize, 8, 64, 256, 1024] {
        let (templates, expected_wkc) = cycle_frames(n);
        eprintln!("{n} slaves: {} frames per cycle", templates.len());
        g.throughput(Throughput::Elements(n as u64));

        // The virtual link's line.
        let mut chain = Chain::of(n, pam_199_p_etc::Pam::default);
        configure_chain(&mut chain, n);
        let mut frames = templates.clone();
        let mut wkc = 0;
        for f in &mut frames {
            chain.process_frame(f);
            wkc += wkc_sum(f);
        }
        assert_eq!(wkc, expected_wkc, "every slave answers the cycle (line)");
        g.bench_with_input(BenchmarkId::new("line", n), &n, |bch, _| {
            bch.iter(|| {
                for (f, t) in frames.iter_mut().zip(&templates) {
                    f.copy_from_slice(t);
                    black_box(&mut chain).process_frame(black_box(f));
                }
            })
        });
        if n > 256 {
            // The reference path walks every frame through every ESC:
            // 1024 x 20 frames per iteration is only slow, not news.
            continue;
        }

        // Each ESC processes the whole frame in turn (the per-ESC path).
        let mut line: Vec<SoftEsc> = (0..n).map(|_| SoftEsc::new(&sii)).collect();
        configure(&mut line);
        let mut frames = templates.clone();
        let mut wkc = 0;
        for f in &mut frames {
            pass(&mut line, f);
            wkc += wkc_sum(f);
        }
        assert_eq!(wkc, expected_wkc, "every slave answers the cycle");
        g.bench_with_input(BenchmarkId::new("serial", n), &n, |bch, _| {
            bch.iter(|| {
                for (f, t) in frames.iter_mut().zip(&templates) {
                    f.copy_from_slice(t);
                    pass(black_box(&mut line), black_box(f));
                }
            })
        });
    }
    g.finish();
}

/// Configuration frames for bit-granular FMMUs: slave `i` gets logical
/// byte `i`, bits 0..=3 written to SM2 (0x1100, 1 byte) and bits 4..=7
/// read from SM3 (0x1180, 1 byte), both at physical bit 0.
fn bit_config_frames(n: usize) -> Vec<Vec<u8>> {
    (0..n as u16)
        .map(|i| {
            let bits = |start_bit, stop_bit| Window {
                logical: u32::from(i),
                len: 1,
                start_bit,
                stop_bit,
            };
            slave_config_frame(i, (1, 1), bits(0, 3), bits(4, 7))
        })
        .collect()
}

fn bench_bits(c: &mut Criterion) {
    let mut g = c.benchmark_group("soft_esc_bit_fmmu");
    for n in [1usize, 64] {
        g.throughput(Throughput::Elements(n as u64));
        let mut buf = vec![0u8; 1600];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).expect("buffer");
        b.push(Command::Lrw, 0, &vec![0x5A; n]).expect("fits");
        let len = b.finish();
        buf.truncate(len);
        let template = buf;
        let mut chain = Chain::of(n, pam_199_p_etc::Pam::default);
        for mut f in bit_config_frames(n) {
            chain.process_frame(&mut f);
        }
        let mut frame = template.clone();
        chain.process_frame(&mut frame);
        assert_eq!(wkc_sum(&frame), 3 * n as u32, "every bit FMMU hit");
        g.bench_with_input(BenchmarkId::new("line", n), &n, |bch, _| {
            bch.iter(|| {
                frame.copy_from_slice(&template);
                black_box(&mut chain).process_frame(black_box(&mut frame));
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench, bench_bits);
criterion_main!(benches);
