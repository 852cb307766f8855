//! FoE server (mailbox protocol layer, ETG.1000.6 §5.8 "File Access over
//! EtherCAT"): firmware download in BOOT (ETG.1000.6 §5.8) and a small
//! read-only info file.
//!
//! [`FoeServer::handle`] takes one parsed request ([`FoeRepr`]) and writes
//! at most one reply into the mailbox data area. It never touches the ESC
//! or the mailbox header and never panics on any request; flash goes
//! through the [`ImageStore`] in the [`FoeContext`], image checks through
//! an [`EfwValidator`], and the boot state only through the
//! [`firmware`](crate::firmware) functions, so an aborted or refused
//! download never changes the active image.
//!
//! # Rules
//!
//! * Write request (WRQ): accepted only in BOOT, with the device's FoE
//!   password (the owner's, stored in the boot records, else the
//!   description's [`FoeSecurity::factory_password`]; `0x00000000` for
//!   the catalog devices) and a file name ending in `.efw` (ASCII case
//!   ignored); answered with ACK 0 after the inactive slot is erased.
//! * Anti-rollback: an image whose version is older than the store's
//!   floor (the version last provisioned or confirmed, see
//!   [`BootState::min_version`](crate::firmware::BootState::min_version))
//!   is refused with `0x8002` as soon as its header is complete, before
//!   any payload byte is written, unless the file name ends in
//!   [`DOWNGRADE_SUFFIX`] (`.downgrade.efw`): the owner's consent, which
//!   needs the password like every write.
//! * WRQ of [`PASSWORD_FILE_NAME`] with the current password: the file
//!   (one short DATA packet, at most [`PASSWORD_FILE_CAPACITY`] bytes)
//!   holds the new password as 1 to 8 hex digits; it is stored power-cut
//!   safely in the boot records before the last ACK (see [`FoeSecurity`]
//!   for why FoE and not CoE). DATA packets are numbered from 1; a repeat of the previous
//!   packet is acknowledged again without being written twice; any other
//!   number aborts with PacketNumberWrong. A DATA packet shorter than the
//!   maximum (mailbox data size − 6) ends the file, so a file whose length
//!   is a multiple of the maximum ends with an empty DATA packet. The
//!   image is then validated and recorded as downloaded; the last ACK
//!   comes only after that.
//! * Read request (RRQ): [`INFO_FILE_NAME`] (any state, password ignored)
//!   returns the device identity and running version as text, in DATA
//!   packets the master acknowledges one by one.
//! * While [`FoeContext::busy`] is set (flash busy), WRQ and DATA are
//!   answered with BUSY and not processed: the master repeats them.
//! * An ERR from the master ends any transfer silently.
//!
//! # Error codes
//!
//! | situation                              | code                          | text |
//! |----------------------------------------|-------------------------------|------|
//! | WRQ outside BOOT                       | `0x8008` BootstrapOnly        | "firmware download only in BOOT" |
//! | WRQ with a wrong password              | `0x800A` NoRights             | "wrong password" |
//! | password file not 1 to 8 hex digits    | `0x8000` NotDefined           | "password file must hold 1 to 8 hex digits" |
//! | password file longer than 32 bytes     | `0x8003` DiskFull             | "password file longer than 32 bytes" |
//! | WRQ name not `*.efw`                   | `0x8009` NotBootstrap         | "only .efw files can be downloaded in BOOT" |
//! | RRQ of an unknown name                 | `0x8001` NotFound             | "file not found" |
//! | wrong DATA/ACK packet number           | `0x8005` PacketNumberWrong    | "packet number wrong" |
//! | DATA/ACK/unknown opcode out of context | `0x8004` Illegal              | "no transfer in progress" … |
//! | image older than the floor             | `0x8002` AccessDenied         | "version 9 is older than the minimum 10: downgrade refused" |
//! | image refused                          | [`EfwError::foe_code`]        | the [`EfwError`] text |
//! | flash failure                          | [`StoreError::foe_code`]      | the [`StoreError`] text |
//!
//! ETG.1000.6 names `0x8008` "Bootstrap only" and `0x8009` "Not bootstrap";
//! the ETG Slave Stack Code documents them as "FoE only supported in
//! Bootstrap" and "downloaded file name is not valid in Bootstrap state",
//! which is how they are used here. For a downgrade the slave will not
//! do, `0x8002` "access denied" was chosen among the ETG.1000.6 codes
//! `0x8000..=0x800F`: the request is understood and the image is valid,
//! the device's policy refuses it (`0x800A` "no rights" would say the
//! password is wrong, `0x800D` that the image does not fit the device).

use crate::text::Text;

use crate::firmware::{
    DeviceIdentity, EfwError, EfwValidator, ImageStore, Slot, StoreError, begin_download,
    cancel_download, finish_download, foe_password, rollback_floor, set_password, write_chunk,
};
use crate::wire::foe::{FoeErrorCode, FoeRepr, HEADER_LEN};

/// Firmware-update security of a device: what the factory ships, before
/// the owner takes over (the book's "Firmware update"
/// section).
///
/// # The FoE password
///
/// ETG.1000.6 §5.8 gives the FoE write and read requests (WRQ, RRQ) a
/// 32-bit password field and leaves its meaning to the device; a wrong one
/// is answered with FoE error `0x800A` "no rights". SOES (`soes/esc_foe.c`,
/// `FOE_fopen`) compares it with a password per file of the application's
/// compiled-in file table and offers no way to change it at run time.
///
/// Here the password starts as [`FoeSecurity::factory_password`] and the
/// owner changes it with a standard FoE download, which any master can do
/// (TwinCAT's FoE dialog, SOEM/pysoem `foe_write`, `master-test foe
/// password`): in BOOT, write the file [`PASSWORD_FILE_NAME`] with the
/// *current* password in the write request's password field; the file
/// holds the new password as 1 to 8 hex digits (`0x` and surrounding
/// whitespace allowed). The slave stores it in its boot records (two
/// copies with CRC and sequence number: a power cut keeps the old or the
/// new one) and asks for it from then on, across power cycles. A CoE
/// object was the alternative; FoE keeps the secret on the one service it
/// protects, needs no object in every device's dictionary, and works the
/// same in BOOT, where a bootloader has no object dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FoeSecurity {
    /// The FoE password a new device asks for until its owner sets another.
    pub factory_password: u32,
    /// Ed25519 public key (32 bytes) whose signature every firmware image
    /// must carry; `None`: unsigned images are accepted. A device with a
    /// key built without the `signed-images` feature accepts no image.
    pub public_key: Option<[u8; 32]>,
}

impl FoeSecurity {
    /// Password `0x00000000`, no signature required: what the catalog
    /// devices ship with, and every master's default.
    pub const OPEN: FoeSecurity = FoeSecurity {
        factory_password: 0,
        public_key: None,
    };
}

impl Default for FoeSecurity {
    fn default() -> Self {
        Self::OPEN
    }
}

/// The factory FoE password of the catalog devices (00000000, the value
/// their manuals give):
/// [`FoeSecurity::OPEN`]. A device's own is its description's
/// [`FoeSecurity::factory_password`] until the owner sets another (see
/// [`PASSWORD_FILE_NAME`]).
pub const FOE_PASSWORD: u32 = FoeSecurity::OPEN.factory_password;

/// Suffix (ASCII case ignored) of a firmware file name that asks to
/// install an image older than the anti-rollback floor: the owner's
/// explicit consent, given with the FoE password (e.g.
/// `app.downgrade.efw`; `master-test foe write --allow-downgrade`).
pub const DOWNGRADE_SUFFIX: &[u8] = b".downgrade.efw";

