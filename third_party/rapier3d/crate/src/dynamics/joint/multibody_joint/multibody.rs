use super::multibody_link::{MultibodyLink, MultibodyLinkVec};
use super::multibody_workspace::{LinkKinematicInputs, MultibodyWorkspace};
use super::tree_lu::TreeLu;
use crate::alloc_prelude::*;
use crate::dynamics::integration_parameters::SpringCoefficients;
use crate::dynamics::solver::{GenericJointConstraint, WritebackId};
use crate::dynamics::{
    IntegrationParameters, RigidBodyChanges, RigidBodyHandle, RigidBodySet, RigidBodyType,
    RigidBodyVelocity,
};
use crate::math::{
    ANG_DIM, AngVector, DIM, DVector, Jacobian, Pose, Real, SPATIAL_DIM, SimdAngVector, Vector,
};
use crate::prelude::MultibodyJoint;
#[cfg(feature = "dim3")]
use crate::utils::mat_to_na;
use crate::utils::{AngularInertiaOps, CrossProduct, CrossProductMatrix, IndexMut2, vect_to_na};
use na::{self, DMatrix, DVectorView, DVectorViewMut, Dyn, LU, SMatrix, SVector, StorageMut};

#[cfg(doc)]
use crate::prelude::{GenericJoint, RigidBody};

#[repr(C)]
#[derive(Copy, Clone, Debug, Default)]
struct Force {
    linear: Vector,
    angular: AngVector,
}

impl Force {
    fn new(linear: Vector, angular: AngVector) -> Self {
        Self { linear, angular }
    }

    fn as_vector(&self) -> &SVector<Real, SPATIAL_DIM> {
        unsafe { core::mem::transmute(self) }
    }
}

/// A value computed on first use: `std`'s `OnceLock` (shared between threads), else `core`'s
/// `OnceCell`.
#[cfg(feature = "std")]
type LazyLu = std::sync::OnceLock<LU<Real, Dyn, Dyn>>;
#[cfg(not(feature = "std"))]
type LazyLu = core::cell::OnceCell<LU<Real, Dyn, Dyn>>;

/// The dot product of two spatial vectors, written out so that it compiles to a few
/// multiply-adds (the mass matrix assembly's inner loop).
#[inline(always)]
fn dot_spatial(a: &SVector<Real, SPATIAL_DIM>, b: &SVector<Real, SPATIAL_DIM>) -> Real {
    let (a, b) = (&a.data.0[0], &b.data.0[0]);
    let mut sum = 0.0;
    for r in 0..SPATIAL_DIM {
        sum += a[r] * b[r];
    }
    sum
}

/// Sets `to` to `from`, reallocating only if their lengths differ.
fn copied(to: &mut DVector, from: &DVector) {
    if to.len() != from.len() {
        *to = from.clone();
    } else {
        to.copy_from(from);
    }
}

/// Sets `v` to `len` zeros, reallocating only if its length differs.
fn zeroed(v: &mut DVector, len: usize) {
    if v.len() != len {
        *v = DVector::zeros(len);
    } else {
        v.fill(0.0);
    }
}

/// The twist `j` of a body at the point `r` from a reference point (its linear velocity there,
/// then its angular velocity) as the velocity of the reference point: `v − ω × r`.
#[inline(always)]
fn twist_at_reference(
    j: &SVector<Real, SPATIAL_DIM>,
    r: &na::SVector<Real, DIM>,
) -> SVector<Real, SPATIAL_DIM> {
    let mut twist = *j;
    let w = j.fixed_rows::<ANG_DIM>(DIM);
    twist
        .fixed_rows_mut::<DIM>(0)
        .gemm(-1.0, &r.gcross_matrix_tr(), &w, 1.0);
    twist
}

/// The wrench `w` applied at the point `r` from a reference point (a force, then a torque) as
/// the same wrench about the reference point: `τ + r × f`.
#[inline(always)]
fn wrench_at_reference(
    w: &SVector<Real, SPATIAL_DIM>,
    r: &na::SVector<Real, DIM>,
) -> SVector<Real, SPATIAL_DIM> {
    let mut wrench = *w;
    let f = w.fixed_rows::<DIM>(0);
    wrench
        .fixed_rows_mut::<ANG_DIM>(DIM)
        .gemm(1.0, &r.gcross_matrix_tr().transpose(), &f, 1.0);
    wrench
}

/// A holonomic coupling between two generalized coordinates of a single
/// [`Multibody`], `q2 = coeff · q1 + offset`, enforced as a velocity-level
/// equality constraint. This is how MuJoCo's `<equality><joint>` (a polynomial
/// joint-to-joint coupling) is represented for the linear (first-order) case —
/// e.g. the robotiq gripper's two driver joints moving together.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Copy, Clone, Debug)]
pub struct MultibodyDofCoupling {
    /// Internal id of the link owning the first joint.
    pub link1: usize,
    /// Local free-DoF index of the coupled DoF within `link1` (its position in
    /// that link's slice of the generalized vectors).
    pub dof1: usize,
    /// Spatial-coordinate axis (`0..6`) of `link1`'s coupled DoF, used to read
    /// its generalized position from the joint coords.
    pub axis1: usize,
    /// Internal id of the link owning the second joint.
    pub link2: usize,
    /// Local free-DoF index of the coupled DoF within `link2`.
    pub dof2: usize,
    /// Spatial-coordinate axis (`0..6`) of `link2`'s coupled DoF.
    pub axis2: usize,
    /// Linear coupling coefficient: the constraint is `q2 − coeff·q1 − offset = 0`.
    pub coeff: Real,
    /// Constant offset of the coupling.
    pub offset: Real,
}

/// An articulated body simulated using the reduced-coordinates approach.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug)]
pub struct Multibody {
    // TODO: serialization: skip the workspace fields.
    pub(crate) links: MultibodyLinkVec,
    pub(crate) velocities: DVector,
    pub(crate) damping: DVector,
    /// Per-DoF reflected rotor inertia (matches MuJoCo’s concept of `armature`).
    pub(crate) armature: DVector,
    /// Per-DoF dry joint friction (matches MuJoCo’s `frictionloss`).
    pub(crate) frictions: DVector,
    pub(crate) accelerations: DVector,

    body_jacobians: Vec<Jacobian<Real>>,
    // NOTE: the mass matrices are dimensioned based on the non-kinematic degrees of
    //       freedoms only. The `Self::augmented_mass_permutation` sequence can be used to
    //       move dofs from/to a format that matches the augmented mass.
    // TODO: use sparse matrices?
    augmented_mass: DMatrix<Real>,
    /// The factors of `augmented_mass` (leading block of the non-kinematic degrees of freedom).
    mass_factors: TreeLu,
    /// `augmented_mass`'s dense LU, computed only if [`Self::inv_augmented_mass`] asks for it.
    #[cfg_attr(feature = "serde-serialize", serde(skip))]
    inv_augmented_mass: LazyLu,
    // The indexing sequence for moving all kinematics degrees of
    // freedoms to the end of the generalized coordinates vector.
    augmented_mass_indices: IndexSequence,

    /// The matrix of the semi-implicit velocity update (`augmented_mass` plus `dt` times the
    /// derivatives of the Coriolis and gyroscopic forces) and its factors; neither is assembled
    /// when `explicit_coriolis` is set.
    acc_augmented_mass: DMatrix<Real>,
    acc_mass_factors: TreeLu,
    /// Whether the Coriolis, centrifugal and gyroscopic forces are integrated explicitly (the
    /// velocity update solves with `augmented_mass`) instead of semi-implicitly (the default).
    explicit_coriolis: bool,

    ndofs: usize,
    pub(crate) root_is_dynamic: bool,
    pub(crate) solver_id: u32,
    self_contacts_enabled: bool,
    /// Holonomic couplings between two of this multibody's generalized
    /// coordinates (`q2 = coeff·q1 + offset`), e.g. MuJoCo's
    /// `<equality><joint>`. Resolved as velocity constraints each step.
    couplings: Vec<MultibodyDofCoupling>,

    /*
     * Workspaces.
     */
    workspace: MultibodyWorkspace,
}
impl Default for Multibody {
    fn default() -> Self {
        Multibody::new()
    }
}

impl Multibody {
    /// Creates a new multibody with no link.
    pub fn new() -> Self {
        Self::with_self_contacts(true)
    }

    pub(crate) fn with_self_contacts(self_contacts_enabled: bool) -> Self {
        Multibody {
            links: MultibodyLinkVec(Vec::new()),
            velocities: DVector::zeros(0),
            damping: DVector::zeros(0),
            armature: DVector::zeros(0),
            frictions: DVector::zeros(0),
            accelerations: DVector::zeros(0),
            body_jacobians: Vec::new(),
            augmented_mass: DMatrix::zeros(0, 0),
            mass_factors: TreeLu::default(),
            inv_augmented_mass: LazyLu::default(),
            acc_augmented_mass: DMatrix::zeros(0, 0),
            acc_mass_factors: TreeLu::default(),
            explicit_coriolis: false,
            augmented_mass_indices: IndexSequence::new(),
            ndofs: 0,
            solver_id: 0,
            workspace: MultibodyWorkspace::new(),
            root_is_dynamic: false,
            self_contacts_enabled,
            couplings: Vec::new(),
            // solver_workspace: Some(SolverWorkspace::new()),
        }
    }

    pub(crate) fn with_root(handle: RigidBodyHandle, self_contacts_enabled: bool) -> Self {
        let mut mb = Multibody::with_self_contacts(self_contacts_enabled);
        // NOTE: we have no way of knowing if the root in fixed at this point, so
        //       we mark it as dynamic and will fix later with `Self::update_root_type`.
        mb.root_is_dynamic = true;
        let joint = MultibodyJoint::free(Pose::IDENTITY);
        mb.add_link(None, joint, handle);
        mb
    }

    pub(crate) fn remove_link(self, to_remove: usize, joint_only: bool) -> Vec<Multibody> {
        let mut result = vec![];
        let mut link2mb = vec![usize::MAX; self.links.len()];
        let mut link_id2new_id = vec![usize::MAX; self.links.len()];
        // Links whose joint is replaced by a fixed one: their DoFs no longer exist.
        let mut joint_replaced = vec![false; self.links.len()];

        // Split multibody and update the set of links and ndofs.
        for (i, mut link) in self.links.0.into_iter().enumerate() {
            let is_new_root = i == 0
                || !joint_only && link.parent_internal_id == to_remove
                || joint_only && i == to_remove;

            if !joint_only && i == to_remove {
                continue;
            } else if is_new_root {
                link2mb[i] = result.len();
                let mut mb = Multibody::with_self_contacts(self.self_contacts_enabled);
                mb.explicit_coriolis = self.explicit_coriolis;
                result.push(mb);
            } else {
                link2mb[i] = link2mb[link.parent_internal_id]
            }

            let curr_mb = &mut result[link2mb[i]];
            link_id2new_id[i] = curr_mb.links.len();

            if is_new_root {
                let joint = MultibodyJoint::fixed(*link.local_to_world());
                link.joint = joint;
                joint_replaced[i] = true;
            }

            curr_mb.ndofs += link.joint().ndofs();
            curr_mb.links.push(link);
        }

        // Adjust all the internal ids, and copy the data from the
        // previous multibody to the new one.
        for mb in &mut result {
            mb.grow_buffers(mb.ndofs, mb.links.len());
            mb.workspace.resize(mb.links.len(), mb.ndofs);

            let mut assembly_id = 0;
            for (i, link) in mb.links.iter_mut().enumerate() {
                let link_ndofs = link.joint().ndofs();
                mb.velocities
                    .rows_mut(assembly_id, link_ndofs)
                    .copy_from(&self.velocities.rows(link.assembly_id, link_ndofs));
                mb.damping
                    .rows_mut(assembly_id, link_ndofs)
                    .copy_from(&self.damping.rows(link.assembly_id, link_ndofs));
                mb.armature
                    .rows_mut(assembly_id, link_ndofs)
                    .copy_from(&self.armature.rows(link.assembly_id, link_ndofs));
                mb.frictions
                    .rows_mut(assembly_id, link_ndofs)
                    .copy_from(&self.frictions.rows(link.assembly_id, link_ndofs));
                mb.accelerations
                    .rows_mut(assembly_id, link_ndofs)
                    .copy_from(&self.accelerations.rows(link.assembly_id, link_ndofs));

                link.internal_id = i;
                link.assembly_id = assembly_id;

                // NOTE: for the root, the current`link.parent_internal_id` is invalid since that
                //       parent lies in a different multibody now.
                link.parent_internal_id = if i != 0 {
                    link_id2new_id[link.parent_internal_id]
                } else {
                    0
                };
                assembly_id += link_ndofs;
            }
        }

        // Keep the couplings whose DoFs still exist and ended up in the same multibody.
        for coupling in &self.couplings {
            let (l1, l2) = (coupling.link1, coupling.link2);
            let kept = |l: usize| link_id2new_id[l] != usize::MAX && !joint_replaced[l];
            if kept(l1) && kept(l2) && link2mb[l1] == link2mb[l2] {
                result[link2mb[l1]].couplings.push(MultibodyDofCoupling {
                    link1: link_id2new_id[l1],
                    link2: link_id2new_id[l2],
                    ..*coupling
                });
            }
        }

        result
    }

