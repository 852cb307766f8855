//! The Distributed Clocks unit's registers (0x0900-0x09A3): receive-time
//! latching, system time and its offset, delay and drift control, and the
//! SYNC0 unit. The clock itself is [`DcClock`](super::dc::DcClock).

use super::*;

impl SoftEsc {
    /// The injected times at which the next datagrams pass this ESC's
    /// port 0 (on the way down the line) and port 1 (on the way back;
    /// `None` when port 1 is closed): what the DC unit latches as receive
    /// times and reads its clock at. A line sets them per slave from its
    /// position and hop delay.
    pub fn set_frame_times(&mut self, port0_ns: u64, port1_ns: Option<u64>) {
        // Time only moves forward for a clock (a frame stamped earlier
        // than what the ESC has seen is taken as now).
        self.dc_port0_ns = port0_ns.max(self.dc_port0_ns);
        self.dc_port1_ns = port1_ns.map(|t| t.max(self.dc_port0_ns));
        if self.sii_busy_until.is_some() {
            self.sii_tick(self.dc_port0_ns);
        }
    }

    /// Makes this ESC's oscillator run `error_ppb` parts per billion fast
    /// (negative: slow) from the current frame time on.
    pub fn set_dc_oscillator(&mut self, error_ppb: i64) {
        self.dc.set_error_ppb(error_ppb, self.dc_port0_ns);
    }

    /// Sets the DC local time to `local_ns` at the current frame time (a
    /// slave powered on earlier or later than its neighbours).
    pub fn set_dc_local_time(&mut self, local_ns: u64) {
        self.dc.set_local(self.dc_port0_ns, local_ns);
    }

    /// The DC unit's clock (oscillator error, drift correction).
    pub fn dc_clock(&self) -> &DcClock {
        &self.dc
    }

    /// The DC local time at injected time `t_ns`.
    pub fn dc_local_time(&self, t_ns: u64) -> u64 {
        self.dc.local(t_ns)
    }

    /// The DC system time (local time + 0x0920 offset) at injected time
    /// `t_ns`, what a read of 0x0910 at that time returns.
    pub fn dc_system_time(&self, t_ns: u64) -> u64 {
        self.dc
            .local(t_ns)
            .wrapping_add(self.mem_u64(reg::DC_SYSTEM_TIME_OFFSET))
    }

    /// The last system time difference (0x092C) as a signed ns value
    /// (own − received).
    pub fn dc_difference(&self) -> i64 {
        dc::difference_of_register(self.mem_u32(reg::DC_SYSTEM_TIME_DIFF))
    }

    /// Runs the SYNC0 unit up to injected time `now_ns`: every pulse due
    /// by then (start time + k × cycle, in system time) sets 0x098E bit 0
    /// and AL event bit 2. Cheap when SYNC0 is off. A line calls this
    /// before it looks for AL events, so a firmware waits on SYNC0 as it
    /// would on its IRQ line.
    pub fn update_dc(&mut self, now_ns: u64) {
        let Some(next) = self.sync0_next else {
            return;
        };
        let now = self.dc_system_time(now_ns);
        if now < next {
            return;
        }
        let cycle = u64::from(self.mem_u32(reg::DC_SYNC0_CYCLE_TIME));
        let (count, last) = match (now - next).checked_div(cycle) {
            // Cycle time 0: a single pulse.
            None => {
                self.sync0_next = None;
                (1, next)
            }
            Some(k) => {
                let last = next + k * cycle;
                self.sync0_next = last.checked_add(cycle);
                (k.saturating_add(1), last)
            }
        };
        self.sync0_pulses = self.sync0_pulses.saturating_add(count);
        self.sync0_last = Some(last);
        let st = self.mem_u8(reg::DC_SYNC0_STATUS) | 0x01;
        self.set_u8(reg::DC_SYNC0_STATUS, st);
        // Only when the SII maps SYNC0 into the AL event request
        // (0x0151 bit 3); else a firmware polls 0x098E or wires SYNC0.
        if self.mem_u8(reg::PDI_CONFIG + 1) & 0x08 != 0 {
            self.raise_al_event(reg::AL_EVENT_SYNC0);
        }
    }

