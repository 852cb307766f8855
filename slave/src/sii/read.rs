//! Zero-copy SII image reader (ETG.2010 Tables 2..15), for our own images
//! and other vendors' EEPROM dumps. Every access is bounds-checked; no input
//! makes it panic or loop forever.

use super::{
    CategoryType, DC_ENTRY_LEN, FIRST_CATEGORY_BYTE, FIRST_CATEGORY_WORD, FmmuUsage, GENERAL_LEN,
    PDO_RECORD_LEN, SYNC_MANAGER_LEN, SiiError, SiiGeneral, SiiIdentity, SiiMailbox,
    SiiSyncManager, SmType, crc8,
};

fn u16_at(bytes: &[u8], at: usize) -> u16 {
    match bytes.get(at..at.saturating_add(2)) {
        Some(&[a, b]) => u16::from_le_bytes([a, b]),
        _ => 0,
    }
}

fn i16_at(bytes: &[u8], at: usize) -> i16 {
    i16::from_le_bytes(u16_at(bytes, at).to_le_bytes())
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    match bytes.get(at..at.saturating_add(4)) {
        Some(&[a, b, c, d]) => u32::from_le_bytes([a, b, c, d]),
        _ => 0,
    }
}

fn u8_at(bytes: &[u8], at: usize) -> u8 {
    bytes.get(at).copied().unwrap_or(0)
}

/// A read-only view over an SII image (ETG.2010 Table 2 header followed by
/// the Table 3 category chain).
///
/// The header accessors never fail once [`SiiReader::new`] accepted the
/// image; category decoders report malformed data as [`SiiError`]s.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SiiReader<'a> {
    image: &'a [u8],
}

impl<'a> SiiReader<'a> {
    /// Wraps `image`, which must hold at least the 128-byte header (words
    /// 0x00..0x3F of ETG.2010 Table 2). The checksum is not enforced: see
    /// [`Self::crc_ok`].
    pub fn new(image: &'a [u8]) -> Result<Self, SiiError> {
        if image.len() < FIRST_CATEGORY_BYTE {
            return Err(SiiError::ImageTooShort { len: image.len() });
        }
        Ok(Self { image })
    }

    /// The whole image.
    pub fn image(&self) -> &'a [u8] {
        self.image
    }

    /// The word at `word_addr` (little-endian), if inside the image.
    pub fn word(&self, word_addr: u16) -> Option<u16> {
        let at = usize::from(word_addr).checked_mul(2)?;
        match self.image.get(at..at.checked_add(2)?) {
            Some(&[a, b]) => Some(u16::from_le_bytes([a, b])),
            _ => None,
        }
    }

    fn header_word(&self, word_addr: u16) -> u16 {
        self.word(word_addr).unwrap_or(0)
    }

    /// PDI control, word 0x00 (ETG.2010 Table 2).
    pub fn pdi_control(&self) -> u16 {
        self.header_word(0x00)
    }

    /// PDI configuration, word 0x01 (ETG.2010 Table 2).
    pub fn pdi_config(&self) -> u16 {
        self.header_word(0x01)
    }

    /// SYNC impulse length, word 0x02 (ETG.2010 Table 2).
    pub fn sync_impulse(&self) -> u16 {
        self.header_word(0x02)
    }

    /// PDI configuration 2, word 0x03 (ETG.2010 Table 2).
    pub fn pdi_config2(&self) -> u16 {
        self.header_word(0x03)
    }

    /// Configured station alias, word 0x04 (ETG.2010 Table 2).
    pub fn station_alias(&self) -> u16 {
        self.header_word(0x04)
    }

    /// Bytes 0..14 (words 0x00..0x06), the ESI `ConfigData` the checksum
    /// covers (ETG.2010 Table 2).
    pub fn config_data(&self) -> [u8; 14] {
        let mut out = [0u8; 14];
        if let Some(src) = self.image.get(..14) {
            out.copy_from_slice(src);
        }
        out
    }

    /// The checksum byte stored in the low byte of word 0x07 (ETG.2010
    /// Table 2).
    pub fn stored_crc(&self) -> u8 {
        u8_at(self.image, 14)
    }

    /// The CRC-8 of bytes 0..14 (ETG.2010 Table 2), see [`crc8`].
    pub fn computed_crc(&self) -> u8 {
        crc8(&self.config_data())
    }

    /// Whether the stored checksum matches the computed one (ETG.2010
    /// Table 2). A mismatch does not stop reading.
    pub fn crc_ok(&self) -> bool {
        self.stored_crc() == self.computed_crc()
    }

    /// Vendor id, product code, revision, serial: words 0x08..0x0F
    /// (ETG.2010 Table 2).
    pub fn identity(&self) -> SiiIdentity {
        SiiIdentity {
            vendor_id: u32_at(self.image, 0x10),
            product_code: u32_at(self.image, 0x14),
            revision: u32_at(self.image, 0x18),
            serial: u32_at(self.image, 0x1C),
        }
    }

    fn mailbox_at(&self, word_addr: u16) -> SiiMailbox {
        SiiMailbox {
            rx_offset: self.header_word(word_addr),
            rx_size: self.header_word(word_addr.saturating_add(1)),
            tx_offset: self.header_word(word_addr.saturating_add(2)),
            tx_size: self.header_word(word_addr.saturating_add(3)),
        }
    }

    /// Bootstrap mailbox, words 0x14..0x17 (ETG.2010 Table 2).
    pub fn bootstrap_mailbox(&self) -> SiiMailbox {
        self.mailbox_at(0x14)
    }

    /// Standard mailbox, words 0x18..0x1B (ETG.2010 Table 2).
    pub fn standard_mailbox(&self) -> SiiMailbox {
        self.mailbox_at(0x18)
    }

    /// Supported mailbox protocols, word 0x1C (ETG.2010 Table 2, bits in
    /// [`super::protocols`]).
    pub fn mailbox_protocols(&self) -> u16 {
        self.header_word(0x1C)
    }

    /// Declared EEPROM size in bytes: (word 0x3E + 1) KiBit (ETG.2010
    /// Table 2).
    pub fn eeprom_size_bytes(&self) -> u32 {
        (u32::from(self.header_word(0x3E)) + 1) * 128
    }

    /// Version, word 0x3F (ETG.2010 Table 2; 1 for current images).
    pub fn version(&self) -> u16 {
        self.header_word(0x3F)
    }

    /// Iterates the category chain from word 0x40 (ETG.2010 Table 3).
    pub fn categories(&self) -> Categories<'a> {
        Categories {
            image: self.image,
            next_word: Some(u32::from(FIRST_CATEGORY_WORD)),
        }
    }

    /// The first category of type `kind`, or `None` when the chain ends
    /// without one (ETG.2010 Table 3). A broken chain before it is an error.
    pub fn find(&self, kind: CategoryType) -> Result<Option<Category<'a>>, SiiError> {
        for cat in self.categories() {
            let cat = cat?;
            if cat.kind == kind {
                return Ok(Some(cat));
            }
        }
        Ok(None)
    }

    fn find_data(&self, kind: CategoryType) -> Result<&'a [u8], SiiError> {
        Ok(self.find(kind)?.map_or(&[][..], |c| c.data))
    }

    /// The Strings category (ETG.2010 Table 6); empty when absent.
    pub fn strings(&self) -> Result<SiiStrings<'a>, SiiError> {
        Ok(SiiStrings {
            data: self.find_data(CategoryType::Strings)?,
        })
    }

    /// The General category (ETG.2010 Table 7), `None` when absent.
    ///
    /// Fewer than 16 bytes is [`SiiError::CategoryTooShort`]; bytes 16..32
    /// read as 0 when a (pre-ETG.2010) category stops early; bytes after 32
    /// are ignored.
    pub fn general(&self) -> Result<Option<SiiGeneralRaw>, SiiError> {
        let Some(cat) = self.find(CategoryType::General)? else {
            return Ok(None);
        };
        SiiGeneralRaw::parse(cat.data).map(Some)
    }

    /// Usage bytes of the FMMU category (ETG.2010 Table 8), padding
    /// included; empty when absent.
    pub fn fmmus(&self) -> Result<FmmuIter<'a>, SiiError> {
        Ok(FmmuIter {
            data: self.find_data(CategoryType::Fmmu)?.iter(),
        })
    }

    /// Elements of the SyncM category (ETG.2010 Table 9); empty when
    /// absent. A trailing partial element is ignored.
    pub fn sync_managers(&self) -> Result<SyncManagerIter<'a>, SiiError> {
        Ok(SyncManagerIter {
            chunks: self
                .find_data(CategoryType::SyncM)?
                .chunks_exact(SYNC_MANAGER_LEN),
        })
    }

    /// PDOs of every TxPDO or RxPDO category, in chain order (ETG.2010
    /// Tables 14, 15); empty when absent.
    ///
    /// Our encoder writes all PDOs of a direction into one category, as
    /// ETG.2010 recommends; other generators (and real vendors' EEPROMs)
    /// write one category per PDO, so every category of the type is read.
    /// A broken category chain is an error here when it comes before the
    /// first PDO category, else it ends the iteration with that error.
    pub fn pdos(&self, direction: PdoDirection) -> Result<PdoIter<'a>, SiiError> {
        let kind = match direction {
            PdoDirection::Tx => CategoryType::TxPdo,
            PdoDirection::Rx => CategoryType::RxPdo,
        };
        let mut categories = self.categories();
        // Position on the first category of the type (an error before it
        // is reported now, as for every other accessor).
        let mut rest: &'a [u8] = &[];
        for cat in categories.by_ref() {
            let cat = cat?;
            if cat.kind == kind {
                rest = cat.data;
                break;
            }
        }
        Ok(PdoIter {
            categories,
            kind,
            rest,
            failed: false,
        })
    }

    /// Elements of the DC category (ETG.2010, category DC = 60); empty when absent.
    /// A trailing partial element is ignored.
    pub fn dc(&self) -> Result<DcIter<'a>, SiiError> {
        Ok(DcIter {
            chunks: self.find_data(CategoryType::Dc)?.chunks_exact(DC_ENTRY_LEN),
        })
    }
}

