//! The search loop: CMA-ES asks for a generation, hexsim evaluates it in parallel (or replays it
//! from the log), CMA-ES is told. A resumed search replays what its folder's log holds — the
//! same specification and seed ask for the same candidates — and a shard evaluates only its
//! slice of one generation, to its own file, and stops (a cluster's array job; see
//! docs/optimize.md).

use super::recording::Evaluated;
use super::{Evaluation, Optimization, log};
use crate::batch::Shard;
use anyhow::Result;
use fcmaes_core::{Cmaes, CmaesParams, Fitness};
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;

/// Where and how a search runs.
#[derive(Clone, Copy)]
pub struct Setting<'a> {
    /// The folder of its log, its shard files and its specification.
    pub output: &'a Path,
    /// Replay the log's evaluations rather than start anew.
    pub resume: bool,
    /// One step of a sharded search: this slice of the next generation not yet logged.
    pub shard: Option<Shard>,
}

/// What the search tells as it goes.
pub enum Progress<'a> {
    /// The start's evaluation (run or replayed).
    Start(&'a Evaluation),
    /// A generation told to the optimiser.
    Generation(&'a Generation),
}

/// A generation's summary.
pub struct Generation {
    pub number: usize,
    pub of: usize,
    /// The best objective so far.
    pub best: Option<f64>,
    /// The generation's median objective (of those that did not fail).
    pub median: Option<f64>,
    pub failed: usize,
    /// Evaluations run (not replayed) per second so far, and the seconds left at that rate.
    pub rate: f64,
    pub eta_seconds: f64,
    /// Every candidate came from the log.
    pub replayed: bool,
}

/// What the search found.
pub struct Searched {
    /// The start's result; None when it belongs to another shard not yet logged.
    pub start: Option<Evaluation>,
    pub best: Option<(f64, Vec<f64>)>,
    /// Every evaluation told to the optimiser (and the start), in order.
    pub history: Vec<Evaluated>,
    /// Evaluations run (not replayed) by this process.
    pub run: usize,
    pub interrupted: bool,
    /// A shard step: the generation it stopped at, and the candidates other shards still owe.
    pub stopped_at: Option<(usize, Vec<usize>)>,
}

/// How a candidate's result was had.
enum Source<'a> {
    /// Run now.
    Run,
    /// Replayed from the log, from the main log or (to be copied into it) from a shard file.
    Logged(&'a log::Entry),
}

/// Runs the search (on the calling rayon pool), logging every evaluation; `progress` hears the
/// start and each generation.
pub fn run(
    opt: &Optimization,
    setting: Setting,
    mut progress: impl FnMut(Progress),
) -> Result<Searched> {
    let started = std::time::Instant::now();
    let population = opt.population_size();
    let mut es = cma_es(opt, population);
    let logged = read_log(opt, setting)?;
    let mut out = open_log(setting)?;
    // a failed write (a full disk) names the log
    let log_path = match setting.shard {
        Some(shard) => log::shard_file(setting.output, shard),
        None => log::main_file(setting.output),
    };
    let named = |e: std::io::Error| anyhow::anyhow!("cannot write {}: {e}", log_path.display());
    let mine = |index: usize| setting.shard.is_none_or(|s| s.contains(index));
    // None: another shard's candidate, not logged yet
    let evaluate = |generation: usize, index: usize, x: &[f64]| -> Option<(Evaluation, Source)> {
        match logged.get(generation, index, x) {
            Some(entry) => Some((entry.evaluation(), Source::Logged(entry))),
            None if mine(index) => Some((opt.evaluate(x), Source::Run)),
            None => None,
        }
    };
    // logs a result: a run's line, or a shard file's copied into the main log
    let write = |out: &mut std::io::BufWriter<std::fs::File>,
                 generation: usize,
                 index: usize,
                 x: &[f64],
                 (e, source): &(Evaluation, Source)|
     -> std::io::Result<()> {
        match source {
            Source::Run if !e.interrupted() => {
                writeln!(out, "{}", log::line(opt, generation, index, x, e))
            }
            Source::Logged(entry) if !entry.in_main && setting.shard.is_none() => {
                writeln!(out, "{}", entry.line)
            }
            _ => Ok(()),
        }
    };
    let mut searched = Searched {
        start: None,
        best: None,
        history: Vec::new(),
        run: 0,
        interrupted: false,
        stopped_at: None,
    };
    if let Some(result) = evaluate(0, 0, &opt.start) {
        write(&mut out, 0, 0, &opt.start, &result).map_err(named)?;
        let (start, source) = result;
        searched.run += usize::from(matches!(source, Source::Run));
        searched.interrupted = start.interrupted();
        if !searched.interrupted {
            progress(Progress::Start(&start));
            searched.best = start.objective.map(|o| (o, opt.start.clone()));
            searched.history.push(Evaluated {
                x: opt.start.clone(),
                objective: start.objective,
            });
            searched.start = Some(start);
        }
    }
    for generation in 1..=opt.generations {
        if searched.interrupted {
            break;
        }
        let xs = es.ask();
        let results: Vec<Option<(Evaluation, Source)>> = xs
            .par_iter()
            .enumerate()
            .map(|(i, x)| evaluate(generation, i, x))
            .collect();
        // cut short by Ctrl-C: only the candidates before the first interrupted one are logged,
        // so that --resume appends the rest in order and the log reads line for line as an
        // uninterrupted search's (the later ones finished are run again: the same results)
        let cut = results
            .iter()
            .position(|r| r.as_ref().is_some_and(|(e, _)| e.interrupted()))
            .unwrap_or(results.len());
        for (i, (x, result)) in xs.iter().zip(&results).enumerate().take(cut) {
            if let Some(result) = result {
                write(&mut out, generation, i, x, result).map_err(named)?;
            }
        }
        out.flush().map_err(named)?;
        let ran = results
            .iter()
            .flatten()
            .filter(|(_, s)| matches!(s, Source::Run))
            .count();
        searched.run += ran;
        if results.iter().flatten().any(|(e, _)| e.interrupted()) {
            // what finished is logged; the generation is not told, --resume runs the rest
            searched.interrupted = true;
            break;
        }
        let owed: Vec<usize> = (0..xs.len()).filter(|&i| results[i].is_none()).collect();
        if setting.shard.is_some() && (ran > 0 || !owed.is_empty()) {
            // a shard step: one generation's slice; the next step needs every shard's
            searched.stopped_at = Some((generation, owed));
            break;
        }
        let told: Vec<(&[f64], &Evaluation)> = xs
            .iter()
            .zip(&results)
            .filter_map(|(x, r)| r.as_ref().map(|(e, _)| (&x[..], e)))
            .collect();
        let ys = searched.take(&told);
        let mut objectives: Vec<f64> = told.iter().filter_map(|(_, e)| e.objective).collect();
        objectives.sort_by(f64::total_cmp);
        let rate = searched.run.max(1) as f64 / started.elapsed().as_secs_f64();
        progress(Progress::Generation(&Generation {
            number: generation,
            of: opt.generations,
            best: searched.best.as_ref().map(|(b, _)| *b),
            median: objectives.get(objectives.len() / 2).copied(),
            failed: xs.len() - objectives.len(),
            rate,
            eta_seconds: ((opt.generations - generation) * population) as f64 / rate.max(1e-9),
            replayed: ran == 0,
        }));
        if es.tell(&ys) != 0 {
            break;
        }
    }
    out.flush().map_err(named)?;
    Ok(searched)
}

impl Searched {
    /// Takes a generation's results into the history and the best; returns what CMA-ES is told
    /// (it minimises: the negated objective, and a failed candidate below every one that ran).
    fn take(&mut self, told: &[(&[f64], &Evaluation)]) -> Vec<f64> {
        let mut ys = Vec::with_capacity(told.len());
        for (x, e) in told {
            ys.push(e.objective.map_or(f64::MAX, |o| -o));
            self.history.push(Evaluated {
                x: x.to_vec(),
                objective: e.objective,
            });
            if let Some(o) = e.objective
                && self.best.as_ref().is_none_or(|(b, _)| o > *b)
            {
                self.best = Some((o, x.to_vec()));
            }
        }
        ys
    }
}

/// CMA-ES within the parameters' bounds (normalised), from the start, seeded by the search.
fn cma_es(opt: &Optimization, population: usize) -> Cmaes {
    let (low, high): (Vec<f64>, Vec<f64>) = opt.parameters.iter().map(|p| p.bounds()).unzip();
    let mut fitness = Fitness::bounded(low.len(), 1, &low, &high);
    fitness.set_normalize(true);
    let params = CmaesParams {
        popsize: population as i32,
        max_evaluations: (opt.generations * population) as u64,
        seed: opt.seed,
        ..CmaesParams::default()
    };
    Cmaes::new(fitness, &opt.start, &[0.3], &params)
}

/// The evaluations a resumed search or a shard replays (after checking that the folder's
/// specification is this one); a new search writes its specification and replays none.
fn read_log(opt: &Optimization, setting: Setting) -> Result<log::Logged> {
    if setting.resume || setting.shard.is_some() {
        log::claim_folder(setting.output, opt).map_err(anyhow::Error::msg)?;
        log::Logged::read(setting.output, opt).map_err(anyhow::Error::msg)
    } else {
        log::write_specification(setting.output, &log::fingerprint(opt))
            .map_err(anyhow::Error::msg)?;
        Ok(log::Logged::default())
    }
}

/// The log this process appends to: a shard's own file, or the main log (which only a whole
/// search writes; a new one starts it anew).
fn open_log(setting: Setting) -> Result<std::io::BufWriter<std::fs::File>> {
    let (path, append) = match setting.shard {
        Some(shard) => (log::shard_file(setting.output, shard), true),
        None => (log::main_file(setting.output), setting.resume),
    };
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(append)
        .write(true)
        .truncate(!append)
        .open(&path)?;
    Ok(std::io::BufWriter::new(file))
}
