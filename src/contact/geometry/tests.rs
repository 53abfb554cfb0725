//! Tests of `geometry`.

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
    // 3 mm into the face, the lower tread 0.1 mm clear
    let g = against_brute_force(DVec3::new(WALL - 0.047, 0.1, 0.0501));
    assert!((g.penetration - 0.003).abs() < 1e-9, "{}", g.penetration);
    assert!(
        g.frame.normal.abs_diff_eq(-DVec3::X, 1e-12),
        "{}",
        g.frame.normal
    );
    assert!((g.point.x - WALL).abs() < 1e-12 && (g.point.z - 0.0501).abs() < 1e-12);
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
}

/// The least translation that takes a sphere (r = 0.05) at `center` out of the riser's ground,
/// by brute force: the ground's profile sampled every 1 µm (it is uniform along y), and in
/// each direction of the x–z plane the shortest move, by bisection, after which the sphere
/// is clear of every sample's column; directions 1° apart, then 0.002° apart within 1° of the
/// best (the shortest move has a kink at the way out of a corner). For a sphere against faces
/// at right angles this is the depth vector's length √(Σ xᵢ²), what the summed springs report.
fn brute_force_way_out(center: DVec3) -> (f64, DVec3) {
    let (terrain, r) = (riser(), 0.05);
    let profile: Vec<(f64, f64)> = (0..=140_000)
        .map(|k| center.x - 0.07 + k as f64 * 1e-6)
        .map(|x| (x, terrain.height(x, center.y)))
        .collect();
    let clear = |p: DVec3| {
        profile
            .iter()
            .filter(|(x, _)| (x - p.x).abs() < r)
            .all(|&(x, h)| (x - p.x).hypot((p.z - h).max(0.0)) >= r)
    };
    let shortest = |degrees: f64| {
        let angle = degrees.to_radians();
        let direction = DVec3::new(angle.cos(), 0.0, angle.sin());
        let (mut lo, mut hi) = (0.0, 0.02);
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if clear(center + mid * direction) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        (hi, direction, degrees)
    };
    let least = |a: (f64, DVec3, f64), b: (f64, DVec3, f64)| if b.0 < a.0 { b } else { a };
    let start = (f64::INFINITY, DVec3::ZERO, 0.0);
    let coarse = (0..360).map(|k| shortest(k as f64)).fold(start, least);
    let fine = (0..=1000)
        .map(|k| shortest(coarse.2 - 1.0 + k as f64 * 0.002))
        .fold(coarse, least);
    (fine.0, fine.1)
}

#[test]
fn a_sphere_in_the_corner_of_a_tread_and_a_riser_presses_into_both() {
    // 1 mm into the tread and 2 mm into the face: both springs, along (−2, 0, 1)/√5; the
    // nearest alone said 2 mm along −x
    let center = DVec3::new(WALL - 0.048, 0.0, 0.049);
    let g = sphere_geometry(&riser(), center, 0.05, Orientation::Exact);
    let expected = DVec3::new(-0.002, 0.0, 0.001);
    assert!(
        (g.penetration - expected.length()).abs() < 1e-12,
        "{}",
        g.penetration
    );
    assert!(g.frame.normal.abs_diff_eq(expected.normalize(), 1e-12));
    // the centre on the normal through the point, the gap along it
    assert!(((center - g.point).dot(g.frame.normal) - (0.05 - g.penetration)).abs() < 1e-12);
    assert!((center - g.point).cross(g.frame.normal).length() < 1e-12);
    // against the brute force's way out, here and where the two are equally deep (where the
    // nearest alone turned the force by 90°)
    for center in [center, DVec3::new(WALL - 0.047, 0.3, 0.047)] {
        let g = sphere_geometry(&riser(), center, 0.05, Orientation::Exact);
        let (depth, direction) = brute_force_way_out(center);
        assert!(
            (g.penetration - depth).abs() < 2e-6,
            "{} mm against {} mm",
            g.penetration * 1e3,
            depth * 1e3
        );
        assert!(
            g.frame.normal.angle_between(direction) < 0.25f64.to_radians(),
            "{} against {direction}",
            g.frame.normal
        );
    }
}