    pub(crate) fn append(&mut self, mut rhs: Multibody, parent: usize, joint: MultibodyJoint) {
        let joint_ndofs = joint.ndofs();
        let rhs_root_ndofs = rhs.links[0].joint.ndofs();
        let ndofs_before_append = self.velocities.len();
        let base_internal_id = self.links.len();
        // Values for rhs will be copied into the buffers of `self` starting at this index.
        let rhs_copy_shift = ndofs_before_append + joint_ndofs;
        // Number of dofs to copy from rhs. The root’s dofs isn’t included because it will be
        // replaced by `joint`.
        let rhs_copy_ndofs = rhs.ndofs - rhs_root_ndofs;

        // Adjust the ids of all the rhs links except the first one.
        for link in &mut rhs.links.0[1..] {
            link.assembly_id =
                (link.assembly_id + ndofs_before_append + joint_ndofs) - rhs_root_ndofs;
            link.internal_id += base_internal_id;
            link.parent_internal_id += base_internal_id;
        }

        // Adjust the first link.
        {
            rhs.links[0].joint = joint;
            rhs.links[0].assembly_id = ndofs_before_append;
            rhs.links[0].internal_id = base_internal_id;
            rhs.links[0].parent_internal_id = parent;
        }

        // Grow buffers then append data from rhs.
        self.grow_buffers(rhs_copy_ndofs + joint_ndofs, rhs.links.len());

        if rhs_copy_ndofs > 0 {
            self.velocities
                .rows_mut(rhs_copy_shift, rhs_copy_ndofs)
                .copy_from(&rhs.velocities.rows(rhs_root_ndofs, rhs_copy_ndofs));
            self.damping
                .rows_mut(rhs_copy_shift, rhs_copy_ndofs)
                .copy_from(&rhs.damping.rows(rhs_root_ndofs, rhs_copy_ndofs));
            self.armature
                .rows_mut(rhs_copy_shift, rhs_copy_ndofs)
                .copy_from(&rhs.armature.rows(rhs_root_ndofs, rhs_copy_ndofs));
            self.frictions
                .rows_mut(rhs_copy_shift, rhs_copy_ndofs)
                .copy_from(&rhs.frictions.rows(rhs_root_ndofs, rhs_copy_ndofs));
            self.accelerations
                .rows_mut(rhs_copy_shift, rhs_copy_ndofs)
                .copy_from(&rhs.accelerations.rows(rhs_root_ndofs, rhs_copy_ndofs));
        }

        // Set the default damping for the new joint.
        rhs.links[0]
            .joint
            .default_damping(&mut self.damping.rows_mut(ndofs_before_append, joint_ndofs));

        self.links.append(&mut rhs.links);
        self.ndofs = self.velocities.len();
        self.workspace.resize(self.links.len(), self.ndofs);

        // The rhs couplings follow its links, except the ones on its root whose joint was replaced.
        self.couplings.extend(
            rhs.couplings
                .iter()
                .filter(|c| c.link1 != 0 && c.link2 != 0)
                .map(|c| MultibodyDofCoupling {
                    link1: c.link1 + base_internal_id,
                    link2: c.link2 + base_internal_id,
                    ..*c
                }),
        );
        // Self-contacts stay disabled for the links of a multibody that had them disabled.
        self.self_contacts_enabled &= rhs.self_contacts_enabled;
        // The explicit Coriolis forces only if both parts had them (the default otherwise).
        self.explicit_coriolis &= rhs.explicit_coriolis;
    }

    /// Whether self-contacts are enabled on this multibody.
    ///
    /// If set to `false` no two link from this multibody can generate contacts, even
    /// if the contact is enabled on the individual joint with [`GenericJoint::contacts_enabled`].
    pub fn self_contacts_enabled(&self) -> bool {
        self.self_contacts_enabled
    }

    /// Sets whether self-contacts are enabled on this multibody.
    ///
    /// If set to `false` no two link from this multibody can generate contacts, even
    /// if the contact is enabled on the individual joint with [`GenericJoint::contacts_enabled`].
    pub fn set_self_contacts_enabled(&mut self, enabled: bool) {
        self.self_contacts_enabled = enabled;
    }

    /// Whether the Coriolis, centrifugal and gyroscopic forces are integrated explicitly; see
    /// [`Self::set_explicit_coriolis`].
    pub fn explicit_coriolis(&self) -> bool {
        self.explicit_coriolis
    }

    /// Sets whether the Coriolis, centrifugal and gyroscopic forces are integrated explicitly.
    ///
    /// By default (`false`) the velocity update is semi-implicit in them: each step assembles,
    /// besides the augmented mass matrix `M`, a second matrix `M + dt·∂c/∂q̇` (`c` those forces)
    /// and factorises it, and an energy check solves again with `M` alone when the semi-implicit
    /// update would add energy. Explicit (`true`) solves `M·q̈ = f − c(q, q̇)` with the factors of
    /// `M` that the constraints use, as MuJoCo's default Euler integrator does: the second
    /// matrix, its factorisation and the energy check are skipped, which roughly halves the
    /// mass matrix update's cost. The velocity update is then the same as the energy check's
    /// fallback. It suits a multibody whose links turn slowly compared with `1 / dt` (a robot
    /// at a millisecond step); a fast spinning link can gain energy.
    ///
    /// A multibody split off this one keeps the setting; one made by joining two has it only if
    /// both had it.
    pub fn set_explicit_coriolis(&mut self, explicit: bool) {
        self.explicit_coriolis = explicit;
    }

    /// The inverse augmented mass matrix of this multibody, as a dense LU factorisation.
    ///
    /// rapier itself solves with [`Self::augmented_mass_factors`]; this dense LU is computed from
    /// the same matrix on the first call after each mass matrix update.
    pub fn inv_augmented_mass(&self) -> &LU<Real, Dyn, Dyn> {
        self.inv_augmented_mass.get_or_init(|| {
            let n = self.mass_factors.dim();
            LU::new(self.augmented_mass.view((0, 0), (n, n)).into_owned())
        })
    }

    /// The factors of the augmented mass matrix ([`TreeLu`]), in the order of the generalized
    /// coordinates with the kinematic degrees of freedom removed (without kinematic joints: the
    /// generalized coordinates' order).
    pub fn augmented_mass_factors(&self) -> &TreeLu {
        &self.mass_factors
    }

    /// Solves `M·x = b` in place for each column of `b` (`ndofs` rows, in the order of the
    /// generalized coordinates), `M` the augmented mass matrix; a kinematic degree of freedom's
    /// entry of `x` is zero.
    pub fn solve_augmented_mass_mut<C: na::Dim, S: StorageMut<Real, Dyn, C>>(
        &self,
        b: &mut na::Matrix<Real, Dyn, C, S>,
    ) {
        let factors = &self.mass_factors;
        self.augmented_mass_indices
            .with_rearranged_rows_mut(b, |b| {
                factors.solve_mut(b);
            });
    }

    /// The first link of this multibody.
    #[inline]
    pub fn root(&self) -> &MultibodyLink {
        &self.links[0]
    }

    /// Mutable reference to the first link of this multibody.
    #[inline]
    pub fn root_mut(&mut self) -> &mut MultibodyLink {
        &mut self.links[0]
    }

    /// Reference `i`-th multibody link of this multibody.
    ///
    /// Return `None` if there is less than `i + 1` multibody links.
    #[inline]
    pub fn link(&self, id: usize) -> Option<&MultibodyLink> {
        self.links.get(id)
    }

    /// Mutable reference to the multibody link with the given id.
    ///
    /// Return `None` if the given id does not identifies a multibody link part of `self`.
    #[inline]
    pub fn link_mut(&mut self, id: usize) -> Option<&mut MultibodyLink> {
        self.links.get_mut(id)
    }

    /// The number of links on this multibody.
    pub fn num_links(&self) -> usize {
        self.links.len()
    }

    /// Iterator through all the links of this multibody.
    ///
    /// All link are guaranteed to be yielded before its descendant.
    pub fn links(&self) -> impl Iterator<Item = &MultibodyLink> {
        self.links.iter()
    }

    /// Mutable iterator through all the links of this multibody.
    ///
    /// All link are guaranteed to be yielded before its descendant.
    pub fn links_mut(&mut self) -> impl Iterator<Item = &mut MultibodyLink> {
        self.links.iter_mut()
    }

    /// The vector of damping applied to this multibody.
    #[inline]
    pub fn damping(&self) -> &DVector {
        &self.damping
    }

    /// Mutable vector of damping applied to this multibody.
    #[inline]
    pub fn damping_mut(&mut self) -> &mut DVector {
        &mut self.damping
    }

    /// The vector of per-DoF armature (reflected rotor inertia) of this multibody: additional
    /// inertia added directly to the mass matrix, simulating the joint's own weight distribution.
    #[inline]
    pub fn armature(&self) -> &DVector {
        &self.armature
    }

    /// Mutable vector of per-DoF armature (reflected rotor inertia) of this
    /// multibody.
    #[inline]
    pub fn armature_mut(&mut self) -> &mut DVector {
        &mut self.armature
    }

    /// The vector of per-DoF dry joint friction (MuJoCo's `frictionloss`, in N
    /// or N·m): the largest force friction may generate on that DoF.
    #[inline]
    pub fn frictions(&self) -> &DVector {
        &self.frictions
    }

    /// Mutable vector of per-DoF dry joint friction of this multibody.
    #[inline]
    pub fn frictions_mut(&mut self) -> &mut DVector {
        &mut self.frictions
    }

    pub(crate) fn add_link(
        &mut self,
        parent: Option<usize>, // TODO: should be a RigidBodyHandle?
        dof: MultibodyJoint,
        body: RigidBodyHandle,
    ) -> &mut MultibodyLink {
        assert!(
            parent.is_none() || !self.links.is_empty(),
            "Multibody::build_body: invalid parent id."
        );

        /*
         * Compute the indices.
         */
        let assembly_id = self.velocities.len();
        let internal_id = self.links.len();

        /*
         * Grow the buffers.
         */
        let ndofs = dof.ndofs();
        self.grow_buffers(ndofs, 1);
        self.ndofs += ndofs;

        /*
         * Setup default damping.
         */
        dof.default_damping(&mut self.damping.rows_mut(assembly_id, ndofs));

        /*
         * Create the multibody.
         */
        let local_to_parent = dof.body_to_parent();
        let local_to_world;

        let parent_internal_id;
        if let Some(parent) = parent {
            parent_internal_id = parent;
            let parent_link = &mut self.links[parent_internal_id];
            local_to_world = parent_link.local_to_world * local_to_parent;
        } else {
            parent_internal_id = 0;
            local_to_world = local_to_parent;
        }

        let rb = MultibodyLink::new(
            body,
            internal_id,
            assembly_id,
            parent_internal_id,
            dof,
            local_to_world,
            local_to_parent,
        );

        self.links.push(rb);
        self.workspace.resize(self.links.len(), self.ndofs);

        &mut self.links[internal_id]
    }

