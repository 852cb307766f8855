//! File access over EtherCAT (ETG.1000.6 FoE) on the raw mailbox client,
//! and the AL transitions around a firmware update (manual 5.10: BOOT,
//! download, INIT).

use crate::mailbox::{ClientError, MailboxClient};
use crate::registers;
use ecat_slave::wire::foe::{FoeRepr, HEADER_LEN};
use ecat_slave::wire::mailbox::MailboxType;
use ethercrab::{Command, MainDevice};
use std::time::{Duration, Instant};

fn reply(payload: &[u8]) -> Result<FoeRepr<'_>, ClientError> {
    FoeRepr::parse(payload).map_err(|e| ClientError::Protocol(e.to_string()))
}

fn foe_error(code: u32, text: &[u8]) -> ClientError {
    ClientError::Foe {
        code,
        text: String::from_utf8_lossy(text).into_owned(),
    }
}

async fn exchange(
    client: &mut MailboxClient<'_>,
    req: &FoeRepr<'_>,
) -> Result<Vec<u8>, ClientError> {
    let mut buf = vec![0u8; req.buffer_len()];
    req.emit(&mut buf)
        .map_err(|e| ClientError::Protocol(e.to_string()))?;
    client.send(MailboxType::FoE, &buf).await?;
    loop {
        let m = client.receive().await?;
        match m.kind {
            MailboxType::FoE => return Ok(m.payload),
            // Emergencies may arrive meanwhile.
            MailboxType::CoE => continue,
            other => return Err(ClientError::Protocol(format!("mailbox type {other:?}"))),
        }
    }
}

/// Writes `data` as file `name` (FoE write request, DATA packets of the
/// mailbox size, each acknowledged; BUSY answers are retried). `progress`
/// gets (bytes sent, total).
pub async fn write(
    client: &mut MailboxClient<'_>,
    name: &str,
    password: u32,
    data: &[u8],
    mut progress: impl FnMut(usize, usize),
) -> Result<(), ClientError> {
    match write_inner(client, name, password, data, &mut progress, &mut |_| false).await {
        Ok(_) => Ok(()),
        Err(e) => {
            // Unless the slave itself refused, tell it the master gave up:
            // a slave that finished the file but whose final
            // acknowledgement was lost then drops the image, and both
            // agree the update did not happen (best effort).
            if !matches!(e, ClientError::Foe { .. }) {
                let _ = send_abort(client).await;
            }
            Err(e)
        }
    }
}

/// The owner sets a new FoE password (the slave in BOOT): a download of
/// the password file ([`ecat_slave::foe::PASSWORD_FILE_NAME`]) with the
/// `current` password in the write request, holding `new` as 8 hex
/// digits. A wrong `current` password is refused with 0x800A.
pub async fn set_password(
    client: &mut MailboxClient<'_>,
    current: u32,
    new: u32,
) -> Result<(), ClientError> {
    let name = String::from_utf8_lossy(ecat_slave::foe::PASSWORD_FILE_NAME).into_owned();
    let file = format!("{new:08X}\n");
    write(client, &name, current, file.as_bytes(), |_, _| {}).await
}

/// Sends a FoE error request "aborted by the master" (no reply expected).
pub async fn send_abort(client: &mut MailboxClient<'_>) -> Result<(), ClientError> {
    let abort = FoeRepr::Error {
        code: ecat_slave::wire::foe::FoeErrorCode::NotDefined,
        text: b"aborted by the master",
    };
    let mut buf = vec![0u8; abort.buffer_len()];
    abort
        .emit(&mut buf)
        .map_err(|e| ClientError::Protocol(e.to_string()))?;
    client.send(MailboxType::FoE, &buf).await.map(|_| ())
}

/// Like [`write()`] but stops after `stop_after` bytes without ending the
/// file (a master that gives up midway; for tests).
pub async fn write_partial(
    client: &mut MailboxClient<'_>,
    name: &str,
    password: u32,
    data: &[u8],
    stop_after: usize,
    progress: &mut impl FnMut(usize, usize),
) -> Result<(), ClientError> {
    let mut stop = |sent: usize| sent >= stop_after && stop_after < data.len();
    write_inner(client, name, password, data, progress, &mut stop)
        .await
        .map(|_| ())
}

