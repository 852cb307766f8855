//! The slave's SII EEPROM through the ESC's EEPROM interface (ETG.1000.4
//! registers 0x0500-0x050F), as a master's EEPROM tool reads and writes it.

use crate::mailbox::{ClientError, MailboxGeometry};
use crate::registers;
use ecat_slave::sii::SiiReader;
use ethercrab::{Command, MainDevice};
use std::time::{Duration, Instant};

const CONTROL: u16 = registers::SII_CONTROL;
const DATA: u16 = registers::SII_DATA;
/// Busy (bit 15) of the control/status word.
const BUSY: u16 = 0x8000;
/// Error bits 11-14 of the control/status word (checksum, device info,
/// command, write enable).
const ERRORS: u16 = 0x7800;
/// Words of the SII header (ETG.2010 Table 2) before the categories.
pub const HEADER_WORDS: usize = 0x40;
/// Most words a SII can hold (the address is 16 bits in words here).
const MAX_WORDS: usize = 0x1_0000;

/// Errors of the EEPROM interface.
#[derive(Debug, thiserror::Error)]
pub enum EepromError {
    /// The frame exchange failed.
    #[error(transparent)]
    Client(#[from] ClientError),
    /// The ESC set an error bit in 0x0502 (the device refused the access).
    #[error(
        "the EEPROM interface reports an error (0x0502 = {status:#06x}: {})",
        error_text(*status)
    )]
    Refused {
        /// The EEPROM control/status word.
        status: u16,
    },
    /// What was read back differs from what was written.
    #[error("verify failed: word {word:#06x} reads {read:#06x}, {written:#06x} was written")]
    Verify {
        /// Word address.
        word: usize,
        /// Value read back.
        read: u16,
        /// Value written.
        written: u16,
    },
}

impl EepromError {
    /// Whether the device said no (as opposed to a communication failure).
    pub fn refused_by_device(&self) -> bool {
        matches!(
            self,
            EepromError::Refused { .. } | EepromError::Verify { .. }
        )
    }
}

fn error_text(status: u16) -> &'static str {
    if status & 0x0800 != 0 {
        "checksum error"
    } else if status & 0x1000 != 0 {
        "EEPROM not loaded"
    } else if status & 0x2000 != 0 {
        "missing acknowledge or invalid command"
    } else if status & 0x4000 != 0 {
        "write without write enable"
    } else {
        "unknown"
    }
}

impl From<ethercrab::error::Error> for EepromError {
    fn from(e: ethercrab::error::Error) -> Self {
        EepromError::Client(ClientError::Ethercrab(e))
    }
}

async fn wait_idle(md: &MainDevice<'_>, station: u16) -> Result<u16, EepromError> {
    let start = Instant::now();
    let limit = Duration::from_millis(500);
    loop {
        let st: u16 = Command::fprd(station, CONTROL).receive(md).await?;
        if st & BUSY == 0 {
            if st & ERRORS & !0x0800 != 0 {
                return Err(EepromError::Refused { status: st });
            }
            return Ok(st);
        }
        if start.elapsed() > limit {
            return Err(ClientError::Timeout(limit).into());
        }
        smol::Timer::after(Duration::from_micros(100)).await;
    }
}

/// Reads `words` 16-bit words of the SII from word `from` (4 or 8 bytes
/// per access, as the ESC offers).
pub async fn read_words(
    md: &MainDevice<'_>,
    station: u16,
    from: usize,
    words: usize,
) -> Result<Vec<u8>, EepromError> {
    let mut out = Vec::with_capacity(words * 2);
    while out.len() < words * 2 {
        let word = (from + out.len() / 2) as u32;
        let st = wait_idle(md, station).await?;
        let chunk = if st & 0x0040 != 0 { 8 } else { 4 };
        let mut cmd = [0u8; 6];
        cmd[1] = 0x01; // read
        cmd[2..6].copy_from_slice(&word.to_le_bytes());
        Command::fpwr(station, CONTROL).send(md, cmd).await?;
        wait_idle(md, station).await?;
        let data = Command::fprd(station, DATA)
            .receive_slice(md, chunk as u16)
            .await?;
        out.extend_from_slice(&data);
    }
    out.truncate(words * 2);
    Ok(out)
}

/// Reads `words` words from word 0.
pub async fn read(md: &MainDevice<'_>, station: u16, words: usize) -> Result<Vec<u8>, EepromError> {
    read_words(md, station, 0, words).await
}

