//! The live object dictionary as TwinCAT's CoE-Online tab shows it: every
//! object SDO Information lists, every entry it describes, and each
//! readable entry's value read over SDO. The `od dump` command prints it.

use crate::cli::{self, Value};
use crate::mailbox::{ClientError, MailboxClient};
use crate::sdo_info::{self, EntryInfo, ObjectInfo, value_info};

/// What the dump shows in an entry's value column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EntryValue {
    /// The value read over SDO.
    Value(Value),
    /// The entry has write but no read rights: nothing to read.
    WriteOnly,
    /// A padding gap of a record (data type NULL, no access rights, as
    /// the SSC describes them): it only takes up bits.
    Padding,
    /// The slave refused or failed the upload of a readable entry.
    Error(String),
}

impl EntryValue {
    /// The text of the value column (`1000`, `(write-only)`, `(padding)`,
    /// `(abort 0x06010000 ...)`).
    pub fn text(&self, bit_len: u16) -> String {
        match self {
            EntryValue::Value(v) => cli::show(v, bit_len),
            EntryValue::WriteOnly => "(write-only)".into(),
            EntryValue::Padding => "(padding)".into(),
            EntryValue::Error(e) => format!("({e})"),
        }
    }
}

/// One described entry with its value.
#[derive(Debug, Clone)]
pub struct DumpEntry {
    /// The entry description (value info: all).
    pub info: EntryInfo,
    /// Its value, or why there is none.
    pub value: EntryValue,
}

/// One object of the dump.
#[derive(Debug, Clone)]
pub struct DumpObject {
    /// The object description.
    pub info: ObjectInfo,
    /// Its described entries, subindex order (absent subindices skipped).
    pub entries: Vec<DumpEntry>,
}

/// Reads one object: its description, every entry description and each
/// readable entry's value.
pub async fn read_object(c: &mut MailboxClient<'_>, index: u16) -> Result<DumpObject, ClientError> {
    let info = sdo_info::object_description(c, index).await?;
    let mut entries = Vec::new();
    for sub in 0..=info.max_sub {
        // Absent subindices have no description: skip them.
        let Ok(e) = sdo_info::entry_description(c, index, sub, value_info::ALL).await else {
            continue;
        };
        let value = if e.access & 0x3F == 0 && e.data_type == 0 {
            EntryValue::Padding
        } else if e.access & 0x07 == 0 {
            EntryValue::WriteOnly
        } else {
            match c.sdo_upload(index, sub, false).await {
                Ok(b) => EntryValue::Value(cli::decode(e.data_type, e.bit_len, &b)),
                Err(ClientError::Abort { code, .. }) => EntryValue::Error(format!("abort {code}")),
                Err(err) => EntryValue::Error(err.to_string()),
            }
        };
        entries.push(DumpEntry { info: e, value });
    }
    Ok(DumpObject { info, entries })
}

/// Reads the whole dictionary (SDO Information list type "all objects").
pub async fn read_dictionary(c: &mut MailboxClient<'_>) -> Result<Vec<DumpObject>, ClientError> {
    let objects = sdo_info::od_list(c, sdo_info::list_type::ALL).await?;
    let mut out = Vec::with_capacity(objects.len());
    for index in objects {
        out.push(read_object(c, index).await?);
    }
    Ok(out)
}
