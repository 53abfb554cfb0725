//! The rapier world: the sets rapier needs, stepped with gravity along −z. Bodies carry no colliders,
//! so rapier computes no contacts; the ground forces are ours (see `contact`).

use rapier3d::math::Vector;
use rapier3d::prelude::{
    BroadPhaseBvh, CCDSolver, ColliderSet, ImpulseJointSet, IntegrationParameters, IslandManager,
    MultibodyJointSet, NarrowPhase, PhysicsPipeline, RigidBodySet, SoftBodySet,
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
