//! Group `foe` (opt-in): BOOT, a file download, a wrong password
//! refused.

use super::*;

pub(super) async fn foe_checks(r: &mut Run<'_>, foe_opts: Option<&FoeOptions>) {
    let ids = [
        (
            "foe.boot",
            "ETG.1000.6 6.4.1, ETG.2010 2.2",
            "INIT -> BOOT with the SII's bootstrap mailbox",
        ),
        (
            "foe.write",
            "ETG.1000.6 5.8",
            "a file written in BOOT is acknowledged packet by packet",
        ),
        (
            "foe.wrong-password",
            "ETG.1000.6 5.8",
            "a write request with a wrong password is refused with an FoE error",
        ),
    ];
    let (Some(opts), Some(boot)) = (foe_opts, r.bootstrap) else {
        let why = if foe_opts.is_none() {
            "no --foe-file given"
        } else {
            "no bootstrap mailbox in the SII"
        };
        for (id, reference, what) in ids {
            r.record(id, reference, what, Outcome::NotApplicable(why.into()));
        }
        return;
    };
    let o = match foe::enter_boot_geometry(r.md, r.station, boot).await {
        Ok(()) => Outcome::Pass("BOOT".into()),
        Err(e) => Outcome::Fail(e.to_string()),
    };
    let in_boot = matches!(o, Outcome::Pass(_));
    r.record(ids[0].0, ids[0].1, ids[0].2, o);
    let mut c = MailboxClient::new(r.md, r.station, boot);
    c.timeout = Duration::from_secs(2);
    let o = if in_boot {
        match foe::write(
            &mut c,
            "conformance.bad",
            opts.password ^ 0xFFFF_FFFF,
            &opts.file,
            |_, _| {},
        )
        .await
        {
            Err(e) if e.foe_code().is_some() => Outcome::Pass(e.to_string()),
            Err(e) => Outcome::Fail(e.to_string()),
            Ok(()) => Outcome::Fail("accepted".into()),
        }
    } else {
        Outcome::NotApplicable("not in BOOT".into())
    };
    r.record(ids[2].0, ids[2].1, ids[2].2, o);
    let o = if in_boot {
        match foe::write(&mut c, &opts.name, opts.password, &opts.file, |_, _| {}).await {
            Ok(()) => Outcome::Pass(format!("{} bytes", opts.file.len())),
            Err(e) => Outcome::Fail(e.to_string()),
        }
    } else {
        Outcome::NotApplicable("not in BOOT".into())
    };
    // Report in the documented order.
    let wrong = r.checks.pop();
    r.record(ids[1].0, ids[1].1, ids[1].2, o);
    if let Some(w) = wrong {
        r.checks.push(w);
    }
    let _ = foe::request_state(r.md, r.station, 0x11).await;
    // Back to the standard mailbox.
    if let Some(g) = r.mailbox {
        for (reg, b) in g.sm_registers() {
            let _ = r.write(reg, &b).await;
        }
    }
}
