//! The hexapod in rapier: the URDF model's links as rigid bodies, joined either as one
//! reduced-coordinate multibody ([`Articulation::Multibody`], the default; see `multibody`) or by
//! impulse joints ([`Articulation::Impulse`], faster, the joints drift a little; see `impulse`),
//! with servos at every joint and the paper's contact model under each foot as the only ground force.
//!
//! - Links carry no colliders: rapier computes no contacts at all (neither with the ground nor
//!   between links). Each step, the force from [`crate::contact`] on each foot and on every other
//!   link's contact spheres that touch the terrain is applied to its link (`ground_contact`).
//! - Servos follow the implicit PD law in physical units, τ = k·(q* − q) − d·q̇, limited to the
//!   URDF's `effort`; the sample carries the torque actually applied.
//! - Nothing sleeps.

use super::articulation::{
    Articulation, ContactPoint, JointDrift, Joints, ServoGains, affine_of, pose_of,
};
use super::engine::{Engine, STANDARD_GRAVITY};
use super::ground_contact::GroundContacts;
pub use super::ground_contact::LinkContact;
use super::ringing::Ringing;
use crate::contact::{ContactForce, ContactModel};
use crate::robot::RobotModel;
use crate::terrain::{FittedPlane, GroundFrame, HeightGrid, Orientation};
use glam::{DAffine3, DMat3, DQuat, DVec3};
use rapier3d::prelude::{MassProperties, RigidBodyBuilder, RigidBodyHandle};
use std::sync::Arc;

/// Steps between two measurements of the impulse joints' drift (it changes slowly).
const DRIFT_EVERY: u64 = 10;

/// rapier substeps per step by default: one — V1–V21 hold with it (those met: docs/validation.md) (see docs/performance.md), and
/// each substep rebuilds the multibody's mass matrix.
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
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Placement {
    /// Body x, y (m) and heading (rad).
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
    pub attitude: Attitude,
}

/// How the body is set down.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Attitude {
    /// Level, whatever the ground: on a slope the uphill feet touch first and the body falls
    /// onto the others (0.26 m on 30° for hex18).
    #[default]
    Level,
    /// Parallel to the ground under it — the plane through the terrain under the feet, fitted by
    /// least squares — as a robot put down on a slope stands: every foot touches at once.
    Ground,
}

/// The robot's state after a step.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HexapodSample {
    pub step: u64,
    pub time: f64,
    /// The body (root link) frame in the world.
    pub body: DAffine3,
    /// Height of the hips' plane above the terrain under it (m): the point of the body on its z
    /// axis at the hips' mean height (`RobotModel::hips_plane`), which is what a gait's stance
    /// height sets (hex18's base link origin; a URDF may put its base link's origin anywhere,
    /// e.g. on the ground under the body).
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
    /// The other links' touching contact spheres (shins, knees, the belly), in link order.
    pub link_contacts: Vec<LinkContact>,
    /// How far apart the joints have come (zero for the multibody; measured every 10 steps).
    pub joint_drift: JointDrift,
    /// The first joint that rang at the step rate, its foot off the ground, and when it began
    /// (s): its servo oversteps at this step ([`super::ringing`]). None while none has.
    pub servo_ringing: Option<(f64, usize)>,
}

impl HexapodSample {
    /// Roll, pitch, yaw (rad) of the body, z-y-x convention.
    ///
    /// glam's `to_euler(EulerRot::ZYX)` (its rotation matrix `DMat3::from_quat`, then the angles
    /// of any order read by index) written out for this order: the entries it reads, the same
    /// products, sums and arc tangents, bit for bit (a unit test), without the rest of the matrix
    /// (the walk's metrics read it every step).
    pub fn roll_pitch_yaw(&self) -> (f64, f64, f64) {
        let q = self.body_rotation;
        let (x2, y2, z2) = (q.x + q.x, q.y + q.y, q.z + q.z);
        let (xx, xy, xz) = (q.x * x2, q.x * y2, q.x * z2);
        let (yy, yz, zz) = (q.y * y2, q.y * z2, q.z * z2);
        let (wx, wy, wz) = (q.w * x2, q.w * y2, q.w * z2);
        // the matrix's x axis, and its y and z axes' z entries
        let (x_x, x_y, x_z) = (1.0 - (yy + zz), xy + wz, xz - wy);
        let (y_z, z_z) = (yz + wx, 1.0 - (xx + yy));
        let cy = (z_z * z_z + y_z * y_z).sqrt();
        let pitch = (-x_z).atan2(cy);
        if cy > 16.0 * f64::EPSILON {
            (y_z.atan2(z_z), pitch, x_y.atan2(x_x))
        } else {
            // pitched a quarter turn: the yaw from the y axis, no roll
            let (y_x, y_y) = (xy - wz, 1.0 - (xx + zz));
            (0.0, pitch, (-y_x).atan2(y_y))
        }
    }
}

