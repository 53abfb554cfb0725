//! `hexsim optimize FILE`: searches gait and servo parameters for the best walk on a set of
//! terrain seeds, by CMA-ES (the `fcmaes-core` crate's active CMA-ES, driven ask/tell so that
//! hexsim evaluates each generation's candidates in parallel, each run a plain scenario run).
//!
//! ```toml
//! scenario = "../scenarios/natural_tripod.toml"   # robot, gait, terrain, contact, start
//! duration = 8.0                                   # optional: overrides the scenario's
//! articulation = "impulse"                         # default: impulse joints, about as fast
//! terrains = ["../terrains/natural.toml", "../terrains/slope.toml"]  # default: the scenario's
//! seeds = [11, 12, 13]                             # every terrain with every seed (once if unseeded)
//! generations = 12
//! seed = 1                                         # the search's own seed
//! [parameters]                                     # searched, within [low, high]
//! "gait.period" = [0.6, 1.4]
//! "gait.duty_factor" = [0.5, 0.75]
//! "gait.phase_offsets.rf" = [0.3, 0.7]             # a cycle fraction, taken modulo 1
//! "gait.swing" = ["sine", "cycloid"]               # a choice among names
//! "command.forward" = [0.05, 0.2]                  # the commanded speed (m/s)
//! [objective]                                      # maximised: Σ weight · metric (mean over seeds)
//! forward_distance = 1.0
//! [constraints]                                    # the scenario's [expect] keys
//! max_tilt_deg = 15
//! ```
//!
//! Each candidate is the scenario with its parameters laid over it (the gait written inline); a
//! candidate that breaks a constraint, diverges or cannot stand on any seed ranks below every
//! one that does not, and the search goes on. Every evaluation is a line of the JSON Lines log
//! (`log`), which is also what a resumed or sharded search replays.

pub mod check;
pub mod log;
mod parameters;
pub mod recording;
pub mod results;
pub mod search;

pub use parameters::{Domain, Parameter, searchable};
use parameters::{Range, parameter, start_point};

