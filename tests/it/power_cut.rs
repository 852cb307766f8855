//! Power cuts at the block level: the raw runner keeps its state
//! (`pam-slave --state-dir`) on an ext4 and on an XFS file system, each on
//! a loop device; the master (the `master-test` CLI over a veth pair)
//! saves parameter sets and updates the firmware while the test copies the
//! loop device's backing file at random instants, during and right after
//! each SAVE and during the FoE download.
//!
//! A copy is what a power failure leaves on the disk: every write the
//! file system has sent to the device is in it, whatever is still in the
//! page cache is not. The backing file lives on an XFS with reflinks, and
//! each copy is a reflink clone (`cp --reflink=always`, the FICLONE ioctl),
//! which takes the file's lock and so is a point-in-time image: no write of
//! the loop device is half in it. (Device-mapper snapshots would do the
//! same on a kernel that has them; this one need not.)
//!
//! Each copy is then mounted (the file system replays its journal as after
//! a real power cut) and booted as a new slave on the virtual bus, which
//! ethercrab reads over SDO. What must hold, for every copy:
//! - the parameter set is one whose SAVE had been requested, never older
//!   than the last SAVE acknowledged before the copy (an acknowledged SAVE
//!   is never lost), and never factory defaults after a SAVE;
//! - MEMORY (0xA000:01) is false: a valid set was found, no EEPROM error;
//! - the firmware is the old version until the update was acknowledged
//!   and the new one after, and the slave boots (the runner never refuses
//!   the store for lost boot records).
//!
//! Needs root, loop devices, mkfs.ext4, mkfs.xfs (xfsprogs) and iproute2;
//! skipped with a message otherwise (a failure under `CI=true`).

