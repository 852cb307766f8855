//! Error replies: the ERR byte (0x83, 0x86, 0x8F) and the exception codes
//! (EXCE) of 4.1.3 (CMD 3), 4.3.3 (CMD 6) and 5.3 (CMD 15).
//!
//! The three tables differ (e.g. exception 3 is "CNT == 0 or CNT > 16" for
//! a read but "Wrong Data Value" for a write, and only CMD 15 has codes 7,
//! 8, 9), so each command has its own enum. Codes the manual does not list
//! are kept as `Other(raw)`; `From<u8>` never produces `Other` for a listed
//! code.

use super::Command;

/// Declares an exception enum with its code table, `From<u8>`,
/// `From<Enum> for u8`, `description` and `Display`.
macro_rules! exception_table {
    (
        $(#[$meta:meta])*
        $name:ident {
            $( $(#[$vmeta:meta])* $variant:ident = $code:literal => $text:literal, )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $name {
            $( $(#[$vmeta])* $variant, )*
            /// A code the manual does not list for this command.
            Other(u8),
        }

        impl From<u8> for $name {
            fn from(raw: u8) -> Self {
                match raw {
                    $( $code => Self::$variant, )*
                    other => Self::Other(other),
                }
            }
        }

        impl From<$name> for u8 {
            fn from(exception: $name) -> Self {
                match exception {
                    $( $name::$variant => $code, )*
                    $name::Other(raw) => raw,
                }
            }
        }

        impl $name {
            /// The manual's wording for this code.
            pub const fn description(self) -> &'static str {
                match self {
                    $( Self::$variant => $text, )*
                    Self::Other(_) => "exception code not listed in the manual",
                }
            }
        }

        impl core::fmt::Display for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                write!(f, "{}: {}", u8::from(*self), self.description())
            }
        }
    };
}

exception_table! {
    /// Exception of a failed CMD 3 read, ERR = 0x83 "Read failed" (4.1.3;
    /// Profibus manual 3.3).
    ReadException {
        /// 1: the command is not supported.
        CommandNotSupported = 1 => "Command not supported",
        /// 2: the parameter ID is wrong.
        WrongId = 2 => "Wrong ID",
        /// 3: the number of words is 0 or more than 8 (CNT == 0 or
        /// CNT > 16 bytes).
        CntOutOfRange = 3 => "CNT == 0 or CNT > 16 (0x10)",
        /// 4: reading the ID failed.
        ReadFailed = 4 => "Reading of ID failed",
        /// 5: the module did not answer: address wrong, module not
        /// installed, or an invalid number of connected modules.
        SlaveTimeout = 5 => "timeout slave, address wrong or not installed or Invalid number of connected slaves",
        /// 6: checksum error on the node's internal (Modbus) link.
        ChecksumError = 6 => "Internal checksum error (Modbus)",
    }
}

exception_table! {
    /// Exception of a failed CMD 6 write, ERR = 0x86 "write failed"
    /// (4.3.3; Profibus manual 3.6).
    WriteException {
        /// 1: the command is not supported.
        CommandNotSupported = 1 => "Command not supported",
        /// 2: the parameter ID is wrong.
        WrongId = 2 => "Wrong ID",
        /// 3: the value is out of the parameter's range.
        WrongDataValue = 3 => "Wrong Data Value",
        /// 4: writing the ID failed.
        WriteFailed = 4 => "Writing of ID failed",
        /// 5: the module did not answer: address wrong, module not
        /// installed, or an invalid number of connected modules.
        SlaveTimeout = 5 => "timeout slave, address wrong or not installed or Invalid number of connected slaves",
        /// 6: checksum error on the node's internal (Modbus) link.
        ChecksumError = 6 => "Internal checksum error (Modbus)",
    }
}

exception_table! {
    /// Exception of a failed CMD 15, ERR = 0x8F "write failed" (5.3;
    /// Profibus manual 4.3).
    MultiWriteException {
        /// 1: the command is not supported.
        CommandNotSupported = 1 => "Command not supported",
        /// 2: wrong ID.
        WrongId = 2 => "Wrong ID",
        /// 3: a value is out of range.
        WrongDataValue = 3 => "Wrong Data Value",
        /// 4: writing failed.
        WriteFailed = 4 => "Writing of ID failed",
        /// 5: timeout on the node's internal (Modbus) link.
        ModbusTimeout = 5 => "timeout (Modbus)",
        /// 6: checksum error on the node's internal (Modbus) link.
        ChecksumError = 6 => "Internal checksum error (Modbus)",
        /// 7: SNUM does not match the connected modules.
        InvalidSlaveCount = 7 => "Invalid number of connected slaves",
        /// 8: a module did not answer: address wrong or not installed.
        SlaveTimeout = 8 => "timeout slave, address wrong or not installed",
        /// 9: sent by the node itself (SADR = 0): the received data is
        /// shorter than the telegram (the configured I/O size is too
        /// small).
        DataLengthTooSmall = 9 => "Ethernet node (SADR = 0) send, received data length to small",
    }
}

/// The exception of an error reply, tagged with the command that failed
/// (which the ERR byte names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Exception {
    /// ERR = 0x83, CMD 3 failed.
    Read(ReadException),
    /// ERR = 0x86, CMD 6 failed.
    Write(WriteException),
    /// ERR = 0x8F, CMD 15 failed.
    MultiWrite(MultiWriteException),
}

impl Exception {
    /// Decodes the EXCE byte in the table of `command`.
    pub fn new(command: Command, code: u8) -> Self {
        match command {
            Command::Read => Self::Read(code.into()),
            Command::Write => Self::Write(code.into()),
            Command::MultiWrite => Self::MultiWrite(code.into()),
        }
    }

    /// The command that failed.
    pub const fn command(self) -> Command {
        match self {
            Self::Read(_) => Command::Read,
            Self::Write(_) => Command::Write,
            Self::MultiWrite(_) => Command::MultiWrite,
        }
    }

    /// The ERR byte: 0x83, 0x86 or 0x8F.
    pub const fn error_code(self) -> u8 {
        self.command().error_code()
    }

    /// The EXCE byte.
    pub fn code(self) -> u8 {
        match self {
            Self::Read(e) => e.into(),
            Self::Write(e) => e.into(),
            Self::MultiWrite(e) => e.into(),
        }
    }

    /// The manual's wording for the exception.
    pub const fn description(self) -> &'static str {
        match self {
            Self::Read(e) => e.description(),
            Self::Write(e) => e.description(),
            Self::MultiWrite(e) => e.description(),
        }
    }
}

