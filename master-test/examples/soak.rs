//! Soak: a line of PAM-199-P-ETC slaves in OP behind a faulty wire for a
//! long time, with continuous SDO traffic, checking what must never
//! happen:
//!
//! * an acknowledged SDO write lost (every read-back equals the last value
//!   the slave acknowledged; after a write whose outcome the master did
//!   not learn, the next read tells and is believed);
//! * a stuck mailbox (a slave whose SDO fails many times in a row);
//! * a slave leaving OP (the faults are far below the SM watchdog);
//! * memory growing (a counting allocator: live heap bytes after warm-up
//!   and at the end);
//! * the first slave's invalid frame counter disagreeing with the
//!   corruption the wire injected;
//! * the frame path allocating: before the soak, the same line, brought to
//!   OP by ethercrab on a clean wire, serves 5 000 cyclic frames after
//!   warm-up, and not one heap allocation may happen (the line's dispatch,
//!   the ESCs and every firmware that runs: what the virtual link and the
//!   raw runner do per frame; ethercrab's executor is not counted, its
//!   timers allocate).
//!
//! Slave time is simulated (1 ms per cycle), so a million cycles take
//! minutes, not a quarter of an hour.
//!
//! ```text
//! cargo run --release -p master-test --example soak -- --cycles 1000000
//! cargo run --release -p master-test --example soak -- --cycles 20000 --slaves 8   # .ci/run
//! ```
//!
//! Exit status 0 when every check held, 1 otherwise (the report says which).

use clap::Parser;
use ecat_slave::al::AlState;
use master_test::link::{Clock, FaultConfig, lock};
use master_test::{VirtualBus, pam_line, registers};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Live heap bytes and allocations, counted around the system allocator
/// (stats_alloc: no unsafe code of ours).
#[global_allocator]
static GLOBAL: &stats_alloc::StatsAlloc<std::alloc::System> = &stats_alloc::INSTRUMENTED_SYSTEM;

/// Bytes allocated and not yet freed.
fn live() -> i64 {
    let s = GLOBAL.stats();
    s.bytes_allocated as i64 - s.bytes_deallocated as i64 + s.bytes_reallocated as i64
}

#[derive(Parser)]
#[command(about = "Soak a line of PAM slaves in OP behind a faulty wire with SDO traffic")]
struct Args {
    /// Process data cycles (1 ms of slave time each).
    #[arg(long, default_value_t = 20_000)]
    cycles: u64,
    /// Slaves on the line.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u16).range(1..=64))]
    slaves: u16,
    /// The faulty wire (see `pam-slave --help`).
    #[arg(
        long,
        default_value = "drop=0.5%,corrupt=0.2%,dup=0.1%,reorder=0.1%,delay=1ms@0.1%,seed=2026"
    )]
    faults: String,
    /// One SDO write or read every this many cycles.
    #[arg(long, default_value_t = 5)]
    sdo_every: u64,
}

/// What the master knows about one slave's 0x800D:02 CURRENT.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Known {
    /// The slave acknowledged this value.
    Acked(u16),
    /// A write of this value was sent, its outcome is unknown: the slave
    /// holds this or the previous value.
    Unsure { new: u16, old: u16 },
}

#[derive(Debug, Default)]
struct Report {
    sdo_writes: u64,
    sdo_reads: u64,
    sdo_failed: u64,
    lost_writes: u64,
    longest_failure_run: u64,
    cycles_failed: u64,
    counter_mismatches: u64,
    left_op: u64,
}

/// Discovery, SAFE-OP and the OP request on a clean wire (the slaves reach
/// OP once outputs flow).
async fn request_op(bus: &VirtualBus) -> master_test::Group<ethercrab::subdevice_group::Op> {
    let md = &*bus.maindevice;
    bus.init()
        .await
        .expect("bring-up on a clean wire")
        .into_safe_op(md)
        .await
        .expect("SAFE-OP")
        .request_into_op(md)
        .await
        .expect("request OP")
}

