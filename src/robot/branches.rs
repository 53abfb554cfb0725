//! Which of a robot's branches are its six legs, and which joints it holds still.
//!
//! A real hexapod carries more than legs: a pan-tilt head, an arm, a tail, antennae, a camera
//! mount. Its legs are told apart by structure: each branch from the body to a leaf link with a
//! foot is a candidate, and the legs are the six disjoint candidates whose feet reach lowest
//! (a leg reaches the ground, a head does not) that split three on each side of a walking
//! direction (legs come in left/right pairs; an arm or a tail sits on the axis). Every joint off
//! those six is held at its zero — welded there, so a head rides as part of the body.
//!
//! A leg of more than three joints (a tarsus, a hip roll) walks on three of them: the three that
//! sweep the largest workspace with the others held (∫|det J| dq over their limits, the volume
//! they cover), the others held at their zero. With `redundant_legs = "driven"` in the robot file
//! it is driven whole, up to [`MAX_LEG_JOINTS`] joints and all six legs alike: the same three
//! place the foot and the others are servoed, pulled towards their zero by redundant inverse
//! kinematics (`redundant`), and bent where the three cannot reach. Held is the default: it is
//! stiffer (a servoed femur and tibia in mid-leg let the CSIRO Bullet's feet slide 0.12 m on the
//! natural terrain, 0.07 m held), and it walks where the three reach. A leg of fewer than three
//! cannot place its foot in space, and is refused saying so. A leg of fewer than three cannot
//! place its foot in space, and is refused saying so.

use super::kinematics::MAX_LEG_JOINTS;
use super::legs::{chain_to, choose_forward, is_leaf, split};
use super::model::{HeldJoint, Joint, Link};
use glam::{DAffine3, DVec2, DVec3};

/// A branch from the body to a leaf link that carries a foot.
struct Candidate {
    leaf: usize,
    /// Joint indices from the body out.
    chain: Vec<usize>,
    /// The lowest its foot centre gets in the body frame, its joints swept over their limits (m).
    lowest: f64,
}

/// At most this many candidates (the lowest-reaching) are searched for the six legs.
const MOST_CANDIDATES: usize = 12;

/// The joints to hold still so that the robot is six legs of three joints each, or with `driven`
/// (the robot file's `redundant_legs = "driven"`) of three to [`MAX_LEG_JOINTS`] alike: empty
/// when it is already (then nothing changes). `unfound`: leaf links whose foot could not be
/// found, with why; `forward`: the robot file's walking direction (yaw, rad), if it gives one.
pub(super) fn held_joints(
    links: &[Link],
    joints: &[Joint],
    unfound: &[(String, String)],
    forward: Option<f64>,
    driven: bool,
) -> Result<Vec<HeldJoint>, String> {
    let mut candidates: Vec<Candidate> = (0..links.len())
        .filter(|&k| is_leaf(joints, k))
        .filter_map(|k| {
            let foot = links[k].foot?;
            let chain = chain_to(links, joints, k);
            let lowest = lowest_reach(joints, &chain, foot.center);
            Some(Candidate {
                leaf: k,
                chain,
                lowest,
            })
        })
        .collect();
    if candidates.len() < 6 {
        if let Some((link, why)) = unfound.first() {
            return Err(super::legs::footless_leg(link, Some(why)));
        }
        return Err(found_too_few(candidates.len()));
    }
    // lowest first; ties in the URDF's order
    candidates.sort_by(|a, b| a.lowest.total_cmp(&b.lowest).then(a.leaf.cmp(&b.leaf)));
    candidates.truncate(MOST_CANDIDATES);
    let legs: Vec<&Candidate> = if candidates.len() == 6 {
        candidates.iter().collect()
    } else {
        choose_six(links, joints, &candidates, forward)?
    };
    for leg in &legs {
        if leg.chain.len() < 3 {
            // a leg whose foot was not found leaves a head or an arm among the six: say so
            if let Some((link, why)) = unfound.first() {
                return Err(super::legs::footless_leg(link, Some(why)));
            }
            return Err(too_few_joints(&links[leg.leaf].name, leg.chain.len()));
        }
    }
    let mut active = vec![false; joints.len()];
    let mut on_leg: Vec<Option<usize>> = vec![None; joints.len()];
    // driven whole when asked, the legs alike in length and no longer than MAX_LEG_JOINTS (the
    // multibody's contact mobility is sized per leg length); otherwise each walks on three
    let whole = driven
        && legs
            .iter()
            .all(|l| l.chain.len() == legs[0].chain.len() && l.chain.len() <= MAX_LEG_JOINTS);
    for leg in &legs {
        let foot = links[leg.leaf].foot.map_or(DVec3::ZERO, |f| f.center);
        let driven = if whole {
            leg.chain.clone()
        } else {
            driven_three(joints, &leg.chain, foot)
        };
        for j in driven {
            active[j] = true;
        }
        for &j in &leg.chain {
            on_leg[j] = Some(leg.leaf);
        }
    }
    Ok((0..joints.len())
        .filter(|&j| !active[j])
        .map(|j| HeldJoint {
            name: joints[j].name.clone(),
            angle: hold_angle(&joints[j]),
            on_leg: on_leg[j].map(|k| links[k].name.clone()),
        })
        .collect())
}

