//! Mailbox header and mailbox error replies (ETG.1000.4 "Mailbox" data link
//! structure; ETG.1000.6 §5.5 "Mailbox", where the header is the `MbxHeader`
//! that starts every element of e.g. Table 29 "CoE elements").
//!
//! ```text
//!  0        2         4                5                   6
//! +--------+---------+----------------+-------------------+--------------
//! | length | address | chan | prio    | type | cnt | res  | data (length)
//! +--------+---------+----------------+-------------------+--------------
//!  byte 4: bits 0..=5 channel, bits 6..=7 priority
//!  byte 5: bits 0..=3 type, bits 4..=6 counter (1..=7, 0 = unused), bit 7
//!          reserved
//! ```
//!
//! The mailbox sync manager buffer is usually longer than
//! `HEADER_LEN + length`; the trailing bytes are padding and are not part of
//! [`Mailbox::payload`].

use super::{Field, Rest, WireError};
use crate::codes::protocol_codes;

/// Length of the mailbox header.
pub const HEADER_LEN: usize = field::DATA.start;

/// Largest valid mailbox counter; counters run 1..=7 and wrap to 1.
pub const MAX_COUNTER: u8 = 7;

mod field {
    use super::{Field, Rest};

    /// Length of the data following the header.
    pub const LENGTH: Field = 0..2;
    /// Station address of the source (master → slave) or destination.
    pub const ADDRESS: Field = 2..4;
    /// Channel (bits 0..=5) and priority (bits 6..=7).
    pub const CHANNEL_PRIORITY: usize = 4;
    /// Type (bits 0..=3), counter (bits 4..=6), reserved (bit 7).
    pub const TYPE_COUNTER: usize = 5;
    /// Mailbox data.
    pub const DATA: Rest = 6..;

    /// Error reply: type of the error (always 0x0001, "service").
    pub const ERR_TYPE: Field = 0..2;
    /// Error reply: detail code.
    pub const ERR_DETAIL: Field = 2..4;
}

protocol_codes! {
    /// Mailbox protocol type (ETG.1000.4 / ETG.1000.6 §5.5, mailbox header
    /// "Type" field).
    ///
    /// Each variant's discriminant is its code (`repr(u8)`): the conversion
    /// to `u8` compiles to the tag. `Unknown`'s tag is not a code.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum MailboxType(u8) {
        /// `0x00`: mailbox error reply ([`MailboxError`]).
        Error = 0x00,
        /// `0x01`: ADS over EtherCAT.
        AoE = 0x01,
        /// `0x02`: Ethernet over EtherCAT.
        EoE = 0x02,
        /// `0x03`: CANopen over EtherCAT.
        CoE = 0x03,
        /// `0x04`: File access over EtherCAT.
        FoE = 0x04,
        /// `0x05`: Servo profile over EtherCAT.
        SoE = 0x05,
        /// `0x0F`: Vendor specific.
        VoE = 0x0F,
    } else {
        /// Any other (reserved) value.
        Unknown = 0xFF,
    }
}

/// The counter value following `counter` in the 1..=7 sequence
/// (ETG.1000.4 mailbox header "Cnt": 0 is reserved for "not used", 7 wraps
/// to 1). Out-of-range inputs restart the sequence at 1.
pub const fn next_counter(counter: u8) -> u8 {
    if counter >= MAX_COUNTER {
        1
    } else {
        counter + 1
    }
}

