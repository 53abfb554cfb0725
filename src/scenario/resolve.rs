//! Resolving a scenario: every field checked (the error names it), every file it refers to loaded,
//! every default applied, once — what [`Scenario::run`] gets is fully typed. The scenario's hash
//! covers its fields and the content of every file it uses.

use super::inputs::Inputs;
use super::spec::{
    BALL_LOG_RATE, DEFAULT_DT, DEFAULT_SETTLE, FileOr, Kind, ScenarioSpec, ServoSpec, WALK_LOG_RATE,
};
use super::{Scenario, ScenarioError, Setup, TerrainSource, WalkSetup, builtin};
use crate::contact::{ContactModel, NormalLaw};
use crate::gait::{CommandChange, CommandSchedule, Gait, GaitSpec, VelocityCommand};
use crate::limits::num;
use crate::robot::RobotModel;
use crate::robot::statics::foot_load;
use crate::sim::{
    BallConfig, DEFAULT_SOLVER_ITERATIONS, HexapodSettings, STANDARD_GRAVITY, ServoGains,
};
use crate::terrain::TerrainSpec;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::sync::Arc;

impl Scenario {
    /// Checks the spec and loads what it refers to. `origin` is the scenario's file: relative paths
    /// resolve against its folder, and errors name it.
    pub fn resolve(
        mut spec: ScenarioSpec,
        name: String,
        origin: &Path,
    ) -> Result<Self, ScenarioError> {
        let fail = |message: String| ScenarioError {
            file: origin.to_path_buf(),
            message,
        };
        let base = origin.parent().unwrap_or(Path::new(""));
        check_common(&spec, &name).map_err(fail)?;
        let mut contact = spec.contact.model();
        // hashed with its step, so a default step and the same step given hash alike
        let hashed = ScenarioSpec {
            dt: Some(spec.dt()),
            ..spec.clone()
        };
        let mut inputs = Inputs::default();
        let terrain = resolve_terrain(&spec, &name, origin, &mut inputs).map_err(fail)?;
        let seed = terrain.spec.seed();
        let mut warnings = Vec::new();
        let setup = match spec.kind {
            Kind::Ball => Setup::Ball(resolve_ball(&spec, &contact).map_err(fail)?),
            Kind::Walk => Setup::Walk(Box::new(
                resolve_walk(&spec, &mut contact, base, &mut inputs, &mut warnings)
                    .map_err(fail)?,
            )),
        };
        if let Setup::Walk(w) = &setup {
            // the step the walk chose (smaller than the default for a robot with light legs)
            spec.dt = Some(w.settings.dt);
        }
        let settle = match &setup {
            Setup::Walk(w) => w.settle,
            Setup::Ball(_) => 0.0,
        };
        check_steps(spec.duration, settle, spec.dt()).map_err(fail)?;
        let mut hasher = Sha256::new();
        hasher.update(env!("CARGO_PKG_VERSION"));
        hasher.update(serde_json::to_vec(&hashed).expect("a spec is plain data"));
        inputs.hash_into(&mut hasher);
        let hash = super::inputs::short(&hasher.finalize());
        let log_rate = spec.record.log_rate.unwrap_or(match spec.kind {
            Kind::Walk => WALK_LOG_RATE,
            Kind::Ball => BALL_LOG_RATE,
        });
        Ok(Scenario {
            name,
            file: origin.to_path_buf(),
            hash,
            read: inputs,
            spec,
            seed,
            warnings,
            terrain,
            contact,
            log_rate,
            setup,
        })
    }
}

/// The fields every kind has: name, time step, duration, contact, expectations, tolerances, log
/// rate.
fn check_common(spec: &ScenarioSpec, name: &str) -> Result<(), String> {
    if name.is_empty() || name.contains(['/', '\\']) {
        return Err(format!(
            "name: expected a non-empty name without slashes, got {name:?}"
        ));
    }
    let dt = spec.dt();
    if !(dt.is_finite() && dt > 0.0 && dt <= 0.01) {
        return Err(format!("dt: expected a time step in (0, 0.01] s, got {dt}"));
    }
    if !(spec.duration.is_finite() && spec.duration >= 0.0) {
        return Err(format!(
            "duration: expected a finite number ≥ 0 s, got {}",
            spec.duration
        ));
    }
    if let Err((field, expected)) = spec.contact.model().validate() {
        return Err(format!("contact.{field}: {expected}"));
    }
    if matches!(spec.kind, Kind::Walk) && spec.contact.spin_friction != 0.0 {
        return Err(format!(
            "contact.spin_friction: expected 0 for a walk, got {} (spin friction acts on a ball, \
             `hexsim ball`; a foot's contact is a point force, with no torque about the normal)",
            spec.contact.spin_friction
        ));
    }
    if matches!(spec.kind, Kind::Walk) && spec.contact.rolling_resistance != 0.0 {
        return Err(format!(
            "contact.rolling_resistance: expected 0 for a walk, got {} (rolling resistance acts on \
             a rolling ball, `hexsim ball`; a robot's feet are fixed to its legs and do not roll)",
            spec.contact.rolling_resistance
        ));
    }
    spec.expect.validate(spec.kind)?;
    // a tolerance is of a metric compared with the baseline (one with a noise floor), or default
    let compared: Vec<&str> = match spec.kind {
        Kind::Walk => compared_metrics(crate::metrics::walk::TABLE),
        Kind::Ball => compared_metrics(crate::metrics::ball::TABLE),
    };
    for (field, tolerance) in &spec.tolerance {
        if field != "default" && !compared.contains(&field.as_str()) {
            return Err(format!(
                "tolerance.{field}: unknown field `{field}`, expected `default` or a metric compared with a baseline: {}",
                compared.join(", ")
            ));
        }
        for v in [tolerance.rel, tolerance.abs].into_iter().flatten() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("tolerance.{field}: expected numbers ≥ 0, got {v}"));
            }
        }
    }
    if let Some(rate) = spec.record.log_rate
        && !(rate.is_finite() && rate > 0.0)
    {
        return Err(format!(
            "record.log_rate: expected a rate > 0 per second, got {rate}"
        ));
    }
    Ok(())
}

