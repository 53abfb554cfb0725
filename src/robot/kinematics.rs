//! Leg kinematics from the URDF's geometry: forward kinematics of a leg of three to
//! [`MAX_LEG_JOINTS`] revolute joints in the body frame, and inverse kinematics by damped Newton
//! iterations on the analytic Jacobian — general for any three revolute joints, not only
//! yaw-pitch-pitch legs; a leg of more joints is redundant and solved by `redundant`.

use super::model::{Leg, RobotModel};
use glam::{DAffine3, DMat3, DQuat, DVec3};
use std::ops::{Deref, DerefMut};

/// The most joints a leg may have and be driven whole (a coxa, femur, tibia and up to three more:
/// a tarsus, a hip roll, a wrist). A longer chain walks on three (see `branches`).
pub const MAX_LEG_JOINTS: usize = 6;

/// A leg's joint angles from the body out (rad): as many as the leg has joints, 3 to
/// [`MAX_LEG_JOINTS`]. Kept in a fixed array (no allocation: six legs are solved every step) and
/// read as a slice.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegAngles {
    values: [f64; MAX_LEG_JOINTS],
    len: usize,
}

impl LegAngles {
    /// The angles of a 3-joint leg.
    pub const fn three(q: [f64; 3]) -> Self {
        LegAngles {
            values: [q[0], q[1], q[2], 0.0, 0.0, 0.0],
            len: 3,
        }
    }

    /// `n` zeros (`n` at most [`MAX_LEG_JOINTS`]).
    pub fn zeros(n: usize) -> Self {
        LegAngles {
            values: [0.0; MAX_LEG_JOINTS],
            len: n.min(MAX_LEG_JOINTS),
        }
    }

    /// The angles of `q` (its first [`MAX_LEG_JOINTS`]).
    pub fn from_slice(q: &[f64]) -> Self {
        let mut angles = Self::zeros(q.len());
        let len = angles.len;
        angles.values[..len].copy_from_slice(&q[..len]);
        angles
    }

    /// `guess` as angles of an `n`-joint leg: its first `n`, and a short one's missing joints
    /// at `fill`'s.
    fn fitted(guess: &[f64], n: usize, fill: &[f64]) -> Self {
        let mut angles = Self::from_slice(fill);
        angles.len = n;
        let given = guess.len().min(n);
        angles.values[..given].copy_from_slice(&guess[..given]);
        angles
    }
}

impl Deref for LegAngles {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.values[..self.len]
    }
}

impl DerefMut for LegAngles {
    fn deref_mut(&mut self) -> &mut [f64] {
        &mut self.values[..self.len]
    }
}

impl<'a> IntoIterator for &'a LegAngles {
    type Item = &'a f64;
    type IntoIter = std::slice::Iter<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl IntoIterator for LegAngles {
    type Item = f64;
    type IntoIter = std::iter::Take<std::array::IntoIter<f64, MAX_LEG_JOINTS>>;
    fn into_iter(self) -> Self::IntoIter {
        self.values.into_iter().take(self.len)
    }
}

impl AsRef<[f64]> for LegAngles {
    fn as_ref(&self) -> &[f64] {
        self
    }
}

/// One leg's chain, in the body (root link) frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LegChain {
    /// Joint k's origin in joint k−1's frame, both frames turned so their joint axis is z
    /// (Aₖ₋₁ᵀ·Oₖ·Aₖ, Aₖ taking z onto the URDF axis): a joint's rotation is then a turn about z,
    /// which forward kinematics applies to two columns instead of composing a Rodrigues matrix.
    origins: [DAffine3; MAX_LEG_JOINTS],
    /// How many joints the leg has (3 to [`MAX_LEG_JOINTS`]).
    n: usize,
    /// The foot centre in the last joint's turned frame.
    foot: DVec3,
    pub(super) lower: [f64; MAX_LEG_JOINTS],
    pub(super) upper: [f64; MAX_LEG_JOINTS],
    /// Per joint, the angle a redundant joint is pulled towards (`Leg::posture`), NaN for the
    /// three that place the foot.
    pub(super) rest: [f64; MAX_LEG_JOINTS],
    /// The rest angles with zero for the three: what a short guess is filled with.
    fill: [f64; MAX_LEG_JOINTS],
    /// Each joint's child link's centre of mass in the joint's turned frame, and its mass (kg).
    coms: [DVec3; MAX_LEG_JOINTS],
    masses: [f64; MAX_LEG_JOINTS],
}

/// The result of an inverse-kinematics solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkSolution {
    pub angles: LegAngles,
    /// Distance from the reached foot position to the target (m).
    pub error: f64,
}

