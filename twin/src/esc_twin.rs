//! A twin of a device without a firmware: an ESC whose PDI is digital I/O
//! or nothing (couplers such as the EK1100, EL1xxx/EL2xxx terminals).
//!
//! Such a device is its ESC and its EEPROM. The software ESC runs with the
//! SII image made from the ESI ([`crate::sii::image`]); its ESC
//! configuration byte (SII word 0, high byte) sets *device emulation*, so
//! the AL status follows the AL control register as on the real chip
//! (`ESC_CONFIG_DEVICE_EMULATION`). What the digital I/O pins would do is
//! the [`InputRule`]: each [`EscTwin::poll`] writes the input SyncManagers
//! through the PDI and reads the output ones.

use std::any::Any;

use ecat_sim::chain::LineSlave;
use ecat_sim::esc::{FrameOutcome, SoftEsc};
use ecat_slave::al::{AlState, AlStatus, AlStatusCode};
use ecat_slave::device::{
    CoeServices, DeviceDescription, EscConfig, FoeSecurity, MailboxConfig, ProcessData,
};
use ecat_slave::esc::{Esc, EscError, registers as reg};
use ecat_slave::firmware::ImageStore;
use ecat_slave::hal::NvStorage;
use ecat_slave::led::LedPattern;
use ecat_slave::od::store::{ObjectStore, Od};
use ecat_slave::od::{Dictionary, ValueStorage};
use ecat_slave::sii::SmType;

use crate::esi::EsiDevice;

/// What a twin's inputs do (the pins of a digital I/O ESC).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InputRule {
    /// Inputs hold what [`EscTwin::set_inputs`] last set (zeros at start).
    #[default]
    Hold,
    /// Inputs carry the device's outputs, byte for byte (as far as both
    /// reach): wire an output terminal's pins to an input terminal's.
    Loopback,
    /// Inputs carry a counter (little-endian, repeated over the bytes)
    /// that counts the twin's polls.
    Counter,
}

impl InputRule {
    /// Every rule by its command-line name.
    pub const ALL: [(&'static str, InputRule); 3] = [
        ("hold", InputRule::Hold),
        ("loopback", InputRule::Loopback),
        ("counter", InputRule::Counter),
    ];

    /// The rule named `name`.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name.trim()))
            .map(|(_, r)| *r)
    }
}

/// The input rule of every twin of a line: a default and, per device type
/// (order code, any case), another one. Written `RULE[,TYPE=RULE...]`,
/// e.g. `hold,EL1008=counter,IO8=loopback`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct InputRules {
    /// The rule of devices not named.
    pub default: InputRule,
    /// `(type, rule)` pairs.
    pub per_type: Vec<(String, InputRule)>,
}

impl InputRules {
    /// Every twin follows `rule`.
    pub fn all(rule: InputRule) -> Self {
        InputRules {
            default: rule,
            per_type: Vec::new(),
        }
    }

    /// The rule of a device of type `type_name`.
    pub fn for_type(&self, type_name: &str) -> InputRule {
        self.per_type
            .iter()
            .find(|(t, _)| t.eq_ignore_ascii_case(type_name))
            .map_or(self.default, |(_, r)| *r)
    }
}

impl core::str::FromStr for InputRules {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let unknown =
            |r: &str| format!("unknown input rule '{r}' (known: hold, loopback, counter)");
        let mut out = InputRules::default();
        for (k, part) in s.split(',').map(str::trim).enumerate() {
            match part.split_once('=') {
                Some((ty, r)) if !ty.trim().is_empty() => {
                    let rule = InputRule::parse(r).ok_or_else(|| unknown(r))?;
                    out.per_type.push((ty.trim().to_string(), rule));
                }
                Some(_) => return Err(format!("'{part}': write TYPE=RULE")),
                None if k == 0 => {
                    out.default = InputRule::parse(part).ok_or_else(|| unknown(part))?
                }
                None => {
                    return Err(format!(
                        "'{part}': only the first rule may stand without TYPE="
                    ));
                }
            }
        }
        Ok(out)
    }
}

/// One process-data SyncManager of the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PdSm {
    index: u8,
    output: bool,
}

static EMPTY: Dictionary = Dictionary::new(&[], &[], &[]);

/// Descriptions built so far, one per distinct device.
static DESCRIPTIONS: crate::Cache<&'static DeviceDescription> = crate::Cache::new();

