//! Inverse kinematics of a redundant leg: four to six revolute joints placing a foot's centre (a
//! point: three coordinates), so one to three degrees of freedom are left over — a tarsus, a
//! hip roll. They are resolved by a posture: the leg's extra joints (`Leg::posture`: the joints
//! beyond the three that sweep the largest workspace) are pulled towards their rest angles, and
//! the foot goes where it is sent.
//!
//! Each iteration takes the weighted, damped least-squares step of Levenberg–Marquardt with a
//! posture objective (Nakamura, *Advanced Robotics: Redundancy and Optimization*, 1991, §4;
//! Chan & Dubey, "A weighted least-norm solution based scheme for avoiding joint limits for
//! redundant joint manipulators", IEEE T-RA 11(2), 1995; Buss, "Introduction to inverse
//! kinematics with Jacobian transpose, pseudoinverse and damped least squares methods", 2004):
//! the minimiser of
//!
//! ½ΔqᵀHΔq + ½λ⁻²‖JΔq − e‖²,  H = W + εI,
//!
//! (e the foot's error, J its 3×n Jacobian, W = 1 on the extra joints and 0 on the three), which
//! by the Woodbury identity needs only a 3×3 inverse, plus the posture's step b = W(r − q) (r the
//! rest angles) projected onto the null space of J in the same metric (Liégeois's gradient
//! projection, 1977):
//!
//! Δq = H⁻¹Jᵀ (JH⁻¹Jᵀ + λ²I)⁻¹ e + γ (I − H⁻¹Jᵀ (JH⁻¹Jᵀ)⁻¹ J) H⁻¹b.
//!
//! The weight H⁻¹ makes the posture's step compensated by the three joints (cost ε) rather than
//! the extra ones (cost 1 + ε): a weighted least-norm step. The solve runs in three phases, each
//! a loop of such steps:
//!
//! 1. **reach** (γ = 0, the task alone, H = I: plain damped least squares): Levenberg–Marquardt
//!    on the foot's error, λ² = μ·[`LAMBDA_SCALE`]; a step that brings the foot nearer is taken
//!    and μ lowered, else μ is raised tenfold (a shorter step, turning towards the error's
//!    gradient), until the foot is
//!    within [`ON_TARGET`] or no step helps (a target out of reach: the closest point a local
//!    descent finds from the guess);
//! 2. **settle** (once the foot is within [`POSTURE_NEAR`]): the posture's step with the task's
//!    correction, λ² ≈ 0, then *reach* back onto the target (a projection onto the poses that
//!    reach it); taken when the foot is as near as before and the posture nearer rest, else its
//!    gain γ is halved, until the step is below [`SETTLED_STEP`].
//!
//! The posture's step vanishes when H⁻¹b lies in the row space of J: the first-order condition
//! of the extra joints' least distance from rest among the poses that reach the target. Where the
//! three joints reach it alone, the extra ones stay at rest (the pose a leg held at rest takes);
//! they move where the three cannot — a target beyond their reach, or past a limit.
//!
//! Joint limits: a joint at a limit that the step would push past is taken out of the step (its
//! column and posture dropped, the step solved again on the others: an active set), and every
//! step is clamped to the limits. The answer depends only on the target and the guess (no
//! randomness, fixed iteration bounds): deterministic; warm-started from the last answer it moves
//! little and smoothly from one step of a walk to the next.

use super::kinematics::{IkSolution, JointFrames, LegAngles, LegChain, MAX_LEG_JOINTS};
use glam::{DMat3, DVec3};

/// The posture is settled once the foot is this near its target (m).
const POSTURE_NEAR: f64 = 1e-4;
/// The three joints' share of the step's cost (the extra joints': 1 + ε).
const EPSILON: f64 = 1e-3;
/// Levenberg–Marquardt's damping: its start and bounds, and λ² per unit μ (m²: the scale of
/// JJᵀ, a 0.2 m leg's |J|²).
const MU_START: f64 = 1e-3;
const MU_LEAST: f64 = 1e-12;
const MU_MOST: f64 = 1e8;
const LAMBDA_SCALE: f64 = 0.04;
/// The null-space projector's damping (JH⁻¹Jᵀ's units, m²/ε): keeps it finite at a stretched
/// leg.
const NULL_DAMPING: f64 = 1e-9;
/// The posture step's gain at which settling gives up, and the step (rad) at which it has
/// settled (1e-9 rad moves a 0.2 m leg's foot 0.2 nm).
const LEAST_GAIN: f64 = 1e-6;
const SETTLED_STEP: f64 = 1e-9;
/// A foot this near its target (m) is on it (a hundredth of
/// [`IK_TOLERANCE`](super::kinematics::IK_TOLERANCE)).
const ON_TARGET: f64 = super::kinematics::IK_TOLERANCE * 1e-2;
/// Iterations at most (a warm start needs a few; a cold one some tens).
const MOST_ITERATIONS: usize = 1000;
/// A step shorter than this (rad, largest joint) is no step: converged.
const LEAST_STEP: f64 = 1e-13;

