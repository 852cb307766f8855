//! `master-test`: an EtherCAT commissioning tool on ethercrab.
//!
//! Every command runs on the built-in virtual bus (software slaves in this
//! process, the default) or, with `--iface IF`, on a network interface
//! with ethercrab's raw socket: the `pam-slave` runner or real devices.
//! See `master-test --help`.

#![deny(clippy::print_stdout)]

mod conformance_cmd;
mod demo;
mod eeprom_cmd;
mod failure;
mod foe_cmd;
mod hcs;
mod output;
mod scan;
mod sdo;
mod target;

use clap::{Parser, Subcommand};
use failure::{Failure, input};
use std::process::ExitCode;
use target::Where;

const AFTER_HELP: &str = "\
Buses:
  Without --iface every command runs on the built-in virtual bus: software
  slaves in this process (--device or --line says which), in their
  power-on state each time. With --iface IF it runs on that network
  interface with ethercrab's raw socket (root or CAP_NET_RAW), against the
  pam-slave runner or real devices, which keep their state between
  commands.

Object addresses (sdo): INDEX:SUB, both hexadecimal with or without 0x,
  exactly as the tools print them: 0x800D:02, 800d:2, 0x8006:2A, 8006:0x2a.

Exit status:
  0    done (also when the reader of the output goes away, e.g. `| head`)
  1    the device refused (SDO abort, FoE error, AL status code, EEPROM
       error) or a check found mismatches
  2    usage or input error (bad argument, file or value); nothing was sent
  3    communication failure (no slave, no answer, interface cannot be opened)
  130  stopped by Ctrl-C before the command finished (the message says what
       state the slaves were left in)";

#[derive(Parser)]
#[command(
    name = "master-test",
    version,
    about = "EtherCAT commissioning tool on ethercrab: the PAM-199-P-ETC demo, scan, \
             AL states, SDO, the object dictionary, FoE firmware update, process data, \
             SII EEPROM, ESI check; on a virtual bus of software slaves or any interface",
    after_help = AFTER_HELP
)]
struct Cli {
    /// Network interface to run on (ethercrab raw socket; needs root or
    /// CAP_NET_RAW). Without it: the built-in virtual bus.
    #[arg(long, global = true, value_name = "IF")]
    iface: Option<String>,
    /// The device of the virtual bus (one slave): pam, io8, ... (see `esi
    /// devices`); also the identity `firmware pack` writes. Default: pam.
    #[arg(long, global = true, value_name = "NAME")]
    device: Option<String>,
    /// The virtual bus as a line of devices: `pam,io8,pam`, `pam*4`;
    /// `pam@et1100`, `io8@lan9252` put a slave's firmware behind that SPI
    /// driver and an emulated chip.
    #[arg(long, global = true, value_name = "SPEC", conflicts_with = "device")]
    line: Option<String>,
    /// The virtual bus as the line of an ENI file (ETG.2100): each slave
    /// from the catalog or a twin from an ESI file of --esi-dir.
    #[arg(long, global = true, value_name = "FILE", conflicts_with_all = ["device", "line", "iface"])]
    eni: Option<std::path::PathBuf>,
    /// Directory of ESI files for --eni.
    #[arg(long, global = true, value_name = "DIR", requires = "eni")]
    esi_dir: Option<std::path::PathBuf>,
    /// The slave to talk to, by position (0 = first after the master).
    #[arg(long, global = true, value_name = "N", conflicts_with = "station")]
    slave: Option<usize>,
    /// The slave to talk to, by configured station address (0x1000 is the
    /// first one ethercrab configures).
    #[arg(long, global = true, value_name = "ADDR", value_parser = parse_u16)]
    station: Option<u16>,
    #[command(subcommand)]
    command: Option<Cmd>,
}

/// `0x1001` or `4097`.
fn parse_u16(s: &str) -> Result<u16, String> {
    let v = master_test::cli::parse_int(s)
        .ok_or_else(|| format!("'{s}' is not a number (decimal, or hex with 0x)"))?;
    u16::try_from(v).map_err(|_| format!("{v} is outside 0..=65535 (0x0000..=0xFFFF)"))
}

