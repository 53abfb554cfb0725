//! The robot as one reduced-coordinate multibody (rapier's `MultibodyJointSet`): a floating base and
//! one coordinate per URDF joint, so the joints cannot drift apart.
//!
//! Why it is driven the way it is: each rapier substep rebuilds the multibody's 24×24 mass matrix
//! and factorises it (the bulk of a step), and every joint motor or limit adds a constraint whose
//! set-up is one more 24-wide solve. So:
//! - **Servos are implicit joint springs**, not motor constraints: rapier integrates a spring
//!   −k·(q − q*) and a damper −d·q̇ on a joint coordinate by backward Euler (k·dt² and d·dt on the
//!   mass matrix' diagonal), so the applied torque is τ = k·(q* − qₙ) − (k·dt + d)·q̇ₙ₊₁ — the
//!   ForceBased motor's law, with no constraint to build. When the torque this predicts would
//!   exceed the URDF's `effort`, the spring is switched off for the step and ±effort is applied as
//!   an explicit torque pair on the joint's two links, so the torque limit holds exactly.
//! - **A limit constraint exists only where it can bind**: rapier's limit pushes back only once a
//!   joint is past its limit, so a constraint is enabled when the joint is within one step's travel
//!   (plus a margin) of a limit, and is inert — costless — otherwise.

use super::mobility::{DOFS, Mobility};
use super::{
    Articulation, ContactPoint, Joints, ServoGains, apply_joint_torque, joint_frames,
    limit_can_bind, revolute_joint,
};
use crate::robot::RobotModel;
use crate::sim::engine::Engine;
use glam::{DMat3, DVec3};
use rapier3d::prelude::{
    JointAxesMask, JointAxis, Multibody, MultibodyJointHandle, MultibodyJointSet, RigidBodyHandle,
};
use std::sync::Arc;

/// rapier's index of the revolute coordinate (AngX) in a joint's spatial layout.
const ANG_X: usize = 3;

pub struct MultibodyRobot {
    model: Arc<RobotModel>,
    /// rapier body per model link
    bodies: Vec<RigidBodyHandle>,
    /// rapier joint per model joint
    joints: Vec<MultibodyJointHandle>,
    /// per model joint: its multibody link and degree of freedom
    links: Vec<usize>,
    dofs: Vec<usize>,
    root: RigidBodyHandle,
    /// Per model joint, this step's servo: `None` = implicit spring, `Some(τ)` = saturated torque.
    saturated: Vec<Option<f64>>,
    /// Per model joint, the coordinate at the start of the step (for the applied torque).
    start_angles: Vec<f64>,
    gains: ServoGains,
    dt: f64,
    /// Per model link: its multibody link and its path ([`LinkPath`]).
    link_paths: Vec<LinkPath>,
    /// Scratch for the contact mobility.
    scratch: Scratch,
}

impl MultibodyRobot {
    /// Joins the links with multibody joints and sets the joint coordinates to `pose`.
    pub fn build(
        engine: &mut Engine,
        model: &Arc<RobotModel>,
        bodies: &[RigidBodyHandle],
        root_com: DVec3,
        pose: &[f64],
        gains: ServoGains,
    ) -> Self {
        let mut joints = Vec::with_capacity(model.joints.len());
        for joint in &model.joints {
            let data = revolute_joint(&joint_frames(joint, root_com));
            let handle = engine
                .multibody_joints
                .insert(bodies[joint.parent], bodies[joint.child], data, true)
                .expect("the model is a tree, so every joint attaches a new child");
            joints.push(handle);
        }
        let mut robot = MultibodyRobot {
            model: model.clone(),
            bodies: bodies.to_vec(),
            links: Vec::new(),
            dofs: Vec::new(),
            joints,
            root: bodies[0],
            saturated: vec![None; model.joints.len()],
            start_angles: pose.to_vec(),
            gains,
            dt: engine.dt(),
            // the loader gives six legs of equal length (`robot::branches`)
            scratch: Scratch::for_joints(model.joints.len()).expect("six legs alike"),
            link_paths: Vec::new(),
        };
        for joint in &model.joints {
            let link = robot.multibody_link(engine, bodies[joint.child]);
            let dof = robot
                .multibody(engine)
                .link(link)
                .expect("link")
                .assembly_id();
            robot.links.push(link);
            robot.dofs.push(dof);
        }
        robot.link_paths = bodies
            .iter()
            .map(|&body| {
                let link = robot.multibody_link(engine, body);
                LinkPath {
                    link,
                    dofs: dofs_on_path(robot.multibody(engine), link),
                }
            })
            .collect();
        let mb = robot.multibody_mut(&mut engine.multibody_joints);
        // rapier's default damping of 0.1 on every degree of freedom is not part of the model:
        // air drag on the body is not modelled, and joint damping is the servo's
        mb.damping_mut().fill(0.0);
        // the Coriolis, centrifugal and gyroscopic forces explicit, as MuJoCo's Euler integrator
        // takes them: rapier then factorises only the mass matrix M (patch 0013), the matrix
        // the constraints and the contact mobility (`mobility.rs`) solve with, so the free motion
        // and the contact forces' effect are computed with one matrix
        mb.set_explicit_coriolis(true);
        for (j, &angle) in pose.iter().enumerate() {
            robot
                .joint_mut(engine, j)
                .apply_displacement(&[angle as f32]);
        }
        let mb = robot.multibody_mut(&mut engine.multibody_joints);
        assert_eq!(
            mb.ndofs(),
            6 + model.joints.len(),
            "a free root and one degree of freedom per joint"
        );
        mb.forward_kinematics(&engine.bodies, true);
        mb.update_rigid_bodies(&mut engine.bodies, true);
        // factorise the mass matrix now: rapier does it in its step, and on a steep slope a foot
        // touches before the first one (the contact mobility needs the factors)
        mb.dof_inverse_inertia(&engine.bodies);
        robot
    }

