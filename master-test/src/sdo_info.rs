//! SDO Information client (ETG.1000.6 5.6.3) on top of [`MailboxClient`].
//!
//! Get OD List, Get Object Description and Get Entry Description, with
//! reassembly of fragmented responses. Frames are built and read with the
//! views of `ecat_slave::wire::coe`; the service data layout (list types,
//! value info, the order of the optional values) is decoded here from the
//! specification, independently of the slave's server, so that an encoding
//! mistake on one side shows up as a test failure.
//!
//! An SDO Info error request from the slave becomes
//! [`ClientError::Abort`] with the index and subindex asked about (0 for OD
//! lists); Emergency messages arriving in between are skipped.

use crate::mailbox::{ClientError, MailboxClient};
use ecat_slave::wire::coe::{
    CoeHeader, CoeService, SDO_INFO_HEADER_LEN, SdoAbortCode, SdoInfo, SdoInfoOpcode,
};
use ecat_slave::wire::mailbox::{MailboxError as WireMailboxError, MailboxType};

/// OD list types of Get OD List (ETG.1000.6 5.6.3.3).
pub mod list_type {
    /// Number of objects in each of the lists 1..=5.
    pub const LENGTHS: u16 = 0;
    /// All objects.
    pub const ALL: u16 = 1;
    /// Objects with RxPDO-mappable entries.
    pub const RX_PDO: u16 = 2;
    /// Objects with TxPDO-mappable entries.
    pub const TX_PDO: u16 = 3;
    /// Objects stored for replacement (backup).
    pub const BACKUP: u16 = 4;
    /// Startup parameters (settings).
    pub const SETTINGS: u16 = 5;
}

/// Value info bits of Get Entry Description (ETG.1000.6 5.6.3.6).
pub mod value_info {
    /// Unit type.
    pub const UNIT: u8 = 0x08;
    /// Default value.
    pub const DEFAULT: u8 = 0x10;
    /// Minimum value.
    pub const MIN: u8 = 0x20;
    /// Maximum value.
    pub const MAX: u8 = 0x40;
    /// All four.
    pub const ALL: u8 = UNIT | DEFAULT | MIN | MAX;
}

/// A Get Object Description response.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObjectInfo {
    /// Object index.
    pub index: u16,
    /// Data type index.
    pub data_type: u16,
    /// Highest subindex.
    pub max_sub: u8,
    /// Object code (7 VAR, 8 ARRAY, 9 RECORD).
    pub object_code: u8,
    /// Object name.
    pub name: String,
}

/// A Get Entry Description response.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EntryInfo {
    /// Object index.
    pub index: u16,
    /// Subindex.
    pub sub: u8,
    /// Data type index.
    pub data_type: u16,
    /// Size in bits.
    pub bit_len: u16,
    /// Object access word (bits 0-5 read/write per state, 6 RxPDO, 7 TxPDO,
    /// 8 backup, 9 setting).
    pub access: u16,
    /// Unit type, if the response carries it.
    pub unit: Option<u32>,
    /// Default value (entry size in bytes, little-endian), if present.
    pub default: Option<Vec<u8>>,
    /// Minimum value, if present.
    pub min: Option<Vec<u8>>,
    /// Maximum value, if present.
    pub max: Option<Vec<u8>>,
    /// Entry name.
    pub name: String,
}

fn protocol(what: impl Into<String>) -> ClientError {
    ClientError::Protocol(what.into())
}

/// Collects the service data of a fragmented SDO Info response.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reassembly {
    /// The response opcode expected.
    opcode: SdoInfoOpcode,
    /// Index and subindex of the request, for errors.
    index: u16,
    sub: u8,
    /// Fragments left announced by the previous fragment.
    left: Option<u16>,
    data: Vec<u8>,
}

impl Reassembly {
    /// Expects a response with `opcode` to a request about `index:sub`.
    pub fn new(opcode: SdoInfoOpcode, index: u16, sub: u8) -> Self {
        Reassembly {
            opcode,
            index,
            sub,
            left: None,
            data: Vec::new(),
        }
    }

    /// Takes one SDO Info message (SDO Info header onwards). Returns the
    /// whole service data once the last fragment is in, `None` while more
    /// are to come; an SDO Info error becomes [`ClientError::Abort`].
    pub fn push(&mut self, info: &[u8]) -> Result<Option<Vec<u8>>, ClientError> {
        let view = SdoInfo::new_checked(info).map_err(|e| protocol(e.to_string()))?;
        let opcode = view.opcode();
        if opcode == SdoInfoOpcode::SdoInfoErrorReq {
            let code: [u8; 4] = view
                .payload()
                .get(..4)
                .and_then(|b| b.try_into().ok())
                .ok_or_else(|| protocol("short SDO Info error"))?;
            return Err(ClientError::Abort {
                index: self.index,
                sub: self.sub,
                code: SdoAbortCode::from(u32::from_le_bytes(code)),
            });
        }
        if opcode != self.opcode {
            return Err(protocol(format!(
                "SDO Info opcode {opcode:?}, expected {:?}",
                self.opcode
            )));
        }
        let left = view.fragments_left();
        match self.left {
            Some(before) if before.checked_sub(1) != Some(left) => {
                return Err(protocol(format!("fragments left {left} after {before}")));
            }
            _ => {}
        }
        if view.incomplete() != (left > 0) {
            return Err(protocol(format!(
                "incomplete bit {} with {left} fragments left",
                view.incomplete()
            )));
        }
        self.data.extend_from_slice(view.payload());
        self.left = Some(left);
        Ok((left == 0).then(|| std::mem::take(&mut self.data)))
    }
}

