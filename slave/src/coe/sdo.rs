//! SDO server (ETG.1000.6 5.6.2): expedited, normal and segmented upload
//! and download.
//!
//! The server is an explicit state machine ([`SdoState`]); one request in,
//! at most one response out. Data of a segmented download is collected in
//! the server's buffer and handed to the dictionary only when complete, so
//! an interrupted transfer leaves the object unchanged.

use super::ObjectAccess;
use crate::wire::coe::{CoeService, DownloadKind, SdoAbortCode, SdoRequest, SdoResponse};
use crate::wire::mailbox::MailboxErrorCode;

/// Largest object (or complete-access image) a transfer can carry by
/// default: the host's size. A firmware sizes its server for its device
/// ([`SdoServer`]'s `T`, the third parameter of `device::Slave`).
pub const SDO_BUFFER: usize = 1024;

/// Transfer state of the SDO server.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoState {
    /// No transfer in progress.
    Idle,
    /// A segmented download is collecting data.
    Download {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// Announced size.
        total: usize,
        /// Bytes received so far.
        received: usize,
        /// Toggle bit the next segment must carry.
        toggle: bool,
    },
    /// A segmented upload is sending data.
    Upload {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Size of the data.
        total: usize,
        /// Bytes sent so far.
        sent: usize,
        /// Toggle bit the next request must carry.
        toggle: bool,
    },
}

/// One SDO message the server produced: its length and the CoE service
/// it travels in.
///
/// An "Abort SDO Transfer" is an SDO *request* (ETG.1000.6 5.6.2.7.1,
/// CoE service 2) in either direction; every other answer is an SDO
/// response (service 3). SOEM (`ecx_SDOread`/`ecx_SDOwrite`) and
/// Wireshark's CoE dissector recognise an abort only in service 2, as SOES
/// (`SDO_abort`) and the SSC send it. See docs/MANUAL-NOTES.md, note 44.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SdoOutput {
    /// Bytes of the SDO part (after the CoE header).
    pub len: usize,
    /// The CoE service to put in the CoE header.
    pub service: CoeService,
}

impl SdoOutput {
    fn response(len: usize) -> Self {
        SdoOutput {
            len,
            service: CoeService::SdoResponse,
        }
    }
}

/// The SDO server, with a transfer buffer of `T` bytes: the largest
/// object (or complete-access image) a normal or segmented transfer can
/// carry; a bigger one is refused with 0x05040005 "out of memory".
#[derive(Debug)]
pub struct SdoServer<const T: usize = SDO_BUFFER> {
    state: SdoState,
    buf: [u8; T],
}

impl<const T: usize> Default for SdoServer<T> {
    fn default() -> Self {
        SdoServer {
            state: SdoState::Idle,
            buf: [0; T],
        }
    }
}

impl<const T: usize> SdoServer<T> {
    /// Drops a transfer in progress, in place (the buffer's stale bytes
    /// are never read: a new transfer sets its own length).
    pub fn reset(&mut self) {
        self.state = SdoState::Idle;
    }

    /// The transfer state.
    pub fn state(&self) -> SdoState {
        self.state
    }

    /// Handles the SDO part of a CoE request; writes the SDO answer into
    /// `out` (which bounds segment sizes) and returns its length and CoE
    /// service, or `None` when no answer is due (an abort from the master).
    pub fn handle(
        &mut self,
        request: &[u8],
        out: &mut [u8],
        od: &mut impl ObjectAccess,
    ) -> Result<Option<SdoOutput>, MailboxErrorCode> {
        let Ok(req) = SdoRequest::parse(request) else {
            return Err(MailboxErrorCode::SizeTooShort);
        };
        let resp = self.respond(req, out.len(), od);
        match resp {
            Reply::None => Ok(None),
            Reply::Abort { index, sub, code } => {
                self.state = SdoState::Idle;
                let len = SdoRequest::Abort { index, sub, code }
                    .emit(out)
                    .map_err(|_| MailboxErrorCode::NoMoreMemory)?;
                Ok(Some(SdoOutput {
                    len,
                    service: CoeService::SdoRequest,
                }))
            }
            Reply::Ack(r) => emit(&r, out),
            Reply::UploadFirst {
                index,
                sub,
                complete_access,
                total,
                chunk,
            } => {
                let data = self.buf.get(..chunk).unwrap_or(&[]);
                let r = SdoResponse::UploadNormal {
                    index,
                    sub,
                    complete_access,
                    complete_size: total as u32,
                    data,
                };
                emit(&r, out)
            }
            Reply::UploadSegment {
                from,
                to,
                toggle,
                last,
            } => {
                let data = self.buf.get(from..to).unwrap_or(&[]);
                let r = SdoResponse::UploadSegment { toggle, last, data };
                emit(&r, out)
            }
        }
    }

