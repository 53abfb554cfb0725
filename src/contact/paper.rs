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
//!   the load measured from the last step — hexsim's reading of Karnopp's definition, since the
//!   paper gives no formula for it;
//! - **where it acts**: the force acts at the sphere's centre and its velocity is the centre's (the
//!   paper's SimMechanics body takes the force at its frame; for the ball it assumed no slip and
//!   neglected friction — friction on the ball here is hexsim's addition, so the friction laws can
//!   be compared on it), so a ball does not spin; hexsim's acts at the contact point.

use super::{ContactForce, ContactModel, ContactState, PendingContact, SphereGeometry};
use crate::terrain::{GroundFrame, HeightGrid};
use glam::{DVec2, DVec3};

/// The paper's geometry for a sphere of `radius` centred at `center`: vertical penetration and the
/// central-difference frame with half-steps `xe`, `ye` (eq. 1–2); the force's point is the
/// centre. Heights are read from the table as the paper does, bilinearly between its samples
/// ([`HeightGrid::table_height`]), not from hexsim's bicubic surface.
pub fn paper_geometry(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    xe: f64,
    ye: f64,
) -> SphereGeometry {
    let h = |x: f64, y: f64| terrain.table_height(x, y);
    let (x, y) = (center.x, center.y);
    let ground = h(x, y);
    let alpha = ((h(x, y + ye) - h(x, y - ye)) / (2.0 * ye)).atan();
    let beta = ((h(x + xe, y) - h(x - xe, y)) / (2.0 * xe)).atan();
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
            damper: 0.0,
        };
        Some(self.finish(&pending, stop, dt, state))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper reads its table bilinearly: on a single bump, between the samples, its
    /// penetration and angles are the bilinear table's, not the bicubic surface's.
    #[test]
    fn the_paper_variant_reads_the_table_bilinearly() {
        let bump = HeightGrid::from_fn(5, 5, [-0.2, 0.2], [-0.2, 0.2], |x, y| {
            if x.abs() < 1e-9 && y.abs() < 1e-9 {
                0.01
            } else {
                0.0
            }
        })
        .unwrap();
        let (x, y) = (0.03, 0.02);
        // bilinear: the peak's weight at (0.03, 0.02) in the cell [0, 0.1]²
        let table = 0.01 * (1.0 - 0.3) * (1.0 - 0.2);
        assert!((bump.table_height(x, y) - table).abs() < 1e-15);
        assert!((bump.height(x, y) - table).abs() > 1e-4, "bicubic differs");
        let center = DVec3::new(x, y, 0.05 + 0.001);
        let g = paper_geometry(&bump, center, 0.05, 0.01, 0.01);
        assert!((g.penetration - (table - 0.001)).abs() < 1e-15);
        // the bilinear cell's slopes, h = 0.01·(1 − x/0.1)·(1 − y/0.1): central differences
        // within the cell are exact
        let alpha = (-0.01 * (1.0 - 0.3) / 0.1f64).atan();
        let beta = (-0.01 * (1.0 - 0.2) / 0.1f64).atan();
        let frame = GroundFrame::from_paper_angles(alpha, beta);
        assert!((g.frame.normal - frame.normal).length() < 1e-12);
    }
}
