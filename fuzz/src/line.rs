//! A line of software PAM slaves that the harness reaches only through
//! EtherCAT frames, as a master does.
//!
//! [`Line::bring_up`] does what ethercrab does at start-up: station
//! addresses 0x1000.. by position (APWR 0x0010), SyncManagers configured
//! from what the slave's SII says (read once through the EEPROM interface
//! 0x0502.. with frames, see [`SiiSetup`]), FMMUs for process data, and
//! AL control requests, checking AL status after each.

use std::ops::Range;
use std::sync::OnceLock;

use ecat_sim::chain::Chain;
use ecat_sim::esc::FrameOutcome;
use ecat_slave::sii::{PdoDirection, SiiReader};
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::ecat::{self, Command, Datagram};
use ecat_slave::wire::ethernet;

/// Source MAC of the frames the harness builds (a master's).
pub const MASTER_MAC: [u8; 6] = [0x10, 0x10, 0x10, 0x10, 0x10, 0x10];
/// Station address of the first slave (ethercrab's choice).
pub const FIRST_STATION: u16 = 0x1000;
/// Time between two frames (or two idle polls).
pub const STEP_NS: u64 = 1_000_000;
/// Largest frame the harness builds (EtherCAT header length is 11 bits).
pub const MAX_FRAME: usize = ethernet::HEADER_LEN + ecat::HEADER_LEN + ecat::MAX_LENGTH as usize;
/// Most data bytes one datagram of a harness frame carries (the frame's
/// 11-bit length less the datagram header and working counter).
pub const MAX_DATAGRAM_DATA: usize =
    ecat::MAX_LENGTH as usize - Datagram::<()>::HEADER_LEN - Datagram::<()>::WKC_LEN;

/// AL control register.
pub const AL_CONTROL: u16 = 0x0120;
/// AL status register.
pub const AL_STATUS: u16 = 0x0130;
/// AL status code register.
pub const AL_STATUS_CODE: u16 = 0x0134;
/// First SyncManager register.
pub const SM_BASE: u16 = 0x0800;
/// First FMMU register.
pub const FMMU_BASE: u16 = 0x0600;

/// Raw address field of a physical datagram.
pub const fn phys(adp: u16, ado: u16) -> u32 {
    (adp as u32) | ((ado as u32) << 16)
}

/// ADP that addresses position `pos` with auto-increment addressing.
pub fn position_adp(pos: usize) -> u16 {
    0u16.wrapping_sub(pos as u16)
}

/// An Ethernet frame of `(command, address, data)` datagrams and the byte
/// ranges of their data. `None` when they do not fit one frame.
pub fn build(dgs: &[(Command, u32, &[u8])]) -> Option<(Vec<u8>, Vec<Range<usize>>)> {
    let mut buf = vec![0u8; MAX_FRAME];
    let mut b = FrameBuilder::new(&mut buf, MASTER_MAC).ok()?;
    let mut ranges = Vec::with_capacity(dgs.len());
    for (cmd, addr, data) in dgs {
        ranges.push(b.push(*cmd, *addr, data).ok()?);
    }
    let len = b.finish();
    buf.truncate(len);
    Some((buf, ranges))
}

/// Working counter of the datagram whose data is `data` in `frame`.
pub fn wkc(frame: &[u8], data: &Range<usize>) -> u16 {
    match frame.get(data.end..data.end + 2) {
        Some(&[a, b]) => u16::from_le_bytes([a, b]),
        _ => 0,
    }
}

/// The states [`Line::bring_up`] reaches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// Power-on state (nothing sent).
    PowerOn,
    /// INIT with station addresses set.
    Init,
    /// PRE-OP (standard mailbox).
    PreOp,
    /// SAFE-OP (process data SyncManagers and FMMUs).
    SafeOp,
    /// OP (outputs valid).
    Op,
    /// BOOT (bootstrap mailbox).
    Boot,
}

impl Target {
    /// AL state code.
    pub const fn code(self) -> u16 {
        match self {
            Target::PowerOn | Target::Init => 1,
            Target::PreOp => 2,
            Target::SafeOp => 4,
            Target::Op => 8,
            Target::Boot => 3,
        }
    }
}