/// The names of the metrics a baseline compares (those with a noise floor).
fn compared_metrics<M>(table: &[crate::metrics::Metric<M>]) -> Vec<&'static str> {
    table
        .iter()
        .filter(|m| m.noise.is_some())
        .map(|m| m.name)
        .collect()
}

/// Refuses a run of more than [`crate::limits::MAX_STEPS`] steps, with its count and an estimate
/// of its time.
fn check_steps(duration: f64, settle: f64, dt: f64) -> Result<(), String> {
    let steps = (duration + settle) / dt;
    if steps <= crate::limits::MAX_STEPS {
        return Ok(());
    }
    // a hex18 walk runs some 20,000 steps a second on one core
    let seconds = steps / 2e4;
    let time = match seconds {
        s if s < 3600.0 * 48.0 => format!("{:.0} hours", s / 3600.0),
        s if s < 3.156e7 * 2.0 => format!("{:.0} days", s / 86400.0),
        s => format!("{} years", num((s / 3.156e7).round())),
    };
    let settled = if settle > 0.0 {
        format!(" and settle = {} s", num(settle))
    } else {
        String::new()
    };
    Err(format!(
        "duration: {} s{settled} at dt = {} s is {} steps (about {time} at \
         20,000 steps/s), more than the {} steps hexsim runs; shorten the duration or the \
         settle, or enlarge dt",
        num(duration),
        num(dt),
        num(steps),
        num(crate::limits::MAX_STEPS)
    ))
}

