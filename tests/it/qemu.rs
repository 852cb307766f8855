//! The board's firmware on an emulated Cortex-M4, driven by SOEM.
//!
//! `examples/board/qemu` (the IO8 firmware of the board example: the
//! board's main loop, the unchanged LAN9252 driver, the core) is built for
//! `thumbv7em-none-eabihf` and booted in QEMU's `mps2-an386`. Its UART0 is
//! a Unix socket to `board-bridge`, which answers the firmware's SPI
//! transactions with the LAN9252 emulation in front of a software ESC and
//! keeps its flash in a file; the bridge serves the ESC on a veth pair in
//! a network namespace this test creates. SOEM (pysoem) then runs the
//! script's `board` phase (identity and name, SDO and aborts, SDO
//! Information, the SII, the state machine, 1000 cycles, the SM watchdog,
//! FoE in BOOT), QEMU is restarted (a board reset, its flash kept), and
//! the `board_after_restart` phase finds the downloaded version in 0x100A.
//!
//! Needs qemu-system-arm, the thumbv7em-none-eabihf Rust target, root and
//! pysoem; skipped with a message otherwise, a failure under `CI=true`.
//! The SOEM log is kept in `target/interop-logs/soem-qemu.log`.

use crate::common::{binary, setup, skip};
use crate::soem::{keep_log, pysoem_python, run_python};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The Rust target of the firmware.
const TARGET: &str = "thumbv7em-none-eabihf";

/// Whether `rustup` (or the sysroot) has the firmware's target.
fn has_target() -> bool {
    let Ok(out) = Command::new("rustc").args(["--print", "sysroot"]).output() else {
        return false;
    };
    let sysroot = String::from_utf8_lossy(&out.stdout).trim().to_string();
    Path::new(&sysroot)
        .join("lib/rustlib")
        .join(TARGET)
        .join("lib")
        .is_dir()
}

/// The workspace's target directory (this test binary is in
/// `<target>/<profile>/deps`).
fn target_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test binary path");
    exe.ancestors()
        .nth(3)
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../target")))
}