pub struct Hexapod {
    engine: Engine,
    model: Arc<RobotModel>,
    terrain: Arc<HeightGrid>,
    contact: ContactModel,
    /// rapier body per model link
    bodies: Vec<RigidBodyHandle>,
    joints: Box<dyn Joints>,
    /// the root's rapier frame is the base link frame shifted to its centre of mass
    root_com: DVec3,
    /// The hips' plane's centre in the body frame (see [`HexapodSample::body_height`]).
    hips_centre: DVec3,
    targets: Vec<f64>,
    /// Joint angles and rates now (read once per step: both the servos and the sample use them).
    angles: Vec<f64>,
    rates: Vec<f64>,
    /// The joints' drift, measured every [`DRIFT_EVERY`] steps (impulse joints).
    drift: JointDrift,
    /// Watches the joints' rates for a servo ringing at the step rate.
    ringing: Ringing,
    ground: GroundContacts,
    last_contacts: [Option<ContactForce>; 6],
    last_link_contacts: Vec<LinkContact>,
    /// Every link's world pose as the last step left it ([`Hexapod::place_frames`]).
    frames: Vec<DAffine3>,
    step: u64,
    /// Wall-clock seconds spent inside rapier's step (see [`Hexapod::physics_seconds`]).
    physics_seconds: f64,
}

impl Hexapod {
    /// Builds the robot standing at `placement` with joint angles `pose` (per model joint), its
    /// lowest point (a foot, or any link's contact sphere) just touching the terrain.
    pub fn new(
        model: Arc<RobotModel>,
        terrain: Arc<HeightGrid>,
        contact: ContactModel,
        settings: HexapodSettings,
        placement: Placement,
        pose: &[f64],
    ) -> Self {
        Self::dropped(model, terrain, contact, settings, placement, pose, 0.0)
    }

