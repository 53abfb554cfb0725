//! The robot standing still and level on some of its feet: how its weight is shared among them,
//! the torque each joint's servo must hold (statics of each leg: the moment about the joint axis
//! of the leg's outboard weights and of its foot's ground force), and each leg's segment lengths.

use super::kinematics::LegStatics;
use super::model::{Leg, RobotModel};
use glam::{DAffine3, DMat3, DVec2, DVec3};

/// Per model joint, the servo torque (N·m, about the joint axis, on the child) that holds `pose`
/// (joint angles per model joint) standing level under `gravity` (m/s²), the weight shared
/// equally by `feet_down` feet (6 standing; 3 in a tripod's stance): every leg is given the
/// ground force m·g/feet_down (the loaded legs' torques, whichever they are). See
/// [`holding_torques`].
pub fn standing_torques(
    model: &RobotModel,
    pose: &[f64],
    gravity: f64,
    feet_down: usize,
) -> Vec<f64> {
    let load = foot_load(model, gravity, feet_down);
    let mut torques = vec![0.0; model.joints.len()];
    holding_torques(
        model,
        &model.link_poses(pose),
        gravity,
        &[load; 6],
        &mut torques,
    );
    torques
}

/// Into `torques`, per model joint, the servo torque (N·m, about the joint axis, on the child)
/// that holds the links at `poses` (the model's link poses, body frame, z up) under `gravity`
/// (m/s²), each leg's foot pushed up by `loads` (N, in `legs` order): τ_j = −a_j·[Σ_k (c_k − o_j)
/// × m_k·g + (f − o_j) × F], the sum over the leg's links outboard of joint j.
pub fn holding_torques(
    model: &RobotModel,
    poses: &[DAffine3],
    gravity: f64,
    loads: &[f64; 6],
    torques: &mut [f64],
) {
    holding_torques_under(model, poses, DVec3::new(0.0, 0.0, -gravity), loads, torques);
}

/// Each foot's vertical force (N, in `legs` order) holding the robot still and level on the
/// feet in `stance`, its links at `poses` (body frame, z up): the forces F_i that balance the
/// weight and its moments about the centre of mass, ΣF_i = m·g, ΣF_i·(x_i − x_c) = 0,
/// ΣF_i·(y_i − y_c) = 0 — exact on three feet, the least-squares (minimum ΣF_i²) solution on
/// more. A tripod's lone middle foot carries nearly half the weight, not a third. A foot the
/// balance would pull on (the centre of mass outside the support) is given none, the rest
/// scaled to the weight; feet in a line share it equally.
pub fn stance_loads(
    model: &RobotModel,
    poses: &[DAffine3],
    gravity: f64,
    stance: [bool; 6],
) -> [f64; 6] {
    stance_loads_under(model, poses, DVec3::new(0.0, 0.0, -gravity), stance)
}

/// Each foot's share (N) of the robot's weight under `gravity` (m/s²), standing on `feet_down`
/// feet (at least one).
pub fn foot_load(model: &RobotModel, gravity: f64, feet_down: usize) -> f64 {
    model.total_mass() * gravity / feet_down.max(1) as f64
}

/// A leg's segments with its joints at zero: hip to second joint, second to third, …, the last
/// joint to the foot's centre (m): one per joint.
pub fn segment_lengths(model: &RobotModel, leg: &Leg) -> Vec<f64> {
    let poses = model.link_poses(&vec![0.0; model.joints.len()]);
    let mut points: Vec<DVec3> = leg
        .joints
        .iter()
        .map(|&j| {
            let joint = &model.joints[j];
            (poses[joint.parent] * joint.origin).translation
        })
        .collect();
    points.push(poses[leg.foot_link].transform_point3(leg.foot.center));
    points.windows(2).map(|w| w[0].distance(w[1])).collect()
}

/// Each foot's force (N, along −`gravity`, in `legs` order) holding the robot still on the feet in
/// `stance`, its links at `poses` (body frame) and `gravity` (m/s², body frame): ΣF_i = m·|g| and
/// no moment about the centre of mass, Σ F_i·(p_i − c) ∥ g — exact on three feet, least squares
/// (minimum ΣF_i²) on more. With gravity along −z it is [`stance_loads`]; a foot the
/// balance would pull on gets none, the rest scaled to the weight; feet in a line share it.
pub fn stance_loads_under(
    model: &RobotModel,
    poses: &[DAffine3],
    gravity: DVec3,
    stance: [bool; 6],
) -> [f64; 6] {
    let feet: [DVec3; 6] = std::array::from_fn(|k| {
        let leg = &model.legs[k];
        poses[leg.foot_link].transform_point3(leg.foot.center)
    });
    let mass = model.total_mass();
    stance_loads_at(mass, model.centre_of_mass(poses), &feet, gravity, stance)
}

