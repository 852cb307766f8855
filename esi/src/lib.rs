//! ESI XML and SII image tooling for any device on the `ecat-slave` core
//! (host tools).
//!
//! Everything is generated from the device's description (the one the
//! slave runs), so the EtherCAT master's view (ESI), the EEPROM (SII) and
//! the firmware cannot disagree:
//!
//! - [`sii_image`] is the SII EEPROM image as the slave's own encoder
//!   ([`DeviceDescription::sii_image`]) produces it; [`ihex`] writes it as
//!   Intel HEX (with the `ihex` crate).
//! - [`esi::generate`] writes the ETG.2000 v1.17 ESI XML (dictionary, PDOs,
//!   SyncManagers, mailbox, EEPROM, alternative PDO assignments) with
//!   quick-xml's writer.
//! - [`inspect::inspect`] decodes any SII image (ours or a vendor's dump)
//!   into a listing or JSON (serde_json, schema in [`inspect`]), reporting
//!   broken images instead of failing.
//! - [`check::check`] cross-checks an ESI file against an SII image.
//!
//! The `esi` binary (`src/main.rs`) puts these behind a command line. This
//! crate is a host tool: it may allocate and use `std`, but it never
//! restates device data by hand.

pub mod check;
pub mod esi;
pub mod ihex;
pub mod inspect;
/// The XML element tree the readers use (it lives in `ecat-twin`, which
/// also reads ESI files).
pub use ecat_twin::xml;

use ecat_slave::device::DeviceDescription;
pub use esi::generate;

/// The SII EEPROM image of `dev`, as the software ESC serves it, as long
/// as the device's EEPROM (`eeprom_kbit`; the software ESC's buffer may be
/// larger).
pub fn sii_image(dev: &DeviceDescription) -> Vec<u8> {
    let mut image = dev.sii_image().to_vec();
    image.truncate(
        usize::from(dev.esc.eeprom_kbit)
            .saturating_mul(128)
            .max(128),
    );
    image
}
