//! Cliffs in a height grid: a stair's riser, a box's side, a pit's wall.
//!
//! A grid cannot hold a vertical face, but its user means one where two neighbouring samples jump
//! by far more than the ground around them slopes. Interpolated across, such a jump becomes a ramp
//! one cell wide (bilinear) or a ramp with Catmull–Rom's ringing beside it (7.4 % of the jump: a
//! 10 cm riser grows a 7.4 mm dip before it and a bump after it), and a sphere pushed into the
//! ramp finds its closest point on the wrong tread. Here such a jump is a wall instead, midway
//! between the two samples:
//!
//! - **Detection.** The edge between two neighbouring samples (along x or y) is a cliff when the
//!   jump Δ across it is steeper than [`CLIFF_SLOPE`] (60°) and stands alone: the neighbouring
//!   differences on the same line are at most Δ / [`CLIFF_RATIO`]. A riser between treads two
//!   samples deep or more is a cliff; a steep plane (its differences all equal) is not, nor a
//!   one-sample post or a zigzag of coarse noise (a sampled sin(x·y) at one sample per radian),
//!   which stay the interpolation's bumps. Beyond the grid's edge the neighbouring difference is
//!   zero: the surface there is the level apron of the clamped coordinates
//!   ([`super::HeightGrid::surface`]), so a riser on the border's last edge is a wall like any
//!   other, not a Catmull–Rom ramp ringing 7.4 % of its height into the tread before it (a 6 cm
//!   riser ending a grid of stairs down rose 4.4 mm above the tread 1.4 cm before its edge). A
//!   steep plane reaching the border is still no cliff: the difference before its last edge is
//!   its own.
//! - **Surface.** A cell with a cliff on one of its four edges is split into quadrants, each the
//!   tread of its own corner: the bilinear patch of the corners it reaches without crossing a
//!   cliff, a corner cut off replaced by the tread continued (its own sample across a cliff edge,
//!   the plane through the other three across the diagonal). So on a cliff edge each half takes
//!   its own end's height and the wall stands at the edge's midpoint; on every other edge the
//!   patch is the linear interpolation of its ends, which is what the bilinear neighbour has, so
//!   the surface is continuous everywhere but at the walls. Level treads are reproduced exactly.
//!   Cells whose Catmull–Rom stencil reaches a cliff are bilinear, so no overshoot rings next to
//!   a wall. A grid without cliffs is untouched.

use glam::DVec2;

/// A jump steeper than this between neighbouring samples (tan 60°) may be a cliff.
pub const CLIFF_SLOPE: f64 = 1.732_050_807_568_877_2;
/// …if it is at least this many times the neighbouring differences on its line.
pub const CLIFF_RATIO: f64 = 3.0;

/// How a cell's surface is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum CellKind {
    /// The grid's interpolation.
    Smooth,
    /// Bilinear: the Catmull–Rom stencil reaches a cliff.
    Bilinear,
    /// A cliff on one of its edges: quadrants.
    Split,
}

/// A cell's cliff edges: along x on its two rows, along y on its two columns.
pub(super) type CellEdges = ([bool; 2], [bool; 2]);

/// Where a grid's cliffs are.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Cliffs {
    /// Edges along x, between samples (i, j) and (i, j + 1): row-major, ny × (nx − 1).
    along_x: Vec<bool>,
    /// Edges along y, between samples (i, j) and (i + 1, j): row-major, (ny − 1) × nx.
    along_y: Vec<bool>,
    /// Per cell, row-major (ny − 1) × (nx − 1).
    pub(super) cells: Vec<CellKind>,
    nx: usize,
}

/// Whether the jump `d` across an edge (the next difference along the line either side: `before`,
/// `after`) is a cliff for a sample spacing `spacing`.
fn is_cliff(before: f64, d: f64, after: f64, spacing: f64) -> bool {
    d.abs() > CLIFF_SLOPE * spacing && d.abs() >= CLIFF_RATIO * before.abs().max(after.abs())
}

