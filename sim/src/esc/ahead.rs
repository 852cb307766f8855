//! What a datagram would read from this ESC, worked out without reading:
//! the ESC's part of a line's answer ahead ([`crate::chain::Ahead`]).
//!
//! Only accesses whose result depends on nothing but the memory as it is
//! now, and which no other access of a process-data frame can change, are
//! worked out ahead; everything else returns `None` and the frame takes
//! the normal path.

use super::*;

/// Registers an answer ahead may read: those below the event registers
/// (ESC information, addresses, DL and AL control and status). Their ECAT
/// read has no side effect, and no logical access changes them (a
/// SyncManager's completion raises events at 0x0210 and 0x0220 and sets
/// the SyncManager status at 0x0805; the DC receive times and the error
/// counters lie above as well).
pub(crate) const QUIET_REGISTERS_END: u32 = 0x0200;

/// The DC system time register (0x0910-0x0917), which a cyclic master
/// with Distributed Clocks reads every cycle (FRMW or ARMW: the reference
/// clock reads, every other ESC writes its time into its own 0x0910).
const SYSTEM_TIME: u32 = reg::DC_SYSTEM_TIME as u32;

/// A read of the DC system time worked out ahead: the time depends on
/// when the frame passes the ESC, so what is worked out is the clock, and
/// the time is read from it once the frame's time is known
/// ([`SystemTimeAhead::at`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SystemTimeAhead {
    clock: dc::DcClock,
    /// The system time offset (0x0920).
    offset: u64,
    /// The ESC's last frame time: its clock never reads earlier.
    not_before: u64,
}

impl SystemTimeAhead {
    /// The system time this ESC's 0x0910 holds when a frame passes its
    /// port 0 at `port0_ns` (what [`SoftEsc::set_frame_times`] and the
    /// read then give).
    pub fn at(&self, port0_ns: u64) -> u64 {
        self.clock
            .local(port0_ns.max(self.not_before))
            .wrapping_add(self.offset)
    }
}

