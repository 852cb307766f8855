//! The object entries the amplifier task reads and writes, with their flat
//! positions in the store resolved once, at build time.
//!
//! A tick reads some 80 parameters and outputs and writes some 25 inputs
//! and diagnosis flags. Looking each one up by `index:sub`
//! ([`Od::get`] / [`Od::set`]: a binary search over the objects, then over
//! the entries) cost two thirds of the tick. Here every entry is named once
//! as an [`EntryPos`], whose flat position [`crate::description::od::position`] finds
//! while the crate is compiled (a name missing from [`crate::description::od::OBJECTS`]
//! is a build error); the task then reads and writes the store's value
//! slots directly ([`Od::value`] / [`Od::set_value`]).
//!
//! Nothing is copied out of the store: every read sees the value as it is
//! now, whoever wrote it (an SDO download or complete access, DEFAULT,
//! LOADBACK, the PDO engine, a test). The positions are those of the PAM's
//! dictionary [`crate::description::od::DICT`], so the store must be one of it
//! ([`crate::Store`]).

use crate::description::od;
use ecat_slave::od::Od;

/// One entry: its object index, subindex and flat position in the store.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EntryPos {
    /// Object index.
    pub index: u16,
    /// Subindex.
    pub sub: u8,
    /// Flat position of the entry's value in the store.
    pub flat: u16,
}

#[allow(
    clippy::panic,
    reason = "evaluated in const items only: a missing entry is a build error"
)]
const fn flat_of(index: u16, sub: u8) -> u16 {
    match od::position(index, sub) {
        Some(flat) if flat <= u16::MAX as usize => flat as u16,
        _ => panic!("the amplifier names an entry the dictionary does not have"),
    }
}

impl EntryPos {
    /// `index:sub`, resolved in `const` context (a missing entry stops the
    /// build).
    const fn of(index: u16, sub: u8) -> Self {
        EntryPos {
            index,
            sub,
            flat: flat_of(index, sub),
        }
    }

    /// The entry's value (0 if the store is shorter than the dictionary).
    #[inline]
    pub fn get(self, store: &Od) -> i64 {
        store.value(usize::from(self.flat))
    }

    /// Sets the entry's value without checks (process inputs, diagnosis).
    #[inline]
    pub fn set(self, store: &mut Od, v: i64) {
        store.set_value(usize::from(self.flat), v);
    }
}

/// Subindices `first..=last` of one object, at consecutive flat positions
/// (checked at build time; padding gaps included).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EntryRun {
    /// The first entry.
    pub first: EntryPos,
    /// The last subindex.
    pub last: u8,
}

impl EntryRun {
    #[allow(
        clippy::panic,
        reason = "evaluated in const items only: a hole in the run is a build error"
    )]
    const fn of(index: u16, first: u8, last: u8) -> Self {
        let run = EntryRun {
            first: EntryPos::of(index, first),
            last,
        };
        let mut sub = first;
        while sub <= last {
            if flat_of(index, sub) != run.first.flat + (sub - first) as u16 {
                panic!("the subindices of a run are not consecutive entries");
            }
            if sub == u8::MAX {
                break;
            }
            sub += 1;
        }
        run
    }

    /// Every `(subindex, flat position)` of the run, in order.
    pub fn entries(self) -> impl Iterator<Item = (u8, usize)> {
        let base = usize::from(self.first.flat);
        (self.first.sub..=self.last).zip(base..)
    }

    /// Every `(subindex, value)` of the run, in order.
    pub fn values(self, store: &Od) -> impl Iterator<Item = (u8, i64)> + '_ {
        self.entries().map(|(sub, flat)| (sub, store.value(flat)))
    }

    /// Sets every entry of the run to 0.
    pub fn clear(self, store: &mut Od) {
        for (_, flat) in self.entries() {
            store.set_value(flat, 0);
        }
    }
}