/// Name of the file (ASCII case ignored) whose FoE download in BOOT sets a
/// new FoE password: the write request carries the current password, the
/// file the new one as 1 to 8 hex digits (see [`FoeSecurity`]).
pub const PASSWORD_FILE_NAME: &[u8] = b"foe-password.txt";

/// Longest password file accepted (hex digits, `0x`, whitespace).
pub const PASSWORD_FILE_CAPACITY: usize = 32;

/// Suffix of downloadable firmware files.
pub const FIRMWARE_SUFFIX: &[u8] = b".efw";

/// Name of the read-only info file.
pub const INFO_FILE_NAME: &[u8] = b"info.txt";

/// Capacity of the generated info file.
pub const INFO_FILE_CAPACITY: usize = 192;

/// What the FoE server needs from the device for one request.
pub struct FoeContext<'a> {
    /// The image store (flash HAL).
    pub store: &'a mut dyn ImageStore,
    /// The device identity an image must match (object 0x1018).
    pub identity: DeviceIdentity,
    /// The running firmware's version text.
    pub version: &'a str,
    /// The factory password and the image key (the device description's).
    pub security: FoeSecurity,
    /// The AL state is BOOT.
    pub in_boot: bool,
    /// The flash is busy (e.g. an erase is in progress): answer BUSY.
    pub busy: bool,
}

/// The state of the FoE server.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
// `Receiving` carries the streaming image check (with `signed-images`, the
// Ed25519 verifier state): the core has no heap to box it in, and the
// server holds one state at a time.
#[allow(clippy::large_enum_variant)]
pub enum FoeState {
    /// No transfer.
    #[default]
    Idle,
    /// Receiving a firmware image.
    Receiving {
        /// Slot being written (the inactive one).
        slot: Slot,
        /// Number of the next DATA packet expected.
        next_packet: u32,
        /// Largest DATA size seen or expected; shorter packets end the file.
        segment: usize,
        /// Checks the image as it arrives.
        validator: EfwValidator,
    },
    /// A download completed; only a repeat of its last packet is
    /// acknowledged again.
    Complete {
        /// The last packet number.
        packet: u32,
    },
    /// Receiving a new FoE password ([`PASSWORD_FILE_NAME`]).
    ReceivingPassword {
        /// The file so far.
        text: heapless::Vec<u8, PASSWORD_FILE_CAPACITY>,
        /// Number of the next DATA packet expected.
        next_packet: u32,
        /// Largest DATA size seen or expected; shorter packets end the file.
        segment: usize,
    },
    /// A new password was stored; only a repeat of the last packet is
    /// acknowledged again. (A master error now changes nothing: the
    /// password stays set.)
    PasswordSet {
        /// The last packet number.
        packet: u32,
    },
    /// Sending the info file.
    Sending {
        /// The file.
        file: heapless::Vec<u8, INFO_FILE_CAPACITY>,
        /// Number of the last DATA packet sent.
        packet: u32,
        /// File offset of the last DATA packet sent.
        start: usize,
        /// Length of the last DATA packet sent.
        len: usize,
        /// The last DATA packet sent was the final (short) one.
        last: bool,
    },
    /// The last transfer ended with this error.
    Error {
        /// The error sent.
        code: FoeErrorCode,
    },
}

/// The FoE server of one slave.
#[derive(Debug, Clone, Default)]
pub struct FoeServer {
    state: FoeState,
}

impl FoeServer {
    /// A server with no transfer.
    pub fn new() -> Self {
        Self::default()
    }

    /// The current state.
    pub const fn state(&self) -> &FoeState {
        &self.state
    }

    /// Drops any transfer (AL state change, link loss). The partly written
    /// inactive slot is not referenced by the boot state, so the active
    /// image is untouched.
    pub fn abort(&mut self) {
        self.state = FoeState::Idle;
    }

    /// Handles one request and writes the FoE reply into `out`, the
    /// mailbox data area after the mailbox header (its length is the
    /// mailbox size limit: DATA packets sent are `out.len() - 6` bytes at
    /// most, and DATA packets received of that size are taken as "more to
    /// come"). Returns the reply length, or `None` when nothing is sent.
    pub fn handle(
        &mut self,
        request: FoeRepr<'_>,
        ctx: &mut FoeContext<'_>,
        out: &mut [u8],
    ) -> Option<usize> {
        match request {
            FoeRepr::WriteRequest { password, name } => {
                self.write_request(password, name, ctx, out)
            }
            FoeRepr::ReadRequest { name, .. } => self.read_request(name, ctx, out),
            FoeRepr::Data { packet, data } => self.data(packet, data, ctx, out),
            FoeRepr::Ack { packet } => self.ack(packet, out),
            FoeRepr::Busy { .. } => self.master_busy(out),
            FoeRepr::Error { .. } => {
                // The master gave up. After a completed download that
                // means it never saw the final acknowledgement: the image
                // is dropped so both agree the update did not happen.
                if matches!(self.state, FoeState::Complete { .. }) {
                    let _ = cancel_download(ctx.store);
                }
                self.state = FoeState::Idle;
                None
            }
            FoeRepr::Unknown { .. } => self.fail(out, FoeErrorCode::Illegal, "unknown FoE opcode"),
        }
    }

    fn write_request(
        &mut self,
        password: u32,
        name: &[u8],
        ctx: &mut FoeContext<'_>,
        out: &mut [u8],
    ) -> Option<usize> {
        self.state = FoeState::Idle;
        if !ctx.in_boot {
            return self.fail(
                out,
                FoeErrorCode::BootstrapOnly,
                "firmware download only in BOOT",
            );
        }
        let expected = match foe_password(ctx.store, ctx.security.factory_password) {
            Ok(p) => p,
            Err(e) => return self.fail_store(out, e),
        };
        if password != expected {
            return self.fail(out, FoeErrorCode::NoRights, "wrong password");
        }
        if name.eq_ignore_ascii_case(PASSWORD_FILE_NAME) {
            if ctx.busy {
                return emit(out, FoeRepr::Busy { done: 0, entire: 0 });
            }
            self.state = FoeState::ReceivingPassword {
                text: heapless::Vec::new(),
                next_packet: 1,
                segment: out.len().saturating_sub(HEADER_LEN),
            };
            return emit(out, FoeRepr::Ack { packet: 0 });
        }
        if !ends_with_ignore_case(name, FIRMWARE_SUFFIX) {
            return self.fail(
                out,
                FoeErrorCode::NotBootstrap,
                "only .efw files can be downloaded in BOOT",
            );
        }
        if ctx.busy {
            return emit(out, FoeRepr::Busy { done: 0, entire: 0 });
        }
        let floor = if ends_with_ignore_case(name, DOWNGRADE_SUFFIX) {
            crate::firmware::FirmwareVersion::EMPTY
        } else {
            match rollback_floor(ctx.store) {
                Ok(floor) => floor,
                Err(e) => return self.fail_store(out, e),
            }
        };
        let slot = match begin_download(ctx.store) {
            Ok(slot) => slot,
            Err(e) => return self.fail_store(out, e),
        };
        // The validator is set up where it lives (no copies of it on the
        // stack).
        self.state = FoeState::Receiving {
            slot,
            next_packet: 1,
            segment: out.len().saturating_sub(HEADER_LEN),
            validator: EfwValidator::new(ctx.identity, ctx.store.slot_capacity()),
        };
        if let FoeState::Receiving { validator, .. } = &mut self.state {
            validator.set_rollback_floor(floor);
            if let Some(key) = ctx.security.public_key {
                validator.set_public_key(key);
            }
        }
        emit(out, FoeRepr::Ack { packet: 0 })
    }

