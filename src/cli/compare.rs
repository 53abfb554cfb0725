//! `hexsim compare FILE`: one scenario under several contact settings, side by side — a table of
//! their metrics, a JSON of them, and one recording with every setting superposed.

use anyhow::Result;
use clap::Args;
use hexsim::compare;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct CompareArgs {
    /// Comparison file (TOML): a scenario and the [[setting]]s to run it under (see
    /// comparisons/).
    file: PathBuf,
    /// The recording of every setting superposed.
    #[arg(long, default_value = "compare.rrd", conflicts_with = "no_record")]
    record: PathBuf,
    /// Do not write a recording.
    #[arg(long)]
    no_record: bool,
    /// Every setting's metrics as JSON.
    #[arg(long)]
    metrics: Option<PathBuf>,
    /// Folder for each setting's trajectory CSV (NAME.csv). Default: none written (the recording
    /// is drawn from the trajectories in memory).
    #[arg(long)]
    trajectories: Option<PathBuf>,
    /// Worker threads, one run each. Default: all cores; at most 1024.
    #[arg(short, long, value_parser = hexsim::limits::threads)]
    jobs: Option<usize>,
    /// Open the recording in the rerun viewer when done.
    #[arg(long)]
    spawn: bool,
}

/// Exit codes: 0 every setting ran to its end, 1 some diverged (the others are still reported
/// and recorded), 2 an input error.
pub fn compare(args: CompareArgs) -> Result<ExitCode> {
    let comparison = compare::load(&args.file)?;
    // no output may be the comparison file, a file a setting reads, or another output
    let trajectories: Vec<PathBuf> = match &args.trajectories {
        Some(dir) => comparison
            .settings
            .iter()
            .map(|s| dir.join(format!("{}.csv", s.name.replace(' ', "_"))))
            .collect(),
        None => Vec::new(),
    };
    let record = (!args.no_record).then_some(args.record.as_path());
    let outputs = [("--record", record), ("--metrics", args.metrics.as_deref())]
        .into_iter()
        .filter_map(|(what, path)| Some((what, path?)))
        .chain(trajectories.iter().map(|p| ("trajectory", p.as_path())));
    let inputs: Vec<(&'static str, PathBuf)> =
        std::iter::once(("comparison file", args.file.clone()))
            .chain(comparison.settings.iter().flat_map(|s| s.inputs()))
            .collect();
    hexsim::record::output::check_distinct(
        outputs,
        inputs.iter().map(|(what, path)| (*what, path.as_path())),
    )?;
    if !args.no_record {
        hexsim::record::output::check_writable(&args.record)?;
    }
    if let Some(path) = &args.metrics {
        hexsim::record::output::check_writable(path)?;
    }
    let jobs = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    if let Some(d) = &comparison.description {
        out!("{d}");
    }
    let outcomes = compare::run(&comparison, args.trajectories.as_deref(), jobs)?;
    // Ctrl-C cuts some runs short: their columns are marked, never mixed in unmarked
    let interrupted = hexsim::interrupt::interrupted();
    let complete = |outcome: &compare::Outcome| match &outcome.report {
        Ok(r) => r.metrics.complete() || r.failure.is_some(),
        Err(_) => !interrupted,
    };
    let mut failed = false;
    let mut json = Vec::new();
    let mut rows: Vec<(String, Vec<String>)> = Vec::new();
    for outcome in &outcomes {
        let (metrics, failure) = match &outcome.report {
            Ok(report) => (Some(report.metrics.to_json()), report.failure.clone()),
            Err(e) => (None, Some(format!("{e:#}"))),
        };
        failed |= failure.is_some();
        if let Some(serde_json::Value::Object(map)) = &metrics {
            for (key, v) in table_rows(map) {
                let key = &key;
                let cell = if v.fract() == 0.0 && v.abs() < 1e12 {
                    format!("{v:.0}")
                } else {
                    format!("{v:.4}")
                };
                match rows.iter_mut().find(|(k, _)| k == key) {
                    Some((_, cells)) => cells.push(cell),
                    None => rows.push((key.clone(), vec![cell])),
                }
            }
        }
        json.push(serde_json::json!({
            "name": outcome.name,
            "complete": complete(outcome),
            "metrics": metrics,
            "failure": failure,
        }));
    }
    let names: Vec<String> = outcomes
        .iter()
        .map(|o| {
            if complete(o) {
                o.name.clone()
            } else {
                format!("{} (cut short)", o.name)
            }
        })
        .collect();
    let width = rows.iter().map(|(k, _)| k.len()).max().unwrap_or(6).max(6);
    let cell_width = names.iter().map(|n| n.len()).max().unwrap_or(8).max(10);
    out_part!("{:width$}", "metric");
    for name in &names {
        out_part!("  {name:>cell_width$}");
    }
    out!();
    for (key, cells) in &rows {
        out_part!("{key:width$}");
        for cell in cells {
            out_part!("  {cell:>cell_width$}");
        }
        out!();
    }
    for (outcome, entry) in outcomes.iter().zip(&json) {
        if let Some(failure) = entry["failure"].as_str() {
            out!("{}: {failure}", outcome.name);
        }
    }
    if let Some(path) = &args.metrics {
        let all = serde_json::json!({
            "comparison": args.file.display().to_string(),
            "settings": json,
        });
        let text = serde_json::to_string_pretty(&all)? + "\n";
        hexsim::record::output::write_atomically(path, text.as_bytes())?;
        out!("wrote {}", path.display());
    }
    if !args.no_record {
        let written = hexsim::compare::recording::write(&args.record, &comparison, &outcomes)?;
        out!("wrote {}", written.display());
        if args.spawn {
            hexsim::record::rerun::spawn_viewer(&written)?;
        }
    }
    Ok(if interrupted {
        eprintln!(
            "interrupted: the settings marked (cut short) stopped early; their figures are not comparable with the others'"
        );
        ExitCode::from(130)
    } else if failed {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

/// A run's metrics as the table's rows: numbers as they are; a list per foot (six: foot slip) as
/// its sum over the feet; a list per axis (three: the ball's final position) as one row per axis.
/// An empty list (a walk's `walk_flags` when none is raised) is no figure.
fn table_rows(map: &serde_json::Map<String, serde_json::Value>) -> Vec<(String, f64)> {
    let mut rows = Vec::new();
    for (key, value) in map {
        match value {
            serde_json::Value::Array(items) if items.is_empty() => {}
            serde_json::Value::Array(items) if items.iter().all(|i| i.is_number()) => {
                let values: Vec<f64> = items.iter().filter_map(serde_json::Value::as_f64).collect();
                if values.len() == 3 {
                    for (axis, v) in ["x", "y", "z"].iter().zip(values) {
                        rows.push((format!("{key} {axis}"), v));
                    }
                } else {
                    rows.push((format!("{key} (sum over feet)"), values.iter().sum()));
                }
            }
            _ => {
                if let Some(v) = value.as_f64() {
                    rows.push((key.clone(), v));
                }
            }
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::table_rows;

    /// Per-foot lists are summed, per-axis ones split; a list of text (`walk_flags`, raised or
    /// not) is no row: an empty one once summed to a "-0" row.
    #[test]
    fn rows_sum_feet_split_axes_and_skip_lists_of_no_number() {
        let metrics = serde_json::json!({
            "distance": 1.5,
            "foot_slip": [1.0, 2.0, 0.0, 0.0, 0.0, 0.5],
            "final_position": [1.0, 2.0, 3.0],
            "walk_flags": [],
            "notes": ["skated"],
        });
        let rows = table_rows(metrics.as_object().unwrap());
        let names: Vec<&str> = rows.iter().map(|(name, _)| name.as_str()).collect();
        assert_eq!(
            names,
            [
                "distance",
                "final_position x",
                "final_position y",
                "final_position z",
                "foot_slip (sum over feet)"
            ]
        );
        assert_eq!(rows[4].1, 3.5);
    }
}
