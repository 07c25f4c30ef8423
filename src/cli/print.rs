//! Printing that never panics: `println!` panics when standard output is a closed pipe
//! (`dbuffer inspect ... | head -1`), `eprintln!` when standard error fails.
//!
//! - Standard output: when the reader goes away (EPIPE) the rest of the output is dropped
//!   silently and the command carries on, so that the files it was asked to write are still
//!   written, and exits 0, as `head` expects of the commands it reads. Any other error (a full
//!   disk behind `> file`) is kept and reported once at the end: one line, exit status 1.
//! - Standard error: errors are ignored (there is nowhere left to report them).

use std::fmt;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Standard output is gone (its reader closed it, or writing failed).
static STDOUT_GONE: AtomicBool = AtomicBool::new(false);
/// The first error writing to standard output that was not a closed pipe.
static STDOUT_ERROR: Mutex<Option<io::Error>> = Mutex::new(None);

/// Writes to standard output; see the module documentation for what happens on errors.
pub fn out(args: fmt::Arguments) {
    if STDOUT_GONE.load(Ordering::Relaxed) {
        return;
    }
    let mut stdout = io::stdout().lock();
    if let Err(e) = stdout.write_fmt(args).and_then(|()| stdout.flush()) {
        gone(e);
    }
}

/// Writes to standard error, ignoring errors.
pub fn err(args: fmt::Arguments) {
    let _ = io::stderr().lock().write_fmt(args);
}

fn gone(e: io::Error) {
    STDOUT_GONE.store(true, Ordering::Relaxed);
    if e.kind() != io::ErrorKind::BrokenPipe {
        if let Ok(mut first) = STDOUT_ERROR.lock() {
            first.get_or_insert(e);
        }
    }
}

/// Flushes standard output; the first error writing to it that was not a closed pipe.
pub fn finish() -> Result<(), io::Error> {
    if !STDOUT_GONE.load(Ordering::Relaxed) {
        if let Err(e) = io::stdout().lock().flush() {
            gone(e);
        }
    }
    match STDOUT_ERROR.lock() {
        Ok(mut first) => first.take().map_or(Ok(()), Err),
        Err(_) => Ok(()),
    }
}
