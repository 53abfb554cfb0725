//! `hexsim optimize FILE`: the best gait for a robot on a set of terrains (see `hexsim::optimize`).

use anyhow::Result;
use clap::Args;
use hexsim::batch::Shard;
use hexsim::optimize::check::CaseCheck;
use hexsim::optimize::search::{self, Progress, Searched};
use hexsim::optimize::{self, Optimization, log, results};
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
    /// Worker threads. Default: all cores; at most 1024.
    #[arg(short, long, value_parser = hexsim::limits::threads)]
    jobs: Option<usize>,
    /// Continue an interrupted (or sharded) search: the evaluations already in the output
    /// folder's log and shard files are replayed (the same specification and seed ask for the
    /// same candidates), not run again.
    #[arg(long)]
    resume: bool,
    /// One step of a search spread over a cluster's array jobs sharing the output folder: run
    /// the I-th of N slices of the next generation that is not yet logged, log it to
    /// shard-I-of-N.jsonl and stop. Step every shard, one generation after another, then finish
    /// with --resume (which joins the shard files and writes the results); see docs/optimize.md.
    #[arg(long, value_name = "I/N")]
    shard: Option<Shard>,
    /// Do not write the recordings.
    #[arg(long)]
    no_record: bool,
}

/// Exit codes: 0 done (or a shard step done), 1 no candidate met the constraints, 2 an input
/// error, 130 interrupted (what was found so far written; `--resume` continues).
pub fn optimize(args: OptimizeArgs) -> Result<ExitCode> {
    let opt = optimize::load(&args.file)?;
    // what the search writes in its folder must not replace what it reads
    let written = [
        "best_gait.toml",
        "summary.json",
        "search.rrd",
        "evaluations.jsonl",
    ]
    .map(|name| args.output.join(name));
    hexsim::record::output::check_distinct(
        written.iter().map(|p| ("output", p.as_path())),
        opt.inputs.iter().map(|(what, p)| (*what, p.as_path())),
    )?;
    hexsim::record::output::create_folder(&args.output, "--output")?;
    let jobs = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build()?;
    if let Some(d) = &opt.description {
        out!("{d}");
    }
    let started = std::time::Instant::now();
    let setting = search::Setting {
        output: &args.output,
        resume: args.resume,
        shard: args.shard,
    };
    let searched = pool.install(|| search::run(&opt, setting, print_progress))?;
    if let Some(shard) = args.shard {
        return Ok(report_shard(&opt, &args, shard, &searched));
    }
    let log_path = log::main_file(&args.output);
    if searched.interrupted {
        out!(
            "interrupted: every finished evaluation is in {}; continue with --resume",
            log_path.display()
        );
    }
    let Some((objective, x)) = searched.best.clone() else {
        if !searched.interrupted {
            out!(
                "no candidate met the constraints; every evaluation is in {}",
                log_path.display()
            );
        }
        return Ok(ExitCode::from(if searched.interrupted { 130 } else { 1 }));
    };
    let wall_time = started.elapsed().as_secs_f64();
    let best = (objective, x.as_slice());
    let mut results = results::write(&opt, &args.file, &args.output, &searched, best, wall_time)?;
    let mut written = results.files(&args.output);
    if !args.no_record {
        written.push(results.record(&opt, &args.file, &args.output, &searched)?);
    }
    out!("{}", results.table.replace("**", ""));
    if searched.interrupted {
        // the best so far is written; the checks would be cut short too
        return Ok(ExitCode::from(130));
    }
    let record = (!args.no_record).then_some(args.output.as_path());
    let checks = pool.install(|| optimize::check::run(&opt, &x, record, jobs, &mut written))?;
    let Some(checks) = checks else {
        // the checks were cut short: their runs are not results
        return Ok(ExitCode::from(130));
    };
    print_checks(&checks);
    results.add_checks(&checks)?;
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    out!("wrote {}", names.join(", "));
    Ok(ExitCode::SUCCESS)
}

/// The start's objective, then a line a generation.
fn print_progress(progress: Progress) {
    match progress {
        Progress::Start(start) => out!(
            "start: objective {}",
            start.objective.map_or_else(
                || format!("failed ({})", start.failure.clone().unwrap_or_default()),
                |o| format!("{o:.4}")
            )
        ),
        Progress::Generation(g) => out!(
            "generation {}/{}: best {}, median {}, {} failed; {:.2} evaluations/s, ETA {:.0} s{}",
            g.number,
            g.of,
            g.best.map_or("-".into(), |b| format!("{b:.4}")),
            g.median.map_or("-".into(), |m| format!("{m:.4}")),
            g.failed,
            g.rate,
            g.eta_seconds,
            if g.replayed {
                " (replayed from the log)"
            } else {
                ""
            },
        ),
    }
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
            out!(
                "shard {shard} interrupted: its finished evaluations are in {}; run the step again",
                file.display()
            );
            return ExitCode::from(130);
        }
        None => out!(
            "the search's {} generations are all logged: finish with `hexsim optimize {} --output {} --resume` (the best gait, the summary, the checks and the recordings)",
            opt.generations,
            args.file.display(),
            args.output.display()
        ),
        Some((generation, owed)) if searched.run > 0 => out!(
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
        Some((generation, owed)) => out!(
            "shard {shard}: nothing to run; generation {generation}/{} waits for the other shards' candidates {owed:?}",
            opt.generations
        ),
    }
    ExitCode::SUCCESS
}

/// The start and the best on every terrain and seed, in both articulations.
fn print_checks(checks: &[CaseCheck]) {
    out!(
        "objective                      start (impulse)  best (impulse)  start (multibody)  best (multibody)"
    );
    let cell = |v: &Option<f64>| v.map_or("failed".to_string(), |v| format!("{v:.4}"));
    for c in checks {
        let label = format!(
            "{}{}",
            c.case.label(),
            if c.case.searched {
                ""
            } else {
                " (not searched)"
            }
        );
        out!(
            "{label:30} {:>15}  {:>14}  {:>17}  {:>16}",
            cell(&c.start_impulse),
            cell(&c.best_impulse),
            cell(&c.start_multibody.objective),
            cell(&c.best_multibody.objective),
        );
    }
}