/// A read/write view of a mailbox: 6-byte header and the data it announces
/// (ETG.1000.4 "Mailbox"; ETG.1000.6 §5.5).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mailbox<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Mailbox<T> {
    /// Wraps a buffer (e.g. a mailbox sync manager area) without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`Mailbox::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let mbx = Self::new_unchecked(buffer);
        mbx.check_len()?;
        Ok(mbx)
    }

    /// Checks that the header and the `length()` data bytes fit.
    ///
    /// Returns [`WireError::Truncated`] if the 6-byte header is missing and
    /// [`WireError::BadLength`] if the length field runs past the buffer.
    pub fn check_len(&self) -> Result<(), WireError> {
        let len = self.buffer.as_ref().len();
        if len < HEADER_LEN {
            Err(WireError::Truncated)
        } else if self.total_len() > len {
            Err(WireError::BadLength)
        } else {
            Ok(())
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Header plus data length, according to the length field.
    pub fn total_len(&self) -> usize {
        HEADER_LEN + usize::from(self.length())
    }

    /// Length of the data following the header.
    pub fn length(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::LENGTH)
    }

    /// Station address (of the originator for master → slave mailboxes).
    pub fn address(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::ADDRESS)
    }

    /// Channel (bits 0..=5 of byte 4; 0 is the only channel in use).
    pub fn channel(&self) -> u8 {
        super::get_u8(self.buffer.as_ref(), field::CHANNEL_PRIORITY) & 0x3F
    }

    /// Priority (bits 6..=7 of byte 4; 0 lowest .. 3 highest).
    pub fn priority(&self) -> u8 {
        super::get_u8(self.buffer.as_ref(), field::CHANNEL_PRIORITY) >> 6
    }

    /// Mailbox protocol type (bits 0..=3 of byte 5).
    pub fn mailbox_type(&self) -> MailboxType {
        MailboxType::from(super::get_u8(self.buffer.as_ref(), field::TYPE_COUNTER) & 0x0F)
    }

    /// Counter (bits 4..=6 of byte 5; 1..=7, 0 = not used).
    pub fn counter(&self) -> u8 {
        (super::get_u8(self.buffer.as_ref(), field::TYPE_COUNTER) >> 4) & 0x07
    }

    /// The data following the header, `length()` bytes (clamped to the
    /// buffer).
    pub fn payload(&self) -> &[u8] {
        let buf = self.buffer.as_ref();
        let end = self.total_len().min(buf.len());
        super::slice(buf, HEADER_LEN..end)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Mailbox<T> {
    /// Sets the length field.
    pub fn set_length(&mut self, length: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::LENGTH, length);
    }

    /// Sets the station address.
    pub fn set_address(&mut self, address: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::ADDRESS, address);
    }

    /// Sets the channel (masked to 6 bits), keeping the priority.
    pub fn set_channel(&mut self, channel: u8) {
        let b = super::get_u8(self.buffer.as_ref(), field::CHANNEL_PRIORITY);
        let b = (b & 0xC0) | (channel & 0x3F);
        super::set_u8(self.buffer.as_mut(), field::CHANNEL_PRIORITY, b);
    }

    /// Sets the priority (masked to 2 bits), keeping the channel.
    pub fn set_priority(&mut self, priority: u8) {
        let b = super::get_u8(self.buffer.as_ref(), field::CHANNEL_PRIORITY);
        let b = (b & 0x3F) | ((priority & 0x03) << 6);
        super::set_u8(self.buffer.as_mut(), field::CHANNEL_PRIORITY, b);
    }

    /// Sets the type (masked to 4 bits), keeping counter and reserved bit.
    pub fn set_mailbox_type(&mut self, ty: MailboxType) {
        let b = super::get_u8(self.buffer.as_ref(), field::TYPE_COUNTER);
        let b = (b & 0xF0) | (u8::from(ty) & 0x0F);
        super::set_u8(self.buffer.as_mut(), field::TYPE_COUNTER, b);
    }

    /// Sets the counter (masked to 3 bits), keeping type and reserved bit.
    pub fn set_counter(&mut self, counter: u8) {
        let b = super::get_u8(self.buffer.as_ref(), field::TYPE_COUNTER);
        let b = (b & 0x8F) | ((counter & 0x07) << 4);
        super::set_u8(self.buffer.as_mut(), field::TYPE_COUNTER, b);
    }

    /// The mutable data, `length()` bytes (clamped to the buffer).
    pub fn payload_mut(&mut self) -> &mut [u8] {
        let end = self.total_len();
        let buf = self.buffer.as_mut();
        let end = end.min(buf.len());
        super::slice_mut(buf, HEADER_LEN..end)
    }

    /// Everything after the header regardless of `length()`, to build a
    /// reply before its length is known.
    pub fn rest_mut(&mut self) -> &mut [u8] {
        super::tail_mut(self.buffer.as_mut(), field::DATA)
    }
}

