//! Answering a cyclic frame ahead: its reply worked out from the line's
//! state before it arrives, so the reply leaves without waiting for the
//! ESCs' work on state that a millisecond of other work pushed out of
//! the caches.
//!
//! A cyclic master sends the same frame every cycle: the same datagrams at
//! the same addresses, only the output data changes. What the line does to
//! such a frame depends on the slaves' state and the frame's data, and for
//! the datagrams of process data (logical reads and writes over buffered
//! SyncManagers, broadcast reads of the status registers) in a simple way:
//! every byte of the reply is either the master's byte or a byte of some
//! ESC's memory (copied in by a read window, ORed in by a broadcast read),
//! and the working counters depend on the configuration alone. The read
//! of the DC system time a master with Distributed Clocks adds to its
//! cycle (FRMW or ARMW of 0x0910) depends on the frame's time as well: the
//! reference clock is worked out ahead and read once that time is known
//! ([`Ahead::answer`] takes it). A runner
//! works that out with [`Chain::ahead`] once the firmware has run (the
//! state is in the caches then), answers the next frame of that shape with
//! [`Ahead::answer`] and then runs the ESCs on it as always
//! ([`Chain::process_frame_at`]): their reply is the same, byte for byte,
//! and every side effect (SyncManager buffers and events, DC port times,
//! watchdogs) happens as before.
//!
//! An [`Ahead`] answers correctly only while the line is unchanged since
//! it was worked out: the caller drops it whenever anything runs on the
//! line (a frame, the firmware, a link change).

use super::Chain;
use crate::esc::{SoftEsc, SystemTimeAhead};
use ecat_slave::wire::ecat::{Addressing, Command, Datagram, DatagramCursor, EcatFrame, FrameType};
use ecat_slave::wire::ethernet::{ETHERTYPE_ETHERCAT, EthernetFrame};
use std::ops::Range;

/// One datagram of the frame an [`Ahead`] answers.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Expected {
    /// Where it lies in the EtherCAT payload.
    range: Range<usize>,
    /// Its header but the index (command, address, length and flags).
    cmd: u8,
    address: u32,
    data_len: u16,
    /// What the line adds to ADP (position and broadcast commands) and
    /// to the working counter.
    adp_add: u16,
    wkc_add: u16,
    /// Its changes to the data: `ops[ops.start..ops.end]`.
    ops: Range<usize>,
    /// A read of the DC system time (FRMW, ARMW), read from the clock
    /// when the frame's time is known.
    time: Option<TimeRead>,
}

/// The DC system time a read-multiple-write takes from its reader: bytes
/// `skip..skip + len` of the little-endian time at the frame's passing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct TimeRead {
    clock: SystemTimeAhead,
    /// When the frame passes the reader's port 0, after it entered the
    /// line (its position × the hop delay).
    after_ns: u64,
    skip: usize,
    len: usize,
}

/// One change to a datagram's data: `len` bytes at `at`, from
/// `Ahead::bytes[src..]`, copied or ORed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Op {
    at: usize,
    len: usize,
    src: usize,
    or: bool,
}

/// A frame's reply worked out ahead ([`Chain::ahead`]); see the module
/// documentation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ahead {
    /// Length of the frame it answers, and of its EtherCAT payload.
    frame_len: usize,
    ecat_len: u16,
    datagrams: Vec<Expected>,
    ops: Vec<Op>,
    bytes: Vec<u8>,
}

