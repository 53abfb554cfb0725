//! URDF → [`RobotModel`]: parse with urdf-rs, check what urdf-rs does not (tree, limits, inertials),
//! merge fixed joints, find the feet and the six legs from the structure.
//!
//! Every error names the file and the element (link or joint) and says what was expected.

use super::branches;
use super::contact_set;
use super::foot::{self, Placed};
use super::legs::{self, Forward};
use super::mesh;
use super::model::{Foot, FootFrom, GaitHints, HeldJoint, Joint, Link, RobotModel, Shape, Visual};
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

/// A robot file beside the URDF (`NAME.toml` next to `NAME.urdf`) says what the URDF does not:
///
/// ```toml
/// forward = "+y"              # walking direction: "+x" (default) "-x" "+y" "-y", or degrees about z
/// [feet]                      # for a URDF that does not mark its feet with collision spheres
/// links = ["lf_tibia", "lm_tibia", "lr_tibia", "rf_tibia", "rm_tibia", "rr_tibia"]
/// offset = [0.12, 0.0, 0.0]   # foot centre in each link's frame (m)
/// radius = 0.01               # m
/// [gait]                      # the stance this robot was designed for (m); any may be left out
/// stance_height = 0.10        # and is then fitted, and a gait file's own values win
/// reach = 0.15
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
    #[serde(default)]
    feet: Option<FeetConfig>,
    #[serde(default)]
    forward: Option<toml::Value>,
    #[serde(default)]
    gait: Option<GaitHints>,
}

/// The robot file's `forward` as an angle about z (rad).
fn forward_yaw(value: &toml::Value) -> Result<f64, String> {
    let yaw = match value {
        toml::Value::String(s) => match s.as_str() {
            "+x" | "x" => 0.0,
            "+y" | "y" => 90.0,
            "-x" => 180.0,
            "-y" => -90.0,
            other => {
                return Err(format!(
                    "field `forward`: expected \"+x\", \"-x\", \"+y\", \"-y\" or an angle in degrees, got {other:?}"
                ));
            }
        },
        toml::Value::Integer(d) => *d as f64,
        toml::Value::Float(d) if d.is_finite() => *d,
        other => {
            return Err(format!(
                "field `forward`: expected \"+x\", \"-x\", \"+y\", \"-y\" or an angle in degrees, got {other}"
            ));
        }
    };
    Ok(yaw.to_radians())
}

/// Loads and validates a URDF robot, with the robot file beside it if there is one.
pub fn load(path: &Path) -> Result<RobotModel, RobotError> {
    let text =
        crate::limits::read_to_string(path, crate::limits::TEXT_FILE_BYTES).map_err(|e| {
            RobotError {
                file: path.to_path_buf(),
                message: format!("cannot read the URDF: {e}"),
            }
        })?;
    refuse_xacro(&text, path).map_err(|message| RobotError {
        file: path.to_path_buf(),
        message,
    })?;
    let robot_file = path.with_extension("toml");
    let robot_text = if robot_file.is_file() {
        Some(
            crate::limits::read_to_string(&robot_file, crate::limits::TEXT_FILE_BYTES).map_err(
                |e| RobotError {
                    file: robot_file.clone(),
                    message: format!("cannot read the robot file: {e}"),
                },
            )?,
        )
    } else {
        None
    };
    from_str_with(&text, robot_text.as_deref(), path)
}

/// Drops a URDF's marker frames: links of negligible mass (under 1 % of the robot's) with no
/// visual or collision and no children, hung from anything by a floating joint (Phobos writes a
/// foot's frame so), then a root of that kind whose one remaining joint is floating (Phobos's
/// free base: the body floats from a 1 g root). hexsim's base floats already; any other floating
/// joint is still refused. Returns the dropped joints' names.
fn drop_marker_frames(robot: &mut urdf_rs::Robot) -> Vec<String> {
    let total: f64 = robot.links.iter().map(|l| l.inertial.mass.value).sum();
    let bare = |link: &urdf_rs::Link| {
        link.inertial.mass.value <= 0.01 * total
            && link.visual.is_empty()
            && link.collision.is_empty()
    };
    let floating = |j: &urdf_rs::Joint| matches!(j.joint_type, urdf_rs::JointType::Floating);
    let mut dropped = Vec::new();
    let markers: Vec<String> = robot
        .joints
        .iter()
        .filter(|j| floating(j))
        .filter(|j| {
            let child = &j.child.link;
            !robot.joints.iter().any(|o| &o.parent.link == child)
                && robot.links.iter().any(|l| &l.name == child && bare(l))
        })
        .map(|j| j.child.link.clone())
        .collect();
    robot.joints.retain(|j| {
        let marker = markers.contains(&j.child.link);
        if marker {
            dropped.push(j.name.clone());
        }
        !marker
    });
    robot.links.retain(|l| !markers.contains(&l.name));
    // the root: the link no joint has as its child
    let root = robot
        .links
        .iter()
        .find(|l| !robot.joints.iter().any(|j| j.child.link == l.name))
        .filter(|l| bare(l))
        .map(|l| l.name.clone());
    if let Some(root) = root {
        let from_root: Vec<&urdf_rs::Joint> = robot
            .joints
            .iter()
            .filter(|j| j.parent.link == root)
            .collect();
        if let [only] = from_root[..]
            && floating(only)
        {
            let name = only.name.clone();
            dropped.push(name.clone());
            robot.joints.retain(|j| j.name != name);
            robot.links.retain(|l| l.name != root);
        }
    }
    dropped
}

/// What a robot file says, checked against the URDF it goes with.
#[derive(Debug, Default)]
struct RobotFileSettings {
    feet: Option<FeetConfig>,
    forward: Option<f64>,
    gait: GaitHints,
}

