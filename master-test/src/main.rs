//! `master-test`: the demo and tools for software PAM-199 slaves on the
//! built-in virtual EtherCAT link.

use clap::{Parser, Subcommand};
use master_test::VirtualBus;
use master_test::link::lock;
use std::process::ExitCode;
use std::time::Duration;

#[derive(Parser)]
#[command(
    name = "master-test",
    about = "ethercrab master driving software PAM-199-P-ETC slaves on a virtual EtherCAT link"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
}

#[derive(Subcommand)]
enum Cmd {
    /// Bring PAM slaves to OP, parameterise over SDO, drive a set-point (default).
    Demo {
        /// Number of slaves on the line.
        #[arg(long, default_value_t = 1)]
        slaves: usize,
        /// Solenoid nominal current written to 0x800D:02 CURRENT, in mA.
        #[arg(long, default_value_t = 1500)]
        current: u16,
        /// Command value (0x7000:03) in IO_BASE units (10000 = 100 %).
        #[arg(long, default_value_t = 5000, allow_hyphen_values = true)]
        command: i32,
        /// Process data cycles to run (about 1 ms each).
        #[arg(long, default_value_t = 250)]
        cycles: u32,
        /// Capture every frame of the virtual link (both directions) to
        /// this pcap file (open it with Wireshark or `tshark -r FILE -Y ecat`).
        #[arg(long)]
        pcap: Option<std::path::PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let cmd = cli.command.unwrap_or(Cmd::Demo {
        slaves: 1,
        current: 1500,
        command: 5000,
        cycles: 250,
        pcap: None,
    });
    let result = match cmd {
        Cmd::Demo {
            slaves,
            current,
            command,
            cycles,
            pcap,
        } => smol::block_on(demo(slaves, current, command, cycles, pcap.as_deref())),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

async fn demo(
    slaves: usize,
    current: u16,
    command: i32,
    cycles: u32,
    pcap: Option<&std::path::Path>,
) -> Result<(), Box<dyn std::error::Error>> {
    if slaves == 0 || slaves > master_test::MAX_SUBDEVICES {
        return Err(format!(
            "--slaves must be between 1 and {}",
            master_test::MAX_SUBDEVICES
        )
        .into());
    }
    println!("== PAM-199-P-ETC demo on the virtual EtherCAT link ({slaves} slave(s)) ==");
    let bus =
        VirtualBus::with_options(slaves, master_test::link::Clock::real(), pcap).map_err(|e| {
            match pcap {
                Some(p) => format!("{e} (pcap file {})", p.display()),
                None => e.to_string(),
            }
        })?;
    let md = &*bus.maindevice;
    let group = bus.init().await?;
    for sd in group.iter(md) {
        let id = sd.identity();
        println!(
            "found {:#06x} {:<14} vendor {:#010x} product {:#010x} rev {}",
            sd.configured_address(),
            sd.name(),
            id.vendor_id,
            id.product_id,
            id.revision
        );
    }
    println!("state: PRE-OP");
    for sd in group.iter(md) {
        sd.sdo_write(0x800D, 2, current).await?;
        let back: u16 = sd.sdo_read(0x800D, 2).await?;
        println!(
            "{:#06x}: SDO write 0x800D:02 CURRENT = {current} mA, read back {back} mA",
            sd.configured_address()
        );
        match sd.sdo_write(0x800D, 2, 5000u16).await {
            Err(e) => println!(
                "{:#06x}: CURRENT = 5000 mA refused: {e}",
                sd.configured_address()
            ),
            Ok(()) => println!(
                "{:#06x}: CURRENT = 5000 mA was accepted (unexpected)",
                sd.configured_address()
            ),
        }
    }
    let group = group.into_op(md).await?;
    println!("state: OP");
    println!(
        "driving ENABLE=1, COMMAND VALUE={command} ({:.1} % of IO_BASE 10000) for {cycles} ms",
        f64::from(command) / 100.0
    );
    println!("  W = command in IO_BASE units, C = after the ramp (RA 100 ms), U = after");
    println!("  deadband compensation (TRIGGER 200), IA/IB = simulated solenoid currents");
    println!("  (dither 5 % at 120 Hz rides on IA: 0x800D:03/04).");
    println!("  t/ms  READY       W       C       U   IA/mA   IB/mA   (slave 0x1000)");
    let start = std::time::Instant::now();
    let mut next_print = 0u128;
    for cycle in 0..cycles {
        for sd in group.iter(md) {
            let mut out = sd.outputs_raw_mut();
            if out.len() >= 5 {
                out[0] = 0x01; // ENABLE
                out[1..5].copy_from_slice(&command.to_le_bytes()); // COMMAND VALUE
            }
        }
        let resp = group.tx_rx(md).await?;
        let t = start.elapsed().as_millis();
        if t >= next_print || cycle + 1 == cycles {
            next_print = t + 20;
            if let Some(sd) = group.iter(md).next() {
                let inp = sd.inputs_raw();
                println!(
                    "{:>6}  {}   wkc {}",
                    t,
                    describe_inputs(&inp),
                    resp.working_counter
                );
            }
        }
        smol::Timer::after(Duration::from_millis(1)).await;
    }
    {
        let chain = lock(&bus.chain);
        for (i, s) in chain.slaves().iter().enumerate() {
            let st = &s.slave().store;
            println!(
                "slave {i}: 0x7000:01 ENABLE = {}, 0x7000:03 COMMAND VALUE = {}, IA = {} mA, AL {}",
                st.get(0x7000, 1).unwrap_or(0),
                st.get(0x7000, 3).unwrap_or(0),
                st.get(0x6000, 6).unwrap_or(0),
                s.slave().al_status().state
            );
        }
    }
    let group = group.into_safe_op(md).await?;
    let group = group.into_pre_op(md).await?;
    let _ = group.into_init(md).await?;
    println!("state: INIT (done)");
    if let Some(p) = pcap {
        drop(bus);
        println!(
            "capture written to {} (tshark -r {} -Y ecat)",
            p.display(),
            p.display()
        );
    }
    Ok(())
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