impl<T: AsRef<[u8]>> AsRef<[u8]> for Mailbox<T> {
    fn as_ref(&self) -> &[u8] {
        self.buffer.as_ref()
    }
}

/// High-level representation of a mailbox header (ETG.1000.4 "Mailbox";
/// ETG.1000.6 §5.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MailboxRepr {
    /// Length of the data following the header.
    pub length: u16,
    /// Station address.
    pub address: u16,
    /// Channel, 0..=63.
    pub channel: u8,
    /// Priority, 0..=3.
    pub priority: u8,
    /// Protocol type.
    pub mailbox_type: MailboxType,
    /// Counter, 0..=7.
    pub counter: u8,
}

impl MailboxRepr {
    /// Length of the mailbox header (same as the module's [`HEADER_LEN`]).
    pub const HEADER_LEN: usize = HEADER_LEN;

    /// Parses a mailbox header, checking that the announced data fits.
    pub fn parse<T: AsRef<[u8]>>(mbx: &Mailbox<T>) -> Result<Self, WireError> {
        mbx.check_len()?;
        Ok(Self {
            length: mbx.length(),
            address: mbx.address(),
            channel: mbx.channel(),
            priority: mbx.priority(),
            mailbox_type: mbx.mailbox_type(),
            counter: mbx.counter(),
        })
    }

    /// Header plus data length.
    pub const fn buffer_len(&self) -> usize {
        HEADER_LEN + self.length as usize
    }

    /// Writes the header (reserved bit cleared); the data is untouched.
    ///
    /// Fails with [`WireError::Unrepresentable`] if a bit field is out of
    /// range and with [`WireError::BufferTooSmall`] if the buffer cannot
    /// hold [`MailboxRepr::buffer_len`] bytes.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        mbx: &mut Mailbox<T>,
    ) -> Result<(), WireError> {
        if self.channel > 0x3F
            || self.priority > 0x03
            || u8::from(self.mailbox_type) > 0x0F
            || self.counter > MAX_COUNTER
        {
            return Err(WireError::Unrepresentable);
        }
        if mbx.buffer.as_ref().len() < self.buffer_len() {
            return Err(WireError::BufferTooSmall);
        }
        mbx.set_length(self.length);
        mbx.set_address(self.address);
        let buf = mbx.buffer.as_mut();
        super::set_u8(
            buf,
            field::CHANNEL_PRIORITY,
            self.channel | (self.priority << 6),
        );
        super::set_u8(
            buf,
            field::TYPE_COUNTER,
            u8::from(self.mailbox_type) | (self.counter << 4),
        );
        Ok(())
    }

    /// [`MailboxRepr::emit`] into a raw buffer whose data part is already
    /// in place (`buf` must hold [`MailboxRepr::buffer_len`] bytes).
    pub fn emit_header(&self, buf: &mut [u8]) -> Result<(), WireError> {
        self.emit(&mut Mailbox::new_unchecked(buf))
    }
}

/// Value of the "type" word of a mailbox error reply
/// (ETG.1000.6 §5.5, mailbox error reply: `0x0001` = mailbox service).
pub const ERROR_TYPE_SERVICE: u16 = 0x0001;

/// Length of a mailbox error reply body.
pub const ERROR_LEN: usize = field::ERR_DETAIL.end;

