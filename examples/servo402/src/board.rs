//! The servo402's hardware, as the application sees it: an axis (its
//! power stage with the current, velocity and position loops, the motor
//! and the encoder) that the CiA 402 profile moves, with the power stage's
//! enable line and fault input.
//!
//! A real board implements [`Board`] on its gate driver and encoder: the
//! profile's [`Axis::step`] becomes the set points of the current loop
//! (usually in an FPGA or a motor-control timer), [`Board::fault`] the
//! over-current, over-temperature and STO inputs. [`SimBoard`] is the
//! deterministic [`AxisModel`] with a recorded enable line and an
//! injectable fault, for tests and software slaves.

use ecat_cia402::{Axis, AxisModel, Demand, Limits, Motion, PowerStage};

/// The drive's hardware abstraction.
pub trait Board: Axis {
    /// Switches the power stage (its enable line) and sets its torque:
    /// what the drive decided until the next tick. Called every tick; the
    /// power stage must carry no current when `stage.enabled` is false.
    fn set_power_stage(&mut self, stage: PowerStage);

    /// A fault the power stage reports now (its CiA 301 error code:
    /// 0x2310 over-current, 0x4310 over-temperature, 0x5441 STO ...).
    fn fault(&mut self) -> Option<u16>;
}

/// A simulated board: the [`AxisModel`], the enable line as the firmware
/// drove it, and a fault a test injects.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SimBoard {
    /// The axis.
    pub model: AxisModel,
    /// The power stage as the firmware last set it.
    pub stage: PowerStage,
    /// How many times the firmware set the power stage.
    pub stage_writes: u32,
    /// The fault the power stage reports (`None`: healthy).
    pub fault_code: Option<u16>,
}

impl SimBoard {
    /// A healthy board, the axis at 0 and at rest, the power stage off.
    pub const fn new() -> Self {
        SimBoard {
            model: AxisModel::new(ecat_cia402::ModelParams::DEFAULT),
            stage: PowerStage {
                enabled: false,
                torque: 0,
            },
            stage_writes: 0,
            fault_code: None,
        }
    }
}

impl Axis for SimBoard {
    fn step(&mut self, demand: Demand, limits: Limits, dt_ns: u64) -> Motion {
        self.model.step(demand, limits, dt_ns)
    }

    fn motion(&self) -> Motion {
        self.model.motion()
    }

    fn set_position(&mut self, position_m: i64) {
        self.model.set_position(position_m);
    }
}

impl Board for SimBoard {
    fn set_power_stage(&mut self, stage: PowerStage) {
        self.stage = stage;
        self.stage_writes = self.stage_writes.saturating_add(1);
    }

    fn fault(&mut self) -> Option<u16> {
        self.fault_code
    }
}
