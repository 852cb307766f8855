//! Writing frames to a classic pcap file (link type 1, Ethernet) that
//! Wireshark's EtherCAT dissector decodes.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

/// pcap magic number for microsecond timestamps.
pub const MAGIC: u32 = 0xA1B2_C3D4;
/// Link type Ethernet.
pub const LINKTYPE_ETHERNET: u32 = 1;
/// Largest frame stored.
pub const SNAPLEN: u32 = 65_535;

/// A pcap writer.
pub struct PcapWriter<W: Write> {
    out: W,
}

impl PcapWriter<BufWriter<File>> {
    /// Creates (truncates) `path` and writes the pcap global header.
    pub fn create(path: &Path) -> io::Result<Self> {
        PcapWriter::new(BufWriter::new(File::create(path)?))
    }
}

impl<W: Write> PcapWriter<W> {
    /// Writes the global header to `out`.
    pub fn new(mut out: W) -> io::Result<Self> {
        out.write_all(&MAGIC.to_le_bytes())?;
        out.write_all(&2u16.to_le_bytes())?;
        out.write_all(&4u16.to_le_bytes())?;
        out.write_all(&0i32.to_le_bytes())?;
        out.write_all(&0u32.to_le_bytes())?;
        out.write_all(&SNAPLEN.to_le_bytes())?;
        out.write_all(&LINKTYPE_ETHERNET.to_le_bytes())?;
        Ok(PcapWriter { out })
    }

    /// Appends one frame stamped with the current wall-clock time.
    pub fn write_frame(&mut self, frame: &[u8]) -> io::Result<()> {
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default();
        self.write_frame_at(frame, now.as_secs() as u32, now.subsec_micros())
    }

    /// Appends one frame with an explicit timestamp.
    pub fn write_frame_at(&mut self, frame: &[u8], secs: u32, micros: u32) -> io::Result<()> {
        let len = u32::try_from(frame.len()).unwrap_or(u32::MAX);
        let incl = len.min(SNAPLEN);
        self.out.write_all(&secs.to_le_bytes())?;
        self.out.write_all(&micros.to_le_bytes())?;
        self.out.write_all(&incl.to_le_bytes())?;
        self.out.write_all(&len.to_le_bytes())?;
        self.out
            .write_all(frame.get(..incl as usize).unwrap_or(frame))
    }

    /// Flushes buffered frames.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// The underlying writer.
    pub fn into_inner(self) -> W {
        self.out
    }
}

/// One record read back from a pcap file (for tests and tools).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Record {
    /// Seconds.
    pub secs: u32,
    /// Microseconds.
    pub micros: u32,
    /// Frame bytes.
    pub data: Vec<u8>,
}

/// Errors reading a pcap file.
#[derive(Debug, thiserror::Error)]
pub enum PcapError {
    /// The file is shorter than its headers say.
    #[error("pcap truncated at byte {0}")]
    Truncated(usize),
    /// Not a little-endian microsecond pcap file.
    #[error("bad pcap magic {0:#010x}")]
    BadMagic(u32),
    /// Link type other than Ethernet.
    #[error("link type {0} is not Ethernet")]
    LinkType(u32),
}

/// Parses a whole pcap file written by [`PcapWriter`].
pub fn read_all(bytes: &[u8]) -> Result<Vec<Record>, PcapError> {
    let u32_at = |o: usize| -> Result<u32, PcapError> {
        bytes
            .get(o..o + 4)
            .and_then(|b| <[u8; 4]>::try_from(b).ok())
            .map(u32::from_le_bytes)
            .ok_or(PcapError::Truncated(o))
    };
    let magic = u32_at(0)?;
    if magic != MAGIC {
        return Err(PcapError::BadMagic(magic));
    }
    let link = u32_at(20)?;
    if link != LINKTYPE_ETHERNET {
        return Err(PcapError::LinkType(link));
    }
    let mut records = Vec::new();
    let mut o = 24;
    while o < bytes.len() {
        let secs = u32_at(o)?;
        let micros = u32_at(o + 4)?;
        let incl = u32_at(o + 8)? as usize;
        let data = bytes
            .get(o + 16..o + 16 + incl)
            .ok_or(PcapError::Truncated(o + 16))?
            .to_vec();
        records.push(Record { secs, micros, data });
        o += 16 + incl;
    }
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_frames_read_back_with_headers() {
        let mut w = PcapWriter::new(Vec::new()).unwrap();
        w.write_frame_at(&[1, 2, 3], 10, 20).unwrap();
        w.write_frame_at(&[0x88; 60], 11, 0).unwrap();
        let bytes = w.into_inner();
        assert_eq!(&bytes[..4], &[0xD4, 0xC3, 0xB2, 0xA1]);
        assert_eq!(bytes.len(), 24 + 16 + 3 + 16 + 60);
        let recs = read_all(&bytes).unwrap();
        assert_eq!(recs.len(), 2);
        assert_eq!(
            recs[0],
            Record {
                secs: 10,
                micros: 20,
                data: vec![1, 2, 3]
            }
        );
        assert_eq!(recs[1].data.len(), 60);
    }

    #[test]
    fn truncated_and_foreign_files_are_errors_not_panics() {
        assert!(matches!(read_all(&[]), Err(PcapError::Truncated(0))));
        assert!(matches!(read_all(&[0; 24]), Err(PcapError::BadMagic(0))));
        let mut w = PcapWriter::new(Vec::new()).unwrap();
        w.write_frame_at(&[1, 2, 3, 4], 0, 0).unwrap();
        let mut bytes = w.into_inner();
        bytes.truncate(bytes.len() - 2);
        assert!(matches!(read_all(&bytes), Err(PcapError::Truncated(40))));
    }
}
