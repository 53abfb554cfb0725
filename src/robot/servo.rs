//! Servo gains fitted to a robot when neither the scenario nor the robot file gives them.
//!
//! The reference servo (docs/validation.md: 20 N·m/rad, 0.05 N·m·s/rad) is hex18's: on the inertia
//! its leg presents about the coxa standing, 1.59·10⁻³ kg·m², it closes the loop at ω₀ = √(k/I) ≈
//! 112 rad/s, some eighteen times the tripod's 2π rad/s, so a swinging leg follows its target. A robot
//! with heavier legs needs a stiffer servo for the same tracking (a leg with ten times the inertia
//! under hex18's servo lags its swing and trips the robot), so the fit keeps ω₀ and the damping
//! time d/k: k = ω₀²·max_j I_j over the joints, d = k·(0.05/20). It never goes below the reference.

use super::model::RobotModel;
use glam::{DMat3, DVec3};

/// The reference servo's stiffness (N·m/rad) and damping (N·m·s/rad).
pub const REFERENCE_STIFFNESS: f64 = 20.0;
pub const REFERENCE_DAMPING: f64 = 0.05;
/// The reference servo's bandwidth on hex18's standing leg (rad/s): √(20 / 1.59·10⁻³).
pub const BANDWIDTH: f64 = 112.0;

/// Per model joint, the moment of inertia of everything outboard of it in its leg about its axis
/// (kg·m²), in `pose` (joint angles per model joint): Σ_k a·I_k·a + m_k·|a × (c_k − o)|².
pub fn outboard_inertias(model: &RobotModel, pose: &[f64]) -> Vec<f64> {
    let poses = model.link_poses(pose);
    let mut inertias = vec![0.0; model.joints.len()];
    for leg in &model.legs {
        for (i, &j) in leg.joints.iter().enumerate() {
            let (origin, axis) = model.joint_axis(&poses, j);
            let axis = axis.normalize();
            inertias[j] = leg.joints[i..]
                .iter()
                .map(|&outboard| {
                    let k = model.joints[outboard].child;
                    let link = &model.links[k];
                    let rotation: DMat3 = poses[k].matrix3;
                    let about_com = rotation * link.inertia * rotation.transpose();
                    let com: DVec3 = poses[k].transform_point3(link.com);
                    axis.dot(about_com * axis)
                        + link.mass * axis.cross(com - origin).length_squared()
                })
                .sum();
        }
    }
    inertias
}

/// The most a standing foot may sag under its share of the weight on the gait's fewest feet,
/// through its servos' compliance ([`vertical_compliance`], free to slide), as a fraction of the
/// step height. A foot that sags by much of its step lands early and lifts off late while it
/// still moves, so it is dragged: a 2.6 kg hexapod (enjoykin-ua's) with 0.13 m tibias sags
/// 15.3 mm of its 30 mm step (51 %) on the bandwidth's 21.6 N·m/rad, and its feet slid 0.30 m
/// each in 10 s on flat ground. hex18 on the reference servo: 15 %, kept.
pub const SAG_LIMIT: f64 = 0.2;

/// The vertical compliance Σ_j (∂z_foot/∂q_j)² (m²) of the leg that yields most: a foot pushed
/// up by F on servos of stiffness k, free to slide, lets its hip sink F/k times it (the z row of
/// the leg's compliance J·K⁻¹·Jᵀ, K = k·I). Free to slide, because a sagging tripod splays its
/// legs, and once the splay's push passes friction the feet do slide: the 2.6 kg hexapod of
/// [`SAG_LIMIT`] sagged 13.7 mm where this predicts 15.3 mm. A foot friction holds sags less
/// (hex18: 1.6 mm measured, 4.4 mm predicted), so this bounds the sag from above.
pub fn vertical_compliance(model: &RobotModel, pose: &[f64]) -> f64 {
    let poses = model.link_poses(pose);
    model
        .legs
        .iter()
        .map(|leg| {
            let foot = poses[leg.foot_link].transform_point3(leg.foot.center);
            leg.joints
                .iter()
                .map(|&j| {
                    let (origin, axis) = model.joint_axis(&poses, j);
                    axis.normalize().cross(foot - origin).z.powi(2)
                })
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

/// What the fit chose its stiffness for (see [`fitted_gains`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FittedFor {
    /// hex18's servo: the reference.
    Reference,
    /// The reference bandwidth on heavier legs.
    Bandwidth,
    /// A standing foot's sag within [`SAG_LIMIT`] of the step.
    Sag,
}

/// Stiffness and damping for the robot's legs standing in `pose`, each foot loaded with `load`
/// (N: the weight over the gait's fewest feet) and lifted `step_height` (m) by the gait: the
/// reference servo's bandwidth and damping time (see the module's doc), stiff enough that no foot
/// sags more than [`SAG_LIMIT`] of the step, and never less than the reference.
pub fn fitted_gains(
    model: &RobotModel,
    pose: &[f64],
    load: f64,
    step_height: f64,
) -> (f64, f64, FittedFor) {
    let inertia = outboard_inertias(model, pose)
        .into_iter()
        .fold(0.0, f64::max);
    let bandwidth = BANDWIDTH * BANDWIDTH * inertia;
    let sag = load * vertical_compliance(model, pose) / (SAG_LIMIT * step_height);
    let (stiffness, reason) = [
        (REFERENCE_STIFFNESS, FittedFor::Reference),
        (bandwidth, FittedFor::Bandwidth),
        (sag, FittedFor::Sag),
    ]
    .into_iter()
    .filter(|(k, _)| k.is_finite())
    .fold((0.0, FittedFor::Reference), |best, c| {
        if c.0 > best.0 { c } else { best }
    });
    (
        stiffness,
        stiffness * REFERENCE_DAMPING / REFERENCE_STIFFNESS,
        reason,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inertia about each joint by another route: turning joint j at 1 rad/s, the kinetic
    /// energy of the outboard links is ½·I·1², with each link's centre velocity and the world
    /// inertia taken by central differences of the link poses.
    #[test]
    fn outboard_inertias_match_the_kinetic_energy_of_a_unit_turn() {
        let model = crate::robot::hex18_for_tests();
        let pose: Vec<f64> = (0..model.joints.len())
            .map(|j| [0.2, -0.4, 0.9][j % 3])
            .collect();
        let inertias = outboard_inertias(&model, &pose);
        let h = 1e-6;
        for leg in &model.legs {
            for (i, &j) in leg.joints.iter().enumerate() {
                let mut plus = pose.clone();
                plus[j] += h;
                let mut minus = pose.clone();
                minus[j] -= h;
                let (p, m, at) = (
                    model.link_poses(&plus),
                    model.link_poses(&minus),
                    model.link_poses(&pose),
                );
                let joint = &model.joints[j];
                let axis = ((at[joint.parent] * joint.origin).matrix3 * joint.axis).normalize();
                let energy: f64 = leg.joints[i..]
                    .iter()
                    .map(|&o| {
                        let k = model.joints[o].child;
                        let link = &model.links[k];
                        let v = (p[k].transform_point3(link.com) - m[k].transform_point3(link.com))
                            / (2.0 * h);
                        let r = at[k].matrix3;
                        let world = r * link.inertia * r.transpose();
                        0.5 * link.mass * v.length_squared() + 0.5 * axis.dot(world * axis)
                    })
                    .sum();
                assert!(
                    (2.0 * energy - inertias[j]).abs() < 1e-8,
                    "{}: {} vs {}",
                    joint.name,
                    2.0 * energy,
                    inertias[j]
                );
            }
        }
    }
}
