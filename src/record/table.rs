//! The trajectory as a table of numbers, a row per logged sample: written to a CSV file (under a
//! temporary name, renamed when finished) or kept in memory for the caller ([`SharedTable`]:
//! compare and optimize draw their recordings from it). Both hold the same numbers: the CSV
//! writes each as the shortest text that reads back to it.

use super::output::{commit, partial_path};
use super::{Observer, Sample};
use anyhow::{Context, Result, anyhow};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

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
        writer
            .write_record(values.iter().map(|v| v.to_string()))
            .with_context(|| format!("cannot write the trajectory {}", self.path.display()))?;
        Ok(())
    }

    /// Writes what is pending and moves the file to its name (once; later calls do nothing).
    pub fn finish(&mut self) -> Result<Option<PathBuf>> {
        let Some(mut writer) = self.writer.take() else {
            return Ok(None);
        };
        writer
            .flush()
            .with_context(|| format!("cannot write the trajectory {}", self.path.display()))?;
        drop(writer);
        commit(&self.path)?;
        Ok(Some(self.path.clone()))
    }
}

/// A trajectory in memory: its columns by name and its rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// The index of column `name`; an error, not a silent NaN, when the run has no such column.
    pub fn column(&self, name: &str) -> Result<usize> {
        self.columns
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| anyhow!("the trajectory has no column {name:?}"))
    }
}

/// A [`Table`] filled by a run and read by whoever gave it: clone it into
/// [`super::Output::Table`], run, then [`SharedTable::take`].
#[derive(Clone, Default)]
pub struct SharedTable(Arc<Mutex<Table>>);

impl SharedTable {
    pub fn new() -> Self {
        Self::default()
    }

    /// The rows so far, leaving the table empty.
    pub fn take(&self) -> Table {
        std::mem::take(&mut *self.lock())
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Table> {
        // a run that panicked while holding it left whole rows: they are still the trajectory
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Where a tabulated trajectory's rows go.
pub(crate) enum Sink {
    Csv(Box<CsvTable>),
    Memory(SharedTable),
}

/// A sample's numbers, in the order of its kind's columns (see [`super::Scene`]).
pub type RowOf<S> = fn(&S, &mut Vec<f64>);

/// The trajectory observer: every `every`-th sample as a row, in a file or in memory.
pub(crate) struct Tabulated<S> {
    sink: Sink,
    every: u64,
    row_of: RowOf<S>,
    row: Vec<f64>,
}

impl<S> Tabulated<S> {
    /// Starts the table with its header (a CSV's first line; a memory table's columns).
    pub(crate) fn new(mut sink: Sink, columns: Vec<String>, every: u64, row_of: RowOf<S>) -> Self {
        if let Sink::Memory(shared) = &mut sink {
            *shared.lock() = Table {
                columns,
                rows: Vec::new(),
            };
        }
        Tabulated {
            sink,
            every,
            row_of,
            row: Vec::new(),
        }
    }

    /// A CSV file at `path`.
    pub(crate) fn csv(
        path: &Path,
        columns: Vec<String>,
        every: u64,
        row_of: RowOf<S>,
    ) -> Result<Self> {
        let table = CsvTable::create(path, &columns)?;
        Ok(Self::new(
            Sink::Csv(Box::new(table)),
            columns,
            every,
            row_of,
        ))
    }
}

impl<S: Sample, W: ?Sized> Observer<S, W> for Tabulated<S> {
    fn observe(&mut self, sample: &S, _: &W) -> Result<()> {
        if !sample.step().is_multiple_of(self.every) {
            return Ok(());
        }
        self.row.clear();
        (self.row_of)(sample, &mut self.row);
        match &mut self.sink {
            Sink::Csv(table) => table.row(&self.row),
            Sink::Memory(shared) => {
                shared.lock().rows.push(self.row.clone());
                Ok(())
            }
        }
    }

    fn finish(&mut self, _complete: bool) -> Result<Option<PathBuf>> {
        match &mut self.sink {
            Sink::Csv(table) => table.finish(),
            Sink::Memory(_) => Ok(None),
        }
    }
}
