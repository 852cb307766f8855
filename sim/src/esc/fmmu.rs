//! FMMUs: their cached configuration and logical addressing, byte-aligned and
//! bit-granular (ETG.1000.4 FMMU attributes, 0x0600-0x06FF).

use super::*;

/// Cached configuration of one FMMU.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct FmmuConfig {
    pub(super) logical: u32,
    pub(super) len: u16,
    pub(super) start_bit: u8,
    pub(super) stop_bit: u8,
    pub(super) physical: u16,
    pub(super) physical_bit: u8,
    pub(super) read: bool,
    pub(super) write: bool,
    pub(super) enabled: bool,
}

/// How one FMMU's whole window moves when a datagram covers all of it,
/// worked out once per configuration of the FMMUs and SyncManagers.
///
/// For a byte-aligned window in process RAM whose SyncManagers are all
/// buffered (or none), the SyncManager rules of [`SoftEsc::ecat_read`] and
/// [`SoftEsc::ecat_write`] depend on the addresses alone: whether the
/// access happens and which buffers it completes is the same every cycle.
/// Only a mailbox SyncManager (full or empty) makes them depend on state;
/// such a window, a bit-granular one, one reaching the registers or one
/// that a datagram covers only in part takes the general path.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct FmmuRoute {
    /// Whether this shortcut applies to the FMMU.
    pub(super) fast: bool,
    /// Whether the access happens (a buffered SyncManager of the other
    /// direction refuses a write).
    pub(super) allowed: bool,
    /// Whether the FMMU writes (else it reads).
    pub(super) write: bool,
    /// SyncManagers whose last byte the window covers (bit n = SM n).
    pub(super) complete: u8,
    /// The window: logical start, length, physical start (12 bytes a
    /// route, so the routes of an ESC share two cache lines).
    pub(super) logical: u32,
    pub(super) len: u16,
    pub(super) physical: u16,
}

impl FmmuRoute {
    /// The logical window `[start, end)`.
    fn window(&self) -> (u64, u64) {
        let start = u64::from(self.logical);
        (start, start + u64::from(self.len))
    }
}

impl FmmuConfig {
    /// Logical range in bytes [start, end).
    pub(super) fn logical_end(&self) -> u64 {
        u64::from(self.logical) + u64::from(self.len)
    }
    pub(super) fn byte_aligned(&self) -> bool {
        self.start_bit == 0 && self.stop_bit == 7 && self.physical_bit == 0
    }
}

/// The working counter increment of a logical command that read
/// (`read_hit`) or wrote (`write_hit`) through some FMMU: LRW +1 for a
/// read and +2 for a write, LRD and LWR +1.
#[inline]
pub(super) fn logical_wkc(cmd: Command, read_hit: bool, write_hit: bool) -> u16 {
    match cmd {
        Command::Lrw => u16::from(read_hit) + 2 * u16::from(write_hit),
        _ => u16::from(read_hit || write_hit),
    }
}

impl SoftEsc {
    /// Changes whenever the FMMU configuration may have changed (a write
    /// to the FMMU registers, a power-on), so a line can cache which slave
    /// a logical address reaches ([`SoftEsc::logical_windows`]).
    pub fn fmmu_generation(&self) -> u32 {
        self.fmmu_gen
    }

