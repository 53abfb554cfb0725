//! `hexsim bench`: simulated steps per second on the reference workloads, in the configuration the
//! validation tests pass in.
//!
//! Workloads (all on built-in files, so the benchmark needs nothing at hand):
//! - **walk**: hex18, tripod gait, the natural terrain (0.04 m peak to peak), dt = 1 ms, 1 s settling
//!   + the walk, one thread; with the recording off, and on at the default 50 Hz;
//! - **batch**: the walk on every core at once, one world per thread: total steps/s;
//! - **ball**: the paper's ball on the natural terrain.
//!
//! Each walk also checks V13's criteria on its own result, so a figure from a configuration whose
//! physics broke is flagged as such, and reports the share of its time spent inside rapier's step
//! (what the figure could be if hexsim's own work cost nothing).

pub mod mujoco;

use crate::scenario::{Metrics, Output, Outputs, Report, Scenario, ScenarioSpec};
use crate::sim::Articulation;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What to measure.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    pub articulations: Vec<Articulation>,
    /// Seconds walked (after 1 s settling) and seconds of the ball.
    pub duration: f64,
    /// Threads for the batch figure.
    pub threads: usize,
    /// Each figure is the median of this many runs, with the best beside it (these machines are
    /// noisy).
    pub repeats: usize,
    /// Where the recording of the "recording on" run goes (deleted afterwards).
    pub scratch: PathBuf,
    /// A Python with MuJoCo, to time MuJoCo's equivalent of the walk beside ours.
    pub mujoco: Option<PathBuf>,
}

/// One measured figure.
#[derive(Debug, Clone, Serialize)]
pub struct Figure {
    pub workload: String,
    pub articulation: Option<String>,
    pub threads: usize,
    pub steps: u64,
    pub wall_time: f64,
    /// The median run's.
    pub steps_per_second: f64,
    /// The fastest run's: on a shared machine the least disturbed, so the steadiest estimate of
    /// what a step costs.
    pub best_steps_per_second: f64,
    /// V13's criteria on this run's own result (walks only).
    pub v13: Option<bool>,
    /// Impulse joints: the largest joint anchor separation over the run (m).
    pub max_joint_drift: Option<f64>,
    /// Single-thread walks: the share of the run's wall time spent inside rapier's step; the
    /// rest is hexsim's (contacts, servos, gait, outputs).
    pub rapier_share: Option<f64>,
}

impl Figure {
    /// Steps per second rapier's step alone would allow at this run's speed: the ceiling a
    /// simulator driving rapier could reach if its own work cost nothing.
    pub fn rapier_ceiling(&self) -> Option<f64> {
        self.rapier_share
            .map(|share| self.steps_per_second / share.max(1e-9))
    }

    /// hexsim's own part of a step (s): the step's wall time less rapier's, by the clock —
    /// the figure issue 45 bounds (≤ 4 µs), which a share alone hides.
    pub fn own_step_seconds(&self) -> Option<f64> {
        self.rapier_share
            .map(|share| (1.0 - share) / self.steps_per_second.max(1e-9))
    }
}

/// The whole benchmark.
#[derive(Debug, Clone, Serialize)]
pub struct BenchReport {
    pub configuration: Vec<(String, String)>,
    pub figures: Vec<Figure>,
    /// MuJoCo's equivalent of the walk on the same machine (`hexsim bench --mujoco`), measured
    /// round by round beside the walks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mujoco: Option<mujoco::Comparison>,
}

/// The terrain the walk crosses (for MuJoCo's copy of the workload).
fn bench_terrain() -> Result<crate::terrain::HeightGrid> {
    let scenario = resolve(walk_spec(Articulation::Multibody, 1.0)?, "bench walk")?;
    Ok(scenario.build_terrain()?)
}

fn walk_spec(articulation: Articulation, duration: f64) -> Result<ScenarioSpec> {
    let text = format!(
        "kind = \"walk\"\nduration = {duration}\narticulation = \"{}\"\n",
        articulation.name()
    );
    Ok(toml::from_str(&text)?)
}

fn ball_spec(duration: f64) -> Result<ScenarioSpec> {
    Ok(toml::from_str(&format!(
        "kind = \"ball\"\nduration = {duration}\n"
    ))?)
}

fn resolve(spec: ScenarioSpec, name: &str) -> Result<Scenario> {
    Scenario::resolve(spec, name.into(), Path::new("")).map_err(anyhow::Error::from)
}

fn run(scenario: &Scenario, record: Option<PathBuf>) -> Result<Report> {
    let report = scenario.run(Outputs::new().with_some(record.map(Output::Recording)))?;
    if let Some(failure) = &report.failure {
        anyhow::bail!("{}: {failure}", scenario.name);
    }
    Ok(report)
}

