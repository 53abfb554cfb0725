//! A gait fitted to a robot: the lengths a gait file leaves out (stance height, reach, step
//! height, stride length) chosen from the robot's legs, so that any hexapod walks with the
//! built-in gaits.
//!
//! Each length comes from the first of: the gait file, the robot file's `[gait]` section, the fit.
//! The fit, with L the legs' mean length (hip to foot centre along the segments):
//! - stride L/4 and step height L/8 (hex18, L = 0.25 m, was designed with 0.06 and 0.03 m);
//! - stance height and reach: the pair that leaves the joints the most room over a whole cycle at
//!   the nominal speed on level ground — the largest least distance of any joint to a limit, plus
//!   a tenth of the mean over the joints to choose among stances whose tightest joint is the same
//!   — among the stances where every foot target is reached (at the search's instants and at the
//!   report's finer ones, [`cycle_margins`]), the servos hold the robot standing on
//!   the gait's fewest feet with half their effort to spare ([`TORQUE_SHARE`]), and the body's
//!   lowest point clears the ground by a step height (what a foot steps over the body passes).
//!   A grid over h ∈ [0.05, 0.95]·L, r ∈ [0.05, 1]·L, refined twice around the best cell.
//!   Among the stances that pass, a steady one is preferred: its walk on level ground keeps the
//!   centre of mass over the support on a tilt of [`STEADY_TILT`] any way, with [`STEADY_ROOM`]
//!   of joint room (else one steady to [`STEADY_FALLBACK_TILT`]); the most room alone chose tall
//!   stances on legs hanging under the hips, which fell over on slopes and edges. No stance may put a link other than a foot on the level
//!   ground over the cycle (a shin or a knee walked on).
//! - Splay: when the stance found is steady to less than [`SPLAY_BELOW`] (legs that all point
//!   sideways from hips close together stand on tripods shorter than their stride), the front
//!   and rear feet are turned towards the body's ends by the least of [`SPLAYS`] that gives a
//!   steady stance (else one steady to [`STEADY_FALLBACK_TILT`]), its links
//!   [`SPLAYED_LINK_MARGIN`] clear of the ground (a gait file may give `splay_deg` itself).
//! - When no stance passes, the fitted stride and step height are halved (twice at most); when
//!   still none passes, the error names what binds at the stance that came closest: a joint at
//!   its limit, a servo short of torque, or the body too low.

use super::controller::{GaitController, StanceError};
use super::margins::{CycleMargins, cycle_margins, sampled_margins};
use super::schedule::minimum_support;
use super::spec::{Gait, GaitSpec};
use crate::robot::kinematics::LegAngles;
use crate::robot::{RobotModel, statics};

/// The most of a servo's effort the fitted stance may need standing on the gait's fewest feet:
/// the rest is for accelerating the legs and absorbing touch-downs.
pub const TORQUE_SHARE: f64 = 0.5;
/// Fitted stride and step height per unit of leg length.
const STRIDE_PER_LEG: f64 = 0.25;
const STEP_PER_LEG: f64 = 0.125;
/// Weight of the mean joint room against the least in the fit's score.
const MEAN_WEIGHT: f64 = 0.1;
/// A stance is steady when its walk on level ground keeps the centre of mass's plumb line inside
/// the support on a tilt of this much, any way ([`GaitController::static_tilt`]), with its
/// joints this much room; the fit takes the steady stance with the most room when there is one.
/// On the ladders the public robots whose fitted stance was steady to 26.5° or less fell in 2–70
/// of their 104 runs, those steady to 40° or more in none; raising the bar from 30° to 35°
/// (2026-12-05) lowered seven robots' stances and their falls 24 → 11 (rough-ground.md,
/// *Steady stances*).
pub const STEADY_TILT: f64 = 35.0 * std::f64::consts::PI / 180.0;
/// A stance steady to this is taken when none is steady to [`STEADY_TILT`], with the legs as they
/// point or splayed: a robot whose steadiest stance is steady to 30–35° would otherwise fall
/// back to the stance with the most room however unsteady (MushroomRL's, with its left legs
/// knee down before 2026-12-05: its steadiest splayed stance with its links clear was steady to
/// 34.2°, at 45°; with the most room, unsplayed, 0°).
const STEADY_FALLBACK_TILT: f64 = 30.0 * std::f64::consts::PI / 180.0;
pub const STEADY_ROOM: f64 = 15.0 * std::f64::consts::PI / 180.0;
/// Grid cells per free length in the coarse search, and cycle instants sampled per candidate.
const GRID: usize = 16;
const SEARCH_SAMPLES: usize = 24;
/// The splays ([`Gait::splay`]) the fit tries, in turn, when the stance it finds with the legs
/// as they point is steady to less than [`SPLAY_BELOW`]: the first with a steady stance is
/// taken.
const SPLAYS: [f64; 4] = [
    0.0,
    15.0 * std::f64::consts::PI / 180.0,
    30.0 * std::f64::consts::PI / 180.0,
    45.0 * std::f64::consts::PI / 180.0,
];
/// A stance steady to this tilt or more keeps the legs' own direction, steady or not. Measured
/// on the ladders when the splay came, at a bar of 30° (2026-12-04; rough-ground-log.md,
/// *Splayed stances*): hexapod_description (17.5° → 30.3° at 15°) and MushroomRL (0° → 34.2° at 45°) fell far less splayed; WORMS (26.1° → 31.9° at 15°)
/// diverged in 3 perceptive runs, its front feet starting past the families' first drop.
const SPLAY_BELOW: f64 = 20.0 * std::f64::consts::PI / 180.0;
/// How far the links other than the feet of a splayed stance must stay above the level ground
/// over the cycle (m): turned towards the ends, legs bring their shins lower (MushroomRL's to
/// 1 mm at 45°), and a shin that clears level ground by less than the depth a contact may
/// reach (the ladder's 5 mm) walks on the ground wherever it is uneven.
const SPLAYED_LINK_MARGIN: f64 = 0.005;
/// Standard gravity for the torque check (m/s²).
const GRAVITY: f64 = 9.80665;

