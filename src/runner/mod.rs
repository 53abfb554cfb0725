//! Runs: a set-up (terrain, body, contact, duration) → world → step loop → observers → files.
//! This is where simulation and recording meet; neither knows the other.

pub mod ball;
pub mod walk;

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by a signal handler to stop a run early; the run then writes what it has, marked incomplete.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::Relaxed)
}