/// A solve's answer with the forward kinematics it ended on ([`LegChain::solve_warm`]): the
/// gait solves every leg every step from its last answer, and so starts where this ends. The
/// next solve works in it: the answer's frames and the trial's, in two buffers that trade
/// places as a trial is taken (each holds four matrices: not copied).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkWarm {
    angles: [f64; 3],
    frames: [Frames; 2],
    /// The Jacobian of each of `frames` and its determinant, where a solve computed them (the
    /// branch test of the trial it took): the next iteration's, the next solve's first and the
    /// rolling offset's ([`LegChain::foot_turn_map`]), not computed again.
    jacobians: [Option<(DMat3, f64)>; 2],
    /// Which of `frames` are the answer's.
    now: usize,
}

impl IkWarm {
    /// The answer's frames.
    fn frames(&self) -> &Frames {
        &self.frames[self.now]
    }

    /// Whether these are the forward kinematics of `q`, bit for bit.
    fn answers(&self, q: &[f64]) -> bool {
        q.len() == 3 && self.angles.map(f64::to_bits) == [q[0], q[1], q[2]].map(f64::to_bits)
    }
}

/// Joint positions and axes, foot position and foot rotation ([`LegChain::frames`]), and the
/// first two links' rotations (the load feed-forward's, [`LegChain::statics`]).
type Frames = ([(DVec3, DVec3); 3], DVec3, DMat3, [DMat3; 2]);

/// Frames to be overwritten.
const NO_FRAMES: Frames = (
    [(DVec3::ZERO, DVec3::ZERO); 3],
    DVec3::ZERO,
    DMat3::ZERO,
    [DMat3::ZERO; 2],
);

/// A 3-joint leg's pose as the servos' load feed-forward reads it ([`LegChain::statics`]), body
/// frame: each joint's position and unit axis, the centre of mass of each joint's child link,
/// and the foot centre; and each child link's mass (kg), so that the feed-forward, every step,
/// need not look them up in the model.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LegStatics {
    pub joints: [(DVec3, DVec3); 3],
    pub coms: [DVec3; 3],
    pub foot: DVec3,
    pub masses: [f64; 3],
}

/// The IK answer is accepted as reaching the target within this distance (m).
pub const IK_TOLERANCE: f64 = 1e-6;

/// The damped least squares' damping λ² (m²): small, it keeps the step finite where the leg
/// is stretched (singular) and leaves it Gauss–Newton's elsewhere.
const LAMBDA2: f64 = 1e-6;

/// The most a solve that makes no progress raises λ² to before it stops (m²): against the
/// squared lever arms of a leg's joints (10⁻³–10⁻¹ m²), a step then a short one along the
/// gradient. Near a target out of reach the error is nearly flat along the poses closest to
/// it, and a Gauss–Newton step there overshoots; the damped one goes on down to the closest
/// pose next to the last, where a solve that stopped short left the next one to start from a
/// pose no better than another branch's (see `gait::controller::solve_on_branch`).
const LAMBDA2_MAX: f64 = 1e-1;

/// Joint positions and axes in the body frame, as [`LegChain::frames`] gives them.
pub(super) type JointFrames = [(DVec3, DVec3); MAX_LEG_JOINTS];

impl LegChain {
    pub fn new(model: &RobotModel, leg: &Leg) -> Self {
        let n = leg.joints.len().min(MAX_LEG_JOINTS);
        let j: Vec<_> = leg.joints[..n].iter().map(|&k| &model.joints[k]).collect();
        // The first joint may hang from the body through fixed offsets only (merged into its origin).
        let align: Vec<DAffine3> = j
            .iter()
            .map(|j| DAffine3::from_quat(DQuat::from_rotation_arc(DVec3::Z, j.axis)))
            .collect();
        let mut chain = LegChain {
            origins: [DAffine3::IDENTITY; MAX_LEG_JOINTS],
            n,
            foot: align[n - 1].inverse().transform_point3(leg.foot.center),
            lower: [0.0; MAX_LEG_JOINTS],
            upper: [0.0; MAX_LEG_JOINTS],
            rest: [f64::NAN; MAX_LEG_JOINTS],
            fill: [0.0; MAX_LEG_JOINTS],
            coms: [DVec3::ZERO; MAX_LEG_JOINTS],
            masses: [0.0; MAX_LEG_JOINTS],
        };
        for k in 0..n {
            let previous = if k == 0 {
                DAffine3::IDENTITY
            } else {
                align[k - 1].inverse()
            };
            chain.origins[k] = previous * j[k].origin * align[k];
            chain.coms[k] = align[k]
                .inverse()
                .transform_point3(model.links[j[k].child].com);
            chain.masses[k] = model.links[j[k].child].mass;
            chain.lower[k] = j[k].lower;
            chain.upper[k] = j[k].upper;
            if let Some(Some(rest)) = leg.posture.get(k) {
                chain.rest[k] = *rest;
                chain.fill[k] = *rest;
            }
        }
        chain
    }

    /// How many joints the leg has.
    pub fn joint_count(&self) -> usize {
        self.n
    }

    /// Whether the leg has more joints than the three that place its foot.
    pub fn is_redundant(&self) -> bool {
        self.n > 3
    }

    /// Where the first joint sits in the body frame.
    pub fn hip(&self) -> DVec3 {
        self.origins[0].translation
    }