/// Where a gait length came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    GaitFile,
    RobotFile,
    Fitted,
}

impl Origin {
    pub fn describe(self) -> &'static str {
        match self {
            Origin::GaitFile => "gait file",
            Origin::RobotFile => "robot file",
            Origin::Fitted => "fitted",
        }
    }
}

/// Where each of the four lengths came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Origins {
    pub stance_height: Origin,
    pub reach: Origin,
    pub step_height: Origin,
    pub stride_length: Origin,
    pub splay: Origin,
}

impl Origins {
    pub fn any_fitted(&self) -> bool {
        [
            self.stance_height,
            self.reach,
            self.step_height,
            self.stride_length,
            self.splay,
        ]
        .contains(&Origin::Fitted)
    }
}

/// The most loaded servo standing on the gait's fewest feet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoLoad {
    /// Model joint index.
    pub joint: usize,
    /// N·m.
    pub torque: f64,
    /// |torque| / effort.
    pub share: f64,
    /// Feet carrying the weight.
    pub feet_down: usize,
}

/// A gait on a robot, and how it fits.
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    pub gait: Gait,
    pub origins: Origins,
    /// Joint room over a cycle at the nominal speed.
    pub margins: CycleMargins,
    pub load: ServoLoad,
    /// The body's lowest point above level ground, standing (m); None when the body's shape is
    /// unknown (a mesh hexsim cannot read).
    pub clearance: Option<f64>,
    /// 1, or the factor the fitted stride and step height were reduced by to find a stance.
    pub scale: f64,
    /// Joint angles per model joint, standing in the gait's pose.
    pub standing_pose: Vec<f64>,
    /// The steepest tilt the walk keeps its centre of mass over its support on (rad;
    /// [`GaitController::static_tilt`]).
    pub static_tilt: f64,
}

