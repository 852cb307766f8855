//! The `.efw` firmware image: header view and `Repr`, [`pack`], and the
//! incremental [`EfwValidator`] (format table in the [module
//! docs](super#efw-image-format-project-defined-version-1)).

use super::{Crc32, DeviceIdentity, FirmwareVersion, ImageInfo, VERSION_LEN, crc32};
use crate::text::Text;
use crate::wire::foe::FoeErrorCode;

/// Magic bytes, the last one being the format version.
pub const EFW_MAGIC: [u8; 8] = *b"ECATFW\0\x01";

/// Format version carried in the last magic byte.
pub const EFW_FORMAT_VERSION: u8 = 1;

/// Header length of a format-1 header without extension.
pub const EFW_HEADER_LEN: usize = field::FIXED_END + 4;

/// Largest accepted `header_len` (a header with extension bytes).
pub const EFW_MAX_HEADER_LEN: usize = 512;

/// `flags` bit 0: the header extension starts with an Ed25519 signature
/// ([`EFW_SIGNATURE`]) over the image ([`signed_message`]).
pub const EFW_FLAG_SIGNED: u16 = 0x0001;

/// Where the 64-byte Ed25519 signature of a signed image sits: the first
/// extension bytes of the header.
pub const EFW_SIGNATURE: core::ops::Range<usize> = field::FIXED_END..field::FIXED_END + 64;

/// Header length of a signed image without further extension bytes (the
/// smallest `header_len` with [`EFW_FLAG_SIGNED`]).
pub const EFW_SIGNED_HEADER_LEN: usize = EFW_SIGNATURE.end + 4;

type Field = core::ops::Range<usize>;

mod field {
    use super::Field;

    /// `b"ECATFW\0"`, without the version byte.
    pub const MAGIC_PREFIX: Field = 0..7;
    /// Format version (last magic byte).
    pub const FORMAT: usize = 7;
    /// Header length including the header CRC.
    pub const HEADER_LEN: Field = 8..10;
    /// Flags (reserved, 0).
    pub const FLAGS: Field = 10..12;
    /// Vendor ID.
    pub const VENDOR_ID: Field = 12..16;
    /// Product code.
    pub const PRODUCT_CODE: Field = 16..20;
    /// Lowest supported device revision.
    pub const REVISION_MIN: Field = 20..24;
    /// Highest supported device revision.
    pub const REVISION_MAX: Field = 24..28;
    /// Firmware version text, NUL padded.
    pub const VERSION: Field = 28..44;
    /// Payload length.
    pub const PAYLOAD_LEN: Field = 44..48;
    /// Payload CRC-32.
    pub const PAYLOAD_CRC: Field = 48..52;
    /// End of the fixed fields; extension bytes (if any) and the header CRC
    /// follow.
    pub const FIXED_END: usize = PAYLOAD_CRC.end;
}

fn get_u16(buf: &[u8], f: Field) -> u16 {
    buf.get(f)
        .and_then(|b| <[u8; 2]>::try_from(b).ok())
        .map_or(0, u16::from_le_bytes)
}

fn get_u32(buf: &[u8], f: Field) -> u32 {
    buf.get(f)
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map_or(0, u32::from_le_bytes)
}

fn set_bytes(buf: &mut [u8], f: Field, value: &[u8]) {
    if let Some(dst) = buf.get_mut(f).filter(|d| d.len() == value.len()) {
        dst.copy_from_slice(value);
    }
}

/// Why an `.efw` image was refused. Each variant maps to the FoE error code
/// sent to the master ([`EfwError::foe_code`]); the `Display` text goes
/// into the FoE error text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EfwError {
    /// The file does not start with `ECATFW\0`.
    BadMagic,
    /// The format version byte is not [`EFW_FORMAT_VERSION`].
    UnsupportedFormat(u8),
    /// `header_len` is below [`EFW_HEADER_LEN`] or above
    /// [`EFW_MAX_HEADER_LEN`].
    BadHeaderLen(u16),
    /// The header CRC does not match the header bytes.
    HeaderCrc {
        /// CRC stored in the header.
        expected: u32,
        /// CRC computed over the header bytes.
        computed: u32,
    },
    /// The image is for another vendor.
    WrongVendor {
        /// The device's vendor ID.
        expected: u32,
        /// The image's vendor ID.
        found: u32,
    },
    /// The image is for another product.
    WrongProduct {
        /// The device's product code.
        expected: u32,
        /// The image's product code.
        found: u32,
    },
    /// The device revision is outside the image's supported range.
    RevisionOutOfRange {
        /// The device's revision.
        revision: u32,
        /// Lowest revision the image supports.
        min: u32,
        /// Highest revision the image supports.
        max: u32,
    },
    /// The payload does not fit an image slot.
    TooLarge {
        /// Payload length.
        len: usize,
        /// Slot capacity.
        capacity: usize,
    },
    /// The transfer ended before the announced end of the image.
    Truncated {
        /// Image length announced by the header (or the minimum header
        /// length if the header itself is incomplete).
        expected: usize,
        /// Bytes received.
        received: usize,
    },
    /// More bytes arrived than the header announces.
    Oversized {
        /// Image length announced by the header.
        expected: usize,
    },
    /// The payload CRC does not match the header.
    PayloadCrc {
        /// CRC stored in the header.
        expected: u32,
        /// CRC computed over the payload.
        computed: u32,
    },
    /// [`pack`]/emit: the output buffer is too small.
    BufferTooSmall,
    /// The image carries no firmware (payload length 0): installing it
    /// would replace working firmware with nothing.
    EmptyPayload,
    /// The device requires signed images (it has a public key) and the
    /// image carries no signature.
    Unsigned,
    /// The image's Ed25519 signature does not verify with the device's
    /// public key (another key, or the image was changed after signing).
    BadSignature,
    /// The device has a public key but was built without the
    /// `signed-images` feature: no image can be verified, none is accepted.
    SignatureUnsupported,
    /// Anti-rollback: the image's version is older than the device's floor
    /// (or cannot be compared with it), and the owner did not allow a
    /// downgrade.
    Rollback {
        /// The image's version.
        version: FirmwareVersion,
        /// The device's floor.
        floor: FirmwareVersion,
    },
}

/// Longest error text (what the FoE error reply has room for).
pub const ERROR_TEXT_LEN: usize = 96;

impl core::fmt::Display for EfwError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.text().as_str())
    }
}

impl core::error::Error for EfwError {}

