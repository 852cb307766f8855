//! AL state transitions: what the AL control register asks for, the checks of
//! each transition (mailbox and SM configuration, PDO assignment against the
//! SM lengths, DC settings) and the AL status codes of ETG.1000.6 a refusal
//! answers with.

use super::*;

pub(super) fn read_sm<E: Esc>(esc: &mut E, n: u8) -> Result<(u16, u16, u8, bool), EscError> {
    let base = reg::sm(n).ok_or(EscError::OutOfRange { addr: 0, len: 0 })?;
    let mut b = [0u8; 8];
    esc.read(base, &mut b)?;
    Ok((
        u16::from_le_bytes([b[0], b[1]]),
        u16::from_le_bytes([b[2], b[3]]),
        b[4],
        b[6] & smr::ACTIVATE_ENABLE != 0,
    ))
}

/// SyncManager `n` is set up as this firmware expects: enabled at `start`
/// with `len` bytes and the low control bits of [`SM_CONTROL`]. A
/// process-data SM (2, 3) of `len` 0 (no PDO in its direction) is unused:
/// disabled, or enabled with length 0 as SOEM leaves it (an ESC does not
/// activate a SyncManager of length 0; SOES accepts it too). A mailbox SM
/// (0, 1) is always needed. `Err` when the PDI cannot read it.
pub(super) fn sm_matches<E: Esc>(
    esc: &mut E,
    n: u8,
    start: u16,
    len: usize,
) -> Result<bool, EscError> {
    let (s, l, control, enabled) = read_sm(esc, n)?;
    if n >= 2 && len == 0 {
        return Ok(!enabled || l == 0);
    }
    let expected = SM_CONTROL.get(usize::from(n)).copied().unwrap_or(0);
    Ok(enabled && s == start && usize::from(l) == len && control & 0x0F == expected & 0x0F)
}

/// SM0/SM1 are enabled with the given start and length and mailbox
/// control bits; `Err` when the PDI cannot read them.
pub(super) fn mailbox_matches<E: Esc>(
    esc: &mut E,
    out: (u16, u16),
    inp: (u16, u16),
) -> Result<bool, EscError> {
    Ok(sm_matches(esc, 0, out.0, usize::from(out.1))?
        && sm_matches(esc, 1, inp.0, usize::from(inp.1))?)
}

/// The process-data SMs (SM2 outputs, SM3 inputs) set up for images of
/// `outputs` and `inputs` bytes at `layout`'s addresses ([`sm_matches`]):
/// the AL status code of the first that is not, `None` when both are.
pub(super) fn process_data_sms<E: Esc>(
    esc: &mut E,
    layout: &MemoryLayout,
    outputs: usize,
    inputs: usize,
) -> Result<Option<AlStatusCode>, EscError> {
    Ok(if !sm_matches(esc, 2, layout.pd_out, outputs)? {
        Some(AlStatusCode::InvalidOutputConfig)
    } else if !sm_matches(esc, 3, layout.pd_in, inputs)? {
        Some(AlStatusCode::InvalidInputConfig)
    } else {
        None
    })
}

/// What the checks need to see while the AL state machine runs.
pub(super) struct Checks<'a, E: Esc, A: Application, const PDO: usize, const IMG: usize> {
    pub(super) esc: &'a mut E,
    pub(super) app: &'a mut A,
    pub(super) od: &'a mut Od,
    pub(super) layout: MemoryLayout,
    /// The process images, rebuilt in place by the PRE-OP→SAFE-OP check
    /// (`images_built`); in the states before SAFE-OP nothing reads them.
    pub(super) outputs: &'a mut ProcessImage<PDO>,
    pub(super) inputs: &'a mut ProcessImage<PDO>,
    pub(super) images_built: bool,
    pub(super) now_ns: u64,
    /// A PDI access that failed during a check: the check refuses with
    /// 0x0001 and the firmware goes to its fail-safe state (never "assume
    /// all is well").
    pub(super) pdi_error: Option<EscError>,
    /// The synchronisation the PRE-OP→SAFE-OP check found.
    pub(super) sync_mode: Option<SyncMode>,
    /// Only the bootloader runs: INIT→PRE-OP is refused (0x0014).
    pub(super) no_valid_firmware: bool,
}

