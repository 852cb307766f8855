//! # A `no_std` firmware of one device on the `ecat-slave` core
//!
//! What a real microcontroller firmware would link: the core, one device
//! (`--features io8` or `--features pam`) and board support that reaches
//! the hardware through C functions (the ESC over SPI, GPIO / the power
//! stage, EEPROM, image flash). The firmware object lives in a `static`, so
//! its RAM shows up in `.bss`/`.data` of the linked program like on a
//! microcontroller. The C harness (`harness.c`) provides the board
//! functions and `main`; `scripts/footprint.sh` links the two and measures
//! the result. Without a device feature the crate is the empty baseline
//! (the same entry points, doing nothing).
//!
//! Entry points (C ABI):
//!
//! * `int32_t fw_init(void)`: power-on; 0 on success.
//! * `int32_t fw_poll(uint64_t now_ns)`: one pass of the firmware loop
//!   (`Slave::poll_with`, FoE into the image flash); 0 on success, -1 when
//!   the PDI failed, -2 before `fw_init` or on re-entry.
//! * `fw_layout_t fw_layout(void)`: the device's ESC memory layout, for the
//!   harness's simulated master (a few bytes of code; a real firmware
//!   would not export it).
//!
//! `unsafe` is used only for the FFI (see the comments at each use); the
//! workspace crates stay `forbid(unsafe_code)`.
#![no_std]
#![deny(unsafe_op_in_unsafe_fn, missing_docs)]

#[cfg(all(feature = "io8", feature = "pam"))]
compile_error!("select one device: --features io8 or --features pam, not both");

#[cfg(any(feature = "io8", feature = "pam"))]
mod board;
#[cfg(any(feature = "io8", feature = "pam"))]
mod cell;
mod ffi;

#[cfg(any(feature = "io8", feature = "pam"))]
use cell::FwCell;

/// The memory layout of the device in ESC memory (start, length pairs),
/// as `fw_layout` returns it to C.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct FwLayout {
    /// Standard mailbox out (SM0): start.
    pub mbx_out_start: u16,
    /// Standard mailbox out (SM0): length.
    pub mbx_out_len: u16,
    /// Standard mailbox in (SM1): start.
    pub mbx_in_start: u16,
    /// Standard mailbox in (SM1): length.
    pub mbx_in_len: u16,
    /// Bootstrap mailbox out: start.
    pub boot_out_start: u16,
    /// Bootstrap mailbox out: length (0: no BOOT).
    pub boot_out_len: u16,
    /// Bootstrap mailbox in: start.
    pub boot_in_start: u16,
    /// Bootstrap mailbox in: length.
    pub boot_in_len: u16,
    /// Output process data (SM2) start.
    pub pd_out: u16,
    /// Input process data (SM3) start.
    pub pd_in: u16,
}

#[cfg(any(feature = "io8", feature = "pam"))]
mod device {
    use ecat_slave::device::{MemoryLayout, Slave};

    use crate::FwLayout;

    /// The ESC: the board's C SPI functions, or an SPI driver.
    #[cfg(not(any(feature = "spi-et1100", feature = "spi-lan9252")))]
    pub type Pdi = crate::board::SpiEsc;
    /// The ESC: the board's C SPI functions, or an SPI driver.
    #[cfg(feature = "spi-et1100")]
    pub type Pdi = ecat_esc_spi::et1100::Et1100Spi<crate::board::FfiSpi>;
    /// The ESC: the board's C SPI functions, or an SPI driver.
    #[cfg(all(feature = "spi-lan9252", not(feature = "spi-et1100")))]
    pub type Pdi = ecat_esc_spi::lan9252::Lan9252Spi<crate::board::FfiSpi>;

    fn pdi() -> Pdi {
        #[cfg(not(any(feature = "spi-et1100", feature = "spi-lan9252")))]
        {
            crate::board::SpiEsc
        }
        #[cfg(feature = "spi-et1100")]
        {
            ecat_esc_spi::et1100::Et1100Spi::new(crate::board::FfiSpi, Default::default())
        }
        #[cfg(all(feature = "spi-lan9252", not(feature = "spi-et1100")))]
        {
            // The start-up checks (byte test, ready) as a board runs them
            // before the firmware; their result is the first poll's.
            let mut esc = ecat_esc_spi::lan9252::Lan9252Spi::new(crate::board::FfiSpi);
            let _ = esc.init();
            esc
        }
    }

    #[cfg(feature = "io8")]
    pub use crate::board::io8::App;
    #[cfg(feature = "io8")]
    use io8_example::DEVICE;
    #[cfg(feature = "pam")]
    pub use crate::board::pam::App;
    #[cfg(feature = "pam")]
    use pam_199_p_etc::DEVICE;