/// A length as a 32-bit number of a text (saturated: a slot or an image
/// never holds 4 GiB).
fn n32(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

impl EfwError {
    /// The text of the error, as the FoE error reply carries it and
    /// `Display` prints it (built without `core::fmt`, see [`crate::text`]).
    pub fn text(&self) -> Text<ERROR_TEXT_LEN> {
        let mut t = Text::new();
        match *self {
            Self::BadMagic => t.push_str("not an .efw image (bad magic)"),
            Self::UnsupportedFormat(v) => t
                .push_str("unsupported .efw format version ")
                .push_dec(u32::from(v)),
            Self::BadHeaderLen(n) => t.push_str("bad .efw header length ").push_dec(u32::from(n)),
            Self::HeaderCrc { expected, computed } => t
                .push_str("header CRC ")
                .push_hex(expected, 8, false)
                .push_str(", computed ")
                .push_hex(computed, 8, false),
            Self::WrongVendor { expected, found } => t
                .push_str("image vendor ")
                .push_hex(found, 0, false)
                .push_str(", device vendor ")
                .push_hex(expected, 0, false),
            Self::WrongProduct { expected, found } => t
                .push_str("image product ")
                .push_hex(found, 0, false)
                .push_str(", device product ")
                .push_hex(expected, 0, false),
            Self::RevisionOutOfRange { revision, min, max } => t
                .push_str("device revision ")
                .push_hex(revision, 0, false)
                .push_str(" not in ")
                .push_hex(min, 0, false)
                .push_str("..=")
                .push_hex(max, 0, false),
            Self::TooLarge { len, capacity } => t
                .push_str("payload of ")
                .push_dec(n32(len))
                .push_str(" bytes exceeds slot capacity ")
                .push_dec(n32(capacity)),
            Self::Truncated { expected, received } => t
                .push_str("image truncated: ")
                .push_dec(n32(received))
                .push_str(" of ")
                .push_dec(n32(expected))
                .push_str(" bytes"),
            Self::Oversized { expected } => t
                .push_str("image longer than the ")
                .push_dec(n32(expected))
                .push_str(" bytes announced"),
            Self::PayloadCrc { expected, computed } => t
                .push_str("payload CRC ")
                .push_hex(expected, 8, false)
                .push_str(", computed ")
                .push_hex(computed, 8, false),
            Self::BufferTooSmall => t.push_str("output buffer too small"),
            Self::EmptyPayload => t.push_str("image has an empty payload"),
            Self::Unsigned => {
                t.push_str("image not signed; this device accepts only signed images")
            }
            Self::BadSignature => {
                t.push_str("image signature does not verify with the device's key")
            }
            Self::SignatureUnsupported => {
                t.push_str("this device requires signed images but cannot check signatures")
            }
            Self::Rollback { version, floor } => t
                .push_str("version ")
                .push_ascii(version.as_bytes())
                .push_str(" is older than the minimum ")
                .push_ascii(floor.as_bytes())
                .push_str(": downgrade refused"),
        };
        t
    }

    /// The FoE error code reported for this error (ETG.1000.6 §5.8 and the
    /// SSC extensions, see [`FoeErrorCode`]):
    ///
    /// | error                                            | code                        |
    /// |--------------------------------------------------|-----------------------------|
    /// | bad magic / format / header length / header CRC  | `0x8010` NoFileHeader       |
    /// | wrong vendor / product / revision, empty payload | `0x800D` InvalidFirmware    |
    /// | payload larger than a slot                       | `0x8003` DiskFull           |
    /// | older than the anti-rollback floor               | `0x8002` AccessDenied       |
    /// | unsigned / bad signature / no verifier built in  | `0x800D` InvalidFirmware    |
    /// | truncated / oversized / payload CRC              | `0x800C` InvalidChecksum    |
    /// | buffer too small (tools only)                    | `0x800B` ProgramError       |
    pub const fn foe_code(&self) -> FoeErrorCode {
        match self {
            Self::BadMagic
            | Self::UnsupportedFormat(_)
            | Self::BadHeaderLen(_)
            | Self::HeaderCrc { .. } => FoeErrorCode::NoFileHeader,
            Self::WrongVendor { .. }
            | Self::WrongProduct { .. }
            | Self::RevisionOutOfRange { .. }
            | Self::EmptyPayload
            | Self::Unsigned
            | Self::BadSignature
            | Self::SignatureUnsupported => FoeErrorCode::InvalidFirmware,
            Self::TooLarge { .. } => FoeErrorCode::DiskFull,
            Self::Rollback { .. } => FoeErrorCode::AccessDenied,
            Self::Truncated { .. } | Self::Oversized { .. } | Self::PayloadCrc { .. } => {
                FoeErrorCode::InvalidChecksum
            }
            Self::BufferTooSmall => FoeErrorCode::ProgramError,
        }
    }
}

/// A header whose flags say "signed" must hold the signature.
const fn check_signed_len(flags: u16, header_len: u16) -> Result<(), EfwError> {
    if flags & EFW_FLAG_SIGNED != 0 && (header_len as usize) < EFW_SIGNED_HEADER_LEN {
        return Err(EfwError::BadHeaderLen(header_len));
    }
    Ok(())
}

/// The bytes an image's Ed25519 signature covers, in order: the header
/// before the signature, the header after it up to the header CRC, and the
/// payload, i.e. the whole file except [`EFW_SIGNATURE`] and the header
/// CRC (which is computed after signing). The image must parse (header
/// CRC included), carry [`EFW_FLAG_SIGNED`] and hold its whole payload.
pub fn signed_message(image: &[u8]) -> Result<[&[u8]; 3], EfwError> {
    let h = EfwHeaderRepr::parse(image)?;
    if h.flags & EFW_FLAG_SIGNED == 0 {
        return Err(EfwError::Unsigned);
    }
    let hl = h.buffer_len();
    let truncated = EfwError::Truncated {
        expected: h.image_len(),
        received: image.len(),
    };
    let payload = image.get(hl..h.image_len()).ok_or(truncated)?;
    Ok([
        image.get(..EFW_SIGNATURE.start).ok_or(truncated)?,
        image
            .get(EFW_SIGNATURE.end..hl.saturating_sub(4))
            .ok_or(truncated)?,
        payload,
    ])
}

/// Puts `signature` into a signed image made by [`pack`] (a header with
/// [`EFW_FLAG_SIGNED`]) and recomputes the header CRC.
pub fn set_signature(image: &mut [u8], signature: &[u8; 64]) -> Result<(), EfwError> {
    let h = EfwHeaderRepr::parse(image)?;
    if h.flags & EFW_FLAG_SIGNED == 0 {
        return Err(EfwError::Unsigned);
    }
    let hl = h.buffer_len();
    image
        .get_mut(EFW_SIGNATURE)
        .ok_or(EfwError::BufferTooSmall)?
        .copy_from_slice(signature);
    let crc = image.get(..hl - 4).map_or(0, crc32);
    image
        .get_mut(hl - 4..hl)
        .ok_or(EfwError::BufferTooSmall)?
        .copy_from_slice(&crc.to_le_bytes());
    Ok(())
}

/// The streaming Ed25519 check of a signed image: the verifying state once
/// the signature has arrived. Compared by whether a check runs (the hash
/// state has no useful equality).
#[derive(Clone, Default)]
struct SignatureCheck {
    #[cfg(feature = "signed-images")]
    state: Option<ed25519_compact::VerifyingState>,
}

impl SignatureCheck {
    fn running(&self) -> bool {
        #[cfg(feature = "signed-images")]
        return self.state.is_some();
        #[cfg(not(feature = "signed-images"))]
        false
    }

    /// Starts the check with the signature and the header bytes before it.
    #[cfg(feature = "signed-images")]
    fn start(&mut self, key: &[u8; 32], signature: &[u8; 64], head: &[u8]) -> Result<(), EfwError> {
        let pk = ed25519_compact::PublicKey::new(*key);
        let sig = ed25519_compact::Signature::new(*signature);
        let mut state = pk
            .verify_incremental(&sig)
            .map_err(|_| EfwError::BadSignature)?;
        state.absorb(head);
        self.state = Some(state);
        Ok(())
    }

    fn absorb(&mut self, _bytes: &[u8]) {
        #[cfg(feature = "signed-images")]
        if let Some(state) = self.state.as_mut() {
            state.absorb(_bytes);
        }
    }

    /// The signature verifies over everything absorbed.
    fn verify(&self) -> Result<(), EfwError> {
        #[cfg(feature = "signed-images")]
        return match &self.state {
            Some(state) => state.verify().map_err(|_| EfwError::BadSignature),
            None => Err(EfwError::BadSignature),
        };
        #[cfg(not(feature = "signed-images"))]
        Err(EfwError::SignatureUnsupported)
    }
}

impl PartialEq for SignatureCheck {
    fn eq(&self, other: &Self) -> bool {
        self.running() == other.running()
    }
}

impl Eq for SignatureCheck {}

impl core::fmt::Debug for SignatureCheck {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SignatureCheck")
            .field("running", &self.running())
            .finish()
    }
}

