//! A walk's metrics: accumulated step by step over the walk (settling excluded), written as JSON,
//! and their table.

use crate::record::metadata::MetricsFile;

use crate::contact::ContactForce;
use crate::record::Observer;
use crate::sim::{WalkSample, Walker};
use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

mod table;
pub use table::*;

/// Going backwards against the command by less than this (m) is noise, not a slide: a robot
/// stepping off from standing sways back and forth by a millimetre or so.
pub const BACKWARDS_NOISE: f64 = 0.01;

/// A walk whose worst foot slid more than this share of the distance the body travelled, on the
/// ground (its slip less its [`HexapodMetrics::foot_scuff`]), skated rather than walked (issue
/// 40's bar: a robot at 10 times hex18's scale "walked" 13.5 m with each foot sliding 0.6–1.3 m;
/// hex18's walks slide at most 2 %).
pub const SKATE_SHARE: f64 = 0.10;
/// A walk commanded straight ahead that drifted sideways more than this share of its forward
/// travel went somewhere else.
pub const SIDEWAYS_SHARE: f64 = 0.10;
/// A walk commanded straight ahead that turned more than this (deg) lost its heading.
pub const HEADING_BOUND_DEG: f64 = 10.0;
/// A walk commanded to turn by more than [`HEADING_BOUND_DEG`] that turned less than this share
/// of it, or the other way, did not follow its command.
pub const TURN_SHARE: f64 = 0.5;