use crate::metrics::{HexapodMetrics, Metrics, walk};
use crate::runner::Outputs;
use crate::scenario::{self, Report, Scenario, ScenarioError};
use rayon::prelude::*;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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
    /// Terrain files (relative to this file) each candidate walks, each with every seed (once
    /// if it has no seed); default: the scenario's terrain.
    #[serde(default)]
    terrains: Option<Vec<PathBuf>>,
    /// Terrain seeds not searched on, on which the start and the best are checked after.
    #[serde(default)]
    check_seeds: Vec<u32>,
    #[serde(default = "default_generations")]
    generations: usize,
    #[serde(default)]
    population: Option<usize>,
    #[serde(default = "default_seed")]
    seed: u64,
    parameters: BTreeMap<String, Range>,
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
    /// Every file the search reads, with what it is: no output may be one of them.
    pub inputs: Vec<(&'static str, PathBuf)>,
    /// The digest of every file its walks read, by what it is and its name
    /// ([`crate::scenario::inputs`]): part of
    /// the fingerprint a resumed or sharded search is checked against.
    pub read: BTreeMap<String, String>,
    pub description: Option<String>,
    /// The scenario's table, with the duration, articulation and constraints applied and its
    /// gait inline; candidates change its parameters.
    base: toml::Table,
    scenario_path: PathBuf,
    /// Every (terrain, seed) walked: the searched ones first, then the check seeds'.
    pub cases: Vec<Case>,
    pub generations: usize,
    pub population: Option<usize>,
    pub seed: u64,
    /// In the file's (sorted) order.
    pub parameters: Vec<Parameter>,
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
    let text = crate::limits::read_to_string(path, crate::limits::TEXT_FILE_BYTES)
        .map_err(|e| fail(format!("cannot read the optimisation file: {e}")))?;
    let spec: OptimizeSpec =
        toml::from_str(&text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
    if spec.seeds.is_empty() {
        return Err(fail("seeds: expected at least one terrain seed".into()));
    }
    if let Some(seed) = spec.check_seeds.iter().find(|s| spec.seeds.contains(s)) {
        return Err(fail(format!(
            "check_seeds: seed {seed} is also searched (in seeds); a check is on terrains the search did not see"
        )));
    }
    if spec.terrains.as_ref().is_some_and(Vec::is_empty) {
        return Err(fail(
            "terrains: expected at least one terrain file (or leave it out: the scenario's)".into(),
        ));
    }
    if spec.generations == 0 {
        return Err(fail("generations: expected at least 1".into()));
    }
    let most = crate::limits::MAX_POPULATION;
    if let Some(p) = spec.population
        && !(2..=most).contains(&p)
    {
        return Err(fail(format!(
            "population: expected 2 to {most} candidates a generation, got {p}"
        )));
    }
    let evaluations = spec.generations as f64 * spec.population.unwrap_or(2) as f64;
    if evaluations > crate::limits::MAX_EVALUATIONS {
        return Err(fail(format!(
            "generations: {} generations of {} candidates are {} evaluations, more than the {} a \
             search runs (each is a walk on every terrain and seed)",
            spec.generations,
            spec.population
                .map_or("at least 2".into(), |p| p.to_string()),
            crate::limits::num(evaluations),
            crate::limits::num(crate::limits::MAX_EVALUATIONS)
        )));
    }
    if spec.parameters.is_empty() {
        return Err(fail(
            "parameters: expected at least one, e.g. \"gait.period\" = [0.6, 1.4]".into(),
        ));
    }
    let parameters = spec
        .parameters
        .iter()
        .map(|(name, range)| parameter(name, range))
        .collect::<Result<Vec<_>, _>>()
        .map_err(fail)?;
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
    if let Some(d) = spec.duration {
        crate::limits::check_number(d, crate::limits::Range::Positive, "s")
            .map_err(|e| fail(format!("duration: {e}")))?;
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
    let mut inputs = vec![
        ("optimisation file", path.to_path_buf()),
        ("scenario file", scenario_path.clone()),
    ];
    // the gait as an inline table, so candidates can change its fields
    let gait_text = match base.get("gait") {
        Some(toml::Value::String(file)) => {
            let gait_path = scenario_path.parent().unwrap_or(Path::new("")).join(file);
            inputs.push(("gait file", gait_path.clone()));
            crate::limits::read_to_string(&gait_path, crate::limits::TEXT_FILE_BYTES).map_err(
                |e| {
                    fail(format!(
                        "scenario's gait: cannot read {}: {e}",
                        gait_path.display()
                    ))
                },
            )?
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
    let searched = |name: &str| parameters.iter().any(|p| p.name == name);
    let commands = base.get("command").and_then(toml::Value::as_array);
    if searched("command.forward") && commands.is_some_and(|c| c.len() > 1) {
        return Err(fail(format!(
            "parameters.command.forward: the scenario {} has {} [[command]]s; expected at most \
             one, whose speed is searched",
            scenario_path.display(),
            commands.map_or(0, Vec::len)
        )));
    }
    let commanded = searched("command.forward")
        || commands.is_some_and(|c| c.iter().any(|c| c.get("forward").is_some()));
    if searched("gait.stride_length") && commanded {
        return Err(fail(
            "parameters.gait.stride_length: the speed is commanded ([[command]] forward), and a \
             stance's stride is that speed over the stance time; search command.forward or the \
             timing instead"
                .into(),
        ));
    }
    // each parameter's path laid over the scenario once, so a candidate's is never refused
    for p in &parameters {
        let mut table = base.clone();
        scenario::overlay::set(&mut table, &p.name, p.value(0.5))
            .map_err(|e| fail(format!("parameters.{}: {e}", p.name)))?;
    }
    // the start: the scenario's own values (resolved, so fitted lengths count), in the bounds
    let reference = resolve(&base, &scenario_path, "start", spec.seeds[0])
        .map_err(|e| fail(format!("the scenario as a start: {e}")))?;
    let mut read = BTreeMap::new();
    reference.read.named_into(&mut read);
    let cases = cases(&spec, path, &base, &scenario_path, &reference, &mut read).map_err(fail)?;
    let start = start_point(&parameters, &base, &reference);
    inputs.extend(
        reference
            .inputs()
            .into_iter()
            .filter(|(what, _)| *what != "scenario file"),
    );
    inputs.extend(
        cases
            .iter()
            .filter_map(|c| Some(("terrain file", c.terrain.clone()?))),
    );
    Ok(Optimization {
        inputs,
        read,
        file: path.to_path_buf(),
        description: spec.description,
        base,
        scenario_path,
        cases,
        generations: spec.generations,
        population: spec.population,
        seed: spec.seed,
        parameters,
        objective: spec.objective.into_iter().collect(),
        start,
    })
}

/// One walk of each candidate: a terrain and its seed.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The terrain file (absolute), or None for the scenario's own terrain.
    pub terrain: Option<PathBuf>,
    /// The terrain's name (its file's stem).
    pub terrain_name: String,
    pub seed: u32,
    /// Whether the terrain has a seed (natural, rough); one without is walked once.
    pub seeded: bool,
    /// Searched on, or a check after the search (`check_seeds`).
    pub searched: bool,
}

impl Case {
    /// "natural seed 11", or "bell" for a terrain without a seed.
    pub fn label(&self) -> String {
        if self.seeded {
            format!("{} seed {}", self.terrain_name, self.seed)
        } else {
            self.terrain_name.clone()
        }
    }

    /// A file name for its outputs: "natural-seed-11", "bell".
    pub fn file_stem(&self) -> String {
        self.label().replace(' ', "-")
    }
}

/// A terrain's short name: its file's stem ("natural" for "../terrains/natural.toml").
fn stem(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .map_or(name.to_string(), |s| s.to_string_lossy().into_owned())
}

/// Every terrain × seed of the specification (a terrain without a seed once, searched).
fn cases(
    spec: &OptimizeSpec,
    path: &Path,
    base: &toml::Table,
    scenario_path: &Path,
    reference: &Scenario,
    read: &mut BTreeMap<String, String>,
) -> Result<Vec<Case>, String> {
    let terrains: Vec<(Option<PathBuf>, String, bool)> = match &spec.terrains {
        None => vec![(
            None,
            stem(reference.terrain_name()),
            reference.seed.is_some(),
        )],
        Some(files) => files
            .iter()
            .map(|file| {
                let absolute =
                    std::path::absolute(path.parent().unwrap_or(Path::new("")).join(file))
                        .map_err(|e| format!("terrains: {}: {e}", file.display()))?;
                let mut table = base.clone();
                table.insert(
                    "terrain".into(),
                    toml::Value::String(absolute.to_string_lossy().into_owned()),
                );
                let scenario = resolve(&table, scenario_path, "start", spec.seeds[0])
                    .map_err(|e| format!("terrains: {}: {}", file.display(), e.message))?;
                scenario.read.named_into(read);
                Ok((
                    Some(absolute),
                    stem(scenario.terrain_name()),
                    scenario.seed.is_some(),
                ))
            })
            .collect::<Result<_, String>>()?,
    };
    let mut cases = Vec::new();
    for searched in [true, false] {
        let seeds = if searched {
            &spec.seeds
        } else {
            &spec.check_seeds
        };
        for (terrain, name, seeded) in &terrains {
            let seeds = if *seeded {
                &seeds[..]
            } else if searched {
                &spec.seeds[..1]
            } else {
                &[]
            };
            for &seed in seeds {
                cases.push(Case {
                    terrain: terrain.clone(),
                    terrain_name: name.clone(),
                    seed,
                    seeded: *seeded,
                    searched,
                });
            }
        }
    }
    Ok(cases)
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
    /// Candidates a generation: the file's `population`, else CMA-ES's default 4 + ⌊3 ln n⌋ for
    /// n parameters.
    pub fn population_size(&self) -> usize {
        let dim = self.parameters.len() as f64;
        self.population
            .unwrap_or((4.0 + 3.0 * dim.ln()).floor() as usize)
    }

    /// The optimisation file's stem, naming its recordings.
    pub fn name(&self) -> String {
        stem(&self.file.to_string_lossy())
    }

    /// The scenario table of a candidate: its parameters laid over the base (each checked
    /// when the search was loaded, so none is refused here).
    pub fn candidate_table(&self, x: &[f64]) -> Result<toml::Table, String> {
        let mut table = self.base.clone();
        for (p, &value) in self.parameters.iter().zip(x) {
            scenario::overlay::set(&mut table, &p.name, p.value(value))
                .map_err(|e| format!("parameters.{}: {e}", p.name))?;
        }
        Ok(table)
    }

    /// The candidate's parameters by name, as the scenario gets them (a choice by its name).
    pub fn values(&self, x: &[f64]) -> serde_json::Map<String, serde_json::Value> {
        self.parameters
            .iter()
            .zip(x)
            .map(|(p, &v)| {
                let value = match p.value(v) {
                    toml::Value::String(s) => serde_json::json!(s),
                    other => serde_json::json!(other.as_float()),
                };
                (p.name.clone(), value)
            })
            .collect()
    }

    /// The best candidate's gait, as a gait file's text; the searched values that are not the
    /// gait's (servo gains, the commanded speed) head it as comments saying where they go.
    pub fn gait_file(&self, x: &[f64]) -> String {
        let table = self.candidate_table(x).unwrap_or_default();
        let mut text = String::new();
        for (p, &v) in self.parameters.iter().zip(x) {
            let value = p.value(v);
            match p.name.split_once('.') {
                Some(("servo", field)) => {
                    text += &format!("# and the scenario's [servo] {field} = {value}\n")
                }
                Some(("command", field)) => {
                    text += &format!("# and the scenario's [[command]] {field} = {value}\n")
                }
                _ => {}
            }
        }
        if let Some(toml::Value::Table(gait)) = table.get("gait") {
            text += &toml::to_string(gait).unwrap_or_default();
        }
        text
    }

    /// The terrains and seeds searched on.
    pub fn searched(&self) -> Vec<&Case> {
        self.cases.iter().filter(|c| c.searched).collect()
    }

    /// Evaluates a candidate on every searched terrain and seed: its objective (the mean over
    /// them of Σ w·metric, maximised) or why it failed, and each one's metrics.
    pub fn evaluate(&self, x: &[f64]) -> Evaluation {
        self.evaluate_on(x, &self.searched(), None)
    }

    /// [`Self::evaluate`] on `cases`, in `articulation` if given (else the search's).
    pub fn evaluate_on(
        &self,
        x: &[f64],
        cases: &[&Case],
        articulation: Option<crate::sim::Articulation>,
    ) -> Evaluation {
        let runs: Vec<Result<HexapodMetrics, String>> = cases
            .par_iter()
            .map(|case| {
                let scenario = self
                    .scenario(x, case, articulation, "candidate")
                    .map_err(|e| e.message)?;
                judge(case, &scenario.run(Outputs::default()))
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
        // a metric the walk leaves undefined (the cost of transport of a robot that did not
        // move) fails the candidate rather than scoring it
        for (m, case) in metrics.iter().zip(cases) {
            if let Some((name, _)) = self
                .objective
                .iter()
                .find(|(name, _)| !metric_value(m, name).is_finite())
            {
                return Evaluation {
                    objective: None,
                    failure: Some(format!(
                        "{}: {name} is undefined for this walk (the robot did not move)",
                        case.label()
                    )),
                    metrics,
                };
            }
        }
        let objective = metrics.iter().map(|m| self.score(m)).sum::<f64>() / metrics.len() as f64;
        Evaluation {
            objective: Some(objective),
            failure: None,
            metrics,
        }
    }

    /// The candidate `x` as a scenario named `name` walking `case`, in `articulation` if given
    /// (else the search's).
    pub fn scenario(
        &self,
        x: &[f64],
        case: &Case,
        articulation: Option<crate::sim::Articulation>,
        name: &str,
    ) -> Result<Scenario, ScenarioError> {
        let mut table = self.candidate_table(x).map_err(|message| ScenarioError {
            file: self.file.clone(),
            message,
        })?;
        if let Some(a) = articulation {
            table.insert("articulation".into(), toml::Value::String(a.name().into()));
        }
        if let Some(terrain) = &case.terrain {
            table.insert(
                "terrain".into(),
                toml::Value::String(terrain.to_string_lossy().into_owned()),
            );
        }
        resolve(&table, &self.scenario_path, name, case.seed)
    }
}

/// A candidate's walk of `case`: its metrics, or why it counts as failed (it could not run,
/// diverged, broke a constraint, or Ctrl-C cut it short: [`INTERRUPTED`]).
pub fn judge(case: &Case, report: &anyhow::Result<Report>) -> Result<HexapodMetrics, String> {
    let label = case.label();
    let report = report.as_ref().map_err(|e| {
        // a set-up cut short by Ctrl-C (the terrain's generation) is an interruption
        if crate::interrupt::interrupted() {
            INTERRUPTED.to_string()
        } else {
            format!("{label}: {e:#}")
        }
    })?;
    if let Some(failure) = &report.failure {
        // a run whose set-up Ctrl-C cut short reports it as its failure (the terrain's
        // generation, "interrupted"): an interruption too, run again on --resume
        if crate::interrupt::interrupted() {
            return Err(INTERRUPTED.into());
        }
        return Err(format!("{label}: {failure}"));
    }
    if let Some(check) = report.checks.iter().find(|c| !c.passed) {
        let value = check.value.map_or("none".into(), |v| format!("{v:.4}"));
        return Err(format!(
            "{label}: constraint {} not met ({value})",
            check.expectation
        ));
    }
    match &report.metrics {
        // stopped by Ctrl-C: not a result (the search stops and keeps the rest)
        Metrics::Walk(m) if !m.complete => Err(INTERRUPTED.into()),
        // beyond the grid the ground is a flat apron: not the terrain the search is for
        Metrics::Walk(m) if m.time_off_terrain > 0.0 => Err(format!(
            "{label}: left the terrain's grid for {:.2} s (walked onto the flat apron beyond it)",
            m.time_off_terrain
        )),
        Metrics::Walk(m) => Ok((**m).clone()),
        Metrics::Ball(_) => Err("not a walk".into()),
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
            Value::Each(vs, _) => vs.iter().sum(),
            Value::Absent => f64::NAN,
        })
}

/// The failure of an evaluation that Ctrl-C cut short.
pub const INTERRUPTED: &str = "interrupted";

/// One candidate's result.
pub struct Evaluation {
    /// Σ weight · metric, the mean over the terrains and seeds; None when it failed.
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A robot that did not move has no cost of transport (not 0, which a minimising search would
    /// reward): the metric reads as undefined, a constraint on it is not met, and `evaluate`
    /// fails such a candidate.
    #[test]
    fn the_cost_of_transport_of_a_robot_that_did_not_move_is_undefined() {
        let mut still = HexapodMetrics::default();
        still.servo_energy = 3.0;
        assert_eq!(still.cost_of_transport, None);
        assert!(metric_value(&still, "cost_of_transport").is_nan());
        let mut moved = HexapodMetrics::default();
        moved.cost_of_transport = Some(0.5);
        assert_eq!(metric_value(&moved, "cost_of_transport"), 0.5);
        let expect: crate::scenario::spec::Expectations =
            toml::from_str("cost_of_transport_max = 1.0").unwrap();
        let checks = expect.check(&crate::metrics::Metrics::Walk(Box::new(still)), false);
        let check = checks
            .iter()
            .find(|c| c.expectation == "cost_of_transport_max")
            .unwrap();
        assert!(!check.passed && check.value.is_none());
    }
}
