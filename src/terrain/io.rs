//! Height files in and out: CSV grids, 16-bit grayscale PNG, STL meshes (rasterised to a grid).

use super::grid::{HeightGrid, MAX_SAMPLES};
use std::path::Path;

/// Why a height file could not be read or written. Messages name what was expected; the caller adds
/// the file's path.
#[derive(Debug, thiserror::Error)]
pub enum HeightFileError {
    #[error("cannot read: {0}")]
    Io(std::io::Error),
    #[error("cannot write: {0}")]
    Write(std::io::Error),
    #[error("line {line}: {message}")]
    Csv { line: u64, message: String },
    #[error("no heights: the file has no data rows")]
    Empty,
    #[error("line {line}, column {column}: `{text}` is not a number")]
    NotANumber {
        line: u64,
        column: usize,
        text: String,
    },
    #[error("line {line}, column {column}: height {value} is not finite")]
    NotFinite {
        line: u64,
        column: usize,
        value: f64,
    },
    #[error("line {line} has {got} values, expected {expected} like the first row (a ragged grid)")]
    Ragged {
        line: u64,
        got: usize,
        expected: usize,
    },
    #[error("not a PNG image: {0}")]
    Image(image::ImageError),
    #[error("the PNG is {0:?}, expected a grayscale image (8- or 16-bit, no colour)")]
    NotGrayscale(image::ColorType),
    #[error("not an STL mesh: {0}")]
    Stl(String),
    #[error("the STL mesh has no triangles")]
    EmptyMesh,
    #[error("the STL mesh is not a surface over the xy-plane: {0}")]
    NotAHeightField(String),
    #[error(transparent)]
    Grid(#[from] super::grid::GridError),
}

// Converted by hand rather than with `#[from]`: the messages already include the cause, which
// would otherwise be printed twice in an error chain.
impl From<std::io::Error> for HeightFileError {
    fn from(e: std::io::Error) -> Self {
        HeightFileError::Io(e)
    }
}

impl From<image::ImageError> for HeightFileError {
    fn from(e: image::ImageError) -> Self {
        HeightFileError::Image(e)
    }
}

/// Reads a CSV grid of heights: one row per line (row i → y), comma-separated, `#` lines are comments.
pub fn read_csv(path: &Path) -> Result<(usize, usize, Vec<f64>), HeightFileError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(crate::limits::Bounded::new(
            std::fs::File::open(path)?,
            crate::limits::DATA_FILE_BYTES,
            crate::limits::CSV_LINE_BYTES,
        ));
    let mut heights = Vec::new();
    let mut cols = 0;
    let mut rows = 0;
    for record in reader.records() {
        let record = record.map_err(|e| csv_error(e, rows as u64 + 1))?;
        let line = record.position().map_or(0, |p| p.line());
        if record.len() == 1 && record[0].is_empty() {
            continue; // blank line
        }
        if rows == 0 {
            cols = record.len();
        } else if record.len() != cols {
            return Err(HeightFileError::Ragged {
                line,
                got: record.len(),
                expected: cols,
            });
        }
        for (c, text) in record.iter().enumerate() {
            let value: f64 = text.parse().map_err(|_| HeightFileError::NotANumber {
                line,
                column: c + 1,
                text: text.to_string(),
            })?;
            if !value.is_finite() {
                return Err(HeightFileError::NotFinite {
                    line,
                    column: c + 1,
                    value,
                });
            }
            heights.push(value);
        }
        rows += 1;
        if heights.len() > MAX_SAMPLES {
            return Err(super::grid::GridError::TooLarge {
                rows: rows as f64,
                cols: cols as f64,
                max: MAX_SAMPLES,
            }
            .into());
        }
    }
    if rows == 0 {
        return Err(HeightFileError::Empty);
    }
    Ok((rows, cols, heights))
}

fn csv_error(e: csv::Error, fallback_line: u64) -> HeightFileError {
    let line = e.position().map_or(fallback_line, |p| p.line());
    match e.into_kind() {
        csv::ErrorKind::Io(io) => HeightFileError::Io(io),
        other => HeightFileError::Csv {
            line,
            message: format!("{other:?}"),
        },
    }
}

