//! The replay oracle: a capture of real devices answering a real master
//! (pcapng, as Wireshark writes it), replayed against a line of twins of
//! the same devices. Every master frame goes through the line as it went
//! through the real one, at the capture's time; each datagram of the
//! line's answer is compared with the real devices' answer, data bytes and
//! working counter. What differs is counted by class (the part of the ESC
//! or the protocol it concerns), with the first example of each.
//!
//! A frame is the master's when the locally administered bit of its source
//! MAC is clear (an ESC sets it as the frame passes, ETG.1000.4 5.1; the
//! captures of ethercrab's repository show 10:10:.. and 12:10:..); its
//! answer is the next frame with the bit set. Frames of other EtherTypes
//! are skipped.

use std::collections::BTreeMap;

use ecat_sim::chain::Chain;
use ecat_slave::wire::ecat::{Command, Datagram, EcatFrame};
use ecat_slave::wire::ethernet::{ETHERTYPE_ETHERCAT, EthernetFrame};

/// Why a capture cannot be replayed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The file is no pcapng capture.
    #[error("not a pcapng capture: {0}")]
    Pcap(String),
}

/// One exchange of the capture: the master's frame and the devices'
/// answer, at the time the master sent it (ns since the first frame).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Exchange {
    /// Number of the master's frame in the capture (1-based, as
    /// Wireshark counts every frame).
    pub number: usize,
    /// Time since the capture's first frame, ns.
    pub at_ns: u64,
    /// The master's frame.
    pub request: Vec<u8>,
    /// The devices' answer.
    pub reply: Vec<u8>,
}

/// The EtherCAT exchanges of a pcapng capture, in order. A master frame
/// without an answer (the last one of a capture cut short) is left out.
pub fn exchanges(pcapng: &[u8]) -> Result<Vec<Exchange>, ReplayError> {
    let mut reader = pcap_file::pcapng::PcapNgReader::new(pcapng)
        .map_err(|e| ReplayError::Pcap(e.to_string()))?;
    let mut frames: Vec<(usize, u64, Vec<u8>)> = Vec::new();
    let mut number = 0usize;
    let mut first: Option<u128> = None;
    // Timestamp units (pcapng `if_tsresol`, 10^-6 s when absent) per
    // interface; pcap-file hands over the raw count.
    let mut units: Vec<(u128, u128)> = Vec::new();
    while let Some(block) = reader.next_block() {
        let block = block.map_err(|e| ReplayError::Pcap(e.to_string()))?;
        let (ts, data) = match block {
            pcap_file::pcapng::Block::InterfaceDescription(i) => {
                // (multiply, divide) from the count to ns.
                let mut unit = (1000u128, 1u128);
                for o in &i.options {
                    if let pcap_file::pcapng::blocks::interface_description::InterfaceDescriptionOption::IfTsResol(r) = o {
                        let e = u32::from(r & 0x7F).min(60);
                        unit = if r & 0x80 == 0 {
                            if e <= 9 { (10u128.pow(9 - e), 1) } else { (1, 10u128.pow(e.min(30) - 9)) }
                        } else {
                            (1_000_000_000, 1u128 << e)
                        };
                    }
                }
                units.push(unit);
                continue;
            }
            pcap_file::pcapng::Block::EnhancedPacket(p) => {
                let (mul, div) = units
                    .get(p.interface_id as usize)
                    .copied()
                    .unwrap_or((1000, 1));
                (
                    p.timestamp.as_nanos().saturating_mul(mul) / div.max(1),
                    p.data.into_owned(),
                )
            }
            pcap_file::pcapng::Block::SimplePacket(p) => (first.unwrap_or(0), p.data.into_owned()),
            _ => continue,
        };
        number += 1;
        let t0 = *first.get_or_insert(ts);
        let at = u64::try_from(ts.saturating_sub(t0)).unwrap_or(u64::MAX);
        let Ok(eth) = EthernetFrame::new_checked(&data[..]) else {
            continue;
        };
        if eth.ethertype() != ETHERTYPE_ETHERCAT {
            continue;
        }
        frames.push((number, at, data));
    }
    // A reply belongs to the oldest request still open with the same
    // first datagram (command, index, ADO): a master may send several
    // frames before the first comes back, and a frame may be lost.
    let mut out = Vec::new();
    let mut open: Vec<(usize, u64, Vec<u8>)> = Vec::new();
    for (number, at, data) in frames {
        let processed = data.get(6).is_some_and(|b| b & 0x02 != 0);
        if !processed {
            open.push((number, at, data));
            continue;
        }
        let key = first_key(&data);
        if let Some(k) = open.iter().position(|(_, _, r)| first_key(r) == key) {
            let (n, t, request) = open.remove(k);
            out.push(Exchange {
                number: n,
                at_ns: t,
                request,
                reply: data,
            });
        }
    }
    out.sort_by_key(|x| x.number);
    Ok(out)
}

