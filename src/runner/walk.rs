//! A hexapod run end to end: robot + terrain + gait + contact → walker → step loop → recording,
//! CSV, metrics.

use super::Outputs;
use super::step_loop::{self, Stepper};
use super::watchdog::Watchdog;
use crate::contact::ContactModel;
use crate::gait::{CommandSchedule, Fitted, GaitController};
use crate::metrics::{GroundMetrics, HexapodMetrics, StanceMetrics};
use crate::record::hexapod::{HexapodRecorder, HexapodTrajectory};
use crate::record::progress::Progress;
use crate::record::{Observer, decimation};
use crate::robot::RobotModel;
use crate::sim::{Articulation, Hexapod, HexapodSettings, Placement, WalkSample, Walker};
use crate::terrain::HeightGrid;
use anyhow::Result;
use std::path::PathBuf;
use std::sync::Arc;

/// Everything a walking run needs.
pub struct WalkRun {
    pub robot: Arc<RobotModel>,
    pub terrain: Arc<HeightGrid>,
    pub terrain_name: String,
    /// The gait on the robot, with how it fits (reported in the metrics).
    pub gait: Fitted,
    /// The velocity commands over the walk.
    pub commands: CommandSchedule,
    pub contact: ContactModel,
    /// The contact's stiffness and damping and where they came from, for the metrics.
    pub ground: GroundMetrics,
    pub settings: HexapodSettings,
    pub placement: Placement,
    /// Seconds standing before the gait starts.
    pub settle_time: f64,
    /// Keep the body level by following the terrain under the feet.
    pub terrain_following: bool,
    /// Seconds walked.
    pub duration: f64,
    /// Samples per second in the recording and trajectory.
    pub log_rate: f64,
    pub outputs: Outputs,
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

/// The walker following its velocity commands, watched for divergence.
struct Walking {
    walker: Walker,
    commands: CommandSchedule,
    watchdog: Watchdog,
}

impl Stepper for Walking {
    type Sample = WalkSample;
    type World = Walker;

    fn step(&mut self) -> WalkSample {
        let command = self.commands.at(self.walker.gait_time().max(0.0));
        self.walker.set_command(command);
        self.walker.step()
    }

    fn world(&self) -> &Walker {
        &self.walker
    }

    fn diverged(&self, sample: &WalkSample) -> Option<String> {
        self.watchdog.check_walk(&sample.robot)
    }
}

impl WalkRun {
    /// Runs the set-up, which [`crate::scenario::Scenario::resolve`] has checked field by field
    /// (every command builds its runs from a scenario).
    pub fn execute(self) -> Result<WalkOutcome> {
        self.outputs.check_writable()?;
        let controller = GaitController::new(&self.robot, self.gait.gait.clone())
            .map_err(|e| anyhow::anyhow!("gait {}: {e}", self.gait.gait.name))?;
        let pose = self.robot.pose_from_legs(&controller.standing_angles());
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

        let mut observers: Vec<Box<dyn Observer<WalkSample, Walker>>> = Vec::new();
        if let Some(path) = &self.outputs.record {
            let name = match self.settings.articulation {
                Articulation::Multibody => {
                    format!("{} on {}", self.gait.gait.name, self.terrain_name)
                }
                Articulation::Impulse => format!(
                    "{} on {} (impulse joints)",
                    self.gait.gait.name, self.terrain_name
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
            observers.push(Box::new(recorder.in_background(self.robot.clone())));
        }
        if let Some(path) = &self.outputs.trajectory {
            observers.push(Box::new(HexapodTrajectory::create(
                path,
                &self.robot,
                every,
            )?));
        }
        if let Some(progress) = self.outputs.progress {
            observers.push(Box::new(Progress::new(progress)));
        }
        // last: its file is written once the others are complete
        let mut metrics = HexapodMetrics::new(
            dt,
            self.robot.total_mass(),
            self.robot
                .joints
                .iter()
                .map(|j| (j.lower, j.upper))
                .collect(),
            self.outputs.metrics.clone(),
        )
        .on_terrain(self.terrain.x_range(), self.terrain.y_range());
        metrics.stance = StanceMetrics::of(&self.gait, &self.robot);
        metrics.ground = self.ground.clone();

        let steps = ((self.settle_time + self.duration) / dt).round() as u64;
        let mut walking = Walking {
            walker,
            commands: self.commands,
            watchdog: Watchdog::walk(
                &self.robot,
                self.contact.normal,
                dt,
                crate::sim::STANDARD_GRAVITY,
            ),
        };
        let mut list: Vec<&mut dyn Observer<WalkSample, Walker>> =
            observers.iter_mut().map(|o| o.as_mut() as _).collect();
        list.push(&mut metrics);
        let end = step_loop::run(&mut walking, steps, &mut list)?;
        Ok(WalkOutcome {
            steps_per_second: end.steps as f64 / end.seconds.max(1e-9),
            physics_seconds: walking.walker.hexapod().physics_seconds(),
            metrics,
            written: end.written,
            failure: end.failure,
        })
    }
}