    /// The logical byte windows `[start, end)` of the enabled FMMUs: a
    /// logical datagram outside all of them leaves this ESC untouched.
    pub fn logical_windows(&self) -> impl Iterator<Item = (u64, u64)> + '_ {
        self.fmmus
            .iter()
            .enumerate()
            .filter(|(n, _)| self.fmmu_active & (1 << n) != 0)
            .map(|(_, f)| (u64::from(f.logical), f.logical_end()))
    }

    /// Works out every enabled FMMU's [`FmmuRoute`] for the current FMMU
    /// and SyncManager configuration.
    pub(super) fn reroute(&mut self) {
        self.routes_stale = false;
        for n in 0..FMMU_COUNT {
            let route = match self.fmmus.get(n) {
                Some(f) if self.fmmu_active & (1 << n) != 0 => self.route_of(f),
                _ => FmmuRoute::default(),
            };
            if let Some(slot) = self.routes.get_mut(n) {
                *slot = route;
            }
        }
    }

    /// The route of one FMMU: what [`SoftEsc::ecat_write`] (write FMMU) or
    /// [`SoftEsc::ecat_read`] (read FMMU) would decide for its whole
    /// physical window, when that decision does not depend on state.
    fn route_of(&self, f: &FmmuConfig) -> FmmuRoute {
        let slow = FmmuRoute::default();
        let a = u32::from(f.physical);
        let b = a + u32::from(f.len);
        // One direction per FMMU (a read-write FMMU takes both passes of
        // `logical` with the same window: the general path).
        if !f.byte_aligned()
            || f.read == f.write
            || a < u32::from(reg::PROCESS_RAM)
            || b as usize > self.mem.len()
        {
            return slow;
        }
        let mut route = FmmuRoute {
            fast: true,
            allowed: true,
            write: f.write,
            complete: 0,
            logical: f.logical,
            len: f.len,
            physical: f.physical,
        };
        for (n, sm) in self.sms_overlapping(self.sm_active, a, b) {
            if sm.is_mailbox() {
                return slow;
            }
            if f.write && !sm.ecat_writes() {
                // ecat_write refuses the whole access.
                route.allowed = false;
            }
            // ecat_read lets the master read back an output buffer
            // without completing it.
            let completes = f.write || !sm.ecat_writes();
            if completes && sm.covers_last(a, b) {
                route.complete |= 1 << n;
            }
        }
        if !route.allowed {
            route.complete = 0;
        }
        route
    }

    /// Moves a whole FMMU window over its [`FmmuRoute`], the datagram
    /// `[start, ..)` covering it; returns whether the access happened.
    fn route_transfer(&mut self, route: &FmmuRoute, start: u64, data: &mut [u8]) -> bool {
        if !route.allowed {
            return false;
        }
        let Ok(off) = usize::try_from(u64::from(route.logical) - start) else {
            return false;
        };
        let (n, p) = (usize::from(route.len), usize::from(route.physical));
        let (Some(window), Some(mem)) = (data.get_mut(off..off + n), self.mem.get_mut(p..p + n))
        else {
            return false;
        };
        if route.write {
            mem.copy_from_slice(window);
        } else {
            window.copy_from_slice(mem);
        }
        let mut complete = route.complete;
        while complete != 0 {
            let n = complete.trailing_zeros() as usize;
            complete &= complete - 1;
            if route.write {
                self.ecat_write_complete(n);
            } else {
                self.ecat_read_complete(n);
            }
        }
        true
    }

    /// Logical addressing through the FMMUs; returns the working counter
    /// increment (+1 for any read mapping hit, +2 for any write mapping hit
    /// on LRW; +1 for LRD/LWR).
    pub(super) fn logical(&mut self, cmd: Command, addr: u32, data: &mut [u8]) -> u16 {
        if self.fmmu_active == 0 || data.is_empty() {
            return 0;
        }
        let start = u64::from(addr);
        let end = start + data.len() as u64;
        if self.routes_stale {
            self.reroute();
        }
        let mut read_hit = false;
        let mut write_hit = false;
        // Writes first, with the data as it arrived; then reads overwrite.
        for pass_write in [true, false] {
            let mut bits = self.pass_fmmus(cmd, pass_write);
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if let Some(r) = self.routes.get(i).copied()
                    && r.fast
                    && self.fast_routes
                {
                    let (r_start, r_end) = r.window();
                    if r_end <= start || r_start >= end {
                        continue;
                    }
                    if start <= r_start && r_end <= end {
                        let ok = self.route_transfer(&r, start, data);
                        if pass_write {
                            write_hit |= ok;
                        } else {
                            read_hit |= ok;
                        }
                        continue;
                    }
                }
                let Some(f) = self.fmmus.get(i).copied() else {
                    continue;
                };
                if f.logical_end() <= start || u64::from(f.logical) >= end {
                    continue;
                }
                let ok = if f.byte_aligned() {
                    self.fmmu_bytes(&f, start, data, pass_write)
                } else {
                    self.fmmu_bits(&f, start, data, pass_write)
                };
                if ok {
                    if pass_write {
                        write_hit = true;
                    } else {
                        read_hit = true;
                    }
                }
            }
        }
        logical_wkc(cmd, read_hit, write_hit)
    }

    /// The FMMUs that a logical command's write pass (`write`) or read
    /// pass reaches (bit n = FMMU n).
    #[inline]
    pub(super) fn pass_fmmus(&self, cmd: Command, write: bool) -> u8 {
        match (write, cmd) {
            (true, Command::Lwr | Command::Lrw) => self.fmmu_writes,
            (false, Command::Lrd | Command::Lrw) => self.fmmu_reads,
            _ => 0,
        }
    }

    /// Byte-aligned FMMU transfer of the overlap between the datagram
    /// `[start, start + data.len())` and the FMMU's logical window.
    #[inline(never)]
    pub(super) fn fmmu_bytes(
        &mut self,
        f: &FmmuConfig,
        start: u64,
        data: &mut [u8],
        write: bool,
    ) -> bool {
        let lo = start.max(u64::from(f.logical));
        let hi = (start + data.len() as u64).min(f.logical_end());
        if lo >= hi {
            return false;
        }
        let (Ok(dg_off), Ok(n)) = (usize::try_from(lo - start), usize::try_from(hi - lo)) else {
            return false;
        };
        let Ok(phys_off) = u16::try_from(lo - u64::from(f.logical)) else {
            return false;
        };
        let Some(phys) = f.physical.checked_add(phys_off) else {
            return false;
        };
        let Some(window) = data.get_mut(dg_off..dg_off + n) else {
            return false;
        };
        if write {
            self.ecat_write(phys, window)
        } else {
            self.ecat_read(phys, window, ReadMode::Copy)
        }
    }

    /// Bit-granular FMMU transfer (start/stop bits other than 0/7).
    ///
    /// Hand-written on purpose: the same transfer with `bitvec` (both sides
    /// as `BitSlice<u8, Lsb0>`, `store_le(load_le::<u64>())` per 64 bits)
    /// was measurably slower for the small fields bit FMMUs carry. The
    /// `soft_esc_bit_fmmu` benchmark (one LRW, 4 output and 4 input bits
    /// per slave) took 1527 -> 1638 instructions per cycle with 1 slave
    /// (+7 %) and 87 953 -> 95 058 with 64 (+8 %, cachegrind; criterion
    /// timings on the 2-core CI machine scatter more than that between
    /// identical builds); `copy_from_bitslice` was slower still (+23 % /
    /// +25 %).
    // Out of line, as `fmmu_bytes`: its buffers would otherwise enlarge
    // the stack frame of every logical datagram (1.3 ns of 55 in
    // `soft_esc_cycle/line/1`).
    #[inline(never)]
    pub(super) fn fmmu_bits(
        &mut self,
        f: &FmmuConfig,
        start: u64,
        data: &mut [u8],
        write: bool,
    ) -> bool {
        // Logical bit range [lbit_start, lbit_end] inclusive.
        let lbit_start = u64::from(f.logical) * 8 + u64::from(f.start_bit & 7);
        let Some(last_byte) = f.logical_end().checked_sub(1) else {
            return false;
        };
        let lbit_end = last_byte * 8 + u64::from(f.stop_bit & 7);
        if lbit_end < lbit_start {
            return false;
        }
        let dg_bit_start = start * 8;
        let dg_bit_end = (start + data.len() as u64) * 8; // exclusive
        let lo = lbit_start.max(dg_bit_start);
        let hi = (lbit_end + 1).min(dg_bit_end);
        if lo >= hi {
            return false;
        }
        let phys_bit0 = u64::from(f.physical) * 8 + u64::from(f.physical_bit & 7);
        // Physical byte range touched, for SyncManager checks.
        let p_first = phys_bit0 + (lo - lbit_start);
        let p_last = phys_bit0 + (hi - 1 - lbit_start);
        let (Ok(pa), Ok(pb)) = (u16::try_from(p_first / 8), u16::try_from(p_last / 8)) else {
            return false;
        };
        let plen = usize::from(pb - pa) + 1;
        let mut buf = [0u8; MAX_DATAGRAM];
        let Some(pbuf) = buf.get_mut(..plen) else {
            return false;
        };
        // Read current physical bytes (directly: bit writes are read-modify-write).
        if !self.mem_get(pa, pbuf) {
            return false;
        }
        for bit in lo..hi {
            let pbit = phys_bit0 + (bit - lbit_start) - u64::from(pa) * 8;
            let dbit = bit - dg_bit_start;
            let (Ok(pi), Ok(di)) = (usize::try_from(pbit / 8), usize::try_from(dbit / 8)) else {
                return false;
            };
            let (pm, dm) = (1u8 << (pbit % 8), 1u8 << (dbit % 8));
            if write {
                let v = data.get(di).is_some_and(|b| b & dm != 0);
                if let Some(p) = pbuf.get_mut(pi) {
                    *p = if v { *p | pm } else { *p & !pm };
                }
            } else {
                let v = pbuf.get(pi).is_some_and(|b| b & pm != 0);
                if let Some(d) = data.get_mut(di) {
                    *d = if v { *d | dm } else { *d & !dm };
                }
            }
        }
        if write {
            let touched = buf.get(..plen).unwrap_or(&[]);
            self.ecat_write(pa, touched)
        } else {
            // Run the SyncManager read rules on the touched bytes.
            let mut sink = [0u8; MAX_DATAGRAM];
            let touched = sink.get_mut(..plen).unwrap_or(&mut []);
            self.ecat_read(pa, touched, ReadMode::Copy)
        }
    }

    pub(super) fn reload_fmmus(&mut self) {
        self.fmmu_active = 0;
        self.fmmu_reads = 0;
        self.fmmu_writes = 0;
        self.routes_stale = true;
        self.fmmu_gen = self.fmmu_gen.wrapping_add(1);
        for n in 0..FMMU_COUNT {
            let Some(base) = reg::fmmu(n as u8) else {
                continue;
            };
            let f = FmmuConfig {
                logical: self.mem_u32(base + reg::fmmu::LOGICAL_START),
                len: self.mem_u16(base + reg::fmmu::LENGTH),
                start_bit: self.mem_u8(base + reg::fmmu::LOGICAL_START_BIT),
                stop_bit: self.mem_u8(base + reg::fmmu::LOGICAL_STOP_BIT),
                physical: self.mem_u16(base + reg::fmmu::PHYSICAL_START),
                physical_bit: self.mem_u8(base + reg::fmmu::PHYSICAL_START_BIT),
                read: self.mem_u8(base + reg::fmmu::TYPE) & 0x01 != 0,
                write: self.mem_u8(base + reg::fmmu::TYPE) & 0x02 != 0,
                enabled: self.mem_u8(base + reg::fmmu::ACTIVATE) & 0x01 != 0,
            };
            if f.enabled && f.len > 0 {
                self.fmmu_active |= 1 << n;
                if f.read {
                    self.fmmu_reads |= 1 << n;
                }
                if f.write {
                    self.fmmu_writes |= 1 << n;
                }
            }
            if let Some(slot) = self.fmmus.get_mut(n) {
                *slot = f;
            }
        }
    }
}
