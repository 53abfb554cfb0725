//! The height grid and its interpolated surface.
//!
//! A terrain is a regular grid of heights `z[i][j]` over a rectangle: row `i` lies at
//! `y = y0 + i·dy`, column `j` at `x = x0 + j·dx` (the layout of the paper's MATLAB matrices and of
//! `natural_matlab_seed5489.csv`). Between the samples the surface is interpolated, and the contact
//! model reads the height *and* its analytic gradient from the same interpolant, so the normal it
//! uses is the exact normal of the surface it touches.
//!
//! Outside the rectangle the surface continues flat at the height of the nearest edge point
//! (coordinates are clamped): a body that walks off the map stands on a level apron instead of
//! falling through or panicking.

use super::cliff::{self, CellEdges, CellKind, Cliffs, Wall};
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// How heights are interpolated between grid samples.
///
/// The default is [`Interpolation::Bicubic`] (Catmull–Rom): its surface is C¹, so the normal — and
/// with it the direction of the contact force — varies continuously as a ball rolls from one cell
/// into the next. Bilinear patches meet with a kink, where the normal jumps; a penalty force whose
/// direction jumps is not the gradient of a potential, and a rolling ball can gain energy crossing
/// the kinks. Both interpolants reproduce planes exactly (Catmull–Rom reproduces quadratics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    Bilinear,
    #[default]
    Bicubic,
}

/// A sample of the surface: height and its partial derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    pub height: f64,
    /// ∂z/∂x
    pub slope_x: f64,
    /// ∂z/∂y
    pub slope_y: f64,
}

impl SurfacePoint {
    /// Exact unit normal of the surface z = h(x, y): (−∂h/∂x, −∂h/∂y, 1) / ‖·‖.
    pub fn normal(&self) -> DVec3 {
        DVec3::new(-self.slope_x, -self.slope_y, 1.0).normalize()
    }
}

/// A regular grid of finite heights over a rectangle.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGrid {
    /// Columns (samples along x), at least 2.
    nx: usize,
    /// Rows (samples along y), at least 2.
    ny: usize,
    x0: f64,
    y0: f64,
    dx: f64,
    dy: f64,
    /// Row-major: `heights[i * nx + j]` is the height at row i (y), column j (x).
    heights: Vec<f64>,
    interpolation: Interpolation,
    /// Per cell (row-major, (ny − 1)·(nx − 1)), an upper bound of the interpolated surface over it.
    ceilings: Vec<f64>,
    /// Where neighbouring samples jump like a stair's riser, read as walls (`cliff.rs`); None on
    /// a grid without any, whose surface is then the interpolation alone.
    cliffs: Option<Box<Cliffs>>,
    /// Per cell, on a bicubic grid without cliffs, the largest second difference of the samples
    /// its patch blends (log-encoded, see [`encode_bend`]), for [`Self::curvature_near`]; empty
    /// on other grids.
    bends: Vec<u8>,
}

/// Why a grid could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error("{}", crate::interrupt::MESSAGE)]
    Interrupted,
    #[error("a height grid needs at least 2×2 samples, got {rows}×{cols}")]
    TooSmall { rows: usize, cols: usize },
    #[error("expected {expected} heights for {rows}×{cols} samples, got {got}")]
    WrongLength {
        rows: usize,
        cols: usize,
        expected: usize,
        got: usize,
    },
    #[error("height at row {row}, column {col} is {value}, expected a finite number")]
    NonFinite { row: usize, col: usize, value: f64 },
    #[error("a grid of {rows}×{cols} samples is larger than the {max} samples hexsim accepts")]
    TooLarge { rows: f64, cols: f64, max: usize },
    #[error(
        "the grid's extent must be finite and positive, got x ∈ [{x_min}, {x_max}], y ∈ [{y_min}, {y_max}]"
    )]
    BadExtent {
        x_min: f64,
        x_max: f64,
        y_min: f64,
        y_max: f64,
    },
}

/// The largest grid hexsim accepts: 2²⁶ samples (512 MiB of f64). Checked before allocating.
pub const MAX_SAMPLES: usize = 1 << 26;

