//! Simulations: the rapier world, and the set-ups stepped in it (the paper's ball; the hexapod).

mod articulation;
pub mod ball;
mod engine;
mod face_slots;
mod ground_contact;

pub use articulation::{Articulation, IMPULSE_PGS_ITERATIONS, JointDrift, ServoGains};
pub use ball::{BallConfig, BallSample, BallSim};
pub use engine::{Engine, STANDARD_GRAVITY};
pub use hexapod::{
    Attitude, DEFAULT_SOLVER_ITERATIONS, Hexapod, HexapodSample, HexapodSettings, Placement,
};
pub use walker::{WalkSample, Walker};
pub mod hexapod;
pub mod ringing;
pub mod walker;
