//! The contact mobility of the articulated robot, W = A·M⁻¹·Aᵀ, from rapier's factors of its mass
//! matrix M (M = U·L along the tree of degrees of freedom, `rapier3d::prelude::TreeLu`: no
//! fill-in, a degree of freedom couples only with its ancestors) and the contacts' axis Jacobians A
//! (one row per contact and ground axis, one column per degree of freedom).
//!
//! M is symmetric (rapier mirrors it, and adds its joints' damping and armature on the diagonal;
//! the Coriolis forces are explicit, `MultibodyRobot::build`), so its factors are L = D·Uᵀ with D
//! the pivots, M⁻¹ = U⁻ᵀ·D⁻¹·U⁻¹, and W = Yᵀ·D⁻¹·Y with Y = U⁻¹·Aᵀ: one sweep up the tree, where
//! solving with M takes a second one down, and a W symmetric by construction. Y keeps A's sparsity
//! (the sweep up fills only a contact's ancestors, already on its path).
//!
//! Why its own code: W is needed every step a foot touches, and nalgebra's generic solve on
//! dynamic matrices (one right-hand side at a time, bounds-checked views) cost more than the rest
//! of hexsim's step together. Here the right-hand sides are lanes of fixed-size rows, so each
//! elimination step is a few vector operations over all contact axes at once, and nothing
//! allocates.

use glam::{BVec4A, Vec4};
use rapier3d::prelude::{NO_PARENT, TreeLu};

/// Degrees of freedom of the hexapod's multibody with legs of three joints: the free root and 18
/// joints. Redundant legs (four to six joints each, `robot::redundant`) add 6 a joint: a
/// [`Mobility`] is sized by its `D`.
pub const DOFS: usize = 24;

/// Contact axes are lanes, in chunks of four; six contacts × three axes fit in five chunks.
const LANE: usize = 4;
const CHUNKS: usize = 5;
/// The contact axes of one group: six contacts × (t₁, t₂, n), a hexapod's feet. More contacts
/// (shins, a belly) take more groups.
pub const GROUP_AXES: usize = LANE * CHUNKS - 2;

/// One degree of freedom's entries for a group's contact axes (glam's `Vec4` is one SSE register).
/// A single lane is read and written through `as_ref` / `as_mut` (an array index), not glam's
/// `Index`, which is a match over the four lanes.
type Row = [Vec4; CHUNKS];

/// A group of contact axes: their Jacobian and its solve.
#[derive(Clone)]
struct Group<const D: usize> {
    /// Aᵀ: per degree of freedom, each contact axis' Jacobian entry; after
    /// [`Mobility::compute`], Y = U⁻¹·Aᵀ, solved in place (Aᵀ is not read again: each step sets
    /// it anew, and a copy to solve in was 200 instructions of a step).
    jacobian: [Row; D],
    /// D⁻¹·Y.
    scaled: [Row; D],
}

impl<const D: usize> Default for Group<D> {
    fn default() -> Self {
        Group {
            jacobian: [[Vec4::ZERO; CHUNKS]; D],
            scaled: [[Vec4::ZERO; CHUNKS]; D],
        }
    }
}

/// Scratch for [`Mobility::compute`], kept between steps so a step allocates nothing once it has
/// seen its most contacts; for a multibody of `D` degrees of freedom.
pub struct Mobility<const D: usize = DOFS> {
    groups: Vec<Group<D>>,
    /// W, row by contact axis, then by group of columns: `product[a·groups + h]`.
    product: Vec<Row>,
    /// Groups in use by the last [`Mobility::compute`].
    in_use: usize,
    /// Per degree of freedom, the contact axes whose entries it was set for since
    /// [`Mobility::begin`], a bit per lane of their group: the contacts whose path from the root
    /// (each with its ancestors) it is on. A row is set where it has any.
    row_axes: [u32; D],
    /// Tests: the rows read found by their entries ([`needed_rows`]), as before the rows set.
    #[cfg(test)]
    by_entries: bool,
}

