//! Where a terrain's heights come from: one parameter struct per generator or height file, each
//! with its defaults, its checks and its build, so a new source is one struct here and one line in
//! [`Source`].

use super::generate;
use super::grid::{GridError, HeightGrid};
use super::io::{self, HeightFileError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A field out of range: its name within `[source]`, and what was expected.
pub type FieldError = (&'static str, String);

/// Why a source gave no grid.
pub enum BuildError {
    Grid(GridError),
    /// A height file could not be read (its path, relative to the terrain file).
    Data(PathBuf, HeightFileError),
}

/// What every source does.
pub trait HeightSource {
    /// Checks every parameter's range, naming the field that is wrong.
    fn validate(&self) -> Result<(), FieldError>;

    /// Builds the grid; a height file's path resolves against `base`.
    fn build(&self, base: &Path) -> Result<HeightGrid, BuildError>;

    /// The random generator's seed, for sources that have one.
    fn seed(&self) -> Option<u32> {
        None
    }

    fn seed_mut(&mut self) -> Option<&mut u32> {
        None
    }

    /// The height file read, for sources that read one (relative to the terrain file).
    fn data_file(&self) -> Option<&Path> {
        None
    }
}

/// Where the heights come from (`kind = "..."` in `[source]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Source {
    Natural(Natural),
    Bell(Bell),
    Flat(Flat),
    Slope(Slope),
    Steps(Steps),
    Stairs(Stairs),
    PyramidStairs(PyramidStairs),
    DiscreteObstacles(DiscreteObstacles),
    SteppingStones(SteppingStones),
    Gaps(Gaps),
    Rough(Rough),
    Sine(Sine),
    Csv(Csv),
    Png(Png),
    Stl(Stl),
}

impl Source {
    pub fn get(&self) -> &dyn HeightSource {
        match self {
            Source::Natural(s) => s,
            Source::Bell(s) => s,
            Source::Flat(s) => s,
            Source::Slope(s) => s,
            Source::Steps(s) => s,
            Source::Stairs(s) => s,
            Source::PyramidStairs(s) => s,
            Source::DiscreteObstacles(s) => s,
            Source::SteppingStones(s) => s,
            Source::Gaps(s) => s,
            Source::Rough(s) => s,
            Source::Sine(s) => s,
            Source::Csv(s) => s,
            Source::Png(s) => s,
            Source::Stl(s) => s,
        }
    }

    pub fn get_mut(&mut self) -> &mut dyn HeightSource {
        match self {
            Source::Natural(s) => s,
            Source::Bell(s) => s,
            Source::Flat(s) => s,
            Source::Slope(s) => s,
            Source::Steps(s) => s,
            Source::Stairs(s) => s,
            Source::PyramidStairs(s) => s,
            Source::DiscreteObstacles(s) => s,
            Source::SteppingStones(s) => s,
            Source::Gaps(s) => s,
            Source::Rough(s) => s,
            Source::Sine(s) => s,
            Source::Csv(s) => s,
            Source::Png(s) => s,
            Source::Stl(s) => s,
        }
    }
}

fn zero2() -> [f64; 2] {
    [0.0, 0.0]
}
fn one() -> f64 {
    1.0
}
fn cell_1cm() -> f64 {
    0.01
}
fn flat_size() -> [f64; 2] {
    [20.0, 20.0]
}

// the checks the sources share
fn positive(field: &'static str, v: f64) -> Result<(), FieldError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err((field, format!("expected a finite number > 0, got {v}")))
    }
}
/// The cell (a positive length) no larger than the size: the grid holds at least 2×2 samples
/// with the cell given (rather than silently 2×2 of a larger one).
fn cell_fits(size: [f64; 2], cell: f64) -> Result<(), FieldError> {
    positive("cell", cell)?;
    let least = size[0].min(size[1]);
    if cell > least {
        return Err((
            "cell",
            format!(
                "expected at most the terrain's smaller size ({least} m), so the grid has at least 2×2 samples, got {cell}"
            ),
        ));
    }
    Ok(())
}
fn finite(field: &'static str, v: f64) -> Result<(), FieldError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err((field, format!("expected a finite number, got {v}")))
    }
}
fn size2(field: &'static str, s: [f64; 2]) -> Result<(), FieldError> {
    if s.iter().all(|v| v.is_finite() && *v > 0.0) {
        Ok(())
    } else {
        Err((field, format!("expected two finite sizes > 0, got {s:?}")))
    }
}
fn finite2(field: &'static str, s: [f64; 2]) -> Result<(), FieldError> {
    if s.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err((field, format!("expected two finite numbers, got {s:?}")))
    }
}
fn range(field: &'static str, r: [f64; 2]) -> Result<(), FieldError> {
    if r.iter().all(|v| v.is_finite()) && r[1] > r[0] {
        Ok(())
    } else {
        Err((
            field,
            format!("expected [min, max] with min < max, got {r:?}"),
        ))
    }
}
/// A length the grid must hold at least two samples across: a tread or a pit one sample wide
/// meets its neighbours with equal jumps either side, which is a bump, not walls (`cliff.rs`).
fn cells2(field: &'static str, v: f64, cell: f64) -> Result<(), FieldError> {
    positive(field, v)?;
    if v >= 2.0 * cell {
        Ok(())
    } else {
        Err((
            field,
            format!(
                "expected at least two cells ({} m at `cell` = {cell} m) so the grid holds it between its walls, got {v}",
                2.0 * cell
            ),
        ))
    }
}
fn count(field: &'static str, n: usize, max: usize) -> Result<(), FieldError> {
    if (1..=max).contains(&n) {
        Ok(())
    } else {
        Err((field, format!("expected 1 to {max}, got {n}")))
    }
}
/// [min, max] of finite numbers with min ≤ max.
fn bounds(field: &'static str, r: [f64; 2]) -> Result<(), FieldError> {
    if r.iter().all(|v| v.is_finite()) && r[0] <= r[1] {
        Ok(())
    } else {
        Err((
            field,
            format!("expected [min, max] of finite numbers with min ≤ max, got {r:?}"),
        ))
    }
}
fn non_negative(field: &'static str, v: f64) -> Result<(), FieldError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err((field, format!("expected a finite number ≥ 0, got {v}")))
    }
}
/// The terrain must hold a feature `extent` wide (named by `what`).
fn holds(size: [f64; 2], extent: f64, what: &str) -> Result<(), FieldError> {
    if size[0].min(size[1]) >= extent {
        Ok(())
    } else {
        Err((
            "size",
            format!(
                "expected at least {} m each way to hold {what}, got {size:?}",
                (extent * 1e3).round() / 1e3
            ),
        ))
    }
}
fn one_meter() -> f64 {
    1.0
}

