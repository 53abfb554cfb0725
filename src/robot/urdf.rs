//! URDF → [`RobotModel`]: parse with urdf-rs, check what urdf-rs does not (tree, limits, inertials),
//! merge fixed joints, find the feet and the six legs from the structure.
//!
//! Every error names the file and the element (link or joint) and says what was expected.

use super::model::{Foot, Joint, LEG_NAMES, Leg, Link, RobotModel, Shape, Visual};
use glam::{DAffine3, DMat3, DQuat, DVec3, EulerRot};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A URDF that hexsim cannot use.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {message}")]
pub struct RobotError {
    pub file: PathBuf,
    pub message: String,
}

fn pose(p: &urdf_rs::Pose) -> DAffine3 {
    let rotation = DQuat::from_euler(EulerRot::ZYX, p.rpy[2], p.rpy[1], p.rpy[0]);
    DAffine3::from_rotation_translation(rotation, DVec3::from_array(p.xyz.0))
}

/// Feet named in a robot file beside the URDF (`NAME.toml` next to `NAME.urdf`), for a robot whose
/// URDF does not mark its feet with collision spheres:
///
/// ```toml
/// [feet]
/// links = ["lf_tibia", "lm_tibia", "lr_tibia", "rf_tibia", "rm_tibia", "rr_tibia"]
/// offset = [0.12, 0.0, 0.0]   # foot centre in each link's frame (m)
/// radius = 0.01               # m
/// ```
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeetConfig {
    pub links: Vec<String>,
    pub offset: [f64; 3],
    pub radius: f64,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    feet: FeetConfig,
}

/// Loads and validates a URDF robot, with the robot file beside it if there is one.
pub fn load(path: &Path) -> Result<RobotModel, RobotError> {
    let fail = |message: String| RobotError {
        file: path.to_path_buf(),
        message,
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read the URDF: {e}")))?;
    let robot =
        urdf_rs::read_from_string(&text).map_err(|e| fail(format!("not a valid URDF: {e}")))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let robot_file = path.with_extension("toml");
    let feet = if robot_file.is_file() {
        let fail = |message: String| RobotError {
            file: robot_file.clone(),
            message,
        };
        let text = std::fs::read_to_string(&robot_file)
            .map_err(|e| fail(format!("cannot read the robot file: {e}")))?;
        let file: RobotFile =
            toml::from_str(&text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
        if !(file.feet.radius.is_finite() && file.feet.radius > 0.0) {
            return Err(fail(format!(
                "field `feet.radius`: expected a finite number > 0, got {}",
                file.feet.radius
            )));
        }
        if let Some(missing) = file
            .feet
            .links
            .iter()
            .find(|name| !robot.links.iter().any(|l| &l.name == *name))
        {
            return Err(fail(format!(
                "field `feet.links`: `{missing}` is not a link of {}",
                path.display()
            )));
        }
        Some(file.feet)
    } else {
        None
    };
    build(&robot, base, feet.as_ref()).map_err(fail)
}

/// Parses URDF text (for tests); `base` resolves mesh paths.
pub fn from_str(text: &str, origin: &Path) -> Result<RobotModel, RobotError> {
    let fail = |message: String| RobotError {
        file: origin.to_path_buf(),
        message,
    };
    let robot =
        urdf_rs::read_from_string(text).map_err(|e| fail(format!("not a valid URDF: {e}")))?;
    build(&robot, origin.parent().unwrap_or(Path::new(".")), None).map_err(fail)
}

struct Tree<'a> {
    /// link name → index in robot.links
    index: HashMap<&'a str, usize>,
    /// link index → the joint (index in robot.joints) whose child it is
    parent: Vec<Option<usize>>,
    children: Vec<Vec<usize>>,
    root: usize,
}

fn tree(robot: &urdf_rs::Robot) -> Result<Tree<'_>, String> {
    if robot.links.is_empty() {
        return Err("no <link> elements: a robot needs at least a body".into());
    }
    let mut index = HashMap::new();
    for (k, link) in robot.links.iter().enumerate() {
        if index.insert(link.name.as_str(), k).is_some() {
            return Err(format!("link `{}` is defined twice", link.name));
        }
    }
    let mut parent = vec![None; robot.links.len()];
    let mut children = vec![Vec::new(); robot.links.len()];
    for (j, joint) in robot.joints.iter().enumerate() {
        let find = |name: &str, role: &str| {
            index.get(name).copied().ok_or_else(|| {
                format!(
                    "joint `{}`: its {role} link `{name}` is not defined",
                    joint.name
                )
            })
        };
        let p = find(&joint.parent.link, "parent")?;
        let c = find(&joint.child.link, "child")?;
        if let Some(other) = parent[c] {
            let other: usize = other;
            return Err(format!(
                "link `{}` has two parent joints, `{}` and `{}` (a URDF is a tree)",
                joint.child.link, robot.joints[other].name, joint.name
            ));
        }
        parent[c] = Some(j);
        children[p].push(j);
    }
    let roots: Vec<&str> = (0..robot.links.len())
        .filter(|&k| parent[k].is_none())
        .map(|k| robot.links[k].name.as_str())
        .collect();
    match roots.len() {
        0 => return Err("every link has a parent: the joints form a cycle".into()),
        1 => {}
        _ => {
            return Err(format!(
                "{} root links ({}), expected one body all others hang from",
                roots.len(),
                roots.join(", ")
            ));
        }
    }
    let root = index[roots[0]];
    // reachability from the root: any link not reached sits on a cycle
    let mut seen = vec![false; robot.links.len()];
    let mut stack = vec![root];
    while let Some(k) = stack.pop() {
        seen[k] = true;
        for &j in &children[k] {
            stack.push(index[robot.joints[j].child.link.as_str()]);
        }
    }
    if let Some(k) = seen.iter().position(|s| !s) {
        return Err(format!(
            "link `{}` is on a cycle of joints, not in the tree under `{}`",
            robot.links[k].name, roots[0]
        ));
    }
    Ok(Tree {
        index,
        parent,
        children,
        root,
    })
}

