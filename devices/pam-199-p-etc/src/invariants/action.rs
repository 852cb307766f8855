//! The master actions of the invariant model and their byte encoding.
//!
//! One [`Action`] is one thing a master (or the world around the slave:
//! the power supply, the PDI, the flash) does. The property test generates
//! actions with proptest strategies; the fuzz target decodes them from
//! bytes with [`decode`]; committed seeds are written with [`encode`].
//! `decode(&encode(a)) == a` for every action (tested), so a sequence the
//! property test shrinks can be replayed by the fuzz target and back.

use crate::description::od::DICT;

/// Most actions decoded from one input (a longer input is cut).
pub const MAX_ACTIONS: usize = 128;

/// Objects the decoder and the strategies pick most often: the PDO
/// assignment, the system objects, the outputs and a parameter.
pub const INTERESTING: &[u16] = &[
    0x1C12, 0x1C13, 0xF800, 0xF801, 0xF80F, 0x7000, 0x7010, 0x7020, 0x800D, 0x1600, 0x1C32,
];

/// PDO indices a value of [`Value::Pdo`] selects (0: none).
pub const PDOS: &[u16] = &[0x1600, 0x1601, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0];

/// Time jumps a [`Action::TimeJump`] picks from when decoded (ms): past
/// the SM watchdog, past the SAVE interval, minutes and hours.
pub const JUMPS_MS: &[u32] = &[150, 1_200, 600_000, 18_000_000];

/// AL state a master requests (the low nibble of AL control).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Request {
    /// INIT (1).
    Init,
    /// PRE-OP (2).
    PreOp,
    /// SAFE-OP (4).
    SafeOp,
    /// OP (8).
    Op,
    /// BOOT (3).
    Boot,
    /// Any other value of the low nibble (unknown states, 0).
    Raw(u8),
}

impl Request {
    /// The AL control state code.
    pub fn code(self) -> u16 {
        match self {
            Request::Init => 1,
            Request::PreOp => 2,
            Request::SafeOp => 4,
            Request::Op => 8,
            Request::Boot => 3,
            Request::Raw(v) => u16::from(v & 0x0F),
        }
    }
}

/// How a master configures a process-data SyncManager (SM2 or SM3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SmSetting {
    /// Disabled (all zero).
    Off,
    /// Enabled with the length of the image the assignment in the
    /// dictionary gives now (what a master computes after its uploads).
    Image,
    /// Enabled with the length of the default assignment (the SII's).
    Default,
    /// Enabled with this length (0 included: SOEM leaves unused SMs so).
    Len(u8),
}

/// The cyclic outputs a master sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Outputs {
    /// ENABLE bits (bit 0: 0x7000:01 DIR, bit 1: 0x7010:01, bit 2:
    /// 0x7020:01) and one command value for every COMMAND VALUE entry,
    /// packed as the assigned RxPDOs map them.
    Values {
        /// ENABLE bits.
        enable: u8,
        /// Command value (cut to each entry's bit length).
        command: i32,
    },
    /// Raw bytes (repeated to the SM2 length).
    Raw([u8; 4]),
}

/// A value an SDO download writes (encoded at the entry's size).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Value {
    /// 0.
    Zero,
    /// 1 (commands of 0xF801, ENABLE, DIR).
    One,
    /// 2 (FUNCTION = IND, a count of 2).
    Two,
    /// The entry's default.
    Default,
    /// The entry's minimum (or 0).
    Min,
    /// The entry's maximum (or all ones).
    Max,
    /// The vendor password ([`crate::VENDOR_PASSWORD`]).
    Password,
    /// A PDO index of [`PDOS`].
    Pdo(u8),
    /// Any 32-bit value.
    Raw(u32),
}