/// [`stance_loads_under`] with the legs posed by their IK answers ([`LegStatics`], their links'
/// masses with them): the centre of mass is the root link's and the legs' links', which must be
/// all of the model's ([`legs_hold_every_link`]).
///
/// `mass` is the model's total ([`RobotModel::total_mass`]): the walk's feed-forward reads it
/// every step, and sums it once.
pub fn stance_loads_of_legs(
    model: &RobotModel,
    mass: f64,
    legs: &[LegStatics; 6],
    gravity: DVec3,
    stance: [bool; 6],
) -> [f64; 6] {
    let root = &model.links[0];
    let mut weighted = root.com * root.mass;
    for posed in legs {
        for (&com, &mass) in posed.coms.iter().zip(&posed.masses) {
            weighted += com * mass;
        }
    }
    let com = weighted / mass;
    stance_loads_at(mass, com, &legs.map(|l| l.foot), gravity, stance)
}

/// Whether every link of `model` is its root or the child of a joint of a leg of three joints
/// in a chain from the root, the leg's foot on its last: what [`stance_loads_of_legs`] and
/// [`holding_torques_of_legs`] take for the whole robot.
pub fn legs_hold_every_link(model: &RobotModel) -> bool {
    let on_legs: usize = model.legs.iter().map(|l| l.joints.len()).sum();
    model.legs.len() == 6
        && on_legs == model.joints.len()
        && model.links.len() == 1 + model.joints.len()
        && model.legs.iter().all(|leg| {
            leg.joints.len() == 3
                && model.joints[leg.joints[0]].parent == 0
                && leg
                    .joints
                    .windows(2)
                    .all(|w| model.joints[w[1]].parent == model.joints[w[0]].child)
                && leg.foot_link == model.joints[leg.joints[2]].child
        })
}

/// [`stance_loads_under`] of the feet at `feet` (body frame) of a robot of `mass` (kg, the
/// model's total) with its centre of mass at `com`.
fn stance_loads_at(
    mass: f64,
    com: DVec3,
    feet: &[DVec3; 6],
    gravity: DVec3,
    stance: [bool; 6],
) -> [f64; 6] {
    let weight = mass * gravity.length();
    let down = gravity.normalize_or(DVec3::NEG_Z);
    // two axes across gravity: the body's x and y when it stands level
    let across_y = down.cross(DVec3::X).normalize_or(DVec3::Y) * -1.0;
    let across_x = across_y.cross(-down);
    let feet: [DVec2; 6] = std::array::from_fn(|k| {
        let p = feet[k] - com;
        DVec2::new(p.dot(across_x), p.dot(across_y))
    });
    let count = stance.iter().filter(|&&s| s).count();
    if count == 0 {
        return [0.0; 6];
    }
    let equal = weight / count as f64;
    // F = Aᵀ(AAᵀ)⁻¹b with A's columns (1, u_i, v_i) and b = (m·g, 0, 0)
    let row = |k: usize| DVec3::new(1.0, feet[k].x, feet[k].y);
    let normal = (0..6)
        .filter(|&k| stance[k])
        .map(|k| {
            let a = row(k);
            DMat3::from_cols(a * a.x, a * a.y, a * a.z)
        })
        .fold(DMat3::ZERO, |sum, m| sum + m);
    let scale = feet.iter().map(|f| f.length_squared()).sum::<f64>() + 1e-12;
    if normal.determinant().abs() <= 1e-9 * scale * scale {
        return std::array::from_fn(|k| if stance[k] { equal } else { 0.0 });
    }
    let lambda = normal.inverse() * DVec3::new(weight, 0.0, 0.0);
    let mut loads: [f64; 6] = std::array::from_fn(|k| {
        if stance[k] {
            row(k).dot(lambda).max(0.0)
        } else {
            0.0
        }
    });
    let total: f64 = loads.iter().sum();
    if total > 0.0 {
        loads.iter_mut().for_each(|f| *f *= weight / total);
        loads
    } else {
        std::array::from_fn(|k| if stance[k] { equal } else { 0.0 })
    }
}

