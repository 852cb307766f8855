//! EtherCAT frame header and datagrams (ETG.1000.4, "EtherCAT frame
//! structure" and "EtherCAT DLPDU / datagram structure").
//!
//! The payload of an Ethernet II frame with ethertype `0x88A4` starts with a
//! two-byte EtherCAT header followed by one or more datagrams (DLPDUs):
//!
//! ```text
//! EtherCAT header (2 bytes, little-endian u16)
//!  bits 0..=10  length of the datagrams that follow
//!  bit  11      reserved
//!  bits 12..=15 type (1 = EtherCAT DLPDUs)
//!
//! Datagram (10-byte header, data, 2-byte working counter)
//!  0      1      2            6            8      10         10+n   12+n
//! +------+------+------------+------------+------+----------+------+
//! | cmd  | idx  | address    | len/flags  | IRQ  | data (n) | WKC  |
//! +------+------+------------+------------+------+----------+------+
//!  address: ADP u16 + ADO u16 (position/configured/broadcast addressing)
//!           or a 32-bit logical address (LRD/LWR/LRW)
//!  len/flags: bits 0..=10 n, bits 11..=13 reserved, bit 14 circulating,
//!             bit 15 "more datagrams follow"
//! ```
//!
//! Datagrams are walked with [`DatagramCursor`] (which borrows nothing, so
//! the caller may mutate each datagram in place between steps) or the
//! read-only iterator [`Datagrams`]; both yield the *byte range* of each
//! datagram within the EtherCAT payload.

use core::ops::Range;

use super::{Field, Rest, WireError};

/// Length of the EtherCAT frame header.
pub const HEADER_LEN: usize = 2;

/// Largest value of the 11-bit length fields (frame header and datagram).
pub const MAX_LENGTH: u16 = 0x07FF;

/// Maximum number of datagrams accepted in one frame by [`DatagramCursor`]
/// and [`Datagrams`].
///
/// A full-size Ethernet frame (1498 bytes of EtherCAT payload) holds at most
/// 124 empty datagrams of 12 bytes each; anything beyond this bound is a
/// malformed (or hostile) chain.
pub const MAX_DATAGRAMS: usize = 128;

const LENGTH_MASK: u16 = 0x07FF;
const TYPE_SHIFT: u16 = 12;

mod field {
    use super::{Field, Rest};

    /// EtherCAT header: length (bits 0..=10), reserved (bit 11), type
    /// (bits 12..=15).
    pub const HEADER: Field = 0..2;
    /// Datagrams.
    pub const PAYLOAD: Rest = 2..;

    /// Datagram: command.
    pub const DG_COMMAND: usize = 0;
    /// Datagram: index (master's identifier for the datagram).
    pub const DG_INDEX: usize = 1;
    /// Datagram: 32-bit address (logical, or ADP + ADO).
    pub const DG_ADDRESS: Field = 2..6;
    /// Datagram: auto-increment / configured / broadcast position (ADP).
    pub const DG_ADP: Field = 2..4;
    /// Datagram: physical memory offset (ADO).
    pub const DG_ADO: Field = 4..6;
    /// Datagram: length (bits 0..=10), reserved (11..=13), circulating
    /// (14), more follows (15).
    pub const DG_LEN: Field = 6..8;
    /// Datagram: event request (IRQ) field.
    pub const DG_IRQ: Field = 8..10;
    /// Datagram: data, followed by the working counter.
    pub const DG_DATA: Rest = 10..;
}

/// Frame type carried in the upper nibble of the EtherCAT header
/// (ETG.1000.4, "EtherCAT frame structure", type field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameType {
    /// `1`: EtherCAT DLPDUs (datagrams), the only type processed by slaves.
    Pdu,
    /// `4`: network variables.
    NetworkVariables,
    /// `5`: mailbox (mailbox gateway).
    Mailbox,
    /// Any other (reserved) value.
    Unknown(u8),
}

impl From<u8> for FrameType {
    fn from(raw: u8) -> Self {
        match raw {
            1 => Self::Pdu,
            4 => Self::NetworkVariables,
            5 => Self::Mailbox,
            other => Self::Unknown(other),
        }
    }
}

impl From<FrameType> for u8 {
    fn from(ty: FrameType) -> Self {
        match ty {
            FrameType::Pdu => 1,
            FrameType::NetworkVariables => 4,
            FrameType::Mailbox => 5,
            FrameType::Unknown(raw) => raw,
        }
    }
}

/// A read/write view of an EtherCAT frame: the two-byte EtherCAT header and
/// the datagrams it announces (ETG.1000.4, "EtherCAT frame structure").
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EcatFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> EcatFrame<T> {
    /// Wraps a buffer (the Ethernet payload) without checking it.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`EcatFrame::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let frame = Self::new_unchecked(buffer);
        frame.check_len()?;
        Ok(frame)
    }

    /// Checks that the header and the `length` bytes it announces fit in
    /// the buffer.
    ///
    /// Returns [`WireError::Truncated`] if the header itself is missing and
    /// [`WireError::BadLength`] if the length field runs past the buffer.
    /// Bytes after `HEADER_LEN + length` (Ethernet padding) are allowed.
    pub fn check_len(&self) -> Result<(), WireError> {
        let len = self.buffer.as_ref().len();
        if len < HEADER_LEN {
            Err(WireError::Truncated)
        } else if HEADER_LEN + usize::from(self.length()) > len {
            Err(WireError::BadLength)
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

    /// Length of the datagrams following the header (bits 0..=10).
    pub fn length(&self) -> u16 {
        self.header() & LENGTH_MASK
    }

    /// The reserved bit 11 of the header.
    pub fn reserved(&self) -> bool {
        self.header() & 0x0800 != 0
    }

    /// The frame type (bits 12..=15).
    pub fn frame_type(&self) -> FrameType {
        // The shift leaves 4 bits, which always fit in a u8.
        FrameType::from((self.header() >> TYPE_SHIFT) as u8)
    }

    /// The datagrams, `length()` bytes after the header (clamped to the
    /// buffer; empty if the header is missing).
    pub fn payload(&self) -> &[u8] {
        let buf = self.buffer.as_ref();
        let end = (HEADER_LEN + usize::from(self.length())).min(buf.len());
        super::slice(buf, HEADER_LEN..end)
    }

    /// A read-only iterator over the byte ranges of the datagrams within
    /// [`EcatFrame::payload`].
    pub fn datagrams(&self) -> Datagrams<'_> {
        Datagrams::new(self.payload())
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> EcatFrame<T> {
    fn set_header(&mut self, value: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::HEADER, value);
    }

    /// Sets the length field (masked to 11 bits), keeping the other bits.
    pub fn set_length(&mut self, length: u16) {
        let header = (self.header() & !LENGTH_MASK) | (length & LENGTH_MASK);
        self.set_header(header);
    }

    /// Sets the frame type (masked to 4 bits), keeping the other bits.
    pub fn set_frame_type(&mut self, ty: FrameType) {
        let raw = u16::from(u8::from(ty) & 0x0F);
        let header = (self.header() & 0x0FFF) | (raw << TYPE_SHIFT);
        self.set_header(header);
    }

    /// The mutable datagrams, `length()` bytes after the header (clamped to
    /// the buffer).
    pub fn payload_mut(&mut self) -> &mut [u8] {
        let end = HEADER_LEN + usize::from(self.length());
        let buf = self.buffer.as_mut();
        let end = end.min(buf.len());
        super::slice_mut(buf, HEADER_LEN..end)
    }

    /// Everything after the header, regardless of `length()`; used to lay
    /// out datagrams before the length is known.
    pub fn rest_mut(&mut self) -> &mut [u8] {
        super::tail_mut(self.buffer.as_mut(), field::PAYLOAD)
    }
}

/// High-level representation of the EtherCAT frame header (ETG.1000.4,
/// "EtherCAT frame structure").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EcatFrameRepr {
    /// Length of the datagrams that follow, at most [`MAX_LENGTH`].
    pub length: u16,
    /// Frame type.
    pub frame_type: FrameType,
}