/// The state of one trial: angles, their forward kinematics, the foot's error and the posture's
/// squared distance from rest.
struct Trial {
    q: LegAngles,
    joints: JointFrames,
    foot: DVec3,
    error: f64,
    posture: f64,
}

impl Trial {
    fn at(chain: &LegChain, target: DVec3, q: LegAngles) -> Self {
        let (joints, foot, _) = chain.frames(&q);
        let posture = q
            .iter()
            .zip(&chain.rest)
            .filter(|(_, r)| !r.is_nan())
            .map(|(a, r)| (a - r).powi(2))
            .sum();
        Trial {
            q,
            joints,
            foot,
            error: (target - foot).length(),
            posture,
        }
    }
}

/// The weighted damped least-squares step from `trial` (see the module's doc), with the joints
/// marked in `locked` out of it.
fn step(
    chain: &LegChain,
    trial: &Trial,
    target: DVec3,
    mu: f64,
    gain: f64,
    locked: &[bool; MAX_LEG_JOINTS],
) -> [f64; MAX_LEG_JOINTS] {
    let n = trial.q.len();
    let e = target - trial.foot;
    // H⁻¹ (diagonal) and γb, zero on locked joints
    let mut h_inv = [0.0; MAX_LEG_JOINTS];
    let mut b = [0.0; MAX_LEG_JOINTS];
    let mut columns = [DVec3::ZERO; MAX_LEG_JOINTS];
    for k in 0..n {
        if locked[k] {
            continue;
        }
        let (origin, axis) = trial.joints[k];
        columns[k] = axis.cross(trial.foot - origin);
        let rest = chain.rest[k];
        if gain == 0.0 {
            // the task alone: every joint alike (plain damped least squares)
            h_inv[k] = 1.0;
        } else if rest.is_nan() {
            h_inv[k] = 1.0 / EPSILON;
        } else {
            h_inv[k] = 1.0 / (1.0 + EPSILON);
            b[k] = gain * (rest - trial.q[k]);
        }
    }
    // B = J H⁻¹ Jᵀ, and J H⁻¹ γb
    let mut jhj = DMat3::ZERO;
    let mut jhb = DVec3::ZERO;
    for k in 0..n {
        let c = columns[k];
        jhj += DMat3::from_cols(c * c.x, c * c.y, c * c.z) * h_inv[k];
        jhb += c * (h_inv[k] * b[k]);
    }
    let damped = |lambda2: f64| (jhj + DMat3::from_diagonal(DVec3::splat(lambda2))).inverse();
    // the task's step, damped by μ; the posture's, projected onto J's null space (undamped:
    // it moves the foot at second order only, whatever μ)
    let task = damped(mu * LAMBDA_SCALE) * e;
    let null = damped(NULL_DAMPING) * jhb;
    let mut dq = [0.0; MAX_LEG_JOINTS];
    for k in 0..n {
        dq[k] = h_inv[k] * (b[k] + columns[k].dot(task - null));
    }
    dq
}

/// The step from `trial`, with every joint at a limit that it would push past locked (an active
/// set: each lock is followed by a new step on the joints left).
fn step_within_limits(
    chain: &LegChain,
    trial: &Trial,
    target: DVec3,
    mu: f64,
    gain: f64,
) -> [f64; MAX_LEG_JOINTS] {
    let n = trial.q.len();
    let mut locked = [false; MAX_LEG_JOINTS];
    loop {
        let dq = step(chain, trial, target, mu, gain, &locked);
        let mut more = false;
        for k in 0..n {
            let pushed_past = (trial.q[k] <= chain.lower[k] && dq[k] < 0.0)
                || (trial.q[k] >= chain.upper[k] && dq[k] > 0.0);
            if !locked[k] && pushed_past {
                locked[k] = true;
                more = true;
            }
        }
        if !more {
            return dq;
        }
    }
}

