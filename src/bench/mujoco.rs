//! MuJoCo beside hexsim in one `hexsim bench`: its equivalent of the walk (`bench/mujoco`, built
//! into the binary) timed by Python on the same machine, in the same invocation, so a figure
//! always comes with its comparison — these machines differ by 30 % from one CPU to the next.

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
}

/// A scratch folder, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs the MuJoCo equivalent of the walk with `python` (which needs `mujoco` and `numpy`):
/// hex18 and the bench's natural terrain written to a scratch folder, `steps` steps, best of
/// `repeats`. Its output goes to stderr as it comes; a missing Python or MuJoCo is an error that
/// says how to get them.
pub fn measure(python: &Path, steps: u64, repeats: usize) -> Result<MujocoFigures> {
    let dir = std::env::temp_dir().join(format!("hexsim-bench-mujoco-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let scratch = Scratch(dir);
    let at = |name: &str| scratch.0.join(name);
    std::fs::write(at("hex18_mujoco.py"), SCRIPT)?;
    std::fs::write(at("hex18.urdf"), crate::scenario::builtin::HEX18.text)?;
    let terrain = super::bench_terrain()?;
    crate::terrain::io::write_csv(&terrain, &at("natural.csv"))
        .map_err(|e| anyhow::anyhow!("{e}"))
        .context("writing the bench's terrain for MuJoCo")?;
    let [x0, x1] = terrain.x_range();
    let status = Command::new(python)
        .arg(at("hex18_mujoco.py"))
        .arg(at("natural.csv"))
        .args(["--size", &(x1 - x0).to_string()])
        .args(["--steps", &steps.to_string()])
        .args(["--repeats", &repeats.max(1).to_string()])
        .arg("--urdf")
        .arg(at("hex18.urdf"))
        .arg("--json")
        .arg(at("figures.json"))
        .stdout(std::process::Stdio::inherit())
        .status()
        .with_context(|| {
            format!(
                "--mujoco: cannot run {}: give a Python with MuJoCo (pip install mujoco), e.g. \
                 --mujoco .venv/bin/python",
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
