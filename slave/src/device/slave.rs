//! The firmware loop of any device: [`Slave`] polls the ESC through the PDI
//! ([`Esc`]), runs the AL state machine on AL control events, serves the
//! mailbox, moves process data between the SyncManagers and the object
//! dictionary, and runs the [`Application`].

use crate::al::{self, AlState, AlStatus, AlStatusCode, TransitionChecks};
use crate::coe::ObjectAccess;
use crate::coe::emergency::Emergencies;
use crate::esc::registers::{self as reg, sm as smr};
use crate::esc::{Esc, EscError};
use crate::firmware::{self, DeviceIdentity, ImageStore};
use crate::foe::FoeContext;
use crate::mailbox::MailboxServer;
use crate::od::complete;
use crate::od::modules::{CONFIGURED_MODULES, ObjectView};
use crate::od::store::{ObjectStore, Od};
use crate::od::types::PdoMapping;
use crate::od::{Dictionary, ValueStorage};
use crate::pdo::{Direction, MAX_IMAGE, ProcessImage};
use crate::wire::coe::SdoAbortCode;

use super::application::{Application, Download, StateChange, Tick, Write};
use super::description::{DeviceDescription, MAX_MAILBOX, MemoryLayout};

/// SM control bytes the core expects (and the SII advertises): SM0
/// mailbox out, SM1 mailbox in, SM2 outputs (watchdog), SM3 inputs.
pub const SM_CONTROL: [u8; 4] = [0x26, 0x22, 0x64, 0x20];

/// Longest time between two full passes of the firmware loop (every
/// register checked, events or not): the backstop for what no AL event
/// reports, such as a PDI that fails on a register the events never lead
/// to.
pub const FULL_PASS_NS: u64 = 100_000_000;

pub use crate::limits::DC_MIN_CYCLE_NS;

/// How the firmware synchronises its process data (ETG.1020 sync types,
/// as 0x1C32:01 names them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SyncMode {
    /// Free run (or SM-synchronous: the outputs are taken when SM2's event
    /// comes); no DC SYNC signal.
    #[default]
    FreeRun,
    /// DC-synchronous on SYNC0: the master activated cyclic operation with
    /// SYNC0 (0x0981 = 0x03) before SAFE-OP.
    DcSync0,
}

/// Most changes one SDO download hands to the application.
const MAX_CHANGES: usize = complete::MAX_ENTRIES;

/// A device's firmware on an ESC reached through the PDI.
pub struct Slave<E: Esc, A: Application> {
    esc: E,
    app: A,
    layout: MemoryLayout,
    store: ObjectStore<A::Values>,
    al: AlStatus,
    outputs: ProcessImage,
    inputs: ProcessImage,
    mailbox: MailboxServer,
    /// A response waiting for SM1 to become free.
    pending: Option<(usize, [u8; MAX_MAILBOX])>,
    /// The last response written to SM1, for the repeat service.
    last_sent: Option<(usize, [u8; MAX_MAILBOX])>,
    emergencies: Emergencies,
    emergencies_enabled: bool,
    pdi_failures: u32,
    now_ns: u64,
    /// Time of the last full pass (every register checked).
    full_pass_ns: Option<u64>,
    /// The master read SM1 and there was nothing more to send: its read
    /// event stays in 0x0220 (only a PDI write acknowledges it) and is
    /// ignored until the firmware writes SM1 again.
    sm1_quiet: bool,
    /// Responses written to SM1 so far (wrapping).
    sm1_writes: u32,
    /// Synchronisation chosen at PRE-OP→SAFE-OP.
    sync_mode: SyncMode,
    /// SYNC0 events the firmware saw (wrapping).
    sync0_events: u32,
    /// DC mode: SYNC0 cycles in which no new outputs had arrived (SM2
    /// event) since the previous SYNC0: ETG.1020's "SM event missed".
    sm_event_missed: u32,
    /// An SM2 event came since the last SYNC0.
    outputs_since_sync0: bool,
    /// DC mode: outputs received (length, bytes), applied at the next
    /// SYNC0.
    dc_outputs: Option<(usize, [u8; MAX_IMAGE])>,
    /// The bootloader started no image ([`Slave::set_no_valid_firmware`]).
    no_valid_firmware: bool,
    /// Outputs from SM2 were applied to the dictionary since OP was
    /// entered: the master is exchanging cyclic outputs.
    outputs_applied: bool,
    /// The SM watchdog's time 0x0420 was not 0 at the last full pass in OP.
    sm_watchdog_armed: bool,
}

impl<E: Esc, A: Application> core::fmt::Debug for Slave<E, A> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Slave")
            .field("device", &self.app.description().names.type_name)
            .field("al", &self.al)
            .finish_non_exhaustive()
    }
}

fn read_sm<E: Esc>(esc: &mut E, n: u8) -> Result<(u16, u16, u8, bool), EscError> {
    let base = reg::sm(n).ok_or(EscError::OutOfRange { addr: 0, len: 0 })?;
    let mut b = [0u8; 8];
    esc.read(base, &mut b)?;
    Ok((
        u16::from_le_bytes([b[0], b[1]]),
        u16::from_le_bytes([b[2], b[3]]),
        b[4],
        b[6] & smr::ACTIVATE_ENABLE != 0,
    ))
}

/// SM0/SM1 are enabled with the given start and length and mailbox
/// control bits; `Err` when the PDI cannot read them.
fn mailbox_matches<E: Esc>(
    esc: &mut E,
    out: (u16, u16),
    inp: (u16, u16),
) -> Result<bool, EscError> {
    let sm0 = read_sm(esc, 0)?;
    let sm1 = read_sm(esc, 1)?;
    Ok(sm0 == (out.0, out.1, sm0.2, true)
        && sm0.2 & 0x0F == SM_CONTROL[0] & 0x0F
        && sm1 == (inp.0, inp.1, sm1.2, true)
        && sm1.2 & 0x0F == SM_CONTROL[1] & 0x0F)
}

