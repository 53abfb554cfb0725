//! Scenarios: a simulation described as data (see [`spec`]), resolved against its files, run, and
//! judged by its expectations. `hexsim run`, `hexsim ball` and `hexsim batch` all go through here:
//! scenario → world → step loop → outputs.

pub mod builtin;
pub mod expect;
pub mod spec;
pub mod sweep;

pub use crate::metrics::Metrics;
pub use expect::Check;
pub use spec::{FileOr, Kind, ScenarioSpec};

use crate::contact::ContactModel;
use crate::gait::{CommandChange, CommandSchedule, GaitSpec, VelocityCommand};
use crate::robot::RobotModel;
use crate::runner::ball::BallRun;
use crate::runner::walk::WalkRun;
use crate::sim::{
    BallConfig, DEFAULT_SOLVER_ITERATIONS, HexapodSettings, Placement, STANDARD_GRAVITY, ServoGains,
};
use crate::terrain::{HeightGrid, TerrainSpec};
use sha2::{Digest, Sha256};
use spec::{BALL_LOG_RATE, DEFAULT_SETTLE, START_INSET, WALK_LOG_RATE};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A scenario that cannot be used; names the file (empty for one made on the command line) and
/// what is wrong.
#[derive(Debug)]
pub struct ScenarioError {
    pub file: PathBuf,
    pub message: String,
}

impl std::fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.file.as_os_str().is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.file.display(), self.message)
        }
    }
}

impl std::error::Error for ScenarioError {}

/// A scenario resolved against its files: robot and gait loaded, terrain parsed (built when run).
pub struct Scenario {
    pub name: String,
    /// The file it came from.
    pub file: PathBuf,
    /// Identifies the scenario's content: its fields and the robot, gait and terrain it uses.
    pub hash: String,
    pub spec: ScenarioSpec,
    /// The terrain generator's seed, if it has one.
    pub seed: Option<u32>,
    /// What is doubtful but allowed (a missing visual mesh, a gait that lifts too many feet).
    pub warnings: Vec<String>,
    terrain: TerrainSource,
    /// Every setting typed, with its default applied: what `run` runs.
    contact: ContactModel,
    log_rate: f64,
    setup: Setup,
}

struct TerrainSource {
    spec: TerrainSpec,
    /// The file that relative data paths resolve against and errors name.
    origin: PathBuf,
    name: String,
}

enum Setup {
    Walk(Box<WalkSetup>),
    Ball(BallConfig),
}

struct WalkSetup {
    robot: Arc<RobotModel>,
    gait: GaitSpec,
    commands: CommandSchedule,
    settings: HexapodSettings,
    settle: f64,
    follow_terrain: bool,
    start: spec::StartSpec,
}

impl WalkSetup {
    /// Where the body starts on `grid`: as set, else [`START_INSET`] inside its −x edge, centred
    /// in y.
    fn placement(&self, grid: &HeightGrid) -> Placement {
        let [x_min, _] = grid.x_range();
        let [y_min, y_max] = grid.y_range();
        Placement {
            x: self.start.x.unwrap_or(x_min + START_INSET),
            y: self.start.y.unwrap_or(0.5 * (y_min + y_max)),
            yaw: self.start.heading_deg.to_radians(),
        }
    }
}

/// Files a run writes besides its results.
#[derive(Default)]
pub struct Outputs {
    pub record: Option<PathBuf>,
    pub trajectory: Option<PathBuf>,
    pub metrics: Option<PathBuf>,
    /// Called now and then with the steps done so far.
    pub progress: Option<Box<dyn Fn(u64)>>,
}

/// What a run of a scenario produced.
pub struct Report {
    pub metrics: Metrics,
    pub steps: u64,
    pub wall_time: f64,
    pub steps_per_second: f64,
    /// Walks: of the stepping's wall time, the seconds inside rapier's step.
    pub physics_seconds: Option<f64>,
    /// Why the run stopped early, if it diverged.
    pub failure: Option<String>,
    pub checks: Vec<Check>,
    pub written: Vec<PathBuf>,
}