    /// Angles for this leg from `q`: its first joints' (a shorter `q` leaves the rest at their
    /// rest angle, or zero).
    pub fn angles(&self, q: &[f64]) -> LegAngles {
        LegAngles::fitted(q, self.n, &self.fill)
    }

    /// A 3-joint leg's angles from `q`, as [`Self::angles`] gives them (a short `q` filled as
    /// there), without the copy through [`LegAngles`] (a call to `memcpy` of `q`'s length).
    #[inline]
    fn three(&self, q: &[f64]) -> [f64; 3] {
        std::array::from_fn(|k| q.get(k).copied().unwrap_or(self.fill[k]))
    }

    /// Angles with `three` on the three joints that place the foot (in order from the body) and
    /// a redundant leg's other joints at rest: a starting guess stated as a 3-joint leg's.
    pub fn from_three(&self, three: [f64; 3]) -> LegAngles {
        let mut q = LegAngles::zeros(self.n);
        let mut given = three.into_iter();
        for (k, angle) in q.iter_mut().enumerate() {
            *angle = if self.rest[k].is_nan() {
                given.next().unwrap_or(0.0)
            } else {
                self.rest[k]
            };
        }
        q
    }

    /// How high the leg's joints after its first stand at `q` (the mean of their heights, body
    /// frame): of two poses that put the foot in one place, the one with its knee up stands
    /// higher than the one with its knee down, whichever way the URDF turns its joints.
    pub fn joints_height(&self, q: impl AsRef<[f64]>) -> f64 {
        let (joints, _, _) = self.frames(&self.angles(q.as_ref()));
        let above: f64 = joints[1..self.n].iter().map(|(p, _)| p.z).sum();
        above / (self.n - 1) as f64
    }

    /// Foot centre in the body frame for joint angles `q`.
    pub fn foot_position(&self, q: impl AsRef<[f64]>) -> DVec3 {
        let q = self.angles(q.as_ref());
        if self.n == 3 {
            return self.frames3([q[0], q[1], q[2]]).1;
        }
        self.frames(&q).1
    }

    /// The foot link's orientation in the body frame for joint angles `q`, up to a constant turn
    /// (its frame turned so the last joint's axis is z): compare two of them only.
    pub fn foot_rotation(&self, q: impl AsRef<[f64]>) -> DMat3 {
        let q = self.angles(q.as_ref());
        if self.n == 3 {
            return self.frames3([q[0], q[1], q[2]]).2;
        }
        self.frames(&q).2
    }

    /// Joint positions and axes (body frame), the foot position, and the foot link's orientation
    /// (turned frame), for the leg's `q` (one angle per joint).
    pub(super) fn frames(&self, q: &[f64]) -> (JointFrames, DVec3, DMat3) {
        self.frames_of::<MAX_LEG_JOINTS>(q, self.n)
    }

    /// [`Self::frames`] of a 3-joint leg, its loop of fixed length (the gait solves six legs
    /// every step), with the first two links' rotations as they are turned on the way, kept so
    /// that the load feed-forward does not turn them again (their sines and cosines were 1.3k
    /// instructions of a walk's step on hex18). The arithmetic of [`Self::frames_of`], but for
    /// the first joint's frame: its origin, not the identity times it (the same numbers but
    /// for the sign of a zero).
    fn frames3(&self, q: [f64; 3]) -> Frames {
        let mut frames = NO_FRAMES;
        self.frames3_into(q, &mut frames);
        frames
    }

    /// [`Self::frames3`] into `out`.
    #[inline]
    fn frames3_into(&self, q: [f64; 3], out: &mut Frames) {
        // the first joint's frame is its origin (not the identity times it)
        let mut frame = self.origins[0];
        for (k, angle) in q.into_iter().enumerate() {
            if k > 0 {
                frame *= self.origins[k];
            }
            let m = &mut frame.matrix3;
            out.0[k] = (frame.translation, m.z_axis);
            let (s, c) = angle.sin_cos();
            (m.x_axis, m.y_axis) = (m.x_axis * c + m.y_axis * s, m.y_axis * c - m.x_axis * s);
            if k < 2 {
                out.3[k] = *m;
            }
        }
        out.1 = frame.transform_point3(self.foot);
        out.2 = frame.matrix3;
    }

    /// The first `n` joints' frames (at most `N`), in storage of `N`, for [`Self::frames`]
    /// ([`Self::frames3`] is the same loop for three joints, keeping two links' rotations).
    #[inline]
    fn frames_of<const N: usize>(
        &self,
        q: &[f64],
        n: usize,
    ) -> ([(DVec3, DVec3); N], DVec3, DMat3) {
        let mut frame = DAffine3::IDENTITY;
        let mut joints = [(DVec3::ZERO, DVec3::ZERO); N];
        for k in 0..n {
            frame *= self.origins[k];
            let m = &mut frame.matrix3;
            joints[k] = (frame.translation, m.z_axis);
            // turn about the (turned) joint axis z by q
            let (s, c) = q[k].sin_cos();
            (m.x_axis, m.y_axis) = (m.x_axis * c + m.y_axis * s, m.y_axis * c - m.x_axis * s);
        }
        (joints, frame.transform_point3(self.foot), frame.matrix3)
    }

