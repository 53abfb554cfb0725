//! A hexapod run end to end: robot + terrain + gait + contact → walker → recording, CSV, metrics.

use crate::contact::ContactModel;
use crate::gait::{CommandSchedule, GaitController, GaitSpec};
use crate::record::background::Background;
use crate::record::hexapod::{HexapodMetrics, HexapodRecorder, HexapodTrajectory};
use crate::record::output::check_writable;
use crate::record::{Observer, decimation};
use crate::robot::RobotModel;
use crate::sim::{Articulation, Hexapod, HexapodSettings, Placement, WalkSample, Walker};
use crate::terrain::HeightGrid;
use anyhow::Result;
use glam::DAffine3;
use std::path::PathBuf;
use std::sync::Arc;

/// Everything a walking run needs.
pub struct WalkRun {
    pub robot: Arc<RobotModel>,
    pub terrain: Arc<HeightGrid>,
    pub terrain_name: String,
    pub gait: GaitSpec,
    /// The velocity commands over the walk.
    pub commands: CommandSchedule,
    pub contact: ContactModel,
    pub settings: HexapodSettings,
    pub placement: Placement,
    /// Seconds standing before the gait starts.
    pub settle_time: f64,
    /// Keep the body level by following the terrain under the feet.
    pub terrain_following: bool,
    /// Seconds walked.
    pub duration: f64,
    pub record: Option<PathBuf>,
    pub log_rate: f64,
    pub trajectory: Option<PathBuf>,
    pub metrics: Option<PathBuf>,
    /// Called now and then with the steps done so far, for a progress bar.
    pub progress: Option<Box<dyn Fn(u64)>>,
}

/// What a run produced. A run that diverged still wrote its files; `failure` says what happened.
pub struct WalkOutcome {
    pub metrics: HexapodMetrics,
    pub written: Vec<PathBuf>,
    pub steps_per_second: f64,
    /// Of the stepping's wall time, the seconds inside rapier's step.
    pub physics_seconds: f64,
    pub failure: Option<String>,
}

impl WalkRun {
    /// Runs the set-up, which [`crate::scenario::Scenario::resolve`] has checked field by field
    /// (every command builds its runs from a scenario).
    pub fn execute(self) -> Result<WalkOutcome> {
        for path in [&self.record, &self.trajectory, &self.metrics]
            .into_iter()
            .flatten()
        {
            check_writable(path)?;
        }
        let controller = GaitController::new(&self.robot, self.gait.clone())
            .map_err(|e| anyhow::anyhow!("gait {}: {e}", self.gait.name))?;
        let mut pose = vec![0.0; self.robot.joints.len()];
        for (leg, angles) in self.robot.legs.iter().zip(controller.standing_angles()) {
            for (j, a) in leg.joints.iter().zip(angles) {
                pose[*j] = a;
            }
        }
        let dt = self.settings.dt;
        let hexapod = Hexapod::new(
            self.robot.clone(),
            self.terrain.clone(),
            self.contact,
            self.settings,
            self.placement,
            &pose,
        );
        let mut walker = Walker::new(hexapod, controller, self.commands.at(0.0), self.settle_time);
        walker.terrain_following = self.terrain_following;
        let every = decimation(self.log_rate, dt);
        let mut metrics = HexapodMetrics::new(dt, self.robot.total_mass());
        let recorder = match &self.record {
            Some(path) => {
                let name = match self.settings.articulation {
                    Articulation::Multibody => {
                        format!("{} on {}", self.gait.name, self.terrain_name)
                    }
                    Articulation::Impulse => format!(
                        "{} on {} (impulse joints)",
                        self.gait.name, self.terrain_name
                    ),
                };
                let recorder = HexapodRecorder::create(
                    path,
                    name,
                    dt,
                    &self.terrain,
                    &self.robot,
                    every,
                    self.settings.articulation == Articulation::Impulse,
                )?;
                let robot = self.robot.clone();
                Some(Background::spawn(
                    recorder,
                    move |r, (sample, frames): (WalkSample, Vec<DAffine3>)| {
                        r.observe_with(&sample, &robot, &frames)
                    },
                    HexapodRecorder::finish,
                ))
            }
            None => None,
        };
        let mut trajectory = match &self.trajectory {
            Some(path) => Some(HexapodTrajectory::create(path, &self.robot, every)?),
            None => None,
        };
        let steps = ((self.settle_time + self.duration) / dt).round() as u64;
        let watchdog = super::watchdog::Watchdog::walk(
            &self.robot,
            self.contact.normal,
            dt,
            crate::sim::STANDARD_GRAVITY,
        );
        let started = std::time::Instant::now();
        let mut complete = true;
        let mut failure = None;
        for k in 0..steps {
            if super::interrupted() {
                complete = false;
                break;
            }
            walker.set_command(self.commands.at(walker.gait_time().max(0.0)));
            let sample = walker.step();
            if let Some(message) = watchdog.check_walk(&sample.robot) {
                complete = false;
                failure = Some(message);
                // the diverged step is still observed: the recording shows where it went wrong
                let _ = metrics.observe(&sample);
                if let Some(t) = trajectory.as_mut() {
                    let _ = t.observe(&sample);
                }
                break;
            }
            metrics.observe(&sample)?;
            if let Some(r) = &recorder
                && sample.robot.step.is_multiple_of(every)
                && r.send((sample.clone(), walker.hexapod().link_frames()))
                    .is_err()
            {
                break; // the writer failed: `finish` below reports why
            }
            if let Some(t) = trajectory.as_mut() {
                t.observe(&sample)?;
            }
            if let Some(progress) = &self.progress
                && k % 256 == 255
            {
                progress(k + 1);
            }
        }
        let elapsed = started.elapsed().as_secs_f64();
        metrics.complete = complete;
        metrics.set_clamped(walker.clamped_steps);
        let mut written = Vec::new();
        if let Some(r) = recorder {
            written.push(r.finish()?);
        }
        if let Some(t) = trajectory {
            written.push(t.finish()?);
        }
        super::conclude(&mut written, self.metrics.as_deref(), &metrics)?;
        Ok(WalkOutcome {
            steps_per_second: metrics.steps as f64 / elapsed.max(1e-9),
            physics_seconds: walker.hexapod().physics_seconds(),
            metrics,
            written,
            failure,
        })
    }
}
