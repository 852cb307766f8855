//! Firmware update: the `.efw` image format, its incremental validator, the
//! A/B image store and the bootloader decisions (application layer, used by
//! the FoE server in BOOT, ETG.1000.6 §5.8).
//!
//! This module holds no wire formats of the EtherCAT protocol and never
//! touches the ESC; flash access goes through the [`ImageStore`] HAL trait,
//! so the same logic runs on the device, in the soft slave ([`MemStore`],
//! or `ecat_sim::file_store::FileStore` on a host) and in tests. Nothing
//! here allocates or panics on input.
//!
//! # Update flow (as a device manual describes it to its users)
//!
//! 1. The master switches the slave to BOOT and downloads the `.efw` file by
//!    FoE (password `00000000`). [`begin_download`] picks the inactive slot
//!    and erases it, [`write_chunk`] stores the payload as it arrives while
//!    an [`EfwValidator`] checks the header (as soon as it is complete) and
//!    the payload CRC; [`finish_download`] records the slot as
//!    *downloaded*.
//! 2. The master switches to INIT: [`commit_pending`] marks the image
//!    *pending* (the real device's bootloader copies it at this point).
//! 3. After a power cycle the bootloader ([`power_on`]) verifies the
//!    pending image against its CRC and boots it on trial, counting boot
//!    attempts; the new firmware calls [`confirm_boot`] once it runs, or
//!    [`reject_boot`] if its start check fails. An image that fails
//!    verification, or is not confirmed within [`MAX_BOOT_ATTEMPTS`]
//!    boots, is rolled back to the previous slot. Boot records that
//!    cannot be read start no image at all: the device stays in the
//!    bootloader (AL status 0x0014 "no valid firmware").
//!
//! The boot state lives in two copies with sequence numbers and CRCs
//! ([`BootState`]); a power cut at any moment leaves either the old or the
//! new record valid, and the active slot is never written during a
//! download, so an interrupted download always boots the old firmware.
//!
//! # `.efw` image format (project defined, version 1)
//!
//! A header followed by the payload (the executable image written to the
//! slot, starting at slot offset 0). All integers little-endian.
//!
//! | offset | size | field           | meaning                                                   |
//! |-------:|-----:|-----------------|-----------------------------------------------------------|
//! | 0      | 8    | `magic`         | `b"ECATFW\0"` + format version byte `0x01`                 |
//! | 8      | 2    | `header_len`    | header length incl. `header_crc32`; 56 for v1, ≤ 512       |
//! | 10     | 2    | `flags`         | bit 0 `SIGNED` (below); other bits reserved, written 0, ignored |
//! | 12     | 4    | `vendor_id`     | must equal the device's vendor ID (0x1018:01)             |
//! | 16     | 4    | `product_code`  | must equal the device's product code (0x1018:02)          |
//! | 20     | 4    | `revision_min`  | lowest device revision (0x1018:03) the image supports     |
//! | 24     | 4    | `revision_max`  | highest device revision the image supports                |
//! | 28     | 16   | `version`       | firmware version, ASCII, NUL padded (e.g. `"1.2.3"`)       |
//! | 44     | 4    | `payload_len`   | payload length in bytes, ≤ slot capacity                  |
//! | 48     | 4    | `payload_crc32` | CRC-32 of the payload                                     |
//! | 52     | …    | (extension)     | only if `header_len` > 56: ignored, covered by the CRC     |
//! | hl − 4 | 4    | `header_crc32`  | CRC-32 of header bytes `0 .. header_len − 4`               |
//! | hl     | pl   | payload         | `payload_len` bytes; the file ends exactly here           |
//!
//! **Signed images** (header revision with [`EFW_FLAG_SIGNED`], still
//! format 1): `flags` bit 0 set, `header_len` ≥ 120, and the first 64
//! extension bytes (offset 52..116, [`EFW_SIGNATURE`]) hold an Ed25519
//! signature (RFC 8032, pure Ed25519) over the whole file except the
//! signature field and the header CRC: bytes `0..52`, then `116 .. hl − 4`,
//! then the payload ([`signed_message`]). The header CRC covers the
//! signature and is computed after it ([`set_signature`]). The format
//! version stays 1 because a format-1 parser already skips extension bytes
//! and ignores flags: an older slave installs a signed image as before, a
//! slave without a key ignores the signature, a slave whose description
//! has a public key ([`FoeSecurity::public_key`](crate::device::FoeSecurity))
//! and the `signed-images` feature refuses unsigned images at their
//! header and badly signed ones before anything is committed (FoE error
//! `0x800D`). Unsigned images are byte for byte what they were.
//!
//! CRC-32 is CRC-32/ISO-HDLC (the zlib/Ethernet `crc32`: polynomial
//! `0x04C11DB7` reflected, init and xor-out `0xFFFFFFFF`), see [`crc32`].

mod boot;
mod efw;
mod store;

