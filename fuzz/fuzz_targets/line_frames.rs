//! Whole EtherCAT frames into a line of 1 or 3 software PAM slaves.
//!
//! Input: one header byte, then records (see `ecat_fuzz::records`):
//!
//! - header bit 0: 3 slaves (else 1); bits 1..=2: the state the line is
//!   brought to first through frames (power-on, INIT with station
//!   addresses, PRE-OP, SAFE-OP); bit 3: differential mode, a second line
//!   takes every frame through each ESC in turn (`Chain::process_serial`)
//!   and must answer every frame identically to the dispatching line.
//! - record tags (mod 6): 0 a raw Ethernet frame as is; 1 a raw frame with
//!   EtherType 0x88A4 and an EtherCAT header length that fits (the
//!   datagram headers inside may lie); 2 a structured frame (`arbitrary`):
//!   datagrams aimed at the registers that matter, then lies about its
//!   headers; 3 idle time (the firmware polls); 4 a corrupted frame or a
//!   lost link on port 0; 5 like 0.
//!
//! Each frame passes the line and the firmware runs after it. Invariants:
//! no panic; every frame's wire headers round-trip (parse -> emit ->
//! parse); after the input every slave still answers an APRD of AL status
//! (0x0130) with working counter 1 and a valid state, and a BRD of it is
//! answered by all of them (no frame makes a slave unreachable; position
//! and broadcast addressing do not depend on anything a frame can change).
#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use ecat_fuzz::line::{self, Line, Target, phys, position_adp};
use ecat_fuzz::records::Records;
use ecat_fuzz::roundtrip;
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::ecat::{Command, Datagram};
use libfuzzer_sys::fuzz_target;

/// Most records taken from one input.
const MAX_RECORDS: usize = 48;

/// ADP of a structured datagram.
#[derive(Arbitrary, Debug)]
enum Adp {
    /// Auto-increment: position 0..=3 (3 is past a 3-slave line).
    Position(u8),
    /// Configured: 0x1000 + n.
    Station(u8),
    /// Any value.
    Raw(u16),
}

/// ADO of a structured datagram: the registers a master writes, or any.
#[derive(Arbitrary, Debug)]
enum Ado {
    /// 0x0000 type .. 0x0013 alias.
    Identity(u8),
    /// DL control / status 0x0100..0x0111.
    Dl(u8),
    /// AL control 0x0120, status 0x0130, status code 0x0134.
    Al(u8),
    /// Event mask / request 0x0200..0x0223.
    Events(u8),
    /// Error counters 0x0300..0x0313.
    Errors(u8),
    /// Watchdogs 0x0400..0x0443.
    Watchdog(u8),
    /// SII EEPROM interface 0x0500..0x050F.
    Sii(u8),
    /// FMMU `n`, offset.
    Fmmu(u8, u8),
    /// SyncManager `n`, offset.
    Sm(u8, u8),
    /// Process RAM 0x1000.. (mailboxes and process data).
    Ram(u16),
    /// Any address.
    Raw(u16),
}

impl Ado {
    fn value(&self) -> u16 {
        match *self {
            Ado::Identity(o) => u16::from(o % 0x14),
            Ado::Dl(o) => 0x0100 + u16::from(o % 0x12),
            Ado::Al(o) => [0x0120, 0x0121, 0x0130, 0x0134][usize::from(o % 4)],
            Ado::Events(o) => 0x0200 + u16::from(o % 0x24),
            Ado::Errors(o) => 0x0300 + u16::from(o % 0x14),
            Ado::Watchdog(o) => 0x0400 + u16::from(o % 0x44),
            Ado::Sii(o) => 0x0500 + u16::from(o % 0x10),
            Ado::Fmmu(n, o) => 0x0600 + 16 * u16::from(n % 8) + u16::from(o % 16),
            Ado::Sm(n, o) => 0x0800 + 8 * u16::from(n % 8) + u16::from(o % 8),
            Ado::Ram(o) => 0x1000 + o % 0x2000,
            Ado::Raw(a) => a,
        }
    }
}

/// One structured datagram.
#[derive(Arbitrary, Debug)]
struct DgSpec {
    command: u8,
    adp: Adp,
    ado: Ado,
    /// Logical address for LRD/LWR/LRW (small values hit the FMMUs).
    logical: u16,
    data: Vec<u8>,
    /// Extra zero bytes after `data` (reads of larger areas).
    zeros: u8,
}

