//! The hexapod in rapier: the URDF model as a reduced-coordinate multibody with a floating base,
//! servos as joint motors, and the paper's contact model under each foot as the only ground force.
//!
//! - Links carry no colliders: rapier computes no contacts at all (neither with the ground nor
//!   between links). Each step, each foot's force from [`crate::contact`] is applied to its link.
//! - Servos are rapier's ForceBased joint motors: an implicit PD law in physical units,
//!   τ = k·(q* − q) − d·q̇, limited to the URDF's `effort`. (The default AccelerationBased model
//!   scales the gains by each joint's small effective inertia and lets the robot sag.) Rapier does
//!   not report motor torques for multibodies, so the sample carries the PD law's torque.
//! - Rapier's default damping of 0.1 on every multibody degree of freedom is removed: air drag on
//!   the body is not part of the model, and joint damping is the servo's.
//! - Nothing sleeps.

use super::engine::{Engine, STANDARD_GRAVITY};
use crate::contact::{ContactForce, ContactModel, ContactState, EffectiveMass, sphere_geometry};
use crate::robot::RobotModel;
use crate::terrain::HeightGrid;
use glam::{DAffine3, DMat2, DQuat, DVec2, DVec3};
use rapier3d::math::Pose;
use rapier3d::na;
use rapier3d::prelude::{
    GenericJointBuilder, JointAxesMask, JointAxis, MassProperties, MotorModel, Multibody,
    MultibodyJoint, MultibodyJointHandle, RigidBodyBuilder, RigidBodyHandle,
};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Servo gains (the reference's: 20 N·m/rad, 0.05 N·m·s/rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoGains {
    /// N·m/rad
    pub stiffness: f64,
    /// N·m·s/rad
    pub damping: f64,
}

impl Default for ServoGains {
    fn default() -> Self {
        ServoGains {
            stiffness: 20.0,
            damping: 0.05,
        }
    }
}

/// How the robot is simulated: step, solver substeps, servo gains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HexapodSettings {
    pub dt: f64,
    /// rapier's substeps per step (each rebuilds the multibody's dynamics).
    pub solver_iterations: usize,
    pub gains: ServoGains,
}

