//! The gait controller: a commanded body velocity → foot targets in the body frame → joint
//! targets through inverse kinematics.
//!
//! Each foot has a neutral point N (the standing pose). Over a stance of duration Tₛ = duty·T the
//! ground under a foot moves, seen from the body, by D = −(v + ω×N)·Tₛ; the foot follows it from
//! N − D/2 to N + D/2 and swings back through the air.
//!
//! **Rolling feet.** A foot is a sphere of radius r welded to the leg's last link. When that link
//! turns at ω with the sphere on the ground, the point touching the ground holds still only if the
//! centre moves at r·ω × n over it (n the ground's normal): the sphere rolls. Planning the centre's
//! path as the contact's own makes every turn of the tibia scrub the contact at r·ω — ant_bot's
//! 15.5 mm feet slid 0.18 m in 10 s on the natural terrain this way. With rolling on (the
//! default; [`GaitController::with_rolling_feet`]) the centre target is moved on by r·(Δφ × ẑ),
//! Δφ the rotation vector that turns the foot link from its standing pose (the stance's middle):
//! its rate is ω up to a second-order ½·Δφ × ω. The body then moves at the commanded speed over
//! rolling feet instead of riding on them (hex18: 0.1207 m/s for 0.12 commanded; 0.1242 m/s
//! without). A swinging foot gets the offset of the point under it on the ground (its path
//! without the lift), so the offset passes smoothly from lift-off to touch-down and the lift's
//! own turn of the tibia does not swing the foot sideways. Δφ is read to first order from the
//! leg's last answer, a step away, not by solving the leg a second time (see
//! [`GaitController::place`]). The fit plans the stance without it: the offset is millimetres,
//! an execution detail like the servos' load feed-forward.

use super::clearance::{self, SwingGround};
use super::compliance::{Compliance, GroundForces, Release};
use super::foothold;
use super::lean::{self, HorizontalRoom, Lean};
use super::reactive::{FootFeel, Reactive};
use super::schedule::{LegPhase, leg_phase};
use super::slew;
use super::spec::{Gait, SwingShape};
use crate::robot::kinematics::{
    self, IK_TOLERANCE, IkSolution, IkWarm, LegAngles, LegChain, LegStatics,
};
use crate::robot::{ContactSphere, RobotModel};
use glam::{DMat2, DMat3, DQuat, DVec2, DVec3};

/// A velocity command in the body frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VelocityCommand {
    /// m/s along the body's x.
    pub forward: f64,
    /// m/s along the body's y (left).
    pub sideways: f64,
    /// rad/s about z (left turn positive).
    pub yaw_rate: f64,
}

/// The controller's output for one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaitTargets {
    /// Per leg, its joints' angles from the body out.
    pub joint_angles: [LegAngles; 6],
    /// Foot centre targets (body frame), rolling offset included.
    pub feet: [DVec3; 6],
    pub phases: [LegPhase; 6],
    /// Legs whose target was out of reach this instant (IK answered with the closest pose).
    pub clamped: [bool; 6],
    /// Legs whose foot is on the ground by the gait's reckoning: in stance, or (reactive gait)
    /// its swing ended early on the ground.
    pub grounded: [bool; 6],
}

/// A leg that cannot take a gait's stance: the standing foot position or the swing apex above it
/// is out of its reach.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct StanceError {
    /// Index of the leg (in [`crate::robot::LEG_NAMES`] order).
    pub leg: usize,
    /// Whether the swing apex failed (the standing position was reached).
    pub lift: bool,
    /// Distance from the closest reachable foot position to the target (m).
    pub miss: f64,
    /// The leg's joint angles at that closest position (at a limit where one binds).
    pub angles: LegAngles,
    message: String,
}

pub struct GaitController {
    spec: Gait,
    offsets: [f64; 6],
    chains: Vec<LegChain>,
    neutral: [DVec3; 6],
    last: [LegAngles; 6],
    /// Each foot sphere's radius, and its link's orientation in the standing pose inverted
    /// (transposed once, not every step), for the rolling offset (see the module's doc).
    radius: [f64; 6],
    /// How far each foot reaches across the ground, its sole's rim included
    /// ([`crate::robot::contact_set::sole_reach`]): what a pit must be wider than to take it.
    sole: [f64; 6],
    rest_inverse: [DMat3; 6],
    rolling: bool,
    /// The standing pose's angles per leg: the branch (knee bent the usual way) a solve that
    /// misses its target starts again from (see [`solve_on_branch`]).
    home: [LegAngles; 6],
    /// The forward kinematics of each leg's last answer (`last`), which its next solve starts
    /// from ([`LegChain::solve_warm`]) and its rolling offset reads.
    warm_last: [Option<IkWarm>; 6],
    /// How far each foot's standing target may be lowered and raised (m) and stay within the
    /// leg's reach with room to spare and, raised, to lift a step (see [`Self::levelling`]), at
    /// the stance's middle and its two ends ([`STANCE_TRACK`]).
    vertical_room: [[(f64, f64); 3]; 6],
    /// The reactive gait's state, when on (see [`super::reactive`]).
    reactive: Option<Reactive>,
    /// The body's lean on a slope ([`super::lean`]): none in a controller for the nominal
    /// cycle ([`Self::for_cycle`]), and nothing leaned until gravity is felt off the body's z.
    lean: Option<Lean>,
    /// How far each leg's target gives way to the force it feels, when on (see
    /// [`super::compliance`]).
    compliance: Option<Compliance>,
    /// Perceptive planning per leg ([`Self::targets_on`]): the foothold shift (body frame,
    /// horizontal) of its stance, the one chosen for the swing under way, the ground its foot
    /// lifted off (in `ground`'s units; NaN before the first stance), and whether it swings.
    /// With each foothold, how far its foot's sole rests above the ground under its centre
    /// ([`foothold::resting_ground`]; zero off edges): read once per swing, for where it lands.
    foothold: [DVec3; 6],
    next_foothold: [DVec3; 6],
    rim: [f64; 6],
    next_rim: [f64; 6],
    stance_ground: [f64; 6],
    swinging: [bool; 6],
    /// Where the feet are (body frame, as `ground`'s points), when known: a stance foot stands
    /// on the ground under it, not under its planned point ([`Self::feet_at`]).
    feet_at: Option<[DVec3; 6]>,
    /// The last planned foot points and their gait time, for the bound on a target's speed
    /// ([`super::slew`]), and that bound at the gait's stride, which every shorter stride has
    /// too ([`slew::speed_limit`]): the walk's, not computed again for each leg every step.
    /// Before any, the neutral points: where the robot is set down ([`Self::settling_on`]).
    last_planned: [DVec3; 6],
    last_time: Option<f64>,
    nominal_speed_limit: f64,
    /// The fastest each joint's target may move (rad/s, at the gait's nominal stride:
    /// [`slew::joint_speed_limit`] of the joints' nominal rates, taken once, not every step)
    /// and the last targets given.
    joint_speed_limit: [LegAngles; 6],
    last_angles: [LegAngles; 6],
    /// The body's contact spheres ([`crate::robot::Link::contacts`]) as the point under each
    /// (body frame, z = 0) and how far its bottom stands above the ground the feet stand on, and
    /// half the least of those, the clearance the body keeps ([`Self::body_offset`]). Empty when
    /// the body has no clearance to keep.
    belly: Vec<(DVec3, f64)>,
    belly_margin: f64,
}

/// A foot's points over a stance: the middle, where it lands and where it lifts
/// ([`STANCE_TRACK`]).
pub type StanceTrack = [DVec3; 3];

/// The share of a leg's vertical reach from its standing target that levelling may use: the rest
/// is left for the stride, the servos' sag and the reach's own curvature.
const LEVELLING_SHARE: f64 = 0.7;

/// Where along a forward stance the vertical room is measured and levelling checks it, in
/// strides forward of the neutral point: the middle, where the foot lands and where it lifts.
/// A leg stretched fore or aft reaches less far down than at its neutral point, and on a slope
/// the ground under the downhill end of the track is the lowest: levelled by the middle alone,
/// PhantomX levelled 5° in full, its rear feet's targets at the end of each stance were 12.6 mm
/// out of reach (perceptive, 18 906 steps out of reach), and those feet took no load and slid
/// 0.75 m.
const STANCE_TRACK: [f64; 3] = [0.0, 0.5, -0.5];

/// The share of a leg's vertical reach that levelling may use at the ends of [`STANCE_TRACK`]:
/// there the stride is taken already, and the foot is on the ground (no step's lift to keep);
/// what is left is for the servos' sag and the reach's curvature.
const TRACK_END_SHARE: f64 = 0.9;

/// Starting guesses for the standing pose's inverse kinematics, tried in turn: knee bent one way,
/// the other way, straight, and the two with the femur down (on the three joints that place the
/// foot; a redundant leg's others at rest).
const STANDING_GUESSES: [[f64; 3]; 5] = [
    [0.0, -0.3, 1.2],
    [0.0, 0.3, -1.2],
    [0.0, 0.0, 0.0],
    [0.0, -0.3, -1.2],
    [0.0, 0.3, 1.2],
];

/// Of two standing answers that reach, the one whose joints stand higher by more than this (m)
/// is the knee up; nearer, the two are one pose found twice, and the earlier guess is kept.
const KNEE_TOLERANCE: f64 = 1e-6;

/// For a robot whose legs have joints held still: how to drive them (they may reach what the
/// three driven joints cannot).
fn held_hint(model: &RobotModel) -> &'static str {
    if model.held.iter().any(|h| h.on_leg.is_some()) {
        "; the legs' extra joints are held still: `redundant_legs = \"driven\"` in the robot file drives them too"
    } else {
        ""
    }
}

/// A centring shift smaller than this (m) is not applied (a symmetric robot's rounding).
const CENTRING_TOLERANCE: f64 = 1e-6;

/// The robot's centre of mass in the body frame with its legs at `angles`.
fn centre_of_mass(model: &RobotModel, angles: &[LegAngles; 6]) -> DVec3 {
    model.centre_of_mass(&model.link_poses(&model.pose_from_legs(angles)))
}

/// Instants of a cycle at which the support margin is measured ([`GaitController::support_margin`]).
const SUPPORT_SAMPLES: usize = 64;

/// Farther than this from its target (m), an IK answer counts as clamped.
pub const REACH_TOLERANCE: f64 = 1e-4;

impl GaitController {
    /// Builds the controller and checks that the legs reach the standing pose and the swing apex.
    pub fn new(model: &RobotModel, spec: Gait) -> Result<Self, StanceError> {
        let mut controller = Self::for_cycle(model, spec)?;
        controller.vertical_room = controller.measured_vertical_room();
        controller.joint_speed_limit = joint_speed_limits(controller.nominal_joint_speeds());
        controller.lean = Some(controller.measured_lean(model));
        Ok(controller)
    }

