//! The rerun recording: a `.rrd` file with a `sim_time` timeline computed from the step index.

use super::output::{commit, partial_path};
use crate::terrain::{HeightGrid, io::mesh};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// An open `.rrd` recording, written to a temporary name until [`Recording::finish`].
pub struct Recording {
    stream: rerun::RecordingStream,
    path: PathBuf,
    dt_nanos: i64,
}

impl Recording {
    /// Creates the file; `dt` is the simulation step, for the `sim_time` timeline. `layout` is the
    /// viewer's default arrangement: a 3D view of `world` beside tabs of time-series views.
    pub fn create(path: &Path, name: String, dt: f64, layout: &[(&str, &[&str])]) -> Result<Self> {
        use rerun::blueprint::{
            Blueprint, ContainerLike, Horizontal, Spatial3DView, Tabs, TimePanel, TimeSeriesView,
            Vertical,
        };
        let tabs: Vec<ContainerLike> = layout
            .iter()
            .map(|(tab, origins)| {
                let views: Vec<ContainerLike> = origins
                    .iter()
                    .map(|origin| {
                        TimeSeriesView::new(origin.rsplit('/').next().unwrap_or(origin))
                            .with_origin(*origin)
                            .into()
                    })
                    .collect();
                Vertical::new(views).with_name(*tab).into()
            })
            .collect();
        let blueprint = Blueprint::new(
            Horizontal::new([
                Spatial3DView::new("world").with_origin("world").into(),
                Tabs::new(tabs).into(),
            ])
            .with_column_shares([0.6, 0.4]),
        )
        .with_time_panel(TimePanel::new().with_timeline("sim_time"));
        let stream = rerun::RecordingStreamBuilder::new("hexsim")
            .recording_name(name)
            .enabled(true)
            .with_default_blueprint(blueprint)
            .save(partial_path(path))
            .with_context(|| format!("cannot create the recording {}", path.display()))?;
        stream.set_log_time_enabled(false);
        stream.log_static("/", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP())?;
        Ok(Recording {
            stream,
            path: path.to_path_buf(),
            dt_nanos: (dt * 1e9).round() as i64,
        })
    }

    pub fn stream(&self) -> &rerun::RecordingStream {
        &self.stream
    }

    /// Sets the `step` and `sim_time` timelines (sim_time = step · dt, exact in nanoseconds).
    pub fn set_step(&self, step: u64) {
        self.stream.set_time_sequence("step", step as i64);
        self.stream.set_time(
            "sim_time",
            rerun::TimeCell::from_duration_nanos(step as i64 * self.dt_nanos),
        );
    }

    /// Logs the terrain as a static mesh coloured by height.
    pub fn log_terrain(&self, entity: &str, grid: &HeightGrid) -> Result<()> {
        let (vertices, triangles) = mesh(grid);
        let (lo, hi) = grid.height_bounds();
        let span = (hi - lo).max(1e-9);
        let colors: Vec<[u8; 3]> = vertices
            .iter()
            .map(|v| {
                let t = ((v[2] as f64 - lo) / span).clamp(0.0, 1.0);
                // earthy ramp: dark olive (low) to sand (high)
                let mix = |a: f64, b: f64| (a + (b - a) * t) as u8;
                [mix(70.0, 214.0), mix(92.0, 196.0), mix(50.0, 150.0)]
            })
            .collect();
        let normals: Vec<[f32; 3]> = vertices
            .iter()
            .map(|v| grid.normal(v[0] as f64, v[1] as f64).as_vec3().to_array())
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
    pub fn scalars(&self, entity: &str, values: &[f64]) -> Result<()> {
        self.stream
            .log(entity, &rerun::Scalars::new(values.iter().copied()))?;
        Ok(())
    }

    /// Pushes what has been logged so far to the file, so an interrupted run loses little.
    pub fn flush(&self) {
        let _ = self.stream.flush_blocking();
    }

    /// Completes the file (writes its footer) and moves it to its final name.
    pub fn finish(self) -> Result<PathBuf> {
        self.stream.flush_blocking().ok();
        drop(self.stream);
        commit(&self.path)?;
        Ok(self.path)
    }
}

/// The `rerun` viewer binary on PATH, if installed.
pub fn viewer_on_path() -> Option<PathBuf> {
    let exe = format!("rerun{}", std::env::consts::EXE_SUFFIX);
    let paths = std::env::var_os("PATH")?;
    std::env::split_paths(&paths)
        .map(|d| d.join(&exe))
        .find(|p| p.is_file())
}

/// Opens `file` in the rerun viewer, or explains how to install it.
pub fn spawn_viewer(file: &Path) -> Result<()> {
    match viewer_on_path() {
        Some(viewer) => {
            std::process::Command::new(viewer)
                .arg(file)
                .spawn()
                .context("cannot start the rerun viewer")?;
            Ok(())
        }
        None => anyhow::bail!(
            "the rerun viewer is not installed; install it with `pip install rerun-sdk==0.36.3` \
             (or `cargo binstall rerun-cli@0.36.3`), then open the recording with `rerun {}`",
            file.display()
        ),
    }
}

/// Reads a recording back and counts its messages: a recording that decodes to its end is one the
/// viewer can open (used to check that interrupted runs leave readable files).
pub fn count_messages(path: &std::path::Path) -> anyhow::Result<usize> {
    use rerun::external::re_log_encoding::DecoderApp;
    let file = std::fs::File::open(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot open: {e}", path.display()))?;
    let mut count = 0;
    for message in DecoderApp::decode_eager(std::io::BufReader::new(file))
        .map_err(|e| anyhow::anyhow!("{}: not a recording: {e}", path.display()))?
    {
        let _message =
            message.map_err(|e| anyhow::anyhow!("{}: message {count}: {e}", path.display()))?;
        count += 1;
    }
    Ok(count)
}