/// A hexapod run's summary, written as JSON.
#[derive(Debug, Clone, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct HexapodMetrics {
    /// False when the run stopped early (interrupted or diverged); a walk that stops at its fall
    /// (`stop_at_fall`) is complete there.
    pub complete: bool,
    pub steps: u64,
    pub sim_time: f64,
    /// Seconds walked (after settling).
    pub walk_time: f64,
    /// Body displacement over the walk along the starting heading, across it, and in total (m).
    pub forward_distance: f64,
    pub sideways_distance: f64,
    pub distance: f64,
    pub mean_speed: f64,
    pub heading_change_deg: f64,
    /// The body's travel along the commanded direction (m): each step's displacement on the
    /// command's unit vector (turned by the body's heading), summed; steps without a linear
    /// command count nothing. Negative: the robot went backwards against its command (slid
    /// down a slope it was told to climb), which a distance alone does not say.
    pub command_progress: f64,
    pub max_roll_deg: f64,
    pub max_pitch_deg: f64,
    /// The body's largest tilt from upright over the walk: its z axis from the vertical (°),
    /// what a fall is judged by ([`FALL_TILT`]; roll and pitch each below 45° may tilt it past).
    pub max_body_tilt_deg: f64,
    pub rms_roll_deg: f64,
    pub rms_pitch_deg: f64,
    /// Body height above the terrain under it (m).
    pub body_height_mean: f64,
    pub body_height_std: f64,
    /// The lowest that height came (m): below zero the body has gone into the ground (a robot
    /// whose body has no collision geometry, collapsed).
    pub body_height_min: Option<f64>,
    /// Per foot: distance its contact point slid over the ground while in contact (m), loaded
    /// or not, see [`slid`]. The expectations' `max_foot_slip_mm` bounds this figure.
    pub foot_slip: [f64; 6],
    /// Per foot: the share of [`Self::foot_slip`] slid while the foot bore load (Fn > 0), see
    /// [`slid`]; bounded by `max_foot_slip_loaded_mm`.
    pub foot_slip_loaded: [f64; 6],
    /// Per foot: the share of [`Self::foot_slip`] slid while the gait had the foot in the air
    /// (swinging, not yet touched down): a swing brushing a stone's wall or dragging over a box's
    /// top, which moves the foot at the swing's speed across what it touches. A scuff, not a
    /// stance foot losing its grip: skating ([`SKATE_SHARE`]) is judged on the rest.
    pub foot_scuff: [f64; 6],
    /// Per foot: fraction of the walk on the ground.
    pub stance_fraction: [f64; 6],
    pub peak_normal_force: [f64; 6],
    pub mean_normal_force: [f64; 6],
    pub max_penetration: f64,
    /// Deepest penetration of any contact sphere of a link other than a foot (m): a shin against
    /// a riser, the belly on a rock (see `robot::contact_set`).
    pub max_link_penetration: f64,
    /// Seconds each link touched the ground with a sphere other than its foot, by link name
    /// (links that never did are left out).
    pub link_contact_time: std::collections::BTreeMap<String, f64>,
    /// Seconds the body (the root link) touched the ground: a walking robot's belly does not.
    pub body_contact_time: f64,
    /// When the robot fell (s into the walk; negative: while it settled, before the walk): the
    /// first time its body tilted past [`FALL_TILT`] from upright; None if it never did.
    pub fell_at: Option<f64>,
    /// Mechanical work done by the servos, ∫Σ|τ·q̇| dt (J), and the cost of transport E/(m·g·d):
    /// none for a robot that did not move (d = 0), whose cost per metre is undefined, not 0 — a
    /// search minimising it must not be rewarded for standing still.
    pub servo_energy: f64,
    pub cost_of_transport: Option<f64>,
    /// Steps in which some leg's target was out of reach and was clamped.
    pub clamped_ik_steps: u64,
    /// The worst foot's slip on the ground ([`Self::foot_slip`] less [`Self::foot_scuff`]) over
    /// the distance the body travelled (None when it did not travel 1 cm): above [`SKATE_SHARE`]
    /// the robot skated.
    pub slip_share: Option<f64>,
    /// What makes the walk not the walk commanded, each said in a sentence: its feet skated
    /// ([`SKATE_SHARE`]), it went backwards against the command, drifted sideways
    /// ([`SIDEWAYS_SHARE`]) or turned ([`HEADING_BOUND_DEG`]) when commanded straight ahead, or
    /// turned less than [`TURN_SHARE`] of a turn commanded.
    /// Empty for an honest walk.
    pub walk_flags: Vec<String>,
    /// The longest time any joint stayed within [`NEAR_LIMIT`] of a URDF limit over the walk (s):
    /// a servo pressed against its stop (a gait asking for more than the leg has).
    pub joint_limit_time: f64,
    /// Time the body's centre spent beyond the terrain's grid (s), on the flat apron its edge
    /// heights extend to: a walk there is not on the terrain it was meant for (a speed search
    /// could exploit it).
    pub time_off_terrain: f64,
    /// Impulse joints: the largest distance between a joint's two anchors (m) and rotation about
    /// a locked axis (deg) over the run; zero for the multibody.
    pub max_joint_drift: f64,
    pub max_joint_drift_deg: f64,
    /// The first joint whose servo rang at the step rate while its foot was off the ground
    /// ([`crate::sim::ringing`]), and when it began; None if none did. A servo that rings
    /// oversteps at this dt, and the walk's figures are not its servo's.
    pub servo_ringing: Option<ServoRinging>,
    /// The gait's stance on this robot: its lengths, where each came from, and its room.
    pub stance: StanceMetrics,
    /// The ground's contact stiffness and damping the walk ran on, and where each came from.
    pub ground: GroundMetrics,
    #[serde(skip)]
    acc: Accumulators,
    /// Where the metrics are written as JSON when the run ends, if anywhere.
    #[serde(skip)]
    output: Option<MetricsFile>,
}

/// A joint that rang at the step rate ([`crate::sim::ringing`]): its name, and when it began (s of
/// simulation, settling included).
#[derive(Debug, Clone, Serialize, Deserialize, Default, PartialEq)]
#[serde(default)]
pub struct ServoRinging {
    pub joint: String,
    pub from: f64,
}

