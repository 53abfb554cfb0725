//! The mass matrices that `Multibody::update_mass_matrix` assembles on each link's path equal
//! those of the dense assembly it replaced (every link's terms over every degree of freedom), on
//! a branching tree with revolute, prismatic and spherical joints, offset centres of mass and
//! tilted inertia frames, moving.

use super::Multibody;
use crate::alloc_prelude::*;
use crate::dynamics::RigidBodySet;
use crate::math::{ANG_DIM, DIM, Real, SPATIAL_DIM};
use crate::prelude::*;
use crate::utils::{
    AngularInertiaOps, CrossProduct, CrossProductMatrix, IndexMut2, mat_to_na, vect_to_na,
};
use na::{DMatrix, Dyn, OMatrix, SMatrix};

/// The dense assembly of rapier 0.36.1, verbatim but for the factorisations: `M = Σ Jᵀ·Mᵢ·J` and
/// the semi-implicit update's matrix, over all degrees of freedom of every link.
fn dense_mass_matrices(
    mb: &Multibody,
    dt: Real,
    bodies: &RigidBodySet,
) -> (DMatrix<Real>, DMatrix<Real>) {
    let n = mb.ndofs;
    let mut mass = DMatrix::zeros(n, n);
    let mut acc_mass = DMatrix::zeros(n, n);
    let mut coriolis_v = vec![OMatrix::<Real, crate::math::Dim, Dyn>::zeros(n); mb.links.len()];
    let mut coriolis_w = vec![OMatrix::<Real, crate::math::AngDim, Dyn>::zeros(n); mb.links.len()];
    let mut i_coriolis_dt = crate::math::Jacobian::<Real>::zeros(n);

    for i in 0..mb.links.len() {
        let link = &mb.links[i];
        let rb = &bodies[link.rigid_body];
        let rb_mass = rb.mprops.effective_mass();
        let rb_inertia = rb.mprops.effective_angular_inertia().into_matrix();
        let body_jacobian = &mb.body_jacobians[i];

        let gyroscopic_matrix = rb.vels.angvel.gcross_matrix() * rb_inertia
            - (rb_inertia * rb.vels.angvel).gcross_matrix();
        let augmented_inertia = rb_inertia + gyroscopic_matrix * dt;
        let spatial = |inertia| {
            let mut m = SMatrix::<Real, SPATIAL_DIM, SPATIAL_DIM>::zeros();
            m[(0, 0)] = rb_mass.x;
            m[(1, 1)] = rb_mass.y;
            m[(2, 2)] = rb_mass.z;
            m.fixed_view_mut::<ANG_DIM, ANG_DIM>(DIM, DIM)
                .copy_from(&mat_to_na(inertia));
            m
        };
        mass.quadform(1.0, &spatial(rb_inertia), body_jacobian, 1.0);
        acc_mass.quadform(1.0, &spatial(augmented_inertia), body_jacobian, 1.0);

        let rb_j = &mb.body_jacobians[i];
        let rb_j_w = rb_j.fixed_rows::<ANG_DIM>(DIM);
        let ndofs = link.joint.ndofs();

        if i != 0 {
            let parent_id = link.parent_internal_id;
            let parent_link = &mb.links[parent_id];
            let parent_rb = &bodies[parent_link.rigid_body];
            let parent_j = &mb.body_jacobians[parent_id];
            let parent_j_w = parent_j.fixed_rows::<ANG_DIM>(DIM);
            let parent_w = vect_to_na(parent_rb.vels.angvel).gcross_matrix();

            let (cv, parent_cv) = coriolis_v.index_mut2(i, parent_id);
            let (cw, parent_cw) = coriolis_w.index_mut2(i, parent_id);
            cv.copy_from(parent_cv);
            cw.copy_from(parent_cw);

            let shift_cross_tr = vect_to_na(link.shift02).gcross_matrix_tr();
            cv.gemm(1.0, &shift_cross_tr, parent_cw, 1.0);
            let dvel_cross =
                vect_to_na(rb.vels.angvel.gcross(link.shift02) + 2.0 * link.joint_velocity.linvel)
                    .gcross_matrix_tr();
            cv.gemm(1.0, &dvel_cross, &parent_j_w, 1.0);
            cv.gemm(
                1.0,
                &vect_to_na(link.joint_velocity.linvel).gcross_matrix_tr(),
                &parent_j_w,
                1.0,
            );
            cv.gemm(1.0, &(parent_w * shift_cross_tr), &parent_j_w, 1.0);
            let vel_wrt_joint_w = vect_to_na(link.joint_velocity.angvel).gcross_matrix();
            cw.gemm(-1.0, &vel_wrt_joint_w, &parent_j_w, 1.0);

            if !link.joint.kinematic {
                let mut cv_part = cv.columns_mut(link.assembly_id, ndofs);
                let mut tmp1 = SMatrix::<Real, SPATIAL_DIM, SPATIAL_DIM>::zeros();
                let mut rb_joint_j = tmp1.columns_mut(0, ndofs);
                link.joint.jacobian(
                    &(parent_link.local_to_world.rotation * link.joint.data.local_frame1.rotation),
                    &mut rb_joint_j,
                );
                let rb_joint_j_v = rb_joint_j.fixed_rows::<DIM>(0);
                cv_part.gemm(2.0, &parent_w, &rb_joint_j_v, 1.0);
                let rb_joint_j_w = rb_joint_j.fixed_rows::<ANG_DIM>(DIM);
                let mut cw_part = cw.columns_mut(link.assembly_id, ndofs);
                cw_part.gemm(1.0, &parent_w, &rb_joint_j_w, 1.0);
            }
        }

        let cv = &mut coriolis_v[i];
        let cw = &mut coriolis_w[i];
        let shift_cross_tr = vect_to_na(link.shift23).gcross_matrix_tr();
        cv.gemm(1.0, &shift_cross_tr, cw, 1.0);
        let dvel_cross = vect_to_na(rb.vels.angvel.gcross(link.shift23)).gcross_matrix_tr();
        cv.gemm(1.0, &dvel_cross, &rb_j_w, 1.0);
        cv.gemm(
            1.0,
            &(vect_to_na(rb.vels.angvel).gcross_matrix() * shift_cross_tr),
            &rb_j_w,
            1.0,
        );

        let mut i_coriolis_dt_v = i_coriolis_dt.fixed_rows_mut::<DIM>(0);
        i_coriolis_dt_v.copy_from(cv);
        let rb_mass_dt = vect_to_na(rb_mass * dt);
        i_coriolis_dt_v
            .column_iter_mut()
            .for_each(|mut c| c.component_mul_assign(&rb_mass_dt));
        let mut i_coriolis_dt_w = i_coriolis_dt.fixed_rows_mut::<ANG_DIM>(DIM);
        i_coriolis_dt_w.gemm(dt, &mat_to_na(rb_inertia), cw, 0.0);

        acc_mass.gemm_tr(1.0, rb_j, &i_coriolis_dt, 1.0);
    }
    (mass, acc_mass)
}

