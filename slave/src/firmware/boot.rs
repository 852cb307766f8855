//! Bootloader logic as functions over an [`ImageStore`]: download into the
//! inactive slot, commit, and the power-on decision with trial boots and
//! rollback. No state of its own: everything persistent is the store's
//! [`BootState`].

use super::{
    BootState, Candidate, CandidateStage, Crc32, FirmwareVersion, ImageInfo, ImageStore, Slot,
    StoreError, ValidatedImage, crc32,
};

/// Boots of an unconfirmed image before the bootloader rolls back.
pub const MAX_BOOT_ATTEMPTS: u8 = 3;

/// Why [`power_on`] fell back to the active image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RollbackReason {
    /// The pending image does not match its CRC (or length).
    VerifyFailed,
    /// The image was booted [`MAX_BOOT_ATTEMPTS`] times without being
    /// confirmed.
    TooManyAttempts,
    /// The trial could not be recorded (state write failed), so it was not
    /// started; the candidate is kept for the next power-on.
    StateWriteFailed,
}

/// What [`power_on`] decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BootOutcome {
    /// The active image, nothing pending.
    Normal,
    /// The new image, on trial (`attempt` 1..=[`MAX_BOOT_ATTEMPTS`]).
    Trial {
        /// This boot's attempt number.
        attempt: u8,
    },
    /// The new image was dropped (or not started); the active one runs.
    RolledBack {
        /// Why.
        reason: RollbackReason,
    },
    /// No valid boot state (blank device): slot A, version unknown.
    NoState,
    /// The boot records could not be read ([`ImageStore::read_state`]
    /// failed with an error other than [`StoreError::NoState`]): no image
    /// could be verified, so none is started and the device stays in the
    /// bootloader (INIT and BOOT only; AL status 0x0014 "no valid
    /// firmware" for any other state).
    StateUnreadable {
        /// The error reading the records.
        error: StoreError,
    },
}

/// The slot the bootloader starts, and the version it holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BootDecision {
    /// Slot to start; `None`: no image may be started, the device stays in
    /// the bootloader ([`BootOutcome::StateUnreadable`]).
    pub slot: Option<Slot>,
    /// Version of the image in it ([`FirmwareVersion::EMPTY`] if unknown).
    pub version: FirmwareVersion,
    /// How the decision came about.
    pub outcome: BootOutcome,
}

/// The stored state, or the blank-device state if there is none.
fn load<S: ImageStore + ?Sized>(store: &S) -> Result<BootState, StoreError> {
    match store.read_state() {
        Err(StoreError::NoState) => Ok(BootState::initial()),
        other => other,
    }
}

/// Factory provisioning: writes `image` into slot A and makes it the active
/// image with `version`, dropping any candidate; `version` becomes the
/// anti-rollback floor, the factory password applies again.
pub fn provision<S: ImageStore + ?Sized>(
    store: &mut S,
    version: FirmwareVersion,
    image: &[u8],
) -> Result<(), StoreError> {
    let len = u32::try_from(image.len()).map_err(|_| StoreError::OutOfBounds)?;
    store.erase(Slot::A)?;
    store.write(Slot::A, 0, image)?;
    let info = ImageInfo {
        len,
        crc: crc32(image),
        version,
    };
    if !verify_slot(store, Slot::A, &info) {
        return Err(StoreError::VerifyFailed);
    }
    store.write_state(&BootState {
        active: Slot::A,
        active_image: info,
        min_version: version,
        ..BootState::initial()
    })
}

/// Starts a download: forgets any earlier candidate (state first, so a
/// power cut never leaves a pending record pointing at a half-erased slot)
/// and erases the inactive slot, which it returns.
///
/// Fails with [`StoreError::TrialRunning`] while an unconfirmed image runs
/// (its slot is the inactive one on record).
pub fn begin_download<S: ImageStore + ?Sized>(store: &mut S) -> Result<Slot, StoreError> {
    let mut state = load(store)?;
    if matches!(state.candidate, Some(c) if c.stage == CandidateStage::Trial) {
        return Err(StoreError::TrialRunning);
    }
    let slot = state.active.other();
    if state.candidate.is_some() {
        state.candidate = None;
        state.boot_attempts = 0;
        store.write_state(&state)?;
    }
    store.erase(slot)?;
    Ok(slot)
}