    /// The controller of [`Self::new`] without the two bounds only a walk needs, which take
    /// thousands of inverse kinematics solves: no vertical room for levelling (nor for the
    /// reactive gait's searches) and no bound on a joint target's rate. What the stance fit
    /// samples the nominal cycle with ([`super::margins`]), hundreds of candidates at a time: on
    /// legs with redundant joints, solved iteratively, the bounds took most of a fit.
    pub(super) fn for_cycle(model: &RobotModel, spec: Gait) -> Result<Self, StanceError> {
        let chains: Vec<LegChain> = model
            .legs
            .iter()
            .map(|leg| LegChain::new(model, leg))
            .collect();
        let mut neutral = [DVec3::ZERO; 6];
        let mut last: [LegAngles; 6] =
            std::array::from_fn(|k| LegAngles::zeros(chains[k].joint_count()));
        // the stance is measured from the hips' plane, not from the base link's origin, which a
        // URDF may put anywhere
        let hips = model.hips_plane();
        for (k, chain) in chains.iter().enumerate() {
            let leg = &model.legs[k];
            let reach = spec.reach;
            let yaw = chain.rest_yaw() + splay_turn(k) * spec.splay;
            let hip = chain.hip();
            neutral[k] = DVec3::new(
                hip.x + reach * yaw.cos(),
                hip.y + reach * yaw.sin(),
                hips - spec.stance_height + leg.foot.radius,
            );
            // every guess solved: of the answers that reach, the one whose knee stands highest
            // (an insect's stance, femur up and tibia down), else the closest. URDFs turn their
            // joints either way, so no one guess is the knee up on every robot: the first that
            // reached stood pcrnet's legs and one side of twwawy's and MushroomRL's knee down
            let mut guess = chain.solve(neutral[k], chain.from_three(STANDING_GUESSES[0]));
            let mut height = chain.joints_height(guess.angles);
            for &other in &STANDING_GUESSES[1..] {
                let other = chain.solve(neutral[k], chain.from_three(other));
                let reach = (
                    other.error <= REACH_TOLERANCE,
                    guess.error <= REACH_TOLERANCE,
                );
                let other_height = chain.joints_height(other.angles);
                let better = match reach {
                    (true, true) => other_height > height + KNEE_TOLERANCE,
                    (true, false) => true,
                    (false, true) => false,
                    (false, false) => other.error < guess.error,
                };
                if better {
                    (guess, height) = (other, other_height);
                }
            }
            if guess.error > REACH_TOLERANCE {
                return Err(StanceError {
                    leg: k,
                    lift: false,
                    miss: guess.error,
                    angles: guess.angles,
                    message: format!(
                        "leg {} cannot reach its standing foot position {:?} (stance_height {} m, reach {reach:.3} m): missed by {:.1} mm{}",
                        leg.name,
                        neutral[k].to_array(),
                        spec.stance_height,
                        guess.error * 1e3,
                        held_hint(model)
                    ),
                });
            }
            last[k] = guess.angles;
        }
        // the feet's centroid under the centre of mass, so that every support polygon of the
        // gait holds the centre of mass as deep inside as the stance allows (a leg mounted ahead
        // of its hip, e.g. with an offset femur, would otherwise leave it at a tripod's edge)
        let shift = centre_of_mass(model, &last).truncate()
            - neutral.iter().map(|n| n.truncate()).sum::<glam::DVec2>() / 6.0;
        if shift.length() > CENTRING_TOLERANCE {
            for (k, chain) in chains.iter().enumerate() {
                neutral[k] += shift.extend(0.0);
                let moved = chain.solve(neutral[k], last[k]);
                if moved.error > REACH_TOLERANCE {
                    return Err(StanceError {
                        leg: k,
                        lift: false,
                        miss: moved.error,
                        angles: moved.angles,
                        message: format!(
                            "leg {} cannot reach its standing foot position {:?} (stance_height {} m, reach {:.3} m, centred under the centre of mass): missed by {:.1} mm",
                            model.legs[k].name,
                            neutral[k].to_array(),
                            spec.stance_height,
                            spec.reach,
                            moved.error * 1e3
                        ),
                    });
                }
                last[k] = moved.angles;
            }
        }
        for (k, chain) in chains.iter().enumerate() {
            let leg = &model.legs[k];
            let apex = neutral[k] + DVec3::new(0.0, 0.0, spec.step_height);
            let lifted = chain.solve(apex, last[k]);
            if lifted.error > REACH_TOLERANCE {
                return Err(StanceError {
                    leg: k,
                    lift: true,
                    miss: lifted.error,
                    angles: lifted.angles,
                    message: format!(
                        "leg {} cannot lift its foot {} m (step_height) above the stance: missed by {:.1} mm",
                        leg.name,
                        spec.step_height,
                        lifted.error * 1e3
                    ),
                });
            }
        }
        let radius = std::array::from_fn(|k| model.legs[k].foot.radius);
        let sole = std::array::from_fn(|k| crate::robot::contact_set::sole_reach(model, k));
        let rest = std::array::from_fn(|k| chains[k].foot_rotation(last[k]).transpose());
        let feet_ground = hips - spec.stance_height;
        let above = |c: &ContactSphere| c.center.z - c.radius - feet_ground;
        let body = &model.links[0].contacts;
        let clearance = body.iter().map(above).fold(f64::INFINITY, f64::min);
        let belly = if clearance > 0.0 && clearance.is_finite() {
            body.iter()
                .map(|c| (c.center.with_z(0.0), above(c)))
                .collect()
        } else {
            Vec::new()
        };
        let nominal_speed_limit = slew::speed_limit(&spec, spec.stride_length);
        Ok(GaitController {
            offsets: spec.offsets,
            spec,
            chains,
            neutral,
            last,
            radius,
            sole,
            rest_inverse: rest,
            rolling: true,
            home: last,
            warm_last: [None; 6],
            vertical_room: [[(0.0, 0.0); 3]; 6],
            reactive: None,
            lean: None,
            compliance: None,
            foothold: [DVec3::ZERO; 6],
            next_foothold: [DVec3::ZERO; 6],
            rim: [0.0; 6],
            next_rim: [0.0; 6],
            stance_ground: [f64::NAN; 6],
            swinging: [false; 6],
            feet_at: None,
            last_planned: neutral,
            last_time: None,
            nominal_speed_limit,
            joint_speed_limit: joint_speed_limits(last.map(|q| {
                let mut infinite = q;
                infinite.fill(f64::INFINITY);
                infinite
            })),
            last_angles: last,
            belly,
            belly_margin: 0.5 * clearance,
        })
    }

    /// How far each foot's standing target may be lowered and raised and stay within the leg's
    /// reach ([`Self::levelling`]), at each point of [`STANCE_TRACK`]: the farthest a target
    /// moves along z from the standing one and is reached (bisected), times [`LEVELLING_SHARE`]
    /// and, raised, less a step height; at the track's ends times [`TRACK_END_SHARE`].
    fn measured_vertical_room(&self) -> [[(f64, f64); 3]; 6] {
        let spec = &self.spec;
        let span = 2.0 * spec.reach.max(spec.stance_height) + spec.step_height;
        std::array::from_fn(|k| {
            STANCE_TRACK.map(|along| {
                let start = self.neutral[k] + DVec3::X * along * spec.stride_length;
                let reach = |dz: f64| {
                    let (mut lo, mut hi, mut guess) = (0.0, dz, self.last[k]);
                    for _ in 0..30 {
                        let mid = 0.5 * (lo + hi);
                        let answer = self.chains[k].solve(start + DVec3::Z * mid, guess);
                        if answer.error <= REACH_TOLERANCE {
                            (lo, guess) = (mid, answer.angles);
                        } else {
                            hi = mid;
                        }
                    }
                    lo.abs()
                };
                let (share, lift) = if along == 0.0 {
                    (LEVELLING_SHARE, spec.step_height)
                } else {
                    (TRACK_END_SHARE, 0.0)
                };
                let down = share * reach(-span);
                let up = (share * reach(span) - lift).max(0.0);
                (down, up)
            })
        })
    }

    /// The lean on slopes ([`super::lean`]) for this stance: the centre of mass's height over the
    /// feet's ground, the support's margin around it, the feet's horizontal room, and how far
    /// the body may crouch — the least room any leg has to fold up along its track (the
    /// levelling's share of it), and no lower than the body's clearance allows
    /// ([`Self::body_offset`]'s margin).
    fn measured_lean(&self, model: &RobotModel) -> Lean {
        let (centre, height) = self.centre_over_feet(model);
        let folds = self
            .vertical_room
            .iter()
            .flatten()
            .map(|&(_, up)| up)
            .fold(f64::INFINITY, f64::min);
        let crouch = if self.belly.is_empty() {
            folds
        } else {
            folds.min(self.belly_margin)
        };
        Lean::new(
            height,
            self.support_margin(centre.truncate()),
            self.measured_horizontal_room(),
            crouch,
        )
    }

    /// The standing centre of mass (body frame) and its height over the feet's ground (m).
    fn centre_over_feet(&self, model: &RobotModel) -> (DVec3, f64) {
        let centre = centre_of_mass(model, &self.last);
        let ground = (0..6)
            .map(|k| self.neutral[k].z - self.radius[k])
            .sum::<f64>()
            / 6.0;
        (centre, centre.z - ground)
    }

    /// The steepest tilt, any way, on which the gait's walk on level ground keeps its centre of
    /// mass's plumb line inside every support polygon of its cycle (rad): the support margin's
    /// least way m over the centre of mass's height h above the feet, atan(m / h) (the lean's
    /// plumb line, [`super::lean`], meets the feet's plane h·tan θ off on a tilt θ). 0 for a
    /// gait that leaves its centre of mass outside some support on level ground.
    pub(super) fn static_tilt(&self, model: &RobotModel) -> f64 {
        let (centre, height) = self.centre_over_feet(model);
        let m = self.support_margin(centre.truncate());
        let least = m.back.min(m.fore).min(m.right).min(m.left).max(0.0);
        least.atan2(height.max(f64::MIN_POSITIVE))
    }

