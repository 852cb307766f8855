//! `state`: show the AL state of the slaves, or request one.

use crate::failure::{Failure, input};
use crate::output::outln;
use crate::target::{Selected, Session, Where};
use ecat_slave::al::AlStatusCode;
use ethercrab::{Command, MainDevice};
use master_test::registers;
use std::time::Duration;

/// Options of `state`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// init, preop, safeop, op or boot; none: just show the states.
    #[arg(value_parser = parse_state)]
    target: Option<AlTarget>,
}

/// An AL state a command can request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AlTarget {
    /// INIT.
    Init,
    /// PRE-OP.
    PreOp,
    /// SAFE-OP.
    SafeOp,
    /// OP.
    Op,
    /// BOOT.
    Boot,
}

impl AlTarget {
    fn code(self) -> u16 {
        match self {
            AlTarget::Init => 0x01,
            AlTarget::PreOp => 0x02,
            AlTarget::Boot => 0x03,
            AlTarget::SafeOp => 0x04,
            AlTarget::Op => 0x08,
        }
    }
}

/// `init`, `preop`/`pre-op`, `safeop`/`safe-op`, `op`, `boot`.
pub fn parse_state(s: &str) -> Result<AlTarget, String> {
    match s.to_ascii_lowercase().replace(['-', '_'], "").as_str() {
        "init" => Ok(AlTarget::Init),
        "preop" => Ok(AlTarget::PreOp),
        "safeop" => Ok(AlTarget::SafeOp),
        "op" => Ok(AlTarget::Op),
        "boot" | "bootstrap" => Ok(AlTarget::Boot),
        _ => Err(format!(
            "'{s}' is not an AL state (init, preop, safeop, op or boot)"
        )),
    }
}

/// The name of AL status register bits 0-3.
pub fn state_name(status: u16) -> &'static str {
    match status & 0x0F {
        0x01 => "INIT",
        0x02 => "PRE-OP",
        0x03 => "BOOT",
        0x04 => "SAFE-OP",
        0x08 => "OP",
        _ => "?",
    }
}

/// AL status and AL status code of one slave.
pub async fn al_status(md: &MainDevice<'_>, station: u16) -> Result<(u16, u16), Failure> {
    let st: u16 = Command::fprd(station, registers::AL_STATUS)
        .receive(md)
        .await?;
    let code: u16 = Command::fprd(station, registers::AL_STATUS_CODE)
        .receive(md)
        .await?;
    Ok((st, code))
}

/// Position, station and name of every slave.
type Roster = Vec<(usize, u16, String)>;

fn roster(s: &Session) -> Roster {
    s.group
        .iter(s.md())
        .enumerate()
        .map(|(p, sd)| (p, sd.configured_address(), sd.name().to_string()))
        .collect()
}

/// Prints every slave's state; `Err(Refused)` if one of `stations` is not
/// in `target` or shows an error.
async fn report_states(
    md: &MainDevice<'_>,
    roster: &Roster,
    want: Option<(AlTarget, &[u16])>,
) -> Result<(), Failure> {
    let mut bad = Vec::new();
    for (position, station, name) in roster {
        let (st, code) = al_status(md, *station).await?;
        let err = if st & 0x10 != 0 { "+ERR" } else { "" };
        let code_text = if code != 0 {
            format!(
                ", AL status code {code:#06x} ({})",
                AlStatusCode::from_code(code).text()
            )
        } else {
            String::new()
        };
        outln!(
            "slave {position} {station:#06x} {name:<14} {}{err}{code_text}",
            state_name(st)
        );
        if let Some((target, stations)) = want
            && stations.contains(station)
            && (st & 0x1F != target.code())
        {
            bad.push(format!(
                "slave {position} ({station:#06x}) is in {}{err}{code_text}",
                state_name(st)
            ));
        }
    }
    if bad.is_empty() {
        Ok(())
    } else {
        Err(Failure::Refused(bad.join("; ")))
    }
}

/// Runs `state`.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    let target = args.target;
    let s = Session::open(w).await?;
    let md = s.md();
    let all = roster(&s);
    let Some(target) = target else {
        return report_states(md, &all, None).await;
    };
    let selected: Vec<Selected> = if w.slave.is_some() || w.station.is_some() {
        vec![s.select(w).await?]
    } else {
        let mut v = Vec::new();
        for position in 0..all.len() {
            let one = Where {
                slave: Some(position),
                ..w.clone()
            };
            v.push(s.select(&one).await?);
        }
        v
    };
    let stations: Vec<u16> = selected.iter().map(|x| x.station).collect();
    match target {
        AlTarget::SafeOp | AlTarget::Op if w.slave.is_some() || w.station.is_some() => {
            return Err(input(
                "SAFE-OP and OP are requested for the whole segment (the master \
                 configures process data for all slaves together): leave out \
                 --slave/--station",
            ));
        }
        AlTarget::SafeOp | AlTarget::Op => {
            let Session { bus, group } = s;
            let md = bus.maindevice();
            let result: Result<(), Failure> = if target == AlTarget::SafeOp {
                group
                    .into_safe_op(md)
                    .await
                    .map(|_| ())
                    .map_err(Failure::from)
            } else {
                master_test::into_op_cyclic(group, md, Duration::from_millis(1))
                    .await
                    .map(|_| ())
                    .map_err(Failure::from)
            };
            report_states(md, &all, Some((target, &stations))).await?;
            result?;
            if target == AlTarget::Op {
                outln!(
                    "note: OP holds only while process data runs; without it a slave \
                     with a SyncManager watchdog falls back to SAFE-OP (use `watch`)"
                );
            }
            return Ok(());
        }
        AlTarget::Boot => {
            for sel in &selected {
                let boot = sel.bootstrap()?;
                if let Err(e) = master_test::foe::enter_boot_geometry(md, sel.station, boot).await {
                    eprintln!("{}: {e}", sel.label());
                }
            }
        }
        AlTarget::Init | AlTarget::PreOp => {
            for sel in &selected {
                // With the acknowledge bit: clears a pending error.
                let code = target.code() | 0x10;
                if let Err(e) = master_test::foe::request_state(md, sel.station, code).await {
                    eprintln!("{}: {e}", sel.label());
                }
            }
        }
    }
    report_states(md, &all, Some((target, &stations))).await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn states_parse_in_the_usual_spellings() {
        assert_eq!(parse_state("PRE-OP"), Ok(AlTarget::PreOp));
        assert_eq!(parse_state("safe_op"), Ok(AlTarget::SafeOp));
        assert_eq!(parse_state("Op"), Ok(AlTarget::Op));
        assert_eq!(parse_state("boot"), Ok(AlTarget::Boot));
        assert!(parse_state("run").unwrap_err().contains("not an AL state"));
        assert_eq!(state_name(0x14), "SAFE-OP");
        assert_eq!(state_name(0x03), "BOOT");
    }
}