fn read_robot_file(
    text: &str,
    robot: &urdf_rs::Robot,
    urdf: &Path,
) -> Result<RobotFileSettings, String> {
    let file: RobotFile = toml::from_str(text).map_err(|e| e.to_string().trim_end().to_string())?;
    if let Some(feet) = &file.feet {
        if !(feet.radius.is_finite() && feet.radius > 0.0) {
            return Err(format!(
                "field `feet.radius`: expected a finite number > 0, got {}",
                feet.radius
            ));
        }
        if let Some(missing) = feet
            .links
            .iter()
            .find(|name| !robot.links.iter().any(|l| &l.name == *name))
        {
            return Err(format!(
                "field `feet.links`: `{missing}` is not a link of {}",
                urdf.display()
            ));
        }
    }
    let gait = file.gait.unwrap_or_default();
    gait.validate()?;
    Ok(RobotFileSettings {
        forward: file.forward.as_ref().map(forward_yaw).transpose()?,
        feet: file.feet,
        gait,
    })
}

/// Parses URDF text, with the text of its robot file if it has one (the built-in hex18; tests);
/// `origin` names the URDF in messages and resolves mesh paths.
pub fn from_str_with(
    text: &str,
    robot_file: Option<&str>,
    origin: &Path,
) -> Result<RobotModel, RobotError> {
    let fail = |message: String| RobotError {
        file: origin.to_path_buf(),
        message,
    };
    // a recursive parser: its nesting is checked first, or a deep one overflows the stack
    crate::limits::xml_depth(text, crate::limits::XML_DEPTH).map_err(|(depth, line)| {
        fail(format!(
            "not a valid URDF: line {line}: elements nested {depth} deep, deeper than the {} hexsim reads (a URDF's are 4 or 5)",
            crate::limits::XML_DEPTH
        ))
    })?;
    let mut robot =
        urdf_rs::read_from_string(text).map_err(|e| fail(format!("not a valid URDF: {e}")))?;
    let dropped = drop_marker_frames(&mut robot);
    let settings = match robot_file {
        None => RobotFileSettings::default(),
        Some(file) => read_robot_file(file, &robot, origin).map_err(|message| RobotError {
            file: origin.with_extension("toml"),
            message,
        })?,
    };
    let mut model =
        build(&robot, origin.parent().unwrap_or(Path::new(".")), settings).map_err(fail)?;
    if !dropped.is_empty() {
        model.warnings.push(format!(
            "{} floating joint{} to massless frames without shapes dropped ({}): a free base and marker frames, as Phobos writes them; hexsim's base floats anyway",
            dropped.len(),
            plural(dropped.len()),
            dropped.join(", ")
        ));
    }
    Ok(model)
}

/// The plural ending of a count's noun: "" for one, "s" otherwise.
fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Parses URDF text alone (for tests); `origin` resolves mesh paths.
pub fn from_str(text: &str, origin: &Path) -> Result<RobotModel, RobotError> {
    from_str_with(text, None, origin)
}

/// A xacro file is a URDF template, which only xacro (ROS) expands. xacro's own output keeps the
/// `xmlns:xacro` declaration and often comments holding xacro elements: only a live xacro
/// element or a `${…}` expression outside comments marks a template.
fn refuse_xacro(text: &str, path: &Path) -> Result<(), String> {
    let named = path.extension().is_some_and(|e| e == "xacro");
    let live = without_comments(text);
    if named || live.contains("<xacro:") || live.contains("${") {
        return Err(
            "this is a xacro file (a URDF template): expand it first with xacro (from ROS: `xacro FILE > robot.urdf`) and give hexsim the URDF".into(),
        );
    }
    Ok(())
}

