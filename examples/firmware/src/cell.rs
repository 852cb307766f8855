//! A `static` holding the firmware object, handed out as `&mut` to one
//! caller at a time.
//!
//! `core` has no mutex, and a `static` must be `Sync`, so a plain `static`
//! of the (non-`Sync`, mutable) firmware needs a small wrapper: an atomic
//! "busy" flag guards an `UnsafeCell`. A second caller while one holds it
//! (an interrupt calling `fw_poll` inside `fw_poll`) gets `None` instead of
//! a second `&mut`. On a core without compare-and-swap (Cortex-M0) the
//! same guard would be a critical section.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

/// A value in a `static`, reached by one caller at a time.
pub struct FwCell<T> {
    busy: AtomicBool,
    value: UnsafeCell<Option<T>>,
}

// SAFETY (`unsafe impl Sync`): the value is only reached through `with`,
// which gives out a `&mut` to one caller at a time (the `busy` flag, taken
// with an atomic compare-exchange and released after the call). Handing the
// value to whichever thread holds the flag needs `T: Send`.
unsafe impl<T: Send> Sync for FwCell<T> {}

impl<T> FwCell<T> {
    /// An empty cell (`None`), usable as a `static` initialiser.
    pub const fn new() -> Self {
        FwCell {
            busy: AtomicBool::new(false),
            value: UnsafeCell::new(None),
        }
    }

    /// Runs `f` on the value; `None` if the value is in use (re-entry).
    pub fn with<R>(&self, f: impl FnOnce(&mut Option<T>) -> R) -> Option<R> {
        if self
            .busy
            .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            return None;
        }
        // SAFETY (dereferencing the `UnsafeCell` pointer): the flag was
        // clear and is now ours, so no other reference to the value exists
        // until we clear it below; the reference does not outlive `f`. A
        // panic aborts (panic = "abort"), so no unwinding path can leave
        // the flag set while a reference escapes.
        let value = unsafe { &mut *self.value.get() };
        let r = f(value);
        self.busy.store(false, Ordering::Release);
        Some(r)
    }
}