/// One category of the chain (ETG.2010 Table 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Category<'a> {
    /// Decoded type word.
    pub kind: CategoryType,
    /// Word address of the category header (the data starts two words
    /// later).
    pub word_offset: u16,
    /// The category data (length word x 2 bytes); empty for End.
    pub data: &'a [u8],
}

/// Iterator over the category chain (ETG.2010 Table 3), from
/// [`SiiReader::categories`].
///
/// Yields each category in order, including [`CategoryType::End`] (with
/// empty data) as the last item. Stops after End, when fewer than 4 bytes
/// (2 bytes for End) remain, when the next header would lie beyond word
/// 0xFFFF, or after yielding [`SiiError::CategoryOverrun`] for a category
/// running past the image end. Each step advances at least two words, so it
/// always terminates.
#[derive(Debug, Clone)]
pub struct Categories<'a> {
    image: &'a [u8],
    next_word: Option<u32>,
}

impl<'a> Iterator for Categories<'a> {
    type Item = Result<Category<'a>, SiiError>;

    fn next(&mut self) -> Option<Self::Item> {
        let word = self.next_word.take()?;
        let word_offset = u16::try_from(word).ok()?;
        let at = usize::from(word_offset) * 2;
        let raw_type = match self.image.get(at..at.checked_add(2)?) {
            Some(&[a, b]) => u16::from_le_bytes([a, b]),
            _ => return None,
        };
        let kind = CategoryType::from_raw(raw_type);
        if kind == CategoryType::End {
            return Some(Ok(Category {
                kind,
                word_offset,
                data: &[],
            }));
        }
        let len_words = match self.image.get(at.checked_add(2)?..at.checked_add(4)?) {
            Some(&[a, b]) => u16::from_le_bytes([a, b]),
            _ => return None,
        };
        let data_start = at.checked_add(4)?;
        let data_end = data_start.checked_add(usize::from(len_words) * 2)?;
        let Some(data) = self.image.get(data_start..data_end) else {
            return Some(Err(SiiError::CategoryOverrun {
                word_offset,
                len_words,
            }));
        };
        // Strictly increasing: +2 header words plus the length.
        self.next_word = Some(word + 2 + u32::from(len_words));
        Some(Ok(Category {
            kind,
            word_offset,
            data,
        }))
    }
}

/// The Strings category (ETG.2010 Table 6): a count byte, then each string
/// as a length byte and its bytes. Indices are 1-based; 0 means "none".
///
/// Strings are returned verbatim as `&str` when they are valid UTF-8; other
/// bytes (Latin-1 umlauts, embedded bitmaps) are not converted: [`Self::get`]
/// returns `None` for them and [`Self::get_bytes`] gives the raw bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SiiStrings<'a> {
    data: &'a [u8],
}

impl<'a> SiiStrings<'a> {
    /// Wraps the data of a Strings category (ETG.2010 Table 6).
    pub fn from_data(data: &'a [u8]) -> Self {
        Self { data }
    }

    /// The declared number of strings (first byte; 0 when absent).
    pub fn count(&self) -> u8 {
        u8_at(self.data, 0)
    }

    /// The raw bytes of string `idx` (1-based), `None` for 0, an index above
    /// the count, or a string running past the category end.
    pub fn get_bytes(&self, idx: u8) -> Option<&'a [u8]> {
        if idx == 0 || idx > self.count() {
            return None;
        }
        let mut rest = self.data.get(1..)?;
        let mut current: u8 = 1;
        loop {
            let (&len, tail) = rest.split_first()?;
            let (text, next) = tail.split_at_checked(usize::from(len))?;
            if current == idx {
                return Some(text);
            }
            current = current.checked_add(1)?;
            rest = next;
        }
    }

    /// String `idx` (1-based) as text: `None` for 0, a missing index, a
    /// string running past the category, or bytes that are not UTF-8.
    pub fn get(&self, idx: u8) -> Option<&'a str> {
        core::str::from_utf8(self.get_bytes(idx)?).ok()
    }

    /// String `idx` (1-based) copied into `buf` with every byte outside
    /// printable ASCII replaced by `?` and NUL bytes dropped (what ethercrab
    /// shows), truncated to `buf.len()`. `None` as for [`Self::get_bytes`].
    pub fn get_ascii_lossy<'b>(&self, idx: u8, buf: &'b mut [u8]) -> Option<&'b str> {
        let src = self.get_bytes(idx)?;
        let mut n = 0;
        for (dst, &b) in buf.iter_mut().zip(src.iter().filter(|&&b| b != 0)) {
            *dst = if b.is_ascii() { b } else { b'?' };
            n += 1;
        }
        core::str::from_utf8(buf.get(..n)?).ok()
    }

    /// Iterates all declared strings in index order.
    pub fn iter(&self) -> StringIter<'a> {
        StringIter {
            rest: self.data.get(1..).unwrap_or(&[]),
            next_index: 1,
            remaining: self.count(),
        }
    }
}

