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
        let (adp, ado) = (dg.adp(), dg.ado());
        if matches!(
            cmd.addressing(),
            Addressing::Position | Addressing::Broadcast
        ) {
            // Every ESC increments ADP as the datagram passes (ETG.1000.4).
            dg.set_adp(adp.wrapping_add(1));
        }
        let wkc_add = self.process_data(cmd, adp, ado, dg.data_mut());
        if wkc_add != 0 {
            dg.set_wkc(dg.wkc().wrapping_add(wkc_add));
        }
    }

    /// The work of one datagram whose header the caller decoded (a line
    /// decodes it once for every ESC it reaches): `adp` as this ESC sees
    /// it (after the increments of the ESCs before it on position and
    /// broadcast commands), `ado`, and the data, changed in place. Returns
    /// the working counter increment; adding it and advancing ADP are the
    /// caller's.
    pub fn process_data(&mut self, cmd: Command, adp: u16, ado: u16, data: &mut [u8]) -> u16 {
        match cmd {
            Command::Armw if adp == 0 => self.phys_read_count(ado, data, ReadMode::Copy),
            Command::Armw => self.phys_write_count(ado, data),
            Command::Aprd | Command::Apwr | Command::Aprw if adp == 0 => {
                self.phys_rw(cmd, ado, data, ReadMode::Copy)
            }
            Command::Fprd | Command::Fpwr | Command::Fprw | Command::Frmw => {
                let me = self.answers_to(adp);
                match cmd {
                    Command::Frmw if me => self.phys_read_count(ado, data, ReadMode::Copy),
                    Command::Frmw => self.phys_write_count(ado, data),
                    _ if me => self.phys_rw(cmd, ado, data, ReadMode::Copy),
                    _ => 0,
                }
            }
            Command::Brd | Command::Bwr | Command::Brw => {
                self.phys_rw(cmd, ado, data, ReadMode::Or)
            }
            Command::Lrd | Command::Lwr | Command::Lrw => {
                self.logical(cmd, u32::from(adp) | (u32::from(ado) << 16), data)
            }
            _ => 0,
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
