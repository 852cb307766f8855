//! Board support: the core's and the devices' hardware traits implemented
//! on the C functions of [`crate::ffi`]. Every type here is zero-sized;
//! the state lives on the C side (ESC, EEPROM, flash), as on a real board.

use ecat_slave::esc::{Esc, EscError};
use ecat_slave::firmware::{BootState, ImageStore, STATE_RECORD_LEN, Slot, StoreError};
use ecat_slave::hal::{NvError, NvStorage};
use ecat_slave::params::STORAGE_SIZE;

use crate::ffi;

/// The ESC reached over SPI (a LAN9252 / ET1100 PDI): `spi_read` and
/// `spi_write` of the C side.
#[derive(Debug, Clone, Copy, Default)]
pub struct SpiEsc;

impl Esc for SpiEsc {
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EscError> {
        // SAFETY (FFI call with a pointer): `buf` is a valid, writable
        // region of `buf.len()` bytes for the whole call; the C side writes
        // at most `len` bytes there and keeps no pointer.
        let rc = unsafe { ffi::spi_read(addr, buf.as_mut_ptr(), buf.len()) };
        if rc == 0 {
            Ok(())
        } else {
            Err(EscError::Interface)
        }
    }

    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EscError> {
        // SAFETY (FFI call with a pointer): `data` is valid for reads of
        // `data.len()` bytes for the whole call; the C side only reads it.
        let rc = unsafe { ffi::spi_write(addr, data.as_ptr(), data.len()) };
        if rc == 0 {
            Ok(())
        } else {
            Err(EscError::Interface)
        }
    }
}

/// The ESC bus at byte level (`spi_begin` / `spi_transfer` / `spi_end` of
/// the C side) as an `embedded-hal` SPI device with chip select, for the
/// ET1100 driver of `ecat-esc-spi` (`--features spi-et1100`).
#[cfg(any(feature = "spi-et1100", feature = "spi-lan9252"))]
#[derive(Debug, Clone, Copy, Default)]
pub struct FfiSpi;

#[cfg(any(feature = "spi-et1100", feature = "spi-lan9252"))]
impl embedded_hal::spi::ErrorType for FfiSpi {
    type Error = embedded_hal::spi::ErrorKind;
}

#[cfg(any(feature = "spi-et1100", feature = "spi-lan9252"))]
impl embedded_hal::spi::SpiDevice for FfiSpi {
    fn transaction(
        &mut self,
        operations: &mut [embedded_hal::spi::Operation<'_, u8>],
    ) -> Result<(), Self::Error> {
        use core::ptr::{null, null_mut};
        use embedded_hal::spi::Operation;
        ffi::spi_begin();
        for op in operations {
            // SAFETY (FFI calls with pointers): each pointer comes from a
            // live slice of at least the length passed (or is null, which
            // the C side treats as "send 0x00" / "drop"); the C side keeps
            // no pointer after the call.
            unsafe {
                match op {
                    Operation::Read(r) => ffi::spi_transfer(null(), r.as_mut_ptr(), r.len()),
                    Operation::Write(w) => ffi::spi_transfer(w.as_ptr(), null_mut(), w.len()),
                    Operation::Transfer(r, w) => {
                        let n = r.len().min(w.len());
                        ffi::spi_transfer(w.as_ptr(), r.as_mut_ptr(), n);
                        if let Some(rest) = r.get_mut(n..) {
                            ffi::spi_transfer(null(), rest.as_mut_ptr(), rest.len());
                        }
                        if let Some(rest) = w.get(n..) {
                            ffi::spi_transfer(rest.as_ptr(), null_mut(), rest.len());
                        }
                    }
                    Operation::TransferInPlace(b) => {
                        let p = b.as_mut_ptr();
                        ffi::spi_transfer(p, p, b.len());
                    }
                    Operation::DelayNs(_) => {}
                }
            }
        }
        if ffi::spi_end() == 0 {
            Ok(())
        } else {
            Err(embedded_hal::spi::ErrorKind::Other)
        }
    }
}

/// The parameter EEPROM (`nv_read` / `nv_write`), [`STORAGE_SIZE`] bytes.
#[derive(Debug, Clone, Copy, Default)]
pub struct EepromNv;

impl EepromNv {
    fn check(offset: usize, len: usize) -> Result<(), NvError> {
        match offset.checked_add(len) {
            Some(end) if end <= STORAGE_SIZE => Ok(()),
            _ => Err(NvError::OutOfRange {
                offset,
                len,
                capacity: STORAGE_SIZE,
            }),
        }
    }
}

impl NvStorage for EepromNv {
    fn capacity(&self) -> usize {
        STORAGE_SIZE
    }