/// The terrain: the built-in natural terrain of the kind's scale, a file, or an inline table;
/// with the scenario's seed.
fn resolve_terrain(
    spec: &ScenarioSpec,
    name: &str,
    origin: &Path,
    inputs: &mut Inputs,
) -> Result<TerrainSource, String> {
    let default_terrain = match spec.kind {
        Kind::Walk => builtin::NATURAL,
        Kind::Ball => builtin::NATURAL_BALL,
    };
    let mut terrain = match &spec.terrain {
        None => {
            inputs.builtin("terrain file", default_terrain.path, default_terrain.text);
            TerrainSource {
                spec: TerrainSpec::from_toml(default_terrain.text, Path::new(default_terrain.path))
                    .map_err(|e| e.to_string())?,
                origin: PathBuf::from(default_terrain.path),
                name: format!("{} (built in)", default_terrain.path),
            }
        }
        Some(FileOr::File(file)) => {
            let path = origin.parent().unwrap_or(Path::new("")).join(file);
            match builtin::named(builtin::TERRAINS, file, &path) {
                Some(b) => {
                    inputs.builtin("terrain file", b.path, b.text);
                    TerrainSource {
                        spec: TerrainSpec::from_toml(b.text, Path::new(b.path))
                            .map_err(|e| e.to_string())?,
                        origin: PathBuf::from(b.path),
                        name: format!("{} (built in)", b.path),
                    }
                }
                None => TerrainSource {
                    spec: TerrainSpec::from_file(&path).map_err(|e| {
                        not_found_hint(e.to_string(), &path, "terrains", builtin::TERRAINS)
                    })?,
                    name: file.display().to_string(),
                    origin: path,
                },
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
    if matches!(spec.terrain, Some(FileOr::File(_))) && !terrain.name.ends_with("(built in)") {
        inputs.file(
            "terrain file",
            &terrain.origin,
            crate::limits::TEXT_FILE_BYTES,
        )?;
    }
    let data_base = terrain.origin.parent().unwrap_or(Path::new(""));
    if let Some(path) = terrain.spec.source.get().data_file() {
        inputs.file(
            "terrain's height file",
            &data_base.join(path),
            crate::limits::DATA_FILE_BYTES,
        )?;
    }
    Ok(terrain)
}

/// A walk's fields that a ball scenario must not set.
fn walk_fields(spec: &ScenarioSpec) -> [(&'static str, bool); 12] {
    [
        ("robot", spec.robot.is_some()),
        ("gait", spec.gait.is_some()),
        ("settle", spec.settle.is_some()),
        ("follow_terrain", spec.follow_terrain.is_some()),
        ("rolling_feet", spec.rolling_feet.is_some()),
        ("reactive_gait", spec.reactive_gait.is_some()),
        ("articulation", spec.articulation.is_some()),
        ("solver_iterations", spec.solver_iterations.is_some()),
        ("pgs_iterations", spec.pgs_iterations.is_some()),
        ("servo", spec.servo.is_some()),
        ("start", spec.start.is_some()),
        ("command", spec.command.is_some()),
    ]
}

/// The explicit contact spring's stability: dt below 2/√(k/m) for the lightest `mass` it acts on.
fn check_stable_dt(
    spec: &ScenarioSpec,
    contact: &ContactModel,
    mass: f64,
    radius: f64,
    what: &str,
) -> Result<(), String> {
    let limit = contact.normal.stable_time_step(mass, radius * 0.1);
    if spec.dt() >= limit && !spec.allow_unstable_dt {
        return Err(format!(
            "dt = {} s is too large for the contact spring on {what}: the explicit spring needs dt < {} s (2/√(k/m)); reduce dt or the stiffness (or set allow_unstable_dt = true to run it anyway)",
            spec.dt(),
            rounded_down(limit)
        ));
    }
    if let Some(limit) = explicit_damper_step(contact, mass)
        && spec.dt() >= limit
        && !spec.allow_unstable_dt
    {
        return Err(format!(
            "dt = {} s is too large for the paper variant's explicit damper on {what}: it needs c·dt/m < 2, dt < {} s; reduce dt or the damping, or use hexsim's contact, whose damper is exact over a step (or set allow_unstable_dt = true to run it anyway)",
            spec.dt(),
            rounded_down(limit)
        ));
    }
    Ok(())
}

/// The paper variant's damper is explicit, F = c·ẋ at the step's start: each step multiplies the
/// normal speed by 1 − c·dt/m, stable only while c·dt/m < 2 (hexsim's is exact over the step and
/// has no such bound). The largest stable step on a body of `mass`, for the paper variant.
fn explicit_damper_step(contact: &ContactModel, mass: f64) -> Option<f64> {
    if contact.variant != crate::contact::Variant::Paper {
        return None;
    }
    let c = match contact.normal {
        NormalLaw::SpringDamper { damping, .. } => damping,
        // k·xⁿ·d: its damping coefficient grows with the load; at the static sink it is Fn·d
        NormalLaw::HuntCrossley { .. } => return None,
    };
    (c > 0.0).then(|| 2.0 * mass / c)
}

/// A ball scenario's ball, its lowest point `drop_height` above the ground (the ground's height is
/// added when the terrain is built).
fn resolve_ball(spec: &ScenarioSpec, contact: &ContactModel) -> Result<BallConfig, String> {
    if let Some((field, _)) = walk_fields(spec).iter().find(|(_, set)| *set) {
        return Err(format!(
            "{field}: applies to walk scenarios, but kind = \"ball\""
        ));
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
        return Err(format!("ball.{field}: {expected}"));
    }
    check_ball_scale(&b)?;
    check_stable_dt(
        spec,
        contact,
        b.mass,
        b.radius,
        &format!("a {} kg ball", b.mass),
    )?;
    Ok(config)
}

/// The ball's numbers held to a physical scale, as the robot's start is: a ball of 10³⁰⁸ kg, at
/// 10⁶ m, or thrown at 10³⁰⁰ m/s is a typo, and would run as nonsense rather than fail.
fn check_ball_scale(b: &super::spec::BallSpec) -> Result<(), String> {
    // the length, scaled so that 1e300 does not overflow to inf
    let speed = |v: [f64; 3]| {
        let most = v.iter().fold(0.0f64, |m, c| m.max(c.abs()));
        if most == 0.0 {
            0.0
        } else {
            most * v.iter().map(|c| (c / most).powi(2)).sum::<f64>().sqrt()
        }
    };
    let far = crate::terrain::FARTHEST;
    let checks: [(&str, f64, f64, &str); 6] = [
        ("radius", b.radius, 10.0, "m"),
        ("mass", b.mass, 1e6, "kg"),
        (
            "drop_height",
            b.drop_height.abs(),
            1000.0,
            "m (|drop_height|)",
        ),
        ("velocity", speed(b.velocity), 1000.0, "m/s (its length)"),
        (
            "angular_velocity",
            speed(b.angular_velocity),
            1e4,
            "rad/s (its length)",
        ),
        (
            "at",
            b.at[0].abs().max(b.at[1].abs()),
            far,
            "m from the origin",
        ),
    ];
    for (field, value, most, unit) in checks {
        if value > most {
            let why = if field == "at" {
                ", where the physics' f32 positions resolve too coarsely for the contact; place the terrain and the ball near the origin"
            } else {
                ""
            };
            return Err(format!(
                "ball.{field}: expected at most {} {unit}, got {}{why}",
                num(most),
                num(value)
            ));
        }
    }
    Ok(())
}

/// A walk's robot, gait, commands and settings.
fn resolve_walk(
    spec: &ScenarioSpec,
    contact: &mut ContactModel,
    base: &Path,
    inputs: &mut Inputs,
    warnings: &mut Vec<String>,
) -> Result<WalkSetup, String> {
    if spec.ball.is_some() {
        return Err("ball: applies to ball scenarios; set kind = \"ball\"".into());
    }
    let robot = resolve_robot(spec, base, inputs)?;
    let (gait, gait_name) = resolve_gait(spec, base, inputs)?;
    let support = crate::gait::minimum_support(&gait.offsets(), gait.duty_factor);
    // a robot that does not fit may say why in its warnings (masses in grams): name them too
    let gait = crate::gait::fit(&robot, &gait).map_err(|e| {
        let noted: String = robot
            .warnings
            .iter()
            .map(|w| format!("\n  and the robot warns: {w}"))
            .collect();
        format!("{gait_name}: {e}{noted}")
    })?;
    if support < 3 {
        warnings.push(format!(
            "{gait_name}: at times only {support} feet are on the ground (a hexapod needs 3 to stand statically); check its duty_factor and phase_offsets"
        ));
    }
    warnings.extend(robot.warnings.iter().cloned());
    let ground = fit_ground(&spec.contact, contact, &robot, support)?;
    // the lightest foot link bounds the effective mass the contact spring acts on
    let (foot, foot_mass) = robot
        .legs
        .iter()
        .map(|leg| {
            let link = &robot.links[leg.foot_link];
            (link.name.clone(), link.mass)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .ok_or("the robot has no legs")?;
    let what = format!(
        "the lightest foot link (`{foot}`, {} kg)",
        four_digits(foot_mass)
    );
    if spec.dt.is_some() {
        check_stable_dt(spec, contact, foot_mass, robot.legs[0].foot.radius, &what)?;
    }
    let mut contact_step = ContactStep {
        limit: CONTACT_STEP_LIMIT / (contact.normal.stiffness() / foot_mass).sqrt(),
        what: format!(
            "the contact spring (k = {} N/m{}) on {what} needs √(k/m)·dt ≤ {CONTACT_STEP_LIMIT}",
            num(contact.normal.stiffness()),
            if spec.contact.stiffness.is_some() {
                String::new()
            } else {
                format!(", fitted to the robot's {} kg", num(robot.total_mass()))
            }
        ),
    };
    if let Some(damper) = explicit_damper_step(contact, foot_mass)
        && 0.5 * damper < contact_step.limit
    {
        contact_step = ContactStep {
            limit: 0.5 * damper,
            what: format!(
                "the paper variant's explicit damper on {what} needs c·dt/m ≤ 1 (half its bound)"
            ),
        };
    }
    if let Some(touchdown) = touchdown_step(&gait.gait, contact, &robot, support)
        && touchdown.limit < contact_step.limit
    {
        contact_step = touchdown;
    }
    let settle = spec.settle.unwrap_or(DEFAULT_SETTLE);
    if !(settle.is_finite() && settle >= 0.0) {
        return Err(format!(
            "settle: expected a finite number ≥ 0 s, got {settle}"
        ));
    }
    let most = crate::limits::MAX_ITERATIONS;
    for (field, value) in [
        ("solver_iterations", spec.solver_iterations),
        ("pgs_iterations", spec.pgs_iterations),
    ] {
        if let Some(n) = value
            && !(1..=most).contains(&n)
        {
            return Err(format!(
                "{field}: expected 1 to {most} iterations a step, got {n}"
            ));
        }
    }
    let load = foot_load(&robot, STANDARD_GRAVITY, support);
    let gains = resolve_servo(
        spec.servo.unwrap_or_default(),
        &robot,
        &gait.standing_pose,
        load,
        gait.gait.step_height,
    )?;
    let dt = walk_time_step(
        spec,
        &robot,
        &gait.standing_pose,
        gains,
        contact_step,
        warnings,
    )?;
    let commands = resolve_commands(spec, &gait.gait)?;
    if let Some(start) = spec.start
        && ![start.x, start.y, Some(start.heading_deg)]
            .into_iter()
            .flatten()
            .all(f64::is_finite)
    {
        return Err("start: expected finite numbers".into());
    }
    if let Some(start) = spec.start
        && let Some(far) = [start.x, start.y]
            .into_iter()
            .flatten()
            .find(|v| v.abs() > crate::terrain::FARTHEST)
    {
        return Err(format!(
            "start: {far} m is farther than {} m from the origin, where the physics' f32 positions resolve too coarsely for the contact; place the terrain and the start near the origin",
            crate::terrain::FARTHEST
        ));
    }
    Ok(WalkSetup {
        robot: Arc::new(robot),
        gait,
        commands,
        settings: HexapodSettings {
            articulation: spec.articulation.unwrap_or_default(),
            dt,
            solver_iterations: spec.solver_iterations.unwrap_or(DEFAULT_SOLVER_ITERATIONS),
            pgs_iterations: spec.pgs_iterations,
            gains,
        },
        settle,
        follow_terrain: spec.follow_terrain.unwrap_or(false),
        rolling_feet: spec.rolling_feet.unwrap_or(true),
        reactive_gait: spec.reactive_gait.unwrap_or(false),
        feedforward: spec.servo.and_then(|s| s.feedforward).unwrap_or(true),
        start: spec.start.unwrap_or_default(),
        ground,
    })
}

/// A walk's ground. The reference contact (k = 2·10⁴ N/m, c = 150 N·s/m) was set for hex18: on
/// a robot 30 times as heavy the same spring lets the feet sink past their radius. So where the
/// scenario leaves the stiffness or damping out, it is the reference's scaled to the robot's mass
/// against hex18's ([`crate::contact::NormalLaw::scaled`]): the feet sink as hex18's do on the
/// reference contact, with the same damping ratio (hex18 gets the reference exactly). A stiffness
/// given that lets the feet sink past their radius standing on the gait's fewest feet is refused,
/// naming the stiffness that would hold them.
fn fit_ground(
    given: &super::spec::ContactSpec,
    contact: &mut ContactModel,
    robot: &RobotModel,
    support: usize,
) -> Result<crate::metrics::GroundMetrics, String> {
    let ratio = robot.total_mass() / hex18_mass();
    let fitted = contact.normal.scaled(ratio);
    let mut normal = contact.normal;
    let origin = |given: bool| if given { "given" } else { "fitted" }.to_string();
    if given.stiffness.is_none() || given.damping.is_none() {
        normal = match (normal, fitted) {
            (
                NormalLaw::SpringDamper { stiffness, damping },
                NormalLaw::SpringDamper {
                    stiffness: k,
                    damping: c,
                },
            ) => NormalLaw::SpringDamper {
                stiffness: if given.stiffness.is_some() {
                    stiffness
                } else {
                    k
                },
                damping: if given.damping.is_some() { damping } else { c },
            },
            (
                NormalLaw::HuntCrossley {
                    stiffness,
                    exponent,
                    damping,
                },
                NormalLaw::HuntCrossley {
                    stiffness: k,
                    damping: d,
                    ..
                },
            ) => NormalLaw::HuntCrossley {
                stiffness: if given.stiffness.is_some() {
                    stiffness
                } else {
                    k
                },
                exponent,
                damping: if given.damping.is_some() { damping } else { d },
            },
            (normal, _) => normal,
        };
    }
    if given.stiffness.is_some() && support > 0 {
        let load = foot_load(robot, STANDARD_GRAVITY, support);
        let radius = robot
            .legs
            .iter()
            .map(|leg| leg.foot.radius)
            .fold(f64::INFINITY, f64::min);
        let sink = normal.static_sink(load);
        if sink >= radius {
            return Err(format!(
                "contact.stiffness: {} lets the feet sink {:.1} mm standing on the gait's fewest {support} feet ({load:.1} N each), past their {:.1} mm radius; a stiffness of at least {:.3e} holds them (left out, the contact is fitted to this robot: {:.3e})",
                normal.stiffness(),
                sink * 1e3,
                radius * 1e3,
                normal.stiffness_for(load, radius),
                fitted.stiffness()
            ));
        }
    }
    contact.normal = normal;
    Ok(crate::metrics::GroundMetrics {
        stiffness: normal.stiffness(),
        damping: normal.damping(),
        origins: [
            ("stiffness".to_string(), origin(given.stiffness.is_some())),
            ("damping".to_string(), origin(given.damping.is_some())),
        ]
        .into_iter()
        .collect(),
        mass_ratio: ratio,
    })
}

/// hex18's mass (kg), against which a robot's ground is scaled.
fn hex18_mass() -> f64 {
    static MASS: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *MASS.get_or_init(|| builtin::hex18().total_mass())
}

/// The largest ω·dt of the contact spring on the lightest foot link, ω = √(k/m), for a step
/// hexsim chooses: half the explicit spring's stability bound of 2 (hex18 at 1 ms: 0.63).
pub const CONTACT_STEP_LIMIT: f64 = 1.0;

/// The largest step the contact spring allows ([`CONTACT_STEP_LIMIT`]), and on what.
struct ContactStep {
    limit: f64,
    what: String,
}

/// A step bound for a message, to three significant digits and rounded down: a dt copied from
/// it is allowed, below a strict bound too (4.996e-4 printed as 5.00e-4 refused the 5e-4 a user
/// then tried).
fn rounded_down(limit: f64) -> String {
    let digits = |x: f64| {
        let unit = 10f64.powf(x.log10().floor() - 2.0);
        (x / unit).floor() * unit
    };
    let mut shown = digits(limit);
    if shown >= limit {
        // a bound of exactly 1.00e-3 shows as 9.99e-4
        shown = digits(limit * (1.0 - 1e-9));
    }
    format!("{shown:.2e}")
}

/// `x` with `decimals` decimals where that shows it (0.76), else as short as it reads (1.9e8,
/// 8.2e-297): a number in a message that may be out of scale.
fn fixed(x: f64, decimals: usize) -> String {
    let shown = 10f64.powi(-(decimals as i32));
    if x == 0.0 || (shown..1e6).contains(&x.abs()) {
        format!("{x:.decimals$}")
    } else {
        num(x)
    }
}

/// `x` to four decimals, as short as they allow (20, 61.8926): a fitted value in a message.
fn four_digits(x: f64) -> f64 {
    (x * 1e4).round() / 1e4
}

/// The most a foot's load may rise in one step as it lands, as a share of its standing load
/// (the robot's weight over the gait's fewest feet). A foot landing at speed v presses the
/// ground spring v·dt deeper each step, so its load rises by k·v·dt — v·dt/δ of the standing
/// load, δ the static sink — while the friction holding it is bounded by the load a step
/// before: the faster the load rises per step, the more a landing foot slides. hex18's tripod
/// lands at 0.19 m/s on a 0.41 mm sink: 0.46 at 1 ms. Measured on a 79 kg hexapod with 1 m legs
/// (tests/data/third_party/worms: 0.76 m/s, 1.85 at 1 ms), its worst foot's slide over 10 s on
/// flat ground: 0.124 m at 1 ms, 0.092 m at 0.5 ms (0.93) and at 0.25 ms (0.46), so converged
/// once the share is about hex18's.
pub const TOUCHDOWN_STEP_LIMIT: f64 = 0.5;

/// The largest step [`TOUCHDOWN_STEP_LIMIT`] allows the gait's landing feet, if it binds at all
/// (a cycloid swing lands at no speed).
fn touchdown_step(
    gait: &Gait,
    contact: &ContactModel,
    robot: &RobotModel,
    support: usize,
) -> Option<ContactStep> {
    let speed = gait.touchdown_speed();
    let standing = foot_load(robot, STANDARD_GRAVITY, support);
    let sink = contact.normal.static_sink(standing);
    if !(speed > 0.0 && sink > 0.0) {
        return None;
    }
    Some(ContactStep {
        limit: TOUCHDOWN_STEP_LIMIT * sink / speed,
        what: format!(
            "the feet land at {} m/s (the gait's {} swing, {} m high, period {} s, duty factor \
             {}), so their load must rise by at most {TOUCHDOWN_STEP_LIMIT} of its standing \
             share ({standing:.1} N, a {} mm sink) a step: v·dt ≤ {TOUCHDOWN_STEP_LIMIT}·δ",
            fixed(speed, 2),
            format!("{:?}", gait.swing).to_lowercase(),
            fixed(gait.step_height, 3),
            num(gait.period),
            gait.duty_factor,
            fixed(sink * 1e3, 2)
        ),
    })
}

/// The largest ω·dt a servo tolerates, ω = √(k/I) on the lightest joint (I: the inertia of the
/// links outboard of it about its axis). Above it the knee's fast mode and the step-explicit
/// contact force feed each other: the stance feet's load alternates step to step and they slide.
/// Measured on Kraby (tibia I = 1.85e-5 kg·m², k = 20 N·m/rad, ω = 1040 rad/s): at ω·dt = 1.04
/// (1 ms) each foot slides 0.6–0.95 m over an 8 s walk on flat ground, at 0.52 (0.5 ms) still
/// 0.7–1.3 m, at 0.42 (0.4 ms) 0.02–0.06 m like the other robots; hex18's is 0.28, the other
/// third-party robots' 0.20–0.37. With the load feed-forward (`sim::Walker::load_feedforward`)
/// the legs stand straighter and the mode is less damped: on the natural terrain Kraby's front
/// foot chattered (its load alternating 9 N / 0 step to step) and slid 0.205 m at 0.35 (0.333
/// ms), 0.097 m at 0.31 (0.3 ms), 0.042 m at 0.26 (0.25 ms) and 0.039 m at 0.21 (0.2 ms).
pub const SERVO_STEP_LIMIT: f64 = 0.3;

/// The largest (k·dt + d)·dt / I of the impulse joints' servo, whose torque is explicit in the
/// step, τ = k·(q* − q) − (k·dt + d)·q̇ (`sim::articulation`): each step multiplies the joint's
/// speed by about 1 − that, which must stay well above 0 or the joint rings. hex18's is 0.27 at
/// 1 ms. Measured on Kraby with impulse joints, per foot over a 4 s walk on flat ground: at 0.333
/// ms (1.02) 0.42–0.54 m of slide, at 0.2 ms (0.58) 0.14–0.20 m, at 0.15 ms (0.43) 0.08–0.11 m.
pub const EXPLICIT_SERVO_LIMIT: f64 = 0.5;

/// The time step of a walk: as given — refused when the lightest joint's servo is too fast for
/// it ([`SERVO_STEP_LIMIT`], and [`EXPLICIT_SERVO_LIMIT`] for impulse joints), and warned when
/// it is larger than the contact spring or the landing feet allow ([`CONTACT_STEP_LIMIT`],
/// [`TOUCHDOWN_STEP_LIMIT`]), naming the bound and the step hexsim would choose — else the
/// default, or 1 ms / n with the least n all of them allow (said in a warning).
fn walk_time_step(
    spec: &ScenarioSpec,
    robot: &RobotModel,
    pose: &[f64],
    gains: ServoGains,
    contact: ContactStep,
    warnings: &mut Vec<String>,
) -> Result<f64, String> {
    let inertias = crate::robot::servo::outboard_inertias(robot, pose);
    let Some((joint, inertia)) = robot
        .legs
        .iter()
        .flat_map(|leg| leg.joints.iter().map(|&j| (j, inertias[j])))
        .filter(|(_, i)| *i > 0.0)
        .min_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return Ok(spec.dt());
    };
    let (k, d) = (gains.stiffness, gains.damping);
    let fitted = if spec.servo.and_then(|s| s.stiffness).is_some() {
        ""
    } else {
        ", fitted to the robot's weight and the gait's step height"
    };
    let omega = (k / inertia).sqrt();
    let name = &robot.joints[joint].name;
    let mut limit = SERVO_STEP_LIMIT / omega;
    let mut why = format!(
        "the servo on `{name}` ({inertia:.2e} kg·m² outboard, {} N·m/rad{fitted}: ω = {} rad/s) \
         needs ω·dt ≤ {SERVO_STEP_LIMIT}",
        num(k),
        num(omega.round())
    );
    if spec.articulation.unwrap_or_default() == crate::sim::Articulation::Impulse {
        // the root of k·dt² + d·dt = limit·I
        let explicit = (-d + (d * d + 4.0 * k * EXPLICIT_SERVO_LIMIT * inertia).sqrt()) / (2.0 * k);
        if explicit < limit {
            limit = explicit;
            why = format!(
                "the impulse joints' explicit servo on `{name}` ({inertia:.2e} kg·m² outboard, \
                 {} N·m/rad, {} N·m·s/rad) needs (k·dt + d)·dt/I ≤ {EXPLICIT_SERVO_LIMIT} \
                 (the multibody articulation's implicit servo allows a larger step)",
                num(k),
                num(d)
            );
        }
    }
    let (servo_limit, servo_why) = (limit, why.clone());
    if contact.limit < limit {
        limit = contact.limit;
        why = contact.what;
    }
    if spec.dt.is_none() && (limit.is_nan() || limit < crate::limits::MIN_CHOSEN_DT) {
        return Err(format!(
            "dt: the step hexsim would choose is {} s, below the {} s it accepts: {why}; a \
             number behind it is out of scale (the robot's masses and inertias, the gait's \
             period, duty factor and step height, the contact's or servo's stiffness)",
            num(limit),
            num(crate::limits::MIN_CHOSEN_DT)
        ));
    }
    // the step hexsim chooses: the default, or 1 ms / n with the least n the bounds allow
    let chosen = DEFAULT_DT / (DEFAULT_DT / limit).ceil().max(1.0);
    match spec.dt {
        Some(dt) if dt > servo_limit && !spec.allow_unstable_dt => Err(format!(
            "dt = {dt} s is too large: {servo_why}, dt ≤ {} s; reduce dt or the \
             servo stiffness (or set allow_unstable_dt = true to run it anyway)",
            rounded_down(servo_limit)
        )),
        Some(dt) => {
            // a step the user gives is held to the bounds hexsim chooses its own by: past them
            // the walk runs, but its figures are not converged (the 79 kg WORMS on
            // natural_long, 3 s: its worst foot slides 7.4 mm at 1 ms, 2.7 mm at 0.25 ms)
            if dt > limit {
                warnings.push(format!(
                    "dt = {dt} s is larger than hexsim would choose ({:.3} ms): {why}, \
                     dt ≤ {} s; the walk runs at the step given (leave dt out for hexsim's)",
                    chosen * 1e3,
                    rounded_down(limit)
                ));
            }
            Ok(dt)
        }
        None if chosen < DEFAULT_DT => {
            warnings.push(format!(
                "dt: {:.3} ms, not the default 1 ms: {why} (set dt to choose another)",
                chosen * 1e3
            ));
            Ok(chosen)
        }
        None => Ok(DEFAULT_DT),
    }
}

/// The servo gains: as given, else fitted to the robot standing in `pose` (the gait's), each
/// foot carrying `load` (N) and lifted `step_height` (m).
fn resolve_servo(
    servo: ServoSpec,
    robot: &RobotModel,
    pose: &[f64],
    load: f64,
    step_height: f64,
) -> Result<ServoGains, String> {
    use crate::robot::servo::{REFERENCE_DAMPING, REFERENCE_STIFFNESS, fitted_gains};
    let fitted = || {
        let (k, d, _) = fitted_gains(robot, pose, load, step_height);
        (k, d)
    };
    let (stiffness, damping) = match (servo.stiffness, servo.damping) {
        (Some(k), Some(d)) => (k, d),
        (Some(k), None) => (k, k * REFERENCE_DAMPING / REFERENCE_STIFFNESS),
        (None, Some(d)) => (fitted().0, d),
        (None, None) => fitted(),
    };
    if !(stiffness.is_finite() && stiffness > 0.0 && damping.is_finite() && damping >= 0.0) {
        return Err(format!(
            "servo: expected stiffness > 0 and damping ≥ 0, got {stiffness} and {damping}"
        ));
    }
    Ok(ServoGains { stiffness, damping })
}

/// The robot: hex18 built in, or a URDF (and its robot file beside it).
fn resolve_robot(
    spec: &ScenarioSpec,
    base: &Path,
    inputs: &mut Inputs,
) -> Result<RobotModel, String> {
    // `robot = "hex18"` (or `--robot hex18`) from a folder without such a file: the built-in one
    let file = spec.robot.as_ref().filter(|file| {
        builtin::named(&[("hex18", builtin::HEX18)], file, &base.join(file)).is_none()
    });
    match file {
        None => {
            inputs.builtin("robot", builtin::HEX18.path, builtin::HEX18.text);
            inputs.builtin(
                "robot file",
                builtin::HEX18_FILE.path,
                builtin::HEX18_FILE.text,
            );
            crate::robot::urdf::from_str_with(
                builtin::HEX18.text,
                Some(builtin::HEX18_FILE.text),
                Path::new(builtin::HEX18.path),
            )
        }
        Some(file) => {
            let path = base.join(file);
            inputs.robot(&path).map_err(|e| format!("robot: {e}"))?;
            crate::robot::load(&path)
        }
    }
    .map_err(|e| format!("robot: {e}"))
}

/// `message` for a file that could not be read, with the built-in names of its kind when the
/// file does not exist (a name mistyped, or a repository's file named from elsewhere).
fn not_found_hint(
    message: String,
    path: &Path,
    kind: &str,
    list: &[(&str, builtin::Builtin)],
) -> String {
    if path.exists() {
        message
    } else {
        format!(
            "{message} (built-in {kind}, by name: {})",
            builtin::names(list)
        )
    }
}

/// The gait (the built-in tripod, a file, or an inline table) and its name for messages.
fn resolve_gait(
    spec: &ScenarioSpec,
    base: &Path,
    inputs: &mut Inputs,
) -> Result<(GaitSpec, String), String> {
    let built_in = |inputs: &mut Inputs, b: &builtin::Builtin| {
        inputs.builtin("gait file", b.path, b.text);
        Ok::<_, String>((
            GaitSpec::from_toml(b.text, Path::new(b.path)).map_err(|e| e.to_string())?,
            format!("gait {} (built in)", b.path),
        ))
    };
    Ok(match &spec.gait {
        None => built_in(inputs, &builtin::TRIPOD)?,
        Some(FileOr::File(file)) => match builtin::named(builtin::GAITS, file, &base.join(file)) {
            Some(b) => built_in(inputs, &b)?,
            None => {
                let path = base.join(file);
                let gait = GaitSpec::from_file(&path).map_err(|e| {
                    not_found_hint(format!("gait: {e}"), &path, "gaits", builtin::GAITS)
                })?;
                // digested once read: the loader says what is wrong with a file it cannot use
                inputs.file("gait file", &path, crate::limits::TEXT_FILE_BYTES)?;
                (gait, format!("gait {}", path.display()))
            }
        },
        Some(FileOr::Inline(gait)) => {
            gait.validate().map_err(|e| format!("gait: {e}"))?;
            (gait.clone(), "gait (inline)".to_string())
        }
    })
}

/// The velocity commands over the walk: the gait's nominal speed straight ahead unless given.
fn resolve_commands(spec: &ScenarioSpec, gait: &Gait) -> Result<CommandSchedule, String> {
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
    CommandSchedule::new(changes)
}
