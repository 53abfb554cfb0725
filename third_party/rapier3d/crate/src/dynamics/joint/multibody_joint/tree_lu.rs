//! The LU factorisation of a multibody's mass matrix that follows its kinematic tree.

use crate::alloc_prelude::*;
use crate::math::Real;
use na::{DMatrix, Dim, Dyn, Matrix, StorageMut};

/// A degree of freedom without parent: the first of its path from the root.
pub const NO_PARENT: usize = usize::MAX;

/// The factorisation `A = U·L` of a square matrix whose entry `(i, j)` can be non-zero only if
/// `i` and `j` lie on one path of a tree of degrees of freedom (one is the other's ancestor, or
/// they are equal): the sparsity of a multibody's mass matrix, where a degree of freedom's parent
/// is the one before it in its link's joint, or the last of the nearest ancestor link's.
///
/// Eliminating the degrees of freedom from the leaves up (Featherstone, *Rigid Body Dynamics
/// Algorithms*, §6.5) creates no fill-in: eliminating `k` only updates entries between two of its
/// ancestors, which already lie on one path. The factorisation costs `Σ depth²` and a solve
/// `2·Σ depth`, where a dense LU costs `n³/3` and `n²` (on a hexapod, 24 degrees of freedom of
/// depth at most 9: ~1,300 against ~4,600 multiply-adds, and 300 against 576).
///
/// `U` is unit upper triangular (the multipliers, above the diagonal) and `L` lower triangular,
/// both stored in place of the matrix, on its tree's entries only. There is no pivoting, as suits
/// a mass matrix (symmetric positive definite) and the semi-implicit update's matrix (the mass
/// matrix plus small velocity-dependent terms).
#[cfg_attr(feature = "serde-serialize", derive(Serialize, Deserialize))]
#[derive(Clone, Debug)]
pub struct TreeLu {
    #[cfg_attr(feature = "serde-serialize", serde(with = "portable_parents"))]
    parents: Vec<usize>,
    /// Each degree of freedom's ancestors, nearest first, all lists end to end:
    /// `ancestors[ancestor_start[k]..ancestor_start[k + 1]]` are `k`'s.
    ancestors: Vec<usize>,
    ancestor_start: Vec<usize>,
    /// Whether `factorize` built `ancestors` from `parents` (not read from a snapshot, whose
    /// lists it does not trust for its unchecked indexing: they are built again).
    #[cfg_attr(feature = "serde-serialize", serde(skip))]
    ancestors_built: bool,
    factors: DMatrix<Real>,
    singular: bool,
}

/// Parents in a snapshot as `u32`, [`NO_PARENT`] as `u32::MAX`: `usize::MAX` would be written as
/// `0xFFFF_FFFF_FFFF_FFFF` on a 64-bit target and `0xFFFF_FFFF` on a 32-bit one (bincode writes a
/// `usize` as a `u64`), and a snapshot must be the same bytes on both (`snapshot_portability`).
#[cfg(feature = "serde-serialize")]
pub(crate) mod portable_parents {
    use super::NO_PARENT;
    use crate::alloc_prelude::*;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(parents: &[usize], serializer: S) -> Result<S::Ok, S::Error> {
        let portable: Vec<u32> = parents
            .iter()
            .map(|&p| {
                if p == NO_PARENT {
                    u32::MAX
                } else {
                    u32::try_from(p).expect("fewer than 2³² − 1 degrees of freedom")
                }
            })
            .collect();
        portable.serialize(serializer)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Vec<usize>, D::Error> {
        let portable = Vec::<u32>::deserialize(deserializer)?;
        Ok(portable
            .into_iter()
            .map(|p| if p == u32::MAX { NO_PARENT } else { p as usize })
            .collect())
    }
}

impl Default for TreeLu {
    fn default() -> Self {
        TreeLu {
            parents: Vec::new(),
            ancestors: Vec::new(),
            ancestor_start: Vec::new(),
            ancestors_built: false,
            factors: DMatrix::zeros(0, 0),
            singular: false,
        }
    }
}

impl TreeLu {
    /// Factorises the leading `parents.len()` × `parents.len()` block of `matrix`, whose
    /// degree of freedom `i` has the parent `parents[i]` (`NO_PARENT` for none; parents come
    /// before their children). Allocates only when the size changes.
    pub fn factorize(&mut self, matrix: &DMatrix<Real>, parents: &[usize]) {
        let n = parents.len();
        // The ancestor lists depend on the tree only: listed again only when it changed (a
        // multibody's usually never does).
        let same_tree = self.ancestors_built && self.parents == parents;
        if !same_tree {
            self.parents.clear();
            self.parents.extend_from_slice(parents);
        }
        if self.factors.nrows() != n {
            self.factors = DMatrix::zeros(n, n);
        }
        // Column-major: entry (i, j) at `i + j * n`.
        let rows = matrix.nrows();
        let source = matrix.as_slice();
        let a = self.factors.as_mut_slice();
        for j in 0..n {
            a[j * n..(j + 1) * n].copy_from_slice(&source[j * rows..j * rows + n]);
        }

        if !same_tree {
            self.ancestors.clear();
            self.ancestor_start.clear();
            self.ancestor_start.push(0);
            for &parent in parents {
                if parent != NO_PARENT {
                    self.ancestors.push(parent);
                    let (start, end) =
                        (self.ancestor_start[parent], self.ancestor_start[parent + 1]);
                    self.ancestors.extend_from_within(start..end);
                }
                self.ancestor_start.push(self.ancestors.len());
            }
            self.ancestors_built = true;
        }

        self.singular = false;
        for k in (0..n).rev() {
            let ancestors = &self.ancestors[self.ancestor_start[k]..self.ancestor_start[k + 1]];
            // Columns before `k` and column `k` itself.
            let (before, rest) = a.split_at_mut(k * n);
            let column_k = &mut rest[..n];
            let pivot = column_k[k];
            if pivot == 0.0 {
                self.singular = true;
                continue;
            }
            // The multipliers `a[i][k] / pivot` of the row operations `row_i -= multiplier ·
            // row_k` on each ancestor `i` of `k`: row `k` has non-zeros only on `k`'s ancestors
            // by now (its descendants, eliminated before it, cleared the rest), so only entries
            // between ancestors change.
            //
            // The ancestors are indexed without bounds checks: this is the bulk of the
            // factorisation (`Σ depth²` entries), and a checked index is most of each entry's
            // work. SAFETY: each of `k`'s ancestors is less than `k`, itself less than `n`, the
            // length of `column_k` and `column_j`: the lists are built above from `parents` (by
            // this call or an earlier one on the same `parents`, never read from a snapshot),
            // where `ancestor_start[parent + 1]` exists only for a parent listed before its child.
            let inv_pivot = 1.0 / pivot;
            for &i in ancestors {
                debug_assert!(i < k);
                unsafe { *column_k.get_unchecked_mut(i) *= inv_pivot };
            }
            for &j in ancestors {
                let column_j = &mut before[j * n..(j + 1) * n];
                let akj = column_j[k];
                if akj != 0.0 {
                    for &i in ancestors {
                        unsafe {
                            *column_j.get_unchecked_mut(i) -= *column_k.get_unchecked(i) * akj;
                        }
                    }
                }
            }
        }
    }

