//! `pam-slave`: software PAM-199-P-ETC slaves on a real network interface.
//!
//! ```text
//! pam-slave --iface veth-slave --count 2 --pcap capture.pcap
//! ```

use clap::Parser;
use pam_slave::host::raw::{RunnerConfig, run};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Parser)]
#[command(
    name = "pam-slave",
    about = "Answer EtherCAT frames on a network interface as a line of PAM-199-P-ETC slaves"
)]
struct Cli {
    /// Network interface to serve (e.g. eth1, veth-slave).
    #[arg(long)]
    iface: String,
    /// Number of slaves on the line.
    #[arg(long, default_value_t = 1)]
    count: usize,
    /// Write every frame, both directions, to this pcap file.
    #[arg(long)]
    pcap: Option<PathBuf>,
    /// Directory for persistent slave state.
    #[arg(long)]
    state_dir: Option<PathBuf>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::Release)) {
        eprintln!("warning: cannot install the Ctrl-C handler: {e}");
    }
    let cfg = RunnerConfig {
        iface: cli.iface,
        count: cli.count,
        pcap: cli.pcap,
        state_dir: cli.state_dir,
    };
    eprintln!(
        "pam-slave: {} PAM-199-P-ETC slave(s) on {} (Ctrl-C stops)",
        cfg.count, cfg.iface
    );
    match run(&cfg, &stop) {
        Ok(stats) => {
            eprintln!(
                "pam-slave: stopped after {} EtherCAT frames ({} other frames ignored)",
                stats.answered, stats.ignored
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("pam-slave: error: {e}");
            ExitCode::FAILURE
        }
    }
}
