//! A raw mailbox client on top of ethercrab's register access.
//!
//! It writes the slave's receive mailbox (SM0) with FPWR, polls the send
//! mailbox (SM1) status and reads it with FPRD, and implements what
//! ethercrab 0.7 lacks: normal and segmented SDO transfers in both
//! directions, complete access, mailbox error replies and repeat requests.
//! Frames are encoded and decoded with `ecat_slave::wire`, the same views
//! the slave uses; the SDO state machine on each side is separate code.

use crate::registers;
use ecat_slave::wire::coe::{
    CoeHeader, CoeService, DownloadKind, SdoAbortCode, SdoRequest, SdoResponse,
};
use ecat_slave::wire::mailbox::{
    HEADER_LEN, Mailbox, MailboxError as WireMailboxError, MailboxErrorCode, MailboxRepr,
    MailboxType, next_counter,
};
use ethercrab::{Command, MainDevice};
use std::time::{Duration, Instant};

/// Errors of the mailbox client.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// ethercrab failed to exchange the frame.
    #[error("ethercrab: {0}")]
    Ethercrab(#[from] ethercrab::error::Error),
    /// The slave did not answer in time.
    #[error("no mailbox response within {0:?}")]
    Timeout(Duration),
    /// The slave's receive mailbox stayed full.
    #[error("the slave's receive mailbox stays full")]
    MailboxFull,
    /// The slave answered with a mailbox error reply.
    #[error("mailbox error reply: {0}")]
    Mailbox(MailboxErrorCode),
    /// The slave aborted an SDO transfer.
    #[error("SDO {index:#06x}:{sub:02x} aborted with {code}")]
    Abort {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// The abort code.
        code: SdoAbortCode,
    },
    /// The reply was not what the protocol allows here.
    #[error("unexpected reply: {0}")]
    Protocol(String),
    /// The request does not fit into the mailbox.
    #[error("request of {0} bytes does not fit the mailbox")]
    TooLong(usize),
    /// The slave refused a file transfer with a FoE error.
    #[error("FoE error {code:#06x}: {text}")]
    Foe {
        /// FoE error code (0x8000..).
        code: u32,
        /// The slave's error text.
        text: String,
    },
    /// The slave refused a requested AL state.
    #[error("state change refused: AL status {status:#06x}, AL status code {code:#06x} ({})", ecat_slave::al::AlStatusCode::from_code(*code).text())]
    StateRefused {
        /// AL status (0x0130).
        status: u16,
        /// AL status code (0x0134).
        code: u16,
    },
}

impl ClientError {
    /// Whether the slave itself said no (an SDO abort, a mailbox error
    /// reply, a FoE error, a refused state change), as opposed to a
    /// communication or usage problem.
    pub fn refused_by_device(&self) -> bool {
        matches!(
            self,
            ClientError::Abort { .. }
                | ClientError::Mailbox(_)
                | ClientError::Foe { .. }
                | ClientError::StateRefused { .. }
        )
    }
}

impl ClientError {
    /// The FoE error code, if this is a FoE error.
    pub fn foe_code(&self) -> Option<u32> {
        match self {
            ClientError::Foe { code, .. } => Some(*code),
            _ => None,
        }
    }

    /// The SDO abort code, if this is an abort.
    pub fn abort_code(&self) -> Option<u32> {
        match self {
            ClientError::Abort { code, .. } => Some(u32::from(*code)),
            _ => None,
        }
    }
}

/// One received mailbox message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Message {
    /// Mailbox type.
    pub kind: MailboxType,
    /// Counter the slave used.
    pub counter: u8,
    /// Payload (after the 6-byte header).
    pub payload: Vec<u8>,
}

/// Mailbox geometry of a slave: SM0 and SM1 start and size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MailboxGeometry {
    /// Receive mailbox (master to slave, SM0): start, size.
    pub out: (u16, u16),
    /// Send mailbox (slave to master, SM1): start, size.
    pub inp: (u16, u16),
}

