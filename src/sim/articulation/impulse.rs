//! The robot in maximal coordinates: every link a free rigid body, held to its parent by one of
//! rapier's impulse joints (five locked axes and a revolute one, solved with the contacts' PGS).
//!
//! Why it exists: a step costs a few small constraint rows instead of rebuilding and factorising
//! the multibody's mass matrix: 15 % fewer instructions a step since rapier was patched, about as
//! fast on the clock
//! (docs/performance.md), for large sweeps. The price: the locked axes are held by the solver,
//! not by construction, so the joints drift apart by a little (measured by
//! [`ImpulseRobot::joint_drift`]; see docs/performance.md), and the foot's effective mass is its own link's, not the articulated robot's.
//!
//! Servos: the multibody's law τ = k·(q* − qₙ₊₁) − d·q̇ₙ₊₁, split. The spring k·(q* − qₙ) is
//! an explicit torque pair on the joint's two links at the step's start; the damper, k·dt + d on
//! the step's end velocity (which with the explicit spring is the implicit law: backward Euler
//! adds k·dt of damping), is rapier's joint motor about the free axis with no stiffness and no
//! target speed, solved with the joint's other rows. Both never change, so rapier keeps its
//! joint layout (a motor given a new target every step would rebuild it). Where the law would
//! pass the URDF's `effort`, the effort is applied explicitly and the damper switched off, as
//! the multibody does: the torque limit holds exactly. The torque reported is the spring's plus
//! the motor's impulse over the step.
//!
//! Why the damper is implicit: explicit, a step moves a joint's speed by (k·dt + d)·dt/I of
//! itself, I the inertia the solver's few sweeps leave the joint (less than the articulated
//! robot's, and not to be known in advance), and past 1 it overshoots every step. ant_bot's
//! servos rang so at the 0.5 ms its tibias set, from 7 ms into the drop (`sim::ringing`), and its
//! walk diverged; PhantomX's rang and skated 8–20 m in 20 s. With the damper in the solver they
//! walk 2.550 and 2.689 m (the multibody: 2.572, 2.693 m).

use super::{
    Articulation, ContactPoint, Joints, ServoGains, affine_of, joint_frames, limit_can_bind,
    revolute_joint,
};
use crate::robot::RobotModel;
use crate::sim::engine::Engine;
use glam::{DAffine3, DMat3, DQuat, DVec3, Vec3};
use rapier3d::prelude::{
    GenericJoint, ImpulseJointHandle, JointAxesMask, JointAxis, MotorModel, RigidBodyHandle,
};
use std::sync::Arc;

pub struct ImpulseRobot {
    model: Arc<RobotModel>,
    /// rapier body per model link
    bodies: Vec<RigidBodyHandle>,
    joints: Vec<ImpulseJointHandle>,
    /// Per model joint, its frames in the parent's and the child's rapier body frames.
    frames: Vec<(DAffine3, DAffine3)>,
    /// Their rotations.
    rotations: Vec<(DQuat, DQuat)>,
    /// Per model joint, its axis in the world as last read.
    axes: Vec<DVec3>,
    /// Per model link, its inverse inertia tensor about its centre of mass (link frame).
    inverse_inertias: Vec<DMat3>,
    /// Per model joint, whether its limit constraint is on (switched only when that changes: each
    /// change costs rapier a new joint layout).
    limited: Vec<bool>,
    /// Per model joint, the servo torque applied this step (N·m, on the child about the axis).
    torques: Vec<f64>,
    gains: ServoGains,
    /// Per foot link, the mass its normal damper moves (see `contact_mobility`).
    damper_masses: Vec<(usize, f64)>,
    /// Per model joint, the servo's explicit spring torque k·(q* − q) this step (N·m), and
    /// whether its law saturates at the effort (then the effort is applied explicitly, and its
    /// damper is off: switched only when that changes, as the limits are).
    springs: Vec<f64>,
    saturated: Vec<bool>,
    /// The servos' damper, k·dt + d (N·m·s/rad), solved implicitly by rapier's joint motor.
    damping: f64,
    /// Per model link, the servos' torques on it this step, summed in the order rapier summed
    /// them when each was given apart (see [`Joints::drive`]).
    link_torques: Vec<Vec3>,
    /// The links a joint drives (a joint's parent or child), in order.
    driven_links: Vec<usize>,
}

/// rapier's index of a revolute's free axis (x) among a joint's motors.
const ANG_X: usize = 3;

/// Sets `data`'s motor about its free axis to the servo's damper alone: no stiffness, no target
/// speed, `damping` (N·m·s/rad) as a force, at most `effort`. A motor that never changes costs
/// no new joint layout, and rapier solves it with the joint's other rows, implicitly: the
/// damping acts on the step's end velocity, and no damping makes it ring.
fn set_damper(data: &mut GenericJoint, damping: f64, effort: f64) {
    data.set_motor_model(JointAxis::AngX, MotorModel::ForceBased);
    data.set_motor(JointAxis::AngX, 0.0, 0.0, 0.0, damping as f32);
    data.set_motor_max_force(JointAxis::AngX, effort as f32);
}