/// XML text without its `<!-- … -->` comments (an unclosed comment runs to the end).
fn without_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<!--") {
        out.push_str(&rest[..start]);
        rest = rest[start + 4..]
            .find("-->")
            .map_or("", |end| &rest[start + 4 + end + 3..]);
    }
    out.push_str(rest);
    out
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
    let mut joint_names = std::collections::HashSet::new();
    for joint in &robot.joints {
        if !joint_names.insert(joint.name.as_str()) {
            return Err(format!(
                "joint `{}` is defined twice (joint names must be unique: they name the trajectory's columns)",
                joint.name
            ));
        }
        let origin = &joint.origin;
        if origin
            .xyz
            .iter()
            .chain(origin.rpy.iter())
            .any(|v| !v.is_finite())
        {
            return Err(format!(
                "joint `{}`: <origin xyz rpy> must be finite numbers, got xyz = {:?}, rpy = {:?}",
                joint.name, *origin.xyz, *origin.rpy
            ));
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

/// The principal moments (ascending) of an inertia tensor no rigid body can have: the two smaller
/// sum to less than the largest (A + B ≥ C holds for any mass distribution, since
/// A + B − C = 2∫z² dm about the principal axes). None if the tensor is physical, to a relative
/// 10⁻⁶ that forgives rounding in a URDF's digits (a rod or a disc sits on the bound exactly).
fn impossible_inertia(m: &DMat3) -> Option<[f64; 3]> {
    use rapier3d::na;
    let a = m.to_cols_array();
    let mut moments: Vec<f64> = na::Matrix3::from_column_slice(&a)
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .collect();
    moments.sort_by(f64::total_cmp);
    let [a, b, c] = [moments[0], moments[1], moments[2]];
    (a + b < c * (1.0 - 1e-6)).then_some([a, b, c])
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

/// Visual meshes that could not be used, gathered over the robot so that `build` warns once per
/// kind of problem rather than once per link.
#[derive(Default)]
struct MeshProblems {
    /// (link, file) of meshes in a format the recording cannot draw.
    undrawable: Vec<(String, PathBuf)>,
    /// Per mesh not found: the warning for it (link, URI, where it was looked for).
    missing: Vec<String>,
}

impl MeshProblems {
    /// At most one warning for the undrawable meshes and one for the missing ones.
    fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        if let Some((link, file)) = self.undrawable.first() {
            let n = self.undrawable.len();
            warnings.push(format!(
                "{n} visual mesh{} in a format the recording cannot draw (it draws STL, OBJ, glTF), e.g. link {link}: {}; drawn as the link's collision shape (or a small sphere)",
                if n == 1 { " is" } else { "es are" },
                file.display()
            ));
        }
        if let Some(first) = self.missing.first() {
            let mut warning = first.clone();
            if self.missing.len() > 1 {
                warning.push_str(&format!(
                    "; {} more visual meshes not found, drawn as their links' collision shapes (or small spheres)",
                    self.missing.len() - 1
                ));
            }
            warnings.push(warning);
        }
        warnings
    }
}

/// A visual's shape, or None for a mesh the recording cannot draw (missing, or a format rerun
/// does not read), noted in `problems`: the caller draws the link's collision shape instead
/// where it has one (`has_fallback`), else a small sphere.
fn shape(
    geometry: &urdf_rs::Geometry,
    base: &Path,
    link: &str,
    has_fallback: bool,
    problems: &mut MeshProblems,
) -> Option<Shape> {
    Some(match geometry {
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
            let scale = scale
                .as_ref()
                .map_or(DVec3::ONE, |s| DVec3::from_array(s.0));
            match mesh::resolve(filename, base) {
                Ok(path) if let Some(why) = mesh::unreadable(&path) => {
                    problems.missing.push(format!(
                        "link `{link}`: visual mesh {filename} ({}) cannot be read: {why}; drawn as {}",
                        path.display(),
                        if has_fallback {
                            "its collision shape"
                        } else {
                            "a small sphere"
                        }
                    ));
                    return None;
                }
                Ok(path) if mesh::drawable(&path) => Shape::Mesh { path, scale },
                Ok(path) => {
                    problems.undrawable.push((link.to_string(), path));
                    return None;
                }
                Err(tried) => {
                    let tried: Vec<String> =
                        tried.iter().map(|p| p.display().to_string()).collect();
                    // a robot whose meshes were not shipped with it still shows its shape
                    let drawn = if has_fallback {
                        "its collision shape"
                    } else {
                        "a small sphere"
                    };
                    problems.missing.push(format!(
                        "link `{link}`: visual mesh {filename} not found (looked in {}); drawn as {drawn}",
                        tried.join(", ")
                    ));
                    return None;
                }
            }
        }
    })
}

/// The model of a parsed URDF, in named steps: its bodies (links welded by fixed joints merged),
/// joints and shapes read from the root down; masses checked; feet found where none is given;
/// the joints off six legs of three held still (`branches`: the model is built again with them
/// welded); legs and the walking direction found; then its size checked, its inertias warned
/// about and its unstated efforts fitted.
fn build(
    robot: &urdf_rs::Robot,
    base: &Path,
    settings: RobotFileSettings,
) -> Result<RobotModel, String> {
    build_holding(robot, base, &settings, Vec::new())
}

/// [`build`], with the joints `held` welded at their angles.
fn build_holding(
    robot: &urdf_rs::Robot,
    base: &Path,
    settings: &RobotFileSettings,
    held: Vec<HeldJoint>,
) -> Result<RobotModel, String> {
    let RobotFileSettings {
        feet,
        forward,
        gait: gait_hints,
    } = settings;
    let (forward, gait_hints) = (*forward, *gait_hints);
    let tree = tree(robot)?;
    let held_at: HashMap<&str, f64> = held.iter().map(|h| (h.name.as_str(), h.angle)).collect();
    let mut bodies = Bodies::new(robot, base, feet.as_ref(), &held_at);
    // Walk the tree from the root, parents before children.
    let mut order = vec![tree.root];
    let mut cursor = 0;
    while cursor < order.len() {
        let k = order[cursor];
        cursor += 1;
        bodies.attach(k, tree.parent[k], &tree)?;
        bodies.fold(k)?;
        for &j in &tree.children[k] {
            order.push(tree.index[robot.joints[j].child.link.as_str()]);
        }
    }
    let Bodies {
        mut links,
        mut joints,
        shapes,
        mesh_problems,
        unstated,
        slides_welded,
        passive_welded,
        point_masses,
        ..
    } = bodies;
    check_masses(&links, &point_masses)?;
    let mut warnings: Vec<String> = impossible_inertia_warning(&links).into_iter().collect();
    if !slides_welded.is_empty() {
        warnings.push(format!(
            "{} prismatic joint{} travel{} at most {:.0} mm (a force sensor's mount, as simulators' descriptions have them): read as fixed at zero: {}",
            slides_welded.len(),
            plural(slides_welded.len()),
            if slides_welded.len() == 1 { "s" } else { "" },
            SLIDE_AS_FIXED * 1e3,
            slides_welded.join(", ")
        ));
    }
    if !passive_welded.is_empty() {
        warnings.push(format!(
            "{} revolute joint{} carr{} a massless link (no <inertial>) at the end of a leg, a passive foot: held at zero, welded to the link above: {}",
            passive_welded.len(),
            plural(passive_welded.len()),
            if passive_welded.len() == 1 { "ies" } else { "y" },
            passive_welded.join(", ")
        ));
    }
    warnings.extend(mesh_problems.warnings());
    let unfound = if feet.is_none() {
        let (unfound, warning) = find_feet(&mut links, &joints, &shapes, base);
        warnings.extend(warning);
        unfound
    } else {
        Vec::new()
    };
    if held.is_empty() {
        let to_hold = branches::held_joints(&links, &joints, &unfound, forward)?;
        if !to_hold.is_empty() {
            return build_holding(robot, base, settings, to_hold);
        }
    }
    warnings.extend(contact_set::attach(&mut links, &shapes, base).warnings());
    let (legs, forward): (_, Forward) = legs::find_legs(&links, &joints, &unfound, forward)?;
    legs::turn_to_forward(&mut links, &mut joints, forward.yaw);
    let mut model = RobotModel {
        name: robot.name.clone(),
        source: PathBuf::new(),
        links,
        joints,
        legs,
        forward,
        gait_hints,
        warnings,
        held,
    };
    check_size(&model)?;
    warn_implausible_inertias(&mut model)?;
    unstated.fill(&mut model);
    Ok(model)
}

/// The model's bodies as the URDF's links are read: each URDF link maps to a body (itself, or
/// the body it is welded to by fixed joints) and its pose in that body's frame.
struct Bodies<'a> {
    robot: &'a urdf_rs::Robot,
    base: &'a Path,
    /// The robot file's feet, which replace the URDF's.
    feet: Option<&'a FeetConfig>,
    body_of: Vec<usize>,
    in_body: Vec<DAffine3>,
    links: Vec<Link>,
    joints: Vec<Joint>,
    /// Each body's collision and visual shapes, in its frame: where a foot is found if none is
    /// given.
    shapes: Vec<(Vec<Placed>, Vec<Placed>)>,
    mesh_problems: MeshProblems,
    unstated: Unstated,
    /// Prismatic joints of negligible travel read as fixed ([`SLIDE_AS_FIXED`]), by name.
    slides_welded: Vec<String>,
    /// URDF links with a mass but a zero inertia tensor, by name: named if a body then has no
    /// inertia about some axis.
    point_masses: Vec<String>,
    /// The joints held still (`branches`), by name, at their angle: welded like fixed joints.
    held: &'a HashMap<&'a str, f64>,
    /// Per URDF link: whether a held joint lies between it and its body. Its collision sphere is
    /// then the body's foot (a tarsus's sphere, not the tibia's).
    via_held: Vec<bool>,
    /// Revolute joints whose child is a massless leaf beyond three joints (a passive foot),
    /// welded at zero, by name.
    passive_welded: Vec<String>,
    /// Per URDF link: the joints between it and the root that are not welded.
    depth: Vec<usize>,
}