    fn respond(&mut self, req: SdoRequest<'_>, room: usize, od: &mut impl ObjectAccess) -> Reply {
        // Header bytes before data: normal upload 8 (cmd, index, sub, size),
        // segment 1 (cmd); the CoE header is already outside `room`.
        let normal_room = room.saturating_sub(8);
        let segment_room = room.saturating_sub(1);
        let busy = self.state != SdoState::Idle;
        match req {
            SdoRequest::InitiateDownload {
                index,
                sub,
                complete_access: true,
                ..
            }
            | SdoRequest::InitiateUpload {
                index,
                sub,
                complete_access: true,
            } if !od.complete_access() => {
                // A device without complete access (ETG.1000.6: CoE details
                // bit 5 clear) refuses it before anything is transferred;
                // a segmented transfer in progress is dropped as by any
                // new initiate.
                self.state = SdoState::Idle;
                Reply::Abort {
                    index,
                    sub,
                    code: SdoAbortCode::UnsupportedAccess,
                }
            }
            SdoRequest::InitiateDownload { index, sub, .. }
            | SdoRequest::InitiateUpload { index, sub, .. }
                if busy =>
            {
                // The master abandoned a segmented transfer: drop it (the
                // object stays unchanged) and tell the master so.
                self.state = SdoState::Idle;
                Reply::Abort {
                    index,
                    sub,
                    code: SdoAbortCode::Timeout,
                }
            }
            SdoRequest::InitiateDownload {
                index,
                sub,
                complete_access,
                kind,
            } => match kind {
                DownloadKind::Expedited { data, len } => {
                    let d = data.get(..usize::from(len)).unwrap_or(&data);
                    match od.sdo_download(index, sub, complete_access, d) {
                        Ok(()) => Reply::Ack(SdoResponse::InitiateDownloadAck {
                            index,
                            sub,
                            complete_access,
                        }),
                        Err(code) => Reply::Abort { index, sub, code },
                    }
                }
                DownloadKind::Normal {
                    complete_size,
                    data,
                } => {
                    let total = complete_size as usize;
                    if total > T {
                        return Reply::Abort {
                            index,
                            sub,
                            code: SdoAbortCode::LengthTooHigh,
                        };
                    }
                    if data.len() >= total {
                        let d = data.get(..total).unwrap_or(data);
                        return match od.sdo_download(index, sub, complete_access, d) {
                            Ok(()) => Reply::Ack(SdoResponse::InitiateDownloadAck {
                                index,
                                sub,
                                complete_access,
                            }),
                            Err(code) => Reply::Abort { index, sub, code },
                        };
                    }
                    if let Some(dst) = self.buf.get_mut(..data.len()) {
                        dst.copy_from_slice(data);
                    }
                    self.state = SdoState::Download {
                        index,
                        sub,
                        complete_access,
                        total,
                        received: data.len(),
                        toggle: false,
                    };
                    Reply::Ack(SdoResponse::InitiateDownloadAck {
                        index,
                        sub,
                        complete_access,
                    })
                }
            },
            SdoRequest::DownloadSegment { toggle, last, data } => {
                let SdoState::Download {
                    index,
                    sub,
                    complete_access,
                    total,
                    received,
                    toggle: expected,
                } = self.state
                else {
                    return Reply::Abort {
                        index: 0,
                        sub: 0,
                        code: SdoAbortCode::UnknownCommand,
                    };
                };
                if toggle != expected {
                    return Reply::Abort {
                        index,
                        sub,
                        code: SdoAbortCode::ToggleBit,
                    };
                }
                let end = received + data.len();
                if end > total {
                    return Reply::Abort {
                        index,
                        sub,
                        code: SdoAbortCode::LengthTooHigh,
                    };
                }
                if let Some(dst) = self.buf.get_mut(received..end) {
                    dst.copy_from_slice(data);
                }
                if last {
                    self.state = SdoState::Idle;
                    if end != total {
                        // The segments did not add up to the announced size.
                        return Reply::Abort {
                            index,
                            sub,
                            code: SdoAbortCode::LengthMismatch,
                        };
                    }
                    let d = self.buf.get(..total).unwrap_or(&[]);
                    if let Err(code) = od.sdo_download(index, sub, complete_access, d) {
                        return Reply::Abort { index, sub, code };
                    }
                } else {
                    self.state = SdoState::Download {
                        index,
                        sub,
                        complete_access,
                        total,
                        received: end,
                        toggle: !expected,
                    };
                }
                Reply::Ack(SdoResponse::DownloadSegmentAck { toggle })
            }
            SdoRequest::InitiateUpload {
                index,
                sub,
                complete_access,
            } => {
                let n = match od.sdo_upload(index, sub, complete_access, &mut self.buf) {
                    Ok(n) => n,
                    Err(code) => return Reply::Abort { index, sub, code },
                };
                // Expedited for 1 to 4 bytes; an empty value (a string of
                // length 0) has no expedited form (its size indicator
                // would be 4 unused bytes) and goes as a normal upload of
                // size 0.
                if (1..=4).contains(&n) && !complete_access {
                    let mut data = [0u8; 4];
                    if let (Some(d), Some(s)) = (data.get_mut(..n), self.buf.get(..n)) {
                        d.copy_from_slice(s);
                    }
                    return Reply::Ack(SdoResponse::UploadExpedited {
                        index,
                        sub,
                        complete_access,
                        data,
                        len: n as u8,
                    });
                }
                let chunk = n.min(normal_room);
                if chunk < n {
                    self.state = SdoState::Upload {
                        index,
                        sub,
                        total: n,
                        sent: chunk,
                        toggle: false,
                    };
                }
                Reply::UploadFirst {
                    index,
                    sub,
                    complete_access,
                    total: n,
                    chunk,
                }
            }
            SdoRequest::UploadSegment { toggle } => {
                let SdoState::Upload {
                    index,
                    sub,
                    total,
                    sent,
                    toggle: expected,
                } = self.state
                else {
                    return Reply::Abort {
                        index: 0,
                        sub: 0,
                        code: SdoAbortCode::UnknownCommand,
                    };
                };
                if toggle != expected {
                    return Reply::Abort {
                        index,
                        sub,
                        code: SdoAbortCode::ToggleBit,
                    };
                }
                let to = (sent + segment_room.max(1)).min(total);
                let last = to == total;
                self.state = if last {
                    SdoState::Idle
                } else {
                    SdoState::Upload {
                        index,
                        sub,
                        total,
                        sent: to,
                        toggle: !expected,
                    }
                };
                Reply::UploadSegment {
                    from: sent,
                    to,
                    toggle,
                    last,
                }
            }
            SdoRequest::Abort { .. } => {
                self.state = SdoState::Idle;
                Reply::None
            }
            SdoRequest::Unknown { .. } => Reply::Abort {
                index: 0,
                sub: 0,
                code: SdoAbortCode::UnknownCommand,
            },
        }
    }
}

