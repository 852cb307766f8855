//! The options every command shares (which bus, which slave), checked by
//! clap and turned into the command's target, [`Where`], in one place.

use crate::failure::{Failure, input};
use crate::parse::parse_u16;
use crate::target::Where;
use device_catalog::DeviceEntry;
use std::path::PathBuf;

/// Help heading of the options that say which bus.
const BUS: &str = "Bus";
/// Help heading of the options that pick the slave.
const SLAVE: &str = "Slave selection";

/// The shared options, flattened into the top-level parser and global:
/// they may stand before or after the command (`master-test --slave 1 sdo
/// ...` or `master-test sdo ... --slave 1`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SharedOptions {
    /// Network interface to run on (ethercrab raw socket; needs root or
    /// CAP_NET_RAW). Without it: the built-in virtual bus.
    #[arg(long, global = true, value_name = "IF", help_heading = BUS)]
    pub iface: Option<String>,
    /// The device of the virtual bus (one slave): pam, io8, ... (see `esi
    /// devices`); also the identity `firmware pack` writes. Default: pam.
    #[arg(long, global = true, value_name = "NAME", value_parser = parse_device,
          help_heading = BUS)]
    pub device: Option<&'static DeviceEntry>,
    /// The virtual bus as a line of devices: `pam,io8,pam`, `pam*4`;
    /// `pam@et1100`, `io8@lan9252` put a slave's firmware behind that SPI
    /// driver and an emulated chip.
    #[arg(long, global = true, value_name = "SPEC", value_parser = parse_line,
          conflicts_with = "device", help_heading = BUS)]
    pub line: Option<String>,
    /// The virtual bus as the line of an ENI file (ETG.2100): each slave
    /// from the catalog or a twin from an ESI file of --esi-dir.
    #[arg(long, global = true, value_name = "FILE",
          conflicts_with_all = ["device", "line", "iface"], help_heading = BUS)]
    pub eni: Option<PathBuf>,
    /// Directory of ESI files for --eni.
    #[arg(long, global = true, value_name = "DIR", requires = "eni", help_heading = BUS)]
    pub esi_dir: Option<PathBuf>,
    /// The slave to talk to, by position (0 = first after the master).
    #[arg(long, global = true, value_name = "N", conflicts_with = "station",
          help_heading = SLAVE)]
    pub slave: Option<usize>,
    /// The slave to talk to, by configured station address (0x1000 is the
    /// first one ethercrab configures).
    #[arg(long, global = true, value_name = "ADDR", value_parser = parse_u16,
          help_heading = SLAVE)]
    pub station: Option<u16>,
}

/// `--device`: a device of the catalog by key or type name.
fn parse_device(s: &str) -> Result<&'static DeviceEntry, String> {
    device_catalog::find(s).map_err(|e| e.to_string())
}

/// `--line`: a line spec the catalog can build (devices, counts, PDI
/// paths); kept as written.
fn parse_line(s: &str) -> Result<String, String> {
    device_catalog::parse_line(s)
        .map(|_| s.to_string())
        .map_err(|e| e.to_string())
}

