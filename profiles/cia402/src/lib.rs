//! # ecat-cia402: the CiA 402 drive profile for the `ecat-slave` core
//!
//! A device profile shared by every drive built on the core and by twins
//! of vendors' drives: the CiA 402 *power drive system* (PDS) of IEC
//! 61800-7-201 (= CiA 402-2) as ETG.6010 applies it to EtherCAT. It
//! holds
//!
//! * [`state`]: the PDS finite state automaton (FSA): controlword 0x6040
//!   commands, statusword 0x6041 state coding, the transitions 0-16;
//! * [`mode`]: the modes of operation 0x6060/0x6061 this profile runs
//!   (CSP 8, CSV 9, CST 10, PP 1, PV 3, HM 6) and 0x6502;
//! * [`axis`]: the [`Axis`] a drive moves (its power stage, current and
//!   velocity loops and mechanics) and [`AxisModel`], a simple
//!   deterministic model of one;
//! * [`drive`]: [`Drive`], the profile's behaviour on injected time: the
//!   FSA with quick stop, fault reaction and the reaction to a lost
//!   connection, set-point generation per mode (profile ramps, the
//!   set-point handshake, homing on the current position, cyclic set
//!   points interpolated over the DC cycle), following-error monitoring,
//!   the error code and the Emergency of a fault;
//! * [`objects`]: the profile's objects once, with the core's
//!   `od::build` constructors (0x6007..0x6502 and the fixed PDO mappings
//!   0x1600/0x1A00), and the `const` concatenation a device composes its
//!   dictionary with;
//! * [`od_axis`]: [`Cia402Axis`], a [`Drive`] bound to a dictionary by
//!   object indices: what a device's or a twin's `Application::tick`
//!   calls;
//! * [`safety`]: the safety rules of docs/SAFETY.md (S1-S3, S5) as a checker
//!   of observations, for property tests of drives.
//!
//! Layers: `od_axis` → `objects`, `safety` → `drive` → `axis`, `mode`,
//! `state`
//!
//! ```
//! use ecat_cia402::state::{PowerState, control};
//! use ecat_cia402::{Drive, Link, Parameters, Setpoints};
//!
//! let mut drive = Drive::default();
//! let link = Link { outputs_valid: true, watchdog_armed: true, dc_cycle_ns: None };
//! let p = Parameters::default();
//! let mut cycle = |drive: &mut Drive, cw: u16, t_ms: u64| {
//!     let sp = Setpoints { controlword: cw, ..Setpoints::default() };
//!     drive.step(&sp, link, None, &p, t_ms * 1_000_000)
//! };
//! cycle(&mut drive, 0, 0);
//! assert_eq!(drive.state(), PowerState::SwitchOnDisabled);
//! cycle(&mut drive, control::SHUTDOWN, 1);
//! cycle(&mut drive, control::SWITCH_ON, 2);
//! let report = cycle(&mut drive, control::ENABLE_OPERATION, 3);
//! assert_eq!(drive.state(), PowerState::OperationEnabled);
//! assert_eq!(report.inputs.statusword & 0x6F, 0x27);
//! assert!(report.power_stage.enabled);
//! ```
#![cfg_attr(not(any(test, feature = "std")), no_std)]
#![forbid(unsafe_code)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod axis;
pub mod drive;
pub mod mode;
pub mod objects;
pub mod od_axis;
pub mod safety;
pub mod state;

pub use axis::{Axis, AxisModel, Demand, Limits, ModelParams, Motion};
pub use drive::{Drive, Inputs, Link, Parameters, PowerStage, Report, Setpoints};
pub use mode::Mode;
pub use od_axis::{AxisError, Cia402Axis};
pub use state::PowerState;
