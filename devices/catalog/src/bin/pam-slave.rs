//! `pam-slave`: software slaves (the PAM-199-P-ETC by default, or any
//! device of the catalog, or a mixed line) on a real network interface.
//!
//! ```text
//! pam-slave --iface veth-slave --count 2 --pcap capture.pcap
//! pam-slave --iface veth-slave --device io8 --count 4
//! pam-slave --iface veth-slave --line pam,io8,pam
//! pam-slave --iface veth-a0 --line pam,io8 --forward veth-a1
//! pam-slave --iface veth-slave --esi EL2004.xml --count 2
//! pam-slave --iface veth-slave --eni machine.xml --esi-dir esi/ --dry-run
//! ```

use clap::Parser;
use device_catalog::exit::Exit;
use ecat_sim::raw::{RunnerConfig, run};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Parser)]
#[command(
    name = "pam-slave",
    version,
    about = "Answer EtherCAT frames on a network interface as a line of software slaves",
    after_help = "Exit status:\n  0    stopped by Ctrl-C after serving\n  \
                  2    usage or input error (bad argument, unknown device, line too long)\n  \
                  2    also: the --state-dir firmware store lost its boot records\n  \
                  2    also: the slaves' firmware stores could exceed --memory-cap\n  \
                  3    the interface cannot be opened or fails (needs root or CAP_NET_RAW)\n  \
                  3    also: the --forward relay of returning frames failed"
)]
struct Cli {
    /// Network interface to serve (e.g. eth1, veth-slave).
    #[arg(long)]
    iface: String,
    /// Device of every slave (see --list); default the PAM-199-P-ETC.
    #[arg(long, default_value = "pam", conflicts_with_all = ["line", "esi", "eni"])]
    device: String,
    /// Number of slaves on the line (1..=4096).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=4096), conflicts_with = "line")]
    count: u16,
    /// A mixed line, first to last: e.g. pam,io8,pam or pam*3,io8 (at
    /// most 4096 slaves); `pam@et1100`, `io8@lan9252` run a slave's
    /// firmware through that SPI driver and an emulated chip.
    #[arg(long, conflicts_with_all = ["esi", "eni"])]
    line: Option<String>,
    /// Twins of a device of this ESI file (ETG.2000) instead of a catalog
    /// device: --count of them. What the twin leaves out of the ESI is
    /// printed as a warning naming the line.
    #[arg(long, value_name = "FILE", conflicts_with = "eni")]
    esi: Option<PathBuf>,
    /// With --esi: the device's type (order code) when the file has several.
    #[arg(long = "type", value_name = "NAME", requires = "esi")]
    type_name: Option<String>,
    /// With --esi: the device's revision (decimal or 0x hex); default the
    /// highest of the type.
    #[arg(long, value_name = "R", requires = "esi")]
    revision: Option<String>,
    /// With --esi: list the file's devices (type, revision, product code,
    /// name; those that do not load with the reason) and exit.
    #[arg(long, requires = "esi")]
    list: bool,
    /// The line an ENI file (ETG.2100) describes, in its order: each slave
    /// from the catalog (by vendor ID and product code) or from an ESI file
    /// of --esi-dir.
    #[arg(long, value_name = "FILE")]
    eni: Option<PathBuf>,
    /// Directory of ESI files for --eni.
    #[arg(long, value_name = "DIR", requires = "eni")]
    esi_dir: Option<PathBuf>,
    /// What the inputs of ESI twins do: hold (zeros), loopback (their own
    /// outputs), counter; per device type after the default, e.g.
    /// hold,EL1008=counter.
    #[arg(long, value_name = "RULES", default_value = "hold")]
    inputs: ecat_twin::InputRules,
    /// Load and check everything, print the line, serve nothing.
    #[arg(long)]
    dry_run: bool,
    /// Write every frame, both directions, to this pcap file.
    #[arg(long)]
    pcap: Option<PathBuf>,
    /// Directory for persistent slave state (saved parameters, firmware).
    #[arg(long)]
    state_dir: Option<PathBuf>,
    /// A faulty wire in front of the line, e.g.
    /// drop=1%,corrupt=0.1%,dup=0.1%,delay=5ms@1%,reorder=0.5%,down=2s+500ms,seed=7
    /// (rates per frame; `down` pulls the cable at START for LENGTH).
    #[arg(long, value_name = "SPEC", value_parser = parse_faults)]
    faults: Option<ecat_sim::faults::FaultConfig>,
    /// Port 1 of the last slave: pass every frame, after these slaves
    /// processed it, out of this interface to the next runner (or real
    /// device) and return what comes back to --iface; with no link on it
    /// the frame turns around here. Chains runners across processes and
    /// hosts into one line.
    #[arg(long, value_name = "IFACE")]
    forward: Option<String>,
    /// Benchmark floor: no slaves, answer every EtherCAT frame unchanged
    /// (marked as processed) through the same socket path, to measure
    /// what the kernel costs without EtherCAT work (see the latency
    /// bench).
    #[arg(long, conflicts_with_all = ["line", "forward", "faults", "pcap", "state_dir"])]
    reflect: bool,
    /// Give each slave's DC oscillator an error of up to ±PPM (a fixed
    /// pattern along the line), so a master's DC drift compensation has
    /// something to compensate; default 0 (ideal clocks).
    #[arg(long, value_name = "PPM", default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=500))]
    oscillators: u32,
    /// Firmware slot of each slave: the largest image it accepts over FoE
    /// (4096..=1073741824 bytes; K, M, G suffixes count 1024s). Each
    /// slave's store holds two slots, in memory as images are written (on
    /// disk with --state-dir).
    #[arg(long, value_name = "BYTES", default_value = "2M", value_parser = parse_store_size)]
    image_store_size: u64,
    /// Refuse to start (exit 2) when the slaves' firmware stores could
    /// take more than this: slaves x 2 slots x --image-store-size (K, M,
    /// G suffixes count 1024s). Default: no cap.
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes)]
    memory_cap: Option<u64>,
    /// Poll the socket without sleeping in a short window (at most a
    /// tenth of the period on each side) around the time a cyclic
    /// master's next frame is due, so the frame costs no thread wake-up.
    /// Off by default: where the runner shares its cores with the master
    /// it made round trips slower; try it where it has a core of its own.
    #[arg(long)]
    busy_poll: bool,
    /// Do not answer process-data frames ahead. By default the reply to a
    /// cyclic master's frame is worked out while the runner waits and sent
    /// as the frame arrives; the ESCs then run on the frame as always, and
    /// their reply must be the same (a difference is reported and turns
    /// answering ahead off).
    #[arg(long)]
    no_answer_ahead: bool,
    /// Run on CPU N only (as `taskset -c N`; the runner's threads
    /// included). Where the master shares the machine's cores, pinning
    /// both to the same CPU spares each cycle a wake-up across cores (see
    /// the performance chapter). Default: wherever the scheduler puts it.
    #[arg(long, value_name = "N")]
    cpu: Option<usize>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if cli.list
        && let Some(esi) = &cli.esi
    {
        return match device_catalog::twins::list_esi(esi) {
            Ok(lines) => {
                println!("{}", lines.join("\n"));
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("pam-slave: {e}");
                Exit::Input.into()
            }
        };
    }
    let spec = match &cli.line {
        Some(l) => l.clone(),
        None => format!("{}*{}", cli.device, cli.count),
    };
    let line = match build_line(&cli, &spec) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("pam-slave: {e}");
            return Exit::Input.into();
        }
    };
    let slots = u64::try_from(line.slaves.len())
        .unwrap_or(u64::MAX)
        .saturating_mul(2);
    let worst = slots.saturating_mul(cli.image_store_size);
    if let Some(cap) = cli.memory_cap.filter(|&cap| worst > cap) {
        eprintln!(
            "pam-slave: the firmware stores of {} slave(s) could take {worst} bytes \
             ({} slaves x 2 slots x --image-store-size {}), more than --memory-cap {cap} bytes: \
             lower --image-store-size or the number of slaves, or raise --memory-cap",
            line.slaves.len(),
            line.slaves.len(),
            cli.image_store_size
        );
        return Exit::Input.into();
    }
    // Checked before a dry run too: a bad --cpu is named either way.
    if let Some(cpu) = cli.cpu
        && let Err(e) = ecat_sim::raw::pin_to_cpu(cpu)
    {
        eprintln!("pam-slave: {e}");
        return Exit::Input.into();
    }
    if cli.dry_run {
        println!("{}", line.report.join("\n"));
        return ExitCode::SUCCESS;
    }
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::Release)) {
        eprintln!("warning: cannot install the Ctrl-C handler: {e}");
    }
    if cli.reflect {
        eprintln!(
            "pam-slave: reflecting EtherCAT frames on {} (no slaves; Ctrl-C stops)",
            cli.iface
        );
        return match ecat_sim::raw::reflect(&cli.iface, &stop) {
            Ok(stats) => {
                eprintln!("pam-slave: reflected {} EtherCAT frames", stats.answered);
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("pam-slave: error: {e}");
                Exit::Comm.into()
            }
        };
    }
    let cfg = RunnerConfig {
        iface: cli.iface,
        pcap: cli.pcap,
        state_dir: cli.state_dir,
        faults: cli.faults,
        forward: cli.forward,
        image_slot_capacity: usize::try_from(cli.image_store_size).unwrap_or(usize::MAX),
        busy_poll: cli.busy_poll,
        answer_ahead: !cli.no_answer_ahead,
    };
    let onward = cfg
        .forward
        .as_ref()
        .map(|f| format!(", then on through {f}"))
        .unwrap_or_default();
    eprintln!(
        "pam-slave: {} slave(s) on {}: {}{onward} (Ctrl-C stops)",
        line.slaves.len(),
        cfg.iface,
        line.summary
    );
    let mut slaves = line.slaves;
    for (i, s) in slaves.iter_mut().enumerate() {
        s.esc_mut()
            .set_dc_oscillator(device_catalog::oscillator_ppb(i, cli.oscillators));
    }
    match run(&cfg, slaves, &stop) {
        Ok(stats) => {
            eprintln!(
                "pam-slave: stopped after {} EtherCAT frames ({} answered ahead; {} other frames ignored)",
                stats.answered, stats.answered_ahead, stats.ignored
            );
            if stats.ahead_differed > 0 {
                eprintln!(
                    "pam-slave: error: {} frame(s) answered ahead differed from the ESCs' own reply",
                    stats.ahead_differed
                );
                return Exit::Comm.into();
            }
            if stats.yield_pauses > 0 {
                eprintln!(
                    "pam-slave: the yield after replies answered ahead was paused {} time(s) for a second (yields took long: a busy machine)",
                    stats.yield_pauses
                );
            }
            if let Some(spi) = stats.spi {
                eprintln!(
                    "pam-slave: SPI PDI wires: {} transactions, {} protocol errors, {} refused accesses",
                    spi.transactions, spi.protocol_errors, spi.refused_accesses
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("pam-slave: error: {e}");
            match e {
                // The state directory is input the user gave.
                ecat_sim::raw::RunnerError::LostBootState(_) => Exit::Input.into(),
                _ => Exit::Comm.into(),
            }
        }
    }
}

/// The slaves to serve and what to say about them.
struct Line {
    slaves: Vec<Box<dyn ecat_sim::chain::LineSlave>>,
    summary: String,
    report: Vec<String>,
}

fn build_line(cli: &Cli, spec: &str) -> Result<Line, String> {
    use device_catalog::twins;
    if let Some(eni) = &cli.eni {
        let ecat_twin::line::BuiltLine { slaves, placed } =
            twins::from_eni(eni, cli.esi_dir.as_deref(), &cli.inputs).map_err(|e| e.to_string())?;
        let names: Vec<String> = slaves
            .iter()
            .map(|s| s.description().names.type_name.to_string())
            .collect();
        return Ok(Line {
            slaves,
            summary: format!("the line of {}: {}", eni.display(), summarize(&names)),
            report: placed.iter().map(|p| p.report()).collect(),
        });
    }
    if let Some(esi) = &cli.esi {
        let revision = cli
            .revision
            .as_deref()
            .map(twins::parse_revision)
            .transpose()
            .map_err(|e| e.to_string())?;
        let (label, slaves, warnings) = twins::from_esi(
            esi,
            cli.type_name.as_deref(),
            revision,
            &cli.inputs,
            usize::from(cli.count),
        )
        .map_err(|e| e.to_string())?;
        let what = format!("{label} from {}", esi.display());
        let mut report = vec![format!("{} x {what}", slaves.len())];
        report.extend(
            warnings
                .iter()
                .map(|w| format!("warning: {}: {w}", esi.display())),
        );
        return Ok(Line {
            report,
            summary: format!("{what} x{}", slaves.len()),
            slaves,
        });
    }
    let entries = device_catalog::parse_line(spec).map_err(|e| e.to_string())?;
    let names: Vec<String> = entries
        .iter()
        .map(|d| match d.pdi {
            device_catalog::Pdi::Direct => d.description.names.type_name.to_string(),
            pdi => format!("{}@{}", d.description.names.type_name, pdi.name()),
        })
        .collect();
    Ok(Line {
        slaves: device_catalog::slaves(&entries),
        summary: summarize(&names),
        report: names,
    })
}

/// A byte count: digits with an optional K, M or G (1024, 1024², 1024³).
fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (digits, unit) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&t[..i], c.to_ascii_uppercase()),
        _ => (t, 'B'),
    };
    let scale: u64 = match unit {
        'B' => 1,
        'K' => 1 << 10,
        'M' => 1 << 20,
        'G' => 1 << 30,
        _ => {
            return Err(format!(
                "'{s}' is not a byte count (digits, optionally K, M or G)"
            ));
        }
    };
    let n: u64 = digits
        .parse()
        .map_err(|_| format!("'{s}' is not a byte count (digits, optionally K, M or G)"))?;
    n.checked_mul(scale)
        .ok_or_else(|| format!("'{s}' is too large"))
}

/// `--image-store-size`: a byte count in 4096..=1 GiB.
fn parse_store_size(s: &str) -> Result<u64, String> {
    let n = parse_bytes(s)?;
    if !(4096..=1 << 30).contains(&n) {
        return Err(format!(
            "{n} bytes is outside 4096..=1073741824 for a firmware slot"
        ));
    }
    Ok(n)
}

fn parse_faults(s: &str) -> Result<ecat_sim::faults::FaultConfig, String> {
    s.parse()
        .map_err(|e: ecat_sim::faults::FaultConfigError| e.to_string())
}

/// `PAM-199-P-ETC x2, IO8` for a line.
fn summarize(names: &[String]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < names.len() {
        let mut n = 1;
        while i + n < names.len() && names[i + n] == names[i] {
            n += 1;
        }
        out.push(if n > 1 {
            format!("{} x{n}", names[i])
        } else {
            names[i].to_string()
        });
        i += n;
    }
    out.join(", ")
}