    /// The damped least-squares step (Δq = Jᵀ(JJᵀ + λ²I)⁻¹e) towards a foot error `e` from `q`,
    /// with every joint that sits at a limit the step would push it past held there: its
    /// column of J taken out and the step solved again for the others (an active set, as
    /// box-constrained least squares does). Clamping the full step instead bends it off the
    /// descent direction where the closest pose to a target out of reach leans on a limit
    /// (ant_bot's femur at its upper limit), and the solve stops short of that pose. Away from
    /// the limits it is the plain step.
    fn step_within_limits(&self, j: DMat3, q: [f64; 3], error: DVec3, lambda2: f64) -> DVec3 {
        let dls = |j: DMat3| {
            j.transpose()
                * (j * j.transpose() + DMat3::from_diagonal(DVec3::splat(lambda2))).inverse()
                * error
        };
        let mut step = dls(j);
        let mut held = [false; 3];
        loop {
            let mut changed = false;
            for i in 0..3 {
                let pushed = (q[i] >= self.upper[i] && step[i] > 0.0)
                    || (q[i] <= self.lower[i] && step[i] < 0.0);
                if pushed && !held[i] {
                    held[i] = true;
                    changed = true;
                }
            }
            if !changed {
                return step;
            }
            if held == [true; 3] {
                return DVec3::ZERO;
            }
            let column = |i: usize| if held[i] { DVec3::ZERO } else { j.col(i) };
            step = dls(DMat3::from_cols(column(0), column(1), column(2)));
        }
    }

    fn jacobian_of(joints: &[(DVec3, DVec3); 3], foot: DVec3) -> DMat3 {
        DMat3::from_cols(
            joints[0].1.cross(foot - joints[0].0),
            joints[1].1.cross(foot - joints[1].0),
            joints[2].1.cross(foot - joints[2].0),
        )
    }

    /// `q` within the joints' limits.
    pub fn clamp(&self, q: impl AsRef<[f64]>) -> LegAngles {
        let mut q = self.angles(q.as_ref());
        for (k, angle) in q.iter_mut().enumerate() {
            *angle = angle.clamp(self.lower[k], self.upper[k]);
        }
        q
    }

    #[inline]
    fn clamp3(&self, q: [f64; 3]) -> [f64; 3] {
        let (lower, upper) = (&self.lower, &self.upper);
        [
            q[0].clamp(lower[0], upper[0]),
            q[1].clamp(lower[1], upper[1]),
            q[2].clamp(lower[2], upper[2]),
        ]
    }

    /// Joint angles that put the foot at `target` (body frame), starting from `guess` (use the
    /// last answer: it keeps the knee on the same side). Damped least squares, within the
    /// joints' limits; if the target is out of reach the closest reachable answer is returned
    /// with its error. A leg of more than three joints is redundant: see `redundant`, which
    /// also keeps its extra joints near their rest angles. (The gait solves six legs every
    /// step: each trial's forward kinematics also gives the next iteration's Jacobian.)
    pub fn solve(&self, target: DVec3, guess: impl AsRef<[f64]>) -> IkSolution {
        self.solve_within(target, guess, &mut None, IK_TOLERANCE * 0.1, false)
    }

    /// [`Self::solve`], never crossing a singular pose on the way (see [`same_branch`]): the
    /// answer is on the knee's branch of `guess`, the closest pose of that branch where the
    /// target is out of its reach. The gait starts a leg's solve again from its standing pose
    /// with it (`gait::controller::solve_on_branch`).
    pub fn solve_on_branch(&self, target: DVec3, guess: impl AsRef<[f64]>) -> IkSolution {
        self.solve_within(target, guess, &mut None, IK_TOLERANCE * 0.1, true)
    }

    /// [`Self::solve`], taking a 3-joint leg's forward kinematics of `guess` from `warm` when it
    /// holds them (the last answer's, bit for bit the same as computing them again: a fifth of
    /// the gait's instructions on hex18's walk), and leaving this answer's there for the next
    /// solve. A redundant leg's solve keeps no such state. Like [`Self::solve_on_branch`] it
    /// stays on the branch of `guess`: the answer follows the last one.
    ///
    /// It stops within [`IK_TOLERANCE`] (1 µm) of the target, where a cold [`Self::solve`] goes
    /// on to 0.1 µm: the gait solves every leg every step from its last answer a step's motion
    /// away, and the last Newton step of a third of those solves was to go from under 1 µm to
    /// under 0.1 µm (4.9k instructions of a walk's step on hex18, when it solved each leg
    /// twice). A micrometre is
    /// far below what the servos hold a joint to (their compliance under a leg's load moves the
    /// foot by tenths of a millimetre); the walk's 20 s distance moves by 10⁻⁷ of itself.
    pub fn solve_warm(
        &self,
        target: DVec3,
        guess: impl AsRef<[f64]>,
        warm: &mut Option<IkWarm>,
    ) -> IkSolution {
        self.solve_within(target, guess, warm, IK_TOLERANCE, true)
    }

