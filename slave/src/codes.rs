//! One declaration per protocol-code enum (the AL status codes, the
//! mailbox, CoE, FoE and SDO Information codes): each code is written
//! once, as its variant's discriminant, and both conversions are generated
//! from that one list, so they cannot disagree.
//!
//! ```text
//! protocol_codes! {
//!     /// docs
//!     pub enum FoeOpcode(u8) {
//!         /// docs
//!         ReadRequest = 1,
//!         ...
//!     } else {
//!         /// Any other value.
//!         Unknown = 0xFF,
//!     }
//! }
//! ```
//!
//! declares the enum with `#[repr(u8)]`, each listed variant's tag its
//! code and, from the `else` block, a last variant `Unknown(u8)` (tag
//! `0xFF`, not a code: the raw value is its field), and:
//!
//! * `const fn from_code(raw) -> Self`: the listed variant, else the last
//!   one holding `raw`;
//! * `const fn code(self) -> raw`: the variant's code (the tag itself for
//!   a listed variant: the compiler reads it instead of a `match` of every
//!   arm, which is why the codes are discriminants);
//! * `From<raw>` and `From<enum> for raw`, the same two;
//! * in tests, `LISTED`: every listed variant with its code.
//!
//! The SDO abort codes are not declared so: as discriminants, their
//! conversion from `u32` compiled to a tree of comparisons (+280 B of
//! Cortex-M4 code against their table; see `wire::coe::abort`).

/// See the [module](self).
macro_rules! protocol_codes {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident($raw:ident) {
            $( $(#[$vmeta:meta])* $variant:ident = $code:literal, )*
        } else {
            $(#[$ometa:meta])* $other:ident = $tag:literal $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr($raw)]
        $vis enum $name {
            $( $(#[$vmeta])* $variant = $code, )*
            $(#[$ometa])* $other($raw) = $tag,
        }

        impl $name {
            /// Decodes a raw code: its variant, or the catch-all variant
            /// holding it.
            pub const fn from_code(raw: $raw) -> Self {
                match raw {
                    $( $code => Self::$variant, )*
                    other => Self::$other(other),
                }
            }

            /// The raw code.
            pub const fn code(self) -> $raw {
                match self {
                    $( Self::$variant => $code, )*
                    Self::$other(raw) => raw,
                }
            }

            /// Every listed variant with its code, for the tests.
            #[cfg(test)]
            pub(crate) const LISTED: &'static [(Self, $raw)] = &[$( (Self::$variant, $code), )*];
        }

        impl From<$raw> for $name {
            fn from(raw: $raw) -> Self {
                Self::from_code(raw)
            }
        }

        impl From<$name> for $raw {
            fn from(code: $name) -> Self {
                code.code()
            }
        }
    };
}

pub(crate) use protocol_codes;

#[cfg(test)]
mod tests {
    use crate::al::AlStatusCode;
    use crate::wire::coe::{CoeService, SdoInfoOpcode};
    use crate::wire::foe::{FoeErrorCode, FoeOpcode};
    use crate::wire::mailbox::{MailboxErrorCode, MailboxType};

    /// Every raw value of a `u8` or `u16` code converts to a variant and
    /// back to itself; exactly the listed codes give listed variants.
    macro_rules! check_all_values {
        ($name:ident, $other:ident, $raw:ty) => {{
            for raw in <$raw>::MIN..=<$raw>::MAX {
                let v = $name::from(raw);
                assert_eq!(<$raw>::from(v), raw, "{} {raw:#x}", stringify!($name));
                let listed = $name::LISTED.iter().find(|(_, c)| *c == raw);
                match listed {
                    Some((variant, _)) => assert_eq!(v, *variant),
                    None => assert_eq!(v, $name::$other(raw)),
                }
            }
            for (variant, code) in $name::LISTED {
                assert_eq!(variant.code(), *code);
            }
        }};
    }

    #[test]
    fn every_code_of_8_and_16_bits_round_trips_through_its_enum() {
        check_all_values!(FoeOpcode, Unknown, u8);
        check_all_values!(MailboxType, Unknown, u8);
        check_all_values!(CoeService, Unknown, u8);
        check_all_values!(SdoInfoOpcode, Unknown, u8);
        check_all_values!(MailboxErrorCode, Unknown, u16);
        check_all_values!(AlStatusCode, Other, u16);
    }

    #[test]
    fn foe_error_codes_round_trip_and_unlisted_ones_stay_unknown() {
        for &(variant, code) in FoeErrorCode::LISTED {
            assert_eq!(FoeErrorCode::from(code), variant);
            assert_eq!(u32::from(variant), code);
        }
        for raw in [0, 1, 0x7FFF, 0x800E, 0x8012, 0xFFFF, 0xFFFF_FFFF, 0x1_8001] {
            assert_eq!(FoeErrorCode::from(raw), FoeErrorCode::Unknown(raw));
            assert_eq!(u32::from(FoeErrorCode::Unknown(raw)), raw);
        }
        // The codes of ETG.1000.6 §5.8 and the SSC's, 0x8000..=0x8011
        // without 0x800E.
        let listed: heapless::Vec<u32, 32> = FoeErrorCode::LISTED.iter().map(|(_, c)| *c).collect();
        let expected: heapless::Vec<u32, 32> = (0x8000..=0x8011).filter(|c| *c != 0x800E).collect();
        assert_eq!(listed, expected);
    }
}
