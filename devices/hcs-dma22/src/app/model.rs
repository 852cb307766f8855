//! A simple, deterministic model of one DMA-22(A) module: what the cyclic
//! data of 000 5.5.2-5.5.6 mean in each operation mode, the enable logic
//! of 5.5.1.2, the errors of 5.5.1.1 and the E23/E26 timeout, and a signal
//! path (set value → ramps → gain/offset → controller → solenoid currents)
//! that moves the `d` values within the ranges of chapter 7.
//!
//! Everything is integer arithmetic in the manual's units (mV for "V"
//! values, 1000 == 1.000 V; mA for currents) and depends only on the
//! parameters, the cyclic data and the injected time. What is not modelled
//! (analogue inputs, linearisation curves, dither, the D part, comparator
//! delays) is listed in `NOTES.md` ("Behaviour model").

use ecat_slave::od::Od;

use crate::description::map::{INPUTS, OUTPUTS, parameter, slot_index};

/// Parameter IDs the model reads or writes (chapter 7).
pub mod id {
    #![allow(missing_docs)]
    pub const D1_01: u16 = 0x01;
    pub const D1_02: u16 = 0x02;
    pub const D1_03: u16 = 0x03;
    pub const D1_04: u16 = 0x04;
    pub const D1_05: u16 = 0x05;
    pub const D1_06: u16 = 0x06;
    pub const D1_07: u16 = 0x07;
    pub const D1_08: u16 = 0x08;
    pub const D1_09: u16 = 0x09;
    pub const D1_10: u16 = 0x0A;
    pub const D1_11: u16 = 0x0B;
    pub const D1_12: u16 = 0x0C;
    pub const D1_13: u16 = 0x0D;
    pub const D2_01: u16 = 0x0E;
    pub const D2_02: u16 = 0x0F;
    pub const D2_03: u16 = 0x10;
    pub const D2_04: u16 = 0x11;
    pub const D2_10: u16 = 0x12;
    pub const D2_11: u16 = 0x13;
    pub const D2_12: u16 = 0x14;
    pub const D2_13: u16 = 0x15;
    pub const R1_01: u16 = 0x1B;
    pub const A1_01: u16 = 0x1F;
    pub const A1_02: u16 = 0x20;
    pub const R2_01: u16 = 0x23;
    pub const A2_01: u16 = 0x27;
    pub const A2_02: u16 = 0x28;
    pub const C1_00: u16 = 0x29;
    pub const C2_00: u16 = 0x44;
    pub const E00: u16 = 0x5F;
    pub const E03: u16 = 0x62;
    pub const E10: u16 = 0x69;
    pub const E22: u16 = 0xA3;
    pub const C1_28: u16 = 0xA6;
    pub const C2_28: u16 = 0xAB;
    pub const E_INT: u16 = 0xB0;
    pub const E23: u16 = 0xB1;
    pub const C1_33: u16 = 0xB3;
    pub const C2_33: u16 = 0xB4;
    pub const E26: u16 = 0xCD;
}

/// Control byte bits (000 5.5.2-5.5.6).
pub mod control {
    /// Din_1 (closed-loop modes).
    pub const DIN_1: u8 = 0x01;
    /// TST_CMP.
    pub const TST_CMP: u8 = 0x04;
    /// Din_2 (closed-loop modes).
    pub const DIN_2: u8 = 0x10;
    /// BUS_DISABLE.
    pub const BUS_DISABLE: u8 = 0x80;
}

/// Status word bits (high byte as the mode tables give them, 000 5.5.2;
/// the low byte's bits in closed-loop modes).
pub mod status {
    /// Digital input SP1.
    pub const SP1: u16 = 0x0100;
    /// Digital input SP2.
    pub const SP2: u16 = 0x0200;
    /// Hardware enable.
    pub const HW_ENABLE: u16 = 0x0400;
    /// Error pending (low byte = error number).
    pub const ERROR: u16 = 0x0800;
    /// Digital input SP3.
    pub const SP3: u16 = 0x1000;
    /// Digital input SP4.
    pub const SP4: u16 = 0x2000;
    /// BUS_DISABLE is set.
    pub const BUS_DISABLE: u16 = 0x8000;
    /// Din_1 active.
    pub const DIN_1: u16 = 0x01;
    /// Dout_1 active (branch 1 closed loop).
    pub const DOUT_1: u16 = 0x02;
    /// Comp_1 active.
    pub const COMP_1: u16 = 0x04;
    /// Comp_11 active.
    pub const COMP_11: u16 = 0x08;
    /// Din_2 active.
    pub const DIN_2: u16 = 0x10;
    /// Dout_2 active.
    pub const DOUT_2: u16 = 0x20;
    /// Comp_2 active.
    pub const COMP_2: u16 = 0x40;
    /// Comp_22 active.
    pub const COMP_22: u16 = 0x80;
}