    fn grow_buffers(&mut self, ndofs: usize, num_jacobians: usize) {
        let len = self.velocities.len();
        self.velocities.resize_vertically_mut(len + ndofs, 0.0);
        self.damping.resize_vertically_mut(len + ndofs, 0.0);
        self.armature.resize_vertically_mut(len + ndofs, 0.0);
        self.frictions.resize_vertically_mut(len + ndofs, 0.0);
        self.accelerations.resize_vertically_mut(len + ndofs, 0.0);
        self.body_jacobians
            .extend((0..num_jacobians).map(|_| Jacobian::zeros(0)));
    }

    pub(crate) fn update_acceleration(&mut self, dt: Real, bodies: &RigidBodySet) {
        if self.ndofs == 0 {
            return; // Nothing to do.
        }

        self.accelerations.fill(0.0);

        // If there is significant movement, the semi-implicit coriolis term
        // occasionally cause instabilities due to the matrix being near singular.
        // To prevent that, we enable a check that verifies the result and fallbacks
        // to the explicit term if needed. With explicit Coriolis forces there is nothing to check:
        // the solve below is with the plain mass matrix already.
        let check_implicit_coriolis_divergence =
            !self.explicit_coriolis && dt * self.velocities.amax() >= 1.0e-3;
        // Generalized forces that derive from positions or external inputs
        // (gravity, user forces, spring position terms). The workspace keeps the vector between
        // steps (taken out meanwhile: the loop below borrows the workspace's paths).
        let mut pos_forces = core::mem::replace(&mut self.workspace.pos_forces, DVector::zeros(0));
        if check_implicit_coriolis_divergence {
            zeroed(&mut pos_forces, self.ndofs);
        }

        // Eqn 42 to 45
        for i in 0..self.links.len() {
            let link = &self.links[i];
            let rb = &bodies[link.rigid_body];

            let mut acc = RigidBodyVelocity::zero();

            if i != 0 {
                let parent_id = link.parent_internal_id;
                let parent_link = &self.links[parent_id];
                let parent_rb = &bodies[parent_link.rigid_body];

                acc += self.workspace.accs[parent_id];
                // The 2.0 originates from the two identical terms of Jdot (the terms become
                // identical once they are multiplied by the generalized velocities).
                acc.linvel += 2.0 * parent_rb.vels.angvel.gcross(link.joint_velocity.linvel);
                #[cfg(feature = "dim3")]
                {
                    acc.angvel += parent_rb.vels.angvel.cross(link.joint_velocity.angvel);
                }

                acc.linvel += parent_rb
                    .vels
                    .angvel
                    .gcross(parent_rb.vels.angvel.gcross(link.shift02));
                acc.linvel += self.workspace.accs[parent_id].angvel.gcross(link.shift02);
            }

            acc.linvel += rb.vels.angvel.gcross(rb.vels.angvel.gcross(link.shift23));
            acc.linvel += acc.angvel.gcross(link.shift23);

            self.workspace.accs[i] = acc;

            // TODO: should gyroscopic forces already be computed by the rigid-body itself
            //       (at the same time that we add the gravity force)?
            let gyroscopic;
            let rb_inertia = rb.mprops.effective_angular_inertia();
            let rb_mass = rb.mprops.effective_mass();

            #[cfg(feature = "dim3")]
            {
                let angvel = rb.vels.angvel;
                let inertia_times_angvel = rb_inertia * angvel;
                gyroscopic = angvel.cross(inertia_times_angvel);
            }
            #[cfg(feature = "dim2")]
            {
                gyroscopic = 0.0;
            }

            let external_forces = Force::new(
                rb.forces.force - rb_mass * acc.linvel,
                rb.forces.torque - gyroscopic - rb_inertia * acc.angvel,
            );
            // `Jᵀ·f` on the link's path: its Jacobian's other columns are zero.
            let ws = &self.workspace;
            let path = &ws.path_dofs[ws.path_start[i]..ws.path_start[i + 1]];
            let body_jacobian = &self.body_jacobians[i];
            for &dof in path {
                self.accelerations[dof] += body_jacobian
                    .fixed_view::<SPATIAL_DIM, 1>(0, dof)
                    .dot(external_forces.as_vector());
            }

            if check_implicit_coriolis_divergence {
                let applied_forces = Force::new(rb.forces.force, rb.forces.torque);
                for &dof in path {
                    pos_forces[dof] += body_jacobian
                        .fixed_view::<SPATIAL_DIM, 1>(0, dof)
                        .dot(applied_forces.as_vector());
                }
            }
        }

        self.accelerations
            .cmpy(-1.0, &self.damping, &self.velocities, 1.0);

        // Implicit joint springs: backward-Euler at `q⁺ = q + dt·v⁺` gives `-k·(q − rest) − k·dt·v⁺`,
        // with the `v⁺` part implicit via the `dt²·k` mass-matrix diagonal (see `update_mass_matrix`).
        // Consistency requires BOTH `-k·(q − rest)` and `-k·dt·v` here, else the spring is only semi-implicit.
        for li in 0..self.links.len() {
            let mut idx = self.links[li].assembly_id;
            let locked = self.links[li].joint.data.locked_axes.bits();
            for a in 0..SPATIAL_DIM {
                if (locked >> a) & 1 == 0 {
                    let k = self.links[li].joint.spring_stiffness[a];
                    if k != 0.0 {
                        let q = self.links[li].joint.coords[a];
                        let rest = self.links[li].joint.spring_ref[a];
                        let spring_pos_force = -k * (q - rest);
                        self.accelerations[idx] += spring_pos_force - k * dt * self.velocities[idx];
                        if check_implicit_coriolis_divergence {
                            pos_forces[idx] += spring_pos_force;
                        }
                    }
                    idx += 1;
                }
            }
        }

        // Snapshot the full generalized forces: the energy guard may need them
        // for a re-solve with the plain mass matrix.
        let mut gen_forces = core::mem::replace(&mut self.workspace.gen_forces, DVector::zeros(0));
        if check_implicit_coriolis_divergence {
            copied(&mut gen_forces, &self.accelerations);
        }

        let factors = if self.explicit_coriolis {
            &self.mass_factors
        } else {
            &self.acc_mass_factors
        };
        self.augmented_mass_indices
            .with_rearranged_rows_mut(&mut self.accelerations, |accs| {
                factors.solve_mut(accs);
            });

        if check_implicit_coriolis_divergence {
            self.free_velocity_energy_guard(dt, &gen_forces, &pos_forces);
        }
        self.workspace.pos_forces = pos_forces;
        self.workspace.gen_forces = gen_forces;
    }

    // If the semi-implicit coriolis solve introduces more energy than the external
    // forces’ work, we recalculate without the coriolis term in the mass matrix.
    //
    // This operates by calculating the effective kinematic energy added by the
    // external forces after the solve with the semi-implicit mass matrix, and
    // compare it with the force’s work. If the energy delta exceeds a threshold
    // (indicating undesired/unrealistic energy injection), we fall back to re-solving
    // the forces effect but using only the mass matrix without the implicit coriolis
    // terms.
    fn free_velocity_energy_guard(&mut self, dt: Real, gen_forces: &DVector, pos_forces: &DVector) {
        let eff_dim = self.augmented_mass_indices.dim_after_removal(self.ndofs);
        if eff_dim == 0 {
            return;
        }

        // Move all quantities to the kinematic-reduced ordering of the
        // factorized matrices (no-op when there is no kinematic dof), in the workspace's vectors.
        let ws = &mut self.workspace;
        let indices = &self.augmented_mass_indices;
        for (to, from) in [
            (&mut ws.guard_velocities, &self.velocities),
            (&mut ws.guard_forces, gen_forces),
            (&mut ws.guard_pos_forces, pos_forces),
            (&mut ws.guard_accelerations, &self.accelerations),
        ] {
            copied(to, from);
            indices.rearrange_rows(to, true);
        }
        if ws.guard_product.len() != eff_dim {
            ws.guard_product = DVector::zeros(eff_dim);
        }

        let m = self.augmented_mass.view((0, 0), (eff_dim, eff_dim));
        let v = ws.guard_velocities.rows(0, eff_dim);
        let f = ws.guard_forces.rows(0, eff_dim);
        let f_pos = ws.guard_pos_forces.rows(0, eff_dim);
        let a = ws.guard_accelerations.rows(0, eff_dim);
        let product = &mut ws.guard_product;

        let excess = if !a.iter().all(|x| x.is_finite()) {
            None
        } else {
            product.gemv(1.0, &m, &a, 0.0);
            let energy_delta = dt * v.dot(product) + 0.5 * dt * dt * a.dot(product);
            let work = dt * v.dot(&f) + 0.5 * dt * dt * a.dot(&f_pos);
            // Margin: a small fraction of the current kinetic energy to absorb
            // discretization error on healthy steps.
            product.gemv(1.0, &m, &v, 0.0);
            let kinetic_energy = 0.5 * v.dot(product);
            let energy_margin = 1.0e-2 * kinetic_energy + 1.0e-8;
            Some(energy_delta - work - energy_margin)
        };

        match excess {
            Some(excess) if excess <= 0.0 => (), // Implicit update didn’t introduce too much extra energy.
            _ => {
                // The implicit solve injected energy (or produced non-finite
                // values): fall back to the plain mass matrix.
                self.accelerations.copy_from(gen_forces);
                self.augmented_mass_indices.with_rearranged_rows_mut(
                    &mut self.accelerations,
                    |accs| {
                        self.mass_factors.solve_mut(accs);
                    },
                );

                // Last-chance check: if all else fails, just clear the accelerations vector
                // instead of breaking the simulation. Hopefully it will get back to a
                // sane result in a close timestep.
                if !self.accelerations.iter().all(|x| x.is_finite()) {
                    self.accelerations.fill(0.0);
                }
            }
        }
    }

    /// Computes the constant terms of the dynamics.
    #[profiling::function]
    pub(crate) fn update_velocities(&mut self, bodies: &mut RigidBodySet) {
        /*
         * Compute velocities.
         * NOTE: this is needed for kinematic bodies too.
         */
        let link = &mut self.links[0];
        let joint_velocity = link
            .joint
            .jacobian_mul_coordinates(&self.velocities.as_slice()[link.assembly_id..]);

        link.joint_velocity = joint_velocity;
        bodies.index_mut_internal(link.rigid_body).vels = link.joint_velocity;

        for i in 1..self.links.len() {
            let (link, parent_link) = self.links.get_mut_with_parent(i);
            let rb = &bodies[link.rigid_body];
            let parent_rb = &bodies[parent_link.rigid_body];

            let joint_velocity = link
                .joint
                .jacobian_mul_coordinates(&self.velocities.as_slice()[link.assembly_id..]);
            link.joint_velocity = joint_velocity.transformed(
                &(parent_link.local_to_world.rotation * link.joint.data.local_frame1.rotation),
            );
            let mut new_rb_vels = parent_rb.vels + link.joint_velocity;
            let shift = rb.mprops.world_com - parent_rb.mprops.world_com;
            new_rb_vels.linvel += parent_rb.vels.angvel.gcross(shift);
            new_rb_vels.linvel += link.joint_velocity.angvel.gcross(link.shift23);

            bodies.index_mut_internal(link.rigid_body).vels = new_rb_vels;
        }
    }

