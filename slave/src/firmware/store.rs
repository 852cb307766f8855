//! The A/B image store: the [`ImageStore`] HAL trait, the power-cut safe
//! [`BootState`] record, and the in-memory [`MemStore`].

use super::{Crc32, FirmwareVersion, VERSION_LEN, crc32};
use crate::wire::foe::FoeErrorCode;

/// One of the two image slots.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Slot {
    /// Slot A (the factory slot).
    #[default]
    A,
    /// Slot B.
    B,
}

impl Slot {
    /// The other slot.
    pub const fn other(self) -> Self {
        match self {
            Self::A => Self::B,
            Self::B => Self::A,
        }
    }

    /// 0 for A, 1 for B.
    pub const fn index(self) -> usize {
        match self {
            Self::A => 0,
            Self::B => 1,
        }
    }

    const fn from_raw(raw: u8) -> Option<Self> {
        match raw {
            0 => Some(Self::A),
            1 => Some(Self::B),
            _ => None,
        }
    }
}

/// Failures of the image store and of the bootloader operations on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StoreError {
    /// Offset and length run past the end of a slot.
    OutOfBounds,
    /// Power was lost during the operation (simulated by [`MemStore`]).
    PowerLost,
    /// The flash or file could not be accessed.
    Io,
    /// Neither boot-state copy is valid (a blank device).
    NoState,
    /// A written image does not read back with its CRC.
    VerifyFailed,
    /// A write was aimed at the active (running) slot.
    ActiveSlot,
    /// A new image runs on trial and is not yet confirmed; its slot cannot
    /// be replaced until [`confirm_boot`](super::confirm_boot) or
    /// [`reject_boot`](super::reject_boot).
    TrialRunning,
}

impl core::fmt::Display for StoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.text())
    }
}

impl core::error::Error for StoreError {}

impl StoreError {
    /// The text of the error (the FoE error reply carries it; `Display`
    /// prints it).
    pub const fn text(&self) -> &'static str {
        match self {
            Self::OutOfBounds => "access beyond the end of the slot",
            Self::PowerLost => "power lost during write",
            Self::Io => "flash access failed",
            Self::NoState => "no valid boot state",
            Self::VerifyFailed => "image verify failed after writing",
            Self::ActiveSlot => "refusing to write the active slot",
            Self::TrialRunning => "trial image not yet confirmed",
        }
    }

    /// The FoE error code reported when a download fails with this error:
    /// `0x8003` DiskFull for [`StoreError::OutOfBounds`], `0x8002`
    /// AccessDenied for [`StoreError::ActiveSlot`] and
    /// [`StoreError::TrialRunning`], otherwise `0x8011` FlashError (SSC).
    pub const fn foe_code(&self) -> FoeErrorCode {
        match self {
            Self::OutOfBounds => FoeErrorCode::DiskFull,
            Self::ActiveSlot | Self::TrialRunning => FoeErrorCode::AccessDenied,
            Self::PowerLost | Self::Io | Self::NoState | Self::VerifyFailed => {
                FoeErrorCode::FlashError
            }
        }
    }
}

/// Flash HAL for two image slots and the boot state.
///
/// Implementations must make [`ImageStore::write_state`] power-cut safe:
/// keep two copies of the [`BootState`] record, write the new record
/// (sequence number one above the newest valid copy) over the *other*
/// copy, and let [`ImageStore::read_state`] return the newest copy whose
/// CRC is valid. [`BootState::read_bank`] and [`BootState::bank_write`] do
/// exactly that over two raw records.
pub trait ImageStore {
    /// Size of one slot in bytes.
    fn slot_capacity(&self) -> usize;
    /// Erases a whole slot (to `0xFF`).
    fn erase(&mut self, slot: Slot) -> Result<(), StoreError>;
    /// Writes `data` at `offset` of an erased slot region.
    fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError>;
    /// Reads up to `buf.len()` bytes from `offset`; returns the count (short
    /// at the end of the slot).
    fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError>;
    /// The newest valid boot state ([`StoreError::NoState`] if none).
    fn read_state(&self) -> Result<BootState, StoreError>;
    /// Stores `state` power-cut safely; its `sequence` is ignored and set
    /// by the store.
    fn write_state(&mut self, state: &BootState) -> Result<(), StoreError>;
}

