//! `hexsim robot --record`: a still recording of a robot standing in a pose on level ground — its
//! links with their URDF shapes, the feet named as gait files name them, the walking direction,
//! and optionally each leg's reachable workspace as points — beside the text of the report, so a
//! user sees what hexsim made of their URDF before simulating it.

use super::blueprint::{Layout, View};
use super::camera::{self, FollowCamera};
use super::hexapod::robot_radius;
use super::links::LinkTree;
use super::rerun::Recording;
use crate::robot::RobotModel;
use crate::robot::kinematics::LegChain;
use crate::terrain;
use anyhow::Result;
use glam::{DAffine3, DVec3};
use std::path::{Path, PathBuf};

/// Samples per joint of a leg's workspace: 9³ = 729 points a leg, enough to see its shape; 16³
/// buried a robot whose joints turn ±150° (PhantomX) under 24 576 points.
pub const WORKSPACE_SAMPLES: usize = 9;

/// A workspace point's radius (m) and opacity: small and faint, so the robot shows through.
const WORKSPACE_POINT: (f32, u8) = (0.001, 110);

/// A colour per leg (`lf lm lr rf rm rr`): warm on the left, cool on the right.
const LEG_COLORS: [[u8; 3]; 6] = [
    [230, 80, 60],
    [240, 150, 40],
    [220, 200, 60],
    [60, 130, 230],
    [70, 190, 200],
    [140, 100, 220],
];

/// What to draw.
pub struct Standing<'a> {
    pub model: &'a RobotModel,
    /// Joint angles (indexed like the model's joints).
    pub pose: &'a [f64],
    /// Shown beside the 3D view (the `hexsim robot` report).
    pub report: &'a str,
    /// Draw each leg's reachable workspace.
    pub workspace: bool,
}

/// The body's frame standing level with its lowest foot on the ground (z = 0), given the links'
/// poses in the body frame (`RobotModel::link_poses`).
pub fn body_on_ground(model: &RobotModel, frames: &[DAffine3]) -> DAffine3 {
    let lowest = model
        .legs
        .iter()
        .map(|leg| frames[leg.foot_link].transform_point3(leg.foot.center).z - leg.foot.radius)
        .fold(f64::INFINITY, f64::min);
    let lift = if lowest.is_finite() { -lowest } else { 0.0 };
    DAffine3::from_translation(DVec3::new(0.0, 0.0, lift))
}

/// Each leg's foot positions (body frame) over a grid of `samples` angles per joint between its
/// limits: the volume the foot can reach.
pub fn workspace(model: &RobotModel, samples: usize) -> Vec<Vec<DVec3>> {
    let n = samples.max(2);
    model
        .legs
        .iter()
        .map(|leg| {
            let chain = LegChain::new(model, leg);
            let joints: Vec<&crate::robot::Joint> =
                leg.joints.iter().map(|&j| &model.joints[j]).collect();
            // a redundant leg's extra joints too, with fewer angles each: as many points as
            // a 3-joint leg's n³
            let per = ((n as f64).powf(3.0 / joints.len() as f64).floor() as usize).max(2);
            let at = |joint: &crate::robot::Joint, k: usize| {
                joint.lower + (joint.upper - joint.lower) * k as f64 / (per - 1) as f64
            };
            let count = per.pow(joints.len() as u32);
            let mut points = Vec::with_capacity(count);
            let mut q = vec![0.0; joints.len()];
            for index in 0..count {
                let mut digits = index;
                for (angle, joint) in q.iter_mut().zip(&joints).rev() {
                    *angle = at(joint, digits % per);
                    digits /= per;
                }
                points.push(chain.foot_position(&q));
            }
            points
        })
        .collect()
}

/// Where the camera looks from: ahead of the robot and to its left, a three-quarter view that
/// shows the front legs and the walking direction (degrees about z from the walking direction).
const CAMERA_BEARING_DEG: f64 = 35.0;

/// The viewer's layout: the robot in 3D beside the report.
fn layout() -> Layout {
    Layout::horizontal(
        vec![
            View::spatial_3d("robot standing", "world")
                .through_camera("world/camera")
                .into(),
            View::text_document("report", "report").into(),
        ],
        vec![0.6, 0.4],
    )
}

