//! The paper's ground contact model as a pure function: (terrain, sphere pose and velocity,
//! parameters, a little friction state) → force and contact point. Nothing here knows rapier.
//!
//! Per step, for a sphere of radius r (a ball, or a foot):
//! 1. [`sphere_geometry`]: closest surface point, penetration x along the surface normal, ground frame
//!    (exact normal, or the paper's roll/pitch angles, eq. 1–4).
//! 2. The contact point's velocity is split into the normal part v_n and the in-plane slip (eq. 3–4).
//! 3. Normal force from the [`NormalLaw`] (eq. 5–6: F = k·x + c·ẋ, never pulling).
//! 4. In-plane force from the [`FrictionLaw`] (Coulomb, viscous, Stribeck, Karnopp).
//! 5. The sum acts at the contact point (so a ball rolls).
//!
//! That is hexsim's variant; `paper` holds the paper's as written, for comparison, and `rolling`
//! the rolling resistance the paper's model lacks.

mod friction;
mod geometry;
pub mod joint;
mod normal;
mod paper;
mod rolling;

pub use friction::{FrictionLaw, FrictionOutcome};
pub use geometry::{
    Faces, MAX_FACES, SphereGeometry, closest_from_each, faces_from_below, faces_from_below_into,
    search_start, sphere_faces, sphere_geometry,
};
pub use joint::respond_jointly;
pub use normal::{NormalLaw, REFERENCE_DAMPING, REFERENCE_STIFFNESS, exact_decay_factor};
pub use paper::paper_geometry;
pub use rolling::RollingBody;

use crate::terrain::{GroundFrame, Orientation};
use glam::{DMat2, DMat3, DVec2, DVec3};

/// The contact model's parameters: normal law, friction law, how the ground's orientation is
/// found, and how much of a sticking contact's drift the stick force undoes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactModel {
    pub normal: NormalLaw,
    pub friction: FrictionLaw,
    pub orientation: Orientation,
    /// Fraction r of the drift d accumulated while sticking that the stick force undoes per step:
    /// F_stop = F_prev − M·(u + r·d/h²) (see `friction`). 0 turns it off, and every friction law
    /// is then its equation, its stick force exactly the force that stops the contact under last
    /// step's load. The load is measured one step late, so under a load that keeps changing (a
    /// walking robot's foot) a sticking contact creeps; the default [`DRIFT_RECOVERY`] halves
    /// that drift each step. It acts only while a contact sticks, on its own drift, so it returns
    /// a displaced foot at most to where friction first held it.
    pub drift_recovery: f64,
    /// Rolling resistance ρ (m): a torque of at most ρ·Fn against the body's rolling, its angular
    /// velocity about the ground plane's axes — the lever arm by which a deforming contact's
    /// pressure leads its centre (MuJoCo's rolling friction, condim 6, in the same unit; a
    /// rolling-resistance coefficient c_rr = ρ/r for a sphere of radius r). 0: none.
    pub rolling_resistance: f64,
    /// Spin (torsional) friction μ_t (m): a torque of at most μ_t·Fn against the body's spin about
    /// the ground's normal — MuJoCo's torsional friction, condim 4, in the same unit (the radius
    /// of the patch over which friction acts). 0: none (the paper's point contact).
    pub spin_friction: f64,
    /// hexsim's contact, or the paper's step for step (see `paper`).
    pub variant: Variant,
}

/// Which contact: hexsim's (closest point, exact normal or the paper's angles, exact-decay
/// damper, friction limited at the stopping force) or the paper's as written (`paper`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Variant {
    #[default]
    Hexsim,
    Paper,
}

impl Default for ContactModel {
    /// The reference contact (docs/validation.md), with the default drift recovery.
    fn default() -> Self {
        ContactModel {
            normal: NormalLaw::default(),
            friction: FrictionLaw::default(),
            orientation: Orientation::default(),
            drift_recovery: DRIFT_RECOVERY,
            rolling_resistance: 0.0,
            spin_friction: 0.0,
            variant: Variant::Hexsim,
        }
    }
}

