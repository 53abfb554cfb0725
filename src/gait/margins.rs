//! How much room a gait leaves a robot's joints: over one cycle at the gait's nominal speed on
//! level ground, each joint's smallest distance to a limit, and whether every foot target is
//! reached. What fitting a gait to a robot maximises, and what `hexsim robot` reports.

use super::controller::{GaitController, StanceError, VelocityCommand};
use super::spec::Gait;
use crate::robot::{RobotModel, contact_set};
use glam::DAffine3;

/// Instants sampled per cycle.
const SAMPLES: usize = 64;

/// A gait's room on a robot.
#[derive(Debug, Clone, PartialEq)]
pub struct CycleMargins {
    /// Per model joint, its smallest distance to a limit over the cycle (rad).
    pub per_joint: Vec<f64>,
    /// The joint with the least room, and that room (rad).
    pub worst: (usize, f64),
    /// A leg whose foot target is out of reach, when (s into the cycle), and the leg's joint
    /// angles then (the closest reachable pose).
    pub unreached: Option<Unreached>,
    /// The least height over the level ground of any contact sphere that is not a foot's
    /// (shins, knees, the body; [`link_clearance`]) over the cycle (m): below zero a link
    /// other than a foot walks on the ground. Infinite when no link has contact spheres.
    pub link_clearance: f64,
}

/// A foot target out of a leg's reach during the cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unreached {
    /// Index of the leg (in [`crate::robot::LEG_NAMES`] order).
    pub leg: usize,
    /// Seconds into the cycle.
    pub time: f64,
    pub angles: crate::robot::kinematics::LegAngles,
}

/// The margins of `gait` on `model` (an error when the standing pose or the swing apex cannot
/// be reached at all: [`GaitController::new`]'s).
pub fn cycle_margins(model: &RobotModel, gait: &Gait) -> Result<CycleMargins, StanceError> {
    sampled_margins(model, gait, SAMPLES)
}

/// [`cycle_margins`] from `samples` instants per cycle.
pub(super) fn sampled_margins(
    model: &RobotModel,
    gait: &Gait,
    samples: usize,
) -> Result<CycleMargins, StanceError> {
    // the plan's own path: the fit judges the stance without the feet's rolling offset
    let mut controller = GaitController::for_cycle(model, gait.clone())?.with_rolling_feet(false);
    let command = VelocityCommand {
        forward: gait.nominal_speed(),
        ..Default::default()
    };
    let mut per_joint = vec![f64::INFINITY; model.joints.len()];
    let mut unreached = None;
    let mut link_clearance = f64::INFINITY;
    let ground = model.hips_plane() - gait.stance_height;
    let others = not_feet(model);
    let mut poses = Vec::new();
    for i in 0..samples {
        let t = gait.period * i as f64 / samples as f64;
        let targets = controller.targets(t, command, 1.0);
        for (k, leg) in model.legs.iter().enumerate() {
            if targets.clamped[k] && unreached.is_none() {
                unreached = Some(Unreached {
                    leg: k,
                    time: t,
                    angles: targets.joint_angles[k],
                });
            }
            for (&j, &q) in leg.joints.iter().zip(&targets.joint_angles[k]) {
                let joint = &model.joints[j];
                per_joint[j] = per_joint[j].min((q - joint.lower).min(joint.upper - q));
            }
        }
        model.link_poses_into(&model.pose_from_legs(&targets.joint_angles), &mut poses);
        link_clearance = link_clearance.min(lowest_sphere(model, &poses, &others) - ground);
    }
    let worst = per_joint
        .iter()
        .copied()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0, f64::INFINITY));
    Ok(CycleMargins {
        per_joint,
        worst,
        unreached,
        link_clearance,
    })
}

/// Per link, which of its contact spheres are not part of a foot's sole
/// ([`contact_set::soles`]): the spheres that must stay off the ground.
fn not_feet(model: &RobotModel) -> Vec<Vec<bool>> {
    (0..model.links.len())
        .map(|k| contact_set::soles(model, k).map(|s| s.is_none()).collect())
        .collect()
}

/// The lowest point of any sphere `others` marks, the links posed by `poses` (body frame).
fn lowest_sphere(model: &RobotModel, poses: &[DAffine3], others: &[Vec<bool>]) -> f64 {
    let mut lowest = f64::INFINITY;
    for ((link, pose), marked) in model.links.iter().zip(poses).zip(others) {
        for (sphere, _) in link.contacts.iter().zip(marked).filter(|(_, m)| **m) {
            lowest = lowest.min(pose.transform_point3(sphere.center).z - sphere.radius);
        }
    }
    lowest
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn hex18() -> RobotModel {
        crate::robot::hex18_for_tests()
    }

    /// The tripod at the stance hex18's robot file states (robots/hex18.toml), what the fit
    /// gives it.
    fn tripod() -> Gait {
        let spec = crate::gait::GaitSpec::from_toml(
            include_str!("../../gaits/tripod.toml"),
            Path::new("tripod"),
        )
        .unwrap();
        let offsets = spec.offsets();
        Gait {
            name: spec.name.clone(),
            period: spec.period,
            duty_factor: spec.duty_factor,
            stride_length: 0.06,
            step_height: 0.03,
            stance_height: 0.10,
            reach: 0.15,
            splay: 0.0,
            swing: spec.swing,
            offsets,
        }
    }

    /// hex18's tripod reaches every target with room in every joint; a longer stride takes room
    /// from the coxa (its swing about the hip grows), and one past the coxa's limit is unreached.
    #[test]
    fn a_longer_stride_leaves_the_coxa_less_room() {
        let model = hex18();
        let normal = cycle_margins(&model, &tripod()).unwrap();
        assert!(normal.unreached.is_none());
        assert!(normal.worst.1 > 0.0, "{:?}", normal.worst);
        let coxa = model.legs[0].joints[0];
        let long = Gait {
            stride_length: 0.2,
            ..tripod()
        };
        let long = cycle_margins(&model, &long).unwrap();
        assert!(long.per_joint[coxa] < normal.per_joint[coxa]);
        let too_long = Gait {
            stride_length: 0.5,
            ..tripod()
        };
        let too_long = cycle_margins(&model, &too_long).unwrap();
        assert!(too_long.unreached.is_some() || too_long.worst.1 <= 1e-9);
    }
}
