//! `scan`, `state` and `watch`.

use crate::failure::{Failure, input};
use crate::output::{long_command, outln, stop_requested};
use crate::target::{Selected, Session, Where};
use ecat_slave::al::AlStatusCode;
use ethercrab::{Command, MainDevice};
use master_test::eeprom;
use master_test::mailbox::MailboxClient;
use serde::Serialize;
use std::time::Duration;

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

/// Mailbox protocol names of SII word 0x1C.
fn protocols(bits: u16) -> Vec<&'static str> {
    [
        (0x01, "AoE"),
        (0x02, "EoE"),
        (0x04, "CoE"),
        (0x08, "FoE"),
        (0x10, "SoE"),
        (0x20, "VoE"),
    ]
    .iter()
    .filter(|(b, _)| bits & b != 0)
    .map(|(_, n)| *n)
    .collect()
}

/// One row of `scan` (and its JSON schema).
#[derive(Serialize)]
struct ScanRow {
    position: usize,
    station: u16,
    alias: u16,
    name: String,
    vendor_id: u32,
    product_code: u32,
    revision: u32,
    serial: u32,
    state: &'static str,
    error: bool,
    al_status_code: u16,
    al_status_text: &'static str,
    mailbox: Vec<&'static str>,
}

/// AL status (0x0130) and AL status code (0x0134) of one slave.
async fn al_status(md: &MainDevice<'_>, station: u16) -> Result<(u16, u16), Failure> {
    let st: u16 = Command::fprd(station, 0x0130).receive(md).await?;
    let code: u16 = Command::fprd(station, 0x0134).receive(md).await?;
    Ok((st, code))
}

