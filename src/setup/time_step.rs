//! A walk's time step: the largest the contact spring, the landing feet and the servos allow.
//! A step given is held to the same bounds — refused past the servo's or the explicit spring's
//! stability, warned past hexsim's own choice — and a step left out is chosen: 1 ms, or
//! 1 ms / n with the least n all the bounds allow (said in a warning).

use crate::contact::{ContactModel, NormalLaw};
use crate::gait::Gait;
use crate::limits::num;
use crate::robot::statics::foot_load;
use crate::robot::{Leg, Link, RobotModel};
use crate::sim::{STANDARD_GRAVITY, ServoGains};
use rapier3d::na;

/// The default step (s), and the one hexsim divides when a bound asks for less.
pub const DEFAULT_DT: f64 = 1e-3;

/// What the scenario says of the step.
#[derive(Debug, Clone, Copy)]
pub struct Requested {
    /// The step given, if any.
    pub dt: Option<f64>,
    /// Run a step past the stability bounds anyway.
    pub allow_unstable: bool,
}

impl Requested {
    /// The step given, else the default.
    fn dt(&self) -> f64 {
        self.dt.unwrap_or(DEFAULT_DT)
    }
}

/// The largest ω·dt of the contact spring on the lightest foot link, ω = √(k/m), for a step
/// hexsim chooses: half the explicit spring's stability bound of 2 (hex18 at 1 ms: 0.63).
pub const CONTACT_STEP_LIMIT: f64 = 1.0;

/// The most a foot's load may rise in one step as it lands, as a share of its standing load
/// (the robot's weight over the gait's fewest feet). A foot landing at speed v presses the
/// ground spring v·dt deeper each step, so its load rises by k·v·dt — v·dt/δ of the standing
/// load, δ the static sink — while the friction holding it is bounded by the load a step
/// before: the faster the load rises per step, the more a landing foot slides (measured:
/// docs/robots.md); hex18's tripod lands at 0.46 of it at 1 ms.
pub const TOUCHDOWN_STEP_LIMIT: f64 = 0.5;

/// The largest ω·dt a servo tolerates, ω = √(k/I) on the lightest joint (I: the inertia of the
/// links outboard of it about its axis). Above it the knee's fast mode and the step-explicit
/// contact force feed each other: the stance feet's load alternates step to step and they slide
/// (measured on Kraby: docs/robots.md). hex18's is 0.28.
pub const SERVO_STEP_LIMIT: f64 = 0.3;

/// The largest step the contact allows, and on what (for a message).
pub struct ContactStep {
    pub limit: f64,
    pub what: String,
}

/// The step the contact allows a walk of `robot` on `contact` with `gait` (its fewest feet on
/// the ground `support`): the spring on the lightest foot link ([`CONTACT_STEP_LIMIT`]), the
/// paper variant's explicit damper, and the landing feet ([`TOUCHDOWN_STEP_LIMIT`]), the least
/// of them. A step given is first checked against the explicit spring's stability.
pub fn contact_step(
    requested: Requested,
    robot: &RobotModel,
    contact: &ContactModel,
    gait: &Gait,
    support: usize,
    stiffness_given: bool,
) -> Result<ContactStep, String> {
    // the lightest foot link bounds the effective mass the contact spring acts on
    let (foot, foot_mass) =
        lightest_foot(robot, |_, link| link.mass).ok_or("the robot has no legs")?;
    let what = format!(
        "the lightest foot link (`{foot}`, {} kg)",
        four_digits(foot_mass)
    );
    if requested.dt.is_some() {
        check_stable(
            requested,
            contact,
            foot_mass,
            robot.legs[0].foot.radius,
            &what,
        )?;
    }
    let mut step = ContactStep {
        limit: spring_step(contact, foot_mass),
        what: format!(
            "the contact spring (k = {} N/m{}) on {what} needs √(k/m)·dt ≤ {CONTACT_STEP_LIMIT}",
            num(contact.normal.stiffness()),
            if stiffness_given {
                String::new()
            } else {
                format!(", fitted to the robot's {} kg", num(robot.total_mass()))
            }
        ),
    };
    if let Some(damper) = explicit_damper_step(contact, foot_mass)
        && 0.5 * damper < step.limit
    {
        step = ContactStep {
            limit: 0.5 * damper,
            what: format!(
                "the paper variant's explicit damper on {what} needs c·dt/m ≤ 1 (half its bound)"
            ),
        };
    }
    if let Some(touchdown) = touchdown_step(gait, contact, robot, support)
        && touchdown.limit < step.limit
    {
        step = touchdown;
    }
    Ok(step)
}