    fn multibody_link(&self, engine: &Engine, body: RigidBodyHandle) -> usize {
        let id = engine.multibody_joints.rigid_body_link(body);
        id.expect("every model link is in the multibody").id
    }

    fn multibody<'a>(&self, engine: &'a Engine) -> &'a Multibody {
        let root = engine.multibody_joints.rigid_body_link(self.root);
        let root = root.expect("the root belongs to the multibody");
        engine
            .multibody_joints
            .get_multibody(root.multibody)
            .expect("the multibody exists")
    }

    fn multibody_mut<'a>(&self, joints: &'a mut MultibodyJointSet) -> &'a mut Multibody {
        let root = joints.rigid_body_link(self.root).copied();
        let root = root.expect("the root belongs to the multibody");
        joints
            .get_multibody_mut(root.multibody)
            .expect("the multibody exists")
    }

    fn joint_mut<'a>(
        &self,
        engine: &'a mut Engine,
        joint: usize,
    ) -> &'a mut rapier3d::prelude::MultibodyJoint {
        let (mb, link) = engine
            .multibody_joints
            .get_mut(self.joints[joint])
            .expect("every model joint is in the multibody");
        &mut mb.link_mut(link).expect("a joint's link exists").joint
    }
}

impl Joints for MultibodyRobot {
    fn articulation(&self) -> Articulation {
        Articulation::Multibody
    }

    fn gains(&self) -> ServoGains {
        self.gains
    }

    /// Every joint's angle (rad) and rate (rad/s): its coordinate and generalized velocity.
    fn read_joints(&mut self, engine: &Engine, angles: &mut [f64], rates: &mut [f64]) {
        let mb = self.multibody(engine);
        let q_dot = mb.generalized_velocity();
        let q_dot = q_dot.as_slice();
        // (zipped: no bounds check of the outputs a joint)
        let joints = self.links.iter().zip(&self.dofs);
        for ((angle, rate), (&link, &dof)) in angles.iter_mut().zip(rates.iter_mut()).zip(joints) {
            let link = mb.link(link).expect("link exists");
            *angle = link.joint().coords()[ANG_X] as f64;
            *rate = q_dot[dof] as f64;
        }
    }

