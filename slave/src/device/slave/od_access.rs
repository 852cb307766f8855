//! The SDO adapter: CoE's view of the dictionary ([`ObjectAccess`]) with the
//! checks the device adds (PDO assignment and module list writes, state-
//! dependent access) and the application's write hooks.

use super::*;
use crate::device::Changes;

/// The object dictionary as the CoE server sees it: the store, the core's
/// rules for the PDO assignment, and the application's hooks.
pub(super) struct OdAccess<'a, A: Application> {
    pub(super) app: &'a mut A,
    pub(super) od: &'a mut Od,
    pub(super) state: AlState,
    pub(super) now_ns: u64,
}

/// What SDO access and SDO Information show of a device's dictionary (a
/// modular device hides its empty slots).
pub(super) fn object_view(desc: &'static DeviceDescription, od: &Od) -> ObjectView {
    let dict = desc.dictionary;
    match desc.modules {
        Some(m) => ObjectView::modular(dict, m, od),
        None => ObjectView::all(dict),
    }
}

impl<A: Application> OdAccess<'_, A> {
    /// A configured module list (0xF030) holds idents of module types the
    /// device knows (0 for an empty slot), at most one per slot.
    fn check_module_list(&self, index: u16, changes: Changes<'_>) -> Result<(), SdoAbortCode> {
        let Some(m) = self.app.description().modules else {
            return Ok(());
        };
        if index != CONFIGURED_MODULES {
            return Ok(());
        }
        for (s, v) in changes.iter() {
            if s == 0 {
                if v > i64::from(m.slots) {
                    return Err(SdoAbortCode::ValueTooHigh);
                }
            } else if v != 0 && m.module(v as u32).is_none() {
                return Err(SdoAbortCode::ValueRange);
            }
        }
        Ok(())
    }

    /// The core's rules for 0x1C12/0x1C13: only PDOs of the assignment's
    /// direction that exist, no more than its capacity, all of one PDO set.
    fn check_assignment(&self, index: u16, changes: Changes<'_>) -> Result<(), SdoAbortCode> {
        let dir = match index {
            0x1C12 => Direction::Outputs,
            0x1C13 => Direction::Inputs,
            _ => return Ok(()),
        };
        let new = |s: u8| -> Option<i64> { changes.value(s).or_else(|| self.od.get(index, s)) };
        let dict = self.od.dictionary();
        let cap = dict.find(index).map_or(0, |(_, o)| o.max_sub());
        let count = new(0).unwrap_or(0);
        if count > i64::from(cap) {
            return Err(SdoAbortCode::ValueTooHigh);
        }
        let (lo, hi) = dir.pdo_range();
        // Every written PDO must be one of the direction's mapping objects.
        for (_, v) in changes.iter().filter(|(s, _)| *s != 0) {
            let pdo = v as u16;
            if pdo < lo || pdo > hi || self.view().find(pdo).is_none() {
                return Err(SdoAbortCode::ValueRange);
            }
        }
        // The assigned PDOs (1..=count) must share a PDO set.
        let pd = &self.app.description().process_data;
        if !pd.sets.is_empty() {
            let mut sets = u32::MAX;
            for s in 1..=count.clamp(0, 255) as u8 {
                let pdo = new(s).unwrap_or(0) as u16;
                let m = crate::pdo::sets_of(pd, pdo);
                if m == 0 {
                    continue;
                }
                if sets & m == 0 {
                    return Err(SdoAbortCode::ParameterIncompatible);
                }
                sets &= m;
            }
        }
        Ok(())
    }

    /// The core's rules for a writable PDO mapping object (0x1600-0x17FF,
    /// 0x1A00-0x1BFF whose entries the description makes writable;
    /// ETG.1000.6 5.6.7.4.7, ETG.1020 "PDO mapping"): the entries change
    /// only while subindex 0 is 0 (0x06010003), each names an entry that
    /// exists and may be mapped in the PDO's direction with its own bit
    /// length, or padding (0x06040041); subindex 0 goes back up only over
    /// entries that are all set (0x06040043), at most what a process image
    /// holds (0x06040042). A complete access writes subindex 0 together
    /// with the entries, so its entries are judged as the new count says.
    fn check_mapping(
        &self,
        index: u16,
        complete_access: bool,
        changes: Changes<'_>,
    ) -> Result<(), SdoAbortCode> {
        // Fixed mappings (no writable entry in any mapping object) are
        // reached here only by a complete access writing back the values
        // they hold: nothing changes, nothing to check. Read from the
        // description, whose dictionary a firmware's compiler knows, so it
        // drops the rules.
        if !self.app.description().dictionary.has_writable_mapping() {
            return Ok(());
        }
        let dir = if (0x1600..=0x17FF).contains(&index) {
            Direction::Outputs
        } else if (0x1A00..=0x1BFF).contains(&index) {
            Direction::Inputs
        } else {
            return Ok(());
        };
        let dict = self.od.dictionary();
        let Some((_, o)) = dict.find(index) else {
            return Ok(());
        };
        if matches!(o.code, crate::od::ObjectCode::Var) {
            return Ok(());
        }
        // A mapping changes in PRE-OP only, whatever access a vendor's
        // ESI gives its entries (a twin's `rw`).
        if self.state != AlState::PreOp {
            return Err(SdoAbortCode::InvalidState);
        }
        let new = |s: u8| -> i64 {
            changes
                .value(s)
                .or_else(|| self.od.get(index, s))
                .unwrap_or(0)
        };
        let entries_written = changes.iter().any(|(s, _)| s != 0);
        if entries_written && !complete_access && self.od.get(index, 0).unwrap_or(0) != 0 {
            return Err(SdoAbortCode::SubindexCannotBeWritten);
        }
        // 0 clears a place (checked when the count covers it); a place
        // written with the value it holds changes nothing (a vendor's
        // default there is the vendor's).
        let unchanged = |s: u8, v: i64| self.od.get(index, s) == Some(v);
        for (s, v) in changes
            .iter()
            .filter(|&(s, v)| s != 0 && v != 0 && !unchanged(s, v))
        {
            if !(complete_access && i64::from(s) > new(0)) {
                crate::pdo::check_mapping_value(dict, dir, v as u32)?;
            }
        }
        let count = new(0);
        if count > i64::from(o.max_sub()) {
            return Err(SdoAbortCode::ValueTooHigh);
        }
        if changes.iter().any(|(s, _)| s == 0) && count > 0 {
            let mut bits = 0u32;
            for s in 1..=count.clamp(0, 255) as u8 {
                let m = new(s) as u32;
                if m == 0 {
                    return Err(SdoAbortCode::ParameterIncompatible);
                }
                crate::pdo::check_mapping_value(dict, dir, m)?;
                bits += m & 0xFF;
            }
            if count as usize > crate::pdo::MAX_MAPPED || bits as usize > crate::pdo::MAX_IMAGE * 8
            {
                return Err(SdoAbortCode::PdoLengthExceeded);
            }
        }
        Ok(())
    }

    fn hand_over(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        changes: Changes<'_>,
    ) -> Result<(), SdoAbortCode> {
        self.check_mapping(index, complete_access, changes)?;
        self.check_assignment(index, changes)?;
        self.check_module_list(index, changes)?;
        let d = Download {
            index,
            sub,
            complete_access,
            state: self.state,
            now_ns: self.now_ns,
            changes,
        };
        match self.app.sdo_download(self.od, &d)? {
            Write::Store => d.apply(self.od),
            Write::Done => {}
        }
        Ok(())
    }
}