/// Into `torques`, per model joint, the servo torque (N·m about the joint's axis, on the child)
/// holding the links at `poses` (body frame) under `gravity` (m/s², body frame), each foot pushed
/// against gravity by `loads` (N): τ_j = −a_j·[Σ_k (c_k − o_j) × m_k·g + (f − o_j) × F], over the
/// leg's links outboard of joint j ([`holding_torques`] with gravity along −z). For a body standing
/// tilted (on a slope), where part of the weight pulls along its plane.
pub fn holding_torques_under(
    model: &RobotModel,
    poses: &[DAffine3],
    gravity: DVec3,
    loads: &[f64; 6],
    torques: &mut [f64],
) {
    holding_torques_by(
        model,
        poses,
        |j| model.joint_axis(poses, j),
        gravity,
        loads,
        torques,
    );
}

/// [`holding_torques_under`] with the joints' frames already made
/// ([`RobotModel::link_and_joint_poses_into`]): the walk's feed-forward, every step, which so
/// composes each joint's frame once instead of twice. The same torques, bit for bit.
pub fn holding_torques_at(
    model: &RobotModel,
    poses: &[DAffine3],
    joint_frames: &[DAffine3],
    gravity: DVec3,
    loads: &[f64; 6],
    torques: &mut [f64],
) {
    let joint_axis = |j: usize| {
        let frame = &joint_frames[j];
        (frame.translation, frame.matrix3 * model.joints[j].axis)
    };
    holding_torques_by(model, poses, joint_axis, gravity, loads, torques);
}

/// [`holding_torques_under`] with the legs posed by their IK answers ([`LegStatics`], their
/// links' masses with them; the model's links as [`legs_hold_every_link`] asks).
pub fn holding_torques_of_legs(
    model: &RobotModel,
    legs: &[LegStatics; 6],
    gravity: DVec3,
    loads: &[f64; 6],
    torques: &mut [f64],
) {
    let up = -gravity.normalize_or(DVec3::NEG_Z);
    // every joint is on one of the legs (as `legs_hold_every_link` asks), so each torque is
    // written below: not cleared first
    for ((leg, posed), &load) in model.legs.iter().zip(legs).zip(loads) {
        let ground_force = up * load;
        // each link's weight once, not once per joint inboard of it, in loops of the posed
        // legs' fixed length (the walk's feed-forward, every step)
        let weights = posed.masses.map(|mass| gravity * mass);
        for (i, (&j, &(origin, axis))) in leg.joints.iter().zip(&posed.joints).enumerate() {
            let mut moment = (posed.foot - origin).cross(ground_force);
            for (&com, &weight) in posed.coms[i..].iter().zip(&weights[i..]) {
                moment += (com - origin).cross(weight);
            }
            torques[j] = -axis.dot(moment);
        }
    }
}