impl HeightGrid {
    /// A grid of `rows × cols` heights (row-major, row i at y, column j at x) spanning
    /// `[x_min, x_max] × [y_min, y_max]`.
    pub fn new(
        rows: usize,
        cols: usize,
        x_range: [f64; 2],
        y_range: [f64; 2],
        heights: Vec<f64>,
    ) -> Result<Self, GridError> {
        if rows < 2 || cols < 2 {
            return Err(GridError::TooSmall { rows, cols });
        }
        if heights.len() != rows * cols {
            return Err(GridError::WrongLength {
                rows,
                cols,
                expected: rows * cols,
                got: heights.len(),
            });
        }
        let [x_min, x_max] = x_range;
        let [y_min, y_max] = y_range;
        let extent_ok = [x_min, x_max, y_min, y_max].iter().all(|v| v.is_finite())
            && x_max > x_min
            && y_max > y_min;
        if !extent_ok {
            return Err(GridError::BadExtent {
                x_min,
                x_max,
                y_min,
                y_max,
            });
        }
        if let Some(k) = heights.iter().position(|h| !h.is_finite()) {
            return Err(GridError::NonFinite {
                row: k / cols,
                col: k % cols,
                value: heights[k],
            });
        }
        let (dx, dy) = (
            (x_max - x_min) / (cols - 1) as f64,
            (y_max - y_min) / (rows - 1) as f64,
        );
        let cliffs = Cliffs::find(&heights, cols, rows, dx, dy).map(Box::new);
        let mut grid = Self {
            nx: cols,
            ny: rows,
            x0: x_min,
            y0: y_min,
            dx,
            dy,
            heights,
            interpolation: Interpolation::default(),
            ceilings: Vec::new(),
            cliffs,
            bends: Vec::new(),
        };
        grid.ceilings = grid.cell_ceilings();
        grid.bends = grid.cell_bends();
        Ok(grid)
    }

    /// A grid sampled from a function z = f(x, y).
    pub fn from_fn(
        rows: usize,
        cols: usize,
        x_range: [f64; 2],
        y_range: [f64; 2],
        f: impl Fn(f64, f64) -> f64,
    ) -> Result<Self, GridError> {
        if rows < 2 || cols < 2 {
            return Err(GridError::TooSmall { rows, cols });
        }
        let x_at = |j: usize| x_range[0] + (x_range[1] - x_range[0]) * j as f64 / (cols - 1) as f64;
        let y_at = |i: usize| y_range[0] + (y_range[1] - y_range[0]) * i as f64 / (rows - 1) as f64;
        let mut heights = Vec::with_capacity(rows * cols);
        for i in 0..rows {
            // a large grid takes a while: Ctrl-C ends it between rows
            if crate::interrupt::interrupted() {
                return Err(GridError::Interrupted);
            }
            heights.extend((0..cols).map(|j| f(x_at(j), y_at(i))));
        }
        Self::new(rows, cols, x_range, y_range, heights)
    }

    pub fn with_interpolation(mut self, interpolation: Interpolation) -> Self {
        self.interpolation = interpolation;
        self.ceilings = self.cell_ceilings();
        self.bends = self.cell_bends();
        self
    }

