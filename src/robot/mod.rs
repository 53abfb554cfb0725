//! The robot: URDF loading and validation, leg discovery, and leg kinematics.

pub mod foot;
mod forward;
pub mod kinematics;
pub mod legs;
pub mod mesh;
mod model;
pub mod servo;
pub mod statics;
pub mod urdf;

pub use model::{
    Foot, FootFrom, GaitHints, Joint, LEG_NAMES, Leg, Link, RobotModel, Shape, Visual,
};

/// Loads a URDF robot file.
pub fn load(path: &std::path::Path) -> Result<RobotModel, urdf::RobotError> {
    let mut model = urdf::load(path)?;
    model.source = path.to_path_buf();
    Ok(model)
}
