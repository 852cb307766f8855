//! What the servo402 does: the [`Application`] the core runs.
//!
//! * `tick`: one step of the CiA 402 drive ([`Cia402Axis::tick`]) with
//!   the core's `outputs_valid` and `sm_watchdog_armed`, the board's fault
//!   input and the time; the power stage follows what the drive decided.
//! * `outputs_safe`: nothing at once. The core zeroed the set points; the
//!   drive sees `outputs_valid` false in the same poll and runs its
//!   reaction (6007h: brake on the quick stop ramp, then Fault with the
//!   power stage off). Cutting the power here would let the axis coast
//!   instead of braking (a stop category 0 where 1 is asked for).
//! * `pdi_watchdog_expired`: the firmware stalled; the ESC cut the power
//!   stage, and the drive goes to Fault 0x6010 so nothing drives when it
//!   runs again.
//! * `sdo_download`: the profile's checks (modes, homing methods, the
//!   safety parameters only with the power stage off), 0x1010:01 =
//!   "save" stores the parameters.
//! * `power_on`: the saved parameters back into the dictionary.

use ecat_cia402::Cia402Axis;
use ecat_slave::device::{Application, DeviceDescription, Download, Tick, Write};
use ecat_slave::hal::{MemNv, NvStorage};
use ecat_slave::od::Od;
use ecat_slave::params::{self, STORAGE_SIZE};
use ecat_slave::wire::coe::SdoAbortCode;

use crate::board::{Board, SimBoard};
use crate::description::{DEVICE, ENTRIES, POWER_STAGE_FAULT, SAVE_SIGNATURE, STORE_PARAMETERS};

/// The servo402 on board `B`, keeping its parameters in `N`.
#[derive(Debug, Clone)]
pub struct Servo402<B: Board = SimBoard, N: NvStorage = MemNv<STORAGE_SIZE>> {
    axis: Cia402Axis<B>,
    nv: N,
}

impl Default for Servo402<SimBoard> {
    fn default() -> Self {
        Servo402::new(SimBoard::new(), MemNv::new())
    }
}

impl<B: Board, N: NvStorage> Servo402<B, N> {
    /// The servo402 on `board` with its parameters in `nv` (at least
    /// [`STORAGE_SIZE`] bytes; blank storage means the defaults).
    pub fn new(board: B, nv: N) -> Self {
        Servo402 {
            axis: Cia402Axis::axis0(board),
            nv,
        }
    }

    /// The CiA 402 axis (the drive and its state).
    pub fn axis(&self) -> &Cia402Axis<B> {
        &self.axis
    }

    /// The board.
    pub fn board(&self) -> &B {
        self.axis.drive().axis()
    }

    /// The board, mutably (a test injects a fault here).
    pub fn board_mut(&mut self) -> &mut B {
        self.axis.drive_mut().axis_mut()
    }

    /// The parameter storage.
    pub fn storage(&self) -> &N {
        &self.nv
    }
}

impl<B: Board, N: NvStorage> Application for Servo402<B, N> {
    fn description(&self) -> &'static DeviceDescription {
        &DEVICE
    }
    type Values = [i64; ENTRIES];

    fn power_on(&mut self, od: &mut Od) {
        // Blank or corrupt storage leaves the defaults.
        let _ = params::load(od, &self.nv);
    }

    fn sdo_download(&mut self, od: &mut Od, d: &Download<'_>) -> Result<Write, SdoAbortCode> {
        self.axis.check_download(d)?;
        if d.index != STORE_PARAMETERS {
            return Ok(Write::Store);
        }
        // CiA 301: only the signature "save" stores; 0x1010:01 keeps
        // reading 1 ("saves on command").
        match d.value(1) {
            Some(SAVE_SIGNATURE) => {
                params::save(od, &mut self.nv).map_err(|_| SdoAbortCode::HardwareError)?;
                Ok(Write::Done)
            }
            Some(_) => Err(SdoAbortCode::TransferFailed),
            None => Ok(Write::Done),
        }
    }

    fn tick(&mut self, t: &mut Tick<'_>) {
        let fault = self.board_mut().fault();
        t.od.set(POWER_STAGE_FAULT, 0, i64::from(fault.unwrap_or(0)));
        let report = self.axis.tick(t, fault);
        self.board_mut().set_power_stage(report.power_stage);
    }

    fn pdi_watchdog_expired(&mut self) {
        self.board_mut().set_power_stage(Default::default());
        let _ = self.axis.drive_mut().power_cut();
    }

    fn power_cycle(&mut self) {
        self.board_mut().set_power_stage(Default::default());
        self.axis.reset();
    }

    fn nv(&self) -> Option<&dyn NvStorage> {
        Some(&self.nv)
    }

    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        Some(&mut self.nv)
    }
}
