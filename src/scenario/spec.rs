//! Scenario files (TOML, every table `deny_unknown_fields` so a typo is an error): one simulation —
//! what walks (or falls) on what ground, commanded how, for how long, what to record, and what it
//! must achieve. Paths inside a scenario resolve relative to the scenario file.
//!
//! ```toml
//! description = "tripod on the paper's natural terrain"
//! kind = "walk"                        # walk (default) | ball
//! robot = "../robots/hex18.urdf"       # default: hex18 (built in)
//! terrain = "../terrains/natural.toml" # a terrain file, or an inline table like a terrain file's
//! gait = "../gaits/tripod.toml"        # a gait file, or an inline table like a gait file's
//! duration = 10.0                      # s walked (after `settle`), or simulated for a ball
//! dt = 0.001
//! seed = 7                             # replaces the terrain generator's seed
//! articulation = "multibody"           # multibody (default) | impulse (about as fast; joints drift)
//! [start]                              # default: 0.75 m inside the terrain's −x edge
//! x = -1.25
//! heading_deg = 0.0
//! [[command]]                          # default: the gait's nominal speed straight ahead
//! at = 0.0                             # s into the walk
//! forward = 0.1                        # m/s (default: the gait's nominal speed)
//! turn_deg_s = 10.0
//! ramp = 0.5                           # s to blend from the previous command
//! [contact]                            # default: the reference contact (k = 2e4, c = 150, Karnopp 0.9/0.8)
//! stiffness = 2e4
//! [record]
//! rrd = true                           # write NAME.rrd (and trajectory = true: NAME.csv) in the batch's output folder
//! [expect]
//! distance_min = 1.0
//! max_tilt_deg = 25
//! max_penetration_mm = 5
//! ```

use crate::contact::{ContactModel, FrictionLaw, NormalLaw};
use crate::terrain::{Orientation, TerrainSpec};
use serde::de::{DeserializeOwned, Error as _};
use serde::{Deserialize, Deserializer, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// What is simulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// The hexapod walks a gait.
    #[default]
    Walk,
    /// A ball is dropped on the terrain (the paper's experiment).
    Ball,
}

/// A file name, or the file's content written inline as a table.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum FileOr<T> {
    File(PathBuf),
    Inline(T),
}

