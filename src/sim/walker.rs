//! A hexapod driven by a gait: settle in the standing pose, then walk to a velocity command.

use super::engine::STANDARD_GRAVITY;
use super::hexapod::{Hexapod, HexapodSample};
use crate::gait::reach::ReachTally;
use crate::gait::{
    Compliance, FootFeel, GaitController, GaitTargets, GroundForces, HeadingHold, Reactive,
    StanceTrack, VelocityCommand, away_from_edges, most_extra_lift,
};
use crate::robot::kinematics::{LegAngles, LegStatics};
use crate::robot::{RobotModel, statics};
use crate::terrain::FittedPlane;
use glam::DVec3;

/// The walking robot: a [`Hexapod`] and the [`GaitController`] that sets its servo targets.
pub struct Walker {
    hexapod: Hexapod,
    controller: GaitController,
    command: VelocityCommand,
    /// Seconds standing still before the gait starts.
    settle_time: f64,
    targets_by_joint: Vec<f64>,
    last_targets: Option<GaitTargets>,
    /// Steps in which some leg's target was out of reach (IK clamped): the tally `hexsim
    /// robot` plans too (`gait::reach`).
    pub reach: ReachTally,
    /// Follow the terrain under the feet (see [`GaitController::targets`]); off: every foot path
    /// is planned for level ground.
    pub terrain_following: bool,
    /// Offset each joint's target by the torque it holds over the servo's stiffness (see
    /// [`Walker::hold_load`]; on by default); off: the targets are the gait's angles and the legs
    /// sag under load.
    pub load_feedforward: bool,
    /// The reactive gait (`gait::reactive`): feet find the ground by touch; off: the
    /// schedule's heights.
    pub reactive: bool,
    /// Leg compliance (`gait::compliance`): a leg pressing the ground with more than three
    /// times the robot's weight gives way; off: the servos press their targets to their effort.
    pub compliant: bool,
    /// The body's lean on slopes (`gait::lean`), from its attitude; off: it stands over its
    /// feet as on level ground.
    pub lean: bool,
    /// Heading hold (`gait::heading`): the command's turn corrected by the heading error; off:
    /// the gait turns open loop.
    pub hold_heading: bool,
    heading: Option<HeadingHold>,
    /// What each foot felt in the last step (normal force, ground force in the body frame).
    feel: [FootFeel; 6],
    /// Where each foot's centre was after the last step (world); None before the first.
    feet: Option<[DVec3; 6]>,
    /// The ground's forces on each leg (its foot's and its links') and on the body in the last
    /// step (body frame); summed only for leg compliance, the one that reads them.
    ground_forces: GroundForces,
    /// The joints' angles after the last step (by model joint), for leg compliance's yield;
    /// empty before the first step.
    joint_angles: Vec<f64>,
    /// The leg each model link belongs to (None: the body, a link off the legs).
    leg_of_link: Vec<Option<usize>>,
    /// Joint targets given from outside (rad, by model joint), in place of the gait's.
    given_targets: Option<Vec<f64>>,
    /// Every link is on a leg of three joints ([`statics::legs_hold_every_link`]): the
    /// feed-forward poses the legs from the gait's IK answers.
    legs_hold_every_link: bool,
    /// The model's total mass (kg), summed once: the feed-forward reads it every step.
    total_mass: f64,
    /// The feed-forward's link poses (or legs posed by their IK answers) and holding torques,
    /// kept between steps (no allocation, nothing zeroed: each step writes what it reads).
    poses: Vec<glam::DAffine3>,
    joint_frames: Vec<glam::DAffine3>,
    leg_statics: [LegStatics; 6],
    torques: Vec<f64>,
    /// The ground plane the body rides above when following the terrain, smoothed (see
    /// [`Walker::ground_reference`]); None until the first step that follows it.
    ground_plane: Option<GroundPlane>,
    /// Where the hips' and the neutral feet's ground is read off edges when following the
    /// terrain ([`Walker::standing_points`]); None until the first step that follows it.
    standing: Option<StandingPoints>,
    /// Its rate of change (m/s), for the tracker, and its slope along the world's x and y.
    ground_rate: f64,
    world_slope: glam::DVec2,
    /// The body's reference ground as the last step planned it ([`BodyReference`]); None until
    /// the first step that follows the terrain.
    reference: Option<BodyReference>,
    /// The body started tilted (set down parallel to a slope: `Attitude::Ground`): following
    /// the terrain, the levelling is ramped in over [`LEVELLING_RAMP`] from it.
    tilted_start: bool,
}

