//! Batches: many scenarios run headless in parallel (one rapier world per thread), results as
//! JSON Lines, resumable, sliceable into shards for a cluster, and comparable with a baseline.

pub mod baseline;
pub mod results;
pub mod summary;

use crate::scenario::{self, Output, Outputs, Scenario, ScenarioError};
use anyhow::{Context, Result, bail};
use baseline::Regression;
use rayon::prelude::*;
use results::{Record, Status};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The I-th of N deterministic slices of a batch's scenario list: every N-th scenario from the
/// (I−1)-th, so slices get a mix of scenarios.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based.
    pub index: usize,
    pub count: usize,
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    pub fn contains(&self, position: usize) -> bool {
        position % self.count == self.index - 1
    }
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let parse = || -> Option<Shard> {
            let (i, n) = s.split_once('/')?;
            let (index, count) = (i.trim().parse().ok()?, n.trim().parse().ok()?);
            (1..=count)
                .contains(&index)
                .then_some(Shard { index, count })
        };
        parse().ok_or_else(|| format!("expected I/N with 1 ≤ I ≤ N (e.g. 2/8), got {s:?}"))
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The scenario files named by `inputs`: files, folders (every `.toml` below them) or glob
/// patterns; sorted, without repeats.
pub fn scenario_files(inputs: &[String]) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for input in inputs {
        let path = Path::new(input);
        if path.is_dir() {
            let before = files.len();
            collect_toml(path, &mut files)
                .with_context(|| format!("{input}: cannot list the folder"))?;
            if files.len() == before {
                bail!("{input}: no scenario files (*.toml) in this folder");
            }
        } else if path.is_file() {
            files.push(path.to_path_buf());
        } else if input.contains(['*', '?', '[']) {
            let matches: Vec<PathBuf> = glob::glob(input)
                .with_context(|| format!("{input}: not a valid pattern"))?
                .filter_map(|m| m.ok())
                .filter(|p| p.is_file())
                .collect();
            if matches.is_empty() {
                bail!("{input}: no scenario files match this pattern");
            }
            files.extend(matches);
        } else {
            bail!("{input}: no such scenario file or folder");
        }
    }
    files.sort();
    files.dedup();
    Ok(files)
}

fn collect_toml(dir: &Path, files: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()?;
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect_toml(&path, files)?;
        } else if path.extension().is_some_and(|e| e == "toml") {
            files.push(path);
        }
    }
    Ok(())
}

/// Loads every scenario (sweeps expanded) sorted by name. All errors are collected, so a user sees
/// every broken file at once; two scenarios with one name are an error.
pub fn load(files: &[PathBuf]) -> Result<Vec<Scenario>, Vec<ScenarioError>> {
    let mut scenarios = Vec::new();
    let mut errors = Vec::new();
    for file in files {
        // set-up can take a while over many files: Ctrl-C ends it between them
        if crate::interrupt::interrupted() {
            return Err(vec![ScenarioError {
                file: file.clone(),
                message: crate::interrupt::MESSAGE.into(),
            }]);
        }
        match scenario::load_file(file) {
            Ok(list) => scenarios.extend(list),
            Err(e) => errors.push(e),
        }
    }
    scenarios.sort_by(|a, b| a.name.cmp(&b.name));
    for pair in scenarios.windows(2) {
        if pair[0].name == pair[1].name {
            errors.push(ScenarioError {
                file: pair[1].file.clone(),
                message: format!(
                    "scenario name {:?} is also used by {}; give one of them a `name`",
                    pair[1].name,
                    pair[0].file.display()
                ),
            });
        }
    }
    if errors.is_empty() {
        Ok(scenarios)
    } else {
        Err(errors)
    }
}

/// How a batch reports progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// A progress bar with ETA (for a terminal).
    Bar,
    /// A line per finished scenario (for logs).
    Lines,
    Quiet,
}

