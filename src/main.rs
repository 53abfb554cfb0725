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
                  Without a subcommand, runs the paper's ball experiment on its natural terrain with built-in defaults."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
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

fn load_terrain(
    path: Option<&Path>,
    builtin: &str,
    builtin_name: &str,
) -> Result<(HeightGrid, String)> {
    match path {
        Some(path) => Ok((terrain::load(path)?, path.display().to_string())),
        None => {
            let origin = Path::new(builtin_name);
            let grid = TerrainSpec::from_toml(builtin, origin)?.build(origin)?;
            Ok((grid, format!("{builtin_name} (built in)")))
        }
    }
}

fn ball(args: BallArgs) -> Result<()> {
    let (grid, terrain_name) = load_terrain(
        args.terrain.as_deref(),
        BALL_TERRAIN,
        "terrains/natural_ball.toml",
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
        println!(
            "  first bounce apex {:.4} m (e = {:.3} for the drop height)",
            h,
            (h / args.drop_height).sqrt()
        );
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
    let result = match cli.command {
        None => ball(BallArgs::default()),
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
