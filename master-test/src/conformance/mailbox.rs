//! Group `mailbox`: unsupported protocol, inconsistent lengths,
//! repeated counter, SM1 repeat, nothing stale after INIT; the raw
//! mailbox helpers the other groups use.

use super::*;
use crate::registers;

/// Sends a raw mailbox and waits for one answer; `None` when nothing came
/// within `wait`.
pub(super) async fn exchange_raw(
    c: &mut MailboxClient<'_>,
    kind: MailboxType,
    counter: u8,
    header_len: u16,
    payload: &[u8],
    wait: Duration,
) -> Result<Option<crate::mailbox::Message>, String> {
    let size = c.max_payload() + ecat_slave::wire::mailbox::HEADER_LEN;
    let mut buf = vec![0u8; size];
    buf[0..2].copy_from_slice(&header_len.to_le_bytes());
    buf[5] = u8::from(kind) | (counter << 4);
    let n = payload.len().min(size - 6);
    buf[6..6 + n].copy_from_slice(&payload[..n]);
    let saved = c.timeout;
    // Whatever already waits (an Emergency after a refused state change)
    // is not the answer: keep Emergencies, drop the rest.
    c.timeout = Duration::ZERO;
    for _ in 0..8 {
        match c.receive().await {
            Ok(m) => keep_emergency(c, m),
            Err(_) => break,
        }
    }
    c.timeout = saved;
    c.write_buffer(&buf).await.map_err(|e| e.to_string())?;
    c.timeout = wait;
    let mut answer = None;
    for _ in 0..8 {
        match c.receive().await {
            Ok(m) if is_emergency(&m) => keep_emergency(c, m),
            Ok(m) => {
                answer = Some(Ok(m));
                break;
            }
            Err(e) => {
                answer = Some(Err(e));
                break;
            }
        }
    }
    c.timeout = saved;
    match answer {
        Some(Ok(m)) => Ok(Some(m)),
        None | Some(Err(ClientError::Timeout(_))) => Ok(None),
        Some(Err(e)) => Err(e.to_string()),
    }
}

pub(super) fn is_emergency(m: &crate::mailbox::Message) -> bool {
    m.kind == MailboxType::CoE && m.payload.get(1).is_some_and(|b| b >> 4 == 1)
}

pub(super) fn keep_emergency(c: &mut MailboxClient<'_>, m: crate::mailbox::Message) {
    if is_emergency(&m) {
        c.emergencies.push(m.payload);
    }
}

pub(super) fn mailbox_error(m: &crate::mailbox::Message) -> Option<u16> {
    if m.kind != MailboxType::Error {
        return None;
    }
    WireMailboxError::new_checked(&m.payload[..])
        .ok()
        .map(|e| u16::from(e.detail()))
}

/// An SDO upload request of `index:sub` with its CoE header.
pub(super) fn upload_request(index: u16, sub: u8) -> Vec<u8> {
    let req = SdoRequest::InitiateUpload {
        index,
        sub,
        complete_access: false,
    };
    let mut p = vec![0u8; 2 + req.buffer_len()];
    CoeHeader::emit_into(&mut p[..2], 0, CoeService::SdoRequest);
    let _ = req.emit(&mut p[2..]);
    p
}

