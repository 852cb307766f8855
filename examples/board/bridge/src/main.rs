//! `board-bridge --iface IF --socket PATH [--flash FILE]`
//!
//! Serves one IO8 slave on network interface IF whose firmware runs in
//! QEMU: the software ESC answers the master's EtherCAT frames at once
//! (one thread, a raw socket), and the firmware reaches the same ESC
//! through the LAN9252 emulation over QEMU's UART0, a Unix socket at PATH
//! that QEMU connects to (`-serial unix:PATH`). Each new connection is a
//! reset of the board: the chip powers on again. The flash the firmware
//! keeps its FoE images and parameters in is FILE (default: memory only).
//!
//! Stops on Ctrl-C / SIGTERM and prints what the chip counted.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use board_bridge::{Chip, FlashImage, answer};
use board_example::link::{ParseError, Request};
use clap::Parser;
use ecat_sim::raw::is_request;

/// Command line.
#[derive(Parser, Debug)]
#[command(
    version,
    about = "The host side of the emulated board (QEMU mps2-an386)"
)]
struct Args {
    /// Network interface the master is on.
    #[arg(long)]
    iface: String,
    /// Unix socket QEMU's UART0 connects to.
    #[arg(long)]
    socket: PathBuf,
    /// The board's flash image (FoE images, parameters); kept across runs.
    #[arg(long)]
    flash: Option<PathBuf>,
}

/// What both threads share.
struct Shared {
    chip: Chip,
    /// The connection to QEMU, for IRQ notices from the frame thread.
    qemu: Option<UnixStream>,
}

fn lock(s: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    s.lock().unwrap_or_else(|e| e.into_inner())
}

fn now_ns(start: Instant) -> u64 {
    u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX)
}

/// Tells QEMU that the IRQ output became asserted, if it did.
fn notify(shared: &mut Shared) {
    if let Some(n) = shared.chip.irq_notice()
        && let Some(q) = shared.qemu.as_mut()
    {
        let _ = q.write_all(&n);
    }
}

fn frames(
    iface: &str,
    shared: &Mutex<Shared>,
    stop: &AtomicBool,
    start: Instant,
) -> Result<u64, String> {
    let nic = pnet_datalink::interfaces()
        .into_iter()
        .find(|i| i.name == iface)
        .ok_or_else(|| format!("network interface '{iface}' does not exist"))?;
    let cfg = pnet_datalink::Config {
        read_timeout: Some(Duration::from_millis(1)),
        promiscuous: true,
        ..pnet_datalink::Config::default()
    };
    let (mut tx, mut rx) = match pnet_datalink::channel(&nic, cfg) {
        Ok(pnet_datalink::Channel::Ethernet(tx, rx)) => (tx, rx),
        Ok(_) => return Err(format!("{iface}: not an Ethernet channel")),
        Err(e) => {
            return Err(format!(
                "raw socket on {iface}: {e} (needs root or CAP_NET_RAW)"
            ));
        }
    };
    let mut answered = 0u64;
    let mut buf = Vec::with_capacity(1600);
    while !stop.load(Ordering::Acquire) {
        match rx.next() {
            Ok(f) if is_request(f) => {
                buf.clear();
                buf.extend_from_slice(f);
                {
                    let mut s = lock(shared);
                    let esc = s.chip.esc_mut();
                    esc.update_watchdogs(now_ns(start));
                    esc.process_frame(&mut buf);
                    notify(&mut s);
                }
                if let Some(Err(e)) = tx.send_to(&buf, None) {
                    return Err(format!("sending on {iface}: {e}"));
                }
                answered += 1;
            }
            Ok(_) => {}
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
                ) =>
            {
                // The ESC's watchdogs run on their own clock, frames or not.
                let mut s = lock(shared);
                s.chip.esc_mut().update_watchdogs(now_ns(start));
                notify(&mut s);
            }
            Err(e) => return Err(format!("receiving on {iface}: {e}")),
        }
    }
    Ok(answered)
}