/// One power stage's parameters (0x800D, 0x801D, 0x802D).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StageEntries {
    /// :02 CURRENT.
    pub current: EntryPos,
    /// :03 DAMPL.
    pub dampl: EntryPos,
    /// :04 DFREQ.
    pub dfreq: EntryPos,
    /// :05 PWM.
    pub pwm: EntryPos,
    /// :07 ACC.
    pub acc: EntryPos,
    /// :09 PPWM.
    pub ppwm: EntryPos,
    /// :0A IPWM.
    pub ipwm: EntryPos,
}

impl StageEntries {
    const fn of(index: u16) -> Self {
        StageEntries {
            current: EntryPos::of(index, 2),
            dampl: EntryPos::of(index, 3),
            dfreq: EntryPos::of(index, 4),
            pwm: EntryPos::of(index, 5),
            acc: EntryPos::of(index, 7),
            ppwm: EntryPos::of(index, 9),
            ipwm: EntryPos::of(index, 10),
        }
    }
}

/// F800 BASIS: the settings both modes share.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BasisEntries {
    /// F800:01 IO_BASE.
    pub io_base: EntryPos,
    /// F800:02 FUNCTION.
    pub function: EntryPos,
    /// F800:03 SENS.
    pub sens: EntryPos,
}

/// Channel 0 (DIRECTIONAL): outputs 0x7000, parameters 0x8002, 0x8006,
/// 0x800A, 0x800D, inputs 0x6000.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DirectionalEntries {
    /// 7000:01 ENABLE.
    pub enable: EntryPos,
    /// 7000:03 COMMAND VALUE.
    pub command: EntryPos,
    /// 8002:02 RA:UP:A.
    pub ramp_up_a: EntryPos,
    /// 8002:03 RA:DOWN:A.
    pub ramp_down_a: EntryPos,
    /// 8002:04 RA:UP:B.
    pub ramp_up_b: EntryPos,
    /// 8002:05 RA:DOWN:B.
    pub ramp_down_b: EntryPos,
    /// 8006:01..2A, the 21 curve points (X, Y).
    pub curve: EntryRun,
    /// 800A:01 CCMODE.
    pub cc_mode: EntryPos,
    /// 800A:03 MMTYPE.
    pub mmtype: EntryPos,
    /// 800A:05 TRIGGER.
    pub trigger: EntryPos,
    /// 800A:06 MIN:A.
    pub min_a: EntryPos,
    /// 800A:07 MAX:A.
    pub max_a: EntryPos,
    /// 800A:08 MIN:B.
    pub min_b: EntryPos,
    /// 800A:09 MAX:B.
    pub max_b: EntryPos,
    /// 800D POWER STAGE.
    pub stage: StageEntries,
    /// 6000:01 READY.
    pub ready: EntryPos,
    /// 6000:03 W.
    pub w: EntryPos,
    /// 6000:04 C.
    pub c: EntryPos,
    /// 6000:05 U.
    pub u: EntryPos,
    /// 6000:06 IA.
    pub ia: EntryPos,
    /// 6000:07 IB.
    pub ib: EntryPos,
    /// 6000:01..07, cleared while the independent channels run.
    pub inputs: EntryRun,
}

/// Channel 1 or 2 (INDEPENDENT): outputs 0x7010/0x7020, parameters
/// 0x80n2, 0x80n6, 0x80nA, 0x80nD, inputs 0x6010/0x6020.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IndependentEntries {
    /// 70n0:01 ENABLEn.
    pub enable: EntryPos,
    /// 70n0:03 COMMAND VALUE n.
    pub command: EntryPos,
    /// 80n2:02 RA:UP:n.
    pub ramp_up: EntryPos,
    /// 80n2:03 RA:DOWN:n.
    pub ramp_down: EntryPos,
    /// 80n6:01..16, the 11 curve points (X, Y).
    pub curve: EntryRun,
    /// 80nA:01 CCMODE:n.
    pub cc_mode: EntryPos,
    /// 80nA:03 MMTYPE:n.
    pub mmtype: EntryPos,
    /// 80nA:05 TRIGGER:n.
    pub trigger: EntryPos,
    /// 80nA:06 MIN:n.
    pub min: EntryPos,
    /// 80nA:07 MAX:n.
    pub max: EntryPos,
    /// 80nD POWER STAGE CHANNEL n.
    pub stage: StageEntries,
    /// 60n0:01 READYn.
    pub ready: EntryPos,
    /// 60n0:03 Wn.
    pub w: EntryPos,
    /// 60n0:04 Cn.
    pub c: EntryPos,
    /// 60n0:05 Un.
    pub u: EntryPos,
    /// 60n0:06 In.
    pub current: EntryPos,
    /// 60n0:01..06, cleared while the directional channel runs.
    pub inputs: EntryRun,
}

