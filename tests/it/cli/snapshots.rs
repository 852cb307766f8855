//! Snapshots (insta) of what `master-test` prints: the `--help` of the
//! tool and of every subcommand, found by walking the help itself, and
//! the standard output, standard error and exit status of representative
//! runs on the virtual bus (no root needed).
//!
//! Deterministic on a busy machine: the virtual bus runs on the slaves'
//! frame clock (simulated time), the tool runs in the workspace root with
//! relative paths, and insta's filters redact the little that follows
//! the machine: temporary paths, a download's duration and rate, and
//! values that depend on when the link thread's idle passes ran the
//! firmware (the PAM's dithered solenoid current, the measured watchdog
//! time). A changed snapshot fails the test; `INSTA_UPDATE=always` (or
//! `cargo insta review`) records the new text after review.

use super::{master_test, text};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The workspace root: the tool runs there, so the paths it prints are
/// the short relative ones the commands were given.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate is in the workspace")
        .to_path_buf()
}

/// A temporary directory for files a run writes; its name matches the
/// `[TMP]` filter.
fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mt-snap-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// `master-test ARGS` as a transcript: the command, the exit status,
/// standard output and standard error.
fn transcript(args: &[&str]) -> String {
    let out = assert_cmd::Command::new(master_test())
        .args(args)
        .current_dir(root())
        .timeout(Duration::from_secs(120))
        .output()
        .expect("the tool runs");
    let (o, e) = (text(&out.stdout), text(&out.stderr));
    assert!(!e.contains("panicked"), "{args:?} panicked:\n{e}");
    format!(
        "$ master-test {}\nstatus: {}\n--- stdout\n{o}--- stderr\n{e}",
        args.join(" "),
        out.status
            .code()
            .map_or_else(|| "killed".to_string(), |c| c.to_string())
    )
}

/// Runs `f` with the snapshot settings: snapshots next to this file,
/// named without the module path, and the filters for what varies.
fn with_filters(f: impl FnOnce()) {
    let mut s = insta::Settings::clone_current();
    s.set_prepend_module_to_snapshot(false);
    s.set_snapshot_path("snapshots");
    // Files a run wrote (temp_dir).
    s.add_filter(r"[^\s'()]*mt-snap-\d+-\w+", "[TMP]");
    // A download's wall-clock duration and rate (foe write).
    s.add_filter(
        r"in \d+\.\d+ s \(\d+(\.\d+)?(e\d+)? MB/s\)",
        "in [s] s ([rate] MB/s)",
    );
    // The demo's inputs: the dither phase of the solenoid current depends
    // on when idle passes of the link thread ran the PAM's firmware.
    s.add_filter(
        r"(?m)^( {3,}\d+) {2,}\d .*(   wkc \d+)$",
        "$1  [READY W C U IA IB]$2",
    );
    s.add_filter(r"IA = \d+ mA, IB = \d+ mA", "IA = [mA], IB = [mA]");
    // The watchdog time the conformance check measured (1 ms polls).
    s.add_filter(
        r"after \d+ ms \(watchdog (\d+) ms\)",
        "after [measured] ms (watchdog $1 ms)",
    );
    s.bind(f);
}

/// Asserts the transcript of `master-test ARGS` against snapshot `name`.
fn check(name: &str, args: &[&str]) {
    let t = transcript(args);
    with_filters(|| insta::assert_snapshot!(name, t));
}

/// The subcommands the help text `help` lists under `Commands:`
/// (without `help`).
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| *l != "Commands:")
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| *n != "help")
        .map(str::to_string)
        .collect()
}

#[test]
fn every_help_text_is_as_recorded() {
    let mut todo: Vec<Vec<String>> = vec![vec![]];
    let mut seen = 0;
    while let Some(path) = todo.pop() {
        let mut args: Vec<&str> = path.iter().map(String::as_str).collect();
        args.push("--help");
        let t = transcript(&args);
        assert!(t.contains("status: 0\n"), "{t}");
        let name = std::iter::once("help")
            .chain(path.iter().map(String::as_str))
            .collect::<Vec<_>>()
            .join("_");
        with_filters(|| insta::assert_snapshot!(name, t));
        seen += 1;
        for sub in subcommands(&t) {
            let mut p = path.clone();
            p.push(sub);
            todo.push(p);
        }
    }
    // The tool, its 12 commands and their 16 subcommands.
    assert_eq!(seen, 29, "help texts found");
}

