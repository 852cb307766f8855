//! SOEM, a master we did not write, drives the raw-socket runner through
//! pysoem (PyPI) over a veth pair in a network namespace this test
//! creates: discovery and names, SDO and the abort codes SOEM decodes, SDO
//! Information against the ESI, complete access, the SII against `esi sii`,
//! the state machine, the SM watchdog, 1000 cycles, a second master session,
//! and a FoE firmware update in BOOT with refusals. The runner's capture is
//! then decoded by tshark, a dissector we did not write either.
//!
//! The SOEM side is `tests/interop/soem_interop.py`; its output (names,
//! abort codes, working counters) is printed into the test log. Needs root,
//! iproute2 and a Python with pysoem (`PAM_PYSOEM_PYTHON`, else `python3`);
//! skipped with a message otherwise, a failure under `CI=true`.

use crate::common::{runner_binary, setup, skip};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// A Python interpreter that can import pysoem.
pub(crate) fn pysoem_python() -> Option<String> {
    let mut candidates = Vec::new();
    if let Ok(p) = std::env::var("PAM_PYSOEM_PYTHON") {
        candidates.push(p);
    }
    candidates.push("python3".into());
    candidates.into_iter().find(|py| {
        Command::new(py)
            .args(["-c", "import pysoem"])
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    })
}

/// Starts the runner (`extra`: more arguments); its stderr goes to `log`.
#[allow(clippy::too_many_arguments)]
fn start_runner_with(
    ns: &str,
    bin: &Path,
    line: &str,
    iface: &str,
    state: &Path,
    pcap: &Path,
    log: &Path,
    extra: &[&str],
) -> Child {
    let stderr = std::fs::File::create(log).expect("runner log file");
    Command::new("ip")
        .args(["netns", "exec", ns])
        .arg(bin)
        .args(extra)
        .args(["--iface", iface])
        .args(if line.is_empty() {
            vec![]
        } else {
            vec!["--line", line]
        })
        .arg("--state-dir")
        .arg(state)
        .arg("--pcap")
        .arg(pcap)
        .stdout(Stdio::null())
        .stderr(stderr)
        .spawn()
        .expect("start pam-slave in the namespace")
}

/// Starts the runner; its stderr goes to `log`.
fn start_runner(
    ns: &str,
    bin: &Path,
    line: &str,
    iface: &str,
    state: &Path,
    pcap: &Path,
    log: &Path,
) -> Child {
    start_runner_with(ns, bin, line, iface, state, pcap, log, &[])
}

