//! Standard output that a closed pipe cannot crash, and the stop request
//! (Ctrl-C or a closed pipe) that long commands poll.
//!
//! `master-test demo | head -1` closes the pipe after one line: Rust's
//! `println!` would then panic (exit 101). [`line`] instead notes the
//! closed pipe, asks running commands to stop in order, and the tool ends
//! with status 0.

use std::fmt;
use std::io::Write as _;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};

static PIPE_CLOSED: AtomicBool = AtomicBool::new(false);
static STOP: AtomicBool = AtomicBool::new(false);
/// 0: no long command runs (Ctrl-C ends the process at once); 1: a long
/// command polls [`stop_requested`]; 2: it has been asked to stop once.
static LONG_COMMAND: AtomicU8 = AtomicU8::new(0);

/// Prints one line to standard output; a closed pipe ends output quietly.
macro_rules! outln {
    () => { $crate::output::line(format_args!("")) };
    ($($t:tt)*) => { $crate::output::line(format_args!($($t)*)) };
}
pub(crate) use outln;

/// Writes one line (see [`outln!`]).
pub fn line(args: fmt::Arguments<'_>) {
    let mut text = fmt::format(args);
    text.push('\n');
    bytes(text.as_bytes());
}

/// Writes raw bytes to standard output (binary output to a pipe or
/// file); a closed pipe ends output quietly.
pub fn bytes(b: &[u8]) {
    if PIPE_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(b).and_then(|()| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            PIPE_CLOSED.store(true, Ordering::Relaxed);
            STOP.store(true, Ordering::Relaxed);
        } else {
            eprintln!("error: cannot write to standard output: {e}");
            STOP.store(true, Ordering::Relaxed);
        }
    }
}

/// Whether the reader of standard output went away.
pub fn pipe_closed() -> bool {
    PIPE_CLOSED.load(Ordering::Relaxed)
}

/// Whether a long command should stop now (Ctrl-C, or nobody reads its
/// output any more).
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// Marks the start of a long command: from now on the first Ctrl-C asks
/// it to stop in order (it polls [`stop_requested`]); a second one ends
/// the process at once.
pub fn long_command() {
    LONG_COMMAND.store(1, Ordering::Relaxed);
}

/// Installs the Ctrl-C handler. Outside long commands Ctrl-C ends the
/// process at once with status 130 (nothing has been changed that needs
/// undoing: short commands are single mailbox exchanges).
pub fn install_ctrlc() {
    let _ = ctrlc::set_handler(|| match LONG_COMMAND.load(Ordering::Relaxed) {
        1 => {
            LONG_COMMAND.store(2, Ordering::Relaxed);
            STOP.store(true, Ordering::Relaxed);
            eprintln!("\nCtrl-C: stopping in order (press again to quit at once)");
        }
        _ => {
            eprintln!("\ninterrupted");
            std::process::exit(i32::from(device_catalog::exit::Exit::Interrupted.status()));
        }
    });
}
