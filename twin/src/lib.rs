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
//! - [`esc_twin`]: the twin of a device without a firmware (couplers,
//!   digital I/O terminals: ESC and EEPROM only).
//! - [`eni`]: the slaves of an ENI.
//! - [`line`]: the line of twins an ENI describes, each device from an ESI
//!   library or a built-in device.
//! - [`xml`]: the small element tree (with line numbers) both readers use.
//!
//! **Not yet supported** (refused with an error naming the device): twins
//! of devices with a mailbox (CoE, FoE, EoE...) from their ESI alone; those
//! need the core's CoE server run on a description built at run time.
//! Built-in devices (the PAM, IO8, DMA-22) take their place in a line.
//! DC op modes are read but the SII of a twin has no DC category yet.

pub mod eni;
pub mod esc_twin;
pub mod esi;
pub mod line;
pub mod sii;
pub mod xml;

pub use esc_twin::{EscTwin, InputRule};
pub use esi::{EsiDevice, EsiError, EsiFile};

use std::path::Path;

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
    /// The device has a mailbox: not yet supported from an ESI.
    #[error(
        "{device}: devices with a mailbox (protocols {protocols:#06x}) cannot be twinned from their ESI yet; \
         only ESC-only devices (couplers, digital I/O terminals) can, or a built-in device"
    )]
    MailboxUnsupported {
        /// The device.
        device: String,
        /// Its mailbox protocol bits.
        protocols: u16,
    },
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

/// The twin of `dev` with station alias `alias` and input rule `rule`.
pub fn twin(dev: &EsiDevice, alias: Option<u16>, rule: InputRule) -> Result<EscTwin, TwinError> {
    if dev.has_mailbox() {
        return Err(TwinError::MailboxUnsupported {
            device: dev.label(),
            protocols: dev.mailbox_protocols,
        });
    }
    let image = sii::image(dev, alias)?;
    Ok(EscTwin::new(dev, &image, rule))
}
