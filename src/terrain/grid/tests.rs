//! Tests of `grid`.

use super::*;

fn plane(interp: Interpolation) -> HeightGrid {
    HeightGrid::from_fn(7, 9, [-1.0, 3.0], [-2.0, 1.0], |x, y| {
        0.3 * x - 0.2 * y + 0.1
    })
    .unwrap()
    .with_interpolation(interp)
}

proptest::proptest! {
    /// The ceiling bounds the surface: random grids, random points and radii.
    #[test]
    fn the_ceiling_bounds_the_surface_near_a_point(
        heights in proptest::collection::vec(-1.0f64..1.0, 30),
        bicubic in proptest::bool::ANY,
        x in -0.5f64..2.5,
        y in -0.5f64..1.5,
        r in 0.0f64..0.3,
        (u, v) in (-1.0f64..1.0, -1.0f64..1.0),
    ) {
        let interpolation = if bicubic { Interpolation::Bicubic } else { Interpolation::Bilinear };
        let grid = HeightGrid::new(5, 6, [0.0, 2.0], [0.0, 1.0], heights)
            .unwrap()
            .with_interpolation(interpolation);
        let ceiling = grid.ceiling_near(x, y, r);
        let h = grid.height(x + u * r, y + v * r);
        proptest::prop_assert!(h <= ceiling + 1e-12, "height {h} above ceiling {ceiling}");
    }
}

proptest::proptest! {
    /// The tests against the ceiling give what comparing with it gives, at levels around it
    /// and exactly on it: random grids, points and radii.
    #[test]
    fn the_tests_against_the_ceiling_are_comparisons_with_it(
        heights in proptest::collection::vec(-1.0f64..1.0, 30),
        bicubic in proptest::bool::ANY,
        x in -0.5f64..2.5,
        y in -0.5f64..1.5,
        r in 0.0f64..0.3,
        shift in -0.5f64..0.5,
    ) {
        let interpolation = if bicubic { Interpolation::Bicubic } else { Interpolation::Bilinear };
        let grid = HeightGrid::new(5, 6, [0.0, 2.0], [0.0, 1.0], heights)
            .unwrap()
            .with_interpolation(interpolation);
        let ceiling = grid.ceiling_near(x, y, r);
        for level in [ceiling, ceiling + shift, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            proptest::prop_assert_eq!(grid.ceiling_below(x, y, r, level), level > ceiling);
            proptest::prop_assert_eq!(grid.ceiling_at_most(x, y, r, level), ceiling <= level);
        }
    }
}

#[test]
fn the_ceiling_covers_catmull_rom_overshoot() {
    // a ridge 0, 1, 1, 0 both ways: Catmull–Rom peaks at 1.125² between the ones, above every
    // sample
    let p = [0.0, 1.0, 1.0, 0.0];
    let heights = (0..4).flat_map(|i| p.map(|q| q * p[i])).collect();
    let grid = HeightGrid::new(4, 4, [0.0, 3.0], [0.0, 3.0], heights).unwrap();
    let peak = grid.height(1.5, 1.5);
    assert!((peak - 1.125f64.powi(2)).abs() < 1e-12, "{peak}");
    assert!(grid.ceiling_near(1.5, 1.5, 0.0) >= peak);
}

#[test]
fn the_ceiling_is_tight_on_a_plane_cell_for_bilinear() {
    // a plane's bilinear patch over a point is the plane: the bound there is its height
    let grid = plane(Interpolation::Bilinear);
    let (x, y) = (grid.x_at(4) - 0.01, grid.y_at(0) + 0.01);
    let (ceiling, height) = (grid.ceiling_near(x, y, 0.0), grid.height(x, y));
    assert!(
        ceiling >= height && ceiling - height < 2e-9,
        "{ceiling} {height}"
    );
}

/// A slope is one cell as wide as the terrain: the bound near a point is the plane's highest
/// over the square around it, not the cell's highest corner 5 m uphill, in both interpolations.
#[test]
fn the_ceiling_near_a_point_of_a_wide_plane_cell_is_the_plane_there() {
    let rise = 5f64.to_radians().tan();
    for interp in [Interpolation::Bilinear, Interpolation::Bicubic] {
        let grid = HeightGrid::from_fn(2, 2, [-5.0, 5.0], [-5.0, 5.0], |x, _| rise * x)
            .unwrap()
            .with_interpolation(interp);
        let (x, r) = (-1.0, 0.02);
        let highest = grid.height(x + r, 0.0);
        let ceiling = grid.ceiling_near(x, 0.3, r);
        assert!(
            ceiling >= highest && ceiling - highest < 1e-8,
            "{interp:?}: ceiling {ceiling}, the plane's highest {highest}"
        );
    }
}

#[test]
fn planes_are_exact_in_both_interpolations() {
    for interp in [Interpolation::Bilinear, Interpolation::Bicubic] {
        let g = plane(interp);
        for &(x, y) in &[(0.0, 0.0), (-1.0, -2.0), (2.99, 0.99), (0.123, -1.77)] {
            let s = g.surface(x, y);
            assert!(
                (s.height - (0.3 * x - 0.2 * y + 0.1)).abs() < 1e-12,
                "{interp:?}"
            );
            assert!((s.slope_x - 0.3).abs() < 1e-12);
            assert!((s.slope_y + 0.2).abs() < 1e-12);
        }
    }
}