/// Sends an SDO Info request and reassembles the response's service data.
async fn exchange(
    client: &mut MailboxClient<'_>,
    request: SdoInfoOpcode,
    response: SdoInfoOpcode,
    data: &[u8],
    (index, sub): (u16, u8),
) -> Result<Vec<u8>, ClientError> {
    let head = CoeHeader::<&[u8]>::HEADER_LEN;
    let mut payload = vec![0u8; head + SDO_INFO_HEADER_LEN + data.len()];
    CoeHeader::emit_into(&mut payload[..head], 0, CoeService::SdoInformation);
    {
        let mut info = SdoInfo::new_unchecked(&mut payload[head..]);
        info.set_opcode(request);
        info.set_incomplete(false);
        info.set_reserved(0);
        info.set_fragments_left(0);
        info.payload_mut().copy_from_slice(data);
    }
    client.send(MailboxType::CoE, &payload).await?;
    let mut asm = Reassembly::new(response, index, sub);
    loop {
        let msg = client.receive().await?;
        match msg.kind {
            MailboxType::Error => {
                let e = WireMailboxError::new_checked(&msg.payload[..])
                    .map_err(|e| protocol(e.to_string()))?;
                return Err(ClientError::Mailbox(e.detail()));
            }
            MailboxType::CoE => {
                let coe = CoeHeader::new_checked(&msg.payload[..])
                    .map_err(|e| protocol(e.to_string()))?;
                match coe.service() {
                    CoeService::Emergency => continue,
                    CoeService::SdoInformation => {
                        if let Some(all) = asm.push(coe.payload())? {
                            return Ok(all);
                        }
                    }
                    other => return Err(protocol(format!("CoE service {other:?}"))),
                }
            }
            other => return Err(protocol(format!("mailbox type {other:?}"))),
        }
    }
}

/// Reads the OD list `list_type` (see [`list_type`]): the object indices, or
/// for [`list_type::LENGTHS`] the five list sizes.
pub async fn od_list(
    client: &mut MailboxClient<'_>,
    list_type: u16,
) -> Result<Vec<u16>, ClientError> {
    let data = exchange(
        client,
        SdoInfoOpcode::GetOdListReq,
        SdoInfoOpcode::GetOdListResp,
        &list_type.to_le_bytes(),
        (0, 0),
    )
    .await?;
    parse_od_list(list_type, &data)
}

/// Reads the description of object `index`.
pub async fn object_description(
    client: &mut MailboxClient<'_>,
    index: u16,
) -> Result<ObjectInfo, ClientError> {
    let data = exchange(
        client,
        SdoInfoOpcode::GetObjDescReq,
        SdoInfoOpcode::GetObjDescResp,
        &index.to_le_bytes(),
        (index, 0),
    )
    .await?;
    let info = parse_object_description(&data)?;
    if info.index != index {
        return Err(protocol(format!("description of {:#06x}", info.index)));
    }
    Ok(info)
}

/// Reads the description of entry `index:sub`, asking for the values of
/// `value_info` (see [`value_info`]).
pub async fn entry_description(
    client: &mut MailboxClient<'_>,
    index: u16,
    sub: u8,
    value_info: u8,
) -> Result<EntryInfo, ClientError> {
    let [lo, hi] = index.to_le_bytes();
    let data = exchange(
        client,
        SdoInfoOpcode::GetEntryDescReq,
        SdoInfoOpcode::GetEntryDescResp,
        &[lo, hi, sub, value_info],
        (index, sub),
    )
    .await?;
    let info = parse_entry_description(&data)?;
    if (info.index, info.sub) != (index, sub) {
        return Err(protocol(format!(
            "description of {:#06x}:{:02x}",
            info.index, info.sub
        )));
    }
    Ok(info)
}

/// Decodes the service data of a Get OD List response.
pub fn parse_od_list(list_type: u16, data: &[u8]) -> Result<Vec<u16>, ClientError> {
    if data.len() < 2 || data.len() & 1 != 0 {
        return Err(protocol(format!("OD list of {} bytes", data.len())));
    }
    let words: Vec<u16> = data
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    if words[0] != list_type {
        return Err(protocol(format!("list type {} for {list_type}", words[0])));
    }
    Ok(words[1..].to_vec())
}