/// The redundant leg's answer for `target` from `guess` (see the module's doc): the foot brought
/// to the target, then (on it) the posture settled.
pub(super) fn solve(chain: &LegChain, target: DVec3, guess: &LegAngles) -> IkSolution {
    let mut best = Trial::at(chain, target, chain.clamp(guess));
    let mut budget = MOST_ITERATIONS;
    reach(chain, target, &mut best, &mut budget);
    if best.error < POSTURE_NEAR {
        settle(chain, target, &mut best, &mut budget);
    }
    IkSolution {
        angles: best.q,
        error: best.error,
    }
}

/// `trial` moved by `dq`, within the limits.
fn moved(chain: &LegChain, target: DVec3, trial: &Trial, dq: &[f64; MAX_LEG_JOINTS]) -> Trial {
    let mut next = trial.q;
    for (angle, d) in next.iter_mut().zip(dq) {
        *angle += d;
    }
    Trial::at(chain, target, chain.clamp(next))
}

/// The task alone, Levenberg–Marquardt on the foot's error: a step that brings the foot nearer
/// is taken and μ lowered, else μ raised, until the foot is on the target or no step helps.
fn reach(chain: &LegChain, target: DVec3, best: &mut Trial, budget: &mut usize) {
    let mut mu = MU_START;
    while *budget > 0 && best.error > ON_TARGET {
        *budget -= 1;
        let dq = step_within_limits(chain, best, target, mu, 0.0);
        let largest = dq.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        if !largest.is_finite() || largest < LEAST_STEP {
            return;
        }
        let trial = moved(chain, target, best, &dq);
        if trial.error < best.error {
            *best = trial;
            mu = (mu * 0.1).max(MU_LEAST);
        } else {
            mu *= 10.0;
            if mu > MU_MOST {
                return;
            }
        }
    }
}

