//! MuJoCo beside hexsim in one `hexsim bench`: its equivalent of the walk (`bench/mujoco`, built
//! into the binary) timed by Python on the same machine, in the same invocation, so a figure
//! always comes with its comparison — these machines differ by 30 % from one CPU to the next.
//!
//! On a shared machine the speed also drifts, by a third or more within a minute, so two blocks
//! of runs timed one after the other compare two different machines: three `hexsim bench
//! --mujoco` in one spell put the multibody walk at 1.10×, 1.27× and 1.41× MuJoCo's rollout.
//! The comparison is therefore made in rounds ([`Pair`]): each of MuJoCo's runs beside one run
//! of each of hexsim's walks, the order alternating, and the ratio read per round.

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The script, as in the repository's `bench/mujoco/hex18_mujoco.py`.
const SCRIPT: &str = include_str!("../../bench/mujoco/hex18_mujoco.py");

/// What the script measured.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MujocoFigures {
    pub mujoco_version: String,
    pub steps: u64,
    pub repeats: usize,
    /// A Python loop setting the controls and calling `mj_step`, best of the repeats.
    pub loop_steps_per_second: f64,
    /// `mujoco.rollout` with the controls precomputed (None where its API differs).
    pub rollout_steps_per_second: Option<f64>,
    /// Where the base ended and its tilt: the model must walk, not fall.
    pub base_end: [f64; 3],
    pub tilt_deg: f64,
}

impl MujocoFigures {
    /// MuJoCo's best figure: the rollout where measured, else the loop.
    pub fn best(&self) -> f64 {
        self.rollout_steps_per_second
            .unwrap_or(self.loop_steps_per_second)
    }

    /// The figures of several runs as one: the best of each, the last run's end.
    fn merged(runs: &[MujocoFigures]) -> Option<MujocoFigures> {
        let last = runs.last()?;
        let best =
            |f: fn(&MujocoFigures) -> Option<f64>| runs.iter().filter_map(f).reduce(f64::max);
        Some(MujocoFigures {
            repeats: runs.iter().map(|r| r.repeats).sum(),
            loop_steps_per_second: best(|r| Some(r.loop_steps_per_second))?,
            rollout_steps_per_second: best(|r| r.rollout_steps_per_second),
            ..last.clone()
        })
    }
}

/// One round of the comparison: one of hexsim's walks and MuJoCo's run beside it.
#[derive(Debug, Clone, Serialize)]
pub struct Pair {
    pub articulation: String,
    /// hexsim's walk in this round (steps/s).
    pub hexsim: f64,
    /// MuJoCo's best figure in the same round (steps/s; [`MujocoFigures::best`]).
    pub mujoco: f64,
}

impl Pair {
    pub fn ratio(&self) -> f64 {
        self.hexsim / self.mujoco.max(1e-9)
    }
}

/// MuJoCo measured beside hexsim's walks, round by round.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// MuJoCo's figures over all rounds (the best of each).
    pub figures: MujocoFigures,
    /// Each round's walk against MuJoCo, for every articulation measured.
    pub pairs: Vec<Pair>,
}

/// The median of `values` and their range (NaN for none).
fn median_and_range(mut values: Vec<f64>) -> (f64, f64, f64) {
    values.sort_by(f64::total_cmp);
    match (values.first(), values.last()) {
        (Some(&lo), Some(&hi)) => (values[values.len() / 2], lo, hi),
        _ => (f64::NAN, f64::NAN, f64::NAN),
    }
}

impl Comparison {
    /// `rounds` rounds: in each, MuJoCo's walk once and `walk(i)` once for each of the walks
    /// `names[i]`, MuJoCo first in even rounds and last in odd ones (so neither always runs on
    /// a cache, a clock or a neighbour the other left).
    pub fn measure(
        python: &Path,
        steps: u64,
        rounds: usize,
        names: &[&str],
        mut walk: impl FnMut(usize) -> Result<f64>,
    ) -> Result<Comparison> {
        let script = Script::new(python, steps)?;
        let mut runs = Vec::new();
        let mut pairs = Vec::new();
        for round in 0..rounds.max(1) {
            let mujoco_first = round % 2 == 0;
            if mujoco_first {
                runs.push(script.run(1, true)?);
            }
            let ours = (0..names.len())
                .map(&mut walk)
                .collect::<Result<Vec<_>>>()?;
            if !mujoco_first {
                runs.push(script.run(1, true)?);
            }
            let theirs = runs.last().expect("a run this round").best();
            pairs.extend(names.iter().zip(ours).map(|(name, hexsim)| Pair {
                articulation: name.to_string(),
                hexsim,
                mujoco: theirs,
            }));
        }
        let figures = MujocoFigures::merged(&runs).expect("at least one round");
        Ok(Comparison { figures, pairs })
    }