    /// The largest mailbox and process image of the device, from its
    /// description.
    const MBX: usize = DEVICE.largest_mailbox();
    const IMAGE: (usize, usize) = DEVICE.largest_image();

    /// The whole firmware state: ESC handle, application, dictionary,
    /// mailbox servers, process images, with buffers sized for the device
    /// (`Slave`'s MBX, SDO, PDO and IMG: the largest mailbox, the largest
    /// object an SDO transfer carries, the entries and bytes of one
    /// direction's process image; all but SDO read from the description).
    /// `Slave::with_buffers` refuses sizes smaller than the description
    /// needs at `fw_init`.
    #[cfg(feature = "io8")]
    pub type Firmware = Slave<Pdi, App, MBX, 128, { IMAGE.0 }, { IMAGE.1 }>;
    /// The whole firmware state (see the IO8's).
    #[cfg(feature = "pam")]
    pub type Firmware = Slave<Pdi, App, MBX, 256, { IMAGE.0 }, { IMAGE.1 }>;

    const LAYOUT: MemoryLayout = DEVICE.layout();

    /// Whether the device offers the firmware update over FoE.
    pub const FOE: bool = DEVICE.mailbox.foe;

    pub const FW_LAYOUT: FwLayout = FwLayout {
        mbx_out_start: LAYOUT.mbx_out.0,
        mbx_out_len: LAYOUT.mbx_out.1,
        mbx_in_start: LAYOUT.mbx_in.0,
        mbx_in_len: LAYOUT.mbx_in.1,
        boot_out_start: LAYOUT.boot_out.0,
        boot_out_len: LAYOUT.boot_out.1,
        boot_in_start: LAYOUT.boot_in.0,
        boot_in_len: LAYOUT.boot_in.1,
        pd_out: LAYOUT.pd_out,
        pd_in: LAYOUT.pd_in,
    };

    /// The firmware object built and powered on in `slot` (its static).
    pub fn init(slot: &mut core::mem::MaybeUninit<Firmware>) -> &mut Firmware {
        Slave::init_in(slot, pdi(), crate::board::new_app())
    }
}

/// The firmware object: empty until `fw_init`; the cell hands out `&mut`
/// to one caller at a time (a nested call gets an error, not a second
/// `&mut`).
#[cfg(any(feature = "io8", feature = "pam"))]
static FIRMWARE: FwCell<device::Firmware> = FwCell::new();

/// Power-on: builds the firmware (dictionary at its defaults, saved
/// parameters loaded from the EEPROM) into its static. Returns 0, or -3 if
/// called from inside `fw_poll`.
// SAFETY (`no_mangle`): the C harness links against this exact symbol name;
// no other item in the program is called `fw_init`.
#[unsafe(no_mangle)]
pub extern "C" fn fw_init() -> i32 {
    #[cfg(any(feature = "io8", feature = "pam"))]
    {
        if FIRMWARE.init(device::init) { 0 } else { -3 }
    }
    #[cfg(not(any(feature = "io8", feature = "pam")))]
    {
        0
    }
}

/// One pass of the firmware loop at `now_ns` (monotonic): AL control,
/// mailbox (CoE, FoE into the image flash), process data, the application.
// SAFETY (`no_mangle`): the C harness links against this exact symbol name;
// no other item in the program is called `fw_poll`.
#[unsafe(no_mangle)]
pub extern "C" fn fw_poll(now_ns: u64) -> i32 {
    #[cfg(any(feature = "io8", feature = "pam"))]
    {
        FIRMWARE
            .with(|fw| {
                let mut flash = board::FlashStore;
                // A device without FoE gets no image store: the update's
                // code (FoE, the `.efw` check, the A/B store) is not linked.
                let images = device::FOE.then_some(&mut flash as &mut dyn ecat_slave::firmware::ImageStore);
                match fw.poll_with(now_ns, images) {
                    Ok(()) => 0,
                    Err(_) => -1,
                }
            })
            .unwrap_or(-2)
    }
    #[cfg(not(any(feature = "io8", feature = "pam")))]
    {
        let _ = now_ns;
        0
    }
}

/// The device's memory layout in ESC memory (all zero in the baseline).
// SAFETY (`no_mangle`): the C harness links against this exact symbol name;
// no other item in the program is called `fw_layout`.
#[unsafe(no_mangle)]
pub extern "C" fn fw_layout() -> FwLayout {
    #[cfg(any(feature = "io8", feature = "pam"))]
    {
        device::FW_LAYOUT
    }
    #[cfg(not(any(feature = "io8", feature = "pam")))]
    {
        FwLayout::default()
    }
}

/// A panic stops the firmware: the C side decides what that means (the
/// harness aborts so that a test run fails loudly; a real board would
/// switch its outputs off and reset through the watchdog).
#[panic_handler]
fn panic(_info: &core::panic::PanicInfo<'_>) -> ! {
    ffi::halt()
}