impl<E: Esc, A: Application, const PDO: usize, const IMG: usize> Checks<'_, E, A, PDO, IMG> {
    /// Records a failed PDI access; the refusal code of a check that could
    /// not read the ESC.
    fn pdi_failed(&mut self, e: EscError) -> AlStatusCode {
        self.pdi_error.get_or_insert(e);
        AlStatusCode::Unspecified
    }
}

impl<E: Esc, A: Application, const PDO: usize, const IMG: usize> Checks<'_, E, A, PDO, IMG> {
    /// The DC SYNC configuration the master left in the activation
    /// register (0x0981) and the SYNC0 cycle time (0x09A0): no SYNC means
    /// free run; cyclic operation with SYNC0 means DC mode if the cycle
    /// fits. A SYNC signal without cyclic operation, or SYNC1 (not
    /// supported yet), is refused with 0x0030; a SYNC0 cycle of 0 (single
    /// shot) or shorter than [`DC_MIN_CYCLE_NS`] with 0x0035 (ETG.1000.6
    /// AL status codes; ETG.1020 §22).
    fn check_dc(&mut self) -> Result<SyncMode, AlStatusCode> {
        let act = self
            .esc
            .read_u8(reg::DC_ACTIVATION)
            .map_err(|e| self.pdi_failed(e))?;
        // A sync mode the master wrote into 0x1C32:01 must match the
        // registers; a free-run/SM value with SYNC0 active is overruled
        // by the registers (as the SSC derives the mode from 0x0981).
        let requested = self.od.get(0x1C32, 1);
        if act & 0x06 == 0 {
            if requested == Some(crate::od::build::sync_mode::DC_SYNC0) {
                return Err(AlStatusCode::InvalidDcSyncConfig);
            }
            return Ok(SyncMode::FreeRun);
        }
        if act & 0x01 == 0 || act & 0x04 != 0 {
            return Err(AlStatusCode::InvalidDcSyncConfig);
        }
        // The firmware runs on SYNC0 through the AL event request; an SII
        // that does not map SYNC0 there (0x0151 bit 3) leaves it deaf.
        let sync_map = self
            .esc
            .read_u8(reg::PDI_CONFIG + 1)
            .map_err(|e| self.pdi_failed(e))?;
        if sync_map & 0x08 == 0 {
            return Err(AlStatusCode::InvalidDcSyncConfig);
        }
        let cycle = self
            .esc
            .read_u32(reg::DC_SYNC0_CYCLE_TIME)
            .map_err(|e| self.pdi_failed(e))?;
        if cycle < DC_MIN_CYCLE_NS {
            return Err(AlStatusCode::InvalidDcCycleTime);
        }
        Ok(SyncMode::DcSync0)
    }
}

