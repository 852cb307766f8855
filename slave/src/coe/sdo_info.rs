//! SDO Information server (ETG.1000.6 5.6.3): OD lists, object and entry
//! descriptions, fragmented responses.
//!
//! Layer 3 (`coe`). The server reads only the static description
//! the device's [`Dictionary`]; it holds no object values, knows nothing of the ESC
//! or the mailbox, and allocates nothing. Frames are read and written with
//! the views of [`crate::wire::coe`].
//!
//! # Requests and responses
//!
//! [`SdoInfoServer::handle`] takes the bytes after the CoE header (SDO Info
//! header onwards) and writes the first fragment of the response into `out`;
//! [`SdoInfoServer::next_fragment`] writes the following ones. Every
//! fragment but the last carries the incomplete bit, and "fragments left"
//! counts down to 0 on the last one (assuming every fragment gets the same
//! `out` size; a smaller `out` makes smaller fragments and the count is
//! recomputed from what is left). A new request abandons a response still
//! in progress.
//!
//! * **OD list** (opcode 1 → 2): list type 0 answers the number of objects
//!   of list types 1..=5 (five `u16`). Types 1..=5 answer the list type
//!   followed by the object indices in ascending order; the list is
//!   generated from the dictionary fragment by fragment (a cursor, no buffer),
//!   and a fragment never splits an index. An object belongs to list 2
//!   (RxPDO) / 3 (TxPDO) / 4 (backup) / 5 (settings) when at least one of its
//!   entries is RxPDO-mappable / TxPDO-mappable / `backup` / `setting`.
//! * **Object description** (3 → 4): index, data type, max subindex
//!   ([`Object::max_sub`]), object code, name. The data type is
//!   - VAR: the entry's type code ([`DataType::code`]);
//!   - ARRAY: the element type (subindex 1);
//!   - RECORD: the ETG.1000.6 DEFSTRUCT index where one exists, i.e.
//!     `0x0021` PDO_MAPPING for 0x1600-0x17FF / 0x1A00-0x1BFF and `0x0023`
//!     IDENTITY for 0x1018; every other record reports `0x002A`
//!     (DEFTYPE_RECORD, the generic record type used by the Beckhoff SSC and
//!     other slave stacks). The ESI's per-object types `DTxxxx` are names
//!     only and have no data type index.
//! * **Entry description** (5 → 6): index, subindex, value info, data type,
//!   bit length, object access ([`Access::bits`](crate::od::types::Access::bits) plus 0x0040 RxPDO, 0x0080
//!   TxPDO, 0x0100 backup, 0x0200 setting), the requested values, name.
//!   Values, when asked for, come in the order unit type (`u32`), default,
//!   minimum, maximum; each value takes the entry's size in whole bytes,
//!   little-endian.
//!   - Unit type: the ETG.1004 code as in the ESI (`ms` 0xFD030000,
//!     `mA` 0xFD040000, `Hz` 0x00200000); other units (`0.01 %`) and no unit
//!     give 0.
//!   - Default: the model's default; strings as their text, zero-padded to
//!     the entry's size.
//!   - Minimum / maximum: the model's range where it has one, else the
//!     type's natural range (BOOL 0..=1, BITn 0..=2ⁿ-1, integers their full
//!     range, enumerations their smallest..=largest defined value).
//!     VISIBLE_STRING has no range: for strings the minimum and maximum bits
//!     are cleared in the response's value info and no bytes are sent.
//!   - The response's value info is the request's masked to the defined
//!     bits 3..=6 (and without min/max for strings): it says exactly which
//!     values follow.
//!
//!   Gap entries (`gap: true`) are real subindices of the packed layout.
//!   They are described as the SSC describes record padding: data type
//!   0x0000 (NULL), their bit length, object access 0 (no read or write
//!   right in any state), no value info, named `SubIndex 0NN`. An upload or
//!   download of a gap aborts 0x06010000; a complete access carries them
//!   as zero bits (MANUAL-NOTES note 20).
//! * **Errors** answer with an SDO Info error request (opcode 7, `u32`
//!   abort code): unknown object 0x06020000, unknown subindex 0x06090011,
//!   short or malformed requests, unknown opcodes and unknown list types
//!   0x05040001, a description larger than [`INFO_BUFFER`] 0x06010005.

use crate::od::Dictionary;
use crate::od::modules::ObjectView;
use crate::od::types::{DataType, DefaultValue, Entry, Object, ObjectCode, PdoMapping};
use crate::wire::coe::{SDO_INFO_HEADER_LEN, SdoAbortCode, SdoInfo, SdoInfoOpcode, SdoInfoRepr};

