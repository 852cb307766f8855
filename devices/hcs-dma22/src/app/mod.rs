//! What the DMA-22(A) node does: [`Dma22Node`], the [`Application`] of
//! the core, with 1..=5 modules in its slots; each module's behaviour
//! ([`model`]: the operation modes, ramps, the closed loop, the solenoid
//! currents) and the HCS telegram channel over CoE ([`channel`]).
//!
//! Layers: `channel` → `model`
//!
//! ```
//! use ecat_sim::SoftSlave;
//! use hcs_dma22::Dma22Node;
//!
//! // The node of manual 5.4.2: three modules in operation mode 3.
//! let slave = SoftSlave::new(Dma22Node::<3>::default());
//! assert_eq!(slave.slave().od().get(0xF050, 0), Some(3));
//! ```

pub mod channel;
pub mod model;

use ecat_slave::al::AlState;
use ecat_slave::device::{Application, DeviceDescription, Download, Tick, Write};
use ecat_slave::od::Od;
use ecat_slave::wire::coe::SdoAbortCode;

use crate::description::map::{self, MODULE_IDENT, SLOTS};
use crate::description::{DEVICE, od};
use model::{MODES, Module};

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
        if d.index == map::REQUEST {
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