#[derive(Subcommand)]
enum Cmd {
    /// Bring PAM slaves to OP, parameterise over SDO, drive a set-point
    /// (the default command).
    Demo(demo::DemoArgs),
    /// List the slaves: position, station, alias, identity, name, AL
    /// state and status code, mailbox protocols, process data sizes.
    Scan {
        /// JSON (schema in docs/book/src/commissioning.md) instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Show the AL state of the slaves, or request one.
    ///
    /// INIT, PRE-OP and BOOT are requested from the selected slave (all
    /// slaves without --slave/--station); SAFE-OP and OP from the whole
    /// segment, since the master configures process data for all slaves
    /// together. OP is held only while process data runs (see `watch`):
    /// after this command a slave with a SyncManager watchdog falls back
    /// to SAFE-OP.
    State {
        /// init, preop, safeop, op or boot; none: just show the states.
        #[arg(value_parser = scan::parse_state)]
        target: Option<scan::AlTarget>,
    },
    /// Live process data: bring the segment to OP and print the selected
    /// slave's inputs, decoded by its PDO mapping, until --cycles or
    /// Ctrl-C; then back to PRE-OP.
    Watch(scan::WatchArgs),
    /// Read or write one object entry over CoE SDO (slave in PRE-OP).
    ///
    /// Values are typed by the slave's own SDO Information (Get Entry
    /// Description): data type, bit length, access, unit, range.
    Sdo {
        #[command(subcommand)]
        op: sdo::SdoCmd,
    },
    /// Browse the live object dictionary (slave in PRE-OP).
    Od {
        #[command(subcommand)]
        op: sdo::OdCmd,
    },
    /// File access over EtherCAT: firmware download in BOOT, file read.
    Foe {
        #[command(subcommand)]
        op: foe_cmd::FoeCmd,
    },
    /// The slave's SII EEPROM over the ESC's EEPROM interface.
    Eeprom {
        #[command(subcommand)]
        op: eeprom_cmd::EepromCmd,
    },
    /// The slave against its ESI.
    Esi {
        #[command(subcommand)]
        op: eeprom_cmd::EsiCmd,
    },
    /// Check one slave against the ETG rules this tool knows: ESC, SII,
    /// state machine, mailbox, CoE, FoE (a table of check, expectation
    /// with its ETG reference, observation, verdict; exit status 1 on any
    /// failure).
    ///
    /// The slave is left in PRE-OP. The checks write: AL control, the
    /// SyncManager registers (restored), every writable object entry (with
    /// the value it had), and with --foe-file the file in BOOT.
    Conformance(conformance_cmd::ConformanceArgs),
    /// HCS telegrams (CMD 3 read, CMD 6 write, CMD 15 multi-write)
    /// through the telegram channel of an HCS DMA-22(A) node (objects
    /// 0x2000/0x2001), e.g. `--device dma22 hcs read --module 2 0x07`.
    Hcs {
        #[command(subcommand)]
        op: hcs::HcsCmd,
    },
    /// Firmware image tools (no bus).
    Firmware {
        #[command(subcommand)]
        op: foe_cmd::FirmwareCmd,
    },
}

fn main() -> ExitCode {
    output::install_ctrlc();
    let cli = Cli::parse();
    let result = run(cli);
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // Nobody reads the output any more: a quiet, successful end.
        Err(Failure::Interrupted(_)) if output::pipe_closed() => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
}

fn run(cli: Cli) -> Result<(), Failure> {
    let device = match &cli.device {
        Some(d) => Some(device_catalog::find(d).map_err(|e| input(e.to_string()))?),
        None => None,
    };
    let line = match (&cli.line, device) {
        (Some(l), _) => {
            device_catalog::parse_line(l).map_err(|e| input(format!("--line: {e}")))?;
            l.clone()
        }
        (None, Some(d)) => d.key.to_string(),
        (None, None) => "pam".to_string(),
    };
    if cli.iface.is_some() && (cli.line.is_some() || cli.device.is_some()) {
        let what = if cli.line.is_some() {
            "--line"
        } else {
            "--device"
        };
        if !matches!(cli.command, Some(Cmd::Firmware { .. })) {
            return Err(input(format!(
                "{what} describes the virtual bus; with --iface the slaves are whatever \
                 is on the interface"
            )));
        }
    }
    let mut w = Where {
        iface: cli.iface,
        line,
        slave: cli.slave,
        station: cli.station,
        pcap: None,
        eni: cli.eni.map(|e| (e, cli.esi_dir)),
    };
    let cmd = cli.command.unwrap_or(Cmd::Demo(demo::DemoArgs::default()));
    match cmd {
        Cmd::Demo(args) => {
            if w.eni.is_some() {
                return Err(input(
                    "the demo drives PAMs of its own; use scan, state, sdo, watch or od with --eni",
                ));
            }
            if cli.line.is_none() && cli.device.is_none() {
                w.line = format!("pam*{}", args.slaves);
            } else if args.slaves != 1 {
                return Err(input("--slaves cannot be combined with --line or --device"));
            }
            w.pcap.clone_from(&args.pcap);
            // A long line's group is large (see master_test::LongGroup):
            // the demo runs on a thread with a big stack.
            std::thread::Builder::new()
                .name("demo".into())
                .stack_size(64 << 20)
                .spawn(move || smol::block_on(demo::run(&w, &args)))
                .map_err(|e| Failure::Comm(format!("cannot start the demo thread: {e}")))?
                .join()
                .unwrap_or_else(|_| Err(Failure::Comm("the demo thread panicked".into())))
        }
        Cmd::Scan { json } => smol::block_on(scan::scan(&w, json)),
        Cmd::State { target } => smol::block_on(scan::state(&w, target)),
        Cmd::Watch(args) => smol::block_on(scan::watch(&w, &args)),
        Cmd::Sdo { op } => smol::block_on(sdo::sdo(&w, op)),
        Cmd::Od { op } => smol::block_on(sdo::od(&w, op)),
        Cmd::Foe { op } => smol::block_on(foe_cmd::foe(&w, op)),
        Cmd::Eeprom { op } => smol::block_on(eeprom_cmd::eeprom(&w, op)),
        Cmd::Esi { op } => smol::block_on(eeprom_cmd::esi(&w, op)),
        Cmd::Conformance(args) => smol::block_on(conformance_cmd::conformance(&w, &args)),
        Cmd::Hcs { op } => smol::block_on(hcs::hcs(&w, op)),
        Cmd::Firmware { op } => {
            let dev = device.unwrap_or(&device_catalog::DEVICES[0]);
            foe_cmd::firmware(dev, op)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn station_addresses_parse_in_hex_and_decimal() {
        assert_eq!(parse_u16("0x1001"), Ok(0x1001));
        assert_eq!(parse_u16("4097"), Ok(0x1001));
        assert!(
            parse_u16("0x10000")
                .unwrap_err()
                .contains("outside 0..=65535")
        );
        assert!(parse_u16("abc").unwrap_err().contains("not a number"));
    }
}
