//! `foe write/read` and `firmware pack`.

use crate::failure::{Failure, input};
use crate::output::{self, long_command, outln, stop_requested};
use crate::target::{Session, Where};
use ecat_slave::firmware::{DeviceIdentity, EfwHeaderRepr, EfwValidator};
use master_test::mailbox::MailboxClient;
use std::cmp::Ordering;
use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};

/// `foe` subcommands.
#[derive(clap::Subcommand)]
pub enum FoeCmd {
    /// Download an `.efw` image to the slave in BOOT (manual 5.10), then
    /// INIT; on the virtual bus also a simulated power cycle, after which
    /// the new version runs.
    ///
    /// The image is checked first (header, CRC, vendor, product, revision
    /// range of the live slave): a bad image is refused before anything
    /// is sent. An image older than the running firmware is refused
    /// unless --allow-downgrade confirms it; the slave refuses it too
    /// (anti-rollback, FoE error 0x8002) unless the file name sent ends
    /// in `.downgrade.efw`, which --allow-downgrade does. Ctrl-C aborts the transfer
    /// with a FoE error: the slave keeps its old firmware.
    Write {
        /// The `.efw` file (see `firmware pack`).
        file: PathBuf,
        /// FoE password: 1 to 8 hex digits, 0x optional (the PAM-199
        /// expects 00000000).
        #[arg(long, default_value = "00000000", value_parser = parse_password)]
        password: u32,
        /// File name sent in the write request.
        #[arg(long, default_value = "firmware.efw")]
        name: String,
        /// Confirm writing an image older than the running firmware.
        #[arg(long)]
        allow_downgrade: bool,
    },
    /// Set the slave's FoE password (the owner's; factory 00000000 for
    /// the catalog devices): in BOOT, a download of `foe-password.txt`
    /// with the current password; the slave keeps the new one across
    /// power cycles and asks for it from then on. Then INIT.
    Password {
        /// The new password: 1 to 8 hex digits, 0x optional.
        #[arg(value_parser = parse_password)]
        new: u32,
        /// The current FoE password.
        #[arg(long, default_value = "00000000", value_parser = parse_password)]
        password: u32,
    },
    /// Read a file the slave offers (e.g. `info.txt`) in PRE-OP.
    Read {
        /// File name.
        name: String,
        /// Write the file here instead of printing it.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// FoE password: 1 to 8 hex digits, 0x optional.
        #[arg(long, default_value = "00000000", value_parser = parse_password)]
        password: u32,
    },
}

/// `firmware` subcommands.
#[derive(clap::Subcommand)]
pub enum FirmwareCmd {
    /// Wrap a binary into an `.efw` image for the device (--device,
    /// default pam): identity, revision range, version, CRCs.
    Pack {
        /// The firmware binary (not empty).
        binary: PathBuf,
        /// Firmware version text, 1 to 16 ASCII characters (e.g. 1.2.0).
        #[arg(long)]
        version: String,
        /// Output file.
        #[arg(short, long)]
        output: PathBuf,
        /// Lowest device revision the image supports (0..=4294967295,
        /// decimal or 0x-hex).
        #[arg(long, default_value = "0", value_parser = parse_u32)]
        revision_min: u32,
        /// Highest device revision the image supports (at least
        /// --revision-min).
        #[arg(long, default_value = "0xFFFFFFFF", value_parser = parse_u32)]
        revision_max: u32,
        /// Sign the image with this Ed25519 private key: a PEM file
        /// "-----BEGIN PRIVATE KEY-----" (PKCS#8, as `firmware keygen`
        /// or `openssl genpkey -algorithm ed25519` writes it). A device
        /// whose description has the matching public key accepts only
        /// images signed so.
        #[arg(long, value_name = "KEYFILE")]
        sign: Option<PathBuf>,
    },
    /// Make an Ed25519 key pair for signing images: the private key to
    /// KEYFILE (PEM PKCS#8, mode 0600, never overwritten); prints the
    /// public key for the device description
    /// (`FoeSecurity::public_key`).
    Keygen {
        /// The private key file to create.
        #[arg(short, long, value_name = "KEYFILE")]
        output: PathBuf,
    },
}

