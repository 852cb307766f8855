//! The amplifier as a periodic task (manual 4.5: 1 ms internal signal
//! processing): reads outputs and parameters from the object dictionary,
//! runs the directional or the two independent signal chains, drives the
//! power stage and writes process inputs and diagnosis back.
//!
//! Failure monitoring (manual 6.2.5, 8.1), decided here:
//! - SENS = ON: a fault (open wire, short circuit, supply under/over
//!   voltage, over temperature, EEPROM data error) latches, the power stage
//!   of the affected channel is switched off and READY drops. The latch is
//!   reset while ENABLE is off.
//! - SENS = AUTO: as ON, but the latch is re-checked every second and
//!   cleared when the fault has gone, so the channel resumes by itself. (An
//!   open wire is only seen while current is demanded, so a persistent one
//!   shows READY for a moment each second, as the manual describes.)
//! - SENS = OFF: no monitoring; diagnosis objects stay false.
//! - Diagnosis objects (0xA000/0xA010/0xA020) and their TxPDO bits are
//!   `true` while a fault is present or latched.
//! - No valid outputs (not in OP, watchdog expired) disables the power stage.
//! - An EEPROM data error at power-on (no valid parameter set) keeps the
//!   power stage off, independent of SENS, until parameters are saved
//!   (manual 8.1); 0xA000:01 MEMORY shows it.

use super::chain::{DirectionalChain, DirectionalParams, IndependentChain, IndependentParams};
use super::curve::{DirectionalCurve, IndependentCurve};
use super::deadband::{Deadband, DirectionalDeadband, MmType};
use super::entries::{
    BASIS, DIAGNOSIS, DIRECTIONAL, INDEPENDENT, IndependentEntries, StageEntries,
};
use super::sat_i32;
use crate::board::{Faults, PowerStage, Solenoid, StageParams, acc_gains, pwm_from_code};
use ecat_slave::od::Od;

/// Tick period of the application in microseconds.
pub const TICK_US: u32 = 1_000;
const TICK_NS: u64 = TICK_US as u64 * 1_000;
/// Interval of the SENS = AUTO re-check.
const AUTO_RECHECK_NS: u64 = 1_000_000_000;
/// Most ticks caught up in one call (a longer gap restarts the schedule).
const MAX_CATCH_UP: u64 = 100_000;

/// FUNCTION values (DT0800EN03).
const FUNCTION_IND: i64 = 2;
/// SENS values (DT0801EN03).
const SENS_OFF: i64 = 1;
const SENS_AUTO: i64 = 3;

/// Which faults concern a channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ChannelKind {
    Directional,
    Independent(Solenoid),
}

fn relevant(f: &Faults, kind: ChannelKind) -> Faults {
    let common = Faults {
        undervoltage: f.undervoltage,
        overvoltage: f.overvoltage,
        overtemperature: f.overtemperature,
        ..Faults::default()
    };
    match kind {
        ChannelKind::Directional => *f,
        ChannelKind::Independent(Solenoid::A) => Faults {
            open_a: f.open_a,
            short_a: f.short_a,
            ..common
        },
        ChannelKind::Independent(Solenoid::B) => Faults {
            open_b: f.open_b,
            short_b: f.short_b,
            ..common
        },
    }
}

fn or(a: Faults, b: Faults) -> Faults {
    Faults {
        open_a: a.open_a || b.open_a,
        short_a: a.short_a || b.short_a,
        open_b: a.open_b || b.open_b,
        short_b: a.short_b || b.short_b,
        undervoltage: a.undervoltage || b.undervoltage,
        overvoltage: a.overvoltage || b.overvoltage,
        overtemperature: a.overtemperature || b.overtemperature,
    }
}

/// Latch of one channel's monitored faults.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Monitor {
    latched: bool,
    flags: Faults,
}

impl Monitor {
    /// Updates the latch; returns whether the channel may run.
    fn update(&mut self, sens: i64, enable: bool, now: Faults, recheck: bool) -> bool {
        if sens == SENS_OFF {
            *self = Monitor::default();
            return true;
        }
        let fault = now.any();
        if fault {
            self.latched = true;
            self.flags = or(self.flags, now);
        }
        if !enable && sens != SENS_AUTO && !fault {
            // SENS = ON: deactivating ENABLE resets the failure.
            *self = Monitor::default();
        } else if !enable && sens != SENS_AUTO {
            self.flags = now;
        }
        if sens == SENS_AUTO && recheck && !fault {
            *self = Monitor::default();
        }
        !self.latched
    }
}

