//! Height files: a CSV grid, a grayscale PNG, an STL surface, each read relative to the terrain
//! file.

use super::*;

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