pub struct Options {
    /// Threads (one rapier world each).
    pub jobs: usize,
    /// The results file (JSON Lines).
    pub output: PathBuf,
    /// Keep the results already in `output` for unchanged scenarios and run only the rest.
    pub resume: bool,
    pub shard: Shard,
    /// Where scenarios asking for a recording or trajectory write them.
    pub record_dir: PathBuf,
    pub progress: Progress,
}

/// What a batch did.
pub struct Outcome {
    /// Every result of this shard, this run's and resumed ones, in list order.
    pub records: Vec<Record>,
    /// Results kept from an earlier run (`--resume`).
    pub resumed: usize,
    /// Scenarios run again under `--resume` because they changed since their result, each
    /// with what changed (`NAME: robots/x/foot.stl changed`).
    pub changed: Vec<String>,
    /// Scenarios not run because the batch was interrupted.
    pub not_run: usize,
    pub interrupted: bool,
    pub wall_time: f64,
    /// Steps simulated by this run, all threads together.
    pub steps: u64,
}

impl Outcome {
    /// Total simulated steps per second of wall time.
    pub fn throughput(&self) -> f64 {
        self.steps as f64 / self.wall_time.max(1e-9)
    }
}

/// Runs this shard's part of `scenarios` (the full, name-sorted list).
pub fn run(scenarios: &[Scenario], options: &Options) -> Result<Outcome> {
    let total = scenarios.len();
    let mine: Vec<(usize, &Scenario)> = scenarios
        .iter()
        .enumerate()
        .filter(|(i, _)| options.shard.contains(*i))
        .collect();
    // keep what an earlier run finished (same name and content); a cut-off last line is dropped
    let mut kept = Vec::new();
    let mut changed = Vec::new();
    if options.resume && options.output.exists() {
        let (old, _cut) = results::read(&options.output, true)?;
        let wanted: HashMap<(&str, &str), usize> = mine
            .iter()
            .map(|(i, s)| ((s.name.as_str(), s.hash.as_str()), *i))
            .collect();
        for mut r in old {
            if r.status == Status::Error {
                continue;
            }
            if let Some(&i) = wanted.get(&(r.name.as_str(), r.hash.as_str()))
                && !kept.iter().any(|k: &Record| k.name == r.name)
            {
                r.index = i;
                r.total = total;
                r.shard = [options.shard.index, options.shard.count];
                kept.push(r);
            } else if let Some((_, s)) = mine.iter().find(|(_, s)| s.name == r.name)
                && s.hash != r.hash
                && !changed
                    .iter()
                    .any(|c: &String| c.starts_with(&format!("{}:", s.name)))
            {
                changed.push(rerun_because(s, &r));
            }
        }
    }
    // a folder or an unwritable place named for the results: said before anything is written
    crate::record::output::check_writable(&options.output)?;
    results::write_all(&options.output, &kept)?;
    let done: std::collections::HashSet<&str> = kept.iter().map(|r| r.name.as_str()).collect();
    let mut todo: Vec<(usize, &Scenario)> = mine
        .iter()
        .filter(|(_, s)| !done.contains(s.name.as_str()))
        .copied()
        .collect();
    // longest first, so that no thread is left with a long scenario at the end
    todo.sort_by_key(|(i, s)| (std::cmp::Reverse(s.total_steps()), *i));
    if todo
        .iter()
        .any(|(_, s)| s.spec.record.rrd || s.spec.record.trajectory)
    {
        std::fs::create_dir_all(&options.record_dir).with_context(|| {
            format!(
                "{}: cannot create the recordings folder",
                options.record_dir.display()
            )
        })?;
    }

    let steps_total: u64 = todo.iter().map(|(_, s)| s.total_steps()).sum();
    let bar = match options.progress {
        Progress::Bar => {
            let bar = indicatif::ProgressBar::new(steps_total);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] [{bar:40}] {percent:>3}% ({eta} left) {msg}",
                )
                .expect("the template is valid")
                .progress_chars("=> "),
            );
            bar
        }
        _ => indicatif::ProgressBar::hidden(),
    };
    let count = todo.len();
    let finished = std::sync::atomic::AtomicUsize::new(0);
    bar.set_message(format!("0/{count} scenarios"));
    let appender = Mutex::new(results::Appender::open(&options.output)?);
    let new_records = Mutex::new(Vec::new());
    let started = std::time::Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs.max(1))
        .build()
        .context("cannot start the worker threads")?;
    let outcome: Result<()> = pool.install(|| {
        todo.par_iter().with_max_len(1).try_for_each(|&(index, s)| {
            if crate::runner::interrupted() {
                return Ok(());
            }
            let Some(record) = run_one(s, index, total, options, &bar) else {
                return Ok(()); // interrupted mid-run: not a result
            };
            appender
                .lock()
                .expect("no writer panicked")
                .append(&record)?;
            let n = finished.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            bar.set_message(format!("{n}/{count} scenarios"));
            let line = format!(
                "[{n}/{count}] {:<8} {} ({:.1} s){}",
                status_word(record.status),
                record.name,
                record.wall_time_s,
                record
                    .message
                    .as_deref()
                    .map_or(String::new(), |m| format!(": {m}"))
            );
            match options.progress {
                Progress::Lines => eprintln!("{line}"),
                Progress::Bar if record.status != Status::Passed => bar.println(line),
                _ => {}
            }
            new_records.lock().expect("no writer panicked").push(record);
            Ok(())
        })
    });
    bar.finish_and_clear();
    outcome?;
    let wall_time = started.elapsed().as_secs_f64();
    let new_records = new_records.into_inner().expect("no writer panicked");
    let steps = new_records.iter().map(|r| r.steps).sum();
    let not_run = count - new_records.len();
    let resumed = kept.len();
    let mut records = kept;
    records.extend(new_records);
    records.sort_by_key(|r| r.index);
    Ok(Outcome {
        records,
        resumed,
        changed,
        not_run,
        interrupted: crate::runner::interrupted(),
        wall_time,
        steps,
    })
}

