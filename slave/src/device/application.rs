//! The application trait: the behaviour a device adds to the core.
//!
//! Everything EtherCAT-generic is done by the core: the AL state machine
//! with its SyncManager checks, mailbox, CoE (SDO, complete access, SDO
//! Information, Emergency), FoE, the PDO engine, watchdogs, LEDs. A device
//! implements [`Application`] for what only it knows; every method has a
//! default that does nothing, so the smallest device is a description and
//! an empty `impl`.
//!
//! Call order in one [`Slave::poll`](super::Slave::poll):
//! AL control (the core's checks, then [`Application::state_change`]) →
//! mailbox (SDO writes pass [`Application::sdo_download`]) → outputs from
//! SM2 into the dictionary (OP only) → [`Application::tick`] → inputs from
//! the dictionary into SM3.

use crate::al::{AlState, AlStatusCode};
use crate::coe::emergency::Emergencies;
use crate::hal::NvStorage;
use crate::od::ValueStorage;
use crate::od::complete::{CompleteChanges, CompleteIter};
use crate::od::store::Od;
use crate::wire::coe::SdoAbortCode;

use super::DeviceDescription;

/// Values an SDO download would store, after the core's checks (access in
/// this state, type, length, range, enumeration, PDO assignment rules).
#[derive(Debug, Clone, Copy)]
pub struct Download<'a> {
    /// The object.
    pub index: u16,
    /// The subindex written (a complete access starts at 0 or 1).
    pub sub: u8,
    /// Written with complete access.
    pub complete_access: bool,
    /// The AL state the write arrives in.
    pub state: AlState,
    /// Time of the poll, ns.
    pub now_ns: u64,
    /// `(subindex, value)` of every entry the download changes or writes.
    pub changes: Changes<'a>,
}

impl Download<'_> {
    /// The value the download writes into `sub`, if it writes it.
    pub fn value(&self, sub: u8) -> Option<i64> {
        self.changes.value(sub)
    }

    /// Stores every change into `od` (what [`Write::Store`] makes the core
    /// do; an application that must act after the values are in place
    /// calls it itself and answers [`Write::Done`]).
    pub fn apply(&self, od: &mut Od) {
        for (sub, v) in self.changes.iter() {
            od.set(self.index, sub, v);
        }
    }
}

/// The `(subindex, value)` pairs a download writes, in subindex order: a
/// list (a download by subindex: one pair), or the entries of a checked
/// complete download, decoded from its image on each walk (a list of them
/// was the deepest stack frame of a poll on a microcontroller).
///
/// ```
/// # use ecat_slave::device::Changes;
/// let c = Changes::list(&[(1, 20), (2, -5)]);
/// assert_eq!(c.value(2), Some(-5));
/// assert_eq!(c.iter().map(|(sub, _)| sub).collect::<Vec<_>>(), [1, 2]);
/// ```
#[derive(Debug, Clone, Copy)]
pub struct Changes<'a>(Source<'a>);

#[derive(Debug, Clone, Copy)]
enum Source<'a> {
    List(&'a [(u8, i64)]),
    Complete(CompleteChanges<'a>),
}

impl<'a> Changes<'a> {
    /// The changes of a list of `(subindex, value)` pairs.
    pub const fn list(pairs: &'a [(u8, i64)]) -> Self {
        Changes(Source::List(pairs))
    }

    /// The changes of a checked complete download.
    pub const fn complete(changes: CompleteChanges<'a>) -> Self {
        Changes(Source::Complete(changes))
    }

    /// The pairs, in subindex order.
    // One copy in a firmware (each of the five walks built its own).
    #[inline(never)]
    pub fn iter(&self) -> ChangesIter<'a> {
        ChangesIter(match self.0 {
            Source::List(pairs) => IterSource::List(pairs.iter()),
            Source::Complete(c) => IterSource::Complete(c.iter()),
        })
    }

    /// The value written into `sub`, if the download writes it.
    pub fn value(&self, sub: u8) -> Option<i64> {
        self.iter().find(|(s, _)| *s == sub).map(|(_, v)| v)
    }
}

/// The walk of [`Changes::iter`].
#[derive(Debug, Clone)]
pub struct ChangesIter<'a>(IterSource<'a>);

#[derive(Debug, Clone)]
enum IterSource<'a> {
    List(core::slice::Iter<'a, (u8, i64)>),
    Complete(CompleteIter<'a>),
}

impl Iterator for ChangesIter<'_> {
    type Item = (u8, i64);

    // One copy of the walk in a firmware, called by every loop over the
    // changes (inlined, each loop carried its own decoder: +0.3 KB).
    #[inline(never)]
    fn next(&mut self) -> Option<(u8, i64)> {
        match &mut self.0 {
            IterSource::List(it) => it.next().copied(),
            IterSource::Complete(it) => it.next(),
        }
    }
}

/// What the core does with a download the application accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Write {
    /// Store the values.
    Store,
    /// The application took care of it (stored, or acted on a command
    /// entry whose value is not kept).
    Done,
}