impl<'de, T: DeserializeOwned> Deserialize<'de> for FileOr<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match toml::Value::deserialize(d)? {
            toml::Value::String(path) => Ok(FileOr::File(path.into())),
            table @ toml::Value::Table(_) => table
                .try_into()
                .map(FileOr::Inline)
                .map_err(|e| D::Error::custom(format!("inline table: {}", e.message()))),
            other => Err(D::Error::custom(format!(
                "expected a file name or an inline table, got a {}",
                other.type_str()
            ))),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSpec {
    /// Default: the file's name without `.toml`.
    #[serde(default)]
    pub name: Option<String>,
    #[serde(default)]
    pub description: String,
    #[serde(default)]
    pub kind: Kind,
    /// Default: the natural terrain (walk: terrains/natural.toml; ball: terrains/natural_ball.toml).
    #[serde(default)]
    pub terrain: Option<FileOr<TerrainSpec>>,
    /// Replaces the terrain generator's seed (natural, rough).
    #[serde(default)]
    pub seed: Option<u32>,
    /// Seconds walked after settling (walk) or simulated (ball).
    pub duration: f64,
    /// The time step (s). Default: [`DEFAULT_DT`], or smaller where a walking robot's lightest
    /// servo, the contact spring (impulse joints' feet against walls too) or the landing feet
    /// need it (see `resolve`); one given is
    /// refused past the servo's bound and warned past the others.
    #[serde(default)]
    pub dt: Option<f64>,
    #[serde(default)]
    pub contact: ContactSpec,
    /// Run even when dt is above the contact spring's stability limit (to study the instability).
    #[serde(default)]
    pub allow_unstable_dt: bool,

    // --- walk ---
    /// URDF. Default: robots/hex18.urdf (built in).
    #[serde(default)]
    pub robot: Option<PathBuf>,
    /// Default: gaits/tripod.toml (built in).
    #[serde(default)]
    pub gait: Option<FileOr<crate::gait::GaitSpec>>,
    /// Seconds standing before the gait starts (default [`DEFAULT_SETTLE`]).
    #[serde(default)]
    pub settle: Option<f64>,
    /// Keep the body level by following the terrain under the feet (default false).
    #[serde(default)]
    pub follow_terrain: Option<bool>,
    /// Move each foot's centre target with the rolling of its sphere, so a turning tibia rolls its
    /// foot instead of scrubbing it (default true; see `gait::controller`).
    #[serde(default)]
    pub rolling_feet: Option<bool>,
    /// The reactive gait: feet find the ground by touch, a blocked swing lifts higher, the body
    /// follows the feet that are down (default false; see `gait::reactive`).
    #[serde(default)]
    pub reactive_gait: Option<bool>,
    /// Leg compliance: a leg pressing the ground with more than three times the robot's weight
    /// gives way along the force and yields in its joints, and legs squeezing the ground between
    /// them past two weights all yield (default true; see `gait::compliance`); false: the servos
    /// press their targets to their effort.
    #[serde(default)]
    pub compliant_legs: Option<bool>,
    /// The body's lean on slopes: past a quarter of the gait's support margin the plumb line's
    /// offset is taken back by moving the feet downhill and crouching (default true; see
    /// `gait::lean`); false: the body stands over its feet as on level ground.
    #[serde(default)]
    pub lean_on_slopes: Option<bool>,
    /// Heading hold: the commanded turn corrected by the heading's error, as a robot with a gyro
    /// walks (default false: the gait turns open loop; see `gait::heading`).
    #[serde(default)]
    pub hold_heading: Option<bool>,
    /// End the walk when the robot falls (its body tilted past 45°, the metrics' `fell_at`): the
    /// fall decides a ladder level, as legged_gym's terrain curriculum ends an episode, and what
    /// a robot does tumbling on is no part of it (default false: the walk goes on to its end).
    #[serde(default)]
    pub stop_at_fall: Option<bool>,
    /// How the links are joined: `multibody` (default) or `impulse` (faster; joints drift a little).
    #[serde(default)]
    pub articulation: Option<crate::sim::Articulation>,
    /// rapier substeps per step (default 1).
    #[serde(default)]
    pub solver_iterations: Option<usize>,
    /// Constraint-solver sweeps per substep (default: 1 for the multibody, 5 for impulse joints).
    #[serde(default)]
    pub pgs_iterations: Option<usize>,
    #[serde(default)]
    pub servo: Option<ServoSpec>,
    #[serde(default)]
    pub start: Option<StartSpec>,
    #[serde(default)]
    pub command: Option<Vec<CommandSpec>>,

    // --- ball ---
    #[serde(default)]
    pub ball: Option<BallSpec>,

    #[serde(default)]
    pub record: RecordSpec,
    #[serde(default)]
    pub expect: Expectations,
    /// Per-metric tolerances when comparing with a baseline: `[tolerance.distance] rel = 0.1`.
    #[serde(default)]
    pub tolerance: BTreeMap<String, Tolerance>,
}

/// The defaults of unset fields, in one place (the command line's options take theirs from here).
/// Time step (s).
pub const DEFAULT_DT: f64 = crate::setup::time_step::DEFAULT_DT;

impl ScenarioSpec {
    /// A walk's fields, each with whether it is set: a ball scenario must set none.
    pub fn walk_fields(&self) -> [(&'static str, bool); 16] {
        [
            ("robot", self.robot.is_some()),
            ("gait", self.gait.is_some()),
            ("settle", self.settle.is_some()),
            ("follow_terrain", self.follow_terrain.is_some()),
            ("rolling_feet", self.rolling_feet.is_some()),
            ("reactive_gait", self.reactive_gait.is_some()),
            ("compliant_legs", self.compliant_legs.is_some()),
            ("lean_on_slopes", self.lean_on_slopes.is_some()),
            ("hold_heading", self.hold_heading.is_some()),
            ("stop_at_fall", self.stop_at_fall.is_some()),
            ("articulation", self.articulation.is_some()),
            ("solver_iterations", self.solver_iterations.is_some()),
            ("pgs_iterations", self.pgs_iterations.is_some()),
            ("servo", self.servo.is_some()),
            ("start", self.start.is_some()),
            ("command", self.command.is_some()),
        ]
    }

    /// How a walk of it drives its legs, each switch's default applied.
    pub fn switches(&self) -> crate::runner::walk::WalkSwitches {
        crate::runner::walk::WalkSwitches {
            follow_terrain: self.follow_terrain.unwrap_or(false),
            rolling_feet: self.rolling_feet.unwrap_or(true),
            reactive_gait: self.reactive_gait.unwrap_or(false),
            compliant_legs: self.compliant_legs.unwrap_or(true),
            lean_on_slopes: self.lean_on_slopes.unwrap_or(true),
            hold_heading: self.hold_heading.unwrap_or(false),
            feedforward: self.servo.and_then(|s| s.feedforward).unwrap_or(true),
        }
    }

    /// The time step: as given, else the default (a walk's resolved scenario holds the step it
    /// chose, see `resolve`).
    pub fn dt(&self) -> f64 {
        self.dt.unwrap_or(DEFAULT_DT)
    }
}
/// Seconds a walk stands before the gait starts.
pub const DEFAULT_SETTLE: f64 = 1.0;
/// Seconds walked by `hexsim run` (and a Python `Simulation`) when no duration is given.
pub const RUN_DURATION: f64 = 20.0;
/// Samples per second in a walk's recording and trajectory.
pub const WALK_LOG_RATE: f64 = 50.0;
/// Samples per second in a ball's recording and trajectory (a bounce lasts ~10 ms).
pub const BALL_LOG_RATE: f64 = 100.0;
/// Metres inside the terrain's −x edge where a walk starts unless `start.x` is set.
pub const START_INSET: f64 = 0.75;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum NormalChoice {
    /// The paper's F = k·x + c·ẋ.
    #[default]
    SpringDamper,
    /// F = k·xⁿ·(1 + d·ẋ).
    HuntCrossley,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum FrictionChoice {
    #[default]
    Karnopp,
    Coulomb,
    Viscous,
    Stribeck,
    None,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum OrientationChoice {
    /// The exact normal of the interpolated surface.
    #[default]
    Exact,
    /// The paper's central-difference roll/pitch (eq. 1–4).
    Paper,
}

/// The contact's parameters, each defined once: a scenario's `[contact]` field and, with the same
/// doc, `hexsim run`'s and `hexsim ball`'s option (named after the field, but where the option
/// says more: `--normal-law`, `--hc-exponent`, `--friction-width`, `--contact-model`). Defaults
/// are the reference contact of docs/validation.md; the physics of each is in
/// [`crate::contact::ContactModel`], which [`ContactSpec::model`] builds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSpec {
    /// Normal force law.
    #[arg(long = "normal-law", value_enum, default_value_t = ContactSpec::default().normal)]
    pub normal: NormalChoice,
    /// Normal stiffness k (N/m; for Hunt–Crossley N/mⁿ). Default: the reference 2e4 for a ball;
    /// for a walk, the reference fitted to the robot's weight (hex18's: 2e4).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[arg(long)]
    pub stiffness: Option<f64>,
    /// Normal damping c (N·s/m; for Hunt–Crossley d in s/m). Default: the reference 150 for a
    /// ball; for a walk, the reference fitted to the robot's weight (hex18's: 150).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[arg(long)]
    pub damping: Option<f64>,
    /// Hunt–Crossley exponent n.
    #[arg(long = "hc-exponent", default_value_t = ContactSpec::default().exponent)]
    pub exponent: f64,
    /// Friction law.
    #[arg(long, value_enum, default_value_t = ContactSpec::default().friction)]
    pub friction: FrictionChoice,
    /// Static friction coefficient μs (Karnopp, Stribeck).
    #[arg(long, default_value_t = ContactSpec::default().mu_static)]
    pub mu_static: f64,
    /// Kinetic friction coefficient μk (Karnopp; Coulomb's μ; Stribeck's Coulomb level).
    #[arg(long, default_value_t = ContactSpec::default().mu_kinetic)]
    pub mu_kinetic: f64,
    /// Karnopp stick band Δv (m/s).
    #[arg(long, default_value_t = ContactSpec::default().stick_band)]
    pub stick_band: f64,
    /// Regularisation width of Coulomb and Stribeck (m/s).
    #[arg(long = "friction-width", default_value_t = ContactSpec::default().width)]
    pub width: f64,
    /// Viscous friction coefficient (N·s/m; viscous law, Stribeck's viscous part).
    #[arg(long, default_value_t = ContactSpec::default().viscous)]
    pub viscous: f64,
    /// Stribeck velocity (m/s).
    #[arg(long, default_value_t = ContactSpec::default().stribeck_velocity)]
    pub stribeck_velocity: f64,
    /// How the ground's orientation is found.
    #[arg(long, value_enum, default_value_t = ContactSpec::default().orientation)]
    pub orientation: OrientationChoice,
    /// The paper's half-step XE = YE (m) for its finite-difference angles.
    #[arg(long, default_value_t = ContactSpec::default().paper_step)]
    pub paper_step: f64,
    /// Fraction of a sticking contact's drift that its stick force undoes per step (0: off, each
    /// friction law as its equation; the default halves the creep of a foot under a changing load).
    #[arg(long, default_value_t = ContactSpec::default().drift_recovery)]
    pub drift_recovery: f64,
    /// Rolling resistance ρ (m): a torque of at most ρ·Fn against rolling (0: none; a sphere's
    /// rolling-resistance coefficient is ρ/r).
    #[arg(long, default_value_t = ContactSpec::default().rolling_resistance)]
    pub rolling_resistance: f64,
    /// Spin friction μ_t (m): a torque of at most μ_t·Fn against the spin about the ground's
    /// normal (0: none; MuJoCo's torsional friction, condim 4).
    #[arg(long, default_value_t = ContactSpec::default().spin_friction)]
    pub spin_friction: f64,
    /// Contact model: hexsim's, or the paper's step for step (vertical penetration, its angles
    /// with --paper-step, explicit damper, friction laws unlimited, forces at the sphere's centre).
    #[arg(long = "contact-model", value_enum, default_value_t = ContactSpec::default().variant)]
    pub variant: VariantChoice,
}

/// Which contact model: see `contact::Variant`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum VariantChoice {
    /// hexsim's: closest point along the normal, exact-decay damper, friction limited at the
    /// force that stops the contact, forces at the contact point.
    #[default]
    Hexsim,
    /// The paper's as written: vertical penetration from the height table, its finite-difference
    /// angles, explicit damper, friction laws unlimited, forces at the sphere's centre. Two parts
    /// are hexsim's reading, not the paper's: Karnopp's stick force (cancelling last step's load;
    /// the paper gives no formula) and friction on the ball (the paper assumed no slip and
    /// neglected it).
    Paper,
}

impl Default for ContactSpec {
    fn default() -> Self {
        ContactSpec {
            normal: NormalChoice::SpringDamper,
            stiffness: None,
            damping: None,
            exponent: 1.5,
            friction: FrictionChoice::Karnopp,
            mu_static: 0.9,
            mu_kinetic: 0.8,
            stick_band: 1e-3,
            width: 1e-3,
            viscous: 0.0,
            stribeck_velocity: 0.05,
            orientation: OrientationChoice::Exact,
            paper_step: 0.01,
            drift_recovery: crate::contact::DRIFT_RECOVERY,
            rolling_resistance: 0.0,
            spin_friction: 0.0,
            variant: VariantChoice::Hexsim,
        }
    }
}

impl ContactSpec {
    /// The scenario's key (`contact.KEY`; the flag `--KEY` with dashes) behind a field of
    /// [`Self::model`]'s as [`ContactModel::validate`] names it: the physics' names
    /// (`orientation.xe`, Coulomb's `mu`) are not what the user wrote.
    pub fn key_of(model_field: &str) -> &str {
        match model_field {
            "orientation.xe" | "orientation.ye" => "paper_step",
            "friction.mu" | "friction.mu_coulomb" => "mu_kinetic",
            "friction.coefficient" => "viscous",
            field => field
                .strip_prefix("friction.")
                .or_else(|| field.strip_prefix("normal."))
                .unwrap_or(field),
        }
    }