#[test]
fn bicubic_gradient_matches_finite_difference() {
    let g = HeightGrid::from_fn(12, 12, [0.0, 1.0], [0.0, 1.0], |x, y| {
        (5.0 * x).sin() * (3.0 * y).cos()
    })
    .unwrap();
    let h = 1e-6;
    for &(x, y) in &[(0.31, 0.47), (0.05, 0.93), (0.77, 0.12)] {
        let s = g.surface(x, y);
        let fx = (g.height(x + h, y) - g.height(x - h, y)) / (2.0 * h);
        let fy = (g.height(x, y + h) - g.height(x, y - h)) / (2.0 * h);
        assert!((s.slope_x - fx).abs() < 1e-6, "{} vs {}", s.slope_x, fx);
        assert!((s.slope_y - fy).abs() < 1e-6);
    }
}

#[test]
fn bicubic_is_c1_across_cell_borders() {
    let g = HeightGrid::from_fn(6, 6, [0.0, 5.0], [0.0, 5.0], |x, y| (x * y).sin()).unwrap();
    let e = 1e-9;
    let a = g.surface(2.0 - e, 1.3);
    let b = g.surface(2.0 + e, 1.3);
    assert!((a.slope_x - b.slope_x).abs() < 1e-6);
    assert!((a.slope_y - b.slope_y).abs() < 1e-6);
}

#[test]
fn interpolates_samples_exactly() {
    let g = HeightGrid::from_fn(5, 4, [0.0, 3.0], [0.0, 4.0], |x, y| x * x - y).unwrap();
    for i in 0..5 {
        for j in 0..4 {
            assert!((g.height(g.x_at(j), g.y_at(i)) - g.sample(i, j)).abs() < 1e-12);
        }
    }
}

#[test]
fn outside_is_the_clamped_edge_and_flat_across_it() {
    let g = plane(Interpolation::Bicubic);
    let edge = g.surface(3.0, 0.0);
    let out = g.surface(10.0, 0.0);
    assert!((out.height - edge.height).abs() < 1e-12);
    assert_eq!(out.slope_x, 0.0);
    assert!((out.slope_y + 0.2).abs() < 1e-12);
    let far = g.surface(f64::NAN, 1e300);
    assert!(far.height.is_finite());
}

#[test]
fn rejects_bad_grids() {
    assert!(matches!(
        HeightGrid::new(1, 5, [0.0, 1.0], [0.0, 1.0], vec![0.0; 5]),
        Err(GridError::TooSmall { .. })
    ));
    assert!(matches!(
        HeightGrid::new(2, 2, [0.0, 1.0], [0.0, 1.0], vec![0.0, f64::NAN, 0.0, 0.0]),
        Err(GridError::NonFinite { row: 0, col: 1, .. })
    ));
    assert!(matches!(
        HeightGrid::new(2, 2, [1.0, 1.0], [0.0, 1.0], vec![0.0; 4]),
        Err(GridError::BadExtent { .. })
    ));
}

/// The curvature bound holds: along random directions at random points of a rough bicubic
/// grid, the interpolated surface's second derivative (central differences of `height`)
/// never exceeds [`HeightGrid::curvature_near`] there; and it is not wildly loose (within
/// 20× of the largest found), nor offered where it does not hold (bilinear, cliffs).
#[test]
fn the_curvature_bound_bounds_the_surface() {
    let rough = |x: f64, y: f64| {
        0.02 * (7.0 * x).sin() * (5.0 * y).cos() + 0.005 * (23.0 * x + 17.0 * y).sin()
    };
    let grid = HeightGrid::from_fn(41, 41, [0.0, 1.0], [0.0, 1.0], rough).unwrap();
    let mut largest: f64 = 0.0;
    for k in 0..2000 {
        let f = k as f64;
        let (x, y) = (
            0.1 + 0.8 * (f * 0.6180339).fract(),
            0.1 + 0.8 * (f * 0.4142135).fract(),
        );
        let angle = f * 2.399963;
        let (u, v) = (angle.cos(), angle.sin());
        let e = 1e-4;
        let second = (grid.height(x + e * u, y + e * v) - 2.0 * grid.height(x, y)
            + grid.height(x - e * u, y - e * v))
            / (e * e);
        let bound = grid.curvature_near(x, y, 2.0 * e).unwrap();
        assert!(
            second.abs() <= bound,
            "at ({x}, {y}) along {angle}: {second} > {bound}"
        );
        largest = largest.max(second.abs() / bound);
    }
    assert!(
        largest > 0.05,
        "the bound is {} × the curvature at most",
        1.0 / largest
    );
    assert!(
        HeightGrid::from_fn(5, 5, [0.0, 1.0], [0.0, 1.0], rough)
            .unwrap()
            .with_interpolation(Interpolation::Bilinear)
            .curvature_near(0.5, 0.5, 0.1)
            .is_none()
    );
    let stair = |x: f64, _: f64| if x > 0.5 { 0.1 } else { 0.0 };
    let stairs = HeightGrid::from_fn(11, 101, [0.0, 1.0], [0.0, 1.0], stair).unwrap();
    assert!(stairs.has_cliffs() && stairs.curvature_near(0.2, 0.5, 0.1).is_none());
    assert_eq!(decode_bend(encode_bend(0.0)), 0.0);
    for b in [2e-9, 1e-6, 3.3e-3, 0.5] {
        let back = decode_bend(encode_bend(b));
        assert!(back >= b && back < 1.19 * b, "{b} -> {back}");
    }
}