    fn data(
        &mut self,
        packet: u32,
        data: &[u8],
        ctx: &mut FoeContext<'_>,
        out: &mut [u8],
    ) -> Option<usize> {
        if matches!(self.state, FoeState::ReceivingPassword { .. }) {
            return self.password_data(packet, data, ctx, out);
        }
        let FoeState::Receiving {
            slot,
            next_packet,
            segment,
            validator,
        } = &mut self.state
        else {
            return match self.state {
                FoeState::Complete { packet: last } | FoeState::PasswordSet { packet: last }
                    if packet == last =>
                {
                    emit(out, FoeRepr::Ack { packet })
                }
                _ => self.fail(out, FoeErrorCode::Illegal, "no download in progress"),
            };
        };
        if let Err(r) = gate(packet, *next_packet, ctx.in_boot) {
            return self.refuse(r, packet, out);
        }
        if ctx.busy {
            let (done, entire) = progress(validator);
            return emit(out, FoeRepr::Busy { done, entire });
        }
        // A master with a larger mailbox than ours: its full size counts.
        *segment = (*segment).max(data.len());
        let last = data.len() < *segment;
        let slot = *slot;
        let offset = validator.payload_received();
        let payload = match validator.feed(data) {
            Ok(p) => p,
            Err(e) => return self.fail_efw(out, e),
        };
        if let Err(e) = write_chunk(ctx.store, slot, offset, payload) {
            return self.fail_store(out, e);
        }
        *next_packet = next_packet.wrapping_add(1);
        if !last {
            return emit(out, FoeRepr::Ack { packet });
        }
        let image = match validator.finish() {
            Ok(image) => image,
            Err(e) => return self.fail_efw(out, e),
        };
        if let Err(e) = finish_download(ctx.store, slot, &image) {
            return self.fail_store(out, e);
        }
        self.state = FoeState::Complete { packet };
        emit(out, FoeRepr::Ack { packet })
    }

    /// The answer to a DATA packet [`gate`] did not let through.
    fn refuse(&mut self, r: Refusal, packet: u32, out: &mut [u8]) -> Option<usize> {
        match r {
            // A repeat of the packet just acknowledged.
            Refusal::Repeat => emit(out, FoeRepr::Ack { packet }),
            Refusal::WrongNumber => {
                self.fail(out, FoeErrorCode::PacketNumberWrong, "packet number wrong")
            }
            Refusal::NotInBoot => self.fail(
                out,
                FoeErrorCode::BootstrapOnly,
                "firmware download only in BOOT",
            ),
        }
    }

    /// A DATA packet of the password file; the last one stores the new
    /// password.
    fn password_data(
        &mut self,
        packet: u32,
        data: &[u8],
        ctx: &mut FoeContext<'_>,
        out: &mut [u8],
    ) -> Option<usize> {
        let FoeState::ReceivingPassword {
            text,
            next_packet,
            segment,
        } = &mut self.state
        else {
            return None;
        };
        if let Err(r) = gate(packet, *next_packet, ctx.in_boot) {
            return self.refuse(r, packet, out);
        }
        if ctx.busy {
            return emit(out, FoeRepr::Busy { done: 0, entire: 0 });
        }
        *segment = (*segment).max(data.len());
        let last = data.len() < *segment;
        if text.extend_from_slice(data).is_err() {
            return self.fail(
                out,
                FoeErrorCode::DiskFull,
                "password file longer than 32 bytes",
            );
        }
        *next_packet = next_packet.wrapping_add(1);
        if !last {
            return emit(out, FoeRepr::Ack { packet });
        }
        let Some(new) = parse_password(text) else {
            return self.fail(
                out,
                FoeErrorCode::NotDefined,
                "password file must hold 1 to 8 hex digits",
            );
        };
        if let Err(e) = set_password(ctx.store, new) {
            return self.fail_store(out, e);
        }
        self.state = FoeState::PasswordSet { packet };
        emit(out, FoeRepr::Ack { packet })
    }

    fn read_request(&mut self, name: &[u8], ctx: &FoeContext<'_>, out: &mut [u8]) -> Option<usize> {
        self.state = FoeState::Idle;
        if !name.eq_ignore_ascii_case(INFO_FILE_NAME) {
            return self.fail(out, FoeErrorCode::NotFound, "file not found");
        }
        self.state = FoeState::Sending {
            file: heapless::Vec::new(),
            packet: 0,
            start: 0,
            len: 0,
            last: false,
        };
        // Written where it is sent from (a file returned by value was
        // copied twice on the stack).
        if let FoeState::Sending { file, .. } = &mut self.state {
            let text = info_file(ctx);
            let _ = file.extend_from_slice(text.as_bytes());
        }
        self.send_next(out)
    }

    fn ack(&mut self, packet: u32, out: &mut [u8]) -> Option<usize> {
        match &self.state {
            FoeState::Sending {
                packet: sent, last, ..
            } if *sent == packet => {
                if *last {
                    self.state = FoeState::Idle;
                    None
                } else {
                    self.send_next(out)
                }
            }
            FoeState::Sending { .. } => {
                self.fail(out, FoeErrorCode::PacketNumberWrong, "packet number wrong")
            }
            _ => self.fail(out, FoeErrorCode::Illegal, "no upload in progress"),
        }
    }

    /// The master is busy: repeat the last DATA packet of an upload.
    fn master_busy(&mut self, out: &mut [u8]) -> Option<usize> {
        match &self.state {
            FoeState::Sending {
                file,
                packet,
                start,
                len,
                ..
            } => {
                let data = file.get(*start..start.saturating_add(*len)).unwrap_or(&[]);
                emit(
                    out,
                    FoeRepr::Data {
                        packet: *packet,
                        data,
                    },
                )
            }
            _ => None,
        }
    }

    /// Sends the DATA packet after the last one sent.
    fn send_next(&mut self, out: &mut [u8]) -> Option<usize> {
        let segment = out.len().saturating_sub(HEADER_LEN);
        let FoeState::Sending {
            file,
            packet,
            start,
            len,
            last,
        } = &mut self.state
        else {
            return None;
        };
        if segment == 0 {
            self.state = FoeState::Idle;
            return None;
        }
        *start = start.saturating_add(*len);
        let data = file.get(*start..).unwrap_or(&[]);
        let data = data.get(..segment).unwrap_or(data);
        *len = data.len();
        *last = data.len() < segment;
        *packet = packet.wrapping_add(1);
        let reply = FoeRepr::Data {
            packet: *packet,
            data,
        };
        emit(out, reply)
    }

    /// Ends the transfer with an error reply.
    fn fail(&mut self, out: &mut [u8], code: FoeErrorCode, text: &str) -> Option<usize> {
        self.fail_bytes(out, code, text.as_bytes())
    }

    /// [`Self::fail`] with the text's bytes (a built [`Text`] is passed
    /// as bytes: no UTF-8 check on the firmware path).
    fn fail_bytes(&mut self, out: &mut [u8], code: FoeErrorCode, text: &[u8]) -> Option<usize> {
        self.state = FoeState::Error { code };
        let room = out.len().saturating_sub(HEADER_LEN);
        let text = text.get(..room).unwrap_or(text);
        emit(out, FoeRepr::Error { code, text })
    }

    fn fail_efw(&mut self, out: &mut [u8], e: EfwError) -> Option<usize> {
        self.fail_bytes(out, e.foe_code(), e.text().as_bytes())
    }