impl<'a> IntoIterator for &SiiStrings<'a> {
    type Item = (u8, Result<&'a str, SiiError>);
    type IntoIter = StringIter<'a>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// Iterator over the Strings category (ETG.2010 Table 6), yielding the
/// 1-based index and the string, [`SiiError::InvalidUtf8`] for a non-UTF-8
/// string (iteration continues), or [`SiiError::StringOverrun`] for a string
/// running past the category (iteration stops).
#[derive(Debug, Clone)]
pub struct StringIter<'a> {
    rest: &'a [u8],
    next_index: u8,
    remaining: u8,
}

impl<'a> Iterator for StringIter<'a> {
    type Item = (u8, Result<&'a str, SiiError>);

    fn next(&mut self) -> Option<Self::Item> {
        if self.remaining == 0 {
            return None;
        }
        self.remaining -= 1;
        let index = self.next_index;
        self.next_index = self.next_index.saturating_add(1);
        let parsed = self
            .rest
            .split_first()
            .and_then(|(&len, tail)| tail.split_at_checked(usize::from(len)));
        let Some((text, next)) = parsed else {
            self.remaining = 0;
            return Some((index, Err(SiiError::StringOverrun { index })));
        };
        self.rest = next;
        Some((
            index,
            core::str::from_utf8(text).map_err(|_| SiiError::InvalidUtf8 { index }),
        ))
    }
}

/// The General category (ETG.2010 Table 7) with string indices unresolved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SiiGeneralRaw {
    /// Byte 0: group type string index.
    pub group_idx: u8,
    /// Byte 1: image name string index.
    pub image_idx: u8,
    /// Byte 2: order code string index.
    pub order_idx: u8,
    /// Byte 3: device name string index.
    pub name_idx: u8,
    /// Byte 4: reserved (physical layer in older documents).
    pub reserved4: u8,
    /// Byte 5: CoE details.
    pub coe_details: u8,
    /// Byte 6: FoE details.
    pub foe_details: u8,
    /// Byte 7: EoE details.
    pub eoe_details: u8,
    /// Byte 8: SoE channels.
    pub soe_channels: u8,
    /// Byte 9: DS402 channels.
    pub ds402_channels: u8,
    /// Byte 10: SysmanClass.
    pub sysman_class: u8,
    /// Byte 11: flags.
    pub flags: u8,
    /// Bytes 12..13: current on E-Bus in mA.
    pub current_on_ebus: i16,
    /// Byte 14: group index duplicate (Beckhoff images store the group's
    /// display-name string here).
    pub group_idx_dup: u8,
    /// Bytes 16..17: physical port nibbles.
    pub physical_port: u16,
    /// Bytes 18..19: physical memory address of the identification value.
    pub physical_memory_address: u16,
}

impl SiiGeneralRaw {
    /// Decodes General category data (ETG.2010 Table 7); see
    /// [`SiiReader::general`] for the length rules.
    pub fn parse(data: &[u8]) -> Result<Self, SiiError> {
        if data.len() < 16 {
            return Err(SiiError::CategoryTooShort {
                category: CategoryType::General.raw(),
                len: data.len(),
            });
        }
        let mut b = [0u8; GENERAL_LEN];
        let n = data.len().min(GENERAL_LEN);
        if let (Some(dst), Some(src)) = (b.get_mut(..n), data.get(..n)) {
            dst.copy_from_slice(src);
        }
        let [
            group_idx,
            image_idx,
            order_idx,
            name_idx,
            reserved4,
            coe_details,
            foe_details,
            eoe_details,
            soe_channels,
            ds402_channels,
            sysman_class,
            flags,
            c0,
            c1,
            group_idx_dup,
            _,
            p0,
            p1,
            m0,
            m1,
            ..,
        ] = b;
        Ok(Self {
            group_idx,
            image_idx,
            order_idx,
            name_idx,
            reserved4,
            coe_details,
            foe_details,
            eoe_details,
            soe_channels,
            ds402_channels,
            sysman_class,
            flags,
            current_on_ebus: i16::from_le_bytes([c0, c1]),
            group_idx_dup,
            physical_port: u16::from_le_bytes([p0, p1]),
            physical_memory_address: u16::from_le_bytes([m0, m1]),
        })
    }

    /// Resolves the string indices against `strings`; missing or non-UTF-8
    /// strings become `""`.
    pub fn resolve<'a>(&self, strings: &SiiStrings<'a>) -> SiiGeneral<'a> {
        let s = |idx| strings.get(idx).unwrap_or("");
        SiiGeneral {
            group: s(self.group_idx),
            image: s(self.image_idx),
            order: s(self.order_idx),
            name: s(self.name_idx),
            coe_details: self.coe_details,
            foe_details: self.foe_details,
            eoe_details: self.eoe_details,
            flags: self.flags,
            current_on_ebus: self.current_on_ebus,
            physical_port: self.physical_port,
        }
    }
}

/// Iterator over the FMMU category bytes (ETG.2010 Table 8).
#[derive(Debug, Clone)]
pub struct FmmuIter<'a> {
    data: core::slice::Iter<'a, u8>,
}

impl Iterator for FmmuIter<'_> {
    type Item = FmmuUsage;

    fn next(&mut self) -> Option<Self::Item> {
        self.data.next().map(|&b| FmmuUsage::from_raw(b))
    }
}

/// Iterator over the SyncM category (ETG.2010 Table 9).
#[derive(Debug, Clone)]
pub struct SyncManagerIter<'a> {
    chunks: core::slice::ChunksExact<'a, u8>,
}

impl Iterator for SyncManagerIter<'_> {
    type Item = SiiSyncManager;

    fn next(&mut self) -> Option<Self::Item> {
        let rec = self.chunks.next()?;
        Some(SiiSyncManager {
            start: u16_at(rec, 0),
            length: u16_at(rec, 2),
            control: u8_at(rec, 4),
            enable: u8_at(rec, 6),
            sm_type: SmType::from_raw(u8_at(rec, 7)),
        })
    }
}

/// Which PDO category to read (ETG.2010 Table 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PdoDirection {
    /// TxPDO (category 50): slave to master, inputs.
    Tx,
    /// RxPDO (category 51): master to slave, outputs.
    Rx,
}

