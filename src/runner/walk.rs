//! A hexapod run end to end: robot + terrain + gait + contact → walker → step loop → recording,
//! CSV, metrics.

use super::Outputs;
use super::step_loop::{Looping, Stepper};
use super::watchdog::Watchdog;
use crate::contact::ContactModel;
use crate::gait::{CommandSchedule, Fitted, GaitController, VelocityCommand};
use crate::metrics::walk::fallen;
use crate::metrics::{GroundMetrics, HexapodMetrics, StanceMetrics};
use crate::record::hexapod::WalkScene;
use crate::record::{self, Observer, decimation};
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
    /// How the walker drives its legs, as the scenario's fields of the same names say.
    pub switches: WalkSwitches,
    /// End the walk when the robot falls (its body past
    /// [`FALL_TILT`](crate::metrics::walk::FALL_TILT) from upright, as the metrics' `fell_at`
    /// reads it): the run is complete there, its result decided.
    pub stop_at_fall: bool,
    /// Seconds walked.
    pub duration: f64,
    /// Samples per second in the recording and trajectory.
    pub log_rate: f64,
    pub outputs: Outputs,
}

/// How a walk drives its legs: the scenario's fields of the same names, with their defaults
/// ([`crate::scenario::ScenarioSpec::switches`]). A new one is a field here, read where it acts,
/// and its field in the scenario's spec.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WalkSwitches {
    /// Keep the body level by following the terrain under the feet.
    pub follow_terrain: bool,
    /// Move the feet's targets with their spheres' rolling (see [`crate::gait::controller`]).
    pub rolling_feet: bool,
    /// The reactive gait (see [`crate::gait`]'s `reactive`).
    pub reactive_gait: bool,
    /// Legs give way to more than three times the robot's weight (see [`crate::gait`]'s
    /// `compliance`).
    pub compliant_legs: bool,
    /// The body leans on slopes (see [`crate::gait`]'s `lean`).
    pub lean_on_slopes: bool,
    /// Hold the commanded heading against what turns the body (see [`crate::gait`]'s
    /// `heading`).
    pub hold_heading: bool,
    /// Hold the servo targets against the load (see [`Walker::load_feedforward`]).
    pub feedforward: bool,
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
    /// A command that replaces the schedule (a caller steering step by step).
    command: Option<VelocityCommand>,
    watchdog: Watchdog,
    /// See [`WalkRun::stop_at_fall`].
    stop_at_fall: bool,
}

impl Walking {
    /// Gives the walker this step's command: the caller's, or the schedule's.
    fn command_now(&mut self) {
        let command = self
            .command
            .unwrap_or_else(|| self.commands.at(self.walker.gait_time().max(0.0)));
        self.walker.set_command(command);
    }
}

impl Stepper for Walking {
    type Sample = WalkSample;
    type World = Walker;

    fn step(&mut self) -> WalkSample {
        self.command_now();
        self.walker.step()
    }

    fn step_into(&mut self, last: &mut Option<WalkSample>) {
        self.command_now();
        self.walker
            .step_into(last.get_or_insert_with(WalkSample::default));
    }

    fn world(&self) -> &Walker {
        &self.walker
    }

    fn diverged(&self, sample: &WalkSample) -> Option<String> {
        self.watchdog.check_walk(&sample.robot)
    }

    fn ended(&self, sample: &WalkSample) -> bool {
        // the metrics' test of a fall, on the same samples (settling's too: a robot set down
        // where it cannot stand falls before its walk)
        self.stop_at_fall && fallen(&sample.robot.body.matrix3)
    }
}

impl WalkRun {
    /// Runs the set-up, which the scenario layer has checked field by field when it resolved it
    /// (every command builds its runs from a scenario).
    pub fn execute(self) -> Result<WalkOutcome> {
        let mut session = self.start()?;
        session.advance(session.remaining());
        session.finish()
    }

