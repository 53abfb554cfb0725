//! Scenarios: a simulation described as data (see [`spec`]), resolved against its files, run, and
//! judged by its expectations. `hexsim run`, `hexsim ball` and `hexsim batch` all go through here:
//! scenario → world → step loop → outputs.

pub mod builtin;
pub mod expect;
pub mod inputs;
pub mod overlay;
mod resolve;
pub mod spec;
pub mod sweep;

pub use crate::metrics::Metrics;
pub use crate::runner::{Output, Outputs};
pub use expect::Check;
pub use spec::{FileOr, Kind, ScenarioSpec};

use crate::contact::ContactModel;
use crate::gait::reach::{self, ReachTally};
use crate::gait::{CommandSchedule, Fitted, Gait, GaitController};
use crate::robot::RobotModel;
use crate::runner::ball::BallRun;
use crate::runner::walk::{WalkRun, WalkSession};
use crate::sim::{BallConfig, HexapodSettings, Placement};
use crate::terrain::{HeightGrid, TerrainSpec};
use spec::START_INSET;
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
    /// The scenario's fingerprint: hexsim's version, its fields and the content of every file
    /// it read ([`inputs`]). What `batch --resume` compares.
    pub hash: String,
    /// The files it read, each with its digest.
    pub read: inputs::Inputs,
    pub spec: ScenarioSpec,
    /// The terrain generator's seed, if it has one.
    pub seed: Option<u32>,
    /// What is doubtful but allowed (a missing visual mesh, a gait that lifts too many feet).
    pub warnings: Vec<String>,
    /// What hexsim chose that the scenario left out, worth saying (a smaller step for a robot
    /// with light legs): said, never refused (`--strict` refuses warnings only).
    pub notes: Vec<String>,
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
    /// The gait on this robot, its lengths given or fitted.
    gait: Fitted,
    commands: CommandSchedule,
    settings: HexapodSettings,
    settle: f64,
    switches: crate::runner::walk::WalkSwitches,
    start: spec::StartSpec,
    /// The contact's stiffness and damping and where they came from.
    ground: crate::metrics::GroundMetrics,
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
            attitude: self.start.attitude,
        }
    }
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
/// Reads the scenario file `file`, relative to the folder of `spec` (the file naming it), as a TOML
/// table, for a command that lays fields of its own over a scenario (`compare`, `optimize`).
/// Returns the scenario's path (its relative paths resolve against it) and its table.
pub fn read_table(spec: &Path, file: &Path) -> Result<(PathBuf, toml::Table), String> {
    let path = spec.parent().unwrap_or(Path::new("")).join(file);
    let text = crate::limits::read_to_string(&path, crate::limits::TEXT_FILE_BYTES)
        .map_err(|e| format!("scenario: cannot read {}: {e}", path.display()))?;
    let table = text.parse().map_err(|e: toml::de::Error| {
        format!("scenario {}: {}", path.display(), e.to_string().trim_end())
    })?;
    Ok((path, table))
}

/// Resolves a scenario given as a TOML table (e.g. a scenario file's with some fields changed);
/// `path` is the file it came from, for relative paths and errors.
pub fn from_table(
    table: toml::Table,
    name: String,
    path: &Path,
) -> Result<Scenario, ScenarioError> {
    let spec: ScenarioSpec =
        toml::Value::Table(table)
            .try_into()
            .map_err(|e: toml::de::Error| ScenarioError {
                file: path.to_path_buf(),
                message: format!("{name}: {}", e.message()),
            })?;
    Scenario::resolve(spec, name, path)
}

