//! `hexsim optimize FILE`: the best gait for a robot on a set of terrains (see `hexsim::optimize`).

use anyhow::Result;
use clap::Args;
use fcmaes_core::{Cmaes, CmaesParams, Fitness};
use hexsim::optimize::{self, Evaluation, Optimization};
use hexsim::sim::Articulation;
use rayon::prelude::*;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct OptimizeArgs {
    /// Optimisation file (TOML): the scenario, the parameters and their bounds, the terrain
    /// seeds, the objective and the constraints (see optimizations/).
    file: PathBuf,
    /// Folder for the log of every evaluation (evaluations.jsonl), the best gait (best_gait.toml)
    /// and the summary (summary.json).
    #[arg(long, default_value = "optimize")]
    output: PathBuf,
    /// Worker threads. Default: all cores.
    #[arg(short, long)]
    jobs: Option<usize>,
    /// Continue an interrupted search: the evaluations already in the output folder's log are
    /// replayed (the same specification and seed ask for the same candidates), not run again.
    #[arg(long)]
    resume: bool,
}

/// Whether a logged candidate is this one, to within the last bits a decimal log can lose.
fn same(logged: &[f64], x: &[f64]) -> bool {
    logged.len() == x.len()
        && logged
            .iter()
            .zip(x)
            .all(|(a, b)| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300))
}

/// Logged evaluations by (generation, index): the parameters and the result.
type Logged = std::collections::HashMap<(usize, usize), (Vec<f64>, Evaluation)>;

/// Reads an earlier log (a cut-off last line is dropped).
fn read_log(path: &std::path::Path, opt: &Optimization) -> Result<Logged> {
    let mut logged = Logged::new();
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(logged);
    };
    for line in text.lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        let at = |k: &str| v[k].as_u64().map(|n| n as usize);
        let (Some(generation), Some(index)) = (at("generation"), at("index")) else {
            continue;
        };
        let x: Option<Vec<f64>> = opt
            .parameters
            .iter()
            .map(|(name, _, _)| v["parameters"][name].as_f64())
            .collect();
        let Some(x) = x else { continue };
        let evaluation = Evaluation {
            objective: v["objective"].as_f64(),
            failure: v["failure"].as_str().map(str::to_string),
            metrics: Vec::new(),
        };
        logged.insert((generation, index), (x, evaluation));
    }
    Ok(logged)
}

/// One logged evaluation.
fn log_line(
    opt: &Optimization,
    generation: usize,
    index: usize,
    x: &[f64],
    e: &Evaluation,
) -> serde_json::Value {
    let parameters: serde_json::Map<String, serde_json::Value> = opt
        .parameters
        .iter()
        .zip(x)
        .map(|((name, _, _), v)| (name.clone(), serde_json::json!(v)))
        .collect();
    let metrics: Vec<serde_json::Value> = e
        .metrics
        .iter()
        .map(|m| {
            let named: serde_json::Map<String, serde_json::Value> = opt
                .objective
                .iter()
                .map(|(name, _)| {
                    (
                        name.clone(),
                        serde_json::json!(optimize::metric_value(m, name)),
                    )
                })
                .collect();
            serde_json::Value::Object(named)
        })
        .collect();
    serde_json::json!({
        "generation": generation,
        "index": index,
        "parameters": parameters,
        "objective": e.objective,
        "status": if e.failure.is_some() { "failed" } else { "ok" },
        "failure": e.failure,
        "metrics_per_seed": metrics,
    })
}

/// Each seed's objective for the candidate `x` in `articulation` (None where it failed).
fn per_seed(
    opt: &Optimization,
    x: &[f64],
    seeds: &[u32],
    articulation: Articulation,
) -> Vec<Option<f64>> {
    seeds
        .par_iter()
        .map(|&s| opt.evaluate_on(x, &[s], Some(articulation)).objective)
        .collect()
}

