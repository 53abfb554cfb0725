//! Terrain generators. Each is a pure function of its parameters (and seed), so a terrain is
//! reproducible bit for bit.

use super::grid::{GridError, HeightGrid, MAX_SAMPLES};
use rand_mt::Mt;
use rustfft::{FftPlanner, num_complex::Complex};

/// MATLAB's `rand` for its default generator (`rng default`: Mersenne Twister MT19937 seeded 5489):
/// a double with 53 random bits built from two 32-bit draws (`genrand_res53`).
pub struct MatlabRand(Mt);

impl MatlabRand {
    pub fn new(seed: u32) -> Self {
        MatlabRand(Mt::new(seed))
    }
    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        let a = (self.0.next_u32() >> 5) as f64;
        let b = (self.0.next_u32() >> 6) as f64;
        (a * 67_108_864.0 + b) / 9_007_199_254_740_992.0
    }
}

fn check_samples(rows: usize, cols: usize) -> Result<(), GridError> {
    if rows < 2 || cols < 2 {
        return Err(GridError::TooSmall { rows, cols });
    }
    if rows.checked_mul(cols).is_none_or(|n| n > MAX_SAMPLES) {
        return Err(GridError::TooLarge {
            rows: rows as f64,
            cols: cols as f64,
            max: MAX_SAMPLES,
        });
    }
    Ok(())
}

/// The paper's "natural" fractal terrain, eq. 7:
/// `S = |ifft2((hypot(X, Y) + 0.1)^(−1.7) · exp(2πi·U))|` with X, Y = meshgrid(−n/2 … n/2−1), U uniform
/// from MATLAB's generator seeded `seed` and filled column-major, the spectrum *not* shifted before
/// the inverse FFT (as the paper's MATLAB). The magnitudes are scaled to `[0, peak_to_peak]` over a
/// square of `size` centred on `center`. With seed 5489 and n = 100 this is the paper's terrain.
pub fn natural(
    seed: u32,
    n: usize,
    size: [f64; 2],
    center: [f64; 2],
    peak_to_peak: f64,
) -> Result<HeightGrid, GridError> {
    check_samples(n, n)?;
    let mut rng = MatlabRand::new(seed);
    let half = (n / 2) as f64;
    // column-major fill: MATLAB's rand(n) draws down each column first. The phases go straight
    // into the spectrum, and each buffer is dropped once used: at 8192² samples the peak memory
    // is the spectrum and the heights (1.6 GB), not also the phases and a rescaled copy.
    let mut spectrum = vec![Complex::default(); n * n];
    for j in 0..n {
        if crate::interrupt::interrupted() {
            return Err(GridError::Interrupted);
        }
        for i in 0..n {
            let (x, y) = (j as f64 - half, i as f64 - half);
            let amplitude = (x.hypot(y) + 0.1).powf(-1.7);
            spectrum[i * n + j] =
                Complex::from_polar(amplitude, 2.0 * std::f64::consts::PI * rng.next_f64());
        }
    }
    inverse_fft_2d(&mut spectrum, n)?;
    let mut heights: Vec<f64> = spectrum.iter().map(|c| c.norm()).collect();
    drop(spectrum);
    rescale_in_place(&mut heights, peak_to_peak);
    HeightGrid::new(
        n,
        n,
        span(center[0], size[0]),
        span(center[1], size[1]),
        heights,
    )
}