/// What to answer, before the data is borrowed from the buffer.
enum Reply {
    None,
    Abort {
        index: u16,
        sub: u8,
        code: SdoAbortCode,
    },
    Ack(SdoResponse<'static>),
    UploadFirst {
        index: u16,
        sub: u8,
        complete_access: bool,
        total: usize,
        chunk: usize,
    },
    UploadSegment {
        from: usize,
        to: usize,
        toggle: bool,
        last: bool,
    },
}

fn emit(r: &SdoResponse<'_>, out: &mut [u8]) -> Result<Option<SdoOutput>, MailboxErrorCode> {
    r.emit(out)
        .map(|len| Some(SdoOutput::response(len)))
        .map_err(|_| MailboxErrorCode::NoMoreMemory)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One 100-byte object at 0x2000:00 and a 2-byte one at 0x2001:00.
    struct Od {
        big: [u8; 100],
        small: [u8; 2],
        writes: u32,
        reads: u32,
        complete_access: bool,
    }

    impl ObjectAccess for Od {
        fn dictionary(&self) -> &'static crate::od::Dictionary {
            &crate::testing::DICT
        }

        fn complete_access(&self) -> bool {
            self.complete_access
        }

        fn sdo_upload(
            &mut self,
            index: u16,
            _sub: u8,
            _ca: bool,
            out: &mut [u8],
        ) -> Result<usize, SdoAbortCode> {
            self.reads += 1;
            let src: &[u8] = match index {
                0x2000 => &self.big,
                0x2001 => &self.small,
                // An empty string.
                0x2002 => &[],
                _ => return Err(SdoAbortCode::ObjectNotFound),
            };
            out[..src.len()].copy_from_slice(src);
            Ok(src.len())
        }
        fn sdo_download(
            &mut self,
            index: u16,
            _sub: u8,
            _ca: bool,
            data: &[u8],
        ) -> Result<(), SdoAbortCode> {
            self.writes += 1;
            match index {
                0x2000 if data.len() == 100 => self.big.copy_from_slice(data),
                0x2000 => return Err(SdoAbortCode::LengthMismatch),
                _ => return Err(SdoAbortCode::ObjectNotFound),
            }
            Ok(())
        }
    }