/// What an image slot holds: payload length, CRC-32 and version.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ImageInfo {
    /// Payload length in bytes.
    pub len: u32,
    /// CRC-32 of the payload.
    pub crc: u32,
    /// Firmware version.
    pub version: FirmwareVersion,
}

/// How far a new image has come.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CandidateStage {
    /// Completely downloaded and validated, not yet committed.
    Downloaded,
    /// Committed (BOOT → INIT): the bootloader tries it at the next
    /// power-on.
    Pending,
    /// Booted on trial, not yet confirmed by the new firmware.
    Trial,
}

impl CandidateStage {
    const fn raw(self) -> u8 {
        match self {
            Self::Downloaded => 1,
            Self::Pending => 2,
            Self::Trial => 3,
        }
    }
}

/// A new image in the inactive slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Candidate {
    /// Its slot (never the active one).
    pub slot: Slot,
    /// What it is.
    pub image: ImageInfo,
    /// How far it has come.
    pub stage: CandidateStage,
}

/// Length of one encoded [`BootState`] record (format 2, see
/// [`BootState::encode`]).
pub const STATE_RECORD_LEN: usize = rec::CRC.end;

/// Length of a format-1 record (before the owner's FoE password), which
/// [`BootState::decode`] still reads.
pub const STATE_RECORD_V1_LEN: usize = rec::V1_CRC.end;

/// Offsets of the boot-state record (see [`BootState::encode`]).
mod rec {
    pub type Field = core::ops::Range<usize>;
    pub const MAGIC: Field = 0..4;
    pub const SEQUENCE: Field = 4..8;
    pub const ACTIVE: usize = 8;
    pub const STAGE: usize = 9;
    pub const CANDIDATE_SLOT: usize = 10;
    pub const ATTEMPTS: usize = 11;
    pub const ACTIVE_IMAGE: usize = 12;
    pub const CANDIDATE_IMAGE: usize = 36;
    /// Format 1 ends with its CRC here.
    pub const V1_CRC: Field = 60..64;
    /// Format 2: 1 when the owner set a FoE password.
    pub const PASSWORD_SET: usize = 60;
    /// Format 2: the owner's FoE password.
    pub const PASSWORD: Field = 64..68;
    /// Format 2: the anti-rollback floor (a version, `[u8; 16]`).
    pub const MIN_VERSION: Field = 68..84;
    pub const CRC: Field = 92..96;
}

/// Magic of a format-1 boot-state record (64 bytes, no password).
const STATE_MAGIC_V1: [u8; 4] = *b"PBST";

/// Magic of a format-2 boot-state record (96 bytes).
const STATE_MAGIC: [u8; 4] = *b"PBS2";

/// The boot state: which slot runs, and the new image on its way in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BootState {
    /// Sequence number: the newer of two valid copies wins (serial-number
    /// comparison, so it may wrap). Set by the store on write.
    pub sequence: u32,
    /// The slot that runs when no candidate is tried.
    pub active: Slot,
    /// What the active slot holds.
    pub active_image: ImageInfo,
    /// A new image in the other slot, if any.
    pub candidate: Option<Candidate>,
    /// Boots of the candidate on trial so far.
    pub boot_attempts: u8,
    /// The FoE password the owner set ([`set_password`]); `None`: the
    /// device's factory password
    /// ([`FoeSecurity::factory_password`](crate::device::FoeSecurity)) applies.
    ///
    /// [`set_password`]: super::set_password
    pub password: Option<u32>,
    /// The anti-rollback floor: an image older than this is refused unless
    /// the owner allows the downgrade ([`FirmwareVersion::compare`]). The
    /// version of the image last provisioned or confirmed;
    /// [`FirmwareVersion::EMPTY`]: no floor.
    pub min_version: FirmwareVersion,
}