    /// The contact as given, the reference stiffness and damping where they are left out.
    pub fn model(&self) -> ContactModel {
        use crate::contact::{REFERENCE_DAMPING, REFERENCE_STIFFNESS};
        let stiffness = self.stiffness.unwrap_or(REFERENCE_STIFFNESS);
        let damping = self.damping.unwrap_or(REFERENCE_DAMPING);
        let normal = match self.normal {
            NormalChoice::SpringDamper => NormalLaw::SpringDamper { stiffness, damping },
            NormalChoice::HuntCrossley => NormalLaw::HuntCrossley {
                stiffness,
                exponent: self.exponent,
                damping,
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
                width: self.width,
            },
            FrictionChoice::Viscous => FrictionLaw::Viscous {
                coefficient: self.viscous,
            },
            FrictionChoice::Stribeck => FrictionLaw::Stribeck {
                mu_static: self.mu_static,
                mu_coulomb: self.mu_kinetic,
                viscous: self.viscous,
                stribeck_velocity: self.stribeck_velocity,
                width: self.width,
            },
            FrictionChoice::None => FrictionLaw::None,
        };
        let paper = self.variant == VariantChoice::Paper;
        let orientation = match if paper {
            OrientationChoice::Paper
        } else {
            self.orientation
        } {
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
            drift_recovery: if paper { 0.0 } else { self.drift_recovery },
            rolling_resistance: self.rolling_resistance,
            spin_friction: self.spin_friction,
            variant: if paper {
                crate::contact::Variant::Paper
            } else {
                crate::contact::Variant::Hexsim
            },
        }
    }
}

/// Joint servos: τ = k·(q* − q) − c·q̇, limited to the URDF's effort. What is left out is fitted
/// to the robot (`robot::servo`: the reference's 20 N·m/rad and 0.05 N·m·s/rad on hex18, stiffer
/// for heavier legs); damping given alone keeps the fitted stiffness, stiffness given alone gets
/// the reference's damping time d/k = 2.5 ms.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ServoSpec {
    /// N·m/rad.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// N·m·s/rad.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Move each joint's target on by the torque it holds over the stiffness, so the legs do not
    /// sag under the weight (default true; see `sim::Walker::load_feedforward`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feedforward: Option<bool>,
}

/// Where the body starts; unset x/y: [`START_INSET`] inside the terrain's −x edge, centred in y.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StartSpec {
    pub x: Option<f64>,
    pub y: Option<f64>,
    pub heading_deg: f64,
    /// `level` (default) or `ground`: the body set down parallel to the ground under it.
    pub attitude: crate::sim::Attitude,
}

