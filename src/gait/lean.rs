//! The body's lean on a slope: every foot's target moved across the body, and the body lowered,
//! so that the centre of mass's plumb line keeps inside the feet's support.
//!
//! A body that stands parallel to a slope of angle θ (blind, the body follows the feet; or
//! perceptive, where the legs level only part of it) carries its centre of mass a height h over
//! the feet's plane, and its plumb line meets that plane h·tan θ downhill of where it would on
//! level ground. On hexaross (h ≈ 0.2 m) that is 0.12 m on 30°: behind its tripods' rear edges,
//! and it went over backwards walking up.
//!
//! With ĝ gravity's unit vector in the body frame (an IMU's reading), the plumb line through the
//! centre of mass c meets the feet's plane z = c.z − h at c + ĝ·h/(−ĝ.z): it is off its level
//! ground's point by o = ĝ.xy·h/(−ĝ.z). The gait's support polygons leave it a margin m along
//! each way on level ground ([`support_margin`], the least over a cycle); the lean lets the
//! plumb line use [`SUPPORT_SHARE`] of it and corrects the rest: it moves every foot target by
//! that much along o (the body over them the other way), within the legs' room
//! ([`HorizontalRoom`]), and what the room cannot take it takes by crouching: lowered by c, the
//! plumb line moves c·tan θ back. A walk's rocking on mild ground, and a stair's pitch on a
//! robot with a wide stance, lean nothing. The lean follows its target over [`LEAN_TIME`]. A
//! gait whose support polygons leave the centre of mass outside some of them on level ground
//! (MushroomRL's tripod: its triangles 8 cm deep, the centre of mass 1.6 cm behind them) has no
//! static margin to keep along that way, and does not lean along it: leaning on every tilt of
//! the natural terrain, its walk diverged (a leg's 1 mm contact sphere 1.1 mm deep).

use glam::{DVec2, DVec3};

/// The share of the level ground's support margin the plumb line may use before the lean
/// corrects it: the rest is kept for the walk's own sway. On the ladders (four robots, blind
/// and perceptive) a quarter left 7 falls of 416 runs and half 11 (13 without the lean).
pub const SUPPORT_SHARE: f64 = 0.25;
/// The lean follows its target over this time (s): a gait cycle or two, slower than the body's
/// rocking within one.
pub const LEAN_TIME: f64 = 1.0;

/// Lengths along the body's −x, +x, −y and +y (m): how far the feet may move all together and
/// stay within each leg's reach, or how far the plumb line may move and stay inside the support.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HorizontalRoom {
    pub back: f64,
    pub fore: f64,
    pub right: f64,
    pub left: f64,
}

impl HorizontalRoom {
    fn clamp(&self, s: DVec2) -> DVec2 {
        DVec2::new(
            s.x.clamp(-self.back, self.fore),
            s.y.clamp(-self.right, self.left),
        )
    }

    /// The length along the unit `direction`, between the axes' on an ellipse.
    fn along(&self, direction: DVec2) -> f64 {
        let x = if direction.x < 0.0 {
            self.back
        } else {
            self.fore
        };
        let y = if direction.y < 0.0 {
            self.right
        } else {
            self.left
        };
        // a way the direction does not go counts nothing, a way with no length everything
        let term = |c: f64, length: f64| if c == 0.0 { 0.0 } else { (c / length).powi(2) };
        let inverse = (term(direction.x, x) + term(direction.y, y)).sqrt();
        if inverse > 0.0 { 1.0 / inverse } else { 0.0 }
    }
}