fn put(buf: &mut [u8; STATE_RECORD_LEN], at: usize, bytes: &[u8]) {
    if let Some(dst) = buf.get_mut(at..at.saturating_add(bytes.len())) {
        dst.copy_from_slice(bytes);
    }
}

fn get_u32(buf: &[u8], at: usize) -> u32 {
    buf.get(at..at.saturating_add(4))
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map_or(0, u32::from_le_bytes)
}

fn put_image(buf: &mut [u8; STATE_RECORD_LEN], at: usize, image: &ImageInfo) {
    put(buf, at, &image.len.to_le_bytes());
    put(buf, at + 4, &image.crc.to_le_bytes());
    put(buf, at + 8, image.version.raw());
}

fn get_image(buf: &[u8], at: usize) -> ImageInfo {
    let version = buf
        .get(at + 8..at + 8 + VERSION_LEN)
        .and_then(|b| <[u8; VERSION_LEN]>::try_from(b).ok())
        .unwrap_or([0; VERSION_LEN]);
    ImageInfo {
        len: get_u32(buf, at),
        crc: get_u32(buf, at + 4),
        version: FirmwareVersion::from_raw(version),
    }
}

/// `a` is newer than `b` in serial-number arithmetic.
const fn newer(a: u32, b: u32) -> bool {
    (a.wrapping_sub(b) as i32) > 0
}

impl BootState {
    /// The state of a blank device: slot A active, image unknown.
    pub const fn initial() -> Self {
        Self {
            sequence: 0,
            active: Slot::A,
            active_image: ImageInfo {
                len: 0,
                crc: 0,
                version: FirmwareVersion::EMPTY,
            },
            candidate: None,
            boot_attempts: 0,
            password: None,
            min_version: FirmwareVersion::EMPTY,
        }
    }

    /// Encodes the record (format 2), CRC included. Layout
    /// (little-endian):
    ///
    /// | offset | size | field                                                   |
    /// |-------:|-----:|---------------------------------------------------------|
    /// | 0      | 4    | magic `b"PBS2"`                                          |
    /// | 4      | 4    | sequence number                                         |
    /// | 8      | 1    | active slot (0 = A, 1 = B)                              |
    /// | 9      | 1    | candidate stage (0 none, 1 downloaded, 2 pending, 3 trial) |
    /// | 10     | 1    | candidate slot                                          |
    /// | 11     | 1    | boot attempts of the candidate                          |
    /// | 12     | 24   | active image: len u32, crc u32, version `[u8; 16]`          |
    /// | 36     | 24   | candidate image: len u32, crc u32, version `[u8; 16]`       |
    /// | 60     | 1    | 1: the owner set a FoE password, 0: factory password    |
    /// | 61     | 3    | reserved, 0                                             |
    /// | 64     | 4    | the owner's FoE password (0 when not set)               |
    /// | 68     | 16   | anti-rollback floor: a version, NUL padded (0: none)    |
    /// | 84     | 8    | reserved, 0                                             |
    /// | 92     | 4    | CRC-32 of bytes 0..92                                   |
    ///
    /// Format 1 (magic `b"PBST"`, 64 bytes: the same up to offset 60, then
    /// the CRC-32 of bytes 0..60) is still decoded, as a record without a
    /// password whose floor is the active image's version: a store written before passwords existed keeps working
    /// and is rewritten in format 2 at its next state change.
    pub fn encode(&self) -> [u8; STATE_RECORD_LEN] {
        self.encode_as(self.sequence)
    }