/// From `at` seconds into the walk, ramp to this command over `ramp` seconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CommandSpec {
    #[serde(default)]
    pub at: f64,
    /// m/s; default: the gait's nominal speed.
    #[serde(default)]
    pub forward: Option<f64>,
    /// m/s, left positive.
    #[serde(default)]
    pub sideways: f64,
    /// deg/s, left positive.
    #[serde(default)]
    pub turn_deg_s: f64,
    #[serde(default = "default_ramp")]
    pub ramp: f64,
}

fn default_ramp() -> f64 {
    0.5
}

/// The ball of a ball scenario (defaults: the reference ball, 0.05 m and 1 kg, dropped 0.5 m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BallSpec {
    pub radius: f64,
    pub mass: f64,
    /// Centre x, y at the start (m).
    pub at: [f64; 2],
    /// Height of the ball's lowest point above the ground below it (m).
    pub drop_height: f64,
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
    pub lock_rotation: bool,
}

impl Default for BallSpec {
    fn default() -> Self {
        BallSpec {
            radius: 0.05,
            mass: 1.0,
            at: [0.3, -0.2],
            drop_height: 0.5,
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            lock_rotation: false,
        }
    }
}

/// What to write besides the results record.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecordSpec {
    /// A rerun recording, NAME.rrd.
    pub rrd: bool,
    /// The trajectory CSV, NAME.csv.
    pub trajectory: bool,
    /// Samples per second (default: walk 50, ball 100).
    pub log_rate: Option<f64>,
}