fn samples(field: &'static str, n: usize) -> Result<(), FieldError> {
    if (2..=8192).contains(&n) {
        Ok(())
    } else {
        Err((
            field,
            format!("expected 2 to 8192 samples per side, got {n}"),
        ))
    }
}

/// The paper's fractal terrain (eq. 7); seed 5489 is MATLAB's `rng default`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Natural {
    #[serde(default = "Natural::paper_seed")]
    pub seed: u32,
    #[serde(default = "Natural::samples")]
    pub samples: usize,
    #[serde(default = "Natural::size")]
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    /// The hexapod's scale by default (0.04 m).
    #[serde(default = "Natural::peak_to_peak")]
    pub peak_to_peak: f64,
    /// Copies along x and y, the first in place and the others toward +x and +y (the surface is
    /// periodic, so they meet without a seam); [1, 1]: one.
    #[serde(default = "Natural::one_tile")]
    pub tiles: [usize; 2],
}

impl Natural {
    fn paper_seed() -> u32 {
        5489
    }
    fn samples() -> usize {
        100
    }
    fn size() -> [f64; 2] {
        [4.0, 4.0]
    }
    fn peak_to_peak() -> f64 {
        0.04
    }
    fn one_tile() -> [usize; 2] {
        [1, 1]
    }
}

impl HeightSource for Natural {
    fn validate(&self) -> Result<(), FieldError> {
        samples("samples", self.samples)?;
        size2("size", self.size)?;
        finite2("center", self.center)?;
        if !(self.peak_to_peak.is_finite() && self.peak_to_peak >= 0.0) {
            return Err((
                "peak_to_peak",
                format!("expected a finite number ≥ 0, got {}", self.peak_to_peak),
            ));
        }
        if self.tiles.contains(&0) {
            return Err((
                "tiles",
                format!("expected [x, y] copies of at least 1, got {:?}", self.tiles),
            ));
        }
        Ok(())
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::natural(
            self.seed,
            self.samples,
            self.size,
            self.center,
            self.peak_to_peak,
        )
        .and_then(|tile| generate::tiled(tile, self.tiles))
        .map_err(BuildError::Grid)
    }

    fn seed(&self) -> Option<u32> {
        Some(self.seed)
    }

    fn seed_mut(&mut self) -> Option<&mut u32> {
        Some(&mut self.seed)
    }
}

