//! The SDO Information header (ETG.1000.6 §5.6.3): opcode, incomplete
//! flag, fragments left.

use super::*;
use crate::codes::protocol_codes;

protocol_codes! {
    /// SDO information opcode (ETG.1000.6 §5.6.3.2, SDO information header
    /// "OpCode").
    ///
    /// Each variant's discriminant is its code (`repr(u8)`): the conversion
    /// to `u8` compiles to the tag. `Unknown`'s tag is not a code.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum SdoInfoOpcode(u8) {
        /// `1` Get OD list request.
        GetOdListReq = 1,
        /// `2` Get OD list response.
        GetOdListResp = 2,
        /// `3` Get object description request.
        GetObjDescReq = 3,
        /// `4` Get object description response.
        GetObjDescResp = 4,
        /// `5` Get entry description request.
        GetEntryDescReq = 5,
        /// `6` Get entry description response.
        GetEntryDescResp = 6,
        /// `7` SDO information error request.
        SdoInfoErrorReq = 7,
    } else {
        /// Any other value.
        Unknown = 0xFF,
    }
}

pub(super) const INFO_INCOMPLETE: u8 = 0x80;
pub(super) const INFO_OPCODE_MASK: u8 = 0x7F;

/// A read/write view of an SDO information message after the CoE header:
/// 4-byte header and service data (ETG.1000.6 §5.6.3.2 "SDO Information
/// header").
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SdoInfo<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> SdoInfo<T> {
    /// Wraps a buffer without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`SdoInfo::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let info = Self::new_unchecked(buffer);
        info.check_len()?;
        Ok(info)
    }

    /// Checks that the 4-byte header is present ([`WireError::Truncated`]
    /// otherwise).
    pub fn check_len(&self) -> Result<(), WireError> {
        if self.buffer.as_ref().len() < SDO_INFO_HEADER_LEN {
            Err(WireError::Truncated)
        } else {
            Ok(())
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The opcode (bits 0..=6 of byte 0).
    pub fn opcode(&self) -> SdoInfoOpcode {
        SdoInfoOpcode::from(
            crate::wire::get_u8(self.buffer.as_ref(), field::INFO_OPCODE) & INFO_OPCODE_MASK,
        )
    }

    /// The incomplete flag (bit 7 of byte 0): more fragments follow.
    pub fn incomplete(&self) -> bool {
        crate::wire::get_u8(self.buffer.as_ref(), field::INFO_OPCODE) & INFO_INCOMPLETE != 0
    }

    /// The reserved byte 1.
    pub fn reserved(&self) -> u8 {
        crate::wire::get_u8(self.buffer.as_ref(), field::INFO_RESERVED)
    }

    /// Number of fragments still to come after this one.
    pub fn fragments_left(&self) -> u16 {
        crate::wire::get_u16_le(self.buffer.as_ref(), field::INFO_FRAGMENTS_LEFT)
    }

    /// The service data after the header.
    pub fn payload(&self) -> &[u8] {
        crate::wire::tail(self.buffer.as_ref(), field::INFO_DATA)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> SdoInfo<T> {
    /// Sets the opcode (masked to 7 bits), keeping the incomplete flag.
    pub fn set_opcode(&mut self, op: SdoInfoOpcode) {
        let b = crate::wire::get_u8(self.buffer.as_ref(), field::INFO_OPCODE);
        let b = (b & INFO_INCOMPLETE) | (u8::from(op) & INFO_OPCODE_MASK);
        crate::wire::set_u8(self.buffer.as_mut(), field::INFO_OPCODE, b);
    }

    /// Sets or clears the incomplete flag.
    pub fn set_incomplete(&mut self, incomplete: bool) {
        let b = crate::wire::get_u8(self.buffer.as_ref(), field::INFO_OPCODE);
        let b = if incomplete {
            b | INFO_INCOMPLETE
        } else {
            b & !INFO_INCOMPLETE
        };
        crate::wire::set_u8(self.buffer.as_mut(), field::INFO_OPCODE, b);
    }

    /// Sets the reserved byte.
    pub fn set_reserved(&mut self, value: u8) {
        crate::wire::set_u8(self.buffer.as_mut(), field::INFO_RESERVED, value);
    }

    /// Sets the number of fragments left.
    pub fn set_fragments_left(&mut self, n: u16) {
        crate::wire::set_u16_le(self.buffer.as_mut(), field::INFO_FRAGMENTS_LEFT, n);
    }

    /// The mutable service data after the header.
    pub fn payload_mut(&mut self) -> &mut [u8] {
        crate::wire::tail_mut(self.buffer.as_mut(), field::INFO_DATA)
    }
}

/// High-level representation of an SDO information header (ETG.1000.6
/// §5.6.3.2); the service data is handled by the SDO information server.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SdoInfoRepr {
    /// Opcode.
    pub opcode: SdoInfoOpcode,
    /// More fragments follow.
    pub incomplete: bool,
    /// Fragments still to come.
    pub fragments_left: u16,
}

impl SdoInfoRepr {
    /// Parses the header.
    pub fn parse<T: AsRef<[u8]>>(info: &SdoInfo<T>) -> Result<Self, WireError> {
        info.check_len()?;
        Ok(Self {
            opcode: info.opcode(),
            incomplete: info.incomplete(),
            fragments_left: info.fragments_left(),
        })
    }

    /// Length of the header ([`SDO_INFO_HEADER_LEN`]).
    pub const fn buffer_len(&self) -> usize {
        SDO_INFO_HEADER_LEN
    }

    /// Writes the header (reserved byte zeroed).
    ///
    /// Fails with [`WireError::Unrepresentable`] for opcodes above 0x7F and
    /// with [`WireError::BufferTooSmall`] if the header does not fit.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        info: &mut SdoInfo<T>,
    ) -> Result<(), WireError> {
        if u8::from(self.opcode) > INFO_OPCODE_MASK {
            return Err(WireError::Unrepresentable);
        }
        info.check_len().map_err(|_| WireError::BufferTooSmall)?;
        info.set_opcode(self.opcode);
        info.set_incomplete(self.incomplete);
        info.set_reserved(0);
        info.set_fragments_left(self.fragments_left);
        Ok(())
    }
}
