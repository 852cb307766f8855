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

#[path = "../benches/esc_frames.rs"]
mod esc_frames;

use ecat_sim::chain::Chain;
use std::hint::black_box;

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|v| v.parse().ok()).unwrap_or(1);
    let cycles: u64 = args.next().and_then(|v| v.parse().ok()).unwrap_or(100_000);
    let serial = args.next().is_some_and(|v| v == "serial");
    let mut chain = Chain::of(n, pam_199_p_etc::Pam::default);
    esc_frames::configure_chain(&mut chain, n);
    let (templates, expected) = esc_frames::cycle_frames(n);
    let mut frames = templates.clone();
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