    fn read(&self, offset: usize, buf: &mut [u8]) -> Result<(), NvError> {
        Self::check(offset, buf.len())?;
        // SAFETY (FFI call with a pointer): `buf` is valid for writes of
        // `buf.len()` bytes during the call; the C side keeps no pointer.
        let rc = unsafe { ffi::nv_read(offset, buf.as_mut_ptr(), buf.len()) };
        if rc == 0 {
            Ok(())
        } else {
            Err(NvError::Interrupted)
        }
    }

    fn write(&mut self, offset: usize, data: &[u8]) -> Result<(), NvError> {
        Self::check(offset, data.len())?;
        // SAFETY (FFI call with a pointer): `data` is valid for reads of
        // `data.len()` bytes during the call; the C side only reads it.
        let rc = unsafe { ffi::nv_write(offset, data.as_ptr(), data.len()) };
        if rc == 0 {
            Ok(())
        } else {
            Err(NvError::Interrupted)
        }
    }
}

/// The A/B image flash for FoE firmware updates (`flash_*`): two slots and
/// two copies of the boot-state record.
#[derive(Debug, Clone, Copy, Default)]
pub struct FlashStore;

fn slot_id(slot: Slot) -> u8 {
    match slot {
        Slot::A => 0,
        Slot::B => 1,
    }
}

fn store_rc(rc: i32) -> Result<(), StoreError> {
    if rc == 0 { Ok(()) } else { Err(StoreError::Io) }
}

impl FlashStore {
    /// Both boot-state copies as stored.
    /// (Into the caller's buffer: returned in a `Result`, the 192 bytes
    /// were copied once more on the stack.)
    fn state_copies(copies: &mut [[u8; STATE_RECORD_LEN]; 2]) -> Result<(), StoreError> {
        for (n, copy) in (0u8..).zip(copies.iter_mut()) {
            // SAFETY (FFI call with a pointer): `copy` is a valid, writable
            // array of STATE_RECORD_LEN bytes during the call.
            store_rc(unsafe { ffi::flash_state_read(n, copy.as_mut_ptr(), copy.len()) })?;
        }
        Ok(())
    }
}

impl ImageStore for FlashStore {
    fn slot_capacity(&self) -> usize {
        ffi::flash_slot_capacity()
    }

    fn erase(&mut self, slot: Slot) -> Result<(), StoreError> {
        store_rc(ffi::flash_erase(slot_id(slot)))
    }

    fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError> {
        let end = offset.checked_add(data.len());
        if end.is_none_or(|e| e > self.slot_capacity()) {
            return Err(StoreError::OutOfBounds);
        }
        // SAFETY (FFI call with a pointer): `data` is valid for reads of
        // `data.len()` bytes during the call; the C side only reads it.
        store_rc(unsafe { ffi::flash_write(slot_id(slot), offset, data.as_ptr(), data.len()) })
    }

    fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError> {
        if offset > self.slot_capacity() {
            return Err(StoreError::OutOfBounds);
        }
        // SAFETY (FFI call with a pointer): `buf` is valid for writes of
        // `buf.len()` bytes during the call; the C side writes at most that.
        let n = unsafe { ffi::flash_read(slot_id(slot), offset, buf.as_mut_ptr(), buf.len()) };
        usize::try_from(n)
            .ok()
            .filter(|n| *n <= buf.len())
            .ok_or(StoreError::Io)
    }

