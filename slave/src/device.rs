//! The PAM-199-P-ETC as one EtherCAT device (layer 1).
//!
//! [`Slave`] is the firmware: it polls the ESC through the PDI ([`Esc`]),
//! runs the AL state machine on AL control events, serves the mailbox,
//! moves process data between the SyncManagers and the object dictionary,
//! and keeps 0x10F8 running. [`SoftSlave`] is a `Slave` on the software
//! ESC, which also takes EtherCAT frames. [`sii_image`] encodes the SII from
//! the same model.

use crate::al::{self, AlState, AlStatus, AlStatusCode, TransitionChecks};
use crate::app::amplifier::Amplifier;
use crate::app::power_stage::{PowerStage, SimPowerStage};
use crate::coe::ObjectAccess;
use crate::coe::emergency::{Emergencies, FaultState};
use crate::esc::registers::{self as reg, sm as smr};
use crate::esc::soft::{FrameOutcome, SII_SIZE, SoftEsc};
use crate::esc::{Esc, EscError};
use crate::firmware::{self, DeviceIdentity, ImageStore};
use crate::foe::FoeContext;
use crate::hal::{MemNv, NvStorage};
use crate::mailbox::MailboxServer;
use crate::od::complete;
use crate::od::model;
use crate::od::store::{self, ObjectStore};
use crate::od::types::{DataType, PdoMapping};
use crate::params::{self, STORAGE_SIZE, Stored};
use crate::pdo::{Direction, MAX_IMAGE, PdoMode, ProcessImage};
use crate::sii;
use crate::wire::coe::SdoAbortCode;

/// Vendor ID of W.E.St. Elektronik GmbH.
pub const VENDOR_ID: u32 = 0x0000_05AE;
/// Product code of the PAM-199-P-ETC.
pub const PRODUCT_CODE: u32 = 0x00C7_03F3;
/// Revision number.
pub const REVISION: u32 = 7;
/// Device name.
pub const DEVICE_NAME: &str = "PAM-199-P-ETC";

/// Physical layout of the mailboxes and process data buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryLayout {
    /// Standard mailbox out (SM0, master to slave): start, length.
    pub mbx_out: (u16, u16),
    /// Standard mailbox in (SM1, slave to master): start, length.
    pub mbx_in: (u16, u16),
    /// Bootstrap mailbox out (SM0 in BOOT): start, length.
    pub boot_out: (u16, u16),
    /// Bootstrap mailbox in (SM1 in BOOT): start, length.
    pub boot_in: (u16, u16),
    /// Output process data buffer (SM2) start.
    pub pd_out: u16,
    /// Input process data buffer (SM3) start.
    pub pd_in: u16,
}

/// The default layout: 128-byte standard mailboxes at 0x1000/0x1080, 1 KiB
/// bootstrap mailboxes at 0x1000/0x1400, outputs at 0x1100, inputs at 0x1180.
/// Other standard mailbox sizes: [`MemoryLayout::with_mailbox_size`].
pub const LAYOUT: MemoryLayout = MemoryLayout {
    mbx_out: (0x1000, 128),
    mbx_in: (0x1080, 128),
    boot_out: (0x1000, 1024),
    boot_in: (0x1400, 1024),
    pd_out: 0x1100,
    pd_in: 0x1180,
};

impl MemoryLayout {
    /// The default layout with standard mailboxes of `size` bytes each
    /// (16..=[`MAX_MAILBOX`]): SM0 at 0x1000, SM1 right after it, process
    /// data after both. The bootstrap mailbox stays 1 KiB at 0x1000/0x1400.
    pub const fn with_mailbox_size(size: u16) -> Option<Self> {
        if size < 16 || size as usize > MAX_MAILBOX {
            return None;
        }
        let out = 0x1000;
        let inp = out + size;
        let pd_out = inp + size;
        Some(MemoryLayout {
            mbx_out: (out, size),
            mbx_in: (inp, size),
            boot_out: LAYOUT.boot_out,
            boot_in: LAYOUT.boot_in,
            pd_out,
            pd_in: pd_out + MAX_IMAGE as u16,
        })
    }
}

/// SM control bytes as the SII advertises them.
const SM_CONTROL: [u8; 4] = [0x26, 0x22, 0x64, 0x20];

/// Largest mailbox the device handles.
pub const MAX_MAILBOX: usize = 1024;

/// The vendor password that unlocks the manufacturer settings 0xF80F when
/// written to 0xF801:01 PASSWORD ("WEST" in ASCII, little-endian 0x54534557).
pub const VENDOR_PASSWORD: u32 = 0x5453_4557;

/// Value a command entry (0xF801:02..04) reads back as acknowledgement.
pub const COMMAND_ACK: i64 = 0x1111_1111;

/// How long the acknowledgement stays visible.
pub const COMMAND_ACK_NS: u64 = 500_000_000;

/// Shortest interval between two SAVE commands: SAVE writes the EEPROM and
/// must not be called cyclically (manual 6.2.2). A faster SAVE is refused
/// with abort 0x08000021 (local control).
pub const SAVE_MIN_INTERVAL_NS: u64 = 1_000_000_000;

/// The SII EEPROM image of the device, encoded from the object dictionary,
/// for the default [`LAYOUT`].
pub fn sii_image() -> [u8; SII_SIZE] {
    sii_image_for(&LAYOUT)
}

/// The SII image for a memory layout (mailbox sizes and offsets).
pub fn sii_image_for(layout: &MemoryLayout) -> [u8; SII_SIZE] {
    let mut out = [0xFFu8; SII_SIZE];
    // The encoder only fails on a model that does not fit the EEPROM; the
    // unit tests guarantee it fits, and an unencodable model yields a blank
    // (all 0xFF) EEPROM that no master accepts.
    let _ = encode_sii(layout, &mut out);
    out
}

/// Most entries of one PDO in the SII.
const SII_MAX_ENTRIES: usize = 16;
/// Most PDOs of one direction.
const SII_MAX_PDOS: usize = 4;

type PdoEntries = heapless::Vec<sii::SiiPdoEntry<'static>, SII_MAX_ENTRIES>;

