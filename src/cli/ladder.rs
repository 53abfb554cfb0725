//! `hexsim ladder`: a robot over each terrain family at rising difficulty, blind and perceptive;
//! the highest level crossed per family, and the highest crossed as the walk commanded (no
//! skating, drift or turn), as a table and JSON (see `hexsim::ladder`).

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

use super::warn_about;

#[derive(Args)]
pub struct LadderArgs {
    /// Ladder families: sweep scenario files or folders of them (see docs/rough-ground.md), or
    /// the name of a built-in family (gaps, obstacles, pyramid, rough, slope_down, slope_up,
    /// stairs_down, stairs_up, stones). Default: the folder ladder/ if there is one here, else
    /// every built-in family.
    #[arg(default_value = "ladder")]
    families: Vec<String>,
    /// The robot to walk (a URDF); default: each family's own (hex18). Its runs last as long as
    /// the robot needs at half its nominal speed to cross.
    #[arg(long)]
    robot: Option<PathBuf>,
    /// Folder for the results: ladder.json (per family and per run), results.jsonl (the batch's
    /// records), ladder.md (the table), ladder.svg (the chart: a cell per run, coloured by how
    /// it ended).
    #[arg(short, long, default_value = "ladder-results")]
    output: PathBuf,
    /// Worker threads, one simulation each. Default: all cores; at most 1024.
    #[arg(short, long, value_parser = hexsim::limits::threads)]
    jobs: Option<usize>,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
}

/// Exit codes: 0 the ladder ran (whatever the robot crossed: a stall is a result), 2 an input
/// error, 130 interrupted.
pub fn ladder(args: LadderArgs) -> Result<ExitCode> {
    use hexsim::batch::{self, Progress};
    let sources = hexsim::ladder::Source::resolve(&args.families)?;
    let hexsim::ladder::Ladder {
        families,
        rungs,
        scenarios,
    } = hexsim::ladder::load(&sources, args.robot.as_deref()).map_err(anyhow::Error::new)?;
    warn_about(&scenarios, false)?;
    let jobs = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    if jobs == 0 {
        anyhow::bail!("--jobs: expected at least 1");
    }
    hexsim::record::output::create_folder(&args.output, "--output")?;
    let robot = args
        .robot
        .as_ref()
        .map_or("each family's robot".into(), |p| p.display().to_string());
    eprintln!(
        "{} families, {} runs of {robot} on {jobs} thread{} → {}",
        families.len(),
        scenarios.len(),
        if jobs == 1 { "" } else { "s" },
        args.output.display()
    );
    let options = batch::Options {
        jobs,
        output: args.output.join("results.jsonl"),
        resume: false,
        shard: batch::Shard::WHOLE,
        record_dir: args.output.join("recordings"),
        progress: if args.quiet {
            Progress::Quiet
        } else {
            Progress::Lines
        },
    };
    let outcome = batch::run(&scenarios, &options)?;
    let mut result = hexsim::ladder::summarise(&robot, &families, &rungs, &outcome.records);
    result.caveats = hexsim::ladder::caveats(&scenarios);
    let table = result.table(&families);
    out!("\n{table}");
    use hexsim::ladder::Outcome;
    let broken = |o: Outcome| matches!(o, Outcome::Diverged | Outcome::Error);
    for run in result.runs.iter().filter(|r| broken(r.outcome)) {
        out!(
            "{} at {} ({}): {}",
            run.family,
            run.level,
            if run.perceptive {
                "perceptive"
            } else {
                "blind"
            },
            run.message.as_deref().unwrap_or_default()
        );
    }
    hexsim::record::output::write_json(Some(&args.output.join("ladder.json")), &result)?;
    // each write names its file when it fails (a full disk)
    hexsim::record::output::write_atomically(&args.output.join("ladder.md"), table.as_bytes())?;
    hexsim::record::output::write_atomically(
        &args.output.join("ladder.svg"),
        hexsim::ladder::chart::svg(&result).as_bytes(),
    )?;
    out!(
        "{:.1} s wall; results in {}",
        outcome.wall_time,
        args.output.display()
    );
    if outcome.interrupted {
        out!("interrupted: {} runs not run", outcome.not_run);
        return Ok(ExitCode::from(130));
    }
    Ok(ExitCode::SUCCESS)
}
