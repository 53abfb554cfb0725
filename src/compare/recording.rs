//! The recording of a comparison (`hexsim compare`): every setting's ball or robot superposed in
//! one 3D view, each in its own colour and labelled with its setting's name, and their motion,
//! forces, penetration and energy on shared plots, one series per setting. Drawn from each run's
//! trajectory (kept in memory) after the runs, so the runs themselves stay plain scenario runs.

use super::{Comparison, Outcome};
use crate::record::blueprint::{History, Layout, View};
use crate::record::camera::{self, FollowCamera};
use crate::record::links::LinkTree;
use crate::record::rerun::Recording;
use crate::record::table::Table;
use crate::robot::RobotModel;
use anyhow::{Context, Result};
use glam::{DAffine3, DQuat, DVec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A colour per setting, in the order of the comparison file.
pub const COLORS: [[u8; 3]; 8] = [
    [230, 80, 60],
    [60, 130, 230],
    [80, 190, 90],
    [240, 170, 40],
    [170, 90, 220],
    [60, 200, 200],
    [230, 90, 170],
    [150, 150, 150],
];

/// What is plotted, per kind: a trajectory column, or a quantity computed from its row.
const BALL_PLOTS: [&str; 6] = [
    "height",
    "speed",
    "total_energy",
    "normal_force",
    "penetration_mm",
    "slip",
];
const WALK_PLOTS: [&str; 6] = [
    "forward_x",
    "body_z",
    "roll_deg",
    "feet_normal_force",
    "feet_slip",
    "pitch_deg",
];

/// What the runs move: every setting's robot (the same model) or ball.
enum Kind {
    Robot(Arc<RobotModel>),
    Ball { radius: f64 },
}

/// The moving body and the size the camera frames and the labels stand above (the robot's
/// radius, or ten ball radii), found once.
struct Body {
    kind: Kind,
    size: f64,
}

impl Body {
    fn new(kind: Kind) -> Self {
        let size = match &kind {
            Kind::Robot(model) => crate::record::hexapod::robot_radius(model),
            Kind::Ball { radius } => 10.0 * radius,
        };
        Body { kind, size }
    }

    fn plots(&self) -> &'static [&'static str] {
        match self.kind {
            Kind::Robot(_) => &WALK_PLOTS,
            Kind::Ball { .. } => &BALL_PLOTS,
        }
    }
}

/// Where a plot's value comes from in a trajectory row.
enum Source {
    Height,
    Forward,
    Speed,
    /// A column times a factor (mm from m, degrees from radians, or as it is).
    Column(usize, f64),
    /// The sum of columns: the feet's normal forces, or their slip speeds.
    Sum(Vec<usize>),
}

/// A setting's trajectory with the columns the recording reads found once by name: a column the
/// run does not have is an error here, not a silent NaN in a plot.
struct Track<'a> {
    table: &'a Table,
    time: usize,
    position: [usize; 3],
    velocity: [usize; 3],
    /// Each plot's source, in the order of the body's plots.
    plots: Vec<Source>,
    /// A walk's roll, pitch, yaw and its joint angles by model joint.
    attitude: Option<[usize; 3]>,
    joints: Vec<usize>,
}

impl<'a> Track<'a> {
    fn new(table: &'a Table, body: &Body) -> Result<Self> {
        let col = |name: &str| table.column(name);
        let feet = |quantity: &str| -> Result<Vec<usize>> {
            crate::robot::LEG_NAMES
                .iter()
                .map(|l| col(&format!("{l}_{quantity}")))
                .collect()
        };
        let mut plots = Vec::new();
        for &plot in body.plots() {
            plots.push(match plot {
                "height" | "body_z" => Source::Height,
                "forward_x" => Source::Forward,
                "speed" => Source::Speed,
                "penetration_mm" => Source::Column(col("penetration")?, 1e3),
                "roll_deg" => Source::Column(col("roll")?, 1f64.to_degrees()),
                "pitch_deg" => Source::Column(col("pitch")?, 1f64.to_degrees()),
                "feet_normal_force" => Source::Sum(feet("normal")?),
                "feet_slip" => Source::Sum(feet("slip")?),
                other => Source::Column(col(other)?, 1.0),
            });
        }
        let (attitude, joints) = match &body.kind {
            Kind::Robot(model) => (
                Some([col("roll")?, col("pitch")?, col("yaw")?]),
                crate::record::joint_columns::joint_columns(model)
                    .iter()
                    .map(|j| col(&format!("{j}_angle")))
                    .collect::<Result<_>>()?,
            ),
            Kind::Ball { .. } => (None, Vec::new()),
        };
        Ok(Track {
            table,
            time: col("time")?,
            position: [col("x")?, col("y")?, col("z")?],
            velocity: [col("vx")?, col("vy")?, col("vz")?],
            plots,
            attitude,
            joints,
        })
    }

