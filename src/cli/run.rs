//! `hexsim run` (and hexsim without a command): the hexapod walks a gait on a terrain.

use anyhow::Result;
use clap::{Args, Parser};
use hexsim::scenario::spec::{
    CommandSpec, ContactSpec, DEFAULT_SETTLE, RUN_DURATION, RecordSpec, ServoSpec, StartSpec,
    WALK_LOG_RATE,
};
use hexsim::scenario::{FileOr, Kind, Metrics, Output, Outputs, Scenario, ScenarioSpec};
use hexsim::sim::{Articulation, Attitude};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::{COMMAND_LINE, Cli, Command, conclude, progress_bar, warn_about};

#[derive(Args)]
pub struct RunArgs {
    /// A scenario file (TOML, as `hexsim batch` reads) to run and record instead of the walk
    /// the flags describe; only the output flags (--record, --no-record, --trajectory, --metrics,
    /// --spawn, --strict, --allow-flags) go with it. Its `[expect]` is judged as `hexsim batch` judges it
    /// (exit 1 if one is not met). A sweep is refused: `hexsim batch` runs those.
    #[arg(
        value_name = "SCENARIO",
        conflicts_with_all = [
            "robot", "terrain", "gait", "duration", "settle", "follow_terrain", "reactive", "dt",
            "speed", "sideways", "turn", "start", "heading", "on_ground", "seed",
            "servo_stiffness", "servo_damping", "no_feedforward", "no_rolling", "articulation",
            "solver_iterations", "pgs_iterations", "log_rate", "allow_unstable_dt",
            "stiff_legs", "no_lean", "hold_heading", "stop_at_fall",
        ]
    )]
    scenario: Option<PathBuf>,
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
    #[arg(long, default_value_t = RUN_DURATION)]
    duration: f64,
    /// Seconds standing still before the gait starts.
    #[arg(long, default_value_t = DEFAULT_SETTLE)]
    settle: f64,
    /// Keep the body level on slopes: raise or lower each foot's path by the terrain under it.
    #[arg(long)]
    follow_terrain: bool,
    /// Reactive gait (blind): each foot lands where it touches the ground, reaches down for
    /// ground it does not find, lifts higher when a swing is blocked; the body follows the feet.
    #[arg(long)]
    reactive: bool,
    /// Stiff legs: the servos press their targets to their effort, however hard the ground
    /// pushes back (default: a leg pressing with more than three times the robot's weight gives
    /// way along the force and yields in its joints, as a force-controlled leg does, and legs
    /// squeezing the ground between them past twice its weight all yield).
    #[arg(long)]
    stiff_legs: bool,
    /// No lean on slopes: the body stands over its feet as on level ground (default: past a
    /// quarter of the gait's support margin the feet move downhill and the body crouches, so that
    /// the centre of mass's plumb line keeps inside the feet's support).
    #[arg(long)]
    no_lean: bool,
    /// Hold the heading: the commanded turn is corrected by the body's heading error (0.5 /s,
    /// bounded), as a robot with a gyro walks (default: the gait turns open loop, and a slipping
    /// foot turns the body for good).
    #[arg(long)]
    hold_heading: bool,
    /// End the walk when the robot falls: its body tilted past 45° from upright (the metrics'
    /// `fell_at`), the run complete there, as the terrain ladder's runs end (default: the walk
    /// goes on to its duration, the robot tumbling).
    #[arg(long)]
    stop_at_fall: bool,
    /// Time step (s). Default: 1 ms, or 1 ms / n where the robot's lightest servo, the contact
    /// spring (impulse joints' feet against a terrain's walls too) or the landing feet need a
    /// smaller step (a warning says so). A step given is
    /// refused past the servo's bound and warned past the others, naming the step hexsim would
    /// choose.
    #[arg(long)]
    dt: Option<f64>,
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
    /// Accept a walk that is not the one commanded (skated, went backwards, drifted sideways or
    /// turned: the metrics' `walk_flags`): exit 0 with the warnings instead of 1.
    #[arg(long)]
    allow_flags: bool,
    /// Start heading (deg).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    heading: f64,
    /// Set the body down parallel to the ground under it (the plane through the terrain under
    /// its feet), as a robot put down on a slope stands; default: level.
    #[arg(long)]
    on_ground: bool,
    /// Seed for generated terrains (natural, rough); replaces the terrain file's.
    #[arg(long)]
    seed: Option<u32>,
    #[command(flatten)]
    contact: ContactSpec,
    /// Servo stiffness (N·m/rad). Default: fitted to the robot's legs (hex18: the reference's 20).
    #[arg(long)]
    servo_stiffness: Option<f64>,
    /// Servo damping (N·m·s/rad). Default: 2.5 ms of the stiffness (hex18: the reference's 0.05).
    #[arg(long)]
    servo_damping: Option<f64>,
    /// Servo targets exactly the gait's joint angles: no load feed-forward (by default each
    /// target is moved on by the torque the joint holds over the stiffness, so the legs do not
    /// sag under the weight).
    #[arg(long)]
    no_feedforward: bool,
    /// Foot targets exactly the gait's path: no rolling offset (by default each foot's centre
    /// target moves with its sphere's rolling as the tibia turns, so the foot rolls instead of
    /// scrubbing).
    #[arg(long)]
    no_rolling: bool,
    /// How the links are joined in rapier: one reduced-coordinate multibody (exact joints), or
    /// impulse joints (about as fast, 15 % fewer instructions; the joints drift apart by up to
    /// ~0.35 mm)
    #[arg(long, value_enum, default_value_t = Articulation::default())]
    articulation: Articulation,
    /// rapier substeps per step (each rebuilds the multibody's mass matrix).
    #[arg(long, default_value_t = hexsim::sim::DEFAULT_SOLVER_ITERATIONS)]
    solver_iterations: usize,
    /// Constraint-solver sweeps per substep. Default: 1 for the multibody (it has no
    /// constraints), 5 for impulse joints (the joints are held by the solver: with 2 the legs
    /// shake loose, and a stance levelled on a 30° slope needs 5)
    #[arg(long)]
    pgs_iterations: Option<usize>,
    /// Recording file (.rrd) for the rerun viewer.
    #[arg(long, default_value = "hexsim.rrd", conflicts_with = "no_record")]
    record: PathBuf,
    /// Do not write a recording.
    #[arg(long)]
    no_record: bool,
    /// Samples per second in the recording and trajectory.
    #[arg(long, default_value_t = WALK_LOG_RATE)]
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
    /// Treat warnings (a missing visual mesh, a gait leaving fewer than three feet down) as errors;
    /// notes (a smaller step hexsim chose) are not warnings.
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