    fn read_state(&self) -> Result<BootState, StoreError> {
        let mut copies = [[0u8; STATE_RECORD_LEN]; 2];
        Self::state_copies(&mut copies)?;
        let [a, b] = &copies;
        BootState::read_bank([a, b])
            .map(|(_, s)| s)
            .ok_or(StoreError::NoState)
    }

    fn write_state(&mut self, state: &BootState) -> Result<(), StoreError> {
        let mut copies = [[0u8; STATE_RECORD_LEN]; 2];
        Self::state_copies(&mut copies)?;
        let [a, b] = &copies;
        let (index, record) = BootState::bank_write([a, b], state);
        let copy = u8::try_from(index).map_err(|_| StoreError::Io)?;
        // SAFETY (FFI call with a pointer): `record` is a valid array of
        // STATE_RECORD_LEN bytes during the call; the C side only reads it.
        store_rc(unsafe { ffi::flash_state_write(copy, record.as_ptr(), record.len()) })
    }
}

/// The IO8 on GPIO pins (`board_inputs` / `board_set_outputs`).
#[cfg(feature = "io8")]
pub mod io8 {
    use crate::ffi;

    /// The IO8's eight inputs and eight outputs.
    #[derive(Debug, Clone, Copy, Default)]
    pub struct GpioBoard;

    impl io8_example::Board for GpioBoard {
        fn inputs(&mut self) -> u8 {
            ffi::board_inputs()
        }

        fn set_outputs(&mut self, bits: u8) {
            ffi::board_set_outputs(bits);
        }
    }

    /// The application of the firmware.
    pub type App = io8_example::Io8<GpioBoard, super::EepromNv>;
}

/// The IO8 on its board.
#[cfg(feature = "io8")]
pub fn new_app() -> io8::App {
    io8_example::Io8::new(io8::GpioBoard, EepromNv)
}

/// The PAM's power stage driven through `stage_*`.
#[cfg(feature = "pam")]
pub mod pam {
    use pam_199_p_etc::board::{Dither, Faults, PiGains, PowerStage, Solenoid};

    use crate::ffi;

    /// The solenoid power stage of the PAM board.
    #[derive(Debug, Clone, Copy, Default)]
    pub struct Stage;

    fn id(s: Solenoid) -> u8 {
        match s {
            Solenoid::A => 0,
            Solenoid::B => 1,
        }
    }

    impl PowerStage for Stage {
        fn set_current(
            &mut self,
            solenoid: Solenoid,
            setpoint_ma: u16,
            dither: Dither,
            pwm_hz: u16,
            gains: PiGains,
        ) {
            ffi::stage_set_current(
                id(solenoid),
                setpoint_ma,
                dither.amplitude_ma,
                dither.freq_hz,
                pwm_hz,
                gains.ppwm,
                gains.ipwm,
            );
        }

        fn disable(&mut self) {
            ffi::stage_disable();
        }

        fn measured_ma(&self, solenoid: Solenoid) -> u16 {
            ffi::stage_measured_ma(id(solenoid))
        }

        fn faults(&self) -> Faults {
            let f = ffi::stage_faults();
            let bit = |n: u8| f & (1 << n) != 0;
            Faults {
                open_a: bit(0),
                short_a: bit(1),
                open_b: bit(2),
                short_b: bit(3),
                undervoltage: bit(4),
                overvoltage: bit(5),
                overtemperature: bit(6),
            }
        }

        fn step(&mut self, dt_us: u32) {
            ffi::stage_step(dt_us);
        }
    }

    /// The application of the firmware.
    pub type App = pam_199_p_etc::Pam<Stage, super::EepromNv>;
}

/// The PAM on its board.
#[cfg(feature = "pam")]
pub fn new_app() -> pam::App {
    pam_199_p_etc::Pam::new(pam::Stage, EepromNv)
}
