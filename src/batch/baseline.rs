//! Baselines: a results file from an earlier batch; a metric that moved more than its tolerance is
//! a regression.

use super::results::Record;
use crate::metrics::{self, BallMetrics, HexapodMetrics, Table};
use crate::scenario::Kind;
use crate::scenario::spec::Tolerance;
use std::collections::BTreeMap;

/// A metric that moved beyond its tolerance.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Regression {
    /// e.g. `distance`, `foot_slip[lr]`.
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

/// Compares a result with its baseline, metric by metric of its kind's table (those with a noise
/// floor: the absolute tolerance below which a change is noise). `default_rel` is the relative
/// tolerance for metrics the scenario sets none for; `tolerances` are the scenario's
/// `[tolerance.METRIC]` (and `[tolerance.default]`).
pub fn compare(
    record: &Record,
    baseline: &Record,
    default_rel: f64,
    tolerances: &BTreeMap<String, Tolerance>,
) -> Vec<Regression> {
    match record.kind {
        Kind::Walk => compare_as::<HexapodMetrics>(record, baseline, default_rel, tolerances),
        Kind::Ball => compare_as::<BallMetrics>(record, baseline, default_rel, tolerances),
    }
}

fn compare_as<M: Table>(
    record: &Record,
    baseline: &Record,
    default_rel: f64,
    tolerances: &BTreeMap<String, Tolerance>,
) -> Vec<Regression> {
    // a result without metrics (an error) has every value absent
    let now: Option<M> = metrics::from_json(&record.metrics);
    let then: Option<M> = metrics::from_json(&baseline.metrics);
    let fallback = tolerances.get("default");
    let mut regressions = Vec::new();
    for metric in M::TABLE {
        let Some(abs_floor) = metric.noise else {
            continue;
        };
        let name = metric.name;
        let t = tolerances.get(name);
        let rel = t
            .and_then(|t| t.rel)
            .or(fallback.and_then(|t| t.rel))
            .unwrap_or(default_rel);
        let abs = t
            .and_then(|t| t.abs)
            .or(fallback.and_then(|t| t.abs))
            .unwrap_or(abs_floor);
        let values = |m: &Option<M>| match m {
            Some(m) => (metric.value)(m).flatten(name),
            None => metrics::Value::Absent.flatten(name),
        };
        let (now, then) = (values(&now), values(&then));
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
