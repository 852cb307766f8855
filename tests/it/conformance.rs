//! The conformance checker (`master-test conformance`): it passes on every
//! device we ship, on the virtual bus and against the raw runner over a
//! veth pair, and each deliberately broken slave fails exactly the check
//! meant for its defect.
//!
//! The broken slaves are the PAM-199-P-ETC with one defect each, played by
//! a wrapper around the healthy firmware ([`Defective`]) that changes what
//! the firmware leaves in the ESC after each poll (as a defective firmware
//! would write it), or by a wrong SII written over the EEPROM interface.

use crate::common::{binary, runner_binary, setup, skip};
use ecat_sim::chain::{Chain, LineSlave};
use ecat_sim::esc::{FrameOutcome, SoftEsc};
use ecat_slave::al::AlStatus;
use ecat_slave::device::DeviceDescription;
use ecat_slave::esc::Esc;
use ecat_slave::firmware::ImageStore;
use ecat_slave::hal::NvStorage;
use ecat_slave::led::LedPattern;
use ecat_slave::od::Od;
use master_test::VirtualBus;
use master_test::conformance::{self, Options, Verdict};
use master_test::link::Clock;
use std::any::Any;
use std::collections::BTreeSet;
use std::process::{Command, Stdio};

/// One defect of a broken slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Defect {
    /// SDO aborts sent as CoE service 3 (SDO response), as this slave did
    /// before issue 11.
    AbortInService3,
    /// SDO Information describes the padding entries as readable (access
    /// 0x0007) while their upload aborts.
    PaddingReadable,
    /// The Emergency queue survives INIT: the last Emergency is sent again
    /// after INIT -> PRE-OP.
    EmergencyNotFlushed,
    /// INIT -> OP refused with 0x0012 (invalid requested state change
    /// is 0x0011; 0x0012 is "unknown requested state").
    WrongAlCode,
}

/// A slave whose firmware has `defect`.
struct Defective {
    inner: Box<dyn LineSlave>,
    defect: Defect,
    last_emergency: Option<Vec<u8>>,
    last_state: u16,
}

impl Defective {
    fn pam(defect: Defect) -> Self {
        let entries = device_catalog::parse_line("pam").expect("pam");
        let inner = device_catalog::slaves(&entries).pop().expect("one slave");
        Defective {
            inner,
            defect,
            last_emergency: None,
            last_state: 1,
        }
    }

    /// SM1 (the slave's send mailbox): start and length.
    fn sm1(mem: &[u8]) -> (usize, usize) {
        let start = usize::from(u16::from_le_bytes([mem[0x0808], mem[0x0809]]));
        let len = usize::from(u16::from_le_bytes([mem[0x080A], mem[0x080B]]));
        (start, len)
    }

    /// What the defective firmware changes after a poll.
    fn spoil(&mut self) {
        let defect = self.defect;
        let esc = self.inner.esc_mut();
        let mem = esc.raw_memory_mut();
        let (start, len) = Self::sm1(mem);
        let state = u16::from_le_bytes([mem[0x0130], mem[0x0131]]);
        let mbx_ok = len >= 16 && start + len <= mem.len();
        match defect {
            Defect::AbortInService3 if mbx_ok => {
                let m = &mut mem[start..start + len];
                // CoE (type 3), service 2, command 0x80: an abort.
                if m[5] & 0x0F == 3 && m[7] >> 4 == 2 && m[8] == 0x80 {
                    m[7] = (m[7] & 0x0F) | 0x30;
                }
            }
            Defect::PaddingReadable if mbx_ok => {
                let m = &mut mem[start..start + len];
                // CoE SDO Information (service 8), Get Entry Description
                // response (opcode 6): data type NULL, access 0 -> 0x0007.
                if m[5] & 0x0F == 3 && m[7] >> 4 == 8 && m[8] & 0x7F == 6 {
                    let dtype = u16::from_le_bytes([m[16], m[17]]);
                    let access = u16::from_le_bytes([m[20], m[21]]);
                    if dtype == 0 && access == 0 {
                        m[20] = 0x07;
                    }
                }
            }
            Defect::WrongAlCode => {
                let control = u16::from_le_bytes([mem[0x0120], mem[0x0121]]);
                let code = u16::from_le_bytes([mem[0x0134], mem[0x0135]]);
                if state == 0x11 && control & 0x0F == 0x08 && code == 0x0011 {
                    mem[0x0134..0x0136].copy_from_slice(&0x0012u16.to_le_bytes());
                }
            }
            Defect::EmergencyNotFlushed if mbx_ok => {
                let m = &mem[start..start + len];
                // Remember the last Emergency (CoE service 1) sent.
                if m[5] & 0x0F == 3 && m[7] >> 4 == 1 {
                    self.last_emergency = Some(m.to_vec());
                }
                // After INIT -> PRE-OP: send it again.
                if self.last_state & 0x0F == 0x01
                    && state == 0x02
                    && let Some(e) = self.last_emergency.clone()
                {
                    let _ = esc.write(start as u16, &e);
                }
            }
            _ => {}
        }
        self.last_state = state;
    }
}

