//! `hexsim robot FILE`: what hexsim makes of a robot — its legs, walking direction, masses, and
//! what its servos must hold standing in a gait's pose.

use anyhow::Result;
use clap::Args;
use hexsim::gait::{Fitted, GaitSpec, fit};
use hexsim::metrics::walk::significant;
use hexsim::record::standing;
use hexsim::robot::{self, GaitHints, RobotModel, statics};
use hexsim::scenario::{Scenario, builtin};
use hexsim::sim::STANDARD_GRAVITY;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct RobotArgs {
    /// Robot URDF (with its robot file, NAME.toml, beside it if there is one), or `hex18`, the
    /// built-in reference robot, as `hexsim run --robot` takes it.
    robot: PathBuf,
    /// Gait whose standing pose is checked: a gait file, or a built-in gait's name (tripod,
    /// ripple, wave). Default: gaits/tripod.toml (built in).
    #[arg(long)]
    gait: Option<PathBuf>,
    /// Also write a rerun recording of the robot standing in the gait's fitted pose on level
    /// ground, beside this report.
    #[arg(long, value_name = "FILE.rrd")]
    record: Option<PathBuf>,
    /// With --record: draw each leg's reachable workspace as points (its joints swept between
    /// their limits).
    #[arg(long, requires = "record")]
    workspace: bool,
    /// With --record: open the recording in the rerun viewer.
    #[arg(long, requires = "record")]
    spawn: bool,
    /// Treat the robot's warnings (a CAD export's empty joint limits, a mesh not found) as
    /// errors: the report is printed, and hexsim exits with status 2.
    #[arg(long)]
    strict: bool,
}

pub fn robot_command(args: RobotArgs) -> Result<()> {
    if let Some(path) = &args.record {
        // the recording must not replace the robot, its robot file or the gait
        let robot_file = args.robot.with_extension("toml");
        let inputs = [
            ("robot", Some(&args.robot)),
            ("robot file", Some(&robot_file)),
        ]
        .into_iter()
        .chain([("gait file", args.gait.as_ref())])
        .filter_map(|(what, path)| Some((what, path?.as_path())));
        hexsim::record::output::check_distinct([("--record", path.as_path())], inputs)?;
    }
    // `hex18` and a gait's bare name (`wave`) are the built-in files, as `hexsim run` reads them,
    // where no file of that name is here
    let model = match builtin::named(builtin::ROBOTS, &args.robot, &args.robot) {
        Some(_) => builtin::hex18(),
        None => robot::load(&args.robot)
            .map_err(builtin::with_hint(&args.robot, "robots", builtin::ROBOTS))
            .map_err(anyhow::Error::msg)?,
    };
    let gait = match &args.gait {
        Some(path) => match builtin::named(builtin::GAITS, path, path) {
            Some(b) => GaitSpec::from_toml(b.text, Path::new(b.path))?,
            None => GaitSpec::from_file(path)
                .map_err(builtin::with_hint(path, "gaits", builtin::GAITS))
                .map_err(anyhow::Error::msg)?,
        },
        None => GaitSpec::from_toml(builtin::TRIPOD.text, Path::new(builtin::TRIPOD.path))?,
    };
    let mut report = describe(&args.robot, &model, &gait);
    report.push_str(&walk_reach(&args.robot, args.gait.as_deref()));
    out_part!("{report}");
    if args.strict && !model.warnings.is_empty() {
        anyhow::bail!(
            "{}: {} warning{} treated as errors (--strict)",
            args.robot.display(),
            model.warnings.len(),
            if model.warnings.len() == 1 { "" } else { "s" }
        );
    }
    if let Some(path) = &args.record {
        // the standing pose of the gait's fit; a robot it does not fit stands with its joints at
        // zero, so the recording still shows what was loaded
        let pose = fit(&model, &gait)
            .map(|f| f.standing_pose)
            .unwrap_or_else(|_| vec![0.0; model.joints.len()]);
        let written = standing::record(
            path,
            &standing::Standing {
                model: &model,
                pose: &pose,
                report: &report,
                workspace: args.workspace,
            },
        )?;
        out!("recording: {}", written.display());
        if args.spawn {
            hexsim::record::rerun::spawn_viewer(&written)?;
        }
    }
    Ok(())
}