impl<A: Application> ObjectAccess for OdAccess<'_, A> {
    fn dictionary(&self) -> &'static Dictionary {
        self.app.description().dictionary
    }

    fn view(&self) -> ObjectView {
        object_view(self.app.description(), self.od)
    }

    fn sdo_info(&self) -> bool {
        self.app.description().mailbox.coe.sdo_info
    }

    fn complete_access(&self) -> bool {
        self.app.description().mailbox.coe.complete_access
    }

    fn sdo_upload(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        out: &mut [u8],
    ) -> Result<usize, SdoAbortCode> {
        if !self.view().visible(index) {
            return Err(SdoAbortCode::ObjectNotFound);
        }
        self.app.sdo_upload(self.od, index, sub)?;
        if complete_access {
            // Checked here too, not only at the initiate: for a static
            // description the flag is a constant and a firmware without
            // complete access does not link its code.
            if !self.complete_access() {
                return Err(SdoAbortCode::UnsupportedAccess);
            }
            return complete::upload(self.od, index, sub, out);
        }
        self.od.upload(index, sub, out)
    }

    fn sdo_download(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        if !self.view().visible(index) {
            return Err(SdoAbortCode::ObjectNotFound);
        }
        if complete_access {
            if !self.complete_access() {
                return Err(SdoAbortCode::UnsupportedAccess);
            }
            // Checked here; the (subindex, value) pairs are decoded from
            // `data` wherever they are walked (no list on the stack).
            let changes = complete::check_download(self.od, index, sub, data, self.state)?;
            return self.hand_over(index, sub, true, Changes::complete(changes));
        }
        let (_, entry) = self.od.lookup(index, sub)?;
        let value = self.od.check(entry, data, self.state)?;
        self.hand_over(index, sub, false, Changes::list(&[(sub, value)]))
    }
}