/// Writes the recording to `path`.
pub fn record(path: &Path, standing: &Standing) -> Result<PathBuf> {
    let model = standing.model;
    let recording = Recording::create_still(path, format!("{} standing", model.name), &layout())?;
    let rec = recording.stream();
    let in_body = model.link_poses(standing.pose);
    let body = body_on_ground(model, &in_body);
    let frames: Vec<DAffine3> = in_body.into_iter().map(|f| body * f).collect();
    let feet: Vec<DVec3> = model
        .legs
        .iter()
        .map(|leg| frames[leg.foot_link].transform_point3(leg.foot.center))
        .collect();
    // level ground a little wider than the feet's spread
    let spread = feet
        .iter()
        .map(|f| f.truncate().length())
        .fold(0.05, f64::max);
    let ground = terrain::flat([3.0 * spread, 3.0 * spread], [0.0, 0.0], 0.0)?;
    recording.log_terrain("world/ground", &ground)?;
    let links = LinkTree::log(rec, model, "world/robot")?;
    links.log_frames(rec, model, &frames, false, true)?;
    let names: Vec<&str> = model.legs.iter().map(|l| l.name).collect();
    rec.log_static(
        "world/feet",
        &rerun::Points3D::new(feet.iter().map(|f| f.as_vec3().to_array()))
            .with_radii(model.legs.iter().map(|l| l.foot.radius.max(0.003) as f32))
            .with_colors(LEG_COLORS.iter().take(names.len()).copied())
            .with_labels(names.iter().copied())
            .with_show_labels(true),
    )?;
    // from under the body out past the front feet, just above the ground
    rec.log_static(
        "world/walking_direction",
        &rerun::Arrows3D::from_vectors([[(1.4 * spread) as f32, 0.0, 0.0]])
            .with_origins([[0.0, 0.0, 0.002f32]])
            .with_colors([[250, 250, 250]])
            .with_labels(["walking direction"])
            .with_show_labels(true),
    )?;
    if standing.workspace {
        for ((leg, points), color) in model
            .legs
            .iter()
            .zip(workspace(model, WORKSPACE_SAMPLES))
            .zip(LEG_COLORS)
        {
            rec.log_static(
                format!("world/workspace/{}", leg.name),
                &rerun::Points3D::new(
                    points
                        .iter()
                        .map(|p| body.transform_point3(*p).as_vec3().to_array()),
                )
                .with_radii([WORKSPACE_POINT.0])
                .with_colors([[color[0], color[1], color[2], WORKSPACE_POINT.1]]),
            )?;
        }
    }
    // the same framing as a walk's follow camera, seen from ahead and to the left
    let bearing = CAMERA_BEARING_DEG.to_radians() + std::f64::consts::PI;
    // aimed at the hips rather than the base link's origin, which a URDF may put anywhere
    let hips = body.transform_point3(DVec3::new(0.0, 0.0, model.hips_plane()));
    let view = FollowCamera::new(robot_radius(model), true).follow(hips, bearing, 0.0);
    rec.log_static("world/camera", &camera::pinhole(0.05f32))?;
    rec.log_static("world/camera", &camera::transform(&view))?;
    // in a code block: monospace, lines kept as printed
    rec.log_static(
        "report",
        &rerun::TextDocument::new(format!("```\n{}\n```", standing.report))
            .with_media_type(rerun::MediaType::markdown()),
    )?;
    recording.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::fit;
    use crate::robot::kinematics::IK_TOLERANCE;

    /// In the tripod's fitted standing pose hex18 stands level on all six feet: each foot's lowest
    /// point on the ground, and its hips at the stance height above it (to the IK's tolerance).
    #[test]
    fn hex18_stands_on_all_six_feet_at_its_stance_height() {
        let model = crate::robot::hex18_for_tests();
        let spec = crate::gait::tripod_for_tests();
        let fitted = fit(&model, &spec).unwrap();
        let frames = model.link_poses(&fitted.standing_pose);
        let body = body_on_ground(&model, &frames);
        for leg in &model.legs {
            let foot = (body * frames[leg.foot_link]).transform_point3(leg.foot.center);
            assert!(
                (foot.z - leg.foot.radius).abs() < IK_TOLERANCE,
                "{}: {foot}",
                leg.name
            );
        }
        let hips = body.transform_point3(DVec3::new(0.0, 0.0, model.hips_plane()));
        assert!(
            (hips.z - fitted.gait.stance_height).abs() < IK_TOLERANCE,
            "{hips}"
        );
    }

    /// A leg's workspace spans its joints' limits: hex18's farthest sampled foot is the leg
    /// stretched out (all joints at zero lies on the grid when the limits are symmetric), and no
    /// sample lies farther from the hip than the leg is long.
    #[test]
    fn a_legs_workspace_reaches_as_far_as_the_leg_and_no_farther() {
        let model = crate::robot::hex18_for_tests();
        let spaces = workspace(&model, 5);
        for (leg, points) in model.legs.iter().zip(&spaces) {
            assert_eq!(points.len(), 125);
            let chain = LegChain::new(&model, leg);
            let length: f64 = crate::robot::statics::segment_lengths(&model, leg)
                .iter()
                .sum();
            let farthest = points
                .iter()
                .map(|p| (*p - chain.hip()).length())
                .fold(0.0, f64::max);
            assert!(
                (farthest - length).abs() < 1e-9,
                "{farthest} against {length}"
            );
        }
    }
}
