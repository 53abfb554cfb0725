//! Resolving a scenario: every field checked (the error names it), every file it refers to loaded,
//! every default applied, once — what [`Scenario::run`] gets is fully typed. The scenario's hash
//! covers its fields and the content of every file it uses.

use super::inputs::Inputs;
use super::spec::{BALL_LOG_RATE, DEFAULT_SETTLE, FileOr, Kind, ScenarioSpec, WALK_LOG_RATE};
use super::{Scenario, ScenarioError, Setup, TerrainSource, WalkSetup, builtin};
use crate::contact::ContactModel;
use crate::gait::{CommandChange, CommandSchedule, Gait, GaitSpec, VelocityCommand};
use crate::limits::{Range, check_number, num};
use crate::robot::RobotModel;
use crate::setup::{ground, time_step};
use crate::sim::{BallConfig, DEFAULT_SOLVER_ITERATIONS, HexapodSettings, STANDARD_GRAVITY};
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
        let (mut warnings, mut notes) = (Vec::new(), Vec::new());
        let setup = match spec.kind {
            Kind::Ball => Setup::Ball(resolve_ball(&spec, &contact).map_err(fail)?),
            Kind::Walk => {
                let walls = impulse_against_walls(&spec, &terrain).map_err(fail)?;
                Setup::Walk(Box::new(
                    resolve_walk(
                        &spec,
                        &mut contact,
                        base,
                        walls,
                        &mut inputs,
                        (&mut warnings, &mut notes),
                    )
                    .map_err(fail)?,
                ))
            }
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
            notes,
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
    check_number(spec.duration, Range::NonNegative, "s").map_err(|e| format!("duration: {e}"))?;
    if spec.duration < dt {
        // a run of no step has no metric to judge: its zeros would pass any upper bound
        return Err(format!(
            "duration: expected at least one time step (dt = {} s), got {} s",
            num(dt),
            num(spec.duration)
        ));
    }
    if let Err((field, expected)) = spec.contact.model().validate() {
        let key = super::spec::ContactSpec::key_of(&field);
        return Err(format!("contact.{key}: {expected}"));
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
                        builtin::not_found_hint(e.to_string(), &path, "terrains", builtin::TERRAINS)
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

/// A ball scenario's ball, its lowest point `drop_height` above the ground (the ground's height is
/// added when the terrain is built).
fn resolve_ball(spec: &ScenarioSpec, contact: &ContactModel) -> Result<BallConfig, String> {
    if let Some((field, _)) = spec.walk_fields().iter().find(|(_, set)| *set) {
        return Err(format!(
            "{field}: applies to walk scenarios, but kind = \"ball\""
        ));
    }
    let b = spec.ball.unwrap_or_default();
    if b.drop_height < 0.0 {
        // a ball started inside the ground is thrown out by the compressed spring: not a drop
        return Err(format!(
            "ball.drop_height: expected ≥ 0 m (its lowest point above the ground: 0 starts it \
             resting on it), got {}; the ball would start {} mm inside the ground",
            num(b.drop_height),
            num((-b.drop_height * 1e4).round() / 10.0)
        ));
    }
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
    let requested = time_step::Requested {
        dt: Some(spec.dt()),
        allow_unstable: spec.allow_unstable_dt,
    };
    time_step::check_stable(
        requested,
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

/// Whether a walk's feet are impulse joints' and its terrain has walls (cliffs), where the time
/// step has a bound of its own (`time_step::wall_step`). The terrain is built to be asked, once
/// more than the run builds it, and only for impulse walks.
fn impulse_against_walls(spec: &ScenarioSpec, terrain: &TerrainSource) -> Result<bool, String> {
    if spec.articulation != Some(crate::sim::Articulation::Impulse) {
        return Ok(false);
    }
    let grid = terrain
        .spec
        .build(&terrain.origin)
        .map_err(|e| format!("terrain: {e}"))?;
    Ok(grid.has_cliffs())
}

/// A walk's robot, gait, commands and settings. `walls`: its impulse joints' feet meet walls.
fn resolve_walk(
    spec: &ScenarioSpec,
    contact: &mut ContactModel,
    base: &Path,
    walls: bool,
    inputs: &mut Inputs,
    (warnings, notes): (&mut Vec<String>, &mut Vec<String>),
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
    let given = ground::Given {
        stiffness: spec.contact.stiffness.is_some(),
        damping: spec.contact.damping.is_some(),
    };
    let (normal, ground) = ground::fit(contact.normal, given, &robot, support)?;
    contact.normal = normal;
    let requested = time_step::Requested {
        dt: spec.dt,
        allow_unstable: spec.allow_unstable_dt,
    };
    let mut contact_step = time_step::contact_step(
        requested,
        &robot,
        contact,
        &gait.gait,
        support,
        given.stiffness,
    )?;
    if walls
        && let Some(wall) = time_step::wall_step(&robot, contact)
        && wall.limit < contact_step.limit
    {
        contact_step = wall;
    }
    let settle = spec.settle.unwrap_or(DEFAULT_SETTLE);
    check_number(settle, Range::NonNegative, "s").map_err(|e| format!("settle: {e}"))?;
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
    let servo = spec.servo.unwrap_or_default();
    let (gains, fitted_for) = crate::setup::servo::gains(
        servo.stiffness,
        servo.damping,
        &robot,
        &gait.standing_pose,
        support,
        gait.gait.step_height,
    )?;
    let articulation = spec.articulation.unwrap_or_default();
    let dt = time_step::choose(
        requested,
        &robot,
        &gait.standing_pose,
        gains,
        fitted_for,
        contact_step,
        warnings,
        notes,
    )?;
    let commands = resolve_commands(spec, &gait.gait)?;
    // a change the walk never reaches: a typo in `at` or in `duration`, which the run would hide
    for (i, c) in spec.command.iter().flatten().enumerate() {
        if c.at >= spec.duration {
            warnings.push(format!(
                "command[{i}]: at = {} s, at or after the walk's end (duration = {} s): it is never \
                 used",
                num(c.at),
                num(spec.duration)
            ));
        }
    }
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
            articulation,
            dt,
            solver_iterations: spec.solver_iterations.unwrap_or(DEFAULT_SOLVER_ITERATIONS),
            pgs_iterations: spec.pgs_iterations,
            gains,
        },
        settle,
        switches: spec.switches(),
        start: spec.start.unwrap_or_default(),
        ground,
    })
}

/// The robot: hex18 built in, or a URDF (and its robot file beside it).
fn resolve_robot(
    spec: &ScenarioSpec,
    base: &Path,
    inputs: &mut Inputs,
) -> Result<RobotModel, String> {
    // `robot = "hex18"` (or `--robot hex18`) from a folder without such a file: the built-in one
    let file = spec
        .robot
        .as_ref()
        .filter(|file| builtin::named(builtin::ROBOTS, file, &base.join(file)).is_none());
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
            .map_err(|e| format!("robot: {e}"))
        }
        Some(file) => {
            let path = base.join(file);
            let hint = |e: String| builtin::not_found_hint(e, &path, "robots", builtin::ROBOTS);
            inputs
                .robot(&path)
                .map_err(|e| hint(format!("robot: {e}")))?;
            crate::robot::load(&path).map_err(|e| hint(format!("robot: {e}")))
        }
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
                    builtin::not_found_hint(format!("gait: {e}"), &path, "gaits", builtin::GAITS)
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    /// The step a walk scenario resolves to, and its warnings and notes.
    fn step_of(text: &str) -> (f64, Vec<String>) {
        let table: toml::Table = text.parse().unwrap();
        let scenario =
            super::super::from_table(table, "t".into(), Path::new("/nonexistent/t.toml")).unwrap();
        let said = [scenario.warnings, scenario.notes].concat();
        (scenario.spec.dt(), said)
    }

    const STAIRS: &str = r#"
        duration = 1.0
        [terrain.source]
        kind = "steps"
        step_height = 0.06
        step_length = 0.3
        first_step = 0.3
        size = [3.0, 2.0]
        cell = 0.01
    "#;

    /// hex18's impulse feet against stairs' risers get half the step, said in a warning; on
    /// the default terrain (no walls) they keep 1 ms, and so does the multibody on stairs.
    #[test]
    fn impulse_joints_on_terrain_with_walls_halve_the_step() {
        let (dt, warnings) = step_of(&format!("articulation = \"impulse\"\n{STAIRS}"));
        assert_eq!(dt, 0.0005);
        assert!(
            warnings
                .iter()
                .any(|w| w.starts_with("dt: 0.500 ms") && w.contains("walls")),
            "{warnings:?}"
        );
        let (dt, warnings) = step_of(&format!("articulation = \"multibody\"\n{STAIRS}"));
        assert_eq!(dt, 0.001, "{warnings:?}");
        let (dt, warnings) = step_of("articulation = \"impulse\"\nduration = 1.0");
        assert_eq!(dt, 0.001, "{warnings:?}");
        // a step given is kept, with the bound named
        let (dt, warnings) = step_of(&format!("articulation = \"impulse\"\ndt = 0.001\n{STAIRS}"));
        assert_eq!(dt, 0.001);
        assert!(
            warnings
                .iter()
                .any(|w| w.contains("larger than hexsim would choose (0.500 ms)")),
            "{warnings:?}"
        );
    }
}
