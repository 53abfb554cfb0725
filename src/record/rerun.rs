//! The rerun recording: a `.rrd` file with a `sim_time` timeline computed from the step index.

use super::blueprint::{self, Layout};
use super::output::{commit, partial_path};
use crate::terrain::HeightGrid;
use anyhow::{Context, Result};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// An open `.rrd` recording, written to a temporary name until [`Recording::finish`].
pub struct Recording {
    stream: rerun::RecordingStream,
    path: PathBuf,
    dt: f64,
    dt_nanos: i64,
    samples: u64,
}

/// Samples between pushes of the recording to its file (a minute of a walk at 50 Hz). Each push
/// closes a chunk per entity, and a chunk carries its own schema (about 1.6 kB, some 130 kB for a
/// walk's 80 entities), so frequent pushes bloat the file: pushing every second of a walk made it
/// 11 MB a minute, every 20 s 5.2 MB. A run that stops (finishes, diverges or is interrupted)
/// pushes everything; this only bounds what a killed process loses.
const PUSH_EVERY: u64 = 3000;

/// The timeline the viewer opens on: simulated time, computed from the step index.
pub const TIMELINE: &str = "sim_time";

impl Recording {
    /// Creates the file; `dt` is the simulation step, for the `sim_time` timeline; `layout` is
    /// the viewer's default arrangement of views.
    pub fn create(path: &Path, name: String, dt: f64, layout: &Layout) -> Result<Self> {
        Self::open(path, name, dt, layout, Some(TIMELINE))
    }

    /// Creates the file for a still picture: everything in it is static, and the time panel
    /// names no timeline (the viewer would warn that it finds none).
    pub fn create_still(path: &Path, name: String, layout: &Layout) -> Result<Self> {
        Self::open(path, name, 1.0, layout, None)
    }

    /// Creates the file for data over a sequence (an evaluation count, say) rather than time:
    /// the time panel opens on `timeline`, set by [`Recording::set_sequence`].
    pub fn create_sequence(
        path: &Path,
        name: String,
        timeline: &str,
        layout: &Layout,
    ) -> Result<Self> {
        Self::open(path, name, 1.0, layout, Some(timeline))
    }

    fn open(
        path: &Path,
        name: String,
        dt: f64,
        layout: &Layout,
        timeline: Option<&str>,
    ) -> Result<Self> {
        // chunks as large as the pushes allow, rather than one every 200 ms of wall time
        let batching = rerun::log::ChunkBatcherConfig {
            flush_tick: std::time::Duration::from_secs(3600),
            flush_num_bytes: 64 << 20,
            ..rerun::log::ChunkBatcherConfig::DEFAULT
        };
        let stream = rerun::RecordingStreamBuilder::new("hexsim")
            .recording_name(name)
            .enabled(true)
            .batcher_config(batching)
            .save(partial_path(path))
            .with_context(|| format!("cannot create the recording {}", path.display()))?;
        blueprint::send(&stream, layout, timeline)?;
        stream.set_log_time_enabled(false);
        stream.log_static("/", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP())?;
        Ok(Recording {
            stream,
            path: path.to_path_buf(),
            dt,
            dt_nanos: (dt * 1e9).round() as i64,
            samples: 0,
        })
    }

