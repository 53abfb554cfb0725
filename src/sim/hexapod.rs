//! The hexapod in rapier: the URDF model's links as rigid bodies, joined either as one
//! reduced-coordinate multibody ([`Articulation::Multibody`], the default; see `multibody`) or by
//! impulse joints ([`Articulation::Impulse`], faster, the joints drift a little; see `impulse`),
//! with servos at every joint and the paper's contact model under each foot as the only ground force.
//!
//! - Links carry no colliders: rapier computes no contacts at all (neither with the ground nor
//!   between links). Each step, each foot's force from [`crate::contact`] is applied to its link.
//! - Servos follow the implicit PD law in physical units, τ = k·(q* − q) − d·q̇, limited to the
//!   URDF's `effort`; the sample carries the torque actually applied.
//! - Nothing sleeps.

use super::engine::{Engine, STANDARD_GRAVITY};
use super::impulse::{ImpulseRobot, JointDrift};
use super::multibody::MultibodyRobot;
use crate::contact::joint::JointContact;
use crate::contact::{
    ContactForce, ContactModel, ContactState, SphereGeometry, respond_jointly, sphere_geometry,
};
use crate::robot::{Joint, RobotModel};
use crate::terrain::{GroundFrame, HeightGrid};
use glam::{DAffine3, DQuat, DVec3};
use rapier3d::math::Pose;
use rapier3d::prelude::{
    GenericJoint, GenericJointBuilder, JointAxesMask, MassProperties, RigidBodyBuilder,
    RigidBodyHandle,
};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// How the links are joined in rapier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Articulation {
    /// One reduced-coordinate multibody: joints exact by construction.
    #[default]
    Multibody,
    /// Impulse joints between free bodies: about 4× faster; the joints drift apart by up to
    /// ~0.4 mm.
    Impulse,
}

impl Articulation {
    /// Constraint-solver sweeps per substep unless set: the multibody has no constraints to
    /// solve (its servos are implicit springs), so one; impulse joints are held by the solver:
    /// with 3 sweeps a foot slides at most 2.3 mm per stance on V12 (4: 1.7 mm; 6: 1.3 mm), with
    /// 2 the legs shake loose and the feet slide metres (measured; see the README's Performance
    /// section).
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
}

/// Servo gains (the reference's: 20 N·m/rad, 0.05 N·m·s/rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
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

/// Steps between two measurements of the impulse joints' drift (it changes slowly).
const DRIFT_EVERY: u64 = 10;

/// Constraint-solver sweeps per substep for impulse joints by default.
pub const IMPULSE_PGS_ITERATIONS: usize = 3;

/// rapier substeps per step by default: one — V1–V15 hold with it (see the README's Performance
/// section), and each substep rebuilds the multibody's mass matrix.
pub const DEFAULT_SOLVER_ITERATIONS: usize = 1;

/// How the robot is simulated: articulation, step, solver substeps, servo gains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HexapodSettings {
    pub articulation: Articulation,
    pub dt: f64,
    /// rapier's substeps per step (each rebuilds the multibody's dynamics).
    pub solver_iterations: usize,
    /// Constraint-solver sweeps per substep (the impulse joints' stiffness; `None`: the
    /// articulation's default, [`Articulation::default_pgs_iterations`]).
    pub pgs_iterations: Option<usize>,
    pub gains: ServoGains,
}

impl Default for HexapodSettings {
    fn default() -> Self {
        HexapodSettings {
            articulation: Articulation::default(),
            dt: 1e-3,
            solver_iterations: DEFAULT_SOLVER_ITERATIONS,
            pgs_iterations: None,
            gains: ServoGains::default(),
        }
    }
}

/// Where and how the robot starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Body x, y (m) and heading (rad).
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

/// The robot's state after a step.
#[derive(Debug, Clone, PartialEq)]
pub struct HexapodSample {
    pub step: u64,
    pub time: f64,
    /// The body (root link) frame in the world.
    pub body: DAffine3,
    /// Height of the body frame's origin above the terrain under it (m).
    pub body_height: f64,
    pub body_rotation: DQuat,
    /// Velocity of the body frame's origin and angular velocity (world).
    pub body_velocity: DVec3,
    pub body_angular_velocity: DVec3,
    /// Per model joint.
    pub joint_angles: Vec<f64>,
    pub joint_velocities: Vec<f64>,
    pub joint_targets: Vec<f64>,
    /// The servo's torque by its PD law, limited to the effort (N·m).
    pub joint_torques: Vec<f64>,
    /// Per leg, in the model's leg order.
    pub foot_positions: [DVec3; 6],
    pub foot_contacts: [Option<ContactForce>; 6],
    /// How far apart the joints have come (zero for the multibody; measured every 10 steps).
    pub joint_drift: JointDrift,
}

