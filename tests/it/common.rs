//! Helpers shared by the integration tests.

use ethercrab::error::{Error, MailboxError};

/// The CoE abort code inside an ethercrab SDO error, if it is one.
pub fn abort_code(e: &Error) -> Option<u32> {
    match e {
        Error::Mailbox(MailboxError::Aborted { code, .. }) => Some(u32::from(*code)),
        _ => None,
    }
}
