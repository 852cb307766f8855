//! A [`Drive`] bound to an object dictionary by object indices: what a
//! device's or a twin's `Application` calls.
//!
//! [`Cia402Axis::tick`] reads the set points (0x6040, 0x6060, 0x607A,
//! 0x60FF, 0x6071) and the parameters from the dictionary, runs one
//! [`Drive::step`] with the core's `outputs_valid` / `sm_watchdog_armed`
//! and the DC cycle of 0x1C32, and writes the actual values back (0x6041,
//! 0x6061, 0x6062, 0x6064, 0x606C, 0x6077, 0x60F4, 0x603F); a fault
//! queues its Emergency and sets the error register. Objects the
//! dictionary lacks are skipped (read as their default): a twin of a
//! vendor's drive has what its ESI declares. [`Cia402Axis::check_download`]
//! is the profile's part of `Application::sdo_download`.
//!
//! ```
//! use ecat_cia402::Cia402Axis;
//! use ecat_cia402::objects::{self, join, object_count};
//! use ecat_slave::od::{Object, ObjectStore};
//! use ecat_slave::od::build::var;
//! use ecat_slave::od::{DataType, ObjectCode, PdoMapping};
//!
//! const HEAD: &[Object] = &[Object { index: 0x1000, name: "Device type", code: ObjectCode::Var,
//!     entries: &[var("Device type", DataType::UInt32, PdoMapping::None, objects::DEVICE_TYPE_SERVO)] }];
//! const PARTS: &[&[Object]] = &[HEAD, objects::OBJECTS];
//! const ALL: [Object; object_count(PARTS)] = join(PARTS);
//! ecat_slave::dictionary!(DICT, ENTRIES = &ALL, &[]);
//!
//! assert!(Cia402Axis::is_cia402(&DICT));
//! let mut axis = Cia402Axis::new(&DICT).unwrap();
//! let mut od = ObjectStore::<[i64; ENTRIES]>::new(&DICT);
//! let connected = ecat_cia402::Link { outputs_valid: true, watchdog_armed: true, dc_cycle_ns: None };
//! for (ms, cw) in [(0, 0x00), (1, 0x06), (2, 0x07), (3, 0x0F)] {
//!     od.set(0x6040, 0, cw);
//!     axis.step(&mut od, ms * 1_000_000, connected, None);
//! }
//! assert_eq!(od.get(0x6041, 0).map(|sw| sw & 0x6F), Some(0x27)); // Operation enabled
//! ```

use ecat_slave::device::{Download, Tick};
use ecat_slave::od::{DefaultValue, Dictionary, Od};
use ecat_slave::wire::coe::SdoAbortCode;

use crate::axis::{Axis, AxisModel};
use crate::drive::{Drive, Link, Parameters, Report, Setpoints};
use crate::mode::{HOMING_METHODS, Mode};
use crate::objects::{AXIS_OFFSET, SAFETY_PARAMETERS, index};

/// Why a dictionary cannot carry a CiA 402 axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum AxisError {
    /// A mandatory object is missing.
    #[error(
        "the dictionary has no {index:#06x} (a CiA 402 axis needs its controlword and statusword)"
    )]
    MissingObject {
        /// The object.
        index: u16,
    },
    /// CiA 402 has logical devices 0..=7 only.
    #[error("axis {axis} is beyond the 8 logical devices of CiA 402")]
    NoSuchAxis {
        /// The axis asked for.
        axis: u8,
    },
}

/// The actual values [`Cia402Axis`] writes (relative to the axis).
const WRITTEN: [u16; 8] = [
    index::STATUSWORD,
    index::MODES_DISPLAY,
    index::POSITION_DEMAND,
    index::POSITION_ACTUAL,
    index::VELOCITY_ACTUAL,
    index::TORQUE_ACTUAL,
    index::FOLLOWING_ERROR_ACTUAL,
    index::ERROR_CODE,
];

fn clamp_to<T: TryFrom<i64>>(v: i64, lo: T, hi: T) -> T {
    T::try_from(v).unwrap_or(if v < 0 { lo } else { hi })
}