/// Writes downloaded payload bytes at `offset` of `slot`, refusing the
/// active slot.
pub fn write_chunk<S: ImageStore + ?Sized>(
    store: &mut S,
    slot: Slot,
    offset: usize,
    data: &[u8],
) -> Result<(), StoreError> {
    if data.is_empty() {
        return Ok(());
    }
    if load(store)?.active == slot {
        return Err(StoreError::ActiveSlot);
    }
    store.write(slot, offset, data)
}

/// Ends a download whose image passed [`EfwValidator::finish`]: reads the
/// slot back against the payload CRC and records it as
/// [`CandidateStage::Downloaded`] (not yet pending).
///
/// [`EfwValidator::finish`]: super::EfwValidator::finish
pub fn finish_download<S: ImageStore + ?Sized>(
    store: &mut S,
    slot: Slot,
    image: &ValidatedImage,
) -> Result<ImageInfo, StoreError> {
    let info = image.info();
    let mut state = load(store)?;
    if state.active == slot {
        return Err(StoreError::ActiveSlot);
    }
    if !verify_slot(store, slot, &info) {
        return Err(StoreError::VerifyFailed);
    }
    state.candidate = Some(Candidate {
        slot,
        image: info,
        stage: CandidateStage::Downloaded,
    });
    state.boot_attempts = 0;
    store.write_state(&state)?;
    Ok(info)
}

/// The master ended the transfer with an error after the last packet (it
/// lost the final acknowledgement and gave up): a downloaded, not yet
/// committed image is dropped, so BOOT → INIT keeps the running firmware
/// and master and slave agree that the update did not happen. Returns
/// whether an image was dropped.
pub fn cancel_download<S: ImageStore + ?Sized>(store: &mut S) -> Result<bool, StoreError> {
    let mut state = load(store)?;
    match state.candidate {
        Some(Candidate {
            stage: CandidateStage::Downloaded,
            ..
        }) => {
            state.candidate = None;
            store.write_state(&state)?;
            Ok(true)
        }
        _ => Ok(false),
    }
}

/// What BOOT → INIT does: a downloaded image becomes pending, to be tried
/// at the next power-on. Returns the pending image, or `None` if there is
/// nothing to commit.
pub fn commit_pending<S: ImageStore + ?Sized>(
    store: &mut S,
) -> Result<Option<ImageInfo>, StoreError> {
    let mut state = load(store)?;
    match state.candidate {
        Some(mut c) if c.stage == CandidateStage::Downloaded => {
            c.stage = CandidateStage::Pending;
            state.candidate = Some(c);
            store.write_state(&state)?;
            Ok(Some(c.image))
        }
        Some(c) if c.stage == CandidateStage::Pending => Ok(Some(c.image)),
        _ => Ok(None),
    }
}

/// The slot's first `image.len` bytes have CRC `image.crc`.
pub fn verify_slot<S: ImageStore + ?Sized>(store: &S, slot: Slot, image: &ImageInfo) -> bool {
    let Ok(len) = usize::try_from(image.len) else {
        return false;
    };
    if len > store.slot_capacity() {
        return false;
    }
    let mut crc = Crc32::new();
    let mut buf = [0u8; 256];
    let mut offset = 0;
    while offset < len {
        let want = (len - offset).min(buf.len());
        let Some(chunk) = buf.get_mut(..want) else {
            return false;
        };
        match store.read(slot, offset, chunk) {
            Ok(n) if n == want => crc.update(chunk),
            _ => return false,
        }
        offset += want;
    }
    crc.finish() == image.crc
}