/// The stance the robot walked in (see `gait::fit`), as the metrics JSON's `stance` object.
#[derive(Debug, Clone, Serialize, Deserialize, Default, PartialEq)]
#[serde(default)]
pub struct StanceMetrics {
    /// The hips' plane above level ground, standing (m).
    pub stance_height: f64,
    /// Standing feet from their hips, horizontally (m).
    pub reach: f64,
    pub step_height: f64,
    pub stride_length: f64,
    /// The front and rear feet turned towards the body's ends (deg; `Gait::splay`).
    pub splay_deg: f64,
    /// Where each length came from: "gait file", "robot file" or "fitted".
    pub origins: std::collections::BTreeMap<String, String>,
    /// The least distance of any joint to a limit over a cycle at the nominal speed on level
    /// ground (deg), and that joint.
    pub least_joint_room_deg: f64,
    pub least_room_joint: String,
    /// The most loaded servo standing on the gait's fewest feet: |torque| / effort.
    pub max_servo_share: f64,
    pub max_servo_joint: String,
    /// The body's lowest point above level ground, standing (m), when its shape is known.
    pub body_clearance: Option<f64>,
    /// The lowest any link's contact sphere but a foot's comes to level ground over a cycle
    /// (m; null: no link has contact spheres).
    pub link_clearance: Option<f64>,
    /// The steepest tilt on which the walk keeps its centre of mass over its support (deg;
    /// `GaitController::static_tilt`).
    pub static_tilt_deg: f64,
}

impl StanceMetrics {
    pub fn of(fitted: &crate::gait::Fitted, model: &crate::robot::RobotModel) -> Self {
        let g = &fitted.gait;
        let o = &fitted.origins;
        let origins = [
            ("stance_height", o.stance_height),
            ("reach", o.reach),
            ("step_height", o.step_height),
            ("stride_length", o.stride_length),
            ("splay", o.splay),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.describe().to_string()))
        .collect();
        let (joint, room) = fitted.margins.worst;
        StanceMetrics {
            stance_height: g.stance_height,
            reach: g.reach,
            step_height: g.step_height,
            stride_length: g.stride_length,
            splay_deg: g.splay.to_degrees(),
            origins,
            least_joint_room_deg: room.to_degrees(),
            least_room_joint: model.joints[joint].name.clone(),
            max_servo_share: fitted.load.share,
            max_servo_joint: model.joints[fitted.load.joint].name.clone(),
            body_clearance: fitted.clearance,
            link_clearance: Some(fitted.margins.link_clearance).filter(|c| c.is_finite()),
            static_tilt_deg: fitted.static_tilt.to_degrees(),
        }
    }
}

/// The ground a walk ran on, as the metrics JSON's `ground` object: the contact's stiffness and
/// damping, "given" by the scenario or "fitted" to the robot's weight (the reference contact
/// scaled by `mass_ratio`, the robot's mass over hex18's; see `setup::ground`).
#[derive(Debug, Clone, Serialize, Deserialize, Default, PartialEq)]
#[serde(default)]
pub struct GroundMetrics {
    pub stiffness: f64,
    pub damping: f64,
    pub origins: std::collections::BTreeMap<String, String>,
    pub mass_ratio: f64,
}

impl GroundMetrics {
    /// "k = 2.00e4 N/m, c = 150 N·s/m (fitted: 1.00 × hex18's mass)" for a run's summary.
    pub fn describe(&self) -> String {
        let origin = |field: &str| self.origins.get(field).map_or("given", String::as_str);
        let fitted = [origin("stiffness"), origin("damping")]
            .iter()
            .filter(|o| **o == "fitted")
            .count();
        let why = match fitted {
            0 => "as given".to_string(),
            2 => format!(
                "fitted to the robot's weight, {:.2} × hex18's: its feet sink as hex18's on the reference contact",
                self.mass_ratio
            ),
            _ => format!(
                "stiffness {}, damping {} (fitted: {:.2} × hex18's weight)",
                origin("stiffness"),
                origin("damping"),
                self.mass_ratio
            ),
        };
        format!(
            "k = {} N/m, c = {} N·s/m ({why})",
            significant(self.stiffness),
            significant(self.damping)
        )
    }
}