    /// [`BootState::encode`] with another sequence number (no copy of the
    /// state to change it).
    fn encode_as(&self, sequence: u32) -> [u8; STATE_RECORD_LEN] {
        let mut buf = [0u8; STATE_RECORD_LEN];
        put(&mut buf, rec::MAGIC.start, &STATE_MAGIC);
        put(&mut buf, rec::SEQUENCE.start, &sequence.to_le_bytes());
        put(&mut buf, rec::ACTIVE, &[self.active.index() as u8]);
        let (stage, slot, image) = match &self.candidate {
            Some(c) => (c.stage.raw(), c.slot.index() as u8, c.image),
            None => (0, 0, ImageInfo::default()),
        };
        put(&mut buf, rec::STAGE, &[stage]);
        put(&mut buf, rec::CANDIDATE_SLOT, &[slot]);
        put(&mut buf, rec::ATTEMPTS, &[self.boot_attempts]);
        put_image(&mut buf, rec::ACTIVE_IMAGE, &self.active_image);
        put_image(&mut buf, rec::CANDIDATE_IMAGE, &image);
        put(
            &mut buf,
            rec::PASSWORD_SET,
            &[u8::from(self.password.is_some())],
        );
        put(
            &mut buf,
            rec::PASSWORD.start,
            &self.password.unwrap_or(0).to_le_bytes(),
        );
        put(&mut buf, rec::MIN_VERSION.start, self.min_version.raw());
        let crc = buf.get(..rec::CRC.start).map_or(0, crc32);
        put(&mut buf, rec::CRC.start, &crc.to_le_bytes());
        buf
    }

    /// Decodes a record of format 2 or 1; `None` if it is short, torn
    /// (CRC), blank or holds impossible values.
    pub fn decode(buf: &[u8]) -> Option<Self> {
        let magic = buf.get(rec::MAGIC)?;
        let (len, crc_at) = if magic == STATE_MAGIC {
            (STATE_RECORD_LEN, rec::CRC.start)
        } else if magic == STATE_MAGIC_V1 {
            (STATE_RECORD_V1_LEN, rec::V1_CRC.start)
        } else {
            return None;
        };
        let buf = buf.get(..len)?;
        let mut crc = Crc32::new();
        crc.update(buf.get(..crc_at)?);
        if crc.finish() != get_u32(buf, crc_at) {
            return None;
        }
        let byte = |at: usize| buf.get(at).copied();
        let active_image = get_image(buf, rec::ACTIVE_IMAGE);
        // Reserved bytes are written 0 and ignored (room for later fields).
        let (password, min_version) = if len == STATE_RECORD_LEN {
            let password = match byte(rec::PASSWORD_SET)? {
                0 => None,
                1 => Some(get_u32(buf, rec::PASSWORD.start)),
                _ => return None,
            };
            let floor = buf
                .get(rec::MIN_VERSION)
                .and_then(|b| <[u8; VERSION_LEN]>::try_from(b).ok())?;
            (password, FirmwareVersion::from_raw(floor))
        } else {
            (None, active_image.version)
        };
        let active = Slot::from_raw(byte(rec::ACTIVE)?)?;
        let slot = Slot::from_raw(byte(rec::CANDIDATE_SLOT)?)?;
        let stage = match byte(rec::STAGE)? {
            0 => None,
            1 => Some(CandidateStage::Downloaded),
            2 => Some(CandidateStage::Pending),
            3 => Some(CandidateStage::Trial),
            _ => return None,
        };
        if stage.is_some() && slot == active {
            return None;
        }
        Some(Self {
            sequence: get_u32(buf, rec::SEQUENCE.start),
            active,
            active_image,
            candidate: stage.map(|stage| Candidate {
                slot,
                image: get_image(buf, rec::CANDIDATE_IMAGE),
                stage,
            }),
            boot_attempts: byte(rec::ATTEMPTS)?,
            password,
            min_version,
        })
    }

    /// The newest valid record of two copies, with its copy index.
    pub fn read_bank(copies: [&[u8]; 2]) -> Option<(usize, Self)> {
        let (index, _) = Self::newest(copies)?;
        Some((index, Self::decode(copies.get(index)?)?))
    }

