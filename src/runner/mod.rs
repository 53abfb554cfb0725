//! Runs: a set-up (terrain, body, contact, duration) → world → step loop → observers → files.
//! This is where simulation and recording meet; neither knows the other.

pub mod ball;
pub mod step_loop;
pub mod walk;
pub mod watchdog;

pub use crate::interrupt::{INTERRUPTED, interrupted};

pub use crate::record::{Output, Outputs};

/// A failed run's error: what happened and every file the run still wrote.
pub fn failure_error(message: &str, written: &[std::path::PathBuf]) -> anyhow::Error {
    let files: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    let files = if files.is_empty() {
        "none".to_string()
    } else {
        files.join(", ")
    };
    anyhow::anyhow!("{message} (files written: {files})")
}