    /// The simulation step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    pub fn stream(&self) -> &rerun::RecordingStream {
        &self.stream
    }

    /// Starts a sample: sets the `sim_time` timeline to step · dt (exact in nanoseconds), and
    /// now and then pushes what has been logged to the file. Returns the sample's index (0 for
    /// the first), by which recorders decimate what they draw less often.
    pub fn set_step(&mut self, step: u64) -> u64 {
        let sample = self.samples;
        self.samples += 1;
        if self.samples.is_multiple_of(PUSH_EVERY) {
            self.flush();
        }
        self.stream.set_time(
            TIMELINE,
            rerun::TimeCell::from_duration_nanos(step as i64 * self.dt_nanos),
        );
        sample
    }

    /// Sets the sequence `timeline` (see [`Recording::create_sequence`]) to `n`.
    pub fn set_sequence(&self, timeline: &'static str, n: i64) {
        self.stream.set_time_sequence(timeline, n);
    }

    /// Logs the terrain as a static mesh coloured by height, drawn with at most
    /// [`TERRAIN_MESH_SAMPLES`] of its samples (every n-th each way), and the flat apron the
    /// contact reads beyond its edges out to [`APRON`], dimmed: without it the view showed the
    /// viewer's background past the edge, a maroon band, where the robot walks on level ground.
    pub fn log_terrain(&self, entity: &str, grid: &HeightGrid) -> Result<()> {
        let decimated = decimated(grid, TERRAIN_MESH_SAMPLES)?;
        let (vertices, triangles, apron) = mesh_with_apron(decimated.as_ref().unwrap_or(grid));
        let (lo, hi) = grid.height_bounds();
        let span = (hi - lo).max(1e-9);
        let colors: Vec<[u8; 3]> = vertices
            .iter()
            .zip(&apron)
            .map(|(v, &outside)| {
                let t = ((v[2] as f64 - lo) / span).clamp(0.0, 1.0);
                let shade = if outside { 0.7 } else { 1.0 };
                // earthy ramp: dark olive (low) to sand (high)
                let mix = |a: f64, b: f64| ((a + (b - a) * t) * shade) as u8;
                [mix(70.0, 214.0), mix(92.0, 196.0), mix(50.0, 150.0)]
            })
            .collect();
        let normals: Vec<[f32; 3]> = vertices
            .iter()
            .zip(&apron)
            .map(|(v, &outside)| match outside {
                true => [0.0, 0.0, 1.0],
                false => grid.normal(v[0] as f64, v[1] as f64).as_vec3().to_array(),
            })
            .collect();
        self.stream.log_static(
            entity,
            &rerun::Mesh3D::new(vertices)
                .with_triangle_indices(triangles)
                .with_vertex_normals(normals)
                .with_vertex_colors(colors),
        )?;
        Ok(())
    }

    /// Logs the names of the series plotted at `entity`.
    pub fn name_series(&self, entity: &str, names: &[&str]) -> Result<()> {
        self.stream.log_static(
            entity,
            &rerun::SeriesLines::new().with_names(names.iter().copied()),
        )?;
        Ok(())
    }

    /// Logs one or more scalars at the current time.
    pub fn scalars(&self, entity: impl Into<rerun::EntityPath>, values: &[f64]) -> Result<()> {
        self.stream
            .log(entity, &rerun::Scalars::new(values.iter().copied()))?;
        Ok(())
    }

    /// Pushes what has been logged so far to the file, so an interrupted run loses little.
    fn flush(&self) {
        let _ = self.stream.flush_blocking();
    }

    /// Completes the file (writes its footer) and moves it to its final name.
    /// A write that failed (a full disk) is an error naming the file, and the truncated file
    /// keeps its temporary name.
    pub fn finish(self) -> Result<PathBuf> {
        let flushed = self.stream.flush_blocking();
        drop(self.stream);
        let failed = |why: String| {
            anyhow::anyhow!(
                "cannot write the recording {}: {why}; the file is incomplete",
                self.path.display()
            )
        };
        flushed.map_err(|e| failed(e.to_string()))?;
        let partial = partial_path(&self.path);
        if std::fs::metadata(&partial).is_ok_and(|m| m.is_file()) && !has_footer(&partial) {
            // the writer thread only logs a failure to write the footer
            return Err(failed(
                "its footer was not written (is the disk full?)".into(),
            ));
        }
        commit(&self.path)?;
        Ok(self.path)
    }
}

/// True if the file ends with an RRD stream footer (`RRF2` … `FOOT` in its last 32 bytes), as
/// a recording finished whole does.
fn has_footer(path: &Path) -> bool {
    use std::io::{Read, Seek, SeekFrom};
    let tail = std::fs::File::open(path).and_then(|mut file| {
        let length = file.metadata()?.len();
        file.seek(SeekFrom::Start(length.saturating_sub(32)))?;
        let mut tail = Vec::new();
        file.read_to_end(&mut tail)?;
        Ok(tail)
    });
    tail.is_ok_and(|tail| {
        let has = |word: &[u8]| tail.windows(4).any(|w| w == word);
        has(b"RRF2") && has(b"FOOT")
    })
}

/// The most samples of a terrain the recording draws (1024²: some 60 MB of mesh). A larger grid
/// (up to [`crate::terrain::MAX_SAMPLES`], 8192²) is drawn with every n-th sample each way: its
/// whole mesh took 3 GB more memory while the recording was written, for a viewer that shows no
/// more detail than this.
pub const TERRAIN_MESH_SAMPLES: usize = 1 << 20;

/// How far the drawn terrain continues past the grid's edges (m): far enough that the ground
/// reaches the horizon seen from the follow camera (below it by under 1° at 50 m).
pub const APRON: f32 = 50.0;

