use crate::alloc_prelude::*;
use crate::dynamics::RigidBodyVelocity;
use crate::math::{ANG_DIM, DIM, DVector, Real, SPATIAL_DIM};
use na::SVector;

use super::multibody_link::MultibodyLink;
use super::tree_lu::NO_PARENT;

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
    /// One link's `Mᵢ·J` and the semi-implicit update's counterpart, column per path entry.
    pub mass_columns: Vec<SVector<Real, SPATIAL_DIM>>,
    pub acc_mass_columns: Vec<SVector<Real, SPATIAL_DIM>>,
    /// Per non-kinematic degree of freedom (in order, kinematic ones left out), the one before
    /// it on its path to the root (`NO_PARENT` for none): the tree the factorisations follow.
    pub dof_parents: Vec<usize>,
    /// Per link, the last non-kinematic degree of freedom on its path (scratch).
    link_last_dof: Vec<usize>,
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
            mass_columns: Vec::new(),
            acc_mass_columns: Vec::new(),
            dof_parents: Vec::new(),
            link_last_dof: Vec::new(),
        }
    }

    /// Resize the workspace so it is enough for `nlinks` links.
    pub fn resize(&mut self, nlinks: usize, ndofs: usize) {
        self.accs.resize(nlinks, RigidBodyVelocity::zero());
        self.ndofs_vec = DVector::zeros(ndofs)
    }

    /// Lists each link's path degrees of freedom (see [`Self::path_dofs`]) and sizes the
    /// per-path buffers. Links are stored parents first, so a parent's list is ready before its
    /// children's. Allocates only when the multibody has grown.
    pub fn update_paths(&mut self, links: &[MultibodyLink]) {
        self.path_dofs.clear();
        self.path_start.clear();
        self.path_start.push(0);
        let mut longest = 0;
        for (i, link) in links.iter().enumerate() {
            let start = self.path_dofs.len();
            if i != 0 {
                let parent = link.parent_internal_id;
                let parent_path = self.path_start[parent]..self.path_start[parent + 1];
                self.path_dofs.extend_from_within(parent_path);
            }
            self.path_dofs
                .extend(link.assembly_id..link.assembly_id + link.joint.ndofs());
            self.path_start.push(self.path_dofs.len());
            longest = longest.max(self.path_dofs.len() - start);
        }
        let total = self.path_dofs.len();
        self.path_jacobians.resize(total, SVector::zeros());
        self.path_coriolis_v.resize(total, SVector::zeros());
        self.path_coriolis_w.resize(total, SVector::zeros());
        self.mass_columns.resize(longest, SVector::zeros());
        self.acc_mass_columns.resize(longest, SVector::zeros());
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
