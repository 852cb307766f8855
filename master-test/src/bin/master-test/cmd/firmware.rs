//! `firmware pack/keygen`: `.efw` images and their signing keys (no bus).

use crate::failure::{Failure, input, read_file};
use crate::output::outln;
use crate::parse::parse_u32;
use device_catalog::DeviceEntry;
use ecat_slave::firmware::EfwHeaderRepr;
use std::path::{Path, PathBuf};

/// Options of `firmware`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(subcommand)]
    op: Op,
}

/// `firmware` subcommands.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Op {
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

/// Runs a `firmware` command for the device `dev` (`--device`).
pub fn run(dev: &DeviceEntry, args: Args) -> Result<(), Failure> {
    let (binary, version, output, revision_min, revision_max, sign) = match args.op {
        Op::Keygen { output } => return keygen(&output),
        Op::Pack {
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
