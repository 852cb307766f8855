//! The solenoid power stage (manual 6.4, 4.5, 8.1): the [`PowerStage`]
//! trait the device drives, and [`SimPowerStage`], a simulated stage with
//! fault injection. The real board implements the same trait.
//!
//! Solenoid A is output 1 (PIN 3/4), B is output 2 (PIN 1/2). In directional
//! mode they are solenoids A and B; in independent mode A is channel 1 and B
//! channel 2.
//!
//! ## Simulation model (`f32`, it is a simulation)
//!
//! * Per solenoid an R-L coil (default R = 6 Ω, L = 30 mH: a 24 V valve coil that can carry the 3 A maximum) on a supply of
//!   24 V, `L di/dt = v − R i`, integrated with backward Euler (stable for any
//!   R, L) at a fixed internal step of [`SUB_STEP_US`] = 50 µs (the manual's
//!   current-control sample time is 0.053 ms). `step(dt_us)` runs
//!   `dt_us / 50` sub-steps and carries the remainder to the next call; one
//!   call runs at most [`MAX_SUB_STEPS`] sub-steps (1 s), longer gaps are
//!   cut off (the electrical time constants are milliseconds).
//! * The PWM is averaged: the applied voltage is `duty * supply` with duty
//!   0..1, the current never goes negative (freewheel diode). The PWM
//!   frequency is stored and used only to choose gains with ACC = ON
//!   ([`acc_gains`]); its ripple is not simulated.
//! * A PI current controller computes the coil voltage:
//!   `v = Kp * e + ∫ Ki * e dt`, `e = i_set − i`, with
//!   **`Kp = PPWM * 10` V/A** and **`Ki = IPWM * 500` V/(A·s)** (default
//!   PPWM 7, IPWM 40 → Kp = 70 V/A, Ki = 20000 V/(A·s); closed-loop poles
//!   ≈ −400 and −500 rad/s for the default coil). The output is clamped to
//!   0..supply, the integrator likewise and it stops integrating while the
//!   output saturates (anti-windup). A 750 mA step settles within ±2 % in
//!   well under 100 ms.
//! * When a solenoid's setpoint is 0 (or after [`PowerStage::disable`]) the
//!   stage applies quick discharge (−supply) until the current is 0, so
//!   switching off gives 0 mA within a few ms.
//! * Dither: a triangular wave of peak amplitude `DAMPL * CURRENT / 10000` mA
//!   (so peak-to-peak twice that) and frequency DFREQ, added to the setpoint
//!   while the setpoint is above 0; the sum is clamped at 0.
//!
//! ## Faults ([`SimPowerStage::inject`])
//!
//! Flags are *live* (they describe the present state); latching and the
//! SENS ON/OFF/AUTO behaviour belong to the device layer.
//!
//! * Open wire: the current is 0; `open_x` is set while a current is
//!   demanded (setpoint > 0).
//! * Short circuit: the output's protection switches it off, so the current
//!   is limited to 0; `short_x` is set while a current is demanded.
//! * Supply voltage: below [`UNDERVOLTAGE_V`] (12 V) → `undervoltage`, above
//!   [`OVERVOLTAGE_V`] (30 V) → `overvoltage` (manual 4.5: 12..30 V). The
//!   simulated coil sees the injected voltage (so at low supply the current
//!   may not reach its setpoint).
//! * Temperature of the stage: above [`OVERTEMPERATURE_C`] (85 °C, our
//!   choice: the manual gives only the ambient range −20..60 °C) →
//!   `overtemperature`.

use crate::description::FULL_SCALE;

/// Internal simulation step in µs.
pub const SUB_STEP_US: u32 = 50;
/// Most sub-steps run by one `step` call (1 s).
pub const MAX_SUB_STEPS: u32 = 20_000;
/// Supply voltage below which `undervoltage` is reported.
pub const UNDERVOLTAGE_V: f32 = 12.0;
/// Supply voltage above which `overvoltage` is reported.
pub const OVERVOLTAGE_V: f32 = 30.0;
/// Stage temperature above which `overtemperature` is reported.
pub const OVERTEMPERATURE_C: f32 = 85.0;
/// Default supply voltage.
pub const DEFAULT_SUPPLY_V: f32 = 24.0;
/// Default stage temperature.
pub const DEFAULT_TEMPERATURE_C: f32 = 25.0;
/// Default coil resistance.
pub const DEFAULT_R_OHM: f32 = 6.0;
/// Default coil inductance.
pub const DEFAULT_L_H: f32 = 0.03;