    /// Builds the world and the outputs and stands the robot at its start, ready to step:
    /// [`WalkRun::execute`] is this, every planned step, and [`WalkSession::finish`].
    pub fn start(self) -> Result<WalkSession> {
        let controller = GaitController::new(&self.robot, self.gait.gait.clone())
            .map_err(|e| anyhow::anyhow!("gait {}: {e}", self.gait.gait.name))?
            .with_rolling_feet(self.switches.rolling_feet);
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
        walker.terrain_following = self.switches.follow_terrain;
        walker.load_feedforward = self.switches.feedforward;
        walker.reactive = self.switches.reactive_gait;
        walker.compliant = self.switches.compliant_legs;
        walker.lean = self.switches.lean_on_slopes;
        walker.hold_heading = self.switches.hold_heading;
        let every = decimation(self.log_rate, dt);

        let name = match self.settings.articulation {
            Articulation::Multibody => format!("{} on {}", self.gait.gait.name, self.terrain_name),
            Articulation::Impulse => format!(
                "{} on {} (impulse joints)",
                self.gait.gait.name, self.terrain_name
            ),
        };
        let scene = WalkScene {
            name,
            dt,
            terrain: self.terrain.clone(),
            robot: self.robot.clone(),
            every,
            joints_drift: self.settings.articulation == Articulation::Impulse,
        };
        let (observers, metrics_file) = record::observers(&scene, self.outputs)?;
        // last: its file is written once the others are complete
        let mut metrics = HexapodMetrics::new(
            dt,
            self.robot.total_mass(),
            self.robot
                .joints
                .iter()
                .map(|j| (j.lower, j.upper))
                .collect(),
            metrics_file,
        )
        .on_terrain(self.terrain.x_range(), self.terrain.y_range());
        metrics.stance = StanceMetrics::of(&self.gait, &self.robot);
        metrics.ground = self.ground.clone();

        let planned = ((self.settle_time + self.duration) / dt).round() as u64;
        let walking = Walking {
            walker,
            commands: self.commands,
            command: None,
            watchdog: Watchdog::walk(
                &self.robot,
                self.contact.normal,
                dt,
                crate::sim::STANDARD_GRAVITY,
            ),
            stop_at_fall: self.stop_at_fall,
        };
        let mut session = WalkSession {
            walking,
            observers,
            metrics,
            planned,
            looping: None,
        };
        let looping = {
            let (walking, mut list) = session.parts();
            Looping::begin(walking, &mut list)
        };
        session.looping = Some(looping);
        Ok(session)
    }
}

/// A walk being stepped a stretch at a time: the same world, observers and step loop as
/// [`WalkRun::execute`], with the state readable between stretches and the commands or the joint
/// targets set from outside (the Python package drives it).
pub struct WalkSession {
    walking: Walking,
    observers: Vec<Box<dyn Observer<WalkSample, Walker>>>,
    metrics: HexapodMetrics,
    /// The steps of the set-up's settle time and duration.
    planned: u64,
    /// Always Some between calls (taken by `finish`).
    looping: Option<Looping<WalkSample>>,
}

impl WalkSession {
    /// The stepper and every observer, the metrics last.
    fn parts(&mut self) -> (&mut Walking, Vec<&mut dyn Observer<WalkSample, Walker>>) {
        let mut list: Vec<&mut dyn Observer<WalkSample, Walker>> =
            self.observers.iter_mut().map(|o| o.as_mut() as _).collect();
        list.push(&mut self.metrics);
        (&mut self.walking, list)
    }

    fn looping(&self) -> &Looping<WalkSample> {
        self.looping
            .as_ref()
            .expect("a session is finished only once")
    }

    /// Takes up to `steps` steps (fewer at the end of the planned duration, on divergence, on an
    /// output's error or when interrupted); returns the steps taken.
    pub fn advance(&mut self, steps: u64) -> u64 {
        let steps = steps.min(self.remaining());
        let mut looping = self
            .looping
            .take()
            .expect("a session is finished only once");
        let (walking, mut list) = self.parts();
        let taken = looping.advance(walking, steps, &mut list);
        self.looping = Some(looping);
        // the metrics' derived figures, read between stretches ([`Self::metrics`])
        self.metrics.update();
        taken
    }

    /// Steps left of the planned settle time and duration.
    pub fn remaining(&self) -> u64 {
        self.planned.saturating_sub(self.looping().steps())
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.looping().steps()
    }

    /// True once no more steps will be taken: the run diverged, an output failed or it ended at
    /// the robot's fall (`stop_at_fall`).
    pub fn stopped(&self) -> bool {
        self.looping().stopped()
    }

    /// What diverged, if the run did.
    pub fn failure(&self) -> Option<&str> {
        self.looping().failure()
    }

    /// The latest step's state (None before the first step).
    pub fn sample(&self) -> Option<&WalkSample> {
        self.looping().last()
    }

    /// The metrics so far.
    pub fn metrics(&self) -> &HexapodMetrics {
        &self.metrics
    }

    /// The walker: the robot, its model and the gait.
    pub fn walker(&self) -> &Walker {
        &self.walking.walker
    }

    /// Replaces the scenario's command schedule by `command` from the next step on (None: back
    /// to the schedule).
    pub fn set_command(&mut self, command: Option<VelocityCommand>) {
        self.walking.command = command;
    }

    /// Drives the joints to these targets (rad, by model joint) from the next step on, instead
    /// of the gait (None: back to the gait).
    pub fn set_joint_targets(&mut self, targets: Option<Vec<f64>>) -> Result<()> {
        self.walking.walker.set_joint_targets(targets)
    }

    /// Finishes every output (the recording, the trajectory, the metrics file) and returns what
    /// the run measured; complete if it took every planned step.
    pub fn finish(mut self) -> Result<WalkOutcome> {
        let looping = self
            .looping
            .take()
            .expect("a session is finished only once");
        let planned = self.planned;
        let (_, mut list) = self.parts();
        let end = looping.finish(planned, &mut list)?;
        Ok(WalkOutcome {
            steps_per_second: end.steps as f64 / end.seconds.max(1e-9),
            physics_seconds: self.walking.walker.hexapod().physics_seconds(),
            metrics: self.metrics,
            written: end.written,
            failure: end.failure,
        })
    }
}