fn pdo_entries(pdo: u16) -> PdoEntries {
    let mut v = PdoEntries::new();
    let Some((_, obj)) = model::find(pdo) else {
        return v;
    };
    for e in obj.entries.iter().filter(|e| e.sub != 0) {
        let crate::od::types::DefaultValue::Int(mapping) = e.default else {
            continue;
        };
        let mapping = mapping as u32;
        let index = (mapping >> 16) as u16;
        let sub = ((mapping >> 8) & 0xFF) as u8;
        let bits = (mapping & 0xFF) as u8;
        let (name, dtype) = match model::find_entry(index, sub) {
            Some((_, m)) if index != 0 => (m.name, sii_type(&m.data_type)),
            _ => ("", 0),
        };
        let _ = v.push(sii::SiiPdoEntry {
            index,
            sub,
            name,
            data_type: dtype,
            bit_len: bits,
        });
    }
    v
}

fn sii_type(t: &DataType) -> u8 {
    // The SII carries the base type code in one byte; enums and bit types
    // are not mapped into PDOs here.
    (t.code() & 0xFF) as u8
}

fn encode_sii(layout: &MemoryLayout, out: &mut [u8]) -> Result<usize, sii::SiiError> {
    const RX: [(u16, Option<u8>); 2] = [(0x1600, Some(2)), (0x1601, None)];
    const TX: [(u16, Option<u8>); 4] = [
        (0x1A00, Some(3)),
        (0x1A01, None),
        (0x1A02, Some(3)),
        (0x1A03, None),
    ];
    let rx_entries: [PdoEntries; 2] = [pdo_entries(RX[0].0), pdo_entries(RX[1].0)];
    let tx_entries: [PdoEntries; 4] = [
        pdo_entries(TX[0].0),
        pdo_entries(TX[1].0),
        pdo_entries(TX[2].0),
        pdo_entries(TX[3].0),
    ];
    let mut rx: heapless::Vec<sii::SiiPdo<'_>, SII_MAX_PDOS> = heapless::Vec::new();
    for ((index, sm), entries) in RX.iter().zip(rx_entries.iter()) {
        let name = model::find(*index).map_or("", |(_, o)| o.name);
        let _ = rx.push(sii::SiiPdo {
            index: *index,
            sm: *sm,
            name,
            flags: crate::pdo::sii_flags(*index),
            entries,
        });
    }
    let mut tx: heapless::Vec<sii::SiiPdo<'_>, SII_MAX_PDOS> = heapless::Vec::new();
    for ((index, sm), entries) in TX.iter().zip(tx_entries.iter()) {
        let name = model::find(*index).map_or("", |(_, o)| o.name);
        let _ = tx.push(sii::SiiPdo {
            index: *index,
            sm: *sm,
            name,
            flags: crate::pdo::sii_flags(*index),
            entries,
        });
    }
    let out_len = ProcessImage::build(&ObjectStore::new(), Direction::Outputs)
        .map_or(0, |i| i.byte_len()) as u16;
    let in_len = ProcessImage::build(&ObjectStore::new(), Direction::Inputs)
        .map_or(0, |i| i.byte_len()) as u16;
    let sms = [
        sii::SiiSyncManager {
            start: layout.mbx_out.0,
            length: layout.mbx_out.1,
            control: SM_CONTROL[0],
            enable: 0x01,
            sm_type: sii::SmType::MailboxOut,
        },
        sii::SiiSyncManager {
            start: layout.mbx_in.0,
            length: layout.mbx_in.1,
            control: SM_CONTROL[1],
            enable: 0x01,
            sm_type: sii::SmType::MailboxIn,
        },
        sii::SiiSyncManager {
            start: layout.pd_out,
            length: out_len,
            control: SM_CONTROL[2],
            enable: 0x01,
            sm_type: sii::SmType::ProcessOut,
        },
        sii::SiiSyncManager {
            start: layout.pd_in,
            length: in_len,
            control: SM_CONTROL[3],
            enable: 0x01,
            sm_type: sii::SmType::ProcessIn,
        },
    ];
    let fmmus = [
        sii::FmmuUsage::Outputs,
        sii::FmmuUsage::Inputs,
        sii::FmmuUsage::SyncMStatus,
    ];
    let cfg = sii::SiiConfig {
        // SPI PDI (0x05), no special ESC configuration.
        pdi_control: 0x0005,
        pdi_config: 0x0000,
        sync_impulse: 0x0000,
        pdi_config2: 0x0000,
        station_alias: 0,
        identity: sii::SiiIdentity {
            vendor_id: VENDOR_ID,
            product_code: PRODUCT_CODE,
            revision: REVISION,
            serial: 0,
        },
        bootstrap_mailbox: sii::SiiMailbox {
            rx_offset: layout.boot_out.0,
            rx_size: layout.boot_out.1,
            tx_offset: layout.boot_in.0,
            tx_size: layout.boot_in.1,
        },
        standard_mailbox: sii::SiiMailbox {
            rx_offset: layout.mbx_out.0,
            rx_size: layout.mbx_out.1,
            tx_offset: layout.mbx_in.0,
            tx_size: layout.mbx_in.1,
        },
        // CoE | FoE.
        mailbox_protocols: 0x0004 | 0x0008,
        eeprom_kbit: (SII_SIZE * 8 / 1024) as u16,
        general: sii::SiiGeneral {
            group: "PAM",
            image: "",
            order: DEVICE_NAME,
            name: DEVICE_NAME,
            // SDO (bit 0), SDO Information (bit 1), PDO assignment (bit 2),
            // complete access (bit 5). PDO configuration (bit 3) is not
            // offered: the mappings are fixed.
            coe_details: 0x01 | 0x02 | 0x04 | 0x20,
            foe_details: 0x01,
            eoe_details: 0x00,
            // Identity in AL status code: no; safe-op: yes.
            flags: 0x01,
            current_on_ebus: 0,
            physical_port: 0x0011,
        },
        fmmus: &fmmus,
        sync_managers: &sms,
        tx_pdos: &tx,
        rx_pdos: &rx,
    };
    sii::encode(&cfg, out)
}

/// The PDO mode F800:02 FUNCTION selects.
fn function_mode(store: &ObjectStore) -> PdoMode {
    if store.get(0xF800, 2) == Some(2) {
        PdoMode::Independent
    } else {
        PdoMode::Directional
    }
}