    /// [`Hexapod::new`] with the robot's lowest point `height` (m) above the terrain: dropped.
    pub fn dropped(
        model: Arc<RobotModel>,
        terrain: Arc<HeightGrid>,
        contact: ContactModel,
        settings: HexapodSettings,
        placement: Placement,
        pose: &[f64],
        height: f64,
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
        if settings.articulation == Articulation::Multibody {
            engine.track_forces();
        }
        // body height: each foot and every link's contact sphere above the ground under it
        let link_poses = model.link_poses(pose);
        let heading = match placement.attitude {
            Attitude::Level => DQuat::from_rotation_z(placement.yaw),
            Attitude::Ground => {
                let level = DQuat::from_rotation_z(placement.yaw);
                let feet: Vec<DVec3> = model
                    .legs
                    .iter()
                    .map(|leg| level * link_poses[leg.foot_link].transform_point3(leg.foot.center))
                    .collect();
                ground_tilt(&terrain, placement.x, placement.y, &feet) * level
            }
        };
        let spheres: Vec<(DVec3, f64)> =
            model
                .legs
                .iter()
                .map(|leg| (leg.foot_link, leg.foot.center, leg.foot.radius))
                .chain(model.links.iter().enumerate().flat_map(|(k, link)| {
                    link.contacts.iter().map(move |c| (k, c.center, c.radius))
                }))
                .map(|(link, center, radius)| {
                    (heading * link_poses[link].transform_point3(center), radius)
                })
                .collect();
        // each sphere its radius above the ground under its centre, then lifted out of the ground
        // along the normal where that leaves it in (on a slope a sphere its radius above the
        // ground vertically sinks r·(1 − cos θ) into it: 1.3 mm on 30°)
        let mut body_z = spheres
            .iter()
            .map(|(p, r)| terrain.height(placement.x + p.x, placement.y + p.y) + r - p.z)
            .fold(f64::NEG_INFINITY, f64::max);
        let lift = spheres
            .iter()
            .map(|(p, r)| {
                let center = DVec3::new(placement.x + p.x, placement.y + p.y, body_z + p.z);
                let g = crate::contact::sphere_geometry(&terrain, center, *r, Orientation::Exact);
                g.penetration.max(0.0) / g.frame.normal.z.max(0.1)
            })
            .fold(0.0, f64::max);
        body_z += lift;
        let body = DAffine3::from_rotation_translation(
            heading,
            DVec3::new(placement.x, placement.y, body_z + 1e-3 + height),
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
        engine.update_mass_properties();
        let joints = settings.articulation.build(
            &mut engine,
            &model,
            &bodies,
            root_com,
            pose,
            settings.gains,
        );
        let n = model.joints.len();
        let hips_centre = DVec3::new(0.0, 0.0, model.hips_plane());
        let ground = GroundContacts::new(&model, &terrain);
        let ringing = Ringing::new(&model);
        let mut hexapod = Hexapod {
            engine,
            model,
            terrain,
            contact,
            bodies,
            joints,
            root_com,
            hips_centre,
            targets: pose.to_vec(),
            angles: vec![0.0; n],
            rates: vec![0.0; n],
            drift: JointDrift::default(),
            ringing,
            ground,
            last_contacts: [None; 6],
            last_link_contacts: Vec::new(),
            frames: Vec::new(),
            step: 0,
            physics_seconds: 0.0,
        };
        hexapod.read_joints();
        hexapod.place_frames();
        if settings.articulation == Articulation::Impulse {
            // the feet's normal dampers move the articulated robot, as in the multibody
            let mut reference = Hexapod::new(
                hexapod.model.clone(),
                hexapod.terrain.clone(),
                contact,
                HexapodSettings {
                    articulation: Articulation::Multibody,
                    ..settings
                },
                placement,
                pose,
            );
            // its mass matrix as a step augments it (the servos' implicit springs and dampers)
            reference.step();
            let masses: Vec<(usize, f64)> = hexapod
                .model
                .legs
                .iter()
                .zip(reference.foot_normal_masses())
                .map(|(leg, mass)| (leg.foot_link, mass))
                .collect();
            hexapod.joints.set_damper_masses(&masses);
        }
        hexapod
    }

    /// Each foot's effective mass along the vertical at its lowest point, 1/W_nn, as the contact
    /// model sees it now (the articulated robot's in the multibody).
    pub fn foot_normal_masses(&mut self) -> [f64; 6] {
        self.foot_masses_along(DVec3::Z)
    }

    /// Each foot's effective mass along the unit `normal` at the point of its sphere the ground
    /// would touch there (1/W_nn, as [`Self::foot_normal_masses`]): a wall's normal is level.
    pub fn foot_masses_along(&mut self, normal: DVec3) -> [f64; 6] {
        let mut masses = [0.0; 6];
        for (k, leg) in self.model.legs.iter().enumerate() {
            let frame = self.link_frame(leg.foot_link);
            let point = [ContactPoint {
                link: leg.foot_link,
                body: self.bodies[leg.foot_link],
                point: frame.transform_point3(leg.foot.center) - normal * leg.foot.radius,
                com: frame.transform_point3(self.model.links[leg.foot_link].com),
                frame: GroundFrame::from_normal(normal),
            }];
            let mut velocity = [DVec3::ZERO];
            let mut mobility = [DMat3::ZERO];
            self.joints
                .contact_mobility(&self.engine, &point, &mut velocity, &mut mobility);
            masses[k] = 1.0 / mobility[0].z_axis.z;
        }
        masses
    }

    /// Reads every joint's angle and rate from rapier.
    fn read_joints(&mut self) {
        self.joints
            .read_joints(&self.engine, &mut self.angles, &mut self.rates);
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
        self.joints.articulation()
    }

    /// The servos' gains.
    pub fn gains(&self) -> ServoGains {
        self.joints.gains()
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
        self.frames.clone()
    }

    /// Wall-clock seconds spent inside rapier's step so far. The rest of a step is hexsim's
    /// (contacts, servos, gait): the benchmark reports the split, so a figure can be read against
    /// what rapier alone would allow.
    pub fn physics_seconds(&self) -> f64 {
        self.physics_seconds
    }

    /// How far apart the joints have come (always zero for the multibody).
    pub fn joint_drift(&self) -> JointDrift {
        self.joints.joint_drift(&self.engine)
    }

    /// World pose of a model link's frame (as the last step left it: [`Self::place_frames`]).
    fn link_frame(&self, link: usize) -> DAffine3 {
        self.frames[link]
    }

    /// Every link's world pose, read from rapier's bodies: once the robot is built and after
    /// each step, so that the step's contacts, its sample and the gait read them without
    /// converting rapier's poses again (only a step moves the bodies).
    fn place_frames(&mut self) {
        let mut frames = std::mem::take(&mut self.frames);
        frames.clear();
        frames.extend((0..self.model.links.len()).map(|k| self.frame_of(k)));
        self.frames = frames;
    }

    /// World pose of a model link's frame, from its rapier body.
    fn frame_of(&self, link: usize) -> DAffine3 {
        let pose = affine_of(self.engine.bodies[self.bodies[link]].position());
        if link == 0 {
            pose * DAffine3::from_translation(-self.root_com)
        } else {
            pose
        }
    }

    /// Computes each foot's ground force, applies it with the servos', and advances one step.
    pub fn step(&mut self) -> HexapodSample {
        let mut sample = HexapodSample::default();
        self.step_into(&mut sample);
        sample
    }

    /// [`Hexapod::step`], written over `sample` (an earlier one no longer read) in place: its
    /// vectors (joint angles, rates, targets, torques, link contacts) are reused, not
    /// allocated, and the sample is not copied: the step loop hands each step the last one's.
    pub fn step_into(&mut self, sample: &mut HexapodSample) {
        // not `bodies[h]`: a body indexed mutably is marked modified, and rapier then redoes its
        // island, mass and (impulse joints) joint layout work in the step
        self.engine.reset_forces(&self.bodies);
        self.joints
            .drive(&mut self.engine, &self.targets, &self.angles, &self.rates);
        let frames = std::mem::take(&mut self.frames);
        // the feet's forces written over the last step's in place (nothing reads those again)
        self.ground.apply(
            &mut self.engine,
            self.joints.as_mut(),
            &self.model,
            &self.bodies,
            &self.terrain,
            &self.contact,
            &frames,
            &mut self.last_link_contacts,
            &mut self.last_contacts,
        );
        self.frames = frames;
        let started = std::time::Instant::now();
        self.engine.step();
        self.physics_seconds += started.elapsed().as_secs_f64();
        self.step += 1;
        self.read_joints();
        self.place_frames();
        if self.step.is_multiple_of(DRIFT_EVERY) {
            self.drift = self.joint_drift();
        }
        let time = self.time();
        self.ringing
            .update(time, self.engine.dt(), &self.rates, &self.last_contacts);
        self.sample_into(sample);
    }

    /// The current state.
    pub fn sample(&self) -> HexapodSample {
        let mut sample = HexapodSample::default();
        self.sample_into(&mut sample);
        sample
    }

    /// [`Hexapod::sample`] written over `sample`, its vectors reused.
    fn sample_into(&self, sample: &mut HexapodSample) {
        let copy = |into: &mut Vec<f64>, from: &[f64]| {
            into.clear();
            into.extend_from_slice(from);
        };
        copy(&mut sample.joint_angles, &self.angles);
        copy(&mut sample.joint_velocities, &self.rates);
        copy(&mut sample.joint_targets, &self.targets);
        sample.joint_torques.clear();
        let n = self.model.joints.len();
        self.joints.applied_torques(
            &self.targets[..n],
            &self.rates[..n],
            &mut sample.joint_torques,
        );
        sample.link_contacts.clear();
        sample
            .link_contacts
            .extend_from_slice(&self.last_link_contacts);
        let (v_com, omega) = self.joints.base_velocity(&self.engine);
        let body = self.link_frame(0);
        let com_offset = body.matrix3 * self.root_com;
        let mut foot_positions = [DVec3::ZERO; 6];
        for (k, leg) in self.model.legs.iter().enumerate() {
            foot_positions[k] = self
                .link_frame(leg.foot_link)
                .transform_point3(leg.foot.center);
        }
        sample.step = self.step;
        sample.time = self.time();
        sample.body_height = {
            let hips = body.transform_point3(self.hips_centre);
            hips.z - self.terrain.height(hips.x, hips.y)
        };
        sample.body = body;
        sample.body_rotation = DQuat::from_mat3(&body.matrix3).normalize();
        sample.body_velocity = v_com - omega.cross(com_offset);
        sample.body_angular_velocity = omega;
        sample.foot_positions = foot_positions;
        sample.foot_contacts = self.last_contacts;
        sample.joint_drift = self.drift;
        sample.servo_ringing = self.ringing.rang();
    }
}

/// The rotation that turns the vertical into the normal of the plane fitted by least squares to
/// the terrain under `feet` (offsets from the body at `x`, `y`): the shortest arc, so the heading
/// is kept. Level for fewer than three feet or feet in a line.
fn ground_tilt(terrain: &HeightGrid, x: f64, y: f64, feet: &[DVec3]) -> DQuat {
    let ground: Vec<DVec3> = feet
        .iter()
        .map(|p| DVec3::new(p.x, p.y, terrain.height(x + p.x, y + p.y)))
        .collect();
    DQuat::from_rotation_arc(DVec3::Z, FittedPlane::fit(&ground).normal())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::fit;

    fn standing(articulation: Articulation) -> Hexapod {
        let model = Arc::new(crate::robot::hex18_for_tests());
        let spec = crate::gait::tripod_for_tests();
        let pose = fit(&model, &spec).unwrap().standing_pose;
        let ground = Arc::new(crate::terrain::flat([2.0, 2.0], [0.0, 0.0], 0.0).unwrap());
        Hexapod::new(
            model,
            ground,
            ContactModel::default(),
            HexapodSettings {
                articulation,
                ..HexapodSettings::default()
            },
            Placement::default(),
            &pose,
        )
    }

    /// A foot's normal damper moves the articulated robot in both articulations: with impulse
    /// joints the damping uses the multibody's effective mass (in the starting pose, after a
    /// step), not the foot link's alone, which is much lighter — so the same c damps the same.
    #[test]
    fn feet_are_damped_with_the_articulated_robots_mass_in_both_articulations() {
        // the multibody's after a step, whose mass matrix carries the servos as a step does
        let mut multibody = standing(Articulation::Multibody);
        multibody.step();
        let multibody = multibody.foot_normal_masses();
        let mut impulse = standing(Articulation::Impulse);
        let link_alone: Vec<f64> = {
            let model = impulse.model.clone();
            model
                .legs
                .iter()
                .map(|l| model.links[l.foot_link].mass)
                .collect()
        };
        let impulse = impulse.foot_normal_masses();
        for k in 0..6 {
            assert!(
                (impulse[k] - multibody[k]).abs() < 1e-9 * multibody[k],
                "foot {k}: impulse {} kg, multibody {} kg",
                impulse[k],
                multibody[k]
            );
            // the articulated mass is well above the foot link's own (0.05 kg on hex18)
            assert!(
                multibody[k] > 1.2 * link_alone[k],
                "foot {k}: {} kg against the link's {} kg",
                multibody[k],
                link_alone[k]
            );
        }
    }

    /// The body's roll, pitch and yaw are glam's z-y-x Euler angles of its rotation, bit for
    /// bit, the quarter-turn pitches (where the yaw is read off the y axis) among them.
    #[test]
    fn roll_pitch_yaw_is_glams_zyx_euler_angles() {
        let mut uniform = crate::test_rng::uniform(0x51_7cc1_b727_220a);
        let mut next = || uniform() * 2.0 - 1.0;
        let mut rotations: Vec<DQuat> = (0..20_000)
            .map(|_| DQuat::from_xyzw(next(), next(), next(), next()).normalize())
            .collect();
        for k in 0..2000 {
            let (yaw, roll) = (3.0 * next(), 3.0 * next());
            let pitch = std::f64::consts::FRAC_PI_2 * (1.0 - 1e-9 * k as f64) * next().signum();
            rotations.push(DQuat::from_euler(glam::EulerRot::ZYX, yaw, pitch, roll));
        }
        rotations.extend([DQuat::IDENTITY, DQuat::from_xyzw(0.0, 1.0, 0.0, 0.0)]);
        let mut quarter_turns = 0;
        for q in rotations {
            let m = DMat3::from_quat(q);
            let cy = (m.z_axis.z * m.z_axis.z + m.y_axis.z * m.y_axis.z).sqrt();
            quarter_turns += usize::from(cy <= 16.0 * f64::EPSILON);
            let sample = HexapodSample {
                body_rotation: q,
                ..HexapodSample::default()
            };
            let (yaw, pitch, roll) = q.to_euler(glam::EulerRot::ZYX);
            let bits = |(a, b, c): (f64, f64, f64)| [a.to_bits(), b.to_bits(), c.to_bits()];
            assert_eq!(
                bits(sample.roll_pitch_yaw()),
                bits((roll, pitch, yaw)),
                "{q:?}"
            );
        }
        assert!(quarter_turns > 0, "no quarter-turn pitch tried");
    }

    /// A free contact slot holds the default state (what `ground_contact::free` takes, writing
    /// only the slots taken): a leg lifted off the ground and set down again, over and over.
    #[test]
    fn free_contact_slots_hold_the_default_state() {
        for articulation in [Articulation::Multibody, Articulation::Impulse] {
            let mut hexapod = standing(articulation);
            let start = hexapod.targets.clone();
            let mut targets = start.clone();
            let (femur, knee) = (
                hexapod.model.legs[0].joints[1],
                hexapod.model.legs[0].joints[2],
            );
            let mut touched = [false; 2];
            for step in 0..1500 {
                let swing = (step as f64 * 0.01).sin();
                targets[femur] = start[femur] + 0.6 * swing;
                targets[knee] = start[knee] - 0.6 * swing;
                hexapod.set_targets(&targets);
                let sample = hexapod.step();
                touched[sample.foot_contacts[0].is_some() as usize] = true;
                assert!(hexapod.ground.free_slots_are_default(), "step {step}");
            }
            assert_eq!(touched, [true; 2], "the foot lifted and touched down");
        }
    }

    /// Against a wall an impulse foot's damper moves at most 1.8 free foot links along the
    /// wall's normal (`DAMPER_FREE_MASSES`): pushed sideways a tibia turns on its joints, which
    /// pass nothing on within the step, and with the vertical's articulated mass there the
    /// damper's impulse changed the foot's velocity by three times itself (hex18 in a 2 cm gap
    /// diverged at 0.5 ms). On the flat the bound does not bite: the vertical's stays.
    #[test]
    fn an_impulse_foot_against_a_wall_is_damped_as_the_free_link_it_is() {
        let mut multibody = standing(Articulation::Multibody);
        multibody.step();
        let vertical = multibody.foot_normal_masses();
        let mut impulse = standing(Articulation::Impulse);
        assert_eq!(impulse.foot_normal_masses(), vertical);
        let wall = DVec3::X;
        let against_wall = impulse.foot_masses_along(wall);
        for (k, leg) in impulse.model.legs.clone().iter().enumerate() {
            // the free link's own mass along the wall's normal, 1/(1/m + |r × n|²·…)
            let link = &impulse.model.links[leg.foot_link];
            let frame = impulse.link_frame(leg.foot_link);
            let arm = frame.matrix3 * (leg.foot.center - link.com) - wall * leg.foot.radius;
            let inverse_inertia =
                frame.matrix3 * link.inertia.inverse() * frame.matrix3.transpose();
            let turn = arm.cross(wall);
            let free = 1.0 / (1.0 / link.mass + turn.dot(inverse_inertia * turn));
            assert!(
                (against_wall[k] - 1.8 * free).abs() < 1e-9 * free,
                "foot {k}: {} kg against a wall, free link {free} kg",
                against_wall[k]
            );
            assert!(
                against_wall[k] < 0.6 * vertical[k],
                "foot {k}: {} kg against {} kg",
                against_wall[k],
                vertical[k]
            );
        }
    }

    /// The contact mobility is there from the start: a foot that touches before the first step
    /// (a robot placed on a steep slope) gets a finite effective mass, not the NaN of a mass
    /// matrix factorised before rapier had computed the bodies' mass properties.
    #[test]
    fn feet_have_a_finite_effective_mass_before_the_first_step() {
        for articulation in [Articulation::Multibody, Articulation::Impulse] {
            let masses = standing(articulation).foot_normal_masses();
            assert!(
                masses.iter().all(|m| m.is_finite() && *m > 0.0),
                "{articulation:?}: {masses:?}"
            );
        }
    }
}