    /// Computes each link's body Jacobian (the map from generalized velocities to the twist of
    /// its centre of mass) from its parent's, on the degrees of freedom of its path to the root
    /// only: the other columns are zero (see [`MultibodyWorkspace::update_paths`]).
    fn update_body_jacobians(&mut self) {
        self.workspace.update_paths(&self.links);
        let ws = &self.workspace;

        for i in 0..self.links.len() {
            let link = &self.links[i];

            if self.body_jacobians[i].ncols() != self.ndofs {
                // TODO: use a resize instead.
                self.body_jacobians[i] = Jacobian::zeros(self.ndofs);
            }

            let parent_to_world;
            let path = &ws.path_dofs[ws.path_start[i]..ws.path_start[i + 1]];
            let ndofs = link.joint.ndofs();

            if i != 0 {
                let parent_id = link.parent_internal_id;
                let parent_link = &self.links[parent_id];
                parent_to_world = parent_link.local_to_world;

                let (link_j, parent_j) = self.body_jacobians.index_mut_const(i, parent_id);
                // (a slice's fill is a memset; a matrix's goes element by element)
                link_j.as_mut_slice().fill(0.0);

                // The parent's columns, its angular velocity moving this link's joint by `shift02`.
                let shift_tr = vect_to_na(link.shift02).gcross_matrix_tr();
                for &dof in &path[..path.len() - ndofs] {
                    let parent_col = parent_j.fixed_view::<SPATIAL_DIM, 1>(0, dof);
                    let mut link_col = link_j.fixed_view_mut::<SPATIAL_DIM, 1>(0, dof);
                    link_col.copy_from(&parent_col);
                    let parent_w = parent_col.fixed_rows::<ANG_DIM>(DIM);
                    link_col
                        .fixed_rows_mut::<DIM>(0)
                        .gemm(1.0, &shift_tr, &parent_w, 1.0);
                }
            } else {
                self.body_jacobians[i].as_mut_slice().fill(0.0);
                parent_to_world = Pose::IDENTITY;
            }

            let mut tmp = SMatrix::<Real, SPATIAL_DIM, SPATIAL_DIM>::zeros();
            let mut link_joint_j = tmp.columns_mut(0, ndofs);
            let mut link_j_part = self.body_jacobians[i].columns_mut(link.assembly_id, ndofs);
            link.joint.jacobian(
                &(parent_to_world.rotation * link.joint.data.local_frame1.rotation),
                &mut link_joint_j,
            );
            link_j_part += link_joint_j;

            {
                let link_j = &mut self.body_jacobians[i];
                let shift_tr = vect_to_na(link.shift23).gcross_matrix_tr();
                for &dof in path {
                    let mut col = link_j.fixed_view_mut::<SPATIAL_DIM, 1>(0, dof);
                    let w = col.fixed_rows::<ANG_DIM>(DIM).into_owned();
                    col.fixed_rows_mut::<DIM>(0).gemm(1.0, &shift_tr, &w, 1.0);
                }
            }
        }
    }