/// The inertia a contact point presents: along the normal, and (as a 2×2 matrix in the ground
/// frame's in-plane axes) in the plane. For a free rigid body, 1/m(d) = 1/m + (r×d)ᵀ·I⁻¹·(r×d).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectiveMass {
    pub normal: f64,
    pub tangential: DMat2,
}

impl EffectiveMass {
    /// A point mass (or a body whose rotation is locked).
    pub fn particle(mass: f64) -> Self {
        EffectiveMass {
            normal: mass,
            tangential: DMat2::from_diagonal(DVec2::splat(mass)),
        }
    }

    /// A free rigid body of `mass` with world-frame inverse inertia `inverse_inertia`, whose centre
    /// of mass is at `arm` from the contact point (`arm` = point − centre of mass).
    pub fn rigid_body(mass: f64, inverse_inertia: DMat3, arm: DVec3, frame: &GroundFrame) -> Self {
        let mobility =
            |a: DVec3, b: DVec3| a.dot(b) / mass + arm.cross(a).dot(inverse_inertia * arm.cross(b));
        let (t1, t2, n) = (frame.tangent_x, frame.tangent_y, frame.normal);
        let m12 = mobility(t1, t2);
        let inverse = DMat2::from_cols(
            DVec2::new(mobility(t1, t1), m12),
            DVec2::new(m12, mobility(t2, t2)),
        );
        EffectiveMass {
            normal: 1.0 / mobility(n, n),
            tangential: inverse.inverse(),
        }
    }
}

/// A contact between [`ContactModel::begin`] and [`ContactModel::finish`]: its normal force is
/// known; its in-plane force waits for the stopping force F_stop = `previous_friction` − M·`demand`
/// (in-plane components in the contact's ground frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PendingContact {
    pub point: DVec3,
    pub frame: GroundFrame,
    pub penetration: f64,
    pub normal_velocity: f64,
    pub slip: DVec2,
    pub normal_force: f64,
    pub previous_friction: DVec2,
    /// The in-plane velocity change per second that would bring the contact to rest (and undo
    /// part of its drift) by the end of the step, given last step's load.
    pub demand: DVec2,
    /// The normal force's change since last step (through the body, it pushes other contacts).
    pub normal_change: f64,
    /// The damper's part of `normal_force` (what the next step's push estimate subtracts).
    pub damper: f64,
}

impl PendingContact {
    /// Friction that would push the contact into the ground harder than its normal force pushes
    /// it out, scaled down until the two balance. `w` is the contact's own mobility in its
    /// ground-frame axes (t₁, t₂, n). Where a point is far more mobile along the ground than
    /// across it and the two are coupled — a foot at the end of a leg dragged forward, whose
    /// tibia levers it down (hex18 in a trench: W_nn = 7.6 /kg, W_nt = (11.4, 10.5) /kg, so
    /// μ·|W_nt| = 12.4 > W_nn) — friction at μ·Fn drives the foot in faster than the spring
    /// drives it out: Painlevé's jam. Rigid contact resolves it with a normal impulse that stops
    /// the slip; an explicit spring answers a step late, friction grows with it, and the foot
    /// swings through the ground ×1.5–2 a step (`ladder/gaps.toml` at 2 cm: 10.5 mm deep, a
    /// divergence). Limiting friction to W_nn·Fn + W_nt·F_t ≥ 0 — the contact's forces together
    /// never accelerate it into the ground — only takes friction away, never adds it, and is
    /// inactive wherever the coupling is weaker than 1/μ of the normal mobility (a stance foot
    /// under its hip).
    pub fn unjammed(&self, outcome: FrictionOutcome, w: DMat3) -> FrictionOutcome {
        let push = w.x_axis.z * outcome.force.x + w.y_axis.z * outcome.force.y;
        let out = w.z_axis.z * self.normal_force;
        if push >= -out || push >= 0.0 {
            return outcome;
        }
        FrictionOutcome {
            force: outcome.force * (out / -push),
            sticking: false,
        }
    }

    /// F_stop for a contact alone, whose in-plane effective mass is `mass`.
    pub fn stopping_force(&self, mass: DMat2) -> DVec2 {
        self.previous_friction - mass * self.demand
    }

