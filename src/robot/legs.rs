//! The six legs of a robot, whatever its outline (rectangular, round, hexagonal) and whichever
//! way its URDF points: the chains of three to six joints from the body to a foot (`branches`
//! holds any other joints still first), the walking direction,
//! and each leg's name (`lf lm lr rf rm rr`) from where it sits around the body about that
//! direction, so every gait file works for every robot.
//!
//! The walking direction is the URDF's +x unless the robot file says otherwise
//! (`forward = "+y"`, or an angle in degrees about z). When the hips do not lie three on each side
//! of the x axis (a round robot with legs at 0° and 180°), hexsim picks the direction that splits
//! them: +y if it does, else the one that leaves the hips farthest from the axis, and says so.
//! The model is then turned about z so that its body frame's x is the walking direction.

pub use super::forward::{Forward, ForwardFrom};
use super::kinematics::MAX_LEG_JOINTS;
use super::model::{Foot, Joint, LEG_NAMES, Leg, Link};
use glam::{DAffine3, DMat3, DVec2};

/// A leg before it is named: its joints from the body out, their posture (`Leg::posture`), and
/// its foot.
struct Chain {
    joints: Vec<usize>,
    posture: Vec<Option<f64>>,
    foot_link: usize,
    foot: Foot,
}

/// A hip this close to the walking axis (as a fraction of the hips' mean distance from their
/// centre) is on neither side: the axis does not split the legs.
const SIDE_MARGIN: f64 = 0.05;

/// The legs found, named, and the walking direction. `forward`: the robot file's direction
/// (yaw, rad), if it gives one.
pub(super) fn find_legs(
    links: &[Link],
    joints: &[Joint],
    unfound: &[(String, String)],
    forward: Option<f64>,
) -> Result<(Vec<Leg>, Forward), String> {
    let chains = chains(links, joints, unfound)?;
    // each hip in the body frame (the first joint hangs from the root)
    let hips: Vec<DVec2> = chains
        .iter()
        .map(|c| joints[c.joints[0]].origin.translation.truncate())
        .collect();
    let forward = match forward {
        Some(yaw) => {
            let f = Forward {
                yaw,
                from: ForwardFrom::RobotFile,
            };
            if split(&hips, yaw).is_none() {
                return Err(format!(
                    "the walking direction {} does not have three hips on each side ({}); set `forward` in the robot file to a direction that does",
                    f.describe(),
                    sides(&hips, yaw)
                ));
            }
            f
        }
        None => {
            let chosen = choose_forward(&hips).ok_or_else(|| {
                format!(
                    "the hips cannot be split three on each side of any walking direction (about x: {}); is it a hexapod?",
                    sides(&hips, 0.0)
                )
            })?;
            let names: Vec<Vec<&str>> = chains
                .iter()
                .map(|c| {
                    let mut names: Vec<&str> =
                        c.joints.iter().map(|&j| joints[j].name.as_str()).collect();
                    names.push(links[c.foot_link].name.as_str());
                    names
                })
                .collect();
            front_by_names(chosen, &hips, &names)
        }
    };
    // name by angle from the walking direction: left legs (to its left) front to rear, then right
    let (along, across) = axes(forward.yaw);
    let middle = centre(&hips);
    let angle = |h: DVec2| {
        let d = h - middle;
        d.dot(across).atan2(d.dot(along))
    };
    let mut order: Vec<usize> = (0..chains.len()).collect();
    order.sort_by(|&a, &b| {
        let (aa, ab) = (angle(hips[a]), angle(hips[b]));
        // left (angle > 0) before right, each by |angle| from the front
        (ab > 0.0)
            .cmp(&(aa > 0.0))
            .then(aa.abs().total_cmp(&ab.abs()))
    });
    let legs = order
        .into_iter()
        .zip(LEG_NAMES)
        .map(|(k, name)| Leg {
            name,
            joints: chains[k].joints.clone(),
            posture: chains[k].posture.clone(),
            foot_link: chains[k].foot_link,
            foot: chains[k].foot,
        })
        .collect();
    Ok((legs, forward))
}