/// The description of an ESC-only device: identity and names; no
/// dictionary, no mailbox, no PDO sets (its PDOs are fixed in the SII).
/// Leaked once per distinct device.
fn description(dev: &EsiDevice) -> &'static DeviceDescription {
    let built: Result<_, core::convert::Infallible> =
        DESCRIPTIONS.get_or_build(dev, |dev| Ok(build_description(dev)));
    match built {
        Ok(d) => d,
        Err(never) => match never {},
    }
}

/// [`description`] without the cache.
fn build_description(dev: &EsiDevice) -> &'static DeviceDescription {
    let (identity, names) = crate::identity_and_names(dev);
    Box::leak(Box::new(DeviceDescription {
        identity,
        names,
        dictionary: &EMPTY,
        process_data: ProcessData { sets: &[] },
        mailbox: MailboxConfig {
            size: 0,
            boot_size: None,
            coe: CoeServices {
                sdo_info: false,
                pdo_assign: false,
                pdo_config: false,
                complete_access: false,
            },
            foe: false,
            foe_security: FoeSecurity::OPEN,
        },
        esc: EscConfig {
            pdi_control: u16::from_le_bytes([
                dev.config_data.first().copied().unwrap_or(0),
                dev.config_data.get(1).copied().unwrap_or(0),
            ]),
            eeprom_kbit: 16,
            ebus_current_ma: dev.ebus_current_ma,
            physical_ports: crate::sii::physical_port(&dev.physics),
        },
        modules: None,
    }))
}

/// A twin of an ESC-only device on a line.
pub struct EscTwin {
    esc: SoftEsc,
    description: &'static DeviceDescription,
    od: ObjectStore<[i64; 0]>,
    sms: Vec<PdSm>,
    rule: InputRule,
    held: Vec<u8>,
    outputs: Vec<u8>,
    polls: u32,
    stalled: bool,
}

impl core::fmt::Debug for EscTwin {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("EscTwin")
            .field("device", &self.description.names.type_name)
            .field("rule", &self.rule)
            .finish_non_exhaustive()
    }
}

impl EscTwin {
    /// A twin of `dev` serving `sii` (see [`crate::sii::image`]).
    pub fn new(dev: &EsiDevice, sii: &[u8], rule: InputRule) -> Self {
        let sms = dev
            .sms
            .iter()
            .enumerate()
            .filter_map(|(i, s)| {
                let index = u8::try_from(i).ok()?;
                match s.kind {
                    SmType::ProcessOut => Some(PdSm {
                        index,
                        output: true,
                    }),
                    SmType::ProcessIn => Some(PdSm {
                        index,
                        output: false,
                    }),
                    _ => None,
                }
            })
            .collect();
        EscTwin {
            esc: SoftEsc::new(sii),
            description: description(dev),
            od: ObjectStore::new(&EMPTY),
            sms,
            rule,
            held: Vec::new(),
            outputs: Vec::new(),
            polls: 0,
            stalled: false,
        }
    }

    /// The input rule.
    pub fn rule(&self) -> InputRule {
        self.rule
    }

    /// Sets the input bytes [`InputRule::Hold`] serves (all input
    /// SyncManagers one after the other).
    pub fn set_inputs(&mut self, bytes: &[u8]) {
        self.held = bytes.to_vec();
    }

    /// The output bytes as the ESC held them at the last poll (all output
    /// SyncManagers one after the other).
    pub fn outputs(&self) -> &[u8] {
        &self.outputs
    }

    /// The SyncManager's area as the master configured it, when active.
    fn sm_area(&self, sm: u8) -> Option<(u16, u16)> {
        let mem = self.esc.raw_memory();
        let base = usize::from(reg::sm(sm)?);
        let r = mem.get(base..base + usize::from(reg::SM_LEN))?;
        let word = |at: u16| -> Option<u16> {
            let at = usize::from(at);
            Some(u16::from_le_bytes([*r.get(at)?, *r.get(at + 1)?]))
        };
        let start = word(reg::sm::START)?;
        let len = word(reg::sm::LENGTH)?;
        let active = r.get(usize::from(reg::sm::ACTIVATE))? & reg::sm::ACTIVATE_ENABLE != 0;
        (active && len > 0).then_some((start, len))
    }

    fn al_state(&self) -> Option<AlState> {
        let mem = self.esc.raw_memory();
        let v = mem.get(usize::from(reg::AL_STATUS))?;
        AlState::from_bits(v & 0x0F)
    }

