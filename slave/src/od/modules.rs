//! Modular devices (ETG.5001 Modular Device Profile): slots, modules and
//! the objects that repeat per slot.
//!
//! A modular device carries 1..=`slots` modules. Each module's objects sit
//! at a base index plus `slot × distance` (0x6000/0x7000/0x8000 + n × 0x10,
//! its PDOs at 0x1600/0x1A00 + n); the description lists them for every
//! slot, and an [`ObjectView`] hides the slots no module is plugged into:
//! SDO access to them aborts 0x06020000 and SDO Information does not list
//! them, as on a real modular device whose slot is empty.
//!
//! Three objects describe the modules (ETG.5001 chapter 4, ETG.1000.6
//! table 73):
//! - 0xF000 *Modular device profile*: sub 1 module index distance, sub 2
//!   maximum number of modules;
//! - 0xF030 *Configured module ident list*: written by the master in
//!   PRE-OP (TwinCAT does it from the ESI's `<Slots>`); checked against
//! - 0xF050 *Detected module ident list*: what the device found, filled by
//!   the application at power-on.
//!
//! At PRE-OP→SAFE-OP the core refuses a configured list that does not equal
//! the detected one with AL status 0x0070 (ETG.1000.6: "detected module
//! ident list (0xF050) and configured module ident list (0xF030) do not
//! match"); a master that never wrote 0xF030 (sub 0 = 0) is not checked,
//! as the SSC does (`CheckModuleIdentList` runs only on a written list).

use crate::al::AlStatusCode;
use crate::od::dictionary::Dictionary;
use crate::od::store::Od;
use crate::od::types::Object;

/// 0xF000 Modular device profile.
pub const MODULAR_DEVICE_PROFILE: u16 = 0xF000;
/// 0xF030 Configured module ident list.
pub const CONFIGURED_MODULES: u16 = 0xF030;
/// 0xF050 Detected module ident list.
pub const DETECTED_MODULES: u16 = 0xF050;

/// One kind of module the device accepts in a slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModuleType {
    /// Module ident (0xF030/0xF050 entries, ESI `ModuleIdent`).
    pub ident: u32,
    /// Module type name (ESI `Module/Type`).
    pub type_name: &'static str,
    /// Display name (ESI `Module/Name`).
    pub name: &'static str,
    /// Its RxPDOs in slot 0 (slot n adds n × the PDO increment).
    pub rx: &'static [u16],
    /// Its TxPDOs in slot 0.
    pub tx: &'static [u16],
}

/// Objects that repeat per slot: slot n's copy of `base` is at
/// `base + n × distance`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotRange {
    /// Index of slot 0's object.
    pub base: u16,
    /// Index step from one slot to the next.
    pub distance: u16,
    /// How many consecutive indices of a slot belong to the range.
    pub width: u16,
}

/// The modular layout of a device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModularLayout {
    /// Number of slots (0xF000:02, maximum number of modules).
    pub slots: u8,
    /// Module index distance (0xF000:01).
    pub index_distance: u16,
    /// PDO index increment per slot (ESI `SlotPdoIncrement`).
    pub pdo_increment: u16,
    /// Every range of per-slot objects, PDOs included.
    pub ranges: &'static [SlotRange],
    /// The module types.
    pub modules: &'static [ModuleType],
}

impl ModularLayout {
    /// The slot (0-based) whose object `index` is, or `None` for an object
    /// of the device itself.
    pub const fn slot_of(&self, index: u16) -> Option<u8> {
        let mut rest = self.ranges;
        while let Some((r, tail)) = rest.split_first() {
            rest = tail;
            if index < r.base || r.distance == 0 {
                continue;
            }
            let off = index - r.base;
            let slot = off / r.distance;
            if slot < self.slots as u16 && off % r.distance < r.width {
                return Some(slot as u8);
            }
        }
        None
    }