/// A read-only view of an `.efw` header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EfwHeader<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> EfwHeader<T> {
    /// Wraps a buffer (the start of an image) without checking.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer and runs [`EfwHeader::check_len`].
    pub fn new_checked(buffer: T) -> Result<Self, EfwError> {
        let h = Self::new_unchecked(buffer);
        h.check_len()?;
        Ok(h)
    }

    /// Checks that `header_len` is in range and the whole header is in the
    /// buffer ([`EfwError::Truncated`] or [`EfwError::BadHeaderLen`]).
    pub fn check_len(&self) -> Result<(), EfwError> {
        let len = self.buffer.as_ref().len();
        if len < field::FLAGS.start {
            return Err(EfwError::Truncated {
                expected: EFW_HEADER_LEN,
                received: len,
            });
        }
        let hl = self.header_len();
        if !(EFW_HEADER_LEN..=EFW_MAX_HEADER_LEN).contains(&usize::from(hl)) {
            return Err(EfwError::BadHeaderLen(hl));
        }
        if len < usize::from(hl) {
            return Err(EfwError::Truncated {
                expected: usize::from(hl),
                received: len,
            });
        }
        Ok(())
    }

    /// The magic prefix is `ECATFW\0`.
    pub fn magic_ok(&self) -> bool {
        self.buffer.as_ref().get(field::MAGIC_PREFIX) == EFW_MAGIC.get(field::MAGIC_PREFIX)
    }

    /// Format version byte.
    pub fn format_version(&self) -> u8 {
        self.buffer
            .as_ref()
            .get(field::FORMAT)
            .copied()
            .unwrap_or(0)
    }

    /// Header length including the header CRC.
    pub fn header_len(&self) -> u16 {
        get_u16(self.buffer.as_ref(), field::HEADER_LEN)
    }

    /// Flags.
    pub fn flags(&self) -> u16 {
        get_u16(self.buffer.as_ref(), field::FLAGS)
    }

    /// Vendor ID.
    pub fn vendor_id(&self) -> u32 {
        get_u32(self.buffer.as_ref(), field::VENDOR_ID)
    }

    /// Product code.
    pub fn product_code(&self) -> u32 {
        get_u32(self.buffer.as_ref(), field::PRODUCT_CODE)
    }

    /// Lowest supported device revision.
    pub fn revision_min(&self) -> u32 {
        get_u32(self.buffer.as_ref(), field::REVISION_MIN)
    }

    /// Highest supported device revision.
    pub fn revision_max(&self) -> u32 {
        get_u32(self.buffer.as_ref(), field::REVISION_MAX)
    }

    /// Firmware version field.
    pub fn version(&self) -> FirmwareVersion {
        let raw = self
            .buffer
            .as_ref()
            .get(field::VERSION)
            .and_then(|b| <[u8; VERSION_LEN]>::try_from(b).ok())
            .unwrap_or([0; VERSION_LEN]);
        FirmwareVersion::from_raw(raw)
    }

    /// Payload length.
    pub fn payload_len(&self) -> u32 {
        get_u32(self.buffer.as_ref(), field::PAYLOAD_LEN)
    }

    /// Payload CRC-32.
    pub fn payload_crc(&self) -> u32 {
        get_u32(self.buffer.as_ref(), field::PAYLOAD_CRC)
    }

    /// Range of the header CRC field (the last 4 header bytes).
    fn header_crc_field(&self) -> Field {
        let end = usize::from(self.header_len());
        end.saturating_sub(4)..end
    }

    /// Header CRC as stored.
    pub fn header_crc(&self) -> u32 {
        get_u32(self.buffer.as_ref(), self.header_crc_field())
    }

    /// Header CRC computed over the header bytes before the CRC field
    /// (0 if the header is not in the buffer).
    pub fn computed_header_crc(&self) -> u32 {
        let covered = 0..self.header_crc_field().start;
        self.buffer.as_ref().get(covered).map_or(0, crc32)
    }

    /// The payload following the header, if the buffer holds it.
    pub fn payload(&self) -> Option<&[u8]> {
        let start = usize::from(self.header_len());
        let end = start.checked_add(usize::try_from(self.payload_len()).ok()?)?;
        self.buffer.as_ref().get(start..end)
    }
}

/// High-level representation of an `.efw` header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EfwHeaderRepr {
    /// Header length including the CRC ([`EFW_HEADER_LEN`] unless the
    /// header carries extension bytes, written as zeroes).
    pub header_len: u16,
    /// Flags (reserved, 0).
    pub flags: u16,
    /// Vendor ID the image is for.
    pub vendor_id: u32,
    /// Product code the image is for.
    pub product_code: u32,
    /// Lowest supported device revision.
    pub revision_min: u32,
    /// Highest supported device revision.
    pub revision_max: u32,
    /// Firmware version.
    pub version: FirmwareVersion,
    /// Payload length.
    pub payload_len: u32,
    /// Payload CRC-32.
    pub payload_crc: u32,
}

impl EfwHeaderRepr {
    /// Parses and checks a header: length, magic, format version and header
    /// CRC. Device compatibility is checked by [`EfwHeaderRepr::check_device`].
    pub fn parse(bytes: &[u8]) -> Result<Self, EfwError> {
        let h = EfwHeader::new_unchecked(bytes);
        if bytes.len() >= field::MAGIC_PREFIX.end && !h.magic_ok() {
            return Err(EfwError::BadMagic);
        }
        if bytes.len() > field::FORMAT && h.format_version() != EFW_FORMAT_VERSION {
            return Err(EfwError::UnsupportedFormat(h.format_version()));
        }
        h.check_len()?;
        check_signed_len(h.flags(), h.header_len())?;
        let (expected, computed) = (h.header_crc(), h.computed_header_crc());
        if expected != computed {
            return Err(EfwError::HeaderCrc { expected, computed });
        }
        Ok(Self {
            header_len: h.header_len(),
            flags: h.flags(),
            vendor_id: h.vendor_id(),
            product_code: h.product_code(),
            revision_min: h.revision_min(),
            revision_max: h.revision_max(),
            version: h.version(),
            payload_len: h.payload_len(),
            payload_crc: h.payload_crc(),
        })
    }

    /// Checks that the image fits `device` and a slot of `capacity` bytes.
    pub fn check_device(&self, device: &DeviceIdentity, capacity: usize) -> Result<(), EfwError> {
        if self.vendor_id != device.vendor_id {
            return Err(EfwError::WrongVendor {
                expected: device.vendor_id,
                found: self.vendor_id,
            });
        }
        if self.product_code != device.product_code {
            return Err(EfwError::WrongProduct {
                expected: device.product_code,
                found: self.product_code,
            });
        }
        if !(self.revision_min..=self.revision_max).contains(&device.revision) {
            return Err(EfwError::RevisionOutOfRange {
                revision: device.revision,
                min: self.revision_min,
                max: self.revision_max,
            });
        }
        let len = self.payload_len();
        if len == 0 {
            return Err(EfwError::EmptyPayload);
        }
        if len > capacity {
            return Err(EfwError::TooLarge { len, capacity });
        }
        Ok(())
    }

    /// Payload length as `usize` (saturating on 16-bit targets).
    pub fn payload_len(&self) -> usize {
        usize::try_from(self.payload_len).unwrap_or(usize::MAX)
    }

