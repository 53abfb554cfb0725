//! Terrain files (TOML): a generator with its parameters, or a height file to read.
//!
//! ```toml
//! description = "the paper's natural ground"
//! interpolation = "bicubic"      # or "bilinear"
//! [source]
//! kind = "natural"               # natural | bell | flat | slope | steps | rough | sine | csv | png | stl
//! seed = 5489
//! size = [4.0, 4.0]
//! peak_to_peak = 0.04
//! ```
//! Paths inside a terrain file are relative to the file.

use super::generate;
use super::grid::{GridError, HeightGrid, Interpolation};
use super::io::{self, HeightFileError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainSpec {
    #[serde(default)]
    pub description: String,
    #[serde(default)]
    pub interpolation: Interpolation,
    pub source: Source,
}

fn zero2() -> [f64; 2] {
    [0.0, 0.0]
}
fn natural_size() -> [f64; 2] {
    [4.0, 4.0]
}
fn natural_samples() -> usize {
    100
}
fn paper_seed() -> u32 {
    5489
}
fn hexapod_ptp() -> f64 {
    0.04
}
fn bell_half_width() -> f64 {
    3.0
}
fn bell_samples() -> usize {
    241
}
fn one() -> f64 {
    1.0
}
fn cell_1cm() -> f64 {
    0.01
}
fn default_flat_size() -> [f64; 2] {
    [20.0, 20.0]
}

/// Where the heights come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Source {
    /// The paper's fractal terrain (eq. 7); seed 5489 is MATLAB's `rng default`.
    Natural {
        #[serde(default = "paper_seed")]
        seed: u32,
        #[serde(default = "natural_samples")]
        samples: usize,
        #[serde(default = "natural_size")]
        size: [f64; 2],
        #[serde(default = "zero2")]
        center: [f64; 2],
        #[serde(default = "hexapod_ptp")]
        peak_to_peak: f64,
    },
    /// The paper's inverted bell (eq. 8), −depth·exp(−(x²+y²)/2σ²).
    Bell {
        #[serde(default = "bell_half_width")]
        half_width: f64,
        #[serde(default = "bell_samples")]
        samples: usize,
        #[serde(default = "one")]
        depth: f64,
        #[serde(default = "one")]
        sigma: f64,
    },
    Flat {
        #[serde(default = "default_flat_size")]
        size: [f64; 2],
        #[serde(default = "zero2")]
        center: [f64; 2],
        #[serde(default)]
        height: f64,
    },
    /// A plane rising at `angle_deg` towards the azimuth `ascent_deg` (0 = +x).
    Slope {
        angle_deg: f64,
        #[serde(default)]
        ascent_deg: f64,
        #[serde(default = "default_flat_size")]
        size: [f64; 2],
        #[serde(default = "zero2")]
        center: [f64; 2],
    },
    /// Stairs along +x.
    Steps {
        step_height: f64,
        step_length: f64,
        #[serde(default)]
        first_step: f64,
        #[serde(default = "default_flat_size")]
        size: [f64; 2],
        #[serde(default = "zero2")]
        center: [f64; 2],
        #[serde(default = "cell_1cm")]
        cell: f64,
    },
    /// A seeded sum of random sinusoids.
    Rough {
        peak_to_peak: f64,
        wavelength_min: f64,
        wavelength_max: f64,
        #[serde(default = "sixteen")]
        waves: usize,
        #[serde(default)]
        seed: u32,
        size: [f64; 2],
        #[serde(default = "zero2")]
        center: [f64; 2],
        #[serde(default = "cell_1cm")]
        cell: f64,
    },
    /// amplitude·sin(2πx/λ)·sin(2πy/λ).
    Sine {
        amplitude: f64,
        wavelength: f64,
        size: [f64; 2],
        #[serde(default = "zero2")]
        center: [f64; 2],
        #[serde(default = "cell_1cm")]
        cell: f64,
    },
    /// A CSV grid: row i → y, column j → x, spanning the given ranges.
    Csv {
        path: PathBuf,
        x_range: [f64; 2],
        y_range: [f64; 2],
    },
    /// A grayscale PNG: height = offset + scale·v/v_max; image top = largest y.
    Png {
        path: PathBuf,
        x_range: [f64; 2],
        y_range: [f64; 2],
        height_scale: f64,
        #[serde(default)]
        height_offset: f64,
    },
    /// An STL surface rasterised to a grid with `cell` spacing.
    Stl {
        path: PathBuf,
        #[serde(default = "cell_1cm")]
        cell: f64,
    },
}

fn sixteen() -> usize {
    16
}

/// A terrain file that could not be turned into a terrain; names the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum TerrainError {
    #[error("{file}: cannot read the terrain file: {cause}")]
    Read {
        file: PathBuf,
        cause: std::io::Error,
    },
    #[error("{file}: {message}")]
    Parse { file: PathBuf, message: String },
    #[error("{file}: field `{field}`: {expected}")]
    Field {
        file: PathBuf,
        field: &'static str,
        expected: String,
    },
    #[error("{file}: height file {data}: {cause}")]
    Data {
        file: PathBuf,
        data: PathBuf,
        cause: HeightFileError,
    },
    #[error("{file}: {cause}")]
    Grid { file: PathBuf, cause: GridError },
}