impl IndependentEntries {
    const fn of(ch: u16) -> Self {
        let off = ch * 0x10;
        IndependentEntries {
            enable: EntryPos::of(0x7000 + off, 1),
            command: EntryPos::of(0x7000 + off, 3),
            ramp_up: EntryPos::of(0x8002 + off, 2),
            ramp_down: EntryPos::of(0x8002 + off, 3),
            curve: EntryRun::of(0x8006 + off, 1, 22),
            cc_mode: EntryPos::of(0x800A + off, 1),
            mmtype: EntryPos::of(0x800A + off, 3),
            trigger: EntryPos::of(0x800A + off, 5),
            min: EntryPos::of(0x800A + off, 6),
            max: EntryPos::of(0x800A + off, 7),
            stage: StageEntries::of(0x800D + off),
            ready: EntryPos::of(0x6000 + off, 1),
            w: EntryPos::of(0x6000 + off, 3),
            c: EntryPos::of(0x6000 + off, 4),
            u: EntryPos::of(0x6000 + off, 5),
            current: EntryPos::of(0x6000 + off, 6),
            inputs: EntryRun::of(0x6000 + off, 1, 6),
        }
    }
}

/// The diagnosis flags (0xA000, 0xA010, 0xA020).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DiagnosisEntries {
    /// A000:01 MEMORY.
    pub memory: EntryPos,
    /// A000:02 UNDERVOLTAGES.
    pub undervoltage: EntryPos,
    /// A000:03 OVERVOLTAGES.
    pub overvoltage: EntryPos,
    /// A000:04 TEMPERATURE.
    pub temperature: EntryPos,
    /// A010:01 / A020:01 SHORT CIRCUIT at solenoid A / B.
    pub short: [EntryPos; 2],
    /// A010:02 / A020:02 OPEN CIRCUIT at solenoid A / B.
    pub open: [EntryPos; 2],
}

/// F800 BASIS.
pub const BASIS: BasisEntries = BasisEntries {
    io_base: EntryPos::of(0xF800, 1),
    function: EntryPos::of(0xF800, 2),
    sens: EntryPos::of(0xF800, 3),
};

/// The directional channel.
pub const DIRECTIONAL: DirectionalEntries = DirectionalEntries {
    enable: EntryPos::of(0x7000, 1),
    command: EntryPos::of(0x7000, 3),
    ramp_up_a: EntryPos::of(0x8002, 2),
    ramp_down_a: EntryPos::of(0x8002, 3),
    ramp_up_b: EntryPos::of(0x8002, 4),
    ramp_down_b: EntryPos::of(0x8002, 5),
    curve: EntryRun::of(0x8006, 1, 42),
    cc_mode: EntryPos::of(0x800A, 1),
    mmtype: EntryPos::of(0x800A, 3),
    trigger: EntryPos::of(0x800A, 5),
    min_a: EntryPos::of(0x800A, 6),
    max_a: EntryPos::of(0x800A, 7),
    min_b: EntryPos::of(0x800A, 8),
    max_b: EntryPos::of(0x800A, 9),
    stage: StageEntries::of(0x800D),
    ready: EntryPos::of(0x6000, 1),
    w: EntryPos::of(0x6000, 3),
    c: EntryPos::of(0x6000, 4),
    u: EntryPos::of(0x6000, 5),
    ia: EntryPos::of(0x6000, 6),
    ib: EntryPos::of(0x6000, 7),
    inputs: EntryRun::of(0x6000, 1, 7),
};

/// The independent channels 1 and 2.
pub const INDEPENDENT: [IndependentEntries; 2] =
    [IndependentEntries::of(1), IndependentEntries::of(2)];