    fn vector(row: &[f64], [x, y, z]: [usize; 3]) -> DVec3 {
        DVec3::new(row[x], row[y], row[z])
    }

    fn position(&self, row: &[f64]) -> DVec3 {
        Self::vector(row, self.position)
    }

    /// Plot `k`'s value at `row`.
    fn plot(&self, k: usize, row: &[f64]) -> f64 {
        match &self.plots[k] {
            Source::Height => self.position(row).z,
            Source::Forward => self.position(row).x,
            Source::Speed => Self::vector(row, self.velocity).length(),
            Source::Column(c, factor) => row[*c] * factor,
            Source::Sum(columns) => columns.iter().map(|&c| row[c]).sum(),
        }
    }

    /// A walk's body pose at `row` from its position and roll, pitch, yaw (z-y-x), and the joint
    /// angles.
    fn pose(&self, row: &[f64]) -> Option<(DAffine3, Vec<f64>)> {
        let [roll, pitch, yaw] = self.attitude?;
        let body = DAffine3::from_rotation_translation(
            DQuat::from_euler(glam::EulerRot::ZYX, row[yaw], row[pitch], row[roll]),
            self.position(row),
        );
        Some((body, self.joints.iter().map(|&j| row[j]).collect()))
    }
}

fn layout(body: &Body, title: &str) -> Layout {
    let origins: Vec<String> = body.plots().iter().map(|p| format!("plots/{p}")).collect();
    let refs: Vec<&str> = origins.iter().map(String::as_str).collect();
    let (first, rest) = refs.split_at(refs.len().div_ceil(2));
    Layout::horizontal(
        vec![
            View::spatial_3d(title, "world")
                .through_camera("world/camera")
                .with_history("world/paths", History::Whole)
                .into(),
            Layout::tabs(vec![
                Layout::plots("motion", first),
                Layout::plots("contact", rest),
            ]),
        ],
        vec![0.55, 0.45],
    )
}

/// Writes the comparison's recording to `path` from the runs' trajectories.
pub fn write(path: &Path, comparison: &Comparison, outcomes: &[Outcome]) -> Result<PathBuf> {
    write_titled(path, "settings superposed", comparison, outcomes)
}

/// [`write`], its 3D view titled `title`: the terrain, each setting's body, label and series
/// styled in its colour, one camera framing every path, then the runs row by row.
pub fn write_titled(
    path: &Path,
    title: &str,
    comparison: &Comparison,
    outcomes: &[Outcome],
) -> Result<PathBuf> {
    let first = comparison
        .settings
        .first()
        .context("a comparison has settings")?;
    let body = Body::new(match (first.robot(), first.ball()) {
        (Some(model), _) => Kind::Robot(Arc::new(model.clone())),
        (None, Some(ball)) => Kind::Ball {
            radius: ball.radius,
        },
        (None, None) => anyhow::bail!("a comparison's scenario is a walk or a ball"),
    });
    let dt = first.spec.dt();
    let name = comparison
        .file
        .file_stem()
        .map_or("comparison".into(), |s| s.to_string_lossy().into_owned());
    let mut recording = Recording::create(path, name, dt, &layout(&body, title))?;
    recording.log_terrain("world/terrain", &first.build_terrain()?)?;
    recording
        .stream()
        .log_static("world/camera", &camera::pinhole(0.02f32))?;
    let mut tracks = Vec::new();
    let mut trees = Vec::new();
    for (k, outcome) in outcomes.iter().enumerate() {
        trees.push(log_setting(recording.stream(), &body, k, &outcome.name)?);
        // a setting that could not run has no trajectory: it is in the table with its error
        tracks.push(match outcome.report {
            Ok(_) => Some(
                Track::new(&outcome.trajectory, &body)
                    .with_context(|| format!("setting {:?}", outcome.name))?,
            ),
            Err(_) => None,
        });
    }
    let eye = frame_every_path(&recording, &tracks, body.size)?;
    let rows = tracks
        .iter()
        .flatten()
        .map(|t| t.table.rows.len())
        .max()
        .unwrap_or(0);
    let mut path_ends: Vec<Option<[f32; 3]>> = vec![None; outcomes.len()];
    for row in 0..rows {
        let mut stepped = false;
        for (k, track) in tracks.iter().enumerate() {
            let Some(values) = track.as_ref().and_then(|t| t.table.rows.get(row)) else {
                continue;
            };
            let track = track.as_ref().expect("a row has its track");
            if !stepped {
                recording.set_step((values[track.time] / dt).round() as u64);
                stepped = true;
            }
            let setting = Setting {
                entity: entity_name(&outcomes[k].name),
                index: k,
                eye,
                tree: trees[k].as_ref(),
            };
            log_row(
                &recording,
                &body,
                &setting,
                track,
                values,
                &mut path_ends[k],
            )?;
        }
    }
    recording.finish()
}