    /// What the friction law does given the stopping force (no friction without a normal force).
    pub fn friction(&self, law: &FrictionLaw, stop: DVec2) -> FrictionOutcome {
        if self.normal_force > 0.0 {
            law.force(self.slip, self.normal_force, stop)
        } else {
            FrictionOutcome {
                force: DVec2::ZERO,
                sticking: false,
            }
        }
    }
}

/// The default [`ContactModel::drift_recovery`]: half the drift undone per step.
pub const DRIFT_RECOVERY: f64 = 0.5;

/// Friction's memory between steps: last step's friction and slip (world frame), for the
/// tangential load estimate. Reset when the contact opens.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactState {
    previous: Option<(DVec3, DVec3)>,
    /// How far the contact's material point has slid since friction last held it (world frame).
    drift: DVec3,
    /// Last step's normal force (0 before the contact).
    normal_force: f64,
    /// Last step's rolling-resistance and spin-friction torque and the body's angular velocity
    /// (world), for the rolling load estimate (see `rolling`).
    rolling: Option<(DVec3, DVec3)>,
    /// Last step's penetration rate and the damper force applied, for the push estimate (see
    /// [`ContactModel::begin`]); `None` on a contact's first step.
    damper: Option<(f64, f64)>,
}

/// The contact's response over one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactForce {
    /// Where the force acts (the surface point closest to the sphere's centre).
    pub point: DVec3,
    /// Total force on the sphere (world frame).
    pub force: DVec3,
    /// Normal force magnitude (≥ 0).
    pub normal_force: f64,
    /// In-plane friction force (world frame).
    pub friction: DVec3,
    /// Depth along the normal (> 0 in contact).
    pub penetration: f64,
    /// Normal velocity of the contact point (> 0 separating).
    pub normal_velocity: f64,
    /// In-plane velocity of the contact point (world frame).
    pub slip: DVec3,
    /// Friction held the contact at rest this step.
    pub sticking: bool,
    /// The ground frame at the contact.
    pub frame: GroundFrame,
    /// The magnitudes of its faces' forces summed (N): |`force`| for one face; for a body
    /// pressing several (a foot wedged in a crack) more than the net force, whose opposed parts
    /// cancel (what leg compliance reads as the load the ground carries).
    pub load: f64,
}

impl ContactForce {
    /// One body's contact from several faces it presses into at once (a foot in a pit's
    /// corner): the forces and normal forces summed, the deepest face's point, frame, depth and
    /// slip, sticking only if every face sticks, the loads summed.
    pub fn merge(&mut self, other: &ContactForce) {
        let sticking = self.sticking && other.sticking;
        let (force, normal_force, friction, load) = (
            self.force + other.force,
            self.normal_force + other.normal_force,
            self.friction + other.friction,
            self.load + other.load,
        );
        if other.penetration > self.penetration {
            *self = *other;
        }
        self.force = force;
        self.normal_force = normal_force;
        self.friction = friction;
        self.sticking = sticking;
        self.load = load;
    }
}

impl ContactModel {
    /// The force over a step of length `dt` on a sphere in the given geometry whose material point
    /// at the contact moves with `point_velocity`. Returns `None` (and resets `state`) when the sphere
    /// does not touch the ground.
    pub fn respond(
        &self,
        geometry: &SphereGeometry,
        point_velocity: DVec3,
        mass: &EffectiveMass,
        dt: f64,
        state: &mut ContactState,
    ) -> Option<ContactForce> {
        let pending = self.begin(geometry, point_velocity, mass.normal, true, dt, state)?;
        let stop = pending.stopping_force(mass.tangential);
        Some(self.finish(&pending, stop, dt, state))
    }

