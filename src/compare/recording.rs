//! The recording of a comparison (`hexsim compare`): every setting's ball or robot superposed in
//! one 3D view, each in its own colour and labelled with its setting's name, and their motion,
//! forces, penetration and energy on shared plots, one series per setting. Drawn from each run's
//! trajectory CSV after the runs, so the runs themselves stay plain scenario runs.

use super::{Comparison, Outcome};
use crate::record::blueprint::{History, Layout, View};
use crate::record::camera::{self, FollowCamera};
use crate::record::links::LinkTree;
use crate::record::rerun::Recording;
use crate::robot::RobotModel;
use anyhow::{Context, Result};
use glam::{DAffine3, DQuat, DVec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

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

/// What is plotted, per kind: a trajectory CSV column, or a quantity computed from its row.
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

/// One trajectory CSV, its columns by name.
struct Table {
    columns: HashMap<String, usize>,
    rows: Vec<Vec<f64>>,
}

impl Table {
    fn read(path: &Path) -> Result<Table> {
        let mut reader = csv::Reader::from_path(path)
            .with_context(|| format!("cannot read the trajectory {}", path.display()))?;
        let columns = reader
            .headers()?
            .iter()
            .enumerate()
            .map(|(k, h)| (h.to_string(), k))
            .collect();
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = record?;
            rows.push(
                record
                    .iter()
                    .map(|v| v.parse::<f64>().unwrap_or(f64::NAN))
                    .collect(),
            );
        }
        Ok(Table { columns, rows })
    }

    fn get(&self, row: &[f64], column: &str) -> f64 {
        self.columns.get(column).map_or(f64::NAN, |&k| row[k])
    }
}

