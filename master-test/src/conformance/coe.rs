//! Group `coe`: every announced entry read and rewritten, abort
//! service and codes, complete access, SDO Information against the ESI,
//! Emergency framing.

use super::*;

/// Whether `access` (SDO Information entry access bits) allows reading /
/// writing in PRE-OP.
pub(super) fn readable(access: u16) -> bool {
    access & 0x0001 != 0
}
pub(super) fn writable(access: u16) -> bool {
    access & 0x0008 != 0
}

pub(super) async fn coe_checks(r: &mut Run<'_>, esi: Option<&str>) {
    let protocols = ecat_esi::inspect::inspect(&r.sii)
        .map(|i| i.mailbox_protocols)
        .unwrap_or(0);
    let coe_details = ecat_esi::inspect::inspect(&r.sii)
        .ok()
        .and_then(|i| i.general.map(|(g, _)| g.coe_details))
        .unwrap_or(0);
    let ids: [(&'static str, &'static str, &'static str); 10] = [
        (
            "coe.sdo-info",
            "ETG.1000.6 5.6.3",
            "SDO Information: OD list, every object and entry described",
        ),
        (
            "coe.upload-readable",
            "ETG.1000.6 5.6.2.4, 5.6.3.6",
            "every entry described as readable uploads",
        ),
        (
            "coe.rewrite-writable",
            "ETG.1000.6 5.6.2.1",
            "every entry writable in PRE-OP accepts its own value",
        ),
        (
            "coe.abort-service",
            "ETG.1000.6 5.6.2.7",
            "Abort SDO Transfer travels as CoE service 2 (SDO request), command 0x80",
        ),
        (
            "coe.abort-unknown-object",
            "ETG.1000.6 Table 40",
            "upload of an absent object aborts 0x06020000",
        ),
        (
            "coe.abort-unknown-subindex",
            "ETG.1000.6 Table 40",
            "upload of an absent subindex aborts 0x06090011",
        ),
        (
            "coe.abort-read-only",
            "ETG.1000.6 Table 40",
            "download to a read-only entry aborts 0x06010002",
        ),
        (
            "coe.abort-length",
            "ETG.1000.6 Table 40",
            "download of one byte too many aborts 0x06070010 or 0x06070012",
        ),
        (
            "coe.complete-access",
            "ETG.1000.6 5.6.2.1.2, 5.6.2.4.2",
            "complete access (SII CoE details bit 5): 0x1018 whole = its entries one by one",
        ),
        (
            "coe.sdo-info-esi",
            "ETG.2000 (Dictionary), ETG.1000.6 5.6.3.3",
            "the OD list holds the objects of the ESI's dictionary, no more, no fewer",
        ),
    ];
    let emergency_id = (
        "coe.emergency-framing",
        "ETG.1000.6 5.6.4",
        "every Emergency received is CoE service 1 with 8 data bytes (error code, error register, 5 bytes)",
    );
    let client = if protocols & 0x0004 != 0 {
        r.client()
    } else {
        None
    };
    let Some(mut c) = client else {
        for (id, reference, what) in ids.into_iter().chain([emergency_id]) {
            r.record(
                id,
                reference,
                what,
                Outcome::NotApplicable("no CoE announced".into()),
            );
        }
        return;
    };

    // SDO Information.
    let mut entries: Vec<EntryInfo> = Vec::new();
    let mut list = Vec::new();
    let o = if coe_details & 0x02 == 0 {
        Outcome::NotApplicable("SDO Information not announced (SII CoE details bit 1)".into())
    } else {
        match sdo_info::od_list(&mut c, sdo_info::list_type::ALL).await {
            Err(e) => Outcome::Fail(format!("OD list: {e}")),
            Ok(l) => {
                list = l;
                let mut problems = Vec::new();
                for &index in &list {
                    match sdo_info::object_description(&mut c, index).await {
                        Err(e) => problems.push(format!("{index:#06x}: {e}")),
                        Ok(obj) => {
                            for sub in 0..=obj.max_sub {
                                match sdo_info::entry_description(&mut c, index, sub, 0).await {
                                    Ok(e) => entries.push(e),
                                    // Arrays and records may have gaps.
                                    Err(e) if e.abort_code() == Some(0x0609_0011) => {}
                                    Err(e) => problems.push(format!("{index:#06x}:{sub:02x}: {e}")),
                                }
                            }
                        }
                    }
                }
                if problems.is_empty() {
                    Outcome::Pass(format!(
                        "{} objects, {} entries described",
                        list.len(),
                        entries.len()
                    ))
                } else {
                    Outcome::Fail(problems.join("; "))
                }
            }
        }
    };
    r.record(ids[0].0, ids[0].1, ids[0].2, o);

    // Every readable entry uploads.
    let mut values: Vec<(u16, u8, Vec<u8>, u16)> = Vec::new();
    let o = if entries.is_empty() {
        Outcome::NotApplicable("no entry descriptions".into())
    } else {
        let mut failed = Vec::new();
        for e in entries.iter().filter(|e| readable(e.access)) {
            match c.sdo_upload(e.index, e.sub, false).await {
                Ok(v) => values.push((e.index, e.sub, v, e.access)),
                Err(err) => failed.push(format!("{:#06x}:{:02x}: {err}", e.index, e.sub)),
            }
        }
        if failed.is_empty() {
            Outcome::Pass(format!("{} entries read", values.len()))
        } else {
            Outcome::Fail(format!(
                "{} of {} failed: {}",
                failed.len(),
                failed.len() + values.len(),
                failed.join("; ")
            ))
        }
    };
    r.record(ids[1].0, ids[1].1, ids[1].2, o);

    // Every entry writable in PRE-OP takes its own value (0x1010/0x1011
    // need their signatures instead).
    let o = if values.is_empty() {
        Outcome::NotApplicable("no entries read".into())
    } else {
        let (mut failed, mut refused) = (Vec::new(), Vec::new());
        let mut n = 0;
        // A writable PDO mapping is rewritten as ETG.1020 orders it:
        // subindex 0 to 0, the entries, subindex 0 back (0x06010003 for an
        // entry written while subindex 0 is not 0).
        let mapping = |i: u16| (0x1600..0x1C00).contains(&i);
        let count_of = |i: u16| {
            values
                .iter()
                .find(|(x, s, _, _)| *x == i && *s == 0)
                .map(|(_, _, v, _)| v.clone())
        };
        let mut open: Option<(u16, Vec<u8>)> = None;
        for (index, sub, v, access) in &values {
            if let Some((i, count)) = open.take_if(|(i, _)| i != index)
                && let Err(err) = c.sdo_download(i, 0, false, &count).await
            {
                failed.push(format!("{i:#06x}:00 back to {count:02x?}: {err}"));
            }
            if !writable(*access)
                || matches!(index, 0x1010 | 0x1011)
                || *sub == 0 && mapping(*index)
            {
                continue;
            }
            if mapping(*index)
                && open.is_none()
                && let Some(count) = count_of(*index)
            {
                if let Err(err) = c.sdo_download(*index, 0, false, &[0]).await {
                    failed.push(format!("{index:#06x}:00 = 0: {err}"));
                }
                open = Some((*index, count));
            }
            n += 1;
            match c.sdo_download(*index, *sub, false, v).await {
                Ok(()) => {}
                // Refusals the device may give for reasons of its own: a
                // lock (0x06010000), a value its rules exclude now
                // (0x0609003x), local control or device state (0x0800002x).
                Err(err)
                    if err.abort_code().is_some_and(|a| {
                        a == 0x0601_0000
                            || (0x0609_0030..=0x0609_0036).contains(&a)
                            || (0x0800_0020..=0x0800_0022).contains(&a)
                    }) =>
                {
                    refused.push(format!(
                        "{index:#06x}:{sub:02x} {:#010x}",
                        err.abort_code().unwrap_or(0)
                    ));
                }
                Err(err) => failed.push(format!("{index:#06x}:{sub:02x} = {v:02x?}: {err}")),
            }
        }
        if let Some((i, count)) = open.take()
            && let Err(err) = c.sdo_download(i, 0, false, &count).await
        {
            failed.push(format!("{i:#06x}:00 back to {count:02x?}: {err}"));
        }
        let note = if refused.is_empty() {
            String::new()
        } else {
            format!(
                "; refused by the device's own rules (allowed): {}",
                refused.join(", ")
            )
        };
        if failed.is_empty() {
            Outcome::Pass(format!("{} entries rewritten{note}", n - refused.len()))
        } else {
            Outcome::Fail(format!("{}{note}", failed.join("; ")))
        }
    };
    r.record(ids[2].0, ids[2].1, ids[2].2, o);

    // An index not in the list (or 0x5FFF without a list).
    let absent = (0x2000u16..0x6000)
        .rev()
        .find(|i| !list.contains(i))
        .unwrap_or(0x5FFF);
    let req = upload_request(absent, 0);
    let o = match exchange_raw(
        &mut c,
        MailboxType::CoE,
        0,
        req.len() as u16,
        &req,
        Duration::from_millis(500),
    )
    .await
    {
        Ok(Some(m)) if m.kind == MailboxType::CoE && m.payload.len() >= 3 => {
            let service = m.payload[1] >> 4;
            let cmd = m.payload[2];
            if service == 2 && cmd == 0x80 {
                Outcome::Pass("service 2, command 0x80".into())
            } else {
                Outcome::Fail(format!("service {service}, command {cmd:#04x}"))
            }
        }
        Ok(Some(m)) => Outcome::Fail(format!("{:?} {:02x?}", m.kind, m.payload)),
        Ok(None) => Outcome::Fail("no answer".into()),
        Err(e) => Outcome::Fail(e),
    };
    r.record(ids[3].0, ids[3].1, ids[3].2, o);

    let abort = |res: Result<Vec<u8>, ClientError>, want: &[u32]| match res {
        Err(e) if e.abort_code().is_some_and(|c| want.contains(&c)) => {
            Outcome::Pass(format!("{:#010x}", e.abort_code().unwrap_or(0)))
        }
        Err(e) => Outcome::Fail(e.to_string()),
        Ok(v) => Outcome::Fail(format!("no abort: {v:02x?}")),
    };
    let o = abort(c.sdo_upload(absent, 0, false).await, &[0x0602_0000]);
    r.record(
        ids[4].0,
        ids[4].1,
        &format!("{} ({absent:#06x})", ids[4].2),
        o,
    );

    let max_1018 = c
        .sdo_upload(0x1018, 0, false)
        .await
        .ok()
        .and_then(|v| v.first().copied())
        .unwrap_or(4);
    let o = abort(
        c.sdo_upload(0x1018, max_1018.saturating_add(1), false)
            .await,
        &[0x0609_0011],
    );
    r.record(
        ids[5].0,
        ids[5].1,
        &format!("{} (0x1018:{:02x})", ids[5].2, max_1018.saturating_add(1)),
        o,
    );

    let o = abort(
        c.sdo_download(0x1018, 1, false, &[0, 0, 0, 0])
            .await
            .map(|()| Vec::new()),
        &[0x0601_0002],
    );
    r.record(ids[6].0, ids[6].1, &format!("{} (0x1018:01)", ids[6].2), o);

    let target = values.iter().find(|(i, s, v, a)| {
        writable(*a) && (1..=3).contains(&v.len()) && *s != 0 && !matches!(i, 0x1010 | 0x1011)
    });
    let o = match target {
        None => Outcome::NotApplicable("no writable entry of 1-3 bytes".into()),
        Some((index, sub, v, _)) => {
            let mut long = v.clone();
            long.push(0);
            let res = c
                .sdo_download(*index, *sub, false, &long)
                .await
                .map(|()| Vec::new());
            match abort(res, &[0x0607_0010, 0x0607_0012]) {
                Outcome::Pass(s) => Outcome::Pass(format!("{index:#06x}:{sub:02x}: {s}")),
                Outcome::Fail(s) => Outcome::Fail(format!("{index:#06x}:{sub:02x}: {s}")),
                other => other,
            }
        }
    };
    r.record(ids[7].0, ids[7].1, ids[7].2, o);

    let o = if coe_details & 0x20 == 0 {
        Outcome::NotApplicable("complete access not announced (SII CoE details bit 5)".into())
    } else {
        let whole = c.sdo_upload(0x1018, 0, true).await;
        let mut single = vec![max_1018, 0];
        for sub in 1..=max_1018 {
            if let Ok(v) = c.sdo_upload(0x1018, sub, false).await {
                single.extend(v);
            }
        }
        match whole {
            Ok(w) if w == single => Outcome::Pass(format!("{} bytes", w.len())),
            Ok(w) => Outcome::Fail(format!("complete {w:02x?}, entries {single:02x?}")),
            Err(e) => Outcome::Fail(e.to_string()),
        }
    };
    r.record(ids[8].0, ids[8].1, ids[8].2, o);

    let o = match (esi, list.is_empty()) {
        (None, _) => Outcome::NotApplicable("no ESI given (--esi FILE)".into()),
        (Some(_), true) => Outcome::NotApplicable("no OD list".into()),
        (Some(xml), false) => {
            match esi_objects(xml, &detected_modules(&mut c).await.unwrap_or_default()) {
                Err(e) => Outcome::Fail(format!("the ESI cannot be read: {e}")),
                Ok(esi) => {
                    let missing: Vec<String> = esi
                        .iter()
                        .filter(|i| !list.contains(i))
                        .map(|i| format!("{i:#06x}"))
                        .collect();
                    let extra: Vec<String> = list
                        .iter()
                        .filter(|i| !esi.contains(i))
                        .map(|i| format!("{i:#06x}"))
                        .collect();
                    if missing.is_empty() && extra.is_empty() {
                        Outcome::Pass(format!("{} objects", list.len()))
                    } else {
                        Outcome::Fail(format!(
                            "in the ESI only: [{}]; in the OD list only: [{}]",
                            missing.join(", "),
                            extra.join(", ")
                        ))
                    }
                }
            }
        }
    };
    r.record(ids[9].0, ids[9].1, ids[9].2, o);

    r.emergencies.extend(std::mem::take(&mut c.emergencies));
    let all = std::mem::take(&mut r.emergencies);
    let o = if all.is_empty() {
        Outcome::NotApplicable("no Emergency arrived during the checks".into())
    } else {
        let bad: Vec<String> = all
            .iter()
            .filter(|p| p.len() != 10 || p[1] >> 4 != 1)
            .map(|p| format!("{p:02x?}"))
            .collect();
        if bad.is_empty() {
            Outcome::Pass(format!("{} Emergency message(s) well formed", all.len()))
        } else {
            Outcome::Fail(bad.join("; "))
        }
    };
    r.record(emergency_id.0, emergency_id.1, emergency_id.2, o);
}