use crate::common::{binary, runner_binary, setup, skip};
use ecat_sim::raw::persistent_chain;
use master_test::VirtualBus;
use master_test::link::Clock;
use rand::Rng;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Runs `cmd args`, returning its standard output or a message naming the
/// command and its standard error.
fn sh(cmd: &str, args: &[&str]) -> Result<String, String> {
    let out = Command::new(cmd)
        .args(args)
        .output()
        .map_err(|e| format!("{cmd}: {e}"))?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
    } else {
        Err(format!(
            "{cmd} {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// Mounts and loop devices, undone in reverse order on drop (also when the
/// test fails).
#[derive(Default)]
struct Mounts {
    /// (mount point, loop device if the test attached one).
    stack: Vec<(PathBuf, Option<String>)>,
}

impl Mounts {
    /// Attaches `image` to a loop device and mounts it on `at`.
    fn mount(&mut self, image: &Path, at: &Path) -> Result<(), String> {
        std::fs::create_dir_all(at).map_err(|e| format!("{}: {e}", at.display()))?;
        let dev = sh("losetup", &["--find", "--show", &image.to_string_lossy()])?;
        if let Err(e) = sh("mount", &[&dev, &at.to_string_lossy()]) {
            let _ = sh("losetup", &["-d", &dev]);
            return Err(e);
        }
        self.stack.push((at.to_path_buf(), Some(dev)));
        Ok(())
    }

    /// Unmounts the last mount and detaches its loop device.
    fn pop(&mut self) -> Result<(), String> {
        if let Some((at, dev)) = self.stack.pop() {
            sh("umount", &[&at.to_string_lossy()])?;
            if let Some(dev) = dev {
                sh("losetup", &["-d", &dev])?;
            }
        }
        Ok(())
    }
}

impl Drop for Mounts {
    fn drop(&mut self) {
        while let Some((at, dev)) = self.stack.pop() {
            let _ = sh("umount", &["-l", &at.to_string_lossy()]);
            if let Some(dev) = dev {
                let _ = sh("losetup", &["-d", &dev]);
            }
        }
    }
}

/// One copy of the disk and what the master knew when it was taken.
#[derive(Debug)]
struct Cut {
    /// The copy.
    image: PathBuf,
    /// What the copy was taken during ("SAVE 3", "after SAVE 3", "FoE").
    when: String,
    /// The last SAVE acknowledged before the copy (0: none yet).
    acked: u32,
    /// The last SAVE requested before the copy ended.
    requested: u32,
    /// The firmware update was acknowledged before the copy.
    fw_acked: bool,
    /// The firmware update had started before the copy ended.
    fw_started: bool,
}

/// CURRENT (0x800D:02) of parameter set `k` (k = 0: factory default).
fn current_of(k: u32) -> u16 {
    1000 + 50 * k as u16
}

/// The state of one run: the disk, the master's knowledge and the copies.
struct Run<'a> {
    fs: &'a str,
    disk: PathBuf,
    cuts_dir: PathBuf,
    cuts: Vec<Cut>,
    acked: u32,
    requested: u32,
    fw_acked: bool,
    fw_started: bool,
}

impl Run<'_> {
    /// Copies the disk as it is now (a reflink clone: point in time).
    fn cut(&mut self, when: &str) {
        let image = self
            .cuts_dir
            .join(format!("{}-{:03}.img", self.fs, self.cuts.len()));
        let acked = self.acked;
        let fw_acked = self.fw_acked;
        sh(
            "cp",
            &[
                "--reflink=always",
                &self.disk.to_string_lossy(),
                &image.to_string_lossy(),
            ],
        )
        .expect("reflink copy of the disk");
        self.cuts.push(Cut {
            image,
            when: when.to_string(),
            acked,
            requested: self.requested,
            fw_acked,
            fw_started: self.fw_started,
        });
    }

    /// Cuts at random instants (0..`max_gap`) while `child` runs; returns
    /// whether it succeeded.
    fn cut_while(&mut self, mut child: Child, when: &str, max_gap: Duration) -> bool {
        let mut rng = rand::rng();
        loop {
            let gap = rng.random_range(Duration::ZERO..max_gap);
            std::thread::sleep(gap);
            if let Some(status) = child.try_wait().expect("child status") {
                return status.success();
            }
            self.cut(when);
        }
    }
}

/// What a copy boots as: (CURRENT, MEMORY, firmware version).
fn boot(state: &Path) -> Result<(u16, bool, String), String> {
    let entries = device_catalog::parse_line("pam").map_err(|e| e.to_string())?;
    let (chain, _states) = persistent_chain(state, device_catalog::slaves(&entries))
        .map_err(|e| format!("the runner refuses the state: {e}"))?;
    let bus = VirtualBus::with_chain(chain, Clock::frames(), None).map_err(|e| e.to_string())?;
    smol::block_on(async {
        let md = &*bus.maindevice;
        let group = bus.init().await.map_err(|e| e.to_string())?;
        let sd = group.subdevice(md, 0).map_err(|e| e.to_string())?;
        let current: u16 = sd.sdo_read(0x800D, 2).await.map_err(|e| e.to_string())?;
        let memory: bool = sd.sdo_read(0xA000, 1).await.map_err(|e| e.to_string())?;
        let version: heapless::String<32> =
            sd.sdo_read(0x100A, 0).await.map_err(|e| e.to_string())?;
        Ok((current, memory, version.to_string()))
    })
}

/// One file system: the runner on it, SAVEs and an FoE update with cuts,
/// then every cut booted and checked. Returns a summary line.
fn power_cuts_on(fs: &str, base: &Path, outer: &Path, master: &Path, runner: &Path) -> String {
    let disk = outer.join(format!("{fs}.img"));
    let size = if fs == "xfs" { "320M" } else { "64M" };
    sh("truncate", &["-s", size, &disk.to_string_lossy()]).expect("disk image");
    match fs {
        "xfs" => sh("mkfs.xfs", &["-q", "-f", &disk.to_string_lossy()]),
        _ => sh("mkfs.ext4", &["-q", "-F", &disk.to_string_lossy()]),
    }
    .expect("mkfs");
    let mut mounts = Mounts::default();
    let mnt = base.join(format!("{fs}-live"));
    mounts.mount(&disk, &mnt).expect("mount the disk");
    let state = mnt.join("state");

    let (mut guard, host_if, slave_if) = setup("p").expect("namespace and veth pair");
    let child = Command::new("ip")
        .args(["netns", "exec", &guard.name])
        .arg(runner)
        .args(["--iface", &slave_if, "--state-dir"])
        .arg(&state)
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("start pam-slave in the namespace");
    guard.runner = Some(child);
    crate::common::wait_for_runner(&host_if);
    let spawn = |args: &[&str]| {
        Command::new(master)
            .args(["--iface", &host_if])
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start master-test")
    };
    let firmware = base.join(format!("{fs}-fw.efw"));
    std::fs::write(&firmware, master_test::foe::pam_image("11", 256 * 1024)).expect("image");

    let mut run = Run {
        fs,
        disk: disk.clone(),
        cuts_dir: outer.to_path_buf(),
        cuts: Vec::new(),
        acked: 0,
        requested: 0,
        fw_acked: false,
        fw_started: false,
    };
    let saves = 4u32;
    let mut last_save = Instant::now() - Duration::from_secs(2);
    for k in 1..=saves {
        let value = current_of(k).to_string();
        let ok = spawn(&["sdo", "write", "0x800D:02", &value])
            .wait()
            .expect("master-test")
            .success();
        assert!(ok, "{fs}: CURRENT = {value} written");
        // SAVE at most once a second (the device refuses faster ones).
        let mut tries = 0;
        loop {
            let since = last_save.elapsed();
            if since < Duration::from_millis(1100) {
                std::thread::sleep(Duration::from_millis(1100) - since);
            }
            last_save = Instant::now();
            run.requested = k;
            let save = spawn(&["sdo", "write", "0xF801:02", "1"]);
            if run.cut_while(save, &format!("SAVE {k}"), Duration::from_millis(15)) {
                break;
            }
            tries += 1;
            assert!(tries < 3, "{fs}: SAVE {k} failed three times");
        }
        run.acked = k;
        run.cut(&format!("after SAVE {k}"));
        if k == 2 {
            run.fw_started = true;
            let update = spawn(&["foe", "write", &firmware.to_string_lossy()]);
            assert!(
                run.cut_while(update, "FoE", Duration::from_millis(25)),
                "{fs}: the firmware update succeeds"
            );
            run.fw_acked = true;
            run.cut("after FoE");
        }
    }
    drop(guard);
    mounts.pop().expect("unmount the disk");
    let _ = std::fs::remove_file(&disk);
    let _ = std::fs::remove_file(&firmware);

    // Boot every copy.
    let check = base.join(format!("{fs}-cut"));
    let (mut during_save, mut new_sets) = (0, 0);
    for cut in &run.cuts {
        mounts.mount(&cut.image, &check).unwrap_or_else(|e| {
            panic!(
                "{fs}, cut {} ({}): the file system does not mount after the cut: {e}",
                cut.image.display(),
                cut.when
            )
        });
        let booted = boot(&check.join("state"));
        mounts.pop().expect("unmount the copy");
        let _ = std::fs::remove_file(&cut.image);
        let (current, memory, version) =
            booted.unwrap_or_else(|e| panic!("{fs}, cut {:?}: {e}", cut));
        let allowed: Vec<u16> = (cut.acked..=cut.requested).map(current_of).collect();
        assert!(
            allowed.contains(&current),
            "{fs}, cut {cut:?}: CURRENT {current} mA, expected one of {allowed:?} \
             (an acknowledged SAVE lost, or factory defaults)"
        );
        assert!(
            !memory,
            "{fs}, cut {cut:?}: EEPROM data error although a valid set was saved"
        );
        if cut.fw_acked {
            assert_eq!(version, "11", "{fs}, cut {cut:?}: acknowledged update lost");
        } else if !cut.fw_started {
            assert_eq!(version, "10", "{fs}, cut {cut:?}");
        } else {
            assert!(
                version == "10" || version == "11",
                "{fs}, cut {cut:?}: firmware {version}"
            );
        }
        if cut.when.starts_with("SAVE") {
            during_save += 1;
            if current == current_of(cut.requested) {
                new_sets += 1;
            }
        }
    }
    let foe_cuts = run.cuts.iter().filter(|c| c.when == "FoE").count();
    format!(
        "{fs}: {} cuts ({during_save} during a SAVE, {new_sets} of them already with the new set; \
         {foe_cuts} during the FoE download; {saves} after acknowledged SAVEs, 1 after the update): \
         nothing acknowledged lost, no defaults, no EEPROM error, every copy boots",
        run.cuts.len()
    )
}

#[test]
fn power_cuts_during_save_and_firmware_update_lose_nothing_acknowledged_on_ext4_and_xfs() {
    let Some(runner) = runner_binary() else {
        return skip("pam-slave binary not built next to the test binary");
    };
    let master = binary("master-test", "master-test").expect("master-test builds");
    for tool in ["losetup", "mkfs.ext4", "mkfs.xfs", "ip"] {
        if sh("sh", &["-c", &format!("command -v {tool}")]).is_err() {
            return skip(&format!(
                "{tool} is missing: the power-cut test needs util-linux, e2fsprogs, xfsprogs and iproute2"
            ));
        }
    }
    let _serial = crate::common::NET_TESTS
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let base = std::env::temp_dir().join(format!("pam-powercut-{}", std::process::id()));
    let outer = base.join("outer");
    let _ = std::fs::create_dir_all(&base);
    // The disk images live on an XFS with reflinks, so a copy is a clone.
    let outer_img = base.join("outer.img");
    let mut mounts = Mounts::default();
    let prepared = sh("truncate", &["-s", "2G", &outer_img.to_string_lossy()])
        .and_then(|_| {
            sh(
                "mkfs.xfs",
                &["-q", "-f", "-m", "reflink=1", &outer_img.to_string_lossy()],
            )
        })
        .and_then(|_| mounts.mount(&outer_img, &outer));
    if let Err(e) = prepared {
        drop(mounts);
        let _ = std::fs::remove_dir_all(&base);
        return skip(&format!(
            "cannot loop-mount a file system here ({e}); the power-cut test needs root and loop devices"
        ));
    }
    let mut summary = Vec::new();
    for fs in ["ext4", "xfs"] {
        summary.push(power_cuts_on(fs, &base, &outer, &master, &runner));
    }
    drop(mounts);
    let _ = std::fs::remove_dir_all(&base);
    let text = summary.join("\n");
    eprintln!("{text}");
    let logs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/interop-logs");
    let _ = std::fs::create_dir_all(&logs);
    let _ = std::fs::write(logs.join("power-cut.log"), format!("{text}\n"));
}