/// What the checks need to see while the AL state machine runs.
struct Checks<'a, E: Esc, A: Application> {
    esc: &'a mut E,
    app: &'a mut A,
    od: &'a mut Od,
    layout: MemoryLayout,
    images: Option<(ProcessImage, ProcessImage)>,
    now_ns: u64,
    /// A PDI access that failed during a check: the check refuses with
    /// 0x0001 and the firmware goes to its fail-safe state (never "assume
    /// all is well").
    pdi_error: Option<EscError>,
    /// The synchronisation the PRE-OP→SAFE-OP check found.
    sync_mode: Option<SyncMode>,
    /// Only the bootloader runs: INIT→PRE-OP is refused (0x0014).
    no_valid_firmware: bool,
}

impl<E: Esc, A: Application> Checks<'_, E, A> {
    /// Records a failed PDI access; the refusal code of a check that could
    /// not read the ESC.
    fn pdi_failed(&mut self, e: EscError) -> AlStatusCode {
        self.pdi_error.get_or_insert(e);
        AlStatusCode::Unspecified
    }
}

impl<E: Esc, A: Application> Checks<'_, E, A> {
    /// The DC SYNC configuration the master left in the activation
    /// register (0x0981) and the SYNC0 cycle time (0x09A0): no SYNC means
    /// free run; cyclic operation with SYNC0 means DC mode if the cycle
    /// fits. A SYNC signal without cyclic operation, or SYNC1 (not
    /// supported yet), is refused with 0x0030; a SYNC0 cycle of 0 (single
    /// shot) or shorter than [`DC_MIN_CYCLE_NS`] with 0x0035 (ETG.1000.6
    /// AL status codes; ETG.1020 §22).
    fn check_dc(&mut self) -> Result<SyncMode, AlStatusCode> {
        let act = self
            .esc
            .read_u8(reg::DC_ACTIVATION)
            .map_err(|e| self.pdi_failed(e))?;
        // A sync mode the master wrote into 0x1C32:01 must match the
        // registers; a free-run/SM value with SYNC0 active is overruled
        // by the registers (as the SSC derives the mode from 0x0981).
        let requested = self.od.get(0x1C32, 1);
        if act & 0x06 == 0 {
            if requested == Some(crate::od::build::sync_mode::DC_SYNC0) {
                return Err(AlStatusCode::InvalidDcSyncConfig);
            }
            return Ok(SyncMode::FreeRun);
        }
        if act & 0x01 == 0 || act & 0x04 != 0 {
            return Err(AlStatusCode::InvalidDcSyncConfig);
        }
        // The firmware runs on SYNC0 through the AL event request; an SII
        // that does not map SYNC0 there (0x0151 bit 3) leaves it deaf.
        let sync_map = self
            .esc
            .read_u8(reg::PDI_CONFIG + 1)
            .map_err(|e| self.pdi_failed(e))?;
        if sync_map & 0x08 == 0 {
            return Err(AlStatusCode::InvalidDcSyncConfig);
        }
        let cycle = self
            .esc
            .read_u32(reg::DC_SYNC0_CYCLE_TIME)
            .map_err(|e| self.pdi_failed(e))?;
        if cycle < DC_MIN_CYCLE_NS {
            return Err(AlStatusCode::InvalidDcCycleTime);
        }
        Ok(SyncMode::DcSync0)
    }
}

impl<E: Esc, A: Application> TransitionChecks for Checks<'_, E, A> {
    fn check_mailbox(&mut self) -> Result<(), AlStatusCode> {
        if self.no_valid_firmware {
            return Err(AlStatusCode::NoValidFirmware);
        }
        match mailbox_matches(self.esc, self.layout.mbx_out, self.layout.mbx_in) {
            Ok(true) => Ok(()),
            Ok(false) => Err(AlStatusCode::InvalidMailboxPreOp),
            Err(e) => Err(self.pdi_failed(e)),
        }
    }

    fn check_boot_mailbox(&mut self) -> Result<(), AlStatusCode> {
        if !self.layout.has_boot() {
            return Err(AlStatusCode::BootNotSupported);
        }
        match mailbox_matches(self.esc, self.layout.boot_out, self.layout.boot_in) {
            Ok(true) => Ok(()),
            Ok(false) => Err(AlStatusCode::InvalidMailboxBoot),
            Err(e) => Err(self.pdi_failed(e)),
        }
    }

    fn check_process_data(&mut self) -> Result<(), AlStatusCode> {
        let desc = self.app.description();
        if let Some(m) = desc.modules {
            m.check_configured(self.od)?;
            // Every assigned PDO must belong to a slot that holds a module.
            let view = object_view(desc, self.od);
            for (assign, code) in [
                (0x1C12u16, AlStatusCode::InvalidOutputConfig),
                (0x1C13u16, AlStatusCode::InvalidInputConfig),
            ] {
                let n = self.od.get(assign, 0).unwrap_or(0).clamp(0, 255) as u8;
                for k in 1..=n {
                    let pdo = self.od.get(assign, k).unwrap_or(0) as u16;
                    if !view.visible(pdo) {
                        return Err(code);
                    }
                }
            }
        }
        let pd = &desc.process_data;
        let outputs = ProcessImage::build(self.od, Direction::Outputs, pd)
            .map_err(|_| AlStatusCode::InvalidOutputConfig)?;
        let inputs = ProcessImage::build(self.od, Direction::Inputs, pd)
            .map_err(|_| AlStatusCode::InvalidInputConfig)?;
        // Both directions must come from one PDO set.
        if outputs.sets() & inputs.sets() == 0 {
            return Err(AlStatusCode::InvalidInputConfig);
        }
        let sm2 = read_sm(self.esc, 2).map_err(|e| self.pdi_failed(e))?;
        let sm3 = read_sm(self.esc, 3).map_err(|e| self.pdi_failed(e))?;
        // With no PDO in a direction its SM is unused: disabled, or
        // enabled with length 0 as SOEM leaves it (an ESC does not activate
        // a SyncManager of length 0; SOES accepts it too).
        let out_ok = if outputs.byte_len() == 0 {
            !sm2.3 || sm2.1 == 0
        } else {
            sm2.3
                && sm2.0 == self.layout.pd_out
                && usize::from(sm2.1) == outputs.byte_len()
                && sm2.2 & 0x0F == SM_CONTROL[2] & 0x0F
        };
        if !out_ok {
            return Err(AlStatusCode::InvalidOutputConfig);
        }
        let in_ok = if inputs.byte_len() == 0 {
            !sm3.3 || sm3.1 == 0
        } else {
            sm3.3
                && sm3.0 == self.layout.pd_in
                && usize::from(sm3.1) == inputs.byte_len()
                && sm3.2 & 0x0F == SM_CONTROL[3] & 0x0F
        };
        if !in_ok {
            return Err(AlStatusCode::InvalidInputConfig);
        }
        self.sync_mode = Some(self.check_dc()?);
        self.images = Some((outputs, inputs));
        Ok(())
    }

    fn check_outputs(&mut self) -> Result<(), AlStatusCode> {
        // SAFE-OP -> OP needs valid outputs: an expired SyncManager watchdog
        // is re-armed only by fresh outputs from the master.
        let time = self
            .esc
            .read_u16(reg::WATCHDOG_TIME_PD)
            .map_err(|e| self.pdi_failed(e))?;
        let status = self
            .esc
            .read_u16(reg::WATCHDOG_STATUS_PD)
            .map_err(|e| self.pdi_failed(e))?;
        if time != 0 && status & 1 == 0 {
            return Err(AlStatusCode::SmWatchdog);
        }
        Ok(())
    }

    fn accept(&mut self, from: AlState, to: AlState) -> Result<(), AlStatusCode> {
        let (rx_sets, tx_sets) = self
            .images
            .as_ref()
            .map_or((u32::MAX, u32::MAX), |(o, i)| (o.sets(), i.sets()));
        let change = StateChange {
            from,
            to,
            rx_sets,
            tx_sets,
            now_ns: self.now_ns,
        };
        self.app.state_change(self.od, &change)
    }
}