/// Whole degrees, without a "-0".
fn deg(r: f64) -> String {
    format!("{:.0}°", r.to_degrees().round() + 0.0)
}

/// A signed number to the thousandth (a torque in N·m, a position in m), without a "-0.000".
fn thousandths(t: f64) -> String {
    format!("{:+.3}", (t * 1e3).round() / 1e3 + 0.0)
}

/// The robot with no stance from its robot file: what the fit makes of its legs alone.
fn without_hints(model: &RobotModel) -> RobotModel {
    RobotModel {
        gait_hints: GaitHints::default(),
        ..model.clone()
    }
}

/// The standing pose's joint angles and the torque each servo holds in it, on six feet.
fn standing(out: &mut String, model: &RobotModel, fitted: &Fitted) {
    use std::fmt::Write;
    let pose = &fitted.standing_pose;
    let torques = statics::standing_torques(model, pose, STANDARD_GRAVITY, 6);
    let gait = &fitted.gait;
    let support = hexsim::gait::minimum_support(&gait.offsets, gait.duty_factor);
    let (gains, reason) = hexsim::setup::servo::fitted(model, pose, support, gait.step_height);
    let (stiffness, damping) = (gains.stiffness, gains.damping);
    let why = match reason {
        robot::servo::FittedFor::Reference => "hex18's".to_string(),
        robot::servo::FittedFor::Bandwidth => "the reference bandwidth on these legs".to_string(),
        robot::servo::FittedFor::Sag => format!(
            "stiff enough that a foot on {support} feet sags at most {:.0} % of the {:.3} m step",
            robot::servo::SAG_LIMIT * 100.0,
            gait.step_height
        ),
    };
    let _ = writeln!(
        out,
        "  servo gains for these legs (unless a scenario or the command line sets them): {stiffness:.1} N·m/rad, {damping:.3} N·m·s/rad ({why})"
    );
    let _ = writeln!(
        out,
        "  standing on six feet (hips {:.3} m above the ground): joint angles, and the torque each servo holds (share of its effort):",
        fitted.gait.stance_height
    );
    let mut worst: Option<(f64, String)> = None;
    for leg in &model.legs {
        let cells: Vec<String> = leg
            .joints
            .iter()
            .map(|&j| {
                let joint = &model.joints[j];
                let share = torques[j].abs() / joint.effort;
                if worst.as_ref().is_none_or(|(w, _)| share > *w) {
                    worst = Some((share, joint.name.clone()));
                }
                format!(
                    "{} {} N·m ({:.0} %)",
                    deg(pose[j]),
                    thousandths(torques[j]),
                    100.0 * share
                )
            })
            .collect();
        let _ = writeln!(out, "    {}  {}", leg.name, cells.join(", "));
    }
    if let Some((share, joint)) = worst {
        let _ = writeln!(
            out,
            "  the most loaded servo: {joint} at {:.0} % of its effort{}",
            100.0 * share,
            if share > 1.0 {
                ": it cannot hold the robot up"
            } else {
                ""
            }
        );
    }
    feedforward(out, model, fitted, stiffness);
}

