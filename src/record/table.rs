//! A CSV table of numbers, written under a temporary name and renamed when finished.

use super::output::{commit, partial_path};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

pub struct CsvTable {
    writer: csv::Writer<std::fs::File>,
    path: PathBuf,
}

impl CsvTable {
    pub fn create<S: AsRef<str>>(path: &Path, header: impl IntoIterator<Item = S>) -> Result<Self> {
        let mut writer = csv::Writer::from_path(partial_path(path))
            .with_context(|| format!("cannot write the trajectory {}", path.display()))?;
        writer.write_record(header.into_iter().map(|h| h.as_ref().to_string()))?;
        Ok(CsvTable {
            writer,
            path: path.to_path_buf(),
        })
    }

    pub fn row(&mut self, values: &[f64]) -> Result<()> {
        self.writer
            .write_record(values.iter().map(|v| v.to_string()))?;
        Ok(())
    }

    pub fn finish(mut self) -> Result<PathBuf> {
        self.writer.flush()?;
        drop(self.writer);
        commit(&self.path)?;
        Ok(self.path)
    }
}
