//! Writing frames to a classic pcap file (little-endian, microsecond
//! timestamps, link type 1 Ethernet) that Wireshark's EtherCAT dissector
//! decodes, and reading such files back; the file format is the
//! [`pcap_file`] crate's.

use std::borrow::Cow;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use byteorder_slice::LittleEndian;
use pcap_file::pcap::{PcapHeader, PcapPacket, PcapParser};
use pcap_file::{DataLink, Endianness, TsResolution};

/// pcap magic number for microsecond timestamps.
pub const MAGIC: u32 = 0xA1B2_C3D4;
/// Link type Ethernet.
pub const LINKTYPE_ETHERNET: u32 = 1;
/// Largest frame stored.
pub const SNAPLEN: u32 = 65_535;

/// The global header every file starts with.
fn header() -> PcapHeader {
    PcapHeader {
        version_major: 2,
        version_minor: 4,
        ts_correction: 0,
        ts_accuracy: 0,
        snaplen: SNAPLEN,
        datalink: DataLink::ETHERNET,
        ts_resolution: TsResolution::MicroSecond,
        endianness: Endianness::Little,
    }
}

/// A pcap writer. The header and records are encoded by [`pcap_file`];
/// the writer itself stays reachable (for [`PcapWriter::flush`]), which
/// `pcap_file::pcap::PcapWriter` does not offer.
pub struct PcapWriter<W: Write> {
    out: W,
}

/// A `pcap_file` error as an I/O error (the writers' error type).
fn io_error(e: pcap_file::PcapError) -> io::Error {
    match e {
        pcap_file::PcapError::IoError(e) => e,
        other => io::Error::new(io::ErrorKind::InvalidInput, other),
    }
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
        header().write_to(&mut out).map_err(io_error)?;
        Ok(PcapWriter { out })
    }

    /// Appends one frame stamped with the current wall-clock time.
    pub fn write_frame(&mut self, frame: &[u8]) -> io::Result<()> {
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default();
        let secs = u32::try_from(now.as_secs()).unwrap_or(u32::MAX);
        self.write_frame_at(frame, secs, now.subsec_micros())
    }

    /// Appends one frame with an explicit timestamp; a frame longer than
    /// [`SNAPLEN`] is cut there (its original length is recorded).
    pub fn write_frame_at(&mut self, frame: &[u8], secs: u32, micros: u32) -> io::Result<()> {
        let orig_len = u32::try_from(frame.len()).unwrap_or(u32::MAX);
        let incl = usize::try_from(orig_len.min(SNAPLEN)).unwrap_or(usize::MAX);
        let packet = PcapPacket {
            timestamp: Duration::from_secs(u64::from(secs))
                + Duration::from_micros(u64::from(micros)),
            orig_len,
            data: Cow::Borrowed(frame.get(..incl).unwrap_or(frame)),
        };
        packet
            .write_to::<_, LittleEndian>(&mut self.out, TsResolution::MicroSecond, SNAPLEN)
            .map(|_| ())
            .map_err(io_error)
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
    /// The file ends inside the global header (at 0) or inside the record
    /// that starts at this byte.
    #[error("pcap truncated in the header or record at byte {0}")]
    Truncated(usize),
    /// Not a pcap file (the first four bytes, read little-endian).
    #[error("bad pcap magic {0:#010x}")]
    BadMagic(u32),
    /// Link type other than Ethernet.
    #[error("link type {0} is not Ethernet")]
    LinkType(u32),
    /// A header or record field `pcap_file` refuses (a length beyond the
    /// snap length, a timestamp fraction of a second or more).
    #[error("malformed pcap record at byte {at}: {source}")]
    Malformed {
        /// Offset of the record.
        at: usize,
        /// What `pcap_file` found.
        #[source]
        source: pcap_file::PcapError,
    },
}

/// Parses a whole pcap file (as [`PcapWriter`] writes it; `pcap_file` also
/// reads big-endian and nanosecond files) into its Ethernet frames.
pub fn read_all(bytes: &[u8]) -> Result<Vec<Record>, PcapError> {
    let error_at = |at: usize, e: pcap_file::PcapError| match e {
        pcap_file::PcapError::IncompleteBuffer => PcapError::Truncated(at),
        source => PcapError::Malformed { at, source },
    };
    let (mut rest, parser) = PcapParser::new(bytes).map_err(|e| match e {
        pcap_file::PcapError::InvalidField(_) => {
            let magic = bytes
                .get(..4)
                .and_then(|b| <[u8; 4]>::try_from(b).ok())
                .map_or(0, u32::from_le_bytes);
            PcapError::BadMagic(magic)
        }
        e => error_at(0, e),
    })?;
    let link = parser.header().datalink;
    if link != DataLink::ETHERNET {
        return Err(PcapError::LinkType(u32::from(link)));
    }
    let mut records = Vec::new();
    while !rest.is_empty() {
        let at = bytes.len() - rest.len();
        let (next, packet) = parser.next_packet(rest).map_err(|e| error_at(at, e))?;
        records.push(Record {
            secs: u32::try_from(packet.timestamp.as_secs()).unwrap_or(u32::MAX),
            micros: packet.timestamp.subsec_micros(),
            data: packet.data.into_owned(),
        });
        rest = next;
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
        assert_eq!(&bytes[..4], &MAGIC.to_le_bytes());
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

    /// The bytes are the classic format field by field (what the hand-written
    /// writer produced and tshark reads).
    #[test]
    fn the_layout_is_classic_little_endian_pcap() {
        let mut w = PcapWriter::new(Vec::new()).unwrap();
        w.write_frame_at(&[0xAB, 0xCD], 0x0102_0304, 999_999)
            .unwrap();
        let bytes = w.into_inner();
        let mut expected = Vec::new();
        expected.extend_from_slice(&MAGIC.to_le_bytes());
        expected.extend_from_slice(&2u16.to_le_bytes());
        expected.extend_from_slice(&4u16.to_le_bytes());
        expected.extend_from_slice(&0i32.to_le_bytes());
        expected.extend_from_slice(&0u32.to_le_bytes());
        expected.extend_from_slice(&SNAPLEN.to_le_bytes());
        expected.extend_from_slice(&LINKTYPE_ETHERNET.to_le_bytes());
        expected.extend_from_slice(&0x0102_0304u32.to_le_bytes());
        expected.extend_from_slice(&999_999u32.to_le_bytes());
        expected.extend_from_slice(&2u32.to_le_bytes());
        expected.extend_from_slice(&2u32.to_le_bytes());
        expected.extend_from_slice(&[0xAB, 0xCD]);
        assert_eq!(bytes, expected);
    }

    #[test]
    fn truncated_and_foreign_files_are_errors_not_panics() {
        assert!(matches!(read_all(&[]), Err(PcapError::Truncated(0))));
        assert!(matches!(read_all(&[0; 24]), Err(PcapError::BadMagic(0))));
        let mut w = PcapWriter::new(Vec::new()).unwrap();
        w.write_frame_at(&[1, 2, 3, 4], 0, 0).unwrap();
        let mut bytes = w.into_inner();
        bytes.truncate(bytes.len() - 2);
        assert!(matches!(read_all(&bytes), Err(PcapError::Truncated(24))));
        let mut w = PcapWriter::new(Vec::new()).unwrap();
        w.write_frame_at(&[1], 0, 0).unwrap();
        let mut bytes = w.into_inner();
        bytes[20] = 113; // Linux cooked capture
        assert!(matches!(read_all(&bytes), Err(PcapError::LinkType(113))));
    }
}
