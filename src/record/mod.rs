//! Observers of the step loop: the rerun recording, the trajectory CSV, the summary metrics and
//! the progress report. Physics hands each step's sample to the observers and knows nothing of
//! what they write; each observer decides which samples it keeps and owns its output file.

pub mod background;
pub mod ball;
pub mod blueprint;
pub mod camera;
pub mod hexapod;
pub mod links;
pub mod output;
pub mod progress;
pub mod rerun;
pub mod standing;
pub mod table;

use std::path::PathBuf;

/// A step's state, as observers see it.
pub trait Sample {
    /// Steps taken when the sample was made (0: the state before the first step).
    fn step(&self) -> u64;
}

impl Sample for crate::sim::WalkSample {
    fn step(&self) -> u64 {
        self.robot.step
    }
}

impl Sample for crate::sim::BallSample {
    fn step(&self) -> u64 {
        self.step
    }
}

/// Something that watches a run step by step. `S` is the sample; `W` the simulation after the
/// step, for what the sample does not carry (a walk's link poses).
pub trait Observer<S, W: ?Sized> {
    /// Sees one step's sample (an observer keeps what it wants of them: see [`decimation`]).
    fn observe(&mut self, sample: &S, world: &W) -> anyhow::Result<()>;

    /// Called once after the last sample; `complete` is false when the run stopped early. Writes
    /// what is pending, so the file holds the run as far as it went, and names the file.
    fn finish(&mut self, complete: bool) -> anyhow::Result<Option<PathBuf>>;
}

/// Steps between logged samples for a wanted rate (Hz) at step `dt` (at least every step).
pub fn decimation(rate_hz: f64, dt: f64) -> u64 {
    if rate_hz <= 0.0 {
        u64::MAX
    } else {
        ((1.0 / (rate_hz * dt)).round() as u64).max(1)
    }
}
