//! A scenario's expectations checked against its run's metrics.

use super::spec::{Expectations, Kind};
use crate::record::ball::BallMetrics;
use crate::record::hexapod::HexapodMetrics;
use serde::{Deserialize, Serialize};

/// A run's summary, by kind.
#[derive(Debug, Clone)]
pub enum Metrics {
    Walk(Box<HexapodMetrics>),
    Ball(BallMetrics),
}

impl Metrics {
    pub fn to_json(&self) -> serde_json::Value {
        match self {
            Metrics::Walk(m) => serde_json::to_value(m),
            Metrics::Ball(m) => serde_json::to_value(m),
        }
        .expect("metrics are plain numbers")
    }

    pub fn complete(&self) -> bool {
        match self {
            Metrics::Walk(m) => m.complete,
            Metrics::Ball(m) => m.complete,
        }
    }
}

/// One expectation's verdict.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    pub expectation: String,
    /// The bound (absent for yes/no expectations).
    pub limit: Option<f64>,
    /// The measured value (absent when the run did not produce it).
    pub value: Option<f64>,
    pub passed: bool,
}

#[derive(Clone, Copy)]
enum Bound {
    Min,
    Max,
}

type Getter = fn(&Metrics) -> Option<f64>;

/// An expectation with a bound: name, limit, which side, the kind it applies to (None: both), and
/// how to read the value from the metrics.
type Bounded = (&'static str, Option<f64>, Bound, Option<Kind>, Getter);

fn walk(m: &Metrics) -> Option<&HexapodMetrics> {
    match m {
        Metrics::Walk(m) => Some(m),
        Metrics::Ball(_) => None,
    }
}

fn ball(m: &Metrics) -> Option<&BallMetrics> {
    match m {
        Metrics::Ball(m) => Some(m),
        Metrics::Walk(_) => None,
    }
}

impl Expectations {
    /// Every bounded expectation.
    fn bounds(&self) -> [Bounded; 18] {
        use Bound::{Max, Min};
        use Kind::{Ball, Walk};
        [
            (
                "max_penetration_mm",
                self.max_penetration_mm,
                Max,
                None,
                |m| {
                    Some(
                        1e3 * walk(m).map_or_else(
                            || ball(m).unwrap().max_penetration,
                            |w| w.max_penetration,
                        ),
                    )
                },
            ),
            ("distance_min", self.distance_min, Min, Some(Walk), |m| {
                walk(m).map(|w| w.distance)
            }),
            ("distance_max", self.distance_max, Max, Some(Walk), |m| {
                walk(m).map(|w| w.distance)
            }),
            ("forward_min", self.forward_min, Min, Some(Walk), |m| {
                walk(m).map(|w| w.forward_distance)
            }),
            ("sideways_max", self.sideways_max, Max, Some(Walk), |m| {
                walk(m).map(|w| w.sideways_distance.abs())
            }),
            ("speed_min", self.speed_min, Min, Some(Walk), |m| {
                walk(m).map(|w| w.mean_speed)
            }),
            (
                "heading_change_min_deg",
                self.heading_change_min_deg,
                Min,
                Some(Walk),
                |m| walk(m).map(|w| w.heading_change_deg),
            ),
            (
                "heading_change_max_deg",
                self.heading_change_max_deg,
                Max,
                Some(Walk),
                |m| walk(m).map(|w| w.heading_change_deg),
            ),
            ("max_tilt_deg", self.max_tilt_deg, Max, Some(Walk), |m| {
                walk(m).map(|w| w.max_roll_deg.max(w.max_pitch_deg))
            }),
            (
                "max_foot_slip_mm",
                self.max_foot_slip_mm,
                Max,
                Some(Walk),
                |m| walk(m).map(|w| 1e3 * w.foot_slip.iter().fold(0.0_f64, |a, &b| a.max(b))),
            ),
            (
                "body_height_min",
                self.body_height_min,
                Min,
                Some(Walk),
                |m| walk(m).map(|w| w.body_height_mean),
            ),
            (
                "body_height_max",
                self.body_height_max,
                Max,
                Some(Walk),
                |m| walk(m).map(|w| w.body_height_mean),
            ),
            (
                "cost_of_transport_max",
                self.cost_of_transport_max,
                Max,
                Some(Walk),
                |m| walk(m).map(|w| w.cost_of_transport),
            ),
            (
                "touchdowns_min",
                self.touchdowns_min,
                Min,
                Some(Ball),
                |m| ball(m).map(|b| b.touchdowns as f64),
            ),
            (
                "max_energy_rise_j",
                self.max_energy_rise_j,
                Max,
                Some(Ball),
                |m| ball(m).map(|b| b.max_energy_rise),
            ),
            (
                "final_speed_max",
                self.final_speed_max,
                Max,
                Some(Ball),
                |m| ball(m).map(|b| b.final_speed),
            ),
            ("apex_min", self.apex_min, Min, Some(Ball), |m| {
                ball(m).and_then(|b| b.first_apex_height)
            }),
            ("apex_max", self.apex_max, Max, Some(Ball), |m| {
                ball(m).and_then(|b| b.first_apex_height)
            }),
        ]
    }

    /// Checks that every expectation applies to `kind` and every limit is a finite number; the
    /// error names the expectation.
    pub fn validate(&self, kind: Kind) -> Result<(), String> {
        for (name, limit, _, applies, _) in self.bounds() {
            let Some(limit) = limit else { continue };
            if let Some(applies) = applies
                && applies != kind
            {
                return Err(format!(
                    "expect.{name}: applies to {applies:?} scenarios, not to {kind:?} ones"
                ));
            }
            if !limit.is_finite() {
                return Err(format!(
                    "expect.{name}: expected a finite number, got {limit}"
                ));
            }
        }
        if self.no_clamped_ik && kind != Kind::Walk {
            return Err("expect.no_clamped_ik: applies to Walk scenarios only".into());
        }
        Ok(())
    }

    /// The verdict on each expectation that is set; `diverged` says the run ended in a
    /// non-finite state.
    pub fn check(&self, metrics: &Metrics, diverged: bool) -> Vec<Check> {
        let mut checks = Vec::new();
        if self.no_divergence {
            checks.push(Check {
                expectation: "no_divergence".into(),
                limit: None,
                value: None,
                passed: !diverged,
            });
        }
        if self.no_clamped_ik
            && let Some(w) = walk(metrics)
        {
            checks.push(Check {
                expectation: "no_clamped_ik".into(),
                limit: None,
                value: Some(w.clamped_ik_steps as f64),
                passed: w.clamped_ik_steps == 0,
            });
        }
        for (name, limit, bound, _, get) in self.bounds() {
            let Some(limit) = limit else { continue };
            let value = get(metrics).filter(|v| v.is_finite());
            let passed = value.is_some_and(|v| match bound {
                Bound::Min => v >= limit,
                Bound::Max => v <= limit,
            });
            checks.push(Check {
                expectation: name.to_string(),
                limit: Some(limit),
                value,
                passed,
            });
        }
        checks
    }
}
