//! The C functions the board support calls: provided by `harness.c` for
//! the measurement, by the board's C drivers on real hardware. Every
//! signature here matches a definition in `harness.c`.
//!
//! Return codes: 0 (or a byte count) on success, negative on failure.
// Each device uses a subset of the board functions (the IO8 no power stage,
// the PAM no GPIO), the empty baseline none.
#![allow(dead_code)]

// SAFETY (`unsafe extern`): the compiler cannot check foreign signatures;
// each declaration below matches its C definition in harness.c. Functions
// that take and return only plain values cannot break Rust's memory safety
// whatever they do, so they are declared `safe fn`; the ones taking
// pointers stay `unsafe` to call and are wrapped in board.rs, which passes
// valid slices only.
unsafe extern "C" {
    /// Reads `len` bytes of ESC memory at `addr` into `buf` (SPI read).
    pub fn spi_read(addr: u16, buf: *mut u8, len: usize) -> i32;
    /// Writes `len` bytes from `data` into ESC memory at `addr` (SPI write).
    pub fn spi_write(addr: u16, data: *const u8, len: usize) -> i32;

    /// SPI bus, byte level (the `spi-et1100` build): chip select asserted.
    pub safe fn spi_begin();
    /// Clocks `len` bytes: sends `mosi[i]` (0x00 when `mosi` is null) and
    /// stores what comes back in `miso[i]` (dropped when `miso` is null).
    /// `mosi` and `miso` may be the same buffer (byte i is sent before
    /// byte i is stored).
    pub fn spi_transfer(mosi: *const u8, miso: *mut u8, len: usize);
    /// Chip select released; 0, or negative when the access failed.
    pub safe fn spi_end() -> i32;

    /// IO8: the input pins (bit n: input n + 1 high).
    pub safe fn board_inputs() -> u8;
    /// IO8: drives the output pins (bit n: output n + 1 on).
    pub safe fn board_set_outputs(bits: u8);

    /// PAM: current setpoint for solenoid 0 (A) or 1 (B) with dither,
    /// PWM frequency and controller gains.
    pub safe fn stage_set_current(
        solenoid: u8,
        setpoint_ma: u16,
        dither_ma: u16,
        dither_hz: u16,
        pwm_hz: u16,
        ppwm: u16,
        ipwm: u16,
    );
    /// PAM: both outputs off.
    pub safe fn stage_disable();
    /// PAM: measured current of solenoid 0 (A) or 1 (B), mA.
    pub safe fn stage_measured_ma(solenoid: u8) -> u16;
    /// PAM: fault flags (bit 0 open A, 1 short A, 2 open B, 3 short B,
    /// 4 undervoltage, 5 overvoltage, 6 overtemperature).
    pub safe fn stage_faults() -> u8;
    /// PAM: time passed, µs (a real stage runs its own control loop).
    pub safe fn stage_step(dt_us: u32);

    /// Parameter EEPROM: reads `len` bytes at `offset`.
    pub fn nv_read(offset: usize, buf: *mut u8, len: usize) -> i32;
    /// Parameter EEPROM: writes `len` bytes at `offset`.
    pub fn nv_write(offset: usize, data: *const u8, len: usize) -> i32;

    /// Image flash: size of one of the two image slots in bytes.
    pub safe fn flash_slot_capacity() -> usize;
    /// Image flash: erases slot 0 (A) or 1 (B).
    pub safe fn flash_erase(slot: u8) -> i32;
    /// Image flash: programs `len` bytes at `offset` of a slot.
    pub fn flash_write(slot: u8, offset: usize, data: *const u8, len: usize) -> i32;
    /// Image flash: reads up to `len` bytes at `offset` of a slot; returns
    /// the count (short at the end of the slot) or a negative error.
    pub fn flash_read(slot: u8, offset: usize, buf: *mut u8, len: usize) -> isize;
    /// Boot state: reads copy 0 or 1 of the boot-state record.
    pub fn flash_state_read(copy: u8, buf: *mut u8, len: usize) -> i32;
    /// Boot state: writes copy 0 or 1 of the boot-state record.
    pub fn flash_state_write(copy: u8, data: *const u8, len: usize) -> i32;

    /// Stops the firmware for good (called by the panic handler).
    safe fn fw_halt() -> !;
}

/// Stops the firmware (panic).
pub fn halt() -> ! {
    fw_halt()
}
