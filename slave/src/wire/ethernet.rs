//! Ethernet II frames carrying EtherCAT (ETG.1000.4, "EtherCAT frame
//! structure": an EtherCAT frame is an Ethernet II frame with ethertype
//! `0x88A4`).
//!
//! ```text
//!  0      6      12     14
//! +------+------+------+-----------------
//! | dst  | src  | type | payload (EtherCAT header + datagrams)
//! +------+------+------+-----------------
//! ```
//!
//! The frame check sequence is not part of the view (it is added and
//! stripped by the MAC). The ethertype is big-endian, as in every Ethernet II
//! frame; everything inside the payload is little-endian.

use super::{Field, Rest, WireError};

/// A six-byte Ethernet MAC address.
pub type MacAddress = [u8; 6];

/// Ethertype of EtherCAT frames (ETG.1000.4, "EtherCAT frame structure").
pub const ETHERTYPE_ETHERCAT: u16 = 0x88A4;

/// Length of the Ethernet II header (destination, source, ethertype).
pub const HEADER_LEN: usize = field::PAYLOAD.start;

/// The broadcast MAC address `ff:ff:ff:ff:ff:ff`, used by EtherCAT masters
/// as destination address.
pub const BROADCAST: MacAddress = [0xFF; 6];

mod field {
    use super::{Field, Rest};

    /// Destination MAC address.
    pub const DESTINATION: Field = 0..6;
    /// Source MAC address.
    pub const SOURCE: Field = 6..12;
    /// Ethertype, big-endian.
    pub const ETHERTYPE: Field = 12..14;
    /// Payload.
    pub const PAYLOAD: Rest = 14..;
}

/// A read/write view of an Ethernet II frame (ETG.1000.4, "EtherCAT frame
/// structure"; IEEE 802.3 Ethernet II framing).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EthernetFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> EthernetFrame<T> {
    /// Wraps a buffer without checking its length.
    ///
    /// Accessors on an unchecked view never panic, but read out-of-range
    /// fields as zero.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps a buffer, checking that it holds at least the header.
    pub fn new_checked(buffer: T) -> Result<Self, WireError> {
        let frame = Self::new_unchecked(buffer);
        frame.check_len()?;
        Ok(frame)
    }

    /// Checks that the buffer holds the 14-byte header.
    ///
    /// Returns [`WireError::Truncated`] otherwise.
    pub fn check_len(&self) -> Result<(), WireError> {
        if self.buffer.as_ref().len() < HEADER_LEN {
            Err(WireError::Truncated)
        } else {
            Ok(())
        }
    }

    /// Consumes the view and returns the underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The destination MAC address.
    pub fn dst_addr(&self) -> MacAddress {
        super::get_array(self.buffer.as_ref(), field::DESTINATION)
    }

    /// The source MAC address.
    pub fn src_addr(&self) -> MacAddress {
        super::get_array(self.buffer.as_ref(), field::SOURCE)
    }

    /// The ethertype (big-endian on the wire).
    pub fn ethertype(&self) -> u16 {
        u16::from_be_bytes(super::get_array(self.buffer.as_ref(), field::ETHERTYPE))
    }

    /// Whether the ethertype is [`ETHERTYPE_ETHERCAT`].
    pub fn is_ethercat(&self) -> bool {
        self.ethertype() == ETHERTYPE_ETHERCAT
    }

    /// Whether the locally-administered bit of the source address is set,
    /// i.e. whether a slave has already forwarded this frame (see
    /// [`EthernetFrame::mark_forwarded`]).
    pub fn is_forwarded(&self) -> bool {
        self.src_addr()[0] & 0x02 != 0
    }

    /// The payload following the header (the EtherCAT frame).
    pub fn payload(&self) -> &[u8] {
        super::tail(self.buffer.as_ref(), field::PAYLOAD)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> EthernetFrame<T> {
    /// Sets the destination MAC address.
    pub fn set_dst_addr(&mut self, addr: MacAddress) {
        super::set_array(self.buffer.as_mut(), field::DESTINATION, addr);
    }

    /// Sets the source MAC address.
    pub fn set_src_addr(&mut self, addr: MacAddress) {
        super::set_array(self.buffer.as_mut(), field::SOURCE, addr);
    }

    /// Sets the ethertype (written big-endian).
    pub fn set_ethertype(&mut self, ethertype: u16) {
        super::set_array(
            self.buffer.as_mut(),
            field::ETHERTYPE,
            ethertype.to_be_bytes(),
        );
    }

    /// Sets the locally-administered bit (`src[0] |= 0x02`) of the source
    /// MAC address.
    ///
    /// An EtherCAT slave does this on every frame it processes and forwards
    /// back to the master, so that a master can tell its own outgoing frames
    /// from returning ones (ETG.1000.4, frame processing; ESC datasheets
    /// "Port 0 / MAC address modification").
    pub fn mark_forwarded(&mut self) {
        let mut src = self.src_addr();
        src[0] |= 0x02;
        self.set_src_addr(src);
    }

    /// The mutable payload following the header.
    pub fn payload_mut(&mut self) -> &mut [u8] {
        super::tail_mut(self.buffer.as_mut(), field::PAYLOAD)
    }
}

impl<T: AsRef<[u8]>> AsRef<[u8]> for EthernetFrame<T> {
    fn as_ref(&self) -> &[u8] {
        self.buffer.as_ref()
    }
}

/// High-level representation of an Ethernet II header (ETG.1000.4,
/// "EtherCAT frame structure").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EthernetRepr {
    /// Destination MAC address.
    pub dst_addr: MacAddress,
    /// Source MAC address.
    pub src_addr: MacAddress,
    /// Ethertype.
    pub ethertype: u16,
}

