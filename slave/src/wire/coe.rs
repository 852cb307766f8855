//! CANopen over EtherCAT (ETG.1000.6 §5.6): CoE header, SDO requests and
//! responses, SDO abort codes, SDO information header and emergency
//! messages.
//!
//! Everything here sits in the data of a mailbox of type CoE:
//!
//! ```text
//! CoE header (2 bytes LE, ETG.1000.6 Table 29 "CoE elements")
//!  bits 0..=8 number, bits 9..=11 reserved, bits 12..=15 service
//!
//! SDO (ETG.1000.6 §5.6.2), at least 8 bytes after the CoE header:
//!  0        1       3     4              8
//! +--------+-------+-----+--------------+------------------------
//! | cmd    | index | sub | data / size  | data (normal transfer)
//! +--------+-------+-----+--------------+------------------------
//!  initiate cmd: bit 0 size indicator, bit 1 expedited, bits 2..=3 unused
//!                bytes of expedited data, bit 4 complete access, bits
//!                5..=7 command specifier
//!
//! SDO segment (ETG.1000.6 §5.6.2.3 / §5.6.2.6):
//!  0      1
//! +------+-------------------------------------------- (>= 7 bytes)
//! | cmd  | segment data (padded to 7 bytes)
//! +------+--------------------------------------------
//!  segment cmd: bit 0 last segment, bits 1..=3 unused bytes when the data
//!               is shorter than 7, bit 4 toggle, bits 5..=7 specifier
//! ```
//!
//! SDO frames are never shorter than 10 bytes after the mailbox header
//! ([`SDO_MAILBOX_MIN_LEN`]: CoE header + 8); shorter segment data is padded
//! with zeroes to 7 bytes and the number of padding bytes is given in the
//! command byte. In EtherCAT a segment may be longer than 7 bytes: its data
//! then runs to the end of the mailbox data (the mailbox length bounds it).
//!
//! [`SdoRequest`] and [`SdoResponse`] therefore parse *the bytes after the
//! CoE header, bounded by the mailbox length* (e.g. `coe.payload()` of a
//! [`CoeHeader`] built over `mailbox.payload()`).

use super::{Field, Rest, WireError};

/// Length of the CoE header.
pub const HEADER_LEN: usize = field::PAYLOAD.start;

/// Minimum length of an SDO request/response after the CoE header.
pub const SDO_LEN: usize = field::SDO_NORMAL_DATA.start;

/// Minimum mailbox data length of an SDO frame: CoE header + 8 bytes.
pub const SDO_MAILBOX_MIN_LEN: usize = HEADER_LEN + SDO_LEN;

/// Segment data shorter than this is padded to it (ETG.1000.6 §5.6.2.3).
pub const SEGMENT_MIN_DATA_LEN: usize = 7;

/// Length of the SDO information header after the CoE header.
pub const SDO_INFO_HEADER_LEN: usize = field::INFO_DATA.start;

/// Length of an emergency message after the CoE header.
pub const EMERGENCY_LEN: usize = field::EMCY_DATA.end;

mod field {
    use super::{Field, Rest};

    /// CoE header: number (bits 0..=8), reserved (9..=11), service
    /// (12..=15).
    pub const HEADER: Field = 0..2;
    /// Data following the CoE header.
    pub const PAYLOAD: Rest = 2..;

    /// SDO: command byte.
    pub const SDO_COMMAND: usize = 0;
    /// SDO: object index.
    pub const SDO_INDEX: Field = 1..3;
    /// SDO: subindex.
    pub const SDO_SUBINDEX: usize = 3;
    /// SDO: expedited data, complete size or abort code.
    pub const SDO_DATA: Field = 4..8;
    /// SDO: data of a normal (non-expedited) initiate.
    pub const SDO_NORMAL_DATA: Rest = 8..;
    /// SDO segment: segment data.
    pub const SEGMENT_DATA: Rest = 1..;

    /// SDO information: opcode (bits 0..=6) and incomplete flag (bit 7).
    pub const INFO_OPCODE: usize = 0;
    /// SDO information: reserved byte.
    pub const INFO_RESERVED: usize = 1;
    /// SDO information: fragments left.
    pub const INFO_FRAGMENTS_LEFT: Field = 2..4;
    /// SDO information: service data.
    pub const INFO_DATA: Rest = 4..;

    /// Emergency: error code.
    pub const EMCY_CODE: Field = 0..2;
    /// Emergency: error register (object 0x1001).
    pub const EMCY_REGISTER: usize = 2;
    /// Emergency: manufacturer-specific data.
    pub const EMCY_DATA: Field = 3..8;
}

// ---------------------------------------------------------------------------
// CoE header
// ---------------------------------------------------------------------------

/// CoE service (ETG.1000.6 Table 29 "CoE elements", service field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CoeService {
    /// `1` Emergency.
    Emergency,
    /// `2` SDO request.
    SdoRequest,
    /// `3` SDO response.
    SdoResponse,
    /// `4` TxPDO.
    TxPdo,
    /// `5` RxPDO.
    RxPdo,
    /// `6` TxPDO remote request.
    TxPdoRemoteReq,
    /// `7` RxPDO remote request.
    RxPdoRemoteReq,
    /// `8` SDO information.
    SdoInformation,
    /// Any other (reserved) value.
    Unknown(u8),
}

impl From<u8> for CoeService {
    fn from(raw: u8) -> Self {
        match raw {
            1 => Self::Emergency,
            2 => Self::SdoRequest,
            3 => Self::SdoResponse,
            4 => Self::TxPdo,
            5 => Self::RxPdo,
            6 => Self::TxPdoRemoteReq,
            7 => Self::RxPdoRemoteReq,
            8 => Self::SdoInformation,
            other => Self::Unknown(other),
        }
    }
}

impl From<CoeService> for u8 {
    fn from(service: CoeService) -> Self {
        match service {
            CoeService::Emergency => 1,
            CoeService::SdoRequest => 2,
            CoeService::SdoResponse => 3,
            CoeService::TxPdo => 4,
            CoeService::RxPdo => 5,
            CoeService::TxPdoRemoteReq => 6,
            CoeService::RxPdoRemoteReq => 7,
            CoeService::SdoInformation => 8,
            CoeService::Unknown(raw) => raw,
        }
    }
}

