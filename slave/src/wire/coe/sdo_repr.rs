//! SDO requests and responses as `Repr`s: initiate, expedited, normal
//! and segmented transfers, complete access, abort (ETG.1000.6 §5.6.2).

use super::*;

/// Payload of an initiate SDO download request (ETG.1000.6 §5.6.2.1
/// expedited, §5.6.2.2 normal).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DownloadKind<'a> {
    /// Expedited: up to 4 bytes inside the initiate request. `data` holds
    /// the four bytes as on the wire; the first `len` (1..=4) are valid.
    Expedited {
        /// The four data bytes.
        data: [u8; 4],
        /// Number of valid bytes, 1..=4.
        len: u8,
    },
    /// Normal: the object's complete size and the first part of its data
    /// (the rest follows in download segments).
    Normal {
        /// Complete size of the object in bytes.
        complete_size: u32,
        /// Data carried in this request (to the end of the mailbox data).
        data: &'a [u8],
    },
}

impl DownloadKind<'_> {
    /// The valid data bytes carried in the initiate request.
    pub fn data(&self) -> &[u8] {
        match self {
            Self::Expedited { data, len } => data.get(..usize::from(*len)).unwrap_or(data),
            Self::Normal { data, .. } => data,
        }
    }
}

/// An SDO request from the client (master) (ETG.1000.6 §5.6.2: initiate
/// download §5.6.2.1/2, download segment §5.6.2.3, initiate upload
/// §5.6.2.4/5, upload segment §5.6.2.6, abort §5.6.2.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SdoRequest<'a> {
    /// Initiate SDO download (CCS 1).
    InitiateDownload {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// Expedited or normal payload.
        kind: DownloadKind<'a>,
    },
    /// Download SDO segment (CCS 0).
    DownloadSegment {
        /// Toggle bit.
        toggle: bool,
        /// Last segment.
        last: bool,
        /// Segment data, padding removed.
        data: &'a [u8],
    },
    /// Initiate SDO upload (CCS 2).
    InitiateUpload {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
    },
    /// Upload SDO segment (CCS 3).
    UploadSegment {
        /// Toggle bit.
        toggle: bool,
    },
    /// Abort SDO transfer (CCS 4).
    Abort {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Abort code.
        code: SdoAbortCode,
    },
    /// A request with an unknown command specifier (5..=7).
    Unknown {
        /// The raw command byte.
        command: u8,
    },
}

/// An SDO response from the server (slave) (ETG.1000.6 §5.6.2: initiate
/// download response, download segment response, initiate upload response
/// expedited/normal, upload segment response (Table 39), abort).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SdoResponse<'a> {
    /// Initiate SDO download response (SCS 3).
    InitiateDownloadAck {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access, echoed from the request.
        complete_access: bool,
    },
    /// Download SDO segment response (SCS 1).
    DownloadSegmentAck {
        /// Toggle bit, echoed from the request.
        toggle: bool,
    },
    /// Initiate SDO upload response, expedited (SCS 2, e = 1).
    UploadExpedited {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// The four data bytes; the first `len` are valid.
        data: [u8; 4],
        /// Number of valid bytes, 1..=4.
        len: u8,
    },
    /// Initiate SDO upload response, normal (SCS 2, e = 0).
    UploadNormal {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// Complete size of the object.
        complete_size: u32,
        /// First part of the data (to the end of the mailbox data).
        data: &'a [u8],
    },
    /// Upload SDO segment response (SCS 0).
    UploadSegment {
        /// Toggle bit, echoed from the request.
        toggle: bool,
        /// Last segment.
        last: bool,
        /// Segment data, padding removed.
        data: &'a [u8],
    },
    /// Abort SDO transfer (SCS 4).
    Abort {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Abort code.
        code: SdoAbortCode,
    },
    /// A response with an unknown command specifier (5..=7).
    Unknown {
        /// The raw command byte.
        command: u8,
    },
}

