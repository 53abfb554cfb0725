//! An observer on its own thread: the step loop hands it a message made from each kept sample and
//! goes on, so encoding a recording (rerun's arrow conversion, ~0.3 ms a sample) is off the hot
//! path. The messages arrive in order, so what is written is the same as when observed in the
//! loop.

use super::{Observer, Sample};
use anyhow::{Result, anyhow};
use std::path::PathBuf;
use std::sync::mpsc::{SyncSender, sync_channel};
use std::thread::JoinHandle;

/// Messages in flight before the step loop waits for the writer.
const QUEUE: usize = 256;

/// Keeps every `every`-th sample, turns it into a message with `message` (a copy of what the
/// writer needs) and hands it to the writer thread.
pub struct Background<S, W: ?Sized, M: Send + 'static> {
    every: u64,
    message: fn(&S, &W) -> M,
    sender: Option<SyncSender<M>>,
    writer: Option<JoinHandle<Result<PathBuf>>>,
}

impl<S, W: ?Sized, M: Send + 'static> Background<S, W, M> {
    /// Starts a thread that gives every message to `observe` and, when the loop is done, calls
    /// `finish` (which names the file written). The first error stops it; it is reported by
    /// [`Observer::finish`], or by [`Observer::observe`] once the thread has stopped.
    pub fn spawn<Sink: Send + 'static>(
        every: u64,
        message: fn(&S, &W) -> M,
        mut sink: Sink,
        mut observe: impl FnMut(&mut Sink, M) -> Result<()> + Send + 'static,
        finish: impl FnOnce(Sink) -> Result<PathBuf> + Send + 'static,
    ) -> Self {
        let (sender, receiver) = sync_channel::<M>(QUEUE);
        let writer = std::thread::spawn(move || {
            for message in receiver {
                observe(&mut sink, message)?;
            }
            finish(sink)
        });
        Background {
            every,
            message,
            sender: Some(sender),
            writer: Some(writer),
        }
    }
}

impl<S: Sample, W: ?Sized, M: Send + 'static> Observer<S, W> for Background<S, W, M> {
    /// Hands a kept sample to the writer (waits if it is `QUEUE` messages behind).
    fn observe(&mut self, sample: &S, world: &W) -> Result<()> {
        if !sample.step().is_multiple_of(self.every) {
            return Ok(());
        }
        let sender = self
            .sender
            .as_ref()
            .ok_or_else(|| anyhow!("the recording is already finished"))?;
        sender
            .send((self.message)(sample, world))
            .map_err(|_| anyhow!("the recording's writer stopped"))
    }

    /// Waits for the writer to write everything sent; its file, or its first error.
    fn finish(&mut self, _complete: bool) -> Result<Option<PathBuf>> {
        drop(self.sender.take());
        match self.writer.take() {
            Some(writer) => writer
                .join()
                .map_err(|_| anyhow!("the recording's writer panicked"))?
                .map(Some),
            None => Ok(None),
        }
    }
}
