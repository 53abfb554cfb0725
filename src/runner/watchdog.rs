//! Divergence: a state that has left physics (non-finite numbers, a body sunk through the ground,
//! runaway speed) stops the run with when, where and the likely cause.

use crate::contact::NormalLaw;
use crate::metrics::walk::fallen;
use crate::robot::RobotModel;
use crate::sim::{BallSample, HexapodSample};
use std::cell::Cell;

/// Faster than a walking robot's body moves (a fall from 1 m lands at 4.4 m/s), beyond what its
/// drop from the highest it has been explains (√(2·g·Δh): a robot tumbling down a long slope
/// gains that honestly): the integration has run away.
const WALK_RUNAWAY_SPEED: f64 = 5.0;
const WALK_RUNAWAY_SPIN: f64 = 50.0;
/// A passive ball's total energy may rise by this fraction of its start (plus 0.5 J) before it is
/// called runaway; the contact is passive, so a stable run stays well below (V9: 0.4 %).
const BALL_ENERGY_RISE: f64 = 0.1;
/// A robot's contact may sink as far as its ground gives under this many of the robot's weights
/// (its normal law's static sink), whatever the sphere's radius: a leg presses the ground with
/// at most 3 before it gives way (`gait::compliance::CAP`), and a landing adds to it. The ground
/// fitted to a robot gives 4.9 mm there (the reference's 2·10⁴ N/m under four of hex18's
/// 24.7 N), the ladder's 5 mm bar; a foot found at the tip of a mesh can be far smaller (the
/// Phobos export's 2.2 mm, olli's 4.8 mm), and walking over an edge at that depth is a contact
/// the ground resolves, not a divergence (it stopped 9 of Phobos's 104 ladder runs at 2.2–2.3 mm).
const SINK_WEIGHTS: f64 = 4.0;

/// Checks each step's state against what the contact and bodies allow.
pub struct Watchdog {
    dt: f64,
    law: NormalLaw,
    /// Per foot (or the ball): its name, its radius, and the mass the contact spring acts on at
    /// least (the foot link's; the ball's).
    bodies: Vec<(String, f64, f64)>,
    /// Every model link's name (a walk's), for a link contact that went through.
    links: Vec<String>,
    /// The largest foot radius (m; the ball's radius): how deep a link's contact sphere smaller
    /// than it may sink (see [`Watchdog::check_walk`]).
    feet_radius: f64,
    /// How far the ground gives under [`SINK_WEIGHTS`] of the robot's weights (m; 0 for the
    /// ball): how deep any of a robot's contacts may sink, whatever its radius.
    ground_give: f64,
    /// Weight carried by the contacts (N), to tell a soft ground from an unstable step.
    weight: f64,
    /// The ball's total energy at the start (J).
    start_energy: Option<f64>,
    /// When the body first tilted past [`FALL_TILT`](crate::metrics::walk::FALL_TILT)
    /// (simulation time, s): a foot driven through the ground after it is a tumbling robot's
    /// impact, not the time step's doing.
    fell_at: Cell<Option<f64>>,
    /// Gravity's acceleration (m/s²), and the body's highest point so far (m): the speed its
    /// drop from there explains is not runaway.
    gravity: f64,
    highest: Cell<f64>,
    /// Every model joint's name (a walk's), for a servo that rang at the step rate.
    joints: Vec<String>,
    /// When a joint first rang, and which ([`crate::sim::ringing`]).
    rang: Cell<Option<(f64, usize)>>,
}

