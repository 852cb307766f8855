//! A device on the software ESC: a [`Slave`] whose ESC processes EtherCAT
//! frames itself, for simulated lines (the virtual link, the raw-socket
//! runner) and tests.

use crate::esc::{FrameOutcome, SoftEsc};
use ecat_slave::esc::{Esc, EscError};
use ecat_slave::firmware::ImageStore;
use ecat_slave::led::LedPattern;

use ecat_slave::device::Application;
use ecat_slave::device::MemoryLayout;
use ecat_slave::device::Slave;

/// Counters of a PDI path with an SPI wire (a driver in front of an
/// emulated chip): what a logic analyser on the bus would count.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SpiStats {
    /// Chip-select cycles.
    pub transactions: u64,
    /// Cycles the chip found malformed (bad command, unterminated read, ...).
    pub protocol_errors: u64,
    /// Accesses the ESC behind the chip refused (SyncManager rules, range).
    pub refused_accesses: u64,
}

impl SpiStats {
    /// The sum of two counters (e.g. over the slaves of a line).
    pub fn sum(self, other: SpiStats) -> SpiStats {
        SpiStats {
            transactions: self.transactions.saturating_add(other.transactions),
            protocol_errors: self.protocol_errors.saturating_add(other.protocol_errors),
            refused_accesses: self.refused_accesses.saturating_add(other.refused_accesses),
        }
    }
}

/// How a software slave's firmware reaches its software ESC: directly
/// ([`SoftEsc`] itself, the default), or through a PDI driver and an
/// emulated chip interface in front of the software ESC (an SPI driver
/// talking to a byte-level emulation of an ET1100 or a LAN9252), so the
/// frames a master sends are served by firmware that runs exactly the PDI
/// path it would run on a board.
pub trait SoftPdi: Esc {
    /// The software ESC behind the PDI (frames, watchdogs, links).
    fn soft_esc(&self) -> &SoftEsc;
    /// The software ESC behind the PDI, mutably.
    fn soft_esc_mut(&mut self) -> &mut SoftEsc;
    /// A power cycle of the board: the ESC's registers restart (and a PDI
    /// with state of its own, such as an emulated chip, resets it).
    fn power_on(&mut self) {
        self.soft_esc_mut().power_on();
    }
    /// The SPI wire's counters, for a path that has one.
    fn spi_stats(&self) -> Option<SpiStats> {
        None
    }
}

impl SoftPdi for SoftEsc {
    fn soft_esc(&self) -> &SoftEsc {
        self
    }
    fn soft_esc_mut(&mut self) -> &mut SoftEsc {
        self
    }
}

/// A device on the software ESC: takes EtherCAT frames. `P` is the PDI
/// path of its firmware (see [`SoftPdi`]).
pub struct SoftSlave<A: Application, P: SoftPdi = SoftEsc> {
    inner: Slave<P, A>,
    port1_link: bool,
    stalled: bool,
    now_ns: u64,
}

impl<A: Application, P: SoftPdi> core::fmt::Debug for SoftSlave<A, P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.inner.fmt(f)
    }
}

impl<A: Application + Default> Default for SoftSlave<A> {
    fn default() -> Self {
        Self::new(A::default())
    }
}

impl<A: Application> SoftSlave<A> {
    /// `app` in its power-on state on a software ESC serving the device's
    /// SII image.
    pub fn new(app: A) -> Self {
        Self::with_pdi(app, |esc| esc)
    }

    /// A slave whose standard mailboxes have another layout (the SII it
    /// serves says so, so masters configure SM0/SM1 accordingly).
    ///
    /// The ESC has an ET1100's 8 KiB of process RAM unless a buffer of the
    /// layout starts beyond it; then it has the 60 KiB of an ESC IP core
    /// on an FPGA (the EL6695, for one, puts its inputs at 0x8E00).
    pub fn with_layout(app: A, layout: MemoryLayout) -> Self {
        let sii = app.description().sii_image_for(&layout);
        let starts = [
            layout.mbx_out.0,
            layout.mbx_in.0,
            layout.boot_out.0,
            layout.boot_in.0,
            layout.pd_out,
            layout.pd_in,
        ];
        // Room for a buffer's three copies behind its start.
        let size = if starts
            .iter()
            .any(|&a| usize::from(a) + 0x100 > crate::esc::MEM_SIZE)
        {
            crate::esc::MAX_MEM_SIZE
        } else {
            crate::esc::MEM_SIZE
        };
        let mut inner = Slave::new(SoftEsc::with_memory(&sii, size), app);
        inner.set_layout(layout);
        SoftSlave {
            inner,
            port1_link: false,
            stalled: false,
            now_ns: 0,
        }
    }
}