/// Capacity of the buffer holding one object or entry description (or the
/// list lengths) while it is sent in fragments.
pub const INFO_BUFFER: usize = 160;

/// Value info bits of a Get Entry Description request (ETG.1000.6 5.6.3.6).
pub mod value_info {
    /// Bit 3: unit type.
    pub const UNIT: u8 = 0x08;
    /// Bit 4: default value.
    pub const DEFAULT: u8 = 0x10;
    /// Bit 5: minimum value.
    pub const MIN: u8 = 0x20;
    /// Bit 6: maximum value.
    pub const MAX: u8 = 0x40;
    /// All defined bits.
    pub const ALL: u8 = UNIT | DEFAULT | MIN | MAX;
}

/// Object access bits beyond [`Access::bits`](crate::od::types::Access::bits) (ETG.1000.6 5.6.3.6,
/// "ObjAccess").
pub mod access_flag {
    /// Bit 6: mappable in an RxPDO.
    pub const RX_PDO: u16 = 0x0040;
    /// Bit 7: mappable in a TxPDO.
    pub const TX_PDO: u16 = 0x0080;
    /// Bit 8: stored for replacement (backup).
    pub const BACKUP: u16 = 0x0100;
    /// Bit 9: startup parameter (setting).
    pub const SETTING: u16 = 0x0200;
}

/// Data type indices reported for RECORD objects (ETG.1000.6 DEFSTRUCT).
pub mod record_type {
    /// PDO_MAPPING, the PDO mapping objects 0x1600-0x17FF, 0x1A00-0x1BFF.
    pub const PDO_MAPPING: u16 = 0x0021;
    /// IDENTITY, object 0x1018.
    pub const IDENTITY: u16 = 0x0023;
    /// DEFTYPE_RECORD, every other record.
    pub const RECORD: u16 = 0x002A;
}

/// List type 0 of Get OD List: the number of objects of each list.
pub const LIST_LENGTHS: u16 = 0;

/// An object list of Get OD List (ETG.1000.6 5.6.3.3, list types 1..=5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ListType {
    /// `1`: all objects.
    All,
    /// `2`: objects with an RxPDO-mappable entry.
    RxPdo,
    /// `3`: objects with a TxPDO-mappable entry.
    TxPdo,
    /// `4`: objects stored for replacement (an entry with `backup`).
    Backup,
    /// `5`: startup parameters (an entry with `setting`).
    Settings,
}

impl ListType {
    /// The lists in list-type order, as counted by list type 0.
    pub const LISTS: [ListType; 5] = [
        ListType::All,
        ListType::RxPdo,
        ListType::TxPdo,
        ListType::Backup,
        ListType::Settings,
    ];

    /// The list of list type `code`, if it is one of 1..=5.
    pub const fn from_code(code: u16) -> Option<Self> {
        match code {
            1 => Some(ListType::All),
            2 => Some(ListType::RxPdo),
            3 => Some(ListType::TxPdo),
            4 => Some(ListType::Backup),
            5 => Some(ListType::Settings),
            _ => None,
        }
    }

    /// The list type code.
    pub const fn code(self) -> u16 {
        match self {
            ListType::All => 1,
            ListType::RxPdo => 2,
            ListType::TxPdo => 3,
            ListType::Backup => 4,
            ListType::Settings => 5,
        }
    }

    /// Whether object `o` is in this list.
    pub fn contains(self, o: &Object) -> bool {
        let any = |f: fn(&Entry) -> bool| o.entries.iter().any(f);
        match self {
            ListType::All => true,
            ListType::RxPdo => any(|e| e.pdo().allows(PdoMapping::Rx)),
            ListType::TxPdo => any(|e| e.pdo().allows(PdoMapping::Tx)),
            ListType::Backup => any(|e| e.backup()),
            ListType::Settings => any(|e| e.setting()),
        }
    }

    /// Number of objects of `view` in this list.
    pub fn count(self, view: ObjectView) -> usize {
        view.dict
            .objects()
            .iter()
            .filter(|o| self.contains(o) && view.visible(o.index))
            .count()
    }
}

