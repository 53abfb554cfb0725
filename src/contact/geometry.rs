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
    if terrain.has_cliffs() {
        return among_walls(terrain, center, radius, orientation, below);
    }
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

/// [`sphere_geometry`] on a grid with cliffs (`terrain/cliff.rs`): the surface is the treads and
/// the walls between them, so the closest point is the nearest of the tread found from below the
/// centre (and, if that is clear while the footprint holds higher ground, from the footprint's
/// edges) and the closest point of each wall within reach. The nearest is kept, whichever side
/// the centre is on; the side itself is read from the height below the centre (the centre is in
/// the ground where it is lower than the surface above its own (x, y), walls included) — not from
/// a tangent plane, which on an upper tread reaching over the lower one would call a centre
/// beside the riser buried. On a wall's face the normal is horizontal; at its top edge it points
/// from the edge to the centre, as for any sphere touching a convex edge.
fn among_walls(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
    below: SphereGeometry,
) -> SphereGeometry {
    if terrain.ceiling_near(center.x, center.y, radius) <= center.z - radius {
        return below;
    }
    let buried = center.z < terrain.height(center.x, center.y);
    let depth = |distance: f64| radius + if buried { distance } else { -distance };
    let mut nearest = center.distance(below.point);
    let mut best = SphereGeometry {
        penetration: depth(nearest),
        ..below
    };
    if best.penetration <= 0.0 {
        for (u, v) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
            let start = (center.x + u * radius, center.y + v * radius);
            let g = closest_from(terrain, center, radius, orientation, start);
            let distance = center.distance(g.point);
            if distance < nearest {
                nearest = distance;
                best = SphereGeometry {
                    penetration: depth(distance),
                    ..g
                };
            }
        }
    }
    terrain.walls_near(center.x, center.y, radius, |wall| {
        let (point, face) = wall.closest(center);
        let offset = center - point;
        let distance = offset.length();
        if distance < nearest {
            nearest = distance;
            let normal = if distance < 1e-12 {
                face
            } else if buried {
                -offset / distance
            } else {
                offset / distance
            };
            best = SphereGeometry {
                penetration: depth(distance),
                point,
                frame: GroundFrame::from_normal(normal),
            };
        }
    });
    best
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

    /// The gap to ground uniform along y by brute force, walls included: the solid is the columns
    /// z ≤ h(x) and the nearest point of the column at x is at height min(z, h(x)) (of the air
    /// above it, for a buried centre, max(z, h(x))); the least distance over x sampled every
    /// 1 µm across a 5 cm ball's reach (0.25 µm for a 1 cm foot), signed by the side the centre
    /// is on.
    fn brute_force_penetration(terrain: &HeightGrid, center: DVec3, radius: f64) -> f64 {
        let n = 100_000;
        let buried = center.z < terrain.height(center.x, center.y);
        let distance = (0..=n)
            .map(|k| center.x - radius + 2.0 * radius * k as f64 / n as f64)
            .map(|x| {
                let gap = terrain.height(x, center.y) - center.z;
                let vertical = if buried {
                    gap.max(0.0)
                } else {
                    (-gap).max(0.0)
                };
                (x - center.x).hypot(vertical)
            })
            .fold(f64::INFINITY, f64::min);
        if buried {
            radius + distance
        } else {
            radius - distance
        }
    }

    fn stairs() -> HeightGrid {
        crate::terrain::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/terrains/steps.toml"
        )))
        .unwrap()
    }

    #[test]
    fn a_foot_beside_a_riser_is_not_sunk_into_the_upper_tread() {
        // a foot of hex18 on the stairs scenario, beside the riser midway between x = 1.49 and
        // 1.50, 7.6 mm above the upper tread: it touches the riser's top edge, 0.95 mm deep. The
        // search from below does not converge on the edge, and the upper tread's tangent plane
        // once put it 4.6 mm deep
        let terrain = stairs();
        let center = DVec3::new(
            1.4901076801667015,
            -0.17811939159147336,
            0.10761671697964005,
        );
        let g = sphere_geometry(&terrain, center, 0.01, Orientation::Exact);
        let truth = brute_force_penetration(&terrain, center, 0.01);
        assert!((truth - 0.95e-3).abs() < 0.01e-3, "{truth}");
        assert!(
            (g.penetration - truth).abs() < 1e-6,
            "{} against {truth}",
            g.penetration
        );
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

    /// One 0.10 m riser midway between the samples at x = 0.30 and 0.31 (1 cm cells): V20's.
    fn riser() -> HeightGrid {
        crate::terrain::steps([2.0, 1.0], [0.0, 0.0], 0.305, 10.0, 0.1, 0.01).unwrap()
    }
    const WALL: f64 = 0.305;

    /// Checks `sphere_geometry` against brute force at `center` (r = 0.05): depth within 2 µm
    /// (twice the brute force's sampling),
    /// the point on the surface the normal leaves from, and the centre on that normal.
    fn against_brute_force(center: DVec3) -> SphereGeometry {
        let terrain = riser();
        let g = sphere_geometry(&terrain, center, 0.05, Orientation::Exact);
        let truth = brute_force_penetration(&terrain, center, 0.05);
        assert!(
            (g.penetration - truth).abs() < 2e-6,
            "{} mm against {} mm",
            g.penetration * 1e3,
            truth * 1e3
        );
        let offset = center - g.point;
        assert!(
            offset.cross(g.frame.normal).length() < 1e-9,
            "off the normal"
        );
        assert!(
            ((g.frame.normal.dot(offset)) - (0.05 - g.penetration)).abs() < 1e-9,
            "the gap is not along the normal"
        );
        g
    }

    #[test]
    fn a_sphere_pushed_into_a_riser_touches_its_face_horizontally() {
        // 3 mm into the face, level with nothing below (the lower tread just touched)
        let g = against_brute_force(DVec3::new(WALL - 0.047, 0.1, 0.0499));
        assert!((g.penetration - 0.003).abs() < 1e-9, "{}", g.penetration);
        assert!(
            g.frame.normal.abs_diff_eq(-DVec3::X, 1e-12),
            "{}",
            g.frame.normal
        );
        assert!((g.point.x - WALL).abs() < 1e-12 && (g.point.z - 0.0499).abs() < 1e-12);
        // the frame is a frame
        let f = g.frame;
        assert!((f.tangent_x.cross(f.tangent_y) - f.normal).length() < 1e-12);
    }

    #[test]
    fn a_sphere_on_the_risers_top_edge_is_pushed_away_from_the_edge() {
        let center = DVec3::new(WALL - 0.02, -0.2, 0.14);
        let g = against_brute_force(center);
        let edge = DVec3::new(WALL, -0.2, 0.1);
        let expected = 0.05 - center.distance(edge);
        assert!(
            (g.penetration - expected).abs() < 1e-12,
            "{}",
            g.penetration
        );
        assert!(g.point.abs_diff_eq(edge, 1e-12));
        assert!(
            g.frame
                .normal
                .abs_diff_eq((center - edge).normalize(), 1e-12)
        );
    }

    #[test]
    fn a_sphere_over_the_lower_tread_beside_the_riser_gets_no_invented_depth() {
        // 5 mm into the lower tread, 1 cm clear of the riser: 5 mm, straight up
        let g = against_brute_force(DVec3::new(WALL - 0.06, 0.0, 0.045));
        assert!((g.penetration - 0.005).abs() < 1e-12, "{}", g.penetration);
        assert!(g.frame.normal.abs_diff_eq(DVec3::Z, 1e-12));
        // clear of both, 2 mm from each: a gap of 2 mm, not a depth
        let g = against_brute_force(DVec3::new(WALL - 0.052, 0.0, 0.052));
        assert!((g.penetration + 0.002).abs() < 1e-9, "{}", g.penetration);
        // in the corner, 1 mm into the tread and 2 mm into the face: the face is nearer
        let g = against_brute_force(DVec3::new(WALL - 0.048, 0.0, 0.049));
        assert!((g.penetration - 0.002).abs() < 1e-12, "{}", g.penetration);
    }

    #[test]
    fn the_upper_tread_and_a_centre_buried_past_the_face() {
        // resting on the upper tread 2 cm past the edge
        let g = against_brute_force(DVec3::new(WALL + 0.02, 0.0, 0.149));
        assert!((g.penetration - 0.001).abs() < 1e-12);
        assert!(g.frame.normal.abs_diff_eq(DVec3::Z, 1e-12));
        // the centre 4 mm inside the step, 9 cm below its top: the way out is back through the
        // face, 4 mm + r deep
        let g = against_brute_force(DVec3::new(WALL + 0.004, 0.0, 0.01));
        assert!((g.penetration - 0.054).abs() < 1e-9, "{}", g.penetration);
        assert!(g.frame.normal.abs_diff_eq(-DVec3::X, 1e-12));
    }

    /// Along the riser the surface is the two treads, no ramp and no Catmull–Rom ringing; beside
    /// it the interpolation's own.
    #[test]
    fn the_treads_either_side_of_a_riser_are_level_to_the_wall() {
        let terrain = riser();
        for x in [0.25, 0.29, 0.3, WALL - 1e-9] {
            let s = terrain.surface(x, 0.123);
            assert_eq!((s.height, s.slope_x, s.slope_y), (0.0, 0.0, 0.0), "at {x}");
        }
        // (Catmull–Rom's weights, two cells on, sum to 1 within rounding)
        for x in [WALL, 0.31, 0.32, 0.4] {
            let s = terrain.surface(x, 0.123);
            assert!((s.height - 0.1).abs() < 1e-15, "at {x}: {}", s.height);
            assert!(s.slope_x.abs() < 1e-12 && s.slope_y.abs() < 1e-12, "at {x}");
        }
    }

    /// A box's four sides face out, each horizontally, and its vertical corner edge pushes along
    /// the diagonal: walls along y as well as x, and where two meet. (Pyramid stairs, two 0.1 m
    /// steps: risers 0.205 m and 0.405 m from the centre, midway between samples.)
    #[test]
    fn a_box_pushes_out_of_each_side_and_its_corner() {
        let pyramid =
            crate::terrain::pyramid_stairs([2.0, 2.0], [0.0, 0.0], 2, 0.2, 0.1, 0.41, 0.01)
                .unwrap();
        for out in [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y] {
            let center = (0.405 + 0.048) * out + DVec3::new(0.0, 0.0, 0.05);
            let g = sphere_geometry(&pyramid, center, 0.05, Orientation::Exact);
            assert!(
                (g.penetration - 0.002).abs() < 1e-12,
                "{out}: {}",
                g.penetration
            );
            assert!(
                g.frame.normal.abs_diff_eq(out, 1e-12),
                "{out}: {}",
                g.frame.normal
            );
        }
        let corner = DVec3::new(0.405, -0.405, 0.05);
        let diagonal = DVec3::new(1.0, -1.0, 0.0).normalize();
        let g = sphere_geometry(
            &pyramid,
            corner + 0.047 * diagonal,
            0.05,
            Orientation::Exact,
        );
        assert!((g.penetration - 0.003).abs() < 1e-12, "{}", g.penetration);
        assert!(g.point.abs_diff_eq(corner, 1e-12), "{}", g.point);
        assert!(g.frame.normal.abs_diff_eq(diagonal, 1e-12));
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