/// Writes a grid as CSV in the layout [`read_csv`] reads, with a comment line giving the extent.
pub fn csv_to(grid: &HeightGrid, out: &mut impl std::io::Write) -> std::io::Result<()> {
    let [x0, x1] = grid.x_range();
    let [y0, y1] = grid.y_range();
    writeln!(
        out,
        "# heights [m]; row i -> y in [{y0}, {y1}], column j -> x in [{x0}, {x1}]"
    )?;
    for i in 0..grid.rows() {
        for j in 0..grid.cols() {
            let separator = if j + 1 < grid.cols() { "," } else { "\n" };
            write!(out, "{}{separator}", grid.sample(i, j))?;
        }
    }
    Ok(())
}

/// [`csv_to`] a file (in place: the command line writes through a temporary name).
pub fn write_csv(grid: &HeightGrid, path: &Path) -> Result<(), HeightFileError> {
    let mut out =
        std::io::BufWriter::new(std::fs::File::create(path).map_err(HeightFileError::Write)?);
    csv_to(grid, &mut out)
        .and_then(|()| std::io::Write::flush(&mut out))
        .map_err(HeightFileError::Write)
}

/// Reads a grayscale PNG as heights `offset + scale · v / v_max` (v_max = 65535 for 16-bit, 255 for
/// 8-bit). Image row 0 is the *top* of the picture, i.e. the largest y, as in any map.
pub fn read_png(
    path: &Path,
    scale: f64,
    offset: f64,
) -> Result<(usize, usize, Vec<f64>), HeightFileError> {
    let reader = image::ImageReader::open(path)?.with_guessed_format()?;
    let (w, h) = reader.into_dimensions()?;
    if (w as u64) * (h as u64) > MAX_SAMPLES as u64 {
        return Err(super::grid::GridError::TooLarge {
            rows: h as f64,
            cols: w as f64,
            max: MAX_SAMPLES,
        }
        .into());
    }
    let image = image::ImageReader::open(path)?
        .with_guessed_format()?
        .decode()?;
    let (rows, cols) = (h as usize, w as usize);
    let values: Vec<f64> = match image.color() {
        image::ColorType::L16 => image
            .to_luma16()
            .into_raw()
            .into_iter()
            .map(|v| v as f64 / 65535.0)
            .collect(),
        image::ColorType::L8 => image
            .to_luma8()
            .into_raw()
            .into_iter()
            .map(|v| v as f64 / 255.0)
            .collect(),
        other => return Err(HeightFileError::NotGrayscale(other)),
    };
    let mut heights = vec![0.0; rows * cols];
    for (k, v) in values.into_iter().enumerate() {
        let (img_row, col) = (k / cols, k % cols);
        heights[(rows - 1 - img_row) * cols + col] = offset + scale * v;
    }
    Ok((rows, cols, heights))
}

/// Writes the grid as a 16-bit grayscale PNG spanning its height range; returns (offset, scale)
/// such that height = offset + scale · v / 65535, to be put in the terrain file that reads it back.
pub fn png_to(
    grid: &HeightGrid,
    out: &mut (impl std::io::Write + std::io::Seek),
) -> std::io::Result<(f64, f64)> {
    let (lo, hi) = grid.height_bounds();
    let scale = hi - lo;
    let (rows, cols) = (grid.rows(), grid.cols());
    let mut pixels = vec![0u16; rows * cols];
    for i in 0..rows {
        for j in 0..cols {
            let v = if scale > 0.0 {
                ((grid.sample(i, j) - lo) / scale * 65535.0).round()
            } else {
                0.0
            };
            pixels[(rows - 1 - i) * cols + j] = v as u16;
        }
    }
    let buffer =
        image::ImageBuffer::<image::Luma<u16>, _>::from_raw(cols as u32, rows as u32, pixels)
            .expect("buffer length is rows × cols by construction");
    buffer
        .write_to(out, image::ImageFormat::Png)
        .map_err(|e| match e {
            image::ImageError::IoError(io) => io,
            // encoding a 16-bit grayscale buffer of its own size cannot fail otherwise
            other => std::io::Error::other(other),
        })?;
    Ok((lo, scale))
}

