//! The reactive gait (blind): each foot's height found by touch, as in Walknet and Syropod.
//!
//! The schedule still says when a leg swings and where its foot goes across the ground; what the
//! feet feel says how high. Every foot's target carries a vertical offset from the planned path:
//! - **touch-down**: a swinging foot that meets the ground in the second half of its swing (its
//!   normal force past [`TOUCH_SHARE`] of its standing share) stops descending there and stays at
//!   that height through its stance — early, on a step up;
//! - **search**: a foot whose stance begins with no ground under it keeps reaching down at
//!   [`SEARCH_SPEED`] until it touches or its leg's room runs out — late, on a step down;
//! - **blocked**: a swinging foot pushed back against its swing (a riser in the way) lifts higher,
//!   its lift growing at [`LIFT_GROWTH`] while blocked, and carries on forward over it;
//! - **the body follows the feet that are down**: a plane fitted through the stance feet's offsets
//!   (least squares on their standing points) is taken off every foot's target, low-passed over
//!   [`BODY_TIME`] — the body rises with the feet on a step and pitches with them on a stair, and
//!   a swinging foot aims at that plane.

use super::schedule::LegPhase;
use glam::DVec3;

/// A foot touches when its normal force passes this share of its standing share of the weight.
pub const TOUCH_SHARE: f64 = 0.25;
/// How fast a foot that found no ground reaches down for it (m/s).
pub const SEARCH_SPEED: f64 = 0.15;
/// How fast a blocked swing's lift grows (step heights per second), and the most it grows to.
pub const LIFT_GROWTH: f64 = 12.0;
pub const MAX_EXTRA_LIFT: f64 = 2.5;
/// How fast a blocked swing draws its foot back from the obstacle (m/s), the most it draws it
/// back (m), and how fast it gives that back once free: pushed on into a riser the servos wind
/// up against it to their effort and the released leg kicks the body (hex18 hopped 7 cm).
pub const BACK_OFF_SPEED: f64 = 0.2;
pub const MAX_BACK_OFF: f64 = 0.02;
/// The body's plane follows the feet's over this time (s).
pub const BODY_TIME: f64 = 0.3;
/// The share of a swing at whose start a foot leaving the ground is not yet looked at (its
/// spring still relaxing), and from which on a touch is a touch-down.
const LIFT_OFF_SHARE: f64 = 0.15;
const DESCENT_SHARE: f64 = 0.5;

/// What a foot feels: its normal force (N) and its total ground force in the body frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FootFeel {
    pub normal_force: f64,
    pub force: DVec3,
}

/// The reactive gait's state per leg, between steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Reactive {
    /// Each foot's height offset from its planned path (m, body frame), the body's plane not
    /// yet taken off: set at touch-down, moved by the search.
    offset: [f64; 6],
    /// The offset off the plane at lift-off, which the swing brings back to the plane.
    lift_off: [f64; 6],
    /// The extra lift of a blocked swing (step heights).
    extra: [f64; 6],
    /// How far a blocked swing's foot is drawn back against its swing (m).
    back_off: [f64; 6],
    /// The swing ended early on the ground.
    touched: [bool; 6],
    was_stance: [bool; 6],
    /// The body's plane: offset = a + b·x + c·y (body frame, at the feet's standing points).
    plane: DVec3,
    feel: [FootFeel; 6],
    /// The force at which a foot counts as touching (N).
    touch_force: f64,
    dt: f64,
}

impl Reactive {
    /// `standing_share`: a foot's share of the weight standing on six (N); `dt` the step (s).
    pub fn new(standing_share: f64, dt: f64) -> Self {
        Reactive {
            offset: [0.0; 6],
            lift_off: [0.0; 6],
            extra: [0.0; 6],
            back_off: [0.0; 6],
            touched: [false; 6],
            was_stance: [true; 6],
            plane: DVec3::ZERO,
            feel: [FootFeel::default(); 6],
            touch_force: TOUCH_SHARE * standing_share,
            dt,
        }
    }

    /// What the feet felt in the last step.
    pub fn feel(&mut self, feel: [FootFeel; 6]) {
        self.feel = feel;
    }

    fn plane_at(&self, p: DVec3) -> f64 {
        self.plane.x + self.plane.y * p.x + self.plane.z * p.y
    }