impl EcatFrameRepr {
    /// Parses a frame header, checking that the announced length fits.
    pub fn parse<T: AsRef<[u8]>>(frame: &EcatFrame<T>) -> Result<Self, WireError> {
        frame.check_len()?;
        Ok(Self {
            length: frame.length(),
            frame_type: frame.frame_type(),
        })
    }

    /// Length of header plus datagrams.
    pub const fn buffer_len(&self) -> usize {
        HEADER_LEN + self.length as usize
    }

    /// Writes the header (reserved bit cleared).
    ///
    /// Fails with [`WireError::Unrepresentable`] if the length exceeds
    /// [`MAX_LENGTH`] or the type does not fit in 4 bits, and with
    /// [`WireError::BufferTooSmall`] if the frame cannot hold the header.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        frame: &mut EcatFrame<T>,
    ) -> Result<(), WireError> {
        if self.length > MAX_LENGTH || u8::from(self.frame_type) > 0x0F {
            return Err(WireError::Unrepresentable);
        }
        if frame.buffer.as_ref().len() < HEADER_LEN {
            return Err(WireError::BufferTooSmall);
        }
        let raw = self.length | (u16::from(u8::from(self.frame_type)) << TYPE_SHIFT);
        frame.set_header(raw);
        Ok(())
    }
}

/// Datagram command (ETG.1000.4, "EtherCAT DLPDU" command field, commands
/// NOP..FRMW).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Command {
    /// `0` No operation.
    Nop,
    /// `1` Auto-increment physical read.
    Aprd,
    /// `2` Auto-increment physical write.
    Apwr,
    /// `3` Auto-increment physical read/write.
    Aprw,
    /// `4` Configured-address physical read.
    Fprd,
    /// `5` Configured-address physical write.
    Fpwr,
    /// `6` Configured-address physical read/write.
    Fprw,
    /// `7` Broadcast read.
    Brd,
    /// `8` Broadcast write.
    Bwr,
    /// `9` Broadcast read/write.
    Brw,
    /// `10` Logical memory read.
    Lrd,
    /// `11` Logical memory write.
    Lwr,
    /// `12` Logical memory read/write.
    Lrw,
    /// `13` Auto-increment physical read, multiple write.
    Armw,
    /// `14` Configured-address physical read, multiple write.
    Frmw,
    /// Any other (reserved) command code.
    Unknown(u8),
}

/// How a datagram selects the slave(s) it addresses (ETG.1000.4,
/// "Addressing modes").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Addressing {
    /// Auto-increment (position) addressing: ADP is incremented by every
    /// slave, the slave seeing ADP == 0 is addressed.
    Position,
    /// Configured station address (or alias) in ADP.
    Configured,
    /// Every slave is addressed; ADP is incremented by every slave.
    Broadcast,
    /// 32-bit logical address, mapped via FMMUs.
    Logical,
    /// No slave is addressed (NOP and unknown commands).
    None,
}

impl From<u8> for Command {
    fn from(raw: u8) -> Self {
        match raw {
            0 => Self::Nop,
            1 => Self::Aprd,
            2 => Self::Apwr,
            3 => Self::Aprw,
            4 => Self::Fprd,
            5 => Self::Fpwr,
            6 => Self::Fprw,
            7 => Self::Brd,
            8 => Self::Bwr,
            9 => Self::Brw,
            10 => Self::Lrd,
            11 => Self::Lwr,
            12 => Self::Lrw,
            13 => Self::Armw,
            14 => Self::Frmw,
            other => Self::Unknown(other),
        }
    }
}

impl From<Command> for u8 {
    fn from(cmd: Command) -> Self {
        match cmd {
            Command::Nop => 0,
            Command::Aprd => 1,
            Command::Apwr => 2,
            Command::Aprw => 3,
            Command::Fprd => 4,
            Command::Fpwr => 5,
            Command::Fprw => 6,
            Command::Brd => 7,
            Command::Bwr => 8,
            Command::Brw => 9,
            Command::Lrd => 10,
            Command::Lwr => 11,
            Command::Lrw => 12,
            Command::Armw => 13,
            Command::Frmw => 14,
            Command::Unknown(raw) => raw,
        }
    }
}

impl Command {
    /// Whether an addressed slave copies its memory *into* the datagram
    /// data (the master reads): all `*RD`, `*RW` and `*RMW` commands.
    ///
    /// For ARMW/FRMW only the slave at the address reads; every other slave
    /// writes (see [`Command::is_write`]).
    pub const fn is_read(self) -> bool {
        matches!(
            self,
            Self::Aprd
                | Self::Aprw
                | Self::Fprd
                | Self::Fprw
                | Self::Brd
                | Self::Brw
                | Self::Lrd
                | Self::Lrw
                | Self::Armw
                | Self::Frmw
        )
    }