    /// Before a read of `[a, b)` (either side): the system time is the
    /// clock now, not a stored value; 0x0990 reads as the next SYNC0
    /// pulse while the unit runs.
    pub(super) fn refresh_dc_registers(&mut self, a: u32, b: u32) {
        let st = u32::from(reg::DC_SYSTEM_TIME);
        if a < st + 8 && st < b {
            let now = self.dc_system_time(self.dc_port0_ns);
            self.set_u64(reg::DC_SYSTEM_TIME, now);
        }
        let nx = u32::from(reg::DC_START_TIME);
        if a < nx + 8 && nx < b {
            self.update_dc(self.dc_port0_ns);
            if let Some(next) = self.sync0_next {
                self.set_u64(reg::DC_START_TIME, next);
            }
        }
    }

    /// SYNC0 pulses since power-on.
    pub fn sync0_pulses(&self) -> u64 {
        self.sync0_pulses
    }

    /// System time of the last SYNC0 pulse.
    pub fn sync0_last(&self) -> Option<u64> {
        self.sync0_last
    }

    /// System time of the next SYNC0 pulse (`None`: SYNC0 is off).
    pub fn sync0_next(&self) -> Option<u64> {
        self.sync0_next
    }

    /// ECAT write of the activation register 0x0981: cyclic operation with
    /// SYNC0 (bits 0 and 1) arms the unit at the start time 0x0990; a
    /// start time already past is compared on its low 32 bits, as the
    /// ET1100 does, so the first pulse then comes after the 32-bit system
    /// time wraps around (about 4.3 s later; masters write a start time
    /// ahead of the reference clock's time). Anything else stops it.
    pub(super) fn dc_activate(&mut self) {
        let act = self.mem_u8(reg::DC_ACTIVATION);
        if act & 0x03 != 0x03 {
            self.sync0_next = None;
            return;
        }
        let now = self.dc_system_time(self.dc_port0_ns);
        let mut start = self.mem_u64(reg::DC_START_TIME);
        if start < now {
            let wraps = (now - start).div_ceil(1 << 32);
            start = start.saturating_add(wraps.saturating_mul(1 << 32));
        }
        self.sync0_next = Some(start);
    }

    /// ECAT write to 0x0900: every port's receive time latched (local
    /// time of the frame at the port), and the processing unit's.
    pub(super) fn dc_latch(&mut self) {
        let t0 = self.dc.local(self.dc_port0_ns);
        self.set_u32(reg::DC_RECEIVE_TIME_PORT0, t0 as u32);
        if let Some(t1) = self.dc_port1_ns {
            let t1 = self.dc.local(t1);
            self.set_u32(reg::DC_RECEIVE_TIME_PORT0 + 4, t1 as u32);
        }
        self.set_u64(reg::DC_RECEIVE_TIME_PU, t0);
    }

    /// ECAT write of a system time (`len` 4 or 8 bytes at 0x0910): the
    /// drift control compares it, plus the transmission delay, with this
    /// ESC's own system time (ET1100 Section I, "Propagation delay /
    /// drift compensation"; a 32-bit write compares the low 32 bits).
    pub(super) fn dc_receive(&mut self, received: u64, len: usize) {
        let t = self.dc_port0_ns;
        let own = self.dc_system_time(t);
        let delay = u64::from(self.mem_u32(reg::DC_SYSTEM_TIME_DELAY));
        let reference = received.wrapping_add(delay);
        let diff = if len >= 8 {
            own.wrapping_sub(reference) as i64
        } else {
            i64::from((own as u32).wrapping_sub(reference as u32) as i32)
        };
        let depth = self.mem_u8(reg::DC_TIME_FILTER_DEPTH) & 0x0F;
        let filtered = self.dc.receive(diff, depth, t);
        self.set_u32(reg::DC_SYSTEM_TIME_DIFF, dc::difference_register(filtered));
        // 0x0932 "speed counter diff": here the drift control's rate
        // correction in ppm (an ESC shows it in its own clock units).
        let ppm = (self.dc.correction_ppb() / 1000).clamp(i64::from(i16::MIN), i64::from(i16::MAX));
        self.set_u16(reg::DC_SPEED_COUNTER_START + 2, ppm as i16 as u16);
    }
}