/// A CiA 402 axis on a dictionary. See the module documentation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cia402Axis<A: Axis = AxisModel> {
    drive: Drive<A>,
    /// Added to the axis-0 indices: n × 0x800 for axis n.
    offset: u16,
}

impl Cia402Axis<AxisModel> {
    /// Axis 0 of `dict` on the [`AxisModel`].
    pub fn new(dict: &Dictionary) -> Result<Self, AxisError> {
        Self::with_axis(dict, 0, AxisModel::default())
    }

    /// Whether `dict` describes a CiA 402 drive: 0x1000 names profile 402
    /// (bits 0-15), or it has 0x6040 and 0x6041 (ETG.6010 names both
    /// mandatory; vendors' ESI files do not always set 0x1000).
    pub fn is_cia402(dict: &Dictionary) -> bool {
        let profile = matches!(
            dict.find_entry(0x1000, 0).map(|(_, e)| e.default_value()),
            Some(DefaultValue::Int(v)) if v.get() & 0xFFFF == 402
        );
        let objects = dict.find_entry(index::CONTROLWORD, 0).is_some()
            && dict.find_entry(index::STATUSWORD, 0).is_some();
        profile || objects
    }

    /// The axes of `dict` (axis n present when its 0x6040 + n × 0x800 and
    /// 0x6041 + n × 0x800 are): what a twin of a multi-axis drive runs.
    pub fn axes_of(dict: &Dictionary) -> impl Iterator<Item = u8> + '_ {
        (0..8u8).filter(|&n| {
            let o = u16::from(n) * AXIS_OFFSET;
            dict.find_entry(index::CONTROLWORD + o, 0).is_some()
                && dict.find_entry(index::STATUSWORD + o, 0).is_some()
        })
    }

    /// The DC cycle when the device runs DC-synchronous: 0x1C32:01 = 2
    /// (ETG.1020 "DC SYNC0") with the cycle 0x1C32:02 the core keeps.
    pub fn dc_cycle_ns(od: &Od) -> Option<u32> {
        if od.get(0x1C32, 1) != Some(ecat_slave::od::build::sync_mode::DC_SYNC0) {
            return None;
        }
        od.get(0x1C32, 2)
            .and_then(|c| u32::try_from(c).ok())
            .filter(|&c| c > 0)
    }
}

impl<A: Axis> Cia402Axis<A> {
    /// Axis 0 on a dictionary that holds [`crate::objects::OBJECTS`] (a
    /// device built on the profile; nothing to check, missing objects
    /// would only be skipped).
    pub fn axis0(axis: A) -> Self {
        Cia402Axis {
            drive: Drive::new(axis),
            offset: 0,
        }
    }

    /// Axis `n` (0..=7, objects at 0x6000 + n × 0x800) of `dict`, moving
    /// `axis`.
    pub fn with_axis(dict: &Dictionary, n: u8, axis: A) -> Result<Self, AxisError> {
        if n > 7 {
            return Err(AxisError::NoSuchAxis { axis: n });
        }
        let offset = u16::from(n) * AXIS_OFFSET;
        for i in [index::CONTROLWORD, index::STATUSWORD] {
            let i = i + offset;
            if dict.find_entry(i, 0).is_none() {
                return Err(AxisError::MissingObject { index: i });
            }
        }
        Ok(Cia402Axis {
            drive: Drive::new(axis),
            offset,
        })
    }

    /// The drive.
    pub fn drive(&self) -> &Drive<A> {
        &self.drive
    }

    /// The drive, mutably.
    pub fn drive_mut(&mut self) -> &mut Drive<A> {
        &mut self.drive
    }

    /// The index of this axis's copy of the axis-0 object `index`.
    pub fn index(&self, index: u16) -> u16 {
        index.wrapping_add(self.offset)
    }

    /// Whether the axis writes object `index` (its statusword and actual
    /// values): a twin leaves these to it and out of its input rule.
    pub fn owns(&self, index: u16) -> bool {
        WRITTEN.iter().any(|&i| self.index(i) == index)
    }