/// The most a prismatic joint may travel (m) to be read as fixed: simulators' descriptions mount a
/// foot's force sensor on a slide of ±0.1 mm (elkapod's `legN_FCP_joint`, a Gazebo
/// force-torque sensor), which holds the foot rigidly in all but name.
pub const SLIDE_AS_FIXED: f64 = 1e-3;

/// How far a prismatic joint can move (m): its limit's range; unbounded without one.
fn slide_travel(joint: &urdf_rs::Joint) -> f64 {
    let range = (joint.limit.upper - joint.limit.lower).abs();
    if range.is_finite() && (joint.limit.upper != 0.0 || joint.limit.lower != 0.0) {
        range
    } else {
        f64::INFINITY
    }
}

impl<'a> Bodies<'a> {
    fn new(
        robot: &'a urdf_rs::Robot,
        base: &'a Path,
        feet: Option<&'a FeetConfig>,
        held: &'a HashMap<&'a str, f64>,
    ) -> Self {
        Bodies {
            robot,
            base,
            feet,
            body_of: vec![usize::MAX; robot.links.len()],
            in_body: vec![DAffine3::IDENTITY; robot.links.len()],
            links: Vec::new(),
            joints: Vec::new(),
            shapes: Vec::new(),
            mesh_problems: MeshProblems::default(),
            unstated: Unstated::default(),
            slides_welded: Vec::new(),
            point_masses: Vec::new(),
            held,
            via_held: vec![false; robot.links.len()],
            passive_welded: Vec::new(),
            depth: vec![0; robot.links.len()],
        }
    }