/// The 8-byte SyncManager register image ([`registers::sm`]): start address,
/// length, control byte, activate (enable bit) as ETG.1000.4 lays it out.
pub fn sm_register(start: u16, len: u16, control: u8, enable: bool) -> [u8; 8] {
    let mut b = [0u8; 8];
    b[0..2].copy_from_slice(&start.to_le_bytes());
    b[2..4].copy_from_slice(&len.to_le_bytes());
    b[4] = control;
    b[6] = u8::from(enable);
    b
}

impl MailboxGeometry {
    /// SM0 (master to slave, control 0x26) and SM1 (slave to master, 0x22)
    /// register images for this mailbox, with their register addresses.
    pub fn sm_registers(&self) -> [(u16, [u8; 8]); 2] {
        [
            (
                registers::SM0,
                sm_register(self.out.0, self.out.1, 0x26, true),
            ),
            (
                registers::SM1,
                sm_register(self.inp.0, self.inp.1, 0x22, true),
            ),
        ]
    }

    /// The PAM-199-P-ETC's bootstrap mailbox (BOOT state).
    pub fn bootstrap() -> Self {
        Self::bootstrap_of(&pam_199_p_etc::DEVICE.layout())
    }

    /// The PAM-199-P-ETC's standard mailbox (128 bytes at 0x1000/0x1080,
    /// the core's default).
    pub fn standard() -> Self {
        Self::of(&pam_199_p_etc::DEVICE.layout())
    }

    /// The bootstrap mailbox of a memory layout.
    pub fn bootstrap_of(l: &ecat_slave::device::MemoryLayout) -> Self {
        MailboxGeometry {
            out: l.boot_out,
            inp: l.boot_in,
        }
    }

    /// The standard mailbox of a memory layout.
    pub fn of(l: &ecat_slave::device::MemoryLayout) -> Self {
        MailboxGeometry {
            out: l.mbx_out,
            inp: l.mbx_in,
        }
    }
}

/// A mailbox client for one slave.
pub struct MailboxClient<'a> {
    md: &'a MainDevice<'a>,
    station: u16,
    geometry: MailboxGeometry,
    counter: u8,
    started: bool,
    /// How long to wait for a response.
    pub timeout: Duration,
    /// Accept an SDO abort sent as CoE service 3 (SDO response) as an abort
    /// instead of refusing it as a protocol error: for checks that look at
    /// the abort code only (the conformance checker tests the service
    /// separately).
    pub lenient_abort_service: bool,
    /// CoE Emergency messages that arrived while waiting for an SDO answer
    /// (the CoE payloads, header included), oldest first.
    pub emergencies: Vec<Vec<u8>>,
}

impl<'a> MailboxClient<'a> {
    /// A client for the slave at configured address `station`.
    pub fn new(md: &'a MainDevice<'a>, station: u16, geometry: MailboxGeometry) -> Self {
        MailboxClient {
            md,
            station,
            geometry,
            counter: 0,
            started: false,
            timeout: Duration::from_secs(2),
            lenient_abort_service: false,
            emergencies: Vec::new(),
        }
    }

    /// Largest payload of one message (mailbox size minus the header).
    pub fn max_payload(&self) -> usize {
        usize::from(self.geometry.out.1.min(self.geometry.inp.1)).saturating_sub(HEADER_LEN)
    }

    /// Sends one mailbox message of `kind` with `payload`, using the next
    /// counter value. Returns the counter used.
    pub async fn send(&mut self, kind: MailboxType, payload: &[u8]) -> Result<u8, ClientError> {
        // The first message goes out with counter 0 ("not used"): another
        // master (ethercrab) may have used any counter before, and a slave
        // ignores a message that repeats its last counter.
        let counter = if self.started {
            self.counter = next_counter(self.counter);
            self.counter
        } else {
            self.started = true;
            0
        };
        self.send_raw(kind, counter, payload).await?;
        Ok(counter)
    }

