//! A CSV table of numbers, written under a temporary name and renamed when finished.

use super::output::{commit, partial_path};
use anyhow::{Context, Result, anyhow};
use std::path::{Path, PathBuf};

pub struct CsvTable {
    /// None once finished.
    writer: Option<csv::Writer<std::fs::File>>,
    path: PathBuf,
}

impl CsvTable {
    pub fn create<S: AsRef<str>>(path: &Path, header: impl IntoIterator<Item = S>) -> Result<Self> {
        let mut writer = csv::Writer::from_path(partial_path(path))
            .with_context(|| format!("cannot write the trajectory {}", path.display()))?;
        writer.write_record(header.into_iter().map(|h| h.as_ref().to_string()))?;
        Ok(CsvTable {
            writer: Some(writer),
            path: path.to_path_buf(),
        })
    }

    pub fn row(&mut self, values: &[f64]) -> Result<()> {
        let writer = self
            .writer
            .as_mut()
            .ok_or_else(|| anyhow!("{} is already finished", self.path.display()))?;
        writer.write_record(values.iter().map(|v| v.to_string()))?;
        Ok(())
    }

    /// Writes what is pending and moves the file to its name (once; later calls do nothing).
    pub fn finish(&mut self) -> Result<Option<PathBuf>> {
        let Some(mut writer) = self.writer.take() else {
            return Ok(None);
        };
        writer.flush()?;
        drop(writer);
        commit(&self.path)?;
        Ok(Some(self.path.clone()))
    }
}
