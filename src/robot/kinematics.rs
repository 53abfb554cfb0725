//! Leg kinematics from the URDF's geometry: forward kinematics of a 3-joint leg in the body frame,
//! and inverse kinematics by damped Newton iterations on the analytic Jacobian — general for any
//! three revolute joints, not only yaw-pitch-pitch legs.

use super::model::{Leg, RobotModel};
use glam::{DAffine3, DMat3, DQuat, DVec3};

/// One leg's chain, in the body (root link) frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LegChain {
    /// Joint k's origin in joint k−1's frame, both frames turned so their joint axis is z
    /// (Aₖ₋₁ᵀ·Oₖ·Aₖ, Aₖ taking z onto the URDF axis): a joint's rotation is then a turn about z,
    /// which forward kinematics applies to two columns instead of composing a Rodrigues matrix.
    origins: [DAffine3; 3],
    /// The foot centre in the last joint's turned frame.
    foot: DVec3,
    lower: [f64; 3],
    upper: [f64; 3],
}

/// The result of an inverse-kinematics solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkSolution {
    pub angles: [f64; 3],
    /// Distance from the reached foot position to the target (m).
    pub error: f64,
    /// The foot link's orientation at `angles` ([`LegChain::foot_rotation`]'s).
    pub foot_rotation: DMat3,
}

/// A solve's answer with the forward kinematics it ended on ([`LegChain::solve_warm`]): the
/// gait solves every leg every step from its last answer, and so starts where this ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkWarm {
    angles: [f64; 3],
    frames: Frames,
}

/// Joint positions and axes, foot position and foot rotation ([`LegChain::frames`]).
type Frames = ([(DVec3, DVec3); 3], DVec3, DMat3);

/// The IK answer is accepted as reaching the target within this distance (m).
pub const IK_TOLERANCE: f64 = 1e-6;

impl LegChain {
    pub fn new(model: &RobotModel, leg: &Leg) -> Self {
        let j = leg.joints.map(|k| &model.joints[k]);
        // The first joint may hang from the body through fixed offsets only (merged into its origin).
        let align = j.map(|j| DAffine3::from_quat(DQuat::from_rotation_arc(DVec3::Z, j.axis)));
        LegChain {
            origins: [0, 1, 2].map(|k| {
                let previous = if k == 0 {
                    DAffine3::IDENTITY
                } else {
                    align[k - 1].inverse()
                };
                previous * j[k].origin * align[k]
            }),
            foot: align[2].inverse().transform_point3(leg.foot.center),
            lower: j.map(|j| j.lower),
            upper: j.map(|j| j.upper),
        }
    }

    /// Where the first joint sits in the body frame.
    pub fn hip(&self) -> DVec3 {
        self.origins[0].translation
    }

    /// Foot centre in the body frame for joint angles `q`.
    pub fn foot_position(&self, q: [f64; 3]) -> DVec3 {
        self.frames(q).1
    }

    /// The foot link's orientation in the body frame for joint angles `q`, up to a constant turn
    /// (its frame turned so the last joint's axis is z): compare two of them only.
    pub fn foot_rotation(&self, q: [f64; 3]) -> DMat3 {
        self.frames(q).2
    }

    /// Joint positions and axes (body frame), the foot position, and the foot link's orientation
    /// (turned frame).
    fn frames(&self, q: [f64; 3]) -> Frames {
        let mut frame = DAffine3::IDENTITY;
        let mut joints = [(DVec3::ZERO, DVec3::ZERO); 3];
        for k in 0..3 {
            frame *= self.origins[k];
            let m = &mut frame.matrix3;
            joints[k] = (frame.translation, m.z_axis);
            // turn about the (turned) joint axis z by q
            let (s, c) = q[k].sin_cos();
            (m.x_axis, m.y_axis) = (m.x_axis * c + m.y_axis * s, m.y_axis * c - m.x_axis * s);
        }
        (joints, frame.transform_point3(self.foot), frame.matrix3)
    }

    fn jacobian_of(joints: &[(DVec3, DVec3); 3], foot: DVec3) -> DMat3 {
        DMat3::from_cols(
            joints[0].1.cross(foot - joints[0].0),
            joints[1].1.cross(foot - joints[1].0),
            joints[2].1.cross(foot - joints[2].0),
        )
    }

    pub fn clamp(&self, q: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|k| q[k].clamp(self.lower[k], self.upper[k]))
    }

    /// Joint angles that put the foot at `target` (body frame), starting from `guess` (use the
    /// last answer: it keeps the knee on the same side). Damped least squares, within the
    /// joints' limits; if the target is out of reach the closest reachable answer is returned
    /// with its error. (The gait solves six legs every step: each trial's forward kinematics
    /// also gives the next iteration's Jacobian.)
    pub fn solve(&self, target: DVec3, guess: [f64; 3]) -> IkSolution {
        self.solve_warm(target, guess, &mut None)
    }

    /// [`Self::solve`], taking the forward kinematics of `guess` from `warm` when it holds them
    /// (the last answer's, bit for bit the same as computing them again: a fifth of the gait's
    /// instructions on hex18's walk), and leaving this answer's there for the next solve.
    pub fn solve_warm(
        &self,
        target: DVec3,
        guess: [f64; 3],
        warm: &mut Option<IkWarm>,
    ) -> IkSolution {
        let mut q = self.clamp(guess);
        let (mut joints, mut foot, mut rotation) = match warm {
            Some(w) if w.angles.map(f64::to_bits) == q.map(f64::to_bits) => w.frames,
            _ => self.frames(q),
        };
        let mut error = target - foot;
        for _ in 0..50 {
            if error.length() < IK_TOLERANCE * 0.1 {
                break;
            }
            let j = Self::jacobian_of(&joints, foot);
            // a small damping keeps the step finite where the leg is stretched (singular)
            let lambda2 = 1e-6;
            let step = j.transpose()
                * (j * j.transpose() + DMat3::from_diagonal(DVec3::splat(lambda2))).inverse()
                * error;
            let mut next = self.clamp([q[0] + step.x, q[1] + step.y, q[2] + step.z]);
            let (mut next_joints, mut next_foot, mut next_rotation) = self.frames(next);
            if (target - next_foot).length() >= error.length() {
                // no progress: try a half step once, then stop
                next = self.clamp([
                    q[0] + 0.5 * step.x,
                    q[1] + 0.5 * step.y,
                    q[2] + 0.5 * step.z,
                ]);
                (next_joints, next_foot, next_rotation) = self.frames(next);
                if (target - next_foot).length() >= error.length() {
                    break;
                }
            }
            q = next;
            joints = next_joints;
            foot = next_foot;
            rotation = next_rotation;
            error = target - foot;
        }
        *warm = Some(IkWarm {
            angles: q,
            frames: (joints, foot, rotation),
        });
        IkSolution {
            angles: q,
            error: error.length(),
            foot_rotation: rotation,
        }
    }

    /// Heading of the leg at rest (all joints zero): the yaw of the foot seen from the hip.
    pub fn rest_yaw(&self) -> f64 {
        let d = self.foot_position([0.0; 3]) - self.hip();
        d.y.atan2(d.x)
    }

    /// Horizontal reach of the outstretched leg (all joints zero), from the hip.
    pub fn length(&self) -> f64 {
        (self.foot_position([0.0; 3]) - self.hip())
            .truncate()
            .length()
    }
}