impl Report {
    pub fn passed(&self) -> bool {
        self.failure.is_none() && self.checks.iter().all(|c| c.passed)
    }
}

/// Reads a scenario file; a file with a `[sweep]` table gives one scenario per combination.
pub fn load_file(path: &Path) -> Result<Vec<Scenario>, ScenarioError> {
    let fail = |message: String| ScenarioError {
        file: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| fail(format!("cannot read the scenario file: {e}")))?;
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| fail(e.to_string().trim_end().to_string()))?;
    let stem = path
        .file_stem()
        .map_or("scenario".into(), |s| s.to_string_lossy().into_owned());
    if !table.contains_key("sweep") {
        // parse the text itself, so that errors carry line numbers
        let spec: ScenarioSpec =
            toml::from_str(&text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
        let name = spec.name.clone().unwrap_or(stem);
        return Ok(vec![Scenario::resolve(spec, name, path)?]);
    }
    let base = match table.get("name") {
        Some(toml::Value::String(name)) => name.clone(),
        _ => stem,
    };
    let variants = sweep::expand(table).map_err(fail)?;
    variants
        .into_iter()
        .map(|variant| {
            let name = variant.name(&base);
            let spec: ScenarioSpec = toml::Value::Table(variant.table)
                .try_into()
                .map_err(|e: toml::de::Error| fail(format!("{name}: {}", e.message())))?;
            Scenario::resolve(spec, name, path)
        })
        .collect()
}

fn read_bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_default()
}

impl Scenario {
    /// Checks the spec and loads what it refers to. `origin` is the scenario's file: relative paths
    /// resolve against its folder, and errors name it.
    pub fn resolve(spec: ScenarioSpec, name: String, origin: &Path) -> Result<Self, ScenarioError> {
        let fail = |message: String| ScenarioError {
            file: origin.to_path_buf(),
            message,
        };
        let base = origin.parent().unwrap_or(Path::new(""));
        if name.is_empty() || name.contains(['/', '\\']) {
            return Err(fail(format!(
                "name: expected a non-empty name without slashes, got {name:?}"
            )));
        }
        if !(spec.dt.is_finite() && spec.dt > 0.0 && spec.dt <= 0.01) {
            return Err(fail(format!(
                "dt: expected a time step in (0, 0.01] s, got {}",
                spec.dt
            )));
        }
        if !(spec.duration.is_finite() && spec.duration >= 0.0) {
            return Err(fail(format!(
                "duration: expected a finite number ≥ 0 s, got {}",
                spec.duration
            )));
        }
        let contact = spec.contact.model();
        if let Err((field, expected)) = contact.validate() {
            return Err(fail(format!("contact.{field}: {expected}")));
        }
        spec.expect.validate(spec.kind).map_err(fail)?;
        for (field, tolerance) in &spec.tolerance {
            for v in [tolerance.rel, tolerance.abs].into_iter().flatten() {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(fail(format!(
                        "tolerance.{field}: expected numbers ≥ 0, got {v}"
                    )));
                }
            }
        }
        if let Some(rate) = spec.record.log_rate
            && !(rate.is_finite() && rate > 0.0)
        {
            return Err(fail(format!(
                "record.log_rate: expected a rate > 0 per second, got {rate}"
            )));
        }
        let mut hasher = Sha256::new();
        hasher.update(serde_json::to_vec(&spec).expect("a spec is plain data"));

        // the terrain
        let default_terrain = match spec.kind {
            Kind::Walk => builtin::NATURAL,
            Kind::Ball => builtin::NATURAL_BALL,
        };
        let mut terrain = match &spec.terrain {
            None => TerrainSource {
                spec: TerrainSpec::from_toml(default_terrain.text, Path::new(default_terrain.path))
                    .map_err(|e| fail(e.to_string()))?,
                origin: PathBuf::from(default_terrain.path),
                name: format!("{} (built in)", default_terrain.path),
            },
            Some(FileOr::File(file)) => {
                let path = base.join(file);
                TerrainSource {
                    spec: TerrainSpec::from_file(&path).map_err(|e| fail(e.to_string()))?,
                    name: file.display().to_string(),
                    origin: path,
                }
            }
            Some(FileOr::Inline(inline)) => TerrainSource {
                spec: inline.clone(),
                origin: origin.to_path_buf(),
                name: format!("{name} (inline terrain)"),
            },
        };
        if let Some(seed) = spec.seed {
            terrain.spec = terrain.spec.clone().with_seed(seed);
        }
        let seed = terrain.spec.seed();
        hasher.update(serde_json::to_vec(&terrain.spec).expect("a spec is plain data"));
        let data_base = terrain.origin.parent().unwrap_or(Path::new(""));
        if let Some(path) = terrain.spec.source.get().data_file() {
            hasher.update(read_bytes(&data_base.join(path)));
        }