/// A periodic terrain's grid (one period: [`natural`]'s) repeated `tiles` = [along x, along y]
/// times: the first copy where the tile is, the others continuing it toward +x and +y, where a
/// walk goes.
///
/// Eq. 7's surface is the magnitude of an inverse DFT, so it is periodic: the sample after the
/// last would be the first again. The copies therefore meet without a seam — the tiled grid is
/// the same surface sampled further — and a robot whose 10 s walk is longer than the paper's
/// 4 m can walk it on the paper's terrain instead of on the flat apron past its edge.
pub fn tiled(tile: HeightGrid, tiles: [usize; 2]) -> Result<HeightGrid, GridError> {
    if tiles == [1, 1] {
        return Ok(tile);
    }
    let (nx, ny) = (tile.cols(), tile.rows());
    let (cols, rows) = (nx.saturating_mul(tiles[0]), ny.saturating_mul(tiles[1]));
    check_samples(rows, cols)?;
    let heights = (0..rows * cols)
        .map(|k| tile.sample((k / cols) % ny, (k % cols) % nx))
        .collect();
    let (dx, dy) = tile.spacing();
    let ([x0, _], [y0, _]) = (tile.x_range(), tile.y_range());
    HeightGrid::new(
        rows,
        cols,
        [x0, x0 + (cols - 1) as f64 * dx],
        [y0, y0 + (rows - 1) as f64 * dy],
        heights,
    )
}

/// In-place 2-D inverse DFT of a row-major n×n array (unnormalised; the caller rescales). Ctrl-C
/// ends it between rows and columns (at 8192² it takes some seconds).
fn inverse_fft_2d(data: &mut [Complex<f64>], n: usize) -> Result<(), GridError> {
    let interrupted = || {
        if crate::interrupt::interrupted() {
            Err(GridError::Interrupted)
        } else {
            Ok(())
        }
    };
    let fft = FftPlanner::new().plan_fft_inverse(n);
    for row in data.chunks_exact_mut(n) {
        interrupted()?;
        fft.process(row);
    }
    let mut column = vec![Complex::default(); n];
    for j in 0..n {
        interrupted()?;
        for i in 0..n {
            column[i] = data[i * n + j];
        }
        fft.process(&mut column);
        for i in 0..n {
            data[i * n + j] = column[i];
        }
    }
    Ok(())
}

/// [`rescale`] without a copy.
fn rescale_in_place(values: &mut [f64], peak_to_peak: f64) {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let range = hi - lo;
    for v in values {
        *v = if range > 0.0 {
            (*v - lo) / range * peak_to_peak
        } else {
            0.0
        };
    }
}

/// Affine map of values onto [0, peak_to_peak] (a flat input maps to 0).
fn rescale(values: &[f64], peak_to_peak: f64) -> Vec<f64> {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let range = hi - lo;
    values
        .iter()
        .map(|v| {
            if range > 0.0 {
                (v - lo) / range * peak_to_peak
            } else {
                0.0
            }
        })
        .collect()
}

fn span(center: f64, size: f64) -> [f64; 2] {
    [center - size / 2.0, center + size / 2.0]
}

/// The paper's inverted bell, eq. 8: `z = −depth · exp(−(x² + y²) / (2σ²))` (the paper: depth 1,
/// σ = 1) on the square [−half_width, half_width]², sampled `samples × samples`.
pub fn bell(
    half_width: f64,
    samples: usize,
    depth: f64,
    sigma: f64,
) -> Result<HeightGrid, GridError> {
    check_samples(samples, samples)?;
    let r = [-half_width, half_width];
    HeightGrid::from_fn(samples, samples, r, r, |x, y| {
        -depth * (-(x * x + y * y) / (2.0 * sigma * sigma)).exp()
    })
}

/// A horizontal plane at `height`.
pub fn flat(size: [f64; 2], center: [f64; 2], height: f64) -> Result<HeightGrid, GridError> {
    // Interpolation reproduces planes exactly, so 2×2 samples describe it completely.
    HeightGrid::from_fn(
        2,
        2,
        span(center[0], size[0]),
        span(center[1], size[1]),
        |_, _| height,
    )
}

/// A plane through the centre rising at `angle` (radians) towards the azimuth `ascent` (radians from +x).
pub fn slope(
    size: [f64; 2],
    center: [f64; 2],
    angle: f64,
    ascent: f64,
) -> Result<HeightGrid, GridError> {
    let g = angle.tan();
    let (s, c) = ascent.sin_cos();
    HeightGrid::from_fn(
        2,
        2,
        span(center[0], size[0]),
        span(center[1], size[1]),
        |x, y| g * ((x - center[0]) * c + (y - center[1]) * s),
    )
}