/// The grid as a triangle mesh: vertices (x, y, z) row-major and two triangles per cell, wound
/// counter-clockwise seen from above (normals point up).
pub fn mesh(grid: &HeightGrid) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (rows, cols) = (grid.rows(), grid.cols());
    let vertices = (0..rows)
        .flat_map(|i| (0..cols).map(move |j| (i, j)))
        .map(|(i, j)| {
            [
                grid.x_at(j) as f32,
                grid.y_at(i) as f32,
                grid.sample(i, j) as f32,
            ]
        })
        .collect();
    let mut triangles = Vec::with_capacity(2 * (rows - 1) * (cols - 1));
    for i in 0..rows - 1 {
        for j in 0..cols - 1 {
            let a = (i * cols + j) as u32;
            let b = a + 1;
            let c = a + cols as u32;
            let d = c + 1;
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    (vertices, triangles)
}

/// Writes the grid's surface as a binary STL.
pub fn stl_to(grid: &HeightGrid, out: &mut impl std::io::Write) -> std::io::Result<()> {
    let (vertices, triangles) = mesh(grid);
    let stl_triangles = triangles.iter().map(|t| {
        let [a, b, c] = t.map(|k| vertices[k as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
            .sqrt()
            .max(f32::MIN_POSITIVE);
        stl_io::Triangle {
            normal: stl_io::Normal::new([n[0] / l, n[1] / l, n[2] / l]),
            vertices: [a, b, c].map(stl_io::Vertex::new),
        }
    });
    stl_io::write_stl(out, stl_triangles)
}

/// Reads an STL surface and rasterises it to a grid with the given cell size (metres): each grid
/// point takes the highest triangle above it. The mesh must cover its xy bounding box (a height
/// field: every grid point under some triangle).
pub fn read_stl(path: &Path, cell: f64) -> Result<HeightGrid, HeightFileError> {
    let data = crate::limits::read(path, crate::limits::DATA_FILE_BYTES)?;
    let mesh = stl_io::read_stl(&mut std::io::Cursor::new(data))
        .map_err(|e| HeightFileError::Stl(e.to_string()))?;
    if mesh.faces.is_empty() {
        return Err(HeightFileError::EmptyMesh);
    }
    let v: Vec<[f64; 3]> = mesh
        .vertices
        .iter()
        .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
        .collect();
    if v.iter().flatten().any(|c| !c.is_finite()) {
        return Err(HeightFileError::Stl(
            "a vertex coordinate is not finite".into(),
        ));
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &v {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if !(hi[0] > lo[0] && hi[1] > lo[1]) {
        return Err(HeightFileError::NotAHeightField(
            "its xy bounding box has no area (a vertical or degenerate mesh)".into(),
        ));
    }
    let cols_f = ((hi[0] - lo[0]) / cell).round() + 1.0;
    let rows_f = ((hi[1] - lo[1]) / cell).round() + 1.0;
    let fits = cell > 0.0 && cols_f * rows_f <= MAX_SAMPLES as f64;
    if !fits {
        return Err(super::grid::GridError::TooLarge {
            rows: rows_f,
            cols: cols_f,
            max: MAX_SAMPLES,
        }
        .into());
    }
    let (cols, rows) = (cols_f.max(2.0) as usize, rows_f.max(2.0) as usize);
    let dx = (hi[0] - lo[0]) / (cols - 1) as f64;
    let dy = (hi[1] - lo[1]) / (rows - 1) as f64;
    let mut heights = vec![f64::NEG_INFINITY; rows * cols];
    let eps = 1e-9 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    for face in &mesh.faces {
        let [a, b, c] = face.vertices.map(|k| v[k]);
        let det = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1]);
        if det.abs() < 1e-18 {
            continue; // vertical or degenerate triangle: no area seen from above
        }
        let j0 = (((a[0].min(b[0]).min(c[0]) - lo[0]) / dx).floor().max(0.0)) as usize;
        let j1 = (((a[0].max(b[0]).max(c[0]) - lo[0]) / dx).ceil() as usize).min(cols - 1);
        let i0 = (((a[1].min(b[1]).min(c[1]) - lo[1]) / dy).floor().max(0.0)) as usize;
        let i1 = (((a[1].max(b[1]).max(c[1]) - lo[1]) / dy).ceil() as usize).min(rows - 1);
        for i in i0..=i1 {
            let y = lo[1] + dy * i as f64;
            for j in j0..=j1 {
                let x = lo[0] + dx * j as f64;
                let l1 = ((b[1] - c[1]) * (x - c[0]) + (c[0] - b[0]) * (y - c[1])) / det;
                let l2 = ((c[1] - a[1]) * (x - c[0]) + (a[0] - c[0]) * (y - c[1])) / det;
                let l3 = 1.0 - l1 - l2;
                let tol = -eps;
                if l1 >= tol && l2 >= tol && l3 >= tol {
                    let z = l1 * a[2] + l2 * b[2] + l3 * c[2];
                    let slot = &mut heights[i * cols + j];
                    *slot = slot.max(z);
                }
            }
        }
    }
    if let Some(k) = heights.iter().position(|h| !h.is_finite()) {
        return Err(HeightFileError::NotAHeightField(format!(
            "no triangle covers the point x = {:.4}, y = {:.4} of its bounding box",
            lo[0] + dx * (k % cols) as f64,
            lo[1] + dy * (k / cols) as f64
        )));
    }
    Ok(HeightGrid::new(
        rows,
        cols,
        [lo[0], hi[0]],
        [lo[1], hi[1]],
        heights,
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file `name` in a temporary folder, removed when the test ends.
    fn tmp(name: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::Builder::new()
            .prefix("hexsim-io-")
            .tempdir()
            .unwrap();
        let path = dir.path().join(name);
        (dir, path)
    }

    fn sample_grid() -> HeightGrid {
        HeightGrid::from_fn(11, 9, [-1.0, 1.0], [0.0, 2.5], |x, y| {
            0.1 * x * y + 0.02 * x
        })
        .unwrap()
    }

    #[test]
    fn stl_round_trip_reproduces_the_grid() {
        let g = sample_grid();
        let (_dir, p) = tmp("g.stl");
        stl_to(&g, &mut std::fs::File::create(&p).unwrap()).unwrap();
        let (dx, _) = g.spacing();
        let back = read_stl(&p, dx).unwrap();
        assert_eq!((back.rows(), back.cols()), (g.rows(), g.cols()));
        for (a, b) in g.samples().iter().zip(back.samples()) {
            assert!((a - b).abs() < 1e-6, "{a} vs {b}");
        }
    }

    #[test]
    fn png_round_trip_within_16_bit_quantisation() {
        let g = sample_grid();
        let (_dir, p) = tmp("g.png");
        let (offset, scale) = png_to(&g, &mut std::fs::File::create(&p).unwrap()).unwrap();
        let (rows, cols, h) = read_png(&p, scale, offset).unwrap();
        assert_eq!((rows, cols), (g.rows(), g.cols()));
        for (a, b) in g.samples().iter().zip(&h) {
            assert!((a - b).abs() <= scale / 65535.0);
        }
    }

    #[test]
    fn csv_round_trip_is_exact() {
        let g = sample_grid();
        let (_dir, p) = tmp("g.csv");
        write_csv(&g, &p).unwrap();
        let (rows, cols, h) = read_csv(&p).unwrap();
        assert_eq!((rows, cols), (g.rows(), g.cols()));
        assert_eq!(h, g.samples());
    }

    #[test]
    fn csv_errors_say_where() {
        let (_dir, p) = tmp("ragged.csv");
        std::fs::write(&p, "# c\n1,2,3\n4,5\n").unwrap();
        let e = read_csv(&p).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("ragged"), "{e}");
        std::fs::write(&p, "1,2\n4,abc\n").unwrap();
        let e = read_csv(&p).unwrap_err().to_string();
        assert!(e.contains("line 2, column 2") && e.contains("abc"), "{e}");
        std::fs::write(&p, "1,NaN\n").unwrap();
        assert!(read_csv(&p).unwrap_err().to_string().contains("not finite"));
        std::fs::write(&p, "# only a comment\n").unwrap();
        assert!(matches!(read_csv(&p), Err(HeightFileError::Empty)));
    }
}