const NUMBER_MASK: u16 = 0x01FF;
const SERVICE_SHIFT: u16 = 12;

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
        super::get_u16_le(self.buffer.as_ref(), field::HEADER)
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
        super::tail(self.buffer.as_ref(), field::PAYLOAD)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> CoeHeader<T> {
    fn set_header(&mut self, value: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::HEADER, value);
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
        super::tail_mut(self.buffer.as_mut(), field::PAYLOAD)
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

// ---------------------------------------------------------------------------
// SDO abort codes
// ---------------------------------------------------------------------------

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

        impl From<u32> for SdoAbortCode {
            fn from(raw: u32) -> Self {
                match raw {
                    $($code => Self::$name,)*
                    other => Self::Unknown(other),
                }
            }
        }

        impl From<SdoAbortCode> for u32 {
            fn from(code: SdoAbortCode) -> Self {
                match code {
                    $(SdoAbortCode::$name => $code,)*
                    SdoAbortCode::Unknown(raw) => raw,
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
            const ALL: &'static [SdoAbortCode] = &[$(Self::$name,)*];
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

// ---------------------------------------------------------------------------
// SDO view
// ---------------------------------------------------------------------------

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

const CMD_SIZE_INDICATOR: u8 = 0x01;
const CMD_EXPEDITED: u8 = 0x02;
const CMD_COMPLETE_ACCESS: u8 = 0x10;
const CMD_LAST_SEGMENT: u8 = 0x01;
const CMD_TOGGLE: u8 = 0x10;
const CMD_SPECIFIER_SHIFT: u8 = 5;

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
        super::get_u8(self.buffer.as_ref(), field::SDO_COMMAND)
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
        super::get_u16_le(self.buffer.as_ref(), field::SDO_INDEX)
    }

    /// Initiate/abort: subindex.
    pub fn sub_index(&self) -> u8 {
        super::get_u8(self.buffer.as_ref(), field::SDO_SUBINDEX)
    }

    /// Initiate: the four data bytes (expedited data, all four as on the
    /// wire).
    pub fn data4(&self) -> [u8; 4] {
        super::get_array(self.buffer.as_ref(), field::SDO_DATA)
    }

    /// Normal initiate: the complete size of the object (bytes 4..8).
    pub fn complete_size(&self) -> u32 {
        super::get_u32_le(self.buffer.as_ref(), field::SDO_DATA)
    }

    /// Abort: the abort code (bytes 4..8).
    pub fn abort_code(&self) -> SdoAbortCode {
        SdoAbortCode::from(self.complete_size())
    }

    /// Normal initiate: the data after the complete size (bytes 8..).
    pub fn normal_data(&self) -> &[u8] {
        super::tail(self.buffer.as_ref(), field::SDO_NORMAL_DATA)
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
        let region = super::tail(self.buffer.as_ref(), field::SEGMENT_DATA);
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
        super::set_u8(self.buffer.as_mut(), field::SDO_COMMAND, command);
    }

    /// Sets the object index.
    pub fn set_index(&mut self, index: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::SDO_INDEX, index);
    }

    /// Sets the subindex.
    pub fn set_sub_index(&mut self, sub: u8) {
        super::set_u8(self.buffer.as_mut(), field::SDO_SUBINDEX, sub);
    }

    /// Sets the four data bytes.
    pub fn set_data4(&mut self, data: [u8; 4]) {
        super::set_array(self.buffer.as_mut(), field::SDO_DATA, data);
    }

    /// Sets bytes 4..8 as a complete size (normal initiate).
    pub fn set_complete_size(&mut self, size: u32) {
        super::set_u32_le(self.buffer.as_mut(), field::SDO_DATA, size);
    }

    /// Sets bytes 4..8 as an abort code.
    pub fn set_abort_code(&mut self, code: SdoAbortCode) {
        self.set_complete_size(code.into());
    }

    /// Normal initiate: the mutable data after the complete size.
    pub fn normal_data_mut(&mut self) -> &mut [u8] {
        super::tail_mut(self.buffer.as_mut(), field::SDO_NORMAL_DATA)
    }

    /// Segment: the mutable bytes after the command byte (whole region,
    /// padding included).
    pub fn segment_data_mut(&mut self) -> &mut [u8] {
        super::tail_mut(self.buffer.as_mut(), field::SEGMENT_DATA)
    }
}

// ---------------------------------------------------------------------------
// SDO Reprs
// ---------------------------------------------------------------------------

/// Payload of an initiate SDO download request (ETG.1000.6 §5.6.2.1
/// expedited, §5.6.2.2 normal).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DownloadKind<'a> {
    /// Expedited: up to 4 bytes inside the initiate request. `data` holds
    /// the four bytes as on the wire; the first `len` (1..=4) are valid.
    Expedited {
        /// The four data bytes.
        data: [u8; 4],
        /// Number of valid bytes, 1..=4.
        len: u8,
    },
    /// Normal: the object's complete size and the first part of its data
    /// (the rest follows in download segments).
    Normal {
        /// Complete size of the object in bytes.
        complete_size: u32,
        /// Data carried in this request (to the end of the mailbox data).
        data: &'a [u8],
    },
}

impl DownloadKind<'_> {
    /// The valid data bytes carried in the initiate request.
    pub fn data(&self) -> &[u8] {
        match self {
            Self::Expedited { data, len } => data.get(..usize::from(*len)).unwrap_or(data),
            Self::Normal { data, .. } => data,
        }
    }
}

/// An SDO request from the client (master) (ETG.1000.6 §5.6.2: initiate
/// download §5.6.2.1/2, download segment §5.6.2.3, initiate upload
/// §5.6.2.4/5, upload segment §5.6.2.6, abort §5.6.2.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SdoRequest<'a> {
    /// Initiate SDO download (CCS 1).
    InitiateDownload {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// Expedited or normal payload.
        kind: DownloadKind<'a>,
    },
    /// Download SDO segment (CCS 0).
    DownloadSegment {
        /// Toggle bit.
        toggle: bool,
        /// Last segment.
        last: bool,
        /// Segment data, padding removed.
        data: &'a [u8],
    },
    /// Initiate SDO upload (CCS 2).
    InitiateUpload {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
    },
    /// Upload SDO segment (CCS 3).
    UploadSegment {
        /// Toggle bit.
        toggle: bool,
    },
    /// Abort SDO transfer (CCS 4).
    Abort {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Abort code.
        code: SdoAbortCode,
    },
    /// A request with an unknown command specifier (5..=7).
    Unknown {
        /// The raw command byte.
        command: u8,
    },
}

/// An SDO response from the server (slave) (ETG.1000.6 §5.6.2: initiate
/// download response, download segment response, initiate upload response
/// expedited/normal, upload segment response (Table 39), abort).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SdoResponse<'a> {
    /// Initiate SDO download response (SCS 3).
    InitiateDownloadAck {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access, echoed from the request.
        complete_access: bool,
    },
    /// Download SDO segment response (SCS 1).
    DownloadSegmentAck {
        /// Toggle bit, echoed from the request.
        toggle: bool,
    },
    /// Initiate SDO upload response, expedited (SCS 2, e = 1).
    UploadExpedited {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// The four data bytes; the first `len` are valid.
        data: [u8; 4],
        /// Number of valid bytes, 1..=4.
        len: u8,
    },
    /// Initiate SDO upload response, normal (SCS 2, e = 0).
    UploadNormal {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// Complete size of the object.
        complete_size: u32,
        /// First part of the data (to the end of the mailbox data).
        data: &'a [u8],
    },
    /// Upload SDO segment response (SCS 0).
    UploadSegment {
        /// Toggle bit, echoed from the request.
        toggle: bool,
        /// Last segment.
        last: bool,
        /// Segment data, padding removed.
        data: &'a [u8],
    },
    /// Abort SDO transfer (SCS 4).
    Abort {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Abort code.
        code: SdoAbortCode,
    },
    /// A response with an unknown command specifier (5..=7).
    Unknown {
        /// The raw command byte.
        command: u8,
    },
}