/// The extended default assignment of a mode (manual 7.1, "Directional
/// Mode (Extended)" / "Independent Mode (Extended)").
fn select_assignment(store: &mut ObjectStore, mode: PdoMode) {
    let (rx, tx) = match mode {
        PdoMode::Directional => (0x1600, [0x1A00, 0x1A02]),
        PdoMode::Independent => (0x1601, [0x1A01, 0x1A03]),
    };
    store.set(0x1C12, 0, 1);
    store.set(0x1C12, 1, rx);
    store.set(0x1C13, 0, 2);
    store.set(0x1C13, 1, tx[0]);
    store.set(0x1C13, 2, tx[1]);
}

/// The PAM-199 firmware on an ESC reached through the PDI, driving the
/// solenoids through a [`PowerStage`] and keeping its parameters in an
/// [`NvStorage`].
pub struct Slave<E: Esc, P: PowerStage = SimPowerStage, N: NvStorage = MemNv<STORAGE_SIZE>> {
    esc: E,
    layout: MemoryLayout,
    stage: P,
    nv: N,
    /// What the parameter storage held at power-on.
    stored_at_power_on: Stored,
    unlocked: bool,
    last_save_ns: Option<u64>,
    /// A command entry showing its acknowledgement until the given time.
    ack: Option<(u16, u8, u64)>,
    amplifier: Amplifier,
    /// The live object dictionary.
    pub store: ObjectStore,
    al: AlStatus,
    outputs: ProcessImage,
    inputs: ProcessImage,
    mailbox: MailboxServer,
    /// A response waiting for SM1 to become free.
    pending: Option<(usize, [u8; MAX_MAILBOX])>,
    /// The last response written to SM1, for the repeat service.
    last_sent: Option<(usize, [u8; MAX_MAILBOX])>,
    emergencies: Emergencies,
    emergencies_enabled: bool,
    pdi_failures: u32,
    now_ns: u64,
}

impl<E: Esc, P: PowerStage, N: NvStorage> core::fmt::Debug for Slave<E, P, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Slave")
            .field("al", &self.al)
            .finish_non_exhaustive()
    }
}

/// What the checks need to see while the AL state machine runs.
struct Checks<'a, E: Esc> {
    esc: &'a mut E,
    store: &'a ObjectStore,
    layout: MemoryLayout,
    images: Option<(ProcessImage, ProcessImage)>,
    /// A PDI access that failed during a check: the check refuses with
    /// 0x0001 and the firmware goes to its fail-safe state (never "assume
    /// all is well").
    pdi_error: Option<EscError>,
}

impl<E: Esc> Checks<'_, E> {
    /// Records a failed PDI access; the refusal code of a check that could
    /// not read the ESC.
    fn pdi_failed(&mut self, e: EscError) -> AlStatusCode {
        self.pdi_error.get_or_insert(e);
        AlStatusCode::Unspecified
    }
}

fn read_sm<E: Esc>(esc: &mut E, n: u8) -> Result<(u16, u16, u8, bool), EscError> {
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

impl<E: Esc> Checks<'_, E> {
    /// SM0/SM1 are enabled with the given start and length and mailbox
    /// control bits; `Err` when the PDI cannot read them.
    fn mailbox_matches(&mut self, out: (u16, u16), inp: (u16, u16)) -> Result<bool, EscError> {
        let sm0 = read_sm(self.esc, 0)?;
        let sm1 = read_sm(self.esc, 1)?;
        Ok(sm0 == (out.0, out.1, sm0.2, true)
            && sm0.2 & 0x0F == SM_CONTROL[0] & 0x0F
            && sm1 == (inp.0, inp.1, sm1.2, true)
            && sm1.2 & 0x0F == SM_CONTROL[1] & 0x0F)
    }
}

impl<E: Esc> TransitionChecks for Checks<'_, E> {
    fn check_mailbox(&mut self) -> Result<(), AlStatusCode> {
        match self.mailbox_matches(self.layout.mbx_out, self.layout.mbx_in) {
            Ok(true) => Ok(()),
            Ok(false) => Err(AlStatusCode::InvalidMailboxPreOp),
            Err(e) => Err(self.pdi_failed(e)),
        }
    }

    fn check_boot_mailbox(&mut self) -> Result<(), AlStatusCode> {
        match self.mailbox_matches(self.layout.boot_out, self.layout.boot_in) {
            Ok(true) => Ok(()),
            Ok(false) => Err(AlStatusCode::InvalidMailboxBoot),
            Err(e) => Err(self.pdi_failed(e)),
        }
    }

    fn check_process_data(&mut self) -> Result<(), AlStatusCode> {
        let outputs = ProcessImage::build(self.store, Direction::Outputs)
            .map_err(|_| AlStatusCode::InvalidOutputConfig)?;
        let inputs = ProcessImage::build(self.store, Direction::Inputs)
            .map_err(|_| AlStatusCode::InvalidInputConfig)?;
        if let (Some(a), Some(b)) = (outputs.mode(), inputs.mode()) {
            if a != b {
                return Err(AlStatusCode::InvalidInputConfig);
            }
        }
        // The assignment must match F800:02 FUNCTION (writing FUNCTION in
        // PRE-OP selects the matching assignment; a later hand-written
        // assignment of the other mode is refused here).
        let function = function_mode(self.store);
        if outputs.mode().is_some_and(|m| m != function) {
            return Err(AlStatusCode::InvalidOutputConfig);
        }
        if inputs.mode().is_some_and(|m| m != function) {
            return Err(AlStatusCode::InvalidInputConfig);
        }
        let sm2 = read_sm(self.esc, 2).map_err(|e| self.pdi_failed(e))?;
        let sm3 = read_sm(self.esc, 3).map_err(|e| self.pdi_failed(e))?;
        let out_ok = if outputs.byte_len() == 0 {
            !sm2.3
        } else {
            sm2.3
                && sm2.0 == self.layout.pd_out
                && usize::from(sm2.1) == outputs.byte_len()
                && sm2.2 & 0x0F == SM_CONTROL[2] & 0x0F
        };
        if !out_ok {
            return Err(AlStatusCode::InvalidOutputConfig);
        }
        let in_ok = if inputs.byte_len() == 0 {
            !sm3.3
        } else {
            sm3.3
                && sm3.0 == self.layout.pd_in
                && usize::from(sm3.1) == inputs.byte_len()
                && sm3.2 & 0x0F == SM_CONTROL[3] & 0x0F
        };
        if !in_ok {
            return Err(AlStatusCode::InvalidInputConfig);
        }
        self.images = Some((outputs, inputs));
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
}