/// A FoE password: 1 to 8 hex digits, `0x` optional.
pub fn parse_password(s: &str) -> Result<u32, String> {
    let digits = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    if digits.is_empty() || digits.len() > 8 || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(format!(
            "'{s}' is not a FoE password: 1 to 8 hex digits, 0x optional (e.g. 00000000)"
        ));
    }
    u32::from_str_radix(digits, 16).map_err(|e| e.to_string())
}

fn parse_u32(s: &str) -> Result<u32, String> {
    let v = master_test::cli::parse_int(s)
        .ok_or_else(|| format!("'{s}' is not a number (decimal, or hex with 0x)"))?;
    u32::try_from(v).map_err(|_| format!("{v} is outside 0..=4294967295"))
}

/// Compares firmware versions by their numbers (`1.10` > `1.9`, `v2` >
/// `1.9.9`); `None` when either has no number. The slave's own rule
/// ([`ecat_slave::firmware::compare_versions`]), so the client refuses
/// exactly what the slave's anti-rollback check would.
pub fn compare_versions(a: &str, b: &str) -> Option<Ordering> {
    ecat_slave::firmware::compare_versions(a.as_bytes(), b.as_bytes())
}

/// The file name that asks the slave to accept a downgrade: `name` with
/// `.efw` replaced by `.downgrade.efw` (kept if it has it already).
pub fn downgrade_name(name: &str) -> String {
    let lower = name.to_ascii_lowercase();
    if lower.ends_with(".downgrade.efw") {
        return name.to_string();
    }
    let stem = if lower.ends_with(".efw") {
        &name[..name.len() - 4]
    } else {
        name
    };
    format!("{stem}.downgrade.efw")
}

/// Runs a `foe` command.
pub async fn foe(w: &Where, op: FoeCmd) -> Result<(), Failure> {
    match op {
        FoeCmd::Write {
            file,
            password,
            name,
            allow_downgrade,
        } => foe_write(w, &file, password, &name, allow_downgrade).await,
        FoeCmd::Read {
            name,
            output,
            password,
        } => foe_read(w, &name, output.as_deref(), password).await,
        FoeCmd::Password { new, password } => foe_password(w, password, new).await,
    }
}

async fn foe_password(w: &Where, current: u32, new: u32) -> Result<(), Failure> {
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let boot = sel.bootstrap()?;
    let md = s.md();
    master_test::foe::enter_boot_geometry(md, sel.station, boot).await?;
    let mut client = MailboxClient::new(md, sel.station, boot);
    let set = master_test::foe::set_password(&mut client, current, new).await;
    // Leave BOOT whatever happened.
    let back = master_test::foe::request_state(md, sel.station, 0x11).await;
    set.map_err(|e| {
        Failure::from(e).context(format!(
            "setting the FoE password of {} failed (the old one stays)",
            sel.label()
        ))
    })?;
    back?;
    outln!(
        "{}: FoE password set to {new:08X} (kept across power cycles); BOOT -> INIT",
        sel.label()
    );
    Ok(())
}

fn read_file(p: &Path) -> Result<Vec<u8>, Failure> {
    std::fs::read(p).map_err(|e| input(format!("cannot read {}: {e}", p.display())))
}

/// Checks the image against the live slave: what the slave would check,
/// before anything is sent.
fn check_image(image: &[u8], identity: DeviceIdentity) -> Result<EfwHeaderRepr, Failure> {
    let header =
        EfwHeaderRepr::parse(image).map_err(|e| input(format!("not a valid .efw image: {e}")))?;
    let mut v = EfwValidator::new(identity, usize::MAX);
    let checked = v
        .feed(image)
        .map(|_| ())
        .and_then(|()| v.finish().map(|_| ()));
    checked.map_err(|e| input(format!("the image does not fit this slave: {e}")))?;
    if header.payload_len == 0 {
        return Err(input("the image has an empty payload: nothing to update"));
    }
    Ok(header)
}

async fn running_version(c: &mut MailboxClient<'_>) -> Option<String> {
    let b = c.sdo_upload(0x100A, 0, false).await.ok()?;
    let end = b.iter().rposition(|&x| x != 0).map_or(0, |p| p + 1);
    Some(String::from_utf8_lossy(&b[..end]).into_owned())
}

