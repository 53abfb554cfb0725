//! The robot in maximal coordinates: every link a free rigid body, held to its parent by one of
//! rapier's impulse joints (five locked axes and a revolute one, solved with the contacts' PGS).
//!
//! Why it exists: a step costs a few small constraint rows instead of rebuilding and factorising
//! the multibody's 24×24 mass matrix, which makes it about three times faster — for large sweeps.
//! The price: the locked axes are held by the solver, not by construction, so the joints drift
//! apart by a little (measured by [`ImpulseRobot::joint_drift`]; see the README's Performance
//! section), and the foot's effective mass is its own link's, not the articulated robot's.
//!
//! Servos are rapier's ForceBased joint motors: the same implicit law as the multibody's springs,
//! τ = k·(q* − q) − d·q̇ solved implicitly, with the impulse bounded by the URDF's `effort`.

use super::engine::Engine;
use super::hexapod::{ContactPoint, ServoGains, joint_frames, limit_can_bind, pose_of};
use crate::robot::RobotModel;
use glam::{DAffine3, DMat3, DQuat, DVec3};
use rapier3d::prelude::{
    GenericJointBuilder, ImpulseJointHandle, JointAxesMask, JointAxis, MotorModel, RigidBodyHandle,
};

pub struct ImpulseRobot {
    joints: Vec<ImpulseJointHandle>,
    /// Per model joint, its frames in the parent's and the child's rapier body frames.
    frames: Vec<(DAffine3, DAffine3)>,
    gains: ServoGains,
    /// rapier's substep, over which a motor impulse is applied
    substep: f64,
}

/// How far apart the joints have come: the largest distance between a joint's two anchors (m)
/// and the largest rotation about an axis the joint locks (rad).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointDrift {
    pub anchor: f64,
    pub angle: f64,
}

impl ImpulseRobot {
    /// Joins the links (already placed in `pose`) with impulse joints.
    pub fn build(
        engine: &mut Engine,
        model: &RobotModel,
        bodies: &[RigidBodyHandle],
        root_com: DVec3,
        pose: &[f64],
        gains: ServoGains,
    ) -> Self {
        let mut joints = Vec::with_capacity(model.joints.len());
        let mut frames = Vec::with_capacity(model.joints.len());
        for (joint, &angle) in model.joints.iter().zip(pose) {
            let (frame1, frame2) = joint_frames(joint, root_com);
            let data = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
                .local_frame1(pose_of(&frame1))
                .local_frame2(pose_of(&frame2))
                .contacts_enabled(false)
                .motor_model(JointAxis::AngX, MotorModel::ForceBased)
                .motor_max_force(JointAxis::AngX, joint.effort as f32)
                .motor_position(
                    JointAxis::AngX,
                    angle as f32,
                    gains.stiffness as f32,
                    gains.damping as f32,
                )
                .build();
            joints.push(engine.impulse_joints.insert(
                bodies[joint.parent],
                bodies[joint.child],
                data,
                true,
            ));
            frames.push((frame1, frame2));
        }
        ImpulseRobot {
            joints,
            frames,
            gains,
            substep: engine.dt() / engine.substeps() as f64,
        }
    }

    /// A joint's two frames in the world: the parent's and the child's.
    fn world_frames(
        &self,
        engine: &Engine,
        model: &RobotModel,
        bodies: &[RigidBodyHandle],
        joint: usize,
    ) -> (DAffine3, DAffine3) {
        let j = &model.joints[joint];
        let (f1, f2) = &self.frames[joint];
        let pose = |h: RigidBodyHandle| super::hexapod::affine_of(engine.bodies[h].position());
        (pose(bodies[j.parent]) * *f1, pose(bodies[j.child]) * *f2)
    }