fn check_inertial(link: &urdf_rs::Link) -> Result<(f64, DVec3, DMat3), String> {
    let i = &link.inertial;
    let mass = i.mass.value;
    if !mass.is_finite() || mass < 0.0 {
        return Err(format!(
            "link `{}`: <mass value> must be a finite number ≥ 0, got {mass}",
            link.name
        ));
    }
    let t = &i.inertia;
    let values = [t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
    if values.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "link `{}`: <inertia> has a non-finite entry",
            link.name
        ));
    }
    let local = DMat3::from_cols_array(&[
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    ]);
    let frame = pose(&i.origin);
    let rotation = frame.matrix3;
    Ok((
        mass,
        frame.translation,
        rotation * local * rotation.transpose(),
    ))
}

fn positive_definite(m: &DMat3) -> bool {
    let a = m.to_cols_array_2d();
    let minor1 = a[0][0];
    let minor2 = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    minor1 > 0.0 && minor2 > 0.0 && m.determinant() > 0.0
}

fn color_of(robot: &urdf_rs::Robot, material: &Option<urdf_rs::Material>) -> [f32; 4] {
    let default = [0.6, 0.6, 0.65, 1.0];
    let Some(material) = material else {
        return default;
    };
    let rgba = material.color.as_ref().or_else(|| {
        robot
            .materials
            .iter()
            .find(|m| m.name == material.name)
            .and_then(|m| m.color.as_ref())
    });
    rgba.map_or(default, |c| c.rgba.0.map(|v| v as f32))
}

fn shape(
    geometry: &urdf_rs::Geometry,
    base: &Path,
    link: &str,
    warnings: &mut Vec<String>,
) -> Shape {
    match geometry {
        urdf_rs::Geometry::Box { size } => Shape::Box {
            half_extents: DVec3::from_array(size.0) * 0.5,
        },
        urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
            radius: *radius,
            length: *length,
        },
        urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
            radius: *radius,
            length: *length,
        },
        urdf_rs::Geometry::Sphere { radius } => Shape::Sphere { radius: *radius },
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let relative = filename
                .trim_start_matches("package://")
                .trim_start_matches("file://");
            let path = base.join(relative);
            if path.is_file() {
                Shape::Mesh {
                    path,
                    scale: scale
                        .as_ref()
                        .map_or(DVec3::ONE, |s| DVec3::from_array(s.0)),
                }
            } else {
                warnings.push(format!(
                    "link `{link}`: visual mesh {} not found; drawn as a small sphere",
                    path.display()
                ));
                Shape::Sphere { radius: 0.01 }
            }
        }
    }
}