        let mut warnings = Vec::new();
        let walk_only = [
            ("robot", spec.robot.is_some()),
            ("gait", spec.gait.is_some()),
            ("settle", spec.settle.is_some()),
            ("follow_terrain", spec.follow_terrain.is_some()),
            ("articulation", spec.articulation.is_some()),
            ("solver_iterations", spec.solver_iterations.is_some()),
            ("pgs_iterations", spec.pgs_iterations.is_some()),
            ("servo", spec.servo.is_some()),
            ("start", spec.start.is_some()),
            ("command", spec.command.is_some()),
        ];
        let setup = match spec.kind {
            Kind::Ball => {
                if let Some((field, _)) = walk_only.iter().find(|(_, set)| *set) {
                    return Err(fail(format!(
                        "{field}: applies to walk scenarios, but kind = \"ball\""
                    )));
                }
                let b = spec.ball.unwrap_or_default();
                let config = BallConfig {
                    radius: b.radius,
                    mass: b.mass,
                    position: [b.at[0], b.at[1], b.drop_height + b.radius],
                    velocity: b.velocity,
                    angular_velocity: b.angular_velocity,
                    lock_rotation: b.lock_rotation,
                    gravity: STANDARD_GRAVITY,
                };
                if let Err((field, expected)) = config.validate() {
                    return Err(fail(format!("ball.{field}: {expected}")));
                }
                let limit = contact.normal.stable_time_step(b.mass, b.radius * 0.1);
                if spec.dt >= limit && !spec.allow_unstable_dt {
                    return Err(fail(format!(
                        "dt = {} s is too large for the contact spring on a {} kg ball: the explicit spring needs dt < {limit:.2e} s (2/√(k/m)); reduce dt or the stiffness (or set allow_unstable_dt = true to run it anyway)",
                        spec.dt, b.mass
                    )));
                }
                Setup::Ball(config)
            }
            Kind::Walk => {
                if spec.ball.is_some() {
                    return Err(fail(
                        "ball: applies to ball scenarios; set kind = \"ball\"".into(),
                    ));
                }
                let robot = match &spec.robot {
                    None => {
                        hasher.update(builtin::HEX18.text);
                        crate::robot::urdf::from_str(
                            builtin::HEX18.text,
                            Path::new(builtin::HEX18.path),
                        )
                    }
                    Some(file) => {
                        let path = base.join(file);
                        hasher.update(read_bytes(&path));
                        hasher.update(read_bytes(&path.with_extension("toml")));
                        crate::robot::load(&path)
                    }
                }
                .map_err(|e| fail(format!("robot: {e}")))?;
                let gait = match &spec.gait {
                    None => {
                        GaitSpec::from_toml(builtin::TRIPOD.text, Path::new(builtin::TRIPOD.path))
                            .map_err(|e| fail(e.to_string()))?
                    }
                    Some(FileOr::File(file)) => GaitSpec::from_file(&base.join(file))
                        .map_err(|e| fail(format!("gait: {e}")))?,
                    Some(FileOr::Inline(gait)) => {
                        gait.validate().map_err(|e| fail(format!("gait: {e}")))?;
                        gait.clone()
                    }
                };
                hasher.update(serde_json::to_vec(&gait).expect("a spec is plain data"));
                let gait_name = match &spec.gait {
                    None => format!("gait {} (built in)", builtin::TRIPOD.path),
                    Some(FileOr::File(file)) => format!("gait {}", base.join(file).display()),
                    Some(FileOr::Inline(_)) => "gait (inline)".to_string(),
                };
                crate::gait::GaitController::new(&robot, gait.clone())
                    .map_err(|e| fail(format!("{gait_name}: {e}")))?;
                let support = crate::gait::minimum_support(&gait.offsets(), gait.duty_factor);
                if support < 3 {
                    warnings.push(format!(
                        "{gait_name}: at times only {support} feet are on the ground (a hexapod needs 3 to stand statically); check its duty_factor and phase_offsets"
                    ));
                }
                warnings.extend(robot.warnings.iter().cloned());
                // the lightest foot link bounds the effective mass the contact spring acts on
                if let Some((foot, mass)) = robot
                    .legs
                    .iter()
                    .map(|leg| {
                        (
                            &robot.links[leg.foot_link].name,
                            robot.links[leg.foot_link].mass,
                        )
                    })
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                {
                    let radius = robot.legs[0].foot.radius;
                    let limit = contact.normal.stable_time_step(mass, radius * 0.1);
                    if spec.dt >= limit && !spec.allow_unstable_dt {
                        return Err(fail(format!(
                            "dt = {} s is too large for the contact spring on the lightest foot link (`{foot}`, {mass} kg): the explicit spring needs dt < {limit:.2e} s (2/√(k/m)); reduce dt or the stiffness (or set allow_unstable_dt = true to run it anyway)",
                            spec.dt
                        )));
                    }
                }
                let settle = spec.settle.unwrap_or(DEFAULT_SETTLE);
                if !(settle.is_finite() && settle >= 0.0) {
                    return Err(fail(format!(
                        "settle: expected a finite number ≥ 0 s, got {settle}"
                    )));
                }
                if spec.solver_iterations == Some(0) {
                    return Err(fail("solver_iterations: expected at least 1".into()));
                }
                if spec.pgs_iterations == Some(0) {
                    return Err(fail("pgs_iterations: expected at least 1".into()));
                }
                let servo = spec.servo.unwrap_or_default();
                if !(servo.stiffness.is_finite()
                    && servo.stiffness > 0.0
                    && servo.damping.is_finite()
                    && servo.damping >= 0.0)
                {
                    return Err(fail(format!(
                        "servo: expected stiffness > 0 and damping ≥ 0, got {} and {}",
                        servo.stiffness, servo.damping
                    )));
                }
                let changes = match &spec.command {
                    None => vec![CommandChange {
                        at: 0.0,
                        command: VelocityCommand {
                            forward: gait.nominal_speed(),
                            ..Default::default()
                        },
                        ramp: 0.0,
                    }],
                    Some(list) => list
                        .iter()
                        .map(|c| CommandChange {
                            at: c.at,
                            command: VelocityCommand {
                                forward: c.forward.unwrap_or_else(|| gait.nominal_speed()),
                                sideways: c.sideways,
                                yaw_rate: c.turn_deg_s.to_radians(),
                            },
                            ramp: c.ramp,
                        })
                        .collect(),
                };
                let commands = CommandSchedule::new(changes).map_err(fail)?;
                if let Some(start) = spec.start
                    && ![start.x, start.y, Some(start.heading_deg)]
                        .into_iter()
                        .flatten()
                        .all(f64::is_finite)
                {
                    return Err(fail("start: expected finite numbers".into()));
                }
                Setup::Walk(Box::new(WalkSetup {
                    robot: Arc::new(robot),
                    gait,
                    commands,
                    settings: HexapodSettings {
                        articulation: spec.articulation.unwrap_or_default(),
                        dt: spec.dt,
                        solver_iterations: spec
                            .solver_iterations
                            .unwrap_or(DEFAULT_SOLVER_ITERATIONS),
                        pgs_iterations: spec.pgs_iterations,
                        gains: ServoGains {
                            stiffness: servo.stiffness,
                            damping: servo.damping,
                        },
                    },
                    settle,
                    follow_terrain: spec.follow_terrain.unwrap_or(false),
                    start: spec.start.unwrap_or_default(),
                }))
            }
        };
        let hash: String = hasher.finalize()[..8]
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        let log_rate = spec.record.log_rate.unwrap_or(match spec.kind {
            Kind::Walk => WALK_LOG_RATE,
            Kind::Ball => BALL_LOG_RATE,
        });
        Ok(Scenario {
            name,
            file: origin.to_path_buf(),
            hash,
            spec,
            seed,
            warnings,
            terrain,
            contact,
            log_rate,
            setup,
        })
    }

    pub fn kind(&self) -> Kind {
        self.spec.kind
    }

    /// The terrain's name for messages and recordings.
    pub fn terrain_name(&self) -> &str {
        &self.terrain.name
    }

    /// The robot, for walk scenarios.
    pub fn robot(&self) -> Option<&RobotModel> {
        match &self.setup {
            Setup::Walk(w) => Some(&w.robot),
            Setup::Ball(_) => None,
        }
    }

    /// The gait, for walk scenarios.
    pub fn gait(&self) -> Option<&GaitSpec> {
        match &self.setup {
            Setup::Walk(w) => Some(&w.gait),
            Setup::Ball(_) => None,
        }
    }

    /// Steps the run will take.
    pub fn total_steps(&self) -> u64 {
        let time = match &self.setup {
            Setup::Walk(w) => w.settle + self.spec.duration,
            Setup::Ball(_) => self.spec.duration,
        };
        (time / self.spec.dt).round() as u64
    }

    /// Builds the terrain (generators run here; a file's heights are read here).
    pub fn build_terrain(&self) -> Result<HeightGrid, ScenarioError> {
        self.terrain
            .spec
            .build(&self.terrain.origin)
            .map_err(|e| ScenarioError {
                file: self.file.clone(),
                message: format!("terrain: {e}"),
            })
    }

    /// Runs the scenario and checks its expectations. An error is an input or output problem; a
    /// run that diverged is a [`Report`] with `failure` set.
    pub fn run(&self, outputs: Outputs) -> anyhow::Result<Report> {
        let grid = Arc::new(self.build_terrain()?);
        let spec = &self.spec;
        let started = std::time::Instant::now();
        let (metrics, steps_per_second, physics_seconds, failure, written) = match &self.setup {
            Setup::Walk(w) => {
                let run = WalkRun {
                    robot: w.robot.clone(),
                    placement: w.placement(&grid),
                    terrain: grid,
                    terrain_name: self.terrain.name.clone(),
                    gait: w.gait.clone(),
                    commands: w.commands.clone(),
                    contact: self.contact,
                    settings: w.settings,
                    settle_time: w.settle,
                    terrain_following: w.follow_terrain,
                    duration: spec.duration,
                    record: outputs.record,
                    log_rate: self.log_rate,
                    trajectory: outputs.trajectory,
                    metrics: outputs.metrics,
                    progress: outputs.progress,
                };
                let o = run.execute()?;
                (
                    Metrics::Walk(Box::new(o.metrics)),
                    o.steps_per_second,
                    Some(o.physics_seconds),
                    o.failure,
                    o.written,
                )
            }
            Setup::Ball(config) => {
                let mut config = *config;
                config.position[2] += grid.height(config.position[0], config.position[1]);
                let run = BallRun {
                    ball: config,
                    terrain: grid,
                    terrain_name: self.terrain.name.clone(),
                    contact: self.contact,
                    dt: spec.dt,
                    duration: spec.duration,
                    record: outputs.record,
                    log_rate: self.log_rate,
                    trajectory: outputs.trajectory,
                    metrics: outputs.metrics,
                    progress: outputs.progress,
                };
                let o = run.execute()?;
                (
                    Metrics::Ball(o.metrics),
                    o.steps_per_second,
                    None,
                    o.failure,
                    o.written,
                )
            }
        };
        let steps = metrics.steps();
        let checks = spec.expect.check(&metrics, failure.is_some());
        Ok(Report {
            metrics,
            steps,
            wall_time: started.elapsed().as_secs_f64(),
            steps_per_second,
            physics_seconds,
            failure,
            checks,
            written,
        })
    }
}