/// The grid's mesh (as [`crate::terrain::io::mesh`] makes it) ringed by one more row and column of vertices each side, [`APRON`]
/// beyond the edge at the height of the nearest edge sample (the contact's flat continuation);
/// with, per vertex, whether it lies outside the grid.
fn mesh_with_apron(grid: &HeightGrid) -> (Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<bool>) {
    let (rows, cols) = (grid.rows(), grid.cols());
    // ring index k (0..n+2) → the grid index it copies and the offset past the edge
    let ring = |k: usize, n: usize| match k {
        0 => (0, -APRON),
        k if k == n + 1 => (n - 1, APRON),
        k => (k - 1, 0.0),
    };
    let (mut vertices, mut apron) = (Vec::new(), Vec::new());
    for i in 0..rows + 2 {
        let (gi, dy) = ring(i, rows);
        for j in 0..cols + 2 {
            let (gj, dx) = ring(j, cols);
            vertices.push([
                grid.x_at(gj) as f32 + dx,
                grid.y_at(gi) as f32 + dy,
                grid.sample(gi, gj) as f32,
            ]);
            apron.push(dx != 0.0 || dy != 0.0);
        }
    }
    // two triangles a cell, wound as `terrain::io::mesh` winds them (normals up)
    let width = cols + 2;
    let mut triangles = Vec::with_capacity(2 * (rows + 1) * (cols + 1));
    for i in 0..rows + 1 {
        for j in 0..cols + 1 {
            let a = (i * width + j) as u32;
            let (b, c) = (a + 1, a + width as u32);
            let d = c + 1;
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    (vertices, triangles, apron)
}

/// `grid` with every n-th sample each way, the least n that leaves at most `most` samples;
/// None if it has no more than that already.
fn decimated(grid: &HeightGrid, most: usize) -> Result<Option<HeightGrid>> {
    let (rows, cols) = (grid.rows(), grid.cols());
    let stride = ((rows * cols) as f64 / most as f64).sqrt().ceil() as usize;
    if stride <= 1 {
        return Ok(None);
    }
    let (kept_rows, kept_cols) = ((rows - 1) / stride + 1, (cols - 1) / stride + 1);
    let heights = (0..kept_rows)
        .flat_map(|i| (0..kept_cols).map(move |j| (i * stride, j * stride)))
        .map(|(i, j)| grid.sample(i, j))
        .collect();
    let x_range = [grid.x_at(0), grid.x_at((kept_cols - 1) * stride)];
    let y_range = [grid.y_at(0), grid.y_at((kept_rows - 1) * stride)];
    Ok(Some(HeightGrid::new(
        kept_rows, kept_cols, x_range, y_range, heights,
    )?))
}

/// The `rerun` viewer binary on PATH, if installed.
pub fn viewer_on_path() -> Option<PathBuf> {
    let exe = format!("rerun{}", std::env::consts::EXE_SUFFIX);
    let paths = std::env::var_os("PATH")?;
    std::env::split_paths(&paths)
        .map(|d| d.join(&exe))
        .find(|p| p.is_file())
}

/// How long a started viewer is watched: one that cannot open a window (no display, no GPU)
/// exits within a fraction of this, and the command then fails saying so, rather than ending
/// as if the recording were on screen.
const VIEWER_START: std::time::Duration = std::time::Duration::from_millis(1500);

/// Opens `file` in the rerun viewer; an error if it is not installed, there is no display to
/// open it on, or it exits at once (its own message is printed above ours).
pub fn spawn_viewer(file: &Path) -> Result<()> {
    let Some(viewer) = viewer_on_path() else {
        anyhow::bail!(
            "the rerun viewer is not installed; install it with `pip install rerun-sdk==0.36.3` \
             (or `cargo binstall rerun-cli@0.36.3`), then open the recording with `rerun {}`",
            file.display()
        )
    };
    let elsewhere = format!(
        "the recording is written: open it with `rerun {0}` where there is a display, or serve \
         it to a browser with `rerun --web-viewer {0}`",
        file.display()
    );
    let no_display = ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"]
        .iter()
        .all(|v| std::env::var_os(v).is_none_or(|v| v.is_empty()));
    if cfg!(all(unix, not(target_os = "macos"))) && no_display {
        anyhow::bail!(
            "--spawn: no display to open the viewer on (neither DISPLAY nor WAYLAND_DISPLAY is \
             set); {elsewhere}"
        );
    }
    let mut child = std::process::Command::new(viewer)
        .arg(file)
        .spawn()
        .context("cannot start the rerun viewer")?;
    let started = std::time::Instant::now();
    while started.elapsed() < VIEWER_START {
        match child.try_wait()? {
            // a viewer already open takes the file and exits
            Some(status) if status.success() => return Ok(()),
            Some(status) => anyhow::bail!(
                "--spawn: the rerun viewer stopped at once ({status}; its message is above); \
                 {elsewhere}"
            ),
            None => std::thread::sleep(std::time::Duration::from_millis(50)),
        }
    }
    Ok(())
}

/// What a recording file holds, read back the way the viewer reads it: per store (the data, the
/// blueprint) and entity, the rows, components and text values logged there, and how the
/// blueprint asks to be activated. A file that reads to its end is one the viewer can open.
#[derive(Debug, Default)]
pub struct Contents {
    pub messages: usize,
    /// (in the blueprint store, entity path) → what was logged there.
    pub entities: BTreeMap<(bool, String), Logged>,
    /// Per blueprint activation command: (make_active, make_default).
    pub activations: Vec<(bool, bool)>,
    /// Whether an activation command came before the last blueprint data (a half-sent layout).
    pub activated_early: bool,
}

#[derive(Debug, Default)]
pub struct Logged {
    pub rows: usize,
    pub static_rows: usize,
    /// Component identifiers, e.g. `EyeControls3D:tracking_entity`.
    pub components: BTreeSet<String>,
    /// Every text value logged (entity paths, names, states, timelines).
    pub texts: BTreeSet<String>,
}

impl Contents {
    /// What was logged at `entity` in the data store (`blueprint` false) or the blueprint.
    pub fn at(&self, blueprint: bool, entity: &str) -> Option<&Logged> {
        self.entities.get(&(blueprint, entity.to_string()))
    }

    /// The entities of a store whose path starts with `prefix`.
    pub fn under<'a>(
        &'a self,
        blueprint: bool,
        prefix: &'a str,
    ) -> impl Iterator<Item = (&'a str, &'a Logged)> + 'a {
        self.entities
            .iter()
            .filter(move |((b, path), _)| *b == blueprint && path.starts_with(prefix))
            .map(|((_, path), logged)| (path.as_str(), logged))
    }
}

