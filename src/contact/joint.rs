//! Several contacts on one body in the same step — a walking robot's stance feet.
//!
//! Each contact's stopping force F_stop = F_prev − M·u (see `friction`) assumes it is alone. But
//! stance feet push each other through the body: with contact mobility W (velocity change per
//! impulse, v⁺ = v + W·p), a force at foot j moves foot i by W_ij. Setting every foot's stopping
//! force as if alone is a Jacobi sweep of the joint problem; on a robot whose feet share one light
//! body it overshoots and the feet chatter and slide. So the stopping forces of the contacts that
//! stick are solved for together: with T the in-plane blocks of W, S the sticking contacts and K
//! the others (sliding, or without normal force, whose forces the friction law fixes),
//!
//!   F_S = F_prev,S − T_SS⁻¹·(u_S + T_SK·(F_K − F_prev,K)),
//!
//! which brings every sticking contact to rest at the end of the step under last step's load. Of
//! the contacts whose stopping forces leave their friction cones, the one furthest outside (the
//! ratio of its stopping force to the friction it can give) slides and joins K, and the rest are
//! solved again — one at a time, as an active-set method releases constraints: two faces of one
//! foot in a corner are nearly the same column of T_SS, their stopping forces a large internal
//! pair that cancels, and released together each kept its half (a foot pushed along its own slip
//! by 90 N, `ladder/gaps.toml` at 4 cm). A lone contact gets exactly [`ContactModel::respond`]'s
//! force.

use super::{ContactForce, ContactModel, ContactState, PendingContact, SphereGeometry};
use glam::{DMat3, DVec2, DVec3};
use rapier3d::na;

/// One contact's input to [`respond_jointly`].
pub struct JointContact {
    pub geometry: SphereGeometry,
    /// Velocity of the body's material point at the contact (world).
    pub velocity: DVec3,
    /// How many touching contacts share this one's rigid link this step (≥ 1): their normal
    /// dampers act on the link together, so each damps 1/n of its effective mass — n exact-decay
    /// dampers c on mass M/n sum to the exact decay of n·c on M (see `normal`), where n dampers
    /// each sized for M alone would take n times too much velocity out and overshoot.
    pub sharing: usize,
}

/// Where [`JointSolver::respond`] reads and writes contact `i`'s state between steps: a slice of
/// the contacts' own, or the caller's storage reached through an index — a state is 168 bytes,
/// and copied out and back it was two calls to `memcpy` a contact a step.
pub trait ContactStates {
    fn state(&mut self, i: usize) -> &mut ContactState;
}

impl ContactStates for [ContactState] {
    #[inline]
    fn state(&mut self, i: usize) -> &mut ContactState {
        &mut self[i]
    }
}

/// The most sticking contacts solved in fixed-size storage (a hexapod's feet): a step with more
/// (a belly on the ground) solves in storage it allocates.
pub const MAX_JOINT_CONTACTS: usize = 6;

/// T_SS for up to [`MAX_JOINT_CONTACTS`] sticking contacts; unused rows and columns hold the
/// identity, which leaves their unknowns at zero.
type Block = na::SMatrix<f64, { 2 * MAX_JOINT_CONTACTS }, { 2 * MAX_JOINT_CONTACTS }>;
type Column = na::SVector<f64, { 2 * MAX_JOINT_CONTACTS }>;

/// Singular values below this fraction of T_SS's largest count as zero in the least-squares
/// solve of a singular joint problem (coincident contacts); a Cholesky or LU solution amplifying the
/// right-hand side by more than its inverse (a condition number past 10⁹) is not trusted.
const SINGULAR: f64 = 1e-9;

/// The sticking contacts' T_SS·x = rhs: by Cholesky (or LU) when T_SS is well conditioned, else the
/// least-squares solution of least norm (contacts that nearly coincide share their force instead
/// of pulling against each other with huge internal forces). `active`: the rows in use; the
/// unused ones (fixed-size storage) are padded with the active block's scale, so that the padding
/// neither sets the cut-off nor hides the block's own. None if even that is not finite (a
/// mobility with NaN).
fn solve_sticking<D>(
    mut t_ss: na::OMatrix<f64, D, D>,
    rhs: &na::OVector<f64, D>,
    active: usize,
) -> Option<na::OVector<f64, D>>
where
    D: na::DimMin<D, Output = D> + na::DimSub<na::U1>,
    na::DefaultAllocator: na::allocator::Allocator<D, D>
        + na::allocator::Allocator<D>
        + na::allocator::Allocator<na::DimDiff<D, na::U1>>,
{
    let scale = (0..active).map(|k| t_ss[(k, k)].abs()).fold(0.0, f64::max);
    let scale = if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
    };
    for k in active..t_ss.nrows() {
        t_ss[(k, k)] = scale;
    }
    solve_trusted(t_ss.clone(), rhs, active).or_else(|| {
        let svd = t_ss.svd(true, true);
        let largest = svd.singular_values.amax();
        svd.solve(rhs, SINGULAR * largest)
            .ok()
            .filter(|x| x.iter().all(|v| v.is_finite()))
    })
}