impl core::fmt::Display for Exception {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "ERR {:#04x}, EXCE {}: {}",
            self.error_code(),
            self.code(),
            self.description()
        )
    }
}

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::*;

    #[test]
    fn every_code_round_trips_and_listed_codes_are_named() {
        for raw in 0..=u8::MAX {
            for cmd in [Command::Read, Command::Write, Command::MultiWrite] {
                let e = Exception::new(cmd, raw);
                assert_eq!(e.code(), raw);
                assert_eq!(e.command(), cmd);
                assert!(!e.description().is_empty());
            }
            let listed_read = (1..=6).contains(&raw);
            assert_eq!(
                matches!(ReadException::from(raw), ReadException::Other(_)),
                !listed_read
            );
            assert_eq!(
                matches!(WriteException::from(raw), WriteException::Other(_)),
                !listed_read
            );
            assert_eq!(
                matches!(
                    MultiWriteException::from(raw),
                    MultiWriteException::Other(_)
                ),
                !(1..=9).contains(&raw)
            );
        }
    }

    #[test]
    fn the_tables_differ_where_the_manual_differs() {
        assert_eq!(ReadException::from(3), ReadException::CntOutOfRange);
        assert_eq!(WriteException::from(3), WriteException::WrongDataValue);
        assert_eq!(ReadException::from(5), ReadException::SlaveTimeout);
        assert_eq!(
            MultiWriteException::from(5),
            MultiWriteException::ModbusTimeout
        );
        assert_eq!(
            MultiWriteException::from(8),
            MultiWriteException::SlaveTimeout
        );
        assert_eq!(ReadException::from(8), ReadException::Other(8));
    }

    #[test]
    fn display_names_err_and_exce() {
        assert_eq!(
            Exception::MultiWrite(MultiWriteException::SlaveTimeout).to_string(),
            "ERR 0x8f, EXCE 8: timeout slave, address wrong or not installed"
        );
        assert_eq!(
            ReadException::Other(0).to_string(),
            "0: exception code not listed in the manual"
        );
        assert_eq!(Exception::new(Command::Write, 4).error_code(), 0x86);
    }
}
