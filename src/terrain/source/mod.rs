//! Where a terrain's heights come from: one parameter struct per generator (generated.rs) or
//! height file (files.rs), each with its defaults, its checks and its build, so a new source is
//! one struct there and one line in `sources!` here. The checks they share are here.

use super::generate;
use super::grid::{GridError, HeightGrid};
use super::io::{self, HeightFileError};
use crate::limits::{Range, check_number};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

mod files;
mod generated;
pub use files::{Csv, Png, Stl};
pub use generated::{
    Bell, DiscreteObstacles, Flat, Gaps, Natural, PyramidStairs, Rough, Sine, Slope, Stairs,
    SteppingStones, Steps,
};

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

/// The sources, each as its `kind = "..."` name and its struct: [`Source`] with one variant
/// each, written tagged with that name and read by [`Source::deserialize`]; the one list a new
/// source is added to.
macro_rules! sources {
    ($($kind:literal => $variant:ident),* $(,)?) => {
        /// Where the heights come from (`kind = "..."` in `[source]`).
        #[derive(Debug, Clone, PartialEq, Serialize)]
        #[serde(tag = "kind")]
        pub enum Source {
            $(#[serde(rename = $kind)] $variant($variant),)*
        }

        /// The kinds, as `kind = "..."` names them.
        const KINDS: &[&str] = &[$($kind),*];

        /// The source of `kind` read from its other `fields`: an error names the field.
        fn read_kind(kind: &str, fields: toml::Value) -> Result<Source, String> {
            match kind {
                $($kind => fields.try_into().map(Source::$variant).map_err(|e| field_error(&e)),)*
                other => Err(format!(
                    "field `source.kind`: expected one of {}, got {other:?}",
                    KINDS.join(", ")
                )),
            }
        }

        impl Source {
            pub fn get(&self) -> &dyn HeightSource {
                match self {
                    $(Source::$variant(s) => s,)*
                }
            }

            pub fn get_mut(&mut self) -> &mut dyn HeightSource {
                match self {
                    $(Source::$variant(s) => s,)*
                }
            }
        }
    };
}

sources! {
    "natural" => Natural,
    "bell" => Bell,
    "flat" => Flat,
    "slope" => Slope,
    "steps" => Steps,
    "stairs" => Stairs,
    "pyramid_stairs" => PyramidStairs,
    "discrete_obstacles" => DiscreteObstacles,
    "stepping_stones" => SteppingStones,
    "gaps" => Gaps,
    "rough" => Rough,
    "sine" => Sine,
    "csv" => Csv,
    "png" => Png,
    "stl" => Stl,
}

/// toml's "invalid value: …\nin `seed`" as "field `source.seed`: invalid value: …".
fn field_error(e: &toml::de::Error) -> String {
    let message = e.to_string();
    let message = message.trim_end();
    match message.rsplit_once("\nin `") {
        Some((what, field)) => {
            let field = field.trim_end_matches('`');
            format!("field `source.{field}`: {what}")
        }
        None => format!("in [source]: {message}"),
    }
}

/// Read through the kind's own struct, not serde's tagged enum: that buffers the table and its
/// error names neither the field nor what it holds ("expected u32" at `[source]`).
impl<'de> Deserialize<'de> for Source {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut table = toml::Table::deserialize(d)?;
        let kind = match table.remove("kind") {
            Some(toml::Value::String(kind)) => kind,
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "field `source.kind`: expected a string, one of {}, got {other}",
                    KINDS.join(", ")
                )));
            }
            None => {
                return Err(D::Error::custom(format!(
                    "field `source.kind`: missing; expected one of {}",
                    KINDS.join(", ")
                )));
            }
        };
        read_kind(&kind, toml::Value::Table(table)).map_err(D::Error::custom)
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
    check_number(v, Range::Positive, "").map_err(|e| (field, e))
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
    check_number(v, Range::Any, "").map_err(|e| (field, e))
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
    check_number(v, Range::NonNegative, "").map_err(|e| (field, e))
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
