//! Opt-in CPU pinning of the runner (`pam-slave --cpu N`).
//!
//! On a machine whose cores the master and the runner share, where each
//! process runs decides what a round trip costs: the reply wakes the
//! master, and a wake-up on another core costs far more than one on the
//! same core (on the 2-vCPU VMs of the performance tables, tens of
//! microseconds against a few). Left to the scheduler, the runner's slow
//! round trips come in bursts of about a second, which set its 99th
//! percentile in some runs; with the master and the runner pinned to one
//! core (`taskset -c N` for the master, `--cpu N` here) no run missed.
//! That the bursts are seconds on the other core is the likely reading,
//! not a measured one; see the performance chapter.

use super::RunnerError;
use rustix::thread::{CpuSet, sched_getaffinity, sched_setaffinity};

/// Pins the calling thread, and the threads it starts afterwards, to CPU
/// `cpu` (numbered as `taskset` and `/proc/cpuinfo` number them).
///
/// Fails with [`RunnerError::Cpu`], naming the CPUs the process may use,
/// when `cpu` does not exist or is not among them.
pub fn pin_to_cpu(cpu: usize) -> Result<(), RunnerError> {
    let fail = |reason: String| RunnerError::Cpu { cpu, reason };
    if cpu >= CpuSet::MAX_CPU {
        return Err(fail(format!(
            "CPU numbers end at {} (this process may use {})",
            CpuSet::MAX_CPU - 1,
            allowed_cpus()
        )));
    }
    let mut set = CpuSet::new();
    set.set(cpu);
    sched_setaffinity(None, &set)
        .map_err(|e| fail(format!("{e} (this process may use {})", allowed_cpus())))
}

/// The CPUs the calling thread may run on, as `taskset -c` lists them
/// (`0,1`), or why they are unknown.
pub fn allowed_cpus() -> String {
    match sched_getaffinity(None) {
        Ok(set) => {
            let cpus: Vec<String> = (0..CpuSet::MAX_CPU)
                .filter(|&c| set.is_set(c))
                .map(|c| c.to_string())
                .collect();
            format!("CPUs {}", cpus.join(","))
        }
        Err(e) => format!("unknown CPUs ({e})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Each test pins a thread of its own: affinity is per thread, so the
    // test harness's other threads are not moved.

    #[test]
    fn pinning_to_an_allowed_cpu_leaves_only_that_cpu() {
        let first = sched_getaffinity(None)
            .ok()
            .and_then(|set| (0..CpuSet::MAX_CPU).find(|&c| set.is_set(c)))
            .expect("the test thread may run on some CPU");
        std::thread::spawn(move || {
            pin_to_cpu(first).expect("an allowed CPU");
            let set = sched_getaffinity(None).expect("affinity readable");
            assert_eq!(set.count(), 1);
            assert!(set.is_set(first));
            assert_eq!(allowed_cpus(), format!("CPUs {first}"));
        })
        .join()
        .expect("pinned thread");
    }

    #[test]
    fn pinning_to_a_cpu_that_does_not_exist_names_the_usable_ones() {
        std::thread::spawn(|| {
            let before = allowed_cpus();
            for cpu in [CpuSet::MAX_CPU - 1, CpuSet::MAX_CPU, usize::MAX] {
                let e = pin_to_cpu(cpu).expect_err("no such CPU here").to_string();
                assert!(e.contains(&format!("CPU {cpu}")), "{e}");
                assert!(e.contains(&before), "{e}");
            }
            // Nothing changed.
            assert_eq!(allowed_cpus(), before);
        })
        .join()
        .expect("test thread");
    }
}