pub fn status_word(status: Status) -> &'static str {
    match status {
        Status::Passed => "passed",
        Status::Regressed => "REGRESSED",
        Status::Failed => "FAILED",
        Status::Diverged => "DIVERGED",
        Status::Error => "ERROR",
    }
}

/// The files scenario `s` writes into `record_dir` when its `[record]` asks: its recording
/// (`NAME.rrd`) and its trajectory (`NAME.csv`), each named for [`check_distinct`]'s message. The
/// batch checks them against every scenario's inputs and its results file before it runs: one
/// scenario's output must not overwrite what another reads.
///
/// [`check_distinct`]: crate::record::output::check_distinct
pub fn record_files(s: &Scenario, record_dir: &Path) -> [Option<(&'static str, PathBuf)>; 2] {
    let file = |extension: &str| record_dir.join(format!("{}.{extension}", s.name));
    [
        s.spec
            .record
            .rrd
            .then(|| ("scenario's recording", file("rrd"))),
        s.spec
            .record
            .trajectory
            .then(|| ("scenario's trajectory", file("csv"))),
    ]
}

/// Runs one scenario into a record; None if it was interrupted.
fn run_one(
    s: &Scenario,
    index: usize,
    total: usize,
    options: &Options,
    bar: &indicatif::ProgressBar,
) -> Option<Record> {
    let expected = s.total_steps();
    let reported = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let progress = {
        let bar = bar.clone();
        let reported = reported.clone();
        Box::new(move |done: u64| {
            let before = reported.swap(done, std::sync::atomic::Ordering::Relaxed);
            bar.inc(done.saturating_sub(before));
        }) as Box<dyn Fn(u64) + Send>
    };
    let [recording, trajectory] = record_files(s, &options.record_dir);
    let outputs = Outputs::new()
        .with_some(recording.map(|(_, path)| Output::Recording(path)))
        .with_some(trajectory.map(|(_, path)| Output::Trajectory(path)))
        .with(Output::Progress(progress));
    let started = std::time::Instant::now();
    let result = s.run(outputs);
    bar.inc(expected.saturating_sub(reported.load(std::sync::atomic::Ordering::Relaxed)));
    let mut record = Record {
        name: s.name.clone(),
        file: s.file.display().to_string(),
        hash: s.hash.clone(),
        inputs: s.read.digests(),
        kind: s.kind(),
        seed: s.seed,
        index,
        total,
        shard: [options.shard.index, options.shard.count],
        hexsim_version: env!("CARGO_PKG_VERSION").to_string(),
        status: Status::Error,
        message: None,
        wall_time_s: started.elapsed().as_secs_f64(),
        steps: 0,
        steps_per_second: 0.0,
        metrics: serde_json::Value::Null,
        expectations: Vec::new(),
        regressions: Vec::new(),
        metadata: Some(Box::new(s.metadata())),
    };
    match result {
        // a set-up cut short by Ctrl-C (the terrain's generation): not a result, --resume runs it
        Err(_) if crate::interrupt::interrupted() => return None,
        Err(e) => record.message = Some(format!("{e:#}")),
        Ok(report) => {
            if !report.metrics.complete() && report.failure.is_none() {
                return None;
            }
            let failed: Vec<String> = report
                .checks
                .iter()
                .filter(|c| !c.passed)
                .map(|c| match &report.metrics {
                    // the flags say what was wrong with the walk
                    crate::metrics::Metrics::Walk(w) if c.expectation == "walk_as_commanded" => {
                        format!("walk_as_commanded: it {}", w.walk_flags.join("; it "))
                    }
                    _ => describe_check(c),
                })
                .collect();
            record.status = if report.failure.is_some() && s.spec.expect.no_divergence {
                Status::Diverged
            } else if failed.is_empty() {
                Status::Passed
            } else {
                Status::Failed
            };
            record.message = match (&report.failure, failed.is_empty()) {
                (Some(f), _) if s.spec.expect.no_divergence => Some(f.clone()),
                (_, false) => Some(failed.join("; ")),
                _ => None,
            };
            record.steps = report.steps;
            record.steps_per_second = report.steps_per_second;
            record.metrics = report.metrics.to_json();
            record.expectations = report.checks;
        }
    }
    Some(record)
}

/// Why `--resume` runs `s` again though `r` is its earlier result: the files whose content
/// changed, else its fields or hexsim's version.
fn rerun_because(s: &Scenario, r: &Record) -> String {
    let files = crate::scenario::inputs::changed(&r.inputs, &s.read.digests());
    if !files.is_empty() && !r.inputs.is_empty() {
        format!("{}: {} changed", s.name, files.join(", "))
    } else if r.hexsim_version != env!("CARGO_PKG_VERSION") {
        format!(
            "{}: run by hexsim {}, this is {}",
            s.name,
            r.hexsim_version,
            env!("CARGO_PKG_VERSION")
        )
    } else {
        format!("{}: its fields changed", s.name)
    }
}

/// `distance_min: 0.412 < 2`.
pub fn describe_check(c: &scenario::Check) -> String {
    match (c.value, c.limit) {
        (Some(v), Some(l)) => {
            // the value is on the wrong side of its limit
            let op = match c.side {
                Some(crate::metrics::Side::Min) => "<",
                _ => ">",
            };
            format!("{}: {} {op} {}", c.expectation, round(v), l)
        }
        (None, Some(l)) => format!("{}: no value (limit {l})", c.expectation),
        (Some(v), None) => format!("{}: {}", c.expectation, round(v)),
        (None, None) => format!("{}: not met", c.expectation),
    }
}

fn round(v: f64) -> String {
    let s = format!("{v:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Compares every record with the baseline's record of the same name. Returns the regressions
/// per scenario and the scenarios the baseline lacks.
pub fn compare_with_baseline(
    records: &[Record],
    scenarios: &[Scenario],
    baseline: &[Record],
    default_rel: f64,
) -> (BTreeMap<String, Vec<Regression>>, Vec<String>) {
    let by_name: HashMap<&str, &Record> = baseline.iter().map(|r| (r.name.as_str(), r)).collect();
    let tolerances: HashMap<&str, _> = scenarios
        .iter()
        .map(|s| (s.name.as_str(), &s.spec.tolerance))
        .collect();
    let empty = BTreeMap::new();
    let mut regressions = BTreeMap::new();
    let mut missing = Vec::new();
    for r in records {
        if r.status == Status::Error {
            continue;
        }
        match by_name.get(r.name.as_str()) {
            None => missing.push(r.name.clone()),
            Some(b) => {
                let t = tolerances.get(r.name.as_str()).copied().unwrap_or(&empty);
                let moved = baseline::compare(r, b, default_rel, t);
                if !moved.is_empty() {
                    regressions.insert(r.name.clone(), moved);
                }
            }
        }
    }
    (regressions, missing)
}

/// Marks each record with its regressions against the baseline (`regressions`, by scenario): a
/// record that met its expectations becomes `Regressed`. Marks from an earlier comparison (a
/// resumed result) are cleared first, so a record says what this comparison found. Returns
/// whether any record changed.
pub fn mark_regressions(
    records: &mut [Record],
    regressions: &BTreeMap<String, Vec<Regression>>,
) -> bool {
    let mut changed = false;
    for r in records {
        let moved = regressions.get(&r.name).cloned().unwrap_or_default();
        let status = match r.status {
            Status::Passed | Status::Regressed if !moved.is_empty() => Status::Regressed,
            Status::Regressed => Status::Passed,
            other => other,
        };
        if status != r.status || moved != r.regressions {
            (r.status, r.regressions) = (status, moved);
            changed = true;
        }
    }
    changed
}

/// Joins shard results into one list: refuses a scenario that appears twice, results from
/// different batches, and shards (or results within a shard) that are missing.
pub fn merge(parts: &[(PathBuf, Vec<Record>)]) -> Result<Vec<Record>> {
    let mut all: Vec<(&Path, &Record)> = parts
        .iter()
        .flat_map(|(p, rs)| rs.iter().map(move |r| (p.as_path(), r)))
        .collect();
    let Some((first_file, first)) = all.first().copied() else {
        bail!("no results to merge");
    };
    let (total, count) = (first.total, first.shard[1]);
    for (file, r) in &all {
        if r.total != total || r.shard[1] != count {
            bail!(
                "{}: {} comes from a batch of {} scenarios in {} shards, but {} from one of {total} in {count}; merge shards of one batch",
                file.display(),
                r.name,
                r.total,
                r.shard[1],
                first_file.display()
            );
        }
    }
    all.sort_by_key(|(_, r)| r.index);
    for pair in all.windows(2) {
        if pair[0].1.name == pair[1].1.name || pair[0].1.index == pair[1].1.index {
            bail!(
                "{} appears twice: in {} and {}",
                pair[1].1.name,
                pair[0].0.display(),
                pair[1].0.display()
            );
        }
    }
    let present: std::collections::HashSet<usize> = all.iter().map(|(_, r)| r.index).collect();
    let mut problems = Vec::new();
    for shard in 1..=count {
        let s = Shard {
            index: shard,
            count,
        };
        let expected: Vec<usize> = (0..total).filter(|&i| s.contains(i)).collect();
        let missing = expected.iter().filter(|i| !present.contains(i)).count();
        if missing == expected.len() && missing > 0 {
            problems.push(format!("shard {s} is missing"));
        } else if missing > 0 {
            problems.push(format!(
                "shard {s} has {} of {} results (resume it with --resume)",
                expected.len() - missing,
                expected.len()
            ));
        }
    }
    if !problems.is_empty() {
        bail!("incomplete batch: {}", problems.join("; "));
    }
    Ok(all.into_iter().map(|(_, r)| r.clone()).collect())
}