/// The PWM frequencies of DT0803EN05 as (frequency in Hz, enum code), read
/// from the object dictionary's one description of the enumeration.
pub fn pwm_table() -> impl Iterator<Item = (u16, u8)> {
    crate::description::od::DT0803EN05
        .values
        .iter()
        .filter_map(|(code, text)| Some((text.parse::<u16>().ok()?, u8::try_from(*code).ok()?)))
}

/// The PWM frequency in Hz for a DT0803EN05 code; `None` for unknown codes.
pub fn pwm_from_code(code: u8) -> Option<u16> {
    pwm_table().find(|(_, c)| *c == code).map(|(hz, _)| hz)
}

/// The DT0803EN05 code for a PWM frequency in Hz; `None` if the frequency
/// is not selectable.
pub fn pwm_code(hz: u16) -> Option<u8> {
    pwm_table().find(|(f, _)| *f == hz).map(|(_, c)| c)
}

/// One of the two outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solenoid {
    /// Solenoid A / channel 1 (PIN 3/4).
    A,
    /// Solenoid B / channel 2 (PIN 1/2).
    B,
}

/// The dither signal added to a current setpoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Dither {
    /// Peak amplitude in mA (peak-to-peak is twice this); 0 = off.
    pub amplitude_ma: u16,
    /// Frequency in Hz; 0 = off.
    pub freq_hz: u16,
}

impl Dither {
    /// No dither.
    pub const OFF: Self = Self {
        amplitude_ma: 0,
        freq_hz: 0,
    };

    /// From the parameters DAMPL (0.01 % of CURRENT, 0..3000), DFREQ (Hz,
    /// 50..400) and CURRENT (mA); values are clamped to their ranges.
    pub fn from_params(dampl: u16, dfreq: u16, current_ma: u16) -> Self {
        let a = u32::from(dampl.min(3_000)) * u32::from(current_ma.min(3_000));
        let half = FULL_SCALE.unsigned_abs() / 2;
        let amplitude = (a + half) / FULL_SCALE.unsigned_abs();
        Self {
            amplitude_ma: u16::try_from(amplitude).unwrap_or(u16::MAX),
            freq_hz: dfreq.clamp(50, 400),
        }
    }
}

/// Gains of the PI current controller (PPWM 0..300, IPWM 0..100).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PiGains {
    /// PPWM: P gain, Kp = PPWM * 10 V/A in the simulation.
    pub ppwm: u16,
    /// IPWM: I gain, Ki = IPWM * 500 V/(A·s) in the simulation.
    pub ipwm: u16,
}

impl Default for PiGains {
    /// The OD defaults PPWM 7, IPWM 40.
    fn default() -> Self {
        Self { ppwm: 7, ipwm: 40 }
    }
}

/// Gains chosen automatically with ACC = ON, from the PWM frequency.
///
/// The manual only says that lower PWM frequencies (longer dead times) need
/// lower gains; this table is our own choice, equal to the defaults at and
/// above 2000 Hz:
///
/// | PWM (Hz)     | PPWM | IPWM |
/// |--------------|------|------|
/// | ≥ 2000       | 7    | 40   |
/// | 1000 … 1999  | 6    | 35   |
/// | 400 … 999    | 5    | 25   |
/// | 150 … 399    | 3    | 15   |
/// | < 150        | 2    | 10   |
pub fn acc_gains(pwm_hz: u16) -> PiGains {
    let (ppwm, ipwm) = match pwm_hz {
        2000.. => (7, 40),
        1000..=1999 => (6, 35),
        400..=999 => (5, 25),
        150..=399 => (3, 15),
        _ => (2, 10),
    };
    PiGains { ppwm, ipwm }
}

/// The power-stage parameters of one channel (OD 0x800D / 0x801D / 0x802D),
/// resolved into what [`PowerStage::set_current`] takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StageParams {
    /// CURRENT: nominal current in mA (500..3000).
    pub current_ma: u16,
    /// DAMPL: dither amplitude in 0.01 % of CURRENT (0..3000).
    pub dampl: u16,
    /// DFREQ: dither frequency in Hz (50..400).
    pub dfreq: u16,
    /// PWM frequency in Hz (one of [`pwm_table`]).
    pub pwm_hz: u16,
    /// ACC: gains from the PWM frequency ([`acc_gains`]) instead of
    /// PPWM/IPWM.
    pub acc: bool,
    /// PPWM (used with ACC off).
    pub ppwm: u16,
    /// IPWM (used with ACC off).
    pub ipwm: u16,
}