    fn od() -> Od {
        let mut big = [0u8; 100];
        for (i, b) in big.iter_mut().enumerate() {
            *b = i as u8;
        }
        Od {
            big,
            small: [1, 2],
            writes: 0,
            reads: 0,
            complete_access: true,
        }
    }

    /// Sends `req`; returns the answer's bytes. Aborts come back as SDO
    /// requests (service 2) and are returned re-encoded as
    /// `SdoResponse::Abort` bytes (same layout) for the assertions; any
    /// other answer must be an SDO response (service 3).
    fn ask(srv: &mut SdoServer, od: &mut Od, req: SdoRequest<'_>, room: usize) -> Vec<u8> {
        let mut raw = [0u8; 64];
        let n = req.emit(&mut raw).unwrap();
        let mut out = vec![0u8; room];
        let got = srv.handle(&raw[..n], &mut out, od).unwrap().unwrap();
        out.truncate(got.len);
        let is_abort = matches!(SdoRequest::parse(&out), Ok(SdoRequest::Abort { .. }));
        if is_abort {
            assert_eq!(got.service, CoeService::SdoRequest, "abort in service 2");
        } else {
            assert_eq!(got.service, CoeService::SdoResponse);
        }
        out
    }

    /// Starts a segmented download of 100 bytes to 0x2000:00 carrying the
    /// first 20 bytes of `data`.
    fn begin(srv: &mut SdoServer, od: &mut Od, data: &[u8; 100]) {
        let init = SdoRequest::InitiateDownload {
            index: 0x2000,
            sub: 0,
            complete_access: false,
            kind: DownloadKind::Normal {
                complete_size: 100,
                data: &data[..20],
            },
        };
        ask(srv, od, init, 64);
    }

