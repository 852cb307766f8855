//! Parse → emit → parse checks of the wire formats: whatever a `parse`
//! accepts, its `Repr` emits bytes that parse back to the same `Repr`, and
//! emitting that again gives the same bytes.
//!
//! Every check panics (a fuzz finding) on a mismatch and does nothing for
//! input the parser refuses.

use std::fmt::Debug;

use ecat_slave::wire::coe::{
    CoeHeader, CoeRepr, CoeService, Emergency, EmergencyRepr, SdoInfo, SdoInfoRepr, SdoRequest,
    SdoResponse,
};
use ecat_slave::wire::ecat::{Datagram, DatagramRepr, EcatFrame, EcatFrameRepr};
use ecat_slave::wire::ethernet::{EthernetFrame, EthernetRepr};
use ecat_slave::wire::foe::FoeRepr;
use ecat_slave::wire::mailbox::{
    Mailbox, MailboxError, MailboxErrorRepr, MailboxRepr, MailboxType,
};

fn same<T: PartialEq + Debug>(what: &str, first: &T, again: &T, bytes: &[u8]) {
    assert!(
        first == again,
        "{what}: parse -> emit -> parse changed\n first: {first:?}\n again: {again:?}\n emitted: {bytes:02x?}"
    );
}

/// A fixed-size header `Repr` emitted into a copy of the original bytes:
/// the copy must parse to the same `Repr`.
macro_rules! header_round_trip {
    ($what:expr, $bytes:expr, $view:ident, $repr:ty) => {{
        let bytes: &[u8] = $bytes;
        if let Ok(view) = $view::new_checked(bytes) {
            if let Ok(first) = <$repr>::parse(&view) {
                let mut copy = bytes.to_vec();
                <$repr>::emit(&first, &mut $view::new_unchecked(&mut copy[..]))
                    .unwrap_or_else(|e| panic!("{}: emit of {first:?} failed: {e:?}", $what));
                let again = <$repr>::parse(&$view::new_unchecked(&copy[..]))
                    .unwrap_or_else(|e| panic!("{}: emitted header does not parse: {e:?}", $what));
                same($what, &first, &again, &copy);
                Some(first)
            } else {
                None
            }
        } else {
            None
        }
    }};
}

/// Ethernet header, EtherCAT header and every datagram of a frame.
pub fn ethernet_frame(frame: &[u8]) {
    let Some(_) = header_round_trip!("Ethernet header", frame, EthernetFrame, EthernetRepr) else {
        return;
    };
    let Some(payload) = frame.get(14..) else {
        return;
    };
    let Some(ecat) = header_round_trip!("EtherCAT header", payload, EcatFrame, EcatFrameRepr)
    else {
        return;
    };
    let _ = ecat;
    let Ok(view) = EcatFrame::new_checked(payload) else {
        return;
    };
    for range in view.datagrams() {
        let Ok(range) = range else { break };
        let Some(bytes) = view.payload().get(range) else {
            break;
        };
        datagram(bytes);
    }
}

/// One datagram.
pub fn datagram(bytes: &[u8]) {
    let Ok(dg) = Datagram::new_checked(bytes) else {
        return;
    };
    let Ok(first) = DatagramRepr::parse(&dg) else {
        return;
    };
    let mut out = vec![0u8; first.buffer_len()];
    first
        .emit(&mut Datagram::new_unchecked(&mut out[..]))
        .unwrap_or_else(|e| panic!("datagram: emit of {first:?} failed: {e:?}"));
    let again = DatagramRepr::parse(&Datagram::new_unchecked(&out[..]))
        .unwrap_or_else(|e| panic!("datagram: emitted bytes do not parse: {e:?}"));
    same("datagram", &first, &again, &out);
}

/// A mailbox message (the bytes of SM0 or SM1): header, then the protocol
/// payload. `from_master` chooses SDO request or response parsing.
pub fn mailbox(msg: &[u8], from_master: bool) {
    let Some(header) = header_round_trip!("mailbox header", msg, Mailbox, MailboxRepr) else {
        return;
    };
    let Ok(mbx) = Mailbox::new_checked(msg) else {
        return;
    };
    let payload = mbx.payload();
    match header.mailbox_type {
        MailboxType::Error => {
            header_round_trip!("mailbox error", payload, MailboxError, MailboxErrorRepr);
        }
        MailboxType::CoE => coe(payload, from_master),
        MailboxType::FoE => foe(payload),
        _ => {}
    }
}

/// A CoE element (header and service data).
pub fn coe(payload: &[u8], from_master: bool) {
    let Some(header) = header_round_trip!("CoE header", payload, CoeHeader, CoeRepr) else {
        return;
    };
    let Some(body) = payload.get(2..) else {
        return;
    };
    match header.service {
        CoeService::SdoRequest | CoeService::SdoResponse => {
            if from_master {
                sdo_request(body);
            } else {
                sdo_response(body);
            }
        }
        CoeService::SdoInformation => {
            header_round_trip!("SDO Information header", body, SdoInfo, SdoInfoRepr);
        }
        CoeService::Emergency => {
            header_round_trip!("Emergency", body, Emergency, EmergencyRepr);
        }
        _ => {}
    }
}

/// An SDO request (bytes after the CoE header).
pub fn sdo_request(body: &[u8]) {
    let Ok(first) = SdoRequest::parse(body) else {
        return;
    };
    let mut out = vec![0u8; first.buffer_len()];
    let n = first
        .emit(&mut out)
        .unwrap_or_else(|e| panic!("SDO request: emit of {first:?} failed: {e:?}"));
    let again = SdoRequest::parse(&out[..n])
        .unwrap_or_else(|e| panic!("SDO request: emitted bytes do not parse: {e:?}"));
    same("SDO request", &first, &again, &out[..n]);
    let mut out2 = vec![0u8; again.buffer_len()];
    let n2 = again.emit(&mut out2).expect("emit again");
    assert_eq!(out[..n], out2[..n2], "SDO request: emit not stable");
}

/// An SDO response (bytes after the CoE header).
pub fn sdo_response(body: &[u8]) {
    let Ok(first) = SdoResponse::parse(body) else {
        return;
    };
    let mut out = vec![0u8; first.buffer_len()];
    let n = first
        .emit(&mut out)
        .unwrap_or_else(|e| panic!("SDO response: emit of {first:?} failed: {e:?}"));
    let again = SdoResponse::parse(&out[..n])
        .unwrap_or_else(|e| panic!("SDO response: emitted bytes do not parse: {e:?}"));
    same("SDO response", &first, &again, &out[..n]);
}

/// An FoE packet (the mailbox data).
pub fn foe(payload: &[u8]) {
    let Ok(first) = FoeRepr::parse(payload) else {
        return;
    };
    let mut out = vec![0u8; first.buffer_len()];
    let n = first
        .emit(&mut out)
        .unwrap_or_else(|e| panic!("FoE: emit of {first:?} failed: {e:?}"));
    let again = FoeRepr::parse(&out[..n])
        .unwrap_or_else(|e| panic!("FoE: emitted bytes do not parse: {e:?}"));
    same("FoE", &first, &again, &out[..n]);
}
