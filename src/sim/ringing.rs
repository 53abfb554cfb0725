//! A servo ringing at the step rate: a swinging leg's joint whose rate changes sign every step.
//!
//! No motion a servo drives alternates at the step rate; an explicit law that oversteps does:
//! where its damping moves a joint's speed by α of itself in one step, α > 1 overshoots, and
//! each step turns the last one's motion back (α > 2 grows). The impulse joints' servo was such
//! a law while its damper was explicit: on light legs, at the step hexsim chose, it rang —
//! ant_bot's coxa at 0.5 ms from 7 ms into the drop, with no foot on the ground, and the walk
//! diverged (`sim::articulation::impulse` now damps implicitly). Only a leg whose
//! foot is off the ground counts: a stance foot's friction holding and letting go from one
//! step to the next also alternates a joint's rate, harmlessly (the multibody's walks of the
//! public robots show runs of 100 such steps at up to 3.6 rad/s; in swing, none).

use crate::contact::ContactForce;
use crate::robot::RobotModel;

/// Steps in a row a ringing joint's rate has changed sign.
pub const RING_STEPS: u32 = 20;
/// The least rate (rad/s) an alternation counts at, both sides of it: above a still joint's
/// jitter.
pub const RING_RATE: f64 = 0.1;

/// What a ringing joint says, in a warning or as a divergence's cause: which servo, from when,
/// and what to do.
pub fn describe(joint: &str, from: f64) -> String {
    format!(
        "the servo on `{joint}` rang at the step rate from t = {from:.4} s (its rate changed sign \
         every step for {RING_STEPS} steps and more, its foot off the ground): it oversteps on \
         that joint's inertia at this dt; reduce dt or soften the servo (on impulse joints, \
         whose spring is explicit: or walk on the multibody articulation, whose spring is \
         implicit)"
    )
}

/// Follows every joint's rate step by step; remembers the first that rang.
#[derive(Debug, Clone, Default)]
pub struct Ringing {
    /// Per model joint: its leg (None off the legs), its rate last step, and how many steps in
    /// a row that rate has changed sign.
    leg_of: Vec<Option<usize>>,
    last: Vec<f64>,
    flips: Vec<u32>,
    rang: Option<(f64, usize)>,
}

impl Ringing {
    pub fn new(model: &RobotModel) -> Self {
        let joints = model.joints.len();
        Ringing {
            leg_of: (0..joints)
                .map(|j| model.legs.iter().position(|leg| leg.joints.contains(&j)))
                .collect(),
            last: vec![0.0; joints],
            flips: vec![0; joints],
            rang: None,
        }
    }

    /// Takes one step's joint `rates` and foot `contacts` at `time`, `dt` after the last
    /// (nothing more once a joint has rung).
    pub fn update(&mut self, time: f64, dt: f64, rates: &[f64], contacts: &[Option<ContactForce>]) {
        if self.rang.is_some() {
            return;
        }
        let n = self.last.len().min(rates.len());
        let (rates, last, flips) = (&rates[..n], &mut self.last[..n], &mut self.flips[..n]);
        // the signs first, for every joint in one pass: most steps, none flips
        let mut any = false;
        for j in 0..n {
            // `&`, not `&&`: no branches, so the loop runs as vector code
            let flipped = (rates[j] * last[j] < 0.0)
                & (rates[j].abs() > RING_RATE)
                & (last[j].abs() > RING_RATE);
            flips[j] = (flips[j] + 1) * u32::from(flipped);
            any |= flipped;
        }
        last.copy_from_slice(rates);
        if !any {
            return;
        }
        for (j, flips) in flips.iter_mut().enumerate() {
            if *flips == 0 {
                continue;
            }
            if self.leg_of[j].is_none_or(|k| contacts[k].is_some()) {
                *flips = 0;
            } else if *flips >= RING_STEPS {
                self.rang = Some((time - f64::from(RING_STEPS) * dt, j));
                return;
            }
        }
    }

    /// The first joint that rang, and when it began (s of simulation).
    pub fn rang(&self) -> Option<(f64, usize)> {
        self.rang
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::GroundFrame;
    use glam::DVec3;

    /// A swinging leg's joint whose rate flips sign every step for 20 steps rings, from the
    /// first of them; one that turns one way, flips fewer steps in a row, flips slower than 0.1
    /// rad/s, or whose foot is on the ground (its friction holding and letting go), does not.
    #[test]
    fn a_swinging_joint_flipping_every_step_rings() {
        let model = crate::robot::hex18_for_tests();
        let joint = model.legs[2].joints[2];
        let dt = 1e-3;
        let run = |rate: &dyn Fn(usize) -> f64, grounded: bool| {
            let mut ringing = Ringing::new(&model);
            let mut contacts = [None; 6];
            if grounded {
                contacts[2] = Some(ContactForce {
                    point: DVec3::ZERO,
                    force: DVec3::Z,
                    normal_force: 1.0,
                    friction: DVec3::ZERO,
                    penetration: 1e-4,
                    normal_velocity: 0.0,
                    slip: DVec3::ZERO,
                    sticking: true,
                    frame: GroundFrame::from_normal(DVec3::Z),
                    load: 1.0,
                });
            }
            let mut rates = vec![0.0; model.joints.len()];
            for i in 0..60 {
                rates[joint] = rate(i);
                ringing.update(i as f64 * dt, dt, &rates, &contacts);
            }
            ringing.rang()
        };
        let alternating = |i: usize| if i.is_multiple_of(2) { 2.0 } else { -2.0 };
        let (from, rang) = run(&alternating, false).expect("it rings");
        assert_eq!(rang, joint);
        // the first flip is at step 1, the 20th at step 20
        assert!((from - 0.0).abs() < 1e-12, "{from}");
        assert_eq!(run(&alternating, true), None);
        assert_eq!(run(&|_| 2.0, false), None);
        // a sign held once every 15 steps: 14 flips in a row at most
        let broken = |i: usize| {
            if (i - i / 15).is_multiple_of(2) {
                2.0
            } else {
                -2.0
            }
        };
        assert_eq!(run(&broken, false), None);
        let slow = |i: usize| if i.is_multiple_of(2) { 0.05 } else { -0.05 };
        assert_eq!(run(&slow, false), None);
    }
}