    /// An upper bound of the surface height over the square of half-width `r` around (x, y): a
    /// sphere of radius r centred higher than this above (x, y) cannot touch the ground, which
    /// spares a swinging foot the closest-point search.
    ///
    /// Each cell's stored bound holds over the whole cell; over the part of it the square
    /// covers, the patch also lies below its corners' bilinear interpolant there (highest at a
    /// corner of the part) plus [`Self::patch_slack`]. A cell as wide as the terrain (a slope is
    /// one) has a stored bound as high as its highest corner, and every link sphere within it
    /// was searched: on a 10 m slope of 5°, 1600 closest-point searches a step on PhantomX, the
    /// step ten times slower than on level ground.
    pub fn ceiling_near(&self, x: f64, y: f64, r: f64) -> f64 {
        self.cells_near(x, y, r)
            .flatten()
            .map(|c| self.cell_ceiling_near(c, x, y, r))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Whether [`Self::ceiling_near`]`(x, y, r) < level`, the same answer bit for bit (`level >
    /// ceiling_near(..)`), looking at no more of the cells than it needs: a cell whose stored
    /// bound is below `level` is below it over the square too, and the first cell that reaches
    /// `level` settles it. Only the answer is read where the feet and link spheres are sorted
    /// into near and clear, several times a step.
    pub fn ceiling_below(&self, x: f64, y: f64, r: f64, level: f64) -> bool {
        self.ceiling_within(x, y, r, |c| c < level)
    }

    /// Whether [`Self::ceiling_near`]`(x, y, r) <= level`, the same answer bit for bit, as
    /// [`Self::ceiling_below`] finds it.
    pub fn ceiling_at_most(&self, x: f64, y: f64, r: f64, level: f64) -> bool {
        self.ceiling_within(x, y, r, |c| c <= level)
    }

    /// Whether the largest of the cells' bounds around (x, y) (as [`Self::ceiling_near`] folds
    /// them: from −∞, a NaN passed over) is `within`, a test that holds for every value below
    /// one that it holds for. A cell's bound over the square is its stored bound or less, so a
    /// stored bound `within` needs no more; one that is not is refined, and a refined bound not
    /// `within` answers no.
    #[inline]
    fn ceiling_within(&self, x: f64, y: f64, r: f64, within: impl Fn(f64) -> bool) -> bool {
        for row in self.cells_near(x, y, r) {
            for c in row {
                if within(self.ceilings[c]) {
                    continue;
                }
                let ceiling = self.cell_ceiling_near(c, x, y, r);
                if !(within(ceiling) || ceiling.is_nan()) {
                    return false;
                }
            }
        }
        within(f64::NEG_INFINITY)
    }

    /// Cell `c`'s bound over the square of half-width `r` around (x, y): its stored bound, or
    /// less where its corners' bilinear interpolant over the part the square covers, plus
    /// [`Self::patch_slack`], is lower ([`Self::ceiling_near`]).
    #[inline]
    fn cell_ceiling_near(&self, c: usize, x: f64, y: f64, r: f64) -> f64 {
        let cells = self.nx - 1;
        let stored = self.ceilings[c];
        let Some(slack) = self.patch_slack(c) else {
            return stored;
        };
        let (i, j) = (c / cells, c % cells);
        let (x0, y0) = (self.x_at(j), self.y_at(i));
        let span = |lo: f64, hi: f64, origin: f64, h: f64| {
            [
                ((lo - origin) / h).clamp(0.0, 1.0),
                ((hi - origin) / h).clamp(0.0, 1.0),
            ]
        };
        let (s, t) = (
            span(x - r, x + r, x0, self.dx),
            span(y - r, y + r, y0, self.dy),
        );
        let z = self.corners(i, j);
        let mut top = f64::NEG_INFINITY;
        for t in t {
            for s in s {
                let low = z[0][0] + s * (z[0][1] - z[0][0]);
                let high = z[1][0] + s * (z[1][1] - z[1][0]);
                top = top.max(low + t * (high - low));
            }
        }
        stored.min(top + slack)
    }

    /// How far above its corners' bilinear interpolant cell `c`'s patch may rise, or None where
    /// only its stored bound holds (a grid with cliffs); a nanometre more for rounding, and for
    /// bends below a nanometre, which [`Self::cell_bends`] stores as none. Bilinear: nothing
    /// more. Catmull–Rom: in one dimension the spline departs from the line through its middle
    /// samples by −½·[D₁·t(1 − t)² + D₂·t²(1 − t)], D₁ and D₂ the second differences, so by at
    /// most max|D|/8; across rows the same holds for the rows' splines, whose second differences
    /// are the columns' blended by weights of magnitudes summing to at most 1.25: at most
    /// (1 + 1.25)·B/8 with B the cell's largest second difference ([`Self::cell_bends`], rounded
    /// up).
    fn patch_slack(&self, c: usize) -> Option<f64> {
        if self.cliffs.is_some() {
            return None;
        }
        let bend = match self.interpolation {
            Interpolation::Bilinear => 0.0,
            Interpolation::Bicubic => 2.25 / 8.0 * decode_bend(self.bends[c]),
        };
        Some(bend + 1e-9)
    }

    /// The cells (as ranges of row-major cell indices, a row each) that the square of
    /// half-width `r` around (x, y) overlaps.
    fn cells_near(
        &self,
        x: f64,
        y: f64,
        r: f64,
    ) -> impl Iterator<Item = std::ops::RangeInclusive<usize>> {
        let (j0, _, _) = locate(x - r, self.x0, self.dx, self.nx);
        let (j1, _, _) = locate(x + r, self.x0, self.dx, self.nx);
        let (i0, _, _) = locate(y - r, self.y0, self.dy, self.ny);
        let (i1, _, _) = locate(y + r, self.y0, self.dy, self.ny);
        let cells = self.nx - 1;
        (i0..=i1).map(move |i| i * cells + j0..=i * cells + j1)
    }

    /// An upper bound of the surface's curvature |∂²z/∂u²| along any horizontal direction u
    /// over the square of half-width `r` around (x, y) (1/m), or None where it is not bounded
    /// so (a bilinear grid's patches meet at creases; a grid with cliffs has walls). The surface
    /// rises above a tangent plane at most K·L²/2 at a distance L from its point: where that
    /// cannot reach into a sphere, no second face of a crease need be looked for.
    ///
    /// A Catmull–Rom patch's ∂²z/∂x² at any point is (2D₁ − D₂) + 3t(D₂ − D₁) of a row's second
    /// differences D, at most 3·max|D| per dx², blended across rows by weights whose magnitudes
    /// sum to at most 1.25; its ∂²z/∂x∂y blends the mixed differences by derivative weights
    /// whose partial sums' magnitudes sum to at most 1.5 per axis. So |∂²z/∂u²| ≤
    /// |z_xx| + |z_xy| + |z_yy| over the mixed term's share ≤ (3.75 + 2.25)·B/h² with B the
    /// largest second difference of the 16 samples and h the shorter cell side.
    pub fn curvature_near(&self, x: f64, y: f64, r: f64) -> Option<f64> {
        if self.bends.is_empty() {
            return None;
        }
        let bend = self
            .cells_near(x, y, r)
            .flat_map(|row| &self.bends[row])
            .fold(0u8, |m, &b| m.max(b));
        let h = self.dx.min(self.dy);
        Some(6.0 * decode_bend(bend) / (h * h))
    }

    /// Each cell's largest second difference for [`Self::curvature_near`] (bicubic grids
    /// without cliffs only): along x, along y and mixed, over the 16 samples its patch blends.
    fn cell_bends(&self) -> Vec<u8> {
        if self.interpolation != Interpolation::Bicubic || self.cliffs.is_some() {
            return Vec::new();
        }
        let mut bends = Vec::with_capacity((self.ny - 1) * (self.nx - 1));
        let z = |i: isize, j: isize| self.ghost_sample(i, j);
        for i in 0..self.ny as isize - 1 {
            for j in 0..self.nx as isize - 1 {
                let mut b = 0.0f64;
                // each row's and column's second differences centred on the cell's corners, and
                // the mixed differences of every pair of the 4 × 4
                for k in -1..3 {
                    for m in 0..2 {
                        let (p, q) = (i + k, j + m);
                        b = b.max((z(p, q - 1) - 2.0 * z(p, q) + z(p, q + 1)).abs());
                        let (p, q) = (i + m, j + k);
                        b = b.max((z(p - 1, q) - 2.0 * z(p, q) + z(p + 1, q)).abs());
                    }
                }
                for a in -1..2 {
                    for c in -1..2 {
                        let (p, q) = (i + a, j + c);
                        b = b.max((z(p + 1, q + 1) - z(p + 1, q) - z(p, q + 1) + z(p, q)).abs());
                    }
                }
                bends.push(encode_bend(b));
            }
        }
        bends
    }

    /// Each cell's bound for [`Self::ceiling_near`]. Bilinear: the highest corner (the weights
    /// are non-negative). Catmull–Rom: the 16 samples it blends have weights summing to 1 whose
    /// absolute values sum to at most 1.25² (per axis 1 + t(1 − t) ≤ 1.25), so the surface stays
    /// within 1.5625 half-ranges of the samples' mid-range.
    fn cell_ceilings(&self) -> Vec<f64> {
        let mut ceilings = Vec::with_capacity((self.ny - 1) * (self.nx - 1));
        for i in 0..self.ny - 1 {
            for j in 0..self.nx - 1 {
                if let Some(c) = self.cliff_kind(i, j) {
                    // bilinear patches peak at a corner, a split cell's quadrants at one of
                    // their treads' corners
                    let z = self.corners(i, j);
                    let (ex, ey) = c.1;
                    let high = |e: [[f64; 2]; 2]| {
                        e.iter().flatten().fold(f64::NEG_INFINITY, |m, &v| m.max(v))
                    };
                    ceilings.push(match c.0 {
                        CellKind::Split => (0..4)
                            .map(|k| high(cliff::tread_corners(z, ex, ey, k / 2, k % 2)))
                            .fold(f64::NEG_INFINITY, f64::max),
                        _ => high(z),
                    });
                    continue;
                }
                let (lo, hi) = match self.interpolation {
                    Interpolation::Bilinear => (0..2)
                        .flat_map(|a| (0..2).map(move |b| (a, b)))
                        .map(|(a, b)| self.sample(i + a, j + b))
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), z| {
                            (lo.min(z), hi.max(z))
                        }),
                    Interpolation::Bicubic => (-1..3)
                        .flat_map(|a| (-1..3).map(move |b| (a, b)))
                        .map(|(a, b)| self.ghost_sample(i as isize + a, j as isize + b))
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), z| {
                            (lo.min(z), hi.max(z))
                        }),
                };
                ceilings.push(match self.interpolation {
                    Interpolation::Bilinear => hi,
                    Interpolation::Bicubic => 0.5 * (hi + lo) + 1.5625 * 0.5 * (hi - lo),
                });
            }
        }
        ceilings
    }

    /// Whether some neighbouring samples jump like a riser (and are read as a wall).
    pub fn has_cliffs(&self) -> bool {
        self.cliffs.is_some()
    }

    /// A cell's kind and cliff edges where it is not the plain interpolation's (None: it is).
    fn cliff_kind(&self, i: usize, j: usize) -> Option<(CellKind, CellEdges)> {
        let c = self.cliffs.as_deref()?;
        match c.cells[i * (self.nx - 1) + j] {
            CellKind::Smooth => None,
            kind => Some((kind, c.cell_edges(i, j))),
        }
    }

    /// Cell (i, j)'s corner samples, `[row][column]`.
    fn corners(&self, i: usize, j: usize) -> [[f64; 2]; 2] {
        [
            [self.sample(i, j), self.sample(i, j + 1)],
            [self.sample(i + 1, j), self.sample(i + 1, j + 1)],
        ]
    }

    /// The (x, y) of the sample nearest to `p` among those in the square of half-width `r`
    /// around it, if it lies within `r` of `p`: a point of the surface inside a sphere there,
    /// from which a closest-point search reaches a feature narrower than the sphere (a box's
    /// edge, one cell from the ground) that searches started at the footprint's rim step over.
    pub fn nearest_sample(&self, p: DVec3, r: f64) -> Option<(f64, f64)> {
        let (j0, _, _) = locate(p.x - r, self.x0, self.dx, self.nx);
        let (j1, _, _) = locate(p.x + r, self.x0, self.dx, self.nx);
        let (i0, _, _) = locate(p.y - r, self.y0, self.dy, self.ny);
        let (i1, _, _) = locate(p.y + r, self.y0, self.dy, self.ny);
        let mut best = None;
        let mut nearest = r * r;
        for i in i0..=i1 + 1 {
            let y = self.y_at(i);
            for j in j0..=j1 + 1 {
                let x = self.x_at(j);
                let d2 = DVec3::new(x, y, self.sample(i, j)).distance_squared(p);
                if d2 < nearest {
                    nearest = d2;
                    best = Some((x, y));
                }
            }
        }
        best
    }

    /// Calls `f` with every wall (a cliff's vertical face, [`cliff`]) in the cells the square of
    /// half-width `r` around (x, y) overlaps; nothing on a grid without cliffs.
    pub fn walls_near(&self, x: f64, y: f64, r: f64, mut f: impl FnMut(Wall)) {
        let Some(c) = self.cliffs.as_deref() else {
            return;
        };
        let (j0, _, _) = locate(x - r, self.x0, self.dx, self.nx);
        let (j1, _, _) = locate(x + r, self.x0, self.dx, self.nx);
        let (i0, _, _) = locate(y - r, self.y0, self.dy, self.ny);
        let (i1, _, _) = locate(y + r, self.y0, self.dy, self.ny);
        for i in i0..=i1 {
            for j in j0..=j1 {
                if c.cells[i * (self.nx - 1) + j] != CellKind::Split {
                    continue;
                }
                let (ex, ey) = c.cell_edges(i, j);
                let border = [j == 0, j + 2 == self.nx, i == 0, i + 2 == self.ny];
                let origin = DVec2::new(self.x_at(j), self.y_at(i));
                cliff::cell_walls(
                    self.corners(i, j),
                    ex,
                    ey,
                    origin,
                    (self.dx, self.dy),
                    border,
                    &mut f,
                );
            }
        }
    }

    pub fn interpolation(&self) -> Interpolation {
        self.interpolation
    }
    pub fn rows(&self) -> usize {
        self.ny
    }
    pub fn cols(&self) -> usize {
        self.nx
    }
    pub fn x_range(&self) -> [f64; 2] {
        [self.x0, self.x0 + self.dx * (self.nx - 1) as f64]
    }
    pub fn y_range(&self) -> [f64; 2] {
        [self.y0, self.y0 + self.dy * (self.ny - 1) as f64]
    }
    /// Sample spacing (dx, dy).
    pub fn spacing(&self) -> (f64, f64) {
        (self.dx, self.dy)
    }
    /// The x of column j.
    pub fn x_at(&self, j: usize) -> f64 {
        self.x0 + self.dx * j as f64
    }
    /// The y of row i.
    pub fn y_at(&self, i: usize) -> f64 {
        self.y0 + self.dy * i as f64
    }
    /// The stored sample at row i, column j.
    pub fn sample(&self, i: usize, j: usize) -> f64 {
        self.heights[i * self.nx + j]
    }
    /// All samples, row-major.
    pub fn samples(&self) -> &[f64] {
        &self.heights
    }
    /// (min, max) of the samples.
    pub fn height_bounds(&self) -> (f64, f64) {
        self.heights
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            })
    }

    /// Interpolated height at (x, y): [`Self::surface`]'s, bit for bit, without its slopes on a
    /// smooth grid (the sample's body height reads it every step).
    pub fn height(&self, x: f64, y: f64) -> f64 {
        if self.cliffs.is_some() || self.interpolation != Interpolation::Bicubic {
            return self.surface(x, y).height;
        }
        let (j, tx, _) = locate(x, self.x0, self.dx, self.nx);
        let (i, ty, _) = locate(y, self.y0, self.dy, self.ny);
        let (wx, wy) = (catmull_rom(tx).0, catmull_rom(ty).0);
        self.with_patch(i, j, |z| {
            let mut h = 0.0;
            for a in 0..4 {
                let r = z[a];
                let along = wx[0] * r[0] + wx[1] * r[1] + wx[2] * r[2] + wx[3] * r[3];
                h += wy[a] * along;
            }
            h
        })
    }

    /// The height table's value at (x, y), bilinear between the samples whatever the grid's
    /// interpolation: the paper's lookup (a table of heights read as MATLAB's interp2 does),
    /// for its contact variant step for step. Clamped to the rectangle like [`Self::height`].
    pub fn table_height(&self, x: f64, y: f64) -> f64 {
        let (j, tx, _) = locate(x, self.x0, self.dx, self.nx);
        let (i, ty, _) = locate(y, self.y0, self.dy, self.ny);
        let row = |i: usize| (1.0 - tx) * self.sample(i, j) + tx * self.sample(i, j + 1);
        (1.0 - ty) * row(i) + ty * row(i + 1)
    }

    /// Exact unit normal of the interpolated surface at (x, y).
    pub fn normal(&self, x: f64, y: f64) -> DVec3 {
        self.surface(x, y).normal()
    }

    /// Height and gradient of the interpolated surface at (x, y); outside the rectangle the
    /// coordinates are clamped to it, so the gradient across the boundary is zero there.
    pub fn surface(&self, x: f64, y: f64) -> SurfacePoint {
        let (j, tx, inside_x) = locate(x, self.x0, self.dx, self.nx);
        let (i, ty, inside_y) = locate(y, self.y0, self.dy, self.ny);
        if self.cliffs.is_some()
            && let Some(point) = self.near_cliff_surface(i, j, tx, ty, inside_x, inside_y)
        {
            return point;
        }
        let (wx, dwx) = self.weights(tx);
        let (wy, dwy) = self.weights(ty);
        let (mut h, mut hx, mut hy) = (0.0, 0.0, 0.0);
        match self.interpolation {
            Interpolation::Bilinear => {
                for a in 0..2 {
                    for b in 0..2 {
                        let z = self.sample(i + a, j + b);
                        h += wy[a] * wx[b] * z;
                        hx += wy[a] * dwx[b] * z;
                        hy += dwy[a] * wx[b] * z;
                    }
                }
            }
            Interpolation::Bicubic => {
                // each row blended along x first (its height and x slope), then the rows along
                // y: 44 products instead of the 96 of weighting each sample by both at once
                (h, hx, hy) = self.with_patch(i, j, |z| {
                    for a in 0..4 {
                        let r = z[a];
                        let along = wx[0] * r[0] + wx[1] * r[1] + wx[2] * r[2] + wx[3] * r[3];
                        let slope = dwx[0] * r[0] + dwx[1] * r[1] + dwx[2] * r[2] + dwx[3] * r[3];
                        h += wy[a] * along;
                        hx += wy[a] * slope;
                        hy += dwy[a] * along;
                    }
                    (h, hx, hy)
                });
            }
        }
        SurfacePoint {
            height: h,
            slope_x: if inside_x { hx / self.dx } else { 0.0 },
            slope_y: if inside_y { hy / self.dy } else { 0.0 },
        }
    }

    /// `blend` of the 4×4 samples around cell (i, j) (rows by y, each by x), a Catmull–Rom
    /// patch's: ghosts only at the grid's edge (the contact search evaluates a patch a dozen
    /// times a step, nearly always inside).
    #[inline(always)]
    fn with_patch<R>(&self, i: usize, j: usize, blend: impl FnOnce([&[f64; 4]; 4]) -> R) -> R {
        let inside = i >= 1 && i + 2 < self.ny && j >= 1 && j + 2 < self.nx;
        let ghosts: [[f64; 4]; 4];
        // read in place inside the grid (a copy of the 16 cost as much as their sums)
        let z: [&[f64; 4]; 4] = if inside {
            std::array::from_fn(|a| {
                let start = (i + a - 1) * self.nx + j - 1;
                self.heights[start..start + 4]
                    .try_into()
                    .expect("four samples")
            })
        } else {
            ghosts = std::array::from_fn(|a| {
                let r = i as isize + a as isize - 1;
                std::array::from_fn(|b| self.ghost_sample(r, j as isize + b as isize - 1))
            });
            std::array::from_fn(|a| &ghosts[a])
        };
        blend(z)
    }

    /// The surface in cell (i, j) at (tx, ty) if the cell is near a cliff (`cliff.rs`): bilinear,
    /// or its corner's tread in a split cell. Kept out of line: the hot path is the smooth one.
    #[cold]
    #[inline(never)]
    fn near_cliff_surface(
        &self,
        i: usize,
        j: usize,
        tx: f64,
        ty: f64,
        inside_x: bool,
        inside_y: bool,
    ) -> Option<SurfacePoint> {
        let (kind, (ex, ey)) = self.cliff_kind(i, j)?;
        let z = self.corners(i, j);
        let e = match kind {
            CellKind::Split => {
                cliff::tread_corners(z, ex, ey, (ty >= 0.5) as usize, (tx >= 0.5) as usize)
            }
            _ => z,
        };
        let (h, hx, hy) = cliff::bilinear(e, tx, ty);
        Some(SurfacePoint {
            height: h,
            slope_x: if inside_x { hx / self.dx } else { 0.0 },
            slope_y: if inside_y { hy / self.dy } else { 0.0 },
        })
    }

    /// Interpolation weights and their derivatives (per unit of t) for the local coordinate t ∈ [0, 1].
    fn weights(&self, t: f64) -> ([f64; 4], [f64; 4]) {
        match self.interpolation {
            Interpolation::Bilinear => ([1.0 - t, t, 0.0, 0.0], [-1.0, 1.0, 0.0, 0.0]),
            Interpolation::Bicubic => catmull_rom(t),
        }
    }

    /// A sample with one ghost row/column beyond each edge, extrapolated linearly
    /// (z₋₁ = 2z₀ − z₁), which keeps planes exact up to the edge.
    fn ghost_sample(&self, i: isize, j: isize) -> f64 {
        let column = |i: usize| -> f64 {
            let last = self.nx as isize - 1;
            if j < 0 {
                2.0 * self.sample(i, 0) - self.sample(i, 1)
            } else if j > last {
                2.0 * self.sample(i, self.nx - 1) - self.sample(i, self.nx - 2)
            } else {
                self.sample(i, j as usize)
            }
        };
        let last = self.ny as isize - 1;
        if i < 0 {
            2.0 * column(0) - column(1)
        } else if i > last {
            2.0 * column(self.ny - 1) - column(self.ny - 2)
        } else {
            column(i as usize)
        }
    }
}