/// How far from `from` along the unit `direction` the edge of a convex `hull` ([`convex_hull`])
/// is (m; 0 when `from` is outside it or the hull has fewer than three points): a ray cast
/// against each edge.
pub fn support_margin(hull: &[DVec2], from: DVec2, direction: DVec2) -> f64 {
    if hull.len() < 3 {
        return 0.0;
    }
    let mut nearest = f64::INFINITY;
    for (i, &a) in hull.iter().enumerate() {
        let b = hull[(i + 1) % hull.len()];
        // counter-clockwise: `from` is inside when left of every edge
        let edge = b - a;
        let inside = edge.perp_dot(from - a);
        if inside < 0.0 {
            return 0.0;
        }
        let towards = -edge.perp_dot(direction);
        if towards > 0.0 {
            nearest = nearest.min(inside / towards);
        }
    }
    if nearest.is_finite() { nearest } else { 0.0 }
}

/// The convex hull of a few points, counter-clockwise (Andrew's monotone chain: the lower
/// chain over the points sorted by x, the upper over them in reverse). parry's 2-D hull is not
/// built into the 3-D crate.
pub fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut sorted = points.to_vec();
    sorted.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * sorted.len());
    for _ in 0..2 {
        let start = hull.len();
        for &p in &sorted {
            while hull.len() >= start + 2 {
                let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
                if (b - a).perp_dot(p - a) <= 0.0 {
                    hull.pop();
                } else {
                    break;
                }
            }
            hull.push(p);
        }
        hull.pop(); // the last point starts the other chain
        sorted.reverse();
    }
    hull
}

/// The lean's state: its target's inputs and where it stands.
#[derive(Debug, Clone, PartialEq)]
pub struct Lean {
    /// The centre of mass's height over the feet's standing plane (m, body frame).
    height: f64,
    /// How far the plumb line may move on level ground and stay inside the support.
    margin: HorizontalRoom,
    room: HorizontalRoom,
    /// How far the body may crouch (m): every foot target raised that much.
    crouch_room: f64,
    shift: DVec3,
}

impl Lean {
    pub fn new(
        height: f64,
        margin: HorizontalRoom,
        room: HorizontalRoom,
        crouch_room: f64,
    ) -> Self {
        Lean {
            height,
            margin,
            room,
            crouch_room: crouch_room.max(0.0),
            shift: DVec3::ZERO,
        }
    }

    /// Where the lean heads for with gravity along `down` (body frame; any length): the feet's
    /// move across the body (x, y) and the crouch (z).
    pub fn target(&self, down: DVec3) -> DVec3 {
        let down = down.normalize_or_zero();
        if down.z >= -1e-9 {
            return DVec3::ZERO; // on its side or upside down: no plumb line onto the feet
        }
        let across = down.truncate();
        let offset = across * self.height / -down.z;
        let length = offset.length();
        if length == 0.0 {
            return DVec3::ZERO;
        }
        let margin = self.margin.along(offset / length);
        let allowed = SUPPORT_SHARE * margin;
        if margin <= 0.0 || length <= allowed {
            // no margin: a gait that leaves the centre of mass outside some of its support
            // polygons on level ground stands by its motion, not its plumb line
            return DVec3::ZERO;
        }
        let correction = offset * (1.0 - allowed / length);
        let shift = self.room.clamp(correction);
        // what the feet's room cannot take, a crouch takes: lowered by c, the plumb line moves
        // c·tan θ back over the feet
        let tan = across.length() / -down.z;
        let crouch = ((correction.length() - shift.length()) / tan).min(self.crouch_room);
        shift.extend(crouch)
    }

    /// The tilt (rad) from which the lean acts with gravity along the unit `across` direction of
    /// the body's plane (the plumb line moving that way): where h·tan θ passes the allowed share
    /// of the margin.
    pub fn onset(&self, across: DVec2) -> f64 {
        (SUPPORT_SHARE * self.margin.along(across) / self.height).atan()
    }