impl EthernetRepr {
    /// Parses the header of a frame.
    pub fn parse<T: AsRef<[u8]>>(frame: &EthernetFrame<T>) -> Result<Self, WireError> {
        frame.check_len()?;
        Ok(Self {
            dst_addr: frame.dst_addr(),
            src_addr: frame.src_addr(),
            ethertype: frame.ethertype(),
        })
    }

    /// Length of the emitted header ([`HEADER_LEN`]).
    pub const fn buffer_len(&self) -> usize {
        HEADER_LEN
    }

    /// Writes the header into a frame; the payload is left untouched.
    ///
    /// Fails with [`WireError::BufferTooSmall`] if the frame is shorter than
    /// [`HEADER_LEN`].
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        frame: &mut EthernetFrame<T>,
    ) -> Result<(), WireError> {
        frame.check_len().map_err(|_| WireError::BufferTooSmall)?;
        frame.set_dst_addr(self.dst_addr);
        frame.set_src_addr(self.src_addr);
        frame.set_ethertype(self.ethertype);
        Ok(())
    }
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

    /// A BRD of register 0x0000 (1 byte) as sent by ethercrab from
    /// `10:10:10:10:10:10`.
    static FRAME_BYTES: [u8; 29] = [
        0xff, 0xff, 0xff, 0xff, 0xff, 0xff, // dst
        0x10, 0x10, 0x10, 0x10, 0x10, 0x10, // src
        0x88, 0xa4, // ethertype
        0x0d, 0x10, // EtherCAT header: len 13, type 1
        0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, // BRD header
        0x00, // data
        0x00, 0x00, // wkc
    ];

    #[test]
    fn deconstructs_ethercat_frame() {
        let frame = EthernetFrame::new_checked(&FRAME_BYTES[..]).unwrap();
        assert_eq!(frame.dst_addr(), BROADCAST);
        assert_eq!(frame.src_addr(), [0x10; 6]);
        assert_eq!(frame.ethertype(), ETHERTYPE_ETHERCAT);
        assert!(frame.is_ethercat());
        assert!(!frame.is_forwarded());
        assert_eq!(frame.payload(), &FRAME_BYTES[14..]);
    }

    #[test]
    fn constructs_ethercat_frame() {
        let mut bytes = [0u8; 29];
        let mut frame = EthernetFrame::new_unchecked(&mut bytes[..]);
        frame.set_dst_addr(BROADCAST);
        frame.set_src_addr([0x10; 6]);
        frame.set_ethertype(ETHERTYPE_ETHERCAT);
        frame.payload_mut().copy_from_slice(&FRAME_BYTES[14..]);
        assert_eq!(bytes, FRAME_BYTES);
    }

    #[test]
    fn repr_parse_and_emit_round_trip() {
        let frame = EthernetFrame::new_checked(&FRAME_BYTES[..]).unwrap();
        let repr = EthernetRepr::parse(&frame).unwrap();
        assert_eq!(
            repr,
            EthernetRepr {
                dst_addr: BROADCAST,
                src_addr: [0x10; 6],
                ethertype: 0x88A4,
            }
        );
        assert_eq!(repr.buffer_len(), 14);

        let mut bytes = FRAME_BYTES;
        bytes[..14].fill(0);
        let mut out = EthernetFrame::new_unchecked(&mut bytes[..]);
        repr.emit(&mut out).unwrap();
        assert_eq!(bytes, FRAME_BYTES);

        let mut short = [0u8; 13];
        assert_eq!(
            repr.emit(&mut EthernetFrame::new_unchecked(&mut short[..])),
            Err(WireError::BufferTooSmall)
        );
    }

    #[test]
    fn mark_forwarded_sets_locally_administered_bit_only() {
        let mut bytes = FRAME_BYTES;
        let mut frame = EthernetFrame::new_checked(&mut bytes[..]).unwrap();
        frame.mark_forwarded();
        assert!(frame.is_forwarded());
        assert_eq!(frame.src_addr(), [0x12, 0x10, 0x10, 0x10, 0x10, 0x10]);
        // idempotent
        frame.mark_forwarded();
        assert_eq!(frame.src_addr()[0], 0x12);
        assert_eq!(&bytes[12..], &FRAME_BYTES[12..]);
    }

    #[test]
    fn ethertype_is_big_endian() {
        let mut bytes = [0u8; 14];
        EthernetFrame::new_unchecked(&mut bytes[..]).set_ethertype(0x88A4);
        assert_eq!(&bytes[12..14], &[0x88, 0xA4]);
    }

    #[test]
    fn truncated_frame_is_rejected() {
        assert_eq!(
            EthernetFrame::new_checked(&FRAME_BYTES[..13]).unwrap_err(),
            WireError::Truncated
        );
        assert_eq!(
            EthernetRepr::parse(&EthernetFrame::new_unchecked(&[0u8; 0][..])),
            Err(WireError::Truncated)
        );
    }

    #[test]
    fn header_only_frame_has_empty_payload() {
        let frame = EthernetFrame::new_checked(&FRAME_BYTES[..14]).unwrap();
        assert!(frame.payload().is_empty());
    }

    #[test]
    fn unchecked_short_frame_accessors_do_not_panic() {
        let mut bytes = [0x10u8; 5];
        let mut frame = EthernetFrame::new_unchecked(&mut bytes[..]);
        assert_eq!(frame.src_addr(), [0; 6]);
        assert_eq!(frame.ethertype(), 0);
        assert!(frame.payload().is_empty());
        frame.mark_forwarded();
        frame.set_ethertype(1);
        assert!(frame.payload_mut().is_empty());
        assert_eq!(frame.into_inner(), &[0x10; 5]);
    }
}
