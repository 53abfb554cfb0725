//! The paper's experiment: a rigid ball dropped on a terrain, with the contact model as the only
//! ground force.
//!
//! On one face — the paper's case — the ball has one contact. In a concave corner (a riser's foot,
//! a pit's floor against its wall) it presses into each face at once, and each face is a contact
//! of its own, with its own depth, normal, damper and friction, solved together through the ball's
//! mobility ([`crate::contact::joint`]), as a robot's foot in a corner is
//! ([`super::ground_contact`]): summed into one contact, the springs' normal tilted from the floor
//! to the riser over the first millimetres and lifted the ball against a wall (V20: 60° from
//! horizontal as it met the riser).

use super::engine::{Engine, STANDARD_GRAVITY};
use super::face_slots::{Slot, SlotStates, free, match_faces};
use crate::contact::joint::{JointContact, JointSolver};
use crate::contact::{
    ContactForce, ContactModel, EffectiveMass, MAX_FACES, RollingBody, SphereGeometry, Variant,
};
use crate::limits::{Range, check_number};
use crate::terrain::HeightGrid;
use glam::{DVec3, Vec3};
use rapier3d::prelude::{MassProperties, RigidBodyBuilder, RigidBodyHandle};
use std::sync::Arc;

/// A ball's set-up. A solid sphere (I = 2/5·m·r²) unless `lock_rotation`, which makes it a
/// non-rotating foot (a sliding block with a round sole).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallConfig {
    pub radius: f64,
    pub mass: f64,
    /// Centre at start (m).
    pub position: [f64; 3],
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
    pub lock_rotation: bool,
    pub gravity: f64,
}

impl Default for BallConfig {
    /// The reference ball: r = 0.05 m, m = 1 kg, at rest.
    fn default() -> Self {
        BallConfig {
            radius: 0.05,
            mass: 1.0,
            position: [0.0, 0.0, 0.5],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            lock_rotation: false,
            gravity: STANDARD_GRAVITY,
        }
    }
}

impl BallConfig {
    /// Moment of inertia of the solid sphere about its centre.
    pub fn inertia(&self) -> f64 {
        0.4 * self.mass * self.radius * self.radius
    }

    /// Checks every field, naming the bad one.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        for (name, v) in [("radius", self.radius), ("mass", self.mass)] {
            if let Err(e) = check_number(v, Range::Positive, "") {
                return Err((name, e));
            }
        }
        check_number(self.gravity, Range::NonNegative, "").map_err(|e| ("gravity", e))?;
        for (name, v) in [
            ("position", self.position),
            ("velocity", self.velocity),
            ("angular_velocity", self.angular_velocity),
        ] {
            if v.iter().any(|c| !c.is_finite()) {
                return Err((name, format!("expected three finite numbers, got {v:?}")));
            }
        }
        Ok(())
    }
}

/// The ball's state after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallSample {
    pub step: u64,
    pub time: f64,
    pub position: DVec3,
    pub velocity: DVec3,
    pub angular_velocity: DVec3,
    /// The contact's response during the step that led here (None: in the air); in a concave
    /// corner its faces' merged ([`ContactForce::merge`]: forces summed, the deepest face's
    /// point, frame and depth).
    pub contact: Option<ContactForce>,
    /// Each face's response, the nearest first (one but in a concave corner; None past them).
    pub faces: [Option<ContactForce>; MAX_FACES],
    pub kinetic_energy: f64,
    /// m·g·z of the centre.
    pub potential_energy: f64,
    /// Energy stored in the contact spring at the current penetration.
    pub spring_energy: f64,
}

impl BallSample {
    pub fn total_energy(&self) -> f64 {
        self.kinetic_energy + self.potential_energy + self.spring_energy
    }
}

/// A ball in a rapier world over a terrain.
pub struct BallSim {
    engine: Engine,
    ball: RigidBodyHandle,
    config: BallConfig,
    terrain: Arc<HeightGrid>,
    contact: ContactModel,
    /// Each face's contact state, matched to its face from step to step (`face_slots`).
    slots: [Slot; MAX_FACES],
    solver: JointSolver,
    /// A corner's faces as the joint solver takes them (kept: a step allocates nothing).
    corner: Vec<JointContact>,
    last_faces: [Option<ContactForce>; MAX_FACES],
    step: u64,
}