/// The paper's inverted bell (eq. 8), −depth·exp(−(x²+y²)/2σ²).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bell {
    #[serde(default = "Bell::half_width")]
    pub half_width: f64,
    #[serde(default = "Bell::samples")]
    pub samples: usize,
    #[serde(default = "one")]
    pub depth: f64,
    #[serde(default = "one")]
    pub sigma: f64,
}

impl Bell {
    fn half_width() -> f64 {
        3.0
    }
    fn samples() -> usize {
        241
    }
}

impl HeightSource for Bell {
    fn validate(&self) -> Result<(), FieldError> {
        positive("half_width", self.half_width)?;
        samples("samples", self.samples)?;
        finite("depth", self.depth)?;
        positive("sigma", self.sigma)
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::bell(self.half_width, self.samples, self.depth, self.sigma)
            .map_err(BuildError::Grid)
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Flat {
    #[serde(default = "flat_size")]
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default)]
    pub height: f64,
}

impl HeightSource for Flat {
    fn validate(&self) -> Result<(), FieldError> {
        size2("size", self.size)?;
        finite2("center", self.center)?;
        finite("height", self.height)
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::flat(self.size, self.center, self.height).map_err(BuildError::Grid)
    }
}

/// A plane rising at `angle_deg` towards the azimuth `ascent_deg` (0 = +x).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Slope {
    pub angle_deg: f64,
    #[serde(default)]
    pub ascent_deg: f64,
    #[serde(default = "flat_size")]
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
}

impl HeightSource for Slope {
    fn validate(&self) -> Result<(), FieldError> {
        if !(self.angle_deg.is_finite() && self.angle_deg.abs() < 89.0) {
            return Err((
                "angle_deg",
                format!("expected an angle within ±89°, got {}", self.angle_deg),
            ));
        }
        finite("ascent_deg", self.ascent_deg)?;
        size2("size", self.size)?;
        finite2("center", self.center)
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::slope(
            self.size,
            self.center,
            self.angle_deg.to_radians(),
            self.ascent_deg.to_radians(),
        )
        .map_err(BuildError::Grid)
    }
}

/// Stairs along +x.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Steps {
    pub step_height: f64,
    pub step_length: f64,
    #[serde(default)]
    pub first_step: f64,
    #[serde(default = "flat_size")]
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl HeightSource for Steps {
    fn validate(&self) -> Result<(), FieldError> {
        finite("step_height", self.step_height)?;
        positive("step_length", self.step_length)?;
        finite("first_step", self.first_step)?;
        size2("size", self.size)?;
        finite2("center", self.center)?;
        cell_fits(self.size, self.cell)
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::steps(
            self.size,
            self.center,
            self.first_step,
            self.step_length,
            self.step_height,
            self.cell,
        )
        .map_err(BuildError::Grid)
    }
}

/// Stairs along +x, up `count` steps, a landing, and down as many.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stairs {
    pub step_height: f64,
    pub step_length: f64,
    pub count: usize,
    #[serde(default = "one_meter")]
    pub landing: f64,
    #[serde(default)]
    pub first_step: f64,
    #[serde(default = "flat_size")]
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl HeightSource for Stairs {
    fn validate(&self) -> Result<(), FieldError> {
        positive("cell", self.cell)?;
        finite("step_height", self.step_height)?;
        cells2("step_length", self.step_length, self.cell)?;
        count("count", self.count, 1000)?;
        cells2("landing", self.landing, self.cell)?;
        finite("first_step", self.first_step)?;
        size2("size", self.size)?;
        finite2("center", self.center)
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::stairs(
            self.size,
            self.center,
            self.first_step,
            self.count,
            self.step_length,
            self.step_height,
            self.landing,
            self.cell,
        )
        .map_err(BuildError::Grid)
    }
}

/// Concentric square steps, `count` up to a top at the centre (down into a pit if
/// `step_height` < 0).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PyramidStairs {
    pub step_height: f64,
    pub step_width: f64,
    pub count: usize,
    #[serde(default = "one_meter")]
    pub top: f64,
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl HeightSource for PyramidStairs {
    fn validate(&self) -> Result<(), FieldError> {
        positive("cell", self.cell)?;
        finite("step_height", self.step_height)?;
        cells2("step_width", self.step_width, self.cell)?;
        count("count", self.count, 1000)?;
        cells2("top", self.top, self.cell)?;
        size2("size", self.size)?;
        finite2("center", self.center)?;
        let width = self.top + 2.0 * (self.count - 1) as f64 * self.step_width;
        holds(
            self.size,
            width,
            "the pyramid (top + 2·(count − 1)·step_width)",
        )
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::pyramid_stairs(
            self.size,
            self.center,
            self.count,
            self.step_width,
            self.step_height,
            self.top,
            self.cell,
        )
        .map_err(BuildError::Grid)
    }
}