/// T_SS·x = rhs (`active` rows in use, the rest padded as [`solve_sticking`] pads them), if its
/// answer is finite and trusted (see [`SINGULAR`]): by Cholesky, T_SS being symmetric positive
/// definite when the contacts' points are apart (a block of the mobility W = A·M⁻¹·Aᵀ, half an
/// LU's work and no pivot search), else, nearly singular, by LU.
fn solve_trusted<D>(
    t_ss: na::OMatrix<f64, D, D>,
    rhs: &na::OVector<f64, D>,
    active: usize,
) -> Option<na::OVector<f64, D>>
where
    D: na::DimMin<D, Output = D>,
    na::DefaultAllocator: na::allocator::Allocator<D, D> + na::allocator::Allocator<D>,
{
    let scale = (0..active).map(|k| t_ss[(k, k)].abs()).fold(0.0, f64::max);
    let scale = if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
    };
    let finite = |x: &na::OVector<f64, D>| x.iter().all(|v| v.is_finite());
    let trusted = |x: &na::OVector<f64, D>| x.amax() * scale * SINGULAR <= rhs.amax();
    // a pivot below the cut-off relative to T_SS's scale: nearly singular (contacts that nearly
    // coincide), where the answer's split between them is rounding's, not the least-norm one
    let conditioned = |c: &na::Cholesky<f64, D>| {
        let l = c.l_dirty();
        (0..active).all(|k| l[(k, k)] * l[(k, k)] > SINGULAR * scale)
    };
    if let Some(x) = t_ss
        .clone()
        .cholesky()
        .filter(conditioned)
        .map(|c| c.solve(rhs))
        .filter(|x| finite(x) && trusted(x))
    {
        return Some(x);
    }
    t_ss.lu().solve(rhs).filter(|x| finite(x) && trusted(x))
}

/// T_SS·x = rhs for `m` sticking contacts, from their 2×2 blocks, into `out` (one 2-vector per
/// contact): in fixed-size storage up to [`MAX_JOINT_CONTACTS`], else in storage of their size.
/// False if there is no trustworthy solution (see [`solve_sticking`]).
fn solve_blocks(
    m: usize,
    block: impl Fn(usize, usize) -> na::Matrix2<f64>,
    rhs: impl Fn(usize) -> na::Vector2<f64>,
    out: &mut Vec<DVec2>,
) -> bool {
    // on exactly the rows in use first: the padded solve below gives these rows the same
    // arithmetic bit for bit (the padding's rows and columns are zero beside the block, so they
    // never win a pivot and subtract only zeros) at a fraction of its cost (12 × 12 for three
    // feet's 6 × 6); where that answer is not trusted, the padded solve as before
    macro_rules! exact {
        ($($k:literal => $d:ty),*) => {
            match m {
                $($k => {
                    let mut t_ss = na::OMatrix::<f64, $d, $d>::zeros();
                    let mut column = na::OVector::<f64, $d>::zeros();
                    fill_blocks(&mut t_ss, &mut column, m, &block, &rhs);
                    solve_trusted(t_ss, &column, 2 * m)
                        .map(|x| store(x.as_slice(), m, out))
                        .is_some()
                })*
                _ => false,
            }
        };
    }
    let exact =
        exact!(1 => na::U2, 2 => na::U4, 3 => na::U6, 4 => na::U8, 5 => na::U10, 6 => na::U12);
    if exact {
        return true;
    }
    let solution = if m <= MAX_JOINT_CONTACTS {
        let (mut t_ss, mut column) = (Block::identity(), Column::zeros());
        fill_blocks(&mut t_ss, &mut column, m, &block, &rhs);
        solve_sticking(t_ss, &column, 2 * m).map(|x| store(x.as_slice(), m, out))
    } else {
        let mut t_ss = na::DMatrix::zeros(2 * m, 2 * m);
        let mut column = na::DVector::zeros(2 * m);
        fill_blocks(&mut t_ss, &mut column, m, &block, &rhs);
        solve_sticking(t_ss, &column, 2 * m).map(|x| store(x.as_slice(), m, out))
    };
    solution.is_some()
}

/// T_SS's first 2m rows and columns, symmetrised (W is symmetric, its numerical copy only
/// nearly), and the right-hand side.
fn fill_blocks<R, C, S, R2, S2>(
    t_ss: &mut na::Matrix<f64, R, C, S>,
    column: &mut na::Matrix<f64, R2, na::U1, S2>,
    m: usize,
    block: &impl Fn(usize, usize) -> na::Matrix2<f64>,
    rhs: &impl Fn(usize) -> na::Vector2<f64>,
) where
    R: na::Dim,
    C: na::Dim,
    R2: na::Dim,
    S: na::StorageMut<f64, R, C>,
    S2: na::StorageMut<f64, R2, na::U1>,
{
    for a in 0..m {
        // the block below the diagonal is the one above it transposed, bit for bit (a sum is
        // the same either way round): each pair of blocks is read and summed once
        for b in a..m {
            let symmetric = (block(a, b) + block(b, a).transpose()) * 0.5;
            t_ss.fixed_view_mut::<2, 2>(2 * a, 2 * b)
                .copy_from(&symmetric);
            if b != a {
                t_ss.fixed_view_mut::<2, 2>(2 * b, 2 * a)
                    .copy_from(&symmetric.transpose());
            }
        }
        column.fixed_rows_mut::<2>(2 * a).copy_from(&rhs(a));
    }
}

