//! `eeprom read/write`: the slave's SII EEPROM over the ESC's EEPROM
//! interface.

use crate::failure::{Failure, input};
use crate::output::{self, outln};
use crate::target::{Session, Where};
use ecat_slave::sii::SiiReader;
use master_test::eeprom;
use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};

/// Options of `eeprom`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(subcommand)]
    op: Op,
}

/// How an SII image is written out.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Offset and 16 bytes per line, for people.
    Dump,
    /// The raw bytes (never to a terminal).
    Bin,
    /// Intel HEX text.
    Ihex,
}

/// `eeprom` subcommands.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Op {
    /// Read the whole SII (header and every category up to the end
    /// marker).
    Read {
        /// Write the image to this file (binary; Intel HEX if it ends in
        /// .hex) instead of showing a hex dump.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Output format (default: dump on standard output, bin or ihex by
        /// the extension of --output).
        #[arg(long, value_enum)]
        format: Option<Format>,
    },
    /// Write an SII image (binary or Intel HEX) and verify it by reading
    /// it back. The header checksum and the identity must match the live
    /// slave unless --force.
    Write {
        /// The image (`esi sii -o FILE`, `eeprom read -o FILE`).
        file: PathBuf,
        /// Write even with a bad header checksum or another identity.
        #[arg(long)]
        force: bool,
    },
}

/// A hex dump: offset, 16 bytes.
fn dump(image: &[u8]) -> String {
    let mut out = String::new();
    for (n, chunk) in image.chunks(16).enumerate() {
        let bytes: Vec<String> = chunk.iter().map(|b| format!("{b:02x}")).collect();
        out.push_str(&format!("{:06x}  {}\n", n * 16, bytes.join(" ")));
    }
    out
}

/// Runs an `eeprom` command.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    match args.op {
        Op::Read { output, format } => read(w, output.as_deref(), format).await,
        Op::Write { file, force } => write(w, &file, force).await,
    }
}

async fn read(w: &Where, output: Option<&Path>, format: Option<Format>) -> Result<(), Failure> {
    let by_extension = |p: &Path| {
        if p.extension().is_some_and(|e| e == "hex" || e == "ihex") {
            Format::Ihex
        } else {
            Format::Bin
        }
    };
    let format = format.unwrap_or_else(|| output.map_or(Format::Dump, by_extension));
    if output.is_none() && format == Format::Bin && std::io::stdout().is_terminal() {
        return Err(input(
            "refusing to write binary to a terminal: use -o FILE, a pipe, or --format dump/ihex",
        ));
    }
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let image = eeprom::read_all(s.md(), sel.station).await?;
    let data = match format {
        Format::Dump => dump(&image).into_bytes(),
        Format::Bin => image.clone(),
        Format::Ihex => ecat_esi::ihex::encode(&image).into_bytes(),
    };
    match output {
        Some(p) => {
            std::fs::write(p, &data)
                .map_err(|e| input(format!("cannot write {}: {e}", p.display())))?;
            outln!(
                "{}: SII of {}, {} bytes",
                p.display(),
                sel.label(),
                image.len()
            );
        }
        None => output::bytes(&data),
    }
    Ok(())
}

/// Reads an SII image file: Intel HEX if it starts with `:`, else binary.
pub fn read_image(p: &Path) -> Result<Vec<u8>, Failure> {
    let raw = std::fs::read(p).map_err(|e| input(format!("cannot read {}: {e}", p.display())))?;
    if raw.first() == Some(&b':') {
        let text = String::from_utf8(raw)
            .map_err(|_| input(format!("{}: Intel HEX that is not text", p.display())))?;
        return ecat_esi::ihex::decode(&text)
            .map_err(|e| input(format!("{}: bad Intel HEX: {e}", p.display())));
    }
    Ok(raw)
}

async fn write(w: &Where, file: &Path, force: bool) -> Result<(), Failure> {
    let image = read_image(file)?;
    let r = SiiReader::new(&image)
        .map_err(|e| input(format!("{}: not an SII image: {e}", file.display())))?;
    if image.len() % 2 != 0 {
        return Err(input(format!(
            "{}: {} bytes, not a whole number of 16-bit words",
            file.display(),
            image.len()
        )));
    }
    if !r.crc_ok() && !force {
        return Err(input(format!(
            "{}: header checksum (word 0x07) is {:#04x}, the header computes {:#04x}; \
             an ESC would refuse to load it (--force writes it anyway)",
            file.display(),
            r.stored_crc(),
            r.computed_crc()
        )));
    }
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let id = r.identity();
    if (id.vendor_id, id.product_code) != (sel.identity.vendor_id, sel.identity.product_id)
        && !force
    {
        return Err(input(format!(
            "{} is vendor {:#x} product {:#x}, the image is vendor {:#x} product {:#x} \
             (--force writes it anyway)",
            sel.label(),
            sel.identity.vendor_id,
            sel.identity.product_id,
            id.vendor_id,
            id.product_code
        )));
    }
    let bar = indicatif::ProgressBar::new(image.len() as u64 / 2);
    eeprom::write_with(s.md(), sel.station, &image, |done, _| {
        bar.set_position(done as u64)
    })
    .await?;
    bar.finish_and_clear();
    outln!(
        "wrote and verified {} bytes of {} into the SII of {}; the ESC uses it after \
         its next EEPROM reload or power cycle",
        image.len(),
        file.display(),
        sel.label()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dumps_show_offsets_and_16_bytes_a_line() {
        let d = dump(&(0u8..20).collect::<Vec<_>>());
        let lines: Vec<&str> = d.lines().collect();
        assert_eq!(lines.len(), 2);
        assert!(lines[0].starts_with("000000  00 01 02"));
        assert_eq!(lines[1], "000010  10 11 12 13");
    }
}
