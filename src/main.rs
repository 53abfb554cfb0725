//! hexsim's command line: parse, dispatch, report, exit codes — the work is in the library.

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use hexsim::scenario::spec::{
    self, BallSpec, CommandSpec, ContactSpec, RecordSpec, ServoSpec, StartSpec,
};
use hexsim::scenario::{FileOr, Kind, Metrics, Outputs, Report, Scenario, ScenarioSpec};
use hexsim::sim::Articulation;
use hexsim::terrain;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "hexsim",
    version,
    about = "Hexapod walking-robot simulator on uneven ground, built on the Burkus & Odry ground contact model",
    long_about = "Hexapod walking-robot simulator on uneven ground, built on the Burkus & Odry ground contact \
                  model (spring-damper normal force, exchangeable friction laws, height-grid terrain).\n\n\
                  Without a subcommand, runs `hexsim run`: hex18 walks a tripod gait on the paper's natural terrain for 20 s \
                  and the run is recorded to hexsim.rrd."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Walk the hexapod on a terrain with a gait and record it (the main job).
    Run(Box<RunArgs>),
    /// Drop a ball on a terrain (the paper's experiment) and record it.
    Ball(Box<BallArgs>),
    /// Run scenario files headless in parallel and check their expectations (exit 0: all met,
    /// 1: some failed, diverged or regressed, 2: input error, 130: interrupted).
    Batch(Box<BatchArgs>),
    /// Measure simulated steps per second on the reference workloads (build with --release):
    /// the walk with the recording off and on, a batch on every core, and the ball.
    Bench(BenchArgs),
    /// Join the results of a batch's shards (`batch --shard I/N`) into one file.
    Merge(MergeArgs),
    /// Inspect or export terrains.
    #[command(subcommand)]
    Terrain(TerrainCommand),
}