/// The step the contact spring allows impulse joints' feet against a wall (a terrain with
/// cliffs): there a foot is pushed sideways, and a free link pushed at its foot turns as it
/// moves, so the spring acts on 1/(1/m + |r × n|²/I) — hex18's tibia 0.015 kg against its
/// 0.05 kg, √(k/m)·dt = 1.16 at 1 ms. The multibody's foot moves its leg with it and needs no
/// such bound; on ground without walls the push is along the leg, on its mass, as
/// [`contact_step`] takes it. Measured (docs/rough-ground-log.md, *Impulse joints against
/// walls*): hex18's impulse ladder diverged in 6 runs of 104 at 1 ms, 2 at 0.5 ms.
pub fn wall_step(robot: &RobotModel, contact: &ContactModel) -> Option<ContactStep> {
    let (foot, mass) = lightest_foot(robot, |leg, link| {
        side_mass(link.mass, &link.inertia, leg.foot.center - link.com)
    })?;
    Some(ContactStep {
        limit: spring_step(contact, mass),
        what: format!(
            "on a terrain with walls, impulse joints' feet are pushed sideways: the contact spring \
             (k = {} N/m) on the foot link `{foot}` pushed at its foot ({} kg, the link turning \
             as it moves) needs √(k/m)·dt ≤ {CONTACT_STEP_LIMIT}",
            num(contact.normal.stiffness()),
            four_digits(mass)
        ),
    })
}