/// A floating base with three branches: a revolute chain of three links (the leg of a
/// hexapod), a prismatic joint carrying a spherical one, and a single revolute link.
pub(super) fn branching_tree() -> (RigidBodySet, MultibodyJointSet, RigidBodyHandle) {
    let mut bodies = RigidBodySet::new();
    let mut joints = MultibodyJointSet::new();
    let mut rng = oorandom::Rand32::new(7);
    let mut r = move || rng.rand_float() as Real - 0.5;
    let body = |bodies: &mut RigidBodySet, r: &mut dyn FnMut() -> Real| {
        let frame = Rotation::from_scaled_axis(Vector::new(r(), r(), r()) * 2.0);
        let mprops = MassProperties::with_principal_inertia_frame(
            Vector::new(r(), r(), r()) * 0.2,
            1.0 + r(),
            Vector::new(0.1 + r().abs(), 0.2 + r().abs(), 0.15 + r().abs()) * 0.1,
            frame,
        );
        bodies.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(r(), r(), r()))
                .additional_mass_properties(mprops),
        )
    };
    let base = body(&mut bodies, &mut r);
    let mut links = vec![base];
    for _ in 0..5 {
        links.push(body(&mut bodies, &mut r));
    }
    let leg_body = body(&mut bodies, &mut r);
    let axes = [Vector::Z, Vector::Y, Vector::new(0.3, 0.9, 0.1).normalize()];
    let mut parent = base;
    for (k, axis) in axes.iter().enumerate() {
        let child = links[k + 1];
        let joint = RevoluteJointBuilder::new(*axis)
            .local_anchor1(Vector::new(0.1 * k as Real + 0.05, 0.02, -0.01))
            .local_anchor2(Vector::new(-0.03, 0.01, 0.02));
        joints.insert(parent, child, joint, true).unwrap();
        parent = child;
    }
    let slider = PrismaticJointBuilder::new(Vector::new(0.2, -0.4, 0.9).normalize())
        .local_anchor1(Vector::new(-0.1, 0.05, 0.0));
    joints.insert(base, links[4], slider, true).unwrap();
    let ball = SphericalJointBuilder::new().local_anchor1(Vector::new(0.0, 0.1, 0.05));
    joints.insert(links[4], links[5], ball, true).unwrap();
    let single = RevoluteJointBuilder::new(Vector::X).local_anchor1(Vector::new(0.0, -0.2, 0.0));
    joints.insert(base, leg_body, single, true).unwrap();
    (bodies, joints, base)
}

