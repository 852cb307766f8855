//! # device-catalog: every device on the core, by name
//!
//! The host tools (the `esi` CLI, `master-test`, the `pam-slave` runner)
//! take any device by name through this catalog: its description for the
//! ESI and the SII, and a factory for software slaves on a line. A *line*
//! is written `pam,io8,pam` or `pam*3,io8`.
//!
//! A device may carry its PDI path after an `@`: `pam@et1100` runs the
//! PAM's firmware through the ET1100 SPI driver (`ecat-esc-spi`) against a
//! byte-level emulation of the chip's SPI interface (`ecat-esc-spi-emu`) in
//! front of its software ESC, `io8@lan9252` the same through the LAN9252
//! driver; without `@` the firmware reaches the software ESC directly
//! (see [`Pdi`] and [`spi_pdi`]).
//!
//! Adding a device: write its crate (see `examples/io8/WRITE-YOUR-OWN-DEVICE.md`),
//! add a [`DeviceEntry`] to [`DEVICES`].

use ecat_sim::SoftSlave;
use ecat_sim::chain::LineSlave;
use ecat_slave::device::{Application, DeviceDescription};

pub mod exit;
pub mod spi_pdi;
pub mod twins;

pub use spi_pdi::{Et1100Pdi, Lan9252Pdi};

/// How a software slave's firmware reaches its software ESC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Pdi {
    /// Directly (the software ESC is the firmware's [`ecat_slave::esc::Esc`]).
    #[default]
    Direct,
    /// Through the ET1100 SPI driver and an emulated ET1100 SPI slave
    /// interface (`@et1100`).
    Et1100Spi,
    /// Through the LAN9252 SPI driver and an emulated LAN9252 SPI
    /// interface (`@lan9252`).
    Lan9252Spi,
}

impl Pdi {
    /// Every PDI path by its line-spec name.
    pub const ALL: [(&'static str, Pdi); 3] = [
        ("direct", Pdi::Direct),
        ("et1100", Pdi::Et1100Spi),
        ("lan9252", Pdi::Lan9252Spi),
    ];

    /// The line-spec name (`direct`, `et1100`, `lan9252`).
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, p)| *p == self)
            .map_or("direct", |(n, _)| n)
    }
}

/// One device of the catalog.
#[derive(Clone, Copy)]
pub struct DeviceEntry {
    /// Short name used on command lines (`pam`, `io8`).
    pub key: &'static str,
    /// One line saying what it is.
    pub summary: &'static str,
    /// The device's description.
    pub description: &'static DeviceDescription,
    /// A software slave of the device in its power-on state, its firmware
    /// on the given PDI path.
    pub make: fn(Pdi) -> Box<dyn LineSlave>,
}

/// One slave of a line: a device and its firmware's PDI path.
#[derive(Debug, Clone, Copy)]
pub struct LineEntry {
    /// The device.
    pub device: &'static DeviceEntry,
    /// How its firmware reaches the software ESC.
    pub pdi: Pdi,
}

impl core::ops::Deref for LineEntry {
    type Target = DeviceEntry;
    fn deref(&self) -> &DeviceEntry {
        self.device
    }
}

impl core::fmt::Debug for DeviceEntry {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("DeviceEntry")
            .field("key", &self.key)
            .field("type", &self.description.names.type_name)
            .finish()
    }
}

/// A software slave of `A` in its power-on state on the PDI path `pdi`.
pub fn make<A: Application + Default + Send + 'static>(pdi: Pdi) -> Box<dyn LineSlave> {
    match pdi {
        Pdi::Direct => Box::new(SoftSlave::new(A::default())),
        Pdi::Et1100Spi => Box::new(SoftSlave::with_pdi(A::default(), Et1100Pdi::new)),
        Pdi::Lan9252Spi => Box::new(SoftSlave::with_pdi(A::default(), Lan9252Pdi::new)),
    }
}