impl Watchdog {
    pub fn walk(robot: &RobotModel, law: NormalLaw, dt: f64, gravity: f64) -> Self {
        Watchdog {
            dt,
            law,
            bodies: robot
                .legs
                .iter()
                .map(|leg| {
                    (
                        format!("foot {}", leg.name),
                        leg.foot.radius,
                        robot.links[leg.foot_link].mass,
                    )
                })
                .collect(),
            links: robot.links.iter().map(|l| l.name.clone()).collect(),
            feet_radius: robot
                .legs
                .iter()
                .map(|leg| leg.foot.radius)
                .fold(0.0, f64::max),
            ground_give: law.static_sink(SINK_WEIGHTS * robot.total_mass() * gravity),
            weight: robot.total_mass() * gravity / 3.0, // a tripod carries it on three feet
            start_energy: None,
            fell_at: Cell::new(None),
            gravity,
            highest: Cell::new(f64::NEG_INFINITY),
            joints: robot.joints.iter().map(|j| j.name.clone()).collect(),
            rang: Cell::new(None),
        }
    }

    pub fn ball(
        start: &BallSample,
        radius: f64,
        mass: f64,
        law: NormalLaw,
        dt: f64,
        gravity: f64,
    ) -> Self {
        Watchdog {
            dt,
            law,
            bodies: vec![("ball".into(), radius, mass)],
            links: Vec::new(),
            feet_radius: radius,
            ground_give: 0.0,
            weight: mass * gravity,
            start_energy: Some(start.total_energy()),
            fell_at: Cell::new(None),
            gravity,
            highest: Cell::new(f64::NEG_INFINITY),
            joints: Vec::new(),
            rang: Cell::new(None),
        }
    }

    /// Why a state is not physical, if it is not: what, and which body.
    pub fn check_walk(&self, s: &HexapodSample) -> Option<String> {
        if self.fell_at.get().is_none() && fallen(&s.body.matrix3) {
            self.fell_at.set(Some(s.time));
        }
        // the sample keeps the first joint that rang
        self.rang.set(s.servo_ringing);
        if !(s.body.translation.is_finite()
            && s.body_velocity.is_finite()
            && s.body_angular_velocity.is_finite()
            && s.joint_angles.iter().all(|q| q.is_finite()))
        {
            return Some(self.report(s.time, "non-finite state", "body and joints", None));
        }
        for (k, contact) in s.foot_contacts.iter().enumerate() {
            let radius = self.bodies[k].1;
            if let Some(c) = contact
                && (!c.force.is_finite() || c.penetration > radius.max(self.ground_give))
            {
                let what = format!(
                    "sank {:.1} mm into the ground, deeper than its {:.1} mm radius{}",
                    c.penetration * 1e3,
                    radius * 1e3,
                    self.and_the_ground(radius)
                );
                return Some(self.report(s.time, &what, &self.bodies[k].0, Some(k)));
            }
        }
        // a link's sphere is held to the larger of its radius and the feet's: a mesh of a thin
        // sheet is reduced to spheres of 1 mm, which the ground fitted to hold the robot on its
        // feet lets sink that far under a light load (MushroomRL's tibia, 1.0 mm on a 2 cm
        // pyramid step, was called diverged in 92 of its 104 ladder runs); a depth past a foot's
        // radius is as far from a contact the ground resolves on a link as on a foot
        for c in &s.link_contacts {
            let sphere = c.radius.max(self.feet_radius);
            if !c.force.force.is_finite() || c.force.penetration > sphere.max(self.ground_give) {
                let what = format!(
                    "sank {:.1} mm into the ground, deeper than its {:.1} mm contact sphere{}{}",
                    c.force.penetration * 1e3,
                    c.radius * 1e3,
                    if sphere > c.radius {
                        format!(" and the feet's {:.1} mm radius", sphere * 1e3)
                    } else {
                        String::new()
                    },
                    self.and_the_ground(sphere)
                );
                let place = format!("link {}", self.links[c.link]);
                return Some(self.report(s.time, &what, &place, None));
            }
        }
        let speed = s.body_velocity.length();
        let spin = s.body_angular_velocity.length();
        let height = s.body.translation.z;
        let highest = self.highest.get().max(height);
        self.highest.set(highest);
        let dropped = (2.0 * self.gravity * (highest - height)).sqrt();
        if speed > WALK_RUNAWAY_SPEED + dropped || spin > WALK_RUNAWAY_SPIN {
            let what = format!("runaway motion: {speed:.1} m/s, {spin:.1} rad/s");
            return Some(self.report(s.time, &what, "body", None));
        }
        None
    }

