//! Round-trip latency of the raw-socket runner against its floor, in the
//! same run: two veth pairs, each into a network namespace of its own that
//! this bench creates, a fixed cyclic frame (LRW over the whole process
//! image of PAM-sized slaves, 5 output + 14 input bytes each, plus a BRD
//! of the AL status; ethercrab 0.7's `tx_rx` reads each subdevice's AL
//! status by FPRD instead, which the runner answers ahead alike) sent from the host
//! ends and timed until its answer arrives, 20 000 times each:
//!
//! * `floor/N`: `pam-slave --reflect` on one pair, the same socket path
//!   with no slave (what the kernel and the socket cost), answering the
//!   frame of `runner/N` (the same size: a 64-slave frame carries 1.2 KB);
//! * `runner/1`, `runner/8`, `runner/64`: `pam-slave --count N` on the
//!   other, its ESCs configured like a master does (station address,
//!   SM2/SM3, FMMUs), so every LRW is really processed (the bench checks
//!   the working counter).
//!
//! The floor's and the runner's frames alternate (with `--pace-us`, half
//! a period apart), so both meet the host in the same state: on a shared
//! VM whose noise moves the floor's own p50 by 1.5 × within seconds, two
//! cases measured one after the other compare that noise as much as the
//! code. It prints p50, p99, p99.9 and max per case and the ratio
//! runner/floor at p50 and p99. `--pace-us N` sends one frame every N us
//! to each (1000: a 1 kHz cyclic master), back to back by default;
//! `--busy-poll` and `--no-answer-ahead` pass those flags to the runners;
//! `--dc` adds a FRMW of the first slave's DC system time to the frame;
//! `--dump FILE` writes every timed round trip (`slaves case index µs`)
//! for a look at the tail; `--cpu N` runs the master (this bench), the
//! floor and the runner on CPU N alone (`pam-slave --cpu N`), so no
//! round trip pays a wake-up across cores.
//! Needs root and iproute2 (the namespaces are removed at the end); builds
//! `pam-slave` in release mode first.
//!
//! Run: `cargo bench -p master-test --bench latency` (`-- --frames N` for
//! another count).

use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::ecat::Command as Ecat;
use master_test::registers;
use pnet_datalink::{Channel, Config, DataLinkReceiver, DataLinkSender};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const OUT: u16 = 5;
const IN: u16 = 14;

fn ip(args: &[&str]) {
    let ok = Command::new("ip")
        .args(args)
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok,
        "ip {} failed (the bench needs root and iproute2)",
        args.join(" ")
    );
}

/// A veth pair whose slave end lies in a namespace of its own, the
/// process serving that end, and the master's raw socket on the host end;
/// removed on drop.
struct Link {
    ns: String,
    host: String,
    slave: String,
    child: Option<Child>,
    master: Master,
}

impl Link {
    fn new(name: &str) -> Self {
        let ns = format!("{name}n");
        let host = format!("{name}m");
        let slave = format!("{name}s");
        ip(&["netns", "add", &ns]);
        ip(&[
            "link", "add", &host, "type", "veth", "peer", "name", &slave, "netns", &ns,
        ]);
        ip(&["link", "set", &host, "up"]);
        ip(&["-n", &ns, "link", "set", &slave, "up"]);
        let nic = pnet_datalink::interfaces()
            .into_iter()
            .find(|i| i.name == host)
            .expect("host end");
        let cfg = Config {
            read_timeout: Some(Duration::from_millis(10)),
            promiscuous: true,
            ..Config::default()
        };
        let Ok(Channel::Ethernet(tx, rx)) = pnet_datalink::channel(&nic, cfg) else {
            panic!("raw socket on {host}");
        };
        Self {
            ns,
            host,
            slave,
            child: None,
            master: Master { tx, rx },
        }
    }

    /// Starts `pam-slave --iface <slave end> <args>` in the namespace.
    fn start(&mut self, bin: &str, args: &[&str]) {
        self.stop();
        let child = Command::new("ip")
            .args(["netns", "exec", &self.ns, bin, "--iface", &self.slave])
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start pam-slave");
        self.child = Some(child);
        std::thread::sleep(Duration::from_millis(400));
    }

    fn stop(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = Command::new("kill")
                .args(["-INT", &c.id().to_string()])
                .status();
            let _ = c.wait();
        }
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.stop();
        let _ = Command::new("ip")
            .args(["link", "del", &self.host])
            .status();
        let _ = Command::new("ip").args(["netns", "del", &self.ns]).status();
    }
}

/// An EtherCAT frame from the master (source 10:10:10:10:10:10) holding
/// the datagrams (command, address, data), and where each datagram's data
/// ends (its working counter follows).
fn frame(datagrams: &[(Ecat, u32, Vec<u8>)]) -> (Vec<u8>, Vec<usize>) {
    let mut buf = vec![0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).expect("buffer");
    let ends = datagrams
        .iter()
        .map(|(cmd, addr, data)| b.push(*cmd, *addr, data).expect("fits").end)
        .collect();
    let len = b.finish();
    buf.truncate(len.max(60));
    (buf, ends)
}

