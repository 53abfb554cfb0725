//! How the robot's links are joined in rapier — one reduced-coordinate multibody
//! ([`Articulation::Multibody`], the default; see `multibody`) or impulse joints between free
//! bodies ([`Articulation::Impulse`], faster, the joints drift a little; see `impulse`) — behind
//! one trait, [`Joints`], so the hexapod's step does not care which.
//!
//! What both share lives here: the servo law ([`ServoGains::torque`]), a joint's rapier frames and
//! joint data, when a limit constraint can bind, and the torque pair of a saturated servo.

mod impulse;
mod mobility;
mod multibody;

use super::engine::Engine;
use crate::robot::{Joint, RobotModel};
use crate::terrain::GroundFrame;
use glam::{DAffine3, DMat3, DQuat, DVec3, Vec3};
use rapier3d::math::Pose;
use rapier3d::prelude::{GenericJoint, GenericJointBuilder, JointAxesMask, RigidBodyHandle};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

pub use impulse::JointDrift;

/// How the links are joined in rapier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Articulation {
    /// One reduced-coordinate multibody: joints exact by construction.
    #[default]
    Multibody,
    /// Impulse joints between free bodies: about as fast (15 % fewer instructions); the joints
    /// drift apart by up to ~0.35 mm.
    Impulse,
}

/// Constraint-solver sweeps per substep for impulse joints by default.
pub const IMPULSE_PGS_ITERATIONS: usize = 5;

impl Articulation {
    /// Constraint-solver sweeps per substep unless set: the multibody has no constraints to
    /// solve (its servos are implicit springs), so one; impulse joints are held by the solver,
    /// and 5 sweeps hold a levelled stance on 30° (V21) where on 3 a lightly loaded foot falls
    /// into a period-2 oscillation with the joints and the stance slides 2.4 m (4: it slides
    /// facing up or down the slope). On V12 a foot slides at most 1.3 mm per stance with 5
    /// sweeps, 2.3 mm with 3; with 2 the legs shake loose and the feet slide metres. Since rapier
    /// patches 0014–0015 5 sweeps cost less than 3 did before (docs/performance.md).
    pub fn default_pgs_iterations(self) -> usize {
        match self {
            Articulation::Multibody => 1,
            Articulation::Impulse => IMPULSE_PGS_ITERATIONS,
        }
    }

    /// rapier's bias-free sweeps after the constraint solve. Impulse joints: none. rapier's one
    /// sweep removes the velocity its position correction added, so under a steady load (a robot
    /// standing on a slope) the unconverged joint error is corrected afresh each step and the
    /// robot creeps: 46 mm in 10 s on V14's 15° slope with 8 PGS sweeps and one stabilization
    /// sweep (and motor servos), 1.2 mm with 3 sweeps and none.
    pub fn stabilization_iterations(self) -> usize {
        match self {
            Articulation::Multibody => 1,
            Articulation::Impulse => 0,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Articulation::Multibody => "multibody",
            Articulation::Impulse => "impulse",
        }
    }

    /// Joins the links (rapier bodies `bodies`, one per model link, already placed in `pose`)
    /// this way. `root_com` is the base link's centre of mass, where its rapier frame sits.
    pub(super) fn build(
        self,
        engine: &mut Engine,
        model: &Arc<RobotModel>,
        bodies: &[RigidBodyHandle],
        root_com: DVec3,
        pose: &[f64],
        gains: ServoGains,
    ) -> Box<dyn Joints> {
        match self {
            Articulation::Multibody => Box::new(multibody::MultibodyRobot::build(
                engine, model, bodies, root_com, pose, gains,
            )),
            Articulation::Impulse => Box::new(impulse::ImpulseRobot::build(
                engine, model, bodies, root_com, gains,
            )),
        }
    }
}

/// The joined links as the hexapod's step uses them: read the joints, drive the servos, tell
/// how the feet move under contact forces, report the torques applied.
pub(super) trait Joints: Send {
    fn articulation(&self) -> Articulation;

    /// The servos' gains.
    fn gains(&self) -> ServoGains;

    /// Every joint's angle (rad) and rate (rad/s), per model joint.
    fn read_joints(&mut self, engine: &Engine, angles: &mut [f64], rates: &mut [f64]);

    /// Sets each servo for the coming step towards `targets` from the joints' `angles` and
    /// `rates`, and each joint limit that can bind.
    fn drive(&mut self, engine: &mut Engine, targets: &[f64], angles: &[f64], rates: &[f64]);

    /// For each contact, its material point's velocity, and the contact mobility W (how a unit
    /// force at contact j, in its ground axes, changes the velocity at contact i, in its ground
    /// axes), row-major n×n blocks in `mobility`.
    fn contact_mobility(
        &mut self,
        engine: &Engine,
        contacts: &[ContactPoint],
        velocities: &mut [DVec3],
        mobility: &mut [DMat3],
    );

    /// The mass each foot link's normal damper moves, from the articulated robot (see
    /// `impulse`): `(link, mass)`. Articulations whose contact mobility is the articulated
    /// robot's already ignore it.
    fn set_damper_masses(&mut self, _masses: &[(usize, f64)]) {}

