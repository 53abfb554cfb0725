//! `RigidBodySet::add_force_and_torque` / `reset_forces_and_torques`: pushing bodies every step
//! without putting them in the modified set moves them exactly as `get_mut` + `add_force` does —
//! on an impulse-joint pendulum (whose cached joint layout a modified body invalidates) and on a
//! multibody chain — and still wakes a sleeping body.

use rapier3d::prelude::*;

struct World {
    bodies: RigidBodySet,
    colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft_bodies: SoftBodySet,
    pipeline: PhysicsPipeline,
    islands: IslandManager,
    broad_phase: DefaultBroadPhase,
    narrow_phase: NarrowPhase,
    ccd: CCDSolver,
    pushed: Vec<RigidBodyHandle>,
}

impl World {
    /// A fixed anchor, two links on impulse joints and two on multibody joints.
    fn new() -> Self {
        let mut world = Self {
            bodies: RigidBodySet::new(),
            colliders: ColliderSet::new(),
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
            soft_bodies: SoftBodySet::new(),
            pipeline: PhysicsPipeline::new(),
            islands: IslandManager::new(),
            broad_phase: DefaultBroadPhase::new(),
            narrow_phase: NarrowPhase::new(),
            ccd: CCDSolver::new(),
            pushed: Vec::new(),
        };
        let joint = || {
            RevoluteJointBuilder::new(Vector::Z)
                .local_anchor1(Vector::new(1.0, 0.0, 0.0))
                .local_anchor2(Vector::ZERO)
        };
        for multibody in [false, true] {
            let mut parent = world.bodies.insert(RigidBodyBuilder::fixed());
            for i in 0..2 {
                let child = world.bodies.insert(
                    RigidBodyBuilder::dynamic()
                        .translation(Vector::new(1.0 + i as f32, 0.0, 0.0))
                        .additional_mass(1.0),
                );
                if multibody {
                    world
                        .multibody_joints
                        .insert(parent, child, joint(), true)
                        .unwrap();
                } else {
                    world.impulse_joints.insert(parent, child, joint(), true);
                }
                world.pushed.push(child);
                parent = child;
            }
        }
        world
    }

    fn step(&mut self) {
        self.pipeline.step(
            Vector::new(0.0, -9.81, 0.0),
            &IntegrationParameters::default(),
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

    fn poses(&self) -> Vec<Pose> {
        self.pushed
            .iter()
            .map(|h| *self.bodies[*h].position())
            .collect()
    }
}

fn push(step: usize, i: usize) -> (Vector, Vector) {
    let s = (step as f32 * 0.1 + i as f32).sin();
    (
        Vector::new(0.0, 3.0 * s, 0.0),
        Vector::new(0.0, 0.0, 0.5 * s),
    )
}

#[test]
fn untracked_forces_move_bodies_as_tracked_ones() {
    let mut tracked = World::new();
    let mut untracked = World::new();
    let mut lowest: f32 = 0.0;
    for step in 0..200 {
        for (i, h) in tracked.pushed.clone().into_iter().enumerate() {
            let (force, torque) = push(step, i);
            let rb = tracked.bodies.get_mut(h).unwrap();
            rb.reset_forces(false);
            rb.reset_torques(false);
            rb.add_force(force, true);
            rb.add_torque(torque, true);
        }
        for (i, h) in untracked.pushed.clone().into_iter().enumerate() {
            let (force, torque) = push(step, i);
            assert!(untracked.bodies.reset_forces_and_torques(h));
            assert!(
                untracked
                    .bodies
                    .add_force_and_torque(h, force, torque, true)
            );
        }
        tracked.step();
        untracked.step();
        assert_eq!(tracked.poses(), untracked.poses(), "step {step}");
        lowest = untracked
            .poses()
            .iter()
            .fold(lowest, |l, p| l.min(p.translation.y));
    }
    // the links did swing
    assert!(lowest < -0.5, "{lowest}");
}

#[test]
fn untracked_forces_wake_a_sleeping_body() {
    let mut world = World::new();
    let free = world.bodies.insert(
        RigidBodyBuilder::dynamic()
            .additional_mass(1.0)
            .gravity_scale(0.0),
    );
    world.step();
    world.bodies.get_mut(free).unwrap().sleep();
    world.step();
    assert!(world.bodies[free].is_sleeping());

    // without waking it up, the force waits
    assert!(world.bodies.add_force_and_torque(
        free,
        Vector::new(1.0, 0.0, 0.0),
        Vector::ZERO,
        false
    ));
    world.step();
    assert!(world.bodies[free].is_sleeping());
    assert_eq!(world.bodies[free].translation(), Vector::ZERO);

    assert!(world.bodies.add_force_and_torque(
        free,
        Vector::new(1.0, 0.0, 0.0),
        Vector::ZERO,
        true
    ));
    world.step();
    assert!(!world.bodies[free].is_sleeping());
    assert!(world.bodies[free].translation().x > 0.0);

    let removed = world.bodies.remove(
        free,
        &mut world.islands,
        &mut world.colliders,
        &mut world.impulse_joints,
        &mut world.multibody_joints,
        &mut world.soft_bodies,
        true,
    );
    assert!(removed.is_some());
    assert!(!world.bodies.reset_forces_and_torques(free));
    assert!(
        !world
            .bodies
            .add_force_and_torque(free, Vector::X, Vector::ZERO, true)
    );
}