    /// The first half of [`Self::respond`]: the normal force and what stopping the contact asks
    /// for, before the in-plane force is chosen (alone, or jointly with other contacts on the same
    /// body: [`respond_jointly`]). `alone`: no other contact presses the same rigid body this
    /// step (see below). `None` (and `state` reset) when the sphere does not touch.
    pub fn begin(
        &self,
        geometry: &SphereGeometry,
        point_velocity: DVec3,
        normal_mass: f64,
        alone: bool,
        dt: f64,
        state: &mut ContactState,
    ) -> Option<PendingContact> {
        if geometry.penetration <= 0.0 {
            *state = ContactState::default();
            return None;
        }
        let frame = &geometry.frame;
        let local = frame.to_local(point_velocity);
        let normal_velocity = local.z;
        let slip = DVec2::new(local.x, local.y);
        // The push P on the body along the normal, estimated from last step (normal.rs): over it
        // m·Δẋ = h·(P − F_d,last), so P = m·Δẋ/h + F_d,last, its spring at last step's depth (at
        // this step's, a foot sinking steadily would meet c·ẋ·(1 − k·h²/m), not c·ẋ). A
        // contact's first step has no history: the damper stops the body alone. So does a
        // contact sharing its body with others (a foot in a trench's corner, a shin lying on
        // the ground): the exact average holds for a push the body's velocity does not change
        // within the step, and another contact's damper on the same light body is anything but
        // — each read the other's as a push and answered it a step late, and a foot wedged in
        // a trench rattled between its walls, ×1.3 a step to 13 m/s
        // (`joint::tests::a_foot_wedged_between_two_walls_settles`).
        let rate = -normal_velocity;
        let x = geometry.penetration;
        let push = match state.damper {
            Some((last_rate, last_damper)) if alone => {
                normal_mass * (rate - last_rate) / dt + last_damper
            }
            _ => 0.0,
        };
        let normal_force = self.normal.force(x, rate, normal_mass, dt, push);
        let in_plane = |v: DVec3| DVec2::new(frame.tangent_x.dot(v), frame.tangent_y.dot(v));
        // F_stop = F_prev − M·u (see `friction`): u = (2v − v_prev)/h with last step's load, v/h
        // on a contact's first step; plus a fraction of the drift accumulated while sticking (the
        // load is estimated one step late, which under a changing load — a walking robot's foot —
        // lets the foot creep)
        let (previous_friction, demand) = match state.previous {
            Some((force, prev_slip)) => (in_plane(force), (2.0 * slip - in_plane(prev_slip)) / dt),
            None => (DVec2::ZERO, slip / dt),
        };
        let demand = demand + in_plane(state.drift) * (self.drift_recovery / (dt * dt));
        Some(PendingContact {
            point: geometry.point,
            frame: *frame,
            penetration: geometry.penetration,
            normal_velocity,
            slip,
            normal_force,
            previous_friction,
            demand,
            normal_change: normal_force - state.normal_force,
            damper: normal_force - self.normal.elastic(x),
        })
    }

    /// The second half of [`Self::respond`]: the friction law given the stopping force `stop`
    /// (in-plane components), and the state for the next step.
    pub fn finish(
        &self,
        pending: &PendingContact,
        stop: DVec2,
        dt: f64,
        state: &mut ContactState,
    ) -> ContactForce {
        let outcome = pending.friction(&self.friction, stop);
        Self::conclude(pending, outcome, dt, state)
    }

    /// [`Self::finish`] with the friction already chosen.
    pub fn conclude(
        pending: &PendingContact,
        outcome: FrictionOutcome,
        dt: f64,
        state: &mut ContactState,
    ) -> ContactForce {
        let frame = &pending.frame;
        let friction = frame.to_world(outcome.force.extend(0.0));
        let slip_world = frame.to_world(pending.slip.extend(0.0));
        state.previous = Some((friction, slip_world));
        state.normal_force = pending.normal_force;
        state.damper = Some((-pending.normal_velocity, pending.damper));
        state.drift = if outcome.sticking {
            state.drift + slip_world * dt
        } else {
            DVec3::ZERO
        };
        let force = pending.normal_force * frame.normal + friction;
        ContactForce {
            point: pending.point,
            force,
            normal_force: pending.normal_force,
            friction,
            penetration: pending.penetration,
            normal_velocity: pending.normal_velocity,
            slip: slip_world,
            sticking: outcome.sticking,
            frame: *frame,
            load: force.length(),
        }
    }