    /// What the lean has to go on, for `hexsim robot`.
    pub fn describe(&self) -> String {
        let (m, r) = (&self.margin, &self.room);
        if [m.back, m.fore, m.right, m.left].contains(&0.0) {
            return format!(
                "none: the gait's support polygons do not all hold the centre of mass on level ground (margin {:.3} m back, {:.3} fore, {:.3} right, {:.3} left; it stands by its motion), so there is no margin to keep that way",
                m.back, m.fore, m.right, m.left
            );
        }
        format!(
            "centre of mass {:.3} m over the feet; support margin {:.3} m back, {:.3} fore, {:.3} right, {:.3} left; leans from {:.1}° nose up, {:.1}° nose down, {:.1}° rolled; feet's room {:.1} mm back, {:.1} fore, {:.1} to the side; crouches up to {:.1} mm",
            self.height,
            m.back,
            m.fore,
            m.right,
            m.left,
            self.onset(DVec2::NEG_X).to_degrees(),
            self.onset(DVec2::X).to_degrees(),
            self.onset(DVec2::NEG_Y)
                .min(self.onset(DVec2::Y))
                .to_degrees(),
            r.back * 1e3,
            r.fore * 1e3,
            r.right.min(r.left) * 1e3,
            self.crouch_room * 1e3
        )
    }

    /// One step of `dt` towards [`Self::target`].
    pub fn follow(&mut self, down: DVec3, dt: f64) {
        let target = self.target(down);
        self.shift += (target - self.shift) * (dt / LEAN_TIME).min(1.0);
    }