    fn get(&self, od: &Od, i: u16) -> Option<i64> {
        od.get(self.index(i), 0)
    }

    /// The set points in `od`.
    pub fn setpoints(&self, od: &Od) -> Setpoints {
        let g = |i| self.get(od, i).unwrap_or(0);
        Setpoints {
            controlword: clamp_to(g(index::CONTROLWORD), 0, u16::MAX),
            mode: clamp_to(g(index::MODES_OF_OPERATION), i8::MIN, i8::MAX),
            target_position: clamp_to(g(index::TARGET_POSITION), i32::MIN, i32::MAX),
            target_velocity: clamp_to(g(index::TARGET_VELOCITY), i32::MIN, i32::MAX),
            target_torque: clamp_to(g(index::TARGET_TORQUE), i16::MIN, i16::MAX),
        }
    }

    /// The parameters in `od` (a missing object gives the profile's default).
    pub fn parameters(&self, od: &Od) -> Parameters {
        let d = Parameters::DEFAULT;
        let g = |i, default: i64| self.get(od, i).unwrap_or(default);
        Parameters {
            abort_connection_option: clamp_to(
                g(
                    index::ABORT_CONNECTION_OPTION,
                    d.abort_connection_option.into(),
                ),
                i16::MIN,
                i16::MAX,
            ),
            quick_stop_option: clamp_to(
                g(index::QUICK_STOP_OPTION, d.quick_stop_option.into()),
                i16::MIN,
                i16::MAX,
            ),
            fault_reaction_option: clamp_to(
                g(index::FAULT_REACTION_OPTION, d.fault_reaction_option.into()),
                i16::MIN,
                i16::MAX,
            ),
            following_error_window: clamp_to(
                g(
                    index::FOLLOWING_ERROR_WINDOW,
                    d.following_error_window.into(),
                ),
                0,
                u32::MAX,
            ),
            following_error_timeout_ms: clamp_to(
                g(
                    index::FOLLOWING_ERROR_TIMEOUT,
                    d.following_error_timeout_ms.into(),
                ),
                0,
                u16::MAX,
            ),
            position_window: clamp_to(
                g(index::POSITION_WINDOW, d.position_window.into()),
                0,
                u32::MAX,
            ),
            velocity_window: clamp_to(
                g(index::VELOCITY_WINDOW, d.velocity_window.into()),
                0,
                u16::MAX,
            ),
            velocity_threshold: clamp_to(
                g(index::VELOCITY_THRESHOLD, d.velocity_threshold.into()),
                0,
                u16::MAX,
            ),
            max_torque: clamp_to(g(index::MAX_TORQUE, d.max_torque.into()), 0, u16::MAX),
            home_offset: clamp_to(
                g(index::HOME_OFFSET, d.home_offset.into()),
                i32::MIN,
                i32::MAX,
            ),
            max_motor_speed: clamp_to(
                g(index::MAX_MOTOR_SPEED, d.max_motor_speed.into()),
                0,
                u32::MAX,
            ),
            profile_velocity: clamp_to(
                g(index::PROFILE_VELOCITY, d.profile_velocity.into()),
                0,
                u32::MAX,
            ),
            profile_acceleration: clamp_to(
                g(index::PROFILE_ACCELERATION, d.profile_acceleration.into()),
                0,
                u32::MAX,
            ),
            profile_deceleration: clamp_to(
                g(index::PROFILE_DECELERATION, d.profile_deceleration.into()),
                0,
                u32::MAX,
            ),
            quick_stop_deceleration: clamp_to(
                g(
                    index::QUICK_STOP_DECELERATION,
                    d.quick_stop_deceleration.into(),
                ),
                0,
                u32::MAX,
            ),
            homing_method: clamp_to(
                g(index::HOMING_METHOD, d.homing_method.into()),
                i8::MIN,
                i8::MAX,
            ),
        }
    }