/// A staircase along +x: `step_height` up every `step_length`, starting at x = `first_step`, sampled
/// every `cell` metres (each riser becomes a ramp one cell wide).
pub fn steps(
    size: [f64; 2],
    center: [f64; 2],
    first_step: f64,
    step_length: f64,
    step_height: f64,
    cell: f64,
) -> Result<HeightGrid, GridError> {
    let (cols, rows) = samples_for(size, cell)?;
    HeightGrid::from_fn(
        rows,
        cols,
        span(center[0], size[0]),
        span(center[1], size[1]),
        |x, _| {
            if x < first_step {
                0.0
            } else {
                step_height * (1.0 + ((x - first_step) / step_length).floor())
            }
        },
    )
}

/// A grid of `cell` spacing over the rectangle `size` centred on `center`, sampled from `f`.
fn sampled(
    size: [f64; 2],
    center: [f64; 2],
    cell: f64,
    f: impl Fn(f64, f64) -> f64,
) -> Result<HeightGrid, GridError> {
    let (cols, rows) = samples_for(size, cell)?;
    HeightGrid::from_fn(
        rows,
        cols,
        span(center[0], size[0]),
        span(center[1], size[1]),
        f,
    )
}

/// Stairs along +x, up then down: from x = `first_step`, `count` steps of `step_height` every
/// `step_length`, a landing `landing` long, and as many down. The sampled risers are walls
/// midway between the samples either side of them (`cliff.rs`).
#[allow(clippy::too_many_arguments)]
pub fn stairs(
    size: [f64; 2],
    center: [f64; 2],
    first_step: f64,
    count: usize,
    step_length: f64,
    step_height: f64,
    landing: f64,
    cell: f64,
) -> Result<HeightGrid, GridError> {
    let n = count as f64;
    let top = first_step + n * step_length;
    let down = top + landing;
    sampled(size, center, cell, |x, _| {
        let up = if x < first_step {
            0.0
        } else {
            (1.0 + ((x - first_step) / step_length).floor()).min(n)
        };
        let off = if x < down {
            0.0
        } else {
            (1.0 + ((x - down) / step_length).floor()).min(n)
        };
        step_height * (up - off)
    })
}

/// Square pyramid stairs centred on `center`: `count` steps of `step_height` up (negative: down
/// into a pit) to a square top `top` wide, the rings between `step_width` wide; level 0 outside,
/// `top + 2·(count − 1)·step_width` across.
pub fn pyramid_stairs(
    size: [f64; 2],
    center: [f64; 2],
    count: usize,
    step_width: f64,
    step_height: f64,
    top: f64,
    cell: f64,
) -> Result<HeightGrid, GridError> {
    let n = count as f64;
    sampled(size, center, cell, |x, y| {
        let d = (x - center[0]).abs().max((y - center[1]).abs());
        let level = if d < 0.5 * top {
            n
        } else {
            (n - 1.0 - ((d - 0.5 * top) / step_width).floor()).max(0.0)
        };
        step_height * level
    })
}