    /// Assembles the mass matrix `M = Σᵢ Jᵢᵀ·Mᵢ·Jᵢ` (`augmented_mass`) and the matrix of the
    /// semi-implicit velocity update (`acc_augmented_mass`: `M` plus `dt` times the derivatives
    /// of the gyroscopic and Coriolis forces), then factorises both; with explicit Coriolis forces
    /// ([`Self::set_explicit_coriolis`]) only `M`, without the Coriolis terms.
    ///
    /// A link's velocity depends only on the degrees of freedom of the joints between it and the
    /// root, so its body Jacobian `Jᵢ` is zero outside those columns (a leg's foot on a
    /// floating base: 9 of 24 columns). Each link's terms are computed on those columns alone
    /// (`MultibodyWorkspace::path_dofs`), in the order root first, so that a link's columns begin
    /// with its parent's and the Coriolis terms it inherits are a prefix.
    ///
    /// The sums over links are then taken the way the composite-rigid-body algorithm takes them
    /// (Featherstone, *Rigid Body Dynamics Algorithms*, §6.2): a degree of freedom `a` moves all
    /// the links below its joint with one twist `Sₐ`, so `Jᵢ`'s column `a` is `Sₐ` seen from link
    /// `i`'s centre of mass, and `Σᵢ Jᵢ[a]ᵀ·Fᵢ[b]` is `Sₐᵀ` times the sum of the wrenches
    /// `Fᵢ[b] = Mᵢ·Jᵢ[b]` (and their semi-implicit counterparts) over the links below both `a`'s
    /// and `b`'s joints, taken about one reference point (the root link's centre of mass). Those
    /// wrenches are summed from the leaves up, one addition per path entry, and each matrix entry
    /// is one product: `O(Σᵢ pathᵢ)` work instead of the `O(Σᵢ pathᵢ²)` products of summing
    /// `Jᵢᵀ·Mᵢ·Jᵢ` link by link, or the `O(links·ndofs²)` of the dense assembly.
    pub(crate) fn update_mass_matrix(&mut self, dt: Real, bodies: &RigidBodySet) {
        if self.ndofs == 0 {
            return; // Nothing to do.
        }

        // The semi-implicit update's matrix, unless the Coriolis forces are explicit.
        let semi_implicit = !self.explicit_coriolis;
        if self.augmented_mass.ncols() != self.ndofs {
            // TODO: do a resize instead of a full reallocation.
            self.augmented_mass = DMatrix::zeros(self.ndofs, self.ndofs);
        } else {
            self.augmented_mass.as_mut_slice().fill(0.0);
        }
        if semi_implicit {
            if self.acc_augmented_mass.ncols() != self.ndofs {
                self.acc_augmented_mass = DMatrix::zeros(self.ndofs, self.ndofs);
            } else {
                self.acc_augmented_mass.as_mut_slice().fill(0.0);
            }
        }

        self.augmented_mass_indices.clear();
        // The paths are listed by `forward_kinematics`, which always runs first; a multibody
        // whose links changed since lists them anew.
        if self.workspace.path_start.len() != self.links.len() + 1 {
            self.workspace.update_paths(&self.links);
        }

        let mut curr_assembly_id = 0;

        for i in 0..self.links.len() {
            let link = &self.links[i];
            let rb = &bodies[link.rigid_body];
            let rb_mass = rb.mprops.effective_mass();
            let rb_inertia = rb.mprops.effective_angular_inertia().into_matrix();

            // NOTE: the mass matrix index reordering operates on the assumption that the assembly
            //       ids are traversed in order. This assert is here to ensure the assumption always
            //       hold.
            assert_eq!(
                curr_assembly_id, link.assembly_id,
                "Internal error: contiguity assumption on assembly_id does not hold."
            );
            curr_assembly_id += link.joint.ndofs();

            if link.joint.kinematic {
                for k in link.assembly_id..link.assembly_id + link.joint.ndofs() {
                    self.augmented_mass_indices.remove(k);
                }
            } else {
                for k in link.assembly_id..link.assembly_id + link.joint.ndofs() {
                    self.augmented_mass_indices.keep(k);
                }
            }

            let ws = &mut self.workspace;
            let path = ws.path_start[i]..ws.path_start[i + 1];
            let ndofs = link.joint.ndofs();

            // This link's body Jacobian on its path.
            {
                let body_jacobian = &self.body_jacobians[i];
                for (col, &dof) in ws.path_jacobians[path.clone()]
                    .iter_mut()
                    .zip(&ws.path_dofs[path.clone()])
                {
                    *col = body_jacobian.column(dof).into_owned();
                }
            }

            // This link's centre of mass from the root's, the reference point of the wrenches and
            // twists below: the Jacobians' points follow one another by `shift02` and `shift23`.
            let point = if i == 0 {
                Vector::ZERO
            } else {
                ws.link_points[link.parent_internal_id] + link.shift02 + link.shift23
            };
            ws.link_points[i] = point;
            let point = vect_to_na(point);

            if semi_implicit {
                /*
                 *
                 * Coriolis matrix (the columns of `JDot + JDot/u * qdot` on the path).
                 *
                 */
                if i != 0 {
                    let parent_id = link.parent_internal_id;
                    let parent_link = &self.links[parent_id];
                    let parent_rb = &bodies[parent_link.rigid_body];
                    let parent_w =
                        SimdAngVector::<Real>::from(parent_rb.vels.angvel).gcross_matrix();
                    let parent_path = ws.path_start[parent_id]..ws.path_start[parent_id + 1];
                    let parent_len = parent_path.len();

                    // [c1 - c0].gcross() * (JDot + JDot/u * qdot)"
                    let shift_cross_tr = vect_to_na(link.shift02).gcross_matrix_tr();
                    // JDot (but the 2.0 originates from the sum of two identical terms in JDot and
                    // JDot/u * gdot), JDot/u * qdot, and the parent's rotation of the shift: all
                    // multiply the parent's angular Jacobian.
                    let parent_j_w_coeff = vect_to_na(
                        rb.vels.angvel.gcross(link.shift02) + 2.0 * link.joint_velocity.linvel,
                    )
                    .gcross_matrix_tr()
                        + vect_to_na(link.joint_velocity.linvel).gcross_matrix_tr()
                        + parent_w * shift_cross_tr;
                    #[cfg(feature = "dim3")]
                    let vel_wrt_joint_w = vect_to_na(link.joint_velocity.angvel).gcross_matrix();

                    for k in 0..parent_len {
                        let parent_j_w =
                            ws.path_jacobians[parent_path.start + k].fixed_rows::<ANG_DIM>(DIM);
                        let parent_coriolis_w = ws.path_coriolis_w[parent_path.start + k];
                        ws.path_coriolis_v[path.start + k] = ws.path_coriolis_v
                            [parent_path.start + k]
                            + shift_cross_tr * parent_coriolis_w
                            + parent_j_w_coeff * parent_j_w;
                        #[cfg(feature = "dim3")]
                        {
                            ws.path_coriolis_w[path.start + k] =
                                parent_coriolis_w - vel_wrt_joint_w * parent_j_w;
                        }
                        #[cfg(feature = "dim2")]
                        {
                            ws.path_coriolis_w[path.start + k] = parent_coriolis_w;
                        }
                    }

                    // The link's own degrees of freedom end its path.
                    let own = path.start + parent_len..path.end;
                    for k in own.clone() {
                        ws.path_coriolis_v[k].fill(0.0);
                        ws.path_coriolis_w[k].fill(0.0);
                    }

                    // JDot (but the 2.0 originates from the sum of two identical terms in JDot and JDot/u * gdot)
                    if !link.joint.kinematic {
                        let mut tmp1 = SMatrix::<Real, SPATIAL_DIM, SPATIAL_DIM>::zeros();
                        let mut rb_joint_j = tmp1.columns_mut(0, ndofs);
                        link.joint.jacobian(
                            &(parent_link.local_to_world.rotation
                                * link.joint.data.local_frame1.rotation),
                            &mut rb_joint_j,
                        );

                        for (j, k) in own.enumerate() {
                            let rb_joint_j_v = tmp1.fixed_view::<DIM, 1>(0, j);
                            ws.path_coriolis_v[k] += parent_w * rb_joint_j_v * 2.0;

                            #[cfg(feature = "dim3")]
                            {
                                let rb_joint_j_w = tmp1.fixed_view::<ANG_DIM, 1>(DIM, j);
                                ws.path_coriolis_w[k] += parent_w * rb_joint_j_w;
                            }
                        }
                    }
                } else {
                    for k in path.clone() {
                        ws.path_coriolis_v[k].fill(0.0);
                        ws.path_coriolis_w[k].fill(0.0);
                    }
                }

                {
                    // [c3 - c2].gcross() * (JDot + JDot/u * qdot)
                    let shift_cross_tr = vect_to_na(link.shift23).gcross_matrix_tr();
                    // JDot and JDot/u * qdot: both multiply the link's angular Jacobian.
                    let rb_j_w_coeff = vect_to_na(rb.vels.angvel.gcross(link.shift23))
                        .gcross_matrix_tr()
                        + SimdAngVector::<Real>::from(rb.vels.angvel).gcross_matrix()
                            * shift_cross_tr;

                    for k in path.clone() {
                        let rb_j_w = ws.path_jacobians[k].fixed_rows::<ANG_DIM>(DIM);
                        let coriolis_w = ws.path_coriolis_w[k];
                        ws.path_coriolis_v[k] +=
                            shift_cross_tr * coriolis_w + rb_j_w_coeff * rb_j_w;
                    }
                }
            }

            /*
             * The wrenches `Mᵢ·J` and `Mᵢ·J + dt·G·J_w + dt·Mᵢ·C` (`G` the derivative of the
             * gyroscopic forces, `C` the Coriolis matrix), a column on the path at a time, about
             * the reference point.
             */
            let rb_mass_na = vect_to_na(rb_mass);
            if semi_implicit {
                let rb_mass_dt = vect_to_na(rb_mass * dt);
                #[cfg(feature = "dim3")]
                let (rb_inertia_na, gyroscopic_dt) = {
                    // Derivative of gyroscopic forces.
                    let gyroscopic_matrix = rb.vels.angvel.gcross_matrix() * rb_inertia
                        - (rb_inertia * rb.vels.angvel).gcross_matrix();
                    (mat_to_na(rb_inertia), mat_to_na(gyroscopic_matrix * dt))
                };

                for k in path.clone() {
                    let j = &ws.path_jacobians[k];
                    let j_v = j.fixed_rows::<DIM>(0);
                    let j_w = j.fixed_rows::<ANG_DIM>(DIM);
                    let coriolis_v = &ws.path_coriolis_v[k];
                    let coriolis_w = &ws.path_coriolis_w[k];
                    let mut mass_col = SVector::<Real, SPATIAL_DIM>::zeros();
                    let mut acc_col = SVector::<Real, SPATIAL_DIM>::zeros();

                    mass_col
                        .fixed_rows_mut::<DIM>(0)
                        .copy_from(&j_v.component_mul(&rb_mass_na));
                    acc_col.fixed_rows_mut::<DIM>(0).copy_from(
                        &(j_v.component_mul(&rb_mass_na) + coriolis_v.component_mul(&rb_mass_dt)),
                    );

                    #[cfg(feature = "dim3")]
                    {
                        let i_j_w = rb_inertia_na * j_w;
                        mass_col.fixed_rows_mut::<ANG_DIM>(DIM).copy_from(&i_j_w);
                        acc_col.fixed_rows_mut::<ANG_DIM>(DIM).copy_from(
                            &(i_j_w + gyroscopic_dt * j_w + rb_inertia_na * coriolis_w * dt),
                        );
                    }
                    #[cfg(feature = "dim2")]
                    {
                        let i_j_w = j_w * rb_inertia;
                        mass_col.fixed_rows_mut::<ANG_DIM>(DIM).copy_from(&i_j_w);
                        acc_col
                            .fixed_rows_mut::<ANG_DIM>(DIM)
                            .copy_from(&(i_j_w + coriolis_w * (dt * rb_inertia)));
                    }

                    ws.path_mass_wrenches[k] = wrench_at_reference(&mass_col, &point);
                    ws.path_acc_wrenches[k] = wrench_at_reference(&acc_col, &point);
                }
            } else {
                #[cfg(feature = "dim3")]
                let rb_inertia_na = mat_to_na(rb_inertia);
                for k in path.clone() {
                    let j = &ws.path_jacobians[k];
                    let j_v = j.fixed_rows::<DIM>(0);
                    let j_w = j.fixed_rows::<ANG_DIM>(DIM);
                    let mut mass_col = SVector::<Real, SPATIAL_DIM>::zeros();
                    mass_col
                        .fixed_rows_mut::<DIM>(0)
                        .copy_from(&j_v.component_mul(&rb_mass_na));
                    #[cfg(feature = "dim3")]
                    mass_col
                        .fixed_rows_mut::<ANG_DIM>(DIM)
                        .copy_from(&(rb_inertia_na * j_w));
                    #[cfg(feature = "dim2")]
                    mass_col
                        .fixed_rows_mut::<ANG_DIM>(DIM)
                        .copy_from(&(j_w * rb_inertia));
                    ws.path_mass_wrenches[k] = wrench_at_reference(&mass_col, &point);
                }
            }

            // The twists of the link's own degrees of freedom about the reference point.
            for k in path.end - ndofs..path.end {
                ws.dof_motions[ws.path_dofs[k]] = twist_at_reference(&ws.path_jacobians[k], &point);
            }
        }

        /*
         * Each link's wrenches summed over the links below it, from the leaves up (a link's path
         * begins with its parent's), then each entry `(a, b)` of both matrices as `Sₐᵀ` times the
         * sum for column `b` at the deeper of `a`'s and `b`'s links: set once per entry, on the
         * link that owns the deeper degree of freedom. `M` is symmetric: its entries above the
         * diagonal are mirrored.
         */
        let ws = &mut self.workspace;
        for i in (1..self.links.len()).rev() {
            let parent = self.links[i].parent_internal_id;
            let parent_start = ws.path_start[parent];
            let parent_len = ws.path_start[parent + 1] - parent_start;
            let start = ws.path_start[i];
            for k in 0..parent_len {
                let mass_wrench = ws.path_mass_wrenches[start + k];
                ws.path_mass_wrenches[parent_start + k] += mass_wrench;
                if semi_implicit {
                    let acc_wrench = ws.path_acc_wrenches[start + k];
                    ws.path_acc_wrenches[parent_start + k] += acc_wrench;
                }
            }
        }

        let n = self.ndofs;
        let mass = self.augmented_mass.as_mut_slice();
        let acc_mass = self.acc_augmented_mass.as_mut_slice();
        // Column-major: entry (row, col) at `row + col * n`.
        for (i, link) in self.links.iter().enumerate() {
            let path = ws.path_start[i]..ws.path_start[i + 1];
            let own_start = path.end - link.joint.ndofs();
            for ka in own_start..path.end {
                let a = ws.path_dofs[ka];
                let motion_a = &ws.dof_motions[a];
                for kb in path.start..=ka {
                    let b = ws.path_dofs[kb];
                    let m = dot_spatial(motion_a, &ws.path_mass_wrenches[kb]);
                    mass[a + b * n] = m;
                    mass[b + a * n] = m;
                    if semi_implicit {
                        acc_mass[a + b * n] = dot_spatial(motion_a, &ws.path_acc_wrenches[kb]);
                        if kb < ka {
                            acc_mass[b + a * n] =
                                dot_spatial(&ws.dof_motions[b], &ws.path_acc_wrenches[ka]);
                        }
                    }
                }
            }
        }

        /*
         * Damping and armature.
         *
         * Damping is a velocity-proportional force made implicit, so it adds
         * `dt · d` to the mass-matrix diagonal. Armature is a "reflected
         * rotor inertia" (additional inertia to account for the joint’s
         * mass and geometry itself): it adds to the diagonal directly.
         */
        for i in 0..self.ndofs {
            let diag = self.damping[i] * dt + self.armature[i];
            if semi_implicit {
                self.acc_augmented_mass[(i, i)] += diag;
            }
            self.augmented_mass[(i, i)] += diag;
        }

        // Implicit joint springs: `dt²·k` on the mass-matrix diagonal (force term in `update_acceleration`)
        // keeps a stiff spring on a low-inertia link stable where an explicit position motor injects energy.
        // The spring lives on the link's `MultibodyJoint` so it travels with the link through topology changes.
        let dt2 = dt * dt;
        for li in 0..self.links.len() {
            let mut idx = self.links[li].assembly_id;
            let locked = self.links[li].joint.data.locked_axes.bits();
            for a in 0..SPATIAL_DIM {
                if (locked >> a) & 1 == 0 {
                    let k = self.links[li].joint.spring_stiffness[a];
                    if k != 0.0 {
                        let d = k * dt2;
                        if semi_implicit {
                            self.acc_augmented_mass[(idx, idx)] += d;
                        }
                        self.augmented_mass[(idx, idx)] += d;
                    }
                    idx += 1;
                }
            }
        }

        let effective_dim = self
            .augmented_mass_indices
            .dim_after_removal(self.augmented_mass.nrows());

        // PERF: since we clone the matrix anyway for LU, should be directly output
        //       a new matrix instead of applying permutations?
        if semi_implicit {
            self.augmented_mass_indices
                .rearrange_columns(&mut self.acc_augmented_mass, true);
        }
        self.augmented_mass_indices
            .rearrange_columns(&mut self.augmented_mass, true);

        if semi_implicit {
            self.augmented_mass_indices
                .rearrange_rows(&mut self.acc_augmented_mass, true);
        }
        self.augmented_mass_indices
            .rearrange_rows(&mut self.augmented_mass, true);

        // Factorise both along the tree of degrees of freedom (no fill-in, no allocation once
        // sized); the dense LU of the public `inv_augmented_mass` waits until it is asked for.
        self.workspace.update_dof_parents(&self.links);
        debug_assert_eq!(self.workspace.dof_parents.len(), effective_dim);
        if semi_implicit {
            self.acc_mass_factors
                .factorize(&self.acc_augmented_mass, &self.workspace.dof_parents);
        }
        self.mass_factors
            .factorize(&self.augmented_mass, &self.workspace.dof_parents);
        self.inv_augmented_mass.take();
    }

    /// Per-DoF inverse joint-space inertia `diag(M⁻¹)` at the current configuration, where `M`
    /// includes armature but excludes joint damping and springs — MuJoCo's `dof_invweight0`: the
    /// apparent inverse inertia at each DoF with all other DoFs free, including the articulated
    /// coupling. Re-runs forward kinematics and reassembles the mass matrix, so intended for
    /// occasional use (e.g. sizing `<joint springdamper>` springs at load time), not every step.
    pub fn dof_inverse_inertia(&mut self, bodies: &RigidBodySet) -> DVector {
        // Resolve the root joint type (a fixed base may still be a 6-DoF free root pre-collapse)
        // so `ndofs` is final, then assemble `M`. `dt = 0` drops the `dt·damping` and
        // `dt²·stiffness` diagonal terms, leaving exactly `M + armature`.
        self.forward_kinematics(bodies, false);
        self.update_mass_matrix(0.0, bodies);

        let n = self.ndofs;
        let mut out = DVector::zeros(n);
        if n == 0 {
            return out;
        }
        // `(M⁻¹)[i, i]` for each DoF: solve `M x = e_i` and read `x[i]`. The `inv_augmented_mass`
        // factorization lives in the kinematic-reduced ordering, so route the unit vector through
        // the same rearrangement the solver uses.
        let mut e = DVector::zeros(n);
        for i in 0..n {
            e.fill(0.0);
            e[i] = 1.0;
            self.augmented_mass_indices
                .with_rearranged_rows_mut(&mut e, |b| {
                    self.mass_factors.solve_mut(b);
                });
            out[i] = e[i];
        }
        out
    }

    /// Adds a holonomic coupling between two of this multibody's generalized
    /// coordinates (`q2 = coeff·q1 + offset`), enforced as a velocity-level
    /// equality constraint each step. See [`MultibodyDofCoupling`].
    pub fn add_dof_coupling(&mut self, coupling: MultibodyDofCoupling) {
        self.couplings.push(coupling);
    }

    /// The DoF couplings declared on this multibody.
    ///
    /// Couplings follow the multibody's topology changes (link insertions, merges and splits);
    /// a coupling is dropped once one of its DoFs no longer exists, or when its two DoFs end up
    /// in different multibodies.
    pub fn couplings(&self) -> &[MultibodyDofCoupling] {
        &self.couplings
    }

    /// Removes the `i`-th DoF coupling (in the order of [`Self::couplings`]) and returns it.
    ///
    /// Returns `None` if there is no such coupling. The couplings after it shift down by one.
    pub fn remove_dof_coupling(&mut self, i: usize) -> Option<MultibodyDofCoupling> {
        (i < self.couplings.len()).then(|| self.couplings.remove(i))
    }