pub use boot::{
    BootDecision, BootOutcome, MAX_BOOT_ATTEMPTS, RollbackReason, begin_download, cancel_download,
    commit_pending, confirm_boot, finish_download, foe_password, power_on, provision, reject_boot,
    rollback_floor, set_password, verify_slot, write_chunk,
};
pub use efw::{
    EFW_FLAG_SIGNED, EFW_FORMAT_VERSION, EFW_HEADER_LEN, EFW_MAGIC, EFW_MAX_HEADER_LEN,
    EFW_SIGNATURE, EFW_SIGNED_HEADER_LEN, EfwError, EfwHeader, EfwHeaderRepr, EfwValidator,
    ValidatedImage, pack, set_signature, signed_message,
};
pub use store::{
    BootState, Candidate, CandidateStage, ImageInfo, ImageStore, MemStore, STATE_RECORD_LEN,
    STATE_RECORD_V1_LEN, Slot, StoreError,
};

/// Identity of the running device, which an image must match (object
/// 0x1018 "Identity": vendor ID, product code, revision number).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct DeviceIdentity {
    /// Vendor ID (0x1018:01).
    pub vendor_id: u32,
    /// Product code (0x1018:02).
    pub product_code: u32,
    /// Revision number (0x1018:03).
    pub revision: u32,
}

/// Length of a [`FirmwareVersion`] field.
pub const VERSION_LEN: usize = 16;

/// A firmware version: up to 16 ASCII bytes, NUL padded (the `.efw`
/// `version` field and the boot state's image records).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FirmwareVersion([u8; VERSION_LEN]);

impl FirmwareVersion {
    /// The empty version ("unknown").
    pub const EMPTY: Self = Self([0; VERSION_LEN]);

    /// A version from text: `None` if longer than 16 bytes, not printable
    /// ASCII, or containing NUL.
    pub fn new(text: &str) -> Option<Self> {
        let bytes = text.as_bytes();
        if bytes.len() > VERSION_LEN || !bytes.iter().all(|b| b.is_ascii_graphic() || *b == b' ') {
            return None;
        }
        let mut raw = [0u8; VERSION_LEN];
        raw.get_mut(..bytes.len())?.copy_from_slice(bytes);
        Some(Self(raw))
    }

    /// The version exactly as stored (possibly from an untrusted file).
    pub const fn from_raw(raw: [u8; VERSION_LEN]) -> Self {
        Self(raw)
    }

    /// The 16 stored bytes.
    pub const fn raw(&self) -> &[u8; VERSION_LEN] {
        &self.0
    }

    /// The bytes before the first NUL.
    pub fn as_bytes(&self) -> &[u8] {
        let end = self.0.iter().position(|&b| b == 0).unwrap_or(VERSION_LEN);
        self.0.get(..end).unwrap_or(&[])
    }

    /// Compares two versions by their numbers ([`compare_versions`]):
    /// `None` when either has no digit (e.g. [`FirmwareVersion::EMPTY`]).
    pub fn compare(&self, other: &Self) -> Option<core::cmp::Ordering> {
        compare_versions(self.as_bytes(), other.as_bytes())
    }

    /// The version as text; `"?"` if the stored bytes are not UTF-8.
    pub fn as_str(&self) -> &str {
        core::str::from_utf8(self.as_bytes()).unwrap_or("?")
    }
}

impl core::fmt::Display for FirmwareVersion {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Compares version texts by their numbers: the runs of ASCII digits, in
/// order, missing ones counting as 0 (`1.10` > `1.9`, `1.0` = `1.0.0`,
/// `v2` > `1.9.9`, `2.0-rc1` = `2.0.1`); everything else separates.
/// `None` when either text has no digit. Numbers beyond `u64` saturate.
pub fn compare_versions(a: &[u8], b: &[u8]) -> Option<core::cmp::Ordering> {
    fn numbers(s: &[u8]) -> impl Iterator<Item = u64> + '_ {
        s.split(|c| !c.is_ascii_digit())
            .filter(|p| !p.is_empty())
            .map(|p| {
                p.iter().fold(0u64, |n, d| {
                    n.saturating_mul(10).saturating_add(u64::from(d - b'0'))
                })
            })
    }
    if numbers(a).next().is_none() || numbers(b).next().is_none() {
        return None;
    }
    let (mut x, mut y) = (numbers(a), numbers(b));
    loop {
        match (x.next(), y.next()) {
            (None, None) => return Some(core::cmp::Ordering::Equal),
            (p, q) => match p.unwrap_or(0).cmp(&q.unwrap_or(0)) {
                core::cmp::Ordering::Equal => {}
                other => return Some(other),
            },
        }
    }
}

/// The `crc` crate's CRC-32/ISO-HDLC, bit by bit (`NoTable`): no 1 KiB
/// table in a firmware's flash, for about 8 times the time per byte
/// (images are checked once per download and boot).
static CRC32_ISO_HDLC: crc::Crc<u32, crc::NoTable> =
    crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);