    /// Gives URDF link `k` its body: a new one for the root or a revolute joint's child, its
    /// parent's for a fixed joint's.
    fn attach(&mut self, k: usize, parent_joint: Option<usize>, tree: &Tree) -> Result<(), String> {
        let urdf_link = &self.robot.links[k];
        let Some(j) = parent_joint else {
            self.body_of[k] = self.links.len();
            self.links.push(empty_link(&urdf_link.name, None));
            self.shapes.push(Default::default());
            return Ok(());
        };
        let joint = &self.robot.joints[j];
        let parent = tree.index[joint.parent.link.as_str()];
        let origin = self.in_body[parent] * pose(&joint.origin);
        let revolute_joint = matches!(
            joint.joint_type,
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
        );
        let held_at = self.held.get(joint.name.as_str()).copied();
        // a passive foot: a massless leaf beyond a leg's three joints (a massless tibia is a
        // mistake, refused by the mass check)
        let passive = revolute_joint
            && held_at.is_none()
            && self.depth[parent] >= 3
            && tree.children[k].is_empty()
            && massless(urdf_link);
        if revolute_joint && (held_at.is_some() || passive) {
            let (axis, lower, upper, _) = revolute(joint, &mut Unstated::default())?;
            let angle = held_at.unwrap_or_else(|| 0.0_f64.clamp(lower, upper));
            if passive {
                self.passive_welded.push(joint.name.clone());
            }
            self.body_of[k] = self.body_of[parent];
            self.in_body[k] = origin * DAffine3::from_axis_angle(axis, angle);
            self.via_held[k] = held_at.is_some() || self.via_held[parent];
            self.depth[k] = self.depth[parent];
            self.links[self.body_of[k]]
                .merged
                .push(urdf_link.name.clone());
            return Ok(());
        }
        let welded = match &joint.joint_type {
            urdf_rs::JointType::Fixed => true,
            urdf_rs::JointType::Prismatic if slide_travel(joint) <= SLIDE_AS_FIXED => {
                self.slides_welded.push(joint.name.clone());
                true
            }
            _ => false,
        };
        if welded {
            // a slide held at its zero, or at the end of its range nearest it
            let limit = &joint.limit;
            let at = 0.0_f64.clamp(limit.lower.min(limit.upper), limit.upper.max(limit.lower));
            let axis = DVec3::from_array(joint.axis.xyz.0).normalize_or_zero();
            self.body_of[k] = self.body_of[parent];
            self.in_body[k] = origin * DAffine3::from_translation(axis * at);
            self.via_held[k] = self.via_held[parent];
            self.depth[k] = self.depth[parent];
            self.links[self.body_of[k]]
                .merged
                .push(urdf_link.name.clone());
            return Ok(());
        }
        match &joint.joint_type {
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                let (axis, lower, upper, effort) = revolute(joint, &mut self.unstated)?;
                self.depth[k] = self.depth[parent] + 1;
                self.body_of[k] = self.links.len();
                self.links
                    .push(empty_link(&urdf_link.name, Some(self.joints.len())));
                self.shapes.push(Default::default());
                self.joints.push(Joint {
                    name: joint.name.clone(),
                    parent: self.body_of[parent],
                    child: self.body_of[k],
                    origin,
                    axis,
                    lower,
                    upper,
                    effort,
                });
            }
            urdf_rs::JointType::Prismatic => {
                return Err(format!(
                    "joint `{}`: a prismatic joint travelling {:.1} mm is not supported (hexsim's legs are chains of revolute joints; a slide of at most {:.0} mm, such as a foot's force-sensor mount, is read as fixed; use fixed for rigid attachments)",
                    joint.name,
                    slide_travel(joint) * 1e3,
                    SLIDE_AS_FIXED * 1e3
                ));
            }
            other => {
                return Err(format!(
                    "joint `{}`: type {other:?} is not supported (hexsim's legs are chains of revolute joints; use fixed for rigid attachments)",
                    joint.name
                ));
            }
        }
        Ok(())
    }

    /// Folds URDF link `k`'s inertial, visuals, shapes and foot sphere into its body.
    fn fold(&mut self, k: usize) -> Result<(), String> {
        let urdf_link = &self.robot.links[k];
        let (mass, com, inertia) = check_inertial(urdf_link)?;
        if mass > 0.0 && inertia == DMat3::ZERO {
            self.point_masses.push(urdf_link.name.clone());
        }
        let frame = self.in_body[k];
        let body = &mut self.links[self.body_of[k]];
        add_mass(
            body,
            mass,
            frame.transform_point3(com),
            frame.matrix3 * inertia * frame.matrix3.transpose(),
        );
        // the first collision primitive, drawn (at its own origin) for a visual mesh that cannot be
        let collision_shape = urdf_link.collision.iter().find_map(|c| {
            let ignored = &mut MeshProblems::default();
            let shape = shape(&c.geometry, self.base, &urdf_link.name, false, ignored)
                .filter(|s| !matches!(s, Shape::Mesh { .. }))?;
            Some((frame * pose(&c.origin), shape))
        });
        for visual in &urdf_link.visual {
            let origin = frame * pose(&visual.origin);
            let drawn = shape(
                &visual.geometry,
                self.base,
                &urdf_link.name,
                collision_shape.is_some(),
                &mut self.mesh_problems,
            );
            let (origin, shape) = match (drawn, &collision_shape) {
                (Some(shape), _) => (origin, shape),
                (None, Some(fallback)) => fallback.clone(),
                (None, None) => (origin, Shape::Sphere { radius: 0.01 }),
            };
            body.visuals.push(Visual {
                origin,
                shape,
                color: color_of(self.robot, &visual.material),
            });
        }
        if let Some(feet) = self.feet
            && feet.links.contains(&urdf_link.name)
        {
            body.foot = Some(Foot {
                center: frame.transform_point3(DVec3::from_array(feet.offset)),
                radius: feet.radius,
                from: FootFrom::RobotFile,
            });
        }
        let placed = |origin: &urdf_rs::Pose, geometry: &urdf_rs::Geometry| Placed {
            origin: frame * pose(origin),
            geometry: geometry.clone(),
        };
        let (collisions, visuals) = &mut self.shapes[self.body_of[k]];
        collisions.extend(
            urdf_link
                .collision
                .iter()
                .map(|c| placed(&c.origin, &c.geometry)),
        );
        visuals.extend(
            urdf_link
                .visual
                .iter()
                .map(|v| placed(&v.origin, &v.geometry)),
        );
        for collision in urdf_link.collision.iter().filter(|_| self.feet.is_none()) {
            if let urdf_rs::Geometry::Sphere { radius } = collision.geometry {
                if !(radius.is_finite() && radius > 0.0) {
                    return Err(format!(
                        "link `{}`: foot sphere radius must be > 0, got {radius}",
                        urdf_link.name
                    ));
                }
                if body.foot.is_none() || self.via_held[k] {
                    body.foot = Some(Foot {
                        center: (frame * pose(&collision.origin)).translation,
                        radius,
                        from: FootFrom::Sphere,
                    });
                }
            }
        }
        Ok(())
    }
}

/// Whether a URDF link carries neither mass nor inertia (no `<inertial>`: a frame, a passive
/// foot's).
fn massless(link: &urdf_rs::Link) -> bool {
    let i = &link.inertial.inertia;
    link.inertial.mass.value == 0.0
        && [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz]
            .iter()
            .all(|&v| v == 0.0)
}

/// A revolute (or continuous) joint's unit axis, limits and effort. A CAD exporter's placeholder
/// limits (lower = upper = 0, also what a missing `<limit>` reads as) are absent: a stated
/// default range; a zero effort is fitted to the robot's weight once its legs are known (NaN
/// until then). Both are noted in `unstated`, for one warning each.
fn revolute(
    joint: &urdf_rs::Joint,
    unstated: &mut Unstated,
) -> Result<(DVec3, f64, f64, f64), String> {
    let axis = DVec3::from_array(joint.axis.xyz.0);
    if !(axis.is_finite() && axis.length() > 1e-9) {
        return Err(format!(
            "joint `{}`: <axis xyz> must have a non-zero length, got {axis}",
            joint.name
        ));
    }
    let (mut lower, mut upper) = if matches!(joint.joint_type, urdf_rs::JointType::Continuous) {
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        (joint.limit.lower, joint.limit.upper)
    };
    if lower == 0.0 && upper == 0.0 {
        (lower, upper) = (-UNSTATED_RANGE, UNSTATED_RANGE);
        unstated.range.push(joint.name.clone());
    }
    let ordered = lower < upper; // false for NaN too
    if !ordered {
        return Err(format!(
            "joint `{}`: a revolute joint needs <limit lower=… upper=…> with lower < upper, got lower = {lower}, upper = {upper}",
            joint.name
        ));
    }
    let mut effort = joint.limit.effort;
    if effort == 0.0 {
        effort = f64::NAN;
        unstated.effort.push(joint.name.clone());
    }
    if !(effort.is_nan() || effort.is_finite() && effort > 0.0) {
        return Err(format!(
            "joint `{}`: <limit effort> (the servo's torque limit, N·m) must be > 0, got {effort}",
            joint.name
        ));
    }
    Ok((axis.normalize(), lower, upper, effort))
}