/// Command, index and ADO of a frame's first datagram (what pairs a reply
/// with its request).
fn first_key(frame: &[u8]) -> Option<(u8, u8, u16)> {
    let eth = EthernetFrame::new_checked(frame).ok()?;
    let ecat = EcatFrame::new_checked(eth.payload()).ok()?;
    let p = ecat.payload();
    let cmd = *p.first()?;
    let idx = *p.get(1)?;
    let ado = u16::from_le_bytes([*p.get(4)?, *p.get(5)?]);
    Some((cmd, idx, ado))
}

/// The EEPROM content a capture shows of the slave at configured station
/// address `station`: the data of every read the master made through the
/// EEPROM interface (FPWR of a read command and address to 0x0502, FPRD of
/// 0x0508), at its word address; words it never read are 0xFF. For a
/// device whose own SII dump is not at hand, this is the part of it the
/// master saw.
pub fn sii_from_capture(exchanges: &[Exchange], station: u16) -> Vec<u8> {
    let mut image: Vec<u8> = Vec::new();
    let mut address: Option<usize> = None;
    for x in exchanges {
        let (Some(request), Some(reply)) = (datagrams(&x.request), datagrams(&x.reply)) else {
            continue;
        };
        for (q, r) in request.iter().zip(&reply) {
            if q.1 != station || r.4 == 0 {
                continue;
            }
            match (q.0, q.2) {
                (Command::Fpwr, 0x0502) if q.3.len() >= 6 && q.3[1] & 0x07 == 1 => {
                    address = Some(u32::from_le_bytes([q.3[2], q.3[3], q.3[4], q.3[5]]) as usize);
                }
                (Command::Fpwr, 0x0504) if q.3.len() >= 4 => {
                    address = Some(u32::from_le_bytes([q.3[0], q.3[1], q.3[2], q.3[3]]) as usize);
                }
                (Command::Fprd, 0x0508) => {
                    if let Some(w) = address.take() {
                        let at = w.saturating_mul(2);
                        let end = at.saturating_add(r.3.len());
                        if end <= 0x1_0000 {
                            if image.len() < end {
                                image.resize(end, 0xFF);
                            }
                            image[at..end].copy_from_slice(&r.3);
                        }
                    }
                }
                _ => {}
            }
        }
    }
    image
}

/// What a datagram concerns: the classes differences are counted in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Class {
    /// ESC information 0x0000-0x000F: type, revision, build, FMMU and SM
    /// counts, RAM size, port descriptor, features (the silicon's identity).
    EscInformation,
    /// Station address and alias 0x0010-0x0013.
    Addressing,
    /// DL control, DL status and the ports 0x0100-0x011F.
    DataLink,
    /// AL control, status and status code 0x0120-0x013F.
    ApplicationLayer,
    /// PDI control and ESC configuration 0x0140-0x01FF.
    Pdi,
    /// Error counters 0x0300-0x03FF.
    ErrorCounters,
    /// Watchdogs 0x0400-0x04FF.
    Watchdogs,
    /// The SII EEPROM interface 0x0500-0x050F (its content and busy time).
    Eeprom,
    /// FMMUs 0x0600-0x06FF.
    Fmmu,
    /// SyncManagers 0x0800-0x08FF.
    SyncManager,
    /// Distributed Clocks 0x0900-0x09FF.
    DistributedClocks,
    /// Process RAM and mailboxes (0x1000 on).
    ProcessRam,
    /// Logical addressing (LRD, LWR, LRW): process data.
    ProcessData,
    /// Any other register.
    OtherRegister,
    /// The answer has another number or shape of datagrams.
    Frame,
}