/// Logs setting `k`'s static parts in its colour: its series' names, its path's colour, its
/// body (a tinted copy of the robot, or a ball) and its label; the robot's link tree.
fn log_setting(
    rec: &rerun::RecordingStream,
    body: &Body,
    k: usize,
    name: &str,
) -> Result<Option<LinkTree>> {
    let color = COLORS[k % COLORS.len()];
    let entity = entity_name(name);
    for plot in body.plots() {
        rec.log_static(
            format!("plots/{plot}/{entity}"),
            &rerun::SeriesLines::new()
                .with_names([name])
                .with_colors([color]),
        )?;
    }
    rec.log_static(
        format!("world/paths/{entity}"),
        &rerun::LineStrips3D::update_fields().with_colors([color]),
    )?;
    let tree = match &body.kind {
        Kind::Robot(model) => {
            let root = format!("world/{entity}/robot");
            Some(LinkTree::log_tinted(rec, model, &root, Some(color))?)
        }
        Kind::Ball { radius } => {
            rec.log_static(
                format!("world/{entity}/ball"),
                &rerun::Ellipsoids3D::from_radii([*radius as f32])
                    .with_colors([color])
                    .with_fill_mode(rerun::FillMode::Solid),
            )?;
            None
        }
    };
    rec.log_static(
        format!("world/{entity}/label"),
        &rerun::Points3D::update_fields()
            .with_colors([color])
            .with_radii([0.004f32])
            .with_labels([name])
            .with_show_labels(true),
    )?;
    Ok(tree)
}

/// The height between two settings' labels, as a share of the body's distance from the camera:
/// about 1.5 label lines in the view (50° field of view, looking down 30°) wherever the body
/// is, so labels stand apart rather than under each other, and no farther.
const LABEL_STEP: f64 = 0.05;

/// One camera for all, still, framing every setting's path (and the body's size); returns where
/// it stands.
fn frame_every_path(recording: &Recording, tracks: &[Option<Track>], size: f64) -> Result<DVec3> {
    let (low, high) = tracks
        .iter()
        .flatten()
        .flat_map(|t| t.table.rows.iter().map(move |r| t.position(r)))
        .filter(|p| p.is_finite())
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    let (centre, spread) = if low.is_finite() {
        (0.5 * (low + high), 0.5 * (high - low).truncate().length())
    } else {
        (DVec3::ZERO, 0.0)
    };
    let framed = size.max(spread);
    let mut camera = FollowCamera::new(framed, false);
    let overview = camera.follow(centre, 0.0, 0.0);
    recording
        .stream()
        .log_static("world/camera", &camera::transform(&overview))?;
    Ok(overview.eye)
}

/// A setting as its rows are logged.
struct Setting<'a> {
    entity: String,
    /// Its place in the comparison: its colour, and its label's height above the others'.
    index: usize,
    /// Where the camera stands, for the labels' spacing.
    eye: DVec3,
    tree: Option<&'a LinkTree>,
}

/// Logs one setting's row: its path's next segment, its body (the robot's links from the
/// joint angles, or the ball), its label and its plots.
fn log_row(
    recording: &Recording,
    body: &Body,
    setting: &Setting,
    track: &Track,
    values: &[f64],
    path_end: &mut Option<[f32; 3]>,
) -> Result<()> {
    let rec = recording.stream();
    let name = &setting.entity;
    let position = track.position(values);
    let point = position.as_vec3().to_array();
    if let Some(end) = *path_end {
        rec.log(
            format!("world/paths/{name}"),
            &rerun::LineStrips3D::new([[end, point]]),
        )?;
    }
    *path_end = Some(point);
    let label_step = LABEL_STEP * setting.index as f64 * position.distance(setting.eye);
    let label_at = match &body.kind {
        Kind::Robot(model) => {
            if let (Some(tree), Some((pose, q))) = (setting.tree, track.pose(values)) {
                let frames: Vec<DAffine3> =
                    model.link_poses(&q).into_iter().map(|f| pose * f).collect();
                tree.log_frames(rec, model, &frames, false, false)?;
            }
            // stacked above the body, a line apart in the view, as the robots overlap
            position + DVec3::Z * (body.size * 0.6 + label_step)
        }
        Kind::Ball { .. } => {
            rec.log(
                format!("world/{name}/ball"),
                &rerun::Transform3D::from_translation(point),
            )?;
            position + DVec3::Z * (body.size * 0.3 + label_step)
        }
    };
    rec.log(
        format!("world/{name}/label"),
        &rerun::Points3D::new([label_at.as_vec3().to_array()]),
    )?;
    for (p, plot) in body.plots().iter().enumerate() {
        rec.log(
            format!("plots/{plot}/{name}"),
            &rerun::Scalars::new([track.plot(p, values)]),
        )?;
    }
    Ok(())
}

/// A setting's name as an entity path part (spaces would need escaping).
fn entity_name(name: &str) -> String {
    name.replace(' ', "_")
}