/// legged_gym's discrete obstacles: seeded random boxes (or holes) on level ground.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiscreteObstacles {
    pub count: usize,
    /// Each box's sides, uniform in [min, max] (m).
    pub side: [f64; 2],
    /// Each box's height, uniform in [min, max] (m; negative: a hole).
    pub height: [f64; 2],
    /// The level square this wide at the centre, where a robot starts.
    #[serde(default = "one_meter")]
    pub platform: f64,
    #[serde(default)]
    pub seed: u32,
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl HeightSource for DiscreteObstacles {
    fn validate(&self) -> Result<(), FieldError> {
        positive("cell", self.cell)?;
        count("count", self.count, 100_000)?;
        bounds("side", self.side)?;
        cells2("side", self.side[0], self.cell)?;
        bounds("height", self.height)?;
        non_negative("platform", self.platform)?;
        size2("size", self.size)?;
        finite2("center", self.center)?;
        holds(self.size, self.platform, "the platform")
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::discrete_obstacles(
            self.size,
            self.center,
            self.count,
            self.side,
            self.height,
            self.platform,
            self.seed,
            self.cell,
        )
        .map_err(BuildError::Grid)
    }

    fn seed(&self) -> Option<u32> {
        Some(self.seed)
    }

    fn seed_mut(&mut self) -> Option<&mut u32> {
        Some(&mut self.seed)
    }
}

/// Square stones in a regular grid over pits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SteppingStones {
    /// Each stone's side (m).
    pub stone: f64,
    /// The pit between neighbouring stones (m).
    pub gap: f64,
    /// The pits' depth below the stones' tops (m).
    pub depth: f64,
    /// The solid square this wide at the centre, where a robot starts.
    #[serde(default = "one_meter")]
    pub platform: f64,
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl HeightSource for SteppingStones {
    fn validate(&self) -> Result<(), FieldError> {
        positive("cell", self.cell)?;
        cells2("stone", self.stone, self.cell)?;
        cells2("gap", self.gap, self.cell)?;
        positive("depth", self.depth)?;
        non_negative("platform", self.platform)?;
        size2("size", self.size)?;
        finite2("center", self.center)?;
        holds(self.size, self.platform, "the platform")
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::stepping_stones(
            self.size,
            self.center,
            self.stone,
            self.gap,
            self.depth,
            self.platform,
            self.cell,
        )
        .map_err(BuildError::Grid)
    }
}

/// Trenches across the way along +x.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gaps {
    /// Each trench's width along x (m).
    pub width: f64,
    /// From one trench's start to the next's (m).
    pub spacing: f64,
    pub depth: f64,
    #[serde(default)]
    pub first_gap: f64,
    #[serde(default = "flat_size")]
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl HeightSource for Gaps {
    fn validate(&self) -> Result<(), FieldError> {
        positive("cell", self.cell)?;
        cells2("width", self.width, self.cell)?;
        positive("spacing", self.spacing)?;
        cells2("spacing", self.spacing - self.width, self.cell).map_err(|_| {
            (
                "spacing",
                format!(
                    "expected at least `width` + two cells ({} m) so ground is left between the trenches, got {}",
                    self.width + 2.0 * self.cell,
                    self.spacing
                ),
            )
        })?;
        positive("depth", self.depth)?;
        finite("first_gap", self.first_gap)?;
        size2("size", self.size)?;
        finite2("center", self.center)
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::gaps(
            self.size,
            self.center,
            self.first_gap,
            self.width,
            self.spacing,
            self.depth,
            self.cell,
        )
        .map_err(BuildError::Grid)
    }
}

/// A seeded sum of random sinusoids.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rough {
    pub peak_to_peak: f64,
    pub wavelength_min: f64,
    pub wavelength_max: f64,
    #[serde(default = "Rough::waves")]
    pub waves: usize,
    #[serde(default)]
    pub seed: u32,
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl Rough {
    fn waves() -> usize {
        16
    }
}

