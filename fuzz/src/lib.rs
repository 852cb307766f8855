//! Harness code shared by the fuzz targets in `fuzz_targets/` and by the
//! seed generator (`examples/seed.rs`).
//!
//! - [`records`]: the record format of the `line_frames` and `mailbox`
//!   inputs (tag, length, body), easy to write for seeds and to mutate;
//! - [`line`]: a line of software PAM slaves driven only through EtherCAT
//!   frames, brought to a state the way a master does it (station
//!   addresses, SyncManagers from the SII, AL control);
//! - [`roundtrip`]: parse → emit → parse checks of the wire formats.

pub mod line;
pub mod records;
pub mod roundtrip;