/// The most mass, in free foot links along the contact's normal, a foot's normal damper is taken
/// to move. Joints only add mass (W − W·Jᵀ(J·W·Jᵀ)⁻¹·J·W ≤ W), so the free link is the least the
/// damper can be moving, and its exact-decay impulse m·(1 − e^(−c·h/m))·v on a mass m of at most
/// this many of them changes the velocity by less than this many times itself, under 2 for any
/// c and h: it never sets the foot swinging. (hex18's vertical mass is 1.66 free tibias: on the
/// flat the bound does not bite; against a wall, 0.073 kg on a 0.015 kg link diverged.)
const DAMPER_FREE_MASSES: f64 = 1.8;

/// How far apart the joints have come: the largest distance between a joint's two anchors (m)
/// and the largest rotation about an axis the joint locks (rad).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointDrift {
    pub anchor: f64,
    pub angle: f64,
}

impl ImpulseRobot {
    /// Joins the links (already placed) with impulse joints.
    pub fn build(
        engine: &mut Engine,
        model: &Arc<RobotModel>,
        bodies: &[RigidBodyHandle],
        root_com: DVec3,
        gains: ServoGains,
    ) -> Self {
        let mut joints = Vec::with_capacity(model.joints.len());
        let mut frames = Vec::with_capacity(model.joints.len());
        let damping = gains.stiffness * engine.dt() + gains.damping;
        for joint in &model.joints {
            let joint_frames = joint_frames(joint, root_com);
            let mut data = revolute_joint(&joint_frames);
            set_damper(&mut data, damping, joint.effort);
            joints.push(engine.impulse_joints.insert(
                bodies[joint.parent],
                bodies[joint.child],
                data,
                true,
            ));
            frames.push(joint_frames);
        }
        let n = joints.len();
        let driven_links = (0..model.links.len())
            .filter(|&k| model.joints.iter().any(|j| j.parent == k || j.child == k))
            .collect();
        let rotation = |f: &DAffine3| DQuat::from_mat3(&f.matrix3).normalize();
        ImpulseRobot {
            model: model.clone(),
            bodies: bodies.to_vec(),
            joints,
            rotations: frames
                .iter()
                .map(|(f1, f2)| (rotation(f1), rotation(f2)))
                .collect(),
            axes: vec![DVec3::X; n],
            inverse_inertias: model.links.iter().map(|l| l.inertia.inverse()).collect(),
            frames,
            limited: vec![false; n],
            torques: vec![0.0; n],
            gains,
            damper_masses: Vec::new(),
            springs: vec![0.0; n],
            saturated: vec![false; n],
            damping,
            link_torques: vec![Vec3::ZERO; model.links.len()],
            driven_links,
        }
    }

    /// A joint's two frames in the world: the parent's and the child's.
    fn world_frames(&self, engine: &Engine, joint: usize) -> (DAffine3, DAffine3) {
        let j = &self.model.joints[joint];
        let (f1, f2) = &self.frames[joint];
        let pose = |link: usize| affine_of(engine.bodies[self.bodies[link]].position());
        (pose(j.parent) * *f1, pose(j.child) * *f2)
    }
}

impl Joints for ImpulseRobot {
    fn articulation(&self) -> Articulation {
        Articulation::Impulse
    }

    fn gains(&self) -> ServoGains {
        self.gains
    }