    /// The sphere's geometry as this contact sees it: hexsim's closest point, or the paper's
    /// vertical reading (which needs the paper's orientation: its half-steps).
    pub fn sphere_geometry(
        &self,
        terrain: &crate::terrain::HeightGrid,
        center: DVec3,
        radius: f64,
    ) -> SphereGeometry {
        match (self.variant, self.orientation) {
            (Variant::Paper, Orientation::Paper { xe, ye }) => {
                paper_geometry(terrain, center, radius, xe, ye)
            }
            _ => sphere_geometry(terrain, center, radius, self.orientation),
        }
    }

    /// The faces the sphere presses into as this contact sees them ([`sphere_faces`]): one,
    /// except in a concave corner of a grid with walls. The paper's vertical reading knows one.
    pub fn sphere_faces(
        &self,
        terrain: &crate::terrain::HeightGrid,
        center: DVec3,
        radius: f64,
    ) -> Faces {
        self.sphere_faces_from(terrain, center, radius, &mut None)
    }

    /// [`Self::sphere_faces`] of a sphere whose last search ended at the offset `last` from its
    /// centre ([`geometry::sphere_faces_from`]), left holding this one's.
    pub fn sphere_faces_from(
        &self,
        terrain: &crate::terrain::HeightGrid,
        center: DVec3,
        radius: f64,
        last: &mut Option<(f64, f64)>,
    ) -> Faces {
        match (self.variant, self.orientation) {
            (Variant::Paper, Orientation::Paper { .. }) => {
                *last = None;
                Faces::single(self.sphere_geometry(terrain, center, radius))
            }
            _ => geometry::sphere_faces_from(terrain, center, radius, self.orientation, last),
        }
    }

    /// Whether [`Self::sphere_faces_from`] is [`geometry::sphere_faces_from`]'s search (every
    /// contact but the paper's own with its angles), whose first closest-point searches can be
    /// taken several spheres at once ([`closest_from_each`]).
    pub fn searches_from_below(&self) -> bool {
        !matches!(
            (self.variant, self.orientation),
            (Variant::Paper, Orientation::Paper { .. })
        )
    }

