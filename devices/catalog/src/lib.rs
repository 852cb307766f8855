//! # device-catalog: every device on the core, by name
//!
//! The host tools (the `esi` CLI, `master-test`, the `pam-slave` runner)
//! take any device by name through this catalog: its description for the
//! ESI and the SII, and a factory for software slaves on a line. A *line*
//! is written `pam,io8,pam` or `pam*3,io8`.
//!
//! Adding a device: write its crate (see `examples/io8/WRITE-YOUR-OWN-DEVICE.md`),
//! add a [`DeviceEntry`] to [`DEVICES`].

use ecat_slave::device::{DeviceDescription, SoftSlave};
use ecat_slave::host::chain::LineSlave;

/// One device of the catalog.
#[derive(Clone, Copy)]
pub struct DeviceEntry {
    /// Short name used on command lines (`pam`, `io8`).
    pub key: &'static str,
    /// One line saying what it is.
    pub summary: &'static str,
    /// The device's description.
    pub description: &'static DeviceDescription,
    /// A software slave of the device in its power-on state.
    pub make: fn() -> Box<dyn LineSlave>,
}

impl core::fmt::Debug for DeviceEntry {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("DeviceEntry")
            .field("key", &self.key)
            .field("type", &self.description.names.type_name)
            .finish()
    }
}

fn pam() -> Box<dyn LineSlave> {
    Box::new(SoftSlave::new(pam_199_p_etc::Pam::default()))
}

fn io8() -> Box<dyn LineSlave> {
    Box::new(SoftSlave::new(io8_example::Io8::default()))
}

/// Every device the tools know.
pub const DEVICES: &[DeviceEntry] = &[
    DeviceEntry {
        key: "pam",
        summary: "W.E.St. PAM-199-P-ETC valve amplifier",
        description: &pam_199_p_etc::DEVICE,
        make: pam,
    },
    DeviceEntry {
        key: "io8",
        summary: "IO8 example: 8 digital inputs, 8 outputs, one parameter, FoE",
        description: &io8_example::DEVICE,
        make: io8,
    },
];

/// Why a device or line name was not understood.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CatalogError {
    /// No device has that name.
    #[error("unknown device '{name}' (known: {known})")]
    Unknown {
        /// The name asked for.
        name: String,
        /// The names that exist.
        known: String,
    },
    /// A line is empty, or a repetition count is not a number of 1..=4096.
    #[error(
        "bad line '{0}': write devices separated by commas, e.g. pam,io8,pam or pam*3 (1 to 4096 slaves)"
    )]
    BadLine(String),
}

/// The names of every device, for messages.
pub fn known() -> String {
    DEVICES
        .iter()
        .map(|d| format!("{} ({})", d.key, d.description.names.type_name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The device named `name`: its key or its type name, any case.
pub fn find(name: &str) -> Result<&'static DeviceEntry, CatalogError> {
    let n = name.trim();
    DEVICES
        .iter()
        .find(|d| {
            d.key.eq_ignore_ascii_case(n) || d.description.names.type_name.eq_ignore_ascii_case(n)
        })
        .ok_or_else(|| CatalogError::Unknown {
            name: n.to_string(),
            known: known(),
        })
}

/// Most slaves of one line.
pub const MAX_LINE: usize = 4096;

/// Parses a line: `pam,io8,pam`, `pam*3`, `pam*2,io8`.
pub fn parse_line(spec: &str) -> Result<Vec<&'static DeviceEntry>, CatalogError> {
    let mut out = Vec::new();
    for part in spec.split(',') {
        let part = part.trim();
        if part.is_empty() {
            return Err(CatalogError::BadLine(spec.to_string()));
        }
        let (name, count) = match part.split_once('*') {
            Some((n, c)) => {
                let c: usize = c
                    .trim()
                    .parse()
                    .map_err(|_| CatalogError::BadLine(spec.to_string()))?;
                (n, c)
            }
            None => (part, 1),
        };
        if count == 0 || out.len() + count > MAX_LINE {
            return Err(CatalogError::BadLine(spec.to_string()));
        }
        let d = find(name)?;
        out.extend(std::iter::repeat_n(d, count));
    }
    if out.is_empty() {
        return Err(CatalogError::BadLine(spec.to_string()));
    }
    Ok(out)
}

/// Software slaves for the line `entries`, first to last.
pub fn slaves(entries: &[&DeviceEntry]) -> Vec<Box<dyn LineSlave>> {
    entries.iter().map(|d| (d.make)()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_are_found_by_key_or_type_name() {
        assert_eq!(find("pam").unwrap().key, "pam");
        assert_eq!(find("PAM-199-P-ETC").unwrap().key, "pam");
        let e = find("nope").unwrap_err();
        assert!(e.to_string().contains("unknown device 'nope'"), "{e}");
        assert!(e.to_string().contains("pam"), "{e}");
    }

    #[test]
    fn lines_parse_with_repetitions_and_refuse_nonsense() {
        let l = parse_line("pam*2, io8,pam").unwrap();
        let keys: Vec<&str> = l.iter().map(|d| d.key).collect();
        assert_eq!(keys, ["pam", "pam", "io8", "pam"]);
        assert_eq!(find("IO8").unwrap().key, "io8");
        for bad in ["", "pam,,pam", "pam*0", "pam*x", "pam*4097", "io8*4096,pam"] {
            assert!(parse_line(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn every_catalog_device_is_valid_and_makes_its_slave() {
        for d in DEVICES {
            assert_eq!(d.description.validate(), Ok(()), "{}", d.key);
            let s = (d.make)();
            assert_eq!(
                s.description().identity,
                d.description.identity,
                "{}",
                d.key
            );
        }
    }
}
