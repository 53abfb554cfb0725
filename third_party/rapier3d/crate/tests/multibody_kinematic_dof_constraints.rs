//! Limit and motor constraints on a multibody that also has kinematic degrees of freedom.
//!
//! A kinematic joint's degrees of freedom are left out of the factorised mass matrix, so it has
//! fewer rows than the multibody has degrees of freedom. The constraint builders solved each
//! constraint's `ndofs`-row Jacobian with that smaller factorisation and panicked ("LU solve
//! matrix dimension mismatch") on the first step a limit or motor was active; they now solve in
//! the kinematic-reduced order, a kinematic degree of freedom's entry zero.

use rapier3d::prelude::*;

/// A fixed base, an arm on a kinematic revolute joint (held at 0) and a forearm on a dynamic
/// revolute joint with a position motor towards `target` and limits ±0.5 rad, both about Z,
/// under gravity along −Y. Returns the forearm's angle to the arm (rad) after `steps` steps.
fn forearm_angle(target: Real, steps: usize) -> Real {
    let mut bodies = RigidBodySet::new();
    let mut colliders = ColliderSet::new();
    let mut impulse_joints = ImpulseJointSet::new();
    let mut multibody_joints = MultibodyJointSet::new();

    let base = bodies.insert(RigidBodyBuilder::fixed());
    let link = |x: Real| {
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(x, 0.0, 0.0))
            .additional_mass_properties(MassProperties::new(
                Vector::ZERO,
                1.0,
                Vector::new(0.01, 0.01, 0.01),
            ))
    };
    let arm = bodies.insert(link(0.5));
    let forearm = bodies.insert(link(1.5));
    let shoulder = RevoluteJointBuilder::new(Vector::Z).local_anchor2(Vector::new(-0.5, 0.0, 0.0));
    multibody_joints
        .insert_kinematic(base, arm, shoulder, true)
        .unwrap();
    let elbow = RevoluteJointBuilder::new(Vector::Z)
        .local_anchor1(Vector::new(0.5, 0.0, 0.0))
        .local_anchor2(Vector::new(-0.5, 0.0, 0.0))
        .limits([-0.5, 0.5])
        .motor_position(target, 200.0, 20.0);
    multibody_joints.insert(arm, forearm, elbow, true).unwrap();

    let gravity = Vector::new(0.0, -9.81, 0.0);
    let integration_parameters = IntegrationParameters::default();
    let mut pipeline = PhysicsPipeline::new();
    let mut islands = IslandManager::new();
    let mut broad_phase = DefaultBroadPhase::new();
    let mut narrow_phase = NarrowPhase::new();
    let mut ccd = CCDSolver::new();
    let mut soft_bodies = SoftBodySet::new();
    for _ in 0..steps {
        pipeline.step(
            gravity,
            &integration_parameters,
            &mut islands,
            &mut broad_phase,
            &mut narrow_phase,
            &mut bodies,
            &mut colliders,
            &mut impulse_joints,
            &mut multibody_joints,
            &mut soft_bodies,
            &mut ccd,
            &(),
            &(),
        );
    }
    // the arm is kinematic: it has not moved
    let arm_turn = bodies[arm].rotation();
    assert!(
        arm_turn.z.abs() < 1e-6,
        "the kinematic arm turned: {arm_turn:?}"
    );
    let relative = arm_turn.inverse() * *bodies[forearm].rotation();
    2.0 * relative.z.atan2(relative.w)
}

/// The motor holds the forearm where its law balances gravity: an acceleration-based motor (the
/// default) applies k·(target − θ) times the forearm's inertia about the elbow, I = 0.01 + 1·0.5²
/// kg·m² (the arm is kinematic), against the weight's moment m·g·0.5·cos θ.
#[test]
fn a_motor_on_a_multibody_with_a_kinematic_dof() {
    let angle = forearm_angle(0.3, 300);
    let inertia = 0.01 + 0.25;
    let mut expected: Real = 0.3;
    for _ in 0..50 {
        expected = 0.3 - 9.81 * 0.5 * expected.cos() / (200.0 * inertia);
    }
    assert!(
        (angle - expected).abs() < 2.0e-3,
        "forearm at {angle} rad, balanced at {expected}"
    );
}

/// A target past the limit: the limit holds the forearm at 0.5 rad.
#[test]
fn a_limit_on_a_multibody_with_a_kinematic_dof() {
    let angle = forearm_angle(1.0, 300);
    assert!(
        (angle - 0.5).abs() < 0.02,
        "forearm at {angle} rad, limit 0.5"
    );
}