impl HeightSource for Rough {
    fn validate(&self) -> Result<(), FieldError> {
        positive("peak_to_peak", self.peak_to_peak)?;
        positive("wavelength_min", self.wavelength_min)?;
        positive("wavelength_max", self.wavelength_max)?;
        if self.wavelength_max < self.wavelength_min {
            return Err((
                "wavelength_max",
                format!(
                    "expected ≥ wavelength_min ({}), got {}",
                    self.wavelength_min, self.wavelength_max
                ),
            ));
        }
        if !(1..=4096).contains(&self.waves) {
            return Err((
                "waves",
                format!("expected 1 to 4096 waves, got {}", self.waves),
            ));
        }
        size2("size", self.size)?;
        finite2("center", self.center)?;
        cell_fits(self.size, self.cell)?;
        // each sample sums every wave: bound the work before it starts
        let samples = self.size.map(|s| (s / self.cell).round() + 1.0);
        let work = self.waves as f64 * samples[0] * samples[1];
        if work > crate::limits::TERRAIN_WORK {
            return Err((
                "waves",
                format!(
                    "{} waves on {}×{} samples are {} wave-samples to sum, more than the {} hexsim generates (about a minute); use fewer waves or a larger cell",
                    self.waves,
                    samples[1],
                    samples[0],
                    crate::limits::num(work),
                    crate::limits::num(crate::limits::TERRAIN_WORK)
                ),
            ));
        }
        Ok(())
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::rough(
            self.size,
            self.center,
            self.peak_to_peak,
            self.wavelength_min,
            self.wavelength_max,
            self.waves,
            self.seed,
            self.cell,
        )
        .map_err(BuildError::Grid)
    }

    fn seed(&self) -> Option<u32> {
        Some(self.seed)
    }

    fn seed_mut(&mut self) -> Option<&mut u32> {
        Some(&mut self.seed)
    }
}

/// amplitude·sin(2πx/λ)·sin(2πy/λ).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sine {
    pub amplitude: f64,
    pub wavelength: f64,
    pub size: [f64; 2],
    #[serde(default = "zero2")]
    pub center: [f64; 2],
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl HeightSource for Sine {
    fn validate(&self) -> Result<(), FieldError> {
        finite("amplitude", self.amplitude)?;
        positive("wavelength", self.wavelength)?;
        size2("size", self.size)?;
        finite2("center", self.center)?;
        cell_fits(self.size, self.cell)
    }

    fn build(&self, _: &Path) -> Result<HeightGrid, BuildError> {
        generate::sine(
            self.size,
            self.center,
            self.amplitude,
            self.wavelength,
            self.cell,
        )
        .map_err(BuildError::Grid)
    }
}

/// A CSV grid: row i → y, column j → x, spanning the given ranges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Csv {
    pub path: PathBuf,
    pub x_range: [f64; 2],
    pub y_range: [f64; 2],
}

impl HeightSource for Csv {
    fn validate(&self) -> Result<(), FieldError> {
        range("x_range", self.x_range)?;
        range("y_range", self.y_range)
    }

    fn build(&self, base: &Path) -> Result<HeightGrid, BuildError> {
        let data = |e| BuildError::Data(self.path.clone(), e);
        let (rows, cols, heights) = io::read_csv(&base.join(&self.path)).map_err(data)?;
        HeightGrid::new(rows, cols, self.x_range, self.y_range, heights).map_err(|e| data(e.into()))
    }

    fn data_file(&self) -> Option<&Path> {
        Some(&self.path)
    }
}

/// A grayscale PNG: height = offset + scale·v/v_max; image top = largest y.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Png {
    pub path: PathBuf,
    pub x_range: [f64; 2],
    pub y_range: [f64; 2],
    pub height_scale: f64,
    #[serde(default)]
    pub height_offset: f64,
}

impl HeightSource for Png {
    fn validate(&self) -> Result<(), FieldError> {
        range("x_range", self.x_range)?;
        range("y_range", self.y_range)?;
        finite("height_scale", self.height_scale)?;
        finite("height_offset", self.height_offset)
    }

    fn build(&self, base: &Path) -> Result<HeightGrid, BuildError> {
        let data = |e| BuildError::Data(self.path.clone(), e);
        let (rows, cols, heights) = io::read_png(
            &base.join(&self.path),
            self.height_scale,
            self.height_offset,
        )
        .map_err(data)?;
        HeightGrid::new(rows, cols, self.x_range, self.y_range, heights).map_err(|e| data(e.into()))
    }

    fn data_file(&self) -> Option<&Path> {
        Some(&self.path)
    }
}

/// An STL surface rasterised to a grid with `cell` spacing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stl {
    pub path: PathBuf,
    #[serde(default = "cell_1cm")]
    pub cell: f64,
}

impl HeightSource for Stl {
    fn validate(&self) -> Result<(), FieldError> {
        positive("cell", self.cell)
    }

    fn build(&self, base: &Path) -> Result<HeightGrid, BuildError> {
        io::read_stl(&base.join(&self.path), self.cell)
            .map_err(|e| BuildError::Data(self.path.clone(), e))
    }

    fn data_file(&self) -> Option<&Path> {
        Some(&self.path)
    }
}
