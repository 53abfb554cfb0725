//! Rolling resistance and spin friction: torques of at most ρ·Fn against a body's rolling — its
//! angular velocity about the ground plane's axes — and of at most μ_t·Fn against its spin about
//! the normal (MuJoCo's condim 6 and 4, in the same units), solved together with the contact's
//! friction.
//!
//! Why together: a torque turns the body about its centre, which moves the contact point; the
//! friction turns it back. Chosen one after the other, each reads the other's effect as a load and
//! they fight (measured: a ball that should rest on a 2.5° slope jittered at 2 mm/s). So the
//! contact's five unknowns g = (F₁, F₂, T₁, T₂, Tₙ) — the friction force and the rolling torque
//! along the ground frame's tangents, and the spin torque about its normal — are solved as one
//! stick problem, as Karnopp friction is for one (see `friction`): with the generalised velocity
//! s = (slip₁, slip₂, ω₁, ω₂, ωₙ) and the body's mobility W (velocity change per impulse,
//! s⁺ = s + h·W·g),
//!
//!   g_stop = g_prev − W⁻¹·u,   u = (2s − s_prev)/h (s/h on a contact's first step),
//!
//! which stops the slip, the rolling and the spin within the step under last step's load (the
//! friction's part of u also carries its drift recovery). Each torque is its stopping value while
//! within its limit, else the limit against the motion, which cannot reverse it; the friction law
//! decides whether F_stop holds (else it slides, with its law's force). A part that saturates is
//! fixed and the others solved again with it (at most twice). A ball so stops, and stays at rest
//! on a slope it can hold (tan θ ≤ ρ/r), without creeping; its spin decays at μ_t·Fn/I.

use super::{ContactForce, ContactModel, ContactState, EffectiveMass, SphereGeometry};
use glam::{DVec2, DVec3};
use rapier3d::na;

type Matrix5 = na::SMatrix<f64, 5, 5>;
type Vector5 = na::SVector<f64, 5>;

/// A rigid body with an isotropic rotational inertia (a sphere) at its contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RollingBody {
    pub mass: f64,
    /// Moment of inertia about any axis through the centre of mass (kg·m²).
    pub inertia: f64,
    /// From the contact point to the centre of mass (world).
    pub arm: DVec3,
    /// The body's angular velocity (world).
    pub angular_velocity: DVec3,
}

/// The unknowns g solved with some of them fixed: for the free ones F,
/// g_F = g_prev,F − W_FF⁻¹·(u_F + W_FS·(g_S − g_prev,S)). None if W_FF is singular.
fn solve_free(
    w: &Matrix5,
    u: &Vector5,
    previous: &Vector5,
    fixed: &[Option<f64>; 5],
) -> Option<Vector5> {
    let free: Vec<usize> = (0..5).filter(|&k| fixed[k].is_none()).collect();
    let mut g = *previous;
    for k in 0..5 {
        if let Some(v) = fixed[k] {
            g[k] = v;
        }
    }
    if free.is_empty() {
        return Some(g);
    }
    let n = free.len();
    let w_ff = na::DMatrix::from_fn(n, n, |a, b| w[(free[a], free[b])]);
    let rhs = na::DVector::from_fn(n, |a, _| {
        u[free[a]]
            + (0..5)
                .filter(|k| fixed[*k].is_some())
                .map(|k| w[(free[a], k)] * (g[k] - previous[k]))
                .sum::<f64>()
    });
    let step = w_ff.try_inverse()? * rhs;
    for (a, &k) in free.iter().enumerate() {
        g[k] = previous[k] - step[a];
    }
    Some(g)
}

/// A torque's stopping value `stop` within `limit`, else the limit against the motion `motion`;
/// and whether it saturated. A motion slower than `still` (what one step of the limit torque
/// changes) is numerical noise as far as a step can tell, and its direction would be too: the
/// torque then acts along the stopping value, against the load that overcomes it.
fn saturate(stop: DVec2, limit: f64, motion: DVec2, still: f64) -> (DVec2, bool) {
    if stop.length() <= limit {
        (stop, false)
    } else if motion.length() > still {
        (-limit * motion / motion.length(), true)
    } else {
        (stop * (limit / stop.length()), true)
    }
}