pub fn load_file(path: &Path) -> Result<Vec<Scenario>, ScenarioError> {
    let fail = |message: String| ScenarioError {
        file: path.to_path_buf(),
        message,
    };
    let text = crate::limits::read_to_string(path, crate::limits::TEXT_FILE_BYTES)
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

impl Scenario {
    pub fn kind(&self) -> Kind {
        self.spec.kind
    }

    /// The terrain's name for messages and recordings.
    pub fn terrain_name(&self) -> &str {
        &self.terrain.name
    }

    /// The ball, for ball scenarios.
    pub fn ball(&self) -> Option<&BallConfig> {
        match &self.setup {
            Setup::Ball(config) => Some(config),
            Setup::Walk(_) => None,
        }
    }

    /// The contact model it runs with.
    pub fn contact(&self) -> &ContactModel {
        &self.contact
    }

    /// The robot, for walk scenarios.
    pub fn robot(&self) -> Option<&RobotModel> {
        match &self.setup {
            Setup::Walk(w) => Some(&w.robot),
            Setup::Ball(_) => None,
        }
    }

    /// The gait, for walk scenarios.
    pub fn gait(&self) -> Option<&Gait> {
        self.fitted().map(|f| &f.gait)
    }

    /// The gait and how it fits the robot (where its lengths came from, its joint room), for
    /// walk scenarios.
    pub fn fitted(&self) -> Option<&Fitted> {
        match &self.setup {
            Setup::Walk(w) => Some(&w.gait),
            Setup::Ball(_) => None,
        }
    }

    /// The servo gains (given or fitted) and the velocity commands, for walk scenarios.
    pub fn drive(&self) -> Option<(crate::sim::ServoGains, &CommandSchedule)> {
        match &self.setup {
            Setup::Walk(w) => Some((w.settings.gains, &w.commands)),
            Setup::Ball(_) => None,
        }
    }

    /// For a walk, whether its foot targets are in reach, planned on level ground step by step
    /// as the run plans them (`gait::reach`): on flat ground without terrain following or the
    /// reactive gait, the run's own tally (its `clamped_ik_steps`). `hexsim robot` reports it.
    pub fn planned_reach(&self) -> Option<Result<ReachTally, crate::gait::StanceError>> {
        let Setup::Walk(w) = &self.setup else {
            return None;
        };
        let controller = GaitController::new(&w.robot, w.gait.gait.clone());
        Some(controller.map(|c| {
            let mut controller = c.with_rolling_feet(w.switches.rolling_feet);
            reach::planned(
                &mut controller,
                reach::Stepping {
                    dt: w.settings.dt,
                    settle: w.settle,
                    duration: self.spec.duration,
                    commands: &w.commands,
                    stands_by_controller: w.switches.feedforward && !w.switches.follow_terrain,
                },
            )
        }))
    }

    /// Steps the run will take.
    pub fn total_steps(&self) -> u64 {
        let time = match &self.setup {
            Setup::Walk(w) => w.settle + self.spec.duration,
            Setup::Ball(_) => self.spec.duration,
        };
        (time / self.spec.dt()).round() as u64
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

    fn walk_run(&self, w: &WalkSetup, grid: Arc<HeightGrid>, outputs: Outputs) -> WalkRun {
        WalkRun {
            robot: w.robot.clone(),
            placement: w.placement(&grid),
            terrain: grid,
            terrain_name: self.terrain.name.clone(),
            gait: w.gait.clone(),
            commands: w.commands.clone(),
            contact: self.contact,
            ground: w.ground.clone(),
            settings: w.settings,
            settle_time: w.settle,
            switches: w.switches,
            stop_at_fall: self.spec.stop_at_fall.unwrap_or(false),
            duration: self.spec.duration,
            log_rate: self.log_rate,
            outputs,
        }
    }

    /// Starts a walk scenario to be stepped a stretch at a time (the Python package): the run
    /// [`Scenario::run`] makes, with the state readable between stretches. Its metrics at the end
    /// are `run`'s, bit for bit.
    pub fn start_walk(&self, outputs: Outputs) -> anyhow::Result<WalkSession> {
        let Setup::Walk(w) = &self.setup else {
            anyhow::bail!(
                "{}: {} is a ball scenario; only a walk can be stepped",
                self.file.display(),
                self.name
            );
        };
        let grid = Arc::new(self.build_terrain()?);
        self.walk_run(w, grid, outputs.described(self.metadata()))
            .start()
    }

    /// The same scenario with the terrain generator's seed replaced (as `seed = …` in the file).
    pub fn with_seed(&self, seed: u32) -> Result<Scenario, ScenarioError> {
        let spec = ScenarioSpec {
            seed: Some(seed),
            ..self.spec.clone()
        };
        Scenario::resolve(spec, self.name.clone(), &self.file)
    }

    /// The files this scenario reads, each with what it is: the scenario file, the robot (its
    /// robot file, its meshes), the gait, the terrain and its height data. No output may be one
    /// of them.
    pub fn inputs(&self) -> Vec<(&'static str, PathBuf)> {
        let mut inputs = Vec::new();
        if !self.file.as_os_str().is_empty() {
            inputs.push(("scenario file", self.file.clone()));
        }
        for input in self.read.iter().filter(|i| !i.builtin) {
            inputs.push((input.what, input.path.clone()));
            // a robot file written beside the URDF would be read by the next run
            let robot_file = input.path.with_extension("toml");
            if input.what == "robot" && !self.read.iter().any(|i| i.path == robot_file) {
                inputs.push(("robot file", robot_file));
            }
        }
        inputs
    }

    /// Where a run of it comes from, for the end of its metrics file.
    pub fn metadata(&self) -> crate::record::metadata::Metadata {
        let read = |what: &str| {
            self.read
                .iter()
                .find(|i| i.what == what)
                .map(|i| i.path.display().to_string())
        };
        let walk = match &self.setup {
            Setup::Walk(w) => Some(w),
            Setup::Ball(_) => None,
        };
        crate::record::metadata::Metadata {
            hexsim_version: env!("CARGO_PKG_VERSION").to_string(),
            scenario: self.name.clone(),
            scenario_file: (!self.file.as_os_str().is_empty())
                .then(|| self.file.display().to_string()),
            robot: walk.and(read("robot")),
            terrain: self.terrain.name.clone(),
            gait: walk.map(|_| read("gait file").unwrap_or_else(|| "inline".into())),
            fingerprint: self.hash.clone(),
            inputs: self.read.digests(),
            seed: self.seed,
            dt: self.spec.dt(),
            articulation: walk.map(|w| w.settings.articulation.name().to_string()),
            joints: walk.map(|w| {
                let columns = crate::record::joint_columns::joint_columns(&w.robot);
                let urdf = w.robot.joints.iter().map(|j| j.name.clone());
                columns.into_iter().zip(urdf).collect()
            }),
            legs: walk.map(|w| w.robot.legs.iter().map(|l| l.name.to_string()).collect()),
        }
    }

    /// Runs the scenario and checks its expectations. An error is an input or output problem; a
    /// run that diverged is a [`Report`] with `failure` set.
    pub fn run(&self, outputs: Outputs) -> anyhow::Result<Report> {
        let inputs = self.inputs();
        crate::record::output::check_distinct(
            outputs.named(),
            inputs.iter().map(|(what, path)| (*what, path.as_path())),
        )?;
        let grid = Arc::new(self.build_terrain()?);
        let outputs = outputs.described(self.metadata());
        let spec = &self.spec;
        let started = std::time::Instant::now();
        let (metrics, steps_per_second, physics_seconds, failure, written) = match &self.setup {
            Setup::Walk(w) => {
                let o = self.walk_run(w, grid, outputs).execute()?;
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
                    dt: spec.dt(),
                    duration: spec.duration,
                    log_rate: self.log_rate,
                    outputs,
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