/// Where a PDI fault hits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PdiRegion {
    /// Every register and buffer.
    All,
    /// AL control / status (0x0120..0x0136).
    Al,
    /// The AL event request (0x0220).
    Events,
    /// The watchdog registers (0x0400..0x0450).
    Watchdog,
    /// The SyncManager registers (0x0800..0x0820).
    SyncManagers,
    /// The mailbox buffers.
    Mailbox,
    /// The output and input process data buffers.
    ProcessData,
}

impl PdiRegion {
    /// Every region, in decoding order.
    pub const ALL: [PdiRegion; 7] = [
        PdiRegion::All,
        PdiRegion::Al,
        PdiRegion::Events,
        PdiRegion::Watchdog,
        PdiRegion::SyncManagers,
        PdiRegion::Mailbox,
        PdiRegion::ProcessData,
    ];
}

/// A firmware image a master downloads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Image {
    /// A valid image of the next version.
    Good,
    /// A valid header whose payload has byte `at` (mod length) flipped:
    /// the CRC check must fail.
    Corrupt {
        /// Byte of the payload flipped.
        at: u16,
    },
    /// A valid image for another product.
    OtherProduct,
    /// A valid image older than the running one (anti-rollback).
    Old,
}

/// A solenoid of the power stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Coil {
    /// Solenoid A.
    A,
    /// Solenoid B.
    B,
}

/// What happens to the power stage (simulated faults).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StageEvent {
    /// A broken wire.
    OpenWire(Coil),
    /// A short circuit.
    Short(Coil),
    /// Supply voltage in V.
    Supply(u8),
    /// Stage temperature in °C.
    Temperature(u8),
    /// Every fault removed.
    Clear,
}

/// The bring-up targets of [`Action::BringUp`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Target {
    /// PRE-OP with the standard mailbox.
    PreOp,
    /// SAFE-OP with SM2/SM3 for the assigned image.
    SafeOp,
    /// OP with cyclic outputs (ENABLE set, a command value).
    Op,
    /// BOOT with the bootstrap mailbox (from INIT).
    Boot,
}