/// Every device the tools know.
pub const DEVICES: &[DeviceEntry] = &[
    DeviceEntry {
        key: "pam",
        summary: "W.E.St. PAM-199-P-ETC valve amplifier",
        description: &pam_199_p_etc::DEVICE,
        make: make::<pam_199_p_etc::Pam>,
    },
    DeviceEntry {
        key: "io8",
        summary: "IO8 example: 8 digital inputs, 8 outputs, one parameter, FoE",
        description: &io8_example::DEVICE,
        make: make::<io8_example::Io8>,
    },
    DeviceEntry {
        key: "servo402",
        summary: "servo402 example: a CiA 402 servo drive (CSP/CSV/CST, PP/PV/HM, DC SYNC0)",
        description: &servo402_example::DEVICE,
        make: make::<servo402_example::Servo402>,
    },
    DeviceEntry {
        key: "dma22",
        summary: "HCS DMA-22(A) node, modular: 3 DMA-22(A) modules in mode 3 (manual 5.4.2)",
        description: &hcs_dma22::DEVICE,
        make: make::<hcs_dma22::Dma22Node<3>>,
    },
    DeviceEntry {
        key: "dma22x1",
        summary: "HCS DMA-22(A) node with 1 module in mode 3",
        description: &hcs_dma22::DEVICE,
        make: make::<hcs_dma22::Dma22Node<1>>,
    },
    DeviceEntry {
        key: "dma22x5",
        summary: "HCS DMA-22(A) node with 5 modules in mode 3",
        description: &hcs_dma22::DEVICE,
        make: make::<hcs_dma22::Dma22Node<5>>,
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
    /// A device's `@PDI` suffix names no PDI path.
    #[error("unknown PDI '{name}' in the line (known: direct, et1100, lan9252)")]
    UnknownPdi {
        /// The name after `@`.
        name: String,
    },
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

/// Parses a line: `pam,io8,pam`, `pam*3`, `pam*2,io8`, with an optional
/// PDI path per device: `pam@et1100*2,io8@lan9252`.
pub fn parse_line(spec: &str) -> Result<Vec<LineEntry>, CatalogError> {
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
        let (name, pdi) = match name.split_once('@') {
            Some((n, p)) => {
                let p = p.trim();
                let pdi = Pdi::ALL
                    .iter()
                    .find(|(k, _)| k.eq_ignore_ascii_case(p))
                    .map(|(_, v)| *v)
                    .ok_or_else(|| CatalogError::UnknownPdi {
                        name: p.to_string(),
                    })?;
                (n, pdi)
            }
            None => (name, Pdi::Direct),
        };
        let device = find(name)?;
        out.extend(std::iter::repeat_n(LineEntry { device, pdi }, count));
    }
    if out.is_empty() {
        return Err(CatalogError::BadLine(spec.to_string()));
    }
    Ok(out)
}

/// A deterministic oscillator error for the slave at `position` of a
/// line, spread over ±`spread_ppm` (ppb): what `pam-slave --oscillators`
/// gives each slave, so the DC drift control has real work to do.
pub fn oscillator_ppb(position: usize, spread_ppm: u32) -> i64 {
    let k = (position as i64 * 37 + 11) % 21 - 10; // -10..=10
    k * i64::from(spread_ppm) * 100
}

/// Software slaves for the line `entries`, first to last.
pub fn slaves(entries: &[LineEntry]) -> Vec<Box<dyn LineSlave>> {
    entries.iter().map(|d| (d.device.make)(d.pdi)).collect()
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
        assert!(l.iter().all(|d| d.pdi == Pdi::Direct));
        assert_eq!(find("IO8").unwrap().key, "io8");
        for bad in ["", "pam,,pam", "pam*0", "pam*x", "pam*4097", "io8*4096,pam"] {
            assert!(parse_line(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn oscillators_spread_within_the_bounds_and_differ_between_neighbours() {
        let e: Vec<i64> = (0..64).map(|i| oscillator_ppb(i, 30)).collect();
        assert!(e.iter().all(|x| x.abs() <= 30_000));
        assert!(e.windows(2).all(|w| w[0] != w[1]));
        assert!(e.iter().any(|&x| x > 0) && e.iter().any(|&x| x < 0));
        assert_eq!(oscillator_ppb(5, 0), 0);
    }

    #[test]
    fn a_device_takes_its_pdi_path_after_an_at_sign() {
        let l = parse_line("pam@et1100*2,io8@LAN9252,pam@direct").unwrap();
        let got: Vec<(&str, Pdi)> = l.iter().map(|d| (d.key, d.pdi)).collect();
        assert_eq!(
            got,
            [
                ("pam", Pdi::Et1100Spi),
                ("pam", Pdi::Et1100Spi),
                ("io8", Pdi::Lan9252Spi),
                ("pam", Pdi::Direct)
            ]
        );
        let e = parse_line("pam@spi9").unwrap_err();
        assert_eq!(
            e,
            CatalogError::UnknownPdi {
                name: "spi9".into()
            }
        );
        assert!(e.to_string().contains("et1100, lan9252"), "{e}");
        assert!(matches!(
            parse_line("nope@et1100"),
            Err(CatalogError::Unknown { .. })
        ));
    }

    #[test]
    fn every_catalog_device_is_valid_and_makes_its_slave() {
        for d in DEVICES {
            assert_eq!(d.description.validate(), Ok(()), "{}", d.key);
            for (_, pdi) in Pdi::ALL {
                let s = (d.make)(pdi);
                assert_eq!(
                    s.description().identity,
                    d.description.identity,
                    "{} {pdi:?}",
                    d.key
                );
            }
        }
    }
}