/// A state change requested by the master that passed the core's checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateChange {
    /// State before.
    pub from: AlState,
    /// State requested.
    pub to: AlState,
    /// PRE-OP→SAFE-OP: PDO sets every assigned RxPDO belongs to (bit n: set
    /// n of the description); all bits otherwise.
    pub rx_sets: u32,
    /// PRE-OP→SAFE-OP: the same for the TxPDOs.
    pub tx_sets: u32,
    /// Time of the poll, ns.
    pub now_ns: u64,
}

/// What [`Application::tick`] sees and may do.
pub struct Tick<'a> {
    /// The dictionary: outputs as the master wrote them (in OP), inputs the
    /// application writes for the master.
    pub od: &'a mut Od,
    /// Time now, ns (monotonic, injected).
    pub now_ns: u64,
    /// The outputs are valid: OP, and the master's cyclic outputs (SM2)
    /// have been applied to the dictionary since OP was entered; an
    /// expired SM watchdog has already left OP. Otherwise the application
    /// must drive its outputs to their safe state, whatever an SDO wrote
    /// into the output objects.
    pub outputs_valid: bool,
    /// OP with the SM watchdog armed (0x0420 not 0): the outputs stop on
    /// their own when the master does. A device whose safe state matters
    /// (a valve amplifier) drives nothing without it.
    pub sm_watchdog_armed: bool,
    /// The AL state.
    pub state: AlState,
    pub(crate) emergencies: &'a mut Emergencies,
}

impl<'a> Tick<'a> {
    /// A tick context (for unit tests of an application's `tick`; the core
    /// builds one per poll).
    pub fn new(
        od: &'a mut Od,
        now_ns: u64,
        outputs_valid: bool,
        state: AlState,
        emergencies: &'a mut Emergencies,
    ) -> Self {
        Tick {
            od,
            now_ns,
            outputs_valid,
            sm_watchdog_armed: outputs_valid,
            state,
            emergencies,
        }
    }

    /// Sets the application's error-register bits (0x1001, see
    /// [`crate::coe::emergency::register`]); the core adds the
    /// communication and generic bits.
    pub fn set_error_bits(&mut self, bits: u8) {
        self.emergencies.set_app_bits(bits);
    }

    /// Sends a CoE Emergency (queued; delivered in PRE-OP, SAFE-OP and OP).
    pub fn emergency(&mut self, code: u16, data: [u8; 5]) {
        self.emergencies.raise(code, data);
    }
}

/// A device's behaviour on the core. See the module documentation.
pub trait Application {
    /// The device's description: a `const` for a device known when it is
    /// built (`&DEVICE`), or one made at run time (a twin read from an ESI
    /// file on a host). The core reads it once per use and never expects
    /// it to change while the slave runs.
    fn description(&self) -> &'static DeviceDescription;

    /// Storage for the dictionary's live values: `[i64; N]` with `N` the
    /// dictionary's entry count (the [`dictionary!`](crate::dictionary)
    /// macro defines that constant). A device described at run time uses
    /// a larger `N` (a capacity); entries beyond `N` would read as 0 and
    /// ignore writes, so whoever builds such a description checks that it
    /// fits.
    type Values: ValueStorage;

    /// Power-on, after the dictionary was set to its defaults: restore
    /// saved parameters, start hardware.
    fn power_on(&mut self, od: &mut Od) {
        let _ = od;
    }

    /// A state change the master requested passed the core's checks;
    /// `Err` refuses it with that AL status code (the device stays in the
    /// lower state with the error indication).
    fn state_change(&mut self, od: &mut Od, change: &StateChange) -> Result<(), AlStatusCode> {
        let _ = (od, change);
        Ok(())
    }

    /// An SDO upload of `index:sub` is about to be answered (refresh a
    /// computed value; `Err` refuses it).
    fn sdo_upload(&mut self, od: &mut Od, index: u16, sub: u8) -> Result<(), SdoAbortCode> {
        let _ = (od, index, sub);
        Ok(())
    }

    /// An SDO download passed the core's checks: accept it ([`Write`]) or
    /// refuse it with an abort code.
    fn sdo_download(
        &mut self,
        od: &mut Od,
        download: &Download<'_>,
    ) -> Result<Write, SdoAbortCode> {
        let _ = (od, download);
        Ok(Write::Store)
    }

    /// The periodic task: called every poll with the time; reads outputs
    /// and writes inputs in the dictionary.
    fn tick(&mut self, tick: &mut Tick<'_>) {
        let _ = tick;
    }

    /// The outputs were just set to their safe state in the dictionary
    /// (OP left, watchdog, PDI failure): switch hardware outputs off now.
    fn outputs_safe(&mut self, od: &mut Od) {
        let _ = od;
    }

    /// The application's non-volatile storage (saved parameters), if it
    /// has one: the host runner keeps it in a file across restarts.
    fn nv(&self) -> Option<&dyn NvStorage> {
        None
    }

    /// The non-volatile storage, mutably (restored from the file at start).
    fn nv_mut(&mut self) -> Option<&mut dyn NvStorage> {
        None
    }

    /// The ESC's PDI watchdog expired while the firmware is not running
    /// (simulation of the ESC hardware forcing outputs off).
    fn pdi_watchdog_expired(&mut self) {}

    /// A power cycle: forget everything volatile (non-volatile storage
    /// stays); [`Self::power_on`] runs next.
    fn power_cycle(&mut self) {}
}