/// Like [`write()`], but checks `cancel` before each DATA packet: when it
/// says stop, the transfer is ended with a FoE error request ("aborted by
/// the master"; ETG.1000.6 lets either side end a transfer so) and
/// `Ok(false)` returned; the slave discards the partial file. `Ok(true)`:
/// the whole file was written.
pub async fn write_cancellable(
    client: &mut MailboxClient<'_>,
    name: &str,
    password: u32,
    data: &[u8],
    progress: &mut impl FnMut(usize, usize),
    cancel: impl Fn() -> bool,
) -> Result<bool, ClientError> {
    let done = match write_inner(client, name, password, data, progress, &mut |_| cancel()).await {
        Ok(done) => done,
        Err(e) => {
            if !matches!(e, ClientError::Foe { .. }) {
                let _ = send_abort(client).await;
            }
            return Err(e);
        }
    };
    if !done {
        send_abort(client).await?;
    }
    Ok(done)
}

/// The write loop: `Ok(false)` when `stop(bytes sent)` ended it early.
async fn write_inner(
    client: &mut MailboxClient<'_>,
    name: &str,
    password: u32,
    data: &[u8],
    progress: &mut impl FnMut(usize, usize),
    stop: &mut dyn FnMut(usize) -> bool,
) -> Result<bool, ClientError> {
    let seg = client.max_payload().saturating_sub(HEADER_LEN).max(1);
    let wrq = FoeRepr::WriteRequest {
        password,
        name: name.as_bytes(),
    };
    let r = exchange(client, &wrq).await?;
    match reply(&r)? {
        FoeRepr::Ack { packet: 0 } => {}
        FoeRepr::Error { code, text } => return Err(foe_error(code.into(), text)),
        other => {
            return Err(ClientError::Protocol(format!(
                "after write request: {other:?}"
            )));
        }
    }
    let mut sent = 0usize;
    let mut packet = 1u32;
    loop {
        let end = (sent + seg).min(data.len());
        if stop(sent) {
            return Ok(false);
        }
        let chunk = &data[sent..end];
        let r = exchange(
            client,
            &FoeRepr::Data {
                packet,
                data: chunk,
            },
        )
        .await?;
        match reply(&r)? {
            FoeRepr::Ack { packet: p } if p == packet => {}
            FoeRepr::Busy { .. } => {
                smol::Timer::after(Duration::from_millis(1)).await;
                continue;
            }
            FoeRepr::Error { code, text } => return Err(foe_error(code.into(), text)),
            other => {
                return Err(ClientError::Protocol(format!(
                    "after DATA {packet}: {other:?}"
                )));
            }
        }
        sent = end;
        progress(sent, data.len());
        packet += 1;
        // A packet shorter than the maximum ends the file (an empty one
        // when the length is a multiple of the packet size).
        if chunk.len() < seg {
            return Ok(true);
        }
    }
}

/// Reads file `name` (FoE read request; each DATA packet acknowledged).
pub async fn read(
    client: &mut MailboxClient<'_>,
    name: &str,
    password: u32,
) -> Result<Vec<u8>, ClientError> {
    let seg = client.max_payload().saturating_sub(HEADER_LEN).max(1);
    let mut r = exchange(
        client,
        &FoeRepr::ReadRequest {
            password,
            name: name.as_bytes(),
        },
    )
    .await?;
    let mut out = Vec::new();
    loop {
        match reply(&r)? {
            FoeRepr::Data { packet, data } => {
                out.extend_from_slice(data);
                let last = data.len() < seg;
                let ack = FoeRepr::Ack { packet };
                if last {
                    let mut buf = vec![0u8; ack.buffer_len()];
                    ack.emit(&mut buf)
                        .map_err(|e| ClientError::Protocol(e.to_string()))?;
                    client.send(MailboxType::FoE, &buf).await?;
                    return Ok(out);
                }
                r = exchange(client, &ack).await?;
            }
            FoeRepr::Error { code, text } => return Err(foe_error(code.into(), text)),
            other => return Err(ClientError::Protocol(format!("read: {other:?}"))),
        }
    }
}