pub(super) fn initiate_cmd(specifier: u8, complete_access: bool) -> u8 {
    (specifier << CMD_SPECIFIER_SHIFT)
        | if complete_access {
            CMD_COMPLETE_ACCESS
        } else {
            0
        }
}

pub(super) fn segment_cmd(specifier: u8, toggle: bool, last: bool, data_len: usize) -> u8 {
    let unused = SEGMENT_MIN_DATA_LEN.saturating_sub(data_len);
    // `unused` is at most 7, so it fits in the 3-bit field.
    let unused = (unused as u8) & 0x07;
    (specifier << CMD_SPECIFIER_SHIFT)
        | if toggle { CMD_TOGGLE } else { 0 }
        | (unused << 1)
        | if last { CMD_LAST_SEGMENT } else { 0 }
}

pub(super) fn segment_len(data_len: usize) -> usize {
    1 + data_len.max(SEGMENT_MIN_DATA_LEN)
}

/// Command byte of an expedited initiate (download request or upload
/// response) with `len` valid bytes; `Unrepresentable` unless 1..=4.
pub(super) fn expedited_cmd(
    specifier: u8,
    complete_access: bool,
    len: u8,
) -> Result<u8, WireError> {
    if !(1..=4).contains(&len) {
        return Err(WireError::Unrepresentable);
    }
    Ok(initiate_cmd(specifier, complete_access)
        | ((4 - len) << 2)
        | CMD_EXPEDITED
        | CMD_SIZE_INDICATOR)
}

/// Zeroes `buf[..len]` after checking it fits, returning the view to fill.
pub(super) fn prepare(buf: &mut [u8], len: usize) -> Result<Sdo<&mut [u8]>, WireError> {
    let region = buf.get_mut(..len).ok_or(WireError::BufferTooSmall)?;
    region.fill(0);
    Ok(Sdo::new_unchecked(region))
}

pub(super) fn emit_initiate(
    buf: &mut [u8],
    command: u8,
    index: u16,
    sub: u8,
    data4: [u8; 4],
    extra: &[u8],
) -> Result<usize, WireError> {
    let len = SDO_LEN + extra.len();
    let mut sdo = prepare(buf, len)?;
    sdo.set_command(command);
    sdo.set_index(index);
    sdo.set_sub_index(sub);
    sdo.set_data4(data4);
    crate::wire::set_bytes(sdo.normal_data_mut(), 0, extra);
    Ok(len)
}

pub(super) fn emit_segment(buf: &mut [u8], command: u8, data: &[u8]) -> Result<usize, WireError> {
    let len = segment_len(data.len());
    let mut sdo = prepare(buf, len)?;
    sdo.set_command(command);
    crate::wire::set_bytes(sdo.segment_data_mut(), 0, data);
    Ok(len)
}

impl<'a> SdoRequest<'a> {
    /// Parses a request from the bytes after the CoE header, which must be
    /// bounded by the mailbox length (normal and segment data run to the end
    /// of `sdo`).
    ///
    /// Fails only with [`WireError::Truncated`] when fewer than 8 bytes are
    /// given; unknown command specifiers give [`SdoRequest::Unknown`].
    pub fn parse(sdo: &'a [u8]) -> Result<Self, WireError> {
        let v = Sdo::new_checked(sdo)?;
        let index = v.index();
        let sub = v.sub_index();
        let complete_access = v.complete_access();
        let repr = match v.command_specifier() {
            ccs::INITIATE_DOWNLOAD => {
                let kind = if v.expedited() {
                    DownloadKind::Expedited {
                        data: v.data4(),
                        len: v.expedited_len(),
                    }
                } else {
                    DownloadKind::Normal {
                        complete_size: v.complete_size(),
                        data: crate::wire::tail(sdo, field::SDO_NORMAL_DATA),
                    }
                };
                Self::InitiateDownload {
                    index,
                    sub,
                    complete_access,
                    kind,
                }
            }
            ccs::DOWNLOAD_SEGMENT => Self::DownloadSegment {
                toggle: v.toggle(),
                last: v.last_segment(),
                data: segment_data(sdo),
            },
            ccs::INITIATE_UPLOAD => Self::InitiateUpload {
                index,
                sub,
                complete_access,
            },
            ccs::UPLOAD_SEGMENT => Self::UploadSegment { toggle: v.toggle() },
            ccs::ABORT => Self::Abort {
                index,
                sub,
                code: v.abort_code(),
            },
            _ => Self::Unknown {
                command: v.command(),
            },
        };
        Ok(repr)
    }

