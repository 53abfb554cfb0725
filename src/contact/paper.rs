//! The paper's contact, step for step (Burkus & Odry, §IV), as a variant to compare hexsim's
//! against — what its improvements change:
//! - **penetration** read vertically: the height of the interpolated table under the sphere's
//!   centre less the height of its lowest point, x = h(x_c, y_c) − (z_c − r) ("calculated using
//!   the world coordinates of the ball based on the vector containing the ground heights");
//!   hexsim's measures it along the normal to the closest surface point;
//! - **orientation** from the table's central differences, α = atan(Δz/2YE) about x and
//!   β = atan(Δz/2XE) about y (eq. 1–2), the sphere's velocity rotated into that frame (eq. 3–4);
//! - **normal force** F = k·x + c·ẋ as written (eq. 6), the damper explicit (hexsim's takes its
//!   exact decay over the step, stable on light feet), never pulling;
//! - **friction** the law as written on the in-plane velocity, with no limit at the force that
//!   would stop the contact within the step and no drift recovery; Karnopp's stick force cancels
//!   the load measured from the last step (the law's definition);
//! - **where it acts**: the force acts at the sphere's centre and its velocity is the centre's (the
//!   paper's SimMechanics body takes the force at its frame; for the ball it assumed no slip and
//!   neglected friction), so a ball does not spin; hexsim's acts at the contact point.

use super::{ContactForce, ContactModel, ContactState, PendingContact, SphereGeometry};
use crate::terrain::{GroundFrame, HeightGrid};
use glam::{DVec2, DVec3};

/// The paper's geometry for a sphere of `radius` centred at `center`: vertical penetration and the
/// central-difference frame with half-steps `xe`, `ye`; the force's point is the centre.
pub fn paper_geometry(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    xe: f64,
    ye: f64,
) -> SphereGeometry {
    let ground = terrain.height(center.x, center.y);
    let (alpha, beta) = terrain.paper_angles(center.x, center.y, xe, ye);
    SphereGeometry {
        penetration: ground - (center.z - radius),
        point: center,
        frame: GroundFrame::from_paper_angles(alpha, beta),
    }
}

impl ContactModel {
    /// The paper's response over a step (see the module docs) for a sphere in `geometry` (from
    /// [`paper_geometry`]) whose centre moves at `velocity`, of mass `mass` (Karnopp's stick force
    /// needs it). `None` (and `state` reset) when it does not touch.
    pub fn respond_paper(
        &self,
        geometry: &SphereGeometry,
        velocity: DVec3,
        mass: f64,
        dt: f64,
        state: &mut ContactState,
    ) -> Option<ContactForce> {
        if geometry.penetration <= 0.0 {
            *state = ContactState::default();
            return None;
        }
        let frame = &geometry.frame;
        let local = frame.to_local(velocity);
        let slip = DVec2::new(local.x, local.y);
        let normal_force = self.normal.explicit_force(geometry.penetration, -local.z);
        let in_plane = |v: DVec3| DVec2::new(frame.tangent_x.dot(v), frame.tangent_y.dot(v));
        // Karnopp's stick force cancels the load, measured from the last step; the continuous
        // laws are not limited at all
        let stop = match self.friction {
            super::FrictionLaw::Karnopp { .. } => match state.previous {
                Some((force, previous)) => {
                    in_plane(force) - mass * (2.0 * slip - in_plane(previous)) / dt
                }
                None => -mass * slip / dt,
            },
            _ => DVec2::splat(f64::INFINITY),
        };
        // the law decides given `stop`; `finish` keeps the state as for hexsim's contact
        let pending = PendingContact {
            point: geometry.point,
            frame: *frame,
            penetration: geometry.penetration,
            normal_velocity: local.z,
            slip,
            normal_force,
            previous_friction: DVec2::ZERO,
            demand: DVec2::ZERO,
            normal_change: 0.0,
        };
        Some(self.finish(&pending, stop, dt, state))
    }
}
