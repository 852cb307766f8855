//! ESI XML and SII image generation from the `pam-slave` device model.
//!
//! The SII image is produced by the slave's own encoder
//! ([`pam_slave::device::sii_image`]) so the soft ESC and the generated file
//! cannot disagree. ESI XML generation is not implemented yet.

/// The SII EEPROM image of the PAM-199-P-ETC, as the software ESC serves it.
pub fn sii_image() -> Vec<u8> {
    pam_slave::device::sii_image().to_vec()
}