impl<E: Esc, P: PowerStage, N: NvStorage> Slave<E, P, N> {
    /// The firmware in its power-on state on `esc`, driving `stage`, with
    /// the parameters saved in `nv` (defaults when it is blank; a corrupt
    /// store is an EEPROM data error: power stage off until SAVE).
    pub fn new(esc: E, stage: P, nv: N) -> Self {
        let mut store = ObjectStore::new();
        let mut amplifier = Amplifier::new();
        let stored_at_power_on = params::stored(&nv);
        match stored_at_power_on {
            Stored::Valid(_) => {
                if params::load(&mut store, &nv).is_err() {
                    amplifier.eeprom_error = true;
                }
            }
            Stored::Blank => {}
            Stored::Corrupt => amplifier.eeprom_error = true,
        }
        Slave {
            esc,
            layout: LAYOUT,
            stage,
            nv,
            stored_at_power_on,
            unlocked: false,
            last_save_ns: None,
            ack: None,
            amplifier,
            store,
            al: AlStatus::INIT,
            outputs: ProcessImage::default(),
            inputs: ProcessImage::default(),
            mailbox: MailboxServer::new(),
            pending: None,
            last_sent: None,
            emergencies: Emergencies::default(),
            emergencies_enabled: true,
            pdi_failures: 0,
            now_ns: 0,
        }
    }

    /// Uses `layout` (it must match the SII the ESC serves).
    pub fn set_layout(&mut self, layout: MemoryLayout) {
        self.layout = layout;
    }

    /// The memory layout (mailboxes, process data buffers).
    pub fn layout(&self) -> &MemoryLayout {
        &self.layout
    }

    /// The ESC.
    pub fn esc(&self) -> &E {
        &self.esc
    }

    /// The ESC, mutably.
    pub fn esc_mut(&mut self) -> &mut E {
        &mut self.esc
    }

    /// The current AL status.
    pub fn al_status(&self) -> AlStatus {
        self.al
    }

    /// The power stage.
    pub fn stage(&self) -> &P {
        &self.stage
    }

    /// The power stage, mutably (fault injection on the simulation).
    pub fn stage_mut(&mut self) -> &mut P {
        &mut self.stage
    }

    /// The application state.
    pub fn amplifier(&self) -> &Amplifier {
        &self.amplifier
    }

    /// The running firmware version (0x100A SOFTWARE VERSION).
    pub fn firmware_version(&self) -> heapless::String<32> {
        let mut v = heapless::String::new();
        if let Some((flat, _)) = model::find_entry(0x100A, 0) {
            let _ = v.push_str(self.store.string(flat).unwrap_or(""));
        }
        v
    }

    /// Sets 0x100A to the version the bootloader started.
    pub fn set_firmware_version(&mut self, version: &str) -> bool {
        self.store.set_string(0x100A, 0, version)
    }

    /// The parameter storage.
    pub fn nv(&self) -> &N {
        &self.nv
    }

    /// The parameter storage, mutably (power-cut simulation).
    pub fn nv_mut(&mut self) -> &mut N {
        &mut self.nv
    }

    /// What the parameter storage held at power-on.
    pub fn stored_at_power_on(&self) -> Stored {
        self.stored_at_power_on
    }

    /// Runs SAVE / DEFAULT / LOADBACK (0xF801:02..04 written with 1).
    fn command(&mut self, sub: u8) -> Result<(), SdoAbortCode> {
        match sub {
            2 => {
                if let Some(last) = self.last_save_ns {
                    if self.now_ns.saturating_sub(last) < SAVE_MIN_INTERVAL_NS {
                        return Err(SdoAbortCode::LocalControl);
                    }
                }
                params::save(&self.store, &mut self.nv).map_err(|_| SdoAbortCode::HardwareError)?;
                self.last_save_ns = Some(self.now_ns);
                // Saving valid parameters clears an EEPROM data error.
                self.amplifier.eeprom_error = false;
            }
            3 => params::restore_defaults(&mut self.store),
            4 => {
                params::load(&mut self.store, &self.nv)
                    .map_err(|_| SdoAbortCode::TransferFailed)?;
            }
            _ => return Err(SdoAbortCode::SubindexNotFound),
        }
        self.store.set(0xF801, sub, COMMAND_ACK);
        self.ack = Some((0xF801, sub, self.now_ns.saturating_add(COMMAND_ACK_NS)));
        Ok(())
    }

    /// Runs the firmware once at time `now_ns`: AL control, mailbox,
    /// process data. Returns an error only if the PDI itself fails.
    pub fn poll(&mut self, now_ns: u64) -> Result<(), EscError> {
        self.poll_with(now_ns, None)
    }

    /// [`Slave::poll`] with the firmware image store: FoE writes go there
    /// (in BOOT) and BOOT→INIT marks a downloaded image pending for the
    /// bootloader. Without a store FoE answers "unsupported protocol".
    ///
    /// A failed PDI access is never taken as "all is well": the firmware
    /// goes to its fail-safe state ([`Slave::pdi_failure`]: outputs off,
    /// OP left for SAFE-OP, AL error 0x0001, Emergency 0x5000) and the error
    /// is returned.
    pub fn poll_with<'s>(
        &mut self,
        now_ns: u64,
        images: Option<&mut (dyn ImageStore + 's)>,
    ) -> Result<(), EscError> {
        match self.run_once(now_ns, images) {
            Ok(()) => Ok(()),
            Err(e) => {
                self.pdi_failure(e);
                Err(e)
            }
        }
    }

    /// The fail-safe reaction to a PDI failure `e`: outputs to their safe
    /// state and the power stage off at once, OP left for SAFE-OP, the
    /// error indication set with AL status code 0x0001 (unspecified error;
    /// ETG.1000.6 has no code for "the firmware cannot reach its ESC") and
    /// an Emergency 0x5000 (device hardware) queued. Writing the AL status
    /// is attempted; when the PDI is still down the master sees the
    /// silence of the SM watchdog and the PDI watchdog instead.
    fn pdi_failure(&mut self, e: EscError) {
        self.safe_outputs();
        self.stage.disable();
        self.pdi_failures = self.pdi_failures.saturating_add(1);
        let state = if self.al.state == AlState::Op {
            AlState::SafeOp
        } else {
            self.al.state
        };
        let first = !(self.al.error && self.al.code == AlStatusCode::Unspecified);
        self.al = AlStatus {
            state,
            error: true,
            code: AlStatusCode::Unspecified,
        };
        if first && self.emergencies_enabled && state != AlState::Init && state != AlState::Boot {
            self.emergencies.pdi_failure(e);
        }
        let _ = self.esc.write_u16(reg::AL_STATUS_CODE, self.al.code.code());
        let _ = self.esc.write_u16(reg::AL_STATUS, self.al.register());
    }