/// legged_gym's discrete obstacles: `count` boxes, axis-aligned, each side uniform in
/// `sides` = [min, max], height uniform in `heights` = [min, max] (negative: a hole), centred
/// uniformly over the terrain (MATLAB's generator seeded `seed`: x side, y side, x, y, height per
/// box), later ones over earlier ones; the square `platform` wide at the centre (where a robot
/// starts) is left level, as legged_gym's.
#[allow(clippy::too_many_arguments)]
pub fn discrete_obstacles(
    size: [f64; 2],
    center: [f64; 2],
    count: usize,
    sides: [f64; 2],
    heights: [f64; 2],
    platform: f64,
    seed: u32,
    cell: f64,
) -> Result<HeightGrid, GridError> {
    let (cols, rows) = samples_for(size, cell)?;
    let [x_span, y_span] = [span(center[0], size[0]), span(center[1], size[1])];
    let (dx, dy) = (
        (x_span[1] - x_span[0]) / (cols - 1) as f64,
        (y_span[1] - y_span[0]) / (rows - 1) as f64,
    );
    let mut rng = MatlabRand::new(seed);
    let mut z = vec![0.0; rows * cols];
    // the samples strictly within half-width `half` of `middle`, along an axis from `origin`
    let within = |middle: f64, half: f64, origin: f64, step: f64, n: usize| {
        let first = ((middle - half - origin) / step).floor().max(0.0) as usize;
        let last = (((middle + half - origin) / step).ceil().max(0.0) as usize).min(n - 1);
        (first..=last).filter(move |&k| (origin + step * k as f64 - middle).abs() < half)
    };
    for _ in 0..count {
        let mut draw = |[lo, hi]: [f64; 2]| lo + (hi - lo) * rng.next_f64();
        let (w, l) = (draw(sides), draw(sides));
        let (x, y) = (draw(x_span), draw(y_span));
        let h = draw(heights);
        for i in within(y, 0.5 * l, y_span[0], dy, rows) {
            for j in within(x, 0.5 * w, x_span[0], dx, cols) {
                z[i * cols + j] = h;
            }
        }
    }
    let clear = 0.5 * platform;
    for i in within(center[1], clear, y_span[0], dy, rows) {
        for j in within(center[0], clear, x_span[0], dx, cols) {
            z[i * cols + j] = 0.0;
        }
    }
    HeightGrid::new(rows, cols, x_span, y_span, z)
}

/// Stepping stones over pits: square stones `stone` wide at level 0, `gap` apart, in a grid
/// aligned on `center` (a stone there), over pits `depth` deep; a square `platform` wide at the
/// centre is solid.
pub fn stepping_stones(
    size: [f64; 2],
    center: [f64; 2],
    stone: f64,
    gap: f64,
    depth: f64,
    platform: f64,
    cell: f64,
) -> Result<HeightGrid, GridError> {
    let pitch = stone + gap;
    let on_stone = |u: f64| {
        // distance from the nearest stone's centre, along one axis
        let k = (u / pitch).round();
        (u - k * pitch).abs() < 0.5 * stone
    };
    sampled(size, center, cell, |x, y| {
        let (u, v) = (x - center[0], y - center[1]);
        let solid =
            (u.abs() < 0.5 * platform && v.abs() < 0.5 * platform) || (on_stone(u) && on_stone(v));
        if solid { 0.0 } else { -depth }
    })
}

/// Gaps: trenches across the way along +x, `width` wide and `depth` deep, the first starting at
/// x = `first_gap`, one every `spacing`. A sample on a trench's edge (on a grid whose cells
/// divide the spacing, every edge is one) is in the trench at its start and not at its end, at
/// every trench alike: read as it rounded, the 2 cm trenches of `ladder/gaps.toml` were 1, 2 or
/// 3 samples wide, and a 1 cm one (a V-groove narrower than hex18's 2 cm foot, not walls)
/// wedged a foot 7.2 mm deep.
pub fn gaps(
    size: [f64; 2],
    center: [f64; 2],
    first_gap: f64,
    width: f64,
    spacing: f64,
    depth: f64,
    cell: f64,
) -> Result<HeightGrid, GridError> {
    // far above the rounding of x − first_gap, far below any cell
    let edge = 1e-9 * spacing.max(width);
    sampled(size, center, cell, |x, _| {
        let along = x - first_gap + edge;
        if along >= 0.0 && along.rem_euclid(spacing) < width {
            -depth
        } else {
            0.0
        }
    })
}

