//! The command-line tools as a user (or a script) runs them: `master-test`,
//! `esi` and `pam-slave` as processes, their output, their exit status
//! (0 ok, 1 refused by the device or mismatch, 2 usage or input error,
//! 3 communication, 130 Ctrl-C), closed pipes, Ctrl-C, and `master-test
//! --iface` against the raw runner over a veth pair.

mod snapshots;

use crate::common::{binary, runner_binary, setup, skip};
use assert_cmd::Command;
use std::io::{BufRead as _, BufReader, Read as _};
use std::path::PathBuf;
use std::process::{Output, Stdio};
use std::time::{Duration, Instant};

fn master_test() -> PathBuf {
    binary("master-test", "master-test").expect("master-test builds")
}

fn esi() -> PathBuf {
    binary("ecat-esi", "esi").expect("esi builds")
}

fn run(bin: &PathBuf, args: &[&str]) -> Output {
    Command::new(bin)
        .args(args)
        .timeout(Duration::from_secs(120))
        .output()
        .expect("the tool runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Runs and checks the exit status; returns (stdout, stderr).
fn expect(bin: &PathBuf, args: &[&str], code: i32) -> (String, String) {
    let out = run(bin, args);
    let (o, e) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(
        out.status.code(),
        Some(code),
        "{} {args:?}\nstdout:\n{o}\nstderr:\n{e}",
        bin.display()
    );
    assert!(!e.contains("panicked"), "{args:?} panicked:\n{e}");
    (o, e)
}

/// Starts `bin args`, reads `lines` lines of its output, then closes the
/// pipe (as `| head -N` does) and returns its exit status and stderr.
fn close_after(bin: &PathBuf, args: &[&str], lines: usize) -> (Option<i32>, String) {
    let mut child = std::process::Command::new(bin)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start");
    let stdout = child.stdout.take().expect("stdout");
    let mut reader = BufReader::new(stdout);
    for _ in 0..lines {
        let mut line = String::new();
        if reader.read_line(&mut line).unwrap_or(0) == 0 {
            break;
        }
    }
    drop(reader);
    let mut err = String::new();
    let mut stderr = child.stderr.take().expect("stderr");
    let status = wait(&mut child, Duration::from_secs(120));
    let _ = stderr.read_to_string(&mut err);
    (status, err)
}

fn wait(child: &mut std::process::Child, limit: Duration) -> Option<i32> {
    let start = Instant::now();
    loop {
        if let Ok(Some(st)) = child.try_wait() {
            return st.code();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("the tool did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn broken_pipes_end_quietly_with_status_0() {
    let mt = master_test();
    // `master-test demo | head -1`
    let (code, err) = close_after(&mt, &["demo", "--cycles", "2000"], 1);
    assert_eq!(code, Some(0), "demo | head -1: {err}");
    assert!(!err.contains("panicked"), "{err}");
    // `sdo read ... | head -0`
    let (code, err) = close_after(&mt, &["sdo", "read", "0x800D:02"], 0);
    assert_eq!(code, Some(0), "sdo read | head -0: {err}");
    // `foe read info.txt | true`
    let (code, err) = close_after(&mt, &["foe", "read", "info.txt"], 0);
    assert_eq!(code, Some(0), "foe read | true: {err}");
    // `od dump | head -3`
    let (code, err) = close_after(&mt, &["od", "dump"], 3);
    assert_eq!(code, Some(0), "od dump | head -3: {err}");
    // `esi generate | head`
    let (code, err) = close_after(&esi(), &["generate"], 10);
    assert_eq!(code, Some(0), "esi generate | head: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn subindices_paste_back_exactly_as_printed() {
    let mt = master_test();
    // Printed as 0x8006:2A: it must read back as 0x2A, not fail.
    let (o, _) = expect(&mt, &["sdo", "read", "0x8006:2A"], 0);
    assert!(o.starts_with("0x8006:2A "), "{o}");
    // "10" is 0x10 as printed, not decimal ten (0x0A).
    let (o, _) = expect(&mt, &["sdo", "read", "0x8006:10"], 0);
    assert!(o.starts_with("0x8006:10 "), "{o}");
    let (o, _) = expect(&mt, &["sdo", "read", "8006:0x2a"], 0);
    assert!(o.starts_with("0x8006:2A "), "{o}");
    // Every address `od dump` prints pastes into `sdo read` and names the
    // same entry.
    let (dump, _) = expect(&mt, &["od", "dump"], 0);
    let line = dump
        .lines()
        .find(|l| l.trim_start().starts_with("8006:2A"))
        .expect("od dump lists 8006:2A");
    let address = line.split_whitespace().next().expect("address column");
    let name = line.split_whitespace().nth(1).expect("name column");
    let (o, _) = expect(&mt, &["sdo", "read", address], 0);
    assert!(o.contains(name), "{address}: {o} (od dump: {line})");
    let (_, e) = expect(&mt, &["sdo", "read", "0x8006:2G"], 2);
    assert!(e.contains("not a hex number"), "{e}");
}

#[test]
fn exit_status_says_refused_input_or_communication() {
    let mt = master_test();
    // Out of the range SDO Information gives: refused before sending.
    let (_, e) = expect(&mt, &["sdo", "write", "0x800D:02", "5000"], 2);
    assert!(e.contains("500..=3000 mA"), "{e}");
    assert!(e.contains("nothing was sent"), "{e}");
    // The same value sent anyway: the device refuses it (abort 0x06090031).
    let (_, e) = expect(&mt, &["sdo", "write", "0x800D:02", "5000", "--no-check"], 1);
    assert!(e.contains("0x06090031"), "{e}");
    // A read-only entry: the device refuses.
    let (_, e) = expect(&mt, &["sdo", "write", "0x1018:01", "5"], 1);
    assert!(e.contains("0x06010002"), "{e}");
    // An object that does not exist: the device says so.
    let (_, e) = expect(&mt, &["sdo", "read", "0x1234:00"], 1);
    assert!(e.contains("0x06020000"), "{e}");
    // Usage errors.
    expect(&mt, &["sdo", "read", "0x800D"], 2);
    expect(&mt, &["--slave", "3", "sdo", "read", "0x1000:00"], 2);
    expect(&mt, &["--line", "pam,io8", "sdo", "read", "0x1000:00"], 2);
    expect(&mt, &["--line", "pam,nope", "scan"], 2);
    expect(&mt, &["no-such-command"], 2);
    // An interface that does not exist: communication.
    let (_, e) = expect(&mt, &["--iface", "nosuchif0", "scan"], 3);
    assert!(e.contains("nosuchif0"), "{e}");
    // The help documents the scheme.
    let (o, _) = expect(&mt, &["--help"], 0);
    for needle in [
        "Exit status:",
        "1    the device refused",
        "2    usage",
        "130",
    ] {
        assert!(o.contains(needle), "--help lacks '{needle}':\n{o}");
    }
}

#[test]
fn cli_limits_are_refused_before_anything_runs() {
    let mt = master_test();
    for (args, needle) in [
        (&["demo", "--current", "5000"][..], "500..=3000"),
        (&["demo", "--current", "-1"][..], "500..=3000"),
        (&["demo", "--command", "20000"][..], "-10000..=10000"),
        (&["demo", "--cycles", "4000000000"][..], "3600000"),
        (&["demo", "--slaves", "0"][..], "1..=1024"),
        (&["demo", "--slaves", "1025"][..], "1..=1024"),
        (&["demo", "--line", "io8*1025"][..], "at most 1024"),
        (&["--line", "io8*65", "scan"][..], "at most 64"),
        (&["--line", "pam*4097", "scan"][..], "1 to 4096"),
    ] {
        let (o, e) = expect(&mt, args, 2);
        assert!(e.contains(needle), "{args:?}: {e}");
        assert!(o.is_empty(), "{args:?} ran: {o}");
    }
    // The help names ranges and units.
    let (o, _) = expect(&mt, &["demo", "--help"], 0);
    assert!(o.contains("500..=3000 mA"), "{o}");
    assert!(o.contains("-10000..=10000"), "{o}");
    let runner = runner_binary().expect("pam-slave builds");
    let (o, e) = expect(&runner, &["--iface", "lo", "--count", "0"], 2);
    assert!(e.contains("1..=4096"), "{e}");
    assert!(
        !o.contains("slave") && !e.contains("Ctrl-C stops"),
        "{o}{e}"
    );
}

/// The demo runs lines up to the long group's 1024 slaves (the runner's
/// 4096 are beyond ethercrab's group here): every slave reaches OP, the
/// working counter counts them all, and the last slave is shown.
#[test]
fn the_demo_brings_1024_slaves_to_op_and_shows_the_last() {
    let mt = master_test();
    let (o, e) = expect(&mt, &["demo", "--slaves", "1024", "--cycles", "1"], 0);
    assert!(o.contains("(1024 slave(s): pam*1024)"), "{o}{e}");
    assert!(o.contains("found 0x13ff PAM-199-P-ETC"), "{o}");
    assert!(o.contains("state: OP"), "{o}");
    // 1024 PAMs, each read (+1) and written (+2) by the LRWs (ethercrab
    // sums the frames' counters: a slave whose image spans two frames
    // counts in both).
    let wkc: u32 = o
        .split("wkc ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .and_then(|t| t.parse().ok())
        .expect("a working counter");
    assert!(wkc >= 3072, "wkc {wkc}");
    assert!(
        o.lines()
            .any(|l| l.starts_with("slave 1023 PAM-199-P-ETC: ENABLE = 1")),
        "{o}"
    );
    assert!(o.contains("... the same on 1020 more PAM(s)"), "{o}");
}

#[test]
fn demo_summary_shows_both_solenoids() {
    let mt = master_test();
    let (o, _) = expect(&mt, &["demo", "--command", "-2500", "--cycles", "400"], 0);
    let summary = o
        .lines()
        .find(|l| l.starts_with("slave 0 "))
        .expect("summary line");
    let current = |name: &str| -> u32 {
        let at = summary
            .find(&format!("{name} = "))
            .unwrap_or_else(|| panic!("{name} missing: {summary}"));
        summary[at + name.len() + 3..]
            .split(' ')
            .next()
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{name} value: {summary}"))
    };
    // A negative command drives solenoid B; A stays off.
    assert_eq!(current("IA"), 0, "{summary}");
    assert!(current("IB") > 0, "{summary}");
}

#[test]
fn firmware_images_are_checked_and_downgrades_need_confirmation() {
    let mt = master_test();
    let dir = std::env::temp_dir().join(format!("mt-fw-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let p = |n: &str| dir.join(n).to_string_lossy().into_owned();
    std::fs::write(p("empty.bin"), b"").expect("write");
    std::fs::write(p("app.bin"), vec![0x5Au8; 3000]).expect("write");
    let (_, e) = expect(
        &mt,
        &[
            "firmware",
            "pack",
            &p("empty.bin"),
            "--version",
            "11",
            "-o",
            &p("e.efw"),
        ],
        2,
    );
    assert!(e.contains("empty"), "{e}");
    assert!(!dir.join("e.efw").exists());
    let (_, e) = expect(
        &mt,
        &[
            "firmware",
            "pack",
            &p("app.bin"),
            "--version",
            "11",
            "-o",
            &p("x.efw"),
            "--revision-min",
            "9",
            "--revision-max",
            "2",
        ],
        2,
    );
    assert!(
        e.contains("--revision-min 9 is above --revision-max 2"),
        "{e}"
    );
    expect(
        &mt,
        &[
            "firmware",
            "pack",
            &p("app.bin"),
            "--version",
            "9",
            "-o",
            &p("old.efw"),
        ],
        0,
    );
    let (_, e) = expect(
        &mt,
        &["foe", "write", &p("old.efw"), "--password", "123456789"],
        2,
    );
    assert!(e.contains("1 to 8 hex digits"), "{e}");
    // The slave runs 10: version 9 is a downgrade.
    let (o, e) = expect(&mt, &["foe", "write", &p("old.efw")], 2);
    assert!(e.contains("--allow-downgrade"), "{e}");
    assert!(!o.contains("downloaded"), "{o}");
    let (o, e) = expect(
        &mt,
        &["foe", "write", &p("old.efw"), "--allow-downgrade"],
        0,
    );
    assert!(e.contains("warning: downgrading"), "{e}");
    assert!(o.contains("0x100A SOFTWARE VERSION = 9"), "{o}");
    // An image without payload (packed by another tool) is refused too.
    let empty = master_test::foe::efw_image(
        pam_199_p_etc::VENDOR_ID,
        pam_199_p_etc::PRODUCT_CODE,
        "12",
        &[],
    );
    std::fs::write(p("empty.efw"), empty).expect("write");
    let (_, e) = expect(&mt, &["foe", "write", &p("empty.efw")], 2);
    assert!(e.contains("empty payload"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ctrl_c_stops_the_demo_in_order_and_says_where_it_left_the_slaves() {
    let mt = master_test();
    let mut child = std::process::Command::new(&mt)
        .args(["demo", "--cycles", "3600000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start");
    let stdout = child.stdout.take().expect("stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut all = String::new();
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if line.starts_with("driving") {
                let _ = tx.send(());
            }
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    rx.recv_timeout(Duration::from_secs(60))
        .expect("the demo reaches OP");
    std::thread::sleep(Duration::from_millis(200));
    let killed = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let code = wait(&mut child, Duration::from_secs(60));
    let out = reader.join().expect("reader");
    let mut err = String::new();
    let _ = child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut err);
    assert_eq!(code, Some(130), "stdout:\n{out}\nstderr:\n{err}");
    assert!(err.contains("left in INIT"), "{err}");
    assert!(out.contains("state: INIT (done)"), "{out}");
}

#[test]
fn esi_tool_exit_codes_and_pipes() {
    let esi = esi();
    let dir = std::env::temp_dir().join(format!("esi-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let garbage = dir.join("garbage.bin");
    std::fs::write(&garbage, vec![0xA5u8; 300]).expect("write");
    // Problems found: exit 1, not 0.
    let (o, _) = expect(&esi, &["inspect", &garbage.to_string_lossy()], 1);
    assert!(!o.is_empty());
    let xml = dir.join("pam.xml");
    expect(&esi, &["generate", "-o", &xml.to_string_lossy()], 0);
    let (_, e) = expect(&esi, &["inspect", &xml.to_string_lossy()], 2);
    assert!(e.contains("ESI") || e.contains("XML"), "{e}");
    // Our own image: no problems.
    let sii = dir.join("pam.bin");
    expect(&esi, &["sii", "-o", &sii.to_string_lossy()], 0);
    expect(&esi, &["inspect", &sii.to_string_lossy()], 0);
    let (o, _) = expect(&esi, &["--help"], 0);
    assert!(o.contains("Exit status:"), "{o}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 250 000-deep XML file (1.75 MB) is refused by every tool that reads
/// ESI or ENI files with exit 2 and the line where it nests too deep; it
/// used to overflow the stack and abort them.
#[test]
fn deeply_nested_xml_is_refused_by_the_tools_with_its_line() {
    let dir = std::env::temp_dir().join(format!("deep-xml-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let deep = |root: &str| {
        let path = dir.join(format!("{root}.xml"));
        let text = format!(
            "<{root}>\n{}{}</{root}>",
            "<a>\n".repeat(250_000),
            "</a>".repeat(250_000)
        );
        std::fs::write(&path, text).expect("write");
        path.to_string_lossy().into_owned()
    };
    let (esi_file, eni_file) = (deep("EtherCATInfo"), deep("EtherCATConfig"));
    let says = |e: &str| {
        assert!(
            e.contains("line 257") && e.contains("XML nested deeper than 256 elements"),
            "{e}"
        );
    };
    let sii = dir.join("pam.bin").to_string_lossy().into_owned();
    expect(&esi(), &["sii", "-o", &sii], 0);
    let (_, e) = expect(&esi(), &["check", &esi_file, &sii], 2);
    says(&e);
    let esi_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/testdata/esi");
    let esi_dir = esi_dir.to_str().expect("utf-8");
    let (_, e) = expect(
        &master_test(),
        &["--eni", &eni_file, "--esi-dir", esi_dir, "scan"],
        2,
    );
    says(&e);
    if let Some(runner) = runner_binary() {
        let (_, e) = expect(
            &runner,
            &["--iface", "no-such-if0", "--esi", &esi_file, "--type", "X"],
            2,
        );
        says(&e);
        let (_, e) = expect(
            &runner,
            &[
                "--iface",
                "no-such-if0",
                "--eni",
                &eni_file,
                "--esi-dir",
                esi_dir,
            ],
            2,
        );
        says(&e);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn master_test_iface_drives_the_raw_runner_over_veth() {
    let Some(runner) = runner_binary() else {
        return skip("pam-slave binary not built");
    };
    let mt = master_test();
    let _serial = crate::common::NET_TESTS
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let (mut guard, host_if, slave_if) = match setup("c") {
        Ok(x) => x,
        Err(e) => {
            return skip(&format!(
                "cannot create a network namespace and veth pair here ({e}); needs root and iproute2"
            ));
        }
    };
    let child = std::process::Command::new("ip")
        .args(["netns", "exec", &guard.name])
        .arg(&runner)
        .args(["--iface", &slave_if, "--line", "pam,io8"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start pam-slave in the namespace");
    guard.runner = Some(child);
    crate::common::wait_for_runner(&host_if);
    let on = |args: &[&str], code: i32| {
        let mut all = vec!["--iface", host_if.as_str()];
        all.extend_from_slice(args);
        expect(&mt, &all, code)
    };
    let (o, _) = on(&["scan"], 0);
    assert!(o.contains("PAM-199-P-ETC") && o.contains("IO8"), "{o}");
    assert!(o.contains("0x1001"), "{o}");
    // Two slaves: the tool asks which one.
    let (_, e) = on(&["sdo", "read", "0x1008:00"], 2);
    assert!(e.contains("--slave"), "{e}");
    // The runner keeps its state between commands (unlike the virtual bus).
    on(&["--slave", "0", "sdo", "write", "0x800D:02", "2500"], 0);
    let (o, _) = on(&["--slave", "0", "sdo", "read", "0x800D:02"], 0);
    assert!(o.contains("CURRENT = 2500 mA"), "{o}");
    let (_, e) = on(&["--slave", "0", "sdo", "write", "0x800D:02", "5000"], 2);
    assert!(e.contains("500..=3000 mA"), "{e}");
    let (o, _) = on(&["--station", "0x1001", "sdo", "read", "0x1008:00"], 0);
    assert!(o.contains("= IO8"), "{o}");
    let (o, _) = on(&["--station", "0x1001", "esi", "check"], 0);
    assert!(o.contains("agrees"), "{o}");
    let (o, _) = on(&["--slave", "0", "esi", "check"], 0);
    assert!(o.contains("agrees"), "{o}");
    let (o, _) = on(
        &[
            "--slave",
            "1",
            "watch",
            "--cycles",
            "50",
            "--interval",
            "10",
        ],
        0,
    );
    assert!(o.contains("Input 1=false"), "{o}");
    let (o, _) = on(&["state"], 0);
    assert!(o.contains("PRE-OP"), "{o}");
    let (o, _) = on(&["--slave", "0", "od", "dump", "--json"], 0);
    let v: serde_json::Value = serde_json::from_str(&o).expect("od dump --json is JSON");
    assert!(v.as_array().is_some_and(|a| a.len() > 20), "{o}");
    let sii = std::env::temp_dir().join(format!("mt-sii-{}.bin", std::process::id()));
    on(
        &[
            "--slave",
            "0",
            "eeprom",
            "read",
            "-o",
            &sii.to_string_lossy(),
        ],
        0,
    );
    let image = std::fs::read(&sii).expect("SII written");
    // Everything up to the end marker; the generated image only pads
    // (0xFF) after it.
    let full = ecat_esi::sii_image(&pam_199_p_etc::DEVICE);
    assert_eq!(image, full[..image.len()]);
    assert!(full[image.len()..].iter().all(|&b| b == 0xFF));
    let _ = std::fs::remove_file(&sii);
    let fw = std::env::temp_dir().join(format!("mt-fw-{}.efw", std::process::id()));
    std::fs::write(&fw, master_test::foe::pam_image("11", 4000)).expect("write");
    let (o, _) = on(&["--slave", "0", "foe", "write", &fw.to_string_lossy()], 0);
    assert!(o.contains("downloaded 4056 bytes"), "{o}");
    let _ = std::fs::remove_file(&fw);
}

/// Runs `bin args` with standard output on a pseudo-terminal (util-linux
/// `script`), as a user at a shell does; `None` where `script` is missing.
fn on_terminal(bin: &std::path::Path, args: &[&str]) -> Option<(Option<i32>, String)> {
    let line = std::iter::once(bin.to_string_lossy().into_owned())
        .chain(args.iter().map(|a| a.to_string()))
        .collect::<Vec<_>>()
        .join(" ");
    let out = std::process::Command::new("script")
        .args(["-qec", &line, "/dev/null"])
        .stdin(Stdio::null())
        .output()
        .ok()?;
    Some((out.status.code(), text(&out.stdout)))
}

#[test]
fn binary_output_is_refused_on_a_terminal_but_not_in_a_pipe() {
    let esi = esi();
    let mt = master_test();
    let Some((code, out)) = on_terminal(&esi, &["sii"]) else {
        return skip("util-linux `script` (for a pseudo-terminal) is missing");
    };
    assert_eq!(code, Some(2), "{out}");
    assert!(
        out.contains("refusing to write a binary image to a terminal"),
        "{out}"
    );
    let (code, out) = on_terminal(&mt, &["eeprom", "read", "--format", "bin"]).expect("script");
    assert_eq!(code, Some(2), "{out}");
    assert!(
        out.contains("refusing to write binary to a terminal"),
        "{out}"
    );
    // The same commands into a pipe give the image.
    let image = run(&esi, &["sii"]);
    assert!(image.status.success());
    assert_eq!(image.stdout, ecat_esi::sii_image(&pam_199_p_etc::DEVICE));
    let read = run(&mt, &["eeprom", "read", "--format", "bin"]);
    assert!(read.status.success());
    assert_eq!(read.stdout, image.stdout[..read.stdout.len()]);
}

#[test]
fn master_test_hcs_sends_cmd3_cmd6_cmd15_through_the_dma22_channel() {
    let mt = master_test();
    let dev = ["--device", "dma22", "hcs"];
    let args =
        |rest: &[&'static str]| -> Vec<&'static str> { dev.iter().chain(rest).copied().collect() };
    // CMD 3: software version (ID 0x00, "10.01") of module 1.
    let (o, _) = expect(&mt, &args(&["read", "--module", "1", "0x00"]), 0);
    assert!(o.contains("response 01 01 03 02 03 e9"), "{o}");
    assert!(o.contains("module 1: word 0: 1001"), "{o}");
    // CMD 6: A1.01 of module 3 = -9.999 V, answered with the request.
    let (o, _) = expect(&mt, &args(&["write", "--module", "3", "0x1F", "-9999"]), 0);
    assert!(o.contains("module 3: ID 0x001F written: -9999"), "{o}");
    // A read-only parameter: the node's exception 4, exit 1.
    let (_, e) = expect(&mt, &args(&["write", "0x07", "5"]), 1);
    assert!(e.contains("EXCE 4: Writing of ID failed"), "{e}");
    // A module that is not plugged: exception 5.
    let (_, e) = expect(&mt, &args(&["read", "--module", "5", "0x07"]), 1);
    assert!(e.contains("EXCE 5"), "{e}");
    // CMD 15 for three modules: module 1 answers first, HW enable set.
    let (o, _) = expect(&mt, &args(&["multi", "--values", "1000,2000,-3000"]), 0);
    assert!(o.contains("module 1: status 0x0400"), "{o}");
    // Bad input is refused before anything is sent.
    let (_, e) = expect(&mt, &args(&["read", "0x07", "--words", "9"]), 2);
    assert!(e.contains("CMD 3"), "{e}");
    let (_, e) = expect(&mt, &args(&["multi", "--values", "1,2,3,4,5,6"]), 2);
    assert!(e.contains("CMD 15"), "{e}");
    for bad in ["zz", "a\u{e9}1", "123"] {
        let (_, e) = expect(&mt, &args(&["raw", bad]), 2);
        assert!(e.contains("hex"), "{bad}: {e}");
    }
    // A device without the channel says so.
    let (_, e) = expect(&mt, &["--device", "io8", "hcs", "read", "0x07"], 1);
    assert!(e.contains("no HCS telegram channel"), "{e}");
}

/// `master-test --eni FILE --esi-dir DIR` runs the commissioning commands on
/// the virtual bus holding the ENI's line (twins and built-in devices),
/// without root; an ENI whose slaves nothing matches is refused with exit
/// 2 naming them.
#[test]
fn master_test_scans_and_reads_an_eni_line_of_twins() {
    let mt = master_test();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/testdata");
    let eni = root.join("machine.xml");
    let dir = root.join("esi");
    let (eni, dir) = (eni.to_str().expect("utf-8"), dir.to_str().expect("utf-8"));
    let (o, _) = expect(&mt, &["--eni", eni, "--esi-dir", dir, "scan"], 0);
    assert!(o.starts_with("5 slave(s) on the virtual bus"), "{o}");
    for name in ["EK1100", "EL2004", "EL2828", "EL1008", "PAM-199-P-ETC"] {
        assert!(o.contains(name), "{name} in {o}");
    }
    let (o, _) = expect(
        &mt,
        &[
            "--eni",
            eni,
            "--esi-dir",
            dir,
            "--slave",
            "4",
            "sdo",
            "read",
            "0x1018:02",
        ],
        0,
    );
    assert!(o.contains("0x00C703F3"), "{o}");
    let (_, e) = expect(&mt, &["--eni", eni, "scan"], 2);
    assert!(e.contains("no device for slave 0 'Term 1 (EK1100)'"), "{e}");
    let (_, e) = expect(&mt, &["--eni", eni, "--esi-dir", dir, "demo"], 2);
    assert!(e.contains("use scan, state, sdo"), "{e}");
}

#[test]
fn pam_slave_cpu_names_a_cpu_that_cannot_be_used_and_takes_one_that_can() {
    let runner = runner_binary().expect("pam-slave builds");
    // A CPU that does not exist: refused before the interface is opened
    // (no root needed), the CPUs that can be used named.
    let (o, e) = expect(
        &runner,
        &["--iface", "lo", "--cpu", "99999", "--dry-run"],
        2,
    );
    assert!(e.contains("cannot pin the runner to CPU 99999"), "{e}");
    assert!(e.contains("this process may use CPUs"), "{e}");
    assert!(o.is_empty(), "{o}");
    // Not a number: clap names the option.
    let (_, e) = expect(&runner, &["--iface", "lo", "--cpu", "first"], 2);
    assert!(e.contains("--cpu"), "{e}");
    // The first CPU this process may use (as the kernel lists them).
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    let first = status
        .lines()
        .find_map(|l| l.strip_prefix("Cpus_allowed_list:"))
        .and_then(|l| l.trim().split([',', '-']).next().map(str::to_string))
        .expect("Cpus_allowed_list");
    let (o, _) = expect(&runner, &["--iface", "lo", "--cpu", &first, "--dry-run"], 0);
    assert!(o.contains("PAM-199-P-ETC"), "{o}");
}

#[test]
fn pam_slave_refuses_at_start_when_the_firmware_stores_could_exceed_the_memory_cap() {
    let runner = runner_binary().expect("pam-slave builds");
    // 4 slaves x 2 slots x 1 MiB = 8 MiB > 4 MiB: refused before the
    // interface is opened (no root needed), both numbers named.
    let (o, e) = expect(
        &runner,
        &[
            "--iface",
            "lo",
            "--count",
            "4",
            "--image-store-size",
            "1M",
            "--memory-cap",
            "4M",
        ],
        2,
    );
    assert!(e.contains("8388608 bytes"), "{e}");
    assert!(e.contains("--memory-cap 4194304 bytes"), "{e}");
    assert!(e.contains("--image-store-size 1048576"), "{e}");
    assert!(o.is_empty() && !e.contains("Ctrl-C stops"), "{o}{e}");
    // Within the cap the line is built (dry run: nothing served).
    let (o, _) = expect(
        &runner,
        &[
            "--iface",
            "lo",
            "--count",
            "4",
            "--image-store-size",
            "1048576",
            "--memory-cap",
            "8M",
            "--dry-run",
        ],
        0,
    );
    assert!(o.contains("PAM-199-P-ETC"), "{o}");
    // The default store (2 MiB slots) of 4096 slaves against a 1 GiB cap.
    let (_, e) = expect(
        &runner,
        &["--iface", "lo", "--count", "4096", "--memory-cap", "1G"],
        2,
    );
    assert!(e.contains("17179869184 bytes"), "{e}");
    for bad in ["100", "2T", "x", "2G"] {
        let (_, e) = expect(&runner, &["--iface", "lo", "--image-store-size", bad], 2);
        assert!(e.contains("--image-store-size"), "{bad}: {e}");
    }
}

#[test]
fn a_failed_forward_relay_stops_pam_slave_with_status_3() {
    let Some(runner) = runner_binary() else {
        return skip("pam-slave binary not built");
    };
    let _serial = crate::common::NET_TESTS
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let pid = std::process::id();
    let ns = format!("pamr{pid}");
    let (m, a0, a1, b0) = (
        format!("pr{pid}m"),
        format!("pr{pid}a0"),
        format!("pr{pid}a1"),
        format!("pr{pid}b0"),
    );
    let made = (|| -> Result<crate::common::Netns, String> {
        crate::common::ip(&["netns", "add", &ns])?;
        let guard = crate::common::Netns {
            name: ns.clone(),
            runner: None,
        };
        for (x, y) in [(&m, &a0), (&a1, &b0)] {
            crate::common::ip(&[
                "-n", &ns, "link", "add", x, "type", "veth", "peer", "name", y,
            ])?;
        }
        for i in [&m, &a0, &a1, &b0] {
            crate::common::ip(&["-n", &ns, "link", "set", i, "up"])?;
        }
        Ok(guard)
    })();
    let mut guard = match made {
        Ok(g) => g,
        Err(e) => {
            return skip(&format!(
                "cannot create a network namespace and veth pairs here ({e}); needs root and iproute2"
            ));
        }
    };
    let child = std::process::Command::new("ip")
        .args(["netns", "exec", &ns])
        .arg(&runner)
        .args(["--iface", &a0, "--forward", &a1])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start pam-slave in the namespace");
    guard.runner = Some(child);
    std::thread::sleep(Duration::from_millis(500));
    // Port 0 loses its link, then a processed frame comes back on port 1:
    // the relay cannot pass it on to the master and ends with an error.
    crate::common::ip(&["-n", &ns, "link", "set", &a0, "down"]).expect("a0 down");
    let inject = format!(
        "import socket,time\n\
         s=socket.socket(socket.AF_PACKET,socket.SOCK_RAW)\n\
         s.bind(('{b0}',0))\n\
         f=b'\\xff'*6+b'\\x02\\x00\\x00\\x00\\x00\\x01'+b'\\x88\\xa4'+b'\\x0e\\x10'+bytes(46)\n\
         for _ in range(30):\n s.send(f); time.sleep(0.1)\n"
    );
    let start = Instant::now();
    let status = loop {
        let _ = std::process::Command::new("ip")
            .args(["netns", "exec", &ns, "python3", "-c", &inject])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .and_then(|mut c| c.wait());
        let c = guard.runner.as_mut().expect("runner");
        if let Some(st) = c.try_wait().expect("wait") {
            break Some(st);
        }
        if start.elapsed() > Duration::from_secs(10) {
            break None;
        }
    };
    let mut c = guard.runner.take().expect("runner");
    let mut err = String::new();
    if status.is_none() {
        let _ = c.kill();
    }
    let _ = c.wait();
    let _ = c.stderr.take().map(|mut e| e.read_to_string(&mut err));
    let status = status
        .unwrap_or_else(|| panic!("pam-slave kept running without its relay for 10 s:\n{err}"));
    assert_eq!(status.code(), Some(3), "{err}");
    assert!(
        err.contains(&format!("the relay of frames coming back on {a1} failed")),
        "{err}"
    );
    assert!(err.contains("Network is down"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn firmware_keygen_and_pack_sign_make_images_a_keyed_device_accepts() {
    use ecat_slave::firmware::{DeviceIdentity, EfwError, EfwValidator};
    let mt = master_test();
    let dir = std::env::temp_dir().join(format!("mt-sign-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let p = |n: &str| dir.join(n).to_string_lossy().into_owned();
    std::fs::write(p("app.bin"), vec![0x5Au8; 3000]).expect("write");
    let (o, _) = expect(&mt, &["firmware", "keygen", "-o", &p("owner.pem")], 0);
    let pem = std::fs::read_to_string(p("owner.pem")).expect("key file");
    assert!(pem.starts_with("-----BEGIN PRIVATE KEY-----"), "{pem}");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        let mode = std::fs::metadata(p("owner.pem"))
            .expect("meta")
            .permissions()
            .mode();
        assert_eq!(mode & 0o777, 0o600);
    }
    let hex = o
        .lines()
        .find_map(|l| l.strip_prefix("public key "))
        .expect("public key printed")
        .trim()
        .to_string();
    let key: [u8; 32] = (0..32)
        .map(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).expect("hex"))
        .collect::<Vec<u8>>()
        .try_into()
        .expect("32 bytes");
    // never overwritten
    let (_, e) = expect(&mt, &["firmware", "keygen", "-o", &p("owner.pem")], 2);
    assert!(e.contains("never overwritten"), "{e}");
    let (o, _) = expect(
        &mt,
        &[
            "firmware",
            "pack",
            &p("app.bin"),
            "--version",
            "12",
            "-o",
            &p("signed.efw"),
            "--sign",
            &p("owner.pem"),
        ],
        0,
    );
    assert!(o.contains(&format!("signed by key {hex}")), "{o}");
    expect(
        &mt,
        &[
            "firmware",
            "pack",
            &p("app.bin"),
            "--version",
            "12",
            "-o",
            &p("plain.efw"),
        ],
        0,
    );
    let id = DeviceIdentity {
        vendor_id: pam_199_p_etc::VENDOR_ID,
        product_code: pam_199_p_etc::PRODUCT_CODE,
        revision: pam_199_p_etc::REVISION,
    };
    let check = |file: &str, key: [u8; 32]| {
        let img = std::fs::read(p(file)).expect("image");
        let mut v = EfwValidator::new(id, 1 << 20).with_public_key(key);
        v.feed(&img).and_then(|_| v.finish()).map(|_| ())
    };
    assert_eq!(check("signed.efw", key), Ok(()));
    assert_eq!(check("plain.efw", key), Err(EfwError::Unsigned));
    let mut other = key;
    other[0] ^= 1;
    assert!(check("signed.efw", other).is_err());
    // A key from OpenSSL works the same (when openssl is installed).
    let made = std::process::Command::new("openssl")
        .args(["genpkey", "-algorithm", "ed25519", "-out", &p("ossl.pem")])
        .status();
    if made.is_ok_and(|s| s.success()) {
        expect(
            &mt,
            &[
                "firmware",
                "pack",
                &p("app.bin"),
                "--version",
                "12",
                "-o",
                &p("ossl.efw"),
                "--sign",
                &p("ossl.pem"),
            ],
            0,
        );
        let der = std::process::Command::new("openssl")
            .args(["pkey", "-in", &p("ossl.pem"), "-pubout", "-outform", "DER"])
            .output()
            .expect("openssl pkey");
        let pk: [u8; 32] = der.stdout[der.stdout.len() - 32..].try_into().expect("key");
        assert_eq!(check("ossl.efw", pk), Ok(()));
    }
    // Not a key: refused with a message naming the format.
    let (_, e) = expect(
        &mt,
        &[
            "firmware",
            "pack",
            &p("app.bin"),
            "--version",
            "12",
            "-o",
            &p("x.efw"),
            "--sign",
            &p("app.bin"),
        ],
        2,
    );
    assert!(e.contains("PKCS#8"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