/// A lie about a header of the built frame.
#[derive(Arbitrary, Debug)]
enum Lie {
    /// Datagram `i`'s 16-bit length field (with flags).
    DatagramLen(u8, u16),
    /// Datagram `i`'s "more follows" bit.
    MoreFollows(u8, bool),
    /// Datagram `i`'s working counter.
    Wkc(u8, u16),
    /// The EtherCAT header (length and type).
    EcatHeader(u16),
    /// The EtherType.
    EtherType(u16),
    /// Cut the frame to this length.
    Truncate(u16),
    /// Append bytes.
    Extend(Vec<u8>),
}

#[derive(Arbitrary, Debug)]
struct StructuredFrame {
    datagrams: Vec<DgSpec>,
    lies: Vec<Lie>,
}

impl StructuredFrame {
    fn bytes(&self) -> Vec<u8> {
        let mut buf = vec![0u8; line::MAX_FRAME];
        let Ok(mut b) = FrameBuilder::new(&mut buf, line::MASTER_MAC) else {
            return vec![];
        };
        let mut starts = vec![];
        for d in self.datagrams.iter().take(16) {
            let cmd = Command::from(d.command % 16);
            let address = match cmd {
                Command::Lrd | Command::Lwr | Command::Lrw => u32::from(d.logical),
                _ => {
                    let adp = match d.adp {
                        Adp::Position(p) => position_adp(usize::from(p % 4)),
                        Adp::Station(s) => line::FIRST_STATION + u16::from(s % 4),
                        Adp::Raw(a) => a,
                    };
                    phys(adp, d.ado.value())
                }
            };
            let mut data = d.data.clone();
            data.truncate(1400);
            data.resize(data.len() + usize::from(d.zeros), 0);
            match b.push(cmd, address, &data) {
                Ok(r) => starts.push(r.start - Datagram::<()>::HEADER_LEN),
                Err(_) => break,
            }
        }
        let len = b.finish();
        buf.truncate(len);
        for lie in self.lies.iter().take(4) {
            let at = |i: u8| starts.get(usize::from(i) % starts.len().max(1)).copied();
            match lie {
                Lie::DatagramLen(i, v) => {
                    if let Some(s) = at(*i) {
                        put(&mut buf, s + 6, &v.to_le_bytes());
                    }
                }
                Lie::MoreFollows(i, set) => {
                    if let Some(b) = at(*i).and_then(|s| buf.get_mut(s + 7)) {
                        *b = if *set { *b | 0x80 } else { *b & 0x7F };
                    }
                }
                Lie::Wkc(i, w) => {
                    if let Some(s) = at(*i)
                        && let Some(&[lo, hi]) = buf.get(s + 6..s + 8)
                    {
                        let n = usize::from(u16::from_le_bytes([lo, hi]) & 0x7FF);
                        put(&mut buf, s + 10 + n, &w.to_le_bytes());
                    }
                }
                Lie::EcatHeader(v) => put(&mut buf, 14, &v.to_le_bytes()),
                Lie::EtherType(v) => put(&mut buf, 12, &v.to_be_bytes()),
                Lie::Truncate(n) => buf.truncate(usize::from(*n)),
                Lie::Extend(v) => buf.extend_from_slice(&v[..v.len().min(256)]),
            }
        }
        buf
    }
}

/// Writes `bytes` at `at` if the frame (maybe cut by an earlier lie) holds
/// them.
fn put(buf: &mut [u8], at: usize, bytes: &[u8]) {
    if let Some(dst) = buf.get_mut(at..at + bytes.len()) {
        dst.copy_from_slice(bytes);
    }
}

/// A raw frame made to look like EtherCAT: EtherType 0x88A4 and a header
/// length that fits the frame.
fn plausible(body: &[u8]) -> Vec<u8> {
    let mut f = body.to_vec();
    if f.len() < 16 {
        f.resize(16, 0);
    }
    f[12] = 0x88;
    f[13] = 0xA4;
    let len = (f.len() - 16).min(0x7FF) as u16;
    // Frame type 1 (DLPDU).
    f[14..16].copy_from_slice(&(len | 0x1000).to_le_bytes());
    f
}

