//! The search's log: one JSON line per evaluation (`evaluations.jsonl`), the record a search
//! resumes from, and the shard files (`shard-I-of-N.jsonl`) in which the array jobs of a cluster
//! each log their slice of a generation, to be joined by the next step.

use super::{Evaluation, Optimization};
use crate::batch::Shard;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The main log in an output folder.
pub fn main_file(dir: &Path) -> PathBuf {
    dir.join("evaluations.jsonl")
}

/// The file in which `shard` logs its evaluations.
pub fn shard_file(dir: &Path, shard: Shard) -> PathBuf {
    dir.join(format!("shard-{}-of-{}.jsonl", shard.index, shard.count))
}

/// One evaluation's log line: the parameters as the scenario got them (a choice by its name),
/// the search's coordinates `x` (what a resumed search matches), the objective or why it failed,
/// and the objective's metrics on each terrain and seed.
pub fn line(
    opt: &Optimization,
    generation: usize,
    index: usize,
    x: &[f64],
    e: &Evaluation,
) -> String {
    let metrics: Vec<serde_json::Value> = opt
        .searched()
        .iter()
        .zip(&e.metrics)
        .map(|(case, m)| {
            let mut named = serde_json::Map::new();
            named.insert("terrain".into(), serde_json::json!(case.label()));
            for (name, _) in &opt.objective {
                named.insert(
                    name.clone(),
                    serde_json::json!(super::metric_value(m, name)),
                );
            }
            serde_json::Value::Object(named)
        })
        .collect();
    serde_json::json!({
        "generation": generation,
        "index": index,
        "parameters": opt.values(x),
        "x": x,
        "objective": e.objective,
        "status": if e.failure.is_some() { "failed" } else { "ok" },
        "failure": e.failure,
        "metrics": metrics,
    })
    .to_string()
}

/// A logged evaluation.
pub struct Entry {
    pub x: Vec<f64>,
    pub objective: Option<f64>,
    pub failure: Option<String>,
    /// The line as logged, copied into the main log when it came from a shard file.
    pub line: String,
    /// Whether it is in the main log already.
    pub in_main: bool,
}

impl Entry {
    /// The result it logged (the per-seed metrics are only in the line).
    pub fn evaluation(&self) -> Evaluation {
        Evaluation {
            objective: self.objective,
            failure: self.failure.clone(),
            metrics: Vec::new(),
        }
    }
}

/// The evaluations logged in an output folder, by (generation, index).
#[derive(Default)]
pub struct Logged(HashMap<(usize, usize), Entry>);

impl Logged {
    /// Reads the main log and every shard file in `dir` (the main log's line wins); a line cut
    /// off by a kill, or one of another search's dimension, is skipped.
    pub fn read(dir: &Path, opt: &Optimization) -> std::io::Result<Logged> {
        let mut files = vec![(main_file(dir), true)];
        let mut shards: Vec<PathBuf> = match std::fs::read_dir(dir) {
            Ok(entries) => entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with("shard-") && n.ends_with(".jsonl"))
                })
                .collect(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => return Err(e),
        };
        shards.sort();
        files.extend(shards.into_iter().map(|p| (p, false)));
        let mut logged = Logged::default();
        for (file, in_main) in files {
            let Ok(text) = std::fs::read_to_string(&file) else {
                continue;
            };
            for line in text.lines() {
                let Some((key, entry)) = parse(line, opt, in_main) else {
                    continue;
                };
                logged.0.entry(key).or_insert(entry);
            }
        }
        Ok(logged)
    }

    /// The logged evaluation of candidate `x` at (generation, index), if the log has this very
    /// candidate (the same specification and seed ask for the same ones).
    pub fn get(&self, generation: usize, index: usize, x: &[f64]) -> Option<&Entry> {
        self.0.get(&(generation, index)).filter(|e| same(&e.x, x))
    }
}

fn parse(line: &str, opt: &Optimization, in_main: bool) -> Option<((usize, usize), Entry)> {
    let v: serde_json::Value = serde_json::from_str(line).ok()?;
    let at = |k: &str| v[k].as_u64().map(|n| n as usize);
    let key = (at("generation")?, at("index")?);
    let x: Vec<f64> = v["x"]
        .as_array()?
        .iter()
        .map(serde_json::Value::as_f64)
        .collect::<Option<_>>()?;
    if x.len() != opt.parameters.len() {
        return None;
    }
    Some((
        key,
        Entry {
            x,
            objective: v["objective"].as_f64(),
            failure: v["failure"].as_str().map(str::to_string),
            line: line.to_string(),
            in_main,
        },
    ))
}

/// Whether a logged candidate is this one, to within the last bits a decimal log can lose.
fn same(logged: &[f64], x: &[f64]) -> bool {
    logged.len() == x.len()
        && logged
            .iter()
            .zip(x)
            .all(|(a, b)| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300))
}