    /// Every joint's angle (rad) and rate (rad/s): the child frame's turn about the joint's x axis
    /// relative to the parent frame. Also keeps each joint's axis for [`Self::drive`].
    fn read_joints(&mut self, engine: &Engine, angles: &mut [f64], rates: &mut [f64]) {
        use std::f64::consts::PI;
        let bodies = &self.bodies;
        // each body looked up and its rotation widened once where a joint's parent is the last
        // joint's child (down a leg) or the root
        let root = &engine.bodies[bodies[0]];
        let root_rotation = root.position().rotation.as_dquat();
        let mut last = (0, root, root_rotation);
        // rapier keeps the joints in the order they were inserted, the model's: each is read from
        // its place there, where its handle matches, rather than looked up by its handle
        let mut in_order = engine.impulse_joints.iter();
        for (j, joint) in self.model.joints.iter().enumerate() {
            let (parent, parent_rotation) = if joint.parent == last.0 {
                (last.1, last.2)
            } else if joint.parent == 0 {
                (root, root_rotation)
            } else {
                let parent = &engine.bodies[bodies[joint.parent]];
                (parent, parent.position().rotation.as_dquat())
            };
            let child = &engine.bodies[bodies[joint.child]];
            let child_rotation = child.position().rotation.as_dquat();
            last = (joint.child, child, child_rotation);
            let (r1, r2) = self.rotations[j];
            let parent_frame = parent_rotation * r1;
            let child_frame = child_rotation * r2;
            let relative = parent_frame.inverse() * child_frame;
            // the twist about x of the relative rotation (its swing is drift)
            let q = 2.0 * relative.x.atan2(relative.w);
            angles[j] = wrapped(q + PI) - PI;
            let axis = child_frame * DVec3::X;
            rates[j] = (child.angvel() - parent.angvel()).as_dvec3().dot(axis);
            self.axes[j] = axis;
            // the torque applied over the step just taken: the spring's, and the damper's impulse
            // (rapier's on the parent: the child takes it reversed)
            let rapier_joint = match in_order.next() {
                Some((handle, joint)) if handle == self.joints[j] => Some(joint),
                _ => engine.impulse_joints.get(self.joints[j]),
            };
            let damper = match rapier_joint {
                Some(joint) if !self.saturated[j] => {
                    -f64::from(joint.data.motors[ANG_X].impulse) / engine.dt()
                }
                _ => 0.0,
            };
            self.torques[j] = self.springs[j] + damper;
        }
    }

    /// The root's centre-of-mass velocity and angular velocity (world).
    fn base_velocity(&self, engine: &Engine) -> (DVec3, DVec3) {
        let rb = &engine.bodies[self.bodies[0]];
        (rb.linvel().as_dvec3(), rb.angvel().as_dvec3())
    }

    /// For each contact, its material point's velocity, and the contact mobility of the foot
    /// link alone (W_ij = 0 between feet): within one PGS sweep a force on the foot moves the foot
    /// link first and the joints pass only part of it on, so the articulated robot's mobility would
    /// let the stick force overshoot. All but the normal entry W_nn: the normal damper's
    /// exact-decay factor φ(c·h/m) needs the mass the damper really moves, the articulated
    /// robot's (the foot link alone, 0.044 kg on hex18 against the multibody's 0.073 kg, made
    /// the same c damp a third less); it is the multibody's in the starting pose
    /// ([`Joints::set_damper_masses`]), the foot link's until it is set, bounded by
    /// [`DAMPER_FREE_MASSES`] free links along the contact's normal.
    fn contact_mobility(
        &mut self,
        engine: &Engine,
        contacts: &[ContactPoint],
        velocities: &mut [DVec3],
        mobility: &mut [DMat3],
    ) {
        let n = contacts.len();
        mobility[..n * n].fill(DMat3::ZERO);
        let cross = |r: DVec3| {
            DMat3::from_cols(
                DVec3::new(0.0, r.z, -r.y),
                DVec3::new(-r.z, 0.0, r.x),
                DVec3::new(r.y, -r.x, 0.0),
            )
        };
        let axes = |c: &ContactPoint| {
            DMat3::from_cols(c.frame.tangent_x, c.frame.tangent_y, c.frame.normal)
        };
        for (i, c) in contacts.iter().enumerate() {
            let rb = &engine.bodies[c.body];
            velocities[i] = rb.velocity_at_point(c.point.as_vec3()).as_dvec3();
            let rotation = DMat3::from_quat(rb.position().rotation.as_dquat());
            let inverse_inertia = rotation * self.inverse_inertias[c.link] * rotation.transpose();
            let inverse_mass =
                DMat3::from_diagonal(DVec3::splat(1.0 / self.model.links[c.link].mass));
            // a free rigid body: W_ij = 1/m + [r_i]×ᵀ·I⁻¹·[r_j]× between two points on it, in the
            // ground frames' axes; points on different links are taken as uncoupled
            let r_i = cross(c.point - c.com);
            // the free link's mobility along this normal, summed over the link's contacts (a
            // foot between two walls is pushed by both): the damper's bound below
            let mut alone = 0.0;
            for (j, d) in contacts
                .iter()
                .enumerate()
                .filter(|(_, d)| d.link == c.link)
            {
                let r_j = cross(d.point - d.com);
                let world = inverse_mass + r_i.transpose() * inverse_inertia * r_j;
                alone += c.frame.normal.dot(world * d.frame.normal).abs();
                mobility[i * n + j] = axes(c).transpose() * world * axes(d);
            }
            if let Some(&(_, mass)) = self.damper_masses.iter().find(|(l, _)| *l == c.link) {
                // never more than DAMPER_FREE_MASSES free links along this normal
                let w = &mut mobility[i * n + i];
                w.z_axis.z = (1.0 / mass).max(alone / DAMPER_FREE_MASSES);
            }
        }
    }