    /// Moves the body's plane towards the one through the feet that are down, over [`BODY_TIME`].
    pub fn follow_feet(&mut self, neutral: &[DVec3; 6], phases: &[LegPhase; 6]) {
        let down: Vec<usize> = (0..6)
            .filter(|&k| phases[k].is_stance() || self.touched[k])
            .collect();
        if down.len() < 3 {
            return;
        }
        // least squares of a + b·x + c·y through (x_k, y_k, offset_k)
        let mut normal = glam::DMat3::ZERO;
        let mut rhs = DVec3::ZERO;
        for &k in &down {
            let a = DVec3::new(1.0, neutral[k].x, neutral[k].y);
            normal += glam::DMat3::from_cols(a * a.x, a * a.y, a * a.z);
            rhs += a * self.offset[k];
        }
        if normal.determinant().abs() < 1e-12 {
            return;
        }
        let fit = normal.inverse() * rhs;
        self.plane += (fit - self.plane) * (self.dt / BODY_TIME).min(1.0);
    }

    /// Leg `k`'s height offset (m, body frame) from its planned point `foot` on the ground (the
    /// lift not included) in `phase`: the swing's lift `lift` (m, of the gait's `step_height`)
    /// and its extra when blocked included. The foot moves across the ground along
    /// `swing_direction` (body frame) while it swings; `room` is how far it may go below and
    /// above its standing target.
    #[allow(clippy::too_many_arguments)]
    pub fn offset(
        &mut self,
        k: usize,
        foot: DVec3,
        phase: LegPhase,
        lift: f64,
        step_height: f64,
        swing_direction: DVec3,
        room: (f64, f64),
    ) -> f64 {
        let feel = self.feel[k];
        let touching = feel.normal_force > self.touch_force;
        let plane = self.plane_at(foot);
        let (low, high) = (-room.0, room.1 + (1.0 + MAX_EXTRA_LIFT) * step_height);
        match phase {
            LegPhase::Swing(s) => {
                if self.was_stance[k] {
                    // lift-off: the swing brings the foot from its height back to the plane
                    self.was_stance[k] = false;
                    self.lift_off[k] = self.offset[k] - plane;
                    self.extra[k] = 0.0;
                    self.back_off[k] = 0.0;
                    self.touched[k] = false;
                }
                if self.touched[k] {
                    return (self.offset[k] - plane).clamp(low, high);
                }
                let back = feel.force.truncate().dot(swing_direction.truncate());
                let blocked = s > LIFT_OFF_SHARE
                    && touching
                    && (s < DESCENT_SHARE || back < -0.5 * feel.force.length());
                if blocked {
                    self.extra[k] = (self.extra[k] + LIFT_GROWTH * self.dt).min(MAX_EXTRA_LIFT);
                    self.back_off[k] =
                        (self.back_off[k] + BACK_OFF_SPEED * self.dt).min(MAX_BACK_OFF);
                } else {
                    self.back_off[k] = (self.back_off[k] - BACK_OFF_SPEED * self.dt).max(0.0);
                }
                let towards_plane = 0.5 * (1.0 + (std::f64::consts::PI * s).cos());
                let here = (self.lift_off[k] * towards_plane + lift * (1.0 + self.extra[k]))
                    .clamp(low, high);
                if s >= DESCENT_SHARE && touching && !blocked {
                    // touch-down: the foot stays where it met the ground
                    self.touched[k] = true;
                    self.offset[k] = here + plane;
                } else {
                    // the ground the swing aims at, where a stance that finds none starts to search
                    self.offset[k] = self.lift_off[k] * towards_plane + plane;
                }
                here
            }
            LegPhase::Stance(_) => {
                self.was_stance[k] = true;
                if self.touched[k] || touching {
                    self.touched[k] = true;
                } else {
                    // no ground yet: reach down for it, within the leg's room
                    self.offset[k] = (self.offset[k] - SEARCH_SPEED * self.dt).max(plane + low);
                }
                (self.offset[k] - plane).clamp(low, high)
            }
        }
    }

    /// How far leg `k`'s swinging foot is drawn back against its swing (m).
    pub fn back_off(&self, k: usize) -> f64 {
        if self.touched[k] {
            0.0
        } else {
            self.back_off[k]
        }
    }

