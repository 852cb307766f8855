//! `demo`: PAM slaves to OP, SDO parameters, a set-point, the result.

use crate::failure::{Failure, input};
use crate::options::SharedOptions;
use crate::output::{long_command, outln, stop_requested};
use crate::target::{Where, connect, initialised};
use master_test::bus::Bus;
use master_test::{LONG_LINE, LONG_PDI_LEN, LineProgress, MAX_SUBDEVICES, PDI_LEN};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Range and unit of a PAM dictionary entry, for `--help` and clap.
fn pam_range(index: u16, sub: u8) -> (i64, i64, &'static str) {
    pam_199_p_etc::DEVICE
        .dictionary
        .find_entry(index, sub)
        .and_then(|(_, e)| Some((e.min()?, e.max()?, e.unit())))
        .unwrap_or((0, i64::from(u16::MAX), ""))
}

fn current_help() -> String {
    let (min, max, unit) = pam_range(0x800D, 2);
    format!(
        "Solenoid nominal current written to 0x800D:02 CURRENT, {min}..={max} {unit} \
         (the range SDO Information gives)"
    )
}

fn current_parser() -> clap::builder::RangedI64ValueParser<u16> {
    let (min, max, _) = pam_range(0x800D, 2);
    clap::value_parser!(u16).range(min..=max)
}

/// 100 % of the command value: the default of 0xF800:01 IO_BASE.
fn io_base() -> i64 {
    pam_199_p_etc::DEVICE
        .dictionary
        .find_entry(0xF800, 1)
        .map_or(10_000, |(_, e)| match e.default_value() {
            ecat_slave::od::types::DefaultValue::Int(v) => v.get(),
            _ => 10_000,
        })
}

fn command_help() -> String {
    let b = io_base();
    format!(
        "Command value 0x7000:03 in IO_BASE units, -{b}..={b} ({b} = 100 % with the \
         default 0xF800:01 IO_BASE; negative drives solenoid B)"
    )
}

fn command_parser() -> clap::builder::RangedI64ValueParser<i32> {
    let b = io_base();
    clap::value_parser!(i32).range(-b..=b)
}

/// Most cycles of one demo run: one hour at 1 ms.
pub const MAX_CYCLES: u32 = 3_600_000;

/// Options of `demo`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// Number of PAM slaves on the virtual line, 1..=1024 (or use
    /// --line); a progress bar shows the bring-up of long lines.
    #[arg(long, default_value_t = 1,
          value_parser = clap::value_parser!(u16).range(1..=LONG_LINE as i64))]
    pub slaves: u16,
    #[arg(long, default_value_t = 1500, help = current_help(), value_parser = current_parser(),
          allow_negative_numbers = true)]
    pub current: u16,
    #[arg(long, default_value_t = 5000, help = command_help(), value_parser = command_parser(),
          allow_negative_numbers = true)]
    pub command: i32,
    /// Process data cycles to run, about 1 ms each, 1..=3600000 (one
    /// hour); Ctrl-C stops earlier, in order.
    #[arg(long, default_value_t = 250,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_CYCLES)))]
    pub cycles: u32,
    /// Capture every frame of the virtual link (both directions) to this
    /// pcap file (open it with Wireshark or `tshark -r FILE -Y ecat`).
    #[arg(long, value_name = "FILE")]
    pub pcap: Option<std::path::PathBuf>,
}

impl Default for Args {
    fn default() -> Self {
        Args {
            slaves: 1,
            current: 1500,
            command: 5000,
            cycles: 250,
            pcap: None,
        }
    }
}

/// What the demo saw of one slave at the end.
struct Last {
    inputs: Vec<u8>,
    outputs: Vec<u8>,
}

/// Lines longer than this list only their first and last slaves.
const LIST_ALL_UP_TO: usize = 16;

/// The positions of `n` slaves the demo prints: all of a short line, the
/// first two and the last two of a long one (`None` stands for the rest).
fn shown(n: usize) -> Vec<Option<usize>> {
    if n <= LIST_ALL_UP_TO {
        (0..n).map(Some).collect()
    } else {
        vec![Some(0), Some(1), None, Some(n - 2), Some(n - 1)]
    }
}

