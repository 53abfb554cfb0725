//! Helpers shared by the tests: the validation cases' set-ups, and running the `hexsim` binary.
#![allow(dead_code)]

use hexsim::contact::{ContactModel, FrictionLaw, NormalLaw};
use hexsim::sim::{BallConfig, BallSample, BallSim};
use hexsim::terrain::HeightGrid;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub const G: f64 = 9.81;
pub const DT: f64 = 1e-3;

/// The `hexsim` binary, run from the project's folder.
pub fn hexsim() -> std::process::Command {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_hexsim"));
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"));
    cmd
}

/// Runs `cmd`, which writes its metrics to `json`: fails the test naming `what` with the
/// command's output if it did not succeed, and returns the metrics.
pub fn metrics_of(mut cmd: std::process::Command, json: &Path, what: &str) -> serde_json::Value {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{what}: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

/// A fresh folder for one test's files, removed when the test ends, passing or failing.
pub fn scratch(name: &str) -> Scratch {
    Scratch::new(&format!("hexsim-test-{name}-"))
}

/// A temporary folder (`tempfile`'s), usable as a `Path`.
pub struct Scratch(tempfile::TempDir);

impl Scratch {
    pub fn new(prefix: &str) -> Self {
        Scratch(tempfile::Builder::new().prefix(prefix).tempdir().unwrap())
    }

    pub fn path(&self) -> &Path {
        self.0.path()
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// Runs `cmd` (given the input file `file`) and checks that it is an input error: exit 2, the
/// message naming the file and saying each of `expected`.
pub fn assert_input_error(mut cmd: std::process::Command, file: &Path, expected: &[&str]) {
    let out = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let name = file.file_name().unwrap().to_string_lossy();
    assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
    assert!(stderr.contains(name.as_ref()), "{stderr}");
    for e in expected {
        assert!(stderr.contains(e), "{name}: no {e:?} in {stderr}");
    }
}

pub fn project_file(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

pub fn spring_damper(stiffness: f64, damping: f64, friction: FrictionLaw) -> ContactModel {
    ContactModel {
        normal: NormalLaw::SpringDamper { stiffness, damping },
        friction,
        ..ContactModel::default()
    }
}

pub fn karnopp(mu_static: f64, mu_kinetic: f64) -> FrictionLaw {
    FrictionLaw::Karnopp {
        mu_static,
        mu_kinetic,
        stick_band: 1e-3,
    }
}

/// Runs a ball for `seconds`, returning every step's sample (the first is the initial state).
pub fn run_ball(
    config: BallConfig,
    terrain: HeightGrid,
    contact: ContactModel,
    seconds: f64,
) -> Vec<BallSample> {
    run_ball_with_step(config, terrain, contact, seconds, DT)
}

/// [`run_ball`] with a chosen time step.
pub fn run_ball_with_step(
    config: BallConfig,
    terrain: HeightGrid,
    contact: ContactModel,
    seconds: f64,
    dt: f64,
) -> Vec<BallSample> {
    let mut sim = BallSim::new(config, Arc::new(terrain), contact, dt);
    let steps = (seconds / dt).round() as usize;
    let mut samples = Vec::with_capacity(steps + 1);
    samples.push(sim.sample());
    for _ in 0..steps {
        samples.push(sim.step());
    }
    samples
}

/// Centre of a sphere of radius r resting on the plane through the origin rising at `angle` towards
/// +x, touching it above x = `along`, sunk in by `depth` along the normal.
pub fn on_slope(angle: f64, along: f64, radius: f64, depth: f64) -> [f64; 3] {
    let (s, c) = angle.sin_cos();
    let foot = [along, 0.0, along * angle.tan()];
    let d = radius - depth;
    [foot[0] - s * d, 0.0, foot[2] + c * d]
}

/// Least-squares slope of y(t).
pub fn fitted_rate(t: &[f64], y: &[f64]) -> f64 {
    let n = t.len() as f64;
    let (mt, my) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = t.iter().zip(y).map(|(a, b)| (a - mt) * (b - my)).sum();
    let sxx: f64 = t.iter().map(|a| (a - mt) * (a - mt)).sum();
    sxy / sxx
}

/// A plane rising at `angle_deg` towards +x (60 m × 10 m).
pub fn plane(angle_deg: f64) -> HeightGrid {
    hexsim::terrain::slope([60.0, 10.0], [0.0, 0.0], angle_deg.to_radians(), 0.0).unwrap()
}

/// A ball (or foot) released at rest on [`plane`]`(angle_deg)`, resting at the spring's static
/// depth, run for `seconds` under `contact`.
pub fn released_on_plane(
    angle_deg: f64,
    config: BallConfig,
    contact: ContactModel,
    seconds: f64,
) -> Vec<BallSample> {
    let angle = angle_deg.to_radians();
    let depth = config.mass * G * angle.cos() / 2e4;
    let config = BallConfig {
        position: on_slope(angle, 20.0, config.radius, depth),
        ..config
    };
    run_ball(config, plane(angle_deg), contact, seconds)
}

/// Acceleration along a plane of `angle` (rad) rising towards +x (downhill positive), fitted
/// over [t0, t1].
pub fn downhill_acceleration(samples: &[BallSample], angle: f64, t0: f64, t1: f64) -> f64 {
    let downhill = glam::DVec3::new(-angle.cos(), 0.0, -angle.sin());
    let window: Vec<&BallSample> = samples
        .iter()
        .filter(|s| s.time >= t0 && s.time <= t1)
        .collect();
    let t: Vec<f64> = window.iter().map(|s| s.time).collect();
    let v: Vec<f64> = window.iter().map(|s| s.velocity.dot(downhill)).collect();
    fitted_rate(&t, &v)
}