    /// Number of bytes [`SdoRequest::emit`] writes (after the CoE header).
    pub fn buffer_len(&self) -> usize {
        match self {
            Self::InitiateDownload {
                kind: DownloadKind::Normal { data, .. },
                ..
            } => SDO_LEN + data.len(),
            Self::DownloadSegment { data, .. } => segment_len(data.len()),
            _ => SDO_LEN,
        }
    }

    /// Writes the request into `buf` (the bytes after the CoE header) and
    /// returns the number of bytes written; padding bytes are zeroed.
    ///
    /// Fails with [`WireError::BufferTooSmall`] if `buf` is shorter than
    /// [`SdoRequest::buffer_len`] and with [`WireError::Unrepresentable`]
    /// for expedited data lengths outside 1..=4.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, WireError> {
        match *self {
            Self::InitiateDownload {
                index,
                sub,
                complete_access,
                kind,
            } => match kind {
                DownloadKind::Expedited { data, len } => {
                    let cmd = expedited_cmd(ccs::INITIATE_DOWNLOAD, complete_access, len)?;
                    emit_initiate(buf, cmd, index, sub, data, &[])
                }
                DownloadKind::Normal {
                    complete_size,
                    data,
                } => {
                    let cmd =
                        initiate_cmd(ccs::INITIATE_DOWNLOAD, complete_access) | CMD_SIZE_INDICATOR;
                    emit_initiate(buf, cmd, index, sub, complete_size.to_le_bytes(), data)
                }
            },
            Self::DownloadSegment { toggle, last, data } => emit_segment(
                buf,
                segment_cmd(ccs::DOWNLOAD_SEGMENT, toggle, last, data.len()),
                data,
            ),
            Self::InitiateUpload {
                index,
                sub,
                complete_access,
            } => emit_initiate(
                buf,
                initiate_cmd(ccs::INITIATE_UPLOAD, complete_access),
                index,
                sub,
                [0; 4],
                &[],
            ),
            Self::UploadSegment { toggle } => emit_segment(
                buf,
                (ccs::UPLOAD_SEGMENT << CMD_SPECIFIER_SHIFT) | if toggle { CMD_TOGGLE } else { 0 },
                &[],
            ),
            Self::Abort { index, sub, code } => emit_initiate(
                buf,
                ccs::ABORT << CMD_SPECIFIER_SHIFT,
                index,
                sub,
                u32::from(code).to_le_bytes(),
                &[],
            ),
            Self::Unknown { command } => emit_initiate(buf, command, 0, 0, [0; 4], &[]),
        }
    }
}