/// The data type an object description reports for `o` (see the module
/// docs).
pub fn object_data_type(o: &Object) -> u16 {
    match o.code {
        ObjectCode::Var => o.entries.first().map_or(0, |e| e.data_type.code()),
        ObjectCode::Array => o
            .entry(1)
            .or_else(|| o.entries.first())
            .map_or(0, |e| e.data_type.code()),
        ObjectCode::Record => match o.index {
            0x1018 => record_type::IDENTITY,
            0x1600..=0x17FF | 0x1A00..=0x1BFF => record_type::PDO_MAPPING,
            _ => record_type::RECORD,
        },
    }
}

/// The object access word of an entry description: [`Access::bits`](crate::od::types::Access::bits) plus
/// the PDO, backup and setting flags of [`access_flag`].
pub fn entry_access(e: &Entry) -> u16 {
    if e.gap() {
        // Padding: no read or write right in any state (SSC: access 0).
        return 0;
    }
    let pdo = match e.pdo() {
        PdoMapping::None => 0,
        PdoMapping::Rx => access_flag::RX_PDO,
        PdoMapping::Tx => access_flag::TX_PDO,
        PdoMapping::RxTx => access_flag::RX_PDO | access_flag::TX_PDO,
    };
    let backup = if e.backup() { access_flag::BACKUP } else { 0 };
    let setting = if e.setting() { access_flag::SETTING } else { 0 };
    e.access().bits() | pdo | backup | setting
}

/// The data type an entry description reports: the entry's type, or
/// [`NULL_TYPE`] for a padding gap.
pub fn entry_data_type(e: &Entry) -> u16 {
    if e.gap() {
        NULL_TYPE
    } else {
        e.data_type.code()
    }
}

/// Data type index 0x0000 (`DEFTYPE_NULL`): what the SSC reports for a
/// padding gap in a record (no value, bit length = the gap).
pub const NULL_TYPE: u16 = 0x0000;

/// ETG.1004 unit codes (reserved (8) | SI prefix (8) | unit (8) |
/// denominator (8)) of the unit texts the core knows.
pub const UNITS: &[(&str, u32)] = &[
    ("s", 0x0003_0000),
    ("ms", 0xFD03_0000),
    ("us", 0xFA03_0000),
    ("µs", 0xFA03_0000),
    ("A", 0x0004_0000),
    ("mA", 0xFD04_0000),
    ("V", 0x0026_0000),
    ("mV", 0xFD26_0000),
    ("Hz", 0x0020_0000),
    ("°C", 0x002D_0000),
    ("m", 0x0001_0000),
    ("mm", 0xFD01_0000),
    ("W", 0x0024_0000),
];

/// The ETG.1004 unit code of a unit text (0 when there is none), the same
/// codes the ESI writes.
pub fn unit_code(unit: &str) -> u32 {
    UNITS
        .iter()
        .find(|(t, _)| *t == unit)
        .map_or(0, |(_, c)| *c)
}

/// The unit text of an ETG.1004 unit code ("" when the core knows none;
/// the inverse of [`unit_code`]).
pub fn unit_text(code: u32) -> &'static str {
    UNITS
        .iter()
        .find(|(_, c)| *c == code && code != 0)
        .map_or("", |(t, _)| t)
}

/// Size in bytes of one value of `e` (default, minimum, maximum).
pub fn value_len(e: &Entry) -> usize {
    usize::from(e.bit_len).div_ceil(8)
}

/// The natural range of a data type (`None` for strings, bytes and
/// floats, whose limits are not integers), as the 64-bit two's complement
/// patterns whose low bytes are sent: no wider integer is needed for
/// UNSIGNED64's maximum (128-bit shifts cost 440 bytes of Cortex-M code).
fn natural_range(t: &DataType, bits: u16, dict: &Dictionary) -> Option<(u64, u64)> {
    let b = u32::from(bits.clamp(1, 64));
    let r = match t {
        DataType::Bool => (0, 1),
        DataType::Enum(en) => {
            let values = dict.find_enum(en.index()).map_or(&[][..], |d| d.values);
            // One pass for both ends.
            let range = values.iter().fold(None, |r: Option<(i64, i64)>, &(v, _)| {
                Some(r.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
            });
            match range {
                Some((lo, hi)) => (lo as u64, hi as u64),
                None => (0, u64::MAX >> (64 - u32::from(en.bit_len().clamp(1, 64)))),
            }
        }
        t if t.is_bytes() || t.is_real() => return None,
        t if t.is_signed() => {
            let lo = u64::MAX << (b - 1);
            (lo, !lo)
        }
        _ => (0, u64::MAX >> (64 - b)),
    };
    Some(r)
}

/// The minimum and maximum an entry description reports: the model's range,
/// else the type's natural range (an enumeration's from `dict`'s
/// [`EnumDesc`](crate::od::EnumDesc)); `None` for strings. Each is the
/// 64-bit two's complement pattern of the value (an `i64` minimum as its
/// bits, UNSIGNED64's maximum as `u64::MAX`): the response sends its low
/// bytes.
pub fn value_range(e: &Entry, dict: &Dictionary) -> Option<(u64, u64)> {
    let (lo, hi) = natural_range(&e.data_type, e.bit_len, dict)?;
    Some((
        e.min().map_or(lo, |v| v as u64),
        e.max().map_or(hi, |v| v as u64),
    ))
}

/// Transfer state of the SDO Information server.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InfoState {
    /// No response in progress.
    Idle,
    /// An OD list (types 1..=5) is being sent.
    OdList {
        /// The list.
        list: ListType,
        /// Position in the dictionary's objects from which to look for the next index.
        cursor: usize,
        /// Whether the list type word is still to be sent (first fragment).
        first: bool,
    },
    /// A response held in the server's buffer is being sent.
    Buffered {
        /// Response opcode.
        opcode: SdoInfoOpcode,
        /// Length of the service data in the buffer.
        len: usize,
        /// Bytes sent so far.
        sent: usize,
    },
}