struct Lines {
    main: Line,
    /// Differential mode: the serial reference line.
    reference: Option<Line>,
}

impl Lines {
    fn frame(&mut self, mut f: Vec<u8>) {
        roundtrip::ethernet_frame(&f);
        let mut g = self.reference.as_ref().map(|_| f.clone());
        let outcome = self.main.exchange(&mut f);
        roundtrip::ethernet_frame(&f);
        if let (Some(r), Some(g)) = (self.reference.as_mut(), g.as_mut()) {
            let expected = r.exchange(g);
            assert_eq!(outcome, expected, "dispatch and serial outcomes differ");
            assert!(
                f == *g,
                "dispatch and serial answers differ:\n dispatch {f:02x?}\n serial   {g:02x?}"
            );
        }
    }

    fn each(&mut self, mut op: impl FnMut(&mut Line)) {
        op(&mut self.main);
        if let Some(r) = self.reference.as_mut() {
            op(r);
        }
    }
}

/// The register area of every slave (APRD 0x0000..0x1000: no side
/// effects on the ECAT side).
fn registers(line: &mut Line) -> Vec<Vec<u8>> {
    (0..line.n)
        .map(|pos| {
            let mut regs = Vec::with_capacity(0x1000);
            for start in (0..0x1000u16).step_by(0x400) {
                let (d, w) = line.one(Command::Aprd, phys(position_adp(pos), start), &[0; 0x400]);
                assert_eq!(
                    w, 1,
                    "register read of slave {pos} at {start:#06x} not answered"
                );
                regs.extend_from_slice(&d);
            }
            regs
        })
        .collect()
}

fn run(data: &[u8]) {
    let Some((&header, rest)) = data.split_first() else {
        return;
    };
    let n = if header & 1 != 0 { 3 } else { 1 };
    let target = [Target::PowerOn, Target::Init, Target::PreOp, Target::SafeOp]
        [usize::from((header >> 1) & 3)];
    let mut lines = Lines {
        main: Line::pam(n),
        reference: (header & 0x08 != 0).then(|| Line::pam_serial(n)),
    };
    lines.each(|l| l.bring_up(target).expect("bring-up"));

    for (tag, body) in Records::new(rest).take(MAX_RECORDS) {
        match tag % 6 {
            1 => lines.frame(plausible(body)),
            2 => {
                let mut u = Unstructured::new(body);
                if let Ok(s) = StructuredFrame::arbitrary(&mut u) {
                    lines.frame(s.bytes());
                }
            }
            3 => {
                let steps = u32::from(body.first().copied().unwrap_or(1)) % 64 + 1;
                lines.each(|l| l.idle(steps));
            }
            4 => {
                let lost = body.first().is_some_and(|b| b & 1 != 0);
                lines.each(|l| {
                    if lost {
                        l.chain.link_lost();
                    } else {
                        l.chain.corrupted_frame();
                    }
                });
            }
            _ => lines.frame(body.to_vec()),
        }
    }

    // Differential mode: the same memory (compared first, while both lines
    // have seen the same frames at the same times).
    if let Some(reference) = lines.reference.as_mut() {
        let a = registers(&mut lines.main);
        let b = registers(reference);
        for (pos, (a, b)) in a.iter().zip(&b).enumerate() {
            if let Some(at) = a.iter().zip(b).position(|(x, y)| x != y) {
                panic!(
                    "slave {pos}: registers differ from {at:#06x} between dispatch and serial: {:02x?} vs {:02x?}",
                    &a[at..(at + 16).min(a.len())],
                    &b[at..(at + 16).min(b.len())]
                );
            }
        }
    }
    // Every slave still answers by position and by broadcast.
    let main = &mut lines.main;
    for pos in 0..n {
        let st = main.aprd_u16(pos, line::AL_STATUS);
        let Some(st) = st else {
            panic!("slave {pos} no longer answers APRD of AL status");
        };
        assert!(
            matches!(st & 0x0F, 1 | 2 | 3 | 4 | 8),
            "slave {pos}: AL status {st:#06x} is no state"
        );
    }
    let (_, w) = main.one(Command::Brd, phys(0, line::AL_STATUS), &[0, 0]);
    assert_eq!(
        usize::from(w),
        n,
        "BRD of AL status answered by {w} of {n} slaves"
    );
}

fuzz_target!(|data: &[u8]| run(data));