/// Where a leg's names put it: +1 ahead (`front`, `fore`, `lf`, `rf`, `fl`, `fr`), −1 behind
/// (`rear`, `back`, `hind`, `lr`, `rr`, `rl`, `lh`, `rh`, `bl`, `br`, …), 0 neither or both; a
/// name's words are split at `_`, `-`, `/`, `.` and digits, case aside.
fn named_end(names: &[&str]) -> i32 {
    const AHEAD: [&str; 6] = ["front", "fore", "lf", "rf", "fl", "fr"];
    const BEHIND: [&str; 14] = [
        "rear", "back", "hind", "lr", "rr", "rl", "lh", "rh", "hl", "hr", "lb", "rb", "bl", "br",
    ];
    let words = names.iter().flat_map(|n| {
        n.split(|c: char| !c.is_ascii_alphabetic())
            .filter(|w| !w.is_empty())
            .map(|w| w.to_ascii_lowercase())
    });
    let (mut ahead, mut behind) = (false, false);
    for word in words {
        ahead |= AHEAD.contains(&word.as_str());
        behind |= BEHIND.contains(&word.as_str());
    }
    i32::from(ahead) - i32::from(behind)
}

/// A direction chosen from the legs, turned about when the legs' names put the front behind it:
/// the legs named front sit, on average, behind the hips' centre along it. The URDF's own x is
/// never turned (REP 103: x forward); names only settle which way along a chosen axis.
fn front_by_names(chosen: Forward, hips: &[DVec2], names: &[Vec<&str>]) -> Forward {
    if chosen.from != ForwardFrom::Legs {
        return chosen;
    }
    let (along, _) = axes(chosen.yaw);
    let middle = centre(hips);
    let lean: f64 = hips
        .iter()
        .zip(names)
        .map(|(h, n)| f64::from(named_end(n)) * (*h - middle).dot(along))
        .sum();
    if lean < 0.0 {
        let yaw = chosen.yaw + std::f64::consts::PI;
        Forward {
            yaw: yaw.sin().atan2(yaw.cos()),
            from: ForwardFrom::LegNames,
        }
    } else {
        chosen
    }
}

/// The walking direction and the direction to its left, in the body's xy plane.
fn axes(yaw: f64) -> (DVec2, DVec2) {
    let (s, c) = yaw.sin_cos();
    (DVec2::new(c, s), DVec2::new(-s, c))
}

/// The hips' centre (the walking axis passes through it).
fn centre(hips: &[DVec2]) -> DVec2 {
    hips.iter().copied().sum::<DVec2>() / hips.len().max(1) as f64
}

/// How far each hip sits to the left of the walking axis `yaw` through the hips' centre, and how
/// close to the axis a hip may be before it is on neither side.
fn laterals(hips: &[DVec2], yaw: f64) -> (Vec<f64>, f64) {
    let c = centre(hips);
    let scale = hips.iter().map(|h| (*h - c).length()).sum::<f64>() / hips.len().max(1) as f64;
    let (_, across) = axes(yaw);
    let lateral = hips.iter().map(|h| (*h - c).dot(across)).collect();
    (lateral, SIDE_MARGIN * scale)
}

/// If three hips sit clearly on each side of the walking axis: the smallest distance of a hip
/// from it.
pub(super) fn split(hips: &[DVec2], yaw: f64) -> Option<f64> {
    let (lateral, margin) = laterals(hips, yaw);
    let left = lateral.iter().filter(|&&l| l > 0.0).count();
    let clear = lateral.iter().all(|l| l.abs() > margin);
    (left == 3 && lateral.len() == 6 && clear)
        .then(|| lateral.iter().fold(f64::INFINITY, |m, l| m.min(l.abs())))
}

/// Counts of hips left, right and on the axis, for messages.
fn sides(hips: &[DVec2], yaw: f64) -> String {
    let (lateral, margin) = laterals(hips, yaw);
    let on = lateral.iter().filter(|l| l.abs() <= margin).count();
    let left = lateral.iter().filter(|&&l| l > margin).count();
    format!(
        "{left} left, {} right, {on} on the axis",
        lateral.len() - left - on
    )
}

/// The URDF's +x if it splits the hips three a side; else +y; else, of the whole degrees, the
/// direction whose nearest hip is farthest from the axis (the first such from +x).
pub(super) fn choose_forward(hips: &[DVec2]) -> Option<Forward> {
    if split(hips, 0.0).is_some() {
        return Some(Forward::URDF_X);
    }
    let chosen = |yaw: f64| Forward {
        yaw,
        from: ForwardFrom::Legs,
    };
    if split(hips, std::f64::consts::FRAC_PI_2).is_some() {
        return Some(chosen(std::f64::consts::FRAC_PI_2));
    }
    let mut best: Option<(f64, f64)> = None;
    for deg in 1..360 {
        let yaw = (deg as f64).to_radians();
        if let Some(margin) = split(hips, yaw)
            && best.is_none_or(|(_, m)| margin > m + 1e-12)
        {
            best = Some((yaw, margin));
        }
    }
    best.map(|(yaw, _)| chosen(yaw))
}

