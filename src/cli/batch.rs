//! `hexsim batch`: scenario files run headless in parallel, checked against their expectations
//! and a baseline.

use anyhow::Result;
use clap::Args;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use super::warn_about;

#[derive(Args)]
pub struct BatchArgs {
    /// Scenario files, folders (every .toml below them) or glob patterns.
    #[arg(required = true)]
    scenarios: Vec<String>,
    /// Worker threads, one simulation each. Default: all cores; at most 1024.
    #[arg(short, long, value_parser = hexsim::limits::threads)]
    jobs: Option<usize>,
    /// Results file (JSON Lines, one record per scenario, written as each finishes).
    #[arg(short, long, default_value = "results.jsonl")]
    output: PathBuf,
    /// Keep the results already in the output file (same scenario name and content) and run only
    /// the rest.
    #[arg(long)]
    resume: bool,
    /// Compare the metrics with an earlier results file; a metric that moved beyond its tolerance
    /// fails the batch.
    #[arg(long)]
    baseline: Option<PathBuf>,
    /// Default relative tolerance for --baseline (scenarios can set `[tolerance.METRIC]`).
    #[arg(long, default_value_t = 0.05)]
    rel_tol: f64,
    /// Run only the I-th of N slices of the scenario list (for a cluster array job).
    #[arg(long, default_value = "1/1", value_name = "I/N")]
    shard: hexsim::batch::Shard,
    /// Folder for the recordings and trajectories that scenarios ask for (`[record]`).
    #[arg(long, default_value = "recordings")]
    record_dir: PathBuf,
    /// List every scenario in the table, however many.
    #[arg(long)]
    all: bool,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
    /// Treat warnings (a missing visual mesh, a gait leaving fewer than three feet down) as errors;
    /// notes (a smaller step hexsim chose) are not warnings.
    #[arg(long)]
    strict: bool,
}

/// Exit codes: 0 every expectation met, 1 some failed (or diverged, or regressed against the
/// baseline), 2 a usage or input error, 130 interrupted.
pub fn batch(args: BatchArgs) -> Result<ExitCode> {
    use hexsim::batch::{self, Progress, results};
    let files = batch::scenario_files(&args.scenarios)?;
    let mut scenarios = match batch::load(&files) {
        Ok(s) => s,
        Err(errors) => {
            for e in &errors {
                eprintln!("error: {e}");
            }
            anyhow::bail!(
                "{} scenario file problem{}; nothing was run",
                errors.len(),
                if errors.len() == 1 { "" } else { "s" }
            );
        }
    };
    // every walk is judged against its command unless its file says `walk_as_commanded = false`
    for scenario in &mut scenarios {
        if scenario.spec.kind == hexsim::scenario::Kind::Walk {
            scenario.spec.expect.walk_as_commanded.get_or_insert(true);
        }
    }
    // the results file (and the baseline it is compared with) must not be a file the batch reads
    let inputs: Vec<(&'static str, std::path::PathBuf)> = scenarios
        .iter()
        .flat_map(|s| s.inputs())
        .chain(args.baseline.iter().map(|b| ("baseline", b.clone())))
        .collect();
    // nor is a scenario's recording or trajectory (another scenario's height file, the results)
    let records: Vec<(&'static str, std::path::PathBuf)> = scenarios
        .iter()
        .flat_map(|s| hexsim::batch::record_files(s, &args.record_dir))
        .flatten()
        .collect();
    let outputs = std::iter::once(("results file -o", args.output.as_path()))
        .chain(records.iter().map(|(what, path)| (*what, path.as_path())));
    hexsim::record::output::check_distinct(
        outputs,
        inputs.iter().map(|(what, path)| (*what, path.as_path())),
    )?;
    let baseline = match &args.baseline {
        Some(path) => Some(results::read(path, false)?.0),
        None => None,
    };
    if !(args.rel_tol.is_finite() && args.rel_tol >= 0.0) {
        anyhow::bail!("--rel-tol: expected a fraction ≥ 0, got {}", args.rel_tol);
    }
    let jobs = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    if jobs == 0 {
        anyhow::bail!("--jobs: expected at least 1");
    }
    let mine = (0..scenarios.len())
        .filter(|&i| args.shard.contains(i))
        .count();
    eprintln!(
        "{} scenarios from {} file{}{}; running {mine} on {jobs} thread{} → {}",
        scenarios.len(),
        files.len(),
        if files.len() == 1 { "" } else { "s" },
        if args.shard == batch::Shard::WHOLE {
            String::new()
        } else {
            format!(", shard {}", args.shard)
        },
        if jobs == 1 { "" } else { "s" },
        args.output.display()
    );
    // a shard says what concerns the scenarios it runs (the others' shards say theirs)
    let shards = scenarios.iter().enumerate();
    warn_about(
        shards
            .filter(|&(i, _)| args.shard.contains(i))
            .map(|(_, s)| s),
        args.strict,
    )?;
    let options = batch::Options {
        jobs,
        output: args.output.clone(),
        resume: args.resume,
        shard: args.shard,
        record_dir: args.record_dir.clone(),
        progress: if args.quiet {
            Progress::Quiet
        } else if std::io::stderr().is_terminal() {
            Progress::Bar
        } else {
            Progress::Lines
        },
    };
    let mut outcome = batch::run(&scenarios, &options)?;
    let (regressions, missing) = match &baseline {
        Some(b) => batch::compare_with_baseline(&outcome.records, &scenarios, b, args.rel_tol),
        None => Default::default(),
    };
    // the results file says what the comparison found: a regressed record's status and what moved
    if batch::mark_regressions(&mut outcome.records, &regressions) {
        batch::results::write_all(&args.output, &outcome.records)?;
    }
    out!();
    out_part!(
        "{}",
        batch::summary::table(
            &outcome.records,
            baseline.is_some(),
            outcome.records.len() <= 60 || args.all
        )
    );
    for change in &outcome.changed {
        out!("run again (changed since its result): {change}");
    }
    if outcome.resumed > 0 {
        out!(
            "{} results kept from the earlier run (--resume)",
            outcome.resumed
        );
    }
    if !missing.is_empty() {
        out!("not in the baseline: {} (not compared)", missing.join(", "));
    }
    out!(
        "{:.1} s wall, {:.0} steps/s over {jobs} thread{}; results in {}",
        outcome.wall_time,
        outcome.throughput(),
        if jobs == 1 { "" } else { "s" },
        args.output.display()
    );
    use hexsim::batch::results::Status;
    let any = |s: Status| outcome.records.iter().any(|r| r.status == s);
    if outcome.interrupted {
        out!(
            "interrupted: {} scenarios not run; finish with --resume",
            outcome.not_run
        );
        return Ok(ExitCode::from(130));
    }
    Ok(if any(Status::Error) {
        ExitCode::from(2)
    } else if any(Status::Failed) || any(Status::Diverged) || !regressions.is_empty() {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}
