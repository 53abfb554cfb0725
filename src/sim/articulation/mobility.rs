//! The contact mobility of the articulated robot, W = A·M⁻¹·Aᵀ, from rapier's LU factors of its
//! mass matrix M (P·M = L·U) and the contacts' axis Jacobians A (one row per contact and ground
//! axis, one column per degree of freedom).
//!
//! Why its own code: W is needed every step a foot touches, and nalgebra's generic solve on
//! dynamic matrices (one right-hand side at a time, bounds-checked views) cost more than the rest
//! of hexsim's step together. Here the right-hand sides are lanes of fixed-size rows, so each
//! elimination step is a few vector operations over all contact axes at once, and nothing
//! allocates.

use glam::Vec4;
use rapier3d::na;

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

    /// W = A·M⁻¹·Aᵀ for the first `axes` contact axes, given M's LU factors; `w(a, b)` then reads
    /// an entry. Returns false if the factors are not [`DOFS`] square.
    pub fn compute(&mut self, lu: &na::LU<f32, na::Dyn, na::Dyn>, axes: usize) -> bool {
        let packed = lu.lu_internal();
        if packed.nrows() != DOFS || packed.ncols() != DOFS {
            return false;
        }
        debug_assert!(axes <= MAX_AXES);
        // P·Aᵀ: rapier's LU pivots rows; applying its swaps to the row indices gives the order
        let mut order = na::SVector::<usize, DOFS>::from_fn(|i, _| i);
        lu.p().permute_rows(&mut order);
        for (row, &from) in self.solved.iter_mut().zip(order.iter()) {
            *row = self.jacobian[from];
        }
        // one monomorphised solve per width, so every row operation is a fixed run of registers
        let factors = packed.as_slice();
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

    /// M⁻¹·(P·Aᵀ) in place from the packed column-major factors, then W = A·X; `C` chunks of lanes.
    fn solve<const C: usize>(&mut self, factors: &[f32], axes: usize) {
        let x = &mut self.solved;
        // L·Y = P·Aᵀ (unit diagonal), forward, column by column of L
        for k in 0..DOFS {
            let column = &factors[k * DOFS..(k + 1) * DOFS];
            let (done, rest) = x.split_at_mut(k + 1);
            let yk = done[k];
            for (yi, &l) in rest.iter_mut().zip(&column[k + 1..]) {
                for c in 0..C {
                    yi[c] -= yk[c] * l;
                }
            }
        }
        // U·X = Y, backward, column by column of U
        for k in (0..DOFS).rev() {
            let column = &factors[k * DOFS..(k + 1) * DOFS];
            let inverse = 1.0 / column[k];
            let (above, rest) = x.split_at_mut(k);
            let xk = &mut rest[0];
            for v in &mut xk[..C] {
                *v *= inverse;
            }
            let xk = *xk;
            for (xi, &u) in above.iter_mut().zip(&column[..k]) {
                for c in 0..C {
                    xi[c] -= xk[c] * u;
                }
            }
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

    /// A symmetric positive-definite matrix that needs pivoting (small leading diagonal).
    fn mass() -> na::DMatrix<f32> {
        let mut m = na::DMatrix::<f32>::from_fn(DOFS, DOFS, |i, j| {
            let x = ((i * 7 + j * 13) % 11) as f32 / 11.0 - 0.5;
            let y = ((j * 7 + i * 13) % 11) as f32 / 11.0 - 0.5;
            0.3 * (x + y)
        });
        for i in 0..DOFS {
            m[(i, i)] += if i == 0 { 0.05 } else { 4.0 };
        }
        m
    }

    #[test]
    fn matches_a_dense_solve() {
        let m = mass();
        let lu = m.clone().lu();
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
        assert!(mobility.compute(&lu, axes));
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
        let lu = na::DMatrix::<f32>::identity(6, 6).lu();
        assert!(!Mobility::default().compute(&lu, 3));
    }
}
