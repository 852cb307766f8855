//! The SDO view: command byte, index, subindex, data (ETG.1000.6
//! §5.6.2).

use super::*;

/// Client (request) command specifiers, bits 5..=7 of the SDO command byte
/// (ETG.1000.6 §5.6.2, "Command specifier" of the request tables).
pub mod ccs {
    /// Download SDO segment request.
    pub const DOWNLOAD_SEGMENT: u8 = 0;
    /// Initiate SDO download request (expedited or normal).
    pub const INITIATE_DOWNLOAD: u8 = 1;
    /// Initiate SDO upload request.
    pub const INITIATE_UPLOAD: u8 = 2;
    /// Upload SDO segment request.
    pub const UPLOAD_SEGMENT: u8 = 3;
    /// Abort SDO transfer request.
    pub const ABORT: u8 = 4;
}

/// Server (response) command specifiers, bits 5..=7 of the SDO command byte
/// (ETG.1000.6 §5.6.2, "Command specifier" of the response tables).
pub mod scs {
    /// Upload SDO segment response.
    pub const UPLOAD_SEGMENT: u8 = 0;
    /// Download SDO segment response.
    pub const DOWNLOAD_SEGMENT: u8 = 1;
    /// Initiate SDO upload response (expedited or normal).
    pub const INITIATE_UPLOAD: u8 = 2;
    /// Initiate SDO download response.
    pub const INITIATE_DOWNLOAD: u8 = 3;
    /// Abort SDO transfer.
    pub const ABORT: u8 = 4;
}

pub(super) const CMD_SIZE_INDICATOR: u8 = 0x01;
pub(super) const CMD_EXPEDITED: u8 = 0x02;
pub(super) const CMD_COMPLETE_ACCESS: u8 = 0x10;
pub(super) const CMD_LAST_SEGMENT: u8 = 0x01;
pub(super) const CMD_TOGGLE: u8 = 0x10;
pub(super) const CMD_SPECIFIER_SHIFT: u8 = 5;

