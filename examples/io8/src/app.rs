//! What the IO8 does: the [`Application`] the core runs.
//!
//! * `tick`: outputs from 0x7000 to the board while the outputs are valid
//!   (OP), off otherwise; inputs from the board through the input filter
//!   into 0x6000.
//! * `outputs_safe` / `pdi_watchdog_expired`: outputs off at once.
//! * `power_on`: the saved parameters back into the dictionary.
//! * `sdo_download`: 0x1010:01 = "save" stores the parameters.

use ecat_slave::device::{Application, DeviceDescription, Download, Tick, Write};
use ecat_slave::hal::{MemNv, NvStorage};
use ecat_slave::od::Od;
use ecat_slave::params::{self, STORAGE_SIZE};
use ecat_slave::wire::coe::SdoAbortCode;

use crate::board::{Board, SimBoard};
use crate::description::{
    DEVICE, ENTRIES, INPUT_FILTER, INPUTS, OUTPUTS, SAVE_SIGNATURE, SETTINGS, STORE_PARAMETERS,
};

/// A debounce filter for eight inputs: a change of an input is taken once
/// the input has kept its new level for the filter time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Debounce {
    /// The filtered levels.
    stable: u8,
    /// The levels at the last update.
    raw: u8,
    /// When each input last changed level, ns.
    since: [u64; 8],
}

impl Debounce {
    /// Every input low (the power-on state of 0x6000).
    pub const fn new() -> Self {
        Debounce {
            stable: 0,
            raw: 0,
            since: [0; 8],
        }
    }

    /// Takes the levels `raw` read at `now_ns`; returns the filtered levels.
    /// An input whose level differs from its filtered level and has not
    /// changed for `filter_ns` takes the new level.
    pub fn update(&mut self, raw: u8, now_ns: u64, filter_ns: u64) -> u8 {
        let changed = raw ^ self.raw;
        self.raw = raw;
        for (bit, since) in self.since.iter_mut().enumerate() {
            let mask = 1u8 << bit;
            if changed & mask != 0 {
                *since = now_ns;
            }
            let differs = (raw ^ self.stable) & mask != 0;
            if differs && now_ns.saturating_sub(*since) >= filter_ns {
                self.stable = (self.stable & !mask) | (raw & mask);
            }
        }
        self.stable
    }

    /// The filtered levels.
    pub const fn levels(&self) -> u8 {
        self.stable
    }
}

/// The outputs 0x7000:01..08 as bits (bit n: output n + 1 on).
pub fn outputs_of(od: &Od) -> u8 {
    (0..8u8).fold(0, |bits, n| match od.get(OUTPUTS, n + 1) {
        Some(v) if v != 0 => bits | 1 << n,
        _ => bits,
    })
}

/// Writes input bits (bit n: input n + 1) into 0x6000:01..08.
pub fn write_inputs(od: &mut Od, bits: u8) {
    for n in 0..8u8 {
        od.set(INPUTS, n + 1, i64::from(bits >> n & 1));
    }
}

/// The input filter time 0x8000:01 in ns.
pub fn filter_ns(od: &Od) -> u64 {
    let ms = od.get(SETTINGS, INPUT_FILTER).unwrap_or(0);
    u64::try_from(ms).unwrap_or(0).saturating_mul(1_000_000)
}

/// The IO8 on board `B`, keeping its parameters in `N`.
#[derive(Debug, Clone)]
pub struct Io8<B: Board = SimBoard, N: NvStorage = MemNv<STORAGE_SIZE>> {
    board: B,
    nv: N,
    filter: Debounce,
}

impl Default for Io8<SimBoard> {
    fn default() -> Self {
        Io8::new(SimBoard::new(), MemNv::new())
    }
}

impl<B: Board, N: NvStorage> Io8<B, N> {
    /// The IO8 on `board` with its parameters in `nv` (at least
    /// [`STORAGE_SIZE`] bytes; blank storage means the defaults).
    pub fn new(board: B, nv: N) -> Self {
        Io8 {
            board,
            nv,
            filter: Debounce::new(),
        }
    }

    /// The board.
    pub fn board(&self) -> &B {
        &self.board
    }

    /// The board, mutably (a test sets the simulated inputs here).
    pub fn board_mut(&mut self) -> &mut B {
        &mut self.board
    }

    /// The parameter storage.
    pub fn storage(&self) -> &N {
        &self.nv
    }

    /// The parameter storage, mutably.
    pub fn storage_mut(&mut self) -> &mut N {
        &mut self.nv
    }

    /// The input filter.
    pub fn filter(&self) -> &Debounce {
        &self.filter
    }
}

impl<B: Board, N: NvStorage> Application for Io8<B, N> {
    fn description(&self) -> &'static DeviceDescription {
        &DEVICE
    }
    type Values = [i64; ENTRIES];

    fn power_on(&mut self, od: &mut Od) {
        // Blank or corrupt storage leaves the defaults.
        let _ = params::load(od, &self.nv);
    }

    fn sdo_download(&mut self, od: &mut Od, d: &Download<'_>) -> Result<Write, SdoAbortCode> {
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
        let outputs = if t.outputs_valid { outputs_of(t.od) } else { 0 };
        self.board.set_outputs(outputs);
        let raw = self.board.inputs();
        let inputs = self.filter.update(raw, t.now_ns, filter_ns(t.od));
        write_inputs(t.od, inputs);
    }

    fn outputs_safe(&mut self, _od: &mut Od) {
        self.board.set_outputs(0);
    }

    fn pdi_watchdog_expired(&mut self) {
        self.board.set_outputs(0);
    }

    fn power_cycle(&mut self) {
        self.board.set_outputs(0);
        self.filter = Debounce::new();
    }

    fn nv(&self) -> Option<&dyn NvStorage> {
        Some(&self.nv)
    }

    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        Some(&mut self.nv)
    }
}