    /// Whether an addressed slave copies the datagram data *into* its
    /// memory (the master writes): all `*WR`, `*RW` and `*RMW` commands.
    pub const fn is_write(self) -> bool {
        matches!(
            self,
            Self::Apwr
                | Self::Aprw
                | Self::Fpwr
                | Self::Fprw
                | Self::Bwr
                | Self::Brw
                | Self::Lwr
                | Self::Lrw
                | Self::Armw
                | Self::Frmw
        )
    }

    /// The addressing mode of the command.
    pub const fn addressing(self) -> Addressing {
        match self {
            Self::Aprd | Self::Apwr | Self::Aprw | Self::Armw => Addressing::Position,
            Self::Fprd | Self::Fpwr | Self::Fprw | Self::Frmw => Addressing::Configured,
            Self::Brd | Self::Bwr | Self::Brw => Addressing::Broadcast,
            Self::Lrd | Self::Lwr | Self::Lrw => Addressing::Logical,
            Self::Nop | Self::Unknown(_) => Addressing::None,
        }
    }
}

/// A read/write view of one datagram (DLPDU) (ETG.1000.4, "EtherCAT DLPDU"
/// structure: command, index, address, length/C/M, IRQ, data, WKC).
#[derive(Debug, Clone, PartialEq, Eq)]
///
/// The struct itself carries no bound so that the length helpers on
/// `Datagram<()>` ([`Datagram::HEADER_LEN`], [`Datagram::total_len_for`])
/// can be used without a buffer.
pub struct Datagram<T> {
    buffer: T,
}

impl Datagram<()> {
    /// Length of the datagram header ([`DATAGRAM_HEADER_LEN`]).
    pub const HEADER_LEN: usize = DATAGRAM_HEADER_LEN;
    /// Length of the working counter ([`WKC_LEN`]).
    pub const WKC_LEN: usize = WKC_LEN;
    /// Smallest possible datagram ([`DATAGRAM_MIN_LEN`]).
    pub const MIN_LEN: usize = DATAGRAM_MIN_LEN;

    /// Total wire length of a datagram carrying `data_len` data bytes
    /// (same as [`datagram_len`]).
    pub const fn total_len_for(data_len: usize) -> usize {
        datagram_len(data_len)
    }
}

/// Length of the datagram header (command .. IRQ, before the data).
pub const DATAGRAM_HEADER_LEN: usize = field::DG_DATA.start;

/// Length of the working counter following the datagram data.
pub const WKC_LEN: usize = 2;

/// Smallest possible datagram: header and WKC, no data.
pub const DATAGRAM_MIN_LEN: usize = DATAGRAM_HEADER_LEN + WKC_LEN;

/// Total wire length of a datagram carrying `data_len` data bytes
/// (`10 + data_len + 2`).
pub const fn datagram_len(data_len: usize) -> usize {
    DATAGRAM_HEADER_LEN + data_len + WKC_LEN
}

const DG_LEN_MASK: u16 = 0x07FF;
const DG_CIRCULATING: u16 = 0x4000;
const DG_MORE: u16 = 0x8000;

/// A datagram's header fields read in one pass from its 10 bytes, for a
/// walk that handles every datagram of a frame once (a software ESC's
/// line); [`Datagram`] reads each field from the buffer when asked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DatagramHead {
    /// The command.
    pub command: Command,
    /// Position / configured address (ADP), or the low half of a logical
    /// address.
    pub adp: u16,
    /// Physical memory offset (ADO), or the high half of a logical
    /// address.
    pub ado: u16,
    /// Length of the data.
    pub data_len: u16,
    /// The "more datagrams follow" bit.
    pub more_follows: bool,
}

impl DatagramHead {
    /// Splits the datagram at the start of `buf` off the rest: its header,
    /// its bytes (header, data and working counter) and the bytes after
    /// it. `None` when the header is missing ([`WireError::Truncated`] for
    /// [`Datagram::check_len`]) or the length field runs past `buf`
    /// ([`WireError::BadLength`]).
    #[inline]
    pub fn split(buf: &mut [u8]) -> Option<(Self, &mut [u8], &mut [u8])> {
        let h = buf.first_chunk::<DATAGRAM_HEADER_LEN>()?;
        let len = u16::from_le_bytes([h[6], h[7]]);
        let head = Self {
            command: Command::from(h[0]),
            adp: u16::from_le_bytes([h[2], h[3]]),
            ado: u16::from_le_bytes([h[4], h[5]]),
            data_len: len & DG_LEN_MASK,
            more_follows: len & DG_MORE != 0,
        };
        let (dg, rest) = buf.split_at_mut_checked(datagram_len(usize::from(head.data_len)))?;
        Some((head, dg, rest))
    }
}

/// A datagram split off by [`DatagramHead::split`] in its parts, for
/// handling it in place: the header, the data and the working counter.
#[derive(Debug)]
pub struct DatagramParts<'a> {
    header: &'a mut [u8; DATAGRAM_HEADER_LEN],
    /// The data bytes.
    pub data: &'a mut [u8],
    wkc: &'a mut [u8; WKC_LEN],
}

impl<'a> DatagramParts<'a> {
    /// The parts of `dg`, a datagram of `head.data_len` data bytes (what
    /// [`DatagramHead::split`] returns); `None` if `dg` is shorter.
    pub fn of(head: &DatagramHead, dg: &'a mut [u8]) -> Option<Self> {
        let (header, body) = dg.split_first_chunk_mut::<DATAGRAM_HEADER_LEN>()?;
        let (data, wkc) = body.split_at_mut_checked(usize::from(head.data_len))?;
        let wkc = wkc.first_chunk_mut::<WKC_LEN>()?;
        Some(Self { header, data, wkc })
    }

    /// Sets the ADP (as each slave increments it on position and
    /// broadcast commands).
    pub fn set_adp(&mut self, adp: u16) {
        // On the fixed-size header, not through `set_u16_le`: its checks
        // on a slice of any length cost 9 instructions per datagram on the
        // line path (cachegrind).
        let [lo, hi] = adp.to_le_bytes();
        let [a, b] = &mut self.header[field::DG_ADP.start..field::DG_ADP.end] else {
            return;
        };
        (*a, *b) = (lo, hi);
    }

    /// The working counter.
    pub fn wkc(&self) -> u16 {
        u16::from_le_bytes(*self.wkc)
    }

    /// Sets the working counter.
    pub fn set_wkc(&mut self, wkc: u16) {
        *self.wkc = wkc.to_le_bytes();
    }
}