impl ContactModel {
    /// [`Self::respond`] for a rolling body (a ball): the contact's force, and the rolling
    /// resistance's and spin friction's torque about the body's centre of mass (zero when both
    /// are 0, and then the force is exactly [`Self::respond`]'s). `None` when it does not touch.
    pub fn respond_rolling(
        &self,
        geometry: &SphereGeometry,
        point_velocity: DVec3,
        body: &RollingBody,
        dt: f64,
        state: &mut ContactState,
    ) -> Option<(ContactForce, DVec3)> {
        let r = -body.arm;
        let frame = &geometry.frame;
        let (t1, t2, n) = (frame.tangent_x, frame.tangent_y, frame.normal);
        let inverse_inertia = glam::DMat3::from_diagonal(DVec3::splat(1.0 / body.inertia));
        let mass = EffectiveMass::rigid_body(body.mass, inverse_inertia, r, frame);
        let pending = self.begin(geometry, point_velocity, mass.normal, true, dt, state)?;
        if self.rolling_resistance <= 0.0 && self.spin_friction <= 0.0 {
            state.rolling = None;
            let stop = pending.stopping_force(mass.tangential);
            return Some((self.finish(&pending, stop, dt, state), DVec3::ZERO));
        }
        // W: a unit force along t_b moves the point by t_b/m + (I⁻¹·(r × t_b)) × r and turns the
        // body by I⁻¹·(r × t_b); a unit torque about a_b moves the point by (I⁻¹·a_b) × r and
        // turns the body by I⁻¹·a_b
        let i = body.inertia;
        let axes = [t1, t2, n];
        let mut w = Matrix5::zeros();
        for (b, &tb) in [t1, t2].iter().enumerate() {
            let by_force = tb / body.mass + (r.cross(tb) / i).cross(r);
            let turn_by_force = r.cross(tb) / i;
            for (a, &ta) in [t1, t2].iter().enumerate() {
                w[(a, b)] = ta.dot(by_force);
            }
            for (a, &aa) in axes.iter().enumerate() {
                w[(a + 2, b)] = aa.dot(turn_by_force);
            }
        }
        for (b, &ab) in axes.iter().enumerate() {
            let by_torque = (ab / i).cross(r);
            for (a, &ta) in [t1, t2].iter().enumerate() {
                w[(a, b + 2)] = ta.dot(by_torque);
            }
            for (a, &aa) in axes.iter().enumerate() {
                w[(a + 2, b + 2)] = aa.dot(ab) / i;
            }
        }
        let w = (w + w.transpose()) * 0.5;
        // the body's turning in the ground frame: rolling (t₁, t₂) and spin (n)
        let turning = |v: DVec3| DVec3::new(t1.dot(v), t2.dot(v), n.dot(v));
        let omega = turning(body.angular_velocity);
        let (torque_prev, omega_demand) = match state.rolling {
            Some((torque, previous)) => (turning(torque), (2.0 * omega - turning(previous)) / dt),
            None => (DVec3::ZERO, omega / dt),
        };
        let u = Vector5::new(
            pending.demand.x,
            pending.demand.y,
            omega_demand.x,
            omega_demand.y,
            omega_demand.z,
        );
        let previous = Vector5::new(
            pending.previous_friction.x,
            pending.previous_friction.y,
            torque_prev.x,
            torque_prev.y,
            torque_prev.z,
        );
        let rolling_limit = self.rolling_resistance * pending.normal_force;
        let spin_limit = self.spin_friction * pending.normal_force;
        // the torques within their limits, those that saturate fixed at them
        let limit_torques = |g: &Vector5, fixed: &mut [Option<f64>; 5]| {
            if fixed[2].is_none() {
                let (t, saturated) = saturate(
                    DVec2::new(g[2], g[3]),
                    rolling_limit,
                    omega.truncate(),
                    rolling_limit * dt / i,
                );
                if saturated {
                    (fixed[2], fixed[3]) = (Some(t.x), Some(t.y));
                }
            }
            if fixed[4].is_none() {
                let (t, saturated) = saturate(
                    DVec2::new(g[4], 0.0),
                    spin_limit,
                    DVec2::new(omega.z, 0.0),
                    spin_limit * dt / i,
                );
                if saturated {
                    fixed[4] = Some(t.x);
                }
            }
        };
        let mut fixed = [None; 5];
        let all = solve_free(&w, &u, &previous, &fixed);
        let Some(all) = all else {
            // a mobility no solve can invert: friction alone, no torque
            state.rolling = None;
            let stop = pending.stopping_force(mass.tangential);
            return Some((self.finish(&pending, stop, dt, state), DVec3::ZERO));
        };
        limit_torques(&all, &mut fixed);
        let mut g = if fixed.iter().any(Option::is_some) {
            solve_free(&w, &u, &previous, &fixed).unwrap_or(all)
        } else {
            all
        };
        let friction_stop = DVec2::new(g[0], g[1]);
        let outcome = pending.friction(&self.friction, friction_stop);
        if !outcome.sticking && fixed[2..].iter().any(Option::is_none) {
            // friction slides with its law's force: the free torques stop what it leaves
            (fixed[0], fixed[1]) = (Some(outcome.force.x), Some(outcome.force.y));
            if let Some(again) = solve_free(&w, &u, &previous, &fixed) {
                g = again;
                let mut last = fixed;
                limit_torques(&g, &mut last);
                for k in 2..5 {
                    if let Some(v) = last[k] {
                        g[k] = v;
                    }
                }
            }
        }
        let torque = t1 * g[2] + t2 * g[3] + n * g[4];
        state.rolling = Some((torque, body.angular_velocity));
        Some((self.finish(&pending, friction_stop, dt, state), torque))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::GroundFrame;

    /// Without rolling resistance a rolling body's contact is exactly [`ContactModel::respond`]'s,
    /// step after step, with no torque.
    #[test]
    fn without_rolling_resistance_it_is_the_plain_contact() {
        let frame = GroundFrame::from_normal(DVec3::new(0.2, -0.1, 1.0).normalize());
        let (m, r) = (1.0, 0.05);
        let arm = r * frame.normal;
        let geometry = SphereGeometry {
            penetration: 1e-3,
            point: DVec3::ZERO,
            frame,
        };
        let model = ContactModel::default();
        let inverse_inertia = glam::DMat3::from_diagonal(DVec3::splat(1.0 / (0.4 * m * r * r)));
        let mass = EffectiveMass::rigid_body(m, inverse_inertia, -arm, &frame);
        let (mut plain, mut rolling) = (ContactState::default(), ContactState::default());
        for k in 0..50 {
            let t = k as f64;
            let v = DVec3::new(1e-3 * (0.3 * t).cos(), 0.2 * (0.1 * t).sin(), -0.01);
            let body = RollingBody {
                mass: m,
                inertia: 0.4 * m * r * r,
                arm,
                angular_velocity: DVec3::new(0.1, -3.0, 0.5),
            };
            let expected = model
                .respond(&geometry, v, &mass, 1e-3, &mut plain)
                .unwrap();
            let (got, torque) = model
                .respond_rolling(&geometry, v, &body, 1e-3, &mut rolling)
                .unwrap();
            assert_eq!(got, expected, "step {k}");
            assert_eq!(torque, DVec3::ZERO);
        }
    }
}