    /// One step on `od`: set points and parameters read, actual values
    /// written. `hardware_fault`: a fault the board reports (its error
    /// code), or `None`.
    pub fn step(
        &mut self,
        od: &mut Od,
        now_ns: u64,
        link: Link,
        hardware_fault: Option<u16>,
    ) -> Report {
        let sp = self.setpoints(od);
        let p = self.parameters(od);
        let report = self.drive.step(&sp, link, hardware_fault, &p, now_ns);
        let i = report.inputs;
        for (index, value) in [
            (index::STATUSWORD, i64::from(i.statusword)),
            (index::MODES_DISPLAY, i64::from(i.mode_display)),
            (index::POSITION_DEMAND, i64::from(i.position_demand)),
            (index::POSITION_ACTUAL, i64::from(i.position)),
            (index::VELOCITY_ACTUAL, i64::from(i.velocity)),
            (index::TORQUE_ACTUAL, i64::from(i.torque)),
            (index::FOLLOWING_ERROR_ACTUAL, i64::from(i.following_error)),
            (index::ERROR_CODE, i64::from(i.error_code)),
        ] {
            od.set(self.index(index), 0, value);
        }
        report
    }

    /// The profile's part of `Application::tick`: one [`Self::step`] with
    /// the tick's time, `outputs_valid`, `sm_watchdog_armed` and the DC
    /// cycle; a new fault queues its Emergency (error code, data 0), the
    /// error register (0x1001) gets the fault's class bits.
    pub fn tick(&mut self, t: &mut Tick<'_>, hardware_fault: Option<u16>) -> Report {
        let link = Link {
            outputs_valid: t.outputs_valid,
            watchdog_armed: t.sm_watchdog_armed,
            dc_cycle_ns: Cia402Axis::dc_cycle_ns(t.od),
        };
        let report = self.step(t.od, t.now_ns, link, hardware_fault);
        t.set_error_bits(report.error_register);
        if let Some(code) = report.emergency {
            t.emergency(code, [0; 5]);
        }
        report
    }

    /// A power cycle of the drive's logic (see [`Drive::reset`]).
    pub fn reset(&mut self) {
        self.drive.reset();
    }

    /// The firmware stalled and the ESC's PDI watchdog cut the power
    /// stage: the drive goes to Fault 0x6010 (see [`Drive::power_cut`]),
    /// shown in `od` at once.
    pub fn power_cut(&mut self, od: &mut Od) {
        if self.drive.power_cut().is_some() {
            od.set(
                self.index(index::ERROR_CODE),
                0,
                i64::from(self.drive.error_code()),
            );
        }
    }

    /// The profile's checks of an SDO download the core accepted (call
    /// from `Application::sdo_download`; `Ok` lets the device store it):
    /// 0x6060 takes 0 or a mode this profile runs, 0x6098 a homing method
    /// it runs (0x06090030 otherwise); the parameters that decide how the
    /// drive stops or how fast it may go ([`SAFETY_PARAMETERS`]) change
    /// only while the power stage is off (0x08000022 otherwise,
    /// docs/SAFETY.md S4).
    pub fn check_download(&self, d: &Download<'_>) -> Result<(), SdoAbortCode> {
        let i = d.index.wrapping_sub(self.offset);
        for (_, v) in d.changes.iter() {
            match i {
                index::MODES_OF_OPERATION if v != 0 && Mode::from_code(v).is_none() => {
                    return Err(SdoAbortCode::ValueRange);
                }
                index::HOMING_METHOD if !HOMING_METHODS.iter().any(|&m| i64::from(m) == v) => {
                    return Err(SdoAbortCode::ValueRange);
                }
                _ => {}
            }
        }
        if SAFETY_PARAMETERS.contains(&i) && self.drive.power_stage_enabled() {
            return Err(SdoAbortCode::InvalidState);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::{self, join, object_count};
    use crate::state::PowerState;
    use ecat_slave::AlState;
    use ecat_slave::device::Changes;
    use ecat_slave::od::build::var;
    use ecat_slave::od::{DataType, Object, ObjectCode, ObjectStore, PdoMapping};

    const HEAD: &[Object] = &[Object {
        index: 0x1000,
        name: "Device type",
        code: ObjectCode::Var,
        entries: &[var(
            "Device type",
            DataType::UInt32,
            PdoMapping::None,
            objects::DEVICE_TYPE_SERVO,
        )],
    }];
    const PARTS: &[&[Object]] = &[HEAD, objects::OBJECTS];
    const ALL: [Object; object_count(PARTS)] = join(PARTS);
    ecat_slave::dictionary!(DICT, ENTRIES = &ALL, &[]);

    /// Only a controlword and a statusword, as a vendor's minimal ESI.
    const MINIMAL: &[Object] = &[
        Object {
            index: 0x6040,
            name: "Controlword",
            code: ObjectCode::Var,
            entries: &[ecat_slave::od::build::output(
                0,
                "Controlword",
                DataType::UInt16,
            )],
        },
        Object {
            index: 0x6041,
            name: "Statusword",
            code: ObjectCode::Var,
            entries: &[ecat_slave::od::build::input(
                0,
                "Statusword",
                DataType::UInt16,
            )],
        },
    ];
    ecat_slave::dictionary!(MINIMAL_DICT, MINIMAL_ENTRIES = MINIMAL, &[]);

    const CONNECTED: Link = Link {
        outputs_valid: true,
        watchdog_armed: true,
        dc_cycle_ns: None,
    };

    fn download<'a>(index: u16, changes: &'a [(u8, i64)]) -> Download<'a> {
        Download {
            index,
            sub: 0,
            complete_access: false,
            state: AlState::PreOp,
            now_ns: 0,
            changes: Changes::list(changes),
        }
    }