/// The ground the body rides above when following the terrain (body frame, heading only): its
/// height `level` at the hips' centre (tracked; `measured` as it is this step) and its `slope`
/// along x and y.
#[derive(Debug, Clone, Copy, PartialEq)]
struct GroundPlane {
    level: f64,
    measured: f64,
    slope: glam::DVec2,
    centre: glam::DVec2,
}

impl GroundPlane {
    /// The least-squares plane through `points` (x, y, height).
    fn fit(points: &[DVec3]) -> Self {
        let FittedPlane {
            centre,
            level,
            slope,
        } = FittedPlane::fit(points);
        GroundPlane {
            level,
            measured: level,
            slope,
            centre,
        }
    }

    /// The plane's rise above its level under a body-frame point.
    fn rise(&self, p: DVec3) -> f64 {
        self.slope.dot(p.truncate() - self.centre)
    }
}

/// The ground the legs' targets are measured from when following the terrain: a plane of world
/// heights, `height` at the world point `at`, rising by `slope` (world x, y). A foot's target
/// stands `terrain − reference` above its neutral height, so the plane is the body's planned
/// height and attitude: its level, the share of the flight's slope the body takes, its crouch.
/// Moved no faster at any foot than a swing lands ([`GaitController::landing_speed`]), for the
/// stance and the swing feet alike (see [`Walker::body_reference`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct BodyReference {
    at: glam::DVec2,
    height: f64,
    slope: glam::DVec2,
}

impl BodyReference {
    fn height_at(&self, w: glam::DVec2) -> f64 {
        self.height + self.slope.dot(w - self.at)
    }

    /// `self` moved towards `next` as far as moves no point of `points` (world) more than `most`.
    fn towards(&self, next: &Self, points: impl Iterator<Item = glam::DVec2>, most: f64) -> Self {
        let moved = points
            .map(|w| (next.height_at(w) - self.height_at(w)).abs())
            .fold(0.0, f64::max);
        if moved <= most {
            return *next;
        }
        // the change is affine in the point, so a share of it moves each point by that share
        let share = most / moved;
        let here = self.height_at(next.at);
        BodyReference {
            at: next.at,
            height: here + share * (next.height - here),
            slope: self.slope + share * (next.slope - self.slope),
        }
    }
}

/// Seconds over which a body set down tilted is brought to the levelling that following the
/// terrain asks: all at once, a body set down parallel to 30° was pitched 11° in one step, and
/// the jerk moved hex18 2.0 mm down the slope (V21, multibody; ramped: 0.18 mm, 0.17–0.19 mm
/// since the walker rides a fitted ground plane).
const LEVELLING_RAMP: f64 = 0.5;

/// How far the body moves (m) and turns (the heading's change, ≈ rad) before the standing points
/// off edges are searched again ([`Walker::standing_points`]): a fifth of a 1 cm grid cell, and
/// as much at the hips' 0.1–0.2 m from the centre.
const STANDING_MOVE: f64 = 0.002;
const STANDING_TURN: f64 = 0.01;

/// How far the body moves (m) and turns before the ends of the stance tracks are searched again;
/// in between they are held where they are on the ground. Searched with the middles, every
/// [`STANDING_MOVE`], they took hex18 on 2 cm stepping stones from 9 900 to 6 500 steps/s.
const TRACK_END_MOVE: f64 = 0.01;
const TRACK_END_TURN: f64 = 0.05;

/// Where the ground under the hips and the feet's stance tracks is read when following the
/// terrain (body level frame), and the body's level frame they were searched in.
#[derive(Debug, Clone, Copy)]
struct StandingPoints {
    center: DVec3,
    heading: glam::DMat3,
    /// Where the ground under each hip (over its first joint) is read, off edges.
    hips: [DVec3; 6],
    /// The feet's stance tracks, each point off edges ([`GaitController::track_footholds`]):
    /// `[0]` the neutral foot.
    tracks: [StanceTrack; 6],
    /// How far each track point's foot rests above the ground under it
    /// ([`GaitController::track_rims`]).
    rims: [[f64; 3]; 6],
    /// The tracks' ends on the ground (world frame, as searched in the level frame `ends_at`).
    ends: [[DVec3; 2]; 6],
    ends_at: (DVec3, glam::DMat3),
}