impl LineSlave for Defective {
    fn description(&self) -> &'static DeviceDescription {
        self.inner.description()
    }
    fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome {
        self.inner.process_frame(frame)
    }
    fn esc(&self) -> &SoftEsc {
        self.inner.esc()
    }
    fn esc_mut(&mut self) -> &mut SoftEsc {
        self.inner.esc_mut()
    }
    fn poll_with(
        &mut self,
        now_ns: u64,
        images: Option<&mut dyn ImageStore>,
    ) -> Result<(), ecat_slave::esc::EscError> {
        let r = self.inner.poll_with(now_ns, images);
        self.spoil();
        r
    }
    fn power_cycle(&mut self) {
        self.inner.power_cycle();
    }
    fn set_port1_link(&mut self, link: bool) {
        self.inner.set_port1_link(link);
    }
    fn set_firmware_version(&mut self, version: &str) {
        self.inner.set_firmware_version(version);
    }
    fn set_no_valid_firmware(&mut self, none: bool) {
        self.inner.set_no_valid_firmware(none);
    }
    fn firmware_version(&self) -> String {
        self.inner.firmware_version()
    }
    fn led_patterns(&self) -> (LedPattern, LedPattern) {
        self.inner.led_patterns()
    }
    fn leds(&self) -> (bool, bool) {
        self.inner.leds()
    }
    fn set_stalled(&mut self, stalled: bool) {
        self.inner.set_stalled(stalled);
    }
    fn set_emergencies(&mut self, enabled: bool) {
        self.inner.set_emergencies(enabled);
    }
    fn emergencies_waiting(&self) -> usize {
        self.inner.emergencies_waiting()
    }
    fn al_status(&self) -> AlStatus {
        self.inner.al_status()
    }
    fn od(&self) -> &Od {
        self.inner.od()
    }
    fn od_mut(&mut self) -> &mut Od {
        self.inner.od_mut()
    }
    fn nv(&self) -> Option<&dyn NvStorage> {
        self.inner.nv()
    }
    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        self.inner.nv_mut()
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// Runs every check (FoE with a PAM image) against slave 0 of `bus`.
fn check(bus: &VirtualBus, esi: bool) -> conformance::Report {
    smol::block_on(async {
        let md = &*bus.maindevice;
        bus.init().await.expect("PRE-OP");
        let esi = esi.then(|| {
            String::from_utf8(ecat_esi::esi::generate(&pam_199_p_etc::DEVICE).expect("ESI"))
                .expect("UTF-8")
        });
        let opts = Options {
            only: Vec::new(),
            esi,
            foe: None,
            clock: bus.clock.clone(),
        };
        conformance::run(md, 0x1000, "slave 0", &opts).await
    })
}

fn failed(report: &conformance::Report) -> BTreeSet<&'static str> {
    report.failed().map(|c| c.id).collect()
}