/// A rough field: the sum of `waves` sinusoids with seeded random directions, phases and wavelengths
/// in [`wavelength_min`, `wavelength_max`], scaled to `[0, peak_to_peak]`.
#[allow(clippy::too_many_arguments)]
pub fn rough(
    size: [f64; 2],
    center: [f64; 2],
    peak_to_peak: f64,
    wavelength_min: f64,
    wavelength_max: f64,
    waves: usize,
    seed: u32,
    cell: f64,
) -> Result<HeightGrid, GridError> {
    let (cols, rows) = samples_for(size, cell)?;
    let mut rng = MatlabRand::new(seed);
    let tau = std::f64::consts::TAU;
    let components: Vec<(f64, f64, f64, f64)> = (0..waves)
        .map(|_| {
            let direction = tau * rng.next_f64();
            let wavelength = wavelength_min + (wavelength_max - wavelength_min) * rng.next_f64();
            let phase = tau * rng.next_f64();
            let k = tau / wavelength;
            (k * direction.cos(), k * direction.sin(), phase, wavelength)
        })
        .collect();
    let raw = HeightGrid::from_fn(
        rows,
        cols,
        span(center[0], size[0]),
        span(center[1], size[1]),
        |x, y| {
            // amplitude ∝ wavelength: long waves carry more height, as in natural ground
            components
                .iter()
                .map(|&(kx, ky, phase, wavelength)| wavelength * (kx * x + ky * y + phase).sin())
                .sum()
        },
    )?;
    let heights = rescale(raw.samples(), peak_to_peak);
    HeightGrid::new(rows, cols, raw.x_range(), raw.y_range(), heights)
}

/// An egg-crate field `z = amplitude · sin(2πx/λ) · sin(2πy/λ)`.
pub fn sine(
    size: [f64; 2],
    center: [f64; 2],
    amplitude: f64,
    wavelength: f64,
    cell: f64,
) -> Result<HeightGrid, GridError> {
    let (cols, rows) = samples_for(size, cell)?;
    let k = std::f64::consts::TAU / wavelength;
    HeightGrid::from_fn(
        rows,
        cols,
        span(center[0], size[0]),
        span(center[1], size[1]),
        |x, y| amplitude * (k * x).sin() * (k * y).sin(),
    )
}