    /// Sends a message with an explicit counter (to test repeats).
    pub async fn send_raw(
        &mut self,
        kind: MailboxType,
        counter: u8,
        payload: &[u8],
    ) -> Result<(), ClientError> {
        let size = usize::from(self.geometry.out.1);
        if payload.len() + HEADER_LEN > size {
            return Err(ClientError::TooLong(payload.len()));
        }
        let mut buf = vec![0u8; size];
        MailboxRepr {
            length: payload.len() as u16,
            address: 0,
            channel: 0,
            priority: 0,
            mailbox_type: kind,
            counter,
        }
        .emit(&mut Mailbox::new_unchecked(&mut buf[..]))
        .map_err(|e| ClientError::Protocol(e.to_string()))?;
        buf[HEADER_LEN..HEADER_LEN + payload.len()].copy_from_slice(payload);
        self.write_buffer(&buf).await
    }

    /// Writes a whole, preformatted SM0 buffer (for malformed-header tests).
    pub async fn write_buffer(&mut self, buf: &[u8]) -> Result<(), ClientError> {
        let start = Instant::now();
        loop {
            match Command::fpwr(self.station, self.geometry.out.0)
                .with_wkc(1)
                .send(self.md, buf)
                .await
            {
                Ok(()) => return Ok(()),
                // A full mailbox refuses the write: working counter 0.
                Err(ethercrab::error::Error::WorkingCounter { .. }) => {}
                Err(e) => return Err(e.into()),
            }
            if start.elapsed() > self.timeout {
                return Err(ClientError::MailboxFull);
            }
            smol::Timer::after(Duration::from_micros(200)).await;
        }
    }

    /// Waits for the next message in SM1 and reads it.
    pub async fn receive(&mut self) -> Result<Message, ClientError> {
        let start = Instant::now();
        let status_reg = registers::SM1 + registers::SM_STATUS;
        loop {
            let status: u8 = Command::fprd(self.station, status_reg)
                .receive(self.md)
                .await?;
            if status & 0x08 != 0 {
                break;
            }
            if start.elapsed() > self.timeout {
                return Err(ClientError::Timeout(self.timeout));
            }
            smol::Timer::after(Duration::from_micros(100)).await;
        }
        let data = Command::fprd(self.station, self.geometry.inp.0)
            .receive_slice(self.md, self.geometry.inp.1)
            .await?;
        let mbx =
            Mailbox::new_checked(&data[..]).map_err(|e| ClientError::Protocol(e.to_string()))?;
        Ok(Message {
            kind: mbx.mailbox_type(),
            counter: mbx.counter(),
            payload: mbx.payload().to_vec(),
        })
    }

    /// Toggles the repeat request bit of SM1 and waits for the slave's
    /// acknowledge, then reads the repeated message.
    pub async fn repeat(&mut self) -> Result<Message, ClientError> {
        let activate_reg = registers::SM1 + registers::SM_ACTIVATE;
        let pdi_reg = registers::SM1 + registers::SM_PDI_CONTROL;
        let act: u8 = Command::fprd(self.station, activate_reg)
            .receive(self.md)
            .await?;
        let want = (act & 0x02) ^ 0x02;
        Command::fpwr(self.station, activate_reg)
            .send(self.md, act ^ 0x02)
            .await?;
        let start = Instant::now();
        loop {
            let pdi: u8 = Command::fprd(self.station, pdi_reg)
                .receive(self.md)
                .await?;
            if pdi & 0x02 == want {
                break;
            }
            if start.elapsed() > self.timeout {
                return Err(ClientError::Timeout(self.timeout));
            }
            smol::Timer::after(Duration::from_micros(100)).await;
        }
        self.receive().await
    }