#[test]
fn scan_and_state_print_the_line_as_recorded() {
    check("scan", &["scan"]);
    check(
        "scan_json_line",
        &["--line", "pam,io8,dma22", "scan", "--json"],
    );
    let eni = [
        "--eni",
        "twin/testdata/machine.xml",
        "--esi-dir",
        "twin/testdata/esi",
    ];
    check("scan_eni", &[&eni[..], &["scan"]].concat());
    check("scan_eni_json", &[&eni[..], &["scan", "--json"]].concat());
    check("state", &["--line", "pam,io8", "state"]);
    check(
        "state_init_one_slave",
        &["--line", "pam,io8", "--slave", "1", "state", "init"],
    );
    check("state_safeop", &["--line", "pam,io8", "state", "safeop"]);
}

#[test]
fn sdo_and_od_print_typed_values_as_recorded() {
    check("sdo_read", &["sdo", "read", "0x800D:02"]);
    check("sdo_read_json", &["sdo", "read", "0x800D:02", "--json"]);
    check("sdo_read_raw", &["sdo", "read", "0x1008:00", "--raw"]);
    check("sdo_read_enum", &["sdo", "read", "0xF800:03"]);
    check("sdo_write", &["sdo", "write", "0x800D:02", "2000"]);
    check("sdo_write_enum", &["sdo", "write", "0xF800:03", "auto"]);
    check(
        "sdo_write_out_of_range",
        &["sdo", "write", "0x800D:02", "5000"],
    );
    check(
        "sdo_write_refused",
        &["sdo", "write", "0x800D:02", "5000", "--no-check"],
    );
    check("sdo_read_no_object", &["sdo", "read", "0x1234:00"]);
    check(
        "sdo_read_by_station",
        &[
            "--line",
            "pam,io8",
            "--station",
            "0x1001",
            "sdo",
            "read",
            "0x1008:00",
        ],
    );
    check("od_dump", &["--device", "io8", "od", "dump"]);
    check("od_dump_json", &["--device", "io8", "od", "dump", "--json"]);
}

#[test]
fn watch_prints_inputs_on_the_frame_clock_as_recorded() {
    let watch = [
        "--device",
        "io8",
        "watch",
        "--cycles",
        "30",
        "--interval",
        "5",
    ];
    check("watch", &watch);
    check("watch_json", &[&watch[..], &["--json"]].concat());
}