/// The scenario `hexsim run --robot ROBOT [--gait GAIT]` resolves, every other flag at its
/// default: what `hexsim robot` plans the walk's reach over.
pub(super) fn default_walk(robot: &Path, gait: Option<&Path>) -> ScenarioSpec {
    spec(&RunArgs {
        robot: Some(robot.to_path_buf()),
        gait: gait.map(Path::to_path_buf),
        ..RunArgs::default()
    })
}

/// The one walk a scenario file holds (`hexsim run SCENARIO.toml`).
fn from_file(file: &Path) -> Result<Scenario> {
    let mut scenarios = hexsim::scenario::load_file(file)?;
    let f = file.display();
    if scenarios.len() != 1 {
        anyhow::bail!(
            "{f}: a sweep of {} scenarios; `hexsim run` runs one (run them with `hexsim batch {f}`)",
            scenarios.len()
        );
    }
    let scenario = scenarios.remove(0);
    if scenario.kind() != Kind::Walk {
        anyhow::bail!(
            "{f}: a ball scenario; `hexsim run` walks a robot (`hexsim batch {f}` runs it)"
        );
    }
    Ok(scenario)
}

/// The scenario the flags describe.
fn spec(args: &RunArgs) -> ScenarioSpec {
    ScenarioSpec {
        name: Some("run".into()),
        description: String::new(),
        kind: Kind::Walk,
        terrain: args.terrain.clone().map(FileOr::File),
        seed: args.seed,
        duration: args.duration,
        dt: args.dt,
        contact: args.contact,
        allow_unstable_dt: args.allow_unstable_dt,
        robot: args.robot.clone(),
        gait: args.gait.clone().map(FileOr::File),
        settle: Some(args.settle),
        follow_terrain: Some(args.follow_terrain),
        rolling_feet: args.no_rolling.then_some(false),
        reactive_gait: Some(args.reactive),
        compliant_legs: args.stiff_legs.then_some(false),
        lean_on_slopes: args.no_lean.then_some(false),
        hold_heading: args.hold_heading.then_some(true),
        stop_at_fall: args.stop_at_fall.then_some(true),
        articulation: Some(args.articulation),
        solver_iterations: Some(args.solver_iterations),
        pgs_iterations: args.pgs_iterations,
        servo: Some(ServoSpec {
            stiffness: args.servo_stiffness,
            damping: args.servo_damping,
            feedforward: args.no_feedforward.then_some(false),
        }),
        start: Some(StartSpec {
            x: args.start.as_ref().map(|v| v[0]),
            y: args.start.as_ref().map(|v| v[1]),
            heading_deg: args.heading,
            attitude: if args.on_ground {
                Attitude::Ground
            } else {
                Attitude::Level
            },
        }),
        command: Some(vec![CommandSpec {
            at: 0.0,
            forward: args.speed,
            sideways: args.sideways,
            turn_deg_s: args.turn,
            ramp: 0.0,
        }]),
        record: RecordSpec {
            log_rate: Some(args.log_rate),
            ..Default::default()
        },
        // a field without a flag (a ball's, the expectations) as a scenario file leaves it
        ..ScenarioSpec::default()
    }
}