/// The SDO Information server of one slave.
#[derive(Debug, Clone)]
pub struct SdoInfoServer {
    state: InfoState,
    buf: [u8; INFO_BUFFER],
}

impl Default for SdoInfoServer {
    fn default() -> Self {
        Self::new()
    }
}

impl SdoInfoServer {
    /// A server with no response in progress.
    pub const fn new() -> Self {
        SdoInfoServer {
            state: InfoState::Idle,
            buf: [0; INFO_BUFFER],
        }
    }

    /// Drops a response in progress, in place (no new server built on
    /// the stack; the buffer's stale bytes are never sent).
    pub fn reset(&mut self) {
        self.state = InfoState::Idle;
    }

    /// The transfer state.
    pub fn state(&self) -> InfoState {
        self.state
    }

    /// Whether fragments of a response are still to be sent.
    pub fn busy(&self) -> bool {
        self.state != InfoState::Idle
    }

    /// Handles an SDO Information request: `request` holds the bytes after
    /// the CoE header. Writes the SDO Info payload (from the SDO Info header
    /// on) of the first response fragment into `out` and returns its
    /// length; `None` if `out` cannot hold even the smallest response.
    /// A response still in progress is abandoned.
    pub fn handle(
        &mut self,
        request: &[u8],
        out: &mut [u8],
        view: impl Into<ObjectView>,
    ) -> Option<usize> {
        let view = view.into();
        self.state = InfoState::Idle;
        match self.start(request, view) {
            Ok(()) => self.next_fragment(out, view),
            Err(code) => emit_error(code, out),
        }
    }

    /// Writes the next fragment of the response in progress into `out` and
    /// returns its length; `None` when no response is in progress. If `out`
    /// cannot carry any service data the response is abandoned.
    pub fn next_fragment(&mut self, out: &mut [u8], view: impl Into<ObjectView>) -> Option<usize> {
        let view = view.into();
        let state = self.state;
        let written = match state {
            InfoState::Idle => None,
            InfoState::OdList {
                list,
                cursor,
                first,
            } => self.list_fragment(list, cursor, first, out, view),
            InfoState::Buffered { opcode, len, sent } => {
                self.buffered_fragment(opcode, len, sent, out)
            }
        };
        if written.is_none() {
            self.state = InfoState::Idle;
        }
        written
    }