/// Serves one QEMU run: requests until the connection closes.
fn serve(
    mut conn: UnixStream,
    shared: &Mutex<Shared>,
    flash: &mut FlashImage,
    stop: &AtomicBool,
    start: Instant,
) -> u64 {
    let _ = conn.set_read_timeout(Some(Duration::from_millis(100)));
    let mut inbox: Vec<u8> = Vec::with_capacity(4096);
    let mut out = Vec::with_capacity(4096);
    let mut chunk = [0u8; 4096];
    let mut requests = 0u64;
    while !stop.load(Ordering::Acquire) {
        match conn.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => inbox.extend_from_slice(&chunk[..n]),
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                ) =>
            {
                continue;
            }
            Err(_) => break,
        }
        loop {
            match Request::parse(&inbox) {
                Ok((req, used)) => {
                    out.clear();
                    {
                        let mut s = lock(shared);
                        answer(&req, now_ns(start), &mut s.chip, flash, &mut out);
                    }
                    if conn.write_all(&out).is_err() {
                        return requests;
                    }
                    requests += 1;
                    inbox.drain(..used);
                }
                Err(ParseError::Incomplete(_)) => break,
                Err(e) => {
                    eprintln!("board-bridge: dropping a byte the firmware sent: {e:?}");
                    inbox.remove(0);
                }
            }
        }
    }
    requests
}

fn run(args: Args) -> Result<(), String> {
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Release))
            .map_err(|e| format!("signal handler: {e}"))?;
    }
    let mut flash = match &args.flash {
        Some(p) => FlashImage::open(p).map_err(|e| format!("flash image {}: {e}", p.display()))?,
        None => FlashImage::in_memory(),
    };
    let _ = std::fs::remove_file(&args.socket);
    let listener = UnixListener::bind(&args.socket)
        .map_err(|e| format!("socket {}: {e}", args.socket.display()))?;
    listener
        .set_nonblocking(true)
        .map_err(|e| format!("socket: {e}"))?;
    let shared = Mutex::new(Shared {
        chip: Chip::new(&io8_example::DEVICE.sii_image()),
        qemu: None,
    });
    let start = Instant::now();
    eprintln!(
        "board-bridge: IO8 on an emulated LAN9252 on {}, waiting for QEMU on {}",
        args.iface,
        args.socket.display()
    );
    let result = std::thread::scope(|scope| {
        let frames = scope.spawn(|| frames(&args.iface, &shared, &stop, start));
        let mut runs = 0u32;
        while !stop.load(Ordering::Acquire) && !frames.is_finished() {
            let conn = match listener.accept() {
                Ok((c, _)) => c,
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    std::thread::sleep(Duration::from_millis(10));
                    continue;
                }
                Err(e) => {
                    stop.store(true, Ordering::Release);
                    return Err(format!("accept: {e}"));
                }
            };
            runs += 1;
            let _ = conn.set_nonblocking(false);
            {
                let mut s = lock(&shared);
                s.chip.reset();
                s.qemu = conn.try_clone().ok();
            }
            eprintln!("board-bridge: QEMU run {runs} connected (board reset)");
            let requests = serve(conn, &shared, &mut flash, &stop, start);
            let s = lock(&shared);
            let c = s.chip.emu().counters();
            eprintln!(
                "board-bridge: QEMU run {runs} ended after {requests} requests; SPI so far: {} transactions, {} protocol errors, {} refused accesses",
                c.transactions(),
                c.protocol_errors(),
                c.refused_accesses()
            );
        }
        stop.store(true, Ordering::Release);
        match frames.join() {
            Ok(Ok(n)) => {
                eprintln!("board-bridge: stopped after {n} frames");
                Ok(())
            }
            Ok(Err(e)) => Err(e),
            Err(_) => Err("the frame thread panicked".to_string()),
        }
    });
    let _ = std::fs::remove_file(&args.socket);
    result
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("board-bridge: {e}");
            ExitCode::FAILURE
        }
    }
}
