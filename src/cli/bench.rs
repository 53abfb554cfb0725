//! `hexsim bench`: simulated steps per second on the reference workloads.

use anyhow::{Context, Result};
use clap::Args;
use hexsim::sim::Articulation;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchArgs {
    /// Which articulations to measure.
    #[arg(long, value_enum, default_values_t = [Articulation::Multibody, Articulation::Impulse])]
    articulation: Vec<Articulation>,
    /// Seconds walked (after 1 s settling), and seconds of the ball.
    #[arg(long, default_value_t = 20.0)]
    duration: f64,
    /// Threads for the batch figure. Default: all cores; at most 1024.
    #[arg(short, long, value_parser = hexsim::limits::threads)]
    jobs: Option<usize>,
    /// Runs per figure; the median is reported, and the best beside it.
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Also write the figures and the configuration as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Also time MuJoCo's equivalent of the walk (bench/mujoco, built in) on this machine, now,
    /// with this Python (default python3; it needs `pip install mujoco numpy`), and print
    /// hexsim's walks as multiples of it: in rounds, each of MuJoCo's runs beside one run of
    /// each walk, the median ratio and its range (a shared machine's speed drifts).
    #[arg(long, value_name = "PYTHON", num_args = 0..=1, default_missing_value = "python3")]
    mujoco: Option<PathBuf>,
}

pub fn bench(args: BenchArgs) -> Result<()> {
    if !(args.duration.is_finite() && args.duration > 0.0) {
        anyhow::bail!("--duration: expected seconds > 0, got {}", args.duration);
    }
    if let Some(path) = &args.json {
        hexsim::record::output::check_writable(path)?;
    }
    let options = hexsim::bench::BenchOptions {
        articulations: args.articulation.clone(),
        duration: args.duration,
        threads: args
            .jobs
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
            .max(1),
        repeats: args.repeats,
        scratch: std::env::temp_dir().join(format!("hexsim-bench-{}.rrd", std::process::id())),
        mujoco: args.mujoco.clone(),
    };
    for (key, value) in hexsim::bench::configuration(&options) {
        out!("{key:>13}: {value}");
    }
    out!();
    out!(
        "{:<30} {:<10} {:>7} {:>9} {:>8} {:>12} {:>9}  notes",
        "workload",
        "joints",
        "threads",
        "steps",
        "wall s",
        "steps/s",
        "best"
    );
    let report = hexsim::bench::run_bench(&options, |f| {
        let mut notes = Vec::new();
        if let Some(ok) = f.v13 {
            notes.push(if ok { "V13 met" } else { "V13 NOT MET" }.to_string());
        }
        if let Some(d) = f.max_joint_drift {
            notes.push(format!("joint drift ≤ {:.1} µm", d * 1e6));
        }
        if let (Some(share), Some(ceiling), Some(own)) =
            (f.rapier_share, f.rapier_ceiling(), f.own_step_seconds())
        {
            notes.push(format!(
                "rapier's step {:.0} % (alone {ceiling:.0} steps/s), hexsim's own {:.1} µs a step",
                share * 100.0,
                own * 1e6
            ));
        }
        out!(
            "{:<30} {:<10} {:>7} {:>9} {:>8.2} {:>12.0} {:>9.0}  {}",
            f.workload,
            f.articulation.as_deref().unwrap_or("-"),
            f.threads,
            f.steps,
            f.wall_time,
            f.steps_per_second,
            f.best_steps_per_second,
            notes.join(", ")
        );
    })?;
    for a in &args.articulation {
        let single = report
            .figures
            .iter()
            .find(|f| f.workload == "walk" && f.articulation.as_deref() == Some(a.name()));
        let batch = report.figures.iter().find(|f| {
            f.workload.starts_with("batch") && f.articulation.as_deref() == Some(a.name())
        });
        if let (Some(s), Some(b)) = (single, batch) {
            out!(
                "{}: batch on {} threads = {:.2}× one thread",
                a.name(),
                b.threads,
                b.steps_per_second / s.steps_per_second
            );
        }
    }
    if let Some(comparison) = &report.mujoco {
        let m = &comparison.figures;
        out!(
            "MuJoCo {} on this machine, the same walk's {} steps: rollout {}, Python loop {:.0} \
             steps/s (best of {}; its base ended at x = {:.2} m, tilted {:.1}°)",
            m.mujoco_version,
            m.steps,
            m.rollout_steps_per_second
                .map_or("not measured".into(), |r| format!("{r:.0}")),
            m.loop_steps_per_second,
            m.repeats,
            m.base_end[0],
            m.tilt_deg,
        );
        let theirs = if m.rollout_steps_per_second.is_some() {
            "rollout"
        } else {
            "Python loop"
        };
        for a in &args.articulation {
            let (median, lo, hi) = comparison.ratios(a.name());
            let (ours, mujoco) = comparison.medians(a.name());
            out!(
                "{} walk: {median:.2}× MuJoCo's {theirs} (median of {} rounds, each run beside \
                 MuJoCo's: {lo:.2}–{hi:.2}×; {ours:.0} against {mujoco:.0} steps/s)",
                a.name(),
                m.repeats,
            );
        }
    }
    out!(
        "V1–V21 (docs/validation.md): cargo test --release --test validation_ball --test validation_hexapod --test validation_whole_body"
    );
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
        out!("wrote {}", path.display());
    }
    Ok(())
}
