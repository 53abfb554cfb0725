//! The ball experiment end to end: terrain + ball + contact → step loop → recording, CSV, metrics.

use super::Outputs;
use super::step_loop::{self, Stepper};
use super::watchdog::Watchdog;
use crate::contact::ContactModel;
use crate::metrics::BallMetrics;
use crate::record::ball::BallScene;
use crate::record::{self, Observer, decimation};
use crate::sim::{BallConfig, BallSample, BallSim};
use crate::terrain::HeightGrid;
use anyhow::Result;
use std::path::PathBuf;
use std::sync::Arc;

/// Everything a ball run needs.
pub struct BallRun {
    pub ball: BallConfig,
    pub terrain: Arc<HeightGrid>,
    pub terrain_name: String,
    pub contact: ContactModel,
    pub dt: f64,
    pub duration: f64,
    /// Samples per second in the recording and trajectory.
    pub log_rate: f64,
    pub outputs: Outputs,
}

/// What a run produced.
/// A run that diverged still wrote its files; `failure` says what happened.
pub struct BallOutcome {
    pub metrics: BallMetrics,
    pub written: Vec<PathBuf>,
    pub steps_per_second: f64,
    pub failure: Option<String>,
}

/// The ball falling and rolling, watched for divergence.
struct Dropping {
    sim: BallSim,
    watchdog: Watchdog,
}

impl Stepper for Dropping {
    type Sample = BallSample;
    type World = BallSim;

    fn initial(&self) -> Option<BallSample> {
        Some(self.sim.sample())
    }

    fn step(&mut self) -> BallSample {
        self.sim.step()
    }

    fn world(&self) -> &BallSim {
        &self.sim
    }

    fn diverged(&self, sample: &BallSample) -> Option<String> {
        self.watchdog.check_ball(sample)
    }
}

impl BallRun {
    /// Runs the set-up, which the scenario layer has checked field by field when it resolved it
    /// (every command builds its runs from a scenario).
    pub fn execute(self) -> Result<BallOutcome> {
        let sim = BallSim::new(self.ball, self.terrain.clone(), self.contact, self.dt);
        let every = decimation(self.log_rate, self.dt);
        let initial = sim.sample();

        let scene = BallScene {
            name: format!("ball on {}", self.terrain_name),
            dt: self.dt,
            terrain: self.terrain.clone(),
            ball: self.ball,
            every,
        };
        let (mut observers, metrics_file) = record::observers(&scene, self.outputs)?;
        // last: its file is written once the others are complete
        let mut metrics = BallMetrics::new(&initial, self.ball.radius, metrics_file);

        let steps = (self.duration / self.dt).round() as u64;
        let mut dropping = Dropping {
            watchdog: Watchdog::ball(
                &initial,
                self.ball.radius,
                self.ball.mass,
                self.contact.normal,
                self.dt,
                self.ball.gravity,
            ),
            sim,
        };
        let mut list: Vec<&mut dyn Observer<BallSample, BallSim>> =
            observers.iter_mut().map(|o| o.as_mut() as _).collect();
        list.push(&mut metrics);
        let end = step_loop::run(&mut dropping, steps, &mut list)?;
        Ok(BallOutcome {
            steps_per_second: end.steps as f64 / end.seconds.max(1e-9),
            metrics,
            written: end.written,
            failure: end.failure,
        })
    }
}