impl Default for StageParams {
    /// OD defaults: 1000 mA, DAMPL 500, DFREQ 120 Hz, ACC on, PPWM 7,
    /// IPWM 40. The OD lists the PWM default as "2604", which is not a
    /// selectable frequency; we use 2500 Hz (code 0x09).
    fn default() -> Self {
        Self {
            current_ma: 1_000,
            dampl: 500,
            dfreq: 120,
            pwm_hz: 2_500,
            acc: true,
            ppwm: 7,
            ipwm: 40,
        }
    }
}

impl StageParams {
    /// The effective controller gains (ACC resolved).
    pub fn gains(&self) -> PiGains {
        if self.acc {
            acc_gains(self.pwm_hz)
        } else {
            PiGains {
                ppwm: self.ppwm.min(300),
                ipwm: self.ipwm.min(100),
            }
        }
    }

    /// The dither for these parameters.
    pub fn dither(&self) -> Dither {
        Dither::from_params(self.dampl, self.dfreq, self.current_ma)
    }
}

/// Fault flags of the power stage (live state, see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Faults {
    /// Open wire at solenoid A.
    pub open_a: bool,
    /// Short circuit at solenoid A.
    pub short_a: bool,
    /// Open wire at solenoid B.
    pub open_b: bool,
    /// Short circuit at solenoid B.
    pub short_b: bool,
    /// Supply voltage below 12 V.
    pub undervoltage: bool,
    /// Supply voltage above 30 V.
    pub overvoltage: bool,
    /// Stage temperature above 85 °C.
    pub overtemperature: bool,
}

impl Faults {
    /// Whether any flag is set.
    pub fn any(&self) -> bool {
        self.open_a
            || self.short_a
            || self.open_b
            || self.short_b
            || self.undervoltage
            || self.overvoltage
            || self.overtemperature
    }
}

/// What a device drives: the real board or [`SimPowerStage`].
pub trait PowerStage {
    /// Demands `setpoint_ma` on one solenoid with the given dither, PWM
    /// frequency (Hz) and controller gains. A setpoint of 0 switches the
    /// output off.
    fn set_current(
        &mut self,
        solenoid: Solenoid,
        setpoint_ma: u16,
        dither: Dither,
        pwm_hz: u16,
        gains: PiGains,
    );
    /// Switches both outputs off (setpoints 0).
    fn disable(&mut self);
    /// The measured current of one solenoid in mA.
    fn measured_ma(&self, solenoid: Solenoid) -> u16;
    /// The present fault flags.
    fn faults(&self) -> Faults;
    /// Advances the stage by `dt_us` (the real board may do nothing here).
    fn step(&mut self, dt_us: u32);
    /// The board loses power and restarts: outputs off and, for a
    /// simulation, every state (and injected fault) gone.
    fn power_cycle(&mut self) {
        self.disable();
    }
}

/// A fault (or operating condition) to inject into [`SimPowerStage`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fault {
    /// Broken wire at a solenoid.
    OpenWire(Solenoid),
    /// Short circuit at a solenoid.
    ShortCircuit(Solenoid),
    /// Supply voltage in V.
    SupplyVoltage(f32),
    /// Stage temperature in °C.
    Temperature(f32),
}

/// State of one simulated output.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Coil {
    /// Coil current in A.
    i: f32,
    /// PI integrator in V.
    integ: f32,
    /// Last duty cycle 0..1.
    duty: f32,
    setpoint_ma: u16,
    dither: Dither,
    pwm_hz: u16,
    gains: PiGains,
    open: bool,
    short: bool,
}

impl Default for Coil {
    fn default() -> Self {
        Self {
            i: 0.0,
            integ: 0.0,
            duty: 0.0,
            setpoint_ma: 0,
            dither: Dither::OFF,
            pwm_hz: 2_500,
            gains: PiGains::default(),
            open: false,
            short: false,
        }
    }
}

/// Triangle wave in −1..1 at time `t_us` for frequency `hz` (> 0).
fn triangle(t_us: u64, hz: u16) -> f32 {
    let period = 1_000_000 / u64::from(hz.max(1));
    let period = period.max(1);
    let x = (t_us % period) as f32 / period as f32;
    if x < 0.5 {
        4.0 * x - 1.0
    } else {
        3.0 - 4.0 * x
    }
}

