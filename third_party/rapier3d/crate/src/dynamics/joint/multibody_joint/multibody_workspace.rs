use crate::alloc_prelude::*;
use crate::dynamics::{JointAxesMask, RigidBodyHandle, RigidBodyType, RigidBodyVelocity};
use crate::math::{
    ANG_DIM, DIM, DVector, Pose, Real, Rotation, SPATIAL_DIM, SpatialVector, Vector,
};
use na::SVector;

use super::multibody_link::MultibodyLink;
use super::tree_lu::NO_PARENT;

/// What [`Multibody::forward_kinematics`](super::Multibody::forward_kinematics) reads of one
/// link: when none of it changed since the last call, neither did the results.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct LinkKinematicInputs {
    pub rigid_body: RigidBodyHandle,
    pub body_type: RigidBodyType,
    pub local_com: Vector,
    pub parent_internal_id: usize,
    pub assembly_id: usize,
    pub locked_axes: JointAxesMask,
    pub local_frame1: Pose,
    pub local_frame2: Pose,
    pub coords: SpatialVector,
    pub joint_rot: Rotation,
}

/// A temporary workspace for various updates of the multibody.
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug)]
pub(crate) struct MultibodyWorkspace {
    pub accs: Vec<RigidBodyVelocity<Real>>,
    pub ndofs_vec: DVector,
    /// Per link, the degrees of freedom its motion depends on (those of the joints between it
    /// and the root, its own included), root first, all links' lists end to end: link `i`'s are
    /// `path_dofs[path_start[i]..path_start[i + 1]]`, and they begin with its parent's.
    pub path_dofs: Vec<usize>,
    pub path_start: Vec<usize>,
    /// Per link, its body Jacobian's columns for its path's degrees of freedom (same layout).
    pub path_jacobians: Vec<SVector<Real, SPATIAL_DIM>>,
    /// Per link, the linear and angular parts of the Coriolis matrix on its path (same layout).
    pub path_coriolis_v: Vec<SVector<Real, DIM>>,
    pub path_coriolis_w: Vec<SVector<Real, ANG_DIM>>,
    /// Per link, the wrenches `Mᵢ·J` and the semi-implicit update's counterpart about the root
    /// link's centre of mass, then summed over the links below it (same layout as `path_dofs`).
    pub path_mass_wrenches: Vec<SVector<Real, SPATIAL_DIM>>,
    pub path_acc_wrenches: Vec<SVector<Real, SPATIAL_DIM>>,
    /// Per link, its centre of mass from the root link's.
    pub link_points: Vec<Vector>,
    /// Per degree of freedom, the twist it gives the links below its joint, about the root
    /// link's centre of mass.
    pub dof_motions: Vec<SVector<Real, SPATIAL_DIM>>,
    /// Per non-kinematic degree of freedom (in order, kinematic ones left out), the one before
    /// it on its path to the root (`NO_PARENT` for none): the tree the factorisations follow.
    #[cfg_attr(
        feature = "serde-serialize",
        serde(with = "super::tree_lu::portable_parents")
    )]
    pub dof_parents: Vec<usize>,
    /// Per link, the last non-kinematic degree of freedom on its path (scratch).
    link_last_dof: Vec<usize>,
    /// `update_acceleration`'s generalized forces (all, and those from positions and external
    /// inputs), and its energy guard's vectors, kept so that a step allocates nothing.
    pub gen_forces: DVector,
    pub pos_forces: DVector,
    pub guard_velocities: DVector,
    pub guard_forces: DVector,
    pub guard_pos_forces: DVector,
    pub guard_accelerations: DVector,
    pub guard_product: DVector,
    /// The inputs of the last forward kinematics, per link, and the multibody's number of
    /// degrees of freedom then; empty when they must be computed anew.
    pub kinematic_inputs: Vec<LinkKinematicInputs>,
    pub kinematic_inputs_ndofs: usize,
    /// The current inputs (scratch, swapped with `kinematic_inputs`).
    pub kinematic_inputs_now: Vec<LinkKinematicInputs>,
}