/// The PAM-199 application state.
#[derive(Debug, Clone)]
pub struct Amplifier {
    dir: DirectionalChain,
    ind: [IndependentChain; 2],
    monitors: [Monitor; 3],
    last_ns: Option<u64>,
    next_recheck_ns: u64,
    /// Parameters in the EEPROM were invalid at power-on: the power stage
    /// stays off until parameters are saved (manual 8.1).
    pub eeprom_error: bool,
}

impl Default for Amplifier {
    fn default() -> Self {
        Self::new()
    }
}

// Out of line on a microcontroller: inlined at its many call sites, its
// 64-bit arithmetic costs hundreds of bytes of flash (issue 30).
#[cfg_attr(target_os = "none", inline(never))]
fn u16_of(v: i64) -> u16 {
    v.clamp(0, i64::from(u16::MAX)) as u16
}

fn stage_params(store: &Od, e: &StageEntries) -> StageParams {
    let pwm_hz = pwm_from_code(sat_i32(e.pwm.get(store)).clamp(0, 255) as u8).unwrap_or(2500);
    StageParams {
        current_ma: u16_of(e.current.get(store)),
        dampl: u16_of(e.dampl.get(store)),
        dfreq: u16_of(e.dfreq.get(store)),
        pwm_hz,
        acc: e.acc.get(store) == 1,
        ppwm: u16_of(e.ppwm.get(store)),
        ipwm: u16_of(e.ipwm.get(store)),
    }
}

fn mmtype(v: i64) -> MmType {
    if v == 1 { MmType::Lin } else { MmType::Jmp }
}

fn directional_params(store: &Od) -> DirectionalParams {
    let d = &DIRECTIONAL;
    let mut curve = DirectionalCurve::default();
    for (sub, v) in d.curve.values(store) {
        curve.od_set(sub, sat_i32(v).clamp(-10_000, 10_000) as i16);
    }
    DirectionalParams {
        ramp_up_a_ms: sat_i32(d.ramp_up_a.get(store)).clamp(1, 120_000) as u32,
        ramp_down_a_ms: sat_i32(d.ramp_down_a.get(store)).clamp(1, 120_000) as u32,
        ramp_up_b_ms: sat_i32(d.ramp_up_b.get(store)).clamp(1, 120_000) as u32,
        ramp_down_b_ms: sat_i32(d.ramp_down_b.get(store)).clamp(1, 120_000) as u32,
        cc_enabled: d.cc_mode.get(store) == 1,
        curve,
        deadband: DirectionalDeadband {
            mmtype: mmtype(d.mmtype.get(store)),
            trigger: u16_of(d.trigger.get(store)),
            min_a: u16_of(d.min_a.get(store)),
            max_a: u16_of(d.max_a.get(store)),
            min_b: u16_of(d.min_b.get(store)),
            max_b: u16_of(d.max_b.get(store)),
        },
        io_base: u16_of(BASIS.io_base.get(store)).max(1),
        current_ma: u16_of(d.stage.current.get(store)),
    }
}

fn independent_params(store: &Od, e: &IndependentEntries) -> IndependentParams {
    let mut curve = IndependentCurve::default();
    for (sub, v) in e.curve.values(store) {
        curve.od_set(sub, sat_i32(v).clamp(0, 10_000) as i16);
    }
    IndependentParams {
        ramp_up_ms: sat_i32(e.ramp_up.get(store)).clamp(1, 120_000) as u32,
        ramp_down_ms: sat_i32(e.ramp_down.get(store)).clamp(1, 120_000) as u32,
        cc_enabled: e.cc_mode.get(store) == 1,
        curve,
        deadband: Deadband {
            mmtype: mmtype(e.mmtype.get(store)),
            trigger: u16_of(e.trigger.get(store)),
            min: u16_of(e.min.get(store)),
            max: u16_of(e.max.get(store)),
        },
        io_base: u16_of(BASIS.io_base.get(store)).max(1),
        current_ma: u16_of(e.stage.current.get(store)),
    }
}

/// While ACC is on, PPWM/IPWM show the gains adapted to the PWM frequency.
/// Returns the stage's parameters as they are after that.
fn publish_acc_gains(store: &mut Od, e: &StageEntries) -> StageParams {
    let mut p = stage_params(store, e);
    if p.acc {
        let g = acc_gains(p.pwm_hz);
        e.ppwm.set(store, i64::from(g.ppwm));
        e.ipwm.set(store, i64::from(g.ipwm));
        p.ppwm = u16_of(i64::from(g.ppwm));
        p.ipwm = u16_of(i64::from(g.ipwm));
    }
    p
}

