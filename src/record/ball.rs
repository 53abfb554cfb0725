//! Observers for the ball experiment: rerun recording, trajectory CSV, summary metrics.

use super::Observer;
use super::rerun::Recording;
use super::table::CsvTable;
use crate::sim::BallSample;
use anyhow::Result;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Records the ball, its contact force and time series to rerun, every `every` steps.
pub struct BallRecorder {
    recording: Recording,
    every: u64,
    trail: Vec<[f32; 3]>,
}

impl BallRecorder {
    pub fn new(recording: Recording, radius: f64, every: u64) -> Result<Self> {
        let rec = recording.stream();
        rec.log_static(
            "world/ball",
            &rerun::Ellipsoids3D::from_radii([radius as f32])
                .with_colors([[220, 60, 40]])
                .with_fill_mode(rerun::FillMode::Solid),
        )?;
        recording.name_series("plots/energy", &["kinetic", "potential", "spring", "total"])?;
        recording.name_series("plots/force", &["normal", "tangential"])?;
        Ok(BallRecorder {
            recording,
            every,
            trail: Vec::new(),
        })
    }

    pub fn finish(self) -> Result<PathBuf> {
        self.recording.finish()
    }
}

impl Observer<BallSample> for BallRecorder {
    fn observe(&mut self, s: &BallSample) -> Result<()> {
        if !s.step.is_multiple_of(self.every) {
            return Ok(());
        }
        let r = &self.recording;
        r.set_step(s.step);
        let rec = r.stream();
        let position = s.position.as_vec3().to_array();
        rec.log(
            "world/ball",
            &rerun::Transform3D::from_translation(position),
        )?;
        self.trail.push(position);
        if self.trail.len() % 10 == 1 {
            rec.log(
                "world/path",
                &rerun::LineStrips3D::new([self.trail.clone()]).with_colors([[240, 200, 60]]),
            )?;
        }
        match &s.contact {
            Some(c) => rec.log(
                "world/contact_force",
                &rerun::Arrows3D::from_vectors([(c.force * 0.01).as_vec3().to_array()])
                    .with_origins([c.point.as_vec3().to_array()])
                    .with_colors([[40, 120, 255]]),
            )?,
            None => rec.log("world/contact_force", &rerun::Clear::flat())?,
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
        if s.step.is_multiple_of(1000) {
            r.flush();
        }
        Ok(())
    }
}

/// Writes every `every`-th sample as a CSV row.
pub struct BallTrajectory {
    table: CsvTable,
    every: u64,
}

impl BallTrajectory {
    pub const HEADER: [&str; 18] = [
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
    ];

    pub fn create(path: &Path, every: u64) -> Result<Self> {
        Ok(BallTrajectory {
            table: CsvTable::create(path, Self::HEADER)?,
            every,
        })
    }

    pub fn finish(self) -> Result<PathBuf> {
        self.table.finish()
    }
}

impl Observer<BallSample> for BallTrajectory {
    fn observe(&mut self, s: &BallSample) -> Result<()> {
        if !s.step.is_multiple_of(self.every) {
            return Ok(());
        }
        let force = s.contact.map_or(glam::DVec3::ZERO, |c| c.force);
        let (normal, depth) = s
            .contact
            .map_or((0.0, 0.0), |c| (c.normal_force, c.penetration));
        let row = [
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
        ];
        self.table.row(&row)
    }
}

/// The ball run's summary, written as JSON.
#[derive(Debug, Clone, Serialize, Default)]
pub struct BallMetrics {
    /// False when the run stopped early (interrupted or diverged).
    pub complete: bool,
    pub steps: u64,
    pub sim_time: f64,
    /// Number of touch-downs (contact starts).
    pub touchdowns: u64,
    pub max_penetration: f64,
    pub max_normal_force: f64,
    pub max_speed: f64,
    pub initial_energy: f64,
    pub final_energy: f64,
    /// Largest rise of total energy above its running minimum (J): the contact is passive when ~0.
    pub max_energy_rise: f64,
    pub final_position: [f64; 3],
    pub final_speed: f64,
    /// z of the ball's lowest point at the first apex after the first bounce, if there was one (on
    /// flat ground at z = 0 the restitution is √(apex / drop height)).
    pub first_apex_height: Option<f64>,
    #[serde(skip)]
    lowest_energy: f64,
    #[serde(skip)]
    was_in_contact: bool,
    #[serde(skip)]
    after_first_bounce: bool,
    #[serde(skip)]
    radius: f64,
}

impl BallMetrics {
    pub fn new(initial: &BallSample, radius: f64) -> Self {
        BallMetrics {
            initial_energy: initial.total_energy(),
            lowest_energy: initial.total_energy(),
            final_energy: initial.total_energy(),
            final_position: initial.position.to_array(),
            radius,
            ..Default::default()
        }
    }
}

impl Observer<BallSample> for BallMetrics {
    fn observe(&mut self, s: &BallSample) -> Result<()> {
        self.steps = s.step;
        self.sim_time = s.time;
        let in_contact = s.contact.is_some();
        if in_contact && !self.was_in_contact {
            self.touchdowns += 1;
        }
        if !in_contact && self.was_in_contact && self.touchdowns == 1 {
            self.after_first_bounce = true;
        }
        if self.after_first_bounce
            && self.touchdowns == 1
            && s.velocity.z <= 0.0
            && self.first_apex_height.is_none()
        {
            self.first_apex_height = Some(s.position.z - self.radius);
        }
        self.was_in_contact = in_contact;
        if let Some(c) = s.contact {
            self.max_penetration = self.max_penetration.max(c.penetration);
            self.max_normal_force = self.max_normal_force.max(c.normal_force);
        }
        let speed = s.velocity.length();
        self.max_speed = self.max_speed.max(speed);
        let energy = s.total_energy();
        self.max_energy_rise = self.max_energy_rise.max(energy - self.lowest_energy);
        self.lowest_energy = self.lowest_energy.min(energy);
        self.final_energy = energy;
        self.final_position = s.position.to_array();
        self.final_speed = speed;
        Ok(())
    }
}
