//! The servo gains of a walk: as the scenario gives them, else fitted to the robot standing in
//! the gait's pose on its fewest feet ([`crate::robot::servo::fitted_gains`]).

use crate::robot::RobotModel;
use crate::robot::servo::{FittedFor, REFERENCE_DAMPING, REFERENCE_STIFFNESS, fitted_gains};
use crate::robot::statics::foot_load;
use crate::sim::{STANDARD_GRAVITY, ServoGains};

/// The gains fitted to `robot` standing in `pose` on `support` feet and lifting them
/// `step_height` (m), and what the fit chose the stiffness for.
pub fn fitted(
    robot: &RobotModel,
    pose: &[f64],
    support: usize,
    step_height: f64,
) -> (ServoGains, FittedFor) {
    let load = foot_load(robot, STANDARD_GRAVITY, support);
    let (stiffness, damping, why) = fitted_gains(robot, pose, load, step_height);
    (ServoGains { stiffness, damping }, why)
}

/// The gains: those given, a stiffness given with the reference's damping ratio to it, and the
/// rest [`fitted`]; with what the stiffness was fitted for (None: given), which the time step's
/// message names. Refused unless the stiffness is > 0 and the damping ≥ 0.
pub fn gains(
    stiffness: Option<f64>,
    damping: Option<f64>,
    robot: &RobotModel,
    pose: &[f64],
    support: usize,
    step_height: f64,
) -> Result<(ServoGains, Option<FittedFor>), String> {
    let fit = || fitted(robot, pose, support, step_height);
    let (stiffness, damping, why) = match (stiffness, damping) {
        (Some(k), Some(d)) => (k, d, None),
        (Some(k), None) => (k, k * REFERENCE_DAMPING / REFERENCE_STIFFNESS, None),
        (None, Some(d)) => {
            let (g, why) = fit();
            (g.stiffness, d, Some(why))
        }
        (None, None) => {
            let (g, why) = fit();
            (g.stiffness, g.damping, Some(why))
        }
    };
    if !(stiffness.is_finite() && stiffness > 0.0 && damping.is_finite() && damping >= 0.0) {
        return Err(format!(
            "servo: expected stiffness > 0 and damping ≥ 0, got {stiffness} and {damping}"
        ));
    }
    Ok((ServoGains { stiffness, damping }, why))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex18_standing() -> (RobotModel, Vec<f64>, f64) {
        let robot = crate::scenario::builtin::hex18();
        let tripod = crate::scenario::builtin::TRIPOD;
        let gait = crate::gait::GaitSpec::from_toml(tripod.text, std::path::Path::new(tripod.path))
            .unwrap();
        let fitted = crate::gait::fit(&robot, &gait).unwrap();
        let step = fitted.gait.step_height;
        (robot, fitted.standing_pose, step)
    }

    #[test]
    fn hex18_is_fitted_the_reference_servo() {
        let (robot, pose, step) = hex18_standing();
        let (g, why) = fitted(&robot, &pose, 3, step);
        assert_eq!(why, FittedFor::Reference);
        assert_eq!(
            (g.stiffness, g.damping),
            (REFERENCE_STIFFNESS, REFERENCE_DAMPING)
        );
    }

    #[test]
    fn a_given_stiffness_keeps_the_reference_damping_ratio() {
        let (robot, pose, step) = hex18_standing();
        let (g, _) = gains(
            Some(2.0 * REFERENCE_STIFFNESS),
            None,
            &robot,
            &pose,
            3,
            step,
        )
        .unwrap();
        assert_eq!(g.damping, 2.0 * REFERENCE_DAMPING);
        let (g, _) = gains(None, Some(0.5), &robot, &pose, 3, step).unwrap();
        assert_eq!((g.stiffness, g.damping), (REFERENCE_STIFFNESS, 0.5));
    }

    #[test]
    fn gains_out_of_range_are_refused() {
        let (robot, pose, step) = hex18_standing();
        for (k, d) in [(0.0, 1.0), (f64::NAN, 1.0), (1.0, -1.0)] {
            let error = gains(Some(k), Some(d), &robot, &pose, 3, step).unwrap_err();
            assert!(
                error.starts_with("servo: expected stiffness > 0"),
                "{error}"
            );
        }
    }
}