impl<E: Esc, A: Application, const PDO: usize, const IMG: usize> TransitionChecks
    for Checks<'_, E, A, PDO, IMG>
{
    fn check_mailbox(&mut self) -> Result<(), AlStatusCode> {
        if self.no_valid_firmware {
            return Err(AlStatusCode::NoValidFirmware);
        }
        match mailbox_matches(self.esc, self.layout.mbx_out, self.layout.mbx_in) {
            Ok(true) => Ok(()),
            Ok(false) => Err(AlStatusCode::InvalidMailboxPreOp),
            Err(e) => Err(self.pdi_failed(e)),
        }
    }

    fn check_boot_mailbox(&mut self) -> Result<(), AlStatusCode> {
        if !self.layout.has_boot() {
            return Err(AlStatusCode::BootNotSupported);
        }
        match mailbox_matches(self.esc, self.layout.boot_out, self.layout.boot_in) {
            Ok(true) => Ok(()),
            Ok(false) => Err(AlStatusCode::InvalidMailboxBoot),
            Err(e) => Err(self.pdi_failed(e)),
        }
    }

    fn check_process_data(&mut self) -> Result<(), AlStatusCode> {
        let desc = self.app.description();
        if let Some(m) = desc.modules {
            m.check_configured(self.od)?;
            // Every assigned PDO must belong to a slot that holds a module.
            let view = object_view(desc, self.od);
            for (assign, code) in [
                (0x1C12u16, AlStatusCode::InvalidOutputConfig),
                (0x1C13u16, AlStatusCode::InvalidInputConfig),
            ] {
                let n = self.od.get(assign, 0).unwrap_or(0).clamp(0, 255) as u8;
                for k in 1..=n {
                    let pdo = self.od.get(assign, k).unwrap_or(0) as u16;
                    if !view.visible(pdo) {
                        return Err(code);
                    }
                }
            }
        }
        let pd = &desc.process_data;
        // An image beyond this firmware's buffers is refused as any image
        // the device cannot serve.
        self.images_built = true;
        let od = &*self.od;
        if self.outputs.rebuild(od, Direction::Outputs, pd).is_err()
            || self.outputs.byte_len() > IMG
        {
            return Err(AlStatusCode::InvalidOutputConfig);
        }
        if self.inputs.rebuild(od, Direction::Inputs, pd).is_err() || self.inputs.byte_len() > IMG {
            return Err(AlStatusCode::InvalidInputConfig);
        }
        let (outputs, inputs) = (self.outputs.byte_len(), self.inputs.byte_len());
        let sets = self.outputs.sets() & self.inputs.sets();
        // Both directions must come from one PDO set.
        if sets == 0 {
            return Err(AlStatusCode::InvalidInputConfig);
        }
        match process_data_sms(self.esc, &self.layout, outputs, inputs) {
            Ok(None) => {}
            Ok(Some(code)) => return Err(code),
            Err(e) => return Err(self.pdi_failed(e)),
        }
        self.sync_mode = Some(self.check_dc()?);
        Ok(())
    }

    fn check_outputs(&mut self) -> Result<(), AlStatusCode> {
        // SAFE-OP -> OP needs valid outputs: an expired SyncManager watchdog
        // is re-armed only by fresh outputs from the master.
        let time = self
            .esc
            .read_u16(reg::WATCHDOG_TIME_PD)
            .map_err(|e| self.pdi_failed(e))?;
        let status = self
            .esc
            .read_u16(reg::WATCHDOG_STATUS_PD)
            .map_err(|e| self.pdi_failed(e))?;
        if time != 0 && status & 1 == 0 {
            return Err(AlStatusCode::SmWatchdog);
        }
        Ok(())
    }

    fn accept(&mut self, from: AlState, to: AlState) -> Result<(), AlStatusCode> {
        let (rx_sets, tx_sets) = if self.images_built {
            (self.outputs.sets(), self.inputs.sets())
        } else {
            (u32::MAX, u32::MAX)
        };
        let change = StateChange {
            from,
            to,
            rx_sets,
            tx_sets,
            now_ns: self.now_ns,
        };
        self.app.state_change(self.od, &change)
    }
}