    /// What the digital I/O pins do once: outputs read, inputs written.
    pub fn poll(&mut self, now_ns: u64) -> Result<(), EscError> {
        self.esc.update_watchdogs(now_ns);
        if self.stalled {
            return Ok(());
        }
        self.polls = self.polls.wrapping_add(1);
        let running = matches!(self.al_state(), Some(AlState::SafeOp | AlState::Op));
        let mut outputs = Vec::new();
        for sm in self.sms.iter().filter(|s| s.output) {
            if let Some((start, len)) = self.sm_area(sm.index) {
                let mut buf = vec![0u8; usize::from(len)];
                self.esc.read(start, &mut buf)?;
                outputs.extend_from_slice(&buf);
            }
        }
        if !outputs.is_empty() {
            self.outputs = outputs;
        }
        if !running {
            return Ok(());
        }
        let mut offset = 0usize;
        let counter = self.polls.to_le_bytes();
        for sm in self.sms.clone().iter().filter(|s| !s.output) {
            let Some((start, len)) = self.sm_area(sm.index) else {
                continue;
            };
            let data: Vec<u8> = (0..usize::from(len))
                .map(|i| {
                    let k = offset + i;
                    match self.rule {
                        InputRule::Hold => self.held.get(k).copied().unwrap_or(0),
                        InputRule::Loopback => self.outputs.get(k).copied().unwrap_or(0),
                        InputRule::Counter => counter.get(k % 4).copied().unwrap_or(0),
                    }
                })
                .collect();
            self.esc.write(start, &data)?;
            offset += usize::from(len);
        }
        Ok(())
    }
}

impl LineSlave for EscTwin {
    fn description(&self) -> &'static DeviceDescription {
        self.description
    }
    fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome {
        self.esc.process_frame(frame)
    }
    fn esc(&self) -> &SoftEsc {
        &self.esc
    }
    fn esc_mut(&mut self) -> &mut SoftEsc {
        &mut self.esc
    }
    fn poll_with(
        &mut self,
        now_ns: u64,
        _images: Option<&mut dyn ImageStore>,
    ) -> Result<(), EscError> {
        self.poll(now_ns)
    }
    fn power_cycle(&mut self) {
        self.esc.power_on();
        self.outputs.clear();
        self.polls = 0;
    }
    fn set_port1_link(&mut self, link: bool) {
        self.esc.set_port1_link(link);
    }
    fn set_firmware_version(&mut self, _version: &str) {}
    /// An ESC-only device runs no firmware: nothing to start or refuse.
    fn set_no_valid_firmware(&mut self, _none: bool) {}
    fn firmware_version(&self) -> String {
        String::new()
    }
    fn led_patterns(&self) -> (LedPattern, LedPattern) {
        (LedPattern::Off, LedPattern::Off)
    }
    fn leds(&self) -> (bool, bool) {
        (false, false)
    }
    fn set_stalled(&mut self, stalled: bool) {
        self.stalled = stalled;
    }
    fn set_emergencies(&mut self, _enabled: bool) {}
    fn emergencies_waiting(&self) -> usize {
        0
    }
    fn al_status(&self) -> AlStatus {
        AlStatus {
            state: self.al_state().unwrap_or(AlState::Init),
            error: false,
            code: AlStatusCode::NoError,
        }
    }
    fn od(&self) -> &Od {
        <[i64; 0] as ValueStorage>::view(&self.od)
    }
    fn od_mut(&mut self) -> &mut Od {
        <[i64; 0] as ValueStorage>::view_mut(&mut self.od)
    }
    fn nv(&self) -> Option<&dyn NvStorage> {
        None
    }
    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        None
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_rules_parse_a_default_and_per_type_rules() {
        let r: InputRules = "hold, EL1008=counter,io8=loopback".parse().unwrap();
        assert_eq!(r.for_type("el1008"), InputRule::Counter);
        assert_eq!(r.for_type("IO8"), InputRule::Loopback);
        assert_eq!(r.for_type("EK1100"), InputRule::Hold);
        let r: InputRules = "counter".parse().unwrap();
        assert_eq!(r, InputRules::all(InputRule::Counter));
        for bad in ["jump", "hold,EL1008=jump", "hold,=counter", "hold,counter"] {
            assert!(bad.parse::<InputRules>().is_err(), "{bad}");
        }
    }
}
