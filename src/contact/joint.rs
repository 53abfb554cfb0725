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

use super::{ContactForce, ContactModel, ContactState, PendingContact, SphereGeometry};
use glam::{DMat3, DVec2, DVec3};
use rapier3d::na;

/// One contact's input to [`respond_jointly`].
pub struct JointContact<'a> {
    pub geometry: &'a SphereGeometry,
    /// Velocity of the body's material point at the contact (world).
    pub velocity: DVec3,
}

/// The forces on `contacts` over a step, solved together. `mobility(i, j)` is W_ij in the
/// contacts' ground-frame axes (t₁, t₂, n): W_ij[a][b] = a_i·M⁻¹·b_j. A contact that does not touch
/// gives `None` (and its state is reset).
pub fn respond_jointly(
    model: &ContactModel,
    contacts: &[JointContact],
    mobility: impl Fn(usize, usize) -> DMat3,
    dt: f64,
    states: &mut [ContactState],
    out: &mut [Option<ContactForce>],
) {
    let n = contacts.len();
    let mut pending: Vec<Option<PendingContact>> = Vec::with_capacity(n);
    for (c, state) in contacts.iter().zip(states.iter_mut()) {
        let normal_mass = 1.0 / mobility(pending.len(), pending.len()).z_axis.z;
        pending.push(model.begin(c.geometry, c.velocity, normal_mass, dt, state));
    }
    let touching: Vec<usize> = (0..n).filter(|&i| pending[i].is_some()).collect();
    let p = |i: usize| pending[i].as_ref().expect("touching");
    let in_plane = |w: DMat3| na::Matrix2::new(w.x_axis.x, w.y_axis.x, w.x_axis.y, w.y_axis.y);
    // force fixed by the friction law (K), or None while the contact is taken to stick (S)
    let mut fixed: Vec<Option<DVec2>> = touching
        .iter()
        .map(|&i| (p(i).normal_force <= 0.0).then_some(DVec2::ZERO))
        .collect();
    let mut stops = vec![DVec2::ZERO; touching.len()];
    for _ in 0..=touching.len() {
        let sticking: Vec<usize> = (0..touching.len())
            .filter(|&s| fixed[s].is_none())
            .collect();
        let m = sticking.len();
        if m == 0 {
            break;
        }
        let mut t_ss = na::DMatrix::<f64>::zeros(2 * m, 2 * m);
        let mut rhs = na::DVector::<f64>::zeros(2 * m);
        for (a, &s) in sticking.iter().enumerate() {
            let i = touching[s];
            let mut r = na::Vector2::new(p(i).demand.x, p(i).demand.y);
            // the normal forces' change moves the contact too (last step's load had the old ones)
            for &j in &touching {
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
        let t_ss = (&t_ss + t_ss.transpose()) * 0.5;
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