/// V13 (docs/validation.md): forward ≥ 70 % of the nominal stride/(duty·period)·t, roll and
/// pitch under 25°, no foot deeper than 5 mm.
fn v13(scenario: &Scenario, report: &Report) -> Option<bool> {
    let (Metrics::Walk(m), Some(gait)) = (&report.metrics, scenario.gait()) else {
        return None;
    };
    let nominal = gait.stride_length / (gait.duty_factor * gait.period) * m.walk_time;
    Some(
        m.forward_distance >= 0.7 * nominal
            && m.max_roll_deg < 25.0
            && m.max_pitch_deg < 25.0
            && m.max_penetration < 5e-3,
    )
}

fn figure(
    workload: &str,
    articulation: Option<Articulation>,
    threads: usize,
    steps: u64,
    wall_time: f64,
) -> Figure {
    Figure {
        workload: workload.into(),
        articulation: articulation.map(|a| a.name().into()),
        threads,
        steps,
        wall_time,
        steps_per_second: steps as f64 / wall_time.max(1e-9),
        best_steps_per_second: steps as f64 / wall_time.max(1e-9),
        v13: None,
        max_joint_drift: None,
        rapier_share: None,
    }
}

/// The run with the median wall time of `repeats` runs of `measure`, carrying the fastest run's
/// steps per second as its best.
fn median(repeats: usize, mut measure: impl FnMut() -> Result<Figure>) -> Result<Figure> {
    let mut runs = (0..repeats.max(1))
        .map(|_| measure())
        .collect::<Result<Vec<_>>>()?;
    runs.sort_by(|a, b| a.wall_time.total_cmp(&b.wall_time));
    let best = runs[0].steps_per_second;
    let mut median = runs.swap_remove(runs.len() / 2);
    median.best_steps_per_second = best;
    Ok(median)
}

/// Runs the benchmark; `report` is called with each figure as it is measured.
pub fn run_bench(options: &BenchOptions, mut report: impl FnMut(&Figure)) -> Result<BenchReport> {
    let mut figures = Vec::new();
    let mut push = |f: Figure, figures: &mut Vec<Figure>| {
        report(&f);
        figures.push(f);
    };
    for &articulation in &options.articulations {
        let scenario = resolve(walk_spec(articulation, options.duration)?, "bench walk")?;
        let walk = |record: Option<PathBuf>| -> Result<Figure> {
            let r = run(&scenario, record)?;
            let mut f = figure(
                "walk",
                Some(articulation),
                1,
                r.steps,
                r.steps as f64 / r.steps_per_second,
            );
            f.v13 = v13(&scenario, &r);
            f.rapier_share = r.physics_seconds.map(|s| s / f.wall_time.max(1e-9));
            if let (Metrics::Walk(m), Articulation::Impulse) = (&r.metrics, articulation) {
                f.max_joint_drift = Some(m.max_joint_drift);
            }
            Ok(f)
        };
        push(median(options.repeats, || walk(None))?, &mut figures);
        let mut recorded = median(options.repeats, || {
            let f = walk(Some(options.scratch.clone()));
            std::fs::remove_file(&options.scratch)
                .with_context(|| format!("removing {}", options.scratch.display()))?;
            f
        })?;
        recorded.workload = "walk, recording at 50 Hz".into();
        push(recorded, &mut figures);
        // batch: one world per thread, all at once
        let scenarios: Vec<Scenario> = (0..options.threads)
            .map(|_| resolve(walk_spec(articulation, options.duration)?, "bench walk"))
            .collect::<Result<_>>()?;
        let batch = median(options.repeats, || {
            let started = std::time::Instant::now();
            let steps = std::thread::scope(|s| -> Result<u64> {
                let handles: Vec<_> = scenarios
                    .iter()
                    .map(|sc| s.spawn(move || run(sc, None).map(|r| r.steps)))
                    .collect();
                let mut total = 0;
                for h in handles {
                    total += h.join().expect("a bench thread does not panic")?;
                }
                Ok(total)
            })?;
            Ok(figure(
                "batch, one world per thread",
                Some(articulation),
                options.threads,
                steps,
                started.elapsed().as_secs_f64(),
            ))
        })?;
        push(batch, &mut figures);
    }
    let ball = resolve(ball_spec(options.duration)?, "bench ball")?;
    let ball = median(options.repeats, || {
        let r = run(&ball, None)?;
        Ok(figure(
            "ball on the natural terrain",
            None,
            1,
            r.steps,
            r.steps as f64 / r.steps_per_second,
        ))
    })?;
    push(ball, &mut figures);
    let mujoco = match &options.mujoco {
        // as many steps as the walk: 1 s settling and the duration, at 1 ms; one walk of each
        // articulation beside each of MuJoCo's runs
        Some(python) => {
            let steps = ((options.duration + 1.0) * 1000.0).round() as u64;
            let scenarios = options
                .articulations
                .iter()
                .map(|&a| resolve(walk_spec(a, options.duration)?, "bench walk"))
                .collect::<Result<Vec<_>>>()?;
            let names: Vec<&str> = options.articulations.iter().map(|a| a.name()).collect();
            Some(mujoco::Comparison::measure(
                python,
                steps,
                options.repeats,
                &names,
                |i| run(&scenarios[i], None).map(|r| r.steps_per_second),
            )?)
        }
        None => None,
    };
    Ok(BenchReport {
        configuration: configuration(options),
        figures,
        mujoco,
    })
}

