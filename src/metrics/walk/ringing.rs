//! A servo ringing at the step rate: a swinging leg's joint whose rate changes sign every step.
//!
//! No motion a servo drives alternates at the step rate; an explicit law that oversteps does:
//! where its damping moves a joint's speed by α of itself in one step, α > 1 overshoots, and
//! each step turns the last one's motion back (α > 2 grows). The impulse joints' servo is such
//! a law (`sim::articulation`); on light legs, at the step hexsim chooses, it rings — ant_bot's
//! tibias at 0.5 ms from 4.5 ms into the drop, with no foot on the ground. Only a leg whose
//! foot is off the ground counts: a stance foot's friction holding and letting go from one
//! step to the next also alternates a joint's rate, harmlessly (the multibody's walks of the
//! public robots show runs of 100 such steps at up to 3.6 rad/s; in swing, none).

use crate::robot::RobotModel;
use crate::sim::HexapodSample;

/// Steps in a row a ringing joint's rate has changed sign.
pub const RING_STEPS: u32 = 20;
/// The least rate (rad/s) an alternation counts at, both sides of it: above a still joint's
/// jitter.
pub const RING_RATE: f64 = 0.1;

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

    /// Takes one step's state, `dt` after the last.
    pub fn update(&mut self, s: &HexapodSample, dt: f64) {
        for (j, &rate) in s.joint_velocities.iter().enumerate().take(self.last.len()) {
            let swinging = self.leg_of[j].is_some_and(|k| s.foot_contacts[k].is_none());
            let last = self.last[j];
            let flipped =
                swinging && rate * last < 0.0 && rate.abs() > RING_RATE && last.abs() > RING_RATE;
            self.flips[j] = if flipped { self.flips[j] + 1 } else { 0 };
            self.last[j] = rate;
            if self.rang.is_none() && self.flips[j] >= RING_STEPS {
                self.rang = Some((s.time - f64::from(RING_STEPS) * dt, j));
            }
        }
    }

    /// The first joint that rang, and when it began (s of simulation).
    pub fn rang(&self) -> Option<(f64, usize)> {
        self.rang
    }
}