impl Ahead {
    /// Turns `frame` (a request of the shape this was worked out for),
    /// entering the line at `now_ns` (the time [`Chain::process_frame_at`]
    /// then gets), into the line's reply in place and returns `true`;
    /// returns `false` for a frame of another shape (other length,
    /// commands, addresses), which may then be partly changed and must
    /// not be sent.
    pub fn answer(&self, frame: &mut [u8], now_ns: u64) -> bool {
        if frame.len() != self.frame_len {
            return false;
        }
        let Ok(mut eth) = EthernetFrame::new_checked(&mut *frame) else {
            return false;
        };
        if eth.ethertype() != ETHERTYPE_ETHERCAT {
            return false;
        }
        eth.mark_forwarded();
        let Ok(mut ecat) = EcatFrame::new_checked(eth.payload_mut()) else {
            return false;
        };
        if ecat.frame_type() != FrameType::Pdu || ecat.length() != self.ecat_len {
            return false;
        }
        let payload = ecat.payload_mut();
        let mut cursor = DatagramCursor::new();
        let mut expected = self.datagrams.iter();
        while let Some(Ok(range)) = cursor.next_range(payload) {
            let Some(e) = expected.next() else {
                return false;
            };
            if range != e.range {
                return false;
            }
            let Some(bytes) = payload.get_mut(range) else {
                return false;
            };
            let Ok(mut dg) = Datagram::new_checked(bytes) else {
                return false;
            };
            if u8::from(dg.command()) != e.cmd
                || dg.logical_address() != e.address
                || dg.data_len() != e.data_len
            {
                return false;
            }
            if e.adp_add != 0 {
                dg.set_adp(dg.adp().wrapping_add(e.adp_add));
            }
            if e.wkc_add != 0 {
                dg.set_wkc(dg.wkc().wrapping_add(e.wkc_add));
            }
            let data = dg.data_mut();
            if let Some(r) = e.time {
                let time = r.clock.at(now_ns.saturating_add(r.after_ns)).to_le_bytes();
                let (Some(dst), Some(src)) =
                    (data.get_mut(..r.len), time.get(r.skip..r.skip + r.len))
                else {
                    return false;
                };
                dst.copy_from_slice(src);
            }
            for op in self.ops.get(e.ops.clone()).unwrap_or_default() {
                let (Some(dst), Some(src)) = (
                    data.get_mut(op.at..op.at + op.len),
                    self.bytes.get(op.src..op.src + op.len),
                ) else {
                    return false;
                };
                if op.or {
                    for (d, s) in dst.iter_mut().zip(src) {
                        *d |= *s;
                    }
                } else {
                    dst.copy_from_slice(src);
                }
            }
        }
        // The same datagrams, no fewer.
        expected.next().is_none()
    }
}