impl<const D: usize> Default for Mobility<D> {
    fn default() -> Self {
        Mobility {
            groups: vec![Group::default()],
            product: vec![[Vec4::ZERO; CHUNKS]; GROUP_AXES],
            in_use: 1,
            row_axes: [0; D],
            #[cfg(test)]
            by_entries: false,
        }
    }
}

impl<const D: usize> Mobility<D> {
    /// Makes room for `axes` contact axes (allocating only the first time a step has that many).
    pub fn reserve(&mut self, axes: usize) {
        let groups = groups_for(axes);
        if groups > self.groups.len() {
            self.groups.resize_with(groups, Group::default);
        }
    }

    /// Makes room for `axes` contact axes and clears their groups' Jacobian entries, for a step
    /// that sets only each contact's non-zero ones ([`Mobility::contact`]).
    pub fn begin(&mut self, axes: usize) {
        self.reserve(axes);
        let groups = groups_for(axes);
        for group in &mut self.groups[..groups] {
            group.jacobian = [[Vec4::ZERO; CHUNKS]; D];
        }
        self.row_axes = [0; D];
    }

    /// Sets contact axis `axis`'s Jacobian entry for degree of freedom `dof` (room made by
    /// [`Mobility::reserve`]). Every entry of the axes [`Mobility::compute`] is asked for must be
    /// set (it solves in place: what is left is not Aᵀ).
    #[cfg(test)]
    fn set(&mut self, dof: usize, axis: usize, value: f32) {
        let (group, lane) = (axis / GROUP_AXES, axis % GROUP_AXES);
        self.groups[group].jacobian[dof][lane / LANE].as_mut()[lane % LANE] = value;
        self.row_axes[dof] |= 1 << lane;
    }