pub(super) async fn mailbox_checks(r: &mut Run<'_>) {
    let ids = [
        "mailbox.unsupported-protocol",
        "mailbox.invalid-size",
        "mailbox.size-too-short",
        "mailbox.repeated-counter",
        "mailbox.repeat-request",
        "mailbox.empty-after-init",
    ];
    let Some(mut c) = r.client() else {
        for id in ids {
            r.record(
                id,
                "ETG.1000.6 5.3",
                "mailbox behaviour",
                Outcome::NotApplicable("no mailbox in the SII".into()),
            );
        }
        return;
    };
    let wait = Duration::from_millis(300);
    let protocols = ecat_esi::inspect::inspect(&r.sii)
        .map(|i| i.mailbox_protocols)
        .unwrap_or(0);
    // A protocol the SII does not announce: SoE (bit 4), else VoE, AoE.
    let (kind, _) = [
        (MailboxType::SoE, 0x0010u16),
        (MailboxType::VoE, 0x0020),
        (MailboxType::AoE, 0x0001),
    ]
    .into_iter()
    .find(|(_, b)| protocols & b == 0)
    .unwrap_or((MailboxType::VoE, 0x0020));
    let o = match exchange_raw(&mut c, kind, 1, 4, &[0, 0, 0, 0], wait).await {
        Ok(Some(m)) if mailbox_error(&m) == Some(0x0002) => {
            Outcome::Pass(format!("{kind:?}: mailbox error 0x0002"))
        }
        Ok(Some(m)) => Outcome::Fail(format!("{kind:?}: {:?} {:02x?}", m.kind, m.payload)),
        Ok(None) => Outcome::Fail(format!("{kind:?}: no answer")),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        ids[0],
        "ETG.1000.6 5.3.3, Table 29",
        "a protocol the SII does not announce gets a mailbox error reply 0x0002 (unsupported protocol)",
        o,
    );

    let too_long = c.max_payload() as u16 + 1;
    let o = match exchange_raw(
        &mut c,
        MailboxType::CoE,
        2,
        too_long,
        &upload_request(0x1000, 0),
        wait,
    )
    .await
    {
        Ok(Some(m)) if mailbox_error(&m) == Some(0x0008) => {
            Outcome::Pass("mailbox error 0x0008".into())
        }
        Ok(Some(m)) => Outcome::Fail(format!("{:?} {:02x?}", m.kind, m.payload)),
        Ok(None) => Outcome::Fail("no answer".into()),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        ids[1],
        "ETG.1000.6 5.3.3, Table 29",
        "header length beyond the mailbox: mailbox error reply 0x0008 (invalid size)",
        o,
    );

    let o = match exchange_raw(&mut c, MailboxType::CoE, 3, 1, &[0], wait).await {
        Ok(Some(m)) if mailbox_error(&m) == Some(0x0006) => {
            Outcome::Pass("mailbox error 0x0006".into())
        }
        Ok(Some(m)) => Outcome::Fail(format!("{:?} {:02x?}", m.kind, m.payload)),
        Ok(None) => Outcome::Fail("no answer".into()),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        ids[2],
        "ETG.1000.6 5.3.3, Table 29",
        "a CoE message of 1 byte (shorter than its header): mailbox error reply 0x0006 (size too short)",
        o,
    );

    let coe = protocols & 0x0004 != 0;
    let req = upload_request(0x1000, 0);
    let o = if !coe {
        Outcome::NotApplicable("no CoE announced".into())
    } else {
        let first = exchange_raw(&mut c, MailboxType::CoE, 4, req.len() as u16, &req, wait).await;
        let second = exchange_raw(&mut c, MailboxType::CoE, 4, req.len() as u16, &req, wait).await;
        match (first, second) {
            (Ok(Some(_)), Ok(None)) => Outcome::Pass("answered once".into()),
            (Ok(Some(_)), Ok(Some(m))) => {
                Outcome::Fail(format!("executed twice: {:?} {:02x?}", m.kind, m.payload))
            }
            (Ok(None), _) => Outcome::Fail("the first request got no answer".into()),
            (Err(e), _) | (_, Err(e)) => Outcome::Fail(e),
        }
    };
    r.record(
        ids[3],
        "ETG.1000.6 5.3.2",
        "a mailbox repeated with the same counter (1-7) is not executed again",
        o,
    );

    let o = if !coe {
        Outcome::NotApplicable("no CoE announced".into())
    } else {
        match exchange_raw(&mut c, MailboxType::CoE, 5, req.len() as u16, &req, wait).await {
            Ok(Some(m)) => match c.repeat().await {
                Ok(again) if again == m => Outcome::Pass("the last answer again".into()),
                Ok(again) => Outcome::Fail(format!("{again:?}, first {m:?}")),
                Err(e) => Outcome::Fail(e.to_string()),
            },
            Ok(None) => Outcome::Fail("no answer to repeat".into()),
            Err(e) => Outcome::Fail(e),
        }
    };
    r.record(
        ids[4],
        "ETG.1000.4 8.2.2.3 (SM repeat), ETG.1000.6 5.3.2",
        "toggling the SM1 repeat request gives the last mailbox answer again, acknowledged in 0x080F",
        o,
    );

    // After INIT -> PRE-OP nothing from before may wait in SM1.
    let _ = r.request(0x01).await;
    let _ = r.request(0x02).await;
    r.clock.sleep(Duration::from_millis(20)).await;
    let o = match r.read::<u8>(registers::SM1 + registers::SM_STATUS).await {
        Ok(st) if st & 0x08 == 0 => Outcome::Pass("SM1 empty".into()),
        Ok(st) => {
            let m = c.receive().await;
            Outcome::Fail(format!(
                "SM1 status {st:#04x}: a message waits: {}",
                match m {
                    Ok(m) => format!("{:?} {:02x?}", m.kind, m.payload),
                    Err(e) => e.to_string(),
                }
            ))
        }
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        ids[5],
        "ETG.1000.6 5.3, 6.4.1 (INIT: mailbox off)",
        "after INIT -> PRE-OP the slave's mailbox holds nothing from before (no stale answer or Emergency)",
        o,
    );
    r.emergencies.extend(c.emergencies);
}