/// Decodes the service data of a Get Object Description response.
pub fn parse_object_description(data: &[u8]) -> Result<ObjectInfo, ClientError> {
    if data.len() < 6 {
        return Err(protocol(format!(
            "object description of {} bytes",
            data.len()
        )));
    }
    Ok(ObjectInfo {
        index: u16::from_le_bytes([data[0], data[1]]),
        data_type: u16::from_le_bytes([data[2], data[3]]),
        max_sub: data[4],
        object_code: data[5],
        name: String::from_utf8_lossy(&data[6..]).into_owned(),
    })
}

/// Decodes the service data of a Get Entry Description response; the
/// optional values present are those flagged in the response's value info,
/// each `bit_len` rounded up to whole bytes.
pub fn parse_entry_description(data: &[u8]) -> Result<EntryInfo, ClientError> {
    let short = || protocol(format!("entry description of {} bytes", data.len()));
    if data.len() < 10 {
        return Err(short());
    }
    let u16_at = |at: usize| u16::from_le_bytes([data[at], data[at + 1]]);
    let info = data[3];
    let bit_len = u16_at(6);
    let size = usize::from(bit_len).div_ceil(8);
    let mut rest = &data[10..];
    let mut take = |n: usize, flag: u8| -> Result<Option<Vec<u8>>, ClientError> {
        if info & flag == 0 {
            return Ok(None);
        }
        let (v, tail) = rest.split_at_checked(n).ok_or_else(short)?;
        rest = tail;
        Ok(Some(v.to_vec()))
    };
    let unit = take(4, value_info::UNIT)?.map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let default = take(size, value_info::DEFAULT)?;
    let min = take(size, value_info::MIN)?;
    let max = take(size, value_info::MAX)?;
    Ok(EntryInfo {
        index: u16_at(0),
        sub: data[2],
        data_type: u16_at(4),
        bit_len,
        access: u16_at(8),
        unit,
        default,
        min,
        max,
        name: String::from_utf8_lossy(rest).into_owned(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(opcode: u8, left: u16, data: &[u8]) -> Vec<u8> {
        let mut v = vec![opcode, 0];
        v.extend(left.to_le_bytes());
        v.extend_from_slice(data);
        v
    }

    #[test]
    fn fragments_are_joined_in_order() {
        let mut asm = Reassembly::new(SdoInfoOpcode::GetOdListResp, 0, 0);
        assert_eq!(
            asm.push(&frame(0x82, 2, &[1, 0, 0x00, 0x10])).unwrap(),
            None
        );
        assert_eq!(asm.push(&frame(0x82, 1, &[0x01, 0x10])).unwrap(), None);
        let all = asm.push(&frame(0x02, 0, &[0x08, 0x10])).unwrap().unwrap();
        assert_eq!(parse_od_list(1, &all).unwrap(), [0x1000, 0x1001, 0x1008]);
    }

    #[test]
    fn a_skipped_fragment_is_a_protocol_error() {
        let mut asm = Reassembly::new(SdoInfoOpcode::GetOdListResp, 0, 0);
        asm.push(&frame(0x82, 2, &[1, 0])).unwrap();
        assert!(matches!(
            asm.push(&frame(0x02, 0, &[])),
            Err(ClientError::Protocol(_))
        ));
    }

    #[test]
    fn an_info_error_becomes_an_abort_with_the_request_address() {
        let mut asm = Reassembly::new(SdoInfoOpcode::GetEntryDescResp, 0x1018, 5);
        let err = asm
            .push(&frame(0x07, 0, &0x0609_0011u32.to_le_bytes()))
            .unwrap_err();
        assert_eq!(err.abort_code(), Some(0x0609_0011));
        assert!(matches!(
            err,
            ClientError::Abort {
                index: 0x1018,
                sub: 5,
                ..
            }
        ));
    }

    #[test]
    fn entry_description_values_follow_the_value_info() {
        let mut d = vec![0x0D, 0x80, 0x02, 0x58, 0x06, 0x00, 16, 0, 0x3F, 0x03];
        d.extend(0xFD04_0000u32.to_le_bytes());
        d.extend(1000u16.to_le_bytes());
        d.extend(3000u16.to_le_bytes());
        d.extend_from_slice(b"CURRENT");
        let e = parse_entry_description(&d).unwrap();
        assert_eq!((e.index, e.sub, e.data_type, e.bit_len), (0x800D, 2, 6, 16));
        assert_eq!(e.access, 0x033F);
        assert_eq!(e.unit, Some(0xFD04_0000));
        assert_eq!(e.default, Some(1000u16.to_le_bytes().to_vec()));
        assert_eq!(e.min, None);
        assert_eq!(e.max, Some(3000u16.to_le_bytes().to_vec()));
        assert_eq!(e.name, "CURRENT");
    }

    #[test]
    fn object_description_is_decoded() {
        let mut d = vec![0x18, 0x10, 0x23, 0x00, 4, 9];
        d.extend_from_slice(b"IDENTITY");
        let o = parse_object_description(&d).unwrap();
        assert_eq!(
            o,
            ObjectInfo {
                index: 0x1018,
                data_type: 0x0023,
                max_sub: 4,
                object_code: 9,
                name: "IDENTITY".into()
            }
        );
        assert!(parse_object_description(&d[..5]).is_err());
    }
}