#[derive(Args)]
struct BenchArgs {
    /// Which articulations to measure.
    #[arg(long, value_enum, default_values_t = [Articulation::Multibody, Articulation::Impulse])]
    articulation: Vec<Articulation>,
    /// Seconds walked (after 1 s settling), and seconds of the ball.
    #[arg(long, default_value_t = 20.0)]
    duration: f64,
    /// Threads for the batch figure. Default: all cores.
    #[arg(short, long)]
    jobs: Option<usize>,
    /// Runs per figure; the median is reported, and the best beside it.
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Also write the figures and the configuration as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

#[derive(Args)]
struct BatchArgs {
    /// Scenario files, folders (every .toml below them) or glob patterns.
    #[arg(required = true)]
    scenarios: Vec<String>,
    /// Worker threads, one simulation each. Default: all cores.
    #[arg(short, long)]
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
    /// Treat warnings (a missing visual mesh, a gait leaving fewer than three feet down) as errors.
    #[arg(long)]
    strict: bool,
}

#[derive(Args)]
struct MergeArgs {
    /// The shards' results files.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// The merged results file.
    #[arg(short, long, default_value = "results.jsonl")]
    output: PathBuf,
}

#[derive(Subcommand)]
enum TerrainCommand {
    /// Export a terrain file's surface as STL (mesh), PNG (16-bit heights) and/or CSV.
    Export {
        /// Terrain file (TOML).
        terrain: PathBuf,
        #[arg(long)]
        stl: Option<PathBuf>,
        #[arg(long)]
        png: Option<PathBuf>,
        #[arg(long)]
        csv: Option<PathBuf>,
    },
    /// Print a terrain's size, resolution and height range.
    Info { terrain: PathBuf },
}

#[derive(Clone, Copy, ValueEnum)]
enum NormalChoice {
    SpringDamper,
    HuntCrossley,
}

#[derive(Clone, Copy, ValueEnum)]
enum FrictionChoice {
    Karnopp,
    Coulomb,
    Viscous,
    Stribeck,
    None,
}

#[derive(Clone, Copy, ValueEnum)]
enum OrientationChoice {
    /// Exact normal of the interpolated surface (default).
    Exact,
    /// The paper's central-difference roll/pitch (eq. 1–4).
    Paper,
}

/// Contact parameters (defaults: the reference contact of shared/reference §2).
#[derive(Args)]
struct ContactArgs {
    /// Normal force law.
    #[arg(long, value_enum, default_value = "spring-damper")]
    normal_law: NormalChoice,
    /// Normal stiffness k (N/m; for Hunt–Crossley N/mⁿ).
    #[arg(long, default_value_t = 2.0e4)]
    stiffness: f64,
    /// Normal damping c (N·s/m; for Hunt–Crossley d in s/m).
    #[arg(long, default_value_t = 150.0)]
    damping: f64,
    /// Hunt–Crossley exponent n.
    #[arg(long, default_value_t = 1.5)]
    hc_exponent: f64,
    /// Friction law.
    #[arg(long, value_enum, default_value = "karnopp")]
    friction: FrictionChoice,
    /// Static friction coefficient μs (Karnopp, Stribeck).
    #[arg(long, default_value_t = 0.9)]
    mu_static: f64,
    /// Kinetic friction coefficient μk (Karnopp; Coulomb's μ; Stribeck's Coulomb level).
    #[arg(long, default_value_t = 0.8)]
    mu_kinetic: f64,
    /// Karnopp stick band Δv (m/s).
    #[arg(long, default_value_t = 1e-3)]
    stick_band: f64,
    /// Regularisation width of Coulomb and Stribeck (m/s).
    #[arg(long, default_value_t = 1e-3)]
    friction_width: f64,
    /// Viscous friction coefficient (N·s/m; viscous law, Stribeck's viscous part).
    #[arg(long, default_value_t = 0.0)]
    viscous: f64,
    /// Stribeck velocity (m/s).
    #[arg(long, default_value_t = 0.05)]
    stribeck_velocity: f64,
    /// How the ground's orientation is found.
    #[arg(long, value_enum, default_value = "exact")]
    orientation: OrientationChoice,
    /// The paper's half-step XE = YE (m) for its finite-difference angles.
    #[arg(long, default_value_t = 0.01)]
    paper_step: f64,
}

impl ContactArgs {
    fn spec(&self) -> ContactSpec {
        ContactSpec {
            normal: match self.normal_law {
                NormalChoice::SpringDamper => spec::NormalChoice::SpringDamper,
                NormalChoice::HuntCrossley => spec::NormalChoice::HuntCrossley,
            },
            stiffness: self.stiffness,
            damping: self.damping,
            exponent: self.hc_exponent,
            friction: match self.friction {
                FrictionChoice::Karnopp => spec::FrictionChoice::Karnopp,
                FrictionChoice::Coulomb => spec::FrictionChoice::Coulomb,
                FrictionChoice::Viscous => spec::FrictionChoice::Viscous,
                FrictionChoice::Stribeck => spec::FrictionChoice::Stribeck,
                FrictionChoice::None => spec::FrictionChoice::None,
            },
            mu_static: self.mu_static,
            mu_kinetic: self.mu_kinetic,
            stick_band: self.stick_band,
            width: self.friction_width,
            viscous: self.viscous,
            stribeck_velocity: self.stribeck_velocity,
            orientation: match self.orientation {
                OrientationChoice::Exact => spec::OrientationChoice::Exact,
                OrientationChoice::Paper => spec::OrientationChoice::Paper,
            },
            paper_step: self.paper_step,
        }
    }
}

#[derive(Args)]
struct BallArgs {
    /// Terrain file (TOML). Default: the paper's natural terrain (eq. 7, seed 5489) at ball
    /// scale, 0.2 m peak-to-peak over 4 m × 4 m.
    #[arg(long)]
    terrain: Option<PathBuf>,
    /// Ball radius (m).
    #[arg(long, default_value_t = 0.05)]
    radius: f64,
    /// Ball mass (kg).
    #[arg(long, default_value_t = 1.0)]
    mass: f64,
    /// Start x, y of the centre (m).
    #[arg(long, num_args = 2, value_names = ["X", "Y"], default_values_t = [0.3, -0.2], allow_negative_numbers = true)]
    at: Vec<f64>,
    /// Start height of the ball's lowest point above the ground below it (m).
    #[arg(long, default_value_t = 0.5)]
    drop_height: f64,
    /// Initial velocity (m/s).
    #[arg(long, num_args = 3, value_names = ["VX", "VY", "VZ"], default_values_t = [0.0, 0.0, 0.0], allow_negative_numbers = true)]
    velocity: Vec<f64>,
    /// Initial angular velocity (rad/s).
    #[arg(long, num_args = 3, value_names = ["WX", "WY", "WZ"], default_values_t = [0.0, 0.0, 0.0], allow_negative_numbers = true)]
    angular_velocity: Vec<f64>,
    /// Lock the ball's rotation (a non-rotating foot).
    #[arg(long)]
    lock_rotation: bool,
    #[command(flatten)]
    contact: ContactArgs,
    /// Simulated time (s).
    #[arg(long, default_value_t = 10.0)]
    duration: f64,
    /// Time step (s).
    #[arg(long, default_value_t = 1e-3)]
    dt: f64,
    /// Recording file (.rrd) for the rerun viewer.
    #[arg(long, default_value = "ball.rrd")]
    record: PathBuf,
    /// Do not write a recording.
    #[arg(long)]
    no_record: bool,
    /// Samples per second in the recording and trajectory.
    #[arg(long, default_value_t = 100.0)]
    log_rate: f64,
    /// Trajectory CSV (time, position, velocity, angular velocity, force, penetration, energy).
    #[arg(long)]
    trajectory: Option<PathBuf>,
    /// Summary metrics as JSON.
    #[arg(long)]
    metrics: Option<PathBuf>,
    /// Open the recording in the rerun viewer when done.
    #[arg(long)]
    spawn: bool,
    /// Run even if dt is above the contact spring's stability limit.
    #[arg(long)]
    allow_unstable_dt: bool,
}

#[derive(Args)]
struct RunArgs {
    /// Robot URDF. Default: robots/hex18.urdf (built in).
    #[arg(long)]
    robot: Option<PathBuf>,
    /// Terrain file (TOML). Default: terrains/natural.toml (built in): the paper's natural terrain,
    /// 0.04 m peak-to-peak over 4 m × 4 m.
    #[arg(long)]
    terrain: Option<PathBuf>,
    /// Gait file (TOML). Default: gaits/tripod.toml (built in).
    #[arg(long)]
    gait: Option<PathBuf>,
    /// Seconds walked (after settling).
    #[arg(long, default_value_t = 20.0)]
    duration: f64,
    /// Seconds standing still before the gait starts.
    #[arg(long, default_value_t = 1.0)]
    settle: f64,
    /// Keep the body level on slopes: raise or lower each foot's path by the terrain under it.
    #[arg(long)]
    follow_terrain: bool,
    /// Time step (s).
    #[arg(long, default_value_t = 1e-3)]
    dt: f64,
    /// Forward speed (m/s). Default: the gait's nominal stride / (duty · period).
    #[arg(long, allow_negative_numbers = true)]
    speed: Option<f64>,
    /// Sideways speed (m/s, left positive).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    sideways: f64,
    /// Turn rate (deg/s, left positive).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    turn: f64,
    /// Start position x, y of the body (m). Default: 0.75 m inside the terrain's −x edge, centred in y.
    #[arg(long, num_args = 2, value_names = ["X", "Y"], allow_negative_numbers = true)]
    start: Option<Vec<f64>>,
    /// Start heading (deg).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    heading: f64,
    /// Seed for generated terrains (natural, rough); replaces the terrain file's.
    #[arg(long)]
    seed: Option<u32>,
    #[command(flatten)]
    contact: ContactArgs,
    /// Servo stiffness (N·m/rad).
    #[arg(long, default_value_t = 20.0)]
    servo_stiffness: f64,
    /// Servo damping (N·m·s/rad).
    #[arg(long, default_value_t = 0.05)]
    servo_damping: f64,
    /// How the links are joined in rapier: one reduced-coordinate multibody (exact joints), or
    /// impulse joints (about 4× faster; the joints drift apart by up to ~0.4 mm)
    #[arg(long, value_enum, default_value_t = Articulation::Multibody)]
    articulation: Articulation,
    /// rapier substeps per step (each rebuilds the multibody's mass matrix).
    #[arg(long, default_value_t = hexsim::sim::DEFAULT_SOLVER_ITERATIONS)]
    solver_iterations: usize,
    /// Constraint-solver sweeps per substep. Default: 1 for the multibody (it has no
    /// constraints), 3 for impulse joints (the joints are held by the solver: with 2 the legs
    /// shake loose)
    #[arg(long)]
    pgs_iterations: Option<usize>,
    /// Recording file (.rrd) for the rerun viewer.
    #[arg(long, default_value = "hexsim.rrd")]
    record: PathBuf,
    /// Do not write a recording.
    #[arg(long)]
    no_record: bool,
    /// Samples per second in the recording and trajectory.
    #[arg(long, default_value_t = 50.0)]
    log_rate: f64,
    /// Trajectory CSV (time, body pose and velocity, joint angles/targets/torques, foot forces and contact).
    #[arg(long)]
    trajectory: Option<PathBuf>,
    /// Summary metrics as JSON.
    #[arg(long)]
    metrics: Option<PathBuf>,
    /// Open the recording in the rerun viewer when done.
    #[arg(long)]
    spawn: bool,
    /// Run even if dt is above the contact spring's stability limit.
    #[arg(long)]
    allow_unstable_dt: bool,
    /// Treat warnings (a missing visual mesh, a gait leaving fewer than three feet down) as errors.
    #[arg(long)]
    strict: bool,
}

impl Default for RunArgs {
    fn default() -> Self {
        let cli = Cli::parse_from(["hexsim", "run"]);
        match cli.command {
            Some(Command::Run(args)) => *args,
            _ => unreachable!("`hexsim run` parses to the run command"),
        }
    }
}

/// Prints the scenarios' warnings (a missing visual mesh, a gait with too few feet down), each
/// once; with `strict` they are errors.
fn warn_about<'a>(scenarios: impl IntoIterator<Item = &'a Scenario>, strict: bool) -> Result<()> {
    let warnings: std::collections::BTreeSet<&String> =
        scenarios.into_iter().flat_map(|s| &s.warnings).collect();
    for warning in &warnings {
        eprintln!("{}: {warning}", if strict { "error" } else { "warning" });
    }
    if strict && !warnings.is_empty() {
        anyhow::bail!(
            "{} warning{} treated as errors (--strict); nothing was run",
            warnings.len(),
            if warnings.len() == 1 { "" } else { "s" }
        );
    }
    Ok(())
}

