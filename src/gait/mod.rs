//! Gaits: the gait file, the phase schedule (which legs stand when), and the controller that turns a
//! velocity command into joint targets.

mod command;
mod controller;
mod margins;
mod schedule;
mod spec;

pub use command::{CommandChange, CommandSchedule};
pub use controller::{GaitController, GaitTargets, REACH_TOLERANCE, VelocityCommand};
pub use margins::{CycleMargins, cycle_margins};
pub use schedule::{LegPhase, leg_phase, minimum_support};
pub use spec::{GaitError, GaitSpec, SwingShape};