/// Heap allocations while the line of `n` slaves, brought to OP by
/// ethercrab, serves 5 000 cyclic frames (LRW over the image + BRD AL
/// status) after 1 000 of warm-up: the per-frame work of the virtual link
/// and the raw runner (`Chain::process`: dispatch, the ESCs, every
/// firmware that runs). The frames are fed to the line directly, holding
/// its lock, so ethercrab's executor (whose timers allocate) is not
/// counted. Also returns the working counters of the last frame.
fn steady_state_allocations(n: usize) -> (u64, (u16, u16)) {
    use ecat_slave::wire::builder::FrameBuilder;
    use ecat_slave::wire::ecat::Command;
    let clock = Clock::simulated();
    let bus = VirtualBus::with_clock(n, clock.clone()).expect("bus");
    let image = smol::block_on(async {
        let md = &*bus.maindevice;
        let group = request_op(&bus).await;
        for _ in 0..100 {
            clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("cycle on a clean wire");
        }
        group
            .iter(md)
            .map(|sd| sd.outputs_raw().len() + sd.inputs_raw().len())
            .sum::<usize>()
    });
    let mut chain = lock(&bus.chain);
    assert!(
        chain
            .slaves()
            .iter()
            .all(|s| s.al_status().state == AlState::Op),
        "the line reached OP"
    );
    let mut template = vec![0u8; 1600];
    let (lrw, brd) = {
        let mut b = FrameBuilder::new(&mut template, [0x10; 6]).expect("buffer");
        let lrw = b.push(Command::Lrw, 0, &vec![1u8; image]).expect("fits");
        let brd = b
            .push(Command::Brd, u32::from(registers::AL_STATUS) << 16, &[0, 0])
            .expect("fits");
        let len = b.finish();
        template.truncate(len);
        (lrw, brd)
    };
    let mut frame = template.clone();
    let mut now = clock.now_ns();
    let mut before = 0;
    for k in 0..6_000 {
        if k == 1_000 {
            before = GLOBAL.stats().allocations;
        }
        frame.copy_from_slice(&template);
        now += 1_000_000;
        let _ = chain.process(&mut frame, now);
    }
    let after = GLOBAL.stats().allocations;
    let wkc = |end: usize| u16::from_le_bytes([frame[end], frame[end + 1]]);
    ((after - before) as u64, (wkc(lrw.end), wkc(brd.end)))
}