impl<A: Application, P: SoftPdi> SoftSlave<A, P> {
    /// `app` in its power-on state, its firmware reaching the software ESC
    /// (serving the device's SII image) through the PDI `wrap` builds
    /// around it.
    pub fn with_pdi(app: A, wrap: impl FnOnce(SoftEsc) -> P) -> Self {
        let sii = app.description().sii_image();
        SoftSlave {
            inner: Slave::new(wrap(SoftEsc::new(&sii)), app),
            port1_link: false,
            stalled: false,
            now_ns: 0,
        }
    }

    /// A power cycle: ESC registers and firmware restart; the EEPROM (SII)
    /// and the application's non-volatile storage keep what they hold.
    pub fn power_cycle(&mut self) {
        self.inner.esc_mut().power_on();
        self.inner
            .esc_mut()
            .soft_esc_mut()
            .set_port1_link(self.port1_link);
        self.inner.restart();
        self.stalled = false;
    }

    /// Passes an Ethernet frame through the ESC (in place).
    pub fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome {
        self.inner.esc_mut().soft_esc_mut().process_frame(frame)
    }

    /// Runs the ESC's watchdogs and then the firmware once. A PDI failure
    /// (only possible here when injected with
    /// [`SoftEsc::set_pdi_fault`]) puts the firmware in its fail-safe state
    /// (see [`Slave::poll_with`]) and is returned. While the firmware is
    /// stalled ([`SoftSlave::set_stalled`]) only the ESC runs; once its PDI
    /// watchdog expires the application's hardware outputs go off
    /// ([`Application::pdi_watchdog_expired`]).
    pub fn poll(&mut self, now_ns: u64) -> Result<(), EscError> {
        self.poll_with(now_ns, None)
    }

    /// [`SoftSlave::poll`] with the firmware image store (see
    /// [`Slave::poll_with`]).
    pub fn poll_with<'s>(
        &mut self,
        now_ns: u64,
        images: Option<&mut (dyn ImageStore + 's)>,
    ) -> Result<(), EscError> {
        self.inner.esc_mut().soft_esc_mut().update_watchdogs(now_ns);
        if self.stalled {
            if self.inner.esc().soft_esc().pdi_watchdog_expired() {
                self.inner.app_mut().pdi_watchdog_expired();
            }
            return Ok(());
        }
        let result = self.inner.poll_with(now_ns, images);
        // Stamp the firmware's PDI accesses with the time they happened.
        self.inner.esc_mut().soft_esc_mut().update_watchdogs(now_ns);
        self.now_ns = now_ns;
        result
    }

    /// Switches CoE Emergency messages on or off (see
    /// [`Slave::set_emergencies`]).
    pub fn set_emergencies(&mut self, enabled: bool) {
        self.inner.set_emergencies(enabled);
    }

    /// Simulates the application task stalling (it stops serving the ESC)
    /// or resuming.
    pub fn set_stalled(&mut self, stalled: bool) {
        self.stalled = stalled;
    }

    /// RUN and ERR LED patterns now.
    pub fn led_patterns(&self) -> (LedPattern, LedPattern) {
        self.inner
            .led_patterns(self.inner.esc().soft_esc().pdi_watchdog_expired())
    }

    /// Whether RUN and ERR are lit at the last poll's time.
    pub fn leds(&self) -> (bool, bool) {
        let (run, err) = self.led_patterns();
        let t = self.now_ns / 1_000_000;
        (run.is_on(t), err.is_on(t))
    }

    /// Sets whether port 1 has a link (every slave but the last).
    pub fn set_port1_link(&mut self, link: bool) {
        self.port1_link = link;
        self.inner.esc_mut().soft_esc_mut().set_port1_link(link);
    }

    /// The firmware.
    pub fn slave(&self) -> &Slave<P, A> {
        &self.inner
    }

    /// The firmware, mutably.
    pub fn slave_mut(&mut self) -> &mut Slave<P, A> {
        &mut self.inner
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ecat_slave::testing::TestApp;
    use std::mem::MaybeUninit;

    /// `Slave::init_in` (what a firmware uses to build its object in its
    /// static) gives the firmware `Slave::new` gives: the dictionary at
    /// its defaults, INIT, the same layout.
    #[test]
    fn init_in_builds_in_its_slot_the_slave_new_builds() {
        let app = TestApp::default();
        let sii = app.description().sii_image();
        let by_value = Slave::new(SoftEsc::new(&sii), TestApp::default());
        let mut slot: Box<MaybeUninit<Slave<SoftEsc, TestApp>>> = Box::new(MaybeUninit::uninit());
        let at = slot.as_mut_ptr();
        let in_place = Slave::init_in(&mut slot, SoftEsc::new(&sii), app);
        assert!(std::ptr::eq(in_place, at), "built in the slot");
        assert_eq!(in_place.al_status(), by_value.al_status());
        let (a, b) = (in_place.od(), by_value.od());
        let flats = a.dictionary().entries().count();
        assert!((0..flats).any(|f| b.value(f) != 0), "some default is not 0");
        for flat in 0..flats {
            assert_eq!(a.value(flat), b.value(flat), "entry {flat}");
        }
    }
}
