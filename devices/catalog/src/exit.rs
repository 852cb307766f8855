//! The exit statuses of the workspace's tools (`master-test`, `esi`,
//! `pam-slave`; all three link this catalog): one scheme, documented in
//! their `--help` and in the book's commissioning chapter.
//!
//! | status | meaning |
//! |---|---|
//! | 0 | done (also when the reader of the output went away) |
//! | 1 | the device refused (SDO abort, FoE error, AL status code, EEPROM error) or a check found mismatches |
//! | 2 | usage or input error: bad argument, file or value; nothing was sent |
//! | 3 | communication failure: no slave, no answer, an interface that cannot be opened or a link that died |
//! | 130 | stopped by Ctrl-C before the command finished |

use std::process::ExitCode;

/// Why a tool ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// Done (status 0).
    Done,
    /// The device refused, or a check found mismatches (status 1).
    Refused,
    /// Usage or input error; nothing was sent (status 2).
    Input,
    /// Communication failure (status 3).
    Comm,
    /// Stopped by Ctrl-C (status 130).
    Interrupted,
}

impl Exit {
    /// The process exit status.
    pub const fn status(self) -> u8 {
        match self {
            Exit::Done => 0,
            Exit::Refused => 1,
            Exit::Input => 2,
            Exit::Comm => 3,
            Exit::Interrupted => 130,
        }
    }
}

impl From<Exit> for ExitCode {
    fn from(e: Exit) -> Self {
        ExitCode::from(e.status())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statuses_are_the_documented_ones() {
        let all = [
            Exit::Done,
            Exit::Refused,
            Exit::Input,
            Exit::Comm,
            Exit::Interrupted,
        ];
        assert_eq!(all.map(Exit::status), [0, 1, 2, 3, 130]);
    }
}