    /// Parses a request and sets up the response state.
    fn start(&mut self, request: &[u8], view: ObjectView) -> Result<(), SdoAbortCode> {
        let info = SdoInfo::new_checked(request).map_err(|_| SdoAbortCode::UnknownCommand)?;
        let data = info.payload();
        match info.opcode() {
            SdoInfoOpcode::GetOdListReq => {
                let code = read_u16(data, 0).ok_or(SdoAbortCode::UnknownCommand)?;
                if code == LIST_LENGTHS {
                    self.buffer(SdoInfoOpcode::GetOdListResp, |w| {
                        w.u16(LIST_LENGTHS);
                        for list in ListType::LISTS {
                            w.u16(u16::try_from(list.count(view)).unwrap_or(u16::MAX));
                        }
                    })
                } else {
                    let list = ListType::from_code(code).ok_or(SdoAbortCode::UnknownCommand)?;
                    self.state = InfoState::OdList {
                        list,
                        cursor: 0,
                        first: true,
                    };
                    Ok(())
                }
            }
            SdoInfoOpcode::GetObjDescReq => {
                let index = read_u16(data, 0).ok_or(SdoAbortCode::UnknownCommand)?;
                let (_, o) = view.find(index).ok_or(SdoAbortCode::ObjectNotFound)?;
                self.buffer(SdoInfoOpcode::GetObjDescResp, |w| {
                    w.u16(o.index);
                    w.u16(object_data_type(o));
                    w.u8(o.max_sub());
                    w.u8(o.code.code());
                    w.bytes(o.name.as_bytes());
                })
            }
            SdoInfoOpcode::GetEntryDescReq => {
                let index = read_u16(data, 0).ok_or(SdoAbortCode::UnknownCommand)?;
                let sub = data.get(2).copied().ok_or(SdoAbortCode::UnknownCommand)?;
                let asked = data.get(3).copied().ok_or(SdoAbortCode::UnknownCommand)?;
                let (_, o) = view.find(index).ok_or(SdoAbortCode::ObjectNotFound)?;
                let e = o.entry(sub).ok_or(SdoAbortCode::SubindexNotFound)?;
                self.buffer(SdoInfoOpcode::GetEntryDescResp, |w| {
                    write_entry_description(w, index, e, asked, view.dict);
                })
            }
            _ => Err(SdoAbortCode::UnknownCommand),
        }
    }