/// The foot link whose `mass` (of its leg and link) is least, by name, with that mass.
fn lightest_foot(robot: &RobotModel, mass: impl Fn(&Leg, &Link) -> f64) -> Option<(String, f64)> {
    robot
        .legs
        .iter()
        .map(|leg| {
            let link = &robot.links[leg.foot_link];
            (link.name.clone(), mass(leg, link))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The largest step [`CONTACT_STEP_LIMIT`] allows the contact spring on `mass`: √(k/m)·dt ≤ it.
fn spring_step(contact: &ContactModel, mass: f64) -> f64 {
    CONTACT_STEP_LIMIT / (contact.normal.stiffness() / mass).sqrt()
}

/// The least mass a free body of `mass` and `inertia` (about its centre of mass) presents to a
/// push at `arm` from that centre, over every direction n: 1/λ_max(W), W = 1/m + [r]×ᵀ·I⁻¹·[r]×
/// (the point's mobility). A body that cannot turn (no inertia) presents its mass.
fn side_mass(mass: f64, inertia: &glam::DMat3, arm: glam::DVec3) -> f64 {
    let Some(inverse) = na::Matrix3::from_column_slice(&inertia.to_cols_array()).try_inverse()
    else {
        return mass;
    };
    let r = na::Vector3::new(arm.x, arm.y, arm.z).cross_matrix();
    let w = na::Matrix3::identity() / mass + r.transpose() * inverse * r;
    let largest = w.symmetric_eigenvalues().max();
    if largest.is_finite() && largest > 0.0 {
        1.0 / largest
    } else {
        mass
    }
}

/// The explicit contact spring's stability: dt below 2/√(k/m) for the lightest `mass` it acts
/// on, and the paper variant's damper's below 2m/c.
pub fn check_stable(
    requested: Requested,
    contact: &ContactModel,
    mass: f64,
    radius: f64,
    what: &str,
) -> Result<(), String> {
    let dt = requested.dt();
    let limit = contact.normal.stable_time_step(mass, radius * 0.1);
    if dt >= limit && !requested.allow_unstable {
        return Err(format!(
            "dt = {dt} s is too large for the contact spring on {what}: the explicit spring needs dt < {} s (2/√(k/m)); reduce dt or the stiffness (or set allow_unstable_dt = true to run it anyway)",
            rounded_down(limit)
        ));
    }
    if let Some(limit) = explicit_damper_step(contact, mass)
        && dt >= limit
        && !requested.allow_unstable
    {
        return Err(format!(
            "dt = {dt} s is too large for the paper variant's explicit damper on {what}: it needs c·dt/m < 2, dt < {} s; reduce dt or the damping, or use hexsim's contact, whose damper is exact over a step (or set allow_unstable_dt = true to run it anyway)",
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

/// The time step of a walk: as given — refused when the lightest joint's servo is too fast for
/// it ([`SERVO_STEP_LIMIT`]; both articulations damp their servos implicitly), and warned when
/// it is larger than the contact spring or the landing feet allow (`contact`), naming the bound
/// and the step hexsim would choose — else the default, or 1 ms / n with the least n all of
/// them allow (said in a note: hexsim's own choice, nothing doubtful in the input, so `--strict`
/// does not refuse it). `fitted`: what the servo's stiffness was fitted for (None: given), for
/// the message.
#[allow(clippy::too_many_arguments)]
pub fn choose(
    requested: Requested,
    robot: &RobotModel,
    pose: &[f64],
    gains: ServoGains,
    fitted: Option<crate::robot::servo::FittedFor>,
    contact: ContactStep,
    warnings: &mut Vec<String>,
    notes: &mut Vec<String>,
) -> Result<f64, String> {
    let inertias = crate::robot::servo::outboard_inertias(robot, pose);
    let Some((joint, inertia)) = robot
        .legs
        .iter()
        .flat_map(|leg| leg.joints.iter().map(|&j| (j, inertias[j])))
        .filter(|(_, i)| *i > 0.0)
        .min_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return Ok(requested.dt());
    };
    let k = gains.stiffness;
    use crate::robot::servo::FittedFor;
    let fitted = match fitted {
        None => "",
        Some(FittedFor::Sag) => ", fitted to the robot's weight and the gait's step height",
        Some(FittedFor::Bandwidth) => ", fitted to the reference servo's bandwidth on these legs",
        // the fit's floor: a small robot's own figures ask for less
        Some(FittedFor::Reference) => {
            ", hex18's, the least the fit gives (a robot far smaller than hex18 may set its own: \
             --servo-stiffness, or `servo.stiffness` in a scenario)"
        }
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
    let (servo_limit, servo_why) = (limit, why.clone());
    if contact.limit < limit {
        limit = contact.limit;
        why = contact.what;
    }
    if requested.dt.is_none() && (limit.is_nan() || limit < crate::limits::MIN_CHOSEN_DT) {
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
    match requested.dt {
        Some(dt) if dt > servo_limit && !requested.allow_unstable => Err(format!(
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
            notes.push(format!(
                "dt: {:.3} ms, not the default 1 ms: {why} (set dt to choose another)",
                chosen * 1e3
            ));
            Ok(chosen)
        }
        None => Ok(DEFAULT_DT),
    }
}

/// A step bound for a message, to three significant digits and rounded down: a dt copied from
/// it is allowed, below a strict bound too (4.996e-4 printed as 5.00e-4 refused the 5e-4 a user
/// then tried).
pub fn rounded_down(limit: f64) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::GaitSpec;

    struct Walk {
        robot: RobotModel,
        gait: Gait,
        pose: Vec<f64>,
        gains: ServoGains,
        contact: ContactModel,
    }

    fn hex18(gait: &str) -> Walk {
        let builtin = crate::scenario::builtin::named(
            crate::scenario::builtin::GAITS,
            std::path::Path::new(gait),
            std::path::Path::new("/nonexistent"),
        )
        .unwrap();
        let spec = GaitSpec::from_toml(builtin.text, std::path::Path::new(builtin.path)).unwrap();
        let robot = crate::scenario::builtin::hex18();
        let fitted = crate::gait::fit(&robot, &spec).unwrap();
        let (gains, _) =
            super::super::servo::fitted(&robot, &fitted.standing_pose, 3, fitted.gait.step_height);
        Walk {
            robot,
            gait: fitted.gait,
            pose: fitted.standing_pose,
            gains,
            contact: ContactModel::default(),
        }
    }

    /// The step chosen for `w`, its warnings and notes said in `said` (a step given past a
    /// bound is warned, a step chosen is noted).
    fn choose_for(w: &Walk, requested: Requested, said: &mut Vec<String>) -> Result<f64, String> {
        let contact = contact_step(requested, &w.robot, &w.contact, &w.gait, 3, false)?;
        let mut notes = Vec::new();
        let dt = choose(
            requested,
            &w.robot,
            &w.pose,
            w.gains,
            Some(crate::robot::servo::FittedFor::Sag),
            contact,
            said,
            &mut notes,
        );
        said.extend(notes);
        dt
    }

    const LEFT_OUT: Requested = Requested {
        dt: None,
        allow_unstable: false,
    };

    #[test]
    fn hex18_walks_at_the_default_step_without_a_warning() {
        let mut warnings = Vec::new();
        let dt = choose_for(&hex18("tripod"), LEFT_OUT, &mut warnings).unwrap();
        assert_eq!(dt, DEFAULT_DT);
        assert!(warnings.is_empty(), "{warnings:?}");
    }

    #[test]
    fn a_stiffer_servo_gets_a_divided_step_said_in_a_warning() {
        let mut w = hex18("tripod");
        w.gains.stiffness *= 16.0;
        let mut warnings = Vec::new();
        let dt = choose_for(&w, LEFT_OUT, &mut warnings).unwrap();
        assert!(dt < DEFAULT_DT);
        // 1 ms / n
        let n = DEFAULT_DT / dt;
        assert!((n - n.round()).abs() < 1e-9, "{dt}");
        assert!(
            warnings[0].starts_with("dt: ") && warnings[0].contains("ω·dt"),
            "{warnings:?}"
        );
    }

    #[test]
    fn a_step_past_the_servos_bound_is_refused_unless_allowed() {
        let w = hex18("tripod");
        let large = Requested {
            dt: Some(0.009),
            allow_unstable: false,
        };
        let mut warnings = Vec::new();
        let error = choose_for(&w, large, &mut warnings).unwrap_err();
        assert!(error.starts_with("dt = 0.009 s is too large"), "{error}");
        let allowed = Requested {
            allow_unstable: true,
            ..large
        };
        assert_eq!(choose_for(&w, allowed, &mut warnings), Ok(0.009));
    }

    #[test]
    fn hex18s_tripod_lands_within_the_touchdown_bound_at_the_default_step() {
        let w = hex18("tripod");
        let step = touchdown_step(&w.gait, &w.contact, &w.robot, 3).unwrap();
        // its load rises 0.46 of its standing share a step at 1 ms, under the bound's 0.5
        let share = TOUCHDOWN_STEP_LIMIT * DEFAULT_DT / step.limit;
        assert!((share - 0.46).abs() < 0.01, "{share}");
        assert!(
            step.what.starts_with("the feet land at 0.19 m/s"),
            "{}",
            step.what
        );
    }

    #[test]
    fn hex18s_impulse_feet_against_a_wall_halve_the_step() {
        let w = hex18("tripod");
        let wall = wall_step(&w.robot, &w.contact).unwrap();
        // the tibia, 0.05 kg, 0.12 m to its foot, 7.5575e-5 kg·m² about its middle: pushed
        // across at the foot's centre, 0.06 m from its centre of mass, 1/(20 + 0.06²/7.5575e-5)
        let expected: f64 = 1.0 / (1.0 / 0.05 + 0.06f64.powi(2) / 7.5575e-5);
        let mass = (wall.limit / CONTACT_STEP_LIMIT).powi(2) * w.contact.normal.stiffness();
        assert!(
            (mass - expected).abs() < 1e-9,
            "{mass} kg against {expected} kg"
        );
        assert!((expected - 0.01479).abs() < 1e-5, "{expected}");
        // past 1 ms, within 0.5 ms: the walk's step halves
        assert!(
            wall.limit < DEFAULT_DT && wall.limit > DEFAULT_DT / 2.0,
            "{}",
            wall.limit
        );
        assert!(wall.what.contains("`lf_tibia`"), "{}", wall.what);
        // a body that cannot turn presents its mass
        assert_eq!(side_mass(0.05, &glam::DMat3::ZERO, glam::DVec3::X), 0.05);
    }

    #[test]
    fn a_bound_is_shown_rounded_down() {
        assert_eq!(rounded_down(4.996e-4), "4.99e-4");
        assert_eq!(rounded_down(1e-3), "9.99e-4");
    }
}