#[test]
fn path_assembly_equals_the_dense_one() {
    let (mut bodies, mut joints, base) = branching_tree();
    let colliders = ColliderSet::new();
    for (_, rb) in bodies.iter_mut() {
        rb.recompute_mass_properties_from_colliders(&colliders);
    }
    let root = joints.rigid_body_link(base).copied().unwrap();
    let mb = joints.get_multibody_mut(root.multibody).unwrap();
    let n = mb.ndofs();
    assert_eq!(n, 6 + 3 + 1 + 3 + 1);

    // A configuration and a motion away from the assembly pose, fast enough for the
    // gyroscopic and Coriolis terms to matter.
    let mut rng = oorandom::Rand32::new(11);
    let disp: Vec<Real> = (0..n).map(|_| rng.rand_float() as Real - 0.5).collect();
    mb.apply_displacements(&disp);
    for v in mb.generalized_velocity_mut().iter_mut() {
        *v = 6.0 * (rng.rand_float() as Real - 0.5);
    }
    let dt = 1.0 / 60.0;
    mb.forward_kinematics(&bodies, true);
    mb.update_rigid_bodies(&mut bodies, true);
    mb.update_velocities(&mut bodies);
    mb.update_mass_matrix(dt, &bodies);
    let (mass, acc_mass) = dense_mass_matrices(mb, dt, &bodies);

    // `update_mass_matrix` adds the (here zero) springs and rapier's default damping to both
    // diagonals; the dense reference has none.
    let mut expected_mass = mass;
    let mut expected_acc = acc_mass;
    for i in 0..n {
        let diag = mb.damping[i] * dt + mb.armature[i];
        expected_mass[(i, i)] += diag;
        expected_acc[(i, i)] += diag;
    }
    for (name, got, expected) in [
        ("mass", &mb.augmented_mass, &expected_mass),
        ("semi-implicit", &mb.acc_augmented_mass, &expected_acc),
    ] {
        let scale = expected.amax();
        let error = (got - expected).amax();
        assert!(
            error <= 1.0e-5 * scale,
            "{name} matrix off by {error} (largest entry {scale})"
        );
    }
    // The Coriolis and gyroscopic terms are present (the test would not see them otherwise).
    assert!((&expected_acc - &expected_mass).amax() > 1.0e-3 * expected_mass.amax());
}