    /// [`Self::solve_warm`] to `tolerance` (m), on the branch of `guess` if `follow`: a 3-joint
    /// leg's [`IkSolve`] taken to its end.
    fn solve_within(
        &self,
        target: DVec3,
        guess: impl AsRef<[f64]>,
        warm: &mut Option<IkWarm>,
        tolerance: f64,
        follow: bool,
    ) -> IkSolution {
        if self.is_redundant() {
            return super::redundant::solve(self, target, &self.angles(guess.as_ref()));
        }
        let three = self.three(guess.as_ref());
        let mut solve = IkSolve::new(self, target, three, warm, tolerance, follow);
        let warm = warm.as_mut().expect("set by IkSolve::new");
        while solve.advance(self, warm) {}
        solve.finish(warm)
    }

    /// The leg's pose for the load feed-forward at `q`, from the forward kinematics of the solve
    /// that left `warm`, when `q` is its answer bit for bit (None otherwise, or for a leg of
    /// more than three joints): the gait's targets are that answer nearly always, and the
    /// feed-forward so poses the legs without forward kinematics of all the links. The links'
    /// orientations are those the solve's last forward kinematics turned ([`Self::frames3`]).
    pub fn statics(&self, warm: &IkWarm, q: &[f64]) -> Option<LegStatics> {
        let mut statics = LegStatics::default();
        self.statics_into(warm, q, &mut statics).then_some(statics)
    }

    /// [`Self::statics`] written into `out` (false, `out` untouched, where it gives None): the
    /// feed-forward poses six legs every step, each in place.
    #[inline]
    pub fn statics_into(&self, warm: &IkWarm, q: &[f64], out: &mut LegStatics) -> bool {
        if self.n != 3 || !warm.answers(q) {
            return false;
        }
        let (joints, foot, rotation, [first, second]) = warm.frames();
        let links = [first, second, rotation];
        out.joints = *joints;
        for k in 0..3 {
            out.coms[k] = *links[k] * self.coms[k] + joints[k].0;
        }
        out.foot = *foot;
        out.masses = [self.masses[0], self.masses[1], self.masses[2]];
        true
    }

    /// The foot link's rotation and the foot's position at `q` (body frame), and the map B from
    /// a small motion of the foot to the turn (a rotation vector) it gives the foot link:
    /// Σ aᵢ·δqᵢ over the joints' axes aᵢ, with δq = Jᵀ(JJᵀ + λ²I)⁻¹·δ the damped least
    /// squares' motion (so B = A·Jᵀ(JJᵀ + λ²I)⁻¹, A the axes as columns). Rotations about
    /// parallel axes (a femur's and a tibia's, which do most of a lift) add exactly. From
    /// `warm`'s forward kinematics when they are `q`'s (the gait's last answer nearly always),
    /// computed otherwise.
    pub fn foot_turn_map(&self, warm: Option<&IkWarm>, q: &[f64]) -> (DMat3, DVec3, DMat3) {
        let computed;
        let (joints, foot, rotation, jacobian): (&[(DVec3, DVec3)], DVec3, DMat3, _) = match warm {
            Some(w) if self.n == 3 && w.answers(q) => {
                let (joints, foot, rotation, _) = w.frames();
                (joints, *foot, *rotation, w.jacobians[w.now].map(|(j, _)| j))
            }
            _ => {
                computed = self.frames(&self.angles(q));
                (&computed.0[..self.n], computed.1, computed.2, None)
            }
        };
        // J's columns cᵢ = aᵢ × (foot − pᵢ) (the solve's, where it kept them): JJᵀ = Σ cᵢcᵢᵀ
        // and A·Jᵀ = Σ aᵢcᵢᵀ; JJᵀ summed on and above its diagonal only and mirrored, each entry
        // below it being the same sum of the same products (cᵢₖcᵢₗ = cᵢₗcᵢₖ exactly)
        let outer = |u: DVec3, v: DVec3| DMat3::from_cols(u * v.x, u * v.y, u * v.z);
        let (mut xx, mut yy, mut zz) = (LAMBDA2, LAMBDA2, LAMBDA2);
        let (mut yx, mut zx, mut zy) = (0.0, 0.0, 0.0);
        let mut ajt = DMat3::ZERO;
        for (i, (p, a)) in joints.iter().enumerate() {
            let c = match jacobian {
                Some(j) => j.col(i),
                None => a.cross(foot - *p),
            };
            (xx, yx, zx) = (xx + c.x * c.x, yx + c.y * c.x, zx + c.z * c.x);
            (yy, zy, zz) = (yy + c.y * c.y, zy + c.z * c.y, zz + c.z * c.z);
            ajt += outer(*a, c);
        }
        let jjt = DMat3::from_cols(
            DVec3::new(xx, yx, zx),
            DVec3::new(yx, yy, zy),
            DVec3::new(zx, zy, zz),
        );
        (rotation, foot, ajt * jjt.inverse())
    }