impl<T: AsRef<[u8]>> Datagram<T> {
    /// Wraps a buffer without checking it.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`Datagram::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let dg = Self::new_unchecked(buffer);
        dg.check_len()?;
        Ok(dg)
    }

    /// Checks that the header, the `data_len()` data bytes and the working
    /// counter fit in the buffer.
    ///
    /// Returns [`WireError::Truncated`] if the 10-byte header is missing and
    /// [`WireError::BadLength`] if the length field runs past the buffer.
    /// Bytes after the WKC are allowed (they belong to the next datagram).
    pub fn check_len(&self) -> Result<(), WireError> {
        let len = self.buffer.as_ref().len();
        if len < DATAGRAM_HEADER_LEN {
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

    /// Total wire length (header + data + WKC) according to the length
    /// field.
    pub fn total_len(&self) -> usize {
        datagram_len(usize::from(self.data_len()))
    }

    /// The command.
    pub fn command(&self) -> Command {
        Command::from(super::get_u8(self.buffer.as_ref(), field::DG_COMMAND))
    }

    /// The index (master's identifier, returned unchanged).
    pub fn index(&self) -> u8 {
        super::get_u8(self.buffer.as_ref(), field::DG_INDEX)
    }

    /// Position / configured address (ADP, bytes 2..4).
    pub fn adp(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::DG_ADP)
    }

    /// Physical memory offset (ADO, bytes 4..6).
    pub fn ado(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::DG_ADO)
    }

    /// The whole address field as a 32-bit logical address (bytes 2..6).
    pub fn logical_address(&self) -> u32 {
        super::get_u32_le(self.buffer.as_ref(), field::DG_ADDRESS)
    }

    fn len_field(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::DG_LEN)
    }

    /// Length of the data (bits 0..=10 of bytes 6..8).
    pub fn data_len(&self) -> u16 {
        self.len_field() & DG_LEN_MASK
    }

    /// The circulating-frame bit (bit 14): set by a slave that had to
    /// close a port the frame would otherwise have left by.
    pub fn circulating(&self) -> bool {
        self.len_field() & DG_CIRCULATING != 0
    }

    /// The "more datagrams follow" bit (bit 15).
    pub fn more_follows(&self) -> bool {
        self.len_field() & DG_MORE != 0
    }

    /// The event request (IRQ) field.
    pub fn irq(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), field::DG_IRQ)
    }

    fn data_range(&self) -> Field {
        let start = field::DG_DATA.start;
        start..start + usize::from(self.data_len())
    }

    fn wkc_range(&self) -> Field {
        let end = self.data_range().end;
        end..end + WKC_LEN
    }

    /// The data bytes (empty if the buffer does not hold them).
    pub fn data(&self) -> &[u8] {
        super::slice(self.buffer.as_ref(), self.data_range())
    }

    /// The working counter following the data (0 if out of range).
    pub fn wkc(&self) -> u16 {
        super::get_u16_le(self.buffer.as_ref(), self.wkc_range())
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Datagram<T> {
    /// Sets the command.
    pub fn set_command(&mut self, command: Command) {
        super::set_u8(self.buffer.as_mut(), field::DG_COMMAND, command.into());
    }

    /// Sets the index.
    pub fn set_index(&mut self, index: u8) {
        super::set_u8(self.buffer.as_mut(), field::DG_INDEX, index);
    }

    /// Sets ADP (e.g. to the incremented position on the way through).
    pub fn set_adp(&mut self, adp: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::DG_ADP, adp);
    }

    /// Sets ADO.
    pub fn set_ado(&mut self, ado: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::DG_ADO, ado);
    }

    /// Sets the whole address field as a logical address.
    pub fn set_logical_address(&mut self, address: u32) {
        super::set_u32_le(self.buffer.as_mut(), field::DG_ADDRESS, address);
    }

    fn set_len_field(&mut self, value: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::DG_LEN, value);
    }

    /// Sets the data length (masked to 11 bits), keeping the flag bits.
    pub fn set_data_len(&mut self, len: u16) {
        let v = (self.len_field() & !DG_LEN_MASK) | (len & DG_LEN_MASK);
        self.set_len_field(v);
    }

    /// Sets or clears the circulating bit.
    pub fn set_circulating(&mut self, circulating: bool) {
        let v = self.len_field();
        self.set_len_field(if circulating {
            v | DG_CIRCULATING
        } else {
            v & !DG_CIRCULATING
        });
    }

    /// Sets or clears the "more datagrams follow" bit.
    pub fn set_more_follows(&mut self, more: bool) {
        let v = self.len_field();
        self.set_len_field(if more { v | DG_MORE } else { v & !DG_MORE });
    }

    /// Sets the IRQ field.
    pub fn set_irq(&mut self, irq: u16) {
        super::set_u16_le(self.buffer.as_mut(), field::DG_IRQ, irq);
    }

    /// The mutable data bytes (empty if the buffer does not hold them).
    pub fn data_mut(&mut self) -> &mut [u8] {
        let range = self.data_range();
        super::slice_mut(self.buffer.as_mut(), range)
    }

    /// Sets the working counter.
    pub fn set_wkc(&mut self, wkc: u16) {
        let range = self.wkc_range();
        super::set_u16_le(self.buffer.as_mut(), range, wkc);
    }

    /// Adds `n` to the working counter (wrapping, as the ESC does).
    pub fn add_wkc(&mut self, n: u16) {
        let wkc = self.wkc().wrapping_add(n);
        self.set_wkc(wkc);
    }
}

impl<T: AsRef<[u8]>> AsRef<[u8]> for Datagram<T> {
    fn as_ref(&self) -> &[u8] {
        self.buffer.as_ref()
    }
}

/// High-level representation of a datagram (ETG.1000.4, "EtherCAT DLPDU").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DatagramRepr<'a> {
    /// Command.
    pub command: Command,
    /// Index.
    pub index: u8,
    /// Raw address field: a logical address, or `ADP | (ADO << 16)`.
    pub address: u32,
    /// Circulating bit.
    pub circulating: bool,
    /// "More datagrams follow" bit.
    pub more_follows: bool,
    /// IRQ field.
    pub irq: u16,
    /// Data, at most [`MAX_LENGTH`] bytes.
    pub data: &'a [u8],
    /// Working counter.
    pub wkc: u16,
}

impl<'a> DatagramRepr<'a> {
    /// Builds the raw address field from ADP and ADO.
    pub const fn physical_address(adp: u16, ado: u16) -> u32 {
        (adp as u32) | ((ado as u32) << 16)
    }