/// A read/write view of an SDO request or response: the bytes after the
/// CoE header, bounded by the mailbox length (ETG.1000.6 §5.6.2: initiate
/// download/upload, segments, abort).
///
/// The view gives raw access to every interpretation of the bytes; which
/// one applies depends on the command specifier and on the direction
/// (see [`SdoRequest`] / [`SdoResponse`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Sdo<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Sdo<T> {
    /// Wraps a buffer without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`Sdo::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let sdo = Self::new_unchecked(buffer);
        sdo.check_len()?;
        Ok(sdo)
    }

    /// Checks that the buffer holds the 8 bytes every SDO frame has
    /// ([`SDO_LEN`]); [`WireError::Truncated`] otherwise.
    pub fn check_len(&self) -> Result<(), WireError> {
        if self.buffer.as_ref().len() < SDO_LEN {
            Err(WireError::Truncated)
        } else {
            Ok(())
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The raw command byte.
    pub fn command(&self) -> u8 {
        crate::wire::get_u8(self.buffer.as_ref(), field::SDO_COMMAND)
    }

    /// The command specifier (bits 5..=7), see [`ccs`] and [`scs`].
    pub fn command_specifier(&self) -> u8 {
        self.command() >> CMD_SPECIFIER_SHIFT
    }

    /// Initiate: size indicator (bit 0).
    pub fn size_indicator(&self) -> bool {
        self.command() & CMD_SIZE_INDICATOR != 0
    }

    /// Initiate: expedited transfer (bit 1).
    pub fn expedited(&self) -> bool {
        self.command() & CMD_EXPEDITED != 0
    }

    /// Initiate: number of unused bytes of expedited data (bits 2..=3).
    pub fn expedited_unused(&self) -> u8 {
        (self.command() >> 2) & 0x03
    }

    /// Initiate: number of valid expedited data bytes, `4 - unused` when
    /// the size indicator is set, else 4 (size not specified).
    pub fn expedited_len(&self) -> u8 {
        if self.size_indicator() {
            4 - self.expedited_unused()
        } else {
            4
        }
    }

    /// Initiate: complete access (bit 4).
    pub fn complete_access(&self) -> bool {
        self.command() & CMD_COMPLETE_ACCESS != 0
    }

    /// Initiate/abort: object index.
    pub fn index(&self) -> u16 {
        crate::wire::get_u16_le(self.buffer.as_ref(), field::SDO_INDEX)
    }

    /// Initiate/abort: subindex.
    pub fn sub_index(&self) -> u8 {
        crate::wire::get_u8(self.buffer.as_ref(), field::SDO_SUBINDEX)
    }

    /// Initiate: the four data bytes (expedited data, all four as on the
    /// wire).
    pub fn data4(&self) -> [u8; 4] {
        crate::wire::get_array(self.buffer.as_ref(), field::SDO_DATA)
    }

    /// Normal initiate: the complete size of the object (bytes 4..8).
    pub fn complete_size(&self) -> u32 {
        crate::wire::get_u32_le(self.buffer.as_ref(), field::SDO_DATA)
    }

    /// Abort: the abort code (bytes 4..8).
    pub fn abort_code(&self) -> SdoAbortCode {
        SdoAbortCode::from(self.complete_size())
    }

    /// Normal initiate: the data after the complete size (bytes 8..).
    pub fn normal_data(&self) -> &[u8] {
        crate::wire::tail(self.buffer.as_ref(), field::SDO_NORMAL_DATA)
    }

    /// Segment: last segment flag (bit 0).
    pub fn last_segment(&self) -> bool {
        self.command() & CMD_LAST_SEGMENT != 0
    }

    /// Segment: the 3-bit "segment data size" field (bits 1..=3), the number
    /// of unused bytes of a 7-byte segment.
    pub fn segment_unused(&self) -> u8 {
        (self.command() >> 1) & 0x07
    }

    /// Segment: toggle bit (bit 4).
    pub fn toggle(&self) -> bool {
        self.command() & CMD_TOGGLE != 0
    }

    /// Segment: the segment data.
    ///
    /// When exactly 7 bytes follow the command byte (the minimum size) the
    /// size field is honoured and `7 - unused` bytes are returned; when more
    /// than 7 bytes follow, the data runs to the end of the buffer and the
    /// size field is ignored (it must be 0 there).
    pub fn segment_data(&self) -> &[u8] {
        let region = crate::wire::tail(self.buffer.as_ref(), field::SEGMENT_DATA);
        if region.len() > SEGMENT_MIN_DATA_LEN {
            region
        } else {
            let n = SEGMENT_MIN_DATA_LEN
                .saturating_sub(usize::from(self.segment_unused()))
                .min(region.len());
            region.get(..n).unwrap_or(&[])
        }
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Sdo<T> {
    /// Sets the raw command byte.
    pub fn set_command(&mut self, command: u8) {
        crate::wire::set_u8(self.buffer.as_mut(), field::SDO_COMMAND, command);
    }

    /// Sets the object index.
    pub fn set_index(&mut self, index: u16) {
        crate::wire::set_u16_le(self.buffer.as_mut(), field::SDO_INDEX, index);
    }

    /// Sets the subindex.
    pub fn set_sub_index(&mut self, sub: u8) {
        crate::wire::set_u8(self.buffer.as_mut(), field::SDO_SUBINDEX, sub);
    }

    /// Sets the four data bytes.
    pub fn set_data4(&mut self, data: [u8; 4]) {
        crate::wire::set_array(self.buffer.as_mut(), field::SDO_DATA, data);
    }

    /// Sets bytes 4..8 as a complete size (normal initiate).
    pub fn set_complete_size(&mut self, size: u32) {
        crate::wire::set_u32_le(self.buffer.as_mut(), field::SDO_DATA, size);
    }

    /// Sets bytes 4..8 as an abort code.
    pub fn set_abort_code(&mut self, code: SdoAbortCode) {
        self.set_complete_size(code.into());
    }

    /// Normal initiate: the mutable data after the complete size.
    pub fn normal_data_mut(&mut self) -> &mut [u8] {
        crate::wire::tail_mut(self.buffer.as_mut(), field::SDO_NORMAL_DATA)
    }

    /// Segment: the mutable bytes after the command byte (whole region,
    /// padding included).
    pub fn segment_data_mut(&mut self) -> &mut [u8] {
        crate::wire::tail_mut(self.buffer.as_mut(), field::SEGMENT_DATA)
    }
}
