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
    pub from: FootFrom,
}

/// Where a foot came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FootFrom {
    /// A collision sphere in the URDF.
    Sphere,
    /// The robot file's `[feet]`.
    RobotFile,
    /// Found at the tip of the last link's collision geometry (see `robot::foot`).
    CollisionTip,
    /// Found at the tip of the last link's visual geometry: it has no collision geometry.
    VisualTip,
}

impl FootFrom {
    pub fn describe(self) -> &'static str {
        match self {
            FootFrom::Sphere => "given by the URDF's collision sphere",
            FootFrom::RobotFile => "given by the robot file's [feet]",
            FootFrom::CollisionTip => "found at the tip of the link's collision geometry",
            FootFrom::VisualTip => "found at the tip of the link's visual geometry (no collision)",
        }
    }
}

/// A sphere of a link's contact set, in the link frame: the link's geometry as the terrain feels
/// it (see `robot::contact_set`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSphere {
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
    /// Where the link touches the ground besides its foot: its collision geometry as spheres.
    pub contacts: Vec<ContactSphere>,
    /// The URDF links fixed to this one (by fixed joints) and merged into it, by name.
    pub merged: Vec<String>,
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

/// A leg: three to [`crate::robot::kinematics::MAX_LEG_JOINTS`] joints from the body to a foot.
#[derive(Debug, Clone, PartialEq)]
pub struct Leg {
    /// Canonical position name (`lf`, `lm`, …), from where the leg is mounted.
    pub name: &'static str,
    /// Joint indices from the body outwards.
    pub joints: Vec<usize>,
    /// Per joint of `joints`: None for the three that place the foot (the three that sweep the
    /// largest workspace), and for each further joint of a redundant leg (a tarsus, a hip roll)
    /// the rest angle its inverse kinematics pulls it towards (see `robot::redundant`).
    pub posture: Vec<Option<f64>>,
    /// The link that carries the foot.
    pub foot_link: usize,
    pub foot: Foot,
}

/// A revolute joint of the URDF that hexsim holds still at an angle (welded there: it is not in
/// [`RobotModel::joints`]): a joint off the six legs (a head, an arm, a tail: a passive body held
/// in its pose), or a joint of a leg longer than
/// [`crate::robot::kinematics::MAX_LEG_JOINTS`] beyond the three its gait drives. See `branches`.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldJoint {
    /// The URDF joint's name.
    pub name: String,
    /// The angle it is held at (rad): its zero, or the nearest limit when zero is outside them.
    pub angle: f64,
    /// On a leg (the link at the leg's end, as the URDF names it), or off the legs (None).
    pub on_leg: Option<String>,
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
    pub forward: super::forward::Forward,
    /// The gait geometry the robot file states for this robot, if any.
    pub gait_hints: GaitHints,
    /// Things that were accepted with a fallback (e.g. a missing visual mesh).
    pub warnings: Vec<String>,
    /// The URDF's revolute joints held still (welded at an angle): off the legs, or those of a
    /// leg longer than [`crate::robot::kinematics::MAX_LEG_JOINTS`] beyond three.
    pub held: Vec<HeldJoint>,
}

/// Gait lengths a robot's file states (its designer's stance): a gait file's own values take
/// precedence, and what neither gives is fitted to the robot (see `gait::fit`). All in metres.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitHints {
    /// The hips' plane above the ground, standing.
    pub stance_height: Option<f64>,
    /// Horizontal distance of the standing foot from its hip.
    pub reach: Option<f64>,
    /// Swing apex above the stance.
    pub step_height: Option<f64>,
    /// Foot travel over a stance at the nominal speed.
    pub stride_length: Option<f64>,
}

impl GaitHints {
    /// Each given length must be finite and positive (a stride or step may be 0).
    pub fn validate(&self) -> Result<(), String> {
        let fields = [
            ("stance_height", self.stance_height, false),
            ("reach", self.reach, false),
            ("step_height", self.step_height, true),
            ("stride_length", self.stride_length, true),
        ];
        for (field, value, zero_ok) in fields {
            if let Some(v) = value
                && !(v.is_finite() && (v > 0.0 || (zero_ok && v == 0.0)))
            {
                let bound = if zero_ok { "≥ 0" } else { "> 0" };
                return Err(format!(
                    "field `gait.{field}`: expected a finite number {bound} (m), got {v}"
                ));
            }
        }
        Ok(())
    }
}

impl RobotModel {
    pub fn total_mass(&self) -> f64 {
        self.links.iter().map(|l| l.mass).sum()
    }

    /// The links that touch nothing: neither a foot nor collision geometry hexsim could read
    /// (none in the URDF, or its meshes missing). They pass through the terrain: a belly let
    /// down on the ground or a shin against a riser is not felt there.
    pub fn links_without_contact(&self) -> Vec<&str> {
        self.links
            .iter()
            .filter(|l| l.foot.is_none() && l.contacts.is_empty())
            .map(|l| l.name.as_str())
            .collect()
    }