    /// The Jacobian entries of contact `i`'s three axes (t₁, t₂, n are axes 3i, 3i + 1, 3i + 2;
    /// room made by [`Mobility::begin`]): one lookup of its group for all its entries. Set every
    /// degree of freedom on the contact's path from the root (each with its ancestors), those
    /// whose entries are zero too: [`Mobility::compute`] solves and multiplies on those rows.
    #[inline]
    pub fn contact(&mut self, i: usize) -> ContactAxes<'_, D> {
        let first = 3 * i;
        let lanes = [0, 1, 2].map(|axis| {
            let lane = first % GROUP_AXES + axis;
            (lane / LANE, lane % LANE)
        });
        ContactAxes {
            jacobian: &mut self.groups[first / GROUP_AXES].jacobian,
            row_axes: &mut self.row_axes,
            bits: 0b111 << (first % GROUP_AXES),
            lanes,
        }
    }

    /// W = A·M⁻¹·Aᵀ for the first `axes` contact axes, given M's tree factors; `w(a, b)` then
    /// reads an entry. Returns false if the factors are not `D` square.
    pub fn compute(&mut self, factors: &TreeLu, axes: usize) -> bool {
        if factors.dim() != D {
            return false;
        }
        self.reserve(axes);
        let groups = groups_for(axes);
        self.in_use = groups;
        if self.product.len() < axes * groups {
            self.product.resize(axes * groups, [Vec4::ZERO; CHUNKS]);
        }
        if groups == 1 {
            // a hexapod's feet: one monomorphised solve and product per width, so every row
            // operation is a fixed run of registers
            match axes.div_ceil(LANE) {
                0 => {}
                1 => self.one_group::<1>(factors, axes),
                2 => self.one_group::<2>(factors, axes),
                3 => self.one_group::<3>(factors, axes),
                4 => self.one_group::<4>(factors, axes),
                _ => self.one_group::<CHUNKS>(factors, axes),
            }
            return true;
        }
        // more contacts (shins, a belly): Y and D⁻¹·Y group by group (each column of Aᵀ is
        // solved on its own), then W's blocks between every two groups
        let needed = needed_rows::<CHUNKS, D>(&self.groups[..groups], axes, factors.parents());
        for g in 0..groups {
            let valid = lanes(axes - g * GROUP_AXES);
            solve::<CHUNKS, D>(&mut self.groups[g], factors, &needed, &valid, None);
        }
        for row in &mut self.product[..axes * groups] {
            *row = [Vec4::ZERO; CHUNKS];
        }
        for g in 0..groups {
            let rows = g * GROUP_AXES..axes.min((g + 1) * GROUP_AXES);
            for d in (0..D).filter(|&d| needed[d]) {
                let y_row = self.groups[g].jacobian[d];
                for a in rows.clone() {
                    let lane = a - g * GROUP_AXES;
                    let coefficient = y_row[lane / LANE].as_ref()[lane % LANE];
                    if coefficient == 0.0 {
                        continue;
                    }
                    for h in 0..groups {
                        let z_row = &self.groups[h].scaled[d];
                        let w_row = &mut self.product[a * groups + h];
                        for c in 0..CHUNKS {
                            w_row[c] += z_row[c] * coefficient;
                        }
                    }
                }
            }
        }
        true
    }

    /// [`Mobility::compute`] for one group of axes, `C` chunks of them.
    fn one_group<const C: usize>(&mut self, factors: &TreeLu, axes: usize) {
        // the rows set, not those [`needed_rows`] finds by their entries: a superset (a row with
        // an entry was set, and so were its ancestors, on the same path), whose extra rows are
        // zero in every lane of this step's axes, and stay so (a zero row adds to no ancestor
        // in the solve), so the product, which skips zero coefficients, reads nothing of them
        // and W is the same bit for bit; without a scan of every row's lanes
        let needed = self.row_axes.map(|axes| axes != 0);
        #[cfg(test)]
        let needed = if self.by_entries {
            needed_rows::<C, D>(&self.groups[..1], axes, factors.parents())
        } else {
            needed
        };
        debug_assert!(
            (0..D).all(|k| !needed[k]
                || factors.parents()[k] == NO_PARENT
                || needed[factors.parents()[k]]),
            "the rows set are closed under their ancestors"
        );
        let group = &mut self.groups[0];
        #[cfg(test)]
        let rows_set = (!self.by_entries).then_some(&needed);
        #[cfg(not(test))]
        let rows_set = Some(&needed);
        solve::<C, D>(group, factors, &needed, &lanes(axes), rows_set);
        // W = Yᵀ·(D⁻¹·Y), row a = Σ_d Y[d][a]·(D⁻¹·Y)[d] (Y is sparse: a foot moves with the
        // root and its leg, and a row without entries, not needed, adds nothing)
        let product = &mut self.product[..axes];
        for row in product.iter_mut() {
            *row = [Vec4::ZERO; CHUNKS];
        }
        // Y[d][a] is zero off contact a's path (Aᵀ is, and the solve adds a row only to its
        // ancestors, on the same paths), so a row is read at its contacts' lanes (`row_axes`)
        // alone, not each of its lanes tested: those branches, taken or not as the feet fall,
        // were mispredicted (callgrind's branch simulation, hex18's walk: 90 → 70 mispredicted
        // a step in the contact mobility, 500 instructions more). The terms skipped are zero,
        // and each W[a] sums the same terms in the same order (d rising): bit for bit the same.
        let this_step = (1u32 << axes) - 1;
        let rows =
            (group.jacobian.iter().zip(&group.scaled)).zip(needed.iter().zip(&self.row_axes));
        for ((y_row, z_row), (&needed, &on_path)) in rows {
            if !needed {
                continue;
            }
            #[cfg(test)]
            let on_path = if self.by_entries { u32::MAX } else { on_path };
            let mut lanes = on_path & this_step;
            while lanes != 0 {
                let a = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let coefficient = y_row[a / LANE].as_ref()[a % LANE];
                if coefficient != 0.0 {
                    let w_row = &mut product[a];
                    for c in 0..C {
                        w_row[c] += z_row[c] * coefficient;
                    }
                }
            }
        }
    }

    /// W's 3 × 3 block between contacts `i` and `j` (axes t₁, t₂, n each; `w` of their axes,
    /// read at once: a contact's three axes lie in one group), as `[column][row]`, columns by
    /// `j`'s axes.
    #[inline]
    pub fn block(&self, i: usize, j: usize) -> [[f32; 3]; 3] {
        let (group, first) = (3 * j / GROUP_AXES, 3 * j % GROUP_AXES);
        let mut block = [[0.0; 3]; 3];
        for (b, column) in block.iter_mut().enumerate() {
            let lane = first + b;
            for (a, entry) in column.iter_mut().enumerate() {
                *entry = self.product[(3 * i + a) * self.in_use + group][lane / LANE].as_ref()
                    [lane % LANE];
            }
        }
        block
    }

    /// W's rows of contact `i`'s three axes (t₁, t₂, n), each as one run of lanes, where one
    /// group holds every axis (six contacts at most; None otherwise): [`Mobility::block`]`(i,
    /// j)`'s column b is lane 3j + b of the three, read without a group and lane worked out a
    /// entry.
    #[inline]
    pub fn rows_of(&self, i: usize) -> Option<[[f32; LANE * CHUNKS]; 3]> {
        (self.in_use == 1).then(|| {
            std::array::from_fn(|a| {
                let lanes: [[f32; LANE]; CHUNKS] = self.product[3 * i + a].map(|v| v.to_array());
                *lanes.as_flattened().as_array().expect("a row's lanes")
            })
        })
    }

    /// W's entry for contact axes `a` and `b`.
    #[cfg(test)]
    fn w(&self, a: usize, b: usize) -> f32 {
        let (group, lane) = (b / GROUP_AXES, b % GROUP_AXES);
        self.product[a * self.in_use + group][lane / LANE].as_ref()[lane % LANE]
    }
}