/// Error numbers of 000 5.5.1.1, table 3 (the low byte of the status
/// word with ERROR set).
pub mod error {
    /// Timeout: no cyclic data within E23 × 10 ms.
    pub const TIMEOUT: u8 = 0x0A;
}

/// Operation modes (E00) the manual documents.
pub const MODES: [u8; 8] = [1, 2, 3, 4, 6, 8, 10, 11];

/// Maximum solenoid current per E03 selection 1..=7, mA (chapter 7).
const SOLENOID_MA: [i64; 7] = [800, 1100, 1300, 1600, 2400, 2700, 3500];

/// The parameters `process value 1` and `process value 2` of the cyclic
/// outputs write in operation mode `mode` (000 5.5.2-5.5.6).
pub const fn process_value_targets(mode: u8) -> (u16, u16) {
    match mode {
        1 => (id::A1_01, id::A1_02),
        2 | 8 => (id::A1_01, id::A2_01),
        6 | 11 => (id::A1_01, id::A2_02),
        _ => (id::A1_01, id::A1_02),
    }
}

/// The parameters `value 1` and `value 2` of the cyclic inputs carry in
/// operation mode `mode`.
pub const fn value_sources(mode: u8) -> (u16, u16) {
    match mode {
        1 | 2 => (id::D1_07, id::D1_08),
        6 | 8 | 11 => (id::D1_11, id::D2_11),
        _ => (id::D1_11, id::D1_10),
    }
}

/// Whether `mode` is a closed-loop mode (status low byte carries the
/// Din/Dout/Comp bits, the control byte Din_1/Din_2).
pub const fn closed_loop(mode: u8) -> bool {
    !matches!(mode, 1 | 2)
}

/// Whether branch 2 runs in `mode`.
const fn two_branches(mode: u8) -> bool {
    matches!(mode, 2 | 6 | 8 | 11)
}

/// Reads parameter `id` of slot `n`.
pub fn get(od: &Od, n: u8, id: u16) -> i64 {
    parameter(n, id)
        .and_then(|(i, s)| od.get(i, s))
        .unwrap_or(0)
}

/// Writes parameter `id` of slot `n` (clamped to ±9999 like every `d`
/// value of chapter 7 where it is a voltage).
pub fn set(od: &mut Od, n: u8, id: u16, v: i64) {
    if let Some((i, s)) = parameter(n, id) {
        od.set(i, s, v);
    }
}

fn clamp_mv(v: i64) -> i64 {
    v.clamp(-9999, 9999)
}

/// One branch's state between ticks.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Branch {
    /// Post-ramp set value, µV (so slow ramps still move every tick).
    ramped_uv: i64,
    /// Integral part, µV.
    integral_uv: i64,
    /// Dout (closed loop reached through Din and the comparator), latched
    /// while Din stays on.
    dout: bool,
}

/// The per-branch parameter IDs.
struct BranchIds {
    set_value: u16,
    feedback: u16,
    ramps: u16,
    controller: u16,
    comparator2: u16,
    i_limit: u16,
    d01: u16,
    d02: u16,
    d03: u16,
    d04: u16,
    d10: u16,
    d11: u16,
    d12: u16,
    d13: u16,
}

const BRANCH1: BranchIds = BranchIds {
    set_value: id::A1_01,
    feedback: id::A1_02,
    ramps: id::R1_01,
    controller: id::C1_00,
    comparator2: id::C1_28,
    i_limit: id::C1_33,
    d01: id::D1_01,
    d02: id::D1_02,
    d03: id::D1_03,
    d04: id::D1_04,
    d10: id::D1_10,
    d11: id::D1_11,
    d12: id::D1_12,
    d13: id::D1_13,
};

