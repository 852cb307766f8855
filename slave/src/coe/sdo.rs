//! SDO server (ETG.1000.6 5.6.2): expedited, normal and segmented upload
//! and download.
//!
//! The server is an explicit state machine ([`SdoState`]); one request in,
//! at most one response out. Data of a segmented download is collected in
//! the server's buffer and handed to the dictionary only when complete, so
//! an interrupted transfer leaves the object unchanged.

use super::ObjectAccess;
use crate::wire::coe::{DownloadKind, SdoAbortCode, SdoRequest, SdoResponse};
use crate::wire::mailbox::MailboxErrorCode;

/// Largest object (or complete-access image) a transfer can carry.
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

/// The SDO server.
#[derive(Debug)]
pub struct SdoServer {
    state: SdoState,
    buf: [u8; SDO_BUFFER],
}

impl Default for SdoServer {
    fn default() -> Self {
        SdoServer {
            state: SdoState::Idle,
            buf: [0; SDO_BUFFER],
        }
    }
}

impl SdoServer {
    /// The transfer state.
    pub fn state(&self) -> SdoState {
        self.state
    }

    /// Handles the SDO part of a CoE request; writes the SDO response into
    /// `out` (which bounds segment sizes) and returns its length, or `None`
    /// when no response is due (an abort from the master).
    pub fn handle(
        &mut self,
        request: &[u8],
        out: &mut [u8],
        od: &mut impl ObjectAccess,
    ) -> Result<Option<usize>, MailboxErrorCode> {
        let Ok(req) = SdoRequest::parse(request) else {
            return Err(MailboxErrorCode::SizeTooShort);
        };
        let resp = self.respond(req, out.len(), od);
        match resp {
            Reply::None => Ok(None),
            Reply::Abort { index, sub, code } => {
                self.state = SdoState::Idle;
                emit(&SdoResponse::Abort { index, sub, code }, out).map(Some)
            }
            Reply::Ack(r) => emit(&r, out).map(Some),
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
                emit(&r, out).map(Some)
            }
            Reply::UploadSegment {
                from,
                to,
                toggle,
                last,
            } => {
                let data = self.buf.get(from..to).unwrap_or(&[]);
                let r = SdoResponse::UploadSegment { toggle, last, data };
                emit(&r, out).map(Some)
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
                    if total > SDO_BUFFER {
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
                        return Reply::Abort {
                            index,
                            sub,
                            code: SdoAbortCode::LengthTooLow,
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
                if n <= 4 && !complete_access {
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

fn emit(r: &SdoResponse<'_>, out: &mut [u8]) -> Result<usize, MailboxErrorCode> {
    r.emit(out).map_err(|_| MailboxErrorCode::NoMoreMemory)
}
