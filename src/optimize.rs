//! `hexsim optimize FILE`: searches gait and servo parameters for the best walk on a set of
//! terrain seeds, by CMA-ES (the `fcmaes-core` crate's active CMA-ES, driven ask/tell so that
//! hexsim evaluates each generation's candidates in parallel, each run a plain scenario run).
//!
//! ```toml
//! scenario = "../scenarios/natural_tripod.toml"   # robot, gait, terrain, contact, start
//! duration = 8.0                                   # optional: overrides the scenario's
//! articulation = "impulse"                         # default: impulse joints, 4× faster
//! seeds = [11, 12, 13]                             # terrain seeds every candidate walks
//! generations = 12
//! seed = 1                                         # the search's own seed
//! [parameters]                                     # searched, within [low, high]
//! "gait.period" = [0.6, 1.4]
//! "gait.duty_factor" = [0.5, 0.75]
//! [objective]                                      # maximised: Σ weight · metric (mean over seeds)
//! forward_distance = 1.0
//! [constraints]                                    # the scenario's [expect] keys
//! max_tilt_deg = 15
//! ```
//!
//! Each candidate is the scenario with its parameters laid over it (the gait written inline); a
//! candidate that breaks a constraint, diverges or cannot stand on any seed ranks below every
//! one that does not, and the search goes on. Every evaluation is a line of the JSON Lines log.

use crate::metrics::{HexapodMetrics, Metrics, walk};
use crate::runner::Outputs;
use crate::scenario::{self, Scenario, ScenarioError};
use rayon::prelude::*;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The parameters that can be searched, and the values each accepts (exclusive bounds).
pub const PARAMETERS: &[(&str, f64, f64)] = &[
    ("gait.period", 0.0, f64::INFINITY),
    ("gait.duty_factor", 0.0, 1.0),
    ("gait.stride_length", 0.0, f64::INFINITY),
    ("gait.step_height", 0.0, f64::INFINITY),
    ("gait.stance_height", 0.0, f64::INFINITY),
    ("gait.reach", 0.0, f64::INFINITY),
    ("servo.stiffness", 0.0, f64::INFINITY),
    ("servo.damping", 0.0, f64::INFINITY),
];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OptimizeSpec {
    #[serde(default)]
    description: Option<String>,
    /// A scenario file, or a scenario written inline as a table (its paths relative to this file).
    scenario: toml::Value,
    #[serde(default)]
    duration: Option<f64>,
    #[serde(default = "impulse")]
    articulation: crate::sim::Articulation,
    seeds: Vec<u32>,
    /// Terrain seeds not searched on, on which the start and the best are checked after.
    #[serde(default)]
    check_seeds: Vec<u32>,
    #[serde(default = "default_generations")]
    generations: usize,
    #[serde(default)]
    population: Option<usize>,
    #[serde(default = "default_seed")]
    seed: u64,
    parameters: BTreeMap<String, [f64; 2]>,
    objective: BTreeMap<String, f64>,
    #[serde(default)]
    constraints: toml::Table,
}

fn impulse() -> crate::sim::Articulation {
    crate::sim::Articulation::Impulse
}

fn default_generations() -> usize {
    10
}

fn default_seed() -> u64 {
    1
}

/// An optimisation ready to run.
pub struct Optimization {
    pub file: PathBuf,
    pub description: Option<String>,
    /// The scenario's table, with the duration, articulation and constraints applied and its
    /// gait inline; candidates change its parameters.
    base: toml::Table,
    scenario_path: PathBuf,
    pub seeds: Vec<u32>,
    pub check_seeds: Vec<u32>,
    pub generations: usize,
    pub population: Option<usize>,
    pub seed: u64,
    /// (dotted path, low, high), in a fixed order.
    pub parameters: Vec<(String, f64, f64)>,
    pub objective: Vec<(String, f64)>,
    /// The starting point: the scenario's own values (its gait's as fitted), inside the bounds.
    pub start: Vec<f64>,
}

