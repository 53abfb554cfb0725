//! How fast a foot target may move: a bound from the gait's own swing timing.
//!
//! A servo given a target far from where its joint is swings there as hard as its gains and
//! effort allow: a foot target that jumps lands the foot at metres per second (17 m/s on
//! `stones`, sinking it 11.7 mm). Bounding each joint target's rate by the URDF's `<limit
//! velocity>` was tried and reverted: wild URDFs carry placeholders there (3e-5 rad/s, 1.75
//! rad/s) that stop a walk. The gait itself says how fast a foot needs to move: its swing
//! covers the stride and the lift in the swing's time, the fastest point of the sine lift and
//! the matched swing's horizontal progress being π·h/T_swing up and 2·stride/T_swing along (see
//! `controller::swing_profile`). A target may move [`SPEED_FACTOR`] times that, room for the
//! reactive gait's higher lifts and a perceptive swing over a riser; faster is a jump, and the
//! target follows it at the bound instead.

use super::spec::Gait;
use glam::DVec3;

/// A foot target may move this many times the gait's fastest nominal swing speed.
pub const SPEED_FACTOR: f64 = 4.0;

/// The fastest a foot target may move (m/s) for a gait whose stride this instant is `stride`
/// (m; the command's, which may exceed the gait's nominal one).
pub fn speed_limit(gait: &Gait, stride: f64) -> f64 {
    let swing_time = (1.0 - gait.duty_factor) * gait.period;
    let along = 2.0 * stride.max(gait.stride_length);
    let up = std::f64::consts::PI * gait.step_height;
    // a gait that neither strides nor lifts still moves its feet as far as its stance is high
    let floor = 0.25 * gait.stance_height;
    SPEED_FACTOR * along.hypot(up).max(floor) / swing_time
}

/// How fast a perceptive stance foot's target may sink or rise (m/s): the gait's landing speed,
/// π·h/T_swing (its sine swing's at touch-down, [`Gait::touchdown_speed`], what the time step is
/// fitted to: `setup::time_step`). A stance target follows the ground planned under it, which
/// steps by a riser's height where that point crosses an edge or the body's reference moves;
/// followed at [`speed_limit`]'s pace, a target 3 cm down in 20 ms drove PhantomX's rf foot,
/// in the air over a lower tread, into it at 0.8 m/s and 7.1 mm deep (its radius 7 mm: the run
/// diverged), and a foot on the ground drives the body up as fast. Sinking at the landing
/// speed, a stance foot meets its ground as a swing does. Rising, it lowers the body: at
/// [`speed_limit`]'s pace hexaross, crouching 7 cm to reach the tread below the top of a 10 cm
/// flight, drew its feet up faster than its body could fall after them, every foot unloaded for
/// 0.1 s, and it tumbled down the flight; at the landing speed the body follows its feet down.
pub fn landing_speed(gait: &Gait) -> f64 {
    let swing_time = (1.0 - gait.duty_factor) * gait.period;
    std::f64::consts::PI * gait.step_height / swing_time
}

/// The fastest joint `j` of a leg may move its target (rad/s), from the leg's joints' fastest
/// rates over a nominal cycle (`nominal`): [`SPEED_FACTOR`] times its own, or a quarter of its
/// leg's fastest where its own is smaller (a joint the straight walk hardly turns, as a coxa,
/// turns in a curve). The joint targets are bounded as well as the foot's: a leg that misses
/// its target is solved again from its standing pose and may land on another branch, a radian
/// or more away, however slowly the target moves (`controller::solve_on_branch`).
pub fn joint_speed_limit(nominal: &[f64], j: usize) -> f64 {
    let fastest = nominal.iter().copied().fold(0.0, f64::max);
    if fastest > 0.0 {
        SPEED_FACTOR * nominal[j].max(0.25 * fastest)
    } else {
        f64::INFINITY
    }
}

/// `target` moved from `last` by no more than `longest` (m); `target` itself, bit for bit, when
/// it is within that.
pub fn limited(last: DVec3, target: DVec3, longest: f64) -> DVec3 {
    let step = target - last;
    let length = step.length();
    if length <= longest {
        target
    } else {
        last + step * (longest / length)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_jump_is_followed_at_the_bound_and_a_step_within_it_is_kept() {
        let last = DVec3::new(0.1, 0.1, -0.1);
        let near = last + DVec3::new(0.0, 0.0, 0.0005);
        assert_eq!(limited(last, near, 0.001), near);
        let far = last + DVec3::new(0.0, 0.0, -0.1);
        let moved = limited(last, far, 0.001);
        assert!(((moved - last).length() - 0.001).abs() < 1e-12);
        assert!((moved - last).normalize().abs_diff_eq(DVec3::NEG_Z, 1e-12));
    }

    /// hex18's tripod (0.06 m stride, 0.5 s swing): a nominal swing stays well inside the bound.
    #[test]
    fn the_bound_comes_from_the_swing() {
        let gait = Gait {
            name: "t".into(),
            period: 1.0,
            duty_factor: 0.5,
            stride_length: 0.06,
            step_height: 0.03,
            stance_height: 0.1,
            reach: 0.1,
            splay: 0.0,
            swing: crate::gait::SwingShape::Sine,
            offsets: [0.0; 6],
        };
        let v = speed_limit(&gait, 0.06);
        let nominal = (0.12f64).hypot(std::f64::consts::PI * 0.03) / 0.5;
        assert!((v - SPEED_FACTOR * nominal).abs() < 1e-12, "{v}");
        // twice the stride, twice the horizontal part
        assert!(speed_limit(&gait, 0.12) > v);
    }
}