impl Class {
    /// The class of a datagram of `command` at register `ado`.
    pub fn of(command: Command, ado: u16) -> Class {
        if matches!(command, Command::Lrd | Command::Lwr | Command::Lrw) {
            return Class::ProcessData;
        }
        match ado {
            0x0000..=0x000F => Class::EscInformation,
            0x0010..=0x0013 => Class::Addressing,
            0x0100..=0x011F => Class::DataLink,
            0x0120..=0x013F => Class::ApplicationLayer,
            0x0140..=0x01FF => Class::Pdi,
            0x0300..=0x03FF => Class::ErrorCounters,
            0x0400..=0x04FF => Class::Watchdogs,
            0x0500..=0x050F => Class::Eeprom,
            0x0600..=0x06FF => Class::Fmmu,
            0x0800..=0x08FF => Class::SyncManager,
            0x0900..=0x09FF => Class::DistributedClocks,
            0x1000..=0xFFFF => Class::ProcessRam,
            _ => Class::OtherRegister,
        }
    }

    /// The class in words.
    pub fn text(self) -> &'static str {
        match self {
            Class::EscInformation => "ESC information (0x0000-0x000F)",
            Class::Addressing => "station address and alias (0x0010-0x0013)",
            Class::DataLink => "DL control and status (0x0100-0x011F)",
            Class::ApplicationLayer => "AL control and status (0x0120-0x013F)",
            Class::Pdi => "PDI and ESC configuration (0x0140-0x01FF)",
            Class::ErrorCounters => "error counters (0x0300-0x03FF)",
            Class::Watchdogs => "watchdogs (0x0400-0x04FF)",
            Class::Eeprom => "SII EEPROM interface (0x0500-0x050F)",
            Class::Fmmu => "FMMUs (0x0600-0x06FF)",
            Class::SyncManager => "SyncManagers (0x0800-0x08FF)",
            Class::DistributedClocks => "Distributed Clocks (0x0900-0x09FF)",
            Class::ProcessRam => "process RAM and mailboxes (0x1000-)",
            Class::ProcessData => "process data (logical addressing)",
            Class::OtherRegister => "other registers",
            Class::Frame => "frame shape",
        }
    }
}

/// One differing datagram.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Difference {
    /// The master frame's number in the capture.
    pub frame: usize,
    /// The datagram's position in the frame.
    pub datagram: usize,
    /// Command, ADP and ADO of the master's datagram.
    pub command: Command,
    /// ADP.
    pub adp: u16,
    /// ADO.
    pub ado: u16,
    /// The twins' data and working counter.
    pub ours: (Vec<u8>, u16),
    /// The real devices' data and working counter.
    pub real: (Vec<u8>, u16),
}

impl std::fmt::Display for Difference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "frame {} datagram {}: {:?} {:#06x}:{:#06x}: twins {:02x?} wkc {}, real {:02x?} wkc {}",
            self.frame,
            self.datagram,
            self.command,
            self.adp,
            self.ado,
            self.ours.0,
            self.ours.1,
            self.real.0,
            self.real.1
        )
    }
}

/// The result of a replay.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// Datagrams compared.
    pub datagrams: usize,
    /// Datagrams whose data and working counter equal the real ones.
    pub identical: usize,
    /// Differing datagrams by class: count and the first example.
    pub classes: BTreeMap<Class, (usize, Difference)>,
    /// Every differing datagram, in capture order.
    pub differences: Vec<Difference>,
}

impl Report {
    /// Share of identical datagrams, 0..=1.
    pub fn rate(&self) -> f64 {
        if self.datagrams == 0 {
            0.0
        } else {
            self.identical as f64 / self.datagrams as f64
        }
    }

    /// The report as text: the rate, then each class with its count and
    /// first example.
    pub fn text(&self) -> String {
        let mut s = format!(
            "{} of {} datagrams as the real devices answered ({:.1} %)\n",
            self.identical,
            self.datagrams,
            100.0 * self.rate()
        );
        for (class, (n, first)) in &self.classes {
            s += &format!("  {n:5} {}: first {first}\n", class.text());
        }
        s
    }

    fn count(&mut self, class: Class, d: Difference) {
        self.differences.push(d.clone());
        self.classes
            .entry(class)
            .and_modify(|(n, _)| *n += 1)
            .or_insert((1, d));
    }
}

/// One datagram of a frame: command, ADP, ADO, data, working counter.
pub type DatagramParts = (Command, u16, u16, Vec<u8>, u16);

