//! # What the PAM-199-P-ETC does: [`Pam`], the device's application
//!
//! [`Pam`] is the [`Application`] of the core: the 0xF801 commands, the
//! vendor password, FUNCTION selecting the PDO set, the ACC gain lock,
//! parameter storage, diagnosis emergencies ([`diagnosis`]) and the
//! amplifier task ([`amplifier`]), which drives the solenoids through the
//! board's [`PowerStage`].
//!
//! The amplifier's behaviour follows the product manual (chapters 2, 4.5,
//! 6.2–6.5 and 8.1); its parts below [`amplifier`] know nothing of
//! EtherCAT, the object dictionary or PDOs: the amplifier reads the
//! parameters out of the OD ([`entries`]), feeds the command value and the
//! ENABLE bit in and copies the results (W, C, U, IA/IB, diagnosis flags)
//! back.
//!
//! Properties shared by every module here:
//!
//! * `no_std`, no heap, no `unsafe`, no panics on any input (all arithmetic is
//!   bounded, clamped, saturating or checked; no indexing).
//! * **Time is injected**: every time-dependent function takes `dt_us`
//!   (microseconds since the previous call); there are no clocks.
//! * The signal chain ([`ramp`], [`curve`], [`deadband`], [`chain`]) uses
//!   integer arithmetic only, in units of 0.01 % (full scale
//!   [`FULL_SCALE`] = 10000), so it is exact and deterministic. Only the
//!   solenoid *simulation* of the board ([`crate::board::SimPowerStage`])
//!   uses `f32`.
//!
//! Pipeline per channel (manual 6.5, see [`chain`]):
//!
//! ```text
//! command --IO_BASE--> W --ramp (RA)--> C --CC (CCMODE)--> --TRIGGER/MIN/MAX--> U
//!         U * CURRENT / 10000 --> current setpoint [mA] --> PowerStage --> IA / IB
//! ```

use ecat_slave::al::{AlState, AlStatusCode};
use ecat_slave::device::{Application, DeviceDescription, Download, StateChange, Tick, Write};
use ecat_slave::hal::{MemNv, NvStorage};
use ecat_slave::od::Od;
use ecat_slave::params::{self, STORAGE_SIZE, Stored};
use ecat_slave::wire::coe::SdoAbortCode;

use crate::board::{PowerStage, SimPowerStage};
use crate::description::{DEVICE, function_set, od};
use amplifier::Amplifier;
use diagnosis::FaultState;

pub mod amplifier;
pub mod chain;
pub mod curve;
pub mod deadband;
pub mod diagnosis;
pub mod entries;
pub mod ramp;

pub use chain::{
    ChannelOutput, DirectionalChain, DirectionalParams, IndependentChain, IndependentParams,
};
pub use curve::{Coord, Curve, DirectionalCurve, IndependentCurve, Point};
pub use deadband::{Deadband, DirectionalDeadband, MmType};
pub use ramp::{FourQuadrantRamp, Ramp};

pub use crate::description::FULL_SCALE;

/// Integer division `n / d` rounded to the nearest integer, halves away from
/// zero (so the result is symmetric for positive and negative `n`).
///
/// Returns 0 for `d <= 0` instead of panicking; callers only pass positive
/// divisors. Inputs are bounded by the callers so the intermediate
/// `n ± d / 2` cannot overflow; saturating arithmetic guards it anyway.
// Out of line on a microcontroller: inlined at its many call sites, its
// 64-bit arithmetic costs hundreds of bytes of flash (issue 30).
#[cfg_attr(target_os = "none", inline(never))]
pub(crate) fn div_round(n: i64, d: i64) -> i64 {
    if d <= 0 {
        return 0;
    }
    let d = d.unsigned_abs();
    let max = i64::MAX.unsigned_abs();
    // |n| + d / 2, saturated at i64::MAX as in i64 arithmetic (both terms
    // are below 2^63, so the u64 sum cannot overflow).
    let m = (n.unsigned_abs().min(max) + d / 2).min(max);
    // q <= m <= i64::MAX: the conversion cannot fail.
    let q = i64::try_from(div_rem_u64(m, d).0).unwrap_or(i64::MAX);
    if n >= 0 { q } else { -q }
}