/// Turns the model about z so that its body frame's x is the walking direction `yaw`: what hangs
/// from the root (its visuals, mass, the joints on it) is re-expressed in the turned frame.
pub(super) fn turn_to_forward(links: &mut [Link], joints: &mut [Joint], yaw: f64) {
    if yaw == 0.0 {
        return;
    }
    let turn = DAffine3::from_rotation_z(-yaw);
    let rotation = DMat3::from_rotation_z(-yaw);
    let root = &mut links[0];
    root.com = rotation * root.com;
    root.inertia = rotation * root.inertia * rotation.transpose();
    for visual in &mut root.visuals {
        visual.origin = turn * visual.origin;
    }
    if let Some(foot) = &mut root.foot {
        foot.center = rotation * foot.center;
    }
    for sphere in &mut root.contacts {
        sphere.center = rotation * sphere.center;
    }
    for joint in joints.iter_mut().filter(|j| j.parent == 0) {
        joint.origin = turn * joint.origin;
    }
}

/// The message for a leaf link without a foot: `why` none could be found at its tip.
pub(super) fn footless_leg(link: &str, why: Option<&String>) -> String {
    match why {
        Some(why) => format!(
            "link `{link}` ends a leg and has no foot sphere, and no foot could be found at its tip: {why}; give the foot a <collision> with a <sphere>, or name it in a robot file (NAME.toml, [feet])"
        ),
        None => format!(
            "link `{link}` ends a chain but carries no foot: give it a <collision> with a <sphere> at the foot"
        ),
    }
}

/// The six chains from the body to a foot: every leaf link with a foot, traced back to the root;
/// each must hang from it by three to [`MAX_LEG_JOINTS`] joints of its own (`branches` has held
/// any others still). A foot on the body or on a link that is not a leaf is contact geometry, not a leg's
/// end. `unfound`: (link, why) for each leaf whose foot could not be found from its geometry.
/// Whether link `k` ends a chain: not the root, and no joint hangs from it.
pub(super) fn is_leaf(joints: &[Joint], k: usize) -> bool {
    k != 0 && !joints.iter().any(|j| j.parent == k)
}

/// The joints from the body out to link `k`.
pub(super) fn chain_to(links: &[Link], joints: &[Joint], k: usize) -> Vec<usize> {
    let mut chain = Vec::new();
    let mut at = k;
    while let Some(j) = links[at].parent_joint {
        chain.push(j);
        at = joints[j].parent;
    }
    chain.reverse();
    chain
}