    /// Heading of the leg at rest (all joints zero): the yaw of the foot seen from the hip.
    pub fn rest_yaw(&self) -> f64 {
        let d = self.foot_position(LegAngles::zeros(self.n)) - self.hip();
        d.y.atan2(d.x)
    }

    /// Horizontal reach of the outstretched leg (all joints zero), from the hip.
    pub fn length(&self) -> f64 {
        (self.foot_position(LegAngles::zeros(self.n)) - self.hip())
            .truncate()
            .length()
    }
}

/// The most iterations a 3-joint leg's solve takes (each a damped step, with the shorter trials
/// it may take when the step does not come closer).
const MOST_ITERATIONS: usize = 50;

/// A 3-joint leg's solve between two of its trials ([`LegChain::solve_warm`]): where it stands
/// and what it tries next. A trial is three parts — [`IkSolve::step`], the angles tried;
/// [`IkSolve::forward`], their forward kinematics; [`IkSolve::judge`], taken or not — so that
/// several legs' solves can take turns ([`solve_warm_each`]), and [`IkSolve::advance`] takes
/// them one after the other: a solve alone is this state advanced to its end, the same
/// arithmetic, bit for bit, as in turns.
#[derive(Debug, Clone, Copy)]
struct IkSolve {
    target: DVec3,
    /// The answer so far, the foot's error there and that error's length.
    q: [f64; 3],
    error: DVec3,
    distance: f64,
    /// The damped least squares' λ² for the next full step.
    lambda2: f64,
    tolerance: f64,
    follow: bool,
    /// Iterations begun.
    iterations: usize,
    /// This iteration's Jacobian and its determinant, and its last full step (half of which is
    /// tried when it does not come closer).
    jacobian: DMat3,
    det: f64,
    step: DVec3,
    /// The angles being tried.
    trial: [f64; 3],
    next: Next,
}

/// What an [`IkSolve`] tries next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Next {
    /// A new iteration: the Jacobian where the answer stands, then its full step.
    Iteration,
    /// The iteration's full step, at the present damping.
    Full,
    /// Half the full step just refused.
    Half,
    /// No more: the answer stands.
    Done,
}

impl IkSolve {
    /// The solve of `chain` for `target` from `guess` (its three angles), in `warm`: from the
    /// forward kinematics there when they are those of `guess` (the last answer, bit for bit),
    /// else from `guess` within the joints' limits, its forward kinematics computed there.
    #[inline(always)]
    fn new(
        chain: &LegChain,
        target: DVec3,
        guess: [f64; 3],
        warm: &mut Option<IkWarm>,
        tolerance: f64,
        follow: bool,
    ) -> Self {
        // a guess that is `warm`'s answer is within the limits already (an answer is clamped)
        let known = warm.as_ref().is_some_and(|w| w.answers(&guess));
        let q = if known { guess } else { chain.clamp3(guess) };
        let warm = if known {
            warm.as_mut().expect("known")
        } else {
            let w = warm.insert(IkWarm {
                angles: q,
                frames: [NO_FRAMES; 2],
                jacobians: [None; 2],
                now: 0,
            });
            chain.frames3_into(q, &mut w.frames[0]);
            w
        };
        let error = target - warm.frames().1;
        let distance = error.length();
        IkSolve {
            target,
            q,
            error,
            distance,
            lambda2: LAMBDA2,
            tolerance,
            follow,
            iterations: 0,
            jacobian: DMat3::ZERO,
            det: 0.0,
            step: DVec3::ZERO,
            trial: q,
            next: if distance < tolerance {
                Next::Done
            } else {
                Next::Iteration
            },
        }
    }

    /// One trial: a step from the answer, taken if it comes closer and, following, stays on
    /// the branch (see [`same_branch`]); if not, half of it, then steps damped harder
    /// (Levenberg–Marquardt, towards the gradient's direction) until one is too short to
    /// matter. A solve that need not follow its guess stops at the first damping, as the stance
    /// fit was tuned on. False once the solve has ended (nothing tried).
    #[inline(always)]
    fn advance(&mut self, chain: &LegChain, warm: &mut IkWarm) -> bool {
        if !self.step(chain, warm) {
            return false;
        }
        self.forward(chain, warm);
        self.judge(warm)
    }