/// Working counter of the datagram whose data ends at `end`.
fn wkc(f: &[u8], end: usize) -> u16 {
    u16::from_le_bytes([f[end], f[end + 1]])
}

/// Configuration frames for slave `i` (APWR: station address, SM2, SM3,
/// FMMU0 outputs, FMMU1 inputs).
fn config_frame(i: u16) -> (Vec<u8>, Vec<usize>) {
    let adp = u32::from(0u16.wrapping_sub(i));
    let at = |ado: u32| adp | (ado << 16);
    let log_out = u32::from(i) * u32::from(OUT + IN);
    let fmmu = |logical: u32, len: u16, phys: u16, ty: u8| {
        let mut f = vec![0u8; 16];
        f[0..4].copy_from_slice(&logical.to_le_bytes());
        f[4..6].copy_from_slice(&len.to_le_bytes());
        f[7] = 7;
        f[8..10].copy_from_slice(&phys.to_le_bytes());
        f[11] = ty;
        f[12] = 1;
        f
    };
    frame(&[
        (
            Ecat::Apwr,
            at(u32::from(registers::STATION_ADDRESS)),
            (0x1000 + i).to_le_bytes().to_vec(),
        ),
        (
            Ecat::Apwr,
            at(u32::from(registers::SM2)),
            vec![0x00, 0x11, OUT as u8, 0, 0x64, 0, 1, 0],
        ),
        (
            Ecat::Apwr,
            at(u32::from(registers::SM3)),
            vec![0x80, 0x11, IN as u8, 0, 0x20, 0, 1, 0],
        ),
        (
            Ecat::Apwr,
            at(u32::from(registers::FMMU0)),
            fmmu(log_out, OUT, 0x1100, 2),
        ),
        (
            Ecat::Apwr,
            at(u32::from(registers::FMMU1)),
            fmmu(log_out + u32::from(OUT), IN, 0x1180, 1),
        ),
    ])
}

/// The cyclic frame of `n` slaves: LRW over the image, BRD AL status;
/// with `dc`, a FRMW of the first slave's DC system time as well (what
/// SOEM and ethercrab's `tx_rx_dc` add to their cycle with Distributed
/// Clocks).
fn cycle_frame(n: usize, dc: bool) -> (Vec<u8>, Vec<usize>) {
    let image = n * usize::from(OUT + IN);
    let mut datagrams = vec![
        (Ecat::Lrw, 0, vec![0x5A; image]),
        (Ecat::Brd, u32::from(registers::AL_STATUS) << 16, vec![0, 0]),
    ];
    if dc {
        datagrams.push((
            Ecat::Frmw,
            0x1000 | (u32::from(registers::DC_SYSTEM_TIME) << 16),
            vec![0; 8],
        ));
    }
    frame(&datagrams)
}

struct Master {
    tx: Box<dyn DataLinkSender>,
    rx: Box<dyn DataLinkReceiver>,
}

impl Master {
    /// Sends `f` and waits for the processed frame; returns it and the
    /// round-trip time.
    fn exchange(&mut self, f: &[u8]) -> (Vec<u8>, Duration) {
        let t0 = Instant::now();
        self.tx.send_to(f, None).expect("send").expect("sent");
        loop {
            let got = self.rx.next().expect("receive");
            let answer = got.len() >= 16
                && got[12..14] == [0x88, 0xA4]
                && got[6] & 0x02 != 0
                && got[17] == f[17];
            if answer {
                return (got.to_vec(), t0.elapsed());
            }
            assert!(
                t0.elapsed() < Duration::from_secs(2),
                "no answer within 2 s"
            );
        }
    }
}

fn percentile(sorted: &[Duration], p: f64) -> Duration {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i]
}