/// Every body needs a mass and a positive-definite inertia; a URDF with none at all is a
/// description for drawing, and is refused as such rather than by its first link. A body whose
/// tensor is singular because its URDF links are point masses (`point_masses`: a mass, every
/// moment zero) is refused naming that cause, not only the merged tensor it leads to.
fn check_masses(links: &[Link], point_masses: &[String]) -> Result<(), String> {
    if links.iter().all(|l| l.mass <= 0.0) {
        return Err(
            "no link has a mass: the URDF has no <inertial> elements (a description for drawing, as RViz reads it); hexsim needs each link's <mass> and <inertia>".into(),
        );
    }
    if links.iter().all(|l| l.inertia == DMat3::ZERO) {
        return Err(
            "no link states an inertia (every <inertia> is zero or missing); hexsim needs each link's inertia tensor (kg·m²)".into(),
        );
    }
    for link in links {
        if link.mass <= 0.0 {
            return Err(format!(
                "link `{}`: mass must be > 0 (a link moved by a joint needs inertia; give it an <inertial>)",
                link.name
            ));
        }
        if !positive_definite(&link.inertia) {
            let cause = if point_masses.is_empty() {
                String::new()
            } else {
                let shown: Vec<&str> = point_masses.iter().take(4).map(String::as_str).collect();
                format!(
                    "; the URDF gives {} link{} a mass but a zero inertia tensor (ixx = iyy = izz = 0: {}{}), point masses that cannot turn: give each link its inertia (kg·m²)",
                    point_masses.len(),
                    plural(point_masses.len()),
                    shown.join(", "),
                    if point_masses.len() > 4 { ", …" } else { "" }
                )
            };
            return Err(format!(
                "link `{}`: the inertia tensor is not positive definite ({:?}){cause}",
                link.name,
                link.inertia.to_cols_array()
            ));
        }
    }
    Ok(())
}

/// One warning naming the bodies whose principal moments break the triangle inequality.
fn impossible_inertia_warning(links: &[Link]) -> Option<String> {
    let impossible: Vec<(&str, [f64; 3])> = links
        .iter()
        .filter_map(|l| Some((l.name.as_str(), impossible_inertia(&l.inertia)?)))
        .collect();
    let (first, [a, b, c]) = impossible.first()?;
    let others: Vec<&str> = impossible[1..].iter().map(|(name, _)| *name).collect();
    let more = if others.is_empty() {
        String::new()
    } else {
        format!(", and so do {} more: {}", others.len(), others.join(", "))
    };
    Some(format!(
        "link `{first}`: principal moments of inertia {a:.3e}, {b:.3e}, {c:.3e} kg·m² break \
         A + B ≥ C, which no rigid body can (MuJoCo refuses such a link unless told to \
         balance it){more}; simulated as given"
    ))
}

/// Finds the foot at the tip of the geometry of every chain's last body that has no foot sphere
/// (`foot::find`). Returns the bodies where none was found, with why (the leg finder names them
/// if they end a leg), and a warning if some feet came from the visual geometry because the
/// collision geometry could not be read.
fn find_feet(
    links: &mut [Link],
    joints: &[Joint],
    shapes: &[(Vec<Placed>, Vec<Placed>)],
    base: &Path,
) -> (Vec<(String, String)>, Option<String>) {
    let mut unfound = Vec::new();
    let mut unread: Vec<(String, String)> = Vec::new();
    for (k, link) in links.iter_mut().enumerate() {
        let leaf = k != 0 && !joints.iter().any(|j| j.parent == k);
        if !leaf || link.foot.is_some() {
            continue;
        }
        let knee = link.parent_joint.map_or(DVec3::Z, |j| joints[j].axis);
        let (collisions, visuals) = &shapes[k];
        match foot::find(collisions, visuals, knee, base) {
            Ok(found) => {
                if let Some(first) = found.unread.first() {
                    unread.push((link.name.clone(), first.clone()));
                }
                link.foot = Some(found.foot);
            }
            Err(why) => unfound.push((link.name.clone(), why)),
        }
    }
    let warning = unread.first().map(|(link, why)| {
        format!(
            "{} feet found from their link's visual geometry, the collision geometry unreadable (e.g. link `{link}`: its collision {why})",
            unread.len()
        )
    });
    (unfound, warning)
}

