//! Ctrl-C and SIGTERM: a flag the signal handler sets and every long stage reads — the step loop
//! (it stops at the next step), terrain generation, a batch, compare, optimize — so an
//! interruption ends the command within moments, exit code 130. Below every other module, so
//! each can read it.

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by a signal handler to stop a run early; the run then writes what it has, marked incomplete.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::Relaxed)
}

/// The message of work cut short by an interruption (an error with it is exit code 130).
pub const MESSAGE: &str = "interrupted (Ctrl-C or SIGTERM)";