/// A progress bar on a terminal, nothing otherwise.
fn progress_bar(steps: u64, what: String) -> Option<indicatif::ProgressBar> {
    std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(steps);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} simulating [{bar:40}] {percent:>3}% ({eta} left) {msg}",
            )
            .expect("the template is valid")
            .progress_chars("=> "),
        );
        bar.set_message(what);
        bar
    })
}

/// A command-line run has no scenario file: relative paths resolve from the working folder, and
/// errors name the option's own file.
const COMMAND_LINE: &str = "";

fn run(args: RunArgs) -> Result<ExitCode> {
    let spec = ScenarioSpec {
        name: Some("run".into()),
        description: String::new(),
        kind: Kind::Walk,
        terrain: args.terrain.clone().map(FileOr::File),
        seed: args.seed,
        duration: args.duration,
        dt: args.dt,
        contact: args.contact.spec(),
        allow_unstable_dt: args.allow_unstable_dt,
        robot: args.robot.clone(),
        gait: args.gait.clone().map(FileOr::File),
        settle: Some(args.settle),
        follow_terrain: Some(args.follow_terrain),
        articulation: Some(args.articulation),
        solver_iterations: Some(args.solver_iterations),
        pgs_iterations: args.pgs_iterations,
        servo: Some(ServoSpec {
            stiffness: args.servo_stiffness,
            damping: args.servo_damping,
        }),
        start: Some(StartSpec {
            x: args.start.as_ref().map(|v| v[0]),
            y: args.start.as_ref().map(|v| v[1]),
            heading_deg: args.heading,
        }),
        command: Some(vec![CommandSpec {
            at: 0.0,
            forward: args.speed,
            sideways: args.sideways,
            turn_deg_s: args.turn,
            ramp: 0.0,
        }]),
        ball: None,
        record: RecordSpec {
            log_rate: Some(args.log_rate),
            ..Default::default()
        },
        expect: Default::default(),
        tolerance: Default::default(),
    };
    let scenario = Scenario::resolve(spec, "run".into(), Path::new(COMMAND_LINE))?;
    warn_about([&scenario], args.strict)?;
    let gait_name = scenario.gait().map_or(String::new(), |g| g.name.clone());
    let terrain_name = scenario.terrain_name().to_string();
    let bar = progress_bar(
        scenario.total_steps(),
        format!("{} s", args.settle + args.duration),
    );
    let outputs = Outputs {
        record: (!args.no_record).then(|| args.record.clone()),
        trajectory: args.trajectory.clone(),
        metrics: args.metrics.clone(),
        progress: bar
            .clone()
            .map(|b| Box::new(move |done: u64| b.set_position(done)) as Box<dyn Fn(u64)>),
    };
    let report = scenario.run(outputs);
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let report = report?;
    let Metrics::Walk(m) = &report.metrics else {
        unreachable!("a walk scenario reports walk metrics")
    };
    println!(
        "{gait_name} ({}) on {terrain_name}: walked {:.2} s{}",
        args.robot
            .as_deref()
            .map_or("hex18".into(), |p| p.display().to_string()),
        m.walk_time,
        if m.complete { "" } else { " (stopped early)" }
    );
    println!(
        "  distance {:.3} m (forward {:.3}, sideways {:.3}), mean speed {:.4} m/s, heading change {:.2}°",
        m.distance, m.forward_distance, m.sideways_distance, m.mean_speed, m.heading_change_deg
    );
    println!(
        "  max roll {:.2}°, max pitch {:.2}°; body height {:.4} ± {:.4} m; deepest foot {:.2} mm",
        m.max_roll_deg,
        m.max_pitch_deg,
        m.body_height_mean,
        m.body_height_std,
        m.max_penetration * 1e3
    );
    let slip: Vec<String> = m
        .foot_slip
        .iter()
        .map(|s| format!("{:.1}", s * 1e3))
        .collect();
    println!("  foot slip (mm, lf lm lr rf rm rr): {}", slip.join(" "));
    if m.clamped_ik_steps > 0 {
        println!(
            "  warning: {} steps had foot targets out of reach (IK clamped)",
            m.clamped_ik_steps
        );
    }
    println!("  {:.0} steps/s", report.steps_per_second);
    let code = conclude(&report);
    if args.spawn && !args.no_record {
        hexsim::record::rerun::spawn_viewer(&args.record)?;
    }
    Ok(code)
}