/// Ctrl-C to the runner (it flushes its capture and saves its state).
fn stop_runner(mut child: Child) {
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    for _ in 0..50 {
        if child.try_wait().ok().flatten().is_some() {
            return;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
}

pub(crate) fn run_python(py: &str, args: &[&str]) -> (bool, String) {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/interop/soem_interop.py");
    let out = Command::new(py)
        .arg(script)
        .args(args)
        .output()
        .expect("python runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

/// Appends to `target/interop-logs/<log>` (which `.ci/run` prints after
/// the tests: cargo shows a passing test's output only with --nocapture).
pub(crate) fn keep_log(log: &str, text: &str) {
    use std::io::Write as _;
    let dir = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../target/interop-logs"
    ));
    if std::fs::create_dir_all(&dir).is_ok()
        && let Ok(mut f) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(dir.join(log))
    {
        let _ = f.write_all(text.as_bytes());
    }
}

/// `tshark -T fields -e FIELD` over the capture: the numbers it shows
/// (tshark prints some fields in hex, others in decimal).
fn tshark_fields(pcap: &Path, filter: &str, field: &str) -> Option<Vec<u32>> {
    let out = Command::new("tshark")
        .arg("-r")
        .arg(pcap)
        .args(["-Y", filter, "-T", "fields", "-e", field])
        .output()
        .ok()?;
    out.status.success().then(|| {
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .flat_map(|l| l.split(','))
            .map(|s| s.trim().to_lowercase())
            .filter_map(|s| match s.strip_prefix("0x") {
                Some(h) => u32::from_str_radix(h, 16).ok(),
                None => s.parse().ok(),
            })
            .collect()
    })
}

struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// SOEM's phases 1 and 2 (see the script) against a runner serving the
/// 8-PAM line `line`; returns the directory holding phase 1's capture
/// (`phase1.pcap`), or `None` when the test had to be skipped.
fn soem_phases(tag: &str, line: &str, log: &str) -> Option<TempDir> {
    let Some(py) = pysoem_python() else {
        skip(
            "no Python with pysoem (pip install pysoem, or set PAM_PYSOEM_PYTHON); .ci/run installs it",
        );
        return None;
    };
    let Some(bin) = runner_binary() else {
        skip("pam-slave binary not built next to the test binary");
        return None;
    };
    let _serial = crate::common::NET_TESTS
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let (mut guard, host_if, slave_if) = match setup(tag) {
        Ok(x) => x,
        Err(e) => {
            skip(&format!(
                "cannot create a network namespace and veth pair here ({e}); needs root and iproute2"
            ));
            return None;
        }
    };
    let dir = TempDir(std::env::temp_dir().join(format!("pam-soem-{tag}-{}", std::process::id())));
    std::fs::create_dir_all(&dir.0).expect("temp dir");
    let file = |n: &str| dir.0.join(n);
    let esi = ecat_esi::generate(&pam_199_p_etc::DEVICE).expect("ESI");
    std::fs::write(file("pam.xml"), esi).expect("ESI file");
    std::fs::write(
        file("eeprom.bin"),
        ecat_esi::sii_image(&pam_199_p_etc::DEVICE),
    )
    .expect("SII file");
    let good = master_test::foe::pam_image("11", 40_000);
    let mut bad = good.clone();
    let last = bad.len() - 1;
    bad[last] ^= 0xFF;
    std::fs::write(file("good.efw"), &good).expect("image");
    std::fs::write(file("bad.efw"), &bad).expect("image");
    // Older than the factory firmware 10: the slave's anti-rollback.
    let old = master_test::foe::pam_image("9", 20_000);
    std::fs::write(file("old.efw"), &old).expect("image");
    let state = file("state");
    let s = |p: PathBuf| p.to_string_lossy().into_owned();
    let _ = std::fs::remove_file(
        PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../target/interop-logs"
        ))
        .join(log),
    );
    keep_log(log, &format!("=== pam-slave --line {line} ===\n"));

    // Phase 1: everything up to the firmware download and BOOT -> INIT.
    let runner = start_runner(
        &guard.name,
        &bin,
        line,
        &slave_if,
        &state,
        &file("phase1.pcap"),
        &file("runner1.log"),
    );
    guard.runner = Some(runner);
    crate::common::wait_for_runner(&host_if);
    let (ok, out) = run_python(
        &py,
        &[
            "phase1",
            &host_if,
            &s(file("pam.xml")),
            &s(file("eeprom.bin")),
            &s(file("good.efw")),
            &s(file("bad.efw")),
            "11",
            &s(file("old.efw")),
        ],
    );
    keep_log(log, &format!("--- SOEM phase 1 ---\n{out}"));
    eprintln!("--- SOEM phase 1 ({line}) ---\n{out}");
    stop_runner(guard.runner.take().expect("runner"));
    assert!(ok, "SOEM phase 1 on {line} failed (log above)");

    // The runner restarts on the same state directory: a power cycle.
    let runner = start_runner(
        &guard.name,
        &bin,
        line,
        &slave_if,
        &state,
        &file("phase2.pcap"),
        &file("runner2.log"),
    );
    guard.runner = Some(runner);
    crate::common::wait_for_runner(&host_if);
    let (ok, out) = run_python(&py, &["phase2", &host_if, "11"]);
    keep_log(log, &format!("--- SOEM phase 2 ---\n{out}"));
    eprintln!("--- SOEM phase 2 ({line}) ---\n{out}");
    stop_runner(guard.runner.take().expect("runner"));
    assert!(ok, "SOEM phase 2 on {line} failed (log above)");
    for run in ["runner1.log", "runner2.log"] {
        let text = std::fs::read_to_string(file(run)).unwrap_or_default();
        keep_log(log, &format!("--- {run} ---\n{text}"));
        eprintln!("--- {run} ---\n{text}");
        assert!(
            text.contains("stopped after"),
            "the runner stopped cleanly: {text}"
        );
        // Every frame answered ahead got the reply the ESCs then gave.
        assert!(!text.contains("differed"), "answers ahead: {text}");
        // Slaves on an SPI PDI: the emulated chips saw only well-formed
        // SPI and refused nothing.
        if line.contains('@') {
            assert!(
                text.contains(" transactions, 0 protocol errors, 0 refused accesses"),
                "SPI wires clean: {text}"
            );
        }
    }
    Some(dir)
}

