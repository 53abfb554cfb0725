//! Baselines: a results file from an earlier batch; a metric that moved more than its tolerance is
//! a regression.

use super::results::Record;
use crate::scenario::Kind;
use crate::scenario::spec::Tolerance;
use std::collections::BTreeMap;

/// The metrics compared, with the absolute tolerance below which a change is noise (the relative
/// tolerance is the batch's default unless the scenario sets one).
const WALK: &[(&str, f64)] = &[
    ("distance", 0.01),
    ("forward_distance", 0.01),
    ("sideways_distance", 0.01),
    ("mean_speed", 0.001),
    ("heading_change_deg", 1.0),
    ("max_roll_deg", 0.5),
    ("max_pitch_deg", 0.5),
    ("rms_roll_deg", 0.25),
    ("rms_pitch_deg", 0.25),
    ("body_height_mean", 0.002),
    ("body_height_std", 0.001),
    ("max_penetration", 0.0002),
    ("foot_slip", 0.005),
    ("stance_fraction", 0.02),
    ("mean_normal_force", 0.2),
    ("servo_energy", 0.05),
    ("cost_of_transport", 0.05),
    ("clamped_ik_steps", 0.0),
];

const BALL: &[(&str, f64)] = &[
    ("touchdowns", 1.0),
    ("max_penetration", 0.0002),
    ("max_normal_force", 0.5),
    ("final_position", 0.005),
    ("final_speed", 0.005),
    ("final_energy", 0.01),
    ("max_energy_rise", 0.005),
    ("first_apex_height", 0.002),
];

/// A metric that moved beyond its tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct Regression {
    /// e.g. `distance`, `foot_slip[2]`.
    pub metric: String,
    /// None: the value appeared or disappeared (e.g. no apex any more).
    pub baseline: Option<f64>,
    pub value: Option<f64>,
    pub allowed: f64,
}

impl std::fmt::Display for Regression {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let show = |v: Option<f64>| v.map_or("none".to_string(), |v| format!("{v:.4}"));
        write!(
            f,
            "{} {} → {}",
            self.metric,
            show(self.baseline),
            show(self.value)
        )?;
        if let (Some(b), Some(v)) = (self.baseline, self.value) {
            write!(f, " ({:+.4}", v - b)?;
            if b != 0.0 {
                write!(f, ", {:+.1} %", 100.0 * (v - b) / b.abs())?;
            }
            write!(f, "; allowed ±{:.4})", self.allowed)?;
        }
        Ok(())
    }
}

/// Flattens a metric (a number, an array of numbers, or null) into named values.
fn values(name: &str, v: Option<&serde_json::Value>) -> Vec<(String, Option<f64>)> {
    match v {
        Some(serde_json::Value::Array(items)) => items
            .iter()
            .enumerate()
            .map(|(i, x)| (format!("{name}[{i}]"), x.as_f64()))
            .collect(),
        Some(x) => vec![(name.to_string(), x.as_f64())],
        None => vec![(name.to_string(), None)],
    }
}

/// Compares a result with its baseline. `default_rel` is the relative tolerance for metrics the
/// scenario sets none for; `tolerances` are the scenario's `[tolerance.METRIC]` (and
/// `[tolerance.default]`).
pub fn compare(
    record: &Record,
    baseline: &Record,
    default_rel: f64,
    tolerances: &BTreeMap<String, Tolerance>,
) -> Vec<Regression> {
    let metrics = match record.kind {
        Kind::Walk => WALK,
        Kind::Ball => BALL,
    };
    let fallback = tolerances.get("default");
    let mut regressions = Vec::new();
    for &(name, abs_floor) in metrics {
        let t = tolerances.get(name);
        let rel = t
            .and_then(|t| t.rel)
            .or(fallback.and_then(|t| t.rel))
            .unwrap_or(default_rel);
        let abs = t
            .and_then(|t| t.abs)
            .or(fallback.and_then(|t| t.abs))
            .unwrap_or(abs_floor);
        let now = values(name, record.metrics.get(name));
        let then = values(name, baseline.metrics.get(name));
        for ((metric, value), (_, base)) in now.into_iter().zip(then) {
            let allowed = base.map_or(abs, |b| (rel * b.abs()).max(abs));
            let moved = match (value, base) {
                (Some(v), Some(b)) => (v - b).abs() > allowed || v.is_nan() != b.is_nan(),
                (None, None) => false,
                _ => true,
            };
            if moved {
                regressions.push(Regression {
                    metric,
                    baseline: base,
                    value,
                    allowed,
                });
            }
        }
    }
    regressions
}