const BRANCH2: BranchIds = BranchIds {
    set_value: id::A2_01,
    feedback: id::A2_02,
    ramps: id::R2_01,
    controller: id::C2_00,
    comparator2: id::C2_28,
    i_limit: id::C2_33,
    d01: id::D2_01,
    d02: id::D2_02,
    d03: id::D2_03,
    d04: id::D2_04,
    d10: id::D2_10,
    d11: id::D2_11,
    d12: id::D2_12,
    d13: id::D2_13,
};

/// What one branch computed in a tick.
#[derive(Debug, Clone, Copy, Default)]
struct BranchOut {
    /// Signal driving the solenoids, mV (positive: A, negative: B).
    drive: i64,
    comp: bool,
    comp2: bool,
    dout: bool,
}

/// One module's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Module {
    /// Hardware enable input (X3/1); on by default, as in every example.
    pub hw_enable: bool,
    /// Digital inputs SP1..SP4 (bits 0..3).
    pub inputs: u8,
    /// The pending error number (0: none).
    pub error: u8,
    /// Errors since power-on.
    pub errors: u16,
    /// Control byte in effect.
    control: u8,
    /// Din_1 / Din_2 / BUS_DISABLE as the master last wrote them into
    /// E Int (0xB0) over SDO.
    sdo_control: u8,
    /// BUS_DISABLE was set since the error: resetting it acknowledges.
    ack_armed: bool,
    branches: [Branch; 2],
    last_ns: Option<u64>,
    /// Last time cyclic outputs were valid.
    last_valid_ns: Option<u64>,
    /// The previous tick had valid cyclic outputs.
    was_valid: bool,
}

impl Default for Module {
    fn default() -> Self {
        Self::new()
    }
}

impl Module {
    /// A module at power-on.
    pub const fn new() -> Self {
        Module {
            hw_enable: true,
            inputs: 0,
            error: 0,
            errors: 0,
            control: 0,
            sdo_control: 0,
            ack_armed: false,
            branches: [Branch {
                ramped_uv: 0,
                integral_uv: 0,
                dout: false,
            }; 2],
            last_ns: None,
            last_valid_ns: None,
            was_valid: false,
        }
    }

    /// A write of E Int (0xB0): takes its writable bits (Din_1 0x0001,
    /// Din_2 0x0010, Bus disable 0x8000) as control bits; the others are
    /// read-only and ignored.
    pub fn write_e_int(&mut self, v: u16) {
        self.sdo_control = (if v & 0x0001 != 0 { control::DIN_1 } else { 0 })
            | (if v & 0x0010 != 0 { control::DIN_2 } else { 0 })
            | (if v & 0x8000 != 0 {
                control::BUS_DISABLE
            } else {
                0
            });
    }

    /// A CMD 15 control byte that came through the telegram channel: its
    /// Din_1, TST_CMP, Din_2 and BUS_DISABLE bits act like the cyclic
    /// control byte's until the next one.
    pub fn write_control(&mut self, control: u8) {
        self.sdo_control =
            control & (control::DIN_1 | control::TST_CMP | control::DIN_2 | control::BUS_DISABLE);
    }

    /// The control byte in effect (0 while the hardware enable is off).
    pub fn control(&self) -> u8 {
        self.control
    }

    /// Whether the output stage is enabled: hardware enable, no BUS_DISABLE,
    /// no error.
    pub fn enabled(&self) -> bool {
        self.hw_enable && self.control & control::BUS_DISABLE == 0 && self.error == 0
    }

    /// Raises error `n` (returns whether it is new).
    fn raise(&mut self, n: u8) -> bool {
        if self.error == n {
            return false;
        }
        self.error = n;
        self.errors = self.errors.saturating_add(1);
        self.ack_armed = false;
        true
    }