#[test]
fn eeprom_esi_foe_and_firmware_print_as_recorded() {
    check("eeprom_read", &["--device", "io8", "eeprom", "read"]);
    check(
        "eeprom_read_ihex",
        &["--device", "io8", "eeprom", "read", "--format", "ihex"],
    );
    let dir = temp_dir("files");
    let p = |n: &str| dir.join(n).to_string_lossy().into_owned();
    check(
        "eeprom_read_to_file",
        &["--device", "io8", "eeprom", "read", "-o", &p("sii.bin")],
    );
    check(
        "eeprom_write",
        &["--device", "io8", "eeprom", "write", &p("sii.bin")],
    );
    check("esi_check", &["esi", "check"]);
    check("foe_read", &["foe", "read", "info.txt"]);
    std::fs::write(p("app.bin"), vec![0x5Au8; 3000]).expect("write");
    check(
        "firmware_pack",
        &[
            "firmware",
            "pack",
            &p("app.bin"),
            "--version",
            "11",
            "-o",
            &p("app.efw"),
        ],
    );
    check(
        "firmware_pack_inverted_range",
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
    );
    check("foe_write", &["foe", "write", &p("app.efw")]);
    check("foe_password", &["foe", "password", "C0FFEE42"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn conformance_demo_and_hcs_print_as_recorded() {
    check("conformance", &["conformance"]);
    check(
        "conformance_only_esc_sii",
        &["--device", "io8", "conformance", "--only", "esc,sii"],
    );
    check("demo", &["demo", "--cycles", "60"]);
    check(
        "demo_line",
        &["--line", "pam,io8", "demo", "--cycles", "30"],
    );
    check(
        "hcs_read",
        &["--device", "dma22", "hcs", "read", "--module", "1", "0x00"],
    );
    check(
        "hcs_write_refused",
        &["--device", "dma22", "hcs", "write", "0x07", "5"],
    );
}

#[test]
fn usage_errors_name_the_argument_as_recorded() {
    for (name, args) in [
        ("usage_unknown_command", &["no-such-command"][..]),
        ("usage_no_address_sub", &["sdo", "read", "0x800D"]),
        ("usage_bad_subindex", &["sdo", "read", "0x8006:2G"]),
        (
            "usage_slave_out_of_range",
            &["--slave", "3", "sdo", "read", "0x1000:00"],
        ),
        (
            "usage_two_slaves_no_choice",
            &["--line", "pam,io8", "sdo", "read", "0x1000:00"],
        ),
        (
            "usage_unknown_device_in_line",
            &["--line", "pam,nope", "scan"],
        ),
        ("usage_unknown_device", &["--device", "nope", "scan"]),
        ("usage_line_too_long", &["--line", "io8*65", "scan"]),
        ("usage_line_spec_too_long", &["--line", "pam*4097", "scan"]),
        (
            "usage_line_and_device",
            &["--line", "pam", "--device", "io8", "scan"],
        ),
        (
            "usage_eni_and_line",
            &["--eni", "x.xml", "--line", "pam", "scan"],
        ),
        (
            "usage_esi_dir_without_eni",
            &["--esi-dir", "twin/testdata/esi", "scan"],
        ),
        (
            "usage_slave_and_station",
            &["--slave", "0", "--station", "0x1000", "scan"],
        ),
        (
            "usage_station_not_a_number",
            &["--station", "0x10000", "scan"],
        ),
        (
            "usage_no_such_station",
            &["--station", "0x1005", "sdo", "read", "0x1000:00"],
        ),
        (
            "usage_iface_and_line",
            &["--iface", "nosuchif0", "--line", "pam", "scan"],
        ),
        (
            "usage_eni_demo",
            &[
                "--eni",
                "twin/testdata/machine.xml",
                "--esi-dir",
                "twin/testdata/esi",
                "demo",
            ],
        ),
        (
            "usage_eni_no_esi_dir",
            &["--eni", "twin/testdata/machine.xml", "scan"],
        ),
        (
            "usage_demo_slaves_and_line",
            &["--line", "pam,io8", "demo", "--slaves", "2"],
        ),
        ("usage_demo_current", &["demo", "--current", "5000"]),
        ("usage_demo_slaves", &["demo", "--slaves", "1025"]),
        ("usage_demo_long_line", &["demo", "--line", "io8*1025"]),
        ("usage_state_unknown", &["state", "run"]),
        ("usage_state_op_one_slave", &["--slave", "0", "state", "op"]),
        ("usage_watch_cycles", &["watch", "--cycles", "0"]),
        (
            "usage_foe_password",
            &["foe", "read", "info.txt", "--password", "123456789"],
        ),
        (
            "usage_sdo_type",
            &["sdo", "read", "0x1000:00", "--type", "FLOAT"],
        ),
        (
            "usage_sdo_raw_and_json",
            &["sdo", "read", "0x1000:00", "--raw", "--json"],
        ),
        (
            "usage_conformance_only",
            &["conformance", "--only", "esc,nope"],
        ),
        (
            "usage_conformance_foe_without_file",
            &["conformance", "--only", "foe"],
        ),
        (
            "usage_hcs_words",
            &["--device", "dma22", "hcs", "read", "0x07", "--words", "9"],
        ),
    ] {
        check(name, args);
    }
}