protocol_codes! {
    /// Mailbox error detail code (ETG.1000.6 §5.5, mailbox error reply
    /// "Detail" codes `MBXERR_*`).
    ///
    /// Each variant's discriminant is its code (`repr(u16)`): the conversion
    /// to `u16` compiles to the tag. `Unknown`'s tag is not a code.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum MailboxErrorCode(u16) {
        /// `0x01` Syntax of the 6-octet mailbox header is wrong.
        Syntax = 0x01,
        /// `0x02` The mailbox protocol is not supported.
        UnsupportedProtocol = 0x02,
        /// `0x03` Channel field contains a wrong value.
        InvalidChannel = 0x03,
        /// `0x04` The service in the mailbox protocol is not supported.
        ServiceNotSupported = 0x04,
        /// `0x05` The mailbox protocol header is wrong (without the 6-octet
        /// mailbox header).
        InvalidHeader = 0x05,
        /// `0x06` Length of the received mailbox data is too short.
        SizeTooShort = 0x06,
        /// `0x07` The mailbox protocol cannot be processed for lack of
        /// resources.
        NoMoreMemory = 0x07,
        /// `0x08` The length of the data is inconsistent.
        InvalidSize = 0x08,
    } else {
        /// Any other detail code.
        Unknown = 0xFFFF,
    }
}

impl MailboxErrorCode {
    /// Human-readable description (ETG.1000.6 §5.5 wording).
    pub const fn description(self) -> &'static str {
        match self {
            Self::Syntax => "syntax of the mailbox header is wrong",
            Self::UnsupportedProtocol => "mailbox protocol not supported",
            Self::InvalidChannel => "channel field contains wrong value",
            Self::ServiceNotSupported => "service in the mailbox protocol not supported",
            Self::InvalidHeader => "mailbox protocol header is wrong",
            Self::SizeTooShort => "length of received mailbox data is too short",
            Self::NoMoreMemory => "mailbox protocol cannot be processed: no more memory",
            Self::InvalidSize => "length of data is inconsistent",
            Self::Unknown(_) => "unknown mailbox error",
        }
    }
}

impl core::fmt::Display for MailboxErrorCode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:#06x}: {}", u16::from(*self), self.description())
    }
}

/// A read/write view of a mailbox error reply body, the data of a mailbox
/// of type [`MailboxType::Error`] (ETG.1000.6 §5.5, mailbox error reply:
/// u16 type = `0x0001`, u16 detail).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MailboxError<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> MailboxError<T> {
    /// Wraps a buffer (the mailbox data) without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`MailboxError::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let e = Self::new_unchecked(buffer);
        e.check_len()?;
        Ok(e)
    }

    /// Checks that the 4-byte body is present ([`WireError::Truncated`]
    /// otherwise).
    pub fn check_len(&self) -> Result<(), WireError> {
        if self.buffer.as_ref().len() < ERROR_LEN {
            Err(WireError::Truncated)
        } else {
            Ok(())
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The type word (should be [`ERROR_TYPE_SERVICE`]).
    pub fn error_type(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::ERR_TYPE)
    }

    /// The detail code.
    pub fn detail(&self) -> MailboxErrorCode {
        MailboxErrorCode::from(super::get_u16_le(self.buffer.as_ref(), field::ERR_DETAIL))
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> MailboxError<T> {
    /// Sets the type word.
    pub fn set_error_type(&mut self, ty: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::ERR_TYPE, ty);
    }

    /// Sets the detail code.
    pub fn set_detail(&mut self, code: MailboxErrorCode) {
        super::set_u16_le(self.buffer.as_mut(), field::ERR_DETAIL, code.into());
    }
}

/// High-level representation of a mailbox error reply body (ETG.1000.6
/// §5.5). The type word is always emitted as [`ERROR_TYPE_SERVICE`]; parse
/// does not check it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MailboxErrorRepr {
    /// The detail code.
    pub code: MailboxErrorCode,
}

impl MailboxErrorRepr {
    /// Parses an error reply body.
    pub fn parse<T: AsRef<[u8]>>(err: &MailboxError<T>) -> Result<Self, WireError> {
        err.check_len()?;
        Ok(Self { code: err.detail() })
    }