/// One contact's three axes in its group's Jacobian ([`Mobility::contact`]).
pub struct ContactAxes<'a, const D: usize> {
    jacobian: &'a mut [Row; D],
    row_axes: &'a mut [u32; D],
    /// The contact's three lanes' bits in `row_axes`.
    bits: u32,
    /// Each axis' chunk and lane in a row, found once for all the contact's entries.
    lanes: [(usize, usize); 3],
}

impl<const D: usize> ContactAxes<'_, D> {
    /// Sets the contact's three axes' (t₁, t₂, n) entries for degree of freedom `dof`.
    #[inline]
    pub fn set(&mut self, dof: usize, values: [f32; 3]) {
        let row = &mut self.jacobian[dof];
        for (&(chunk, lane), value) in self.lanes.iter().zip(values) {
            row[chunk].as_mut()[lane] = value;
        }
        self.row_axes[dof] |= self.bits;
    }
}

/// The groups that hold `axes` contact axes (at least one, kept between steps).
fn groups_for(axes: usize) -> usize {
    axes.div_ceil(GROUP_AXES).max(1)
}

/// The lanes of a group that hold this step's contact axes. The others keep the entries of an
/// earlier step's contacts (a step sets only the axes it has): they are solved along, lanes
/// being independent right-hand sides, but never read.
type Lanes = [BVec4A; CHUNKS];

/// A group's first `axes` lanes (at most [`GROUP_AXES`]).
fn lanes(axes: usize) -> Lanes {
    let axes = axes.min(GROUP_AXES);
    std::array::from_fn(|c| {
        let lane = |l: usize| LANE * c + l < axes;
        BVec4A::new(lane(0), lane(1), lane(2), lane(3))
    })
}

/// Whether a row has an entry in one of `lanes`' (its first `C` chunks).
#[inline]
fn has_entry<const C: usize>(row: &Row, lanes: &Lanes) -> bool {
    (0..C).any(|c| (row[c].cmpne(Vec4::ZERO) & lanes[c]).any())
}

/// Which rows of M⁻¹·Aᵀ the product W = A·(M⁻¹·Aᵀ) reads: those where one of the `axes`
/// contact axes (over `groups`) has a Jacobian entry, and their ancestors, which the lower
/// solve reads on the way down. A leg whose foot is in the air (half of them in a tripod's
/// stance) has none.
///
/// `C`: the chunks that hold the axes (a single group's first `C`; [`CHUNKS`] for several): the
/// lanes past them are not valid, so they are not looked at.
fn needed_rows<const C: usize, const D: usize>(
    groups: &[Group<D>],
    axes: usize,
    parents: &[usize],
) -> [bool; D] {
    let mut needed = [false; D];
    for (g, group) in groups.iter().enumerate() {
        let valid = lanes(axes.saturating_sub(g * GROUP_AXES));
        for (k, row) in group.jacobian.iter().enumerate() {
            needed[k] |= has_entry::<C>(row, &valid);
        }
    }
    for k in (0..D).rev() {
        if needed[k] && parents[k] != NO_PARENT {
            needed[parents[k]] = true;
        }
    }
    needed
}

