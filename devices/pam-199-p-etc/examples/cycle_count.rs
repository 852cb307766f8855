//! Runs a fixed number of process-data cycles of a line of N PAM slaves
//! through the virtual link's line path (`Chain::process_frame`), for an
//! instruction count that does not depend on the machine's load:
//!
//! ```text
//! cargo build --release -p pam-199-p-etc --example cycle_count
//! valgrind --tool=cachegrind --cache-sim=no \
//!     target/release/examples/cycle_count 1 100000
//! ```
//!
//! (Total instructions of a run of K cycles minus those of a run of K0,
//! divided by K - K0, is the cost of one cycle; divided by N and by the
//! frames of a cycle, the cost per slave per frame.) `serial` as a third
//! argument takes the reference path (`Chain::process_serial`).
//!
//! `cold` as the third argument times each cycle right after a 32 MiB
//! write sweep has pushed the line's state out of the caches (what a
//! runner's frame meets after a cycle's idle time, taken to the extreme)
//! and again at once (hot), and prints the medians and 90th percentiles
//! in ns per cycle:
//!
//! ```text
//! cargo run --release -p pam-199-p-etc --example cycle_count -- 64 1000 cold
//! ```

#[path = "../benches/esc_frames.rs"]
mod esc_frames;

use ecat_sim::chain::Chain;
use std::hint::black_box;
use std::time::Instant;

/// One cycle of `frames` through the line.
fn cycle(chain: &mut Chain, frames: &mut [Vec<u8>], templates: &[Vec<u8>]) {
    for (f, t) in frames.iter_mut().zip(templates) {
        f.copy_from_slice(t);
        black_box(&mut *chain).process_frame(black_box(f));
    }
}

/// `cycles` cycles, each timed after a cache sweep (cold) and right
/// after that (hot); prints medians and 90th percentiles.
fn cold_and_hot(chain: &mut Chain, frames: &mut [Vec<u8>], templates: &[Vec<u8>], cycles: u64) {
    let mut sweep = vec![0u8; 32 << 20];
    let (mut cold, mut hot) = (Vec::new(), Vec::new());
    for k in 0..cycles {
        for b in sweep.iter_mut().step_by(64) {
            *b = b.wrapping_add(k as u8);
        }
        black_box(&sweep);
        for times in [&mut cold, &mut hot] {
            let t = Instant::now();
            cycle(chain, frames, templates);
            times.push(t.elapsed().as_nanos());
        }
    }
    cold.sort_unstable();
    hot.sort_unstable();
    let q = |v: &[u128], f: f64| v.get((v.len() as f64 * f) as usize).copied().unwrap_or(0);
    println!(
        "ns per cycle: cold p50 {} p90 {}, hot p50 {} p90 {}",
        q(&cold, 0.5),
        q(&cold, 0.9),
        q(&hot, 0.5),
        q(&hot, 0.9)
    );
}

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|v| v.parse().ok()).unwrap_or(1);
    let cycles: u64 = args.next().and_then(|v| v.parse().ok()).unwrap_or(100_000);
    let mode = args.next();
    let serial = mode.as_deref() == Some("serial");
    let mut chain = Chain::of(n, pam_199_p_etc::Pam::default);
    esc_frames::configure_chain(&mut chain, n);
    let (templates, expected) = esc_frames::cycle_frames(n);
    let mut frames = templates.clone();
    if mode.as_deref() == Some("cold") {
        cold_and_hot(&mut chain, &mut frames, &templates, cycles);
        let wkc: u32 = frames.iter().map(|f| esc_frames::wkc_sum(f)).sum();
        assert_eq!(wkc, expected, "every slave answered the last cycle");
        return;
    }
    for _ in 0..cycles {
        for (f, t) in frames.iter_mut().zip(&templates) {
            f.copy_from_slice(t);
            if serial {
                black_box(&mut chain).process_serial(black_box(f));
            } else {
                black_box(&mut chain).process_frame(black_box(f));
            }
        }
    }
    let wkc: u32 = frames.iter().map(|f| esc_frames::wkc_sum(f)).sum();
    assert_eq!(wkc, expected, "every slave answered the last cycle");
    println!(
        "{cycles} cycles of {n} slaves ({} frames each)",
        templates.len()
    );
}