    /// How many polls ended in a PDI failure since power-on.
    pub fn pdi_failures(&self) -> u32 {
        self.pdi_failures
    }

    fn run_once<'s>(
        &mut self,
        now_ns: u64,
        mut images: Option<&mut (dyn ImageStore + 's)>,
    ) -> Result<(), EscError> {
        self.now_ns = now_ns;
        self.store.set(0x10F8, 0, now_ns as i64);
        if let Some((index, sub, until)) = self.ack {
            if now_ns >= until {
                self.store.set(index, sub, 0);
                self.ack = None;
            }
        }
        let events = self.esc.read_u32(reg::AL_EVENT_REQUEST)?;
        if events & reg::AL_EVENT_AL_CONTROL != 0 {
            let control = self.esc.read_u16(reg::AL_CONTROL)?;
            let before = self.al.state;
            self.al_control(control)?;
            if before == AlState::Boot && self.al.state == AlState::Init {
                // Manual 5.10: "change to Init, the bootloader copies the new
                // software": the downloaded image becomes pending. A store
                // that cannot record it is reported, not ignored: INIT with
                // the error indication and 0x0007 "firmware update not
                // successful, old firmware still running".
                if let Some(st) = images.as_deref_mut() {
                    if firmware::commit_pending(st).is_err() {
                        self.al = AlStatus {
                            state: AlState::Init,
                            error: true,
                            code: AlStatusCode::FirmwareUpdateFailed,
                        };
                        self.esc
                            .write_u16(reg::AL_STATUS_CODE, self.al.code.code())?;
                        self.esc.write_u16(reg::AL_STATUS, self.al.register())?;
                    }
                }
            }
        }
        self.supervise()?;
        if matches!(
            self.al.state,
            AlState::PreOp | AlState::SafeOp | AlState::Op | AlState::Boot
        ) {
            self.serve_mailbox(images)?;
        }
        let pd = matches!(self.al.state, AlState::SafeOp | AlState::Op);
        if pd {
            self.read_outputs(events)?;
        }
        let outputs_valid = self.al.state == AlState::Op;
        self.amplifier
            .run_until(&mut self.store, &mut self.stage, now_ns, outputs_valid);
        self.update_error_register();
        if pd {
            self.write_inputs()?;
        }
        Ok(())
    }

    /// Changes state on the device's own account (error indication set).
    fn local_error(&mut self, state: AlState, code: AlStatusCode) -> Result<(), EscError> {
        if self.al.state == AlState::Op && state != AlState::Op {
            self.safe_outputs();
        }
        if matches!(state, AlState::Init) {
            self.pending = None;
            self.last_sent = None;
            self.mailbox = MailboxServer::new();
        }
        self.al = AlStatus {
            state,
            error: true,
            code,
        };
        self.esc.write_u16(reg::AL_STATUS_CODE, code.code())?;
        self.esc.write_u16(reg::AL_STATUS, self.al.register())
    }

    /// Watches what can end a state without a request: the SyncManager
    /// watchdog in OP (-> SAFE-OP, 0x001B), a changed mailbox SM above INIT
    /// (-> INIT, 0x0016 / 0x0015 in BOOT) and a changed process-data SM in
    /// SAFE-OP/OP (-> PRE-OP, 0x001D / 0x001E).
    fn supervise(&mut self) -> Result<(), EscError> {
        if self.al.state == AlState::Op {
            let time = self.esc.read_u16(reg::WATCHDOG_TIME_PD)?;
            let status = self.esc.read_u16(reg::WATCHDOG_STATUS_PD)?;
            if time != 0 && status & 1 == 0 {
                return self.local_error(AlState::SafeOp, AlStatusCode::SmWatchdog);
            }
        }
        if self.al.state != AlState::Init {
            let boot = self.al.state == AlState::Boot;
            let (out, inp) = self.mailbox_layout();
            let mut checks = Checks {
                esc: &mut self.esc,
                store: &self.store,
                layout: self.layout,
                images: None,
                pdi_error: None,
            };
            if !checks.mailbox_matches(out, inp)? {
                let code = if boot {
                    AlStatusCode::InvalidMailboxBoot
                } else {
                    AlStatusCode::InvalidMailboxPreOp
                };
                return self.local_error(AlState::Init, code);
            }
        }
        if matches!(self.al.state, AlState::SafeOp | AlState::Op) {
            let sm2 = read_sm(&mut self.esc, 2)?;
            let sm3 = read_sm(&mut self.esc, 3)?;
            let out_ok = self.outputs.byte_len() == 0
                || (sm2.3
                    && sm2.0 == self.layout.pd_out
                    && usize::from(sm2.1) == self.outputs.byte_len());
            let in_ok = self.inputs.byte_len() == 0
                || (sm3.3
                    && sm3.0 == self.layout.pd_in
                    && usize::from(sm3.1) == self.inputs.byte_len());
            if !out_ok {
                return self.local_error(AlState::PreOp, AlStatusCode::InvalidOutputConfig);
            }
            if !in_ok {
                return self.local_error(AlState::PreOp, AlStatusCode::InvalidInputConfig);
            }
        }
        Ok(())
    }

    /// Sends CoE Emergency messages (default on). Masters that cannot take
    /// an unsolicited emergency in the mailbox (ethercrab 0.7.1 fails when
    /// one arrives instead of an SDO response) may switch them off; 0x1001
    /// is kept either way.
    pub fn set_emergencies(&mut self, enabled: bool) {
        self.emergencies_enabled = enabled;
    }

    /// Emergencies waiting for the master.
    pub fn emergencies_waiting(&self) -> usize {
        self.emergencies.len()
    }

