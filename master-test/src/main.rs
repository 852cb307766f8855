//! `master-test`: the demo and tools for software slaves on the built-in
//! virtual EtherCAT link (the PAM-199-P-ETC, or any catalog device with
//! `--device`).
//!
//! * `demo` (the default): OP, SDO parameters, a set-point.
//! * `sdo read|write INDEX:SUB [VALUE]`: one entry, typed by the slave's
//!   own SDO Information.
//! * `od dump [--json]`: the live object dictionary, like TwinCAT's
//!   CoE-Online tab.

use clap::{Parser, Subcommand};
use master_test::VirtualBus;
use master_test::cli;
use master_test::link::lock;
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use master_test::od::{DumpEntry, EntryValue};
use master_test::sdo_info::{self, EntryInfo, value_info};
use std::io::Write as _;
use std::process::ExitCode;
use std::time::Duration;

#[derive(Parser)]
#[command(
    name = "master-test",
    about = "ethercrab master driving software PAM-199-P-ETC slaves on a virtual EtherCAT link"
)]
struct Cli {
    /// The device the `sdo`, `od`, `foe` and `firmware` commands talk to
    /// (pam, io8, ...; see `esi devices`). The demo always runs the PAM.
    #[arg(long, global = true, default_value = "pam")]
    device: String,
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
        /// A mixed line instead of --slaves PAMs, e.g. pam,io8,pam: the
        /// PAMs are parameterised and driven as above, every other device
        /// gets a walking bit on its outputs.
        #[arg(long, conflicts_with = "slaves")]
        line: Option<String>,
    },
    /// Read or write one object entry over CoE SDO (one slave in PRE-OP).
    ///
    /// Values are typed by the slave's own SDO Information (Get Entry
    /// Description): data type, bit length, access, unit.
    Sdo {
        #[command(subcommand)]
        op: SdoCmd,
    },
    /// Browse the live object dictionary (one slave in PRE-OP).
    Od {
        #[command(subcommand)]
        op: OdCmd,
    },
    /// File access over EtherCAT: firmware download in BOOT, file read.
    Foe {
        #[command(subcommand)]
        op: FoeCmd,
    },
    /// Firmware image tools.
    Firmware {
        #[command(subcommand)]
        op: FirmwareCmd,
    },
}

#[derive(Subcommand)]
enum FoeCmd {
    /// Download an `.efw` image to one slave in BOOT (manual 5.10), then
    /// INIT and a simulated power cycle; prints the version that runs.
    Write {
        /// The `.efw` file (see `firmware pack`).
        file: std::path::PathBuf,
        /// FoE password in hex (the PAM-199 expects 00000000).
        #[arg(long, default_value = "00000000")]
        password: String,
        /// File name sent in the write request.
        #[arg(long, default_value = "pam-199-p-etc.efw")]
        name: String,
    },
    /// Read a file the slave offers (e.g. `info.txt`) in PRE-OP.
    Read {
        /// File name.
        name: String,
        /// Write the file here instead of printing it.
        #[arg(short, long)]
        output: Option<std::path::PathBuf>,
    },
}

#[derive(Subcommand)]
enum FirmwareCmd {
    /// Wrap a binary into an `.efw` image for the PAM-199-P-ETC.
    Pack {
        /// The firmware binary.
        binary: std::path::PathBuf,
        /// Firmware version text (up to 16 ASCII characters).
        #[arg(long)]
        version: String,
        /// Output file.
        #[arg(short, long)]
        output: std::path::PathBuf,
        /// Lowest device revision the image supports.
        #[arg(long, default_value_t = 0)]
        revision_min: u32,
        /// Highest device revision the image supports.
        #[arg(long, default_value_t = u32::MAX)]
        revision_max: u32,
    },
}

#[derive(Subcommand)]
enum SdoCmd {
    /// Upload INDEX:SUB and print its value with name, unit and type.
    ///
    /// Integers print in decimal (signed where the type is), enumerations
    /// as `TEXT (value)`, BOOL as true/false, strings as text.
    Read {
        /// Object address: hex index with or without 0x, subindex decimal
        /// or 0x-hex (`0x800D:02`, `800D:2`, `8006:0x2A`).
        address: String,
        /// Print the uploaded bytes in hex instead of the typed value.
        #[arg(long)]
        raw: bool,
    },
    /// Parse VALUE for the entry's type, download it, read it back.
    ///
    /// Integers in decimal or 0x-hex (negative for signed types),
    /// enumerations by text or number, BOOL as true/false/1/0, strings as
    /// text. The value is encoded in the entry's byte size and downloaded
    /// expedited (up to 4 bytes) or normal.
    Write {
        /// Object address, as for `sdo read`.
        address: String,
        /// The value to write.
        #[arg(allow_hyphen_values = true)]
        value: String,
    },
}