/// One PDO of a TxPDO/RxPDO category (ETG.2010 Table 14) with its entries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoView<'a> {
    /// PDO index.
    pub index: u16,
    /// Number of entries.
    pub entry_count: u8,
    /// Sync manager byte (0xFF: not assigned by default), see [`Self::sm`].
    pub sm_raw: u8,
    /// DC sync byte.
    pub dc_sync: u8,
    /// Name string index.
    pub name_idx: u8,
    /// PDO flags.
    pub flags: u16,
    entries: &'a [u8],
}

impl<'a> PdoView<'a> {
    /// The default sync manager, `None` for 0xFF (ETG.2010 Table 14).
    pub fn sm(&self) -> Option<u8> {
        (self.sm_raw != 0xFF).then_some(self.sm_raw)
    }

    /// The entries (ETG.2010 Table 15).
    pub fn entries(&self) -> PdoEntryIter<'a> {
        PdoEntryIter {
            chunks: self.entries.chunks_exact(PDO_RECORD_LEN),
        }
    }

    /// Sum of the entries' bit lengths.
    pub fn bit_len(&self) -> u32 {
        self.entries().map(|e| u32::from(e.bit_len)).sum()
    }
}

/// One PDO entry (ETG.2010 Table 15).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoEntryView {
    /// Object index (0 for padding).
    pub index: u16,
    /// Subindex.
    pub sub: u8,
    /// Name string index.
    pub name_idx: u8,
    /// CoE base data type code.
    pub data_type: u8,
    /// Length in bits.
    pub bit_len: u8,
    /// Entry flags.
    pub flags: u16,
}

/// Iterator over a PDO's entries (ETG.2010 Table 15).
#[derive(Debug, Clone)]
pub struct PdoEntryIter<'a> {
    chunks: core::slice::ChunksExact<'a, u8>,
}

impl Iterator for PdoEntryIter<'_> {
    type Item = PdoEntryView;

    fn next(&mut self) -> Option<Self::Item> {
        let rec = self.chunks.next()?;
        Some(PdoEntryView {
            index: u16_at(rec, 0),
            sub: u8_at(rec, 2),
            name_idx: u8_at(rec, 3),
            data_type: u8_at(rec, 4),
            bit_len: u8_at(rec, 5),
            flags: u16_at(rec, 6),
        })
    }
}

/// Iterator over the PDOs of every category of one type (ETG.2010 Table
/// 14), from [`SiiReader::pdos`]. Yields [`SiiError::PdoOverrun`] once for
/// a category whose PDO header or entries run past its end and goes on
/// with the next category. Trailing bytes shorter than a header (word
/// padding) end a category quietly. A broken chain after the first PDO
/// category yields its error and ends the iteration.
#[derive(Debug, Clone)]
pub struct PdoIter<'a> {
    categories: Categories<'a>,
    kind: CategoryType,
    rest: &'a [u8],
    failed: bool,
}

impl<'a> PdoIter<'a> {
    /// Moves to the next category of the type; `Some(Err)` for a broken
    /// chain, `None` at its end.
    fn next_category(&mut self) -> Option<Result<(), SiiError>> {
        loop {
            match self.categories.next()? {
                Err(e) => return Some(Err(e)),
                Ok(cat) if cat.kind == CategoryType::End => return None,
                Ok(cat) if cat.kind == self.kind => {
                    self.rest = cat.data;
                    self.failed = false;
                    return Some(Ok(()));
                }
                Ok(_) => {}
            }
        }
    }
}

impl<'a> Iterator for PdoIter<'a> {
    type Item = Result<PdoView<'a>, SiiError>;

    fn next(&mut self) -> Option<Self::Item> {
        while self.failed || self.rest.len() < PDO_RECORD_LEN {
            match self.next_category()? {
                Ok(()) => {}
                Err(e) => {
                    // Nothing after a broken chain can be trusted.
                    self.categories = Categories {
                        image: &[],
                        next_word: None,
                    };
                    self.rest = &[];
                    return Some(Err(e));
                }
            }
        }
        let (head, tail) = self.rest.split_at_checked(PDO_RECORD_LEN)?;
        let index = u16_at(head, 0);
        let entry_count = u8_at(head, 2);
        let entries_len = usize::from(entry_count) * PDO_RECORD_LEN;
        let Some((entries, next)) = tail.split_at_checked(entries_len) else {
            self.failed = true;
            return Some(Err(SiiError::PdoOverrun { index }));
        };
        self.rest = next;
        Some(Ok(PdoView {
            index,
            entry_count,
            sm_raw: u8_at(head, 3),
            dc_sync: u8_at(head, 4),
            name_idx: u8_at(head, 5),
            flags: u16_at(head, 6),
            entries,
        }))
    }
}

/// One element of the DC category (ETG.2010, category DC = 60).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DcEntry {
    /// Bytes 0..3: SYNC0 cycle time in ns.
    pub cycle_time_sync0: u32,
    /// Bytes 4..7: SYNC0 shift time in ns.
    pub shift_time_sync0: u32,
    /// Bytes 8..11: SYNC1 shift time in ns.
    pub shift_time_sync1: u32,
    /// Bytes 12..13: SYNC1 cycle time factor.
    pub sync1_cycle_factor: i16,
    /// Bytes 14..15: AssignActivate (ESC register 0x0980).
    pub assign_activate: u16,
    /// Bytes 16..17: SYNC0 cycle time factor.
    pub sync0_cycle_factor: i16,
    /// Byte 18: name string index.
    pub name_idx: u8,
    /// Byte 19: description string index.
    pub desc_idx: u8,
}

/// Iterator over the DC category (ETG.2010, category DC = 60).
#[derive(Debug, Clone)]
pub struct DcIter<'a> {
    chunks: core::slice::ChunksExact<'a, u8>,
}

