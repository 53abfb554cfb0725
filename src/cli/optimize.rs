//! `hexsim optimize FILE`: the best gait for a robot on a set of terrains (see `hexsim::optimize`).

use anyhow::Result;
use clap::Args;
use fcmaes_core::{Cmaes, CmaesParams, Fitness};
use hexsim::batch::Shard;
use hexsim::compare::{self, Comparison};
use hexsim::optimize::recording::Evaluated;
use hexsim::optimize::{self, Case, Evaluation, Optimization, log};
use hexsim::sim::Articulation;
use rayon::prelude::*;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct OptimizeArgs {
    /// Optimisation file (TOML): the scenario, the parameters and their bounds (or choices), the
    /// terrains and seeds, the objective and the constraints (see optimizations/).
    file: PathBuf,
    /// Folder for the log of every evaluation (evaluations.jsonl), the best gait
    /// (best_gait.toml), the summary (summary.json), the search's recording (search.rrd) and one
    /// of the start and the best walking each terrain and seed (TERRAIN-seed-S.rrd).
    #[arg(long, default_value = "optimize")]
    output: PathBuf,
    /// Worker threads. Default: all cores.
    #[arg(short, long)]
    jobs: Option<usize>,
    /// Continue an interrupted (or sharded) search: the evaluations already in the output
    /// folder's log and shard files are replayed (the same specification and seed ask for the
    /// same candidates), not run again.
    #[arg(long)]
    resume: bool,
    /// One step of a search spread over a cluster's array jobs sharing the output folder: run
    /// the I-th of N slices of the next generation that is not yet logged, log it to
    /// shard-I-of-N.jsonl and stop. Step every shard, one generation after another, then finish
    /// with --resume (which joins the shard files and writes the results); see the README.
    #[arg(long, value_name = "I/N")]
    shard: Option<Shard>,
    /// Do not write the recordings.
    #[arg(long)]
    no_record: bool,
}

/// How a candidate's result was had.
enum Source<'a> {
    /// Run now.
    Run,
    /// Replayed from the log, from the main log or (to be copied into it) from a shard file.
    Logged(&'a log::Entry),
}

/// What the search loop found.
struct Searched {
    /// The start's result; None when it belongs to another shard not yet logged.
    start: Option<Evaluation>,
    best: Option<(f64, Vec<f64>)>,
    /// Every evaluation told to the optimiser (and the start), in order.
    history: Vec<Evaluated>,
    /// Evaluations run (not replayed) by this process.
    run: usize,
    interrupted: bool,
    /// A shard step: the generation it stopped at, and the candidates other shards still owe.
    stopped_at: Option<(usize, Vec<usize>)>,
}

