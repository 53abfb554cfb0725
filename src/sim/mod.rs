//! Simulations: the rapier world, and the set-ups stepped in it (the paper's ball; the hexapod).

pub mod ball;
mod engine;

pub use ball::{BallConfig, BallSample, BallSim};
pub use engine::{Engine, STANDARD_GRAVITY};
pub use hexapod::{Hexapod, HexapodSample, HexapodSettings, Placement, ServoGains};
pub use walker::{WalkSample, Walker};
pub mod hexapod;
pub mod walker;
