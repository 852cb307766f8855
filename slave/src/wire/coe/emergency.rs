//! The Emergency message (ETG.1000.6 §5.6.4): error code, error
//! register, data.

use super::*;

/// A read/write view of an emergency message after the CoE header
/// (ETG.1000.6 §5.6.4 "Emergency": error code, error register, 5 bytes of
/// manufacturer-specific data).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Emergency<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Emergency<T> {
    /// Wraps a buffer without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`Emergency::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let e = Self::new_unchecked(buffer);
        e.check_len()?;
        Ok(e)
    }

    /// Checks that the 8-byte message is present ([`WireError::Truncated`]
    /// otherwise).
    pub fn check_len(&self) -> Result<(), WireError> {
        if self.buffer.as_ref().len() < EMERGENCY_LEN {
            Err(WireError::Truncated)
        } else {
            Ok(())
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The error code (CiA 301 emergency error code).
    pub fn error_code(&self) -> u16 {
        crate::wire::get_u16_le(self.buffer.as_ref(), field::EMCY_CODE)
    }

    /// The error register (value of object 0x1001).
    pub fn error_register(&self) -> u8 {
        crate::wire::get_u8(self.buffer.as_ref(), field::EMCY_REGISTER)
    }

    /// The five manufacturer-specific data bytes.
    pub fn data(&self) -> [u8; 5] {
        crate::wire::get_array(self.buffer.as_ref(), field::EMCY_DATA)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Emergency<T> {
    /// Sets the error code.
    pub fn set_error_code(&mut self, code: u16) {
        crate::wire::set_u16_le(self.buffer.as_mut(), field::EMCY_CODE, code);
    }

    /// Sets the error register.
    pub fn set_error_register(&mut self, register: u8) {
        crate::wire::set_u8(self.buffer.as_mut(), field::EMCY_REGISTER, register);
    }

    /// Sets the manufacturer-specific data.
    pub fn set_data(&mut self, data: [u8; 5]) {
        crate::wire::set_array(self.buffer.as_mut(), field::EMCY_DATA, data);
    }
}

/// High-level representation of an emergency message (ETG.1000.6 §5.6.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EmergencyRepr {
    /// Error code.
    pub error_code: u16,
    /// Error register.
    pub error_register: u8,
    /// Manufacturer-specific data.
    pub data: [u8; 5],
}

impl EmergencyRepr {
    /// Parses an emergency message.
    pub fn parse<T: AsRef<[u8]>>(e: &Emergency<T>) -> Result<Self, WireError> {
        e.check_len()?;
        Ok(Self {
            error_code: e.error_code(),
            error_register: e.error_register(),
            data: e.data(),
        })
    }

    /// Length of the message ([`EMERGENCY_LEN`]).
    pub const fn buffer_len(&self) -> usize {
        EMERGENCY_LEN
    }

    /// Writes the message; [`WireError::BufferTooSmall`] if it does not fit.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        e: &mut Emergency<T>,
    ) -> Result<(), WireError> {
        e.check_len().map_err(|_| WireError::BufferTooSmall)?;
        e.set_error_code(self.error_code);
        e.set_error_register(self.error_register);
        e.set_data(self.data);
        Ok(())
    }
}
