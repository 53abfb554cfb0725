//! The contact mobility of the articulated robot, W = A·M⁻¹·Aᵀ, from rapier's factors of its mass
//! matrix M (M = U·L along the tree of degrees of freedom, `rapier3d::prelude::TreeLu`: no
//! fill-in, a degree of freedom couples only with its ancestors) and the contacts' axis Jacobians A
//! (one row per contact and ground axis, one column per degree of freedom).
//!
//! Why its own code: W is needed every step a foot touches, and nalgebra's generic solve on
//! dynamic matrices (one right-hand side at a time, bounds-checked views) cost more than the rest
//! of hexsim's step together. Here the right-hand sides are lanes of fixed-size rows, so each
//! elimination step is a few vector operations over all contact axes at once, and nothing
//! allocates.

use glam::Vec4;
use rapier3d::prelude::{NO_PARENT, TreeLu};

/// Degrees of freedom of the hexapod's multibody: the free root and 18 joints (the robot loader
/// requires six legs of three joints).
pub const DOFS: usize = 24;

/// Contact axes are lanes, in chunks of four; six contacts × three axes fit in five chunks.
const LANE: usize = 4;
const CHUNKS: usize = 5;
/// The most contact axes: six feet × (t₁, t₂, n).
pub const MAX_AXES: usize = LANE * CHUNKS - 2;

/// One degree of freedom's entries for every contact axis (glam's `Vec4` is one SSE register).
type Row = [Vec4; CHUNKS];

/// Scratch for [`Mobility::compute`], kept between steps so a step allocates nothing.
pub struct Mobility {
    /// Aᵀ: per degree of freedom, each contact axis' Jacobian entry.
    jacobian: [Row; DOFS],
    /// M⁻¹·Aᵀ, solved in place.
    solved: [Row; DOFS],
    /// W, row by contact axis.
    product: [Row; MAX_AXES],
}

impl Default for Mobility {
    fn default() -> Self {
        Mobility {
            jacobian: [[Vec4::ZERO; CHUNKS]; DOFS],
            solved: [[Vec4::ZERO; CHUNKS]; DOFS],
            product: [[Vec4::ZERO; CHUNKS]; MAX_AXES],
        }
    }
}

impl Mobility {
    /// Sets contact axis `axis`'s Jacobian entry for degree of freedom `dof`. Every entry of the
    /// axes [`Mobility::compute`] is asked for must be set (entries are kept between steps).
    #[inline]
    pub fn set(&mut self, dof: usize, axis: usize, value: f32) {
        self.jacobian[dof][axis / LANE][axis % LANE] = value;
    }

    /// W = A·M⁻¹·Aᵀ for the first `axes` contact axes, given M's tree factors; `w(a, b)` then
    /// reads an entry. Returns false if the factors are not [`DOFS`] square.
    pub fn compute(&mut self, factors: &TreeLu, axes: usize) -> bool {
        if factors.dim() != DOFS {
            return false;
        }
        debug_assert!(axes <= MAX_AXES);
        self.solved = self.jacobian;
        // one monomorphised solve per width, so every row operation is a fixed run of registers
        match axes.div_ceil(LANE) {
            0 => {}
            1 => self.solve::<1>(factors, axes),
            2 => self.solve::<2>(factors, axes),
            3 => self.solve::<3>(factors, axes),
            4 => self.solve::<4>(factors, axes),
            _ => self.solve::<CHUNKS>(factors, axes),
        }
        true
    }