/// `x` to four significant digits.
pub fn significant(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(3 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

#[derive(Debug, Clone, Default)]
struct Accumulators {
    /// The body's position at the walk's start.
    start: Option<glam::DVec3>,
    walk_steps: u64,
    roll2: f64,
    pitch2: f64,
    height: f64,
    height2: f64,
    yaw_prev: f64,
    yaw_total: f64,
    /// The turn commanded so far (rad): the commanded yaw rate summed over the steps.
    yaw_commanded: f64,
    stance_steps: [u64; 6],
    force_sum: [f64; 6],
    dt: f64,
    mass: f64,
    /// Each joint's URDF limits (rad), and the steps it has stayed near one.
    limits: Vec<(f64, f64)>,
    near_limit_steps: Vec<u64>,
    /// The terrain grid's x and y ranges, if known.
    terrain: Option<([f64; 2], [f64; 2])>,
    /// Steps each model link touched the ground with a sphere other than its foot, and the
    /// links' names.
    link_steps: Vec<u64>,
    link_names: Vec<String>,
    /// The sine and cosine of the heading at the walk's start.
    start_heading: (f64, f64),
    /// The least cosine of the body's tilt noted ([`HexapodMetrics::note_attitude`]), not yet
    /// read into [`HexapodMetrics::max_body_tilt_deg`].
    least_upright: Option<f64>,
    /// The body's position at the last step (for [`HexapodMetrics::command_progress`]).
    last_position: Option<glam::DVec3>,
    /// Whether any step was commanded to move, to move sideways, or to turn.
    moving: bool,
    strafing: bool,
    turning: bool,
}

/// How far a contact slid over a step of `dt`, as (in contact, bearing load): its in-plane speed
/// |v_t| times `dt` whenever the foot's sphere overlaps the ground, and the same only while the
/// normal force is positive.
///
/// [`HexapodMetrics::foot_slip`] sums the first: the distance the foot's contact point travelled
/// over the ground while touching it, ∫|v_t| dt over the contact — what a legged-robotics reader
/// means by a foot's slip, and what a stance foot assumed fixed (leg odometry, a foothold
/// planner) gets wrong. It is a path length, not the displacement from touchdown to lift-off:
/// a foot that chatters in mid-stance or scrubs back and forth slides although it ends where it
/// landed, and chatter (the load alternating with zero from one step to the next inside a stance)
/// splits a stance into many touchdowns and lift-offs, so a displacement would depend on where
/// they are cut; the path length needs no such cut.
///
/// [`HexapodMetrics::foot_slip_loaded`] sums the second, the share slid under load. A foot
/// lifting off still overlaps the ground's spring for a few steps, but once it rises faster than
/// the damped spring relaxes (ẋ < −k·x/c) the normal force is clamped at zero and friction
/// (≤ μ·Fn) holds nothing; lifting straight up off a slope of angle θ at speed v then shows
/// v·sin θ in the slope's plane. But zero-force steps come in mid-stance too, where the load
/// chatters to zero and back, and the foot slides there as a real foot would: the loaded share
/// leaves out 9–73 % of the feet's sliding in contact on the walks of docs/robots.md (hex18's
/// 20 s walks: 32 % flat, 20 % natural), so it is reported beside the whole, not instead of it.
fn slid(contact: &ContactForce, dt: f64) -> (f64, f64) {
    let whole = contact.slip.length() * dt;
    (
        whole,
        if contact.normal_force > 0.0 {
            whole
        } else {
            0.0
        },
    )
}

/// A body tilted this far from upright (its z axis from the vertical) has fallen (45°, as
/// legged_gym's terrain curriculum and the terrain ladder count a fall).
pub const FALL_TILT: f64 = std::f64::consts::FRAC_PI_4;

/// How far a body whose orientation is `body` has tilted from upright: its z axis from the
/// vertical (rad). Past [`FALL_TILT`] it has fallen (the metrics' `fell_at`, the watchdog's
/// note of a fall).
pub fn tilt(body: &glam::DMat3) -> f64 {
    tilt_of(upright(body))
}

/// The cosine of [`tilt`] (unclamped): the body's z axis along the vertical.
fn upright(body: &glam::DMat3) -> f64 {
    body.z_axis.z / body.z_axis.length()
}

/// [`tilt`] from its cosine [`upright`].
fn tilt_of(upright: f64) -> f64 {
    upright.clamp(-1.0, 1.0).acos()
}

/// Whether `tilt(body) > FALL_TILT`, the same answer, the arc cosine taken only near the
/// threshold: a cosine above 0.7072 (cos 45° is 0.70711) is a tilt 1.4·10⁻⁴ rad short of it,
/// far beyond libm's rounding, and the arc cosine decreases (the watchdog tests every step).
pub fn fallen(body: &glam::DMat3) -> bool {
    fallen_at(upright(body))
}

/// [`fallen`] from the tilt's cosine [`upright`].
fn fallen_at(upright: f64) -> bool {
    let cosine = upright.clamp(-1.0, 1.0);
    cosine <= 0.7072 && cosine.acos() > FALL_TILT
}

/// How close to a limit a joint counts as at it (1°).
pub const NEAR_LIMIT: f64 = std::f64::consts::PI / 180.0;

impl HexapodMetrics {
    /// Metrics of a walk at step `dt` of a robot of `mass` whose joints have `limits` (lower,
    /// upper, rad); written to `output` at the end.
    pub fn new(dt: f64, mass: f64, limits: Vec<(f64, f64)>, output: Option<MetricsFile>) -> Self {
        HexapodMetrics {
            acc: Accumulators {
                dt,
                mass,
                near_limit_steps: vec![0; limits.len()],
                limits,
                ..Default::default()
            },
            output,
            ..Default::default()
        }
    }

    /// The body's tilt from upright (by its cosine [`upright`]), roll and pitch (rad) into
    /// their largest so far: the tilt's as the least cosine, its arc cosine taken by
    /// [`HexapodMetrics::update`] (the arc cosine and the conversion to degrees never decrease
    /// the larger of two tilts, so the largest tilt is the least cosine's, bit for bit: an arc
    /// cosine a step less).
    fn note_attitude(&mut self, upright: f64, roll: f64, pitch: f64) {
        // (`min` keeps the cosine that is not NaN, as `max` kept the tilt)
        let least = self.acc.least_upright.map_or(upright, |c| c.min(upright));
        self.acc.least_upright = Some(least);
        self.max_roll_deg = self.max_roll_deg.max(roll.abs().to_degrees());
        self.max_pitch_deg = self.max_pitch_deg.max(pitch.abs().to_degrees());
    }
}

impl HexapodMetrics {
    /// Judges the walk against its commands ([`Self::slip_share`], [`Self::walk_flags`]).
    fn judge(&mut self) {
        let a = &self.acc;
        // a swing's scuffs are no skating: the slip on the ground is judged
        let worst = (0..6)
            .map(|k| self.foot_slip[k] - self.foot_scuff[k])
            .fold(0.0, f64::max);
        self.slip_share = (self.distance >= 0.01).then(|| worst / self.distance);
        let mut flags = Vec::new();
        // skating is judged against the distance commanded: marking time (or turning on the
        // spot) travels none, and its feet's slip is no share of it
        if let Some(share) = self.slip_share.filter(|&s| a.moving && s > SKATE_SHARE) {
            flags.push(format!(
                "skated: its worst foot slid {worst:.3} m on the ground (its swings' scuffs left out), {:.1} % of the {:.3} m the body travelled (more than {:.0} %)",
                share * 100.0,
                self.distance,
                SKATE_SHARE * 100.0
            ));
        }
        if a.moving && self.command_progress < -BACKWARDS_NOISE {
            flags.push(format!(
                "went {:.3} m backwards against its command",
                -self.command_progress
            ));
        }
        let straight = a.moving && !a.strafing && !a.turning;
        if straight
            && self.sideways_distance.abs() > 0.01
            && self.sideways_distance.abs() > SIDEWAYS_SHARE * self.forward_distance.abs()
        {
            flags.push(format!(
                "drifted {:.3} m sideways against {:.3} m forward, commanded straight ahead (more than {:.0} %)",
                self.sideways_distance.abs(),
                self.forward_distance,
                SIDEWAYS_SHARE * 100.0
            ));
        }
        if straight && self.heading_change_deg.abs() > HEADING_BOUND_DEG {
            flags.push(format!(
                "turned {:+.1}° off its heading, commanded straight ahead (more than {HEADING_BOUND_DEG:.0}°)",
                self.heading_change_deg
            ));
        }
        let commanded = a.yaw_commanded.to_degrees();
        if commanded.abs() > HEADING_BOUND_DEG && self.heading_change_deg / commanded < TURN_SHARE {
            flags.push(format!(
                "turned {:+.1}° of the {commanded:+.1}° commanded (less than {:.0} %)",
                self.heading_change_deg,
                TURN_SHARE * 100.0
            ));
        }
        self.walk_flags = flags;
    }

    /// Brings the figures derived from the step sums (distances, means, fractions, the links'
    /// contact times, the cost of transport) up to the last step observed. Derived once a
    /// stretch of steps and at the end, not every step ([`crate::runner::walk::WalkSession`]):
    /// the same figures, without a dozen divisions, square roots and a sine a step.
    pub fn update(&mut self) {
        if let Some(upright) = self.acc.least_upright {
            let tilt = tilt_of(upright).to_degrees();
            self.max_body_tilt_deg = self.max_body_tilt_deg.max(tilt);
        }
        let a = &self.acc;
        let (Some(start), Some(position)) = (a.start, a.last_position) else {
            return; // no step walked yet
        };
        let dt = a.dt;
        let moved = position - start;
        let (s_h, c_h) = a.start_heading;
        self.forward_distance = moved.x * c_h + moved.y * s_h;
        self.sideways_distance = -moved.x * s_h + moved.y * c_h;
        self.distance = moved.truncate().length();
        self.walk_time = a.walk_steps as f64 * dt;
        self.mean_speed = self.distance / self.walk_time;
        self.heading_change_deg = a.yaw_total.to_degrees();
        let n = a.walk_steps as f64;
        self.rms_roll_deg = (a.roll2 / n).sqrt().to_degrees();
        self.rms_pitch_deg = (a.pitch2 / n).sqrt().to_degrees();
        self.body_height_mean = a.height / n;
        self.body_height_std = (a.height2 / n - self.body_height_mean.powi(2))
            .max(0.0)
            .sqrt();
        for k in 0..6 {
            self.stance_fraction[k] = a.stance_steps[k] as f64 / n;
            self.mean_normal_force[k] = a.force_sum[k] / n;
        }
        for (name, &steps) in a.link_names.iter().zip(&a.link_steps) {
            if steps > 0 {
                self.link_contact_time
                    .insert(name.clone(), steps as f64 * dt);
            }
        }
        if let Some(&steps) = a.link_steps.first().filter(|&&s| s > 0) {
            self.body_contact_time = steps as f64 * dt;
        }
        let weight_distance = a.mass * crate::sim::STANDARD_GRAVITY * self.distance;
        self.cost_of_transport =
            (weight_distance > 0.0).then(|| self.servo_energy / weight_distance);
    }

    /// Also measures the time spent beyond a terrain grid of these x and y ranges.
    pub fn on_terrain(mut self, x: [f64; 2], y: [f64; 2]) -> Self {
        self.acc.terrain = Some((x, y));
        self
    }
}

impl Observer<WalkSample, Walker> for HexapodMetrics {
    fn finish(&mut self, complete: bool) -> Result<Option<PathBuf>> {
        self.complete = complete;
        self.update();
        self.judge();
        crate::record::metadata::write(self.output.as_ref(), self)
    }

    fn observe(&mut self, s: &WalkSample, walker: &Walker) -> Result<()> {
        self.clamped_ik_steps = walker.reach.clamped_steps;
        let r = &s.robot;
        self.steps = r.step;
        self.sim_time = r.time;
        self.max_joint_drift = self.max_joint_drift.max(r.joint_drift.anchor);
        self.max_joint_drift_deg = self
            .max_joint_drift_deg
            .max(r.joint_drift.angle.to_degrees());
        if self.servo_ringing.is_none()
            && let Some((from, j)) = r.servo_ringing
        {
            self.servo_ringing = Some(ServoRinging {
                joint: walker.hexapod().model().joints[j].name.clone(),
                from,
            });
        }
        if s.settling {
            // not part of the walk, but a robot set down where it cannot stand (bullet, 0.41 m
            // tall, parallel to a 25° slope) falls before it walks: when (s before the walk,
            // negative) and how far, not a fall "at 0.00 s into the walk" and a tilt of 0
            let upright = upright(&r.body.matrix3);
            if fallen_at(upright) && self.fell_at.is_none() {
                self.fell_at = Some(walker.gait_time());
                let (roll, pitch, _) = r.roll_pitch_yaw();
                self.note_attitude(upright, roll, pitch);
            }
            return Ok(());
        }
        let (roll, pitch, yaw) = r.roll_pitch_yaw();
        let upright = upright(&r.body.matrix3);
        self.note_attitude(upright, roll, pitch);
        let a = &mut self.acc;
        let position = r.body.translation;
        if a.walk_steps == 0 {
            a.start = Some(position);
            a.start_heading = yaw.sin_cos();
            a.yaw_prev = yaw;
        }
        a.walk_steps += 1;
        let dt = a.dt;
        // unwrap the yaw so turning several times is counted
        let mut dyaw = yaw - a.yaw_prev;
        dyaw -= (dyaw / std::f64::consts::TAU).round() * std::f64::consts::TAU;
        a.yaw_total += dyaw;
        a.yaw_prev = yaw;
        if let Some(([x0, x1], [y0, y1])) = a.terrain
            && !((x0..=x1).contains(&position.x) && (y0..=y1).contains(&position.y))
        {
            self.time_off_terrain += dt;
        }
        let command = walker.command();
        a.moving |= command.forward != 0.0 || command.sideways != 0.0;
        a.strafing |= command.sideways != 0.0;
        a.turning |= command.yaw_rate != 0.0;
        a.yaw_commanded += command.yaw_rate * dt;
        let along = glam::DVec2::new(command.forward, command.sideways).normalize_or_zero();
        if let Some(last) = a.last_position {
            let step = glam::DMat2::from_angle(yaw) * along;
            self.command_progress += (position - last).truncate().dot(step);
        }
        a.last_position = Some(position);
        if self.fell_at.is_none() && fallen_at(upright) {
            self.fell_at = Some(a.walk_steps as f64 * dt);
        }
        a.roll2 += roll * roll;
        a.pitch2 += pitch * pitch;
        self.body_height_min = Some(
            self.body_height_min
                .map_or(r.body_height, |h| h.min(r.body_height)),
        );
        a.height += r.body_height;
        a.height2 += r.body_height * r.body_height;
        for (k, c) in r.foot_contacts.iter().enumerate() {
            if let Some(c) = c {
                a.stance_steps[k] += 1;
                a.force_sum[k] += c.normal_force;
                let (whole, loaded) = slid(c, dt);
                self.foot_slip[k] += whole;
                self.foot_slip_loaded[k] += loaded;
                if s.gait.as_ref().is_some_and(|g| !g.grounded[k]) {
                    self.foot_scuff[k] += whole;
                }
                self.peak_normal_force[k] = self.peak_normal_force[k].max(c.normal_force);
                self.max_penetration = self.max_penetration.max(c.penetration);
            }
        }
        let model = walker.hexapod().model();
        if a.link_names.len() != model.links.len() {
            a.link_names = model.links.iter().map(|l| l.name.clone()).collect();
            a.link_steps.resize(model.links.len(), 0);
        }
        let mut last = None;
        for c in &r.link_contacts {
            self.max_link_penetration = self.max_link_penetration.max(c.force.penetration);
            // contacts come in link order: count each link once a step
            if last != Some(c.link) {
                last = Some(c.link);
                a.link_steps[c.link] += 1;
            }
        }
        for ((q, &(lower, upper)), steps) in r
            .joint_angles
            .iter()
            .zip(&a.limits)
            .zip(&mut a.near_limit_steps)
        {
            if q - lower < NEAR_LIMIT || upper - q < NEAR_LIMIT {
                *steps += 1;
                self.joint_limit_time = self.joint_limit_time.max(*steps as f64 * dt);
            } else {
                *steps = 0;
            }
        }
        let power: f64 = r
            .joint_torques
            .iter()
            .zip(&r.joint_velocities)
            .map(|(t, v)| (t * v).abs())
            .sum();
        self.servo_energy += power * dt;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