    /// `f` of `articulation`'s rounds: median, lowest, highest.
    fn over(&self, articulation: &str, f: impl Fn(&Pair) -> f64) -> (f64, f64, f64) {
        median_and_range(
            self.pairs
                .iter()
                .filter(|p| p.articulation == articulation)
                .map(f)
                .collect(),
        )
    }

    /// The ratios of `articulation`'s rounds: median, lowest, highest.
    pub fn ratios(&self, articulation: &str) -> (f64, f64, f64) {
        self.over(articulation, Pair::ratio)
    }

    /// The medians of `articulation`'s own figures and of MuJoCo's over its rounds.
    pub fn medians(&self, articulation: &str) -> (f64, f64) {
        (
            self.over(articulation, |p| p.hexsim).0,
            self.over(articulation, |p| p.mujoco).0,
        )
    }
}

/// A scratch folder, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The MuJoCo equivalent of the walk, ready to run with `python` (which needs `mujoco` and
/// `numpy`): the script, hex18 and the bench's natural terrain written once to a scratch folder
/// (removed when dropped), and run once a round.
struct Script {
    scratch: Scratch,
    python: PathBuf,
    steps: u64,
    /// The terrain's side (m).
    size: f64,
}

impl Script {
    fn new(python: &Path, steps: u64) -> Result<Script> {
        let dir = std::env::temp_dir().join(format!("hexsim-bench-mujoco-{}", std::process::id()));
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        let scratch = Scratch(dir);
        std::fs::write(scratch.0.join("hex18_mujoco.py"), SCRIPT)?;
        std::fs::write(
            scratch.0.join("hex18.urdf"),
            crate::scenario::builtin::HEX18.text,
        )?;
        let terrain = super::bench_terrain()?;
        crate::terrain::io::write_csv(&terrain, &scratch.0.join("natural.csv"))
            .map_err(|e| anyhow::anyhow!("{e}"))
            .context("writing the bench's terrain for MuJoCo")?;
        let [x0, x1] = terrain.x_range();
        Ok(Script {
            scratch,
            python: python.to_path_buf(),
            steps,
            size: x1 - x0,
        })
    }

    /// `steps` steps, best of `repeats` (after one untimed run of each, if `warmup`). Its output
    /// goes to stderr as it comes; a missing Python or MuJoCo is an error that says how to get
    /// them.
    fn run(&self, repeats: usize, warmup: bool) -> Result<MujocoFigures> {
        let at = |name: &str| self.scratch.0.join(name);
        let python = &self.python;
        // not a stale round's
        let _ = std::fs::remove_file(at("figures.json"));
        let status = Command::new(python)
            .arg(at("hex18_mujoco.py"))
            .arg(at("natural.csv"))
            .args(["--size", &self.size.to_string()])
            .args(["--steps", &self.steps.to_string()])
            .args(["--repeats", &repeats.max(1).to_string()])
            .args(warmup.then_some("--warmup"))
            .arg("--urdf")
            .arg(at("hex18.urdf"))
            .arg("--json")
            .arg(at("figures.json"))
            .stdout(std::process::Stdio::inherit())
            .status()
            .with_context(|| {
                format!(
                    "--mujoco: cannot run {}: give a Python with MuJoCo (pip install mujoco), \
                     e.g. --mujoco .venv/bin/python",
                    python.display()
                )
            })?;
        if !status.success() {
            bail!(
                "--mujoco: {} {} failed ({status}); it needs `pip install mujoco numpy`",
                python.display(),
                at("hex18_mujoco.py").display()
            );
        }
        let text = std::fs::read_to_string(at("figures.json"))
            .context("--mujoco: the script wrote no figures")?;
        serde_json::from_str(&text).context("--mujoco: reading the script's figures")
    }
}