/// Reads the recording at `path` to its end (see [`Contents`]).
pub fn read_back(path: &Path) -> Result<Contents> {
    use rerun::external::arrow::array::{Array, StringArray};
    use rerun::external::re_log_encoding::DecoderApp;
    use rerun::external::re_log_types::{LogMsg, StoreKind};
    let file =
        std::fs::File::open(path).with_context(|| format!("{}: cannot open", path.display()))?;
    let mut contents = Contents::default();
    for message in DecoderApp::decode_eager(std::io::BufReader::new(file))
        .map_err(|e| anyhow::anyhow!("{}: not a recording: {e}", path.display()))?
    {
        let message = message.map_err(|e| {
            anyhow::anyhow!("{}: message {}: {e}", path.display(), contents.messages)
        })?;
        contents.messages += 1;
        match message {
            LogMsg::ArrowMsg(store, arrow) => {
                let chunk = rerun::log::Chunk::from_arrow_msg(&arrow)?;
                let blueprint = store.kind() == StoreKind::Blueprint;
                if blueprint && !contents.activations.is_empty() {
                    contents.activated_early = true;
                }
                let logged = contents
                    .entities
                    .entry((
                        blueprint,
                        chunk
                            .entity_path()
                            .to_string()
                            .trim_start_matches('/')
                            .to_string(),
                    ))
                    .or_default();
                if chunk.is_static() {
                    logged.static_rows += chunk.num_rows();
                } else {
                    logged.rows += chunk.num_rows();
                }
                for (component, column) in chunk.components().iter() {
                    logged.components.insert(component.to_string());
                    if let Some(texts) = column
                        .list_array
                        .values()
                        .as_any()
                        .downcast_ref::<StringArray>()
                    {
                        logged
                            .texts
                            .extend(texts.iter().flatten().map(str::to_string));
                    }
                }
            }
            LogMsg::BlueprintActivationCommand(command) => contents
                .activations
                .push((command.make_active, command.make_default)),
            LogMsg::SetStoreInfo(_) => {}
        }
    }
    Ok(contents)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_terrain_is_drawn_with_every_nth_sample() {
        let grid =
            HeightGrid::from_fn(101, 201, [0.0, 2.0], [0.0, 1.0], |x, y| x + 10.0 * y).unwrap();
        assert!(decimated(&grid, 101 * 201).unwrap().is_none());
        let drawn = decimated(&grid, 2000).unwrap().unwrap();
        assert!(drawn.rows() * drawn.cols() <= 2000);
        assert_eq!((drawn.rows(), drawn.cols()), (26, 51), "every 4th sample");
        assert_eq!(drawn.x_range(), [0.0, 2.0]);
        assert_eq!(drawn.sample(25, 50), grid.sample(100, 200));
    }
}