/// [`holding_torques_under`], each joint's origin and axis from `joint_axis`.
fn holding_torques_by(
    model: &RobotModel,
    poses: &[DAffine3],
    joint_axis: impl Fn(usize) -> (DVec3, DVec3),
    gravity: DVec3,
    loads: &[f64; 6],
    torques: &mut [f64],
) {
    let up = -gravity.normalize_or(DVec3::NEG_Z);
    torques.fill(0.0);
    for (leg, &load) in model.legs.iter().zip(loads) {
        let ground_force = up * load;
        let foot = poses[leg.foot_link].transform_point3(leg.foot.center);
        for (i, &j) in leg.joints.iter().enumerate() {
            let (origin, axis) = joint_axis(j);
            let mut moment = (foot - origin).cross(ground_force);
            for &outboard in &leg.joints[i..] {
                let link = model.joints[outboard].child;
                let com = poses[link].transform_point3(model.links[link].com);
                moment += (com - origin).cross(gravity * model.links[link].mass);
            }
            torques[j] = -axis.dot(moment);
        }
    }
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

    /// The legs posed by their IK answers' own forward kinematics (the walk's feed-forward)
    /// hold the loads and torques the model's forward kinematics give, to rounding.
    #[test]
    fn legs_posed_by_their_ik_answers_hold_what_the_model_holds() {
        use crate::robot::kinematics::LegChain;
        let model = hex18();
        assert!(legs_hold_every_link(&model));
        let mut pose = vec![0.0; model.joints.len()];
        let mut legs = [LegStatics::default(); 6];
        for (k, leg) in model.legs.iter().enumerate() {
            let chain = LegChain::new(&model, leg);
            let target = chain.foot_position(chain.from_three([0.2, -0.4, 1.1]))
                + DVec3::new(0.01, -0.005, 0.003 * k as f64);
            let mut warm = None;
            let answer = chain.solve_warm(target, chain.from_three([0.0, -0.3, 1.2]), &mut warm);
            assert!(answer.error < 1e-6);
            for (i, &j) in leg.joints.iter().enumerate() {
                pose[j] = answer.angles[i];
            }
            legs[k] = chain
                .statics(warm.as_ref().unwrap(), &answer.angles)
                .unwrap();
            // not the answer's angles: no pose
            let mut other = answer.angles;
            other[1] += 1e-9;
            assert!(chain.statics(warm.as_ref().unwrap(), &other).is_none());
        }
        let poses = model.link_poses(&pose);
        let gravity = DVec3::new(0.5, -0.3, -9.7);
        let stance = [true, false, true, false, true, true];
        let loads = stance_loads_under(&model, &poses, gravity, stance);
        let posed = stance_loads_of_legs(&model, model.total_mass(), &legs, gravity, stance);
        for k in 0..6 {
            assert!(
                (loads[k] - posed[k]).abs() < 1e-9,
                "foot {k}: {loads:?} {posed:?}"
            );
        }
        let n = model.joints.len();
        let (mut by_model, mut by_legs) = (vec![0.0; n], vec![0.0; n]);
        holding_torques_under(&model, &poses, gravity, &loads, &mut by_model);
        holding_torques_of_legs(&model, &legs, gravity, &loads, &mut by_legs);
        for j in 0..n {
            assert!(
                (by_model[j] - by_legs[j]).abs() < 1e-12,
                "joint {j}: {} against {}",
                by_model[j],
                by_legs[j]
            );
        }
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

    /// Three feet: the loads are the unique ones that balance the weight and its moments about
    /// the centre of mass (the robot does not tip); hex18's tripod puts nearly half on the lone
    /// middle foot. Six: balanced too. Two (a line): an equal split, the balance undetermined.
    #[test]
    fn stance_loads_balance_the_weight_and_its_moments() {
        let model = hex18();
        let g = 9.81;
        let poses = model.link_poses(&vec![0.0; model.joints.len()]);
        let weight = model.total_mass() * g;
        let com = model.centre_of_mass(&poses);
        let names: Vec<&str> = model.legs.iter().map(|l| l.name).collect();
        let tripod: [bool; 6] = std::array::from_fn(|k| matches!(names[k], "lf" | "rm" | "lr"));
        for stance in [tripod, [true; 6]] {
            let loads = stance_loads(&model, &poses, g, stance);
            let mut sum = DVec3::ZERO;
            for (k, leg) in model.legs.iter().enumerate() {
                let foot = poses[leg.foot_link].transform_point3(leg.foot.center) - com;
                sum += DVec3::new(loads[k], loads[k] * foot.x, loads[k] * foot.y);
                assert!(
                    stance[k] || loads[k] == 0.0,
                    "{} in swing: {loads:?}",
                    leg.name
                );
            }
            assert!((sum.x - weight).abs() < 1e-9 * weight, "{sum} of {weight}");
            assert!(sum.y.abs() < 1e-9 && sum.z.abs() < 1e-9, "moments {sum}");
        }
        let loads = stance_loads(&model, &poses, g, tripod);
        let middle = names.iter().position(|&n| n == "rm").unwrap();
        assert!(
            loads[middle] > 0.4 * weight && loads[middle] < 0.5 * weight,
            "the middle foot carries {} of {weight} N",
            loads[middle]
        );
        let two: [bool; 6] = std::array::from_fn(|k| matches!(names[k], "lf" | "rr"));
        let loads = stance_loads(&model, &poses, g, two);
        for k in 0..6 {
            let expected = if two[k] { weight / 2.0 } else { 0.0 };
            assert!((loads[k] - expected).abs() < 1e-9, "{loads:?}");
        }
    }
}