/// Cell index, local coordinate in [0, 1] and whether the coordinate lay inside the grid.
fn locate(x: f64, origin: f64, spacing: f64, n: usize) -> (usize, f64, bool) {
    let u = (x - origin) / spacing;
    // sizes and cells go between integers and floats through i64, exactly as through usize
    // (they are far below 2⁵³), because x86-64 converts a signed integer in one instruction and
    // an unsigned one in several (the grid lookups run a hundred times a step)
    let last = (n - 1) as i64 as f64;
    // NaN compares false everywhere: treat it as outside, at the origin (callers check finiteness).
    let inside = (0.0..=last).contains(&u);
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, last) };
    // u ≥ 0: truncation is the floor, without the call to libm's `floor` that x86-64's baseline
    // instruction set (no SSE4.1 rounding) makes of it, a dozen times a step for each foot
    let cell = (u as i64 as usize).min(n - 2);
    (cell, u - cell as i64 as f64, inside)
}

/// Catmull–Rom weights for samples at −1, 0, 1, 2 and their derivatives with respect to t.
#[inline]
fn catmull_rom(t: f64) -> ([f64; 4], [f64; 4]) {
    let t2 = t * t;
    let t3 = t2 * t;
    (
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ],
        [
            0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
            0.5 * (9.0 * t2 - 10.0 * t),
            0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
            0.5 * (3.0 * t2 - 2.0 * t),
        ],
    )
}

/// A second difference (m) as a byte, rounded up: 2^(k/4) nm for k ≥ 1 (0: none), so that
/// [`decode_bend`] never gives less than was encoded (at most 19 % more); a grid's bends take one
/// byte a cell where an f64 took eight.
fn encode_bend(b: f64) -> u8 {
    // NaN cannot reach here: a grid's samples are finite
    if b <= 1e-9 {
        return 0;
    }
    (4.0 * (b / 1e-9).log2()).ceil().clamp(1.0, 255.0) as u8
}

fn decode_bend(k: u8) -> f64 {
    BENDS[k as usize]
}

/// [`decode_bend`] of every byte, computed once: the cells' bounds read it for every cell near a
/// foot, several times a step, and libm's `exp2` was a fifth of their cost.
static BENDS: std::sync::LazyLock<[f64; 256]> = std::sync::LazyLock::new(|| {
    std::array::from_fn(|k| {
        if k == 0 {
            0.0
        } else {
            1e-9 * (k as f64 / 4.0).exp2()
        }
    })
});

#[cfg(test)]
mod tests;