    fn set_damper_masses(&mut self, masses: &[(usize, f64)]) {
        self.damper_masses = masses.to_vec();
    }

    /// Applies each servo's torque for the coming step, and switches each limit constraint on
    /// where it can bind.
    ///
    /// A servo's torque pair is summed into its two links' torques here and each link is given
    /// its sum once, not each joint's pair apart (36 calls into rapier a step on hex18, not 19):
    /// the same sums bit for bit. Its forces were cleared just before, so rapier's sum starts at
    /// +0 as this one does, adds each link's torques in the same (joint) order, and skips only
    /// zero vectors, which leave any sum started at +0 unchanged.
    fn drive(&mut self, engine: &mut Engine, targets: &[f64], angles: &[f64], rates: &[f64]) {
        let dt = engine.dt();
        self.link_torques.fill(Vec3::ZERO);
        for (j, joint) in self.model.joints.iter().enumerate() {
            let (q, qd) = (angles[j], rates[j]);
            // the whole law with this step's end velocity estimated by the current one, as the
            // multibody's drive: past the effort, the effort alone, explicitly
            let predicted = self.gains.torque(targets[j], q, qd, dt);
            let saturated = predicted.abs() > joint.effort;
            let spring = if saturated {
                joint.effort.copysign(predicted)
            } else {
                self.gains.stiffness * (targets[j] - q)
            };
            self.springs[j] = spring;
            // as `apply_joint_torque` gives it: the child's, then the parent's
            let t = (self.axes[j] * spring).as_vec3();
            self.link_torques[joint.child] += t;
            self.link_torques[joint.parent] += -t;
            let near_limit = limit_can_bind(joint, q, qd, dt);
            if near_limit == self.limited[j] && saturated == self.saturated[j] {
                continue;
            }
            let data = &mut engine
                .impulse_joints
                .get_mut(self.joints[j], false)
                .expect("every model joint is a rapier joint")
                .data;
            if near_limit != self.limited[j] {
                self.limited[j] = near_limit;
                if near_limit {
                    data.set_limits(JointAxis::AngX, [joint.lower as f32, joint.upper as f32]);
                } else {
                    data.limit_axes.remove(JointAxesMask::ANG_X);
                }
            }
            if saturated != self.saturated[j] {
                self.saturated[j] = saturated;
                if saturated {
                    data.motor_axes.remove(JointAxesMask::ANG_X);
                } else {
                    set_damper(data, self.damping, joint.effort);
                }
            }
        }
        for &k in &self.driven_links {
            engine.add_force_and_torque(self.bodies[k], Vec3::ZERO, self.link_torques[k], false);
        }
    }

    /// The servo torque applied over the last step (N·m, on the child about the axis).
    fn applied_torque(&self, joint: usize, _target: f64, _rate: f64) -> f64 {
        self.torques[joint]
    }

    /// The joints' worst separation now.
    fn joint_drift(&self, engine: &Engine) -> JointDrift {
        let mut drift = JointDrift::default();
        for j in 0..self.joints.len() {
            let (parent, child) = self.world_frames(engine, j);
            let anchor = parent.translation.distance(child.translation);
            // the swing: the angle between the two frames' x axes
            let angle = parent.matrix3.x_axis.angle_between(child.matrix3.x_axis);
            drift.anchor = drift.anchor.max(anchor);
            drift.angle = drift.angle.max(angle);
        }
        drift
    }
}

/// `x.rem_euclid(TAU)` for x in [−π, 3π] (a twist angle 2·atan2(x, w) ∈ [−2π, 2π], plus π), bit
/// for bit, without the call to libm's `fmod` that `rem_euclid` makes (18 joints a step): there
/// `x % TAU` is x or, from TAU up, x − TAU, which is exact there (Sterbenz: TAU ≤ x ≤ 2·TAU).
fn wrapped(x: f64) -> f64 {
    use std::f64::consts::TAU;
    if x < 0.0 {
        x + TAU
    } else if x >= TAU {
        x - TAU
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::wrapped;
    use std::f64::consts::{PI, TAU};

    /// The same bits as `rem_euclid` over the twist angles' range, its ends and the wrap.
    #[test]
    fn wraps_as_rem_euclid_does() {
        let mut xs: Vec<f64> = (0..=200_000)
            .map(|k| -PI + 4.0 * PI * k as f64 / 200_000.0)
            .collect();
        for x in [-PI, 0.0, -0.0, TAU, 3.0 * PI] {
            xs.extend([x, x.next_down(), x.next_up()]);
        }
        for x in xs.into_iter().filter(|x| (-PI..=3.0 * PI).contains(x)) {
            assert_eq!(wrapped(x).to_bits(), x.rem_euclid(TAU).to_bits(), "{x}");
        }
        assert!(wrapped(f64::NAN).is_nan());
    }
}