/// Lists the files written. Exit code: 0 done, 1 diverged (the message says when, where and why),
/// 130 interrupted (Ctrl-C, SIGTERM); the files hold the run so far either way.
fn conclude(report: &Report) -> ExitCode {
    for path in &report.written {
        println!("  wrote {}", path.display());
    }
    if let Some(rrd) = report
        .written
        .iter()
        .find(|p| p.extension().is_some_and(|e| e == "rrd"))
    {
        println!(
            "  view it: `rerun {}` (the viewer: `pip install rerun-sdk==0.36.3`), or run with --spawn",
            rrd.display()
        );
    }
    if let Some(failure) = &report.failure {
        eprintln!(
            "error: {:#}",
            hexsim::runner::failure_error(failure, &report.written)
        );
        ExitCode::from(1)
    } else if !report.metrics.complete() {
        eprintln!("interrupted: the files hold the run so far, marked incomplete");
        ExitCode::from(130)
    } else {
        ExitCode::SUCCESS
    }
}

impl Default for BallArgs {
    fn default() -> Self {
        let cli = Cli::parse_from(["hexsim", "ball"]);
        match cli.command {
            Some(Command::Ball(args)) => *args,
            _ => unreachable!("`hexsim ball` parses to the ball command"),
        }
    }
}