    /// Builds a response in the buffer and makes it the one in progress.
    fn buffer(
        &mut self,
        opcode: SdoInfoOpcode,
        build: impl FnOnce(&mut Writer<'_>),
    ) -> Result<(), SdoAbortCode> {
        let mut w = Writer::new(&mut self.buf);
        build(&mut w);
        let len = w.finish().ok_or(SdoAbortCode::ObjectTooLong)?;
        self.state = InfoState::Buffered {
            opcode,
            len,
            sent: 0,
        };
        Ok(())
    }

    /// One fragment of an OD list: the list type (first fragment only), then
    /// as many whole indices as fit.
    fn list_fragment(
        &mut self,
        list: ListType,
        cursor: usize,
        first: bool,
        out: &mut [u8],
        view: ObjectView,
    ) -> Option<usize> {
        let objects = view.dict.objects();
        let listed = |o: &Object| list.contains(o) && view.visible(o.index);
        let (head, body) = out.split_at_mut_checked(SDO_INFO_HEADER_LEN)?;
        // Even fragment size: the list type and every index stay whole.
        let room = body.len() & !1;
        if room < 2 {
            return None;
        }
        let mut w = Writer::new(body.get_mut(..room)?);
        if first {
            w.u16(list.code());
        }
        let mut cursor = cursor;
        while w.len + 2 <= room {
            let next = objects.get(cursor..).unwrap_or(&[]).iter().position(listed);
            let Some(skip) = next else {
                cursor = objects.len();
                break;
            };
            let pos = cursor.saturating_add(skip);
            w.u16(objects.get(pos).map_or(0, |o| o.index));
            cursor = pos.saturating_add(1);
        }
        let len = w.finish()?;
        let rest = objects
            .get(cursor..)
            .unwrap_or(&[])
            .iter()
            .filter(|o| listed(o))
            .count()
            .saturating_mul(2);
        self.state = if rest == 0 {
            InfoState::Idle
        } else {
            InfoState::OdList {
                list,
                cursor,
                first: false,
            }
        };
        emit_header(head, SdoInfoOpcode::GetOdListResp, rest, room)?;
        Some(SDO_INFO_HEADER_LEN + len)
    }

    /// One fragment of a buffered response.
    fn buffered_fragment(
        &mut self,
        opcode: SdoInfoOpcode,
        len: usize,
        sent: usize,
        out: &mut [u8],
    ) -> Option<usize> {
        let (head, body) = out.split_at_mut_checked(SDO_INFO_HEADER_LEN)?;
        let remaining = len.checked_sub(sent)?;
        let chunk = body.len().min(remaining);
        if chunk == 0 && remaining > 0 {
            return None;
        }
        let end = sent.checked_add(chunk)?;
        body.get_mut(..chunk)?
            .copy_from_slice(self.buf.get(sent..end)?);
        let rest = remaining - chunk;
        self.state = if rest == 0 {
            InfoState::Idle
        } else {
            InfoState::Buffered {
                opcode,
                len,
                sent: end,
            }
        };
        emit_header(head, opcode, rest, body.len())?;
        Some(SDO_INFO_HEADER_LEN + chunk)
    }
}

/// Writes the service data of an entry description (see the module docs).
fn write_entry_description(
    w: &mut Writer<'_>,
    index: u16,
    e: &Entry,
    asked: u8,
    dict: &Dictionary,
) {
    let range = value_range(e, dict);
    let mut info = asked & value_info::ALL;
    if range.is_none() {
        info &= !(value_info::MIN | value_info::MAX);
    }
    if e.gap() {
        // A padding gap has no value to describe.
        info = 0;
    }
    w.u16(index);
    w.u8(e.sub);
    w.u8(info);
    w.u16(entry_data_type(e));
    w.u16(e.bit_len);
    w.u16(entry_access(e));
    let n = value_len(e);
    if info & value_info::UNIT != 0 {
        w.u32(unit_code(e.unit()));
    }
    if info & value_info::DEFAULT != 0 {
        match e.default_value() {
            DefaultValue::Int(v) => w.int(v.get() as u64, n),
            DefaultValue::Str(s) => {
                let text = s.as_bytes();
                for i in 0..n {
                    w.u8(text.get(i).copied().unwrap_or(0));
                }
            }
            DefaultValue::Bytes(b) => {
                for i in 0..n {
                    w.u8(b.get(i).copied().unwrap_or(0));
                }
            }
        }
    }
    if let Some((lo, hi)) = range {
        if info & value_info::MIN != 0 {
            w.int(lo, n);
        }
        if info & value_info::MAX != 0 {
            w.int(hi, n);
        }
    }
    w.bytes(e.name.as_bytes());
}

/// Writes an SDO Info error request (opcode 7) with `code`.
fn emit_error(code: SdoAbortCode, out: &mut [u8]) -> Option<usize> {
    let (head, body) = out.split_at_mut_checked(SDO_INFO_HEADER_LEN)?;
    body.get_mut(..4)?
        .copy_from_slice(&u32::from(code).to_le_bytes());
    emit_header(head, SdoInfoOpcode::SdoInfoErrorReq, 0, 1)?;
    Some(SDO_INFO_HEADER_LEN + 4)
}

/// Writes the SDO Info header of a fragment after which `rest` bytes of
/// service data remain, to be sent `room` bytes per fragment.
fn emit_header(head: &mut [u8], opcode: SdoInfoOpcode, rest: usize, room: usize) -> Option<()> {
    if room == 0 {
        return None;
    }
    let left = rest.div_ceil(room);
    SdoInfoRepr {
        opcode,
        incomplete: rest > 0,
        fragments_left: u16::try_from(left).unwrap_or(u16::MAX),
    }
    .emit(&mut SdoInfo::new_unchecked(head))
    .ok()
}

/// Little-endian `u16` at `at`.
fn read_u16(data: &[u8], at: usize) -> Option<u16> {
    let end = at.checked_add(2)?;
    let b = data.get(at..end)?;
    Some(u16::from_le_bytes(b.try_into().ok()?))
}

/// Appends bytes to a buffer, remembering an overflow instead of panicking.
struct Writer<'a> {
    buf: &'a mut [u8],
    len: usize,
    overflow: bool,
}

impl<'a> Writer<'a> {
    fn new(buf: &'a mut [u8]) -> Self {
        Writer {
            buf,
            len: 0,
            overflow: false,
        }
    }

    fn bytes(&mut self, data: &[u8]) {
        let end = self.len.saturating_add(data.len());
        match self.buf.get_mut(self.len..end) {
            Some(dst) => {
                dst.copy_from_slice(data);
                self.len = end;
            }
            None => self.overflow = true,
        }
    }

    fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }

    fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }

    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }

    /// The two's complement pattern `v` in `n` bytes, little-endian
    /// (sign-filled beyond 8: a byte entry's zero default is as long as
    /// the entry).
    fn int(&mut self, v: u64, n: usize) {
        let b = v.to_le_bytes();
        let fill = if (v as i64) < 0 { 0xFF } else { 0 };
        for i in 0..n {
            self.u8(b.get(i).copied().unwrap_or(fill));
        }
    }

    /// The length written, or `None` if something did not fit.
    fn finish(self) -> Option<usize> {
        (!self.overflow).then_some(self.len)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use crate::testing::DICT;

    fn request(opcode: u8, data: &[u8]) -> Vec<u8> {
        let mut v = vec![opcode, 0, 0, 0];
        v.extend_from_slice(data);
        v
    }

    /// All fragments of the response, each at most `size` bytes.
    fn exchange(req: &[u8], size: usize) -> Vec<Vec<u8>> {
        let mut server = SdoInfoServer::new();
        let mut out = vec![0u8; size];
        let mut frames = Vec::new();
        let n = server
            .handle(req, &mut out, ObjectView::all(&DICT))
            .expect("a response");
        frames.push(out[..n].to_vec());
        while let Some(n) = server.next_fragment(&mut out, ObjectView::all(&DICT)) {
            frames.push(out[..n].to_vec());
            assert!(frames.len() < 1000);
        }
        frames
    }

    fn data(frames: &[Vec<u8>]) -> Vec<u8> {
        frames.iter().flat_map(|f| f[4..].to_vec()).collect()
    }

    #[test]
    fn the_object_list_is_the_dictionary_in_order_across_small_fragments() {
        let d = data(&exchange(&request(1, &1u16.to_le_bytes()), 12));
        let got: Vec<u16> = d[2..]
            .chunks(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect();
        let want: Vec<u16> = DICT.objects().iter().map(|o| o.index).collect();
        assert_eq!(got, want);
        let rx = data(&exchange(&request(1, &2u16.to_le_bytes()), 128));
        assert_eq!(&rx[2..], &[0x00, 0x70, 0x10, 0x70], "0x7000, 0x7010");
    }

    #[test]
    fn objects_of_empty_slots_are_neither_listed_nor_described() {
        use crate::od::modules::{ModularLayout, SlotRange};
        static LAYOUT: ModularLayout = ModularLayout {
            slots: 2,
            index_distance: 0x10,
            pdo_increment: 1,
            ranges: &[SlotRange {
                base: 0x7000,
                distance: 0x10,
                width: 1,
            }],
            modules: &[],
        };
        // No 0xF050 in the test dictionary: no module detected.
        let store = crate::testing::store();
        let view = ObjectView::modular(&DICT, &LAYOUT, store.od());
        let run = |req: &[u8]| {
            let mut server = SdoInfoServer::new();
            let mut out = vec![0u8; 64];
            let mut frames = vec![];
            let n = server.handle(req, &mut out, view).unwrap();
            frames.push(out[..n].to_vec());
            while let Some(n) = server.next_fragment(&mut out, view) {
                frames.push(out[..n].to_vec());
            }
            frames
        };
        let all = data(&run(&request(1, &1u16.to_le_bytes())));
        let got: Vec<u16> = all[2..]
            .chunks(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect();
        let want: Vec<u16> = DICT
            .objects()
            .iter()
            .map(|o| o.index)
            .filter(|i| *i != 0x7000 && *i != 0x7010)
            .collect();
        assert_eq!(got, want);
        let rx = data(&run(&request(1, &2u16.to_le_bytes())));
        assert_eq!(
            rx,
            [2, 0],
            "the RxPDO-mappable objects are all in empty slots"
        );
        let lengths = data(&run(&request(1, &0u16.to_le_bytes())));
        assert_eq!(
            &lengths[2..6],
            &[want.len() as u8, 0, 0, 0],
            "all; RxPDO list empty"
        );
        let f = &run(&request(3, &[0x10, 0x70]))[0];
        assert_eq!(
            &f[4..8],
            &0x0602_0000u32.to_le_bytes(),
            "object does not exist"
        );
        let f = &run(&request(3, &[0x00, 0x60]))[0];
        assert_eq!(f[0] & 0x7F, 4, "a device object is still described");
    }

    #[test]
    fn entry_descriptions_carry_type_access_unit_and_range() {
        let f = &exchange(&request(5, &[0x00, 0x80, 1, 0x78]), 128)[0];
        // UINT, 16 bits, RW + backup + setting; unit mA, default 100, 0..1000.
        assert_eq!(&f[8..14], &[0x06, 0x00, 16, 0, 0x3F, 0x03]);
        assert_eq!(&f[14..18], &0xFD04_0000u32.to_le_bytes());
        assert_eq!(&f[18..24], &[100, 0, 0, 0, 0xE8, 0x03]);
        assert_eq!(&f[24..], b"Gain");
        let gap = &exchange(&request(5, &[0x00, 0x60, 2, 0x78]), 128)[0];
        assert_eq!(gap[7], 0, "no value info for padding");
        assert_eq!(&gap[8..14], &[0, 0, 7, 0, 0, 0], "NULL, 7 bits, no access");
    }

    #[test]
    fn natural_ranges_are_sent_in_the_entrys_bytes_for_every_integer_width() {
        use crate::od::build::base;
        use crate::od::types::Access;
        let sent = |t: DataType| {
            let e = base(1, "x", t, Access::Ro, PdoMapping::None, 0);
            let (lo, hi) = value_range(&e, &DICT).expect("an integer has a range");
            let mut buf = [0u8; 16];
            let mut w = Writer::new(&mut buf);
            w.int(lo, value_len(&e));
            w.int(hi, value_len(&e));
            let n = w.finish().unwrap();
            buf[..n].to_vec()
        };
        assert_eq!(sent(DataType::Bool), [0, 1]);
        assert_eq!(sent(DataType::Int8), [0x80, 0x7F]);
        assert_eq!(sent(DataType::UInt8), [0x00, 0xFF]);
        assert_eq!(sent(DataType::Int16), [0x00, 0x80, 0xFF, 0x7F]);
        assert_eq!(sent(DataType::UInt24), [0, 0, 0, 0xFF, 0xFF, 0xFF]);
        assert_eq!(
            sent(DataType::Int40),
            [0, 0, 0, 0, 0x80, 0xFF, 0xFF, 0xFF, 0xFF, 0x7F]
        );
        let mut int64 = vec![0; 7];
        int64.extend([0x80]);
        int64.extend([0xFF; 7]);
        int64.push(0x7F);
        assert_eq!(sent(DataType::Int64), int64);
        let mut uint64 = vec![0; 8];
        uint64.extend([0xFF; 8]);
        assert_eq!(sent(DataType::UInt64), uint64);
        // An enumeration: its smallest and largest listed value; one the
        // dictionary does not list, its bits' range.
        assert_eq!(sent(crate::testing::MODE.data_type()), [1, 2]);
        let unlisted = crate::od::EnumDesc {
            index: 0x0801,
            name: "DT0801EN04",
            bit_len: 4,
            values: &[],
        };
        assert_eq!(sent(unlisted.data_type()), [0, 0x0F]);
        // No integer range for strings and floats.
        for t in [DataType::VisibleString, DataType::Real32, DataType::Real64] {
            let e = base(1, "x", t, Access::Ro, PdoMapping::None, 0);
            assert_eq!(value_range(&e, &DICT), None, "{t:?}");
        }
    }

    #[test]
    fn a_byte_entrys_zero_default_is_described_in_all_its_bytes() {
        use crate::od::build::base;
        use crate::od::types::Access;
        let e = Entry {
            bit_len: 128,
            ..base(
                1,
                "x",
                DataType::OctetString,
                Access::Ro,
                PdoMapping::None,
                0,
            )
        };
        let mut buf = [0xAAu8; 64];
        let mut w = Writer::new(&mut buf);
        write_entry_description(&mut w, 0x2000, &e, value_info::DEFAULT, &DICT);
        let n = w.finish().unwrap();
        // index, sub, info, type, bits, access (10 bytes), then the default.
        assert_eq!(buf[3], value_info::DEFAULT);
        assert_eq!(&buf[10..26], &[0u8; 16]);
        assert_eq!(&buf[26..n], b"x");
    }

    #[test]
    fn a_model_range_is_sent_as_its_twos_complement_bytes() {
        use crate::od::build::base;
        use crate::od::types::{Access, Limits};
        const L: Limits = Limits::range(-300, 5, "");
        let e = Entry {
            limits: &L,
            ..base(1, "x", DataType::Int16, Access::Rw, PdoMapping::None, 0)
        };
        let (lo, hi) = value_range(&e, &DICT).unwrap();
        let mut buf = [0u8; 4];
        let mut w = Writer::new(&mut buf);
        w.int(lo, 2);
        w.int(hi, 2);
        assert_eq!(w.finish(), Some(4));
        assert_eq!(buf, [0xD4, 0xFE, 5, 0]);
    }

    #[test]
    fn unknown_objects_and_subindices_answer_sdo_info_errors() {
        let f = &exchange(&request(3, &[0x00, 0x20]), 128)[0];
        assert_eq!(&f[..8], &[0x07, 0, 0, 0, 0x00, 0x00, 0x02, 0x06]);
        let f = &exchange(&request(5, &[0x18, 0x10, 9, 0]), 128)[0];
        assert_eq!(&f[4..8], &0x0609_0011u32.to_le_bytes());
        let f = &exchange(&request(9, &[]), 128)[0];
        assert_eq!(&f[4..8], &0x0504_0001u32.to_le_bytes());
    }
}
