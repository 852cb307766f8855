//! The CoE header (ETG.1000.6 Table 29): number and service.

use super::*;
use crate::codes::protocol_codes;

protocol_codes! {
    /// CoE service (ETG.1000.6 Table 29 "CoE elements", service field).
    ///
    /// Each variant's discriminant is its code (`repr(u8)`): the conversion
    /// to `u8` compiles to the tag. `Unknown`'s tag is not a code.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum CoeService(u8) {
        /// `1` Emergency.
        Emergency = 1,
        /// `2` SDO request.
        SdoRequest = 2,
        /// `3` SDO response.
        SdoResponse = 3,
        /// `4` TxPDO.
        TxPdo = 4,
        /// `5` RxPDO.
        RxPdo = 5,
        /// `6` TxPDO remote request.
        TxPdoRemoteReq = 6,
        /// `7` RxPDO remote request.
        RxPdoRemoteReq = 7,
        /// `8` SDO information.
        SdoInformation = 8,
    } else {
        /// Any other (reserved) value.
        Unknown = 0xFF,
    }
}

pub(super) const NUMBER_MASK: u16 = 0x01FF;
pub(super) const SERVICE_SHIFT: u16 = 12;

/// A read/write view of a CoE element: the two-byte CoE header and the
/// service data after it (ETG.1000.6 Table 29 "CoE elements").
///
/// The struct carries no bound so that [`CoeHeader::emit_into`] can be
/// called without naming a buffer type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CoeHeader<T> {
    buffer: T,
}

/// Alias of [`CoeHeader`], the view of a whole CoE element.
pub type Coe<T> = CoeHeader<T>;

impl CoeHeader<()> {
    /// Writes a CoE header with `number` (masked to 9 bits) and `service`
    /// into the first two bytes of `buf`; does nothing if `buf` is shorter
    /// than [`HEADER_LEN`].
    pub fn emit_into(buf: &mut [u8], number: u16, service: CoeService) {
        let mut coe = CoeHeader::new_unchecked(buf);
        coe.set_header(0);
        coe.set_number(number);
        coe.set_service(service);
    }
}

impl<T: AsRef<[u8]>> CoeHeader<T> {
    /// Length of the CoE header (same as the module's [`HEADER_LEN`]).
    pub const HEADER_LEN: usize = HEADER_LEN;

    /// Wraps a buffer (the mailbox data) without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`CoeHeader::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let coe = Self::new_unchecked(buffer);
        coe.check_len()?;
        Ok(coe)
    }

    /// Checks that the 2-byte header is present ([`WireError::Truncated`]
    /// otherwise).
    pub fn check_len(&self) -> Result<(), WireError> {
        if self.buffer.as_ref().len() < HEADER_LEN {
            Err(WireError::Truncated)
        } else {
            Ok(())
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    fn header(&self) -> u16 {
        crate::wire::get_u16_le(self.buffer.as_ref(), field::HEADER)
    }

    /// The number field (bits 0..=8; the PDO number for PDO services, 0
    /// otherwise).
    pub fn number(&self) -> u16 {
        self.header() & NUMBER_MASK
    }

    /// The service (bits 12..=15).
    pub fn service(&self) -> CoeService {
        // The shift leaves 4 bits, which always fit in a u8.
        CoeService::from((self.header() >> SERVICE_SHIFT) as u8)
    }

    /// The service data after the header.
    pub fn payload(&self) -> &[u8] {
        crate::wire::tail(self.buffer.as_ref(), field::PAYLOAD)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> CoeHeader<T> {
    fn set_header(&mut self, value: u16) {
        crate::wire::set_u16_le(self.buffer.as_mut(), field::HEADER, value);
    }

    /// Sets the number (masked to 9 bits), keeping the other bits.
    pub fn set_number(&mut self, number: u16) {
        let v = (self.header() & !NUMBER_MASK) | (number & NUMBER_MASK);
        self.set_header(v);
    }

    /// Sets the service (masked to 4 bits), keeping the other bits.
    pub fn set_service(&mut self, service: CoeService) {
        let raw = u16::from(u8::from(service) & 0x0F);
        let v = (self.header() & 0x0FFF) | (raw << SERVICE_SHIFT);
        self.set_header(v);
    }

    /// The mutable service data after the header.
    pub fn payload_mut(&mut self) -> &mut [u8] {
        crate::wire::tail_mut(self.buffer.as_mut(), field::PAYLOAD)
    }
}

/// High-level representation of a CoE header (ETG.1000.6 Table 29).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CoeRepr {
    /// Number, 0..=511.
    pub number: u16,
    /// Service.
    pub service: CoeService,
}

impl CoeRepr {
    /// Parses a CoE header.
    pub fn parse<T: AsRef<[u8]>>(coe: &CoeHeader<T>) -> Result<Self, WireError> {
        coe.check_len()?;
        Ok(Self {
            number: coe.number(),
            service: coe.service(),
        })
    }

    /// Length of the header ([`HEADER_LEN`]).
    pub const fn buffer_len(&self) -> usize {
        HEADER_LEN
    }

    /// Writes the header (reserved bits cleared).
    ///
    /// Fails with [`WireError::Unrepresentable`] if the number exceeds 9
    /// bits or the service 4 bits, and with [`WireError::BufferTooSmall`] if
    /// the header does not fit.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        coe: &mut CoeHeader<T>,
    ) -> Result<(), WireError> {
        if self.number > NUMBER_MASK || u8::from(self.service) > 0x0F {
            return Err(WireError::Unrepresentable);
        }
        coe.check_len().map_err(|_| WireError::BufferTooSmall)?;
        coe.set_header(self.number | (u16::from(u8::from(self.service)) << SERVICE_SHIFT));
        Ok(())
    }
}