impl SoftEsc {
    /// What [`SoftEsc::process_data`] would do with a logical datagram
    /// (LRD, LWR, LRW) of `len` bytes at logical `addr`, without doing it:
    /// calls `read(offset, bytes)` for every window it would copy into the
    /// data, in the order it would (a later window over the same bytes
    /// wins), and returns the working counter increment. What it would
    /// write changes no data of the datagram.
    ///
    /// `None` when the answer could depend on more than the memory as it
    /// is now: a window the general path takes (bit-granular, read-write,
    /// over a mailbox SyncManager or the registers, or covered only in
    /// part), routes not worked out yet since the last reconfiguration, or
    /// any write window of this ESC overlapping any of its read windows in
    /// physical memory (a write earlier in the frame would change what a
    /// later read returns).
    pub fn logical_ahead(
        &self,
        cmd: Command,
        addr: u32,
        len: usize,
        mut read: impl FnMut(usize, &[u8]),
    ) -> Option<u16> {
        if self.fmmu_active == 0 || len == 0 {
            return Some(0);
        }
        if self.routes_stale || !self.fast_routes || self.writes_reach_reads() {
            return None;
        }
        let start = u64::from(addr);
        let end = start + len as u64;
        let (mut read_hit, mut write_hit) = (false, false);
        // As `logical`: writes first (they change no data), then reads.
        for pass_write in [true, false] {
            let mut bits = self.pass_fmmus(cmd, pass_write);
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let (Some(r), Some(f)) = (self.routes.get(i), self.fmmus.get(i)) else {
                    continue;
                };
                if f.logical_end() <= start || u64::from(f.logical) >= end {
                    continue;
                }
                let (r_start, r_end) = (
                    u64::from(r.logical),
                    u64::from(r.logical) + u64::from(r.len),
                );
                if !r.fast || r_start < start || r_end > end {
                    return None;
                }
                // What `route_transfer` decides.
                if !r.allowed {
                    continue;
                }
                let off = usize::try_from(r_start - start).ok()?;
                let (n, p) = (usize::from(r.len), usize::from(r.physical));
                if off + n > len {
                    continue;
                }
                let Some(mem) = self.mem.get(p..p + n) else {
                    continue;
                };
                if pass_write {
                    write_hit = true;
                } else {
                    read(off, mem);
                    read_hit = true;
                }
            }
        }
        Some(fmmu::logical_wkc(cmd, read_hit, write_hit))
    }

    /// Whether some enabled writing FMMU of this ESC maps physical memory
    /// that some enabled reading FMMU maps too (a read-write FMMU always).
    fn writes_reach_reads(&self) -> bool {
        let span = |f: &FmmuConfig| {
            let a = u32::from(f.physical);
            // A bit-granular window may reach one byte further.
            (a, a + u32::from(f.len) + 1)
        };
        let mut writes = self.fmmu_writes;
        while writes != 0 {
            let w = writes.trailing_zeros() as usize;
            writes &= writes - 1;
            let Some((wa, wb)) = self.fmmus.get(w).map(span) else {
                continue;
            };
            let mut reads = self.fmmu_reads;
            while reads != 0 {
                let r = reads.trailing_zeros() as usize;
                reads &= reads - 1;
                if let Some((ra, rb)) = self.fmmus.get(r).map(span)
                    && ra < wb
                    && wa < rb
                {
                    return true;
                }
            }
        }
        false
    }

    /// What a broadcast read (BRD) of `len` bytes at `ado` would OR into
    /// the data, worked out without reading: `Some(Some(bytes))` (the
    /// working counter counts this ESC), `Some(None)` (the ESC does not
    /// implement those registers: no answer), or `None` beyond the
    /// registers that may be read ahead (those below 0x0200).
    pub fn broadcast_read_ahead(&self, ado: u16, len: usize) -> Option<Option<&[u8]>> {
        let a = u32::from(ado);
        let b = a + u32::try_from(len).ok()?;
        if b > QUIET_REGISTERS_END {
            return None;
        }
        // What `ecat_read_checked` decides for these registers: no DC
        // register, no SyncManager, all within the modelled memory.
        if !self.silicon.implements(a, b) {
            return Some(None);
        }
        self.mem.get(a as usize..b as usize).map(Some)
    }

    /// What a physical read with copy (FPRD, APRD) of `len` bytes at `ado`
    /// addressed to this ESC would copy into the data (always counted:
    /// the plain copy of `ecat_read` for the registers below the FMMUs),
    /// or `None` beyond the registers that may be read ahead (those below
    /// 0x0200).
    pub fn register_read_ahead(&self, ado: u16, len: usize) -> Option<&[u8]> {
        let a = usize::from(ado);
        let b = a.checked_add(len)?;
        if b > QUIET_REGISTERS_END as usize {
            return None;
        }
        self.mem.get(a..b)
    }

    /// For a read-multiple-write (FRMW, ARMW) of `len` bytes at `ado`,
    /// worked out without doing it: `Some(Some(clock))` when the access
    /// lies within the DC system time (0x0910-0x0917) and this ESC
    /// implements it (a read gives the time at the frame's passing, a
    /// write is accepted; either counts once), `Some(None)` when it does
    /// not implement it (no read, no write, no count), `None` for any
    /// other registers.
    pub fn system_time_ahead(&self, ado: u16, len: usize) -> Option<Option<SystemTimeAhead>> {
        let a = u32::from(ado);
        let b = a + u32::try_from(len).ok()?;
        if len == 0 || a < SYSTEM_TIME || b > SYSTEM_TIME + 8 {
            return None;
        }
        // What `ecat_read_checked` and `ecat_write` decide for these
        // registers: no SyncManager lies over them, and a write is taken
        // as a received time (`dc_receive`) and counted.
        if !self.silicon.implements(a, b) {
            return Some(None);
        }
        Some(Some(SystemTimeAhead {
            clock: self.dc,
            offset: self.mem_u64(reg::DC_SYSTEM_TIME_OFFSET),
            not_before: self.dc_port0_ns,
        }))
    }

    /// Whether a configured-address datagram to `adp` addresses this ESC
    /// (its station address or, when set, its alias).
    pub(crate) fn answers_to(&self, adp: u16) -> bool {
        adp == self.station || (self.alias != 0 && adp == self.alias)
    }
}