    /// Whether leg `k`'s foot is on the ground by the gait's reckoning: in stance, or its swing
    /// ended by a touch-down.
    pub fn grounded(&self, k: usize, phase: LegPhase) -> bool {
        phase.is_stance() || self.touched[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1e-3;
    const STEP: f64 = 0.03;
    const ROOM: (f64, f64) = (0.05, 0.04);

    fn pressed(normal: f64, force: DVec3) -> [FootFeel; 6] {
        let mut feel = [FootFeel::default(); 6];
        feel[0] = FootFeel {
            normal_force: normal,
            force,
        };
        feel
    }

    /// A foot that meets the ground late in its swing stays where it met it, through the rest of
    /// the swing and its stance; one that meets nothing reaches down for the ground at the
    /// search speed, no farther than its room.
    #[test]
    fn a_foot_lands_where_it_touches_and_searches_where_it_does_not() {
        let mut r = Reactive::new(4.0, DT);
        let foot = DVec3::new(0.1, 0.1, -0.1);
        let forward = DVec3::X;
        // standing on the ground before the swing
        r.feel(pressed(4.0, DVec3::new(0.0, 0.0, 4.0)));
        r.offset(0, foot, LegPhase::Stance(0.9), 0.0, STEP, forward, ROOM);
        // in the air until 70 % of the swing, then on a 1 cm step
        r.feel(pressed(0.0, DVec3::ZERO));
        let before = r.offset(0, foot, LegPhase::Swing(0.7), 0.012, STEP, forward, ROOM);
        r.feel(pressed(3.0, DVec3::new(0.0, 0.0, 3.0)));
        let touched = r.offset(0, foot, LegPhase::Swing(0.71), 0.011, STEP, forward, ROOM);
        assert_eq!(touched, 0.011);
        assert!(before > touched);
        assert!(r.grounded(0, LegPhase::Swing(0.8)));
        let later = r.offset(0, foot, LegPhase::Swing(0.9), 0.003, STEP, forward, ROOM);
        let stance = r.offset(0, foot, LegPhase::Stance(0.2), 0.0, STEP, forward, ROOM);
        assert_eq!((later, stance), (touched, touched));
        // the next swing finds nothing: its stance reaches down at the search speed
        r.feel(pressed(0.0, DVec3::ZERO));
        r.offset(0, foot, LegPhase::Swing(0.0), 0.0, STEP, forward, ROOM);
        let landed = r.offset(0, foot, LegPhase::Swing(0.999), 0.0, STEP, forward, ROOM);
        let mut heights = vec![];
        for _ in 0..1000 {
            heights.push(r.offset(0, foot, LegPhase::Stance(0.0), 0.0, STEP, forward, ROOM));
        }
        assert!((landed - heights[0] - SEARCH_SPEED * DT).abs() < 1e-12);
        assert!((heights[99] - (landed - 100.0 * SEARCH_SPEED * DT)).abs() < 1e-9);
        assert_eq!(*heights.last().unwrap(), -ROOM.0);
    }

    /// A swing pushed back against its direction lifts higher and draws back; one that touches
    /// nothing keeps the schedule's lift.
    #[test]
    fn a_blocked_swing_lifts_higher() {
        let mut r = Reactive::new(4.0, DT);
        let foot = DVec3::new(0.1, 0.1, -0.1);
        r.feel(pressed(4.0, DVec3::new(0.0, 0.0, 4.0)));
        r.offset(0, foot, LegPhase::Stance(0.9), 0.0, STEP, DVec3::X, ROOM);
        r.feel(pressed(0.0, DVec3::ZERO));
        let free = r.offset(0, foot, LegPhase::Swing(0.4), 0.02, STEP, DVec3::X, ROOM);
        assert!((free - 0.02).abs() < 1e-12);
        r.feel(pressed(3.0, DVec3::new(-3.0, 0.0, 0.5)));
        let mut lifted = free;
        for _ in 0..50 {
            lifted = r.offset(0, foot, LegPhase::Swing(0.4), 0.02, STEP, DVec3::X, ROOM);
        }
        assert!(lifted > free + 0.01, "{lifted} against {free}");
        assert!(r.back_off(0) > 0.0);
        assert!(!r.grounded(0, LegPhase::Swing(0.4)));
    }
}