/// What the servos' load feed-forward (`sim::Walker::load_feedforward`) does over the gait's
/// cycle in the standing pose: the largest share of the weight a foot carries (force and moment
/// balance on the feet down) and the largest target offset τ/k.
fn feedforward(out: &mut String, model: &RobotModel, fitted: &Fitted, stiffness: f64) {
    use std::fmt::Write;
    let gait = &fitted.gait;
    let poses = model.link_poses(&fitted.standing_pose);
    let weight = model.total_mass() * STANDARD_GRAVITY;
    let (mut most_load, mut most_offset) = ((0.0, ""), (0.0, String::new()));
    let mut torques = vec![0.0; model.joints.len()];
    for k in 0..100 {
        let t = k as f64 / 100.0;
        let stance = std::array::from_fn(|l| {
            hexsim::gait::leg_phase(t, 1.0, gait.duty_factor, gait.offsets[l]).is_stance()
        });
        let loads = statics::stance_loads(model, &poses, STANDARD_GRAVITY, stance);
        for (leg, &load) in model.legs.iter().zip(&loads) {
            if load > most_load.0 {
                most_load = (load, leg.name);
            }
        }
        statics::holding_torques(model, &poses, STANDARD_GRAVITY, &loads, &mut torques);
        for (joint, torque) in model.joints.iter().zip(&torques) {
            let offset = (torque / stiffness).abs();
            if offset > most_offset.0 {
                most_offset = (offset, joint.name.clone());
            }
        }
    }
    let _ = writeln!(
        out,
        "  load feed-forward (unless turned off): over the {}'s cycle a foot carries up to {:.0} % of the weight ({}; force and moment balance on the feet down), and a servo's target is moved on by up to {:.1}° ({}) so that it comes to rest on the gait's angle",
        gait.name,
        100.0 * most_load.0 / weight,
        most_load.1,
        most_offset.0.to_degrees(),
        most_offset.1
    );
}

/// The report, as printed.
/// Whether the foot targets of `hexsim run --robot ROBOT [--gait GAIT]` are in reach, planned
/// on level ground step by step as the run plans them (`Scenario::planned_reach`): the run's
/// own count of steps out of reach (`clamped_ik_steps`) on flat ground.
fn walk_reach(robot: &Path, gait: Option<&Path>) -> String {
    let spec = super::run::default_walk(robot, gait);
    let duration = spec.duration;
    let scenario = match Scenario::resolve(spec, "robot".into(), Path::new("hexsim robot")) {
        Ok(scenario) => scenario,
        Err(e) => {
            return format!(
                "  `hexsim run` of this robot would not start: {}\n",
                e.message
            );
        }
    };
    let dt = scenario.spec.dt();
    let speed = scenario.drive().map_or(0.0, |(_, c)| c.at(0.0).forward);
    let verdict = match scenario.planned_reach() {
        None => return String::new(),
        Some(Err(e)) => return format!("  its walk cannot be planned: {e}\n"),
        Some(Ok(tally)) => match tally.first {
            None => format!("every foot target reached in all {} steps", tally.steps),
            Some((leg, t)) => {
                let names = scenario.robot().map(|m| m.legs[leg].name).unwrap_or("?");
                format!(
                    "{} of {} steps had foot targets out of reach (IK clamped), the first leg {names}'s at {t:.3} s",
                    tally.clamped_steps, tally.steps
                )
            }
        },
    };
    format!(
        "  `hexsim run` of it ({duration} s at {speed:.3} m/s, dt {} ms), planned on level ground step by step as the run plans it: {verdict}\n",
        significant(dt * 1e3)
    )
}

/// The joints hexsim holds still, off the legs and on them, with their angles.
fn held_joints(model: &RobotModel) -> Option<String> {
    if model.held.is_empty() {
        return None;
    }
    let list = |on_leg: bool| -> Vec<String> {
        model
            .held
            .iter()
            .filter(|h| h.on_leg.is_some() == on_leg)
            .map(|h| format!("{} {}", h.name, deg(h.angle)))
            .collect()
    };
    let mut parts = Vec::new();
    let off = list(false);
    if !off.is_empty() {
        parts.push(format!(
            "off the legs (a head, an arm, a tail: carried as part of the body): {}",
            off.join(", ")
        ));
    }
    let on = list(true);
    if !on.is_empty() {
        parts.push(format!(
            "on the legs, beyond the three that sweep the largest workspace (legs of up to {} joints alike are driven whole with `redundant_legs = \"driven\"` in the robot file): {}",
            hexsim::robot::kinematics::MAX_LEG_JOINTS,
            on.join(", ")
        ));
    }
    Some(format!(
        "  {} joints held still at the angle shown (welded): {}",
        model.held.len(),
        parts.join("; ")
    ))
}