/// The CPU's model as `/proc/cpuinfo` (`text`) gives it, with its family and model numbers where
/// it has them: on virtual machines the name alone can hide the generation ("AMD EPYC" is a
/// Zen 4, family 25, or a Zen 5, family 26, whose steps differ by half; docs/performance.md).
fn cpu_model(text: &str) -> Option<String> {
    let field = |key: &str| {
        text.lines()
            .take_while(|l| !l.trim().is_empty())
            .find_map(|l| {
                let (name, value) = l.split_once(':')?;
                (name.trim() == key).then(|| value.trim().to_string())
            })
            .filter(|v| !v.is_empty())
    };
    let name = field("model name")?;
    Some(match (field("cpu family"), field("model")) {
        (Some(family), Some(model)) => format!("{name} (family {family}, model {model})"),
        _ => name,
    })
}

/// The first core's caches from Linux's `cache/index*` directories under `dir` ("L1i 32K, L1d
/// 32K, L2 1024K, L3 32768K"): a step touches more code than the L1 instruction cache holds, and
/// its time depends on how much of it stays near the core (docs/performance.md), so a figure says
/// what it ran on. None where the directory is not there or says nothing.
fn cpu_caches(dir: &std::path::Path) -> Option<String> {
    let read = |d: &std::path::Path, f: &str| {
        std::fs::read_to_string(d.join(f))
            .ok()
            .map(|s| s.trim().to_string())
    };
    let mut caches: Vec<(u32, &str, String)> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| {
            let d = e.ok()?.path();
            if !d.file_name()?.to_str()?.starts_with("index") {
                return None;
            }
            let level: u32 = read(&d, "level")?.parse().ok()?;
            let kind = match read(&d, "type")?.as_str() {
                "Instruction" => "i",
                "Data" => "d",
                _ => "",
            };
            Some((level, kind, read(&d, "size")?))
        })
        .collect();
    // by level, the instruction cache before the data cache
    caches.sort_by_key(|&(level, kind, _)| (level, kind != "i", kind));
    (!caches.is_empty()).then(|| {
        caches
            .iter()
            .map(|(level, kind, size)| format!("L{level}{kind} {size}"))
            .collect::<Vec<_>>()
            .join(", ")
    })
}

/// The build, in words: cargo's profile (`build.rs` reads it from the folder it builds in), and
/// what of the flags given to rustc changes the speed of the code: a profile-guided build
/// (`-Cprofile-use`, docs/performance.md), an instrumented one, one for a given CPU.
fn build_line(profile: &str, debug_assertions: bool, rustflags: &str) -> String {
    let mut line = profile.to_string();
    if debug_assertions {
        line.push_str(" (debug assertions: numbers meaningless, use --release)");
    }
    let flags: Vec<&str> = rustflags.split_whitespace().collect();
    // a flag is `-Cname=value`, or `-C` and `name=value` apart
    let codegen = flags.iter().enumerate().filter_map(|(i, &f)| match f {
        "-C" | "--codegen" => flags.get(i + 1).copied(),
        _ => f
            .strip_prefix("-C")
            .or_else(|| f.strip_prefix("--codegen=")),
    });
    for option in codegen {
        if option.starts_with("profile-use") {
            line.push_str(", profile-guided (-Cprofile-use)");
        } else if option.starts_with("profile-generate") {
            line.push_str(", instrumented for profiling (numbers meaningless)");
        } else if let Some(cpu) = option.strip_prefix("target-cpu=") {
            line.push_str(&format!(", target-cpu={cpu}"));
        } else if let Some(features) = option.strip_prefix("target-feature=") {
            line.push_str(&format!(", target-feature={features}"));
        }
    }
    line
}