    /// The copy index and sequence number of the newest valid record of
    /// two copies. One decoded record at a time is held (on a
    /// microcontroller two side by side made this the deepest frame of a
    /// state write).
    fn newest(copies: [&[u8]; 2]) -> Option<(usize, u32)> {
        let [a, b] = copies;
        let a = Self::decode(a).map(|s| s.sequence);
        let b = Self::decode(b).map(|s| s.sequence);
        match (a, b) {
            (Some(a), Some(b)) if newer(b, a) => Some((1, b)),
            (Some(a), _) => Some((0, a)),
            (None, Some(b)) => Some((1, b)),
            (None, None) => None,
        }
    }

    /// Which copy to overwrite with `state`, and the record to write there
    /// (sequence one above the newest valid copy), so that a torn write
    /// leaves the newest valid copy intact.
    pub fn bank_write(copies: [&[u8]; 2], state: &Self) -> (usize, [u8; STATE_RECORD_LEN]) {
        let (index, sequence) = match Self::newest(copies) {
            Some((newest, sequence)) => (1 - newest, sequence.wrapping_add(1)),
            None => (0, 1),
        };
        (index, state.encode_as(sequence))
    }
}

/// An in-memory [`ImageStore`] of `N` bytes of image flash (two slots of
/// `N / 2` bytes) plus two boot-state records, for tests and the soft
/// slave.
///
/// Slots behave like NOR flash: erase sets `0xFF`, a write can only clear
/// bits (`old & new`), so writing without erasing corrupts the image. For
/// power-cut tests, [`MemStore::cut_power_after`] lets only a given number
/// of further bytes (erased or written, slots and state alike) reach the
/// memory; after that every erase or write fails with
/// [`StoreError::PowerLost`] until [`MemStore::restore_power`].
///
/// `N` bytes live inline: put large stores in a `static` or on the heap.
#[derive(Debug, Clone)]
pub struct MemStore<const N: usize> {
    flash: [u8; N],
    state: [[u8; STATE_RECORD_LEN]; 2],
    budget: Option<usize>,
    powered: bool,
    bytes_written: usize,
}

impl<const N: usize> Default for MemStore<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> MemStore<N> {
    /// A blank store: slots erased, no boot state.
    pub const fn new() -> Self {
        Self {
            flash: [0xFF; N],
            state: [[0; STATE_RECORD_LEN]; 2],
            budget: None,
            powered: true,
            bytes_written: 0,
        }
    }

    /// Lets only `bytes` more bytes be erased or written, then cuts power.
    pub fn cut_power_after(&mut self, bytes: usize) {
        self.budget = Some(bytes);
    }

    /// Restores power (and removes any pending cut).
    pub fn restore_power(&mut self) {
        self.budget = None;
        self.powered = true;
    }

    /// Power is on.
    pub const fn is_powered(&self) -> bool {
        self.powered
    }

    /// Bytes erased or written so far (to choose cut points in tests).
    pub const fn bytes_written(&self) -> usize {
        self.bytes_written
    }

    /// The raw contents of a slot.
    pub fn slot_bytes(&self, slot: Slot) -> &[u8] {
        let cap = N / 2;
        let start = slot.index() * cap;
        self.flash.get(start..start + cap).unwrap_or(&[])
    }

    /// The two raw boot-state records.
    pub const fn state_copies(&self) -> &[[u8; STATE_RECORD_LEN]; 2] {
        &self.state
    }

    /// Takes one byte of the power budget.
    fn spend(&mut self) -> Result<(), StoreError> {
        if !self.powered {
            return Err(StoreError::PowerLost);
        }
        match self.budget {
            Some(0) => {
                self.powered = false;
                Err(StoreError::PowerLost)
            }
            Some(n) => {
                self.budget = Some(n - 1);
                self.bytes_written += 1;
                Ok(())
            }
            None => {
                self.bytes_written += 1;
                Ok(())
            }
        }
    }

