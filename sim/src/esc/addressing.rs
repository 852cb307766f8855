//! Station address and alias: the cache configured addressing reads (0x0010,
//! 0x0012).

use super::*;

impl SoftEsc {
    /// The configured station address (0x0010).
    pub fn station_address(&self) -> u16 {
        self.station
    }

    /// A number that changes whenever the station address or alias does
    /// (a line rebuilds its address index when it sees a new one).
    pub fn address_generation(&self) -> u32 {
        self.addr_gen
    }

    /// Takes the station address and alias registers into the cache that
    /// configured addressing uses, counting a change.
    pub(super) fn refresh_address(&mut self) {
        let station = self.mem_u16(reg::STATION_ADDRESS);
        let alias = self.mem_u16(reg::STATION_ALIAS);
        if (station, alias) != (self.station, self.alias) {
            self.station = station;
            self.alias = alias;
            self.addr_gen = self.addr_gen.wrapping_add(1);
        }
    }

    /// The configured station alias (0x0012).
    pub fn station_alias(&self) -> u16 {
        self.alias
    }
}
