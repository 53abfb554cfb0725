//! hexsim's command line: parse, dispatch, report, exit codes — the work is in the library.

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use hexsim::contact::{ContactModel, FrictionLaw, NormalLaw};
use hexsim::runner::ball::BallRun;
use hexsim::sim::{BallConfig, STANDARD_GRAVITY};
use hexsim::terrain::{self, HeightGrid, Orientation, TerrainSpec};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

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
    /// Inspect or export terrains.
    #[command(subcommand)]
    Terrain(TerrainCommand),
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
    fn model(&self) -> ContactModel {
        let normal = match self.normal_law {
            NormalChoice::SpringDamper => NormalLaw::SpringDamper {
                stiffness: self.stiffness,
                damping: self.damping,
            },
            NormalChoice::HuntCrossley => NormalLaw::HuntCrossley {
                stiffness: self.stiffness,
                exponent: self.hc_exponent,
                damping: self.damping,
            },
        };
        let friction = match self.friction {
            FrictionChoice::Karnopp => FrictionLaw::Karnopp {
                mu_static: self.mu_static,
                mu_kinetic: self.mu_kinetic,
                stick_band: self.stick_band,
            },
            FrictionChoice::Coulomb => FrictionLaw::Coulomb {
                mu: self.mu_kinetic,
                width: self.friction_width,
            },
            FrictionChoice::Viscous => FrictionLaw::Viscous {
                coefficient: self.viscous,
            },
            FrictionChoice::Stribeck => FrictionLaw::Stribeck {
                mu_static: self.mu_static,
                mu_coulomb: self.mu_kinetic,
                viscous: self.viscous,
                stribeck_velocity: self.stribeck_velocity,
                width: self.friction_width,
            },
            FrictionChoice::None => FrictionLaw::None,
        };
        let orientation = match self.orientation {
            OrientationChoice::Exact => Orientation::Exact,
            OrientationChoice::Paper => Orientation::Paper {
                xe: self.paper_step,
                ye: self.paper_step,
            },
        };
        ContactModel {
            normal,
            friction,
            orientation,
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
    /// rapier substeps per step.
    #[arg(long, default_value_t = 4)]
    solver_iterations: usize,
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

const HEX18: &str = include_str!("../robots/hex18.urdf");
const NATURAL: &str = include_str!("../terrains/natural.toml");
const TRIPOD: &str = include_str!("../gaits/tripod.toml");

fn run(args: RunArgs) -> Result<()> {
    use hexsim::gait::{GaitSpec, VelocityCommand};
    use hexsim::runner::walk::WalkRun;
    use hexsim::sim::{HexapodSettings, Placement, ServoGains};
    use std::io::IsTerminal;

    let robot = match &args.robot {
        Some(path) => hexsim::robot::load(path)?,
        None => hexsim::robot::urdf::from_str(HEX18, Path::new("robots/hex18.urdf"))?,
    };
    for warning in &robot.warnings {
        eprintln!("warning: {warning}");
    }
    let (grid, terrain_name) = load_terrain(
        args.terrain.as_deref(),
        NATURAL,
        "terrains/natural.toml",
        args.seed,
    )?;
    let gait = match &args.gait {
        Some(path) => GaitSpec::from_file(path)?,
        None => GaitSpec::from_toml(TRIPOD, Path::new("gaits/tripod.toml"))?,
    };
    let [x_min, _] = grid.x_range();
    let [y_min, y_max] = grid.y_range();
    let (x, y) = match &args.start {
        Some(v) => (v[0], v[1]),
        None => (x_min + 0.75, 0.5 * (y_min + y_max)),
    };
    let command = VelocityCommand {
        forward: args.speed.unwrap_or_else(|| gait.nominal_speed()),
        sideways: args.sideways,
        yaw_rate: args.turn.to_radians(),
    };
    let total = args.settle + args.duration;
    let bar = std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(1000);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} simulating [{bar:40}] {percent:>3}% ({eta} left) {msg}",
            )
            .expect("the template is valid")
            .progress_chars("=> "),
        );
        bar.set_message(format!("{total} s"));
        bar
    });
    let progress_bar = bar.clone();
    let run = WalkRun {
        robot: Arc::new(robot),
        terrain: Arc::new(grid),
        terrain_name: terrain_name.clone(),
        gait: gait.clone(),
        command,
        contact: args.contact.model(),
        settings: HexapodSettings {
            dt: args.dt,
            solver_iterations: args.solver_iterations,
            gains: ServoGains {
                stiffness: args.servo_stiffness,
                damping: args.servo_damping,
            },
        },
        placement: Placement {
            x,
            y,
            yaw: args.heading.to_radians(),
        },
        settle_time: args.settle,
        terrain_following: args.follow_terrain,
        duration: args.duration,
        record: (!args.no_record).then(|| args.record.clone()),
        log_rate: args.log_rate,
        trajectory: args.trajectory.clone(),
        metrics: args.metrics.clone(),
        progress: progress_bar.map(|b| {
            Box::new(move |f: f64| b.set_position((f * 1000.0) as u64)) as Box<dyn Fn(f64)>
        }),
    };
    let outcome = run.execute();
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let outcome = outcome?;
    let m = &outcome.metrics;
    println!(
        "{} ({}) on {terrain_name}: walked {:.2} s{}",
        gait.name,
        args.robot
            .as_deref()
            .map_or("hex18".into(), |p| p.display().to_string()),
        m.walk_time,
        if m.complete { "" } else { " (interrupted)" }
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
    println!("  {:.0} steps/s", outcome.steps_per_second);
    for path in &outcome.written {
        println!("  wrote {}", path.display());
    }
    if args.spawn && !args.no_record {
        hexsim::record::rerun::spawn_viewer(&args.record)?;
    }
    Ok(())
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

/// The ball experiment's default ground: the paper's natural terrain at ball scale.
const BALL_TERRAIN: &str = include_str!("../terrains/natural_ball.toml");

/// A terrain from its file, or the built-in one; `seed` replaces a generator's seed.
fn load_terrain(
    path: Option<&Path>,
    builtin: &str,
    builtin_name: &str,
    seed: Option<u32>,
) -> Result<(HeightGrid, String)> {
    let (spec, origin, name) = match path {
        Some(path) => (
            TerrainSpec::from_file(path)?,
            path,
            path.display().to_string(),
        ),
        None => {
            let origin = Path::new(builtin_name);
            let spec = TerrainSpec::from_toml(builtin, origin)?;
            (spec, origin, format!("{builtin_name} (built in)"))
        }
    };
    let spec = match seed {
        Some(seed) => spec.with_seed(seed),
        None => spec,
    };
    Ok((spec.build(origin)?, name))
}

fn ball(args: BallArgs) -> Result<()> {
    let (grid, terrain_name) = load_terrain(
        args.terrain.as_deref(),
        BALL_TERRAIN,
        "terrains/natural_ball.toml",
        None,
    )?;
    let (x, y) = (args.at[0], args.at[1]);
    let start_z = grid.height(x, y) + args.drop_height + args.radius;
    let run = BallRun {
        ball: BallConfig {
            radius: args.radius,
            mass: args.mass,
            position: [x, y, start_z],
            velocity: [args.velocity[0], args.velocity[1], args.velocity[2]],
            angular_velocity: [
                args.angular_velocity[0],
                args.angular_velocity[1],
                args.angular_velocity[2],
            ],
            lock_rotation: args.lock_rotation,
            gravity: STANDARD_GRAVITY,
        },
        terrain: Arc::new(grid),
        terrain_name: terrain_name.clone(),
        contact: args.contact.model(),
        dt: args.dt,
        duration: args.duration,
        record: (!args.no_record).then(|| args.record.clone()),
        log_rate: args.log_rate,
        trajectory: args.trajectory.clone(),
        metrics: args.metrics.clone(),
    };
    let outcome = run.execute()?;
    let m = &outcome.metrics;
    println!(
        "ball on {terrain_name}: {:.2} s simulated{}",
        m.sim_time,
        if m.complete { "" } else { " (interrupted)" }
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
    for path in &outcome.written {
        println!("  wrote {}", path.display());
    }
    if args.spawn && !args.no_record {
        hexsim::record::rerun::spawn_viewer(&args.record)?;
    }
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
        Some(Command::Terrain(command)) => terrain_command(command),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::from(2)
        }
    }
}