/// Requests AL state `state` (AL control) and waits until the AL status
/// shows it.
/// Fails with the AL status code when the slave refuses.
pub async fn request_state(
    md: &MainDevice<'_>,
    station: u16,
    state: u16,
) -> Result<(), ClientError> {
    Command::fpwr(station, registers::AL_CONTROL)
        .send(md, state)
        .await?;
    let start = Instant::now();
    loop {
        let st: u16 = Command::fprd(station, registers::AL_STATUS)
            .receive(md)
            .await?;
        if st & 0x1F == state & 0x0F {
            return Ok(());
        }
        if st & 0x10 != 0 {
            let code: u16 = Command::fprd(station, registers::AL_STATUS_CODE)
                .receive(md)
                .await?;
            return Err(ClientError::StateRefused { status: st, code });
        }
        if start.elapsed() > Duration::from_secs(5) {
            return Err(ClientError::Timeout(Duration::from_secs(5)));
        }
        smol::Timer::after(Duration::from_micros(200)).await;
    }
}

/// INIT, SM0/SM1 set to the PAM-199-P-ETC's bootstrap mailbox, then BOOT
/// (see [`enter_boot_with`] for another device).
pub async fn enter_boot(md: &MainDevice<'_>, station: u16) -> Result<(), ClientError> {
    enter_boot_with(md, station, &pam_199_p_etc::DEVICE.layout()).await
}

/// INIT, SM0/SM1 set to the bootstrap mailbox of `l` (what the device's SII
/// says), then BOOT.
pub async fn enter_boot_with(
    md: &MainDevice<'_>,
    station: u16,
    l: &ecat_slave::device::MemoryLayout,
) -> Result<(), ClientError> {
    enter_boot_geometry(
        md,
        station,
        crate::mailbox::MailboxGeometry::bootstrap_of(l),
    )
    .await
}

/// INIT, SM0/SM1 set to the bootstrap mailbox `boot` (from the slave's SII
/// words 0x14-0x17, see [`crate::eeprom::mailboxes`]), then BOOT.
pub async fn enter_boot_geometry(
    md: &MainDevice<'_>,
    station: u16,
    boot: crate::mailbox::MailboxGeometry,
) -> Result<(), ClientError> {
    request_state(md, station, 0x11).await?;
    for (reg, b) in boot.sm_registers() {
        Command::fpwr(station, reg).send(md, b).await?;
    }
    request_state(md, station, 0x03).await
}

/// A `.efw` image of `payload` with firmware `version` for the device with
/// `vendor_id`/`product_code`, any revision.
pub fn efw_image(vendor_id: u32, product_code: u32, version: &str, payload: &[u8]) -> Vec<u8> {
    use ecat_slave::firmware::{EFW_HEADER_LEN, EfwHeaderRepr, FirmwareVersion, pack};
    let header = EfwHeaderRepr {
        header_len: EFW_HEADER_LEN as u16,
        flags: 0,
        vendor_id,
        product_code,
        revision_min: 0,
        revision_max: u32::MAX,
        version: FirmwareVersion::new(version).unwrap_or_default(),
        payload_len: 0,
        payload_crc: 0,
    };
    let mut out = vec![0u8; payload.len() + 1024];
    let n = pack(&header, payload, &mut out).unwrap_or(0);
    out.truncate(n);
    out
}

/// [`efw_image`] for the PAM-199-P-ETC with `len` bytes of test payload.
pub fn pam_image(version: &str, len: usize) -> Vec<u8> {
    let payload: Vec<u8> = (0..len).map(|i| (i * 7 + i / 251) as u8).collect();
    efw_image(
        pam_199_p_etc::VENDOR_ID,
        pam_199_p_etc::PRODUCT_CODE,
        version,
        &payload,
    )
}