/// Y = U⁻¹·Aᵀ in place in `group.jacobian` (holding Aᵀ) from the tree factors (column-major,
/// entries only between a degree of freedom and its ancestors), and D⁻¹·Y into `group.scaled`;
/// `C` chunks of lanes. Only the rows `needed` ([`needed_rows`]) are scaled; the others are left
/// as they are, and the product never reads them.
///
/// What is skipped changes no bit of what is read: a row that is zero in every lane of this
/// step's axes (`valid`) would subtract nothing from its ancestors' (y − 0·u = y). A leg in the
/// air so costs the solve nothing (its three rows, each with a chain of up to eight ancestors).
fn solve<const C: usize, const D: usize>(
    group: &mut Group<D>,
    factors: &TreeLu,
    needed: &[bool; D],
    valid: &Lanes,
    rows_set: Option<&[bool; D]>,
) {
    let parents = factors.parents();
    let a = factors.factors().as_slice();
    let (y, scaled) = (&mut group.jacobian, &mut group.scaled);
    // U·Y = Aᵀ (unit upper): from the leaves up, a solved row updates its ancestors'
    for k in (0..D).rev() {
        let yk = y[k];
        // the rows set, where known ([`Mobility::contact`]: the rows unset are zero in every
        // lane), else the rows with an entry in this step's lanes; a row set and zero in them
        // all subtracts zeros, which change no bit of a non-zero entry, and the product reads
        // none of the zero ones (it skips zero coefficients, and adds a zero term to a sum that
        // starts at +0 and so is never −0)
        let solved = match rows_set {
            Some(set) => set[k],
            None => has_entry::<C>(&yk, valid),
        };
        if !solved {
            continue;
        }
        let mut i = parents[k];
        while i != NO_PARENT {
            let u = a[i + k * D];
            for c in 0..C {
                y[i][c] -= yk[c] * u;
            }
            i = parents[i];
        }
    }
    // D⁻¹·Y, D the diagonal of L
    for k in (0..D).filter(|&k| needed[k]) {
        let inverse = 1.0 / a[k + k * D];
        for (z, y) in scaled[k][..C].iter_mut().zip(&y[k][..C]) {
            *z = *y * inverse;
        }
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

    /// Six feet's axes (one group) and a belly's too (several groups, W's blocks across them).
    #[test]
    fn matches_a_dense_solve() {
        for axes in [11, 18, 47, 48] {
            let parents = parents();
            assert_eq!(parents.len(), DOFS);
            let m = mass(&parents);
            let mut factors = TreeLu::default();
            factors.factorize(&m, &parents);
            let a = na::DMatrix::<f32>::from_fn(axes, DOFS, |r, d| {
                // sparse like a foot's row: the root's six and three more
                if d < 6 || (d - 6) / 3 == r % 6 {
                    ((r * 5 + d * 3) % 17) as f32 / 17.0 - 0.4
                } else {
                    0.0
                }
            });
            let mut mobility = Mobility::<DOFS>::default();
            mobility.reserve(axes);
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
                    if axes % 3 == 0 {
                        // whole contacts: their blocks read the same entries
                        assert_eq!(mobility.block(r / 3, c / 3)[c % 3][r % 3], mobility.w(r, c));
                    }
                    assert!(
                        error <= 1e-4 * scale,
                        "{axes} axes: W[{r}][{c}] off by {error}"
                    );
                }
            }
        }
    }

    /// Legs without contacts are skipped, judged on this step's axes alone: after a step with
    /// six feet down, a step with two (the other lanes holding the six's entries) gets the
    /// same W bit for bit as a fresh solve, and the dense one's within rounding.
    #[test]
    fn legs_in_the_air_are_skipped_exactly() {
        let parents = parents();
        let m = mass(&parents);
        let mut factors = TreeLu::default();
        factors.factorize(&m, &parents);
        let jacobian = |axes: usize, legs: usize| {
            na::DMatrix::<f32>::from_fn(axes, DOFS, |r, d| {
                if d < 6 || (d - 6) / 3 == (r / 3) % legs {
                    ((r * 5 + d * 3) % 17) as f32 / 17.0 - 0.4
                } else {
                    0.0
                }
            })
        };
        let fill = |mobility: &mut Mobility, a: &na::DMatrix<f32>| {
            mobility.reserve(a.nrows());
            for r in 0..a.nrows() {
                for d in 0..DOFS {
                    mobility.set(d, r, a[(r, d)]);
                }
            }
            assert!(mobility.compute(&factors, a.nrows()));
        };
        let mut reused = Mobility::default();
        fill(&mut reused, &jacobian(18, 6));
        let two = jacobian(6, 2);
        fill(&mut reused, &two);
        let mut fresh = Mobility::default();
        fill(&mut fresh, &two);
        let expected = &two * m.try_inverse().expect("invertible") * two.transpose();
        for r in 0..6 {
            for c in 0..6 {
                assert_eq!(reused.w(r, c).to_bits(), fresh.w(r, c).to_bits());
                let error = (reused.w(r, c) - expected[(r, c)]).abs();
                assert!(
                    error <= 1e-4 * expected.amax(),
                    "W[{r}][{c}] off by {error}"
                );
            }
        }
    }

    /// The rows set (the contacts' paths) read instead of those found by their entries, each at
    /// its contacts' lanes only instead of at every lane: W bit for bit the same, with path rows
    /// whose entries are zero (a foot's last joint that does not move it along any axis), and a
    /// step with fewer contacts after one with more.
    #[test]
    fn the_rows_set_give_the_same_w_as_the_rows_with_entries() {
        let parents = parents();
        let m = mass(&parents);
        let mut factors = TreeLu::default();
        factors.factorize(&m, &parents);
        let mut by_paths = Mobility::<DOFS>::default();
        let mut by_entries = Mobility::<DOFS> {
            by_entries: true,
            ..Default::default()
        };
        for (step, legs) in [[0, 2, 4, 5], [1, 3, 5, 0], [2, 4, 0, 0]]
            .iter()
            .enumerate()
        {
            let n = if step == 2 { 2 } else { 4 };
            for mobility in [&mut by_paths, &mut by_entries] {
                mobility.begin(3 * n);
                for (i, &leg) in legs[..n].iter().enumerate() {
                    let mut axes = mobility.contact(i);
                    let path = (0..6).chain(6 + 3 * leg..9 + 3 * leg);
                    for dof in path {
                        let value = |a: usize| {
                            let x = ((dof * 7 + a * 5 + i * 3 + step) % 13) as f32 / 13.0 - 0.4;
                            // the leaf's row zero on the first contact, an entry zero here and there
                            if (i == 0 && dof == 8 + 3 * leg) || x.abs() < 0.05 {
                                0.0
                            } else {
                                x
                            }
                        };
                        axes.set(dof, [value(0), value(1), value(2)]);
                    }
                }
                assert!(mobility.compute(&factors, 3 * n));
            }
            for a in 0..3 * n {
                for b in 0..3 * n {
                    assert_eq!(
                        by_paths.w(a, b).to_bits(),
                        by_entries.w(a, b).to_bits(),
                        "step {step}: W[{a}][{b}]"
                    );
                }
            }
            // a contact's rows, as one run of lanes each, give its blocks
            for i in 0..n {
                let rows = by_paths.rows_of(i).expect("one group");
                for j in 0..n {
                    let block = by_paths.block(i, j);
                    for (b, column) in block.iter().enumerate() {
                        for (a, entry) in column.iter().enumerate() {
                            assert_eq!(entry.to_bits(), rows[a][3 * j + b].to_bits());
                        }
                    }
                }
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
        assert!(!Mobility::<DOFS>::default().compute(&factors, 3));
    }
}