    /// Keeps only the DoF couplings for which `f` returns `true`.
    pub fn retain_dof_couplings(&mut self, f: impl FnMut(&MultibodyDofCoupling) -> bool) {
        self.couplings.retain(f);
    }

    /// Removes all the DoF couplings of this multibody.
    pub fn clear_dof_couplings(&mut self) {
        self.couplings.clear();
    }

    /// The number of dry-friction rows `link_id`'s joint will emit: one per
    /// free DoF whose `frictionloss` entry is non-zero.
    pub(crate) fn num_friction_constraints(&self, link_id: usize) -> usize {
        let Some(link) = self.link(link_id) else {
            return 0;
        };
        let ndofs = link.joint().ndofs();
        (0..ndofs)
            .filter(|i| self.frictions[link.assembly_id + i] > 0.0)
            .count()
    }

    /// Number of coupling constraints "owned" by `owner_link` — couplings whose first joint
    /// (`link1`) is that link. Each coupling is generated once, by `link1` (which always has a
    /// free DoF and so is an active link in the solver island, unlike a possibly-fixed root).
    pub(crate) fn num_couplings_owned_by(&self, owner_link: usize) -> usize {
        self.couplings
            .iter()
            .filter(|c| c.link1 == owner_link)
            .count()
    }

    /// Generates the velocity constraints for the DoF couplings owned by `owner_link` into
    /// `out[..]`: each coupling `q2 = coeff·q1 + offset` is one bilateral constraint with jacobian
    /// `J = e_{q2} − coeff·e_{q1}` and a rhs pulling the position drift back to zero.
    pub(crate) fn coupling_velocity_constraints(
        &self,
        owner_link: usize,
        params: &IntegrationParameters,
        mut j_id: usize,
        jacobians: &mut DVector,
        out: &mut [GenericJointConstraint],
    ) -> usize {
        let ndofs = self.ndofs;
        let erp_inv_dt = SpringCoefficients::<Real>::joint_defaults().erp_inv_dt(params.dt);

        let mut i = 0;
        for c in self.couplings.iter().filter(|c| c.link1 == owner_link) {
            let g1 = self.links[c.link1].assembly_id + c.dof1;
            let g2 = self.links[c.link2].assembly_id + c.dof2;
            let q1 = self.links[c.link1].joint().coords()[c.axis1];
            let q2 = self.links[c.link2].joint().coords()[c.axis2];

            // Jacobian J = e_{g2} − coeff·e_{g1}, then WJ = M⁻¹ J.
            jacobians.rows_mut(j_id, ndofs * 2).fill(0.0);
            jacobians[j_id + g2] += 1.0;
            jacobians[j_id + g1] -= c.coeff;
            for k in 0..ndofs {
                jacobians[j_id + ndofs + k] = jacobians[j_id + k];
            }
            self.solve_augmented_mass_mut(&mut jacobians.rows_mut(j_id + ndofs, ndofs));

            // lhs = Jᵀ M⁻¹ J = Σ J[k]·WJ[k]; only g1/g2 entries of J are nonzero.
            let lhs = jacobians[j_id + ndofs + g2] - c.coeff * jacobians[j_id + ndofs + g1];

            let drift = q2 - c.coeff * q1 - c.offset;

            out[i] = GenericJointConstraint {
                is_rigid_body1: false,
                solver_vel1: u32::MAX,
                ndofs1: 0,
                j_id1: 0,
                is_rigid_body2: false,
                solver_vel2: self.solver_id,
                ndofs2: ndofs,
                j_id2: j_id,
                joint_id: usize::MAX, // internal: no impulse writeback.
                impulse: 0.0,
                impulse_bounds: [-Real::MAX, Real::MAX],
                inv_lhs: crate::utils::inv(lhs),
                rhs: drift * erp_inv_dt,
                rhs_wo_bias: 0.0,
                cfm_coeff: 0.0,
                cfm_gain: 0.0,
                writeback_id: WritebackId::Dof(0),
            };

            j_id += 2 * ndofs;
            i += 1;
        }

        i
    }

