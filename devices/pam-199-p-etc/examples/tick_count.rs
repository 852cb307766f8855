//! Runs a fixed number of 1 ms amplifier ticks in one mode, for an
//! instruction count that does not depend on the machine's load:
//!
//! ```text
//! cargo build --release -p pam-199-p-etc --example tick_count
//! valgrind --tool=cachegrind --cache-sim=no \
//!     target/release/examples/tick_count directional 10000
//! ```
//!
//! The total instructions (`I refs`) divided by the tick count is the cost
//! of one tick (the set-up is a few thousand instructions).

use pam_199_p_etc::app::amplifier::Amplifier;
use pam_199_p_etc::board::SimPowerStage;
use std::hint::black_box;

fn main() {
    let mut args = std::env::args().skip(1);
    let mode = args.next().unwrap_or_else(|| "directional".into());
    let ticks: u64 = args.next().and_then(|n| n.parse().ok()).unwrap_or(10_000);
    let function = match mode.as_str() {
        "directional" => 1,
        "independent" => 2,
        other => {
            eprintln!("tick_count: mode must be directional or independent, not {other:?}");
            std::process::exit(2);
        }
    };
    let mut store = pam_199_p_etc::store();
    store.set(0xF800, 2, function);
    store.set(0x800A, 1, 1);
    store.set(0x7000, 1, 1);
    store.set(0x7000, 3, 5000);
    store.set(0x7010, 1, 1);
    store.set(0x7010, 3, 5000);
    store.set(0x7020, 1, 1);
    store.set(0x7020, 3, 2500);
    let mut amp = Amplifier::new();
    let mut stage = SimPowerStage::new();
    for t in 1..=ticks {
        amp.tick(black_box(&mut store), &mut stage, t * 1_000_000, true);
    }
    let current = if function == 1 {
        (0x6000, "IA")
    } else {
        (0x6010, "I1")
    };
    println!(
        "{mode}: {ticks} ticks, {} = {:?} mA",
        current.1,
        store.get(current.0, 6)
    );
}