    /// Derives the fault state from the diagnosis objects and the AL
    /// status, queues emergencies for new faults and writes 0x1001.
    fn update_error_register(&mut self) {
        let d = |i: u16, s: u8| self.store.get(i, s) == Some(1);
        let state = FaultState {
            short: [d(0xA010, 1), d(0xA020, 1)],
            open: [d(0xA010, 2), d(0xA020, 2)],
            overvoltage: d(0xA000, 3),
            undervoltage: d(0xA000, 2),
            overtemperature: d(0xA000, 4),
            eeprom: d(0xA000, 1),
            watchdog: self.al.error && self.al.code == AlStatusCode::SmWatchdog,
        };
        let reg = self.emergencies.update(state, self.al.code.code());
        self.store.set(0x1001, 0, i64::from(reg));
        // No mailbox in INIT (and BOOT has only the bootstrap mailbox for
        // FoE): what is queued there would reach the next master session
        // as a stale message (SOEM's config_map then fails). Like the SSC
        // and SOES, INIT empties the queue; 0x1001 stays consistent.
        if !self.emergencies_enabled || matches!(self.al.state, AlState::Init | AlState::Boot) {
            self.emergencies.clear();
        }
    }

    /// RUN and ERR LED patterns (manual 4.1); `pdi_watchdog_expired` comes
    /// from the ESC.
    pub fn led_patterns(
        &self,
        pdi_watchdog_expired: bool,
    ) -> (crate::led::LedPattern, crate::led::LedPattern) {
        crate::led::patterns(&self.al, pdi_watchdog_expired)
    }

    fn al_control(&mut self, control: u16) -> Result<(), EscError> {
        let before = self.al;
        let mut checks = Checks {
            esc: &mut self.esc,
            store: &self.store,
            layout: self.layout,
            images: None,
            pdi_error: None,
        };
        let after = al::transition(before, control, &mut checks);
        if let Some(e) = checks.pdi_error {
            // The check could not read the ESC: fail safe (see poll_with).
            return Err(e);
        }
        if after.error && !before.error && before.state == AlState::PreOp && (control & 0x0F) == 4 {
            self.emergencies.transition_refused(after.code.code());
        }
        if let Some((o, i)) = checks.images.take() {
            self.outputs = o;
            self.inputs = i;
        }
        if after.state != AlState::Op && before.state == AlState::Op {
            self.safe_outputs();
        }
        if matches!(after.state, AlState::Init | AlState::Boot) && before.state != after.state {
            self.pending = None;
            self.last_sent = None;
            self.mailbox = MailboxServer::new();
        }
        self.al = after;
        self.esc.write_u16(reg::AL_STATUS_CODE, after.code.code())?;
        self.esc.write_u16(reg::AL_STATUS, after.register())?;
        Ok(())
    }

    /// Outputs to their safe state: every RxPDO-mappable entry (ENABLE,
    /// COMMAND VALUE) back to zero.
    fn safe_outputs(&mut self) {
        let mut flat = 0usize;
        for obj in model::OBJECTS {
            for e in obj.entries {
                if e.pdo == PdoMapping::Rx {
                    self.store.set_value(flat, 0);
                }
                flat += 1;
            }
        }
    }

    fn mailbox_layout(&self) -> ((u16, u16), (u16, u16)) {
        if self.al.state == AlState::Boot {
            (self.layout.boot_out, self.layout.boot_in)
        } else {
            (self.layout.mbx_out, self.layout.mbx_in)
        }
    }

    /// Writes the waiting response into SM1 if SM1 is free. The whole
    /// buffer is written so that the ESC sees its last byte and marks the
    /// mailbox full.
    fn deliver_pending(&mut self) -> Result<(), EscError> {
        if self.pending.is_none() || self.sm_full(1)? {
            return Ok(());
        }
        let (_, inp) = self.mailbox_layout();
        if let Some((len, buf)) = self.pending.take() {
            let n = usize::from(inp.1).min(MAX_MAILBOX);
            let mut frame = [0u8; MAX_MAILBOX];
            if let (Some(dst), Some(src)) = (frame.get_mut(..len), buf.get(..len)) {
                dst.copy_from_slice(src);
            }
            if let Some(f) = frame.get(..n) {
                self.esc.write(inp.0, f)?;
            }
            self.last_sent = Some((len, frame));
        }
        Ok(())
    }

    /// Mailbox repeat (ETG.1000.4 SyncManager repeat): when the master
    /// toggles the repeat request bit of SM1 (activate byte bit 1), the
    /// last response is put into SM1 again and the repeat acknowledge bit
    /// (PDI control bit 1) is toggled to match.
    fn serve_repeat(&mut self) -> Result<(), EscError> {
        let base = reg::sm(1).ok_or(EscError::OutOfRange { addr: 0, len: 0 })?;
        let request = self.esc.read_u8(base + smr::ACTIVATE)? & smr::ACTIVATE_REPEAT;
        let pdi = self.esc.read_u8(base + smr::PDI_CONTROL)?;
        if request == pdi & smr::PDI_REPEAT_ACK {
            return Ok(());
        }
        if !self.sm_full(1)? {
            if let Some((_, frame)) = &self.last_sent {
                let (_, inp) = self.mailbox_layout();
                let n = usize::from(inp.1).min(MAX_MAILBOX);
                let copy = *frame;
                if let Some(f) = copy.get(..n) {
                    self.esc.write(inp.0, f)?;
                }
            }
        }
        self.esc.write(
            base + smr::PDI_CONTROL,
            &[(pdi & !smr::PDI_REPEAT_ACK) | request],
        )
    }

    fn serve_mailbox<'s>(
        &mut self,
        images: Option<&mut (dyn ImageStore + 's)>,
    ) -> Result<(), EscError> {
        self.serve_repeat()?;
        self.deliver_pending()?;
        // One request at a time: a new request waits in SM0 until the
        // previous response has left.
        if self.pending.is_some() {
            return Ok(());
        }
        if !self.sm_full(0)? {
            // Nothing new: continue a response that spans several mailboxes.
            let (_, inp) = self.mailbox_layout();
            let max = usize::from(inp.1).min(MAX_MAILBOX);
            let mut response = [0u8; MAX_MAILBOX];
            let mut produced = response
                .get_mut(..max)
                .and_then(|r| self.mailbox.next_pending(r));
            if produced.is_none() && self.emergencies_enabled && !self.emergencies.is_empty() {
                produced = response.get_mut(..max).and_then(|r| {
                    let body = r.get_mut(crate::wire::mailbox::HEADER_LEN..)?;
                    let n = self.emergencies.pop_into(body)?;
                    self.mailbox.frame_coe(r, n)
                });
            }
            if let Some(len) = produced {
                self.pending = Some((len, response));
                self.deliver_pending()?;
            }
            return Ok(());
        }
        let (out, inp) = self.mailbox_layout();
        let mut request = [0u8; MAX_MAILBOX];
        let n = usize::from(out.1).min(MAX_MAILBOX);
        let Some(req) = request.get_mut(..n) else {
            return Ok(());
        };
        self.esc.read(out.0, req)?;
        let mut response = [0u8; MAX_MAILBOX];
        let max = usize::from(inp.1).min(MAX_MAILBOX);
        let state = self.al.state;
        let mut mailbox = core::mem::take(&mut self.mailbox);
        let version = self.firmware_version();
        let mut ctx = images.map(|store| FoeContext {
            store,
            identity: DeviceIdentity {
                vendor_id: VENDOR_ID,
                product_code: PRODUCT_CODE,
                revision: REVISION,
            },
            version: version.as_str(),
            in_boot: state == AlState::Boot,
            busy: false,
        });
        let produced = match response.get_mut(..max) {
            Some(resp) => mailbox.handle(
                req,
                resp,
                &mut OdAccess { slave: self, state },
                ctx.as_mut(),
            ),
            None => None,
        };
        self.mailbox = mailbox;
        if let Some(len) = produced {
            self.pending = Some((len, response));
            self.deliver_pending()?;
        }
        Ok(())
    }