    /// How far all six stance tracks ([`STANCE_TRACK`]) may move together along each of the
    /// body's horizontal axes and every point stay within its leg's reach, for the lean
    /// ([`super::lean`]): per leg the farthest move that reaches all three points (bisected),
    /// the least over the legs, times [`LEVELLING_SHARE`] (the rest for the levelling, the
    /// stride's lift and the servos' sag).
    fn measured_horizontal_room(&self) -> HorizontalRoom {
        let spec = &self.spec;
        let span = 2.0 * spec.reach.max(spec.stance_height);
        let room = |direction: DVec3| {
            (0..6)
                .map(|k| {
                    let track = STANCE_TRACK
                        .map(|along| self.neutral[k] + DVec3::X * along * spec.stride_length);
                    let (mut lo, mut hi) = (0.0, span);
                    for _ in 0..20 {
                        let mid = 0.5 * (lo + hi);
                        let reached = track.iter().all(|&p| {
                            self.chains[k]
                                .solve(p + direction * mid, self.last[k])
                                .error
                                <= REACH_TOLERANCE
                        });
                        if reached {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    lo
                })
                .fold(f64::INFINITY, f64::min)
                * LEVELLING_SHARE
        };
        HorizontalRoom {
            back: room(DVec3::NEG_X),
            fore: room(DVec3::X),
            right: room(DVec3::NEG_Y),
            left: room(DVec3::Y),
        }
    }

    /// How far the centre of mass's plumb line may move from `centre` (body frame) along each of
    /// the body's horizontal axes and stay inside every support polygon of a cycle at the
    /// gait's nominal stride on level ground (the stance feet's points), for the lean
    /// ([`super::lean`]): the least over [`SUPPORT_SAMPLES`] instants.
    fn support_margin(&self, centre: DVec2) -> HorizontalRoom {
        let spec = &self.spec;
        let stride = DVec3::NEG_X * spec.stride_length;
        let directions = [DVec2::NEG_X, DVec2::X, DVec2::NEG_Y, DVec2::Y];
        let mut margin = [f64::INFINITY; 4];
        let mut points = Vec::with_capacity(6);
        for i in 0..SUPPORT_SAMPLES {
            let t = spec.period * i as f64 / SUPPORT_SAMPLES as f64;
            points.clear();
            for k in 0..6 {
                if let LegPhase::Stance(s) =
                    leg_phase(t, spec.period, spec.duty_factor, self.offsets[k])
                {
                    points.push((self.neutral[k] + stride * (s - 0.5)).truncate());
                }
            }
            let hull = lean::convex_hull(&points);
            for (m, &direction) in margin.iter_mut().zip(&directions) {
                *m = m.min(lean::support_margin(&hull, centre, direction));
            }
        }
        let [back, fore, right, left] = margin;
        HorizontalRoom {
            back,
            fore,
            right,
            left,
        }
    }

    /// Leg `k`'s vertical room ([`Self::measured_vertical_room`]) less the lean's crouch
    /// ([`super::lean`]): crouched by c, a target has c more to go down and c less up. What the
    /// body's offset and the blind search go by; the levelling keeps the stance's own.
    fn room_left(&self, k: usize) -> [(f64, f64); 3] {
        let crouch = self.lean().z;
        self.vertical_room[k].map(|(down, up)| (down + crouch, (up - crouch).max(0.0)))
    }

    /// Each joint's fastest rate (rad/s) over one cycle of the gait at its nominal speed on
    /// level ground, for the bound on a joint target's rate ([`slew`]); the controller's state
    /// is as new afterwards.
    fn nominal_joint_speeds(&mut self) -> [LegAngles; 6] {
        let last = self.last;
        let command = VelocityCommand {
            forward: self.spec.nominal_speed(),
            ..Default::default()
        };
        let samples = 400;
        let h = self.spec.period / samples as f64;
        let mut speed = last.map(|q| LegAngles::zeros(q.len()));
        let mut before = self.targets(0.0, command, 1.0).joint_angles;
        for i in 1..=samples {
            let now = self.targets(i as f64 * h, command, 1.0).joint_angles;
            for (k, leg) in speed.iter_mut().enumerate() {
                for (j, v) in leg.iter_mut().enumerate() {
                    *v = v.max((now[k][j] - before[k][j]).abs() / h);
                }
            }
            before = now;
        }
        (self.last, self.last_time) = (last, None);
        self.last_planned = self.neutral;
        self.last_angles = last;
        speed
    }

    /// Perceptive: where the feet's centres are now (body frame, as the points of
    /// [`Self::targets_on`]'s `ground`), so that a stance foot does not follow its planned
    /// point over an edge it does not stand on ([`foothold::stance_ground`]), nor hang at its
    /// planned ground over a pit it stands over ([`foothold::standing_ground`]).
    pub fn feet_at(&mut self, feet: [DVec3; 6]) {
        self.feet_at = Some(feet);
    }

    /// Turns the feet's rolling offset on or off (on after [`Self::new`]; the fit and its
    /// reports plan the stance without it: see the module's doc).
    pub fn with_rolling_feet(mut self, on: bool) -> Self {
        self.rolling = on;
        self
    }

    /// Turns the reactive gait on (`Some`: its state from the start) or off.
    pub fn set_reactive(&mut self, reactive: Option<Reactive>) {
        self.reactive = reactive;
    }

    /// Turns leg compliance on (`Some`: its state from the start) or off.
    pub fn set_compliance(&mut self, compliance: Option<Compliance>) {
        self.compliance = compliance;
    }

    /// The ground's forces on the legs and the body over the last step (body frame), and each
    /// leg's joints' largest distance from the gait's angles (rad), for leg compliance (ignored
    /// when it is off).
    pub fn feel_forces(&mut self, ground: &GroundForces, gaps: &[f64; 6], dt: f64) {
        if let Some(compliance) = &mut self.compliance {
            compliance.feel(ground, gaps, dt);
        }
    }

    /// How fast a loaded leg takes back what it gave way ([`super::compliance`]): its foot at
    /// the landing speed, its joints at the landing speed over the leg's outstretched length.
    /// A gait whose feet do not lift (`step_height = 0`) has no landing speed: its legs are
    /// released over [`super::compliance::RELEASE_TIME`] alone, not held yielded.
    pub fn compliance_release(&self) -> Release {
        let foot_speed = self.landing_speed();
        if foot_speed <= 0.0 {
            return Release::FREE;
        }
        Release {
            joint_speed: std::array::from_fn(|k| foot_speed / self.chains[k].length()),
            foot_speed,
        }
    }

    /// Gravity as the body feels it (body frame, any length: an IMU's reading), for the lean
    /// ([`super::lean`]), one step of `dt` (s).
    pub fn feel_gravity(&mut self, down: DVec3, dt: f64) {
        if let Some(lean) = &mut self.lean {
            lean.follow(down, dt);
        }
    }

    /// The lean on slopes, as measured for this stance ([`super::lean`]); none in a controller
    /// for the nominal cycle.
    pub fn lean_on_slopes(&self) -> Option<&Lean> {
        self.lean.as_ref()
    }

    /// The lean's move of every foot target (body frame, horizontal; [`super::lean`]).
    pub fn lean(&self) -> DVec3 {
        self.lean.as_ref().map_or(DVec3::ZERO, Lean::shift)
    }

    /// The fraction of the way leg `k`'s joint targets are to be sent to its joints' angles
    /// (leg compliance's yield; 0 when it is off).
    pub fn leg_yield(&self, k: usize) -> f64 {
        self.compliance.as_ref().map_or(0.0, |c| c.yielded(k))
    }

    pub fn is_compliant(&self) -> bool {
        self.compliance.is_some()
    }

    pub fn is_reactive(&self) -> bool {
        self.reactive.is_some()
    }

    /// What the feet felt in the last step, for the reactive gait (ignored when it is off).
    pub fn feel(&mut self, feel: [FootFeel; 6]) {
        if let Some(reactive) = &mut self.reactive {
            reactive.feel(feel);
        }
    }

    /// The fastest a perceptive stance target sinks or rises (m/s): the nominal swing's speed at
    /// touch-down ([`slew::landing_speed`]).
    pub fn landing_speed(&self) -> f64 {
        slew::landing_speed(&self.spec)
    }

    pub fn gait(&self) -> &Gait {
        &self.spec
    }

    /// The farthest standing foot's horizontal distance from the body's vertical axis (m): the
    /// lever a turn moves the feet by.
    pub fn turn_radius(&self) -> f64 {
        self.neutral
            .iter()
            .map(|n| n.truncate().length())
            .fold(0.0, f64::max)
    }

    pub fn chains(&self) -> &[LegChain] {
        &self.chains
    }

    /// Joint angles of the standing pose, per leg.
    pub fn standing_angles(&self) -> [LegAngles; 6] {
        std::array::from_fn(|k| self.chains[k].solve(self.neutral[k], self.last[k]).angles)
    }

    /// The share λ ∈ [0, 1] of the ground plane's rise under each foot that the legs can
    /// follow: the largest for which every standing target moved by the terrain's departure
    /// from the plane (`residual`) and λ times the plane's rise (`planar`) stays within its
    /// leg's vertical room. Levelled on a slope the downhill feet reach down and the uphill
    /// ones up; hex18's legs level at most 10.7° (λ < 1 from 11° on), and a target out of
    /// reach is clamped — the IK answers with the stretched leg, the body tips onto it, and on
    /// 30° it slid 0.95 m in 10 s. Levelled by λ instead, the body keeps the rest of the tilt.
    /// On stairs the treads' departure from the flight's plane is followed in full and the
    /// flight's slope by λ: the body pitches with the stairs by the rest.
    ///
    /// Each foot's rise is taken at `standing`, where it would stand ([`Self::standing_footholds`]),
    /// the plane's also half a stride fore and aft of it, where the foot lands and lifts
    /// ([`STANCE_TRACK`]).
    ///
    /// Where no share keeps every point within its room, the share that leaves the worst point
    /// least out of it (the worst excess is convex in λ: a ternary search). Taken as none
    /// before — the body took the plane's whole tilt — hexaross on 12 cm stairs down pitched
    /// 37° and its rear feet stood in the air over the top landing (18° now); and a point
    /// brought into its room only by a larger share, a bound from below, was not read.
    pub fn levelling(
        &self,
        residual: impl Fn(DVec3) -> f64,
        planar: impl Fn(DVec3) -> f64,
        standing: &[DVec3; 6],
    ) -> f64 {
        let stride = DVec3::X * self.spec.stride_length;
        // each point's r + λ·q within [−down, up]: a line in λ against its room
        let mut points = [(0.0, 0.0, 0.0, 0.0); 18];
        for (k, &standing) in standing.iter().enumerate() {
            // the terrain's departure from the plane where the foot stands (the foothold is
            // chosen on one tread: a track's end may lie over the next), the plane's rise at
            // each point of the track
            let r = residual(standing);
            // the stance's own room, not the crouch's (`room_left`): given c more to go down,
            // PhantomX levelled more of 30° than its legs reached (2 720 steps out of reach)
            // and skated 35 % of its walk
            for (i, (&along, &(down, up))) in
                STANCE_TRACK.iter().zip(&self.vertical_room[k]).enumerate()
            {
                points[3 * k + i] = (r, planar(standing + stride * along), down, up);
            }
        }
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for &(r, q, down, up) in &points {
            if q > 0.0 {
                hi = hi.min((up - r) / q);
                lo = lo.max((-down - r) / q);
            } else if q < 0.0 {
                hi = hi.min((down + r) / -q);
                lo = lo.max((r - up) / -q);
            }
        }
        if lo <= hi {
            return hi;
        }
        // no share keeps every point within its room: the one that leaves the worst point
        // least out of it (the worst excess is convex in λ)
        let excess = |share: f64| {
            points
                .iter()
                .map(|&(r, q, down, up)| {
                    let z = r + share * q;
                    (z - up).max(-down - z).max(0.0)
                })
                .fold(0.0, f64::max)
        };
        let (mut a, mut b) = (0.0f64, 1.0f64);
        for _ in 0..40 {
            let (m1, m2) = (a + (b - a) / 3.0, b - (b - a) / 3.0);
            if excess(m1) <= excess(m2) {
                b = m2;
            } else {
                a = m1;
            }
        }
        0.5 * (a + b)
    }

    /// Where each foot would stand at its neutral point on `ground`: off any edge (the foothold
    /// a swing would choose, [`foothold::away_from_edges`]) — a standing point over a stone's pit
    /// would otherwise count the pit's depth in [`Self::levelling`], and every foot's target
    /// would scale down by it.
    pub fn standing_footholds(&self, ground: &impl Fn(DVec3) -> f64) -> [DVec3; 6] {
        std::array::from_fn(|k| self.foothold_near(ground, k, 0.0))
    }

    /// Each foot's stance track on `ground` ([`STANCE_TRACK`]: where it stands, lands and lifts),
    /// each point moved off any edge as a swing would move it ([`Self::standing_footholds`]).
    pub fn track_footholds(&self, ground: &impl Fn(DVec3) -> f64) -> [StanceTrack; 6] {
        std::array::from_fn(|k| STANCE_TRACK.map(|along| self.foothold_near(ground, k, along)))
    }

    /// How far each point of the stance `track` lies under the ground its foot's sole rests on
    /// there ([`foothold::resting_ground`] less the ground under the point): zero but where the
    /// footprint holds an edge it could not be moved off. A track point in a pit narrower than
    /// the sole read as the pit's floor crouched the body into it: WORMS (pads 0.115 m across)
    /// over 2 and 4 cm stepping stones' gaps lowered its body 7.3 cm at once when settling, at
    /// 3.6 m/s, and the run stopped for runaway motion. Read when the tracks are (they are held
    /// while the body moves a little), not every step: an edge test of a wide sole is hundreds
    /// of terrain reads.
    pub fn track_rims(
        &self,
        ground: &impl Fn(DVec3) -> f64,
        track: &[StanceTrack; 6],
    ) -> [[f64; 3]; 6] {
        std::array::from_fn(|k| {
            track[k].map(|p| foothold::resting_ground(ground, p, self.sole[k]) - ground(p))
        })
    }

    /// Leg `k`'s foothold `along` strides forward of its neutral point, off any edge.
    fn foothold_near(&self, ground: &impl Fn(DVec3) -> f64, k: usize, along: f64) -> DVec3 {
        let p = self.neutral[k] + self.lean() + DVec3::X * along * self.spec.stride_length;
        let longest = self.spec.stride_length;
        p + foothold::away_from_edges(ground, p, DVec3::X, self.radius[k], longest)
    }

    /// How far to raise the body over the feet's ground (m; lowered where negative) so that the
    /// terrain under every point of every stance `track` ([`Self::track_footholds`]) stays
    /// within its leg's vertical room: the offset nearest zero that does so, or, where one leg
    /// must reach down farther than another can fold up, the middle of the two. `ground` is the
    /// terrain as the feet follow it ([`Self::levelling`]'s residual and share): the levelling
    /// share scales the plane's rise, but a bump, a dip or a tread is followed in full, and a
    /// leg stretched to the end of its track reaches little further down (PhantomX's front legs
    /// 9.5 mm where they land). On bumps of 10 cm PhantomX's targets were out of reach in 22 577
    /// of 50 000 steps and a foot skated 0.37 m; the body now crouches into the dips, up to
    /// 2.4 cm. Never lowered so far that the body's lowest sphere (`belly`) comes within half
    /// its standing clearance of the ground under it: lowered freely, ant_bot crouched 7.8 cm
    /// to reach a stair's lower tread and sat on the upper one.
    ///
    /// `rims` holds how far each track point's sole rests above the ground under its centre
    /// ([`Self::track_rims`]): a foot wider than a pit stands on its rims, not on its floor.
    pub fn body_offset(
        &self,
        ground: impl Fn(DVec3) -> f64,
        track: &[StanceTrack; 6],
        rims: &[[f64; 3]; 6],
    ) -> f64 {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for (k, points) in track.iter().enumerate() {
            let room = self.room_left(k);
            for ((&p, (down, up)), rim) in points.iter().zip(room).zip(rims[k]) {
                let v = ground(p) + rim;
                lo = lo.max(v - up);
                hi = hi.min(v + down);
            }
        }
        let within = if lo <= hi {
            0.0f64.clamp(lo, hi)
        } else {
            0.5 * (lo + hi)
        };
        // the lean's crouch lowers the body too
        let crouch = self.lean().z;
        self.belly
            .iter()
            .map(|&(p, above)| ground(p) - above + self.belly_margin + crouch)
            .fold(within, f64::max)
    }

    /// The legs' angles standing still, each foot at its neutral point on the ground it rests on
    /// there ([`foothold::resting_ground`]: a pit narrower than the foot holds it on its rims).
    pub fn standing_on(&mut self, ground: impl Fn(DVec3) -> f64) -> [LegAngles; 6] {
        self.stand(ground, None)
    }

    /// [`Self::standing_on`] for a robot standing still before a perceptive walk, `dt` (s) a
    /// step: each foot's target rises or sinks from where the robot was set down (its neutral
    /// point, on level ground) no faster than a swing lands ([`slew::landing_speed`]), as a
    /// walk's stance targets do ([`Self::targets_on`]). Taken at once, the ground ahead of WORMS,
    /// splayed at the top of the ladder's 12 cm stairs down, moved every femur target 0.5 rad
    /// in a step; its legs swung with every foot in the air and threw the 79 kg body at 3.8 m/s
    /// (the run diverged).
    pub fn settling_on(&mut self, ground: impl Fn(DVec3) -> f64, dt: f64) -> [LegAngles; 6] {
        let most = self.landing_speed() * dt;
        self.stand(ground, Some((self.last_planned, most)))
    }

    /// The legs' angles standing, each foot on the ground under its neutral point; with
    /// `bound` = (the feet's last targets, a distance), no foot's target moves more than that
    /// distance up or down from its last.
    fn stand(
        &mut self,
        ground: impl Fn(DVec3) -> f64,
        bound: Option<([DVec3; 6], f64)>,
    ) -> [LegAngles; 6] {
        self.last_time = None;
        let angles = std::array::from_fn(|k| {
            let mut foot = self.neutral[k];
            self.stance_ground[k] = foothold::resting_ground(&ground, foot, self.sole[k]);
            self.rim[k] = self.stance_ground[k] - ground(foot);
            foot.z += self.stance_ground[k];
            if let Some((last, most)) = bound {
                foot.z = foot.z.clamp(last[k].z - most, last[k].z + most);
            }
            self.last_planned[k] = foot;
            let (_, solution) = self.place(k, foot, 0.0, true);
            self.last[k] = solution.angles;
            solution.angles
        });
        self.last_angles = angles;
        angles
    }

    /// Targets at gait time `t` (s since the gait started) for a command on level ground (blind),
    /// with the stride scaled by `blend` ∈ [0, 1] (ramped up at start so the feet leave the
    /// standing pose smoothly).
    pub fn targets(&mut self, t: f64, command: VelocityCommand, blend: f64) -> GaitTargets {
        self.plan(t, command, blend, None::<fn(DVec3) -> f64>)
    }

    /// [`Self::targets`] over known terrain (perceptive). `ground` gives, for a point (body
    /// frame), how far the terrain under it lies above the terrain under the body: following it
    /// the body stays level and at the stance height while the legs reach down a slope or over
    /// a bump. A stance foot stands on the ground under it; a swing is planned over the whole
    /// ground it crosses ([`super::clearance`]), from the ground it lifted off to where it will
    /// land, which is moved off any edge onto the tread ([`super::foothold`]).
    pub fn targets_on(
        &mut self,
        t: f64,
        command: VelocityCommand,
        blend: f64,
        ground: impl Fn(DVec3) -> f64,
    ) -> GaitTargets {
        self.plan(t, command, blend, Some(ground))
    }

    fn plan(
        &mut self,
        t: f64,
        command: VelocityCommand,
        blend: f64,
        ground: Option<impl Fn(DVec3) -> f64>,
    ) -> GaitTargets {
        let stance_time = self.spec.duty_factor * self.spec.period;
        let swing_time = self.spec.period - stance_time;
        let v = DVec3::new(command.forward, command.sideways, 0.0);
        let omega = DVec3::new(0.0, 0.0, command.yaw_rate);
        let mut out = GaitTargets {
            // every leg's written below
            joint_angles: [LegAngles::three([0.0; 3]); 6],
            feet: [DVec3::ZERO; 6],
            phases: [LegPhase::Stance(0.0); 6],
            clamped: [false; 6],
            grounded: [true; 6],
        };
        let phases: [LegPhase; 6] = std::array::from_fn(|k| {
            leg_phase(t, self.spec.period, self.spec.duty_factor, self.offsets[k])
        });
        if let Some(reactive) = &mut self.reactive {
            reactive.follow_feet(&self.neutral, &phases);
        }
        // how far a target may move since the last call (the first one is free)
        let elapsed = self.last_time.map(|last| t - last).filter(|&dt| dt > 0.0);
        self.last_time = Some(t);
        let lean = self.lean();
        // each leg's planned point, then the six placed at once ([`Self::place_each`]), then
        // each leg's joints bounded
        let mut planned = [DVec3::ZERO; 6];
        let mut lifts = [0.0; 6];
        let mut strides = [0.0; 6];
        for (k, &phase) in phases.iter().enumerate() {
            let n = self.neutral[k] + lean;
            // ground displacement under the foot over one stance, seen from the body
            let d = -(v + omega.cross(n)) * stance_time * blend;
            if let Some(ground) = &ground {
                self.choose_foothold(k, phase, n, d, swing_time / stance_time, ground);
            }
            let (mut foot, mut lift, progress) = match phase {
                LegPhase::Stance(s) => (n + d * (s - 0.5), 0.0, 0.0),
                LegPhase::Swing(s) => {
                    let duty = self.spec.duty_factor;
                    let (progress, lift) = swing_profile(self.spec.swing, s, -(1.0 - duty) / duty);
                    let lift = self.spec.step_height * lift;
                    (n + d * (0.5 - progress) + DVec3::Z * lift, lift, progress)
                }
            };
            if ground.is_some() {
                foot += match phase {
                    LegPhase::Stance(_) => self.foothold[k],
                    LegPhase::Swing(_) => self.foothold[k].lerp(self.next_foothold[k], progress),
                };
            }
            out.grounded[k] = phase.is_stance();
            // the room only the reactive gait reads, not taken for every leg of every step
            let down_room = self.reactive.is_some().then(|| self.room_left(k)[0]);
            if let (Some(reactive), Some(down_room)) = (&mut self.reactive, down_room) {
                let base = foot - DVec3::Z * lift;
                let height = reactive.offset(
                    k,
                    base,
                    phase,
                    lift,
                    self.spec.step_height,
                    -d.normalize_or_zero(),
                    down_room,
                );
                let shift = reactive.shift(k, phase, progress, d, stance_time);
                foot =
                    base + DVec3::Z * height + shift + d.normalize_or_zero() * reactive.back_off(k);
                out.grounded[k] = reactive.grounded(k, phase);
                lift = if out.grounded[k] {
                    0.0
                } else {
                    height.max(0.0)
                };
            }
            if let Some(ground) = &ground {
                foot.z += match phase {
                    LegPhase::Stance(_) => {
                        self.stance_ground[k] = match self.feet_at {
                            Some(feet) => {
                                let (r, at) = (self.radius[k], feet[k]);
                                let planned =
                                    self.rim[k] + foothold::stance_ground(ground, foot, at, r);
                                foothold::standing_ground(
                                    ground,
                                    foot,
                                    planned,
                                    at,
                                    r,
                                    self.sole[k],
                                )
                            }
                            None => self.rim[k] + ground(foot),
                        };
                        self.stance_ground[k]
                    }
                    LegPhase::Swing(s) => {
                        let ratio = swing_time / stance_time;
                        // where the foot lifted off and where it will land, seen now: the
                        // ground moves by d over a stance
                        let from = n + d * (0.5 + s * ratio) + self.foothold[k];
                        let to = n - d * (0.5 + (1.0 - s) * ratio) + self.next_foothold[k];
                        let crossed = SwingGround::new(ground, from, to, self.radius[k]);
                        let landing = ground(to) + self.next_rim[k];
                        let lifted = if self.stance_ground[k].is_nan() {
                            ground(from)
                        } else {
                            self.stance_ground[k]
                        };
                        let under = foot - DVec3::Z * lift;
                        clearance::swing_ground(
                            lifted,
                            landing,
                            progress,
                            crossed.envelope(under),
                            s,
                        )
                    }
                };
            }
            if let (Some(dt), Some(_), LegPhase::Stance(_)) = (elapsed, &ground, phase) {
                // perceptive: a standing foot's target sinks or rises no faster than a swing
                // lands ([`slew::landing_speed`])
                let most = self.landing_speed() * dt;
                let last = self.last_planned[k].z;
                foot.z = foot.z.max(last - most).min(last + most);
            }
            let stride = d.length();
            if let Some(dt) = elapsed {
                let limit = if stride <= self.spec.stride_length {
                    self.nominal_speed_limit
                } else {
                    slew::speed_limit(&self.spec, stride)
                };
                foot = slew::limited(self.last_planned[k], foot, limit * dt);
            }
            self.last_planned[k] = foot;
            if let Some(compliance) = &self.compliance {
                foot += compliance.offset(k);
            }
            (planned[k], lifts[k], strides[k]) = (foot, lift, stride);
        }
        let (feet, solutions) = self.place_each(&planned, &lifts, elapsed.is_none());
        for (k, &phase) in phases.iter().enumerate() {
            let (foot, solution, stride) = (feet[k], &solutions[k], strides[k]);
            self.last[k] = solution.angles;
            let mut angles = solution.angles;
            if let Some(dt) = elapsed {
                // a leg solved again from its standing pose may change branch: the joints
                // are bounded too
                let scale = (stride / self.spec.stride_length).max(1.0);
                for (j, angle) in angles.iter_mut().enumerate() {
                    let longest = self.joint_speed_limit[k][j] * scale * dt;
                    let last = self.last_angles[k][j];
                    *angle = angle.clamp(last - longest, last + longest);
                }
            }
            self.last_angles[k] = angles;
            out.joint_angles[k] = angles;
            out.feet[k] = foot;
            out.phases[k] = phase;
            out.clamped[k] = solution.error > REACH_TOLERANCE;
        }
        out
    }

    /// Perceptive: at the start of leg `k`'s swing, where its foot will land, moved off any edge
    /// and out of any pit deeper than the gait's step ([`foothold::away_from_pits_within`]) and
    /// held through the swing; at touch-down, that foothold
    /// becomes the stance's. `ratio` is the swing's time over the stance's.
    fn choose_foothold(
        &mut self,
        k: usize,
        phase: LegPhase,
        n: DVec3,
        d: DVec3,
        ratio: f64,
        ground: &impl Fn(DVec3) -> f64,
    ) {
        match phase {
            LegPhase::Stance(_) if self.swinging[k] => {
                self.swinging[k] = false;
                self.foothold[k] = self.next_foothold[k];
                self.rim[k] = self.next_rim[k];
            }
            LegPhase::Swing(s) if !self.swinging[k] => {
                self.swinging[k] = true;
                // the ground that will be under the touch-down point when the foot lands
                let landing = n - d * (0.5 + (1.0 - s) * ratio);
                let longest = self.spec.stride_length.max(d.length());
                // the leg reaches the foothold through the stance that follows: from where it
                // lands (n − d/2 moved) to where it lifts (n + d/2 moved), on its ground
                let (chain, home) = (&self.chains[k], &self.home[k]);
                let reaches = |shift: DVec3| {
                    let z = n.z + ground(landing + shift);
                    [-0.5, 0.0, 0.5].iter().all(|&along| {
                        let target = (n + d * along + shift).with_z(z);
                        chain.solve(target, home).error <= REACH_TOLERANCE
                    })
                };
                self.next_foothold[k] = foothold::away_from_pits_within(
                    ground,
                    landing,
                    -d,
                    self.radius[k],
                    longest,
                    self.spec.step_height,
                    reaches,
                );
                let there = landing + self.next_foothold[k];
                self.next_rim[k] =
                    foothold::resting_ground(ground, there, self.sole[k]) - ground(there);
            }
            _ => {}
        }
    }

    /// Leg `k`'s pose at `angles` for the load feed-forward into `out`, from its last solve's
    /// forward kinematics when `angles` are that solve's answer ([`LegChain::statics_into`]);
    /// false (`out` untouched) otherwise.
    #[inline]
    pub fn leg_statics(&self, k: usize, angles: &[f64], out: &mut LegStatics) -> bool {
        self.warm_last[k]
            .as_ref()
            .is_some_and(|warm| self.chains[k].statics_into(warm, angles, out))
    }

    /// Leg `k`'s foot centre target and joint angles for the planned point `planned`, `lift`
    /// above the ground: with rolling on, moved on by the rolling offset of the point under it
    /// on the ground (see the module's doc).
    ///
    /// The offset's turn Δφ is the foot link's at the answer for the path on the ground moved
    /// on by the offset, read to first order from the leg's last answer, a step's motion away
    /// ([`LegChain::foot_turn_map`]): for a standing foot the pose the leg is sent to, for a
    /// swinging one the pose without the lift, exactly as the lift goes to zero at touch-down.
    /// Solving the leg for its path on the ground instead (a second IK solve per leg, until
    /// 2026-12-03) read a standing foot's turn a rolling offset away from its pose (the front
    /// and rear feet's scrub 9 % of the unrolled one's, now 1.5 %), and took 5.2k instructions
    /// more of a step of hex18's walk (209.8k against 204.7k).
    ///
    /// `fresh`: the last answer is not a step's motion away (the first targets of a walk, or
    /// of a stance set down, half a stride from the standing pose): the offset is read again at
    /// each answer and the leg solved again, until the offset moves by less than
    /// [`FRESH_TOLERANCE`] (at most [`FRESH_PASSES`] times).
    fn place(&mut self, k: usize, planned: DVec3, lift: f64, fresh: bool) -> (DVec3, IkSolution) {
        let chain = &self.chains[k];
        let home = &self.home[k];
        let warm_last = &mut self.warm_last[k];
        if !self.rolling {
            return (
                planned,
                solve_on_branch(chain, planned, &self.last[k], warm_last, home),
            );
        }
        let grounded = planned - DVec3::Z * lift;
        let rolled = self.rolling_offset(k, grounded, &self.last[k]);
        let target = planned + rolled;
        let warm_last = &mut self.warm_last[k];
        let solution = solve_on_branch(chain, target, &self.last[k], warm_last, home);
        self.placed(k, planned, grounded, rolled, solution, fresh)
    }

    /// [`Self::place`] of the six legs, `planned` and `lifts` theirs: the same arithmetic leg by
    /// leg, in stages across the legs — the rolling offsets ([`Self::rolling_offsets`]), then
    /// the solves from the last answers in turns ([`kinematics::solve_warm_each`]), then each
    /// leg's solve again from its standing pose where it missed, and a fresh start's passes —
    /// so that one leg's part computes while another's waits on its latencies. The feet's
    /// targets and the legs' answers.
    fn place_each(
        &mut self,
        planned: &[DVec3; 6],
        lifts: &[f64; 6],
        fresh: bool,
    ) -> ([DVec3; 6], [IkSolution; 6]) {
        // (the arrays built as they are filled, not zeroed first)
        let (mut feet, grounded, rolled) = if self.rolling {
            let grounded: [DVec3; 6] = std::array::from_fn(|k| planned[k] - DVec3::Z * lifts[k]);
            let rolled = self.rolling_offsets(&grounded);
            let feet = std::array::from_fn(|k| planned[k] + rolled[k]);
            (feet, grounded, rolled)
        } else {
            // (not planned + 0 without rolling: a −0 coordinate would become +0)
            (*planned, [DVec3::ZERO; 6], [DVec3::ZERO; 6])
        };
        let mut solutions =
            kinematics::solve_warm_each(&self.chains, &feet, &self.last, &mut self.warm_last);
        for k in 0..6 {
            let (chain, home) = (&self.chains[k], &self.home[k]);
            solutions[k] = or_from_home(chain, feet[k], solutions[k], home);
            if self.rolling && fresh {
                (feet[k], solutions[k]) =
                    self.placed(k, planned[k], grounded[k], rolled[k], solutions[k], fresh);
            }
        }
        (feet, solutions)
    }

    /// Leg `k`'s rolling offset (horizontal) for the point `grounded` on the ground, read from
    /// its last answer's pose `last` (and the forward kinematics the solve left with it).
    fn rolling_offset(&self, k: usize, grounded: DVec3, last: &LegAngles) -> DVec3 {
        let (rotation, foot, b) = self.chains[k].foot_turn_map(self.warm_last[k].as_ref(), last);
        let phi = DQuat::from_mat3(&(rotation * self.rest_inverse[k])).to_scaled_axis();
        offset_for_turn(phi, b, grounded - foot, self.radius[k])
    }

    /// [`Self::rolling_offset`] of the six legs at their last answers, in stages across the
    /// legs — each leg's turn map ([`LegChain::foot_turn_map`]), then each one's turn as a
    /// quaternion, then as a rotation vector, then each one's offset — so that one leg's
    /// divisions, square roots and `atan2` overlap another's.
    fn rolling_offsets(&self, grounded: &[DVec3; 6]) -> [DVec3; 6] {
        let mut turned = [DMat3::ZERO; 6];
        let mut feet = [DVec3::ZERO; 6];
        let mut maps = [DMat3::ZERO; 6];
        for k in 0..6 {
            let (rotation, foot, b) =
                self.chains[k].foot_turn_map(self.warm_last[k].as_ref(), &self.last[k]);
            (turned[k], feet[k], maps[k]) = (rotation * self.rest_inverse[k], foot, b);
        }
        let quats = turned.map(|turned| DQuat::from_mat3(&turned));
        let phis = quats.map(DQuat::to_scaled_axis);
        std::array::from_fn(|k| {
            offset_for_turn(phis[k], maps[k], grounded[k] - feet[k], self.radius[k])
        })
    }

    /// Leg `k`'s foot centre target and answer, rolling, from its first `solution` for the
    /// planned point moved on by the offset `rolled`: with `fresh` (see [`Self::place`]) the
    /// offset read again at each answer and the leg solved again until it holds.
    #[inline]
    fn placed(
        &mut self,
        k: usize,
        planned: DVec3,
        grounded: DVec3,
        mut rolled: DVec3,
        mut solution: IkSolution,
        fresh: bool,
    ) -> (DVec3, IkSolution) {
        // a pose far from the last (the first targets), the first-order turn read again at
        // each answer until it holds
        for _ in 0..if fresh { FRESH_PASSES } else { 0 } {
            let next = self.rolling_offset(k, grounded, &solution.angles);
            let change = next.distance(rolled);
            rolled = next;
            let (chain, home) = (&self.chains[k], &self.home[k]);
            let warm_last = &mut self.warm_last[k];
            solution = solve_on_branch(chain, planned + rolled, &solution.angles, warm_last, home);
            if change < FRESH_TOLERANCE {
                break;
            }
        }
        (planned + rolled, solution)
    }
}

/// The rolling offset (horizontal) of a foot of `radius` whose link has turned by `phi`, `b` the
/// map from a small motion of the foot to the link's turn ([`LegChain::foot_turn_map`]) and
/// `to_ground` the foot's motion to the point on the ground it is planned for. The offset
/// o = r·(Δφ × ẑ), Δφ the foot link's turn at the answer for the path's point G moved by o: from
/// a pose with the foot at F and turn φ, to first order Δφ = φ + J_L⁻¹·B·(G + o − F), a linear
/// equation in o's two components (its own turn moves the offset by a tenth or so: were it near
/// a whole one, as on no leg built to walk, it is read without it).
#[inline]
fn offset_for_turn(phi: DVec3, b: DMat3, to_ground: DVec3, radius: f64) -> DVec3 {
    // a turn ε of the link adds J_L⁻¹·ε to its rotation vector φ (SO(3)'s inverse left
    // Jacobian, I − ½[φ]× + [φ]×²/12 to second order in φ), not ε itself
    let j_inv = |e: DVec3| {
        let pe = phi.cross(e);
        e - 0.5 * pe + phi.cross(pe) / 12.0
    };
    let roll = |turn: DVec3| DVec2::new(turn.y, -turn.x) * radius;
    let p = roll(phi + j_inv(b * to_ground));
    let m = DMat2::from_cols(roll(j_inv(b.x_axis)), roll(j_inv(b.y_axis)));
    let a = DMat2::IDENTITY - m;
    let offset = if a.determinant() > 0.5 {
        a.inverse() * p
    } else {
        p
    };
    offset.extend(0.0)
}

/// Which way [`Gait::splay`] turns leg `k`'s standing foot about its hip ([`crate::robot::LEG_NAMES`]
/// order: lf, lm, lr, rf, rm, rr): a front foot towards the front (clockwise on the left,
/// counter-clockwise on the right, seen from above), a rear one towards the rear, a middle one
/// not at all.
fn splay_turn(k: usize) -> f64 {
    let left = if k < 3 { 1.0 } else { -1.0 };
    match k % 3 {
        0 => -left,
        2 => left,
        _ => 0.0,
    }
}

/// Each joint's bound on its target's rate ([`slew::joint_speed_limit`]) from its leg's joints'
/// fastest rates `speeds`.
fn joint_speed_limits(speeds: [LegAngles; 6]) -> [LegAngles; 6] {
    speeds.map(|leg| {
        let mut limits = leg;
        for (j, limit) in limits.iter_mut().enumerate() {
            *limit = slew::joint_speed_limit(&leg, j);
        }
        limits
    })
}

/// The most solves more a leg's first targets take to read the rolling offset at the pose it
/// moves the foot to ([`GaitController::place`]), and the change of offset (m) they stop at: a
/// hundredth of the IK's tolerance, so that the next step's, read from it, goes on without a
/// jump (a micrometre in the 0.1 ms of a test's steps is 10 mm/s of scrub).
const FRESH_PASSES: usize = 8;
const FRESH_TOLERANCE: f64 = 0.01 * IK_TOLERANCE;

/// The leg's joint angles for `target` from its last answer `last`
/// ([`LegChain::solve_warm`]); where that misses the target, solved again from the standing
/// pose `home`, and the closer answer kept. A solve started from the last answer follows it
/// along: after a target out of reach, the closest pose may be on another branch — ant_bot's
/// rear leg, its femur against its upper limit and its knee folded past 2 rad, where the
/// target's pull holds the femur at the limit — and from there it misses targets the usual
/// branch reaches (perceptive over 2 cm gaps: 6 cm off, 24 646 steps out of reach in 25 s, a
/// foot that skated 0.58 m, where blind had none). The joints' slew bound in the plan then
/// takes the leg back over several steps. Both solves keep to their start's branch
/// ([`LegChain::solve_on_branch`]): a leg reaches another branch only by this restart.
fn solve_on_branch(
    chain: &LegChain,
    target: DVec3,
    last: &LegAngles,
    warm: &mut Option<IkWarm>,
    home: &LegAngles,
) -> IkSolution {
    let followed = chain.solve_warm(target, last, warm);
    or_from_home(chain, target, followed, home)
}

/// [`solve_on_branch`]'s answer from `followed`, the solve from the last answer: it, where it
/// reaches `target`; else the leg solved again from its standing pose `home`, and the closer
/// answer kept.
fn or_from_home(
    chain: &LegChain,
    target: DVec3,
    followed: IkSolution,
    home: &LegAngles,
) -> IkSolution {
    if followed.error <= REACH_TOLERANCE {
        return followed;
    }
    let homed = chain.solve_on_branch(target, home);
    if homed.error + REACH_TOLERANCE < followed.error {
        homed
    } else {
        followed
    }
}

/// Horizontal progress (0 → 1) and lift (0 → 1 → 0) through a swing at progress s ∈ [0, 1).
///
/// For the smooth shapes the horizontal progress is the cubic Hermite curve from 0 to 1 whose slope
/// at both ends is `end_slope` = −(1 − duty)/duty: the foot lifts off and touches down moving
/// backwards exactly as the ground does under the body, so it does not skid at touch-down.
fn swing_profile(shape: SwingShape, s: f64, end_slope: f64) -> (f64, f64) {
    use std::f64::consts::PI;
    let matched = || {
        let (s2, s3) = (s * s, s * s * s);
        3.0 * s2 - 2.0 * s3 + end_slope * (2.0 * s3 - 3.0 * s2 + s)
    };
    match shape {
        SwingShape::Sine => (matched(), (PI * s).sin()),
        SwingShape::Cycloid => (matched(), (1.0 - (2.0 * PI * s).cos()) / 2.0),
        SwingShape::Rectangle => {
            let third = 1.0 / 3.0;
            if s < third {
                (0.0, s / third)
            } else if s < 2.0 * third {
                ((s - third) / third, 1.0)
            } else {
                (1.0, (1.0 - s) / third)
            }
        }
    }
}

impl Gait {
    /// The vertical speed (m/s) at which a swinging foot meets level ground: the step height
    /// times the lift's slope at the swing's end over the swing's duration — π·h/T_swing for
    /// the sine, 3·h/T_swing for the rectangle, 0 for the cycloid, which lands softly.
    pub fn touchdown_speed(&self) -> f64 {
        let swing_time = (1.0 - self.duty_factor) * self.period;
        let ds = 1e-6;
        let (_, before) = swing_profile(self.swing, 1.0 - ds, 0.0);
        let (_, end) = swing_profile(self.swing, 1.0, 0.0);
        self.step_height * ((before - end) / ds).max(0.0) / swing_time
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ant_bot's rear left leg, as a perceptive walk over 2 cm gaps left it: femur against its
    /// upper limit, knee folded to 2 rad. Solved from there, a target on its usual stance misses
    /// by 37 mm (the pull towards the target holds the femur at its limit); solved again from the
    /// standing pose, it is reached, and a target out of reach keeps the closer answer.
    #[test]
    fn a_solve_stuck_on_another_branch_starts_again_from_the_standing_pose() {
        let model = ant_bot();
        let chain = LegChain::new(&model, &model.legs[2]);
        let stuck = chain.from_three([-0.0672, 0.55, 2.0073]);
        let home = chain.from_three(STANDING_GUESSES[0]);
        let target = DVec3::new(-0.2613, 0.2139, -0.0765);
        let followed = chain.solve_warm(target, stuck, &mut None);
        assert!(followed.error > 0.03, "{followed:?}");
        let solved = solve_on_branch(&chain, target, &stuck, &mut None, &home);
        assert!(solved.error <= REACH_TOLERANCE, "{solved:?}");
        assert!(solved.angles[1] < 0.5, "{solved:?}");
        // far out of reach: never worse than the followed answer
        let far = DVec3::new(-0.6, 0.4, -0.3);
        let followed = chain.solve_warm(far, stuck, &mut None);
        let solved = solve_on_branch(&chain, far, &stuck, &mut None, &home);
        assert!(solved.error <= followed.error, "{solved:?} {followed:?}");
    }

    /// A target swept out of the leg's reach and back, a millimetre a step, each solve from the
    /// last answer as the gait does: the answer follows it, with no jump from one pose to
    /// another between steps (ant_bot, all six legs, out along 16 directions at three heights
    /// to 15 cm past its standing foot). Near the stretched pose a joint moves as the square
    /// root of the target's motion, 0.2 rad for a millimetre here; before the solve was damped
    /// towards the closest pose and kept from crossing a singular pose, answers here jumped
    /// 1.3 rad between two steps (2.4 rad in a walk over 8 cm stones, traced).
    #[test]
    fn a_target_swept_out_of_reach_and_back_is_followed_without_jumps() {
        let model = ant_bot();
        let (mut worst, mut at) = (0.0_f64, String::new());
        for leg in &model.legs {
            let chain = LegChain::new(&model, leg);
            let home = chain.from_three(STANDING_GUESSES[0]);
            let start = chain.foot_position(home);
            for d in 0..16 {
                let angle = d as f64 * std::f64::consts::TAU / 16.0;
                for dz in [-0.08, 0.0, 0.05] {
                    let way = DVec3::new(angle.cos() * 0.15, angle.sin() * 0.15, dz);
                    let mut last = home;
                    let mut warm = None;
                    for i in (0..=150).chain((0..150).rev()) {
                        let target = start + way * (i as f64 / 150.0);
                        let answer = solve_on_branch(&chain, target, &last, &mut warm, &home);
                        let jump = (0..3)
                            .map(|j| (answer.angles[j] - last[j]).abs())
                            .fold(0.0, f64::max);
                        if jump > worst {
                            worst = jump;
                            at = format!(
                                "{} dir {d} dz {dz} i {i}: {last:?} -> {:?}",
                                leg.name, answer.angles
                            );
                        }
                        last = answer.angles;
                    }
                }
            }
        }
        assert!(worst < 0.3, "an answer jumped {worst:.3} rad: {at}");
    }

    /// The six legs placed in stages ([`GaitController::place_each`]: the rolling offsets, then
    /// the solves in turns) are each leg placed alone ([`GaitController::place`]), bit for bit:
    /// the feet's targets, the answers and the warm state each leg's solve leaves. hex18 and
    /// ant_bot, rolling and not, over targets that circle the standing feet, lift and swing out
    /// of reach and back (ant_bot's legs then start again from their standing pose), with a
    /// fresh start (the rolling offset read again until it holds) now and then.
    #[test]
    fn legs_placed_in_stages_are_each_leg_placed_alone() {
        let spec = crate::gait::tripod_for_tests();
        let mut missed = 0;
        for model in [crate::robot::hex18_for_tests(), ant_bot()] {
            let gait = crate::gait::fit(&model, &spec).unwrap().gait;
            for rolling in [true, false] {
                let controller = || {
                    GaitController::for_cycle(&model, gait.clone())
                        .unwrap()
                        .with_rolling_feet(rolling)
                };
                let (mut staged, mut alone) = (controller(), controller());
                for step in 0..300 {
                    let t = step as f64;
                    let fresh = step % 75 == 0;
                    let reach = 0.01 + 0.2 * (std::f64::consts::PI * t / 300.0).sin().powi(4);
                    let planned: [DVec3; 6] = std::array::from_fn(|k| {
                        let turn = 0.07 * t + k as f64;
                        staged.neutral[k] + reach * DVec3::new(turn.cos(), turn.sin(), 0.0)
                    });
                    let lifts: [f64; 6] =
                        std::array::from_fn(|k| 0.03 * (0.1 * t + k as f64).sin().max(0.0));
                    let planned = std::array::from_fn(|k| planned[k] + DVec3::Z * lifts[k]);
                    let (feet, solutions) = staged.place_each(&planned, &lifts, fresh);
                    for k in 0..6 {
                        let (foot, solution) = alone.place(k, planned[k], lifts[k], fresh);
                        let at = format!("{} leg {k}, step {step}, rolling {rolling}", model.name);
                        let bits = |v: DVec3| v.to_array().map(f64::to_bits);
                        assert_eq!(bits(foot), bits(feet[k]), "{at}");
                        let angles = |s: &IkSolution| -> Vec<u64> {
                            s.angles.iter().map(|a| a.to_bits()).collect()
                        };
                        assert_eq!(angles(&solution), angles(&solutions[k]), "{at}");
                        assert_eq!(
                            solution.error.to_bits(),
                            solutions[k].error.to_bits(),
                            "{at}"
                        );
                        missed += usize::from(solution.error > REACH_TOLERANCE);
                        // as the plan does after placing a leg
                        (alone.last[k], staged.last[k]) = (solution.angles, solutions[k].angles);
                    }
                    let warm = |c: &GaitController| format!("{:?}", c.warm_last);
                    assert_eq!(warm(&alone), warm(&staged), "step {step}");
                }
            }
        }
        assert!(missed > 50, "only {missed} targets out of reach");
    }

    /// ant_bot, from `tests/data/third_party`.
    fn ant_bot() -> RobotModel {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/third_party/ant_bot/ant_bot/urdf/hexapod.urdf"
        );
        crate::robot::load(std::path::Path::new(path)).unwrap()
    }

    /// A splay turns each front foot about its hip towards the front and each rear foot towards
    /// the rear, by the splay and at the same reach; the middle feet stay.
    #[test]
    fn a_splay_turns_the_front_and_rear_feet_towards_the_ends() {
        let (model, gait) = hex18_tripod();
        let straight = GaitController::for_cycle(&model, gait.clone()).unwrap();
        let splay = 20f64.to_radians();
        let splayed = GaitController::for_cycle(&model, Gait { splay, ..gait }).unwrap();
        for k in 0..6 {
            let hip = straight.chains[k].hip().truncate();
            let (before, after) = (
                straight.neutral[k].truncate() - hip,
                splayed.neutral[k].truncate() - hip,
            );
            let turn = before.angle_to(after);
            let forward = after.x - before.x;
            let at = format!("leg {k}: {before} → {after}, turned {turn}");
            assert!((after.length() - before.length()).abs() < 1e-9, "{at}");
            match k % 3 {
                0 => assert!((turn.abs() - splay).abs() < 1e-9 && forward > 0.02, "{at}"),
                2 => assert!((turn.abs() - splay).abs() < 1e-9 && forward < -0.02, "{at}"),
                _ => assert!(turn.abs() < 1e-9, "{at}"),
            }
            assert_eq!(splayed.neutral[k].z, straight.neutral[k].z);
        }
    }

    /// hex18 and the tripod fitted to it.
    fn hex18_tripod() -> (RobotModel, Gait) {
        let model = crate::robot::hex18_for_tests();
        let spec = crate::gait::tripod_for_tests();
        let gait = crate::gait::fit(&model, &spec).unwrap().gait;
        (model, gait)
    }

    /// Levelled on a slope, every point of a stance's track stays within its leg's reach: the
    /// middle, where the foot lands and where it lifts, on hex18 and on PhantomX, whose rear
    /// legs reach down less at the end of their stance than at its middle (levelled by the
    /// middle alone, λ = 1 on 5°: the rear left foot's target there was 12.6 mm out of reach).
    #[test]
    fn levelled_on_a_slope_the_whole_stance_track_is_within_reach() {
        for (model, c) in hex18_and_phantomx() {
            let gait = &c.spec;
            let standing = c.standing_footholds(&|_| 0.0);
            for degrees in [5.0f64, 10.0, 20.0, 30.0] {
                for ascent in [1.0, -1.0] {
                    let rise = move |p: DVec3| ascent * degrees.to_radians().tan() * p.x;
                    let share = c.levelling(|_| 0.0, rise, &standing);
                    assert!(share > 0.0, "{degrees}°: nothing levelled");
                    for (k, &standing) in standing.iter().enumerate() {
                        for along in STANCE_TRACK {
                            let p = standing + DVec3::X * along * gait.stride_length;
                            let target = p + DVec3::Z * share * rise(p);
                            let answer = c.chains[k].solve(target, c.last[k]);
                            assert!(
                                answer.error <= REACH_TOLERANCE,
                                "{}: {degrees}° ({ascent}), λ {share:.3}, leg {k} at {along}: \
                                 out of reach by {:.2} mm",
                                model.name,
                                answer.error * 1e3
                            );
                        }
                    }
                }
            }
        }
    }

    /// Where no share of a flight's slope keeps every foot within its leg's room — hex18's rear
    /// feet 6 cm below what they reach unless the body levels much of a 45° plane, its front
    /// feet out of reach if it levels more than a little — the share is the one that leaves the
    /// worst point least out of reach, not none: levelling none (the body taking the whole
    /// tilt) left hexaross's rear feet in the air over a 12 cm flight's top landing.
    #[test]
    fn where_no_share_fits_the_worst_foot_misses_least() {
        let (model, c) = hex18_and_phantomx().remove(0);
        let standing = c.standing_footholds(&|_| 0.0);
        let down = c
            .vertical_room
            .iter()
            .flatten()
            .map(|r| r.0)
            .fold(0.0, f64::max);
        let residual = move |p: DVec3| if p.x < 0.0 { -(down + 0.06) } else { 0.0 };
        let planar = |p: DVec3| -p.x;
        let share = c.levelling(residual, planar, &standing);
        let stride = DVec3::X * c.spec.stride_length;
        let miss = |share: f64| {
            let mut worst = 0.0f64;
            for (k, &standing) in standing.iter().enumerate() {
                for along in STANCE_TRACK {
                    let p = standing + stride * along;
                    let target = p + DVec3::Z * (residual(p) + share * planar(p));
                    worst = worst.max(c.chains[k].solve(target, c.last[k]).error);
                }
            }
            worst
        };
        let grid = (0..=100)
            .map(|i| miss(i as f64 / 100.0))
            .fold(f64::INFINITY, f64::min);
        println!(
            "{}: λ {share:.3}, the worst foot {:.1} mm out of reach (λ 0: {:.1} mm; the best of a 0.01 grid {:.1} mm)",
            model.name,
            miss(share) * 1e3,
            miss(0.0) * 1e3,
            grid * 1e3
        );
        assert!(share > 0.0, "nothing levelled");
        assert!(miss(share) < miss(0.0));
        assert!(miss(share) < grid + 0.005, "{:.1} mm", miss(share) * 1e3);
    }

    /// hex18 and PhantomX, fitted to the tripod, with their controllers.
    fn hex18_and_phantomx() -> Vec<(RobotModel, GaitController)> {
        let phantomx = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/third_party/phantomx_description/urdf/phantomx.urdf");
        let spec = crate::gait::tripod_for_tests();
        [
            crate::robot::hex18_for_tests(),
            crate::robot::load(&phantomx).unwrap(),
        ]
        .into_iter()
        .map(|model| {
            let gait = crate::gait::fit(&model, &spec).unwrap().gait;
            let c = GaitController::new(&model, gait).unwrap();
            (model, c)
        })
        .collect()
    }

    /// A dip under one foot's landing point deeper than that leg reaches down there (2 mm
    /// more): the body is lowered so that every point of every stance track is reached, the
    /// dip's and the level ground's under the other legs.
    #[test]
    fn a_dip_beyond_a_legs_reach_lowers_the_body() {
        for (model, c) in hex18_and_phantomx() {
            let level = |_: DVec3| 0.0;
            let tracks = c.track_footholds(&level);
            let landing = tracks[0][1];
            // reached from the standing pose through the level track point above it, as the
            // gait's solves follow their last answers
            let reached = |k: usize, target: DVec3| {
                let (from, mut guess) = (target.with_z(c.neutral[k].z), c.last[k]);
                (1..=40).all(|i| {
                    let answer = c.chains[k].solve(from.lerp(target, i as f64 / 40.0), guess);
                    guess = answer.angles;
                    answer.error <= REACH_TOLERANCE
                })
            };
            // the dip: the deepest the leg reaches there, 2 mm more
            let (mut lo, mut hi) = (0.0, 0.5);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if reached(0, landing - DVec3::Z * mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let depth = lo + 0.002;
            let ground = move |p: DVec3| {
                if (p - landing).truncate().length() < 0.01 {
                    -depth
                } else {
                    0.0
                }
            };
            assert!(!reached(0, landing - DVec3::Z * depth), "{}", model.name);
            let lowered = -c.body_offset(ground, &tracks, &[[0.0; 3]; 6]);
            assert!(lowered > 0.002, "{}: lowered {lowered}", model.name);
            for (k, track) in tracks.iter().enumerate() {
                for &p in track {
                    let target = p + DVec3::Z * (ground(p) + lowered);
                    assert!(reached(k, target), "{}: leg {k} at {p}", model.name);
                }
            }
        }
    }

    /// A hole under one leg's whole track deeper than it reaches down, and level ground under
    /// the body: the body is lowered toward the hole, but keeps half its standing clearance.
    #[test]
    fn the_body_is_not_lowered_onto_the_ground_under_it() {
        for (model, c) in hex18_and_phantomx() {
            let clearance = c.belly.iter().map(|b| b.1).fold(f64::INFINITY, f64::min);
            assert!(clearance > 0.0 && clearance.is_finite(), "{}", model.name);
            let tracks = c.track_footholds(&|_| 0.0);
            let (down, _) = c.vertical_room[0][0];
            let depth = down + clearance;
            let hole = move |p: DVec3| {
                if tracks[0]
                    .iter()
                    .any(|q| (p - *q).truncate().length() < 1e-9)
                {
                    -depth
                } else {
                    0.0
                }
            };
            let lowered = -c.body_offset(hole, &tracks, &[[0.0; 3]; 6]);
            assert!(
                (lowered - 0.5 * clearance).abs() < 1e-12,
                "{}: lowered {lowered}, clearance {clearance}",
                model.name
            );
        }
    }

    /// Perceptive, a stance foot's target sinks no faster than the gait lands
    /// ([`slew::landing_speed`]) when the ground planned under it drops 5 cm at once, early in
    /// its stance, and stands on the new ground before the stance ends; the swinging feet are
    /// not held to it.
    #[test]
    fn a_stance_target_sinks_at_the_landing_speed() {
        stance_targets_follow_a_step_at_the_landing_speed(0.05);
    }

    /// … and rises no faster: a stance target that rises in the body's frame lowers the body,
    /// and lowered faster than it falls the body leaves its feet (hexaross perceptive at the
    /// top of 10 cm stairs: the body crouched 7 cm in 0.1 s with every foot unloaded).
    #[test]
    fn a_stance_target_rises_at_the_landing_speed() {
        stance_targets_follow_a_step_at_the_landing_speed(-0.05);
    }

    /// A loaded leg's release follows the landing speed, its joints that speed over the leg's
    /// reach; a gait whose feet do not lift has none and releases by time, not never.
    #[test]
    fn compliance_is_released_at_the_landing_speed_or_by_time() {
        let (model, gait) = hex18_tripod();
        let c = GaitController::new(&model, gait.clone()).unwrap();
        let release = c.compliance_release();
        let landing = slew::landing_speed(&gait);
        assert!(landing > 0.0);
        assert_eq!(release.foot_speed, landing);
        for k in 0..6 {
            let reach = c.chains()[k].length();
            assert_eq!(release.joint_speed[k], landing / reach);
        }
        let flat = Gait {
            step_height: 0.0,
            ..gait
        };
        let c = GaitController::new(&model, flat).unwrap();
        assert_eq!(c.compliance_release(), Release::FREE);
    }

    /// The ground planned under the feet steps down by `depth` (up where negative) 20 ms into
    /// the first stance that begins: the stance targets follow at the landing speed, the
    /// swings faster.
    fn stance_targets_follow_a_step_at_the_landing_speed(depth: f64) {
        let (model, gait) = hex18_tripod();
        let (command, h) = (VelocityCommand::default(), 1e-3);
        let mut c = GaitController::new(&model, gait.clone()).unwrap();
        let level = std::cell::Cell::new(0.0);
        let landing = slew::landing_speed(&gait);
        let mut before = c.targets_on(0.0, command, 1.0, |_| level.get());
        let standing = before.feet;
        // the drop comes 20 ms into the first stance that begins; those legs are watched
        let mut drop: Option<(f64, Vec<usize>)> = None;
        let (mut fastest_swing, mut checked) = (0.0f64, 0);
        for i in 1..=(2.0 * gait.period / h).round() as usize {
            let t = i as f64 * h;
            if let Some((at, _)) = &drop
                && t >= *at
            {
                level.set(-depth);
            }
            let now = c.targets_on(t, command, 1.0, |_| level.get());
            for k in 0..6 {
                // along the step
                let sink = (before.feet[k].z - now.feet[k].z) * depth.signum();
                let standing_still = before.phases[k].is_stance() && now.phases[k].is_stance();
                if standing_still {
                    assert!(sink <= landing * h + 1e-12, "leg {k} at {t}: {sink}");
                } else {
                    fastest_swing = fastest_swing.max(sink / h);
                }
            }
            if drop.is_none() {
                let landed: Vec<usize> = (0..6)
                    .filter(|&k| !before.phases[k].is_stance() && now.phases[k].is_stance())
                    .collect();
                if !landed.is_empty() {
                    drop = Some((t + 0.02, landed));
                }
            }
            if let Some((at, legs)) = &drop
                && (t - at - depth.abs() / landing - 0.01).abs() < 0.5 * h
            {
                for &k in legs {
                    assert!(now.phases[k].is_stance(), "leg {k} left its stance");
                    let down = standing[k].z - now.feet[k].z;
                    assert!((down - depth).abs() < 1e-9, "leg {k}: {down}");
                    checked += 1;
                }
            }
            before = now;
        }
        assert_eq!(checked, 3);
        assert!(fastest_swing > landing, "{fastest_swing} against {landing}");
    }

    /// Over hex18's stances, the foot sphere's material point on the ground moves with the ground
    /// (no scrub) when the centre targets roll; planned as the contact, it scrubs at r·ω. The
    /// offset is read to first order at the pose it moves the foot to: what is left is 1.5 % of
    /// the scrub on the front and rear legs (0.113 of 7.66 mm/s) and 4.7 % on the middle ones
    /// (0.087 of 1.86). Read at the pose for the path on the ground, a rolling offset away (a
    /// second IK solve per leg, until 2026-12-03), it was 9 % and 9.6 % (0.68 and 0.178).
    #[test]
    fn rolling_targets_hold_the_contact_point_still() {
        let (model, gait) = hex18_tripod();
        let command = VelocityCommand {
            forward: gait.nominal_speed(),
            ..Default::default()
        };
        let ground = DVec3::new(-command.forward, 0.0, 0.0);
        let scrub = |rolling: bool| {
            let mut c = GaitController::new(&model, gait.clone())
                .unwrap()
                .with_rolling_feet(rolling);
            let h = 1e-4;
            let mut worst = [0.0f64; 6];
            let mut before: Option<GaitTargets> = None;
            for i in 0..=(gait.period / h).round() as usize {
                let now = c.targets(i as f64 * h, command, 1.0);
                if let Some(b) = before {
                    for (k, worst) in worst.iter_mut().enumerate() {
                        if !(b.phases[k].is_stance() && now.phases[k].is_stance()) {
                            continue;
                        }
                        let chain = &c.chains[k];
                        let turn = chain.foot_rotation(now.joint_angles[k])
                            * chain.foot_rotation(b.joint_angles[k]).transpose();
                        let omega = DQuat::from_mat3(&turn).to_scaled_axis() / h;
                        let centre = (now.feet[k] - b.feet[k]) / h;
                        // the sphere's point on the ground: v_C + ω × (−r·ẑ)
                        let point = centre - omega.cross(DVec3::Z) * model.legs[k].foot.radius;
                        *worst = worst.max((point - ground).length());
                    }
                }
                before = Some(now);
            }
            worst
        };
        let (rolled, planned) = (scrub(true), scrub(false));
        println!(
            "scrub (mm/s), rolling: {:.3?}; planned as the contact: {:.3?}",
            rolled.map(|v| v * 1e3),
            planned.map(|v| v * 1e3)
        );
        for k in 0..6 {
            assert!(
                planned[k] > 1e-3 && rolled[k] < 0.06 * planned[k],
                "leg {k}: scrub {:.2} mm/s rolling, {:.2} mm/s planned as the contact",
                rolled[k] * 1e3,
                planned[k] * 1e3
            );
        }
    }

    #[test]
    fn smooth_swings_start_and_end_at_ground_speed() {
        let duty = 0.5;
        let slope = -(1.0 - duty) / duty;
        for shape in [SwingShape::Sine, SwingShape::Cycloid] {
            let (p0, l0) = swing_profile(shape, 0.0, slope);
            let (p1, l1) = swing_profile(shape, 1.0, slope);
            assert!(
                p0.abs() < 1e-12
                    && (p1 - 1.0).abs() < 1e-12
                    && l0.abs() < 1e-12
                    && l1.abs() < 1e-12
            );
            let h = 1e-6;
            let start = (swing_profile(shape, h, slope).0 - p0) / h;
            let end = (p1 - swing_profile(shape, 1.0 - h, slope).0) / h;
            assert!(
                (start - slope).abs() < 1e-4 && (end - slope).abs() < 1e-4,
                "{start} {end}"
            );
        }
    }
}