async fn foe_write(
    w: &Where,
    file: &Path,
    password: u32,
    name: &str,
    allow_downgrade: bool,
) -> Result<(), Failure> {
    let image = read_file(file)?;
    if image.is_empty() {
        return Err(input(format!("{} is empty", file.display())));
    }
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let boot = sel.bootstrap()?;
    let identity = DeviceIdentity {
        vendor_id: sel.identity.vendor_id,
        product_code: sel.identity.product_id,
        revision: sel.identity.revision,
    };
    let header = check_image(&image, identity)?;
    let new = header.version.as_str().to_string();
    let md = s.md();
    let before = {
        let mut c = s.client(&sel)?;
        running_version(&mut c).await
    };
    match before.as_deref().map(|b| (b, compare_versions(&new, b))) {
        Some((b, Some(Ordering::Less))) if !allow_downgrade => {
            return Err(input(format!(
                "{} runs firmware {b}; the image has {new}, an older version: \
                 confirm the downgrade with --allow-downgrade",
                sel.label()
            )));
        }
        Some((b, Some(Ordering::Less))) => {
            eprintln!("warning: downgrading {} from {b} to {new}", sel.label());
        }
        Some((b, Some(Ordering::Equal))) => {
            eprintln!("note: {} already runs {b}; writing it again", sel.label());
        }
        Some((b, None)) => {
            eprintln!(
                "warning: cannot compare versions '{b}' (running) and '{new}' (image); \
                 no downgrade check"
            );
        }
        _ => {}
    }
    outln!(
        "{} runs firmware {}; image {} ({} bytes, version {new}); switching to BOOT",
        sel.label(),
        before.as_deref().unwrap_or("(unknown: no 0x100A)"),
        file.display(),
        image.len()
    );
    long_command();
    master_test::foe::enter_boot_geometry(md, sel.station, boot).await?;
    let mut client = MailboxClient::new(md, sel.station, boot);
    let bar = indicatif::ProgressBar::new(image.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {bytes}/{total_bytes} {binary_bytes_per_sec}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let start = std::time::Instant::now();
    let name = if allow_downgrade {
        downgrade_name(name)
    } else {
        name.to_string()
    };
    let sent = master_test::foe::write_cancellable(
        &mut client,
        &name,
        password,
        &image,
        &mut |done, _| bar.set_position(done as u64),
        stop_requested,
    )
    .await;
    bar.finish_and_clear();
    let completed = match sent {
        Err(e) if e.foe_code() == Some(0x8002) && !allow_downgrade => {
            let _ = master_test::foe::request_state(md, sel.station, 0x11).await;
            return Err(Failure::from(e).context(format!(
                "{} refused the image (anti-rollback: older than the last firmware it \
                 confirmed); confirm the downgrade with --allow-downgrade",
                sel.label()
            )));
        }
        Ok(c) => c,
        Err(e) => {
            // Leave BOOT whatever happened; the old firmware stays.
            let _ = master_test::foe::request_state(md, sel.station, 0x11).await;
            return Err(Failure::from(e).context(format!(
                "firmware download to {} failed (slave back in INIT, old firmware kept)",
                sel.label()
            )));
        }
    };
    master_test::foe::request_state(md, sel.station, 0x11).await?;
    if !completed {
        return Err(Failure::Interrupted(format!(
            "the download was aborted with a FoE error; {} is in INIT and keeps firmware {}",
            sel.label(),
            before.as_deref().unwrap_or("(unknown)")
        )));
    }
    let secs = start.elapsed().as_secs_f64();
    outln!(
        "downloaded {} bytes in {:.3} s ({:.1} MB/s); BOOT -> INIT",
        image.len(),
        secs,
        image.len() as f64 / secs / 1e6
    );
    match s.bus.power_cycle(sel.position) {
        Some(version) => {
            outln!("simulated power cycle: 0x100A SOFTWARE VERSION = {version}");
            if version != new {
                return Err(Failure::Refused(format!(
                    "after the power cycle the slave runs {version}, not {new}"
                )));
            }
        }
        None => outln!(
            "the bootloader installs the image at the slave's next power cycle; \
             then `sdo read 0x100A:00` shows {new}"
        ),
    }
    Ok(())
}

async fn foe_read(
    w: &Where,
    name: &str,
    output: Option<&Path>,
    password: u32,
) -> Result<(), Failure> {
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let mut c = s.client(&sel)?;
    let data = master_test::foe::read(&mut c, name, password).await?;
    match output {
        Some(p) => {
            std::fs::write(p, &data)
                .map_err(|e| input(format!("cannot write {}: {e}", p.display())))?;
            outln!("{} bytes written to {}", data.len(), p.display());
        }
        None => {
            let text = std::str::from_utf8(&data).ok().filter(|t| {
                t.chars()
                    .all(|c| !c.is_control() || c == '\n' || c == '\r' || c == '\t')
            });
            match text {
                Some(t) => output::bytes(t.as_bytes()),
                None if std::io::stdout().is_terminal() => {
                    return Err(input(format!(
                        "{name} is binary ({} bytes): write it to a file with -o FILE",
                        data.len()
                    )));
                }
                None => output::bytes(&data),
            }
        }
    }
    Ok(())
}

/// Runs a `firmware` command.
pub fn firmware(dev: &device_catalog::DeviceEntry, op: FirmwareCmd) -> Result<(), Failure> {
    let (binary, version, output, revision_min, revision_max, sign) = match op {
        FirmwareCmd::Keygen { output } => return keygen(&output),
        FirmwareCmd::Pack {
            binary,
            version,
            output,
            revision_min,
            revision_max,
            sign,
        } => (binary, version, output, revision_min, revision_max, sign),
    };
    use ecat_slave::firmware::{
        EFW_FLAG_SIGNED, EFW_HEADER_LEN, EFW_SIGNED_HEADER_LEN, FirmwareVersion, pack,
        set_signature, signed_message,
    };
    let key = sign.as_deref().map(read_key).transpose()?;
    if revision_min > revision_max {
        return Err(input(format!(
            "--revision-min {revision_min} is above --revision-max {revision_max}: \
             no revision could run the image"
        )));
    }
    let version_text = version;
    let version = FirmwareVersion::new(&version_text).ok_or_else(|| {
        input(format!(
            "--version must be 1 to 16 ASCII characters, got '{version_text}'"
        ))
    })?;
    let payload = read_file(&binary)?;
    if payload.is_empty() {
        return Err(input(format!(
            "{} is empty: an image needs a payload",
            binary.display()
        )));
    }
    let (header_len, flags) = match key {
        Some(_) => (EFW_SIGNED_HEADER_LEN, EFW_FLAG_SIGNED),
        None => (EFW_HEADER_LEN, 0),
    };
    let header = EfwHeaderRepr {
        header_len: header_len as u16,
        flags,
        vendor_id: dev.description.identity.vendor_id,
        product_code: dev.description.identity.product_code,
        revision_min,
        revision_max,
        version,
        payload_len: 0,
        payload_crc: 0,
    };
    let mut out = vec![0u8; payload.len() + 1024];
    let n = pack(&header, &payload, &mut out).map_err(|e| input(format!("cannot pack: {e}")))?;
    out.truncate(n);
    let signed = match &key {
        Some(kp) => {
            let message = signed_message(&out)
                .map_err(|e| input(format!("cannot sign: {e}")))?
                .concat();
            let signature = kp.sk.sign(&message, None);
            kp.pk
                .verify(&message, &signature)
                .map_err(|e| input(format!("the signature does not verify: {e}")))?;
            set_signature(&mut out, &signature).map_err(|e| input(format!("cannot sign: {e}")))?;
            format!(", signed by key {}", hex(&kp.pk[..]))
        }
        None => String::new(),
    };
    std::fs::write(&output, &out)
        .map_err(|e| input(format!("cannot write {}: {e}", output.display())))?;
    outln!(
        "{}: {} bytes ({} payload, {} version {}, revisions {revision_min}..={revision_max}{signed})",
        output.display(),
        n,
        payload.len(),
        dev.description.names.type_name,
        version.as_str()
    );
    Ok(())
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// An Ed25519 private key from a PEM PKCS#8 file.
fn read_key(path: &Path) -> Result<ed25519_compact::KeyPair, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| input(format!("cannot read the key {}: {e}", path.display())))?;
    ed25519_compact::KeyPair::from_pem(&text).map_err(|e| {
        input(format!(
            "{} is not an Ed25519 private key in PEM (PKCS#8, \"-----BEGIN PRIVATE KEY-----\"): {e}",
            path.display()
        ))
    })
}