/// The same SOEM phases with every PAM's firmware talking to its ESC
/// through an SPI driver and an emulated chip: four on the ET1100 driver,
/// four on the LAN9252 driver (the FoE update goes to the eighth, a
/// LAN9252 one).
#[test]
fn soem_drives_8_slaves_whose_firmware_runs_on_the_et1100_and_lan9252_spi_drivers() {
    soem_phases("q", "pam@et1100*4,pam@lan9252*4", "soem-spi.log");
}

#[test]
fn soem_through_pysoem_drives_8_runner_slaves_over_a_veth_pair() {
    let Some(dir) = soem_phases("s", "pam*8", "soem.log") else {
        return;
    };
    let file = |n: &str| dir.0.join(n);

    // tshark decodes every abort SOEM provoked as an SDO abort with its
    // code, and the FoE refusals with theirs.
    if Command::new("tshark").arg("--version").output().is_err() {
        return skip("tshark is not installed; the SOEM part passed");
    }
    let pcap = file("phase1.pcap");
    let aborts = tshark_fields(
        &pcap,
        "ecat_mailbox.coe.abortcode",
        "ecat_mailbox.coe.abortcode",
    )
    .expect("tshark reads the runner's capture");
    keep_log(
        "soem.log",
        &format!("tshark: SDO abort codes {aborts:#010x?}\n"),
    );
    eprintln!("tshark: SDO abort codes {aborts:#010x?}");
    for code in [
        0x0609_0031,
        0x0601_0002,
        0x0602_0000,
        0x0609_0011,
        0x0601_0000,
    ] {
        assert!(
            aborts.contains(&code),
            "tshark decodes abort {code:#010x}: {aborts:#010x?}"
        );
    }
    let foe_errors = tshark_fields(
        &pcap,
        "ecat_mailbox.foe_opmode == 5",
        "ecat_mailbox.foe_errcode",
    )
    .expect("tshark FoE");
    keep_log(
        "soem.log",
        &format!("tshark: FoE error codes {foe_errors:#06x?}\n"),
    );
    eprintln!("tshark: FoE error codes {foe_errors:#06x?}");
    assert!(
        foe_errors.contains(&0x800A),
        "wrong password answered 0x800A: {foe_errors:#06x?}"
    );
    assert!(
        foe_errors.contains(&0x800C),
        "corrupt image answered 0x800C: {foe_errors:#06x?}"
    );
    assert!(
        foe_errors.contains(&0x8002),
        "the older image SOEM sent answered 0x8002 (anti-rollback): {foe_errors:#06x?}"
    );
    assert_eq!(
        foe_errors.iter().filter(|&&c| c == 0x800A).count(),
        2,
        "0x800A for the wrong password and for the factory one after the owner's: {foe_errors:#06x?}"
    );
}

/// Starts the runner with `line` (and `runner_args`) in a fresh namespace
/// `tag`, runs the script's `phase` with `phase_args` after the host-side
/// interface, keeps its output as `target/interop-logs/soem-{name}.log`
/// and asserts that every check passed.
pub(crate) fn soem_phase(tag: &str, name: &str, line: &str, runner_args: &[&str], phase: &[&str]) {
    soem_power_cycled_phases(tag, name, line, runner_args, &[phase]);
}

