//! A software slave's firmware on a real PDI driver: the SPI drivers of
//! `ecat-esc-spi` talking to the byte-level chip emulations of
//! `ecat-esc-spi-emu`, which forward the decoded accesses to the software
//! ESC that the master drives with frames. Only the wire between the MCU
//! and the chip is not real.
//!
//! The two crates are written independently (the emulation from the
//! datasheets' protocol tables, not from the driver), so a line of such
//! slaves that a master brings to OP is evidence for both.

use ecat_esc_spi::et1100::{Et1100Config, Et1100Spi};
use ecat_esc_spi::lan9252::Lan9252Spi;
use ecat_esc_spi_emu::Counters;
use ecat_esc_spi_emu::et1100::Et1100Emu;
use ecat_esc_spi_emu::lan9252::Lan9252Emu;
use ecat_sim::esc::SoftEsc;
use ecat_sim::{SoftPdi, SpiStats};
use ecat_slave::esc::{Esc, EscError};

/// The line's view of what an emulated chip counted.
fn stats(c: &Counters) -> SpiStats {
    SpiStats {
        transactions: c.transactions(),
        protocol_errors: c.protocol_errors(),
        refused_accesses: c.refused_accesses(),
    }
}

/// The ET1100 SPI driver on an emulated ET1100 in front of a software ESC.
pub struct Et1100Pdi {
    driver: Et1100Spi<Et1100Emu>,
}

impl Et1100Pdi {
    /// The driver (default configuration: 2-byte addressing below 0x2000,
    /// reads with a wait-state byte) on an emulated chip around `esc`.
    pub fn new(esc: SoftEsc) -> Self {
        Self::with_config(esc, Et1100Config::default())
    }

    /// [`Et1100Pdi::new`] with a driver configuration.
    pub fn with_config(esc: SoftEsc, config: Et1100Config) -> Self {
        Et1100Pdi {
            driver: Et1100Spi::new(Et1100Emu::new(esc), config),
        }
    }

    /// The driver.
    pub fn driver(&self) -> &Et1100Spi<Et1100Emu> {
        &self.driver
    }

    /// The emulated chip.
    pub fn chip(&self) -> &Et1100Emu {
        self.driver.spi()
    }
}

impl Esc for Et1100Pdi {
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
        self.driver.read(addr, buf)
    }
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
        self.driver.write(addr, data)
    }
    fn al_event(&mut self) -> Result<u32, EscError> {
        self.driver.al_event()
    }
}

impl SoftPdi for Et1100Pdi {
    fn soft_esc(&self) -> &SoftEsc {
        self.driver.spi().esc()
    }
    fn soft_esc_mut(&mut self) -> &mut SoftEsc {
        self.driver.spi_mut().esc_mut()
    }
    fn power_on(&mut self) {
        self.driver.spi_mut().reset();
    }
    fn spi_stats(&self) -> Option<SpiStats> {
        Some(stats(self.chip().counters()))
    }
}

/// The LAN9252 SPI driver on an emulated LAN9252 in front of a software
/// ESC. The driver's start-up (byte test, ready check) runs when it is
/// built and again after a power cycle; until it succeeds every access
/// fails with [`EscError::Interface`] and retries it.
pub struct Lan9252Pdi {
    driver: Lan9252Spi<Lan9252Emu>,
    ready: bool,
}

impl Lan9252Pdi {
    /// The driver on an emulated chip around `esc`, initialised.
    pub fn new(esc: SoftEsc) -> Self {
        let mut pdi = Lan9252Pdi {
            driver: Lan9252Spi::new(Lan9252Emu::new(esc)),
            ready: false,
        };
        let _ = pdi.ensure_ready();
        pdi
    }

    fn ensure_ready(&mut self) -> Result<(), EscError> {
        if !self.ready {
            self.driver.init().map_err(|_| EscError::Interface)?;
            self.ready = true;
        }
        Ok(())
    }

    /// The driver.
    pub fn driver(&self) -> &Lan9252Spi<Lan9252Emu> {
        &self.driver
    }

    /// The emulated chip.
    pub fn chip(&self) -> &Lan9252Emu {
        self.driver.spi()
    }
}

impl Esc for Lan9252Pdi {
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
        self.ensure_ready()?;
        self.driver.read(addr, buf)
    }
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
        self.ensure_ready()?;
        self.driver.write(addr, data)
    }
    fn al_event(&mut self) -> Result<u32, EscError> {
        self.ensure_ready()?;
        self.driver.al_event()
    }
}

impl SoftPdi for Lan9252Pdi {
    fn soft_esc(&self) -> &SoftEsc {
        self.driver.spi().esc()
    }
    fn soft_esc_mut(&mut self) -> &mut SoftEsc {
        self.driver.spi_mut().esc_mut()
    }
    fn power_on(&mut self) {
        self.driver.spi_mut().reset();
        self.ready = false;
        let _ = self.ensure_ready();
    }
    fn spi_stats(&self) -> Option<SpiStats> {
        Some(stats(self.chip().counters()))
    }
}