    /// One cycle of module `n` in operation mode `mode` at `now_ns`:
    /// takes the cyclic outputs (when `outputs_valid`), runs the signal
    /// path and writes the cyclic inputs and `d` values. Returns the error
    /// number when a new error was raised.
    ///
    /// `outputs_valid` means OP with valid cyclic outputs (the node passes
    /// the AL state in): only then does the power stage drive the
    /// solenoids (ETG.1000.6: outside OP the outputs stay in their safe
    /// state). Otherwise the set values, also those written acyclically,
    /// stay and run through the set-value path (`d` values), but the
    /// controller output and the solenoid currents are 0 (`NOTES.md` 31).
    pub fn tick(
        &mut self,
        od: &mut Od,
        n: u8,
        mode: u8,
        now_ns: u64,
        outputs_valid: bool,
    ) -> Option<u8> {
        let dt = self.last_ns.map_or(0, |t| now_ns.saturating_sub(t));
        self.last_ns = Some(now_ns);
        let mut raised = None;
        let out = slot_index(OUTPUTS, n);
        let sdo_control = self.sdo_control;
        if outputs_valid {
            self.last_valid_ns = Some(now_ns);
            let (t1, t2) = process_value_targets(mode);
            let pv1 = od.get(out, 2).unwrap_or(0);
            let pv2 = od.get(out, 3).unwrap_or(0);
            set(od, n, t1, pv1.clamp(-9999, 9999));
            set(od, n, t2, pv2.clamp(-9999, 9999));
        }
        let wire = if outputs_valid {
            od.get(out, 1).unwrap_or(0) as u8
        } else {
            0
        };
        let requested = if self.hw_enable {
            wire | sdo_control
        } else {
            0
        };
        // 5.5.1.1: an error is reset by setting and resetting BUS_DISABLE
        // (or by switching the hardware enable off and on).
        if !self.hw_enable && self.error != 0 {
            self.ack_armed = true;
        }
        if self.error != 0 && requested & control::BUS_DISABLE != 0 {
            self.ack_armed = true;
        }
        self.control = requested;
        let timeout_ms = get(od, n, id::E23).saturating_mul(10);
        let stale = match self.last_valid_ns {
            Some(t) => !outputs_valid && now_ns.saturating_sub(t) > timeout_ms as u64 * 1_000_000,
            None => false,
        };
        if self.error != 0
            && self.ack_armed
            && self.hw_enable
            && requested & control::BUS_DISABLE == 0
        {
            // Acknowledged: cleared if the cause is gone.
            if !(self.error == error::TIMEOUT && stale) {
                self.error = 0;
                self.ack_armed = false;
            }
        }
        let discard = if timeout_ms > 0 && stale {
            let new = self.raise(error::TIMEOUT);
            if new {
                raised = Some(error::TIMEOUT);
            }
            new
        } else {
            // E23 = 0: the cyclic set values go when the cyclic data stop;
            // set values written acyclically (SDO, CMD 6) outside OP stay
            // written, as A1.01 "when written, always active" (chapter 7),
            // but drive nothing before OP (`driving` below).
            self.was_valid && !outputs_valid && timeout_ms == 0
        };
        self.was_valid = outputs_valid;
        if self.error == error::TIMEOUT && outputs_valid && get(od, n, id::E26) == 0 {
            // E26 = 0: work continues with the next valid telegram.
            self.error = 0;
        }
        // 5.5.1.1: "the electronic discards every set point in error case".
        if discard {
            set(od, n, id::A1_01, 0);
            set(od, n, id::A1_02, 0);
            set(od, n, id::A2_01, 0);
            set(od, n, id::A2_02, 0);
        }
        let enabled = self.enabled();
        // The power stage drives only in OP with valid cyclic outputs.
        let driving = enabled && outputs_valid;
        let b1 = self.branch(od, n, 0, &BRANCH1, dt, (enabled, driving), mode);
        let b2 = if two_branches(mode) {
            self.branch(od, n, 1, &BRANCH2, dt, (enabled, driving), mode)
        } else {
            self.branches[1] = Branch::default();
            BranchOut::default()
        };
        self.solenoids(od, n, mode, b1, b2, driving);
        // E Int (read part) and the status word.
        let mut low = 0u16;
        if closed_loop(mode) {
            let c = self.control;
            low |= if c & control::DIN_1 != 0 {
                status::DIN_1
            } else {
                0
            };
            low |= if b1.dout { status::DOUT_1 } else { 0 };
            low |= if b1.comp { status::COMP_1 } else { 0 };
            low |= if b1.comp2 { status::COMP_11 } else { 0 };
            low |= if c & control::DIN_2 != 0 {
                status::DIN_2
            } else {
                0
            };
            low |= if b2.dout { status::DOUT_2 } else { 0 };
            low |= if b2.comp { status::COMP_2 } else { 0 };
            low |= if b2.comp2 { status::COMP_22 } else { 0 };
        }
        let mut high = 0u16;
        let sp = u16::from(self.inputs);
        high |= if sp & 1 != 0 { status::SP1 } else { 0 };
        high |= if sp & 2 != 0 { status::SP2 } else { 0 };
        high |= if sp & 4 != 0 { status::SP3 } else { 0 };
        high |= if sp & 8 != 0 { status::SP4 } else { 0 };
        high |= if self.hw_enable { status::HW_ENABLE } else { 0 };
        high |= if self.control & control::BUS_DISABLE != 0 {
            status::BUS_DISABLE
        } else {
            0
        };
        let word = if self.error != 0 {
            high | status::ERROR | u16::from(self.error)
        } else {
            high | low
        };
        // E Int: the status word's bits without the error number
        // (chapter 7 gives them the same positions).
        let e_int = if self.error != 0 {
            high | status::ERROR
        } else {
            word
        };
        set(od, n, id::E_INT, i64::from(e_int));
        let inp = slot_index(INPUTS, n);
        let (v1, v2) = value_sources(mode);
        od.set(inp, 1, i64::from(word));
        od.set(inp, 2, get(od, n, v1));
        od.set(inp, 3, get(od, n, v2));
        raised
    }