    fn sm_full(&mut self, n: u8) -> Result<bool, EscError> {
        let base = reg::sm(n).ok_or(EscError::OutOfRange { addr: 0, len: 0 })?;
        Ok(self.esc.read_u8(base + smr::STATUS)? & smr::STATUS_MAILBOX_FULL != 0)
    }

    fn read_outputs(&mut self, events: u32) -> Result<(), EscError> {
        let mut buf = [0u8; MAX_IMAGE];
        if events & reg::al_event_sm(2) != 0 && self.outputs.byte_len() > 0 {
            let n = self.outputs.byte_len();
            if let Some(b) = buf.get_mut(..n) {
                self.esc.read(self.layout.pd_out, b)?;
                if self.al.state == AlState::Op {
                    self.outputs.unpack(&mut self.store, b);
                }
            }
        }
        Ok(())
    }

    fn write_inputs(&mut self) -> Result<(), EscError> {
        let n = self.inputs.byte_len();
        if n > 0 {
            let mut inb = [0u8; MAX_IMAGE];
            if let Some(b) = inb.get_mut(..n) {
                self.inputs.pack(&self.store, b);
                self.esc.write(self.layout.pd_in, b)?;
            }
        }
        Ok(())
    }
}

/// The object dictionary as the CoE server sees it: the store plus the
/// device's rules (state-dependent access, assignment consistency).
struct OdAccess<'a, E: Esc, P: PowerStage, N: NvStorage> {
    slave: &'a mut Slave<E, P, N>,
    state: AlState,
}

impl<E: Esc, P: PowerStage, N: NvStorage> ObjectAccess for OdAccess<'_, E, P, N> {
    fn sdo_upload(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        out: &mut [u8],
    ) -> Result<usize, SdoAbortCode> {
        if complete_access {
            return complete::upload(&self.slave.store, index, sub, out);
        }
        self.slave.store.upload(index, sub, out)
    }

    fn sdo_download(
        &mut self,
        index: u16,
        sub: u8,
        complete_access: bool,
        data: &[u8],
    ) -> Result<(), SdoAbortCode> {
        if complete_access {
            return self.complete_download(index, sub, data);
        }
        let (flat, entry) = store::lookup(index, sub)?;
        let value = ObjectStore::check(entry, data, self.state)?;
        // 0xF801: PASSWORD unlocks (or with 0 locks) the manufacturer
        // settings; SAVE / DEFAULT / LOADBACK run when written with 1.
        if index == 0xF801 {
            if sub == 1 {
                self.slave.unlocked = match value as u32 {
                    VENDOR_PASSWORD => true,
                    0 => false,
                    _ => {
                        self.slave.unlocked = false;
                        return Err(SdoAbortCode::ValueRange);
                    }
                };
                return Ok(());
            }
            if value != 1 {
                return Err(SdoAbortCode::ValueRange);
            }
            return self.slave.command(sub);
        }
        // 0xF80F manufacturer settings need the vendor password first.
        if index == 0xF80F && !self.slave.unlocked {
            return Err(SdoAbortCode::UnsupportedAccess);
        }
        // F800:02 FUNCTION changes the process image: PRE-OP only, and it
        // selects the matching extended PDO assignment.
        if index == 0xF800 && sub == 2 {
            if self.state != AlState::PreOp {
                return Err(SdoAbortCode::InvalidState);
            }
            self.slave.store.set_value(flat, value);
            let mode = function_mode(&self.slave.store);
            select_assignment(&mut self.slave.store, mode);
            return Ok(());
        }
        // Manual 6.4.5: with ACC = ON the controller gains follow the PWM
        // frequency and cannot be set by the user.
        if matches!(index, 0x800D | 0x801D | 0x802D)
            && matches!(sub, 9 | 10)
            && self.slave.store.get(index, 7) == Some(1)
        {
            return Err(SdoAbortCode::LocalControl);
        }
        // The assignment may only name PDOs of its own direction, and the
        // assigned PDOs (subindices 1..=count) must all belong to one mode.
        if index == 0x1C12 || index == 0x1C13 {
            let count = if sub == 0 {
                value
            } else {
                self.slave.store.get(index, 0).unwrap_or(0)
            };
            let pdo_at = |s: u8| -> u16 {
                if s == sub {
                    value as u16
                } else {
                    self.slave.store.get(index, s).unwrap_or(0) as u16
                }
            };
            let mut mode = None;
            for s in 1..=count.clamp(0, 255) as u8 {
                if let Some(m) = crate::pdo::pdo_mode(pdo_at(s)) {
                    if mode.is_some_and(|x| x != m) {
                        return Err(SdoAbortCode::ParameterIncompatible);
                    }
                    mode = Some(m);
                }
            }
        }
        if (index == 0x1C12 || index == 0x1C13) && sub != 0 {
            let dir = if index == 0x1C12 {
                Direction::Outputs
            } else {
                Direction::Inputs
            };
            let (lo, hi) = dir.pdo_range();
            let pdo = value as u16;
            if pdo < lo || pdo > hi || model::find(pdo).is_none() {
                return Err(SdoAbortCode::ValueRange);
            }
        }
        if (index == 0x1C12 || index == 0x1C13) && sub == 0 {
            let cap = model::find(index).map_or(0, |(_, o)| o.max_sub());
            if value > i64::from(cap) {
                return Err(SdoAbortCode::ValueTooHigh);
            }
        }
        self.slave.store.set_value(flat, value);
        Ok(())
    }
}