    fn fail_store(&mut self, out: &mut [u8], e: StoreError) -> Option<usize> {
        self.fail(out, e.foe_code(), e.text())
    }
}

fn emit(out: &mut [u8], reply: FoeRepr<'_>) -> Option<usize> {
    reply.emit(out).ok()
}

fn ends_with_ignore_case(name: &[u8], suffix: &[u8]) -> bool {
    name.len() > suffix.len()
        && name
            .get(name.len() - suffix.len()..)
            .is_some_and(|tail| tail.eq_ignore_ascii_case(suffix))
}

/// A password file: 1 to 8 hex digits, `0x` optional, ASCII whitespace
/// around them ignored.
fn parse_password(text: &[u8]) -> Option<u32> {
    let text = text.trim_ascii();
    let digits = match text {
        [b'0', b'x' | b'X', rest @ ..] => rest,
        _ => text,
    };
    if digits.is_empty() || digits.len() > 8 {
        return None;
    }
    digits.iter().try_fold(0u32, |acc, &c| {
        let d = char::from(c).to_digit(16)?;
        Some(acc << 4 | d)
    })
}

/// BUSY progress in percent once the image length is known.
fn progress(validator: &EfwValidator) -> (u16, u16) {
    match validator.expected_len() {
        Some(total) if total > 0 => {
            let done = validator.received().saturating_mul(100) / total;
            (u16::try_from(done).unwrap_or(100), 100)
        }
        _ => (0, 0),
    }
}

/// The info file: identity and running version, one `key=value` per line.
fn info_file(ctx: &FoeContext<'_>) -> Text<INFO_FILE_CAPACITY> {
    let mut text: Text<INFO_FILE_CAPACITY> = Text::new();
    let id = &ctx.identity;
    for (key, value) in [
        ("vendor_id=0x", id.vendor_id),
        ("\nproduct_code=0x", id.product_code),
        ("\nrevision=0x", id.revision),
    ] {
        text.push_str(key).push_hex_digits(value, 8, true);
    }
    text.push_str("\nversion=")
        .push_str(ctx.version)
        .push_str("\n");
    text
}

/// Why a DATA packet of a download is not taken.
enum Refusal {
    /// The packet just acknowledged, again: acknowledge it again.
    Repeat,
    /// Any other packet number than the next one.
    WrongNumber,
    /// Downloads go on only in BOOT.
    NotInBoot,
}