    /// Sends a CoE SDO request and returns the SDO response bytes.
    async fn sdo_exchange(&mut self, request: &SdoRequest<'_>) -> Result<Vec<u8>, ClientError> {
        let mut payload = vec![0u8; CoeHeader::<&[u8]>::HEADER_LEN + request.buffer_len()];
        CoeHeader::emit_into(&mut payload[..2], 0, CoeService::SdoRequest);
        request
            .emit(&mut payload[2..])
            .map_err(|e| ClientError::Protocol(e.to_string()))?;
        self.send(MailboxType::CoE, &payload).await?;
        loop {
            let msg = self.receive().await?;
            match msg.kind {
                MailboxType::Error => {
                    let e = WireMailboxError::new_checked(&msg.payload[..])
                        .map_err(|e| ClientError::Protocol(e.to_string()))?;
                    return Err(ClientError::Mailbox(e.detail()));
                }
                MailboxType::CoE => {
                    let coe = CoeHeader::new_checked(&msg.payload[..])
                        .map_err(|e| ClientError::Protocol(e.to_string()))?;
                    let sdo = &msg.payload[2..];
                    match coe.service() {
                        // ETG.1000.6 5.6.2.7: "Abort SDO Transfer" is an
                        // SDO request (service 2), whichever side sends it.
                        CoeService::SdoRequest => {
                            return match SdoRequest::parse(sdo) {
                                Ok(SdoRequest::Abort { index, sub, code }) => {
                                    Err(ClientError::Abort { index, sub, code })
                                }
                                Ok(other) => Err(ClientError::Protocol(format!(
                                    "the slave sent an SDO request that is not an abort: {other:?}"
                                ))),
                                Err(e) => Err(ClientError::Protocol(e.to_string())),
                            };
                        }
                        CoeService::SdoResponse => {
                            // A response with command specifier 4 is not an
                            // abort: SOEM and Wireshark would read it as a
                            // successful transfer. Refuse it.
                            if let Ok(SdoResponse::Abort { index, sub, code }) =
                                SdoResponse::parse(sdo)
                            {
                                if self.lenient_abort_service {
                                    return Err(ClientError::Abort { index, sub, code });
                                }
                                return Err(ClientError::Protocol(format!(
                                    "SDO abort {:#010x} sent as CoE service 3 (SDO response); ETG.1000.6 sends Abort SDO Transfer as service 2 (SDO request)",
                                    u32::from(code)
                                )));
                            }
                            return Ok(sdo.to_vec());
                        }
                        CoeService::Emergency => {
                            self.emergencies.push(msg.payload.clone());
                            continue;
                        }
                        // Other services are not the answer.
                        _ => continue,
                    }
                }
                other => return Err(ClientError::Protocol(format!("mailbox type {other:?}"))),
            }
        }
    }

    fn check_abort(resp: &SdoResponse<'_>) -> Result<(), ClientError> {
        if let SdoResponse::Abort { index, sub, code } = resp {
            return Err(ClientError::Abort {
                index: *index,
                sub: *sub,
                code: *code,
            });
        }
        Ok(())
    }

    /// Uploads `index:sub` (whole object with `complete_access`), using
    /// whatever transfer type the slave chooses (expedited, normal,
    /// segmented).
    pub async fn sdo_upload(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
    ) -> Result<Vec<u8>, ClientError> {
        let raw = self
            .sdo_exchange(&SdoRequest::InitiateUpload {
                index,
                sub,
                complete_access,
            })
            .await?;
        let resp = SdoResponse::parse(&raw).map_err(|e| ClientError::Protocol(e.to_string()))?;
        Self::check_abort(&resp)?;
        let (total, mut data) = match resp {
            SdoResponse::UploadExpedited { data, len, .. } => {
                return Ok(data[..usize::from(len)].to_vec());
            }
            SdoResponse::UploadNormal {
                complete_size,
                data,
                ..
            } => (complete_size as usize, data.to_vec()),
            other => return Err(ClientError::Protocol(format!("{other:?}"))),
        };
        let mut toggle = false;
        while data.len() < total {
            let raw = self
                .sdo_exchange(&SdoRequest::UploadSegment { toggle })
                .await?;
            let resp =
                SdoResponse::parse(&raw).map_err(|e| ClientError::Protocol(e.to_string()))?;
            Self::check_abort(&resp)?;
            let SdoResponse::UploadSegment {
                toggle: t,
                last,
                data: seg,
            } = resp
            else {
                return Err(ClientError::Protocol(format!("{resp:?}")));
            };
            if t != toggle {
                return Err(ClientError::Protocol("toggle bit mismatch".into()));
            }
            data.extend_from_slice(seg);
            toggle = !toggle;
            if last {
                break;
            }
        }
        data.truncate(total);
        Ok(data)
    }