/// `firmware keygen`: a fresh key pair from the system's random source.
fn keygen(output: &Path) -> Result<(), Failure> {
    use std::io::{Read as _, Write as _};
    let mut seed = [0u8; 32];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut seed))
        .map_err(|e| input(format!("cannot read /dev/urandom for a key: {e}")))?;
    let kp = ed25519_compact::KeyPair::from_seed(ed25519_compact::Seed::new(seed));
    seed.fill(0);
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::mode(&mut options, 0o600);
    let mut f = options.open(output).map_err(|e| {
        input(format!(
            "cannot create {} (an existing key is never overwritten): {e}",
            output.display()
        ))
    })?;
    f.write_all(kp.sk.to_pem().as_bytes())
        .map_err(|e| input(format!("cannot write {}: {e}", output.display())))?;
    let bytes: Vec<String> = kp.pk.iter().map(|b| format!("0x{b:02x}")).collect();
    outln!(
        "{}: Ed25519 private key (keep it secret)\npublic key {}\n\
         for the device description: foe_security: FoeSecurity {{ factory_password: 0, \
         public_key: Some([{}]) }}",
        output.display(),
        hex(&kp.pk[..]),
        bytes.join(", ")
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passwords_are_1_to_8_hex_digits() {
        assert_eq!(parse_password("00000000"), Ok(0));
        assert_eq!(parse_password("0x1234ABCD"), Ok(0x1234_ABCD));
        assert_eq!(parse_password("f"), Ok(15));
        for bad in ["", "0x", "123456789", "12G4", "-1"] {
            let e = parse_password(bad).unwrap_err();
            assert!(e.contains("1 to 8 hex digits"), "{bad}: {e}");
        }
    }

    #[test]
    fn versions_compare_by_their_numbers() {
        assert_eq!(compare_versions("1.10", "1.9"), Some(Ordering::Greater));
        assert_eq!(compare_versions("1.0", "1.0.0"), Some(Ordering::Equal));
        assert_eq!(compare_versions("v2", "1.9.9"), Some(Ordering::Greater));
        assert_eq!(compare_versions("10", "11"), Some(Ordering::Less));
        assert_eq!(compare_versions("beta", "1.0"), None);
    }

    #[test]
    fn the_downgrade_consent_is_the_efw_suffix_downgrade_efw() {
        assert_eq!(downgrade_name("firmware.efw"), "firmware.downgrade.efw");
        assert_eq!(downgrade_name("APP.EFW"), "APP.downgrade.efw");
        assert_eq!(downgrade_name("a.Downgrade.efw"), "a.Downgrade.efw");
        assert_eq!(downgrade_name("image"), "image.downgrade.efw");
    }

    #[test]
    fn images_are_checked_against_the_slave_before_sending() {
        let id = DeviceIdentity {
            vendor_id: pam_199_p_etc::VENDOR_ID,
            product_code: pam_199_p_etc::PRODUCT_CODE,
            revision: 1,
        };
        let good = master_test::foe::pam_image("12", 100);
        assert!(check_image(&good, id).is_ok());
        let Err(Failure::Input(m)) = check_image(&good[..50], id) else {
            panic!("truncated accepted");
        };
        assert!(
            m.contains("not a valid .efw") || m.contains("does not fit"),
            "{m}"
        );
        let other = DeviceIdentity {
            product_code: 1,
            ..id
        };
        assert!(check_image(&good, other).is_err());
        let empty = master_test::foe::efw_image(id.vendor_id, id.product_code, "12", &[]);
        let Err(Failure::Input(m)) = check_image(&empty, id) else {
            panic!("empty payload accepted");
        };
        assert!(m.contains("empty payload"), "{m}");
    }
}
