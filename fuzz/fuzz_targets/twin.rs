//! The twin loaders of `ecat-twin`: an ESI file into devices
//! (`EsiFile::parse`), each device into a twin (`ecat_twin::twin`: the SII
//! image from the ESI, the dictionary and description of a device with a
//! mailbox, the ESC-only twin), one poll of each twin, and the same bytes
//! as an ENI (`eni::parse`).
//!
//! Input: bytes, converted lossily to UTF-8.
//!
//! Invariants: no panic; a twin that builds serves an SII image of the
//! emulated EEPROM's size; every error names a line inside the input.
//!
//! A twin's description is leaked on purpose, once per distinct device
//! (`ecat-twin` keeps what it built), so a long run grows with the new
//! devices it finds; the input rule is picked by the input's length to
//! keep one twin per device and input.
#![no_main]

use ecat_twin::{EsiFile, InputRule, eni};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let lines = u32::try_from(text.lines().count() + 1).unwrap_or(u32::MAX);
    match EsiFile::parse(&text) {
        Ok(file) => {
            for (_, e) in &file.refused {
                if let ecat_twin::EsiError::BadValue { at, .. } = e {
                    assert!(at.line <= lines, "{e}");
                }
            }
            for dev in file.devices.iter().take(4) {
                let _ = ecat_twin::warnings(dev);
                let rule = InputRule::ALL[data.len() % 3].1;
                if let Ok(mut t) = ecat_twin::twin(dev, Some(7), rule) {
                    assert!(t.esc().sii().len() >= 128);
                    let _ = t.poll_with(1_000_000, None);
                }
            }
        }
        Err(e) => {
            if let ecat_twin::EsiError::BadValue { at, .. } = &e {
                assert!(at.line <= lines, "{e}");
            }
        }
    }
    let _ = eni::parse(&text);
    // The bytes as a file: decoded by their BOM or declaration.
    let _ = EsiFile::parse_bytes(data);
});