    #[test]
    fn a_dictionary_with_controlword_and_statusword_is_a_cia402_axis_and_one_without_is_not() {
        assert!(Cia402Axis::is_cia402(&DICT));
        assert!(Cia402Axis::is_cia402(&MINIMAL_DICT));
        assert_eq!(Cia402Axis::axes_of(&DICT).collect::<Vec<_>>(), [0]);
        ecat_slave::dictionary!(NONE, NONE_ENTRIES = HEAD, &[]);
        assert_eq!(NONE_ENTRIES, 1);
        assert!(Cia402Axis::is_cia402(&NONE), "0x1000 says 402");
        assert_eq!(
            Cia402Axis::new(&NONE).err(),
            Some(AxisError::MissingObject { index: 0x6040 })
        );
        assert_eq!(
            Cia402Axis::with_axis(&DICT, 8, AxisModel::default()).err(),
            Some(AxisError::NoSuchAxis { axis: 8 })
        );
        assert_eq!(
            Cia402Axis::with_axis(&DICT, 1, AxisModel::default()).err(),
            Some(AxisError::MissingObject { index: 0x6840 })
        );
    }

    #[test]
    fn a_minimal_twin_dictionary_runs_the_state_machine_on_default_parameters() {
        let mut axis = Cia402Axis::new(&MINIMAL_DICT).unwrap();
        let mut od = ObjectStore::<[i64; MINIMAL_ENTRIES]>::new(&MINIMAL_DICT);
        for (ms, cw) in [(0, 0x00), (1, 0x06), (2, 0x0F)] {
            od.set(0x6040, 0, cw);
            axis.step(&mut od, ms * 1_000_000, CONNECTED, None);
        }
        assert_eq!(axis.drive().state(), PowerState::OperationEnabled);
        assert_eq!(od.get(0x6041, 0).map(|s| s & 0x6F), Some(0x27));
        assert_eq!(axis.parameters(&od), Parameters::DEFAULT);
        assert!(axis.owns(0x6041) && !axis.owns(0x6040));
    }

    #[test]
    fn the_axis_writes_the_actual_values_into_the_dictionary() {
        let mut axis = Cia402Axis::new(&DICT).unwrap();
        let mut od = ObjectStore::<[i64; ENTRIES]>::new(&DICT);
        od.set(index::MODES_OF_OPERATION, 0, 9); // CSV
        for (ms, cw) in [(0, 0x00), (1, 0x06), (2, 0x0F)] {
            od.set(0x6040, 0, cw);
            axis.step(&mut od, ms * 1_000_000, CONNECTED, None);
        }
        od.set(index::TARGET_VELOCITY, 0, 10_000);
        for ms in 3..100 {
            axis.step(&mut od, ms * 1_000_000, CONNECTED, None);
        }
        assert_eq!(od.get(index::MODES_DISPLAY, 0), Some(9));
        let v = od.get(index::VELOCITY_ACTUAL, 0).unwrap();
        assert!((9_990..=10_000).contains(&v), "{v}");
        let x = od.get(index::POSITION_ACTUAL, 0).unwrap();
        assert!((900..=980).contains(&x), "{x}");
        assert_eq!(
            od.get(index::STATUSWORD, 0).map(|s| s & 0x1000),
            Some(0x1000)
        );
    }

