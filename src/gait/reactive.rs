//! The reactive gait (blind): each foot's height found by touch, as in Walknet and Syropod.
//!
//! The schedule still says when a leg swings and where its foot goes across the ground; what the
//! feet feel says how high, and where a foot stops. Every foot's target carries an offset from the
//! planned path:
//! - **touch-down**: a swinging foot that meets the ground in the second half of its swing (its
//!   normal force past [`TOUCH_SHARE`] of its standing share) stops descending there and stays at
//!   that height through its stance — early, on a step up. From then on it moves with the ground,
//!   not along the rest of its swing: a foot that touched a tread and went on forward at the
//!   swing's speed slid across it (hex18 on 6 cm stairs, 30–40 mm at every touch-down). The
//!   foot's shift from the planned path is kept through the stance and given back in the air
//!   over the next swing, as its height is;
//! - **search**: a foot whose stance begins with no ground under it keeps reaching down at
//!   [`SEARCH_SPEED`] until it touches or its leg's room runs out — late, on a step down;
//! - **blocked**: a swinging foot pushed back against its swing (a riser in the way) lifts higher,
//!   its lift growing at [`LIFT_GROWTH`] while blocked, stays where it is across the ground
//!   meanwhile, and carries on forward over it, catching up with its swing by the landing;
//! - **not on a riser**: ground steeper than 45° ([`FOOTHOLD_COS`]) that pushes back against
//!   the swing is an obstacle, not a foothold, however near vertical its friction turns the
//!   force: a swing that meets it is blocked, from its lift-off on. Landed on a stair's nose
//!   (its friction holding the force 35° off vertical), hex18's rear foot slid 5 cm down the
//!   riser early in its stance; lifting from a riser's foot, a front foot scraped up its face;
//! - **the lift remembered**: the extra lift a blocked swing needed is remembered, fading over
//!   [`LIFT_MEMORY_TIME`], and every swing starts that much higher — the legs behind the one
//!   that met a riser, and the next risers of a flight, are cleared instead of met (stick
//!   insects step higher after meeting an obstacle). The memory and a swing's own extra
//!   together are at most one stance height ([`most_extra_lift`]), and the extra comes down
//!   with the square of the swing's lift: however high a swing was lifted, it lands at the
//!   gait's landing speed;
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
/// How long the legs remember the extra lift a blocked swing needed (s, the memory's time
/// constant): every swing starts that much higher, so on a flight of stairs the legs behind
/// the first and the swings at the next risers clear them instead of each scraping up the
/// riser's face again (stick insects step higher after meeting an obstacle).
pub const LIFT_MEMORY_TIME: f64 = 3.0;
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

/// The steepest ground a swing lands on (the cosine of its slope: 45°). A foot that meets
/// steeper ground pushing back against its swing (a riser's nose or face) has met an obstacle,
/// not a foothold: landed on a stair's nose, hex18's rear foot slid 5 cm down the riser in its
/// stance, at 1 m/s.
pub const FOOTHOLD_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The most extra lift a swing of a gait lifting `step_height` from a stance `stance_height`
/// high has, remembered and its own together (step heights): its foot at most one stance height
/// over its lift. A riser taller than the hips stand is not stepped onto by lifting higher, and
/// a foot stuck in a pit, blocked swing after swing, stacked its lifts up without bound.
pub fn most_extra_lift(stance_height: f64, step_height: f64) -> f64 {
    if step_height > 0.0 {
        stance_height / step_height
    } else {
        0.0
    }
}

