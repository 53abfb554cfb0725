//! The robot: URDF loading and validation, leg discovery, and leg kinematics.

mod branches;
pub mod contact_set;
pub mod foot;
mod forward;
pub mod kinematics;
pub mod legs;
pub mod mesh;
mod model;
mod redundant;
pub mod servo;
pub mod statics;
pub mod urdf;

pub use model::{
    ContactSphere, Foot, FootFrom, GaitHints, HeldJoint, Joint, LEG_NAMES, Leg, Link, RobotModel,
    Shape, Visual,
};

/// Loads a URDF robot file.
pub fn load(path: &std::path::Path) -> Result<RobotModel, urdf::RobotError> {
    let mut model = urdf::load(path)?;
    model.source = path.to_path_buf();
    Ok(model)
}

/// The reference robot for the unit tests of this layer and those above it (the scenario layer's
/// built-in copy is above them: `scenario::builtin`).
#[cfg(test)]
pub(crate) fn hex18_for_tests() -> RobotModel {
    urdf::from_str_with(
        include_str!("../../robots/hex18.urdf"),
        Some(include_str!("../../robots/hex18.toml")),
        std::path::Path::new("robots/hex18.urdf"),
    )
    .expect("hex18 loads")
}