    /// Joint angles per model joint from each leg's (in `legs` order).
    pub fn pose_from_legs(&self, angles: &[impl AsRef<[f64]>]) -> Vec<f64> {
        let mut pose = vec![0.0; self.joints.len()];
        for (leg, angles) in self.legs.iter().zip(angles) {
            for (&j, &q) in leg.joints.iter().zip(angles.as_ref()) {
                pose[j] = q;
            }
        }
        pose
    }

    /// Height of the hips' plane in the body frame: the mean height of the legs' first joints,
    /// which hang from the body (zero for hex18, whose base link origin is at its hips). Stance
    /// heights are measured from it, not from the base link's origin, which a URDF may put anywhere.
    pub fn hips_plane(&self) -> f64 {
        let total: f64 = self
            .legs
            .iter()
            .map(|leg| self.joints[leg.joints[0]].origin.translation.z)
            .sum();
        total / self.legs.len().max(1) as f64
    }

    /// The lowest point of the body (the root link's visuals) below its frame's origin, in the body
    /// frame (m); None when the body has no shape hexsim can measure (a mesh other than STL).
    pub fn body_bottom(&self) -> Option<f64> {
        let lowest = |visual: &Visual| -> Option<f64> {
            let frame = visual.origin;
            let z_axis = frame.matrix3.z_axis;
            // how far a disc of radius r about the frame's z reaches down
            let disc = |r: f64| r * (1.0 - (z_axis.z * z_axis.z).min(1.0)).sqrt();
            let ends = |length: f64| {
                let c = frame.translation;
                let half = frame.matrix3 * DVec3::new(0.0, 0.0, length / 2.0);
                (c + half).z.min((c - half).z)
            };
            match &visual.shape {
                Shape::Box { half_extents } => (0..8)
                    .map(|k| {
                        let sign = DVec3::new(
                            if k & 1 == 0 { -1.0 } else { 1.0 },
                            if k & 2 == 0 { -1.0 } else { 1.0 },
                            if k & 4 == 0 { -1.0 } else { 1.0 },
                        );
                        frame.transform_point3(*half_extents * sign).z
                    })
                    .reduce(f64::min),
                Shape::Sphere { radius } => Some(frame.translation.z - radius),
                Shape::Cylinder { radius, length } => Some(ends(*length) - disc(*radius)),
                Shape::Capsule { radius, length } => Some(ends(*length) - radius),
                Shape::Mesh { path, scale } => super::mesh::mesh_vertices(path)?
                    .into_iter()
                    .map(|v| frame.transform_point3(v * *scale).z)
                    .reduce(f64::min),
            }
        };
        self.links[0]
            .visuals
            .iter()
            .filter_map(lowest)
            .reduce(f64::min)
    }

    /// The pose of every link relative to the root for joint angles `q` (indexed like `joints`).
    pub fn link_poses(&self, q: &[f64]) -> Vec<DAffine3> {
        let mut poses = Vec::new();
        self.link_poses_into(q, &mut poses);
        poses
    }

    /// [`Self::link_poses`] into `poses`, reusing its allocation (every step of a walk).
    pub fn link_poses_into(&self, q: &[f64], poses: &mut Vec<DAffine3>) {
        self.poses_into(q, poses, |_, _| {});
    }

    /// [`Self::link_poses_into`], and into `joints` each joint's frame on the way: its parent's
    /// pose times its origin, the frame [`Self::joint_axis`] would compute again (per model joint;
    /// [`crate::robot::statics::holding_torques_at`] reads them).
    pub fn link_and_joint_poses_into(
        &self,
        q: &[f64],
        poses: &mut Vec<DAffine3>,
        joints: &mut Vec<DAffine3>,
    ) {
        joints.clear();
        joints.resize(self.joints.len(), DAffine3::IDENTITY);
        self.poses_into(q, poses, |j, frame| joints[j] = frame);
    }

    /// Each link's pose into `poses`, telling `joint` each joint's frame on the way.
    fn poses_into(
        &self,
        q: &[f64],
        poses: &mut Vec<DAffine3>,
        mut joint: impl FnMut(usize, DAffine3),
    ) {
        poses.clear();
        poses.resize(self.links.len(), DAffine3::IDENTITY);
        for (k, link) in self.links.iter().enumerate() {
            if let Some(ji) = link.parent_joint {
                let j = &self.joints[ji];
                let frame = poses[j.parent] * j.origin;
                joint(ji, frame);
                poses[k] = frame * DAffine3::from_axis_angle(j.axis, q[ji]);
            }
        }
    }

    /// Joint `j`'s origin and axis (as the URDF scales it) in the frame of `poses`
    /// ([`Self::link_poses`]).
    pub fn joint_axis(&self, poses: &[DAffine3], j: usize) -> (DVec3, DVec3) {
        let joint = &self.joints[j];
        let frame = poses[joint.parent] * joint.origin;
        (frame.translation, frame.matrix3 * joint.axis)
    }

    /// The centre of mass in the frame of `poses` ([`Self::link_poses`]).
    pub fn centre_of_mass(&self, poses: &[DAffine3]) -> DVec3 {
        let weighted: DVec3 = self
            .links
            .iter()
            .zip(poses)
            .map(|(link, p)| p.transform_point3(link.com) * link.mass)
            .sum();
        weighted / self.total_mass()
    }
}