/// Builds the QEMU firmware (release, in target/board-firmware, where
/// `.ci/run` builds both board binaries first) and returns the ELF; or
/// returns `BOARD_QEMU_ELF`, a firmware built elsewhere (the nightly size
/// build of `examples/firmware/README.md` is run so). The crate's `.cargo/config.toml` (target,
/// linker script) applies only when cargo runs inside its folder.
fn build_firmware() -> PathBuf {
    if let Some(elf) = std::env::var_os("BOARD_QEMU_ELF") {
        return PathBuf::from(elf);
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/board/qemu");
    let target_dir = target_dir().join("board-firmware");
    let status = Command::new(env!("CARGO"))
        .current_dir(&dir)
        .args(["build", "-q", "--release", "--target", TARGET])
        .arg("--target-dir")
        .arg(&target_dir)
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("RUSTFLAGS")
        .status()
        .expect("cargo runs");
    assert!(
        status.success(),
        "building examples/board/qemu for {TARGET} failed"
    );
    target_dir.join(TARGET).join("release/board-qemu")
}

/// A process killed when the test ends, however it ends.
struct Killed(Option<Child>);

impl Drop for Killed {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Boots the firmware in QEMU with UART0 on the bridge's socket and UART1
/// (the console) into `console`; waits until the firmware printed its boot
/// line and returns it.
fn boot_qemu(elf: &Path, socket: &Path, console: &Path) -> (Killed, String) {
    let child = Command::new("qemu-system-arm")
        .args([
            "-machine",
            "mps2-an386",
            "-display",
            "none",
            "-monitor",
            "none",
        ])
        .arg("-serial")
        .arg(format!("unix:{}", socket.display()))
        .arg("-serial")
        .arg(format!("file:{}", console.display()))
        .arg("-kernel")
        .arg(elf)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start qemu-system-arm");
    let qemu = Killed(Some(child));
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(60) {
        let text = std::fs::read_to_string(console).unwrap_or_default();
        // Whole lines only: the emulated UART writes the file a byte at a
        // time, so the last line may still be coming.
        if let Some(line) = text
            .split_inclusive('\n')
            .filter(|l| l.ends_with('\n'))
            .find(|l| l.contains("board-qemu:") && l.contains("firmware"))
        {
            return (qemu, line.trim_end().to_string());
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    panic!(
        "the firmware in QEMU printed no boot line within 60 s: {:?}",
        std::fs::read_to_string(console).unwrap_or_default()
    );
}

#[test]
fn soem_brings_the_board_firmware_in_qemu_to_op_and_updates_it_over_foe() {
    if Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .is_err()
    {
        return skip("qemu-system-arm is not installed (Debian: apt-get install qemu-system-arm)");
    }
    if !has_target() {
        return skip(
            "the Rust target thumbv7em-none-eabihf is missing (rustup target add thumbv7em-none-eabihf)",
        );
    }
    let Some(py) = pysoem_python() else {
        return skip(
            "no Python with pysoem (pip install pysoem, or set PAM_PYSOEM_PYTHON); .ci/run installs it",
        );
    };
    let t0 = Instant::now();
    let elf = build_firmware();
    let Some(bridge) = binary("board-bridge", "board-bridge") else {
        return skip("board-bridge binary not built next to the test binary");
    };
    let built = t0.elapsed();
    let _serial = crate::common::NET_TESTS
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let (mut guard, host_if, slave_if) = match setup("k") {
        Ok(x) => x,
        Err(e) => {
            return skip(&format!(
                "cannot create a network namespace and veth pair here ({e}); needs root and iproute2"
            ));
        }
    };
    let dir = std::env::temp_dir().join(format!("pam-qemu-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = |n: &str| dir.join(n);
    let s = |p: PathBuf| p.to_string_lossy().into_owned();
    let dev = &io8_example::DEVICE;
    std::fs::write(file("io8.xml"), ecat_esi::generate(dev).expect("ESI")).expect("ESI file");
    std::fs::write(file("eeprom.bin"), ecat_esi::sii_image(dev)).expect("SII file");
    let payload: Vec<u8> = (0..6000u32).map(|i| (i * 7 + i / 251) as u8).collect();
    let good = master_test::foe::efw_image(
        dev.identity.vendor_id,
        dev.identity.product_code,
        "11",
        &payload,
    );
    let mut bad = good.clone();
    let last = bad.len() - 1;
    bad[last] ^= 0xFF;
    std::fs::write(file("good.efw"), &good).expect("image");
    std::fs::write(file("bad.efw"), &bad).expect("image");
    let layout = dev.layout();
    let boot_out = format!("{:x}:{:x}", layout.boot_out.0, layout.boot_out.1);
    let boot_in = format!("{:x}:{:x}", layout.boot_in.0, layout.boot_in.1);
    let log = "soem-qemu.log";
    let _ = std::fs::remove_file(
        Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../target/interop-logs"
        ))
        .join(log),
    );

    let socket = file("uart0.sock");
    let bridge_log = file("bridge.log");
    let runner = Command::new("ip")
        .args(["netns", "exec", &guard.name])
        .arg(&bridge)
        .args(["--iface", &slave_if])
        .arg("--socket")
        .arg(&socket)
        .arg("--flash")
        .arg(file("flash.bin"))
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&bridge_log).expect("bridge log"))
        .spawn()
        .expect("start board-bridge in the namespace");
    guard.runner = Some(runner);
    let start = Instant::now();
    while !socket.exists() && start.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(
        socket.exists(),
        "board-bridge did not open {}",
        socket.display()
    );
    crate::common::wait_for_runner(&host_if);

    // Run 1: the factory firmware, every check up to the FoE download.
    let t1 = Instant::now();
    let (qemu, boot1) = boot_qemu(&elf, &socket, &file("console-1.log"));
    keep_log(log, &format!("=== board-qemu on mps2-an386 ===\n{boot1}\n"));
    assert!(
        boot1.contains("firmware 10 from slot A"),
        "factory boot: {boot1}"
    );
    let (ok, out) = run_python(
        &py,
        &[
            "board",
            &host_if,
            &s(file("io8.xml")),
            &s(file("eeprom.bin")),
            &s(file("good.efw")),
            &s(file("bad.efw")),
            &boot_out,
            &boot_in,
        ],
    );
    keep_log(log, &format!("--- SOEM board ---\n{out}"));
    eprintln!("--- SOEM board ---\n{out}");
    drop(qemu);
    assert!(
        ok,
        "SOEM board phase against the firmware in QEMU failed (log above)"
    );

    // Run 2: QEMU restarted on the same bridge (a board reset; the flash
    // file is kept): the bootloader starts the downloaded image.
    let (qemu, boot2) = boot_qemu(&elf, &socket, &file("console-2.log"));
    keep_log(log, &format!("--- QEMU restarted ---\n{boot2}\n"));
    assert!(
        boot2.contains("firmware 11 from slot B"),
        "boot after the update: {boot2}"
    );
    crate::common::wait_for_runner(&host_if);
    let (ok, out) = run_python(&py, &["board_after_restart", &host_if, "11"]);
    keep_log(log, &format!("--- SOEM board_after_restart ---\n{out}"));
    eprintln!("--- SOEM board_after_restart ---\n{out}");
    drop(qemu);
    let ran = t1.elapsed();
    assert!(ok, "SOEM after the restart failed (log above)");

    let runner = guard.runner.take().expect("bridge");
    let _ = Command::new("kill")
        .args(["-INT", &runner.id().to_string()])
        .status();
    let mut runner = Killed(Some(runner));
    if let Some(c) = runner.0.as_mut() {
        for _ in 0..100 {
            if c.try_wait().ok().flatten().is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    drop(runner);
    let text = std::fs::read_to_string(&bridge_log).unwrap_or_default();
    keep_log(
        log,
        &format!(
            "--- board-bridge ---\n{text}(firmware and bridge built in {:.1} s, both QEMU runs {:.1} s)\n",
            built.as_secs_f64(),
            ran.as_secs_f64()
        ),
    );
    eprintln!("--- board-bridge ---\n{text}");
    assert!(
        text.contains("QEMU run 2 ended")
            && text.contains(" 0 protocol errors, 0 refused accesses"),
        "two QEMU runs over a clean SPI wire: {text}"
    );
    assert!(
        text.contains("stopped after"),
        "the bridge stopped cleanly: {text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
