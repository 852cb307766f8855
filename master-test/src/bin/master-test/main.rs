//! `master-test`: an EtherCAT commissioning tool on ethercrab.
//!
//! Every command runs on the built-in virtual bus (software slaves in this
//! process, the default) or, with `--iface IF`, on a network interface
//! with ethercrab's raw socket: the `pam-slave` runner or real devices.
//! See `master-test --help`.
//!
//! The shape: one module per command under [`cmd`] (its clap `Args` and
//! its `run`), the options every command shares in [`options`] (checked
//! by clap, turned into the target once), the target and its session in
//! [`target`], failures and their exit statuses in [`failure`], output a
//! closed pipe cannot crash in [`output`].

#![deny(clippy::print_stdout)]

mod cmd;
mod failure;
mod options;
mod output;
mod parse;
mod target;

use clap::Parser;
use cmd::Cmd;
use failure::Failure;
use options::SharedOptions;
use std::process::ExitCode;

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

#[derive(Parser, Debug)]
#[command(
    name = "master-test",
    version,
    about = "EtherCAT commissioning tool on ethercrab: the PAM-199-P-ETC demo, scan, \
             AL states, SDO, the object dictionary, FoE firmware update, process data, \
             SII EEPROM, ESI check; on a virtual bus of software slaves or any interface",
    after_help = AFTER_HELP
)]
struct Cli {
    #[command(flatten)]
    shared: SharedOptions,
    #[command(subcommand)]
    command: Option<Cmd>,
}

fn main() -> ExitCode {
    output::install_ctrlc();
    let cli = Cli::parse();
    let result = cli.command.unwrap_or_default().run(&cli.shared);
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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("master-test").chain(args.iter().copied()))
    }

    #[test]
    fn cli_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn without_a_command_the_demo_runs() {
        let cli = parse(&["--line", "pam*2"]).unwrap();
        assert!(cli.command.is_none());
        assert!(matches!(cli.command.unwrap_or_default(), Cmd::Demo(_)));
    }

    #[test]
    fn shared_options_stand_before_or_after_the_command() {
        for args in [
            &[
                "--line",
                "pam,io8",
                "--slave",
                "1",
                "sdo",
                "read",
                "0x1008:00",
            ][..],
            &[
                "sdo",
                "read",
                "0x1008:00",
                "--line",
                "pam,io8",
                "--slave",
                "1",
            ],
            &[
                "sdo",
                "--slave",
                "1",
                "read",
                "--line",
                "pam,io8",
                "0x1008:00",
            ],
        ] {
            let cli = parse(args).unwrap();
            assert_eq!(cli.shared.line.as_deref(), Some("pam,io8"), "{args:?}");
            assert_eq!(cli.shared.slave, Some(1), "{args:?}");
            assert!(matches!(cli.command, Some(Cmd::Sdo(_))), "{args:?}");
        }
    }

    #[test]
    fn bad_arguments_are_usage_errors_with_exit_status_2() {
        for args in [
            &["--device", "nope", "scan"][..],
            &["--station", "x", "scan"],
            &["--line", "pam", "--device", "io8"],
            &["scan", "--no-such-flag"],
            &["demo", "--current", "5000"],
        ] {
            let e = parse(args).expect_err("refused");
            assert_eq!(e.exit_code(), 2, "{args:?}: {e}");
        }
    }
}
