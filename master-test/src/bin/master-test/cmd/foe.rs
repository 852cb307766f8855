//! `foe write/password/read`: file access over EtherCAT, the firmware
//! update in BOOT.

use crate::failure::{Failure, input, read_file};
use crate::output::{self, long_command, outln, stop_requested};
use crate::parse::parse_password;
use crate::target::{Session, Where};
use ecat_slave::firmware::{DeviceIdentity, EfwHeaderRepr, EfwValidator};
use master_test::mailbox::MailboxClient;
use std::cmp::Ordering;
use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};

/// Options of `foe`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(subcommand)]
    op: Op,
}

/// `foe` subcommands.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Op {
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
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    match args.op {
        Op::Write {
            file,
            password,
            name,
            allow_downgrade,
        } => foe_write(w, &file, password, &name, allow_downgrade).await,
        Op::Read {
            name,
            output,
            password,
        } => foe_read(w, &name, output.as_deref(), password).await,
        Op::Password { new, password } => foe_password(w, password, new).await,
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

#[cfg(test)]
mod tests {
    use super::*;

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