/// A solution's pairs as one 2-vector per contact.
fn store(x: &[f64], m: usize, out: &mut Vec<DVec2>) {
    out.clear();
    out.extend((0..m).map(|a| DVec2::new(x[2 * a], x[2 * a + 1])));
}

/// Scratch for [`JointSolver::respond`], kept between steps so that a step allocates nothing
/// once it has seen its largest number of contacts.
#[derive(Default)]
pub struct JointSolver {
    pending: Vec<Option<PendingContact>>,
    touching: Vec<usize>,
    /// Per touching contact: its force fixed by the friction law (K), or None while it is taken
    /// to stick (S).
    fixed: Vec<Option<DVec2>>,
    stops: Vec<DVec2>,
    sticking: Vec<usize>,
    /// The joint solve's answer per sticking contact.
    solution: Vec<DVec2>,
}

/// The forces on `contacts` over a step, solved together (see the module docs), with scratch
/// of its own: [`JointSolver::respond`] for a loop.
pub fn respond_jointly(
    model: &ContactModel,
    contacts: &[JointContact],
    mobility: impl Fn(usize, usize) -> DMat3,
    dt: f64,
    states: &mut [ContactState],
    out: &mut [Option<ContactForce>],
) {
    JointSolver::default().respond(model, contacts, mobility, dt, states, out);
}

