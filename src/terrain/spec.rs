//! Terrain files (TOML): a generator with its parameters, or a height file to read.
//!
//! ```toml
//! description = "the paper's natural ground"
//! interpolation = "bicubic"      # or "bilinear"
//! [source]
//! kind = "natural"               # natural | bell | flat | slope | steps | stairs | pyramid_stairs |
//!                                # discrete_obstacles | stepping_stones | gaps | rough | sine | csv | png | stl
//! seed = 5489
//! size = [4.0, 4.0]
//! peak_to_peak = 0.04
//! ```
//! Paths inside a terrain file are relative to the file.

use super::grid::{GridError, HeightGrid, Interpolation};
use super::io::HeightFileError;
use super::source::{BuildError, Source};
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
    #[error("{file}: field `source.{field}`: {expected}")]
    Field {
        file: PathBuf,
        /// Within `[source]`.
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
    #[error(
        "{file}: a {kind} height file, not a terrain file (TOML): a {kind} file holds no extent, so write a terrain file beside it that gives one (docs/terrains.md) and name that, e.g. {stem}.toml:\n{example}"
    )]
    HeightFile {
        file: PathBuf,
        kind: &'static str,
        stem: String,
        example: String,
    },
}

impl TerrainSpec {
    /// Reads and parses a terrain file (without building the grid). A height file given instead
    /// is wrapped when its kind's other fields have defaults (STL), and explained, with the
    /// terrain file to write, when it needs an extent only its author knows (CSV, PNG).
    pub fn from_file(path: &Path) -> Result<Self, TerrainError> {
        if let Some(spec) = height_file(path)? {
            return Ok(spec);
        }
        let text = crate::limits::read_to_string(path, crate::limits::TEXT_FILE_BYTES).map_err(
            |cause| TerrainError::Read {
                file: path.to_path_buf(),
                cause,
            },
        )?;
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
        if let Some(seed) = self.source.get_mut().seed_mut() {
            *seed = new_seed;
        }
        self
    }

    /// The generator's seed, if it has one.
    pub fn seed(&self) -> Option<u32> {
        self.source.get().seed()
    }

    /// Builds the height grid. `origin` is the file the spec came from: relative data paths resolve
    /// against its folder, and errors name it.
    pub fn build(&self, origin: &Path) -> Result<HeightGrid, TerrainError> {
        let source = self.source.get();
        source
            .validate()
            .map_err(|(field, expected)| TerrainError::Field {
                file: origin.to_path_buf(),
                field,
                expected,
            })?;
        let base = origin.parent().unwrap_or(Path::new("."));
        let grid = source.build(base).map_err(|e| match e {
            BuildError::Grid(cause) => TerrainError::Grid {
                file: origin.to_path_buf(),
                cause,
            },
            BuildError::Data(data, cause) => TerrainError::Data {
                file: origin.to_path_buf(),
                data: base.join(data),
                cause,
            },
        })?;
        check_near_origin(&grid).map_err(|(field, expected)| match field {
            Some(field) => TerrainError::Field {
                file: origin.to_path_buf(),
                field,
                expected,
            },
            None => TerrainError::Parse {
                file: origin.to_path_buf(),
                message: expected,
            },
        })?;
        Ok(grid.with_interpolation(self.interpolation))
    }
}

/// The spec of a height file given where a terrain file is expected (by its extension), or why it
/// needs one; `None` for any other file.
fn height_file(path: &Path) -> Result<Option<TerrainSpec>, TerrainError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let Some(name) = path.file_name().map(PathBuf::from) else {
        return Ok(None);
    };
    let quoted = name
        .display()
        .to_string()
        .replace('\\', "\\\\")
        .replace('"', "\\\"");
    let (kind, fields) = match extension.as_deref() {
        // `cell` has its default; the mesh gives the extent
        Some("stl") => {
            let text = format!("[source]\nkind = \"stl\"\npath = \"{quoted}\"\n");
            return TerrainSpec::from_toml(&text, path).map(Some);
        }
        Some("csv") => ("csv", ""),
        Some("png") => ("png", "\nheight_scale = 0.1    # m at the brightest value"),
        _ => return Ok(None),
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let example = format!(
        "[source]\nkind = \"{kind}\"\npath = \"{quoted}\"\nx_range = [-2.0, 2.0]    # m, first to last column\ny_range = [-2.0, 2.0]    # m, first to last row{fields}"
    );
    Err(TerrainError::HeightFile {
        file: path.to_path_buf(),
        kind,
        stem,
        example,
    })
}

/// How far from the world's origin a terrain may reach (m). rapier computes in f32, whose
/// resolution at a distance d is d·2⁻²³: at 100 m 12 µm, 3 % of hex18's 0.41 mm static sink; a
/// terrain at map coordinates (a DEM at 350 m, UTM at 10⁵ m) would make the contact noise.
pub const FARTHEST: f64 = 100.0;

/// Refuses a grid reaching farther than [`FARTHEST`] from the origin, saying why and what to do.
/// The field to blame is `center` when the grid's extent is far, none (the heights themselves:
/// a height file's values, a generator's height) when only its heights are.
fn check_near_origin(
    grid: &crate::terrain::HeightGrid,
) -> Result<(), (Option<&'static str>, String)> {
    use crate::limits::num;
    let [x0, x1] = grid.x_range();
    let [y0, y1] = grid.y_range();
    let (low, high) = grid.height_bounds();
    let farthest = |values: &[f64]| values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (extent, heights) = (farthest(&[x0, x1, y0, y1]), farthest(&[low, high]));
    let reach = extent.max(heights);
    if reach <= FARTHEST {
        return Ok(());
    }
    let why = format!(
        "the physics computes positions in f32, which at {} m resolves {:.1e} m against a foot's sub-millimetre sink",
        num(reach.round()),
        reach * f64::powi(2.0, -23)
    );
    Err(if extent > FARTHEST {
        (
            Some("center"),
            format!(
                "the terrain reaches {} m from the origin (x {}..{}, y {}..{} m); {why}: place the terrain within {FARTHEST} m of the origin (its `center`)",
                num(extent.round()),
                num(x0),
                num(x1),
                num(y0),
                num(y1)
            ),
        )
    } else {
        (
            None,
            format!(
                "the terrain's heights reach {}..{} m; {why}: give heights within {FARTHEST} m of the origin (relative to a datum near the terrain: a height file's values, its `height_offset`, a generator's height)",
                num(low),
                num(high)
            ),
        )
    })
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

    /// Every terrain file builds; those meant to have walls have them, and no smooth one is read
    /// with any (so its surface is the interpolation's, as before walls existed).
    #[test]
    fn the_terrain_files_have_walls_where_meant() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains");
        let walled = [
            "steps",
            "steps_down",
            "stairs",
            "pyramid_stairs",
            "discrete_obstacles",
            "stepping_stones",
            "gaps",
        ];
        let mut seen = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let grid = crate::terrain::load(&path).unwrap();
            let name = path.file_stem().unwrap().to_string_lossy().to_string();
            let meant = walled.contains(&name.as_str());
            assert_eq!(grid.has_cliffs(), meant, "{name}");
            seen += meant as usize;
        }
        assert_eq!(seen, walled.len());
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
