//! The commands, one module each: its clap `Args` and its `run`. The
//! variants' doc comments are the one-line summaries `--help` lists.

pub mod conformance;
pub mod demo;
pub mod eeprom;
pub mod esi;
pub mod firmware;
pub mod foe;
pub mod hcs;
pub mod od;
pub mod scan;
pub mod sdo;
pub mod state;
pub mod watch;

use crate::failure::Failure;
use crate::options::SharedOptions;

/// A command of `master-test`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Cmd {
    /// Bring PAM slaves to OP, parameterise over SDO, drive a set-point
    /// (the default command).
    Demo(demo::Args),
    /// List the slaves: position, station, alias, identity, name, AL
    /// state and status code, mailbox protocols, process data sizes.
    Scan(scan::Args),
    /// Show the AL state of the slaves, or request one.
    ///
    /// INIT, PRE-OP and BOOT are requested from the selected slave (all
    /// slaves without --slave/--station); SAFE-OP and OP from the whole
    /// segment, since the master configures process data for all slaves
    /// together. OP is held only while process data runs (see `watch`):
    /// after this command a slave with a SyncManager watchdog falls back
    /// to SAFE-OP.
    State(state::Args),
    /// Live process data: bring the segment to OP and print the selected
    /// slave's inputs, decoded by its PDO mapping, until --cycles or
    /// Ctrl-C; then back to PRE-OP.
    Watch(watch::Args),
    /// Read or write one object entry over CoE SDO (slave in PRE-OP).
    ///
    /// Values are typed by the slave's own SDO Information (Get Entry
    /// Description): data type, bit length, access, unit, range.
    Sdo(sdo::Args),
    /// Browse the live object dictionary (slave in PRE-OP).
    Od(od::Args),
    /// File access over EtherCAT: firmware download in BOOT, file read.
    Foe(foe::Args),
    /// The slave's SII EEPROM over the ESC's EEPROM interface.
    Eeprom(eeprom::Args),
    /// The slave against its ESI.
    Esi(esi::Args),
    /// Check one slave against the ETG rules this tool knows: ESC, SII,
    /// state machine, mailbox, CoE, FoE (a table of check, expectation
    /// with its ETG reference, observation, verdict; exit status 1 on any
    /// failure).
    ///
    /// The slave is left in PRE-OP. The checks write: AL control, the
    /// SyncManager registers (restored), every writable object entry (with
    /// the value it had), and with --foe-file the file in BOOT.
    Conformance(conformance::Args),
    /// HCS telegrams (CMD 3 read, CMD 6 write, CMD 15 multi-write)
    /// through the telegram channel of an HCS DMA-22(A) node (objects
    /// 0x2000/0x2001), e.g. `--device dma22 hcs read --module 2 0x07`.
    Hcs(hcs::Args),
    /// Firmware image tools (no bus).
    Firmware(firmware::Args),
}

impl Default for Cmd {
    /// `master-test` without a command runs the demo.
    fn default() -> Self {
        Cmd::Demo(demo::Args::default())
    }
}

impl Cmd {
    /// Runs the command on the target `shared` names (the bus commands)
    /// or for its device (`firmware`).
    pub fn run(self, shared: &SharedOptions) -> Result<(), Failure> {
        let on_bus = || shared.bus_target();
        match self {
            Cmd::Demo(a) => demo::run(shared, a),
            Cmd::Scan(a) => smol::block_on(scan::run(&on_bus()?, a)),
            Cmd::State(a) => smol::block_on(state::run(&on_bus()?, a)),
            Cmd::Watch(a) => smol::block_on(watch::run(&on_bus()?, a)),
            Cmd::Sdo(a) => smol::block_on(sdo::run(&on_bus()?, a)),
            Cmd::Od(a) => smol::block_on(od::run(&on_bus()?, a)),
            Cmd::Foe(a) => smol::block_on(foe::run(&on_bus()?, a)),
            Cmd::Eeprom(a) => smol::block_on(eeprom::run(&on_bus()?, a)),
            Cmd::Esi(a) => smol::block_on(esi::run(&on_bus()?, a)),
            Cmd::Conformance(a) => smol::block_on(conformance::run(&on_bus()?, a)),
            Cmd::Hcs(a) => smol::block_on(hcs::run(&on_bus()?, a)),
            Cmd::Firmware(a) => firmware::run(shared.device(), a),
        }
    }
}
