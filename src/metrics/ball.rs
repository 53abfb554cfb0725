//! The ball experiment's metrics: bounces, penetration, energy, where it came to rest; written as
//! JSON, and their table.

use super::{Better, Bound, Metric, Table, Value};
use crate::record::Observer;
use crate::sim::BallSample;
use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// The ball run's summary, written as JSON.
#[derive(Debug, Clone, Serialize, Deserialize, Default)]
#[serde(default)]
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
    /// Where the metrics are written as JSON when the run ends, if anywhere.
    #[serde(skip)]
    output: Option<crate::record::metadata::MetricsFile>,
}

impl BallMetrics {
    /// Metrics of a ball of `radius` starting at `initial`; written to `output` at the end.
    pub fn new(
        initial: &BallSample,
        radius: f64,
        output: Option<crate::record::metadata::MetricsFile>,
    ) -> Self {
        BallMetrics {
            output,
            initial_energy: initial.total_energy(),
            lowest_energy: initial.total_energy(),
            final_energy: initial.total_energy(),
            final_position: initial.position.to_array(),
            radius,
            ..Default::default()
        }
    }
}

impl<W: ?Sized> Observer<BallSample, W> for BallMetrics {
    fn finish(&mut self, complete: bool) -> Result<Option<PathBuf>> {
        self.complete = complete;
        crate::record::metadata::write(self.output.as_ref(), self)
    }

    fn observe(&mut self, s: &BallSample, _: &W) -> Result<()> {
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

impl Table for BallMetrics {
    const TABLE: &'static [Metric<Self>] = TABLE;
}

/// Every metric of a ball run.
pub const TABLE: &[Metric<BallMetrics>] = &[
    Metric {
        name: "touchdowns",
        unit: "",
        what: "contact starts (a bounce, or the first touch of a roll)",
        noise: Some(1.0),
        better: Better::Neither,
        bounds: &[Bound::min("touchdowns_min")],
        value: |m| Value::One(m.touchdowns as f64),
    },
    Metric {
        name: "max_penetration",
        unit: "m",
        what: "deepest penetration of the ball into the ground",
        noise: Some(0.0002),
        better: Better::Lower,
        bounds: &[Bound::max("max_penetration_mm").scaled(1e3)],
        value: |m| Value::One(m.max_penetration),
    },
    Metric {
        name: "max_normal_force",
        unit: "N",
        what: "largest normal force",
        noise: Some(0.5),
        better: Better::Lower,
        bounds: &[],
        value: |m| Value::One(m.max_normal_force),
    },
    Metric {
        name: "max_speed",
        unit: "m/s",
        what: "largest speed of the centre",
        noise: None,
        better: Better::Neither,
        bounds: &[],
        value: |m| Value::One(m.max_speed),
    },
    Metric {
        name: "final_position",
        unit: "m",
        what: "x, y, z of the centre at the end",
        noise: Some(0.005),
        better: Better::Neither,
        bounds: &[],
        value: |m| Value::per_axis(&m.final_position),
    },
    Metric {
        name: "final_speed",
        unit: "m/s",
        what: "speed of the centre at the end",
        noise: Some(0.005),
        better: Better::Lower,
        bounds: &[Bound::max("final_speed_max")],
        value: |m| Value::One(m.final_speed),
    },
    Metric {
        name: "final_energy",
        unit: "J",
        what: "kinetic + potential + spring energy at the end",
        noise: Some(0.01),
        better: Better::Neither,
        bounds: &[],
        value: |m| Value::One(m.final_energy),
    },
    Metric {
        name: "max_energy_rise",
        unit: "J",
        what: "largest rise of the total energy above its running minimum (≈ 0: the contact is passive)",
        noise: Some(0.005),
        better: Better::Lower,
        bounds: &[Bound::max("max_energy_rise_j")],
        value: |m| Value::One(m.max_energy_rise),
    },
    Metric {
        name: "first_apex_height",
        unit: "m",
        what: "z of the lowest point at the first apex after the first bounce (flat ground: restitution = √(apex / drop))",
        noise: Some(0.002),
        better: Better::Neither,
        bounds: &[Bound::min("apex_min"), Bound::max("apex_max")],
        value: |m| m.first_apex_height.map_or(Value::Absent, Value::One),
    },
];