/// `(n / d, n % d)`, and `(0, n)` for `d == 0` instead of a panic (no
/// caller divides by 0).
///
/// One hardware division when both fit in 32 bits (a Cortex-M divides
/// those in one instruction); else binary long division, one bit per
/// step. The compiler's 64-bit division (`__aeabi_uldivmod`, built for
/// speed) is about 930 bytes of Cortex-M4 flash, this 174 (issue 30);
/// the 64 steps are a few hundred cycles, taken only by a ramp of more
/// than about 200 s or a tick after a pause of more than 4 s.
#[cfg_attr(target_os = "none", inline(never))]
pub(crate) fn div_rem_u64(n: u64, d: u64) -> (u64, u64) {
    if d == 0 {
        return (0, n);
    }
    if let (Ok(n), Ok(d)) = (u32::try_from(n), u32::try_from(d)) {
        return (
            u64::from(n.checked_div(d).unwrap_or(0)),
            u64::from(n.checked_rem(d).unwrap_or(n)),
        );
    }
    let (mut q, mut r) = (0u64, 0u64);
    for bit in (0..64).rev() {
        // No bit is lost to the shift: r < 2^63 here. For d <= 2^63,
        // r < d; for a larger d, nothing is subtracted before the last
        // bit, so r is n shifted right by at least one.
        r = (r << 1) | ((n >> bit) & 1);
        if r >= d {
            r = r.wrapping_sub(d);
            q |= 1 << bit;
        }
    }
    (q, r)
}

/// Clamps an `i64` into the `i32` range.
// Out of line on a microcontroller: inlined at its many call sites, its
// 64-bit arithmetic costs hundreds of bytes of flash (issue 30).
#[cfg_attr(target_os = "none", inline(never))]
pub(crate) fn sat_i32(v: i64) -> i32 {
    // After the clamp the value fits, so the fallback is never taken.
    i32::try_from(v.clamp(i64::from(i32::MIN), i64::from(i32::MAX))).unwrap_or(0)
}

/// The vendor password that unlocks the manufacturer settings 0xF80F when
/// written to 0xF801:01 PASSWORD ("WEST" in ASCII, little-endian 0x54534557).
pub const VENDOR_PASSWORD: u32 = 0x5453_4557;

/// Value a command entry (0xF801:02..04) reads back as acknowledgement.
pub const COMMAND_ACK: i64 = 0x1111_1111;

/// How long the acknowledgement stays visible.
pub const COMMAND_ACK_NS: u64 = 500_000_000;

/// Shortest interval between two SAVE commands: SAVE writes the EEPROM and
/// must not be called cyclically (manual 6.2.2). A faster SAVE is refused
/// with abort 0x08000021 (local control).
pub const SAVE_MIN_INTERVAL_NS: u64 = 1_000_000_000;

/// Whether `index:sub` is mapped by an RxPDO of the assignment 0x1C12.
fn rx_mapped(od: &Od, index: u16, sub: u8) -> bool {
    if !(0x7000..=0x7FFF).contains(&index) {
        return false;
    }
    let count = od.get(0x1C12, 0).unwrap_or(0).clamp(0, 254) as u8;
    (1..=count).any(|k| {
        let pdo = od.get(0x1C12, k).unwrap_or(0) as u16;
        let entries = od.get(pdo, 0).unwrap_or(0).clamp(0, 254) as u8;
        (1..=entries).any(|e| {
            let m = od.get(pdo, e).unwrap_or(0) as u32;
            (m >> 16) as u16 == index && (m >> 8) as u8 == sub
        })
    })
}

/// The PAM-199-P-ETC's behaviour, driving the solenoids through a
/// [`PowerStage`] and keeping its parameters in an [`NvStorage`].
pub struct Pam<P: PowerStage = SimPowerStage, N: NvStorage = MemNv<STORAGE_SIZE>> {
    amplifier: Amplifier,
    stage: P,
    nv: N,
    /// What the parameter storage held at power-on.
    stored_at_power_on: Stored,
    unlocked: bool,
    last_save_ns: Option<u64>,
    /// A command entry showing its acknowledgement until the given time.
    ack: Option<(u16, u8, u64)>,
    /// The faults reported so far (emergencies on new ones).
    faults: FaultState,
}

impl<P: PowerStage, N: NvStorage> core::fmt::Debug for Pam<P, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Pam")
            .field("stored_at_power_on", &self.stored_at_power_on)
            .field("unlocked", &self.unlocked)
            .finish_non_exhaustive()
    }
}