fn to_f64(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

impl BallSim {
    pub fn new(
        config: BallConfig,
        terrain: Arc<HeightGrid>,
        contact: ContactModel,
        dt: f64,
    ) -> Self {
        let mut engine = Engine::new(dt, config.gravity, 1, 1, 1);
        let inertia = config.inertia() as f32;
        let mut builder = RigidBodyBuilder::dynamic()
            .translation(DVec3::from(config.position).as_vec3())
            .linvel(DVec3::from(config.velocity).as_vec3())
            .angvel(DVec3::from(config.angular_velocity).as_vec3())
            .additional_mass_properties(MassProperties::new(
                Vec3::ZERO,
                config.mass as f32,
                Vec3::splat(inertia),
            ))
            .can_sleep(false)
            .allow_fast_rotation(true)
            // A uniform sphere's inertia is isotropic: ω × I·ω = 0, no gyroscopic torque. rapier's
            // gyroscopic pass (on by default) still maps ω through I and I⁻¹ in f32 each step, and
            // their rounding grew a free spin by an ulp a step (+0.082 % in 10 s at 10 rad/s, V17)
            .gyroscopic_forces_enabled(false);
        if config.lock_rotation {
            builder = builder.lock_rotations();
        }
        let ball = engine.bodies.insert(builder.build());
        BallSim {
            engine,
            ball,
            config,
            terrain,
            contact,
            slots: [Slot::default(); MAX_FACES],
            solver: JointSolver::default(),
            corner: Vec::with_capacity(MAX_FACES),
            last_faces: [None; MAX_FACES],
            step: 0,
        }
    }

    pub fn dt(&self) -> f64 {
        self.engine.dt()
    }

    pub fn terrain(&self) -> &HeightGrid {
        &self.terrain
    }

    pub fn config(&self) -> &BallConfig {
        &self.config
    }

    /// Computes the ground force for the current state, applies it, and advances one step.
    pub fn step(&mut self) -> BallSample {
        let dt = self.dt();
        let body = &self.engine.bodies[self.ball];
        let center = to_f64(body.translation());
        let velocity = to_f64(body.linvel());
        let angular_velocity = to_f64(body.angvel());
        let radius = self.config.radius;
        let all = self.contact.sphere_faces(&self.terrain, center, radius);
        let faces = all.as_slice();
        let mut responses = [None; MAX_FACES];
        let mut rolling = DVec3::ZERO;
        if self.contact.variant == Variant::Paper {
            // the paper's: one contact, the centre's velocity, the force at the centre (no spin)
            responses[0] = self.contact.respond_paper(
                &all.summed(center, radius),
                velocity,
                self.config.mass,
                dt,
                &mut self.slots[0].state,
            );
        } else if faces[0].penetration <= 0.0 {
            free(&mut self.slots);
        } else {
            let ids = match_faces(&mut self.slots, faces);
            // rolling resistance and spin friction act on one contact: a corner under them keeps
            // its faces' springs summed into one
            let torques = self.contact.rolling_resistance > 0.0 || self.contact.spin_friction > 0.0;
            let motion = (center, velocity, angular_velocity);
            if faces.len() == 1 || torques {
                let geometry = all.summed(center, radius);
                (responses[0], rolling) = self.respond_alone(&geometry, motion, ids[0]);
            } else {
                self.respond_jointly(faces, motion, &ids, &mut responses);
            }
        }
        // through the set, not `bodies[ball]`: a body indexed mutably is marked modified, which
        // costs rapier work in the step
        let bodies = &mut self.engine.bodies;
        bodies.reset_forces_and_torques(self.ball);
        if responses[0].is_some() {
            // Force and torque about our own centre: rapier's `add_force_at_point` measures the arm
            // from its world centre of mass, which is not computed until the first step.
            let (mut force, mut torque) = (DVec3::ZERO, rolling);
            for c in responses.iter().flatten() {
                force += c.force;
                torque += (c.point - center).cross(c.force);
            }
            bodies.add_force_and_torque(self.ball, force.as_vec3(), torque.as_vec3(), true);
        }
        self.engine.step();
        self.step += 1;
        self.last_faces = responses;
        self.sample()
    }

    /// The force of one contact, its state in slot `slot` (and the rolling resistance's and spin
    /// friction's torque); `motion`: the ball's centre, velocity and angular velocity.
    fn respond_alone(
        &mut self,
        geometry: &SphereGeometry,
        (center, velocity, angular_velocity): (DVec3, DVec3, DVec3),
        slot: usize,
    ) -> (Option<ContactForce>, DVec3) {
        let dt = self.engine.dt();
        let state = &mut self.slots[slot].state;
        let arm = geometry.point - center;
        let point_velocity = velocity + angular_velocity.cross(arm);
        if self.config.lock_rotation {
            let mass = EffectiveMass::particle(self.config.mass);
            let response = self
                .contact
                .respond(geometry, point_velocity, &mass, dt, state);
            return (response, DVec3::ZERO);
        }
        let body = RollingBody {
            mass: self.config.mass,
            inertia: self.config.inertia(),
            arm: -arm,
            angular_velocity,
        };
        match self
            .contact
            .respond_rolling(geometry, point_velocity, &body, dt, state)
        {
            Some((c, rolling)) => (Some(c), rolling),
            None => (None, DVec3::ZERO),
        }
    }

    /// The forces of the faces of a concave corner, solved together through the ball's mobility:
    /// a unit impulse b at face j's point moves face i's point by
    /// W_ij(a, b) = a·b/m + (r_i × a)·I⁻¹·(r_j × b), r the arms from the centre (the rotation's
    /// part left out for a ball that does not turn).
    fn respond_jointly(
        &mut self,
        faces: &[SphereGeometry],
        (center, velocity, angular_velocity): (DVec3, DVec3, DVec3),
        ids: &[usize; MAX_FACES],
        out: &mut [Option<ContactForce>; MAX_FACES],
    ) {
        let (mass, locked) = (self.config.mass, self.config.lock_rotation);
        let inverse_inertia = if locked {
            0.0
        } else {
            1.0 / self.config.inertia()
        };
        let spin = if locked {
            DVec3::ZERO
        } else {
            angular_velocity
        };
        let n = faces.len();
        self.corner.clear();
        self.corner.extend(faces.iter().map(|face| JointContact {
            geometry: *face,
            velocity: velocity + spin.cross(face.point - center),
            sharing: n,
        }));
        let mobility = |i: usize, j: usize| {
            let (fi, fj) = (&faces[i].frame, &faces[j].frame);
            let (ri, rj) = (faces[i].point - center, faces[j].point - center);
            let w = |a: DVec3, b: DVec3| {
                a.dot(b) / mass + ri.cross(a).dot(rj.cross(b)) * inverse_inertia
            };
            let column =
                |b: DVec3| DVec3::new(w(fi.tangent_x, b), w(fi.tangent_y, b), w(fi.normal, b));
            glam::DMat3::from_cols(
                column(fj.tangent_x),
                column(fj.tangent_y),
                column(fj.normal),
            )
        };
        let mut states = SlotStates {
            slots: &mut self.slots,
            ids: &ids[..n],
        };
        self.solver.respond(
            &self.contact,
            &self.corner,
            mobility,
            self.engine.dt(),
            &mut states,
            &mut out[..n],
        );
    }

    /// The current state.
    pub fn sample(&self) -> BallSample {
        let body = &self.engine.bodies[self.ball];
        let position = to_f64(body.translation());
        let velocity = to_f64(body.linvel());
        let angular_velocity = if self.config.lock_rotation {
            DVec3::ZERO
        } else {
            to_f64(body.angvel())
        };
        let c = &self.config;
        let kinetic_energy = 0.5 * c.mass * velocity.length_squared()
            + 0.5 * c.inertia() * angular_velocity.length_squared();
        // each face's spring (one but in a corner; its depth ≤ 0 clear of the ground)
        let faces = self.contact.sphere_faces(&self.terrain, position, c.radius);
        let spring_energy = match faces.as_slice() {
            [one] => self.contact.normal.stored_energy(one.penetration),
            several => several
                .iter()
                .map(|g| self.contact.normal.stored_energy(g.penetration))
                .sum(),
        };
        let mut faces = self.last_faces.iter().flatten();
        let contact = faces.next().map(|first| {
            let mut merged = *first;
            faces.for_each(|other| merged.merge(other));
            merged
        });
        BallSample {
            step: self.step,
            time: self.step as f64 * self.dt(),
            position,
            velocity,
            angular_velocity,
            contact,
            faces: self.last_faces,
            kinetic_energy,
            potential_energy: c.mass * c.gravity * position.z,
            spring_energy,
        }
    }
}