    /// What a report adds when the ground's give bounds a contact deeper than its `sphere`.
    fn and_the_ground(&self, sphere: f64) -> String {
        if self.ground_give > sphere {
            format!(
                " and the {:.1} mm the ground gives under {SINK_WEIGHTS} of the robot's weights",
                self.ground_give * 1e3
            )
        } else {
            String::new()
        }
    }

    pub fn check_ball(&self, s: &BallSample) -> Option<String> {
        if !(s.position.is_finite() && s.velocity.is_finite() && s.angular_velocity.is_finite()) {
            return Some(self.report(s.time, "non-finite state", "ball", None));
        }
        if let Some(c) = &s.contact
            && c.penetration > self.bodies[0].1
        {
            let what = format!(
                "sank {:.1} mm into the ground, deeper than its {:.1} mm radius",
                c.penetration * 1e3,
                self.bodies[0].1 * 1e3
            );
            return Some(self.report(s.time, &what, "ball", Some(0)));
        }
        let start = self.start_energy.unwrap_or(0.0);
        let energy = s.total_energy();
        if energy > start + BALL_ENERGY_RISE * start.abs() + 0.5 {
            let what = format!(
                "runaway energy: {energy:.2} J against {start:.2} J at the start (the contact is passive)"
            );
            return Some(self.report(s.time, &what, "ball", None));
        }
        None
    }

