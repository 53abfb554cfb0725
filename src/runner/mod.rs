//! Runs: a set-up (terrain, body, contact, duration) → world → step loop → observers → files.
//! This is where simulation and recording meet; neither knows the other.

pub mod ball;
pub mod step_loop;
pub mod walk;
pub mod watchdog;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set by a signal handler to stop a run early; the run then writes what it has, marked incomplete.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::Relaxed)
}

/// Files a run writes besides its results, and whom it tells how far it is.
#[derive(Default)]
pub struct Outputs {
    pub record: Option<PathBuf>,
    pub trajectory: Option<PathBuf>,
    pub metrics: Option<PathBuf>,
    /// Called now and then with the steps done so far.
    pub progress: Option<Box<dyn Fn(u64)>>,
}

impl Outputs {
    /// Checks, before a simulation starts, that every file can be written.
    fn check_writable(&self) -> anyhow::Result<()> {
        for path in [&self.record, &self.trajectory, &self.metrics]
            .into_iter()
            .flatten()
        {
            crate::record::output::check_writable(path)?;
        }
        Ok(())
    }
}

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