/// The bootloader at power-on. A pending (or unconfirmed trial) image is
/// verified against its CRC and started on trial, counting attempts; a
/// failed verify or [`MAX_BOOT_ATTEMPTS`] unconfirmed boots roll back to
/// the active slot and clear the candidate. A merely downloaded
/// (uncommitted) image is left alone. Never fails, but may start nothing:
///
/// - A blank store (no valid record, [`StoreError::NoState`]) starts
///   slot A with an unknown version ([`BootOutcome::NoState`]): the
///   factory image written without records.
/// - Records that cannot be read (any other error) start no image
///   (`slot: None`, [`BootOutcome::StateUnreadable`]). The slots hold the
///   bare payload; its length and CRC live only in the records, so no
///   image can be verified without them, and slot A may hold a
///   half-written download (after an update, downloads go to slot A). The
///   caller stays in the bootloader: INIT and BOOT only, AL status 0x0014
///   "no valid firmware" for any other state requested.
pub fn power_on<S: ImageStore + ?Sized>(store: &mut S) -> BootDecision {
    let state = match store.read_state() {
        Ok(state) => state,
        Err(StoreError::NoState) => {
            return BootDecision {
                slot: Some(Slot::A),
                version: FirmwareVersion::EMPTY,
                outcome: BootOutcome::NoState,
            };
        }
        Err(error) => {
            return BootDecision {
                slot: None,
                version: FirmwareVersion::EMPTY,
                outcome: BootOutcome::StateUnreadable { error },
            };
        }
    };
    let active = |outcome| BootDecision {
        slot: Some(state.active),
        version: state.active_image.version,
        outcome,
    };
    let Some(candidate) = state.candidate else {
        return active(BootOutcome::Normal);
    };
    let attempts = match candidate.stage {
        CandidateStage::Downloaded => return active(BootOutcome::Normal),
        CandidateStage::Pending => 0,
        CandidateStage::Trial => state.boot_attempts,
    };
    let reason = if attempts >= MAX_BOOT_ATTEMPTS {
        Some(RollbackReason::TooManyAttempts)
    } else if !verify_slot(store, candidate.slot, &candidate.image) {
        Some(RollbackReason::VerifyFailed)
    } else {
        None
    };
    if let Some(reason) = reason {
        // Even if this write is lost, the next power-on decides the same.
        let _ = store.write_state(&BootState {
            candidate: None,
            boot_attempts: 0,
            ..state
        });
        return active(BootOutcome::RolledBack { reason });
    }
    let attempt = attempts + 1;
    let trial = BootState {
        candidate: Some(Candidate {
            stage: CandidateStage::Trial,
            ..candidate
        }),
        boot_attempts: attempt,
        ..state
    };
    if store.write_state(&trial).is_err() {
        return active(BootOutcome::RolledBack {
            reason: RollbackReason::StateWriteFailed,
        });
    }
    BootDecision {
        slot: Some(candidate.slot),
        version: candidate.image.version,
        outcome: BootOutcome::Trial { attempt },
    }
}

/// The FoE password a write request must carry: the one the owner set
/// ([`set_password`]), else `factory` (the device description's
/// [`FoeSecurity::factory_password`](crate::device::FoeSecurity)). A blank
/// store has the factory password; records that cannot be read are an
/// error (the caller refuses: no password can be checked).
pub fn foe_password<S: ImageStore + ?Sized>(store: &S, factory: u32) -> Result<u32, StoreError> {
    Ok(load(store)?.password.unwrap_or(factory))
}

/// The anti-rollback floor ([`BootState::min_version`]): images older
/// than this are refused unless the owner allows the downgrade. A blank
/// store has none ([`FirmwareVersion::EMPTY`]).
pub fn rollback_floor<S: ImageStore + ?Sized>(store: &S) -> Result<FirmwareVersion, StoreError> {
    Ok(load(store)?.min_version)
}

/// The owner sets a new FoE password: stored in the boot records, power-cut
/// safe like every state change (a cut keeps the old or the new password,
/// never neither), so it survives a power cycle. Everything else in the
/// record is kept. The caller checks the old password first.
pub fn set_password<S: ImageStore + ?Sized>(
    store: &mut S,
    password: u32,
) -> Result<(), StoreError> {
    let state = load(store)?;
    store.write_state(&BootState {
        password: Some(password),
        ..state
    })
}