    /// ADP part of [`DatagramRepr::address`].
    pub const fn adp(&self) -> u16 {
        (self.address & 0xFFFF) as u16
    }

    /// ADO part of [`DatagramRepr::address`].
    pub const fn ado(&self) -> u16 {
        (self.address >> 16) as u16
    }

    /// Parses a datagram, checking its length.
    ///
    /// The returned `data` borrows from the datagram's underlying buffer.
    pub fn parse<T: AsRef<[u8]> + ?Sized>(dg: &Datagram<&'a T>) -> Result<Self, WireError> {
        dg.check_len()?;
        let buf: &'a T = dg.buffer;
        let data = super::slice(buf.as_ref(), dg.data_range());
        Ok(Self {
            command: dg.command(),
            index: dg.index(),
            address: dg.logical_address(),
            circulating: dg.circulating(),
            more_follows: dg.more_follows(),
            irq: dg.irq(),
            data,
            wkc: dg.wkc(),
        })
    }

    /// Wire length: header + data + WKC.
    pub const fn buffer_len(&self) -> usize {
        datagram_len(self.data.len())
    }

    /// Writes the datagram.
    ///
    /// Fails with [`WireError::Unrepresentable`] if the data is longer than
    /// [`MAX_LENGTH`] and with [`WireError::BufferTooSmall`] if the buffer
    /// cannot hold [`DatagramRepr::buffer_len`] bytes.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        dg: &mut Datagram<T>,
    ) -> Result<(), WireError> {
        let len = u16::try_from(self.data.len())
            .ok()
            .filter(|l| *l <= MAX_LENGTH)
            .ok_or(WireError::Unrepresentable)?;
        if dg.buffer.as_ref().len() < self.buffer_len() {
            return Err(WireError::BufferTooSmall);
        }
        dg.set_command(self.command);
        dg.set_index(self.index);
        dg.set_logical_address(self.address);
        let mut len_field = len;
        if self.circulating {
            len_field |= DG_CIRCULATING;
        }
        if self.more_follows {
            len_field |= DG_MORE;
        }
        dg.set_len_field(len_field);
        dg.set_irq(self.irq);
        dg.data_mut().copy_from_slice(self.data);
        dg.set_wkc(self.wkc);
        Ok(())
    }
}

/// A borrow-free cursor over the datagrams of an EtherCAT payload
/// (ETG.1000.4: datagrams are chained by the "more follows" bit).
///
/// Each step is given the payload afresh, so the caller can mutate the
/// datagram it has just been handed before asking for the next one:
///
/// ```ignore
/// let mut cursor = DatagramCursor::new();
/// while let Some(range) = cursor.next_range(frame.payload()) {
///     let range = range?;
///     let mut dg = Datagram::new_unchecked(&mut frame.payload_mut()[range]);
///     dg.add_wkc(1);
/// }
/// ```
///
/// The chain starts at offset 0 and must contain at least one datagram.
/// Yielded ranges always hold a complete datagram (`Datagram::check_len`
/// succeeds on them). On the first malformed datagram — fewer than 10 header
/// bytes left ([`WireError::Truncated`]), a length running past the payload
/// ([`WireError::BadLength`]), or more than [`MAX_DATAGRAMS`]
/// ([`WireError::TooManyDatagrams`]) — the cursor yields that error once and
/// then stops. Bytes after the last datagram (more bit clear) are ignored.
/// The payload should not change length between steps.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DatagramCursor {
    offset: usize,
    count: usize,
    done: bool,
}

impl DatagramCursor {
    /// A cursor positioned at the first datagram.
    pub const fn new() -> Self {
        Self {
            offset: 0,
            count: 0,
            done: false,
        }
    }

    /// Number of datagrams yielded so far.
    pub const fn count(&self) -> usize {
        self.count
    }

    /// Byte range of the next datagram in `payload`, an error, or `None`
    /// once the chain has ended (or after an error).
    #[inline]
    pub fn next_range(&mut self, payload: &[u8]) -> Option<Result<Range<usize>, WireError>> {
        if self.done {
            return None;
        }
        self.done = true;
        if self.count >= MAX_DATAGRAMS {
            return Some(Err(WireError::TooManyDatagrams));
        }
        let start = self.offset;
        let rest = payload.get(start..).unwrap_or(&[]);
        let dg = Datagram::new_unchecked(rest);
        if let Err(e) = dg.check_len() {
            return Some(Err(e));
        }
        let end = start + dg.total_len();
        self.count += 1;
        self.offset = end;
        self.done = !dg.more_follows();
        Some(Ok(start..end))
    }
}

/// A read-only iterator over the byte ranges of the datagrams in an
/// EtherCAT payload (ETG.1000.4); see [`DatagramCursor`] for the rules and
/// for in-place processing.
#[derive(Debug, Clone)]
pub struct Datagrams<'a> {
    payload: &'a [u8],
    cursor: DatagramCursor,
}

impl<'a> Datagrams<'a> {
    /// Iterates over the datagrams of `payload` (the bytes after the
    /// EtherCAT header).
    pub const fn new(payload: &'a [u8]) -> Self {
        Self {
            payload,
            cursor: DatagramCursor::new(),
        }
    }
}

impl Iterator for Datagrams<'_> {
    type Item = Result<Range<usize>, WireError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.cursor.next_range(self.payload)
    }
}