    /// Downloads `data` into `index:sub`: expedited up to 4 bytes, else
    /// normal with as much as fits and segments for the rest.
    pub async fn sdo_download(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        data: &[u8],
    ) -> Result<(), ClientError> {
        // Nothing (an empty string) has no expedited form: a normal
        // download of size 0.
        self.sdo_download_with(
            index,
            sub,
            complete_access,
            data,
            data.is_empty() || data.len() > 4,
        )
        .await
    }

    /// Like [`MailboxClient::sdo_download`], forcing the normal/segmented
    /// path even for short data when `force_normal` is set.
    pub async fn sdo_download_with(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        data: &[u8],
        force_normal: bool,
    ) -> Result<(), ClientError> {
        let room = usize::from(self.geometry.out.1) - HEADER_LEN - 2 - 10;
        let first = if force_normal || data.len() > 4 {
            // Put at most one byte in the initiate request when forcing the
            // segmented path, so short data is segmented too.
            let n = if force_normal && data.len() <= 4 {
                0
            } else {
                data.len().min(room)
            };
            DownloadKind::Normal {
                complete_size: data.len() as u32,
                data: &data[..n],
            }
        } else {
            let mut d = [0u8; 4];
            d[..data.len()].copy_from_slice(data);
            DownloadKind::Expedited {
                data: d,
                len: data.len() as u8,
            }
        };
        let mut sent = match &first {
            DownloadKind::Normal { data, .. } => data.len(),
            DownloadKind::Expedited { len, .. } => usize::from(*len),
        };
        let raw = self
            .sdo_exchange(&SdoRequest::InitiateDownload {
                index,
                sub,
                complete_access,
                kind: first,
            })
            .await?;
        let resp = SdoResponse::parse(&raw).map_err(|e| ClientError::Protocol(e.to_string()))?;
        Self::check_abort(&resp)?;
        let seg_room = usize::from(self.geometry.out.1) - HEADER_LEN - 2 - 1;
        let mut toggle = false;
        while sent < data.len() {
            let n = (data.len() - sent).min(seg_room);
            let last = sent + n == data.len();
            self.download_segment(toggle, last, &data[sent..sent + n])
                .await?;
            sent += n;
            toggle = !toggle;
        }
        Ok(())
    }

    /// Sends one download segment and checks the acknowledge (exposed so
    /// tests can interrupt a transfer midway or send a wrong toggle).
    pub async fn download_segment(
        &mut self,
        toggle: bool,
        last: bool,
        data: &[u8],
    ) -> Result<(), ClientError> {
        let raw = self
            .sdo_exchange(&SdoRequest::DownloadSegment { toggle, last, data })
            .await?;
        let resp = SdoResponse::parse(&raw).map_err(|e| ClientError::Protocol(e.to_string()))?;
        Self::check_abort(&resp)?;
        match resp {
            SdoResponse::DownloadSegmentAck { toggle: t } if t == toggle => Ok(()),
            other => Err(ClientError::Protocol(format!("{other:?}"))),
        }
    }

    /// Starts a segmented download announcing `total` bytes and sending
    /// `first` with the initiate request (for interruption tests).
    pub async fn begin_download(
        &mut self,
        index: u16,
        sub: u8,
        total: u32,
        first: &[u8],
    ) -> Result<(), ClientError> {
        let raw = self
            .sdo_exchange(&SdoRequest::InitiateDownload {
                index,
                sub,
                complete_access: false,
                kind: DownloadKind::Normal {
                    complete_size: total,
                    data: first,
                },
            })
            .await?;
        let resp = SdoResponse::parse(&raw).map_err(|e| ClientError::Protocol(e.to_string()))?;
        Self::check_abort(&resp)
    }
}