fn main() -> ExitCode {
    let a = Args::parse();
    let (steady_allocs, (lrw_wkc, brd_wkc)) = steady_state_allocations(usize::from(a.slaves));
    println!(
        "soak: frame path, {} slaves in OP, 5 000 cyclic frames after warm-up (WKC {lrw_wkc} + \
         {brd_wkc}): {steady_allocs} heap allocations",
        a.slaves
    );
    let faults: FaultConfig = match a.faults.parse() {
        Ok(f) => f,
        Err(e) => {
            eprintln!("soak: {e}");
            return ExitCode::from(2);
        }
    };
    let clock = Clock::simulated();
    let bus = match VirtualBus::with_faults(
        pam_line(usize::from(a.slaves)),
        clock.clone(),
        FaultConfig::default(),
    ) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("soak: {e}");
            return ExitCode::from(3);
        }
    };
    let wire = bus.faults.clone().expect("a faulty wire");
    let started = Instant::now();
    let (r, live_warm, live_end, allocs) = smol::block_on(async {
        let md = &*bus.maindevice;
        let group = request_op(&bus).await;
        let stations: Vec<u16> = group.iter(md).map(|sd| sd.configured_address()).collect();
        for _ in 0..500 {
            clock.advance(Duration::from_millis(1));
            let _ = group.tx_rx(md).await;
            if lock(&bus.chain)
                .slaves()
                .iter()
                .all(|s| s.al_status().state == AlState::Op)
            {
                break;
            }
        }
        master_test::link::lock_faults(&wire).set_config(faults);
        let mut r = Report::default();
        let mut known: Vec<Known> = vec![Known::Acked(1000); stations.len()];
        let mut failing: Vec<u64> = vec![0; stations.len()];
        let mut value: u16 = 500;
        let mut live_warm = 0i64;
        let mut counter_base: Option<u64> = None;
        for cycle in 0..a.cycles {
            if cycle == a.cycles / 10 {
                live_warm = live();
            }
            for sd in group.iter(md) {
                let mut out = sd.outputs_raw_mut();
                out[0] = 1;
                out[1..5].copy_from_slice(&((cycle % 20_000) as i32 - 10_000).to_le_bytes());
            }
            clock.advance(Duration::from_millis(1));
            if group.tx_rx(md).await.is_err() {
                r.cycles_failed += 1;
            }
            // The invalid frame counter against the injected corruption,
            // every 10 000 cycles (it saturates at 255).
            if cycle % 10_000 == 0 {
                let injected = || master_test::link::lock_faults(&wire).stats().corrupted;
                if let Some(base) = counter_base.take()
                    && let Ok(v) =
                        ethercrab::Command::fprd(stations[0], registers::RX_ERROR_COUNTER)
                            .receive::<u8>(md)
                            .await
                {
                    let expect = (injected() - base).min(255);
                    if u64::from(v) != expect {
                        r.counter_mismatches += 1;
                        eprintln!("cycle {cycle}: invalid frame counter {v}, injected {expect}");
                    }
                }
                if ethercrab::Command::fpwr(stations[0], registers::RX_ERROR_COUNTER)
                    .send(md, 0u8)
                    .await
                    .is_ok()
                {
                    counter_base = Some(injected());
                }
            }
            if cycle % a.sdo_every != 0 {
                continue;
            }
            let i = ((cycle / a.sdo_every) as usize) % stations.len();
            let sd = group.subdevice(md, i).expect("slave");
            let write = (cycle / a.sdo_every / stations.len() as u64).is_multiple_of(2);
            let ok = if write {
                value = if value >= 3000 { 500 } else { value + 7 };
                r.sdo_writes += 1;
                let old = match known[i] {
                    Known::Acked(v) => v,
                    Known::Unsure { old, .. } => old,
                };
                match sd.sdo_write(0x800D, 2, value).await {
                    Ok(()) => {
                        known[i] = Known::Acked(value);
                        true
                    }
                    Err(_) => {
                        known[i] = Known::Unsure { new: value, old };
                        false
                    }
                }
            } else {
                r.sdo_reads += 1;
                match sd.sdo_read::<u16>(0x800D, 2).await {
                    Ok(v) => {
                        match known[i] {
                            Known::Acked(k) if k != v => {
                                r.lost_writes += 1;
                                eprintln!("cycle {cycle}: slave {i} reads {v}, acknowledged {k}");
                            }
                            Known::Unsure { new, old } if v != new && v != old => {
                                r.lost_writes += 1;
                                eprintln!(
                                    "cycle {cycle}: slave {i} reads {v}, wrote {new} over {old}"
                                );
                            }
                            _ => {}
                        }
                        known[i] = Known::Acked(v);
                        true
                    }
                    Err(_) => false,
                }
            };
            if ok {
                failing[i] = 0;
            } else {
                r.sdo_failed += 1;
                failing[i] += 1;
                r.longest_failure_run = r.longest_failure_run.max(failing[i]);
            }
        }
        r.left_op = lock(&bus.chain)
            .slaves()
            .iter()
            .filter(|s| s.al_status().state != AlState::Op)
            .count() as u64;
        (r, live_warm, live(), GLOBAL.stats().allocations as u64)
    });
    let stats = bus.fault_stats();
    let growth = live_end - live_warm;
    println!(
        "soak: {} cycles x {} slaves in {:.1} s; wire {stats:?}",
        a.cycles,
        a.slaves,
        started.elapsed().as_secs_f64()
    );
    println!(
        "soak: SDO {} writes, {} reads, {} failed (longest run {}); lost acknowledged writes {}; \
         failed cycles {}; counter mismatches {}; slaves not in OP {}; live heap {} -> {} bytes \
         ({growth:+}), {} allocations",
        r.sdo_writes,
        r.sdo_reads,
        r.sdo_failed,
        r.longest_failure_run,
        r.lost_writes,
        r.cycles_failed,
        r.counter_mismatches,
        r.left_op,
        live_warm,
        live_end,
        allocs
    );
    let mut bad = Vec::new();
    if r.lost_writes > 0 {
        bad.push("acknowledged writes lost");
    }
    if r.longest_failure_run >= 10 {
        bad.push("a mailbox got stuck (10 SDO failures in a row)");
    }
    if r.left_op > 0 {
        bad.push("slaves left OP");
    }
    if r.counter_mismatches > 0 {
        bad.push("invalid frame counter disagrees with the injected corruption");
    }
    if growth > 64 * 1024 {
        bad.push("live heap grew by more than 64 KiB after warm-up");
    }
    if steady_allocs > 0 {
        bad.push("the frame path allocated in steady-state OP");
    }
    if usize::from(lrw_wkc) != 3 * usize::from(a.slaves)
        || usize::from(brd_wkc) != usize::from(a.slaves)
    {
        bad.push("the frame path check's frames did not reach every slave");
    }
    if bad.is_empty() {
        println!("soak: PASS");
        ExitCode::SUCCESS
    } else {
        println!("soak: FAIL: {}", bad.join("; "));
        ExitCode::from(1)
    }
}
