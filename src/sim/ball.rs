//! The paper's experiment: a rigid ball dropped on a terrain, with the contact model as the only
//! ground force.

use super::engine::{Engine, STANDARD_GRAVITY};
use crate::contact::{
    ContactForce, ContactModel, ContactState, EffectiveMass, RollingBody, Variant,
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
    /// The contact's response during the step that led here (None: in the air).
    pub contact: Option<ContactForce>,
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
    contact_state: ContactState,
    last_contact: Option<ContactForce>,
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
            contact_state: ContactState::default(),
            last_contact: None,
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
        let geometry = self
            .contact
            .sphere_geometry(&self.terrain, center, self.config.radius);
        let response = if self.contact.variant == Variant::Paper {
            // the paper's: the centre's velocity, the force at the centre (no spin)
            self.contact
                .respond_paper(
                    &geometry,
                    velocity,
                    self.config.mass,
                    dt,
                    &mut self.contact_state,
                )
                .map(|c| (c, DVec3::ZERO))
        } else if geometry.penetration > 0.0 {
            let arm = geometry.point - center;
            let point_velocity = velocity + angular_velocity.cross(arm);
            if self.config.lock_rotation {
                let mass = EffectiveMass::particle(self.config.mass);
                self.contact
                    .respond(
                        &geometry,
                        point_velocity,
                        &mass,
                        dt,
                        &mut self.contact_state,
                    )
                    .map(|c| (c, DVec3::ZERO))
            } else {
                let body = RollingBody {
                    mass: self.config.mass,
                    inertia: self.config.inertia(),
                    arm: -arm,
                    angular_velocity,
                };
                self.contact.respond_rolling(
                    &geometry,
                    point_velocity,
                    &body,
                    dt,
                    &mut self.contact_state,
                )
            }
        } else {
            self.contact
                .respond(
                    &geometry,
                    DVec3::ZERO,
                    &EffectiveMass::particle(1.0),
                    dt,
                    &mut self.contact_state,
                )
                .map(|c| (c, DVec3::ZERO))
        };
        // through the set, not `bodies[ball]`: a body indexed mutably is marked modified, which
        // costs rapier work in the step
        let bodies = &mut self.engine.bodies;
        bodies.reset_forces_and_torques(self.ball);
        if let Some((c, rolling)) = &response {
            // Force and torque about our own centre: rapier's `add_force_at_point` measures the arm
            // from its world centre of mass, which is not computed until the first step.
            let torque = (c.point - center).cross(c.force) + *rolling;
            bodies.add_force_and_torque(self.ball, c.force.as_vec3(), torque.as_vec3(), true);
        }
        self.engine.step();
        self.step += 1;
        self.last_contact = response.map(|(c, _)| c);
        self.sample()
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
        let geometry = self
            .contact
            .sphere_geometry(&self.terrain, position, c.radius);
        BallSample {
            step: self.step,
            time: self.step as f64 * self.dt(),
            position,
            velocity,
            angular_velocity,
            contact: self.last_contact,
            kinetic_energy,
            potential_energy: c.mass * c.gravity * position.z,
            spring_energy: self.contact.normal.stored_energy(geometry.penetration),
        }
    }
}
