//! Mailbox messages to one software PAM slave in PRE-OP, SAFE-OP, OP or
//! BOOT.
//!
//! Input: one header byte (`% 4`: PRE-OP, SAFE-OP, OP, BOOT; the slave is
//! brought there through frames, mailbox SyncManagers from its SII), then
//! records (see `ecat_fuzz::records`), tags `% 8`:
//!
//! - 0, 7: a raw mailbox message (padded or cut to the SM0 size) written
//!   with FPWR into SM0;
//! - 1: a structured message (`arbitrary`): CoE SDO upload/download
//!   (expedited, normal, segments, complete access), abort, SDO
//!   Information, Emergency, other CoE services, FoE read/write/data/ack/
//!   busy/error/unknown (data packets may carry a valid PAM `.efw` image),
//!   unknown mailbox types; with lies about the mailbox header;
//! - 2: read the reply mailbox (SM1);
//! - 3: idle time (the firmware polls);
//! - 4: a write of any bytes anywhere in the mailbox RAM (partial buffers),
//!   at most one datagram's worth;
//! - 5: the SM1 repeat request toggled;
//! - 6: a read of part of SM1.
//!
//! In OP every record is followed by an LRW process data cycle. Invariants:
//! no panic; every message sent and every reply read round-trips through
//! the wire `Repr`s (parse -> emit -> parse); after the input the slave
//! still answers APRD of AL status in a mailbox state, and the mailbox is
//! not stuck: a well-formed SDO upload of 0x1000:00 gets its response.
#![no_main]

use std::sync::OnceLock;

use arbitrary::{Arbitrary, Unstructured};
use ecat_fuzz::line::{self, Line, SiiSetup, Target};
use ecat_fuzz::records::Records;
use ecat_fuzz::roundtrip;
use ecat_slave::firmware::{EFW_HEADER_LEN, EfwHeaderRepr, FirmwareVersion, pack};
use ecat_slave::wire::coe::{
    CoeHeader, CoeService, Emergency as EmergencyView, EmergencyRepr, SdoAbortCode,
    SdoInfo as SdoInfoView, SdoInfoOpcode, SdoInfoRepr, SdoRequest, SdoResponse,
};
use ecat_slave::wire::foe::{FoeErrorCode, FoeRepr};
use ecat_slave::wire::mailbox::{HEADER_LEN, Mailbox, MailboxRepr, MailboxType};
use libfuzzer_sys::fuzz_target;

/// Most records taken from one input.
const MAX_RECORDS: usize = 64;

/// An object index: one of the PAM's, or any.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Index {
    Known(u16),
    Raw(u16),
}

impl Index {
    fn value(self) -> u16 {
        match self {
            Index::Known(k) => {
                let objects = pam_199_p_etc::DEVICE.dictionary.objects();
                objects[usize::from(k) % objects.len()].index
            }
            Index::Raw(i) => i,
        }
    }
}

/// A FoE file name.
#[derive(Arbitrary, Debug)]
enum Name {
    Firmware,
    Info,
    Other(Vec<u8>),
}

