//! Heading hold: a walk keeps the heading its command asks for, as a robot with a gyro does.
//!
//! The gait turns the body at the commanded yaw rate only as well as its feet grip: a foot that
//! slips on an edge, a leg blocked by a riser, a stone under one side turn it off its course, and
//! an open-loop gait never turns back (hex18 on the ladder's stepping stones turned 59° while
//! commanded straight ahead). The hold integrates the commanded yaw rate into a heading goal and
//! adds a turn proportional to the error: ω = ω_cmd + K·wrap(ψ_goal − ψ), as legged_gym's heading
//! command does (K = 0.5 /s), bounded so the correction moves the outermost standing foot at most
//! [`TURN_SHARE`] of the walk's nominal speed (the turn takes stride the feet must reach).

use super::VelocityCommand;

/// The gain from heading error to yaw rate (1/s): an error closes with a 2 s time constant.
pub const GAIN: f64 = 0.5;
/// The correction's bound, as a share of the nominal speed at the outermost standing foot.
pub const TURN_SHARE: f64 = 0.25;

/// The heading goal, set at the first step it steers.
#[derive(Debug, Clone, PartialEq)]
pub struct HeadingHold {
    goal: Option<f64>,
    /// The largest correction (rad/s).
    most: f64,
}

impl HeadingHold {
    /// For a gait of `nominal_speed` (m/s) whose farthest standing foot is `radius` (m) from the
    /// body's vertical axis.
    pub fn new(nominal_speed: f64, radius: f64) -> Self {
        let most = if radius > 0.0 {
            TURN_SHARE * nominal_speed / radius
        } else {
            0.0
        };
        HeadingHold { goal: None, most }
    }

    /// The command with the correction added, the body's heading being `yaw` (rad) and `dt` (s)
    /// the step over which the command holds.
    pub fn steer(&mut self, command: VelocityCommand, yaw: f64, dt: f64) -> VelocityCommand {
        let goal = self.goal.get_or_insert(yaw);
        let error = wrap(*goal - yaw);
        *goal = wrap(*goal + command.yaw_rate * dt);
        VelocityCommand {
            yaw_rate: command.yaw_rate + (GAIN * error).clamp(-self.most, self.most),
            ..command
        }
    }
}

/// An angle brought into (−π, π].
fn wrap(angle: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let a = angle.rem_euclid(TAU);
    if a > PI { a - TAU } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight() -> VelocityCommand {
        VelocityCommand {
            forward: 0.1,
            sideways: 0.0,
            yaw_rate: 0.0,
        }
    }

    /// A body turned off its start turns back, at K times the error, within the bound, and the
    /// long way round is never taken.
    #[test]
    fn a_body_turned_off_its_heading_is_turned_back() {
        let mut hold = HeadingHold::new(0.1, 0.25);
        let most = TURN_SHARE * 0.1 / 0.25;
        assert_eq!(hold.steer(straight(), 0.3, 1e-3).yaw_rate, 0.0);
        let small = hold.steer(straight(), 0.35, 1e-3).yaw_rate;
        assert!((small - GAIN * -0.05).abs() < 1e-12, "{small}");
        assert_eq!(hold.steer(straight(), 1.3, 1e-3).yaw_rate, -most);
        assert_eq!(hold.steer(straight(), -0.7, 1e-3).yaw_rate, most);
        // 0.3 rad against −3.0 (across ±π): 2.98 rad to the left, not 3.3 to the right
        assert_eq!(hold.steer(straight(), -3.0, 1e-3).yaw_rate, -most);
        let mut hold = HeadingHold::new(0.1, 0.25);
        hold.steer(straight(), 3.1, 1e-3);
        let across = hold.steer(straight(), -3.1, 1e-3).yaw_rate;
        assert!(across < 0.0 && across > -most, "{across}");
    }

    /// A commanded turn moves the goal with it: a body that turns as commanded gets no
    /// correction, one that lags is pushed on.
    #[test]
    fn a_commanded_turn_moves_the_goal() {
        let turn = VelocityCommand {
            yaw_rate: 0.2,
            ..straight()
        };
        let mut hold = HeadingHold::new(0.1, 0.25);
        let dt = 0.01;
        let mut yaw = 0.0;
        for _ in 0..100 {
            let steered = hold.steer(turn, yaw, dt);
            assert!((steered.yaw_rate - 0.2).abs() < 1e-9, "{steered:?}");
            yaw += 0.2 * dt;
        }
        let lagging = hold.steer(turn, yaw - 0.02, dt).yaw_rate;
        assert!((lagging - (0.2 + GAIN * 0.02)).abs() < 1e-9, "{lagging}");
    }
}
