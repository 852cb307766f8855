//! Building EtherCAT frames datagram by datagram (ETG.1000.4 clause 5).
//!
//! Used by tests, benchmarks and tools that talk to an ESC without a
//! master; slaves never build frames, they modify them in place.

use super::WireError;
use super::ecat::{Command, Datagram, EcatFrame, FrameType};
use super::ethernet::{ETHERTYPE_ETHERCAT, EthernetFrame};
use core::ops::Range;

/// Offset of the first datagram in an Ethernet frame (Ethernet header +
/// EtherCAT header).
pub const FIRST_DATAGRAM: usize = 14 + 2;

/// Writes an EtherCAT frame into a buffer, one datagram at a time.
#[derive(Debug)]
pub struct FrameBuilder<'a> {
    buf: &'a mut [u8],
    len: usize,
    last: Option<usize>,
}

impl<'a> FrameBuilder<'a> {
    /// Starts a frame in `buf` sent from `src` to the broadcast address.
    pub fn new(buf: &'a mut [u8], src: [u8; 6]) -> Result<Self, WireError> {
        if buf.len() < FIRST_DATAGRAM {
            return Err(WireError::Truncated);
        }
        let mut eth = EthernetFrame::new_unchecked(&mut *buf);
        eth.set_dst_addr([0xFF; 6]);
        eth.set_src_addr(src);
        eth.set_ethertype(ETHERTYPE_ETHERCAT);
        Ok(FrameBuilder {
            buf,
            len: FIRST_DATAGRAM,
            last: None,
        })
    }

    /// Appends a datagram. `address` is the logical address, or for
    /// physical commands `adp | (ado << 16)`. Returns the byte range of the
    /// datagram's data inside the frame.
    pub fn push(
        &mut self,
        command: Command,
        address: u32,
        data: &[u8],
    ) -> Result<Range<usize>, WireError> {
        let total = Datagram::<()>::total_len_for(data.len());
        let end = self.len.checked_add(total).ok_or(WireError::Truncated)?;
        let data_len = u16::try_from(data.len()).map_err(|_| WireError::Truncated)?;
        // The EtherCAT header's 11-bit length bounds the whole payload.
        if end > self.buf.len() || end - FIRST_DATAGRAM > usize::from(super::ecat::MAX_LENGTH) {
            return Err(WireError::Truncated);
        }
        if let Some(prev) = self.last {
            let bytes = self.buf.get_mut(prev..).ok_or(WireError::Truncated)?;
            Datagram::new_unchecked(bytes).set_more_follows(true);
        }
        let bytes = self
            .buf
            .get_mut(self.len..end)
            .ok_or(WireError::Truncated)?;
        bytes.fill(0);
        let mut dg = Datagram::new_unchecked(bytes);
        dg.set_command(command);
        dg.set_logical_address(address);
        dg.set_data_len(data_len);
        dg.data_mut().copy_from_slice(data);
        let start = self.len + Datagram::<()>::HEADER_LEN;
        self.last = Some(self.len);
        self.len = end;
        Ok(start..start + data.len())
    }

    /// Writes the EtherCAT header and returns the frame length.
    pub fn finish(self) -> usize {
        let payload = (self.len - FIRST_DATAGRAM) as u16;
        if let Some(hdr) = self.buf.get_mut(14..) {
            let mut f = EcatFrame::new_unchecked(hdr);
            f.set_length(payload);
            f.set_frame_type(FrameType::Pdu);
        }
        self.len
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_a_two_datagram_frame_that_parses_back() {
        let mut buf = [0u8; 64];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
        let r1 = b.push(Command::Brd, 0x0000_0000, &[0]).unwrap();
        let r2 = b.push(Command::Fprd, 0x0130_1000, &[0, 0]).unwrap();
        let len = b.finish();
        assert_eq!(len, 16 + 13 + 14);
        assert_eq!(r1, 26..27);
        assert_eq!(r2, 39..41);
        let eth = EthernetFrame::new_checked(&buf[..len]).unwrap();
        let ecat = EcatFrame::new_checked(eth.payload()).unwrap();
        assert_eq!(usize::from(ecat.length()), 27);
        let ranges: Vec<_> = ecat.datagrams().map(|r| r.unwrap()).collect();
        assert_eq!(ranges.len(), 2);
        let dg = Datagram::new_checked(&ecat.payload()[ranges[1].clone()]).unwrap();
        assert_eq!(dg.command(), Command::Fprd);
        assert_eq!((dg.adp(), dg.ado()), (0x1000, 0x0130));
        assert!(!dg.more_follows());
    }

    #[test]
    fn refuses_datagrams_that_do_not_fit() {
        let mut buf = [0u8; 30];
        let mut b = FrameBuilder::new(&mut buf, [0; 6]).unwrap();
        assert!(b.push(Command::Lrw, 0, &[0; 20]).is_err());
        let mut big = [0u8; 4096];
        let mut b = FrameBuilder::new(&mut big, [0; 6]).unwrap();
        assert!(b.push(Command::Lrw, 0, &[0; 2000]).is_ok());
        assert!(
            b.push(Command::Lrw, 0, &[0; 100]).is_err(),
            "payload over 2047 bytes"
        );
        let mut small = [0u8; 4];
        assert!(FrameBuilder::new(&mut small, [0; 6]).is_err());
    }
}
