//! URDF → [`RobotModel`]: parse with urdf-rs (`parse`), undo exporters' quirks (`quirks`), read
//! the robot file beside it (`robot_file`), fold fixed joints into bodies (`fold`), check the
//! inertials (`inertials`), find the feet and the six legs from the structure.
//!
//! Every error names the file and the element (link or joint) and says what was expected.

mod fold;
mod inertia_from;
mod inertials;
mod joint_limits;
mod parse;
mod places;
mod quirks;
mod robot_file;
mod visuals;

pub use fold::SLIDE_AS_FIXED;
#[cfg(test)]
pub(in crate::robot) use fold::empty_link;
pub use inertials::IMPOSSIBLE_SPREAD;
pub use joint_limits::UNSTATED_RANGE;
pub use robot_file::FeetConfig;

use super::branches;
use super::contact_set;
use super::foot::{self, Placed};
use super::legs::{self, Forward};
use super::model::{HeldJoint, Joint, Link, RobotModel};
use fold::Bodies;
use glam::{DAffine3, DQuat, DVec3, EulerRot};
use robot_file::RobotFileSettings;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A URDF that hexsim cannot use: `FILE: message`, or `FILE:LINE: message` where the line is known.
#[derive(Debug, thiserror::Error)]
pub struct RobotError {
    pub file: PathBuf,
    pub line: Option<u32>,
    pub message: String,
}

impl std::fmt::Display for RobotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}: {}", self.file.display(), self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

pub(super) fn pose(p: &urdf_rs::Pose) -> DAffine3 {
    let rotation = DQuat::from_euler(EulerRot::ZYX, p.rpy[2], p.rpy[1], p.rpy[0]);
    DAffine3::from_rotation_translation(rotation, DVec3::from_array(p.xyz.0))
}

/// Loads and validates a URDF robot, with the robot file beside it if there is one.
pub fn load(path: &Path) -> Result<RobotModel, RobotError> {
    let text =
        crate::limits::read_to_string(path, crate::limits::TEXT_FILE_BYTES).map_err(|e| {
            RobotError {
                file: path.to_path_buf(),
                line: None,
                message: format!("cannot read the URDF: {e}"),
            }
        })?;
    parse::refuse_xacro(&text, path).map_err(|message| RobotError {
        file: path.to_path_buf(),
        line: None,
        message,
    })?;
    let robot_file = path.with_extension("toml");
    let robot_text = if robot_file.is_file() {
        Some(
            crate::limits::read_to_string(&robot_file, crate::limits::TEXT_FILE_BYTES).map_err(
                |e| RobotError {
                    file: robot_file.clone(),
                    line: None,
                    message: format!("cannot read the robot file: {e}"),
                },
            )?,
        )
    } else {
        None
    };
    from_str_with(&text, robot_text.as_deref(), path)
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
        line: None,
        message,
    };
    let mut robot = parse::read(text).map_err(|(line, message)| RobotError {
        file: origin.to_path_buf(),
        line,
        message,
    })?;
    let quirk_warnings = quirks::apply(&mut robot);
    let settings = match robot_file {
        None => RobotFileSettings::default(),
        Some(file) => robot_file::read(file, &robot, origin).map_err(|message| RobotError {
            file: origin.with_extension("toml"),
            line: None,
            message,
        })?,
    };
    let mut model =
        build(&robot, origin.parent().unwrap_or(Path::new(".")), settings).map_err(fail)?;
    model.warnings.extend(quirk_warnings);
    model.warnings.extend(places::unknown_elements(text));
    Ok(model)
}

/// The plural ending of a count's noun: "" for one, "s" otherwise.
pub(super) fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Parses URDF text alone (for tests); `origin` resolves mesh paths.
pub fn from_str(text: &str, origin: &Path) -> Result<RobotModel, RobotError> {
    from_str_with(text, None, origin)
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
        redundant_legs,
        inertia,
    } = settings;
    let (forward, gait_hints) = (*forward, *gait_hints);
    let tree = parse::tree(robot)?;
    let held_at: HashMap<&str, f64> = held.iter().map(|h| (h.name.as_str(), h.angle)).collect();
    let mut bodies = Bodies::new(robot, base, feet.as_ref(), &held_at);
    bodies.inertia_from_collision = *inertia == robot_file::InertiaFrom::Collision;
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
        inertia_kept,
        ..
    } = bodies;
    inertials::check_masses(&links, &point_masses)?;
    let mut warnings: Vec<String> = inertials::impossible_inertia_warning(&links)
        .into_iter()
        .collect();
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
    if let Some((link, why)) = inertia_kept.first() {
        warnings.push(format!(
            "the robot file's `inertia = \"collision\"`: {} link{} kept {} URDF inertial{} (e.g. `{link}`: {why})",
            inertia_kept.len(),
            plural(inertia_kept.len()),
            if inertia_kept.len() == 1 { "its" } else { "their" },
            plural(inertia_kept.len()),
        ));
    }
    let unfound = if feet.is_none() {
        let (unfound, warning) = find_feet(&mut links, &joints, &shapes, base);
        warnings.extend(warning);
        unfound
    } else {
        Vec::new()
    };
    if held.is_empty() {
        let driven = *redundant_legs == robot_file::RedundantLegs::Driven;
        let to_hold = branches::held_joints(&links, &joints, &unfound, forward, driven)?;
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
    inertials::warn_implausible_inertias(&mut model)?;
    inertials::warn_implausible_density(&mut model);
    unstated.fill(&mut model);
    Ok(model)
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
            "the legs are {longest:.1} m long (coxa + femur + tibia, and any segments beyond): is the URDF in millimetres? URDF lengths are in metres (and masses in kg)"
        ));
    }
    Ok(())
}