    /// The number of rows of the factorised matrix.
    pub fn dim(&self) -> usize {
        self.parents.len()
    }

    /// Each degree of freedom's parent, `NO_PARENT` for none.
    pub fn parents(&self) -> &[usize] {
        &self.parents
    }

    /// The factors in place of the matrix: `U`'s multipliers above the diagonal, `L` on and
    /// below it; only the entries between a degree of freedom and its ancestors are meaningful.
    pub fn factors(&self) -> &DMatrix<Real> {
        &self.factors
    }

    /// Whether a pivot was zero (the matrix is singular: a solve then yields non-finite values).
    pub fn is_singular(&self) -> bool {
        self.singular
    }

    /// Solves `A·x = b` in place for every column of `b` (`dim()` rows). Returns `false` if `A`
    /// is singular.
    pub fn solve_mut<C: Dim, S: StorageMut<Real, Dyn, C>>(
        &self,
        b: &mut Matrix<Real, Dyn, C, S>,
    ) -> bool {
        let n = self.parents.len();
        assert_eq!(b.nrows(), n, "TreeLu::solve_mut: wrong number of rows");
        let a = self.factors.as_slice();
        for mut x in b.column_iter_mut() {
            // U·y = b, from the leaves up: once y_k is known it updates its ancestors.
            for k in (0..n).rev() {
                let yk = x[k];
                let column_k = &a[k * n..(k + 1) * n];
                for &i in &self.ancestors[self.ancestor_start[k]..self.ancestor_start[k + 1]] {
                    x[i] -= column_k[i] * yk;
                }
            }
            // L·x = y, from the root down: a row's off-diagonal entries are its ancestors'.
            for k in 0..n {
                let mut sum = x[k];
                for &j in &self.ancestors[self.ancestor_start[k]..self.ancestor_start[k + 1]] {
                    sum -= a[k + j * n] * x[j];
                }
                x[k] = sum / a[k + k * n];
            }
        }
        !self.singular
    }
}

#[cfg(test)]
mod test {
    use super::*;

    /// A floating base's six degrees of freedom and two legs of three: a non-symmetric matrix
    /// on the tree's pattern, solved like a dense LU.
    #[test]
    fn solves_like_a_dense_lu() {
        let mut parents = vec![NO_PARENT, 0, 1, 2, 3, 4];
        parents.extend([5, 6, 7, 5, 9, 10]);
        let n = parents.len();
        let ancestors = |mut k: usize| {
            let mut list = vec![k];
            while parents[k] != NO_PARENT {
                k = parents[k];
                list.push(k);
            }
            list
        };
        let mut matrix = DMatrix::<Real>::zeros(n, n);
        for k in 0..n {
            for &i in &ancestors(k) {
                let v = ((i * 7 + k * 3) % 5) as Real * 0.1 - 0.2;
                matrix[(i, k)] = v;
                matrix[(k, i)] = v + if i != k { 0.05 } else { 0.0 };
            }
            matrix[(k, k)] += 2.0;
        }
        let mut lu = TreeLu::default();
        lu.factorize(&matrix, &parents);
        let b = DMatrix::<Real>::from_fn(n, 3, |i, j| (i as Real - j as Real * 2.0) * 0.3);
        let mut x = b.clone();
        assert!(lu.solve_mut(&mut x));
        let expected = matrix.clone().lu().solve(&b).unwrap();
        assert!((&x - &expected).amax() < 1.0e-5, "{x} != {expected}");
        assert!((&matrix * &x - &b).amax() < 1.0e-5);
    }
}
