//! Whether a walk's foot targets are in reach: one tally, kept by a run as it steps
//! (`sim::walker`) and by `hexsim robot` over the same walk planned on level ground
//! ([`planned`]), so that the two give one answer. (They once disagreed both ways: `robot`
//! judged a cycle sampled 64 times without the feet's rolling offset, which a run adds; hex18
//! with a 0.19 m stride was "out of reach" by one and reached in every step by the other.)

use super::command::CommandSchedule;
use super::controller::{GaitController, GaitTargets};

/// The steps of a walk in which some leg's target was out of reach (its inverse kinematics
/// answered with the closest pose, farther than [`super::REACH_TOLERANCE`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ReachTally {
    /// Steps walked (the gait running, not standing).
    pub steps: u64,
    /// Of them, steps with some foot target out of reach.
    pub clamped_steps: u64,
    /// The first such: the leg (index in [`crate::robot::LEG_NAMES`] order) and the gait time (s).
    pub first: Option<(usize, f64)>,
}

impl ReachTally {
    /// Counts one step's targets, planned `t` seconds into the gait.
    pub fn record(&mut self, t: f64, targets: &GaitTargets) {
        self.steps += 1;
        if let Some(k) = targets.clamped.iter().position(|&c| c) {
            self.clamped_steps += 1;
            if self.first.is_none() {
                self.first = Some((k, t));
            }
        }
    }
}

/// A walk as a run steps it: its step, its standing time and duration, its commands.
#[derive(Debug, Clone, Copy)]
pub struct Stepping<'a> {
    pub dt: f64,
    /// Seconds standing before the gait starts.
    pub settle: f64,
    pub duration: f64,
    pub commands: &'a CommandSchedule,
    /// The walker stands on the controller's standing pose while settling (the load
    /// feed-forward on): it solves the legs then, which seeds the first steps' solutions.
    pub stands_by_controller: bool,
}

/// The tally of `stepping` planned by `controller` on level ground, step by step as
/// `sim::Walker::step` plans it (the same gait times, commands and stride ramp): on flat ground,
/// without terrain following or the reactive gait, the run's own tally, bit for bit.
pub fn planned(controller: &mut GaitController, stepping: Stepping) -> ReachTally {
    let Stepping {
        dt,
        settle,
        duration,
        commands,
        stands_by_controller,
    } = stepping;
    let period = controller.gait().period;
    let steps = ((settle + duration) / dt).round() as u64;
    let mut tally = ReachTally::default();
    for step in 0..steps {
        let t = step as f64 * dt - settle;
        if t >= 0.0 {
            let blend = (t / period).min(1.0);
            let targets = controller.targets(t, commands.at(t), blend);
            tally.record(t, &targets);
        } else if stands_by_controller {
            controller.standing_on(|_| 0.0);
        }
    }
    tally
}