/// The message for too few legs found.
pub(super) fn found_too_few(n: usize) -> String {
    format!(
        "found {n} leg{} (a chain of revolute joints from the body to a link with a foot); a hexapod needs 6",
        if n == 1 { "" } else { "s" }
    )
}

/// Why a leg of one or two joints cannot walk.
fn too_few_joints(leaf: &str, n: usize) -> String {
    let reach = if n == 1 {
        "its foot moves on a circle"
    } else {
        "its foot moves on a surface, not through a volume"
    };
    format!(
        "the leg ending at link `{leaf}` has {n} joint{}: {reach}, so it cannot keep the body's height while it strokes along the ground as a walking gait needs; hexsim's legs have at least 3 revolute joints (coxa, femur, tibia)",
        if n == 1 { "" } else { "s" }
    )
}

/// A held joint's angle, and a redundant leg's extra joint's rest: its zero, or the limit
/// nearest it.
pub(super) fn hold_angle(joint: &Joint) -> f64 {
    0.0_f64.clamp(joint.lower, joint.upper)
}

/// `n` angles spread over a joint's range (its limits, within ±π).
fn sweep(joint: &Joint, n: usize) -> Vec<f64> {
    let (lo, hi) = (
        joint.lower.max(-std::f64::consts::PI),
        joint.upper.min(std::f64::consts::PI),
    );
    (0..n)
        .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
        .collect()
}

/// Each joint's (origin, axis) and the foot centre in the body frame, for angles `q` along
/// `chain` (which hangs from the body, each joint from the one before).
fn forward(
    joints: &[Joint],
    chain: &[usize],
    q: &[f64],
    foot: DVec3,
) -> (Vec<(DVec3, DVec3)>, DVec3) {
    let mut frame = DAffine3::IDENTITY;
    let mut axes = Vec::with_capacity(chain.len());
    for (&j, &angle) in chain.iter().zip(q) {
        let joint = &joints[j];
        frame *= joint.origin;
        axes.push((frame.translation, frame.matrix3 * joint.axis));
        frame *= DAffine3::from_axis_angle(joint.axis, angle);
    }
    (axes, frame.transform_point3(foot))
}

/// Calls `visit` with every point of a grid over the joints' ranges (`per_joint` angles each).
fn grid(ranges: &[Vec<f64>], visit: &mut impl FnMut(&[f64])) {
    let mut index = vec![0; ranges.len()];
    let mut q: Vec<f64> = ranges.iter().map(|r| r[0]).collect();
    loop {
        visit(&q);
        let mut k = 0;
        loop {
            if k == ranges.len() {
                return;
            }
            index[k] += 1;
            if index[k] < ranges[k].len() {
                q[k] = ranges[k][index[k]];
                break;
            }
            index[k] = 0;
            q[k] = ranges[k][0];
            k += 1;
        }
    }
}

/// The lowest the foot centre gets in the body frame, the chain's joints swept over their limits.
fn lowest_reach(joints: &[Joint], chain: &[usize], foot: DVec3) -> f64 {
    let per_joint = match chain.len() {
        0..=4 => 7,
        5..=6 => 5,
        _ => 3,
    };
    let ranges: Vec<Vec<f64>> = chain
        .iter()
        .map(|&j| sweep(&joints[j], per_joint))
        .collect();
    let mut lowest = f64::INFINITY;
    grid(&ranges, &mut |q| {
        lowest = lowest.min(forward(joints, chain, q, foot).1.z);
    });
    lowest
}

/// The six disjoint candidates that split three a side (about the robot file's direction, or
/// one hexsim can choose) and reach lowest together.
fn choose_six<'a>(
    links: &[Link],
    joints: &[Joint],
    candidates: &'a [Candidate],
    forward: Option<f64>,
) -> Result<Vec<&'a Candidate>, String> {
    let hip = |c: &Candidate| joints[c.chain[0]].origin.translation.truncate();
    let n = candidates.len();
    let mut best: Option<(f64, [usize; 6])> = None;
    let mut pick = [0usize, 1, 2, 3, 4, 5];
    loop {
        let chosen: Vec<&Candidate> = pick.iter().map(|&i| &candidates[i]).collect();
        let disjoint = {
            let mut seen = std::collections::HashSet::new();
            chosen
                .iter()
                .flat_map(|c| &c.chain)
                .all(|j| seen.insert(*j))
        };
        if disjoint {
            let hips: Vec<DVec2> = chosen.iter().map(|c| hip(c)).collect();
            let splits = match forward {
                Some(yaw) => split(&hips, yaw).is_some(),
                None => choose_forward(&hips).is_some(),
            };
            let score: f64 = chosen.iter().map(|c| c.lowest).sum();
            if splits && best.is_none_or(|(s, _)| score < s) {
                best = Some((score, pick));
            }
        }
        // the next 6 of n in lexicographic order
        let Some(i) = (0..6).rev().find(|&i| pick[i] < n - 6 + i) else {
            break;
        };
        pick[i] += 1;
        for k in i + 1..6 {
            pick[k] = pick[k - 1] + 1;
        }
    }
    let (_, pick) = best.ok_or_else(|| {
        let names: Vec<&str> = candidates
            .iter()
            .map(|c| links[c.leaf].name.as_str())
            .collect();
        format!(
            "no six of the {n} chains ending in a foot ({}) are legs: none of their sets of six has three on each side of a walking direction without sharing joints",
            names.join(", ")
        )
    })?;
    Ok(pick.iter().map(|&i| &candidates[i]).collect())
}

