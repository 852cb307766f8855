//! Twins for `pam-slave --esi` and `--eni` (see the `ecat-twin` crate):
//! one device of an ESI file, or the line an ENI describes with each slave
//! taken from the catalog (by vendor ID and product code) or from the ESI
//! files of a directory.

use std::path::Path;

use ecat_sim::chain::LineSlave;
use ecat_twin::eni::{self, EniSlave};
use ecat_twin::line::{self, BuiltLine, EsiLibrary};
use ecat_twin::{InputRules, TwinError};

use crate::{DEVICES, Pdi};

/// Why a twin or a line of twins cannot start (the message names the
/// file, element and line, or the slaves nothing matched).
#[derive(Debug, thiserror::Error)]
pub enum TwinsError {
    /// An ESI file or the device in it.
    #[error(transparent)]
    Twin(#[from] TwinError),
    /// The ENI file cannot be read.
    #[error("{path}: {source}")]
    EniIo {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The ENI is wrong.
    #[error("{path}: {source}")]
    Eni {
        /// The file.
        path: String,
        /// What, with element and line.
        source: eni::EniError,
    },
    /// The line cannot be built.
    #[error(transparent)]
    Line(#[from] line::LineError),
    /// `--revision` is not a number.
    #[error("bad revision '{0}' (decimal or 0x hex)")]
    BadRevision(String),
}

/// The catalog device with the ENI slave's vendor ID and product code (the
/// first of equal ones), as a software slave in its power-on state.
pub fn builtin(s: &EniSlave) -> Option<(String, Box<dyn LineSlave>)> {
    DEVICES
        .iter()
        .find(|d| {
            d.description.identity.vendor_id == s.vendor_id
                && d.description.identity.product_code == s.product_code
        })
        .map(|d| (d.key.to_string(), (d.make)(Pdi::Direct)))
}

/// Parses `--revision`: decimal or `0x` hex.
pub fn parse_revision(s: &str) -> Result<u32, TwinsError> {
    eni::number(s)
        .and_then(|v| u32::try_from(v).ok())
        .ok_or_else(|| TwinsError::BadRevision(s.to_string()))
}

/// What [`from_esi`] makes: the device's label, its twins, and what they
/// leave out of the ESI or assume.
pub type FromEsi = (
    String,
    Vec<Box<dyn LineSlave>>,
    Vec<ecat_twin::esi::Warning>,
);

/// `count` twins of the device `type_name`/`revision` of the ESI file
/// `path` (either may be omitted when the file has one device type), and
/// what the twin leaves out of the ESI or assumes.
pub fn from_esi(
    path: &Path,
    type_name: Option<&str>,
    revision: Option<u32>,
    rules: &InputRules,
    count: usize,
) -> Result<FromEsi, TwinsError> {
    let file = ecat_twin::load_esi(path)?;
    let dev = file
        .device(type_name, revision)
        .map_err(|source| TwinError::Esi {
            path: path.display().to_string(),
            source,
        })?;
    let mut slaves: Vec<Box<dyn LineSlave>> = Vec::with_capacity(count);
    for _ in 0..count {
        slaves.push(ecat_twin::twin(dev, None, rules.for_type(&dev.type_name))?);
    }
    let warnings = ecat_twin::warnings(dev)?;
    Ok((dev.label(), slaves, warnings))
}

/// The devices of the ESI file `path`, one line each: `TYPE rev 0x...
/// product 0x... NAME`, and the devices that do not load with the reason.
pub fn list_esi(path: &Path) -> Result<Vec<String>, TwinsError> {
    let file = ecat_twin::load_esi(path)?;
    let mut out: Vec<String> = file
        .devices
        .iter()
        .map(|d| format!("{} product {:#010x} {}", d.label(), d.product_code, d.name))
        .collect();
    out.extend(
        file.refused
            .iter()
            .map(|(label, e)| format!("{label} does not load: {}: {e}", path.display())),
    );
    Ok(out)
}

/// The line the ENI file `eni_path` describes, devices from the catalog
/// or the ESI files of `esi_dir`.
pub fn from_eni(
    eni_path: &Path,
    esi_dir: Option<&Path>,
    rules: &InputRules,
) -> Result<BuiltLine, TwinsError> {
    let text = std::fs::read_to_string(eni_path).map_err(|source| TwinsError::EniIo {
        path: eni_path.display().to_string(),
        source,
    })?;
    let slaves = eni::parse(&text).map_err(|source| TwinsError::Eni {
        path: eni_path.display().to_string(),
        source,
    })?;
    let lib = match esi_dir {
        Some(d) => EsiLibrary::load_dir(d)?,
        None => EsiLibrary::default(),
    };
    Ok(line::build(&slaves, &lib, &builtin, rules)?)
}