impl Coil {
    /// One sub-step of `dt` seconds.
    fn sub_step(&mut self, t_us: u64, supply: f32, r: f32, l: f32, dt: f32) {
        let demanded = self.setpoint_ma > 0;
        if self.open || self.short || !demanded {
            self.integ = 0.0;
            self.duty = 0.0;
        }
        if self.open || self.short {
            // No current path (open) / protection switched off (short).
            self.i = 0.0;
            return;
        }
        let vs = supply.max(0.0);
        let v = if demanded {
            let mut target = f32::from(self.setpoint_ma) / 1000.0;
            if self.dither.amplitude_ma > 0 && self.dither.freq_hz > 0 {
                let a = f32::from(self.dither.amplitude_ma) / 1000.0;
                target = (target + a * triangle(t_us, self.dither.freq_hz)).max(0.0);
            }
            let kp = f32::from(self.gains.ppwm) * 10.0;
            let ki = f32::from(self.gains.ipwm) * 500.0;
            let e = target - self.i;
            let unsat = kp * e + self.integ;
            // Anti-windup: integrate only if not pushing further into a limit.
            let pushing_high = unsat >= vs && e > 0.0;
            let pushing_low = unsat <= 0.0 && e < 0.0;
            if !(pushing_high || pushing_low) {
                self.integ = (self.integ + ki * e * dt).clamp(0.0, vs);
            }
            let v = (kp * e + self.integ).clamp(0.0, vs);
            self.duty = if vs > 0.0 { v / vs } else { 0.0 };
            v
        } else if self.i > 0.0 {
            // Quick discharge.
            -vs
        } else {
            0.0
        };
        // Backward Euler: L (i' - i) / dt = v - R i'.
        let k = dt / l;
        let next = (self.i + k * v) / (1.0 + k * r);
        self.i = if next.is_finite() {
            next.clamp(0.0, 100.0)
        } else {
            0.0
        };
    }

    /// No setpoint, no current, controller reset: a sub-step changes
    /// nothing.
    fn at_rest(&self) -> bool {
        self.setpoint_ma == 0 && self.i == 0.0 && self.integ == 0.0 && self.duty == 0.0
    }

    fn measured_ma(&self) -> u16 {
        // `as` saturates (and maps NaN to 0).
        (self.i * 1000.0 + 0.5) as u16
    }
}

/// A simulated two-output power stage (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SimPowerStage {
    a: Coil,
    b: Coil,
    r_ohm: f32,
    l_h: f32,
    supply_v: f32,
    temperature_c: f32,
    t_us: u64,
    pending_us: u32,
}

impl Default for SimPowerStage {
    fn default() -> Self {
        Self::new()
    }
}

impl SimPowerStage {
    /// A stage with the default coil (6 Ω, 30 mH), 24 V, 25 °C, outputs off.
    pub fn new() -> Self {
        Self::with_coil(DEFAULT_R_OHM, DEFAULT_L_H)
    }

    /// A stage with both coils of `r_ohm` (clamped 0.1..1000 Ω) and `l_h`
    /// (clamped 0.0001..10 H).
    pub fn with_coil(r_ohm: f32, l_h: f32) -> Self {
        let r = if r_ohm.is_finite() {
            r_ohm
        } else {
            DEFAULT_R_OHM
        };
        let l = if l_h.is_finite() { l_h } else { DEFAULT_L_H };
        Self {
            a: Coil::default(),
            b: Coil::default(),
            r_ohm: r.clamp(0.1, 1000.0),
            l_h: l.clamp(0.0001, 10.0),
            supply_v: DEFAULT_SUPPLY_V,
            temperature_c: DEFAULT_TEMPERATURE_C,
            t_us: 0,
            pending_us: 0,
        }
    }

    fn coil(&self, s: Solenoid) -> &Coil {
        match s {
            Solenoid::A => &self.a,
            Solenoid::B => &self.b,
        }
    }

    fn coil_mut(&mut self, s: Solenoid) -> &mut Coil {
        match s {
            Solenoid::A => &mut self.a,
            Solenoid::B => &mut self.b,
        }
    }

