//! The behaviour of a twin with a mailbox: outputs stored, inputs per the
//! input rule, a drive's CiA 402 axes.

use super::*;

/// The generic behaviour of a twin with a mailbox: outputs are stored by
/// the core; inputs (entries mappable into TxPDOs) follow the rule.
#[derive(Debug)]
pub struct EsiApp {
    desc: &'static DeviceDescription,
    rule: InputRule,
    /// Module idents a modular device detects at power-on, slot order.
    modules: Vec<u32>,
    /// (input flat position, bit length, output flat position of the same
    /// type for the loopback).
    inputs: Vec<(usize, u16, Option<usize>)>,
    ticks: u64,
    /// A drive's axes (CiA 402: profile 402 in 0x1000, or 0x6040/0x6041,
    /// one per axis at n × 0x800): the profile's state machine and axis
    /// model answer its controlword and set points, so a master enables
    /// the twin as it enables the drive.
    axes: Vec<ecat_cia402::Cia402Axis>,
}

impl EsiApp {
    /// The behaviour of `desc` with input rule `rule`.
    pub fn new(desc: &'static DeviceDescription, rule: InputRule) -> Self {
        let mut flat = 0usize;
        let mut ins: Vec<(usize, DataType, u16)> = Vec::new();
        let mut outs: Vec<(usize, DataType)> = Vec::new();
        for o in desc.dictionary.objects() {
            for e in o.entries {
                let numeric = !e.data_type.is_bytes() && !e.gap();
                match e.pdo() {
                    PdoMapping::Tx if numeric => ins.push((flat, e.data_type, e.bit_len)),
                    PdoMapping::Rx if numeric => outs.push((flat, e.data_type)),
                    _ => {}
                }
                flat += 1;
            }
        }
        // Loopback: the k-th input of a type takes the k-th output of it.
        let mut used = vec![false; outs.len()];
        let inputs = ins
            .into_iter()
            .map(|(f, t, bits)| {
                let pick = outs
                    .iter()
                    .enumerate()
                    .find(|(i, (_, ot))| *ot == t && !used.get(*i).copied().unwrap_or(true))
                    .map(|(i, (of, _))| (i, *of));
                if let Some((i, _)) = pick
                    && let Some(u) = used.get_mut(i)
                {
                    *u = true;
                }
                (f, bits, pick.map(|(_, of)| of))
            })
            .collect();
        let dict = desc.dictionary;
        let axes = if ecat_cia402::Cia402Axis::is_cia402(dict) {
            ecat_cia402::Cia402Axis::axes_of(dict)
                .filter_map(|n| {
                    ecat_cia402::Cia402Axis::with_axis(dict, n, ecat_cia402::AxisModel::default())
                        .ok()
                })
                .collect()
        } else {
            Vec::new()
        };
        EsiApp {
            desc,
            rule,
            modules: Vec::new(),
            inputs,
            ticks: 0,
            axes,
        }
    }

    /// How many CiA 402 axes the twin runs (0: not a drive).
    pub fn axes(&self) -> usize {
        self.axes.len()
    }

    /// The same with these modules plugged (a modular device; see
    /// [`default_modules`]).
    pub fn with_modules(mut self, idents: Vec<u32>) -> Self {
        self.modules = idents;
        self
    }
}

impl Application for EsiApp {
    fn description(&self) -> &'static DeviceDescription {
        self.desc
    }

    type Values = [i64; TWIN_ENTRIES];

    fn power_on(&mut self, od: &mut ecat_slave::od::store::Od) {
        if let Some(m) = self.desc.modules {
            m.set_detected(od, &self.modules);
        }
    }

    fn sdo_download(
        &mut self,
        _od: &mut ecat_slave::od::store::Od,
        d: &ecat_slave::device::Download<'_>,
    ) -> Result<ecat_slave::device::Write, ecat_slave::SdoAbortCode> {
        for axis in &self.axes {
            axis.check_download(d)?;
        }
        Ok(ecat_slave::device::Write::Store)
    }

    fn power_cycle(&mut self) {
        for axis in &mut self.axes {
            axis.reset();
        }
    }

    fn tick(&mut self, tick: &mut Tick<'_>) {
        self.tick_inputs(tick);
        // After the input rule: a drive's actual values are the axis's.
        for axis in &mut self.axes {
            axis.tick(tick, None);
        }
    }
}

impl EsiApp {
    fn tick_inputs(&mut self, tick: &mut Tick<'_>) {
        self.ticks = self.ticks.wrapping_add(1);
        match self.rule {
            InputRule::Hold => {}
            InputRule::Loopback => {
                for (f, _, src) in &self.inputs {
                    if let Some(s) = src {
                        let v = tick.od.value(*s);
                        tick.od.set_value(*f, v);
                    }
                }
            }
            InputRule::Counter => {
                for (f, bits, _) in &self.inputs {
                    let mask = if *bits >= 64 {
                        u64::MAX
                    } else {
                        (1u64 << bits) - 1
                    };
                    tick.od.set_value(*f, (self.ticks & mask) as i64);
                }
            }
        }
    }
}

/// A software slave of `desc` laid out as `layout`, with `modules`
/// plugged when it is a modular device.
pub fn slave(
    desc: &'static DeviceDescription,
    layout: MemoryLayout,
    rule: InputRule,
    modules: Vec<u32>,
) -> SoftSlave<EsiApp> {
    SoftSlave::with_layout(EsiApp::new(desc, rule).with_modules(modules), layout)
}