    /// The generalized velocity at the multibody_joint of the given link.
    #[inline]
    pub fn joint_velocity(&self, link: &MultibodyLink) -> DVectorView<'_, Real> {
        let ndofs = link.joint().ndofs();
        DVectorView::from_slice(
            &self.velocities.as_slice()[link.assembly_id..link.assembly_id + ndofs],
            ndofs,
        )
    }

    /// The generalized accelerations of this multibodies.
    #[inline]
    pub fn generalized_acceleration(&self) -> DVectorView<'_, Real> {
        self.accelerations.rows(0, self.ndofs)
    }

    /// The generalized velocities of this multibodies.
    #[inline]
    pub fn generalized_velocity(&self) -> DVectorView<'_, Real> {
        self.velocities.rows(0, self.ndofs)
    }

    /// The body jacobian for link `link_id` calculated by the last call to [`Multibody::forward_kinematics`].
    #[inline]
    pub fn body_jacobian(&self, link_id: usize) -> &Jacobian<Real> {
        &self.body_jacobians[link_id]
    }

    /// The mutable generalized velocities of this multibodies.
    #[inline]
    pub fn generalized_velocity_mut(&mut self) -> DVectorViewMut<'_, Real> {
        self.velocities.rows_mut(0, self.ndofs)
    }

    #[inline]
    pub(crate) fn integrate(&mut self, dt: Real) {
        for rb in self.links.iter_mut() {
            rb.joint
                .integrate(dt, &self.velocities.as_slice()[rb.assembly_id..])
        }
    }

    /// Apply displacements, in generalized coordinates, to this multibody.
    ///
    /// Note this does **not** updates the link poses, only their generalized coordinates.
    /// To update the link poses and associated rigid-bodies, call [`Self::forward_kinematics`].
    pub fn apply_displacements(&mut self, disp: &[Real]) {
        for link in self.links.iter_mut() {
            link.joint.apply_displacement(&disp[link.assembly_id..])
        }
    }

    pub(crate) fn update_root_type(&mut self, bodies: &RigidBodySet, take_body_pose: bool) {
        if let Some(rb) = bodies.get(self.links[0].rigid_body) {
            if rb.is_dynamic() != self.root_is_dynamic {
                let root_pose = if take_body_pose {
                    *rb.position()
                } else {
                    self.links[0].local_to_world
                };

                if rb.is_dynamic() {
                    let free_joint = MultibodyJoint::free(root_pose);
                    let prev_root_ndofs = self.links[0].joint().ndofs();
                    self.links[0].joint = free_joint;
                    self.links[0].assembly_id = 0;
                    self.ndofs += SPATIAL_DIM;

                    self.velocities = self.velocities.clone().insert_rows(0, SPATIAL_DIM, 0.0);
                    self.damping = self.damping.clone().insert_rows(0, SPATIAL_DIM, 0.0);
                    self.armature = self.armature.clone().insert_rows(0, SPATIAL_DIM, 0.0);
                    self.frictions = self.frictions.clone().insert_rows(0, SPATIAL_DIM, 0.0);
                    self.accelerations =
                        self.accelerations.clone().insert_rows(0, SPATIAL_DIM, 0.0);

                    for link in &mut self.links[1..] {
                        link.assembly_id += SPATIAL_DIM - prev_root_ndofs;
                    }
                } else {
                    assert!(self.velocities.len() >= SPATIAL_DIM);
                    assert!(self.damping.len() >= SPATIAL_DIM);
                    assert!(self.armature.len() >= SPATIAL_DIM);
                    assert!(self.frictions.len() >= SPATIAL_DIM);
                    assert!(self.accelerations.len() >= SPATIAL_DIM);

                    let fixed_joint = MultibodyJoint::fixed(root_pose);
                    let prev_root_ndofs = self.links[0].joint().ndofs();
                    self.links[0].joint = fixed_joint;
                    self.links[0].assembly_id = 0;
                    self.ndofs -= prev_root_ndofs;

                    if self.ndofs == 0 {
                        self.velocities = DVector::zeros(0);
                        self.damping = DVector::zeros(0);
                        self.armature = DVector::zeros(0);
                        self.frictions = DVector::zeros(0);
                        self.accelerations = DVector::zeros(0);
                    } else {
                        self.velocities =
                            self.velocities.index((prev_root_ndofs.., 0)).into_owned();
                        self.damping = self.damping.index((prev_root_ndofs.., 0)).into_owned();
                        self.armature = self.armature.index((prev_root_ndofs.., 0)).into_owned();
                        self.frictions = self.frictions.index((prev_root_ndofs.., 0)).into_owned();
                        self.accelerations = self
                            .accelerations
                            .index((prev_root_ndofs.., 0))
                            .into_owned();
                    }

                    for link in &mut self.links[1..] {
                        link.assembly_id -= prev_root_ndofs;
                    }
                }

                self.root_is_dynamic = rb.is_dynamic();
            }

            // Make sure the positions are properly set to match the rigid-body’s.
            if take_body_pose {
                if self.links[0].joint.data.locked_axes.is_empty() {
                    self.links[0].joint.set_free_pos(*rb.position());
                } else {
                    self.links[0].joint.data.local_frame1 = *rb.position();
                }
            }
        }
    }

    /// Update the rigid-body poses based on this multibody joint poses.
    ///
    /// This is typically called after [`Self::forward_kinematics`] to apply the new joint poses
    /// to the rigid-bodies.
    pub fn update_rigid_bodies(&self, bodies: &mut RigidBodySet, update_mass_properties: bool) {
        self.update_rigid_bodies_internal(bodies, update_mass_properties, false, true)
    }

    pub(crate) fn update_rigid_bodies_internal(
        &self,
        bodies: &mut RigidBodySet,
        update_mass_properties: bool,
        update_next_positions_only: bool,
        change_tracking: bool,
    ) {
        // Handle the children. They all have a parent within this multibody.
        for link in self.links.iter() {
            let rb = if change_tracking {
                bodies.get_mut_internal_with_modification_tracking(link.rigid_body)
            } else {
                bodies.get_mut_internal(link.rigid_body)
            };

            if let Some(rb) = rb {
                rb.pos.next_position = link.local_to_world;

                if !update_next_positions_only {
                    rb.pos.position = link.local_to_world;
                }

                if update_mass_properties {
                    rb.mprops
                        .update_world_mass_properties(rb.body_type, &link.local_to_world);
                }
            }
        }
    }

    // TODO: make a version that doesn’t write back to bodies and doesn’t update the jacobians
    //       (i.e. just something used by the velocity solver’s small steps).
    /// Apply forward-kinematics to this multibody.
    ///
    /// This will update the [`MultibodyLink`] pose information as wall as the body jacobians.
    /// This will also ensure that the multibody has the proper number of degrees of freedom if
    /// its root node changed between dynamic and non-dynamic.
    ///
    /// Note that this does **not** update the poses of the [`RigidBody`] attached to the joints.
    /// Run [`Self::update_rigid_bodies`] to trigger that update.
    ///
    /// This method updates `self` with the result of the forward-kinematics operation.
    /// For a non-mutable version running forward kinematics on a single link, see
    /// [`Self::forward_kinematics_single_link`].
    ///
    /// ## Parameters
    /// - `bodies`: the set of rigid-bodies.
    /// - `read_root_pose_from_rigid_body`: if set to `true`, the root joint (either a fixed joint,
    ///   or a free joint) will have its pose set to its associated-rigid-body pose. Set this to `true`
    ///   when the root rigid-body pose has been modified and needs to affect the multibody.
    pub fn forward_kinematics(
        &mut self,
        bodies: &RigidBodySet,
        read_root_pose_from_rigid_body: bool,
    ) {
        self.forward_kinematics_if_changed(bodies, read_root_pose_from_rigid_body);
    }

    /// [`Self::forward_kinematics`], telling whether it computed anything: `false` when
    /// nothing it reads changed since its last call, whose results stand.
    pub(crate) fn forward_kinematics_if_changed(
        &mut self,
        bodies: &RigidBodySet,
        read_root_pose_from_rigid_body: bool,
    ) -> bool {
        // Be sure the degrees of freedom match and take the root position if needed.
        self.update_root_type(bodies, read_root_pose_from_rigid_body);

        // Nothing it reads changed since the last call (the usual case at the start of a step,
        // right after the previous step ended with its own forward kinematics): its results
        // stand, bit for bit.
        if self.kinematic_inputs_unchanged(bodies) {
            return false;
        }

        // Special case for the root, which has no parent.
        {
            let link = &mut self.links[0];
            link.local_to_parent = link.joint.body_to_parent();
            link.local_to_world = link.local_to_parent;
        }

        // Handle the children. They all have a parent within this multibody.
        for i in 1..self.links.len() {
            let (link, parent_link) = self.links.get_mut_with_parent(i);

            link.local_to_parent = link.joint.body_to_parent();
            link.local_to_world = parent_link.local_to_world * link.local_to_parent;

            {
                let parent_rb = &bodies[parent_link.rigid_body];
                let link_rb = &bodies[link.rigid_body];
                let c0 = parent_link.local_to_world * parent_rb.mprops.local_mprops.local_com;
                let c2 = link.local_to_world * link.joint.data.local_frame2.translation;
                let c3 = link.local_to_world * link_rb.mprops.local_mprops.local_com;

                link.shift02 = c2 - c0;
                link.shift23 = c3 - c2;
            }

            assert_eq!(
                bodies[link.rigid_body].body_type,
                RigidBodyType::Dynamic,
                "A rigid-body that is not at the root of a multibody must be dynamic."
            );
        }

        /*
         * Compute body jacobians.
         */
        self.update_body_jacobians();
        true
    }

    /// Whether every link's rigid-body already holds what
    /// [`Self::update_rigid_bodies_internal`] would write with `update_mass_properties` and
    /// not `update_next_positions_only`: its position and next position are its link's pose,
    /// and the user changed nothing of it since the last step (so its world mass properties
    /// were last computed at that pose, by the last step's end or the user-changes handler).
    pub(crate) fn rigid_bodies_hold_link_poses(&self, bodies: &RigidBodySet) -> bool {
        self.links.iter().all(|link| {
            bodies.get(link.rigid_body).is_none_or(|rb| {
                rb.changes
                    .difference(RigidBodyChanges::IN_MODIFIED_SET)
                    .is_empty()
                    && rb.pos.position == link.local_to_world
                    && rb.pos.next_position == link.local_to_world
            })
        })
    }

    /// Records what [`Self::forward_kinematics`] reads, after the root's pose is taken, and tells
    /// whether it is what the last call read: the joints' coordinates and frames, the links'
    /// centres of mass, the bodies' types and the tree's shape.
    fn kinematic_inputs_unchanged(&mut self, bodies: &RigidBodySet) -> bool {
        let ws = &mut self.workspace;
        ws.kinematic_inputs_now.clear();
        for link in self.links.iter() {
            let rb = &bodies[link.rigid_body];
            let joint = &link.joint;
            ws.kinematic_inputs_now.push(LinkKinematicInputs {
                rigid_body: link.rigid_body,
                body_type: rb.body_type,
                local_com: rb.mprops.local_mprops.local_com,
                parent_internal_id: link.parent_internal_id,
                assembly_id: link.assembly_id,
                locked_axes: joint.data.locked_axes,
                local_frame1: joint.data.local_frame1,
                local_frame2: joint.data.local_frame2,
                coords: joint.coords,
                joint_rot: joint.joint_rot,
            });
        }
        let unchanged = ws.kinematic_inputs_ndofs == self.ndofs
            && ws.kinematic_inputs_now == ws.kinematic_inputs;
        core::mem::swap(&mut ws.kinematic_inputs, &mut ws.kinematic_inputs_now);
        ws.kinematic_inputs_ndofs = self.ndofs;
        unchanged
    }

    /// Computes the ids of all the links between the root and the link identified by `link_id`.
    pub fn kinematic_branch(&self, link_id: usize) -> Vec<usize> {
        let mut branch = vec![]; // Perf: avoid allocation.
        let mut curr_id = Some(link_id);

        while let Some(id) = curr_id {
            branch.push(id);
            curr_id = self.links[id].parent_id();
        }

        branch.reverse();
        branch
    }

    /// Apply forward-kinematics to compute the position of a single link of this multibody.
    ///
    /// If `out_jacobian` is `Some`, this will simultaneously compute the new jacobian of this link.
    /// If `displacement` is `Some`, the generalized position considered during transform propagation
    /// is the sum of the current position of `self` and this `displacement`.
    // TODO: this shares a lot of code with `forward_kinematics` and `update_body_jacobians`, except
    //       that we are only traversing a single kinematic chain. Could this be refactored?
    pub fn forward_kinematics_single_link(
        &self,
        bodies: &RigidBodySet,
        link_id: usize,
        displacement: Option<&[Real]>,
        out_jacobian: Option<&mut Jacobian<Real>>,
    ) -> Pose {
        let branch = self.kinematic_branch(link_id);
        self.forward_kinematics_single_branch(bodies, &branch, displacement, out_jacobian)
    }

    /// Apply forward-kinematics to compute the position of a single sorted branch of this multibody.
    ///
    /// The given `branch` must have the following properties:
    /// - It must be sorted, i.e., `branch[i] < branch[i + 1]`.
    /// - All the indices must be part of the same kinematic branch.
    /// - If a link is `branch[i]`, then `branch[i - 1]` must be its parent.
    ///
    /// In general, this method shouldn’t be used directly and [`Self::forward_kinematics_single_link`]
    /// should be preferred since it computes the branch indices automatically.
    ///
    /// If you want to calculate the branch indices manually, see [`Self::kinematic_branch`].
    ///
    /// If `out_jacobian` is `Some`, this will simultaneously compute the new jacobian of this branch.
    /// This represents the body jacobian for the last link in the branch.
    ///
    /// If `displacement` is `Some`, the generalized position considered during transform propagation
    /// is the sum of the current position of `self` and this `displacement`.
    // TODO: this shares a lot of code with `forward_kinematics` and `update_body_jacobians`, except
    //       that we are only traversing a single kinematic chain. Could this be refactored?
    #[profiling::function]
    pub fn forward_kinematics_single_branch(
        &self,
        bodies: &RigidBodySet,
        branch: &[usize],
        displacement: Option<&[Real]>,
        mut out_jacobian: Option<&mut Jacobian<Real>>,
    ) -> Pose {
        if let Some(out_jacobian) = out_jacobian.as_deref_mut() {
            if out_jacobian.ncols() != self.ndofs {
                *out_jacobian = Jacobian::zeros(self.ndofs);
            } else {
                out_jacobian.fill(0.0);
            }
        }

        let mut parent_link: Option<MultibodyLink> = None;

        for i in branch {
            let mut link = self.links[*i];

            if let Some(displacement) = displacement {
                link.joint
                    .apply_displacement(&displacement[link.assembly_id..]);
            }

            let parent_to_world;

            if let Some(parent_link) = parent_link {
                link.local_to_parent = link.joint.body_to_parent();
                link.local_to_world = parent_link.local_to_world * link.local_to_parent;

                {
                    let parent_rb = &bodies[parent_link.rigid_body];
                    let link_rb = &bodies[link.rigid_body];
                    let c0 = parent_link.local_to_world * parent_rb.mprops.local_mprops.local_com;
                    let c2 = link.local_to_world
                        * Vector::from(link.joint.data.local_frame2.translation);
                    let c3 = link.local_to_world * link_rb.mprops.local_mprops.local_com;

                    link.shift02 = c2 - c0;
                    link.shift23 = c3 - c2;
                }

                parent_to_world = parent_link.local_to_world;

                if let Some(out_jacobian) = out_jacobian.as_deref_mut() {
                    let (mut link_j_v, parent_j_w) =
                        out_jacobian.rows_range_pair_mut(0..DIM, DIM..DIM + ANG_DIM);
                    let shift_tr = vect_to_na(link.shift02).gcross_matrix_tr();
                    link_j_v.gemm(1.0, &shift_tr, &parent_j_w, 1.0);
                }
            } else {
                link.local_to_parent = link.joint.body_to_parent();
                link.local_to_world = link.local_to_parent;
                parent_to_world = Pose::IDENTITY;
            }

            if let Some(out_jacobian) = out_jacobian.as_deref_mut() {
                let ndofs = link.joint.ndofs();
                let mut tmp = SMatrix::<Real, SPATIAL_DIM, SPATIAL_DIM>::zeros();
                let mut link_joint_j = tmp.columns_mut(0, ndofs);
                let mut link_j_part = out_jacobian.columns_mut(link.assembly_id, ndofs);
                link.joint.jacobian(
                    &(parent_to_world.rotation * link.joint.data.local_frame1.rotation),
                    &mut link_joint_j,
                );
                link_j_part += link_joint_j;

                {
                    let (mut link_j_v, link_j_w) =
                        out_jacobian.rows_range_pair_mut(0..DIM, DIM..DIM + ANG_DIM);
                    let shift_tr = vect_to_na(link.shift23).gcross_matrix_tr();
                    link_j_v.gemm(1.0, &shift_tr, &link_j_w, 1.0);
                }
            }

            parent_link = Some(link);
        }

        parent_link
            .map(|link| link.local_to_world)
            .unwrap_or(Pose::IDENTITY)
    }

    /// The total number of freedoms of this multibody.
    #[inline]
    pub fn ndofs(&self) -> usize {
        self.ndofs
    }

    pub(crate) fn fill_jacobians(
        &self,
        link_id: usize,
        unit_force: Vector,
        unit_torque: AngVector,
        j_id: &mut usize,
        jacobians: &mut DVector,
    ) -> (Real, Real) {
        if self.ndofs == 0 {
            return (0.0, 0.0);
        }

        let wj_id = *j_id + self.ndofs;
        let force = Force {
            linear: unit_force,
            #[cfg(feature = "dim2")]
            angular: unit_torque,
            #[cfg(feature = "dim3")]
            angular: unit_torque,
        };

        let link = &self.links[link_id];
        let mut out_j = jacobians.rows_mut(*j_id, self.ndofs);
        self.body_jacobians[link.internal_id].tr_mul_to(force.as_vector(), &mut out_j);

        // TODO: Optimize with a copy_nonoverlapping?
        for i in 0..self.ndofs {
            jacobians[wj_id + i] = jacobians[*j_id + i];
        }

        {
            let mut out_invm_j = jacobians.rows_mut(wj_id, self.ndofs);
            self.augmented_mass_indices
                .with_rearranged_rows_mut(&mut out_invm_j, |out_invm_j| {
                    self.mass_factors.solve_mut(out_invm_j);
                });
        }

        let j = jacobians.rows(*j_id, self.ndofs);
        let invm_j = jacobians.rows(wj_id, self.ndofs);
        *j_id += self.ndofs * 2;

        (j.dot(&invm_j), j.dot(&self.generalized_velocity()))
    }

    /// Fills `jacobians` with the relative jacobian `J = J2ᵀ·f2 − J1ᵀ·f1` of two links of `self`, then `M⁻¹·J`
    /// (e.g. a loop closure). The difference must be explicit: per-link blocks lose the `J1ᵀ·W·J2` effective-mass
    /// coupling since both act on the same generalized velocities. Cancellation-vanished rows are zeroed so the solver skips them.
    pub(crate) fn fill_relative_jacobians(
        &self,
        link_id1: usize,
        unit_force1: Vector,
        unit_torque1: AngVector,
        link_id2: usize,
        unit_force2: Vector,
        unit_torque2: AngVector,
        j_id: &mut usize,
        jacobians: &mut DVector,
    ) {
        if self.ndofs == 0 {
            return;
        }

        let wj_id = *j_id + self.ndofs;
        let force1 = Force {
            linear: unit_force1,
            angular: unit_torque1,
        };
        let force2 = Force {
            linear: unit_force2,
            angular: unit_torque2,
        };

        let link1 = &self.links[link_id1];
        let link2 = &self.links[link_id2];

        {
            let jb1 = &self.body_jacobians[link1.internal_id];
            let jb2 = &self.body_jacobians[link2.internal_id];

            // Use the (overwritten below) W·J slot as workspace for J1ᵀ·f1.
            let (mut out_j, mut workspace) =
                jacobians.rows_range_pair_mut(*j_id..*j_id + self.ndofs, wj_id..wj_id + self.ndofs);
            jb2.tr_mul_to(force2.as_vector(), &mut out_j);
            jb1.tr_mul_to(force1.as_vector(), &mut workspace);
            out_j.axpy(-1.0, &workspace, 1.0);

            // Cancellation guard: the reference scale is the magnitude of the dot-product operands,
            // not their results (which may be pure cancellation noise when the direction isn’t
            // expressible by the dofs). Rows below ~1000·ε times that scale are noise, not a constraint.
            let scale_sq = jb1.norm_squared() * force1.as_vector().norm_squared()
                + jb2.norm_squared() * force2.as_vector().norm_squared();
            let eps = Real::EPSILON * 1.0e3;
            if out_j.norm_squared() <= eps * eps * scale_sq {
                out_j.fill(0.0);
            }
        }

        // TODO: Optimize with a copy_nonoverlapping?
        for i in 0..self.ndofs {
            jacobians[wj_id + i] = jacobians[*j_id + i];
        }

        {
            let mut out_invm_j = jacobians.rows_mut(wj_id, self.ndofs);
            self.augmented_mass_indices
                .with_rearranged_rows_mut(&mut out_invm_j, |out_invm_j| {
                    self.mass_factors.solve_mut(out_invm_j);
                });
        }

        *j_id += self.ndofs * 2;
    }
}