/// Sliding into the corner, the force turns continuously from the tread's normal to the
/// face's and its size never jumps: 10 µm steps change the normal by at most 0.3° (10 µm of
/// the face's depth against 2 mm of the tread's; the nearest alone turned it 90°) and the
/// depth by at most the step.
#[test]
fn the_force_turns_continuously_into_a_corner() {
    let terrain = riser();
    let at = |x: f64| {
        sphere_geometry(
            &terrain,
            DVec3::new(x, 0.0, 0.048),
            0.05,
            Orientation::Exact,
        )
    };
    let mut last = at(WALL - 0.055);
    assert!(last.frame.normal.abs_diff_eq(DVec3::Z, 1e-12));
    for k in 1..=1000 {
        let g = at(WALL - 0.055 + k as f64 * 1e-5);
        let turn = g.frame.normal.angle_between(last.frame.normal);
        assert!(turn < 0.3f64.to_radians(), "at step {k}: {turn} rad");
        assert!(
            (g.penetration - last.penetration).abs() <= 1.0001e-5,
            "at step {k}"
        );
        last = g;
    }
    // 5 mm into the face and 2 mm into the tread at the end
    assert!((last.penetration - 0.029e-3f64.sqrt()).abs() < 1e-12);
}

/// In a stepped pit's bottom corner a sphere presses into the floor and two walls at right
/// angles: three springs.
#[test]
fn a_sphere_in_a_pits_corner_presses_into_the_floor_and_both_walls() {
    // the bottom, 0.2 m down, within 0.205 m of the centre (walls midway between samples)
    let pit =
        crate::terrain::pyramid_stairs([2.0, 2.0], [0.0, 0.0], 2, 0.2, -0.1, 0.41, 0.01).unwrap();
    assert!((pit.height(0.1, 0.1) + 0.2).abs() < 1e-12);
    let center = DVec3::new(0.205 - 0.048, 0.205 - 0.047, -0.2 + 0.049);
    let g = sphere_geometry(&pit, center, 0.05, Orientation::Exact);
    let expected = DVec3::new(-0.002, -0.003, 0.001);
    assert!(
        (g.penetration - expected.length()).abs() < 1e-12,
        "{}",
        g.penetration
    );
    assert!(
        g.frame.normal.abs_diff_eq(expected.normalize(), 1e-12),
        "{}",
        g.frame.normal
    );
}

/// A foot in a trench as wide as itself touches both walls: the springs push it to the middle,
/// and where they balance they cancel instead of the nearer wall pushing alone.
#[test]
fn a_foot_in_a_trench_its_own_width_is_pushed_to_the_middle() {
    // walls at x = 0.505 and 0.525, 0.1 m deep
    let trench = crate::terrain::gaps([1.0, 0.5], [0.5, 0.0], 0.505, 0.02, 0.4, 0.1, 0.01).unwrap();
    assert!((trench.height(0.515, 0.0) + 0.1).abs() < 1e-12);
    // 1 mm off the middle, 5 cm above the floor: 1 mm into one wall, 1 mm clear of the other
    let g = sphere_geometry(
        &trench,
        DVec3::new(0.514, 0.0, -0.05),
        0.01,
        Orientation::Exact,
    );
    assert!((g.penetration - 0.001).abs() < 1e-12, "{}", g.penetration);
    assert!(g.frame.normal.abs_diff_eq(DVec3::X, 1e-12));
    // an 11.5 mm sphere 1 mm off the middle: 2.5 and 0.5 mm into the walls, net 2 mm
    let g = sphere_geometry(
        &trench,
        DVec3::new(0.514, 0.0, -0.05),
        0.0115,
        Orientation::Exact,
    );
    assert!((g.penetration - 0.002).abs() < 1e-12, "{}", g.penetration);
    assert!(g.frame.normal.abs_diff_eq(DVec3::X, 1e-12));
    // in the middle the springs cancel
    let g = sphere_geometry(
        &trench,
        DVec3::new(0.515, 0.0, -0.05),
        0.0115,
        Orientation::Exact,
    );
    assert!(g.penetration.abs() < 1e-12, "{}", g.penetration);
}