/// Exit codes: 0 done (or a shard step done), 1 no candidate met the constraints, 2 an input
/// error, 130 interrupted (what was found so far written; `--resume` continues).
pub fn optimize(args: OptimizeArgs) -> Result<ExitCode> {
    let opt = optimize::load(&args.file)?;
    std::fs::create_dir_all(&args.output)?;
    let jobs = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build()?;
    if let Some(d) = &opt.description {
        println!("{d}");
    }
    let started = std::time::Instant::now();
    let searched = pool.install(|| search(&opt, &args, started))?;
    if let Some(shard) = args.shard {
        return Ok(report_shard(&opt, &args, shard, &searched));
    }
    let log_path = log::main_file(&args.output);
    if searched.interrupted {
        println!(
            "interrupted: every finished evaluation is in {}; continue with --resume",
            log_path.display()
        );
    }
    let Some((objective, x)) = searched.best.clone() else {
        if !searched.interrupted {
            println!(
                "no candidate met the constraints; every evaluation is in {}",
                log_path.display()
            );
        }
        return Ok(ExitCode::from(if searched.interrupted { 130 } else { 1 }));
    };
    let start_objective = searched.start.as_ref().and_then(|s| s.objective);
    let shown = |o: Option<f64>| o.map_or("failed".to_string(), |o| format!("{o:.4}"));
    let gait_path = args.output.join("best_gait.toml");
    std::fs::write(
        &gait_path,
        format!(
            "# found by `hexsim optimize {}`: objective {objective:.4} (start {})\n{}",
            args.file.display(),
            shown(start_objective),
            opt.gait_file(&x)
        ),
    )?;
    let mut summary = serde_json::json!({
        "optimization": args.file.display().to_string(),
        "evaluations": searched.history.len(),
        "failed": searched.history.iter().filter(|e| e.objective.is_none()).count(),
        "wall_time_s": started.elapsed().as_secs_f64(),
        "start": { "parameters": opt.values(&opt.start), "objective": start_objective },
        "best": { "parameters": opt.values(&x), "objective": objective },
    });
    let summary_path = args.output.join("summary.json");
    // written now, so the summary survives checks that Ctrl-C cuts short
    std::fs::write(
        &summary_path,
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    let mut table = String::from("| parameter | start | best |\n|---|---|---|\n");
    let values = (opt.values(&opt.start), opt.values(&x));
    for p in &opt.parameters {
        let cell = |v: &serde_json::Value| match v {
            serde_json::Value::Number(n) => format!("{:.4}", n.as_f64().unwrap_or(f64::NAN)),
            other => other.as_str().unwrap_or("").to_string(),
        };
        table += &format!(
            "| {} | {} | {} |\n",
            p.name,
            cell(&values.0[&p.name]),
            cell(&values.1[&p.name])
        );
    }
    table += &format!(
        "| **objective** | {} | {objective:.4} |\n",
        shown(start_objective)
    );
    let mut written = vec![gait_path.clone(), log_path.clone(), summary_path.clone()];
    if !args.no_record {
        let failed = summary["failed"].as_u64().unwrap_or(0);
        let text = format!(
            "# {}\n\n{}\n\n{}\n\n{} evaluations ({failed} failed) on {}.\n",
            args.file.display(),
            opt.description.as_deref().unwrap_or(""),
            table,
            searched.history.len(),
            opt.searched()
                .iter()
                .map(|c| c.label())
                .collect::<Vec<_>>()
                .join(", "),
        );
        written.push(hexsim::optimize::recording::write(
            &args.output.join("search.rrd"),
            &opt,
            &searched.history,
            &text,
        )?);
    }
    println!("{}", table.replace("**", ""));
    if searched.interrupted {
        // the best so far is written; the checks would be cut short too
        return Ok(ExitCode::from(130));
    }
    let Some(checks) = pool.install(|| check(&opt, &x, &args, jobs, &mut written))? else {
        // the checks were cut short: their runs are not results
        return Ok(ExitCode::from(130));
    };
    summary["per_terrain"] = serde_json::Value::Array(checks);
    std::fs::write(
        &summary_path,
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    println!("wrote {}", names.join(", "));
    Ok(ExitCode::SUCCESS)
}

/// Runs the search: CMA-ES asks for a generation, hexsim evaluates it in parallel (or replays
/// it from the log), CMA-ES is told; a shard evaluates only its slice of one generation.
fn search(
    opt: &Optimization,
    args: &OptimizeArgs,
    started: std::time::Instant,
) -> Result<Searched> {
    let bounds: Vec<(f64, f64)> = opt.parameters.iter().map(|p| p.bounds()).collect();
    let (low, high): (Vec<f64>, Vec<f64>) = bounds.iter().copied().unzip();
    let dim = low.len();
    let population = opt
        .population
        .unwrap_or((4.0 + 3.0 * (dim as f64).ln()).floor() as usize);
    let mut fitness = Fitness::bounded(dim, 1, &low, &high);
    fitness.set_normalize(true);
    let params = CmaesParams {
        popsize: population as i32,
        max_evaluations: (opt.generations * population) as u64,
        seed: opt.seed,
        ..CmaesParams::default()
    };
    let mut es = Cmaes::new(fitness, &opt.start, &[0.3], &params);
    let logged = if args.resume || args.shard.is_some() {
        log::claim_folder(&args.output, opt).map_err(anyhow::Error::msg)?;
        log::Logged::read(&args.output, opt).map_err(anyhow::Error::msg)?
    } else {
        log::write_specification(&args.output, &log::fingerprint(opt))
            .map_err(anyhow::Error::msg)?;
        log::Logged::default()
    };
    // a shard logs to its own file; the main log is written only by a whole search
    let (log_path, append) = match args.shard {
        Some(shard) => (log::shard_file(&args.output, shard), true),
        None => (log::main_file(&args.output), args.resume),
    };
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(append)
        .write(true)
        .truncate(!append)
        .open(&log_path)?;
    let mut out = std::io::BufWriter::new(file);
    let mine = |index: usize| args.shard.is_none_or(|s| s.contains(index));
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
            Source::Logged(entry) if !entry.in_main && args.shard.is_none() => {
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
        write(&mut out, 0, 0, &opt.start, &result)?;
        let (start, source) = result;
        searched.run += usize::from(matches!(source, Source::Run));
        searched.interrupted = start.interrupted();
        if !searched.interrupted {
            println!(
                "start: objective {}",
                start.objective.map_or_else(
                    || format!("failed ({})", start.failure.clone().unwrap_or_default()),
                    |o| format!("{o:.4}")
                )
            );
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
        for (i, (x, result)) in xs.iter().zip(&results).enumerate() {
            if let Some(result) = result {
                write(&mut out, generation, i, x, result)?;
            }
        }
        out.flush()?;
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
        if args.shard.is_some() && (ran > 0 || !owed.is_empty()) {
            // a shard step: one generation's slice; the next step needs every shard's
            searched.stopped_at = Some((generation, owed));
            break;
        }
        let mut ys = Vec::with_capacity(xs.len());
        let mut objectives = Vec::new();
        for (x, result) in xs.iter().zip(&results) {
            let Some((e, _)) = result else { continue };
            // CMA-ES minimises; a failed candidate ranks below every one that ran
            ys.push(e.objective.map_or(f64::MAX, |o| -o));
            searched.history.push(Evaluated {
                x: x.clone(),
                objective: e.objective,
            });
            if let Some(o) = e.objective {
                objectives.push(o);
                if searched.best.as_ref().is_none_or(|(b, _)| o > *b) {
                    searched.best = Some((o, x.clone()));
                }
            }
        }
        objectives.sort_by(f64::total_cmp);
        let median = objectives.get(objectives.len() / 2).copied();
        let rate = searched.run.max(1) as f64 / started.elapsed().as_secs_f64();
        let left = (opt.generations - generation) * population;
        println!(
            "generation {generation}/{}: best {}, median {}, {} failed; {rate:.2} evaluations/s, ETA {:.0} s{}",
            opt.generations,
            searched
                .best
                .as_ref()
                .map_or("-".into(), |(b, _)| format!("{b:.4}")),
            median.map_or("-".into(), |m| format!("{m:.4}")),
            xs.len() - objectives.len(),
            left as f64 / rate.max(1e-9),
            if ran == 0 {
                " (replayed from the log)"
            } else {
                ""
            },
        );
        if es.tell(&ys) != 0 {
            break;
        }
    }
    out.flush()?;
    Ok(searched)
}

/// What a shard step did and what comes next; exit 0 (130 when interrupted).
fn report_shard(
    opt: &Optimization,
    args: &OptimizeArgs,
    shard: Shard,
    searched: &Searched,
) -> ExitCode {
    let file = log::shard_file(&args.output, shard);
    match &searched.stopped_at {
        _ if searched.interrupted => {
            println!(
                "shard {shard} interrupted: its finished evaluations are in {}; run the step again",
                file.display()
            );
            return ExitCode::from(130);
        }
        None => println!(
            "the search's {} generations are all logged: finish with `hexsim optimize {} --output {} --resume` (the best gait, the summary, the checks and the recordings)",
            opt.generations,
            args.file.display(),
            args.output.display()
        ),
        Some((generation, owed)) if searched.run > 0 => println!(
            "shard {shard}: ran {} evaluations of generation {generation}/{} into {}{}",
            searched.run,
            opt.generations,
            file.display(),
            if owed.is_empty() {
                String::new()
            } else {
                format!(
                    "; the next step needs the other shards' candidates {owed:?} of generation {generation}"
                )
            }
        ),
        Some((generation, owed)) => println!(
            "shard {shard}: nothing to run; generation {generation}/{} waits for the other shards' candidates {owed:?}",
            opt.generations
        ),
    }
    ExitCode::SUCCESS
}

/// The objective of candidate `x` on each of `cases` in `articulation` (None where it failed).
fn per_case(
    opt: &Optimization,
    x: &[f64],
    cases: &[&Case],
    articulation: Articulation,
) -> Vec<Option<f64>> {
    cases
        .par_iter()
        .map(|&c| opt.evaluate_on(x, &[c], Some(articulation)).objective)
        .collect()
}

/// The start and the best on every terrain and seed, searched and not, in both articulations —
/// what the search found, and how much of it the exact (multibody) joints keep — the multibody
/// runs recorded, start and best superposed, one recording each. None when Ctrl-C cut them
/// short.
fn check(
    opt: &Optimization,
    x: &[f64],
    args: &OptimizeArgs,
    jobs: usize,
    written: &mut Vec<PathBuf>,
) -> Result<Option<Vec<serde_json::Value>>> {
    let cases: Vec<&Case> = opt.cases.iter().collect();
    let (start_impulse, best_impulse) = rayon::join(
        || per_case(opt, &opt.start, &cases, Articulation::Impulse),
        || per_case(opt, x, &cases, Articulation::Impulse),
    );
    let mut multibody = Vec::new();
    for case in &cases {
        let (pair, path) = multibody_pair(opt, x, case, args, jobs)?;
        multibody.push(pair);
        written.extend(path);
    }
    if hexsim::runner::interrupted() {
        return Ok(None);
    }
    println!(
        "objective                      start (impulse)  best (impulse)  start (multibody)  best (multibody)"
    );
    let cell = |v: &Option<f64>| v.map_or("failed".to_string(), |v| format!("{v:.4}"));
    let mut checks = Vec::new();
    for (k, case) in cases.iter().enumerate() {
        let label = format!(
            "{}{}",
            case.label(),
            if case.searched { "" } else { " (not searched)" }
        );
        println!(
            "{label:30} {:>15}  {:>14}  {:>17}  {:>16}",
            cell(&start_impulse[k]),
            cell(&best_impulse[k]),
            cell(&multibody[k].0.objective),
            cell(&multibody[k].1.objective),
        );
        checks.push(serde_json::json!({
            "terrain": case.terrain_name,
            "seed": case.seeded.then_some(case.seed),
            "searched": case.searched,
            "start_impulse": start_impulse[k],
            "best_impulse": best_impulse[k],
            "start_multibody": multibody[k].0.objective,
            "best_multibody": multibody[k].1.objective,
            "start_multibody_constraints": multibody[k].0.constraints,
            "best_multibody_constraints": multibody[k].1.constraints,
        }));
    }
    Ok(Some(checks))
}

/// A check run: its objective (None: failed) and each constraint's measured value.
struct Checked {
    objective: Option<f64>,
    constraints: serde_json::Map<String, serde_json::Value>,
}

/// The start and the best walking `case` in the multibody; unless --no-record, recorded
/// superposed to DIR/TERRAIN-seed-S.rrd, their trajectories kept in DIR/trajectories/.
fn multibody_pair(
    opt: &Optimization,
    x: &[f64],
    case: &Case,
    args: &OptimizeArgs,
    jobs: usize,
) -> Result<((Checked, Checked), Option<PathBuf>)> {
    let settings = [("start", &opt.start[..]), ("best", x)]
        .into_iter()
        .map(|(name, x)| opt.scenario(x, case, Some(Articulation::Multibody), name))
        .collect::<Result<Vec<_>, _>>()?;
    let comparison = Comparison {
        file: PathBuf::from(format!("{} {}", opt.name(), case.label())),
        description: opt.description.clone(),
        settings,
    };
    let dir = if args.no_record {
        std::env::temp_dir().join(format!(
            "hexsim-optimize-{}-{}",
            std::process::id(),
            case.file_stem()
        ))
    } else {
        args.output.join("trajectories").join(case.file_stem())
    };
    let outcomes = compare::run(&comparison, &dir, jobs)?;
    let checked = |k: usize| Checked {
        objective: optimize::judge(case, &outcomes[k].report)
            .ok()
            .map(|m| opt.score(&m)),
        constraints: outcomes[k]
            .report
            .as_ref()
            .map(|r| {
                r.checks
                    .iter()
                    .map(|c| (c.expectation.clone(), serde_json::json!(c.value)))
                    .collect()
            })
            .unwrap_or_default(),
    };
    let pair = (checked(0), checked(1));
    if args.no_record {
        let _ = std::fs::remove_dir_all(&dir);
        return Ok((pair, None));
    }
    let path = hexsim::compare::recording::write_titled(
        &args.output.join(format!("{}.rrd", case.file_stem())),
        &format!("start and best on {}", case.label()),
        &comparison,
        &outcomes,
    )?;
    Ok((pair, Some(path)))
}