impl TerrainSpec {
    /// Reads and parses a terrain file (without building the grid).
    pub fn from_file(path: &Path) -> Result<Self, TerrainError> {
        let text = std::fs::read_to_string(path).map_err(|cause| TerrainError::Read {
            file: path.to_path_buf(),
            cause,
        })?;
        Self::from_toml(&text, path)
    }

    /// Parses terrain TOML; `origin` names the file in errors.
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self, TerrainError> {
        toml::from_str(text).map_err(|e| TerrainError::Parse {
            file: origin.to_path_buf(),
            message: e.to_string().trim_end().to_string(),
        })
    }

    /// Replaces the generator's seed, for generators that have one (natural, rough); others ignore it.
    pub fn with_seed(mut self, new_seed: u32) -> Self {
        match &mut self.source {
            Source::Natural { seed, .. } | Source::Rough { seed, .. } => *seed = new_seed,
            _ => {}
        }
        self
    }

    /// Builds the height grid. `origin` is the file the spec came from: relative data paths resolve
    /// against its folder, and errors name it.
    pub fn build(&self, origin: &Path) -> Result<HeightGrid, TerrainError> {
        self.validate(origin)?;
        let base = origin.parent().unwrap_or(Path::new("."));
        let grid_err = |cause| TerrainError::Grid {
            file: origin.to_path_buf(),
            cause,
        };
        let data_err = |data: &Path, cause| TerrainError::Data {
            file: origin.to_path_buf(),
            data: base.join(data),
            cause,
        };
        let grid = match self.source {
            Source::Natural {
                seed,
                samples,
                size,
                center,
                peak_to_peak,
            } => generate::natural(seed, samples, size, center, peak_to_peak).map_err(grid_err)?,
            Source::Bell {
                half_width,
                samples,
                depth,
                sigma,
            } => generate::bell(half_width, samples, depth, sigma).map_err(grid_err)?,
            Source::Flat {
                size,
                center,
                height,
            } => generate::flat(size, center, height).map_err(grid_err)?,
            Source::Slope {
                angle_deg,
                ascent_deg,
                size,
                center,
            } => generate::slope(
                size,
                center,
                angle_deg.to_radians(),
                ascent_deg.to_radians(),
            )
            .map_err(grid_err)?,
            Source::Steps {
                step_height,
                step_length,
                first_step,
                size,
                center,
                cell,
            } => generate::steps(size, center, first_step, step_length, step_height, cell)
                .map_err(grid_err)?,
            Source::Rough {
                peak_to_peak,
                wavelength_min,
                wavelength_max,
                waves,
                seed,
                size,
                center,
                cell,
            } => generate::rough(
                size,
                center,
                peak_to_peak,
                wavelength_min,
                wavelength_max,
                waves,
                seed,
                cell,
            )
            .map_err(grid_err)?,
            Source::Sine {
                amplitude,
                wavelength,
                size,
                center,
                cell,
            } => generate::sine(size, center, amplitude, wavelength, cell).map_err(grid_err)?,
            Source::Csv {
                ref path,
                x_range,
                y_range,
            } => {
                let (rows, cols, heights) =
                    io::read_csv(&base.join(path)).map_err(|e| data_err(path, e))?;
                HeightGrid::new(rows, cols, x_range, y_range, heights)
                    .map_err(|e| data_err(path, e.into()))?
            }
            Source::Png {
                ref path,
                x_range,
                y_range,
                height_scale,
                height_offset,
            } => {
                let (rows, cols, heights) =
                    io::read_png(&base.join(path), height_scale, height_offset)
                        .map_err(|e| data_err(path, e))?;
                HeightGrid::new(rows, cols, x_range, y_range, heights)
                    .map_err(|e| data_err(path, e.into()))?
            }
            Source::Stl { ref path, cell } => {
                io::read_stl(&base.join(path), cell).map_err(|e| data_err(path, e))?
            }
        };
        Ok(grid.with_interpolation(self.interpolation))
    }

