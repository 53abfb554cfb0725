//! A scenario's expectations checked against its run's metrics, through the metrics tables.

use super::spec::{Expectations, Kind};
use crate::metrics::{self, Bound, Metric, Metrics, Side, Table};
use serde::{Deserialize, Serialize};

/// One expectation's verdict.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    pub expectation: String,
    /// The bound (absent for yes/no expectations).
    pub limit: Option<f64>,
    /// Which side of the limit the value must be.
    #[serde(default)]
    pub side: Option<Side>,
    /// The measured value, in the limit's unit (absent when the run did not produce it).
    pub value: Option<f64>,
    pub passed: bool,
}

/// The metric an expectation key bounds in `kind`'s table, or why there is none.
fn find<M: Table>(key: &str) -> Option<(&'static Metric<M>, Bound)> {
    metrics::bound_of(M::TABLE, key)
}

fn keys<M: Table>() -> impl Iterator<Item = &'static str> {
    M::TABLE.iter().flat_map(|m| m.bounds.iter().map(|b| b.key))
}

/// A least bound above a greatest on one metric (in its unit): no run meets both, which would
/// only show as a failure after the run.
fn contradiction<M: Table>(bounds: &std::collections::BTreeMap<String, f64>) -> Option<String> {
    for metric in M::TABLE {
        let set = |side: Side| {
            metric
                .bounds
                .iter()
                .filter(move |b| b.side == side)
                .filter_map(|b| Some((b, *bounds.get(b.key)?)))
        };
        for (least, low) in set(Side::Min) {
            for (most, high) in set(Side::Max) {
                if low / least.scale > high / most.scale {
                    return Some(format!(
                        "expect.{}: {} is above expect.{} = {}: no run can meet both",
                        least.key,
                        crate::limits::num(low),
                        most.key,
                        crate::limits::num(high)
                    ));
                }
            }
        }
    }
    None
}

impl Expectations {
    /// Checks that every expectation applies to `kind` and every limit is a finite number; the
    /// error names the expectation.
    pub fn validate(&self, kind: Kind) -> Result<(), String> {
        for (key, &limit) in &self.bounds {
            let (walk, ball) = (
                find::<metrics::HexapodMetrics>(key).is_some(),
                find::<metrics::BallMetrics>(key).is_some(),
            );
            let applies = match kind {
                Kind::Walk => walk,
                Kind::Ball => ball,
            };
            if !applies {
                if walk || ball {
                    let other = if walk { Kind::Walk } else { Kind::Ball };
                    return Err(format!(
                        "expect.{key}: applies to {other:?} scenarios, not to {kind:?} ones"
                    ));
                }
                let mut known: Vec<&str> = match kind {
                    Kind::Walk => keys::<metrics::HexapodMetrics>().collect(),
                    Kind::Ball => keys::<metrics::BallMetrics>().collect(),
                };
                known.extend(["no_divergence", "no_clamped_ik", "walk_as_commanded"]);
                return Err(format!(
                    "expect: unknown field `{key}`, expected one of {}",
                    known.join(", ")
                ));
            }
            if !limit.is_finite() {
                return Err(format!(
                    "expect.{key}: expected a finite number, got {limit}"
                ));
            }
        }
        let contradiction = match kind {
            Kind::Walk => contradiction::<metrics::HexapodMetrics>(&self.bounds),
            Kind::Ball => contradiction::<metrics::BallMetrics>(&self.bounds),
        };
        if let Some(message) = contradiction {
            return Err(message);
        }
        if self.no_clamped_ik && kind != Kind::Walk {
            return Err("expect.no_clamped_ik: applies to Walk scenarios only".into());
        }
        if self.walk_as_commanded.is_some() && kind != Kind::Walk {
            return Err("expect.walk_as_commanded: applies to Walk scenarios only".into());
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
                side: None,
                value: None,
                passed: !diverged,
            });
        }
        if self.no_clamped_ik
            && let Metrics::Walk(w) = metrics
        {
            checks.push(Check {
                expectation: "no_clamped_ik".into(),
                limit: None,
                side: None,
                value: Some(w.clamped_ik_steps as f64),
                passed: w.clamped_ik_steps == 0,
            });
        }
        if self.walk_as_commanded == Some(true)
            && let Metrics::Walk(w) = metrics
        {
            checks.push(Check {
                expectation: "walk_as_commanded".into(),
                limit: None,
                side: None,
                value: Some(w.walk_flags.len() as f64),
                passed: w.walk_flags.is_empty(),
            });
        }
        match metrics {
            Metrics::Walk(m) => self.check_bounds(m.as_ref(), &mut checks),
            Metrics::Ball(m) => self.check_bounds(m, &mut checks),
        }
        checks
    }

    /// The verdict on each bound that is set, in the order of the metrics table.
    fn check_bounds<M: Table>(&self, m: &M, checks: &mut Vec<Check>) {
        for metric in M::TABLE {
            for bound in metric.bounds {
                let Some(&limit) = self.bounds.get(bound.key) else {
                    continue;
                };
                let value = (metric.value)(m)
                    .bounded(bound.side)
                    .map(|v| v * bound.scale)
                    .filter(|v| v.is_finite());
                let passed = value.is_some_and(|v| match bound.side {
                    Side::Min => v >= limit,
                    Side::Max => v <= limit,
                });
                checks.push(Check {
                    expectation: bound.key.to_string(),
                    limit: Some(limit),
                    side: Some(bound.side),
                    value,
                    passed,
                });
            }
        }
    }
}