    /// The module type of `ident`.
    pub fn module(&self, ident: u32) -> Option<&'static ModuleType> {
        self.modules.iter().find(|m| m.ident == ident)
    }

    /// Number of modules detected (0xF050:00, at most [`Self::slots`]).
    pub fn detected(&self, od: &Od) -> u8 {
        let n = od.get(DETECTED_MODULES, 0).unwrap_or(0);
        n.clamp(0, i64::from(self.slots)) as u8
    }

    /// The ident of the module detected in `slot`, if any.
    pub fn detected_ident(&self, od: &Od, slot: u8) -> Option<u32> {
        if slot >= self.detected(od) {
            return None;
        }
        od.get(DETECTED_MODULES, slot.saturating_add(1))
            .map(|v| v as u32)
    }

    /// Sets the detected module list (0xF050) to `idents` (at most
    /// [`Self::slots`]; the rest is cut off) and the PDO assignment
    /// (0x1C12/0x1C13) to the modules' PDOs in slot order: what a device
    /// does at power-on after it has looked at its modules.
    pub fn set_detected(&self, od: &mut Od, idents: &[u32]) {
        let n = idents.len().min(usize::from(self.slots));
        od.set(DETECTED_MODULES, 0, n as i64);
        for s in 0..self.slots {
            let v = idents.get(usize::from(s)).filter(|_| usize::from(s) < n);
            od.set(
                DETECTED_MODULES,
                s.saturating_add(1),
                v.map_or(0, |v| i64::from(*v)),
            );
        }
        for (assign, rx) in [(0x1C12u16, true), (0x1C13u16, false)] {
            let mut k = 0u8;
            for (slot, ident) in idents.iter().take(n).enumerate() {
                let Some(m) = self.module(*ident) else {
                    continue;
                };
                let step = self.pdo_increment.saturating_mul(slot as u16);
                for pdo in if rx { m.rx } else { m.tx } {
                    k = k.saturating_add(1);
                    od.set(assign, k, i64::from(pdo.saturating_add(step)));
                }
            }
            od.set(assign, 0, i64::from(k));
        }
    }

    /// The PRE-OP→SAFE-OP check: a configured module list (0xF030, sub 0
    /// not 0) must equal the detected one (0xF050), count and idents.
    pub fn check_configured(&self, od: &Od) -> Result<(), AlStatusCode> {
        let configured = od.get(CONFIGURED_MODULES, 0).unwrap_or(0);
        if configured == 0 {
            return Ok(());
        }
        let detected = self.detected(od);
        if configured != i64::from(detected) {
            return Err(AlStatusCode::ModuleIdentMismatch);
        }
        for s in 1..=detected {
            if od.get(CONFIGURED_MODULES, s) != od.get(DETECTED_MODULES, s) {
                return Err(AlStatusCode::ModuleIdentMismatch);
            }
        }
        Ok(())
    }
}

impl From<&'static Dictionary> for ObjectView {
    fn from(dict: &'static Dictionary) -> Self {
        ObjectView::all(dict)
    }
}

/// What of a dictionary a master sees: every object of a compact device;
/// of a modular device, the device's own objects and those of the slots
/// that hold a module.
#[derive(Debug, Clone, Copy)]
pub struct ObjectView {
    /// The dictionary.
    pub dict: &'static Dictionary,
    layout: Option<&'static ModularLayout>,
    present: u8,
}

impl ObjectView {
    /// Every object of `dict`.
    pub const fn all(dict: &'static Dictionary) -> Self {
        ObjectView {
            dict,
            layout: None,
            present: 0,
        }
    }

    /// The objects of `dict` a modular device with `layout` shows with the
    /// modules it detected (0xF050) in `od`.
    pub fn modular(dict: &'static Dictionary, layout: &'static ModularLayout, od: &Od) -> Self {
        ObjectView {
            dict,
            layout: Some(layout),
            present: layout.detected(od),
        }
    }

    /// Whether object `index` is visible.
    pub fn visible(&self, index: u16) -> bool {
        match self.layout.and_then(|l| l.slot_of(index)) {
            Some(slot) => slot < self.present,
            None => true,
        }
    }

    /// The visible object `index` (position, object).
    pub fn find(&self, index: u16) -> Option<(usize, &'static Object)> {
        if !self.visible(index) {
            return None;
        }
        self.dict.find(index)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    const RANGES: &[SlotRange] = &[
        SlotRange {
            base: 0x1600,
            distance: 1,
            width: 1,
        },
        SlotRange {
            base: 0x6000,
            distance: 0x10,
            width: 2,
        },
    ];
    const LAYOUT: ModularLayout = ModularLayout {
        slots: 3,
        index_distance: 0x10,
        pdo_increment: 1,
        ranges: RANGES,
        modules: &[],
    };

    #[test]
    fn slot_of_finds_the_slot_of_repeated_objects_only() {
        assert_eq!(LAYOUT.slot_of(0x1600), Some(0));
        assert_eq!(LAYOUT.slot_of(0x1602), Some(2));
        assert_eq!(LAYOUT.slot_of(0x1603), None, "past the last slot");
        assert_eq!(LAYOUT.slot_of(0x6011), Some(1));
        assert_eq!(LAYOUT.slot_of(0x6012), None, "outside the slot's width");
        assert_eq!(LAYOUT.slot_of(0x6030), None);
        assert_eq!(LAYOUT.slot_of(0x1000), None);
        assert_eq!(LAYOUT.slot_of(0xFFFF), None);
    }
}