#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug)]
struct IndexSequence {
    first_to_remove: u32,
    index_map: Vec<usize>,
}

impl IndexSequence {
    const NONE: u32 = u32::MAX;

    fn new() -> Self {
        Self {
            first_to_remove: Self::NONE,
            index_map: vec![],
        }
    }

    /// Index of the first removed dof, assuming there is one.
    fn start(&self) -> usize {
        self.first_to_remove as usize
    }

    fn clear(&mut self) {
        self.first_to_remove = Self::NONE;
        self.index_map.clear();
    }

    fn keep(&mut self, i: usize) {
        if self.first_to_remove == Self::NONE {
            // Nothing got removed yet. No need to register any
            // special indexing.
            return;
        }

        self.index_map.push(i);
    }

    fn remove(&mut self, i: usize) {
        if self.first_to_remove == Self::NONE {
            self.first_to_remove = i as u32;
        }
    }

    fn dim_after_removal(&self, original_dim: usize) -> usize {
        if self.first_to_remove == Self::NONE {
            original_dim
        } else {
            self.start() + self.index_map.len()
        }
    }

    fn rearrange_columns<R: na::Dim, C: na::Dim, S: StorageMut<Real, R, C>>(
        &self,
        mat: &mut na::Matrix<Real, R, C, S>,
        clear_removed: bool,
    ) {
        if self.first_to_remove == Self::NONE {
            // Nothing to rearrange.
            return;
        }

        for (target_shift, source) in self.index_map.iter().enumerate() {
            let target = self.start() + target_shift;
            let (mut target_col, source_col) = mat.columns_range_pair_mut(target, *source);
            target_col.copy_from(&source_col);
        }

        if clear_removed {
            mat.columns_range_mut(self.start() + self.index_map.len()..)
                .fill(0.0);
        }
    }

    fn rearrange_rows<R: na::Dim, C: na::Dim, S: StorageMut<Real, R, C>>(
        &self,
        mat: &mut na::Matrix<Real, R, C, S>,
        clear_removed: bool,
    ) {
        if self.first_to_remove == Self::NONE {
            // Nothing to rearrange.
            return;
        }

        for mut col in mat.column_iter_mut() {
            for (target_shift, source) in self.index_map.iter().enumerate() {
                let target = self.start() + target_shift;
                col[target] = col[*source];
            }

            if clear_removed {
                col.rows_range_mut(self.start() + self.index_map.len()..)
                    .fill(0.0);
            }
        }
    }

    fn inv_rearrange_rows<R: na::Dim, C: na::Dim, S: StorageMut<Real, R, C>>(
        &self,
        mat: &mut na::Matrix<Real, R, C, S>,
    ) {
        if self.first_to_remove == Self::NONE {
            // Nothing to rearrange.
            return;
        }

        for mut col in mat.column_iter_mut() {
            for (target_shift, source) in self.index_map.iter().enumerate().rev() {
                let target = self.start() + target_shift;
                col[*source] = col[target];
                col[target] = 0.0;
            }
        }
    }

    fn with_rearranged_rows_mut<C: na::Dim, S: StorageMut<Real, Dyn, C>>(
        &self,
        mat: &mut na::Matrix<Real, Dyn, C, S>,
        mut f: impl FnMut(&mut na::MatrixViewMut<Real, Dyn, C, S::RStride, S::CStride>),
    ) {
        self.rearrange_rows(mat, true);
        let effective_dim = self.dim_after_removal(mat.nrows());
        if effective_dim > 0 {
            f(&mut mat.rows_mut(0, effective_dim));
        }
        self.inv_rearrange_rows(mat);
    }
}

#[cfg(all(test, feature = "dim3"))]
mod mass_matrix_tests;

#[cfg(all(test, feature = "dim3"))]
mod kinematics_tests;

#[cfg(test)]
mod test {
    use super::IndexSequence;
    use crate::alloc_prelude::*;
    use crate::dynamics::{ImpulseJointSet, IslandManager};
    #[cfg(feature = "dim3")]
    use crate::math::Vector;
    use crate::math::{Real, SPATIAL_DIM};
    use crate::prelude::{
        ColliderSet, MultibodyJointHandle, MultibodyJointSet, RevoluteJoint, RigidBodyBuilder,
        RigidBodySet, SoftBodySet,
    };
    use na::{DVector, RowDVector};

    #[test]
    fn test_multibody_append() {
        let mut bodies = RigidBodySet::new();
        let mut joints = MultibodyJointSet::new();

        let a = bodies.insert(RigidBodyBuilder::dynamic());
        let b = bodies.insert(RigidBodyBuilder::dynamic());
        let c = bodies.insert(RigidBodyBuilder::dynamic());
        let d = bodies.insert(RigidBodyBuilder::dynamic());

        #[cfg(feature = "dim2")]
        let joint = RevoluteJoint::new();
        #[cfg(feature = "dim3")]
        let joint = RevoluteJoint::new(Vector::X);

        let mb_handle = joints.insert(a, b, joint, true).unwrap();
        joints.insert(c, d, joint, true).unwrap();
        joints.insert(b, c, joint, true).unwrap();

        assert_eq!(joints.get(mb_handle).unwrap().0.ndofs, SPATIAL_DIM + 3);
    }

    #[test]
    fn test_multibody_insert() {
        let mut rnd = oorandom::Rand32::new(1234);

        for k in 0..10 {
            let mut bodies = RigidBodySet::new();
            let mut multibody_joints = MultibodyJointSet::new();

            let num_links = 100;
            let mut handles = vec![];

            for _ in 0..num_links {
                handles.push(bodies.insert(RigidBodyBuilder::dynamic()));
            }

            let mut insertion_id: Vec<_> = (0..num_links - 1).collect();

            #[cfg(feature = "dim2")]
            let joint = RevoluteJoint::new();
            #[cfg(feature = "dim3")]
            let joint = RevoluteJoint::new(Vector::X);

            match k {
                0 => {} // Remove in insertion order.
                1 => {
                    // Remove from leaf to root.
                    insertion_id.reverse();
                }
                _ => {
                    // Shuffle the vector a bit.
                    // (This test checks multiple shuffle arrangements due to k > 2).
                    for l in 0..num_links - 1 {
                        insertion_id.swap(l, rnd.rand_range(0..num_links as u32 - 1) as usize);
                    }
                }
            }

            let mut mb_handle = MultibodyJointHandle::invalid();
            for i in insertion_id {
                mb_handle = multibody_joints
                    .insert(handles[i], handles[i + 1], joint, true)
                    .unwrap();
            }

            assert_eq!(
                multibody_joints.get(mb_handle).unwrap().0.ndofs,
                SPATIAL_DIM + num_links - 1
            );
        }
    }

    #[test]
    fn test_multibody_remove() {
        let mut rnd = oorandom::Rand32::new(1234);

        for k in 0..10 {
            let mut bodies = RigidBodySet::new();
            let mut multibody_joints = MultibodyJointSet::new();
            let mut colliders = ColliderSet::new();
            let mut impulse_joints = ImpulseJointSet::new();
            let mut islands = IslandManager::new();
            let mut soft_bodies = SoftBodySet::new();

            let num_links = 100;
            let mut handles = vec![];

            for _ in 0..num_links {
                handles.push(bodies.insert(RigidBodyBuilder::dynamic()));
            }

            #[cfg(feature = "dim2")]
            let joint = RevoluteJoint::new();
            #[cfg(feature = "dim3")]
            let joint = RevoluteJoint::new(Vector::X);

            for i in 0..num_links - 1 {
                multibody_joints
                    .insert(handles[i], handles[i + 1], joint, true)
                    .unwrap();
            }

            match k {
                0 => {} // Remove in insertion order.
                1 => {
                    // Remove from leaf to root.
                    handles.reverse();
                }
                _ => {
                    // Shuffle the vector a bit.
                    // (This test checks multiple shuffle arrangements due to k > 2).
                    for l in 0..num_links {
                        handles.swap(l, rnd.rand_range(0..num_links as u32) as usize);
                    }
                }
            }

            for handle in handles {
                bodies.remove(
                    handle,
                    &mut islands,
                    &mut colliders,
                    &mut impulse_joints,
                    &mut multibody_joints,
                    &mut soft_bodies,
                    true,
                );
            }
        }
    }

    fn test_sequence() -> IndexSequence {
        let mut seq = IndexSequence::new();
        seq.remove(2);
        seq.remove(3);
        seq.remove(4);
        seq.keep(5);
        seq.keep(6);
        seq.remove(7);
        seq.keep(8);
        seq
    }

    #[test]
    fn index_sequence_rearrange_columns() {
        let seq = test_sequence();
        let mut vec = RowDVector::from_fn(10, |_, c| c as Real);
        seq.rearrange_columns(&mut vec, true);
        assert_eq!(
            vec,
            RowDVector::from(vec![0.0, 1.0, 5.0, 6.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        );
    }

    #[test]
    fn index_sequence_rearrange_rows() {
        let seq = test_sequence();
        let mut vec = DVector::from_fn(10, |r, _| r as Real);
        seq.rearrange_rows(&mut vec, true);
        assert_eq!(
            vec,
            DVector::from(vec![0.0, 1.0, 5.0, 6.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        );
        seq.inv_rearrange_rows(&mut vec);
        assert_eq!(
            vec,
            DVector::from(vec![0.0, 1.0, 0.0, 0.0, 0.0, 5.0, 6.0, 0.0, 8.0, 0.0])
        );
    }

    #[test]
    fn index_sequence_with_rearranged_rows_mut() {
        let seq = test_sequence();
        let mut vec = DVector::from_fn(10, |r, _| r as Real);
        seq.with_rearranged_rows_mut(&mut vec, |v| {
            assert_eq!(v.len(), 5);
            assert_eq!(*v, DVector::from(vec![0.0, 1.0, 5.0, 6.0, 8.0]));
            *v *= 10.0;
        });
        assert_eq!(
            vec,
            DVector::from(vec![0.0, 10.0, 0.0, 0.0, 0.0, 50.0, 60.0, 0.0, 80.0, 0.0])
        );
    }
}
