//! The raw-socket runner: a chain of software PAM-199 slaves answering
//! EtherCAT frames (EtherType 0x88A4) on a real network interface, so any
//! master (TwinCAT, SOEM/pysoem, IgH, ethercrab's raw-socket task) can drive
//! them. Frames come back out of the same interface, as from the last slave
//! of a line. Everything that is not EtherCAT, and frames a slave already
//! processed (source MAC with the locally administered bit set: our own
//! replies seen again), is ignored.

use super::chain::Chain;
use super::pcap::PcapWriter;
use pnet_datalink::{Channel, Config, NetworkInterface};
use std::fs::File;
use std::io::{self, BufWriter};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// What to run.
#[derive(Debug, Clone)]
pub struct RunnerConfig {
    /// Network interface name.
    pub iface: String,
    /// Number of slaves on the line.
    pub count: usize,
    /// Capture every frame (both directions) to this pcap file.
    pub pcap: Option<PathBuf>,
    /// Directory for the slaves' persistent state.
    pub state_dir: Option<PathBuf>,
}

/// Why the runner could not run.
#[derive(Debug, thiserror::Error)]
pub enum RunnerError {
    /// No interface of that name.
    #[error("network interface '{name}' does not exist (available: {available})")]
    NoSuchInterface {
        /// The name asked for.
        name: String,
        /// Interfaces that exist.
        available: String,
    },
    /// The process may not open a raw socket.
    #[error(
        "no permission to open a raw socket on '{0}': run as root or grant CAP_NET_RAW (sudo setcap cap_net_raw+ep <binary>)"
    )]
    Permission(String),
    /// The slave count is out of range.
    #[error("--count must be between 1 and 512, got {0}")]
    Count(usize),
    /// Any other I/O failure.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The error.
        source: io::Error,
    },
}

/// Counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RunStats {
    /// EtherCAT frames answered.
    pub answered: u64,
    /// Frames ignored (other EtherTypes, our own replies).
    pub ignored: u64,
}

/// Opens the interface and serves frames until `stop` is set.
pub fn run(config: &RunnerConfig, stop: &AtomicBool) -> Result<RunStats, RunnerError> {
    if config.count == 0 || config.count > 512 {
        return Err(RunnerError::Count(config.count));
    }
    let all = pnet_datalink::interfaces();
    let Some(iface) = all.iter().find(|i| i.name == config.iface).cloned() else {
        return Err(RunnerError::NoSuchInterface {
            name: config.iface.clone(),
            available: all
                .iter()
                .map(|i| i.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        });
    };
    if let Some(dir) = &config.state_dir {
        std::fs::create_dir_all(dir).map_err(|source| RunnerError::Io {
            context: format!("creating state directory {}", dir.display()),
            source,
        })?;
    }
    let mut pcap: Option<PcapWriter<BufWriter<File>>> = match &config.pcap {
        Some(p) => Some(PcapWriter::create(p).map_err(|source| RunnerError::Io {
            context: format!("creating pcap file {}", p.display()),
            source,
        })?),
        None => None,
    };
    let (mut tx, mut rx) = open(&iface)?;
    let mut chain = Chain::new(config.count);
    let start = Instant::now();
    let mut stats = RunStats::default();
    let mut buf = Vec::with_capacity(1600);
    while !stop.load(Ordering::Acquire) {
        let now = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        match rx.next() {
            Ok(frame) => {
                if !is_request(frame) {
                    stats.ignored += 1;
                    continue;
                }
                buf.clear();
                buf.extend_from_slice(frame);
                if let Some(p) = pcap.as_mut() {
                    let _ = p.write_frame(&buf);
                }
                chain.process(&mut buf, now);
                if let Some(p) = pcap.as_mut() {
                    let _ = p.write_frame(&buf);
                }
                if let Some(Err(source)) = tx.send_to(&buf, None) {
                    return Err(RunnerError::Io {
                        context: format!("sending on {}", iface.name),
                        source,
                    });
                }
                stats.answered += 1;
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock
                ) =>
            {
                chain.poll(now);
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(source) => {
                return Err(RunnerError::Io {
                    context: format!("receiving on {}", iface.name),
                    source,
                });
            }
        }
    }
    if let Some(p) = pcap.as_mut() {
        let _ = p.flush();
    }
    Ok(stats)
}

type Tx = Box<dyn pnet_datalink::DataLinkSender>;
type Rx = Box<dyn pnet_datalink::DataLinkReceiver>;

fn open(iface: &NetworkInterface) -> Result<(Tx, Rx), RunnerError> {
    let cfg = Config {
        read_timeout: Some(Duration::from_millis(1)),
        write_buffer_size: 16384,
        read_buffer_size: 16384,
        promiscuous: true,
        ..Config::default()
    };
    match pnet_datalink::channel(iface, cfg) {
        Ok(Channel::Ethernet(tx, rx)) => Ok((tx, rx)),
        Ok(_) => Err(RunnerError::Io {
            context: format!("opening {}", iface.name),
            source: io::Error::other("not an Ethernet channel"),
        }),
        Err(e) if e.kind() == io::ErrorKind::PermissionDenied => {
            Err(RunnerError::Permission(iface.name.clone()))
        }
        Err(source) => Err(RunnerError::Io {
            context: format!("opening raw socket on {}", iface.name),
            source,
        }),
    }
}

/// Whether `frame` is an EtherCAT frame from a master (not yet processed
/// by any slave).
pub fn is_request(frame: &[u8]) -> bool {
    frame.len() >= 16
        && frame.get(12..14) == Some(&[0x88, 0xA4][..])
        && frame.get(6).is_some_and(|b| b & 0x02 == 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_unprocessed_ethercat_frames_are_requests() {
        let mut f = vec![0u8; 60];
        f[6] = 0x10;
        f[12] = 0x88;
        f[13] = 0xA4;
        assert!(is_request(&f));
        f[6] = 0x12;
        assert!(!is_request(&f), "our own reply");
        f[6] = 0x10;
        f[12] = 0x08;
        f[13] = 0x00;
        assert!(!is_request(&f), "IPv4");
        assert!(!is_request(&f[..10]));
    }

    #[test]
    fn unknown_interface_is_named_in_the_error() {
        let cfg = RunnerConfig {
            iface: "no-such-if0".into(),
            count: 1,
            pcap: None,
            state_dir: None,
        };
        let err = run(&cfg, &AtomicBool::new(false)).unwrap_err();
        assert!(err.to_string().contains("no-such-if0"), "{err}");
    }
}
