//! The search's log: one JSON line per evaluation (`evaluations.jsonl`), the record a search
//! resumes from, and the shard files (`shard-I-of-N.jsonl`) in which the array jobs of a cluster
//! each log their slice of a generation, to be joined by the next step.

use super::{Evaluation, Optimization};
use crate::batch::Shard;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// The main log in an output folder.
pub fn main_file(dir: &Path) -> PathBuf {
    dir.join("evaluations.jsonl")
}

/// The file in which `shard` logs its evaluations.
pub fn shard_file(dir: &Path, shard: Shard) -> PathBuf {
    dir.join(format!("shard-{}-of-{}.jsonl", shard.index, shard.count))
}

/// The file in which a search's output folder keeps the specification its log was written by.
pub fn specification_file(dir: &Path) -> PathBuf {
    dir.join("specification.json")
}

/// What decides a search's evaluations, part by part, each as a short hash: the scenario (its
/// robot, terrain, gait, contact and duration; the constraints and articulation), the searched
/// terrains and seeds, the parameters and their bounds, the objective, CMA-ES's seed and
/// population, and the start. A resumed search or a shard step replays logged evaluations only
/// under the same parts, and the same content of every file the walks read (each a part of its
/// own, named by what it is and its file name) and hexsim's version. Left out: the number of generations (a search may be extended) and the
/// check seeds (walked after the search, not logged).
pub fn fingerprint(opt: &Optimization) -> BTreeMap<String, String> {
    let mut scenario = opt.base.clone();
    let constraints = scenario.remove("expect");
    let duration = scenario.remove("duration");
    let articulation = scenario.remove("articulation");
    let searched: Vec<String> = opt.searched().iter().map(|c| c.label()).collect();
    let parameters: Vec<String> = opt
        .parameters
        .iter()
        .map(|p| format!("{} {:?}", p.name, p.domain))
        .collect();
    let parts: [(&str, serde_json::Value); 9] = [
        ("scenario", serde_json::json!(scenario)),
        ("duration", serde_json::json!(duration)),
        ("articulation", serde_json::json!(articulation)),
        ("constraints", serde_json::json!(constraints)),
        ("terrains and seeds", serde_json::json!(searched)),
        ("parameters", serde_json::json!(parameters)),
        ("objective", serde_json::json!(opt.objective)),
        (
            "CMA-ES seed and population",
            serde_json::json!([opt.seed, opt.population]),
        ),
        ("start", serde_json::json!(opt.start)),
    ];
    let mut parts: BTreeMap<String, String> = parts
        .into_iter()
        .map(|(name, value)| (name.to_string(), short_hash(&value.to_string())))
        .collect();
    parts.insert(
        "hexsim version".into(),
        short_hash(env!("CARGO_PKG_VERSION")),
    );
    // every file the walks read, by its content: the robot, its meshes, the gait, the terrains
    for (name, digest) in &opt.read {
        parts.insert(name.clone(), digest.clone());
    }
    parts
}

fn short_hash(text: &str) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(text.as_bytes())[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The fingerprint as one hash, carried by every log line.
pub fn specification_hash(parts: &BTreeMap<String, String>) -> String {
    short_hash(&serde_json::json!(parts).to_string())
}

/// Checks a folder's recorded specification against `opt`'s, and writes it if there is none:
/// an error names the parts that changed.
pub fn claim_folder(dir: &Path, opt: &Optimization) -> Result<(), String> {
    let file = specification_file(dir);
    let parts = fingerprint(opt);
    match std::fs::read_to_string(&file) {
        Ok(text) => {
            let recorded: BTreeMap<String, String> = serde_json::from_str(&text)
                .map_err(|e| format!("{}: not a specification record: {e}", file.display()))?;
            let changed: Vec<&str> = parts
                .iter()
                .filter(|(k, v)| recorded.get(*k) != Some(*v))
                .map(|(k, _)| k.as_str())
                .chain(
                    recorded
                        .keys()
                        .filter(|k| !parts.contains_key(*k))
                        .map(String::as_str),
                )
                .collect();
            if changed.is_empty() {
                Ok(())
            } else {
                Err(format!(
                    "{} holds evaluations of another specification: its {} changed since; resuming would replay them as this one's. Use another --output folder (or empty this one)",
                    dir.display(),
                    changed.join(", ")
                ))
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => write_specification(dir, &parts),
        Err(e) => Err(format!("{}: {e}", file.display())),
    }
}

/// Records the specification a fresh search's log is written by: whole or not at all, written
/// beside it and renamed into place, for the shards of an array job start together and each
/// reads what the first wrote (written in place, a shard once read it empty: "EOF while
/// parsing", cluster/test).
pub fn write_specification(dir: &Path, parts: &BTreeMap<String, String>) -> Result<(), String> {
    let file = specification_file(dir);
    let partial = dir.join(format!("specification.json.{}.partial", std::process::id()));
    std::fs::create_dir_all(dir)
        .and_then(|()| {
            std::fs::write(
                &partial,
                serde_json::to_string_pretty(parts).unwrap_or_default(),
            )
        })
        .and_then(|()| std::fs::rename(&partial, &file))
        .map_err(|e| {
            let _ = std::fs::remove_file(&partial);
            format!("{}: {e}", file.display())
        })
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
        "specification": specification_hash(&fingerprint(opt)),
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
    /// off by a kill is skipped; a file with lines of another specification (a stale shard file,
    /// a log from before the specification changed) is an error naming it.
    pub fn read(dir: &Path, opt: &Optimization) -> Result<Logged, String> {
        let hash = specification_hash(&fingerprint(opt));
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
            Err(e) => return Err(format!("{}: {e}", dir.display())),
        };
        shards.sort();
        files.extend(shards.into_iter().map(|p| (p, false)));
        let mut logged = Logged::default();
        for (file, in_main) in files {
            let Ok(text) = std::fs::read_to_string(&file) else {
                continue;
            };
            for line in text.lines() {
                let Some((key, entry, logged_by)) = parse(line, opt, in_main) else {
                    continue;
                };
                if logged_by.as_deref() != Some(hash.as_str()) {
                    return Err(format!(
                        "{}: evaluations of another specification (logged by {}, this one is {hash}); use another --output folder, or remove the file if it is stale",
                        file.display(),
                        logged_by.as_deref().unwrap_or("an unrecorded one")
                    ));
                }
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

/// A log line's key, entry and the specification hash it was logged by.
fn parse(
    line: &str,
    opt: &Optimization,
    in_main: bool,
) -> Option<((usize, usize), Entry, Option<String>)> {
    let v: serde_json::Value = serde_json::from_str(line).ok()?;
    let at = |k: &str| v[k].as_u64().map(|n| n as usize);
    let key = (at("generation")?, at("index")?);
    let x: Vec<f64> = v["x"]
        .as_array()?
        .iter()
        .map(serde_json::Value::as_f64)
        .collect::<Option<_>>()?;
    let logged_by = v["specification"].as_str().map(str::to_string);
    if x.len() != opt.parameters.len() {
        // another search's dimension: another specification
        return Some((key, dummy_entry(line, in_main), logged_by));
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
        logged_by,
    ))
}

fn dummy_entry(line: &str, in_main: bool) -> Entry {
    Entry {
        x: Vec::new(),
        objective: None,
        failure: None,
        line: line.to_string(),
        in_main,
    }
}

/// Whether a logged candidate is this one, to within the last bits a decimal log can lose.
fn same(logged: &[f64], x: &[f64]) -> bool {
    logged.len() == x.len()
        && logged
            .iter()
            .zip(x)
            .all(|(a, b)| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300))
}