pub fn run(args: RunArgs) -> Result<ExitCode> {
    let scenario = match &args.scenario {
        Some(file) => from_file(file)?,
        None => Scenario::resolve(spec(&args), "run".into(), Path::new(COMMAND_LINE))?,
    };
    warn_about([&scenario], args.strict)?;
    let gait_name = scenario.gait().map_or(String::new(), |g| g.name.clone());
    let terrain_name = scenario.terrain_name().to_string();
    let bar = progress_bar(
        scenario.total_steps(),
        format!(
            "{} s",
            scenario.spec.settle.unwrap_or(DEFAULT_SETTLE) + scenario.spec.duration
        ),
    );
    let record = (!args.no_record).then(|| args.record.clone());
    let outputs = Outputs::files(record, args.trajectory.clone(), args.metrics.clone()).with_some(
        bar.clone()
            .map(|b| Output::Progress(Box::new(move |done: u64| b.set_position(done)))),
    );
    let report = scenario.run(outputs);
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let report = report?;
    let Metrics::Walk(m) = &report.metrics else {
        unreachable!("a walk scenario reports walk metrics")
    };
    out!(
        "{gait_name} ({}) on {terrain_name}: walked {:.2} s{}",
        scenario
            .spec
            .robot
            .as_deref()
            .map_or("hex18".into(), |p| p.display().to_string()),
        m.walk_time,
        if m.complete { "" } else { " (stopped early)" }
    );
    if let Some(robot) = scenario.robot()
        && robot.forward.from != hexsim::robot::legs::ForwardFrom::Urdf
    {
        out!("  walking direction {}", robot.forward.describe());
    }
    out!(
        "  distance {:.3} m (forward {:.3}, sideways {:.3}), mean speed {:.4} m/s, heading change {:.2}°",
        m.distance,
        m.forward_distance,
        m.sideways_distance,
        m.mean_speed,
        m.heading_change_deg
    );
    out!(
        "  max roll {:.2}°, max pitch {:.2}°; body height {:.4} ± {:.4} m; deepest foot {:.2} mm",
        m.max_roll_deg,
        m.max_pitch_deg,
        m.body_height_mean,
        m.body_height_std,
        m.max_penetration * 1e3
    );
    out!("  ground: {}", m.ground.describe());
    let mm = |slip: &[f64; 6]| -> String {
        let each: Vec<String> = slip.iter().map(|s| format!("{:.1}", s * 1e3)).collect();
        each.join(" ")
    };
    out!(
        "  foot slip in contact (mm, lf lm lr rf rm rr): {}; of it under load: {}; swings' scuffs: {}",
        mm(&m.foot_slip),
        mm(&m.foot_slip_loaded),
        mm(&m.foot_scuff)
    );
    if m.time_off_terrain > 0.0 {
        // the default terrain is 4 m long: a robot 1–2 m across walks off it in a few seconds
        let longer = if terrain_name.starts_with(hexsim::scenario::builtin::NATURAL.path) {
            " (`--terrain natural_long`: the same terrain continued to 12 m along +x)"
        } else {
            ""
        };
        out!(
            "  warning: the body was beyond the terrain's grid for {:.2} s, walking on the flat apron that extends the grid's edges: those seconds are no walk on that terrain{longer}",
            m.time_off_terrain
        );
    }
    if let Some(h) = m.body_height_min.filter(|h| *h < 0.0) {
        out!(
            "  warning: the body went {:.1} mm into the ground (its hips below the terrain): the robot collapsed where its links have no collision geometry to hold it",
            -h * 1e3
        );
    }
    if let Some(ringing) = &m.servo_ringing {
        out!(
            "  warning: {}; the walk's figures are not its servo's",
            hexsim::sim::ringing::describe(&ringing.joint, ringing.from)
        );
    }
    if let Some(t) = m.fell_at {
        let when = if t < 0.0 {
            format!("while it settled, {:.2} s before the walk", -t)
        } else {
            format!("at {t:.2} s into the walk")
        };
        out!(
            "  warning: the robot fell {when} (its body tilted past {:.0}°){}",
            hexsim::metrics::walk::FALL_TILT.to_degrees(),
            if scenario.spec.stop_at_fall == Some(true) {
                "; the walk stopped there (stop_at_fall)"
            } else {
                ""
            }
        );
    }
    if !m.link_contact_time.is_empty() {
        let links: Vec<String> = m
            .link_contact_time
            .iter()
            .map(|(link, t)| format!("{link} {t:.2} s"))
            .collect();
        out!(
            "  {}: links other than the feet touched the ground ({}), {:.2} mm deep at most",
            if m.body_contact_time > 0.0 {
                "warning"
            } else {
                "note"
            },
            links.join(", "),
            m.max_link_penetration * 1e3
        );
    }
    if m.command_progress < -hexsim::metrics::walk::BACKWARDS_NOISE {
        out!(
            "  warning: the body went {:.3} m backwards against the command (slid?)",
            -m.command_progress
        );
    }
    for flag in m.walk_flags.iter().filter(|f| !f.starts_with("went ")) {
        out!("  warning: not the walk commanded: it {flag}");
    }
    if m.clamped_ik_steps > 0 {
        out!(
            "  warning: {} steps had foot targets out of reach (IK clamped)",
            m.clamped_ik_steps
        );
    }
    out!("  {:.0} steps/s", report.steps_per_second);
    let mut code = conclude(&report);
    let judged = report.failure.is_none() && m.complete && !args.allow_flags;
    if judged && !m.walk_flags.is_empty() {
        eprintln!(
            "error: not the walk commanded ({}); --allow-flags accepts it",
            m.walk_flags
                .iter()
                .map(|f| match f.split([' ', ':']).next().unwrap_or_default() {
                    "went" => "went backwards",
                    "drifted" => "drifted sideways",
                    first => first,
                })
                .collect::<Vec<_>>()
                .join(", ")
        );
        code = ExitCode::from(1);
    }
    // a scenario file's own expectations (`[expect]`), judged as `hexsim batch` judges them
    // (a divergence and the walk's flags are judged above)
    if report.failure.is_none() && m.complete {
        let unmet: Vec<String> = report
            .checks
            .iter()
            .filter(|c| {
                !c.passed
                    && !matches!(
                        c.expectation.as_str(),
                        "no_divergence" | "walk_as_commanded"
                    )
            })
            .map(hexsim::batch::describe_check)
            .collect();
        if !unmet.is_empty() {
            eprintln!("error: expectation not met: {}", unmet.join("; "));
            code = ExitCode::from(1);
        }
    }
    if args.spawn && !args.no_record {
        hexsim::record::rerun::spawn_viewer(&args.record)?;
    }
    Ok(code)
}