/// The three joints of a leg that place its foot: all three of a 3-joint leg; of a longer one,
/// the three that sweep the largest workspace with the others held ([`hold_angle`]): the volume
/// ∫|det J| dq over their limits (7³ samples), J the foot's Jacobian in those three joints.
pub(super) fn driven_three(joints: &[Joint], chain: &[usize], foot: DVec3) -> Vec<usize> {
    if chain.len() <= 3 {
        return chain.to_vec();
    }
    let held: Vec<f64> = chain.iter().map(|&j| hold_angle(&joints[j])).collect();
    let mut best: Option<(f64, [usize; 3])> = None;
    for a in 0..chain.len() {
        for b in a + 1..chain.len() {
            for c in b + 1..chain.len() {
                let three = [a, b, c];
                let ranges: Vec<Vec<f64>> =
                    three.iter().map(|&i| sweep(&joints[chain[i]], 7)).collect();
                let mut q = held.clone();
                let mut volume = 0.0;
                grid(&ranges, &mut |angles| {
                    for (&i, &angle) in three.iter().zip(angles) {
                        q[i] = angle;
                    }
                    let (axes, p) = forward(joints, chain, &q, foot);
                    let column = |i: usize| axes[i].1.cross(p - axes[i].0);
                    volume += glam::DMat3::from_cols(column(a), column(b), column(c))
                        .determinant()
                        .abs();
                });
                if best.is_none_or(|(v, _)| volume > v * (1.0 + 1e-9)) {
                    best = Some((volume, three));
                }
            }
        }
    }
    let (_, three) = best.expect("a chain of more than three joints has a triple");
    three.map(|i| chain[i]).to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn revolute(name: &str, parent: usize, at: DVec3, axis: DVec3) -> Joint {
        Joint {
            name: name.into(),
            parent,
            child: parent + 1,
            origin: DAffine3::from_translation(at),
            axis,
            lower: -1.5,
            upper: 1.5,
            effort: 1.0,
        }
    }

    /// A coxa (yaw) – femur – tibia – tarsus leg (pitch ×3): the three driven are the coxa and
    /// two of the pitch joints — never three parallel pitch axes, which move the foot in a plane.
    #[test]
    fn a_tarsus_leg_is_driven_by_its_coxa_and_two_pitch_joints() {
        let joints = vec![
            revolute("coxa", 0, DVec3::new(0.1, 0.05, 0.0), DVec3::Z),
            revolute("femur", 1, DVec3::new(0.05, 0.0, 0.0), DVec3::Y),
            revolute("tibia", 2, DVec3::new(0.08, 0.0, 0.0), DVec3::Y),
            revolute("tarsus", 3, DVec3::new(0.12, 0.0, 0.0), DVec3::Y),
        ];
        let three = driven_three(&joints, &[0, 1, 2, 3], DVec3::new(0.03, 0.0, 0.0));
        assert_eq!(three[0], 0, "{three:?}");
        // the longest segments sweep the most: femur and tibia
        assert_eq!(three, vec![0, 1, 2]);
    }

    /// The workspace volume is |det J| integrated over the joints: for a planar two-link arm
    /// turned about a vertical axis it is 2π·∫∫ r·a·b·|sin θ₂| — checked against that integral
    /// on the same grid (an independent route through the analytic determinant).
    #[test]
    fn the_jacobian_determinant_is_the_analytic_one() {
        let (a, b) = (0.08, 0.12);
        let joints = vec![
            revolute("coxa", 0, DVec3::ZERO, DVec3::Z),
            revolute("femur", 1, DVec3::ZERO, DVec3::Y),
            revolute("tibia", 2, DVec3::new(a, 0.0, 0.0), DVec3::Y),
        ];
        let foot = DVec3::new(b, 0.0, 0.0);
        for (q1, q2) in [(0.3, 0.7), (-0.4, 1.2), (0.9, -0.5)] {
            let (axes, p) = forward(&joints, &[0, 1, 2], &[0.2, q1, q2], foot);
            let column = |i: usize| axes[i].1.cross(p - axes[i].0);
            let det = glam::DMat3::from_cols(column(0), column(1), column(2)).determinant();
            let r = (p.x * p.x + p.y * p.y).sqrt();
            let expected = r * a * b * f64::sin(q2);
            assert!(
                (det.abs() - expected.abs()).abs() < 1e-12,
                "{det} vs {expected}"
            );
        }
    }
}
