//! CANopen over EtherCAT servers.
//!
//! [`CoeServer`] takes the CoE part of a mailbox request, dispatches on the
//! CoE service and writes the CoE response. Object access goes through the
//! [`ObjectAccess`] trait that the device implements, so this layer holds
//! no object values and knows nothing of the ESC.

pub mod emergency;
pub mod sdo;
pub mod sdo_info;

use crate::od::Dictionary;
use crate::od::modules::ObjectView;
use crate::wire::coe::{CoeHeader, CoeService, SdoAbortCode};
use crate::wire::mailbox::MailboxErrorCode;

/// What the CoE servers need from the object dictionary.
pub trait ObjectAccess {
    /// The dictionary SDO Information describes.
    fn dictionary(&self) -> &'static Dictionary;

    /// What of the dictionary is visible now (a modular device hides the
    /// objects of its empty slots); everything by default.
    fn view(&self) -> ObjectView {
        ObjectView::all(self.dictionary())
    }

    /// Whether the device offers SDO Information (SII CoE details bit 1,
    /// ESI `Mailbox/CoE@SdoInfo`); `true` by default. Without it an SDO
    /// Information request gets the mailbox error "service not supported"
    /// (0x0004), as every other CoE service the device does not offer.
    fn sdo_info(&self) -> bool {
        true
    }

    /// Whether the device offers SDO complete access (CoE details bit 5,
    /// ESI `Mailbox/CoE@CompleteAccess`); `true` by default. Without it a
    /// complete-access request is aborted with 0x0601_0000 "unsupported
    /// access to an object" at its initiate.
    fn complete_access(&self) -> bool {
        true
    }

    /// Reads `index:sub` (or the whole object with `complete_access`) into
    /// `out`; returns the number of bytes.
    fn sdo_upload(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        out: &mut [u8],
    ) -> Result<usize, SdoAbortCode>;

    /// Writes `data` into `index:sub` (or the whole object with
    /// `complete_access`), all or nothing.
    fn sdo_download(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        data: &[u8],
    ) -> Result<(), SdoAbortCode>;
}

/// The CoE server of one slave (`T`: the SDO transfer buffer, see
/// [`sdo::SdoServer`]).
#[derive(Debug, Default)]
pub struct CoeServer<const T: usize = { sdo::SDO_BUFFER }> {
    sdo: sdo::SdoServer<T>,
    info: sdo_info::SdoInfoServer,
}

impl<const T: usize> CoeServer<T> {
    /// A server with no transfer in progress.
    pub fn new() -> Self {
        Self::default()
    }

    /// Handles the CoE payload `request` (CoE header onwards) and writes the
    /// CoE response into `out`. Returns the response length, or the mailbox
    /// error code to answer with when the request cannot be served at all.
    pub fn handle(
        &mut self,
        request: &[u8],
        out: &mut [u8],
        od: &mut impl ObjectAccess,
    ) -> Result<Option<usize>, MailboxErrorCode> {
        let header = CoeHeader::new_checked(request).map_err(|_| MailboxErrorCode::SizeTooShort)?;
        let body = request.get(CoeHeader::<&[u8]>::HEADER_LEN..).unwrap_or(&[]);
        match header.service() {
            CoeService::SdoRequest => {
                let (head, rest) = out
                    .split_at_mut_checked(CoeHeader::<&[u8]>::HEADER_LEN)
                    .ok_or(MailboxErrorCode::NoMoreMemory)?;
                let Some(out) = self.sdo.handle(body, rest, od)? else {
                    return Ok(None);
                };
                // An abort travels as an SDO request (service 2), every
                // other answer as an SDO response (service 3).
                CoeHeader::emit_into(head, 0, out.service);
                Ok(Some(out.len + CoeHeader::<&[u8]>::HEADER_LEN))
            }
            CoeService::SdoInformation if od.sdo_info() => {
                let (head, rest) = out
                    .split_at_mut_checked(CoeHeader::<&[u8]>::HEADER_LEN)
                    .ok_or(MailboxErrorCode::NoMoreMemory)?;
                let Some(n) = self.info.handle(body, rest, od.view()) else {
                    return Ok(None);
                };
                CoeHeader::emit_into(head, 0, CoeService::SdoInformation);
                Ok(Some(n + CoeHeader::<&[u8]>::HEADER_LEN))
            }
            _ => Err(MailboxErrorCode::ServiceNotSupported),
        }
    }

    /// Drops every transfer in progress, in place: what [`CoeServer::new`]
    /// gives, without building a new server (its buffers) on the stack.
    pub fn reset(&mut self) {
        self.sdo.reset();
        self.info.reset();
    }

    /// Whether an SDO Information response is in progress (more fragments
    /// to send).
    pub fn has_fragment(&self) -> bool {
        self.info.busy()
    }

    /// The next fragment of an SDO Information response in progress (CoE
    /// header onwards), if any.
    pub fn next_fragment(&mut self, out: &mut [u8], view: ObjectView) -> Option<usize> {
        if !self.info.busy() {
            return None;
        }
        let (head, rest) = out.split_at_mut_checked(CoeHeader::<&[u8]>::HEADER_LEN)?;
        let n = self.info.next_fragment(rest, view)?;
        CoeHeader::emit_into(head, 0, CoeService::SdoInformation);
        Some(n + CoeHeader::<&[u8]>::HEADER_LEN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An object access that answers nothing, with or without SDO
    /// Information.
    struct Access {
        sdo_info: bool,
    }

    impl ObjectAccess for Access {
        fn dictionary(&self) -> &'static Dictionary {
            &crate::testing::DICT
        }

        fn sdo_info(&self) -> bool {
            self.sdo_info
        }

        fn sdo_upload(
            &mut self,
            _: u16,
            _: u8,
            _: bool,
            _: &mut [u8],
        ) -> Result<usize, SdoAbortCode> {
            Err(SdoAbortCode::ObjectNotFound)
        }

        fn sdo_download(&mut self, _: u16, _: u8, _: bool, _: &[u8]) -> Result<(), SdoAbortCode> {
            Err(SdoAbortCode::ObjectNotFound)
        }
    }

    /// CoE header of service 8, then "Get OD List request" (opcode 1) of
    /// all objects (list type 1).
    const OD_LIST_REQUEST: [u8; 8] = [0x00, 0x80, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00];

    #[test]
    fn sdo_information_on_a_device_without_it_is_mailbox_error_0004() {
        let mut out = [0u8; 128];
        let mut without = Access { sdo_info: false };
        let got = <CoeServer>::new().handle(&OD_LIST_REQUEST, &mut out, &mut without);
        assert_eq!(got, Err(MailboxErrorCode::ServiceNotSupported));
        assert_eq!(u16::from(MailboxErrorCode::ServiceNotSupported), 0x0004);
        // The same request on a device that offers it: an OD list response
        // (opcode 2) in service 8.
        let mut with = Access { sdo_info: true };
        let n = <CoeServer>::new()
            .handle(&OD_LIST_REQUEST, &mut out, &mut with)
            .expect("served")
            .expect("an answer");
        assert!(n > 8);
        assert_eq!((out[1] >> 4, out[2] & 0x7F), (8, 2));
    }
}