/// The datagrams of an Ethernet frame carrying EtherCAT; `None` for
/// anything else.
pub fn datagrams(frame: &[u8]) -> Option<Vec<DatagramParts>> {
    let eth = EthernetFrame::new_checked(frame).ok()?;
    let ecat = EcatFrame::new_checked(eth.payload()).ok()?;
    let mut out = Vec::new();
    for r in ecat.datagrams() {
        let r = r.ok()?;
        let d = Datagram::new_checked(ecat.payload().get(r)?).ok()?;
        out.push((d.command(), d.adp(), d.ado(), d.data().to_vec(), d.wkc()));
    }
    Some(out)
}

/// Brings `chain` into the state a capture that starts mid-session
/// assumes (TwinCAT's run-mode capture polls stations 0x03E9.. in PRE-OP
/// without configuring them): each slave gets its station address from
/// `stations` (APWR 0x0010, line order) and AL control `state`, through
/// frames as a master sends them, at time 0. These frames are not
/// compared.
pub fn prepare(chain: &mut Chain, stations: &[u16], state: u8) {
    let send = |chain: &mut Chain, command: Command, adp: u16, ado: u16, data: &[u8]| {
        let mut buf = vec![0u8; 64];
        if let Ok(mut b) = ecat_slave::wire::builder::FrameBuilder::new(&mut buf, [0x10; 6])
            && b.push(command, u32::from(ado) << 16 | u32::from(adp), data)
                .is_ok()
        {
            let n = b.finish();
            chain.process_frame_at(&mut buf[..n], 0);
            let _ = chain.service(0);
        }
    };
    for (k, station) in stations.iter().enumerate() {
        let position = 0u16.wrapping_sub(k as u16);
        send(
            chain,
            Command::Apwr,
            position,
            0x0010,
            &station.to_le_bytes(),
        );
    }
    for station in stations {
        send(chain, Command::Fpwr, *station, 0x0120, &[state, 0]);
    }
}

/// Replays `exchanges` against `chain` (the twins of the captured line, in
/// line order) and compares every answer with the real one.
pub fn replay(chain: &mut Chain, exchanges: &[Exchange]) -> Report {
    let mut report = Report::default();
    for x in exchanges {
        let mut frame = x.request.clone();
        chain.process_frame_at(&mut frame, x.at_ns);
        let _ = chain.service(x.at_ns);
        let (Some(request), Some(ours), Some(real)) = (
            datagrams(&x.request),
            datagrams(&frame),
            datagrams(&x.reply),
        ) else {
            continue;
        };
        if ours.len() != real.len() {
            report.datagrams += real.len();
            let (command, adp, ado) = request
                .first()
                .map_or((Command::Nop, 0, 0), |r| (r.0, r.1, r.2));
            report.count(
                Class::Frame,
                Difference {
                    frame: x.number,
                    datagram: 0,
                    command,
                    adp,
                    ado,
                    ours: (Vec::new(), ours.len() as u16),
                    real: (Vec::new(), real.len() as u16),
                },
            );
            continue;
        }
        for (k, ((req, o), r)) in request.iter().zip(&ours).zip(&real).enumerate() {
            report.datagrams += 1;
            if o.3 == r.3 && o.4 == r.4 {
                report.identical += 1;
                continue;
            }
            report.count(
                Class::of(req.0, req.2),
                Difference {
                    frame: x.number,
                    datagram: k,
                    command: req.0,
                    adp: req.1,
                    ado: req.2,
                    ours: (o.3.clone(), o.4),
                    real: (r.3.clone(), r.4),
                },
            );
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_follow_the_register_map() {
        assert_eq!(Class::of(Command::Fprd, 0x0008), Class::EscInformation);
        assert_eq!(Class::of(Command::Aprd, 0x0502), Class::Eeprom);
        assert_eq!(Class::of(Command::Brd, 0x0910), Class::DistributedClocks);
        assert_eq!(Class::of(Command::Lrw, 0x0000), Class::ProcessData);
        assert_eq!(Class::of(Command::Fpwr, 0x1000), Class::ProcessRam);
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        assert!(exchanges(&[]).is_err());
        assert!(exchanges(&[0x0A, 0x0D, 0x0D, 0x0A, 1, 2, 3]).is_err());
    }
}