/// [`soem_phase`] for several phases, the runner restarted on the same
/// state directory before each one after the first (a power cycle: saved
/// parameters and firmware survive, everything else starts afresh).
fn soem_power_cycled_phases(
    tag: &str,
    name: &str,
    line: &str,
    runner_args: &[&str],
    phases: &[&[&str]],
) {
    let Some(py) = pysoem_python() else {
        return skip(
            "no Python with pysoem (pip install pysoem, or set PAM_PYSOEM_PYTHON); .ci/run installs it",
        );
    };
    let Some(bin) = runner_binary() else {
        return skip("pam-slave binary not built next to the test binary");
    };
    let _serial = crate::common::NET_TESTS
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let (mut guard, host_if, slave_if) = match setup(tag) {
        Ok(x) => x,
        Err(e) => {
            return skip(&format!(
                "cannot create a network namespace and veth pair here ({e}); needs root and iproute2"
            ));
        }
    };
    let dir = TempDir(std::env::temp_dir().join(format!("pam-soem-{name}-{}", std::process::id())));
    std::fs::create_dir_all(&dir.0).expect("temp dir");
    let file = |n: &str| dir.0.join(n);
    let log = format!("soem-{name}.log");
    let _ = std::fs::remove_file(
        std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../target/interop-logs"
        ))
        .join(&log),
    );
    for (k, phase) in phases.iter().enumerate() {
        let runner = start_runner_with(
            &guard.name,
            &bin,
            line,
            &slave_if,
            &file("state"),
            &file(&format!("{name}-{k}.pcap")),
            &file(&format!("runner-{k}.log")),
            runner_args,
        );
        guard.runner = Some(runner);
        crate::common::wait_for_runner(&host_if);
        let mut args = vec![phase[0], host_if.as_str()];
        args.extend_from_slice(&phase[1..]);
        let (ok, out) = run_python(&py, &args);
        keep_log(&log, &format!("--- SOEM {name} {} ---\n{out}", phase[0]));
        eprintln!("--- SOEM {name} {} ---\n{out}", phase[0]);
        stop_runner(guard.runner.take().expect("runner"));
        assert!(ok, "SOEM {name} phase {} failed (log above)", phase[0]);
        let text = std::fs::read_to_string(file(&format!("runner-{k}.log"))).unwrap_or_default();
        eprintln!("--- runner-{k}.log ---\n{text}");
        assert!(
            text.contains("stopped after"),
            "the runner stopped cleanly: {text}"
        );
        // Every frame answered ahead (SOEM's DC frames among them) got
        // the reply the ESCs then gave.
        assert!(!text.contains("differed"), "answers ahead: {text}");
    }
}

/// The PAM's safety rules through SOEM (docs/SAFETY.md; issue 29 findings
/// 1-3): ENABLE and a command value written over SDO with no RxPDO drive
/// no current; DEFAULT and LOADBACK in OP that would change FUNCTION are
/// refused with 0x08000022 and FUNCTION stays; after SAVE and a power
/// cycle FUNCTION = IND comes back with its PDO set and SOEM reaches OP
/// without rewriting the assignment.
#[test]
fn soem_finds_the_pam_safe_when_it_drives_it_by_sdo_and_changes_function_behind_the_master() {
    soem_power_cycled_phases(
        "y",
        "safety",
        "pam",
        &[],
        &[&["safety"], &["safety_after_power_cycle"]],
    );
}

/// SOEM's Distributed Clocks against the runner: `config_dc`, `dcsync0`
/// on every slave, OP with SOEM's cycle (which distributes the reference
/// time), the slaves within 1 us of the reference, 0x1C32 in DC mode,
/// SYNC0 running, and a 10 us SYNC0 cycle refused with 0x0035 (the `dc`
/// phase of the script).
#[test]
fn soem_configures_distributed_clocks_and_runs_the_line_dc_synchronous() {
    // Oscillators up to ±30 ppm apart: SOEM's cycle must steer them.
    soem_phase(
        "d",
        "dc",
        "pam,io8,pam,io8",
        &["--oscillators", "30"],
        &["dc", "4"],
    );
}

/// The HCS DMA-22 node of 3 modules (the script's `dma22` phase): 0xF050,
/// a wrong 0xF030 refused with 0x0070 and its Emergency, OP with the right
/// one, the manual's 5.4.2 set values back from every module.
#[test]
fn soem_brings_a_dma22_node_with_three_modules_to_op_after_writing_0xf030() {
    soem_phase("h", "dma22", "dma22", &[], &["dma22"]);
}