/// What was measured, in words: build, machine, solver, contact scheme.
pub fn configuration(options: &BenchOptions) -> Vec<(String, String)> {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| cpu_model(&s))
        .unwrap_or_else(|| "unknown".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let caches = cpu_caches(std::path::Path::new("/sys/devices/system/cpu/cpu0/cache"))
        .map_or(String::new(), |caches| format!("; caches {caches}"));
    let articulations = options
        .articulations
        .iter()
        .map(|a| {
            format!(
                "{} ({} substep{} of {} constraint sweep{})",
                a.name(),
                crate::sim::DEFAULT_SOLVER_ITERATIONS,
                if crate::sim::DEFAULT_SOLVER_ITERATIONS == 1 {
                    ""
                } else {
                    "s"
                },
                a.default_pgs_iterations(),
                if a.default_pgs_iterations() == 1 {
                    ""
                } else {
                    "s"
                },
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let build = build_line(
        env!("HEXSIM_PROFILE"),
        cfg!(debug_assertions),
        env!("HEXSIM_RUSTFLAGS"),
    );
    [
        ("hexsim", env!("CARGO_PKG_VERSION").to_string()),
        ("build", build),
        ("machine", format!("{cpu}, {cores} cores{caches}")),
        (
            "method",
            format!(
                "median (and best) of {} runs per figure",
                options.repeats.max(1)
            ),
        ),
        (
            "physics",
            format!(
                "rapier3d 0.36.1 + {}, f32, default features (no simd, no parallel)",
                rapier_patches()
            ),
        ),
        ("articulation", articulations),
        (
            "servos",
            "multibody: implicit joint springs (k·dt², d·dt on the mass matrix), torque limit \
             as an explicit torque; impulse: explicit torques, the same law at the step's start; \
             limits only near a limit"
                .into(),
        ),
        (
            "contact",
            "paper spring-damper k = 2e4 N/m, c = 150 N·s/m; Karnopp μs 0.9, μk 0.8; exact \
             normal; stance feet's stopping forces solved jointly; no rapier colliders"
                .into(),
        ),
        (
            "workload",
            format!(
                "hex18, tripod, natural terrain 0.04 m p-p, dt = 1 ms, 1 s settle + {} s",
                options.duration
            ),
        ),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// rapier's patch series (`third_party/rapier3d/patches`), as built into this binary: a figure
/// from a build on other patches is not comparable.
macro_rules! patch {
    ($name:literal) => {
        (
            $name,
            include_bytes!(concat!("../../third_party/rapier3d/patches/", $name)).as_slice(),
        )
    };
}
pub const RAPIER_PATCHES: &[(&str, &[u8])] = &[
    patch!("0001-multibody-assemble-the-mass-matrix-on-each-link-s-pa.patch"),
    patch!("0002-multibody-compute-each-body-Jacobian-on-its-link-s-p.patch"),
    patch!("0003-multibody-apply-each-link-s-forces-on-its-path-s-deg.patch"),
    patch!("0004-multibody-copy-the-mass-matrices-for-their-LU-with-o.patch"),
    patch!("0005-multibody-factorise-the-mass-matrices-along-the-tree.patch"),
    patch!("0006-multibody-sum-the-mass-matrices-link-terms-as-compos.patch"),
    patch!("0007-multibody-skip-forward-kinematics-when-nothing-it-re.patch"),
    patch!("0008-multibody-keep-update_acceleration-s-vectors-between.patch"),
    patch!("0009-multibody-write-the-tree-s-parents-portably-re-mint-.patch"),
    patch!("0010-bodies-add-and-clear-forces-without-marking-the-body.patch"),
    patch!("0011-multibody-skip-the-start-of-step-writeback-when-noth.patch"),
    patch!("0012-multibody-factorise-along-the-tree-without-re-listin.patch"),
    patch!("0013-multibody-optionally-integrate-the-Coriolis-forces-e.patch"),
    patch!("0014-solver-lay-small-joint-colors-out-in-SIMD-chunks-in-.patch"),
    patch!("0015-solver-read-a-joint-s-body-velocities-once-for-all-i.patch"),
    patch!("0016-solver-emit-a-3D-revolute-s-angular-motor-row-in-the.patch"),
    patch!("0017-solver-reuse-the-island-s-stage-sync-and-generic-vel.patch"),
];

/// The patch series in a line: how many, the first and last number, and the first 12 hex digits
/// of the SHA-256 of their contents in order.
pub fn rapier_patches() -> String {
    use sha2::{Digest, Sha256};
    let mut hash = Sha256::new();
    for (_, bytes) in RAPIER_PATCHES {
        hash.update(bytes);
    }
    let digest = hash.finalize();
    let hex: String = digest.iter().take(6).map(|b| format!("{b:02x}")).collect();
    let number = |k: usize| RAPIER_PATCHES[k].0.split('-').next().unwrap_or("?");
    format!(
        "{} patches ({}–{}, sha256 {hex})",
        RAPIER_PATCHES.len(),
        number(0),
        number(RAPIER_PATCHES.len() - 1)
    )
}

#[cfg(test)]
mod tests {
    /// The build line names the profile and the flags that change the code's speed, whether
    /// cargo passed them joined (`-Cprofile-use=…`) or apart (`-C target-cpu=…`), and nothing
    /// of flags that do not.
    #[test]
    fn the_build_line_names_profile_guided_and_tuned_builds() {
        assert_eq!(super::build_line("release", false, ""), "release");
        assert_eq!(
            super::build_line(
                "release",
                false,
                "-Cprofile-use=/t/merged.profdata -Cdebuginfo=1"
            ),
            "release, profile-guided (-Cprofile-use)"
        );
        assert_eq!(
            super::build_line(
                "release",
                false,
                "-Cprofile-generate=/t/pgo -C target-cpu=native"
            ),
            "release, instrumented for profiling (numbers meaningless), target-cpu=native"
        );
        assert_eq!(
            super::build_line("release-lto", false, "--codegen=target-feature=+avx2"),
            "release-lto, target-feature=+avx2"
        );
        assert_eq!(
            super::build_line("debug", true, "-Dwarnings"),
            "debug (debug assertions: numbers meaningless, use --release)"
        );
    }

    /// Every patch in `third_party/rapier3d/patches` is in [`super::RAPIER_PATCHES`], in order:
    /// a patch added to the series and not here would leave the id unchanged.
    #[test]
    fn the_patch_id_covers_the_whole_series() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/third_party/rapier3d/patches");
        let mut files: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".patch"))
            .collect();
        files.sort();
        let listed: Vec<&str> = super::RAPIER_PATCHES.iter().map(|(n, _)| *n).collect();
        assert_eq!(listed, files);
        let id = super::rapier_patches();
        assert!(
            id.starts_with(&format!("{} patches (0001–", files.len())),
            "{id}"
        );
    }

    /// The machine line names the CPU's family and model from the first processor's block; a
    /// `/proc/cpuinfo` without them (other architectures) gives the name alone, and one without a
    /// name gives none.
    #[test]
    fn the_cpu_is_named_with_its_family_and_model() {
        let zen4 = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: 17\n\
                    model name\t: AMD EPYC\nstepping\t: 0\n\nprocessor\t: 1\ncpu family\t: 26\n\
                    model\t\t: 2\nmodel name\t: AMD EPYC\n";
        assert_eq!(
            super::cpu_model(zen4).as_deref(),
            Some("AMD EPYC (family 25, model 17)")
        );
        let bare = "processor\t: 0\nmodel name\t: ARMv8 Processor rev 1 (v8l)\n";
        assert_eq!(
            super::cpu_model(bare).as_deref(),
            Some("ARMv8 Processor rev 1 (v8l)")
        );
        assert_eq!(
            super::cpu_model("processor\t: 0\nBogoMIPS\t: 50.00\n"),
            None
        );
    }

    /// The caches are read from Linux's `cache/index*` directories, the instruction cache before
    /// the data cache of the same level; a missing directory gives none.
    #[test]
    fn the_caches_are_listed_by_level() {
        let dir = tempfile::tempdir().unwrap();
        for (index, level, kind, size) in [
            (0, 1, "Data", "32K"),
            (1, 1, "Instruction", "32K"),
            (2, 2, "Unified", "1024K"),
            (3, 3, "Unified", "32768K"),
        ] {
            let d = dir.path().join(format!("index{index}"));
            std::fs::create_dir(&d).unwrap();
            std::fs::write(d.join("level"), format!("{level}\n")).unwrap();
            std::fs::write(d.join("type"), format!("{kind}\n")).unwrap();
            std::fs::write(d.join("size"), format!("{size}\n")).unwrap();
        }
        std::fs::create_dir(dir.path().join("uevent_dir")).unwrap();
        assert_eq!(
            super::cpu_caches(dir.path()).as_deref(),
            Some("L1i 32K, L1d 32K, L2 1024K, L3 32768K")
        );
        assert_eq!(super::cpu_caches(&dir.path().join("absent")), None);
    }
}
