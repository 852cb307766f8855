//! Helpers shared by the integration tests.

use ethercrab::error::{Error, MailboxError};
use std::path::PathBuf;
use std::process::{Child, Command};

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