fn build(
    robot: &urdf_rs::Robot,
    base: &Path,
    feet: Option<&FeetConfig>,
) -> Result<RobotModel, String> {
    let tree = tree(robot)?;
    let mut warnings = Vec::new();
    let mut mesh_collisions = Vec::new();
    // Walk the tree from the root, parents before children. Each URDF link maps to a body (itself,
    // or the body it is welded to by fixed joints) and its pose in that body's frame.
    let mut body_of = vec![usize::MAX; robot.links.len()];
    let mut in_body = vec![DAffine3::IDENTITY; robot.links.len()];
    let mut links: Vec<Link> = Vec::new();
    let mut joints: Vec<Joint> = Vec::new();
    let mut order = vec![tree.root];
    let mut cursor = 0;
    while cursor < order.len() {
        let k = order[cursor];
        cursor += 1;
        let urdf_link = &robot.links[k];
        match tree.parent[k] {
            None => {
                body_of[k] = links.len();
                links.push(empty_link(&urdf_link.name, None));
            }
            Some(j) => {
                let joint = &robot.joints[j];
                let parent = tree.index[joint.parent.link.as_str()];
                let origin = in_body[parent] * pose(&joint.origin);
                match &joint.joint_type {
                    urdf_rs::JointType::Fixed => {
                        body_of[k] = body_of[parent];
                        in_body[k] = origin;
                    }
                    urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                        let axis = DVec3::from_array(joint.axis.xyz.0);
                        if !(axis.is_finite() && axis.length() > 1e-9) {
                            return Err(format!(
                                "joint `{}`: <axis xyz> must have a non-zero length, got {axis}",
                                joint.name
                            ));
                        }
                        let (lower, upper) =
                            if matches!(joint.joint_type, urdf_rs::JointType::Continuous) {
                                (f64::NEG_INFINITY, f64::INFINITY)
                            } else {
                                (joint.limit.lower, joint.limit.upper)
                            };
                        let ordered = lower < upper;
                        if !ordered {
                            return Err(format!(
                                "joint `{}`: a revolute joint needs <limit lower=… upper=…> with lower < upper, got lower = {lower}, upper = {upper} (a missing <limit> reads as 0, 0)",
                                joint.name
                            ));
                        }
                        let effort = joint.limit.effort;
                        if !(effort.is_finite() && effort > 0.0) {
                            return Err(format!(
                                "joint `{}`: <limit effort> (the servo's torque limit, N·m) must be > 0, got {effort}",
                                joint.name
                            ));
                        }
                        body_of[k] = links.len();
                        links.push(empty_link(&urdf_link.name, Some(joints.len())));
                        joints.push(Joint {
                            name: joint.name.clone(),
                            parent: body_of[parent],
                            child: body_of[k],
                            origin,
                            axis: axis.normalize(),
                            lower,
                            upper,
                            effort,
                        });
                    }
                    other => {
                        return Err(format!(
                            "joint `{}`: type {other:?} is not supported (hexsim's legs are chains of revolute joints; use fixed for rigid attachments)",
                            joint.name
                        ));
                    }
                }
            }
        }
        // fold this URDF link's inertial, visuals and foot into its body
        let (mass, com, inertia) = check_inertial(urdf_link)?;
        let frame = in_body[k];
        let body = &mut links[body_of[k]];
        add_mass(
            body,
            mass,
            frame.transform_point3(com),
            frame.matrix3 * inertia * frame.matrix3.transpose(),
        );
        for visual in &urdf_link.visual {
            body.visuals.push(Visual {
                origin: frame * pose(&visual.origin),
                shape: shape(&visual.geometry, base, &urdf_link.name, &mut warnings),
                color: color_of(robot, &visual.material),
            });
        }
        if let Some(feet) = feet
            && feet.links.contains(&urdf_link.name)
        {
            body.foot = Some(Foot {
                center: frame.transform_point3(DVec3::from_array(feet.offset)),
                radius: feet.radius,
            });
        }
        for collision in urdf_link.collision.iter().filter(|_| feet.is_none()) {
            if let urdf_rs::Geometry::Mesh { filename, .. } = &collision.geometry {
                mesh_collisions.push((
                    urdf_link.name.clone(),
                    filename.clone(),
                    base.to_path_buf(),
                ));
            }
            if let urdf_rs::Geometry::Sphere { radius } = collision.geometry {
                if !(radius.is_finite() && radius > 0.0) {
                    return Err(format!(
                        "link `{}`: foot sphere radius must be > 0, got {radius}",
                        urdf_link.name
                    ));
                }
                if body.foot.is_none() {
                    body.foot = Some(Foot {
                        center: (frame * pose(&collision.origin)).translation,
                        radius,
                    });
                }
            }
        }
        for &j in &tree.children[k] {
            order.push(tree.index[robot.joints[j].child.link.as_str()]);
        }
    }
    for link in &links {
        let massive = link.mass > 0.0;
        if !massive {
            return Err(format!(
                "link `{}`: mass must be > 0 (a link moved by a joint needs inertia; give it an <inertial>)",
                link.name
            ));
        }
        if !positive_definite(&link.inertia) {
            return Err(format!(
                "link `{}`: the inertia tensor is not positive definite ({:?})",
                link.name,
                link.inertia.to_cols_array()
            ));
        }
    }
    let legs = find_legs(&links, &joints, &mesh_collisions)?;
    Ok(RobotModel {
        name: robot.name.clone(),
        source: PathBuf::new(),
        links,
        joints,
        legs,
        warnings,
    })
}

