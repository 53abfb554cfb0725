//! Rolling resistance: a torque of at most ρ·Fn against a body's rolling — its angular velocity
//! about the ground plane's axes (spin about the normal is not rolling) — solved together with
//! the contact's friction.
//!
//! Why together: the torque turns the body about its centre, which moves the contact point; the
//! friction turns it back. Chosen one after the other, each reads the other's effect as a load and
//! they fight (measured: a ball that should rest on a 2.5° slope jittered at 2 mm/s). So the
//! contact's four in-plane unknowns g = (F₁, F₂, T₁, T₂) — the friction force and the rolling
//! torque along the ground frame's tangents — are solved as one stick problem, as Karnopp friction
//! is for one (see `friction`): with the generalised velocity s = (slip₁, slip₂, ω₁, ω₂) and the
//! body's mobility W (velocity change per impulse, s⁺ = s + h·W·g),
//!
//!   g_stop = g_prev − W⁻¹·u,   u = (2s − s_prev)/h (s/h on a contact's first step),
//!
//! which stops both the slip and the rolling within the step under last step's load (the
//! friction's part of u also carries its drift recovery). The friction law then decides whether
//! F_stop holds (else it slides, with its law's force); the rolling torque is T_stop while
//! |T_stop| ≤ ρ·Fn, else −ρ·Fn·ω_t/|ω_t|, which cannot reverse the rolling. A part that
//! saturates is fixed and the other solved again with it (at most twice). A ball so stops, and
//! stays at rest on a slope it can hold (tan θ ≤ ρ/r), without creeping.

use super::{ContactForce, ContactModel, ContactState, EffectiveMass, SphereGeometry};
use glam::{DMat2, DVec2, DVec3};
use rapier3d::na;

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

impl ContactModel {
    /// [`Self::respond`] for a rolling body (a ball): the contact's force, and the rolling
    /// resistance's torque about the body's centre of mass (zero when `rolling_resistance` is 0,
    /// and then the force is exactly [`Self::respond`]'s). `None` when it does not touch.
    pub fn respond_rolling(
        &self,
        geometry: &SphereGeometry,
        point_velocity: DVec3,
        body: &RollingBody,
        dt: f64,
        state: &mut ContactState,
    ) -> Option<(ContactForce, DVec3)> {
        let r = -body.arm;
        let (t1, t2) = (geometry.frame.tangent_x, geometry.frame.tangent_y);
        let inverse_inertia = glam::DMat3::from_diagonal(DVec3::splat(1.0 / body.inertia));
        let mass = EffectiveMass::rigid_body(body.mass, inverse_inertia, r, &geometry.frame);
        let pending = self.begin(geometry, point_velocity, mass.normal, dt, state)?;
        if self.rolling_resistance <= 0.0 {
            state.rolling = None;
            let stop = pending.stopping_force(mass.tangential);
            return Some((self.finish(&pending, stop, dt, state), DVec3::ZERO));
        }
        // W: a unit force along t_b moves the point by t_b/m + (I⁻¹·(r × t_b)) × r and turns the
        // body by I⁻¹·(r × t_b); a unit torque about t_b moves the point by (I⁻¹·t_b) × r
        let axes = [t1, t2];
        let i = body.inertia;
        let mut w = na::Matrix4::<f64>::zeros();
        for (b, &tb) in axes.iter().enumerate() {
            let by_force = tb / body.mass + (r.cross(tb) / i).cross(r);
            let turn_by_force = r.cross(tb) / i;
            let by_torque = (tb / i).cross(r);
            for (a, &ta) in axes.iter().enumerate() {
                w[(a, b)] = ta.dot(by_force);
                w[(a + 2, b)] = ta.dot(turn_by_force);
                w[(a, b + 2)] = ta.dot(by_torque);
                w[(a + 2, b + 2)] = ta.dot(tb) / i;
            }
        }
        let w = (w + w.transpose()) * 0.5;
        let in_plane = |v: DVec3| DVec2::new(t1.dot(v), t2.dot(v));
        let n = geometry.frame.normal;
        let rolling = body.angular_velocity - body.angular_velocity.dot(n) * n;
        let omega = in_plane(rolling);
        let (torque_prev, omega_demand) = match state.rolling {
            Some((torque, previous)) => (in_plane(torque), (2.0 * omega - in_plane(previous)) / dt),
            None => (DVec2::ZERO, omega / dt),
        };
        let u = na::Vector4::new(
            pending.demand.x,
            pending.demand.y,
            omega_demand.x,
            omega_demand.y,
        );
        let block = |r0: usize, c0: usize| {
            DMat2::from_cols(
                DVec2::new(w[(r0, c0)], w[(r0 + 1, c0)]),
                DVec2::new(w[(r0, c0 + 1)], w[(r0 + 1, c0 + 1)]),
            )
        };
        let limit = self.rolling_resistance * pending.normal_force;
        let saturate = |stop: DVec2| {
            if stop.length() <= limit {
                (stop, false)
            } else if omega.length() > 0.0 {
                (-limit * omega / omega.length(), true)
            } else {
                (stop * (limit / stop.length()), true)
            }
        };
        // both parts taken to hold; then fix what saturates and solve the other with it
        let (mut friction_stop, mut torque) = match w.try_inverse() {
            Some(inverse) => {
                let g = inverse * u;
                (
                    pending.previous_friction - DVec2::new(g[0], g[1]),
                    torque_prev - DVec2::new(g[2], g[3]),
                )
            }
            None => (pending.stopping_force(mass.tangential), torque_prev),
        };
        let (t, torque_saturated) = saturate(torque);
        torque = t;
        let demand_v = pending.demand;
        if torque_saturated {
            // the torque is known: friction stops the slip it and the load leave
            let push = block(0, 2) * (torque - torque_prev);
            friction_stop = pending.previous_friction - block(0, 0).inverse() * (demand_v + push);
        }
        let outcome = pending.friction(&self.friction, friction_stop);
        if !outcome.sticking && !torque_saturated {
            // friction slides with its law's force: the torque stops the rolling it leaves
            let push = block(2, 0) * (outcome.force - pending.previous_friction);
            let stop = torque_prev - block(2, 2).inverse() * (omega_demand + push);
            torque = saturate(stop).0;
        }
        let torque = t1 * torque.x + t2 * torque.y;
        state.rolling = Some((torque, rolling));
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