impl<E: Esc, P: PowerStage, N: NvStorage> OdAccess<'_, E, P, N> {
    /// Complete download: every member checked first, then all applied.
    fn complete_download(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbortCode> {
        if index == 0xF801 {
            // Commands and the password are written one at a time.
            return Err(SdoAbortCode::CompleteAccessNotSupported);
        }
        if index == 0xF80F && !self.slave.unlocked {
            return Err(SdoAbortCode::UnsupportedAccess);
        }
        let changes = complete::check_download(&self.slave.store, index, sub, data, self.state)?;
        let new_value = |s: u8| -> Option<i64> {
            let (flat, _) = model::find_entry(index, s)?;
            changes.iter().find(|(f, _)| *f == flat).map(|(_, v)| *v)
        };
        if index == 0x1C12 || index == 0x1C13 {
            let dir = if index == 0x1C12 {
                Direction::Outputs
            } else {
                Direction::Inputs
            };
            let (lo, hi) = dir.pdo_range();
            let count = new_value(0).or(self.slave.store.get(index, 0)).unwrap_or(0);
            let mut mode = None;
            for s in 1..=count.clamp(0, 255) as u8 {
                let pdo = new_value(s).or(self.slave.store.get(index, s)).unwrap_or(0) as u16;
                if pdo < lo || pdo > hi || model::find(pdo).is_none() {
                    return Err(SdoAbortCode::ValueRange);
                }
                if let Some(m) = crate::pdo::pdo_mode(pdo) {
                    if mode.is_some_and(|x| x != m) {
                        return Err(SdoAbortCode::ParameterIncompatible);
                    }
                    mode = Some(m);
                }
            }
        }
        if matches!(index, 0x800D | 0x801D | 0x802D) {
            let acc = new_value(7).or(self.slave.store.get(index, 7)) == Some(1);
            let gains_change = [9u8, 10]
                .iter()
                .any(|s| new_value(*s).is_some_and(|v| Some(v) != self.slave.store.get(index, *s)));
            if acc && gains_change {
                return Err(SdoAbortCode::LocalControl);
            }
        }
        let old_mode = function_mode(&self.slave.store);
        if index == 0xF800 {
            let new_mode = match new_value(2) {
                Some(2) => PdoMode::Independent,
                Some(_) => PdoMode::Directional,
                None => old_mode,
            };
            if new_mode != old_mode && self.state != AlState::PreOp {
                return Err(SdoAbortCode::InvalidState);
            }
        }
        for (flat, value) in changes {
            self.slave.store.set_value(flat, value);
        }
        let mode = function_mode(&self.slave.store);
        if mode != old_mode {
            select_assignment(&mut self.slave.store, mode);
        }
        Ok(())
    }
}

/// The PAM-199 on the software ESC: takes EtherCAT frames.
pub struct SoftSlave {
    inner: Slave<SoftEsc, SimPowerStage, MemNv<STORAGE_SIZE>>,
    port1_link: bool,
    stalled: bool,
    now_ns: u64,
}

impl core::fmt::Debug for SoftSlave {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.inner.fmt(f)
    }
}

impl Default for SoftSlave {
    fn default() -> Self {
        Self::new()
    }
}

impl SoftSlave {
    /// A slave in its power-on state with the device's SII image.
    pub fn new() -> Self {
        let sii = sii_image();
        SoftSlave {
            inner: Slave::new(SoftEsc::new(&sii), SimPowerStage::new(), MemNv::new()),
            port1_link: false,
            stalled: false,
            now_ns: 0,
        }
    }

    /// A slave whose standard mailboxes have another layout (the SII it
    /// serves says so, so masters configure SM0/SM1 accordingly).
    pub fn with_layout(layout: MemoryLayout) -> Self {
        let sii = sii_image_for(&layout);
        let mut inner = Slave::new(SoftEsc::new(&sii), SimPowerStage::new(), MemNv::new());
        inner.set_layout(layout);
        SoftSlave {
            inner,
            port1_link: false,
            stalled: false,
            now_ns: 0,
        }
    }

    /// A power cycle: ESC, firmware and power stage restart; the parameter
    /// storage (EEPROM) keeps what was saved.
    pub fn power_cycle(&mut self) {
        let nv = core::mem::take(self.inner.nv_mut());
        let layout = self.inner.layout;
        let sii = sii_image_for(&layout);
        self.inner = Slave::new(SoftEsc::new(&sii), SimPowerStage::new(), nv);
        self.inner.set_layout(layout);
        self.inner.esc.set_port1_link(self.port1_link);
    }

    /// Passes an Ethernet frame through the ESC (in place).
    pub fn process_frame(&mut self, frame: &mut [u8]) -> FrameOutcome {
        self.inner.esc.process_frame(frame)
    }

    /// Runs the ESC's watchdogs and then the firmware once. A PDI failure
    /// (only possible here when injected with
    /// [`SoftEsc::set_pdi_fault`]) puts the firmware in its fail-safe state
    /// (see [`Slave::poll_with`]) and is returned. While the firmware is
    /// stalled ([`SoftSlave::set_stalled`]) only the ESC runs; once its PDI
    /// watchdog expires the outputs go to the safe state.
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
        self.inner.esc.update_watchdogs(now_ns);
        if self.stalled {
            if self.inner.esc.pdi_watchdog_expired() {
                self.inner.stage.disable();
            }
            return Ok(());
        }
        let result = self.inner.poll_with(now_ns, images);
        // Stamp the firmware's PDI accesses with the time they happened.
        self.inner.esc.update_watchdogs(now_ns);
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
    pub fn led_patterns(&self) -> (crate::led::LedPattern, crate::led::LedPattern) {
        self.inner
            .led_patterns(self.inner.esc.pdi_watchdog_expired())
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
        self.inner.esc.set_port1_link(link);
    }

    /// The firmware.
    pub fn slave(&self) -> &Slave<SoftEsc, SimPowerStage, MemNv<STORAGE_SIZE>> {
        &self.inner
    }

    /// The firmware, mutably.
    pub fn slave_mut(&mut self) -> &mut Slave<SoftEsc, SimPowerStage, MemNv<STORAGE_SIZE>> {
        &mut self.inner
    }
}
