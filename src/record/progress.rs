//! Progress of a run, for a progress bar: the steps done so far, now and then.

use super::{Observer, Sample};
use std::path::PathBuf;

/// Samples between two reports: often enough for a bar, rare enough to cost nothing.
const EVERY: u64 = 256;

/// Calls `report` with the steps done every [`EVERY`] steps and once at the end.
pub struct Progress {
    report: Box<dyn Fn(u64) + Send>,
    done: u64,
}

impl Progress {
    pub fn new(report: Box<dyn Fn(u64) + Send>) -> Self {
        Progress { report, done: 0 }
    }
}

impl<S: Sample, W: ?Sized> Observer<S, W> for Progress {
    fn observe(&mut self, sample: &S, _: &W) -> anyhow::Result<()> {
        self.done = sample.step();
        if self.done > 0 && self.done.is_multiple_of(EVERY) {
            (self.report)(self.done);
        }
        Ok(())
    }

    fn finish(&mut self, _complete: bool) -> anyhow::Result<Option<PathBuf>> {
        (self.report)(self.done);
        Ok(None)
    }
}
