//! The robot as hexsim sees it: rigid links with inertials, movable joints, visuals, feet, and
//! the six legs found in its structure. Immutable once loaded; shared by every simulation of it.

use glam::{DAffine3, DMat3, DVec3};
use std::path::PathBuf;

/// A visual shape in its link's frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    Box {
        half_extents: DVec3,
    },
    /// Along the shape frame's z axis, centred.
    Cylinder {
        radius: f64,
        length: f64,
    },
    /// Along the shape frame's z axis, centred; `length` between the cap centres.
    Capsule {
        radius: f64,
        length: f64,
    },
    Sphere {
        radius: f64,
    },
    /// A mesh file that could not be used is replaced by a small sphere (with a warning).
    Mesh {
        path: PathBuf,
        scale: DVec3,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Visual {
    /// Shape frame in the link frame.
    pub origin: DAffine3,
    pub shape: Shape,
    /// RGBA in [0, 1].
    pub color: [f32; 4],
}

/// A foot: a sphere fixed to a link, which the contact model puts on the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Foot {
    /// Sphere centre in the link frame.
    pub center: DVec3,
    pub radius: f64,
}

/// A rigid link (links joined by fixed joints are merged into one).
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    pub name: String,
    /// The movable joint whose child this link is (None for the root).
    pub parent_joint: Option<usize>,
    pub mass: f64,
    /// Centre of mass in the link frame.
    pub com: DVec3,
    /// Inertia tensor about the centre of mass, in the link frame's axes.
    pub inertia: DMat3,
    pub visuals: Vec<Visual>,
    pub foot: Option<Foot>,
}

/// A revolute joint: the child's frame is `parent frame · origin · Rot(axis, q)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    pub parent: usize,
    pub child: usize,
    pub origin: DAffine3,
    /// Unit axis in the joint frame.
    pub axis: DVec3,
    pub lower: f64,
    pub upper: f64,
    /// Torque limit (N·m).
    pub effort: f64,
}

/// Where a leg sits on the body, as gait files name legs: left/right × front/middle/rear.
pub const LEG_NAMES: [&str; 6] = ["lf", "lm", "lr", "rf", "rm", "rr"];

/// A leg: three joints from the body to a foot.
#[derive(Debug, Clone, PartialEq)]
pub struct Leg {
    /// Canonical position name (`lf`, `lm`, …), from where the leg is mounted.
    pub name: &'static str,
    /// Joint indices from the body outwards.
    pub joints: [usize; 3],
    /// The link that carries the foot.
    pub foot_link: usize,
    pub foot: Foot,
}

/// A loaded, validated robot.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotModel {
    pub name: String,
    pub source: PathBuf,
    /// Index 0 is the root (the floating base); a link's parent comes before it.
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
    /// In the order of [`LEG_NAMES`].
    pub legs: Vec<Leg>,
    /// The walking direction in the URDF's base link frame; the model's body frame is that frame
    /// turned about z so that its x points this way (see `legs`).
    pub forward: super::legs::Forward,
    /// Things that were accepted with a fallback (e.g. a missing visual mesh).
    pub warnings: Vec<String>,
}

impl RobotModel {
    pub fn total_mass(&self) -> f64 {
        self.links.iter().map(|l| l.mass).sum()
    }

    /// The pose of every link relative to the root for joint angles `q` (indexed like `joints`).
    pub fn link_poses(&self, q: &[f64]) -> Vec<DAffine3> {
        let mut poses = vec![DAffine3::IDENTITY; self.links.len()];
        for (k, link) in self.links.iter().enumerate() {
            if let Some(ji) = link.parent_joint {
                let j = &self.joints[ji];
                poses[k] = poses[j.parent] * j.origin * DAffine3::from_axis_angle(j.axis, q[ji]);
            }
        }
        poses
    }
}