    /// The root's centre-of-mass velocity and angular velocity (world).
    fn base_velocity(&self, engine: &Engine) -> (DVec3, DVec3) {
        // generalized velocities 0..3: the root's centre-of-mass velocity; 3..6: its angular velocity
        let v = self.multibody(engine).generalized_velocity();
        (
            DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64),
            DVec3::new(v[3] as f64, v[4] as f64, v[5] as f64),
        )
    }

    /// For each contact, its material point's velocity, and the contact mobility of the
    /// articulated robot, W_ij = A_i·M⁻¹·A_jᵀ (A the point Jacobians projected on each contact's
    /// ground-frame axes), row-major n×n blocks in `mobility`.
    fn contact_mobility(
        &mut self,
        engine: &Engine,
        contacts: &[ContactPoint],
        velocities: &mut [DVec3],
        mobility: &mut [DMat3],
    ) {
        let mb = self.multibody(engine);
        let args = (mb, &self.link_paths[..], contacts, velocities, mobility);
        match &mut self.scratch {
            Scratch::Legs3(scratch) => contact_mobility_in(scratch, args),
            Scratch::Legs4(scratch) => contact_mobility_in(scratch, args),
            Scratch::Legs5(scratch) => contact_mobility_in(scratch, args),
            Scratch::Legs6(scratch) => contact_mobility_in(scratch, args),
        }
    }

    /// Sets each servo for the coming step (see the module docs): an implicit spring towards its
    /// target, or the effort limit as an explicit torque; and each limit constraint that can bind.
    fn drive(&mut self, engine: &mut Engine, targets: &[f64], angles: &[f64], rates: &[f64]) {
        let model = &self.model;
        let ServoGains {
            stiffness: k,
            damping: d,
        } = self.gains;
        let dt = self.dt;
        let mut saturated_torques = [(0, DVec3::ZERO, 0.0); DOFS + 18];
        let mut n_saturated = 0;
        let mb = self.multibody_mut(&mut engine.multibody_joints);
        // (each joint's inputs and outputs zipped: no bounds check of seven vectors a joint)
        let servos = (model.joints.iter().zip(targets).zip(angles).zip(rates))
            .zip(self.start_angles.iter_mut().zip(&mut self.saturated))
            .zip(&self.links);
        for (j, (((((joint, &target), &q), &qd), (start, saturated_j)), &link)) in
            servos.enumerate()
        {
            *start = q;
            // the implicit law's torque, with this step's end velocity estimated by the current one
            let predicted = self.gains.torque(target, q, qd, dt);
            let saturated =
                (predicted.abs() > joint.effort).then(|| joint.effort.copysign(predicted));
            *saturated_j = saturated;
            let near_limit = limit_can_bind(joint, q, qd, dt);
            let link = mb.link_mut(link).expect("a joint's link exists");
            let rapier_joint = &mut link.joint;
            match saturated {
                None => rapier_joint.set_spring(ANG_X, k as f32, target as f32),
                Some(_) => rapier_joint.set_spring(ANG_X, 0.0, 0.0),
            }
            if near_limit {
                rapier_joint
                    .data
                    .set_limits(JointAxis::AngX, [joint.lower as f32, joint.upper as f32]);
            } else {
                rapier_joint.data.limit_axes.remove(JointAxesMask::ANG_X);
            }
            if let Some(torque) = saturated {
                // the joint's axis in the world, on the child link's side
                let frame =
                    link.local_to_world().rotation * link.joint().data.local_frame2.rotation;
                saturated_torques[n_saturated] = (j, (frame * glam::Vec3::X).as_dvec3(), torque);
                n_saturated += 1;
            }
        }
        // each servo's damper on its degree of freedom (a slice, not nalgebra's checked index)
        let damping = mb.damping_mut().as_mut_slice();
        for (&dof, saturated) in self.dofs.iter().zip(&self.saturated) {
            damping[dof] = if saturated.is_some() { 0.0 } else { d as f32 };
        }
        for &(j, axis, torque) in &saturated_torques[..n_saturated] {
            apply_joint_torque(engine, &self.bodies, &model.joints[j], axis, torque);
        }
    }

    /// The torque the servo applied over the last step (N·m): the implicit spring-damper's
    /// k·(q* − qₙ) − (k·dt + d)·q̇ₙ₊₁, or the saturated effort.
    fn applied_torque(&self, joint: usize, target: f64, qd: f64) -> f64 {
        self.servo_torque(self.saturated[joint], self.start_angles[joint], target, qd)
    }

    /// [`Joints::applied_torques`], each joint's state zipped with its target and rate (no
    /// bounds check a joint).
    fn applied_torques(&self, targets: &[f64], rates: &[f64], out: &mut Vec<f64>) {
        let servos = self.saturated.iter().zip(&self.start_angles);
        out.extend(
            servos
                .zip(targets.iter().zip(rates))
                .map(|((&saturated, &q), (&target, &qd))| {
                    self.servo_torque(saturated, q, target, qd)
                }),
        );
    }
}

impl MultibodyRobot {
    /// A servo's torque over the last step: its `saturated` effort, or the implicit law from the
    /// step's start angle `q`, with the step's end velocity `qd`, which rapier's spring saw.
    #[inline]
    fn servo_torque(&self, saturated: Option<f64>, q: f64, target: f64, qd: f64) -> f64 {
        match saturated {
            Some(torque) => torque,
            None => self.gains.torque(target, q, qd, self.dt),
        }
    }
}

/// The contact mobility's scratch, sized to the multibody's degrees of freedom: the free root and
/// six legs of three joints (hex18 and most hexapods: [`DOFS`]) to six each (redundant legs,
/// `robot::redundant`), one monomorphised solve per size.
enum Scratch {
    Legs3(Box<Mobility<DOFS>>),
    Legs4(Box<Mobility<{ DOFS + 6 }>>),
    Legs5(Box<Mobility<{ DOFS + 12 }>>),
    Legs6(Box<Mobility<{ DOFS + 18 }>>),
}