/// Exit codes: 0 done, 1 no candidate met the constraints, 2 an input error, 130 interrupted
/// (what was found so far written; `--resume` continues).
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
    let (low, high): (Vec<f64>, Vec<f64>) = opt.parameters.iter().map(|(_, l, h)| (*l, *h)).unzip();
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
    let log_path = args.output.join("evaluations.jsonl");
    let logged = if args.resume {
        read_log(&log_path, &opt)?
    } else {
        Logged::new()
    };
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(args.resume)
        .write(true)
        .truncate(!args.resume)
        .open(&log_path)?;
    let mut log = std::io::BufWriter::new(file);
    let started = std::time::Instant::now();
    // a candidate the log already holds (same generation, index and parameters) is replayed
    let evaluate = |generation: usize, index: usize, x: &[f64]| -> (Evaluation, bool) {
        match logged.get(&(generation, index)) {
            // the same candidate: JSON's decimal round trip may move the last bit
            Some((logged_x, e)) if same(logged_x, x) => (
                Evaluation {
                    objective: e.objective,
                    failure: e.failure.clone(),
                    metrics: Vec::new(),
                },
                true,
            ),
            _ => (opt.evaluate(x), false),
        }
    };
    let (start, replayed) = pool.install(|| evaluate(0, 0, &opt.start));
    if !replayed && !start.interrupted() {
        writeln!(log, "{}", log_line(&opt, 0, 0, &opt.start, &start))?;
    }
    println!(
        "start: objective {}",
        start.objective.map_or_else(
            || format!("failed ({})", start.failure.clone().unwrap_or_default()),
            |o| format!("{o:.4}")
        )
    );
    let mut best: Option<(f64, Vec<f64>)> = start.objective.map(|o| (o, opt.start.clone()));
    let (mut evaluations, mut replays) = (1usize, usize::from(replayed));
    let mut interrupted = start.interrupted();
    for generation in 1..=opt.generations {
        if interrupted {
            break;
        }
        let xs = es.ask();
        let results: Vec<(Evaluation, bool)> = pool.install(|| {
            xs.par_iter()
                .enumerate()
                .map(|(i, x)| evaluate(generation, i, x))
                .collect()
        });
        if results.iter().any(|(e, _)| e.interrupted()) {
            // keep what finished; the generation is not told, --resume runs it again
            for (i, (x, (e, replayed))) in xs.iter().zip(&results).enumerate() {
                if !replayed && !e.interrupted() {
                    writeln!(log, "{}", log_line(&opt, generation, i, x, e))?;
                }
            }
            interrupted = true;
            break;
        }
        evaluations += xs.len();
        let mut ys = Vec::with_capacity(xs.len());
        let mut objectives = Vec::new();
        for (i, (x, (e, replayed))) in xs.iter().zip(&results).enumerate() {
            if *replayed {
                replays += 1;
            } else {
                writeln!(log, "{}", log_line(&opt, generation, i, x, e))?;
            }
            // CMA-ES minimises; a failed candidate ranks below every one that ran
            ys.push(e.objective.map_or(f64::MAX, |o| -o));
            if let Some(o) = e.objective {
                objectives.push(o);
                if best.as_ref().is_none_or(|(b, _)| o > *b) {
                    best = Some((o, x.clone()));
                }
            }
        }
        log.flush()?;
        objectives.sort_by(f64::total_cmp);
        let median = objectives.get(objectives.len() / 2).copied();
        let rate = (evaluations - replays).max(1) as f64 / started.elapsed().as_secs_f64();
        let left = (opt.generations - generation) * population;
        println!(
            "generation {generation}/{}: best {}, median {}, {} failed; {rate:.2} evaluations/s, ETA {:.0} s{}",
            opt.generations,
            best.as_ref().map_or("-".into(), |(b, _)| format!("{b:.4}")),
            median.map_or("-".into(), |m| format!("{m:.4}")),
            xs.len() - objectives.len(),
            left as f64 / rate.max(1e-9),
            if results.iter().all(|(_, r)| *r) {
                " (replayed from the log)"
            } else {
                ""
            },
        );
        let stop = es.tell(&ys);
        if stop != 0 {
            break;
        }
    }
    log.flush()?;
    if interrupted {
        println!(
            "interrupted: every finished evaluation is in {}; continue with --resume",
            log_path.display()
        );
    }
    let Some((objective, x)) = best else {
        if !interrupted {
            println!(
                "no candidate met the constraints; every evaluation is in {}",
                log_path.display()
            );
        }
        return Ok(ExitCode::from(if interrupted { 130 } else { 1 }));
    };
    let gait_path = args.output.join("best_gait.toml");
    std::fs::write(
        &gait_path,
        format!(
            "# found by `hexsim optimize {}`: objective {objective:.4} (start {})\n{}",
            args.file.display(),
            start
                .objective
                .map_or("failed".into(), |o| format!("{o:.4}")),
            opt.gait_file(&x)
        ),
    )?;
    let summary = serde_json::json!({
        "optimization": args.file.display().to_string(),
        "evaluations": evaluations,
        "wall_time_s": started.elapsed().as_secs_f64(),
        "start": { "parameters": opt.start, "objective": start.objective },
        "best": { "parameters": x, "objective": objective },
        "parameter_names": opt.parameters.iter().map(|(n, _, _)| n.clone()).collect::<Vec<_>>(),
    });
    // written now, so the summary survives checks that Ctrl-C cuts short
    std::fs::write(
        args.output.join("summary.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    if interrupted {
        // the best so far is written; the checks would be cut short too
        return Ok(ExitCode::from(130));
    }
    // the start and the best on every seed, searched and not, in both articulations: what the
    // search found, and how much of it the exact (multibody) joints keep
    let all_seeds: Vec<(u32, bool)> = opt
        .seeds
        .iter()
        .map(|&s| (s, true))
        .chain(opt.check_seeds.iter().map(|&s| (s, false)))
        .collect();
    let seeds: Vec<u32> = all_seeds.iter().map(|(s, _)| *s).collect();
    let mut columns = Vec::new();
    for articulation in [Articulation::Impulse, Articulation::Multibody] {
        let (a, b) = pool.install(|| {
            rayon::join(
                || per_seed(&opt, &opt.start, &seeds, articulation),
                || per_seed(&opt, &x, &seeds, articulation),
            )
        });
        columns.push((a, b));
    }
    if hexsim::runner::interrupted() {
        // the checks were cut short: their runs are not results
        return Ok(ExitCode::from(130));
    }
    println!(
        "objective per seed             start (impulse)  best (impulse)  start (multibody)  best (multibody)"
    );
    let cell = |v: &Option<f64>| v.map_or("failed".to_string(), |v| format!("{v:.4}"));
    let mut checks = Vec::new();
    for (k, (seed, searched)) in all_seeds.iter().enumerate() {
        let label = format!(
            "seed {seed}{}",
            if *searched { "" } else { " (not searched)" }
        );
        println!(
            "{label:30} {:>15}  {:>14}  {:>17}  {:>16}",
            cell(&columns[0].0[k]),
            cell(&columns[0].1[k]),
            cell(&columns[1].0[k]),
            cell(&columns[1].1[k]),
        );
        checks.push(serde_json::json!({
            "seed": seed,
            "searched": searched,
            "start_impulse": columns[0].0[k],
            "best_impulse": columns[0].1[k],
            "start_multibody": columns[1].0[k],
            "best_multibody": columns[1].1[k],
        }));
    }
    let mut summary = summary;
    summary["per_seed"] = serde_json::Value::Array(checks);
    std::fs::write(
        args.output.join("summary.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    println!("parameter          start       best");
    for ((name, _, _), (s, b)) in opt.parameters.iter().zip(opt.start.iter().zip(&x)) {
        println!("{name:18} {s:>8.4}   {b:>8.4}");
    }
    println!(
        "objective          {:>8}   {objective:>8.4}",
        start
            .objective
            .map_or("failed".into(), |o| format!("{o:.4}"))
    );
    println!(
        "wrote {}, {} and summary.json",
        gait_path.display(),
        log_path.display()
    );
    Ok(ExitCode::SUCCESS)
}