/// For a leg of more than three joints: which three place the foot and which are redundant,
/// pulled towards their rest by its inverse kinematics (`robot::redundant`).
fn redundant_joints(model: &RobotModel, leg: &robot::Leg) -> Option<String> {
    if leg.joints.len() <= 3 {
        return None;
    }
    let name = |j: usize| model.joints[j].name.as_str();
    let (mut three, mut extra) = (Vec::new(), Vec::new());
    for (&j, rest) in leg.joints.iter().zip(&leg.posture) {
        match rest {
            None => three.push(name(j).to_string()),
            Some(angle) => extra.push(format!("{} {}", name(j), deg(*angle))),
        }
    }
    Some(format!(
        "        redundant: {} place the foot, {} driven too and pulled towards rest (damped least squares with a posture term)",
        three.join(" "),
        extra.join(", ")
    ))
}

fn describe(file: &Path, model: &RobotModel, gait: &GaitSpec) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: {}, {} links, {} joints, 6 legs",
        file.display(),
        model.name,
        model.links.len(),
        model.joints.len()
    );
    let _ = writeln!(out, "  walking direction {}", model.forward.describe());
    let merged: Vec<String> = model
        .links
        .iter()
        .filter(|l| !l.merged.is_empty())
        .map(|l| format!("{} into {}", l.merged.join(", "), l.name))
        .collect();
    if !merged.is_empty() {
        let count: usize = model.links.iter().map(|l| l.merged.len()).sum();
        let _ = writeln!(
            out,
            "  {count} URDF links fixed to others, merged: {}",
            merged.join("; ")
        );
    }
    if let Some(held) = held_joints(model) {
        let _ = writeln!(out, "{held}");
    }
    let leg_mass = |leg: &robot::Leg| -> f64 {
        leg.joints
            .iter()
            .map(|&j| model.links[model.joints[j].child].mass)
            .sum()
    };
    let legs: Vec<String> = model
        .legs
        .iter()
        .map(|l| format!("{:.3}", leg_mass(l)))
        .collect();
    let _ = writeln!(
        out,
        "  mass {:.3} kg: body {:.3} kg, legs {} kg (lf lm lr rf rm rr)",
        model.total_mass(),
        model.links[0].mass,
        legs.join(" ")
    );
    let _ = writeln!(
        out,
        "  legs (in hexsim's body frame: x the walking direction, z up):"
    );
    for leg in &model.legs {
        let joints: Vec<&robot::Joint> = leg.joints.iter().map(|&j| &model.joints[j]).collect();
        let hip = joints[0].origin.translation;
        let segments: Vec<String> = statics::segment_lengths(model, leg)
            .iter()
            .map(|s| format!("{s:.3}"))
            .collect();
        let names: Vec<&str> = joints.iter().map(|j| j.name.as_str()).collect();
        let _ = writeln!(
            out,
            "    {}  hip ({}, {}, {}) m; joints {}; segments {} m",
            leg.name,
            thousandths(hip.x),
            thousandths(hip.y),
            thousandths(hip.z),
            names.join(" "),
            segments.join(" "),
        );
        if let Some(line) = redundant_joints(model, leg) {
            let _ = writeln!(out, "{line}");
        }
        let limits: Vec<String> = joints
            .iter()
            .map(|j| format!("[{}, {}]", deg(j.lower), deg(j.upper)))
            .collect();
        let efforts: Vec<String> = joints
            .iter()
            .map(|j| format!("{}", (j.effort * 1e4).round() / 1e4))
            .collect();
        let _ = writeln!(
            out,
            "        limits {}; effort {} N·m",
            limits.join(" "),
            efforts.join(" ")
        );
        let foot = leg.foot;
        let _ = writeln!(
            out,
            "        foot: sphere of radius {:.1} mm centred at ({:+.1}, {:+.1}, {:+.1}) mm in link {}, {}",
            foot.radius * 1e3,
            foot.center.x * 1e3 + 0.0,
            foot.center.y * 1e3 + 0.0,
            foot.center.z * 1e3 + 0.0,
            model.links[leg.foot_link].name,
            foot.from.describe()
        );
    }
    // where a tool finds the URDF joint behind each trajectory column
    let columns = hexsim::record::joint_columns::joint_columns(model);
    let pairs: Vec<String> = columns
        .iter()
        .zip(&model.joints)
        .map(|(column, joint)| format!("{column} = {}", joint.name))
        .collect();
    let _ = writeln!(
        out,
        "  trajectory joint columns ({{name}}_angle, _target, _torque) and their URDF joints: {}",
        pairs.join(", ")
    );
    let _ = writeln!(out, "  {}", contact_spheres(model));
    match fit(model, gait) {
        Err(e) => {
            let _ = writeln!(out, "  gait {}: does not fit: {e}", gait.name);
        }
        Ok(fitted) => {
            let _ = writeln!(out, "  gait {} on this robot:", gait.name);
            for line in fitted.describe(model) {
                let _ = writeln!(out, "    {line}");
            }
            let given = model.gait_hints != GaitHints::default();
            if given && let Ok(bare) = fit(&without_hints(model), gait) {
                let _ = writeln!(
                    out,
                    "    fitted to the legs alone (without the robot file's [gait]):"
                );
                for line in bare.describe(model) {
                    let _ = writeln!(out, "      {line}");
                }
            }
            standing(&mut out, model, &fitted);
            let (joint, room) = fitted.margins.worst;
            // whether its targets are reached: the walk planned as a run plans it (below)
            let _ = writeln!(
                out,
                "  walking {}'s cycle at {:.3} m/s on level ground: least room {} {} from a limit",
                gait.name,
                fitted.gait.nominal_speed(),
                model.joints[joint].name,
                deg(room)
            );
            if let Ok(controller) = hexsim::gait::GaitController::new(model, fitted.gait.clone())
                && let Some(lean) = controller.lean_on_slopes()
            {
                let _ = writeln!(out, "  lean on slopes: {}", lean.describe());
            }
        }
    }
    let (ground, fitted) = hexsim::setup::ground::fit(
        hexsim::contact::NormalLaw::default(),
        hexsim::setup::ground::Given::default(),
        model,
        0,
    )
    .expect("a fitted ground is never refused");
    let ratio = fitted.mass_ratio;
    let _ = writeln!(
        out,
        "  ground for a scenario that leaves the contact out: k = {} N/m, c = {} N·s/m (the reference contact fitted to the robot's weight, {ratio:.2} × hex18's: its feet sink as hex18's)",
        significant(ground.stiffness()),
        significant(ground.damping())
    );
    for warning in &model.warnings {
        let _ = writeln!(out, "  warning: {warning}");
    }
    out
}

