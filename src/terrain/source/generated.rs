//! The generators: heights made from parameters (and a seed, for the random ones).

use super::*;

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
        non_negative("peak_to_peak", self.peak_to_peak)?;
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
        cells2("step_length", self.step_length, self.cell)?;
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
        cell_fits(self.size, self.cell)?;
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
        cell_fits(self.size, self.cell)?;
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
        cell_fits(self.size, self.cell)?;
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
        cell_fits(self.size, self.cell)?;
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
        cell_fits(self.size, self.cell)?;
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