impl Amplifier {
    /// An amplifier with every channel at rest.
    pub fn new() -> Self {
        Amplifier {
            dir: DirectionalChain::new(DirectionalParams::default()),
            ind: [
                IndependentChain::new(IndependentParams::default()),
                IndependentChain::new(IndependentParams::default()),
            ],
            monitors: [Monitor::default(); 3],
            last_ns: None,
            next_recheck_ns: AUTO_RECHECK_NS,
            eeprom_error: false,
        }
    }

    /// Runs every 1 ms tick due up to `now_ns`. `outputs_valid` is false
    /// when the master's outputs must not act (not OP, watchdog expired):
    /// the power stage is then off.
    pub fn run_until<P: PowerStage>(
        &mut self,
        store: &mut Od,
        stage: &mut P,
        now_ns: u64,
        outputs_valid: bool,
    ) {
        let last = match self.last_ns {
            Some(l) if now_ns >= l => l,
            _ => {
                self.last_ns = Some(now_ns);
                self.next_recheck_ns = now_ns + AUTO_RECHECK_NS;
                self.tick(store, stage, now_ns, outputs_valid);
                return;
            }
        };
        let due = super::div_rem_u64(now_ns - last, TICK_NS).0;
        if due > MAX_CATCH_UP {
            self.last_ns = Some(now_ns);
            self.tick(store, stage, now_ns, outputs_valid);
            return;
        }
        for i in 1..=due {
            self.tick(store, stage, last + i * TICK_NS, outputs_valid);
        }
        self.last_ns = Some(last + due * TICK_NS);
    }