impl<E: Esc, A: Application> Slave<E, A> {
    /// The device's description.
    pub fn description(&self) -> &'static DeviceDescription {
        self.app.description()
    }

    /// The firmware in its power-on state on `esc`, running `app`.
    ///
    /// The application's `Values` must hold at least its dictionary's
    /// entry count ([`Application::Values`]).
    ///
    /// # Panics
    ///
    /// When `Values` is too small: a programming error, stopped in every
    /// build (for a static description the comparison is a constant and
    /// costs nothing in the firmware).
    pub fn new(esc: E, mut app: A) -> Self {
        let desc = app.description();
        assert!(
            <A::Values as ValueStorage>::LEN >= desc.dictionary.entry_count(),
            "Application::Values must hold the dictionary's entry count"
        );
        let mut store = ObjectStore::<A::Values>::new(desc.dictionary);
        app.power_on(A::Values::view_mut(&mut store));
        Slave {
            esc,
            app,
            layout: desc.layout(),
            store,
            al: AlStatus::INIT,
            outputs: ProcessImage::default(),
            inputs: ProcessImage::default(),
            mailbox: MailboxServer::new(),
            pending: None,
            last_sent: None,
            emergencies: Emergencies::default(),
            emergencies_enabled: true,
            pdi_failures: 0,
            now_ns: 0,
            full_pass_ns: None,
            sm1_quiet: false,
            sm1_writes: 0,
            sync_mode: SyncMode::FreeRun,
            sync0_events: 0,
            sm_event_missed: 0,
            outputs_since_sync0: false,
            dc_outputs: None,
            no_valid_firmware: false,
            outputs_applied: false,
            sm_watchdog_armed: false,
        }
    }

    /// The firmware restarts (a power cycle, seen from the firmware): every
    /// volatile state is lost, the application forgets its own
    /// ([`Application::power_cycle`]) and powers on again with the
    /// dictionary at its defaults. The ESC is not touched.
    pub fn restart(&mut self) {
        self.app.power_cycle();
        let mut store = ObjectStore::<A::Values>::new(self.app.description().dictionary);
        self.app.power_on(A::Values::view_mut(&mut store));
        self.store = store;
        self.al = AlStatus::INIT;
        self.outputs = ProcessImage::default();
        self.inputs = ProcessImage::default();
        self.mailbox = MailboxServer::new();
        self.pending = None;
        self.last_sent = None;
        self.emergencies = Emergencies::default();
        self.pdi_failures = 0;
        self.now_ns = 0;
        self.full_pass_ns = None;
        self.sm1_quiet = false;
        self.sync_mode = SyncMode::FreeRun;
        self.sync0_events = 0;
        self.sm_event_missed = 0;
        self.outputs_since_sync0 = false;
        self.dc_outputs = None;
        self.outputs_applied = false;
        self.sm_watchdog_armed = false;
    }

    /// Uses another memory layout (standard mailbox size); it must match
    /// the SII the ESC serves.
    pub fn set_layout(&mut self, layout: MemoryLayout) {
        self.layout = layout;
    }

    /// The memory layout (mailboxes, process data buffers).
    pub fn layout(&self) -> &MemoryLayout {
        &self.layout
    }

    /// The ESC.
    pub fn esc(&self) -> &E {
        &self.esc
    }

    /// The ESC, mutably.
    pub fn esc_mut(&mut self) -> &mut E {
        &mut self.esc
    }

    /// The application.
    pub fn app(&self) -> &A {
        &self.app
    }

    /// The application, mutably.
    pub fn app_mut(&mut self) -> &mut A {
        &mut self.app
    }

    /// The live object dictionary.
    pub fn od(&self) -> &Od {
        A::Values::view(&self.store)
    }

    /// The live object dictionary, mutably.
    pub fn od_mut(&mut self) -> &mut Od {
        A::Values::view_mut(&mut self.store)
    }

    /// The current AL status.
    pub fn al_status(&self) -> AlStatus {
        self.al
    }

    /// The application and the dictionary together (a test or a board
    /// support package acting on both).
    pub fn app_and_od(&mut self) -> (&mut A, &mut Od) {
        (&mut self.app, A::Values::view_mut(&mut self.store))
    }

    /// Consumes the firmware, returning the ESC and the application (a
    /// power cycle reuses both).
    pub fn into_parts(self) -> (E, A) {
        (self.esc, self.app)
    }

    /// The running firmware version (0x100A, if the device has it).
    pub fn firmware_version(&self) -> heapless::String<32> {
        let mut v = heapless::String::new();
        let od = self.od();
        if let Some((flat, _)) = od.dictionary().find_entry(0x100A, 0) {
            let _ = v.push_str(od.string(flat).unwrap_or(""));
        }
        v
    }

    /// Sets 0x100A to the version the bootloader started.
    pub fn set_firmware_version(&mut self, version: &str) -> bool {
        self.od_mut().set_string(0x100A, 0, version)
    }

    /// Whether the bootloader started no image
    /// ([`BootDecision::slot`](crate::firmware::BootDecision::slot)
    /// `None`): then only the bootloader runs, INIT and BOOT are accepted
    /// (a firmware download stays possible) and INIT→PRE-OP is refused
    /// with AL status 0x0014 "no valid firmware". Kept across
    /// [`Slave::restart`]; whoever runs the bootloader sets it at every
    /// power-on.
    pub fn set_no_valid_firmware(&mut self, none: bool) {
        self.no_valid_firmware = none;
    }

    /// Whether only the bootloader runs ([`Slave::set_no_valid_firmware`]).
    pub fn no_valid_firmware(&self) -> bool {
        self.no_valid_firmware
    }

    /// Runs the firmware once at time `now_ns`: AL control, mailbox,
    /// process data, application. Returns an error only if the PDI itself
    /// fails.
    pub fn poll(&mut self, now_ns: u64) -> Result<(), EscError> {
        self.poll_with(now_ns, None)
    }

    /// [`Slave::poll`] with the firmware image store: FoE writes go there
    /// (in BOOT) and BOOT→INIT marks a downloaded image pending for the
    /// bootloader. Without a store FoE answers "unsupported protocol".
    ///
    /// A failed PDI access is never taken as "all is well": the firmware
    /// goes to its fail-safe state (outputs off, OP left for SAFE-OP, AL
    /// error 0x0001, Emergency 0x5000) and the error is returned.
    pub fn poll_with<'s>(
        &mut self,
        now_ns: u64,
        images: Option<&mut (dyn ImageStore + 's)>,
    ) -> Result<(), EscError> {
        match self.run_once(now_ns, images) {
            Ok(()) => Ok(()),
            Err(e) => {
                self.pdi_failure(e);
                Err(e)
            }
        }
    }

    /// The fail-safe reaction to a PDI failure `e`: outputs to their safe
    /// state and hardware outputs off at once, OP left for SAFE-OP, the
    /// error indication set with AL status code 0x0001 (unspecified error;
    /// ETG.1000.6 has no code for "the firmware cannot reach its ESC") and
    /// an Emergency 0x5000 (device hardware) queued. Writing the AL status
    /// is attempted; when the PDI is still down the master sees the
    /// silence of the SM watchdog and the PDI watchdog instead.
    fn pdi_failure(&mut self, e: EscError) {
        self.safe_outputs();
        self.pdi_failures = self.pdi_failures.saturating_add(1);
        let state = if self.al.state == AlState::Op {
            AlState::SafeOp
        } else {
            self.al.state
        };
        let first = !(self.al.error && self.al.code == AlStatusCode::Unspecified);
        self.al = AlStatus {
            state,
            error: true,
            code: AlStatusCode::Unspecified,
        };
        if first && self.emergencies_enabled && state != AlState::Init && state != AlState::Boot {
            self.emergencies.pdi_failure(e);
        }
        let _ = self.esc.write_u16(reg::AL_STATUS_CODE, self.al.code.code());
        let _ = self.esc.write_u16(reg::AL_STATUS, self.al.register());
    }

    /// How many polls ended in a PDI failure since power-on.
    pub fn pdi_failures(&self) -> u32 {
        self.pdi_failures
    }

    fn run_once<'s>(
        &mut self,
        now_ns: u64,
        mut images: Option<&mut (dyn ImageStore + 's)>,
    ) -> Result<(), EscError> {
        self.now_ns = now_ns;
        // Event-driven, as the SSC: the AL event request register first,
        // and only what it flags. Without an event, nothing queued to send
        // and no full pass due, a pass is one PDI read (plus the inputs in
        // SAFE-OP/OP) and the application's tick.
        let events = self.esc.al_event()?;
        let sm1 = reg::al_event_sm(1);
        let relevant = if self.sm1_quiet {
            events & !sm1
        } else {
            events
        };
        let mailbox_state = matches!(
            self.al.state,
            AlState::PreOp | AlState::SafeOp | AlState::Op | AlState::Boot
        );
        let queued = self.pending.is_some()
            || (mailbox_state && self.emergencies_enabled && !self.emergencies.is_empty());
        let due = self
            .full_pass_ns
            .is_none_or(|t| now_ns.saturating_sub(t) >= FULL_PASS_NS);
        // The process-data SyncManagers' events need only the process
        // data exchanged.
        let process_data = reg::al_event_sm(2) | reg::al_event_sm(3) | reg::AL_EVENT_SYNC0;
        if relevant & !process_data == 0 && !queued && !due {
            return self.light_pass(events);
        }
        self.full_pass_ns = Some(now_ns);
        let sm1_writes = self.sm1_writes;
        if events & reg::AL_EVENT_AL_CONTROL != 0 {
            let control = self.esc.read_u16(reg::AL_CONTROL)?;
            let before = self.al.state;
            self.al_control(control)?;
            if before == AlState::Boot && self.al.state == AlState::Init {
                // "Change to INIT, the bootloader copies the new software":
                // the downloaded image becomes pending. A store that cannot
                // record it is reported, not ignored: INIT with the error
                // indication and 0x0007 "firmware update not successful,
                // old firmware still running".
                if let Some(st) = images.as_deref_mut()
                    && firmware::commit_pending(st).is_err()
                {
                    self.al = AlStatus {
                        state: AlState::Init,
                        error: true,
                        code: AlStatusCode::FirmwareUpdateFailed,
                    };
                    self.esc
                        .write_u16(reg::AL_STATUS_CODE, self.al.code.code())?;
                    self.esc.write_u16(reg::AL_STATUS, self.al.register())?;
                }
            }
        }
        self.supervise(events)?;
        if matches!(
            self.al.state,
            AlState::PreOp | AlState::SafeOp | AlState::Op | AlState::Boot
        ) {
            self.serve_mailbox(images)?;
        }
        let pd = matches!(self.al.state, AlState::SafeOp | AlState::Op);
        if pd {
            self.read_outputs(events)?;
        }
        self.sync0(events)?;
        self.run_app();
        if pd {
            self.write_inputs()?;
        }
        // SM1's read event with nothing written in answer: ignore it until
        // the next response.
        self.sm1_quiet = events & sm1 != 0 && self.sm1_writes == sm1_writes;
        Ok(())
    }

    /// A pass with nothing flagged but process data: in SAFE-OP/OP the
    /// outputs the master wrote (SM2 event), the application's tick, the
    /// inputs; else the tick alone.
    fn light_pass(&mut self, events: u32) -> Result<(), EscError> {
        let pd = matches!(self.al.state, AlState::SafeOp | AlState::Op);
        if pd {
            self.read_outputs(events)?;
        }
        self.sync0(events)?;
        self.run_app();
        if pd {
            self.write_inputs()?;
        }
        Ok(())
    }

    /// The application's tick, then the error register.
    fn run_app(&mut self) {
        let state = self.al.state;
        {
            let op = state == AlState::Op;
            let mut tick = Tick {
                od: A::Values::view_mut(&mut self.store),
                now_ns: self.now_ns,
                outputs_valid: op && self.outputs_applied,
                sm_watchdog_armed: op && self.sm_watchdog_armed,
                state,
                emergencies: &mut self.emergencies,
            };
            self.app.tick(&mut tick);
        }
        self.update_error_register();
    }

    /// Changes state on the device's own account (error indication set).
    fn local_error(&mut self, state: AlState, code: AlStatusCode) -> Result<(), EscError> {
        if self.al.state == AlState::Op && state != AlState::Op {
            self.safe_outputs();
        }
        if matches!(state, AlState::Init | AlState::PreOp) {
            self.reset_sync();
        }
        if matches!(state, AlState::Init) {
            self.pending = None;
            self.last_sent = None;
            self.mailbox = MailboxServer::new();
        }
        self.al = AlStatus {
            state,
            error: true,
            code,
        };
        self.esc.write_u16(reg::AL_STATUS_CODE, code.code())?;
        self.esc.write_u16(reg::AL_STATUS, self.al.register())
    }

    /// Watches what can end a state without a request: the SyncManager
    /// watchdog in OP (-> SAFE-OP, 0x001B), a changed mailbox SM above INIT
    /// (-> INIT, 0x0016 / 0x0015 in BOOT) and a changed process-data SM in
    /// SAFE-OP/OP (-> PRE-OP, 0x001D / 0x001E).
    fn supervise(&mut self, events: u32) -> Result<(), EscError> {
        if events & reg::AL_EVENT_WATCHDOG_PD != 0 && self.al.state != AlState::Op {
            // Acknowledge (the check below reads it in OP).
            self.esc.read_u16(reg::WATCHDOG_STATUS_PD)?;
        }
        if self.al.state == AlState::Op {
            let time = self.esc.read_u16(reg::WATCHDOG_TIME_PD)?;
            let status = self.esc.read_u16(reg::WATCHDOG_STATUS_PD)?;
            self.sm_watchdog_armed = time != 0;
            if time != 0 && status & 1 == 0 {
                return self.local_error(AlState::SafeOp, AlStatusCode::SmWatchdog);
            }
        }
        if self.al.state != AlState::Init {
            let boot = self.al.state == AlState::Boot;
            let (out, inp) = self.mailbox_layout();
            if !mailbox_matches(&mut self.esc, out, inp)? {
                let code = if boot {
                    AlStatusCode::InvalidMailboxBoot
                } else {
                    AlStatusCode::InvalidMailboxPreOp
                };
                return self.local_error(AlState::Init, code);
            }
        }
        if self.al.state == AlState::Op && self.sync_mode == SyncMode::DcSync0 {
            // The master switched SYNC0 off under a DC-synchronous
            // firmware in OP: its outputs have no time base any more
            // (in SAFE-OP the master may do so on its way down).
            let act = self.esc.read_u8(reg::DC_ACTIVATION)?;
            if act & 0x03 != 0x03 && !self.al.error {
                return self.local_error(AlState::SafeOp, AlStatusCode::FatalSyncError);
            }
        }
        if matches!(self.al.state, AlState::SafeOp | AlState::Op) {
            let sm2 = read_sm(&mut self.esc, 2)?;
            let sm3 = read_sm(&mut self.esc, 3)?;
            let out_ok = self.outputs.byte_len() == 0
                || (sm2.3
                    && sm2.0 == self.layout.pd_out
                    && usize::from(sm2.1) == self.outputs.byte_len()
                    && sm2.2 & 0x0F == SM_CONTROL[2] & 0x0F);
            let in_ok = self.inputs.byte_len() == 0
                || (sm3.3
                    && sm3.0 == self.layout.pd_in
                    && usize::from(sm3.1) == self.inputs.byte_len()
                    && sm3.2 & 0x0F == SM_CONTROL[3] & 0x0F);
            if !out_ok {
                return self.local_error(AlState::PreOp, AlStatusCode::InvalidOutputConfig);
            }
            if !in_ok {
                return self.local_error(AlState::PreOp, AlStatusCode::InvalidInputConfig);
            }
        }
        Ok(())
    }

    /// Sends CoE Emergency messages (default on). Masters that cannot take
    /// an unsolicited emergency in the mailbox (ethercrab 0.7.1 fails when
    /// one arrives instead of an SDO response) may switch them off; 0x1001
    /// is kept either way.
    pub fn set_emergencies(&mut self, enabled: bool) {
        self.emergencies_enabled = enabled;
    }

    /// Emergencies waiting for the master.
    pub fn emergencies_waiting(&self) -> usize {
        self.emergencies.len()
    }

    /// The core's part of the error register after the application's tick:
    /// the SM watchdog as a communication error, 0x0000 when every fault is
    /// gone; writes 0x1001 (when the device has it).
    fn update_error_register(&mut self) {
        let comm = self.al.error && self.al.code == AlStatusCode::SmWatchdog;
        let reg = self.emergencies.update(comm, self.al.code.code());
        self.od_mut().set(0x1001, 0, i64::from(reg));
        // No mailbox in INIT (and BOOT has only the bootstrap mailbox for
        // FoE): what is queued there would reach the next master session
        // as a stale message (SOEM's config_map then fails). Like the SSC
        // and SOES, INIT empties the queue; 0x1001 stays consistent.
        if !self.emergencies_enabled || matches!(self.al.state, AlState::Init | AlState::Boot) {
            self.emergencies.clear();
        }
    }

    /// RUN and ERR LED patterns (ETG.1300); `pdi_watchdog_expired` comes
    /// from the ESC.
    pub fn led_patterns(
        &self,
        pdi_watchdog_expired: bool,
    ) -> (crate::led::LedPattern, crate::led::LedPattern) {
        crate::led::patterns(&self.al, pdi_watchdog_expired)
    }

    fn al_control(&mut self, control: u16) -> Result<(), EscError> {
        let before = self.al;
        let mut checks = Checks {
            esc: &mut self.esc,
            app: &mut self.app,
            od: A::Values::view_mut(&mut self.store),
            layout: self.layout,
            images: None,
            now_ns: self.now_ns,
            pdi_error: None,
            sync_mode: None,
            no_valid_firmware: self.no_valid_firmware,
        };
        let after = al::transition(before, control, &mut checks);
        if let Some(e) = checks.pdi_error {
            // The check could not read the ESC: fail safe (see poll_with).
            return Err(e);
        }
        if after.error && !before.error && before.state == AlState::PreOp && (control & 0x0F) == 4 {
            self.emergencies.transition_refused(after.code.code());
        }
        if let Some((o, i)) = checks.images.take() {
            self.outputs = o;
            self.inputs = i;
        }
        // The synchronisation the check found counts only if SAFE-OP was
        // reached (the application may still have refused it).
        if let Some(m) = checks.sync_mode
            && after.state == AlState::SafeOp
            && before.state == AlState::PreOp
        {
            self.sync_mode = m;
            self.outputs_since_sync0 = true;
            self.sm_event_missed = 0;
            self.dc_outputs = None;
            let cycle = if m == SyncMode::DcSync0 {
                i64::from(self.esc.read_u32(reg::DC_SYNC0_CYCLE_TIME)?)
            } else {
                0
            };
            self.publish_sync(cycle);
        }
        if matches!(after.state, AlState::Init | AlState::PreOp | AlState::Boot)
            && before.state != after.state
        {
            self.reset_sync();
        }
        if after.state != AlState::Op && before.state == AlState::Op {
            self.safe_outputs();
        }
        if after.state == AlState::Op && before.state != AlState::Op {
            // Outputs count from the first SM2 write in OP on (what the
            // master sent in SAFE-OP was never applied).
            self.outputs_applied = false;
        }
        if matches!(after.state, AlState::Init | AlState::Boot) && before.state != after.state {
            self.pending = None;
            self.last_sent = None;
            self.mailbox = MailboxServer::new();
        }
        self.al = after;
        self.esc.write_u16(reg::AL_STATUS_CODE, after.code.code())?;
        self.esc.write_u16(reg::AL_STATUS, after.register())?;
        Ok(())
    }

    /// Outputs to their safe state: every RxPDO-mappable entry back to
    /// zero, then the application switches its hardware outputs off.
    fn safe_outputs(&mut self) {
        // Outputs held for the next SYNC0 are as stale as the rest.
        self.dc_outputs = None;
        self.outputs_applied = false;
        let od = A::Values::view_mut(&mut self.store);
        let dict = od.dictionary();
        for (flat, _, e) in dict.entries() {
            if e.pdo == PdoMapping::Rx {
                od.set_value(flat, 0);
            }
        }
        self.app.outputs_safe(od);
    }

    fn mailbox_layout(&self) -> ((u16, u16), (u16, u16)) {
        if self.al.state == AlState::Boot {
            (self.layout.boot_out, self.layout.boot_in)
        } else {
            (self.layout.mbx_out, self.layout.mbx_in)
        }
    }

    /// Writes the waiting response into SM1 if SM1 is free. The whole
    /// buffer is written so that the ESC sees its last byte and marks the
    /// mailbox full.
    fn deliver_pending(&mut self) -> Result<(), EscError> {
        if self.pending.is_none() || self.sm_full(1)? {
            return Ok(());
        }
        let (_, inp) = self.mailbox_layout();
        if let Some((len, buf)) = self.pending.take() {
            let n = usize::from(inp.1).min(MAX_MAILBOX);
            let mut frame = [0u8; MAX_MAILBOX];
            if let (Some(dst), Some(src)) = (frame.get_mut(..len), buf.get(..len)) {
                dst.copy_from_slice(src);
            }
            if let Some(f) = frame.get(..n) {
                self.esc.write(inp.0, f)?;
                self.sm1_writes = self.sm1_writes.wrapping_add(1);
            }
            self.last_sent = Some((len, frame));
        }
        Ok(())
    }

    /// Mailbox repeat (ETG.1000.4 SyncManager repeat): when the master
    /// toggles the repeat request bit of SM1 (activate byte bit 1), the
    /// last response is put into SM1 again and the repeat acknowledge bit
    /// (PDI control bit 1) is toggled to match.
    fn serve_repeat(&mut self) -> Result<(), EscError> {
        let base = reg::sm(1).ok_or(EscError::OutOfRange { addr: 0, len: 0 })?;
        let request = self.esc.read_u8(base + smr::ACTIVATE)? & smr::ACTIVATE_REPEAT;
        let pdi = self.esc.read_u8(base + smr::PDI_CONTROL)?;
        if request == pdi & smr::PDI_REPEAT_ACK {
            return Ok(());
        }
        if !self.sm_full(1)?
            && let Some((_, frame)) = &self.last_sent
        {
            let (_, inp) = self.mailbox_layout();
            let n = usize::from(inp.1).min(MAX_MAILBOX);
            let copy = *frame;
            if let Some(f) = copy.get(..n) {
                self.esc.write(inp.0, f)?;
                self.sm1_writes = self.sm1_writes.wrapping_add(1);
            }
        }
        self.esc.write(
            base + smr::PDI_CONTROL,
            &[(pdi & !smr::PDI_REPEAT_ACK) | request],
        )
    }

    fn serve_mailbox<'s>(
        &mut self,
        images: Option<&mut (dyn ImageStore + 's)>,
    ) -> Result<(), EscError> {
        self.serve_repeat()?;
        self.deliver_pending()?;
        // One request at a time: a new request waits in SM0 until the
        // previous response has left.
        if self.pending.is_some() {
            return Ok(());
        }
        let view = object_view(self.app.description(), A::Values::view(&self.store));
        if !self.sm_full(0)? {
            // Nothing new: continue a response that spans several mailboxes.
            let (_, inp) = self.mailbox_layout();
            let max = usize::from(inp.1).min(MAX_MAILBOX);
            let mut response = [0u8; MAX_MAILBOX];
            let mut produced = response
                .get_mut(..max)
                .and_then(|r| self.mailbox.next_pending(r, view));
            if produced.is_none() && self.emergencies_enabled && !self.emergencies.is_empty() {
                produced = response.get_mut(..max).and_then(|r| {
                    let body = r.get_mut(crate::wire::mailbox::HEADER_LEN..)?;
                    let n = self.emergencies.pop_into(body)?;
                    self.mailbox.frame_coe(r, n)
                });
            }
            if let Some(len) = produced {
                self.pending = Some((len, response));
                self.deliver_pending()?;
            }
            return Ok(());
        }
        let (out, inp) = self.mailbox_layout();
        let mut request = [0u8; MAX_MAILBOX];
        let n = usize::from(out.1).min(MAX_MAILBOX);
        let Some(req) = request.get_mut(..n) else {
            return Ok(());
        };
        self.esc.read(out.0, req)?;
        let mut response = [0u8; MAX_MAILBOX];
        let max = usize::from(inp.1).min(MAX_MAILBOX);
        let state = self.al.state;
        let version = self.firmware_version();
        let desc = self.app.description();
        let id = &desc.identity;
        let foe_offered = desc.mailbox.foe;
        let mut ctx = images.filter(|_| foe_offered).map(|store| FoeContext {
            store,
            identity: DeviceIdentity {
                vendor_id: id.vendor_id,
                product_code: id.product_code,
                revision: id.revision,
            },
            version: version.as_str(),
            security: desc.mailbox.foe_security,
            in_boot: state == AlState::Boot,
            busy: false,
        });
        let now_ns = self.now_ns;
        let produced = match response.get_mut(..max) {
            // Disjoint field borrows: no copy of the mailbox server.
            Some(resp) => self.mailbox.handle(
                req,
                resp,
                &mut OdAccess {
                    app: &mut self.app,
                    od: A::Values::view_mut(&mut self.store),
                    state,
                    now_ns,
                },
                ctx.as_mut(),
            ),
            None => None,
        };
        if let Some(len) = produced {
            self.pending = Some((len, response));
            self.deliver_pending()?;
        }
        Ok(())
    }

    fn sm_full(&mut self, n: u8) -> Result<bool, EscError> {
        let base = reg::sm(n).ok_or(EscError::OutOfRange { addr: 0, len: 0 })?;
        Ok(self.esc.read_u8(base + smr::STATUS)? & smr::STATUS_MAILBOX_FULL != 0)
    }

    /// A SYNC0 event: acknowledged by reading 0x098E (one PDI read);
    /// counted, and in DC mode a cycle without new outputs since the last
    /// SYNC0 counts as an SM event missed.
    fn sync0(&mut self, events: u32) -> Result<(), EscError> {
        if events & reg::AL_EVENT_SYNC0 == 0 {
            return Ok(());
        }
        self.esc.read_u8(reg::DC_SYNC0_STATUS)?;
        self.sync0_events = self.sync0_events.wrapping_add(1);
        // DC-synchronous outputs take effect at SYNC0, not when they
        // arrive (ETG.1020: outputs valid at the SYNC0 event).
        if let Some((n, buf)) = self.dc_outputs.take()
            && self.al.state == AlState::Op
            && let Some(b) = buf.get(..n)
        {
            let od = A::Values::view_mut(&mut self.store);
            self.outputs.unpack(od, b);
            self.outputs_applied = true;
        }
        if self.sync_mode == SyncMode::DcSync0 && self.al.state == AlState::Op {
            // `read_outputs` ran first in this pass: outputs that came
            // with this SYNC0 count for it.
            if !self.outputs_since_sync0 {
                self.sm_event_missed = self.sm_event_missed.wrapping_add(1);
                let n = i64::from(self.sm_event_missed as u16);
                let od = A::Values::view_mut(&mut self.store);
                od.set(0x1C32, 11, n);
                od.set(0x1C33, 11, n);
            }
            self.outputs_since_sync0 = false;
        }
        Ok(())
    }

    /// Back to free run (PRE-OP, INIT, BOOT): no held outputs, and
    /// 0x1C32/0x1C33 say so (a stale "DC" there would read as the next
    /// master's request).
    fn reset_sync(&mut self) {
        self.sync_mode = SyncMode::FreeRun;
        self.dc_outputs = None;
        self.publish_sync(0);
    }

    /// 0x1C32/0x1C33 (if the device has them) show the sync mode and
    /// cycle time chosen and the SM event missed counter.
    fn publish_sync(&mut self, cycle: i64) {
        use crate::od::build::sync_mode;
        let mode = match self.sync_mode {
            SyncMode::FreeRun => sync_mode::FREE_RUN,
            SyncMode::DcSync0 => sync_mode::DC_SYNC0,
        };
        let od = A::Values::view_mut(&mut self.store);
        for index in [0x1C32, 0x1C33] {
            od.set(index, 1, mode);
            od.set(index, 2, cycle);
            od.set(index, 10, cycle);
            od.set(index, 11, i64::from(self.sm_event_missed as u16));
        }
    }

    /// The synchronisation chosen at the last PRE-OP→SAFE-OP.
    pub fn sync_mode(&self) -> SyncMode {
        self.sync_mode
    }

    /// SYNC0 events the firmware has seen (wrapping).
    pub fn sync0_events(&self) -> u32 {
        self.sync0_events
    }

    /// DC mode: SYNC0 cycles in OP that came without new outputs since
    /// the previous one (ETG.1020 "SM event missed").
    pub fn sm_event_missed(&self) -> u32 {
        self.sm_event_missed
    }

    fn read_outputs(&mut self, events: u32) -> Result<(), EscError> {
        if events & reg::al_event_sm(2) != 0 {
            self.outputs_since_sync0 = true;
        }
        let mut buf = [0u8; MAX_IMAGE];
        if events & reg::al_event_sm(2) != 0 && self.outputs.byte_len() > 0 {
            let n = self.outputs.byte_len();
            if let Some(b) = buf.get_mut(..n) {
                match self.esc.read(self.layout.pd_out, b) {
                    // SM2 turned into a mailbox by the master: nothing to
                    // take; the supervision answers it with 0x001D.
                    Err(EscError::SmBusy { .. }) => return Ok(()),
                    r => r?,
                }
            }
            if self.sync_mode == SyncMode::DcSync0 {
                // Held until the next SYNC0.
                self.dc_outputs = Some((n, buf));
            } else if self.al.state == AlState::Op
                && let Some(b) = buf.get(..n)
            {
                let od = A::Values::view_mut(&mut self.store);
                self.outputs.unpack(od, b);
                self.outputs_applied = true;
            }
        }
        Ok(())
    }

    fn write_inputs(&mut self) -> Result<(), EscError> {
        let n = self.inputs.byte_len();
        if n > 0 {
            let mut inb = [0u8; MAX_IMAGE];
            if let Some(b) = inb.get_mut(..n) {
                self.inputs.pack(A::Values::view(&self.store), b);
                match self.esc.write(self.layout.pd_in, b) {
                    // The master made SM3 a mailbox it has not emptied:
                    // its configuration, not the PDI, is at fault; the
                    // supervision answers it with 0x001E.
                    Err(EscError::SmBusy { .. }) => {}
                    r => r?,
                }
            }
        }
        Ok(())
    }
}