impl<E: Esc, A: Application, const MBX: usize, const SDO: usize, const PDO: usize, const IMG: usize>
    Slave<E, A, MBX, SDO, PDO, IMG>
{
    pub(super) fn al_control(&mut self, control: u16) -> Result<(), EscError> {
        let before = self.al;
        let mut checks = Checks::<E, A, PDO, IMG> {
            esc: &mut self.esc,
            app: &mut self.app,
            od: A::Values::view_mut(&mut self.store),
            layout: self.layout,
            outputs: &mut self.outputs,
            inputs: &mut self.inputs,
            images_built: false,
            now_ns: self.now_ns,
            pdi_error: None,
            sync_mode: None,
            no_valid_firmware: self.no_valid_firmware,
        };
        let after = al::transition(before, control, &mut checks);
        if let Some(e) = checks.pdi_error {
            // The check could not read the ESC: fail safe (see poll_with).
            return Err(e);
        }
        if after.error && !before.error && before.state == AlState::PreOp && (control & 0x0F) == 4 {
            self.emergencies.transition_refused(after.code.code());
        }
        // The synchronisation the check found counts only if SAFE-OP was
        // reached (the application may still have refused it).
        if let Some(m) = checks.sync_mode
            && after.state == AlState::SafeOp
            && before.state == AlState::PreOp
        {
            self.sync_mode = m;
            self.outputs_since_sync0 = true;
            self.sm_event_missed = 0;
            self.dc_outputs = None;
            let cycle = if m == SyncMode::DcSync0 {
                i64::from(self.esc.read_u32(reg::DC_SYNC0_CYCLE_TIME)?)
            } else {
                0
            };
            self.publish_sync(cycle);
        }
        if matches!(after.state, AlState::Init | AlState::PreOp | AlState::Boot)
            && before.state != after.state
        {
            self.reset_sync();
        }
        if after.state != AlState::Op && before.state == AlState::Op {
            self.safe_outputs();
        }
        if after.state == AlState::Op && before.state != AlState::Op {
            // Outputs count from the first SM2 write in OP on (what the
            // master sent in SAFE-OP was never applied).
            self.outputs_applied = false;
        }
        if matches!(after.state, AlState::Init | AlState::Boot) && before.state != after.state {
            self.pending = None;
            self.last_sent = None;
            self.mailbox.reset();
        }
        self.al = after;
        self.write_al_status()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The SyncManager registers (0x0800..0x0840) as plain memory; a read
    /// elsewhere fails as a PDI failure would.
    struct SmRegisters([u8; 64]);

    impl SmRegisters {
        fn new() -> Self {
            SmRegisters([0; 64])
        }

        /// SM `n` at `start` with `len` bytes, control byte `control`,
        /// enabled or not.
        fn set(&mut self, n: usize, start: u16, len: u16, control: u8, enabled: bool) {
            let r = &mut self.0[8 * n..8 * n + 8];
            r[..2].copy_from_slice(&start.to_le_bytes());
            r[2..4].copy_from_slice(&len.to_le_bytes());
            r[4] = control;
            r[6] = u8::from(enabled);
        }
    }

    impl Esc for SmRegisters {
        fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
            let at = usize::from(addr.wrapping_sub(0x0800));
            let src = self.0.get(at..at + buf.len()).ok_or(EscError::OutOfRange {
                addr,
                len: buf.len(),
            })?;
            buf.copy_from_slice(src);
            Ok(())
        }

        fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
            Err(EscError::OutOfRange {
                addr,
                len: data.len(),
            })
        }
    }

    const LAYOUT: MemoryLayout = match MemoryLayout::new(128, None) {
        Some(l) => l,
        None => panic!("layout"),
    };

    /// The SMs as the PRE-OP -> SAFE-OP check wants them for 2 output
    /// and 3 input bytes.
    fn configured() -> SmRegisters {
        let mut esc = SmRegisters::new();
        esc.set(0, LAYOUT.mbx_out.0, LAYOUT.mbx_out.1, SM_CONTROL[0], true);
        esc.set(1, LAYOUT.mbx_in.0, LAYOUT.mbx_in.1, SM_CONTROL[1], true);
        esc.set(2, LAYOUT.pd_out, 2, SM_CONTROL[2], true);
        esc.set(3, LAYOUT.pd_in, 3, SM_CONTROL[3], true);
        esc
    }

    #[test]
    fn sync_managers_set_up_as_described_match() {
        let mut esc = configured();
        assert_eq!(
            mailbox_matches(&mut esc, LAYOUT.mbx_out, LAYOUT.mbx_in),
            Ok(true)
        );
        assert_eq!(process_data_sms(&mut esc, &LAYOUT, 2, 3), Ok(None));
    }

    #[test]
    fn a_process_data_sm_of_another_length_start_control_or_disabled_is_refused_with_its_direction_code()
     {
        let sms = [
            (2, LAYOUT.pd_out, 2, AlStatusCode::InvalidOutputConfig),
            (3, LAYOUT.pd_in, 3, AlStatusCode::InvalidInputConfig),
        ];
        for (n, start, len, code) in sms {
            let control = SM_CONTROL[n];
            let wrong = [
                (start, len + 1, control, true),
                (start + 1, len, control, true),
                (start, len, control ^ 0x04, true),
                (start, len, control, false),
            ];
            for (start, len, control, enabled) in wrong {
                let mut esc = configured();
                esc.set(n, start, len, control, enabled);
                assert_eq!(process_data_sms(&mut esc, &LAYOUT, 2, 3), Ok(Some(code)));
            }
        }
    }

    #[test]
    fn control_bits_above_the_low_four_do_not_matter() {
        let mut esc = configured();
        esc.set(2, LAYOUT.pd_out, 2, SM_CONTROL[2] | 0xF0, true);
        assert_eq!(process_data_sms(&mut esc, &LAYOUT, 2, 3), Ok(None));
    }

    #[test]
    fn an_unused_process_data_sm_may_be_disabled_or_enabled_with_length_0_not_with_a_length() {
        let mut esc = configured();
        esc.set(2, 0, 0, 0, false);
        assert_eq!(process_data_sms(&mut esc, &LAYOUT, 0, 3), Ok(None));
        // As SOEM leaves it.
        esc.set(2, LAYOUT.pd_out, 0, SM_CONTROL[2], true);
        assert_eq!(process_data_sms(&mut esc, &LAYOUT, 0, 3), Ok(None));
        esc.set(2, LAYOUT.pd_out, 1, SM_CONTROL[2], true);
        assert_eq!(
            process_data_sms(&mut esc, &LAYOUT, 0, 3),
            Ok(Some(AlStatusCode::InvalidOutputConfig))
        );
    }

    #[test]
    fn a_mailbox_sm_is_always_needed() {
        let mut esc = configured();
        esc.set(1, LAYOUT.mbx_in.0, LAYOUT.mbx_in.1, SM_CONTROL[1], false);
        assert_eq!(
            mailbox_matches(&mut esc, LAYOUT.mbx_out, LAYOUT.mbx_in),
            Ok(false)
        );
        let mut esc = configured();
        esc.set(
            0,
            LAYOUT.mbx_out.0,
            LAYOUT.mbx_out.1 - 1,
            SM_CONTROL[0],
            true,
        );
        assert_eq!(
            mailbox_matches(&mut esc, LAYOUT.mbx_out, LAYOUT.mbx_in),
            Ok(false)
        );
        // Even one described with length 0 is not "unused" as SM2/SM3 are.
        let mut esc = configured();
        esc.set(0, 0, 0, 0, false);
        assert_eq!(mailbox_matches(&mut esc, (0, 0), LAYOUT.mbx_in), Ok(false));
    }

    #[test]
    fn a_failed_pdi_read_is_an_error_not_a_mismatch() {
        struct Broken;
        impl Esc for Broken {
            fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
                Err(EscError::OutOfRange {
                    addr,
                    len: buf.len(),
                })
            }
            fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
                Err(EscError::OutOfRange {
                    addr,
                    len: data.len(),
                })
            }
        }
        assert!(process_data_sms(&mut Broken, &LAYOUT, 2, 3).is_err());
        assert!(mailbox_matches(&mut Broken, LAYOUT.mbx_out, LAYOUT.mbx_in).is_err());
    }
}
