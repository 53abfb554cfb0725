//! Results files: JSON Lines, one [`Record`] per scenario, appended and flushed as each finishes so a
//! killed batch keeps what it finished.

use crate::scenario::{Check, Kind};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// How a scenario ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Every expectation met.
    Passed,
    /// Every expectation met, but a metric moved past its tolerance against the baseline
    /// (`regressions` says which).
    Regressed,
    /// Some expectation not met.
    Failed,
    /// The state became non-finite (and the scenario expected it not to).
    Diverged,
    /// The scenario could not be run (a file it needs is missing or broken).
    Error,
}

/// One scenario's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    pub name: String,
    /// The scenario (or sweep) file.
    pub file: String,
    /// The scenario's content hash (see [`crate::scenario::Scenario::hash`]).
    pub hash: String,
    /// Every file the scenario read, with the digest of its content (see
    /// [`crate::scenario::inputs`]): what `--resume` names when a scenario changed.
    #[serde(default)]
    pub inputs: std::collections::BTreeMap<String, String>,
    pub kind: Kind,
    pub seed: Option<u32>,
    /// Position in the batch's expanded, name-sorted scenario list, and the list's length.
    pub index: usize,
    pub total: usize,
    /// [I, N]: the slice of the list this result was run in (`--shard I/N`).
    pub shard: [usize; 2],
    pub hexsim_version: String,
    pub status: Status,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    pub wall_time_s: f64,
    pub steps: u64,
    pub steps_per_second: f64,
    /// The run's metrics (see `hexsim run --metrics`); null when the scenario could not run.
    pub metrics: serde_json::Value,
    pub expectations: Vec<Check>,
    /// The metrics that moved past their tolerance against the baseline (`batch --baseline`):
    /// each with the baseline's value, this run's and the change allowed. Empty without a
    /// baseline, or when nothing moved.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regressions: Vec<super::baseline::Regression>,
    /// Where the run came from: the block a metrics file ends with (robot, terrain, gait, dt,
    /// articulation, …), so that a record read alone says what it measured. Absent in results
    /// written before it existed, or for a scenario that could not be set up.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metadata: Option<Box<crate::record::metadata::Metadata>>,
}

impl Record {
    /// The record without what varies from run to run (wall time, speed): two runs of the same
    /// scenario on the same build give equal results.
    pub fn result(&self) -> Record {
        Record {
            wall_time_s: 0.0,
            steps_per_second: 0.0,
            ..self.clone()
        }
    }
}

/// A results file that cannot be read.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {message}")]
pub struct ResultsError {
    pub file: PathBuf,
    pub message: String,
}

/// Reads a results file. `lenient`: skip lines that do not parse (a line cut off when a batch was
/// killed) and return how many; otherwise such a line is an error naming it.
pub fn read(path: &Path, lenient: bool) -> Result<(Vec<Record>, usize), ResultsError> {
    let fail = |message: String| ResultsError {
        file: path.to_path_buf(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
        fail(format!(
            "line {line}: not UTF-8 text (byte {} of the file); a hexsim results file is JSON Lines",
            valid.len() + 1
        ))
    })?;
    let mut records = Vec::new();
    let mut skipped = 0;
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<Record>(line) {
            Ok(r) => records.push(r),
            Err(_) if lenient => skipped += 1,
            Err(e) => {
                return Err(fail(format!(
                    "line {}: not a hexsim result record: {e}",
                    i + 1
                )));
            }
        }
    }
    Ok((records, skipped))
}

/// Writes records as JSON Lines to a temporary name and renames it into place.
pub fn write_all(path: &Path, records: &[Record]) -> anyhow::Result<()> {
    let mut text = String::new();
    for r in records {
        text.push_str(&serde_json::to_string(r)?);
        text.push('\n');
    }
    crate::record::output::write_atomically(path, text.as_bytes())
}

/// Appends records to a results file, one line each, flushed at once.
pub struct Appender {
    file: std::fs::File,
    path: PathBuf,
}

impl Appender {
    pub fn open(path: &Path) -> anyhow::Result<Self> {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| anyhow::anyhow!("{}: cannot write results: {e}", path.display()))?;
        Ok(Appender {
            file,
            path: path.to_path_buf(),
        })
    }

    pub fn append(&mut self, record: &Record) -> anyhow::Result<()> {
        let mut line = serde_json::to_string(record)?;
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| anyhow::anyhow!("{}: cannot write results: {e}", self.path.display()))
    }
}

#[cfg(test)]
mod tests {
    /// Results read back (merge, resume, baselines) and optimisation logs replayed must hold the
    /// very numbers that were written. serde_json's default float parser may be one ulp off; this
    /// value, a ball's final height from `scenarios/ball_bell.toml`, was (`hexsim merge` changed
    /// it) until the `float_roundtrip` feature was turned on.
    #[test]
    fn a_tail_that_is_not_utf8_is_named_by_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("results.jsonl");
        std::fs::write(&path, b"{}\n\xff\xfe\n").unwrap();
        let e = super::read(&path, true).unwrap_err().to_string();
        assert!(
            e.contains("results.jsonl") && e.contains("line 2: not UTF-8"),
            "{e}"
        );
    }

    #[test]
    fn numbers_read_back_bit_for_bit() {
        for value in [
            -0.9205063581466675_f64,
            0.1 + 0.2,
            1e-300,
            6.02214076e23,
            -2.5e-8,
        ] {
            let text = serde_json::to_string(&value).unwrap();
            let back: f64 = serde_json::from_str(&text).unwrap();
            assert_eq!(
                back.to_bits(),
                value.to_bits(),
                "{text} read back as {back:e}"
            );
        }
    }
}