/// The object dictionary as the CoE server sees it: the store, the core's
/// rules for the PDO assignment, and the application's hooks.
struct OdAccess<'a, A: Application> {
    app: &'a mut A,
    od: &'a mut Od,
    state: AlState,
    now_ns: u64,
}

/// What SDO access and SDO Information show of a device's dictionary (a
/// modular device hides its empty slots).
fn object_view(desc: &'static DeviceDescription, od: &Od) -> ObjectView {
    let dict = desc.dictionary;
    match desc.modules {
        Some(m) => ObjectView::modular(dict, m, od),
        None => ObjectView::all(dict),
    }
}

impl<A: Application> OdAccess<'_, A> {
    /// A configured module list (0xF030) holds idents of module types the
    /// device knows (0 for an empty slot), at most one per slot.
    fn check_module_list(&self, index: u16, changes: &[(u8, i64)]) -> Result<(), SdoAbortCode> {
        let Some(m) = self.app.description().modules else {
            return Ok(());
        };
        if index != CONFIGURED_MODULES {
            return Ok(());
        }
        for (s, v) in changes {
            if *s == 0 {
                if *v > i64::from(m.slots) {
                    return Err(SdoAbortCode::ValueTooHigh);
                }
            } else if *v != 0 && m.module(*v as u32).is_none() {
                return Err(SdoAbortCode::ValueRange);
            }
        }
        Ok(())
    }

    /// The core's rules for 0x1C12/0x1C13: only PDOs of the assignment's
    /// direction that exist, no more than its capacity, all of one PDO set.
    fn check_assignment(&self, index: u16, changes: &[(u8, i64)]) -> Result<(), SdoAbortCode> {
        let dir = match index {
            0x1C12 => Direction::Outputs,
            0x1C13 => Direction::Inputs,
            _ => return Ok(()),
        };
        let new = |s: u8| -> Option<i64> {
            changes
                .iter()
                .find(|(x, _)| *x == s)
                .map(|(_, v)| *v)
                .or_else(|| self.od.get(index, s))
        };
        let dict = self.od.dictionary();
        let cap = dict.find(index).map_or(0, |(_, o)| o.max_sub());
        let count = new(0).unwrap_or(0);
        if count > i64::from(cap) {
            return Err(SdoAbortCode::ValueTooHigh);
        }
        let (lo, hi) = dir.pdo_range();
        // Every written PDO must be one of the direction's mapping objects.
        for (s, v) in changes.iter().filter(|(s, _)| *s != 0) {
            let pdo = *v as u16;
            if pdo < lo || pdo > hi || self.view().find(pdo).is_none() {
                let _ = s;
                return Err(SdoAbortCode::ValueRange);
            }
        }
        // The assigned PDOs (1..=count) must share a PDO set.
        let pd = &self.app.description().process_data;
        if !pd.sets.is_empty() {
            let mut sets = u32::MAX;
            for s in 1..=count.clamp(0, 255) as u8 {
                let pdo = new(s).unwrap_or(0) as u16;
                let m = crate::pdo::sets_of(pd, pdo);
                if m == 0 {
                    continue;
                }
                if sets & m == 0 {
                    return Err(SdoAbortCode::ParameterIncompatible);
                }
                sets &= m;
            }
        }
        Ok(())
    }

    fn hand_over(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        changes: &[(u8, i64)],
    ) -> Result<(), SdoAbortCode> {
        self.check_assignment(index, changes)?;
        self.check_module_list(index, changes)?;
        let d = Download {
            index,
            sub,
            complete_access,
            state: self.state,
            now_ns: self.now_ns,
            changes,
        };
        match self.app.sdo_download(self.od, &d)? {
            Write::Store => d.apply(self.od),
            Write::Done => {}
        }
        Ok(())
    }
}

