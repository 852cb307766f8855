//! Mailbox layer (ETG.1000.6 5.3): framing, counters, dispatch to
//! the protocol servers, mailbox error replies.
//!
//! [`MailboxServer::handle`] takes the bytes the master wrote into the
//! receive mailbox (SM0) and produces at most one reply for the send mailbox
//! (SM1). It knows nothing of the ESC: the device moves the bytes.

use crate::coe::{CoeServer, ObjectAccess};
use crate::foe::{FoeContext, FoeServer};
use crate::od::modules::ObjectView;
use crate::wire::foe::FoeRepr;
use crate::wire::mailbox::{
    HEADER_LEN, Mailbox, MailboxError, MailboxErrorCode, MailboxErrorRepr, MailboxRepr,
    MailboxType, next_counter,
};

/// What [`MailboxServer::handle`] did with a request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Handled {
    /// The request repeats the last one (same counter, same content: the
    /// master sent it again); it was not executed again and the reply
    /// buffer was not touched.
    Repeated,
    /// The request was executed: the reply's length in the reply buffer,
    /// or `None` when nothing is to be sent (an SDO abort from the
    /// master).
    Done(Option<usize>),
}

/// The mailbox server of one slave (`T`: the SDO transfer buffer, see
/// [`crate::coe::sdo::SdoServer`]).
#[derive(Debug, Default)]
pub struct MailboxServer<const T: usize = { crate::coe::sdo::SDO_BUFFER }> {
    coe: CoeServer<T>,
    foe: FoeServer,
    /// Counter and content checksum of the last request processed, to drop
    /// repeats: a retransmission carries the same counter and the same
    /// bytes (two masters' sequences may share a counter value with
    /// different content, which is not a repeat).
    last_request: Option<(u8, u32)>,
    /// Counter of the last response sent (1..7).
    tx_counter: u8,
}

impl<const T: usize> MailboxServer<T> {
    /// A server in its initial state.
    pub fn new() -> Self {
        Self::default()
    }

    /// Back to the initial state in place: what [`MailboxServer::new`]
    /// gives, without a new server (about 0.7 KiB of buffers on a
    /// microcontroller) built on the stack and copied over.
    pub fn reset(&mut self) {
        self.coe.reset();
        self.foe.abort();
        self.last_request = None;
        self.tx_counter = 0;
    }

    fn next_counter(&mut self) -> u8 {
        self.tx_counter = next_counter(self.tx_counter);
        self.tx_counter
    }

    /// Handles one request (the whole SM0 buffer) and writes the reply into
    /// `out` (the SM1 buffer size), which it clears first, unless the
    /// request repeats the last one ([`Handled::Repeated`]: `out` is left
    /// as it is, so it may hold the last reply for the repeat service).
    pub fn handle(
        &mut self,
        request: &[u8],
        out: &mut [u8],
        od: &mut impl ObjectAccess,
        foe: Option<&mut FoeContext<'_>>,
    ) -> Handled {
        let mbx = match Mailbox::new_checked(request) {
            Ok(m) => m,
            Err(_) => {
                out.fill(0);
                let code = if request.len() < HEADER_LEN {
                    MailboxErrorCode::InvalidHeader
                } else {
                    MailboxErrorCode::InvalidSize
                };
                return Handled::Done(self.error_reply(out, code));
            }
        };
        let counter = mbx.counter();
        let digest =
            crate::firmware::crc32(mbx.payload()) ^ u32::from(u8::from(mbx.mailbox_type()));
        if counter != 0 && self.last_request == Some((counter, digest)) {
            // A repeated mailbox (same counter, same content): the master
            // sent it again; it is not executed twice.
            return Handled::Repeated;
        }
        self.last_request = (counter != 0).then_some((counter, digest));
        out.fill(0);
        Handled::Done(self.execute(mbx, out, od, foe))
    }

    fn execute(
        &mut self,
        mbx: Mailbox<&[u8]>,
        out: &mut [u8],
        od: &mut impl ObjectAccess,
        foe: Option<&mut FoeContext<'_>>,
    ) -> Option<usize> {
        let header_len = HEADER_LEN;
        match mbx.mailbox_type() {
            MailboxType::CoE => {
                let body = out.get_mut(header_len..)?;
                match self.coe.handle(mbx.payload(), body, od) {
                    Ok(Some(n)) => self.frame(out, MailboxType::CoE, n),
                    Ok(None) => None,
                    Err(code) => self.error_reply(out, code),
                }
            }
            MailboxType::FoE => {
                // Without an image store the device offers no FoE.
                let Some(ctx) = foe else {
                    return self.error_reply(out, MailboxErrorCode::UnsupportedProtocol);
                };
                let Ok(req) = FoeRepr::parse(mbx.payload()) else {
                    return self.error_reply(out, MailboxErrorCode::SizeTooShort);
                };
                let body = out.get_mut(header_len..)?;
                let n = self.foe.handle(req, ctx, body)?;
                self.frame(out, MailboxType::FoE, n)
            }
            _ => self.error_reply(out, MailboxErrorCode::UnsupportedProtocol),
        }
    }

    /// Drops a FoE transfer in progress (state change, link loss).
    pub fn abort_foe(&mut self) {
        self.foe.abort();
    }

    /// Whether a response spanning several mailboxes is in progress
    /// ([`MailboxServer::next_pending`] has a fragment to give).
    pub fn has_pending(&self) -> bool {
        self.coe.has_fragment()
    }

    /// The next part of a response that spans several mailboxes (SDO
    /// Information fragments), framed for SM1; `None` when nothing is due.
    pub fn next_pending(&mut self, out: &mut [u8], view: ObjectView) -> Option<usize> {
        let body = out.get_mut(HEADER_LEN..)?;
        let n = self.coe.next_fragment(body, view)?;
        self.frame(out, MailboxType::CoE, n)
    }

    /// Frames a CoE payload of `len` bytes already written after the
    /// mailbox header in `out` (emergencies); returns the total length.
    pub fn frame_coe(&mut self, out: &mut [u8], len: usize) -> Option<usize> {
        self.frame(out, MailboxType::CoE, len)
    }

    /// Writes the mailbox header for a `len`-byte payload already in place.
    fn frame(&mut self, out: &mut [u8], kind: MailboxType, len: usize) -> Option<usize> {
        let repr = MailboxRepr {
            length: u16::try_from(len).ok()?,
            address: 0,
            channel: 0,
            priority: 0,
            mailbox_type: kind,
            counter: self.next_counter(),
        };
        repr.emit(&mut Mailbox::new_unchecked(&mut *out)).ok()?;
        Some(HEADER_LEN + len)
    }

    fn error_reply(&mut self, out: &mut [u8], code: MailboxErrorCode) -> Option<usize> {
        let body = out.get_mut(HEADER_LEN..)?;
        let repr = MailboxErrorRepr { code };
        repr.emit(&mut MailboxError::new_unchecked(body)).ok()?;
        self.frame(out, MailboxType::Error, repr.buffer_len())
    }
}