    /// Checks every parameter, naming the bad one (`normal.damping`, `friction.mu_static`, …).
    pub fn validate(&self) -> Result<(), (String, String)> {
        self.normal
            .validate()
            .map_err(|(f, e)| (format!("normal.{f}"), e))?;
        self.friction
            .validate()
            .map_err(|(f, e)| (format!("friction.{f}"), e))?;
        if !(self.drift_recovery.is_finite() && (0.0..=1.0).contains(&self.drift_recovery)) {
            return Err((
                "drift_recovery".into(),
                format!(
                    "expected a fraction of the drift undone per step, 0 (off) to 1, got {}",
                    self.drift_recovery
                ),
            ));
        }
        if self.variant == Variant::Paper {
            if !matches!(self.orientation, Orientation::Paper { .. }) {
                return Err((
                    "orientation".into(),
                    "expected the paper's (its finite differences) for the paper variant".into(),
                ));
            }
            if self.rolling_resistance != 0.0 {
                return Err((
                    "rolling_resistance".into(),
                    format!(
                        "expected 0 for the paper variant, which has none, got {}",
                        self.rolling_resistance
                    ),
                ));
            }
        }
        if self.variant == Variant::Paper && self.spin_friction != 0.0 {
            return Err((
                "spin_friction".into(),
                format!(
                    "expected 0 for the paper variant, which has none, got {}",
                    self.spin_friction
                ),
            ));
        }
        if !(self.spin_friction.is_finite() && self.spin_friction >= 0.0) {
            return Err((
                "spin_friction".into(),
                format!(
                    "expected a lever arm ≥ 0 m (0: none), got {}",
                    self.spin_friction
                ),
            ));
        }
        if !(self.rolling_resistance.is_finite() && self.rolling_resistance >= 0.0) {
            return Err((
                "rolling_resistance".into(),
                format!(
                    "expected a lever arm ≥ 0 m (0: none), got {}",
                    self.rolling_resistance
                ),
            ));
        }
        if let Orientation::Paper { xe, ye } = self.orientation {
            for (name, v) in [("orientation.xe", xe), ("orientation.ye", ye)] {
                if !(v.is_finite() && v > 0.0) {
                    return Err((
                        name.into(),
                        format!("expected a finite step > 0 m, got {v}"),
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pending contact with normal force `normal_force`, for [`PendingContact::unjammed`].
    fn pending(normal_force: f64) -> PendingContact {
        PendingContact {
            point: DVec3::ZERO,
            frame: GroundFrame::from_normal(DVec3::Z),
            penetration: 1e-3,
            normal_velocity: 0.0,
            slip: DVec2::new(1.0, 0.0),
            normal_force,
            previous_friction: DVec2::ZERO,
            demand: DVec2::ZERO,
            normal_change: 0.0,
            damper: 0.0,
        }
    }

    /// A foot wedged in a crack presses two opposed walls: their forces cancel in the net force,
    /// not in its load, and the merged contact keeps the deeper face's geometry.
    #[test]
    fn a_wedged_foot_merges_to_the_net_force_and_the_summed_load() {
        let face = |normal: DVec3, normal_force: f64, penetration: f64, sticking: bool| {
            let force = normal * normal_force;
            ContactForce {
                point: -normal * 0.01,
                force,
                normal_force,
                friction: DVec3::ZERO,
                penetration,
                normal_velocity: 0.0,
                slip: DVec3::ZERO,
                sticking,
                frame: GroundFrame::from_normal(normal),
                load: force.length(),
            }
        };
        let mut foot = face(DVec3::X, 40.0, 2e-3, true);
        foot.merge(&face(-DVec3::X, 30.0, 1.5e-3, false));
        assert!((foot.force - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-12);
        assert_eq!((foot.normal_force, foot.load), (70.0, 70.0));
        assert_eq!(
            (foot.penetration, foot.point),
            (2e-3, DVec3::new(-0.01, 0.0, 0.0))
        );
        assert!(!foot.sticking);
    }

    /// A 39 g foot (PhantomX's, along the normal) on a damper alone, c = 93 N·s/m at 1 ms (c·h/m
    /// = 2.4), coming down at 0.6 m/s: `(push, rates)` over 40 steps of m·ẋ' = P − F, the
    /// contact's force F from [`ContactModel::respond`].
    fn pushed_foot(push: f64) -> (f64, f64, f64, Vec<f64>) {
        let (m, c, h) = (0.039, 93.0, 1e-3);
        let model = ContactModel {
            normal: NormalLaw::SpringDamper {
                stiffness: 0.0,
                damping: c,
            },
            ..ContactModel::default()
        };
        let geometry = SphereGeometry {
            penetration: 1e-3,
            point: DVec3::ZERO,
            frame: GroundFrame::from_normal(DVec3::Z),
        };
        let mut state = ContactState::default();
        let mut rates = vec![0.6];
        for _ in 0..40 {
            let rate = *rates.last().unwrap();
            let velocity = DVec3::new(0.0, 0.0, -rate);
            let mass = EffectiveMass::particle(m);
            let f = model
                .respond(&geometry, velocity, &mass, h, &mut state)
                .unwrap();
            rates.push(rate + h / m * (push - f.normal_force));
        }
        (m, c, h, rates)
    }

    /// The damper is exact under a steady push (normal.rs): from the second step on (the first
    /// has no estimate of P) each step's rate is the exact solution of m·ẋ' = P − c·ẋ,
    /// P/c + (ẋ − P/c)·e^(−c·h/m), and a foot pushed at 20 N sinks at P/c = 0.215 m/s. The
    /// damper alone (P = 0 in the law) would let it sink at P/(c·φ) = 0.49 m/s: the body above
    /// would meet 41 N·s/m of damping, not 93.
    #[test]
    fn a_pushed_foot_meets_the_whole_damper() {
        for push in [20.0, 2.0, 0.0] {
            let (m, c, h, rates) = pushed_foot(push);
            let decay = (-c * h / m).exp();
            for pair in rates[1..].windows(2) {
                let exact = push / c + (pair[0] - push / c) * decay;
                assert!(
                    (pair[1] - exact).abs() < 1e-12,
                    "P = {push}: {} against the exact {exact}",
                    pair[1]
                );
            }
            let terminal = *rates.last().unwrap();
            assert!(
                (terminal - push / c).abs() < 1e-12,
                "P = {push}: {terminal}"
            );
        }
        let phi = exact_decay_factor(93.0 * 1e-3 / 0.039);
        assert!(20.0 / (93.0 * phi) > 2.0 * 20.0 / 93.0);
    }

    /// hex18's foot in a trench (measured): W_nn = 7.6 /kg and W_nt = (11.4, 10.5) /kg. Friction
    /// of 0.8·100 N along −(1, 1)/√2 would push it in at (11.4 + 10.5)·80/√2 = 1239 N/kg against
    /// the normal force's 760 out: it is scaled to balance; friction that pushes it out, or in
    /// less than the normal force pushes out, is left alone.
    #[test]
    fn friction_never_jams_a_contact_into_the_ground() {
        let w = DMat3::from_cols(
            DVec3::new(32.4, 13.5, 11.4),
            DVec3::new(13.5, 32.1, 10.5),
            DVec3::new(11.4, 10.5, 7.6),
        );
        let p = pending(100.0);
        let along = |f: DVec2| FrictionOutcome {
            force: f,
            sticking: true,
        };
        let jam = DVec2::new(-1.0, -1.0).normalize() * 80.0;
        let out = p.unjammed(along(jam), w);
        assert!(!out.sticking);
        let push = |f: DVec2| w.x_axis.z * f.x + w.y_axis.z * f.y;
        assert!(
            (push(out.force) + 7.6 * 100.0).abs() < 1e-9,
            "{}",
            out.force
        );
        assert!(out.force.normalize().abs_diff_eq(jam.normalize(), 1e-12));
        for kept in [-jam, DVec2::new(-30.0, 0.0), DVec2::new(60.0, -65.0)] {
            assert!(push(kept) >= -760.0);
            assert_eq!(p.unjammed(along(kept), w), along(kept));
        }
    }

    #[test]
    fn rigid_sphere_presents_two_sevenths_of_its_mass_in_the_plane() {
        let (m, r) = (1.0, 0.05);
        let inertia = 0.4 * m * r * r;
        let frame = GroundFrame::from_normal(DVec3::Z);
        let eff = EffectiveMass::rigid_body(
            m,
            DMat3::from_diagonal(DVec3::splat(1.0 / inertia)),
            DVec3::new(0.0, 0.0, -r),
            &frame,
        );
        assert!((eff.normal - m).abs() < 1e-12);
        assert!((eff.tangential.x_axis.x - 2.0 / 7.0 * m).abs() < 1e-12);
        assert!(eff.tangential.x_axis.y.abs() < 1e-12);
    }

    /// The laws under test, each in a setting where it sticks at slips of 10 µm/s and slides at
    /// 0.3 m/s on a 1 kg contact.
    fn laws() -> [FrictionLaw; 4] {
        [
            FrictionLaw::Coulomb {
                mu: 0.5,
                width: 1e-3,
            },
            FrictionLaw::Viscous { coefficient: 1e4 },
            FrictionLaw::Stribeck {
                mu_static: 0.9,
                mu_coulomb: 0.6,
                viscous: 2.0,
                stribeck_velocity: 0.05,
                width: 1e-3,
            },
            FrictionLaw::default(),
        ]
    }

    /// With drift recovery off, every friction law is its equation: sliding, the law's own force
    /// (Coulomb −μ·Fn·v/|v|, viscous −b·v, Stribeck's curve, Karnopp's kinetic −μk·Fn·v/|v|);
    /// sticking, exactly the force that stops the contact under last step's load,
    /// F_stop = F_prev − M·(2v − v_prev)/h. With it on, a sticking contact's force also undoes
    /// r·M·d/h² (d its drift since it stuck), which is what the parameter switches.
    #[test]
    fn without_drift_recovery_each_friction_law_is_its_equation() {
        let frame = GroundFrame::from_normal(DVec3::Z);
        let geometry = SphereGeometry {
            penetration: 1e-3,
            point: DVec3::ZERO,
            frame,
        };
        let (m, dt) = (1.0, 1e-3);
        let mass = EffectiveMass::particle(m);
        for law in laws() {
            let model = ContactModel {
                friction: law,
                drift_recovery: 0.0,
                ..ContactModel::default()
            };
            let on = ContactModel {
                drift_recovery: 0.5,
                ..model
            };
            let (mut state, mut state_on) = (ContactState::default(), ContactState::default());
            let mut previous: Option<(DVec3, DVec3)> = None;
            let mut previous_on: Option<(DVec3, DVec3)> = None;
            let mut drift = DVec3::ZERO;
            let (mut stuck, mut shifted) = (0, 0);
            for k in 0..40 {
                let t = k as f64;
                let speed = if k < 20 { 1e-5 } else { 0.3 };
                let v = DVec3::new(speed * (0.3 * t).cos(), speed * (0.2 * t).sin(), -0.01);
                let got = model.respond(&geometry, v, &mass, dt, &mut state).unwrap();
                let with_drift = on.respond(&geometry, v, &mass, dt, &mut state_on).unwrap();
                let slip = v.truncate();
                let fn_ = got.normal_force;
                let stop = match previous {
                    Some((f, s)) => f.truncate() - m * (2.0 * slip - s.truncate()) / dt,
                    None => -m * slip / dt,
                };
                let expected = if got.sticking {
                    stuck += 1;
                    stop
                } else {
                    let s = slip.length();
                    match law {
                        FrictionLaw::Coulomb { mu, width } => -mu * fn_ * slip / s.max(width),
                        FrictionLaw::Viscous { coefficient } => -coefficient * slip,
                        FrictionLaw::Stribeck {
                            mu_static,
                            mu_coulomb,
                            viscous,
                            stribeck_velocity,
                            width,
                        } => {
                            let level = mu_coulomb * fn_
                                + (mu_static - mu_coulomb)
                                    * fn_
                                    * (-(s / stribeck_velocity).powi(2)).exp();
                            -level * slip / s.max(width) - viscous * slip
                        }
                        // against the slip, or, where the step would reverse it, the
                        // stopping force projected onto the kinetic disc
                        FrictionLaw::Karnopp { mu_kinetic, .. } => {
                            let kinetic = -mu_kinetic * fn_ * slip / s;
                            if (kinetic - stop).dot(slip) >= 0.0 {
                                kinetic
                            } else {
                                mu_kinetic * fn_ * stop / stop.length()
                            }
                        }
                        FrictionLaw::None => DVec2::ZERO,
                    }
                };
                let error = (got.friction.truncate() - expected).length();
                assert!(
                    error <= 1e-9 * expected.length().max(1e-9),
                    "{law:?} step {k}: {} against {expected}",
                    got.friction
                );
                // the same contact with drift recovery: its stick force also undoes r·d
                if with_drift.sticking {
                    let stop_on = match previous_on {
                        Some((f, s)) => f.truncate() - m * (2.0 * slip - s.truncate()) / dt,
                        None => -m * slip / dt,
                    };
                    let expected_on = stop_on - 0.5 * m * drift.truncate() / (dt * dt);
                    let error = (with_drift.friction.truncate() - expected_on).length();
                    assert!(
                        error <= 1e-9 * expected_on.length().max(1e-9),
                        "{law:?} step {k}: with drift recovery {} against {expected_on}",
                        with_drift.friction
                    );
                    if drift.length() > 0.0 {
                        shifted += 1;
                    }
                }
                drift = if with_drift.sticking {
                    drift + v * dt
                } else {
                    DVec3::ZERO
                };
                previous = Some((got.friction, v));
                previous_on = Some((with_drift.friction, v));
            }
            // (the extra force can leave a weak stick band, Coulomb's, on some steps)
            assert!(shifted >= 5, "{law:?}: drift recovered on {shifted} steps");
            assert!(stuck >= 10, "{law:?} stuck {stuck} steps of 20");
        }
    }

    #[test]
    fn drift_recovery_outside_0_to_1_is_refused() {
        for bad in [-0.1, 1.5, f64::NAN] {
            let model = ContactModel {
                drift_recovery: bad,
                ..ContactModel::default()
            };
            assert_eq!(model.validate().unwrap_err().0, "drift_recovery");
        }
    }
}