impl Chain {
    /// The reply to frames of `request`'s shape, worked out now from the
    /// line's state ([`Ahead`]; valid until anything runs on the line), or
    /// `None` when the line's reply could depend on more than that: a
    /// datagram other than a logical read or write, a broadcast,
    /// configured-address or position read of the registers below 0x0200
    /// or one read of the DC system time by
    /// FRMW or ARMW (mailboxes, other DC registers, any other access to
    /// physical memory), a window the ESCs' general path takes, a write
    /// window over a read window, or indexes to rebuild first.
    pub fn ahead(&self, request: &[u8]) -> Option<Ahead> {
        let n = self.slaves.len();
        if n == 0 {
            return None;
        }
        let eth = EthernetFrame::new_checked(request).ok()?;
        if eth.ethertype() != ETHERTYPE_ETHERCAT {
            return None;
        }
        let ecat = EcatFrame::new_checked(eth.payload()).ok()?;
        if ecat.frame_type() != FrameType::Pdu {
            return None;
        }
        let mut ahead = Ahead {
            frame_len: request.len(),
            ecat_len: ecat.length(),
            datagrams: Vec::new(),
            ops: Vec::new(),
            bytes: Vec::new(),
        };
        let payload = ecat.payload();
        let mut cursor = DatagramCursor::new();
        let mut time_read = false;
        while let Some(next) = cursor.next_range(payload) {
            let range = next.ok()?;
            let dg = Datagram::new_checked(payload.get(range.clone())?).ok()?;
            let cmd = dg.command();
            let len = usize::from(dg.data_len());
            let first_op = ahead.ops.len();
            let (mut adp_add, mut wkc_add) = (0u16, 0u16);
            let mut time = None;
            match cmd {
                Command::Nop => {}
                Command::Lrd | Command::Lwr | Command::Lrw => {
                    let addr = dg.logical_address();
                    for i in self.logical_hits(addr, len)? {
                        let esc: &SoftEsc = self.slaves.get(i)?.esc();
                        let w = esc.logical_ahead(cmd, addr, len, |at, src| {
                            ahead.push(first_op, at, src, false);
                        })?;
                        wkc_add = wkc_add.wrapping_add(w);
                    }
                }
                Command::Brd => {
                    let mut mask = vec![0u8; len];
                    for s in &self.slaves {
                        if let Some(bytes) = s.esc().broadcast_read_ahead(dg.ado(), len)? {
                            for (m, b) in mask.iter_mut().zip(bytes) {
                                *m |= *b;
                            }
                            wkc_add = wkc_add.wrapping_add(1);
                        }
                    }
                    if mask.iter().any(|&b| b != 0) {
                        ahead.push(first_op, 0, &mask, true);
                    }
                }
                // A status register of one slave (ethercrab's `tx_rx`
                // reads each subdevice's AL status by FPRD): what the
                // line's address index reaches, in its order.
                Command::Fprd => {
                    let adp = dg.adp();
                    let mut k = self
                        .first_of
                        .get(usize::from(adp))
                        .map_or(usize::MAX, |&k| k as usize);
                    while let Some(&(a, i)) = self.addresses.get(k) {
                        if a != adp {
                            break;
                        }
                        let esc: &SoftEsc = self.slaves.get(i)?.esc();
                        ahead.push(first_op, 0, esc.register_read_ahead(dg.ado(), len)?, false);
                        wkc_add = wkc_add.wrapping_add(1);
                        k += 1;
                    }
                }
                Command::Aprd => {
                    let pos = usize::from(0u16.wrapping_sub(dg.adp()));
                    if let Some(s) = self.slaves.get(pos) {
                        ahead.push(
                            first_op,
                            0,
                            s.esc().register_read_ahead(dg.ado(), len)?,
                            false,
                        );
                        wkc_add = 1;
                    }
                }
                // The DC system time: the reader's time as the frame
                // passes it, every other ESC writes (its own drift
                // control, nothing the reply shows). One per frame: the
                // writes change the writers' clocks.
                Command::Frmw | Command::Armw if !time_read => {
                    time_read = true;
                    let (adp, ado) = (dg.adp(), dg.ado());
                    for (i, s) in self.slaves.iter().enumerate() {
                        let esc = s.esc();
                        let Some(clock) = esc.system_time_ahead(ado, len)? else {
                            continue;
                        };
                        wkc_add = wkc_add.wrapping_add(1);
                        let reads = if cmd == Command::Frmw {
                            esc.answers_to(adp)
                        } else {
                            adp.wrapping_add(i as u16) == 0
                        };
                        if reads {
                            if time.is_some() {
                                // Two readers: the later overwrites.
                                return None;
                            }
                            time = Some(TimeRead {
                                clock,
                                // The line's rule for when a frame
                                // passes port 0 ([`super::port_times`]),
                                // for a frame entering at 0.
                                after_ns: super::port_times(i, n, (0, self.hop_ns)).0,
                                skip: usize::from(ado)
                                    - usize::from(ecat_slave::esc::registers::DC_SYSTEM_TIME),
                                len,
                            });
                        }
                    }
                }
                _ => return None,
            }
            if matches!(
                cmd.addressing(),
                Addressing::Position | Addressing::Broadcast
            ) {
                adp_add = n as u16;
            }
            ahead.datagrams.push(Expected {
                range,
                cmd: u8::from(cmd),
                address: dg.logical_address(),
                data_len: dg.data_len(),
                adp_add,
                wkc_add,
                ops: first_op..ahead.ops.len(),
                time,
            });
        }
        Some(ahead)
    }

    /// The slaves a logical datagram `[addr, addr + len)` reaches, in
    /// line order (what the line's dispatch walks); `None` while the
    /// window index is stale.
    fn logical_hits(&self, addr: u32, len: usize) -> Option<Vec<usize>> {
        if self.windows_stale {
            return None;
        }
        let start = u64::from(addr);
        let end = start + len as u64;
        let lo = start.saturating_sub(self.widest);
        let first = self.windows.partition_point(|w| w.0 < lo);
        let mut hits: Vec<usize> = self
            .windows
            .get(first..)
            .unwrap_or_default()
            .iter()
            .take_while(|w| w.0 < end)
            .filter(|w| w.1 > start)
            .map(|w| w.2)
            .collect();
        hits.sort_unstable();
        hits.dedup();
        Some(hits)
    }
}