/// The diagnosis flags.
pub const DIAGNOSIS: DiagnosisEntries = DiagnosisEntries {
    memory: EntryPos::of(0xA000, 1),
    undervoltage: EntryPos::of(0xA000, 2),
    overvoltage: EntryPos::of(0xA000, 3),
    temperature: EntryPos::of(0xA000, 4),
    short: [EntryPos::of(0xA010, 1), EntryPos::of(0xA020, 1)],
    open: [EntryPos::of(0xA010, 2), EntryPos::of(0xA020, 2)],
};

/// 0x10F8 Timestamp Object (written by the device every poll).
pub const TIMESTAMP: EntryPos = EntryPos::of(0x10F8, 0);

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
mod tests {
    use super::*;

    fn stage_names(s: &StageEntries, n: &str) -> Vec<(EntryPos, String)> {
        let name = |base: &str| format!("{base}{n}");
        vec![
            (s.current, name("CURRENT")),
            (s.dampl, name("DAMPL")),
            (s.dfreq, name("DFREQ")),
            (s.pwm, name("PWM")),
            (s.acc, name("ACC")),
            (s.ppwm, name("PPWM")),
            (s.ipwm, name("IPWM")),
        ]
    }

    /// Every single entry the amplifier uses, with the manual's name of
    /// the entry it is meant to be.
    fn named() -> Vec<(EntryPos, String)> {
        let d = &DIRECTIONAL;
        let mut v: Vec<(EntryPos, String)> = [
            (BASIS.io_base, "IO_BASE"),
            (BASIS.function, "FUNCTION"),
            (BASIS.sens, "SENS"),
            (d.enable, "ENABLE"),
            (d.command, "COMMAND VALUE"),
            (d.ramp_up_a, "RA:UP:A"),
            (d.ramp_down_a, "RA:DOWN:A"),
            (d.ramp_up_b, "RA:UP:B"),
            (d.ramp_down_b, "RA:DOWN:B"),
            (d.cc_mode, "CCMODE"),
            (d.mmtype, "MMTYPE"),
            (d.trigger, "TRIGGER"),
            (d.min_a, "MIN:A"),
            (d.max_a, "MAX:A"),
            (d.min_b, "MIN:B"),
            (d.max_b, "MAX:B"),
            (d.ready, "READY"),
            (d.w, "W"),
            (d.c, "C"),
            (d.u, "U"),
            (d.ia, "IA"),
            (d.ib, "IB"),
            (DIAGNOSIS.memory, "MEMORY"),
            (DIAGNOSIS.undervoltage, "UNDERVOLTAGES"),
            (DIAGNOSIS.overvoltage, "OVERVOLTAGES"),
            (DIAGNOSIS.temperature, "TEMPERATURE"),
            (DIAGNOSIS.short[0], "SHORT CIRCUIT"),
            (DIAGNOSIS.short[1], "SHORT CIRCUIT"),
            (DIAGNOSIS.open[0], "OPEN CIRCUIT"),
            (DIAGNOSIS.open[1], "OPEN CIRCUIT"),
            (TIMESTAMP, "Timestamp Object"),
        ]
        .into_iter()
        .map(|(e, n)| (e, n.to_string()))
        .collect();
        v.extend(stage_names(&d.stage, ""));
        for (i, c) in INDEPENDENT.iter().enumerate() {
            let n = i + 1;
            v.extend([
                (c.enable, format!("ENABLE{n}")),
                (c.command, format!("COMMAND VALUE {n}")),
                (c.ramp_up, format!("RA:UP:{n}")),
                (c.ramp_down, format!("RA:DOWN:{n}")),
                (c.cc_mode, format!("CCMODE:{n}")),
                (c.mmtype, format!("MMTYPE:{n}")),
                (c.trigger, format!("TRIGGER:{n}")),
                (c.min, format!("MIN:{n}")),
                (c.max, format!("MAX:{n}")),
                (c.ready, format!("READY{n}")),
                (c.w, format!("W{n}")),
                (c.c, format!("C{n}")),
                (c.u, format!("U{n}")),
                (c.current, format!("I{n}")),
            ]);
            v.extend(stage_names(&c.stage, &format!(":{n}")));
        }
        v
    }