    /// Injects a fault or sets an operating condition (non-finite values
    /// are ignored).
    pub fn inject(&mut self, fault: Fault) {
        match fault {
            Fault::OpenWire(s) => self.coil_mut(s).open = true,
            Fault::ShortCircuit(s) => self.coil_mut(s).short = true,
            Fault::SupplyVoltage(v) if v.is_finite() => self.supply_v = v,
            Fault::Temperature(c) if c.is_finite() => self.temperature_c = c,
            Fault::SupplyVoltage(_) | Fault::Temperature(_) => {}
        }
    }

    /// Removes all injected faults: wires intact, 24 V, 25 °C.
    pub fn clear_faults(&mut self) {
        self.a.open = false;
        self.a.short = false;
        self.b.open = false;
        self.b.short = false;
        self.supply_v = DEFAULT_SUPPLY_V;
        self.temperature_c = DEFAULT_TEMPERATURE_C;
    }

    /// The simulated supply voltage in V.
    pub fn supply_voltage(&self) -> f32 {
        self.supply_v
    }

    /// The simulated stage temperature in °C.
    pub fn temperature(&self) -> f32 {
        self.temperature_c
    }

    /// The last PWM duty cycle (0..1) of one output.
    pub fn duty(&self, s: Solenoid) -> f32 {
        self.coil(s).duty
    }

    /// The PWM frequency last set for one output, in Hz.
    pub fn pwm_hz(&self, s: Solenoid) -> u16 {
        self.coil(s).pwm_hz
    }

    /// The setpoint last demanded for one output, in mA.
    pub fn setpoint_ma(&self, s: Solenoid) -> u16 {
        self.coil(s).setpoint_ma
    }
}

impl PowerStage for SimPowerStage {
    fn power_cycle(&mut self) {
        *self = SimPowerStage::new();
    }

    fn set_current(
        &mut self,
        solenoid: Solenoid,
        setpoint_ma: u16,
        dither: Dither,
        pwm_hz: u16,
        gains: PiGains,
    ) {
        let c = self.coil_mut(solenoid);
        c.setpoint_ma = setpoint_ma;
        c.dither = dither;
        c.pwm_hz = pwm_hz;
        c.gains = gains;
    }

    fn disable(&mut self) {
        for c in [&mut self.a, &mut self.b] {
            c.setpoint_ma = 0;
            c.integ = 0.0;
            c.duty = 0.0;
        }
    }

    fn measured_ma(&self, solenoid: Solenoid) -> u16 {
        self.coil(solenoid).measured_ma()
    }

    fn faults(&self) -> Faults {
        let demanded = |c: &Coil| c.setpoint_ma > 0;
        Faults {
            open_a: self.a.open && demanded(&self.a),
            short_a: self.a.short && demanded(&self.a),
            open_b: self.b.open && demanded(&self.b),
            short_b: self.b.short && demanded(&self.b),
            undervoltage: self.supply_v < UNDERVOLTAGE_V,
            overvoltage: self.supply_v > OVERVOLTAGE_V,
            overtemperature: self.temperature_c > OVERTEMPERATURE_C,
        }
    }