impl Ahead {
    /// Adds a change to the datagram being worked out (whose changes start
    /// at `ops[first]`); one that continues the datagram's last change
    /// (the next bytes, copied from the next bytes) extends it.
    fn push(&mut self, first: usize, at: usize, src: &[u8], or: bool) {
        let from = self.bytes.len();
        self.bytes.extend_from_slice(src);
        if self.ops.len() > first
            && let Some(last) = self.ops.last_mut()
            && !or
            && !last.or
            && last.at + last.len == at
            && last.src + last.len == from
        {
            last.len += src.len();
            return;
        }
        self.ops.push(Op {
            at,
            len: src.len(),
            src: from,
            or,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{fmmu, sm};
    use ecat_slave::esc::Esc;
    use ecat_slave::wire::builder::FrameBuilder;
    use proptest::prelude::*;

    /// Slaves of the test line.
    const N: u16 = 6;

    fn frame(datagrams: &[(Command, u32, Vec<u8>)]) -> Vec<u8> {
        let mut buf = vec![0u8; 1514];
        let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
        for (cmd, address, data) in datagrams {
            fb.push(*cmd, *address, data).unwrap();
        }
        let len = fb.finish();
        buf.truncate(len);
        buf
    }

    fn configured(address: u16, ado: u16) -> u32 {
        u32::from(address) | (u32::from(ado) << 16)
    }

    /// A line of 6 slaves as a master sets it up for process data: slave
    /// `i` at station 0x1000 + i, 4 output bytes at logical 8·i into SM2
    /// (buffered, 0x1100) and 4 input bytes at 8·i + 4 from SM3 (buffered,
    /// 0x1180), the image in line order; one cycle has run.
    fn pd_line() -> Chain {
        let mut line = crate::testing::line(usize::from(N));
        for i in 0..N {
            let pos = u32::from(0u16.wrapping_sub(i));
            let mut f = frame(&[
                (
                    Command::Apwr,
                    pos | (0x0010 << 16),
                    (0x1000 + i).to_le_bytes().to_vec(),
                ),
                (Command::Apwr, pos | (0x0810 << 16), sm(0x1100, 4, 0x64)),
                (Command::Apwr, pos | (0x0818 << 16), sm(0x1180, 4, 0x20)),
                (
                    Command::Apwr,
                    pos | (0x0600 << 16),
                    fmmu(u32::from(i) * 8, 4, 0x1100, 2),
                ),
                (
                    Command::Apwr,
                    pos | (0x0610 << 16),
                    fmmu(u32::from(i) * 8 + 4, 4, 0x1180, 1),
                ),
            ]);
            line.process_frame(&mut f);
        }
        // The first cycle: the line indexes the new windows as it runs it
        // (until then nothing is worked out ahead).
        assert_eq!(line.ahead(&cyclic(0)), None);
        line.process_frame(&mut cyclic(0));
        line
    }

    /// The inputs slave `i`'s firmware publishes.
    fn publish(line: &mut Chain, i: usize, inputs: &[u8]) {
        line.slaves_mut()[i]
            .esc_mut()
            .write(0x1180, inputs)
            .unwrap();
    }

    /// A cyclic frame: an LRW over the image and a BRD of AL status.
    fn cyclic(outputs: u8) -> Vec<u8> {
        frame(&[
            (Command::Lrw, 0, vec![outputs; 8 * usize::from(N)]),
            (Command::Brd, 0x0130 << 16, vec![0; 2]),
        ])
    }

    #[test]
    fn the_answer_ahead_of_a_cyclic_frame_is_the_lines_reply() {
        let mut line = pd_line();
        for i in 0..usize::from(N) {
            publish(&mut line, i, &[i as u8 + 1; 4]);
        }
        // Worked out from last cycle's frame, answering this cycle's.
        let ahead = line.ahead(&cyclic(0x11)).expect("a process-data frame");
        let request = cyclic(0x22);
        let mut answered = request.clone();
        assert!(ahead.answer(&mut answered, 0));
        let mut processed = request.clone();
        line.process_frame(&mut processed);
        assert_eq!(answered, processed);
        // What the master reads: every slave's inputs, its outputs as
        // sent, all slaves counted (LRW 3 each, BRD 1 each).
        let eth = EthernetFrame::new_checked(&answered[..]).unwrap();
        let ecat = EcatFrame::new_checked(eth.payload()).unwrap();
        let dgs: Vec<_> = ecat
            .datagrams()
            .map(|r| Datagram::new_checked(&ecat.payload()[r.unwrap()]).unwrap())
            .collect();
        for i in 0..usize::from(N) {
            assert_eq!(&dgs[0].data()[8 * i..8 * i + 4], &[0x22; 4]);
            assert_eq!(&dgs[0].data()[8 * i + 4..8 * i + 8], &[i as u8 + 1; 4]);
        }
        assert_eq!(dgs[0].wkc(), 3 * N);
        assert_eq!(dgs[1].wkc(), N);
        assert_eq!(dgs[1].adp(), N);
    }

    /// SOEM's and ethercrab's cyclic frame with Distributed Clocks: the
    /// process data and a FRMW of the reference clock's system time.
    fn cyclic_dc(outputs: u8, reference: u16) -> Vec<u8> {
        frame(&[
            (Command::Lrw, 0, vec![outputs; 8 * usize::from(N)]),
            (Command::Frmw, configured(reference, 0x0910), vec![0; 8]),
        ])
    }

    #[test]
    fn a_dc_time_read_is_answered_with_the_reference_clock_at_the_frames_time() {
        let mut line = pd_line();
        // The reference clock (slave 1) runs 100 ppm fast and has an
        // offset; every other slave writes the time into its own 0x0910.
        line.slaves_mut()[1].esc_mut().set_dc_oscillator(100_000);
        let offset = 7_000_000_000u64.to_le_bytes();
        let mut f = frame(&[(Command::Fpwr, configured(0x1001, 0x0920), offset.to_vec())]);
        line.process_frame_at(&mut f, 1_000_000);
        line.process_frame_at(&mut cyclic_dc(0, 0x1001), 2_000_000);
        for (t, outputs) in [(3_000_000u64, 0x33u8), (4_000_250, 0x44)] {
            let ahead = line.ahead(&cyclic_dc(0, 0x1001)).expect("answered ahead");
            let request = cyclic_dc(outputs, 0x1001);
            let mut answered = request.clone();
            assert!(ahead.answer(&mut answered, t));
            let mut processed = request.clone();
            line.process_frame_at(&mut processed, t);
            assert_eq!(answered, processed, "at {t} ns");
            let eth = EthernetFrame::new_checked(&answered[..]).unwrap();
            let ecat = EcatFrame::new_checked(eth.payload()).unwrap();
            let dc = ecat.datagrams().nth(1).unwrap().unwrap();
            let dc = Datagram::new_checked(&ecat.payload()[dc]).unwrap();
            // Slave 1 reads (one hop after the frame entered), the other
            // five write: all six count.
            let esc = line.slaves()[1].esc();
            let time = u64::from_le_bytes(dc.data().try_into().unwrap());
            assert_eq!(time, esc.dc_system_time(t + crate::chain::DEFAULT_HOP_NS));
            assert!(time > 7_000_000_000 + t);
            assert_eq!(dc.wkc(), N);
        }
        // An ARMW at position 0: the first slave reads.
        let armw = |b: u8| {
            frame(&[
                (Command::Lrw, 0, vec![b; 8 * usize::from(N)]),
                (Command::Armw, 0x0910 << 16, vec![0; 8]),
            ])
        };
        line.process_frame_at(&mut armw(0), 5_000_000);
        let ahead = line.ahead(&armw(0)).expect("answered ahead");
        let mut answered = armw(1);
        assert!(ahead.answer(&mut answered, 6_000_000));
        let mut processed = armw(1);
        line.process_frame_at(&mut processed, 6_000_000);
        assert_eq!(answered, processed);
        // A FRMW to an address nobody has: every slave writes, the data
        // stays the master's.
        line.process_frame_at(&mut cyclic_dc(0, 0x2000), 7_000_000);
        let ahead = line.ahead(&cyclic_dc(0, 0x2000)).expect("answered ahead");
        let mut answered = cyclic_dc(5, 0x2000);
        assert!(ahead.answer(&mut answered, 8_000_000));
        let mut processed = cyclic_dc(5, 0x2000);
        line.process_frame_at(&mut processed, 8_000_000);
        assert_eq!(answered, processed);
    }

    #[test]
    fn a_frame_of_another_shape_is_not_answered() {
        let line = pd_line();
        let ahead = line.ahead(&cyclic(0)).unwrap();
        let other_length = frame(&[(Command::Lrw, 0, vec![0; 40])]);
        let other_address = frame(&[
            (Command::Lrw, 8, vec![0; 8 * usize::from(N)]),
            (Command::Brd, 0x0130 << 16, vec![0; 2]),
        ]);
        let other_command = frame(&[
            (Command::Lrd, 0, vec![0; 8 * usize::from(N)]),
            (Command::Brd, 0x0130 << 16, vec![0; 2]),
        ]);
        let fewer = frame(&[(Command::Lrw, 0, vec![0; 8 * usize::from(N) + 12])]);
        for mut f in [other_length, other_address, other_command, fewer] {
            assert!(!ahead.answer(&mut f, 0));
        }
        assert!(!ahead.answer(&mut [0u8; 10], 0));
        assert!(!ahead.answer(&mut [], 0));
    }

    #[test]
    fn frames_whose_reply_depends_on_more_than_memory_are_not_worked_out() {
        let line = pd_line();
        let declined = [
            // DC registers other than a read-multiple-write of the
            // system time, or two of those (the writes of the first
            // change the writers' clocks).
            frame(&[(Command::Brd, 0x0910 << 16, vec![0; 8])]),
            frame(&[(Command::Frmw, configured(0x1000, 0x0918), vec![0; 8])]),
            frame(&[(Command::Frmw, configured(0x1000, 0x090c), vec![0; 8])]),
            frame(&[
                (Command::Frmw, configured(0x1000, 0x0910), vec![0; 8]),
                (Command::Frmw, configured(0x1001, 0x0910), vec![0; 8]),
            ]),
            // Event registers a SyncManager completion changes.
            frame(&[(Command::Brd, 0x0220 << 16, vec![0; 4])]),
            // Writes, physical reads with side effects.
            frame(&[(Command::Fpwr, configured(0x1000, 0x1100), vec![0; 4])]),
            frame(&[(Command::Fprd, configured(0x1000, 0x1180), vec![0; 4])]),
            frame(&[(Command::Fprd, configured(0x1000, 0x0220), vec![0; 4])]),
            frame(&[(Command::Aprd, 0xffff | (0x0210 << 16), vec![0; 4])]),
            // A window covered in part.
            frame(&[(Command::Lrw, 2, vec![0; 4])]),
        ];
        for f in &declined {
            assert_eq!(line.ahead(f), None, "{f:02x?}");
        }
        assert!(line.ahead(&[0u8; 20]).is_none());
        // A write window over a read window: the write would change what
        // the read returns.
        let mut overlapping = pd_line();
        let mut f = frame(&[(Command::Apwr, 0x0610 << 16, fmmu(4, 4, 0x1100, 1))]);
        overlapping.process_frame(&mut f);
        overlapping.process_frame(&mut cyclic(0));
        assert_eq!(overlapping.ahead(&cyclic(0)), None);
        let mut reads_back = pd_line();
        let mut f = frame(&[(Command::Apwr, 0x0620 << 16, fmmu(100, 4, 0x1100, 1))]);
        reads_back.process_frame(&mut f);
        reads_back.process_frame(&mut cyclic(0));
        assert_eq!(reads_back.ahead(&cyclic(0)), None);
        // A reconfigured FMMU: its window index is rebuilt by the next
        // logical frame first.
        let mut moved = pd_line();
        let mut f = frame(&[(Command::Apwr, 0x0600 << 16, fmmu(100, 4, 0x1100, 2))]);
        moved.process_frame(&mut f);
        assert_eq!(moved.ahead(&cyclic(0)), None);
    }

    /// One step of a line's life.
    #[derive(Debug, Clone)]
    enum Step {
        /// A cyclic frame: logical datagrams (command, start, length), an
        /// optional register read (BRD, FPRD or APRD, address, register,
        /// length), an optional read-multiple-write
        /// (FRMW or ARMW, address, register, length), the output data
        /// byte, the time since the last frame; the answer is worked out
        /// from a frame of the same shape with other data.
        Cyclic(
            Vec<(Command, u32, usize)>,
            Option<(Command, u16, u16, usize)>,
            Option<(Command, u16, u16, usize)>,
            u8,
            u64,
        ),
        /// A slave's DC oscillator runs fast or slow (ppb).
        Oscillator(usize, i64),
        /// A slave's firmware publishes inputs or writes elsewhere.
        Pdi(usize, u16, Vec<u8>),
        /// A master reconfigures a slave (FMMU or SyncManager registers,
        /// station address, process RAM) with any bytes.
        Write(u16, u16, Vec<u8>),
        /// A master maps an FMMU of a slave elsewhere: FMMU, logical
        /// start, length, physical start, kind (read, write, both).
        Remap(u16, u16, u32, u16, u16, u8),
        /// A master sets a SyncManager of a slave up anew: SyncManager,
        /// start, length, control byte.
        Resync(u16, u16, u16, u16, u8),
    }

    fn step() -> impl Strategy<Value = Step> {
        let logical = prop_oneof![Just(Command::Lrw), Just(Command::Lrd), Just(Command::Lwr)];
        prop_oneof![
            6 => (
                prop::collection::vec(
                    (
                        logical,
                        prop_oneof![Just(0u32), (0u32..7).prop_map(|k| 8 * k), 0u32..52],
                        prop_oneof![Just(48usize), Just(8), Just(16), 1usize..60],
                    ),
                    1..4,
                ),
                proptest::option::of((
                    prop_oneof![Just(Command::Brd), Just(Command::Fprd), Just(Command::Aprd)],
                    prop_oneof![
                        0x1000u16..0x1000 + N,
                        Just(0x2000),
                        (0..N).prop_map(|i| 0u16.wrapping_sub(i)),
                        any::<u16>(),
                    ],
                    prop_oneof![Just(0x0130u16), 0u16..0x0240],
                    1usize..9,
                )),
                proptest::option::of((
                    prop_oneof![Just(Command::Frmw), Just(Command::Armw)],
                    prop_oneof![0x1000u16..0x1000 + N, Just(0x2000), 0u16..2, Just(0xfffe)],
                    prop_oneof![Just(0x0910u16), 0x0908u16..0x0920],
                    prop_oneof![Just(8usize), Just(4), 1usize..9],
                )),
                any::<u8>(),
                prop_oneof![Just(1_000_000u64), 0u64..3_000_000],
            )
                .prop_map(|(l, b, dc, d, dt)| Step::Cyclic(l, b, dc, d, dt)),
            1 => (0..usize::from(N), -500_000i64..500_000)
                .prop_map(|(i, e)| Step::Oscillator(i, e)),
            3 => (0..usize::from(N), 0x1100u16..0x11a0, prop::collection::vec(any::<u8>(), 1..9))
                .prop_map(|(i, a, d)| Step::Pdi(i, a, d)),
            1 => (
                0..N,
                prop_oneof![
                    0x0600u16..0x0620,
                    0x0800u16..0x0820,
                    Just(0x0010u16),
                    0x1100u16..0x1190,
                    0x0900u16..0x0930,
                ],
                prop::collection::vec(any::<u8>(), 1..17),
            )
                .prop_map(|(i, a, d)| Step::Write(i, a, d)),
            1 => (
                0..N,
                0u16..3,
                prop_oneof![(0u32..6).prop_map(|k| 8 * k), (0u32..6).prop_map(|k| 8 * k + 4), 0u32..60],
                prop_oneof![Just(4u16), 1u16..9],
                prop_oneof![Just(0x1100u16), Just(0x1180), 0x10fcu16..0x1188, Just(0x0130)],
                1u8..4,
            )
                .prop_map(|(i, k, l, n, p, t)| Step::Remap(i, k, l, n, p, t)),
            1 => (
                0..N,
                2u16..4,
                prop_oneof![Just(0x1100u16), Just(0x1180), 0x10fcu16..0x1188],
                prop_oneof![Just(4u16), 1u16..9],
                prop_oneof![Just(0x64u8), Just(0x20), Just(0x26), Just(0x22), any::<u8>()],
            )
                .prop_map(|(i, k, a, n, c)| Step::Resync(i, k, a, n, c)),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Whenever a frame's answer can be worked out ahead, it is the
        /// line's reply to that frame, byte for byte, whatever the data
        /// and whatever the line went through.
        #[test]
        fn an_answer_ahead_equals_the_lines_reply(
            steps in prop::collection::vec(step(), 1..40),
        ) {
            let mut line = pd_line();
            let mut answered = 0;
            let mut now = 1_000_000u64;
            let first = Step::Cyclic(
                vec![(Command::Lrw, 0, 48)],
                Some((Command::Brd, 0, 0x0130, 2)),
                None,
                0,
                0,
            );
            for (k, step) in std::iter::once(first).chain(steps).enumerate() {
                match step {
                    Step::Cyclic(logical, brd, dc, data, dt) => {
                        now += dt;
                        let shape = |byte: u8| {
                            let mut dgs: Vec<_> = logical
                                .iter()
                                .map(|&(cmd, start, len)| (cmd, start, vec![byte; len]))
                                .collect();
                            if let Some((cmd, adp, ado, n)) = brd {
                                dgs.push((cmd, configured(adp, ado), vec![byte; n]));
                            }
                            if let Some((cmd, adp, ado, n)) = dc {
                                dgs.push((cmd, configured(adp, ado), vec![byte; n]));
                            }
                            frame(&dgs)
                        };
                        let ahead = line.ahead(&shape(data.wrapping_add(0x5a)));
                        let request = shape(data);
                        let mut processed = request.clone();
                        line.process_frame_at(&mut processed, now);
                        if let Some(ahead) = ahead {
                            let mut reply = request.clone();
                            prop_assert!(ahead.answer(&mut reply, now), "step {}", k);
                            prop_assert_eq!(&reply, &processed, "step {}", k);
                            answered += 1;
                        }
                    }
                    Step::Pdi(i, addr, data) => {
                        let _ = line.slaves_mut()[i].esc_mut().write(addr, &data);
                    }
                    Step::Oscillator(i, error_ppb) => {
                        line.slaves_mut()[i].esc_mut().set_dc_oscillator(error_ppb);
                    }
                    Step::Remap(i, k, logical, len, physical, kind) => {
                        let mut f = frame(&[(
                            Command::Fpwr,
                            configured(0x1000 + i, 0x0600 + 16 * k),
                            fmmu(logical, len, physical, kind),
                        )]);
                        line.process_frame(&mut f);
                    }
                    Step::Resync(i, k, start, len, control) => {
                        let mut f = frame(&[(
                            Command::Fpwr,
                            configured(0x1000 + i, 0x0800 + 8 * k),
                            sm(start, len, control),
                        )]);
                        line.process_frame(&mut f);
                    }
                    Step::Write(i, ado, data) => {
                        let mut f = frame(&[(Command::Fpwr, configured(0x1000 + i, ado), data)]);
                        let ahead = line.ahead(&f);
                        prop_assert_eq!(ahead, None);
                        line.process_frame(&mut f);
                    }
                }
            }
            // The first frame at least (the line as configured).
            prop_assert!(answered >= 1);
        }
    }
}