    /// Every foot target's move (body frame): across the body, and up by the crouch.
    pub fn shift(&self) -> DVec3 {
        self.shift
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROOM: HorizontalRoom = HorizontalRoom {
        back: 0.05,
        fore: 0.04,
        right: 0.03,
        left: 0.03,
    };
    const WIDE: HorizontalRoom = HorizontalRoom {
        back: 1.0,
        fore: 1.0,
        right: 1.0,
        left: 1.0,
    };
    /// A support that leaves the plumb line 0.08 m every way: 0.02 m of it used before leaning.
    const MARGIN: HorizontalRoom = HorizontalRoom {
        back: 0.08,
        fore: 0.08,
        right: 0.08,
        left: 0.08,
    };

    /// Gravity in the frame of a body pitched nose-up by `deg` (up a slope towards +x).
    fn pitched_up(deg: f64) -> DVec3 {
        let a = deg.to_radians();
        DVec3::new(-a.sin(), 0.0, -a.cos())
    }

    #[test]
    fn the_support_margin_is_the_distance_to_the_hulls_edge() {
        let square = [
            (-1.0, -1.0),
            (1.0, -1.0),
            (1.0, 1.0),
            (-1.0, 1.0),
            (0.2, 0.3),
        ]
        .map(|(x, y)| DVec2::new(x, y));
        let hull = convex_hull(&square);
        let margin = |from: DVec2, d: DVec2| support_margin(&hull, from, d.normalize());
        assert!((margin(DVec2::ZERO, DVec2::X) - 1.0).abs() < 1e-12);
        assert!((margin(DVec2::ZERO, DVec2::new(1.0, 1.0)) - 2f64.sqrt()).abs() < 1e-12);
        assert!((margin(DVec2::new(0.5, 0.0), DVec2::NEG_X) - 1.5).abs() < 1e-12);
        // outside, or with no polygon to stand in, no margin
        assert_eq!(margin(DVec2::new(1.5, 0.0), DVec2::NEG_X), 0.0);
        assert_eq!(
            support_margin(&convex_hull(&square[..2]), DVec2::ZERO, DVec2::X),
            0.0
        );
        // a tripod's triangle: from its centroid towards a vertex, a third of the way beyond
        let tripod = [(0.0, 2.0), (-1.5, -1.0), (1.5, -1.0)].map(|(x, y)| DVec2::new(x, y));
        let tripod = convex_hull(&tripod);
        assert!((support_margin(&tripod, DVec2::ZERO, DVec2::Y) - 2.0).abs() < 1e-12);
        assert!((support_margin(&tripod, DVec2::ZERO, DVec2::NEG_Y) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn up_a_slope_the_feet_move_downhill_by_what_the_margin_does_not_allow() {
        let lean = Lean::new(0.2, MARGIN, WIDE, 0.05);
        // 30°: the plumb line meets the feet's plane 0.2·tan 30° = 0.1155 m downhill, 0.02 m of
        // it allowed; the room takes the rest and nothing is left to crouch
        let s = lean.target(pitched_up(30.0));
        let want = 0.2 * 30f64.to_radians().tan() - SUPPORT_SHARE * MARGIN.back;
        assert!((s.x + want).abs() < 1e-12, "{s}");
        assert_eq!((s.y, s.z), (0.0, 0.0));
        // down the slope, the other way
        assert!((lean.target(pitched_up(-30.0)).x - want).abs() < 1e-12);
        // within the allowed share (0.2·tan 5° = 0.0175 m), nothing
        assert_eq!(lean.target(pitched_up(5.0)), DVec3::ZERO);
        assert_eq!(lean.target(DVec3::NEG_Z), DVec3::ZERO);
        assert_eq!(lean.target(DVec3::X), DVec3::ZERO);
    }

    #[test]
    fn the_room_bounds_the_shift_and_a_crouch_takes_the_rest_within_its_room() {
        let lean = Lean::new(0.2, MARGIN, ROOM, 1.0);
        let tan = 30f64.to_radians().tan();
        let s = lean.target(pitched_up(30.0));
        assert_eq!(s.x, -ROOM.back);
        // lowered c, the plumb line moves c·tan 30°
        let crouch = (0.2 * tan - SUPPORT_SHARE * MARGIN.back - ROOM.back) / tan;
        assert!((s.z - crouch).abs() < 1e-12, "{s} against {crouch}");
        assert_eq!(
            Lean::new(0.2, MARGIN, ROOM, 0.03)
                .target(pitched_up(30.0))
                .z,
            0.03
        );
        // a negative room (none measured) crouches nothing
        assert_eq!(
            Lean::new(0.2, MARGIN, ROOM, -0.1)
                .target(pitched_up(30.0))
                .z,
            0.0
        );
        // rolled 40° onto its right side (gravity towards −y): the feet move right
        let a = 40f64.to_radians();
        let rolled = DVec3::new(0.0, -a.sin(), -a.cos());
        assert_eq!(lean.target(rolled).y, -ROOM.right);
    }

    #[test]
    fn a_gait_with_no_static_margin_along_a_way_does_not_lean_that_way() {
        let no_fore_aft = HorizontalRoom {
            back: 0.0,
            fore: 0.0,
            ..MARGIN
        };
        let lean = Lean::new(0.2, no_fore_aft, ROOM, 1.0);
        assert_eq!(lean.target(pitched_up(30.0)), DVec3::ZERO);
        assert!(lean.describe().starts_with("none"));
        // rolled, it still has its sideways margin to keep
        let a = 40f64.to_radians();
        assert_eq!(
            lean.target(DVec3::new(0.0, -a.sin(), -a.cos())).y,
            -ROOM.right
        );
    }

    #[test]
    fn the_lean_follows_its_target_over_its_time() {
        let mut lean = Lean::new(0.2, MARGIN, ROOM, 1.0);
        let target = lean.target(pitched_up(25.0));
        assert!(target.x < 0.0 && target.z > 0.0, "{target}");
        let dt = 0.001;
        let steps = (LEAN_TIME / dt).round() as usize;
        for _ in 0..steps {
            lean.follow(pitched_up(25.0), dt);
        }
        // a first-order lag: 1 − 1/e of the way after one time constant
        for (got, want) in [(lean.shift().x, target.x), (lean.shift().z, target.z)] {
            let share = got / want;
            assert!((share - (1.0 - (-1.0f64).exp())).abs() < 1e-3, "{share}");
        }
    }
}