/// What a foot feels: its normal force (N), its total ground force in the body frame, and
/// which way up the ground it touches is, if it touches any (the contact normal's share along
/// gravity's up, 1 on level ground, 0 on a wall: what a spherical foot's tactile skin tells
/// from where it is touched, even as it lifts away and the force is nil).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FootFeel {
    pub normal_force: f64,
    pub force: DVec3,
    pub upright: Option<f64>,
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
    /// The extra lift the last blocked swings needed, fading over [`LIFT_MEMORY_TIME`], with
    /// which every swing starts (step heights).
    lift_memory: f64,
    /// The memory each swing started with (step heights).
    remembered: [f64; 6],
    /// How far a blocked swing's foot is drawn back against its swing (m).
    back_off: [f64; 6],
    /// Each foot's horizontal shift from its planned path (m, body frame): a foot that touched
    /// down early moves with the ground from there, not on along its swing.
    shift: [DVec3; 6],
    /// The shift at lift-off, which the swing gives back as it does the height.
    shift_lift_off: [DVec3; 6],
    /// The part of the shift a blocked swing held back, given back by its landing.
    held: [DVec3; 6],
    /// The swing's horizontal progress and phase at the last step, and whether the shift saw
    /// this swing begin.
    progress: [(f64, f64); 6],
    shifting: [bool; 6],
    /// The swing was blocked at the last step.
    blocked: [bool; 6],
    /// The swing ended early on the ground.
    touched: [bool; 6],
    was_stance: [bool; 6],
    /// The body's plane: offset = a + b·x + c·y (body frame, at the feet's standing points).
    plane: DVec3,
    feel: [FootFeel; 6],
    /// The force at which a foot counts as touching (N).
    touch_force: f64,
    /// The most extra lift a swing has, remembered and its own together (step heights).
    most_extra: f64,
    dt: f64,
}