/// Incremental CRC-32/ISO-HDLC (zlib `crc32`): polynomial `0x04C11DB7`
/// reflected, init `0xFFFFFFFF`, xor-out `0xFFFFFFFF`; check value of
/// `"123456789"` is `0xCBF43926`. Computed by the `crc` crate.
///
/// The state is the CRC of the bytes fed so far, so a `Crc32` is a plain
/// `Copy` value that can sit in `const` structures and be compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crc32 {
    /// CRC of everything fed so far (0 for no bytes).
    crc: u32,
}

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A CRC over no bytes yet.
    pub const fn new() -> Self {
        Self { crc: 0 }
    }

    /// Feeds `data`.
    pub const fn update(&mut self, data: &[u8]) {
        // Resume the crate's digest where the CRC so far left it: for this
        // reflected algorithm with xor-out `0xFFFFFFFF` the shift register
        // is `!crc`, and `digest_with_initial` bit-reverses the initial
        // value it is given (as for the algorithm's own `init`).
        let mut digest = CRC32_ISO_HDLC.digest_with_initial((!self.crc).reverse_bits());
        digest.update(data);
        self.crc = digest.finalize();
    }

    /// The CRC of everything fed so far (the state is kept).
    pub const fn finish(&self) -> u32 {
        self.crc
    }
}

/// CRC-32/ISO-HDLC of `data` (see [`Crc32`]).
pub fn crc32(data: &[u8]) -> u32 {
    CRC32_ISO_HDLC.checksum(data)
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

    #[test]
    fn crc32_matches_the_standard_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
        assert_eq!(crc32(b"a"), 0xE8B7_BE43);
    }

    /// CRC-32/ISO-HDLC bit by bit, from its definition.
    fn crc32_bitwise(data: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in data {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    (c >> 1) ^ 0xEDB8_8320
                } else {
                    c >> 1
                };
            }
        }
        !c
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]

        /// Fed in any pieces, [`Crc32`] gives the CRC of the whole, which
        /// is the bitwise definition's.
        #[test]
        fn crc32_in_pieces_equals_the_bitwise_definition(
            data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..600),
            cuts in proptest::collection::vec(proptest::prelude::any::<proptest::sample::Index>(), 0..6),
        ) {
            let mut at: Vec<usize> = cuts.iter().map(|i| i.index(data.len() + 1)).collect();
            at.sort_unstable();
            let mut c = Crc32::new();
            let mut from = 0;
            for to in at.into_iter().chain([data.len()]) {
                c.update(&data[from..to]);
                from = to;
            }
            proptest::prop_assert_eq!(c.finish(), crc32(&data));
            proptest::prop_assert_eq!(crc32(&data), crc32_bitwise(&data));
        }
    }

    #[test]
    fn crc32_is_incremental() {
        let data: [u8; 300] = core::array::from_fn(|i| (i * 7) as u8);
        let mut c = Crc32::new();
        for part in data.chunks(17) {
            c.update(part);
        }
        assert_eq!(c.finish(), crc32(&data));
    }

    #[test]
    fn versions_compare_by_their_numbers() {
        use core::cmp::Ordering::*;
        let c = |a: &str, b: &str| compare_versions(a.as_bytes(), b.as_bytes());
        assert_eq!(c("1.10", "1.9"), Some(Greater));
        assert_eq!(c("1.0", "1.0.0"), Some(Equal));
        assert_eq!(c("v2", "1.9.9"), Some(Greater));
        assert_eq!(c("10", "11"), Some(Less));
        assert_eq!(c("9", "10"), Some(Less));
        assert_eq!(c("99999999999999999999", "1"), Some(Greater));
        assert_eq!(c("beta", "1.0"), None);
        assert_eq!(c("1.0", ""), None);
        let v = |s: &str| FirmwareVersion::new(s).unwrap();
        assert_eq!(v("2.0.0").compare(&v("10")), Some(Less));
        assert_eq!(FirmwareVersion::EMPTY.compare(&v("1")), None);
    }

    #[test]
    fn version_text_is_nul_padded_ascii() {
        let v = FirmwareVersion::new("1.2.3").unwrap();
        assert_eq!(&v.raw()[..6], b"1.2.3\0");
        assert_eq!(v.as_str(), "1.2.3");
        assert!(FirmwareVersion::new("12345678901234567").is_none());
        assert!(FirmwareVersion::new("1.0\0").is_none());
        assert!(FirmwareVersion::new("1.0-é").is_none());
        assert_eq!(
            FirmwareVersion::new("1234567890123456")
                .unwrap()
                .as_str()
                .len(),
            16
        );
        assert_eq!(FirmwareVersion::from_raw([0xFF; 16]).as_str(), "?");
    }
}