impl JointSolver {
    /// The forces on `contacts` over a step, solved together. `mobility(i, j)` is W_ij in the
    /// contacts' ground-frame axes (t₁, t₂, n): W_ij[a][b] = a_i·M⁻¹·b_j. A contact that does
    /// not touch gives `None` (and its state is reset).
    pub fn respond(
        &mut self,
        model: &ContactModel,
        contacts: &[JointContact],
        mobility: impl Fn(usize, usize) -> DMat3,
        dt: f64,
        states: &mut (impl ContactStates + ?Sized),
        out: &mut [Option<ContactForce>],
    ) {
        let n = contacts.len();
        let JointSolver {
            pending,
            touching,
            fixed,
            stops,
            sticking,
            solution,
        } = self;
        pending.clear();
        for (i, c) in contacts.iter().enumerate() {
            let normal_mass = 1.0 / mobility(i, i).z_axis.z / c.sharing.max(1) as f64;
            let alone = c.sharing <= 1;
            let state = states.state(i);
            pending.push(model.begin(&c.geometry, c.velocity, normal_mass, alone, dt, state));
        }
        touching.clear();
        touching.extend((0..n).filter(|&i| pending[i].is_some()));
        let t = touching.len();
        let p = |i: usize| pending[i].as_ref().expect("touching");
        let in_plane = |w: DMat3| na::Matrix2::new(w.x_axis.x, w.y_axis.x, w.x_axis.y, w.y_axis.y);
        fixed.clear();
        fixed.extend(
            touching
                .iter()
                .map(|&i| (p(i).normal_force <= 0.0).then_some(DVec2::ZERO)),
        );
        stops.clear();
        stops.resize(t, DVec2::ZERO);
        for _ in 0..=t {
            sticking.clear();
            sticking.extend((0..t).filter(|&s| fixed[s].is_none()));
            let m = sticking.len();
            if m == 0 {
                break;
            }
            let rhs = |a: usize| {
                let i = touching[sticking[a]];
                let mut r = na::Vector2::new(p(i).demand.x, p(i).demand.y);
                // the normal forces' change moves the contact too (last step's load had the old
                // ones)
                for &j in touching.iter() {
                    let w = mobility(i, j);
                    r += na::Vector2::new(w.z_axis.x, w.z_axis.y) * p(j).normal_change;
                }
                for (k, f) in fixed.iter().enumerate() {
                    if let Some(f) = f {
                        let j = touching[k];
                        let g = *f - p(j).previous_friction;
                        r += in_plane(mobility(i, j)) * na::Vector2::new(g.x, g.y);
                    }
                }
                r
            };
            // T_SS is singular when contacts coincide (two spheres on one point): any split of their force stops them,
            // and the least-squares solution of least norm shares it equally
            let block = |a: usize, b: usize| {
                in_plane(mobility(touching[sticking[a]], touching[sticking[b]]))
            };
            if !solve_blocks(m, block, rhs, solution) {
                // not even that (a mobility with NaN): each contact's force as if alone
                for &s in sticking.iter() {
                    let pc = p(touching[s]);
                    let t_ii = in_plane(mobility(touching[s], touching[s]));
                    stops[s] = match t_ii.try_inverse() {
                        Some(mass) => {
                            let u = mass * na::Vector2::new(pc.demand.x, pc.demand.y);
                            pc.previous_friction - DVec2::new(u.x, u.y)
                        }
                        None => DVec2::splat(f64::INFINITY),
                    };
                }
                break;
            }
            // the contact whose stopping force lies furthest outside its friction cone slides;
            // the others are solved again without it
            let mut worst: Option<(usize, f64, DVec2)> = None;
            for (a, &s) in sticking.iter().enumerate() {
                let pc = p(touching[s]);
                let stop = pc.previous_friction - solution[a];
                stops[s] = stop;
                let outcome = pc.friction(&model.friction, stop);
                if !outcome.sticking {
                    let excess = stop.length() / outcome.force.length().max(f64::MIN_POSITIVE);
                    if worst.is_none_or(|(_, e, _)| excess > e) {
                        worst = Some((s, excess, outcome.force));
                    }
                }
            }
            match worst {
                Some((s, _, force)) => fixed[s] = Some(force),
                None => break,
            }
        }
        out[..n].fill(None);
        for (s, &i) in touching.iter().enumerate() {
            let outcome = p(i).friction(&model.friction, stops[s]);
            let outcome = p(i).unjammed(outcome, mobility(i, i));
            out[i] = Some(ContactModel::conclude(p(i), outcome, dt, states.state(i)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::EffectiveMass;
    use crate::terrain::GroundFrame;

    const DT: f64 = 1e-3;

    /// A rigid body (mass, inverse inertia about its centre of mass at the origin) and contact
    /// points on it: W_ij = I/m − [r_i]×·I⁻¹·[r_j]× in world axes, expressed in the contacts'
    /// ground-frame axes (t₁, t₂, n).
    struct Body {
        mass: f64,
        inverse_inertia: DMat3,
        arms: Vec<DVec3>,
        frames: Vec<GroundFrame>,
    }

    fn cross(r: DVec3) -> DMat3 {
        DMat3::from_cols(
            DVec3::new(0.0, r.z, -r.y),
            DVec3::new(-r.z, 0.0, r.x),
            DVec3::new(r.y, -r.x, 0.0),
        )
    }

    impl Body {
        fn axes(&self, i: usize) -> DMat3 {
            let f = &self.frames[i];
            DMat3::from_cols(f.tangent_x, f.tangent_y, f.normal)
        }

        fn mobility(&self, i: usize, j: usize) -> DMat3 {
            let world = DMat3::from_diagonal(DVec3::splat(1.0 / self.mass))
                - cross(self.arms[i]) * self.inverse_inertia * cross(self.arms[j]);
            self.axes(i).transpose() * world * self.axes(j)
        }

        fn geometry(&self, i: usize, penetration: f64) -> SphereGeometry {
            SphereGeometry {
                penetration,
                point: self.arms[i],
                frame: self.frames[i],
            }
        }

        /// Two contacts on this body, from rest, solved together: both must touch.
        fn respond_pair(
            &self,
            model: &ContactModel,
            contacts: &[JointContact; 2],
        ) -> [ContactForce; 2] {
            let mut states = [ContactState::default(); 2];
            let mut out = [None; 2];
            respond_jointly(
                model,
                contacts,
                |i, j| self.mobility(i, j),
                DT,
                &mut states,
                &mut out,
            );
            out.map(|f| f.unwrap())
        }
    }

    fn tilted(nx: f64, ny: f64) -> GroundFrame {
        GroundFrame::from_normal(DVec3::new(nx, ny, 1.0).normalize())
    }

    /// A contact alone on its body gets exactly the force `ContactModel::respond` gives it with
    /// the same effective mass, step after step, sticking and sliding (a ball: its arm is along
    /// the normal, so the normal force does not push the contact sideways).
    #[test]
    fn a_lone_contact_gets_the_force_of_respond() {
        let frame = tilted(0.2, -0.1);
        let (m, r) = (1.0, 0.05);
        let body = Body {
            mass: m,
            inverse_inertia: DMat3::from_diagonal(DVec3::splat(1.0 / (0.4 * m * r * r))),
            arms: vec![-r * frame.normal],
            frames: vec![frame],
        };
        let mass = EffectiveMass::rigid_body(m, body.inverse_inertia, body.arms[0], &frame);
        let model = ContactModel::default();
        let (mut alone, mut jointly) = (ContactState::default(), ContactState::default());
        let mut sticking = [0, 0];
        for k in 0..200 {
            // slow enough to stick, then fast enough to slide, with the load changing
            let speed = if k < 100 { 2e-4 } else { 0.3 };
            let velocity = frame.to_world(DVec3::new(
                speed * (k as f64 * 0.1).cos(),
                speed * (k as f64 * 0.07).sin(),
                -0.01 * (k as f64 * 0.2).sin(),
            ));
            let geometry = body.geometry(0, 1e-3 * (1.0 + 0.3 * (k as f64 * 0.05).sin()));
            let expected = model
                .respond(&geometry, velocity, &mass, DT, &mut alone)
                .unwrap();
            let mut out = [None];
            respond_jointly(
                &model,
                &[JointContact {
                    geometry,
                    velocity,
                    sharing: 1,
                }],
                |i, j| body.mobility(i, j),
                DT,
                std::slice::from_mut(&mut jointly),
                &mut out,
            );
            let got = out[0].unwrap();
            assert_eq!(got.sticking, expected.sticking, "step {k}");
            let error = (got.force - expected.force).length();
            assert!(
                error <= 1e-9 * expected.force.length(),
                "step {k}: {:?} against {:?}",
                got.force,
                expected.force
            );
            sticking[usize::from(got.sticking)] += 1;
        }
        assert!(
            sticking[0] > 50 && sticking[1] > 50,
            "{sticking:?} (slid, stuck)"
        );
    }

    /// A body with two contacts off its centre (two feet of one robot), both touching down slowly
    /// enough to stick: the joint forces, applied as impulses over the step through the body's
    /// mobility, leave both contact points without in-plane velocity. Solving each alone (a Jacobi
    /// sweep) does not: each foot's force moves the other.
    #[test]
    fn two_coupled_contacts_that_stick_are_both_stopped() {
        let body = Body {
            mass: 3.0,
            inverse_inertia: DMat3::from_diagonal(DVec3::new(1.0 / 0.02, 1.0 / 0.03, 1.0 / 0.04)),
            // on opposite sides of the centre of mass and a little below it, so the touch-down's
            // normal forces nearly balance (one-sided or far below, they would tip the body over,
            // swinging the points sideways, whatever the friction)
            arms: vec![
                DVec3::new(0.12, 0.09, -0.02),
                DVec3::new(-0.11, -0.1, -0.02),
            ],
            frames: vec![tilted(0.1, 0.0), tilted(-0.05, 0.15)],
        };
        // a grippy ground, so that the touch-down's normal impulse, which pushes each point
        // sideways through the body's rotation, stays inside the friction cones
        let model = ContactModel {
            friction: crate::contact::FrictionLaw::Karnopp {
                mu_static: 1.5,
                mu_kinetic: 1.4,
                stick_band: 1e-3,
            },
            ..ContactModel::default()
        };
        let slips = [
            DVec3::new(3e-4, -2e-4, -0.005),
            DVec3::new(-1e-4, 4e-4, -0.005),
        ];
        let velocities: Vec<DVec3> = (0..2).map(|i| body.axes(i) * slips[i]).collect();
        let geometries = [body.geometry(0, 1e-3), body.geometry(1, 1e-3)];
        let contacts = [0, 1].map(|i| JointContact {
            geometry: geometries[i],
            velocity: velocities[i],
            sharing: 1,
        });
        let forces = body.respond_pair(&model, &contacts);
        assert!(forces.iter().all(|f| f.sticking), "{forces:?}");
        // against a dense solve of the module's equation, F_S = F_prev − T⁻¹·(u + W_n·ΔN), with
        // u, ΔN and F_prev from each contact's own `begin`
        let pending = [0, 1].map(|i| {
            model
                .begin(
                    &geometries[i],
                    velocities[i],
                    1.0 / body.mobility(i, i).z_axis.z,
                    true,
                    DT,
                    &mut ContactState::default(),
                )
                .unwrap()
        });
        let t = na::DMatrix::<f64>::from_fn(4, 4, |r, c| {
            let w = body.mobility(r / 2, c / 2);
            w.col(c % 2)[r % 2]
        });
        let rhs = na::DVector::<f64>::from_fn(4, |r, _| {
            let i = r / 2;
            let coupling: f64 = (0..2)
                .map(|j| body.mobility(i, j).z_axis[r % 2] * pending[j].normal_change)
                .sum();
            pending[i].demand[r % 2] + coupling
        });
        let x = t.lu().solve(&rhs).expect("T is invertible");
        for i in 0..2 {
            let expected = pending[i].previous_friction - DVec2::new(x[2 * i], x[2 * i + 1]);
            let got = body.axes(i).transpose() * forces[i].friction;
            let error = (got.truncate() - expected).length();
            assert!(
                error < 1e-9 * expected.length(),
                "contact {i}: {got} against {expected}"
            );
        }
        // and what that means: v⁺_i = v_i + dt·Σ_j W_ij·F_j (contact i's axes; forces in j's)
        let after = |jointly: [DVec3; 2]| {
            [0, 1].map(|i| {
                let change: DVec3 = (0..2)
                    .map(|j| body.mobility(i, j) * (body.axes(j).transpose() * jointly[j]))
                    .sum();
                slips[i] + DT * change
            })
        };
        for (i, v) in after([forces[0].force, forces[1].force]).iter().enumerate() {
            let in_plane = v.truncate().length();
            assert!(in_plane < 1e-9, "contact {i} still slips at {in_plane} m/s");
        }
        // each contact stopped as if alone leaves them moving
        let alone: [DVec3; 2] = [0, 1].map(|i| {
            let mut state = ContactState::default();
            let mass = EffectiveMass::rigid_body(
                body.mass,
                body.inverse_inertia,
                body.arms[i],
                &body.frames[i],
            );
            model
                .respond(&geometries[i], velocities[i], &mass, DT, &mut state)
                .unwrap()
                .force
        });
        let worst = after(alone)
            .iter()
            .map(|v| v.truncate().length())
            .fold(0.0, f64::max);
        assert!(
            worst > 1e-5,
            "solved alone, the contacts still slip at most {worst} m/s"
        );
    }

    /// Two contacts at the same point of a body (a foot that two collision spheres would both
    /// report, or a URDF with duplicated feet) make the joint problem singular: T_SS has two equal
    /// block rows. The stopping forces are then the least-squares (minimum-norm) solution — the
    /// contacts share the force that stops the point, together exactly the lone contact's — not
    /// zero, which is what a failed LU solve used to leave them with (reported as sticking).
    #[test]
    fn coincident_contacts_share_the_force_that_stops_them() {
        let frame = tilted(0.1, -0.2);
        let (m, r) = (1.0, 0.05);
        let arm = -r * frame.normal;
        let body = Body {
            mass: m,
            inverse_inertia: DMat3::from_diagonal(DVec3::splat(1.0 / (0.4 * m * r * r))),
            arms: vec![arm, arm],
            frames: vec![frame, frame],
        };
        let model = ContactModel::default();
        let velocity = frame.to_world(DVec3::new(3e-4, -2e-4, -0.01));
        let geometry = body.geometry(0, 1e-3);
        let contacts = [0, 1].map(|_| JointContact {
            geometry,
            velocity,
            sharing: 1,
        });
        let forces = body.respond_pair(&model, &contacts);
        assert!(forces.iter().all(|f| f.sticking), "{forces:?}");
        // the pair's friction stops the point as one contact with the pair's normal impulse would
        let total = forces[0].friction + forces[1].friction;
        let slip = frame.to_local(velocity).truncate();
        let mobility = body.mobility(0, 0);
        let t = glam::DMat2::from_cols(mobility.x_axis.truncate(), mobility.y_axis.truncate());
        let normal_push = mobility.z_axis.truncate() * (forces[0].normal_force * 2.0);
        let after = slip + DT * (t * frame.to_local(total).truncate() + normal_push);
        assert!(
            after.length() < 1e-9 && total.length() > 0.1,
            "friction {total} leaves the point slipping at {after}"
        );
        assert!(
            (forces[0].friction - forces[1].friction).length() < 1e-9 * total.length(),
            "shared unequally: {:?}",
            [forces[0].friction, forces[1].friction]
        );
    }

    /// A 5 g foot wedged between two walls (PhantomX's in a 4 cm trench: k = 12,382 N/m,
    /// c = 93 N·s/m, 0.5 ms), each pressing it 1 mm, pushed at 20 N into one and set moving at
    /// 0.3 m/s, the two contacts solved together as a walk solves them. Each wall's damper
    /// reverses the foot every step; a damper reading the other's force as a push to answer
    /// (`ContactModel::begin`) pumped it, 0.48 m/s still after 150 ms in this set-up and 13 m/s
    /// in a ladder's trench. Its speed must die out and the walls hold it.
    #[test]
    fn a_foot_wedged_between_two_walls_settles() {
        let (m, h) = (0.005, 5e-4);
        let model = ContactModel {
            normal: crate::contact::NormalLaw::SpringDamper {
                stiffness: 12_382.0,
                damping: 93.0,
            },
            ..ContactModel::default()
        };
        let (radius, half_width) = (0.007, 0.006);
        let walls = [1.0f64, -1.0];
        let frames = walls.map(|wall| GroundFrame::from_normal(DVec3::new(-wall, 0.0, 0.0)));
        let axes = |f: &GroundFrame| DMat3::from_cols(f.tangent_x, f.tangent_y, f.normal);
        let (mut x, mut v) = (0.0f64, 0.3f64);
        let mut states = [ContactState::default(); 2];
        let (mut deepest, mut late_speed) = (0.0f64, 0.0f64);
        for step in 0..400 {
            let contacts = [0, 1].map(|i| JointContact {
                geometry: SphereGeometry {
                    penetration: radius - (walls[i] * half_width - x).abs(),
                    point: DVec3::new(walls[i] * half_width, 0.0, 0.0),
                    frame: frames[i],
                },
                velocity: DVec3::new(v, 0.0, 0.0),
                sharing: 2,
            });
            let mut out = [None; 2];
            respond_jointly(
                &model,
                &contacts,
                |i, j| axes(&frames[i]).transpose() * axes(&frames[j]) / m,
                h,
                &mut states,
                &mut out,
            );
            let mut force = 20.0;
            for f in out.iter().flatten() {
                force += f.force.x;
                deepest = deepest.max(f.penetration);
            }
            v += h / m * force;
            x += h * v;
            if step >= 300 {
                late_speed = late_speed.max(v.abs());
            }
        }
        assert!(late_speed < 1e-3, "still rattling at {late_speed} m/s");
        assert!(deepest < 3e-3, "{} mm deep", deepest * 1e3);
    }

    /// n contacts sharing one rigid body (a box landing flat on its four corner spheres) damp it
    /// as one damper of n·c: each sized for M/n, their forces over a step sum to
    /// M·ẋ·(1 − e^(−n·c·h/M))/h, so the body's approach decays by exactly e^(−n·c·h/M) in the
    /// step. n dampers each sized for M alone (φ(c·h/M) each) would take 2.2 times that here
    /// (n·c·h/M = 3) and throw the box back up.
    #[test]
    fn dampers_sharing_a_body_decay_as_one_of_their_sum() {
        let (mass, c, h, x) = (0.2, 150.0, 1e-3, 1e-9);
        let model = ContactModel {
            normal: crate::contact::NormalLaw::SpringDamper {
                stiffness: 2e4,
                damping: c,
            },
            ..ContactModel::default()
        };
        let frame = GroundFrame::from_normal(DVec3::Z);
        let approach = 0.3;
        for n in [1usize, 2, 4] {
            let contacts: Vec<JointContact> = (0..n)
                .map(|i| JointContact {
                    geometry: SphereGeometry {
                        penetration: x,
                        point: DVec3::new(0.1 * i as f64, 0.0, 0.0),
                        frame,
                    },
                    velocity: DVec3::new(0.0, 0.0, -approach),
                    sharing: n,
                })
                .collect();
            let mut states = vec![ContactState::default(); n];
            let mut out = vec![None; n];
            // a particle: every contact's unit impulse moves every other contact by 1/M
            let w = |_: usize, _: usize| DMat3::IDENTITY / mass;
            respond_jointly(&model, &contacts, w, h, &mut states, &mut out);
            let damper: f64 =
                out.iter().flatten().map(|f| f.normal_force).sum::<f64>() - n as f64 * 2e4 * x;
            let after = approach - damper * h / mass;
            let exact = approach * (-(n as f64) * c * h / mass).exp();
            assert!(
                (after - exact).abs() <= 1e-12 * approach,
                "n = {n}: {after} m/s after a step, the exact decay {exact}"
            );
        }
    }

    /// Two contacts a nanometre apart: T_SS is singular to within rounding, and an LU solve
    /// returns huge opposite internal forces that the friction cone then clips (the contacts
    /// reported sliding). Solved with the cut-off relative to T_SS's own scale they share the
    /// force that stops the point, as coincident ones do; so also on a body 1000 times as heavy,
    /// whose mobility is far below the identity that pads the unused rows.
    #[test]
    fn nearly_coincident_contacts_share_the_force_too() {
        for m in [1.0, 1000.0] {
            let frame = tilted(0.1, -0.2);
            let r = 0.05;
            let arm = -r * frame.normal;
            let body = Body {
                mass: m,
                inverse_inertia: DMat3::from_diagonal(DVec3::splat(1.0 / (0.4 * m * r * r))),
                arms: vec![arm, arm + 1e-9 * frame.tangent_x],
                frames: vec![frame, frame],
            };
            let model = ContactModel::default();
            // a slip the friction can stop within a step on either body
            let velocity = frame.to_world(DVec3::new(3e-4 / m, -2e-4 / m, -0.01));
            let geometry = body.geometry(0, 1e-3);
            let contacts = [0, 1].map(|_| JointContact {
                geometry,
                velocity,
                sharing: 1,
            });
            let forces = body.respond_pair(&model, &contacts);
            assert!(forces.iter().all(|f| f.sticking), "m = {m}: {forces:?}");
            let total = (forces[0].friction + forces[1].friction).length();
            assert!(
                (forces[0].friction - forces[1].friction).length() < 1e-3 * total,
                "m = {m}: shared unequally: {:?}",
                [forces[0].friction, forces[1].friction]
            );
        }
    }

    /// A foot at the bottom of a 4 cm trench (`ladder/gaps.toml` at 0.04, perceptive), sliding
    /// along it at 1.8 m/s: pressed 3.5 mm into the floor and grazing the wall, two faces of one
    /// sphere a centimetre apart whose tangents share the sliding direction (W₂₂, W₂₃, W₃₃
    /// along it: 31.7, 29.6, 27.6 /kg — nearly equal columns), with two other feet standing.
    /// Solved together the two faces pull against each other with large internal forces; both
    /// leaving their cones at once, each kept its share, and the floor's pushed the foot along
    /// its slip (90 N along 1.8 m/s; the next steps 103, 125 N, the foot 6 m/s and 6.5 mm deep).
    /// Released one at a time, the worst first, the friction on the foot opposes its slip.
    /// The state as recorded in that run, step 11703.
    #[test]
    fn the_faces_of_one_sphere_never_push_it_along_its_slip() {
        // W_ij, column by column (t₁, t₂, n of contact j, in contact i's axes), as recorded
        #[rustfmt::skip]
        const W: [[f64; 9]; 16] = [
            [13.879, 4.19563, 1.26304, 4.19563, 49.9444, 10.5644, 1.26304, 10.5644, 13.0669],
            [-0.188831, -0.212682, 0.0852528, 0.265814, -0.195101, 0.0562346, 0.0129103, -0.00849655, 0.00243171],
            [0.110407, 0.219019, -0.0858394, -0.426702, 0.00913882, -0.00359338, -0.51471, 0.239997, -0.10614],
            [-0.485217, 0.263166, -0.114014, -0.443982, -0.0107504, 0.00149234, -0.0910047, -0.203776, 0.0806594],
            [-0.188831, 0.265814, 0.0129105, -0.212682, -0.195101, -0.00849652, 0.0852527, 0.0562346, 0.00243172],
            [32.8866, -12.2798, 13.8437, -12.2798, 27.3749, -10.7969, 13.8437, -10.7969, 19.0894],
            [-0.375034, -0.0660098, 0.00818244, -0.00319344, -0.37182, -0.0244451, -0.425319, -0.55873, -0.0390174],
            [-0.467772, -0.560074, -0.0409794, 0.0483066, -0.338299, -0.0115053, 0.347105, 0.0651254, -0.00947344],
            [0.110407, -0.426702, -0.51471, 0.219019, 0.0091389, 0.239997, -0.0858392, -0.00359342, -0.10614],
            [-0.375034, -0.00319363, -0.425319, -0.06601, -0.37182, -0.55873, 0.00818251, -0.024445, -0.0390174],
            [28.7937, 12.7703, -10.4734, 12.7703, 31.6681, -11.9367, -10.4734, -11.9367, 8.22923],
            [-8.9114, -10.2762, 7.35691, 12.6378, 29.5533, -11.2724, -27.7661, -11.6779, 9.89948],
            [-0.485217, -0.443982, -0.0910046, 0.263166, -0.0107504, -0.203776, -0.114014, 0.0014923, 0.0806591],
            [-0.467772, 0.0483066, 0.347105, -0.560074, -0.338299, 0.0651255, -0.0409795, -0.0115052, -0.00947333],
            [-8.9114, 12.6378, -27.7661, -10.2762, 29.5533, -11.6779, 7.35691, -11.2724, 9.89948],
            [6.64136, -9.7251, 8.44065, -9.7251, 27.6358, -11.6198, 8.44064, -11.6198, 26.8063],
        ];
        let mobility = |i: usize, j: usize| DMat3::from_cols_array(&W[4 * i + j]);
        let floor = GroundFrame::from_normal(DVec3::Z);
        let wall = GroundFrame::from_normal(-DVec3::X);
        let contact = |penetration, point, frame, velocity, sharing| JointContact {
            geometry: SphereGeometry {
                penetration,
                point,
                frame,
            },
            velocity,
            sharing,
        };
        let contacts = [
            contact(
                7.4265e-4,
                DVec3::new(0.75626, 0.233, 0.0),
                floor,
                DVec3::new(-0.075419, 0.0111528, -0.066954),
                1,
            ),
            contact(
                3.9467e-4,
                DVec3::new(0.99163, -0.1697, 0.0),
                floor,
                DVec3::new(0.0652881, 0.00116988, -0.0152451),
                1,
            ),
            contact(
                3.54548e-3,
                DVec3::new(0.525189, -0.138559, -0.1),
                floor,
                DVec3::new(-0.0388154, 1.78579, -0.758251),
                2,
            ),
            contact(
                1.89025e-4,
                DVec3::new(0.535, -0.138559, -0.0935455),
                wall,
                DVec3::new(-0.0804004, 1.65782, -0.695041),
                2,
            ),
        ];
        let state = |friction: DVec3, slip: DVec3, drift: DVec3, normal_force| ContactState {
            previous: Some((friction, slip)),
            drift,
            normal_force,
            rolling: None,
            damper: None,
        };
        let mut states = [
            state(
                DVec3::new(4.79432, -7.54403, 0.0),
                DVec3::new(-0.0704037, 0.0174882, 0.0),
                DVec3::new(1.05383e-4, 1.48907e-5, 0.0),
                17.3148,
            ),
            state(
                DVec3::new(3.76128, 4.9577, 0.0),
                DVec3::new(0.0702582, 0.0287343, 0.0),
                DVec3::ZERO,
                7.77877,
            ),
            state(
                DVec3::new(10.536, 56.8375, 0.0),
                DVec3::new(-0.123813, 1.11438, 0.0),
                DVec3::ZERO,
                95.4976,
            ),
            state(
                DVec3::new(0.0, -1.85724, 1.25981),
                DVec3::new(0.0, 1.02933, -0.698224),
                DVec3::ZERO,
                2.80526,
            ),
        ];
        let mut out = [None; 4];
        respond_jointly(
            &ContactModel::default(),
            &contacts,
            mobility,
            DT,
            &mut states,
            &mut out,
        );
        let [floor_face, wall_face] = [out[2].unwrap(), out[3].unwrap()];
        let slip = floor_face.slip;
        assert!(slip.length() > 1.7, "{slip}");
        let on_foot = floor_face.friction + wall_face.friction;
        assert!(
            on_foot.dot(slip) < 0.0 && floor_face.friction.dot(slip) < 0.0,
            "friction {} on the floor, {} on the wall, along the slip {slip}",
            floor_face.friction,
            wall_face.friction
        );
    }
}