/// What the PAM's SII says about its SyncManagers, read once through the
/// ESC's EEPROM interface and decoded with [`SiiReader`].
#[derive(Debug, Clone)]
pub struct SiiSetup {
    /// The SII image as read through 0x0502/0x0508.
    pub image: Vec<u8>,
    /// Standard mailbox out (SM0): start, length.
    pub mbx_out: (u16, u16),
    /// Standard mailbox in (SM1).
    pub mbx_in: (u16, u16),
    /// Bootstrap mailbox out.
    pub boot_out: (u16, u16),
    /// Bootstrap mailbox in.
    pub boot_in: (u16, u16),
    /// Control bytes of SM0..SM3 (SyncM category).
    pub sm_control: [u8; 4],
    /// Enable bytes of SM0..SM3 (SyncM category).
    pub sm_enable: [u8; 4],
    /// Output process data (SM2): start, bytes of the default PDOs.
    pub pd_out: (u16, u16),
    /// Input process data (SM3).
    pub pd_in: (u16, u16),
}

impl SiiSetup {
    /// The PAM's setup (computed on first use).
    pub fn pam() -> &'static SiiSetup {
        static SETUP: OnceLock<SiiSetup> = OnceLock::new();
        SETUP.get_or_init(|| {
            let mut line = Line::pam(1);
            let image = line.read_sii(0);
            SiiSetup::from_image(image).expect("the PAM's SII describes its SyncManagers")
        })
    }

    fn from_image(image: Vec<u8>) -> Result<SiiSetup, String> {
        let r = SiiReader::new(&image).map_err(|e| e.to_string())?;
        let std = r.standard_mailbox();
        let boot = r.bootstrap_mailbox();
        let sms: Vec<_> = r.sync_managers().map_err(|e| e.to_string())?.collect();
        if sms.len() < 4 {
            return Err(format!("{} SyncManagers in the SII", sms.len()));
        }
        let mut sm_control = [0u8; 4];
        let mut sm_enable = [0u8; 4];
        for (i, sm) in sms.iter().take(4).enumerate() {
            sm_control[i] = sm.control;
            sm_enable[i] = sm.enable;
        }
        let bytes = |dir: PdoDirection, sm: u8| -> Result<u16, String> {
            let mut bits = 0u32;
            for p in r.pdos(dir).map_err(|e| e.to_string())? {
                let p = p.map_err(|e| e.to_string())?;
                if p.sm() == Some(sm) {
                    bits += p.bit_len();
                }
            }
            Ok(bits.div_ceil(8) as u16)
        };
        let pd_out = (sms[2].start, bytes(PdoDirection::Rx, 2)?);
        let pd_in = (sms[3].start, bytes(PdoDirection::Tx, 3)?);
        Ok(SiiSetup {
            mbx_out: (std.rx_offset, std.rx_size),
            mbx_in: (std.tx_offset, std.tx_size),
            boot_out: (boot.rx_offset, boot.rx_size),
            boot_in: (boot.tx_offset, boot.tx_size),
            sm_control,
            sm_enable,
            pd_out,
            pd_in,
            image,
        })
    }

    /// The 8 SyncManager register bytes for SM `n` at `area`.
    pub fn sm_bytes(&self, n: usize, area: (u16, u16)) -> [u8; 8] {
        let mut b = [0u8; 8];
        b[0..2].copy_from_slice(&area.0.to_le_bytes());
        b[2..4].copy_from_slice(&area.1.to_le_bytes());
        b[4] = self.sm_control[n];
        b[6] = self.sm_enable[n] & 0x01 | 0x01;
        b
    }

    /// Bytes of one slave's part of the logical process image.
    pub fn stride(&self) -> u32 {
        u32::from(self.pd_out.1) + u32::from(self.pd_in.1)
    }
}

/// How a [`Line`] passes frames: through [`Chain::process`] (the dispatch
/// path) or through every ESC in turn ([`Chain::process_serial`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    /// [`Chain::process`].
    Dispatch,
    /// [`Chain::process_serial`], then [`Chain::poll`].
    Serial,
}

/// A line of PAM slaves reached through frames only.
pub struct Line {
    /// The slaves.
    pub chain: Chain,
    /// Number of slaves.
    pub n: usize,
    /// Time of the last frame or poll.
    pub now_ns: u64,
    /// How frames pass.
    pub path: Path,
}

impl Line {
    /// `n` PAMs in their power-on state.
    pub fn pam(n: usize) -> Self {
        Line {
            chain: Chain::of(n, pam_199_p_etc::Pam::default),
            n,
            now_ns: 0,
            path: Path::Dispatch,
        }
    }