    /// One 1 ms tick at time `now_ns`.
    pub fn tick<P: PowerStage>(
        &mut self,
        store: &mut Od,
        stage: &mut P,
        now_ns: u64,
        outputs_valid: bool,
    ) {
        let recheck = now_ns >= self.next_recheck_ns;
        if recheck {
            self.next_recheck_ns = now_ns + AUTO_RECHECK_NS;
        }
        let sens = BASIS.sens.get(store);
        let faults = stage.faults();
        let eeprom = self.eeprom_error;
        let mut shown = Faults::default();
        if BASIS.function.get(store) == FUNCTION_IND {
            let mut outs = [None, None];
            for (i, sol) in [Solenoid::A, Solenoid::B].into_iter().enumerate() {
                let Some(e) = INDEPENDENT.get(i) else {
                    continue;
                };
                let enable = e.enable.get(store) != 0 && outputs_valid;
                let rel = relevant(&faults, ChannelKind::Independent(sol));
                let Some(mon) = self.monitors.get_mut(i + 1) else {
                    continue;
                };
                let ok = mon.update(sens, enable, rel, recheck);
                shown = or(shown, mon.flags);
                let ready = enable && ok && !eeprom;
                let Some(chain) = self.ind.get_mut(i) else {
                    continue;
                };
                chain.set_params(independent_params(store, e));
                let out = chain.step(e.command.get(store) as i32, ready, TICK_US);
                let sp = publish_acc_gains(store, &e.stage);
                if ready {
                    let ma = u16_of(i64::from(out.current_setpoint_ma));
                    stage.set_current(sol, ma, sp.dither(), sp.pwm_hz, sp.gains());
                } else {
                    stage.set_current(sol, 0, sp.dither(), sp.pwm_hz, sp.gains());
                }
                if let Some(slot) = outs.get_mut(i) {
                    *slot = Some((ready, out));
                }
            }
            stage.step(TICK_US);
            for (i, sol) in [Solenoid::A, Solenoid::B].into_iter().enumerate() {
                if let (Some(e), Some(Some((ready, out)))) = (INDEPENDENT.get(i), outs.get(i)) {
                    e.ready.set(store, i64::from(*ready));
                    e.w.set(store, i64::from(out.w.max(0)));
                    e.c.set(store, i64::from(out.c.max(0)));
                    e.u.set(store, i64::from(out.u.max(0)));
                    e.current.set(store, i64::from(stage.measured_ma(sol)));
                }
            }
            DIRECTIONAL.inputs.clear(store);
            self.dir.reset();
        } else {
            let d = &DIRECTIONAL;
            let enable = d.enable.get(store) != 0 && outputs_valid;
            let rel = relevant(&faults, ChannelKind::Directional);
            let mon = &mut self.monitors[0];
            let ok = mon.update(sens, enable, rel, recheck);
            shown = mon.flags;
            let ready = enable && ok && !eeprom;
            self.dir.set_params(directional_params(store));
            let out = self.dir.step(d.command.get(store) as i32, ready, TICK_US);
            let sp = publish_acc_gains(store, &d.stage);
            let setpoint = if ready { out.current_setpoint_ma } else { 0 };
            let a = u16_of(i64::from(setpoint.max(0)));
            let b = u16_of(i64::from((-setpoint).max(0)));
            stage.set_current(Solenoid::A, a, sp.dither(), sp.pwm_hz, sp.gains());
            stage.set_current(Solenoid::B, b, sp.dither(), sp.pwm_hz, sp.gains());
            stage.step(TICK_US);
            d.ready.set(store, i64::from(ready));
            d.w.set(store, i64::from(out.w));
            d.c.set(store, i64::from(out.c));
            d.u.set(store, i64::from(out.u));
            d.ia.set(store, i64::from(stage.measured_ma(Solenoid::A)));
            d.ib.set(store, i64::from(stage.measured_ma(Solenoid::B)));
            for e in &INDEPENDENT {
                e.inputs.clear(store);
            }
            for c in &mut self.ind {
                c.reset();
            }
        }
        let show = sens != SENS_OFF;
        let flag = |on: bool| i64::from(show && on);
        let diag = &DIAGNOSIS;
        diag.memory.set(store, flag(eeprom));
        diag.undervoltage
            .set(store, flag(shown.undervoltage || faults.undervoltage));
        diag.overvoltage
            .set(store, flag(shown.overvoltage || faults.overvoltage));
        diag.temperature
            .set(store, flag(shown.overtemperature || faults.overtemperature));
        let [short_a, short_b] = diag.short;
        let [open_a, open_b] = diag.open;
        short_a.set(store, flag(shown.short_a || faults.short_a));
        open_a.set(store, flag(shown.open_a || faults.open_a));
        short_b.set(store, flag(shown.short_b || faults.short_b));
        open_b.set(store, flag(shown.open_b || faults.open_b));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::board::{Fault, SimPowerStage};

    fn run(amp: &mut Amplifier, s: &mut Od, st: &mut SimPowerStage, from: u64, ms: u64) -> u64 {
        let to = from + ms * 1_000_000;
        amp.run_until(s, st, to, true);
        to
    }

    fn setup() -> (Amplifier, crate::Store, SimPowerStage, u64) {
        let mut s = crate::store();
        s.set(0x800D, 2, 1500);
        s.set(0x800A, 5, 0); // TRIGGER 0: U = C exactly
        s.set(0x800D, 3, 0); // no dither: a steady current
        let mut amp = Amplifier::new();
        let mut st = SimPowerStage::new();
        amp.run_until(&mut s, &mut st, 0, true);
        (amp, s, st, 0)
    }

    #[test]
    fn half_command_settles_ia_at_half_current_after_the_ramp() {
        let (mut amp, mut s, mut st, t) = setup();
        s.set(0x7000, 1, 1);
        s.set(0x7000, 3, 5000);
        let t = run(&mut amp, &mut s, &mut st, t, 50);
        assert_eq!(
            s.get(0x6000, 4),
            Some(5000),
            "C reached W after the 100 ms ramp's half"
        );
        let _ = run(&mut amp, &mut s, &mut st, t, 150);
        assert_eq!(s.get(0x6000, 1), Some(1), "READY");
        assert_eq!(s.get(0x6000, 3), Some(5000));
        let ia = s.get(0x6000, 6).unwrap();
        assert!((735..=765).contains(&ia), "IA {ia} mA within 2 % of 750");
        assert_eq!(s.get(0x6000, 7), Some(0), "IB off");
    }

    #[test]
    fn negative_command_drives_solenoid_b() {
        let (mut amp, mut s, mut st, t) = setup();
        s.set(0x7000, 1, 1);
        s.set(0x7000, 3, -10_000);
        run(&mut amp, &mut s, &mut st, t, 300);
        let ib = s.get(0x6000, 7).unwrap();
        assert!((1470..=1530).contains(&ib), "IB {ib}");
        assert_eq!(s.get(0x6000, 6), Some(0));
    }

    #[test]
    fn open_wire_with_sens_on_latches_until_enable_is_cycled() {
        let (mut amp, mut s, mut st, t) = setup();
        s.set(0x7000, 1, 1);
        s.set(0x7000, 3, 5000);
        let t = run(&mut amp, &mut s, &mut st, t, 200);
        st.inject(Fault::OpenWire(Solenoid::A));
        let t = run(&mut amp, &mut s, &mut st, t, 20);
        assert_eq!(s.get(0x6000, 1), Some(0), "READY dropped");
        assert_eq!(s.get(0xA010, 2), Some(1), "open circuit shown");
        st.clear_faults();
        let t = run(&mut amp, &mut s, &mut st, t, 2000);
        assert_eq!(
            s.get(0x6000, 1),
            Some(0),
            "SENS=ON stays off after the fault went"
        );
        assert_eq!(s.get(0x6000, 6), Some(0), "current zero");
        s.set(0x7000, 1, 0);
        let t = run(&mut amp, &mut s, &mut st, t, 5);
        s.set(0x7000, 1, 1);
        run(&mut amp, &mut s, &mut st, t, 300);
        assert_eq!(s.get(0x6000, 1), Some(1), "ENABLE off/on resets");
        assert_eq!(s.get(0xA010, 2), Some(0));
    }

    #[test]
    fn sens_auto_resumes_once_the_fault_has_gone() {
        let (mut amp, mut s, mut st, t) = setup();
        s.set(0xF800, 3, 3);
        s.set(0x7000, 1, 1);
        s.set(0x7000, 3, 5000);
        let t = run(&mut amp, &mut s, &mut st, t, 200);
        st.inject(Fault::ShortCircuit(Solenoid::A));
        let t = run(&mut amp, &mut s, &mut st, t, 20);
        assert_eq!(s.get(0x6000, 1), Some(0));
        assert_eq!(s.get(0xA010, 1), Some(1));
        st.clear_faults();
        run(&mut amp, &mut s, &mut st, t, 1500);
        assert_eq!(s.get(0x6000, 1), Some(1), "AUTO resumed within a second");
    }

    #[test]
    fn sens_off_ignores_faults() {
        let (mut amp, mut s, mut st, t) = setup();
        s.set(0xF800, 3, 1);
        s.set(0x7000, 1, 1);
        s.set(0x7000, 3, 5000);
        st.inject(Fault::SupplyVoltage(10.0));
        run(&mut amp, &mut s, &mut st, t, 50);
        assert_eq!(s.get(0x6000, 1), Some(1));
        assert_eq!(s.get(0xA000, 2), Some(0));
    }

    #[test]
    fn independent_channels_run_separately() {
        let (mut amp, mut s, mut st, t) = setup();
        s.set(0xF800, 2, 2);
        s.set(0x801D, 2, 2000);
        s.set(0x802D, 2, 1000);
        s.set(0x801A, 5, 0);
        s.set(0x802A, 5, 0);
        s.set(0x801D, 3, 0);
        s.set(0x802D, 3, 0);
        s.set(0x7010, 1, 1);
        s.set(0x7010, 3, 10_000);
        s.set(0x7020, 1, 0);
        s.set(0x7020, 3, 10_000);
        run(&mut amp, &mut s, &mut st, t, 300);
        assert_eq!(s.get(0x6010, 1), Some(1));
        assert_eq!(s.get(0x6020, 1), Some(0), "channel 2 not enabled");
        let i1 = s.get(0x6010, 6).unwrap();
        assert!((1960..=2040).contains(&i1), "I1 {i1}");
        assert_eq!(s.get(0x6020, 6), Some(0));
        assert_eq!(s.get(0x6000, 1), Some(0), "directional inputs idle in IND");
    }

    #[test]
    fn invalid_outputs_switch_the_stage_off() {
        let (mut amp, mut s, mut st, t) = setup();
        s.set(0x7000, 1, 1);
        s.set(0x7000, 3, 5000);
        let t = run(&mut amp, &mut s, &mut st, t, 200);
        amp.run_until(&mut s, &mut st, t + 20_000_000, false);
        assert_eq!(s.get(0x6000, 1), Some(0));
        assert_eq!(s.get(0x6000, 6), Some(0));
    }

    #[test]
    fn acc_on_publishes_gains_for_the_pwm_frequency() {
        let (mut amp, mut s, mut st, t) = setup();
        s.set(0x800D, 5, 0x08); // 100 Hz
        run(&mut amp, &mut s, &mut st, t, 2);
        let g = acc_gains(100);
        assert_eq!(s.get(0x800D, 9), Some(i64::from(g.ppwm)));
        assert_eq!(s.get(0x800D, 10), Some(i64::from(g.ipwm)));
    }
}