    /// Checks every parameter's range, naming the field that is wrong.
    fn validate(&self, origin: &Path) -> Result<(), TerrainError> {
        let fail = |field: &'static str, expected: String| TerrainError::Field {
            file: origin.to_path_buf(),
            field,
            expected,
        };
        let positive = |field: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(fail(
                    field,
                    format!("expected a finite number > 0, got {v}"),
                ))
            }
        };
        let finite = |field: &'static str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(fail(field, format!("expected a finite number, got {v}")))
            }
        };
        let size2 = |field: &'static str, s: [f64; 2]| {
            if s.iter().all(|v| v.is_finite() && *v > 0.0) {
                Ok(())
            } else {
                Err(fail(
                    field,
                    format!("expected two finite sizes > 0, got {s:?}"),
                ))
            }
        };
        let finite2 = |field: &'static str, s: [f64; 2]| {
            if s.iter().all(|v| v.is_finite()) {
                Ok(())
            } else {
                Err(fail(
                    field,
                    format!("expected two finite numbers, got {s:?}"),
                ))
            }
        };
        let range = |field: &'static str, r: [f64; 2]| {
            if r.iter().all(|v| v.is_finite()) && r[1] > r[0] {
                Ok(())
            } else {
                Err(fail(
                    field,
                    format!("expected [min, max] with min < max, got {r:?}"),
                ))
            }
        };
        let samples = |field: &'static str, n: usize| {
            if (2..=8192).contains(&n) {
                Ok(())
            } else {
                Err(fail(
                    field,
                    format!("expected 2 to 8192 samples per side, got {n}"),
                ))
            }
        };
        match self.source {
            Source::Natural {
                samples: n,
                size,
                center,
                peak_to_peak,
                ..
            } => {
                samples("source.samples", n)?;
                size2("source.size", size)?;
                finite2("source.center", center)?;
                if !(peak_to_peak.is_finite() && peak_to_peak >= 0.0) {
                    return Err(fail(
                        "source.peak_to_peak",
                        format!("expected a finite number ≥ 0, got {peak_to_peak}"),
                    ));
                }
            }
            Source::Bell {
                half_width,
                samples: n,
                depth,
                sigma,
            } => {
                positive("source.half_width", half_width)?;
                samples("source.samples", n)?;
                finite("source.depth", depth)?;
                positive("source.sigma", sigma)?;
            }
            Source::Flat {
                size,
                center,
                height,
            } => {
                size2("source.size", size)?;
                finite2("source.center", center)?;
                finite("source.height", height)?;
            }
            Source::Slope {
                angle_deg,
                ascent_deg,
                size,
                center,
            } => {
                if !(angle_deg.is_finite() && angle_deg.abs() < 89.0) {
                    return Err(fail(
                        "source.angle_deg",
                        format!("expected an angle within ±89°, got {angle_deg}"),
                    ));
                }
                finite("source.ascent_deg", ascent_deg)?;
                size2("source.size", size)?;
                finite2("source.center", center)?;
            }
            Source::Steps {
                step_height,
                step_length,
                first_step,
                size,
                center,
                cell,
            } => {
                finite("source.step_height", step_height)?;
                positive("source.step_length", step_length)?;
                finite("source.first_step", first_step)?;
                size2("source.size", size)?;
                finite2("source.center", center)?;
                positive("source.cell", cell)?;
            }
            Source::Rough {
                peak_to_peak,
                wavelength_min,
                wavelength_max,
                waves,
                size,
                center,
                cell,
                ..
            } => {
                positive("source.peak_to_peak", peak_to_peak)?;
                positive("source.wavelength_min", wavelength_min)?;
                positive("source.wavelength_max", wavelength_max)?;
                if wavelength_max < wavelength_min {
                    return Err(fail(
                        "source.wavelength_max",
                        format!(
                            "expected ≥ wavelength_min ({wavelength_min}), got {wavelength_max}"
                        ),
                    ));
                }
                if !(1..=4096).contains(&waves) {
                    return Err(fail(
                        "source.waves",
                        format!("expected 1 to 4096 waves, got {waves}"),
                    ));
                }
                size2("source.size", size)?;
                finite2("source.center", center)?;
                positive("source.cell", cell)?;
            }
            Source::Sine {
                amplitude,
                wavelength,
                size,
                center,
                cell,
            } => {
                finite("source.amplitude", amplitude)?;
                positive("source.wavelength", wavelength)?;
                size2("source.size", size)?;
                finite2("source.center", center)?;
                positive("source.cell", cell)?;
            }
            Source::Csv {
                x_range, y_range, ..
            } => {
                range("source.x_range", x_range)?;
                range("source.y_range", y_range)?;
            }
            Source::Png {
                x_range,
                y_range,
                height_scale,
                height_offset,
                ..
            } => {
                range("source.x_range", x_range)?;
                range("source.y_range", y_range)?;
                finite("source.height_scale", height_scale)?;
                finite("source.height_offset", height_offset)?;
            }
            Source::Stl { cell, .. } => positive("source.cell", cell)?,
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<TerrainSpec, TerrainError> {
        TerrainSpec::from_toml(text, Path::new("t.toml"))
    }

    #[test]
    fn defaults_make_the_papers_natural_terrain() {
        let spec = parse("[source]\nkind = \"natural\"\n").unwrap();
        let g = spec.build(Path::new("t.toml")).unwrap();
        assert_eq!((g.rows(), g.cols()), (100, 100));
        assert_eq!(g.x_range(), [-2.0, 2.0]);
    }

    #[test]
    fn unknown_fields_and_bad_values_name_the_field() {
        let e = parse("[source]\nkind = \"bell\"\nhalf_widht = 3\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("t.toml") && e.contains("half_widht"), "{e}");
        let e =
            parse("[source]\nkind = \"steps\"\nstep_height = 0.1\nstep_length = 0.3\ncell = -1\n")
                .unwrap()
                .build(Path::new("t.toml"))
                .unwrap_err()
                .to_string();
        assert!(e.contains("source.cell") && e.contains("> 0"), "{e}");
    }
}
