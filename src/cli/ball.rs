//! `hexsim ball`: the paper's experiment, a ball dropped on a terrain.

use anyhow::Result;
use clap::{Args, Parser};
use hexsim::scenario::spec::{BALL_LOG_RATE, BallSpec, ContactSpec, DEFAULT_DT, RecordSpec};
use hexsim::scenario::{FileOr, Kind, Metrics, Outputs, Scenario, ScenarioSpec};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::{COMMAND_LINE, Cli, Command, conclude};

#[derive(Args)]
pub struct BallArgs {
    /// Terrain file (TOML). Default: the paper's natural terrain (eq. 7, seed 5489) at ball
    /// scale, 0.2 m peak-to-peak over 4 m × 4 m.
    #[arg(long)]
    terrain: Option<PathBuf>,
    /// Ball radius (m).
    #[arg(long, default_value_t = BallSpec::default().radius)]
    radius: f64,
    /// Ball mass (kg).
    #[arg(long, default_value_t = BallSpec::default().mass)]
    mass: f64,
    /// Start x, y of the centre (m).
    #[arg(long, num_args = 2, value_names = ["X", "Y"], default_values_t = BallSpec::default().at, allow_negative_numbers = true)]
    at: Vec<f64>,
    /// Start height of the ball's lowest point above the ground below it (m).
    #[arg(long, default_value_t = BallSpec::default().drop_height)]
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
    contact: ContactSpec,
    /// Simulated time (s).
    #[arg(long, default_value_t = 10.0)]
    duration: f64,
    /// Time step (s).
    #[arg(long, default_value_t = DEFAULT_DT)]
    dt: f64,
    /// Recording file (.rrd) for the rerun viewer.
    #[arg(long, default_value = "ball.rrd", conflicts_with = "no_record")]
    record: PathBuf,
    /// Do not write a recording.
    #[arg(long)]
    no_record: bool,
    /// Samples per second in the recording and trajectory.
    #[arg(long, default_value_t = BALL_LOG_RATE)]
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

impl Default for BallArgs {
    fn default() -> Self {
        let cli = Cli::parse_from(["hexsim", "ball"]);
        match cli.command {
            Some(Command::Ball(args)) => *args,
            _ => unreachable!("`hexsim ball` parses to the ball command"),
        }
    }
}

pub fn ball(args: BallArgs) -> Result<ExitCode> {
    let spec = ScenarioSpec {
        name: Some("ball".into()),
        description: String::new(),
        kind: Kind::Ball,
        terrain: args.terrain.clone().map(FileOr::File),
        seed: None,
        duration: args.duration,
        dt: Some(args.dt),
        contact: args.contact,
        allow_unstable_dt: args.allow_unstable_dt,
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
        // the walk's fields unset (a ball refuses them), no expectations
        ..ScenarioSpec::default()
    };
    let scenario = Scenario::resolve(spec, "ball".into(), Path::new(COMMAND_LINE))?;
    let terrain_name = scenario.terrain_name().to_string();
    let record = (!args.no_record).then(|| args.record.clone());
    let report = scenario.run(Outputs::files(
        record,
        args.trajectory.clone(),
        args.metrics.clone(),
    ))?;
    let Metrics::Ball(m) = &report.metrics else {
        unreachable!("a ball scenario reports ball metrics")
    };
    out!(
        "ball on {terrain_name}: {:.2} s simulated{}",
        m.sim_time,
        if m.complete { "" } else { " (stopped early)" }
    );
    out!(
        "  touch-downs {}, max penetration {:.3} mm, max normal force {:.2} N",
        m.touchdowns,
        m.max_penetration * 1e3,
        m.max_normal_force
    );
    if let Some(h) = m.first_apex_height {
        out!("  first bounce apex: lowest point at z = {h:.4} m");
    }
    out!(
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