fn layout(walk: bool, title: &str) -> Layout {
    let plots: &[&str] = if walk { &WALK_PLOTS } else { &BALL_PLOTS };
    let origins: Vec<String> = plots.iter().map(|p| format!("plots/{p}")).collect();
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

/// [`write`], its 3D view titled `title`.
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
    let robot = first.robot().map(|r| std::sync::Arc::new(r.clone()));
    let dt = first.spec.dt();
    let name = comparison
        .file
        .file_stem()
        .map_or("comparison".into(), |s| s.to_string_lossy().into_owned());
    let recording = Recording::create(path, name, dt, &layout(robot.is_some(), title))?;
    let rec = recording.stream();
    recording.log_terrain("world/terrain", &first.build_terrain()?)?;
    let size = match (&robot, first.ball()) {
        (Some(model), _) => crate::record::hexapod::robot_radius(model),
        (None, Some(ball)) => 10.0 * ball.radius,
        _ => 0.5,
    };
    rec.log_static("world/camera", &camera::pinhole(0.02f32))?;
    let plots: &[&str] = if robot.is_some() {
        &WALK_PLOTS
    } else {
        &BALL_PLOTS
    };
    let mut tables = Vec::new();
    let mut trees = Vec::new();
    for (k, outcome) in outcomes.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let entity = entity_name(&outcome.name);
        // a setting that could not run has no trajectory: it is in the table with its error
        let table = if outcome.report.is_ok() {
            Table::read(&outcome.trajectory)?
        } else {
            Table {
                columns: HashMap::new(),
                rows: Vec::new(),
            }
        };
        for plot in plots {
            rec.log_static(
                format!("plots/{plot}/{entity}"),
                &rerun::SeriesLines::new()
                    .with_names([outcome.name.as_str()])
                    .with_colors([color]),
            )?;
        }
        rec.log_static(
            format!("world/paths/{entity}"),
            &rerun::LineStrips3D::update_fields().with_colors([color]),
        )?;
        match (&robot, first.ball()) {
            (Some(model), _) => {
                let root = format!("world/{entity}/robot");
                trees.push(Some(LinkTree::log_tinted(rec, model, &root, Some(color))?));
            }
            (None, Some(ball)) => {
                rec.log_static(
                    format!("world/{entity}/ball"),
                    &rerun::Ellipsoids3D::from_radii([ball.radius as f32])
                        .with_colors([color])
                        .with_fill_mode(rerun::FillMode::Solid),
                )?;
                trees.push(None);
            }
            _ => trees.push(None),
        }
        rec.log_static(
            format!("world/{entity}/label"),
            &rerun::Points3D::update_fields()
                .with_colors([color])
                .with_radii([0.004f32])
                .with_labels([outcome.name.as_str()])
                .with_show_labels(true),
        )?;
        tables.push(table);
    }
    let mut recording = recording;
    // one camera for all, framing every setting's path (and the body's size)
    let (low, high) = tables
        .iter()
        .flat_map(|t| t.rows.iter().map(move |r| (t, r)))
        .map(|(t, r)| DVec3::new(t.get(r, "x"), t.get(r, "y"), t.get(r, "z")))
        .filter(|p| p.is_finite())
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    let spread = if low.is_finite() {
        0.5 * (high - low).truncate().length()
    } else {
        0.0
    };
    let mut camera = FollowCamera::new(size.max(spread), false);
    let overview = camera.follow(
        if low.is_finite() {
            0.5 * (low + high)
        } else {
            DVec3::ZERO
        },
        0.0,
        0.0,
    );
    recording
        .stream()
        .log_static("world/camera", &camera::transform(&overview))?;
    let steps = tables.iter().map(|t| t.rows.len()).max().unwrap_or(0);
    let mut last_point: Vec<Option<[f32; 3]>> = vec![None; outcomes.len()];
    for row in 0..steps {
        let mut shown = 0;
        for (k, (outcome, table)) in outcomes.iter().zip(&tables).enumerate() {
            let Some(values) = table.rows.get(row) else {
                continue;
            };
            let time = table.get(values, "time");
            if shown == 0 {
                recording.set_step((time / dt).round() as u64);
            }
            let rec = recording.stream();
            let position = DVec3::new(
                table.get(values, "x"),
                table.get(values, "y"),
                table.get(values, "z"),
            );
            shown += 1;
            let velocity = DVec3::new(
                table.get(values, "vx"),
                table.get(values, "vy"),
                table.get(values, "vz"),
            );
            let name = entity_name(&outcome.name);
            let point = position.as_vec3().to_array();
            if let Some(end) = last_point[k] {
                rec.log(
                    format!("world/paths/{name}"),
                    &rerun::LineStrips3D::new([[end, point]]),
                )?;
            }
            last_point[k] = Some(point);
            let label_at = match &robot {
                Some(model) => {
                    log_robot(rec, model, trees[k].as_ref(), table, values)?;
                    // stacked above the body, one line per setting, as the robots overlap
                    position + DVec3::Z * (size * (0.6 + 0.12 * k as f64))
                }
                None => {
                    rec.log(
                        format!("world/{name}/ball"),
                        &rerun::Transform3D::from_translation(point),
                    )?;
                    position + DVec3::Z * (size * (0.3 + 0.06 * k as f64))
                }
            };
            rec.log(
                format!("world/{name}/label"),
                &rerun::Points3D::new([label_at.as_vec3().to_array()]),
            )?;
            let value = |plot: &str| -> f64 {
                match plot {
                    "height" => position.z,
                    "speed" => velocity.length(),
                    "penetration_mm" => 1e3 * table.get(values, "penetration"),
                    "forward_x" => position.x,
                    "body_z" => table.get(values, "z"),
                    "roll_deg" => table.get(values, "roll").to_degrees(),
                    "pitch_deg" => table.get(values, "pitch").to_degrees(),
                    "feet_normal_force" => crate::robot::LEG_NAMES
                        .iter()
                        .map(|l| table.get(values, &format!("{l}_normal")))
                        .sum(),
                    // the feet's slip speeds summed: how much the stance feet slide
                    "feet_slip" => crate::robot::LEG_NAMES
                        .iter()
                        .map(|l| table.get(values, &format!("{l}_slip")))
                        .sum(),
                    other => table.get(values, other),
                }
            };
            for plot in plots {
                rec.log(
                    format!("plots/{plot}/{name}"),
                    &rerun::Scalars::new([value(plot)]),
                )?;
            }
        }
    }
    recording.finish()
}

/// A setting's name as an entity path part (spaces would need escaping).
fn entity_name(name: &str) -> String {
    name.replace(' ', "_")
}

/// Logs a robot's links at a trajectory row: the body's pose from its position and roll, pitch,
/// yaw (z-y-x), the links from the joint angles.
fn log_robot(
    rec: &rerun::RecordingStream,
    model: &RobotModel,
    tree: Option<&LinkTree>,
    table: &Table,
    values: &[f64],
) -> Result<()> {
    let Some(tree) = tree else {
        return Ok(());
    };
    let body = DAffine3::from_rotation_translation(
        DQuat::from_euler(
            glam::EulerRot::ZYX,
            table.get(values, "yaw"),
            table.get(values, "pitch"),
            table.get(values, "roll"),
        ),
        DVec3::new(
            table.get(values, "x"),
            table.get(values, "y"),
            table.get(values, "z"),
        ),
    );
    let q: Vec<f64> = model
        .joints
        .iter()
        .map(|j| table.get(values, &format!("{}_angle", j.name)))
        .collect();
    let frames: Vec<DAffine3> = model.link_poses(&q).into_iter().map(|f| body * f).collect();
    tree.log_frames(rec, model, &frames, false, false)
}