/// Runs `scan`.
pub async fn scan(w: &Where, json: bool) -> Result<(), Failure> {
    let s = Session::open(w).await?;
    let md = s.md();
    let mut rows = Vec::new();
    for (position, sd) in s.group.iter(md).enumerate() {
        let station = sd.configured_address();
        let (st, code) = al_status(md, station).await?;
        let header = eeprom::read_header(md, station).await?;
        let bits = ecat_slave::sii::SiiReader::new(&header)
            .map(|r| r.mailbox_protocols())
            .unwrap_or(0);
        let id = sd.identity();
        rows.push(ScanRow {
            position,
            station,
            alias: sd.alias_address(),
            name: sd.name().to_string(),
            vendor_id: id.vendor_id,
            product_code: id.product_id,
            revision: id.revision,
            serial: id.serial,
            state: state_name(st),
            error: st & 0x10 != 0,
            al_status_code: code,
            al_status_text: AlStatusCode::from_code(code).text(),
            mailbox: protocols(bits),
        });
    }
    if json {
        let text = serde_json::to_string_pretty(&rows)
            .map_err(|e| Failure::Comm(format!("cannot encode JSON: {e}")))?;
        outln!("{text}");
        return Ok(());
    }
    outln!("{} slave(s) on {}", rows.len(), s.bus.describe());
    outln!(
        "{:<3} {:<7} {:<6} {:<16} {:<10} {:<10} {:<10} {:<10} {:<8} Mailbox",
        "Pos",
        "Station",
        "Alias",
        "Name",
        "Vendor",
        "Product",
        "Revision",
        "Serial",
        "State"
    );
    for r in &rows {
        let state = if r.error {
            format!("{}+ERR", r.state)
        } else {
            r.state.to_string()
        };
        outln!(
            "{:<3} {:<#7x} {:<6} {:<16} {:<#10x} {:<#10x} {:<#10x} {:<#10x} {:<8} {}",
            r.position,
            r.station,
            r.alias,
            r.name,
            r.vendor_id,
            r.product_code,
            r.revision,
            r.serial,
            state,
            r.mailbox.join(",")
        );
        if r.al_status_code != 0 {
            outln!(
                "    AL status code {:#06x}: {}",
                r.al_status_code,
                r.al_status_text
            );
        }
    }
    Ok(())
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
pub async fn state(w: &Where, target: Option<AlTarget>) -> Result<(), Failure> {
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

/// Options of `watch`.
#[derive(clap::Args, Debug, Clone)]
pub struct WatchArgs {
    /// Stop after this many process data cycles (1..=3600000, about 1 ms
    /// each); without it: until Ctrl-C.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=3_600_000))]
    cycles: Option<u32>,
    /// Print every this many milliseconds (1..=60000).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=60_000))]
    interval: u32,
    /// One JSON object per line: {"t_ms": .., "inputs": {"NAME": value, ..}}.
    #[arg(long)]
    json: bool,
}

/// One mapped input entry.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Mapped {
    index: u16,
    sub: u8,
    bits: u8,
    /// Bit offset in the slave's input image.
    offset: usize,
    name: String,
    data_type: u16,
}

/// Bits `offset..offset+len` of `image` (LSB first, as EtherCAT packs
/// process data), as little-endian bytes.
fn extract_bits(image: &[u8], offset: usize, len: usize) -> Option<Vec<u8>> {
    if offset.checked_add(len)? > image.len() * 8 {
        return None;
    }
    let mut out = vec![0u8; len.div_ceil(8)];
    for i in 0..len {
        let b = offset + i;
        if image[b / 8] >> (b % 8) & 1 != 0 {
            out[i / 8] |= 1 << (i % 8);
        }
    }
    Some(out)
}

/// The input mapping of a slave: 0x1C13 assignment, 0x1Axx entries,
/// names and types from SDO Information.
async fn input_mapping(c: &mut MailboxClient<'_>) -> Result<Vec<Mapped>, Failure> {
    let u8_of = |b: Vec<u8>| b.first().copied().unwrap_or(0);
    let n = u8_of(c.sdo_upload(0x1C13, 0, false).await?);
    let mut out = Vec::new();
    let mut offset = 0usize;
    for i in 1..=n {
        let b = c.sdo_upload(0x1C13, i, false).await?;
        let pdo = u16::from_le_bytes([b[0], b.get(1).copied().unwrap_or(0)]);
        let m = u8_of(c.sdo_upload(pdo, 0, false).await?);
        for j in 1..=m {
            let e = c.sdo_upload(pdo, j, false).await?;
            let v = u32::from_le_bytes([
                e.first().copied().unwrap_or(0),
                e.get(1).copied().unwrap_or(0),
                e.get(2).copied().unwrap_or(0),
                e.get(3).copied().unwrap_or(0),
            ]);
            let (index, sub, bits) = ((v >> 16) as u16, (v >> 8) as u8, v as u8);
            if index != 0 {
                let info = master_test::sdo_info::entry_description(
                    c,
                    index,
                    sub,
                    master_test::sdo_info::value_info::UNIT,
                )
                .await;
                let (name, data_type) = match info {
                    Ok(i) => (i.name, i.data_type),
                    Err(_) => (format!("0x{index:04X}:{sub:02X}"), 0),
                };
                out.push(Mapped {
                    index,
                    sub,
                    bits,
                    offset,
                    name,
                    data_type,
                });
            }
            offset += usize::from(bits);
        }
    }
    unique_names(&mut out);
    Ok(out)
}

/// Names that occur more than once (`SHORT CIRCUIT` of solenoid A and B)
/// get their address appended, so every printed name and JSON key is
/// unique.
fn unique_names(m: &mut [Mapped]) {
    let names: Vec<String> = m.iter().map(|x| x.name.clone()).collect();
    for x in m.iter_mut() {
        if names.iter().filter(|n| **n == x.name).count() > 1 {
            x.name = format!("{} ({:04X}:{:02X})", x.name, x.index, x.sub);
        }
    }
}

/// Runs `watch`.
pub async fn watch(w: &Where, a: &WatchArgs) -> Result<(), Failure> {
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let mapping = match s.client(&sel) {
        Ok(mut c) => input_mapping(&mut c).await.unwrap_or_else(|e| {
            eprintln!("note: no PDO mapping over SDO ({e}); inputs shown as bytes");
            Vec::new()
        }),
        Err(_) => Vec::new(),
    };
    let Session { bus, group } = s;
    let md = bus.maindevice();
    long_command();
    let group = master_test::into_op_cyclic(group, md, Duration::from_millis(1)).await?;
    // With --json standard output carries only the JSON lines.
    let say = |t: String| {
        if a.json {
            eprintln!("{t}");
        } else {
            outln!("{t}");
        }
    };
    say(format!(
        "{} in OP; inputs every {} ms ({}; Ctrl-C stops)",
        sel.label(),
        a.interval,
        if mapping.is_empty() {
            "raw bytes".to_string()
        } else {
            mapping
                .iter()
                .map(|m| format!("{} = 0x{:04X}:{:02X}", m.name, m.index, m.sub))
                .collect::<Vec<_>>()
                .join(", ")
        }
    ));
    let clock = bus.clock().clone();
    let start = clock.elapsed();
    let mut next = Duration::ZERO;
    let mut cycles = 0u32;
    let mut result = Ok(());
    while !stop_requested() && a.cycles.is_none_or(|n| cycles < n) {
        if let Err(e) = group.tx_rx(md).await {
            result = Err(Failure::from(e));
            break;
        }
        cycles += 1;
        let t = clock.elapsed() - start;
        if t >= next {
            next = t + Duration::from_millis(u64::from(a.interval));
            let sd = group.subdevice(md, sel.position)?;
            let image = sd.inputs_raw();
            print_inputs(t, &image, &mapping, a.json);
        }
        clock.sleep(Duration::from_millis(1)).await;
    }
    let group = group.into_safe_op(md).await?;
    let _ = group.into_pre_op(md).await?;
    say(format!(
        "stopped after {cycles} cycles; the segment is back in PRE-OP"
    ));
    result
}

fn print_inputs(t: Duration, image: &[u8], mapping: &[Mapped], json: bool) {
    let values: Vec<(String, master_test::cli::Value)> = mapping
        .iter()
        .filter_map(|m| {
            let b = extract_bits(image, m.offset, usize::from(m.bits))?;
            Some((
                m.name.clone(),
                master_test::cli::decode(m.data_type, u16::from(m.bits), &b),
            ))
        })
        .collect();
    if json {
        let mut inputs = serde_json::Map::new();
        for (n, v) in &values {
            inputs.insert(n.clone(), v.to_json());
        }
        if mapping.is_empty() {
            inputs.insert("raw".into(), master_test::cli::hex(image).into());
        }
        let line = serde_json::json!({ "t_ms": t.as_millis() as u64, "inputs": inputs });
        outln!("{line}");
    } else if mapping.is_empty() {
        outln!("{:>7}  {}", t.as_millis(), master_test::cli::hex(image));
    } else {
        let text: Vec<String> = values.iter().map(|(n, v)| format!("{n}={v}")).collect();
        outln!("{:>7}  {}", t.as_millis(), text.join("  "));
    }
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

    #[test]
    fn process_data_bits_are_taken_lsb_first() {
        let image = [0b1010_0001u8, 0xE8, 0x03, 0xFF];
        assert_eq!(extract_bits(&image, 0, 1), Some(vec![1]));
        assert_eq!(extract_bits(&image, 5, 3), Some(vec![0b101]));
        assert_eq!(extract_bits(&image, 8, 16), Some(vec![0xE8, 0x03]));
        assert_eq!(extract_bits(&image, 4, 8), Some(vec![0x8A]));
        assert_eq!(extract_bits(&image, 30, 4), None);
        assert_eq!(extract_bits(&image, usize::MAX, 4), None);
        assert_eq!(protocols(0x0C), vec!["CoE", "FoE"]);
    }

    #[test]
    fn duplicate_input_names_get_their_address() {
        let m = |index, name: &str| Mapped {
            index,
            sub: 1,
            bits: 1,
            offset: 0,
            name: name.into(),
            data_type: 1,
        };
        let mut v = vec![
            m(0xA010, "SHORT CIRCUIT"),
            m(0xA020, "SHORT CIRCUIT"),
            m(0x6000, "READY"),
        ];
        unique_names(&mut v);
        assert_eq!(v[0].name, "SHORT CIRCUIT (A010:01)");
        assert_eq!(v[1].name, "SHORT CIRCUIT (A020:01)");
        assert_eq!(v[2].name, "READY");
    }
}
