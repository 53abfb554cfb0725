//! Folding: the URDF's links read from the root down into the model's bodies — a link welded by a
//! fixed joint (or a held one, a negligible slide, a passive foot's) folds into its parent's body,
//! its mass, shapes and foot moved into that body's frame.

use super::inertia_from;
use super::inertials::{add_mass, check_inertial, massless};
use super::joint_limits::{Unstated, revolute};
use super::parse::Tree;
use super::pose;
use super::robot_file::FeetConfig;
use super::visuals::{MeshProblems, color_of, shape};
use crate::robot::foot::Placed;
use crate::robot::model::{Foot, FootFrom, Joint, Link, Shape, Visual};
use glam::{DAffine3, DMat3, DVec3};
use std::collections::HashMap;
use std::path::Path;

/// The model's bodies as the URDF's links are read: each URDF link maps to a body (itself, or
/// the body it is welded to by fixed joints) and its pose in that body's frame.
pub(super) struct Bodies<'a> {
    pub(super) robot: &'a urdf_rs::Robot,
    pub(super) base: &'a Path,
    /// The robot file's feet, which replace the URDF's.
    pub(super) feet: Option<&'a FeetConfig>,
    pub(super) body_of: Vec<usize>,
    pub(super) in_body: Vec<DAffine3>,
    pub(super) links: Vec<Link>,
    pub(super) joints: Vec<Joint>,
    /// Each body's collision and visual shapes, in its frame: where a foot is found if none is
    /// given.
    pub(super) shapes: Vec<(Vec<Placed>, Vec<Placed>)>,
    pub(super) mesh_problems: MeshProblems,
    pub(super) unstated: Unstated,
    /// Prismatic joints of negligible travel read as fixed ([`SLIDE_AS_FIXED`]), by name.
    pub(super) slides_welded: Vec<String>,
    /// URDF links with a mass but a zero inertia tensor, by name, with their mass (kg): named if a
    /// body then has no inertia about some axis.
    pub(super) point_masses: Vec<(String, f64)>,
    /// The joints held still (`branches`), by name, at their angle: welded like fixed joints.
    pub(super) held: &'a HashMap<&'a str, f64>,
    /// Per URDF link: whether a held joint lies between it and its body. Its collision sphere is
    /// then the body's foot (a tarsus's sphere, not the tibia's).
    pub(super) via_held: Vec<bool>,
    /// Revolute joints whose child is a massless leaf beyond three joints (a passive foot),
    /// welded at zero, by name.
    pub(super) passive_welded: Vec<String>,
    /// Per URDF link: the joints between it and the root that are not welded.
    pub(super) depth: Vec<usize>,
    /// Whether each link's centre of mass and inertia come from its collision geometry (the
    /// robot file's `inertia`), and the links that kept their URDF's, with why.
    pub(super) inertia_from_collision: bool,
    pub(super) inertia_kept: Vec<(String, String)>,
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
    pub(super) fn new(
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
            inertia_from_collision: false,
            inertia_kept: Vec::new(),
        }
    }

    /// Gives URDF link `k` its body: a new one for the root or a revolute joint's child, its
    /// parent's for a fixed joint's.
    pub(super) fn attach(
        &mut self,
        k: usize,
        parent_joint: Option<usize>,
        tree: &Tree,
    ) -> Result<(), String> {
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
        // a passive foot: massless links beyond a leg's three joints, a leaf or a chain of them
        // (a ball joint written as two revolute joints, roll and pitch, between massless links,
        // often ending in a massless frame); a massless tibia is a mistake, refused by the mass
        // check
        let passive = revolute_joint
            && held_at.is_none()
            && self.depth[parent] >= 3
            && massless_subtree(self.robot, tree, k);
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
    pub(super) fn fold(&mut self, k: usize) -> Result<(), String> {
        let urdf_link = &self.robot.links[k];
        let (mass, mut com, mut inertia) = check_inertial(urdf_link)?;
        if self.inertia_from_collision && mass > 0.0 {
            match inertia_from::from_collision(urdf_link, mass, self.base) {
                Ok(found) => (com, inertia) = found,
                Err(why) => self.inertia_kept.push((urdf_link.name.clone(), why)),
            }
        }
        if mass > 0.0 && inertia == DMat3::ZERO {
            self.point_masses.push((urdf_link.name.clone(), mass));
        }
        let frame = self.in_body[k];
        let body = &mut self.links[self.body_of[k]];
        add_mass(
            body,
            mass,
            frame.transform_point3(com),
            frame.matrix3 * inertia * frame.matrix3.transpose(),
        );
        // drawn (at its own origin) for a visual mesh that cannot be: the first collision
        // primitive, else the first collision mesh the recording can draw (PhantomX ships its
        // body's collision mesh but not its visual one: a small sphere hid the body plate)
        // (one pass: each collision mesh is resolved once)
        let mut first_mesh = None;
        let collision_shape = urdf_link
            .collision
            .iter()
            .find_map(|c| {
                let ignored = &mut MeshProblems::default();
                let shape = shape(&c.geometry, self.base, &urdf_link.name, false, ignored)?;
                let placed = (frame * pose(&c.origin), shape);
                if matches!(placed.1, Shape::Mesh { .. }) {
                    first_mesh.get_or_insert(placed);
                    return None;
                }
                Some(placed)
            })
            .or(first_mesh);
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

/// Whether URDF link `k` and every link below it carry neither mass nor inertia: a passive foot
/// however many joints it hangs by.
fn massless_subtree(robot: &urdf_rs::Robot, tree: &Tree, k: usize) -> bool {
    massless(&robot.links[k])
        && tree.children[k].iter().all(|&j| {
            let child = tree.index[robot.joints[j].child.link.as_str()];
            massless_subtree(robot, tree, child)
        })
}

pub(in crate::robot) fn empty_link(name: &str, parent_joint: Option<usize>) -> Link {
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

#[cfg(test)]
mod tests {
    use super::super::from_str;
    use std::path::Path;

    /// A prismatic joint of negligible travel (a foot's force-sensor mount, ±0.1 mm) is read as
    /// fixed, with a warning naming it; one that travels 5 mm is refused, saying so.
    #[test]
    fn a_slide_of_negligible_travel_is_read_as_fixed() {
        let hex18 = include_str!("../../../robots/hex18.urdf");
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