#[derive(Subcommand)]
enum OdCmd {
    /// Every object of the OD list (all objects) with every subindex:
    /// name, type, access, unit and the current value.
    Dump {
        /// Print a JSON array of objects with their entries (including
        /// default, minimum and maximum) instead of a table.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let dev = match device_catalog::find(&cli.device) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    cli::use_enums(dev.description.dictionary.enums());
    let cmd = cli.command.unwrap_or(Cmd::Demo {
        slaves: 1,
        current: 1500,
        command: 5000,
        cycles: 250,
        pcap: None,
        line: None,
    });
    let result = match cmd {
        Cmd::Demo {
            slaves,
            current,
            command,
            cycles,
            pcap,
            line,
        } => {
            let spec = line.unwrap_or_else(|| format!("pam*{slaves}"));
            smol::block_on(demo(&spec, current, command, cycles, pcap.as_deref()))
        }
        Cmd::Sdo {
            op: SdoCmd::Read { address, raw },
        } => smol::block_on(sdo_read(dev, &address, raw)),
        Cmd::Sdo {
            op: SdoCmd::Write { address, value },
        } => smol::block_on(sdo_write(dev, &address, &value)),
        Cmd::Od {
            op: OdCmd::Dump { json },
        } => smol::block_on(od_dump(dev, json)),
        Cmd::Foe {
            op:
                FoeCmd::Write {
                    file,
                    password,
                    name,
                },
        } => smol::block_on(foe_write(dev, &file, &password, &name)),
        Cmd::Foe {
            op: FoeCmd::Read { name, output },
        } => smol::block_on(foe_read(dev, &name, output.as_deref())),
        Cmd::Firmware {
            op:
                FirmwareCmd::Pack {
                    binary,
                    version,
                    output,
                    revision_min,
                    revision_max,
                },
        } => firmware_pack(dev, &binary, &version, &output, revision_min, revision_max),
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
    spec: &str,
    current: u16,
    command: i32,
    cycles: u32,
    pcap: Option<&std::path::Path>,
) -> Result<(), Box<dyn std::error::Error>> {
    let bus =
        VirtualBus::line_with(spec, master_test::link::Clock::real(), pcap).map_err(
            |e| match pcap {
                Some(p) => format!("{e} (pcap file {})", p.display()),
                None => e.to_string(),
            },
        )?;
    let slaves = lock(&bus.chain).slaves().len();
    println!("== PAM-199-P-ETC demo on the virtual EtherCAT link ({slaves} slave(s): {spec}) ==");
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
    println!("state: PRE-OP   LEDs {}", leds(&bus));
    let pams: Vec<bool> = group
        .iter(md)
        .map(|sd| sd.identity().product_id == pam_199_p_etc::PRODUCT_CODE)
        .collect();
    for (sd, _) in group.iter(md).zip(&pams).filter(|(_, pam)| **pam) {
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
    println!("state: OP       LEDs {}", leds(&bus));
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
        for (sd, pam) in group.iter(md).zip(&pams) {
            let mut out = sd.outputs_raw_mut();
            if *pam && out.len() >= 5 {
                out[0] = 0x01; // ENABLE
                out[1..5].copy_from_slice(&command.to_le_bytes()); // COMMAND VALUE
            } else if let Some(b) = out.first_mut() {
                // Any other device: a bit walking once per 100 ms.
                *b = 1 << ((cycle / 100) % 8);
            }
        }
        let resp = group.tx_rx(md).await?;
        let t = start.elapsed().as_millis();
        if t >= next_print || cycle + 1 == cycles {
            next_print = t + 20;
            let first_pam = group.iter(md).zip(&pams).find(|(_, p)| **p);
            if let Some((sd, _)) = first_pam {
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
            let st = s.od();
            let name = s.description().names.type_name;
            if s.description().identity.product_code == pam_199_p_etc::PRODUCT_CODE {
                println!(
                    "slave {i} {name}: 0x7000:01 ENABLE = {}, 0x7000:03 COMMAND VALUE = {}, IA = {} mA, AL {}",
                    st.get(0x7000, 1).unwrap_or(0),
                    st.get(0x7000, 3).unwrap_or(0),
                    st.get(0x6000, 6).unwrap_or(0),
                    s.al_status().state
                );
            } else {
                let bits: String = (1..=8u8)
                    .map(|c| {
                        if st.get(0x7000, c) == Some(1) {
                            '1'
                        } else {
                            '0'
                        }
                    })
                    .collect();
                println!(
                    "slave {i} {name}: outputs 0x7000:01..08 = {bits}, AL {}",
                    s.al_status().state
                );
            }
        }
    }
    let group = group.into_safe_op(md).await?;
    let group = group.into_pre_op(md).await?;
    let _ = group.into_init(md).await?;
    println!("state: INIT (done)   LEDs {}", leds(&bus));
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

type BoxError = Box<dyn std::error::Error>;

/// Runs `f` with a mailbox client for the one slave of a fresh virtual bus
/// in PRE-OP.
async fn with_client<T>(
    dev: &device_catalog::DeviceEntry,
    f: impl AsyncFnOnce(&mut MailboxClient<'_>) -> Result<T, BoxError>,
) -> Result<T, BoxError> {
    let bus = VirtualBus::line(dev.key, master_test::link::Clock::real())?;
    let md = &*bus.maindevice;
    let group = bus.init().await?;
    let station = group
        .subdevice(md, 0)
        .map_err(|e| format!("no slave on the virtual bus: {e}"))?
        .configured_address();
    let geometry = MailboxGeometry::of(&dev.description.layout());
    let mut client = MailboxClient::new(md, station, geometry);
    f(&mut client).await
}

/// `0x800D:02 CURRENT = 1000 mA  (UINT, RW)`.
/// Without `unit` (raw bytes) the unit is left out.
fn describe(e: &EntryInfo, value: &str, unit: bool) -> String {
    let unit = if unit { cli::unit_text(e.unit) } else { "" };
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    format!(
        "0x{:04X}:{:02X} {} = {value}{unit}  ({}, {})",
        e.index,
        e.sub,
        e.name,
        cli::type_name(e.data_type),
        cli::access_text(e.access)
    )
}

async fn sdo_read(
    dev: &device_catalog::DeviceEntry,
    address: &str,
    raw: bool,
) -> Result<(), BoxError> {
    let (index, sub) = cli::parse_address(address)?;
    with_client(dev, async |c| {
        let e = sdo_info::entry_description(c, index, sub, value_info::UNIT).await?;
        let bytes = c.sdo_upload(index, sub, false).await?;
        let shown = if raw {
            cli::hex(&bytes)
        } else {
            cli::show(&cli::decode(e.data_type, e.bit_len, &bytes), e.bit_len)
        };
        println!("{}", describe(&e, &shown, !raw));
        Ok(())
    })
    .await
}

async fn sdo_write(
    dev: &device_catalog::DeviceEntry,
    address: &str,
    value: &str,
) -> Result<(), BoxError> {
    let (index, sub) = cli::parse_address(address)?;
    with_client(dev, async |c| {
        let e = sdo_info::entry_description(c, index, sub, value_info::UNIT).await?;
        let bytes = cli::parse_value(e.data_type, e.bit_len, value).map_err(|m| {
            format!(
                "bad value for 0x{index:04X}:{sub:02X} {} ({}): {m}",
                e.name,
                cli::type_name(e.data_type)
            )
        })?;
        let how = if bytes.len() <= 4 {
            "expedited"
        } else {
            "normal"
        };
        println!(
            "0x{:04X}:{sub:02X} {} := {} ({}, {how} download)",
            index,
            e.name,
            cli::format_value(e.data_type, e.bit_len, &bytes),
            cli::hex(&bytes)
        );
        c.sdo_download(index, sub, false, &bytes).await?;
        let back = c.sdo_upload(index, sub, false).await?;
        let shown = cli::show(&cli::decode(e.data_type, e.bit_len, &back), e.bit_len);
        println!("{}", describe(&e, &shown, true));
        Ok(())
    })
    .await
}

async fn od_dump(dev: &device_catalog::DeviceEntry, json: bool) -> Result<(), BoxError> {
    let result = with_client(dev, async |c| {
        let stdout = std::io::stdout();
        let mut out = std::io::BufWriter::new(stdout.lock());
        let objects = sdo_info::od_list(c, sdo_info::list_type::ALL).await?;
        if json {
            writeln!(out, "[")?;
        } else {
            writeln!(
                out,
                "{:<9}  {:<28} {:<11} {:<3} {:<4} Value",
                "Index", "Name", "Type", "Acc", "Unit"
            )?;
        }
        for (n, &index) in objects.iter().enumerate() {
            let o = master_test::od::read_object(c, index).await?;
            let (obj, entries) = (&o.info, &o.entries);
            if json {
                let last = n + 1 == objects.len();
                write_json_object(&mut out, obj, entries, last)?;
            } else {
                writeln!(
                    out,
                    "{:04X}       {:<28} [{}]",
                    obj.index,
                    obj.name,
                    cli::object_code_text(obj.object_code)
                )?;
                for d in entries {
                    let e = &d.info;
                    writeln!(
                        out,
                        "  {:04X}:{:02X}  {:<28} {:<11} {:<3} {:<4} {}",
                        e.index,
                        e.sub,
                        e.name,
                        cli::type_name(e.data_type),
                        cli::access_text(e.access),
                        cli::unit_text(e.unit),
                        d.value.text(e.bit_len)
                    )?;
                }
            }
        }
        if json {
            writeln!(out, "]")?;
        }
        out.flush()?;
        Ok(())
    })
    .await;
    // `od dump | head` closes the pipe early: that is not an error.
    match result {
        Err(e)
            if e.downcast_ref::<std::io::Error>()
                .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe) =>
        {
            Ok(())
        }
        other => other,
    }
}

/// Writes one object of `od dump --json` (entries one per line).
fn write_json_object(
    out: &mut impl std::io::Write,
    obj: &sdo_info::ObjectInfo,
    entries: &[DumpEntry],
    last: bool,
) -> std::io::Result<()> {
    let opt = |v: &Option<Vec<u8>>, e: &EntryInfo| {
        v.as_deref().map_or_else(
            || "null".to_string(),
            |b| cli::decode(e.data_type, e.bit_len, b).to_json(),
        )
    };
    writeln!(out, "  {{")?;
    writeln!(out, "    \"index\": {},", obj.index)?;
    writeln!(out, "    \"name\": {},", cli::json_str(&obj.name))?;
    writeln!(out, "    \"object_code\": {},", obj.object_code)?;
    writeln!(out, "    \"entries\": [")?;
    for (i, d) in entries.iter().enumerate() {
        let e = &d.info;
        let mut line = format!(
            "{{ \"sub\": {}, \"name\": {}, \"type\": {}, \"type_code\": {}, \"bit_len\": {}, \
             \"access\": \"{}\", \"unit\": \"{}\", \"default\": {}, \"min\": {}, \"max\": {}, \
             \"value\": ",
            e.sub,
            cli::json_str(&e.name),
            cli::json_str(&cli::type_name(e.data_type)),
            e.data_type,
            e.bit_len,
            cli::access_text(e.access),
            cli::unit_text(e.unit),
            opt(&e.default, e),
            opt(&e.min, e),
            opt(&e.max, e),
        );
        match &d.value {
            EntryValue::Value(v) => {
                line.push_str(&v.to_json());
                if let cli::Value::Enum { text: Some(t), .. } = v {
                    line.push_str(&format!(", \"value_text\": {}", cli::json_str(t)));
                }
            }
            EntryValue::WriteOnly => line.push_str("null"),
            EntryValue::Padding => line.push_str("null, \"padding\": true"),
            EntryValue::Error(s) => {
                line.push_str(&format!("null, \"error\": {}", cli::json_str(s)));
            }
        }
        line.push_str(" }");
        let comma = if i + 1 == entries.len() { "" } else { "," };
        writeln!(out, "      {line}{comma}")?;
    }
    writeln!(out, "    ]")?;
    writeln!(out, "  }}{}", if last { "" } else { "," })
}

/// RUN / ERR LED patterns of the first slave (manual 4.1).
fn leds(bus: &VirtualBus) -> String {
    let chain = lock(&bus.chain);
    match chain.slaves().first() {
        Some(s) => {
            let (run, err) = s.led_patterns();
            format!("RUN {}, ERR {}", run.name(), err.name())
        }
        None => String::new(),
    }
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

/// `foe write`: BOOT, download with a progress bar, INIT, power cycle.
async fn foe_write(
    dev: &device_catalog::DeviceEntry,
    file: &std::path::Path,
    password: &str,
    name: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    let image = std::fs::read(file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    let password = u32::from_str_radix(password.trim_start_matches("0x"), 16)
        .map_err(|_| format!("--password must be hex, got '{password}'"))?;
    let layout = dev.description.layout();
    if !dev.description.mailbox.foe || !layout.has_boot() {
        return Err(format!(
            "{} offers no firmware update over FoE",
            dev.description.names.type_name
        )
        .into());
    }
    let bus = VirtualBus::line(dev.key, master_test::link::Clock::real())?;
    let md = &*bus.maindevice;
    let group = bus.init().await?;
    let station = group.subdevice(md, 0)?.configured_address();
    let before: heapless::String<32> = group.subdevice(md, 0)?.sdo_read(0x100A, 0).await?;
    println!("slave {station:#06x} runs firmware {before}; switching to BOOT");
    master_test::foe::enter_boot_with(md, station, &layout).await?;
    let mut client = MailboxClient::new(md, station, MailboxGeometry::bootstrap_of(&layout));
    let bar = indicatif::ProgressBar::new(image.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {bytes}/{total_bytes} {binary_bytes_per_sec}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let start = std::time::Instant::now();
    master_test::foe::write(&mut client, name, password, &image, |done, _| {
        bar.set_position(done as u64)
    })
    .await?;
    bar.finish();
    let secs = start.elapsed().as_secs_f64();
    println!(
        "downloaded {} bytes in {:.3} s ({:.1} MB/s)",
        image.len(),
        secs,
        image.len() as f64 / secs / 1e6
    );
    master_test::foe::request_state(md, station, 0x01).await?;
    println!("BOOT -> INIT: image pending for the bootloader; power cycle");
    let version = lock(&bus.chain).power_cycle(0).ok_or("no slave")?;
    println!("after the power cycle 0x100A SOFTWARE VERSION = {version}");
    Ok(())
}

/// `foe read`: a file from one slave in PRE-OP.
async fn foe_read(
    dev: &device_catalog::DeviceEntry,
    name: &str,
    output: Option<&std::path::Path>,
) -> Result<(), Box<dyn std::error::Error>> {
    let bus = VirtualBus::line(dev.key, master_test::link::Clock::real())?;
    let md = &*bus.maindevice;
    let group = bus.init().await?;
    let station = group.subdevice(md, 0)?.configured_address();
    let geometry = MailboxGeometry::of(&dev.description.layout());
    let mut client = MailboxClient::new(md, station, geometry);
    let data = master_test::foe::read(&mut client, name, 0).await?;
    match output {
        Some(p) => {
            std::fs::write(p, &data).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
            println!("{} bytes written to {}", data.len(), p.display());
        }
        None => print!("{}", String::from_utf8_lossy(&data)),
    }
    Ok(())
}

/// `firmware pack`: header with identity, revision range, version, CRC.
fn firmware_pack(
    dev: &device_catalog::DeviceEntry,
    binary: &std::path::Path,
    version: &str,
    output: &std::path::Path,
    revision_min: u32,
    revision_max: u32,
) -> Result<(), Box<dyn std::error::Error>> {
    use ecat_slave::firmware::{EFW_HEADER_LEN, EfwHeaderRepr, FirmwareVersion, pack};
    let payload =
        std::fs::read(binary).map_err(|e| format!("cannot read {}: {e}", binary.display()))?;
    let version = FirmwareVersion::new(version)
        .ok_or_else(|| format!("--version must be 1 to 16 ASCII characters, got '{version}'"))?;
    let header = EfwHeaderRepr {
        header_len: EFW_HEADER_LEN as u16,
        flags: 0,
        vendor_id: dev.description.identity.vendor_id,
        product_code: dev.description.identity.product_code,
        revision_min,
        revision_max,
        version,
        payload_len: 0,
        payload_crc: 0,
    };
    let mut out = vec![0u8; payload.len() + 1024];
    let n = pack(&header, &payload, &mut out).map_err(|e| format!("cannot pack: {e}"))?;
    std::fs::write(output, &out[..n])
        .map_err(|e| format!("cannot write {}: {e}", output.display()))?;
    println!(
        "{}: {} bytes ({} payload, version {}, revisions {revision_min}..={revision_max})",
        output.display(),
        n,
        payload.len(),
        version.as_str()
    );
    Ok(())
}
