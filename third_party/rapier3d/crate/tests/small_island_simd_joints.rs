//! Patch 0014: in an island too small for any joint color to be shared among workers (fewer
//! than 64 joints), a color of two joints or more is built and solved in SIMD chunks instead of
//! one joint at a time (hexsim's hexapod: 18 joints in colors of 7, 7, 1, 1, 1 and 1, so 14 of
//! them in four chunks).
//!
//! The chunked joints must hold as the scalar ones do: a free body with three legs of three
//! revolute joints each is thrown spinning, with its legs' centres of mass off their joint
//! anchors (the SIMD builder once pinned such a body at its centre of mass, issue 952), and
//! every joint's two anchors must stay together. The links' colliders carry their mass only (no
//! collision groups): no contact pushes on them.

use rapier3d::prelude::*;

/// Distance from a link's origin (its joint's anchor) to its centre of mass, along the leg.
const HALF_LENGTH: f32 = 0.05;
/// Three legs: from four on, this robot's unactuated legs flail apart on rapier's scalar layout
/// too (anchors 7–20 cm apart in 2 s at 1 ms, as published), a limit of its own, not traced here.
const LEGS: usize = 3;
/// The robot's spin and throw (its body's centre of mass is at the origin).
const SPIN: Vector = Vector::new(0.5, 2.0, 1.0);
const THROW: Vector = Vector::new(0.3, 1.0, 0.0);

/// Builds the robot and returns each joint's handle.
fn robot(world: &mut PhysicsWorld) -> Vec<ImpulseJointHandle> {
    let base = world.bodies.insert(
        RigidBodyBuilder::dynamic()
            .angvel(SPIN)
            .linvel(THROW)
            .can_sleep(false),
    );
    world.colliders.insert_with_parent(
        ColliderBuilder::cuboid(0.12, 0.03, 0.08).collision_groups(InteractionGroups::none()),
        base,
        &mut world.bodies,
    );
    let mut joints = Vec::new();
    for leg in 0..LEGS {
        let angle = leg as f32 * core::f32::consts::TAU / 6.0 + 0.3;
        let out = Vector::new(angle.cos(), 0.0, angle.sin());
        let across = Vector::Y.cross(out);
        let hip = out * 0.1;
        let mut parent = base;
        // coxa about the vertical, femur and tibia about the leg's horizontal cross axis
        for (segment, axis) in [Vector::Y, across, across].into_iter().enumerate() {
            let origin = hip + out * (2.0 * HALF_LENGTH * segment as f32);
            let child = world.bodies.insert(
                RigidBodyBuilder::dynamic()
                    .translation(origin)
                    // the whole robot turning as one body: its centre of mass's velocity
                    .linvel(THROW + SPIN.cross(origin + out * HALF_LENGTH))
                    .angvel(SPIN)
                    .can_sleep(false),
            );
            // the link's collider, so its centre of mass, halfway along it from the anchor
            world.colliders.insert_with_parent(
                ColliderBuilder::capsule_from_endpoints(
                    Vector::ZERO,
                    out * 2.0 * HALF_LENGTH,
                    0.01,
                )
                .density(1000.0 + 300.0 * segment as f32)
                .collision_groups(InteractionGroups::none()),
                child,
                &mut world.bodies,
            );
            let parent_pose = *world.bodies[parent].position();
            let joint = RevoluteJointBuilder::new(axis)
                .local_anchor1(parent_pose.inverse() * origin)
                .local_anchor2(Vector::ZERO)
                .contacts_enabled(false);
            joints.push(world.impulse_joints.insert(parent, child, joint, true));
            parent = child;
        }
    }
    joints
}

/// The largest distance between a joint's two anchors over `steps` steps.
fn max_anchor_gap(steps: usize) -> f32 {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    // hexsim's step, 1 ms, with no gravity: the robot spins where it was thrown
    world.integration_parameters.dt = 1.0e-3;
    let joints = robot(&mut world);
    let mut worst: f32 = 0.0;
    for _ in 0..steps {
        world.step();
        for handle in &joints {
            let joint = world.impulse_joints.get(*handle).unwrap();
            let a1 = world.bodies[joint.body1()].position() * joint.data.local_anchor1();
            let a2 = world.bodies[joint.body2()].position() * joint.data.local_anchor2();
            worst = worst.max((a1 - a2).length());
        }
    }
    worst
}

#[test]
fn a_small_islands_chunked_joints_hold() {
    let gap = max_anchor_gap(2000);
    println!("three legs of impulse joints, 2 s spinning: anchors at most {gap:e} m apart");
    // the links' centres of mass are 5 cm off their anchors: a chunk that pinned them there
    // (issue 952) would part the anchors by centimetres
    assert!(gap < 1.0e-3, "the joints parted: {gap} m");
}

#[test]
fn a_small_islands_chunked_joints_are_deterministic() {
    assert_eq!(max_anchor_gap(60).to_bits(), max_anchor_gap(60).to_bits());
}
