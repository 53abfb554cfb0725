//! Observers of the step loop: the rerun recording, the trajectory (CSV or in memory), the
//! summary metrics and the progress report. Physics hands each step's sample to the observers
//! and knows nothing of what they write; each observer decides which samples it keeps and owns
//! its output file.
//!
//! A run is given its outputs as a list ([`Outputs`]); [`observers`] turns each into the observer
//! that writes it, for a walk or a ball alike (each kind says how it is drawn and tabulated: its
//! [`Scene`]). A new output is its observer's file and one line in [`observers`].

pub mod background;
pub mod ball;
pub mod blueprint;
pub mod camera;
pub mod hexapod;
pub mod joint_columns;
pub mod links;
pub mod mesh;
pub mod metadata;
pub mod output;
pub mod progress;
pub mod rerun;
pub mod standing;
pub mod table;

use anyhow::Result;
use metadata::{Metadata, MetricsFile};
use std::path::{Path, PathBuf};
use table::{RowOf, SharedTable, Sink, Tabulated};

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
pub trait Observer<S, W: ?Sized>: Send {
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

/// One thing a run writes, or hands back, as it steps.
pub enum Output {
    /// The rerun recording (.rrd): the scene in 3D and the plots.
    Recording(PathBuf),
    /// The trajectory as CSV: a row of numbers per logged sample.
    Trajectory(PathBuf),
    /// The same rows kept in memory, for the caller to read when the run has ended.
    Table(SharedTable),
    /// The metrics as JSON, written once every other output is complete.
    Metrics(PathBuf),
    /// Told now and then the steps done so far (a progress bar).
    Progress(Box<dyn Fn(u64) + Send>),
}

impl Output {
    /// The file this output writes, if it writes one.
    pub fn path(&self) -> Option<&Path> {
        match self {
            Output::Recording(p) | Output::Trajectory(p) | Output::Metrics(p) => Some(p),
            Output::Table(_) | Output::Progress(_) => None,
        }
    }
}

/// What a run is asked to write, in order (the files it wrote are named in this order).
#[derive(Default)]
pub struct Outputs(Vec<Output>, Option<Box<Metadata>>);

impl Outputs {
    pub fn new() -> Self {
        Self::default()
    }

    /// The list with `output` added.
    pub fn with(mut self, output: Output) -> Self {
        self.0.push(output);
        self
    }

    /// The list with `output` added if there is one (an optional flag's file).
    pub fn with_some(self, output: Option<Output>) -> Self {
        match output {
            Some(output) => self.with(output),
            None => self,
        }
    }

    /// The list, its metrics file ending with `metadata` (where the run came from).
    pub fn described(mut self, metadata: Metadata) -> Self {
        self.1 = Some(Box::new(metadata));
        self
    }

    /// The files of a run's command-line options: a recording, a trajectory CSV, a metrics
    /// JSON, each if given.
    pub fn files(
        record: Option<PathBuf>,
        trajectory: Option<PathBuf>,
        metrics: Option<PathBuf>,
    ) -> Self {
        Self::new()
            .with_some(record.map(Output::Recording))
            .with_some(trajectory.map(Output::Trajectory))
            .with_some(metrics.map(Output::Metrics))
    }

    /// The files of the list, each with what it is (for a message).
    pub fn named(&self) -> impl Iterator<Item = (&'static str, &Path)> {
        self.0.iter().filter_map(|output| match output {
            Output::Recording(p) => Some(("recording", p.as_path())),
            Output::Trajectory(p) => Some(("trajectory", p.as_path())),
            Output::Metrics(p) => Some(("metrics file", p.as_path())),
            Output::Table(_) | Output::Progress(_) => None,
        })
    }

    /// Checks, before a simulation starts, that every file can be written.
    pub fn check_writable(&self) -> Result<()> {
        for path in self.0.iter().filter_map(Output::path) {
            output::check_writable(path)?;
        }
        Ok(())
    }
}

/// What a kind of run (a walk, the ball) gives its outputs: how it is drawn and how a sample
/// reads as a row of numbers.
pub trait Scene {
    type Sample: Sample + 'static;
    type World: ?Sized + 'static;

    /// The rerun recording of this run at `path`.
    fn recorder(&self, path: &Path) -> Result<Box<dyn Observer<Self::Sample, Self::World>>>;

    /// The trajectory's columns, and how a sample fills a row of them.
    fn columns(&self) -> (Vec<String>, RowOf<Self::Sample>);

    /// Steps between logged samples (recording and trajectory).
    fn every(&self) -> u64;
}

/// The observers writing `outputs` of a run shown by `scene`, in the list's order, and the
/// metrics file, which the run's metrics write last (once the others are complete). Every file
/// is checked writable first, so a long run does not fail at its end.
#[allow(clippy::type_complexity)]
pub fn observers<S: Scene>(
    scene: &S,
    mut outputs: Outputs,
) -> Result<(
    Vec<Box<dyn Observer<S::Sample, S::World>>>,
    Option<MetricsFile>,
)> {
    outputs.check_writable()?;
    let mut list: Vec<Box<dyn Observer<S::Sample, S::World>>> = Vec::new();
    let mut metrics = None;
    for output in std::mem::take(&mut outputs.0) {
        match output {
            Output::Recording(path) => list.push(scene.recorder(&path)?),
            Output::Trajectory(path) => {
                let (columns, row) = scene.columns();
                list.push(Box::new(Tabulated::csv(
                    &path,
                    columns,
                    scene.every(),
                    row,
                )?));
            }
            Output::Table(shared) => {
                let (columns, row) = scene.columns();
                let sink = Sink::Memory(shared);
                list.push(Box::new(Tabulated::new(sink, columns, scene.every(), row)));
            }
            Output::Progress(report) => list.push(Box::new(progress::Progress::new(report))),
            Output::Metrics(path) => {
                metrics = Some(MetricsFile {
                    path,
                    metadata: outputs.1.clone(),
                })
            }
        }
    }
    Ok((list, metrics))
}
