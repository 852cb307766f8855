//! The firmware loop of any device: [`Slave`] polls the ESC through the PDI
//! ([`Esc`]), runs the AL state machine on AL control events, serves the
//! mailbox, moves process data between the SyncManagers and the object
//! dictionary, and runs the [`Application`].
//!
//! One file per job: the loop itself and the device's accessors here, AL
//! transitions and their checks (`transition.rs`), the mailbox
//! (`mailbox.rs`), process data and the safe outputs (`process_data.rs`),
//! SYNC0 (`sync.rs`) and the SDO adapter between CoE and the dictionary
//! (`od_access.rs`).

mod mailbox;
mod od_access;
mod process_data;
mod sync;
mod transition;

use od_access::{OdAccess, object_view};
use transition::{mailbox_matches, process_data_sms};

use crate::al::{self, AlState, AlStatus, AlStatusCode, TransitionChecks};
use crate::coe::ObjectAccess;
use crate::coe::emergency::Emergencies;
use crate::esc::registers::{self as reg, sm as smr};
use crate::esc::{Esc, EscError};
use crate::firmware::{self, DeviceIdentity, ImageStore};
use crate::foe::FoeContext;
use crate::mailbox::{Handled, MailboxServer};
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

/// A device's firmware on an ESC reached through the PDI.
///
/// The last four parameters size its buffers (a firmware sizes them for
/// its device; the defaults are the host's, large enough for any device
/// the core accepts):
///
/// * `MBX`: bytes of a mailbox message: the largest of the device's
///   standard and bootstrap mailboxes ([`MailboxConfig`](super::MailboxConfig));
///   two such buffers live in the object (the response waiting for SM1 and
///   the last one sent, for the repeat service) and two on the stack while
///   a request is served.
/// * `SDO`: the SDO transfer buffer: the largest object (or complete-access
///   image) a normal or segmented transfer carries; bigger ones are
///   refused with 0x05040005.
/// * `PDO`: the most entries (padding included) one direction's PDOs may
///   map; an assignment with more is refused at PRE-OP→SAFE-OP (0x001D /
///   0x001E).
/// * `IMG`: the largest process image of one direction in bytes; a bigger
///   one is refused at PRE-OP→SAFE-OP the same way.
///
/// [`Slave::new`] stops with a panic when the description needs more
/// (a mailbox larger than `MBX`, a default assignment beyond `PDO`/`IMG`):
/// a programming error of the firmware, as a too small value storage is.
pub struct Slave<
    E: Esc,
    A: Application,
    const MBX: usize = MAX_MAILBOX,
    const SDO: usize = { crate::coe::sdo::SDO_BUFFER },
    const PDO: usize = { crate::pdo::MAX_MAPPED },
    const IMG: usize = MAX_IMAGE,
> {
    esc: E,
    app: A,
    layout: MemoryLayout,
    store: ObjectStore<A::Values>,
    al: AlStatus,
    outputs: ProcessImage<PDO>,
    inputs: ProcessImage<PDO>,
    mailbox: MailboxServer<SDO>,
    /// The length of a response in `sent` waiting for SM1 to become free
    /// (only after a failed PDI write: a response is built when SM1 is
    /// empty and written in the same pass).
    pending: Option<usize>,
    /// The request read from SM0.
    request: [u8; MBX],
    /// The length of the last response written to SM1 (in `sent`), for
    /// the repeat service.
    last_sent: Option<usize>,
    /// The response: built here once the master has read the previous
    /// one, written to SM1, and kept for the repeat service.
    sent: [u8; MBX],
    emergencies: Emergencies,
    emergencies_enabled: bool,
    pdi_failures: u32,
    /// The AL status registers could not be written in a PDI failure:
    /// written again at the first pass that reaches the ESC, so the master
    /// never reads a state the firmware has left.
    status_unwritten: bool,
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
    dc_outputs: Option<(usize, [u8; IMG])>,
    /// The bootloader started no image ([`Slave::set_no_valid_firmware`]).
    no_valid_firmware: bool,
    /// Outputs from SM2 were applied to the dictionary since OP was
    /// entered: the master is exchanging cyclic outputs.
    outputs_applied: bool,
    /// The SM watchdog's time 0x0420 was not 0 at the last full pass in OP.
    sm_watchdog_armed: bool,
}

impl<E: Esc, A: Application, const MBX: usize, const SDO: usize, const PDO: usize, const IMG: usize>
    core::fmt::Debug for Slave<E, A, MBX, SDO, PDO, IMG>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Slave")
            .field("device", &self.app.description().names.type_name)
            .field("al", &self.al)
            .finish_non_exhaustive()
    }
}

