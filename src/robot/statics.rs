//! The robot standing still, level, its weight shared equally by the six feet: the torque each
//! joint's servo must hold (statics of each leg: the moment about the joint axis of the leg's
//! outboard weights and of its foot's ground force), and each leg's segment lengths.

use super::model::{Leg, RobotModel};
use glam::DVec3;

/// Per model joint, the servo torque (N·m, about the joint axis, on the child) that holds `pose`
/// (joint angles per model joint) standing level under `gravity` (m/s²), the weight shared
/// equally by `feet_down` feet (6 standing; 3 in a tripod's stance): τ_j = −a_j·[Σ_k (c_k − o_j)
/// × m_k·g + (f − o_j) × F], the sum over the leg's links outboard of joint j, F = m·g/feet_down
/// (every leg is given the ground force: the loaded legs' torques, whichever they are).
pub fn standing_torques(
    model: &RobotModel,
    pose: &[f64],
    gravity: f64,
    feet_down: usize,
) -> Vec<f64> {
    let poses = model.link_poses(pose);
    let g = DVec3::new(0.0, 0.0, -gravity);
    let ground_force = DVec3::new(0.0, 0.0, foot_load(model, gravity, feet_down));
    let mut torques = vec![0.0; model.joints.len()];
    for leg in &model.legs {
        let foot = poses[leg.foot_link].transform_point3(leg.foot.center);
        for (i, &j) in leg.joints.iter().enumerate() {
            let joint = &model.joints[j];
            let frame = poses[joint.parent] * joint.origin;
            let (origin, axis) = (frame.translation, frame.matrix3 * joint.axis);
            let mut moment = (foot - origin).cross(ground_force);
            for &outboard in &leg.joints[i..] {
                let link = model.joints[outboard].child;
                let com = poses[link].transform_point3(model.links[link].com);
                moment += (com - origin).cross(g * model.links[link].mass);
            }
            torques[j] = -axis.dot(moment);
        }
    }
    torques
}

/// Each foot's share (N) of the robot's weight under `gravity` (m/s²), standing on `feet_down`
/// feet (at least one).
pub fn foot_load(model: &RobotModel, gravity: f64, feet_down: usize) -> f64 {
    model.total_mass() * gravity / feet_down.max(1) as f64
}

/// A leg's segments with its joints at zero: hip to second joint, second to third, third to the
/// foot's centre (m).
pub fn segment_lengths(model: &RobotModel, leg: &Leg) -> [f64; 3] {
    let poses = model.link_poses(&vec![0.0; model.joints.len()]);
    let at = |j: usize| {
        let joint = &model.joints[j];
        (poses[joint.parent] * joint.origin).translation
    };
    let [a, b, c] = leg.joints.map(at);
    let foot = poses[leg.foot_link].transform_point3(leg.foot.center);
    [a.distance(b), b.distance(c), c.distance(foot)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn hex18() -> RobotModel {
        super::super::urdf::from_str(
            include_str!("../../robots/hex18.urdf"),
            Path::new("robots/hex18.urdf"),
        )
        .unwrap()
    }

    /// Virtual work, an independent route: holding still, τ_j = ∂/∂q_j [Σ_k m_k·g·z_k − F·z_foot]
    /// (the servo balances the change of potential energy of the leg's links and the work of the
    /// foot's ground force), by central differences in a bent pose.
    #[test]
    fn the_torques_match_virtual_work() {
        let model = hex18();
        let g = 9.81;
        let pose: Vec<f64> = (0..model.joints.len())
            .map(|j| [0.3, -0.5, 0.8][j % 3])
            .collect();
        let torques = standing_torques(&model, &pose, g, 6);
        let force = model.total_mass() * g / 6.0;
        for leg in &model.legs {
            let energy = |q: &[f64]| {
                let poses = model.link_poses(q);
                let links: f64 = leg
                    .joints
                    .iter()
                    .map(|&j| {
                        let k = model.joints[j].child;
                        model.links[k].mass * g * poses[k].transform_point3(model.links[k].com).z
                    })
                    .sum();
                links - force * poses[leg.foot_link].transform_point3(leg.foot.center).z
            };
            for &j in &leg.joints {
                let h = 1e-6;
                let (mut up, mut down) = (pose.clone(), pose.clone());
                up[j] += h;
                down[j] -= h;
                let expected = (energy(&up) - energy(&down)) / (2.0 * h);
                assert!(
                    (torques[j] - expected).abs() < 1e-6,
                    "{} joint {j}: {} N·m, virtual work says {expected}",
                    leg.name,
                    torques[j]
                );
            }
        }
    }

    /// A foot straight out from a horizontal joint axis at distance d, loaded with F: τ = F·d
    /// plus the leg's own weights (checked against the hand computation for the tibia joint).
    #[test]
    fn the_last_joint_holds_the_foot_force_times_its_lever() {
        let model = hex18();
        let zero = vec![0.0; model.joints.len()];
        let torques = standing_torques(&model, &zero, 9.81, 6);
        let poses = model.link_poses(&zero);
        for leg in &model.legs {
            let j = leg.joints[2];
            let joint = &model.joints[j];
            let frame = poses[joint.parent] * joint.origin;
            let axis = frame.matrix3 * joint.axis;
            let foot = poses[leg.foot_link].transform_point3(leg.foot.center);
            let link = &model.links[leg.foot_link];
            let com = poses[leg.foot_link].transform_point3(link.com);
            let weight = model.total_mass() * 9.81 / 6.0;
            let lever = |p: DVec3| (p - frame.translation).truncate();
            // moment about the axis of vertical forces: a·(r × F ẑ) = F·(a_x r_y − a_y r_x)
            let about = |r: glam::DVec2, f: f64| f * (axis.x * r.y - axis.y * r.x);
            let expected = -(about(lever(foot), weight) + about(lever(com), -link.mass * 9.81));
            assert!(
                (torques[j] - expected).abs() < 1e-9,
                "{}: {} vs {expected}",
                leg.name,
                torques[j]
            );
        }
    }
}