impl Scratch {
    /// The scratch for `joints` joints on six legs of equal length, or why there is none.
    fn for_joints(joints: usize) -> Result<Self, String> {
        Ok(match joints {
            18 => Scratch::Legs3(Box::default()),
            24 => Scratch::Legs4(Box::default()),
            30 => Scratch::Legs5(Box::default()),
            36 => Scratch::Legs6(Box::default()),
            _ => {
                return Err(format!(
                    "the multibody articulation takes six legs of 3, 4, 5 or 6 joints each, all alike; this robot's legs have {joints} joints in all (use --articulation impulse)"
                ));
            }
        })
    }
}

/// A model link's multibody link, and the degrees of freedom on its path from the root in
/// increasing order: the only columns of its body Jacobian rapier fills (patch 0002).
struct LinkPath {
    link: usize,
    dofs: Vec<usize>,
}

/// The degrees of freedom on multibody link `link`'s path from the root, in increasing order:
/// each ancestor link's joint's (the root's six first), then its own.
fn dofs_on_path(mb: &Multibody, link: usize) -> Vec<usize> {
    let mut dofs = Vec::new();
    let mut at = Some(link);
    while let Some(l) = at {
        let l = mb.link(l).expect("a link's ancestors are links");
        dofs.extend(l.assembly_id()..l.assembly_id() + l.joint().ndofs());
        at = l.parent_id();
    }
    dofs.sort_unstable();
    dofs
}

/// [`MultibodyRobot::contact_mobility`] with the scratch of `D` degrees of freedom.
fn contact_mobility_in<const D: usize>(
    scratch: &mut Mobility<D>,
    (mb, link_paths, contacts, velocities, mobility): (
        &Multibody,
        &[LinkPath],
        &[ContactPoint],
        &mut [DVec3],
        &mut [DMat3],
    ),
) {
    let n = contacts.len();
    let q_dot = mb.generalized_velocity();
    let q_dot = q_dot.as_slice();
    // every entry cleared, then each contact's path set: a degree of freedom off a contact's path
    // (another leg's joint: two thirds of them) moves its point not at all
    scratch.begin(3 * n);
    for (i, c) in contacts.iter().enumerate() {
        let LinkPath { link, dofs: path } = &link_paths[c.link];
        // a material point's velocity column per degree of freedom: J_v − [r]×·J_ω, with the
        // arm r from the link's centre of mass (J the link's centre-of-mass Jacobian)
        let jacobian = mb.body_jacobian(*link).as_slice();
        let arm = c.point - c.com;
        // in SSE registers (`Vec3A`): the same products and sums, lane by lane, as scalars
        let r = glam::Vec3A::new(arm.x as f32, arm.y as f32, arm.z as f32);
        let axes = [c.frame.tangent_x, c.frame.tangent_y, c.frame.normal]
            .map(|a| glam::Vec3A::from(a.as_vec3()));
        // the axes as rows: this times a column gives the three axes' dot products in its
        // lanes, each the same products summed in the same order as `dot`'s ((x + y) + z)
        let along = glam::Mat3A::from_cols(axes[0], axes[1], axes[2]).transpose();
        let mut velocity = glam::Vec3A::ZERO;
        let mut rows = scratch.contact(i);
        for &dof in path {
            let column = &jacobian[6 * dof..6 * dof + 6];
            let linear = glam::Vec3A::from_slice(&column[..3]);
            let angular = glam::Vec3A::from_slice(&column[3..]);
            let point = linear - r.cross(angular);
            velocity += point * q_dot[dof];
            rows.set(dof, (along * point).to_array());
        }
        velocities[i] = glam::Vec3::from(velocity).as_dvec3();
    }
    if n == 0 {
        return;
    }
    assert!(
        scratch.compute(mb.augmented_mass_factors(), 3 * n),
        "the mass matrix is factorised from the start, {D} degrees of freedom"
    );
    // W is symmetric (`mobility.rs`): each block above the diagonal is read, and mirrored below
    for i in 0..n {
        // (a hexapod's feet: the contact's rows read once, each block's entries by lane)
        let rows = scratch.rows_of(i);
        for j in i..n {
            let columns = match &rows {
                Some(rows) => {
                    let mut columns = [[0.0; 3]; 3];
                    for (b, column) in columns.iter_mut().enumerate() {
                        for (entry, row) in column.iter_mut().zip(rows) {
                            *entry = row[3 * j + b];
                        }
                    }
                    columns
                }
                None => scratch.block(i, j),
            };
            let [x, y, z] = columns.map(|c| glam::Vec3::from_array(c).as_dvec3());
            let block = DMat3::from_cols(x, y, z);
            mobility[i * n + j] = block;
            if j != i {
                mobility[j * n + i] = block.transpose();
            }
        }
    }
}