    /// Length of the body ([`ERROR_LEN`]).
    pub const fn buffer_len(&self) -> usize {
        ERROR_LEN
    }

    /// Writes the body; [`WireError::BufferTooSmall`] if it does not fit.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        err: &mut MailboxError<T>,
    ) -> Result<(), WireError> {
        err.check_len().map_err(|_| WireError::BufferTooSmall)?;
        err.set_error_type(ERROR_TYPE_SERVICE);
        err.set_detail(self.code);
        Ok(())
    }
}

/// Writes a mailbox error reply body for `code` into `body` (the bytes
/// after the mailbox header) and returns its length, [`ERROR_LEN`]
/// (ETG.1000.6 §5.5, mailbox error reply).
///
/// Fails with [`WireError::BufferTooSmall`] if `body` is shorter than
/// [`ERROR_LEN`].
pub fn emit_error(code: MailboxErrorCode, body: &mut [u8]) -> Result<usize, WireError> {
    let repr = MailboxErrorRepr { code };
    repr.emit(&mut MailboxError::new_unchecked(body))?;
    Ok(repr.buffer_len())
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

    /// CoE SDO upload request for 0x1018:01 (ethercrab/Wireshark style):
    /// length 10, address 0, channel 0, priority 0, CoE, counter 3, then
    /// 10 bytes of CoE data and 4 bytes of sync-manager padding.
    static MAILBOX_BYTES: [u8; 20] = [
        0x0a, 0x00, // length 10
        0x00, 0x00, // address
        0x00, // channel 0, priority 0
        0x33, // type CoE, counter 3
        0x00, 0x20, 0x40, 0x18, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00, // CoE
        0xEE, 0xEE, 0xEE, 0xEE, // padding
    ];

    /// Mailbox error reply: length 4, address 0x1001, type Error, counter
    /// 1, type word 1, detail 0x0002 (unsupported protocol).
    static ERROR_REPLY_BYTES: [u8; 10] =
        [0x04, 0x00, 0x01, 0x10, 0x00, 0x10, 0x01, 0x00, 0x02, 0x00];

    #[test]
    fn deconstructs_coe_mailbox() {
        let mbx = Mailbox::new_checked(&MAILBOX_BYTES[..]).unwrap();
        assert_eq!(mbx.length(), 10);
        assert_eq!(mbx.address(), 0);
        assert_eq!(mbx.channel(), 0);
        assert_eq!(mbx.priority(), 0);
        assert_eq!(mbx.mailbox_type(), MailboxType::CoE);
        assert_eq!(mbx.counter(), 3);
        assert_eq!(mbx.total_len(), 16);
        assert_eq!(mbx.payload(), &MAILBOX_BYTES[6..16]);
    }

    #[test]
    fn constructs_coe_mailbox() {
        let mut bytes = [0xEEu8; 20];
        let mut mbx = Mailbox::new_unchecked(&mut bytes[..]);
        mbx.set_length(10);
        mbx.set_address(0);
        mbx.set_channel(0);
        mbx.set_priority(0);
        // clear the reserved bit left by the fill
        super::super::set_u8(mbx.buffer, field::TYPE_COUNTER, 0);
        mbx.set_mailbox_type(MailboxType::CoE);
        mbx.set_counter(3);
        mbx.payload_mut().copy_from_slice(&MAILBOX_BYTES[6..16]);
        assert_eq!(bytes, MAILBOX_BYTES);
    }

    #[test]
    fn repr_parse_and_emit_round_trip() {
        let mbx = Mailbox::new_checked(&MAILBOX_BYTES[..]).unwrap();
        let repr = MailboxRepr::parse(&mbx).unwrap();
        assert_eq!(
            repr,
            MailboxRepr {
                length: 10,
                address: 0,
                channel: 0,
                priority: 0,
                mailbox_type: MailboxType::CoE,
                counter: 3,
            }
        );
        assert_eq!(repr.buffer_len(), 16);
        let mut out = MAILBOX_BYTES;
        out[..6].fill(0xFF);
        repr.emit(&mut Mailbox::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, MAILBOX_BYTES);
    }

    #[test]
    fn header_bit_fields_are_independent() {
        let mut bytes = [0u8; 6];
        let mut mbx = Mailbox::new_unchecked(&mut bytes[..]);
        mbx.set_channel(0x3F);
        mbx.set_priority(3);
        mbx.set_mailbox_type(MailboxType::VoE);
        mbx.set_counter(7);
        assert_eq!(mbx.channel(), 0x3F);
        assert_eq!(mbx.priority(), 3);
        assert_eq!(mbx.mailbox_type(), MailboxType::VoE);
        assert_eq!(mbx.counter(), 7);
        mbx.set_channel(0);
        mbx.set_counter(0);
        assert_eq!(mbx.priority(), 3);
        assert_eq!(mbx.mailbox_type(), MailboxType::VoE);
        assert_eq!(bytes, [0, 0, 0, 0, 0xC0, 0x0F]);
    }

    #[test]
    fn mailbox_with_length_beyond_buffer_is_rejected() {
        let mut bytes = MAILBOX_BYTES;
        bytes[0] = 15; // 6 + 15 > 20
        let mbx = Mailbox::new_unchecked(&bytes[..]);
        assert_eq!(mbx.check_len(), Err(WireError::BadLength));
        assert_eq!(MailboxRepr::parse(&mbx), Err(WireError::BadLength));
        // clamped, no panic
        assert_eq!(mbx.payload().len(), 14);
    }

    #[test]
    fn mailbox_shorter_than_header_is_truncated() {
        assert_eq!(
            Mailbox::new_checked(&MAILBOX_BYTES[..5]).unwrap_err(),
            WireError::Truncated
        );
        let mbx = Mailbox::new_unchecked(&MAILBOX_BYTES[..3]);
        assert!(mbx.payload().is_empty());
        assert_eq!(mbx.counter(), 0);
    }

    #[test]
    fn huge_length_field_does_not_panic() {
        let bytes = [0xFFu8; 6];
        let mut copy = bytes;
        let mut mbx = Mailbox::new_unchecked(&mut copy[..]);
        assert_eq!(mbx.check_len(), Err(WireError::BadLength));
        assert!(mbx.payload().is_empty());
        assert!(mbx.payload_mut().is_empty());
        assert!(mbx.rest_mut().is_empty());
        assert_eq!(mbx.mailbox_type(), MailboxType::VoE);
    }

    #[test]
    fn unknown_mailbox_type_is_kept() {
        let bytes = [0u8, 0, 0, 0, 0, 0x17];
        let mbx = Mailbox::new_checked(&bytes[..]).unwrap();
        assert_eq!(mbx.mailbox_type(), MailboxType::Unknown(7));
        for raw in 0..16u8 {
            assert_eq!(u8::from(MailboxType::from(raw)), raw);
        }
    }

    #[test]
    fn repr_with_out_of_range_fields_is_unrepresentable() {
        let mut out = [0u8; 6];
        let base = MailboxRepr {
            length: 0,
            address: 0,
            channel: 0,
            priority: 0,
            mailbox_type: MailboxType::CoE,
            counter: 1,
        };
        for bad in [
            MailboxRepr {
                channel: 64,
                ..base
            },
            MailboxRepr {
                priority: 4,
                ..base
            },
            MailboxRepr { counter: 8, ..base },
            MailboxRepr {
                mailbox_type: MailboxType::Unknown(0x10),
                ..base
            },
        ] {
            assert_eq!(
                bad.emit(&mut Mailbox::new_unchecked(&mut out[..])),
                Err(WireError::Unrepresentable)
            );
        }
        let too_long = MailboxRepr { length: 1, ..base };
        assert_eq!(
            too_long.emit(&mut Mailbox::new_unchecked(&mut out[..])),
            Err(WireError::BufferTooSmall)
        );
        assert_eq!(out, [0; 6]);
    }

    #[test]
    fn counter_sequence_wraps_from_seven_to_one() {
        assert_eq!(next_counter(0), 1);
        assert_eq!(next_counter(1), 2);
        assert_eq!(next_counter(6), 7);
        assert_eq!(next_counter(7), 1);
        assert_eq!(next_counter(200), 1);
    }

    #[test]
    fn deconstructs_error_reply() {
        let mbx = Mailbox::new_checked(&ERROR_REPLY_BYTES[..]).unwrap();
        assert_eq!(mbx.mailbox_type(), MailboxType::Error);
        assert_eq!(mbx.address(), 0x1001);
        assert_eq!(mbx.counter(), 1);
        let err = MailboxError::new_checked(mbx.payload()).unwrap();
        assert_eq!(err.error_type(), ERROR_TYPE_SERVICE);
        assert_eq!(err.detail(), MailboxErrorCode::UnsupportedProtocol);
        assert_eq!(
            MailboxErrorRepr::parse(&err).unwrap().code,
            MailboxErrorCode::UnsupportedProtocol
        );
    }

    #[test]
    fn constructs_error_reply() {
        let mut out = [0u8; 10];
        let mut mbx = Mailbox::new_unchecked(&mut out[..]);
        MailboxRepr {
            length: 4,
            address: 0x1001,
            channel: 0,
            priority: 0,
            mailbox_type: MailboxType::Error,
            counter: 1,
        }
        .emit(&mut mbx)
        .unwrap();
        let repr = MailboxErrorRepr {
            code: MailboxErrorCode::UnsupportedProtocol,
        };
        assert_eq!(repr.buffer_len(), 4);
        repr.emit(&mut MailboxError::new_unchecked(mbx.payload_mut()))
            .unwrap();
        assert_eq!(out, ERROR_REPLY_BYTES);
    }

    #[test]
    fn emit_error_and_emit_header_build_a_complete_reply() {
        let mut out = [0u8; 10];
        let n = emit_error(MailboxErrorCode::UnsupportedProtocol, &mut out[6..]).unwrap();
        assert_eq!(n, ERROR_LEN);
        MailboxRepr {
            length: 4,
            address: 0x1001,
            channel: 0,
            priority: 0,
            mailbox_type: MailboxType::Error,
            counter: 1,
        }
        .emit_header(&mut out)
        .unwrap();
        assert_eq!(out, ERROR_REPLY_BYTES);
        assert_eq!(
            emit_error(MailboxErrorCode::Syntax, &mut out[7..]),
            Err(WireError::BufferTooSmall)
        );
    }

    #[test]
    fn truncated_error_reply_is_rejected() {
        assert_eq!(
            MailboxError::new_checked(&ERROR_REPLY_BYTES[6..9]).unwrap_err(),
            WireError::Truncated
        );
        let mut small = [0u8; 3];
        let repr = MailboxErrorRepr {
            code: MailboxErrorCode::Syntax,
        };
        assert_eq!(
            repr.emit(&mut MailboxError::new_unchecked(&mut small[..])),
            Err(WireError::BufferTooSmall)
        );
    }

    #[test]
    fn error_codes_round_trip_and_have_text() {
        use core::fmt::Write;
        for raw in 0..=0x0Au16 {
            let code = MailboxErrorCode::from(raw);
            assert_eq!(u16::from(code), raw);
            assert!(!code.description().is_empty());
        }
        assert_eq!(
            MailboxErrorCode::from(0x0A),
            MailboxErrorCode::Unknown(0x0A)
        );
        let mut s: heapless::String<64> = heapless::String::new();
        write!(s, "{}", MailboxErrorCode::InvalidSize).unwrap();
        assert_eq!(s.as_str(), "0x0008: length of data is inconsistent");
    }
}
