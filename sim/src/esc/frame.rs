//! Frame and datagram processing on the ECAT side: addressing (auto-
//! increment, configured, broadcast, logical) and the working counter rules
//! of ETG.1000.4 for all 14 commands.

use super::*;

impl SoftEsc {
    /// Processes one Ethernet frame in place, as the frame passes through
    /// this ESC. Non-EtherCAT and malformed frames are left untouched.
    pub fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome {
        let Ok(mut eth) = EthernetFrame::new_checked(&mut *frame) else {
            return FrameOutcome::Malformed;
        };
        if eth.ethertype() != ETHERTYPE_ETHERCAT {
            return FrameOutcome::NotEthercat;
        }
        eth.mark_forwarded();
        let Ok(mut ecat) = EcatFrame::new_checked(eth.payload_mut()) else {
            return FrameOutcome::Malformed;
        };
        if ecat.frame_type() != FrameType::Pdu {
            return FrameOutcome::Malformed;
        }
        let payload = ecat.payload_mut();
        let mut count = 0;
        let mut cursor = DatagramCursor::new();
        while let Some(item) = cursor.next_range(payload) {
            let Ok(range) = item else { break };
            let Some(bytes) = payload.get_mut(range) else {
                break;
            };
            let Ok(mut dg) = Datagram::new_checked(bytes) else {
                break;
            };
            self.process_datagram(&mut dg);
            count += 1;
        }
        FrameOutcome::Processed { datagrams: count }
    }

    /// Processes one datagram in place (addressing, data, working counter).
    pub fn process_datagram<T: AsRef<[u8]> + AsMut<[u8]>>(&mut self, dg: &mut Datagram<T>) {
        let cmd = dg.command();
        let mut wkc_add: u16 = 0;
        match cmd {
            Command::Aprd | Command::Apwr | Command::Aprw | Command::Armw => {
                let (adp, ado) = (dg.adp(), dg.ado());
                dg.set_adp(adp.wrapping_add(1));
                let data = dg.data_mut();
                wkc_add = match cmd {
                    Command::Armw if adp == 0 => self.phys_read_count(ado, data, ReadMode::Copy),
                    Command::Armw => self.phys_write_count(ado, data),
                    _ if adp == 0 => self.phys_rw(cmd, ado, data, ReadMode::Copy),
                    _ => 0,
                };
            }
            Command::Fprd | Command::Fpwr | Command::Fprw | Command::Frmw => {
                let (adp, ado) = (dg.adp(), dg.ado());
                let me = adp == self.station || (self.alias != 0 && adp == self.alias);
                if !me && cmd != Command::Frmw {
                    return;
                }
                let data = dg.data_mut();
                wkc_add = match cmd {
                    Command::Frmw if me => self.phys_read_count(ado, data, ReadMode::Copy),
                    Command::Frmw => self.phys_write_count(ado, data),
                    _ if me => self.phys_rw(cmd, ado, data, ReadMode::Copy),
                    _ => 0,
                };
            }
            Command::Brd | Command::Bwr | Command::Brw => {
                let (adp, ado) = (dg.adp(), dg.ado());
                dg.set_adp(adp.wrapping_add(1));
                let data = dg.data_mut();
                wkc_add = self.phys_rw(cmd, ado, data, ReadMode::Or);
            }
            Command::Lrd | Command::Lwr | Command::Lrw => {
                let logical = dg.logical_address();
                let data = dg.data_mut();
                wkc_add = self.logical(cmd, logical, data);
            }
            Command::Nop | Command::Unknown(_) => {}
        }
        if wkc_add != 0 {
            dg.set_wkc(dg.wkc().wrapping_add(wkc_add));
        }
    }

    /// A read, write or read-write on physical memory; returns the working
    /// counter increment (read 1, write 1, read-write 3 / 1 / 2).
    pub(super) fn phys_rw(
        &mut self,
        cmd: Command,
        addr: u16,
        data: &mut [u8],
        mode: ReadMode,
    ) -> u16 {
        match cmd {
            Command::Aprd | Command::Fprd | Command::Brd => self.phys_read_count(addr, data, mode),
            Command::Apwr | Command::Fpwr | Command::Bwr => self.phys_write_count(addr, data),
            Command::Aprw | Command::Fprw | Command::Brw => self.phys_read_write(addr, data, mode),
            _ => 0,
        }
    }

    /// A read-write: the old contents go out, the datagram's data in.
    /// Out of line: its scratch buffer would otherwise enlarge the stack
    /// frame of every datagram.
    #[inline(never)]
    fn phys_read_write(&mut self, addr: u16, data: &mut [u8], mode: ReadMode) -> u16 {
        let n = data.len().min(MAX_DATAGRAM);
        let mut scratch = [0u8; MAX_DATAGRAM];
        let (Some(tmp), Some(src)) = (scratch.get_mut(..n), data.get(..n)) else {
            return 0;
        };
        tmp.copy_from_slice(src);
        let r = self.phys_read_count(addr, data, mode);
        let w = self.phys_write_count(addr, tmp);
        r + 2 * w
    }

    pub(super) fn phys_read_count(&mut self, addr: u16, data: &mut [u8], mode: ReadMode) -> u16 {
        u16::from(self.ecat_read(addr, data, mode))
    }

    pub(super) fn phys_write_count(&mut self, addr: u16, data: &[u8]) -> u16 {
        u16::from(self.ecat_write(addr, data))
    }
}