impl HexapodSample {
    /// Roll, pitch, yaw (rad) of the body, z-y-x convention.
    pub fn roll_pitch_yaw(&self) -> (f64, f64, f64) {
        let (yaw, pitch, roll) = self.body_rotation.to_euler(glam::EulerRot::ZYX);
        (roll, pitch, yaw)
    }
}

pub struct Hexapod {
    engine: Engine,
    model: Arc<RobotModel>,
    terrain: Arc<HeightGrid>,
    contact: ContactModel,
    /// rapier body per model link
    bodies: Vec<RigidBodyHandle>,
    joints: Joints,
    /// the root's rapier frame is the base link frame shifted to its centre of mass
    root_com: DVec3,
    targets: Vec<f64>,
    /// Joint angles and rates now (read once per step: both the servos and the sample use them).
    angles: Vec<f64>,
    rates: Vec<f64>,
    /// The joints' drift, measured every [`DRIFT_EVERY`] steps (impulse joints).
    drift: JointDrift,
    foot_states: [ContactState; 6],
    last_contacts: [Option<ContactForce>; 6],
    step: u64,
    /// Wall-clock seconds spent inside rapier's step (see [`Hexapod::physics_seconds`]).
    physics_seconds: f64,
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

/// The links' joining, by articulation.
enum Joints {
    Multibody(MultibodyRobot),
    Impulse(ImpulseRobot),
}

fn pose_of(a: &DAffine3) -> Pose {
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
pub(super) fn apply_joint_torque(
    engine: &mut Engine,
    bodies: &[RigidBodyHandle],
    joint: &Joint,
    axis: DVec3,
    torque: f64,
) {
    let t = (axis * torque).as_vec3();
    engine.bodies[bodies[joint.child]].add_torque(t, false);
    engine.bodies[bodies[joint.parent]].add_torque(-t, false);
}

/// A limit constraint is enabled within this margin (rad) beyond one step's travel of the limit.
const LIMIT_MARGIN: f64 = 1e-3;

/// Whether a joint at angle `q` moving at `qd` can reach a limit within the step. rapier's limit
/// constraint pushes only once the joint is past the limit, yet costs a constraint set-up (on the
/// multibody, a 24-wide solve) every step it exists: it is enabled only where it can bind.
pub(super) fn limit_can_bind(joint: &Joint, q: f64, qd: f64, dt: f64) -> bool {
    let reach = qd.abs() * dt + LIMIT_MARGIN;
    q - joint.lower < reach || joint.upper - q < reach
}

/// A joint's frames in its parent's and its child's rapier body frames. rapier's revolute turns
/// about the frames' x axis, so x is rotated onto the URDF axis; the root's body frame sits at
/// its centre of mass.
pub(super) fn joint_frames(joint: &Joint, root_com: DVec3) -> (DAffine3, DAffine3) {
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
pub(super) fn revolute_joint((frame1, frame2): &(DAffine3, DAffine3)) -> GenericJoint {
    GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
        .local_frame1(pose_of(frame1))
        .local_frame2(pose_of(frame2))
        .contacts_enabled(false)
        .build()
}

impl Hexapod {
    /// Builds the robot standing at `placement` with joint angles `pose` (per model joint), its
    /// lowest foot just touching the terrain.
    pub fn new(
        model: Arc<RobotModel>,
        terrain: Arc<HeightGrid>,
        contact: ContactModel,
        settings: HexapodSettings,
        placement: Placement,
        pose: &[f64],
    ) -> Self {
        let pgs = settings
            .pgs_iterations
            .unwrap_or(settings.articulation.default_pgs_iterations());
        let mut engine = Engine::new(
            settings.dt,
            STANDARD_GRAVITY,
            settings.solver_iterations,
            pgs,
            settings.articulation.stabilization_iterations(),
        );
        // body height: each foot just above the ground under it
        let heading = DQuat::from_rotation_z(placement.yaw);
        let link_poses = model.link_poses(pose);
        let mut body_z = f64::NEG_INFINITY;
        for leg in &model.legs {
            let foot = heading * link_poses[leg.foot_link].transform_point3(leg.foot.center);
            let ground = terrain.height(placement.x + foot.x, placement.y + foot.y);
            body_z = body_z.max(ground + leg.foot.radius - foot.z);
        }
        let body = DAffine3::from_rotation_translation(
            heading,
            DVec3::new(placement.x, placement.y, body_z + 1e-3),
        );
        let root_com = model.links[0].com;
        let mut bodies = Vec::with_capacity(model.links.len());
        for (k, link) in model.links.iter().enumerate() {
            let (frame, com) = if k == 0 {
                (body * DAffine3::from_translation(root_com), DVec3::ZERO)
            } else {
                (body * link_poses[k], link.com)
            };
            let inertia =
                glam::Mat3::from_cols_array(&link.inertia.to_cols_array().map(|v| v as f32));
            let rb = RigidBodyBuilder::dynamic()
                .pose(pose_of(&frame))
                .additional_mass_properties(MassProperties::with_inertia_matrix(
                    com.as_vec3(),
                    link.mass as f32,
                    inertia,
                ))
                .can_sleep(false)
                .build();
            bodies.push(engine.bodies.insert(rb));
        }
        let joints = match settings.articulation {
            Articulation::Multibody => Joints::Multibody(MultibodyRobot::build(
                &mut engine,
                &model,
                &bodies,
                root_com,
                pose,
                settings.gains,
            )),
            Articulation::Impulse => Joints::Impulse(ImpulseRobot::build(
                &mut engine,
                &model,
                &bodies,
                root_com,
                settings.gains,
            )),
        };
        let n = model.joints.len();
        let mut hexapod = Hexapod {
            engine,
            model,
            terrain,
            contact,
            bodies,
            joints,
            root_com,
            targets: pose.to_vec(),
            angles: vec![0.0; n],
            rates: vec![0.0; n],
            drift: JointDrift::default(),
            foot_states: Default::default(),
            last_contacts: [None; 6],
            step: 0,
            physics_seconds: 0.0,
        };
        hexapod.read_joints();
        hexapod
    }

    /// Reads every joint's angle and rate from rapier.
    fn read_joints(&mut self) {
        match &mut self.joints {
            Joints::Multibody(r) => r.read_joints(&self.engine, &mut self.angles, &mut self.rates),
            Joints::Impulse(r) => r.read_joints(
                &self.engine,
                &self.model,
                &self.bodies,
                &mut self.angles,
                &mut self.rates,
            ),
        }
    }

    pub fn model(&self) -> &RobotModel {
        &self.model
    }

    pub fn terrain(&self) -> &HeightGrid {
        &self.terrain
    }

    pub fn dt(&self) -> f64 {
        self.engine.dt()
    }

    pub fn time(&self) -> f64 {
        self.step as f64 * self.engine.dt()
    }

    pub fn articulation(&self) -> Articulation {
        match self.joints {
            Joints::Multibody(_) => Articulation::Multibody,
            Joints::Impulse(_) => Articulation::Impulse,
        }
    }

    /// Sets the servos' position targets (per model joint), used from the next step on.
    pub fn set_targets(&mut self, targets: &[f64]) {
        self.targets.copy_from_slice(targets);
    }

    /// The body (root link) frame in the world.
    pub fn body_frame(&self) -> DAffine3 {
        self.link_frame(0)
    }

    /// World poses of all the model's links (for drawing).
    pub fn link_frames(&self) -> Vec<DAffine3> {
        (0..self.model.links.len())
            .map(|k| self.link_frame(k))
            .collect()
    }

    /// Wall-clock seconds spent inside rapier's step so far. The rest of a step is hexsim's
    /// (contacts, servos, gait): the benchmark reports the split, so a figure can be read against
    /// what rapier alone would allow.
    pub fn physics_seconds(&self) -> f64 {
        self.physics_seconds
    }

    /// How far apart the joints have come (always zero for the multibody).
    pub fn joint_drift(&self) -> JointDrift {
        match &self.joints {
            Joints::Multibody(_) => JointDrift::default(),
            Joints::Impulse(r) => r.joint_drift(&self.engine, &self.model, &self.bodies),
        }
    }

    /// World pose of a model link's frame.
    fn link_frame(&self, link: usize) -> DAffine3 {
        let pose = affine_of(self.engine.bodies[self.bodies[link]].position());
        if link == 0 {
            pose * DAffine3::from_translation(-self.root_com)
        } else {
            pose
        }
    }

    /// Computes each foot's ground force, applies it with the servos', and advances one step.
    pub fn step(&mut self) -> HexapodSample {
        let dt = self.dt();
        for &h in &self.bodies {
            let body = &mut self.engine.bodies[h];
            body.reset_forces(false);
            body.reset_torques(false);
        }
        match &mut self.joints {
            Joints::Multibody(r) => r.drive(
                &mut self.engine,
                &self.model,
                &self.bodies,
                &self.targets,
                (&self.angles, &self.rates),
            ),
            Joints::Impulse(r) => r.drive(
                &mut self.engine,
                &self.model,
                &self.bodies,
                &self.targets,
                (&self.angles, &self.rates),
            ),
        }
        // the feet touching the ground, then their forces together (they push each other)
        let mut geometries = [None; 6];
        let mut points = [ContactPoint::default(); 6];
        let mut legs = [0; 6];
        let mut n = 0;
        for (k, leg) in self.model.legs.iter().enumerate() {
            let frame = self.link_frame(leg.foot_link);
            let center = frame.transform_point3(leg.foot.center);
            let r = leg.foot.radius;
            // a swinging foot well clear of the ground needs no closest-point search
            if center.z - r > self.terrain.ceiling_near(center.x, center.y, r) {
                self.foot_states[k] = ContactState::default();
                continue;
            }
            let geometry = sphere_geometry(
                &self.terrain,
                center,
                leg.foot.radius,
                self.contact.orientation,
            );
            if geometry.penetration <= 0.0 {
                self.foot_states[k] = ContactState::default();
                continue;
            }
            points[n] = ContactPoint {
                link: leg.foot_link,
                body: self.bodies[leg.foot_link],
                point: geometry.point,
                com: frame.transform_point3(self.model.links[leg.foot_link].com),
                frame: geometry.frame,
            };
            geometries[n] = Some(geometry);
            legs[n] = k;
            n += 1;
        }
        let mut velocities = [DVec3::ZERO; 6];
        let mut mobility = [glam::DMat3::ZERO; 36];
        match &mut self.joints {
            Joints::Multibody(r) => {
                r.contact_mobility(&self.engine, &points[..n], &mut velocities, &mut mobility)
            }
            Joints::Impulse(r) => r.contact_mobility(
                &self.engine,
                &self.model,
                &points[..n],
                &mut velocities,
                &mut mobility,
            ),
        }
        // (the entries past n are placeholders: only inputs[..n] is read)
        let placeholder = SphereGeometry {
            penetration: 0.0,
            point: DVec3::ZERO,
            frame: GroundFrame::from_normal(DVec3::Z),
        };
        let inputs: [JointContact; 6] = std::array::from_fn(|i| JointContact {
            geometry: geometries[i].as_ref().unwrap_or(&placeholder),
            velocity: velocities[i],
        });
        let mut states = [ContactState::default(); 6];
        for i in 0..n {
            states[i] = self.foot_states[legs[i]];
        }
        let mut forces = [None; 6];
        respond_jointly(
            &self.contact,
            &inputs[..n],
            |i, j| mobility[i * n + j],
            dt,
            &mut states[..n],
            &mut forces[..n],
        );
        let mut contacts = [None; 6];
        for i in 0..n {
            self.foot_states[legs[i]] = states[i];
            if let Some(c) = forces[i] {
                let body = &mut self.engine.bodies[points[i].body];
                body.add_force(c.force.as_vec3(), true);
                body.add_torque((c.point - points[i].com).cross(c.force).as_vec3(), true);
            }
            contacts[legs[i]] = forces[i];
        }
        let started = std::time::Instant::now();
        self.engine.step();
        self.physics_seconds += started.elapsed().as_secs_f64();
        self.step += 1;
        self.read_joints();
        if self.step.is_multiple_of(DRIFT_EVERY) {
            self.drift = self.joint_drift();
        }
        self.last_contacts = contacts;
        self.sample()
    }

    /// The current state.
    pub fn sample(&self) -> HexapodSample {
        let joint_torques = (0..self.model.joints.len())
            .map(|j| match &self.joints {
                Joints::Multibody(r) => r.applied_torque(j, self.targets[j], self.rates[j]),
                Joints::Impulse(r) => r.applied_torque(j),
            })
            .collect();
        let (v_com, omega) = match &self.joints {
            Joints::Multibody(r) => r.base_velocity(&self.engine),
            Joints::Impulse(r) => r.base_velocity(&self.engine, self.bodies[0]),
        };
        let body = self.link_frame(0);
        let com_offset = body.matrix3 * self.root_com;
        let mut foot_positions = [DVec3::ZERO; 6];
        for (k, leg) in self.model.legs.iter().enumerate() {
            foot_positions[k] = self
                .link_frame(leg.foot_link)
                .transform_point3(leg.foot.center);
        }
        HexapodSample {
            step: self.step,
            time: self.time(),
            body_height: body.translation.z
                - self.terrain.height(body.translation.x, body.translation.y),
            body,
            body_rotation: DQuat::from_mat3(&body.matrix3).normalize(),
            body_velocity: v_com - omega.cross(com_offset),
            body_angular_velocity: omega,
            joint_angles: self.angles.clone(),
            joint_velocities: self.rates.clone(),
            joint_targets: self.targets.clone(),
            joint_torques,
            foot_positions,
            foot_contacts: self.last_contacts,
            joint_drift: self.drift,
        }
    }
}