impl Fitted {
    /// One line per length, saying where it came from, and the stance's margins.
    pub fn describe(&self, model: &RobotModel) -> Vec<String> {
        let g = &self.gait;
        let o = &self.origins;
        let mut lines = vec![format!(
            "stance height {:.3} m ({}), reach {:.3} m ({}), step height {:.3} m ({}), stride {:.3} m ({}); nominal speed {:.3} m/s",
            g.stance_height,
            o.stance_height.describe(),
            g.reach,
            o.reach.describe(),
            g.step_height,
            o.step_height.describe(),
            g.stride_length,
            o.stride_length.describe(),
            g.nominal_speed()
        )];
        if g.splay != 0.0 || o.splay != Origin::Fitted {
            lines.push(format!(
                "front and rear feet splayed {:.0}° towards the body's ends ({}){}",
                g.splay.to_degrees(),
                o.splay.describe(),
                if o.splay == Origin::Fitted {
                    ": no steady stance with the legs as they point at rest"
                } else {
                    ""
                }
            ));
        }
        if self.scale < 1.0 {
            lines.push(format!(
                "the fitted stride and step height were scaled by {} to find a stance that fits",
                self.scale
            ));
        }
        lines.push(format!(
            "walking on level ground its centre of mass stays over the support on tilts up to {:.1}°{}",
            self.static_tilt.to_degrees(),
            if self.static_tilt >= STEADY_TILT {
                String::new()
            } else if (o.stance_height == Origin::Fitted || o.reach == Origin::Fitted)
                && self.static_tilt >= STEADY_FALLBACK_TILT
            {
                format!(
                    " (short of the {:.0}° of a steady stance: none with {:.0}° of joint room reaches it, so the fit took one steady to {:.0}°)",
                    STEADY_TILT.to_degrees(),
                    STEADY_ROOM.to_degrees(),
                    STEADY_FALLBACK_TILT.to_degrees()
                )
            } else if self.origins.stance_height == Origin::Fitted
                || self.origins.reach == Origin::Fitted
            {
                format!(
                    " (less than the {:.0}° of a steady stance: the fit found none with {:.0}° of joint room)",
                    STEADY_TILT.to_degrees(),
                    STEADY_ROOM.to_degrees()
                )
            } else {
                format!(
                    " (less than the {:.0}° of a steady stance; the stance is given)",
                    STEADY_TILT.to_degrees()
                )
            }
        ));
        let (joint, room) = self.margins.worst;
        let clearance = self.clearance.map_or(String::new(), |c| {
            format!("; body {c:.3} m above the ground")
        });
        let links = self.margins.link_clearance;
        let clearance = if links.is_finite() {
            format!(
                "{clearance}; links other than the feet {:.3} m above it at their lowest over the cycle",
                links
            )
        } else {
            clearance
        };
        lines.push(format!(
            "least joint room over a cycle {:.0}° ({}); most loaded servo {} at {:.0} % of its effort on {} feet{clearance}",
            room.to_degrees(),
            model.joints[joint].name,
            model.joints[self.load.joint].name,
            100.0 * self.load.share,
            self.load.feet_down
        ));
        lines
    }
}

/// Why a gait cannot be fitted to a robot.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct FitError(pub String);

/// The gait `spec` on `model`: the lengths it leaves out taken from the robot file or fitted
/// (see the module's doc), then checked as a whole. Given lengths are kept, and an error says
/// why they do not fit (the miss).
pub fn fit(model: &RobotModel, spec: &GaitSpec) -> Result<Fitted, FitError> {
    fit_to(model, spec, [STEADY_TILT, STEADY_FALLBACK_TILT])
}

/// [`fit`] with the bars of a steady stance, `[bar, fallback]` (rad).
fn fit_to(model: &RobotModel, spec: &GaitSpec, bars: [f64; 2]) -> Result<Fitted, FitError> {
    let hints = &model.gait_hints;
    let pick = |file: Option<f64>, robot: Option<f64>| match (file, robot) {
        (Some(v), _) => (Some(v), Origin::GaitFile),
        (None, Some(v)) => (Some(v), Origin::RobotFile),
        (None, None) => (None, Origin::Fitted),
    };
    let (stance_height, o_stance) = pick(spec.stance_height, hints.stance_height);
    let (reach, o_reach) = pick(spec.reach, hints.reach);
    let (step_height, o_step) = pick(spec.step_height, hints.step_height);
    let (stride_length, o_stride) = pick(spec.stride_length, hints.stride_length);
    let (splay, o_splay) = pick(spec.splay_deg.map(f64::to_radians), None);
    let origins = Origins {
        stance_height: o_stance,
        reach: o_reach,
        step_height: o_step,
        stride_length: o_stride,
        splay: o_splay,
    };
    let leg = leg_length(model);
    let feet_down = minimum_support(&spec.offsets(), spec.duty_factor).max(1);
    let gait = |scale: f64, h: f64, r: f64, splay: f64| Gait {
        name: spec.name.clone(),
        period: spec.period,
        duty_factor: spec.duty_factor,
        stride_length: stride_length.unwrap_or(STRIDE_PER_LEG * leg * scale),
        step_height: step_height.unwrap_or(STEP_PER_LEG * leg * scale),
        stance_height: h,
        reach: r,
        splay,
        swing: spec.swing,
        offsets: spec.offsets(),
    };
    let depth = body_depth(model);
    let measure = |gait: Gait, scale: f64| measure(model, gait, origins, feet_down, depth, scale);
    if let (Some(h), Some(r)) = (stance_height, reach) {
        // nothing to search: the stance is given; check it
        return measure(gait(1.0, h, r, splay.unwrap_or(0.0)), 1.0);
    }
    let scalable = stride_length.is_none() || step_height.is_none();
    let scales: &[f64] = if scalable { &[1.0, 0.5, 0.25] } else { &[1.0] };
    let mut closest: Vec<Assessment> = Vec::new();
    let splays: &[f64] = match &splay {
        Some(given) => std::slice::from_ref(given),
        None => &SPLAYS,
    };
    for &scale in scales {
        let search = |splay: f64| {
            Search {
                model,
                leg,
                body_depth: depth,
                feet_down,
                gait: &|h, r| gait(scale, h, r, splay),
                link_margin: if splay == 0.0 {
                    0.0
                } else {
                    SPLAYED_LINK_MARGIN
                },
                bars,
            }
            .run(stance_height, reach)
        };
        let (best, near) = search(splays[0]);
        if let Some(found) = best {
            // far from steady with the legs as they point: the least splay that is steady, else
            // the least steady to the fallback
            let tilt = || {
                GaitController::for_cycle(model, gait(scale, found.height, found.reach, splays[0]))
                    .map_or(0.0, |c| c.static_tilt(model))
            };
            let steady = (found.steadiness == 0 && splay.is_none() && tilt() < SPLAY_BELOW)
                .then(|| {
                    let mut fallback = None;
                    for &splay in &splays[1..] {
                        match search(splay).0 {
                            Some(b) if b.steadiness == 2 => return Some((b, splay)),
                            Some(b) if b.steadiness == 1 => {
                                fallback = fallback.or(Some((b, splay)));
                            }
                            _ => {}
                        }
                    }
                    fallback
                })
                .flatten();
            let (chosen, splay) = steady.unwrap_or((found, splays[0]));
            return measure(gait(scale, chosen.height, chosen.reach, splay), scale);
        }
        closest = near;
    }
    let reasons: Vec<String> = closest.iter().map(|a| a.explain(model)).collect();
    Err(FitError(format!(
        "no feasible stance for gait `{}` on this robot (searched stance heights {:.3}–{:.3} m and reaches {:.3}–{:.3} m{}); what binds, at the stance closest to fitting for each reason: {}",
        spec.name,
        0.05 * leg,
        0.95 * leg,
        0.05 * leg,
        leg,
        if scalable {
            ", with the stride and step height down to a quarter"
        } else {
            ""
        },
        reasons.join("; ")
    )))
}