fn initiate_cmd(specifier: u8, complete_access: bool) -> u8 {
    (specifier << CMD_SPECIFIER_SHIFT)
        | if complete_access {
            CMD_COMPLETE_ACCESS
        } else {
            0
        }
}

fn segment_cmd(specifier: u8, toggle: bool, last: bool, data_len: usize) -> u8 {
    let unused = SEGMENT_MIN_DATA_LEN.saturating_sub(data_len);
    // `unused` is at most 7, so it fits in the 3-bit field.
    let unused = (unused as u8) & 0x07;
    (specifier << CMD_SPECIFIER_SHIFT)
        | if toggle { CMD_TOGGLE } else { 0 }
        | (unused << 1)
        | if last { CMD_LAST_SEGMENT } else { 0 }
}

fn segment_len(data_len: usize) -> usize {
    1 + data_len.max(SEGMENT_MIN_DATA_LEN)
}

/// Command byte of an expedited initiate (download request or upload
/// response) with `len` valid bytes; `Unrepresentable` unless 1..=4.
fn expedited_cmd(specifier: u8, complete_access: bool, len: u8) -> Result<u8, WireError> {
    if !(1..=4).contains(&len) {
        return Err(WireError::Unrepresentable);
    }
    Ok(initiate_cmd(specifier, complete_access)
        | ((4 - len) << 2)
        | CMD_EXPEDITED
        | CMD_SIZE_INDICATOR)
}

/// Zeroes `buf[..len]` after checking it fits, returning the view to fill.
fn prepare(buf: &mut [u8], len: usize) -> Result<Sdo<&mut [u8]>, WireError> {
    let region = buf.get_mut(..len).ok_or(WireError::BufferTooSmall)?;
    region.fill(0);
    Ok(Sdo::new_unchecked(region))
}

fn emit_initiate(
    buf: &mut [u8],
    command: u8,
    index: u16,
    sub: u8,
    data4: [u8; 4],
    extra: &[u8],
) -> Result<usize, WireError> {
    let len = SDO_LEN + extra.len();
    let mut sdo = prepare(buf, len)?;
    sdo.set_command(command);
    sdo.set_index(index);
    sdo.set_sub_index(sub);
    sdo.set_data4(data4);
    super::set_bytes(sdo.normal_data_mut(), 0, extra);
    Ok(len)
}

fn emit_segment(buf: &mut [u8], command: u8, data: &[u8]) -> Result<usize, WireError> {
    let len = segment_len(data.len());
    let mut sdo = prepare(buf, len)?;
    sdo.set_command(command);
    super::set_bytes(sdo.segment_data_mut(), 0, data);
    Ok(len)
}

impl<'a> SdoRequest<'a> {
    /// Parses a request from the bytes after the CoE header, which must be
    /// bounded by the mailbox length (normal and segment data run to the end
    /// of `sdo`).
    ///
    /// Fails only with [`WireError::Truncated`] when fewer than 8 bytes are
    /// given; unknown command specifiers give [`SdoRequest::Unknown`].
    pub fn parse(sdo: &'a [u8]) -> Result<Self, WireError> {
        let v = Sdo::new_checked(sdo)?;
        let index = v.index();
        let sub = v.sub_index();
        let complete_access = v.complete_access();
        let repr = match v.command_specifier() {
            ccs::INITIATE_DOWNLOAD => {
                let kind = if v.expedited() {
                    DownloadKind::Expedited {
                        data: v.data4(),
                        len: v.expedited_len(),
                    }
                } else {
                    DownloadKind::Normal {
                        complete_size: v.complete_size(),
                        data: super::tail(sdo, field::SDO_NORMAL_DATA),
                    }
                };
                Self::InitiateDownload {
                    index,
                    sub,
                    complete_access,
                    kind,
                }
            }
            ccs::DOWNLOAD_SEGMENT => Self::DownloadSegment {
                toggle: v.toggle(),
                last: v.last_segment(),
                data: segment_data(sdo),
            },
            ccs::INITIATE_UPLOAD => Self::InitiateUpload {
                index,
                sub,
                complete_access,
            },
            ccs::UPLOAD_SEGMENT => Self::UploadSegment { toggle: v.toggle() },
            ccs::ABORT => Self::Abort {
                index,
                sub,
                code: v.abort_code(),
            },
            _ => Self::Unknown {
                command: v.command(),
            },
        };
        Ok(repr)
    }

    /// Number of bytes [`SdoRequest::emit`] writes (after the CoE header).
    pub fn buffer_len(&self) -> usize {
        match self {
            Self::InitiateDownload {
                kind: DownloadKind::Normal { data, .. },
                ..
            } => SDO_LEN + data.len(),
            Self::DownloadSegment { data, .. } => segment_len(data.len()),
            _ => SDO_LEN,
        }
    }

    /// Writes the request into `buf` (the bytes after the CoE header) and
    /// returns the number of bytes written; padding bytes are zeroed.
    ///
    /// Fails with [`WireError::BufferTooSmall`] if `buf` is shorter than
    /// [`SdoRequest::buffer_len`] and with [`WireError::Unrepresentable`]
    /// for expedited data lengths outside 1..=4.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, WireError> {
        match *self {
            Self::InitiateDownload {
                index,
                sub,
                complete_access,
                kind,
            } => match kind {
                DownloadKind::Expedited { data, len } => {
                    let cmd = expedited_cmd(ccs::INITIATE_DOWNLOAD, complete_access, len)?;
                    emit_initiate(buf, cmd, index, sub, data, &[])
                }
                DownloadKind::Normal {
                    complete_size,
                    data,
                } => {
                    let cmd =
                        initiate_cmd(ccs::INITIATE_DOWNLOAD, complete_access) | CMD_SIZE_INDICATOR;
                    emit_initiate(buf, cmd, index, sub, complete_size.to_le_bytes(), data)
                }
            },
            Self::DownloadSegment { toggle, last, data } => emit_segment(
                buf,
                segment_cmd(ccs::DOWNLOAD_SEGMENT, toggle, last, data.len()),
                data,
            ),
            Self::InitiateUpload {
                index,
                sub,
                complete_access,
            } => emit_initiate(
                buf,
                initiate_cmd(ccs::INITIATE_UPLOAD, complete_access),
                index,
                sub,
                [0; 4],
                &[],
            ),
            Self::UploadSegment { toggle } => emit_segment(
                buf,
                (ccs::UPLOAD_SEGMENT << CMD_SPECIFIER_SHIFT) | if toggle { CMD_TOGGLE } else { 0 },
                &[],
            ),
            Self::Abort { index, sub, code } => emit_initiate(
                buf,
                ccs::ABORT << CMD_SPECIFIER_SHIFT,
                index,
                sub,
                u32::from(code).to_le_bytes(),
                &[],
            ),
            Self::Unknown { command } => emit_initiate(buf, command, 0, 0, [0; 4], &[]),
        }
    }
}