/// Sample counts (cols, rows) for a rectangle at a given cell size, refusing absurd sizes before
/// anything is allocated.
fn samples_for(size: [f64; 2], cell: f64) -> Result<(usize, usize), GridError> {
    let count = |extent: f64| -> f64 { (extent / cell).round() + 1.0 };
    let (cols, rows) = (count(size[0]), count(size[1]));
    let fits = cols * rows <= MAX_SAMPLES as f64;
    if !fits {
        // also catches NaN and infinite counts (a zero or negative cell size)
        return Err(GridError::TooLarge {
            rows,
            cols,
            max: MAX_SAMPLES,
        });
    }
    let (cols, rows) = (cols.max(2.0) as usize, rows.max(2.0) as usize);
    check_samples(rows, cols)?;
    Ok((cols, rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matlab_rand_matches_known_first_draws() {
        // `rng default; rand(1,3)` in MATLAB: 0.8147 0.9058 0.1270
        let mut r = MatlabRand::new(5489);
        let v: Vec<f64> = (0..3).map(|_| r.next_f64()).collect();
        assert!((v[0] - 0.814_723_686_393_179).abs() < 1e-15, "{v:?}");
        assert!((v[1] - 0.905_791_937_075_619).abs() < 1e-15);
        assert!((v[2] - 0.126_986_816_293_506).abs() < 1e-15);
    }

    #[test]
    fn natural_is_scaled_and_reproducible() {
        let a = natural(7, 32, [2.0, 2.0], [0.0, 0.0], 0.05).unwrap();
        let b = natural(7, 32, [2.0, 2.0], [0.0, 0.0], 0.05).unwrap();
        assert_eq!(a, b);
        let (lo, hi) = a.height_bounds();
        assert_eq!(lo, 0.0);
        assert!((hi - 0.05).abs() < 1e-15);
        assert_ne!(a, natural(8, 32, [2.0, 2.0], [0.0, 0.0], 0.05).unwrap());
    }

    /// The copies meet without a seam: no step between neighbouring samples across a seam is
    /// larger than the largest inside a tile (an aperiodic surface would jump there by up to its
    /// whole peak-to-peak), and the tiled grid is the tile again at every copy.
    #[test]
    fn tiled_natural_terrain_is_seamless() {
        let n = 32;
        let tile = natural(7, n, [2.0, 2.0], [0.0, 0.0], 0.05).unwrap();
        let tiled = tiled(tile.clone(), [3, 2]).unwrap();
        assert_eq!((tiled.rows(), tiled.cols()), (2 * n, 3 * n));
        assert_eq!(tiled.spacing(), tile.spacing());
        // the first copy is the tile, in place
        assert_eq!(tiled.x_range()[0], tile.x_range()[0]);
        assert_eq!(tiled.y_range()[0], tile.y_range()[0]);
        assert_eq!(tiled.height(0.3, -0.2), tile.height(0.3, -0.2));
        for i in 0..2 * n {
            for j in 0..3 * n {
                assert_eq!(tiled.sample(i, j), tile.sample(i % n, j % n));
            }
        }
        let step = |g: &HeightGrid, i: usize, j: usize| (g.sample(i, j + 1) - g.sample(i, j)).abs();
        let inside = (0..n)
            .flat_map(|i| (0..n - 1).map(move |j| (i, j)))
            .map(|(i, j)| step(&tile, i, j))
            .fold(0.0, f64::max);
        let seam = (0..n).map(|i| step(&tiled, i, n - 1)).fold(0.0, f64::max);
        assert!(seam <= inside, "seam step {seam}, inside {inside}");
        // one tile is the paper's grid unchanged
        assert_eq!(super::tiled(tile.clone(), [1, 1]).unwrap(), tile);
    }

    #[test]
    fn bell_has_its_formula() {
        let g = bell(3.0, 61, 1.0, 1.0).unwrap();
        assert!((g.height(0.0, 0.0) + 1.0).abs() < 1e-12);
        assert!((g.height(1.0, 0.0) + (-0.5f64).exp()).abs() < 1e-12);
    }

    /// Heights along the row nearest y = 0 (the profile of a terrain uniform along y).
    fn profile(g: &HeightGrid, x: f64) -> f64 {
        g.height(x, 0.0)
    }

    #[test]
    fn stairs_go_up_then_down_with_walls() {
        let g = stairs([4.0, 1.0], [0.0, 0.0], 0.305, 3, 0.2, 0.05, 0.4, 0.01).unwrap();
        assert!(g.has_cliffs());
        let expected = [
            (0.0, 0.0),
            (0.3, 0.0),
            (0.31, 0.05),
            (0.6, 0.1),
            (0.8, 0.15),
            (1.1, 0.15),
            (1.3, 0.15),
            (1.4, 0.1),
            (1.6, 0.05),
            (1.75, 0.0),
            (1.95, 0.0),
        ];
        for (x, h) in expected {
            assert!(
                (profile(&g, x) - h).abs() < 1e-12,
                "at {x}: {}",
                profile(&g, x)
            );
        }
    }

    #[test]
    fn pyramid_stairs_rise_ring_by_ring_to_the_top() {
        // top 0.41 m, rings 0.2 m: risers at 0.205, 0.405 and 0.605 from the centre
        let g = pyramid_stairs([2.0, 2.0], [0.0, 0.0], 3, 0.2, 0.05, 0.41, 0.01).unwrap();
        assert!(g.has_cliffs());
        for (d, h) in [
            (0.0, 0.15),
            (0.2, 0.15),
            (0.21, 0.1),
            (0.5, 0.05),
            (0.61, 0.0),
        ] {
            for (x, y) in [(d, 0.0), (-d, 0.0), (0.0, d), (0.0, -d), (d, -d)] {
                assert!((g.height(x, y) - h).abs() < 1e-12, "at ({x}, {y})");
            }
        }
    }

    #[test]
    fn discrete_obstacles_are_seeded_boxes_off_the_platform() {
        let build = |seed| {
            discrete_obstacles(
                [4.0, 4.0],
                [0.0, 0.0],
                40,
                [0.1, 0.3],
                [0.05, 0.1],
                1.0,
                seed,
                0.01,
            )
            .unwrap()
        };
        let a = build(3);
        assert_eq!(a, build(3));
        assert_ne!(a, build(4));
        assert!(a.has_cliffs());
        let boxed = a.samples().iter().filter(|&&h| h != 0.0).count();
        assert!(boxed > 1000, "{boxed} samples on boxes");
        assert!(
            a.samples()
                .iter()
                .all(|&h| h == 0.0 || (0.05..=0.1).contains(&h))
        );
        // the platform is level
        for k in 0..=20 {
            let u = -0.49 + 0.049 * k as f64;
            assert_eq!(a.height(u, 0.3), 0.0);
            assert_eq!(a.height(-0.3, u), 0.0);
        }
    }

    #[test]
    fn stepping_stones_stand_over_pits() {
        let g = stepping_stones([4.0, 4.0], [0.0, 0.0], 0.15, 0.05, 0.1, 1.0, 0.01).unwrap();
        assert!(g.has_cliffs());
        // the platform, a stone's middle (pitch 0.2 m), the pit between stones, a stone's corner
        for ((x, y), h) in [
            ((0.3, 0.45), 0.0),
            ((1.2, 1.4), 0.0),
            ((1.3, 1.4), -0.1),
            ((1.2, 1.3), -0.1),
            ((1.26, 1.46), 0.0),
        ] {
            assert!((g.height(x, y) - h).abs() < 1e-12, "at ({x}, {y})");
        }
    }

    #[test]
    fn gaps_are_trenches_across_the_way() {
        let g = gaps([4.0, 1.0], [0.0, 0.0], 0.505, 0.06, 0.4, 0.1, 0.01).unwrap();
        assert!(g.has_cliffs());
        for (x, h) in [
            (0.4, 0.0),
            (0.53, -0.1),
            (0.6, 0.0),
            (0.93, -0.1),
            (1.0, 0.0),
        ] {
            assert!(
                (profile(&g, x) - h).abs() < 1e-12,
                "at {x}: {}",
                profile(&g, x)
            );
        }
    }

    #[test]
    fn refuses_absurd_sizes_before_allocating() {
        assert!(steps([1e6, 1e6], [0.0, 0.0], 0.0, 1.0, 0.1, 1e-3).is_err());
        assert!(sine([1.0, 1.0], [0.0, 0.0], 0.1, 1.0, 0.0).is_err());
    }

    /// Every trench of a gaps terrain is as wide as asked, in samples and in walls: on a grid
    /// whose cells divide the spacing each edge falls on a sample, and read as it rounded the
    /// ladder's 2 cm trenches were 1, 2 or 3 samples wide.
    #[test]
    fn every_trench_is_as_wide_as_asked() {
        for (w, samples) in [(0.02, 2), (0.06, 6), (0.1, 10), (0.12, 12)] {
            let g = gaps([6.0, 4.0], [0.0, 0.0], 0.5, w, 0.4, 0.1, 0.01).unwrap();
            let mut trenches = vec![];
            let mut low = 0;
            for i in 0..600 {
                if g.height(-3.0 + i as f64 * 0.01, 0.0) < -0.05 {
                    low += 1;
                } else if low > 0 {
                    trenches.push(low);
                    low = 0;
                }
            }
            assert!(trenches.len() >= 6, "{trenches:?}");
            assert!(
                trenches.iter().all(|&n| n == samples),
                "{w} m: {trenches:?}"
            );
        }
    }
}
