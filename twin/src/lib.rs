//! # ecat-twin: software twins of any vendor's device, lines from an ENI
//!
//! A *twin* is a software slave that looks to a master like a real device
//! described by an ESI file (ETG.2000): same SII (identity, names, FMMUs,
//! SyncManagers, PDOs), same AL state machine, same process image. A whole
//! machine line is built from the ENI (ETG.2100) a configurator exports.
//!
//! - [`esi`]: one device of an ESI file, with errors naming element and
//!   line.
//! - [`sii`]: its SII image (`<Eeprom><Data>` verbatim, or encoded from the
//!   ESI with the core's encoder).
//! - [`mod@esc_twin`]: the twin of a device without a firmware (couplers,
//!   digital I/O terminals: ESC and EEPROM only).
//! - [`coe_twin`] and [`dictionary`]: the twin of a device with a mailbox:
//!   the core's firmware (CoE, SDO Information, PDO engine, AL state
//!   machine) on a description built from the ESI at run time.
//! - [`eni`]: the slaves of an ENI.
//! - [`mod@line`]: the line of twins an ENI describes, each device from an ESI
//!   library or a built-in device.
//! - [`xml`]: the small element tree (with line numbers) both readers use.
//!
//! **Not yet supported** (refused with an error naming the device and,
//! where it is in the file, the element and line): data types the core does not serve (`REAL`, `LREAL`,
//! `UINT24`, `OCTET_STRING`, arrays of bytes), writable PDO mappings, EoE,
//! SoE, AoE. DC op modes are read but the SII of a twin has no DC category
//! yet. Built-in devices (the PAM, IO8, DMA-22) run their real behaviour
//! in a line.

pub mod coe_twin;
pub mod dictionary;
pub mod eni;
pub mod esc_twin;
pub mod esi;
pub mod line;
pub mod sii;
pub mod xml;

pub use esc_twin::{EscTwin, InputRule, InputRules};
pub use esi::{EsiDevice, EsiError, EsiFile};

use std::path::Path;

use ecat_slave::host::chain::LineSlave;

/// `s` as `'static` text: a twin's description lives as long as its line,
/// which a process builds once, so it is leaked on purpose.
pub(crate) fn leak(s: &str) -> &'static str {
    Box::leak(s.to_string().into_boxed_str())
}

/// Identity and names of `dev` for a description (names cut to what
/// ethercrab accepts, [`sii::fit_name`]).
pub(crate) fn identity_and_names(
    dev: &EsiDevice,
) -> (
    ecat_slave::device::Identity,
    ecat_slave::device::DeviceNames,
) {
    (
        ecat_slave::device::Identity {
            vendor_id: dev.vendor_id,
            product_code: dev.product_code,
            revision: dev.revision,
            serial: 0,
        },
        ecat_slave::device::DeviceNames {
            vendor: leak(&dev.vendor_name),
            type_name: leak(sii::fit_name(&dev.type_name)),
            name: leak(sii::fit_name(&dev.name)),
            group_type: leak(sii::fit_name(&dev.group_type)),
            group_name: leak(&dev.group_name),
        },
    )
}

/// Why a twin cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum TwinError {
    /// The file cannot be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The ESI is wrong.
    #[error("{path}: {source}")]
    Esi {
        /// The file.
        path: String,
        /// What is wrong, with element and line.
        source: EsiError,
    },
    /// The SII image cannot be made.
    #[error(transparent)]
    Sii(#[from] sii::SiiBuildError),
    /// The description of a device with a mailbox cannot be made.
    #[error(transparent)]
    Description(#[from] coe_twin::DescriptionBuildError),
}

/// Reads and parses one ESI file.
pub fn load_esi(path: &Path) -> Result<EsiFile, TwinError> {
    let text = std::fs::read_to_string(path).map_err(|source| TwinError::Io {
        path: path.display().to_string(),
        source,
    })?;
    EsiFile::parse(&text).map_err(|source| TwinError::Esi {
        path: path.display().to_string(),
        source,
    })
}

/// The twin of an ESC-only `dev` (no mailbox) with station alias `alias`
/// and input rule `rule`; see [`twin`] for any device.
pub fn esc_twin(
    dev: &EsiDevice,
    alias: Option<u16>,
    rule: InputRule,
) -> Result<EscTwin, TwinError> {
    let image = sii::image(dev, alias)?;
    Ok(EscTwin::new(dev, &image, rule))
}

/// The twin of `dev` with station alias `alias` and input rule `rule`: an
/// [`EscTwin`] for a device without a mailbox, else the core's firmware on
/// a description built from the ESI ([`coe_twin`]). The SII is the ESI's
/// `<Eeprom><Data>` when it has one, else encoded from the description.
pub fn twin(
    dev: &EsiDevice,
    alias: Option<u16>,
    rule: InputRule,
) -> Result<Box<dyn LineSlave>, TwinError> {
    twin_with_modules(dev, alias, rule, None)
}

/// [`twin`] with the modules a modular device holds (`None`: each slot's
/// default module, [`coe_twin::default_modules`]).
pub fn twin_with_modules(
    dev: &EsiDevice,
    alias: Option<u16>,
    rule: InputRule,
    modules: Option<&[u32]>,
) -> Result<Box<dyn LineSlave>, TwinError> {
    if !dev.has_mailbox() {
        return Ok(Box::new(esc_twin(dev, alias, rule)?));
    }
    let (desc, layout) = coe_twin::describe(dev)?;
    let modules = modules.map_or_else(|| coe_twin::default_modules(dev), <[u32]>::to_vec);
    let mut slave = coe_twin::slave(desc, layout, rule, modules);
    let esc = LineSlave::esc_mut(&mut slave);
    if dev.eeprom_data.is_some() {
        esc.program_sii(&sii::image(dev, alias)?);
    } else if let Some(a) = alias {
        esc.program_sii_alias(a);
    }
    esc.power_on();
    Ok(Box::new(slave))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An ESI (or ENI) root with `depth` levels of `<a>` below it, one per
    /// line (250 000 levels: about 2 MB).
    fn deep(root: &str, depth: usize) -> String {
        format!(
            "<{root}>\n{}{}</{root}>",
            "<a>\n".repeat(depth),
            "</a>".repeat(depth)
        )
    }

    #[test]
    fn the_loaders_refuse_a_250000_deep_file_naming_file_and_line() {
        let path = std::env::temp_dir().join(format!("twin-deep-{}.xml", std::process::id()));
        std::fs::write(&path, deep("EtherCATInfo", 250_000)).unwrap();
        let e = load_esi(&path).unwrap_err().to_string();
        let _ = std::fs::remove_file(&path);
        assert!(e.starts_with(&path.display().to_string()), "{e}");
        assert!(
            e.contains("XML error at line 257 ")
                && e.contains("XML nested deeper than 256 elements"),
            "{e}"
        );
        let e = eni::parse(&deep("EtherCATConfig", 250_000)).unwrap_err();
        assert!(matches!(&e, eni::EniError::Xml(x) if x.line == 257), "{e}");
    }
}