/// Reads the SII header (words 0x00-0x3F).
pub async fn read_header(md: &MainDevice<'_>, station: u16) -> Result<Vec<u8>, EepromError> {
    read(md, station, HEADER_WORDS).await
}

/// Reads the whole SII image: the header, then the category chain up to
/// and including the end marker (0xFFFF), or up to the size the header
/// declares if the chain does not end.
pub async fn read_all(md: &MainDevice<'_>, station: u16) -> Result<Vec<u8>, EepromError> {
    let mut image = read_header(md, station).await?;
    let declared = SiiReader::new(&image)
        .map(|r| r.eeprom_size_bytes() as usize / 2)
        .unwrap_or(HEADER_WORDS)
        .clamp(HEADER_WORDS, MAX_WORDS);
    let mut word = HEADER_WORDS;
    while word + 2 <= declared {
        let head = read_words(md, station, word, 2).await?;
        image.extend_from_slice(&head);
        let kind = u16::from_le_bytes([head[0], head[1]]);
        if kind == 0xFFFF {
            break;
        }
        let len = usize::from(u16::from_le_bytes([head[2], head[3]]));
        let len = len.min(declared.saturating_sub(word + 2));
        if len > 0 {
            image.extend(read_words(md, station, word + 2, len).await?);
        }
        word += 2 + len;
    }
    Ok(image)
}

/// Writes `image` into the SII word by word from word 0 (write access
/// enabled with each command, as the ESC requires), then reads it back
/// and compares.
pub async fn write(md: &MainDevice<'_>, station: u16, image: &[u8]) -> Result<(), EepromError> {
    write_with(md, station, image, |_, _| {}).await
}

/// [`write()`] reporting (words written, total words) after each word.
pub async fn write_with(
    md: &MainDevice<'_>,
    station: u16,
    image: &[u8],
    mut progress: impl FnMut(usize, usize),
) -> Result<(), EepromError> {
    let total = image.len().div_ceil(2);
    for (word, pair) in image.chunks(2).enumerate() {
        wait_idle(md, station).await?;
        let v = [pair[0], pair.get(1).copied().unwrap_or(0xFF)];
        Command::fpwr(station, DATA).send(md, v).await?;
        let mut cmd = [0u8; 6];
        cmd[0] = 0x01; // write enable
        cmd[1] = 0x02; // write
        cmd[2..6].copy_from_slice(&(word as u32).to_le_bytes());
        Command::fpwr(station, CONTROL).send(md, cmd).await?;
        progress(word + 1, total);
    }
    wait_idle(md, station).await?;
    let back = read(md, station, total).await?;
    for (word, (w, r)) in image.chunks(2).zip(back.chunks(2)).enumerate() {
        let written = u16::from_le_bytes([w[0], w.get(1).copied().unwrap_or(0xFF)]);
        let read = u16::from_le_bytes([r[0], r.get(1).copied().unwrap_or(0)]);
        if written != read {
            return Err(EepromError::Verify {
                word,
                read,
                written,
            });
        }
    }
    Ok(())
}

/// Standard and bootstrap mailbox of the SII header `header` (words
/// 0x14-0x1B), `None` where the header declares none.
pub fn mailboxes(header: &[u8]) -> (Option<MailboxGeometry>, Option<MailboxGeometry>) {
    let Ok(r) = SiiReader::new(header) else {
        return (None, None);
    };
    let geometry = |m: ecat_slave::sii::SiiMailbox| {
        (m.rx_size > 0 && m.tx_size > 0).then_some(MailboxGeometry {
            out: (m.rx_offset, m.rx_size),
            inp: (m.tx_offset, m.tx_size),
        })
    };
    (
        geometry(r.standard_mailbox()),
        geometry(r.bootstrap_mailbox()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mailboxes_come_from_sii_words_0x14_to_0x1b() {
        let image = ecat_esi::sii_image(&pam_199_p_etc::DEVICE);
        let (std, boot) = mailboxes(&image[..128]);
        assert_eq!(std, Some(MailboxGeometry::standard()));
        assert_eq!(boot, Some(MailboxGeometry::bootstrap()));
        let mut none = image[..128].to_vec();
        none[0x14 * 2..0x1C * 2].fill(0);
        assert_eq!(mailboxes(&none), (None, None));
        assert_eq!(mailboxes(&[0u8; 10]), (None, None));
    }

    #[test]
    fn error_bits_are_named() {
        assert_eq!(error_text(0x4000), "write without write enable");
        assert_eq!(error_text(0x2000), "missing acknowledge or invalid command");
        assert_eq!(error_text(0x0800), "checksum error");
    }
}