    /// The runs, with the object they cover and the names of their first
    /// and last entries.
    fn runs() -> Vec<(EntryRun, u16, &'static str, &'static str)> {
        vec![
            (DIRECTIONAL.curve, 0x8006, "CCB:10_X", "CCA:10_Y"),
            (DIRECTIONAL.inputs, 0x6000, "READY", "IB"),
            (INDEPENDENT[0].curve, 0x8016, "CC1:0_X", "CC1:10_Y"),
            (INDEPENDENT[0].inputs, 0x6010, "READY1", "I1"),
            (INDEPENDENT[1].curve, 0x8026, "CC2:0_X", "CC2:10_Y"),
            (INDEPENDENT[1].inputs, 0x6020, "READY2", "I2"),
        ]
    }

    /// The object at flat position `flat`, by the core's own lookup.
    fn object_at(flat: usize) -> u16 {
        let (pos, _) = od::DICT.locate(flat).unwrap();
        od::OBJECTS[pos].index
    }

    #[test]
    fn every_position_names_the_entry_it_is_meant_to() {
        let all = named();
        assert_eq!(all.len(), 31 + 7 + 2 * (14 + 7));
        for (e, name) in &all {
            let flat = usize::from(e.flat);
            // The core's search finds the same position for index:sub ...
            let (found, entry) = od::find_entry(e.index, e.sub).unwrap();
            assert_eq!(found, flat, "{name}: {:#06x}:{:02x}", e.index, e.sub);
            // ... and the position, read back, is that entry of that object.
            let at = od::entry_at(flat).unwrap();
            assert_eq!(object_at(flat), e.index, "{name}");
            assert_eq!(at.sub, e.sub, "{name}");
            assert_eq!(at.name, name.as_str(), "{:#06x}:{:02x}", e.index, e.sub);
            assert!(!entry.gap(), "{name} is a padding gap");
        }
        // No two names share a position.
        let mut flats: Vec<u16> = all.iter().map(|(e, _)| e.flat).collect();
        flats.sort_unstable();
        flats.dedup();
        assert_eq!(flats.len(), all.len());
    }

    #[test]
    fn every_run_covers_its_object_entry_by_entry() {
        for (run, index, first, last) in runs() {
            assert_eq!(run.first.index, index);
            let mut n = 0;
            for (sub, flat) in run.entries() {
                assert_eq!(od::find_entry(index, sub).map(|f| f.0), Some(flat));
                assert_eq!(object_at(flat), index);
                assert_eq!(od::entry_at(flat).unwrap().sub, sub);
                n += 1;
            }
            assert_eq!(n, usize::from(run.last - run.first.sub) + 1);
            let name = |sub| od::find_entry(index, sub).unwrap().1.name;
            assert_eq!(name(run.first.sub), first);
            assert_eq!(name(run.last), last);
            // The run ends with the object (its highest subindex).
            let (_, obj) = od::find(index).unwrap();
            assert_eq!(obj.entries.last().unwrap().sub, run.last);
        }
    }

    #[test]
    fn reads_and_writes_by_position_are_the_stores_by_index() {
        let mut s = crate::store();
        for (e, name) in named() {
            let v = i64::from(e.flat) * 7 + 3;
            e.set(&mut s, v);
            assert_eq!(s.get(e.index, e.sub), Some(v), "{name}");
            s.set(e.index, e.sub, -v);
            assert_eq!(e.get(&s), -v, "{name}");
        }
        for (run, index, ..) in runs() {
            for (sub, _) in run.entries() {
                s.set(index, sub, i64::from(sub) + 1);
            }
            let read: Vec<_> = run.values(&s).collect();
            assert!(read.iter().all(|(sub, v)| *v == i64::from(*sub) + 1));
            run.clear(&mut s);
            assert!(run.entries().all(|(sub, _)| s.get(index, sub) == Some(0)));
        }
    }
}