impl Default for HexapodSettings {
    fn default() -> Self {
        HexapodSettings {
            dt: 1e-3,
            solver_iterations: 4,
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
    gains: ServoGains,
    /// rapier body per model link
    bodies: Vec<RigidBodyHandle>,
    /// rapier joint per model joint
    joints: Vec<MultibodyJointHandle>,
    /// the root's rapier frame is the base link frame shifted to its centre of mass
    root_com: DVec3,
    targets: Vec<f64>,
    foot_states: [ContactState; 6],
    last_contacts: [Option<ContactForce>; 6],
    step: u64,
}

fn pose_of(a: &DAffine3) -> Pose {
    Pose::from_parts(
        a.translation.as_vec3(),
        DQuat::from_mat3(&a.matrix3).normalize().as_quat(),
    )
}

fn affine_of(p: &Pose) -> DAffine3 {
    DAffine3::from_rotation_translation(p.rotation.as_dquat(), p.translation.as_dvec3())
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
        let mut engine = Engine::new(settings.dt, STANDARD_GRAVITY, settings.solver_iterations);
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
        let mut joints = Vec::with_capacity(model.joints.len());
        for joint in &model.joints {
            let parent_shift = if joint.parent == 0 {
                DAffine3::from_translation(-root_com)
            } else {
                DAffine3::IDENTITY
            };
            // rapier's revolute turns about the joint frames' x axis: rotate x onto the URDF axis
            let to_axis = DAffine3::from_quat(DQuat::from_rotation_arc(DVec3::X, joint.axis));
            let data = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
                .local_frame1(pose_of(&(parent_shift * joint.origin * to_axis)))
                .local_frame2(pose_of(&to_axis))
                .contacts_enabled(false)
                .limits(JointAxis::AngX, [joint.lower as f32, joint.upper as f32])
                .motor_model(JointAxis::AngX, MotorModel::ForceBased)
                .motor_max_force(JointAxis::AngX, joint.effort as f32)
                .build();
            let handle = engine
                .multibody_joints
                .insert(bodies[joint.parent], bodies[joint.child], data, true)
                .expect("the model is a tree, so every joint attaches a new child");
            joints.push(handle);
        }
        let mut hexapod = Hexapod {
            engine,
            model,
            terrain,
            contact,
            gains: settings.gains,
            bodies,
            joints,
            root_com,
            targets: pose.to_vec(),
            foot_states: Default::default(),
            last_contacts: [None; 6],
            step: 0,
        };
        hexapod.initialise_multibody(pose);
        hexapod
    }

    /// Sets the joint coordinates to `pose`, clears rapier's default damping, moves the links.
    fn initialise_multibody(&mut self, pose: &[f64]) {
        let link_id = self
            .engine
            .multibody_joints
            .rigid_body_link(self.bodies[0])
            .copied();
        let link_id = link_id.expect("the root belongs to the multibody");
        let ndofs;
        {
            let mb = self
                .engine
                .multibody_joints
                .get_multibody_mut(link_id.multibody)
                .expect("the multibody exists");
            mb.damping_mut().fill(0.0);
            ndofs = mb.ndofs();
        }
        for (k, &angle) in pose.iter().enumerate() {
            self.joint_mut(k).apply_displacement(&[angle as f32]);
        }
        let mb = self
            .engine
            .multibody_joints
            .get_multibody_mut(link_id.multibody)
            .expect("the multibody exists");
        debug_assert_eq!(ndofs, 6 + self.model.joints.len());
        mb.forward_kinematics(&self.engine.bodies, true);
        mb.update_rigid_bodies(&mut self.engine.bodies, true);
        self.set_targets(pose);
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

    /// Sets the servos' position targets (per model joint).
    pub fn set_targets(&mut self, targets: &[f64]) {
        self.targets.copy_from_slice(targets);
        let (k, d) = (self.gains.stiffness as f32, self.gains.damping as f32);
        for (j, &target) in targets.iter().enumerate() {
            self.joint_mut(j)
                .data
                .set_motor_position(JointAxis::AngX, target as f32, k, d);
        }
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

    /// World pose of a model link's frame.
    fn link_frame(&self, link: usize) -> DAffine3 {
        let pose = affine_of(self.engine.bodies[self.bodies[link]].position());
        if link == 0 {
            pose * DAffine3::from_translation(-self.root_com)
        } else {
            pose
        }
    }

    /// The rapier joint of a model joint.
    fn joint_mut(&mut self, joint: usize) -> &mut MultibodyJoint {
        let (mb, link) = self
            .engine
            .multibody_joints
            .get_mut(self.joints[joint])
            .expect("every model joint is in the multibody");
        let link = mb
            .link_mut(link)
            .expect("a joint's link is in its multibody");
        &mut link.joint
    }

    /// The robot's multibody.
    fn multibody(&self) -> &Multibody {
        let root = self.engine.multibody_joints.rigid_body_link(self.bodies[0]);
        let root = root.expect("the root belongs to the multibody");
        self.engine
            .multibody_joints
            .get_multibody(root.multibody)
            .expect("the multibody exists")
    }

    /// The multibody link of a model link.
    fn multibody_link(&self, link: usize) -> usize {
        let id = self
            .engine
            .multibody_joints
            .rigid_body_link(self.bodies[link]);
        id.expect("every model link is in the multibody").id
    }

    /// Computes each foot's ground force, applies it, and advances one step.
    pub fn step(&mut self) -> HexapodSample {
        let dt = self.dt();
        for &h in &self.bodies {
            let body = &mut self.engine.bodies[h];
            body.reset_forces(false);
            body.reset_torques(false);
        }
        let mut contacts = [None; 6];
        for (k, leg) in self.model.legs.iter().enumerate() {
            let frame = self.link_frame(leg.foot_link);
            let center = frame.transform_point3(leg.foot.center);
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
            let com = frame.transform_point3(self.model.links[leg.foot_link].com);
            let mb = self.multibody();
            let mb_link = self.multibody_link(leg.foot_link);
            let point_jacobian =
                PointJacobian::new(mb.body_jacobian(mb_link), geometry.point - com);
            let velocity = point_jacobian.velocity(&mb.generalized_velocity());
            let frame_axes = [
                geometry.frame.tangent_x,
                geometry.frame.tangent_y,
                geometry.frame.normal,
            ];
            let mass = point_jacobian.effective_mass(mb.inv_augmented_mass(), frame_axes);
            let response =
                self.contact
                    .respond(&geometry, velocity, &mass, dt, &mut self.foot_states[k]);
            if let Some(c) = response {
                let body = &mut self.engine.bodies[self.bodies[leg.foot_link]];
                body.add_force(c.force.as_vec3(), true);
                body.add_torque((c.point - com).cross(c.force).as_vec3(), true);
            }
            contacts[k] = response;
        }
        self.engine.step();
        self.step += 1;
        self.last_contacts = contacts;
        self.sample()
    }

    /// The current state.
    pub fn sample(&self) -> HexapodSample {
        let mb = self.multibody();
        let velocities = mb.generalized_velocity();
        let mut joint_angles = Vec::with_capacity(self.joints.len());
        let mut joint_velocities = Vec::with_capacity(self.joints.len());
        let mut joint_torques = Vec::with_capacity(self.joints.len());
        for (j, joint) in self.model.joints.iter().enumerate() {
            let link = mb
                .link(self.multibody_link(joint.child))
                .expect("link exists");
            let q = link.joint().coords()[3] as f64;
            let qd = mb.joint_velocity(link)[0] as f64;
            let effort = joint.effort;
            let torque = (self.gains.stiffness * (self.targets[j] - q) - self.gains.damping * qd)
                .clamp(-effort, effort);
            joint_angles.push(q);
            joint_velocities.push(qd);
            joint_torques.push(torque);
        }
        // root: generalized velocities 0..3 are the root (centre of mass) linear velocity, 3..6 angular
        let v_com = DVec3::new(
            velocities[0] as f64,
            velocities[1] as f64,
            velocities[2] as f64,
        );
        let omega = DVec3::new(
            velocities[3] as f64,
            velocities[4] as f64,
            velocities[5] as f64,
        );
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
            joint_angles,
            joint_velocities,
            joint_targets: self.targets.clone(),
            joint_torques,
            foot_positions,
            foot_contacts: self.last_contacts,
        }
    }
}

/// The Jacobian of a material point on a multibody link: its velocity is J·q̇, with
/// J = J_v − [r]×·J_ω from the link's centre-of-mass Jacobian and the arm r from that centre.
struct PointJacobian {
    rows: na::Matrix3xX<f32>,
}

impl PointJacobian {
    fn new(body_jacobian: &na::Matrix6xX<f32>, arm: DVec3) -> Self {
        let linear = body_jacobian.fixed_rows::<3>(0);
        let angular = body_jacobian.fixed_rows::<3>(3);
        let r = na::Vector3::new(arm.x as f32, arm.y as f32, arm.z as f32);
        let rows = linear - r.cross_matrix() * angular;
        PointJacobian { rows }
    }

    fn velocity(&self, q_dot: &na::DVectorView<f32>) -> DVec3 {
        let v = &self.rows * q_dot;
        DVec3::new(v.x as f64, v.y as f64, v.z as f64)
    }

    /// Effective masses along the ground frame's axes [t₁, t₂, n]: W = A·M⁻¹·Aᵀ with A the point
    /// Jacobian projected on the axes; the in-plane block is inverted as a 2×2 matrix.
    fn effective_mass(
        &self,
        inverse_mass: &na::LU<f32, na::Dyn, na::Dyn>,
        axes: [DVec3; 3],
    ) -> EffectiveMass {
        let projected: [na::DVector<f32>; 3] = axes.map(|a| {
            let d = na::Vector3::new(a.x as f32, a.y as f32, a.z as f32);
            self.rows.tr_mul(&d)
        });
        let solved: [na::DVector<f32>; 3] = [0, 1, 2].map(|k| {
            let mut w = projected[k].clone();
            inverse_mass.solve_mut(&mut w);
            w
        });
        let w = |a: usize, b: usize| projected[a].dot(&solved[b]) as f64;
        let w12 = 0.5 * (w(0, 1) + w(1, 0));
        let inverse = DMat2::from_cols(DVec2::new(w(0, 0), w12), DVec2::new(w12, w(1, 1)));
        EffectiveMass {
            normal: 1.0 / w(2, 2),
            tangential: inverse.inverse(),
        }
    }
}