impl Iterator for DcIter<'_> {
    type Item = DcEntry;

    fn next(&mut self) -> Option<Self::Item> {
        let rec = self.chunks.next()?;
        Some(DcEntry {
            cycle_time_sync0: u32_at(rec, 0),
            shift_time_sync0: u32_at(rec, 4),
            shift_time_sync1: u32_at(rec, 8),
            sync1_cycle_factor: i16_at(rec, 12),
            assign_activate: u16_at(rec, 14),
            sync0_cycle_factor: i16_at(rec, 16),
            name_idx: u8_at(rec, 18),
            desc_idx: u8_at(rec, 19),
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::super::{SiiConfig, SiiPdo, SiiPdoEntry, encode, protocols};
    use super::*;
    use std::path::PathBuf;
    use std::string::String;
    use std::vec::Vec;

    /// The real devices' SII dumps committed with the repository
    /// (`tests/data/sii-dumps`, provenance in `tests/data/README.md`).
    pub(crate) fn dump_dir() -> PathBuf {
        PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../tests/data/sii-dumps"
        ))
    }

    /// All `*.bin` files of `dir`, sorted by name.
    pub(crate) fn dumps(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
        let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
            .unwrap()
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "bin"))
            .map(|p| {
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                (name, std::fs::read(&p).unwrap())
            })
            .collect();
        out.sort();
        out
    }

    const TX_ENTRIES_0: [SiiPdoEntry<'static>; 3] = [
        SiiPdoEntry {
            index: 0x6000,
            sub: 1,
            name: "Status word",
            data_type: 6,
            bit_len: 16,
        },
        SiiPdoEntry {
            index: 0x6001,
            sub: 0,
            name: "Fault",
            data_type: 1,
            bit_len: 1,
        },
        SiiPdoEntry {
            index: 0,
            sub: 0,
            name: "",
            data_type: 0,
            bit_len: 7,
        },
    ];
    const TX_ENTRIES_1: [SiiPdoEntry<'static>; 1] = [SiiPdoEntry {
        index: 0x6000,
        sub: 1,
        name: "Status word",
        data_type: 6,
        bit_len: 16,
    }];
    const RX_ENTRIES_0: [SiiPdoEntry<'static>; 2] = [
        SiiPdoEntry {
            index: 0x7000,
            sub: 1,
            name: "Control word",
            data_type: 6,
            bit_len: 16,
        },
        SiiPdoEntry {
            index: 0x7001,
            sub: 1,
            name: "Setpoint",
            data_type: 3,
            bit_len: 16,
        },
    ];
    const TX_PDOS: [SiiPdo<'static>; 2] = [
        SiiPdo {
            index: 0x1A00,
            sm: Some(3),
            name: "Inputs",
            flags: 0,
            entries: &TX_ENTRIES_0,
        },
        SiiPdo {
            index: 0x1A01,
            sm: None,
            name: "Inputs",
            flags: 0,
            entries: &TX_ENTRIES_1,
        },
    ];
    const RX_PDOS: [SiiPdo<'static>; 2] = [
        SiiPdo {
            index: 0x1600,
            sm: Some(2),
            name: "Outputs",
            flags: 0,
            entries: &RX_ENTRIES_0,
        },
        SiiPdo {
            index: 0x1601,
            sm: None,
            name: "Outputs",
            flags: 0,
            entries: &RX_ENTRIES_0,
        },
    ];
    const FMMUS: [FmmuUsage; 3] = [
        FmmuUsage::Outputs,
        FmmuUsage::Inputs,
        FmmuUsage::SyncMStatus,
    ];
    const SMS: [SiiSyncManager; 4] = [
        SiiSyncManager {
            start: 0x1000,
            length: 128,
            control: 0x26,
            enable: 1,
            sm_type: SmType::MailboxOut,
        },
        SiiSyncManager {
            start: 0x1080,
            length: 128,
            control: 0x22,
            enable: 1,
            sm_type: SmType::MailboxIn,
        },
        SiiSyncManager {
            start: 0x1100,
            length: 5,
            control: 0x64,
            enable: 1,
            sm_type: SmType::ProcessOut,
        },
        SiiSyncManager {
            start: 0x1180,
            length: 14,
            control: 0x20,
            enable: 1,
            sm_type: SmType::ProcessIn,
        },
    ];

    fn sample_config() -> SiiConfig<'static> {
        SiiConfig {
            pdi_control: 0x0C08,
            pdi_config: 0x66E8,
            sync_impulse: 0x000A,
            pdi_config2: 0x0000,
            station_alias: 0x0000,
            identity: SiiIdentity {
                vendor_id: 0x0000_0ABC,
                product_code: 0x0012_3456,
                revision: 7,
                serial: 0,
            },
            bootstrap_mailbox: SiiMailbox {
                rx_offset: 0x1000,
                rx_size: 1024,
                tx_offset: 0x1400,
                tx_size: 1024,
            },
            standard_mailbox: SiiMailbox {
                rx_offset: 0x1000,
                rx_size: 128,
                tx_offset: 0x1080,
                tx_size: 128,
            },
            mailbox_protocols: protocols::COE | protocols::FOE,
            eeprom_kbit: 4,
            general: SiiGeneral {
                group: "DEMO",
                image: "",
                order: "XY-123-Z-DEMO",
                name: "XY-123-Z-DEMO",
                coe_details: 0x23,
                foe_details: 1,
                eoe_details: 0,
                flags: 0x01,
                current_on_ebus: 0,
                physical_port: 0x0011,
            },
            fmmus: &FMMUS,
            sync_managers: &SMS,
            tx_pdos: &TX_PDOS,
            rx_pdos: &RX_PDOS,
        }
    }

    #[test]
    fn sample_image_round_trips_every_field() {
        let cfg = sample_config();
        let mut image = [0u8; 512];
        let used = encode(&cfg, &mut image).unwrap();
        let r = SiiReader::new(&image).unwrap();

        assert!(r.crc_ok());
        assert_eq!(r.stored_crc(), crc8(&image[..14]));
        assert_eq!(r.pdi_control(), 0x0C08);
        assert_eq!(r.pdi_config(), 0x66E8);
        assert_eq!(r.sync_impulse(), 0x000A);
        assert_eq!(r.pdi_config2(), 0);
        assert_eq!(r.station_alias(), 0);
        assert_eq!(
            r.config_data(),
            [0x08, 0x0C, 0xE8, 0x66, 0x0A, 0, 0, 0, 0, 0, 0, 0, 0, 0]
        );
        assert_eq!(r.identity(), cfg.identity);
        assert_eq!(
            &image[0x10..0x20],
            &[
                0xBC, 0x0A, 0, 0, 0x56, 0x34, 0x12, 0x00, 7, 0, 0, 0, 0, 0, 0, 0
            ]
        );
        assert_eq!(r.bootstrap_mailbox(), cfg.bootstrap_mailbox);
        assert_eq!(r.standard_mailbox(), cfg.standard_mailbox);
        assert_eq!(
            &image[0x30..0x3A],
            &[0x00, 0x10, 0x80, 0x00, 0x80, 0x10, 0x80, 0x00, 0x0C, 0x00]
        );
        assert_eq!(r.mailbox_protocols(), 0x000C);
        assert_eq!(r.eeprom_size_bytes(), 512);
        assert_eq!(&image[0x7C..0x80], &[3, 0, 1, 0]);
        assert_eq!(r.version(), 1);

        // Category order and the End marker at `used`, 0xFF after it.
        let kinds: Vec<CategoryType> = r.categories().map(|c| c.unwrap().kind).collect();
        assert_eq!(
            kinds,
            [
                CategoryType::Strings,
                CategoryType::General,
                CategoryType::Fmmu,
                CategoryType::SyncM,
                CategoryType::TxPdo,
                CategoryType::RxPdo,
                CategoryType::End,
            ]
        );
        let end = r.categories().last().unwrap().unwrap();
        assert_eq!(usize::from(end.word_offset) * 2 + 4, used);
        assert!(image[used - 4..].iter().all(|&b| b == 0xFF));

        // Strings: deduplicated, the order code stored once.
        let strings = r.strings().unwrap();
        let all: Vec<&str> = strings.iter().map(|(_, s)| s.unwrap()).collect();
        assert_eq!(
            all,
            [
                "XY-123-Z-DEMO",
                "DEMO",
                "Inputs",
                "Status word",
                "Fault",
                "Outputs",
                "Control word",
                "Setpoint"
            ]
        );
        assert_eq!(strings.count(), 8);
        let needle = b"XY-123-Z-DEMO";
        let hits = image.windows(needle.len()).filter(|w| w == needle).count();
        assert_eq!(hits, 1);

        // General: exactly 32 bytes, resolves back to the config.
        let general_cat = r.find(CategoryType::General).unwrap().unwrap();
        assert_eq!(general_cat.data.len(), 32);
        let general = r.general().unwrap().unwrap();
        assert_eq!(general.order_idx, 1);
        assert_eq!(general.name_idx, 1);
        assert_eq!(general.group_idx, 2);
        assert_eq!(general.group_idx_dup, 2);
        assert_eq!(general.image_idx, 0);
        assert_eq!(general.resolve(&strings), cfg.general);

        // FMMUs, with the 0xFF word padding.
        let fmmus: Vec<FmmuUsage> = r.fmmus().unwrap().collect();
        assert_eq!(fmmus, [FMMUS[0], FMMUS[1], FMMUS[2], FmmuUsage::NotUsed]);

        let sms: Vec<SiiSyncManager> = r.sync_managers().unwrap().collect();
        assert_eq!(sms, SMS);
        let sm_cat = r.find(CategoryType::SyncM).unwrap().unwrap();
        assert_eq!(
            &sm_cat.data[16..24],
            &[0x00, 0x11, 0x05, 0x00, 0x64, 0x00, 0x01, 0x03]
        );

        for (dir, expected) in [(PdoDirection::Tx, &TX_PDOS), (PdoDirection::Rx, &RX_PDOS)] {
            let pdos: Vec<PdoView<'_>> = r.pdos(dir).unwrap().map(Result::unwrap).collect();
            assert_eq!(pdos.len(), expected.len());
            for (got, want) in pdos.iter().zip(expected.iter()) {
                assert_eq!(got.index, want.index);
                assert_eq!(got.sm(), want.sm);
                assert_eq!(strings.get(got.name_idx), Some(want.name));
                assert_eq!(usize::from(got.entry_count), want.entries.len());
                let entries: Vec<PdoEntryView> = got.entries().collect();
                assert_eq!(entries.len(), want.entries.len());
                for (e, w) in entries.iter().zip(want.entries) {
                    assert_eq!(e.index, w.index);
                    assert_eq!(e.sub, w.sub);
                    assert_eq!(strings.get(e.name_idx).unwrap_or(""), w.name);
                    assert_eq!(e.data_type, w.data_type);
                    assert_eq!(e.bit_len, w.bit_len);
                    assert_eq!(e.flags, 0);
                }
            }
        }
        let tx: Vec<PdoView<'_>> = r
            .pdos(PdoDirection::Tx)
            .unwrap()
            .map(Result::unwrap)
            .collect();
        assert_eq!(tx[0].bit_len(), 24);
        assert_eq!(tx[1].sm_raw, 0xFF);
        let padding = tx[0].entries().nth(2).unwrap();
        assert_eq!(
            padding,
            PdoEntryView {
                index: 0,
                sub: 0,
                name_idx: 0,
                data_type: 0,
                bit_len: 7,
                flags: 0
            }
        );
        // The raw PDO header of 0x1A01: index, 1 entry, SM 0xFF.
        let tx_cat = r.find(CategoryType::TxPdo).unwrap().unwrap();
        assert_eq!(&tx_cat.data[32..36], &[0x01, 0x1A, 0x01, 0xFF]);
        assert_eq!(r.dc().unwrap().count(), 0);
    }

    #[test]
    fn sample_image_fits_2_kibit_without_pdo_names() {
        let mut cfg = sample_config();
        cfg.eeprom_kbit = 2;
        let mut image = [0u8; 256];
        // With all PDO names the image needs more than 256 bytes.
        assert!(matches!(
            encode(&cfg, &mut image),
            Err(SiiError::BufferTooSmall { .. } | SiiError::ImageTooLarge { .. })
        ));
        let entries = [SiiPdoEntry {
            index: 0x7000,
            sub: 1,
            name: "",
            data_type: 6,
            bit_len: 16,
        }];
        let rx = [SiiPdo {
            index: 0x1600,
            sm: Some(2),
            name: "",
            flags: 0,
            entries: &entries,
        }];
        cfg.tx_pdos = &[];
        cfg.rx_pdos = &rx;
        let used = encode(&cfg, &mut image).unwrap();
        assert!(used <= 256);
        let r = SiiReader::new(&image).unwrap();
        assert_eq!(r.eeprom_size_bytes(), 256);
        assert!(r.crc_ok());
        assert_eq!(r.pdos(PdoDirection::Tx).unwrap().count(), 0);
        assert_eq!(r.pdos(PdoDirection::Rx).unwrap().count(), 1);
    }

    #[test]
    fn real_dumps_decode_without_error() {
        let dir = dump_dir();
        let all = dumps(&dir);
        assert!(!all.is_empty());
        for (name, image) in &all {
            let r = SiiReader::new(image).unwrap();
            assert!(r.crc_ok(), "{name}");
            let id = r.identity();
            assert_ne!(id.vendor_id, 0, "{name}");
            assert_ne!(id.product_code, 0, "{name}");
            let cats: Vec<Category<'_>> = r.categories().map(|c| c.unwrap()).collect();
            assert_eq!(cats.last().unwrap().kind, CategoryType::End, "{name}");
            let strings = r.strings().unwrap();
            let general = r.general().unwrap().unwrap();
            let resolved = general.resolve(&strings);
            assert!(
                !resolved.order.is_empty() || !resolved.name.is_empty(),
                "{name}"
            );
            let fmmus = r.fmmus().unwrap().count();
            let sms = r.sync_managers().unwrap().count();
            let mut pdo_counts = [0usize; 2];
            for (slot, dir) in pdo_counts
                .iter_mut()
                .zip([PdoDirection::Tx, PdoDirection::Rx])
            {
                for pdo in r.pdos(dir).unwrap() {
                    let pdo = pdo.unwrap();
                    assert_eq!(pdo.entries().count(), usize::from(pdo.entry_count));
                    *slot += 1;
                }
            }
            let dc = r.dc().unwrap().count();
            let bad_strings = strings.iter().filter(|(_, s)| s.is_err()).count();
            std::println!(
                "{name}: vendor {:#010x} product {:#010x} rev {:#010x} serial {:#x} \
                 alias {} mbx {:#06x}/{} {:#06x}/{} proto {:#06x} size {} B v{} \
                 order {:?} name {:?} group {:?} coe {:#04x} foe {} flags {:#04x} \
                 ebus {} mA ports {:#06x}; {} categories, {} strings ({} not UTF-8), \
                 {fmmus} FMMUs, {sms} SMs, {} TxPDOs, {} RxPDOs, {dc} DC",
                id.vendor_id,
                id.product_code,
                id.revision,
                id.serial,
                r.station_alias(),
                r.standard_mailbox().rx_offset,
                r.standard_mailbox().rx_size,
                r.standard_mailbox().tx_offset,
                r.standard_mailbox().tx_size,
                r.mailbox_protocols(),
                r.eeprom_size_bytes(),
                r.version(),
                resolved.order,
                resolved.name,
                resolved.group,
                general.coe_details,
                general.foe_details,
                general.flags,
                general.current_on_ebus,
                general.physical_port,
                cats.len(),
                strings.count(),
                bad_strings,
                pdo_counts[0],
                pdo_counts[1],
            );
        }
    }

    #[test]
    fn el2828_dump_decodes_to_known_values() {
        let dir = dump_dir();
        let image = std::fs::read(dir.join("el2828.bin")).unwrap();
        let r = SiiReader::new(&image).unwrap();
        assert_eq!(r.identity().vendor_id, 2);
        let strings = r.strings().unwrap();
        let general = r.general().unwrap().unwrap().resolve(&strings);
        assert_eq!(general.order, "EL2828");
        assert_eq!(general.group, "DigOut");
        let sms: Vec<SiiSyncManager> = r.sync_managers().unwrap().collect();
        assert_eq!(sms[0].start, 0x0F00);
        assert_eq!(sms[0].sm_type, SmType::ProcessOut);
        assert_eq!(r.pdos(PdoDirection::Rx).unwrap().count(), 8);
    }

    #[test]
    fn el2262_dump_has_dc_entries() {
        let dir = dump_dir();
        let image = std::fs::read(dir.join("el2262.bin")).unwrap();
        let r = SiiReader::new(&image).unwrap();
        let dc: Vec<DcEntry> = r.dc().unwrap().collect();
        assert_eq!(dc.len(), 4);
        assert_eq!(dc[1].sync0_cycle_factor, -8);
        assert_eq!(dc[3].name_idx, 8);
        assert_eq!(dc[0].assign_activate, 0x0730);
        assert_eq!(dc[0].sync1_cycle_factor, -1);
        assert_eq!(dc[0].sync0_cycle_factor, -1);
        assert_eq!(dc[0].name_idx, 5);
    }

    /// A 0x80-byte all-zero header followed by `tail`.
    fn image_with(tail: &[u8]) -> Vec<u8> {
        let mut v = std::vec![0u8; 0x80];
        v.extend_from_slice(tail);
        v
    }

    #[test]
    fn truncated_image_is_refused() {
        assert_eq!(
            SiiReader::new(&[0u8; 0x7F]),
            Err(SiiError::ImageTooShort { len: 0x7F })
        );
        assert_eq!(SiiReader::new(&[]), Err(SiiError::ImageTooShort { len: 0 }));
        assert!(SiiReader::new(&[0u8; 0x80]).is_ok());
    }

    #[test]
    fn header_only_image_has_no_categories() {
        let image = [0u8; 0x80];
        let r = SiiReader::new(&image).unwrap();
        assert_eq!(r.categories().count(), 0);
        assert_eq!(r.general(), Ok(None));
        assert_eq!(r.strings().unwrap().count(), 0);
    }

    #[test]
    fn category_running_past_the_end_yields_one_error_and_stops() {
        // Strings (10) claiming 4 words with only 2 present.
        let image = image_with(&[10, 0, 4, 0, 1, 1, b'A', 0]);
        let r = SiiReader::new(&image).unwrap();
        let items: Vec<_> = r.categories().collect();
        assert_eq!(
            items,
            [Err(SiiError::CategoryOverrun {
                word_offset: 0x40,
                len_words: 4
            })]
        );
        assert!(r.strings().is_err());
        assert!(r.general().is_err());
    }

    #[test]
    fn string_running_past_the_category_is_not_returned() {
        // Count 2: "A", then a string claiming 9 bytes in a 2-word category.
        let image = image_with(&[10, 0, 2, 0, 2, 1, b'A', 9, 0xFF, 0xFF, 0xFF, 0xFF]);
        let r = SiiReader::new(&image).unwrap();
        let strings = r.strings().unwrap();
        assert_eq!(strings.get(1), Some("A"));
        assert_eq!(strings.get(2), None);
        assert_eq!(strings.get(3), None);
        assert_eq!(strings.get(0), None);
        let items: Vec<_> = strings.iter().collect();
        assert_eq!(
            items,
            [(1, Ok("A")), (2, Err(SiiError::StringOverrun { index: 2 }))]
        );
        // The chain itself is fine and ends at End.
        assert_eq!(
            r.categories().last().unwrap().unwrap().kind,
            CategoryType::End
        );
    }

    #[test]
    fn ascii_lossy_copy_replaces_non_ascii_and_truncates() {
        let image = image_with(&[10, 0, 3, 0, 1, 4, 0xE4, b'x', 0, b'y', 0xFF, 0xFF]);
        let strings = SiiReader::new(&image).unwrap().strings().unwrap();
        let mut buf = [0u8; 8];
        assert_eq!(strings.get_ascii_lossy(1, &mut buf), Some("?xy"));
        let mut small = [0u8; 2];
        assert_eq!(strings.get_ascii_lossy(1, &mut small), Some("?x"));
        assert_eq!(strings.get_ascii_lossy(2, &mut buf), None);
    }

    #[test]
    fn non_utf8_string_is_none_but_raw_bytes_remain() {
        let image = image_with(&[10, 0, 3, 0, 2, 2, 0xE4, b'x', 1, b'B', 0xFF, 0xFF]);
        let r = SiiReader::new(&image).unwrap();
        let strings = r.strings().unwrap();
        assert_eq!(strings.get(1), None);
        assert_eq!(strings.get_bytes(1), Some(&[0xE4, b'x'][..]));
        assert_eq!(strings.get(2), Some("B"));
        let items: Vec<_> = strings.iter().collect();
        assert_eq!(
            items,
            [(1, Err(SiiError::InvalidUtf8 { index: 1 })), (2, Ok("B"))]
        );
    }

    #[test]
    fn corrupted_crc_is_reported_but_reading_continues() {
        let mut image = [0u8; 512];
        encode(&sample_config(), &mut image).unwrap();
        image[14] ^= 0x5A;
        let r = SiiReader::new(&image).unwrap();
        assert!(!r.crc_ok());
        assert_ne!(r.stored_crc(), r.computed_crc());
        assert_eq!(r.identity().vendor_id, 0x0ABC);
        let strings = r.strings().unwrap();
        assert_eq!(
            r.general().unwrap().unwrap().resolve(&strings).name,
            "XY-123-Z-DEMO"
        );
    }

    #[test]
    fn zero_length_category_chain_terminates() {
        // Nop and vendor categories of length 0, then End.
        let image = image_with(&[0, 0, 0, 0, 0, 0x08, 0, 0, 1, 0, 0, 0, 0xFF, 0xFF]);
        let r = SiiReader::new(&image).unwrap();
        let cats: Vec<Category<'_>> = r.categories().map(Result::unwrap).collect();
        assert_eq!(cats.len(), 4);
        assert_eq!(
            cats.iter().map(|c| c.word_offset).collect::<Vec<_>>(),
            [0x40, 0x42, 0x44, 0x46]
        );
        assert_eq!(cats[1].kind, CategoryType::Vendor(0x0800));
        assert_eq!(cats[2].kind, CategoryType::DeviceSpecific(1));
        assert!(cats.iter().all(|c| c.data.is_empty()));
        assert_eq!(cats[3].kind, CategoryType::End);
    }

    #[test]
    fn all_zero_image_iterates_nops_to_the_buffer_end() {
        let image = [0u8; 2048];
        let r = SiiReader::new(&image).unwrap();
        assert_eq!(r.identity(), SiiIdentity::default());
        assert_eq!(r.categories().count(), (2048 - 0x80) / 4);
        assert!(
            r.categories()
                .all(|c| c.is_ok_and(|c| c.kind == CategoryType::Nop))
        );
        assert_eq!(r.general(), Ok(None));
        assert_eq!(r.fmmus().unwrap().count(), 0);
        assert_eq!(r.eeprom_size_bytes(), 128);
    }

    #[test]
    fn all_ff_image_is_just_an_end_marker() {
        let image = [0xFFu8; 2048];
        let r = SiiReader::new(&image).unwrap();
        let cats: Vec<_> = r.categories().collect();
        assert_eq!(cats.len(), 1);
        assert_eq!(cats[0].unwrap().kind, CategoryType::End);
        assert_eq!(r.general(), Ok(None));
        assert_eq!(r.strings().unwrap().count(), 0);
        assert_eq!(r.eeprom_size_bytes(), 65536 * 128);
        assert_eq!(r.version(), 0xFFFF);
        assert_eq!(r.identity().vendor_id, 0xFFFF_FFFF);
    }

    #[test]
    fn odd_length_image_and_half_header_stop_quietly() {
        // One byte after the header: no category header fits.
        let image = image_with(&[0x1E]);
        assert_eq!(SiiReader::new(&image).unwrap().categories().count(), 0);
        // A type word without its length word.
        let image = image_with(&[0x1E, 0x00]);
        assert_eq!(SiiReader::new(&image).unwrap().categories().count(), 0);
    }

    #[test]
    fn short_general_category_is_an_error() {
        let image = image_with(&[30, 0, 2, 0, 1, 2, 3, 4, 0xFF, 0xFF]);
        let r = SiiReader::new(&image).unwrap();
        assert_eq!(
            r.general(),
            Err(SiiError::CategoryTooShort {
                category: 30,
                len: 4
            })
        );
    }

    #[test]
    fn pdo_entries_past_the_category_end_yield_one_error() {
        // TxPDO with a header claiming 2 entries but carrying 1.
        let mut tail = std::vec![50, 0, 8, 0];
        tail.extend_from_slice(&[0x00, 0x1A, 2, 3, 0, 0, 0, 0]);
        tail.extend_from_slice(&[0x00, 0x60, 1, 0, 6, 16, 0, 0]);
        tail.extend_from_slice(&[0xFF, 0xFF]);
        let image = image_with(&tail);
        let r = SiiReader::new(&image).unwrap();
        let items: Vec<_> = r.pdos(PdoDirection::Tx).unwrap().collect();
        assert_eq!(items, [Err(SiiError::PdoOverrun { index: 0x1A00 })]);
    }

    #[test]
    fn pdos_of_every_category_of_a_direction_are_read() {
        // Three TxPDO categories of one PDO each (as other generators
        // write them), an RxPDO category in between, then End.
        let mut tail = std::vec![];
        for (index, obj) in [(0x1A00u16, 0x6000u16), (0x1A01, 0x6010)] {
            tail.extend_from_slice(&[50, 0, 8, 0]);
            tail.extend_from_slice(&index.to_le_bytes());
            tail.extend_from_slice(&[1, 3, 0, 0, 0, 0]);
            tail.extend_from_slice(&obj.to_le_bytes());
            tail.extend_from_slice(&[1, 0, 6, 16, 0, 0]);
        }
        tail.extend_from_slice(&[51, 0, 8, 0]);
        tail.extend_from_slice(&[0x00, 0x16, 1, 2, 0, 0, 0x10, 0]);
        tail.extend_from_slice(&[0x00, 0x70, 1, 0, 6, 16, 0, 0]);
        tail.extend_from_slice(&[50, 0, 8, 0]);
        tail.extend_from_slice(&[0x02, 0x1A, 1, 0xFF, 0, 0, 0, 0]);
        tail.extend_from_slice(&[0x20, 0x60, 1, 0, 6, 16, 0, 0]);
        tail.extend_from_slice(&[0xFF, 0xFF]);
        let image = image_with(&tail);
        let r = SiiReader::new(&image).unwrap();
        let tx: Vec<u16> = r
            .pdos(PdoDirection::Tx)
            .unwrap()
            .map(|p| p.unwrap().index)
            .collect();
        assert_eq!(tx, [0x1A00, 0x1A01, 0x1A02]);
        let rx: Vec<(u16, u16)> = r
            .pdos(PdoDirection::Rx)
            .unwrap()
            .map(|p| p.map(|p| (p.index, p.flags)).unwrap())
            .collect();
        assert_eq!(rx, [(0x1600, 0x0010)]);
    }

    #[test]
    fn an_overrun_pdo_category_does_not_hide_the_next_one() {
        let mut tail = std::vec![50, 0, 4, 0];
        tail.extend_from_slice(&[0x00, 0x1A, 2, 3, 0, 0, 0, 0]); // claims 2 entries, has 0
        tail.extend_from_slice(&[50, 0, 8, 0]);
        tail.extend_from_slice(&[0x01, 0x1A, 1, 3, 0, 0, 0, 0]);
        tail.extend_from_slice(&[0x00, 0x60, 1, 0, 6, 16, 0, 0]);
        tail.extend_from_slice(&[0xFF, 0xFF]);
        let image = image_with(&tail);
        let r = SiiReader::new(&image).unwrap();
        let items: Vec<_> = r
            .pdos(PdoDirection::Tx)
            .unwrap()
            .map(|p| p.map(|p| p.index))
            .collect();
        assert_eq!(
            items,
            [Err(SiiError::PdoOverrun { index: 0x1A00 }), Ok(0x1A01)]
        );
    }

    #[test]
    fn reader_never_panics_on_bit_flipped_images() {
        let mut image = [0u8; 512];
        encode(&sample_config(), &mut image).unwrap();
        // Flip every byte of the category area to a few values and walk
        // every decoder.
        for at in 0x80..image.len() {
            for value in [0x00, 0x01, 0x7F, 0xFF] {
                let mut m = image;
                m[at] = value;
                let r = SiiReader::new(&m).unwrap();
                for c in r.categories() {
                    let _ = c;
                }
                if let Ok(s) = r.strings() {
                    for i in 0..=255u8 {
                        let _ = s.get(i);
                    }
                    let _ = s.iter().count();
                }
                let _ = r.general();
                let _ = r.fmmus().map(Iterator::count);
                let _ = r.sync_managers().map(Iterator::count);
                for dir in [PdoDirection::Tx, PdoDirection::Rx] {
                    if let Ok(it) = r.pdos(dir) {
                        for p in it.flatten() {
                            let _ = p.entries().count();
                            let _ = p.bit_len();
                        }
                    }
                }
                let _ = r.dc().map(Iterator::count);
            }
        }
    }
}