impl SharedOptions {
    /// The device `firmware pack` writes the identity of: `--device`, else
    /// the first of the catalog (the PAM).
    pub fn device(&self) -> &'static DeviceEntry {
        self.device.unwrap_or(&device_catalog::DEVICES[0])
    }

    /// Whether `--line` or `--device` chose the virtual line.
    pub fn names_virtual_line(&self) -> bool {
        self.line.is_some() || self.device.is_some()
    }

    /// The target of a bus command: the bus and the slave these options
    /// name. Without `--line` or `--device` the virtual line is
    /// `default_line`. `--line` and `--device` describe the virtual bus,
    /// so they are refused with `--iface` (clap cannot say this one:
    /// `firmware pack` takes `--device` for its identity whatever the bus).
    pub fn target(&self, default_line: impl FnOnce() -> String) -> Result<Where, Failure> {
        if self.iface.is_some() && self.names_virtual_line() {
            let what = if self.line.is_some() {
                "--line"
            } else {
                "--device"
            };
            return Err(input(format!(
                "{what} describes the virtual bus; with --iface the slaves are whatever \
                 is on the interface"
            )));
        }
        let line = match (&self.line, self.device) {
            (Some(l), _) => l.clone(),
            (None, Some(d)) => d.key.to_string(),
            (None, None) => default_line(),
        };
        Ok(Where {
            iface: self.iface.clone(),
            line,
            slave: self.slave,
            station: self.station,
            pcap: None,
            eni: self.eni.clone().map(|eni| (eni, self.esi_dir.clone())),
        })
    }

    /// [`SharedOptions::target`] with the one-PAM line as the default.
    pub fn bus_target(&self) -> Result<Where, Failure> {
        self.target(|| "pam".to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser as _;

    /// Only the shared options, as the top-level parser holds them.
    #[derive(clap::Parser)]
    struct Only {
        #[command(flatten)]
        shared: SharedOptions,
    }

    fn parse(args: &[&str]) -> Result<SharedOptions, clap::Error> {
        Only::try_parse_from(std::iter::once("master-test").chain(args.iter().copied()))
            .map(|o| o.shared)
    }

    #[test]
    fn without_options_the_target_is_one_pam_on_the_virtual_bus() {
        let w = parse(&[]).unwrap().bus_target().unwrap();
        assert_eq!(w.line, "pam");
        assert!(w.iface.is_none() && w.eni.is_none() && w.pcap.is_none());
        assert_eq!((w.slave, w.station), (None, None));
    }

    #[test]
    fn a_device_names_its_line_by_key_and_is_the_firmware_identity() {
        let o = parse(&["--device", "IO8"]).unwrap();
        assert_eq!(o.bus_target().unwrap().line, "io8");
        assert_eq!(o.device().key, "io8");
        assert_eq!(parse(&[]).unwrap().device().key, "pam");
        // The line wins over the command's default line.
        let o = parse(&["--line", "pam,io8"]).unwrap();
        assert_eq!(o.target(|| "pam*4".into()).unwrap().line, "pam,io8");
        assert_eq!(
            parse(&[]).unwrap().target(|| "pam*4".into()).unwrap().line,
            "pam*4"
        );
    }

    #[test]
    fn unknown_devices_and_bad_lines_are_usage_errors_naming_the_option() {
        for args in [
            &["--device", "nope"][..],
            &["--line", "pam,nope"],
            &["--line", "pam*4097"],
        ] {
            let e = parse(args).expect_err("refused");
            assert_eq!(
                e.kind(),
                clap::error::ErrorKind::ValueValidation,
                "{args:?}"
            );
            let text = e.to_string();
            assert!(text.contains(args[0]), "{args:?}: {text}");
        }
        let e = parse(&["--station", "0x10000"]).expect_err("refused");
        assert!(e.to_string().contains("outside 0..=65535"), "{e}");
    }

    #[test]
    fn contradicting_options_are_refused_by_clap() {
        for args in [
            &["--line", "pam", "--device", "io8"][..],
            &["--eni", "x.xml", "--line", "pam"],
            &["--eni", "x.xml", "--iface", "eth0"],
            &["--slave", "0", "--station", "0x1000"],
        ] {
            let e = parse(args).expect_err("refused");
            assert_eq!(
                e.kind(),
                clap::error::ErrorKind::ArgumentConflict,
                "{args:?}"
            );
        }
        let e = parse(&["--esi-dir", "d"]).expect_err("refused");
        assert_eq!(e.kind(), clap::error::ErrorKind::MissingRequiredArgument);
    }

    #[test]
    fn the_virtual_line_is_refused_on_an_interface_with_exit_2() {
        for (args, what) in [
            (&["--iface", "eth0", "--line", "pam"][..], "--line"),
            (&["--iface", "eth0", "--device", "io8"], "--device"),
        ] {
            let o = parse(args).unwrap();
            let Err(Failure::Input(m)) = o.bus_target() else {
                panic!("{args:?} accepted");
            };
            assert!(m.starts_with(what) && m.contains("--iface"), "{m}");
            // firmware pack only takes the identity.
            assert!(o.device().key == "pam" || o.device().key == "io8");
        }
    }

    #[test]
    fn eni_selection_and_station_reach_the_target() {
        let w = parse(&["--eni", "m.xml", "--esi-dir", "esi", "--slave", "4"])
            .unwrap()
            .bus_target()
            .unwrap();
        assert_eq!(
            w.eni,
            Some((PathBuf::from("m.xml"), Some(PathBuf::from("esi"))))
        );
        assert_eq!(w.slave, Some(4));
        let w = parse(&["--iface", "eth0", "--station", "0x1001"])
            .unwrap()
            .bus_target()
            .unwrap();
        assert_eq!(
            (w.iface.as_deref(), w.station),
            (Some("eth0"), Some(0x1001))
        );
    }
}