    /// M⁻¹·Aᵀ in place from the tree factors (column-major, entries only between a degree of
    /// freedom and its ancestors), then W = A·X; `C` chunks of lanes.
    fn solve<const C: usize>(&mut self, factors: &TreeLu, axes: usize) {
        let parents = factors.parents();
        let a = factors.factors().as_slice();
        let x = &mut self.solved;
        // U·Y = Aᵀ (unit upper): from the leaves up, a solved row updates its ancestors'
        for k in (0..DOFS).rev() {
            let yk = x[k];
            let mut i = parents[k];
            while i != NO_PARENT {
                let u = a[i + k * DOFS];
                for c in 0..C {
                    x[i][c] -= yk[c] * u;
                }
                i = parents[i];
            }
        }
        // L·X = Y (lower): from the root down, a row's off-diagonal entries are its ancestors'
        for k in 0..DOFS {
            let mut row = x[k];
            let mut j = parents[k];
            while j != NO_PARENT {
                let l = a[k + j * DOFS];
                for c in 0..C {
                    row[c] -= x[j][c] * l;
                }
                j = parents[j];
            }
            let inverse = 1.0 / a[k + k * DOFS];
            for v in &mut row[..C] {
                *v *= inverse;
            }
            x[k] = row;
        }
        // W = A·X, row a = Σ_d A[a][d]·X[d] (A is sparse: a foot moves with the root and its leg)
        for row in &mut self.product[..axes] {
            *row = [Vec4::ZERO; CHUNKS];
        }
        for (a_row, x_row) in self.jacobian.iter().zip(x.iter()) {
            for (a, w_row) in self.product[..axes].iter_mut().enumerate() {
                let coefficient = a_row[a / LANE][a % LANE];
                if coefficient != 0.0 {
                    for c in 0..C {
                        w_row[c] += x_row[c] * coefficient;
                    }
                }
            }
        }
    }

    /// W's entry for contact axes `a` and `b`.
    #[inline]
    pub fn w(&self, a: usize, b: usize) -> f32 {
        self.product[a][b / LANE][b % LANE]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::na;

    /// The hexapod's tree of degrees of freedom: the free base's six in a chain, then six legs
    /// of three hanging from its last.
    fn parents() -> Vec<usize> {
        let mut parents: Vec<usize> = (0..6usize).map(|d| d.wrapping_sub(1)).collect();
        parents[0] = NO_PARENT;
        for _leg in 0..6 {
            parents.extend([5, parents.len(), parents.len() + 1]);
        }
        parents
    }

    fn on_one_path(parents: &[usize], i: usize, j: usize) -> bool {
        let (low, mut high) = (i.min(j), i.max(j));
        while high != NO_PARENT && high > low {
            high = parents[high];
        }
        high == low
    }

    /// A symmetric positive-definite matrix with the tree's pattern (as a mass matrix has).
    fn mass(parents: &[usize]) -> na::DMatrix<f32> {
        let mut m = na::DMatrix::<f32>::from_fn(DOFS, DOFS, |i, j| {
            if !on_one_path(parents, i, j) {
                return 0.0;
            }
            let x = ((i * 7 + j * 13) % 11) as f32 / 11.0 - 0.5;
            let y = ((j * 7 + i * 13) % 11) as f32 / 11.0 - 0.5;
            0.3 * (x + y)
        });
        for i in 0..DOFS {
            m[(i, i)] += if i == 0 { 0.5 } else { 4.0 };
        }
        m
    }

    #[test]
    fn matches_a_dense_solve() {
        let parents = parents();
        assert_eq!(parents.len(), DOFS);
        let m = mass(&parents);
        let mut factors = TreeLu::default();
        factors.factorize(&m, &parents);
        let axes = 11;
        let a = na::DMatrix::<f32>::from_fn(axes, DOFS, |r, d| {
            // sparse like a foot's row: the root's six and three more
            if d < 6 || (d - 6) / 3 == r % 6 {
                ((r * 5 + d * 3) % 17) as f32 / 17.0 - 0.4
            } else {
                0.0
            }
        });
        let mut mobility = Mobility::default();
        for r in 0..axes {
            for d in 0..DOFS {
                mobility.set(d, r, a[(r, d)]);
            }
        }
        assert!(mobility.compute(&factors, axes));
        let expected = &a * m.try_inverse().expect("invertible") * a.transpose();
        let scale = expected.amax();
        for r in 0..axes {
            for c in 0..axes {
                let error = (mobility.w(r, c) - expected[(r, c)]).abs();
                assert!(error <= 1e-4 * scale, "W[{r}][{c}] off by {error}");
            }
        }
    }

    #[test]
    fn rejects_factors_of_another_size() {
        let mut factors = TreeLu::default();
        factors.factorize(
            &na::DMatrix::<f32>::identity(6, 6),
            &[NO_PARENT, 0, 1, 2, 3, 4],
        );
        assert!(!Mobility::default().compute(&factors, 3));
    }
}