impl<E: Esc, A: Application> Slave<E, A> {
    /// The firmware in its power-on state on `esc`, running `app`, with
    /// buffers large enough for any device ([`Slave::with_buffers`] sizes
    /// them for one device).
    ///
    /// # Panics
    ///
    /// When the application's `Values` cannot hold its dictionary's entry
    /// count ([`Application::Values`]): a programming error.
    pub fn new(esc: E, app: A) -> Self {
        Self::with_buffers(esc, app)
    }
}

impl<E: Esc, A: Application, const MBX: usize, const SDO: usize, const PDO: usize, const IMG: usize>
    Slave<E, A, MBX, SDO, PDO, IMG>
{
    /// The device's description.
    pub fn description(&self) -> &'static DeviceDescription {
        self.app.description()
    }

    /// The firmware in its power-on state on `esc`, running `app`, with
    /// the buffer sizes of its type (see [`Slave`]; [`Slave::new`] is the
    /// same with the host's defaults).
    ///
    /// The application's `Values` must hold at least its dictionary's
    /// entry count ([`Application::Values`]).
    ///
    /// # Panics
    ///
    /// When `Values` or a buffer is too small for the description: a
    /// programming error, stopped in every build (for a static description
    /// the comparisons are constants and cost nothing in the firmware).
    pub fn with_buffers(esc: E, app: A) -> Self {
        let mut s = Self::unpowered(esc, app);
        s.power_on();
        s
    }

    /// [`Slave::with_buffers`] written into `slot` (a `static`'s
    /// `MaybeUninit`, say) and powered on there: the firmware object is
    /// never built on the stack and copied, so a firmware's start-up needs
    /// little more stack than one poll (a `Slave` is kilobytes).
    ///
    /// # Panics
    ///
    /// As [`Slave::with_buffers`].
    pub fn init_in(slot: &mut core::mem::MaybeUninit<Self>, esc: E, app: A) -> &mut Self {
        let s = slot.write(Self::unpowered(esc, app));
        s.power_on();
        s
    }

    /// Every field at its power-on value but the dictionary, whose values
    /// are 0 until [`Slave::power_on`]. Mostly zeros and no address taken,
    /// so the compiler can build it where it is written.
    #[inline(always)]
    fn unpowered(esc: E, app: A) -> Self {
        let desc = app.description();
        Slave {
            esc,
            app,
            layout: desc.layout(),
            store: ObjectStore::zeroed(desc.dictionary),
            al: AlStatus::INIT,
            outputs: ProcessImage::default(),
            inputs: ProcessImage::default(),
            mailbox: MailboxServer::new(),
            pending: None,
            request: [0; MBX],
            last_sent: None,
            sent: [0; MBX],
            emergencies: Emergencies::default(),
            emergencies_enabled: true,
            pdi_failures: 0,
            status_unwritten: false,
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

    /// Checks the buffers against the description, sets the dictionary to
    /// its defaults and powers the application on, in place.
    fn power_on(&mut self) {
        let desc = self.app.description();
        assert!(
            <A::Values as ValueStorage>::LEN >= desc.dictionary.entry_count(),
            "Application::Values must hold the dictionary's entry count"
        );
        let mbx = desc.mailbox;
        assert!(
            usize::from(mbx.size) <= MBX && mbx.boot_size.is_none_or(|b| usize::from(b) <= MBX),
            "Slave's MBX must hold the device's standard and bootstrap mailboxes"
        );
        self.store.od_mut().load_defaults();
        for dir in [Direction::Outputs, Direction::Inputs] {
            // Built in the Slave's own image, cleared again below.
            let fits = match self
                .outputs
                .rebuild(self.store.od(), dir, &desc.process_data)
            {
                Ok(()) => self.outputs.byte_len() <= IMG,
                Err(e) => e != crate::pdo::PdoError::TooLarge,
            };
            assert!(
                fits,
                "Slave's PDO and IMG must hold the device's default process image"
            );
        }
        self.outputs.clear();
        self.app.power_on(self.store.od_mut());
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
        self.mailbox.reset();
        self.pending = None;
        self.last_sent = None;
        self.emergencies = Emergencies::default();
        self.pdi_failures = 0;
        self.status_unwritten = false;
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
    ///
    /// # Panics
    ///
    /// If a mailbox of `layout` is longer than `MBX` (the firmware's
    /// buffers): a loader of untrusted files checks the lengths first, as
    /// the twins' does.
    pub fn set_layout(&mut self, layout: MemoryLayout) {
        let lens = [
            layout.mbx_out.1,
            layout.mbx_in.1,
            layout.boot_out.1,
            layout.boot_in.1,
        ];
        assert!(
            lens.iter().all(|&n| usize::from(n) <= MBX),
            "Slave's MBX must hold the layout's mailboxes"
        );
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

    /// Runs the firmware once at time `now_ns`: AL control, supervision,
    /// the outputs, the mailbox, the application, the inputs. Returns an
    /// error only if the PDI itself fails.
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
    pub(super) fn pdi_failure(&mut self, e: EscError) {
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
        // Both writes are tried even when the first fails, unlike
        // `write_al_status`, which stops at the first error: the PDI just
        // failed, and the status (SAFE-OP + ERR) is what the master must
        // see if either write gets through. A lost write is retried at the
        // next pass that reaches the ESC.
        let code = self.esc.write_u16(reg::AL_STATUS_CODE, self.al.code.code());
        let status = self.esc.write_u16(reg::AL_STATUS, self.al.register());
        if code.is_err() || status.is_err() {
            self.status_unwritten = true;
        }
    }

    /// How many polls ended in a PDI failure since power-on.
    pub fn pdi_failures(&self) -> u32 {
        self.pdi_failures
    }

    pub(super) fn run_once<'s>(
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
        if self.status_unwritten {
            // The ESC answers again after a PDI failure whose AL status
            // write was lost: the master must see SAFE-OP + ERR 0x0001 now,
            // not at its next AL control request.
            self.write_al_status()?;
            self.status_unwritten = false;
        }
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
                    self.write_al_status()?;
                }
            }
        }
        self.supervise(events)?;
        // The outputs before the mailbox: a master that wrote outputs and
        // then asks for them by SDO gets the values it wrote even when
        // both reach the firmware in one pass (the frame with the SDO
        // request can arrive before the firmware ran after the process
        // data frame; the SSC's SM2 interrupt has the same order).
        let pd = matches!(self.al.state, AlState::SafeOp | AlState::Op);
        if pd {
            self.read_outputs(events)?;
        }
        if matches!(
            self.al.state,
            AlState::PreOp | AlState::SafeOp | AlState::Op | AlState::Boot
        ) {
            self.serve_mailbox(images)?;
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
    pub(super) fn light_pass(&mut self, events: u32) -> Result<(), EscError> {
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
    pub(super) fn run_app(&mut self) {
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
    pub(super) fn local_error(
        &mut self,
        state: AlState,
        code: AlStatusCode,
    ) -> Result<(), EscError> {
        if self.al.state == AlState::Op && state != AlState::Op {
            self.safe_outputs();
        }
        if matches!(state, AlState::Init | AlState::PreOp) {
            self.reset_sync();
        }
        if matches!(state, AlState::Init) {
            self.pending = None;
            self.last_sent = None;
            self.mailbox.reset();
        }
        self.al = AlStatus {
            state,
            error: true,
            code,
        };
        self.write_al_status()
    }

    /// Writes `self.al` into the AL status code and AL status registers,
    /// the code first (a master that sees the error flag reads its code).
    /// One copy for the four places that report a state (each wrote both
    /// registers itself).
    #[inline(never)]
    pub(super) fn write_al_status(&mut self) -> Result<(), EscError> {
        self.esc
            .write_u16(reg::AL_STATUS_CODE, self.al.code.code())?;
        self.esc.write_u16(reg::AL_STATUS, self.al.register())
    }

    /// Watches what can end a state without a request: the SyncManager
    /// watchdog in OP (-> SAFE-OP, 0x001B), a changed mailbox SM above INIT
    /// (-> INIT, 0x0016 / 0x0015 in BOOT) and a changed process-data SM in
    /// SAFE-OP/OP (-> PRE-OP, 0x001D / 0x001E).
    pub(super) fn supervise(&mut self, events: u32) -> Result<(), EscError> {
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
            // The rule of the PRE-OP -> SAFE-OP check
            // (`Checks::check_process_data`): a changed process-data SM
            // ends the state; enabling an unused one with a length too.
            let (outputs, inputs) = (self.outputs.byte_len(), self.inputs.byte_len());
            if let Some(code) = process_data_sms(&mut self.esc, &self.layout, outputs, inputs)? {
                return self.local_error(AlState::PreOp, code);
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
    pub(super) fn update_error_register(&mut self) {
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
}
