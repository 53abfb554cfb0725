//! Simulations: the rapier world, and the set-ups stepped in it (the paper's ball; the hexapod).

pub mod ball;
mod engine;
mod impulse;
mod mobility;
mod multibody;

pub use ball::{BallConfig, BallSample, BallSim};
pub use engine::{Engine, STANDARD_GRAVITY};
pub use hexapod::{
    Articulation, DEFAULT_SOLVER_ITERATIONS, Hexapod, HexapodSample, HexapodSettings,
    IMPULSE_PGS_ITERATIONS, Placement, ServoGains,
};
pub use impulse::JointDrift;
pub use walker::{WalkSample, Walker};
pub mod hexapod;
pub mod walker;
