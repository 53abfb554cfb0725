//! `hexsim terrain`: inspect and export terrains.

use anyhow::Result;
use clap::Subcommand;
use hexsim::record::output::write_streamed;
use hexsim::scenario::builtin;
use hexsim::terrain::{self, TerrainSpec};
use std::path::{Path, PathBuf};

#[derive(Subcommand)]
pub enum TerrainCommand {
    /// Export a terrain file's surface as STL (mesh), PNG (16-bit heights) and/or CSV.
    Export {
        /// Terrain file (TOML), or a built-in terrain's name (`natural`, `flat`, …), as
        /// `hexsim run --terrain` takes it.
        terrain: PathBuf,
        #[arg(long)]
        stl: Option<PathBuf>,
        #[arg(long)]
        png: Option<PathBuf>,
        #[arg(long)]
        csv: Option<PathBuf>,
    },
    /// Print a terrain's size, resolution and height range.
    Info {
        /// Terrain file (TOML), or a built-in terrain's name (`natural`, `flat`, …), as
        /// `hexsim run --terrain` takes it.
        terrain: PathBuf,
    },
}

/// The terrain `path` names: its file, or the built-in terrain of that bare name when no such
/// file is there (as `--terrain` reads it); with the path its relative files resolve against.
fn spec_of(path: &Path) -> Result<(TerrainSpec, PathBuf)> {
    Ok(match builtin::named(builtin::TERRAINS, path, path) {
        Some(b) => (
            TerrainSpec::from_toml(b.text, Path::new(b.path))?,
            PathBuf::from(b.path),
        ),
        None => (
            TerrainSpec::from_file(path)
                .map_err(builtin::with_hint(path, "terrains", builtin::TERRAINS))
                .map_err(anyhow::Error::msg)?,
            path.to_path_buf(),
        ),
    })
}

pub fn terrain_command(command: TerrainCommand) -> Result<()> {
    match command {
        TerrainCommand::Export {
            terrain,
            stl,
            png,
            csv,
        } => {
            if stl.is_none() && png.is_none() && csv.is_none() {
                anyhow::bail!("nothing to export: give --stl FILE, --png FILE and/or --csv FILE");
            }
            // no export may overwrite the terrain file or its height file, or another export
            let (spec, origin) = spec_of(&terrain)?;
            let mut inputs = vec![("terrain file", terrain.clone())];
            if let Some(data) = spec.source.get().data_file() {
                let folder = terrain.parent().unwrap_or(std::path::Path::new(""));
                inputs.push(("terrain's height file", folder.join(data)));
            }
            let outputs = [("--stl", &stl), ("--png", &png), ("--csv", &csv)];
            hexsim::record::output::check_distinct(
                outputs
                    .iter()
                    .filter_map(|(flag, path)| Some((*flag, path.as_deref()?))),
                inputs.iter().map(|(what, path)| (*what, path.as_path())),
            )?;
            let grid = spec.build(&origin)?;
            if let Some(path) = stl {
                write_streamed(&path, |out| Ok(terrain::io::stl_to(&grid, out)?))?;
                out!("wrote {}", path.display());
            }
            if let Some(path) = png {
                let mut read_back = (0.0, 0.0);
                write_streamed(&path, |out| {
                    read_back = terrain::io::png_to(&grid, out)?;
                    Ok(())
                })?;
                let (offset, scale) = read_back;
                let [x0, x1] = grid.x_range();
                let [y0, y1] = grid.y_range();
                out!(
                    "wrote {} — to read it back: kind = \"png\", height_scale = {scale}, height_offset = {offset}, x_range = [{x0}, {x1}], y_range = [{y0}, {y1}]",
                    path.display()
                );
            }
            if let Some(path) = csv {
                write_streamed(&path, |out| Ok(terrain::io::csv_to(&grid, out)?))?;
                out!("wrote {}", path.display());
            }
            Ok(())
        }
        TerrainCommand::Info { terrain } => {
            let (spec, origin) = spec_of(&terrain)?;
            let grid = spec.build(&origin)?;
            let (lo, hi) = grid.height_bounds();
            let (dx, dy) = grid.spacing();
            out!("{}", terrain.display());
            out!(
                "  {} × {} samples, cell {dx:.4} × {dy:.4} m",
                grid.cols(),
                grid.rows()
            );
            out!("  x ∈ {:?}, y ∈ {:?} m", grid.x_range(), grid.y_range());
            out!(
                "  height ∈ [{lo:.4}, {hi:.4}] m ({:.4} m peak to peak)",
                hi - lo
            );
            out!("  interpolation {:?}", grid.interpolation());
            Ok(())
        }
    }
}