/// Called by the new firmware once it runs well: the trial image becomes
/// the active one, and its version the anti-rollback floor (an older
/// version got this far only with the owner's consent, which lowers the
/// floor with it). Without a trial image this does nothing.
pub fn confirm_boot<S: ImageStore + ?Sized>(store: &mut S) -> Result<(), StoreError> {
    let state = load(store)?;
    match state.candidate {
        Some(c) if c.stage == CandidateStage::Trial => store.write_state(&BootState {
            active: c.slot,
            active_image: c.image,
            candidate: None,
            boot_attempts: 0,
            min_version: c.image.version,
            ..state
        }),
        _ => Ok(()),
    }
}

/// Called when the new firmware's start check fails: the trial image is
/// dropped. Returns the slot to restart into (the old active one).
pub fn reject_boot<S: ImageStore + ?Sized>(store: &mut S) -> Result<Slot, StoreError> {
    let state = load(store)?;
    if matches!(state.candidate, Some(c) if c.stage == CandidateStage::Trial) {
        store.write_state(&BootState {
            candidate: None,
            boot_attempts: 0,
            ..state
        })?;
    }
    Ok(state.active)
}

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::super::{
        DeviceIdentity, EFW_HEADER_LEN, EfwHeaderRepr, EfwValidator, MemStore, pack,
    };
    use super::*;

    type Store = MemStore<8192>;
    const DEVICE: DeviceIdentity = DeviceIdentity {
        vendor_id: 0x5AE,
        product_code: 0x12_3456,
        revision: 1,
    };

    fn v(s: &str) -> FirmwareVersion {
        FirmwareVersion::new(s).unwrap()
    }

    fn efw(version: &str, payload: &[u8]) -> Vec<u8> {
        let h = EfwHeaderRepr {
            header_len: EFW_HEADER_LEN as u16,
            flags: 0,
            vendor_id: DEVICE.vendor_id,
            product_code: DEVICE.product_code,
            revision_min: 0,
            revision_max: 5,
            version: v(version),
            payload_len: 0,
            payload_crc: 0,
        };
        let mut out = vec![0; EFW_HEADER_LEN + payload.len()];
        pack(&h, payload, &mut out).unwrap();
        out
    }

    fn provisioned() -> Store {
        let mut s = Store::new();
        provision(&mut s, v("1.0.0"), &[0x11; 3000]).unwrap();
        s
    }

    /// Runs a whole download as the FoE server does, in `chunk`-byte
    /// pieces.
    fn download(s: &mut Store, image: &[u8], chunk: usize) -> Result<ImageInfo, StoreError> {
        let slot = begin_download(s)?;
        let mut val = EfwValidator::new(DEVICE, s.slot_capacity());
        for c in image.chunks(chunk) {
            let off = val.payload_received();
            let p = val.feed(c).unwrap();
            write_chunk(s, slot, off, p)?;
        }
        finish_download(s, slot, &val.finish().unwrap())
    }

    #[test]
    fn blank_store_boots_slot_a_with_unknown_version() {
        let mut s = Store::new();
        let d = power_on(&mut s);
        assert_eq!((d.slot, d.outcome), (Some(Slot::A), BootOutcome::NoState));
        assert_eq!(d.version, FirmwareVersion::EMPTY);
    }

    /// A store whose boot records cannot be read (a flash read error);
    /// slots and everything else work.
    struct UnreadableState(Store);

    impl ImageStore for UnreadableState {
        fn slot_capacity(&self) -> usize {
            self.0.slot_capacity()
        }
        fn erase(&mut self, slot: Slot) -> Result<(), StoreError> {
            self.0.erase(slot)
        }
        fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError> {
            self.0.write(slot, offset, data)
        }
        fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError> {
            self.0.read(slot, offset, buf)
        }
        fn read_state(&self) -> Result<BootState, StoreError> {
            Err(StoreError::Io)
        }
        fn write_state(&mut self, state: &BootState) -> Result<(), StoreError> {
            self.0.write_state(state)
        }
    }

    #[test]
    fn unreadable_boot_records_start_no_image_not_a_half_written_slot_a() {
        // 2.0.0 in slot B is active; a download of 3.0.0 into slot A was
        // interrupted halfway.
        let mut s = provisioned();
        download(&mut s, &efw("2.0.0", &[0x22; 600]), 100).unwrap();
        commit_pending(&mut s).unwrap();
        power_on(&mut s);
        confirm_boot(&mut s).unwrap();
        assert_eq!(begin_download(&mut s), Ok(Slot::A));
        write_chunk(&mut s, Slot::A, 0, &[0x33; 300]).unwrap();
        let mut s = UnreadableState(s);
        let d = power_on(&mut s);
        assert_eq!(d.slot, None, "nothing verifiable may start");
        assert_eq!(
            d.outcome,
            BootOutcome::StateUnreadable {
                error: StoreError::Io
            }
        );
        assert_eq!(d.version, FirmwareVersion::EMPTY);
        // Once the records read again, the verified image runs.
        let d = power_on(&mut s.0);
        assert_eq!((d.slot, d.version.as_str()), (Some(Slot::B), "2.0.0"));
    }

    #[test]
    fn provisioned_store_boots_the_factory_image() {
        let mut s = provisioned();
        let d = power_on(&mut s);
        assert_eq!(d.slot, Some(Slot::A));
        assert_eq!(d.version.as_str(), "1.0.0");
        assert_eq!(d.outcome, BootOutcome::Normal);
    }

    #[test]
    fn downloaded_image_runs_only_after_commit_and_confirm_makes_it_active() {
        let mut s = provisioned();
        let img = efw("2.0.0", &[0x22; 2500]);
        download(&mut s, &img, 100).unwrap();
        assert_eq!(power_on(&mut s).version.as_str(), "1.0.0", "not committed");
        assert_eq!(
            commit_pending(&mut s).unwrap().unwrap().version.as_str(),
            "2.0.0"
        );
        let d = power_on(&mut s);
        assert_eq!(
            (d.slot, d.version.as_str(), d.outcome),
            (Some(Slot::B), "2.0.0", BootOutcome::Trial { attempt: 1 })
        );
        confirm_boot(&mut s).unwrap();
        let d = power_on(&mut s);
        assert_eq!((d.slot, d.outcome), (Some(Slot::B), BootOutcome::Normal));
        // the next download goes to slot A
        assert_eq!(begin_download(&mut s).unwrap(), Slot::A);
    }

    #[test]
    fn unconfirmed_image_is_rolled_back_after_max_attempts() {
        let mut s = provisioned();
        download(&mut s, &efw("2.0.0", &[0x22; 100]), 64).unwrap();
        commit_pending(&mut s).unwrap();
        for attempt in 1..=MAX_BOOT_ATTEMPTS {
            assert_eq!(power_on(&mut s).outcome, BootOutcome::Trial { attempt });
            assert_eq!(begin_download(&mut s), Err(StoreError::TrialRunning));
        }
        let d = power_on(&mut s);
        assert_eq!(d.slot, Some(Slot::A));
        assert_eq!(d.version.as_str(), "1.0.0");
        assert_eq!(
            d.outcome,
            BootOutcome::RolledBack {
                reason: RollbackReason::TooManyAttempts
            }
        );
        assert_eq!(power_on(&mut s).outcome, BootOutcome::Normal);
    }

    #[test]
    fn start_check_failure_rolls_back() {
        let mut s = provisioned();
        download(&mut s, &efw("2.0.0", &[0x22; 100]), 64).unwrap();
        commit_pending(&mut s).unwrap();
        assert_eq!(power_on(&mut s).slot, Some(Slot::B));
        assert_eq!(reject_boot(&mut s), Ok(Slot::A));
        let d = power_on(&mut s);
        assert_eq!((d.slot, d.version.as_str()), (Some(Slot::A), "1.0.0"));
    }

    #[test]
    fn corrupted_pending_image_is_rolled_back_at_power_on() {
        let mut s = provisioned();
        download(&mut s, &efw("2.0.0", &[0x22; 100]), 64).unwrap();
        commit_pending(&mut s).unwrap();
        s.write(Slot::B, 10, &[0x00]).unwrap(); // bit rot
        let d = power_on(&mut s);
        assert_eq!(
            (d.slot, d.outcome),
            (
                Some(Slot::A),
                BootOutcome::RolledBack {
                    reason: RollbackReason::VerifyFailed
                }
            )
        );
        assert_eq!(s.read_state().unwrap().candidate, None);
    }

    #[test]
    fn writes_to_the_active_slot_are_refused() {
        let mut s = provisioned();
        assert_eq!(
            write_chunk(&mut s, Slot::A, 0, &[0]),
            Err(StoreError::ActiveSlot)
        );
    }

    #[test]
    fn power_cut_at_any_byte_of_a_download_keeps_the_old_firmware() {
        let img = efw("2.0.0", &[0x5A; 600]);
        let base = provisioned();
        // how many bytes a complete download writes
        let mut full = base.clone();
        let start = full.bytes_written();
        download(&mut full, &img, 100).unwrap();
        let total = full.bytes_written() - start;
        for cut in (0..total).step_by(37).chain(total - 140..total) {
            let mut s = base.clone();
            s.cut_power_after(cut);
            assert!(download(&mut s, &img, 100).is_err(), "cut {cut}");
            s.restore_power();
            // even committing afterwards cannot bring up a half image
            let _ = commit_pending(&mut s);
            let d = power_on(&mut s);
            assert_eq!(
                (d.slot, d.version.as_str()),
                (Some(Slot::A), "1.0.0"),
                "cut {cut}"
            );
            assert_eq!(d.outcome, BootOutcome::Normal, "cut {cut}");
        }
    }

    #[test]
    fn power_cut_during_commit_boots_old_or_new_never_garbage() {
        let mut base = provisioned();
        download(&mut base, &efw("2.0.0", &[0x5A; 600]), 100).unwrap();
        for cut in 0..=crate::firmware::STATE_RECORD_LEN {
            let mut s = base.clone();
            s.cut_power_after(cut);
            let r = commit_pending(&mut s);
            s.restore_power();
            let d = power_on(&mut s);
            if r.is_ok() {
                assert_eq!(d.version.as_str(), "2.0.0");
            } else {
                assert_eq!(d.version.as_str(), "1.0.0");
            }
        }
    }

    #[test]
    fn power_cut_during_trial_bookkeeping_never_loses_both_images() {
        let mut base = provisioned();
        download(&mut base, &efw("2.0.0", &[0x5A; 600]), 100).unwrap();
        commit_pending(&mut base).unwrap();
        for cut in 0..=crate::firmware::STATE_RECORD_LEN {
            let mut s = base.clone();
            s.cut_power_after(cut);
            let d1 = power_on(&mut s);
            s.restore_power();
            let d2 = power_on(&mut s);
            assert!(matches!(d1.version.as_str(), "1.0.0" | "2.0.0"));
            assert_eq!(
                d2.version.as_str(),
                "2.0.0",
                "cut {cut}: still pending or trial"
            );
        }
    }

    #[test]
    fn new_download_replaces_an_uncommitted_one() {
        let mut s = provisioned();
        download(&mut s, &efw("2.0.0", &[1; 100]), 64).unwrap();
        download(&mut s, &efw("3.0.0", &[2; 100]), 64).unwrap();
        commit_pending(&mut s).unwrap();
        assert_eq!(power_on(&mut s).version.as_str(), "3.0.0");
    }

    #[test]
    fn commit_without_download_does_nothing() {
        let mut s = provisioned();
        assert_eq!(commit_pending(&mut s), Ok(None));
        assert_eq!(power_on(&mut s).outcome, BootOutcome::Normal);
        assert_eq!(confirm_boot(&mut s), Ok(()));
    }
}
