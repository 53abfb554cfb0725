//! The rapier world: the sets rapier needs, stepped with gravity along −z. Bodies carry no colliders,
//! so rapier computes no contacts; the ground forces are ours (see `contact`).

use rapier3d::math::{AngVector, Vector};
use rapier3d::prelude::{
    BroadPhaseBvh, CCDSolver, ColliderSet, ImpulseJointSet, IntegrationParameters, IslandManager,
    MultibodyJointSet, NarrowPhase, PhysicsPipeline, RigidBodyHandle, RigidBodySet, SoftBodySet,
};

/// Standard gravity, m/s² (the reference's g).
pub const STANDARD_GRAVITY: f64 = 9.81;

/// rapier's sets and pipeline, owned together.
pub struct Engine {
    pub bodies: RigidBodySet,
    pub multibody_joints: MultibodyJointSet,
    pub impulse_joints: ImpulseJointSet,
    colliders: ColliderSet,
    soft_bodies: SoftBodySet,
    islands: IslandManager,
    broad_phase: BroadPhaseBvh,
    narrow_phase: NarrowPhase,
    ccd: CCDSolver,
    pipeline: PhysicsPipeline,
    params: IntegrationParameters,
    gravity: Vector,
    /// The step in f64, so times computed from step indices are exact multiples of it.
    dt: f64,
    /// Where tracked ([`Engine::track_forces`]), the bodies given a force or torque through
    /// [`Engine::add_force_and_torque`] since [`Engine::reset_forces`] last cleared them.
    forced: Option<Vec<RigidBodyHandle>>,
}

impl Engine {
    /// A world stepping `dt` seconds with `solver_iterations` substeps per step,
    /// `pgs_iterations` sweeps of the constraint solver per substep, and
    /// `stabilization_iterations` bias-free sweeps after them (rapier's default: 1).
    pub fn new(
        dt: f64,
        gravity: f64,
        solver_iterations: usize,
        pgs_iterations: usize,
        stabilization_iterations: usize,
    ) -> Self {
        let params = IntegrationParameters {
            dt: dt as f32,
            num_solver_iterations: solver_iterations,
            // no colliders, so no CCD either
            max_ccd_substeps: 0,
            num_internal_pgs_iterations: pgs_iterations,
            num_internal_stabilization_iterations: stabilization_iterations,
            ..IntegrationParameters::default()
        };
        Engine {
            bodies: RigidBodySet::new(),
            multibody_joints: MultibodyJointSet::new(),
            impulse_joints: ImpulseJointSet::new(),
            colliders: ColliderSet::new(),
            soft_bodies: SoftBodySet::new(),
            islands: IslandManager::new(),
            broad_phase: BroadPhaseBvh::new(),
            narrow_phase: NarrowPhase::new(),
            ccd: CCDSolver::new(),
            pipeline: PhysicsPipeline::new(),
            params,
            gravity: Vector::new(0.0, 0.0, -gravity as f32),
            dt,
            forced: None,
        }
    }

    /// From now on, remembers the bodies given forces, so that [`Engine::reset_forces`] clears
    /// those alone: on the multibody the ground's forces reach the feet in stance (a few bodies
    /// of 19), and a clear of every body was 740 instructions a step. Not where nearly every body
    /// is given a torque each step (the impulse joints' servos, two bodies a joint): there the
    /// list costs more than the clears it spares.
    pub fn track_forces(&mut self) {
        self.forced.get_or_insert_with(Vec::new);
    }

    /// Adds `force` and `torque` to a body's ([`RigidBodySet::add_force_and_torque`]: the body
    /// is not marked modified), remembering it where forces are tracked.
    pub fn add_force_and_torque(
        &mut self,
        body: RigidBodyHandle,
        force: Vector,
        torque: AngVector,
        wake_up: bool,
    ) {
        if let Some(forced) = &mut self.forced {
            forced.push(body);
        }
        self.bodies
            .add_force_and_torque(body, force, torque, wake_up);
    }

    /// Clears the forces and torques given to bodies ([`RigidBodySet::reset_forces_and_torques`]:
    /// not marked modified): where tracked, those of the bodies given some since the last clear,
    /// the others have none; else those of every body in `all`.
    pub fn reset_forces(&mut self, all: &[RigidBodyHandle]) {
        match &mut self.forced {
            Some(forced) => {
                for h in forced.drain(..) {
                    self.bodies.reset_forces_and_torques(h);
                }
            }
            None => {
                for &h in all {
                    self.bodies.reset_forces_and_torques(h);
                }
            }
        }
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Computes every body's world-frame mass properties now. rapier does it in its step, so
    /// before the first one a body's inverse inertia is unset and a multibody's mass matrix,
    /// factorised then, is not its own (the contact mobility read from it was NaN).
    pub fn update_mass_properties(&mut self) {
        for (_, body) in self.bodies.iter_mut() {
            body.recompute_mass_properties_from_colliders(&self.colliders);
        }
    }

    /// Advances the world by one step.
    pub fn step(&mut self) {
        self.pipeline.step(
            self.gravity,
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft_bodies,
            &mut self.ccd,
            &(),
            &(),
        );
    }
}