impl core::iter::FusedIterator for Datagrams<'_> {}

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::*;

    /// EtherCAT payload of ethercrab's first frame: BRD of register 0x0000,
    /// 1 byte, index 0 (after the Ethernet header).
    static BRD_FRAME_BYTES: [u8; 15] = [
        0x0d, 0x10, // header: length 13, type 1
        0x07, 0x00, // BRD, index 0
        0x00, 0x00, 0x00, 0x00, // ADP 0, ADO 0x0000
        0x01, 0x00, // len 1, last
        0x00, 0x00, // IRQ
        0x00, // data
        0x00, 0x00, // WKC
    ];

    /// An LRW of 4 bytes at logical address 0x0001_0000, index 0x42, WKC 3.
    static LRW_BYTES: [u8; 16] = [
        0x0c, 0x42, // LRW, index 0x42
        0x00, 0x00, 0x01, 0x00, // logical 0x0001_0000
        0x04, 0x00, // len 4, last
        0x00, 0x00, // IRQ
        0xde, 0xad, 0xbe, 0xef, // data
        0x03, 0x00, // WKC
    ];

    /// Two datagrams: FPRD 0x1001:0x0130 (2 bytes, more) + APWR 0xFFFF:0x0120
    /// (2 bytes, last), with 4 bytes of Ethernet padding after them.
    static TWO_DATAGRAMS_BYTES: [u8; 34] = [
        0x1c, 0x10, // header: length 28, type 1
        0x04, 0x01, 0x01, 0x10, 0x30, 0x01, 0x02, 0x80, 0x00, 0x00, 0x08, 0x00, 0x01, 0x00, 0x02,
        0x02, 0xff, 0xff, 0x20, 0x01, 0x02, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x00, // padding
    ];

    #[test]
    fn deconstructs_brd_frame() {
        let frame = EcatFrame::new_checked(&BRD_FRAME_BYTES[..]).unwrap();
        assert_eq!(frame.length(), 13);
        assert_eq!(frame.frame_type(), FrameType::Pdu);
        assert!(!frame.reserved());
        assert_eq!(frame.payload(), &BRD_FRAME_BYTES[2..]);

        let dg = Datagram::new_checked(frame.payload()).unwrap();
        assert_eq!(dg.command(), Command::Brd);
        assert_eq!(dg.index(), 0);
        assert_eq!(dg.adp(), 0);
        assert_eq!(dg.ado(), 0);
        assert_eq!(dg.data_len(), 1);
        assert!(!dg.more_follows());
        assert!(!dg.circulating());
        assert_eq!(dg.irq(), 0);
        assert_eq!(dg.data(), &[0]);
        assert_eq!(dg.wkc(), 0);
        assert_eq!(dg.total_len(), 13);
    }

    #[test]
    fn constructs_brd_frame() {
        let mut bytes = [0xAAu8; 15];
        let mut frame = EcatFrame::new_unchecked(&mut bytes[..]);
        frame.set_length(0);
        frame.set_frame_type(FrameType::Pdu);
        // clear reserved bit that came from the 0xAA fill
        frame.set_header(0x1000);
        frame.set_length(13);
        let mut dg = Datagram::new_unchecked(frame.payload_mut());
        dg.set_command(Command::Brd);
        dg.set_index(0);
        dg.set_adp(0);
        dg.set_ado(0);
        dg.set_len_field(0);
        dg.set_data_len(1);
        dg.set_more_follows(false);
        dg.set_circulating(false);
        dg.set_irq(0);
        dg.data_mut().fill(0);
        dg.set_wkc(0);
        assert_eq!(bytes, BRD_FRAME_BYTES);
    }

    #[test]
    fn slave_processing_brd_increments_adp_and_wkc() {
        let mut bytes = BRD_FRAME_BYTES;
        let mut frame = EcatFrame::new_checked(&mut bytes[..]).unwrap();
        let mut dg = Datagram::new_checked(frame.payload_mut()).unwrap();
        dg.set_adp(dg.adp().wrapping_add(1));
        dg.data_mut()[0] = 0x11;
        dg.add_wkc(1);
        assert_eq!(&bytes[2..], &[7, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0x11, 1, 0]);
    }

    #[test]
    fn lrw_exposes_logical_address() {
        let dg = Datagram::new_checked(&LRW_BYTES[..]).unwrap();
        assert_eq!(dg.command(), Command::Lrw);
        assert_eq!(dg.command().addressing(), Addressing::Logical);
        assert_eq!(dg.index(), 0x42);
        assert_eq!(dg.logical_address(), 0x0001_0000);
        assert_eq!(dg.data(), &[0xde, 0xad, 0xbe, 0xef]);
        assert_eq!(dg.wkc(), 3);
    }

    #[test]
    fn lrw_repr_parse_and_emit_round_trip() {
        let dg = Datagram::new_checked(&LRW_BYTES[..]).unwrap();
        let repr = DatagramRepr::parse(&dg).unwrap();
        assert_eq!(
            repr,
            DatagramRepr {
                command: Command::Lrw,
                index: 0x42,
                address: 0x0001_0000,
                circulating: false,
                more_follows: false,
                irq: 0,
                data: &[0xde, 0xad, 0xbe, 0xef],
                wkc: 3,
            }
        );
        assert_eq!(repr.buffer_len(), LRW_BYTES.len());
        let mut out = [0u8; 16];
        repr.emit(&mut Datagram::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, LRW_BYTES);
    }

    #[test]
    fn datagram_repr_emit_into_short_buffer_fails() {
        let dg = Datagram::new_checked(&LRW_BYTES[..]).unwrap();
        let repr = DatagramRepr::parse(&dg).unwrap();
        let mut out = [0u8; 15];
        assert_eq!(
            repr.emit(&mut Datagram::new_unchecked(&mut out[..])),
            Err(WireError::BufferTooSmall)
        );
        assert_eq!(out, [0; 15]);
    }

    #[test]
    fn datagram_repr_with_oversized_data_is_unrepresentable() {
        let data = [0u8; 0x800];
        let repr = DatagramRepr {
            command: Command::Lwr,
            index: 0,
            address: 0,
            circulating: false,
            more_follows: false,
            irq: 0,
            data: &data,
            wkc: 0,
        };
        let mut out = [0u8; 0x800 + 12];
        assert_eq!(
            repr.emit(&mut Datagram::new_unchecked(&mut out[..])),
            Err(WireError::Unrepresentable)
        );
    }

    #[test]
    fn physical_address_splits_into_adp_and_ado() {
        let repr = DatagramRepr {
            command: Command::Fprd,
            index: 1,
            address: DatagramRepr::physical_address(0x1001, 0x0130),
            circulating: false,
            more_follows: true,
            irq: 0,
            data: &[0x08, 0x00],
            wkc: 1,
        };
        assert_eq!(repr.adp(), 0x1001);
        assert_eq!(repr.ado(), 0x0130);
        let mut out = [0u8; 14];
        repr.emit(&mut Datagram::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(&out[..], &TWO_DATAGRAMS_BYTES[2..16]);
    }

    #[test]
    fn frame_with_two_datagrams_yields_both_ranges() {
        let frame = EcatFrame::new_checked(&TWO_DATAGRAMS_BYTES[..]).unwrap();
        assert_eq!(frame.payload().len(), 28);
        let mut it = frame.datagrams();
        assert_eq!(it.next(), Some(Ok(0..14)));
        assert_eq!(it.next(), Some(Ok(14..28)));
        assert_eq!(it.next(), None);
        assert_eq!(it.next(), None);

        let first = Datagram::new_checked(&frame.payload()[0..14]).unwrap();
        assert_eq!(first.command(), Command::Fprd);
        assert_eq!(first.adp(), 0x1001);
        assert_eq!(first.ado(), 0x0130);
        assert!(first.more_follows());
        assert_eq!(first.data(), &[0x08, 0x00]);
        assert_eq!(first.wkc(), 1);
        let second = Datagram::new_checked(&frame.payload()[14..28]).unwrap();
        assert_eq!(second.command(), Command::Apwr);
        assert_eq!(second.adp(), 0xFFFF);
        assert!(!second.more_follows());
    }

    #[test]
    fn cursor_allows_in_place_mutation_between_steps() {
        let mut bytes = TWO_DATAGRAMS_BYTES;
        let mut frame = EcatFrame::new_checked(&mut bytes[..]).unwrap();
        let mut cursor = DatagramCursor::new();
        while let Some(range) = cursor.next_range(frame.payload()) {
            let range = range.unwrap();
            let mut dg = Datagram::new_unchecked(&mut frame.payload_mut()[range]);
            dg.add_wkc(1);
        }
        assert_eq!(cursor.count(), 2);
        assert_eq!(u16::from_le_bytes([bytes[14], bytes[15]]), 2);
        assert_eq!(u16::from_le_bytes([bytes[28], bytes[29]]), 1);
    }

    #[test]
    fn truncated_datagram_header_is_rejected() {
        let payload = &BRD_FRAME_BYTES[2..11];
        let mut it = Datagrams::new(payload);
        assert_eq!(it.next(), Some(Err(WireError::Truncated)));
        assert_eq!(it.next(), None);
        assert_eq!(
            Datagram::new_checked(payload).unwrap_err(),
            WireError::Truncated
        );
    }

    #[test]
    fn datagram_missing_its_wkc_is_rejected() {
        let payload = &BRD_FRAME_BYTES[2..14];
        assert_eq!(
            Datagram::new_checked(payload).unwrap_err(),
            WireError::BadLength
        );
        let mut it = Datagrams::new(payload);
        assert_eq!(it.next(), Some(Err(WireError::BadLength)));
        assert_eq!(it.next(), None);
    }

    #[test]
    fn datagram_head_split_reads_the_header_and_splits_off_the_rest() {
        let mut bytes = [0u8; 19];
        bytes[..16].copy_from_slice(&LRW_BYTES);
        bytes[7] |= 0x80; // more follows
        bytes[16..].copy_from_slice(&[0xAA, 0xBB, 0xCC]);
        let (head, dg, rest) = DatagramHead::split(&mut bytes).unwrap();
        assert_eq!(
            head,
            DatagramHead {
                command: Command::Lrw,
                adp: 0x0000,
                ado: 0x0001,
                data_len: 4,
                more_follows: true,
            }
        );
        assert_eq!(dg.len(), 16);
        assert_eq!(&dg[10..14], &[0xde, 0xad, 0xbe, 0xef]);
        assert_eq!(rest, &[0xAA, 0xBB, 0xCC]);
    }

    #[test]
    fn datagram_parts_edit_adp_and_wkc_in_place() {
        let mut bytes = LRW_BYTES;
        let (head, dg, _) = DatagramHead::split(&mut bytes).unwrap();
        let mut parts = DatagramParts::of(&head, dg).unwrap();
        assert_eq!(parts.data, &[0xde, 0xad, 0xbe, 0xef]);
        assert_eq!(parts.wkc(), 3);
        parts.set_adp(0x1234);
        parts.set_wkc(7);
        let dg = Datagram::new_checked(&bytes[..]).unwrap();
        assert_eq!((dg.adp(), dg.ado(), dg.wkc()), (0x1234, 0x0001, 7));
        // A buffer shorter than the header says: no parts.
        let mut short = [0u8; 12];
        assert!(DatagramParts::of(&head, &mut short).is_none());
    }

    #[test]
    fn datagram_head_split_refuses_what_check_len_refuses() {
        // Header cut short, WKC missing, length field past the buffer,
        // nothing at all: each refused, never a panic.
        let mut short = [0u8; 9];
        short.copy_from_slice(&BRD_FRAME_BYTES[2..11]);
        assert_eq!(DatagramHead::split(&mut short), None);
        let mut no_wkc = [0u8; 12];
        no_wkc.copy_from_slice(&BRD_FRAME_BYTES[2..14]);
        assert_eq!(DatagramHead::split(&mut no_wkc), None);
        let mut long = LRW_BYTES;
        long[6] = 0xFF;
        long[7] = 0x07; // 2047 data bytes
        assert_eq!(DatagramHead::split(&mut long), None);
        assert_eq!(DatagramHead::split(&mut []), None);
        // An unknown command code is carried, not refused.
        let mut odd = LRW_BYTES;
        odd[0] = 0x3F;
        let (head, _, rest) = DatagramHead::split(&mut odd).unwrap();
        assert_eq!(head.command, Command::Unknown(0x3F));
        assert!(rest.is_empty());
    }

    #[test]
    fn datagram_with_length_beyond_frame_is_rejected() {
        let mut bytes = LRW_BYTES;
        bytes[6] = 0xFF;
        bytes[7] = 0x07; // 2047 data bytes
        let dg = Datagram::new_unchecked(&bytes[..]);
        assert_eq!(dg.check_len(), Err(WireError::BadLength));
        // accessors still do not panic
        assert!(dg.data().is_empty());
        assert_eq!(dg.wkc(), 0);
        assert_eq!(
            Datagrams::new(&bytes).collect::<heapless::Vec<_, 4>>(),
            [Err(WireError::BadLength)]
        );
    }

    #[test]
    fn frame_length_beyond_buffer_is_rejected() {
        let mut bytes = BRD_FRAME_BYTES;
        bytes[0] = 0x0e; // 14 > 13 available
        let frame = EcatFrame::new_unchecked(&bytes[..]);
        assert_eq!(frame.check_len(), Err(WireError::BadLength));
        assert_eq!(frame.payload().len(), 13);
        assert_eq!(
            EcatFrameRepr::parse(&frame).unwrap_err(),
            WireError::BadLength
        );
    }

    #[test]
    fn frame_shorter_than_header_is_truncated() {
        assert_eq!(
            EcatFrame::new_checked(&[0x0du8][..]).unwrap_err(),
            WireError::Truncated
        );
        let frame = EcatFrame::new_unchecked(&[][..]);
        assert!(frame.payload().is_empty());
        assert_eq!(frame.datagrams().next(), Some(Err(WireError::Truncated)));
    }

    #[test]
    fn more_bit_on_last_datagram_is_an_error() {
        let mut bytes = BRD_FRAME_BYTES;
        bytes[9] |= 0x80;
        let frame = EcatFrame::new_checked(&bytes[..]).unwrap();
        let mut it = frame.datagrams();
        assert_eq!(it.next(), Some(Ok(0..13)));
        assert_eq!(it.next(), Some(Err(WireError::Truncated)));
        assert_eq!(it.next(), None);
    }

    #[test]
    fn endless_chain_stops_at_max_datagrams() {
        // 200 empty datagrams, each with the more bit set.
        let mut payload = [0u8; 200 * 12];
        for chunk in payload.chunks_mut(12) {
            chunk[7] = 0x80;
        }
        let mut it = Datagrams::new(&payload);
        for _ in 0..MAX_DATAGRAMS {
            assert!(matches!(it.next(), Some(Ok(_))));
        }
        assert_eq!(it.next(), Some(Err(WireError::TooManyDatagrams)));
        assert_eq!(it.next(), None);
    }

    #[test]
    fn frame_header_repr_round_trip() {
        let frame = EcatFrame::new_checked(&BRD_FRAME_BYTES[..]).unwrap();
        let repr = EcatFrameRepr::parse(&frame).unwrap();
        assert_eq!(
            repr,
            EcatFrameRepr {
                length: 13,
                frame_type: FrameType::Pdu
            }
        );
        assert_eq!(repr.buffer_len(), 15);
        let mut out = [0u8; 2];
        repr.emit(&mut EcatFrame::new_unchecked(&mut out[..]))
            .unwrap();
        assert_eq!(out, [0x0d, 0x10]);
    }

    #[test]
    fn frame_header_repr_rejects_unrepresentable_values() {
        let mut out = [0u8; 2];
        let too_long = EcatFrameRepr {
            length: 0x800,
            frame_type: FrameType::Pdu,
        };
        assert_eq!(
            too_long.emit(&mut EcatFrame::new_unchecked(&mut out[..])),
            Err(WireError::Unrepresentable)
        );
        let bad_type = EcatFrameRepr {
            length: 0,
            frame_type: FrameType::Unknown(0x10),
        };
        assert_eq!(
            bad_type.emit(&mut EcatFrame::new_unchecked(&mut out[..])),
            Err(WireError::Unrepresentable)
        );
        let ok = EcatFrameRepr {
            length: 0,
            frame_type: FrameType::Mailbox,
        };
        assert_eq!(
            ok.emit(&mut EcatFrame::new_unchecked(&mut out[..1])),
            Err(WireError::BufferTooSmall)
        );
    }

    #[test]
    fn unknown_frame_type_is_kept() {
        let frame = EcatFrame::new_checked(&[0x00u8, 0xB8][..]).unwrap();
        assert_eq!(frame.frame_type(), FrameType::Unknown(0x0B));
        assert!(frame.reserved());
        assert_eq!(frame.length(), 0);
        assert_eq!(u8::from(frame.frame_type()), 0x0B);
    }

    #[test]
    fn frame_setters_preserve_other_bits() {
        let mut bytes = [0x00u8, 0x08];
        let mut frame = EcatFrame::new_unchecked(&mut bytes[..]);
        frame.set_frame_type(FrameType::Mailbox);
        frame.set_length(0xFFFF);
        assert_eq!(frame.length(), 0x7FF);
        assert!(frame.reserved());
        assert_eq!(frame.frame_type(), FrameType::Mailbox);
        assert_eq!(bytes, [0xFF, 0x5F]);
    }

    #[test]
    fn datagram_flag_setters_preserve_length() {
        let mut bytes = LRW_BYTES;
        let mut dg = Datagram::new_checked(&mut bytes[..]).unwrap();
        dg.set_more_follows(true);
        dg.set_circulating(true);
        assert_eq!(dg.data_len(), 4);
        assert!(dg.more_follows() && dg.circulating());
        dg.set_circulating(false);
        dg.set_more_follows(false);
        assert_eq!(dg.into_inner(), &LRW_BYTES);
    }

    #[test]
    fn command_codes_round_trip() {
        for raw in 0..=u8::MAX {
            let cmd = Command::from(raw);
            assert_eq!(u8::from(cmd), raw);
            if raw > 14 {
                assert_eq!(cmd, Command::Unknown(raw));
            }
        }
        assert_eq!(Command::from(7), Command::Brd);
        assert_eq!(Command::from(14), Command::Frmw);
    }

    #[test]
    fn command_directions() {
        assert!(Command::Brd.is_read() && !Command::Brd.is_write());
        assert!(!Command::Apwr.is_read() && Command::Apwr.is_write());
        assert!(Command::Lrw.is_read() && Command::Lrw.is_write());
        assert!(Command::Frmw.is_read() && Command::Frmw.is_write());
        assert!(!Command::Nop.is_read() && !Command::Nop.is_write());
        assert!(!Command::Unknown(99).is_read() && !Command::Unknown(99).is_write());
        assert_eq!(Command::Aprd.addressing(), Addressing::Position);
        assert_eq!(Command::Fpwr.addressing(), Addressing::Configured);
        assert_eq!(Command::Bwr.addressing(), Addressing::Broadcast);
        assert_eq!(Command::Nop.addressing(), Addressing::None);
    }

    #[test]
    fn length_helpers_agree() {
        assert_eq!(Datagram::<()>::HEADER_LEN, 10);
        assert_eq!(Datagram::<()>::WKC_LEN, 2);
        assert_eq!(Datagram::<()>::MIN_LEN, 12);
        assert_eq!(Datagram::<()>::total_len_for(4), LRW_BYTES.len());
        assert_eq!(datagram_len(1), 13);
    }

    #[test]
    fn unchecked_empty_datagram_accessors_do_not_panic() {
        let mut bytes = [0u8; 3];
        let mut dg = Datagram::new_unchecked(&mut bytes[..]);
        assert_eq!(dg.command(), Command::Nop);
        assert_eq!(dg.logical_address(), 0);
        dg.set_adp(5);
        dg.set_wkc(1);
        dg.add_wkc(1);
        assert!(dg.data_mut().is_empty());
        assert_eq!(dg.total_len(), DATAGRAM_MIN_LEN);
    }
}