/// The legs' mean length: hip to foot centre along the segments (m).
fn leg_length(model: &RobotModel) -> f64 {
    let total: f64 = model
        .legs
        .iter()
        .map(|leg| statics::segment_lengths(model, leg).iter().sum::<f64>())
        .sum();
    total / model.legs.len().max(1) as f64
}

/// How far the body's lowest point hangs below the hips' plane (m), when the body's shape is known
/// (read once: it may read a mesh file).
fn body_depth(model: &RobotModel) -> Option<f64> {
    model
        .body_bottom()
        .map(|bottom| model.hips_plane() - bottom)
}

/// The gait on the robot, measured: its standing pose, joint room, servo load and clearance.
fn measure(
    model: &RobotModel,
    gait: Gait,
    origins: Origins,
    feet_down: usize,
    body_depth: Option<f64>,
    scale: f64,
) -> Result<Fitted, FitError> {
    let controller =
        GaitController::for_cycle(model, gait.clone()).map_err(|e| FitError(e.to_string()))?;
    let standing_pose = model.pose_from_legs(&controller.standing_angles());
    let margins = cycle_margins(model, &gait).map_err(|e| FitError(e.to_string()))?;
    Ok(Fitted {
        static_tilt: controller.static_tilt(model),
        load: load_in(model, &standing_pose, feet_down),
        clearance: body_depth.map(|depth| gait.stance_height - depth),
        standing_pose,
        gait,
        origins,
        margins,
        scale,
    })
}

/// The most loaded servo standing in `pose` on `feet_down` feet.
fn load_in(model: &RobotModel, pose: &[f64], feet_down: usize) -> ServoLoad {
    let torques = statics::standing_torques(model, pose, GRAVITY, feet_down);
    let (joint, share) = torques
        .iter()
        .enumerate()
        .map(|(j, t)| (j, t.abs() / model.joints[j].effort))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0, 0.0));
    ServoLoad {
        joint,
        torque: torques.get(joint).copied().unwrap_or(0.0),
        share,
        feet_down,
    }
}

/// What keeps a candidate stance from fitting.
#[derive(Debug, Clone, PartialEq)]
enum Problem {
    /// The standing position or swing apex is out of a leg's reach.
    Stance(StanceError),
    /// A foot target during the cycle is out of reach.
    Cycle {
        leg: usize,
        time: f64,
        angles: LegAngles,
    },
    Torque(ServoLoad),
    /// The body's lowest point is this far above the ground, less than a step height.
    Clearance(f64),
    /// A link other than a foot reaches this far below the level ground over the cycle
    /// ([`super::margins::CycleMargins::link_clearance`]): a shin or a knee walked on.
    Links(f64),
}