impl Default for Pam {
    fn default() -> Self {
        Pam::new(SimPowerStage::new(), MemNv::new())
    }
}

impl<P: PowerStage, N: NvStorage> Pam<P, N> {
    /// The amplifier driving `stage`, with its parameters in `nv` (defaults
    /// when blank; a corrupt store is an EEPROM data error: power stage off
    /// until SAVE).
    pub fn new(stage: P, nv: N) -> Self {
        Pam {
            amplifier: Amplifier::new(),
            stage,
            nv,
            stored_at_power_on: Stored::Blank,
            unlocked: false,
            last_save_ns: None,
            ack: None,
            faults: FaultState::default(),
        }
    }

    /// The power stage.
    pub fn stage(&self) -> &P {
        &self.stage
    }

    /// The power stage, mutably (fault injection on the simulation).
    pub fn stage_mut(&mut self) -> &mut P {
        &mut self.stage
    }

    /// The amplifier task.
    pub fn amplifier(&self) -> &Amplifier {
        &self.amplifier
    }

    /// The parameter storage.
    pub fn nv(&self) -> &N {
        &self.nv
    }

    /// The parameter storage, mutably (power-cut simulation).
    pub fn nv_mut(&mut self) -> &mut N {
        &mut self.nv
    }

    /// What the parameter storage held at power-on.
    pub fn stored_at_power_on(&self) -> Stored {
        self.stored_at_power_on
    }

    /// Runs SAVE / DEFAULT / LOADBACK (0xF801:02..04 written with 1) in
    /// AL state `state`.
    ///
    /// DEFAULT and LOADBACK restore the parameters but keep two rules
    /// (docs/SAFETY.md): F800:02 FUNCTION selects the process image, so a
    /// command that would change it is refused outside PRE-OP (0x08000022,
    /// as a write of F800:02 is) and in PRE-OP selects the matching PDO
    /// assignment; the manufacturer settings 0xF80F change only while the
    /// vendor password is given.
    fn command(
        &mut self,
        od: &mut Od,
        sub: u8,
        state: AlState,
        now_ns: u64,
    ) -> Result<(), SdoAbortCode> {
        if matches!(sub, 3 | 4) {
            let function = od.get(0xF800, 2);
            let next = if sub == 3 {
                od.dictionary()
                    .find_entry(0xF800, 2)
                    .and_then(|(_, e)| e.default_value().as_int())
            } else {
                params::stored_value(&self.nv, od.dictionary(), 0xF800, 2)
            };
            let changes_function = next.is_some() && next != function;
            if changes_function && state != AlState::PreOp {
                return Err(SdoAbortCode::InvalidState);
            }
            let manufacturer = [od.get(0xF80F, 1), od.get(0xF80F, 2)];
            match sub {
                3 => params::restore_defaults(od),
                _ => {
                    params::load(od, &self.nv).map_err(|_| SdoAbortCode::TransferFailed)?;
                }
            }
            if !self.unlocked {
                for (s, v) in (1u8..).zip(manufacturer) {
                    if let Some(v) = v {
                        od.set(0xF80F, s, v);
                    }
                }
            }
            if changes_function {
                ecat_slave::pdo::assign_set(od, &DEVICE.process_data, function_set(od));
            }
            od.set(0xF801, sub, COMMAND_ACK);
            self.ack = Some((0xF801, sub, now_ns.saturating_add(COMMAND_ACK_NS)));
            return Ok(());
        }
        match sub {
            2 => {
                if let Some(last) = self.last_save_ns
                    && now_ns.saturating_sub(last) < SAVE_MIN_INTERVAL_NS
                {
                    return Err(SdoAbortCode::LocalControl);
                }
                params::save(od, &mut self.nv).map_err(|_| SdoAbortCode::HardwareError)?;
                self.last_save_ns = Some(now_ns);
                // Saving valid parameters clears an EEPROM data error.
                self.amplifier.eeprom_error = false;
            }
            _ => return Err(SdoAbortCode::SubindexNotFound),
        }
        od.set(0xF801, sub, COMMAND_ACK);
        self.ack = Some((0xF801, sub, now_ns.saturating_add(COMMAND_ACK_NS)));
        Ok(())
    }
}

