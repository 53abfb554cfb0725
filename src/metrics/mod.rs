//! What a run measured, one table per kind of run ([`walk::TABLE`], [`ball::TABLE`]): each
//! metric's name (its key in the metrics JSON), unit, how it is computed, the change below which
//! a baseline comparison calls it noise, whether lower or higher is better, and the expectations a
//! scenario can set on it. Expectations, baselines, printing and objectives read these tables, so
//! a new metric is its field, its computation and one entry here.

pub mod ball;
pub mod walk;

pub use ball::BallMetrics;
pub use walk::{GroundMetrics, HexapodMetrics, StanceMetrics};

use serde::de::DeserializeOwned;

/// Which way a metric is better.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Better {
    Lower,
    Higher,
    /// Neither: a quantity to watch, not to push (a heading change, a stance fraction).
    Neither,
}

/// Which side of its limit an expectation keeps a metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// value ≥ limit
    Min,
    /// value ≤ limit
    Max,
}

/// An expectation a scenario can set on a metric: `[expect] KEY = limit`.
#[derive(Debug, Clone, Copy)]
pub struct Bound {
    pub key: &'static str,
    pub side: Side,
    /// The limit's unit per the metric's (1e3: a limit in mm on a metric in m).
    pub scale: f64,
}

impl Bound {
    pub const fn min(key: &'static str) -> Self {
        Bound {
            key,
            side: Side::Min,
            scale: 1.0,
        }
    }

    pub const fn max(key: &'static str) -> Self {
        Bound {
            key,
            side: Side::Max,
            scale: 1.0,
        }
    }

    /// The same bound with its limit in `scale` of the metric's unit.
    pub const fn scaled(self, scale: f64) -> Self {
        Bound { scale, ..self }
    }
}

/// A metric's value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    One(f64),
    /// One per leg (lf lm lr rf rm rr) or per axis (x y z), with those names.
    Each(Vec<f64>, &'static [&'static str]),
    /// Not measured in this run (e.g. no apex when the ball never left the ground).
    Absent,
}

impl Value {
    /// The value an expectation bounds: a list's largest entry for a `Max` bound, its smallest for
    /// a `Min` one (every leg must meet it).
    pub fn bounded(&self, side: Side) -> Option<f64> {
        match self {
            Value::One(v) => Some(*v),
            Value::Each(vs, _) => match side {
                Side::Max => vs.iter().copied().reduce(f64::max),
                Side::Min => vs.iter().copied().reduce(f64::min),
            },
            Value::Absent => None,
        }
    }

    /// One value per leg, named by the legs (the per-foot lists' order).
    pub fn per_leg(values: &[f64; 6]) -> Self {
        Value::Each(values.to_vec(), &crate::robot::LEG_NAMES)
    }

    /// One value per axis, x y z.
    pub fn per_axis(values: &[f64; 3]) -> Self {
        Value::Each(values.to_vec(), &["x", "y", "z"])
    }

    /// Named scalars: `name` itself, or `name[entry]` for each entry of a list (`foot_slip[lf]`,
    /// `final_position[z]`).
    pub fn flatten(&self, name: &str) -> Vec<(String, Option<f64>)> {
        match self {
            Value::One(v) => vec![(name.to_string(), Some(*v))],
            Value::Each(vs, labels) => vs
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    let entry = labels.get(i).map_or(i.to_string(), |l| l.to_string());
                    (format!("{name}[{entry}]"), Some(*v))
                })
                .collect(),
            Value::Absent => vec![(name.to_string(), None)],
        }
    }
}

/// One metric of the metrics `M` of a kind of run.
pub struct Metric<M> {
    /// Its key in the metrics JSON (or, for one derived from others, its name in messages).
    pub name: &'static str,
    pub unit: &'static str,
    /// How it is computed.
    pub what: &'static str,
    /// Compared with a baseline: changes up to this (in `unit`) are noise. None: not compared
    /// (derived from metrics that are, or too noisy to compare).
    pub noise: Option<f64>,
    pub better: Better,
    /// The expectations a scenario can set on it.
    pub bounds: &'static [Bound],
    pub value: fn(&M) -> Value,
}

/// The metrics of one kind of run: its table, and the JSON it is written as.
pub trait Table: serde::Serialize + DeserializeOwned + Sized + 'static {
    const TABLE: &'static [Metric<Self>];
}

/// The metric of `table` an expectation key bounds, with its bound.
pub fn bound_of<M>(table: &'static [Metric<M>], key: &str) -> Option<(&'static Metric<M>, Bound)> {
    table
        .iter()
        .find_map(|m| m.bounds.iter().find(|b| b.key == key).map(|b| (m, *b)))
}

/// A run's metrics, by kind.
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

    pub fn steps(&self) -> u64 {
        match self {
            Metrics::Walk(m) => m.steps,
            Metrics::Ball(m) => m.steps,
        }
    }
}

/// Reads metrics back from their JSON (a results file's record): missing fields are zero, so a
/// file from an older hexsim still reads.
pub fn from_json<M: Table>(json: &serde_json::Value) -> Option<M> {
    serde_json::from_value(json.clone()).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every metric compared with baselines is a key of the JSON (so old results files read), and
    /// every expectation key is the table's once.
    fn consistent<M: Table + Default>() {
        let json = serde_json::to_value(M::default()).unwrap();
        let mut keys = std::collections::BTreeSet::new();
        for metric in M::TABLE {
            if metric.noise.is_some() {
                assert!(
                    json.get(metric.name).is_some(),
                    "{} is not in the JSON",
                    metric.name
                );
            }
            for bound in metric.bounds {
                assert!(keys.insert(bound.key), "{} bounds two metrics", bound.key);
                let (found, _) = bound_of(M::TABLE, bound.key).unwrap();
                assert_eq!(found.name, metric.name);
            }
        }
    }

    #[test]
    fn the_tables_match_their_json_and_their_keys_are_unique() {
        consistent::<HexapodMetrics>();
        consistent::<BallMetrics>();
    }

    #[test]
    fn a_bound_on_a_list_holds_for_every_entry() {
        let legs = Value::per_leg(&[0.2, 0.5, 0.1, 0.3, 0.3, 0.3]);
        assert_eq!(legs.bounded(Side::Max), Some(0.5));
        assert_eq!(legs.bounded(Side::Min), Some(0.1));
        assert_eq!(Value::Absent.bounded(Side::Max), None);
        assert_eq!(
            legs.flatten("foot_slip")[2],
            ("foot_slip[lr]".to_string(), Some(0.1))
        );
        assert_eq!(
            Value::per_axis(&[1.0, 2.0, 3.0]).flatten("final_position")[2],
            ("final_position[z]".to_string(), Some(3.0))
        );
    }
}
