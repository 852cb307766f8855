//! SDO abort codes (ETG.1000.6 Table 41).

macro_rules! abort_codes {
    ($($name:ident = $code:literal => $text:literal,)*) => {
        /// SDO abort code (ETG.1000.6 Table 41 "SDO abort codes").
        ///
        /// Unknown codes are kept as [`SdoAbortCode::Unknown`].
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum SdoAbortCode {
            $(
                #[doc = concat!("`", stringify!($code), "`: ", $text, ".")]
                $name,
            )*
            /// Any other abort code.
            Unknown(u32),
        }

        /// The known codes in the order of the variants: both conversions
        /// index or walk this table instead of a `match` of 35 arms (a few
        /// hundred bytes of firmware each).
        const CODES: &[u32] = &[$($code,)*];

        impl SdoAbortCode {
            /// The known variant at position `n` of [`CODES`] (the
            /// compiler reduces this chain to a store of the tag).
            const fn from_ordinal(n: usize) -> Option<Self> {
                let mut i = 0;
                $(
                    if n == i {
                        return Some(SdoAbortCode::$name);
                    }
                    i += 1;
                )*
                let _ = i;
                None
            }

            /// Position of a known variant in [`CODES`] (the compiler
            /// reduces this `match` to the enum's tag).
            const fn ordinal(self) -> Option<usize> {
                let mut i = 0;
                $(
                    if let SdoAbortCode::$name = self {
                        return Some(i);
                    }
                    i += 1;
                )*
                let _ = i;
                None
            }
        }

        impl From<u32> for SdoAbortCode {
            fn from(raw: u32) -> Self {
                CODES
                    .iter()
                    .position(|code| *code == raw)
                    .and_then(Self::from_ordinal)
                    .unwrap_or(Self::Unknown(raw))
            }
        }

        impl From<SdoAbortCode> for u32 {
            fn from(code: SdoAbortCode) -> Self {
                match code {
                    SdoAbortCode::Unknown(raw) => raw,
                    known => known.ordinal().and_then(|i| CODES.get(i)).copied().unwrap_or(0),
                }
            }
        }

        impl SdoAbortCode {
            /// Human-readable description (ETG.1000.6 Table 41 wording).
            pub const fn description(self) -> &'static str {
                match self {
                    $(Self::$name => $text,)*
                    Self::Unknown(_) => "unknown abort code",
                }
            }

            #[cfg(test)]
            pub(crate) const ALL: &'static [SdoAbortCode] = &[$(Self::$name,)*];
        }
    };
}

abort_codes! {
    ToggleBit = 0x0503_0000 => "toggle bit not changed",
    Timeout = 0x0504_0000 => "SDO protocol timeout",
    UnknownCommand = 0x0504_0001 => "client/server command specifier not valid or unknown",
    InvalidBlockSize = 0x0504_0002 => "invalid block size",
    OutOfMemory = 0x0504_0005 => "out of memory",
    UnsupportedAccess = 0x0601_0000 => "unsupported access to an object",
    WriteOnly = 0x0601_0001 => "attempt to read a write-only object",
    ReadOnly = 0x0601_0002 => "attempt to write a read-only object",
    SubindexCannotBeWritten = 0x0601_0003 =>
        "subindex cannot be written, SI0 must be 0 for write access",
    CompleteAccessNotSupported = 0x0601_0004 =>
        "SDO complete access not supported for objects of variable length",
    ObjectTooLong = 0x0601_0005 => "object length exceeds mailbox size",
    ObjectMappedToRxPdo = 0x0601_0006 => "object mapped to RxPDO, SDO download blocked",
    ObjectNotFound = 0x0602_0000 => "the object does not exist in the object dictionary",
    CannotMap = 0x0604_0041 => "the object cannot be mapped into the PDO",
    PdoLengthExceeded = 0x0604_0042 =>
        "the number and length of the objects to be mapped would exceed the PDO length",
    ParameterIncompatible = 0x0604_0043 => "general parameter incompatibility reason",
    InternalIncompatible = 0x0604_0047 => "general internal incompatibility in the device",
    HardwareError = 0x0606_0000 => "access failed due to a hardware error",
    LengthMismatch = 0x0607_0010 =>
        "data type does not match, length of service parameter does not match",
    LengthTooHigh = 0x0607_0012 => "data type does not match, length of service parameter too high",
    LengthTooLow = 0x0607_0013 => "data type does not match, length of service parameter too low",
    SubindexNotFound = 0x0609_0011 => "subindex does not exist",
    ValueRange = 0x0609_0030 => "value range of parameter exceeded (only for write access)",
    ValueTooHigh = 0x0609_0031 => "value of parameter written too high",
    ValueTooLow = 0x0609_0032 => "value of parameter written too low",
    MaxBelowMin = 0x0609_0036 => "maximum value is less than minimum value",
    GeneralError = 0x0800_0000 => "general error",
    TransferFailed = 0x0800_0020 => "data cannot be transferred or stored to the application",
    LocalControl = 0x0800_0021 =>
        "data cannot be transferred or stored to the application because of local control",
    InvalidState = 0x0800_0022 =>
        "data cannot be transferred or stored to the application in the present device state",
    NoObjectDictionary = 0x0800_0023 =>
        "object dictionary dynamic generation fails or no object dictionary is present",
}

impl core::fmt::Display for SdoAbortCode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:#010x}: {}", u32::from(*self), self.description())
    }
}