    /// Runs branch `b` (0 or 1) of module `n`; `(enabled, driving)`: the
    /// output stage is enabled (the set-value path runs), the power stage
    /// drives (the controller and the drive signal run).
    #[allow(clippy::too_many_arguments)]
    fn branch(
        &mut self,
        od: &mut Od,
        n: u8,
        b: usize,
        ids: &BranchIds,
        dt: u64,
        (enabled, driving): (bool, bool),
        mode: u8,
    ) -> BranchOut {
        let din = self.control
            & if b == 0 {
                control::DIN_1
            } else {
                control::DIN_2
            }
            != 0;
        let Some(st) = self.branches.get_mut(b) else {
            return BranchOut::default();
        };
        // Every parameter first (the C parameters of branch 2 are those of
        // branch 1 + 0x1B: C1.00 0x29 .. C1.26 0x43, C2.00 0x44 .. 0x5E).
        let p = |k: u16| get(od, n, k);
        let c = |k: u16| get(od, n, ids.controller + k);
        let sum = if enabled { p(ids.set_value) } else { 0 };
        let ramps = [
            p(ids.ramps),
            p(ids.ramps + 1),
            p(ids.ramps + 2),
            p(ids.ramps + 3),
        ];
        let (gain_sv, offset_sv) = (c(5), c(6));
        let feedback = p(ids.feedback);
        let (gain_x, offset_x, sign_x) = (c(10), c(11), c(12).signum());
        let (kp1, threshold, kp2, ki, gain) = (c(13), c(15), c(16), c(17), c(20).max(1));
        let controller = c(0);
        let comp_sel = (c(25), c(21), c(22));
        let comp2_sel = (
            p(ids.comparator2 + 4),
            p(ids.comparator2),
            p(ids.comparator2 + 1),
        );
        let limit = p(ids.i_limit).saturating_abs().saturating_mul(1000);
        // Ramps r.01 0 -> -, r.02 - -> 0, r.03 0 -> +, r.04 + -> 0:
        // 1 == 10 ms for 10 V, i.e. (1 / r) µV per ns.
        let target = sum * 1000;
        let cur = st.ramped_uv;
        let ramp = if target == cur {
            0
        } else if cur >= 0 && target > cur {
            ramps[2]
        } else if cur > 0 && target < cur {
            ramps[3]
        } else if cur <= 0 && target < cur {
            ramps[0]
        } else {
            ramps[1]
        };
        // A gap of any length (u64 ns) moves at most to the target.
        let dt_ns = i64::try_from(dt).unwrap_or(i64::MAX);
        st.ramped_uv = if ramp <= 0 || !enabled {
            target
        } else {
            let step = (dt_ns / ramp).max(1);
            if target > cur {
                cur.saturating_add(step).min(target)
            } else {
                cur.saturating_sub(step).max(target)
            }
        };
        let d02 = clamp_mv(st.ramped_uv / 1000);
        let d03 = d02; // linearisation: only "linear" (C.02 = 0) is modelled
        let d04 = clamp_mv(d03 * gain_sv / 100 + offset_sv);
        set(od, n, ids.d01, clamp_mv(sum));
        set(od, n, ids.d02, d02);
        set(od, n, ids.d03, d03);
        set(od, n, ids.d04, d04);
        if !closed_loop(mode) {
            set(od, n, ids.d10, d04);
            return BranchOut {
                drive: if driving { d04 } else { 0 },
                ..BranchOut::default()
            };
        }
        // Closed loop: feedback from the Ethernet value (A.02) through
        // actual value gain C.10, offset C.11 and sign C.12.
        let w = d04;
        let x = if enabled {
            clamp_mv((feedback * gain_x / 100 + offset_x) * sign_x)
        } else {
            0
        };
        let e = clamp_mv(w - x);
        let kp = if e.abs() < threshold { kp1 } else { kp2 };
        if driving {
            // I part C.17: 1000 == 1.000 1/s, limited to C.33 (anti-windup).
            // In i128: e * ki * dt overflows i64 after minutes without a
            // tick; any gap saturates at the limit.
            let delta = i128::from(e) * i128::from(ki) * i128::from(dt) / 1_000_000_000;
            let sum =
                (i128::from(st.integral_uv) + delta).clamp(-i128::from(limit), i128::from(limit));
            st.integral_uv = i64::try_from(sum).unwrap_or(0);
        } else {
            st.integral_uv = 0;
        }
        let y = match controller {
            0 => w, // controller off: the set value drives the valve
            _ => clamp_mv(e * kp * gain / 100 + st.integral_uv / 1000),
        };
        set(od, n, ids.d10, w);
        set(od, n, ids.d11, x);
        set(od, n, ids.d12, e);
        set(od, n, ids.d13, if driving { y } else { 0 });
        // Comparators Comp_x (C.21..C.25) and Comp_xx (C.28..C.32).
        let pick = |sel: i64| match sel {
            1 => Some(w),
            2 => Some(x),
            3 => Some(e),
            _ => None,
        };
        let within = |(sel, hi, lo): (i64, i64, i64)| pick(sel).is_some_and(|v| v <= hi && v >= lo);
        let comp = within(comp_sel);
        let comp2 = within(comp2_sel);
        let remote = matches!(controller, 2 | 4);
        st.dout = remote && din && (st.dout || !comp);
        BranchOut {
            drive: if driving { y } else { 0 },
            comp,
            comp2,
            dout: st.dout,
        }
    }

