//! An observer on its own thread: the step loop hands it a copy of each logged sample and goes on,
//! so encoding a recording (rerun's arrow conversion, ~0.3 ms a sample) is off the hot path.
//! The samples arrive in order, so what is written is the same as when observed in the loop.

use anyhow::{Result, anyhow};
use std::path::PathBuf;
use std::sync::mpsc::{SyncSender, sync_channel};
use std::thread::JoinHandle;

/// Samples in flight before the step loop waits for the writer.
const QUEUE: usize = 256;

pub struct Background<M: Send + 'static> {
    sender: SyncSender<M>,
    writer: JoinHandle<Result<PathBuf>>,
}

impl<M: Send + 'static> Background<M> {
    /// Starts a thread that gives every message to `observe` and, when the loop is done, calls
    /// `finish` (which names the file written). The first error stops it; it is reported by
    /// [`Self::finish`], or by [`Self::send`] once the thread has stopped.
    pub fn spawn<S: Send + 'static>(
        mut sink: S,
        mut observe: impl FnMut(&mut S, M) -> Result<()> + Send + 'static,
        finish: impl FnOnce(S) -> Result<PathBuf> + Send + 'static,
    ) -> Self {
        let (sender, receiver) = sync_channel::<M>(QUEUE);
        let writer = std::thread::spawn(move || {
            for message in receiver {
                observe(&mut sink, message)?;
            }
            finish(sink)
        });
        Background { sender, writer }
    }

    /// Hands a message to the writer (waits if it is `QUEUE` messages behind).
    pub fn send(&self, message: M) -> Result<()> {
        self.sender
            .send(message)
            .map_err(|_| anyhow!("the recording's writer stopped"))
    }

    /// Waits for the writer to write everything sent; its file, or its first error.
    pub fn finish(self) -> Result<PathBuf> {
        drop(self.sender);
        self.writer
            .join()
            .map_err(|_| anyhow!("the recording's writer panicked"))?
    }
}