fn ball(args: BallArgs) -> Result<ExitCode> {
    let spec = ScenarioSpec {
        name: Some("ball".into()),
        description: String::new(),
        kind: Kind::Ball,
        terrain: args.terrain.clone().map(FileOr::File),
        seed: None,
        duration: args.duration,
        dt: args.dt,
        contact: args.contact.spec(),
        allow_unstable_dt: args.allow_unstable_dt,
        robot: None,
        gait: None,
        settle: None,
        follow_terrain: None,
        articulation: None,
        solver_iterations: None,
        pgs_iterations: None,
        servo: None,
        start: None,
        command: None,
        ball: Some(BallSpec {
            radius: args.radius,
            mass: args.mass,
            at: [args.at[0], args.at[1]],
            drop_height: args.drop_height,
            velocity: [args.velocity[0], args.velocity[1], args.velocity[2]],
            angular_velocity: [
                args.angular_velocity[0],
                args.angular_velocity[1],
                args.angular_velocity[2],
            ],
            lock_rotation: args.lock_rotation,
        }),
        record: RecordSpec {
            log_rate: Some(args.log_rate),
            ..Default::default()
        },
        expect: Default::default(),
        tolerance: Default::default(),
    };
    let scenario = Scenario::resolve(spec, "ball".into(), Path::new(COMMAND_LINE))?;
    let terrain_name = scenario.terrain_name().to_string();
    let report = scenario.run(Outputs {
        record: (!args.no_record).then(|| args.record.clone()),
        trajectory: args.trajectory.clone(),
        metrics: args.metrics.clone(),
        progress: None,
    })?;
    let Metrics::Ball(m) = &report.metrics else {
        unreachable!("a ball scenario reports ball metrics")
    };
    println!(
        "ball on {terrain_name}: {:.2} s simulated{}",
        m.sim_time,
        if m.complete { "" } else { " (stopped early)" }
    );
    println!(
        "  touch-downs {}, max penetration {:.3} mm, max normal force {:.2} N",
        m.touchdowns,
        m.max_penetration * 1e3,
        m.max_normal_force
    );
    if let Some(h) = m.first_apex_height {
        println!("  first bounce apex: lowest point at z = {h:.4} m");
    }
    println!(
        "  final position ({:.3}, {:.3}, {:.3}) m, speed {:.4} m/s; energy {:.3} → {:.3} J (largest rise {:.2e} J)",
        m.final_position[0],
        m.final_position[1],
        m.final_position[2],
        m.final_speed,
        m.initial_energy,
        m.final_energy,
        m.max_energy_rise
    );
    let code = conclude(&report);
    if args.spawn && !args.no_record {
        hexsim::record::rerun::spawn_viewer(&args.record)?;
    }
    Ok(code)
}