impl<A: Application> ObjectAccess for OdAccess<'_, A> {
    fn dictionary(&self) -> &'static Dictionary {
        self.app.description().dictionary
    }

    fn view(&self) -> ObjectView {
        object_view(self.app.description(), self.od)
    }

    fn sdo_upload(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        out: &mut [u8],
    ) -> Result<usize, SdoAbortCode> {
        if !self.view().visible(index) {
            return Err(SdoAbortCode::ObjectNotFound);
        }
        self.app.sdo_upload(self.od, index, sub)?;
        if complete_access {
            return complete::upload(self.od, index, sub, out);
        }
        self.od.upload(index, sub, out)
    }

    fn sdo_download(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        if !self.view().visible(index) {
            return Err(SdoAbortCode::ObjectNotFound);
        }
        if complete_access {
            let flat_changes = complete::check_download(self.od, index, sub, data, self.state)?;
            let dict = self.od.dictionary();
            let mut changes: heapless::Vec<(u8, i64), MAX_CHANGES> = heapless::Vec::new();
            for (flat, v) in flat_changes {
                let s = dict.entry_at(flat).map_or(0, |e| e.sub);
                changes
                    .push((s, v))
                    .map_err(|_| SdoAbortCode::ObjectTooLong)?;
            }
            return self.hand_over(index, sub, true, &changes);
        }
        let (_, entry) = self.od.lookup(index, sub)?;
        let value = Od::check(entry, data, self.state)?;
        self.hand_over(index, sub, false, &[(sub, value)])
    }
}