impl<'a> SdoResponse<'a> {
    /// Parses a response from the bytes after the CoE header, which must be
    /// bounded by the mailbox length (normal and segment data run to the end
    /// of `sdo`).
    ///
    /// Fails only with [`WireError::Truncated`] when fewer than 8 bytes are
    /// given; unknown command specifiers give [`SdoResponse::Unknown`].
    pub fn parse(sdo: &'a [u8]) -> Result<Self, WireError> {
        let v = Sdo::new_checked(sdo)?;
        let index = v.index();
        let sub = v.sub_index();
        let complete_access = v.complete_access();
        let repr = match v.command_specifier() {
            scs::INITIATE_DOWNLOAD => Self::InitiateDownloadAck {
                index,
                sub,
                complete_access,
            },
            scs::DOWNLOAD_SEGMENT => Self::DownloadSegmentAck { toggle: v.toggle() },
            scs::INITIATE_UPLOAD if v.expedited() => Self::UploadExpedited {
                index,
                sub,
                complete_access,
                data: v.data4(),
                len: v.expedited_len(),
            },
            scs::INITIATE_UPLOAD => Self::UploadNormal {
                index,
                sub,
                complete_access,
                complete_size: v.complete_size(),
                data: super::tail(sdo, field::SDO_NORMAL_DATA),
            },
            scs::UPLOAD_SEGMENT => Self::UploadSegment {
                toggle: v.toggle(),
                last: v.last_segment(),
                data: segment_data(sdo),
            },
            scs::ABORT => Self::Abort {
                index,
                sub,
                code: v.abort_code(),
            },
            _ => Self::Unknown {
                command: v.command(),
            },
        };
        Ok(repr)
    }

    /// Number of bytes [`SdoResponse::emit`] writes (after the CoE header).
    pub fn buffer_len(&self) -> usize {
        match self {
            Self::UploadNormal { data, .. } => SDO_LEN + data.len(),
            Self::UploadSegment { data, .. } => segment_len(data.len()),
            _ => SDO_LEN,
        }
    }

    /// Writes the response into `buf` (the bytes after the CoE header) and
    /// returns the number of bytes written; padding bytes are zeroed.
    ///
    /// Fails with [`WireError::BufferTooSmall`] if `buf` is shorter than
    /// [`SdoResponse::buffer_len`] and with [`WireError::Unrepresentable`]
    /// for expedited data lengths outside 1..=4.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, WireError> {
        match *self {
            Self::InitiateDownloadAck {
                index,
                sub,
                complete_access,
            } => emit_initiate(
                buf,
                initiate_cmd(scs::INITIATE_DOWNLOAD, complete_access),
                index,
                sub,
                [0; 4],
                &[],
            ),
            Self::DownloadSegmentAck { toggle } => emit_segment(
                buf,
                (scs::DOWNLOAD_SEGMENT << CMD_SPECIFIER_SHIFT)
                    | if toggle { CMD_TOGGLE } else { 0 },
                &[],
            ),
            Self::UploadExpedited {
                index,
                sub,
                complete_access,
                data,
                len,
            } => {
                let cmd = expedited_cmd(scs::INITIATE_UPLOAD, complete_access, len)?;
                // Unused expedited bytes are sent as zero.
                let mut four = [0u8; 4];
                super::set_bytes(&mut four, 0, data.get(..usize::from(len)).unwrap_or(&data));
                emit_initiate(buf, cmd, index, sub, four, &[])
            }
            Self::UploadNormal {
                index,
                sub,
                complete_access,
                complete_size,
                data,
            } => emit_initiate(
                buf,
                initiate_cmd(scs::INITIATE_UPLOAD, complete_access) | CMD_SIZE_INDICATOR,
                index,
                sub,
                complete_size.to_le_bytes(),
                data,
            ),
            Self::UploadSegment { toggle, last, data } => emit_segment(
                buf,
                segment_cmd(scs::UPLOAD_SEGMENT, toggle, last, data.len()),
                data,
            ),
            Self::Abort { index, sub, code } => emit_initiate(
                buf,
                scs::ABORT << CMD_SPECIFIER_SHIFT,
                index,
                sub,
                u32::from(code).to_le_bytes(),
                &[],
            ),
            Self::Unknown { command } => emit_initiate(buf, command, 0, 0, [0; 4], &[]),
        }
    }
}

/// Segment data of `sdo` with the lifetime of the input slice.
fn segment_data(sdo: &[u8]) -> &[u8] {
    let region = super::tail(sdo, field::SEGMENT_DATA);
    let used = Sdo::new_unchecked(sdo).segment_data().len();
    region.get(..used).unwrap_or(&[])
}

// ---------------------------------------------------------------------------
// SDO information
// ---------------------------------------------------------------------------

/// SDO information opcode (ETG.1000.6 §5.6.3.2, SDO information header
/// "OpCode").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SdoInfoOpcode {
    /// `1` Get OD list request.
    GetOdListReq,
    /// `2` Get OD list response.
    GetOdListResp,
    /// `3` Get object description request.
    GetObjDescReq,
    /// `4` Get object description response.
    GetObjDescResp,
    /// `5` Get entry description request.
    GetEntryDescReq,
    /// `6` Get entry description response.
    GetEntryDescResp,
    /// `7` SDO information error request.
    SdoInfoErrorReq,
    /// Any other value.
    Unknown(u8),
}

impl From<u8> for SdoInfoOpcode {
    fn from(raw: u8) -> Self {
        match raw {
            1 => Self::GetOdListReq,
            2 => Self::GetOdListResp,
            3 => Self::GetObjDescReq,
            4 => Self::GetObjDescResp,
            5 => Self::GetEntryDescReq,
            6 => Self::GetEntryDescResp,
            7 => Self::SdoInfoErrorReq,
            other => Self::Unknown(other),
        }
    }
}

impl From<SdoInfoOpcode> for u8 {
    fn from(op: SdoInfoOpcode) -> Self {
        match op {
            SdoInfoOpcode::GetOdListReq => 1,
            SdoInfoOpcode::GetOdListResp => 2,
            SdoInfoOpcode::GetObjDescReq => 3,
            SdoInfoOpcode::GetObjDescResp => 4,
            SdoInfoOpcode::GetEntryDescReq => 5,
            SdoInfoOpcode::GetEntryDescResp => 6,
            SdoInfoOpcode::SdoInfoErrorReq => 7,
            SdoInfoOpcode::Unknown(raw) => raw,
        }
    }
}