/// Issue 28: the checker on twins. Every slave of the test ENI's line
/// (twins of an EK1100, EL2004, EL2828 and EL1008 from ESI files, and a
/// PAM) passes with its ESI; the ESC-only terminals run in device
/// emulation (0x0141 bit 0), so they are judged by what such an ESC
/// promises (the AL status follows AL control) instead of refusals, and
/// they do.
#[test]
fn every_twin_of_the_eni_line_passes_the_checker_device_emulation_judged_as_such() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/testdata");
    let eni = root.join("machine.xml");
    let esi_dir = root.join("esi");
    let rules = ecat_twin::InputRules::default();
    let line = device_catalog::twins::from_eni(&eni, Some(&esi_dir), &rules).expect("the line");
    let n = line.slaves.len();
    assert_eq!(n, 5);
    let chain = ecat_sim::chain::Chain::with_slaves(line.slaves);
    let bus = VirtualBus::with_chain(chain, Clock::frames(), None).expect("bus");
    let esi_of = |name: &str| -> Option<String> {
        for f in std::fs::read_dir(&esi_dir).expect("ESI folder") {
            let text = std::fs::read_to_string(f.expect("entry").path()).expect("ESI");
            if text.contains(&format!(">{name}</Type>")) {
                return Some(text);
            }
        }
        None
    };
    let mut emulated = 0;
    smol::block_on(async {
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("PRE-OP");
        for (k, sd) in group.iter(md).enumerate() {
            let name = sd.name().to_string();
            let esi = if name == "PAM-199-P-ETC" {
                Some(
                    String::from_utf8(ecat_esi::generate(&pam_199_p_etc::DEVICE).expect("ESI"))
                        .expect("UTF-8"),
                )
            } else {
                esi_of(&name)
            };
            let opts = Options {
                only: Vec::new(),
                esi,
                foe: None,
                clock: bus.clock.clone(),
            };
            let station = 0x1000 + k as u16;
            let report = conformance::run(md, station, &name, &opts).await;
            assert!(failed(&report).is_empty(), "{name}:\n{}", report.to_text());
            let text = report.to_text();
            if text.contains("device emulation") {
                emulated += 1;
                assert!(
                    report
                        .checks
                        .iter()
                        .filter(
                            |c| c.id.ends_with("-refused") && c.id != "state.preop-to-boot-refused"
                        )
                        .all(|c| c.verdict == Verdict::Pass),
                    "{name}: {text}"
                );
            }
        }
    });
    assert_eq!(
        emulated, 4,
        "the four ESC-only terminals run in device emulation"
    );
}

#[test]
fn every_catalog_device_passes_the_checker_on_the_virtual_bus() {
    for device in device_catalog::DEVICES {
        let bus = VirtualBus::line(device.key, Clock::frames()).expect("bus");
        let report = smol::block_on(async {
            let md = &*bus.maindevice;
            bus.init().await.expect("PRE-OP");
            let esi = String::from_utf8(ecat_esi::esi::generate(device.description).expect("ESI"))
                .expect("UTF-8");
            let foe = (device.key == "pam").then(|| conformance::FoeOptions {
                file: master_test::foe::pam_image("11", 3000),
                name: "fw.efw".into(),
                password: 0,
            });
            let opts = Options {
                only: Vec::new(),
                esi: Some(esi),
                foe,
                clock: bus.clock.clone(),
            };
            conformance::run(md, 0x1000, device.key, &opts).await
        });
        assert!(
            failed(&report).is_empty(),
            "{}:\n{}",
            device.key,
            report.to_text()
        );
        let (pass, _, na) = report.counts();
        assert!(pass >= 40, "{}: only {pass} checks passed", device.key);
        // Only the FoE group may not apply, and for a device without a
        // bootstrap mailbox (no BOOT) the PRE-OP -> BOOT check; everything
        // else ran.
        let no_boot = device.description.mailbox.boot_size.is_none();
        assert!(
            report
                .checks
                .iter()
                .filter(|c| c.verdict == Verdict::NotApplicable)
                .all(|c| c.id.starts_with("foe.")
                    || (no_boot && c.id == "state.preop-to-boot-refused")),
            "{}: {na} not applicable:\n{}",
            device.key,
            report.to_text()
        );
    }
}

#[test]
fn each_broken_slave_fails_exactly_the_check_meant_for_its_defect() {
    for (defect, expected) in [
        (Defect::AbortInService3, "coe.abort-service"),
        (Defect::PaddingReadable, "coe.upload-readable"),
        (Defect::EmergencyNotFlushed, "mailbox.empty-after-init"),
        (Defect::WrongAlCode, "state.init-to-op-refused"),
    ] {
        let chain = Chain::with_slaves(vec![Box::new(Defective::pam(defect))]);
        let bus = VirtualBus::with_chain(chain, Clock::frames(), None).expect("bus");
        let report = check(&bus, true);
        assert_eq!(
            failed(&report),
            BTreeSet::from([expected]),
            "{defect:?}:\n{}",
            report.to_text()
        );
    }
}