impl Cliffs {
    /// The cliffs of a row-major `ny × nx` grid of `heights` with spacing (dx, dy); None without any.
    pub(super) fn find(heights: &[f64], nx: usize, ny: usize, dx: f64, dy: f64) -> Option<Self> {
        let z = |i: usize, j: usize| heights[i * nx + j];
        let along_x: Vec<bool> = (0..ny)
            .flat_map(|i| (0..nx - 1).map(move |j| (i, j)))
            .map(|(i, j)| {
                let d = z(i, j + 1) - z(i, j);
                let before = if j > 0 { z(i, j) - z(i, j - 1) } else { 0.0 };
                let after = if j + 2 < nx {
                    z(i, j + 2) - z(i, j + 1)
                } else {
                    0.0
                };
                is_cliff(before, d, after, dx)
            })
            .collect();
        let along_y: Vec<bool> = (0..ny - 1)
            .flat_map(|i| (0..nx).map(move |j| (i, j)))
            .map(|(i, j)| {
                let d = z(i + 1, j) - z(i, j);
                let before = if i > 0 { z(i, j) - z(i - 1, j) } else { 0.0 };
                let after = if i + 2 < ny {
                    z(i + 2, j) - z(i + 1, j)
                } else {
                    0.0
                };
                is_cliff(before, d, after, dy)
            })
            .collect();
        if !along_x.contains(&true) && !along_y.contains(&true) {
            return None;
        }
        let mut cliffs = Cliffs {
            along_x,
            along_y,
            cells: Vec::new(),
            nx,
        };
        // a cliff edge within the Catmull–Rom stencil (rows i−1..i+2, columns j−1..j+2)
        let near = |c: &Cliffs, i: usize, j: usize| {
            let rows = i.saturating_sub(1)..(i + 3).min(ny);
            let cols = j.saturating_sub(1)..(j + 3).min(nx);
            rows.clone().any(|r| {
                cols.clone().any(|k| {
                    (k + 1 < cols.end && c.x_edge(r, k)) || (r + 1 < rows.end && c.y_edge(r, k))
                })
            })
        };
        cliffs.cells = (0..ny - 1)
            .flat_map(|i| (0..nx - 1).map(move |j| (i, j)))
            .map(|(i, j)| {
                let (ex, ey) = cliffs.cell_edges(i, j);
                if ex.contains(&true) || ey.contains(&true) {
                    CellKind::Split
                } else if near(&cliffs, i, j) {
                    CellKind::Bilinear
                } else {
                    CellKind::Smooth
                }
            })
            .collect();
        Some(cliffs)
    }

    fn x_edge(&self, i: usize, j: usize) -> bool {
        self.along_x[i * (self.nx - 1) + j]
    }
    fn y_edge(&self, i: usize, j: usize) -> bool {
        self.along_y[i * self.nx + j]
    }

    /// Cell (i, j)'s cliff edges: along x on its rows i and i + 1, along y on its columns j and
    /// j + 1.
    pub(super) fn cell_edges(&self, i: usize, j: usize) -> CellEdges {
        (
            [self.x_edge(i, j), self.x_edge(i + 1, j)],
            [self.y_edge(i, j), self.y_edge(i, j + 1)],
        )
    }
}

/// A split cell's corners `z[a][b]` (a: row, b: column) as the tread of corner (a, b) sees them:
/// a corner across a cliff edge takes (a, b)'s own height, the diagonal one reached only across
/// cliffs the plane through the other three.
pub(super) fn tread_corners(
    z: [[f64; 2]; 2],
    ex: [bool; 2],
    ey: [bool; 2],
    a: usize,
    b: usize,
) -> [[f64; 2]; 2] {
    let own = z[a][b];
    let along_x = if ex[a] { own } else { z[a][1 - b] };
    let along_y = if ey[b] { own } else { z[1 - a][b] };
    let linked = (!ex[a] && !ey[1 - b]) || (!ey[b] && !ex[1 - a]);
    let diagonal = if linked {
        z[1 - a][1 - b]
    } else {
        along_x + along_y - own
    };
    let mut e = [[0.0; 2]; 2];
    e[a][b] = own;
    e[a][1 - b] = along_x;
    e[1 - a][b] = along_y;
    e[1 - a][1 - b] = diagonal;
    e
}

/// Bilinear height and its derivatives per unit (tx, ty) over corners `e[a][b]`.
/// Written from the first corner so that a level patch is its height exactly, not within rounding.
pub(super) fn bilinear(e: [[f64; 2]; 2], tx: f64, ty: f64) -> (f64, f64, f64) {
    let (along_x, along_y) = (e[0][1] - e[0][0], e[1][0] - e[0][0]);
    let twist = e[1][1] - e[1][0] - e[0][1] + e[0][0];
    (
        e[0][0] + tx * along_x + ty * along_y + tx * ty * twist,
        along_x + ty * twist,
        along_y + tx * twist,
    )
}

/// A vertical face between two treads: the part of a cliff in one cell (half an edge's length),
/// on the plane where coordinate `axis` (0: x, 1: y) equals `at`, spanning `span` along the other
/// horizontal axis. `heights[side][end]`: the tread's height at each end of the span, side 0 the
/// one towards smaller `axis` coordinates. An `open` end continues past the span at that end's
/// heights (a cliff reaching the grid's border goes on along the flat apron beyond it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    pub axis: usize,
    pub at: f64,
    pub span: [f64; 2],
    pub open: [bool; 2],
    pub heights: [[f64; 2]; 2],
}