/// The branching tree moving, its multibody's mass matrices and free accelerations computed with
/// the Coriolis forces semi-implicit (rapier's default) or explicit, and forces on two links.
fn moving_tree(explicit: bool, dt: Real) -> (RigidBodySet, MultibodyJointSet, RigidBodyHandle) {
    let (mut bodies, mut joints, base) = branching_tree();
    let colliders = ColliderSet::new();
    for (_, rb) in bodies.iter_mut() {
        rb.recompute_mass_properties_from_colliders(&colliders);
    }
    let handles: Vec<_> = bodies.iter().map(|(h, _)| h).collect();
    bodies
        .get_mut(handles[1])
        .unwrap()
        .add_force(Vector::new(0.3, -2.0, 0.7), true);
    bodies
        .get_mut(handles[3])
        .unwrap()
        .add_torque(Vector::new(-0.2, 0.1, 0.4), true);
    let root = joints.rigid_body_link(base).copied().unwrap();
    let mb = joints.get_multibody_mut(root.multibody).unwrap();
    mb.set_explicit_coriolis(explicit);
    let n = mb.ndofs();
    let mut rng = oorandom::Rand32::new(5);
    let disp: Vec<Real> = (0..n).map(|_| rng.rand_float() as Real - 0.5).collect();
    mb.apply_displacements(&disp);
    for v in mb.generalized_velocity_mut().iter_mut() {
        *v = 6.0 * (rng.rand_float() as Real - 0.5);
    }
    mb.forward_kinematics(&bodies, true);
    mb.update_rigid_bodies(&mut bodies, true);
    mb.update_velocities(&mut bodies);
    mb.update_mass_matrix(dt, &bodies);
    mb.update_acceleration(dt, &bodies);
    (bodies, joints, base)
}

#[test]
fn explicit_coriolis_solves_with_the_mass_matrix() {
    let dt = 1.0 / 60.0;
    let (_, semi_joints, base) = moving_tree(false, dt);
    let (_, explicit_joints, _) = moving_tree(true, dt);
    let root = semi_joints.rigid_body_link(base).copied().unwrap();
    let semi = semi_joints.get_multibody(root.multibody).unwrap();
    let explicit = explicit_joints.get_multibody(root.multibody).unwrap();
    assert!(!semi.explicit_coriolis() && explicit.explicit_coriolis());

    // The same mass matrix, bit for bit; no second matrix.
    assert_eq!(semi.augmented_mass, explicit.augmented_mass);
    assert_eq!(explicit.acc_augmented_mass.len(), 0);

    // `M·q̈ = f − c(q, q̇)`: the right-hand side is what the semi-implicit update solved for (its
    // energy guard keeps a copy, the velocities being large enough for it to run).
    let rhs = &semi.workspace.gen_forces;
    assert_eq!(rhs.len(), semi.ndofs());
    assert!(rhs.amax() > 0.1);
    let residual = &explicit.augmented_mass * &explicit.accelerations - rhs;
    assert!(
        residual.amax() <= 1.0e-4 * rhs.amax(),
        "M·q̈ off f − c by {} (largest entry {})",
        residual.amax(),
        rhs.amax()
    );
    // … and the semi-implicit update solves with the other matrix (the Coriolis derivatives
    // change the accelerations: the test would not see the difference otherwise).
    let semi_residual = &semi.acc_augmented_mass * &semi.accelerations - rhs;
    assert!(semi_residual.amax() <= 1.0e-4 * rhs.amax());
    let difference = (&semi.accelerations - &explicit.accelerations).amax();
    assert!(difference > 1.0e-2 * explicit.accelerations.amax());
}