    fn step(&mut self, dt_us: u32) {
        let total = u64::from(self.pending_us) + u64::from(dt_us);
        let n = total / u64::from(SUB_STEP_US);
        self.pending_us = u32::try_from(total % u64::from(SUB_STEP_US)).unwrap_or(0);
        let n = n.min(u64::from(MAX_SUB_STEPS));
        if self.a.at_rest() && self.b.at_rest() {
            // Nothing demanded, no current: every sub-step would leave
            // both coils as they are (only the dither phase advances).
            self.t_us = self.t_us.wrapping_add(n * u64::from(SUB_STEP_US));
            return;
        }
        let dt = SUB_STEP_US as f32 * 1e-6;
        let (supply, r, l) = (self.supply_v, self.r_ohm, self.l_h);
        for _ in 0..n {
            self.t_us = self.t_us.wrapping_add(u64::from(SUB_STEP_US));
            self.a.sub_step(self.t_us, supply, r, l, dt);
            self.b.sub_step(self.t_us, supply, r, l, dt);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(ps: &mut SimPowerStage, ms: u32) {
        for _ in 0..ms {
            ps.step(1000);
        }
    }

    #[test]
    fn pwm_table_round_trips_all_twenty_codes() {
        assert_eq!(pwm_table().count(), 20, "all 20 frequencies of the manual");
        for (hz, code) in pwm_table() {
            assert_eq!(pwm_code(hz), Some(code));
            assert_eq!(pwm_from_code(code), Some(hz));
        }
        assert_eq!(pwm_code(60), Some(0x11));
        assert_eq!(pwm_code(2_500), Some(0x09));
        assert_eq!(pwm_from_code(0x14), Some(10_000));
        assert_eq!(pwm_code(2_604), None);
        assert_eq!(pwm_from_code(0x00), None);
        assert_eq!(pwm_from_code(0x15), None);
    }

    #[test]
    fn current_settles_to_750_ma_within_2_percent_after_100_ms_with_default_gains() {
        let mut ps = SimPowerStage::new();
        ps.set_current(Solenoid::A, 750, Dither::OFF, 2_500, PiGains::default());
        run(&mut ps, 100);
        let m = ps.measured_ma(Solenoid::A);
        assert!((735..=765).contains(&m), "measured {m} mA");
        // And it stays there.
        for _ in 0..50 {
            ps.step(1000);
            let m = ps.measured_ma(Solenoid::A);
            assert!((735..=765).contains(&m), "measured {m} mA");
        }
        // Duty = R * I / U = 6 * 0.75 / 24 = 0.1875.
        assert!((ps.duty(Solenoid::A) - 0.1875).abs() < 0.01);
        assert_eq!(ps.measured_ma(Solenoid::B), 0);
        assert!(!ps.faults().any());
    }

    #[test]
    fn acc_gains_settle_too_and_fall_with_the_pwm_frequency() {
        assert_eq!(acc_gains(2_500), PiGains::default());
        let mut last = acc_gains(10_000);
        for (hz, _) in pwm_table().collect::<Vec<_>>().iter().rev() {
            let g = acc_gains(*hz);
            assert!(g.ppwm <= last.ppwm && g.ipwm <= last.ipwm);
            last = g;
            let mut ps = SimPowerStage::new();
            ps.set_current(Solenoid::B, 1_000, Dither::OFF, *hz, g);
            run(&mut ps, 100);
            let m = ps.measured_ma(Solenoid::B);
            assert!((980..=1_020).contains(&m), "{hz} Hz: {m} mA");
        }
        let p = StageParams {
            acc: false,
            ppwm: 999,
            ..StageParams::default()
        };
        assert_eq!(
            p.gains(),
            PiGains {
                ppwm: 300,
                ipwm: 40
            }
        );
        assert_eq!(StageParams::default().gains(), acc_gains(2_500));
    }

    #[test]
    fn disable_drives_the_current_to_zero() {
        let mut ps = SimPowerStage::new();
        ps.set_current(Solenoid::A, 1_000, Dither::OFF, 2_500, PiGains::default());
        ps.set_current(Solenoid::B, 500, Dither::OFF, 2_500, PiGains::default());
        run(&mut ps, 100);
        assert!(ps.measured_ma(Solenoid::A) > 950);
        ps.disable();
        run(&mut ps, 10);
        assert_eq!(ps.measured_ma(Solenoid::A), 0);
        assert_eq!(ps.measured_ma(Solenoid::B), 0);
        assert_eq!(ps.setpoint_ma(Solenoid::A), 0);
    }

    #[test]
    fn open_wire_gives_zero_current_and_the_open_flag_when_current_is_demanded() {
        let mut ps = SimPowerStage::new();
        ps.inject(Fault::OpenWire(Solenoid::A));
        run(&mut ps, 10);
        assert!(!ps.faults().open_a); // nothing demanded yet
        ps.set_current(Solenoid::A, 800, Dither::OFF, 2_500, PiGains::default());
        ps.set_current(Solenoid::B, 800, Dither::OFF, 2_500, PiGains::default());
        run(&mut ps, 100);
        assert_eq!(ps.measured_ma(Solenoid::A), 0);
        assert!(ps.measured_ma(Solenoid::B) > 780);
        let f = ps.faults();
        assert!(f.open_a && !f.open_b && !f.short_a && !f.short_b);
        ps.clear_faults();
        run(&mut ps, 100);
        assert!(!ps.faults().any());
        assert!(ps.measured_ma(Solenoid::A) > 780);
    }

    #[test]
    fn short_circuit_is_reported_and_the_current_limited() {
        let mut ps = SimPowerStage::new();
        ps.set_current(Solenoid::B, 2_000, Dither::OFF, 2_500, PiGains::default());
        run(&mut ps, 50);
        ps.inject(Fault::ShortCircuit(Solenoid::B));
        run(&mut ps, 1);
        let f = ps.faults();
        assert!(f.short_b && !f.short_a && !f.open_b);
        assert_eq!(ps.measured_ma(Solenoid::B), 0);
    }

    #[test]
    fn supply_and_temperature_limits_raise_their_flags() {
        let mut ps = SimPowerStage::new();
        ps.inject(Fault::SupplyVoltage(11.9));
        assert!(ps.faults().undervoltage && !ps.faults().overvoltage);
        ps.inject(Fault::SupplyVoltage(12.0));
        assert!(!ps.faults().any());
        ps.inject(Fault::SupplyVoltage(30.0));
        assert!(!ps.faults().any());
        ps.inject(Fault::SupplyVoltage(30.5));
        assert!(ps.faults().overvoltage);
        ps.inject(Fault::SupplyVoltage(f32::NAN)); // ignored
        assert_eq!(ps.supply_voltage(), 30.5);
        ps.inject(Fault::Temperature(85.0));
        assert!(!ps.faults().overtemperature);
        ps.inject(Fault::Temperature(90.0));
        assert!(ps.faults().overtemperature);
        ps.clear_faults();
        assert!(!ps.faults().any());
        // At 10 V the 6 Ω coil cannot carry more than 1667 mA.
        ps.inject(Fault::SupplyVoltage(10.0));
        ps.set_current(Solenoid::A, 2000, Dither::OFF, 2_500, PiGains::default());
        run(&mut ps, 200);
        let m = ps.measured_ma(Solenoid::A);
        assert!((1650..=1667).contains(&m), "{m} mA");
    }

    #[test]
    fn dither_shows_up_as_peak_to_peak_in_the_measured_current() {
        let mut ps = SimPowerStage::new();
        // DAMPL 500 (5 %) of 1500 mA = 75 mA peak, 150 mA peak-to-peak.
        let d = Dither::from_params(500, 120, 1_500);
        assert_eq!(
            d,
            Dither {
                amplitude_ma: 75,
                freq_hz: 120
            }
        );
        ps.set_current(Solenoid::A, 750, d, 2_500, PiGains::default());
        run(&mut ps, 100);
        let (mut lo, mut hi) = (u16::MAX, 0);
        for _ in 0..2_000 {
            ps.step(50);
            let m = ps.measured_ma(Solenoid::A);
            lo = lo.min(m);
            hi = hi.max(m);
        }
        let pp = hi - lo;
        assert!((75..=180).contains(&pp), "peak-to-peak {pp} mA");
        let mid = (u32::from(hi) + u32::from(lo)) / 2;
        assert!((720..=780).contains(&mid), "mid {mid} mA");
    }

    #[test]
    fn odd_step_sizes_carry_the_remainder() {
        let mut a = SimPowerStage::new();
        let mut b = SimPowerStage::new();
        for ps in [&mut a, &mut b] {
            ps.set_current(Solenoid::A, 600, Dither::OFF, 2_500, PiGains::default());
        }
        for _ in 0..1000 {
            a.step(30);
        }
        b.step(30_000);
        assert_eq!(a.measured_ma(Solenoid::A), b.measured_ma(Solenoid::A));
        a.step(u32::MAX); // capped, no hang, no panic
    }

    #[test]
    fn a_stage_at_rest_skips_its_sub_steps_with_the_same_result() {
        let mut fast = SimPowerStage::new();
        fast.step(12_345);
        // The slow path, forced by a setpoint that is taken back at once.
        let mut slow = SimPowerStage::new();
        slow.set_current(Solenoid::A, 1, Dither::OFF, 2_500, PiGains::default());
        slow.set_current(Solenoid::A, 0, Dither::OFF, 2_500, PiGains::default());
        slow.a.duty = 0.0;
        for _ in 0..12_345 / 50 {
            slow.a.sub_step(0, 24.0, 6.0, 0.03, 50e-6);
            slow.b.sub_step(0, 24.0, 6.0, 0.03, 50e-6);
        }
        assert_eq!(fast.a, slow.a);
        assert_eq!(fast.b, slow.b);
        assert_eq!(fast.t_us, 12_300);
        // From rest a setpoint still drives the coil.
        fast.set_current(Solenoid::B, 800, Dither::OFF, 2_500, PiGains::default());
        run(&mut fast, 100);
        assert!(fast.measured_ma(Solenoid::B) > 780);
    }
}