/// A progress bar of the bring-up of a virtual line (on a terminal; it
/// draws nothing into a pipe), fed from the slaves' registers.
struct BringUp {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl BringUp {
    /// Starts watching `bus` (nothing on a network interface).
    fn watch(bus: &Bus) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let thread = bus.shared_chain().map(|chain| {
            let stop = stop.clone();
            std::thread::spawn(move || {
                let total = LineProgress::of(&master_test::link::lock(&chain)).total();
                let bar = indicatif::ProgressBar::new(total as u64);
                bar.set_style(
                    indicatif::ProgressStyle::with_template("{bar:40} {msg} {elapsed}")
                        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                );
                while !stop.load(Ordering::Acquire) {
                    let p = LineProgress::of(&master_test::link::lock(&chain));
                    bar.set_position(p.done() as u64);
                    bar.set_message(format!(
                        "{} slaves: SII read {}, PRE-OP {}, SAFE-OP {}, OP {}",
                        p.slaves, p.sii_read, p.pre_op, p.safe_op, p.op
                    ));
                    std::thread::sleep(Duration::from_millis(100));
                }
                bar.finish_and_clear();
            })
        });
        BringUp { stop, thread }
    }
}

impl Drop for BringUp {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Slaves on the virtual line `w` names (0 on an interface or for an
/// unknown device, which the bus then reports).
fn line_length(w: &Where) -> usize {
    if w.iface.is_some() || w.eni.is_some() {
        return 0;
    }
    device_catalog::parse_line(&w.line).map_or(0, |l| l.len())
}

/// Runs `demo`: without --line or --device on a line of --slaves PAMs,
/// on a thread with a big stack (a long line's group is large, see
/// [`master_test::LongGroup`]).
pub fn run(shared: &SharedOptions, args: Args) -> Result<(), Failure> {
    let mut w = shared.target(|| format!("pam*{}", args.slaves))?;
    if w.eni.is_some() {
        return Err(input(
            "the demo drives PAMs of its own; use scan, state, sdo, watch or od with --eni",
        ));
    }
    if shared.names_virtual_line() && args.slaves != 1 {
        return Err(input("--slaves cannot be combined with --line or --device"));
    }
    w.pcap.clone_from(&args.pcap);
    std::thread::Builder::new()
        .name("demo".into())
        .stack_size(64 << 20)
        .spawn(move || smol::block_on(demo(&w, &args)))
        .map_err(|e| Failure::Comm(format!("cannot start the demo thread: {e}")))?
        .join()
        .unwrap_or_else(|_| Err(Failure::Comm("the demo thread panicked".into())))
}

/// The demo: a line of up to [`MAX_SUBDEVICES`] in the tools' group,
/// longer ones (up to [`LONG_LINE`]) in a long group.
async fn demo(w: &Where, a: &Args) -> Result<(), Failure> {
    if w.iface.is_some() && a.pcap.is_some() {
        return Err(input(
            "--pcap captures the virtual bus; on an interface use tshark or tcpdump",
        ));
    }
    if line_length(w) > MAX_SUBDEVICES {
        let bus = connect(w, LONG_LINE)?;
        let bring_up = BringUp::watch(&bus);
        let group = bus.init_group::<LONG_LINE, LONG_PDI_LEN>().await;
        drop(bring_up);
        let group = initialised(&bus, group)?;
        drive(w, a, bus, group).await
    } else {
        let bus = connect(w, MAX_SUBDEVICES)?;
        let bring_up = BringUp::watch(&bus);
        let group = bus.init_group::<MAX_SUBDEVICES, PDI_LEN>().await;
        drop(bring_up);
        let group = initialised(&bus, group)?;
        drive(w, a, bus, group).await
    }
}

/// The demo on an initialised group of up to `N` slaves.
async fn drive<const N: usize, const P: usize>(
    w: &Where,
    a: &Args,
    bus: Bus,
    group: ethercrab::SubDeviceGroup<
        N,
        P,
        ethercrab::DefaultLock,
        ethercrab::subdevice_group::PreOp,
    >,
) -> Result<(), Failure> {
    let md = bus.maindevice();
    let line = if w.iface.is_none() {
        format!(": {}", w.line)
    } else {
        String::new()
    };
    let n = group.len();
    outln!(
        "== PAM-199-P-ETC demo on {} ({n} slave(s){line}) ==",
        bus.describe(),
    );
    for i in shown(n) {
        let Some(sd) = i.and_then(|i| group.subdevice(md, i).ok()) else {
            outln!("... ({} more)", n.saturating_sub(4));
            continue;
        };
        let id = sd.identity();
        outln!(
            "found {:#06x} {:<14} vendor {:#010x} product {:#010x} rev {}",
            sd.configured_address(),
            sd.name(),
            id.vendor_id,
            id.product_id,
            id.revision
        );
    }
    outln!("state: PRE-OP{}", leds_of(&bus));
    let pams: Vec<bool> = group
        .iter(md)
        .map(|sd| {
            let id = sd.identity();
            id.vendor_id == pam_199_p_etc::VENDOR_ID && id.product_id == pam_199_p_etc::PRODUCT_CODE
        })
        .collect();
    if !pams.contains(&true) {
        outln!("no PAM-199-P-ETC on the segment: the other devices get a walking bit");
    }
    let listed = shown(n);
    let mut quiet = 0;
    for (i, (sd, _)) in group
        .iter(md)
        .zip(&pams)
        .enumerate()
        .filter(|(_, (_, pam))| **pam)
    {
        sd.sdo_write(0x800D, 2, a.current).await?;
        let back: u16 = sd.sdo_read(0x800D, 2).await?;
        // Show the device's own range check: one value above the range.
        let (_, max, _) = pam_range(0x800D, 2);
        let above = u16::try_from(max + 1).unwrap_or(u16::MAX);
        let refused = sd.sdo_write(0x800D, 2, above).await;
        if !listed.contains(&Some(i)) {
            quiet += 1;
            if refused.is_ok() || back != a.current {
                outln!(
                    "{:#06x}: CURRENT read back {back} mA, {above} mA {}",
                    sd.configured_address(),
                    if refused.is_ok() {
                        "accepted (unexpected)"
                    } else {
                        "refused"
                    }
                );
            }
            continue;
        }
        outln!(
            "{:#06x}: SDO write 0x800D:02 CURRENT = {} mA, read back {back} mA",
            sd.configured_address(),
            a.current
        );
        match refused {
            Err(e) => outln!(
                "{:#06x}: CURRENT = {above} mA refused by the slave: {e}",
                sd.configured_address()
            ),
            Ok(()) => outln!(
                "{:#06x}: CURRENT = {above} mA was accepted (unexpected)",
                sd.configured_address()
            ),
        }
    }
    if quiet > 0 {
        outln!(
            "... the same on {quiet} more PAM(s): CURRENT = {} mA written and read back, \
             {} mA refused",
            a.current,
            pam_range(0x800D, 2).1 + 1
        );
    }
    long_command();
    let bring_up = BringUp::watch(&bus);
    let group = master_test::into_op_cyclic(group, md, Duration::from_millis(1)).await?;
    drop(bring_up);
    outln!("state: OP{}", leds_of(&bus));
    let base = io_base() as f64;
    outln!(
        "driving ENABLE=1, COMMAND VALUE={} ({:.1} % of IO_BASE {base}) for {} ms",
        a.command,
        f64::from(a.command) * 100.0 / base,
        a.cycles
    );
    outln!("  W = command in IO_BASE units, C = after the ramp (RA 100 ms), U = after");
    outln!("  deadband compensation (TRIGGER 200), IA/IB = simulated solenoid currents");
    outln!("  (dither 5 % at 120 Hz rides on IA: 0x800D:03/04).");
    outln!("  t/ms  READY       W       C       U   IA/mA   IB/mA   (first PAM)");
    let clock = bus.clock().clone();
    let start = clock.elapsed();
    let mut next_print = 0u128;
    let mut done = 0u32;
    let mut result = Ok(());
    while done < a.cycles && !stop_requested() {
        for (i, (sd, pam)) in group.iter(md).zip(&pams).enumerate() {
            let mut out = sd.outputs_raw_mut();
            if *pam && out.len() >= 5 {
                out[0] = 0x01; // ENABLE
                out[1..5].copy_from_slice(&a.command.to_le_bytes()); // COMMAND VALUE
            } else if let Some(b) = out.first_mut() {
                // Any other device: a bit walking once per 100 ms.
                *b = 1 << ((done / 100 + i as u32) % 8);
            }
        }
        let resp = match group.tx_rx(md).await {
            Ok(r) => r,
            Err(e) => {
                result = Err(Failure::from(e));
                break;
            }
        };
        done += 1;
        let t = (clock.elapsed() - start).as_millis();
        if t >= next_print || done == a.cycles {
            next_print = t + 20;
            if let Some((sd, _)) = group.iter(md).zip(&pams).find(|(_, p)| **p) {
                outln!(
                    "{:>6}  {}   wkc {}",
                    t,
                    describe_inputs(&sd.inputs_raw()),
                    resp.working_counter
                );
            }
        }
        clock.sleep(Duration::from_millis(1)).await;
    }
    let last: Vec<Last> = group
        .iter(md)
        .map(|sd| Last {
            inputs: sd.inputs_raw().to_vec(),
            outputs: sd.outputs_raw().to_vec(),
        })
        .collect();
    let names: Vec<String> = group.iter(md).map(|sd| sd.name().to_string()).collect();
    // An orderly stop whatever happened: outputs off (SAFE-OP), then INIT.
    let group = group.into_safe_op(md).await?;
    let group = group.into_pre_op(md).await?;
    let _ = group.into_init(md).await?;
    for i in shown(last.len()) {
        let Some(((l, pam), name)) =
            i.and_then(|i| Some((last.get(i)?, pams.get(i)?)).zip(names.get(i)))
        else {
            outln!("... ({} more)", last.len().saturating_sub(4));
            continue;
        };
        let i = i.unwrap_or_default();
        if *pam {
            outln!("slave {i} {name}: {}", pam_summary(l));
        } else {
            outln!(
                "slave {i} {name}: outputs {} inputs {}",
                master_test::cli::hex(&l.outputs),
                master_test::cli::hex(&l.inputs)
            );
        }
    }
    outln!("state: INIT (done){}", leds_of(&bus));
    if let Some(p) = &a.pcap {
        drop(bus);
        outln!(
            "capture written to {} (tshark -r {} -Y ecat)",
            p.display(),
            p.display()
        );
    }
    result?;
    if done < a.cycles {
        return Err(Failure::Interrupted(format!(
            "after {done} of {} cycles; outputs were switched off and the slaves \
             left in INIT",
            a.cycles
        )));
    }
    Ok(())
}

fn leds_of(bus: &master_test::bus::Bus) -> String {
    bus.leds()
        .map(|l| format!("   LEDs {l}"))
        .unwrap_or_default()
}

/// The end of the run of one PAM from its last process data: what was
/// commanded and both solenoid currents.
fn pam_summary(l: &Last) -> String {
    let command = l
        .outputs
        .get(1..5)
        .map_or(0, |b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let enable = l.outputs.first().map_or(0, |b| b & 1);
    let u16_at = |o: usize| {
        l.inputs
            .get(o..o + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let current = |v: Option<u16>| v.map_or_else(|| "?".into(), |v| format!("{v} mA"));
    format!(
        "ENABLE = {enable}, COMMAND VALUE = {command}, READY = {}, IA = {}, IB = {}",
        l.inputs.first().map_or(0, |b| b & 1),
        current(u16_at(10)),
        current(u16_at(12))
    )
}

/// Decodes the directional input image (0x1A00 + 0x1A02) as one line.
fn describe_inputs(b: &[u8]) -> String {
    if b.len() < 14 {
        return format!("{b:02x?}");
    }
    let i16_at = |o: usize| i16::from_le_bytes([b[o], b[o + 1]]);
    let u16_at = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]);
    let diag = if b[1] | b[2] | b[3] != 0 {
        format!(" diag {:#04x}/{:#04x}/{:#04x}", b[1], b[2], b[3])
    } else {
        String::new()
    };
    format!(
        "{:>5} {:>7} {:>7} {:>7} {:>7} {:>7}{diag}",
        b[0] & 1,
        i16_at(4),
        i16_at(6),
        i16_at(8),
        u16_at(10),
        u16_at(12)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_come_from_the_pam_dictionary() {
        assert_eq!(pam_range(0x800D, 2), (500, 3000, "mA"));
        assert_eq!(io_base(), 10_000);
        assert!(current_help().contains("500..=3000 mA"));
        assert!(command_help().contains("-10000..=10000"));
    }

    #[test]
    fn summary_shows_both_solenoids() {
        let mut inputs = vec![0u8; 14];
        inputs[0] = 1;
        inputs[12..14].copy_from_slice(&417u16.to_le_bytes());
        let mut outputs = vec![1u8, 0, 0, 0, 0];
        outputs[1..5].copy_from_slice(&(-2500i32).to_le_bytes());
        let s = pam_summary(&Last { inputs, outputs });
        assert_eq!(
            s,
            "ENABLE = 1, COMMAND VALUE = -2500, READY = 1, IA = 0 mA, IB = 417 mA"
        );
    }
}
