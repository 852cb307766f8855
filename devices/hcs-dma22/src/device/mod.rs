//! The DMA-22(A) node as an EtherCAT modular device (ETG.5001) on the
//! `ecat-slave` core: one node with 1..=5 DMA-22(A) modules in slots 1..=5
//! (module address E22 = slot), each with the parameter list of chapter 7,
//! its CMD 15 block as process data and the behaviour of [`model`].
//!
//! Layers: `od` → `channel` → `model`, `params` → `map`
//!
//! ```
//! use ecat_sim::SoftSlave;
//! use hcs_dma22::device::Dma22Node;
//!
//! // The node of manual 5.4.2: three modules in operation mode 3.
//! let slave = SoftSlave::new(Dma22Node::<3>::default());
//! assert_eq!(slave.slave().od().get(0xF050, 0), Some(3));
//! ```

pub mod channel;
pub mod map;
pub mod model;
pub mod od;
pub mod params;

use ecat_slave::al::AlState;
use ecat_slave::device::{
    Application, DeviceDescription, DeviceNames, Download, EscConfig, Identity, MailboxConfig,
    PdoSet, ProcessData, Tick, Write,
};
use ecat_slave::od::Od;
use ecat_slave::wire::coe::SdoAbortCode;

use model::{MODES, Module};

pub use map::{DEVICE_NAME, MODULE_IDENT, PRODUCT_CODE, REVISION, SLOTS, VENDOR_ID};

/// The node, described once.
pub const DEVICE: DeviceDescription = DeviceDescription {
    identity: Identity {
        vendor_id: VENDOR_ID,
        product_code: PRODUCT_CODE,
        revision: REVISION,
        serial: 0,
    },
    names: DeviceNames {
        vendor: "HCS Hydraulic Control Systems GmbH",
        type_name: DEVICE_NAME,
        name: "DMA-22(A) EtherCAT node",
        group_type: "DMA",
        group_name: "HCS digital amplifiers",
    },
    dictionary: &od::DICT,
    process_data: ProcessData {
        sets: &[PdoSet {
            name: "Modules",
            rx: &[0x1600, 0x1601, 0x1602, 0x1603, 0x1604],
            tx: &[0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x1A04],
        }],
    },
    // 128-byte mailbox, SDO Information, PDO assignment, complete
    // access; no BOOT, no FoE.
    mailbox: MailboxConfig::STANDARD,
    esc: EscConfig::DEFAULT,
    modules: Some(&od::LAYOUT),
};

const _: () = DEVICE.assert_valid();

/// The node with `N` modules plugged in (1..=5; more are cut to 5).
#[derive(Debug, Clone)]
pub struct Dma22Node<const N: usize> {
    modes: [u8; N],
    modules: [Module; N],
    channel: channel::Channel,
}

impl<const N: usize> Default for Dma22Node<N> {
    /// `N` modules in operation mode 3 (closed loop, one valve), the
    /// default of E00 and the mode of the manual's 5.4.2 example.
    fn default() -> Self {
        Self::new([3; N])
    }
}

impl<const N: usize> Dma22Node<N> {
    /// The node with modules in the given operation modes (E00, one of
    /// [`MODES`]; an undocumented mode is taken as 3).
    pub fn new(modes: [u8; N]) -> Self {
        Dma22Node {
            modes: modes.map(|m| if MODES.contains(&m) { m } else { 3 }),
            modules: [Module::new(); N],
            channel: channel::Channel::new(),
        }
    }

    /// Module `slot` (0-based), if plugged in.
    pub fn module(&self, slot: usize) -> Option<&Module> {
        self.modules.get(slot)
    }

    /// Module `slot` (0-based), mutably: its hardware enable and digital
    /// inputs are the simulation's inputs.
    pub fn module_mut(&mut self, slot: usize) -> Option<&mut Module> {
        self.modules.get_mut(slot)
    }

    fn count() -> u8 {
        N.min(usize::from(SLOTS)) as u8
    }
}

impl<const N: usize> Application for Dma22Node<N> {
    fn description(&self) -> &'static DeviceDescription {
        &DEVICE
    }
    type Values = [i64; od::ENTRIES];

    fn power_on(&mut self, od: &mut Od) {
        let idents = [MODULE_IDENT; SLOTS as usize];
        let n = Self::count();
        od::LAYOUT.set_detected(od, idents.get(..usize::from(n)).unwrap_or(&[]));
        for (slot, mode) in self.modes.iter().enumerate().take(usize::from(n)) {
            let s = slot as u8;
            model::set(od, s, model::id::E00, i64::from(*mode));
            model::set(od, s, model::id::E22, i64::from(s) + 1);
        }
    }

    fn sdo_download(&mut self, od: &mut Od, d: &Download<'_>) -> Result<Write, SdoAbortCode> {
        // The HCS telegram channel: writing the request's length hands it
        // to the node, which answers into 0x2001.
        if d.index == channel::REQUEST {
            d.apply(od);
            if d.value(1).is_some() {
                let n = usize::from(Self::count());
                self.channel.serve_od(
                    od,
                    channel::Modules {
                        modules: self.modules.get_mut(..n).unwrap_or(&mut []),
                        modes: self.modes.get(..n).unwrap_or(&[]),
                    },
                );
            }
            return Ok(Write::Done);
        }
        // E Int (ID 0xB0, subindex 0xB1 of 0x80n0): only Din_1, Din_2 and
        // Bus disable are writable; the value shown is the module's.
        if d.index & 0xFF8F == map::PARAMS_LOW
            && let Some(v) = d.value(0xB1)
        {
            let slot = usize::from((d.index - map::PARAMS_LOW) >> 4);
            if let Some(m) = self.modules.get_mut(slot) {
                m.write_e_int(v as u16);
            }
        }
        Ok(Write::Store)
    }

    fn tick(&mut self, t: &mut Tick<'_>) {
        let valid = t.outputs_valid && t.state == AlState::Op;
        let mut bits = 0u8;
        for (slot, m) in self
            .modules
            .iter_mut()
            .enumerate()
            .take(usize::from(Self::count()))
        {
            let s = slot as u8;
            let mode = self.modes.get(slot).copied().unwrap_or(3);
            if let Some(err) = m.tick(t.od, s, mode, t.now_ns, valid) {
                // Manufacturer-specific Emergency: module address, error.
                t.emergency(0xFF00 | u16::from(err), [s + 1, err, 0, 0, 0]);
            }
            let diag = map::slot_index(map::DIAGNOSIS, s);
            t.od.set(diag, 1, i64::from(m.error));
            t.od.set(diag, 2, i64::from(m.errors));
            if m.error != 0 {
                bits |= ecat_slave::coe::emergency::register::MANUFACTURER;
            }
        }
        t.set_error_bits(bits);
    }

    fn power_cycle(&mut self) {
        self.modules = [Module::new(); N];
        self.channel = channel::Channel::new();
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests;
