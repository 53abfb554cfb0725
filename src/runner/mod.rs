//! Runs: a set-up (terrain, body, contact, duration) → world → step loop → observers → files.
//! This is where simulation and recording meet; neither knows the other.

pub mod ball;
pub mod walk;
pub mod watchdog;

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by a signal handler to stop a run early; the run then writes what it has, marked incomplete.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::Relaxed)
}

/// Writes the metrics (if asked for) after the recording and trajectory have been finished.
pub(crate) fn conclude(
    written: &mut Vec<std::path::PathBuf>,
    metrics_path: Option<&std::path::Path>,
    metrics: &impl serde::Serialize,
) -> anyhow::Result<()> {
    if let Some(path) = metrics_path {
        crate::record::output::write_atomically(
            path,
            serde_json::to_string_pretty(metrics)?.as_bytes(),
        )?;
        written.push(path.to_path_buf());
    }
    Ok(())
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
