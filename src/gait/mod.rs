//! Gaits: the gait file, its lengths fitted to a robot, the phase schedule (which legs stand when),
//! and the controller that turns a velocity command into joint targets.

mod clearance;
mod command;
mod compliance;
mod controller;
mod fit;
mod foothold;
mod heading;
mod lean;
mod margins;
pub mod reach;
mod reactive;
mod schedule;
mod slew;
mod spec;

pub use command::{CommandChange, CommandSchedule};
pub use compliance::{Compliance, GroundForces, Release};
pub use controller::{
    GaitController, GaitTargets, REACH_TOLERANCE, StanceError, StanceTrack, VelocityCommand,
};
pub use fit::{FitError, Fitted, Origin, Origins, ServoLoad, TORQUE_SHARE, fit};
pub use foothold::away_from_edges;
pub use heading::HeadingHold;
pub use lean::Lean;
pub use margins::{CycleMargins, Unreached, cycle_margins};
pub use reactive::{FootFeel, Reactive, most_extra_lift};
pub use schedule::{LegPhase, leg_phase, minimum_support};
pub use spec::{Gait, GaitError, GaitSpec, SwingShape};

/// The tripod gait file, for the unit tests of this layer and those above it.
#[cfg(test)]
pub(crate) fn tripod_for_tests() -> GaitSpec {
    GaitSpec::from_toml(
        include_str!("../../gaits/tripod.toml"),
        std::path::Path::new("gaits/tripod.toml"),
    )
    .expect("the tripod parses")
}
