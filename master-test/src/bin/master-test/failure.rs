//! Why a command failed, and the exit status that says so.
//!
//! The statuses are the workspace's one scheme, [`device_catalog::exit`].

use device_catalog::exit::Exit;
use master_test::BusError;
use master_test::eeprom::EepromError;
use master_test::mailbox::ClientError;
use std::fmt;
use std::process::ExitCode;

/// A failed command.
#[derive(Debug)]
pub enum Failure {
    /// The device refused (exit 1).
    Refused(String),
    /// A check found mismatches (exit 1); they have been printed.
    Mismatch(String),
    /// Usage or input error (exit 2).
    Input(String),
    /// Communication failure (exit 3).
    Comm(String),
    /// Stopped by Ctrl-C (exit 130); the text says what state it left.
    Interrupted(String),
}

impl Failure {
    /// The process exit status.
    pub fn exit_code(&self) -> ExitCode {
        ExitCode::from(match self {
            Failure::Refused(_) | Failure::Mismatch(_) => Exit::Refused,
            Failure::Input(_) => Exit::Input,
            Failure::Comm(_) => Exit::Comm,
            Failure::Interrupted(_) => Exit::Interrupted,
        })
    }

    /// Adds context in front of the message.
    pub fn context(self, what: impl fmt::Display) -> Self {
        let f = |m: String| format!("{what}: {m}");
        match self {
            Failure::Refused(m) => Failure::Refused(f(m)),
            Failure::Mismatch(m) => Failure::Mismatch(f(m)),
            Failure::Input(m) => Failure::Input(f(m)),
            Failure::Comm(m) => Failure::Comm(f(m)),
            Failure::Interrupted(m) => Failure::Interrupted(f(m)),
        }
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Refused(m) => write!(f, "refused by the device: {m}"),
            Failure::Mismatch(m) | Failure::Input(m) | Failure::Comm(m) => f.write_str(m),
            Failure::Interrupted(m) => write!(f, "stopped by Ctrl-C: {m}"),
        }
    }
}

/// An input error.
pub fn input(m: impl Into<String>) -> Failure {
    Failure::Input(m.into())
}

/// The bytes of a file the user named, or the input error naming it.
pub fn read_file(p: &std::path::Path) -> Result<Vec<u8>, Failure> {
    std::fs::read(p).map_err(|e| input(format!("cannot read {}: {e}", p.display())))
}

impl From<ClientError> for Failure {
    fn from(e: ClientError) -> Self {
        if e.refused_by_device() {
            Failure::Refused(e.to_string())
        } else {
            Failure::Comm(e.to_string())
        }
    }
}

impl From<EepromError> for Failure {
    fn from(e: EepromError) -> Self {
        match e {
            EepromError::Client(c) => c.into(),
            e if e.refused_by_device() => Failure::Refused(e.to_string()),
            e => Failure::Comm(e.to_string()),
        }
    }
}

impl From<ethercrab::error::Error> for Failure {
    fn from(e: ethercrab::error::Error) -> Self {
        use ethercrab::error::{Error, MailboxError};
        match e {
            Error::Mailbox(MailboxError::Aborted { .. }) | Error::SubDevice(_) => {
                Failure::Refused(e.to_string())
            }
            e => Failure::Comm(format!("ethercrab: {e}")),
        }
    }
}

impl From<BusError> for Failure {
    fn from(e: BusError) -> Self {
        match e {
            BusError::Line(_) | BusError::LineTooLong(..) | BusError::Twins(_) => {
                Failure::Input(e.to_string())
            }
            BusError::Ethercrab(e) => e.into(),
            e => Failure::Comm(e.to_string()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refusals_exit_1_input_2_communication_3() {
        let abort = ClientError::Abort {
            index: 0x1018,
            sub: 1,
            code: ecat_slave::wire::coe::SdoAbortCode::from(0x0601_0002u32),
        };
        assert_eq!(Failure::from(abort).exit_code(), ExitCode::from(1));
        let timeout = ClientError::Timeout(std::time::Duration::from_secs(1));
        assert_eq!(Failure::from(timeout).exit_code(), ExitCode::from(3));
        assert_eq!(input("x").exit_code(), ExitCode::from(2));
        assert_eq!(
            Failure::Interrupted("x".into()).exit_code(),
            ExitCode::from(130)
        );
    }
}