impl Reactive {
    /// `standing_share`: a foot's share of the weight standing on six (N); `most_extra`: the
    /// most extra lift a swing has, remembered and its own together (step heights; see
    /// [`most_extra_lift`]); `dt` the step (s).
    pub fn new(standing_share: f64, most_extra: f64, dt: f64) -> Self {
        Reactive {
            offset: [0.0; 6],
            lift_off: [0.0; 6],
            extra: [0.0; 6],
            lift_memory: 0.0,
            remembered: [0.0; 6],
            back_off: [0.0; 6],
            shift: [DVec3::ZERO; 6],
            shift_lift_off: [DVec3::ZERO; 6],
            held: [DVec3::ZERO; 6],
            progress: [(0.0, 0.0); 6],
            shifting: [false; 6],
            blocked: [false; 6],
            touched: [false; 6],
            was_stance: [true; 6],
            plane: DVec3::ZERO,
            feel: [FootFeel::default(); 6],
            touch_force: TOUCH_SHARE * standing_share,
            most_extra,
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
        self.lift_memory *= 1.0 - (self.dt / LIFT_MEMORY_TIME).min(1.0);
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
                    self.remembered[k] = self.lift_memory;
                    self.back_off[k] = 0.0;
                    self.touched[k] = false;
                }
                if self.touched[k] {
                    return (self.offset[k] - plane).clamp(low, high);
                }
                let back = feel.force.truncate().dot(swing_direction.truncate());
                // ground too steep to stand on that pushes back against the swing blocks it,
                // from its lift-off on (a foot lifting from a riser's foot scraped 5 cm up its
                // face); a stair's nose under a swing on its way down is passed over
                let against = back < 0.0 && feel.upright.is_some_and(|up| up < FOOTHOLD_COS);
                let blocked = against
                    || touching
                        && s > LIFT_OFF_SHARE
                        && (s < DESCENT_SHARE || back < -0.5 * feel.force.length());
                self.blocked[k] = blocked;
                if blocked {
                    // the swing's whole extra, remembered and its own, is bounded: a foot stuck
                    // in a pit, blocked swing after swing, stacked the memory up until it
                    // lifted 26 cm over MushroomRL's 8 cm stance, and landed at 2 m/s
                    let most = (self.most_extra - self.remembered[k]).clamp(0.0, MAX_EXTRA_LIFT);
                    self.extra[k] = (self.extra[k] + LIFT_GROWTH * self.dt).min(most);
                    self.lift_memory = self.lift_memory.max(self.remembered[k] + self.extra[k]);
                    self.back_off[k] =
                        (self.back_off[k] + BACK_OFF_SPEED * self.dt).min(MAX_BACK_OFF);
                } else {
                    self.back_off[k] = (self.back_off[k] - BACK_OFF_SPEED * self.dt).max(0.0);
                }
                let towards_plane = 0.5 * (1.0 + (std::f64::consts::PI * s).cos());
                // the remembered lift rises and falls with zero slope at both ends: it adds
                // nothing to the speed at which the foot lands (π·h/T_swing for the sine)
                let remembered =
                    step_height * self.remembered[k] * (std::f64::consts::PI * s).sin().powi(2);
                // the extra lift rises with the swing's lift and comes down past the top with
                // its square: landing, it adds nothing to the foot's speed. Scaled with the lift
                // all the way, a swing freed at 2.5 step heights of extra landed at 3.5 times
                // the gait's landing speed (MushroomRL's rear foot at 2 m/s on a trench's edge,
                // pressed with 6.6 of its weights)
                let descending = s > 0.5 && step_height > 0.0;
                let shape = if descending { lift / step_height } else { 1.0 };
                let extra = lift * self.extra[k] * shape;
                let here =
                    (self.lift_off[k] * towards_plane + lift + extra + remembered).clamp(low, high);
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

    /// Leg `k`'s horizontal shift (m, body frame) from its planned point, after [`Self::offset`]
    /// of the same step: `progress` is the swing's horizontal progress along the planned path
    /// n + d·(½ − progress) (0 in stance), `d` the ground's displacement under the foot over a
    /// stance of `stance_time` (s).
    ///
    /// A foot on the ground moves as the ground does, d/stance_time, while a swing's plan moves
    /// −d·Δprogress: the shift takes the difference — after an early touch-down, and while a
    /// swing is blocked (the foot stays at the riser, instead of the plan driving it on into the
    /// riser with the servos' whole effort: hex18 pressed 31 N into a 6 cm riser and pushed
    /// the body back across its stance feet). A blocked swing, freed, catches up with its plan
    /// by its landing. In stance plan and ground move together and the shift holds; the next
    /// swing gives it back in the air along ½(1 + cos πs), as the height's lift-off offset.
    pub fn shift(
        &mut self,
        k: usize,
        phase: LegPhase,
        progress: f64,
        d: DVec3,
        stance_time: f64,
    ) -> DVec3 {
        match phase {
            LegPhase::Swing(s) => {
                if !self.shifting[k] {
                    self.shifting[k] = true;
                    self.shift_lift_off[k] = self.shift[k];
                    self.held[k] = DVec3::ZERO;
                    self.progress[k] = (progress, s);
                }
                let (last_progress, last_s) = self.progress[k];
                let with_ground = d * (self.dt / stance_time + progress - last_progress);
                if self.touched[k] {
                    self.shift[k] += with_ground;
                } else {
                    if self.blocked[k] {
                        self.held[k] += with_ground;
                    } else if last_s < 1.0 {
                        self.held[k] *= ((1.0 - s) / (1.0 - last_s)).clamp(0.0, 1.0);
                    }
                    let towards_plan = 0.5 * (1.0 + (std::f64::consts::PI * s).cos());
                    self.shift[k] = self.shift_lift_off[k] * towards_plan + self.held[k];
                }
                self.progress[k] = (progress, s);
            }
            LegPhase::Stance(_) => self.shifting[k] = false,
        }
        self.shift[k]
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
            upright: (normal > 0.0).then(|| force.normalize_or_zero().z),
        };
        feel
    }