/// Whether DATA packet `packet` is the `next` one of a download in BOOT.
fn gate(packet: u32, next: u32, in_boot: bool) -> Result<(), Refusal> {
    if packet != next {
        if packet.wrapping_add(1) == next && packet != 0 {
            return Err(Refusal::Repeat);
        }
        return Err(Refusal::WrongNumber);
    }
    if !in_boot {
        return Err(Refusal::NotInBoot);
    }
    Ok(())
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
    use crate::firmware::{
        BootOutcome, EFW_HEADER_LEN, EfwHeaderRepr, FirmwareVersion, MemStore, commit_pending,
        pack, power_on, provision,
    };

    const DEVICE: DeviceIdentity = DeviceIdentity {
        vendor_id: 0x0000_0ABC,
        product_code: 0x0012_3456,
        revision: 7,
    };
    /// Mailbox data area of 1024 bytes: 1018 bytes of FoE data per packet.
    const MBX: usize = 1024;
    const SEG: usize = MBX - HEADER_LEN;

    type Small = MemStore<{ 64 * 1024 }>;

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

    fn efw(h: &EfwHeaderRepr, payload: &[u8]) -> Vec<u8> {
        let mut out = vec![0; usize::from(h.header_len) + payload.len()];
        pack(h, payload, &mut out).unwrap();
        out
    }

    fn payload(len: usize) -> Vec<u8> {
        (0..len)
            .map(|i| (i as u32).wrapping_mul(2_654_435_761) as u8 ^ (i >> 12) as u8)
            .collect()
    }

    /// A simulated master side: sends requests, decodes replies.
    struct Bench<'s> {
        server: FoeServer,
        store: &'s mut dyn ImageStore,
        security: FoeSecurity,
        in_boot: bool,
        busy: bool,
        out: Vec<u8>,
    }

    #[derive(Debug, PartialEq, Eq)]
    enum Reply {
        Ack(u32),
        Data(u32, Vec<u8>),
        Err(FoeErrorCode, String),
        Busy(u16, u16),
        None,
    }

    impl<'s> Bench<'s> {
        fn new(store: &'s mut dyn ImageStore) -> Self {
            Self {
                server: FoeServer::new(),
                store,
                security: FoeSecurity::OPEN,
                in_boot: true,
                busy: false,
                out: vec![0; MBX],
            }
        }

        fn send(&mut self, req: FoeRepr<'_>) -> Reply {
            // round trip through the wire format, as on the bus
            let mut raw = vec![0u8; req.buffer_len()];
            req.emit(&mut raw).unwrap();
            let req = FoeRepr::parse(&raw).unwrap();
            let mut ctx = FoeContext {
                store: &mut *self.store,
                identity: DEVICE,
                version: "1.0.0",
                security: self.security,
                in_boot: self.in_boot,
                busy: self.busy,
            };
            self.out.fill(0xEE);
            let Some(n) = self.server.handle(req, &mut ctx, &mut self.out) else {
                return Reply::None;
            };
            match FoeRepr::parse(&self.out[..n]).unwrap() {
                FoeRepr::Ack { packet } => Reply::Ack(packet),
                FoeRepr::Data { packet, data } => Reply::Data(packet, data.to_vec()),
                FoeRepr::Error { code, text } => {
                    Reply::Err(code, String::from_utf8(text.to_vec()).unwrap())
                }
                FoeRepr::Busy { done, entire } => Reply::Busy(done, entire),
                other => panic!("unexpected reply {other:?}"),
            }
        }

        fn wrq(&mut self, name: &str, password: u32) -> Reply {
            self.send(FoeRepr::WriteRequest {
                password,
                name: name.as_bytes(),
            })
        }

        fn data(&mut self, packet: u32, data: &[u8]) -> Reply {
            self.send(FoeRepr::Data { packet, data })
        }

        /// A whole download as a master does it; returns the last reply.
        fn download(&mut self, file: &[u8]) -> Reply {
            let reply = self.wrq("dev1.efw", 0);
            if reply != Reply::Ack(0) {
                return reply;
            }
            let mut packet = 0;
            let mut chunks = file.chunks(SEG).peekable();
            loop {
                packet += 1;
                let chunk = chunks.next().unwrap_or(&[]);
                let reply = self.data(packet, chunk);
                let ended = chunk.len() < SEG;
                if reply != Reply::Ack(packet) || ended {
                    return reply;
                }
            }
        }
    }

    fn provisioned<const N: usize>() -> MemStore<N> {
        let mut s = MemStore::<N>::new();
        provision(
            &mut s,
            FirmwareVersion::new("1.0.0").unwrap(),
            &[0xA5; 4000],
        )
        .unwrap();
        s
    }

    fn running_version(store: &mut dyn ImageStore) -> String {
        power_on(store).version.as_str().to_owned()
    }

    /// Runs `f` on a thread with a stack large enough for a MiB-sized
    /// `MemStore` built by value.
    fn with_big_stack(f: impl FnOnce() + Send + 'static) {
        std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn(f)
            .unwrap()
            .join()
            .unwrap();
    }

    #[test]
    fn full_download_of_a_1_mib_image_then_commit_and_power_on_runs_it() {
        with_big_stack(|| {
            type Big = MemStore<{ 2 * 1024 * 1024 }>;
            let mut store: Box<Big> = Box::new(provisioned::<{ 2 * 1024 * 1024 }>());
            let file = efw(&header("2.1.0"), &payload(1024 * 1024));
            let mut bench = Bench::new(&mut *store);
            assert_eq!(
                bench.download(&file),
                Reply::Ack(file.len() as u32 / SEG as u32 + 1)
            );
            assert!(matches!(bench.server.state(), FoeState::Complete { .. }));
            drop(bench);
            commit_pending(&mut *store).unwrap();
            let d = power_on(&mut *store);
            assert_eq!(d.version.as_str(), "2.1.0");
            assert_eq!(d.slot, Some(Slot::B));
            assert_eq!(d.outcome, BootOutcome::Trial { attempt: 1 });
        });
    }

    #[test]
    fn file_of_exact_multiple_length_ends_with_an_empty_data_packet() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        // header + payload = 3 full packets
        let file = efw(&header("2.0.0"), &payload(3 * SEG - EFW_HEADER_LEN));
        assert_eq!(file.len(), 3 * SEG);
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.EFW", 0), Reply::Ack(0));
        for (i, c) in file.chunks(SEG).enumerate() {
            assert_eq!(b.data(i as u32 + 1, c), Reply::Ack(i as u32 + 1));
            assert!(matches!(b.server.state(), FoeState::Receiving { .. }));
        }
        assert_eq!(b.data(4, &[]), Reply::Ack(4));
        drop(b);
        commit_pending(&mut store).unwrap();
        assert_eq!(running_version(&mut store), "2.0.0");
    }

    /// Sets a new password through the password file, as a master does.
    fn set_password_file(b: &mut Bench<'_>, current: u32, file: &[u8]) -> Reply {
        let reply = b.wrq("FOE-PASSWORD.TXT", current);
        if reply != Reply::Ack(0) {
            return reply;
        }
        b.data(1, file)
    }

    #[test]
    fn the_factory_password_of_the_description_is_asked_for() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(3000));
        let mut b = Bench::new(&mut store);
        b.security = FoeSecurity {
            factory_password: 0x5EC2_E701,
            public_key: None,
        };
        assert_eq!(
            b.wrq("fw.efw", 0),
            Reply::Err(FoeErrorCode::NoRights, "wrong password".into())
        );
        assert_eq!(b.wrq("fw.efw", 0x5EC2_E701), Reply::Ack(0));
        for (i, c) in file.chunks(SEG).enumerate() {
            assert_eq!(b.data(i as u32 + 1, c), Reply::Ack(i as u32 + 1));
        }
        drop(b);
        commit_pending(&mut store).unwrap();
        assert_eq!(running_version(&mut store), "2.0.0");
    }

    #[test]
    fn the_owner_changes_the_password_and_it_survives_a_power_cycle() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let mut b = Bench::new(&mut store);
        assert_eq!(
            set_password_file(&mut b, 0, b"  0xC0FFEE42\r\n"),
            Reply::Ack(1)
        );
        assert!(matches!(
            b.server.state(),
            FoeState::PasswordSet { packet: 1 }
        ));
        // a repeat of the last packet is acknowledged again
        assert_eq!(b.data(1, b"C0FFEE42"), Reply::Ack(1));
        // the old password no longer opens anything, the new one does
        assert_eq!(
            b.wrq("fw.efw", 0),
            Reply::Err(FoeErrorCode::NoRights, "wrong password".into())
        );
        assert_eq!(b.wrq("fw.efw", 0xC0FF_EE42), Reply::Ack(0));
        drop(b);
        // power cycle: the bootloader runs, the records keep the password
        let d = power_on(&mut store);
        assert_eq!(d.outcome, BootOutcome::Normal);
        assert_eq!(crate::firmware::foe_password(&store, 0), Ok(0xC0FF_EE42));
        let mut b = Bench::new(&mut store);
        assert_eq!(
            b.wrq("fw.efw", 0),
            Reply::Err(FoeErrorCode::NoRights, "wrong password".into())
        );
        // and it can be changed again, with the current one
        assert_eq!(set_password_file(&mut b, 0xC0FF_EE42, b"0"), Reply::Ack(1));
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
    }

    #[test]
    fn the_password_is_changed_only_with_the_current_one_in_boot() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let mut b = Bench::new(&mut store);
        assert_eq!(
            set_password_file(&mut b, 0x1111, b"2222"),
            Reply::Err(FoeErrorCode::NoRights, "wrong password".into())
        );
        b.in_boot = false;
        assert!(matches!(
            set_password_file(&mut b, 0, b"2222"),
            Reply::Err(FoeErrorCode::BootstrapOnly, _)
        ));
        drop(b);
        assert_eq!(crate::firmware::foe_password(&store, 0), Ok(0));
    }

    #[test]
    fn a_malformed_password_file_changes_nothing() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let records = *store.state_copies();
        let mut b = Bench::new(&mut store);
        for bad in [
            &b""[..],
            b"0x",
            b"123456789",
            b"12G4",
            b"-1",
            b"12 34",
            b"\xff",
        ] {
            let reply = set_password_file(&mut b, 0, bad);
            assert_eq!(
                reply,
                Reply::Err(
                    FoeErrorCode::NotDefined,
                    "password file must hold 1 to 8 hex digits".into()
                ),
                "{bad:?}"
            );
        }
        b.out = vec![0; 16]; // 10 data bytes per packet: a long file
        assert_eq!(b.wrq("foe-password.txt", 0), Reply::Ack(0));
        for p in 1..=3 {
            assert_eq!(b.data(p, b"0000000000"), Reply::Ack(p));
        }
        assert_eq!(
            b.data(4, b"0000000000"),
            // the text is cut to the small mailbox
            Reply::Err(FoeErrorCode::DiskFull, "password f".into())
        );
        drop(b);
        assert_eq!(store.state_copies(), &records, "no record written");
    }

    #[test]
    fn a_power_cut_while_storing_the_password_keeps_the_old_or_the_new_one() {
        let base = provisioned::<{ 64 * 1024 }>();
        for cut in 0..=crate::firmware::STATE_RECORD_LEN {
            let mut store = base.clone();
            store.cut_power_after(cut);
            let reply = set_password_file(&mut Bench::new(&mut store), 0, b"ABCD");
            store.restore_power();
            let now = crate::firmware::foe_password(&store, 0).unwrap();
            if cut == crate::firmware::STATE_RECORD_LEN {
                assert_eq!((reply, now), (Reply::Ack(1), 0xABCD));
            } else {
                assert!(
                    matches!(reply, Reply::Err(FoeErrorCode::FlashError, _)),
                    "cut {cut}: {reply:?}"
                );
                assert_eq!(now, 0, "cut {cut}");
            }
            assert_eq!(running_version(&mut store), "1.0.0", "cut {cut}");
        }
    }

    #[test]
    fn a_master_error_after_a_password_change_keeps_a_downloaded_image() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(1000));
        let mut b = Bench::new(&mut store);
        assert!(matches!(b.download(&file), Reply::Ack(_)));
        assert_eq!(set_password_file(&mut b, 0, b"7"), Reply::Ack(1));
        assert_eq!(
            b.send(FoeRepr::Error {
                code: FoeErrorCode::NotDefined,
                text: b"late"
            }),
            Reply::None
        );
        drop(b);
        assert!(commit_pending(&mut store).unwrap().is_some());
        assert_eq!(crate::firmware::foe_password(&store, 0), Ok(7));
    }

    /// Downloads `file` under `name`, commits it and power-cycles with a
    /// confirmed boot, as the runner does; returns the last reply.
    fn install(store: &mut Small, name: &str, file: &[u8]) -> Reply {
        let mut b = Bench::new(store);
        let mut reply = b.wrq(name, 0);
        if reply == Reply::Ack(0) {
            for (i, c) in file.chunks(SEG).enumerate() {
                reply = b.data(i as u32 + 1, c);
                if reply != Reply::Ack(i as u32 + 1) {
                    break;
                }
            }
            if file.len().is_multiple_of(SEG) && reply == Reply::Ack((file.len() / SEG) as u32) {
                reply = b.data((file.len() / SEG) as u32 + 1, &[]);
            }
        }
        drop(b);
        let _ = commit_pending(store);
        let _ = power_on(store);
        let _ = crate::firmware::confirm_boot(store);
        reply
    }

    #[test]
    fn an_older_image_is_refused_with_access_denied_before_anything_is_written() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        // upgrade 1.0.0 -> 2.0.0: accepted, and 2.0.0 becomes the floor
        let up = efw(&header("2.0.0"), &payload(3000));
        assert!(matches!(install(&mut store, "fw.efw", &up), Reply::Ack(_)));
        assert_eq!(running_version(&mut store), "2.0.0");
        assert_eq!(
            crate::firmware::rollback_floor(&store).unwrap().as_str(),
            "2.0.0"
        );
        // back to 1.5: refused at its header, nothing of it written
        let down = efw(&header("1.5"), &payload(3000));
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        let records = b.store.read_state().unwrap();
        assert_eq!(
            b.data(1, &down[..SEG]),
            Reply::Err(
                FoeErrorCode::AccessDenied,
                "version 1.5 is older than the minimum 2.0.0: downgrade refused".into()
            )
        );
        assert_eq!(b.store.read_state().unwrap(), records, "no record written");
        let mut slot = [0u8; 3000];
        b.store.read(Slot::A, 0, &mut slot).unwrap();
        assert!(slot.iter().all(|&x| x == 0xFF), "no payload byte written");
        drop(b);
        assert_eq!(commit_pending(&mut store), Ok(None));
        assert_eq!(running_version(&mut store), "2.0.0");
        // the same version again is no downgrade
        let same = efw(&header("2.0"), &payload(2000));
        assert!(matches!(
            install(&mut store, "fw.efw", &same),
            Reply::Ack(_)
        ));
        assert_eq!(running_version(&mut store), "2.0");
    }

    #[test]
    fn the_owner_allows_a_downgrade_with_the_downgrade_file_name_and_the_password() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let up = efw(&header("2.0.0"), &payload(3000));
        assert!(matches!(install(&mut store, "fw.efw", &up), Reply::Ack(_)));
        // the owner's password guards the override like every write
        let mut b = Bench::new(&mut store);
        assert_eq!(set_password_file(&mut b, 0, b"5EC2E7"), Reply::Ack(1));
        assert_eq!(
            b.wrq("fw.downgrade.efw", 0),
            Reply::Err(FoeErrorCode::NoRights, "wrong password".into())
        );
        drop(b);
        let down = efw(&header("1.5"), &payload(2900));
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("FW.DOWNGRADE.EFW", 0x5E_C2E7), Reply::Ack(0));
        assert_eq!(b.data(1, &down[..SEG]), Reply::Ack(1));
        assert_eq!(b.data(2, &down[SEG..2 * SEG]), Reply::Ack(2));
        assert_eq!(b.data(3, &down[2 * SEG..]), Reply::Ack(3));
        drop(b);
        commit_pending(&mut store).unwrap();
        let _ = power_on(&mut store);
        crate::firmware::confirm_boot(&mut store).unwrap();
        assert_eq!(running_version(&mut store), "1.5");
        // the confirmed downgrade is the new floor: 1.6 is an upgrade again
        assert_eq!(
            crate::firmware::rollback_floor(&store).unwrap().as_str(),
            "1.5"
        );
    }

    #[test]
    fn a_pending_upgrade_does_not_raise_the_floor_until_it_is_confirmed() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let up = efw(&header("3"), &payload(3000));
        let mut b = Bench::new(&mut store);
        assert!(matches!(b.download(&up), Reply::Ack(_)));
        drop(b);
        commit_pending(&mut store).unwrap();
        assert_eq!(
            crate::firmware::rollback_floor(&store).unwrap().as_str(),
            "1.0.0"
        );
        // a trial that is rejected leaves the floor at the running image
        let _ = power_on(&mut store);
        crate::firmware::reject_boot(&mut store).unwrap();
        assert_eq!(running_version(&mut store), "1.0.0");
        assert_eq!(
            crate::firmware::rollback_floor(&store).unwrap().as_str(),
            "1.0.0"
        );
    }

    #[cfg(feature = "signed-images")]
    #[test]
    fn a_device_with_a_key_installs_only_images_signed_with_it() {
        use crate::firmware::{
            EFW_FLAG_SIGNED, EFW_SIGNED_HEADER_LEN, set_signature, signed_message,
        };
        use ed25519_compact::{KeyPair, Seed};
        let owner = KeyPair::from_seed(Seed::new([3; 32]));
        let sign = |kp: &KeyPair, version: &str, len: usize| {
            let h = EfwHeaderRepr {
                flags: EFW_FLAG_SIGNED,
                header_len: EFW_SIGNED_HEADER_LEN as u16,
                ..header(version)
            };
            let mut img = efw(&h, &payload(len));
            let msg = signed_message(&img).unwrap().concat();
            set_signature(&mut img, &kp.sk.sign(&msg, None)).unwrap();
            img
        };
        let security = FoeSecurity {
            factory_password: 0,
            public_key: Some(*owner.pk),
        };
        let mut store = provisioned::<{ 64 * 1024 }>();
        // unsigned: refused at its header, before any payload is written
        let mut b = Bench::new(&mut store);
        b.security = security;
        let before = b.store.read_state().unwrap();
        assert_eq!(
            b.download(&efw(&header("2.0.0"), &payload(3000))),
            Reply::Err(
                FoeErrorCode::InvalidFirmware,
                "image not signed; this device accepts only signed images".into()
            )
        );
        assert_eq!(b.store.read_state().unwrap(), before, "nothing recorded");
        // signed by someone else: the whole file arrives, nothing is committed
        let stranger = KeyPair::from_seed(Seed::new([4; 32]));
        assert_eq!(
            b.download(&sign(&stranger, "2.0.0", 3000)),
            Reply::Err(
                FoeErrorCode::InvalidFirmware,
                "image signature does not verify with the device's key".into()
            )
        );
        drop(b);
        assert_eq!(commit_pending(&mut store), Ok(None));
        assert_eq!(running_version(&mut store), "1.0.0");
        // signed by the owner: installed
        let mut b = Bench::new(&mut store);
        b.security = security;
        assert!(matches!(
            b.download(&sign(&owner, "2.0.0", 3000)),
            Reply::Ack(_)
        ));
        drop(b);
        commit_pending(&mut store).unwrap();
        assert_eq!(running_version(&mut store), "2.0.0");
    }

    #[test]
    fn wrong_password_is_refused_with_no_rights() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let mut b = Bench::new(&mut store);
        assert_eq!(
            b.wrq("fw.efw", 0x1234),
            Reply::Err(FoeErrorCode::NoRights, "wrong password".into())
        );
        assert!(matches!(b.server.state(), FoeState::Error { .. }));
        // data after the refusal is illegal, nothing written
        assert!(matches!(
            b.data(1, &[1, 2]),
            Reply::Err(FoeErrorCode::Illegal, _)
        ));
        drop(b);
        assert_eq!(store.slot_bytes(Slot::B), &[0xFF; 32 * 1024][..]);
    }

    #[test]
    fn write_outside_boot_is_refused_bootstrap_only() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let mut b = Bench::new(&mut store);
        b.in_boot = false;
        assert_eq!(
            b.wrq("fw.efw", 0),
            Reply::Err(
                FoeErrorCode::BootstrapOnly,
                "firmware download only in BOOT".into()
            )
        );
    }

    #[test]
    fn non_efw_file_name_is_refused() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let mut b = Bench::new(&mut store);
        for name in ["fw.bin", "efw", ".efw", "fw.efw.txt", ""] {
            assert!(
                matches!(b.wrq(name, 0), Reply::Err(FoeErrorCode::NotBootstrap, _)),
                "{name}"
            );
        }
    }

    #[test]
    fn wrong_product_is_refused_at_the_first_packet() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let h = EfwHeaderRepr {
            product_code: 0x0BAD,
            ..header("2.0.0")
        };
        let file = efw(&h, &payload(5000));
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        let Reply::Err(code, text) = b.data(1, &file[..SEG]) else {
            panic!()
        };
        assert_eq!(code, FoeErrorCode::InvalidFirmware);
        assert_eq!(text, "image product 0xbad, device product 0x123456");
        drop(b);
        assert_eq!(running_version(&mut store), "1.0.0");
    }

    #[test]
    fn bad_payload_crc_is_refused_at_the_end_and_old_image_stays() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let mut file = efw(&header("2.0.0"), &payload(5000));
        file[3000] ^= 0x01;
        let mut b = Bench::new(&mut store);
        let reply = b.download(&file);
        assert!(
            matches!(&reply, Reply::Err(FoeErrorCode::InvalidChecksum, t) if t.starts_with("payload CRC")),
            "{reply:?}"
        );
        drop(b);
        assert_eq!(commit_pending(&mut store), Ok(None));
        assert_eq!(running_version(&mut store), "1.0.0");
    }

    #[test]
    fn truncated_transfer_aborted_by_the_master_keeps_the_old_image() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(10_000));
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        for (i, c) in file.chunks(SEG).take(5).enumerate() {
            assert_eq!(b.data(i as u32 + 1, c), Reply::Ack(i as u32 + 1));
        }
        // the master stops; the device leaves BOOT
        b.server.abort();
        assert_eq!(b.server.state(), &FoeState::Idle);
        drop(b);
        assert_eq!(commit_pending(&mut store), Ok(None));
        assert_eq!(running_version(&mut store), "1.0.0");
    }

    #[test]
    fn file_ending_early_is_refused_as_truncated() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(10_000));
        let mut b = Bench::new(&mut store);
        let reply = b.download(&file[..2 * SEG + 100]);
        assert_eq!(
            reply,
            Reply::Err(
                FoeErrorCode::InvalidChecksum,
                format!("image truncated: {} of {} bytes", 2 * SEG + 100, file.len())
            )
        );
    }

    #[test]
    fn oversized_image_is_refused() {
        // payload larger than the 32 KiB slot: refused from the header
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(40_000));
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        assert_eq!(
            b.data(1, &file[..SEG]),
            Reply::Err(
                FoeErrorCode::DiskFull,
                "payload of 40000 bytes exceeds slot capacity 32768".into()
            )
        );
        // file longer than its header says: refused when the extra arrives
        let mut file = efw(&header("2.0.0"), &payload(3000));
        file.extend_from_slice(&[0; 2000]);
        let reply = b.download(&file);
        assert!(
            matches!(reply, Reply::Err(FoeErrorCode::InvalidChecksum, _)),
            "{reply:?}"
        );
        drop(b);
        assert_eq!(running_version(&mut store), "1.0.0");
    }

    #[test]
    fn duplicate_data_packet_is_reacknowledged_without_writing_twice() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        // 2956 bytes: two full packets and a short final one
        let file = efw(&header("2.0.0"), &payload(2900));
        let chunks: Vec<&[u8]> = file.chunks(SEG).collect();
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        assert_eq!(b.data(1, chunks[0]), Reply::Ack(1));
        assert_eq!(b.data(2, chunks[1]), Reply::Ack(2));
        assert_eq!(b.data(2, chunks[1]), Reply::Ack(2));
        let FoeState::Receiving { validator, .. } = b.server.state() else {
            panic!()
        };
        assert_eq!(validator.received(), 2 * SEG);
        assert_eq!(b.data(3, chunks[2]), Reply::Ack(3));
        // repeat of the final packet after completion
        assert_eq!(b.data(3, chunks[2]), Reply::Ack(3));
        drop(b);
        commit_pending(&mut store).unwrap();
        assert_eq!(running_version(&mut store), "2.0.0");
    }

    #[test]
    fn packet_number_skip_aborts_and_keeps_the_old_image() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(5000));
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        assert_eq!(b.data(1, &file[..SEG]), Reply::Ack(1));
        assert_eq!(
            b.data(3, &file[SEG..2 * SEG]),
            Reply::Err(
                FoeErrorCode::PacketNumberWrong,
                "packet number wrong".into()
            )
        );
        assert_eq!(
            b.server.state(),
            &FoeState::Error {
                code: FoeErrorCode::PacketNumberWrong
            }
        );
        assert!(matches!(
            b.data(2, &file[SEG..2 * SEG]),
            Reply::Err(FoeErrorCode::Illegal, _)
        ));
        drop(b);
        assert_eq!(commit_pending(&mut store), Ok(None));
        assert_eq!(running_version(&mut store), "1.0.0");
    }

    #[test]
    fn packet_zero_and_old_packets_are_wrong_numbers() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(5000));
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        assert!(matches!(
            b.data(0, &file[..SEG]),
            Reply::Err(FoeErrorCode::PacketNumberWrong, _)
        ));
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        assert_eq!(b.data(1, &file[..SEG]), Reply::Ack(1));
        assert_eq!(b.data(2, &file[SEG..2 * SEG]), Reply::Ack(2));
        assert!(matches!(
            b.data(1, &file[..SEG]),
            Reply::Err(FoeErrorCode::PacketNumberWrong, _)
        ));
    }

    #[test]
    fn power_cut_in_the_middle_of_a_download_keeps_the_old_image() {
        let file = efw(&header("2.0.0"), &payload(20_000));
        let base = provisioned::<{ 64 * 1024 }>();
        let mut full = base.clone();
        let before = full.bytes_written();
        assert!(matches!(
            Bench::new(&mut full).download(&file),
            Reply::Ack(_)
        ));
        let total = full.bytes_written() - before;
        for cut in [0, 1, 16_000, 32_767, 32_768, 40_000, total - 64, total - 1] {
            let mut store = base.clone();
            store.cut_power_after(cut);
            let reply = Bench::new(&mut store).download(&file);
            assert!(
                matches!(reply, Reply::Err(FoeErrorCode::FlashError, _)),
                "cut {cut}: {reply:?}"
            );
            store.restore_power();
            let _ = commit_pending(&mut store);
            let d = power_on(&mut store);
            assert_eq!(
                (d.slot, d.version.as_str()),
                (Some(Slot::A), "1.0.0"),
                "cut {cut}"
            );
        }
    }

    #[test]
    fn busy_store_answers_busy_and_the_repeat_goes_through() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(2900));
        let mut b = Bench::new(&mut store);
        b.busy = true;
        assert_eq!(b.wrq("fw.efw", 0), Reply::Busy(0, 0));
        b.busy = false;
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        assert_eq!(b.data(1, &file[..SEG]), Reply::Ack(1));
        b.busy = true;
        let Reply::Busy(done, 100) = b.data(2, &file[SEG..2 * SEG]) else {
            panic!()
        };
        assert_eq!(usize::from(done), SEG * 100 / file.len());
        b.busy = false;
        assert_eq!(b.data(2, &file[SEG..2 * SEG]), Reply::Ack(2));
        assert_eq!(b.data(3, &file[2 * SEG..]), Reply::Ack(3));
        assert!(matches!(b.server.state(), FoeState::Complete { packet: 3 }));
    }

    #[test]
    fn read_request_of_the_info_file_returns_identity_and_version() {
        let mut store = Small::new();
        let mut b = Bench::new(&mut store);
        b.in_boot = false;
        let Reply::Data(1, data) = b.send(FoeRepr::ReadRequest {
            password: 0,
            name: b"info.txt",
        }) else {
            panic!()
        };
        assert_eq!(
            String::from_utf8(data).unwrap(),
            "vendor_id=0x00000ABC\nproduct_code=0x00123456\nrevision=0x00000007\nversion=1.0.0\n"
        );
        assert_eq!(b.send(FoeRepr::Ack { packet: 1 }), Reply::None);
        assert_eq!(b.server.state(), &FoeState::Idle);
    }

    #[test]
    fn info_file_is_split_over_small_mailboxes() {
        let mut store = Small::new();
        let mut b = Bench::new(&mut store);
        b.out = vec![0; 16]; // 10 data bytes per packet
        let mut file = Vec::new();
        let mut reply = b.send(FoeRepr::ReadRequest {
            password: 0,
            name: b"INFO.TXT",
        });
        let mut expected = 1;
        loop {
            let Reply::Data(n, data) = reply else {
                panic!("{reply:?}")
            };
            assert_eq!(n, expected);
            file.extend_from_slice(&data);
            let more = data.len() == 10;
            if n == 2 {
                // the master is busy once: the packet is sent again
                assert_eq!(
                    b.send(FoeRepr::Busy { done: 0, entire: 0 }),
                    Reply::Data(2, data)
                );
            }
            reply = b.send(FoeRepr::Ack { packet: n });
            if !more {
                assert_eq!(reply, Reply::None);
                break;
            }
            expected += 1;
        }
        assert!(file.ends_with(b"version=1.0.0\n"));
        assert_eq!(file.len(), 79);
        // 79 bytes = 7 full packets + one of 9 bytes
        assert_eq!(expected, 8);
    }

    #[test]
    fn wrong_ack_during_upload_is_a_packet_number_error() {
        let mut store = Small::new();
        let mut b = Bench::new(&mut store);
        b.out = vec![0; 16];
        assert!(matches!(
            b.send(FoeRepr::ReadRequest {
                password: 0,
                name: b"info.txt"
            }),
            Reply::Data(1, _)
        ));
        assert!(matches!(
            b.send(FoeRepr::Ack { packet: 5 }),
            Reply::Err(FoeErrorCode::PacketNumberWrong, _)
        ));
    }

    #[test]
    fn unknown_read_request_name_is_not_found() {
        let mut store = Small::new();
        let mut b = Bench::new(&mut store);
        assert_eq!(
            b.send(FoeRepr::ReadRequest {
                password: 0,
                name: b"secret.bin"
            }),
            Reply::Err(FoeErrorCode::NotFound, "file not found".into())
        );
    }

    #[test]
    fn master_error_ends_a_download_silently() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let mut b = Bench::new(&mut store);
        assert_eq!(b.wrq("fw.efw", 0), Reply::Ack(0));
        assert_eq!(
            b.send(FoeRepr::Error {
                code: FoeErrorCode::NotDefined,
                text: b"user abort"
            }),
            Reply::None
        );
        assert_eq!(b.server.state(), &FoeState::Idle);
    }

    #[test]
    fn a_master_error_after_the_last_packet_drops_the_downloaded_image() {
        // The master lost the final acknowledgement and gave up: the
        // update must not happen behind its back at BOOT -> INIT.
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(1000));
        let mut b = Bench::new(&mut store);
        assert!(matches!(b.download(&file), Reply::Ack(_)));
        assert!(matches!(b.server.state(), FoeState::Complete { .. }));
        assert_eq!(
            b.send(FoeRepr::Error {
                code: FoeErrorCode::NotDefined,
                text: b"aborted by the master"
            }),
            Reply::None
        );
        drop(b);
        assert_eq!(commit_pending(&mut store), Ok(None), "nothing pending");
        assert_eq!(running_version(&mut store), "1.0.0");
    }

    #[test]
    fn stray_and_unknown_packets_are_illegal() {
        let mut store = Small::new();
        let mut b = Bench::new(&mut store);
        assert!(matches!(
            b.send(FoeRepr::Ack { packet: 1 }),
            Reply::Err(FoeErrorCode::Illegal, _)
        ));
        assert!(matches!(
            b.data(1, b"x"),
            Reply::Err(FoeErrorCode::Illegal, _)
        ));
        assert!(matches!(
            b.send(FoeRepr::Unknown {
                opcode: 9,
                word: 0,
                tail: &[]
            }),
            Reply::Err(FoeErrorCode::Illegal, _)
        ));
        assert_eq!(b.send(FoeRepr::Busy { done: 1, entire: 2 }), Reply::None);
    }

    #[test]
    fn tiny_or_missing_reply_buffer_never_panics() {
        let mut store = provisioned::<{ 64 * 1024 }>();
        let file = efw(&header("2.0.0"), &payload(100));
        let requests = [
            FoeRepr::WriteRequest {
                password: 0,
                name: b"a.efw",
            },
            FoeRepr::Data {
                packet: 1,
                data: &file,
            },
            FoeRepr::ReadRequest {
                password: 0,
                name: b"info.txt",
            },
            FoeRepr::Ack { packet: 1 },
            FoeRepr::Error {
                code: FoeErrorCode::Unknown(7),
                text: &[],
            },
        ];
        for len in 0..12 {
            let mut server = FoeServer::new();
            for req in requests {
                let mut out = vec![0u8; len];
                let mut ctx = FoeContext {
                    store: &mut store,
                    identity: DEVICE,
                    version: "1.0.0",
                    security: FoeSecurity::OPEN,
                    in_boot: true,
                    busy: false,
                };
                if let Some(n) = server.handle(req, &mut ctx, &mut out) {
                    assert!(n <= len);
                    assert!(FoeRepr::parse(&out[..n]).is_ok());
                }
            }
        }
    }

    #[test]
    fn error_text_is_cut_to_the_mailbox() {
        let mut store = Small::new();
        let mut server = FoeServer::new();
        let mut out = [0u8; 10];
        let mut ctx = FoeContext {
            store: &mut store,
            identity: DEVICE,
            version: "1.0.0",
            security: FoeSecurity::OPEN,
            in_boot: false,
            busy: false,
        };
        let req = FoeRepr::WriteRequest {
            password: 0,
            name: b"a.efw",
        };
        assert_eq!(server.handle(req, &mut ctx, &mut out), Some(10));
        assert_eq!(
            FoeRepr::parse(&out).unwrap(),
            FoeRepr::Error {
                code: FoeErrorCode::BootstrapOnly,
                text: b"firm"
            }
        );
    }
}