/// One thing a master or the slave's surroundings do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Action {
    /// What a master does to reach `target` from where the slave is:
    /// INIT, mailbox SMs, PRE-OP, SM2/SM3, SAFE-OP, cycles, OP.
    BringUp {
        /// Where to go.
        target: Target,
    },
    /// SM0/SM1 with the standard (`boot` false) or bootstrap mailbox.
    Mailbox {
        /// Bootstrap mailbox geometry.
        boot: bool,
    },
    /// SM2 and SM3 (process data).
    ProcessData {
        /// SM2 (outputs).
        sm2: SmSetting,
        /// SM3 (inputs).
        sm3: SmSetting,
    },
    /// An AL control write, then 5 ms of polling.
    Request {
        /// The state requested.
        state: Request,
        /// Error acknowledge (bit 4).
        ack: bool,
    },
    /// `count` process-data cycles 1 ms apart (SM2 written, SM3 read).
    Cycles {
        /// Cycles (at least 1).
        count: u8,
        /// The outputs of every cycle.
        outputs: Outputs,
    },
    /// No frames for `ms` milliseconds; the firmware runs every ms.
    Silence {
        /// Duration (capped at 500 ms: past the SM and PDI watchdogs).
        ms: u16,
    },
    /// The clock jumps `ms` ahead with no firmware pass in between.
    TimeJump {
        /// The jump.
        ms: u32,
    },
    /// The master writes the SM watchdog time 0x0420 (0 disables it).
    Watchdog {
        /// Watchdog time in base ticks (100 µs by default).
        time: u16,
    },
    /// An SDO download (expedited, normal or segmented as the size needs).
    Download {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// The value.
        value: Value,
        /// Complete access: the object is uploaded with complete access,
        /// the value's bytes written at this byte offset (mod the image
        /// length) and the image downloaded with complete access.
        complete: Option<u8>,
    },
    /// An SDO upload (complete access or not).
    Upload {
        /// Object index.
        index: u16,
        /// Subindex.
        sub: u8,
        /// Complete access.
        complete: bool,
    },
    /// Power off and on: ESC and firmware restart, the parameter
    /// EEPROM and the firmware store keep what they hold, the bootloader
    /// decides what runs.
    PowerCycle {
        /// The started image confirms itself (a new image on trial
        /// becomes the active one); without, it is rolled back after
        /// [`ecat_slave::firmware::MAX_BOOT_ATTEMPTS`] boots.
        confirm: bool,
    },
    /// SAVE (0xF801:02) with the power failing after `after` bytes of the
    /// EEPROM write, then a power cycle.
    CutSave {
        /// Bytes that reach the EEPROM.
        after: u16,
    },
    /// PDI accesses to `region` fail for `ms` milliseconds of polling.
    PdiFault {
        /// Where.
        region: PdiRegion,
        /// Reads fail.
        reads: bool,
        /// Writes fail.
        writes: bool,
        /// Duration.
        ms: u8,
    },
    /// The firmware stops serving the ESC for `ms` milliseconds.
    Stall {
        /// Duration (capped at 500 ms: past the SM and PDI watchdogs).
        ms: u16,
    },
    /// An FoE firmware download in BOOT: write request, data packets.
    Foe {
        /// The file.
        image: Image,
        /// The write request carries the right FoE password.
        password: bool,
        /// Stop after this many data packets (the master gives up).
        stop_after: Option<u8>,
        /// The power fails after this many bytes reach the flash (64-byte
        /// units), then the slave is power cycled.
        cut_after: Option<u16>,
    },
    /// The boot records become unreadable (a flash read fault) or
    /// readable again; the bootloader sees it at the next power cycle.
    BootRecords {
        /// Readable.
        readable: bool,
    },
    /// Simulated power-stage conditions.
    Stage(StageEvent),
    /// A byte of the parameter EEPROM flips (`xor`, made non-zero).
    CorruptNv {
        /// Byte (mod the EEPROM size).
        at: u16,
        /// Bits flipped.
        xor: u8,
    },
    /// Flash decay: bits of the inactive image slot clear (`mask` is
    /// ANDed in at byte `at`), e.g. after a download was verified.
    CorruptSlot {
        /// Byte (mod the slot's used length).
        at: u16,
        /// Bits kept.
        mask: u8,
    },
}

/// A little-endian byte reader that reads 0 past the end.
struct Reader<'a> {
    bytes: &'a [u8],
}

impl Reader<'_> {
    fn done(&self) -> bool {
        self.bytes.is_empty()
    }

    fn u8(&mut self) -> u8 {
        match self.bytes.split_first() {
            Some((b, rest)) => {
                self.bytes = rest;
                *b
            }
            None => 0,
        }
    }

    fn bool(&mut self) -> bool {
        self.u8() & 1 != 0
    }

    fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }

    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    fn option<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> Option<T> {
        if self.bool() { Some(f(self)) } else { None }
    }
}

/// Tags of the actions (the first byte of each, mod the count).
const TAGS: u8 = 20;

fn object_index(r: &mut Reader<'_>) -> u16 {
    let b = r.u8();
    let objects = DICT.objects();
    if b == 0xFF {
        return r.u16();
    }
    if b & 0x80 == 0 {
        let i = usize::from(b) % INTERESTING.len();
        return INTERESTING.get(i).copied().unwrap_or(0x1C12);
    }
    let i = usize::from(b & 0x7F) % objects.len().max(1);
    objects.get(i).map_or(0x1000, |o| o.index)
}

fn encode_object(index: u16, out: &mut Vec<u8>) {
    if let Some(p) = INTERESTING.iter().position(|i| *i == index) {
        out.push(p as u8);
    } else if let Some((p, _)) = DICT.find(index).filter(|(p, _)| *p < 0x7F) {
        out.push(0x80 | p as u8);
    } else {
        out.push(0xFF);
        out.extend_from_slice(&index.to_le_bytes());
    }
}