    /// Header plus payload length: the exact file length.
    pub fn image_len(&self) -> usize {
        self.buffer_len().saturating_add(self.payload_len())
    }

    /// Header length.
    pub const fn buffer_len(&self) -> usize {
        self.header_len as usize
    }

    /// What the image is, for the boot state.
    pub const fn image_info(&self) -> ImageInfo {
        ImageInfo {
            len: self.payload_len,
            crc: self.payload_crc,
            version: self.version,
        }
    }

    /// Writes the header (extension bytes zero, CRC computed) and returns
    /// its length. [`EfwError::BadHeaderLen`] if `header_len` is out of
    /// range, [`EfwError::BufferTooSmall`] if `buf` is shorter.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EfwError> {
        let hl = usize::from(self.header_len);
        if !(EFW_HEADER_LEN..=EFW_MAX_HEADER_LEN).contains(&hl) {
            return Err(EfwError::BadHeaderLen(self.header_len));
        }
        let header = buf.get_mut(..hl).ok_or(EfwError::BufferTooSmall)?;
        header.fill(0);
        set_bytes(header, 0..8, &EFW_MAGIC);
        set_bytes(header, field::HEADER_LEN, &self.header_len.to_le_bytes());
        set_bytes(header, field::FLAGS, &self.flags.to_le_bytes());
        set_bytes(header, field::VENDOR_ID, &self.vendor_id.to_le_bytes());
        set_bytes(
            header,
            field::PRODUCT_CODE,
            &self.product_code.to_le_bytes(),
        );
        set_bytes(
            header,
            field::REVISION_MIN,
            &self.revision_min.to_le_bytes(),
        );
        set_bytes(
            header,
            field::REVISION_MAX,
            &self.revision_max.to_le_bytes(),
        );
        set_bytes(header, field::VERSION, self.version.raw());
        set_bytes(header, field::PAYLOAD_LEN, &self.payload_len.to_le_bytes());
        set_bytes(header, field::PAYLOAD_CRC, &self.payload_crc.to_le_bytes());
        let crc_at = hl - 4;
        let crc = header.get(..crc_at).map_or(0, crc32);
        set_bytes(header, crc_at..hl, &crc.to_le_bytes());
        Ok(hl)
    }
}

/// Builds an `.efw` image of `payload` into `out` and returns its length.
/// The `payload_len` and `payload_crc` of `header` are ignored and computed
/// from `payload`. No allocation: the caller provides `out`.
pub fn pack(header: &EfwHeaderRepr, payload: &[u8], out: &mut [u8]) -> Result<usize, EfwError> {
    let payload_len = u32::try_from(payload.len()).map_err(|_| EfwError::TooLarge {
        len: payload.len(),
        capacity: u32::MAX as usize,
    })?;
    let repr = EfwHeaderRepr {
        payload_len,
        payload_crc: crc32(payload),
        ..*header
    };
    let total = repr.image_len();
    if out.len() < total {
        return Err(EfwError::BufferTooSmall);
    }
    let hl = repr.emit(out)?;
    out.get_mut(hl..total)
        .ok_or(EfwError::BufferTooSmall)?
        .copy_from_slice(payload);
    Ok(total)
}

/// An image that passed [`EfwValidator::finish`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ValidatedImage {
    /// Its header.
    pub header: EfwHeaderRepr,
}

impl ValidatedImage {
    /// Payload length, CRC and version, for the boot state.
    pub const fn info(&self) -> ImageInfo {
        self.header.image_info()
    }
}

/// The key a validator checks signatures with; without `signed-images`
/// only whether one was set (every image is then refused), so a firmware
/// without signatures does not hold 96 bytes of key and signature.
#[cfg(feature = "signed-images")]
type Key = Option<[u8; 32]>;
#[cfg(not(feature = "signed-images"))]
type Key = bool;
#[cfg(feature = "signed-images")]
const NO_KEY: Key = None;
#[cfg(not(feature = "signed-images"))]
const NO_KEY: Key = false;

/// Checks an `.efw` image fed in arbitrary chunks (e.g. FoE DATA packets)
/// without buffering it: the header is checked as soon as its last byte
/// arrives (magic and format even earlier), the length and payload CRC at
/// [`EfwValidator::finish`]. The first error is sticky.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EfwValidator {
    device: DeviceIdentity,
    capacity: usize,
    /// Anti-rollback floor ([`FirmwareVersion::EMPTY`]: none).
    floor: FirmwareVersion,
    /// The Ed25519 key images must be signed with (`None`: any image).
    key: Key,
    /// The signature bytes of a signed image.
    #[cfg(feature = "signed-images")]
    signature: [u8; 64],
    /// The running signature check.
    check: SignatureCheck,
    /// Bytes accepted so far.
    received: usize,
    /// The header bytes (only the first `header_len` are used).
    head: [u8; EFW_HEADER_LEN],
    /// CRC over the extension bytes is folded in here for long headers.
    header_crc: Crc32,
    header: Option<EfwHeaderRepr>,
    payload_crc: Crc32,
    error: Option<EfwError>,
}

impl EfwValidator {
    /// A validator for an image to run on `device`, whose payload must fit
    /// `capacity` bytes (the slot size).
    pub const fn new(device: DeviceIdentity, capacity: usize) -> Self {
        Self {
            device,
            capacity,
            floor: FirmwareVersion::EMPTY,
            key: NO_KEY,
            #[cfg(feature = "signed-images")]
            signature: [0; 64],
            check: SignatureCheck {
                #[cfg(feature = "signed-images")]
                state: None,
            },
            received: 0,
            head: [0; EFW_HEADER_LEN],
            header_crc: Crc32::new(),
            header: None,
            payload_crc: Crc32::new(),
            error: None,
        }
    }

    /// Refuses, as soon as the header is complete (before any payload
    /// byte is handed out), an image whose version is older than `floor`
    /// or cannot be compared with it ([`EfwError::Rollback`]);
    /// [`FirmwareVersion::EMPTY`] (the default) checks nothing.
    #[must_use]
    pub const fn with_rollback_floor(mut self, floor: FirmwareVersion) -> Self {
        self.floor = floor;
        self
    }

    /// Requires the image to carry an Ed25519 signature by `key`
    /// ([`EFW_FLAG_SIGNED`], [`signed_message`]): an unsigned image is
    /// refused when its header is complete ([`EfwError::Unsigned`]), a
    /// signature that does not verify at the end ([`EfwError::BadSignature`],
    /// from [`EfwValidator::finish`], before anything is committed).
    /// Without the `signed-images` feature every image is refused
    /// ([`EfwError::SignatureUnsupported`]).
    #[must_use]
    pub const fn with_public_key(mut self, key: [u8; 32]) -> Self {
        self.set_public_key(key);
        self
    }

    /// [`EfwValidator::with_rollback_floor`] on a validator in place (a
    /// firmware builds it where it lives: by value, the builders copy its
    /// few hundred bytes on the stack).
    pub const fn set_rollback_floor(&mut self, floor: FirmwareVersion) {
        self.floor = floor;
    }

    /// [`EfwValidator::with_public_key`] on a validator in place.
    pub const fn set_public_key(&mut self, key: [u8; 32]) {
        #[cfg(feature = "signed-images")]
        {
            self.key = Some(key);
        }
        #[cfg(not(feature = "signed-images"))]
        {
            let _ = key;
            self.key = true;
        }
    }

    /// Whether images must be signed (a key was set).
    const fn keyed(&self) -> bool {
        #[cfg(feature = "signed-images")]
        return self.key.is_some();
        #[cfg(not(feature = "signed-images"))]
        self.key
    }

