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
//! which brings every sticking contact to rest at the end of the step under last step's load. A
//! contact whose stopping force leaves its friction cone slides, joins K, and the rest are solved
//! again (at most once per contact). A lone contact gets exactly [`ContactModel::respond`]'s force.

use super::{ContactForce, ContactModel, ContactState, SphereGeometry};
use glam::{DMat3, DVec2, DVec3};
use rapier3d::na;

/// One contact's input to [`respond_jointly`].
pub struct JointContact<'a> {
    pub geometry: &'a SphereGeometry,
    /// Velocity of the body's material point at the contact (world).
    pub velocity: DVec3,
}

/// The most contacts solved together: a hexapod's feet (the robot loader requires six legs). The
/// solve works in fixed-size storage, so a step allocates nothing.
pub const MAX_JOINT_CONTACTS: usize = 6;

/// T_SS for up to [`MAX_JOINT_CONTACTS`] sticking contacts; unused rows and columns hold the
/// identity, which leaves their unknowns at zero.
type Block = na::SMatrix<f64, { 2 * MAX_JOINT_CONTACTS }, { 2 * MAX_JOINT_CONTACTS }>;
type Column = na::SVector<f64, { 2 * MAX_JOINT_CONTACTS }>;

/// The forces on `contacts` over a step, solved together. `mobility(i, j)` is W_ij in the
/// contacts' ground-frame axes (t₁, t₂, n): W_ij[a][b] = a_i·M⁻¹·b_j. A contact that does not touch
/// gives `None` (and its state is reset). At most [`MAX_JOINT_CONTACTS`] contacts.
pub fn respond_jointly(
    model: &ContactModel,
    contacts: &[JointContact],
    mobility: impl Fn(usize, usize) -> DMat3,
    dt: f64,
    states: &mut [ContactState],
    out: &mut [Option<ContactForce>],
) {
    let n = contacts.len();
    assert!(
        n <= MAX_JOINT_CONTACTS,
        "{n} contacts solved together, at most {MAX_JOINT_CONTACTS}"
    );
    let mut pending = [None; MAX_JOINT_CONTACTS];
    for (i, (c, state)) in contacts.iter().zip(states.iter_mut()).enumerate() {
        let normal_mass = 1.0 / mobility(i, i).z_axis.z;
        pending[i] = model.begin(c.geometry, c.velocity, normal_mass, dt, state);
    }
    let mut touching = [0; MAX_JOINT_CONTACTS];
    let mut t = 0;
    for i in (0..n).filter(|&i| pending[i].is_some()) {
        touching[t] = i;
        t += 1;
    }
    let touching = &touching[..t];
    let p = |i: usize| pending[i].as_ref().expect("touching");
    let in_plane = |w: DMat3| na::Matrix2::new(w.x_axis.x, w.y_axis.x, w.x_axis.y, w.y_axis.y);
    // force fixed by the friction law (K), or None while the contact is taken to stick (S)
    let mut fixed = [None; MAX_JOINT_CONTACTS];
    for (s, &i) in touching.iter().enumerate() {
        fixed[s] = (p(i).normal_force <= 0.0).then_some(DVec2::ZERO);
    }
    let fixed = &mut fixed[..t];
    let mut stops = [DVec2::ZERO; MAX_JOINT_CONTACTS];
    for _ in 0..=t {
        let mut sticking = [0; MAX_JOINT_CONTACTS];
        let mut m = 0;
        for s in (0..t).filter(|&s| fixed[s].is_none()) {
            sticking[m] = s;
            m += 1;
        }
        if m == 0 {
            break;
        }
        let sticking = &sticking[..m];
        let mut t_ss = Block::identity();
        let mut rhs = Column::zeros();
        for (a, &s) in sticking.iter().enumerate() {
            let i = touching[s];
            let mut r = na::Vector2::new(p(i).demand.x, p(i).demand.y);
            // the normal forces' change moves the contact too (last step's load had the old ones)
            for &j in touching {
                let w = mobility(i, j);
                r += na::Vector2::new(w.z_axis.x, w.z_axis.y) * p(j).normal_change;
            }
            for (b, &s2) in sticking.iter().enumerate() {
                t_ss.fixed_view_mut::<2, 2>(2 * a, 2 * b)
                    .copy_from(&in_plane(mobility(i, touching[s2])));
            }
            for (k, f) in fixed.iter().enumerate() {
                if let Some(f) = f {
                    let j = touching[k];
                    let g = *f - p(j).previous_friction;
                    r += in_plane(mobility(i, j)) * na::Vector2::new(g.x, g.y);
                }
            }
            rhs.fixed_rows_mut::<2>(2 * a).copy_from(&r);
        }
        // symmetrise: W is symmetric, its numerical copy only nearly
        let t_ss = (t_ss + t_ss.transpose()) * 0.5;
        let Some(x) = t_ss.lu().solve(&rhs) else {
            break;
        };
        let mut changed = false;
        for (a, &s) in sticking.iter().enumerate() {
            let pc = p(touching[s]);
            let stop = pc.previous_friction - DVec2::new(x[2 * a], x[2 * a + 1]);
            stops[s] = stop;
            let outcome = pc.friction(&model.friction, stop);
            if !outcome.sticking {
                fixed[s] = Some(outcome.force);
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    out[..n].fill(None);
    for (s, &i) in touching.iter().enumerate() {
        out[i] = Some(model.finish(p(i), stops[s], dt, &mut states[i]));
    }
}