fn subindex(r: &mut Reader<'_>, index: u16) -> u8 {
    let b = r.u8();
    if b >= 0xF0 {
        return r.u8();
    }
    match DICT.find(index) {
        Some((_, o)) if !o.entries.is_empty() => o
            .entries
            .get(usize::from(b) % o.entries.len())
            .map_or(0, |e| e.sub),
        _ => b,
    }
}

fn encode_sub(index: u16, sub: u8, out: &mut Vec<u8>) {
    let pos = DICT
        .find(index)
        .and_then(|(_, o)| o.entries.iter().position(|e| e.sub == sub));
    match pos {
        Some(p) if p < 0xF0 => out.push(p as u8),
        None if DICT.find(index).is_none_or(|(_, o)| o.entries.is_empty()) && sub < 0xF0 => {
            out.push(sub)
        }
        _ => out.extend_from_slice(&[0xF0, sub]),
    }
}

fn value(r: &mut Reader<'_>) -> Value {
    match r.u8() % 9 {
        0 => Value::Zero,
        1 => Value::One,
        2 => Value::Two,
        3 => Value::Default,
        4 => Value::Min,
        5 => Value::Max,
        6 => Value::Password,
        7 => Value::Pdo(r.u8() % PDOS.len() as u8),
        _ => Value::Raw(r.u32()),
    }
}

