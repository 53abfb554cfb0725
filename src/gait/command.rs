//! What the robot is asked to do over time: a schedule of velocity commands.

use super::VelocityCommand;

/// One change of command: from `at` seconds into the walk, ramp linearly from the command in force
/// to `command` over `ramp` seconds (a step change would jump every stance foot's target, since
/// the controller plans each stance from the command).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandChange {
    pub at: f64,
    pub command: VelocityCommand,
    pub ramp: f64,
}

/// Piecewise-constant velocity commands joined by linear ramps; before the first change the
/// robot is asked to stand (zero command).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CommandSchedule {
    changes: Vec<CommandChange>,
}

/// The fastest walk a command may ask for (m/s), forward or sideways.
pub const MAX_SPEED: f64 = 10.0;

/// The fastest turn a command may ask for (°/s).
pub const MAX_TURN_DEG_S: f64 = 3600.0;

impl CommandSchedule {
    /// Changes must be in time order with finite values and ramps ≥ 0; the error names the entry.
    pub fn new(changes: Vec<CommandChange>) -> Result<Self, String> {
        for (i, c) in changes.iter().enumerate() {
            let VelocityCommand {
                forward,
                sideways,
                yaw_rate,
            } = c.command;
            if ![c.at, forward, sideways, yaw_rate]
                .iter()
                .all(|v| v.is_finite())
            {
                return Err(format!(
                    "command[{i}]: expected finite `at`, `forward`, `sideways` and `turn_deg_s`"
                ));
            }
            // a legged robot's walk: 10 m/s is some thirty times a fast hexapod's
            for (field, value, most, unit) in [
                ("forward", forward, MAX_SPEED, "m/s"),
                ("sideways", sideways, MAX_SPEED, "m/s"),
                ("turn_deg_s", yaw_rate.to_degrees(), MAX_TURN_DEG_S, "°/s"),
            ] {
                if value.abs() > most {
                    return Err(format!(
                        "command[{i}].{field}: expected at most {most} {unit} either way, got {}",
                        crate::limits::num(value)
                    ));
                }
            }
            if c.at < 0.0 || !(c.ramp.is_finite() && c.ramp >= 0.0) {
                return Err(format!(
                    "command[{i}]: expected `at` ≥ 0 s and `ramp` ≥ 0 s, got at = {} and ramp = {}",
                    c.at, c.ramp
                ));
            }
            if i > 0 && c.at < changes[i - 1].at + changes[i - 1].ramp {
                return Err(format!(
                    "command[{i}]: starts at {} s, before command[{}] has finished ramping ({} s); list changes in time order",
                    c.at,
                    i - 1,
                    changes[i - 1].at + changes[i - 1].ramp
                ));
            }
        }
        Ok(CommandSchedule { changes })
    }

    pub fn changes(&self) -> &[CommandChange] {
        &self.changes
    }

    /// The command `t` seconds into the walk.
    pub fn at(&self, t: f64) -> VelocityCommand {
        let mut current = VelocityCommand::default();
        for c in &self.changes {
            if t < c.at {
                break;
            }
            let s = if c.ramp > 0.0 {
                ((t - c.at) / c.ramp).min(1.0)
            } else {
                1.0
            };
            current = VelocityCommand {
                forward: current.forward + s * (c.command.forward - current.forward),
                sideways: current.sideways + s * (c.command.sideways - current.sideways),
                yaw_rate: current.yaw_rate + s * (c.command.yaw_rate - current.yaw_rate),
            };
        }
        current
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fwd(v: f64) -> VelocityCommand {
        VelocityCommand {
            forward: v,
            ..Default::default()
        }
    }

    #[test]
    fn ramps_between_commands_and_holds_the_last() {
        let s = CommandSchedule::new(vec![
            CommandChange {
                at: 0.0,
                command: fwd(0.1),
                ramp: 0.0,
            },
            CommandChange {
                at: 2.0,
                command: fwd(0.0),
                ramp: 1.0,
            },
        ])
        .unwrap();
        assert_eq!(s.at(1.0).forward, 0.1);
        assert!((s.at(2.5).forward - 0.05).abs() < 1e-12);
        assert_eq!(s.at(10.0).forward, 0.0);
    }

    #[test]
    fn refuses_changes_out_of_order() {
        let e = CommandSchedule::new(vec![
            CommandChange {
                at: 2.0,
                command: fwd(0.1),
                ramp: 1.0,
            },
            CommandChange {
                at: 2.5,
                command: fwd(0.0),
                ramp: 0.0,
            },
        ])
        .unwrap_err();
        assert!(e.contains("command[1]"), "{e}");
    }
}