/// A candidate stance judged.
#[derive(Debug, Clone, PartialEq)]
struct Assessment {
    stance_height: f64,
    reach: f64,
    step_height: f64,
    /// The score to maximise, or what is wrong with the stance.
    outcome: Result<f64, Problem>,
    /// How steady the stance is ([`Search::bars`], with [`STEADY_ROOM`]): 2 to the bar, 1 to
    /// the fallback only, 0 to neither or when it fails.
    steadiness: u8,
    /// How far from fitting (0 when it fits): the miss over the leg length, the torque excess
    /// as a share of the effort, the clearance shortfall over the leg length.
    penalty: f64,
}

impl Assessment {
    /// What binds, in words: which joint at which limit, which servo, or the body's height.
    fn explain(&self, model: &RobotModel) -> String {
        let at = format!(
            "stance height {:.3} m, reach {:.3} m",
            self.stance_height, self.reach
        );
        let limits = |leg: usize, angles: LegAngles| {
            let leg = &model.legs[leg];
            let bound: Vec<String> = leg
                .joints
                .iter()
                .zip(angles.iter().copied())
                .filter_map(|(&j, q)| {
                    let joint = &model.joints[j];
                    let (which, limit) = if (q - joint.lower).abs() < 1e-6 {
                        ("lower", joint.lower)
                    } else if (q - joint.upper).abs() < 1e-6 {
                        ("upper", joint.upper)
                    } else {
                        return None;
                    };
                    Some(format!(
                        "joint `{}` at its {which} limit {:.0}°",
                        joint.name,
                        limit.to_degrees()
                    ))
                })
                .collect();
            if bound.is_empty() {
                format!("leg {} is stretched out (no joint at a limit)", leg.name)
            } else {
                format!("leg {}: {}", leg.name, bound.join(", "))
            }
        };
        match &self.outcome {
            Ok(_) => format!("{at}: it fits"),
            Err(Problem::Stance(e)) => format!(
                "{at}: {} ({})",
                limits(e.leg, e.angles),
                if e.lift {
                    format!(
                        "lifting the foot {:.3} m misses by {:.1} mm",
                        self.step_height,
                        e.miss * 1e3
                    )
                } else {
                    format!(
                        "the standing foot position misses by {:.1} mm",
                        e.miss * 1e3
                    )
                }
            ),
            Err(Problem::Cycle { leg, time, angles }) => format!(
                "{at}: {} ({:.2} s into the cycle, the foot target is out of reach)",
                limits(*leg, *angles),
                time
            ),
            Err(Problem::Torque(load)) => {
                let joint = &model.joints[load.joint];
                format!(
                    "{at}: joint `{}` must hold {:.3} N·m standing on {} feet, {:.0} % of its effort {} N·m (at most {:.0} % leaves room to move)",
                    joint.name,
                    load.torque.abs(),
                    load.feet_down,
                    100.0 * load.share,
                    joint.effort,
                    100.0 * TORQUE_SHARE
                )
            }
            Err(Problem::Clearance(c)) => format!(
                "{at}: the body's lowest point is {:.3} m above the ground, less than the step height {:.3} m",
                c, self.step_height
            ),
            Err(Problem::Links(c)) => format!(
                "{at}: a link other than a foot reaches {:.1} mm into the level ground over the cycle",
                -c * 1e3
            ),
        }
    }
}

/// The stance a [`Search`] chose.
#[derive(Debug, Clone, Copy)]
struct Found {
    height: f64,
    reach: f64,
    /// As [`Assessment`]'s.
    steadiness: u8,
}

/// The grid search over the free stance lengths.
struct Search<'a> {
    model: &'a RobotModel,
    leg: f64,
    /// [`body_depth`], read once (it may read a mesh file).
    body_depth: Option<f64>,
    feet_down: usize,
    gait: &'a dyn Fn(f64, f64) -> Gait,
    /// How far every link other than a foot must stay above the level ground over the cycle
    /// (m): 0, or [`SPLAYED_LINK_MARGIN`] for a splayed stance.
    link_margin: f64,
    /// The tilts a steady stance keeps its plumb line inside the support on (rad): the bar,
    /// [`STEADY_TILT`], and the fallback taken when no stance reaches it,
    /// [`STEADY_FALLBACK_TILT`].
    bars: [f64; 2],
}