fn us(d: Duration) -> f64 {
    d.as_nanos() as f64 / 1000.0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--list") {
        return;
    }
    let frames: usize = args
        .iter()
        .position(|a| a == "--frames")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000);
    // `--pace-us N`: N microseconds between frames, as a cyclic master
    // sends them (1000: 1 kHz); 0 (the default): back to back.
    let pace = args
        .iter()
        .position(|a| a == "--pace-us")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse::<u64>().ok())
        .map_or(Duration::ZERO, Duration::from_micros);
    let ok = Command::new(env!("CARGO"))
        .args([
            "build",
            "-q",
            "--release",
            "-p",
            "device-catalog",
            "--bin",
            "pam-slave",
        ])
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok, "cargo build of pam-slave");
    // Where that build put it (CARGO_TARGET_DIR, else the workspace's).
    let target = std::env::var("CARGO_TARGET_DIR")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../target").to_string());
    let bin = format!("{target}/release/pam-slave");

    // `--cpu N`: the master and both slaves on CPU N (after the build,
    // which keeps every core).
    let cpu = args
        .iter()
        .position(|a| a == "--cpu")
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse::<usize>().expect("--cpu N: a CPU number"));
    if let Some(c) = cpu {
        ecat_sim::raw::pin_to_cpu(c).unwrap_or_else(|e| panic!("--cpu: {e}"));
    }
    let cpu_arg = cpu.map(|c| c.to_string());
    let pid = std::process::id();
    // Two veth pairs, each into a namespace of its own: the floor on one,
    // the runner on the other.
    let mut floor_link = Link::new(&format!("lf{pid}"));
    let mut runner_link = Link::new(&format!("lr{pid}"));

    println!(
        "{frames} round trips per case over veth pairs, {}, the floor's and the runner's \
         interleaved{}; times in microseconds",
        if pace.is_zero() {
            "back to back".to_string()
        } else {
            format!("one frame every {} us to each", pace.as_micros())
        },
        cpu.map(|c| format!(", master and slaves on CPU {c}"))
            .unwrap_or_default()
    );
    println!("| case | p50 | p99 | p99.9 | max | p50 / floor | p99 / floor |");
    println!("|---|---|---|---|---|---|---|");
    let busy_poll = args.iter().any(|a| a == "--busy-poll");
    let dc = args.iter().any(|a| a == "--dc");
    let no_ahead = args.iter().any(|a| a == "--no-answer-ahead");
    // `--dump FILE`: every timed round trip as `slaves case index µs`.
    let mut dump = args
        .iter()
        .position(|a| a == "--dump")
        .and_then(|i| args.get(i + 1))
        .map(|p| std::io::BufWriter::new(std::fs::File::create(p).expect("--dump file")));
    for n in [1usize, 8, 64] {
        let mut floor_args = vec!["--reflect"];
        if let Some(c) = &cpu_arg {
            floor_args.extend(["--cpu", c.as_str()]);
        }
        floor_link.start(&bin, &floor_args);
        let count = n.to_string();
        let mut a = vec!["--count", &count];
        if let Some(c) = &cpu_arg {
            a.extend(["--cpu", c.as_str()]);
        }
        if busy_poll {
            a.push("--busy-poll");
        }
        if no_ahead {
            a.push("--no-answer-ahead");
        }
        runner_link.start(&bin, &a);
        for i in 0..n as u16 {
            let (f, ends) = config_frame(i);
            let (r, _) = runner_link.master.exchange(&f);
            assert!(
                ends.iter().all(|&e| wkc(&r, e) == 1),
                "slave {i} configured"
            );
        }
        let (f, ends) = cycle_frame(n, dc);
        let (mut floor_times, mut runner_times) =
            (Vec::with_capacity(frames), Vec::with_capacity(frames));
        let mut next = Instant::now();
        for k in 0..frames + 1000 {
            // Each cycle: the floor's frame, then half a period later the
            // runner's, so both see one frame per period and whatever the
            // host does to the round trips falls on both alike.
            for runner in [false, true] {
                if !pace.is_zero() {
                    // One period after the last one started (a master's
                    // cycle timer), not after its answer.
                    next += pace / 2;
                    let now = Instant::now();
                    if next > now {
                        std::thread::sleep(next - now);
                    } else {
                        next = now;
                    }
                }
                let link = if runner {
                    &mut runner_link
                } else {
                    &mut floor_link
                };
                let (r, t) = link.master.exchange(&f);
                if runner {
                    assert_eq!(
                        usize::from(wkc(&r, ends[0])),
                        3 * n,
                        "LRW reached every slave"
                    );
                    assert_eq!(usize::from(wkc(&r, ends[1])), n, "BRD reached every slave");
                    if dc {
                        assert_eq!(usize::from(wkc(&r, ends[2])), n, "FRMW reached every slave");
                    }
                }
                // The first 1000 warm up the caches and the scheduler.
                if k >= 1000 {
                    if let Some(d) = dump.as_mut() {
                        use std::io::Write;
                        let case = if runner { "runner" } else { "floor" };
                        writeln!(d, "{n} {case} {} {:.1}", k - 1000, us(t)).expect("--dump");
                    }
                    if runner {
                        runner_times.push(t);
                    } else {
                        floor_times.push(t);
                    }
                }
            }
        }
        runner_link.stop();
        floor_link.stop();
        let stats = |times: &mut Vec<Duration>| {
            times.sort_unstable();
            let max = *times.last().expect("samples");
            (
                percentile(times, 0.5),
                percentile(times, 0.99),
                percentile(times, 0.999),
                max,
            )
        };
        let fl = stats(&mut floor_times);
        let ru = stats(&mut runner_times);
        for (name, (p50, p99, p999, max)) in
            [(format!("floor/{n}"), fl), (format!("runner/{n}"), ru)]
        {
            println!(
                "| {name} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} |",
                us(p50),
                us(p99),
                us(p999),
                us(max),
                us(p50) / us(fl.0),
                us(p99) / us(fl.1)
            );
        }
    }
}
