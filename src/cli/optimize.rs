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

/// Exit codes: 0 done (or interrupted, with what was found so far), 1 no candidate met the
/// constraints, 2 an input error.
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
    let mut log = std::io::BufWriter::new(std::fs::File::create(&log_path)?);
    let started = std::time::Instant::now();
    let start = pool.install(|| opt.evaluate(&opt.start));
    writeln!(log, "{}", log_line(&opt, 0, 0, &opt.start, &start))?;
    println!(
        "start: objective {}",
        start.objective.map_or_else(
            || format!("failed ({})", start.failure.clone().unwrap_or_default()),
            |o| format!("{o:.4}")
        )
    );
    let mut best: Option<(f64, Vec<f64>)> = start.objective.map(|o| (o, opt.start.clone()));
    let mut evaluations = 1usize;
    for generation in 1..=opt.generations {
        let xs = es.ask();
        let results: Vec<Evaluation> =
            pool.install(|| xs.par_iter().map(|x| opt.evaluate(x)).collect());
        evaluations += xs.len();
        let mut ys = Vec::with_capacity(xs.len());
        let mut objectives = Vec::new();
        for (i, (x, e)) in xs.iter().zip(&results).enumerate() {
            writeln!(log, "{}", log_line(&opt, generation, i, x, e))?;
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
        let rate = evaluations as f64 / started.elapsed().as_secs_f64();
        let left = (opt.generations - generation) * population;
        println!(
            "generation {generation}/{}: best {}, median {}, {} failed; {rate:.2} evaluations/s, ETA {:.0} s",
            opt.generations,
            best.as_ref().map_or("-".into(), |(b, _)| format!("{b:.4}")),
            median.map_or("-".into(), |m| format!("{m:.4}")),
            xs.len() - objectives.len(),
            left as f64 / rate.max(1e-9),
        );
        let stop = es.tell(&ys);
        if stop != 0 || hexsim::runner::interrupted() {
            break;
        }
    }
    let Some((objective, x)) = best else {
        println!(
            "no candidate met the constraints; every evaluation is in {}",
            log_path.display()
        );
        return Ok(ExitCode::from(1));
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
    std::fs::write(
        args.output.join("summary.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
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
