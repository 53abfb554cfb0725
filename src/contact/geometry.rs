//! Where a sphere touches the terrain: the closest surface point, measured along the surface
//! normal (a sphere on a slope touches off-centre, not below its centre).

use crate::terrain::{GroundFrame, HeightGrid, Orientation};
use glam::DVec3;

/// A sphere's relation to the ground: signed gap and the ground frame at the contact point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereGeometry {
    /// Depth of the sphere below the surface along the normal, `r − d` (negative: a gap of −x).
    pub penetration: f64,
    /// The surface point closest to the sphere's centre (where the force acts).
    pub point: DVec3,
    /// Ground frame at `point`; its normal points out of the ground, towards the sphere.
    pub frame: GroundFrame,
}

/// Fixed-point iterations for the closest surface point. On a plane the first is exact; on the
/// paper's terrains (curvature radius ≫ foot radius) three bring the point to well under a micron.
const CLOSEST_POINT_ITERATIONS: usize = 3;

/// Finds the closest surface point to the sphere's centre: start below the centre, take the tangent
/// plane there, drop the perpendicular from the centre onto it, and repeat at the foot of that
/// perpendicular. The distance to the last tangent plane is the centre's height above the ground
/// measured along the normal.
pub fn sphere_geometry(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
) -> SphereGeometry {
    let (mut x, mut y) = (center.x, center.y);
    let (height, mut frame) = terrain.height_and_frame(x, y, orientation);
    let mut surface = DVec3::new(x, y, height);
    let mut distance = (center - surface).dot(frame.normal);
    for _ in 1..CLOSEST_POINT_ITERATIONS {
        let foot = center - distance * frame.normal;
        if (foot.x - x).abs() < 1e-12 && (foot.y - y).abs() < 1e-12 {
            break;
        }
        (x, y) = (foot.x, foot.y);
        let height;
        (height, frame) = terrain.height_and_frame(x, y, orientation);
        surface = DVec3::new(x, y, height);
        distance = (center - surface).dot(frame.normal);
    }
    SphereGeometry {
        penetration: radius - distance,
        point: center - distance * frame.normal,
        frame,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::slope;

    #[test]
    fn sphere_on_a_slope_touches_off_centre_along_the_normal() {
        let angle = 20f64.to_radians();
        let plane = slope([4.0, 4.0], [0.0, 0.0], angle, 0.0).unwrap();
        let n = DVec3::new(-angle.sin(), 0.0, angle.cos());
        // centre 0.05 m from the plane along its normal, above x = 0.3 on the surface
        let foot = DVec3::new(0.3, 0.0, 0.3 * angle.tan());
        let center = foot + 0.049 * n;
        let g = sphere_geometry(&plane, center, 0.05, Orientation::Exact);
        assert!((g.penetration - 0.001).abs() < 1e-12, "{}", g.penetration);
        assert!(g.point.abs_diff_eq(foot, 1e-12));
        assert!(g.frame.normal.abs_diff_eq(n, 1e-12));
    }

    #[test]
    fn converges_on_a_curved_surface() {
        let bell = crate::terrain::bell(3.0, 241, 1.0, 1.0).unwrap();
        let center = DVec3::new(0.7, 0.3, bell.height(0.7, 0.3) + 0.04);
        let g = sphere_geometry(&bell, center, 0.05, Orientation::Exact);
        // the contact point lies on the surface and the centre lies on its normal
        assert!((g.point.z - bell.height(g.point.x, g.point.y)).abs() < 1e-9);
        let offset = center - g.point;
        assert!(offset.cross(g.frame.normal).length() < 1e-6);
        assert!(g.penetration > 0.0 && g.penetration < 0.02);
    }
}