/// A link's radius of gyration k = √(I_max/m) (its mass's spread about its centre) against the
/// robot's size D (the diagonal of the box around its joints and feet, standing at zero): no
/// part of a robot has k > D, and k < 0.5 % of D is a mass far denser than any material — the
/// marks of an inertia in g·mm² or kg·mm², or a mass in grams, where URDF wants kg·m² and kg
/// (hex18's links: 2–5 % of D). One warning per kind, naming the links; simulated as given.
/// A link whose k passes [`IMPOSSIBLE_SPREAD`]·D is refused: its inertia is more than 100 times
/// what its mass allows inside the robot (placeholder inertials: 10 mg links of 1 kg·m²).
fn warn_implausible_inertias(model: &mut RobotModel) -> Result<(), String> {
    let poses = model.link_poses(&vec![0.0; model.joints.len()]);
    let mut points: Vec<DVec3> = poses.iter().map(|p| p.translation).collect();
    points.extend(
        model
            .legs
            .iter()
            .map(|leg| poses[leg.foot_link].transform_point3(leg.foot.center)),
    );
    let low = points.iter().copied().fold(DVec3::INFINITY, DVec3::min);
    let high = points.iter().copied().fold(DVec3::NEG_INFINITY, DVec3::max);
    let size = (high - low).length();
    if !(size.is_finite() && size > 0.0) {
        return Ok(());
    }
    let gyration = |l: &Link| {
        let largest = l
            .inertia
            .x_axis
            .x
            .max(l.inertia.y_axis.y)
            .max(l.inertia.z_axis.z);
        (largest / l.mass).sqrt()
    };
    let (mut wide, mut dense) = (Vec::new(), Vec::new());
    for link in &model.links {
        let k = gyration(link);
        if k > size {
            wide.push((link.name.clone(), k));
        } else if k < 0.005 * size {
            dense.push((link.name.clone(), k));
        }
    }
    let named = |links: &[(String, f64)]| {
        let more = links.len() - 1;
        let others = if more > 0 {
            format!(" (and {more} more link{})", plural(more))
        } else {
            String::new()
        };
        (links[0].0.clone(), links[0].1, others)
    };
    if let Some((name, k)) = wide
        .iter()
        .filter(|(_, k)| *k > IMPOSSIBLE_SPREAD * size)
        .max_by(|a, b| a.1.total_cmp(&b.1))
    {
        let mass = model.total_mass();
        let weighs = if mass < 0.1 {
            format!("{:.2} g", mass * 1e3)
        } else {
            format!("{mass:.3} kg")
        };
        let ratio = (k / size).powi(2);
        let count = wide
            .iter()
            .filter(|(_, k)| *k > IMPOSSIBLE_SPREAD * size)
            .count();
        let others = if count > 1 {
            format!(" (and {} more link{})", count - 1, plural(count - 1))
        } else {
            String::new()
        };
        return Err(format!(
            "the robot weighs {weighs}, and link `{name}`{others} has an inertia {ratio:.0e} times what its mass allows: it spreads its mass {k:.3} m from its centre (√(I/m)), the whole robot is {size:.3} m across — placeholder inertials, or an inertia in kg·mm² instead of kg·m²? No rigid body can be so; give each link its mass (kg) and inertia (kg·m²)"
        ));
    }
    if !wide.is_empty() {
        let (name, k, others) = named(&wide);
        model.warnings.push(format!(
            "link `{name}`{others}: its inertia spreads its mass {k:.3} m from its centre, more than the whole robot's {size:.3} m: an inertia in g·mm² or kg·mm² instead of kg·m²? Simulated as given"
        ));
    }
    if !dense.is_empty() {
        let (name, k, others) = named(&dense);
        model.warnings.push(format!(
            "link `{name}`{others}: its inertia spreads its mass only {:.2} mm from its centre, under 0.5 % of the robot's {size:.3} m (denser than any material): a mass in grams instead of kg? Simulated as given",
            k * 1e3
        ));
    }
    Ok(())
}

/// A link's radius of gyration beyond this many times the robot's size is refused (see
/// [`warn_implausible_inertias`]); between 1 and this it is warned about (the PhantomX's
/// placeholder inertias spread 3.6 times its size, and it walks).
pub const IMPOSSIBLE_SPREAD: f64 = 10.0;

/// The longest leg a hexapod could have (m): a URDF whose legs are longer is in other units.
const LONGEST_LEG: f64 = 10.0;