/// The posture: the extra joints towards rest in the null space of the foot's Jacobian (the
/// foot's error corrected in the same step), each step followed by [`reach`] back onto the
/// target, and taken when the foot is as near as before and the posture nearer rest; else its
/// gain is halved.
fn settle(chain: &LegChain, target: DVec3, best: &mut Trial, budget: &mut usize) {
    let mut gain = 1.0;
    while *budget > 0 {
        *budget -= 1;
        let dq = step_within_limits(chain, best, target, MU_LEAST, gain);
        let largest = dq.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        if !largest.is_finite() || largest < SETTLED_STEP {
            return;
        }
        let mut trial = moved(chain, target, best, &dq);
        reach(chain, target, &mut trial, budget);
        if trial.error <= best.error.max(ON_TARGET) && trial.posture < best.posture {
            *best = trial;
            gain = (gain * 2.0).min(1.0);
        } else {
            gain *= 0.5;
            if gain < LEAST_GAIN {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::model::{Foot, FootFrom, Joint, Leg, Link, RobotModel};
    use glam::DAffine3;

    /// A body and one leg of the joints `axes` (each at `offsets[k]` from the one before), the
    /// foot `foot` beyond the last, limits ±`limit`; the joints in `extra` pulled to zero.
    fn leg(
        axes: &[DVec3],
        offsets: &[DVec3],
        foot: DVec3,
        limit: f64,
        extra: &[usize],
    ) -> LegChain {
        let link = |name: String, parent_joint| Link {
            name,
            parent_joint,
            mass: 0.1,
            com: DVec3::ZERO,
            inertia: DMat3::IDENTITY * 1e-4,
            visuals: vec![],
            foot: None,
            contacts: vec![],
            merged: vec![],
        };
        let mut links = vec![link("body".into(), None)];
        let mut joints = vec![];
        for (k, (&axis, &at)) in axes.iter().zip(offsets).enumerate() {
            joints.push(Joint {
                name: format!("j{k}"),
                parent: k,
                child: k + 1,
                origin: DAffine3::from_translation(at),
                axis,
                lower: -limit,
                upper: limit,
                effort: 1.0,
            });
            links.push(link(format!("l{k}"), Some(k)));
        }
        let n = axes.len();
        let leg = Leg {
            name: "lf",
            joints: (0..n).collect(),
            posture: (0..n).map(|k| extra.contains(&k).then_some(0.0)).collect(),
            foot_link: n,
            foot: Foot {
                center: foot,
                radius: 0.01,
                from: FootFrom::Sphere,
            },
        };
        let model = RobotModel {
            name: "leg".into(),
            source: Default::default(),
            links,
            joints,
            legs: vec![leg.clone()],
            forward: crate::robot::legs::Forward::URDF_X,
            gait_hints: Default::default(),
            warnings: vec![],
            held: vec![],
        };
        LegChain::new(&model, &leg)
    }

    /// hex18's leg with a tarsus: coxa (yaw), femur, tibia, tarsus (pitch), the tibia cut to
    /// 0.08 m and a 0.04 m tarsus (tests/data/robots/hex18_tarsus.urdf's proportions).
    fn tarsus(limit: f64) -> LegChain {
        leg(
            &[DVec3::Z, DVec3::Y, DVec3::Y, DVec3::Y],
            &[
                DVec3::new(0.1, 0.05, 0.0),
                DVec3::new(0.04, 0.0, 0.0),
                DVec3::new(0.08, 0.0, 0.0),
                DVec3::new(0.08, 0.0, 0.0),
            ],
            DVec3::new(0.04, 0.0, 0.0),
            limit,
            &[3],
        )
    }

    /// The same with a hip roll between coxa and femur: five joints, two of them extra.
    fn five(limit: f64) -> LegChain {
        leg(
            &[DVec3::Z, DVec3::X, DVec3::Y, DVec3::Y, DVec3::Y],
            &[
                DVec3::new(0.1, 0.05, 0.0),
                DVec3::new(0.02, 0.0, 0.0),
                DVec3::new(0.02, 0.0, 0.0),
                DVec3::new(0.08, 0.0, 0.0),
                DVec3::new(0.08, 0.0, 0.0),
            ],
            DVec3::new(0.04, 0.0, 0.0),
            limit,
            &[1, 4],
        )
    }

    /// Deterministic pseudo-random numbers in [0, 1) (a 64-bit LCG: the test needs no crate).
    fn uniform(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    fn random_angles(chain: &LegChain, state: &mut u64, spread: f64) -> LegAngles {
        let mut q = LegAngles::zeros(chain.joint_count());
        for (k, a) in q.iter_mut().enumerate() {
            let (lo, hi) = (chain.lower[k] * spread, chain.upper[k] * spread);
            *a = lo + (hi - lo) * uniform(state);
        }
        q
    }

    /// Targets made by forward kinematics of random angles about a standing pose are reached
    /// within 1e-6 m from a guess elsewhere (the standing pose, and a pose up to 0.4 rad off the
    /// target's in each joint), within the limits, and the answer's foot is where forward
    /// kinematics puts it.
    #[test]
    fn reachable_targets_are_reached_within_a_micrometre() {
        for chain in [tarsus(1.5), five(1.5)] {
            let mut state = 7;
            let mut worst = 0.0f64;
            for _ in 0..500 {
                // a target about the standing pose (knee bent), as a walk's are: each joint
                // within ±0.5 rad of it
                let standing = chain.from_three([0.0, -0.3, 1.2]);
                let mut q = standing;
                for a in q.iter_mut() {
                    *a += uniform(&mut state) - 0.5;
                }
                let target = chain.foot_position(q);
                // from a pose 0.4 rad off in each joint (a walk's guess is a step's motion
                // away), and from the controller's first standing guess (knee bent)
                let mut near = q;
                for a in near.iter_mut() {
                    *a += 0.8 * (uniform(&mut state) - 0.5);
                }
                for guess in [near, standing] {
                    let answer = chain.solve(target, guess);
                    let reached = chain.foot_position(answer.angles);
                    assert!(
                        (reached - target).length() < 1e-6 && answer.error < 1e-6,
                        "{} joints: missed {target} from {guess:?} by {:.3e} m ({:?})",
                        chain.joint_count(),
                        (reached - target).length(),
                        answer.angles
                    );
                    assert!((answer.error - (reached - target).length()).abs() < 1e-12);
                    for (k, a) in answer.angles.iter().enumerate() {
                        assert!(chain.lower[k] <= *a && *a <= chain.upper[k], "{k}: {a}");
                    }
                    worst = worst.max(answer.error);
                }
            }
            println!("{} joints: worst error {worst:.2e} m", chain.joint_count());
        }
    }

    /// A target the three joints reach alone is reached with the extra joints at rest (the
    /// posture's minimum), and one beyond their reach with the tarsus bent: the held-at-rest leg
    /// misses it.
    #[test]
    fn the_extra_joints_stay_at_rest_until_the_three_cannot_reach() {
        let chain = tarsus(1.5);
        let mut guess = LegAngles::zeros(4);
        guess[1] = -0.3;
        guess[2] = 1.2;
        let three_reach = chain.foot_position([0.2, -0.4, 1.0, 0.0]);
        let answer = chain.solve(three_reach, guess);
        assert!(answer.error < 1e-6, "{answer:?}");
        assert!(answer.angles[3].abs() < 1e-6, "{:?}", answer.angles);
        // below the hip, farther out than femur + tibia reach with the tarsus straight: the
        // tarsus must bend (tibia 1.5 rad is its limit)
        let low = chain.foot_position([0.0, 0.6, 1.5, 1.2]);
        let answer = chain.solve(low, guess);
        assert!(answer.error < 1e-6, "{answer:?}");
        assert!(answer.angles[3].abs() > 0.1, "{:?}", answer.angles);
        // held at rest: the tarsus fixed at zero cannot reach it
        let held = leg(
            &[DVec3::Z, DVec3::Y, DVec3::Y],
            &[
                DVec3::new(0.1, 0.05, 0.0),
                DVec3::new(0.04, 0.0, 0.0),
                DVec3::new(0.08, 0.0, 0.0),
            ],
            DVec3::new(0.12, 0.0, 0.0),
            1.5,
            &[],
        );
        let miss = held.solve(low, [0.0, -0.3, 1.2]);
        assert!(miss.error > 5e-3, "held tarsus reaches it: {miss:?}");
    }

    /// A target out of reach gets the closest point the leg reaches within its limits: no
    /// random trial within the limits comes closer, and the limits hold.
    #[test]
    fn an_unreachable_target_gets_the_closest_point_within_the_limits() {
        for chain in [tarsus(1.0), five(1.0)] {
            let target = chain.hip() + DVec3::new(0.1, 0.0, -0.6); // far below: out of reach
            let mut guess = LegAngles::zeros(chain.joint_count());
            guess[1] = -0.3;
            guess[2] = 0.8;
            let answer = chain.solve(target, guess);
            let reached = chain.foot_position(answer.angles);
            assert!((answer.error - (reached - target).length()).abs() < 1e-12);
            for (k, a) in answer.angles.iter().enumerate() {
                assert!(chain.lower[k] <= *a && *a <= chain.upper[k], "{k}: {a}");
            }
            let mut state = 11;
            let closest = (0..20000)
                .map(|_| {
                    let q = random_angles(&chain, &mut state, 1.0);
                    (chain.foot_position(q) - target).length()
                })
                .fold(f64::INFINITY, f64::min);
            println!(
                "{} joints: {:.4} m from the target, random trials {:.4} m",
                chain.joint_count(),
                answer.error,
                closest
            );
            assert!(
                answer.error <= closest + 1e-9,
                "{} > {closest}",
                answer.error
            );
        }
    }

    /// The same target and guess give the same answer, bit for bit; a target moved a little
    /// moves the answer a little (warm-started, as a walk solves).
    #[test]
    fn answers_are_deterministic_and_smooth() {
        let chain = five(1.5);
        let mut guess = LegAngles::zeros(5);
        guess[2] = -0.3;
        guess[3] = 1.2;
        let start = chain.foot_position([0.1, 0.0, 0.7, 1.2, 0.4]);
        let a = chain.solve(start, guess);
        let b = chain.solve(start, guess);
        assert_eq!(a, b);
        let mut last = a.angles;
        // 0.37 mm a step, outwards and down (a stance's stroke at a walk's steps is finer)
        for i in 1..=100 {
            let target = start + DVec3::new(0.0003, 0.0001, -0.0002) * i as f64;
            let answer = chain.solve(target, last);
            assert!(answer.error < 1e-6, "{i}: {answer:?}");
            let jump = answer
                .angles
                .iter()
                .zip(last.iter())
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(jump < 0.02, "step {i}: a joint jumped {jump} rad");
            last = answer.angles;
        }
    }

    /// A target that is not a number gets an answer that says so (a NaN error, the guess kept),
    /// not a panic.
    #[test]
    fn a_nan_target_is_answered_without_a_panic() {
        let chain = tarsus(1.5);
        let guess = chain.from_three([0.0, -0.3, 1.2]);
        let answer = chain.solve(DVec3::NAN, guess);
        assert!(answer.error.is_nan(), "{answer:?}");
        assert_eq!(answer.angles, guess);
    }
}