fn chains(
    links: &[Link],
    joints: &[Joint],
    unfound: &[(String, String)],
) -> Result<Vec<Chain>, String> {
    let mut found = Vec::new();
    for (k, link) in links.iter().enumerate() {
        if !is_leaf(joints, k) {
            continue;
        }
        let Some(foot) = link.foot else {
            let why = unfound
                .iter()
                .find(|(l, _)| *l == link.name)
                .map(|(_, w)| w);
            return Err(footless_leg(&link.name, why));
        };
        let chain = chain_to(links, joints, k);
        if !(3..=MAX_LEG_JOINTS).contains(&chain.len()) {
            return Err(format!(
                "the foot on link `{}` hangs from the body by {} joints, expected 3 to {MAX_LEG_JOINTS} (coxa, femur, tibia and any tarsus, hip roll, …)",
                link.name,
                chain.len()
            ));
        }
        // the three that place the foot; the others (a redundant leg's) pulled to their rest
        let three = super::branches::driven_three(joints, &chain, foot.center);
        let posture = chain
            .iter()
            .map(|j| (!three.contains(j)).then(|| super::branches::hold_angle(&joints[*j])))
            .collect();
        found.push(Chain {
            joints: chain,
            posture,
            foot_link: k,
            foot,
        });
    }
    if found.len() != 6 {
        return Err(super::branches::found_too_few(found.len()));
    }
    let shared = found
        .iter()
        .flat_map(|c| c.joints.iter())
        .collect::<std::collections::HashSet<_>>();
    if shared.len() != found.iter().map(|c| c.joints.len()).sum::<usize>() {
        return Err("legs share joints: each of the six legs needs its own joints".into());
    }
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(degrees: &[f64]) -> Vec<DVec2> {
        degrees
            .iter()
            .map(|d| 0.1 * DVec2::new(d.to_radians().cos(), d.to_radians().sin()))
            .collect()
    }

    #[test]
    fn a_rectangular_or_round_robot_split_about_x_walks_along_x() {
        let rectangle = [(0.12, 0.06), (0.0, 0.08), (-0.12, 0.06)]
            .iter()
            .flat_map(|&(x, y)| [DVec2::new(x, y), DVec2::new(x, -y)])
            .collect::<Vec<_>>();
        assert_eq!(choose_forward(&rectangle), Some(Forward::URDF_X));
        let round = ring(&[30.0, 90.0, 150.0, 210.0, 270.0, 330.0]);
        assert_eq!(choose_forward(&round), Some(Forward::URDF_X));
    }

    #[test]
    fn legs_on_the_x_axis_make_it_walk_along_y() {
        for hips in [
            ring(&[0.0, 45.0, 135.0, 180.0, 225.0, 315.0]),
            ring(&[0.0, 60.0, 120.0, 180.0, 240.0, 300.0]),
        ] {
            let forward = choose_forward(&hips).unwrap();
            assert_eq!(forward.from, ForwardFrom::Legs);
            assert!((forward.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
            assert!(
                forward.describe().starts_with("+y"),
                "{}",
                forward.describe()
            );
        }
    }

    #[test]
    fn an_off_axis_layout_gets_the_direction_that_clears_the_hips_most() {
        // legs on both the x and the y axis: neither splits them three a side
        let hips = ring(&[0.0, 90.0, 150.0, 180.0, 270.0, 330.0]);
        assert!(split(&hips, 0.0).is_none() && split(&hips, std::f64::consts::FRAC_PI_2).is_none());
        let forward = choose_forward(&hips).unwrap();
        assert_eq!(forward.from, ForwardFrom::Legs);
        let margin = split(&hips, forward.yaw).unwrap();
        for deg in 0..360 {
            if let Some(m) = split(&hips, (deg as f64).to_radians()) {
                assert!(
                    m <= margin + 1e-12,
                    "{deg}° clears the hips by {m} > {margin}"
                );
            }
        }
    }

    /// Legs on the x axis make hexsim walk along y; front legs named at −y turn it to −y (issue
    /// 40: a robot walked along +y although its `front_*` legs sat at −y), and names that say
    /// nothing, or the URDF's own x, leave the direction as it is.
    #[test]
    fn leg_names_put_the_front_where_the_geometry_leaves_it_open() {
        let hips = ring(&[0.0, 45.0, 135.0, 180.0, 225.0, 315.0]);
        let chosen = choose_forward(&hips).unwrap();
        assert!((chosen.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // front legs at −y (225° and 315°), rear legs at +y (45°, 135°)
        let named = |deg: f64| -> Vec<&str> {
            match deg as i32 {
                225 | 315 => vec!["front_left_coxa_joint"],
                45 | 135 => vec!["rear_right_coxa_joint"],
                _ => vec!["middle_coxa_joint"],
            }
        };
        let degrees = [0.0, 45.0, 135.0, 180.0, 225.0, 315.0];
        let names: Vec<Vec<&str>> = degrees.iter().map(|&d| named(d)).collect();
        let turned = front_by_names(chosen, &hips, &names);
        assert_eq!(turned.from, ForwardFrom::LegNames);
        assert!(
            (turned.yaw + std::f64::consts::FRAC_PI_2).abs() < 1e-12,
            "{}",
            turned.yaw
        );
        assert!(turned.describe().starts_with("-y"), "{}", turned.describe());
        let silent: Vec<Vec<&str>> = degrees.iter().map(|_| vec!["leg_joint_1"]).collect();
        assert_eq!(front_by_names(chosen, &hips, &silent), chosen);
        assert_eq!(
            front_by_names(Forward::URDF_X, &hips, &names),
            Forward::URDF_X
        );
        assert_eq!(named_end(&["leg_FR_1"]), 1);
        assert_eq!(named_end(&["hind_left_femur", "lh_foot"]), -1);
        assert_eq!(named_end(&["AR_coxa_joint"]), 0);
    }

    #[test]
    fn a_direction_with_hips_on_its_axis_is_refused() {
        let hips = ring(&[0.0, 45.0, 135.0, 180.0, 225.0, 315.0]);
        assert!(split(&hips, 0.0).is_none());
        assert_eq!(sides(&hips, 0.0), "2 left, 2 right, 2 on the axis");
    }
}