    /// A foot that meets the ground late in its swing stays where it met it, through the rest of
    /// the swing and its stance; one that meets nothing reaches down for the ground at the
    /// search speed, no farther than its room.
    #[test]
    fn a_foot_lands_where_it_touches_and_searches_where_it_does_not() {
        let mut r = Reactive::new(4.0, f64::INFINITY, DT);
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
        let mut r = Reactive::new(4.0, f64::INFINITY, DT);
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

    /// A swing that meets ground too steep to stand on (a stair's nose, a riser's face) has met
    /// an obstacle, not a foothold, even when the force it feels is near vertical: it does not
    /// land there but lifts and draws back, from its lift-off on; the same force on a tread is a
    /// touch-down, and a foot lifting off a tread is not blocked.
    #[test]
    fn a_foot_does_not_land_on_a_riser() {
        let foot = DVec3::new(0.1, 0.1, -0.1);
        // up and back, 25° off vertical: the nose's push with its friction up
        let force = DVec3::new(-7.0, 0.0, 15.0);
        let swing_into = |upright: f64, s: f64| {
            let mut r = Reactive::new(4.0, f64::INFINITY, DT);
            r.feel(pressed(4.0, DVec3::new(0.0, 0.0, 4.0)));
            r.offset(0, foot, LegPhase::Stance(0.9), 0.0, STEP, DVec3::X, ROOM);
            let mut feel = pressed(force.length(), force);
            feel[0].upright = Some(upright);
            r.feel(feel);
            let free = r.offset(0, foot, LegPhase::Swing(s), 0.01, STEP, DVec3::X, ROOM);
            let mut lifted = free;
            for _ in 0..20 {
                lifted = r.offset(0, foot, LegPhase::Swing(s), 0.01, STEP, DVec3::X, ROOM);
            }
            (
                r.grounded(0, LegPhase::Swing(s)),
                r.back_off(0),
                lifted - free,
            )
        };
        // a nose whose normal is 71° off vertical, late in the swing: blocked
        let (grounded, back_off, lift) = swing_into(0.32, 0.8);
        assert!(
            !grounded && back_off > 0.0 && lift > 0.0,
            "{back_off} {lift}"
        );
        // a tread: the touch-down
        let (grounded, back_off, _) = swing_into(1.0, 0.8);
        assert!(grounded && back_off == 0.0);
        // lifting off against a riser's face: blocked; off a tread: free
        let (grounded, back_off, lift) = swing_into(0.0, 0.02);
        assert!(
            !grounded && back_off > 0.0 && lift > 0.0,
            "{back_off} {lift}"
        );
        let (_, back_off, lift) = swing_into(1.0, 0.02);
        assert!(back_off == 0.0 && lift == 0.0);
    }

    /// A swing's planned point at progress p of `d` (the ground's displacement over a stance).
    fn planned(foot: DVec3, d: DVec3, progress: f64) -> DVec3 {
        foot + d * (0.5 - progress)
    }

    /// A foot that touches down early stays where it touched, moving with the ground through the
    /// rest of its swing and its stance; the next swing gives the shift back in the air.
    #[test]
    fn a_foot_that_touched_down_moves_with_the_ground() {
        let mut r = Reactive::new(4.0, f64::INFINITY, DT);
        let foot = DVec3::new(0.1, 0.1, -0.1);
        let d = DVec3::new(-0.05, 0.0, 0.0);
        let (stance_time, swing_time) = (0.5, 0.5);
        r.feel(pressed(4.0, DVec3::new(0.0, 0.0, 4.0)));
        r.offset(0, foot, LegPhase::Stance(0.9), 0.0, STEP, DVec3::X, ROOM);
        r.shift(0, LegPhase::Stance(0.9), 0.0, d, stance_time);
        // a swing of 500 steps with progress = s, touching from s = 0.6 on
        let mut at = vec![];
        for i in 0..500 {
            let s = i as f64 / 500.0;
            let touching = s >= 0.6;
            let force = if touching { 3.0 } else { 0.0 };
            r.feel(pressed(force, DVec3::new(0.0, 0.0, force)));
            r.offset(0, foot, LegPhase::Swing(s), 0.0, STEP, DVec3::X, ROOM);
            at.push(planned(foot, d, s) + r.shift(0, LegPhase::Swing(s), s, d, stance_time));
        }
        let touched = (0.6 * 500.0) as usize;
        assert!(r.grounded(0, LegPhase::Swing(0.99)));
        // from the touch on the foot moves d/stance_time a second, as the ground does
        for w in at[touched + 1..].windows(2) {
            assert!((w[1] - w[0] - d * (DT / stance_time)).length() < 1e-12);
        }
        // through the stance plan and ground move together: the shift holds
        r.offset(0, foot, LegPhase::Stance(0.0), 0.0, STEP, DVec3::X, ROOM);
        let held = r.shift(0, LegPhase::Stance(0.0), 0.0, d, stance_time);
        let expected = d * (1.0 - 0.6 + 0.4 * swing_time / stance_time);
        assert!(
            (held - expected).length() < 1e-3 * d.length(),
            "{held} against {expected}"
        );
        assert_eq!(r.shift(0, LegPhase::Stance(0.7), 0.0, d, stance_time), held);
        // the next swing, touching nothing, gives it back by its end
        r.feel(pressed(0.0, DVec3::ZERO));
        r.offset(0, foot, LegPhase::Swing(0.0), 0.0, STEP, DVec3::X, ROOM);
        let start = r.shift(0, LegPhase::Swing(0.0), 0.0, d, stance_time);
        r.offset(0, foot, LegPhase::Swing(0.999), 0.0, STEP, DVec3::X, ROOM);
        let end = r.shift(0, LegPhase::Swing(0.999), 0.999, d, stance_time);
        assert_eq!(start, held);
        assert!(end.length() < 1e-4 * held.length());
    }

    /// A blocked swing's foot stays where it is across the ground instead of being driven on into
    /// the riser, and once free catches up with its plan by the landing.
    #[test]
    fn a_blocked_swing_holds_its_ground_and_catches_up() {
        let mut r = Reactive::new(4.0, f64::INFINITY, DT);
        let foot = DVec3::new(0.1, 0.1, -0.1);
        let d = DVec3::new(-0.05, 0.0, 0.0);
        r.feel(pressed(4.0, DVec3::new(0.0, 0.0, 4.0)));
        r.offset(0, foot, LegPhase::Stance(0.9), 0.0, STEP, DVec3::X, ROOM);
        r.shift(0, LegPhase::Stance(0.9), 0.0, d, 0.5);
        let mut at = vec![];
        for i in 0..500 {
            let s = i as f64 / 500.0;
            // pushed back by a riser from 30 % to 40 % of the swing
            let force = if (0.3..0.4).contains(&s) {
                DVec3::new(-3.0, 0.0, 0.5)
            } else {
                DVec3::ZERO
            };
            r.feel(pressed(force.length(), force));
            r.offset(0, foot, LegPhase::Swing(s), 0.02, STEP, DVec3::X, ROOM);
            at.push(planned(foot, d, s) + r.shift(0, LegPhase::Swing(s), s, d, 0.5));
        }
        for w in at[151..200].windows(2) {
            assert!((w[1] - w[0] - d * (DT / 0.5)).length() < 1e-12);
        }
        let last = *at.last().unwrap();
        assert!((last - planned(foot, d, 0.998)).length() < 1e-3 * d.length());
    }

    /// The extra lift a blocked swing needed raises the next swings, of every leg, with zero slope
    /// at their ends (the landing no faster), and fades over the memory's time.
    #[test]
    fn the_lift_a_riser_asked_for_is_remembered() {
        let mut r = Reactive::new(4.0, f64::INFINITY, DT);
        let foot = DVec3::new(0.1, 0.1, -0.1);
        let phases = [LegPhase::Stance(0.5); 6];
        let neutral = [foot; 6];
        r.feel(pressed(0.0, DVec3::ZERO));
        // leg 1 standing on the ground, then swinging through nothing
        let mut standing = [FootFeel::default(); 6];
        standing[1] = FootFeel {
            normal_force: 4.0,
            force: DVec3::new(0.0, 0.0, 4.0),
            upright: Some(1.0),
        };
        let swing = |r: &mut Reactive| {
            r.feel(standing);
            r.offset(1, foot, LegPhase::Stance(0.9), 0.0, STEP, DVec3::X, ROOM);
            r.feel(pressed(0.0, DVec3::ZERO));
            r.offset(1, foot, LegPhase::Swing(0.5), 0.02, STEP, DVec3::X, ROOM)
        };
        let plain = swing(&mut r);
        // leg 0 blocked for 50 steps
        r.feel(pressed(3.0, DVec3::new(-3.0, 0.0, 0.5)));
        for _ in 0..50 {
            r.offset(0, foot, LegPhase::Swing(0.4), 0.02, STEP, DVec3::X, ROOM);
        }
        let needed = 50.0 * LIFT_GROWTH * DT;
        let raised = swing(&mut r);
        assert!(
            (raised - plain - needed * STEP).abs() < 1e-9,
            "{raised} against {plain}"
        );
        let near_end = r.offset(1, foot, LegPhase::Swing(0.999), 0.0, STEP, DVec3::X, ROOM);
        assert!(near_end.abs() < 1e-4 * needed * STEP);
        // one memory time later the next swing starts 1/e as high
        for _ in 0..(LIFT_MEMORY_TIME / DT) as usize {
            r.follow_feet(&neutral, &phases);
        }
        let faded = swing(&mut r);
        let share = (faded - plain) / (needed * STEP);
        assert!((share - (-1.0f64).exp()).abs() < 1e-3, "{share}");
    }
    /// A swing freed from an obstacle lands as fast as a plain one: its extra lift comes down
    /// with the square of the swing's lift. Scaled with the lift to the end, this one, freed at
    /// 0.6 step heights of extra, landed 1.6 times as fast.
    #[test]
    fn a_freed_swing_lands_as_fast_as_a_plain_one() {
        use std::f64::consts::PI;
        let foot = DVec3::new(0.1, 0.1, -0.1);
        let lift = |s: f64| STEP * (PI * s).sin();
        let landing = |blocked: bool| {
            let mut r = Reactive::new(4.0, f64::INFINITY, DT);
            r.feel(pressed(4.0, DVec3::new(0.0, 0.0, 4.0)));
            r.offset(0, foot, LegPhase::Stance(0.9), 0.0, STEP, DVec3::X, ROOM);
            if blocked {
                r.feel(pressed(3.0, DVec3::new(-3.0, 0.0, 0.5)));
                for _ in 0..50 {
                    r.offset(
                        0,
                        foot,
                        LegPhase::Swing(0.3),
                        lift(0.3),
                        STEP,
                        DVec3::X,
                        ROOM,
                    );
                }
            }
            r.feel(pressed(0.0, DVec3::ZERO));
            let mut at =
                |s: f64| r.offset(0, foot, LegPhase::Swing(s), lift(s), STEP, DVec3::X, ROOM);
            let top = at(0.5);
            let ds = 1e-3;
            let (before, end) = (at(1.0 - ds), at(1.0));
            (top, (before - end) / ds)
        };
        let (plain_top, plain) = landing(false);
        let (freed_top, freed) = landing(true);
        assert!(
            (freed_top - plain_top - 0.6 * STEP).abs() < 1e-9,
            "{freed_top} against {plain_top}"
        );
        assert!((plain - PI * STEP).abs() < 1e-3 * PI * STEP, "{plain}");
        assert!(
            (freed - plain).abs() < 0.01 * plain,
            "{freed} against {plain}"
        );
    }

    /// A foot blocked swing after swing (stuck in a pit) lifts no higher than its bound, the
    /// memory of the last blocked swings and its own extra together; unbounded, each swing
    /// stacked its extra on the memory the last one left.
    #[test]
    fn blocked_swing_after_swing_lifts_no_higher_than_the_bound() {
        let most = 1.5;
        let mut r = Reactive::new(4.0, most, DT);
        let foot = DVec3::new(0.1, 0.1, -0.1);
        let mut tops = vec![];
        for _ in 0..4 {
            r.feel(pressed(4.0, DVec3::new(0.0, 0.0, 4.0)));
            r.offset(0, foot, LegPhase::Stance(0.9), 0.0, STEP, DVec3::X, ROOM);
            r.feel(pressed(3.0, DVec3::new(-3.0, 0.0, 0.5)));
            let mut top = 0.0f64;
            for _ in 0..500 {
                let height = r.offset(0, foot, LegPhase::Swing(0.5), STEP, STEP, DVec3::X, ROOM);
                top = top.max(height);
            }
            tops.push(top);
        }
        for top in tops {
            assert!((top - (1.0 + most) * STEP).abs() < 1e-9, "{top}");
        }
    }
}
