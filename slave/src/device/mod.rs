//! The device API: all an embedded team writes to put its device on the
//! core.
//!
//! 1. A [`DeviceDescription`]: identity, names, the object dictionary
//!    ([`crate::od::Dictionary`], built with [`crate::dictionary!`] and
//!    [`crate::od::build`]), PDO sets, mailbox and ESC data. `const`, no
//!    heap; [`DeviceDescription::assert_valid`] in a `const` item turns
//!    every contradiction into a build error.
//! 2. An [`Application`]: the device's behaviour (state-change veto, SDO
//!    write hooks with abort codes, the periodic tick with injected time,
//!    safe outputs, power-on and storage).
//!
//! Contradictions do not compile: a description that `validate` refuses
//! fails the `const` assertion. Value storage too small for the dictionary
//! is a programming error that [`Slave::new`] stops with a panic in every
//! build (the description may be made at run time, so this check cannot be
//! a `const`):
//!
//! ```should_panic
//! use ecat_slave::device::*;
//! use ecat_slave::od::build::{constant, sub0, var};
//! use ecat_slave::od::{DataType, Object, ObjectCode, PdoMapping};
//! const OBJECTS: &[Object] = &[
//!     Object { index: 0x1000, name: "Device type", code: ObjectCode::Var,
//!         entries: &[var("Device type", DataType::UInt32, PdoMapping::None, 0)] },
//!     Object { index: 0x1018, name: "Identity", code: ObjectCode::Record, entries: &[
//!         sub0(1), constant(1, "Vendor ID", DataType::UInt32, 1)] },
//! ];
//! ecat_slave::dictionary!(DICT, ENTRIES = OBJECTS, &[]);
//! const DEV: DeviceDescription = DeviceDescription {
//!     identity: Identity { vendor_id: 1, product_code: 1, revision: 1, serial: 0 },
//!     names: DeviceNames { vendor: "V", type_name: "T", name: "T", group_type: "G",
//!         group_name: "G" },
//!     dictionary: &DICT,
//!     process_data: ProcessData { sets: &[] },
//!     mailbox: MailboxConfig::STANDARD,
//!     esc: EscConfig::DEFAULT,
//!     modules: None,
//! };
//! struct Bad;
//! impl Application for Bad {
//!     fn description(&self) -> &'static DeviceDescription {
//!         &DEV
//!     }
//!     type Values = [i64; 2]; // the dictionary has 3 entries
//! }
//! struct NoEsc; // any ESC: a chip driver, or ecat-sim's software ESC
//! impl ecat_slave::esc::Esc for NoEsc {
//!     fn read(&mut self, _: u16, buf: &mut [u8]) -> Result<(), ecat_slave::esc::EscError> {
//!         buf.fill(0);
//!         Ok(())
//!     }
//!     fn write(&mut self, _: u16, _: &[u8]) -> Result<(), ecat_slave::esc::EscError> {
//!         Ok(())
//!     }
//! }
//! let _ = Slave::new(NoEsc, Bad);
//! ```
//!
//! The core does the rest: [`Slave`] is the firmware loop on any ESC
//! reached through the [`Esc`](crate::esc::Esc) PDI trait (`ecat_sim::SoftSlave`
//! runs the same loop on the software ESC). The ESI, the SII ([`DeviceDescription::sii_image`]),
//! SDO Information and the PDO engine all read the one description.

mod application;
mod description;
mod schedule;
mod sii_image;
mod slave;

pub use application::{Application, Changes, ChangesIter, Download, StateChange, Tick, Write};
pub use description::{
    CoeServices, DeviceDescription, DeviceNames, EscConfig, FoeSecurity, Identity, MAX_MAILBOX,
    MailboxConfig, MemoryLayout, PdoSet, ProcessData,
};
pub use schedule::PollSchedule;
pub use sii_image::mapping_entries;
pub use slave::{DC_MIN_CYCLE_NS, FULL_PASS_NS, SM_CONTROL, Slave, SyncMode};
