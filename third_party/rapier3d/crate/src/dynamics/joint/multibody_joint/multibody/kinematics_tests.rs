//! `Multibody::forward_kinematics` keeps its last results when nothing it reads changed since
//! then; whatever a user changes between two calls, its results equal those of a multibody that
//! computes them anew.

use super::Multibody;
use super::mass_matrix_tests::branching_tree;
use crate::alloc_prelude::*;
use crate::dynamics::RigidBodySet;
use crate::math::{Pose, Real, Rotation, Vector};
use crate::prelude::*;

/// The results of forward kinematics: every link's poses and lever arms, and body Jacobian.
fn assert_same_kinematics(got: &Multibody, expected: &Multibody, what: &str) {
    for (i, (a, b)) in got.links.iter().zip(expected.links.iter()).enumerate() {
        assert_eq!(
            a.local_to_world, b.local_to_world,
            "{what}: link {i}'s pose"
        );
        assert_eq!(
            a.local_to_parent, b.local_to_parent,
            "{what}: link {i}'s pose in its parent"
        );
        assert_eq!(a.shift02, b.shift02, "{what}: link {i}'s shift02");
        assert_eq!(a.shift23, b.shift23, "{what}: link {i}'s shift23");
        assert_eq!(
            got.body_jacobians[i], expected.body_jacobians[i],
            "{what}: link {i}'s body Jacobian"
        );
    }
}

/// Runs forward kinematics on `mb` and on a copy that has no memory of an earlier call, and
/// checks that both agree.
fn check(mb: &mut Multibody, bodies: &RigidBodySet, read_root_pose: bool, what: &str) {
    let mut anew = mb.clone();
    anew.workspace.kinematic_inputs.clear();
    mb.forward_kinematics(bodies, read_root_pose);
    anew.forward_kinematics(bodies, read_root_pose);
    assert_same_kinematics(mb, &anew, what);
}

#[test]
fn forward_kinematics_is_recomputed_whenever_an_input_changes() {
    let (mut bodies, mut joints, base) = branching_tree();
    let colliders = ColliderSet::new();
    for (_, rb) in bodies.iter_mut() {
        rb.recompute_mass_properties_from_colliders(&colliders);
    }
    let root = joints.rigid_body_link(base).copied().unwrap();
    let mb = joints.get_multibody_mut(root.multibody).unwrap();
    mb.forward_kinematics(&bodies, true);
    mb.update_rigid_bodies(&mut bodies, true);

    // Nothing changed: the results stand, and the work is skipped (a result planted in
    // between survives).
    check(mb, &bodies, true, "unchanged");
    let planted = Vector::new(1.0, 2.0, 3.0);
    mb.links[2].shift02 = planted;
    mb.forward_kinematics(&bodies, true);
    assert_eq!(mb.links[2].shift02, planted, "an unchanged call recomputed");
    mb.workspace.kinematic_inputs.clear();
    mb.forward_kinematics(&bodies, true);

    // The joints' coordinates.
    let disp: Vec<Real> = (0..mb.ndofs()).map(|i| 0.01 * i as Real - 0.05).collect();
    mb.apply_displacements(&disp);
    check(mb, &bodies, true, "coordinates displaced");

    // A joint's frames.
    mb.link_mut(3)
        .unwrap()
        .joint
        .data
        .set_local_anchor2(Vector::new(0.01, -0.02, 0.03));
    check(mb, &bodies, true, "a joint's second frame moved");
    mb.link_mut(5)
        .unwrap()
        .joint
        .data
        .set_local_frame1(Pose::from_parts(
            Vector::new(0.0, 0.1, 0.0),
            Rotation::from_scaled_axis(Vector::new(0.0, 0.0, 0.3)),
        ));
    check(mb, &bodies, true, "a joint's first frame turned");

    // The root body's pose, read when asked for.
    let root_body = mb.links[0].rigid_body;
    bodies[root_body].set_position(
        Pose::from_parts(
            Vector::new(0.4, -0.2, 1.0),
            Rotation::from_scaled_axis(Vector::X),
        ),
        false,
    );
    check(mb, &bodies, true, "the root body moved");

    // A link's centre of mass.
    let link_body = mb.links[4].rigid_body;
    let mprops = MassProperties::new(Vector::new(0.05, 0.0, -0.02), 1.3, Vector::splat(0.01));
    bodies[link_body].set_additional_mass_properties(mprops, false);
    bodies[link_body].recompute_mass_properties_from_colliders(&colliders);
    check(mb, &bodies, true, "a link's centre of mass moved");

    // The root made fixed: its six degrees of freedom go.
    let ndofs = mb.ndofs();
    bodies[root_body].set_body_type(RigidBodyType::Fixed, false);
    check(mb, &bodies, true, "the root fixed");
    assert_eq!(mb.ndofs(), ndofs - 6);
}
