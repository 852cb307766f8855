//! A `static` holding the firmware object, handed out as `&mut` to one
//! caller at a time.
//!
//! `core` has no mutex, and a `static` must be `Sync`, so a plain `static`
//! of the (non-`Sync`, mutable) firmware needs a small wrapper: an atomic
//! state guards an `UnsafeCell`. A second caller while one holds it (an
//! interrupt calling `fw_poll` inside `fw_poll`) gets `None` instead of a
//! second `&mut`. On a core without compare-and-swap (Cortex-M0) the same
//! guard would be a critical section.
//!
//! The value is a `MaybeUninit` rather than an `Option`: an `Option` of the
//! firmware is `None` through a niche somewhere inside it, so its initial
//! image is not all zeros and the whole object (kilobytes) would land in
//! `.data`, costing its size twice on a microcontroller (flash for the
//! initial image, RAM for the copy). Uninitialised, it lands in `.bss`.

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicU8, Ordering};

/// No value yet.
const EMPTY: u8 = 0;
/// A value, not in use.
const READY: u8 = 1;
/// In use by a caller (initialised or not, see `with`).
const BUSY: u8 = 2;

/// A value in a `static`, built at run time, reached by one caller at a
/// time.
pub struct FwCell<T> {
    state: AtomicU8,
    value: UnsafeCell<MaybeUninit<T>>,
}

// SAFETY (`unsafe impl Sync`): the value is only reached through `init` and
// `with`, which take the state to BUSY with an atomic compare-exchange
// first, so at most one caller has a reference at any time. Handing the
// value to whichever thread holds it needs `T: Send`.
unsafe impl<T: Send> Sync for FwCell<T> {}

impl<T> FwCell<T> {
    /// An empty cell, usable as a `static` initialiser (all `.bss`).
    pub const fn new() -> Self {
        FwCell {
            state: AtomicU8::new(EMPTY),
            value: UnsafeCell::new(MaybeUninit::uninit()),
        }
    }

    /// Builds the value in place with `make`, which must initialise the
    /// slot it is given and return it (`MaybeUninit::write`, or a
    /// constructor such as `Slave::init_in` that writes there): the value
    /// is never built on the stack and copied. A value stored before is
    /// dropped first. `false` if the value is in use (re-entry), or if
    /// `make` returned a reference to anything but its slot (the cell then
    /// stays empty).
    pub fn init(&self, make: impl FnOnce(&mut MaybeUninit<T>) -> &mut T) -> bool {
        let Ok(before) = self.take(&[EMPTY, READY]) else {
            return false;
        };
        // SAFETY (access through the `UnsafeCell` pointer): `take` moved
        // the state to BUSY, so no other reference to the value exists
        // until the state is released below. The old value is dropped only
        // if the state said it was initialised (READY).
        let slot = unsafe { &mut *self.value.get() };
        if before == READY {
            // SAFETY (`assume_init_drop`): READY means `slot` holds a
            // value written by an earlier `init`.
            unsafe { slot.assume_init_drop() };
        }
        let at = slot.as_mut_ptr();
        // A `&mut T` into the slot exists only once the slot is
        // initialised (safe code gets one only from `MaybeUninit::write`),
        // so a returned reference to the slot proves it holds a value.
        let built = core::ptr::eq(make(slot), at);
        self.state
            .store(if built { READY } else { EMPTY }, Ordering::Release);
        built
    }

    /// Runs `f` on the value: `None` before `init` or while the value is
    /// in use (re-entry).
    pub fn with<R>(&self, f: impl FnOnce(&mut T) -> R) -> Option<R> {
        self.take(&[READY]).ok()?;
        // SAFETY (access through the `UnsafeCell` pointer and
        // `assume_init_mut`): the state was READY, so the value is
        // initialised, and `take` moved it to BUSY, so no other reference
        // exists until the state is released below; the reference does not
        // outlive `f`. A panic aborts (panic = "abort"), so no unwinding
        // path can leave a reference behind.
        let value = unsafe { (*self.value.get()).assume_init_mut() };
        let r = f(value);
        self.state.store(READY, Ordering::Release);
        Some(r)
    }

    /// Moves the state from one of `from` to BUSY; returns the old state.
    fn take(&self, from: &[u8]) -> Result<u8, ()> {
        for &s in from {
            if self
                .state
                .compare_exchange(s, BUSY, Ordering::Acquire, Ordering::Relaxed)
                .is_ok()
            {
                return Ok(s);
            }
        }
        Err(())
    }
}
