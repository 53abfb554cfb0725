//! The start-of-step writeback of a multibody's link poses into its rigid-bodies, skipped when
//! nothing changed since the last step, still happens when the user moved a link's body: the
//! multibody's pose wins, as it always did.

use rapier3d::prelude::*;

#[test]
fn a_moved_link_body_is_put_back_on_its_multibody() {
    let mut bodies = RigidBodySet::new();
    let mut colliders = ColliderSet::new();
    let mut impulse_joints = ImpulseJointSet::new();
    let mut multibody_joints = MultibodyJointSet::new();
    let mut soft_bodies = SoftBodySet::new();
    let mut pipeline = PhysicsPipeline::new();
    let mut islands = IslandManager::new();
    let mut broad_phase = DefaultBroadPhase::new();
    let mut narrow_phase = NarrowPhase::new();
    let mut ccd = CCDSolver::new();
    let root = bodies.insert(RigidBodyBuilder::fixed());
    let link = bodies.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(1.0, 0.0, 0.0))
            .additional_mass(1.0),
    );
    let joint = RevoluteJointBuilder::new(Vector::Z)
        .local_anchor1(Vector::new(1.0, 0.0, 0.0))
        .local_anchor2(Vector::ZERO);
    multibody_joints.insert(root, link, joint, true).unwrap();

    let mut step = |bodies: &mut RigidBodySet| {
        pipeline.step(
            Vector::ZERO,
            &IntegrationParameters::default(),
            &mut islands,
            &mut broad_phase,
            &mut narrow_phase,
            bodies,
            &mut colliders,
            &mut impulse_joints,
            &mut multibody_joints,
            &mut soft_bodies,
            &mut ccd,
            &(),
            &(),
        );
    };
    step(&mut bodies);
    step(&mut bodies);
    let held = *bodies[link].position();
    assert_eq!(held.translation, Vector::new(1.0, 0.0, 0.0));

    // no gravity, no motion: only the user's move can bring the writeback back
    bodies[link].set_translation(Vector::new(5.0, 5.0, 0.0), true);
    step(&mut bodies);
    assert_eq!(*bodies[link].position(), held);
    assert_eq!(bodies[link].center_of_mass(), held.translation);
}