    /// A trial's first part: the angles it tries (`trial`), the iteration's damped step or
    /// half of it. False once the solve has ended (nothing to try).
    #[inline(always)]
    fn step(&mut self, chain: &LegChain, warm: &IkWarm) -> bool {
        if self.next == Next::Done {
            return false;
        }
        if self.next == Next::Iteration {
            self.iterations += 1;
            // the Jacobian a solve kept with the answer's frames, if it computed one there
            (self.jacobian, self.det) = warm.jacobians[warm.now].unwrap_or_else(|| {
                let (joints, foot, ..) = warm.frames();
                let j = LegChain::jacobian_of(joints, *foot);
                (j, j.determinant())
            });
            self.next = Next::Full;
        }
        let q = self.q;
        self.trial = if self.next == Next::Full {
            self.step = chain.step_within_limits(self.jacobian, q, self.error, self.lambda2);
            let step = self.step;
            chain.clamp3([q[0] + step.x, q[1] + step.y, q[2] + step.z])
        } else {
            // no progress: a half step
            let step = self.step;
            chain.clamp3([
                q[0] + 0.5 * step.x,
                q[1] + 0.5 * step.y,
                q[2] + 0.5 * step.z,
            ])
        };
        true
    }

    /// A trial's second part: its forward kinematics, into `warm`'s buffer that is not the
    /// answer's.
    #[inline(always)]
    fn forward(&self, chain: &LegChain, warm: &mut IkWarm) {
        chain.frames3_into(self.trial, &mut warm.frames[1 - warm.now]);
    }

    /// A trial's last part: taken if it comes closer and, following, stays on the branch (its
    /// frames and Jacobian then the answer's), and what to try next. False once the solve has
    /// ended.
    #[inline(always)]
    fn judge(&mut self, warm: &mut IkWarm) -> bool {
        let full = self.next == Next::Full;
        let trial = 1 - warm.now;
        if let Some(closer) = self.progress(&warm.frames[trial], &mut warm.jacobians[trial]) {
            if full {
                self.lambda2 = (self.lambda2 * 0.1).max(LAMBDA2);
            }
            self.distance = closer;
            self.q = self.trial;
            warm.now = trial;
            self.error = self.target - warm.frames[trial].1;
            let ended = self.iterations == MOST_ITERATIONS || self.distance < self.tolerance;
            self.next = if ended { Next::Done } else { Next::Iteration };
        } else if full && self.lambda2 == LAMBDA2 {
            self.next = Next::Half;
        } else {
            // still none: damp harder, towards the gradient's direction; a solve that need not
            // follow its guess stops here
            self.lambda2 *= 10.0;
            let ended = !self.follow || self.lambda2 > LAMBDA2_MAX;
            self.next = if ended { Next::Done } else { Next::Full };
        }
        self.next != Next::Done
    }

    /// The distance to the target from the trial whose forward kinematics are `frames`, if it
    /// is taken: it comes closer and, following, stays on the branch. The Jacobian computed for
    /// that is kept in `jacobian` (for the next iteration, the next solve and
    /// [`LegChain::foot_turn_map`]), None where none was.
    #[inline(always)]
    fn progress(&self, frames: &Frames, jacobian: &mut Option<(DMat3, f64)>) -> Option<f64> {
        *jacobian = None;
        let closer = (self.target - frames.1).length();
        let taken = closer < self.distance
            && (!self.follow || {
                let to = LegChain::jacobian_of(&frames.0, frames.1);
                let to_det = to.determinant();
                *jacobian = Some((to, to_det));
                same_branch(self.det, to_det)
            });
        taken.then_some(closer)
    }

    /// The answer, its angles kept in `warm` with their forward kinematics.
    #[inline(always)]
    fn finish(&self, warm: &mut IkWarm) -> IkSolution {
        warm.angles = self.q;
        IkSolution {
            angles: LegAngles::three(self.q),
            error: self.distance,
        }
    }
}

/// [`LegChain::solve_warm`] of a hexapod's six legs at once: `chains`, and per leg its target,
/// its guess (the last answer) and the warm state that answer left. Each 3-joint leg's solve is
/// its own, the same arithmetic, but they take turns, a trial of each a round, and each
/// trial's parts in stages across the legs: every leg's step, then every leg's forward
/// kinematics, then every leg's test. Alone, a solve is one chain of latencies (the step's
/// division, three `sincos`, the frames turned one after the other, the distance's square
/// root, each waiting on the last); in stages, the processor computes one leg's part while
/// another's waits. A redundant leg is solved alone (no warm state), after the others.
pub fn solve_warm_each(
    chains: &[LegChain],
    targets: &[DVec3; 6],
    guesses: &[LegAngles; 6],
    warms: &mut [Option<IkWarm>; 6],
) -> [IkSolution; 6] {
    assert_eq!(chains.len(), 6, "six legs");
    let mut solves: [Option<IkSolve>; 6] = [None; 6];
    for k in 0..6 {
        let chain = &chains[k];
        if !chain.is_redundant() {
            let guess = chain.three(&guesses[k]);
            let solve = IkSolve::new(chain, targets[k], guess, &mut warms[k], IK_TOLERANCE, true);
            solves[k] = Some(solve);
        }
    }
    let mut going = true;
    while going {
        going = false;
        let mut tried = [false; 6];
        for k in 0..6 {
            if let (Some(solve), Some(warm)) = (&mut solves[k], &warms[k]) {
                tried[k] = solve.step(&chains[k], warm);
            }
        }
        for k in 0..6 {
            if let (true, Some(solve), Some(warm)) = (tried[k], &solves[k], &mut warms[k]) {
                solve.forward(&chains[k], warm);
            }
        }
        for k in 0..6 {
            if let (true, Some(solve), Some(warm)) = (tried[k], &mut solves[k], &mut warms[k]) {
                going |= solve.judge(warm);
            }
        }
    }
    std::array::from_fn(|k| match (&solves[k], &mut warms[k]) {
        (Some(solve), Some(warm)) => solve.finish(warm),
        _ => {
            let chain = &chains[k];
            super::redundant::solve(chain, targets[k], &chain.angles(&guesses[k]))
        }
    })
}