    #[test]
    fn complete_access_to_a_device_without_it_aborts_0601_0000_at_the_initiate() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        od.complete_access = false;
        let abort = |index: u16, sub: u8| {
            let mut v = vec![0x80, index as u8, (index >> 8) as u8, sub];
            v.extend_from_slice(&0x0601_0000u32.to_le_bytes());
            v
        };
        let up = SdoRequest::InitiateUpload {
            index: 0x2000,
            sub: 1,
            complete_access: true,
        };
        assert_eq!(ask(&mut srv, &mut od, up, 64), abort(0x2000, 1));
        // A normal (segmented) complete download is refused before its
        // first segment: nothing reaches the object.
        let data = [7u8; 100];
        let down = SdoRequest::InitiateDownload {
            index: 0x2000,
            sub: 1,
            complete_access: true,
            kind: DownloadKind::Normal {
                complete_size: 100,
                data: &data[..20],
            },
        };
        assert_eq!(ask(&mut srv, &mut od, down, 64), abort(0x2000, 1));
        assert_eq!((od.reads, od.writes), (0, 0), "no object was touched");
        // The same object by subindex still works.
        let plain = SdoRequest::InitiateUpload {
            index: 0x2001,
            sub: 0,
            complete_access: false,
        };
        let got = ask(&mut srv, &mut od, plain, 64);
        assert_eq!(&got[4..6], &[1, 2]);
    }

    #[test]
    fn sdo_abort_travels_as_an_sdo_request_service_2() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let mut raw = [0u8; 16];
        let n = SdoRequest::InitiateUpload {
            index: 0x1234,
            sub: 0,
            complete_access: false,
        }
        .emit(&mut raw)
        .unwrap();
        let mut out = [0u8; 64];
        let got = srv.handle(&raw[..n], &mut out, &mut od).unwrap().unwrap();
        assert_eq!(got.service, CoeService::SdoRequest);
        assert_eq!(
            &out[..got.len],
            &[0x80, 0x34, 0x12, 0x00, 0x00, 0x00, 0x02, 0x06, 0, 0][..got.len]
        );
        assert_eq!(
            SdoRequest::parse(&out[..got.len]).unwrap(),
            SdoRequest::Abort {
                index: 0x1234,
                sub: 0,
                code: SdoAbortCode::ObjectNotFound
            }
        );
    }

    #[test]
    fn an_empty_value_uploads_as_a_normal_upload_of_size_0() {
        // A string whose value is empty: no expedited form fits.
        let mut od = od();
        let mut srv = SdoServer::<64>::default();
        let mut raw = [0u8; 10];
        let n = SdoRequest::InitiateUpload {
            index: 0x2002,
            sub: 0,
            complete_access: false,
        }
        .emit(&mut raw)
        .unwrap();
        let mut out = [0u8; 64];
        let got = srv.handle(&raw[..n], &mut out, &mut od).unwrap().unwrap();
        assert_eq!(got.service, CoeService::SdoResponse);
        assert_eq!(
            out[0] & 0xE3,
            0x41,
            "initiate upload response, size indicated, not expedited"
        );
        assert_eq!(&out[4..8], &0u32.to_le_bytes(), "size 0");
        assert_eq!(got.len, 8);
    }

    #[test]
    fn upload_longer_than_the_mailbox_is_segmented_with_toggles() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let r = ask(
            &mut srv,
            &mut od,
            SdoRequest::InitiateUpload {
                index: 0x2000,
                sub: 0,
                complete_access: false,
            },
            30,
        );
        let SdoResponse::UploadNormal {
            complete_size,
            data,
            ..
        } = SdoResponse::parse(&r).unwrap()
        else {
            panic!("normal upload expected");
        };
        assert_eq!(complete_size, 100);
        let mut got = data.to_vec();
        let mut toggle = false;
        loop {
            let r = ask(&mut srv, &mut od, SdoRequest::UploadSegment { toggle }, 30);
            let SdoResponse::UploadSegment {
                toggle: t,
                last,
                data,
            } = SdoResponse::parse(&r).unwrap()
            else {
                panic!("segment expected");
            };
            assert_eq!(t, toggle);
            got.extend_from_slice(data);
            toggle = !toggle;
            if last {
                break;
            }
        }
        assert_eq!(got, od.big.to_vec());
        assert_eq!(srv.state(), SdoState::Idle);
    }

    #[test]
    fn short_objects_upload_expedited() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let r = ask(
            &mut srv,
            &mut od,
            SdoRequest::InitiateUpload {
                index: 0x2001,
                sub: 0,
                complete_access: false,
            },
            30,
        );
        assert!(matches!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::UploadExpedited { len: 2, .. }
        ));
    }

    #[test]
    fn segmented_download_is_stored_only_when_complete() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let data = [7u8; 100];
        begin(&mut srv, &mut od, &data);
        ask(
            &mut srv,
            &mut od,
            SdoRequest::DownloadSegment {
                toggle: false,
                last: false,
                data: &data[20..60],
            },
            64,
        );
        assert_eq!(od.writes, 0, "nothing stored mid-transfer");
        let r = ask(
            &mut srv,
            &mut od,
            SdoRequest::DownloadSegment {
                toggle: true,
                last: true,
                data: &data[60..],
            },
            64,
        );
        assert_eq!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::DownloadSegmentAck { toggle: true }
        );
        assert_eq!(od.big, data);
    }

    #[test]
    fn toggle_error_aborts_0503_0000_and_leaves_the_object() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let data = [9u8; 100];
        begin(&mut srv, &mut od, &data);
        let r = ask(
            &mut srv,
            &mut od,
            SdoRequest::DownloadSegment {
                toggle: true,
                last: false,
                data: &data[20..40],
            },
            64,
        );
        assert!(matches!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::Abort {
                code: SdoAbortCode::ToggleBit,
                ..
            }
        ));
        assert_eq!(od.big[0], 0);
        assert_eq!(srv.state(), SdoState::Idle);
    }

    #[test]
    fn a_new_request_during_a_segmented_transfer_aborts_0504_0000() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let data = [9u8; 100];
        begin(&mut srv, &mut od, &data);
        let r = ask(
            &mut srv,
            &mut od,
            SdoRequest::InitiateUpload {
                index: 0x2001,
                sub: 0,
                complete_access: false,
            },
            64,
        );
        assert!(matches!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::Abort {
                code: SdoAbortCode::Timeout,
                ..
            }
        ));
        assert_eq!(od.writes, 0);
        // The next request is served normally.
        let r = ask(
            &mut srv,
            &mut od,
            SdoRequest::InitiateUpload {
                index: 0x2001,
                sub: 0,
                complete_access: false,
            },
            64,
        );
        assert!(matches!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::UploadExpedited { .. }
        ));
    }

    #[test]
    fn segments_without_a_transfer_abort_0504_0001() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let r = ask(
            &mut srv,
            &mut od,
            SdoRequest::UploadSegment { toggle: false },
            64,
        );
        assert!(matches!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::Abort {
                code: SdoAbortCode::UnknownCommand,
                ..
            }
        ));
    }

    #[test]
    fn early_last_segment_aborts_with_length_mismatch() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let data = [9u8; 100];
        begin(&mut srv, &mut od, &data);
        let r = ask(
            &mut srv,
            &mut od,
            SdoRequest::DownloadSegment {
                toggle: false,
                last: true,
                data: &data[20..30],
            },
            64,
        );
        assert!(matches!(
            SdoResponse::parse(&r).unwrap(),
            SdoResponse::Abort {
                code: SdoAbortCode::LengthMismatch,
                ..
            }
        ));
        assert_eq!(od.writes, 0);
    }

    #[test]
    fn garbage_requests_do_not_panic() {
        let (mut srv, mut od) = (<SdoServer>::default(), od());
        let mut out = [0u8; 16];
        for len in 0..12 {
            let req = [0xFFu8; 12];
            let _ = srv.handle(&req[..len], &mut out, &mut od);
        }
        let _ = srv.handle(
            &[0x21, 0, 0x20, 0, 0xFF, 0xFF, 0xFF, 0xFF],
            &mut [0u8; 4],
            &mut od,
        );
    }
}