/// "ground contact beyond the feet: 92 spheres on 19 links (body 32, …)": what touches the
/// terrain besides the feet (`robot::contact_set`).
fn contact_spheres(model: &RobotModel) -> String {
    let with: Vec<&robot::Link> = model
        .links
        .iter()
        .filter(|l| !l.contacts.is_empty())
        .collect();
    let total: usize = with.iter().map(|l| l.contacts.len()).sum();
    if total == 0 {
        return "ground contact: the feet alone (no other link has collision geometry)".to_string();
    }
    let radii = with
        .iter()
        .flat_map(|l| l.contacts.iter().map(|c| c.radius))
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
            (lo.min(r), hi.max(r))
        });
    let soles = (0..model.links.len())
        .flat_map(|link| robot::contact_set::soles(model, link))
        .flatten()
        .count();
    let soles = if soles > 0 {
        format!(
            "; {soles} of them at the feet's tips, reported as the feet's contact (a sole wider than its foot sphere)"
        )
    } else {
        String::new()
    };
    format!(
        "ground contact beyond the feet: {total} spheres of {:.1}–{:.1} mm on {} of {} links (body {}), from their collision geometry; links without it do not touch{soles}",
        radii.0 * 1e3,
        radii.1 * 1e3,
        with.len(),
        model.links.len(),
        model.links[0].contacts.len()
    )
}