    /// [`Line::pam`] passing frames through every ESC in turn.
    pub fn pam_serial(n: usize) -> Self {
        Line {
            path: Path::Serial,
            ..Line::pam(n)
        }
    }

    /// One frame through the line; then the firmware runs (the clock
    /// advances by [`STEP_NS`]).
    pub fn exchange(&mut self, frame: &mut [u8]) -> FrameOutcome {
        self.now_ns += STEP_NS;
        match self.path {
            Path::Dispatch => {
                // Where the line works out an answer ahead (what the
                // runner sends before the ESCs run), it is the line's
                // reply to the frame, byte for byte.
                let ahead = self.chain.ahead(frame).map(|a| {
                    let mut reply = frame.to_vec();
                    (a.answer(&mut reply, self.now_ns), reply)
                });
                let outcome = self.chain.process_frame_at(frame, self.now_ns);
                if let Some((answered, reply)) = ahead {
                    assert!(answered, "the answer ahead refused its own frame");
                    assert_eq!(
                        reply.as_slice(),
                        &*frame,
                        "the answer ahead differs from the line's reply"
                    );
                }
                let _ = self.chain.service(self.now_ns);
                outcome
            }
            Path::Serial => {
                let outcome = self.chain.process_serial_at(frame, self.now_ns);
                let _ = self.chain.poll(self.now_ns);
                outcome
            }
        }
    }

    /// Polls the firmware `steps` times, [`STEP_NS`] apart.
    pub fn idle(&mut self, steps: u32) {
        for _ in 0..steps {
            self.now_ns += STEP_NS;
            let _ = self.chain.poll(self.now_ns);
        }
    }

    /// Sends the datagrams in one frame; returns the answered frame and the
    /// data ranges. Panics when they do not fit a frame (harness bug).
    pub fn send(&mut self, dgs: &[(Command, u32, &[u8])]) -> (Vec<u8>, Vec<Range<usize>>) {
        let (mut f, r) = build(dgs).expect("harness datagrams fit one frame");
        self.exchange(&mut f);
        (f, r)
    }

    /// One datagram; (data, working counter).
    pub fn one(&mut self, cmd: Command, addr: u32, data: &[u8]) -> (Vec<u8>, u16) {
        let (f, r) = self.send(&[(cmd, addr, data)]);
        (f[r[0].clone()].to_vec(), wkc(&f, &r[0]))
    }

    /// APRD of a `u16` register of the slave at `pos`; `None` when the
    /// working counter is not 1.
    pub fn aprd_u16(&mut self, pos: usize, ado: u16) -> Option<u16> {
        let (d, w) = self.one(Command::Aprd, phys(position_adp(pos), ado), &[0, 0]);
        (w == 1).then(|| u16::from_le_bytes([d[0], d[1]]))
    }

    /// FPRD of `len` bytes; `None` when the working counter is not 1.
    pub fn fprd(&mut self, station: u16, ado: u16, len: usize) -> Option<Vec<u8>> {
        let (d, w) = self.one(Command::Fprd, phys(station, ado), &vec![0; len]);
        (w == 1).then_some(d)
    }

    /// FPWR; whether the working counter is 1.
    pub fn fpwr(&mut self, station: u16, ado: u16, data: &[u8]) -> bool {
        self.one(Command::Fpwr, phys(station, ado), data).1 == 1
    }

    /// Station address of position `pos` after [`Line::bring_up`].
    pub fn station(pos: usize) -> u16 {
        FIRST_STATION + pos as u16
    }

    /// Reads the whole SII EEPROM of the slave at `pos` through the EEPROM
    /// interface (8-byte reads, read command in 0x0502, data in 0x0508).
    pub fn read_sii(&mut self, pos: usize) -> Vec<u8> {
        let adp = position_adp(pos);
        let mut image = Vec::with_capacity(ecat_sim::esc::SII_SIZE);
        for word in (0..ecat_sim::esc::SII_SIZE / 2).step_by(4) {
            let [lo, hi] = (word as u16).to_le_bytes();
            let (f, r) = self.send(&[
                (
                    Command::Apwr,
                    phys(adp, 0x0502),
                    &[0x00, 0x01, lo, hi, 0, 0],
                ),
                (Command::Aprd, phys(adp, 0x0508), &[0; 8]),
            ]);
            image.extend_from_slice(&f[r[1].clone()]);
        }
        image
    }