    fn slot_range(
        slot: Slot,
        offset: usize,
        len: usize,
    ) -> Result<core::ops::Range<usize>, StoreError> {
        let cap = N / 2;
        let end = offset.checked_add(len).ok_or(StoreError::OutOfBounds)?;
        if end > cap {
            return Err(StoreError::OutOfBounds);
        }
        let base = slot.index() * cap;
        Ok(base + offset..base + end)
    }
}

impl<const N: usize> ImageStore for MemStore<N> {
    fn slot_capacity(&self) -> usize {
        N / 2
    }

    fn erase(&mut self, slot: Slot) -> Result<(), StoreError> {
        let range = Self::slot_range(slot, 0, N / 2)?;
        for at in range {
            self.spend()?;
            if let Some(b) = self.flash.get_mut(at) {
                *b = 0xFF;
            }
        }
        Ok(())
    }

    fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError> {
        let range = Self::slot_range(slot, offset, data.len())?;
        for (at, &value) in range.zip(data) {
            self.spend()?;
            if let Some(b) = self.flash.get_mut(at) {
                *b &= value;
            }
        }
        Ok(())
    }

    fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError> {
        let cap = N / 2;
        if offset > cap {
            return Err(StoreError::OutOfBounds);
        }
        let n = buf.len().min(cap - offset);
        let range = Self::slot_range(slot, offset, n)?;
        let src = self.flash.get(range).ok_or(StoreError::OutOfBounds)?;
        buf.get_mut(..n)
            .ok_or(StoreError::OutOfBounds)?
            .copy_from_slice(src);
        Ok(n)
    }

    fn read_state(&self) -> Result<BootState, StoreError> {
        let [a, b] = &self.state;
        BootState::read_bank([a, b])
            .map(|(_, s)| s)
            .ok_or(StoreError::NoState)
    }