/// What the run must achieve: `no_divergence` (default true), `no_clamped_ik`,
/// `walk_as_commanded` (default true in `hexsim batch`), and bounds on the
/// metrics, `KEY = limit`, with the keys of the metrics tables (`crate::metrics::walk::TABLE`,
/// `crate::metrics::ball::TABLE`: e.g. `distance_min`, `max_tilt_deg`, `apex_max`). Unset
/// expectations are not checked; keys are checked against the tables when the scenario resolves.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Expectations {
    /// The run must not diverge (non-finite state).
    pub no_divergence: bool,
    /// No leg target out of reach.
    pub no_clamped_ik: bool,
    /// The walk is the one commanded: none of the metrics' `walk_flags` (skated, went
    /// backwards, drifted sideways, turned). Unset in a file, `hexsim batch` sets it for every
    /// walk; `false` accepts a flagged walk.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub walk_as_commanded: Option<bool>,
    /// Each bound's limit, by its key.
    #[serde(flatten)]
    pub bounds: BTreeMap<String, f64>,
}

impl<'de> Deserialize<'de> for Expectations {
    /// By hand, so that a wrong value names its key (`expect.distance_min: expected a number`).
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let table = toml::Table::deserialize(d)?;
        let mut expect = Expectations::default();
        for (key, value) in table {
            match (key.as_str(), value) {
                ("no_divergence", toml::Value::Boolean(b)) => expect.no_divergence = b,
                ("no_clamped_ik", toml::Value::Boolean(b)) => expect.no_clamped_ik = b,
                ("walk_as_commanded", toml::Value::Boolean(b)) => {
                    expect.walk_as_commanded = Some(b)
                }
                ("no_divergence" | "no_clamped_ik" | "walk_as_commanded", other) => {
                    return Err(D::Error::custom(format!(
                        "expect.{key}: expected true or false, got {other}"
                    )));
                }
                (_, toml::Value::Float(v)) => {
                    expect.bounds.insert(key, v);
                }
                (_, toml::Value::Integer(v)) => {
                    expect.bounds.insert(key, v as f64);
                }
                (_, other) => {
                    return Err(D::Error::custom(format!(
                        "expect.{key}: expected a number (the limit), got {other}"
                    )));
                }
            }
        }
        Ok(expect)
    }
}

impl Default for Expectations {
    fn default() -> Self {
        Expectations {
            no_divergence: true,
            no_clamped_ik: false,
            walk_as_commanded: None,
            bounds: BTreeMap::new(),
        }
    }
}

/// How far a metric may move from its baseline: |new − old| ≤ max(rel·|old|, abs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    #[serde(default)]
    pub rel: Option<f64>,
    #[serde(default)]
    pub abs: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The file's defaults are the model's: one reference contact, whichever way it is built.
    #[test]
    fn the_default_contact_is_the_reference_contact() {
        assert_eq!(ContactSpec::default().model(), ContactModel::default());
    }
}
