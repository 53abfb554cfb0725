//! The ball experiment end to end: terrain + ball + contact → step loop → recording, CSV, metrics.

use crate::contact::ContactModel;
use crate::record::ball::{BallMetrics, BallRecorder, BallTrajectory};
use crate::record::output::check_writable;
use crate::record::{Observer, decimation};
use crate::sim::{BallConfig, BallSim};
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
    pub record: Option<PathBuf>,
    pub log_rate: f64,
    pub trajectory: Option<PathBuf>,
    pub metrics: Option<PathBuf>,
}

/// What a run produced.
/// A run that diverged still wrote its files; `failure` says what happened.
pub struct BallOutcome {
    pub metrics: BallMetrics,
    pub written: Vec<PathBuf>,
    pub steps_per_second: f64,
    pub failure: Option<String>,
}

impl BallRun {
    /// Runs the set-up, which [`crate::scenario::Scenario::resolve`] has checked field by field
    /// (every command builds its runs from a scenario).
    pub fn execute(&self) -> Result<BallOutcome> {
        for path in [&self.record, &self.trajectory, &self.metrics]
            .into_iter()
            .flatten()
        {
            check_writable(path)?;
        }
        let mut sim = BallSim::new(self.ball, self.terrain.clone(), self.contact, self.dt);
        let every = decimation(self.log_rate, self.dt);
        let initial = sim.sample();
        let mut metrics = BallMetrics::new(&initial, self.ball.radius);
        let mut recorder = match &self.record {
            Some(path) => Some(BallRecorder::create(
                path,
                format!("ball on {}", self.terrain_name),
                self.dt,
                &self.terrain,
                &self.ball,
                every,
            )?),
            None => None,
        };
        let mut trajectory = match &self.trajectory {
            Some(path) => Some(BallTrajectory::create(path, every)?),
            None => None,
        };
        let steps = (self.duration / self.dt).round() as u64;
        let watchdog = super::watchdog::Watchdog::ball(
            &initial,
            self.ball.radius,
            self.ball.mass,
            self.contact.normal,
            self.dt,
            self.ball.gravity,
        );
        let mut observe = |sample: &crate::sim::BallSample| -> Result<()> {
            metrics.observe(sample)?;
            if let Some(r) = recorder.as_mut() {
                r.observe(sample)?;
            }
            if let Some(t) = trajectory.as_mut() {
                t.observe(sample)?;
            }
            Ok(())
        };
        observe(&initial)?;
        let started = std::time::Instant::now();
        let mut complete = true;
        let mut failure = None;
        for _ in 0..steps {
            if super::interrupted() {
                complete = false;
                break;
            }
            let sample = sim.step();
            if let Some(message) = watchdog.check_ball(&sample) {
                complete = false;
                failure = Some(message);
                break;
            }
            observe(&sample)?;
        }
        metrics.complete = complete;
        let mut written = Vec::new();
        if let Some(r) = recorder {
            written.push(r.finish()?);
        }
        if let Some(t) = trajectory {
            written.push(t.finish()?);
        }
        super::conclude(&mut written, self.metrics.as_deref(), &metrics)?;
        Ok(BallOutcome {
            steps_per_second: metrics.steps as f64 / started.elapsed().as_secs_f64().max(1e-9),
            metrics,
            written,
            failure,
        })
    }
}