    /// One LRW over every slave's process image (zero outputs); returns
    /// the working counter.
    pub fn lrw_cycle(&mut self) -> u16 {
        let s = SiiSetup::pam();
        let len = s.stride() as usize * self.n;
        if len == 0 {
            return 0;
        }
        let (_, w) = self.one(Command::Lrw, 0, &vec![0; len]);
        w
    }

    /// Requests `state` from every slave and waits (up to 10 polls) until
    /// every AL status shows it without the error bit.
    fn request(&mut self, state: u16) -> Result<(), String> {
        let ctl = state.to_le_bytes();
        let dgs: Vec<(Command, u32, &[u8])> = (0..self.n)
            .map(|i| (Command::Fpwr, phys(Self::station(i), AL_CONTROL), &ctl[..]))
            .collect();
        self.send(&dgs);
        for _ in 0..10 {
            let mut ok = true;
            for i in 0..self.n {
                let st = self.aprd_u16(i, AL_STATUS);
                ok &= st == Some(state);
            }
            if ok {
                return Ok(());
            }
        }
        let got: Vec<_> = (0..self.n)
            .map(|i| {
                (
                    self.aprd_u16(i, AL_STATUS),
                    self.aprd_u16(i, AL_STATUS_CODE),
                )
            })
            .collect();
        Err(format!(
            "state {state:#x} not reached: (status, code) {got:x?}"
        ))
    }

    /// Brings every slave to `target` through frames only.
    pub fn bring_up(&mut self, target: Target) -> Result<(), String> {
        if target == Target::PowerOn {
            return Ok(());
        }
        let s = SiiSetup::pam();
        let stations: Vec<[u8; 2]> = (0..self.n)
            .map(|i| Self::station(i).to_le_bytes())
            .collect();
        let dgs: Vec<(Command, u32, &[u8])> = (0..self.n)
            .map(|i| {
                (
                    Command::Apwr,
                    phys(position_adp(i), 0x0010),
                    &stations[i][..],
                )
            })
            .collect();
        self.send(&dgs);
        match target {
            Target::PowerOn | Target::Init => Ok(()),
            Target::Boot => {
                let (sm0, sm1) = (s.sm_bytes(0, s.boot_out), s.sm_bytes(1, s.boot_in));
                for i in 0..self.n {
                    let st = Self::station(i);
                    self.send(&[
                        (Command::Fpwr, phys(st, SM_BASE), &sm0),
                        (Command::Fpwr, phys(st, SM_BASE + 8), &sm1),
                    ]);
                }
                self.request(0x03)
            }
            Target::PreOp | Target::SafeOp | Target::Op => {
                let (sm0, sm1) = (s.sm_bytes(0, s.mbx_out), s.sm_bytes(1, s.mbx_in));
                for i in 0..self.n {
                    let st = Self::station(i);
                    self.send(&[
                        (Command::Fpwr, phys(st, SM_BASE), &sm0),
                        (Command::Fpwr, phys(st, SM_BASE + 8), &sm1),
                    ]);
                }
                self.request(0x02)?;
                if target == Target::PreOp {
                    return Ok(());
                }
                let (sm2, sm3) = (s.sm_bytes(2, s.pd_out), s.sm_bytes(3, s.pd_in));
                for i in 0..self.n {
                    let st = Self::station(i);
                    let base = s.stride() * i as u32;
                    let fmmu = |logical: u32, (start, len): (u16, u16), ty: u8| {
                        let mut f = [0u8; 16];
                        f[0..4].copy_from_slice(&logical.to_le_bytes());
                        f[4..6].copy_from_slice(&len.to_le_bytes());
                        f[7] = 7;
                        f[8..10].copy_from_slice(&start.to_le_bytes());
                        f[11] = ty;
                        f[12] = 1;
                        f
                    };
                    let f0 = fmmu(base, s.pd_out, 2);
                    let f1 = fmmu(base + u32::from(s.pd_out.1), s.pd_in, 1);
                    self.send(&[
                        (Command::Fpwr, phys(st, SM_BASE + 16), &sm2),
                        (Command::Fpwr, phys(st, SM_BASE + 24), &sm3),
                        (Command::Fpwr, phys(st, FMMU_BASE), &f0),
                        (Command::Fpwr, phys(st, FMMU_BASE + 16), &f1),
                    ]);
                }
                self.request(0x04)?;
                if target == Target::SafeOp {
                    return Ok(());
                }
                self.lrw_cycle();
                self.request(0x08)
            }
        }
    }
}
