//! A line of software slaves that frames pass through in order.

use crate::device::SoftSlave;

/// A line of software slaves, first to last.
pub struct Chain {
    slaves: Vec<SoftSlave>,
    frames: u64,
}

impl core::fmt::Debug for Chain {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Chain")
            .field("slaves", &self.slaves.len())
            .field("frames", &self.frames)
            .finish()
    }
}

impl Chain {
    /// `n` PAM-199 slaves in their power-on state; every slave but the last
    /// reports a link on port 1.
    pub fn new(n: usize) -> Self {
        let mut slaves: Vec<SoftSlave> = (0..n).map(|_| SoftSlave::new()).collect();
        let last = slaves.len().saturating_sub(1);
        for (i, s) in slaves.iter_mut().enumerate() {
            s.set_port1_link(i != last);
        }
        Chain { slaves, frames: 0 }
    }

    /// Passes one Ethernet frame through every slave in order (as the
    /// frame travels down the line and back), then lets each slave's
    /// firmware run at `now_ns`.
    pub fn process(&mut self, frame: &mut [u8], now_ns: u64) {
        for s in &mut self.slaves {
            s.process_frame(frame);
        }
        self.frames += 1;
        self.poll(now_ns);
    }

    /// Runs every slave's firmware once.
    pub fn poll(&mut self, now_ns: u64) {
        for s in &mut self.slaves {
            s.poll(now_ns);
        }
    }

    /// The slaves.
    pub fn slaves(&self) -> &[SoftSlave] {
        &self.slaves
    }

    /// The slaves, mutably (to set inputs, inject faults).
    pub fn slaves_mut(&mut self) -> &mut [SoftSlave] {
        &mut self.slaves
    }

    /// Number of frames processed so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }
}