impl StandingPoints {
    /// The neutral feet, off edges ([`GaitController::standing_footholds`]).
    fn feet(&self) -> [DVec3; 6] {
        self.tracks.map(|track| track[0])
    }
}

/// A step of the walker: the robot's state and the gait's targets for it.
#[derive(Debug, Clone, Default)]
pub struct WalkSample {
    pub robot: HexapodSample,
    /// The gait's targets; None while settling and while the joints are driven from outside.
    pub gait: Option<GaitTargets>,
    /// Standing still before the walk (the settle time): not part of the walk's metrics.
    pub settling: bool,
}

impl Walker {
    pub fn new(
        hexapod: Hexapod,
        controller: GaitController,
        command: VelocityCommand,
        settle_time: f64,
    ) -> Self {
        let n = hexapod.model().joints.len();
        // more than 1° off vertical
        let tilted_start = hexapod.body_frame().matrix3.z_axis.z < 1f64.to_radians().cos();
        let model = hexapod.model();
        let mut leg_of_link = vec![None; model.links.len()];
        for (k, leg) in model.legs.iter().enumerate() {
            for &j in &leg.joints {
                leg_of_link[model.joints[j].child] = Some(k);
            }
            leg_of_link[leg.foot_link] = Some(k);
        }
        let legs_hold_every_link = statics::legs_hold_every_link(model);
        let total_mass = model.total_mass();
        Walker {
            hexapod,
            controller,
            command,
            settle_time,
            targets_by_joint: vec![0.0; n],
            last_targets: None,
            reach: ReachTally::default(),
            terrain_following: false,
            load_feedforward: true,
            reactive: false,
            compliant: true,
            lean: true,
            hold_heading: false,
            heading: None,
            feel: [FootFeel::default(); 6],
            feet: None,
            ground_forces: GroundForces::default(),
            joint_angles: Vec::new(),
            leg_of_link,
            given_targets: None,
            legs_hold_every_link,
            total_mass,
            poses: Vec::new(),
            joint_frames: Vec::new(),
            leg_statics: [LegStatics::default(); 6],
            torques: vec![0.0; n],
            ground_plane: None,
            standing: None,
            ground_rate: 0.0,
            world_slope: glam::DVec2::ZERO,
            reference: None,
            tilted_start,
        }
    }

    pub fn hexapod(&self) -> &Hexapod {
        &self.hexapod
    }

    /// The velocity command the gait follows.
    pub fn command(&self) -> VelocityCommand {
        self.command
    }

    pub fn set_command(&mut self, command: VelocityCommand) {
        self.command = command;
    }

    /// Seconds standing still before the gait starts.
    pub fn settle_time(&self) -> f64 {
        self.settle_time
    }

    /// Seconds since the gait started (negative while settling).
    pub fn gait_time(&self) -> f64 {
        self.hexapod.time() - self.settle_time
    }

    /// The frame of [`Self::terrain_under`]'s points: the body's centre, turned by its heading
    /// only (world = centre + heading · point).
    fn level_frame(hexapod: &Hexapod) -> (DVec3, glam::DMat3) {
        let body = hexapod.body_frame();
        let heading = glam::DMat3::from_rotation_z(heading_of(&body.matrix3));
        (body.translation, heading)
    }