    fn write_state(&mut self, state: &BootState) -> Result<(), StoreError> {
        let [a, b] = &self.state;
        let (index, record) = BootState::bank_write([a, b], state);
        for (i, &value) in record.iter().enumerate() {
            self.spend()?;
            if let Some(b) = self.state.get_mut(index).and_then(|r| r.get_mut(i)) {
                *b = value;
            }
        }
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

    fn info(version: &str, len: u32) -> ImageInfo {
        ImageInfo {
            len,
            crc: 0x1234_5678 ^ len,
            version: FirmwareVersion::new(version).unwrap(),
        }
    }

    fn sample() -> BootState {
        BootState {
            sequence: 41,
            active: Slot::B,
            active_image: info("1.0.0", 1000),
            candidate: Some(Candidate {
                slot: Slot::A,
                image: info("1.1.0", 2000),
                stage: CandidateStage::Trial,
            }),
            boot_attempts: 2,
            password: Some(0x1234_ABCD),
            min_version: FirmwareVersion::new("0.9").unwrap(),
        }
    }

    #[test]
    fn state_record_round_trips() {
        let s = sample();
        let rec = s.encode();
        assert_eq!(&rec[..4], b"PBS2");
        assert_eq!(rec.len(), 96);
        assert_eq!(&rec[60..68], &[1, 0, 0, 0, 0xCD, 0xAB, 0x34, 0x12]);
        assert_eq!(&rec[68..72], b"0.9\0");
        assert_eq!(BootState::decode(&rec), Some(s));
        let plain = BootState::initial();
        assert_eq!(BootState::decode(&plain.encode()), Some(plain));
        // The password 0 set by the owner is not "no password".
        let zero = BootState {
            password: Some(0),
            ..sample()
        };
        assert_eq!(BootState::decode(&zero.encode()), Some(zero));
    }

    /// A format-1 record (64 bytes, magic "PBST", before passwords) as an
    /// earlier version of this module wrote it: byte for byte.
    fn v1_record(s: &BootState) -> [u8; 64] {
        let mut r = [0u8; 64];
        r[..4].copy_from_slice(b"PBST");
        r[4..8].copy_from_slice(&s.sequence.to_le_bytes());
        r[8] = s.active.index() as u8;
        if let Some(c) = &s.candidate {
            r[9] = c.stage.raw();
            r[10] = c.slot.index() as u8;
            put_image_at(&mut r, 36, &c.image);
        }
        r[11] = s.boot_attempts;
        put_image_at(&mut r, 12, &s.active_image);
        let crc = crc32(&r[..60]);
        r[60..].copy_from_slice(&crc.to_le_bytes());
        r
    }

    fn put_image_at(r: &mut [u8], at: usize, i: &ImageInfo) {
        r[at..at + 4].copy_from_slice(&i.len.to_le_bytes());
        r[at + 4..at + 8].copy_from_slice(&i.crc.to_le_bytes());
        r[at + 8..at + 24].copy_from_slice(i.version.raw());
    }

    #[test]
    fn a_format_1_record_still_decodes_as_one_without_a_password() {
        let old = BootState {
            password: None,
            // a format-1 store's floor: the version that runs
            min_version: sample().active_image.version,
            ..sample()
        };
        let v1 = v1_record(&old);
        assert_eq!(BootState::decode(&v1), Some(old));
        // As a file store reads it: zero padded to the format-2 length.
        let mut padded = [0u8; STATE_RECORD_LEN];
        padded[..64].copy_from_slice(&v1);
        assert_eq!(BootState::decode(&padded), Some(old));
        // The next write goes to the other copy, in format 2, newer.
        let (i, rec) = BootState::bank_write([&padded, &[0; STATE_RECORD_LEN]], &sample());
        assert_eq!(i, 1);
        assert_eq!(&rec[..4], b"PBS2");
        assert_eq!(
            BootState::read_bank([&padded, &rec]).map(|(i, s)| (i, s.password)),
            Some((1, Some(0x1234_ABCD)))
        );
        // A torn format-1 record is as invalid as ever.
        let mut torn = v1;
        torn[30] ^= 4;
        assert_eq!(BootState::decode(&torn), None);
    }

    #[test]
    fn any_flipped_bit_invalidates_the_record() {
        let rec = sample().encode();
        for byte in 0..STATE_RECORD_LEN {
            for bit in 0..8 {
                let mut bad = rec;
                bad[byte] ^= 1 << bit;
                assert_eq!(BootState::decode(&bad), None, "byte {byte} bit {bit}");
            }
        }
        assert_eq!(BootState::decode(&rec[..95]), None);
        assert_eq!(BootState::decode(&[0xFF; 64]), None);
        assert_eq!(BootState::decode(&[0; 64]), None);
    }

    #[test]
    fn record_with_candidate_in_the_active_slot_is_invalid() {
        let mut s = sample();
        s.active = Slot::A;
        assert_eq!(BootState::decode(&s.encode()), None);
    }

    #[test]
    fn newer_valid_copy_wins_and_sequence_wraps() {
        let mut old = sample();
        old.sequence = u32::MAX;
        let mut new = sample();
        new.sequence = 0; // wrapped: newer than u32::MAX
        new.boot_attempts = 0;
        let (o, n) = (old.encode(), new.encode());
        assert_eq!(BootState::read_bank([&o, &n]), Some((1, new)));
        assert_eq!(BootState::read_bank([&n, &o]), Some((0, new)));
        let blank = [0u8; STATE_RECORD_LEN];
        assert_eq!(BootState::read_bank([&o, &blank]), Some((0, old)));
        assert_eq!(BootState::read_bank([&blank, &blank]), None);
    }

    #[test]
    fn bank_write_targets_the_older_copy() {
        let blank = [0u8; STATE_RECORD_LEN];
        let (i, rec) = BootState::bank_write([&blank, &blank], &sample());
        assert_eq!(i, 0);
        assert_eq!(BootState::decode(&rec).unwrap().sequence, 1);
        let (j, rec2) = BootState::bank_write([&rec, &blank], &sample());
        assert_eq!(j, 1);
        assert_eq!(BootState::decode(&rec2).unwrap().sequence, 2);
        let (k, _) = BootState::bank_write([&rec, &rec2], &sample());
        assert_eq!(k, 0);
    }

    #[test]
    fn power_cut_at_every_byte_of_a_state_write_keeps_old_or_new_state() {
        let mut store = MemStore::<64>::new();
        let old = BootState {
            candidate: None,
            ..sample()
        };
        store.write_state(&old).unwrap();
        store.write_state(&old).unwrap(); // both copies valid
        let new = BootState {
            active: Slot::A,
            candidate: None,
            ..sample()
        };
        for cut in 0..=STATE_RECORD_LEN {
            let mut s = store.clone();
            let before = s.read_state().unwrap();
            s.cut_power_after(cut);
            let result = s.write_state(&new);
            s.restore_power();
            let after = s.read_state().unwrap();
            if cut == STATE_RECORD_LEN {
                assert!(result.is_ok());
                assert_eq!(after.active, Slot::A);
                assert_eq!(after.sequence, before.sequence + 1);
            } else {
                assert_eq!(result, Err(StoreError::PowerLost));
                assert_eq!(after, before, "cut after {cut} bytes");
            }
        }
    }

    #[test]
    fn power_cut_during_the_first_state_write_leaves_no_state() {
        for cut in 0..STATE_RECORD_LEN {
            let mut s = MemStore::<64>::new();
            s.cut_power_after(cut);
            assert!(s.write_state(&sample()).is_err());
            s.restore_power();
            assert_eq!(s.read_state(), Err(StoreError::NoState));
        }
    }

    #[test]
    fn mem_store_slots_behave_like_flash() {
        let mut s = MemStore::<16>::new();
        assert_eq!(s.slot_capacity(), 8);
        s.write(Slot::B, 2, &[0x0F, 0xF0]).unwrap();
        s.write(Slot::B, 2, &[0xFF, 0x30]).unwrap();
        assert_eq!(
            s.slot_bytes(Slot::B),
            &[0xFF, 0xFF, 0x0F, 0x30, 0xFF, 0xFF, 0xFF, 0xFF]
        );
        assert_eq!(s.slot_bytes(Slot::A), &[0xFF; 8]);
        s.erase(Slot::B).unwrap();
        assert_eq!(s.slot_bytes(Slot::B), &[0xFF; 8]);
        let mut buf = [0u8; 5];
        assert_eq!(s.read(Slot::B, 6, &mut buf), Ok(2));
        assert_eq!(s.read(Slot::B, 8, &mut buf), Ok(0));
        assert_eq!(s.read(Slot::B, 9, &mut buf), Err(StoreError::OutOfBounds));
        assert_eq!(s.write(Slot::A, 7, &[1, 2]), Err(StoreError::OutOfBounds));
        assert_eq!(
            s.write(Slot::A, usize::MAX, &[1]),
            Err(StoreError::OutOfBounds)
        );
    }

    #[test]
    fn cut_power_stops_all_further_writes() {
        let mut s = MemStore::<16>::new();
        s.cut_power_after(3);
        assert_eq!(s.write(Slot::A, 0, &[0; 5]), Err(StoreError::PowerLost));
        assert_eq!(&s.slot_bytes(Slot::A)[..5], &[0, 0, 0, 0xFF, 0xFF]);
        assert!(!s.is_powered());
        assert_eq!(s.erase(Slot::B), Err(StoreError::PowerLost));
        s.restore_power();
        assert!(s.write(Slot::A, 3, &[0]).is_ok());
    }

    #[test]
    fn store_errors_map_to_foe_codes() {
        assert_eq!(StoreError::OutOfBounds.foe_code(), FoeErrorCode::DiskFull);
        assert_eq!(StoreError::Io.foe_code(), FoeErrorCode::FlashError);
        assert_eq!(
            StoreError::TrialRunning.foe_code(),
            FoeErrorCode::AccessDenied
        );
    }
}