/// Exit codes: 0 every expectation met, 1 some failed (or diverged, or regressed against the
/// baseline), 2 a usage or input error, 130 interrupted.
fn batch(args: BatchArgs) -> Result<ExitCode> {
    use hexsim::batch::{self, Progress, results};
    let files = batch::scenario_files(&args.scenarios)?;
    let scenarios = match batch::load(&files) {
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
    warn_about(&scenarios, args.strict)?;
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
    let outcome = batch::run(&scenarios, &options)?;
    let (regressions, missing) = match &baseline {
        Some(b) => batch::compare_with_baseline(&outcome.records, &scenarios, b, args.rel_tol),
        None => Default::default(),
    };
    println!();
    print!(
        "{}",
        batch::summary::table(
            &outcome.records,
            &regressions,
            outcome.records.len() <= 60 || args.all
        )
    );
    if outcome.resumed > 0 {
        println!(
            "{} results kept from the earlier run (--resume)",
            outcome.resumed
        );
    }
    if !missing.is_empty() {
        println!("not in the baseline: {} (not compared)", missing.join(", "));
    }
    println!(
        "{:.1} s wall, {:.0} steps/s over {jobs} thread{}; results in {}",
        outcome.wall_time,
        outcome.throughput(),
        if jobs == 1 { "" } else { "s" },
        args.output.display()
    );
    use hexsim::batch::results::Status;
    let any = |s: Status| outcome.records.iter().any(|r| r.status == s);
    if outcome.interrupted {
        println!(
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

fn bench(args: BenchArgs) -> Result<()> {
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
    };
    for (key, value) in hexsim::bench::configuration(&options) {
        println!("{key:>13}: {value}");
    }
    println!();
    println!(
        "{:<30} {:<10} {:>7} {:>9} {:>8} {:>12} {:>9}  notes",
        "workload", "joints", "threads", "steps", "wall s", "steps/s", "best"
    );
    let report = hexsim::bench::run_bench(&options, |f| {
        let mut notes = Vec::new();
        if let Some(ok) = f.v13 {
            notes.push(if ok { "V13 met" } else { "V13 NOT MET" }.to_string());
        }
        if let Some(d) = f.max_joint_drift {
            notes.push(format!("joint drift ≤ {:.1} µm", d * 1e6));
        }
        if let (Some(share), Some(ceiling)) = (f.rapier_share, f.rapier_ceiling()) {
            notes.push(format!(
                "rapier's step {:.0} % (alone {ceiling:.0} steps/s)",
                share * 100.0
            ));
        }
        println!(
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
            println!(
                "{}: batch on {} threads = {:.2}× one thread",
                a.name(),
                b.threads,
                b.steps_per_second / s.steps_per_second
            );
        }
    }
    println!(
        "V1–V15 in both articulations: cargo test --release --test validation_hexapod --test validation_ball"
    );
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn merge(args: MergeArgs) -> Result<()> {
    use hexsim::batch::{self, results};
    let mut parts = Vec::new();
    for path in &args.shards {
        let (records, _) = results::read(path, false)?;
        parts.push((path.clone(), records));
    }
    let merged = batch::merge(&parts)?;
    results::write_all(&args.output, &merged)?;
    println!(
        "merged {} results from {} files into {}",
        merged.len(),
        parts.len(),
        args.output.display()
    );
    Ok(())
}

fn terrain_command(command: TerrainCommand) -> Result<()> {
    match command {
        TerrainCommand::Export {
            terrain,
            stl,
            png,
            csv,
        } => {
            let grid = terrain::load(&terrain)?;
            if stl.is_none() && png.is_none() && csv.is_none() {
                anyhow::bail!("nothing to export: give --stl FILE, --png FILE and/or --csv FILE");
            }
            if let Some(path) = stl {
                terrain::io::write_stl(&grid, &path)
                    .with_context(|| format!("writing {}", path.display()))?;
                println!("wrote {}", path.display());
            }
            if let Some(path) = png {
                let (offset, scale) = terrain::io::write_png(&grid, &path)
                    .with_context(|| format!("writing {}", path.display()))?;
                let [x0, x1] = grid.x_range();
                let [y0, y1] = grid.y_range();
                println!(
                    "wrote {} — to read it back: kind = \"png\", height_scale = {scale}, height_offset = {offset}, x_range = [{x0}, {x1}], y_range = [{y0}, {y1}]",
                    path.display()
                );
            }
            if let Some(path) = csv {
                terrain::io::write_csv(&grid, &path)
                    .with_context(|| format!("writing {}", path.display()))?;
                println!("wrote {}", path.display());
            }
            Ok(())
        }
        TerrainCommand::Info { terrain } => {
            let grid = terrain::load(&terrain)?;
            let (lo, hi) = grid.height_bounds();
            let (dx, dy) = grid.spacing();
            println!("{}", terrain.display());
            println!(
                "  {} × {} samples, cell {dx:.4} × {dy:.4} m",
                grid.cols(),
                grid.rows()
            );
            println!("  x ∈ {:?}, y ∈ {:?} m", grid.x_range(), grid.y_range());
            println!(
                "  height ∈ [{lo:.4}, {hi:.4}] m ({:.4} m peak to peak)",
                hi - lo
            );
            println!("  interpolation {:?}", grid.interpolation());
            Ok(())
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Ctrl-C / SIGTERM stop the run at the next step; it then writes what it has, marked incomplete.
    let _ = ctrlc::set_handler(|| {
        hexsim::runner::INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed);
    });
    let result = match cli.command {
        None => run(RunArgs::default()),
        Some(Command::Run(args)) => run(*args),
        Some(Command::Ball(args)) => ball(*args),
        Some(Command::Batch(args)) => batch(*args),
        Some(Command::Merge(args)) => merge(args).map(|()| ExitCode::SUCCESS),
        Some(Command::Bench(args)) => bench(args).map(|()| ExitCode::SUCCESS),
        Some(Command::Terrain(command)) => terrain_command(command).map(|()| ExitCode::SUCCESS),
    };
    match result {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::from(2)
        }
    }
}