impl Search<'_> {
    fn assess(&self, h: f64, r: f64) -> Assessment {
        let gait = (self.gait)(h, r);
        let judged = |outcome: Result<f64, Problem>, penalty: f64| Assessment {
            stance_height: h,
            reach: r,
            step_height: gait.step_height,
            outcome,
            steadiness: 0,
            penalty,
        };
        let controller = match GaitController::for_cycle(self.model, gait.clone()) {
            Ok(c) => c,
            Err(e) => {
                let penalty = 1.0 + e.miss / self.leg;
                return judged(Err(Problem::Stance(e)), penalty);
            }
        };
        if let Some(c) = self.body_depth.map(|depth| h - depth)
            && c < gait.step_height
        {
            let penalty = (gait.step_height - c) / self.leg;
            return judged(Err(Problem::Clearance(c)), penalty);
        }
        let pose = self.model.pose_from_legs(&controller.standing_angles());
        let load = load_in(self.model, &pose, self.feet_down);
        if load.share > TORQUE_SHARE {
            return judged(Err(Problem::Torque(load)), load.share - TORQUE_SHARE);
        }
        let margins = match sampled_margins(self.model, &gait, SEARCH_SAMPLES) {
            Ok(m) => m,
            Err(e) => {
                let penalty = 1.0 + e.miss / self.leg;
                return judged(Err(Problem::Stance(e)), penalty);
            }
        };
        // the report's finer cycle must reach every target too: between the search's instants a
        // leg can pass out of reach (ant_bot's front right, 0.47 s into the cycle)
        let unreached = margins.unreached.or_else(|| {
            cycle_margins(self.model, &gait)
                .ok()
                .and_then(|fine| fine.unreached)
        });
        if let Some(u) = unreached {
            return judged(
                Err(Problem::Cycle {
                    leg: u.leg,
                    time: u.time,
                    angles: u.angles,
                }),
                0.5,
            );
        }
        if margins.link_clearance < self.link_margin {
            let c = margins.link_clearance;
            return judged(Err(Problem::Links(c)), -c / self.leg);
        }
        let mean = margins.per_joint.iter().sum::<f64>() / margins.per_joint.len().max(1) as f64;
        let steadiness = if margins.worst.1 >= STEADY_ROOM {
            let tilt = controller.static_tilt(self.model);
            self.bars.iter().filter(|&&bar| tilt >= bar).count() as u8
        } else {
            0
        };
        Assessment {
            steadiness,
            ..judged(Ok(margins.worst.1 + MEAN_WEIGHT * mean), 0.0)
        }
    }

    /// The best (stance height, reach) with the given ones held, how steady it is, and the
    /// failure closest to fitting of each kind (reach, torque, the body's clearance, the other
    /// links').
    fn run(&self, h: Option<f64>, r: Option<f64>) -> (Option<Found>, Vec<Assessment>) {
        let axis = |given: Option<f64>, from: f64, to: f64| match given {
            Some(v) => (v, v, 0.0),
            None => {
                let step = (to - from) * self.leg / (GRID - 1) as f64;
                (from * self.leg, to * self.leg, step)
            }
        };
        let (h_lo, h_hi, mut h_step) = axis(h, 0.05, 0.95);
        let (r_lo, r_hi, mut r_step) = axis(r, 0.05, 1.0);
        let points = |lo: f64, hi: f64, step: f64| -> Vec<f64> {
            if step == 0.0 {
                vec![lo]
            } else {
                (0..)
                    .map(|k| lo + step * k as f64)
                    .take_while(|v| *v <= hi + 1e-12)
                    .collect()
            }
        };
        // the best stance, the best steady to the fallback, and the best steady to the bar: the
        // steadiest found is taken
        let mut best: [Option<Assessment>; 3] = [None, None, None];
        let mut closest: [Option<Assessment>; 4] = [None, None, None, None];
        let consider = |a: Assessment,
                        best: &mut [Option<Assessment>; 3],
                        closest: &mut [Option<Assessment>; 4]| {
            match a.outcome {
                Ok(score) => {
                    let better = |b: &Option<Assessment>| {
                        b.as_ref()
                            .is_none_or(|b| b.outcome.as_ref().is_ok_and(|&s| score > s))
                    };
                    for steadiest in &mut best[1..=a.steadiness as usize] {
                        if better(steadiest) {
                            *steadiest = Some(a.clone());
                        }
                    }
                    if better(&best[0]) {
                        best[0] = Some(a);
                    }
                }
                Err(ref problem) => {
                    let kind = match problem {
                        Problem::Stance(_) | Problem::Cycle { .. } => 0,
                        Problem::Torque(_) => 1,
                        Problem::Clearance(_) => 2,
                        Problem::Links(_) => 3,
                    };
                    if closest[kind].as_ref().is_none_or(|c| a.penalty < c.penalty) {
                        closest[kind] = Some(a);
                    }
                }
            }
        };
        for &hv in &points(h_lo, h_hi, h_step) {
            for &rv in &points(r_lo, r_hi, r_step) {
                consider(self.assess(hv, rv), &mut best, &mut closest);
            }
        }
        // refine twice: a 5 × 5 grid at half the spacing around the best
        let chosen = |best: &[Option<Assessment>; 3]| best.iter().rev().flatten().next().cloned();
        for _ in 0..2 {
            let Some(centre) = chosen(&best) else { break };
            h_step /= 2.0;
            r_step /= 2.0;
            let around = |c: f64, step: f64, lo: f64, hi: f64| -> Vec<f64> {
                if step == 0.0 {
                    return vec![c];
                }
                (-2..=2)
                    .map(|k| c + step * k as f64)
                    .filter(|v| *v >= lo - 1e-12 && *v <= hi + 1e-12)
                    .collect()
            };
            for &hv in &around(centre.stance_height, h_step, h_lo, h_hi) {
                for &rv in &around(centre.reach, r_step, r_lo, r_hi) {
                    if (hv, rv) != (centre.stance_height, centre.reach) {
                        consider(self.assess(hv, rv), &mut best, &mut closest);
                    }
                }
            }
        }
        (
            chosen(&best).map(|b| Found {
                height: b.stance_height,
                reach: b.reach,
                steadiness: b.steadiness,
            }),
            closest.into_iter().flatten().collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::GaitHints;
    use std::path::Path;

    fn tripod() -> GaitSpec {
        GaitSpec::from_toml(include_str!("../../gaits/tripod.toml"), Path::new("tripod")).unwrap()
    }

    /// hex18 without its robot file's stance: the fit's answer meets every constraint it states,
    /// and no stance around it (a step of the search's finest grid either way in height and
    /// reach, 3.75 and 3.96 mm) scores higher. (Nearer than the grid the search does not look: 2 mm
    /// higher scores 0.9956 against its 0.9946, since the gait's IK follows its last answer;
    /// before, it jumped branch there and scored 0.33.)
    #[test]
    fn the_fitted_stance_meets_its_constraints_and_is_a_local_best() {
        let model = RobotModel {
            gait_hints: GaitHints::default(),
            ..crate::robot::hex18_for_tests()
        };
        let fitted = fit(&model, &tripod()).unwrap();
        let g = &fitted.gait;
        assert!(fitted.origins.any_fitted());
        assert_eq!(fitted.scale, 1.0);
        // L = 0.25 m: a quarter and an eighth
        assert!((g.stride_length - 0.0625).abs() < 1e-9 && (g.step_height - 0.03125).abs() < 1e-9);
        assert!(fitted.margins.unreached.is_none() && fitted.margins.worst.1 > 0.0);
        assert!(fitted.load.share <= TORQUE_SHARE && fitted.load.feet_down == 3);
        assert!(fitted.clearance.unwrap() >= g.step_height);
        let search = Search {
            model: &model,
            leg: leg_length(&model),
            body_depth: body_depth(&model),
            feet_down: 3,
            link_margin: 0.0,
            bars: [STEADY_TILT, STEADY_FALLBACK_TILT],
            gait: &|h, r| Gait {
                stance_height: h,
                reach: r,
                ..g.clone()
            },
        };
        let best = search.assess(g.stance_height, g.reach).outcome.unwrap();
        // the grid's spacing after the search's two refinements (`Search::run`)
        let (h, r) = (
            0.9 * search.leg / (GRID - 1) as f64 / 4.0,
            0.95 * search.leg / (GRID - 1) as f64 / 4.0,
        );
        for (dh, dr) in [(h, 0.0), (-h, 0.0), (0.0, r), (0.0, -r)] {
            if let Ok(score) = search.assess(g.stance_height + dh, g.reach + dr).outcome {
                assert!(score <= best + 1e-9, "({dh}, {dr}): {score} > {best}");
            }
        }
    }

    /// Each length comes from the gait file, else the robot file, else the fit.
    /// Where no stance reaches the bar of a steady stance, the fit takes the fallback's, not
    /// the stance with the most room: hex18's legs with no stance of their own (the most room
    /// is steady to 56°), asked for 89° (no stance is) and then 60°, stand as asked for 60°
    /// alone, steadier than with the most room.
    #[test]
    fn a_bar_no_stance_reaches_falls_back_to_the_next() {
        let model = RobotModel {
            gait_hints: GaitHints::default(),
            ..crate::robot::hex18_for_tests()
        };
        let degrees = |d: f64| d.to_radians();
        let at = |bars: [f64; 2]| {
            let fitted = fit_to(&model, &tripod(), bars).unwrap();
            (
                fitted.gait.stance_height,
                fitted.gait.reach,
                fitted.static_tilt,
            )
        };
        let steady = at([degrees(60.0), degrees(60.0)]);
        let fallen_back = at([degrees(89.0), degrees(60.0)]);
        let most_room = at([degrees(89.0), degrees(89.0)]);
        println!("60°: {steady:?}; 89° then 60°: {fallen_back:?}; most room: {most_room:?}");
        assert_eq!(fallen_back, steady);
        assert!(steady.2 >= degrees(60.0), "{steady:?}");
        assert!(most_room.2 < steady.2, "{most_room:?} against {steady:?}");
    }

    #[test]
    fn given_lengths_win_over_the_robot_file_and_the_fit() {
        let model = crate::robot::hex18_for_tests(); // robot file: 0.10, 0.15, 0.03, 0.06
        let spec = GaitSpec {
            stance_height: Some(0.12),
            ..tripod()
        };
        let fitted = fit(&model, &spec).unwrap();
        assert_eq!(fitted.gait.stance_height, 0.12);
        assert_eq!(fitted.origins.stance_height, Origin::GaitFile);
        assert_eq!(fitted.gait.reach, 0.15);
        assert_eq!(fitted.origins.reach, Origin::RobotFile);
        let bare = RobotModel {
            gait_hints: GaitHints {
                reach: Some(0.16),
                ..GaitHints::default()
            },
            ..model
        };
        let fitted = fit(&bare, &spec).unwrap();
        assert_eq!(fitted.gait.reach, 0.16);
        assert_eq!(fitted.origins.step_height, Origin::Fitted);
        assert_eq!(fitted.gait.stance_height, 0.12);
    }

    /// Given lengths that do not fit are refused with the miss, not searched around.
    #[test]
    fn a_given_stance_out_of_reach_is_an_error() {
        let spec = GaitSpec {
            stance_height: Some(0.4),
            ..tripod()
        };
        let e = fit(&crate::robot::hex18_for_tests(), &spec).unwrap_err();
        assert!(
            e.0.contains("cannot reach its standing foot position"),
            "{e}"
        );
    }

    /// A load ten times hex18's on its legs: the servos are stiffened until a foot, free to
    /// slide, sags [`SAG_LIMIT`] of the step and no more; hex18's own load leaves them alone.
    #[test]
    fn servos_are_stiffened_against_sag() {
        use crate::robot::servo::{FittedFor, SAG_LIMIT, fitted_gains, vertical_compliance};
        let model = crate::robot::hex18_for_tests();
        let pose = fit(&model, &tripod()).unwrap().standing_pose;
        let load = model.total_mass() * 9.81 / 3.0;
        let compliance = vertical_compliance(&model, &pose);
        let (k, _, why) = fitted_gains(&model, &pose, load, 0.03);
        assert_ne!(why, FittedFor::Sag);
        assert!(load * compliance / k < SAG_LIMIT * 0.03);
        let (k, d, why) = fitted_gains(&model, &pose, 10.0 * load, 0.03);
        assert_eq!(why, FittedFor::Sag);
        assert!((10.0 * load * compliance / k - SAG_LIMIT * 0.03).abs() < 1e-12);
        assert!((d / k - crate::robot::servo::REFERENCE_DAMPING / 20.0).abs() < 1e-15);
    }

    /// hex18 standing in its fitted pose gets the reference servo; legs ten times as heavy get
    /// ten times the stiffness and damping (same bandwidth, same damping time).
    #[test]
    fn heavier_legs_get_proportionally_stiffer_servos() {
        use crate::robot::servo::{
            BANDWIDTH, REFERENCE_DAMPING, REFERENCE_STIFFNESS, fitted_gains, outboard_inertias,
        };
        let model = crate::robot::hex18_for_tests();
        let pose = fit(&model, &tripod()).unwrap().standing_pose;
        // hex18's load on three feet and step: its sag does not bind
        let load = model.total_mass() * 9.81 / 3.0;
        let (k, d, _) = fitted_gains(&model, &pose, load, 0.03);
        let coxa = outboard_inertias(&model, &pose)[model.legs[0].joints[0]];
        assert!(BANDWIDTH * BANDWIDTH * coxa < REFERENCE_STIFFNESS * 1.05);
        assert_eq!((k, d), (REFERENCE_STIFFNESS, REFERENCE_DAMPING));
        let mut heavy = model.clone();
        for leg in &model.legs {
            for &j in &leg.joints {
                let link = &mut heavy.links[model.joints[j].child];
                link.mass *= 10.0;
                link.inertia *= 10.0;
            }
        }
        let (k10, d10, _) = fitted_gains(&heavy, &pose, heavy.total_mass() * 9.81 / 3.0, 0.03);
        let heavy_coxa = outboard_inertias(&heavy, &pose)[model.legs[0].joints[0]];
        assert!((heavy_coxa / coxa - 10.0).abs() < 1e-9);
        assert!((k10 - BANDWIDTH * BANDWIDTH * heavy_coxa).abs() < 1e-9);
        assert!((d10 / k10 - REFERENCE_DAMPING / REFERENCE_STIFFNESS).abs() < 1e-12);
    }
}