    /// Solenoid signals and currents (d1.05-d1.09) from the branches'
    /// drive signals; all 0 unless the power stage is `driving`.
    fn solenoids(&self, od: &mut Od, n: u8, mode: u8, b1: BranchOut, b2: BranchOut, driving: bool) {
        let e03 = get(od, n, id::E03);
        let e10 = get(od, n, id::E10);
        let c = |k: u16| get(od, n, id::C1_00 + k);
        let (gain_a, gain_b, dead_a, dead_b) = (c(3), c(4), c(7), c(8));
        // Mode 2 drives one solenoid per branch; otherwise branch 1's sign
        // picks solenoid A (+) or B (-).
        let (a, b) = if mode == 2 {
            (b1.drive.max(0), b2.drive.max(0))
        } else {
            (b1.drive.max(0), (-b1.drive).max(0))
        };
        // Gain C1.03/C1.04 and dead band C1.07/C1.08 per solenoid.
        let signal = |v: i64, gain: i64, dead: i64| {
            if v == 0 || !driving {
                0
            } else {
                (dead + v * gain / 100 * (9999 - dead) / 9999).clamp(0, 9999)
            }
        };
        let sa = signal(a, gain_a, dead_a);
        let sb = signal(b, gain_b, dead_b);
        let sel = e03.clamp(1, 7) as usize;
        let max_ma = SOLENOID_MA.get(sel - 1).copied().unwrap_or(2700) * e10 / 100;
        let ia = (sa * max_ma / 9999).clamp(0, 5000);
        let ib = (sb * max_ma / 9999).clamp(0, 5000);
        set(od, n, id::D1_05, sa);
        set(od, n, id::D1_06, sb);
        set(od, n, id::D1_07, ia);
        set(od, n, id::D1_08, ib);
        set(od, n, id::D1_09, (ia + ib).min(5000));
    }
}
