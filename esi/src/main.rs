//! `esi`: generate a device's ESI XML and SII image (the PAM-199-P-ETC by
//! default, any device of the catalog with `--device`), inspect SII images
//! and cross-check an ESI against an SII.
//!
//! Exit status (the scheme of every tool of the workspace): 0 done (also
//! when the reader of the output goes away), 1 `check` found mismatches or
//! `inspect` found problems, 2 usage or input error (a file that cannot be
//! read, parsed or written).

use device_catalog::exit::Exit;
use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use ecat_esi::{check, esi, ihex, inspect};

const AFTER_HELP: &str = "\
Exit status:
  0    done (also when the reader of the output goes away, e.g. `| head`)
  1    `check` found mismatches, or `inspect` found problems in the image
  2    usage or input error (a file that cannot be read, parsed or written)";

/// ESI and SII tooling for the devices of the ecat-slave catalog.
#[derive(Debug, Parser)]
#[command(name = "esi", version, about, after_help = AFTER_HELP)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Write the ESI XML (stdout without -o).
    Generate {
        /// Output file, e.g. PAM-199-P-ETC.xml.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// The device (pam, io8, ...; `esi devices` lists them).
        #[arg(long, default_value = "pam")]
        device: String,
    },
    /// List the devices of the catalog.
    Devices,
    /// Write the SII EEPROM image (binary; Intel HEX with --hex). Binary
    /// goes to a file or a pipe, never to a terminal.
    Sii {
        /// The device (pam, io8, ...).
        #[arg(long, default_value = "pam")]
        device: String,
        /// Output file, e.g. eeprom.bin (stdout without -o).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Write Intel HEX instead of binary.
        #[arg(long)]
        hex: bool,
    },
    /// Decode an SII image (binary, or Intel HEX starting with ':'); exit 1
    /// when the image has problems (they are listed).
    Inspect {
        /// The image file.
        file: PathBuf,
        /// Print JSON instead of the listing.
        #[arg(long)]
        json: bool,
    },
    /// Cross-check an ESI file against an SII image; exit 1 on mismatch.
    Check {
        /// The ESI XML file.
        esi: PathBuf,
        /// The SII image (binary or Intel HEX).
        sii: PathBuf,
    },
}

/// A failure that ends the program with exit code 2.
struct Failure(String);

fn read(path: &Path) -> Result<Vec<u8>, Failure> {
    std::fs::read(path).map_err(|e| Failure(format!("cannot read {}: {e}", path.display())))
}

/// Reads an SII image: Intel HEX if the file starts with ':', else binary.
fn read_image(path: &Path) -> Result<Vec<u8>, Failure> {
    let bytes = read(path)?;
    if bytes.first() == Some(&b':') {
        let text = String::from_utf8(bytes)
            .map_err(|_| Failure(format!("{}: Intel HEX is not text", path.display())))?;
        ihex::decode(&text)
            .map_err(|e| Failure(format!("{}: invalid Intel HEX: {e}", path.display())))
    } else {
        Ok(bytes)
    }
}

fn write(path: Option<&Path>, data: &[u8]) -> Result<(), Failure> {
    match path {
        Some(p) => std::fs::write(p, data)
            .map_err(|e| Failure(format!("cannot write {}: {e}", p.display()))),
        None => {
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            match out.write_all(data).and_then(|()| out.flush()) {
                // `esi generate | head`: the reader went away; not an error.
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
                r => r.map_err(|e| Failure(format!("cannot write to stdout: {e}"))),
            }
        }
    }
}

/// Whether `data` starts like an XML document (after a BOM and blanks).
fn looks_like_xml(data: &[u8]) -> bool {
    let data = data.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(data);
    data.iter()
        .find(|b| !b.is_ascii_whitespace())
        .is_some_and(|&b| b == b'<')
}

fn find(name: &str) -> Result<&'static device_catalog::DeviceEntry, Failure> {
    device_catalog::find(name).map_err(|e| Failure(e.to_string()))
}

fn run(cli: Cli) -> Result<ExitCode, Failure> {
    match cli.command {
        Command::Generate { output, device } => {
            let dev = find(&device)?;
            let xml = esi::generate(dev.description)
                .map_err(|e| Failure(format!("cannot generate the ESI: {e}")))?;
            write(output.as_deref(), &xml)?;
        }
        Command::Devices => {
            let mut text = String::new();
            for d in device_catalog::DEVICES {
                let n = &d.description.names;
                text.push_str(&format!("{:<6} {:<16} {}\n", d.key, n.type_name, d.summary));
            }
            write(None, text.as_bytes())?;
        }
        Command::Sii {
            output,
            hex,
            device,
        } => {
            if output.is_none() && !hex && std::io::stdout().is_terminal() {
                return Err(Failure(
                    "refusing to write a binary image to a terminal: use -o FILE, --hex, \
                     or a pipe"
                        .into(),
                ));
            }
            let image = ecat_esi::sii_image(find(&device)?.description);
            let data = if hex {
                ihex::encode(&image).into_bytes()
            } else {
                image
            };
            write(output.as_deref(), &data)?;
        }
        Command::Inspect { file, json } => {
            let image = read_image(&file)?;
            if looks_like_xml(&image) {
                return Err(Failure(format!(
                    "{} is XML (an ESI file?), not an SII image: compare an ESI with an \
                     image with `esi check ESI SII`",
                    file.display()
                )));
            }
            let report = inspect::inspect(&image)
                .map_err(|e| Failure(format!("{}: not an SII image: {e}", file.display())))?;
            let text = if json {
                report.to_json() + "\n"
            } else {
                report.to_text()
            };
            write(None, text.as_bytes())?;
            if !report.problems.is_empty() {
                eprintln!(
                    "esi: {}: {} problem(s) in the image",
                    file.display(),
                    report.problems.len()
                );
                return Ok(Exit::Refused.into());
            }
        }
        Command::Check { esi, sii } => {
            let xml = String::from_utf8(read(&esi)?).map_err(|_| {
                Failure(format!(
                    "{}: not an ESI XML file (not UTF-8 text)",
                    esi.display()
                ))
            })?;
            let image = read_image(&sii)?;
            let mismatches = check::check(&xml, &image).map_err(|e| {
                Failure(format!(
                    "cannot check {} against {}: {e}",
                    esi.display(),
                    sii.display()
                ))
            })?;
            let mut text = String::new();
            if mismatches.is_empty() {
                text.push_str(&format!("{} and {} agree\n", esi.display(), sii.display()));
            } else {
                for m in &mismatches {
                    text.push_str(&format!("{m}\n"));
                }
                text.push_str(&format!("{} mismatch(es)\n", mismatches.len()));
            }
            write(None, text.as_bytes())?;
            if !mismatches.is_empty() {
                return Ok(Exit::Refused.into());
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(Failure(msg)) => {
            eprintln!("esi: {msg}");
            Exit::Input.into()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_is_told_apart_from_sii_images() {
        assert!(looks_like_xml(b"<?xml version=\"1.0\"?><EtherCATInfo/>"));
        assert!(looks_like_xml(b"\xEF\xBB\xBF  \n<EtherCATInfo/>"));
        assert!(!looks_like_xml(&[0x05, 0x00, 0x00]));
        assert!(!looks_like_xml(b""));
        assert!(!looks_like_xml(b":10000000"));
    }
}