    /// The servo torque applied at `joint` over the last step (N·m), given its target and its
    /// rate now.
    fn applied_torque(&self, joint: usize, target: f64, rate: f64) -> f64;

    /// Every joint's [`Joints::applied_torque`], appended to `out`: one call through the trait
    /// object for the sample's eighteen or more (inside it, compiled for each articulation,
    /// `applied_torque` is a direct call).
    fn applied_torques(&self, targets: &[f64], rates: &[f64], out: &mut Vec<f64>) {
        out.extend(
            targets
                .iter()
                .zip(rates)
                .enumerate()
                .map(|(j, (&target, &rate))| self.applied_torque(j, target, rate)),
        );
    }

    /// The root's centre-of-mass velocity and angular velocity (world).
    fn base_velocity(&self, engine: &Engine) -> (DVec3, DVec3);

    /// How far apart the joints have come (zero where they cannot drift).
    fn joint_drift(&self, _engine: &Engine) -> JointDrift {
        JointDrift::default()
    }
}

/// Servo gains (the reference's: 20 N·m/rad, 0.05 N·m·s/rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoGains {
    /// N·m/rad
    pub stiffness: f64,
    /// N·m·s/rad
    pub damping: f64,
}

impl ServoGains {
    /// The servo's torque over a step of `dt` towards `target` from angle `q` and rate `qd`:
    /// τ = k·(q* − q) − (k·dt + d)·q̇. It is the implicit PD law (backward Euler on the spring adds
    /// k·dt of damping on the step's end velocity) with the rate at the step's start: what the
    /// multibody's springs apply up to that rate, and what impulse joints apply outright.
    pub fn torque(&self, target: f64, q: f64, qd: f64, dt: f64) -> f64 {
        self.stiffness * (target - q) - (self.stiffness * dt + self.damping) * qd
    }
}

impl Default for ServoGains {
    fn default() -> Self {
        ServoGains {
            stiffness: 20.0,
            damping: 0.05,
        }
    }
}

/// A foot touching the ground: its link, the contact point, the link's centre of mass and the
/// ground frame there (world).
#[derive(Debug, Clone, Copy)]
pub(super) struct ContactPoint {
    pub link: usize,
    pub body: RigidBodyHandle,
    pub point: DVec3,
    pub com: DVec3,
    pub frame: GroundFrame,
}

impl Default for ContactPoint {
    fn default() -> Self {
        ContactPoint {
            link: 0,
            body: RigidBodyHandle::invalid(),
            point: DVec3::ZERO,
            com: DVec3::ZERO,
            frame: GroundFrame::from_normal(DVec3::Z),
        }
    }
}

pub(super) fn pose_of(a: &DAffine3) -> Pose {
    Pose::from_parts(
        a.translation.as_vec3(),
        DQuat::from_mat3(&a.matrix3).normalize().as_quat(),
    )
}

pub(super) fn affine_of(p: &Pose) -> DAffine3 {
    DAffine3::from_rotation_translation(p.rotation.as_dquat(), p.translation.as_dvec3())
}

/// Applies `torque` (N·m) about the world `axis` to a joint's child link, and its reaction to the
/// parent.
fn apply_joint_torque(
    engine: &mut Engine,
    bodies: &[RigidBodyHandle],
    joint: &Joint,
    axis: DVec3,
    torque: f64,
) {
    let t = (axis * torque).as_vec3();
    engine.add_force_and_torque(bodies[joint.child], Vec3::ZERO, t, false);
    engine.add_force_and_torque(bodies[joint.parent], Vec3::ZERO, -t, false);
}

/// A limit constraint is enabled within this margin (rad) beyond one step's travel of the limit.
const LIMIT_MARGIN: f64 = 1e-3;

/// Whether a joint at angle `q` moving at `qd` can reach a limit within the step. rapier's limit
/// constraint pushes only once the joint is past the limit, yet costs a constraint set-up (on the
/// multibody, a 24-wide solve) every step it exists: it is enabled only where it can bind.
fn limit_can_bind(joint: &Joint, q: f64, qd: f64, dt: f64) -> bool {
    let reach = qd.abs() * dt + LIMIT_MARGIN;
    q - joint.lower < reach || joint.upper - q < reach
}

/// A joint's frames in its parent's and its child's rapier body frames. rapier's revolute turns
/// about the frames' x axis, so x is rotated onto the URDF axis; the root's body frame sits at
/// its centre of mass.
fn joint_frames(joint: &Joint, root_com: DVec3) -> (DAffine3, DAffine3) {
    let parent_shift = if joint.parent == 0 {
        DAffine3::from_translation(-root_com)
    } else {
        DAffine3::IDENTITY
    };
    let to_axis = DAffine3::from_quat(DQuat::from_rotation_arc(DVec3::X, joint.axis));
    (parent_shift * joint.origin * to_axis, to_axis)
}

/// A model joint as rapier joint data for either articulation: a revolute about x between its
/// [`joint_frames`], no contacts between its links.
fn revolute_joint((frame1, frame2): &(DAffine3, DAffine3)) -> GenericJoint {
    GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
        .local_frame1(pose_of(frame1))
        .local_frame2(pose_of(frame2))
        .contacts_enabled(false)
        .build()
}