impl MultibodyWorkspace {
    /// Create an empty workspace.
    pub fn new() -> Self {
        MultibodyWorkspace {
            accs: Vec::new(),
            ndofs_vec: DVector::zeros(0),
            path_dofs: Vec::new(),
            path_start: Vec::new(),
            path_jacobians: Vec::new(),
            path_coriolis_v: Vec::new(),
            path_coriolis_w: Vec::new(),
            path_mass_wrenches: Vec::new(),
            path_acc_wrenches: Vec::new(),
            link_points: Vec::new(),
            dof_motions: Vec::new(),
            dof_parents: Vec::new(),
            link_last_dof: Vec::new(),
            gen_forces: DVector::zeros(0),
            pos_forces: DVector::zeros(0),
            guard_velocities: DVector::zeros(0),
            guard_forces: DVector::zeros(0),
            guard_pos_forces: DVector::zeros(0),
            guard_accelerations: DVector::zeros(0),
            guard_product: DVector::zeros(0),
            kinematic_inputs: Vec::new(),
            kinematic_inputs_ndofs: 0,
            kinematic_inputs_now: Vec::new(),
        }
    }

    /// Resize the workspace so it is enough for `nlinks` links (the multibody's links changed:
    /// its forward kinematics must be computed anew).
    pub fn resize(&mut self, nlinks: usize, ndofs: usize) {
        self.accs.resize(nlinks, RigidBodyVelocity::zero());
        self.ndofs_vec = DVector::zeros(ndofs);
        self.kinematic_inputs.clear();
    }

    /// Lists each link's path degrees of freedom (see [`Self::path_dofs`]) and sizes the
    /// per-path buffers. Links are stored parents first, so a parent's list is ready before its
    /// children's. Allocates only when the multibody has grown.
    pub fn update_paths(&mut self, links: &[MultibodyLink]) {
        self.path_dofs.clear();
        self.path_start.clear();
        self.path_start.push(0);
        for (i, link) in links.iter().enumerate() {
            if i != 0 {
                let parent = link.parent_internal_id;
                let parent_path = self.path_start[parent]..self.path_start[parent + 1];
                self.path_dofs.extend_from_within(parent_path);
            }
            self.path_dofs
                .extend(link.assembly_id..link.assembly_id + link.joint.ndofs());
            self.path_start.push(self.path_dofs.len());
        }
        let total = self.path_dofs.len();
        self.path_jacobians.resize(total, SVector::zeros());
        self.path_coriolis_v.resize(total, SVector::zeros());
        self.path_coriolis_w.resize(total, SVector::zeros());
        self.path_mass_wrenches.resize(total, SVector::zeros());
        self.path_acc_wrenches.resize(total, SVector::zeros());
        self.link_points.resize(links.len(), Vector::ZERO);
        let ndofs = links
            .last()
            .map_or(0, |link| link.assembly_id + link.joint.ndofs());
        self.dof_motions.resize(ndofs, SVector::zeros());
    }

    /// Lists [`Self::dof_parents`]: a joint's degrees of freedom follow one another, and the
    /// first follows the last of the nearest ancestor link that has one. The kinematic ones are
    /// left out, the others keep their order (as `Multibody`'s kinematic reordering does).
    pub fn update_dof_parents(&mut self, links: &[MultibodyLink]) {
        self.dof_parents.clear();
        self.link_last_dof.clear();
        for (i, link) in links.iter().enumerate() {
            let mut previous = if i == 0 {
                NO_PARENT
            } else {
                self.link_last_dof[link.parent_internal_id]
            };
            if !link.joint.kinematic {
                for _ in 0..link.joint.ndofs() {
                    self.dof_parents.push(previous);
                    previous = self.dof_parents.len() - 1;
                }
            }
            self.link_last_dof.push(previous);
        }
    }
}
