//! The ball experiment's outputs: its rerun recording and its trajectory's columns (its metrics:
//! `crate::metrics`).

use super::background::Background;
use super::blueprint::{History, Layout, View};
use super::camera::{self, FollowCamera};
use super::rerun::Recording;
use super::table::RowOf;
use super::{Observer, Scene};
use crate::sim::{BallConfig, BallSample, BallSim};
use crate::terrain::HeightGrid;
use anyhow::Result;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Records the ball, its contact force, its path and time series to rerun, every `every` steps,
/// with a camera that follows the ball.
pub struct BallRecorder {
    recording: Recording,
    every: u64,
    /// Metres of drawn arrow per newton: the ball's weight gets an arrow four radii long.
    force_scale: f64,
    camera: FollowCamera,
    /// The last point of the path.
    path_end: Option<[f32; 3]>,
}

/// The viewer's default layout for the ball: the ball in 3D beside its plots.
fn layout() -> Layout {
    Layout::horizontal(
        vec![
            View::spatial_3d("ball", "world")
                .through_camera("world/camera")
                .with_history("world/path", History::Whole)
                .into(),
            Layout::tabs(vec![
                Layout::plots("energy", &["plots/energy", "plots/height"]),
                Layout::plots("contact", &["plots/force", "plots/penetration_mm"]),
                Layout::plots("motion", &["plots/speed", "plots/height"]),
            ]),
        ],
        vec![0.6, 0.4],
    )
}

impl BallRecorder {
    /// Creates the recording at `path` with its layout, the terrain and the ball.
    pub fn create(
        path: &Path,
        name: String,
        dt: f64,
        terrain: &HeightGrid,
        ball: &BallConfig,
        every: u64,
    ) -> Result<Self> {
        let recording = Recording::create(path, name, dt, &layout())?;
        recording.log_terrain("world/terrain", terrain)?;
        let rec = recording.stream();
        rec.log_static(
            "world/ball",
            &rerun::Ellipsoids3D::from_radii([ball.radius as f32])
                .with_colors([[220, 60, 40]])
                .with_fill_mode(rerun::FillMode::Solid),
        )?;
        rec.log_static("world/camera", &camera::pinhole(0.02f32))?;
        recording.name_series("plots/energy", &["kinetic", "potential", "spring", "total"])?;
        recording.name_series("plots/force", &["normal", "tangential"])?;
        let weight = ball.mass * ball.gravity.abs();
        Ok(BallRecorder {
            recording,
            every,
            force_scale: 4.0 * ball.radius / weight.max(1e-9),
            // as for a body twenty radii across: the ball, and the ground it rolls on around it
            camera: FollowCamera::new(10.0 * ball.radius, false),
            path_end: None,
        })
    }

    pub fn finish(self) -> Result<PathBuf> {
        self.recording.finish()
    }

    /// The recorder as an observer of a ball run, writing on its own thread (see
    /// [`super::background`]).
    pub fn in_background<W: ?Sized>(self) -> Background<BallSample, W, BallSample> {
        Background::spawn(
            self.every,
            |sample: &BallSample, _: &W| *sample,
            self,
            |r: &mut BallRecorder, sample: BallSample| r.record(&sample),
            BallRecorder::finish,
        )
    }

    /// Logs a sample.
    fn record(&mut self, s: &BallSample) -> Result<()> {
        self.recording.set_step(s.step);
        let r = &self.recording;
        let rec = r.stream();
        let position = s.position.as_vec3().to_array();
        rec.log(
            "world/ball",
            &rerun::Transform3D::from_translation(position),
        )?;
        let view = self
            .camera
            .follow(s.position, 0.0, r.dt() * self.every as f64);
        camera::log_pose(rec, "world/camera", &view)?;
        // one segment a sample; the view draws them all (History::Whole): linear in the run
        if let Some(end) = self.path_end {
            rec.log(
                "world/path",
                &rerun::LineStrips3D::new([[end, position]]).with_colors([[240, 200, 60]]),
            )?;
        }
        self.path_end = Some(position);
        // each face's force at its point (two in a riser's foot)
        let faces: Vec<_> = s.faces.iter().flatten().collect();
        if faces.is_empty() {
            rec.log("world/contact_force", &rerun::Clear::flat())?;
        } else {
            let scaled = |f: glam::DVec3| (f * self.force_scale).as_vec3().to_array();
            rec.log(
                "world/contact_force",
                &rerun::Arrows3D::from_vectors(faces.iter().map(|c| scaled(c.force)))
                    .with_origins(faces.iter().map(|c| c.point.as_vec3().to_array()))
                    .with_colors([[40, 120, 255]]),
            )?;
        }
        let (normal, tangential, depth) = s.contact.map_or((0.0, 0.0, 0.0), |c| {
            (c.normal_force, c.friction.length(), c.penetration)
        });
        r.scalars("plots/height", &[s.position.z])?;
        r.scalars("plots/speed", &[s.velocity.length()])?;
        r.scalars("plots/force", &[normal, tangential])?;
        r.scalars("plots/penetration_mm", &[depth * 1e3])?;
        r.scalars(
            "plots/energy",
            &[
                s.kinetic_energy,
                s.potential_energy,
                s.spring_energy,
                s.total_energy(),
            ],
        )?;
        Ok(())
    }
}

/// The ball run as its outputs see it: the recorder's set-up and the trajectory's columns.
pub struct BallScene {
    pub name: String,
    pub dt: f64,
    pub terrain: Arc<HeightGrid>,
    pub ball: BallConfig,
    pub every: u64,
}

/// The trajectory's columns.
pub const COLUMNS: [&str; 19] = [
    "time",
    "x",
    "y",
    "z",
    "vx",
    "vy",
    "vz",
    "wx",
    "wy",
    "wz",
    "fx",
    "fy",
    "fz",
    "normal_force",
    "penetration",
    "kinetic_energy",
    "potential_energy",
    "total_energy",
    "slip",
];

/// A sample's row, in the order of [`COLUMNS`].
fn row(s: &BallSample, row: &mut Vec<f64>) {
    let force = s.contact.map_or(glam::DVec3::ZERO, |c| c.force);
    let (normal, depth) = s
        .contact
        .map_or((0.0, 0.0), |c| (c.normal_force, c.penetration));
    row.extend([
        s.time,
        s.position.x,
        s.position.y,
        s.position.z,
        s.velocity.x,
        s.velocity.y,
        s.velocity.z,
        s.angular_velocity.x,
        s.angular_velocity.y,
        s.angular_velocity.z,
        force.x,
        force.y,
        force.z,
        normal,
        depth,
        s.kinetic_energy,
        s.potential_energy,
        s.total_energy(),
        s.contact.map_or(0.0, |c| c.slip.length()),
    ]);
}

impl Scene for BallScene {
    type Sample = BallSample;
    type World = BallSim;

    fn recorder(&self, path: &Path) -> Result<Box<dyn Observer<BallSample, BallSim>>> {
        let recorder = BallRecorder::create(
            path,
            self.name.clone(),
            self.dt,
            &self.terrain,
            &self.ball,
            self.every,
        )?;
        Ok(Box::new(recorder.in_background()))
    }

    fn columns(&self) -> (Vec<String>, RowOf<BallSample>) {
        (COLUMNS.map(String::from).to_vec(), row)
    }

    fn every(&self) -> u64 {
        self.every
    }
}
