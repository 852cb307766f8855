//! Group `state`: allowed and refused AL transitions with their codes,
//! error acknowledge, SM checks, the SM watchdog and its recovery.

use super::*;
use crate::registers;

pub(super) async fn state_checks(r: &mut Run<'_>) {
    const INVALID: u16 = 0x0011;
    // Refused transitions from PRE-OP, then INIT. An ESC in device
    // emulation (0x0141 bit 0) refuses none: its AL status is the state
    // AL control asks for (Beckhoff ESC datasheet, section II, 0x0141),
    // which is what it promises and what is checked instead; the state is
    // then set back.
    let refused = async |r: &mut Run<'_>, id, from: u16, to: u16, what: &str| {
        if r.device_emulation {
            let o = match r.request(to).await {
                Ok((st, _)) if st == to => Outcome::Pass(format!(
                    "{}: device emulation (0x0141 bit 0), the AL status follows AL control",
                    state_name(st)
                )),
                Ok((st, code)) => Outcome::Fail(format!(
                    "{} under device emulation (0x0141 bit 0): the AL status should be the requested state",
                    al_text(st, code)
                )),
                Err(e) => Outcome::Fail(e),
            };
            r.record(
                id,
                "ESC register 0x0141 bit 0 (device emulation)",
                "the AL status follows AL control (ESC in device emulation, 0x0141 bit 0)",
                o,
            );
            let _ = r.request(from).await;
            return;
        }
        let o = match r.request(to).await {
            Ok((st, code)) if st == (from | 0x10) && code == INVALID => {
                Outcome::Pass(al_text(st, code))
            }
            Ok((st, code)) => Outcome::Fail(al_text(st, code)),
            Err(e) => Outcome::Fail(e),
        };
        r.record(id, "ETG.1000.6 6.4.1, Table 9", what, o);
        let _ = r.acknowledge(from).await;
    };
    refused(
        r,
        "state.preop-to-op-refused",
        0x02,
        0x08,
        "PRE-OP -> OP refused: PRE-OP + error, 0x0011 invalid requested state change",
    )
    .await;

    let o = match r.al().await {
        Ok((0x02, _)) => Outcome::Pass("PRE-OP, error flag cleared".into()),
        Ok((st, code)) => Outcome::Fail(al_text(st, code)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "state.error-acknowledge",
        "ETG.1000.6 6.4.1.3",
        "writing the current state with the acknowledge bit (0x0010) clears the error flag",
        o,
    );

    if r.bootstrap.is_some() {
        refused(
            r,
            "state.preop-to-boot-refused",
            0x02,
            0x03,
            "PRE-OP -> BOOT refused (BOOT only from INIT): 0x0011",
        )
        .await;
    } else {
        r.record(
            "state.preop-to-boot-refused",
            "ETG.1000.6 6.4.1, Table 9",
            "PRE-OP -> BOOT refused (BOOT only from INIT): 0x0011",
            Outcome::NotApplicable("no bootstrap mailbox in the SII".into()),
        );
    }

    let o = match r.request(0x01).await {
        Ok((0x01, _)) => Outcome::Pass("INIT".into()),
        Ok((st, code)) => Outcome::Fail(al_text(st, code)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "state.preop-to-init",
        "ETG.1000.6 6.4.1",
        "PRE-OP -> INIT",
        o,
    );
    refused(
        r,
        "state.init-to-safeop-refused",
        0x01,
        0x04,
        "INIT -> SAFE-OP refused: INIT + error, 0x0011",
    )
    .await;
    refused(
        r,
        "state.init-to-op-refused",
        0x01,
        0x08,
        "INIT -> OP refused: INIT + error, 0x0011",
    )
    .await;

    // Mailbox SM checks at INIT -> PRE-OP.
    if let Some(g) = r.mailbox {
        let good0 = r.read::<[u8; 8]>(registers::SM0).await.unwrap_or_default();
        let good1 = r.read::<[u8; 8]>(registers::SM1).await.unwrap_or_default();
        let cases: [(&'static str, u16, [u8; 8], &str); 3] = [
            (
                "state.sm-mailbox-start",
                registers::SM0,
                {
                    let mut b = good0;
                    b[0..2].copy_from_slice(&g.out.0.wrapping_add(0x40).to_le_bytes());
                    b
                },
                "SM0 start not the SII's: INIT -> PRE-OP refused, 0x0016 invalid mailbox configuration",
            ),
            (
                "state.sm-mailbox-length",
                registers::SM1,
                {
                    let mut b = good1;
                    b[2..4].copy_from_slice(&g.inp.1.saturating_sub(2).to_le_bytes());
                    b
                },
                "SM1 length not the SII's: INIT -> PRE-OP refused, 0x0016",
            ),
            (
                "state.sm-mailbox-control",
                registers::SM0,
                {
                    let mut b = good0;
                    b[4] = 0x24; // 3-buffer mode instead of mailbox
                    b
                },
                "SM0 in buffered instead of mailbox mode: INIT -> PRE-OP refused, 0x0016",
            ),
        ];
        for (id, reg, bad, what) in cases {
            let o = match r.write(reg, &bad).await {
                Err(e) => Outcome::Fail(e),
                Ok(()) => match r.request(0x02).await {
                    Ok((st, code)) if st == 0x11 && code == 0x0016 => {
                        Outcome::Pass(al_text(st, code))
                    }
                    Ok((st, code)) => Outcome::Fail(al_text(st, code)),
                    Err(e) => Outcome::Fail(e),
                },
            };
            r.record(id, "ETG.1000.6 6.4.1.1, Table 10", what, o);
            let _ = r.request(0x01).await;
            let _ = r.acknowledge(0x01).await;
            let _ = r.write(registers::SM0, &good0).await;
            let _ = r.write(registers::SM1, &good1).await;
        }
    } else {
        for id in [
            "state.sm-mailbox-start",
            "state.sm-mailbox-length",
            "state.sm-mailbox-control",
        ] {
            r.record(
                id,
                "ETG.1000.6 6.4.1.1",
                "mailbox SM checked at INIT -> PRE-OP",
                Outcome::NotApplicable("no mailbox".into()),
            );
        }
    }

    let o = match r.request(0x02).await {
        Ok((0x02, _)) => Outcome::Pass("PRE-OP".into()),
        Ok((st, code)) => Outcome::Fail(al_text(st, code)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "state.init-to-preop",
        "ETG.1000.6 6.4.1",
        "INIT -> PRE-OP with the SII's mailbox configuration",
        o,
    );

    // Process data SMs (SM2 outputs, SM3 inputs) as a master configures
    // them: start, control and enable of the SII's SyncM category, length
    // of the PDOs assigned now.
    let found = (
        r.read::<[u8; 8]>(registers::SM2).await.unwrap_or_default(),
        r.read::<[u8; 8]>(registers::SM3).await.unwrap_or_default(),
    );
    let (sm2, sm3) = process_data_sms(r).await;
    let _ = r.write(registers::SM2, &sm2).await;
    let _ = r.write(registers::SM3, &sm3).await;
    let len = |b: &[u8; 8]| u16::from_le_bytes([b[2], b[3]]);
    let enabled = |b: &[u8; 8]| b[6] & 1 != 0 && len(b) > 0;

    let o = match r.request(0x04).await {
        Ok((0x04, _)) => Outcome::Pass("SAFE-OP".into()),
        Ok((st, code)) => Outcome::Fail(al_text(st, code)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "state.preop-to-safeop",
        "ETG.1000.6 6.4.1",
        "PRE-OP -> SAFE-OP with the process data SMs the master configured",
        o,
    );
    let _ = r.request(0x02).await;

    for (id, reg, sm, code, what) in [
        (
            "state.sm-output-length",
            registers::SM2,
            sm2,
            0x001Du16,
            "SM2 (outputs) one byte longer than the mapping: PRE-OP -> SAFE-OP refused, 0x001D invalid output configuration",
        ),
        (
            "state.sm-input-length",
            registers::SM3,
            sm3,
            0x001E,
            "SM3 (inputs) one byte longer than the mapping: PRE-OP -> SAFE-OP refused, 0x001E invalid input configuration",
        ),
    ] {
        if !enabled(&sm) {
            r.record(
                id,
                "ETG.1000.6 6.4.1.2, Table 10",
                what,
                Outcome::NotApplicable("the SM carries no process data".into()),
            );
            continue;
        }
        let mut bad = sm;
        bad[2..4].copy_from_slice(&(len(&sm) + 1).to_le_bytes());
        let o = match r.write(reg, &bad).await {
            Err(e) => Outcome::Fail(e),
            Ok(()) => match r.request(0x04).await {
                Ok((st, c)) if st == 0x12 && c == code => Outcome::Pass(al_text(st, c)),
                Ok((st, c)) => Outcome::Fail(al_text(st, c)),
                Err(e) => Outcome::Fail(e),
            },
        };
        r.record(id, "ETG.1000.6 6.4.1.2, Table 10", what, o);
        let _ = r.acknowledge(0x02).await;
        let _ = r.request(0x02).await;
        let _ = r.write(reg, &sm).await;
    }

    watchdog_checks(r, sm2).await;
    let _ = r.request(0x02).await;
    let _ = r.write(registers::SM2, &found.0).await;
    let _ = r.write(registers::SM3, &found.1).await;
}

/// SM2 and SM3 register images (0x0810, 0x0818) for the process data the
/// slave has assigned now: start, control byte and enable from the SII's
/// SyncM category; the length from the assigned PDOs' mapping (over CoE),
/// or the SII's default length without CoE.
pub(super) async fn process_data_sms(r: &Run<'_>) -> ([u8; 8], [u8; 8]) {
    let sms = ecat_esi::inspect::inspect(&r.sii)
        .map(|i| i.sync_managers)
        .unwrap_or_default();
    let mut client = r.client();
    let mut out = [[0u8; 8]; 2];
    for (k, (n, assign)) in [(2usize, 0x1C12u16), (3, 0x1C13)].into_iter().enumerate() {
        let Some(sm) = sms.get(n) else { continue };
        let mut len = sm.length;
        if let Some(c) = client.as_mut()
            && let Ok(count) = c.sdo_upload(assign, 0, false).await
        {
            let mut bits = 0u32;
            for i in 1..=count.first().copied().unwrap_or(0) {
                let Ok(p) = c.sdo_upload(assign, i, false).await else {
                    continue;
                };
                let pdo = u16::from_le_bytes([
                    p.first().copied().unwrap_or(0),
                    p.get(1).copied().unwrap_or(0),
                ]);
                let entries = c
                    .sdo_upload(pdo, 0, false)
                    .await
                    .ok()
                    .and_then(|v| v.first().copied())
                    .unwrap_or(0);
                for e in 1..=entries {
                    if let Ok(v) = c.sdo_upload(pdo, e, false).await {
                        bits += u32::from(v.first().copied().unwrap_or(0));
                    }
                }
            }
            len = u16::try_from(bits.div_ceil(8)).unwrap_or(u16::MAX);
        }
        if let Some(b) = out.get_mut(k) {
            *b = sm_register(sm.start, len, sm.control, len > 0 && sm.enable & 1 != 0);
        }
    }
    (out[0], out[1])
}

/// SAFE-OP -> OP with outputs, the SM watchdog when they stop, and the
/// recovery.
pub(super) async fn watchdog_checks(r: &mut Run<'_>, sm2: [u8; 8]) {
    let start = u16::from_le_bytes([sm2[0], sm2[1]]);
    let len = usize::from(u16::from_le_bytes([sm2[2], sm2[3]]));
    let watchdog_on = sm2[4] & 0x40 != 0;
    let divider = r
        .read::<u16>(registers::WATCHDOG_DIVIDER)
        .await
        .unwrap_or(0);
    let wd = r.read::<u16>(registers::SM_WATCHDOG).await.unwrap_or(0);
    let wd_time = Duration::from_nanos(40 * (u64::from(divider) + 2) * u64::from(wd));
    let ids = [
        ("state.safeop-to-op", "SAFE-OP -> OP while outputs arrive"),
        (
            "state.sm-watchdog",
            "outputs stop: OP -> SAFE-OP + error, 0x001B sync manager watchdog, after the watchdog time",
        ),
        (
            "state.watchdog-recovery",
            "acknowledge and fresh outputs: back to OP",
        ),
    ];
    if len == 0 || sm2[6] & 1 == 0 {
        for (id, what) in ids {
            r.record(
                id,
                "ETG.1000.6 6.4.1, ETG.1000.4 6.7",
                what,
                Outcome::NotApplicable("no output SM (SM2)".into()),
            );
        }
        return;
    }
    let outputs = vec![0u8; len];
    let send = async |r: &Run<'_>| {
        let _ = Command::fpwr(r.station, start)
            .send(r.md, &outputs[..])
            .await;
    };
    // SAFE-OP, outputs flowing, then OP.
    let _ = r.request(0x04).await;
    let mut reached = None;
    let _ = r.write(registers::AL_CONTROL, &0x08u16.to_le_bytes()).await;
    let t0 = r.clock.elapsed();
    while (r.clock.elapsed() - t0) < Duration::from_secs(3) {
        send(r).await;
        if let Ok((st, code)) = r.al().await
            && (st == 0x08 || st & 0x10 != 0)
        {
            reached = Some((st, code));
            break;
        }
        r.clock.sleep(Duration::from_millis(1)).await;
    }
    let o = match reached {
        Some((0x08, _)) => Outcome::Pass("OP".into()),
        Some((st, code)) => Outcome::Fail(al_text(st, code)),
        None => Outcome::Fail("no OP within 3 s".into()),
    };
    let in_op = matches!(reached, Some((0x08, _)));
    r.record(ids[0].0, "ETG.1000.6 6.4.1", ids[0].1, o);

    if !watchdog_on || wd == 0 {
        r.record(
            ids[1].0,
            "ETG.1000.4 6.7, ETG.1000.6 Table 10",
            ids[1].1,
            Outcome::NotApplicable(format!(
                "SM2 watchdog {} (control {:#04x}), 0x0420 = {wd}",
                if watchdog_on { "on" } else { "off" },
                sm2[4]
            )),
        );
        r.record(
            ids[2].0,
            "ETG.1000.6 6.4.1.3",
            ids[2].1,
            Outcome::NotApplicable("no SM watchdog".into()),
        );
        return;
    }
    let o = if !in_op {
        Outcome::NotApplicable("OP was not reached".into())
    } else {
        let stop = r.clock.elapsed();
        let mut seen = None;
        while (r.clock.elapsed() - stop) < wd_time * 5 + Duration::from_secs(2) {
            if let Ok((st, code)) = r.al().await
                && st != 0x08
            {
                seen = Some((st, code, r.clock.elapsed() - stop));
                break;
            }
            r.clock.sleep(Duration::from_millis(1)).await;
        }
        match seen {
            Some((0x14, 0x001B, t)) => Outcome::Pass(format!(
                "SAFE-OP + error, 0x001B after {} ms (watchdog {} ms)",
                t.as_millis(),
                wd_time.as_millis()
            )),
            Some((st, code, _)) => Outcome::Fail(al_text(st, code)),
            None => Outcome::Fail(format!(
                "still OP {} ms after the outputs stopped (watchdog {} ms)",
                (r.clock.elapsed() - stop).as_millis(),
                wd_time.as_millis()
            )),
        }
    };
    r.record(ids[1].0, "ETG.1000.4 6.7, ETG.1000.6 Table 10", ids[1].1, o);

    let o = if !in_op {
        Outcome::NotApplicable("OP was not reached".into())
    } else {
        // Fresh outputs first (the watchdog is re-armed by them), then the
        // acknowledge, then OP, outputs flowing all along.
        for _ in 0..5 {
            send(r).await;
            r.clock.sleep(Duration::from_millis(1)).await;
        }
        let _ = r.write(registers::AL_CONTROL, &0x14u16.to_le_bytes()).await;
        for _ in 0..5 {
            send(r).await;
            r.clock.sleep(Duration::from_millis(1)).await;
        }
        let _ = r.write(registers::AL_CONTROL, &0x08u16.to_le_bytes()).await;
        let t0 = r.clock.elapsed();
        let mut last = (0, 0);
        loop {
            send(r).await;
            if let Ok(s) = r.al().await {
                last = s;
                if s.0 == 0x08 {
                    break Outcome::Pass("OP".into());
                }
            }
            if (r.clock.elapsed() - t0) > Duration::from_secs(3) {
                break Outcome::Fail(al_text(last.0, last.1));
            }
            r.clock.sleep(Duration::from_millis(1)).await;
        }
    };
    r.record(ids[2].0, "ETG.1000.6 6.4.1.3", ids[2].1, o);
    let _ = r.request(0x04).await;
    let _ = r.request(0x02).await;
}