    fn report(&self, time: f64, what: &str, place: &str, body: Option<usize>) -> String {
        let (name, radius, mass) = match body {
            Some(k) => self.bodies[k].clone(),
            None => self
                .bodies
                .iter()
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .cloned()
                .expect("a watchdog watches something"),
        };
        let limit = self.law.stable_time_step(mass, radius * 0.1);
        let stiffness = match self.law {
            NormalLaw::SpringDamper { stiffness, .. }
            | NormalLaw::HuntCrossley { stiffness, .. } => stiffness,
        };
        let rang = self
            .rang
            .get()
            .filter(|&(from, _)| self.fell_at.get().is_none_or(|fell| from <= fell));
        let cause = if let Some((from, joint)) = rang {
            crate::sim::ringing::describe(&self.joints[joint], from)
        } else if let Some(fell) = self.fell_at.get() {
            format!(
                "the robot had fallen {:.2} s before (its body tilted past 45° at t = {fell:.4} s), and a tumbling robot's impacts drive a body deeper than a soft ground resolves; the walk had failed before it diverged",
                time - fell
            )
        } else if self.dt > 0.5 * limit {
            format!(
                "dt = {} s is at or above half the contact spring's stability limit {limit:.2e} s (2/√(k/m) for k = {stiffness} N/m on the {mass} kg {name}); reduce dt or the stiffness",
                self.dt
            )
        } else if matches!(self.law, NormalLaw::SpringDamper { .. })
            && self.weight / stiffness > 0.5 * radius
        {
            format!(
                "the ground is too soft for the load: k = {stiffness} N/m sinks {:.1} mm under {:.1} N; raise the stiffness",
                1e3 * self.weight / stiffness,
                self.weight
            )
        } else {
            "the servo gains, the command or the contact parameters drive the system beyond what the time step resolves; reduce dt".to_string()
        };
        format!(
            "the simulation diverged at t = {time:.4} s: {place}: {what}; likely cause: {cause}"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ContactForce;
    use crate::terrain::GroundFrame;
    use glam::{DAffine3, DVec3};

    /// hex18's left front foot `depth` into the ground, the body at `body`, at `time`.
    fn sample(time: f64, body: DAffine3, depth: f64) -> HexapodSample {
        let mut s = HexapodSample {
            time,
            body,
            ..Default::default()
        };
        s.foot_contacts[0] = (depth > 0.0).then(|| ContactForce {
            point: DVec3::ZERO,
            force: DVec3::Z,
            normal_force: 1.0,
            friction: DVec3::ZERO,
            penetration: depth,
            normal_velocity: 0.0,
            slip: DVec3::ZERO,
            sticking: true,
            frame: GroundFrame::from_normal(DVec3::Z),
            load: 1.0,
        });
        s
    }

    /// A foot through the ground after the body tilted past 45° is reported as the fall's
    /// doing, with its time; the same foot on a robot that never fell keeps the time step's
    /// advice.
    #[test]
    fn a_divergence_after_a_fall_names_the_fall() {
        let model = crate::robot::hex18_for_tests();
        let radius = model.legs[0].foot.radius;
        let tilted = DAffine3::from_rotation_x(60f64.to_radians());
        let fell = Watchdog::walk(&model, NormalLaw::default(), 1e-3, 9.81);
        assert_eq!(fell.check_walk(&sample(1.5, tilted, 0.0)), None);
        let report = fell
            .check_walk(&sample(2.0, DAffine3::IDENTITY, 1.1 * radius))
            .expect("a foot through the ground diverges");
        assert!(
            report.contains("fallen 0.50 s before (its body tilted past 45° at t = 1.5000 s)"),
            "{report}"
        );
        assert!(!report.contains("reduce dt"), "{report}");

        let upright = Watchdog::walk(&model, NormalLaw::default(), 1e-3, 9.81);
        assert_eq!(
            upright.check_walk(&sample(1.5, DAffine3::from_rotation_x(0.5), 0.0)),
            None
        );
        let report = upright
            .check_walk(&sample(2.0, DAffine3::IDENTITY, 1.1 * radius))
            .expect("a foot through the ground diverges");
        assert!(!report.contains("fallen"), "{report}");
    }

    /// A link's sphere smaller than the feet (a thin mesh's 1 mm ones) may sink past its own
    /// radius as far as a foot's: 1.5 mm into a 1 mm sphere is a contact, past the feet's 10 mm
    /// it is not; a sphere larger than the feet is held to its own radius.
    #[test]
    fn a_small_link_sphere_is_held_to_the_feet_radius() {
        let model = crate::robot::hex18_for_tests();
        let feet = model.legs[0].foot.radius;
        let pressed = |radius: f64, depth: f64| {
            let mut s = sample(1.0, DAffine3::IDENTITY, 0.0);
            let force = sample(1.0, DAffine3::IDENTITY, depth).foot_contacts[0].unwrap();
            s.link_contacts.push(crate::sim::hexapod::LinkContact {
                link: 3,
                radius,
                force,
            });
            Watchdog::walk(&model, NormalLaw::default(), 1e-3, 9.81).check_walk(&s)
        };
        assert_eq!(pressed(1e-3, 1.5e-3), None);
        assert_eq!(pressed(1e-3, 0.9 * feet), None);
        let report = pressed(1e-3, 1.1 * feet).expect("past the feet's radius diverges");
        assert!(report.contains("and the feet's 10.0 mm radius"), "{report}");
        assert_eq!(pressed(2.0 * feet, 1.5 * feet), None);
        assert!(pressed(2.0 * feet, 2.1 * feet).is_some());
    }

    /// A foot smaller than the ground's give (the Phobos export's 2.2 mm, found at the tip of
    /// a mesh) may sink as far as the ground gives under four of the robot's weights, 4.9 mm on
    /// hex18's reference ground, and diverges past it, the report naming both bounds.
    #[test]
    fn a_small_foot_may_sink_as_far_as_the_ground_gives() {
        let mut model = crate::robot::hex18_for_tests();
        for leg in &mut model.legs {
            leg.foot.radius = 2.2e-3;
        }
        let give = 4.0 * model.total_mass() * 9.81 / crate::contact::REFERENCE_STIFFNESS;
        assert!((give - 4.9e-3).abs() < 0.1e-3, "{give}");
        let watchdog = Watchdog::walk(&model, NormalLaw::default(), 1e-3, 9.81);
        for depth in [2.3e-3, 0.99 * give] {
            let verdict = watchdog.check_walk(&sample(1.0, DAffine3::IDENTITY, depth));
            assert_eq!(verdict, None, "{depth}");
        }
        let report = watchdog
            .check_walk(&sample(1.0, DAffine3::IDENTITY, 1.01 * give))
            .expect("past the ground's give diverges");
        assert!(
            report.contains(
                "deeper than its 2.2 mm radius and the 4.9 mm the ground gives under 4 of the robot's weights"
            ),
            "{report}"
        );
    }

    /// A divergence after a servo rang names that joint's servo and when it started, even
    /// where the robot fell later (ant_bot on impulse joints at 0.5 ms: a coxa rang from 7 ms,
    /// in the air, and the robot fell at 3.15 s); a robot whose servos never rang is said to
    /// have fallen.
    #[test]
    fn a_servo_ringing_at_the_step_rate_is_named_as_the_cause() {
        let model = crate::robot::hex18_for_tests();
        let radius = model.legs[0].foot.radius;
        let tilted = DAffine3::from_rotation_x(60f64.to_radians());
        let rang = |ringing: Option<(f64, usize)>| {
            let watchdog = Watchdog::walk(&model, NormalLaw::default(), 1e-3, 9.81);
            let mut early = sample(0.5, DAffine3::IDENTITY, 0.0);
            early.servo_ringing = ringing;
            assert_eq!(watchdog.check_walk(&early), None);
            let mut fell = sample(1.0, tilted, 0.0);
            fell.servo_ringing = ringing;
            assert_eq!(watchdog.check_walk(&fell), None);
            let mut through = sample(2.0, DAffine3::IDENTITY, 1.1 * radius);
            through.servo_ringing = ringing;
            watchdog
                .check_walk(&through)
                .expect("a foot through the ground diverges")
        };
        let report = rang(Some((0.007, 14)));
        assert!(
            report.contains(&format!(
                "the servo on `{}` rang at the step rate from t = 0.0070 s",
                model.joints[14].name
            )),
            "{report}"
        );
        let report = rang(None);
        assert!(!report.contains("rang"), "{report}");
        assert!(report.contains("fallen"), "{report}");
    }

    /// A body faster than 5 m/s is runaway unless its drop from the highest it has been
    /// explains the rest: hex18 tumbling 3 m down a 35° slope at 6 m/s (a fall from 3 m lands at
    /// 7.7 m/s) is not; the same speed on the level is.
    #[test]
    fn speed_a_drop_explains_is_not_runaway() {
        let model = crate::robot::hex18_for_tests();
        let at = |time: f64, z: f64, speed: f64| {
            let mut s = sample(time, DAffine3::from_translation(DVec3::Z * z), 0.0);
            s.body_velocity = DVec3::new(-speed, 0.0, 0.0);
            s
        };
        let sliding = Watchdog::walk(&model, NormalLaw::default(), 1e-3, 9.81);
        assert_eq!(sliding.check_walk(&at(0.0, 0.1, 0.0)), None);
        assert_eq!(sliding.check_walk(&at(2.0, -2.9, 6.0)), None);
        // 5 m/s more than a fall from 3 m gives: runaway however far it has dropped
        let report = sliding
            .check_walk(&at(2.1, -2.9, 5.1 + (2.0f64 * 9.81 * 3.0).sqrt()))
            .expect("faster than any drop explains");
        assert!(report.contains("runaway motion"), "{report}");

        let level = Watchdog::walk(&model, NormalLaw::default(), 1e-3, 9.81);
        assert_eq!(level.check_walk(&at(0.0, 0.1, 0.0)), None);
        let report = level
            .check_walk(&at(2.0, 0.1, 6.0))
            .expect("6 m/s on the level is runaway");
        assert!(report.contains("runaway motion: 6.0 m/s"), "{report}");
    }
}