    /// Bytes accepted so far.
    pub const fn received(&self) -> usize {
        self.received
    }

    /// The header, once complete and valid.
    pub const fn header(&self) -> Option<&EfwHeaderRepr> {
        self.header.as_ref()
    }

    /// The image length the header announces, once known.
    pub fn expected_len(&self) -> Option<usize> {
        self.header.map(|h| h.image_len())
    }

    /// Payload bytes accepted so far (the slot offset of the next payload
    /// byte).
    pub fn payload_received(&self) -> usize {
        self.header
            .map_or(0, |h| self.received.saturating_sub(h.buffer_len()))
    }

    /// Feeds the next `chunk` and returns the payload bytes it contains
    /// (to be written to the slot at the offset [`payload_received`]
    /// had before the call). Errors are sticky; on error nothing of the
    /// chunk counts as received.
    ///
    /// [`payload_received`]: EfwValidator::payload_received
    pub fn feed<'c>(&mut self, chunk: &'c [u8]) -> Result<&'c [u8], EfwError> {
        if let Some(e) = self.error {
            return Err(e);
        }
        let result = self.feed_inner(chunk);
        if let Err(e) = result {
            self.error = Some(e);
        }
        result
    }

    fn feed_inner<'c>(&mut self, chunk: &'c [u8]) -> Result<&'c [u8], EfwError> {
        let mut rest = chunk;
        while self.header.is_none() {
            let Some((&byte, tail)) = rest.split_first() else {
                return Ok(&[]);
            };
            rest = tail;
            self.header_byte(byte)?;
        }
        let header = self.header.ok_or(EfwError::BadMagic)?;
        let expected = header.image_len();
        let room = expected.saturating_sub(self.received);
        if rest.len() > room {
            return Err(EfwError::Oversized { expected });
        }
        self.payload_crc.update(rest);
        self.check.absorb(rest);
        self.received += rest.len();
        Ok(rest)
    }

    /// Takes one header byte at position `self.received`.
    fn header_byte(&mut self, byte: u8) -> Result<(), EfwError> {
        let pos = self.received;
        let header_len = usize::from(get_u16(&self.head, field::HEADER_LEN));
        if let Some(slot) = self.head.get_mut(pos).filter(|_| pos < field::FIXED_END) {
            *slot = byte;
            self.header_crc.update(&[byte]);
        } else if pos < header_len.saturating_sub(4) {
            self.header_crc.update(&[byte]);
            #[cfg(feature = "signed-images")]
            {
                let signed = get_u16(&self.head, field::FLAGS) & EFW_FLAG_SIGNED != 0;
                match self
                    .signature
                    .get_mut(pos.wrapping_sub(EFW_SIGNATURE.start))
                {
                    Some(slot) if signed => *slot = byte,
                    _ => self.check.absorb(&[byte]),
                }
            }
            // Without signature checks the signature bytes are not kept
            // (an image is refused before them when a key is set).
        } else {
            // CRC bytes: stored at the end of the fixed head buffer.
            let at = field::FIXED_END + (pos + 4 - header_len);
            if let Some(slot) = self.head.get_mut(at) {
                *slot = byte;
            }
        }
        self.received = pos + 1;
        let view = EfwHeader::new_unchecked(self.head.as_slice());
        if self.received == field::MAGIC_PREFIX.end && !view.magic_ok() {
            return Err(EfwError::BadMagic);
        }
        if self.received == field::FORMAT + 1 && view.format_version() != EFW_FORMAT_VERSION {
            return Err(EfwError::UnsupportedFormat(view.format_version()));
        }
        if self.received == field::HEADER_LEN.end {
            let hl = view.header_len();
            if !(EFW_HEADER_LEN..=EFW_MAX_HEADER_LEN).contains(&usize::from(hl)) {
                return Err(EfwError::BadHeaderLen(hl));
            }
        }
        if self.received == field::FLAGS.end {
            check_signed_len(view.flags(), view.header_len())?;
            if self.keyed() && view.flags() & EFW_FLAG_SIGNED == 0 {
                return Err(EfwError::Unsigned);
            }
            #[cfg(not(feature = "signed-images"))]
            if self.keyed() {
                return Err(EfwError::SignatureUnsupported);
            }
        }
        #[cfg(feature = "signed-images")]
        if let Some(key) = self
            .key
            .filter(|_| self.received == EFW_SIGNATURE.end && view.flags() & EFW_FLAG_SIGNED != 0)
        {
            let head = self.head.get(..EFW_SIGNATURE.start).unwrap_or(&[]);
            self.check.start(&key, &self.signature, head)?;
        }
        if self.received >= EFW_HEADER_LEN && self.received == header_len {
            let expected = get_u32(&self.head, field::FIXED_END..EFW_HEADER_LEN);
            let computed = self.header_crc.finish();
            if expected != computed {
                return Err(EfwError::HeaderCrc { expected, computed });
            }
            let repr = EfwHeaderRepr {
                header_len: view.header_len(),
                flags: view.flags(),
                vendor_id: view.vendor_id(),
                product_code: view.product_code(),
                revision_min: view.revision_min(),
                revision_max: view.revision_max(),
                version: view.version(),
                payload_len: view.payload_len(),
                payload_crc: view.payload_crc(),
            };
            repr.check_device(&self.device, self.capacity)?;
            if self.floor != FirmwareVersion::EMPTY
                && !matches!(
                    repr.version.compare(&self.floor),
                    Some(core::cmp::Ordering::Greater | core::cmp::Ordering::Equal)
                )
            {
                return Err(EfwError::Rollback {
                    version: repr.version,
                    floor: self.floor,
                });
            }
            self.header = Some(repr);
        }
        Ok(())
    }

    /// Ends the image: it must be exactly `header_len + payload_len` bytes
    /// with a matching payload CRC.
    pub fn finish(&self) -> Result<ValidatedImage, EfwError> {
        if let Some(e) = self.error {
            return Err(e);
        }
        let Some(header) = self.header else {
            let hl = usize::from(get_u16(&self.head, field::HEADER_LEN));
            return Err(EfwError::Truncated {
                expected: if self.received >= field::HEADER_LEN.end {
                    hl
                } else {
                    EFW_HEADER_LEN
                },
                received: self.received,
            });
        };
        let expected = header.image_len();
        if self.received != expected {
            return Err(EfwError::Truncated {
                expected,
                received: self.received,
            });
        }
        let computed = self.payload_crc.finish();
        if computed != header.payload_crc {
            return Err(EfwError::PayloadCrc {
                expected: header.payload_crc,
                computed,
            });
        }
        if self.keyed() {
            self.check.verify()?;
        }
        Ok(ValidatedImage { header })
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

    const DEVICE: DeviceIdentity = DeviceIdentity {
        vendor_id: 0x0000_0ABC,
        product_code: 0x0012_3456,
        revision: 7,
    };

    fn header(version: &str) -> EfwHeaderRepr {
        EfwHeaderRepr {
            header_len: EFW_HEADER_LEN as u16,
            flags: 0,
            vendor_id: DEVICE.vendor_id,
            product_code: DEVICE.product_code,
            revision_min: 1,
            revision_max: 9,
            version: FirmwareVersion::new(version).unwrap(),
            payload_len: 0,
            payload_crc: 0,
        }
    }

    fn image(h: &EfwHeaderRepr, payload: &[u8]) -> Vec<u8> {
        let mut out = vec![0u8; usize::from(h.header_len) + payload.len()];
        let n = pack(h, payload, &mut out).unwrap();
        assert_eq!(n, out.len());
        out
    }

    fn validate(bytes: &[u8], chunk: usize, capacity: usize) -> Result<ValidatedImage, EfwError> {
        let mut v = EfwValidator::new(DEVICE, capacity);
        let mut payload_seen = 0;
        for c in bytes.chunks(chunk) {
            let before = v.payload_received();
            let p = v.feed(c)?;
            assert_eq!(before, payload_seen);
            payload_seen += p.len();
        }
        v.finish()
    }

    /// A hand-assembled v1 header for payload "abc" (version "1.2.3").
    #[test]
    fn packs_byte_exact_header() {
        let img = image(&header("1.2.3"), b"abc");
        let mut expected = Vec::new();
        expected.extend_from_slice(b"ECATFW\0\x01");
        expected.extend_from_slice(&56u16.to_le_bytes());
        expected.extend_from_slice(&0u16.to_le_bytes());
        expected.extend_from_slice(&0x0ABCu32.to_le_bytes());
        expected.extend_from_slice(&0x0012_3456u32.to_le_bytes());
        expected.extend_from_slice(&1u32.to_le_bytes());
        expected.extend_from_slice(&9u32.to_le_bytes());
        expected.extend_from_slice(b"1.2.3\0\0\0\0\0\0\0\0\0\0\0");
        expected.extend_from_slice(&3u32.to_le_bytes());
        expected.extend_from_slice(&0x3524_41C2u32.to_le_bytes()); // crc32("abc")
        let hcrc = crc32(&expected);
        expected.extend_from_slice(&hcrc.to_le_bytes());
        expected.extend_from_slice(b"abc");
        assert_eq!(img, expected);
        let h = EfwHeader::new_checked(&img[..]).unwrap();
        assert!(h.magic_ok());
        assert_eq!(h.version().as_str(), "1.2.3");
        assert_eq!(h.payload(), Some(&b"abc"[..]));
        assert_eq!(h.header_crc(), hcrc);
    }

    #[test]
    fn header_repr_round_trips() {
        let h = EfwHeaderRepr {
            payload_len: 3,
            payload_crc: crc32(b"abc"),
            ..header("9.9")
        };
        let img = image(&h, b"abc");
        assert_eq!(EfwHeaderRepr::parse(&img).unwrap(), h);
    }

    #[test]
    fn valid_image_passes_in_any_chunking() {
        let payload: Vec<u8> = (0..5000u32).map(|i| (i * 31) as u8).collect();
        let img = image(&header("1.2.3"), &payload);
        for chunk in [1, 7, 55, 56, 57, 1018, img.len()] {
            let ok = validate(&img, chunk, 8192).unwrap();
            assert_eq!(ok.header.payload_len, 5000);
            assert_eq!(ok.info().version.as_str(), "1.2.3");
        }
    }

    #[test]
    fn feed_returns_exactly_the_payload_bytes() {
        let img = image(&header("1"), b"0123456789");
        let mut v = EfwValidator::new(DEVICE, 100);
        assert_eq!(v.feed(&img[..50]).unwrap(), b"");
        assert!(v.header().is_none());
        assert_eq!(v.feed(&img[50..60]).unwrap(), b"0123");
        assert_eq!(v.header().unwrap().version.as_str(), "1");
        assert_eq!(v.payload_received(), 4);
        assert_eq!(v.feed(&img[60..]).unwrap(), b"456789");
        assert_eq!(v.expected_len(), Some(66));
        assert!(v.finish().is_ok());
    }

    #[test]
    fn long_header_with_extension_is_accepted() {
        let h = EfwHeaderRepr {
            header_len: 100,
            ..header("2.0")
        };
        let img = image(&h, b"xyz");
        assert_eq!(img.len(), 103);
        assert_eq!(&img[52..96], &[0u8; 44][..]);
        assert_eq!(validate(&img, 3, 10).unwrap().header.header_len, 100);
        assert_eq!(EfwHeaderRepr::parse(&img).unwrap().header_len, 100);
    }

    #[test]
    fn bad_magic_is_detected_after_seven_bytes() {
        let mut img = image(&header("1"), b"x");
        img[0] = b'X';
        let mut v = EfwValidator::new(DEVICE, 10);
        assert_eq!(v.feed(&img[..7]), Err(EfwError::BadMagic));
        assert_eq!(v.feed(&img[7..]), Err(EfwError::BadMagic), "sticky");
        assert_eq!(v.finish(), Err(EfwError::BadMagic));
        assert_eq!(EfwHeaderRepr::parse(&img), Err(EfwError::BadMagic));
    }

    #[test]
    fn unknown_format_version_is_refused() {
        let mut img = image(&header("1"), b"x");
        img[7] = 2;
        assert_eq!(validate(&img, 8, 10), Err(EfwError::UnsupportedFormat(2)));
    }

    #[test]
    fn impossible_header_len_is_refused() {
        for bad in [0u16, 55, 513, 0xFFFF] {
            let mut img = image(&header("1"), b"x");
            img[8..10].copy_from_slice(&bad.to_le_bytes());
            assert_eq!(validate(&img, 64, 10), Err(EfwError::BadHeaderLen(bad)));
            assert_eq!(EfwHeaderRepr::parse(&img), Err(EfwError::BadHeaderLen(bad)));
        }
    }

    #[test]
    fn corrupted_header_fails_header_crc() {
        let mut img = image(&header("1"), b"x");
        img[30] ^= 1;
        assert!(matches!(
            validate(&img, 1018, 10),
            Err(EfwError::HeaderCrc { .. })
        ));
        assert!(matches!(
            EfwHeaderRepr::parse(&img),
            Err(EfwError::HeaderCrc { .. })
        ));
    }

    #[test]
    fn wrong_product_vendor_and_revision_are_refused() {
        let wrong_product = EfwHeaderRepr {
            product_code: 0x1234,
            ..header("1")
        };
        assert_eq!(
            validate(&image(&wrong_product, b"x"), 1018, 10),
            Err(EfwError::WrongProduct {
                expected: DEVICE.product_code,
                found: 0x1234
            })
        );
        let wrong_vendor = EfwHeaderRepr {
            vendor_id: 2,
            ..header("1")
        };
        assert!(matches!(
            validate(&image(&wrong_vendor, b"x"), 1018, 10),
            Err(EfwError::WrongVendor { found: 2, .. })
        ));
        let too_new = EfwHeaderRepr {
            revision_min: 8,
            revision_max: 8,
            ..header("1")
        };
        assert_eq!(
            validate(&image(&too_new, b"x"), 1018, 10),
            Err(EfwError::RevisionOutOfRange {
                revision: 7,
                min: 8,
                max: 8
            })
        );
    }

    #[test]
    fn empty_payload_is_refused_with_invalid_firmware() {
        let img = image(&header("1"), b"");
        let mut v = EfwValidator::new(DEVICE, 10);
        assert_eq!(v.feed(&img), Err(EfwError::EmptyPayload));
        assert_eq!(
            EfwError::EmptyPayload.foe_code(),
            FoeErrorCode::InvalidFirmware
        );
    }

    #[test]
    fn payload_larger_than_the_slot_is_refused_at_the_header() {
        let img = image(&header("1"), &[0u8; 11]);
        let mut v = EfwValidator::new(DEVICE, 10);
        assert_eq!(
            v.feed(&img[..EFW_HEADER_LEN]),
            Err(EfwError::TooLarge {
                len: 11,
                capacity: 10
            })
        );
        assert!(validate(&img, 1018, 11).is_ok());
    }

    #[test]
    fn truncated_image_is_refused() {
        let img = image(&header("1"), &[7u8; 100]);
        assert_eq!(
            validate(&img[..120], 1018, 1000),
            Err(EfwError::Truncated {
                expected: 156,
                received: 120
            })
        );
        assert_eq!(
            validate(&img[..20], 1018, 1000),
            Err(EfwError::Truncated {
                expected: 56,
                received: 20
            })
        );
        assert_eq!(
            validate(&[], 1, 1000),
            Err(EfwError::Truncated {
                expected: 56,
                received: 0
            })
        );
    }

    #[test]
    fn oversized_image_is_refused_when_the_extra_byte_arrives() {
        let mut img = image(&header("1"), &[7u8; 100]);
        img.push(0);
        let mut v = EfwValidator::new(DEVICE, 1000);
        v.feed(&img[..156]).unwrap();
        assert_eq!(
            v.feed(&img[156..]),
            Err(EfwError::Oversized { expected: 156 })
        );
        assert_eq!(v.finish(), Err(EfwError::Oversized { expected: 156 }));
    }

    #[test]
    fn corrupted_payload_fails_payload_crc() {
        let mut img = image(&header("1"), &[7u8; 100]);
        img[100] ^= 0x80;
        assert!(matches!(
            validate(&img, 64, 1000),
            Err(EfwError::PayloadCrc { .. })
        ));
    }

    #[test]
    fn every_error_has_its_text_with_its_numbers_in_place() {
        let v = |s: &str| FirmwareVersion::new(s).unwrap();
        let cases = [
            (EfwError::BadMagic, "not an .efw image (bad magic)"),
            (
                EfwError::UnsupportedFormat(9),
                "unsupported .efw format version 9",
            ),
            (EfwError::BadHeaderLen(17), "bad .efw header length 17"),
            (
                EfwError::HeaderCrc {
                    expected: 0x12,
                    computed: 0xDEAD_BEEF,
                },
                "header CRC 0x00000012, computed 0xdeadbeef",
            ),
            (
                EfwError::WrongVendor {
                    expected: 0x2,
                    found: 0x1,
                },
                "image vendor 0x1, device vendor 0x2",
            ),
            (
                EfwError::WrongProduct {
                    expected: 0x20,
                    found: 0x10,
                },
                "image product 0x10, device product 0x20",
            ),
            (
                EfwError::RevisionOutOfRange {
                    revision: 0x5,
                    min: 0x1,
                    max: 0x3,
                },
                "device revision 0x5 not in 0x1..=0x3",
            ),
            (
                EfwError::TooLarge {
                    len: 5000,
                    capacity: 4096,
                },
                "payload of 5000 bytes exceeds slot capacity 4096",
            ),
            (
                EfwError::Truncated {
                    expected: 10,
                    received: 3,
                },
                "image truncated: 3 of 10 bytes",
            ),
            (
                EfwError::Oversized { expected: 12 },
                "image longer than the 12 bytes announced",
            ),
            (
                EfwError::PayloadCrc {
                    expected: 0xA,
                    computed: 0xB,
                },
                "payload CRC 0x0000000a, computed 0x0000000b",
            ),
            (EfwError::BufferTooSmall, "output buffer too small"),
            (EfwError::EmptyPayload, "image has an empty payload"),
            (
                EfwError::Unsigned,
                "image not signed; this device accepts only signed images",
            ),
            (
                EfwError::BadSignature,
                "image signature does not verify with the device's key",
            ),
            (
                EfwError::SignatureUnsupported,
                "this device requires signed images but cannot check signatures",
            ),
            (
                EfwError::Rollback {
                    version: v("0.9"),
                    floor: v("1.0"),
                },
                "version 0.9 is older than the minimum 1.0: downgrade refused",
            ),
        ];
        for (e, text) in cases {
            assert_eq!(e.text().as_str(), text, "{e:?}");
        }
    }

    #[test]
    fn error_texts_print_their_numbers_in_decimal_and_hex() {
        let cases = [
            (
                EfwError::UnsupportedFormat(2),
                "unsupported .efw format version 2",
            ),
            (
                EfwError::BadHeaderLen(65535),
                "bad .efw header length 65535",
            ),
            (
                EfwError::HeaderCrc {
                    expected: 0xCBF4_3926,
                    computed: 0x0000_00FF,
                },
                "header CRC 0xcbf43926, computed 0x000000ff",
            ),
            (
                EfwError::WrongVendor {
                    expected: 0xABC,
                    found: 0xFFFF_FFFF,
                },
                "image vendor 0xffffffff, device vendor 0xabc",
            ),
            (
                EfwError::TooLarge {
                    len: 4_294_967_295,
                    capacity: 0,
                },
                "payload of 4294967295 bytes exceeds slot capacity 0",
            ),
            (
                EfwError::Truncated {
                    expected: 100,
                    received: 9,
                },
                "image truncated: 9 of 100 bytes",
            ),
        ];
        for (e, text) in cases {
            assert_eq!(e.text().as_str(), text);
        }
        // A length past 32 bits (a 64-bit host only) prints saturated.
        if let Ok(huge) = usize::try_from(u64::from(u32::MAX) + 1) {
            let e = EfwError::Oversized { expected: huge };
            assert_eq!(
                e.text().as_str(),
                "image longer than the 4294967295 bytes announced"
            );
        }
    }

    #[test]
    fn an_image_below_the_rollback_floor_is_refused_at_its_header() {
        let v = |s: &str| FirmwareVersion::new(s).unwrap();
        let old = image(&header("1.9"), &[7u8; 100]);
        let mut val = EfwValidator::new(DEVICE, 1000).with_rollback_floor(v("1.10"));
        assert_eq!(val.feed(&old[..EFW_HEADER_LEN - 1]), Ok(&[][..]));
        let refused = EfwError::Rollback {
            version: v("1.9"),
            floor: v("1.10"),
        };
        assert_eq!(val.feed(&old[EFW_HEADER_LEN - 1..]), Err(refused));
        assert_eq!(val.payload_received(), 0, "no payload byte handed out");
        assert_eq!(val.finish(), Err(refused));
        assert_eq!(
            refused.to_string(),
            "version 1.9 is older than the minimum 1.10: downgrade refused"
        );
        assert_eq!(refused.foe_code(), FoeErrorCode::AccessDenied);
        // the same version and newer ones pass; no floor checks nothing
        for ok in ["1.10", "1.10.0", "2"] {
            let img = image(&header(ok), &[7u8; 100]);
            let mut val = EfwValidator::new(DEVICE, 1000).with_rollback_floor(v("1.10"));
            val.feed(&img).unwrap();
            assert!(val.finish().is_ok(), "{ok}");
        }
        let mut val = EfwValidator::new(DEVICE, 1000);
        val.feed(&old).unwrap();
        assert!(val.finish().is_ok());
        // a version without numbers cannot be shown to be newer
        let beta = image(&header("beta"), &[7u8; 100]);
        let mut val = EfwValidator::new(DEVICE, 1000).with_rollback_floor(v("1"));
        assert!(matches!(val.feed(&beta), Err(EfwError::Rollback { .. })));
    }

    #[test]
    fn a_signed_flag_without_room_for_the_signature_is_a_bad_header() {
        let h = EfwHeaderRepr {
            flags: EFW_FLAG_SIGNED,
            ..header("1")
        };
        let img = image(&h, b"x");
        assert_eq!(EfwHeaderRepr::parse(&img), Err(EfwError::BadHeaderLen(56)));
        assert_eq!(validate(&img, 7, 10), Err(EfwError::BadHeaderLen(56)));
    }

    #[cfg(not(feature = "signed-images"))]
    #[test]
    fn a_device_with_a_key_but_no_verifier_accepts_no_image() {
        let img = image(&header("1"), b"x");
        let mut v = EfwValidator::new(DEVICE, 10).with_public_key([7; 32]);
        assert_eq!(v.feed(&img), Err(EfwError::Unsigned));
        let signed = EfwHeaderRepr {
            flags: EFW_FLAG_SIGNED,
            header_len: EFW_SIGNED_HEADER_LEN as u16,
            ..header("1")
        };
        let img = image(&signed, b"x");
        let mut v = EfwValidator::new(DEVICE, 10).with_public_key([7; 32]);
        assert_eq!(v.feed(&img), Err(EfwError::SignatureUnsupported));
        assert_eq!(v.payload_received(), 0);
    }

    #[test]
    fn errors_map_to_foe_codes() {
        assert_eq!(EfwError::BadMagic.foe_code(), FoeErrorCode::NoFileHeader);
        assert_eq!(
            EfwError::WrongProduct {
                expected: 1,
                found: 2
            }
            .foe_code(),
            FoeErrorCode::InvalidFirmware
        );
        assert_eq!(
            EfwError::TooLarge {
                len: 2,
                capacity: 1
            }
            .foe_code(),
            FoeErrorCode::DiskFull
        );
        assert_eq!(
            EfwError::PayloadCrc {
                expected: 1,
                computed: 2
            }
            .foe_code(),
            FoeErrorCode::InvalidChecksum
        );
    }

    #[test]
    fn pack_into_short_buffer_fails() {
        let mut out = [0u8; 58];
        assert_eq!(
            pack(&header("1"), b"abc", &mut out),
            Err(EfwError::BufferTooSmall)
        );
        let bad = EfwHeaderRepr {
            header_len: 10,
            ..header("1")
        };
        let mut out = [0u8; 100];
        assert_eq!(
            pack(&bad, b"abc", &mut out),
            Err(EfwError::BadHeaderLen(10))
        );
    }

    #[test]
    fn short_buffers_never_panic_the_view() {
        for len in 0..EFW_HEADER_LEN {
            let img = image(&header("1"), b"abc");
            let h = EfwHeader::new_unchecked(&img[..len]);
            let _ = (
                h.header_crc(),
                h.computed_header_crc(),
                h.payload(),
                h.version(),
            );
            assert!(EfwHeaderRepr::parse(&img[..len]).is_err());
        }
    }

    /// Signed images (`signed-images`): keys from fixed seeds, so the
    /// signatures (deterministic Ed25519) are the same in every run.
    #[cfg(feature = "signed-images")]
    mod signed {
        use super::*;
        use ed25519_compact::{KeyPair, Seed};

        fn keys(n: u8) -> KeyPair {
            KeyPair::from_seed(Seed::new([n; 32]))
        }

        fn signed_header(version: &str) -> EfwHeaderRepr {
            EfwHeaderRepr {
                flags: EFW_FLAG_SIGNED,
                header_len: EFW_SIGNED_HEADER_LEN as u16,
                ..header(version)
            }
        }

        /// Packs and signs as `master-test firmware pack --sign` does.
        fn signed(kp: &KeyPair, h: &EfwHeaderRepr, payload: &[u8]) -> Vec<u8> {
            let mut img = image(h, payload);
            let msg = signed_message(&img).unwrap().concat();
            let sig = kp.sk.sign(&msg, None);
            set_signature(&mut img, &sig).unwrap();
            img
        }

        fn check(img: &[u8], key: [u8; 32], chunk: usize) -> Result<ValidatedImage, EfwError> {
            let mut v = EfwValidator::new(DEVICE, 10_000).with_public_key(key);
            for c in img.chunks(chunk) {
                v.feed(c)?;
            }
            v.finish()
        }

        #[test]
        fn a_signed_image_is_laid_out_byte_for_byte() {
            let kp = keys(1);
            let img = signed(&kp, &signed_header("1.2.3"), b"abc");
            assert_eq!(img.len(), 120 + 3);
            assert_eq!(&img[..8], b"ECATFW\0\x01", "still format 1");
            assert_eq!(&img[8..10], &120u16.to_le_bytes());
            assert_eq!(&img[10..12], &1u16.to_le_bytes(), "flags: SIGNED");
            let mut msg = img[..52].to_vec();
            msg.extend_from_slice(b"abc");
            let sig = kp.sk.sign(&msg, None);
            assert_eq!(&img[52..116], &sig[..], "signature over 0..52 + payload");
            assert_eq!(&img[116..120], &crc32(&img[..116]).to_le_bytes());
            assert_eq!(&img[120..], b"abc");
            assert!(kp.pk.verify(&msg, &sig).is_ok());
        }

        #[test]
        fn a_signed_image_passes_in_any_chunking_with_the_right_key() {
            let kp = keys(1);
            let payload: Vec<u8> = (0..5000u32).map(|i| (i * 31) as u8).collect();
            let img = signed(&kp, &signed_header("2.0"), &payload);
            for chunk in [1, 7, 52, 64, 116, 117, 1018, img.len()] {
                let ok = check(&img, *kp.pk, chunk).unwrap();
                assert_eq!(ok.header.payload_len, 5000, "chunk {chunk}");
            }
            // a longer header: extension bytes after the signature are signed too
            let long = EfwHeaderRepr {
                header_len: 200,
                ..signed_header("2.0")
            };
            let img = signed(&kp, &long, &payload);
            assert!(check(&img, *kp.pk, 33).is_ok());
            // a device without a key ignores the signature (as format 1 did)
            assert!(validate(&img, 100, 10_000).is_ok());
        }

        #[test]
        fn an_unsigned_image_is_refused_at_its_header() {
            let img = image(&header("2.0"), &[1; 500]);
            let mut v = EfwValidator::new(DEVICE, 10_000).with_public_key(*keys(1).pk);
            assert_eq!(v.feed(&img[..11]), Ok(&[][..]));
            assert_eq!(v.feed(&img[11..12]), Err(EfwError::Unsigned));
            assert_eq!(v.payload_received(), 0);
            assert_eq!(EfwError::Unsigned.foe_code(), FoeErrorCode::InvalidFirmware);
        }

        #[test]
        fn a_changed_or_foreign_signed_image_fails_its_signature_at_the_end() {
            let kp = keys(1);
            let img = signed(&kp, &signed_header("2.0"), &[1; 500]);
            // another key
            assert_eq!(check(&img, *keys(2).pk, 64), Err(EfwError::BadSignature));
            // another payload (CRCs made to match) under the same signature
            let mut other = image(&signed_header("2.0"), &[2; 500]);
            let sig: [u8; 64] = img[52..116].try_into().unwrap();
            set_signature(&mut other, &sig).unwrap();
            assert!(EfwHeaderRepr::parse(&other).is_ok(), "CRCs are right");
            assert_eq!(check(&other, *kp.pk, 100), Err(EfwError::BadSignature));
            // the version raised in the header, header CRC fixed
            let mut raised = img.clone();
            raised[28] = b'9';
            let crc = crc32(&raised[..116]);
            raised[116..120].copy_from_slice(&crc.to_le_bytes());
            assert_eq!(check(&raised, *kp.pk, 1018), Err(EfwError::BadSignature));
            // a signature that is no Ed25519 signature at all: at its last byte
            let mut junk = img.clone();
            set_signature(&mut junk, &[0xFF; 64]).unwrap();
            let mut v = EfwValidator::new(DEVICE, 10_000).with_public_key(*kp.pk);
            assert_eq!(v.feed(&junk[..116]), Err(EfwError::BadSignature));
            assert_eq!(v.payload_received(), 0);
        }
    }
}
