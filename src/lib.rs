//! hexsim: a hexapod walking-robot simulator on uneven ground, built on the ground contact model of
//! Burkus & Odry, "Implementation of 3D Ground Contact Model for Uneven Ground".

pub mod batch;
pub mod bench;
pub mod compare;
pub mod contact;
pub mod gait;
pub mod interrupt;
pub mod ladder;
pub mod limits;
pub mod metrics;
pub mod optimize;
pub mod record;
pub mod robot;
pub mod runner;
pub mod scenario;
pub mod setup;
pub mod sim;
pub mod terrain;
#[cfg(test)]
mod test_rng;
