//! `watch`: live process data of one slave, decoded by its PDO mapping.

use crate::failure::Failure;
use crate::output::{long_command, outln, stop_requested};
use crate::target::{Session, Where};
use master_test::mailbox::MailboxClient;
use std::time::Duration;

/// Options of `watch`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
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
pub async fn run(w: &Where, a: Args) -> Result<(), Failure> {
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
    fn process_data_bits_are_taken_lsb_first() {
        let image = [0b1010_0001u8, 0xE8, 0x03, 0xFF];
        assert_eq!(extract_bits(&image, 0, 1), Some(vec![1]));
        assert_eq!(extract_bits(&image, 5, 3), Some(vec![0b101]));
        assert_eq!(extract_bits(&image, 8, 16), Some(vec![0xE8, 0x03]));
        assert_eq!(extract_bits(&image, 4, 8), Some(vec![0x8A]));
        assert_eq!(extract_bits(&image, 30, 4), None);
        assert_eq!(extract_bits(&image, usize::MAX, 4), None);
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