/// Refuses legs too long to be in metres: a URDF written in millimetres (a CAD export set to mm)
/// has legs a thousand times too long.
fn check_size(model: &RobotModel) -> Result<(), String> {
    let longest = model
        .legs
        .iter()
        .map(|leg| {
            super::statics::segment_lengths(model, leg)
                .iter()
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    if longest > LONGEST_LEG {
        return Err(format!(
            "the legs are {longest:.1} m long (coxa + femur + tibia): is the URDF in millimetres? URDF lengths are in metres (and masses in kg)"
        ));
    }
    Ok(())
}

/// A joint range left unstated is this wide each way: a hobby servo's 300° (Dynamixel AX/MX).
pub const UNSTATED_RANGE: f64 = 150.0 * std::f64::consts::PI / 180.0;

/// The joints whose `<limit>` states no range (lower = upper = 0) or no effort (0), as CAD
/// exporters write them on every joint.
#[derive(Default)]
struct Unstated {
    range: Vec<String>,
    effort: Vec<String>,
}

impl Unstated {
    /// Fits the unstated efforts and says, in one warning each, what was read as absent and what
    /// was fitted. An unstated effort is the torque that holds a third of the robot's weight at
    /// the longest leg's full length from its femur joint: the most any joint of a leg meets
    /// standing on three feet (a tripod's fewest), reached only with the leg stretched level, so
    /// a stance whose feet are within half that length keeps every servo at or under half its
    /// effort, as the gait fit asks.
    fn fill(self, model: &mut RobotModel) {
        let list = |names: &[String]| {
            let shown: Vec<&str> = names.iter().take(6).map(String::as_str).collect();
            let more = names.len().saturating_sub(6);
            let more = if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            };
            format!("{}{more}", shown.join(", "))
        };
        if !self.range.is_empty() {
            model.warnings.push(format!(
                "{} joint{} state{} no range (lower = upper = 0, a CAD exporter's placeholder, or no <limit>): {}; read as absent, ±{:.0}° (a hobby servo's range)",
                self.range.len(),
                plural(self.range.len()),
                if self.range.len() == 1 { "s" } else { "" },
                list(&self.range),
                UNSTATED_RANGE.to_degrees()
            ));
        }
        if self.effort.is_empty() {
            return;
        }
        let weight = model.total_mass() * 9.81;
        let reach = model
            .legs
            .iter()
            .map(|leg| {
                let [_, femur, tibia] = super::statics::segment_lengths(model, leg);
                femur + tibia
            })
            .fold(0.0, f64::max);
        let effort = weight / 3.0 * reach;
        for joint in model.joints.iter_mut().filter(|j| j.effort.is_nan()) {
            joint.effort = effort;
        }
        model.warnings.push(format!(
            "{} joint{} state{} no effort (effort = 0, a CAD exporter's placeholder, or no <limit>): {}; fitted from the robot's weight: {effort:.3} N·m, a third of its {weight:.1} N held at the legs' full {reach:.3} m",
            self.effort.len(),
            plural(self.effort.len()),
            if self.effort.len() == 1 { "s" } else { "" },
            list(&self.effort),
        ));
    }
}

pub(super) fn empty_link(name: &str, parent_joint: Option<usize>) -> Link {
    Link {
        name: name.to_string(),
        parent_joint,
        mass: 0.0,
        com: DVec3::ZERO,
        inertia: DMat3::ZERO,
        visuals: Vec::new(),
        foot: None,
        contacts: Vec::new(),
        merged: Vec::new(),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// xacro's output (the namespace declared, xacro elements commented out) is a URDF; a live
    /// xacro element or expression is a template.
    #[test]
    fn only_live_xacro_marks_a_template() {
        let urdf = Path::new("robot.urdf");
        let output = r#"<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <!-- <xacro:include filename="legs.xacro"/> -->
  <!--<xacro:property name="l" value="${2*r}"/>--><link name="a"/>
</robot>"#;
        assert_eq!(refuse_xacro(output, urdf), Ok(()));
        for template in [
            r#"<robot xmlns:xacro="x"><xacro:property name="l" value="1"/></robot>"#,
            r#"<robot><link name="a"><!-- a --><mass value="${m}"/></link></robot>"#,
            r#"<robot><!-- unclosed <link/> --> <xacro:leg/></robot>"#,
        ] {
            assert!(refuse_xacro(template, urdf).is_err(), "{template}");
        }
        assert!(refuse_xacro(output, Path::new("robot.urdf.xacro")).is_err());
        assert_eq!(without_comments("a<!-- b"), "a");
    }

    /// Phobos's free base and foot frames (1 g links without shapes, on floating joints) are
    /// dropped and the body becomes the root; a floating joint to a real link is still refused.
    #[test]
    fn phobos_marker_frames_are_dropped() {
        let urdf = |body_shape: &str, tail_mass: f64| {
            format!(
                r#"<robot name="r">
  <link name="root"><inertial><mass value="0.001"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>
  <link name="body"><inertial><mass value="2"/><inertia ixx="1e-2" ixy="0" ixz="0" iyy="1e-2" iyz="0" izz="1e-2"/></inertial>{body_shape}</link>
  <link name="foot_frame"><inertial><mass value="{tail_mass}"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>
  <joint name="body_jnt" type="floating"><parent link="root"/><child link="body"/></joint>
  <joint name="foot_jnt" type="floating"><parent link="root"/><child link="foot_frame"/></joint>
</robot>"#
            )
        };
        let mut robot = urdf_rs::read_from_string(&urdf("", 0.001)).unwrap();
        assert_eq!(drop_marker_frames(&mut robot), ["foot_jnt", "body_jnt"]);
        assert_eq!(robot.links.len(), 1);
        assert_eq!(robot.links[0].name, "body");
        assert!(robot.joints.is_empty());
        // a 0.5 kg link on a floating joint is not a marker: nothing is dropped
        let mut robot = urdf_rs::read_from_string(&urdf("", 0.5)).unwrap();
        assert!(drop_marker_frames(&mut robot).is_empty());
        assert_eq!(robot.joints.len(), 2);
    }

    /// A solid box's inertia is physical; a thin disc sits on A + B = C and passes; a tensor whose
    /// two smaller moments fall short of the largest is flagged, however it is turned.
    #[test]
    fn inertias_no_rigid_body_can_have_are_flagged() {
        let (m, x, y, z) = (2.0, 0.3, 0.2, 0.1);
        let solid = DMat3::from_diagonal(
            DVec3::new(y * y + z * z, x * x + z * z, x * x + y * y) * m / 12.0,
        );
        assert_eq!(impossible_inertia(&solid), None);
        let r: f64 = 0.1;
        let disc = DMat3::from_diagonal(DVec3::new(0.25, 0.25, 0.5) * m * r * r);
        assert_eq!(impossible_inertia(&disc), None);
        let turn = DMat3::from_euler(glam::EulerRot::ZYX, 0.4, -0.7, 1.1);
        let bad = DMat3::from_diagonal(DVec3::new(1.0, 2.0, 3.5));
        let found = impossible_inertia(&(turn * bad * turn.transpose())).unwrap();
        for (got, want) in found.iter().zip([1.0, 2.0, 3.5]) {
            assert!((got - want).abs() < 1e-9, "{found:?}");
        }
        assert_eq!(impossible_inertia(&(turn * solid * turn.transpose())), None);
    }

    /// A prismatic joint of negligible travel (a foot's force-sensor mount, ±0.1 mm) is read as
    /// fixed, with a warning naming it; one that travels 5 mm is refused, saying so.
    #[test]
    fn a_slide_of_negligible_travel_is_read_as_fixed() {
        let hex18 = include_str!("../../robots/hex18.urdf");
        let with_slide = |travel: f64| {
            let sensor = format!(
                r#"<link name="lf_fsr"/>
  <joint name="lf_fsr_joint" type="prismatic"><parent link="lf_tibia"/><child link="lf_fsr"/>
    <origin xyz="0.1 0 0"/><axis xyz="1 0 0"/>
    <limit lower="{}" upper="{}" effort="1000" velocity="30"/></joint>
</robot>"#,
                -travel / 2.0,
                travel / 2.0
            );
            hex18.replacen("</robot>", &sensor, 1)
        };
        let model = from_str(&with_slide(2e-4), Path::new("hex18_fsr.urdf")).unwrap();
        assert_eq!(model.joints.len(), 18);
        let tibia = model.links.iter().find(|l| l.name == "lf_tibia").unwrap();
        assert!(
            tibia.merged.contains(&"lf_fsr".to_string()),
            "{:?}",
            tibia.merged
        );
        assert!(
            model
                .warnings
                .iter()
                .any(|w| w.contains("1 prismatic joint travels at most 1 mm")
                    && w.contains("lf_fsr_joint")),
            "{:?}",
            model.warnings
        );
        let error = from_str(&with_slide(5e-3), Path::new("hex18_fsr.urdf"))
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("`lf_fsr_joint`: a prismatic joint travelling 5.0 mm is not supported"),
            "{error}"
        );
    }
}