    #[test]
    fn the_dc_cycle_is_read_from_0x1c32_only_in_dc_mode() {
        const SYNC: &[Object] = &[Object {
            index: 0x1C32,
            name: "SM output parameter",
            code: ObjectCode::Record,
            entries: ecat_slave::od::build::SYNC_PARAMETER_ENTRIES,
        }];
        ecat_slave::dictionary!(S, S_ENTRIES = SYNC, &[]);
        let mut od = ObjectStore::<[i64; S_ENTRIES]>::new(&S);
        od.set(0x1C32, 2, 1_000_000);
        assert_eq!(Cia402Axis::dc_cycle_ns(&od), None);
        od.set(0x1C32, 1, 2);
        assert_eq!(Cia402Axis::dc_cycle_ns(&od), Some(1_000_000));
    }

    #[test]
    fn sdo_writes_of_unsupported_modes_and_homing_methods_are_refused() {
        let axis = Cia402Axis::new(&DICT).unwrap();
        for (index, v, ok) in [
            (index::MODES_OF_OPERATION, 0, true),
            (index::MODES_OF_OPERATION, 8, true),
            (index::MODES_OF_OPERATION, 2, false),
            (index::MODES_OF_OPERATION, -1, false),
            (index::HOMING_METHOD, 37, true),
            (index::HOMING_METHOD, 35, true),
            (index::HOMING_METHOD, 36, false),
            (index::PROFILE_VELOCITY, 1, true),
        ] {
            let changes = [(0, v)];
            let r = axis.check_download(&download(index, &changes));
            assert_eq!(r.is_ok(), ok, "{index:#06x} = {v}: {r:?}");
            if !ok {
                assert_eq!(r, Err(SdoAbortCode::ValueRange));
            }
        }
    }

    #[test]
    fn safety_parameters_are_refused_while_the_power_stage_is_on() {
        let mut axis = Cia402Axis::new(&DICT).unwrap();
        let mut od = ObjectStore::<[i64; ENTRIES]>::new(&DICT);
        let changes = [(0, 1_000)];
        for i in SAFETY_PARAMETERS {
            assert_eq!(axis.check_download(&download(i, &changes)), Ok(()));
        }
        for (ms, cw) in [(0, 0x00), (1, 0x06), (2, 0x0F)] {
            od.set(0x6040, 0, cw);
            axis.step(&mut od, ms * 1_000_000, CONNECTED, None);
        }
        for i in SAFETY_PARAMETERS {
            assert_eq!(
                axis.check_download(&download(i, &changes)),
                Err(SdoAbortCode::InvalidState),
                "{i:#06x}"
            );
        }
        // Set points and other parameters stay writable.
        assert_eq!(
            axis.check_download(&download(index::PROFILE_VELOCITY, &changes)),
            Ok(())
        );
        assert_eq!(
            axis.check_download(&download(index::TARGET_POSITION, &changes)),
            Ok(())
        );
    }

    #[test]
    fn a_power_cut_shows_fault_0x6010_in_the_dictionary() {
        let mut axis = Cia402Axis::new(&DICT).unwrap();
        let mut od = ObjectStore::<[i64; ENTRIES]>::new(&DICT);
        axis.power_cut(&mut od);
        assert_eq!(od.get(index::ERROR_CODE, 0), Some(0x6010));
        axis.step(&mut od, 0, CONNECTED, None);
        assert_eq!(od.get(index::STATUSWORD, 0).map(|s| s & 0x4F), Some(0x08));
    }
}