const INFO_INCOMPLETE: u8 = 0x80;
const INFO_OPCODE_MASK: u8 = 0x7F;

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
            super::get_u8(self.buffer.as_ref(), field::INFO_OPCODE) & INFO_OPCODE_MASK,
        )
    }

    /// The incomplete flag (bit 7 of byte 0): more fragments follow.
    pub fn incomplete(&self) -> bool {
        super::get_u8(self.buffer.as_ref(), field::INFO_OPCODE) & INFO_INCOMPLETE != 0
    }

    /// The reserved byte 1.
    pub fn reserved(&self) -> u8 {
        super::get_u8(self.buffer.as_ref(), field::INFO_RESERVED)
    }

    /// Number of fragments still to come after this one.
    pub fn fragments_left(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::INFO_FRAGMENTS_LEFT)
    }

    /// The service data after the header.
    pub fn payload(&self) -> &[u8] {
        super::tail(self.buffer.as_ref(), field::INFO_DATA)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> SdoInfo<T> {
    /// Sets the opcode (masked to 7 bits), keeping the incomplete flag.
    pub fn set_opcode(&mut self, op: SdoInfoOpcode) {
        let b = super::get_u8(self.buffer.as_ref(), field::INFO_OPCODE);
        let b = (b & INFO_INCOMPLETE) | (u8::from(op) & INFO_OPCODE_MASK);
        super::set_u8(self.buffer.as_mut(), field::INFO_OPCODE, b);
    }

    /// Sets or clears the incomplete flag.
    pub fn set_incomplete(&mut self, incomplete: bool) {
        let b = super::get_u8(self.buffer.as_ref(), field::INFO_OPCODE);
        let b = if incomplete {
            b | INFO_INCOMPLETE
        } else {
            b & !INFO_INCOMPLETE
        };
        super::set_u8(self.buffer.as_mut(), field::INFO_OPCODE, b);
    }

    /// Sets the reserved byte.
    pub fn set_reserved(&mut self, value: u8) {
        super::set_u8(self.buffer.as_mut(), field::INFO_RESERVED, value);
    }

    /// Sets the number of fragments left.
    pub fn set_fragments_left(&mut self, n: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::INFO_FRAGMENTS_LEFT, n);
    }

    /// The mutable service data after the header.
    pub fn payload_mut(&mut self) -> &mut [u8] {
        super::tail_mut(self.buffer.as_mut(), field::INFO_DATA)
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

// ---------------------------------------------------------------------------
// Emergency
// ---------------------------------------------------------------------------

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
        super::get_u16_le(self.buffer.as_ref(), field::EMCY_CODE)
    }

    /// The error register (value of object 0x1001).
    pub fn error_register(&self) -> u8 {
        super::get_u8(self.buffer.as_ref(), field::EMCY_REGISTER)
    }

    /// The five manufacturer-specific data bytes.
    pub fn data(&self) -> [u8; 5] {
        super::get_array(self.buffer.as_ref(), field::EMCY_DATA)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Emergency<T> {
    /// Sets the error code.
    pub fn set_error_code(&mut self, code: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::EMCY_CODE, code);
    }

    /// Sets the error register.
    pub fn set_error_register(&mut self, register: u8) {
        super::set_u8(self.buffer.as_mut(), field::EMCY_REGISTER, register);
    }

    /// Sets the manufacturer-specific data.
    pub fn set_data(&mut self, data: [u8; 5]) {
        super::set_array(self.buffer.as_mut(), field::EMCY_DATA, data);
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

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::*;

    /// Mailbox data of an SDO upload request for 0x1018:01 (CoE header
    /// 0x2000 = SDO request).
    static UPLOAD_REQUEST_BYTES: [u8; 10] =
        [0x00, 0x20, 0x40, 0x18, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00];

    /// Expedited upload response for 0x1018:01 = 0x0000_029A (4 bytes).
    static EXPEDITED_UPLOAD_RESPONSE_BYTES: [u8; 10] =
        [0x00, 0x30, 0x43, 0x18, 0x10, 0x01, 0x9A, 0x02, 0x00, 0x00];

    /// Expedited download request 0x6040:00 = 0x000F (2 bytes, n = 2).
    static EXPEDITED_DOWNLOAD_BYTES: [u8; 10] =
        [0x00, 0x20, 0x2B, 0x40, 0x60, 0x00, 0x0F, 0x00, 0x00, 0x00];

    /// Initiate download response for 0x6040:00.
    static DOWNLOAD_ACK_BYTES: [u8; 10] =
        [0x00, 0x30, 0x60, 0x40, 0x60, 0x00, 0x00, 0x00, 0x00, 0x00];

    /// Normal upload response for 0x1008:00 = "TD-1-NAME" (9 bytes).
    static NORMAL_UPLOAD_RESPONSE_BYTES: [u8; 19] = [
        0x00, 0x30, 0x41, 0x08, 0x10, 0x00, 0x09, 0x00, 0x00, 0x00, b'T', b'D', b'-', b'1', b'-',
        b'N', b'A', b'M', b'E',
    ];

    /// Normal download request with complete access for 0x1C12 (complete
    /// size 6, all 6 bytes in the request).
    static NORMAL_DOWNLOAD_BYTES: [u8; 16] = [
        0x00, 0x20, 0x31, 0x12, 0x1C, 0x00, 0x06, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x16, 0x01,
        0x16,
    ];

    /// Last download segment carrying 3 bytes, padded to 7 (unused = 4).
    static SHORT_SEGMENT_BYTES: [u8; 10] =
        [0x00, 0x20, 0x09, b'a', b'b', b'c', 0x00, 0x00, 0x00, 0x00];

    /// Upload segment response, toggle 1, last, 9 bytes (longer than 7).
    static LONG_SEGMENT_RESPONSE_BYTES: [u8; 12] = [
        0x00, 0x30, 0x11, b'1', b'2', b'3', b'4', b'5', b'6', b'7', b'8', b'9',
    ];

    /// Abort request for 0x7000:00, object does not exist.
    static ABORT_BYTES: [u8; 10] = [0x00, 0x20, 0x80, 0x00, 0x70, 0x00, 0x00, 0x00, 0x02, 0x06];

    /// Emergency 0x8130 (life guard/heartbeat error), register 0x11.
    static EMERGENCY_BYTES: [u8; 10] = [0x00, 0x10, 0x30, 0x81, 0x11, 1, 2, 3, 4, 5];

    /// SDO information: get OD list request for all objects (list type 1).
    static SDO_INFO_BYTES: [u8; 8] = [0x00, 0x80, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00];

    /// The SDO part of a CoE element (after the 2-byte CoE header).
    fn sdo_body(bytes: &[u8]) -> &[u8] {
        assert!(CoeHeader::new_checked(bytes).is_ok());
        &bytes[HEADER_LEN..]
    }

    #[test]
    fn deconstructs_coe_header() {
        let coe = CoeHeader::new_checked(&UPLOAD_REQUEST_BYTES[..]).unwrap();
        assert_eq!(coe.number(), 0);
        assert_eq!(coe.service(), CoeService::SdoRequest);
        assert_eq!(coe.payload(), &UPLOAD_REQUEST_BYTES[2..]);
        let coe = Coe::new_checked(&EMERGENCY_BYTES[..]).unwrap();
        assert_eq!(coe.service(), CoeService::Emergency);
    }

    #[test]
    fn constructs_coe_header() {
        let mut bytes = [0xFFu8; 2];
        CoeHeader::emit_into(&mut bytes, 0, CoeService::SdoResponse);
        assert_eq!(bytes, [0x00, 0x30]);
        let mut coe = CoeHeader::new_unchecked(&mut bytes[..]);
        coe.set_number(0x1FF);
        coe.set_service(CoeService::RxPdo);
        assert_eq!(coe.number(), 0x1FF);
        assert_eq!(coe.service(), CoeService::RxPdo);
        assert_eq!(bytes, [0xFF, 0x51]);
        // too short: nothing written, no panic
        let mut one = [0u8; 1];
        CoeHeader::emit_into(&mut one, 1, CoeService::SdoRequest);
        assert_eq!(one, [0]);
    }

    #[test]
    fn coe_repr_round_trip_and_limits() {
        let coe = CoeHeader::new_checked(&SDO_INFO_BYTES[..]).unwrap();
        let repr = CoeRepr::parse(&coe).unwrap();
        assert_eq!(
            repr,
            CoeRepr {
                number: 0,
                service: CoeService::SdoInformation
            }
        );
        let mut out = [0xAAu8; 2];
        repr.emit(&mut CoeHeader::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, [0x00, 0x80]);
        let bad = CoeRepr {
            number: 0x200,
            service: CoeService::TxPdo,
        };
        assert_eq!(
            bad.emit(&mut CoeHeader::new_unchecked(&mut out[..])),
            Err(WireError::Unrepresentable)
        );
        assert_eq!(
            repr.emit(&mut CoeHeader::new_unchecked(&mut out[..1])),
            Err(WireError::BufferTooSmall)
        );
        assert_eq!(
            CoeRepr::parse(&CoeHeader::new_unchecked(&[0u8][..])),
            Err(WireError::Truncated)
        );
    }

    #[test]
    fn unknown_coe_service_is_kept() {
        let coe = CoeHeader::new_checked(&[0x00u8, 0xF0][..]).unwrap();
        assert_eq!(coe.service(), CoeService::Unknown(15));
        for raw in 0..16u8 {
            assert_eq!(u8::from(CoeService::from(raw)), raw);
        }
    }

    #[test]
    fn parses_initiate_upload_request() {
        let req = SdoRequest::parse(sdo_body(&UPLOAD_REQUEST_BYTES)).unwrap();
        assert_eq!(
            req,
            SdoRequest::InitiateUpload {
                index: 0x1018,
                sub: 1,
                complete_access: false
            }
        );
        let mut out = [0xEEu8; 8];
        assert_eq!(req.emit(&mut out), Ok(8));
        assert_eq!(out, UPLOAD_REQUEST_BYTES[2..]);
    }

    #[test]
    fn sdo_view_deconstructs_expedited_download() {
        let sdo = Sdo::new_checked(sdo_body(&EXPEDITED_DOWNLOAD_BYTES)).unwrap();
        assert_eq!(sdo.command_specifier(), ccs::INITIATE_DOWNLOAD);
        assert!(sdo.expedited());
        assert!(sdo.size_indicator());
        assert_eq!(sdo.expedited_unused(), 2);
        assert_eq!(sdo.expedited_len(), 2);
        assert!(!sdo.complete_access());
        assert_eq!(sdo.index(), 0x6040);
        assert_eq!(sdo.sub_index(), 0);
        assert_eq!(sdo.data4(), [0x0F, 0, 0, 0]);
    }

    #[test]
    fn expedited_download_round_trip() {
        let req = SdoRequest::parse(sdo_body(&EXPEDITED_DOWNLOAD_BYTES)).unwrap();
        let expected = SdoRequest::InitiateDownload {
            index: 0x6040,
            sub: 0,
            complete_access: false,
            kind: DownloadKind::Expedited {
                data: [0x0F, 0, 0, 0],
                len: 2,
            },
        };
        assert_eq!(req, expected);
        if let SdoRequest::InitiateDownload { kind, .. } = req {
            assert_eq!(kind.data(), &[0x0F, 0x00]);
        }
        let mut out = [0u8; 8];
        assert_eq!(expected.emit(&mut out), Ok(8));
        assert_eq!(out, EXPEDITED_DOWNLOAD_BYTES[2..]);
    }

    #[test]
    fn expedited_size_bits_give_data_length() {
        for (cmd, len) in [(0x2F, 1), (0x2B, 2), (0x27, 3), (0x23, 4), (0x22, 4)] {
            let mut body = [0u8; 8];
            body[0] = cmd;
            match SdoRequest::parse(&body).unwrap() {
                SdoRequest::InitiateDownload {
                    kind: DownloadKind::Expedited { len: l, .. },
                    ..
                } => assert_eq!(l, len, "cmd {cmd:#x}"),
                other => panic!("unexpected {other:?}"),
            }
        }
    }

    #[test]
    fn expedited_with_impossible_length_is_unrepresentable() {
        let mut out = [0u8; 8];
        for len in [0u8, 5] {
            let req = SdoRequest::InitiateDownload {
                index: 1,
                sub: 0,
                complete_access: false,
                kind: DownloadKind::Expedited { data: [0; 4], len },
            };
            assert_eq!(req.emit(&mut out), Err(WireError::Unrepresentable));
            let resp = SdoResponse::UploadExpedited {
                index: 1,
                sub: 0,
                complete_access: false,
                data: [0; 4],
                len,
            };
            assert_eq!(resp.emit(&mut out), Err(WireError::Unrepresentable));
        }
    }

    #[test]
    fn download_ack_round_trip() {
        let resp = SdoResponse::parse(sdo_body(&DOWNLOAD_ACK_BYTES)).unwrap();
        assert_eq!(
            resp,
            SdoResponse::InitiateDownloadAck {
                index: 0x6040,
                sub: 0,
                complete_access: false
            }
        );
        let mut out = [0xFFu8; 8];
        assert_eq!(resp.emit(&mut out), Ok(8));
        assert_eq!(out, DOWNLOAD_ACK_BYTES[2..]);
    }

    #[test]
    fn expedited_upload_response_round_trip() {
        let resp = SdoResponse::parse(sdo_body(&EXPEDITED_UPLOAD_RESPONSE_BYTES)).unwrap();
        let expected = SdoResponse::UploadExpedited {
            index: 0x1018,
            sub: 1,
            complete_access: false,
            data: [0x9A, 0x02, 0, 0],
            len: 4,
        };
        assert_eq!(resp, expected);
        let mut out = [0u8; 8];
        assert_eq!(expected.emit(&mut out), Ok(8));
        assert_eq!(out, EXPEDITED_UPLOAD_RESPONSE_BYTES[2..]);
    }

    #[test]
    fn expedited_upload_emit_zeroes_unused_bytes() {
        let resp = SdoResponse::UploadExpedited {
            index: 0x6041,
            sub: 0,
            complete_access: false,
            data: [0x37, 0x02, 0xAA, 0xBB],
            len: 2,
        };
        let mut out = [0xFFu8; 8];
        assert_eq!(resp.emit(&mut out), Ok(8));
        assert_eq!(out, [0x4B, 0x41, 0x60, 0x00, 0x37, 0x02, 0x00, 0x00]);
    }

    #[test]
    fn normal_upload_response_round_trip() {
        let body = sdo_body(&NORMAL_UPLOAD_RESPONSE_BYTES);
        let resp = SdoResponse::parse(body).unwrap();
        let expected = SdoResponse::UploadNormal {
            index: 0x1008,
            sub: 0,
            complete_access: false,
            complete_size: 9,
            data: b"TD-1-NAME",
        };
        assert_eq!(resp, expected);
        assert_eq!(expected.buffer_len(), 17);
        let mut out = [0u8; 32];
        assert_eq!(expected.emit(&mut out), Ok(17));
        assert_eq!(&out[..17], body);
    }

    #[test]
    fn normal_download_with_complete_access_round_trip() {
        let body = sdo_body(&NORMAL_DOWNLOAD_BYTES);
        let req = SdoRequest::parse(body).unwrap();
        let expected = SdoRequest::InitiateDownload {
            index: 0x1C12,
            sub: 0,
            complete_access: true,
            kind: DownloadKind::Normal {
                complete_size: 6,
                data: &[0x02, 0x00, 0x00, 0x16, 0x01, 0x16],
            },
        };
        assert_eq!(req, expected);
        assert_eq!(expected.buffer_len(), 14);
        let mut out = [0u8; 14];
        assert_eq!(expected.emit(&mut out), Ok(14));
        assert_eq!(&out[..], body);
    }

    #[test]
    fn short_segment_honours_size_bits() {
        let body = sdo_body(&SHORT_SEGMENT_BYTES);
        let sdo = Sdo::new_checked(body).unwrap();
        assert_eq!(sdo.segment_unused(), 4);
        assert!(sdo.last_segment());
        assert!(!sdo.toggle());
        let req = SdoRequest::parse(body).unwrap();
        let expected = SdoRequest::DownloadSegment {
            toggle: false,
            last: true,
            data: b"abc",
        };
        assert_eq!(req, expected);
        assert_eq!(expected.buffer_len(), 8);
        let mut out = [0xFFu8; 8];
        assert_eq!(expected.emit(&mut out), Ok(8));
        assert_eq!(&out[..], body);
    }

    #[test]
    fn long_segment_runs_to_mailbox_length() {
        let body = sdo_body(&LONG_SEGMENT_RESPONSE_BYTES);
        let resp = SdoResponse::parse(body).unwrap();
        let expected = SdoResponse::UploadSegment {
            toggle: true,
            last: true,
            data: b"123456789",
        };
        assert_eq!(resp, expected);
        let mut out = [0u8; 10];
        assert_eq!(expected.emit(&mut out), Ok(10));
        assert_eq!(&out[..], body);
    }

    #[test]
    fn empty_segment_is_padded_to_seven_bytes() {
        let seg = SdoResponse::UploadSegment {
            toggle: false,
            last: true,
            data: &[],
        };
        let mut out = [0xFFu8; 8];
        assert_eq!(seg.emit(&mut out), Ok(8));
        assert_eq!(out, [0x0F, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(
            SdoResponse::parse(&out).unwrap(),
            SdoResponse::UploadSegment {
                toggle: false,
                last: true,
                data: &[]
            }
        );
    }

    #[test]
    fn segment_acks_and_segment_requests_round_trip() {
        let cases = [
            (
                SdoResponse::DownloadSegmentAck { toggle: true },
                [0x30u8, 0, 0, 0, 0, 0, 0, 0],
            ),
            (
                SdoResponse::DownloadSegmentAck { toggle: false },
                [0x20, 0, 0, 0, 0, 0, 0, 0],
            ),
        ];
        for (resp, bytes) in cases {
            let mut out = [0xFFu8; 8];
            assert_eq!(resp.emit(&mut out), Ok(8));
            assert_eq!(out, bytes);
            assert_eq!(SdoResponse::parse(&bytes).unwrap(), resp);
        }
        let req = SdoRequest::UploadSegment { toggle: true };
        let mut out = [0xFFu8; 8];
        assert_eq!(req.emit(&mut out), Ok(8));
        assert_eq!(out, [0x70, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(SdoRequest::parse(&out).unwrap(), req);
    }

    #[test]
    fn abort_request_and_response_round_trip() {
        let body = sdo_body(&ABORT_BYTES);
        let expected = SdoRequest::Abort {
            index: 0x7000,
            sub: 0,
            code: SdoAbortCode::ObjectNotFound,
        };
        assert_eq!(SdoRequest::parse(body).unwrap(), expected);
        let mut out = [0u8; 8];
        assert_eq!(expected.emit(&mut out), Ok(8));
        assert_eq!(&out[..], body);

        let resp = SdoResponse::Abort {
            index: 0x7000,
            sub: 0,
            code: SdoAbortCode::ObjectNotFound,
        };
        assert_eq!(SdoResponse::parse(body).unwrap(), resp);
        let mut out = [0u8; 8];
        assert_eq!(resp.emit(&mut out), Ok(8));
        assert_eq!(&out[..], body);
    }

    #[test]
    fn unknown_command_specifier_is_kept() {
        let body = [0xE0u8, 1, 2, 3, 4, 5, 6, 7];
        assert_eq!(
            SdoRequest::parse(&body).unwrap(),
            SdoRequest::Unknown { command: 0xE0 }
        );
        assert_eq!(
            SdoResponse::parse(&body).unwrap(),
            SdoResponse::Unknown { command: 0xE0 }
        );
        let mut out = [0xFFu8; 8];
        assert_eq!(SdoRequest::Unknown { command: 0xA0 }.emit(&mut out), Ok(8));
        assert_eq!(out, [0xA0, 0, 0, 0, 0, 0, 0, 0]);
    }

    #[test]
    fn sdo_shorter_than_eight_bytes_is_truncated() {
        for n in 0..SDO_LEN {
            let body = &UPLOAD_REQUEST_BYTES[2..2 + n];
            assert_eq!(SdoRequest::parse(body), Err(WireError::Truncated));
            assert_eq!(SdoResponse::parse(body), Err(WireError::Truncated));
        }
    }

    #[test]
    fn emit_into_short_buffer_fails_without_writing() {
        let resp = SdoResponse::UploadNormal {
            index: 0x1008,
            sub: 0,
            complete_access: false,
            complete_size: 9,
            data: b"TD-1-NAME",
        };
        let mut out = [0xEEu8; 16];
        assert_eq!(resp.emit(&mut out), Err(WireError::BufferTooSmall));
        assert_eq!(out, [0xEE; 16]);
        let seg = SdoRequest::DownloadSegment {
            toggle: false,
            last: false,
            data: b"x",
        };
        assert_eq!(seg.emit(&mut out[..7]), Err(WireError::BufferTooSmall));
    }

    #[test]
    fn unchecked_short_sdo_accessors_do_not_panic() {
        let sdo = Sdo::new_unchecked(&[0x09u8, b'a'][..]);
        assert_eq!(sdo.segment_data(), b"a");
        assert_eq!(sdo.index(), 0);
        assert_eq!(sdo.complete_size(), 0);
        assert!(sdo.normal_data().is_empty());
        let empty = Sdo::new_unchecked(&[][..]);
        assert!(empty.segment_data().is_empty());
        assert_eq!(empty.expedited_len(), 4);
    }

    #[test]
    fn abort_codes_round_trip_and_have_text() {
        use core::fmt::Write;
        assert_eq!(SdoAbortCode::ALL.len(), 31);
        for &code in SdoAbortCode::ALL {
            let raw = u32::from(code);
            assert_eq!(SdoAbortCode::from(raw), code);
            assert!(!code.description().is_empty());
        }
        assert_eq!(SdoAbortCode::from(0x0601_0001), SdoAbortCode::WriteOnly);
        assert_eq!(SdoAbortCode::from(0x0800_0022), SdoAbortCode::InvalidState);
        assert_eq!(
            SdoAbortCode::from(0x1234_5678),
            SdoAbortCode::Unknown(0x1234_5678)
        );
        assert_eq!(u32::from(SdoAbortCode::Unknown(7)), 7);
        let mut s: heapless::String<96> = heapless::String::new();
        write!(s, "{}", SdoAbortCode::ObjectNotFound).unwrap();
        assert_eq!(
            s.as_str(),
            "0x06020000: the object does not exist in the object dictionary"
        );
    }

    #[test]
    fn sdo_info_header_deconstructs_and_round_trips() {
        let coe = CoeHeader::new_checked(&SDO_INFO_BYTES[..]).unwrap();
        assert_eq!(coe.service(), CoeService::SdoInformation);
        let info = SdoInfo::new_checked(coe.payload()).unwrap();
        assert_eq!(info.opcode(), SdoInfoOpcode::GetOdListReq);
        assert!(!info.incomplete());
        assert_eq!(info.reserved(), 0);
        assert_eq!(info.fragments_left(), 0);
        assert_eq!(info.payload(), &[0x01, 0x00]);
        let repr = SdoInfoRepr::parse(&info).unwrap();
        let mut out = [0xFFu8; 4];
        repr.emit(&mut SdoInfo::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, SDO_INFO_BYTES[2..6]);
    }

    #[test]
    fn sdo_info_incomplete_flag_is_separate_from_opcode() {
        let mut bytes = [0u8; 6];
        let mut info = SdoInfo::new_unchecked(&mut bytes[..]);
        info.set_opcode(SdoInfoOpcode::GetOdListResp);
        info.set_incomplete(true);
        info.set_fragments_left(3);
        info.payload_mut().copy_from_slice(&[0x00, 0x10]);
        assert_eq!(info.opcode(), SdoInfoOpcode::GetOdListResp);
        assert!(info.incomplete());
        info.set_opcode(SdoInfoOpcode::Unknown(0x7F));
        assert!(info.incomplete());
        assert_eq!(bytes, [0xFF, 0x00, 0x03, 0x00, 0x00, 0x10]);
        for raw in 0..0x80u8 {
            assert_eq!(u8::from(SdoInfoOpcode::from(raw)), raw);
        }
    }

    #[test]
    fn sdo_info_truncated_or_unrepresentable_is_rejected() {
        assert_eq!(
            SdoInfo::new_checked(&SDO_INFO_BYTES[2..5]).unwrap_err(),
            WireError::Truncated
        );
        let bad = SdoInfoRepr {
            opcode: SdoInfoOpcode::Unknown(0x80),
            incomplete: false,
            fragments_left: 0,
        };
        let mut out = [0u8; 4];
        assert_eq!(
            bad.emit(&mut SdoInfo::new_unchecked(&mut out[..])),
            Err(WireError::Unrepresentable)
        );
        let ok = SdoInfoRepr {
            opcode: SdoInfoOpcode::GetObjDescReq,
            ..bad
        };
        assert_eq!(ok.buffer_len(), 4);
        assert_eq!(
            ok.emit(&mut SdoInfo::new_unchecked(&mut out[..3])),
            Err(WireError::BufferTooSmall)
        );
    }

    #[test]
    fn emergency_round_trip() {
        let coe = CoeHeader::new_checked(&EMERGENCY_BYTES[..]).unwrap();
        let e = Emergency::new_checked(coe.payload()).unwrap();
        assert_eq!(e.error_code(), 0x8130);
        assert_eq!(e.error_register(), 0x11);
        assert_eq!(e.data(), [1, 2, 3, 4, 5]);
        let repr = EmergencyRepr::parse(&e).unwrap();
        assert_eq!(repr.buffer_len(), 8);
        let mut out = [0u8; 8];
        repr.emit(&mut Emergency::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, EMERGENCY_BYTES[2..]);
    }

    #[test]
    fn truncated_emergency_is_rejected() {
        assert_eq!(
            Emergency::new_checked(&EMERGENCY_BYTES[2..9]).unwrap_err(),
            WireError::Truncated
        );
        let e = Emergency::new_unchecked(&EMERGENCY_BYTES[2..4]);
        assert_eq!(e.error_code(), 0x8130);
        assert_eq!(e.data(), [0; 5]);
        let repr = EmergencyRepr {
            error_code: 0,
            error_register: 0,
            data: [0; 5],
        };
        let mut out = [0u8; 7];
        assert_eq!(
            repr.emit(&mut Emergency::new_unchecked(&mut out[..])),
            Err(WireError::BufferTooSmall)
        );
    }

    #[test]
    fn sdo_frames_meet_mailbox_minimum() {
        assert_eq!(SDO_MAILBOX_MIN_LEN, 10);
        let reqs = [
            SdoRequest::InitiateUpload {
                index: 0,
                sub: 0,
                complete_access: false,
            },
            SdoRequest::UploadSegment { toggle: false },
            SdoRequest::DownloadSegment {
                toggle: false,
                last: true,
                data: &[1],
            },
        ];
        for r in reqs {
            assert!(HEADER_LEN + r.buffer_len() >= SDO_MAILBOX_MIN_LEN);
        }
    }
}