/// The servo402 CiA 402 drive through SOEM (the script's `servo402`
/// phase): a PDO mapping of SOEM's own written in its configuration hook
/// (the refusals on the way checked by abort code), the assignment and
/// CSP in PRE-OP, the images sized from the written mapping, DC with SYNC0
/// every 1 ms, OP, the drive's state machine to Operation enabled, a
/// target ramp the position follows, a quick stop to Switch on disabled.
#[test]
fn soem_drives_servo402_to_operation_enabled_in_csp_on_sync0_and_the_position_follows() {
    soem_phase("w", "servo402", "servo402", &[], &["servo402"]);
}

/// A line built from an ENI (`pam-slave --eni`, the script's `twins`
/// phase): EK1100, EL2004, EL2828 twins from their ESI files, an EL1008
/// twin counting, the PAM built in, and a CoE twin from an ESI (the IO8's,
/// under another product code so the catalog does not claim it); SOEM
/// downloads the ENI's CoE init commands, sees the identities, names and
/// image sizes of the real devices' SII dumps and runs the line in OP.
#[test]
fn soem_runs_an_eni_line_of_esi_twins_and_a_pam_with_the_real_devices_identities() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/testdata");
    let dir = std::env::temp_dir().join(format!("pam-soem-eni-{}", std::process::id()));
    let esi_dir = dir.join("esi");
    std::fs::create_dir_all(&esi_dir).expect("dir");
    for f in std::fs::read_dir(root.join("esi")).expect("testdata") {
        let f = f.expect("entry").path();
        std::fs::copy(&f, esi_dir.join(f.file_name().expect("name"))).expect("copy");
    }
    let (esi, eni) = crate::twins::coe_twin_line(
        &std::fs::read_to_string(root.join("machine.xml")).expect("ENI"),
    );
    std::fs::write(esi_dir.join("IO8-twin.xml"), esi).expect("write");
    let eni_path = dir.join("machine.xml");
    std::fs::write(&eni_path, eni).expect("write");
    let spec = crate::twins::soem_expectations();
    let eni_arg = eni_path.to_str().expect("utf-8 path").to_string();
    soem_phase(
        "t",
        "twins",
        "",
        &[
            "--eni",
            &eni_arg,
            "--esi-dir",
            esi_dir.to_str().expect("utf-8 path"),
            "--inputs",
            "counter",
        ],
        &["twins", &spec, &eni_arg],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A twin of a device with CoE built from its ESI alone (the script's
/// `esi_twin` phase): the IO8's generated ESI served by `pam-slave --esi`
/// with looped-back inputs; SOEM checks identity, SDO Information against
/// the ESI, the image sizes, OP and the loopback.
#[test]
fn soem_drives_a_coe_twin_built_from_an_esi_file() {
    let esi = ecat_esi::generate(&io8_example::DEVICE).expect("ESI");
    soem_esi_twin_phase("e", "esi-twin", &esi);
}

/// SOEM's `esi_twin` phase on a twin the runner builds from `esi`
/// (written to a temporary file, removed after).
fn soem_esi_twin_phase(netns_tag: &str, name: &str, esi: &[u8]) {
    let dir = std::env::temp_dir().join(format!("pam-soem-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join(format!("{name}.xml"));
    std::fs::write(&file, esi).expect("write");
    let path = file.to_str().expect("utf-8 path").to_string();
    soem_phase(
        netns_tag,
        name,
        "",
        &["--esi", &path, "--inputs", "loopback"],
        &["esi_twin", &path],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The same twin from an ESI that offers neither SDO Information nor
/// complete access (`esi_twin` reads the ESI's `Mailbox/CoE`): SOEM's OD
/// list read is refused and its complete-access upload aborted with
/// 0x06010000, while the rest runs as before.
#[test]
fn soem_finds_the_coe_services_a_twins_esi_does_not_offer_refused() {
    let esi = crate::common::io8_esi_without_sdo_info_nor_complete_access();
    soem_esi_twin_phase("f", "esi-twin-no-info", esi.as_bytes());
}
