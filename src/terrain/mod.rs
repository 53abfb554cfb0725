//! Terrain: a height grid, its interpolated surface and normals, the paper's orientation method,
//! generators, and height files (CSV, PNG, STL).

mod cliff;
mod generate;
mod grid;
pub mod io;
mod orientation;
pub mod source;
mod spec;

pub use cliff::{CLIFF_RATIO, CLIFF_SLOPE, Wall};
pub use generate::{
    MatlabRand, bell, discrete_obstacles, flat, gaps, natural, pyramid_stairs, rough, sine, slope,
    stairs, stepping_stones, steps,
};
pub use grid::{GridError, HeightGrid, Interpolation, MAX_SAMPLES, SurfacePoint};
pub use orientation::{FittedPlane, GroundFrame, Orientation};
pub use source::Source;
pub use spec::{FARTHEST, TerrainError, TerrainSpec};

/// Loads a terrain file and builds its grid.
pub fn load(path: &std::path::Path) -> Result<HeightGrid, TerrainError> {
    TerrainSpec::from_file(path)?.build(path)
}