fn encode_value(v: &Value, out: &mut Vec<u8>) {
    match v {
        Value::Zero => out.push(0),
        Value::One => out.push(1),
        Value::Two => out.push(2),
        Value::Default => out.push(3),
        Value::Min => out.push(4),
        Value::Max => out.push(5),
        Value::Password => out.push(6),
        Value::Pdo(p) => out.extend_from_slice(&[7, *p]),
        Value::Raw(x) => {
            out.push(8);
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
}

fn sm_setting(r: &mut Reader<'_>) -> SmSetting {
    match r.u8() % 4 {
        0 => SmSetting::Off,
        1 => SmSetting::Image,
        2 => SmSetting::Default,
        _ => SmSetting::Len(r.u8()),
    }
}

fn encode_sm(s: &SmSetting, out: &mut Vec<u8>) {
    match s {
        SmSetting::Off => out.push(0),
        SmSetting::Image => out.push(1),
        SmSetting::Default => out.push(2),
        SmSetting::Len(l) => out.extend_from_slice(&[3, *l]),
    }
}

fn coil(r: &mut Reader<'_>) -> Coil {
    if r.bool() { Coil::B } else { Coil::A }
}

fn encode_coil(c: &Coil) -> u8 {
    match c {
        Coil::A => 0,
        Coil::B => 1,
    }
}

fn one(r: &mut Reader<'_>) -> Action {
    match r.u8() % TAGS {
        0 | 1 => Action::BringUp {
            target: match r.u8() % 4 {
                0 => Target::PreOp,
                1 => Target::SafeOp,
                2 => Target::Op,
                _ => Target::Boot,
            },
        },
        2 => Action::Mailbox { boot: r.bool() },
        3 => Action::ProcessData {
            sm2: sm_setting(r),
            sm3: sm_setting(r),
        },
        4 => Action::Request {
            state: match r.u8() {
                b if b & 0x80 != 0 => Request::Raw(b & 0x0F),
                b => match b % 5 {
                    0 => Request::Init,
                    1 => Request::PreOp,
                    2 => Request::SafeOp,
                    3 => Request::Op,
                    _ => Request::Boot,
                },
            },
            ack: r.bool(),
        },
        5 | 6 => Action::Cycles {
            count: r.u8().max(1),
            outputs: if r.bool() {
                Outputs::Raw([r.u8(), r.u8(), r.u8(), r.u8()])
            } else {
                Outputs::Values {
                    enable: r.u8() & 0x07,
                    command: r.u32() as i32,
                }
            },
        },
        7 => Action::Silence { ms: r.u16() % 501 },
        8 => Action::TimeJump {
            ms: match r.u8() {
                0xFF => r.u32(),
                b => JUMPS_MS
                    .get(usize::from(b) % JUMPS_MS.len())
                    .copied()
                    .unwrap_or(150),
            },
        },
        9 => Action::Watchdog { time: r.u16() },
        10 | 11 => {
            let index = object_index(r);
            let sub = subindex(r, index);
            Action::Download {
                index,
                sub,
                value: value(r),
                complete: r.option(Reader::u8),
            }
        }
        12 => {
            let index = object_index(r);
            let sub = subindex(r, index);
            Action::Upload {
                index,
                sub,
                complete: r.bool(),
            }
        }
        13 => Action::PowerCycle { confirm: r.bool() },
        14 => Action::CutSave { after: r.u16() },
        15 => Action::PdiFault {
            region: PdiRegion::ALL
                .get(usize::from(r.u8()) % PdiRegion::ALL.len())
                .copied()
                .unwrap_or(PdiRegion::All),
            reads: r.bool(),
            writes: r.bool(),
            ms: r.u8(),
        },
        16 => Action::Stall { ms: r.u16() % 501 },
        17 => Action::Foe {
            image: match r.u8() % 4 {
                0 => Image::Good,
                1 => Image::Corrupt { at: r.u16() },
                2 => Image::OtherProduct,
                _ => Image::Old,
            },
            password: r.bool(),
            stop_after: r.option(Reader::u8),
            cut_after: r.option(Reader::u16),
        },
        18 => match r.u8() % 4 {
            0 => Action::BootRecords { readable: r.bool() },
            1 => Action::CorruptNv {
                at: r.u16(),
                xor: r.u8().max(1),
            },
            2 => Action::CorruptSlot {
                at: r.u16(),
                mask: r.u8(),
            },
            _ => Action::Stage(match r.u8() % 5 {
                0 => StageEvent::OpenWire(coil(r)),
                1 => StageEvent::Short(coil(r)),
                2 => StageEvent::Supply(r.u8()),
                3 => StageEvent::Temperature(r.u8()),
                _ => StageEvent::Clear,
            }),
        },
        _ => Action::BringUp { target: Target::Op },
    }
}

/// The actions a fuzz input stands for (at most [`MAX_ACTIONS`]). Every
/// byte string decodes; missing bytes read as 0.
pub fn decode(bytes: &[u8]) -> Vec<Action> {
    let mut r = Reader { bytes };
    let mut out = Vec::new();
    while !r.done() && out.len() < MAX_ACTIONS {
        out.push(one(&mut r));
    }
    out
}

/// The bytes [`decode`] turns back into `actions` (seeds; shrunk
/// property-test cases replayed by the fuzz target).
pub fn encode(actions: &[Action]) -> Vec<u8> {
    let mut out = Vec::new();
    for a in actions {
        encode_one(a, &mut out);
    }
    out
}

fn encode_one(a: &Action, out: &mut Vec<u8>) {
    match a {
        Action::BringUp { target } => out.extend_from_slice(&[
            0,
            match target {
                Target::PreOp => 0,
                Target::SafeOp => 1,
                Target::Op => 2,
                Target::Boot => 3,
            },
        ]),
        Action::Mailbox { boot } => out.extend_from_slice(&[2, u8::from(*boot)]),
        Action::ProcessData { sm2, sm3 } => {
            out.push(3);
            encode_sm(sm2, out);
            encode_sm(sm3, out);
        }
        Action::Request { state, ack } => {
            let b = match state {
                Request::Init => 0,
                Request::PreOp => 1,
                Request::SafeOp => 2,
                Request::Op => 3,
                Request::Boot => 4,
                Request::Raw(v) => 0x80 | (v & 0x0F),
            };
            out.extend_from_slice(&[4, b, u8::from(*ack)]);
        }
        Action::Cycles { count, outputs } => {
            out.extend_from_slice(&[5, *count]);
            match outputs {
                Outputs::Raw(b) => {
                    out.push(1);
                    out.extend_from_slice(b);
                }
                Outputs::Values { enable, command } => {
                    out.extend_from_slice(&[0, *enable]);
                    out.extend_from_slice(&command.to_le_bytes());
                }
            }
        }
        Action::Silence { ms } => {
            out.push(7);
            out.extend_from_slice(&ms.to_le_bytes());
        }
        Action::TimeJump { ms } => {
            out.push(8);
            match JUMPS_MS.iter().position(|j| j == ms) {
                Some(p) => out.push(p as u8),
                None => {
                    out.push(0xFF);
                    out.extend_from_slice(&ms.to_le_bytes());
                }
            }
        }
        Action::Watchdog { time } => {
            out.push(9);
            out.extend_from_slice(&time.to_le_bytes());
        }
        Action::Download {
            index,
            sub,
            value,
            complete,
        } => {
            out.push(10);
            encode_object(*index, out);
            encode_sub(*index, *sub, out);
            encode_value(value, out);
            match complete {
                Some(at) => out.extend_from_slice(&[1, *at]),
                None => out.push(0),
            }
        }
        Action::Upload {
            index,
            sub,
            complete,
        } => {
            out.push(12);
            encode_object(*index, out);
            encode_sub(*index, *sub, out);
            out.push(u8::from(*complete));
        }
        Action::PowerCycle { confirm } => out.extend_from_slice(&[13, u8::from(*confirm)]),
        Action::CutSave { after } => {
            out.push(14);
            out.extend_from_slice(&after.to_le_bytes());
        }
        Action::PdiFault {
            region,
            reads,
            writes,
            ms,
        } => {
            let r = PdiRegion::ALL.iter().position(|x| x == region).unwrap_or(0) as u8;
            out.extend_from_slice(&[15, r, u8::from(*reads), u8::from(*writes), *ms]);
        }
        Action::Stall { ms } => {
            out.push(16);
            out.extend_from_slice(&ms.to_le_bytes());
        }
        Action::Foe {
            image,
            password,
            stop_after,
            cut_after,
        } => {
            out.push(17);
            match image {
                Image::Good => out.push(0),
                Image::Corrupt { at } => {
                    out.push(1);
                    out.extend_from_slice(&at.to_le_bytes());
                }
                Image::OtherProduct => out.push(2),
                Image::Old => out.push(3),
            }
            out.push(u8::from(*password));
            match stop_after {
                Some(n) => out.extend_from_slice(&[1, *n]),
                None => out.push(0),
            }
            match cut_after {
                Some(n) => {
                    out.push(1);
                    out.extend_from_slice(&n.to_le_bytes());
                }
                None => out.push(0),
            }
        }
        Action::BootRecords { readable } => out.extend_from_slice(&[18, 0, u8::from(*readable)]),
        Action::CorruptNv { at, xor } => {
            out.extend_from_slice(&[18, 1]);
            out.extend_from_slice(&at.to_le_bytes());
            out.push(*xor);
        }
        Action::CorruptSlot { at, mask } => {
            out.extend_from_slice(&[18, 2]);
            out.extend_from_slice(&at.to_le_bytes());
            out.push(*mask);
        }
        Action::Stage(e) => {
            out.extend_from_slice(&[18, 3]);
            match e {
                StageEvent::OpenWire(c) => out.extend_from_slice(&[0, encode_coil(c)]),
                StageEvent::Short(c) => out.extend_from_slice(&[1, encode_coil(c)]),
                StageEvent::Supply(v) => out.extend_from_slice(&[2, *v]),
                StageEvent::Temperature(t) => out.extend_from_slice(&[3, *t]),
                StageEvent::Clear => out.push(4),
            }
        }
    }
}