    /// A joint's angle (rad) and rate (rad/s): the child frame's turn about the joint's x axis
    /// relative to the parent frame.
    pub fn joint_state(
        &self,
        engine: &Engine,
        model: &RobotModel,
        bodies: &[RigidBodyHandle],
        joint: usize,
    ) -> (f64, f64) {
        let (parent, child) = self.world_frames(engine, model, bodies, joint);
        let relative = DQuat::from_mat3(&(parent.matrix3.transpose() * child.matrix3));
        // the twist about x of the relative rotation (its swing is drift)
        let q = 2.0 * relative.x.atan2(relative.w);
        let q = (q + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        let j = &model.joints[joint];
        let w = |h: RigidBodyHandle| engine.bodies[h].angvel().as_dvec3();
        let axis = child.matrix3.x_axis;
        (q, (w(bodies[j.child]) - w(bodies[j.parent])).dot(axis))
    }

    /// The root's centre-of-mass velocity and angular velocity (world).
    pub fn base_velocity(&self, engine: &Engine, root: RigidBodyHandle) -> (DVec3, DVec3) {
        let rb = &engine.bodies[root];
        (rb.linvel().as_dvec3(), rb.angvel().as_dvec3())
    }

    /// For each contact, its material point's velocity, and the contact mobility of the foot
    /// link alone (W_ij = 0 between feet): within one PGS sweep a force on the foot moves the foot
    /// link first and the joints pass only part of it on, so the articulated robot's mobility would
    /// let the stick force overshoot.
    pub fn contact_mobility(
        &self,
        engine: &Engine,
        model: &RobotModel,
        contacts: &[ContactPoint],
        velocities: &mut [DVec3],
        mobility: &mut [DMat3],
    ) {
        let n = contacts.len();
        mobility[..n * n].fill(DMat3::ZERO);
        for (i, c) in contacts.iter().enumerate() {
            let rb = &engine.bodies[c.body];
            velocities[i] = rb.velocity_at_point(c.point.as_vec3()).as_dvec3();
            let rotation = DMat3::from_quat(rb.position().rotation.as_dquat());
            let l = &model.links[c.link];
            let inverse_inertia = rotation * l.inertia.inverse() * rotation.transpose();
            let arm = c.point - c.com;
            let axes = [c.frame.tangent_x, c.frame.tangent_y, c.frame.normal];
            // a free rigid body: a·b/m + (r×a)·I⁻¹·(r×b)
            let w = |a: DVec3, b: DVec3| {
                a.dot(b) / l.mass + arm.cross(a).dot(inverse_inertia * arm.cross(b))
            };
            mobility[i * n + i] = DMat3::from_cols_array_2d(&axes.map(|b| axes.map(|a| w(a, b))));
        }
    }

    /// Sets each motor's target for the coming step, and each limit constraint that can bind.
    pub fn drive(
        &mut self,
        engine: &mut Engine,
        model: &RobotModel,
        targets: &[f64],
        (angles, rates): (&[f64], &[f64]),
    ) {
        let ServoGains {
            stiffness: k,
            damping: d,
        } = self.gains;
        let dt = engine.dt();
        for (j, joint) in model.joints.iter().enumerate() {
            let (q, qd) = (angles[j], rates[j]);
            let near_limit = limit_can_bind(joint, q, qd, dt);
            let data = &mut engine
                .impulse_joints
                .get_mut(self.joints[j], false)
                .expect("every model joint is a rapier joint")
                .data;
            data.set_motor_position(JointAxis::AngX, targets[j] as f32, k as f32, d as f32);
            if near_limit {
                data.set_limits(JointAxis::AngX, [joint.lower as f32, joint.upper as f32]);
            } else {
                data.limit_axes.remove(JointAxesMask::ANG_X);
            }
        }
    }

    /// The torque the motor applied over the last substep (N·m, on the child about the axis).
    pub fn applied_torque(&self, engine: &Engine, joint: usize) -> f64 {
        let j = engine
            .impulse_joints
            .get(self.joints[joint])
            .expect("every model joint is a rapier joint");
        // rapier signs the motor impulse along its own constraint axis: the torque on the child is
        // its opposite (checked against the statics by `servo_torques_hold_the_standing_robot`)
        -j.data.motors[JointAxis::AngX as usize].impulse as f64 / self.substep
    }

    /// The joints' worst separation now.
    pub fn joint_drift(
        &self,
        engine: &Engine,
        model: &RobotModel,
        bodies: &[RigidBodyHandle],
    ) -> JointDrift {
        let mut drift = JointDrift::default();
        for j in 0..self.joints.len() {
            let (parent, child) = self.world_frames(engine, model, bodies, j);
            let anchor = parent.translation.distance(child.translation);
            // the swing: the angle between the two frames' x axes
            let angle = parent.matrix3.x_axis.angle_between(child.matrix3.x_axis);
            drift.anchor = drift.anchor.max(anchor);
            drift.angle = drift.angle.max(angle);
        }
        drift
    }
}
