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
//! The core does the rest: [`Slave`] is the firmware loop on any ESC
//! reached through the [`Esc`](crate::esc::Esc) PDI trait, [`SoftSlave`] the
//! same on the software ESC. The ESI, the SII ([`DeviceDescription::sii_image`]),
//! SDO Information and the PDO engine all read the one description.

mod application;
mod description;
mod sii_image;
mod slave;
mod soft;

pub use application::{Application, Download, StateChange, Tick, Write};
pub use description::{
    CoeServices, DeviceDescription, DeviceNames, EscConfig, Identity, MAX_MAILBOX, MailboxConfig,
    MemoryLayout, PdoSet, ProcessData,
};
pub use sii_image::mapping_entries;
pub use slave::{SM_CONTROL, Slave};
pub use soft::SoftSlave;
