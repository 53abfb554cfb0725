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

/// The most fixed-point iterations for the closest surface point, and the step (m) below which it
/// has converged. On a plane the first is exact; where the ground curves the error shrinks by
/// about d·κ per iteration (d: the centre's distance, κ: the curvature), so a 50 mm ball in a
/// hollow of the ball-scale natural terrain (curvature radius ~60 mm) needs dozens where a
/// 10 mm foot needs three. Stopping early leaves the contact point off the normal through the
/// centre: the normal force then has a lever about the normal and spins the ball up (measured:
/// 1.9 mm off at 3 iterations, 1.5 rad/s² of spin, the held ball creeping downhill).
const CLOSEST_POINT_ITERATIONS: usize = 64;
const CLOSEST_POINT_TOLERANCE: f64 = 1e-10;

/// Finds the closest surface point to the sphere's centre: start below the centre, take the tangent
/// plane there, drop the perpendicular from the centre onto it, and repeat at the foot of that
/// perpendicular. The distance to the last tangent plane is the centre's height above the ground
/// measured along the normal.
///
/// A steep feature beside the centre — a stair's riser — can touch the sphere's side while the
/// ground beneath the centre is clear: when the search from below finds no contact but the
/// terrain within the sphere's footprint rises above its lowest point
/// ([`HeightGrid::ceiling_near`]), it is repeated from the footprint's four edges and the
/// deepest answer kept.
pub fn sphere_geometry(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
) -> SphereGeometry {
    let below = closest_from(terrain, center, radius, orientation, (center.x, center.y));
    if below.penetration > 0.0
        || terrain.ceiling_near(center.x, center.y, radius) <= center.z - radius
    {
        return below;
    }
    [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
        .map(|(u, v)| (center.x + u * radius, center.y + v * radius))
        .into_iter()
        .map(|start| closest_from(terrain, center, radius, orientation, start))
        .fold(below, |deepest, g| {
            if g.penetration > deepest.penetration {
                g
            } else {
                deepest
            }
        })
}

/// The fixed-point search for the closest surface point, from the ground at `start`. The gap is
/// measured to the surface point the search ends on (signed by the side of its tangent plane the
/// centre lies on), not to that point's tangent plane: once converged the two agree, but on a
/// sharp feature where three iterations do not converge the plane of an upper stair tread would
/// extend over the lower one and report a foot above the lower tread as sunk into it (seen on
/// `terrains/steps.toml`: 4.6 mm out of nothing). A surface point's distance never exceeds the
/// true gap's, so an unconverged search can miss depth but never invent it.
fn closest_from(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
    (mut x, mut y): (f64, f64),
) -> SphereGeometry {
    let (height, mut frame) = terrain.height_and_frame(x, y, orientation);
    let mut surface = DVec3::new(x, y, height);
    // Where d·κ < −1 (the centre beyond the hollow's centre of curvature) the plain iteration
    // overshoots and oscillates: each time a step grows, the steps are shortened by half.
    let mut relax = 1.0;
    let mut last_step = f64::INFINITY;
    for _ in 1..CLOSEST_POINT_ITERATIONS {
        let distance = (center - surface).dot(frame.normal);
        let foot = center - distance * frame.normal;
        let step = ((foot.x - x).powi(2) + (foot.y - y).powi(2)).sqrt();
        if step < CLOSEST_POINT_TOLERANCE {
            break;
        }
        if step > last_step {
            relax *= 0.5;
        }
        last_step = step;
        (x, y) = (x + relax * (foot.x - x), y + relax * (foot.y - y));
        let height;
        (height, frame) = terrain.height_and_frame(x, y, orientation);
        surface = DVec3::new(x, y, height);
    }
    let offset = center - surface;
    let distance = offset.length().copysign(offset.dot(frame.normal));
    SphereGeometry {
        penetration: radius - distance,
        point: surface,
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

    /// The gap to stairs (uniform along y) by brute force: the least distance from the centre to
    /// the surface curve y = const, sampled every 2.5 µm over the sphere's reach.
    fn brute_force_penetration(terrain: &HeightGrid, center: DVec3, radius: f64) -> f64 {
        let n = 8000;
        let distance = (0..=n)
            .map(|k| center.x - radius + 2.0 * radius * k as f64 / n as f64)
            .map(|x| center.distance(DVec3::new(x, center.y, terrain.height(x, center.y))))
            .fold(f64::INFINITY, f64::min);
        radius - distance
    }

    fn stairs() -> HeightGrid {
        crate::terrain::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/terrains/steps.toml"
        )))
        .unwrap()
    }

    #[test]
    fn a_foot_over_the_lower_tread_is_not_sunk_into_the_upper_one() {
        // a foot of hex18 on the stairs scenario, beside the riser at x = 1.5: the search does not
        // converge there, and the upper tread's tangent plane used to put it 4.6 mm deep
        let terrain = stairs();
        let center = DVec3::new(
            1.4901076801667015,
            -0.17811939159147336,
            0.10761671697964005,
        );
        let g = sphere_geometry(&terrain, center, 0.01, Orientation::Exact);
        let truth = brute_force_penetration(&terrain, center, 0.01);
        assert!(truth < 0.0, "the sphere is clear of the stairs: {truth}");
        assert!(g.penetration <= truth + 1e-9, "{} > {truth}", g.penetration);
    }

    #[test]
    fn a_sphere_against_a_riser_touches_its_side() {
        // the ground beneath the centre is the lower tread, well clear; the riser is 5 mm into the
        // sphere's side
        let terrain = stairs();
        let low = terrain.height(1.45, 0.0);
        let center = DVec3::new(1.4865, 0.0, low + 0.0105);
        let truth = brute_force_penetration(&terrain, center, 0.01);
        assert!(truth > 1e-3, "{truth}");
        let g = sphere_geometry(&terrain, center, 0.01, Orientation::Exact);
        assert!(
            (g.penetration - truth).abs() < 0.05e-3,
            "{} mm against {} mm",
            g.penetration * 1e3,
            truth * 1e3
        );
    }

    /// A 50 mm ball in a hollow whose curvature radius at the bottom is 61 mm (d·κ ≈ 0.8): the
    /// plain iteration gains a factor 0.8 a step, so three leave the contact point millimetres off
    /// the normal through the centre (the lever that spun a held ball up); iterated to
    /// convergence the centre lies on the normal.
    #[test]
    fn converges_in_a_hollow_nearly_as_tight_as_the_ball() {
        let (depth, sigma) = (0.02, 0.035);
        let hollow = crate::terrain::bell(0.5, 501, depth, sigma).unwrap();
        assert!((sigma * sigma / depth - 0.06125).abs() < 1e-12);
        let center = DVec3::new(0.012, -0.007, hollow.height(0.012, -0.007) + 0.049);
        let g = sphere_geometry(&hollow, center, 0.05, Orientation::Exact);
        let offset = center - g.point;
        assert!((g.point.z - hollow.height(g.point.x, g.point.y)).abs() < 1e-12);
        assert!(
            offset.cross(g.frame.normal).length() < 1e-9,
            "{}",
            offset.cross(g.frame.normal).length()
        );
        // what three iterations leave: a point well off the normal
        let (mut x, mut y) = (center.x, center.y);
        for _ in 1..3 {
            let (h, frame) = hollow.height_and_frame(x, y, Orientation::Exact);
            let surface = DVec3::new(x, y, h);
            let foot = center - (center - surface).dot(frame.normal) * frame.normal;
            (x, y) = (foot.x, foot.y);
        }
        let early = DVec3::new(x, y, hollow.height(x, y));
        assert!(
            (early - g.point).length() > 1e-4,
            "{}",
            (early - g.point).length()
        );
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