impl<'a> SdoResponse<'a> {
    /// Parses a response from the bytes after the CoE header, which must be
    /// bounded by the mailbox length (normal and segment data run to the end
    /// of `sdo`).
    ///
    /// Fails only with [`WireError::Truncated`] when fewer than 8 bytes are
    /// given; unknown command specifiers give [`SdoResponse::Unknown`].
    pub fn parse(sdo: &'a [u8]) -> Result<Self, WireError> {
        let v = Sdo::new_checked(sdo)?;
        let index = v.index();
        let sub = v.sub_index();
        let complete_access = v.complete_access();
        let repr = match v.command_specifier() {
            scs::INITIATE_DOWNLOAD => Self::InitiateDownloadAck {
                index,
                sub,
                complete_access,
            },
            scs::DOWNLOAD_SEGMENT => Self::DownloadSegmentAck { toggle: v.toggle() },
            scs::INITIATE_UPLOAD if v.expedited() => Self::UploadExpedited {
                index,
                sub,
                complete_access,
                data: v.data4(),
                len: v.expedited_len(),
            },
            scs::INITIATE_UPLOAD => Self::UploadNormal {
                index,
                sub,
                complete_access,
                complete_size: v.complete_size(),
                data: crate::wire::tail(sdo, field::SDO_NORMAL_DATA),
            },
            scs::UPLOAD_SEGMENT => Self::UploadSegment {
                toggle: v.toggle(),
                last: v.last_segment(),
                data: segment_data(sdo),
            },
            scs::ABORT => Self::Abort {
                index,
                sub,
                code: v.abort_code(),
            },
            _ => Self::Unknown {
                command: v.command(),
            },
        };
        Ok(repr)
    }

    /// Number of bytes [`SdoResponse::emit`] writes (after the CoE header).
    pub fn buffer_len(&self) -> usize {
        match self {
            Self::UploadNormal { data, .. } => SDO_LEN + data.len(),
            Self::UploadSegment { data, .. } => segment_len(data.len()),
            _ => SDO_LEN,
        }
    }

    /// Writes the response into `buf` (the bytes after the CoE header) and
    /// returns the number of bytes written; padding bytes are zeroed.
    ///
    /// Fails with [`WireError::BufferTooSmall`] if `buf` is shorter than
    /// [`SdoResponse::buffer_len`] and with [`WireError::Unrepresentable`]
    /// for expedited data lengths outside 1..=4.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, WireError> {
        match *self {
            Self::InitiateDownloadAck {
                index,
                sub,
                complete_access,
            } => emit_initiate(
                buf,
                initiate_cmd(scs::INITIATE_DOWNLOAD, complete_access),
                index,
                sub,
                [0; 4],
                &[],
            ),
            Self::DownloadSegmentAck { toggle } => emit_segment(
                buf,
                (scs::DOWNLOAD_SEGMENT << CMD_SPECIFIER_SHIFT)
                    | if toggle { CMD_TOGGLE } else { 0 },
                &[],
            ),
            Self::UploadExpedited {
                index,
                sub,
                complete_access,
                data,
                len,
            } => {
                let cmd = expedited_cmd(scs::INITIATE_UPLOAD, complete_access, len)?;
                // Unused expedited bytes are sent as zero.
                let mut four = [0u8; 4];
                crate::wire::set_bytes(&mut four, 0, data.get(..usize::from(len)).unwrap_or(&data));
                emit_initiate(buf, cmd, index, sub, four, &[])
            }
            Self::UploadNormal {
                index,
                sub,
                complete_access,
                complete_size,
                data,
            } => emit_initiate(
                buf,
                initiate_cmd(scs::INITIATE_UPLOAD, complete_access) | CMD_SIZE_INDICATOR,
                index,
                sub,
                complete_size.to_le_bytes(),
                data,
            ),
            Self::UploadSegment { toggle, last, data } => emit_segment(
                buf,
                segment_cmd(scs::UPLOAD_SEGMENT, toggle, last, data.len()),
                data,
            ),
            Self::Abort { index, sub, code } => emit_initiate(
                buf,
                scs::ABORT << CMD_SPECIFIER_SHIFT,
                index,
                sub,
                u32::from(code).to_le_bytes(),
                &[],
            ),
            Self::Unknown { command } => emit_initiate(buf, command, 0, 0, [0; 4], &[]),
        }
    }
}

/// Segment data of `sdo` with the lifetime of the input slice.
pub(super) fn segment_data(sdo: &[u8]) -> &[u8] {
    let region = crate::wire::tail(sdo, field::SEGMENT_DATA);
    let used = Sdo::new_unchecked(sdo).segment_data().len();
    region.get(..used).unwrap_or(&[])
}