/// A wrong SII written over the EEPROM interface: the device type is no
/// longer string 1 (the group name is), as SOEM then names the slave
/// after its group. The General category still points at the right
/// strings, so ethercrab is not fooled; the checker is.
#[test]
fn an_sii_with_the_group_name_first_fails_the_device_name_check() {
    let image = ecat_esi::sii_image(&pam_199_p_etc::DEVICE);
    let broken = swap_strings_1_and_2(&image);
    let bus = VirtualBus::new(1).expect("bus");
    smol::block_on(async {
        let md = &*bus.maindevice;
        bus.init().await.expect("PRE-OP");
        master_test::eeprom::write(md, 0x1000, &broken)
            .await
            .expect("SII written");
    });
    // A new master session reads the new SII. The ESI check is left out:
    // a device built this way would have an ESI that says the same.
    let next = bus.next_session().expect("second session");
    let report = check(&next, false);
    assert_eq!(
        failed(&report),
        BTreeSet::from(["sii.device-name"]),
        "{}",
        report.to_text()
    );
}

/// `image` with the texts of strings 1 and 2 swapped and the General
/// category's references to them swapped too.
fn swap_strings_1_and_2(image: &[u8]) -> Vec<u8> {
    let mut out = image.to_vec();
    let mut at = 0x80; // first category, in bytes
    while at + 4 <= out.len() {
        let kind = u16::from_le_bytes([out[at], out[at + 1]]);
        let words = usize::from(u16::from_le_bytes([out[at + 2], out[at + 3]]));
        let body = at + 4;
        match kind {
            0xFFFF => break,
            10 => {
                // Strings: count, then length-prefixed texts.
                let mut p = body + 1;
                let l1 = usize::from(out[p]);
                let s1 = out[p + 1..p + 1 + l1].to_vec();
                p += 1 + l1;
                let l2 = usize::from(out[p]);
                let s2 = out[p + 1..p + 1 + l2].to_vec();
                let mut swapped = vec![l2 as u8];
                swapped.extend(&s2);
                swapped.push(l1 as u8);
                swapped.extend(&s1);
                out[body + 1..body + 1 + swapped.len()].copy_from_slice(&swapped);
            }
            30 => {
                // General: group, image, order, name string indices.
                for b in &mut out[body..body + 4] {
                    *b = match *b {
                        1 => 2,
                        2 => 1,
                        other => other,
                    };
                }
            }
            _ => {}
        }
        at = body + 2 * words;
    }
    out
}

#[test]
fn master_test_conformance_passes_against_the_raw_runner_over_veth() {
    let Some(runner) = runner_binary() else {
        return skip("pam-slave binary not built");
    };
    let mt = binary("master-test", "master-test").expect("master-test builds");
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
    let line: Vec<&str> = device_catalog::DEVICES.iter().map(|d| d.key).collect();
    let child = Command::new("ip")
        .args(["netns", "exec", &guard.name])
        .arg(&runner)
        .args(["--iface", &slave_if, "--line", &line.join(",")])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start pam-slave in the namespace");
    guard.runner = Some(child);
    crate::common::wait_for_runner(&host_if);
    let dir = std::env::temp_dir().join(format!("pam-conformance-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let fw = dir.join("fw.efw");
    std::fs::write(&fw, master_test::foe::pam_image("11", 3000)).expect("image");
    for (i, key) in line.iter().enumerate() {
        let junit = dir.join(format!("{key}.xml"));
        let mut args = vec![
            "--iface".to_string(),
            host_if.clone(),
            "--slave".into(),
            i.to_string(),
            "conformance".into(),
            "--junit".into(),
            junit.to_string_lossy().into_owned(),
        ];
        if *key == "pam" {
            args.extend(["--foe-file".into(), fw.to_string_lossy().into_owned()]);
        }
        let out = Command::new(&mt).args(&args).output().expect("master-test");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{key}: exit {:?}\n{text}\n{}",
            out.status.code(),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(text.contains(" 0 failed"), "{key}: {text}");
        let xml = std::fs::read_to_string(&junit).expect("JUnit written");
        assert!(xml.contains("failures=\"0\""), "{key}: {xml}");
        assert!(xml.matches("<testcase ").count() >= 40, "{key}: {xml}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