/// Reads an optimisation file; errors name the file and the field.
pub fn load(path: &Path) -> Result<Optimization, ScenarioError> {
    let fail = |message: String| ScenarioError {
        file: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| fail(format!("cannot read the optimisation file: {e}")))?;
    let spec: OptimizeSpec =
        toml::from_str(&text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
    if spec.seeds.is_empty() {
        return Err(fail("seeds: expected at least one terrain seed".into()));
    }
    if spec.generations == 0 {
        return Err(fail("generations: expected at least 1".into()));
    }
    if spec.population.is_some_and(|p| p < 2) {
        return Err(fail("population: expected at least 2".into()));
    }
    if spec.parameters.is_empty() {
        return Err(fail(
            "parameters: expected at least one, e.g. \"gait.period\" = [0.6, 1.4]".into(),
        ));
    }
    let mut parameters = Vec::new();
    for (name, [low, high]) in &spec.parameters {
        let Some(&(_, min, max)) = PARAMETERS.iter().find(|(p, _, _)| p == name) else {
            let known: Vec<&str> = PARAMETERS.iter().map(|(p, _, _)| *p).collect();
            return Err(fail(format!(
                "parameters.{name}: unknown parameter; expected one of {}",
                known.join(", ")
            )));
        };
        if !(low.is_finite() && high.is_finite() && low < high) {
            return Err(fail(format!(
                "parameters.{name}: expected [low, high] with low < high, got [{low}, {high}]"
            )));
        }
        if *low <= min || *high >= max {
            return Err(fail(format!(
                "parameters.{name}: [{low}, {high}] leaves what the field accepts: expected \
                 values in ({min}, {max})"
            )));
        }
        parameters.push((name.clone(), *low, *high));
    }
    if spec.objective.is_empty() {
        return Err(fail(
            "objective: expected at least one metric and its weight, e.g. forward_distance = 1"
                .into(),
        ));
    }
    for (name, weight) in &spec.objective {
        if !walk::TABLE.iter().any(|m| m.name == name) {
            let known: Vec<&str> = walk::TABLE.iter().map(|m| m.name).collect();
            return Err(fail(format!(
                "objective.{name}: unknown metric; expected one of {}",
                known.join(", ")
            )));
        }
        if !weight.is_finite() || *weight == 0.0 {
            return Err(fail(format!(
                "objective.{name}: expected a finite, non-zero weight, got {weight}"
            )));
        }
    }
    if let Some(d) = spec.duration
        && !(d.is_finite() && d > 0.0)
    {
        return Err(fail(format!(
            "duration: expected a finite number > 0 s, got {d}"
        )));
    }
    let (scenario_path, mut base) = match &spec.scenario {
        toml::Value::String(file) => scenario::read_table(path, Path::new(file)).map_err(fail)?,
        toml::Value::Table(table) => (path.to_path_buf(), table.clone()),
        _ => {
            return Err(fail(
                "scenario: expected a scenario file's name or an inline table".into(),
            ));
        }
    };
    if base.contains_key("sweep") || base.get("kind").and_then(|k| k.as_str()) == Some("ball") {
        return Err(fail(format!(
            "scenario {}: expected one walk scenario (no [sweep], not a ball)",
            scenario_path.display()
        )));
    }
    if let Some(d) = spec.duration {
        base.insert("duration".into(), toml::Value::Float(d));
    }
    base.insert(
        "articulation".into(),
        toml::Value::String(spec.articulation.name().into()),
    );
    base.insert(
        "expect".into(),
        toml::Value::Table(spec.constraints.clone()),
    );
    // the gait as an inline table, so candidates can change its fields
    let gait_text = match base.get("gait") {
        Some(toml::Value::String(file)) => {
            let gait_path = scenario_path.parent().unwrap_or(Path::new("")).join(file);
            std::fs::read_to_string(&gait_path).map_err(|e| {
                fail(format!(
                    "scenario's gait: cannot read {}: {e}",
                    gait_path.display()
                ))
            })?
        }
        Some(_) => String::new(),
        None => crate::scenario::builtin::TRIPOD.text.to_string(),
    };
    if !gait_text.is_empty() {
        let gait: toml::Table = gait_text
            .parse()
            .map_err(|e: toml::de::Error| fail(format!("scenario's gait: {e}")))?;
        base.insert("gait".into(), toml::Value::Table(gait));
    }
    // the start: the scenario's own values (resolved, so fitted lengths count), in the bounds
    let reference = resolve(&base, &scenario_path, "start", spec.seeds[0])
        .map_err(|e| fail(format!("the scenario as a start: {e}")))?;
    let start = parameters
        .iter()
        .map(|(name, low, high)| {
            let value = reference.gait().and_then(|g| match name.as_str() {
                "gait.period" => Some(g.period),
                "gait.duty_factor" => Some(g.duty_factor),
                "gait.stride_length" => Some(g.stride_length),
                "gait.step_height" => Some(g.step_height),
                "gait.stance_height" => Some(g.stance_height),
                "gait.reach" => Some(g.reach),
                _ => None,
            });
            value.unwrap_or(0.5 * (low + high)).clamp(*low, *high)
        })
        .collect();
    Ok(Optimization {
        file: path.to_path_buf(),
        description: spec.description,
        base,
        scenario_path,
        seeds: spec.seeds,
        check_seeds: spec.check_seeds,
        generations: spec.generations,
        population: spec.population,
        seed: spec.seed,
        parameters,
        objective: spec.objective.into_iter().collect(),
        start,
    })
}

/// The base table with `seed` and resolved as a scenario named `name`.
fn resolve(
    table: &toml::Table,
    scenario_path: &Path,
    name: &str,
    seed: u32,
) -> Result<Scenario, ScenarioError> {
    let mut table = table.clone();
    table.insert("seed".into(), toml::Value::Integer(seed.into()));
    scenario::from_table(table, name.to_string(), scenario_path)
}

impl Optimization {
    /// The scenario table of a candidate: its parameters laid over the base.
    pub fn candidate_table(&self, x: &[f64]) -> toml::Table {
        let mut table = self.base.clone();
        for ((name, _, _), &value) in self.parameters.iter().zip(x) {
            let (section, field) = name.split_once('.').expect("parameters are dotted");
            // the base's gait and servo are tables (load checked the gait; servo is made)
            let _ = scenario::overlay(
                &mut table,
                section,
                [(field.to_string(), toml::Value::Float(value))],
            );
        }
        table
    }

    /// The best candidate's gait, as a gait file's text.
    pub fn gait_file(&self, x: &[f64]) -> String {
        let table = self.candidate_table(x);
        match table.get("gait") {
            Some(toml::Value::Table(gait)) => toml::to_string(gait).unwrap_or_default(),
            _ => String::new(),
        }
    }

    /// Evaluates a candidate on every seed: its objective (the mean over seeds of Σ w·metric,
    /// maximised) or why it failed, and each seed's metrics.
    pub fn evaluate(&self, x: &[f64]) -> Evaluation {
        self.evaluate_on(x, &self.seeds, None)
    }

    /// [`Self::evaluate`] on `seeds`, in `articulation` if given (else the search's).
    pub fn evaluate_on(
        &self,
        x: &[f64],
        seeds: &[u32],
        articulation: Option<crate::sim::Articulation>,
    ) -> Evaluation {
        let mut table = self.candidate_table(x);
        if let Some(a) = articulation {
            table.insert("articulation".into(), toml::Value::String(a.name().into()));
        }
        let runs: Vec<Result<HexapodMetrics, String>> = seeds
            .par_iter()
            .map(|&seed| {
                let scenario = resolve(&table, &self.scenario_path, "candidate", seed)
                    .map_err(|e| e.message)?;
                let report = scenario
                    .run(Outputs::default())
                    .map_err(|e| format!("{e:#}"))?;
                if let Some(failure) = &report.failure {
                    return Err(format!("seed {seed}: {failure}"));
                }
                if let Some(check) = report.checks.iter().find(|c| !c.passed) {
                    let value = check.value.map_or("none".into(), |v| format!("{v:.4}"));
                    return Err(format!(
                        "seed {seed}: constraint {} not met ({value})",
                        check.expectation
                    ));
                }
                match report.metrics {
                    // stopped by Ctrl-C: not a result (the search stops and keeps the rest)
                    Metrics::Walk(m) if !m.complete => Err(INTERRUPTED.into()),
                    Metrics::Walk(m) => Ok(*m),
                    Metrics::Ball(_) => Err("not a walk".into()),
                }
            })
            .collect();
        let mut metrics = Vec::new();
        for run in runs {
            match run {
                Ok(m) => metrics.push(m),
                Err(reason) => {
                    return Evaluation {
                        objective: None,
                        failure: Some(reason),
                        metrics,
                    };
                }
            }
        }
        let objective = metrics.iter().map(|m| self.score(m)).sum::<f64>() / metrics.len() as f64;
        Evaluation {
            objective: Some(objective),
            failure: None,
            metrics,
        }
    }
}

impl Optimization {
    /// One run's Σ weight · metric.
    pub fn score(&self, m: &HexapodMetrics) -> f64 {
        self.objective
            .iter()
            .map(|(name, weight)| weight * metric_value(m, name))
            .sum()
    }
}

/// A metric's value (a per-foot list summed).
pub fn metric_value(m: &HexapodMetrics, name: &str) -> f64 {
    use crate::metrics::Value;
    walk::TABLE
        .iter()
        .find(|t| t.name == name)
        .map_or(f64::NAN, |t| match (t.value)(m) {
            Value::One(v) => v,
            Value::Each(vs) => vs.iter().sum(),
            Value::Absent => f64::NAN,
        })
}

/// The failure of an evaluation that Ctrl-C cut short.
pub const INTERRUPTED: &str = "interrupted";

/// One candidate's result.
pub struct Evaluation {
    /// Σ weight · metric, the mean over the seeds; None when it failed.
    pub objective: Option<f64>,
    pub failure: Option<String>,
    pub metrics: Vec<HexapodMetrics>,
}

impl Evaluation {
    /// Cut short by Ctrl-C: neither logged nor told to the optimiser.
    pub fn interrupted(&self) -> bool {
        self.failure.as_deref() == Some(INTERRUPTED)
    }
}