/// Whether a pose whose Jacobian's determinant is `to` is on the same side of the leg's
/// singular poses as one whose is `from`: det J changes sign where the leg passes through one
/// (stretched, or its foot on the coxa's axis), and a knee's two branches have opposite signs.
/// A step across is refused: a target out of reach is closest at the stretched pose, and a
/// solve free to cross it comes back on either branch (ant_bot's knee, folded past 2 rad on its
/// femur's limit, then missed targets its usual branch reaches).
fn same_branch(from: f64, to: f64) -> bool {
    // a pose on the singular set itself (a straight leg at zero angles) belongs to neither
    from == 0.0 || from * to > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chains_of(model: &RobotModel) -> Vec<LegChain> {
        model
            .legs
            .iter()
            .map(|leg| LegChain::new(model, leg))
            .collect()
    }

    /// Solves taken in turns ([`solve_warm_each`]) end where each alone ([`LegChain::solve_warm`])
    /// ends, bit for bit: the answers, their errors and the warm state each leaves. hex18's six
    /// legs, and the same with two of them a tarsus leg's (redundant, solved alone), follow
    /// targets that circle their standing feet and drift out of reach and back (a step's motion:
    /// one iteration; out of reach: half steps and harder damping), with now and then a guess
    /// that is not the last answer, or no warm state (cold: several iterations).
    #[test]
    fn solves_in_turns_are_each_the_solve_alone() {
        let hex18 = crate::robot::hex18_for_tests();
        let tarsus = super::super::urdf::from_str_with(
            include_str!("../../tests/data/robots/hex18_tarsus.urdf"),
            None,
            std::path::Path::new("tests/data/robots/hex18_tarsus.urdf"),
        )
        .expect("hex18_tarsus loads");
        let (plain, tarsi) = (chains_of(&hex18), chains_of(&tarsus));
        let mixed: Vec<LegChain> = (0..6)
            .map(|k| {
                if k % 3 == 1 {
                    tarsi[k].clone()
                } else {
                    plain[k].clone()
                }
            })
            .collect();
        let (mut missed, mut cold) = (0, 0);
        for chains in [&plain, &mixed] {
            let mut last: [LegAngles; 6] =
                std::array::from_fn(|k| chains[k].from_three([0.0, -0.3, 1.2]));
            let standing: [DVec3; 6] = std::array::from_fn(|k| chains[k].foot_position(last[k]));
            let mut warms: [Option<IkWarm>; 6] = [None; 6];
            for round in 0..400 {
                let t = round as f64;
                let targets: [DVec3; 6] = std::array::from_fn(|k| {
                    let turn = 0.05 * t + k as f64;
                    // out to 0.3 m from the standing foot and back, past every leg's reach
                    let radius = 0.02 + 0.28 * (std::f64::consts::PI * t / 400.0).sin().powi(4);
                    standing[k] + radius * DVec3::new(turn.cos(), turn.sin(), 0.3 * turn.sin())
                });
                let guesses: [LegAngles; 6] = std::array::from_fn(|k| {
                    if (round + k) % 37 == 0 {
                        cold += 1;
                        chains[k].from_three([0.1, 0.2, 0.5])
                    } else {
                        last[k]
                    }
                });
                if round % 50 == 0 {
                    warms = [None; 6];
                }
                let mut warms_alone = warms;
                let alone: [IkSolution; 6] = std::array::from_fn(|k| {
                    chains[k].solve_warm(targets[k], guesses[k], &mut warms_alone[k])
                });
                let in_turns = solve_warm_each(chains, &targets, &guesses, &mut warms);
                for k in 0..6 {
                    let bits = |s: &IkSolution| {
                        let angles: Vec<u64> = s.angles.iter().map(|a| a.to_bits()).collect();
                        (angles, s.error.to_bits())
                    };
                    assert_eq!(
                        bits(&alone[k]),
                        bits(&in_turns[k]),
                        "leg {k}, round {round}"
                    );
                    // the frames and Jacobians left (Debug prints each float's bits apart)
                    assert_eq!(format!("{:?}", warms_alone[k]), format!("{:?}", warms[k]));
                    missed += usize::from(in_turns[k].error > 1e-3);
                }
                last = in_turns.map(|s| s.angles);
            }
        }
        assert!(
            missed > 100 && cold > 10,
            "{missed} out of reach, {cold} cold"
        );
    }
}