fn empty_link(name: &str, parent_joint: Option<usize>) -> Link {
    Link {
        name: name.to_string(),
        parent_joint,
        mass: 0.0,
        com: DVec3::ZERO,
        inertia: DMat3::ZERO,
        visuals: Vec::new(),
        foot: None,
    }
}

/// Adds a point mass distribution (mass at `com` with `inertia` about it, all in the body frame)
/// to a body: combined centre of mass, parallel-axis theorem for the inertia.
fn add_mass(body: &mut Link, mass: f64, com: DVec3, inertia: DMat3) {
    if mass <= 0.0 {
        return;
    }
    let total = body.mass + mass;
    let new_com = (body.com * body.mass + com * mass) / total;
    let shift =
        |m: f64, d: DVec3| DMat3::from_diagonal(DVec3::splat(d.dot(d))) * m - outer(d, d) * m;
    body.inertia =
        body.inertia + shift(body.mass, body.com - new_com) + inertia + shift(mass, com - new_com);
    body.mass = total;
    body.com = new_com;
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// The legs: every body with a foot, traced back to the root; each must hang from the root by
/// exactly three joints, three on each side of the body.
/// `mesh_collisions`: (link, mesh file, folder it resolves from) of every collision mesh, to say
/// what is wrong with a leg whose foot is a mesh.
fn find_legs(
    links: &[Link],
    joints: &[Joint],
    mesh_collisions: &[(String, String, std::path::PathBuf)],
) -> Result<Vec<Leg>, String> {
    let mut found = Vec::new();
    for (k, link) in links.iter().enumerate() {
        let Some(foot) = link.foot else { continue };
        let mut chain = Vec::new();
        let mut at = k;
        while let Some(j) = links[at].parent_joint {
            chain.push(j);
            at = joints[j].parent;
        }
        chain.reverse();
        if chain.len() != 3 {
            return Err(format!(
                "the foot on link `{}` hangs from the body by {} joints, expected 3 (coxa, femur, tibia)",
                link.name,
                chain.len()
            ));
        }
        found.push((chain, k, foot));
    }
    // leaves without a foot are legs without a foot
    for (k, link) in links.iter().enumerate() {
        let is_leaf = !joints.iter().any(|j| j.parent == k);
        if is_leaf && k != 0 && link.foot.is_none() {
            if let Some((_, file, base)) = mesh_collisions.iter().find(|(l, ..)| *l == link.name) {
                let relative = file
                    .trim_start_matches("package://")
                    .trim_start_matches("file://");
                let path = base.join(relative);
                let problem = if path.is_file() {
                    "hexsim's feet are spheres".to_string()
                } else {
                    format!("{} does not exist", path.display())
                };
                return Err(format!(
                    "link `{}` ends a leg and its foot is a collision mesh ({file}): {problem}; give the foot a <collision> with a <sphere>, or name it in a robot file (NAME.toml, [feet])",
                    link.name
                ));
            }
            return Err(format!(
                "link `{}` ends a chain but carries no foot: give it a <collision> with a <sphere> at the foot",
                link.name
            ));
        }
    }
    if found.len() != 6 {
        return Err(format!(
            "found {} legs (chains of 3 revolute joints ending in a foot sphere), expected 6 for a hexapod",
            found.len()
        ));
    }
    let shared = found
        .iter()
        .flat_map(|(c, ..)| c.iter())
        .collect::<std::collections::HashSet<_>>();
    if shared.len() != 18 {
        return Err("legs share joints: each of the six legs needs its own three joints".into());
    }
    // classify by where the first joint sits on the body
    let hip = |chain: &[usize]| joints[chain[0]].origin.translation;
    let (mut left, mut right): (Vec<_>, Vec<_>) =
        found.into_iter().partition(|(c, ..)| hip(c).y > 0.0);
    if left.len() != 3 || right.len() != 3 {
        return Err(format!(
            "expected three legs on each side of the body (hip y > 0 left, y < 0 right), found {} left and {} right",
            left.len(),
            right.len()
        ));
    }
    let by_x_descending = |a: &(Vec<usize>, usize, Foot), b: &(Vec<usize>, usize, Foot)| {
        hip(&b.0).x.total_cmp(&hip(&a.0).x)
    };
    left.sort_by(by_x_descending);
    right.sort_by(by_x_descending);
    Ok(left
        .into_iter()
        .chain(right)
        .zip(LEG_NAMES)
        .map(|((chain, foot_link, foot), name)| Leg {
            name,
            joints: [chain[0], chain[1], chain[2]],
            foot_link,
            foot,
        })
        .collect())
}