impl<P: PowerStage + Send + 'static, N: NvStorage + Send + 'static> Application for Pam<P, N> {
    fn description(&self) -> &'static DeviceDescription {
        &DEVICE
    }
    type Values = [i64; od::ENTRY_COUNT];

    fn power_on(&mut self, od: &mut Od) {
        self.stored_at_power_on = params::stored(&self.nv, od.dictionary());
        match self.stored_at_power_on {
            Stored::Valid(_) => {
                if params::load(od, &self.nv).is_err() {
                    self.amplifier.eeprom_error = true;
                }
                // A saved FUNCTION comes back with its PDO set.
                ecat_slave::pdo::assign_set(od, &DEVICE.process_data, function_set(od));
            }
            Stored::Blank => {}
            Stored::Corrupt => self.amplifier.eeprom_error = true,
        }
    }

    fn state_change(&mut self, od: &mut Od, change: &StateChange) -> Result<(), AlStatusCode> {
        // The assignment must match F800:02 FUNCTION (writing FUNCTION in
        // PRE-OP selects the matching set; a hand-written assignment of the
        // other set is refused here).
        if change.from == AlState::PreOp && change.to == AlState::SafeOp {
            let bit = 1u32 << function_set(od);
            if change.rx_sets & bit == 0 {
                return Err(AlStatusCode::InvalidOutputConfig);
            }
            if change.tx_sets & bit == 0 {
                return Err(AlStatusCode::InvalidInputConfig);
            }
        }
        Ok(())
    }

    fn sdo_download(&mut self, od: &mut Od, d: &Download<'_>) -> Result<Write, SdoAbortCode> {
        let index = d.index;
        // In OP the cyclic outputs own the mapped output objects: an SDO
        // write there would drive the valve until the next cycle
        // overwrote it (docs/SAFETY.md P2, found by invariant I1).
        if d.state == AlState::Op && d.changes.iter().any(|(sub, _)| rx_mapped(od, index, sub)) {
            return Err(SdoAbortCode::InvalidState);
        }
        // 0xF801: PASSWORD unlocks (or with 0 locks) the manufacturer
        // settings; SAVE / DEFAULT / LOADBACK run when written with 1.
        if index == 0xF801 {
            if d.complete_access {
                // Commands and the password are written one at a time.
                return Err(SdoAbortCode::CompleteAccessNotSupported);
            }
            let value = d.value(d.sub).unwrap_or(0);
            if d.sub == 1 {
                self.unlocked = match value as u32 {
                    VENDOR_PASSWORD => true,
                    0 => false,
                    _ => {
                        self.unlocked = false;
                        return Err(SdoAbortCode::ValueRange);
                    }
                };
                return Ok(Write::Done);
            }
            if value != 1 {
                return Err(SdoAbortCode::ValueRange);
            }
            self.command(od, d.sub, d.state, d.now_ns)?;
            return Ok(Write::Done);
        }
        // 0xF80F manufacturer settings need the vendor password first.
        if index == 0xF80F && !self.unlocked {
            return Err(SdoAbortCode::UnsupportedAccess);
        }
        // Manual 6.4.5: with ACC = ON the controller gains follow the PWM
        // frequency and cannot be set by the user.
        if matches!(index, 0x800D | 0x801D | 0x802D) {
            if d.complete_access {
                let acc = d.value(7).or(od.get(index, 7)) == Some(1);
                let gains_change = [9u8, 10]
                    .iter()
                    .any(|s| d.value(*s).is_some_and(|v| Some(v) != od.get(index, *s)));
                if acc && gains_change {
                    return Err(SdoAbortCode::LocalControl);
                }
            } else if matches!(d.sub, 9 | 10) && od.get(index, 7) == Some(1) {
                return Err(SdoAbortCode::LocalControl);
            }
        }
        // F800:02 FUNCTION changes the process image: PRE-OP only, and it
        // selects the matching extended PDO assignment.
        if index == 0xF800 {
            let old = function_set(od);
            let new = match d.value(2) {
                Some(2) => 1,
                Some(_) => 0,
                None => old,
            };
            let single = !d.complete_access && d.sub == 2;
            if (single || new != old) && d.state != AlState::PreOp {
                return Err(SdoAbortCode::InvalidState);
            }
            d.apply(od);
            if single || new != old {
                ecat_slave::pdo::assign_set(od, &DEVICE.process_data, new);
            }
            return Ok(Write::Done);
        }
        Ok(Write::Store)
    }

    fn tick(&mut self, t: &mut Tick<'_>) {
        // The vendor unlock ends with the master session: INIT (ETG.1000.6:
        // the state every master starts from) locks 0xF80F again.
        if t.state == AlState::Init {
            self.unlocked = false;
        }
        crate::app::entries::TIMESTAMP.set(t.od, t.now_ns as i64);
        if let Some((index, sub, until)) = self.ack
            && t.now_ns >= until
        {
            t.od.set(index, sub, 0);
            self.ack = None;
        }
        // The solenoids are driven only from cyclic outputs in OP under an
        // armed SM watchdog (docs/SAFETY.md, PAM rule 1).
        let drive = t.outputs_valid && t.sm_watchdog_armed;
        self.amplifier
            .run_until(t.od, &mut self.stage, t.now_ns, drive);
        let faults = FaultState::from_od(t.od);
        faults.report(&self.faults, t);
        self.faults = faults;
    }

    fn outputs_safe(&mut self, _od: &mut Od) {
        self.stage.disable();
    }

    fn pdi_watchdog_expired(&mut self) {
        self.stage.disable();
    }

    fn power_cycle(&mut self) {
        self.amplifier = Amplifier::new();
        self.stage.power_cycle();
        self.unlocked = false;
        self.last_save_ns = None;
        self.ack = None;
        self.faults = FaultState::default();
    }

    fn nv(&self) -> Option<&dyn NvStorage> {
        Some(&self.nv)
    }

    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        Some(&mut self.nv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn div_round_is_symmetric_and_rounds_halves_away_from_zero() {
        assert_eq!(div_round(5, 2), 3);
        assert_eq!(div_round(-5, 2), -3);
        assert_eq!(div_round(4, 3), 1);
        assert_eq!(div_round(-4, 3), -1);
        assert_eq!(div_round(7, 0), 0);
        assert_eq!(div_round(i64::MIN, 3), -(i64::MAX / 3));
    }

    #[test]
    fn div_rem_u64_agrees_with_the_division_operator_at_the_edges() {
        let edges = [
            0,
            1,
            2,
            3,
            999,
            1_000_000,
            u64::from(u32::MAX) - 1,
            u64::from(u32::MAX),
            u64::from(u32::MAX) + 1,
            1 << 40,
            (1 << 63) - 1,
            1 << 63,
            (1 << 63) + 1,
            u64::MAX - 1,
            u64::MAX,
        ];
        for n in edges {
            for d in edges.into_iter().filter(|d| *d != 0) {
                assert_eq!(div_rem_u64(n, d), (n / d, n % d), "{n} / {d}");
            }
            assert_eq!(div_rem_u64(n, 0), (0, n));
        }
    }

    proptest::proptest! {
        #[test]
        fn div_rem_u64_agrees_with_the_division_operator(n: u64, d in 1u64..) {
            proptest::prop_assert_eq!(div_rem_u64(n, d), (n / d, n % d));
        }

        #[test]
        fn div_rem_u64_agrees_for_small_divisors(n: u64, d in 1u64..=u64::from(u32::MAX)) {
            proptest::prop_assert_eq!(div_rem_u64(n, d), (n / d, n % d));
        }

        #[test]
        fn div_round_agrees_with_i128_rounding(n: i64, d in 1i64..) {
            // The reference in i128: |n| + d / 2 saturated at i64::MAX.
            let max = i128::from(i64::MAX);
            let m = (i128::from(n).abs().min(max) + i128::from(d / 2)).min(max);
            let q = m / i128::from(d);
            let expected = if n >= 0 { q } else { -q };
            proptest::prop_assert_eq!(i128::from(div_round(n, d)), expected);
        }

        /// The amplifier clamps its parameters as `sat_i32(v).clamp(lo,
        /// hi)` (a 32-bit clamp after one out-of-line call): the same as
        /// the 64-bit clamp for any range inside `i32`.
        #[test]
        fn a_32_bit_clamp_after_sat_i32_is_the_64_bit_clamp(v: i64, a: i32, b: i32) {
            let (lo, hi) = (a.min(b), a.max(b));
            proptest::prop_assert_eq!(
                i64::from(sat_i32(v).clamp(lo, hi)),
                v.clamp(i64::from(lo), i64::from(hi))
            );
        }
    }

    #[test]
    fn sat_i32_clamps() {
        assert_eq!(sat_i32(i64::MAX), i32::MAX);
        assert_eq!(sat_i32(i64::MIN), i32::MIN);
        assert_eq!(sat_i32(-7), -7);
    }
}