/// The same trench face by face: each wall the foot presses into is a face of its own with
/// its own depth and horizontal normal, and in the middle both push (the sum cancels).
#[test]
fn a_foot_in_a_trench_its_own_width_presses_into_each_wall() {
    let trench = crate::terrain::gaps([1.0, 0.5], [0.5, 0.0], 0.505, 0.02, 0.4, 0.1, 0.01).unwrap();
    let center = DVec3::new(0.514, 0.0, -0.05);
    let faces = sphere_faces(&trench, center, 0.0115, Orientation::Exact);
    let mut faces: Vec<_> = faces
        .as_slice()
        .iter()
        .map(|g| (g.penetration, g.frame.normal))
        .collect();
    faces.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(faces.len(), 2, "{faces:?}");
    assert!((faces[0].0 - 0.0005).abs() < 1e-12 && faces[0].1.abs_diff_eq(-DVec3::X, 1e-12));
    assert!((faces[1].0 - 0.0025).abs() < 1e-12 && faces[1].1.abs_diff_eq(DVec3::X, 1e-12));
    // on the floor too: three faces, the floor's normal up
    let center = DVec3::new(0.515, 0.0, -0.1 + 0.011);
    let faces = sphere_faces(&trench, center, 0.0115, Orientation::Exact);
    assert_eq!(faces.as_slice().len(), 3);
    assert!(
        faces
            .as_slice()
            .iter()
            .any(|g| g.frame.normal.abs_diff_eq(DVec3::Z, 1e-12)
                && (g.penetration - 0.0005).abs() < 1e-12)
    );
    // a sphere on open ground has one face, the one `sphere_geometry` gives
    let flat = crate::terrain::flat([1.0, 1.0], [0.0, 0.0], 0.0).unwrap();
    let center = DVec3::new(0.1, 0.1, 0.009);
    let faces = sphere_faces(&flat, center, 0.01, Orientation::Exact);
    assert_eq!(faces.as_slice().len(), 1);
    assert_eq!(
        faces.as_slice()[0],
        sphere_geometry(&flat, center, 0.01, Orientation::Exact)
    );
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

/// A riser on the grid's last edge is a wall like any other: the apron beyond the border is
/// level (the clamped coordinates), so the tread before it stays level to the wall. Read as a
/// Catmull–Rom ramp, the 6 cm riser ending the ladder's stairs down at x = 3 rose 4.4 mm above
/// its tread 1.4 cm before the edge, and a WORMS foot standing there was put 5.24 mm deep.
/// (Catmull–Rom's weights, where the cells are smooth, sum to 1 within rounding.)
#[test]
fn a_riser_on_the_grids_border_is_a_wall_too() {
    let terrain = crate::terrain::steps([6.0, 4.0], [0.0, 0.0], 0.3, 0.3, -0.06, 0.01).unwrap();
    assert_eq!(terrain.x_range()[1], 3.0);
    assert_eq!(terrain.sample(200, 599), -0.54);
    assert_eq!(terrain.sample(200, 600), -0.6);
    let mut walls = Vec::new();
    terrain.walls_near(2.99, 0.5, 0.004, |w| walls.push(w));
    assert!(!walls.is_empty() && walls.iter().all(|w| w.axis == 0 && w.at == 2.995));
    for x in [2.97, 2.98, 2.986, 2.99, 2.9949] {
        let s = terrain.surface(x, 0.5124);
        assert!((s.height - -0.54).abs() < 1e-15, "at {x}: {}", s.height);
        assert!(s.slope_x.abs() < 1e-12 && s.slope_y.abs() < 1e-12, "at {x}");
    }
    for x in [2.9951, 2.998, 3.0, 3.2] {
        let s = terrain.surface(x, 0.5124);
        assert!((s.height - -0.6).abs() < 1e-15, "at {x}: {}", s.height);
        assert!(s.slope_x.abs() < 1e-12 && s.slope_y.abs() < 1e-12, "at {x}");
    }
    // a ball 1 mm into the tread, 1.5 cm before the wall (its top edge out of reach): 1 mm
    let r = 0.05;
    let center = DVec3::new(2.98, 0.5124, -0.54 + r - 0.001);
    let g = sphere_geometry(&terrain, center, r, Orientation::Exact);
    assert!((g.penetration - 0.001).abs() < 1e-9, "{}", g.penetration);
    assert!(
        g.frame.normal.abs_diff_eq(DVec3::Z, 1e-9),
        "{}",
        g.frame.normal
    );
}

/// A box's four sides face out, each horizontally, and its vertical corner edge pushes along
/// the diagonal: walls along y as well as x, and where two meet. (Pyramid stairs, two 0.1 m
/// steps: risers 0.205 m and 0.405 m from the centre, midway between samples.)
#[test]
fn a_box_pushes_out_of_each_side_and_its_corner() {
    let pyramid =
        crate::terrain::pyramid_stairs([2.0, 2.0], [0.0, 0.0], 2, 0.2, 0.1, 0.41, 0.01).unwrap();
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

/// A sphere in a V-shaped groove between two 45° faces (5 mm cells, the faces exact
/// beyond a cell of the crease), off-centre: it presses 7.37 mm into one face and 1.72 mm
/// into the other, and gets both, each with its own depth and normal — on a smooth grid and
/// on one with a riser elsewhere (the walls' search). The search from below the centre
/// finds only the nearer face; the sphere pressed into both then got that face's spring
/// alone, on the other face the next step, and swung between them ever faster (see
/// [`crease_starts`]).
#[test]
fn a_sphere_in_a_groove_presses_into_both_faces() {
    let v = |x: f64, _: f64| x.abs();
    let smooth = HeightGrid::from_fn(41, 81, [-0.2, 0.2], [-0.1, 0.1], v).unwrap();
    let riser = |x: f64, y: f64| v(x, y) + if x > 0.15 { 0.2 } else { 0.0 };
    let walled = HeightGrid::from_fn(41, 81, [-0.2, 0.2], [-0.1, 0.1], riser).unwrap();
    assert!(!smooth.has_cliffs() && walled.has_cliffs());
    let (center, r) = (DVec3::new(0.004, 0.0, 0.036), 0.03);
    let s = std::f64::consts::FRAC_1_SQRT_2;
    // (depth, normal) of the face z = x and of z = −x
    let expected = [
        (r - 0.032 * s, DVec3::new(-s, 0.0, s)),
        (r - 0.040 * s, DVec3::new(s, 0.0, s)),
    ];
    for terrain in [&smooth, &walled] {
        let faces = sphere_faces(terrain, center, r, Orientation::Exact);
        let faces = faces.as_slice();
        assert_eq!(faces.len(), 2, "{faces:?}");
        for (face, (depth, normal)) in faces.iter().zip(expected) {
            assert!(
                (face.penetration - depth).abs() < 1e-6,
                "{} mm against {} mm",
                face.penetration * 1e3,
                depth * 1e3
            );
            assert!(face.frame.normal.abs_diff_eq(normal, 1e-6), "{face:?}");
        }
    }
}

/// Searches taken in turns end where each alone ends, bit for bit: from warm starts near the
/// answer and cold ones below the centre, touching and clear, on the paper's natural terrain
/// and in a hollow of the ball-scale one (dozens of iterations), in both orientations.
#[test]
fn searches_in_turns_are_each_the_search_alone() {
    let grids = [
        crate::terrain::natural(5489, 100, [2.0, 2.0], [0.0, 0.0], 0.04).unwrap(),
        crate::terrain::natural(5489, 100, [2.0, 2.0], [0.0, 0.0], 0.4).unwrap(),
    ];
    let orientations = [
        Orientation::Exact,
        Orientation::Paper { xe: 0.01, ye: 0.01 },
    ];
    for (terrain, orientation) in grids.iter().flat_map(|g| orientations.map(|o| (g, o))) {
        for round in 0..20 {
            let t = round as f64;
            let spheres: Vec<(DVec3, f64, (f64, f64))> = (0..1 + round % 6)
                .map(|k| {
                    let (x, y) = (
                        0.3 * (0.7 * t + k as f64).sin(),
                        0.3 * (1.3 * t - k as f64).cos(),
                    );
                    let r = 0.01 + 0.01 * (k % 3) as f64;
                    let z = terrain.height(x, y) + r * (0.9 - 0.1 * k as f64);
                    let start = if k % 2 == 0 {
                        (x, y)
                    } else {
                        (x + 1e-3, y - 2e-3)
                    };
                    (DVec3::new(x, y, z), r, start)
                })
                .collect();
            let together = closest_from_each(terrain, orientation, &spheres);
            for (k, &(center, r, start)) in spheres.iter().enumerate() {
                let alone = closest_from(terrain, center, r, orientation, start);
                let turn = together[k].expect("one answer a sphere");
                let bits = |v: DVec3| v.to_array().map(f64::to_bits);
                assert_eq!(turn.penetration.to_bits(), alone.penetration.to_bits());
                assert_eq!(bits(turn.point), bits(alone.point));
                assert_eq!(bits(turn.frame.normal), bits(alone.frame.normal));
                assert_eq!(bits(turn.frame.tangent_x), bits(alone.frame.tangent_x));
            }
            assert!(together[spheres.len()..].iter().all(Option::is_none));
        }
    }
}
