//! Helpers shared by the integration tests.

use ethercrab::error::{Error, MailboxError};
use std::path::PathBuf;
use std::process::{Child, Command};
use std::time::Duration;

/// The CoE abort code inside an ethercrab SDO error, if it is one.
pub fn abort_code(e: &Error) -> Option<u32> {
    match e {
        Error::Mailbox(MailboxError::Aborted { code, .. }) => Some(u32::from(*code)),
        _ => None,
    }
}

/// Held by the tests that run `pam-slave` on a veth pair, so two runners
/// and their masters do not compete for the two cores at the same time.
pub static NET_TESTS: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Says why a test cannot run here and returns; under `CI=true` (as
/// `.ci/run` sets it) a skip is a failure, so CI never passes by skipping.
pub fn skip(reason: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("cannot run under CI=true: {reason}");
    }
    eprintln!("SKIPPED: {reason}");
}

/// A network namespace (and the veth end inside it) with the runner
/// process started in it; both are removed on drop, even when a test fails.
pub struct Netns {
    /// Namespace name.
    pub name: String,
    /// The runner started in it.
    pub runner: Option<Child>,
}

impl Drop for Netns {
    fn drop(&mut self) {
        if let Some(mut c) = self.runner.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
        let _ = Command::new("ip")
            .args(["netns", "del", &self.name])
            .status();
    }
}

pub fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("ip: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// The `pam-slave` binary next to this test binary, built on demand
/// (`cargo test` builds other packages' binaries only as test harnesses).
pub fn runner_binary() -> Option<PathBuf> {
    binary("device-catalog", "pam-slave")
}

/// Binary `bin` of workspace package `package`, (re)built next to this
/// test binary: cargo does nothing when it is up to date, and a stale
/// binary from an older checkout must not be tested.
pub fn binary(package: &str, bin: &str) -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    let dir = exe.parent()?.parent()?;
    let path = dir.join(bin);
    let profile_release = dir.file_name().is_some_and(|n| n == "release");
    let mut cmd = Command::new(env!("CARGO"));
    cmd.args(["build", "-q", "-p", package, "--bin", bin]);
    if profile_release {
        cmd.arg("--release");
    }
    let _ = cmd.status();
    path.exists().then_some(path)
}

/// Creates namespace + veth, or explains why the test cannot run here.
pub fn setup(tag: &str) -> Result<(Netns, String, String), String> {
    let pid = std::process::id();
    let ns = format!("pam{tag}{pid}");
    // Interface names are global (at most 15 bytes): tag them per test.
    let host_if = format!("pm{pid}{tag}m");
    let slave_if = format!("pm{pid}{tag}s");
    ip(&["netns", "add", &ns])?;
    let guard = Netns {
        name: ns.clone(),
        runner: None,
    };
    ip(&[
        "link", "add", &host_if, "type", "veth", "peer", "name", &slave_if, "netns", &ns,
    ])?;
    ip(&["link", "set", &host_if, "up"])?;
    ip(&["-n", &ns, "link", "set", &slave_if, "up"])?;
    ip(&["-n", &ns, "link", "set", "lo", "up"])?;
    Ok((guard, host_if, slave_if))
}

/// The master type of the tests.
pub type Md = ethercrab::MainDevice<'static>;

/// AL status (0x0130) and AL status code (0x0134) of `station`.
pub async fn status(md: &Md, station: u16) -> (u16, u16) {
    let st: u16 = ethercrab::Command::fprd(station, 0x0130)
        .receive(md)
        .await
        .expect("AL status");
    let code: u16 = ethercrab::Command::fprd(station, 0x0134)
        .receive(md)
        .await
        .expect("AL status code");
    (st, code)
}

/// A few frames, so the link thread polls the firmware after each.
pub async fn settle(md: &Md) {
    for _ in 0..3 {
        let _: u8 = ethercrab::Command::brd(0x0000)
            .receive(md)
            .await
            .expect("poll");
    }
}

/// Writes AL control and returns (AL status, AL status code) once the
/// firmware has run.
pub async fn request(md: &Md, station: u16, control: u16) -> (u16, u16) {
    ethercrab::Command::fpwr(station, 0x0120)
        .send(md, control)
        .await
        .expect("AL control");
    settle(md).await;
    status(md, station).await
}

/// Waits until a runner on the far end of `host_if` answers EtherCAT
/// frames (a BRD of register 0x0000 comes back processed), instead of
/// guessing how long it takes to start on a busy machine. Panics after
/// 60 s.
pub fn wait_for_runner(host_if: &str) {
    wait_for_line(host_if, None);
}

/// Ethernet (broadcast, from a master), EtherCAT header (one datagram of
/// 10 + 2 + 2 bytes, type 1), BRD 0x0000 of 2 bytes, working counter.
pub fn brd_frame() -> Vec<u8> {
    let mut frame = vec![0xFFu8; 6];
    frame.extend_from_slice(&[0x10, 0, 0, 0, 0, 1, 0x88, 0xA4]);
    frame.extend_from_slice(&[14, 0x10]);
    frame.extend_from_slice(&[0x07, 0x5A, 0, 0, 0, 0, 2, 0, 0, 0]);
    frame.extend_from_slice(&[0, 0, 0, 0]);
    frame.resize(60, 0);
    frame
}

/// [`wait_for_runner`] until `slaves` slaves answer (the BRD's working
/// counter), e.g. after a cable between chained runners was pulled or
/// plugged back; `None`: any answer.
pub fn wait_for_line(host_if: &str, slaves: Option<u16>) {
    let ifaces = pnet_datalink::interfaces();
    let nic = ifaces
        .iter()
        .find(|i| i.name == host_if)
        .unwrap_or_else(|| panic!("no interface {host_if}"));
    let cfg = pnet_datalink::Config {
        read_timeout: Some(Duration::from_millis(20)),
        ..pnet_datalink::Config::default()
    };
    let Ok(pnet_datalink::Channel::Ethernet(mut tx, mut rx)) = pnet_datalink::channel(nic, cfg)
    else {
        panic!("raw socket on {host_if}");
    };
    let frame = brd_frame();
    let start = std::time::Instant::now();
    let mut last = None;
    while start.elapsed() < Duration::from_secs(60) {
        let _ = tx.send_to(&frame, None);
        let sent = std::time::Instant::now();
        while sent.elapsed() < Duration::from_millis(50) {
            if let Ok(f) = rx.next()
                && ecat_sim::raw::is_processed(f)
            {
                let wkc = f.get(28..30).map(|b| u16::from_le_bytes([b[0], b[1]]));
                if slaves.is_none() || wkc == slaves {
                    return;
                }
                last = wkc;
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    panic!("no line of {slaves:?} slaves answered on {host_if} within 60 s (last: {last:?})");
}

/// The IO8's generated ESI with `SdoInfo` and `CompleteAccess` cleared: a
/// device description that offers neither service (twin and SOEM tests).
pub fn io8_esi_without_sdo_info_nor_complete_access() -> String {
    let xml =
        String::from_utf8(ecat_esi::generate(&io8_example::DEVICE).expect("ESI")).expect("utf-8");
    let edited = xml.replacen("SdoInfo=\"1\"", "SdoInfo=\"0\"", 1).replacen(
        "CompleteAccess=\"1\"",
        "CompleteAccess=\"0\"",
        1,
    );
    assert_ne!(edited, xml, "the ESI offered both");
    edited
}
