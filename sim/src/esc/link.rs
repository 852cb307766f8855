//! The ports: link state in DL status (0x0110) and the error counters of a
//! bad frame or a lost link (0x0300-0x0313).

use super::*;

impl SoftEsc {
    /// Sets whether port 1 has a link (a slave that is not last in a chain
    /// has one). Updates DL status 0x0110 accordingly.
    pub fn set_port1_link(&mut self, link: bool) {
        use reg::dl_status::{
            PDI_OPERATIONAL, PDI_WATCHDOG_OK, communication, link as up, loop_closed,
        };
        // Port 0 is open with a link and communication; ports 2 and 3
        // have no link, so their loops are closed (as every real ESC of
        // tests/data/captures shows them). The PDI watchdog of an ESC
        // without a PDI (PDI control 0) never runs: expired.
        let watchdog = if self.mem_u8(reg::PDI_CONTROL) == 0 {
            0
        } else {
            self.mem_u16(reg::DL_STATUS) & PDI_WATCHDOG_OK
        };
        let mut dl =
            PDI_OPERATIONAL | watchdog | up(0) | communication(0) | loop_closed(2) | loop_closed(3);
        if link {
            dl |= up(1) | communication(1);
        } else {
            dl |= loop_closed(1);
        }
        self.set_u16(reg::DL_STATUS, dl);
    }

    /// Counts a frame that arrived on `port` with a bad checksum (a bit
    /// flip, a runt): the invalid frame counter of the port (0x0300 +
    /// 2 x port, saturating at 255, cleared by any ECAT write) goes up; the
    /// ESC does not act on such a frame.
    pub fn count_invalid_frame(&mut self, port: u8) {
        let a = reg::RX_ERROR_COUNTER + 2 * u16::from(port.min(3));
        let v = self.mem_u8(a);
        self.set_u8(a, v.saturating_add(1));
    }

    /// Counts a loss of link on `port` (lost link counter 0x0310 + port,
    /// saturating at 255, cleared by any ECAT write).
    pub fn count_lost_link(&mut self, port: u8) {
        let a = reg::LOST_LINK_COUNTER + u16::from(port.min(3));
        let v = self.mem_u8(a);
        self.set_u8(a, v.saturating_add(1));
    }
}
