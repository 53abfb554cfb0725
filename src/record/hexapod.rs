//! Observers for a hexapod run: rerun recording, trajectory CSV, summary metrics.

use super::Observer;
use super::rerun::Recording;
use super::table::CsvTable;
use crate::gait::LegPhase;
use crate::robot::{LEG_NAMES, RobotModel, Shape};
use crate::sim::WalkSample;
use anyhow::Result;
use glam::{DAffine3, DQuat};
use serde::Serialize;
use std::path::{Path, PathBuf};

fn quaternion(m: &DAffine3) -> rerun::Quaternion {
    rerun::Quaternion::from_xyzw(
        DQuat::from_mat3(&m.matrix3)
            .normalize()
            .as_quat()
            .to_array(),
    )
}

fn rgba(c: [f32; 4]) -> [u8; 4] {
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Records the robot (links with their URDF shapes), foot forces, the body's path and time series.
pub struct HexapodRecorder {
    recording: Recording,
    every: u64,
    link_paths: Vec<String>,
    path: Vec<[f32; 3]>,
}

/// Newtons per metre of drawn force arrow.
const FORCE_SCALE: f64 = 0.01;

impl HexapodRecorder {
    pub fn new(recording: Recording, model: &RobotModel, every: u64) -> Result<Self> {
        let rec = recording.stream();
        let mut link_paths = Vec::new();
        for link in &model.links {
            let entity = format!("world/robot/{}", link.name);
            for (k, visual) in link.visuals.iter().enumerate() {
                let shape_entity = format!("{entity}/visual_{k}");
                let mut origin = visual.origin;
                let color = rgba(visual.color);
                match &visual.shape {
                    Shape::Box { half_extents } => rec.log_static(
                        shape_entity.as_str(),
                        &rerun::Boxes3D::from_half_sizes([half_extents.as_vec3().to_array()])
                            .with_colors([color])
                            .with_fill_mode(rerun::FillMode::Solid),
                    )?,
                    Shape::Cylinder { radius, length } => rec.log_static(
                        shape_entity.as_str(),
                        &rerun::Cylinders3D::from_lengths_and_radii(
                            [*length as f32],
                            [*radius as f32],
                        )
                        .with_colors([color])
                        .with_fill_mode(rerun::FillMode::Solid),
                    )?,
                    Shape::Capsule { radius, length } => {
                        // rerun's capsule runs from its origin along +z; the URDF's is centred
                        origin *=
                            DAffine3::from_translation(glam::DVec3::new(0.0, 0.0, -length / 2.0));
                        rec.log_static(
                            shape_entity.as_str(),
                            &rerun::Capsules3D::from_lengths_and_radii(
                                [*length as f32],
                                [*radius as f32],
                            )
                            .with_colors([color])
                            .with_fill_mode(rerun::FillMode::Solid),
                        )?
                    }
                    Shape::Sphere { radius } => rec.log_static(
                        shape_entity.as_str(),
                        &rerun::Ellipsoids3D::from_radii([*radius as f32])
                            .with_colors([color])
                            .with_fill_mode(rerun::FillMode::Solid),
                    )?,
                    Shape::Mesh { path, .. } => match rerun::Asset3D::from_file_path(path) {
                        Ok(asset) => {
                            rec.log_static(shape_entity.as_str(), &asset.with_albedo_factor(color))?
                        }
                        Err(_) => rec.log_static(
                            shape_entity.as_str(),
                            &rerun::Ellipsoids3D::from_radii([0.01f32]).with_colors([color]),
                        )?,
                    },
                }
                rec.log_static(
                    shape_entity.as_str(),
                    &rerun::Transform3D::from_translation_rotation(
                        origin.translation.as_vec3().to_array(),
                        quaternion(&origin),
                    ),
                )?;
            }
            link_paths.push(entity);
        }
        recording.name_series("plots/body/attitude_deg", &["roll", "pitch", "yaw"])?;
        recording.name_series("plots/feet/normal_force", &LEG_NAMES)?;
        recording.name_series("plots/feet/in_contact", &LEG_NAMES)?;
        recording.name_series("plots/gait/stance", &LEG_NAMES)?;
        for leg in &model.legs {
            let names: Vec<String> = leg
                .joints
                .iter()
                .map(|&j| model.joints[j].name.clone())
                .collect();
            let mut series = names.clone();
            series.extend(names.iter().map(|n| format!("{n} target")));
            let refs: Vec<&str> = series.iter().map(String::as_str).collect();
            recording.name_series(&format!("plots/joints/{}/angle", leg.name), &refs)?;
            let refs: Vec<&str> = names.iter().map(String::as_str).collect();
            recording.name_series(&format!("plots/joints/{}/torque", leg.name), &refs)?;
        }
        Ok(HexapodRecorder {
            recording,
            every,
            link_paths,
            path: Vec::new(),
        })
    }

    pub fn finish(self) -> Result<PathBuf> {
        self.recording.finish()
    }

    /// Pushes what was logged so far to the file.
    pub fn flush(&self) {
        self.recording.flush();
    }
}

impl HexapodRecorder {
    /// Logs a sample; `link_frames` are the world poses of the model's links.
    pub fn observe_with(
        &mut self,
        s: &WalkSample,
        model: &RobotModel,
        link_frames: &[DAffine3],
    ) -> Result<()> {
        if !s.robot.step.is_multiple_of(self.every) {
            return Ok(());
        }
        let r = &self.recording;
        let rec = r.stream();
        r.set_step(s.robot.step);
        for (entity, frame) in self.link_paths.iter().zip(link_frames) {
            rec.log(
                entity.as_str(),
                &rerun::Transform3D::from_translation_rotation(
                    frame.translation.as_vec3().to_array(),
                    quaternion(frame),
                ),
            )?;
        }
        let (origins, vectors): (Vec<[f32; 3]>, Vec<[f32; 3]>) = s
            .robot
            .foot_contacts
            .iter()
            .flatten()
            .map(|c| {
                (
                    c.point.as_vec3().to_array(),
                    (c.force * FORCE_SCALE).as_vec3().to_array(),
                )
            })
            .unzip();
        rec.log(
            "world/foot_forces",
            &rerun::Arrows3D::from_vectors(vectors)
                .with_origins(origins)
                .with_colors([[40, 120, 255]]),
        )?;
        let body = s.robot.body.translation;
        self.path.push(body.as_vec3().to_array());
        if self.path.len() % 10 == 1 {
            rec.log(
                "world/body_path",
                &rerun::LineStrips3D::new([self.path.clone()]).with_colors([[240, 200, 60]]),
            )?;
        }
        let (roll, pitch, yaw) = s.robot.roll_pitch_yaw();
        r.scalars("plots/body/height_above_ground", &[s.robot.body_height])?;
        r.scalars(
            "plots/body/attitude_deg",
            &[roll.to_degrees(), pitch.to_degrees(), yaw.to_degrees()],
        )?;
        let forward = s.robot.body.matrix3.x_axis.dot(s.robot.body_velocity);
        r.scalars("plots/body/forward_speed", &[forward])?;
        let normal: Vec<f64> = s
            .robot
            .foot_contacts
            .iter()
            .map(|c| c.map_or(0.0, |c| c.normal_force))
            .collect();
        r.scalars("plots/feet/normal_force", &normal)?;
        let touching: Vec<f64> = s
            .robot
            .foot_contacts
            .iter()
            .map(|c| if c.is_some() { 1.0 } else { 0.0 })
            .collect();
        r.scalars("plots/feet/in_contact", &touching)?;
        if let Some(gait) = &s.gait {
            let stance: Vec<f64> = gait
                .phases
                .iter()
                .map(|p| if p.is_stance() { 1.0 } else { 0.0 })
                .collect();
            r.scalars("plots/gait/stance", &stance)?;
            let phase: Vec<f64> = gait
                .phases
                .iter()
                .map(|p| match p {
                    LegPhase::Stance(x) | LegPhase::Swing(x) => *x,
                })
                .collect();
            r.scalars("plots/gait/progress", &phase)?;
        }
        for leg in &model.legs {
            let mut values: Vec<f64> = leg
                .joints
                .iter()
                .map(|&j| s.robot.joint_angles[j])
                .collect();
            values.extend(leg.joints.iter().map(|&j| s.robot.joint_targets[j]));
            r.scalars(&format!("plots/joints/{}/angle", leg.name), &values)?;
            let torques: Vec<f64> = leg
                .joints
                .iter()
                .map(|&j| s.robot.joint_torques[j])
                .collect();
            r.scalars(&format!("plots/joints/{}/torque", leg.name), &torques)?;
        }
        if s.robot.step.is_multiple_of(self.every * 50) {
            r.flush();
        }
        Ok(())
    }
}

/// Writes every `every`-th step as a CSV row: time, body pose and velocity, joint angles, targets
/// and torques, and per foot its force and contact state.
pub struct HexapodTrajectory {
    table: CsvTable,
    every: u64,
}

impl HexapodTrajectory {
    pub fn create(path: &Path, model: &RobotModel, every: u64) -> Result<Self> {
        let mut header: Vec<String> = [
            "time", "x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz", "wx", "wy", "wz",
        ]
        .map(String::from)
        .to_vec();
        for suffix in ["angle", "target", "torque"] {
            header.extend(model.joints.iter().map(|j| format!("{}_{suffix}", j.name)));
        }
        for leg in LEG_NAMES {
            header.extend(["fx", "fy", "fz", "normal", "contact"].map(|q| format!("{leg}_{q}")));
        }
        Ok(HexapodTrajectory {
            table: CsvTable::create(path, header)?,
            every,
        })
    }

    pub fn finish(self) -> Result<PathBuf> {
        self.table.finish()
    }
}

impl Observer<WalkSample> for HexapodTrajectory {
    fn observe(&mut self, s: &WalkSample) -> Result<()> {
        let r = &s.robot;
        if !r.step.is_multiple_of(self.every) {
            return Ok(());
        }
        let (roll, pitch, yaw) = r.roll_pitch_yaw();
        let p = r.body.translation;
        let mut row = vec![
            r.time,
            p.x,
            p.y,
            p.z,
            roll,
            pitch,
            yaw,
            r.body_velocity.x,
            r.body_velocity.y,
            r.body_velocity.z,
            r.body_angular_velocity.x,
            r.body_angular_velocity.y,
            r.body_angular_velocity.z,
        ];
        row.extend(&r.joint_angles);
        row.extend(&r.joint_targets);
        row.extend(&r.joint_torques);
        for c in &r.foot_contacts {
            match c {
                Some(c) => row.extend([c.force.x, c.force.y, c.force.z, c.normal_force, 1.0]),
                None => row.extend([0.0; 5]),
            }
        }
        self.table.row(&row)
    }
}

/// A hexapod run's summary, written as JSON.
#[derive(Debug, Clone, Serialize, Default)]
pub struct HexapodMetrics {
    /// False when the run stopped early (interrupted or diverged).
    pub complete: bool,
    pub steps: u64,
    pub sim_time: f64,
    /// Seconds walked (after settling).
    pub walk_time: f64,
    /// Body displacement over the walk along the starting heading, across it, and in total (m).
    pub forward_distance: f64,
    pub sideways_distance: f64,
    pub distance: f64,
    pub mean_speed: f64,
    pub heading_change_deg: f64,
    pub max_roll_deg: f64,
    pub max_pitch_deg: f64,
    pub rms_roll_deg: f64,
    pub rms_pitch_deg: f64,
    /// Body height above the terrain under it (m).
    pub body_height_mean: f64,
    pub body_height_std: f64,
    /// Per foot: distance slid while on the ground (m).
    pub foot_slip: [f64; 6],
    /// Per foot: fraction of the walk on the ground.
    pub stance_fraction: [f64; 6],
    pub peak_normal_force: [f64; 6],
    pub mean_normal_force: [f64; 6],
    pub max_penetration: f64,
    /// Mechanical work done by the servos, ∫Σ|τ·q̇| dt (J), and the cost of transport E/(m·g·d).
    pub servo_energy: f64,
    pub cost_of_transport: f64,
    /// Steps in which some leg's target was out of reach and was clamped.
    pub clamped_ik_steps: u64,
    /// Impulse joints: the largest distance between a joint's two anchors (m) and rotation about
    /// a locked axis (deg) over the run; zero for the multibody.
    pub max_joint_drift: f64,
    pub max_joint_drift_deg: f64,
    #[serde(skip)]
    acc: Accumulators,
}

#[derive(Debug, Clone, Default)]
struct Accumulators {
    start: Option<(glam::DVec3, f64)>,
    walk_steps: u64,
    roll2: f64,
    pitch2: f64,
    height: f64,
    height2: f64,
    yaw_prev: f64,
    yaw_total: f64,
    stance_steps: [u64; 6],
    force_sum: [f64; 6],
    dt: f64,
    mass: f64,
}

impl HexapodMetrics {
    pub fn new(dt: f64, mass: f64) -> Self {
        HexapodMetrics {
            acc: Accumulators {
                dt,
                mass,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    pub fn set_clamped(&mut self, steps: u64) {
        self.clamped_ik_steps = steps;
    }
}

impl Observer<WalkSample> for HexapodMetrics {
    fn observe(&mut self, s: &WalkSample) -> Result<()> {
        let r = &s.robot;
        self.steps = r.step;
        self.sim_time = r.time;
        self.max_joint_drift = self.max_joint_drift.max(r.joint_drift.anchor);
        self.max_joint_drift_deg = self
            .max_joint_drift_deg
            .max(r.joint_drift.angle.to_degrees());
        if s.gait.is_none() {
            return Ok(()); // settling: not part of the walk
        }
        let a = &mut self.acc;
        let (roll, pitch, yaw) = r.roll_pitch_yaw();
        let position = r.body.translation;
        let (start, heading) = *a.start.get_or_insert((position, yaw));
        if a.walk_steps == 0 {
            a.yaw_prev = yaw;
        }
        a.walk_steps += 1;
        let dt = a.dt;
        // unwrap the yaw so turning several times is counted
        let mut dyaw = yaw - a.yaw_prev;
        dyaw -= (dyaw / std::f64::consts::TAU).round() * std::f64::consts::TAU;
        a.yaw_total += dyaw;
        a.yaw_prev = yaw;
        let moved = position - start;
        let (s_h, c_h) = heading.sin_cos();
        self.forward_distance = moved.x * c_h + moved.y * s_h;
        self.sideways_distance = -moved.x * s_h + moved.y * c_h;
        self.distance = moved.truncate().length();
        self.walk_time = a.walk_steps as f64 * dt;
        self.mean_speed = self.distance / self.walk_time;
        self.heading_change_deg = a.yaw_total.to_degrees();
        self.max_roll_deg = self.max_roll_deg.max(roll.abs().to_degrees());
        self.max_pitch_deg = self.max_pitch_deg.max(pitch.abs().to_degrees());
        a.roll2 += roll * roll;
        a.pitch2 += pitch * pitch;
        let n = a.walk_steps as f64;
        self.rms_roll_deg = (a.roll2 / n).sqrt().to_degrees();
        self.rms_pitch_deg = (a.pitch2 / n).sqrt().to_degrees();
        a.height += r.body_height;
        a.height2 += r.body_height * r.body_height;
        self.body_height_mean = a.height / n;
        self.body_height_std = (a.height2 / n - self.body_height_mean.powi(2))
            .max(0.0)
            .sqrt();
        for (k, c) in r.foot_contacts.iter().enumerate() {
            if let Some(c) = c {
                a.stance_steps[k] += 1;
                a.force_sum[k] += c.normal_force;
                self.foot_slip[k] += c.slip.length() * dt;
                self.peak_normal_force[k] = self.peak_normal_force[k].max(c.normal_force);
                self.max_penetration = self.max_penetration.max(c.penetration);
            }
            self.stance_fraction[k] = a.stance_steps[k] as f64 / n;
            self.mean_normal_force[k] = a.force_sum[k] / n;
        }
        let power: f64 = r
            .joint_torques
            .iter()
            .zip(&r.joint_velocities)
            .map(|(t, v)| (t * v).abs())
            .sum();
        self.servo_energy += power * dt;
        let weight_distance = a.mass * crate::sim::STANDARD_GRAVITY * self.distance;
        self.cost_of_transport = if weight_distance > 0.0 {
            self.servo_energy / weight_distance
        } else {
            0.0
        };
        Ok(())
    }
}