impl Name {
    fn bytes(&self) -> &[u8] {
        match self {
            Name::Firmware => b"firmware.efw",
            Name::Info => b"info.txt",
            Name::Other(v) => v,
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Body {
    Upload {
        index: Index,
        sub: u8,
        complete: bool,
    },
    UploadSegment {
        toggle: bool,
    },
    DownloadExpedited {
        index: Index,
        sub: u8,
        complete: bool,
        data: [u8; 4],
        len: u8,
    },
    DownloadNormal {
        index: Index,
        sub: u8,
        complete: bool,
        size: Option<u32>,
        data: Vec<u8>,
    },
    DownloadSegment {
        toggle: bool,
        last: bool,
        data: Vec<u8>,
    },
    Abort {
        index: Index,
        sub: u8,
        code: u32,
    },
    SdoRaw {
        command: u8,
        index: Index,
        sub: u8,
        data: [u8; 4],
        tail: Vec<u8>,
    },
    SdoInfo {
        opcode: u8,
        incomplete: bool,
        fragments: u16,
        index: Index,
        sub: u8,
        arg: u16,
        extra: Vec<u8>,
    },
    Emergency {
        code: u16,
        register: u8,
        data: [u8; 5],
    },
    CoeOther {
        service: u8,
        number: u16,
        data: Vec<u8>,
    },
    FoeRead {
        password: u32,
        name: Name,
    },
    FoeWrite {
        password: u32,
        name: Name,
    },
    FoeData {
        packet: u32,
        data: Vec<u8>,
    },
    /// Packet `packet` of a valid PAM `.efw` image, maybe with a flipped byte.
    FoeImage {
        packet: u8,
        flip: Option<(u16, u8)>,
    },
    FoeAck {
        packet: u32,
    },
    FoeBusy {
        done: u16,
        entire: u16,
    },
    FoeError {
        code: u32,
        text: Vec<u8>,
    },
    FoeUnknown {
        opcode: u8,
        word: u32,
        tail: Vec<u8>,
    },
    Other {
        mailbox_type: u8,
        data: Vec<u8>,
    },
}

/// A lie about the mailbox header.
#[derive(Arbitrary, Debug)]
enum Lie {
    Length(u16),
    TypeCounter(u8),
    Truncate(u16),
}

#[derive(Arbitrary, Debug)]
struct Message {
    body: Body,
    counter: u8,
    channel: u8,
    priority: u8,
    address: u16,
    lie: Option<Lie>,
}

/// A PAM `.efw` image of 2500 payload bytes (three FoE packets in BOOT).
fn image() -> &'static [u8] {
    static IMAGE: OnceLock<Vec<u8>> = OnceLock::new();
    IMAGE.get_or_init(|| {
        let payload: Vec<u8> = (0..2500u32).map(|i| (i * 7 + i / 251) as u8).collect();
        let header = EfwHeaderRepr {
            header_len: EFW_HEADER_LEN as u16,
            flags: 0,
            vendor_id: pam_199_p_etc::VENDOR_ID,
            product_code: pam_199_p_etc::PRODUCT_CODE,
            revision_min: 0,
            revision_max: u32::MAX,
            version: FirmwareVersion::new("99").expect("version"),
            payload_len: 0,
            payload_crc: 0,
        };
        let mut out = vec![0u8; payload.len() + 1024];
        let n = pack(&header, &payload, &mut out).expect("pack");
        out.truncate(n);
        out
    })
}

/// At most 1100 bytes of `v` (more never fits a mailbox).
fn cap(v: &[u8]) -> &[u8] {
    &v[..v.len().min(1100)]
}

fn coe(service: CoeService, body: &[u8]) -> Vec<u8> {
    let mut v = vec![0u8; 2 + body.len()];
    CoeHeader::emit_into(&mut v, 0, service);
    v[2..].copy_from_slice(body);
    v
}

fn sdo(req: &SdoRequest<'_>) -> Vec<u8> {
    let mut b = vec![0u8; req.buffer_len()];
    let n = req.emit(&mut b).unwrap_or(0);
    b.truncate(n);
    coe(CoeService::SdoRequest, &b)
}

fn foe(repr: &FoeRepr<'_>) -> Vec<u8> {
    let mut b = vec![0u8; repr.buffer_len()];
    let n = repr.emit(&mut b).unwrap_or(0);
    b.truncate(n);
    b
}

impl Message {
    /// Mailbox type and payload.
    fn payload(&self, sm0_len: usize) -> (MailboxType, Vec<u8>) {
        use Body::*;
        match &self.body {
            Upload {
                index,
                sub,
                complete,
            } => (
                MailboxType::CoE,
                sdo(&SdoRequest::InitiateUpload {
                    index: index.value(),
                    sub: *sub,
                    complete_access: *complete,
                }),
            ),
            UploadSegment { toggle } => (
                MailboxType::CoE,
                sdo(&SdoRequest::UploadSegment { toggle: *toggle }),
            ),
            DownloadExpedited {
                index,
                sub,
                complete,
                data,
                len,
            } => (
                MailboxType::CoE,
                sdo(&SdoRequest::InitiateDownload {
                    index: index.value(),
                    sub: *sub,
                    complete_access: *complete,
                    kind: ecat_slave::wire::coe::DownloadKind::Expedited {
                        data: *data,
                        len: len % 4 + 1,
                    },
                }),
            ),
            DownloadNormal {
                index,
                sub,
                complete,
                size,
                data,
            } => (
                MailboxType::CoE,
                sdo(&SdoRequest::InitiateDownload {
                    index: index.value(),
                    sub: *sub,
                    complete_access: *complete,
                    kind: ecat_slave::wire::coe::DownloadKind::Normal {
                        complete_size: size.unwrap_or(data.len() as u32),
                        data: cap(data),
                    },
                }),
            ),
            DownloadSegment { toggle, last, data } => (
                MailboxType::CoE,
                sdo(&SdoRequest::DownloadSegment {
                    toggle: *toggle,
                    last: *last,
                    data: cap(data),
                }),
            ),
            Abort { index, sub, code } => (
                MailboxType::CoE,
                sdo(&SdoRequest::Abort {
                    index: index.value(),
                    sub: *sub,
                    code: SdoAbortCode::from(*code),
                }),
            ),
            SdoRaw {
                command,
                index,
                sub,
                data,
                tail,
            } => {
                let mut b = vec![*command];
                b.extend_from_slice(&index.value().to_le_bytes());
                b.push(*sub);
                b.extend_from_slice(data);
                b.extend_from_slice(cap(tail));
                (MailboxType::CoE, coe(CoeService::SdoRequest, &b))
            }
            SdoInfo {
                opcode,
                incomplete,
                fragments,
                index,
                sub,
                arg,
                extra,
            } => {
                let op = SdoInfoOpcode::from(opcode % 0x80);
                let mut b = vec![0u8; 4];
                let _ = SdoInfoRepr {
                    opcode: op,
                    incomplete: *incomplete,
                    fragments_left: *fragments,
                }
                .emit(&mut SdoInfoView::new_unchecked(&mut b[..]));
                match op {
                    SdoInfoOpcode::GetOdListReq => b.extend_from_slice(&(arg % 6).to_le_bytes()),
                    SdoInfoOpcode::GetObjDescReq => {
                        b.extend_from_slice(&index.value().to_le_bytes())
                    }
                    _ => {
                        b.extend_from_slice(&index.value().to_le_bytes());
                        b.push(*sub);
                        b.push(*arg as u8);
                    }
                }
                b.extend_from_slice(&extra[..extra.len().min(64)]);
                (MailboxType::CoE, coe(CoeService::SdoInformation, &b))
            }
            Emergency {
                code,
                register,
                data,
            } => {
                let mut b = vec![0u8; 8];
                let _ = EmergencyRepr {
                    error_code: *code,
                    error_register: *register,
                    data: *data,
                }
                .emit(&mut EmergencyView::new_unchecked(&mut b[..]));
                (MailboxType::CoE, coe(CoeService::Emergency, &b))
            }
            CoeOther {
                service,
                number,
                data,
            } => {
                let mut v = coe(CoeService::from(service % 16), cap(data));
                v[0..2].copy_from_slice(
                    &((number & 0x01FF) | (u16::from(service % 16) << 12)).to_le_bytes(),
                );
                (MailboxType::CoE, v)
            }
            FoeRead { password, name } => (
                MailboxType::FoE,
                foe(&FoeRepr::ReadRequest {
                    password: *password,
                    name: name.bytes(),
                }),
            ),
            FoeWrite { password, name } => (
                MailboxType::FoE,
                foe(&FoeRepr::WriteRequest {
                    password: *password,
                    name: name.bytes(),
                }),
            ),
            FoeData { packet, data } => (
                MailboxType::FoE,
                foe(&FoeRepr::Data {
                    packet: *packet,
                    data: cap(data),
                }),
            ),
            FoeImage { packet, flip } => {
                let seg = sm0_len.saturating_sub(HEADER_LEN + 6).max(1);
                let img = image();
                let p = usize::from(packet.max(&1) - 1);
                let start = (p * seg).min(img.len());
                let mut data = img[start..(start + seg).min(img.len())].to_vec();
                if let (Some((at, x)), false) = (flip, data.is_empty()) {
                    let i = usize::from(*at) % data.len();
                    data[i] ^= x | 1;
                }
                (
                    MailboxType::FoE,
                    foe(&FoeRepr::Data {
                        packet: u32::from(*packet),
                        data: &data,
                    }),
                )
            }
            FoeAck { packet } => (MailboxType::FoE, foe(&FoeRepr::Ack { packet: *packet })),
            FoeBusy { done, entire } => (
                MailboxType::FoE,
                foe(&FoeRepr::Busy {
                    done: *done,
                    entire: *entire,
                }),
            ),
            FoeError { code, text } => (
                MailboxType::FoE,
                foe(&FoeRepr::Error {
                    code: FoeErrorCode::from(*code),
                    text: cap(text),
                }),
            ),
            FoeUnknown { opcode, word, tail } => {
                let mut b = vec![*opcode, 0];
                b.extend_from_slice(&word.to_le_bytes());
                b.extend_from_slice(cap(tail));
                (MailboxType::FoE, b)
            }
            Other { mailbox_type, data } => {
                (MailboxType::from(mailbox_type % 16), cap(data).to_vec())
            }
        }
    }

    fn bytes(&self, sm0_len: usize) -> Vec<u8> {
        let (ty, payload) = self.payload(sm0_len);
        let mut msg = vec![0u8; HEADER_LEN + payload.len()];
        msg[HEADER_LEN..].copy_from_slice(&payload);
        let _ = MailboxRepr {
            length: payload.len().min(usize::from(u16::MAX)) as u16,
            address: self.address,
            channel: self.channel % 64,
            priority: self.priority % 4,
            mailbox_type: ty,
            counter: self.counter % 8,
        }
        .emit(&mut Mailbox::new_unchecked(&mut msg[..]));
        match self.lie {
            Some(Lie::Length(l)) => msg[0..2].copy_from_slice(&l.to_le_bytes()),
            Some(Lie::TypeCounter(t)) => msg[5] = t,
            Some(Lie::Truncate(n)) => msg.truncate(usize::from(n)),
            None => {}
        }
        msg
    }
}

/// The slave and its mailbox geometry.
struct Harness {
    line: Line,
    /// SM0: start, length.
    out: (u16, u16),
    /// SM1: start, length.
    inp: (u16, u16),
    op: bool,
}

const STATION: u16 = line::FIRST_STATION;

impl Harness {
    /// After each record: process data in OP.
    fn cycle(&mut self) {
        if self.op {
            self.line.lrw_cycle();
        }
    }

    /// Writes a message into SM0 (padded or cut to its size); whether the
    /// ESC took it.
    fn write(&mut self, msg: &[u8]) -> bool {
        roundtrip::mailbox(msg, true);
        let mut buf = msg.to_vec();
        buf.resize(usize::from(self.out.1), 0);
        self.line.fpwr(STATION, self.out.0, &buf)
    }

    /// Reads SM1 if the slave put something there.
    fn read(&mut self) -> Option<Vec<u8>> {
        let reply = self
            .line
            .fprd(STATION, self.inp.0, usize::from(self.inp.1))?;
        roundtrip::mailbox(&reply, false);
        Some(reply)
    }

    /// A write that waits (reading replies away) until SM0 takes it.
    fn write_patiently(&mut self, msg: &[u8]) -> bool {
        for _ in 0..8 {
            if self.write(msg) {
                return true;
            }
            self.read();
            self.cycle();
        }
        false
    }
}

/// Whether `reply` answers an upload of 0x1000:00 with its value.
fn is_device_type(reply: &[u8]) -> bool {
    let Ok(m) = Mailbox::new_checked(reply) else {
        return false;
    };
    if m.mailbox_type() != MailboxType::CoE {
        return false;
    }
    let Ok(c) = CoeHeader::new_checked(m.payload()) else {
        return false;
    };
    if c.service() != CoeService::SdoResponse {
        return false;
    }
    matches!(
        SdoResponse::parse(c.payload()),
        Ok(SdoResponse::UploadExpedited {
            index: 0x1000,
            sub: 0,
            ..
        }) | Ok(SdoResponse::UploadNormal {
            index: 0x1000,
            sub: 0,
            ..
        })
    )
}

fn run(data: &[u8]) {
    let Some((&header, rest)) = data.split_first() else {
        return;
    };
    let target = [Target::PreOp, Target::SafeOp, Target::Op, Target::Boot][usize::from(header % 4)];
    let setup = SiiSetup::pam();
    let (out, inp) = if target == Target::Boot {
        (setup.boot_out, setup.boot_in)
    } else {
        (setup.mbx_out, setup.mbx_in)
    };
    let mut line = Line::pam(1);
    line.bring_up(target).expect("bring-up");
    let mut h = Harness {
        line,
        out,
        inp,
        op: target == Target::Op,
    };
    let ram = (out.0, (inp.0 + inp.1).max(out.0 + out.1) + 16);

    for (tag, body) in Records::new(rest).take(MAX_RECORDS) {
        match tag % 8 {
            1 => {
                let mut u = Unstructured::new(body);
                if let Ok(m) = Message::arbitrary(&mut u) {
                    let bytes = m.bytes(usize::from(out.1));
                    h.write(&bytes);
                }
            }
            2 => {
                h.read();
            }
            3 => {
                let steps = u32::from(body.first().copied().unwrap_or(1)) % 64 + 1;
                h.line.idle(steps);
            }
            4 => {
                let (off, bytes) = match body {
                    [a, b, rest @ ..] => (u16::from_le_bytes([*a, *b]), rest),
                    _ => (0, &[][..]),
                };
                let span = ram.1 - ram.0;
                let at = ram.0 + off % span;
                // The boot mailboxes span more RAM than one datagram carries.
                let n = bytes
                    .len()
                    .min(usize::from(ram.1 - at))
                    .min(line::MAX_DATAGRAM_DATA);
                h.line.fpwr(STATION, at, &bytes[..n]);
            }
            5 => {
                let activate = line::SM_BASE + 8 + 6;
                if let Some(a) = h.line.fprd(STATION, activate, 1) {
                    h.line.fpwr(STATION, activate, &[a[0] ^ 0x02]);
                }
            }
            6 => {
                let n = usize::from(body.first().copied().unwrap_or(0)) % usize::from(inp.1);
                let skip = usize::from(body.get(1).copied().unwrap_or(0)) % usize::from(inp.1);
                let n = n.min(usize::from(inp.1) - skip);
                let _ = h.line.fprd(STATION, inp.0 + skip as u16, n.max(1));
            }
            _ => {
                h.write(body);
            }
        }
        h.cycle();
    }

    // The slave still answers, in a state with a mailbox.
    let st = h
        .line
        .aprd_u16(0, line::AL_STATUS)
        .expect("AL status answered");
    let code = h.line.aprd_u16(0, line::AL_STATUS_CODE);
    assert!(
        matches!(st & 0x0F, 2 | 3 | 4 | 8),
        "slave left the mailbox states: AL status {st:#06x}, code {code:x?} (from {target:?})"
    );

    // The mailbox is not stuck: drain what is waiting, then an SDO upload of
    // 0x1000:00 gets its response. Two counters, so that one differs from
    // the last request's (a repeat with the same counter is dropped).
    for _ in 0..8 {
        h.read();
        h.cycle();
    }
    for counter in [4u8, 7] {
        let mut msg = vec![0u8; HEADER_LEN];
        msg.extend_from_slice(&sdo(&SdoRequest::InitiateUpload {
            index: 0x1000,
            sub: 0,
            complete_access: false,
        }));
        MailboxRepr {
            length: (msg.len() - HEADER_LEN) as u16,
            address: 0,
            channel: 0,
            priority: 0,
            mailbox_type: MailboxType::CoE,
            counter,
        }
        .emit(&mut Mailbox::new_unchecked(&mut msg[..]))
        .expect("upload request");
        assert!(h.write_patiently(&msg), "SM0 never takes a new request");
        for _ in 0..48 {
            h.cycle();
            if h.read().is_some_and(|r| is_device_type(&r)) {
                return;
            }
        }
    }
    panic!("mailbox stuck: no response to an SDO upload of 0x1000:00 (from {target:?})");
}

fuzz_target!(|data: &[u8]| run(data));