    /// The terrain's height under a body-frame point, seen with the body's heading only (its
    /// tilt is what following the terrain avoids).
    fn terrain_under(hexapod: &Hexapod) -> impl Fn(DVec3) -> f64 + '_ {
        let terrain = hexapod.terrain();
        let (center, heading) = Self::level_frame(hexapod);
        move |p: DVec3| {
            let w = center + heading * p;
            terrain.height(w.x, w.y)
        }
    }

    /// The ground plane the body rides above when following the terrain (see [`GroundPlane`]):
    /// fitted through the terrain under the hips, each hip's height taken where its foot would
    /// stand — off any edge ([`away_from_edges`]), not in a stone's pit, which would sink the
    /// body with every pit it passed — and tracked over about a quarter gait period. The height
    /// under the body's centre alone steps by a whole riser as the centre crosses it, and every
    /// foot's target stepped with it in one step (hex18 on 2 cm stairs: 0.25 rad at every swing
    /// femur, all six feet thrown off the ground); under six hips it steps by a sixth, and the
    /// tracker spreads that over the next steps.
    fn ground_reference(&mut self, standing: &StandingPoints) -> GroundPlane {
        let model = self.hexapod.model();
        let ground = Self::terrain_under(&self.hexapod);
        let points: [DVec3; 6] = std::array::from_fn(|k| {
            let hip = Self::hip(model, k);
            DVec3::new(hip.x, hip.y, ground(standing.hips[k]))
        });
        let mut fit = GroundPlane::fit(&points);
        // the slope tracked as the world sees it: turned into the heading's frame each step, a
        // slope's own fit would lag behind the body's turns (hex18 standing levelled on 30°
        // crept 5.5 mm in 10 s against 1.9 mm)
        let body = self.hexapod.body_frame().matrix3;
        let heading = glam::DMat2::from_angle(heading_of(&body));
        let world_slope = heading * fit.slope;
        let dt = self.hexapod.dt();
        let tau = 0.25 * self.controller.gait().period;
        let plane = match self.ground_plane {
            None => {
                self.ground_rate = 0.0;
                self.world_slope = world_slope;
                fit
            }
            Some(last) => {
                // a first-order lag would trail a slope by v·τ; this one follows a ramp exactly
                // and spreads a step over a quarter period (an α-β tracker: level and rate)
                let predicted = last.level + self.ground_rate * dt;
                let residual = fit.level - predicted;
                let alpha = (2.0 * dt / tau).min(1.0);
                let beta = alpha * alpha / (2.0 - alpha);
                self.ground_rate += beta * residual / dt;
                // constant on a slope; on stairs it steps as a hip crosses a riser
                self.world_slope += (world_slope - self.world_slope) * (dt / tau).min(1.0);
                fit.slope = heading.transpose() * self.world_slope;
                GroundPlane {
                    level: predicted + alpha * residual,
                    measured: fit.level,
                    ..fit
                }
            }
        };
        self.ground_plane = Some(plane);
        plane
    }

    /// Leg `k`'s hip: its first joint's origin (body frame).
    fn hip(model: &RobotModel, k: usize) -> DVec3 {
        model.joints[model.legs[k].joints[0]].origin.translation
    }

    /// The points off edges ([`away_from_edges`]) where the ground under each hip and each
    /// foot's stance track is read (body level frame), searched afresh only when the body has
    /// moved [`STANDING_MOVE`] or turned [`STANDING_TURN`] since the last search (the tracks'
    /// ends [`TRACK_END_MOVE`] or [`TRACK_END_TURN`]), and held in between:
    /// searched every step, they took nine tenths of a perceptive walk's time on 2 cm stepping
    /// stones (a footprint's edge test is a hundred terrain reads, the search up to 288 tests).
    fn standing_points(&mut self) -> StandingPoints {
        let (center, heading) = Self::level_frame(&self.hexapod);
        let now = (center, heading);
        if let Some(held) = &self.standing
            && within(
                (held.center, held.heading),
                now,
                STANDING_MOVE,
                STANDING_TURN,
            )
        {
            return *held;
        }
        let model = self.hexapod.model();
        let ground = Self::terrain_under(&self.hexapod);
        let longest = self.controller.gait().stride_length;
        let hips = std::array::from_fn(|k| {
            let (hip, radius) = (Self::hip(model, k), model.legs[k].foot.radius);
            hip + away_from_edges(&ground, hip, DVec3::X, radius, longest)
        });
        let ends_held = self
            .standing
            .filter(|held| within(held.ends_at, now, TRACK_END_MOVE, TRACK_END_TURN));
        let (tracks, ends, ends_at) = match ends_held {
            Some(held) => {
                // the ends held where they are on the ground, seen from the body now
                let to_level = heading.transpose();
                let feet = self.controller.standing_footholds(&ground);
                let tracks = std::array::from_fn(|k| {
                    let [fore, aft] =
                        held.ends[k].map(|w| (to_level * (w - center)).with_z(feet[k].z));
                    [feet[k], fore, aft]
                });
                (tracks, held.ends, held.ends_at)
            }
            None => {
                let tracks = self.controller.track_footholds(&ground);
                let ends = tracks.map(|t| [t[1], t[2]].map(|p| center + heading * p));
                (tracks, ends, (center, heading))
            }
        };
        let rims = self.controller.track_rims(&ground, &tracks);
        let held = StandingPoints {
            center,
            heading,
            hips,
            tracks,
            rims,
            ends,
            ends_at,
        };
        self.standing = Some(held);
        held
    }

    /// The body's reference ([`BodyReference`]): the terrain under a body-frame point less the
    /// reference is how far its foot reaches up or down. Split as the legs can follow it
    /// ([`GaitController::levelling`]): the terrain's departure from the body's ground `plane`
    /// (a stair's treads, a bump) in full, the plane's own rise under the foot (a slope, a
    /// flight of stairs) by the share λ the legs reach. The rest of the plane's tilt the body
    /// takes: it pitches with a flight of stairs steeper than its legs can level. A body set
    /// down tilted is brought to that share over [`LEVELLING_RAMP`]. Less the body's offset over
    /// it ([`GaitController::body_offset`]): it crouches into dips its legs cannot reach.
    ///
    /// The reference moves no faster at any point of the feet's stance tracks than a swing
    /// lands. It steps as a hip crosses a riser (the plane's fit, the share λ, the crouch): on
    /// 12 cm stairs down hexaross's share fell from 1 to 0 as its front hips passed the top's
    /// edge, and the reference pitched at 0.3 m/s at its rear feet and rose 7 cm in 0.12 s. The
    /// stance feet followed at the landing speed (theirs is bounded,
    /// [`GaitController::targets_on`]), the swinging feet in full: two landed 7 mm under the top
    /// landing and threw the body up, the front one 2 cm over the tread below, and the robot
    /// tumbled down the flight.
    fn body_reference(&mut self, plane: GroundPlane, standing: &StandingPoints) -> BodyReference {
        let hexapod = &self.hexapod;
        let controller = &self.controller;
        let terrain = Self::terrain_under(hexapod);
        // the plane through the hips' ground as it is now, at the tracked slope: its level
        // lags while the body lands or slides, and that lag is the body's, levelled by λ with
        // the rest (followed in full, it pushed hex18 11 mm down a 30° slope while standing)
        let residual = |p: DVec3| terrain(p) - plane.measured - plane.rise(p);
        let planar = |p: DVec3| plane.measured - plane.level + plane.rise(p);
        // a body set down tilted is brought to it over LEVELLING_RAMP
        let ramp = if self.tilted_start {
            (hexapod.time() / LEVELLING_RAMP).min(1.0)
        } else {
            1.0
        };
        let share = ramp * controller.levelling(residual, planar, &standing.feet());
        let followed = |p: DVec3| residual(p) + share * planar(p);
        let raised = controller.body_offset(followed, &standing.tracks, &standing.rims);
        // terrain − followed + raised, a plane: (1 − λ)·(measured + rise) + λ·level + raised
        let (center, heading) = Self::level_frame(hexapod);
        let to_world = |p: glam::DVec2| center.truncate() + heading.transform_vector2(p);
        let next = BodyReference {
            at: to_world(plane.centre),
            height: (1.0 - share) * plane.measured + share * plane.level + raised,
            slope: heading.transform_vector2((1.0 - share) * plane.slope),
        };
        let reference = match self.reference {
            None => next,
            Some(last) => {
                let most = controller.landing_speed() * hexapod.dt();
                let points = standing.tracks.iter().flatten();
                last.towards(&next, points.map(|p| to_world(p.truncate())), most)
            }
        };
        self.reference = Some(reference);
        reference
    }

    /// How far the terrain under a body-frame point lies above the body's `reference`.
    fn ground_within_reach(
        hexapod: &Hexapod,
        reference: BodyReference,
    ) -> impl Fn(DVec3) -> f64 + '_ {
        // the point turned into the world once, for the terrain and the reference both
        let terrain = hexapod.terrain();
        let (center, heading) = Self::level_frame(hexapod);
        move |p: DVec3| {
            let w = center + heading * p;
            terrain.height(w.x, w.y) - reference.height_at(w.truncate())
        }
    }

    /// Sets the servos' targets to the legs' `angles`, held against the load of the feet in
    /// `stance` when [`Self::load_feedforward`] is on.
    fn set_leg_targets(&mut self, angles: &[LegAngles; 6], stance: [bool; 6]) {
        for (leg, angles) in self.hexapod.model().legs.iter().zip(angles) {
            for (j, &a) in leg.joints.iter().zip(angles) {
                self.targets_by_joint[*j] = a;
            }
        }
        if self.load_feedforward {
            self.hold_load(angles, stance);
        }
        if !self.joint_angles.is_empty() {
            // leg compliance's yield: the gait's angles sent part of the way to the joints'
            // angles, the feed-forward's offset kept: fully yielded, a leg's servos hold the
            // load planned for it and nothing beyond
            for (k, (leg, angles)) in self.hexapod.model().legs.iter().zip(angles).enumerate() {
                let y = self.controller.leg_yield(k);
                if y > 0.0 {
                    for (&j, &a) in leg.joints.iter().zip(angles) {
                        self.targets_by_joint[j] += y * (self.joint_angles[j] - a);
                    }
                }
            }
        }
        let targets_by_joint = std::mem::take(&mut self.targets_by_joint);
        self.hexapod.set_targets(&targets_by_joint);
        self.targets_by_joint = targets_by_joint;
    }

    /// A position servo under load stands τ/k short of its target (τ = k·(q* − q) at rest), so
    /// a stance leg sags and, with three legs pushing against each other, splays and slides.
    /// Feed-forward: with the robot standing in the target pose, each joint's target is moved on
    /// by τ/k, τ the torque it holds ([`statics::holding_torques_under`]) — its outboard links' weight and its
    /// foot's share of the body's weight ([`statics::stance_loads_under`]: force and moment balance on the feet
    /// the gait has down, none on a foot in swing). The servo then comes to rest on the gait's
    /// angle under the planned load.
    ///
    /// The weight acts along gravity as the body's attitude shows it (an IMU's reading), not
    /// along the body's −z: walking parallel to a 25° slope, part of the weight pulls along the
    /// body, and planned as vertical loads the stance legs took it up through their compliance
    /// each step and the feet slid (uphill, blind: 1.77 m in 20 s, the worst foot sliding
    /// 0.27 m; planned along gravity: 2.09 m, 0.085 m).
    ///
    /// The legs are posed from the gait's last IK solves, whose forward kinematics end on the
    /// targets' angles ([`GaitController::leg_statics`]), not by forward kinematics of all the
    /// links again (13.5k → 7.6k instructions of a walk's step on hex18).
    ///
    /// `angles` are the legs' targets as [`Self::set_leg_targets`] has just written them.
    fn hold_load(&mut self, angles: &[LegAngles; 6], stance: [bool; 6]) {
        let model = self.hexapod.model();
        let body = self.hexapod.body_frame().matrix3;
        let gravity = body.transpose() * DVec3::new(0.0, 0.0, -STANDARD_GRAVITY);
        let legs = &mut self.leg_statics;
        let mut posed = self.legs_hold_every_link;
        for (k, q) in angles.iter().enumerate() {
            if !posed {
                break;
            }
            posed = self.controller.leg_statics(k, q, &mut legs[k]);
        }
        if posed {
            let mass = self.total_mass;
            let loads = statics::stance_loads_of_legs(model, mass, legs, gravity, stance);
            statics::holding_torques_of_legs(model, legs, gravity, &loads, &mut self.torques);
        } else {
            model.link_and_joint_poses_into(
                &self.targets_by_joint,
                &mut self.poses,
                &mut self.joint_frames,
            );
            let loads = statics::stance_loads_under(model, &self.poses, gravity, stance);
            statics::holding_torques_at(
                model,
                &self.poses,
                &self.joint_frames,
                gravity,
                &loads,
                &mut self.torques,
            );
        }
        let stiffness = self.hexapod.gains().stiffness;
        for (target, torque) in self.targets_by_joint.iter_mut().zip(&self.torques) {
            *target += torque / stiffness;
        }
    }

    /// Drives the servos to `targets` (rad, one per model joint, in the model's joint order) from
    /// the next step on, instead of the gait; None hands the joints back to the gait. Targets
    /// beyond a joint's limits are passed on as they are: the limit stops the joint.
    pub fn set_joint_targets(&mut self, targets: Option<Vec<f64>>) -> anyhow::Result<()> {
        if let Some(targets) = &targets {
            let joints = &self.hexapod.model().joints;
            if targets.len() != joints.len() {
                anyhow::bail!(
                    "joint targets: {} given, the robot has {} joints ({})",
                    targets.len(),
                    joints.len(),
                    joints
                        .iter()
                        .map(|j| j.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            }
            if let Some((i, t)) = targets.iter().enumerate().find(|(_, t)| !t.is_finite()) {
                anyhow::bail!(
                    "joint targets: {t} for joint {} ({}) is not a finite angle",
                    i,
                    joints[i].name
                );
            }
        }
        self.given_targets = targets;
        Ok(())
    }

    /// Per leg, its joints' largest distance from the angles the gait sent them last (rad):
    /// what a yielded leg has to take back (nothing before the walk's first targets).
    fn leg_gaps(&self) -> [f64; 6] {
        let mut gaps = [0.0f64; 6];
        if let Some(targets) = &self.last_targets
            && !self.joint_angles.is_empty()
        {
            for (gap, (leg, angles)) in gaps
                .iter_mut()
                .zip(self.hexapod.model().legs.iter().zip(&targets.joint_angles))
            {
                for (&j, &a) in leg.joints.iter().zip(angles) {
                    *gap = (*gap).max((self.joint_angles[j] - a).abs());
                }
            }
        }
        gaps
    }

    pub fn step(&mut self) -> WalkSample {
        let mut sample = WalkSample::default();
        self.step_into(&mut sample);
        sample
    }

    /// [`Walker::step`], written over `sample` (an earlier one no longer read) in place: its
    /// vectors are reused, not allocated ([`Hexapod::step_into`]).
    pub fn step_into(&mut self, sample: &mut WalkSample) {
        let t = self.gait_time();
        if let Some(targets) = &self.given_targets {
            self.hexapod.set_targets(targets);
            self.last_targets = None;
        } else if t >= 0.0 {
            let period = self.controller.gait().period;
            // ramp the stride up over the first cycle so the feet leave the standing pose smoothly
            let blend = (t / period).min(1.0);
            if self.reactive != self.controller.is_reactive() {
                let model = self.hexapod.model();
                let share = model.total_mass() * STANDARD_GRAVITY / 6.0;
                let gait = self.controller.gait();
                let most = most_extra_lift(gait.stance_height, gait.step_height);
                let reactive = Reactive::new(share, most, self.hexapod.dt());
                self.controller
                    .set_reactive(self.reactive.then_some(reactive));
            }
            if self.compliant != self.controller.is_compliant() {
                let weight = self.hexapod.model().total_mass() * STANDARD_GRAVITY;
                let longest = 2.0 * self.controller.gait().step_height;
                let release = self.controller.compliance_release();
                self.controller.set_compliance(
                    self.compliant
                        .then(|| Compliance::new(weight, longest, release)),
                );
            }
            self.controller.feel(self.feel);
            let dt = self.hexapod.dt();
            // read only while a leg has yielded: nothing else uses them
            let gaps = if (0..6).any(|k| self.controller.leg_yield(k) > 0.0) {
                self.leg_gaps()
            } else {
                [0.0; 6]
            };
            self.controller.feel_forces(&self.ground_forces, &gaps, dt);
            if self.lean {
                let body = self.hexapod.body_frame().matrix3;
                self.controller
                    .feel_gravity(body.transpose() * DVec3::NEG_Z, dt);
            }
            let command = if self.hold_heading {
                let hold = self.heading.get_or_insert_with(|| {
                    let gait = self.controller.gait();
                    HeadingHold::new(gait.nominal_speed(), self.controller.turn_radius())
                });
                let yaw = heading_of(&self.hexapod.body_frame().matrix3);
                hold.steer(self.command, yaw, self.hexapod.dt())
            } else {
                self.command
            };
            let targets = if self.terrain_following {
                if let Some(feet) = self.feet {
                    // the feet where they are, as `terrain_under`'s points
                    let (center, heading) = Self::level_frame(&self.hexapod);
                    let to_level = heading.transpose();
                    self.controller
                        .feet_at(feet.map(|w| to_level * (w - center)));
                }
                let standing = self.standing_points();
                let plane = self.ground_reference(&standing);
                let reference = self.body_reference(plane, &standing);
                let ground = Self::ground_within_reach(&self.hexapod, reference);
                self.controller.targets_on(t, command, blend, ground)
            } else {
                self.controller.targets(t, command, blend)
            };
            self.set_leg_targets(&targets.joint_angles, targets.grounded);
            self.reach.record(t, &targets);
            self.last_targets = Some(targets);
        } else if self.terrain_following {
            // stand level from the start, so the walk does not begin tilted with the ground
            let standing = self.standing_points();
            let plane = self.ground_reference(&standing);
            let reference = self.body_reference(plane, &standing);
            let ground = Self::ground_within_reach(&self.hexapod, reference);
            let angles = self.controller.settling_on(ground, self.hexapod.dt());
            self.set_leg_targets(&angles, [true; 6]);
        } else if self.load_feedforward {
            let angles = self.controller.standing_on(|_| 0.0);
            self.set_leg_targets(&angles, [true; 6]);
        }
        self.hexapod.step_into(&mut sample.robot);
        let robot = &sample.robot;
        self.feet = Some(robot.foot_positions);
        let to_body = robot.body.matrix3.transpose();
        // written in place, not built and copied over (every step)
        for (feel, c) in self.feel.iter_mut().zip(&robot.foot_contacts) {
            *feel = c.as_ref().map_or(FootFeel::default(), |c| FootFeel {
                normal_force: c.normal_force,
                force: to_body * c.force,
                upright: Some(c.frame.normal.z),
            });
        }
        if self.compliant {
            let ground = &mut self.ground_forces;
            for (k, (feel, c)) in self.feel.iter().zip(&robot.foot_contacts).enumerate() {
                ground.legs[k] = feel.force;
                ground.leg_loads[k] = c.as_ref().map_or(0.0, |c| c.load);
            }
            (ground.body, ground.body_load) = (DVec3::ZERO, 0.0);
            for contact in &robot.link_contacts {
                let force = to_body * contact.force.force;
                match self.leg_of_link[contact.link] {
                    Some(k) => {
                        ground.legs[k] += force;
                        ground.leg_loads[k] += contact.force.load;
                    }
                    None => {
                        ground.body += force;
                        ground.body_load += contact.force.load;
                    }
                }
            }
            self.joint_angles.clone_from(&robot.joint_angles);
        }
        sample.gait = self.last_targets;
        sample.settling = t < 0.0;
    }
}

/// Whether the body's level frame `to` (centre, heading) is within `distance` (m, across the
/// ground) and `turn` (of its x axis) of `from`.
fn within(from: (DVec3, glam::DMat3), to: (DVec3, glam::DMat3), distance: f64, turn: f64) -> bool {
    (from.0 - to.0).truncate().length() < distance && (from.1.x_axis - to.1.x_axis).length() < turn
}

/// The body's heading: the yaw of its x axis seen from above (rad, in (−π, π]).
fn heading_of(body: &glam::DMat3) -> f64 {
    body.x_axis.y.atan2(body.x_axis.x)
}

#[cfg(test)]
mod tests {
    use super::BodyReference;
    use glam::DVec2;

    /// A step of the reference towards a plan pitched 0.3 and raised 7 cm (hexaross's first edge
    /// of 12 cm stairs down): the foot it moves most moves the bound, every foot moves by the
    /// same share of its own change, and a step within the bound is taken whole.
    #[test]
    fn the_reference_moves_no_foot_faster_than_the_bound() {
        let last = BodyReference {
            at: DVec2::ZERO,
            height: 0.10,
            slope: DVec2::ZERO,
        };
        let next = BodyReference {
            at: DVec2::new(0.01, 0.0),
            height: 0.17,
            slope: DVec2::new(-0.3, 0.05),
        };
        let feet = [
            (-0.2, 0.15),
            (0.0, 0.2),
            (0.2, 0.15),
            (-0.2, -0.15),
            (0.0, -0.2),
        ]
        .map(|(x, y)| DVec2::new(x, y));
        let most = 0.19e-3;
        let moved = last.towards(&next, feet.into_iter(), most);
        let shares: Vec<f64> = feet
            .iter()
            .map(|&w| {
                let step = moved.height_at(w) - last.height_at(w);
                assert!(step.abs() <= most * (1.0 + 1e-12), "moved {step} at {w}");
                step / (next.height_at(w) - last.height_at(w))
            })
            .collect();
        assert!(
            shares.iter().all(|s| (s - shares[0]).abs() < 1e-9),
            "{shares:?}"
        );
        let worst = feet
            .iter()
            .map(|&w| (moved.height_at(w) - last.height_at(w)).abs())
            .fold(0.0, f64::max);
        assert!((worst - most).abs() < 1e-12, "the worst foot moved {worst}");
        let near = BodyReference {
            height: 0.1001,
            ..last
        };
        assert_eq!(last.towards(&near, feet.into_iter(), most), near);
    }
}