impl Wall {
    /// The point of the face closest to `p` and the face's outward normal there (towards the
    /// lower tread), exact for a face between level treads (a rectangle); between sloping treads
    /// the clamped height is a close approximation to the closest boundary point.
    pub fn closest(&self, p: glam::DVec3) -> (glam::DVec3, glam::DVec3) {
        let s = if self.axis == 0 { p.y } else { p.x };
        let lo = if self.open[0] {
            f64::NEG_INFINITY
        } else {
            self.span[0]
        };
        let hi = if self.open[1] {
            f64::INFINITY
        } else {
            self.span[1]
        };
        let along = s.clamp(lo, hi);
        let t = ((along - self.span[0]) / (self.span[1] - self.span[0])).clamp(0.0, 1.0);
        let side = |k: usize| self.heights[k][0] + t * (self.heights[k][1] - self.heights[k][0]);
        let (h0, h1) = (side(0), side(1));
        let z = p.z.clamp(h0.min(h1), h0.max(h1));
        // out of the face towards the lower tread
        let sign = if h0 < h1 { -1.0 } else { 1.0 };
        let (point, normal) = if self.axis == 0 {
            (
                glam::DVec3::new(self.at, along, z),
                glam::DVec3::new(sign, 0.0, 0.0),
            )
        } else {
            (
                glam::DVec3::new(along, self.at, z),
                glam::DVec3::new(0.0, sign, 0.0),
            )
        };
        (point, normal)
    }
}

/// The walls of split cell (i, j) with corners `z`, cliff edges `ex`, `ey`, the cell's lower
/// corner `origin` and spacing `(dx, dy)`; `border` says which of its sides (−x, +x, −y, +y) lie on
/// the grid's border. Each is passed to `f`.
#[allow(clippy::too_many_arguments)]
pub(super) fn cell_walls(
    z: [[f64; 2]; 2],
    ex: [bool; 2],
    ey: [bool; 2],
    origin: DVec2,
    (dx, dy): (f64, f64),
    border: [bool; 4],
    f: &mut impl FnMut(Wall),
) {
    let height =
        |a: usize, b: usize, tx: f64, ty: f64| bilinear(tread_corners(z, ex, ey, a, b), tx, ty).0;
    for a in (0..2).filter(|&k| ex[k]) {
        // the face at x = mid over this row's half of the cell (a = 0: ty ∈ [0, ½])
        let (t0, t1) = (0.5 * a as f64, 0.5 * a as f64 + 0.5);
        f(Wall {
            axis: 0,
            at: origin.x + 0.5 * dx,
            span: [origin.y + t0 * dy, origin.y + t1 * dy],
            open: [a == 0 && border[2], a == 1 && border[3]],
            heights: [
                [height(a, 0, 0.5, t0), height(a, 0, 0.5, t1)],
                [height(a, 1, 0.5, t0), height(a, 1, 0.5, t1)],
            ],
        });
    }
    for b in (0..2).filter(|&k| ey[k]) {
        let (t0, t1) = (0.5 * b as f64, 0.5 * b as f64 + 0.5);
        f(Wall {
            axis: 1,
            at: origin.y + 0.5 * dy,
            span: [origin.x + t0 * dx, origin.x + t1 * dx],
            open: [b == 0 && border[0], b == 1 && border[1]],
            heights: [
                [height(0, b, t0, 0.5), height(0, b, t1, 0.5)],
                [height(1, b, t0, 0.5), height(1, b, t1, 0.5)],
            ],
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_riser_between_level_treads_is_a_cliff_a_steep_plane_is_not() {
        assert!(is_cliff(0.0, 0.1, 0.0, 0.01));
        // a riser beside gently sloping treads
        assert!(is_cliff(0.003, 0.1, -0.002, 0.01));
        // a one-sample post, or noise: the neighbours jump as much
        assert!(!is_cliff(-0.1, 0.1, -0.1, 0.01));
        // a plane at 70°: every difference the same
        let d = 0.01 * 70f64.to_radians().tan();
        assert!(!is_cliff(d, d, d, 0.01));
        // a jump less steep than 60°
        assert!(!is_cliff(0.0, 0.017, 0.0, 0.01));
    }

    #[test]
    fn level_treads_are_reproduced_exactly_in_every_quadrant() {
        // a box corner: only (1, 1) high, cliffs on the edges that reach it
        let z = [[0.0, 0.0], [0.0, 0.1]];
        let (ex, ey) = ([false, true], [false, true]);
        for (a, b, want) in [(0, 0, 0.0), (0, 1, 0.0), (1, 0, 0.0), (1, 1, 0.1)] {
            let e = tread_corners(z, ex, ey, a, b);
            for (tx, ty) in [(0.1, 0.2), (0.4, 0.45), (0.6, 0.9)] {
                let (h, hx, hy) = bilinear(e, tx, ty);
                assert_eq!((h, hx, hy), (want, 0.0, 0.0), "quadrant ({a}, {b})");
            }
        }
    }
}
